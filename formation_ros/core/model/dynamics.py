# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
Bodies that are not q' = u: actuator lag, acceleration limits, noisy and late sensing.

The paper's theorem assumes the ideal body of eq. (1): the velocity is the command, at once, and
every robot senses exact positions without delay. A real base lags its command, cannot
accelerate without limit, and its localisation is noisy and late. These settings (beyond the
paper: it proves nothing for them) describe such bodies for the one plant model
(``core.model.plant``), so that ``formation_sim --dt`` and the plant node both have them. Every
value 0 is the ideal body, and then the model does exactly what it did without them.

The body (docs/equations.md, "Beyond the paper: non-ideal bodies", D1 to D4). With tau =
``actuator_lag`` and a = ``max_acceleration``, every component of the body's velocity v (the
world velocity of a point; v and w of a unicycle) follows the admitted command u, held over a
step (zero-order hold), by::

    v' = clip((u - v) / tau, -a, a)                                              (D1)

(tau = 0: v' = a sign(u - v) until v = u; a = 0: no limit, v' = (u - v) / tau). With u held
this has a closed form over a step (:func:`lagged_velocity`): while ``|u - v| > a tau`` the body
accelerates at a (a ramp, for ``t1 = (|u - v| - a tau) / a``), then the gap decays as
``e^(-t / tau)``. Both the velocity and its integral (the displacement) are exact, so points are
stepped exactly (:func:`point_step`, D2). A unicycle integrates (U1) with its lagged (v, w)
(:func:`unicycle_step`, D3): the heading change is the exact integral of w; the position is
advanced over :data:`UNICYCLE_SUBSTEPS` substeps, each the exact arc of the substep's mean v and
mean w (exact integrals), which is second order in the substep h = dt / UNICYCLE_SUBSTEPS:
local error O(h^3) (|v'| |w| + |v| |w'|), global O(h^2).

Sensing (D4): each state's positions are sensed with Gaussian noise of ``pose_noise`` m per
component, one draw per body per state, from ``np.random.default_rng([seed,
NOISE_SEED_OFFSET])``; a state reaches the robots ``state_delay`` s later, rounded to whole steps
(:meth:`Imperfections.delay_steps`), stamped with the time it was measured.
"""

from dataclasses import asdict, dataclass
from typing import Dict, Tuple

from formation_ros.core.maths.unicycle import heading_vectors
from formation_ros.core.maths.units import NS_PER_S
import numpy as np
from numpy.typing import ArrayLike, NDArray

Float = NDArray[np.float64]
NOISE_SEED_OFFSET = 2
"""Pose noise comes from the generator seeded with (start.seed, this): the random start of a
seed (start.seed alone) and its random headings (offset 1) stay what they are without noise."""
UNICYCLE_SUBSTEPS = 8
"""Substeps of a unicycle step with a lagged (v, w): each the exact arc of its mean v and w."""


@dataclass(frozen=True)
class Imperfections:
    """
    What separates the bodies from the ideal q' = u (``plant.*``; all 0: ideal).

    actuator_lag: time constant tau of the first-order lag v' = (u - v) / tau between the
    admitted command u and the body's velocity v, s; max_acceleration: limit on |v'| per
    world component for points, on v' and w' for unicycles, m/s^2 (rad/s^2 for w); pose_noise:
    standard deviation of Gaussian noise on every sensed position, m; state_delay: a state
    reaches the robots this much after it happened, s; seed: seed of the noise (start.seed).
    """

    actuator_lag: float = 0.0
    max_acceleration: float = 0.0
    pose_noise: float = 0.0
    state_delay: float = 0.0
    seed: int = 0

    @property
    def ideal_body(self) -> bool:
        """Tell whether the body's velocity is its command at once (no lag, no limit)."""
        return self.actuator_lag == 0.0 and self.max_acceleration == 0.0

    @property
    def ideal_sensing(self) -> bool:
        """Tell whether every robot senses exact positions at once."""
        return self.pose_noise == 0.0 and self.state_delay == 0.0

    @property
    def is_ideal(self) -> bool:
        """Tell whether this is the paper's body, q' = u sensed exactly and at once."""
        return self.ideal_body and self.ideal_sensing

    def delay_steps(self, step_ns: int) -> int:
        """Return ``state_delay`` in whole steps of ``step_ns`` ns (rounded to the nearest)."""
        return int(round(self.state_delay * NS_PER_S / step_ns))

    def as_dict(self) -> Dict[str, float]:
        """Return the four settings by parameter name (for metrics.json, plant_stats.json)."""
        values = asdict(self)
        return {f'plant.{name}': float(values[name])
                for name in ('actuator_lag', 'max_acceleration', 'pose_noise', 'state_delay')}

    def noise_generator(self) -> np.random.Generator:
        """Return the generator of the pose noise, seeded with (seed, NOISE_SEED_OFFSET)."""
        return np.random.default_rng([self.seed, NOISE_SEED_OFFSET])


