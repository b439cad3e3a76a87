# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
The frames of a run's animation (``figures.animate``), with the colours and helpers of ``plots``.

The robots' control points (hand points of unicycles, whose axle centres, bodies and headings
are drawn too), each one's sensing disc (radius R_i) and repulsion disc (radius b: another
robot's centre inside it is repelled), the desired formation in force, the recent paths, the
static obstacles (``figures.obstacles``, drawn once), the time, the shape in force and whether
the team is stopped; a strip below marks the events along the run and the time. 3D runs are
drawn in their x-y projection (a disc is then the outline of the sphere).

The axes, ticks, legend and events are drawn once; each frame redraws only what moves on a copy
of that background (blitting), which makes a frame several times cheaper than a full draw.
"""

from typing import List, Optional, Sequence, Tuple, Union

from formation_ros.core.maths.obstacles import Obstacles
from formation_ros.core.runs.events import Event, EventKind, ordered, shape_in_force, stopped_at
from formation_ros.core.runs.trajectory import Trajectory
from formation_ros.figures.obstacles import draw_plan, OBSTACLE_ALPHA, OBSTACLE_COLOR
from formation_ros.figures.plots import (DESIRED_COLOR, HEADING_COLOR, heading_length, is_moving,
                                         polygon, REFERENCE_STYLE, REPULSION_COLOR, robot_color,
                                         shown_robots, THICK)
import matplotlib
import numpy as np
from numpy.typing import NDArray

matplotlib.use('Agg')
from matplotlib.animation import FFMpegWriter, PillowWriter  # noqa: E402, I100
from matplotlib.artist import Artist  # noqa: E402
from matplotlib.collections import EllipseCollection, LineCollection  # noqa: E402
from matplotlib.colors import to_rgb  # noqa: E402
from matplotlib.lines import Line2D  # noqa: E402
from matplotlib.patches import Patch  # noqa: E402
import matplotlib.pyplot as plt  # noqa: E402
from PIL import Image  # noqa: E402

TRAIL_POINTS = 60
"""Samples per trail at most."""
SHAPE_COLOR = 'tab:purple'
STOP_COLOR = '0.75'
BODY_COLOR = '0.3'
GIF_BASES = ('k', *(f'C{i}' for i in range(10)), STOP_COLOR, BODY_COLOR, OBSTACLE_COLOR)
"""Every colour a frame draws in (plots.robot_color cycles through C0..C9)."""
GIF_SHADES = (1.0, 0.8, 0.6, 0.45, 0.3, 0.15)
"""Each base colour enters a GIF's palette at these weights over white (antialiased edges)."""
GIF_GREYS = 16


def _limits(trajectory: Trajectory, margin: float) -> Tuple[Tuple[float, float], ...]:
    """Axis limits (x, y) holding every control point, body and desired place, plus margin."""
    clouds = [trajectory.q[..., :2], trajectory.q_desired[..., :2]]
    if trajectory.q_body is not None:
        clouds.append(trajectory.q_body[..., :2])
    points = np.concatenate([cloud.reshape(-1, 2) for cloud in clouds])
    low, high = points.min(axis=0) - margin, points.max(axis=0) + margin
    return (float(low[0]), float(high[0])), (float(low[1]), float(high[1]))


MARGIN_LEFT, MARGIN_RIGHT, MARGIN_TOP = 0.6, 0.15, 0.3
"""Inches around the plan view: tick labels, the title."""
STRIP_GAP, STRIP_HEIGHT, STRIP_BOTTOM = 0.5, 0.3, 0.4
"""Inches: below the plan view (its tick labels), the events strip, below it."""
ASPECT_RANGE = (0.5, 1.4)
"""Height / width of the plan view at least and at most (the limits widen to keep it)."""


def _widen(limits: Tuple[float, float], span: float) -> Tuple[float, float]:
    middle = 0.5 * (limits[0] + limits[1])
    half = 0.5 * max(span, limits[1] - limits[0])
    return middle - half, middle + half


