# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""Obstacles in the physics world: geoms where the map says, bodies that stop at them, counts."""

import json
import math
import os
from xml.etree import ElementTree

from formation_ros.core.maths.obstacles import Obstacles
from formation_ros.core.runs.trajectory import Trajectory
from formation_ros.core.settings.params import FormationConfig, load_config
import numpy as np
import pytest

mujoco = pytest.importorskip('mujoco')

from formation_ros.physics.contacts import ObstacleApproach, ObstacleContactLog  # noqa: E402, I100
from formation_ros.physics.engine import Engine  # noqa: E402, I100
from formation_ros.physics.obstacles import footprint_note, obstacle_of_geom  # noqa: E402, I100
from formation_ros.physics.scene import build_scene, CEILING_ABOVE  # noqa: E402, I100
from formation_ros.simulation.engine_run import engine_summary, run_on_engine  # noqa: E402, I100
from formation_ros.simulation.simulate import shapes_of  # noqa: E402, I100
from formation_ros.tools.sim import main as sim_main  # noqa: E402, I100
from physics_helpers import bases, run, team  # noqa: E402, I100

LIVE = {'world.cmd_timeout': 10.0}
ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
OBSTACLE_CONFIG = os.path.join(ROOT, 'config', 'world_turtlebot3_obstacles.yaml')


def floats(*values):
    """Return the numbers given as a list of Python float values: parameters are typed."""
    return [float(v) for v in values]


MAP = {'obstacles.circles': floats(1.0, 0.0, 0.3),
       'obstacles.walls': floats(-1.0, -1.0, 0.5, 0.5, 0.1, 2.0, 2.0, 2.0, 2.0, 0.15),
       'obstacles.clearance': 0.2}
"""A pillar, a diagonal wall and a wall whose ends coincide (a disc of radius t)."""


class Quiet:
    """A progress that says nothing."""

    def update(self, t):
        """Take the time reached, s."""


def free_points(obstacles, count, low, high, clearance, seed, dim):
    """Return ``count`` random points (count, dim) ``clearance`` off the obstacles and apart."""
    rng = np.random.default_rng(seed)
    points = []
    while len(points) < count:
        point = rng.uniform(low, high)
        apart = all(np.linalg.norm(point - other) > 2.5 * clearance for other in points)
        if apart and obstacles.surface(point[None, :dim]).distances.min() > clearance:
            points.append(point[:dim])
    return np.array(points)


def far_places(n, dim):
    """Return vertices (flat) far from every obstacle of the tests."""
    return floats(*(np.arange(n * dim) * 0.5 + 40.0))


def geom_gaps(engine, robot_geoms, obstacle_geoms, labels):
    """Return MuJoCo's distance from each robot's footprint to each obstacle (N, M), m."""
    model, data = engine.mj_model, engine.data
    gaps = np.full((len(robot_geoms), len(labels)), np.inf)
    for i, robot in enumerate(robot_geoms):
        for geom, obstacle in obstacle_geoms:
            distance = mujoco.mj_geomDistance(model, data, robot, geom, 10.0, None)
            gaps[i, obstacle] = min(gaps[i, obstacle], distance)
    return gaps


def obstacle_geoms(engine):
    """Return [(geom id, obstacle index)] of the engine's obstacle geoms."""
    return [(geom, int(engine._geom_obstacle[geom])) for geom in range(engine.mj_model.ngeom)
            if engine._geom_obstacle[geom] >= 0]


def test_the_geoms_are_where_the_map_says_in_3d_every_shape():
    extra = {**MAP, 'obstacles.spheres': floats(0.0, 2.0, 1.5, 0.4), 'body.radius': 0.05}
    obstacles = Obstacles(extra['obstacles.circles'], extra['obstacles.walls'],
                          extra['obstacles.spheres'], 0.2, 3)
    start = free_points(obstacles, 30, (-2.5, -2.5, 0.8), (3.0, 3.0, 2.2), 0.07, 1, 3)
    config = team(start, 3, None, {**extra, 'formation.vertices': far_places(30, 3)})
    engine = Engine(config)
    names = [f'{name}_footprint' for name in engine.scene.names]
    robots = [mujoco.mj_name2id(engine.mj_model, mujoco.mjtObj.mjOBJ_GEOM, n) for n in names]
    found = geom_gaps(engine, robots, obstacle_geoms(engine), obstacles.labels())
    expected = obstacles.surface(start).distances - 0.05
    assert np.allclose(found, expected, atol=1e-4), np.max(np.abs(found - expected))
    pillar = engine.mj_model.geom('obstacle_circle_1')
    floor_z = engine.mj_model.geom('floor').pos[2]
    top = pillar.pos[2] + pillar.size[1]
    assert pillar.pos[2] - pillar.size[1] == pytest.approx(floor_z)
    highest = max(start[:, 2].max(), np.max(config.vertices[:, 2]))
    assert top == pytest.approx(highest + CEILING_ABOVE)


