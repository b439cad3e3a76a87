# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""The README stays true: its commands are CI's, and it documents every parameter."""

import os

from formation_ros.core.declarations import DECLARATIONS as SCHEMA

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def read(name):
    with open(os.path.join(ROOT, name), encoding='utf-8') as stream:
        return stream.read()


def test_ci_runs_the_readme_test_command():
    lines = [line.strip() for line in read('.ci/run').splitlines()]
    command = [line for line in lines if line and not line.startswith('#')][-1]
    assert f'\n{command}\n' in read('README.md')


def test_every_parameter_is_in_the_readme_table():
    readme = read('README.md')
    missing = [p.name for p in SCHEMA if f'| `{p.name}` |' not in readme]
    assert not missing, missing


def test_scripts_are_strict_and_have_help():
    for name in ('setup_env.sh', 'demo.sh', 'run_tests.sh'):
        text = read(os.path.join('scripts', name))
        assert 'set -euo pipefail' in text and '--help' in text, name
