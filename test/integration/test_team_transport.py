# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
The team transport (``transport: team``) over real DDS: one state message, one per fleet back.

Lockstep gives the robot transport's trajectory (and formation_sim's: unicycles, points that
take body-frame commands); free-running, the team converges, a robot's own ``cmd_vel`` carries
what its team message carries while someone listens (and only then), untrusted team command
bytes are counted and dropped, a dead robot process is reported and its body held still, and a
reference node whose samples are not the frame the robots evaluate is refused, loudly.
"""

import signal
import time

from diagnostic_msgs.msg import DiagnosticArray
from formation_ros.core.runs.trajectory import Trajectory
from formation_ros.core.settings.params import load_config
from formation_ros.ros import fields, qos
from formation_ros.ros.cdr import encode_header, encode_names, encode_team_commands
from formation_ros.simulation.simulate import simulate
from geometry_msgs.msg import PoseArray, PoseStamped, TwistStamped
from helpers import (launch, logged, node, said_once, SimClock, start_system, START_UP,
                     Statuses, stop_when, write_params)
import numpy as np
import pytest
from trajectory_msgs.msg import MultiDOFJointTrajectory

UNTIL = 2.0
"""Simulated seconds of each lockstep run (200 steps)."""
SWITCH = 1.0
"""When the lockstep runs switch to the wedge (formation.schedule), s."""
WEDGE = [0.0, 1.5, -1.5, 0.0, 1.5, 0.0, 0.0, -1.5]
NOTICE_WITHIN = 10.0
"""Bound (s) on kill -> the plant's status: lease 1 s + diagnostics period 1 s + a busy machine."""


def distances(points):
    """Return the pairwise distances of each row of points (T, N, dim): (T, N, N)."""
    return np.linalg.norm(points[:, :, None, :] - points[:, None, :, :], axis=-1)


def robot_subscribers(probe, topic):
    """Return the namespaces of the robot nodes that subscribe to ``topic``, sorted."""
    return sorted(info.node_namespace for info in probe.get_subscriptions_info_by_topic(topic)
                  if info.node_namespace.startswith('/robot_'))


def lockstep_run(processes, probe, install, tmp_path, transport):
    """
    Run square_4 on a moving reference in lockstep, two robots a fleet; return its trajectory.

    The shape switches to a wedge at SWITCH. With the team transport, run until every robot
    (the second of each fleet too) reports 'lockstep' with its neighbours in /diagnostics, and
    check (either transport) that only the first of each fleet subscribes to the reference and
    the changes, and no robot to /clock.
    """
    out = tmp_path / transport
    params = write_params(tmp_path, 'square_4.yaml', {
        'plant.lockstep': True, 'plant.realtime_factor': 200.0, 'transport': transport,
        'reference.kind': 'circle', 'reference.radius': 1.0, 'reference.speed': 0.5,
        'formations.names': ['wedge'], 'formations.wedge.vertices': WEDGE,
        'formation.schedule.times': [SWITCH], 'formation.schedule.names': ['wedge'],
        'plant.output_dir': str(out)}, name=f'{transport}.yaml')
    clock = SimClock(probe)
    statuses = {}
    diagnostics = probe.create_subscription(DiagnosticArray, '/diagnostics', lambda message: (
        statuses.update({status.name: (status.message,
                                       {pair.key: pair.value for pair in status.values})
                         for status in message.status})), qos.DIAGNOSTICS)
    robots = [f'formation_ros/robot_{i}' for i in range(1, 5)]

    def every_robot_reports():
        return transport == 'robot' or all(statuses.get(name, ('',))[0] == 'lockstep'
                                           for name in robots)

    launch(processes, install, params, name=transport, options=('--robots-per-process', '2'))
    leaders = ['/robot_1', '/robot_3']
    shared = ('/formation/reference', '/formation/shape', '/formation/status')

    def leaders_subscribe():
        # the graph shows each subscription when its announcement arrives, in any order
        return all(robot_subscribers(probe, topic) == leaders for topic in shared)

    assert probe.spin_until(lambda: every_robot_reports() and leaders_subscribe(), START_UP), (
        statuses, {topic: robot_subscribers(probe, topic) for topic in shared},
        processes.log(transport))
    assert robot_subscribers(probe, '/clock') == []
    try:
        info = stop_when(probe, processes,
                         lambda: clock.seconds >= UNTIL and every_robot_reports(), name=transport)
    except AssertionError as exc:
        raise AssertionError(f'{exc}\nsimulated time {clock.seconds} s; last statuses of '
                             f'the robots: {statuses}') from None
    probe.destroy_subscription(clock.subscription)
    probe.destroy_subscription(diagnostics)
    assert info.returncode == 0, processes.log(transport)
    assert transport == 'robot' or all('neighbours within R_i' in statuses[name][1]
                                       for name in robots), statuses
    return Trajectory.load(str(out / 'trajectory.npz'))


