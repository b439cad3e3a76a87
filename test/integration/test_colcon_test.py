# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
``colcon test`` runs the package's pytest suite, and its result says what ran and failed.

It selects one quick test (the copyright headers) in one file of the suite, on the install
space the other integration tests use: collecting the whole suite again would take half a
minute, and the linters themselves already run in the suite.
"""

import os
import re
import subprocess
import sys
import xml.etree.ElementTree as ElementTree

from conftest import ROOT

SELECTED = 'test_every_source_file_starts_with_the_copyright_header'


def colcon(base, *args):
    """Run ``python -m colcon`` with its log under ``base``; return the completed process."""
    return subprocess.run([sys.executable, '-m', 'colcon', '--log-base', str(base / 'log'), *args],
                          cwd=str(base), capture_output=True, text=True, timeout=600)


def test_colcon_test_runs_the_selected_pytest_tests_and_reports_them(install, tmp_path):
    colcon_base = os.path.dirname(os.path.dirname(install))
    results = tmp_path / 'test_results'
    run = colcon(tmp_path, 'test', '--packages-select', 'formation_ros',
                 '--base-paths', ROOT, '--build-base', os.path.join(colcon_base, 'build'),
                 '--install-base', os.path.join(colcon_base, 'install'),
                 '--test-result-base', str(results), '--return-code-on-test-failure',
                 '--event-handlers', 'console_cohesion+',
                 '--pytest-args', os.path.join('test', 'test_copyright.py'), '-k', SELECTED)
    output = run.stdout + run.stderr
    assert 'Ran 0 tests' not in output, 'colcon fell back to unittest:\n' + output
    assert run.returncode == 0, output

    junit = results / 'formation_ros' / 'pytest.xml'
    assert junit.is_file(), f'no pytest result at {junit}:\n{output}'
    suite = ElementTree.parse(junit).getroot()
    if suite.tag == 'testsuites':
        (suite,) = suite
    cases = [case.get('name') for case in suite.iter('testcase')]
    assert cases == [SELECTED], cases
    assert int(suite.get('tests')) >= 1
    assert int(suite.get('failures')) == 0 and int(suite.get('errors')) == 0, output

    summary = colcon(tmp_path, 'test-result', '--test-result-base', str(results), '--verbose')
    assert summary.returncode == 0, summary.stdout + summary.stderr
    counts = re.search(r'^Summary: (\d+) tests?, (\d+) errors?, (\d+) failures?',
                       summary.stdout, re.MULTILINE)
    assert counts, summary.stdout
    ran, errors, failures = (int(value) for value in counts.groups())
    assert ran >= 1 and errors == 0 and failures == 0, summary.stdout
