# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""colcon builds a normal ament_python install space."""

import json
import os
import re
import subprocess

from helpers import exe

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
with open(os.path.join(ROOT, 'setup.py'), encoding='utf-8') as setup:
    EXECUTABLES = tuple(re.findall(r"^\s*'(\w+) = formation_ros\.", setup.read(), re.M))


def test_install_layout(install):
    assert {'robot', 'plant', 'world', 'formation_sim', 'formation_render'} <= set(EXECUTABLES)
    for name in EXECUTABLES:
        path = exe(install, name)
        assert os.path.isfile(path) and os.access(path, os.X_OK), path
    share = os.path.join(install, 'share')
    assert os.path.isfile(os.path.join(share, 'formation_ros', 'package.xml'))
    assert os.path.isfile(os.path.join(share, 'ament_index', 'resource_index', 'packages',
                                       'formation_ros'))
    configs = os.listdir(os.path.join(share, 'formation_ros', 'config'))
    assert 'paper_section5.yaml' in configs and 'square_4.yaml' in configs
    assert os.path.isfile(os.path.join(share, 'formation_ros', 'launch', 'formation.launch.py'))


def test_installed_executable_runs_from_install_space(install, ros_env, tmp_path):
    params = os.path.join(install, 'share', 'formation_ros', 'config', 'square_4.yaml')
    out = tmp_path / 'sim'
    result = subprocess.run([exe(install, 'formation_sim'), params, '--out', str(out),
                             '--duration', '0.5', '--dt', '0.01', '--no-plots', '--quiet'],
                            env=ros_env, capture_output=True, text=True, timeout=120)
    assert result.returncode == 0, result.stderr
    metrics = json.loads((out / 'metrics.json').read_text())
    assert metrics['num_robots'] == 4 and abs(metrics['duration'] - 0.5) < 1e-9
