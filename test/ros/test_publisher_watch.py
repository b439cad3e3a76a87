# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""PublisherWatch (ros/team.py): a bounded number of graph looks per call, every topic in turn."""

from types import SimpleNamespace

from formation_ros.ros.team import NAMES_WAIT, PublisherWatch, UNNAMED

OWN = '/plant'


class Graph:
    """A stand-in for a node's graph: {topic: [(namespace, name), ...]}, counting the looks."""

    def __init__(self, topics):
        """Start with one publisher, the plant, on each of ``topics``."""
        self.publishers = {topic: [('/', 'plant')] for topic in topics}
        self.looks = []

    def count_publishers(self, topic):
        """Count the publishers of ``topic`` (a look, recorded)."""
        self.looks.append(topic)
        return len(self.publishers[topic])

    def get_publishers_info_by_topic(self, topic):
        """Describe the publishers of ``topic`` as rclpy's TopicEndpointInfo does."""
        return [SimpleNamespace(node_namespace=ns, node_name=name)
                for ns, name in self.publishers[topic]]


def test_a_second_publisher_is_seen_within_the_topics_over_the_limit_calls():
    topics = [f'/robot_{i}/pose' for i in range(1, 11)]
    graph = Graph(topics)
    watch = PublisherWatch(graph, limit=3)
    expected = dict.fromkeys(topics, OWN)
    graph.publishers['/robot_8/pose'].append(('/', 'forger'))
    found = []
    for call in range(4):
        graph.looks.clear()
        found.append(watch.check(expected, float(call)))
        assert len(graph.looks) <= 3 + len(watch.listed)
    assert found[:2] == [{}, {}] and found[2] == {'/robot_8/pose': '/forger'}
    assert found[3] == found[2]
    graph.looks.clear()
    graph.publishers['/robot_8/pose'].pop()
    assert watch.check(expected, 4.0) == {}
    assert '/robot_8/pose' in graph.looks and watch.listed == {}


def test_every_topic_is_looked_at_in_turn_and_all_without_a_limit():
    topics = [f'/t{i}' for i in range(7)]
    graph = Graph(topics)
    watch = PublisherWatch(graph, limit=3)
    for call in range(7):
        watch.check(dict.fromkeys(topics, OWN), float(call))
    assert sorted(set(graph.looks)) == sorted(topics)
    assert len(graph.looks) == 21
    graph.looks.clear()
    PublisherWatch(graph).check(dict.fromkeys(topics, OWN), 0.0)
    assert graph.looks == topics


def test_a_publisher_without_a_ros_name_yet_is_named_once_the_graph_has_it():
    graph = Graph(['/clock'])
    watch = PublisherWatch(graph)
    graph.publishers['/clock'].append(('_NODE_NAMESPACE_UNKNOWN_', '_NODE_NAME_UNKNOWN_'))
    assert watch.named_publishers('/clock', 10.0) is None
    assert watch.check({'/clock': OWN}, 10.0) == {}
    assert watch.named_publishers('/clock', 10.0 + NAMES_WAIT / 2) is None
    graph.publishers['/clock'][-1] = ('/', 'probe')
    assert watch.named_publishers('/clock', 11.0) == ['/plant', '/probe']
    assert watch.check({'/clock': OWN}, 11.0) == {'/clock': '/probe'}


def test_a_publisher_never_named_is_called_so_after_the_wait():
    graph = Graph(['/clock'])
    watch = PublisherWatch(graph)
    graph.publishers['/clock'].append(('_NODE_NAMESPACE_UNKNOWN_', '_NODE_NAME_UNKNOWN_'))
    assert watch.named_publishers('/clock', 3.0) is None
    assert watch.named_publishers('/clock', 3.0 + NAMES_WAIT) == ['/plant', UNNAMED]
