# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""Fault: the recorder killed with SIGKILL mid-run; formation_report recovers and repairs."""

import json
import signal
import subprocess

from formation_ros.core.settings.params import load_config
from formation_ros.ros.bag_writer import BagError
from formation_ros.tools.bag import read_messages, recover_bag
from helpers import exe, launch, node, SimClock, SQUARE, START_UP, wait_exit
import pytest

COMMANDS = '/robot_1/cmd_vel'
RECORDED_COMMANDS = 50


def commands_on_disk(bag):
    """Robot 1's commands that a reader finds in the bag's file now (0 before any)."""
    if not bag.exists() or not any(name.suffix == '.mcap' for name in bag.iterdir()):
        return 0
    try:
        recovery = recover_bag(str(bag))
    except BagError:
        return 0
    topic = recovery.topics.get(COMMANDS)
    return len(topic.messages) if topic is not None else 0


def report(ros_env, install, *args):
    return subprocess.run([exe(install, 'formation_report'), *map(str, args)],
                          capture_output=True, text=True, env=ros_env, timeout=START_UP * 4)


@pytest.mark.faults
def test_bag_of_a_recorder_killed_with_sigkill_is_recovered_and_repaired(
        processes, install, probe, ros_env, tmp_path):
    bag, out = tmp_path / 'bag', tmp_path / 'report'
    processes.start(node(install, 'record', SQUARE, '-p', f'record.path:={bag}'))
    assert probe.spin_until(lambda: probe.count_subscribers('/robot_1/pose') == 1, START_UP), \
        processes.log('record')
    clock = SimClock(probe)
    launch(processes, install, SQUARE, per_process=4)
    assert probe.spin_until(lambda: clock.seconds >= 3.0, START_UP), processes.log('launcher')
    assert probe.spin_until(lambda: commands_on_disk(bag) >= RECORDED_COMMANDS, START_UP), \
        processes.log('record')
    assert not (bag / 'metadata.yaml').exists()
    processes.send_signal('record', signal.SIGKILL)
    killed = wait_exit(probe, processes, 'record', START_UP)
    assert killed is not None and killed.returncode == -signal.SIGKILL, processes.log('record')
    on_disk = recover_bag(str(bag)).count
    processes.stop(['launcher'])
    assert not (bag / 'metadata.yaml').exists()

    result = report(ros_env, install, bag, '--out', out, '--no-plots')
    assert result.returncode == 0, result.stdout + result.stderr
    assert 'Traceback' not in result.stderr
    (line,) = [ln for ln in result.stderr.splitlines() if 'recovered' in ln]
    assert f'recovered {on_disk} messages on ' in line and 'no metadata.yaml' in line
    metrics = json.loads((out / 'metrics.json').read_text())
    assert metrics['recovered_messages'] == metrics['messages'] == on_disk
    assert metrics['source'] == 'rosbag2' and metrics['reference_source'] == 'recorded'
    assert metrics['num_robots'] == 4 and metrics['min_pair_distance'] > 0
    assert 0 < metrics['max_abs_u_component'] <= load_config(SQUARE).law().u_bound
    assert metrics.get('collisions', 0) == 0 and metrics.get('bound_violations', 0) == 0

    repaired = report(ros_env, install, bag, '--repair')
    assert repaired.returncode == 0, repaired.stdout + repaired.stderr
    assert f'repaired {bag}: {on_disk} messages' in repaired.stdout
    assert (bag / f'{bag.name}.mcap.damaged').exists()
    topics, counts = read_messages(str(bag))
    assert counts == {topic: len(messages) for topic, messages in topics.items()}
    assert sum(counts.values()) == on_disk and counts[COMMANDS] >= RECORDED_COMMANDS
    again = report(ros_env, install, bag, '--out', tmp_path / 'again', '--no-plots')
    assert again.returncode == 0 and 'recovered' not in again.stderr, again.stderr
    assert json.loads((tmp_path / 'again' / 'metrics.json').read_text())['messages'] == on_disk