def _layout(x_lim: Tuple[float, float], y_lim: Tuple[float, float], width: float):
    """
    Return (figure, plan view, events strip), the plan view's limits set, equal in x and y.

    The plan view is as tall as the run needs within :data:`ASPECT_RANGE`; beyond, the
    shorter side's limits are widened about their middle.
    """
    plan_width = width - MARGIN_LEFT - MARGIN_RIGHT
    x_span, y_span = x_lim[1] - x_lim[0], y_lim[1] - y_lim[0]
    ratio = min(max(y_span / max(x_span, 1e-12), ASPECT_RANGE[0]), ASPECT_RANGE[1])
    x_lim, y_lim = _widen(x_lim, y_span / ratio), _widen(y_lim, x_span * ratio)
    plan_height = plan_width * ratio
    height = MARGIN_TOP + plan_height + STRIP_GAP + STRIP_HEIGHT + STRIP_BOTTOM
    fig = plt.figure(figsize=(width, height))

    def box(left, bottom, box_width, box_height):
        return [left / width, bottom / height, box_width / width, box_height / height]

    strip = fig.add_axes(box(MARGIN_LEFT, STRIP_BOTTOM, plan_width, STRIP_HEIGHT))
    plan = fig.add_axes(box(MARGIN_LEFT, STRIP_BOTTOM + STRIP_HEIGHT + STRIP_GAP, plan_width,
                            plan_height))
    plan.set_xlim(*x_lim)
    plan.set_ylim(*y_lim)
    plan.set_aspect('equal', adjustable='box')
    return fig, plan, strip


