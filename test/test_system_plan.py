# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""A lab without the plant: launch_formation.sh --no-plant and launch/lab.launch.py agree."""

import dataclasses
import os
from pathlib import Path
import subprocess
import sys

from formation_ros.core.settings.params_file import load_params_file, write_params_file
import pytest
from test_package import launched_nodes, node_parameters, Shutdown
from test_scripts import launch_fake, make_fake_install, run
import yaml

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SQUARE = os.path.join(ROOT, 'config', 'square_4.yaml')
NAMES = ['tb1', 'tb2', 'tb3', 'tb4']


@pytest.fixture
def lab_install(tmp_path):
    """Give the test an install prefix of stand-in nodes (test_scripts' fake), relay included."""
    return make_fake_install(tmp_path, ('plant', 'relay', 'reference', 'robot', 'record',
                                        'fleet'))


@pytest.fixture
def named(tmp_path):
    """Give the test square_4.yaml with relay.source_names tb1..tb4 and a mocap source."""
    values = load_params_file(SQUARE)
    values.update({'relay.source_names': NAMES, 'relay.source_topic': '/mocap/{name}/pose',
                   'world_frame': 'map'})
    path = str(tmp_path / 'lab.yaml')
    write_params_file(path, values)
    return path


@pytest.mark.parametrize('args, says', [
    (('--cmd-topic', '/tb{i}/cmd_vel'), '--cmd-topic needs --no-plant'),
    (('--source-topic', '/m/{i}'), '--source-topic needs --no-plant'),
    (('--no-plant', '--out', 'x'), '--out with --no-plant needs --record'),
    (('--no-plant', '--cmd-topic', '/tb{i}/cmd_vel', '--robots-per-process', '2'),
     '--cmd-topic cannot be used with more than one robot per process'),
    (('--no-plant', '--cmd-topic'), '--cmd-topic needs a topic template'),
])
def test_lab_options_that_cannot_work_are_refused_in_one_line(args, says):
    result = run('launch_formation.sh', SQUARE, *args)
    assert result.returncode == 2
    assert result.stderr.startswith(f'launch_formation.sh: {says}'), result.stderr
    assert len(result.stderr.splitlines()) == 1, result.stderr


@pytest.mark.parametrize('args, says', [
    (('--cmd-topic', '/tb{x}/cmd_vel'),
     "--cmd-topic may use only {i} and {name}, got {x} in '/tb{x}/cmd_vel'"),
    (('--cmd-topic', '/tb{name}/cmd_vel'),
     "relay.source_names is required: --cmd-topic '/tb{name}/cmd_vel' uses {name}"),
    (('--cmd-topic', '/base/cmd_vel'), "--cmd-topic '/base/cmd_vel' names no robot"),
    (('--cmd-topic', 'tb{i}/cmd_vel'),
     "--cmd-topic 'tb{i}/cmd_vel' gives robot 1 'tb1/cmd_vel', not an absolute ROS topic"),
    (('--cmd-topic', '/{i}/cmd_vel'),
     "--cmd-topic '/{i}/cmd_vel' gives robot 1 '/1/cmd_vel', not an absolute ROS topic"),
    (('--cmd-topic', '/tb{i'), '--cmd-topic is not a topic template'),
    (('--source-topic', '/mocap/{i}/{k}'),
     '--source-topic may use only {i} and {name}, got {k}'),
    (('--source-topic', '/mocap/{name}'),
     "relay.source_names is required: --source-topic '/mocap/{name}' uses {name}"),
    (('--source-topic', '{i}/pose'), "--source-topic '{i}/pose' gives robot 1 '1/pose'"),
])
def test_bad_topic_templates_are_refused_in_one_line(lab_install, args, says):
    result = run('launch_formation.sh', SQUARE, '--no-plant', *args, '--prefix',
                 str(lab_install))
    assert result.returncode == 2
    assert result.stderr.startswith(f'launch_formation.sh: {says}'), result.stderr
    assert len(result.stderr.splitlines()) == 1, result.stderr


def test_an_install_without_the_relay_is_refused(lab_install):
    (lab_install / 'lib' / 'formation_ros' / 'relay').unlink()
    result = run('launch_formation.sh', SQUARE, '--no-plant', '--prefix', str(lab_install))
    assert result.returncode == 2
    assert result.stderr == ('launch_formation.sh: --no-plant needs the relay: no '
                             f"{lab_install / 'lib' / 'formation_ros' / 'relay'}\n")


