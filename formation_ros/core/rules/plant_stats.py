# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
The plant's run statistics, without ROS: what a run gathers and ``plant_stats.json``.

:class:`RunStats` follows the steps (closest pair, largest u_hat, held steps, answer latency
by :class:`AnswerTimes`) and makes the record of ``plant_stats.json`` (:meth:`RunStats.record`;
its keys: docs/ros_interface.md, "Behaviour of the nodes", Shutdown, and docs/faults.md) and
the summary line. The model's own counters are ``core.model.plant.PlantCounts``.
:func:`trajectory_sample` is what a step gives ``core.runs.output.RunOutput``, which writes the
run into ``plant.output_dir``.
"""

from collections import OrderedDict
from typing import Any, Dict, List, Optional, Tuple

from formation_ros.core.maths.units import NS_PER_S
from formation_ros.core.model.plant import Commands, CommandStatus, PlantModel, StepReport
from formation_ros.core.rules.admission import Reason, Refusals
from formation_ros.core.rules.plant_intake import refused_by_robot, Source, TEAM
import numpy as np
from numpy.typing import ArrayLike, NDArray

PUBLISHES_TIMED = 256
"""States whose first publish time is kept for the answer latency; answers to older states are
not timed."""


class DurationHistogram:
    """
    Durations counted in bins of ``bin_ns`` up to ``limit_ns`` (longer ones in one more bin).

    Percentiles are read back as the upper edge of their bin; the largest duration is kept
    exactly. Memory is fixed however many durations are added.
    """

    def __init__(self, bin_ns: int = 100_000, limit_ns: int = 2 * NS_PER_S) -> None:
        """Count durations of 0 to ``limit_ns`` in bins ``bin_ns`` wide (default 0.1 ms, 2 s)."""
        self.bin_ns = int(bin_ns)
        self.bins = np.zeros(-(-int(limit_ns) // self.bin_ns) + 1, dtype=np.int64)
        self.largest_ns = 0

    def add(self, durations_ns: ArrayLike) -> None:
        """Count each of ``durations_ns`` (negative ones count as 0)."""
        values = np.maximum(np.asarray(durations_ns, dtype=np.int64).ravel(), 0)
        if values.size:
            np.add.at(self.bins, np.minimum(values // self.bin_ns, len(self.bins) - 1), 1)
            self.largest_ns = max(self.largest_ns, int(values.max()))

    @property
    def count(self) -> int:
        """Return how many durations were added."""
        return int(self.bins.sum())

    def percentile_ns(self, percent: float) -> Optional[int]:
        """Return the duration below which ``percent`` % of them fall (bin edge), or None."""
        total = self.count
        if total == 0:
            return None
        index = int(np.searchsorted(np.cumsum(self.bins), percent / 100.0 * total))
        if index >= len(self.bins) - 1:
            return self.largest_ns
        return min((index + 1) * self.bin_ns, self.largest_ns)

    def record(self) -> Dict[str, Optional[float]]:
        """Return count, p50_ms, p99_ms (None without durations) and max_ms."""
        percentiles = {p: self.percentile_ns(p) for p in (50, 99)}
        return {'count': self.count,
                **{f'p{p}_ms': None if ns is None else ns / 1e6 for p, ns in percentiles.items()},
                'max_ms': self.largest_ns / 1e6}


class AnswerTimes:
    """How long each command took: from its state's first publish to its arrival (steady ns)."""

    def __init__(self, num_robots: int) -> None:
        """Time the commands of ``num_robots`` robots."""
        self.published_ns: 'OrderedDict[int, int]' = OrderedDict()
        self.timed_stamp: NDArray[np.int64] = np.full(num_robots, -1, dtype=np.int64)
        self.latency = DurationHistogram()

    def published(self, stamp_ns: int, now_ns: int) -> None:
        """Note that the state stamped ``stamp_ns`` went out at ``now_ns`` (its first time)."""
        self.published_ns.setdefault(stamp_ns, now_ns)
        while len(self.published_ns) > PUBLISHES_TIMED:
            self.published_ns.popitem(last=False)

    def time(self, commands: Commands, arrived_ns: NDArray[np.int64]) -> None:
        """Count each command not timed yet whose state was published lately (arrived_ns: (N,))."""
        stamps = commands.stamp_ns
        new = np.flatnonzero(commands.present & (stamps != self.timed_stamp))
        sent = np.array([self.published_ns.get(int(stamps[i]), -1) for i in new],
                        dtype=np.int64)
        known = sent >= 0
        self.latency.add(arrived_ns[new[known]] - sent[known])
        self.timed_stamp[new] = stamps[new]


