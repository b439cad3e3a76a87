# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""A sampled formation run and its ``trajectory.npz`` file."""

from dataclasses import dataclass, replace
import os
from typing import Any, Dict, List, Optional, Sequence, Tuple

from formation_ros.core.maths.frames import desired_positions, FrameSample, to_frame_velocity
from formation_ros.core.maths.obstacle_tracking import FeedForwardGuard
import numpy as np
from numpy.typing import ArrayLike, NDArray

TRAJECTORY_FILE = 'trajectory.npz'
"""The file name of a run's trajectory in its output directory (:meth:`Trajectory.save`)."""
ARRAYS = ('t', 'q', 'u', 'u_hat', 'q_desired', 'q_od')
BODY_ARRAYS = ('heading', 'q_body', 'body_command')
"""Arrays of a unicycle run, beside :data:`ARRAYS` (which then describe the hand points)."""
HELD_ARRAYS = ('u_held', 'u_hat_held')
"""Arrays of a run whose commands need a heading (unicycles, body-frame commands): the command
held at each sample read at the body's heading then, beside u (read at the heading answered)."""
OPTIONAL_ARRAYS = BODY_ARRAYS + HELD_ARRAYS


@dataclass(frozen=True)
class Trajectory:
    """
    Samples of a run.

    t: (T,) s; q, q_desired: (T, N, dim) m; u: (T, N, dim) world-frame commands, m/s;
    u_hat: (T, N, dim) bounded formation-frame commands of eq. (14), m/s;
    q_od: (T, dim) the reference centre, m.

    For unicycles q, u and u_hat are those of the hand points (what the law controls), and
    heading (T, N) in rad, q_body (T, N, 2) the axle centres in m and body_command (T, N, 2)
    the (v, w) held, in m/s and rad/s, describe the bodies; all three are None for points.

    u is what each robot commanded: its published command read at the orientation of the
    state it answered (``core.model.commanded``; NaN where the run cannot tell). Where that needs a
    heading (unicycles, body-frame commands) u_held (T, N, dim) m/s is the command held at each
    sample read at the body's heading at that sample instead (a world's true heading), and
    u_hat_held (T, N, dim) m/s that in the formation frame (eq. 25 inverted): u_hat rotated by
    the heading turned since the state answered, so within sqrt(2) c M1, not c M1, per
    component. Both None otherwise.
    """

    t: NDArray[np.float64]
    q: NDArray[np.float64]
    u: NDArray[np.float64]
    u_hat: NDArray[np.float64]
    q_desired: NDArray[np.float64]
    q_od: NDArray[np.float64]
    heading: Optional[NDArray[np.float64]] = None
    q_body: Optional[NDArray[np.float64]] = None
    body_command: Optional[NDArray[np.float64]] = None
    u_held: Optional[NDArray[np.float64]] = None
    u_hat_held: Optional[NDArray[np.float64]] = None

    @property
    def num_robots(self) -> int:
        """Return N."""
        return int(self.q.shape[1])

    @property
    def dim(self) -> int:
        """Return the dimension, 2 or 3."""
        return int(self.q.shape[2])

    def save(self, path: str) -> None:
        """
        Write the arrays to ``path`` (a .npz file, not compressed); body arrays when present.

        Float trajectories compress by a few per cent only, and zlib was a tenth of a 1000-robot
        formation_sim run; ``np.load`` reads either kind. Written whole or not at all
        (:func:`save_atomically`): an OSError leaves no partial file.
        """
        arrays = {name: getattr(self, name) for name in ARRAYS + OPTIONAL_ARRAYS
                  if getattr(self, name) is not None}
        save_atomically(path, lambda stream: np.savez(stream, **arrays))

    @classmethod
    def from_frames(cls, t: ArrayLike, q: ArrayLike, u: ArrayLike,
                    frames: Sequence[FrameSample], vertices: ArrayLike,
                    guard: Optional[FeedForwardGuard] = None,
                    answered: Optional[ArrayLike] = None) -> 'Trajectory':
        """
        Build a trajectory from states and commands and the reference frame of each sample.

        t: (T,) s; q, u: (T, N, dim); frames: T FrameSamples; vertices: (N, dim), or (T, N,
        dim) for a shape that changes (the shape in force at each sample). u_hat comes from
        inverting eq. (25) (the obstacles' rule ``guard`` taken off first, if given; at the
        positions of the states the commands ``answered`` where known,
        :func:`frame_velocities`), desired positions from eq. (20).
        """
        q = np.asarray(q, dtype=float)
        u = np.asarray(u, dtype=float)
        shapes = np.asarray(vertices, dtype=float)
        per_sample = shapes if shapes.ndim == 3 else [shapes] * len(frames)
        return cls(t=np.asarray(t, dtype=float), q=q, u=u,
                   u_hat=frame_velocities(u, q, frames, guard, answered),
                   q_desired=np.array([desired_positions(v, f)
                                       for v, f in zip(per_sample, frames)]),
                   q_od=np.array([f.q_od for f in frames]))

    def with_held(self, u_held: ArrayLike, frames: Sequence[FrameSample],
                  guard: Optional[FeedForwardGuard] = None) -> 'Trajectory':
        """
        Return a copy with u_held (T, N, dim) m/s and its u_hat_held (eq. 25 inverted at q).

        frames: the T reference samples the trajectory was built with (:meth:`from_frames`).
        """
        held = np.array(u_held, dtype=float)
        return replace(self, u_held=held,
                       u_hat_held=frame_velocities(held, self.q, frames, guard))

    @classmethod
    def load(cls, path: str) -> 'Trajectory':
        """Read a ``trajectory.npz`` written by :meth:`save`; ValueError if arrays are missing."""
        if not os.path.exists(path):
            raise ValueError(f'{path}: no such file')
        with np.load(path) as data:
            missing = [name for name in ARRAYS if name not in data]
            if missing:
                raise ValueError(f"{path}: missing arrays {', '.join(missing)}")
            return cls(**{name: data[name] for name in ARRAYS + OPTIONAL_ARRAYS
                          if name in data})


