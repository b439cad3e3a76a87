# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
Command-line tools and what only they use.

``formation_sim`` (``sim``), ``formation_report`` (``report``), ``formation_render``
(``render``), the launcher (``launcher``, with its plan of processes ``system``, its
supervision ``supervise`` and its domain ``domain``), several hosts (``hosts``) and the
reading of bags back (``bag``). The simulator library is in ``formation_ros.simulation``, the
figures in ``formation_ros.figures``; no node imports any of them.
"""
