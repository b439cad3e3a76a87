# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
Publishers made on demand: a topic's publisher once a subscriber to it shows in the graph.

With the team transport the plant publishes a robot's ``pose`` and ``neighbors``, and a team
robot its ``cmd_vel``, only for a subscriber (docs/ros_interface.md, "Transports"): a thousand
publishers nobody hears are a thousand endpoints for discovery. :class:`OnDemand` looks up a
few items a look, in turn (``core.rules.turns``), and makes an item's publishers when one shows.
"""

from typing import Callable, List

from formation_ros.core.rules.turns import Turns
import numpy as np
from numpy.typing import NDArray

LISTENERS_PERIOD = 0.5
"""Seconds between looks at who subscribes to the topics published on demand."""


class OnDemand:
    """The items (robots) whose publishers exist, made once a subscriber to them shows."""

    def __init__(self, count: int, looks: int, made: Callable[[int], bool],
                 subscribed: Callable[[int], bool], make: Callable[[int], None],
                 listened: Callable[[int], bool]) -> None:
        """
        Look after ``count`` items, looking up at most ``looks`` of them in the graph a look.

        made(k): whether item k's publishers exist; subscribed(k): whether the graph shows a
        subscriber to its topics (a graph lookup, made only for items without publishers);
        make(k): make its publishers; listened(k): whether its publishers have matched
        subscribers (no graph lookup).
        """
        self.count = count
        self.turns = Turns(looks)
        self.made, self.subscribed = made, subscribed
        self.make, self.listened = make, listened
        self.listening: NDArray[np.bool_] = np.zeros(count, dtype=bool)
        """Which items' publishers have a subscriber, as of the last :meth:`look`."""

    def look(self) -> NDArray[np.bool_]:
        """
        Make the publishers of the items due a look that have a subscriber; return who listens.

        An item whose publishers are made in this look is published to from the next look on,
        once the subscriber has matched them: within ceil(count / looks) + 1 looks of its
        discovery.
        """
        lazy: List[int] = [k for k in self.turns.due(self.count) if not self.made(k)]
        for k in lazy:
            if self.subscribed(k):
                self.make(k)
        self.listening = np.array([self.made(k) and self.listened(k)
                                   for k in range(self.count)], dtype=bool)
        return self.listening