def test_help_tells_the_lab_options():
    usage = run('launch_formation.sh', '--help').stdout
    for option in ('--no-plant', '--cmd-topic TEMPLATE', '--source-topic TEMPLATE'):
        assert option in usage


def test_templates_fill_in_ids_and_names(named):
    from formation_ros.tools.system import read_formation
    formation = read_formation(named, plant=False, cmd_topic='/{name}/cmd_vel_{i}')
    assert formation.cmd_topics == tuple(f'/tb{i}/cmd_vel_{i}' for i in range(1, 5))
    assert formation.num_robots == 4
    assert formation.wall_seconds == load_params_file(named)['duration']


def spec_view(spec):
    """Return (executable, own args, namespace, params file, overrides, remaps) of a spec."""
    argv = list(spec.argv)
    split = argv.index('--ros-args')
    view = {'executable': os.path.basename(argv[0]), 'arguments': argv[1:split],
            'namespace': None, 'params_file': None, 'parameters': {}, 'remappings': []}
    ros = iter(argv[split + 1:])
    for flag in ros:
        value = next(ros)
        if flag == '--params-file':
            view['params_file'] = value
        elif flag == '-p':
            name, text = value.split(':=', 1)
            view['parameters'][name] = yaml.safe_load(text)
        elif flag == '-r' and value.startswith('__ns:='):
            view['namespace'] = value[len('__ns:='):]
        else:
            assert flag == '-r', argv
            view['remappings'].append(tuple(value.split(':=', 1)))
    return view


def node_view(node):
    """Return the same view of a launch_ros Node stand-in, its namespace made absolute."""
    params_file, overrides = node_parameters(node)
    namespace = node.kwargs['namespace']
    on_exit = node.kwargs['on_exit']
    if node.kwargs['executable'] == 'record' and not isinstance(on_exit, Shutdown):
        on_exit = on_exit.shutdown
    assert isinstance(on_exit, Shutdown)
    assert node.kwargs['package'] == 'formation_ros'
    return {'executable': node.kwargs['executable'],
            'arguments': list(node.kwargs['arguments'] or []),
            'namespace': None if namespace is None else '/' + namespace,
            'params_file': params_file, 'parameters': overrides,
            'remappings': [tuple(pair) for pair in node.kwargs['remappings'] or []]}


def launcher_views(params, argv):
    """Return the views of every process the launcher starts for ``argv``, recorder first."""
    from formation_ros.tools import launcher
    options = launcher.check_paths(launcher.parse_args([params, *argv]))
    formation = launcher.read_parameters(options)
    options = dataclasses.replace(options, cmd_topics=formation.cmd_topics)
    install = launcher.Install('/opt/formation')
    specs = launcher.node_specs(install, options, formation.num_robots, {})
    if options.record is not None:
        specs.insert(0, launcher.recorder_spec(install, options, {}))
    return [spec_view(spec) for spec in specs]


LAB_CASES = [
    ((), {}),
    (('--cmd-topic', '/base_{i}/cmd_vel'), {'cmd_topic': '/base_{i}/cmd_vel'}),
    (('--cmd-topic', '/base{i}/cmd_vel'), {'cmd_topic': '/base{i}/cmd_vel'}),
    (('--cmd-topic', '/{name}/cmd_vel', '--source-topic', '/vrpn_mocap/{name}/pose'),
     {'cmd_topic': '/{name}/cmd_vel', 'source_topic': '/vrpn_mocap/{name}/pose'}),
    (('--cmd-topic', '/{name}/cmd_vel', '--source-topic', '/vrpn_mocap/{name}/pose',
      '--record', '/tmp/lab_bag'),
     {'cmd_topic': '/{name}/cmd_vel', 'source_topic': '/vrpn_mocap/{name}/pose',
      'record': '/tmp/lab_bag'}),
    (('--robots-per-process', '3', '--record', '/tmp/lab_bag'),
     {'robots_per_process': '3', 'record': '/tmp/lab_bag'}),
]


