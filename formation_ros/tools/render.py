# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
``formation_render``: a run replayed in 3D in its MuJoCo world, as an animated GIF.

The run (what ``formation_report`` reads: a run directory of ``formation_sim``, with or without
``--engine mujoco``, or of the launcher, or a bag) is put back into the scene its parameters
build (``physics.scene.build_scene``). For each frame every robot's joints are set to its
recorded pose (the axle centre and heading of a differential-drive base, the position and,
where recorded, heading of a point body), ``mj_forward`` places the bodies, and MuJoCo's
offscreen renderer draws them from a camera that frames the team (``follow``: the team as it
is, zooming out as it spreads; ``fixed``: everything the run visits). Each robot has a colour
of its own, and beside its body are drawn, as extra geoms of the frame: its desired position
in force (a flat disc of its colour), its recent path and, with ``--sensing``, its sensing
circle (radius R_i about its control point; paths and circles for teams of up to
:data:`MAX_LINED_ROBOTS`). The obstacles of the parameters (``obstacles.*``) are the scene's own
static geoms (``physics.obstacles``): pillars and walls of ``world.obstacle_height`` in 2D; a
flying team's, which span its flight, are drawn see-through (:data:`OBSTACLE_ALPHA_3D`) so
that they hide no robot. Nothing is simulated: the picture is the run as it was recorded.

