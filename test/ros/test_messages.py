# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""The plant's state messages written as bytes equal the messages built one by one."""

from formation_ros.core.maths.sensing import sensed_pairs
from formation_ros.ros import fields, messages
from formation_ros.ros.cdr import StateEncoder
from geometry_msgs.msg import PoseArray, PoseStamped
import numpy as np
import pytest
from rclpy.serialization import deserialize_message
from scipy.spatial import cKDTree
import wire


@pytest.mark.parametrize('dim', [2, 3])
def test_encoded_states_equal_messages_built_alone_at_every_step(dim):
    rng = np.random.default_rng(dim)
    n = 7
    encoder = StateEncoder(n, dim, messages.WORLD_FRAME)
    for step in range(3):
        q = rng.uniform(-2.0, 2.0, (n, dim))
        radii = np.full(n, 1.5 + step)
        observer, seen = sensed_pairs(q, radii, cKDTree(q))
        stamp = 1_000_000_007 * (step + 1)
        poses, arrays = encoder.encode(q, observer, seen, stamp)
        assert len(poses) == len(arrays) == n
        for i in range(n):
            assert deserialize_message(poses[i], PoseStamped) == wire.pose_stamped(
                q[i], stamp, dim)
            mine = seen[observer == i]
            array = deserialize_message(arrays[i], PoseArray)
            assert array == messages.pose_array(q[mine], stamp, dim)
            assert np.array_equal(fields.points_of(array, dim), q[mine])


def test_encode_leaves_its_inputs_alone_and_lists_nobody_unseen():
    q = np.array([[0.0, 0.0], [0.5, 0.0], [3.0, 3.0]])
    observer, seen = sensed_pairs(q, np.ones(3), cKDTree(q))
    before = (q.copy(), observer.copy(), seen.copy())
    poses, arrays = StateEncoder(3, 2, messages.WORLD_FRAME).encode(q, observer, seen, 5)
    assert np.array_equal(q, before[0]) and np.array_equal(observer, before[1])
    assert np.array_equal(seen, before[2])
    assert [len(deserialize_message(a, PoseArray).poses) for a in arrays] == [1, 1, 0]
    assert all(isinstance(p, bytes) for p in poses + arrays)


@pytest.mark.parametrize('dim', [2, 3])
def test_states_are_written_little_endian_from_big_endian_arrays_too(dim):
    """The bytes are the values as '<f8', whatever the byte order of the arrays given."""
    rng = np.random.default_rng(10 + dim)
    n = 5
    q = rng.uniform(-2.0, 2.0, (n, dim))
    quaternions = rng.normal(size=(n, 4))
    quaternions /= np.linalg.norm(quaternions, axis=1)[:, None]
    observer, seen = sensed_pairs(q, np.full(n, 10.0), cKDTree(q))
    native = StateEncoder(n, dim, 'map').encode(q, observer, seen, 9, orientations=quaternions)
    big_q, big_quaternions = q.astype('>f8'), quaternions.astype('>f8')
    assert big_q.tobytes() != q.tobytes()
    swapped = StateEncoder(n, dim, 'map').encode(big_q, observer, seen, 9,
                                                 orientations=big_quaternions)
    assert swapped == native
    headings = rng.uniform(-3.0, 3.0, n)
    assert (StateEncoder(n, dim, 'map').encode(big_q, observer, seen, 9,
                                               headings=headings.astype('>f8'))
            == StateEncoder(n, dim, 'map').encode(q, observer, seen, 9, headings=headings))
    poses, arrays = swapped
    for i in range(n):
        row = np.frombuffer(poses[i][-8 * 7:], dtype='<f8')
        assert np.array_equal(row[:dim], q[i]) and np.array_equal(row[3:], quaternions[i])
        message = deserialize_message(arrays[i], PoseArray)
        assert np.array_equal(fields.points_of(message, dim), q[seen[observer == i]])
