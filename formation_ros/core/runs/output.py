# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
A node's run written into its output directory: the trajectory in chunks, then the files.

The plant (``plant.output_dir``) and the world (``world.output_dir``) write their runs alike
(:class:`RunOutput`): a chunk of samples every second into ``trajectory_chunks/``, so a run cut
short (even by SIGKILL) keeps all but the last second; at the end the statistics file
(``plant_stats.json`` or ``world_stats.json``, :func:`stats_text`) and ``trajectory.npz``
rebuilt from the chunks (:func:`trajectory_from_chunks`, which ``formation_report`` also reads
when a run did not finish), each written whole or not at all, and then the chunks are dropped.
A write that fails stops the output: one line says where, why and what the directory keeps
(docs/faults.md: the disk fills under the output directory), and nothing more is written there.
"""

from dataclasses import replace
import json
import math
import os
import shutil
from typing import Any, Callable, Dict, Mapping, Optional, Tuple

from formation_ros.core.maths.frames import FrameSample
from formation_ros.core.maths.obstacle_tracking import FeedForwardGuard
from formation_ros.core.maths.units import NS_PER_S
from formation_ros.core.runs.trajectory import (CHUNKS_DIR, ChunkWriter, read_answered_chunks,
                                                read_body_chunks, read_chunks, read_held_chunks,
                                                save_atomically, Trajectory, TRAJECTORY_FILE)
import numpy as np
from numpy.typing import ArrayLike, NDArray

FrameAt = Callable[[float], FrameSample]
"""The reference frame at a time, s."""
ShapeAt = Callable[[int], ArrayLike]
"""The shape in force at a time, ns: (N, dim) vertices, m."""


class ChunkShapeError(ValueError):
    """The chunks hold another number of robots or dimension than the run's (``found``)."""

    def __init__(self, folder: str, found: Tuple[int, int]) -> None:
        """Keep the folder and what its chunks hold: (robots, dim)."""
        super().__init__(f'{folder}: {found[0]} robots in {found[1]}D')
        self.folder, self.found = folder, found


class FixedShape:
    """
    The :data:`ShapeAt` of a shape that never changes: ``vertices`` (N, dim), m, at every time.

    :func:`trajectory_from_chunks` then keeps one (N, dim) array, not one per sample.
    """

    def __init__(self, vertices: ArrayLike) -> None:
        """Keep a copy of ``vertices``."""
        self.vertices: NDArray[np.float64] = np.array(vertices, dtype=float)

    def __call__(self, t_ns: int) -> NDArray[np.float64]:
        """Return the vertices, whatever the time."""
        return self.vertices


def trajectory_from_chunks(folder: str, frame_at: FrameAt, shape_at: ShapeAt, bodies: bool,
                           robots: Optional[Tuple[int, int]] = None,
                           guard: Optional[FeedForwardGuard] = None) -> Trajectory:
    """
    Return the run a :class:`~formation_ros.core.runs.trajectory.ChunkWriter` wrote to ``folder``.

    frame_at(t): the reference frame at t s; shape_at(t_ns): the shape in force then (N, dim),
    m; bodies: read the unicycles' heading, axle centres and (v, w) too; robots: the (N, dim)
    the chunks must hold, else :class:`ChunkShapeError`. A command held beside the one sent
    (u_held, written by a world) is read back with its formation-frame u_hat_held. ValueError
    when the folder holds no readable chunk. guard: the obstacles' feed-forward rule the
    commands were given under (``Trajectory.from_frames``), or None.
    """
    t, q, u = read_chunks(folder)
    if robots is not None and q.shape[1:] != tuple(robots):
        raise ChunkShapeError(folder, (int(q.shape[1]), int(q.shape[2])))
    frames = [frame_at(time_s) for time_s in t]
    shapes = (shape_at.vertices if isinstance(shape_at, FixedShape) else
              [np.asarray(shape_at(int(round(time_s * NS_PER_S))), dtype=float) for time_s in t])
    trajectory = Trajectory.from_frames(t, q, u, frames, shapes, guard,
                                        read_answered_chunks(folder))
    body = read_body_chunks(folder) if bodies else None
    if body is not None:
        trajectory = replace(trajectory, **body)
    held = read_held_chunks(folder)
    return trajectory if held is None else trajectory.with_held(held, frames, guard)


def stats_text(record: Mapping[str, Any]) -> bytes:
    """
    Return a run's statistics as the bytes of its JSON file (indented, one newline at the end).

    Non-finite numbers are written as null (:func:`finite_record`).
    """
    return (json.dumps(finite_record(record), indent=2) + '\n').encode()


def finite_record(record: Mapping[str, Any]) -> Dict[str, Any]:
    """
    Return ``record`` with its non-finite numbers (top level) as None.

    JSON has no infinity or NaN: the closest approach of a single robot is none.
    """
    return {name: None if isinstance(value, float) and not math.isfinite(value) else value
            for name, value in record.items()}


