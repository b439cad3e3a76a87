# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
A stand-in for a lab, run by the test's probe node: real-ish bodies, their bases and a mocap.

Written here, independently of the package's plant model (``core.model.plant``,
``core.maths.unicycle``): the point of a lab test is that the robots meet bodies the package did
not write.

* Bodies: holonomic points (velocity (vx, vy) in the world) or differential-drive unicycles
  (forward speed v, turn rate w), each with a first-order lag (time constant ``lag``, s) from
  its base's command to its velocity and an acceleration limit (``max_acceleration``, m/s^2 per
  component; ``max_angular_acceleration``, rad/s^2, on w), integrated with explicit Euler steps
  of at most :data:`SUBSTEP` s over the wall-clock time between two ticks of a probe timer.
* Bases: a holonomic base takes geometry_msgs/Twist in its BODY frame and turns it into the
  world with its own heading (fixed, one per body); a diff_drive-like base takes TwistStamped
  in ``robot_<i>/base_link`` (linear.x = v, angular.z = w) and drops a command whose stamp is
  older than ``cmd_vel_timeout`` s (as diff_drive_controller does); a world base (the relay's
  dropout test) takes TwistStamped in the world frame. A base that heard no command for
  ``cmd_vel_timeout`` s stops.
* Mocap: every body's pose on its own topic at ``rate`` Hz, best effort, each stamped with its
  own capture time (wall clock), positions with Gaussian noise of ``noise`` m; robots listed in
  ``hidden`` are not measured (a marker occluded).