IDEAL = Imperfections()


def lagged_velocity(velocity: ArrayLike, command: ArrayLike, dt: ArrayLike, lag: float,
                    max_acceleration: float) -> Tuple[Float, Float]:
    """
    Exact solution of (D1) over dt with the command held: (velocity at dt, its integral).

    velocity, command: equal shapes (any), per component (m/s, or rad/s for w); dt: s, a
    number or an array that broadcasts with them (several durations at once); lag: s;
    max_acceleration: a per component (0: none). Not both lag and max_acceleration 0 (the
    ideal body has no velocity state). With e = u - v, the body ramps at a for
    ``t1 = max(|e| - a tau, 0) / a``, then ``e(t) = e(t1) e^(-(t - t1) / tau)``; returns
    ``(u - e(dt), u dt - integral of e over [0, dt])``.
    """
    v = np.asarray(velocity, dtype=float)
    u = np.asarray(command, dtype=float)
    gap = u - v
    size = np.abs(gap)
    sign = np.sign(gap)
    if max_acceleration > 0.0:
        a = float(max_acceleration)
        ramp_end = np.maximum(size - a * lag, 0.0) / a
        ramp = np.minimum(ramp_end, dt)
        size_after = np.where(ramp >= ramp_end, np.minimum(size, a * lag), size - a * ramp)
        ramped = size * ramp - 0.5 * a * ramp * ramp
    else:
        ramp = np.zeros_like(size)
        size_after = size
        ramped = np.zeros_like(size)
    rest = dt - ramp
    if lag > 0.0:
        decayed = -np.expm1(-rest / lag)
        size_end = size_after * (1.0 - decayed)
        integral = ramped + size_after * lag * decayed
    else:
        size_end = size_after
        integral = ramped + size_after * rest
    return u - sign * size_end, u * dt - sign * integral


def point_step(q: ArrayLike, velocity: ArrayLike, command: ArrayLike, dt: float, lag: float,
               max_acceleration: float) -> Tuple[Float, Float]:
    """
    Exact step of points with a lagged velocity (D2): (q at dt, velocity at dt).

    q, velocity, command: (N, dim) in m, m/s, m/s (world frame, per component).
    """
    v_end, displacement = lagged_velocity(velocity, command, dt, lag, max_acceleration)
    return np.asarray(q, dtype=float) + displacement, v_end


def unicycle_step(q: ArrayLike, heading: ArrayLike, velocity: ArrayLike, command: ArrayLike,
                  dt: float, lag: float, max_acceleration: float,
                  substeps: int = UNICYCLE_SUBSTEPS) -> Tuple[Float, Float, Float]:
    """
    Step unicycles (U1) whose (v, w) lag the command (D3): (q, heading, (v, w)) at dt.

    q: (N, 2) m; heading: (N,) rad; velocity, command: (N, 2) (v, w) in m/s and rad/s. The
    heading turns by the exact integral of w; the axle moves along ``substeps`` exact arcs, each
    with the mean v and w of its substep (second order in dt / substeps). The velocities and
    their integrals at the substeps' ends come from the closed form of (D1) at once.
    """
    h = dt / substeps
    ends = h * np.arange(1, substeps + 1).reshape(-1, 1, 1)
    v = np.asarray(velocity, dtype=float)
    speeds, moved = lagged_velocity(v, command, ends, lag, max_acceleration)
    before = np.concatenate([np.zeros_like(moved[:1]), moved[:-1]])
    mean = (moved - before) / h
    th = np.asarray(heading, dtype=float)
    half = 0.5 * h * mean[..., 1]
    chords = h * mean[..., 0] * np.sinc(half / np.pi)
    arcs = chords[..., None] * heading_vectors(th + before[..., 1] + half)
    return np.asarray(q, dtype=float) + arcs.sum(axis=0), th + moved[-1, :, 1], speeds[-1]
