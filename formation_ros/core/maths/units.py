# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
The units of time: ROS stamps and the plant's clock count whole nanoseconds, the math seconds.

Stamps stay integers (a float of the seconds since 1970 resolves about 0.24 us); a time in
seconds is ``stamp_ns / NS_PER_S`` and a stamp ``int(round(t * NS_PER_S))``.
"""

NS_PER_S = 1_000_000_000
"""Nanoseconds per second."""
