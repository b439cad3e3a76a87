# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
The relay over DDS: measured poses in, every robot's pose and neighbours out, as the plant.

The probe plays the motion-capture system; the neighbour lists are checked against a brute-force
reference of the sensing rule written here (strictly within R_i; R_i + 2 l for unicycles).
"""

import itertools
import math
import os

from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus
from formation_ros.ros import fields, qos
from formation_ros.ros.cdr import encode_odometry
from geometry_msgs.msg import PoseArray, PoseStamped
from helpers import CONFIG, logged, node, write_params
from lab_standin import Base, Lab, steady_s
from nav_msgs.msg import Odometry
import numpy as np
import pytest
from rclpy.clock import Clock, ClockType
from rclpy.qos import QoSProfile, ReliabilityPolicy
from rosgraph_msgs.msg import Clock as ClockMsg
import wire

START_UP = 90.0
NS_PER_S = 1_000_000_000
PENTAGON = [1.5 * v for k in range(5)
            for v in (math.cos(0.4 * math.pi * k), math.sin(0.4 * math.pi * k))]
FIVE = {'num_robots': 5, 'world_frame': 'map', 'formation.vertices': PENTAGON,
        'sensing_radii': [1.0, 1.0, 2.0, 1.0, 1.5], 'repulsion_radius': 0.5}
POSITIONS = np.array([[0.0, 0.0], [0.9, 0.0], [0.0, 1.5], [0.0, -1.0], [1.2, 1.2]])
"""Robot 3 (R = 2) sees robot 1 at 1.5 m, robot 1 (R = 1) does not see it; robot 4 is exactly
R_1 = 1 m from robot 1: not seen (strictly within)."""
RELIABLE = QoSProfile(depth=10, reliability=ReliabilityPolicy.RELIABLE)
WALL = Clock(clock_type=ClockType.SYSTEM_TIME)


def brute_force_lists(q, reach):
    """Robot i's neighbours (0-based, ascending): every j != i with ||q_i - q_j|| < reach_i."""
    n = len(q)
    return [[j for j in range(n) if j != i and math.dist(q[i], q[j]) < reach[i]]
            for i in range(n)]


def unit_quaternions(count, seed):
    rng = np.random.default_rng(seed)
    values = rng.normal(size=(count, 4))
    return values / np.linalg.norm(values, axis=1)[:, None]


class Outputs:
    """Every /robot_<i>/pose and /robot_<i>/neighbors the probe hears, and the relay's status."""

    def __init__(self, probe, count):
        """Subscribe ``probe`` to the outputs of robots 1..count and to /diagnostics."""
        self.poses = {i: [] for i in range(1, count + 1)}
        self.neighbours = {i: [] for i in range(1, count + 1)}
        self.statuses = []
        self.subscriptions = []
        for i in range(1, count + 1):
            self.subscriptions.append(probe.create_subscription(
                PoseStamped, f'/robot_{i}/pose', self.poses[i].append, qos.STATE))
            self.subscriptions.append(probe.create_subscription(
                PoseArray, f'/robot_{i}/neighbors', self.neighbours[i].append, qos.STATE))
        probe.create_subscription(DiagnosticArray, '/diagnostics', self._on_diagnostics,
                                  qos.DIAGNOSTICS)

    def _on_diagnostics(self, array):
        self.statuses += [s for s in array.status if s.name == 'formation_ros/relay']

    def values(self):
        """Return the latest relay status as {key: value} ({} before any)."""
        return {kv.key: kv.value for kv in self.statuses[-1].values} if self.statuses else {}

    def complete_cycles(self, robots):
        """Return the stamps (ns, ascending) at which every robot got pose and neighbours."""
        stamps = None
        for i in robots:
            mine = ({fields.stamp_to_ns(m.header.stamp) for m in self.poses[i]}
                    & {fields.stamp_to_ns(m.header.stamp) for m in self.neighbours[i]})
            stamps = mine if stamps is None else stamps & mine
        return sorted(stamps or ())

    def at(self, kind, robot, stamp_ns):
        heard = self.poses if kind == 'pose' else self.neighbours
        return [m for m in heard[robot] if fields.stamp_to_ns(m.header.stamp) == stamp_ns][-1]


def positions_of(array):
    return [(p.position.x, p.position.y) for p in array.poses]