class Scene:
    """
    The figure of an animation and its moving artists; :meth:`render` draws one sample.

    trajectory: with ``q_desired`` of the shape in force; radii: (N,) R_i in m;
    repulsion_radius: b in m; body_radius: m (0: none drawn); events: as ``core.runs.events``;
    width: of the figure, inches (its height follows the run's extent). The moving artists are
    in :attr:`moving`, each with a gid: 'sensing', 'repulsion', 'trails', 'desired', 'bodies'
    and 'headings' (unicycles), 'robots', 'clock', 'cursor'. obstacles: the static obstacles
    (world frame), filled in the background (gid 'obstacles', ``figures.obstacles``), or None.
    """

    def __init__(self, trajectory: Trajectory, radii: NDArray[np.float64],
                 repulsion_radius: float, body_radius: float, events: Sequence[Event],
                 title: str, width: float, obstacles: Optional[Obstacles] = None):
        """Lay out the figure and every artist (nothing drawn yet)."""
        self.trajectory = trajectory
        self.events = ordered(events)
        self.shown = shown_robots(trajectory.num_robots)
        self.colors = [robot_color(int(i)) for i in self.shown]
        x_lim, y_lim = _limits(trajectory, repulsion_radius)
        self.fig, self.ax, self.strip = _layout(x_lim, y_lim, width)
        ax = self.ax
        ax.set_autoscale_on(False)
        ax.grid(True, alpha=0.3)
        ax.set_xlabel('x [m]', fontsize=8)
        ax.set_ylabel('y [m]', fontsize=8)
        ax.tick_params(labelsize=7)
        ax.set_title(title, fontsize=9)
        legend = [Line2D([], [], marker='o', linestyle='', color='k', markersize=4,
                         label='robots (control points)'),
                  Line2D([], [], color='0.5', linewidth=0.8, label='sensing disc R_i'),
                  Line2D([], [], color=REPULSION_COLOR, linestyle=':',
                         label='repulsion disc b'),
                  Line2D([], [], color=DESIRED_COLOR, marker='x', markersize=4,
                         label='desired formation')]
        if obstacles is not None and obstacles.count:
            draw_plan(ax, obstacles)
            legend.append(Patch(facecolor=OBSTACLE_COLOR, alpha=OBSTACLE_ALPHA,
                                label='obstacles' + (' (x-y projection)' if trajectory.dim == 3
                                                     else '')))
        if is_moving(trajectory):
            legend += ax.plot(trajectory.q_od[:, 0], trajectory.q_od[:, 1], **REFERENCE_STYLE,
                              label='reference path q_od')
        first = trajectory.q[0, self.shown, :2]
        self.sensing = self._discs(np.asarray(radii, dtype=float)[self.shown], first,
                                   facecolors='none', edgecolors=self.colors, alpha=0.5,
                                   linewidths=0.7, gid='sensing')
        self.repulsion = self._discs(np.full(len(self.shown), repulsion_radius), first,
                                     facecolors='none', edgecolors=REPULSION_COLOR,
                                     linestyles=':', linewidths=0.8, gid='repulsion')
        self.trails = LineCollection([], colors=self.colors, linewidths=0.9, gid='trails')
        ax.add_collection(self.trails)
        (self.desired,) = ax.plot([], [], color=DESIRED_COLOR, linewidth=1.2, marker='x',
                                  markersize=4, gid='desired')
        self.moving: List[Artist] = [self.sensing, self.repulsion, self.trails, self.desired]
        self.bodies = self.headings = None
        if trajectory.q_body is not None and trajectory.heading is not None:
            if body_radius > 0.0:
                self.bodies = self._discs(np.full(len(self.shown), body_radius),
                                          trajectory.q_body[0, self.shown],
                                          facecolors='none', edgecolors=BODY_COLOR,
                                          linewidths=0.8, gid='bodies')
                self.moving.append(self.bodies)
            self.heading_length = heading_length(trajectory)
            self.headings = LineCollection([], colors=HEADING_COLOR, linewidths=THICK,
                                           gid='headings')
            ax.add_collection(self.headings)
            self.moving.append(self.headings)
            legend.append(Line2D([], [], color=HEADING_COLOR, linewidth=THICK,
                                 label='heading (from the axle)'))
        self.robots = ax.scatter(first[:, 0], first[:, 1], s=14, c=self.colors, zorder=5,
                                 gid='robots')
        self.clock = ax.text(0.02, 0.98, '', transform=ax.transAxes, va='top', fontsize=8,
                             family='monospace', gid='clock',
                             bbox={'facecolor': 'white', 'alpha': 0.8, 'edgecolor': 'none'})
        ax.legend(handles=legend, loc='lower right', fontsize=6, framealpha=0.8)
        self.cursor = self._draw_strip()
        self.moving += [self.robots, self.clock, self.cursor]
        for artist in self.moving:
            artist.set_animated(True)
        self._background = None

    def _discs(self, radii: NDArray[np.float64], offsets: NDArray[np.float64], **style):
        collection = EllipseCollection(2.0 * radii, 2.0 * radii, np.zeros(len(radii)),
                                       units='xy', offsets=offsets,
                                       offset_transform=self.ax.transData, **style)
        self.ax.add_collection(collection)
        return collection

    def _draw_strip(self):
        strip, t = self.strip, self.trajectory.t
        span = float(t[-1] - t[0]) if t[-1] > t[0] else 1.0
        strip.set_xlim(float(t[0]) - 0.01 * span, float(t[0]) + 1.01 * span)
        strip.set_ylim(0.0, 1.0)
        strip.set_yticks([])
        strip.tick_params(axis='x', labelsize=6)
        strip.set_xlabel('t [s]: shape changes (purple), stopped (grey)', fontsize=6,
                         labelpad=1)
        stopped_since = None
        for event in self.events:
            if event.kind is EventKind.SHAPE:
                strip.axvline(event.t, color=SHAPE_COLOR, linewidth=1.5)
                strip.text(event.t, 0.5, f' {event.label}', fontsize=6, va='center',
                           color=SHAPE_COLOR)
            elif event.kind is EventKind.STOP and stopped_since is None:
                stopped_since = event.t
            elif event.kind is EventKind.START and stopped_since is not None:
                strip.axvspan(stopped_since, event.t, color=STOP_COLOR, alpha=0.6)
                stopped_since = None
        if stopped_since is not None:
            strip.axvspan(stopped_since, float(t[-1]), color=STOP_COLOR, alpha=0.6)
        return strip.axvline(float(t[0]), color='k', linewidth=1.2, gid='cursor')

    def _update(self, k: int, trail_start: int) -> None:
        traj, shown = self.trajectory, self.shown
        now = traj.q[k, shown, :2]
        self.robots.set_offsets(now)
        self.sensing.set_offsets(now)
        self.repulsion.set_offsets(now)
        picks = np.unique(np.linspace(trail_start, k, min(k - trail_start + 1,
                                                          TRAIL_POINTS)).astype(int))
        self.trails.set_segments(list(np.swapaxes(traj.q[picks][:, shown, :2], 0, 1)))
        self.desired.set_data(*polygon(traj.q_desired[k, :, :2]).T)
        if self.headings is not None:
            assert traj.q_body is not None and traj.heading is not None
            axle = traj.q_body[k, shown]
            heading = traj.heading[k, shown]
            tip = axle + self.heading_length * np.stack([np.cos(heading), np.sin(heading)], 1)
            self.headings.set_segments(list(np.stack([axle, tip], axis=1)))
            if self.bodies is not None:
                self.bodies.set_offsets(axle)
        t = float(traj.t[k])
        shape = shape_in_force(self.events, t)
        shape_text = 'as started' if shape is None else f'{shape.label} since {shape.t:.2f} s'
        state = 'STOPPED' if stopped_at(self.events, t) else 'running'
        self.clock.set_text(f't = {t:7.2f} s  {state}\nshape: {shape_text}')
        self.cursor.set_xdata([t, t])

    def render(self, k: int, trail_start: int, dpi: float) -> NDArray[np.uint8]:
        """
        Draw sample ``k`` (trails from sample ``trail_start``); return the pixels (H, W, 4).

        The first call draws the still parts once at ``dpi``; later calls reuse them.
        """
        canvas = self.fig.canvas
        if self._background is None or self.fig.dpi != dpi:
            self.fig.set_dpi(dpi)
            canvas.draw()
            self._background = canvas.copy_from_bbox(self.fig.bbox)
        self._update(k, trail_start)
        canvas.restore_region(self._background)
        for artist in self.moving:
            self.fig.draw_artist(artist)
        return np.array(canvas.buffer_rgba())

    def close(self) -> None:
        """Release the figure."""
        plt.close(self.fig)