@pytest.mark.parametrize('argv, arguments', LAB_CASES)
def test_lab_launch_file_starts_what_the_launcher_starts(lab_launch_file, named, argv,
                                                         arguments):
    nodes = launched_nodes(lab_launch_file, params_file=named, **arguments)
    assert [node_view(node) for node in nodes] == launcher_views(named, ['--no-plant', *argv])


def test_a_lab_runs_relay_reference_and_robots_on_wall_clock_time(named):
    from formation_ros.core.settings.declarations import BY_NAME as schema, Exe
    views = launcher_views(named, ['--no-plant', '--cmd-topic', '/{name}/cmd_vel',
                                   '--source-topic', '/vrpn_mocap/{name}/pose', '--record',
                                   '/tmp/lab_bag'])
    assert [view['executable'] for view in views] == ['record', 'relay', 'reference'] + \
        ['robot'] * 4
    record, relay, reference, *robots = views
    assert record['parameters'] == {'record.path': '/tmp/lab_bag'}
    assert record['remappings'] == [(f'/robot_{i}/cmd_vel', f'/tb{i}/cmd_vel')
                                    for i in range(1, 5)]
    assert relay['parameters'] == {'relay.source_topic': '/vrpn_mocap/{name}/pose'}
    assert relay['remappings'] == [] and relay['namespace'] is None
    assert reference['parameters'] == {'use_sim_time': False}
    for i, robot in enumerate(robots, start=1):
        assert robot['namespace'] == f'/robot_{i}'
        assert robot['parameters'] == {'robot_id': i, 'wait_for_subscribers': 2,
                                       'use_sim_time': False}
        assert robot['remappings'] == [('cmd_vel', f'/tb{i}/cmd_vel')]
    for view in views:
        assert view['params_file'] == named
        for name in view['parameters']:
            assert name == 'use_sim_time' or Exe(view['executable']) in schema[name].users, \
                f"{view['executable']} does not read {name}"


def test_a_lab_robot_waits_for_its_base_alone_without_a_recorder(named):
    views = launcher_views(named, ['--no-plant', '--cmd-topic', '/base_{i}/cmd_vel'])
    assert [view['executable'] for view in views] == ['relay', 'reference'] + ['robot'] * 4
    assert {view['parameters'].get('wait_for_subscribers') for view in views[2:]} == {1}
    assert views[0]['parameters'] == {}


def test_lab_launch_file_declares_its_arguments(lab_launch_file):
    description = lab_launch_file.generate_launch_description()
    declared = {action.args[0]: action.kwargs.get('default_value')
                for action in description.args[0] if action.args}
    assert declared == {'params_file': None, 'cmd_topic': '', 'source_topic': '',
                        'robots_per_process': '1', 'discovery': '', 'domain_id': '',
                        'record': '', 'on_record_failure': 'continue'}


@pytest.mark.parametrize('arguments, says', [
    ({'cmd_topic': '/tb{i}/cmd_vel', 'robots_per_process': '2'},
     'cmd_topic cannot be used with more than one robot per process'),
    ({'cmd_topic': '/tb{x}/cmd_vel'}, r'cmd_topic may use only \{i\} and \{name\}'),
    ({'source_topic': 'pose_{i}'}, "source_topic 'pose_{i}' gives robot 1 'pose_1'"),
    ({'discovery': 'wan'}, 'discovery must be one of localhost, subnet'),
    ({'domain_id': '300'}, 'domain_id must be a whole number from 0 to 232'),
    ({'robots_per_process': '0'}, 'robots_per_process must be >= 1'),
])
def test_lab_launch_file_refuses_what_the_launcher_refuses(lab_launch_file, arguments, says):
    with pytest.raises(ValueError, match=says):
        launched_nodes(lab_launch_file, params_file=SQUARE, **arguments)


def test_lab_launch_file_refuses_bad_parameters(lab_launch_file, tmp_path):
    from formation_ros.core.settings.declarations import ParamError
    values = dict(load_params_file(SQUARE), **{'relay.source_names': ['a', 'a', 'b', 'c']})
    path = str(tmp_path / 'twice.yaml')
    write_params_file(path, values)
    with pytest.raises(ParamError, match='names must differ'):
        launched_nodes(lab_launch_file, params_file=path)


