# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""rosbag2 writing and reading (bag.py) and the report from a bag (report.py), without DDS."""

import json
import os
import shutil
import subprocess
import sys

from formation_ros.core.maths.frames import frame_to_pose
from formation_ros.core.settings.params import load_config, validate
from formation_ros.core.settings.params_file import (dump_params_text, load_params_file,
                                                     parse_params_text)
from formation_ros.ros.bag_writer import BagError, BagWriter, TYPESTORE
from formation_ros.ros.topics import PARAMS as PARAMS_TOPIC
from formation_ros.simulation.simulate import run_metrics, simulate
from formation_ros.tools.bag import read_messages, read_or_recover, recover_bag, repair_bag
from formation_ros.tools.report import main as report_main
import numpy as np
import pytest
import yaml

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
CONFIG = os.path.join(ROOT, 'config')
SQUARE = os.path.join(CONFIG, 'square_4.yaml')
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


def write_run_as_bag(path, config, trajectory, with_params=True, flush_every=0,
                     on_flush=None, flushes_per_file=0):
    """
    Write a simulated run as the recorder would record it.

    flush_every: flush the bag after every that many samples, as the recorder's timer does,
    calling ``on_flush(bag)`` after each flush (the bag is still open: what SIGKILL would leave).
    flushes_per_file: start a new MCAP file after that many flushes (0: one file).
    """
    reference = config.reference()
    with BagWriter(path, flushes_per_file=flushes_per_file) as bag:
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
            if flush_every and (k + 1) % flush_every == 0:
                bag.flush()
                if on_flush is not None:
                    on_flush(bag)
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


def test_a_split_bag_lists_its_files_and_reads_as_one(tmp_path):
    config = load_config(os.path.join(CONFIG, 'square_4.yaml'))
    trajectory = simulate(config, duration=2.0, dt=0.01, sample_dt=0.02)
    whole, split = tmp_path / 'whole', tmp_path / 'split'
    write_run_as_bag(str(whole), config, trajectory, flush_every=10)
    bag = write_run_as_bag(str(split), config, trajectory, flush_every=10, flushes_per_file=3)
    names = sorted(name for name in os.listdir(split) if name.endswith('.mcap'))
    assert len(names) == 4 and 'split.mcap' in names and 'split_3.mcap' in names
    with open(split / 'metadata.yaml') as stream:
        metadata = yaml.safe_load(stream)['rosbag2_bagfile_information']
    assert sorted(metadata['relative_file_paths']) == names
    assert [entry['path'] for entry in metadata['files']] == metadata['relative_file_paths']
    assert sum(entry['message_count'] for entry in metadata['files']) == \
        metadata['message_count'] == sum(bag.counts.values())
    starts = [entry['starting_time']['nanoseconds_since_epoch'] for entry in metadata['files']]
    assert starts == sorted(starts)
    from mcap.reader import make_reader
    for name in names:
        with open(split / name, 'rb') as stream:
            statistics = make_reader(stream).get_summary().statistics
        entry = next(e for e in metadata['files'] if e['path'] == name)
        assert statistics.message_count == entry['message_count'] > 0
        assert statistics.channel_count == 2 * config.num_robots + 2
    whole_topics, whole_counts = read_messages(str(whole))
    split_topics, split_counts = read_messages(str(split))
    assert split_counts == whole_counts
    for topic, messages in whole_topics.items():
        assert [stamp for stamp, _ in split_topics[topic]] == [stamp for stamp, _ in messages]
    assert recover_bag(str(split)).count == sum(whole_counts.values())


