# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""The shell scripts' command lines: help, clear errors, strict mode."""

import os
import signal
import subprocess
import sys
import time

import pytest

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SCRIPTS = ('setup_env.sh', 'demo.sh', 'run_tests.sh', 'launch_formation.sh', 'hosts.sh',
           'build_docs.sh')


def run(script, *args):
    return subprocess.run(['bash', os.path.join(ROOT, 'scripts', script), *args],
                          capture_output=True, text=True, timeout=60)


@pytest.mark.parametrize('script', SCRIPTS)
def test_help_and_strict_mode(script):
    result = run(script, '--help')
    assert result.returncode == 0 and result.stdout.startswith('Usage:')
    with open(os.path.join(ROOT, 'scripts', script)) as stream:
        assert 'set -euo pipefail' in stream.read()


@pytest.mark.parametrize('script', SCRIPTS)
def test_unknown_option_is_refused(script):
    result = run(script, '--no-such-option')
    assert result.returncode == 2 and 'unknown option' in result.stderr


def test_launcher_reports_a_missing_file(tmp_path):
    result = run('launch_formation.sh', str(tmp_path / 'missing.yaml'))
    assert result.returncode == 2 and 'not found' in result.stderr


def test_launcher_rejects_a_bad_duration():
    result = run('launch_formation.sh', os.path.join(ROOT, 'config', 'square_4.yaml'),
                 '--duration', 'soon')
    assert result.returncode == 2 and '--duration' in result.stderr


def test_launcher_refuses_an_existing_bag_directory(tmp_path):
    (tmp_path / 'bag').mkdir()
    (tmp_path / 'bag' / 'x').write_text('x')
    result = run('launch_formation.sh', os.path.join(ROOT, 'config', 'square_4.yaml'),
                 '--record', str(tmp_path / 'bag'), '--prefix', str(tmp_path))
    assert result.returncode == 2 and 'exists already' in result.stderr


def test_launcher_takes_one_parameters_file():
    square = os.path.join(ROOT, 'config', 'square_4.yaml')
    result = run('launch_formation.sh', square, square)
    assert result.returncode == 2 and 'only one parameters file' in result.stderr


def test_launcher_refuses_a_non_empty_out_directory(tmp_path):
    (tmp_path / 'run').mkdir()
    (tmp_path / 'run' / 'x').write_text('x')
    result = run('launch_formation.sh', os.path.join(ROOT, 'config', 'square_4.yaml'),
                 '--out', str(tmp_path / 'run'))
    assert result.returncode == 2 and 'is not empty' in result.stderr


def test_launcher_names_a_prefix_without_the_package(tmp_path):
    result = run('launch_formation.sh', os.path.join(ROOT, 'config', 'square_4.yaml'),
                 '--prefix', str(tmp_path / 'no install'))
    assert result.returncode == 2
    assert f"no {tmp_path / 'no install' / 'lib' / 'formation_ros' / 'plant'}" in result.stderr
    assert len(result.stderr.splitlines()) == 1


FAKE_NODE = """#!{python}
import os, signal, sys, time
name = os.path.basename(sys.argv[0])
ns = next((a[len('__ns:='):] for a in sys.argv if a.startswith('__ns:=')), '')
me = ns.strip('/') or name
signal.signal(signal.SIGINT, lambda *_: (print('closing', me, flush=True), sys.exit(0)))
up = os.environ['FAKE_UP_DIR']
open(os.path.join(up, me), 'w').close()
print('up', os.environ.get('FORMATION_LAUNCHER_PID'), flush=True)
print('args', *sys.argv[1:], flush=True)
print('network', *(os.environ.get(name, '-') for name in (
    'ROS_DOMAIN_ID', 'ROS_AUTOMATIC_DISCOVERY_RANGE', 'ROS_LOCALHOST_ONLY')), flush=True)
if me == os.environ.get('FAKE_DIES'):
    deadline = time.monotonic() + 60.0
    while len(os.listdir(up)) < 6 and time.monotonic() < deadline:
        time.sleep(0.01)
    sys.exit(3)
while True:
    time.sleep(1)
"""
"""A fake node: ready for Ctrl-C before it says it is up; the one that dies waits for all six."""


def make_fake_install(folder, names=('plant', 'reference', 'robot', 'record')):
    """Make an install prefix in ``folder`` whose nodes ``names`` are :data:`FAKE_NODE`."""
    prefix = folder / 'fake install'
    programs = prefix / 'lib' / 'formation_ros'
    programs.mkdir(parents=True)
    for name in names:
        (programs / name).write_text(FAKE_NODE.format(python=sys.executable))
        (programs / name).chmod(0o755)
    sites = prefix / 'lib' / 'python3' / 'site-packages'
    sites.mkdir(parents=True)
    (sites / 'formation_ros').symlink_to(os.path.join(ROOT, 'formation_ros'))
    return prefix


