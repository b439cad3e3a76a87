# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""The reference as a robot follows it: the samples it admits, the frame at a state's stamp."""

from dataclasses import dataclass, replace
import os
from typing import Tuple

from formation_ros.core.maths.frames import frame_to_pose, FrameSample
from formation_ros.core.maths.units import NS_PER_S
from formation_ros.core.rules.admission import Reason
from formation_ros.core.rules.reference_track import OTHER_IN_ROW, ReferenceTrack
from formation_ros.core.runs.timeline import Mode, ReferenceTimeline, TeamState, Timeline
from formation_ros.core.settings.params import load_params_file, validate
import numpy as np
import pytest

SQUARE = os.path.join(os.path.dirname(__file__), '..', '..', 'config', 'square_4.yaml')

TIMEOUT = NS_PER_S // 2


@dataclass(frozen=True)
class Sample:
    """A sample as ``ros.cdr.OdometryData`` reads one (what the track needs of it)."""

    stamp_ns: int
    frame_id: str
    linear: Tuple[float, float, float]
    angular: Tuple[float, float, float]
    carried: FrameSample

    @property
    def finite(self):
        return bool(np.all(np.isfinite(self.carried.q_od)) and np.all(np.isfinite(self.linear)))

    def frame(self, dim):
        return self.carried


def circle():
    values = load_params_file(SQUARE)
    values.update({'reference.kind': 'circle', 'reference.radius': 1.0,
                   'reference.speed': 0.5})
    config = validate(values)
    base = config.reference()
    states = Timeline(TeamState.of(Mode.RUNNING, config.shape_name, base))
    return ReferenceTimeline(base, states), base.rate_limits()


def sample_of(timeline, stamp_s, shift=0.0, frame='world'):
    stamp = int(round(stamp_s * NS_PER_S))
    mine = timeline.frame_at(stamp)
    moved = FrameSample(mine.t, mine.q_od + shift, mine.qdot_od, mine.J, mine.Jdot)
    speed = tuple(np.pad(mine.qdot_od, (0, 3 - len(mine.qdot_od))))
    return Sample(stamp, frame, speed, (0.0, 0.0, 0.5), moved)


@pytest.fixture
def track():
    timeline, limits = circle()
    return ReferenceTrack(timeline, 2, 'world', limits, evaluates=True, timeout_ns=TIMEOUT)


def never():
    return False


def test_samples_unlike_the_frame_are_refused_and_logged_only_when_two_in_a_row(track):
    state = 5 * NS_PER_S
    timeline = track.timeline
    assert track.refusal(sample_of(timeline, 5.0), state, never) is None
    first = track.refusal(sample_of(timeline, 5.02, 0.5), state, never)
    assert first.reason is Reason.OTHER_REFERENCE and not first.log
    assert track.refusal(sample_of(timeline, 5.04), state, never) is None
    assert not track.refusal(sample_of(timeline, 5.06, 0.5), state, never).log
    assert OTHER_IN_ROW == 2
    assert track.refusal(sample_of(timeline, 5.08, 0.5), state, never).log
    assert track.refusal(sample_of(timeline, 5.10), state, never) is None
    assert len(track.samples) == 3


def test_a_sample_ahead_of_its_change_is_looked_at_again_after_taking_the_changes(track):
    moved = sample_of(track.timeline, 5.0, 0.5)
    taken = []

    def catch_up():
        taken.append(1)
        return False

    assert track.refusal(moved, 5 * NS_PER_S, catch_up).reason is Reason.OTHER_REFERENCE
    assert taken


def test_a_sample_far_from_the_states_is_another_clock_not_another_reference(track):
    """A reference on the wall clock beside a plant: its samples are kept, then refused in use."""
    wall = sample_of(track.timeline, 1.7e9)
    for state in (0, 5 * NS_PER_S):
        assert track.refusal(wall, state, never) is None
    assert track.others_in_row == 0
    frame, gap = track.frame_at(5 * NS_PER_S, False, True, TIMEOUT)
    assert frame is None and gap == pytest.approx(1.7e9 - 5.0)


def test_before_any_state_a_sample_near_the_clock_is_checked_one_far_from_it_kept(track):
    """A robot on simulated time before its first state: its clock is 0, the plant's start."""
    near = track.refusal(sample_of(track.timeline, 0.0, 0.5), 0, never)
    assert near.reason is Reason.OTHER_REFERENCE
    assert track.refusal(sample_of(track.timeline, 1.7e9, 0.5), 0, never) is None


def test_frame_finite_and_speed_are_checked_first(track):
    timeline = track.timeline
    assert track.refusal(sample_of(timeline, 5.0, frame='map'), 0, never).reason is Reason.FRAME
    nan = sample_of(timeline, 5.0, float('nan'))
    assert track.refusal(nan, 0, never).reason is Reason.NON_FINITE
    fast = replace(sample_of(timeline, 5.0), linear=(50.0, 0.0, 0.0))
    assert track.refusal(fast, 0, never).reason is Reason.TOO_FAST
    track.widen((60.0, 1.0))
    assert track.refusal(fast, 5 * NS_PER_S, never) is None


def test_the_frame_at_a_stamp_is_evaluated_or_carried_forward(track):
    timeline = track.timeline
    assert track.frame_at(5 * NS_PER_S, False, True, TIMEOUT) == (None, None)
    heard = sample_of(timeline, 5.0, 0.25)
    track.samples.append(heard)
    evaluated, _ = track.frame_at(int(5.2 * NS_PER_S), False, True, TIMEOUT)
    assert np.allclose(evaluated.q_od, timeline.frame_at(int(5.2 * NS_PER_S)).q_od)
    assert track.frame_at(int(5.2 * NS_PER_S), True, True, TIMEOUT) == (None, None)
    exact, _ = track.frame_at(5 * NS_PER_S, True, False, TIMEOUT)
    assert exact is heard.carried
    carried, _ = track.frame_at(int(5.2 * NS_PER_S), False, False, TIMEOUT)
    assert np.allclose(carried.q_od, heard.carried.q_od + 0.2 * heard.carried.qdot_od)
    assert frame_to_pose(carried, 2) is not None
