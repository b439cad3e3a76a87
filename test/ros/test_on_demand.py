# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""Publishers made once a subscriber shows, a few items looked up a look."""

from formation_ros.ros.on_demand import OnDemand


class Graph:
    """Items' publishers and subscribers as a fake graph, counting the lookups."""

    def __init__(self, count):
        self.publishers = [False] * count
        self.subscribers = [False] * count
        self.lookups = []

    def subscribed(self, k):
        self.lookups.append(k)
        return self.subscribers[k]

    def make(self, k):
        self.publishers[k] = True

    def demand(self, count, looks):
        return OnDemand(count, looks, lambda k: self.publishers[k], self.subscribed, self.make,
                        lambda k: self.publishers[k] and self.subscribers[k])


def test_a_subscriber_gets_its_publisher_within_its_turn_and_is_listened_to():
    graph = Graph(5)
    demand = graph.demand(5, looks=2)
    graph.subscribers[4] = True
    assert not demand.look().any()
    assert graph.lookups == [0, 1]
    assert not demand.look().any()
    assert graph.publishers == [False] * 4 + [False]
    listening = demand.look()
    assert graph.publishers[4]
    assert listening.tolist() == [False] * 4 + [True]


def test_items_with_publishers_are_never_looked_up_in_the_graph():
    graph = Graph(3)
    graph.publishers[1] = True
    demand = graph.demand(3, looks=3)
    demand.look()
    assert graph.lookups == [0, 2]
    graph.subscribers[1] = True
    assert demand.look().tolist() == [False, True, False]
