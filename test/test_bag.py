# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""rosbag2 writing and reading (bag.py) and the report from a bag (report.py), without DDS."""

import json
import os
import subprocess
import sys

from formation_ros.core.frames import frame_to_pose
from formation_ros.core.params import load_config, validate
from formation_ros.core.params_file import dump_params_text, load_params_file, parse_params_text
from formation_ros.ros.bag_writer import BagError, BagWriter, TYPESTORE
from formation_ros.ros.topics import PARAMS as PARAMS_TOPIC
from formation_ros.tools.bag import read_messages
from formation_ros.tools.report import main as report_main
from formation_ros.tools.sim import run_metrics, simulate
import numpy as np
import pytest
import yaml

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
CONFIG = os.path.join(ROOT, 'config')
NS = 1_000_000_000
Time = TYPESTORE.types['builtin_interfaces/msg/Time']
Header = TYPESTORE.types['std_msgs/msg/Header']


def header(stamp_ns):
    return Header(stamp=Time(sec=stamp_ns // NS, nanosec=stamp_ns % NS), frame_id='world')


def vector3(values):
    padded = list(values) + [0.0] * (3 - len(values))
    return TYPESTORE.types['geometry_msgs/msg/Vector3'](x=padded[0], y=padded[1], z=padded[2])


def point(values):
    padded = list(values) + [0.0] * (3 - len(values))
    return TYPESTORE.types['geometry_msgs/msg/Point'](x=padded[0], y=padded[1], z=padded[2])


def identity():
    return TYPESTORE.types['geometry_msgs/msg/Quaternion'](x=0.0, y=0.0, z=0.0, w=1.0)


def pose_msg(stamp_ns, position):
    types = TYPESTORE.types
    return types['geometry_msgs/msg/PoseStamped'](
        header=header(stamp_ns),
        pose=types['geometry_msgs/msg/Pose'](position=point(position), orientation=identity()))


def twist_msg(stamp_ns, velocity):
    types = TYPESTORE.types
    return types['geometry_msgs/msg/TwistStamped'](
        header=header(stamp_ns),
        twist=types['geometry_msgs/msg/Twist'](linear=vector3(velocity),
                                               angular=vector3([0.0, 0.0, 0.0])))


def odometry_msg(stamp_ns, frame, dim):
    types = TYPESTORE.types
    position, quat, linear, angular = frame_to_pose(frame, dim)
    pose = types['geometry_msgs/msg/Pose'](
        position=point(position),
        orientation=types['geometry_msgs/msg/Quaternion'](
            x=quat[0], y=quat[1], z=quat[2], w=quat[3]))
    return types['nav_msgs/msg/Odometry'](
        header=header(stamp_ns), child_frame_id='formation',
        pose=types['geometry_msgs/msg/PoseWithCovariance'](pose=pose,
                                                           covariance=np.zeros(36)),
        twist=types['geometry_msgs/msg/TwistWithCovariance'](
            twist=types['geometry_msgs/msg/Twist'](linear=vector3(linear),
                                                   angular=vector3(angular)),
            covariance=np.zeros(36)))


def write_run_as_bag(path, config, trajectory, with_params=True):
    """Write a simulated run as the recorder would record it."""
    reference = config.reference()
    with BagWriter(path) as bag:
        for i in range(1, config.num_robots + 1):
            bag.add_topic(f'/robot_{i}/pose', 'geometry_msgs/msg/PoseStamped')
            bag.add_topic(f'/robot_{i}/cmd_vel', 'geometry_msgs/msg/TwistStamped')
        bag.add_topic('/formation/reference', 'nav_msgs/msg/Odometry')
        if with_params:
            bag.write_params(config.values, 1)
        for k, t in enumerate(trajectory.t):
            stamp = int(round(t * NS))
            frame = reference.sample(stamp / NS)
            bag.write('/formation/reference', stamp + 1, TYPESTORE.serialize_cdr(
                odometry_msg(stamp, frame, config.dim), 'nav_msgs/msg/Odometry'))
            for i in range(config.num_robots):
                bag.write(f'/robot_{i + 1}/pose', stamp + 2, TYPESTORE.serialize_cdr(
                    pose_msg(stamp, trajectory.q[k, i]), 'geometry_msgs/msg/PoseStamped'))
                bag.write(f'/robot_{i + 1}/cmd_vel', stamp + 3, TYPESTORE.serialize_cdr(
                    twist_msg(stamp, trajectory.u[k, i]), 'geometry_msgs/msg/TwistStamped'))
    return bag


@pytest.mark.parametrize('name', ['square_4.yaml', 'helix_3d.yaml'])
def test_report_from_bag_equals_report_from_simulation(tmp_path, name):
    config = load_config(os.path.join(CONFIG, name))
    trajectory = simulate(config, duration=4.0, dt=0.01, sample_dt=0.02)
    bag_dir = tmp_path / 'bag'
    write_run_as_bag(str(bag_dir), config, trajectory)
    assert report_main([str(bag_dir), '--out', str(tmp_path / 'report'), '--no-plots']) == 0
    from_bag = json.loads((tmp_path / 'report' / 'metrics.json').read_text())
    direct = run_metrics(trajectory, config, 'test')
    for key in ('min_pair_distance', 'final_max_error', 'max_abs_u_component',
                'max_abs_u_hat_component', 'dis_all_final', 'num_robots', 'dim'):
        assert from_bag[key] == pytest.approx(direct[key], rel=1e-9, abs=1e-12), key
    assert from_bag['settle_time'] == pytest.approx(direct['settle_time'])
    assert from_bag['reference_source'] == 'recorded'


def test_metadata_counts_equal_messages_read(tmp_path):
    config = load_config(os.path.join(CONFIG, 'square_4.yaml'))
    trajectory = simulate(config, duration=1.0, dt=0.01, sample_dt=0.05)
    bag = write_run_as_bag(str(tmp_path / 'bag'), config, trajectory)
    topics, counts = read_messages(str(tmp_path / 'bag'))
    assert counts == {topic: len(messages) for topic, messages in topics.items()}
    assert counts == {topic: count for topic, count in bag.counts.items() if count}
    assert counts['/robot_1/pose'] == len(trajectory.t) and counts[PARAMS_TOPIC] == 1
    with open(tmp_path / 'bag' / 'metadata.yaml') as stream:
        metadata = yaml.safe_load(stream)['rosbag2_bagfile_information']
    assert metadata['storage_identifier'] == 'mcap'
    assert metadata['message_count'] == sum(counts.values())


def test_independent_mcap_reader_decodes_every_message(tmp_path):
    """The mcap + mcap_ros2 libraries decode the bag from its embedded definitions alone."""
    from mcap.reader import make_reader
    from mcap_ros2.decoder import DecoderFactory
    config = load_config(os.path.join(CONFIG, 'circle_2d.yaml'))
    trajectory = simulate(config, duration=0.5, dt=0.01, sample_dt=0.1)
    write_run_as_bag(str(tmp_path / 'bag'), config, trajectory)
    (mcap_file,) = [name for name in os.listdir(tmp_path / 'bag') if name.endswith('.mcap')]
    decoded = {}
    with open(tmp_path / 'bag' / mcap_file, 'rb') as stream:
        reader = make_reader(stream, decoder_factories=[DecoderFactory()])
        assert reader.get_header().profile == 'ros2'
        for schema, channel, _, message in reader.iter_decoded_messages():
            assert schema.encoding == 'ros2msg' and channel.message_encoding == 'cdr'
            decoded.setdefault(channel.topic, []).append(message)
    assert len(decoded['/robot_1/pose']) == len(trajectory.t)
    assert decoded['/robot_2/pose'][-1].pose.position.x == trajectory.q[-1, 1, 0]
    assert decoded['/robot_3/cmd_vel'][0].twist.linear.y == trajectory.u[0, 2, 1]
    assert decoded['/formation/reference'][1].child_frame_id == 'formation'
    assert 'num_robots: 6' in decoded[PARAMS_TOPIC][0].data


def test_bag_stores_its_parameters(tmp_path):
    config = load_config(os.path.join(CONFIG, 'helix_3d.yaml'))
    with BagWriter(str(tmp_path / 'bag')) as bag:
        bag.write_params(config.values, 5)
    topics, _ = read_messages(str(tmp_path / 'bag'))
    text = topics[PARAMS_TOPIC][0][1].data
    assert text == (tmp_path / 'bag' / 'params.yaml').read_text()
    again = validate(parse_params_text(text, 'bag'))
    assert np.array_equal(again.vertices, config.vertices)
    assert np.array_equal(again.start, config.start)
    assert again.reference_kind == 'helix'


def test_params_yaml_round_trip():
    raw = load_params_file(os.path.join(CONFIG, 'paper_section5.yaml'))
    assert parse_params_text(dump_params_text(raw), 'text') == raw


def test_refuses_to_overwrite(tmp_path):
    path = tmp_path / 'bag'
    BagWriter(str(path)).close()
    with pytest.raises(BagError, match='refusing to overwrite'):
        BagWriter(str(path))
    BagWriter(str(path), overwrite=True).close()
    other = tmp_path / 'notes'
    other.mkdir()
    (other / 'important.txt').write_text('keep me')
    with pytest.raises(BagError, match='not a bag directory'):
        BagWriter(str(other), overwrite=True)
    assert (other / 'important.txt').exists()


def test_report_on_bag_without_parameters_says_why(tmp_path):
    config = load_config(os.path.join(CONFIG, 'square_4.yaml'))
    trajectory = simulate(config, duration=0.2, dt=0.01, sample_dt=0.05)
    write_run_as_bag(str(tmp_path / 'bag'), config, trajectory, with_params=False)
    result = subprocess.run([sys.executable, '-m', 'formation_ros.tools.report',
                             str(tmp_path / 'bag'), '--out', str(tmp_path / 'out')],
                            capture_output=True, text=True, timeout=120)
    assert result.returncode == 2
    assert 'has no parameters' in result.stderr and 'Traceback' not in result.stderr
    assert not (tmp_path / 'out').exists()


def test_report_on_missing_input(tmp_path):
    assert report_main([str(tmp_path / 'nothing'), '--out', str(tmp_path / 'out')]) == 2


def test_rviz_config_shows_the_markers():
    with open(os.path.join(CONFIG, 'formation.rviz')) as stream:
        rviz = yaml.safe_load(stream)
    manager = rviz['Visualization Manager']
    assert manager['Global Options']['Fixed Frame'] == 'world'
    topics = [d.get('Topic', {}).get('Value') for d in manager['Displays']]
    assert '/formation/markers' in topics
