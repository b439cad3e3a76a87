# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""Events of a run (core/runs/events.py) and its per-segment metrics (core/runs/metrics.py)."""

import itertools
import math

from formation_ros.core.maths.frames import FrameSample, stationary_frame
from formation_ros.core.runs.events import (Event, EventKind, segments, shape_in_force, stopped_at,
                                            with_shapes)
from formation_ros.core.runs.metrics import segment_metrics
from formation_ros.core.runs.trajectory import Trajectory
import numpy as np
import pytest

WEDGE = np.array([[0.0, 4.0], [0.0, 0.0]])
LINE = np.array([[5.0, 0.0], [0.0, 0.0]])


def test_an_event_is_checked_and_its_vertices_frozen():
    vertices = LINE.copy()
    event = Event(1.0, EventKind.SHAPE, 'line', vertices)
    vertices[0, 0] = 99.0
    assert event.vertices[0, 0] == 5.0
    with pytest.raises(ValueError):
        event.vertices[0, 0] = 1.0
    for bad in (lambda: Event(1.0, EventKind.SHAPE, 'none'),
                lambda: Event(1.0, EventKind.STOP, 'stop', LINE),
                lambda: Event(math.nan, EventKind.START, 'start'),
                lambda: Event(1.0, EventKind.SHAPE, 'nan', [[math.nan, 0.0]]),
                lambda: Event(1.0, EventKind.SHAPE, 'flat', [1.0, 2.0]),
                lambda: Event(1.0, 'stop', 'stop')):
        with pytest.raises(ValueError):
            bad()


def test_the_shape_and_the_team_state_in_force_at_a_time():
    events = [Event(4.0, EventKind.SHAPE, 'wedge', WEDGE), Event(2.0, EventKind.STOP, 'stop'),
              Event(1.0, EventKind.SHAPE, 'line', LINE), Event(3.0, EventKind.START, 'start')]
    assert shape_in_force(events, 0.5) is None and not stopped_at(events, 0.5)
    assert shape_in_force(events, 1.0).label == 'line'
    assert shape_in_force(events, 3.99).label == 'line'
    assert shape_in_force(events, 4.0).label == 'wedge'
    assert [stopped_at(events, t) for t in (1.99, 2.0, 2.5, 3.0, 9.0)] == \
        [False, True, True, False, False]


def rotation(angle):
    """Return J of a formation frame turned by ``angle`` (J rotates world -> frame)."""
    c, s = math.cos(angle), math.sin(angle)
    return np.array([[c, s], [-s, c]])


def test_desired_positions_come_from_the_shape_in_force():
    t = np.arange(6) / 2.0
    q = np.zeros((6, 2, 2))
    original = np.full((6, 2, 2), 7.0)
    trajectory = Trajectory(t=t, q=q, u=q, u_hat=q, q_desired=original.copy(),
                            q_od=np.zeros((6, 2)))
    origin = np.array([1.0, -2.0])
    angles = t * 0.3
    frames = [FrameSample(float(s), origin, np.zeros(2), rotation(a), np.zeros((2, 2)))
              for s, a in zip(t, angles)]
    events = [Event(1.0, EventKind.SHAPE, 'wedge', WEDGE), Event(1.5, EventKind.STOP, 'stop')]
    shaped = with_shapes(trajectory, events, frames)
    assert np.array_equal(trajectory.q_desired, original)
    assert np.array_equal(shaped.q_desired[:2], original[:2])
    for k in range(2, 6):
        for i in range(2):
            x, y = WEDGE[i]
            c, s = math.cos(angles[k]), math.sin(angles[k])
            expected = origin + np.array([c * x - s * y, s * x + c * y])
            assert shaped.q_desired[k, i] == pytest.approx(expected, abs=1e-12)
    assert with_shapes(trajectory, events[1:], frames) is trajectory
    with pytest.raises(ValueError):
        with_shapes(trajectory, [Event(1.0, EventKind.SHAPE, 'three', np.zeros((3, 2)))],
                    frames)
    with pytest.raises(ValueError):
        with_shapes(trajectory, events, frames[:3])


def test_segments_cut_the_samples_at_the_events():
    t = np.arange(11, dtype=float)
    events = [Event(6.0, EventKind.SHAPE, 'wedge', WEDGE), Event(2.5, EventKind.STOP, 'stop'),
              Event(12.0, EventKind.START, 'after the end')]
    parts = segments(t, events)
    assert [(p.start, p.end, p.first, p.stop) for p in parts] == \
        [(0.0, 2.5, 0, 3), (2.5, 6.0, 3, 6), (6.0, 10.0, 6, 11)]
    assert [p.opened_by for p in parts] == [None, events[1], events[0]]
    assert segments(t, []) == [] and segments(t, events[2:]) == []
    together = segments(t, [Event(0.0, EventKind.STOP, 'stop'),
                            Event(0.0, EventKind.START, 'start')])
    assert [(p.first, p.stop, p.opened_by.label) for p in together] == \
        [(0, 0, 'stop'), (0, 11, 'start')]


TAU = 0.5
FIRST, SECOND = 2.0, 1.0
"""Initial errors of robot 1 in the segments [0, 4) and [4, 10]; it decays as exp(-t / TAU)."""