def test_the_geoms_are_where_the_map_says_in_2d_from_the_floor_to_the_height_asked():
    obstacles = Obstacles(MAP['obstacles.circles'], MAP['obstacles.walls'], [], 0.2, 2)
    start = free_points(obstacles, 30, (-2.5, -2.5), (3.0, 3.0), 0.12, 2, 2)
    config = team(start, 2, None, {**MAP, 'body.radius': 0.1, 'world.obstacle_height': 0.8,
                                   'formation.vertices': far_places(30, 2)})
    engine = Engine(config)
    robots = [mujoco.mj_name2id(engine.mj_model, mujoco.mjtObj.mjOBJ_GEOM, f'{n}_footprint')
              for n in engine.scene.names]
    found = geom_gaps(engine, robots, obstacle_geoms(engine), obstacles.labels())
    expected = obstacles.surface(start).distances - 0.1
    assert np.allclose(found, expected, atol=1e-4), np.max(np.abs(found - expected))
    root = ElementTree.fromstring(build_scene(config).xml)
    named = {geom.get('name'): geom for geom in root.iter('geom')}
    assert sorted(name for name in named if name.startswith('obstacle_')) == [
        'obstacle_circle_1', 'obstacle_wall_1', 'obstacle_wall_1_end_1', 'obstacle_wall_1_end_2',
        'obstacle_wall_2_end_1']
    box_type = mujoco.mjtGeom.mjGEOM_BOX
    for name in ('obstacle_circle_1', 'obstacle_wall_1', 'obstacle_wall_2_end_1'):
        geom = engine.mj_model.geom(name)
        half = geom.size[2] if geom.type[0] == box_type else geom.size[1]
        assert (geom.pos[2] - half, geom.pos[2] + half) == pytest.approx((0.0, 0.8))
    box = engine.mj_model.geom('obstacle_wall_1')
    assert box.size[0] == pytest.approx(0.5 * math.hypot(1.5, 1.5))
    assert box.pos[2] + box.size[2] == pytest.approx(0.8)


def test_a_base_driven_into_a_pillar_stops_at_it_and_counts_one_obstacle_contact():
    config = bases([[0.0, 0.0], [0.0, 2.0]], [0.0, 0.0],
                   {'obstacles.circles': floats(1.0, 0.0, 0.2), 'obstacles.clearance': 0.3,
                    **LIVE})
    engine = Engine(config)
    engine.apply([[0.2, 0.0], [0.0, 0.0]])
    ahead = [pose.positions[0, 0] for pose in run(engine, 6.0, every=25)]
    footprint = engine.model.footprint
    assert max(ahead) < 1.0 - 0.2 - footprint + 0.005
    assert ahead[-1] > 1.0 - 0.2 - footprint - 0.01
    stats = engine.stats(engine.wall)
    assert stats.obstacle_contacts == 1 and stats.contacts == 0
    (event,) = stats.obstacle_contact_events
    assert (event.robot, event.obstacle) == (1, 'circle 1')
    assert event.t == pytest.approx((0.8 - footprint) / 0.2, abs=0.3)
    assert -0.005 < stats.min_obstacle_gap < 0.001
    record = stats.record()
    assert record['obstacle_contact_events'] == [{'robot': 1, 'obstacle': 'circle 1',
                                                  't': event.t}]


def test_points_against_a_wall_and_each_other_are_counted_apart():
    config = team([[0.0, 0.0], [0.0, 0.45], [0.0, 3.0]], 2, None,
                  {'body.radius': 0.2, 'obstacles.walls': floats(1.0, -1.0, 1.0, 1.0, 0.05),
                   'obstacles.clearance': 0.3, 'formation.vertices': far_places(3, 2), **LIVE})
    engine = Engine(config)
    engine.apply([[0.3, 0.0], [0.3, -0.1], [0.3, 0.0]])
    run(engine, 5.0, every=10)
    stats = engine.stats(engine.wall)
    positions = engine.poses().positions
    assert positions[2, 0] > 1.3
    assert np.all(positions[:2, 0] < 1.0 - 0.05 - 0.2 + 0.005)
    assert {event.robot for event in stats.obstacle_contact_events} == {1, 2}
    assert stats.obstacle_contacts == 2
    assert [(event.i, event.j) for event in stats.contact_events] == [(1, 2)]


def test_a_team_without_obstacles_has_no_obstacle_geom_and_no_gap():
    engine = Engine(team([[0.0, 0.0], [1.0, 0.0]], 2, None, {'body.radius': 0.1}))
    assert not np.any(engine._geom_obstacle >= 0)
    run(engine, 0.1)
    stats = engine.stats(engine.wall)
    assert stats.obstacle_contacts == 0 and stats.min_obstacle_gap == math.inf
    assert stats.obstacle_contact_events == []


