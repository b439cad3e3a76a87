# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
An animation of a formation run: ``animation.mp4`` (ffmpeg on PATH) or ``animation.gif`` (Pillow).

Each frame shows the robots' control points (hand points of unicycles, whose axle centres,
bodies and headings are drawn too), each one's sensing disc (radius R_i) and repulsion disc
(radius b: another robot's centre inside it is repelled), the desired formation in force, the
recent paths, the static obstacles (filled), the time, the shape in force and whether the team
is stopped; a strip below marks the events (``core.runs.events``) along the run (drawn by
``figures.scene``).

The size is bounded: at most :data:`MAX_FRAMES` frames, never more than the run has samples,
chosen evenly in time at a fixed frame rate. This module loads matplotlib only to write.
"""

from dataclasses import dataclass
import os
import subprocess
import sys
from typing import Optional, Sequence, TextIO

from formation_ros.core.maths.frames import FrameSample
from formation_ros.core.runs.events import check_fit, Event
from formation_ros.core.runs.trajectory import Trajectory
from formation_ros.core.settings.params import FormationConfig
from formation_ros.simulation.simulate import Progress, shaped
import numpy as np
from numpy.typing import ArrayLike, NDArray

MAX_FRAMES = 600
DEFAULT_FPS = 20.0
DEFAULT_DPI = 72
FIGURE_WIDTH = 6.4
"""Inches; times the dpi gives the frame's width in pixels (460 at the default 72 dpi)."""
TRAIL_FRACTION = 0.15
"""The trails show the last this fraction of the run."""
MP4 = 'animation.mp4'
GIF = 'animation.gif'


class AnimationError(Exception):
    """The animation cannot be made or written; the message (one line) says why."""


@dataclass(frozen=True)
class FramePlan:
    """
    Which samples become frames: ``indices`` (K,) into the trajectory's samples, in time order.

    fps: frames per video second; speed: simulated seconds per video second.
    """

    indices: NDArray[np.int64]
    fps: float
    speed: float


def plan_frames(times: ArrayLike, fps: float = DEFAULT_FPS, speed: Optional[float] = None,
                max_frames: int = MAX_FRAMES) -> FramePlan:
    """
    Choose the frames of a run sampled at ``times`` (T,) in s.

    The K frames are at K times spaced evenly from the first sample to the last, each showing
    the latest sample at or before its time (within 1e-9 of the duration);
    K = round(duration fps / speed) + 1, at most ``max_frames`` and at most T. ``speed``
    (simulated s per video s) defaults to real time, or faster where the run would need more
    frames than that; a ``speed`` that needs more is refused (AnimationError).
    """
    t = np.asarray(times, dtype=float)
    duration = float(t[-1] - t[0])
    limit = min(int(max_frames), len(t))
    if duration <= 0.0 or limit < 2:
        return FramePlan(np.array([len(t) - 1]), fps, 1.0 if speed is None else speed)
    slowest = duration * fps / (limit - 1)
    if speed is None:
        speed = max(1.0, slowest)
    elif speed < slowest * (1.0 - 1e-9):
        what = f'{len(t)} samples' if limit == len(t) else f'{limit} frames at most'
        raise AnimationError(f'--speed {speed:g} needs {duration * fps / speed + 1:.0f} frames '
                             f'of this {duration:g} s run at {fps:g} fps, but it has {what}; '
                             f'give --speed {slowest:.4g} or more (or a lower --fps)')
    count = max(2, min(limit, int(round(duration * fps / speed)) + 1))
    wanted = np.linspace(t[0], t[-1], count)
    late = 1e-9 * duration
    indices = np.clip(np.searchsorted(t, wanted + late, side='right') - 1, 0, len(t) - 1)
    return FramePlan(indices.astype(np.int64), float(fps), float(speed))


def write_animation(trajectory: Trajectory, config: FormationConfig, out_dir: str,
                    events: Sequence[Event] = (), plan: Optional[FramePlan] = None,
                    dpi: float = DEFAULT_DPI, stream: TextIO = sys.stderr,
                    name: str = 'formation_report', quiet: bool = False,
                    frames: Optional[Sequence[FrameSample]] = None) -> str:
    """
    Write the animation of a run into ``out_dir``: :data:`MP4` or :data:`GIF`; return its path.

    plan: from :func:`plan_frames` (default: its defaults); events: ``core.runs.events`` (the
    trajectory's desired positions are the shape in force already; with ``frames``, the
    reference at each sample, they are rebuilt from the events' shapes: ``sim.shaped``);
    progress
    lines '<name>: animation at t = ...' go to ``stream`` at most every 10 % of the run once
    the render takes over 2 s. AnimationError (one line) when the file cannot be written.
    """
    from formation_ros.figures.scene import choose_writer, Scene
    plan = plan or plan_frames(trajectory.t)
    writer, is_mp4 = choose_writer(plan.fps)
    path = os.path.join(out_dir, MP4 if is_mp4 else GIF)
    try:
        check_fit(events, trajectory.num_robots, trajectory.dim)
        if frames is not None:
            trajectory = shaped(trajectory, config, events, frames)
    except ValueError as exc:
        raise AnimationError(str(exc)) from None
    try:
        with open(path, 'wb'):
            pass
    except OSError as exc:
        raise AnimationError(f'cannot write {path}: {exc.strerror or exc}') from None
    dimension = '' if trajectory.dim == 2 else ', x-y projection'
    title = (f'{trajectory.num_robots} {config.body.kind.value} robots{dimension}, '
             f'{plan.speed:.3g} s of the run per second')
    scene = Scene(trajectory, config.sensing_radii, config.repulsion_radius, config.body.radius,
                  events, title, FIGURE_WIDTH, config.obstacles)
    t = trajectory.t
    duration = float(t[-1] - t[0])
    trail = duration * TRAIL_FRACTION
    progress = Progress(max(duration, 1e-9), stream=stream, quiet=quiet, name=name,
                        what='animation at t')
    try:
        with writer.saving(scene.fig, path, dpi):
            for k in plan.indices:
                trail_start = int(np.searchsorted(t, t[k] - trail, side='left'))
                writer.add(scene.render(int(k), trail_start, dpi))
                progress.update(float(t[k] - t[0]))
    except (OSError, subprocess.SubprocessError) as exc:
        if os.path.isfile(path):
            os.remove(path)
        raise AnimationError(f'cannot write {path}: {getattr(exc, "strerror", None) or exc}') \
            from None
    finally:
        scene.close()
    return path


def describe(path: str, plan: FramePlan, seconds: float) -> str:
    """One line about a written animation: file, frames, rate, speed, size and render time."""
    size = os.path.getsize(path)
    return (f'{os.path.basename(path)}: {len(plan.indices)} frames at {plan.fps:g} fps, '
            f'{plan.speed:.3g} s of the run per second, {size / 1e6:.2f} MB, rendered in '
            f'{seconds:.1f} s')
