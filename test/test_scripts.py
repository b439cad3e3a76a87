# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""The shell scripts' command lines: help, clear errors, strict mode."""

import os
import subprocess

import pytest

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SCRIPTS = ('setup_env.sh', 'demo.sh', 'run_tests.sh', 'launch_formation.sh')


def run(script, *args):
    return subprocess.run(['bash', os.path.join(ROOT, 'scripts', script), *args],
                          capture_output=True, text=True, timeout=60)


@pytest.mark.parametrize('script', SCRIPTS)
def test_help_and_strict_mode(script):
    result = run(script, '--help')
    assert result.returncode == 0 and result.stdout.startswith('Usage:')
    with open(os.path.join(ROOT, 'scripts', script)) as stream:
        assert 'set -euo pipefail' in stream.read()


@pytest.mark.parametrize('script', SCRIPTS)
def test_unknown_option_is_refused(script):
    result = run(script, '--no-such-option')
    assert result.returncode == 2 and 'unknown option' in result.stderr


def test_launcher_reports_a_missing_file(tmp_path):
    result = run('launch_formation.sh', str(tmp_path / 'missing.yaml'))
    assert result.returncode == 2 and 'not found' in result.stderr


def test_launcher_rejects_a_bad_duration():
    result = run('launch_formation.sh', os.path.join(ROOT, 'config', 'square_4.yaml'),
                 '--duration', 'soon')
    assert result.returncode == 2 and '--duration' in result.stderr


def test_launcher_refuses_an_existing_bag_directory(tmp_path):
    (tmp_path / 'bag').mkdir()
    (tmp_path / 'bag' / 'x').write_text('x')
    result = run('launch_formation.sh', os.path.join(ROOT, 'config', 'square_4.yaml'),
                 '--record', str(tmp_path / 'bag'), '--prefix', str(tmp_path))
    assert result.returncode == 2 and 'exists already' in result.stderr


def test_launcher_takes_one_parameters_file():
    square = os.path.join(ROOT, 'config', 'square_4.yaml')
    result = run('launch_formation.sh', square, square)
    assert result.returncode == 2 and 'only one parameters file' in result.stderr


def test_launcher_refuses_a_non_empty_out_directory(tmp_path):
    (tmp_path / 'run').mkdir()
    (tmp_path / 'run' / 'x').write_text('x')
    result = run('launch_formation.sh', os.path.join(ROOT, 'config', 'square_4.yaml'),
                 '--out', str(tmp_path / 'run'))
    assert result.returncode == 2 and 'is not empty' in result.stderr


def test_launcher_names_a_prefix_without_the_package(tmp_path):
    result = run('launch_formation.sh', os.path.join(ROOT, 'config', 'square_4.yaml'),
                 '--prefix', str(tmp_path / 'no install'))
    assert result.returncode == 2
    assert f"no {tmp_path / 'no install' / 'lib' / 'formation_ros' / 'plant'}" in result.stderr
    assert len(result.stderr.splitlines()) == 1
