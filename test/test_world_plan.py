# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""A simulated lab: launch_formation.sh --world and world.launch.py agree; misfits refused."""

import os

from formation_ros.core.settings.params_file import load_params_file, write_params_file
import pytest
from test_package import launched_nodes
from test_scripts import make_fake_install, run
from test_system_plan import launcher_views, node_view

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
WORLD = os.path.join(ROOT, 'config', 'world_turtlebot3.yaml')
WORLD_OBSTACLES = os.path.join(ROOT, 'config', 'world_turtlebot3_obstacles.yaml')
WORLD_DOORWAY = os.path.join(ROOT, 'config', 'world_doorway.yaml')
LAB = os.path.join(ROOT, 'config', 'lab_turtlebot3.yaml')


@pytest.fixture
def world_launch_file(monkeypatch):
    """Give the test launch/world.launch.py on stand-ins (``test_package.load_launch_file``)."""
    from test_package import load_launch_file
    return load_launch_file(monkeypatch, 'world.launch.py')


@pytest.fixture
def world_install(tmp_path):
    """Give the test an install prefix of stand-in nodes, world and relay included."""
    return make_fake_install(tmp_path, ('plant', 'world', 'relay', 'reference', 'robot',
                                        'record', 'fleet'))


@pytest.mark.parametrize('config', [WORLD, WORLD_OBSTACLES, WORLD_DOORWAY])
def test_the_world_relay_reference_and_robots_run_on_the_worlds_clock(config):
    from formation_ros.core.settings.declarations import BY_NAME as schema, Exe
    views = launcher_views(config, ['--world', '--out', '/nonexistent/w', '--record',
                                    '/nonexistent/w_bag'])
    values = load_params_file(config)
    robots_started = ['robot'] * values['num_robots']
    assert [view['executable'] for view in views] == ['record', 'world', 'relay',
                                                      'reference'] + robots_started
    record, world, relay, reference, *robots = views
    assert record['parameters'] == {'record.path': '/nonexistent/w_bag'}
    assert world['parameters'] == {'world.output_dir': '/nonexistent/w'}
    assert relay['parameters'] == {'use_sim_time': True}
    assert reference['parameters'] == {'use_sim_time': True}
    rate = values.get('relay.rate', schema['relay.rate'].default)
    for i, robot in enumerate(robots, start=1):
        assert robot['parameters'] == {'robot_id': i, 'wait_for_subscribers': 2,
                                       'use_sim_time': True, 'plant.rate': rate,
                                       'plant.publish_rate': rate}
        assert robot['remappings'] == []
    for view in views:
        for name in view['parameters']:
            assert name == 'use_sim_time' or Exe(view['executable']) in schema[name].users


@pytest.mark.parametrize('argv, arguments', [
    ((), {}),
    (('--out', '/nonexistent/w'), {'output_dir': '/nonexistent/w'}),
    (('--robots-per-process', '2', '--record', '/nonexistent/w_bag'),
     {'robots_per_process': '2', 'record': '/nonexistent/w_bag'}),
    (('--source-topic', '/robot_{i}/measured_pose'),
     {'source_topic': '/robot_{i}/measured_pose'}),
])
def test_world_launch_file_starts_what_the_launcher_starts(world_launch_file, argv, arguments):
    nodes = launched_nodes(world_launch_file, params_file=WORLD, **arguments)
    assert [node_view(node) for node in nodes] == launcher_views(WORLD, ['--world', *argv])


def test_world_launch_file_defaults_to_the_turtlebot3_like_team(world_launch_file):
    nodes = launched_nodes(world_launch_file)
    assert node_view(nodes[0])['executable'] == 'world'
    assert node_view(nodes[0])['params_file'].endswith('config/world_turtlebot3.yaml')


def lockstep(tmp_path):
    path = str(tmp_path / 'lockstep.yaml')
    write_params_file(path, dict(load_params_file(WORLD), **{'plant.lockstep': True}))
    return path


@pytest.mark.parametrize('params, args, says', [
    (LAB, (), "the world's relay reads the world: relay.source_topic gives "
              "'/vrpn_mocap/tb1/pose' (pose) for robot 1, not '/robot_1/measured_pose'"),
    (WORLD, ('--source-topic', '/mocap/robot_{i}'), "the world's relay reads the world"),
    (WORLD, ('--no-plant',), '--world is a lab of its own: leave out --no-plant'),
    (WORLD, ('--cmd-topic', '/tb{i}/cmd_vel'), '--cmd-topic does not fit --world'),
    (None, (), 'plant.lockstep does not fit a world'),
])
def test_world_runs_that_cannot_work_are_refused_in_one_line(world_install, tmp_path, params,
                                                             args, says):
    result = run('launch_formation.sh', params or lockstep(tmp_path), '--world', *args,
                 '--prefix', str(world_install))
    assert result.returncode == 2
    assert result.stderr.startswith(f'launch_formation.sh: {says}'), result.stderr
    assert len(result.stderr.splitlines()) == 1, result.stderr
    assert result.stdout == ''


def test_an_install_without_the_world_is_refused(world_install):
    (world_install / 'lib' / 'formation_ros' / 'world').unlink()
    result = run('launch_formation.sh', WORLD, '--world', '--prefix', str(world_install))
    assert result.returncode == 2
    assert result.stderr == ('launch_formation.sh: --world needs the world: no '
                             f"{world_install / 'lib' / 'formation_ros' / 'world'}\n")


def test_help_tells_the_world_option():
    usage = run('launch_formation.sh', '--help').stdout
    assert '[--world [--world-params' in usage and '--world        a simulated lab' in usage