class RunOutput:
    """
    The run written into ``output_dir`` by the node ``who`` ('plant' or 'world').

    goes_on: what the node does once its output stopped, as its failure line says it ('the
    plant goes on controlling'). :meth:`start` makes the chunk folder, :meth:`append` keeps a
    sample, :meth:`flush` writes a chunk, :meth:`write` the files at the end. A write that fails
    stops the output (:attr:`failure`); what was written is kept.
    """

    def __init__(self, output_dir: str, who: str, goes_on: str,
                 guard: Optional[FeedForwardGuard] = None) -> None:
        """
        Write into ``output_dir`` once :meth:`start` made its chunk folder.

        guard: the obstacles' feed-forward rule the commands were given under, taken off when
        u_hat is read back (``FormationConfig.feed_forward_guard``; None without obstacles).
        """
        self.output_dir = output_dir
        self.who = who
        self.goes_on = goes_on
        self.guard = guard
        self.chunks: Optional[ChunkWriter] = None
        self.failure: Optional[str] = None
        """Why the output stopped: 'cannot write to WHERE (REASON)'; None while it runs."""
        self.trajectory_written = False
        """Whether :meth:`write` wrote ``trajectory.npz`` (not when no chunk holds a sample)."""

    def start(self, t: float,
              first: Optional[Callable[[str], str]] = None) -> Optional[str]:
        """
        Make the chunk folder, after ``first(output_dir)`` (a file written at the start).

        first returns the path it wrote (the world's ``world.xml``). Returns the line of a
        failure, None if none; t: now, s.
        """
        where = self.output_dir
        try:
            if first is not None:
                where = first(self.output_dir)
            where = os.path.join(self.output_dir, CHUNKS_DIR)
            self.chunks = ChunkWriter(where)
        except OSError as exc:
            return self._failed(exc, where, t)
        return None

    @property
    def running(self) -> bool:
        """Whether samples are still kept: started, and nothing failed."""
        return self.chunks is not None and self.failure is None

    def append(self, t: float, q: ArrayLike, u: ArrayLike, **extras: ArrayLike) -> None:
        """
        Keep one sample for the next chunk (nothing once the output stopped).

        t: s; q, u: (N, dim) m and m/s; extras: ``core.runs.trajectory.CHUNK_EXTRAS``.
        """
        if self.running:
            assert self.chunks is not None
            self.chunks.append(t, q, u, **extras)

    def flush(self, t: float) -> Optional[str]:
        """Write the samples kept as a chunk; return the line of a failure (t: now, s)."""
        if not self.running:
            return None
        assert self.chunks is not None
        try:
            self.chunks.flush()
        except OSError as exc:
            return self._failed(exc, self.chunks.folder, t)
        return None

    def _failed(self, exc: OSError, where: str, t: float) -> str:
        """Note that the output stopped at ``t`` (s) writing ``where``; return the line."""
        until = None if self.chunks is None else self.chunks.written_until
        kept = ('nothing of the trajectory' if until is None or self.chunks is None else
                f'the trajectory up to t = {until:.2f} s in {self.chunks.count} chunks '
                f'({CHUNKS_DIR}/, which formation_report reads)')
        reason = exc.strerror or ' '.join(str(exc).split()) or type(exc).__name__
        self.failure = f'cannot write to {where} ({reason})'
        return (f'{self.who}: output stopped at t = {t:.2f} s: {self.failure}; '
                f'{self.output_dir} keeps {kept}; {self.goes_on} and writes nothing more there')

    def trajectory(self, frame_at: FrameAt, shape_at: ShapeAt,
                   bodies: bool) -> Optional[Trajectory]:
        """
        Return the run in the chunks written (None if none): :func:`trajectory_from_chunks`.

        Call after a :meth:`flush` that did not fail.
        """
        if self.chunks is None:
            return None
        try:
            return trajectory_from_chunks(self.chunks.folder, frame_at, shape_at, bodies,
                                          guard=self.guard)
        except ValueError:
            return None

    def write(self, stats_file: str, record: Mapping[str, Any], frame_at: FrameAt,
              shape_at: ShapeAt, bodies: bool, t: float) -> Optional[str]:
        """
        Write ``stats_file`` (``record``, :func:`stats_text`) and ``trajectory.npz``; drop chunks.

        frame_at, shape_at, bodies: as :func:`trajectory_from_chunks`; t: now, s. Returns the
        line of a failure, None when both are written (:attr:`trajectory_written` tells whether
        there was a trajectory). Each file is written whole or not at all
        (``core.runs.trajectory.save_atomically``).
        """
        if not self.running:
            return None
        failed = self.flush(t)
        if failed is not None:
            return failed
        where = os.path.join(self.output_dir, stats_file)
        text = stats_text(record)
        try:
            save_atomically(where, lambda stream: stream.write(text))
            trajectory = self.trajectory(frame_at, shape_at, bodies)
            where = os.path.join(self.output_dir, TRAJECTORY_FILE)
            if trajectory is not None:
                trajectory.save(where)
        except OSError as exc:
            return self._failed(exc, where, t)
        if trajectory is not None and self.chunks is not None:
            shutil.rmtree(self.chunks.folder, ignore_errors=True)
        self.trajectory_written = trajectory is not None
        return None