def test_a_split_bag_whose_metadata_names_one_file_is_not_read_as_whole(tmp_path):
    config = load_config(os.path.join(CONFIG, 'square_4.yaml'))
    trajectory = simulate(config, duration=1.0, dt=0.01, sample_dt=0.02)
    folder = tmp_path / 'bag'
    bag = write_run_as_bag(str(folder), config, trajectory, flush_every=10, flushes_per_file=2)
    total = sum(bag.counts.values())
    from mcap.reader import make_reader
    names = sorted(name for name in os.listdir(folder) if name.endswith('.mcap'))
    with open(folder / names[-1], 'rb') as stream:
        (record,) = [m for m in make_reader(stream).iter_metadata() if m.name == 'rosbag2']
    embedded = yaml.safe_load(record.metadata['serialized_metadata'])
    assert sorted(embedded['relative_file_paths']) == names and len(names) > 2
    metadata_path = folder / 'metadata.yaml'
    document = yaml.safe_load(metadata_path.read_text())
    information = document['rosbag2_bagfile_information']
    information['relative_file_paths'] = information['relative_file_paths'][:1]
    information['files'] = information['files'][:1]
    metadata_path.write_text(yaml.safe_dump(document))
    with pytest.raises(BagError, match=f'counts {total} messages, its files hold'):
        read_messages(str(folder))
    recorded, counts, note = read_or_recover(str(folder))
    assert sum(counts.values()) == total and 'recovered' in note


def test_a_split_bag_cut_by_sigkill_is_recovered_and_repaired(tmp_path):
    config = load_config(os.path.join(CONFIG, 'square_4.yaml'))
    trajectory = simulate(config, duration=2.0, dt=0.01, sample_dt=0.02)
    folder = tmp_path / 'bag'
    kept = tmp_path / 'kept'
    written = []

    def snapshot(bag):
        if len(written) == 7:
            shutil.copytree(folder, kept)
        written.append(sum(bag.counts.values()))

    write_run_as_bag(str(folder), config, trajectory, flush_every=10, on_flush=snapshot,
                     flushes_per_file=3)
    assert len([name for name in os.listdir(kept) if name.endswith('.mcap')]) == 3
    assert not (kept / 'metadata.yaml').exists()
    recorded, counts, note = read_or_recover(str(kept))
    assert sum(counts.values()) == written[7]
    assert f'recovered {written[7]} messages' in note
    assert 'repaired' in repair_bag(str(kept))
    topics, counts = read_messages(str(kept))
    assert sum(counts.values()) == written[7]


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


# Bags cut short: what a recorder killed with SIGKILL leaves, and damaged files.

def _mcap_of(folder):
    (name,) = [n for n in os.listdir(folder) if n.endswith('.mcap')]
    return os.path.join(str(folder), name)


@pytest.fixture(scope='module')
def killed_recordings(tmp_path_factory):
    """
    Record a run, keeping the MCAP bytes on disk after each flush (what SIGKILL would leave).

    Returns (config, [(bytes, messages written so far), ...]).
    """
    config = load_config(os.path.join(CONFIG, 'square_4.yaml'))
    trajectory = simulate(config, duration=3.0, dt=0.01, sample_dt=0.02)
    folder = tmp_path_factory.mktemp('killed') / 'bag'
    snapshots = []

    def snapshot(bag):
        with open(_mcap_of(folder), 'rb') as stream:
            snapshots.append((stream.read(), sum(bag.counts.values())))

    write_run_as_bag(str(folder), config, trajectory, flush_every=10, on_flush=snapshot)
    return config, snapshots


def cut_bag(folder, data, config=None):
    """Make a bag directory as a killed recorder leaves it: params.yaml, an MCAP, no metadata."""
    folder.mkdir()
    (folder / f'{folder.name}.mcap').write_bytes(data)
    if config is not None:
        (folder / 'params.yaml').write_text(dump_params_text(config.values))
    return folder


def run_report(*args):
    return subprocess.run([sys.executable, '-m', 'formation_ros.tools.report', *map(str, args)],
                          capture_output=True, text=True, timeout=120)


