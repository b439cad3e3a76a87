# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
The robots' bodies: their kinds and body mapping, imperfections, the plant model.

The plant model is the one every integrator shares (``formation_sim --dt``, the plant node);
``commanded`` reads a published command back at a body's orientation. Imports the maths only.
"""
