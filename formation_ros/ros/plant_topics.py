# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
What the plant publishes of each state: ``/clock``, then what every robot senses.

Each robot's ``obstacles`` (when the map has some), ``pose`` and ``neighbors``, or with the team
transport one ``/formation/obstacles`` and one ``/formation/states`` message and a robot's own
topics only while someone subscribes to them (``ros.on_demand``).
The topics and their QoS: docs/ros_interface.md ("Topics", "Transports"); the bytes:
``ros.cdr.StateEncoder``.
"""

from typing import List, Optional

from formation_ros.core.maths.obstacles import Obstacles, told_obstacles
from formation_ros.core.model.plant import PlantModel
from formation_ros.ros import qos, topics
from formation_ros.ros.cdr import (encode_clock, encode_obstacles, encode_team_obstacles,
                                   StateEncoder)
from formation_ros.ros.on_demand import LISTENERS_PERIOD, OnDemand
from geometry_msgs.msg import PoseArray, PoseStamped
import numpy as np
from rclpy.clock import Clock
from rclpy.node import Node
from rclpy.publisher import Publisher
from rosgraph_msgs.msg import Clock as ClockMsg
from trajectory_msgs.msg import MultiDOFJointTrajectory

LISTENER_LOOKS = 50
"""Team transport: robots whose pose and neighbors subscribers are looked up in the graph per
LISTENERS_PERIOD while the plant has no publishers of theirs (two lookups each)."""


class PlantTopics:
    """
    The plant's state topics on ``node``: /clock, and each robot's pose and neighbors.

    team: the team transport (/formation/states); lazy: a robot's pose and neighbors publishers
    are made once someone subscribes to either (looked up on a timer of ``clock``); headed: the
    poses carry headings (unicycles, body-frame commands); obstacles: the map (None: none,
    no obstacle topic) and radii (N,) the robots' R_i, m (``core.maths.obstacles.told_obstacles``).
    """

    def __init__(self, node: Node, num_robots: int, dim: int, world_frame: str, team: bool,
                 lazy: bool, headed: bool, clock: Clock,
                 obstacles: Optional[Obstacles] = None,
                 radii: Optional[np.ndarray] = None) -> None:
        """Create the publishers (lazy ones later)."""
        self.node = node
        self.team, self.headed = team, headed
        self.world_frame = world_frame
        self.obstacles, self.radii = obstacles, radii
        self.encoder = StateEncoder(num_robots, dim, world_frame)
        self.pose_topics = [topics.robot_topic(i, topics.POSE) for i in range(1, num_robots + 1)]
        self.neighbour_topics = [topics.robot_topic(i, topics.NEIGHBOURS)
                                 for i in range(1, num_robots + 1)]
        self.obstacle_topics = ([topics.robot_topic(i, topics.OBSTACLES)
                                 for i in range(1, num_robots + 1)] if obstacles else [])
        self.pubs: List[Optional[List[Publisher]]] = [None] * num_robots
        """Each robot's [pose, neighbors] publishers, then its obstacles' with a map (None: not
        made yet)."""
        self.listened = np.ones(num_robots, dtype=bool)
        """Which robots' pose and neighbors are published."""
        for i in range(num_robots if not lazy else 0):
            self._make(i)
        self.clock_pub = node.create_publisher(ClockMsg, topics.CLOCK, qos.CLOCK)
        if team:
            self.states_pub = node.create_publisher(PoseArray, topics.STATES, qos.STATE)
            if obstacles:
                self.team_obstacles_pub = node.create_publisher(
                    MultiDOFJointTrajectory, topics.TEAM_OBSTACLES, qos.STATE)
            self.on_demand = OnDemand(
                num_robots, LISTENER_LOOKS, lambda i: self.pubs[i] is not None,
                lambda i: any(node.count_subscribers(topic) > 0 for topic in
                              self._robot_topics(i)),
                self._make, lambda i: any(pub.get_subscription_count() > 0
                                          for pub in self.pubs[i]))
            self.listeners_timer = node.create_timer(LISTENERS_PERIOD, self.look_at_listeners,
                                                     clock=clock)
            self.look_at_listeners()

    def _robot_topics(self, index: int) -> List[str]:
        """Return robot ``index``'s (0-based) topics: pose, neighbors and obstacles (a map)."""
        return ([self.pose_topics[index], self.neighbour_topics[index]]
                + self.obstacle_topics[index:index + 1])

    def _make(self, index: int) -> None:
        """Create the ``pose``, ``neighbors`` (and ``obstacles``) publishers of robot ``index``."""
        self.pubs[index] = [
            self.node.create_publisher(PoseStamped, self.pose_topics[index], qos.STATE),
            self.node.create_publisher(PoseArray, self.neighbour_topics[index], qos.STATE)]
        if self.obstacle_topics:
            self.pubs[index].append(self.node.create_publisher(
                PoseArray, self.obstacle_topics[index], qos.STATE))

    def look_at_listeners(self) -> None:
        """Team transport: publish a robot's pose and neighbors only while someone listens."""
        self.listened = self.on_demand.look()

    def published_topics(self) -> List[str]:
        """Return the topics published, /clock first, then each robot's pose and neighbors."""
        return ([topics.CLOCK] + [topic for i in range(len(self.pose_topics))
                                  for topic in self._robot_topics(i)]
                + ([topics.STATES] if self.team else [])
                + ([topics.TEAM_OBSTACLES] if self.team and self.obstacles else []))

    def publish(self, model: PlantModel) -> int:
        """
        Publish /clock, then the model's sensed state (``PlantModel.sensed``); return its stamp.

        The state is the present one for ideal sensing, else the one measured a delay ago,
        stamped with its measurement time (ns); the clock stays the present. With a map each
        robot's obstacles of that state go first (``told_obstacles`` of its positions and
        control points), so that a robot has them when its pose and neighbours come.
        """
        self.clock_pub.publish(encode_clock(model.t_ns))
        state = model.sensed()
        headings = state.heading if self.headed else None
        told = (None if self.obstacles is None else
                told_obstacles(self.obstacles, state.q, state.points, self.radii))
        if self.team:
            if told is not None:
                self.team_obstacles_pub.publish(
                    encode_team_obstacles(state.stamp_ns, self.world_frame, told))
            self.encoder.set_rows(state.q, headings)
            self.states_pub.publish(self.encoder.team(state.stamp_ns))
        if not self.team or np.any(self.listened):
            observer, seen = model.sensed_pairs()
            poses, arrays = self.encoder.encode(state.q, observer, seen, state.stamp_ns,
                                                headings)
            told_bytes = (None if told is None
                          else encode_obstacles(state.stamp_ns, self.world_frame, told))
            for i in np.flatnonzero(self.listened).tolist():
                publishers = self.pubs[i]
                if told_bytes is not None:
                    publishers[2].publish(told_bytes[i])
                publishers[0].publish(poses[i])
                publishers[1].publish(arrays[i])
        return state.stamp_ns

    def unheard(self, wanted: int) -> bool:
        """Whether a pose topic has fewer than ``wanted`` subscribers, or the states none."""
        return ((wanted > 0 and any(pubs is None or pubs[0].get_subscription_count() < wanted
                                    for pubs in self.pubs))
                or (self.team and self.states_pub.get_subscription_count() < 1))

    def clock_unmatched(self) -> bool:
        """Whether a /clock subscriber the graph shows is not matched to the clock publisher."""
        return (self.clock_pub.get_subscription_count()
                < self.node.count_subscribers(topics.CLOCK))
