# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""Parameter files and their validation (core/settings/params.py)."""

import math
import os
import re

from formation_ros.core.settings.declarations import DECLARATIONS as SCHEMA, ParamError, REQUIRED
from formation_ros.core.settings.params import load_config, shape_problem, validate
from formation_ros.core.settings.params_file import load_params_file
import numpy as np
import pytest
import yaml

CONFIG_DIR = os.path.join(os.path.dirname(__file__), '..', '..', 'config')
SECTION5 = os.path.join(CONFIG_DIR, 'paper_section5.yaml')


def base():
    return load_params_file(SECTION5)


def test_section5_file_matches_the_paper():
    config = load_config(SECTION5)
    assert (config.num_robots, config.dim) == (10, 2)
    i = np.arange(10)
    expected = 8.0 * np.column_stack([np.sin(i * 2 * np.pi / 10), np.cos(i * 2 * np.pi / 10)])
    assert np.allclose(config.vertices, expected, atol=1e-9)
    assert np.all(config.sensing_radii == 2.0) and config.repulsion_radius == 1.0
    assert (config.gain, config.kappa, config.psi) == (2.0, 1.0, 'arctan')
    assert (config.jump_kind, config.jump_order) == ('poly', 2)
    assert np.all(np.linalg.norm(config.start, axis=1) <= 1.0)
    gaps = np.linalg.norm(config.start[:, None] - config.start[None], axis=2)
    assert np.min(gaps[np.triu_indices(10, 1)]) >= 0.1


@pytest.mark.parametrize('name', sorted(f for f in os.listdir(CONFIG_DIR) if f.endswith('.yaml')))
def test_every_shipped_config_is_valid(name):
    load_config(os.path.join(CONFIG_DIR, name))


def test_random_start_is_reproducible_and_seeded():
    raw = base()
    first, again = validate(raw).start, validate(raw).start
    raw['start.seed'] = 99
    assert np.array_equal(first, again)
    assert not np.allclose(first, validate(raw).start)


def test_scientific_notation_is_a_double(tmp_path):
    path = tmp_path / 'p.yaml'
    text = open(SECTION5).read().replace('gain: 2.0', 'gain: 2e0')
    path.write_text(text)
    assert load_config(str(path)).gain == 2.0


BAD_CASES = [
    ('controller.gain', {'controller.gain': 2}, 'write 2.0'),
    ('controller.gain', {'controller.gain': -1.0}, 'must be > 0, got -1.0'),
    ('controller.gain', {'controller.gain': 0.0}, 'must be > 0, got 0.0'),
    ('controller.gain', {'controller.gain': 'fast'}, 'finite double'),
    ('controller.gain', {'controller.gain': math.nan}, 'finite double'),
    ('num_robots', {'num_robots': 'ten'}, 'integer'),
    ('num_robots', {'num_robots': 1}, '>= 2'),
    ('dim', {'dim': 4}, '<= 3'),
    ('controller.psi', {'controller.psi': 'sigmoid'}, 'arctan, tanh'),
    ('jump.kind', {'jump.kind': 'cubic'}, 'poly, smooth'),
    ('jump.order', {'jump.order': 0}, '>= 1'),
    ('formation.vertices', {'formation.vertices': [0.0, 1.0, 2.0]}, '10 x 2 = 20'),
    ('formation.vertices', {'formation.vertices': [0.0, 1, 2.0]}, 'write 1.0'),
    ('formation.vertices', {'formation.vertices': [0.0] * 20}, 'same vertex'),
    ('start.positions', {'start.positions': [0.5] * 20, 'start.random_radius': None,
                         'start.min_separation': None}, 'start at the same point'),
    ('start.positions', {'start.positions': [0.5, 1.0]}, 'not both'),
    ('start.positions', {'start.random_radius': None}, 'is required'),
    ('start.min_separation', {'start.min_separation': 0.9}, 'do not fit'),
    ('repulsion_radius', {'repulsion_radius': 3.0}, 'sensing radius'),
    ('repulsion_radius', {'repulsion_radius': 1.5, 'sensing_radius': 6.0,
                          'formation.vertices': [0.0, 0.0, 1.2, 0.0] + [
                              float(v) for k in range(8) for v in (10.0 * k, 20.0)]},
     'closest vertices'),
    ('sensing_radii', {'sensing_radii': [2.0] * 9}, 'num_robots = 10'),
    ('repulsion_radius', {'sensing_radii': [2.0] * 9 + [0.5]}, 'smallest R_i = 0.5'),
    ('controller.gian', {'controller.gian': 2.0}, "did you mean 'controller.gain'"),
    ('reference.kind', {'reference.kind': 'helix'}, 'dim 3'),
    ('reference.kind', {'reference.kind': 'spiral'}, 'one of'),
    ('reference.velocity', {'reference.kind': 'line'}, 'required for a line'),
    ('reference.origin', {'reference.origin': [0.0, 0.0, 0.0]}, 'dim = 2'),
    ('reference.speed', {'reference.kind': 'circle', 'reference.speed': 0.0}, '> 0'),
    ('sensing_radius', {'sensing_radius': None}, 'is required'),
    ('duration', {'duration': 0.0}, 'must be > 0'),
    ('jump.order', {'jump.order': 51}, 'must be <= 50'),
    ('use_sim_time', {'use_sim_time': 1}, 'must be true or false, got 1'),
    ('start_type_description_service', {'start_type_description_service': 'no'},
     "must be true or false, got 'no'"),
]


