# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""The package as ROS tools read it: package.xml dependencies and what colcon sees in setup.py."""

import ast
import glob
import importlib.util
import os
from pathlib import Path
import sys
import types
import xml.etree.ElementTree as ElementTree

import pytest

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
PACKAGE = 'formation_ros'

# Imports whose rosdep key differs from the module name; a ROS package is imported by its name.
ROSDEP_KEYS = {
    'matplotlib': 'python3-matplotlib',
    'PIL': 'python3-pil',
    'numpy': 'python3-numpy',
    'scipy': 'python3-scipy',
    'yaml': 'python3-yaml',
}
# Imports without an apt package: package.xml must say, in a comment, how to install them.
PIP_ONLY = {'rosbags': 'pip install rosbags', 'mcap': 'pip install mcap',
            'mujoco': 'pip install mujoco'}
TEST_DEPENDS = ('ament_flake8', 'ament_pep257', 'python3-pytest', 'python3-mypy',
                'python3-hypothesis')


def package_xml():
    """Return the parsed package.xml root element."""
    return ElementTree.parse(os.path.join(ROOT, 'package.xml')).getroot()


def dependencies(root, *tags):
    """Return the names declared in package.xml under the given dependency tags."""
    return {element.text.strip() for tag in tags for element in root.findall(tag)}


def package_comments():
    """Return the text of every XML comment in package.xml."""
    parser = ElementTree.XMLParser(target=ElementTree.TreeBuilder(insert_comments=True))
    root = ElementTree.parse(os.path.join(ROOT, 'package.xml'), parser).getroot()
    return [element.text for element in root.iter() if element.tag is ElementTree.Comment]


def imported_modules(path):
    """Return the top-level names of the absolute imports in a Python file."""
    with open(path) as stream:
        tree = ast.parse(stream.read(), path)
    names = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            names.update(alias.name.split('.')[0] for alias in node.names)
        elif isinstance(node, ast.ImportFrom) and node.level == 0:
            names.add(node.module.split('.')[0])
    return names


def code_files():
    """Return the installed Python files: the package's modules and the launch files."""
    files = glob.glob(os.path.join(ROOT, PACKAGE, '**', '*.py'), recursive=True)
    files += glob.glob(os.path.join(ROOT, 'launch', '*.py'))
    assert files
    return sorted(files)


def test_every_import_has_a_declared_dependency():
    runtime = dependencies(package_xml(), 'depend', 'exec_depend')
    comments = '\n'.join(package_comments())
    missing = []
    for path in code_files():
        for name in sorted(imported_modules(path)):
            if name == PACKAGE or name in sys.stdlib_module_names:
                continue
            if name in PIP_ONLY:
                if PIP_ONLY[name] not in comments:
                    missing.append(f'{name}: no comment with "{PIP_ONLY[name]}" in package.xml')
            elif ROSDEP_KEYS.get(name, name) not in runtime:
                missing.append(f'{os.path.relpath(path, ROOT)} imports {name}: no '
                               f'<exec_depend>{ROSDEP_KEYS.get(name, name)}</exec_depend>')
    assert not missing, '\n'.join(missing)


def test_the_import_scan_sees_the_ros_and_python_dependencies():
    found = set().union(*(imported_modules(path) for path in code_files()))
    assert {'rclpy', 'rcl_interfaces', 'builtin_interfaces', 'numpy', 'yaml', 'rosbags'} <= found


def test_test_tools_are_test_dependencies():
    declared = dependencies(package_xml(), 'depend', 'test_depend')
    assert set(TEST_DEPENDS) <= declared, sorted(set(TEST_DEPENDS) - declared)


@pytest.fixture(scope='module')
def setup_data():
    """Return setup.py's arguments as colcon reads them (a dry run of setup.py)."""
    from colcon_python_setup_py.package_identification.python_setup_py import (
        get_setup_information)
    return get_setup_information(Path(ROOT) / 'setup.py')


def test_colcon_tests_the_package_with_pytest(setup_data):
    from colcon_core.task.python.test import has_test_dependency
    assert has_test_dependency(setup_data, 'pytest')


def test_setup_py_and_package_xml_agree(setup_data):
    root = package_xml()
    assert setup_data['metadata']['name'] == root.findtext('name') == PACKAGE
    assert setup_data['metadata']['version'] == root.findtext('version')


@pytest.mark.filterwarnings('ignore:nodes.Node.traverse:DeprecationWarning')
def test_changelog_is_read_by_catkin_and_its_last_release_is_the_package_version():
    from catkin_pkg.changelog import get_changelog_from_path
    changelog = get_changelog_from_path(os.path.join(ROOT, 'CHANGELOG.rst'), PACKAGE)
    versions = [version for version, _, _ in changelog.foreach_version()]
    assert versions and versions[0] == package_xml().findtext('version'), versions
    with open(os.path.join(ROOT, 'CHANGELOG.rst')) as stream:
        title = stream.read().splitlines()[:3]
    assert title[1] == f'Changelog for package {PACKAGE}'
    assert title[0] == title[2] == '^' * len(title[1])


