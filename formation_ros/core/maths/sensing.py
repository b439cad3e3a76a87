# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
The range sensor of every robot: who sees whom (the paper's limited sensing, Section 2).

Robot i senses robot j when ``||q_i - q_j|| < R_i``, strictly, with q the body positions. A
unicycle's law acts on hand points ``l`` ahead of the bodies (docs/equations.md U2), so its
sensor reaches ``R_i + 2 l``: then it sees every hand point within R_i of its own (two hand
points within R_i have bodies within R_i + 2 l), and the law keeps those within R_i.

One rule, used by the plant model (``core.model.plant``: the simulator and the plant node) and by
the relay node, which applies it to measured poses instead of simulated bodies.
"""

from typing import List, Optional, Tuple, TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

if TYPE_CHECKING:
    from scipy.spatial import cKDTree

DIRECT_LIMIT = 1 << 18
"""Up to this many (observer, body) pairs the few observers' pairs come from every distance,
without a k-d tree (a fleet of 25 in a team of 10,000; no scipy import in a robot process)."""
SEARCH_MARGIN = 1.0 + 1e-9
"""The ball search of a few observers reaches this much farther than their sensors; the strict
test on squared distances then decides, as for the whole team."""


def sensor_radii(radii: NDArray[np.float64], sensing_margin: float) -> NDArray[np.float64]:
    """Return how far each sensor reaches, m: R_i (N,) plus the bodies' margin (2 l or 0)."""
    return np.asarray(radii, dtype=float) + float(sensing_margin)


def sensed_pairs(q: NDArray[np.float64], reach: NDArray[np.float64],
                 tree: Optional['cKDTree'] = None,
                 observers: Optional[NDArray[np.intp]] = None
                 ) -> Tuple[NDArray[np.intp], NDArray[np.intp]]:
    """
    Who senses whom: arrays (observer, seen) of every ordered pair with ||q_o - q_s|| < reach_o.

    q: (N, dim) body positions, m; reach: (N,) sensor reach, m (:func:`sensor_radii`); tree: a
    k-d tree of ``q`` when the caller has one (else one is built, but for few observers);
    observers: (K,) distinct 0-based indices of the only observers wanted (a fleet's robots:
    the pairs of the whole team whose observer is one of them, the same pairs), None for every
    robot. Sorted by observer, then seen; indices 0-based.
    """
    if observers is not None and tree is None and len(observers) * len(q) <= DIRECT_LIMIT:
        return _pairs_direct(q, reach, np.asarray(observers, dtype=np.intp))
    if tree is None:
        from scipy.spatial import cKDTree  # here: a robot imports the plant model, not the tree
        tree = cKDTree(q)
    if observers is not None:
        return _pairs_of(q, reach, tree, np.asarray(observers, dtype=np.intp))
    pairs = tree.query_pairs(r=float(np.max(reach)), output_type='ndarray').reshape(-1, 2)
    diff = q[pairs[:, 0]] - q[pairs[:, 1]]
    d2 = np.einsum('kd,kd->k', diff, diff)
    first = pairs[d2 < reach[pairs[:, 0]] ** 2]
    second = pairs[d2 < reach[pairs[:, 1]] ** 2][:, ::-1]
    both = np.concatenate([first, second])
    order = np.lexsort((both[:, 1], both[:, 0]))
    return both[order, 0], both[order, 1]


def _pairs_direct(q: NDArray[np.float64], reach: NDArray[np.float64],
                  observers: NDArray[np.intp]) -> Tuple[NDArray[np.intp], NDArray[np.intp]]:
    """:func:`sensed_pairs` of the given observers only, from every (observer, body) distance."""
    diff = q[observers][:, None, :] - q[None, :, :]
    d2 = np.einsum('kjd,kjd->kj', diff, diff)
    near = d2 < (reach[observers] ** 2)[:, None]
    near[np.arange(len(observers)), observers] = False
    rows, seen = np.nonzero(near)
    observer = observers[rows]
    order = np.lexsort((seen, observer))
    return observer[order], seen[order].astype(np.intp)


def _pairs_of(q: NDArray[np.float64], reach: NDArray[np.float64], tree: 'cKDTree',
              observers: NDArray[np.intp]) -> Tuple[NDArray[np.intp], NDArray[np.intp]]:
    """:func:`sensed_pairs` of the given observers only, from a ball search around each."""
    if len(observers) == 0:
        empty = np.zeros(0, dtype=np.intp)
        return empty, empty
    found = tree.query_ball_point(q[observers], r=reach[observers] * SEARCH_MARGIN)
    counts = np.fromiter(map(len, found), dtype=np.intp, count=len(observers))
    observer = np.repeat(observers, counts)
    seen = np.fromiter((j for near in found for j in near), dtype=np.intp, count=int(counts.sum()))
    diff = q[observer] - q[seen]
    d2 = np.einsum('kd,kd->k', diff, diff)
    keep = (observer != seen) & (d2 < reach[observer] ** 2)
    observer, seen = observer[keep], seen[keep]
    order = np.lexsort((seen, observer))
    return observer[order], seen[order]


def neighbour_lists(observer: NDArray[np.intp], seen: NDArray[np.intp],
                    num_robots: int) -> List[NDArray[np.intp]]:
    """Split sorted (observer, seen) pairs into robot i's list of the bodies it sees (0-based)."""
    splits = np.searchsorted(observer, np.arange(1, num_robots))
    return np.split(seen, splits)