@pytest.mark.parametrize('name,changes,message', BAD_CASES,
                         ids=[f'{c[0]}-{i}' for i, c in enumerate(BAD_CASES)])
def test_bad_parameter_named_with_what_is_allowed(name, changes, message):
    raw = base()
    for key, value in changes.items():
        if value is None:
            raw.pop(key, None)
        else:
            raw[key] = value
    with pytest.raises(ParamError) as info:
        validate(raw)
    text = str(info.value)
    assert f"parameter '{name}'" in text
    assert message in text


def test_every_problem_is_reported_at_once():
    raw = base()
    raw.update({'controller.gain': -1.0, 'dim': 7, 'typo': 1})
    with pytest.raises(ParamError) as info:
        validate(raw)
    names = {name for name, _ in info.value.problems}
    assert names == {'controller.gain', 'dim', 'typo'}


@pytest.mark.parametrize('text,message', [
    ('num_robots: [unclosed', 'cannot read it as YAML'),
    ('robot:\n  ros__parameters:\n    num_robots: 3\n', "'/**:'"),
    ('- just\n- a list\n', "'/**:'"),
])
def test_bad_files(tmp_path, text, message):
    path = tmp_path / 'bad.yaml'
    path.write_text(text)
    with pytest.raises(ParamError, match=re.escape(message)):
        load_params_file(str(path))


def test_missing_file():
    with pytest.raises(ParamError, match='file not found'):
        load_params_file('/nonexistent/params.yaml')


def test_nodes_need_no_start_positions():
    raw = base()
    for key in ('start.random_radius', 'start.min_separation', 'start.seed'):
        raw.pop(key)
    config = validate({**raw, 'robot_id': 3}, executable='robot')
    assert config.start is None
    with pytest.raises(ParamError, match='start.positions'):
        validate(raw, executable='plant')


def test_schema_defaults_have_their_declared_types():
    kinds = {'int': int, 'double': float, 'string': str, 'bool': bool, 'double_array': list}
    for param in SCHEMA:
        if param.default is not None and param.default is not REQUIRED:
            assert isinstance(param.default, kinds[param.kind.value]), param.name


def test_section5_file_is_plain_yaml_for_ros():
    """The ROS parser sees the same document: no Python-only YAML tags, numbers typed."""
    with open(SECTION5) as stream:
        document = yaml.safe_load(stream)
    params = document['/**']['ros__parameters']
    assert isinstance(params['controller']['gain'], float)
    assert all(isinstance(v, float) for v in params['formation']['vertices'])


