# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
Whether a subscription's publishers are alive, from DDS liveliness (the lease of ``qos.py``).

The robots' ``cmd_vel`` publishers offer the lease :data:`formation_ros.ros.qos.LIVELINESS_LEASE`
and the plant's subscribers ask for it, so DDS tells the plant within the lease when a robot
stops showing signs of life, and when it is back (docs/faults.md: a peer dies or its link is
cut). A :class:`PeerLiveliness` keeps what the subscription's liveliness events say; the node's
diagnostics timer reports it.
"""

import time
from typing import Any, Optional

from rclpy.event_handler import SubscriptionEventCallbacks


class PeerLiveliness:
    """The publishers of one subscription: how many are alive, how often one was lost."""

    def __init__(self) -> None:
        """Start knowing nothing: no event yet."""
        self.alive = 0
        self.not_alive = 0
        self.lost = 0
        self.changed_ns: Optional[int] = None

    def callbacks(self) -> SubscriptionEventCallbacks:
        """Return the event callbacks to give ``create_subscription``."""
        return SubscriptionEventCallbacks(liveliness=self.on_event)

    def on_event(self, event: Any) -> None:
        """Store a liveliness change (rclpy's QoSLivelinessChangedInfo)."""
        if event.alive_count_change < 0 or event.not_alive_count_change > 0:
            self.lost += 1
        self.alive = int(event.alive_count)
        self.not_alive = int(event.not_alive_count)
        self.changed_ns = time.monotonic_ns()

    def state(self) -> str:
        """Return 'alive', 'lost' (one was alive and is not now) or 'unknown' (never heard)."""
        if self.alive > 0:
            return 'alive'
        return 'lost' if self.lost else 'unknown'