def test_every_flush_reaches_the_file_and_is_recovered(killed_recordings, tmp_path):
    _, snapshots = killed_recordings
    assert len(snapshots) >= 10
    sizes = [len(data) for data, _ in snapshots]
    assert sizes == sorted(sizes) and sizes[0] > 0
    for k, (data, written) in enumerate(snapshots):
        recovery = recover_bag(str(cut_bag(tmp_path / f'flush{k}', data)))
        assert recovery.count == written
        assert not recovery.complete and recovery.kept == recovery.size
        assert recovery.dropped_chunks == recovery.dropped_messages == 0


def test_a_cut_at_any_byte_keeps_the_whole_chunks_before_it(killed_recordings, tmp_path):
    _, snapshots = killed_recordings
    ends = [(len(data), written) for data, written in snapshots]
    data = snapshots[-1][0]
    offsets = set()
    for (start, _), (end, _) in zip(ends, ends[1:]):
        offsets.update({start + 1, start + 9, start + 10, (start + end) // 2, end - 100,
                        end - 1})
    for offset in sorted(offsets):
        folder = cut_bag(tmp_path / f'cut{offset}', data[:offset])
        recovery = recover_bag(str(folder))
        before = max(written for end, written in ends if end <= offset)
        after = min(written for end, written in ends if end > offset)
        assert before <= recovery.count <= after, offset
        assert recovery.count in {written for _, written in ends}, offset
        assert recovery.kept <= offset and recovery.dropped_chunks == 0
        recorded, counts, note = read_or_recover(str(folder))
        assert sum(counts.values()) == recovery.count
        assert f'recovered {recovery.count} messages' in note and 'no metadata.yaml' in note


def test_a_cut_before_the_first_chunk_recovers_nothing(killed_recordings, tmp_path):
    _, snapshots = killed_recordings
    data = snapshots[0][0]
    for offset in (0, 4, 8, 20, 100, 1000):
        folder = cut_bag(tmp_path / f'cut{offset}', data[:offset])
        with pytest.raises(BagError) as caught:
            read_or_recover(str(folder))
        assert 'nothing to recover' in str(caught.value)
        assert '\n' not in str(caught.value)