def orientation_of(pose):
    o = pose.orientation
    return (o.x, o.y, o.z, o.w)


def check_cycle(outputs, stamp, q, reach, frame):
    """Every robot's pose and neighbour list at ``stamp``: the measured positions, brute force."""
    expected = brute_force_lists(q, reach)
    assert any(0 < len(mine) < len(q) - 1 for mine in expected)
    for i in range(1, len(q) + 1):
        pose = outputs.at('pose', i, stamp)
        array = outputs.at('neighbours', i, stamp)
        assert pose.header.frame_id == array.header.frame_id == frame
        assert (pose.pose.position.x, pose.pose.position.y) == tuple(q[i - 1])
        assert positions_of(array) == [tuple(q[j]) for j in expected[i - 1]], (i, expected)


def test_relay_publishes_every_pose_and_the_brute_force_neighbours_with_one_stamp(
        processes, install, probe, tmp_path):
    """Points, PoseStamped sources in 'map': robots 1-2 best effort, 3-5 reliable publishers."""
    params = write_params(tmp_path, 'square_4.yaml', FIVE)
    outputs = Outputs(probe, 5)
    processes.start(node(install, 'relay', params))
    assert probe.spin_until(lambda: outputs.values().get('cycles published') == '0', START_UP), \
        processes.log('relay')
    assert not any(outputs.poses.values()) and not any(outputs.neighbours.values())
    assert logged(probe, processes, 'relay', 'no robot measured yet').count(
        'no robot measured yet') == 1
    publishers = [probe.create_publisher(PoseStamped, f'/robot_{i}/measured_pose',
                                         qos.STATE if i <= 2 else RELIABLE)
                  for i in range(1, 6)]
    turned = unit_quaternions(5, 1)
    stamps = itertools.count(17)

    def measure():
        stamp = next(stamps)
        for i, publisher in enumerate(publishers):
            publisher.publish(wire.pose_stamped_bytes(stamp, 'map', POSITIONS[i], turned[i]))
        return len(outputs.complete_cycles(range(1, 6))) >= 3

    assert probe.spin_until(measure, START_UP), processes.log('relay')
    stamps = outputs.complete_cycles(range(1, 6))
    assert abs(stamps[-1] - WALL.now().nanoseconds) < 5 * NS_PER_S, 'not wall-clock time'
    for stamp in stamps:
        check_cycle(outputs, stamp, POSITIONS, FIVE['sensing_radii'], 'map')
        for i in range(1, 6):
            got = orientation_of(outputs.at('pose', i, stamp).pose)
            assert np.allclose(got, turned[i - 1], rtol=0, atol=1e-12)
    log = processes.log('relay')
    assert log.count('measured: publishing') == 1 and 'Traceback' not in log


def test_relay_reads_odometry_by_name_and_lists_unicycles_within_r_plus_2l(
        processes, install, probe, tmp_path):
    """Unicycles from nav_msgs/Odometry on /mocap/{name}/odom; headings as pure yaw."""
    hand = 0.2
    params = write_params(tmp_path, 'square_4.yaml', {
        **FIVE, 'body.kind': 'unicycle', 'body.hand_distance': hand,
        'relay.source_topic': '/mocap/{name}/odom', 'relay.source_type': 'odometry',
        'relay.source_names': ['ann', 'bo', 'cy', 'di', 'ed']})
    outputs = Outputs(probe, 5)
    processes.start(node(install, 'relay', params))
    names = ['ann', 'bo', 'cy', 'di', 'ed']
    publishers = [probe.create_publisher(Odometry, f'/mocap/{name}/odom', RELIABLE)
                  for name in names]
    q = POSITIONS + np.array([[0.0, 0.0], [0.35, 0.0], [0.0, 0.0], [0.0, -0.3], [0.0, 0.0]])
    headings = np.array([0.3, -2.0, 1.0, 2.9, -0.7])
    tilt = 0.05
    quaternions = [(math.sin(tilt / 2) * math.cos(h / 2), math.sin(tilt / 2) * math.sin(h / 2),
                    math.cos(tilt / 2) * math.sin(h / 2), math.cos(tilt / 2) * math.cos(h / 2))
                   for h in headings]
    """A rotation about z by th after a small roll about x: yaw th, not a pure z rotation."""
    stamps = itertools.count(5)

    def measure():
        stamp = next(stamps)
        for i, publisher in enumerate(publishers):
            publisher.publish(encode_odometry(stamp, 'map', names[i], q[i], quaternions[i],
                                              (0.0, 0.0, 0.0), (0.0, 0.0, 0.0)))
        return bool(outputs.complete_cycles(range(1, 6)))

    assert probe.spin_until(measure, START_UP), processes.log('relay')
    stamp = outputs.complete_cycles(range(1, 6))[-1]
    reach = [r + 2 * hand for r in FIVE['sensing_radii']]
    assert brute_force_lists(q, reach) != brute_force_lists(q, FIVE['sensing_radii'])
    check_cycle(outputs, stamp, q, reach, 'map')
    for i in range(1, 6):
        x, y, z, w = orientation_of(outputs.at('pose', i, stamp).pose)
        assert x == y == 0.0
        assert abs(math.remainder(2 * math.atan2(z, w) - headings[i - 1], 2 * math.pi)) < 1e-12
        for listed in outputs.at('neighbours', i, stamp).poses:
            assert listed.orientation.x == listed.orientation.y == 0.0


