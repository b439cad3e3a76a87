# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
Figures and animations of a run (matplotlib): the paper's plots, the animation's frames.

Imports the core and the simulator library (its progress line, the shape in force); the
command-line tools use it; no node imports it.
"""
