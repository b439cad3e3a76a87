# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
Formations that change while they run, over real DDS and the parameter and Trigger services.

Shapes are set as ``ros2 param set /reference ...`` sets them (rcl_interfaces SetParameters),
the team is stopped and started as ``ros2 service call /formation/stop std_srvs/srv/Trigger``
does, and a scheduled switch in lockstep is compared with ``formation_sim``.
"""

import json
import math
import subprocess

from formation_ros.core.runs.trajectory import Trajectory
from formation_ros.core.settings.params import load_config
from formation_ros.ros import fields, qos
from geometry_msgs.msg import PoseStamped, TwistStamped
from helpers import exe, launch, SimClock, stop_when, TWICE_REAL_TIME, write_params
import numpy as np
from PIL import Image
from rcl_interfaces.msg import Parameter, ParameterType, ParameterValue
from rcl_interfaces.srv import SetParameters
from std_srvs.srv import Trigger
from test_system import lockstep_matches_simulation

LINE = [-3.0, 0.0, -1.0, 0.0, 1.0, 0.0, 3.0, 0.0]
WEDGE = [0.0, 1.5, -1.5, 0.0, 1.5, 0.0, 0.0, -1.5]
SHAPES = {'formations.names': ['line', 'wedge'], 'formations.line.vertices': LINE,
          'formations.wedge.vertices': WEDGE}


def call(probe, client, request, timeout=30.0, tries=3):
    """
    Call a service from the probe and return its response (asserting it came).

    A request sent just after the service is discovered can lose its answer (the service
    replies before the client's reply reader is matched); every request here can be repeated
    without harm, so it is sent again if no answer came.
    """
    assert probe.spin_until(lambda: client.service_is_ready(), timeout), client.srv_name
    for _ in range(tries):
        future = client.call_async(request)
        if probe.spin_until(future.done, timeout / tries):
            return future.result()
        client.remove_pending_request(future)
    raise AssertionError(f'{client.srv_name}: no answer to {tries} requests')


def set_parameter(probe, client, name, value):
    """Set one parameter of the reference as ``ros2 param set`` does; return the result."""
    if isinstance(value, str):
        typed = ParameterValue(type=ParameterType.PARAMETER_STRING, string_value=value)
    elif isinstance(value, float):
        typed = ParameterValue(type=ParameterType.PARAMETER_DOUBLE, double_value=value)
    else:
        typed = ParameterValue(type=ParameterType.PARAMETER_DOUBLE_ARRAY,
                               double_array_value=value)
    request = SetParameters.Request(parameters=[Parameter(name=name, value=typed)])
    return call(probe, client, request).results[0]


class Poses:
    """The latest pose of every robot, heard by the probe."""

    def __init__(self, probe, count):
        self.latest = {}
        for i in range(1, count + 1):
            probe.create_subscription(
                PoseStamped, f'/robot_{i}/pose',
                lambda m, i=i: self.latest.__setitem__(i, (m.pose.position.x,
                                                           m.pose.position.y)),
                qos.STATE_INPUT)

    def error(self, vertices):
        """Largest distance of a robot from its vertex (fixed reference at the origin), m."""
        if len(self.latest) < 4:
            return float('inf')
        q = np.array([self.latest[i] for i in range(1, 5)])
        return float(np.max(np.linalg.norm(q - np.reshape(vertices, (4, 2)), axis=1)))


def all_zero(commands):
    """Tell whether each of the four robots' latest command among (robot, stamp, x, y) is 0."""
    latest = {}
    for robot, stamp, x, y in commands:
        if stamp >= latest.get(robot, (-1, None))[0]:
            latest[robot] = (stamp, (x, y))
    return len(latest) == 4 and all(u == (0.0, 0.0) for _, u in latest.values())


def test_shapes_switch_and_the_team_stops_and_goes(processes, install, probe, tmp_path):
    params = write_params(tmp_path, 'square_4.yaml', {**SHAPES, **TWICE_REAL_TIME})
    config = load_config(params, 'plant')
    bound = config.law().u_bound
    poses, clock = Poses(probe, 4), SimClock(probe)
    commands = []
    for i in range(1, 5):
        probe.create_subscription(
            TwistStamped, f'/robot_{i}/cmd_vel', lambda m, i=i: commands.append(
                (i, fields.stamp_to_ns(m.header.stamp), m.twist.linear.x, m.twist.linear.y)),
            qos.COMMAND)
    parameters = probe.create_client(SetParameters, '/reference/set_parameters')
    stop = probe.create_client(Trigger, '/formation/stop')
    start = probe.create_client(Trigger, '/formation/start')
    out, bag = tmp_path / 'out', tmp_path / 'bag'
    launch(processes, install, params, out=out, record=bag, per_process=4)
    square = config.vertices.ravel().tolist()
    assert probe.spin_until(lambda: poses.error(square) < 0.01, 90), processes.log('launcher')

    close = [0.0, 0.0, 0.5, 0.0, -1.0, 1.0, 1.0, -1.0]
    refused = set_parameter(probe, parameters, 'formation.vertices', close)
    assert not refused.successful and 'b = 1 m must not exceed' in refused.reason
    short = set_parameter(probe, parameters, 'formation.vertices', LINE[:6])
    assert not short.successful and '4 x 2 = 8 values' in short.reason
    nan = set_parameter(probe, parameters, 'formation.vertices', [math.nan] + LINE[1:])
    assert not nan.successful and 'finite' in nan.reason
    unknown = set_parameter(probe, parameters, 'formation.name', 'circle')
    assert not unknown.successful and 'line, wedge' in unknown.reason

    assert set_parameter(probe, parameters, 'formation.name', 'line').successful
    assert probe.spin_until(lambda: poses.error(LINE) < 0.01, 60), processes.log('reference')
    assert set_parameter(probe, parameters, 'formation.vertices', WEDGE).successful
    assert probe.spin_until(lambda: poses.error(WEDGE) < 0.01, 60), processes.log('reference')

    assert set_parameter(probe, parameters, 'formation.name', 'line').successful
    moving_from = clock.seconds
    assert probe.spin_until(lambda: clock.seconds > moving_from + 0.3, 30)
    before = len(commands)
    response = call(probe, stop, Trigger.Request())
    assert response.success and 'team stopped' in response.message
    # Each robot hears the stop on /formation/status after its own delay: wait until every
    # robot's latest command is zero, then for the poses in flight.
    assert probe.spin_until(lambda: all_zero(commands[before:]), 30), commands[-8:]
    holding = clock.seconds
    assert probe.spin_until(lambda: clock.seconds > holding + 0.2, 30)
    held = dict(poses.latest)
    assert probe.spin_until(lambda: clock.seconds > holding + 2.0, 30)
    late = [(i, x, y) for i, stamp, x, y in commands if stamp >= holding * 1e9]
    assert {i for i, _, _ in late} == {1, 2, 3, 4}
    assert all(x == 0.0 and y == 0.0 for _, x, y in late), late[:5]
    drift = max(np.hypot(poses.latest[i][0] - held[i][0], poses.latest[i][1] - held[i][1])
                for i in held)
    assert drift < 1e-9, drift
    assert poses.error(LINE) > 0.1
    assert call(probe, start, Trigger.Request()).success
    info = stop_when(probe, processes, lambda: poses.error(LINE) < 0.01)
    assert info.returncode == 0, processes.log('launcher')

    assert all(max(abs(x), abs(y)) <= bound + 1e-9 for _, _, x, y in commands)
    stats = json.loads((out / 'plant_stats.json').read_text())
    assert stats['collisions'] == 0 and stats['bound_violations'] == 0
    assert stats['held_steps'] > 100 and stats['shape_changes'] >= 3
    trajectory = Trajectory.load(str(out / 'trajectory.npz'))
    assert np.allclose(trajectory.q_desired[-1].ravel(), LINE)
    assert np.allclose(trajectory.q_desired[0], config.vertices)
    from_bag = json.loads((out / 'metrics.json').read_text())
    assert from_bag['source'] == 'rosbag2' and from_bag['shape_changes'] >= 3
    assert from_bag['final_max_error'] < 0.02 and from_bag['collisions'] == 0
    segments = from_bag['segments']
    assert [row['kind'] for row in segments] == [None, 'shape', 'shape', 'shape', 'stop',
                                                 'start'], segments
    assert [row['label'] for row in segments[1:4]] == ['line', 'wedge', 'line']
    assert segments[1]['settle_time'] is not None and segments[-1]['settle_time'] is not None
    anim = tmp_path / 'anim'
    done = subprocess.run([exe(install, 'formation_report'), str(bag), '--out', str(anim),
                           '--animate', '--max-frames', '12', '--dpi', '30'],
                          capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    if (anim / 'animation.mp4').exists():
        assert (anim / 'animation.mp4').read_bytes()[4:8] == b'ftyp'
    else:
        with Image.open(anim / 'animation.gif') as gif:
            assert gif.n_frames == 12


def test_a_scheduled_switch_in_lockstep_is_formation_sims(processes, install, probe, tmp_path):
    plant, params = lockstep_matches_simulation(
        processes, install, probe, tmp_path, 'square_4.yaml',
        {**SHAPES, 'formation.schedule.times': [0.8], 'formation.schedule.names': ['wedge']},
        until=1.6)
    switched = plant.t >= 0.8 - 1e-9
    assert np.allclose(plant.q_desired[switched].reshape(-1, 8), WEDGE)
    assert np.allclose(plant.q_desired[~switched].reshape(-1, 8),
                       load_config(params).vertices.ravel())
