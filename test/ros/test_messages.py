# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""The plant's preallocated state messages equal messages built one by one."""

from formation_ros.core.plant import sensed_pairs
from formation_ros.ros import fields, messages
from geometry_msgs.msg import PoseArray, PoseStamped
import numpy as np
import pytest
from rclpy.serialization import deserialize_message, serialize_message
from scipy.spatial import cKDTree


def neighbour_lists(q, radii):
    observer, seen = sensed_pairs(cKDTree(q), q, radii)
    return [seen[observer == i] for i in range(len(q))]


@pytest.mark.parametrize('dim', [2, 3])
def test_state_messages_equal_messages_built_alone_at_every_fill(dim):
    rng = np.random.default_rng(dim)
    n = 7
    state = messages.StateMessages(n, dim)
    for step in range(3):
        q = rng.uniform(-2.0, 2.0, (n, dim))
        radii = np.full(n, 1.5 + step)
        seen = neighbour_lists(q, radii)
        stamp = 1_000_000_007 * (step + 1)
        poses, arrays = state.fill(q, seen, stamp)
        for i in range(n):
            alone = messages.pose_stamped(q[i], stamp, dim)
            assert poses[i] == alone
            expected = messages.pose_array(q[seen[i]], stamp, dim)
            assert arrays[i] == expected
            assert deserialize_message(serialize_message(arrays[i]), PoseArray) == expected
            assert np.array_equal(fields.points_of(arrays[i], dim), q[seen[i]])
        assert sum(len(a.poses) for a in arrays) == sum(len(s) for s in seen)


def test_fill_leaves_its_inputs_alone():
    q = np.array([[0.0, 0.0], [0.5, 0.0], [3.0, 3.0]])
    seen = neighbour_lists(q, np.ones(3))
    before = (q.copy(), [s.copy() for s in seen])
    poses, arrays = messages.StateMessages(3, 2).fill(q, seen, 5)
    assert np.array_equal(q, before[0])
    assert all(np.array_equal(a, b) for a, b in zip(seen, before[1]))
    assert isinstance(poses[0], PoseStamped) and isinstance(arrays[2], PoseArray)
    assert [len(a.poses) for a in arrays] == [1, 1, 0]
