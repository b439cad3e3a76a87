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
OUTSIDE_CORE = ('formation_ros.ros', 'formation_ros.nodes', 'formation_ros.tools',
                'formation_ros.physics', 'formation_ros.simulation', 'formation_ros.figures')
FORBIDDEN = {
    'core': ROS_MODULES + OUTSIDE_CORE + ('mujoco', 'matplotlib'),
    'physics': ROS_MODULES + ('formation_ros.ros', 'formation_ros.nodes', 'formation_ros.tools',
                              'formation_ros.simulation', 'formation_ros.figures',
                              'matplotlib'),
    'ros': ('formation_ros.nodes', 'formation_ros.tools', 'formation_ros.simulation',
            'formation_ros.figures', 'matplotlib', 'mujoco'),
    'nodes': ('formation_ros.tools', 'formation_ros.simulation', 'formation_ros.figures',
              'matplotlib'),
    'simulation': ROS_MODULES + ('formation_ros.ros', 'formation_ros.nodes', 'formation_ros.tools',
                                 'formation_ros.figures', 'matplotlib'),
    'figures': ROS_MODULES + ('formation_ros.ros', 'formation_ros.nodes', 'formation_ros.tools',
                              'formation_ros.physics', 'mujoco'),
    'tools': ('formation_ros.nodes',),
}
"""Each layer and what it must not import: the arrows point down only."""
CORE_ROOMS = {
    'maths': (),
    'model': ('maths',),
    'runs': ('maths',),
    'settings': ('maths', 'model'),
    'rules': ('maths', 'model', 'runs', 'settings'),
}
"""The rooms of the core and the rooms each may import (``formation_ros/core/__init__.py``)."""
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
    """Every module of a layer, its rooms included."""
    folder = os.path.join(PACKAGE, layer)
    return sorted(os.path.join(root, name) for root, _, names in os.walk(folder)
                  for name in names if name.endswith('.py'))


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
    layers = {name for name in os.listdir(PACKAGE)
              if os.path.isfile(os.path.join(PACKAGE, name, '__init__.py'))}
    assert layers == set(FORBIDDEN), layers


def test_every_core_module_is_in_a_room():
    core = os.path.join(PACKAGE, 'core')
    loose = [name for name in os.listdir(core) if name.endswith('.py') and name != '__init__.py']
    assert not loose, loose
    rooms = {name for name in os.listdir(core)
             if os.path.isfile(os.path.join(core, name, '__init__.py'))}
    assert rooms == set(CORE_ROOMS), rooms


@pytest.mark.parametrize('room', sorted(CORE_ROOMS))
def test_core_rooms_import_only_the_rooms_below(room):
    allowed = {room, *CORE_ROOMS[room]}
    files = layer_files(os.path.join('core', room))
    assert len(files) > 1
    wrong = [(os.path.relpath(path, ROOT), module) for path in files
             for module in sorted(imported_modules(path))
             if module.startswith('formation_ros.core.')
             and module.split('.')[2] not in allowed]
    assert not wrong, wrong


def test_tools_hold_command_line_tools_and_what_only_they_use():
    """A module of tools/ is a command or is imported by tools only (no bench, no other layer)."""
    tools = {os.path.basename(path)[:-3] for path in layer_files('tools')} - {'__init__'}
    users = {}
    for layer in sorted(set(FORBIDDEN) - {'tools'}):
        for path in layer_files(layer):
            for module in imported_modules(path):
                if module.startswith('formation_ros.tools.'):
                    users.setdefault(module.split('.')[2], []).append(path)
    assert tools and not users, users


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


def test_no_module_of_the_package_is_ignored_by_git():
    """A module git ignores is missing from every clone (a room once lost its __init__.py)."""
    inside = subprocess.run(['git', 'rev-parse', '--is-inside-work-tree'], cwd=ROOT,
                            capture_output=True, text=True)
    if inside.returncode != 0:
        pytest.skip('not a git checkout')
    modules = [os.path.relpath(path, ROOT) for layer in FORBIDDEN for path in layer_files(layer)]
    ignored = subprocess.run(['git', 'check-ignore', '--no-index', *modules], cwd=ROOT,
                             capture_output=True, text=True)
    assert ignored.returncode == 1 and not ignored.stdout, ignored.stdout
