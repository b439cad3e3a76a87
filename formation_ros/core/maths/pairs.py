# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
Pairs of nearby points with numpy alone: a grid of cells one radius wide (no k-d tree).

The law's pairs within b (``law.neighbour_pairs``), the plant model's candidates and the closest
pair of a state (``metrics``, ``params``) are searched here, so that ``formation_sim --dt`` does
not load scipy. Each point is compared with the points of its own cell and of the neighbouring
cells; pairs come out sorted by i, then j (i < j, 0-based), the order in which the law sums them.
"""

import math
from typing import Tuple

import numpy as np
from numpy.typing import ArrayLike, NDArray


def squared_norms(v: NDArray[np.float64]) -> NDArray[np.float64]:
    """Squared norms (K,) of the rows of v (K, dim), summed axis after axis."""
    total: NDArray[np.float64] = v[:, 0] * v[:, 0]
    for axis in range(1, v.shape[1]):
        total = total + v[:, axis] * v[:, axis]
    return total


def row_differences(q: NDArray[np.float64], i: NDArray[np.intp],
                    j: NDArray[np.intp]) -> NDArray[np.float64]:
    """Rows q_i - q_j (K, dim) for index arrays i, j (K,): ``q[i] - q[j]``, gathered faster."""
    difference: NDArray[np.float64] = np.take(q, i, axis=0) - np.take(q, j, axis=0)
    return difference


CELL_MARGIN = 1.0 + 1e-6
"""Cells are this much wider than the radius, so that rounding in the cell index cannot put
two points within the radius two cells apart."""
MAX_CELLS = 2.0 ** 62
"""Beyond this many cells (points very far apart for the radius) a k-d tree searches instead."""


def _rows(dim: int) -> NDArray[np.int64]:
    """
    Offsets (dim - 1,) in {-1, 0, 1} of the neighbouring rows of cells along the first axis.

    The own row first, then the rows after it in order: with the cells numbered along the first
    axis within a row, the cells x - 1 to x + 1 of a row are one run of the sorted cell keys.
    """
    every = np.array(list(np.ndindex(*(3,) * (dim - 1))), dtype=np.int64).reshape(-1, dim - 1)
    return every[len(every) // 2:] - 1


def pairs_within(points: ArrayLike, radius: float) -> NDArray[np.intp]:
    """
    Every pair (i, j), i < j, with ||q_i - q_j|| <= radius (m): (P, 2), sorted by i, then j.

    points: (N, dim) in m. Raises ValueError for a non-finite position.
    """
    q = np.asarray(points, dtype=float)
    n, dim = q.shape
    if not np.all(np.isfinite(q)):
        raise ValueError('positions must be finite numbers')
    if n < 2 or not radius >= 0.0:
        return np.zeros((0, 2), dtype=np.intp)
    low = np.min(q, axis=0)
    cell = radius * CELL_MARGIN if radius > 0.0 else 1.0
    with np.errstate(over='ignore'):
        scaled = np.floor((q - low) / cell)
        cells_needed = float(np.prod(np.max(scaled, axis=0) + 3.0))
    if not cells_needed <= MAX_CELLS:
        return _tree_pairs(q, radius)
    cells = scaled.astype(np.int64)
    sizes = np.max(cells, axis=0) + 3
    strides = np.concatenate([[1], np.cumprod(sizes[:-1])]).astype(np.int64)
    key = (cells + 1) @ strides
    order = np.argsort(key, kind='stable')
    sorted_key = key[order]
    firsts, seconds = [], []
    positions = np.arange(n)
    for row in _rows(dim):
        target = sorted_key + int(row @ strides[1:])
        stop = np.searchsorted(sorted_key, target + 1, side='right')
        start = (positions + 1 if not row.any()
                 else np.searchsorted(sorted_key, target - 1, side='left'))
        counts = np.maximum(stop - start, 0)
        total = int(counts.sum())
        if total == 0:
            continue
        firsts.append(np.repeat(positions, counts))
        seconds.append(np.arange(total) + np.repeat(start - (np.cumsum(counts) - counts), counts))
    if not firsts:
        return np.zeros((0, 2), dtype=np.intp)
    a, b = order[np.concatenate(firsts)], order[np.concatenate(seconds)]
    with np.errstate(over='ignore'):
        near = squared_norms(row_differences(q, a, b)) <= radius * radius
    a, b = a[near], b[near]
    return sorted_pairs(np.minimum(a, b), np.maximum(a, b), n)


def sorted_pairs(i: ArrayLike, j: ArrayLike, n: int) -> NDArray[np.intp]:
    """Pairs (i, j) of N = n points, i < j, as (P, 2) sorted by i, then j."""
    key = np.sort(np.asarray(i, dtype=np.int64) * n + np.asarray(j, dtype=np.int64))
    pairs: NDArray[np.intp] = np.stack([key // n, key % n], axis=1).astype(np.intp)
    return pairs


def _tree_pairs(q: NDArray[np.float64], radius: float) -> NDArray[np.intp]:
    """:func:`pairs_within` by a k-d tree (points too far apart for a grid)."""
    from scipy.spatial import cKDTree
    found = cKDTree(q).query_pairs(r=radius, output_type='ndarray').reshape(-1, 2)
    return sorted_pairs(found[:, 0], found[:, 1], len(q))


def closest_pair(points: ArrayLike, guess: float = 0.0) -> Tuple[float, int, int]:
    """
    Return (distance in m, i, j) of the closest two of the points (N, dim), 0-based i < j.

    Of several closest pairs, the first by i, then j. (inf, -1, -1) for fewer than 2 points.
    The search radius starts at ``guess`` (m) when it is > 0 (e.g. a little more than the
    distance of the sample before), else at the spacing N points would have spread evenly over
    their bounding box, and doubles until some pair is found.
    """
    q = np.asarray(points, dtype=float)
    n, dim = q.shape
    if n < 2:
        return math.inf, -1, -1
    largest = float(np.max(np.max(q, axis=0) - np.min(q, axis=0)))
    if largest == 0.0:
        return 0.0, 0, 1
    radius = guess if 0.0 < guess < math.inf else largest / n ** (1.0 / dim)
    while True:
        pairs = pairs_within(q, radius)
        if len(pairs):
            k = int(np.argmin(squared_norms(row_differences(q, pairs[:, 0], pairs[:, 1]))))
            i, j = int(pairs[k, 0]), int(pairs[k, 1])
            return math.dist(q[i], q[j]), i, j
        radius *= 2.0
