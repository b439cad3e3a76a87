# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""Style: the ament flake8 rules (99 columns, single quotes, import order, docstrings)."""

import os

from ament_flake8.main import main_with_errors
import pytest

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


@pytest.mark.flake8
@pytest.mark.linter
def test_flake8():
    names = ('formation_ros', 'test', 'bench', 'launch', 'docs', 'setup.py')
    paths = [os.path.join(ROOT, name) for name in names]
    rc, errors = main_with_errors(argv=[p for p in paths if os.path.exists(p)])
    assert rc == 0, f'{len(errors)} flake8 findings:\n' + '\n'.join(errors)