@pytest.fixture
def fake_install(tmp_path):
    """Give the test an install prefix whose nodes are tiny Python scripts that need no ROS."""
    return make_fake_install(tmp_path)


FAKE_RUN_LIMIT = 120.0
"""Seconds after which a fake run that neither met its condition nor ended is ended (a fail)."""


def launch_fake(prefix, dies, *options, until=None):
    """
    Run the launcher on the fake install with FAKE_DIES=dies; return its result.

    until(stdout, stderr): when it holds, the launcher is sent Ctrl-C as a user would; without
    it the run lasts until the launcher stops on its own (a node it cannot do without ended).
    """
    up = prefix.parent / 'up'
    up.mkdir(exist_ok=True)
    env = dict(os.environ, FAKE_DIES=dies, FAKE_UP_DIR=str(up))
    env.pop('FORMATION_PREFIX', None)
    out, err = prefix.parent / 'launcher.out', prefix.parent / 'launcher.err'
    with open(out, 'w') as stdout, open(err, 'w') as stderr:
        launcher = subprocess.Popen(
            ['bash', os.path.join(ROOT, 'scripts', 'launch_formation.sh'),
             os.path.join(ROOT, 'config', 'square_4.yaml'), '--prefix', str(prefix),
             '--duration', '0', *options], stdout=stdout, stderr=stderr, text=True, env=env)
        try:
            deadline = time.monotonic() + FAKE_RUN_LIMIT
            while launcher.poll() is None and time.monotonic() < deadline:
                if until is not None and until(out.read_text(), err.read_text()):
                    launcher.send_signal(signal.SIGINT)
                    break
                try:
                    launcher.wait(timeout=0.05)
                except subprocess.TimeoutExpired:
                    pass
            launcher.wait(timeout=FAKE_RUN_LIMIT)
        finally:
            if launcher.poll() is None:
                launcher.kill()
                launcher.wait()
    return subprocess.CompletedProcess(launcher.args, launcher.returncode, out.read_text(),
                                       err.read_text())


def all_up(stdout, stderr):
    """Whether the six fake nodes (plant, reference, four robots) have said they are up."""
    return stdout.count('] up ') >= 6


@pytest.mark.faults
def test_launcher_goes_on_without_a_dead_robot_by_default(fake_install):
    result = launch_fake(fake_install, 'robot_2',
                         until=lambda stdout, stderr: 'the others go on' in stderr)
    assert result.returncode == 1, result.stderr
    assert 'robot_2 ended on its own (exit code 3); the others go on' in result.stderr
    assert result.stderr.rstrip().endswith(
        'exit code 1: robot_2 ended on its own (exit code 3)'), result.stderr
    for name in ('plant', 'reference', 'robot_1', 'robot_3', 'robot_4'):
        assert f'[{name}] closing {name}' in result.stdout, result.stdout


@pytest.mark.faults
def test_launcher_stops_everything_when_a_robot_dies_with_on_exit_stop(fake_install):
    result = launch_fake(fake_install, 'robot_3', '--on-exit', 'stop')
    assert result.returncode == 1
    assert 'robot_3 ended on its own (exit code 3); stopped the others' in result.stderr
    assert 'the others go on' not in result.stderr
    assert '[robot_1] closing robot_1' in result.stdout


@pytest.mark.faults
def test_launcher_respawns_a_robot_at_most_five_times(fake_install):
    result = launch_fake(fake_install, 'robot_2', '--on-exit', 'respawn',
                         until=lambda stdout, stderr: 'after 5 restarts' in stderr)
    assert result.returncode == 1, result.stderr
    for k in range(1, 6):
        assert result.stderr.count(f'starting it again (restart {k} of 5)') == 1, result.stderr
    assert 'after 5 restarts; not starting it again, the others go on' in result.stderr
    assert result.stdout.count('[robot_2] up') == 6
    assert 'restarted 5 times' in result.stderr.splitlines()[-1]


@pytest.mark.faults
@pytest.mark.parametrize('essential', ['plant', 'reference'])
def test_launcher_always_stops_when_plant_or_reference_dies(fake_install, essential):
    result = launch_fake(fake_install, essential, '--on-exit', 'respawn')
    assert result.returncode == 1
    assert f'{essential} ended on its own (exit code 3); stopped the others' in result.stderr
    assert 'starting it again' not in result.stderr


