# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
Read rosbag2 directories of formation runs (``rosbags``) back into a trajectory.

Bags are written by the recorder (:mod:`formation_ros.ros.bag_writer`). Reading rebuilds a
:class:`formation_ros.core.trajectory.Trajectory` from the recorded poses, commands and
reference samples (header stamps, i.e. simulated time).
"""

import os
from typing import Any, Dict, List, Optional, Tuple

from formation_ros.core.frames import advance, FrameSample
from formation_ros.core.params import FormationConfig
from formation_ros.core.trajectory import Trajectory
from formation_ros.ros import topics as names
from formation_ros.ros.bag_writer import BagError, PARAMS_FILE, TYPESTORE
from formation_ros.ros.fields import frame_of, NS_PER_S, position_of, stamp_to_ns, velocity_of
import numpy as np
from rosbags.rosbag2 import Reader


Recorded = Dict[str, List[Tuple[int, Any]]]


def read_messages(path: str) -> Tuple[Recorded, Dict[str, int]]:
    """Return ({topic: [(timestamp_ns, message), ...]}, {topic: count in metadata.yaml})."""
    if not os.path.isfile(os.path.join(path, 'metadata.yaml')):
        raise BagError(f'{path}: no metadata.yaml, not a rosbag2 directory')
    recorded: Recorded = {}
    counts: Dict[str, int] = {}
    with Reader(path) as reader:
        for connection in reader.connections:
            counts[connection.topic] = counts.get(connection.topic, 0) + connection.msgcount
        for connection, timestamp, raw in reader.messages():
            message = TYPESTORE.deserialize_cdr(raw, connection.msgtype)
            recorded.setdefault(connection.topic, []).append((timestamp, message))
    return recorded, counts


def bag_params_text(path: str, recorded: Recorded) -> Optional[str]:
    """Return the parameters YAML stored with a bag (topic, else params.yaml), or None."""
    if recorded.get(names.PARAMS):
        return recorded[names.PARAMS][-1][1].data
    file_path = os.path.join(path, PARAMS_FILE)
    if os.path.isfile(file_path):
        with open(file_path, encoding='utf-8') as stream:
            return stream.read()
    return None


def _frames_at(stamps: List[int], reference_messages: List[Tuple[int, Any]],
               config: FormationConfig) -> Tuple[List[FrameSample], str]:
    """
    Return the reference frame at each stamp and where it came from.

    The recorded sample with that stamp, else the last earlier one carried on; before the first
    recorded sample (or with none recorded) the reference in the parameters.
    """
    dim = config.dim
    reference = config.reference()
    if not reference_messages:
        return [reference.sample(s / NS_PER_S) for s in stamps], 'parameters'
    by_stamp = {}
    for _, message in reference_messages:
        by_stamp[stamp_to_ns(message.header.stamp)] = message
    known = np.array(sorted(by_stamp))
    frames = []
    for stamp in stamps:
        if stamp in by_stamp:
            frames.append(frame_of(by_stamp[stamp], dim))
            continue
        index = int(np.searchsorted(known, stamp, side='right')) - 1
        if index < 0:
            frames.append(reference.sample(stamp / NS_PER_S))
            continue
        base = frame_of(by_stamp[int(known[index])], dim)
        frames.append(advance(base, (stamp - int(known[index])) / NS_PER_S))
    return frames, 'recorded'


def trajectory_from_topics(recorded: Recorded,
                           config: FormationConfig) -> Tuple[Trajectory, Dict[str, str]]:
    """
    Rebuild the run from recorded messages.

    Samples are the state stamps at which every robot's pose was recorded; u_i at a sample is
    the command robot i sent for that state (or its latest earlier one, zero before its first);
    desired positions come from the recorded reference samples (or, if none were recorded, from
    the reference in the parameters) and the formation vertices. Returns (Trajectory, info).
    """
    n, dim = config.num_robots, config.dim
    poses: Dict[int, Dict[int, Any]] = {}
    for i in range(1, n + 1):
        for _, message in recorded.get(names.robot_topic(i, names.POSE), []):
            poses.setdefault(stamp_to_ns(message.header.stamp), {})[i - 1] = \
                position_of(message, dim)
    stamps = sorted(stamp for stamp, seen in poses.items() if len(seen) == n)
    if len(stamps) < 2:
        raise BagError('fewer than two moments with the poses of all robots recorded')
    q = np.array([[poses[stamp][i] for i in range(n)] for stamp in stamps])
    u = np.zeros((len(stamps), n, dim))
    for i in range(1, n + 1):
        commands = {}
        for _, message in recorded.get(names.robot_topic(i, names.CMD_VEL), []):
            commands[stamp_to_ns(message.header.stamp)] = velocity_of(message, dim)
        if not commands:
            continue
        known = np.array(sorted(commands))
        index = np.searchsorted(known, stamps, side='right') - 1
        values = np.array([commands[int(k)] for k in known])
        u[:, i - 1] = np.where((index >= 0)[:, None], values[np.maximum(index, 0)], 0.0)
    frames, source = _frames_at(stamps, recorded.get(names.REFERENCE, []), config)
    trajectory = Trajectory.from_frames(np.array(stamps) / NS_PER_S, q, u, frames,
                                        config.vertices)
    return trajectory, {'reference_source': source}


def plant_status(recorded: Recorded) -> Dict[str, int]:
    """
    Return the counters of the plant's last /diagnostics status, or {}.

    Keys as in ``plant_stats.json`` (``stale_command_steps``...): the status's keys
    (``stale command steps``) with underscores.
    """
    wanted = ('collisions', 'bound_violations', 'stale_command_steps', 'bad_command_steps',
              'missing_command_steps', 'steps')
    for _, message in reversed(recorded.get(names.DIAGNOSTICS, [])):
        for status in message.status:
            if status.name == 'formation_ros/plant':
                return {key: int(kv.value) for kv in status.values
                        for key in [kv.key.replace(' ', '_')] if key in wanted}
    return {}
