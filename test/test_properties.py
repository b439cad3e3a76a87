# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
Property-based tests (hypothesis): the parameter loader and the control law on hostile input.

Loader (``core.settings.params_file.parse_params_text`` + ``core.settings.params.validate`` for
every ``Exe``): random YAML documents and text, wrong types, NaN, inf, 1e300, subnormal numbers,
huge lists, unicode and missing sections raise nothing but ``ParamError``, and valid files, over
the whole range the parameters allow, give a config. Law (``core.maths.law.robot_command``,
``team_command``): for finite positions, even extreme or coincident ones and many neighbours, u_hat
is finite with every component within c M1 (inclusive) and u is finite.

The contract for non-finite input: the robot node drops poses, neighbours and references with
non-finite values before the law (``nodes/robot.py``), so the law does not promise a finite
command for them. ``robot_command`` must not raise: a non-finite neighbour is out of range (its
distance does not compare below R_i) and so ignored, and a non-finite own position or vertex may
give NaN components but never a finite one above c M1.

The inputs these tests first found to break the contract (robots closer than the doubles
resolve, law constants or lengths beyond double precision, pathological YAML, strings that read
back as numbers) are regression tests at the end: they are fixed, or refused with the documented
error. The plant model's properties are in ``test/core/test_plant_properties.py``.
"""

import math
import os

from formation_ros.core.maths.frames import STATIONARY
from formation_ros.core.maths.law import (GAIN_MAX, KAPPA_MAX, make_law, REPULSION_RANGE,
                                          robot_command, team_command)
from formation_ros.core.maths.reference import Reference
from formation_ros.core.settings.declarations import BY_NAME, Exe, Kind, ParamError
from formation_ros.core.settings.params import FormationConfig, validate
from formation_ros.core.settings.params_file import (dump_params_text, load_params_file, nest,
                                                     parse_params_text)
from hypothesis import assume, given, HealthCheck, settings, strategies as st
import numpy as np
import pytest
import yaml

CONFIG = os.path.join(os.path.dirname(__file__), '..', 'config', 'paper_section5.yaml')
SETTINGS = settings(max_examples=60, deadline=None, database=None,
                    suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])
NASTY_FLOATS = (0.0, -0.0, 5e-324, -5e-324, 2.2250738585072014e-308, 1e-300, 1e300, -1e300,
                1.7976931348623157e308, -1.7976931348623157e308, math.inf, -math.inf, math.nan)
NASTY_INTS = (0, 1, -1, 2, 3, 50, 51, 100000, 100001, 2 ** 31 - 1, 2 ** 31, 2 ** 63, -2 ** 63,
              10 ** 30)
UNKNOWN_NAMES = ('controller.gian', 'plant', 'robot_id.x', '\u00fcber', 'qos_overrides./x',
                 'use_sim_time', '', '.', 'num_robots.', '\U0001f916')
FINITE_LIMIT = 1e300


def section5_values():
    """Section 5 as flat values, with its start as explicit positions (no random start)."""
    raw = load_params_file(CONFIG)
    start = validate(raw).start
    for name in ('start.random_radius', 'start.min_separation', 'start.seed'):
        raw.pop(name)
    raw['start.positions'] = [float(v) for v in start.ravel()]
    raw.update({'robot_id': 1, 'record.path': '/tmp/formation_properties_bag'})
    return raw


BASE = section5_values()


def load_for(raw, exe):
    """Validate ``raw`` for ``exe``: the config, or None on ParamError (anything else raises)."""
    try:
        config = validate(raw, exe)
    except ParamError as exc:
        assert exc.problems and all(isinstance(name, str) for name, _ in exc.problems)
        return None
    assert isinstance(config, FormationConfig)
    return config


def check_config(config, raw):
    """Assert what every config returned by the loader guarantees."""
    n, dim = config.num_robots, config.dim
    assert n == raw['num_robots'] and dim in (2, 3)
    assert config.vertices.shape == (n, dim) and np.all(np.isfinite(config.vertices))
    assert config.sensing_radii.shape == (n,)
    assert np.all(config.sensing_radii > 0.0) and np.all(np.isfinite(config.sensing_radii))
    assert 0.0 < config.repulsion_radius <= np.min(config.sensing_radii)
    if config.start is not None:
        assert config.start.shape == (n, dim) and np.all(np.isfinite(config.start))
    assert config.law().u_bound > 0.0


def _searchable(raw):
    """
    Tell whether the random search may try ``raw``.

    Not when it asks for a random start that may take long to place or fail: the loader then
    tries up to 20000 N points one by one (seconds for 3 robots that do not fit, far longer for
    thousands).
    """
    n, radius, separation = (raw.get(name) for name in
                             ('num_robots', 'start.random_radius', 'start.min_separation'))
    valid = [isinstance(v, float) and math.isfinite(v) and v > 0.0 for v in (radius, separation)]
    if raw.get('start.positions') is not None or not all(valid):
        return True
    if not (isinstance(n, int) and not isinstance(n, bool)) or not 2 <= n <= 100000:
        return True
    return n <= 6 and separation < 1e150 and 8.0 * n * separation <= radius


floats = st.one_of(st.floats(), st.sampled_from(NASTY_FLOATS))
ints = st.one_of(st.integers(min_value=-10 ** 20, max_value=10 ** 20),
                 st.sampled_from(NASTY_INTS))
texts = st.text(alphabet=st.characters(blacklist_categories=('Cs',)), max_size=12)
scalars = st.one_of(st.none(), st.booleans(), ints, floats, texts)
huge_lists = st.builds(lambda value, size: [value] * size, st.one_of(floats, ints, scalars),
                       st.sampled_from([1000, 20000, 100000]))
any_values = st.one_of(scalars, st.lists(scalars, max_size=6), st.lists(floats, max_size=25),
                       huge_lists, st.dictionaries(texts, scalars, max_size=3))


def typed_values(param):
    """Draw values of the declared type of ``param``, with extreme contents."""
    if param.kind is Kind.INT:
        return ints
    if param.kind is Kind.DOUBLE:
        return floats
    if param.kind is Kind.BOOL:
        return st.booleans()
    if param.kind is Kind.STRING:
        return st.one_of(texts, st.sampled_from(param.choices or ('',)))
    return st.one_of(st.lists(floats, max_size=25), huge_lists)


@st.composite
def mutated_values(draw):
    """Draw Section 5 with some parameters replaced, removed or added."""
    raw = dict(BASE)
    names = sorted(BY_NAME) + list(UNKNOWN_NAMES)
    for name in draw(st.lists(st.sampled_from(names), max_size=6, unique=True)):
        action = draw(st.sampled_from(['typed', 'any', 'remove']))
        if action == 'remove':
            raw.pop(name, None)
        elif action == 'typed' and name in BY_NAME:
            raw[name] = draw(typed_values(BY_NAME[name]))
        else:
            raw[name] = draw(any_values)
    return raw


def test_section5_loads_for_every_executable():
    for exe in Exe:
        check_config(load_for(BASE, exe), BASE)


@SETTINGS
@given(mutated_values())
def test_loader_raises_only_param_error_for_any_values(raw):
    assume(_searchable(raw))
    for exe in Exe:
        config = load_for(raw, exe)
        if config is not None:
            check_config(config, raw)


yaml_keys = st.one_of(texts, st.integers(min_value=-5, max_value=5), st.booleans(), st.none())
yaml_trees = st.recursive(scalars, lambda children: st.one_of(
    st.lists(children, max_size=4), st.dictionaries(yaml_keys, children, max_size=4)),
    max_leaves=25)


@st.composite
def yaml_documents(draw):
    """Draw a YAML document: random, or a parameters file with random sections and values."""
    tree = nest(BASE)
    for name in draw(st.lists(st.sampled_from(sorted(tree) + ['controller', 'x']), max_size=3)):
        tree[name] = draw(yaml_trees)
    wrapped = draw(st.sampled_from(['file', 'no ros__parameters', 'bare', 'random']))
    if wrapped == 'file':
        document = {'/**': {'ros__parameters': tree}}
    elif wrapped == 'no ros__parameters':
        document = {'/**': tree}
    elif wrapped == 'bare':
        document = tree
    else:
        document = draw(yaml_trees)
    return yaml.safe_dump(document, allow_unicode=draw(st.booleans()))


@SETTINGS
@given(yaml_documents())
def test_loader_raises_only_param_error_for_yaml_documents(text):
    try:
        raw = parse_params_text(text, 'random.yaml')
    except ParamError:
        return
    assume(_searchable(raw))
    for exe in Exe:
        config = load_for(raw, exe)
        if config is not None:
            check_config(config, raw)


YAML_CHARACTERS = list('{}[]:,-?&*!|>\'"%@`#\n \t.0123456789eE+_naif/')
yaml_text = st.text(alphabet=st.one_of(st.sampled_from(YAML_CHARACTERS),
                                       st.characters(blacklist_categories=('Cs',))),
                    max_size=200)


@SETTINGS
@given(st.sampled_from(['', '/**:\n  ros__parameters:\n    ']), yaml_text)
def test_loader_raises_only_param_error_for_random_text(header, text):
    try:
        raw = parse_params_text(header + text, 'random.yaml')
    except ParamError as exc:
        assert "parameter 'random.yaml'" in str(exc)
        return
    assume(_searchable(raw))
    for exe in Exe:
        load_for(raw, exe)


scales = st.one_of(st.floats(min_value=0.1, max_value=1e3), st.sampled_from([0.1, 1.0, 1e3]))
positive = st.one_of(st.floats(min_value=5e-324, max_value=1e6, exclude_min=False),
                     st.sampled_from([5e-324, 2.2250738585072014e-308, 1e-300, 1e6]))
in_range = st.floats(min_value=-1e6, max_value=1e6)


@st.composite
def valid_values(draw):
    """Draw a valid parameters file: a lattice at the extremes of the allowed scales and gains."""
    n = draw(st.integers(min_value=2, max_value=6))
    dim = draw(st.sampled_from([2, 3]))
    scale = draw(scales)
    lattice = np.array([[float(i), float(i % 2)] + [0.0] * (dim - 2) for i in range(n)])
    kind = draw(st.sampled_from(['fixed', 'line', 'circle', 'figure_eight'] +
                                (['helix'] if dim == 3 else [])))
    raw = {
        'num_robots': n, 'dim': dim, 'sensing_radius': 2.0 * scale,
        'repulsion_radius': scale * draw(st.floats(min_value=0.01, max_value=1.0)),
        'formation.vertices': [float(v) for v in (scale * lattice).ravel()],
        'start.positions': [float(v) for v in (scale * (lattice + 0.5)).ravel()],
        'controller.gain': draw(positive), 'controller.kappa': draw(positive),
        'controller.psi': draw(st.sampled_from(['arctan', 'tanh'])),
        'jump.kind': draw(st.sampled_from(['poly', 'smooth'])),
        'jump.order': draw(st.integers(min_value=1, max_value=50)),
        'reference.kind': kind, 'reference.speed': draw(positive),
        'reference.radius': draw(positive), 'reference.pitch': draw(in_range),
        'reference.origin': [draw(in_range) for _ in range(dim)],
        'reference.velocity': [draw(in_range) for _ in range(dim)],
        'duration': draw(positive), 'robot_id': draw(st.integers(min_value=1, max_value=n)),
        'record.path': draw(texts),
    }
    return raw


@SETTINGS
@given(valid_values())
def test_valid_files_load_for_every_executable_through_yaml(raw):
    read_back = parse_params_text(dump_params_text(raw), 'valid.yaml')
    assert read_back == raw
    for exe in Exe:
        config = validate(read_back, exe)
        check_config(config, raw)
        assert config.gain == raw['controller.gain'] and config.kappa == raw['controller.kappa']
        assert np.array_equal(config.vertices.ravel(), raw['formation.vertices'])


gains = st.one_of(st.floats(min_value=5e-324, max_value=GAIN_MAX),
                  st.sampled_from([5e-324, 1e-300, 1.0, GAIN_MAX]))
kappas = st.one_of(st.floats(min_value=5e-324, max_value=KAPPA_MAX),
                   st.sampled_from([5e-324, 1e-300, 1.0, KAPPA_MAX]))


@st.composite
def laws(draw):
    """
    Draw law constants over the whole range the law takes (``core.maths.law``).

    Gain and kappa up to 1e6, b from 1 mm to 10 km for either jump function, R_i up to 1000 b.
    """
    jump_kind = draw(st.sampled_from(['poly', 'poly', 'smooth']))
    low, high = REPULSION_RANGE
    exponent = draw(st.floats(min_value=math.log10(low), max_value=math.log10(high)))
    b = min(high, max(low, 10.0 ** exponent))
    law = make_law(draw(gains), draw(kappas), draw(st.sampled_from(['arctan', 'tanh'])),
                   jump_kind, draw(st.integers(min_value=1, max_value=50)), b)
    radius = b * draw(st.floats(min_value=1.0, max_value=1e3))
    return law, radius


coordinates = st.one_of(st.floats(min_value=-FINITE_LIMIT, max_value=FINITE_LIMIT),
                        st.sampled_from([0.0, -0.0, 5e-324, -5e-324, 1e-300, 1e300, -1e300]))


def assert_bounded(command, law):
    assert np.all(np.isfinite(command.u_hat)), command.u_hat
    assert np.all(np.abs(command.u_hat) <= law.u_bound)
    assert np.all(np.isfinite(command.u)), command.u


@st.composite
def robot_inputs(draw):
    """Draw a robot, its vertex and up to 2000 neighbours: coincident, close, far, extreme."""
    law, radius = draw(laws())
    dim = draw(st.sampled_from([2, 3]))
    q_i = np.array([draw(coordinates) for _ in range(dim)])
    vertex = np.array([draw(coordinates) for _ in range(dim)])
    rng = np.random.default_rng(draw(st.integers(min_value=0, max_value=2 ** 32 - 1)))
    parts = [np.tile(q_i, (draw(st.integers(min_value=0, max_value=3)), 1)),
             np.array([[draw(coordinates) for _ in range(dim)]
                       for _ in range(draw(st.integers(min_value=0, max_value=3)))]
                      ).reshape(-1, dim)]
    many = draw(st.sampled_from([0, 1, 5, 50, 2000]))
    if law.jump.kind == 'smooth':
        many = min(many, 5)
    spread = law.repulsion_radius * draw(st.sampled_from([1e-6, 0.3, 1.0, 3.0]))
    parts.append(q_i + rng.uniform(-spread, spread, size=(many, dim)))
    neighbours = np.concatenate(parts)
    return law, radius, q_i, vertex, neighbours


@SETTINGS
@given(robot_inputs())
def test_robot_command_is_bounded_for_finite_extreme_input(inputs):
    law, radius, q_i, vertex, neighbours = inputs
    with np.errstate(all='ignore'):
        command = robot_command(q_i, vertex, neighbours, radius, law, STATIONARY)
    assert command.u_hat.shape == (len(q_i),)
    assert_bounded(command, law)
    assert np.array_equal(command.u, command.u_hat)


team_coordinates = st.one_of(st.floats(min_value=-1e150, max_value=1e150),
                             st.sampled_from([0.0, -0.0, 5e-324, 1e-300, 1e150, -1e150]))


@st.composite
def team_inputs(draw):
    """
    Draw a team of up to 300 robots: extreme, clustered and coincident positions.

    Coordinates stay within 1e150 m: farther apart, the k-d tree raises, as documented
    (``test_team_command_refuses_positions_it_cannot_search``).
    """
    law, radius = draw(laws())
    assume(law.jump.kind == 'poly')
    dim = draw(st.sampled_from([2, 3]))
    rng = np.random.default_rng(draw(st.integers(min_value=0, max_value=2 ** 32 - 1)))
    n = draw(st.sampled_from([2, 3, 10, 300]))
    spread = law.repulsion_radius * draw(st.sampled_from([1e-3, 0.5, 2.0, 100.0]))
    centre = np.array([draw(team_coordinates) for _ in range(dim)])
    q = centre + rng.uniform(-spread, spread, size=(n, dim))
    extremes = draw(st.lists(st.tuples(st.integers(0, n - 1),
                                       st.lists(team_coordinates, min_size=dim, max_size=dim)),
                             max_size=3))
    for index, point in extremes:
        q[index] = point
    if draw(st.booleans()):
        q[-1] = q[0]
    vertices = rng.uniform(-1.0, 1.0, size=(n, dim)) * draw(st.sampled_from([1.0, 1e300]))
    radii = np.full(n, radius)
    return law, q, vertices, radii


@SETTINGS
@given(team_inputs())
def test_team_command_is_bounded_for_finite_extreme_input(inputs):
    law, q, vertices, radii = inputs
    with np.errstate(all='ignore'):
        command = team_command(q, vertices, radii, law, STATIONARY)
    assert command.u_hat.shape == q.shape
    assert_bounded(command, law)


@SETTINGS
@given(st.sampled_from(['line', 'circle', 'figure_eight', 'helix']),
       st.floats(min_value=0.0, max_value=1e4), st.floats(min_value=1e-3, max_value=1e3),
       st.floats(min_value=1e-3, max_value=10.0), robot_inputs())
def test_commands_in_a_moving_frame_are_bounded(kind, t, radius, speed, inputs):
    law, sensing_radius, q_i, vertex, neighbours = inputs
    dim = len(q_i)
    assume(kind != 'helix' or dim == 3)
    reference = Reference(kind, dim, np.zeros(dim), np.full(dim, speed), radius, speed, 1.0)
    frame = reference.sample(t)
    q_i, vertex = np.clip(q_i, -1e6, 1e6), np.clip(vertex, -1e6, 1e6)
    neighbours = np.clip(neighbours, -1e6, 1e6)
    with np.errstate(all='ignore'):
        command = robot_command(q_i, vertex, neighbours, sensing_radius, law, frame)
    assert_bounded(command, law)


@SETTINGS
@given(robot_inputs(), st.lists(st.sampled_from([math.nan, math.inf, -math.inf]), min_size=1,
                                max_size=3), st.integers(min_value=0, max_value=2))
def test_non_finite_neighbours_are_ignored(inputs, bad_values, axis):
    law, radius, q_i, vertex, neighbours = inputs
    axis = min(axis, len(q_i) - 1)
    bad = np.tile(q_i, (len(bad_values), 1))
    bad[:, axis] = bad_values
    with np.errstate(all='ignore'):
        clean = robot_command(q_i, vertex, neighbours, radius, law)
        dirty = robot_command(q_i, vertex, np.concatenate([bad, neighbours]), radius, law)
    assert np.array_equal(dirty.u_hat, clean.u_hat)


@SETTINGS
@given(robot_inputs(), st.sampled_from([math.nan, math.inf, -math.inf]),
       st.sampled_from(['own position', 'vertex']), st.integers(min_value=0, max_value=2))
def test_non_finite_own_state_never_raises_or_exceeds_the_bound(inputs, value, where, axis):
    law, radius, q_i, vertex, neighbours = inputs
    target = q_i.copy() if where == 'own position' else vertex.copy()
    target[min(axis, len(target) - 1)] = value
    q_i, vertex = (target, vertex) if where == 'own position' else (q_i, target)
    with np.errstate(all='ignore'):
        command = robot_command(q_i, vertex, neighbours, radius, law)
    finite = np.isfinite(command.u_hat)
    assert np.all(np.isnan(command.u_hat[~finite]))
    assert np.all(np.abs(command.u_hat[finite]) <= law.u_bound)


LAW = make_law(2.0, 1.0, 'arctan', 'poly', 2, 1.0)


@pytest.mark.parametrize('gap', [1e-160, 1e-170, 5e-324])
def test_robots_closer_than_the_doubles_resolve_still_repel_at_the_bound(gap):
    """h'/h overflows below about 1e-150 m: the term is capped, the command saturates."""
    one = robot_command([0.0, 0.0], [1.0, 0.0], [[gap, 0.0]], 2.0, LAW)
    assert_bounded(one, LAW)
    assert one.u_hat[0] == pytest.approx(-LAW.u_bound) and one.u_hat[1] == 0.0
    both = robot_command([0.0, 0.0], [1.0, 0.0], [[gap, 0.0], [-gap, 0.0]], 2.0, LAW)
    assert_bounded(both, LAW)
    team = team_command(np.array([[0.0, 0.0], [gap, 0.0]]), np.array([[0.0, 0.0], [1.0, 0.0]]),
                        np.array([2.0, 2.0]), LAW)
    assert_bounded(team, LAW)
    assert team.u_hat[0, 0] < 0.0 < team.u_hat[1, 0]