@pytest.mark.faults
def test_nodes_are_told_the_launcher_process(fake_install):
    result = launch_fake(fake_install, '', until=all_up)
    assert result.returncode == 0, result.stderr
    pids = {line.split()[-1] for line in result.stdout.splitlines() if ' up ' in line}
    assert len(pids) == 1 and pids.pop().isdigit(), result.stdout


def test_launcher_refuses_an_unknown_on_exit_mode():
    result = run('launch_formation.sh', os.path.join(ROOT, 'config', 'square_4.yaml'),
                 '--on-exit', 'retry')
    assert result.returncode == 2
    assert '--on-exit must be one of continue, stop, respawn' in result.stderr
    assert '--on-exit' in run('launch_formation.sh', '--help').stdout


@pytest.mark.parametrize('value', ['0', '-1', 'two', '2.5'])
def test_launcher_refuses_a_bad_robots_per_process(value):
    result = run('launch_formation.sh', os.path.join(ROOT, 'config', 'square_4.yaml'),
                 '--robots-per-process', value)
    assert result.returncode == 2
    assert '--robots-per-process must be a whole number >= 1' in result.stderr


@pytest.mark.parametrize('per_process, expected', [
    (1, [('robot_1', None), ('robot_2', None), ('robot_3', None), ('robot_4', None)]),
    (3, [('fleet_1', '1-3'), ('fleet_2', '4-4')]),
    (4, [('fleet_1', '1-4')]),
    (10, [('fleet_1', '1-4')]),
])
def test_launcher_spreads_the_robots_over_processes(per_process, expected):
    from formation_ros.tools.launcher import Install, node_specs, Options
    options = Options(os.path.join(ROOT, 'config', 'square_4.yaml'),
                      robots_per_process=per_process)
    specs = node_specs(Install('/opt/x'), options, 4, {})[2:]
    got = []
    for spec in specs:
        args = list(spec.argv)
        executable = os.path.basename(args[0])
        assert executable == ('robot' if per_process == 1 else 'fleet'), args
        assert args[args.index('--ros-args'):].count('use_sim_time:=true') == 1, args
        got.append((spec.name, args[args.index('--robots') + 1] if '--robots' in args
                    else None))
    assert got == expected


def test_fleet_command_line():
    from formation_ros.nodes.fleet import parse_command_line, parse_ids, UsageError
    assert parse_ids('1-3,7, 9 - 10') == [1, 2, 3, 7, 9, 10]
    assert parse_command_line(['fleet', '--robots', '2-4', '--ros-args', '-p', 'x:=1']) == \
        [2, 3, 4]
    assert parse_command_line(['fleet', '--help']) is None
    for bad, says in (('0-2', 'below 1'), ('3-1', 'empty'), ('1,1', 'robot 1 is given twice'),
                      ('a', 'neither an id nor a range'), ('1-200000', 'more than')):
        with pytest.raises(UsageError, match=says):
            parse_ids(bad)
    with pytest.raises(UsageError, match='give the robots as --robots IDS'):
        parse_command_line(['fleet', '--ros-args', '-p', 'x:=1'])
    with pytest.raises(UsageError, match="'__ns:=/a' cannot be used"):
        parse_command_line(['fleet', '--robots', '1', '--ros-args', '-r', '__ns:=/a'])


@pytest.mark.parametrize('given, options, expected', [
    ({}, {}, ('LOCALHOST', None, None)),
    ({'ROS_AUTOMATIC_DISCOVERY_RANGE': 'SUBNET'}, {}, ('SUBNET', None, None)),
    ({'ROS_AUTOMATIC_DISCOVERY_RANGE': ''}, {}, ('LOCALHOST', None, None)),
    ({'ROS_AUTOMATIC_DISCOVERY_RANGE': 'SUBNET', 'ROS_LOCALHOST_ONLY': '1'},
     {'discovery': 'localhost'}, ('LOCALHOST', None, None)),
    ({'ROS_LOCALHOST_ONLY': '1'}, {'discovery': 'subnet'}, ('SUBNET', None, None)),
    ({'ROS_DOMAIN_ID': '5'}, {}, ('LOCALHOST', '5', None)),
    ({'ROS_DOMAIN_ID': '5'}, {'domain_id': 0}, ('LOCALHOST', '0', None)),
    ({}, {'domain_id': 232, 'discovery': 'subnet'}, ('SUBNET', '232', None)),
])
def test_launcher_sets_discovery_and_domain_for_the_nodes(given, options, expected):
    from formation_ros.tools.launcher import discovery_environment, Options
    base = dict(given, PATH='/bin')
    env = discovery_environment(Options('p.yaml', **options), base)
    assert (env['ROS_AUTOMATIC_DISCOVERY_RANGE'], env.get('ROS_DOMAIN_ID'),
            env.get('ROS_LOCALHOST_ONLY')) == expected
    assert env['PATH'] == '/bin' and base == dict(given, PATH='/bin')