Rendering needs an OpenGL backend that draws without a display: OSMesa (the Debian package
``libosmesa6``, which ``scripts/setup_env.sh`` installs) or EGL. ``MUJOCO_GL=osmesa`` or
``egl`` chooses one, else OSMesa when its library is found, else EGL. The context is made here
for the chosen backend rather than by ``mujoco.Renderer``, which takes whatever ``MUJOCO_GL``
said when mujoco was first imported in the process (a display's GLFW when it was unset).

A bad input, an ``--out`` that cannot be written or no usable backend ends with exit code 2
and one line saying why.
"""

import argparse
from dataclasses import dataclass
import math
import os
import sys
import time
from typing import Any, Callable, List, Mapping, Optional, Sequence, TextIO, Tuple

from formation_ros.core.runs.trajectory import Trajectory, TRAJECTORY_FILE
from formation_ros.core.settings.params import FormationConfig
import numpy as np
from numpy.typing import NDArray

NAME = 'formation_render'
BACKENDS = ('osmesa', 'egl')
"""The OpenGL backends that draw without a display, in the order tried."""
BACKEND_LIBRARIES = {'osmesa': 'OSMesa', 'egl': 'EGL'}
NO_BACKEND = ('no OpenGL backend for offscreen rendering (install libosmesa6: '
              'bash scripts/setup_env.sh as root, or apt-get install libosmesa6; or set '
              'MUJOCO_GL=egl where an EGL driver is installed)')
DEFAULT_WIDTH = 640
DEFAULT_HEIGHT = 480
MAX_SIDE = 4096
"""Largest frame width or height, pixels."""
DEFAULT_FPS = 10.0
DEFAULT_MAX_FRAMES = 150
MAX_FRAMES = 1000
GIF_COLORS = 128
"""Colours of the GIF's one palette (:func:`gif_palette`)."""
PALETTE_SHADES = (0.6, 0.85, 1.0)
"""The robots' colours enter the palette at these brightnesses."""
CAMERAS = ('follow', 'fixed')
ELEVATION = -50.0
"""The camera looks down at this angle, degrees."""
AZIMUTH = 90.0
"""The camera looks along +y: x to the right, y up the picture, as in the 2D figures."""
MARGIN = 1.15
"""The camera's distance leaves this factor of room around what it frames."""
MIN_VIEW_RADIUS = 1.0
"""The follow camera frames at least a disc of this radius, m."""
SMOOTHING = 0.5
"""The follow camera's framing is smoothed over this many seconds of video on either side."""
TRAIL_FRACTION = 0.15
"""The paths show the last this fraction of the run."""
TRAIL_POINTS = 40
"""A robot's path is drawn through at most this many of its samples."""
CIRCLE_SEGMENTS = 48
MAX_LINED_ROBOTS = 200
"""Paths and sensing circles are drawn for teams of at most this many robots."""
SHADOW_SIZE = 1024
"""The shadow map's side, pixels: with OSMesa, MuJoCo's default 4096 took most of a frame."""
LINE_WIDTH = 2.0
"""Paths and sensing circles, pixels."""
LINE_SHADE = 0.7
"""A path's colour is its robot's at this brightness: the lights brighten lines past it."""
MARKER_HEIGHT = 0.003
"""Half the height of a desired-position disc, m (it lies on the floor)."""
LIFT = 0.02
"""Lines on the floor are drawn this high above it, m."""
COLORS = ((0.12, 0.47, 0.71), (1.0, 0.5, 0.05), (0.17, 0.63, 0.17), (0.84, 0.15, 0.16),
          (0.58, 0.4, 0.74), (0.55, 0.34, 0.29), (0.89, 0.47, 0.76), (0.1, 0.1, 0.35),
          (0.74, 0.74, 0.13), (0.09, 0.75, 0.81))
"""Robot i's colour is entry (i - 1) mod 10 (matplotlib's tab10, its grey made navy)."""
FORMATION_COLOR = np.array((0.35, 0.2, 0.5, 0.7), dtype=np.float32)
"""The desired formation's outline."""
OBSTACLE_ALPHA_3D = 0.35
"""The opacity of a flying team's obstacles in the picture."""


class RenderError(Exception):
    """The run cannot be rendered or written; the message (one line) says why."""


@dataclass(frozen=True)
class RenderOptions:
    """
    How to render a run.

    width, height: the frame in pixels; fps: frames per second of the GIF; speed: simulated
    seconds per second of GIF (None: as ``figures.animate.plan_frames`` chooses); max_frames:
    at most this many frames; camera: one of :data:`CAMERAS`; sensing: draw the sensing
    circles; shadows: draw shadows (with OSMesa, about 1.5 times the CPU of a frame).
    """

    width: int = DEFAULT_WIDTH
    height: int = DEFAULT_HEIGHT
    fps: float = DEFAULT_FPS
    speed: Optional[float] = None
    max_frames: int = DEFAULT_MAX_FRAMES
    camera: str = 'follow'
    sensing: bool = False
    shadows: bool = True


@dataclass(frozen=True)
class Rendered:
    """A written GIF: its path, frames, rate, speed, backend and render time (s)."""

    path: str
    frames: int
    fps: float
    speed: float
    backend: str
    seconds: float

    def describe(self) -> str:
        """Return one line about the GIF."""
        size = os.path.getsize(self.path) / 1e6
        rate = self.frames / self.seconds if self.seconds > 0.0 else math.inf
        return (f'{self.path}: {self.frames} frames at {self.fps:g} fps, {self.speed:.3g} s of '
                f'the run per second, {size:.2f} MB; rendered with {self.backend} in '
                f'{self.seconds:.1f} s ({rate:.1f} frames/s)')


def _one_line(text: Any) -> str:
    return '; '.join(line.strip() for line in str(text).splitlines() if line.strip())


def choose_backend(environ: Mapping[str, str] = os.environ,
                   find_library: Optional[Callable[[str], Optional[str]]] = None) -> str:
    """
    Return the offscreen backend to use: 'osmesa' or 'egl'; RenderError if there is none.

    ``MUJOCO_GL`` (or else ``PYOPENGL_PLATFORM``) chooses when it names one; a display backend
    there is refused. Otherwise the first of :data:`BACKENDS` whose library is found.
    """
    if find_library is None:
        import ctypes.util
        find_library = ctypes.util.find_library
    for variable in ('MUJOCO_GL', 'PYOPENGL_PLATFORM'):
        wanted = environ.get(variable, '').strip().lower()
        if wanted in BACKENDS:
            return wanted
        if wanted and variable == 'MUJOCO_GL':
            raise RenderError(f'MUJOCO_GL={wanted} draws on a display; offscreen rendering '
                              f'takes MUJOCO_GL=osmesa or MUJOCO_GL=egl')
    for backend in BACKENDS:
        if find_library(BACKEND_LIBRARIES[backend]):
            return backend
    raise RenderError(NO_BACKEND)


def open_context(backend: str, width: int, height: int) -> Any:
    """Return a current OpenGL context of ``backend`` of at least width x height pixels."""
    try:
        if backend == 'osmesa':
            from mujoco.osmesa import GLContext
        else:
            from mujoco.egl import GLContext
        context = GLContext(width, height)
        context.make_current()
    # The backend loads native libraries through PyOpenGL: any error means it cannot be used.
    except Exception as exc:
        raise RenderError(f'{NO_BACKEND}: {backend} failed: '
                          f'{_one_line(exc) or type(exc).__name__}') from None
    return context


def robot_color(index: int, alpha: float = 1.0) -> NDArray[np.float32]:
    """Return robot ``index``'s (0-based) colour as RGBA."""
    return np.array(COLORS[index % len(COLORS)] + (alpha,), dtype=np.float32)


class Poser:
    """Sets every robot's joints in a scene's model to a recorded pose."""

    def __init__(self, mj_model: Any, names: Sequence[str]):
        """Find the joints of the robots ``names`` (robot i at entry i - 1) in ``mj_model``."""
        import mujoco
        self.free: List[Tuple[int, int, float]] = []
        """(robot, qpos address, height of the body) of robots on a free joint."""
        self.slides: List[Tuple[int, int, int, float]] = []
        """(robot, axis, qpos address, the carriage's position along the axis)."""
        self.yaws: List[Tuple[int, int, float]] = []
        """(robot, qpos address, the body's own heading in the model)."""

        def find(kind: Any, name: str) -> int:
            return int(mujoco.mj_name2id(mj_model, kind, name))

        joint, body = mujoco.mjtObj.mjOBJ_JOINT, mujoco.mjtObj.mjOBJ_BODY
        for robot, name in enumerate(names):
            root = find(joint, f'{name}_root')
            if root >= 0:
                height = float(mj_model.body_pos[find(body, name)][2])
                self.free.append((robot, int(mj_model.jnt_qposadr[root]), height))
                continue
            carriage = find(body, f'{name}_carriage')
            for axis, letter in enumerate('xyz'):
                slide = find(joint, f'{name}_{letter}')
                if slide >= 0:
                    self.slides.append((robot, axis, int(mj_model.jnt_qposadr[slide]),
                                        float(mj_model.body_pos[carriage][axis])))
            yaw = find(joint, f'{name}_yaw')
            if yaw >= 0:
                w, _, _, z = mj_model.body_quat[find(body, name)]
                self.yaws.append((robot, int(mj_model.jnt_qposadr[yaw]),
                                  2.0 * math.atan2(float(z), float(w))))

    def put(self, qpos: NDArray[np.float64], positions: NDArray[np.float64],
            headings: Optional[NDArray[np.float64]]) -> None:
        """
        Write the poses into ``qpos``: positions (N, dim) of the bodies' frames, m.

        headings (N,), rad, or None to keep each body at its start heading.
        """
        for robot, address, height in self.free:
            qpos[address:address + 2] = positions[robot, :2]
            qpos[address + 2] = height
            if headings is not None:
                half = 0.5 * float(headings[robot])
                qpos[address + 3:address + 7] = (math.cos(half), 0.0, 0.0, math.sin(half))
        for robot, axis, address, origin in self.slides:
            qpos[address] = positions[robot, axis] - origin
        if headings is not None:
            for robot, address, start in self.yaws:
                qpos[address] = float(headings[robot]) - start


def body_positions(trajectory: Trajectory, config: FormationConfig) -> NDArray[np.float64]:
    """
    Return the bodies' frames over the run (T, N, dim), m.

    The axle centres of unicycles (``q_body``, else the hand points less l along the
    heading), the control points of point robots.
    """
    if trajectory.q_body is not None:
        return np.asarray(trajectory.q_body, dtype=float)
    q = np.asarray(trajectory.q, dtype=float)
    hand = config.body.hand_distance
    if trajectory.heading is None or not config.body.is_unicycle or not hand:
        return q
    heading = np.asarray(trajectory.heading, dtype=float)
    return q - hand * np.stack([np.cos(heading), np.sin(heading)], axis=-1)


def _smooth(values: NDArray[np.float64], half: int, widen: bool) -> NDArray[np.float64]:
    """Average over 2 half + 1 frames (after the largest of as many, if widen)."""
    if half <= 0 or len(values) < 2:
        return values
    padded = np.concatenate([np.repeat(values[:1], half, axis=0), values,
                             np.repeat(values[-1:], half, axis=0)])
    windows = np.lib.stride_tricks.sliding_window_view(padded, 2 * half + 1, axis=0)
    if widen:
        widened = windows.max(axis=-1)
        return _smooth(widened, half, False)
    smoothed: NDArray[np.float64] = windows.mean(axis=-1)
    return smoothed


def camera_axes(azimuth: float = AZIMUTH, elevation: float = ELEVATION
                ) -> Tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    """Return a free camera's right, up and forward unit vectors (MuJoCo's convention)."""
    a, e = math.radians(azimuth), math.radians(elevation)
    forward = np.array([math.cos(e) * math.cos(a), math.cos(e) * math.sin(a), math.sin(e)])
    right = np.array([math.sin(a), -math.cos(a), 0.0])
    return right, np.cross(right, forward), forward


def plan_camera(points: NDArray[np.float64], mode: str, half_window: int, fovy: float,
                aspect: float, lowest: float) -> Tuple[NDArray[np.float64], NDArray[np.float64]]:
    """
    Return the camera's look-at points (K, 3) and distances (K,) for K frames.

    points: (K, M, 3) what each frame must show (``fixed``: every frame shows all of them),
    looked at from their box's centre at :data:`AZIMUTH` and :data:`ELEVATION`, each inside
    the picture with :data:`MARGIN` to spare; fovy: the vertical field of view, degrees;
    aspect: width / height; lowest: the smallest radius framed, m.
    """
    if mode == 'fixed':
        points = np.repeat(points.reshape(1, -1, 3), len(points), axis=0)
    centre = 0.5 * (points.min(axis=1) + points.max(axis=1))
    right, up, forward = camera_axes()
    relative = points - centre[:, None, :]
    tan_y = math.tan(math.radians(0.5 * fovy)) / MARGIN
    depth = relative @ forward
    needed = np.maximum(np.abs(relative @ up) / tan_y,
                        np.abs(relative @ right) / (tan_y * aspect)) - depth
    distance = np.maximum(needed.max(axis=1), lowest / tan_y)
    return _smooth(centre, half_window, False), _smooth(distance, half_window, True)


def _lift(points: NDArray[np.float64], dim: int, height: float) -> NDArray[np.float64]:
    """Return points (..., dim) as 3D points, at ``height`` when planar."""
    if dim == 3:
        return points
    lifted = np.full(points.shape[:-1] + (3,), height)
    lifted[..., :2] = points
    return lifted


class Frames:
    """
    Draws the frames of a run: the scene of its parameters, posed sample by sample.

    Use as a context manager (the OpenGL context is freed on exit).
    """

    def __init__(self, trajectory: Trajectory, config: FormationConfig,
                 options: RenderOptions, backend: str, times: NDArray[np.float64]):
        """Build the scene and the renderer; ``times``: the frames' sample times, s."""
        import mujoco
        from formation_ros.physics.scene import build_scene
        self.mujoco = mujoco
        self.trajectory, self.config, self.options = trajectory, config, options
        try:
            scene = build_scene(config)
            self.model = mujoco.MjModel.from_xml_string(scene.xml)
        except (ValueError, mujoco.FatalError) as exc:
            raise RenderError(f'cannot build the scene of the run: {_one_line(exc)}') from None
        self.data = mujoco.MjData(self.model)
        self.names = scene.names
        self.dim = trajectory.dim
        self.poser = Poser(self.model, scene.names)
        self.bodies = body_positions(trajectory, config)
        self.footprint = float(scene.model.footprint)
        self.floor = float(self.model.geom_pos[mujoco.mj_name2id(
            self.model, mujoco.mjtObj.mjOBJ_GEOM, 'floor')][2])
        self._color_robots()
        if self.dim == 3:
            self._fade_obstacles()
        self.height = float(scene.model.height)
        self.radii = np.asarray(config.sensing_radii, dtype=float)
        n = trajectory.num_robots
        self.lines = n <= MAX_LINED_ROBOTS
        decorations = n * (3 + (TRAIL_POINTS + (CIRCLE_SEGMENTS if options.sensing else 0)
                                if self.lines else 0))
        self.model.vis.quality.shadowsize = SHADOW_SIZE
        self.model.vis.global_.offwidth = max(options.width, self.model.vis.global_.offwidth)
        self.model.vis.global_.offheight = max(options.height,
                                               self.model.vis.global_.offheight)
        self._frame_cameras(times)
        self.context = open_context(backend, options.width, options.height)
        self._closed = False
        try:
            self.scene = mujoco.MjvScene(self.model, maxgeom=self.model.ngeom + decorations + 16)
            self.scene.flags[mujoco.mjtRndFlag.mjRND_SHADOW] = options.shadows
            self.option = mujoco.MjvOption()
            self.perturb = mujoco.MjvPerturb()
            scale = (mujoco.mjtFontScale.mjFONTSCALE_100 if options.height < 400
                     else mujoco.mjtFontScale.mjFONTSCALE_150)
            self.render_context = mujoco.MjrContext(self.model, scale.value)
            mujoco.mjr_setBuffer(mujoco.mjtFramebuffer.mjFB_OFFSCREEN.value,
                                 self.render_context)
        except Exception as exc:
            self.close()
            raise RenderError(f'{NO_BACKEND}: {backend} failed: {_one_line(exc)}') from None
        self.viewport = mujoco.MjrRect(0, 0, options.width, options.height)
        self.camera = mujoco.MjvCamera()
        self.camera.type = mujoco.mjtCamera.mjCAMERA_FREE
        self.camera.azimuth = AZIMUTH
        self.camera.elevation = ELEVATION
        self.pixels = np.empty((options.height, options.width, 3), dtype=np.uint8)

    def _color_robots(self) -> None:
        """Give every robot's footprint its own colour."""
        geom = self.mujoco.mjtObj.mjOBJ_GEOM
        for index, name in enumerate(self.names):
            found = self.mujoco.mj_name2id(self.model, geom, f'{name}_footprint')
            if found >= 0:
                self.model.geom_rgba[found] = robot_color(index)

    def _fade_obstacles(self) -> None:
        """Make the obstacles' geoms see-through (:data:`OBSTACLE_ALPHA_3D`)."""
        from formation_ros.physics.obstacles import PREFIX
        geom = self.mujoco.mjtObj.mjOBJ_GEOM
        for index in range(self.model.ngeom):
            name = self.mujoco.mj_id2name(self.model, geom, index) or ''
            if name.startswith(PREFIX):
                self.model.geom_rgba[index, 3] = OBSTACLE_ALPHA_3D

    def _frame_cameras(self, times: NDArray[np.float64]) -> None:
        """Plan the camera of every frame: look-at points and distances."""
        t = self.trajectory.t
        indices = np.clip(np.searchsorted(t, times, side='left'), 0, len(t) - 1)
        shown = self.bodies[indices]
        if self.options.camera == 'fixed':
            shown = np.concatenate([shown, np.asarray(self.trajectory.q_desired)[indices]],
                                   axis=1)
        points = _lift(shown, self.dim, self.height)
        half = int(round(SMOOTHING * self.options.fps))
        lowest = max(MIN_VIEW_RADIUS, 4.0 * self.footprint)
        self.lookat, self.distance = plan_camera(
            points, self.options.camera, half, float(self.model.vis.global_.fovy),
            self.options.width / self.options.height, lowest)
        extent = max(float(self.model.stat.extent), 1e-3)
        needed = 4.0 * (float(np.max(self.distance)) + float(np.max(self.radii))) / extent
        self.model.vis.map.zfar = max(float(self.model.vis.map.zfar), needed)

    def close(self) -> None:
        """Free the OpenGL context (once)."""
        if getattr(self, '_closed', True):
            return
        self._closed = True
        for resource in (getattr(self, 'render_context', None), self.context):
            try:
                if resource is not None:
                    resource.free()
            # Freeing a context the driver already lost must not hide the real outcome.
            except Exception:
                pass

    def __enter__(self) -> 'Frames':
        """Return self."""
        return self

    def __exit__(self, *exc: Any) -> None:
        """Free the context."""
        self.close()

    def _geom(self, kind: Any, size: Sequence[float], pos: Sequence[float],
              rgba: NDArray[np.float32]) -> Any:
        scene = self.scene
        if scene.ngeom >= scene.maxgeom:
            return None
        geom = scene.geoms[scene.ngeom]
        self.mujoco.mjv_initGeom(geom, kind, np.asarray(size, dtype=float),
                                 np.asarray(pos, dtype=float), np.eye(3).ravel(), rgba)
        geom.category = self.mujoco.mjtCatBit.mjCAT_DECOR
        geom.specular = 0.0
        scene.ngeom += 1
        return geom

    def _line(self, start: NDArray[np.float64], end: NDArray[np.float64],
              rgba: NDArray[np.float32]) -> None:
        line = self.mujoco.mjtGeom.mjGEOM_LINE
        geom = self._geom(line, (0.0, 0.0, 0.0), (0.0, 0.0, 0.0), rgba)
        if geom is not None:
            self.mujoco.mjv_connector(geom, line, LINE_WIDTH, start, end)

    def _decorate(self, k: int, trail_start: int) -> None:
        """
        Add sample k's desired formation, paths (from ``trail_start``) and sensing circles.

        The desired positions are joined in the robots' order, as the 2D figures draw them.
        """
        mj = self.mujoco
        trajectory, dim = self.trajectory, self.dim
        floor = self.floor + LIFT
        desired = _lift(np.asarray(trajectory.q_desired[k]), dim, floor)
        steps = max(1, (k - trail_start) // TRAIL_POINTS)
        path = _lift(np.asarray(trajectory.q[trail_start:k + 1:steps]), dim, floor)
        if len(path) and not np.array_equal(path[-1], trajectory.q[k]):
            path = np.concatenate([path, _lift(np.asarray(trajectory.q[k:k + 1]), dim, floor)])
        here = _lift(np.asarray(trajectory.q[k]), dim, floor)
        angles = np.linspace(0.0, 2.0 * math.pi, CIRCLE_SEGMENTS + 1)
        ring = np.stack([np.cos(angles), np.sin(angles), np.zeros_like(angles)], axis=1)
        if trajectory.num_robots >= 3:
            corners = np.vstack([desired, desired[:1]])
            for start, end in zip(corners[:-1], corners[1:]):
                self._line(start, end, FORMATION_COLOR)
        for robot in range(trajectory.num_robots):
            color = robot_color(robot)
            color[:3] *= LINE_SHADE
            marker = robot_color(robot, 0.45)
            if dim == 2:
                self._geom(mj.mjtGeom.mjGEOM_CYLINDER,
                           (self.footprint, MARKER_HEIGHT, 0.0),
                           desired[robot] + (0.0, 0.0, MARKER_HEIGHT - LIFT), marker)
            else:
                self._geom(mj.mjtGeom.mjGEOM_SPHERE, (0.5 * self.footprint, 0.0, 0.0),
                           desired[robot], marker)
            if not self.lines:
                continue
            for start, end in zip(path[:-1, robot], path[1:, robot]):
                self._line(start, end, color)
            if self.options.sensing:
                circle = here[robot] + self.radii[robot] * ring
                faint = robot_color(robot, 0.6)
                for start, end in zip(circle[:-1], circle[1:]):
                    self._line(start, end, faint)

    def draw(self, frame: int, k: int, trail_start: int, caption: str) -> NDArray[np.uint8]:
        """Return frame ``frame`` (H, W, 3): sample k, paths from sample ``trail_start``."""
        mj = self.mujoco
        trajectory = self.trajectory
        headings = None if trajectory.heading is None else trajectory.heading[k]
        self.poser.put(self.data.qpos, self.bodies[k], headings)
        mj.mj_forward(self.model, self.data)
        self.camera.lookat[:] = self.lookat[frame]
        self.camera.distance = float(self.distance[frame])
        mj.mjv_updateScene(self.model, self.data, self.option, self.perturb, self.camera,
                           mj.mjtCatBit.mjCAT_ALL.value, self.scene)
        self._decorate(k, trail_start)
        mj.mjr_render(self.viewport, self.scene, self.render_context)
        mj.mjr_overlay(mj.mjtFont.mjFONT_NORMAL.value, mj.mjtGridPos.mjGRID_TOPLEFT.value,
                       self.viewport, caption, '', self.render_context)
        mj.mjr_readPixels(self.pixels, None, self.viewport, self.render_context)
        return np.flipud(self.pixels).copy()


def check_out(path: str) -> Optional[str]:
    """Say why a GIF cannot be written at ``path``, or None (the file is created and removed)."""
    if not path.lower().endswith('.gif'):
        return f'--out {path}: give a .gif file (the animation is a GIF)'
    if os.path.isdir(path):
        return f'--out {path}: a directory; give a .gif file'
    folder = os.path.dirname(os.path.abspath(path))
    existed = os.path.exists(path)
    try:
        os.makedirs(folder, exist_ok=True)
        with open(path, 'ab'):
            pass
    except OSError as exc:
        return f'cannot write {path}: {exc.strerror or exc}'
    if not existed:
        os.remove(path)
    return None


def gif_palette(samples: Sequence[NDArray[np.uint8]], num_robots: int) -> Any:
    """
    Return the GIF's palette (a Pillow 'P' image) of sample frames (H, W, 3) of a run.

    :data:`GIF_COLORS` colours: the robots' colours at a few shades (their paths and circles
    take them whatever the samples show), the rest the samples' own by median cut.
    """
    from PIL import Image
    shades = np.array([robot_color(robot)[:3] * shade for robot in range(min(num_robots,
                                                                             len(COLORS)))
                       for shade in PALETTE_SHADES] + [FORMATION_COLOR[:3]])
    fixed = np.clip(np.round(255.0 * shades), 0, 255).astype(int).ravel().tolist()
    adaptive = Image.fromarray(np.concatenate(list(samples), axis=0)).quantize(
        GIF_COLORS - len(fixed) // 3, method=Image.Quantize.MEDIANCUT)
    colours = adaptive.getpalette()[:3 * (GIF_COLORS - len(fixed) // 3)] + fixed
    palette = Image.new('P', (1, 1))
    palette.putpalette(colours + [0] * (768 - len(colours)))
    return palette


def render_run(trajectory: Trajectory, config: FormationConfig, path: str,
               options: RenderOptions = RenderOptions(), stream: TextIO = sys.stderr,
               quiet: bool = False, backend: Optional[str] = None) -> Rendered:
    """
    Render a run into the GIF ``path``; return what was written.

    backend: 'osmesa' or 'egl' (default :func:`choose_backend`). Progress lines go to
    ``stream`` at most every 10 % once the render takes over 2 s. RenderError (one line) when
    the run cannot be rendered or the file written; no partial file is left.
    """
    from formation_ros.figures.animate import AnimationError, plan_frames
    from formation_ros.simulation.simulate import Progress
    from PIL import Image
    started = time.monotonic()
    if not (np.all(np.isfinite(trajectory.q)) and np.all(np.isfinite(trajectory.q_desired))):
        raise RenderError('the trajectory has positions that are not finite')
    try:
        plan = plan_frames(trajectory.t, options.fps, options.speed, options.max_frames)
    except AnimationError as exc:
        raise RenderError(str(exc)) from None
    backend = backend or choose_backend()
    try:
        import mujoco
    except ImportError as exc:
        raise RenderError(f'MuJoCo is not installed (pip install mujoco): {exc}') from None
    t = trajectory.t
    duration = float(t[-1] - t[0])
    trail = duration * TRAIL_FRACTION
    progress = Progress(max(duration, 1e-9), stream=stream, quiet=quiet, name=NAME,
                        what='rendering t')
    kind = config.body.kind.value
    frames: List[Any] = []
    palette = None
    try:
        with Frames(trajectory, config, options, backend, t[plan.indices]) as drawer:
            def draw(position: int) -> NDArray[np.uint8]:
                k = int(plan.indices[position])
                caption = (f'{trajectory.num_robots} {kind} robots, {plan.speed:.3g}x\n'
                           f't = {t[k] - t[0]:.1f} s')
                trail_start = int(np.searchsorted(t, t[k] - trail, side='left'))
                return drawer.draw(position, k, trail_start, caption)

            last = len(plan.indices) - 1
            ends = {0: draw(0), last: draw(last)}
            palette = gif_palette([ends[0], ends[last]], trajectory.num_robots)
            for position in range(len(plan.indices)):
                pixels = ends[position] if position in ends else draw(position)
                frames.append(Image.fromarray(pixels).quantize(
                    palette=palette, dither=Image.Dither.NONE))
                progress.update(float(t[plan.indices[position]] - t[0]))
    except (mujoco.FatalError, RuntimeError, ValueError) as exc:
        raise RenderError(f'cannot render the run: {_one_line(exc)}') from None
    partial = path + '.part'
    try:
        frames[0].save(partial, format='GIF', save_all=True, append_images=frames[1:],
                       duration=int(round(1000.0 / plan.fps)), loop=0, optimize=False)
        os.replace(partial, path)
    except OSError as exc:
        if os.path.exists(partial):
            os.remove(partial)
        raise RenderError(f'cannot write {path}: {exc.strerror or exc}') from None
    return Rendered(path, len(frames), plan.fps, plan.speed, backend,
                    time.monotonic() - started)


def default_out(run: str) -> str:
    """Return the GIF a run is rendered into by default: render.gif in a run directory."""
    if os.path.isfile(os.path.join(run, TRAJECTORY_FILE)):
        return os.path.join(run, 'render.gif')
    return os.path.splitext(os.path.normpath(run))[0] + '.gif'


def build_parser() -> argparse.ArgumentParser:
    """Command-line interface of formation_render."""
    parser = argparse.ArgumentParser(
        prog=NAME,
        description='Replay a run in 3D in its MuJoCo world (the bodies of its parameters, '
                    "posed as recorded) and write an animated GIF, drawn by MuJoCo's "
                    'offscreen renderer (OSMesa or EGL: MUJOCO_GL=osmesa|egl chooses).',
        epilog=f'Example: formation_sim config/section5_turtlebot3.yaml --engine mujoco '
               f'--out runs/s5 && {NAME} runs/s5 --out runs/s5.gif')
    parser.add_argument('run', help='run directory (trajectory.npz and params.yaml), rosbag2 '
                                    'directory or .mcap file: what formation_report reads')
    parser.add_argument('--out', help='the GIF to write (default: render.gif in a run '
                                      "directory, else the bag's name with .gif)")
    parser.add_argument('--fps', type=float, default=DEFAULT_FPS,
                        help=f'frames per second of the GIF (default {DEFAULT_FPS:g}; a GIF '
                             'holds each frame a whole number of 1/100 s)')
    parser.add_argument('--speed', type=float,
                        help='simulated seconds per second of GIF (default: real time, faster '
                             'where the run would need more than --max-frames frames)')
    parser.add_argument('--max-frames', type=int, default=DEFAULT_MAX_FRAMES,
                        help=f'at most this many frames, 2 to {MAX_FRAMES} (default '
                             f'{DEFAULT_MAX_FRAMES}); never more than the run has samples')
    parser.add_argument('--width', type=int, default=DEFAULT_WIDTH,
                        help=f'frame width, pixels (default {DEFAULT_WIDTH}, at most {MAX_SIDE})')
    parser.add_argument('--height', type=int, default=DEFAULT_HEIGHT,
                        help=f'frame height, pixels (default {DEFAULT_HEIGHT}, at most '
                             f'{MAX_SIDE})')
    parser.add_argument('--camera', choices=CAMERAS, default='follow',
                        help="'follow' (default): frames the team as it is, zooming out as it "
                             "spreads; 'fixed': frames everything the run visits")
    parser.add_argument('--sensing', action='store_true',
                        help="also draw each robot's sensing circle (radius R_i)")
    parser.add_argument('--no-shadows', action='store_true',
                        help='draw no shadows (with OSMesa, a third less CPU per frame)')
    parser.add_argument('--quiet', action='store_true', help='print no progress')
    return parser


def _fail(message: str) -> int:
    print(f'{NAME}: {message}', file=sys.stderr)
    return 2


def main(argv: Optional[List[str]] = None) -> int:
    """Entry point of ``formation_render``; returns the exit code."""
    parser = build_parser()
    args = parser.parse_args(argv)
    for option, value, low, high in (('--fps', args.fps, 0.0, 100.0),
                                     ('--speed', args.speed, 0.0, math.inf)):
        if value is not None and not (math.isfinite(value) and low < value <= high):
            parser.error(f'{option} must be a number in ({low:g}, {high:g}], got {value}')
    if not 2 <= args.max_frames <= MAX_FRAMES:
        parser.error(f'--max-frames must be 2 to {MAX_FRAMES}, got {args.max_frames}')
    for option, value in (('--width', args.width), ('--height', args.height)):
        if not 16 <= value <= MAX_SIDE:
            parser.error(f'{option} must be 16 to {MAX_SIDE} pixels, got {value}')
    from formation_ros.tools.report import load_run, ReportError
    out = args.out or default_out(args.run)
    notes: List[str] = []
    try:
        trajectory, config, _ = load_run(args.run, notes)
    except ReportError as exc:
        return _fail(_one_line(exc))
    for note in notes:
        print(f'{NAME}: {note}', file=sys.stderr)
    problem = check_out(out)
    if problem is not None:
        return _fail(problem)
    options = RenderOptions(width=args.width, height=args.height, fps=args.fps,
                            speed=args.speed, max_frames=args.max_frames, camera=args.camera,
                            sensing=args.sensing, shadows=not args.no_shadows)
    try:
        rendered = render_run(trajectory, config, out, options, quiet=args.quiet)
    except RenderError as exc:
        return _fail(f'cannot render: {exc}')
    print(f'{NAME}: {rendered.describe()}')
    return 0


if __name__ == '__main__':
    sys.exit(main())