"""

from dataclasses import dataclass, field
import enum
import math
from typing import Dict, List, Optional, Sequence, Set, Tuple

from geometry_msgs.msg import PoseStamped, Twist, TwistStamped
import numpy as np
from rclpy.clock import Clock, ClockType
from rclpy.qos import qos_profile_sensor_data, QoSProfile, ReliabilityPolicy
import wire

SUBSTEP = 0.002
NS_PER_S = 1_000_000_000
WALL = Clock(clock_type=ClockType.SYSTEM_TIME)
STEADY = Clock(clock_type=ClockType.STEADY_TIME)
COMMANDS_QOS = QoSProfile(depth=10, reliability=ReliabilityPolicy.RELIABLE)


class Base(enum.Enum):
    """What a base takes on its cmd_vel."""

    HOLONOMIC_BODY = 'geometry_msgs/Twist in the body frame'
    DIFF_DRIVE = 'TwistStamped (v, w) in robot_<i>/base_link'
    WORLD = 'TwistStamped in the world frame'


def steady_s() -> float:
    return STEADY.now().nanoseconds / NS_PER_S


@dataclass
class Lab:
    """
    The bodies, their bases and the mocap of ``len(q)`` robots.

    q: (N, 2) start positions, m; heading: (N,) headings, rad (fixed for holonomic bodies);
    command_topic / mocap_topic: templates with ``{i}`` (the robot's id, 1-based) and, when
    ``names`` are given (one per robot, as ``relay.source_names``), ``{name}``.
    """

    q: np.ndarray
    heading: np.ndarray
    base: Base
    command_topic: str
    mocap_topic: str
    frame: str = 'map'
    rate: float = 100.0
    noise: float = 0.0
    lag: float = 0.0
    max_acceleration: float = 0.0
    max_angular_acceleration: Optional[float] = None
    cmd_vel_timeout: float = 0.5
    seed: int = 0
    hidden: Set[int] = field(default_factory=set)
    names: Sequence[str] = ()
    velocity: np.ndarray = field(init=False)
    target: np.ndarray = field(init=False)
    heard_at: np.ndarray = field(init=False)
    heard: List[Tuple[float, int, Tuple[float, ...]]] = field(default_factory=list)
    """Every command heard: (steady s, robot 1-based, the message's (x, y, z, ax, ay, az))."""
    commands: List[Tuple[float, int, Tuple[float, ...]]] = field(default_factory=list)
    """Every command taken (not dropped), as in ``heard``."""
    dropped: Dict[str, int] = field(default_factory=dict)
    history: List[Tuple[float, np.ndarray, np.ndarray]] = field(default_factory=list)
    """(steady s, q (N, 2), heading (N,)) after every tick."""
    measured: Dict[int, Tuple[float, Tuple[float, float]]] = field(default_factory=dict)
    """Robot (0-based) -> (steady s, position) of its latest measurement sent."""
    measure_times: List[float] = field(default_factory=list)
    """Steady s of every measurement round (all visible bodies at once)."""

    def __post_init__(self) -> None:
        """Start at rest."""
        self.q = np.array(self.q, dtype=float)
        self.heading = np.array(self.heading, dtype=float)
        n = len(self.q)
        self.velocity = np.zeros((n, 2))
        self.target = np.zeros((n, 2))
        self.heard_at = np.full(n, -math.inf)
        self.rng = np.random.default_rng(self.seed)
        self.last = steady_s()
        self.next_measure = self.last
        angular = (self.max_acceleration if self.max_angular_acceleration is None
                   else self.max_angular_acceleration)
        self.limits = np.array([self.max_acceleration,
                                angular if self.base is Base.DIFF_DRIVE
                                else self.max_acceleration])
        """Largest change of each velocity component per second: m/s^2 (rad/s^2 for w)."""

    def topic(self, template: str, i: int) -> str:
        """Robot ``i``'s (0-based) topic of ``template``."""
        return template.format(i=i + 1, **({'name': self.names[i]} if self.names else {}))

    def attach(self, probe) -> None:
        """Subscribe the bases to their commands, create the mocap publishers, start ticking."""
        kind = Twist if self.base is Base.HOLONOMIC_BODY else TwistStamped
        self.subscriptions = [
            probe.create_subscription(kind, self.topic(self.command_topic, i),
                                      lambda m, i=i: self.on_command(i, m), COMMANDS_QOS)
            for i in range(len(self.q))]
        self.mocap = [probe.create_publisher(PoseStamped, self.topic(self.mocap_topic, i),
                                             qos_profile_sensor_data)
                      for i in range(len(self.q))]
        self.timer = probe.create_timer(1.0 / self.rate, self.tick)

    def _drop(self, why: str) -> None:
        self.dropped[why] = self.dropped.get(why, 0) + 1

    def on_command(self, i: int, message) -> None:
        """Take a command as the base would: frame and age checks, then the velocity wanted."""
        now = steady_s()
        twist = message if self.base is Base.HOLONOMIC_BODY else message.twist
        values = (twist.linear.x, twist.linear.y, twist.linear.z,
                  twist.angular.x, twist.angular.y, twist.angular.z)
        self.heard.append((now, i + 1, values))
        if not all(map(math.isfinite, values)):
            self._drop('non-finite')
            return
        if self.base is Base.HOLONOMIC_BODY:
            c, s = math.cos(self.heading[i]), math.sin(self.heading[i])
            vx, vy = values[0], values[1]
            self.target[i] = (c * vx - s * vy, s * vx + c * vy)
        else:
            stamp = message.header.stamp.sec + message.header.stamp.nanosec * 1e-9
            if WALL.now().nanoseconds / NS_PER_S - stamp > self.cmd_vel_timeout:
                self._drop('stale stamp')
                return
            expected = (f'robot_{i + 1}/base_link' if self.base is Base.DIFF_DRIVE
                        else self.frame)
            if message.header.frame_id != expected:
                self._drop(f'frame {message.header.frame_id!r}')
                return
            self.target[i] = ((values[0], values[5]) if self.base is Base.DIFF_DRIVE
                              else (values[0], values[1]))
        self.heard_at[i] = now
        self.commands.append((now, i + 1, values))

    def _accelerate(self, target: np.ndarray, dt: float) -> None:
        """One Euler step of the lag v' = (target - v) / lag, clipped to the acceleration."""
        if self.lag > 0.0:
            change = (target - self.velocity) * (1.0 - math.exp(-dt / self.lag))
        else:
            change = target - self.velocity
        if self.max_acceleration > 0.0:
            change = np.clip(change, -self.limits * dt, self.limits * dt)
        self.velocity += change

    def tick(self) -> None:
        """Integrate the bodies up to now, then measure them (at ``rate``)."""
        now = steady_s()
        target = np.where((now - self.heard_at <= self.cmd_vel_timeout)[:, None],
                          self.target, 0.0)
        span = now - self.last
        steps = max(1, int(math.ceil(span / SUBSTEP)))
        for _ in range(steps):
            dt = span / steps
            self._accelerate(target, dt)
            if self.base is Base.DIFF_DRIVE:
                v, w = self.velocity[:, 0], self.velocity[:, 1]
                self.q += dt * v[:, None] * np.stack((np.cos(self.heading),
                                                      np.sin(self.heading)), axis=1)
                self.heading += dt * w
            else:
                self.q += dt * self.velocity
        self.last = now
        self.history.append((now, self.q.copy(), self.heading.copy()))
        if now >= self.next_measure:
            self.next_measure = now + 1.0 / self.rate
            self.measure(now)

    def measure(self, now: float) -> None:
        """Publish every visible body's pose, each stamped with its own capture time."""
        self.measure_times.append(now)
        for i, publisher in enumerate(self.mocap):
            if i in self.hidden:
                continue
            position = self.q[i] + (self.rng.normal(0.0, self.noise, 2) if self.noise else 0.0)
            half = 0.5 * float(self.heading[i])
            publisher.publish(wire.pose_stamped_bytes(
                WALL.now().nanoseconds, self.frame, position,
                (0.0, 0.0, math.sin(half), math.cos(half))))
            self.measured[i] = (now, (float(position[0]), float(position[1])))

    def stalls(self, longer_than: float) -> int:
        """How many times this stand-in (a busy test process) measured nothing for a while, s."""
        return int(np.count_nonzero(np.diff(self.measure_times) > longer_than))

    def closest_pair(self) -> float:
        """Smallest distance between two bodies over the whole run so far, m."""
        best = math.inf
        for _, q, _ in self.history:
            gaps = np.linalg.norm(q[:, None] - q[None], axis=2)
            best = min(best, float(np.min(gaps[np.triu_indices(len(q), 1)])))
        return best

    def latest(self) -> Optional[Tuple[float, np.ndarray, np.ndarray]]:
        return self.history[-1] if self.history else None
