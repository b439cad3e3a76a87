# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
The rules of single nodes: what they admit, when they answer, their status and statistics.

For robots, the plant and the world, and the team transport's layouts. The top room of the
core: it may import every other room; none imports it.
"""