def unicycles(**changes):
    """Return the Section 5 file as unicycles within TurtleBot3 Burger limits, changed."""
    raw = base()
    raw.update({'body.kind': 'unicycle', 'body.hand_distance': 0.08, 'body.radius': 0.05,
                'controller.gain': 0.09, 'body.max_linear': 0.22, 'body.max_angular': 2.84})
    for key, value in changes.items():
        if value is None:
            raw.pop(key, None)
        else:
            raw[key] = value
    return raw


def test_point_bodies_are_the_default_and_unchanged():
    config = validate(base())
    assert config.body.kind == 'point' and not config.body.is_unicycle
    assert config.start_headings is None and config.body.radius == 0.0


def test_unicycles_get_seeded_random_headings_and_keep_the_point_start():
    config = validate(unicycles())
    assert config.body.is_unicycle and config.body.hand_distance == 0.08
    assert (config.body.max_linear, config.body.max_angular) == (0.22, 2.84)
    assert np.array_equal(config.start, validate(base()).start)
    headings = config.start_headings
    assert headings.shape == (10,) and np.all((headings >= -math.pi) & (headings < math.pi))
    assert np.array_equal(headings, validate(unicycles()).start_headings)
    assert not np.allclose(headings, validate(unicycles(**{'start.seed': 5})).start_headings)
    assert len(np.unique(np.round(headings, 6))) == 10


def test_unicycle_headings_given_or_zero_with_given_positions():
    given = [0.1 * k for k in range(10)]
    assert np.array_equal(validate(unicycles(**{'start.headings': given})).start_headings,
                          given)
    explicit = unicycles(**{'start.random_radius': None, 'start.min_separation': None,
                            'start.positions': [float(v) for k in range(10) for v in (k, 0.0)]})
    assert np.array_equal(validate(explicit).start_headings, np.zeros(10))
    assert validate({**unicycles(), 'robot_id': 2}, 'reference').start_headings is None


def test_turtlebot_limits_refuse_a_gain_that_exceeds_them_and_say_what_fits():
    with pytest.raises(ParamError) as info:
        validate(unicycles(**{'controller.gain': 2.0}))
    lines = str(info.value).splitlines()
    linear = [line for line in lines if "'body.max_linear'" in line]
    angular = [line for line in lines if "'body.max_angular'" in line]
    assert len(linear) == 1 and len(angular) == 1
    assert 'sqrt(2) c M1 = 4.443 m/s exceeds body.max_linear = 0.22 m/s' in linear[0]
    assert 'controller.gain <= 0.09903 would fit' in linear[0]
    assert 'controller.gain <= 0.1022 or body.hand_distance >= 1.565 m would fit' in angular[0]
    fits = unicycles(**{'controller.gain': 0.09903})
    assert validate(fits).body.max_linear == 0.22
    slower = unicycles(**{'controller.gain': 0.09903, 'body.max_angular': 2.0})
    with pytest.raises(ParamError, match='body.hand_distance >= 0.11 m would fit'):
        validate(slower)
    validate(unicycles(**{'controller.gain': 0.09903, 'body.max_angular': 2.0,
                          'body.hand_distance': 0.11}))


UNICYCLE_CASES = [
    ('body.kind', {'dim': 3, 'formation.vertices': [float(k) for k in range(30)],
                   'start.min_separation': 0.1}, 'unicycle needs dim 2'),
    ('body.kind', {'body.kind': 'tank'}, 'point, unicycle'),
    ('body.hand_distance', {'body.hand_distance': None}, 'is required for body.kind unicycle'),
    ('body.hand_distance', {'body.hand_distance': 0.0}, 'must be > 0'),
    ('body.radius', {'body.radius': -0.1}, 'must be >= 0'),
    ('body.radius', {'body.radius': 0.2}, 'overlap at the start'),
    ('start.headings', {'start.headings': [0.0] * 9}, 'num_robots = 10'),
    ('start.headings', {'start.headings': [0.0, 1] + [0.0] * 8}, 'write 1.0'),
    ('plant.max_speed', {'plant.max_speed': 1.0}, 'body.max_linear'),
    ('body.max_angular', {'body.hand_distance': 0.05}, 'body.hand_distance >= 0.0704 m'),
]