def test_the_geom_names_read_back_as_their_obstacles():
    obstacles = Obstacles([0.0, 0.0, 1.0], [1.0, 1.0, 2.0, 2.0, 0.1], [], 0.2, 2)
    assert obstacle_of_geom('obstacle_circle_1', obstacles) == 0
    assert obstacle_of_geom('obstacle_wall_1_end_2', obstacles) == 1
    assert obstacle_of_geom('obstacle_wall_2', obstacles) == -1
    assert obstacle_of_geom('robot_1_footprint', obstacles) == -1
    assert obstacle_of_geom(None, obstacles) == -1


def test_the_obstacle_log_holds_a_pair_until_it_parts_and_the_approach_is_exact_near():
    obstacles = Obstacles([0.0, 0.0, 1.0], [], [], 0.2, 2)
    log = ObstacleContactLog(obstacles, 0.1)
    touching = np.array([[1.1, 0.0], [5.0, 0.0]])
    assert len(log.update(np.array([0]), np.array([0]), touching, 10)) == 1
    assert log.update(np.array([], dtype=np.intp), np.array([], dtype=np.intp), touching,
                      20) == []
    near = np.array([[1.105, 0.0], [5.0, 0.0]])
    assert log.update(np.array([0]), np.array([0]), near, 30) == []
    apart = np.array([[1.2, 0.0], [5.0, 0.0]])
    log.update(np.array([], dtype=np.intp), np.array([], dtype=np.intp), apart, 40)
    assert not len(log.touching)
    assert len(log.update(np.array([0]), np.array([0]), touching, 50)) == 1
    assert log.count == 2 and [event.robot for event in log.events] == [1, 1]
    approach = ObstacleApproach(obstacles, 0.1, np.array([[3.0, 0.0], [0.0, 2.0]]))
    assert approach.gap == pytest.approx(0.9) and approach.pair == (1, 0)
    approach.update(np.array([[3.0, 0.0], [0.0, 1.75]]), 7)
    approach.update(np.array([[3.0, 0.0], [0.0, 1.5]]), 8)
    assert approach.gap == pytest.approx(0.4) and approach.t_ns == 8


def test_the_turtlebot3_config_among_obstacles_crosses_them_without_contact(tmp_path, capsys):
    out = tmp_path / 'run'
    assert sim_main([OBSTACLE_CONFIG, '--engine', 'mujoco', '--out', str(out), '--duration',
                     '20', '--no-plots', '--quiet']) == 0
    assert 'with obstacles (closest body +' in capsys.readouterr().out
    stats = json.loads((out / 'world_stats.json').read_text())
    assert stats['obstacle_contacts'] == 0 and stats['contacts'] == 0
    assert stats['obstacle_contact_events'] == [] and stats['min_obstacle_gap'] > 0.0
    trajectory = Trajectory.load(str(out / 'trajectory.npz'))
    config = load_config(OBSTACLE_CONFIG)
    pillar_x, _, pillar_r = config.obstacles.circles[0]
    assert np.all(trajectory.q_body[0, :, 0] < pillar_x - pillar_r)
    assert np.all(trajectory.q_body[-1, :, 0] > pillar_x + pillar_r), 'the team got past it'
    gaps = config.obstacles.surface(trajectory.q_body.reshape(-1, 2)).distances - 0.105
    assert stats['min_obstacle_gap'] == pytest.approx(gaps.min(), abs=0.01)
    model = mujoco.MjModel.from_xml_path(str(out / 'world.xml'))
    assert model.geom('obstacle_wall_2').pos[1] == pytest.approx(-1.3)


def test_a_flyer_driven_into_a_sphere_and_one_into_a_pillar_stop_at_them():
    config = team([[0.0, 0.0, 1.0], [0.0, 3.0, 1.0]], 3, None,
                  {'body.radius': 0.1, 'obstacles.spheres': floats(1.0, 0.0, 1.0, 0.3),
                   'obstacles.circles': floats(1.0, 3.0, 0.2), 'obstacles.clearance': 0.3,
                   'formation.vertices': far_places(2, 3), **LIVE})
    engine = Engine(config)
    engine.apply([[0.3, 0.0, 0.0], [0.3, 0.0, 0.0]])
    run(engine, 5.0, every=10)
    positions = engine.poses().positions
    assert positions[0, 0] == pytest.approx(1.0 - 0.3 - 0.1, abs=0.005)
    assert positions[1, 0] == pytest.approx(1.0 - 0.2 - 0.1, abs=0.005)
    stats = engine.stats(engine.wall)
    assert sorted((e.robot, e.obstacle) for e in stats.obstacle_contact_events) == [
        (1, 'sphere 1'), (2, 'circle 1')]
    assert stats.contacts == 0 and -0.005 < stats.min_obstacle_gap < 0.001