def exponential_run(heading=None):
    """
    Robot 2 holds its desired place; robot 1 approaches its own along the line to robot 2.

    Before t = 4 the shape is LINE (places 5 m apart), from t = 4 WEDGE (4 m apart); the
    error of robot 1 is FIRST exp(-t / TAU), then SECOND exp(-(t - 4) / TAU). Samples every
    0.01 s from 0 to 10 s. Returns the trajectory (q_desired of LINE throughout, as a record
    made before the switch was known) and the events.
    """
    t = np.arange(1001) / 100.0
    switched = t >= 4.0
    error = np.where(switched, SECOND * np.exp(-(t - 4.0) / TAU), FIRST * np.exp(-t / TAU))
    shape = np.where(switched[:, None, None], WEDGE, LINE)
    toward = shape[:, 1] - shape[:, 0]
    toward /= np.linalg.norm(toward, axis=1)[:, None]
    q = shape.copy()
    q[:, 0] += error[:, None] * toward
    u_hat = np.zeros_like(q)
    u_hat[:, 0] = -error[:, None] / TAU * toward
    body = {}
    if heading is not None:
        headings = np.broadcast_to(heading, (len(t), 2)).copy()
        body = {'heading': headings, 'q_body': q - 0.1 * np.stack([np.cos(headings),
                                                                   np.sin(headings)], -1),
                'body_command': np.zeros_like(q)}
    trajectory = Trajectory(t=t, q=q, u=u_hat, u_hat=u_hat,
                            q_desired=np.broadcast_to(LINE, q.shape).copy(),
                            q_od=np.zeros((len(t), 2)), **body)
    events = [Event(4.0, EventKind.SHAPE, 'wedge', WEDGE), Event(7.0, EventKind.STOP, 'stop')]
    return trajectory, events


def first_sample_after(start, delay):
    """Return the first sample time (0.01 s apart) at or after start + delay."""
    return math.ceil((start + delay) * 100.0 - 1e-9) / 100.0


def brute_min_distance(points):
    return min(math.dist(p[i], p[j]) for p in points
               for i, j in itertools.combinations(range(len(p)), 2))


def test_segment_metrics_of_an_exponential_approach():
    trajectory, events = exponential_run()
    frames = [stationary_frame(2, t=float(s)) for s in trajectory.t]
    rows = segment_metrics(with_shapes(trajectory, events, frames), events)
    assert [(r['start'], r['end'], r['kind'], r['label'], r['num_samples']) for r in rows] == \
        [(0.0, 4.0, None, 'start of the run', 400), (4.0, 7.0, 'shape', 'wedge', 300),
         (7.0, 10.0, 'stop', 'stop', 301)]
    tolerance = 0.05
    settle = [first_sample_after(0.0, TAU * math.log(FIRST / tolerance)),
              first_sample_after(4.0, TAU * math.log(SECOND / tolerance)) - 4.0, 0.0]
    for row, expected in zip(rows, settle):
        assert row['settle_time'] == pytest.approx(expected, abs=1e-9)
    assert settle[0] == pytest.approx(1.85) and settle[1] == pytest.approx(1.5)
    assert rows[0]['min_pair_distance'] == pytest.approx(5.0 - FIRST, abs=1e-12)
    assert rows[1]['min_pair_distance'] == pytest.approx(4.0 - SECOND, abs=1e-12)
    assert rows[2]['min_pair_distance'] == pytest.approx(
        4.0 - SECOND * math.exp(-3.0 / TAU), abs=1e-12)
    assert rows[0]['max_abs_u_hat_component'] == pytest.approx(FIRST / TAU)
    assert rows[1]['max_abs_u_hat_component'] == pytest.approx(SECOND / TAU)
    assert rows[0]['final_max_error'] == pytest.approx(FIRST * math.exp(-3.99 / TAU))
    assert rows[2]['final_max_error'] == pytest.approx(SECOND * math.exp(-6.0 / TAU))
    assert 'min_body_distance' not in rows[0]
    unshaped = segment_metrics(trajectory, events)
    assert unshaped[1]['settle_time'] is None, 'against LINE robot 1 is metres off after t = 4'
    assert segment_metrics(trajectory, []) == []


def test_segment_metrics_of_unicycles_measure_the_bodies_too():
    trajectory, events = exponential_run(heading=np.array([0.0, math.pi / 2]))
    rows = segment_metrics(trajectory, events)
    for row, (first, stop) in zip(rows, [(0, 400), (400, 700), (700, 1001)]):
        assert row['min_body_distance'] == pytest.approx(
            brute_min_distance(trajectory.q_body[first:stop]), abs=1e-12)
        assert row['min_body_distance'] != pytest.approx(row['min_pair_distance'])


def test_a_segment_without_samples_has_no_measurements():
    trajectory, _ = exponential_run()
    rows = segment_metrics(trajectory, [Event(4.001, EventKind.STOP, 'stop'),
                                        Event(4.005, EventKind.START, 'start')])
    assert rows[1]['num_samples'] == 0
    assert all(rows[1][key] is None for key in ('settle_time', 'min_pair_distance',
                                                'max_abs_u_hat_component', 'final_max_error'))
    assert rows[2]['num_samples'] == 1001 - 401