def test_world_launch_file_refuses_a_lab_file(world_launch_file):
    with pytest.raises(ValueError, match="the world's relay reads the world"):
        launched_nodes(world_launch_file, params_file=LAB)


def world_file(tmp_path, changes, source=WORLD_OBSTACLES, name='lab.yaml'):
    """Write the world's own parameters file: ``source`` with ``changes``; return its path."""
    path = str(tmp_path / name)
    write_params_file(path, dict(load_params_file(source), **changes))
    return path


CHAIR = {'obstacles.circles': [-0.4, 0.05, 0.15, 1.2, 1.5, 0.1, 0.0, -0.9, 0.12]}
"""The world's obstacles of config/world_turtlebot3_obstacles.yaml and a pillar off the map."""
THREE = {'num_robots': 3, 'formation.vertices': [1.8, 0.6, 0.6, 0.6, 0.6, -0.6],
         'start.positions': [-1.35, 0.45, -2.1, 0.4, -2.0, -0.45],
         'start.headings': [0.3, 0.0, -0.2]}
"""Three of the file's four robots: a world file with one robot less than the team's."""


def test_world_params_start_the_world_alone_from_its_own_file(tmp_path):
    lab = world_file(tmp_path, dict(CHAIR, **{'world.realtime_factor': 2.0}))
    views = launcher_views(WORLD_OBSTACLES, ['--world', '--world-params', lab, '--record',
                                             '/nonexistent/w_bag'])
    files = {view['executable']: view['params_file'] for view in views}
    assert [view['executable'] for view in views] == ['record', 'world', 'relay',
                                                      'reference'] + ['robot'] * 4
    assert files['world'] == lab
    assert {view['params_file'] for view in views if view['executable'] != 'world'} == {
        WORLD_OBSTACLES}
    assert [dict(view, params_file=WORLD_OBSTACLES) for view in views] == launcher_views(
        WORLD_OBSTACLES, ['--world', '--record', '/nonexistent/w_bag'])


def test_world_params_give_the_run_the_worlds_realtime_factor(tmp_path):
    from formation_ros.tools import launcher
    lab = world_file(tmp_path, dict(CHAIR, **{'world.realtime_factor': 2.0}))
    options = launcher.check_paths(launcher.parse_args([WORLD_OBSTACLES, '--world']))
    alone = launcher.read_parameters(options)
    apart = launcher.read_parameters(launcher.check_paths(launcher.parse_args(
        [WORLD_OBSTACLES, '--world', '--world-params', lab])))
    duration = load_params_file(WORLD_OBSTACLES)['duration']
    assert alone.wall_seconds == duration and apart.wall_seconds == duration / 2.0
    assert apart.num_robots == alone.num_robots and apart.relay_rate == alone.relay_rate


@pytest.mark.parametrize('changes, args, says', [
    (None, ('--no-plant',), "--world-params needs --world: it is the world's own parameters "
                            'file'),
    (None, (), "--world-params needs --world: it is the world's own parameters file"),
    ('missing', ('--world',), "--world-params file '{lab}' not found"),
    (THREE, ('--world',), '--world-params {lab} gives the world another num_robots 3 '
                          '(PARAMS: 4); sensing radii '),
    ({'world_frame': 'map', 'controller.gain': 0.1}, ('--world',),
     '--world-params {lab} gives the world another law c=0.1 kappa=10.0 psi=tanh '
     'jump=poly/2 b=0.8 (PARAMS: c=0.15 kappa=10.0 psi=tanh jump=poly/2 b=0.8); world_frame '
     'map (PARAMS: world): the world and the team must share them'),
    ({'body.hand_distance': 0.1}, ('--world',), '--world-params {lab} gives the world another '
                                                'body unicycle l=0.1 (PARAMS: unicycle '
                                                'l=0.08)'),
])
def test_world_params_that_cannot_work_are_refused_in_one_line(world_install, tmp_path,
                                                               changes, args, says):
    lab = (str(tmp_path / 'no such lab.yaml') if changes == 'missing'
           else world_file(tmp_path, changes or {}))
    result = run('launch_formation.sh', WORLD_OBSTACLES, *args, '--world-params', lab,
                 '--prefix', str(world_install))
    assert result.returncode == 2
    assert result.stderr.startswith('launch_formation.sh: ' + says.format(lab=lab)), \
        result.stderr
    assert len(result.stderr.splitlines()) == 1, result.stderr
    assert result.stdout == ''


def test_a_world_file_the_world_would_refuse_is_refused_before_anything_starts(world_install,
                                                                               tmp_path):
    lab = world_file(tmp_path, {'world.timestep': -0.002})
    result = run('launch_formation.sh', WORLD_OBSTACLES, '--world', '--world-params', lab,
                 '--prefix', str(world_install))
    assert result.returncode == 2
    assert result.stderr.startswith(f'launch_formation.sh: invalid parameters in {lab}:\n'), \
        result.stderr
    assert 'world.timestep' in result.stderr
    assert result.stdout == ''
    broken = tmp_path / 'broken.yaml'
    broken.write_text('/**:\n  ros__parameters: [\n')
    result = run('launch_formation.sh', WORLD_OBSTACLES, '--world', '--world-params',
                 str(broken), '--prefix', str(world_install))
    assert result.returncode == 2
    assert result.stderr.startswith(f'launch_formation.sh: --world-params file {broken}'), \
        result.stderr
    assert len(result.stderr.splitlines()) == 1, result.stderr


def test_help_tells_the_world_params_option():
    usage = run('launch_formation.sh', '--help').stdout
    assert '[--world [--world-params WORLD.yaml]]' in usage
    assert "--world-params WORLD.yaml\n                 (with --world) the world's own" in usage