def gif_palette() -> Image.Image:
    """
    Return the one palette of a GIF, as a 'P' image to quantize to.

    Each of :data:`GIF_BASES` at each of :data:`GIF_SHADES` over white, and :data:`GIF_GREYS`
    greys from black to white.
    """
    white = np.ones(3)
    colors = [weight * np.array(to_rgb(base)) + (1.0 - weight) * white
              for base in GIF_BASES for weight in GIF_SHADES]
    colors += [np.full(3, level) for level in np.linspace(0.0, 1.0, GIF_GREYS)]
    palette = Image.new('P', (1, 1))
    palette.putpalette(np.round(255 * np.array(colors)).astype(np.uint8).ravel().tolist())
    return palette


class GifWriter(PillowWriter):
    """
    matplotlib's PillowWriter fed the pixels of :meth:`Scene.render` (:meth:`add`).

    Every frame is mapped, without dithering, to one palette (:func:`gif_palette`): still
    parts keep their exact colour from frame to frame, so Pillow stores only what changed (the
    rest transparent). A GIF holds a frame a whole number of
    1/100 s.
    """

    def setup(self, fig, outfile, dpi=None):
        """Start a GIF (see PillowWriter)."""
        super().setup(fig, outfile, dpi=dpi)
        self._palette = gif_palette()

    def add(self, pixels: NDArray[np.uint8]) -> None:
        """Append one frame: (H, W, 4) RGBA bytes."""
        image = Image.fromarray(np.ascontiguousarray(pixels[..., :3]), 'RGB')
        self._frames.append(image.quantize(palette=self._palette, dither=Image.Dither.NONE))

    def finish(self):
        """Write the GIF; pixels unchanged since the previous frame are stored as transparent."""
        self._frames[0].save(self.outfile, save_all=True, append_images=self._frames[1:],
                             duration=int(1000 / self.fps), loop=0, optimize=True)


class Mp4Writer(FFMpegWriter):
    """matplotlib's FFMpegWriter (h264) fed the pixels of :meth:`Scene.render` (:meth:`add`)."""

    def add(self, pixels: NDArray[np.uint8]) -> None:
        """Pipe one frame, (H, W, 4) RGBA bytes of the writer's frame size, to ffmpeg."""
        width, height = self.frame_size
        if pixels.shape[:2] != (height, width):
            raise OSError(f'a frame of {pixels.shape[1]} x {pixels.shape[0]} pixels, the movie '
                          f'is {width} x {height}')
        self._proc.stdin.write(np.ascontiguousarray(pixels).tobytes())


def choose_writer(fps: float) -> Tuple[Union[GifWriter, Mp4Writer], bool]:
    """Return (writer, is_mp4): an MP4 writer where ffmpeg is on PATH, else a GIF one."""
    if Mp4Writer.isAvailable():
        return Mp4Writer(fps=fps), True
    return GifWriter(fps=fps), False
