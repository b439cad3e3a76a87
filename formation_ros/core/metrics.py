"""
Numbers that show the controller kept its promises, from sampled runs (Section 5).

Inputs are sampled trajectories: t (T,) in s, q and q_desired (T, N, dim) in m, u and u_hat
(T, N, dim) in m/s. The same functions serve ``formation_sim`` and the bag report.
"""

import math

import numpy as np
from scipy.spatial import cKDTree
from scipy.spatial.distance import pdist

SETTLE_TOLERANCE = 0.05
DIS_ALL_MAX_SAMPLES = 400
DIS_ALL_MAX_ROBOTS = 2000


def formation_errors(q, q_desired):
    """Distance of each robot from its desired place, ||q_i - q_i,desired||: (T, N) in m."""
    diff = np.asarray(q, dtype=float) - np.asarray(q_desired, dtype=float)
    return np.sqrt(np.einsum('...d,...d->...', diff, diff))


def settle_time(t, errors, tolerance=SETTLE_TOLERANCE):
    """
    First sample time after which every error stays <= tolerance; None if never.

    t: (T,); errors: (T, N). Measured on the samples, so its resolution is the sample spacing.
    """
    outside = np.any(np.asarray(errors) > tolerance, axis=1)
    if not np.any(outside):
        return float(t[0])
    last = int(np.nonzero(outside)[0][-1])
    return None if last == len(t) - 1 else float(t[last + 1])


def closest_pair_distance(points):
    """Smallest distance between two of the points (N, dim), by k-d tree; inf for N < 2."""
    points = np.asarray(points, dtype=float)
    if len(points) < 2:
        return math.inf
    dist, _ = cKDTree(points).query(points, k=2)
    return float(np.min(dist[:, 1]))


def dis_min_series(q):
    """dis_min of Section 5 at each sample: the closest pair distance, (T,) in m."""
    return np.array([closest_pair_distance(sample) for sample in np.asarray(q)])


def dis_all(points):
    """Return dis_all of Section 5, the geometric mean of ||q_ij|| (docs/equations.md, slip 7)."""
    with np.errstate(divide='ignore'):
        return float(np.exp(np.mean(np.log(pdist(np.asarray(points, dtype=float))))))


def dis_all_series(t, q):
    """
    dis_all over time: (times (K,), values (K,)), thinned to at most 400 samples.

    Empty arrays when N > 2000 (N**2 / 2 distances per sample would dominate the run).
    """
    q = np.asarray(q)
    if q.shape[1] > DIS_ALL_MAX_ROBOTS:
        return np.empty(0), np.empty(0)
    index = np.unique(np.linspace(0, len(t) - 1, min(len(t), DIS_ALL_MAX_SAMPLES)).astype(int))
    return np.asarray(t)[index], np.array([dis_all(q[k]) for k in index])


def compute_metrics(t, q, u, u_hat, q_desired, u_bound, extra=None):
    """
    Return the metrics.json dictionary of a run.

    u_bound: c * M1 (m/s), the bound every component of u_hat must keep; with a fixed reference
    u equals u_hat. extra: more keys to merge (e.g. reference kind, integrator).
    """
    t = np.asarray(t, dtype=float)
    q = np.asarray(q, dtype=float)
    errors = formation_errors(q, q_desired)
    settle = settle_time(t, errors)
    u_hat = np.asarray(u_hat, dtype=float)
    num_robots, dim = q.shape[1], q.shape[2]
    metrics = {
        'num_robots': int(num_robots),
        'dim': int(dim),
        'duration': float(t[-1] - t[0]),
        'num_samples': int(len(t)),
        'min_pair_distance': float(np.min(dis_min_series(q))),
        'dis_all_final': dis_all(q[-1]) if num_robots <= 4 * DIS_ALL_MAX_ROBOTS else None,
        'final_max_error': float(np.max(errors[-1])),
        'final_mean_error': float(np.mean(errors[-1])),
        'settle_tolerance': SETTLE_TOLERANCE,
        'settle_time': settle,
        'max_abs_u_component': float(np.max(np.abs(u))),
        'max_abs_u_hat_component': float(np.max(np.abs(u_hat))),
        'u_bound': float(u_bound),
        'bound_violations': int(np.count_nonzero(np.abs(u_hat) > u_bound * (1.0 + 1e-12))),
    }
    metrics.update(extra or {})
    return metrics
