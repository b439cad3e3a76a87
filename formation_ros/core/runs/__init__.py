# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
A run as sampled and measured: trajectories, events, metrics.

What changed when (shapes, stop / go) and the numbers that show the law kept its promises.
Imports the maths only.
"""
