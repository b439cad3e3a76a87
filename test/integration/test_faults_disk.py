# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
Fault: the disk fills while a run records (the recorder's bag) or writes (the plant's --out).

A tmpfs of 2 MB is mounted for the test (root only; skipped otherwise) and filled up to a few
hundred kilobytes, so that it is full a few seconds into the run. The launcher runs as a user
starts it; the test judges from its output (every node's lines), its exit code, and the files
left on the tmpfs read back with the offline readers.
"""

import json
import os
import re
import subprocess
import time

from formation_ros.core.runs.trajectory import CHUNKS_DIR, read_chunks
from formation_ros.core.settings.exits import RECORDING_FAILED
from formation_ros.tools.bag import read_messages
from helpers import launch, START_UP, wait_exit, write_params
import pytest

pytestmark = pytest.mark.faults

DISK = '2m'
RUN = 12.0
"""Wall-clock seconds of a run that goes to its end (its --duration)."""
LONG_RUN = 600.0
"""A run that only a failure can end within the test."""
PLANT_SUMMARY = re.compile(r'\[plant\] .*plant: (\d+) steps \(([0-9.]+) s simulated')
RECORD_LINE = re.compile(r'the bag holds (\d+) messages \(([0-9.]+) MB\) up to simulated time '
                         r'([0-9.]+) s, closed, readable \(metadata.yaml written\)')


@pytest.fixture
def tiny_disk(tmp_path):
    """Mount a tmpfs of 2 MB at tmp_path/disk for the test; unmount it afterwards."""
    if os.geteuid() != 0:
        pytest.skip('mounting a tmpfs needs root')
    disk = tmp_path / 'disk'
    disk.mkdir()
    result = subprocess.run(['mount', '-t', 'tmpfs', '-o', f'size={DISK}', 'tmpfs', str(disk)],
                            capture_output=True, text=True)
    if result.returncode != 0:
        pytest.skip(f'cannot mount a tmpfs: {result.stderr.strip()}')
    try:
        yield disk
    finally:
        subprocess.run(['umount', '-l', str(disk)], capture_output=True)


def fill(disk, leave):
    """Fill ``disk`` with one file until ``leave`` bytes are free."""
    stat = os.statvfs(disk)
    free = stat.f_bavail * stat.f_frsize
    with open(disk / 'filler', 'wb') as stream:
        stream.write(b'\0' * max(0, free - leave))


def run_until_exit(probe, processes, timeout):
    """Wait for the launcher to end on its own; return (exit, its whole output)."""
    info = wait_exit(probe, processes, 'launcher', timeout)
    assert info is not None, 'the launcher did not end:\n' + processes.log('launcher')[-4000:]
    return info, processes.log('launcher')


def plant_simulated(log):
    (summary,) = PLANT_SUMMARY.findall(log)
    return float(summary[1])


@pytest.mark.parametrize('mode', ['continue', 'stop'])
def test_a_full_disk_stops_the_recording_alone_and_leaves_a_readable_bag(
        processes, install, probe, tmp_path, tiny_disk, mode):
    fill(tiny_disk, 400_000)
    bag, out = tiny_disk / 'bag', tmp_path / 'out'
    duration = RUN if mode == 'continue' else LONG_RUN
    params = write_params(tmp_path, 'square_4.yaml', {'duration': duration})
    started = time.monotonic()
    launch(processes, install, params, out=out, record=bag, duration=duration,
           options=('--on-record-failure', mode), per_process=4)
    info, log = run_until_exit(probe, processes, duration + 4 * START_UP)
    elapsed = time.monotonic() - started

    assert info.returncode == RECORDING_FAILED, log[-4000:]
    assert 'Traceback' not in log and 'Errno' not in log, log[-4000:]
    stopped = [line for line in log.splitlines() if 'recording stopped:' in line]
    assert len(stopped) == 1 and stopped[0].startswith('[record] '), stopped
    assert f'cannot write {bag} (No space left on device)' in stopped[0]
    ((messages, megabytes, clock),) = RECORD_LINE.findall(stopped[0])
    said = [line for line in log.splitlines() if 'the recording stopped early' in line]
    assert len(said) == 2, said
    assert f'could not write {bag} (exit code {RECORDING_FAILED})' in said[0]
    assert 'ended on its own' not in log, log[-4000:]

    topics, counts = read_messages(str(bag))
    assert sum(counts.values()) == sum(len(m) for m in topics.values()) == int(messages)
    assert counts['/robot_1/cmd_vel'] > 0 and counts['/formation/params'] == 1
    last_clock = max(m.clock.sec + m.clock.nanosec * 1e-9 for _, m in topics['/clock'])
    assert f'{last_clock:.2f}' == clock
    size = sum(os.path.getsize(bag / name) for name in os.listdir(bag) if name.endswith('.mcap'))
    assert f'{size / 1e6:.2f}' == megabytes
    metrics = json.loads((out / 'metrics.json').read_text())
    assert metrics['messages'] == int(messages) and 'recovered_messages' not in metrics

    simulated = plant_simulated(log)
    if mode == 'continue':
        assert said[1].endswith('the others ran to the end of the run'), said
        assert elapsed >= RUN, 'the launcher ran its whole duration'
        assert simulated > float(clock), 'the team went on after the recording stopped'
    else:
        assert 'stopping the others (--on-record-failure stop)' in said[0]
        assert said[1].endswith('the others were stopped then (--on-record-failure stop)')
        assert simulated < LONG_RUN / 2


def test_a_full_output_directory_stops_the_plant_output_alone(
        processes, install, probe, tmp_path, tiny_disk):
    fill(tiny_disk, 20_000)
    out = tiny_disk / 'out'
    params = write_params(tmp_path, 'square_4.yaml', {'duration': RUN})
    started = time.monotonic()
    launch(processes, install, params, out=out, duration=RUN, per_process=4, plots=True)
    info, log = run_until_exit(probe, processes, RUN + 4 * START_UP)
    elapsed = time.monotonic() - started

    assert 'Traceback' not in log and 'Errno' not in log, log[-4000:]
    stopped = [line for line in log.splitlines() if 'output stopped' in line]
    assert len(stopped) == 2, stopped
    line, summary = stopped
    assert line.startswith('[plant] ') and 'No space left on device' in line
    assert 'the plant goes on controlling' in line
    (until,) = re.findall(r'the trajectory up to t = ([0-9.]+) s in (\d+) chunks', line)
    assert PLANT_SUMMARY.search(summary) and summary.endswith('(No space left on device)')
    t, q, u = read_chunks(str(out / CHUNKS_DIR))
    assert f'{t[-1]:.2f}' == until[0] and len(os.listdir(out / CHUNKS_DIR)) == int(until[1])
    assert q.shape == u.shape == (len(t), 4, 2) and (t[1:] > t[:-1]).all()
    assert not [name for name in os.listdir(out / CHUNKS_DIR) if name.endswith('.part')]
    assert not (out / 'trajectory.npz').exists() and not (out / 'plant_stats.json').exists()
    assert elapsed >= RUN and plant_simulated(log) > t[-1] + 1.0, \
        'the plant went on controlling to the end of the run'
    assert 'ended on its own' not in log
    assert info.returncode == 1 and 'formation_report failed' in log, log[-3000:]
    assert 'cannot write the report to' in log
