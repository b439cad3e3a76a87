# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""What a recording holds (ros/topics.recorded_topics): the obstacles a robot was told too."""

from formation_ros.ros.bag_writer import TYPESTORE
from formation_ros.ros.topics import recorded_topics


def test_a_map_with_obstacles_records_what_each_robot_was_told():
    names = {topic.name: topic.type_name for topic in recorded_topics(3, False, obstacles=True)}
    assert {names[f'/robot_{i}/obstacles'] for i in (1, 2, 3)} == {'geometry_msgs/msg/PoseArray'}
    without = {topic.name for topic in recorded_topics(3, False)}
    assert not any(name.endswith('/obstacles') for name in without)
    assert set(names) - without == {f'/robot_{i}/obstacles' for i in (1, 2, 3)}


def test_every_recorded_type_can_be_written():
    for topic in recorded_topics(2, True, obstacles=True):
        assert topic.type_name in TYPESTORE.types, topic.type_name