@pytest.mark.parametrize('option, value, says', [
    ('--discovery', 'internet', '--discovery must be one of localhost, subnet'),
    ('--discovery', 'LOCALHOST', '--discovery must be one of localhost, subnet'),
    ('--domain-id', '233', '--domain-id must be a whole number from 0 to 232'),
    ('--domain-id', '-1', '--domain-id must be a whole number from 0 to 232'),
    ('--domain-id', '7.0', '--domain-id must be a whole number from 0 to 232'),
    ('--domain-id', '1000', '--domain-id must be a whole number from 0 to 232'),
    ('--domain-id', '', '--domain-id needs a number'),
])
def test_launcher_refuses_a_bad_discovery_or_domain(option, value, says):
    result = run('launch_formation.sh', os.path.join(ROOT, 'config', 'square_4.yaml'),
                 option, value)
    assert result.returncode == 2
    assert result.stderr == f'launch_formation.sh: {says}, got {value!r}\n' if value else \
        result.stderr == f'launch_formation.sh: {says}\n', result.stderr


@pytest.mark.parametrize('options, given, expected', [
    ((), {}, '71 LOCALHOST -'),
    (('--discovery', 'subnet', '--domain-id', '0'), {'ROS_LOCALHOST_ONLY': '1'}, '0 SUBNET -'),
    ((), {'ROS_AUTOMATIC_DISCOVERY_RANGE': 'SUBNET'}, '71 SUBNET -'),
])
def test_every_node_gets_the_discovery_settings(fake_install, monkeypatch, options, given,
                                                expected):
    monkeypatch.setenv('ROS_DOMAIN_ID', '71')
    monkeypatch.delenv('ROS_AUTOMATIC_DISCOVERY_RANGE', raising=False)
    for name, value in given.items():
        monkeypatch.setenv(name, value)
    result = launch_fake(fake_install, 'plant', *options)
    assert 'plant ended on its own (exit code 3)' in result.stderr, result.stderr
    lines = [line.split('] network ')[1] for line in result.stdout.splitlines()
             if '] network ' in line]
    assert lines == [expected] * 6, result.stdout
    head = result.stdout.splitlines()[0]
    domain, discovery = expected.split()[:2]
    assert head.endswith(f'; ROS_DOMAIN_ID {domain}, discovery {discovery.lower()}'), head


@pytest.mark.parametrize('args, says', [
    (('--robot-hosts', '0'), '--robot-hosts must be a whole number from 1 to 100'),
    (('--loss', '101'), '--loss must be a whole number from 0 to 100'),
    (('--loss', 'some'), '--loss must be a whole number from 0 to 100'),
    (('--discovery', 'localhost'), '--discovery cannot be given'),
    (('--cleanup', 'x.yaml'), '--cleanup takes no other arguments'),
    (('--domain-id', '300'), '--domain-id must be a whole number from 0 to 232'),
])
def test_hosts_script_refuses_bad_options(args, says):
    result = run('hosts.sh', os.path.join(ROOT, 'config', 'square_4.yaml'), *args)
    assert result.returncode == 2
    assert result.stderr.startswith(f'hosts.sh: {says}'), result.stderr
    assert len(result.stderr.splitlines()) == 1


def test_hosts_places_plant_and_robots():
    from formation_ros.tools.hosts import host_names, host_of, spread
    assert host_names(2) == ['plant', 'robots_1', 'robots_2']
    assert spread(5, 2) == [[1, 3, 5], [2, 4]]
    assert spread(2, 3) == [[1], [2], []]
    for name in ('plant', 'reference', 'record'):
        assert host_of(name, 2) == 'plant'
    for robots, host in zip(spread(7, 3), host_names(3)[1:]):
        assert {host_of(f'robot_{i}', 3) for i in robots} == {host}
    assert host_of('fleet_3', 2) == 'robots_1'


def test_run_tests_runs_the_files_it_is_given_instead_of_the_whole_suite():
    one = run('run_tests.sh', '--workers', '0', '--', 'test/core/test_lockstep.py',
              '--collect-only', '-q')
    assert one.returncode == 0, one.stdout[-2000:] + one.stderr[-2000:]
    assert '4 tests collected' in one.stdout, one.stdout[-2000:]
    assert 'test_jump' not in one.stdout
    chosen = run('run_tests.sh', '--workers', '0', '--', '-k', 'silent_robot_is_named',
                 '--collect-only', '-q')
    assert 'test/core/test_lockstep.py' in chosen.stdout, chosen.stdout[-2000:]