def test_the_lab_executables_are_console_scripts(lab_launch_file, named):
    from colcon_python_setup_py.package_identification.python_setup_py import (
        get_setup_information)
    setup_data = get_setup_information(Path(ROOT) / 'setup.py')
    scripts = {entry.split('=')[0].strip()
               for entry in setup_data['entry_points']['console_scripts']}
    executables = {node.kwargs['executable']
                   for node in launched_nodes(lab_launch_file, params_file=named)}
    assert executables <= scripts, executables - scripts


@pytest.mark.faults
def test_the_relay_is_essential_and_the_robots_get_their_remaps(lab_install):
    result = launch_fake(lab_install, 'relay', '--no-plant', '--cmd-topic', '/base_{i}/cmd_vel')
    assert result.returncode == 1, result.stderr
    assert 'relay ended on its own (exit code 3); stopped the others' in result.stderr
    head = result.stdout.splitlines()[0]
    assert '4 robots, no plant (relay, wall-clock time) from' in head, head
    assert '[plant]' not in result.stdout
    args = {line.split('] ')[0][1:]: line.split('] args ')[1].split()
            for line in result.stdout.splitlines() if '] args ' in line}
    assert sorted(args) == ['reference', 'relay'] + [f'robot_{i}' for i in range(1, 5)]
    for i in range(1, 5):
        robot = args[f'robot_{i}']
        assert robot[robot.index('-r', robot.index('--params-file')) + 1] == \
            f'cmd_vel:=/base_{i}/cmd_vel', robot
        assert 'use_sim_time:=false' in robot and 'wait_for_subscribers:=1' in robot
    for i in range(1, 5):
        assert f'[robot_{i}] closing robot_{i}' in result.stdout


def test_launcher_module_runs_without_ros_for_help():
    result = subprocess.run([sys.executable, '-c', 'import sys, formation_ros.tools.launcher; '
                             "print(sorted(m for m in sys.modules if m.split('.')[0] in "
                             "('numpy', 'rclpy', 'launch', 'launch_ros')))"],
                            capture_output=True, text=True, cwd=ROOT, timeout=60)
    assert result.returncode == 0 and result.stdout.strip() == '[]', result.stdout + \
        result.stderr


class Exited:
    """Stands in for launch.events.process.ProcessExited: the exit code of a process."""

    def __init__(self, returncode):
        """Keep ``returncode``."""
        self.returncode = returncode


@pytest.mark.parametrize('policy', ['continue', 'stop', ''])
def test_a_failed_recording_ends_a_launch_file_run_only_when_asked(launch_file, policy):
    from formation_ros.core.settings.exits import RECORDING_FAILED
    nodes = launched_nodes(launch_file, params_file=SQUARE, record='/tmp/bag',
                           on_record_failure=policy)
    (recorder,) = [node for node in nodes if node.kwargs['executable'] == 'record']
    on_exit = recorder.kwargs['on_exit']
    if policy == 'stop':
        assert isinstance(on_exit, Shutdown)
        return
    shutdown = on_exit.shutdown
    assert isinstance(shutdown, Shutdown)
    assert on_exit(Exited(RECORDING_FAILED), {}) is None
    for code in (0, 1, 2, -9):
        assert on_exit(Exited(code), {}) is shutdown
    others = [node for node in nodes if node.kwargs['executable'] != 'record']
    assert all(isinstance(node.kwargs['on_exit'], Shutdown) for node in others)


def test_a_launch_file_refuses_an_unknown_record_failure_policy(launch_file):
    with pytest.raises(ValueError, match='on_record_failure must be one of continue, stop, '
                                         "got 'later'"):
        launched_nodes(launch_file, params_file=SQUARE, record='/tmp/bag',
                       on_record_failure='later')


FORMATION_CASES = [
    ((), {}),
    (('--record', '/tmp/bag', '--out', '/tmp/out'),
     {'record': '/tmp/bag', 'output_dir': '/tmp/out'}),
    (('--robots-per-process', '3'), {'robots_per_process': '3'}),
    (('--robots-per-process', '3', '--record', '/tmp/bag'),
     {'robots_per_process': '3', 'record': '/tmp/bag'}),
    (('--discovery', 'subnet', '--domain-id', '7'), {'discovery': 'subnet', 'domain_id': '7'}),
]
NETWORK_CASES = [
    ((), {}),
    (('--discovery', 'subnet'), {'discovery': 'subnet'}),
    (('--discovery', 'localhost', '--domain-id', '7'),
     {'discovery': 'localhost', 'domain_id': '7'}),
    (('--domain-id', '0'), {'domain_id': '0'}),
]
SHELLS = [{}, {'ROS_AUTOMATIC_DISCOVERY_RANGE': 'SUBNET', 'ROS_DOMAIN_ID': '3'},
          {'ROS_LOCALHOST_ONLY': '1'}, {'ROS_AUTOMATIC_DISCOVERY_RANGE': ''}]