@pytest.mark.parametrize('name,changes,message', UNICYCLE_CASES,
                         ids=[f'{c[0]}-{i}' for i, c in enumerate(UNICYCLE_CASES)])
def test_bad_unicycle_parameter_named_with_what_is_allowed(name, changes, message):
    with pytest.raises(ParamError) as info:
        validate(unicycles(**changes), 'plant' if name == 'plant.max_speed' else 'formation_sim')
    assert f"parameter '{name}'" in str(info.value) and message in str(info.value)


@pytest.mark.parametrize('name', ['body.hand_distance', 'body.max_linear', 'body.max_angular',
                                  'start.headings'])
def test_unicycle_parameters_are_refused_for_point_bodies(name):
    raw = base()
    raw[name] = [0.0] * 10 if name == 'start.headings' else 0.1
    message = ('applies to unicycles and to points with command.frame body'
               if name == 'start.headings' else 'applies only to body.kind unicycle')
    with pytest.raises(ParamError, match=f"'{re.escape(name)}': {message}"):
        validate(raw)


def test_hand_points_that_coincide_at_the_start_are_refused():
    positions = [0.0, 0.0, 0.16] + [0.0] + [float(v) for k in range(2, 10) for v in (k, 5.0)]
    raw = unicycles(**{'start.random_radius': None, 'start.min_separation': None,
                       'start.positions': positions,
                       'start.headings': [0.0, math.pi] + [0.0] * 8, 'body.radius': 0.0})
    with pytest.raises(ParamError, match='robots 1 and 2 start with their hand points at the '
                                         'same point'):
        validate(raw)


def test_a_formation_moving_faster_than_the_robots_can_is_refused():
    circle = load_params_file(os.path.join(CONFIG_DIR, 'unicycle_circle_2d.yaml'))
    assert validate(circle).reference_kind == 'circle'
    circle['reference.speed'] = 0.25
    with pytest.raises(ParamError) as info:
        validate(circle)
    text = str(info.value)
    vertices = np.array(circle['formation.vertices']).reshape(-1, 2)
    fastest = 0.25 / 4.0 * np.max(np.hypot(vertices[:, 0], 4.0 + np.abs(vertices[:, 1])))
    assert f"'body.max_linear': the formation moves its vertices at up to {fastest:.4g} m/s" \
        in text
    factor = math.ceil(fastest / 0.22 * 1000) / 1000
    assert f'a reference {factor:g} times slower (or vertices nearer its path) would fit' in text
    circle['reference.speed'] = 0.25 / factor
    validate(circle)
    line = load_params_file(os.path.join(CONFIG_DIR, 'unicycle_2d.yaml'))
    line.update({'reference.kind': 'line', 'reference.velocity': [0.3, 0.0]})
    with pytest.raises(ParamError, match='up to 0.3 m/s'):
        validate(line)


@pytest.mark.parametrize('n', [2, 40, 1600])
def test_the_closest_vertices_are_named_as_a_brute_force_finds_them(n):
    rng = np.random.default_rng(n)
    vertices = rng.uniform(-50.0, 50.0, (n, 3))
    pairs = [(math.dist(vertices[i], vertices[j]), i + 1, j + 1)
             for i in range(n) for j in range(i + 1, n)]
    gap, i, j = min(pairs)
    problem = shape_problem(vertices, gap * 1.5)
    assert f'({i} and {j}: {gap:g} m)' in problem, problem
    assert shape_problem(vertices, gap * 0.99) is None