def test_team_and_robot_transports_give_one_trajectory_in_lockstep(processes, install, probe,
                                                                   tmp_path):
    robot = lockstep_run(processes, probe, install, tmp_path, 'robot')
    team = lockstep_run(processes, probe, install, tmp_path, 'team')
    assert '[fleet_2] ' in processes.log('team') and 'team transport' in processes.log('team')
    assert 'team transport' not in processes.log('robot')
    steps = min(len(robot.t), len(team.t))
    assert steps >= 100 * UNTIL
    assert np.array_equal(robot.t[:steps], team.t[:steps])
    assert np.max(np.abs(robot.q[:steps] - team.q[:steps])) < 1e-12
    assert np.max(np.abs(robot.u[:steps] - team.u[:steps])) < 1e-12
    assert np.ptp(team.q[:steps], axis=0).max() > 0.5
    switched = team.t[:steps] >= SWITCH - 1e-9
    assert 0 < np.count_nonzero(switched) < steps
    square = load_config(str(tmp_path / 'team.yaml')).vertices
    for rows, shape in ((~switched, square), (switched, np.reshape(WEDGE, (4, 2)))):
        assert np.allclose(distances(team.q_desired[:steps][rows]), distances(shape[None]))


@pytest.mark.parametrize('source, changes', [
    ('unicycle_2d.yaml', {}),
    ('square_4.yaml', {'command.frame': 'body', 'start.headings': [0.5, 2.0, -1.0, 3.0]})],
    ids=['unicycles', 'body-frame points'])
def test_bodies_of_the_team_transport_in_lockstep_are_formation_sims(
        processes, install, probe, tmp_path, source, changes):
    out = tmp_path / 'run'
    params = write_params(tmp_path, source, {
        'plant.lockstep': True, 'plant.realtime_factor': 200.0, 'transport': 'team',
        'plant.output_dir': str(out), **changes})
    clock = SimClock(probe)
    launch(processes, install, params, options=('--robots-per-process', '4'))
    info = stop_when(probe, processes, lambda: clock.seconds >= UNTIL)
    assert info.returncode == 0, processes.log('launcher')
    plant = Trajectory.load(str(out / 'trajectory.npz'))
    assert len(plant.t) >= 100 * UNTIL
    sim = simulate(load_config(params), duration=plant.t[-1], dt=0.01, sample_dt=0.01)
    assert np.max(np.abs(sim.q - plant.q)) < 1e-9
    assert np.max(np.abs(sim.u - plant.u)) < 1e-9
    if plant.heading is not None:
        assert np.max(np.abs(sim.heading - plant.heading)) < 1e-9
        assert np.max(np.abs(sim.body_command - plant.body_command)) < 1e-9
    assert (plant.heading is not None) == (source == 'unicycle_2d.yaml')
    assert np.max(np.abs(plant.u)) > 0.05