@pytest.mark.parametrize('gain,kappa,b,kind', [
    (1.5e308, 1.0, 1.0, 'poly'), (2.0, 1e7, 1.0, 'poly'), (2.0, 1.0, 1e-200, 'poly'),
    (2.0, 1.0, 1e-4, 'smooth'), (2.0, 1.0, 1e12, 'smooth')])
def test_law_constants_outside_its_range_are_refused(gain, kappa, b, kind):
    """The law raises ValueError for them, and the loader names the parameter."""
    with pytest.raises(ValueError, match='the law is computed for'):
        make_law(gain, kappa, 'arctan', kind, 2, b)
    raw = {**BASE, 'controller.gain': gain, 'controller.kappa': kappa, 'repulsion_radius': b,
           'sensing_radius': max(2.0, b), 'jump.kind': kind}
    with pytest.raises(ParamError) as info:
        validate(raw)
    assert {name for name, _ in info.value.problems} & {
        'controller.gain', 'controller.kappa', 'repulsion_radius'}


def test_a_huge_sensing_radius_sees_everything():
    command = robot_command([0.0, 0.0], [1.0, 0.0], [[0.5, 0.0]], 2e200, LAW)
    assert_bounded(command, LAW)
    assert np.array_equal(command.u_hat,
                          robot_command([0.0, 0.0], [1.0, 0.0], [[0.5, 0.0]], 3.0, LAW).u_hat)


