# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
Numbers that show the controller kept its promises, from sampled runs (Section 5).

Inputs are sampled trajectories: t (T,) in s, q and q_desired (T, N, dim) in m, u and u_hat
(T, N, dim) in m/s (NaN rows: commands the run cannot tell, ``core.runs.trajectory``). The same
functions serve ``formation_sim`` and the bag report.
"""

import math
from typing import Any, List, Mapping, Optional, Sequence

from formation_ros.core.maths.pairs import closest_pair
from formation_ros.core.maths.unicycle import command_bounds
from formation_ros.core.runs.events import Event, segments
from formation_ros.core.runs.trajectory import Trajectory
import numpy as np
from numpy.typing import ArrayLike, NDArray

SETTLE_TOLERANCE = 0.05
DIS_ALL_MAX_SAMPLES = 400
DIS_ALL_BLOCK = 128
DIS_MIN_GUESS = 1.5
"""dis_min of a sample is searched first within this many times the sample's before."""
DIS_ALL_MAX_ROBOTS = 2000


def formation_errors(q: ArrayLike, q_desired: ArrayLike) -> NDArray[np.float64]:
    """Distance of each robot from its desired place, ||q_i - q_i,desired||: (T, N) in m."""
    diff = np.asarray(q, dtype=float) - np.asarray(q_desired, dtype=float)
    errors: NDArray[np.float64] = np.sqrt(np.einsum('...d,...d->...', diff, diff))
    return errors


def settle_time(t: ArrayLike, errors: ArrayLike,
                tolerance: float = SETTLE_TOLERANCE) -> Optional[float]:
    """
    First sample time after which every error stays <= tolerance; None if never.

    t: (T,); errors: (T, N). Measured on the samples, so its resolution is the sample spacing.
    """
    times = np.asarray(t)
    outside = np.any(np.asarray(errors) > tolerance, axis=1)
    if not np.any(outside):
        return float(times[0])
    last = int(np.nonzero(outside)[0][-1])
    return None if last == len(times) - 1 else float(times[last + 1])


def closest_pair_distance(points: ArrayLike) -> float:
    """Smallest distance between two of the points (N, dim) (``maths.pairs``); inf for N < 2."""
    return closest_pair(points)[0]


def dis_min_series(q: ArrayLike) -> NDArray[np.float64]:
    """dis_min of Section 5 at each sample: the closest pair distance, (T,) in m."""
    series = np.asarray(q, dtype=float)
    distances = np.empty(len(series))
    previous = 0.0
    for k, sample in enumerate(series):
        distances[k] = previous = closest_pair(sample, DIS_MIN_GUESS * previous)[0]
    return distances


def dis_all(points: ArrayLike) -> float:
    """
    Return dis_all of Section 5, the geometric mean of ||q_ij|| (docs/equations.md, slip 7).

    Over every pair i < j, log ||q_ij|| = log(||q_ij||**2) / 2, DIS_ALL_BLOCK rows of pairs at a
    time (numpy only); NaN for N < 2.
    """
    q = np.asarray(points, dtype=float)
    n = len(q)
    if n < 2:
        return math.nan
    total = 0.0
    with np.errstate(divide='ignore'):
        for first in range(0, n - 1, DIS_ALL_BLOCK):
            rows = np.arange(first, min(first + DIS_ALL_BLOCK, n - 1))
            diff = q[rows, None, :] - q[None, first + 1:, :]
            later = np.arange(first + 1, n)[None, :] > rows[:, None]
            total += 0.5 * float(np.sum(np.log(np.einsum('ikd,ikd->ik', diff, diff)[later])))
    return float(np.exp(total / (0.5 * n * (n - 1))))


def dis_all_series(t: ArrayLike,
                   q: ArrayLike) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """
    dis_all over time: (times (K,), values (K,)), thinned to at most 400 samples.

    Empty arrays when N > 2000 (N**2 / 2 distances per sample would dominate the run).
    """
    times, positions = np.asarray(t), np.asarray(q)
    if positions.shape[1] > DIS_ALL_MAX_ROBOTS:
        return np.empty(0), np.empty(0)
    count = min(len(times), DIS_ALL_MAX_SAMPLES)
    index = np.unique(np.linspace(0, len(times) - 1, count).astype(int))
    return times[index], np.array([dis_all(positions[k]) for k in index])


def largest_component(values: ArrayLike) -> Optional[float]:
    """Return the largest |component| of (..., dim) values, NaN left out; None if all are NaN."""
    magnitudes = np.abs(np.asarray(values, dtype=float))
    known = magnitudes[~np.isnan(magnitudes)]
    return float(np.max(known)) if known.size else None


def unknown_commands(values: ArrayLike) -> int:
    """Return how many (sample, robot) commands (..., dim) are unknown (a NaN component)."""
    return int(np.count_nonzero(np.any(np.isnan(np.asarray(values, dtype=float)), axis=-1)))


def above(values: ArrayLike, bound: float) -> int:
    """Return how many components of ``values`` exceed ``bound`` (beyond rounding); NaN not."""
    magnitudes = np.abs(np.asarray(values, dtype=float))
    return int(np.count_nonzero(magnitudes > bound * (1.0 + 1e-12)))


def held_metrics(u_hat_held: ArrayLike, u_bound: float) -> dict[str, Any]:
    """
    Return the metrics.json keys of u_hat_held (``core.runs.trajectory``): (T, N, dim) m/s.

    The held command read at the body's heading at each sample is u_hat turned by the heading
    turned since the state it answered; a rotation keeps the Euclidean norm, so its components
    stay within sqrt(2) c M1 (``u_hat_held_bound``), not c M1 (u_bound, m/s).
    """
    bound = math.sqrt(2.0) * u_bound
    return {'max_abs_u_hat_held_component': largest_component(u_hat_held),
            'u_hat_held_bound': bound,
            'u_hat_held_above_bound': above(u_hat_held, bound)}


