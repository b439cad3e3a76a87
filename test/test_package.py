# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""The package as ROS tools read it: package.xml dependencies and what colcon sees in setup.py."""

import ast
import glob
import os
from pathlib import Path
import sys
import xml.etree.ElementTree as ElementTree

import pytest

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
PACKAGE = 'formation_ros'

# Imports whose rosdep key differs from the module name; a ROS package is imported by its name.
ROSDEP_KEYS = {
    'matplotlib': 'python3-matplotlib',
    'numpy': 'python3-numpy',
    'scipy': 'python3-scipy',
    'yaml': 'python3-yaml',
}
# Imports without an apt package: package.xml must say, in a comment, how to install them.
PIP_ONLY = {'rosbags': 'pip install rosbags'}
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
