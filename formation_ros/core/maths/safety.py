# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
How close robots can come: the distance the potential guarantees, and what it means for bodies.

Along the closed loop of the paper's points (eq. 1 with eqs. 13, 14; in the formation frame for
tracking, eq. 21) ``L = log(phi + 1)`` never increases: its gradient with respect to q_i is
Omega_i, so ``L' = -c sum_i Omega_i . psi(Omega_i) <= 0``. Each term of
``L = gamma - kappa sum_{i<j} log beta_ij`` is >= 0, so at every time and for every pair
``-kappa log beta_ij <= L(0)``, that is ``beta_ij >= exp(-L(0) / kappa)``. beta_ij grows with
||q_ij|| (eq. 11), so no two robots ever come closer than the d with
``beta(d**2) = exp(-L(0) / kappa)`` (docs/equations.md, U6). This holds in continuous time;
with a zero-order hold it is approximate (measured in the tests).

For unicycles the law acts on the hand points, which in continuous time move exactly as the
paper's points (core/maths/unicycle.py, U3), so d bounds the hand points; two bodies are then at
least ``d - 2 l`` apart, and bodies of radius r never touch when ``d >= 2 r + 2 l``.
"""

import math
from typing import Optional

from formation_ros.core.maths.frames import FrameSample, STATIONARY
from formation_ros.core.maths.law import beta, LawParams, log_potential
import numpy as np
from numpy.typing import ArrayLike


def guaranteed_min_distance(q0: ArrayLike, vertices: ArrayLike, law: LawParams,
                            frame: Optional[FrameSample] = STATIONARY) -> float:
    """
    Return the distance d (m) no two robots ever come closer than, from their start q0.

    q0: (N, dim) start positions (hand points of unicycles), world frame, m; vertices (N, dim);
    frame: the reference at time 0 (default: stabilisation). Returns 0 for a start with two
    robots at one point, and b when beta_ij >= 1 is guaranteed (no pair ever within b).
    """
    start_value = log_potential(q0, vertices, law, frame)
    if not math.isfinite(start_value):
        return 0.0
    floor = math.exp(-start_value / law.kappa)
    b = law.repulsion_radius
    if floor >= 1.0:
        return b

    def gap(distance: float) -> float:
        return float(beta(np.array(distance * distance), law)) - floor

    from scipy.optimize import brentq  # only unicycle runs ask; formation_sim starts faster
    return float(brentq(gap, 0.0, b, xtol=1e-12 * b, rtol=1e-12))


def body_clearance(hand_point_distance: float, hand_distance: float) -> float:
    """Return the smallest distance (m) of two axle centres whose hand points are that far."""
    return hand_point_distance - 2.0 * hand_distance