class Heard:
    """What the probe hears: team states and commands, robot 2's cmd_vel, the plant's status."""

    def __init__(self, probe):
        """Subscribe ``probe`` to the team topics, /robot_2/cmd_vel and /diagnostics."""
        self.states, self.team, self.own, self.status = [], {}, {}, []
        probe.create_subscription(PoseArray, '/formation/states', self.states.append,
                                  qos.STATE_INPUT)
        probe.create_subscription(MultiDOFJointTrajectory, '/formation/commands',
                                  self._on_team, qos.COMMAND)
        # as ros2 topic echo does: asking for no lease (a team robot's cmd_vel offers none)
        self.cmd_vel = probe.create_subscription(TwistStamped, '/robot_2/cmd_vel', self._on_own,
                                                 qos.TEAM_CMD_VEL)
        probe.create_subscription(DiagnosticArray, '/diagnostics', self._on_diagnostics,
                                  qos.DIAGNOSTICS)

    def _on_team(self, message):
        if list(message.joint_names) == ['robot_2']:
            twist = message.points[0].velocities[0]
            stamp = fields.stamp_to_ns(message.header.stamp)
            self.team[stamp] = (twist.linear.x, twist.linear.y)

    def _on_own(self, message):
        twist = message.twist
        self.own[fields.stamp_to_ns(message.header.stamp)] = (twist.linear.x, twist.linear.y)

    def _on_diagnostics(self, message):
        self.status.extend((time.monotonic(), status.name,
                            {pair.key: pair.value for pair in status.values})
                           for status in message.status)

    def common(self):
        """Return the stamps at which robot 2 answered on both topics."""
        return sorted(set(self.team) & set(self.own))

    def plant_value(self, key, since=0.0, name='formation_ros/plant'):
        """Return the latest value of ``key`` in the plant's status since ``since`` (or None)."""
        found = [values[key] for at, who, values in self.status
                 if who == name and at >= since and key in values]
        return found[-1] if found else None

    def poses(self, robot):
        """Return (stamp in ns, position) of robot ``robot`` (1-based) in every state heard."""
        return [(fields.stamp_to_ns(state.header.stamp),
                 (state.poses[robot - 1].position.x, state.poses[robot - 1].position.y))
                for state in self.states]