def compute_metrics(t: ArrayLike, q: ArrayLike, u: ArrayLike, u_hat: ArrayLike,
                    q_desired: ArrayLike, u_bound: float,
                    extra: Optional[Mapping[str, Any]] = None) -> dict[str, Any]:
    """
    Return the metrics.json dictionary of a run.

    u_bound: c * M1 (m/s), the bound every component of u_hat must keep; with a fixed reference
    u equals u_hat. extra: more keys to merge (e.g. reference kind, integrator). Commands the
    run cannot tell (NaN) are left out of the maxima (None if every one is) and counted under
    ``unknown_commands``, a key only present when there are some.
    """
    times = np.asarray(t, dtype=float)
    positions = np.asarray(q, dtype=float)
    errors = formation_errors(positions, q_desired)
    settle = settle_time(times, errors)
    bounded = np.asarray(u_hat, dtype=float)
    unknown = unknown_commands(bounded)
    num_robots, dim = positions.shape[1], positions.shape[2]
    metrics: dict[str, Any] = {
        'num_robots': int(num_robots),
        'dim': int(dim),
        'duration': float(times[-1] - times[0]),
        'num_samples': int(len(times)),
        'min_pair_distance': float(np.min(dis_min_series(positions))),
        'dis_all_final': (dis_all(positions[-1]) if num_robots <= 4 * DIS_ALL_MAX_ROBOTS
                          else None),
        'final_max_error': float(np.max(errors[-1])),
        'final_mean_error': float(np.mean(errors[-1])),
        'settle_tolerance': SETTLE_TOLERANCE,
        'settle_time': settle,
        'max_abs_u_component': largest_component(u),
        'max_abs_u_hat_component': largest_component(bounded),
        'u_bound': float(u_bound),
        'bound_violations': above(bounded, u_bound),
    }
    if unknown:
        metrics['unknown_commands'] = unknown
    metrics.update(extra or {})
    return metrics


def body_metrics(q_body: ArrayLike, body_command: ArrayLike, u_bound: float,
                 hand_distance: float, body_radius: float) -> dict[str, Any]:
    """
    Return the metrics.json keys of a unicycle run (docs/equations.md, U5 and U6).

    q_body: (T, N, 2) axle centres, m; body_command: (T, N, 2) (v, w) held, m/s and rad/s;
    u_bound: c * M1, m/s; hand_distance: l, m; body_radius: m. ``v_bound`` and
    ``omega_bound`` are sqrt(2) c M1 and sqrt(2) c M1 / l, what the law's bounded part can ask
    for; ``min_body_distance`` is the closest approach of two axle centres (bodies touch
    below twice the radius).
    """
    commands = np.asarray(body_command, dtype=float)
    v_bound, omega_bound = command_bounds(u_bound, hand_distance)
    return {
        'body_kind': 'unicycle',
        'hand_distance': float(hand_distance),
        'body_radius': float(body_radius),
        'min_body_distance': float(np.min(dis_min_series(q_body))),
        'max_abs_v': float(np.max(np.abs(commands[..., 0]))),
        'max_abs_omega': float(np.max(np.abs(commands[..., 1]))),
        'v_bound': v_bound,
        'omega_bound': omega_bound,
    }


def segment_metrics(trajectory: Trajectory, events: Sequence[Event],
                    tolerance: float = SETTLE_TOLERANCE) -> List[dict[str, Any]]:
    """
    Return the metrics of each segment of the run between its events (``core.runs.events``).

    One dictionary per segment, in time order; [] without events. Keys: ``start``, ``end`` (s);
    ``kind`` (the opening event's kind value, None before the first event) and ``label``;
    ``num_samples``; ``settle_time``: s after ``start`` from which every error stays <=
    ``tolerance`` to the segment's end (as :func:`settle_time` on the segment's samples; None
    if it never does); ``min_pair_distance``: closest approach of two control points (m);
    ``min_body_distance`` for unicycles: of two axle centres (m); ``max_abs_u_hat_component``
    (m/s) and ``final_max_error`` (m, at the segment's last sample). A segment without samples
    has None for the measured values. The errors are against ``trajectory.q_desired``: pass the
    trajectory of ``events.with_shapes`` for the shape in force.
    """
    errors = formation_errors(trajectory.q, trajectory.q_desired)
    times = np.asarray(trajectory.t, dtype=float)
    rows = []
    for part in segments(times, events):
        row: dict[str, Any] = {
            'start': part.start, 'end': part.end,
            'kind': None if part.opened_by is None else part.opened_by.kind.value,
            'label': 'start of the run' if part.opened_by is None else part.opened_by.label,
            'num_samples': part.stop - part.first,
            'settle_time': None, 'min_pair_distance': None,
            'max_abs_u_hat_component': None, 'final_max_error': None}
        if trajectory.q_body is not None:
            row['min_body_distance'] = None
        if part.stop > part.first:
            span = slice(part.first, part.stop)
            settled = settle_time(times[span], errors[span], tolerance)
            row.update({
                'settle_time': None if settled is None else settled - part.start,
                'min_pair_distance': float(np.min(dis_min_series(trajectory.q[span]))),
                'max_abs_u_hat_component': largest_component(trajectory.u_hat[span]),
                'final_max_error': float(np.max(errors[part.stop - 1]))})
            if trajectory.q_body is not None:
                row['min_body_distance'] = float(np.min(dis_min_series(trajectory.q_body[span])))
        rows.append(row)
    return rows
