# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
Sphinx configuration of the formation_ros documentation (MyST Markdown, Read the Docs theme).

Build: ``.venv/bin/python -m sphinx -W -n -b html docs build/docs`` (no network needed). The
reference tables (parameters, topics, command lines, benchmarks) are generated at build time
by the extension ``docs/_ext/formation_docs.py`` from the package's own definitions.
"""

import os
import sys

DOCS = os.path.dirname(os.path.abspath(__file__))
sys.path[:0] = [os.path.join(DOCS, '_ext'), os.path.dirname(DOCS)]

project = 'formation_ros'
author = 'The formation_ros authors'
copyright = '2026, The formation_ros authors'  # noqa: A001 (the name Sphinx reads)
release = version = '0.1.0'

extensions = ['myst_parser', 'formation_docs']
source_suffix = {'.md': 'markdown'}
root_doc = 'index'
exclude_patterns = ['_build', 'bench/*.json']
myst_enable_extensions = ['dollarmath']
myst_heading_anchors = 3
nitpicky = True
suppress_warnings = []

html_theme = 'sphinx_rtd_theme'
html_title = 'formation_ros'
html_static_path = ['_static']
html_css_files = ['formation.css']