@pytest.mark.parametrize('q', [[[math.nan, 0.0], [0.5, 0.0]], [[0.0, 0.0], [-9e-4, 1.35e154]]])
def test_team_command_refuses_positions_it_cannot_search(q):
    """Documented: team_command raises ValueError for non-finite or astronomically far robots."""
    with pytest.raises(ValueError):
        team_command(np.array(q), np.array([[0.0, 0.0], [1.0, 0.0]]), np.array([2.0, 2.0]), LAW)


@pytest.mark.parametrize('text', [
    '[' * 5000 + ']' * 5000,
    '/**:\n  ros__parameters: &a\n    x: *a\n',
    '/**:\n  ros__parameters:\n    num_robots: ' + '9' * 5000 + '\n'])
def test_pathological_yaml_is_a_param_error(text):
    with pytest.raises(ParamError):
        parse_params_text(text, 'pathological.yaml')


def test_extreme_values_in_range_checks_are_param_errors():
    raw = dump_params_text({**load_params_file(CONFIG), 'start.min_separation': 1e200})
    for exe in Exe:
        assert load_for(parse_params_text(raw, 'huge.yaml'), exe) is None or exe in (
            Exe.ROBOT, Exe.REFERENCE, Exe.RELAY)


def test_distinct_tiny_vertices_are_told_apart():
    """Vertices 1e-199 m apart are two vertices (math.dist), named 1 and 2."""
    raw = {**BASE, 'num_robots': 2, 'formation.vertices': [0.0, 0.0, 1e-199, 0.0],
           'start.positions': [0.0, 0.0, 3.0, 0.0]}
    with pytest.raises(ParamError) as info:
        validate(raw)
    text = str(info.value)
    assert 'same vertex' not in text and '(1 and 2: 1e-199 m)' in text, text


def test_a_string_like_a_ros_double_reads_back_as_a_string():
    values = {'record.path': '1e3', 'plant.output_dir': '2e-1'}
    assert parse_params_text(dump_params_text(values), 'dumped.yaml') == values
