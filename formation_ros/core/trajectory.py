"""A sampled formation run and its ``trajectory.npz`` file."""

from dataclasses import dataclass
import os

from formation_ros.core.frames import desired_positions, to_frame_velocity
import numpy as np

ARRAYS = ('t', 'q', 'u', 'u_hat', 'q_desired', 'q_od')


@dataclass(frozen=True)
class Trajectory:
    """
    Samples of a run.

    t: (T,) s; q, q_desired: (T, N, dim) m; u: (T, N, dim) world-frame commands, m/s;
    u_hat: (T, N, dim) bounded formation-frame commands of eq. (14), m/s;
    q_od: (T, dim) the reference centre, m.
    """

    t: np.ndarray
    q: np.ndarray
    u: np.ndarray
    u_hat: np.ndarray
    q_desired: np.ndarray
    q_od: np.ndarray

    @property
    def num_robots(self):
        """N."""
        return self.q.shape[1]

    @property
    def dim(self):
        """2 or 3."""
        return self.q.shape[2]

    def save(self, path):
        """Write the arrays to ``path`` (a .npz file)."""
        np.savez_compressed(path, **{name: getattr(self, name) for name in ARRAYS})

    @classmethod
    def from_frames(cls, t, q, u, frames, vertices):
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
    def load(cls, path):
        """Read a ``trajectory.npz`` written by :meth:`save`; ValueError if arrays are missing."""
        if not os.path.exists(path):
            raise ValueError(f'{path}: no such file')
        with np.load(path) as data:
            missing = [name for name in ARRAYS if name not in data]
            if missing:
                raise ValueError(f"{path}: missing arrays {', '.join(missing)}")
            return cls(**{name: data[name] for name in ARRAYS})
