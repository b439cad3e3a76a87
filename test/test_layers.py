# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""Arrows point down only: core <- ros adapters <- nodes; offline tools beside the nodes."""

import ast
import json
import os
import subprocess
import sys

import pytest

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
PACKAGE = os.path.join(ROOT, 'formation_ros')
ROS_MODULES = ('rclpy', 'rcl_interfaces', 'builtin_interfaces', 'geometry_msgs', 'nav_msgs',
               'std_msgs', 'rosgraph_msgs', 'diagnostic_msgs', 'visualization_msgs', 'rosbags')
FORBIDDEN = {
    'core': ROS_MODULES + ('formation_ros.ros', 'formation_ros.nodes', 'formation_ros.tools',
                           'formation_ros.physics', 'mujoco', 'matplotlib'),
    'physics': ROS_MODULES + ('formation_ros.ros', 'formation_ros.nodes', 'formation_ros.tools',
                              'matplotlib'),
    'ros': ('formation_ros.nodes', 'formation_ros.tools', 'matplotlib'),
    'nodes': ('formation_ros.tools', 'matplotlib'),
    'tools': ('formation_ros.nodes',),
}
NODES = ('robot', 'fleet', 'plant', 'reference', 'recorder', 'relay', 'world')
NEVER_IN_A_NODE = ('matplotlib', 'scipy.integrate', 'formation_ros.tools')
NOT_IN_A_ROBOT = ('scipy',)
"""A robot process (one per robot) needs no k-d tree, quadrature or rotation library: scipy
took half a second to import and 33 MiB of its memory."""


def imported_modules(path):
    """Every module a file imports (absolute names), wherever the import statement is."""
    with open(path, encoding='utf-8') as stream:
        tree = ast.parse(stream.read(), path)
    names = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            names.update(alias.name for alias in node.names)
        elif isinstance(node, ast.ImportFrom) and node.module:
            names.add(node.module)
            names.update(f'{node.module}.{alias.name}' for alias in node.names)
    return names


def layer_files(layer):
    folder = os.path.join(PACKAGE, layer)
    return sorted(os.path.join(folder, name) for name in os.listdir(folder)
                  if name.endswith('.py'))


@pytest.mark.parametrize('layer', sorted(FORBIDDEN))
def test_imports_point_down(layer):
    files = layer_files(layer)
    assert files
    wrong = [(os.path.relpath(path, ROOT), module) for path in files
             for module in sorted(imported_modules(path))
             if module.startswith(FORBIDDEN[layer])]
    assert not wrong, wrong


def test_every_module_is_in_a_layer():
    loose = [name for name in os.listdir(PACKAGE)
             if name.endswith('.py') and name != '__init__.py']
    assert not loose, loose


@pytest.mark.parametrize('node', NODES)
def test_a_node_loads_only_what_it_uses(node):
    """Each node module, imported in a fresh interpreter, loads no offline tool or plotting."""
    code = (f'import sys, json\nimport formation_ros.nodes.{node}\n'
            'print(json.dumps(sorted(sys.modules)))')
    result = subprocess.run([sys.executable, '-c', code], capture_output=True, text=True,
                            cwd=ROOT, timeout=120)
    assert result.returncode == 0, result.stderr
    loaded = json.loads(result.stdout.strip().splitlines()[-1])
    assert f'formation_ros.nodes.{node}' in loaded and 'rclpy' in loaded
    forbidden = (NEVER_IN_A_NODE + (() if node == 'recorder' else ('rosbags',))
                 + (NOT_IN_A_ROBOT if node in ('robot', 'fleet') else ()))
    wrong = [name for name in loaded if name.startswith(forbidden)]
    assert not wrong, wrong


def test_the_package_works_without_mujoco():
    """Only formation_ros.physics needs mujoco: the simulator loads and checks a file without."""
    code = ('import sys, json\nsys.modules["mujoco"] = None\n'
            'from formation_ros.tools import sim\n'
            'config = sim.load_config("config/unicycle_2d.yaml")\n'
            'print(json.dumps([config.world.timestep, "mujoco" in sys.modules and '
            'sys.modules["mujoco"] is not None]))')
    result = subprocess.run([sys.executable, '-c', code], capture_output=True, text=True,
                            cwd=ROOT, timeout=120)
    assert result.returncode == 0, result.stderr
    assert json.loads(result.stdout.strip().splitlines()[-1]) == [0.002, False]
