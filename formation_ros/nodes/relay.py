# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

r"""
Relay node (executable ``relay``): the range sensor of the plant, without the bodies.

In a lab the bodies are real and a motion-capture system measures them: :class:`RelayNode`
reads each robot's measured pose (``relay.source_topic``, a PoseStamped or an Odometry) and
publishes what the plant would, every robot's ``pose`` and ``neighbors`` with the one sensing
rule of ``core.maths.sensing``, all with one wall-clock stamp per cycle at ``relay.rate``, and with
an arena map (``obstacles.*``) each robot's ``obstacles`` by the plant's rule
(``core.maths.obstacles.told_obstacles``), stamped as its pose and sent before it. Beside a
simulated lab (the ``world`` node) it runs on the world's ``/clock`` (``use_sim_time:=true``):
a cycle is due every ``1 / relay.rate`` s of simulated time, stamped with it, and a
measurement's age is simulated time since it arrived (:meth:`RelayNode.now_ns`). A
measurement is admitted by ``core.rules.admission`` (frame, finite values, a unit quaternion, whole
bytes; every refusal counted and logged once through ``ros.once.RefusalLog``) and by its stamp
(:meth:`RelayNode._advances`: later than the last one taken). The rules and the stale robots:
docs/lab.md and docs/faults.md ("the motion capture repeats a lost body's last pose")::

    ros2 run formation_ros relay --ros-args --params-file config/lab_turtlebot3.yaml
    ros2 run formation_ros relay --ros-args --params-file config/world_turtlebot3.yaml \\
        -p use_sim_time:=true
"""

import time
from typing import Callable, Dict, List, Optional, Tuple

from diagnostic_msgs.msg import DiagnosticArray
from formation_ros.core.maths.frames import valid_quaternions
from formation_ros.core.maths.obstacles import told_obstacles
from formation_ros.core.maths.sensing import sensed_pairs, sensor_radii
from formation_ros.core.maths.unicycle import headings_from_quaternions
from formation_ros.core.maths.units import NS_PER_S
from formation_ros.core.model.bodies import make_bodies
from formation_ros.core.rules.admission import Reason, refusal
from formation_ros.core.settings.declarations import Exe, ParamError, SourceType
from formation_ros.core.settings.team import team_values
from formation_ros.ros import qos, topics
from formation_ros.ros.cdr import (CdrError, encode_obstacles, PoseData, read_odometry,
                                   read_pose_stamped, StateEncoder)
from formation_ros.ros.diagnostics import diagnostics, PERIOD
from formation_ros.ros.once import OnceLog, RefusalLog
from formation_ros.ros.parameters import declare_parameters
from formation_ros.ros.runner import run
from formation_ros.ros.team import announced
from formation_ros.ros.wake import Wake
from geometry_msgs.msg import PoseArray, PoseStamped
from nav_msgs.msg import Odometry
import numpy as np
from rclpy.clock import Clock, ClockType, JumpThreshold
from rclpy.duration import Duration
from rclpy.node import Node
from scipy.spatial import cKDTree

NEVER = -1
UNSTAMPED = 0
"""A stamp that means none, on the wall clock; on a world's /clock 0 is its first moment, and
only a second 0 in a row means none."""
MESSAGE_TYPES = {SourceType.POSE: PoseStamped, SourceType.ODOMETRY: Odometry}


