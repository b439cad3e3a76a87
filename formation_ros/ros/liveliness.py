# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
Whether a subscription's publishers are alive, from DDS liveliness (the lease of ``qos.py``).

The robots' ``cmd_vel`` publishers offer a liveliness lease of
:data:`formation_ros.ros.qos.LIVELINESS_LEASE`, kept by their commands (a running robot sends
one at least every control period), and the plant's subscribers ask for it, so DDS
tells the plant within that lease when a robot stopped showing signs of life (its process was
killed, its host lost power or its link was cut), and again when it is back. (The plant offers
the lease on ``pose`` and ``neighbors`` too, but robots ask for none there: they hear any
publisher, and notice a silent plant by their watchdog.) A
:class:`PeerLiveliness` stores what the subscription's liveliness events say; the node's
diagnostics timer reports it. Without liveliness the dead process's publisher stays listed
until DDS drops its participant, about 20 s later.
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