class RunStats:
    """
    What the plant gathers over a run, beyond the model's counters.

    model: the plant model at its start; publish_every: steps per published state (the
    closest distances are sampled on those); lockstep, unicycles: as configured.
    """

    def __init__(self, model: PlantModel, publish_every: int, lockstep: bool,
                 unicycles: bool) -> None:
        """Start with the start state's distances, nothing timed."""
        self.publish_every = publish_every
        self.lockstep = lockstep
        self.unicycles = unicycles
        self.closest = model.closest_pair_distance()
        """Closest pair of control points over the published states, m."""
        self.closest_body = model.closest_body_distance()
        self.largest_u_hat = 0.0
        """Largest |u_hat| component of any command as sent, m/s."""
        self.held_steps = 0
        """Steps run while the team was stopped (``/formation/status``)."""
        self.answers = AnswerTimes(model.num_robots)

    def stepped(self, model: PlantModel, report: StepReport, held: bool) -> bool:
        """
        Count the step ``model`` just made (``report``; ``held``: the team was stopped).

        Returns whether its starting state is a sample of the trajectory (one per published
        state), on which the closest distances are taken.
        """
        self.held_steps += int(held)
        self.largest_u_hat = max(self.largest_u_hat,
                                 float(np.max(report.admission.largest_u_hat)))
        sampled = (model.counts.steps - 1) % self.publish_every == 0
        if sampled:
            self.closest = min(self.closest, model.closest_pair_distance())
            self.closest_body = min(self.closest_body, model.closest_body_distance())
        return sampled

    def summary(self, model: PlantModel, wall: float, desired: ArrayLike,
                u_bound: float) -> str:
        """
        Return the line that sums the run up.

        wall: the run's wall-clock time, s; desired: (N, dim) where the control points should
        be now, m; u_bound: c M1, m/s.
        """
        totals = model.counts.totals()
        error = float(np.max(np.linalg.norm(model.points - np.asarray(desired), axis=1)))
        bodies = (f', min body distance {self.closest_body:.4g} m' if self.unicycles else '')
        return (f"plant: {totals['steps']} steps ({model.t:.2f} s simulated in {wall:.1f} s), "
                f'final max error {error:.3g} m, min pair distance {self.closest:.4g} m{bodies}, '
                f'max |u_hat| {self.largest_u_hat:.4g} m/s (bound {u_bound:.4g}), '
                f"{totals['collisions']} collisions, {totals['bound_violations']} commands above "
                f"the bound, {totals['stale_command_steps']} stale commands")

    def record(self, model: PlantModel, wall: float, refusals: 'Refusals[Source]',
               shape_changes: int, events: List[Dict[str, Any]],
               imperfections: Dict[str, float], transport: str) -> Dict[str, Any]:
        """
        Return the content of ``plant_stats.json``.

        wall: the run's wall-clock time, s; refusals: the plant's refused messages
        (``core.rules.plant_intake``); shape_changes, events: the run's (``core.runs.events``);
        imperfections: ``Imperfections.as_dict()``; transport: 'robot' or 'team'.
        """
        counts = model.counts
        totals = counts.totals()
        stats: Dict[str, Any] = {
            'integrator': f'plant, zero-order hold, dt = {model.dt:g} s'
                          + (', lockstep' if self.lockstep else ''),
            'simulated_time': model.t, 'wall_time': wall,
            'achieved_step_rate': totals['steps'] / wall if wall > 0 else None}
        stats.update(totals)
        stats['held_steps'] = self.held_steps
        stats['shape_changes'] = shape_changes
        stats['events'] = events
        stats['imperfections'] = imperfections
        stats['state_delay_steps'] = model.delay_steps
        stats['oldest_command_counted'] = counts.oldest_counted_ns / NS_PER_S
        stats['command_age_steps'] = counts.age_steps.tolist()
        stats['answer_latency'] = self.answers.latency.record()
        stats['by_robot'] = {status.name.lower(): counts.by_robot(status)
                             for status in CommandStatus if status is not CommandStatus.APPLIED}
        if self.unicycles:
            stats['min_body_distance'] = self.closest_body
        stats['wrong_frame_command_messages'] = refused_by_robot(refusals, Reason.FRAME)
        stats['malformed_command_messages'] = refused_by_robot(refusals, Reason.MALFORMED)
        stats['non_finite_command_messages'] = refused_by_robot(refusals, Reason.NON_FINITE)
        stats['transport'] = transport
        if transport == 'team':
            stats['malformed_team_command_messages'] = refusals.count(TEAM, Reason.MALFORMED)
            stats['non_finite_team_command_messages'] = refusals.count(TEAM, Reason.NON_FINITE)
        return stats


def trajectory_sample(report: StepReport, unicycles: bool) -> Tuple[
        float, NDArray[np.float64], NDArray[np.float64], Dict[str, NDArray[np.float64]]]:
    """
    Return the sample of ``trajectory.npz`` a step starts from: (t, q, u, extras).

    t: s; q: (N, dim) control points, m (hand points of unicycles); u: (N, dim) the velocity
    applied, m/s; extras, for unicycles: heading (N,) rad, q_body (N, 2) m and body_command
    (N, 2) the (v, w) applied (``core.runs.trajectory.CHUNK_EXTRAS``).
    """
    t = report.t_ns / NS_PER_S
    if not unicycles:
        return t, report.q, report.admission.velocity, {}
    return t, report.points, report.admission.velocity, {
        'heading': report.heading, 'q_body': report.q, 'body_command': report.admission.u}