def frame_velocities(u: ArrayLike, q: ArrayLike, frames: Sequence[FrameSample],
                     guard: Optional[FeedForwardGuard] = None,
                     answered: Optional[ArrayLike] = None) -> NDArray[np.float64]:
    """
    Return u (T, N, dim) m/s in the formation frame of each sample, eq. (25) inverted.

    guard: the obstacles' feed-forward rule the commands were given under
    (``core.maths.obstacle_tracking``), taken off before the inversion; None: none. answered:
    (T, N, dim) the positions of the states the commands answered, m, where known (NaN: not):
    eq. (25)'s feed-forward and the rule depend on the position the robot computed at, which
    a plant or world has moved on from by the sample (near an obstacle the rule changes within
    centimetres); None: the samples' positions.
    """
    q = np.asarray(q, dtype=float)
    at = q if answered is None else np.where(np.isfinite(answered), answered, q)
    return np.array([to_frame_velocity(u_k if guard is None else guard.sent(u_k, q_k, f),
                                       q_k, f)
                     for u_k, q_k, f in zip(np.asarray(u, dtype=float), at, frames)])


CHUNKS_DIR = 'trajectory_chunks'
CHUNK_EXTRAS = BODY_ARRAYS + ('u_held', 'q_answered')
"""Arrays a chunk may hold beside t, q and u (u_hat_held is computed from u_held on reading;
q_answered, the positions of the states the commands answered, is used in reading u_hat)."""


class ChunkWriter:
    """
    Writes samples (t, q, u) to a folder of numbered ``.npz`` files as a run goes.

    A process that keeps its samples only here holds at most one chunk in memory, and a run cut
    short (even by SIGKILL) loses at most the chunk not yet written: :func:`read_chunks` reads
    back every complete file. t in s; q, u (N, dim); for unicycles also heading (N,), q_body
    (N, 2) and body_command (N, 2) (:data:`BODY_ARRAYS`, read back by :func:`read_body_chunks`)
    and u_held (N, dim) (read back by :func:`read_held_chunks`).

    A chunk that cannot be written (a full disk) is removed, and the writer stops: :meth:`flush`
    raises that OSError once, then :attr:`failed` holds it and samples are no longer kept, so
    the folder stays a gap-free run up to :attr:`written_until`.
    """

    def __init__(self, folder: str):
        """Write into ``folder`` (created; files already there are kept and read back)."""
        self.folder = folder
        os.makedirs(folder, exist_ok=True)
        self.count = len(_chunk_files(folder))
        self._t: List[float] = []
        self._q: List[NDArray[np.float64]] = []
        self._u: List[NDArray[np.float64]] = []
        self._body: Dict[str, List[NDArray[np.float64]]] = {name: [] for name in CHUNK_EXTRAS}
        self.failed: Optional[OSError] = None
        self.written_until: Optional[float] = None
        """Time of the last sample in the chunks written, s (None before any)."""

    def append(self, t: float, q: ArrayLike, u: ArrayLike, **body: ArrayLike) -> None:
        """Keep one sample until the next :meth:`flush`; body: :data:`CHUNK_EXTRAS`."""
        if self.failed is not None:
            return
        self._t.append(float(t))
        self._q.append(np.array(q, dtype=float))
        self._u.append(np.array(u, dtype=float))
        for name, value in body.items():
            self._body[name].append(np.array(value, dtype=float))

    def flush(self) -> None:
        """Write the samples kept so far as the next chunk (atomically: a rename)."""
        if not self._t or self.failed is not None:
            return
        path = os.path.join(self.folder, f'{self.count:06d}.npz')
        arrays: Dict[str, Any] = {'t': np.array(self._t), 'q': np.array(self._q),
                                  'u': np.array(self._u)}
        arrays.update({name: np.array(values) for name, values in self._body.items()
                       if len(values) == len(self._t)})
        last = self._t[-1]
        self._t, self._q, self._u = [], [], []
        self._body = {name: [] for name in CHUNK_EXTRAS}
        try:
            save_atomically(path, lambda stream: np.savez(stream, **arrays))
        except OSError as exc:
            self.failed = exc
            raise
        self.count += 1
        self.written_until = last


