# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""The world node with obstacles over DDS: a base driven into a pillar stops at it, counted."""

import json
import os
import signal

from formation_ros.core.settings.params_file import load_params_file, write_params_file
from formation_ros.ros import qos
from geometry_msgs.msg import PoseStamped, TwistStamped
from helpers import CONFIG, logged, node, SimClock, Statuses, wait_exit
import numpy as np
import wire

START_UP = 90.0
STATUS = 'formation_ros/world'
PILLAR = (0.5, 0.0, 0.1)
"""A pillar straight ahead of robot 1: x, y, r (m)."""


def obstacle_params(folder, out):
    """Write two of a lab's bases, robot 1 heading +x at a pillar, robot 2 aside; return it."""
    values = load_params_file(os.path.join(CONFIG, 'lab_turtlebot3.yaml'))
    values = {name: value for name, value in values.items()
              if not name.startswith(('relay.', 'start.'))}
    values.update({'num_robots': 2, 'formation.vertices': [-1.0, 0.0, -1.0, 1.0],
                   'start.positions': [0.0, 0.0, 0.0, 1.0], 'start.headings': [0.0, 0.0],
                   'obstacles.circles': [float(v) for v in PILLAR],
                   'obstacles.clearance': 0.3, 'world.cmd_timeout': 0.3,
                   'world.output_dir': str(out)})
    path = os.path.join(str(folder), 'params.yaml')
    write_params_file(path, values)
    return path


def value(statuses, key):
    """Return the world's latest status value ``key`` as a number (0 before any)."""
    status = statuses.get(STATUS)
    values = {kv.key: kv.value for kv in status.values} if status is not None else {}
    return float(values.get(key, 0))


def test_a_base_driven_into_a_pillar_stops_there_and_the_world_counts_it_apart(
        processes, install, probe, tmp_path):
    out = tmp_path / 'world'
    processes.start(node(install, 'world', obstacle_params(tmp_path, out)))
    clock, statuses = SimClock(probe), Statuses(probe)
    poses = []
    probe.create_subscription(PoseStamped, '/robot_1/measured_pose', poses.append,
                              qos.MEASUREMENT)
    drive = probe.create_publisher(TwistStamped, '/robot_1/cmd_vel', qos.COMMAND)
    assert probe.spin_until(lambda: poses and clock.seconds > 0.2
                            and drive.get_subscription_count(), START_UP), \
        processes.log('world')

    def into_the_pillar():
        message = wire.twist_stamped(np.array([0.2, 0.0]), int(round(clock.seconds * 1e9)), 2)
        message.header.frame_id = 'robot_1/base_link'
        drive.publish(message)
        return value(statuses, 'obstacle contacts') >= 1

    assert probe.spin_until(into_the_pillar, 60), processes.log('world')
    pushed = clock.seconds + 1.0
    assert probe.spin_until(lambda: into_the_pillar() and clock.seconds > pushed, 30)
    log = logged(probe, processes, 'world',
                 'obstacle contact 1: robot 1 touched circle 1 at t = ')
    assert log.count('obstacle contact 1: ') == 1 and 'obstacle contact 2' not in log
    assert value(statuses, 'contacts') == 0
    x = poses[-1].pose.position.x
    processes.send_signal('world', signal.SIGINT)
    info = wait_exit(probe, processes, 'world', 30)
    assert info is not None and info.returncode == 0, processes.log('world')
    assert '1 contacts with obstacles, min obstacle gap ' in processes.log('world')
    # The axle stops where its footprint (body.radius 0.11 m) meets the pillar.
    touching = PILLAR[0] - PILLAR[2] - 0.11
    assert touching - 0.01 < x < touching + 0.002, 'it stops at the pillar (soft contact)'

    stats = json.loads((out / 'world_stats.json').read_text())
    assert stats['obstacle_contacts'] == 1 and stats['contacts'] == 0
    (event,) = stats['obstacle_contact_events']
    assert (event['robot'], event['obstacle']) == (1, 'circle 1')
    assert -0.01 < stats['min_obstacle_gap'] < 0.001
    import mujoco
    model = mujoco.MjModel.from_xml_path(str(out / 'world.xml'))
    pillar = model.geom('obstacle_circle_1')
    assert np.allclose(pillar.pos[:2], PILLAR[:2]) and pillar.size[0] == PILLAR[2]
