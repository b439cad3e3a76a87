# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""The licence: LICENSE, package.xml and setup.py agree, and every source file says so."""

import ast
import glob
import hashlib
import os
import re
import xml.etree.ElementTree as ElementTree

import pytest

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
HEADER = ['# Copyright 2026 The formation_ros authors.', '# SPDX-License-Identifier: Apache-2.0']
# SHA-256 of the Apache License 2.0 text with its whitespace collapsed to single spaces.
LICENSE_TEXTS = {
    '0ffddef9e48f8a09aed5caf2d44f7ba1c1be2d9b8e0a6f693b1635b2d5566645': 'Apache-2.0',
}
ENCODING_LINE = re.compile(r'^[ \t\f]*#.*?coding[:=][ \t]*[-\w.]+')
SOURCE_DIRS = ('formation_ros', 'test', 'bench', 'launch', 'docs')


def license_of_license_file():
    """Return the SPDX identifier of the text in LICENSE, or None for an unknown text."""
    with open(os.path.join(ROOT, 'LICENSE')) as stream:
        words = ' '.join(stream.read().split())
    return LICENSE_TEXTS.get(hashlib.sha256(words.encode()).hexdigest())


def setup_py_license():
    """Return the ``license`` argument of setup() in setup.py."""
    with open(os.path.join(ROOT, 'setup.py')) as stream:
        tree = ast.parse(stream.read())
    (value,) = [keyword.value for node in ast.walk(tree) if isinstance(node, ast.Call)
                for keyword in node.keywords if keyword.arg == 'license']
    return ast.literal_eval(value)


def header_problem(path):
    """Return what is wrong with the start of a Python file, or None when it has the header."""
    with open(path) as stream:
        source = stream.read()
    lines = source.splitlines()
    start = 0
    if lines[start:start + 1] and lines[start].startswith('#!'):
        start += 1
    if lines[start:start + 1] and ENCODING_LINE.match(lines[start]):
        start += 1
    if lines[start:start + 2] != HEADER:
        return f'line {start + 1}: not the copyright header'
    if lines[start + 2:start + 3] not in ([], ['']):
        return f'line {start + 3}: no blank line after the copyright header'
    tree = ast.parse(source, path)
    if ast.get_docstring(tree) is not None and tree.body[0].lineno != start + 4:
        return f'line {tree.body[0].lineno}: the docstring does not follow the header'
    return None


def source_files():
    """Return every Python file of the repository that carries the header."""
    files = [os.path.join(ROOT, 'setup.py')]
    for folder in SOURCE_DIRS:
        files += glob.glob(os.path.join(ROOT, folder, '**', '*.py'), recursive=True)
    return sorted(files)


def test_license_file_is_the_apache_license_2_0():
    assert license_of_license_file() == 'Apache-2.0'


def test_package_xml_and_setup_py_name_the_license_of_license_file():
    root = ElementTree.parse(os.path.join(ROOT, 'package.xml')).getroot()
    licenses = [element.text.strip() for element in root.findall('license')]
    assert licenses == [license_of_license_file()]
    assert setup_py_license() == license_of_license_file()


@pytest.mark.linter
def test_every_source_file_starts_with_the_copyright_header():
    files = source_files()
    assert os.path.join(ROOT, 'launch', 'formation.launch.py') in files
    problems = [f'{os.path.relpath(path, ROOT)}: {problem}' for path in files
                for problem in [header_problem(path)] if problem]
    assert not problems, 'files without the copyright header:\n' + '\n'.join(problems)


def test_header_check_accepts_the_forms_it_should_and_nothing_else(tmp_path):
    header = '\n'.join(HEADER) + '\n'
    accepted = {
        'empty_init.py': header,
        'module.py': header + '\n"""Docstring."""\n',
        'script.py': '#!/usr/bin/env python3\n# -*- coding: utf-8 -*-\n' + header + '\nx = 1\n',
    }
    rejected = {
        'missing.py': '"""Docstring."""\n',
        'other_year.py': header.replace('2026', '2025') + '\n"""Docstring."""\n',
        'no_blank.py': header + '"""Docstring."""\n',
        'two_blanks.py': header + '\n\n"""Docstring."""\n',
        'late.py': '"""Docstring."""\n' + header,
    }
    for name, text in {**accepted, **rejected}.items():
        (tmp_path / name).write_text(text)
    for name in accepted:
        assert header_problem(str(tmp_path / name)) is None, name
    for name in rejected:
        assert header_problem(str(tmp_path / name)) is not None, name