def test_the_engine_run_s_law_keeps_a_base_off_a_pillar_it_would_hit_without(monkeypatch):
    config = bases([[-1.0, 0.0], [0.0, 3.0]], [0.0, 0.0],
                   {'obstacles.circles': floats(0.0, 0.02, 0.15), 'obstacles.clearance': 0.3,
                    'formation.vertices': floats(1.0, 0.0, 0.0, 3.0), 'controller.gain': 0.15,
                    'controller.psi': 'tanh', 'controller.kappa': 10.0,
                    'repulsion_radius': 0.8, 'sensing_radius': 1.5})
    runs = {'among': run_on_engine(config, 10.0, 0.02, 0.1, shapes_of(config), Quiet())}
    monkeypatch.setattr(FormationConfig, 'law_obstacles', lambda self: None)
    runs['blind'] = run_on_engine(config, 10.0, 0.02, 0.1, shapes_of(config), Quiet())
    assert runs['blind'].stats.obstacle_contacts == 1, 'the pillar is in its way'
    assert runs['among'].stats.obstacle_contacts == 0
    assert runs['among'].stats.min_obstacle_gap > 0.1


def test_the_closest_approach_to_obstacles_is_the_exact_minimum_over_a_random_walk():
    obstacles = Obstacles([0.0, 0.0, 0.5, 3.0, 1.0, 0.3], [-2.0, 2.0, 2.0, 2.5, 0.1], [], 0.2,
                          2)
    rng = np.random.default_rng(4)
    points = np.array([[0.9, 0.0], [-1.5, -1.0], [0.0, 1.5], [3.0, 1.6]])
    approach = ObstacleApproach(obstacles, 0.1, points)
    smallest = (obstacles.surface(points).distances - 0.1).min()
    for step in range(1, 600):
        points = points + rng.normal(0.0, 0.01, points.shape)
        approach.update(points, step)
        gaps = obstacles.surface(points).distances - 0.1
        if gaps.min() < smallest:
            smallest, when = gaps.min(), step
            pair = np.unravel_index(np.argmin(gaps), gaps.shape)
    assert smallest < 0.25
    assert approach.gap == pytest.approx(smallest, abs=1e-12)
    assert approach.t_ns == when and approach.pair == tuple(int(k) for k in pair)


def test_a_flying_team_s_pillars_cover_every_shape_it_may_take():
    config = team([[0.0, 0.0, 1.0], [1.0, 0.0, 1.0]], 3, None, {
        'obstacles.circles': floats(3.0, 3.0, 0.2), 'obstacles.clearance': 0.2,
        'formation.vertices': floats(-2.0, 0.0, 1.0, -2.0, 1.0, 1.0),
        'formations.names': ['high'],
        'formations.high.vertices': floats(-2.0, 0.0, 4.0, -2.0, 1.0, 6.5)})
    pillar = ElementTree.fromstring(build_scene(config).xml).find(
        ".//geom[@name='obstacle_circle_1']")
    z, half = float(pillar.get('pos').split()[2]), float(pillar.get('size').split()[1])
    assert z + half == pytest.approx(6.5 + CEILING_ABOVE)


def test_bodies_larger_than_the_law_keeps_off_the_obstacles_are_said_once():
    pillar = {'obstacles.circles': floats(3.0, 3.0, 0.2), 'obstacles.clearance': 0.2,
              'formation.vertices': far_places(2, 2)}
    bare = team([[0.0, 0.0], [1.0, 0.0]], 2, None, pillar)
    run = run_on_engine(bare, 0.04, 0.02, 0.02, shapes_of(bare), Quiet())
    assert run.note == ('the bodies in the world are 0.1 m in radius but body.radius is 0 m, '
                        'all the law keeps off the obstacles: a body may touch one '
                        '(body.radius: 0.1 would cover it)')
    assert engine_summary(run).endswith(f'\n  note: {run.note}')
    sized = Engine(team([[0.0, 0.0], [1.0, 0.0]], 2, None, {**pillar, 'body.radius': 0.1}))
    assert footprint_note(sized.obstacles, 0.1, sized.model.footprint) is None
    base = Engine(bases([[0.0, 0.0], [1.0, 0.0]], [0.0, 0.0], pillar))
    assert footprint_note(base.obstacles, 0.11, base.model.footprint) is None
    free = Engine(team([[0.0, 0.0], [1.0, 0.0]]))
    assert footprint_note(free.obstacles, 0.0, free.model.footprint) is None
