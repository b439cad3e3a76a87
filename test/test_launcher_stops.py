# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""The launcher's exit code when a process fails while the run is being stopped (no ROS)."""

import os
import subprocess
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
PARAMS = os.path.join(ROOT, 'config', 'square_4.yaml')
NODE = '#!/usr/bin/env bash\ntrap "exit 0" INT TERM\nsleep infinity &\nwait\n'
RECORDER_THAT_FAILS_AT_STOP = (
    '#!/usr/bin/env bash\n'
    'for arg in "$@"; do case "$arg" in record.path:=*) bag="${arg#record.path:=}" ;; esac; done\n'
    'mkdir -p "$bag"\n'
    'trap \'echo "recording stopped: cannot write $bag"; exit 74\' INT TERM\n'
    'sleep infinity &\n'
    'wait\n')
"""A recorder whose last write fails when it is asked to stop (a disk that fills then)."""


def fake_install(folder):
    """Write an install prefix whose executables stand in for the nodes; return it."""
    lib = folder / 'lib' / 'formation_ros'
    lib.mkdir(parents=True)
    scripts = {name: NODE for name in ('plant', 'reference', 'robot')}
    scripts['record'] = RECORDER_THAT_FAILS_AT_STOP
    scripts['formation_report'] = '#!/usr/bin/env bash\necho "report $*"\n'
    for name, text in scripts.items():
        (lib / name).write_text(text)
        (lib / name).chmod(0o755)
    return folder


def test_a_recording_that_fails_as_the_run_stops_is_exit_74_and_said_once(tmp_path):
    bag = tmp_path / 'bag'
    env = dict(os.environ, ROS_DOMAIN_ID='13')
    done = subprocess.run([sys.executable, '-m', 'formation_ros.tools.launcher', PARAMS,
                           '--prefix', str(fake_install(tmp_path / 'install')),
                           '--duration', '1', '--record', str(bag)],
                          capture_output=True, text=True, env=env, timeout=120)
    assert done.returncode == 74, done.stdout + done.stderr
    said = [line for line in done.stderr.splitlines() if 'the recording stopped early' in line]
    assert said == [
        f'launch_formation.sh: the recording stopped early: the recorder could not write {bag} '
        '(exit code 74), as the run was stopping',
        f'launch_formation.sh: exit code 74: the recording stopped early: the recorder could '
        f'not write {bag}; the others ran to the end of the run'], done.stderr


def test_no_plots_asks_the_report_for_the_metrics_alone(tmp_path):
    install = fake_install(tmp_path / 'install')
    (install / 'lib' / 'formation_ros' / 'record').write_text(
        RECORDER_THAT_FAILS_AT_STOP.replace('exit 74', 'exit 0').replace(
            'echo "recording stopped: cannot write $bag"; ', ''))
    env = dict(os.environ, ROS_DOMAIN_ID='13')
    reports = []
    for extra in ((), ('--no-plots',)):
        bag = tmp_path / f'bag{len(reports)}'
        done = subprocess.run([sys.executable, '-m', 'formation_ros.tools.launcher', PARAMS,
                               '--prefix', str(install), '--duration', '0.5',
                               '--record', str(bag), *extra],
                              capture_output=True, text=True, env=env, timeout=120)
        assert done.returncode == 0, done.stdout + done.stderr
        reports.append([line for line in done.stdout.splitlines() if line.startswith('report')])
    assert reports == [[f'report {tmp_path}/bag0 --out {tmp_path}/bag0'],
                       [f'report {tmp_path}/bag1 --out {tmp_path}/bag1 --no-plots']]
