# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
The ROS-free core, in rooms by concern, arrows pointing down only (``test/test_layers.py``).

``maths`` (the paper) <- ``model`` (the bodies) <- ``settings`` (parameters and files);
``maths`` <- ``runs`` (sampled runs); ``rules`` (the nodes' rules) may import all four.
``test/test_layers.py`` (``CORE_ROOMS``) states the same. Nothing here imports ROS, MuJoCo or
matplotlib.
"""
