# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
The package's lag model (core/model/dynamics.py, D1) fitted to a step response: tau, a, RMS error.

A body that starts at rest and is commanded a step u follows, in the plant model,
``v(t) = lagged_velocity(0, u, t, tau, a)`` (a ramp at a while ``|u - v| > a tau``, then a
first-order lag of time constant tau). :func:`fit_lag` finds the (tau, a) that fit measured
responses best by least squares: a grid first, then ``scipy.optimize.least_squares`` from the
best point of the grid. Several responses (v and w of a unicycle) can be fitted together with
one (tau, a), as the plant model has one of each; each response's residuals are then divided
by its step, so that m/s and rad/s weigh alike. Bench code, not the package's.
"""

from dataclasses import dataclass
import math
from typing import Dict, Sequence, Tuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

Float = NDArray[np.float64]
LAG_GRID = np.linspace(0.0, 0.3, 31)
"""The grid's time constants tau, s."""
ACCELERATION_GRID = np.concatenate([[0.0], np.geomspace(0.05, 200.0, 49)])
"""The grid's acceleration limits a (0: none), m/s^2 or rad/s^2."""
NO_LIMIT = 1e4
"""An acceleration limit this large is no limit within a step response (the refinement's
upper bound; a fit that reaches it is reported as 0, no limit)."""


@dataclass(frozen=True)
class LagFit:
    """
    A fit of (D1) to step responses.

    lag: tau, s; max_acceleration: a (0: no limit); rms: root mean square of the residuals
    (in the responses' units when one response, else as a fraction of each step); relative_rms:
    that over the step (the largest step when several).
    """

    lag: float
    max_acceleration: float
    rms: float
    relative_rms: float

    def as_dict(self) -> Dict[str, float]:
        """Return the fit as plain numbers (for JSON)."""
        return {'lag': self.lag, 'max_acceleration': self.max_acceleration, 'rms': self.rms,
                'relative_rms': self.relative_rms}


def model_response(t: ArrayLike, step: float, lag: float, max_acceleration: float) -> Float:
    """Return (D1)'s velocity at times t (s) after a step ``step`` from rest."""
    from formation_ros.core.model.dynamics import lagged_velocity
    times = np.asarray(t, dtype=float)
    if lag <= 0.0 and max_acceleration <= 0.0:
        return np.full_like(times, step)
    velocity, _ = lagged_velocity(np.zeros_like(times), np.full_like(times, step), times, lag,
                                  max_acceleration)
    return np.asarray(velocity, dtype=float)


def _residuals(responses: Sequence[Tuple[Float, Float, float]], lag: float,
               max_acceleration: float, scaled: bool) -> Float:
    parts = []
    for t, measured, step in responses:
        residual = model_response(t, step, lag, max_acceleration) - measured
        parts.append(residual / abs(step) if scaled else residual)
    return np.concatenate(parts)


def fit_lag(responses: Sequence[Tuple[ArrayLike, ArrayLike, float]]) -> LagFit:
    """
    Fit one (tau, a) of (D1) to step responses from rest by least squares.

    responses: (t (T,) s, measured velocity (T,), step u) each; one response is fitted in its
    own units, several in fractions of their steps. Returns the best fit (a = 0: no limit).
    """
    from scipy.optimize import least_squares
    given = [(np.asarray(t, dtype=float), np.asarray(v, dtype=float), float(u))
             for t, v, u in responses]
    if not given or any(u == 0.0 or len(t) != len(v) or not len(t) for t, v, u in given):
        raise ValueError('each response needs samples and a step other than 0')
    scaled = len(given) > 1

    def cost(lag: float, acceleration: float) -> float:
        return float(np.sum(_residuals(given, lag, acceleration, scaled) ** 2))

    best = min(((cost(lag, a), lag, a) for lag in LAG_GRID for a in ACCELERATION_GRID
                if lag > 0.0 or a > 0.0))
    _, lag, acceleration = best
    start = [max(lag, 1e-4), acceleration if acceleration > 0.0 else NO_LIMIT]
    refined = least_squares(lambda x: _residuals(given, x[0], x[1], scaled), start,
                            bounds=([0.0, 1e-3], [1.0, NO_LIMIT]), x_scale=[0.01, 1.0])
    lag, acceleration = float(refined.x[0]), float(refined.x[1])
    if cost(lag, acceleration) > best[0]:
        _, lag, acceleration = best
    if acceleration >= 0.999 * NO_LIMIT:
        acceleration = 0.0
    residual = _residuals(given, lag, acceleration, scaled)
    rms = float(math.sqrt(np.mean(residual ** 2)))
    largest = max(abs(u) for _, _, u in given)
    return LagFit(lag, acceleration, rms, rms if scaled else rms / largest)
