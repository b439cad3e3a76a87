# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""A sampled formation run and its ``trajectory.npz`` file."""

from dataclasses import dataclass
import os
from typing import Sequence

from formation_ros.core.frames import desired_positions, FrameSample, to_frame_velocity
import numpy as np
from numpy.typing import ArrayLike, NDArray

ARRAYS = ('t', 'q', 'u', 'u_hat', 'q_desired', 'q_od')


@dataclass(frozen=True)
class Trajectory:
    """
    Samples of a run.

    t: (T,) s; q, q_desired: (T, N, dim) m; u: (T, N, dim) world-frame commands, m/s;
    u_hat: (T, N, dim) bounded formation-frame commands of eq. (14), m/s;
    q_od: (T, dim) the reference centre, m.
    """

    t: NDArray[np.float64]
    q: NDArray[np.float64]
    u: NDArray[np.float64]
    u_hat: NDArray[np.float64]
    q_desired: NDArray[np.float64]
    q_od: NDArray[np.float64]

    @property
    def num_robots(self) -> int:
        """Return N."""
        return int(self.q.shape[1])

    @property
    def dim(self) -> int:
        """Return the dimension, 2 or 3."""
        return int(self.q.shape[2])

    def save(self, path: str) -> None:
        """Write the arrays to ``path`` (a .npz file)."""
        np.savez_compressed(path, **{name: getattr(self, name) for name in ARRAYS})

    @classmethod
    def from_frames(cls, t: ArrayLike, q: ArrayLike, u: ArrayLike,
                    frames: Sequence[FrameSample], vertices: ArrayLike) -> 'Trajectory':
        """
        Build a trajectory from states and commands and the reference frame of each sample.

        t: (T,) s; q, u: (T, N, dim); frames: T FrameSamples; vertices: (N, dim). u_hat comes
        from inverting eq. (25), desired positions from eq. (20).
        """
        q = np.asarray(q, dtype=float)
        u = np.asarray(u, dtype=float)
        return cls(t=np.asarray(t, dtype=float), q=q, u=u,
                   u_hat=np.array([to_frame_velocity(u_k, q_k, f)
                                   for u_k, q_k, f in zip(u, q, frames)]),
                   q_desired=np.array([desired_positions(vertices, f) for f in frames]),
                   q_od=np.array([f.q_od for f in frames]))

    @classmethod
    def load(cls, path: str) -> 'Trajectory':
        """Read a ``trajectory.npz`` written by :meth:`save`; ValueError if arrays are missing."""
        if not os.path.exists(path):
            raise ValueError(f'{path}: no such file')
        with np.load(path) as data:
            missing = [name for name in ARRAYS if name not in data]
            if missing:
                raise ValueError(f"{path}: missing arrays {', '.join(missing)}")
            return cls(**{name: data[name] for name in ARRAYS})
