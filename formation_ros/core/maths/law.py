# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
The bounded formation control law: eqs. (8)-(14) and the tracking transform (21), (25).

Conventions: positions are rows, ``q`` has shape (N, dim) in metres, ``dim`` is 2 or 3; velocities
are in m/s. ``vertices`` (N, dim) are the robots' places in the formation frame (``q_if`` for
stabilisation, ``qhat_id`` for tracking). Nothing here imports ROS and no function modifies its
arguments.

The one formula for the repulsive part of eq. (13) lives in :func:`repulsion_terms`; the per-robot
form (what a robot node calls) and the vectorised all-robots form (what the simulator calls) both
use it, so they agree to rounding.
"""

from dataclasses import dataclass
import math
from typing import Callable, Dict, Optional, Tuple, TYPE_CHECKING, Union

from formation_ros.core.maths.choice import Choice
from formation_ros.core.maths.frames import (FrameSample, from_frame_velocity, STATIONARY,
                                             to_frame, to_frame_vectors)
from formation_ros.core.maths.jump import JumpFunction, JumpKind, make_jump
from formation_ros.core.maths.obstacles import log_obstacle_factor, Obstacles, ObstacleSurfaces
from formation_ros.core.maths.pairs import (pairs_within, row_differences, sorted_pairs,
                                            squared_norms)
import numpy as np
from numpy.typing import ArrayLike, NDArray

if TYPE_CHECKING:
    from scipy.spatial import cKDTree

MAX_REPULSION = 1e200
GAIN_MAX = 1e6
KAPPA_MAX = 1e6
REPULSION_RANGE = (1e-3, 1e4)
"""Where every formula stays within double precision (tested): c and kappa up to 1e6, b from 1 mm
to 10 km (the smooth jump's integrals underflow below, its scaling above)."""
RADIUS_MAX = 1e150


class PsiKind(Choice):
    """Bounded function psi of eq. (14): ``controller.psi``."""

    ARCTAN = 'arctan'
    TANH = 'tanh'


PsiFunction = Callable[[NDArray[np.float64]], NDArray[np.float64]]
PSI_FUNCTIONS: Dict[PsiKind, Tuple[PsiFunction, float]] = {
    PsiKind.ARCTAN: (np.arctan, math.pi / 2.0),
    PsiKind.TANH: (np.tanh, 1.0),
}
"""Each psi with its bound M1 of eq. (15)."""


@dataclass(frozen=True)
class LawParams:
    """
    Constants of the control law.

    gain: c of eq. (14), m/s per unit of psi; kappa: kappa of eqs. (8), (13);
    psi: :class:`PsiKind` (eq. 15; a string is converted); jump: a ``core.maths.jump.JumpFunction``
    (Lemma 1); repulsion_radius: b_ij of eq. (11) in m, the same for every pair.
    """

    gain: float
    kappa: float
    psi: PsiKind
    jump: JumpFunction
    repulsion_radius: float

    def __post_init__(self) -> None:
        """Check the constants once, so that the hot path need not."""
        object.__setattr__(self, 'psi', psi_kind(self.psi))
        for name in ('gain', 'kappa', 'repulsion_radius'):
            value = getattr(self, name)
            if not (math.isfinite(value) and value > 0.0):
                raise ValueError(f'{name} must be a finite number > 0, got {value!r}')
        low, high = REPULSION_RANGE
        if not (self.gain <= GAIN_MAX and self.kappa <= KAPPA_MAX
                and low <= self.repulsion_radius <= high):
            raise ValueError(f'the law is computed for gain <= {GAIN_MAX:g} m/s, kappa <= '
                             f'{KAPPA_MAX:g} and {low:g} m <= b <= {high:g} m; got gain '
                             f'{self.gain!r}, kappa {self.kappa!r}, b {self.repulsion_radius!r}')

    @property
    def psi_bound(self) -> float:
        """M1 of eq. (15): the bound of |psi| (pi/2 for arctan, 1 for tanh)."""
        return PSI_FUNCTIONS[self.psi][1]

    @property
    def u_bound(self) -> float:
        """Bound c * M1 on every component of the stabilising command (eq. 14), m/s."""
        return self.gain * self.psi_bound


def psi_kind(value: Union[PsiKind, str]) -> PsiKind:
    """Return the :class:`PsiKind` named ``value``; ValueError naming the kinds if none is."""
    try:
        return PsiKind(value)
    except ValueError:
        raise ValueError(f'psi must be one of {[str(kind) for kind in PsiKind]}, got '
                         f'{value!r}') from None


def make_law(gain: float, kappa: float, psi: Union[PsiKind, str],
             jump_kind: Union[JumpKind, str], jump_order: int,
             repulsion_radius: float) -> LawParams:
    """Build :class:`LawParams` from the parameter values of the YAML file."""
    return LawParams(float(gain), float(kappa), psi_kind(psi), make_jump(jump_kind, jump_order),
                     float(repulsion_radius))


def psi(omega: ArrayLike, law: LawParams) -> NDArray[np.float64]:
    """Apply psi element by element (eq. 14); same shape as ``omega``."""
    return PSI_FUNCTIONS[law.psi][0](np.asarray(omega, dtype=float))


def beta(distance_sq: ArrayLike, law: LawParams) -> NDArray[np.float64]:
    """Return beta_ij of eq. (11) (docs/equations.md, slip 1) from ||q_ij||**2, any shape."""
    b = law.repulsion_radius
    return law.jump.h(0.5 * np.asarray(distance_sq, dtype=float), 0.0, 0.5 * b * b)


def repulsion_terms(q_ij: ArrayLike, law: LawParams) -> NDArray[np.float64]:
    """
    Return betabar'_ij * q_ij for rows of relative positions q_ij = q_i - q_j.

    q_ij: (K, dim) in m. Returns (K, dim) in 1/m. betabar' = h'/h (eq. 13; docs/equations.md,
    slip 3) is zero for ||q_ij|| >= b. A row with q_ij exactly zero (two robots at one point) has
    no direction and contributes zero; the callers report such a collision. Where the term
    overflows (robots closer than about 1e-150 m, where h'/h is beyond the doubles) it is
    :data:`MAX_REPULSION` along q_ij: the command saturates at c M1 all the same.
    """
    q_ij = np.asarray(q_ij, dtype=float)
    return _repulsion_terms(q_ij, np.einsum('kd,kd->k', q_ij, q_ij), law)


def _repulsion_terms(q_ij: NDArray[np.float64], d2: NDArray[np.float64],
                     law: LawParams) -> NDArray[np.float64]:
    """:func:`repulsion_terms` of q_ij (K, dim) whose squared norms d2 (K,) are known."""
    b = law.repulsion_radius
    with np.errstate(invalid='ignore', over='ignore', divide='ignore'):
        weight = law.jump.ratio(0.5 * d2, 0.0, 0.5 * b * b)
        terms: NDArray[np.float64] = weight[:, None] * q_ij
    if np.all(d2 != 0.0) and np.all(np.isfinite(terms)):
        return terms  # every row apart and finite: nothing below would change
    apart = np.any(q_ij != 0.0, axis=1)
    huge = apart & ((d2 == 0.0) | ~np.all(np.isfinite(terms), axis=1))
    if np.any(huge):
        rows = q_ij[huge] / np.max(np.abs(q_ij[huge]), axis=1, keepdims=True)
        terms[huge] = MAX_REPULSION * rows / np.linalg.norm(rows, axis=1, keepdims=True)
    terms[~apart] = 0.0
    return terms


def omega(error: ArrayLike, repulsion_sum: ArrayLike, law: LawParams) -> NDArray[np.float64]:
    """Omega_i of eq. (13): ``(q_i - q_if) - kappa * sum_j betabar'_ij q_ij``, shape of error."""
    return np.asarray(error, dtype=float) - law.kappa * np.asarray(repulsion_sum, dtype=float)


def bounded_command(omega_value: ArrayLike, law: LawParams) -> NDArray[np.float64]:
    """Bounded command u_i = -c psi(Omega_i) of eq. (14), same shape as ``omega_value``."""
    return -law.gain * psi(omega_value, law)


@dataclass(frozen=True)
class Command:
    """
    A command and its parts.

    u: the world-frame velocity q' = u (eq. 25; equal to u_hat when stabilising);
    u_hat: the bounded command of eq. (14) in the formation frame, |u_hat| <= c M1;
    omega: Omega of eq. (13) in the formation frame.
    """

    u: NDArray[np.float64]
    u_hat: NDArray[np.float64]
    omega: NDArray[np.float64]


def robot_command(q_i: ArrayLike, vertex_i: ArrayLike, neighbours: ArrayLike,
                  sensing_radius: float, law: LawParams,
                  frame: Optional[FrameSample] = STATIONARY,
                  obstacles: Optional[ObstacleSurfaces] = None) -> Command:
    """
    Control of one robot from what it knows (eqs. 13, 14, 21, 25).

    q_i: (dim,) own position, world frame, m. vertex_i: (dim,) own place in the formation frame.
    neighbours: (K, dim) positions the robot has sensed, world frame; those at distance
    >= ``sensing_radius`` (R_i) are ignored. frame: a ``FrameSample`` of the reference (the
    default is stabilisation: q_od = 0, J = I); obstacles: the static obstacles, if any
    (docs/equations.md, "Obstacles"). Returns a :class:`Command` with (dim,) arrays.
    """
    q_i = np.asarray(q_i, dtype=float)
    neighbours = np.asarray(neighbours, dtype=float).reshape(-1, q_i.shape[0])
    command = robot_commands(q_i[None, :], np.asarray(vertex_i, dtype=float)[None, :],
                             np.zeros(len(neighbours), dtype=np.intp), neighbours,
                             [sensing_radius], law, frame, obstacles)
    return Command(u=command.u[0], u_hat=command.u_hat[0], omega=command.omega[0])


def robot_commands(q_own: ArrayLike, vertices: ArrayLike, observer: ArrayLike,
                   neighbours: ArrayLike, sensing_radii: ArrayLike, law: LawParams,
                   frame: Optional[FrameSample] = STATIONARY,
                   obstacles: Optional[ObstacleSurfaces] = None) -> Command:
    """
    Control of K robots, each from what it knows: :func:`robot_command` for all in one call.

    q_own: (K, dim) the robots' own positions, world frame, m; vertices: (K, dim) their places
    in the formation frame; (observer, neighbours): (P,) 0-based indices into the K robots and
    (P, dim) world positions, row p a neighbour robot ``observer[p]`` has sensed (as the rows
    of each robot's ``neighbours``, in the same order: the sums run in that order); those at
    distance >= R_i (``sensing_radii``, (K,) m) of their observer are ignored. frame: the
    reference's ``FrameSample`` (one for all); obstacles: the static obstacles, each robot
    using those within its R_i (:func:`obstacle_sum`). Returns a :class:`Command` with (K, dim)
    arrays; :func:`robot_command` is this for K = 1.
    """
    q_own = np.asarray(q_own, dtype=float)
    k, dim = q_own.shape
    observer = np.asarray(observer, dtype=np.intp)
    q_ij = q_own[observer] - np.asarray(neighbours, dtype=float).reshape(-1, dim)
    radii = np.minimum(np.asarray(sensing_radii, dtype=float), RADIUS_MAX)
    in_range = np.einsum('kd,kd->k', q_ij, q_ij) < radii[observer] ** 2
    terms = repulsion_terms(to_frame_vectors(q_ij[in_range], frame), law)
    heard = observer[in_range]
    rep: NDArray[np.float64] = np.stack([np.bincount(heard, terms[:, axis], k)
                                         for axis in range(dim)], axis=1)
    if obstacles is not None:
        rep = rep + obstacle_sum(q_own, radii, law, frame, obstacles)
    error_hat = to_frame(q_own, frame) - np.asarray(vertices, dtype=float)
    omega_hat = omega(error_hat, rep, law)
    u_hat = bounded_command(omega_hat, law)
    return Command(u=from_frame_velocity(u_hat, q_own, frame), u_hat=u_hat, omega=omega_hat)


def neighbour_pairs(q: ArrayLike, radius: float,
                    tree: Optional['cKDTree'] = None) -> NDArray[np.intp]:
    """
    Pairs (i, j), i < j, with ||q_i - q_j|| <= radius, from a k-d tree: (P, 2) int array.

    Sorted by i, then j, whatever the search: the law sums each robot's terms in this order, so
    any search that finds the same pairs gives the same numbers. tree: a k-d tree of ``q``
    already built (e.g. the plant model's), else the grid of ``core.maths.pairs`` searches.
    """
    if tree is None:
        return pairs_within(q, radius)
    found = tree.query_pairs(r=radius, output_type='ndarray').reshape(-1, 2)
    return sorted_pairs(found[:, 0], found[:, 1], int(tree.n))


def team_command(q: ArrayLike, vertices: ArrayLike, sensing_radii: ArrayLike, law: LawParams,
                 frame: Optional[FrameSample] = STATIONARY,
                 tree: Optional['cKDTree'] = None,
                 pairs: Optional[NDArray[np.intp]] = None,
                 obstacles: Optional[ObstacleSurfaces] = None) -> Command:
    """
    Control of every robot at once (the vectorised form of :func:`robot_command`).

    q: (N, dim) positions, world frame, m. vertices: (N, dim). sensing_radii: (N,) R_i in m.
    Neighbours are found with a k-d tree within b (betabar' vanishes beyond b and b <= R_i), then
    each robot keeps only those within its own R_i, so a step costs O(N log N).
    Returns a :class:`Command` with (N, dim) arrays. Raises ValueError for a non-finite position
    or robots farther apart than about 1e150 m (the k-d tree cannot search them). tree: a k-d
    tree of ``q`` (world frame) if the caller has one, so a step builds one tree, not two;
    pairs: the (P, 2) pairs i < j within b of each other, if the caller has them (the plant
    model keeps them for ``formation_sim``), so they are not searched again; obstacles: the
    static obstacles, each robot using those within its R_i (:func:`obstacle_sum`).
    """
    q = np.asarray(q, dtype=float)
    radii = np.asarray(sensing_radii, dtype=float)
    n, dim = q.shape
    q_hat = to_frame(q, frame)
    if pairs is None:
        pairs = neighbour_pairs(q, law.repulsion_radius, tree)
    i, j = pairs[:, 0], pairs[:, 1]
    q_hat_ij = row_differences(q_hat, i, j)
    d2 = squared_norms(q_hat_ij)
    terms = _repulsion_terms(q_hat_ij, d2, law)
    radii_sq = radii ** 2
    heard_by_i, heard_by_j = (_within(terms, d2, radii_sq[k]) for k in (i, j))
    rep = np.stack([np.bincount(i, heard_by_i[:, axis], n) - np.bincount(j, heard_by_j[:, axis], n)
                    for axis in range(dim)], axis=1)
    if obstacles is not None:
        rep = rep + obstacle_sum(q, radii, law, frame, obstacles)
    omega_hat = omega(q_hat - np.asarray(vertices, dtype=float), rep, law)
    u_hat = bounded_command(omega_hat, law)
    return Command(u=from_frame_velocity(u_hat, q, frame), u_hat=u_hat, omega=omega_hat)


def obstacle_sum(q: ArrayLike, sensing_radii: ArrayLike, law: LawParams,
                 frame: Optional[FrameSample],
                 obstacles: ObstacleSurfaces) -> NDArray[np.float64]:
    """
    Return each robot's sum over its obstacles of betabar'_io (q_i - p_io), formation frame.

    q: (N, dim) world positions, m; sensing_radii: (N,) R_i, m. The obstacles' part of the
    repulsion sum of eq. (13) (``core.maths.obstacles.obstacle_terms``, docs/equations.md,
    "Obstacles") with the law's jump function, rotated into the formation frame as the pairs'
    q_ij are. (N, dim) in 1/m; zeros without obstacles.
    """
    q = np.asarray(q, dtype=float)
    if obstacles.count == 0:
        return np.zeros_like(q)
    terms = obstacles.terms(q, law.jump,
                            np.minimum(np.asarray(sensing_radii, dtype=float), RADIUS_MAX))
    return to_frame_vectors(terms, frame)


def _within(terms: NDArray[np.float64], d2: NDArray[np.float64],
            radius_sq: NDArray[np.float64]) -> NDArray[np.float64]:
    """Keep the rows of terms (K, dim) whose d2 (K,) is below radius_sq (K,), zero the others."""
    inside = d2 < radius_sq
    if np.all(inside):
        return terms  # times 1.0: the same numbers
    within: NDArray[np.float64] = terms * inside[:, None]
    return within


def log_potential(q: ArrayLike, vertices: ArrayLike, law: LawParams,
                  frame: Optional[FrameSample] = STATIONARY,
                  obstacles: Optional[Obstacles] = None) -> float:
    """
    Return log(phi + 1) = gamma - kappa * sum_{i<j} log beta_ij (eqs. 8-11), a float.

    phi itself overflows quickly (e**gamma / beta**kappa); its logarithm is monotone in phi and
    its gradient with respect to q_i (formation frame) is exactly Omega_i of eq. (13). Returns
    +inf at a collision within b. obstacles: their factors beta_io too (world positions).
    """
    q_hat = to_frame(np.asarray(q, dtype=float), frame)
    gamma = 0.5 * float(np.sum((q_hat - np.asarray(vertices, dtype=float)) ** 2))
    pairs = neighbour_pairs(q_hat, law.repulsion_radius)
    diff = q_hat[pairs[:, 0]] - q_hat[pairs[:, 1]]
    with np.errstate(divide='ignore'):
        log_beta = np.log(beta(np.einsum('kd,kd->k', diff, diff), law))
    value = gamma - law.kappa * float(np.sum(log_beta))
    if obstacles is not None:
        value += log_obstacle_factor(np.asarray(q, dtype=float), obstacles, law.jump, law.kappa)
    return value


def potential(q: ArrayLike, vertices: ArrayLike, law: LawParams,
              frame: Optional[FrameSample] = STATIONARY) -> float:
    """Potential phi of eq. (8) (may overflow to +inf far from the formation)."""
    with np.errstate(over='ignore'):
        return float(np.expm1(log_potential(q, vertices, law, frame)))
