# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
The physics engine of the robots' bodies on MuJoCo (beyond the paper; no ROS).

``models`` chooses among the three bodies (``diff_drive``: a differential-drive base;
``points``: a holonomic planar base, a flying body; made of the MJCF ``parts``), each of which
says how a command becomes its motors' set points; ``scene`` builds the MJCF world from
a validated :class:`~formation_ros.core.settings.params.FormationConfig`; ``engine`` steps it,
applies commands and reads ground truth, wheel odometry and contacts (``contacts``, ``odometry``),
and casts the planar bodies' laser scans (``scanner``); ``obstacles`` builds the map's geoms.
Only this group imports ``mujoco``; the numpy core never imports it.
"""
