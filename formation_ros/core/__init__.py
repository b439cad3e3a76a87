# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
The ROS-free core, in rooms by concern, arrows pointing down only (``test/test_layers.py``).

``maths`` (the paper) <- ``model`` (the bodies) and ``runs`` (sampled runs) <- ``settings``
(parameters and files) <- ``rules`` (the nodes' rules). Nothing here imports ROS, MuJoCo or
matplotlib.
"""