STATUS_KEY = 'robot {robot}: refused measurements ({reason})'
REFUSALS = {
    2: ('a frame other than world_frame', "got frame 'world', expected world_frame 'map'"),
    3: ('non-finite values', 'non-finite values: position'),
    4: ('bytes that are not a whole message of its type', 'expected a '
                                                          'geometry_msgs/msg/PoseStamped'),
    5: ('an orientation that is not a unit quaternion', 'orientation (0.0, 0.0, 0.0, 0.0)'),
}


def test_refused_measurements_are_counted_logged_once_and_never_published(
        processes, install, probe, tmp_path):
    """Wrong frame, non-finite, Odometry bytes, zero quaternion; a publisher of another type."""
    params = write_params(tmp_path, 'square_4.yaml', {**FIVE, 'num_robots': 6,
                                                      'sensing_radii': [5.0] * 6,
                                                      'formation.vertices': [
                                                          1.5 * v for k in range(6)
                                                          for v in (math.cos(math.pi * k / 3),
                                                                    math.sin(math.pi * k / 3))]})
    outputs = Outputs(probe, 6)
    processes.start(node(install, 'relay', params))
    pubs = {i: probe.create_publisher(PoseStamped, f'/robot_{i}/measured_pose', RELIABLE)
            for i in range(1, 6)}
    probe.create_publisher(Odometry, '/robot_6/measured_pose', RELIABLE)
    near = np.array([0.5, 0.0])
    forged = {
        1: wire.pose_stamped_bytes(3, 'map', (0.0, 0.0)),
        2: wire.pose_stamped_bytes(3, 'world', near),
        3: wire.pose_stamped_bytes(3, 'map', (math.nan, 0.0)),
        4: encode_odometry(3, 'map', 'base', (0.5, 0.0, 0.0), (0.0, 0.0, 0.0, 1.0),
                           (0.0, 0.0, 0.0), (0.0, 0.0, 0.0)),
        5: wire.pose_stamped_bytes(3, 'map', near, (0.0, 0.0, 0.0, 0.0)),
    }
    sent = []

    def counted():
        forged[1] = wire.pose_stamped_bytes(3 + len(sent), 'map', (0.0, 0.0))
        for i, publisher in pubs.items():
            publisher.publish(forged[i])
        sent.append(1)
        values = outputs.values()
        return (len(sent) > 50 and all(
            int(values.get(STATUS_KEY.format(robot=robot, reason=reason), 0)) > 10
            for robot, (reason, _) in REFUSALS.items())
            and 'type nav_msgs/msg/Odometry' in processes.log('relay'))

    assert probe.spin_until(counted, START_UP), (outputs.values(), processes.log('relay'))
    log = processes.log('relay')
    for robot, (_, detail) in REFUSALS.items():
        topic = f'/robot_{robot}/measured_pose'
        lines = [line for line in log.splitlines() if f'ignoring measurements on {topic} ' in line]
        assert len(lines) == 1 and detail in lines[0], (robot, lines)
    assert log.count('topic /robot_6/measured_pose has type nav_msgs/msg/Odometry, '
                     'relay.source_type expects geometry_msgs/msg/PoseStamped') == 1, log
    assert outputs.poses[1] and all(not outputs.poses[i] for i in range(2, 7))
    assert all(not outputs.neighbours[i] for i in range(2, 7))
    assert all(not array.poses for array in outputs.neighbours[1])
    values = outputs.values()
    assert values['robots not measured yet'] == '2, 3, 4, 5, 6'
    assert values['/robot_6/measured_pose: publishers of another type'] == \
        'nav_msgs/msg/Odometry'
    assert outputs.statuses[-1].level == DiagnosticStatus.ERROR
    assert 'Traceback' not in log