class RelayNode(Node):
    """Measured poses in, every robot's pose and sensor reading out, one stamp per cycle."""

    def __init__(self) -> None:
        """Declare and check parameters, then subscribe to every source and start the cycle."""
        super().__init__('relay')
        config = declare_parameters(self, Exe.RELAY)
        team = team_values(config, config.vertices)
        del team['shape in force']
        self.team_keys = announced(team)
        settings = config.relay
        assert settings is not None
        self.sim_time = bool(self.get_parameter('use_sim_time').value)
        """Whether the relay runs on a simulated world's /clock (else the host's clocks)."""
        self.settings = settings
        self.n, self.dim = config.num_robots, config.dim
        self.world_frame = config.world_frame
        self.unicycles = config.body.is_unicycle
        self.bodies = make_bodies(config.body)
        margin = self.bodies.sensing_margin
        self.reach = sensor_radii(config.sensing_radii, margin)
        self.radii = config.sensing_radii
        self.obstacles = config.obstacles
        """The arena's map (None: none, no obstacles topics)."""
        self.max_age_ns = int(settings.max_age * NS_PER_S)
        self.sources = [settings.source(i) for i in range(1, self.n + 1)]
        outputs = {topics.robot_topic(i, name) for i in range(1, self.n + 1)
                   for name in (topics.POSE, topics.NEIGHBOURS, topics.CMD_VEL,
                                topics.OBSTACLES)}
        outputs |= {topics.REFERENCE, topics.CLOCK, topics.DIAGNOSTICS, topics.MARKERS,
                    topics.PARAMS, topics.SHAPE, topics.STATUS}
        looped = sorted(set(self.sources) & outputs)
        if looped:
            raise ParamError([('relay.source_topic', f'{settings.source_topic!r} gives '
                                                     f'{looped[0]}, a topic of the robots '
                                                     '(the relay would read what it writes, or '
                                                     'the commands): use e.g. '
                                                     "'/robot_{i}/measured_pose'")])
        self.source_type_name = topics.MEASUREMENT_TYPES[settings.source_type.value]
        self.once = OnceLog(self.get_logger())
        self.steady = Clock(clock_type=ClockType.STEADY_TIME)

        self.positions = np.zeros((self.n, 3))
        self.orientations = np.tile([0.0, 0.0, 0.0, 1.0], (self.n, 1))
        self.received_ns = np.full(self.n, NEVER, dtype=np.int64)
        self.stamps_ns: List[Optional[int]] = [None] * self.n
        self.measurements = np.zeros(self.n, dtype=np.int64)
        self.refusals: RefusalLog[int] = RefusalLog(self.once, self._refusal_line)
        """Refused measurements by robot id (1-based) and reason."""
        self.foreign_types: Dict[str, List[str]] = {}
        self.cycles = 0
        self.waiting = False
        """Whether no robot was measured at the last cycle (said once, and once when one is)."""
        self.published_cycles = 0
        self.rate_window = (time.monotonic(), 0)
        self.stale = np.ones(self.n, dtype=bool)

        self.encoder = StateEncoder(self.n, self.dim, self.world_frame)
        message_type = MESSAGE_TYPES[settings.source_type]
        callback = (self.on_odometry if settings.source_type is SourceType.ODOMETRY
                    else self.on_pose)
        self.source_subs = [
            self.create_subscription(message_type, topic,
                                     lambda data, index=i: callback(index, data),
                                     qos.MEASUREMENT, raw=True)
            for i, topic in enumerate(self.sources)]
        self.pose_pubs, self.neighbour_pubs, self.obstacle_pubs = [], [], []
        for i in range(1, self.n + 1):
            if self.obstacles is not None:
                self.obstacle_pubs.append(self.create_publisher(
                    PoseArray, topics.robot_topic(i, topics.OBSTACLES), qos.STATE))
            self.pose_pubs.append(self.create_publisher(
                PoseStamped, topics.robot_topic(i, topics.POSE), qos.STATE))
            self.neighbour_pubs.append(self.create_publisher(
                PoseArray, topics.robot_topic(i, topics.NEIGHBOURS), qos.STATE))
        self.diagnostics_pub = self.create_publisher(
            DiagnosticArray, topics.DIAGNOSTICS, qos.DIAGNOSTICS)
        self.period_ns = max(1, int(round(NS_PER_S / settings.rate)))
        self.due_ns: Optional[int] = None
        """Simulated time the next cycle is due at (on simulated time; None: the first)."""
        if self.sim_time:
            self.clock_moved = Wake(self, self.on_clock, self.steady)
            self.jump_handle = self.get_clock().create_jump_callback(
                JumpThreshold(min_forward=Duration(nanoseconds=1), min_backward=None),
                post_callback=lambda jump: self.clock_moved.arm())
        else:
            self.timer = self.create_timer(1.0 / settings.rate, self.on_cycle,
                                           clock=self.steady)
        self.diagnostics_timer = self.create_timer(PERIOD, self.on_diagnostics,
                                                   clock=self.steady)
        shown = ', '.join(self.sources[:3]) + (', ...' if self.n > 3 else '')
        self.get_logger().info(
            f'relay: {self.n} robots ({config.body.kind.value}s) measured on {shown} '
            f'({self.source_type_name}), publishing pose and neighbors in '
            f"'{self.world_frame}' at {settings.rate:g} Hz, stale after {settings.max_age:g} s"
            + (' (simulated time, /clock)' if self.sim_time else ''))

    def _refusal_line(self, robot: int, reason: Reason, detail: str) -> str:
        """Return the log line of robot ``robot``'s measurements refused for ``reason``."""
        return (f'robot {robot}: ignoring measurements on {self.sources[robot - 1]} with '
                f'{reason.value}: {detail} (logged once; counted in diagnostics)')

    def on_pose(self, index: int, data: bytes) -> None:
        """Store robot ``index``'s measured pose, read from a serialized PoseStamped."""
        self._read(index, data, lambda raw: read_pose_stamped(raw, exact=True))

    def on_odometry(self, index: int, data: bytes) -> None:
        """Store robot ``index``'s measured pose, read from a serialized nav_msgs/Odometry."""
        self._read(index, data, lambda raw: read_odometry(raw, exact=True).pose)

    def _read(self, index: int, data: bytes, reader: Callable[[bytes], PoseData]) -> None:
        """Store what ``reader`` makes of the bytes; refuse (count, log once) what it cannot."""
        try:
            pose = reader(data)
        except CdrError as exc:
            self.refusals.refuse(index + 1, Reason.MALFORMED,
                                 f'{exc}, expected a {self.source_type_name}')
            return
        self._store(index, pose)

    def _store(self, index: int, pose: PoseData) -> None:
        """Keep a measurement that is in world_frame, finite and rotated by a unit quaternion."""
        reason = refusal(pose.frame_id, self.world_frame, pose.finite,
                         bool(valid_quaternions(pose.orientation)))
        if reason is Reason.FRAME:
            self.refusals.refuse(index + 1, reason, f"got frame '{pose.frame_id}', expected "
                                                    f"world_frame '{self.world_frame}'")
        elif reason is Reason.NON_FINITE:
            self.refusals.refuse(index + 1, reason, f'position {pose.position}, orientation '
                                                    f'{pose.orientation}')
        elif reason is Reason.ORIENTATION:
            self.refusals.refuse(index + 1, reason, f'orientation {pose.orientation}')
        elif self._advances(index, pose.stamp_ns):
            self.positions[index] = pose.position
            self.orientations[index] = pose.orientation
            self.received_ns[index] = self.now_ns()
            self.measurements[index] += 1

    def _advances(self, index: int, stamp_ns: int) -> bool:
        """Return whether robot ``index``'s measurement stamped ``stamp_ns`` is a new one."""
        last, self.stamps_ns[index] = self.stamps_ns[index], stamp_ns
        source = self.sources[index]
        if stamp_ns == UNSTAMPED and (not self.sim_time or last == UNSTAMPED):
            self.once.start(f'unstamped-{index}',
                            f'robot {index + 1}: measurements on {source} carry no stamp: '
                            'taken as they arrive (a repeating source would look fresh)')
        elif last is not None and last != UNSTAMPED and stamp_ns <= last:
            if last - stamp_ns <= self.max_age_ns:
                self.stamps_ns[index] = last
                self.refusals.refuse(index + 1, Reason.NOT_NEWER,
                                     f'stamp {stamp_ns / NS_PER_S:.9f} s after '
                                     f'{last / NS_PER_S:.9f} s')
                return False
            self.once.start(f'restarted-{index}',
                            f'robot {index + 1}: stamps on {source} went back by '
                            f'{(last - stamp_ns) / NS_PER_S:.3f} s (a restarted source?): '
                            'taking its measurements from here on')
        return True

    def now_ns(self) -> int:
        """
        Return the time measurements are aged by, ns: the steady clock, or the simulated time.

        In a lab a measurement's age is this host's time since it arrived (a mocap PC's clock
        need not agree); beside a world on ``/clock`` it is simulated time since it arrived, so
        a world running below real time does not age its measurements faster than it moves.
        """
        return self.get_clock().now().nanoseconds if self.sim_time else time.monotonic_ns()

    def on_clock(self) -> None:
        """On simulated time: run a cycle when one is due (every relay period of /clock)."""
        now = self.now_ns()
        due = self.due_ns
        if due is not None and due - self.period_ns <= now < due:
            return
        if due is None or not due <= now < due + self.period_ns:
            due = now
        self.due_ns = due + self.period_ns
        self.on_cycle()

    def on_cycle(self) -> None:
        """Publish the pose and sensor reading of every fresh robot, all with one stamp."""
        self.cycles += 1
        now = self.now_ns()
        measured = self.received_ns != NEVER
        fresh = measured & (now - self.received_ns <= self.max_age_ns)
        self._log_staleness(measured, fresh)
        self.stale = ~fresh
        if not np.any(measured):
            self.waiting = True
            self.once.start('waiting', f'no robot measured yet (robots 1..{self.n} on '
                                       f'{self.sources[0]}, ...): publishing nothing until one '
                                       'is', 'info')
            return
        if self.waiting:
            self.waiting = False
            missing = (np.flatnonzero(~measured) + 1).tolist()
            self.once.end('waiting', f'robots {(np.flatnonzero(measured) + 1).tolist()} '
                                     f'measured: publishing; not measured yet: '
                                     f"{missing or 'none'}")
        stamp_ns = self.get_clock().now().nanoseconds
        poses, arrays = self._encode(np.flatnonzero(measured), stamp_ns)
        told = self._told(stamp_ns)
        for i in np.flatnonzero(fresh).tolist():
            if told:
                self.obstacle_pubs[i].publish(told[i])
            self.pose_pubs[i].publish(poses[i])
            self.neighbour_pubs[i].publish(arrays[i])
        self.published_cycles += 1

    def _encode(self, known: np.ndarray, stamp_ns: int) -> Tuple[List[bytes], List[bytes]]:
        """
        Return every robot's pose and neighbour list at ``stamp_ns`` (``StateEncoder``).

        known: indices of the robots ever measured, the only ones a sensor can see; the others'
        messages are encoded too, but never published.
        """
        q = self.positions[:, :self.dim]
        observer, seen = sensed_pairs(q[known], self.reach[known], cKDTree(q[known]))
        if self.unicycles:
            return self.encoder.encode(q, known[observer], known[seen], stamp_ns,
                                       headings=headings_from_quaternions(self.orientations))
        norms = np.linalg.norm(self.orientations, axis=1)
        return self.encoder.encode(q, known[observer], known[seen], stamp_ns,
                                   orientations=self.orientations / norms[:, None])

    def _told(self, stamp_ns: int) -> List[bytes]:
        """
        Return every robot's obstacles at ``stamp_ns`` from its measured pose, as the plant's.

        The rule is ``told_obstacles``: the obstacles within R_i of the measured position,
        each by its surface point closest to the control point (a unicycle's hand point, from
        the measured heading). Empty without a map.
        """
        if self.obstacles is None:
            return []
        q = self.positions[:, :self.dim]
        points = self.bodies.control_points(q, headings_from_quaternions(self.orientations))
        return encode_obstacles(stamp_ns, self.world_frame,
                                told_obstacles(self.obstacles, q, points, self.radii))

    def _log_staleness(self, measured: np.ndarray, fresh: np.ndarray) -> None:
        """Say once when a measured robot goes stale and once when it is measured again."""
        for i in np.flatnonzero(fresh != ~self.stale).tolist():
            if fresh[i]:
                self.once.end(f'stale-{i}', f'robot {i + 1}: measured again on '
                                            f'{self.sources[i]}: publishing its pose')
            elif measured[i]:
                where = np.round(self.positions[i, :self.dim], 3).tolist()
                self.once.start(f'stale-{i}', f'robot {i + 1}: no new measurement on '
                                              f'{self.sources[i]} for {self.settings.max_age:g}'
                                              ' s: no pose for it (its watchdog stops it); '
                                              'the others keep it in their neighbour lists at '
                                              f'its last position {where}')

    def _check_source_types(self) -> None:
        """Log once each source topic that has publishers of another type than the relay's."""
        for topic in self.sources:
            foreign = sorted({info.topic_type for info in self.get_publishers_info_by_topic(topic)
                              if info.topic_type != self.source_type_name})
            if foreign:
                self.foreign_types[topic] = foreign
                for name in foreign:
                    self.once.start(f'type-{topic}-{name}',
                                    f'topic {topic} has type {name}, relay.source_type expects '
                                    f'{self.source_type_name} (DDS does not connect them: no '
                                    'measurement from that publisher)', 'error')
            else:
                self.foreign_types.pop(topic, None)

    def on_diagnostics(self) -> None:
        """Publish the relay's status: stale robots, refused measurements, cycle rate."""
        self._check_source_types()
        now = time.monotonic()
        since, cycles = self.rate_window
        rate = (self.cycles - cycles) / (now - since) if now > since else 0.0
        self.rate_window = (now, self.cycles)
        measured = self.received_ns != NEVER
        stale = [i + 1 for i in np.flatnonzero(self.stale & measured).tolist()]
        never = [i + 1 for i in np.flatnonzero(~measured).tolist()]
        ages = (self.now_ns() - self.received_ns[measured & ~self.stale]) / NS_PER_S
        values = {'cycle rate achieved [Hz]': rate,
                  'cycle rate target [Hz]': self.settings.rate,
                  'cycles published': self.published_cycles,
                  'max age [s]': self.settings.max_age,
                  'stale robots': ', '.join(map(str, stale)) or 'none',
                  'robots not measured yet': ', '.join(map(str, never)) or 'none',
                  'oldest fresh measurement [s]': float(np.max(ages)) if len(ages) else 'none',
                  'measurements': int(np.sum(self.measurements))}
        for (robot, reason), count in sorted(self.refusals.refusals.items(),
                                             key=lambda item: (item[0][0], item[0][1].name)):
            values[f'robot {robot}: refused measurements ({reason.value})'] = count
        for topic, names in self.foreign_types.items():
            values[f'{topic}: publishers of another type'] = ', '.join(names)
        counts = [sub.get_publisher_count() for sub in self.source_subs]
        values['robots whose source has no publisher'] = ', '.join(
            str(i + 1) for i, count in enumerate(counts) if count == 0) or 'none'
        shared = [i + 1 for i, count in enumerate(counts) if count > 1]
        if shared:
            values['robots whose source has several publishers'] = ', '.join(map(str, shared))
        for robot in shared:
            self.once.start(f'shared-{robot}', f'robot {robot}: {self.sources[robot - 1]} has '
                                               'more than one publisher (two mocap nodes?); '
                                               'the latest measurement of any of them is used')
        values.update(self.team_keys)
        if self.foreign_types:
            level, message = 'error', (f'{len(self.foreign_types)} source topics with '
                                       f'publishers of another type than {self.source_type_name}')
        elif stale or never:
            level, message = 'warn', ', '.join(
                ([f"stale: robots {', '.join(map(str, stale))}"] if stale else [])
                + ([f"not measured yet: robots {', '.join(map(str, never))}"] if never else []))
        else:
            level, message = 'ok', f'relaying {self.n} robots'
        self.diagnostics_pub.publish(diagnostics('formation_ros/relay', level, message, values))


def main(args: Optional[List[str]] = None) -> int:
    """Entry point of ``ros2 run formation_ros relay``."""
    return run(RelayNode, args, name='relay')