NETWORK_NAMES = ('ROS_AUTOMATIC_DISCOVERY_RANGE', 'ROS_DOMAIN_ID', 'ROS_LOCALHOST_ONLY')


def launched_environment(actions, base):
    """Return each node's environment: ``base`` after the actions before it, its own added."""
    from test_package import Node, UnsetEnvironmentVariable
    env = dict(base)
    environments = []
    for action in actions:
        if isinstance(action, UnsetEnvironmentVariable):
            env.pop(action.args[0], None)
        else:
            assert isinstance(action, Node), action
            environments.append(dict(env, **action.kwargs['additional_env']))
    return environments


@pytest.mark.parametrize('argv, arguments', FORMATION_CASES)
def test_formation_launch_file_starts_what_the_launcher_starts(launch_file, argv, arguments):
    nodes = launched_nodes(launch_file, params_file=SQUARE, **arguments)
    assert [node_view(node) for node in nodes] == launcher_views(SQUARE, list(argv))


@pytest.mark.parametrize('lab', [False, True])
@pytest.mark.parametrize('shell', SHELLS)
@pytest.mark.parametrize('argv, arguments', NETWORK_CASES)
def test_both_launch_files_give_every_node_the_launchers_environment(
        launch_file, lab_launch_file, named, monkeypatch, lab, shell, argv, arguments):
    """The discovery range, domain and ROS_LOCALHOST_ONLY of each node, from one shell."""
    from formation_ros.tools import launcher
    from test_package import launched_actions
    for name in NETWORK_NAMES:
        monkeypatch.delenv(name, raising=False)
    for name, value in shell.items():
        monkeypatch.setenv(name, value)
    base = dict(os.environ)
    options = launcher.parse_args([named, *(('--no-plant',) if lab else ()), *argv])
    expected = launcher.discovery_environment(options, base)
    actions = launched_actions(lab_launch_file if lab else launch_file, params_file=named,
                               **arguments)
    environments = launched_environment(actions, base)
    assert len(environments) == 6
    assert all(env == expected for env in environments), (environments[0], expected)
    if 'discovery' in arguments:
        assert expected['ROS_AUTOMATIC_DISCOVERY_RANGE'] == arguments['discovery'].upper()
        assert 'ROS_LOCALHOST_ONLY' not in expected
    else:
        assert expected['ROS_AUTOMATIC_DISCOVERY_RANGE'] == (
            shell.get('ROS_AUTOMATIC_DISCOVERY_RANGE') or 'LOCALHOST')
    assert expected.get('ROS_DOMAIN_ID') == arguments.get('domain_id',
                                                          shell.get('ROS_DOMAIN_ID'))


def test_the_launcher_stops_what_it_started_in_the_planned_order(named):
    """Robots, reference and relay (or plant) together, the recorder after them."""
    from formation_ros.tools.system import ESSENTIAL, plan, Run, stop_stages
    names = [node.name for node in plan(Run(4, plant=False, record='/tmp/b'))]
    assert names[0] == 'record'
    assert stop_stages(names) == [names[1:], ['record']]
    assert stop_stages(names[1:]) == [names[1:]]
    assert [name for name in names if name in ESSENTIAL] == ['record', 'relay', 'reference']


def test_the_domain_range_is_told_as_the_code_checks_it(launch_file):
    from formation_ros.tools import launcher
    from formation_ros.tools.system import domain_problem, MAX_DOMAIN_ID
    told = f'0 to {MAX_DOMAIN_ID}'
    assert told in launcher.USAGE and told in launch_file.__doc__
    assert domain_problem(str(MAX_DOMAIN_ID)) is None
    assert domain_problem(str(MAX_DOMAIN_ID + 1)) is not None