def test_a_free_running_team_converges_and_shows_its_commands_per_robot(processes, install,
                                                                        probe, tmp_path):
    params = write_params(tmp_path, 'square_4.yaml', {'transport': 'team'})
    heard = Heard(probe)
    clock = SimClock(probe)
    start_system(processes, install, params, 4)
    assert probe.spin_until(lambda: clock.seconds >= 5.0 and len(heard.common()) >= 50,
                            START_UP), processes.log('plant') + processes.log('robot_2')
    vertices = load_config(params).vertices
    final = heard.states[-1]
    error = max(np.hypot(pose.position.x - x, pose.position.y - y)
                for pose, (x, y) in zip(final.poses, vertices))
    assert len(final.poses) == 4 and error < 0.05, error
    common = heard.common()
    assert [heard.own[stamp] for stamp in common] == [heard.team[stamp] for stamp in common]
    assert max(max(abs(v) for v in heard.team[stamp]) for stamp in common) > 0.0
    assert heard.plant_value('robots with pose and neighbors published') == 'none'
    assert heard.plant_value('cmd_vel published', name='formation_ros/robot_2') == 'yes'
    assert heard.plant_value('cmd_vel published', name='formation_ros/robot_1') == 'no'

    own_poses, own_neighbours = {}, {}
    probe.create_subscription(PoseStamped, '/robot_3/pose', lambda message: own_poses.update(
        {fields.stamp_to_ns(message.header.stamp): message.pose.position}), qos.STATE_INPUT)
    probe.create_subscription(PoseArray, '/robot_3/neighbors', lambda message: (
        own_neighbours.update({fields.stamp_to_ns(message.header.stamp): message.poses})),
        qos.STATE_INPUT)
    assert probe.spin_until(
        lambda: (heard.plant_value('robots with pose and neighbors published') == '3'
                 and len(set(own_poses) & set(own_neighbours)) >= 10), NOTICE_WITHIN), \
        heard.plant_value('robots with pose and neighbors published')
    states = {fields.stamp_to_ns(state.header.stamp): state for state in heard.states}
    radius = load_config(params).sensing_radii[2]
    compared = 0
    for stamp in sorted(set(own_poses) & set(own_neighbours) & set(states)):
        team = np.array([(pose.position.x, pose.position.y) for pose in states[stamp].poses])
        position = own_poses[stamp]
        assert (position.x, position.y) == tuple(team[2])
        near = sorted(tuple(row) for k, row in enumerate(team)
                      if k != 2 and np.hypot(*(row - team[2])) < radius)
        assert sorted((pose.position.x, pose.position.y)
                      for pose in own_neighbours[stamp]) == near
        compared += 1
    assert compared >= 5

    publisher = probe.create_publisher(MultiDOFJointTrajectory, '/formation/commands',
                                       qos.COMMAND)
    oversized = encode_team_commands(0, 'world', encode_names(
        [f'robot_{i}' for i in range(1, 6)]), np.zeros((5, 3)), np.zeros((5, 3)))
    bad = [encode_header(0, 'world') + b'\x07' * 9, oversized, b'\x00\x01\x00\x00']
    assert probe.spin_until(lambda: publisher.get_subscription_count() >= 1, 30)

    def malformed():
        return int(heard.plant_value('malformed team command messages') or 0)

    # The probe's writer can match the plant's reader before the reader has matched it:
    # what is sent in between is lost, so the bad messages go again until they are counted.
    for _ in range(5):
        for data in bad:
            publisher.publish(data)
        if probe.spin_until(lambda: malformed() >= len(bad), NOTICE_WITHIN / 2):
            break
    assert malformed() >= len(bad), malformed()
    log = logged(probe, processes, 'plant', 'ignoring /formation/commands bytes')
    assert log.count('ignoring /formation/commands bytes') == 1, log
    assert heard.plant_value('robots with alive cmd_vel') == '1, 2, 3, 4'

    processes.send_signal('robot_4', signal.SIGKILL)
    killed = time.monotonic()
    assert probe.spin_until(
        lambda: heard.plant_value('robots with lost cmd_vel', killed) == '4', NOTICE_WITHIN), \
        heard.plant_value('robots with lost cmd_vel')
    assert heard.plant_value('robots with alive cmd_vel', killed) == '1, 2, 3'
    reported = len(heard.states)
    assert probe.spin_until(lambda: len(heard.states) > reported + 25, 30)
    still = heard.poses(4)[reported:]
    assert still[-1][0] > still[0][0] and len({position for _, position in still}) == 1, still
    assert '4' in (heard.plant_value('robots with stale commands') or ''), heard.status[-1]


@pytest.mark.parametrize('transport', ['team', 'robot'])
def test_a_robot_on_sim_time_refuses_a_reference_other_than_it_evaluates(
        processes, install, probe, tmp_path, transport):
    circle = {'transport': transport, 'reference.kind': 'circle', 'reference.speed': 0.5}
    params = write_params(tmp_path, 'square_4.yaml', {**circle, 'reference.radius': 1.0})
    other = write_params(tmp_path, 'square_4.yaml', {**circle, 'reference.radius': 2.0},
                         name='other.yaml')
    statuses = Statuses(probe)
    processes.start(node(install, 'plant', params))
    processes.start(node(install, 'reference', other, '-p', 'use_sim_time:=true'))
    processes.start(node(install, 'robot', params, '-r', '__ns:=/robot_1', '-p', 'robot_id:=1',
                         '-p', 'use_sim_time:=true', process='robot_1'))
    text = 'ignoring reference messages with a frame other than the one its reference'
    assert said_once(probe, processes, 'robot_1', text, statuses,
                     'formation_ros/robot_1') == 1
    values = {pair.key: pair.value for pair in statuses['formation_ros/robot_1'].values}
    assert int(values['rejected reference messages (a frame other than the one its reference '
                      'parameters and the announced changes give)']) > 1, values
    assert values['reference message age [s]'] == 'never'
    assert statuses['formation_ros/robot_1'].message == 'waiting for its first inputs'
