# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""The admission rules and the refusal counter (no ROS)."""

import math

from formation_ros.core.rules.admission import poses_refusal, Reason, refusal, Refusals
import numpy as np

UNIT = (0.0, 0.0, 0.0, 1.0)


def test_the_frame_is_looked_at_before_the_values_and_the_values_before_the_orientation():
    assert refusal('map', 'world', finite=False, oriented=False) is Reason.FRAME
    assert refusal('world', 'world', finite=False, oriented=False) is Reason.NON_FINITE
    assert refusal('world', 'world', finite=True, oriented=False) is Reason.ORIENTATION
    assert refusal('world', 'world', finite=True) is None


def test_poses_are_refused_for_their_orientation_only_where_it_is_needed():
    positions = np.zeros((2, 3))
    zero = np.array([UNIT, (0.0, 0.0, 0.0, 0.0)])
    assert poses_refusal('world', 'world', positions, zero, needs_orientation=True) \
        is Reason.ORIENTATION
    assert poses_refusal('world', 'world', positions, zero, needs_orientation=False) is None
    nan = np.array([UNIT, (math.nan, 0.0, 0.0, 1.0)])
    assert poses_refusal('world', 'world', positions, nan, needs_orientation=True) \
        is Reason.NON_FINITE
    assert poses_refusal('world', 'world', positions, nan, needs_orientation=False) is None


def test_non_finite_positions_are_refused_and_the_inputs_are_not_changed():
    positions = np.array([[0.0, math.inf, 0.0]])
    orientations = np.array([UNIT])
    before = positions.copy(), orientations.copy()
    assert poses_refusal('world', 'world', positions, orientations, True) is Reason.NON_FINITE
    np.testing.assert_array_equal(positions, before[0])
    np.testing.assert_array_equal(orientations, before[1])


def test_refusals_are_counted_by_source_and_reason():
    refusals = Refusals()
    assert refusals.add('pose', Reason.FRAME) == 1
    assert refusals.add('pose', Reason.FRAME) == 2
    assert refusals.add(3, Reason.FRAME) == 1
    refusals.add('pose', Reason.CLOCK)
    assert refusals.count() == 4
    assert refusals.count(source='pose') == 3
    assert refusals.count(reason=Reason.FRAME) == 3
    assert refusals[('pose', Reason.FRAME)] == 2
    assert ('pose', Reason.MALFORMED) not in refusals
    assert refusals.get(('pose', Reason.MALFORMED)) == 0
    assert [key for key, _ in refusals.items()] == [('pose', Reason.FRAME), (3, Reason.FRAME),
                                                    ('pose', Reason.CLOCK)]
