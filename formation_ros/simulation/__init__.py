# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
The offline simulator library: the law's closed loop on the ideal bodies and on the engine.

No ROS; imports the core and the physics engine. The command-line tools (``tools.sim``,
``tools.report``) and the benches use it; no node imports it.
"""