def test_setup_py_installs_the_launch_files(setup_data):
    installed = dict(setup_data['data_files']).get(f'share/{PACKAGE}/launch', [])
    assert {'launch/formation.launch.py', 'launch/lab.launch.py'} <= set(installed), \
        setup_data['data_files']


class Recorded:
    """Stands in for a launch action: keeps the arguments it was created with."""

    def __init__(self, *args, **kwargs):
        """Keep ``args`` and ``kwargs``."""
        self.args = args
        self.kwargs = kwargs


class Shutdown(Recorded):
    """Stands in for launch.actions.Shutdown."""


class Node(Recorded):
    """Stands in for launch_ros.actions.Node."""


class UnsetEnvironmentVariable(Recorded):
    """Stands in for launch.actions.UnsetEnvironmentVariable."""


class LaunchConfiguration:
    """Stands in for launch.substitutions.LaunchConfiguration: reads the context's value."""

    def __init__(self, variable_name, *, default=None):
        """Name the launch argument."""
        self.variable_name = variable_name

    def perform(self, context):
        """Return the argument's value in ``context`` (a dict here)."""
        return context[self.variable_name]


def load_launch_file(monkeypatch, file_name):
    """
    Load launch/FILE_NAME with launch and launch_ros replaced by recorders.

    The ROS launch packages are not on PyPI; these stand-ins take the same arguments and keep
    them, so the test sees the nodes the file asks for. The package's share directory is the
    source tree (it has the same config/ folder).
    """
    modules = {
        'launch': {'LaunchDescription': Recorded},
        'launch.actions': {'DeclareLaunchArgument': Recorded, 'OpaqueFunction': Recorded,
                           'Shutdown': Shutdown,
                           'UnsetEnvironmentVariable': UnsetEnvironmentVariable},
        'launch.substitutions': {'LaunchConfiguration': LaunchConfiguration},
        'launch_ros': {},
        'launch_ros.actions': {'Node': Node},
        'ament_index_python': {},
        'ament_index_python.packages': {
            'get_package_share_directory': {PACKAGE: ROOT}.__getitem__},
    }
    for name, attributes in modules.items():
        module = types.ModuleType(name)
        module.__dict__.update(attributes)
        monkeypatch.setitem(sys.modules, name, module)
    path = os.path.join(ROOT, 'launch', file_name)
    spec = importlib.util.spec_from_file_location(file_name.split('.')[0] + '_launch', path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def launched_nodes(launch_file, **arguments):
    """
    Return the Node stand-ins the launch file starts for the given launch arguments.

    Arguments not given take their declared defaults; one without a default must be given.
    """
    return [action for action in launched_actions(launch_file, **arguments)
            if isinstance(action, Node)]


def launched_actions(launch_file, **arguments):
    """Return every action the launch file's nodes come with (see :func:`launched_nodes`)."""
    description = launch_file.generate_launch_description()
    (actions,) = description.args
    declared = {action.args[0]: action.kwargs['default_value'] for action in actions
                if 'default_value' in action.kwargs}
    context = {**declared, **arguments}
    (opaque,) = [action for action in actions if 'function' in action.kwargs]
    return opaque.kwargs['function'](context)


def node_parameters(node):
    """Return a node's parameters file and its parameter overrides merged in order."""
    params_file, *overrides = node.kwargs['parameters']
    merged = {}
    for override in overrides:
        merged.update(override)
    return params_file, merged


def test_launch_file_declares_its_arguments_and_defaults_to_section5(launch_file):
    description = launch_file.generate_launch_description()
    declared = {action.args[0]: action.kwargs['default_value']
                for action in description.args[0] if action.args}
    assert declared == {
        'params_file': os.path.join(ROOT, 'config', 'paper_section5.yaml'),
        'record': '', 'output_dir': '', 'robots_per_process': '1', 'discovery': '',
        'domain_id': '', 'on_record_failure': 'continue'}


def test_launch_file_spreads_robots_over_fleet_processes(launch_file):
    params = os.path.join(ROOT, 'config', 'square_4.yaml')
    nodes = launched_nodes(launch_file, params_file=params, record='', output_dir='',
                           robots_per_process='3')
    fleets = [node for node in nodes if node.kwargs['executable'] == 'fleet']
    assert sorted(node.kwargs['executable'] for node in nodes) == \
        ['fleet', 'fleet', 'plant', 'reference']
    assert [node.kwargs['arguments'] for node in fleets] == [['--robots', '1-3'],
                                                             ['--robots', '4-4']]
    for fleet in fleets:
        assert fleet.kwargs['namespace'] is None
        assert node_parameters(fleet) == (params, {'wait_for_subscribers': 1,
                                                   'use_sim_time': True})


@pytest.mark.parametrize('record', ['', '/tmp/formation_bag'])
def test_launch_file_starts_the_system_of_the_shell_launcher(launch_file, setup_data, record):
    from formation_ros.core.settings.declarations import BY_NAME as schema, Exe
    scripts = {entry.split('=')[0].strip()
               for entry in setup_data['entry_points']['console_scripts']}
    params = os.path.join(ROOT, 'config', 'square_4.yaml')
    nodes = launched_nodes(launch_file, params_file=params, record=record,
                           output_dir='/tmp/formation_out')

    executables = sorted(node.kwargs['executable'] for node in nodes)
    assert executables == sorted(['plant', 'reference'] + ['robot'] * 4
                                 + (['record'] if record else []))
    assert set(executables) <= scripts
    robots = {}
    for node in nodes:
        executable = node.kwargs['executable']
        assert node.kwargs['package'] == PACKAGE
        on_exit = node.kwargs['on_exit']
        if executable == 'record':
            on_exit = on_exit.shutdown
        assert isinstance(on_exit, Shutdown), f'{executable} exits alone'
        params_file, overrides = node_parameters(node)
        assert params_file == params
        assert overrides.pop('use_sim_time', False) == (executable in ('reference', 'robot'))
        for name in overrides:
            assert name in schema, f'{executable}: {name} is not a parameter of the schema'
            assert Exe(executable) in schema[name].users, f'{executable} does not read {name}'
        if executable == 'robot':
            robots[overrides['robot_id']] = (node.kwargs['namespace'], overrides)
        else:
            assert node.kwargs['namespace'] is None, executable

    waits = 2 if record else 1
    assert robots == {i: (f'robot_{i}', {'robot_id': i, 'wait_for_subscribers': waits})
                      for i in range(1, 5)}
    (plant,) = [node for node in nodes if node.kwargs['executable'] == 'plant']
    assert node_parameters(plant)[1] == {
        'plant.output_dir': '/tmp/formation_out',
        **({'plant.wait_for_subscribers': 2} if record else {})}
    if record:
        (recorder,) = [node for node in nodes if node.kwargs['executable'] == 'record']
        assert node_parameters(recorder)[1] == {'record.path': record}


def test_launch_file_without_output_dir_sets_none(launch_file):
    nodes = launched_nodes(launch_file, params_file=os.path.join(ROOT, 'config', 'square_4.yaml'))
    (plant,) = [node for node in nodes if node.kwargs['executable'] == 'plant']
    assert node_parameters(plant)[1] == {}


@pytest.mark.parametrize('given, arguments, expected', [
    ({}, {}, {'ROS_AUTOMATIC_DISCOVERY_RANGE': 'LOCALHOST'}),
    ({'ROS_AUTOMATIC_DISCOVERY_RANGE': 'SUBNET'}, {}, {}),
    ({'ROS_AUTOMATIC_DISCOVERY_RANGE': 'SUBNET'}, {'discovery': 'localhost'},
     {'ROS_AUTOMATIC_DISCOVERY_RANGE': 'LOCALHOST'}),
    ({}, {'discovery': 'subnet', 'domain_id': '7'},
     {'ROS_AUTOMATIC_DISCOVERY_RANGE': 'SUBNET', 'ROS_DOMAIN_ID': '7'}),
])
def test_launch_file_sets_discovery_and_domain(launch_file, monkeypatch, given, arguments,
                                               expected):
    monkeypatch.delenv('ROS_AUTOMATIC_DISCOVERY_RANGE', raising=False)
    for name, value in given.items():
        monkeypatch.setenv(name, value)
    square = os.path.join(ROOT, 'config', 'square_4.yaml')
    nodes = launched_nodes(launch_file, params_file=square, **arguments)
    assert len(nodes) == 6
    assert all(node.kwargs['additional_env'] == expected for node in nodes)


@pytest.mark.parametrize('arguments', [{'discovery': 'wan'}, {'domain_id': '233'},
                                       {'domain_id': '-1'}])
def test_launch_file_refuses_a_bad_discovery_or_domain(launch_file, arguments):
    with pytest.raises(ValueError, match='discovery must be|domain_id must be'):
        launched_nodes(launch_file, params_file=os.path.join(ROOT, 'config', 'square_4.yaml'),
                       **arguments)


def test_test_modules_have_distinct_names():
    names = {}
    for folder, _, files in os.walk(os.path.join(ROOT, 'test')):
        for name in files:
            if name.startswith('test_') and name.endswith('.py'):
                names.setdefault(name, []).append(folder)
    shared = {name: folders for name, folders in names.items() if len(folders) > 1}
    assert not shared, f'pytest imports test modules by their basename: {shared}'


def test_the_maintainer_is_the_copyright_holder_of_every_file(setup_data):
    with open(os.path.join(ROOT, 'setup.py'), encoding='utf-8') as stream:
        holder = stream.readline().split('Copyright 2026 ', 1)[1].strip().rstrip('.')
    (maintainer,) = package_xml().findall('maintainer')
    assert maintainer.text == holder == 'The formation_ros authors'
    assert setup_data['metadata']['maintainer'] == holder
    email = maintainer.get('email')
    assert email == setup_data['metadata']['maintainer_email']
    assert email.endswith('@example.com'), 'a reserved domain (RFC 2606), never a real inbox'