def test_a_frozen_source_goes_stale_an_unstamped_one_is_taken_a_restarted_one_resumes(
        processes, install, probe, tmp_path):
    """
    A frozen source goes stale; an unstamped one and one whose stamps jump back do not.

    Robot 1's stamps advance (and later jump 100 s back), robot 2's stay at one value (a driver
    repeating a lost body's pose), robot 3's are 0 (no stamps).
    """
    max_age = 0.3
    triangle = [1.0, 0.0, -0.5, 0.866, -0.5, -0.866]
    params = write_params(tmp_path, 'square_4.yaml', {
        'num_robots': 3, 'world_frame': 'map', 'formation.vertices': triangle,
        'sensing_radii': [5.0] * 3, 'relay.max_age': max_age})
    outputs = Outputs(probe, 3)
    processes.start(node(install, 'relay', params))
    publishers = {i: probe.create_publisher(PoseStamped, f'/robot_{i}/measured_pose', RELIABLE)
                  for i in range(1, 4)}
    reason = 'a stamp no later than the last one taken (a repeated or reordered measurement)'
    key = STATUS_KEY.format(robot=2, reason=reason)
    ticks = itertools.count()
    back = {'by': 0}

    def measure():
        tick = next(ticks)
        stamps = {1: 1000 * NS_PER_S + tick * 1_000_000 - back['by'], 2: 500 * NS_PER_S, 3: 0}
        for i, publisher in publishers.items():
            publisher.publish(wire.pose_stamped_bytes(stamps[i], 'map', POSITIONS[i - 1]))
        values = outputs.values()
        return (values.get('stale robots') == '2' and int(values.get(key, 0)) > 10
                and len(outputs.poses[1]) > 20 and len(outputs.poses[3]) > 20)

    assert probe.spin_until(measure, START_UP), (outputs.values(), processes.log('relay'))
    seen = {i: len(outputs.poses[i]) for i in range(1, 4)}
    back['by'] = 100 * NS_PER_S
    assert probe.spin_until(lambda: measure() and len(outputs.poses[1]) > seen[1] + 20,
                            START_UP), (outputs.values(), processes.log('relay'))
    values = outputs.values()
    assert not [k for k in values if k.startswith('robot 1: refused')], values
    assert not [k for k in values if k.startswith('robot 3: refused')], values
    assert outputs.statuses[-1].level == DiagnosticStatus.WARN
    said = ('robot 2: ignoring measurements on /robot_2/measured_pose with a stamp no later '
            'than the last one taken',
            'robot 3: measurements on /robot_3/measured_pose carry no stamp',
            'robot 1: stamps on /robot_1/measured_pose went back by',
            'robot 2: no new measurement on /robot_2/measured_pose')
    log = logged(probe, processes, 'relay', *said)
    for line in said:
        assert log.count(line) == 1, (line, log)
    assert 'Traceback' not in log


def test_relay_refuses_a_source_that_is_its_own_output(install, processes, probe, tmp_path):
    params = write_params(tmp_path, 'square_4.yaml', {'relay.source_topic': '/robot_{i}/pose'})
    processes.start(node(install, 'relay', params, process='looped'))
    assert probe.spin_until(lambda: not processes.running('looped'), START_UP)
    info = processes.exit_info('looped')
    assert info.returncode == 2, processes.log('looped')
    log = processes.log('looped')
    assert "parameter 'relay.source_topic'" in log and 'Traceback' not in log


SLOW_WORLD = 0.25
"""Simulated seconds per wall-clock second of the probe's world (below real time)."""
TICK_NS = 10_000_000
"""The probe world's /clock and measured poses: every 10 ms of simulated time."""