def _remove(path: str) -> None:
    try:
        os.remove(path)
    except OSError:
        pass


def save_atomically(path: str, write: Any) -> None:
    """
    Write a file with ``write(stream)`` into ``path.part``, then rename it to ``path``.

    A failure (OSError: a full disk) leaves no part file and no half-written ``path``.
    """
    partial = path + '.part'
    try:
        with open(partial, 'wb') as stream:
            write(stream)
        os.replace(partial, path)
    except OSError:
        _remove(partial)
        raise


def _chunk_files(folder: str) -> List[str]:
    return sorted(name for name in os.listdir(folder) if name.endswith('.npz'))


def read_chunks(folder: str) -> Tuple[NDArray[np.float64], NDArray[np.float64],
                                      NDArray[np.float64]]:
    """
    Read back what a :class:`ChunkWriter` wrote: (t (T,), q (T, N, dim), u (T, N, dim)).

    Raises ValueError when the folder holds no readable chunk.
    """
    t, q, u = [], [], []
    for name in _chunk_files(folder):
        try:
            with np.load(os.path.join(folder, name)) as data:
                t.append(data['t'])
                q.append(data['q'])
                u.append(data['u'])
        except (OSError, ValueError, KeyError, EOFError) as exc:
            raise ValueError(f'{folder}/{name}: cannot read it: {exc}') from None
    if not t:
        raise ValueError(f'{folder}: no trajectory chunk')
    return np.concatenate(t), np.concatenate(q), np.concatenate(u)


def read_body_chunks(folder: str) -> Optional[Dict[str, NDArray[np.float64]]]:
    """
    Read back the :data:`BODY_ARRAYS` of the chunks in ``folder``: {name: (T, ...)}.

    None when the chunks hold none (point bodies). Call after :func:`read_chunks` succeeded.
    """
    return _optional_chunks(folder, BODY_ARRAYS)


def read_held_chunks(folder: str) -> Optional[NDArray[np.float64]]:
    """
    Read back u_held (T, N, dim) of the chunks in ``folder``, m/s.

    None when the chunks hold none (commands that need no heading, or an older writer). Call
    after :func:`read_chunks` succeeded.
    """
    parts = _optional_chunks(folder, ('u_held',))
    return None if parts is None else parts['u_held']


def read_answered_chunks(folder: str) -> Optional[NDArray[np.float64]]:
    """
    Read back q_answered (T, N, dim) of the chunks in ``folder``, m (NaN: not known).

    None when the chunks hold none. Call after :func:`read_chunks` succeeded.
    """
    parts = _optional_chunks(folder, ('q_answered',))
    return None if parts is None else parts['q_answered']


def _optional_chunks(folder: str,
                     names: Sequence[str]) -> Optional[Dict[str, NDArray[np.float64]]]:
    """Return the arrays ``names`` of every chunk, concatenated; None if a chunk lacks one."""
    parts: Dict[str, List[NDArray[np.float64]]] = {name: [] for name in names}
    for name in _chunk_files(folder):
        with np.load(os.path.join(folder, name)) as data:
            if not all(key in data for key in names):
                return None
            for key in names:
                parts[key].append(data[key])
    if not parts[names[0]]:
        return None
    return {key: np.concatenate(values) for key, values in parts.items()}
