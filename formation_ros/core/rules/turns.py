# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
Bounded looks in turn: at most ``limit`` of n items a call, each item once every ceil(n / limit).

A node that must look something up for each of many items (who subscribes to a robot's topic,
who publishes it) and where each lookup costs more as the ROS graph grows, looks at a few items
a call instead of all of them: :class:`Turns` hands out the indices of the next ``limit`` items,
going round. An item is then looked at within ceil(n / limit) calls of any change.
"""

from typing import List, Optional


class Turns:
    """The indices of the items to look at in each call, ``limit`` of them in turn."""

    def __init__(self, limit: Optional[int]) -> None:
        """Hand out ``limit`` indices a call (None: all of them every call); limit >= 1."""
        if limit is not None and limit < 1:
            raise ValueError(f'limit must be at least 1, not {limit}')
        self.limit = limit
        self.cursor = 0

    def due(self, n: int) -> List[int]:
        """
        Return the indices (of n items) to look at now: the next ``limit`` after the last call's.

        All of 0..n-1 when ``limit`` is None or at least n. The number of items may change
        between calls; the turn goes on from where it stopped (modulo n).
        """
        if n <= 0:
            return []
        if self.limit is None or self.limit >= n:
            return list(range(n))
        start = self.cursor % n
        self.cursor = (start + self.limit) % n
        return [(start + k) % n for k in range(self.limit)]