def test_relay_on_a_worlds_clock_stamps_and_ages_in_simulated_time(
        install, processes, probe, tmp_path):
    """
    A world at a quarter of real time: /clock and measured poses every 10 ms simulated.

    The relay (use_sim_time) publishes a cycle every 20 ms of simulated time (relay.rate 50
    Hz; a cycle late by a tick the probe's world missed, the next one on time), stamped with
    it; robot 2, no longer measured, is stale only after relay.max_age of
    simulated time (0.2 s: 0.8 s of wall-clock time here), not of wall-clock time.
    """
    params = write_params(tmp_path, 'square_4.yaml', {})
    outputs = Outputs(probe, 4)
    processes.start(node(install, 'relay', params, '-p', 'use_sim_time:=true'))
    clock = probe.create_publisher(ClockMsg, '/clock', qos.CLOCK)
    sources = [probe.create_publisher(PoseStamped, f'/robot_{i}/measured_pose', qos.MEASUREMENT)
               for i in range(1, 5)]
    world = {'began': None, 'ns': -1, 'measured': {1, 2, 3, 4}, 'last_2': None}

    def step():
        now = steady_s()
        if world['began'] is None:
            world['began'] = now
        t_ns = int((now - world['began']) * SLOW_WORLD * NS_PER_S) // TICK_NS * TICK_NS
        if t_ns == world['ns']:
            return
        world['ns'] = t_ns
        message = ClockMsg()
        message.clock.sec, message.clock.nanosec = divmod(t_ns, NS_PER_S)
        clock.publish(message)
        for i in world['measured']:
            sources[i - 1].publish(wire.pose_stamped_bytes(t_ns, 'world', POSITIONS[i - 1]))
        if 2 in world['measured']:
            world['last_2'] = t_ns

    def cycles(count):
        step()
        return len(outputs.poses[1]) >= count

    assert probe.spin_until(lambda: cycles(20), START_UP), processes.log('relay')
    stamps = [fields.stamp_to_ns(m.header.stamp) for m in outputs.poses[1]]
    assert stamps[-1] <= world['ns'] < 5 * NS_PER_S, 'stamped with the simulated time'
    gaps = np.diff(stamps)
    assert np.all(gaps >= TICK_NS) and np.median(gaps) == 20_000_000, gaps
    assert 19e6 <= np.mean(gaps) <= 25e6, gaps
    world['measured'].discard(2)
    assert probe.spin_until(lambda: step() or world['ns'] > world['last_2'] + 150_000_000, 30)
    fresh = fields.stamp_to_ns(outputs.poses[2][-1].header.stamp)
    assert fresh >= world['last_2'] + 100_000_000, 'stale after 0.2 s simulated, not wall'
    assert probe.spin_until(lambda: step() or world['ns'] > world['last_2'] + 400_000_000, 30)
    last = fields.stamp_to_ns(outputs.poses[2][-1].header.stamp)
    assert last <= world['last_2'] + 200_000_000 + TICK_NS, (last, world['last_2'])
    assert fields.stamp_to_ns(outputs.poses[1][-1].header.stamp) > world['last_2'] + 3e8
    assert 'simulated time, /clock' in processes.log('relay')