def test_a_damaged_chunk_is_dropped_and_counted(killed_recordings, tmp_path):
    _, snapshots = killed_recordings
    (before, written_before), (after, written_after) = snapshots[3:5]
    data = bytearray(snapshots[-1][0])
    data[(len(before) + len(after)) // 2] ^= 0xFF
    recovery = recover_bag(str(cut_bag(tmp_path / 'flipped', bytes(data))))
    assert recovery.dropped_chunks == 1
    assert recovery.count == snapshots[-1][1] - (written_after - written_before)
    assert 'dropped 1 damaged chunks' in recovery.describe()


def test_random_bytes_are_never_more_than_a_bag_error(killed_recordings, tmp_path):
    _, snapshots = killed_recordings
    head = snapshots[0][0][:40]
    rng = np.random.default_rng(9)
    for k in range(60):
        noise = rng.integers(0, 256, int(rng.integers(0, 3000)), dtype=np.uint8).tobytes()
        for prefix in (b'', head):
            folder = tmp_path / f'noise{k}_{len(prefix)}'
            try:
                recover_bag(str(cut_bag(folder, prefix + noise)))
            except BagError as exc:
                assert '\n' not in str(exc)


def test_report_recovers_a_killed_recording(killed_recordings, tmp_path):
    config, snapshots = killed_recordings
    (before, recovered), (data, _) = snapshots[-3][0:2], snapshots[-2]
    bag = cut_bag(tmp_path / 'bag', data[:(len(before) + len(data)) // 2], config)
    result = run_report(bag, '--out', tmp_path / 'out', '--no-plots')
    assert result.returncode == 0, result.stderr
    assert 'Traceback' not in result.stderr
    (line,) = [ln for ln in result.stderr.splitlines() if 'recovered' in ln]
    assert f'recovered {recovered} messages on ' in line and 'no metadata.yaml' in line
    assert 'dropped the last' in line
    metrics = json.loads((tmp_path / 'out' / 'metrics.json').read_text())
    assert metrics['recovered_messages'] == metrics['messages'] == recovered
    assert metrics['source'] == 'rosbag2' and metrics['reference_source'] == 'recorded'
    assert metrics['num_robots'] == 4 and metrics['min_pair_distance'] > 0


def test_repair_makes_a_killed_recording_whole(killed_recordings, tmp_path):
    config, snapshots = killed_recordings
    data, written = snapshots[-1]
    bag = cut_bag(tmp_path / 'bag', data, config)
    result = run_report(bag, '--repair')
    assert result.returncode == 0 and 'Traceback' not in result.stderr, result.stderr
    assert f'repaired {bag}: {written} messages on 10 topics' in result.stdout
    assert (bag / 'bag.mcap.damaged').read_bytes() == data
    topics, counts = read_messages(str(bag))
    assert counts == {topic: len(messages) for topic, messages in topics.items()}
    assert sum(counts.values()) == written
    with open(bag / 'metadata.yaml') as stream:
        metadata = yaml.safe_load(stream)['rosbag2_bagfile_information']
    assert metadata['message_count'] == written
    qos = {t['topic_metadata']['name']: t['topic_metadata']['offered_qos_profiles']
           for t in metadata['topics_with_message_count']}
    assert qos[PARAMS_TOPIC][0]['durability'] == 'transient_local'
    again = run_report(bag, '--repair', '--out', tmp_path / 'out', '--no-plots')
    assert again.returncode == 0, again.stderr
    assert 'nothing to repair' in again.stdout and 'recovered' not in again.stderr
    assert json.loads((tmp_path / 'out' / 'metrics.json').read_text())['messages'] == written


def test_report_recovers_a_bag_with_a_garbage_metadata_file(tmp_path):
    config = load_config(os.path.join(CONFIG, 'square_4.yaml'))
    trajectory = simulate(config, duration=0.5, dt=0.01, sample_dt=0.05)
    write_run_as_bag(str(tmp_path / 'bag'), config, trajectory)
    for text in ('', ':: not yaml [', 'rosbag2_bagfile_information: 3\n'):
        (tmp_path / 'bag' / 'metadata.yaml').write_text(text)
        recorded, counts, note = read_or_recover(str(tmp_path / 'bag'))
        assert sum(counts.values()) == 4 * 2 * len(trajectory.t) + len(trajectory.t) + 1
        assert 'rosbags cannot read it' in note and 'data section whole' in note
    assert repair_bag(str(tmp_path / 'bag')).startswith(f'repaired {tmp_path / "bag"}')
    assert (tmp_path / 'bag' / 'metadata.yaml.damaged').read_text() == text
    assert (tmp_path / 'bag' / 'bag.mcap.damaged').exists()
    topics, counts = read_messages(str(tmp_path / 'bag'))
    assert counts == {topic: len(messages) for topic, messages in topics.items()}
    assert repair_bag(str(tmp_path / 'bag')).endswith('is whole; nothing to repair')


def _not_an_mcap(tmp_path):
    path = tmp_path / 'random.mcap'
    path.write_bytes(np.random.default_rng(3).integers(0, 256, 5000, dtype=np.uint8).tobytes())
    return path


def _random_mcap_in_a_bag(tmp_path):
    folder = tmp_path / 'bag'
    folder.mkdir()
    _not_an_mcap(folder)
    return folder


def _truncated_whole_bag(tmp_path):
    config = load_config(os.path.join(CONFIG, 'square_4.yaml'))
    write_run_as_bag(str(tmp_path / 'bag'), config,
                     simulate(config, duration=0.2, dt=0.01, sample_dt=0.05))
    mcap = _mcap_of(tmp_path / 'bag')
    with open(mcap, 'r+b') as stream:
        stream.truncate(300)
    return tmp_path / 'bag'


def _garbage_metadata(tmp_path):
    folder = tmp_path / 'bag'
    folder.mkdir()
    (folder / 'metadata.yaml').write_bytes(b'\x00\xff garbage: [')
    return folder


def _empty_metadata(tmp_path):
    folder = tmp_path / 'bag'
    folder.mkdir()
    (folder / 'metadata.yaml').write_text('')
    return folder


def _not_a_bag(tmp_path):
    folder = tmp_path / 'photos'
    folder.mkdir()
    (folder / 'cat.jpg').write_bytes(b'meow')
    return folder


def _plain_file(tmp_path):
    path = tmp_path / 'notes.txt'
    path.write_text('hello')
    return path


def _garbage_trajectory(tmp_path):
    folder = tmp_path / 'run'
    folder.mkdir()
    (folder / 'params.yaml').write_text(dump_params_text(load_params_file(SQUARE)))
    (folder / 'trajectory.npz').write_bytes(b'PK\x03\x04 not a zip')
    return folder


@pytest.mark.parametrize('make, expected', [
    (_not_an_mcap, 'not an MCAP file'),
    (_random_mcap_in_a_bag, 'not an MCAP file'),
    (_truncated_whole_bag, 'nothing to recover: no whole message'),
    (_garbage_metadata, 'no .mcap file'),
    (_empty_metadata, 'no .mcap file'),
    (_not_a_bag, 'neither a bag'),
    (_plain_file, 'not a bag directory'),
    (lambda tmp_path: tmp_path / 'missing', 'no such file or directory'),
    (_garbage_trajectory, 'not a readable trajectory'),
])
def test_unreadable_input_is_one_line_and_exit_2(tmp_path, capsys, make, expected):
    source = make(tmp_path)
    result = run_report(source, '--out', tmp_path / 'out', '--no-plots')
    assert result.returncode == 2, result.stdout + result.stderr
    assert 'Traceback' not in result.stderr
    assert result.stderr.count('\n') == 1 and expected in result.stderr, result.stderr
    assert not (tmp_path / 'out').exists()
    assert report_main([str(source), '--repair']) == 2
    assert capsys.readouterr().err.count('\n') == 1


def test_out_that_cannot_be_written_is_one_line_and_exit_2(tmp_path):
    config = load_config(os.path.join(CONFIG, 'square_4.yaml'))
    write_run_as_bag(str(tmp_path / 'bag'), config,
                     simulate(config, duration=0.2, dt=0.01, sample_dt=0.05))
    taken = tmp_path / 'taken'
    taken.write_text('mine')
    for out, expected in ((taken, 'exists and is not a directory'),
                          (taken / 'report', 'is not a directory')):
        result = run_report(tmp_path / 'bag', '--out', out, '--no-plots')
        assert result.returncode == 2 and 'Traceback' not in result.stderr, result.stderr
        assert result.stderr.count('\n') == 1 and expected in result.stderr, result.stderr
    assert taken.read_text() == 'mine'


def test_topics_of_unknown_types_are_counted_not_read(tmp_path):
    with BagWriter(str(tmp_path / 'odd')) as odd:
        odd.add_topic('/blobs', 'my_pkg/msg/Blob',
                      definition=('uint8[] data', 'RIHS01_' + '0' * 64))
        odd.write('/blobs', 5, b'\x00\x01\x00\x00\x02\x00\x00\x00\x07\x08')
    topics, counts = read_messages(str(tmp_path / 'odd'))
    assert counts == {'/blobs': 1} and topics == {}
    (tmp_path / 'odd' / 'metadata.yaml').unlink()
    with pytest.raises(BagError, match='none of the 1 messages decodes'):
        read_or_recover(str(tmp_path / 'odd'))
    recovery = recover_bag(str(tmp_path / 'odd'))
    assert recovery.topics['/blobs'].msgtype == 'my_pkg/msg/Blob' and recovery.count == 1
