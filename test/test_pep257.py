# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""Style: the ament pep257 docstring rules."""

import os

from ament_pep257.main import main
import pytest

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


@pytest.mark.linter
@pytest.mark.pep257
def test_pep257():
    names = ('formation_ros', 'test', 'bench', 'launch', 'docs')
    paths = [os.path.join(ROOT, name) for name in names]
    rc = main(argv=[p for p in paths if os.path.exists(p)])
    assert rc == 0, 'pep257 findings: see the output above'