def test_mocap_dropout_stops_one_robot_and_the_others_keep_it_in_their_lists(
        processes, install, probe, tmp_path):
    """
    Relay + four robots + reference on wall-clock time in 'map'; the probe plays mocap, bodies.

    Robot 3 is not measured for 2 s: its watchdog stops it, the others' neighbour lists keep
    it at its last measured position, the relay's diagnostics name it (WARN); once measured
    again it moves and the WARN clears.
    """
    max_age, timeout = 0.4, 0.5
    params = write_params(tmp_path, 'square_4.yaml', {
        'sensing_radius': 3.0, 'controller.gain': 0.5, 'relay.max_age': max_age,
        'relay.rate': 30.0, 'input_timeout': timeout, 'world_frame': 'map'})
    outputs = Outputs(probe, 4)
    lab = Lab(q=[[0.3, 0.2], [-0.2, 0.4], [-0.3, -0.3], [0.4, -0.2]], heading=np.zeros(4),
              base=Base.WORLD, command_topic='/robot_{i}/cmd_vel',
              mocap_topic='/robot_{i}/measured_pose', frame='map', rate=50.0)
    lab.attach(probe)
    processes.start(node(install, 'relay', params))
    processes.start(node(install, 'reference', params))
    for i in range(1, 5):
        processes.start(node(install, 'robot', params, '-r', f'__ns:=/robot_{i}',
                             process=f'robot_{i}'))

    def moving(robot, since):
        return any(any(c) for t, i, c in lab.heard if i == robot and t > since)

    def commands_of(robot, since):
        return [(t, c) for t, i, c in lab.heard if i == robot and t > since]

    assert probe.spin_until(lambda: all(moving(i, 0.0) for i in range(1, 5)), START_UP), \
        processes.log('robot_3') + processes.log('relay')
    lab.hidden.add(2)
    dropped_at, last_position = lab.measured[2]
    dropped_wall = WALL.now().nanoseconds

    def stale():
        zero = [t for t, c in commands_of(3, dropped_at) if not any(c)]
        status = outputs.statuses[-1] if outputs.statuses else None
        return (bool(zero) and status is not None and status.level == DiagnosticStatus.WARN
                and outputs.values()['stale robots'] == '3')

    assert probe.spin_until(stale, 30), (outputs.values(), processes.log('relay'))
    assert probe.spin_until(lambda: steady_s() - dropped_at >= 2.0, 10)
    resumed_wall = WALL.now().nanoseconds
    first_zero = min(t for t, c in commands_of(3, dropped_at) if not any(c))
    print(f'robot 3 commanded zero {first_zero - dropped_at:.3f} s after its last measurement '
          f'(relay.max_age {max_age} s + input_timeout {timeout} s)')
    assert all(not any(c) for t, c in commands_of(3, first_zero))
    window = (dropped_wall + int((max_age + 0.1) * NS_PER_S), resumed_wall)
    during = {j: [a for a in outputs.neighbours[j]
                  if window[0] < fields.stamp_to_ns(a.header.stamp) < window[1]]
              for j in (1, 2, 4)}
    assert all(len(arrays) >= 10 for arrays in during.values()), \
        {j: len(a) for j, a in during.items()}
    assert all(last_position in positions_of(a) for arrays in during.values() for a in arrays)
    assert not [p for p in outputs.poses[3]
                if window[0] < fields.stamp_to_ns(p.header.stamp) < window[1]]
    assert not [a for a in outputs.neighbours[3]
                if window[0] < fields.stamp_to_ns(a.header.stamp) < window[1]]
    lab.hidden.clear()
    resumed = steady_s()

    def back():
        status = outputs.statuses[-1]
        return (moving(3, resumed) and status.level == DiagnosticStatus.OK
                and outputs.values()['stale robots'] == 'none')

    assert probe.spin_until(back, 30), (outputs.values(), processes.log('relay'))
    log = processes.log('relay')
    stalls = lab.stalls(max_age / 2)
    said = ['stale' if 'robot 3: no new measurement' in line else 'again'
            for line in log.splitlines() if 'robot 3: ' in line]
    assert said == ['stale', 'again'] * (len(said) // 2), log
    assert 1 <= len(said) // 2 <= 1 + stalls, (stalls, log)
    for i in (1, 2, 4):
        assert log.count(f'robot {i}: no new measurement') <= stalls, (stalls, log)


@pytest.mark.parametrize('name, first_source', [('lab_turtlebot3.yaml', '/vrpn_mocap/tb1/pose'),
                                                ('lab_holonomic.yaml', '/base1/pose')])
def test_the_shipped_lab_files_start_the_relay_as_its_docstring_says(processes, install, probe,
                                                                     name, first_source):
    """``relay --ros-args --params-file config/<lab>.yaml``: it waits for its mocap sources."""
    outputs = Outputs(probe, 4)
    processes.start(node(install, 'relay', os.path.join(CONFIG, name)))
    assert probe.spin_until(lambda: outputs.values().get('robots whose source has no publisher')
                            == '1, 2, 3, 4', START_UP), processes.log('relay')
    log = processes.log('relay')
    assert f'measured on {first_source}' in log and "in 'world'" in log, log
    assert outputs.statuses[-1].level == DiagnosticStatus.WARN
    assert processes.running('relay')
