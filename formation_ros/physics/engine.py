# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
The physics engine of a formation's bodies (MuJoCo): step, apply commands, read the bodies.

:class:`Engine` is the one interface the offline simulator and a world node drive, as
crazyswarm2's simulator backends share one. It builds the scene of a validated configuration
(:mod:`formation_ros.physics.scene`) and then

* :meth:`Engine.apply` takes commands (N, width) in each robot's command frame ((v, w) of a
  unicycle; the velocity of a point in the world or, with ``command.frame: body``, its body
  frame), each stamped (ns of simulated time). A command is held until the next; one older
  than ``world.cmd_timeout``, or none at all, stops the robot's motors (their set points are
  zero), as ``diff_drive_controller`` does. It takes commands an intake admitted
  (``core.rules.admission.command_refusal``: finite) and raises ValueError on any other. A
  command beyond the motors is not refused: the motors are limited;
* :meth:`Engine.step` advances ``world.timestep`` at a time (integer ns: :attr:`time_ns`);
* :meth:`Engine.poses` is the ground truth (positions (N, 3) m, orientations (N, 4)
  quaternions x, y, z, w), :meth:`Engine.measured_poses` the same with ``world.pose_noise``,
  :meth:`Engine.odometry` the wheel-encoder odometry of differential-drive bases (updated
  every ``odometry.ODOMETRY_PERIOD``);
* :attr:`Engine.contacts` counts contact events between robots from MuJoCo's contact list and
  :attr:`Engine.closest` keeps the closest approach of two robots' positions; with obstacles
  (``obstacles.*``, static geoms: ``physics.obstacles``) :attr:`Engine.obstacle_contacts`
  counts a robot's contacts with them apart and :attr:`Engine.obstacle_approach` keeps the
  smallest gap of a body to an obstacle's surface (ground truth, footprint subtracted);
* :meth:`Engine.scans` casts the planar bodies' laser scans (``physics.scanner``);
* :meth:`Engine.stats` is what the run did (``core.runs.world_stats.WorldRunStats``).

A step that makes a body's pose non-finite or absurd (MuJoCo's own check of the state, which
resets it, or a body faster than :data:`ABSURD_SPEED`) raises :class:`Unstable` naming the
robot and the simulated time; the engine then refuses to step again, and its poses are those
of the step before (docs/physics.md, "When the engine blows up").
"""

from dataclasses import dataclass
import time
from typing import Dict, Optional, Sequence, Tuple

from formation_ros.core.maths.obstacles import Obstacles
from formation_ros.core.maths.unicycle import headings_from_quaternions
from formation_ros.core.maths.units import NS_PER_S
from formation_ros.core.model.dynamics import NOISE_SEED_OFFSET
from formation_ros.core.rules.pacing import Pacer
from formation_ros.core.runs.world_stats import (BlowUp, Contact, ObstacleContact, ratio,
                                                 WorldRunStats)
from formation_ros.core.settings.params import FormationConfig, WorldSettings
from formation_ros.physics.contacts import (ClosestApproach, ContactLog, ObstacleApproach,
                                            ObstacleContactLog, RELEASE_GAP)
from formation_ros.physics.diff_drive import DiffDrive
from formation_ros.physics.obstacles import obstacle_of_geom
from formation_ros.physics.odometry import ODOMETRY_PERIOD, WheelOdometry
from formation_ros.physics.scanner import Scanner
from formation_ros.physics.scene import build_scene, Scene
import mujoco
import numpy as np
from numpy.typing import ArrayLike, NDArray

Float = NDArray[np.float64]
WXYZ_TO_XYZW = (1, 2, 3, 0)
"""MuJoCo's quaternions are (w, x, y, z), the package's (x, y, z, w)."""
ABSURD_SPEED = 100.0
"""A pose body moving faster than this, m/s, is taken for an engine that blew up: a thousand
times a TurtleBot3's 0.22 m/s; MuJoCo's own check misses the growth that comes before."""
BAD_STATE = (int(mujoco.mjtWarning.mjWARN_BADQPOS), int(mujoco.mjtWarning.mjWARN_BADQVEL),
             int(mujoco.mjtWarning.mjWARN_BADQACC))
"""MuJoCo's warnings of a state it found non-finite or huge (it then resets the state)."""
BAD_STATE_WORDS = ('its position', 'its velocity', 'its acceleration')


class Unstable(Exception):
    """
    The engine blew up: robot ``robot`` (1-based) got an absurd pose at ``t`` s (simulated).

    what: what was wrong, in a few words.
    """

    def __init__(self, robot: int, t: float, what: str) -> None:
        """Keep the robot, the time and what was wrong."""
        super().__init__(f'robot {robot}: {what} at t = {t:.3f} s')
        self.robot, self.t, self.what = robot, t, what


UNSTABLE_SETTINGS = {True: ('timestep', 'mass', 'wheel_torque', 'wheel_radius', 'floor_friction'),
                     False: ('timestep', 'mass', 'force_limit', 'torque_limit', 'floor_friction')}
"""The world.* settings named with their values when the engine blows up, for wheeled bases
(True) and for points: those the unstable cases combined (docs/physics.md, "When the engine
blows up")."""


def unstable_line(failure: Unstable, world: WorldSettings, wheeled: bool) -> str:
    """Return the one line that says the engine blew up: robot, time and the settings in force."""
    values = ', '.join(f'world.{name} {getattr(world, name):g}'
                       for name in UNSTABLE_SETTINGS[wheeled])
    return (f'the physics engine blew up: {failure}; stopped there, no pose after it ({values}: '
            'a shorter timestep, or less extreme bodies)')


def _quiet(message: bytes) -> None:
    """Keep MuJoCo's warnings off the terminal: the engine reads them from its data."""


@dataclass(frozen=True)
class Poses:
    """Positions (N, 3) in m and orientations (N, 4) as unit quaternions (x, y, z, w)."""

    positions: Float
    orientations: Float

    @property
    def headings(self) -> Float:
        """Return the yaw of each orientation (N,), rad."""
        return headings_from_quaternions(self.orientations)


class Engine:
    """A formation's bodies on MuJoCo; see the module's docstring."""

    def __init__(self, config: FormationConfig, world: Optional[WorldSettings] = None):
        """Build the scene of ``config`` (validated with a start) with ``world`` (default its)."""
        self.world = world or config.world or WorldSettings()
        mujoco.set_mju_user_warning(_quiet)
        self.failure: Optional[Unstable] = None
        self.scene: Scene = build_scene(config, self.world)
        self.model = self.scene.model
        self.mj_model = mujoco.MjModel.from_xml_string(self.scene.xml)
        self.data = mujoco.MjData(self.mj_model)
        self.num_robots = len(self.scene.names)
        self.dim = self.scene.dim
        self.steps = 0
        self.wall = 0.0
        n, width = self.num_robots, self.model.command_width
        self.command = np.zeros((n, width))
        self.stamp_ns = np.zeros(n, dtype=np.int64)
        self.present = np.zeros(n, dtype=bool)
        self.timeout_ns = self.world.cmd_timeout_ns
        self.step_ns = self.world.timestep_ns
        self._pose_bodies = np.array([self._id(mujoco.mjtObj.mjOBJ_BODY, name)
                                      for name in self.scene.names])
        self._geom_robot = self._robots_of_geoms()
        self._body_robot = self._robots_of_bodies()
        self._warnings = self.data.warning.number[list(BAD_STATE)].copy()
        self._noise = np.random.default_rng([self.world.seed, NOISE_SEED_OFFSET])
        mujoco.mj_forward(self.mj_model, self.data)
        start = self.poses()
        self.contacts = ContactLog(n, 2.0 * self.model.footprint + RELEASE_GAP)
        self.closest = ClosestApproach(start.positions[:, :self.dim],
                                       2.0 * self.model.footprint)
        self.obstacles = config.obstacles or Obstacles(
            np.zeros((0, 3)), np.zeros((0, 5)), np.zeros((0, 4)), 1.0, self.dim)
        self.labels = self.obstacles.labels()
        self._geom_obstacle = np.array([
            obstacle_of_geom(mujoco.mj_id2name(self.mj_model, mujoco.mjtObj.mjOBJ_GEOM, geom),
                             self.obstacles) for geom in range(self.mj_model.ngeom)],
            dtype=np.intp)
        self.obstacle_contacts = ObstacleContactLog(self.obstacles, self.model.footprint)
        self.obstacle_approach = ObstacleApproach(self.obstacles, self.model.footprint,
                                                  start.positions[:, :self.dim])
        self._last_positions = start.positions[:, :self.dim].copy()
        self._max_move = ABSURD_SPEED * self.world.timestep
        self._no_yaw = np.zeros(n)
        self._live = np.zeros(n, dtype=bool)
        self._changed = True
        self.odometer: Optional[WheelOdometry] = None
        self._odometry_steps = max(1, int(round(ODOMETRY_PERIOD / self.world.timestep)))
        if isinstance(self.model, DiffDrive):
            self._wheel_angles = np.array([[self._angle(f'{name}_{side}_wheel')
                                            for side in ('left', 'right')]
                                           for name in self.scene.names])
            self.odometer = WheelOdometry(self.model, start.positions[:, :2], start.headings,
                                          self.data.qpos[self._wheel_angles])
        self.scanner: Optional[Scanner] = None
        if self.dim == 2 and self.world.scan_rate > 0.0:
            footprint = self._id(mujoco.mjtObj.mjOBJ_GEOM, f'{self.scene.names[0]}_footprint')
            self.scanner = Scanner(self.mj_model, self._pose_bodies,
                                   float(self.data.geom_xpos[footprint, 2]), self.world)

    def _id(self, kind: 'mujoco.mjtObj', name: str) -> int:
        index = int(mujoco.mj_name2id(self.mj_model, kind, name))
        if index < 0:
            raise KeyError(f'no {kind.name} {name!r} in the scene')
        return index

    def _angle(self, joint: str) -> int:
        """Return where hinge ``joint``'s angle is in qpos."""
        return int(self.mj_model.jnt_qposadr[self._id(mujoco.mjtObj.mjOBJ_JOINT, joint)])

    def _robots_of_bodies(self) -> NDArray[np.intp]:
        """Return the robot (0-based) each body belongs to, -1 for the world's: (nbody,)."""
        robot_of_root = np.full(self.mj_model.nbody, -1, dtype=np.intp)
        roots = self.mj_model.body_rootid[self._pose_bodies]
        robot_of_root[roots] = np.arange(self.num_robots)
        result: NDArray[np.intp] = robot_of_root[self.mj_model.body_rootid]
        return result

    def _robots_of_geoms(self) -> NDArray[np.intp]:
        """Return the robot (0-based) each geom belongs to, -1 for the world's: (ngeom,)."""
        result: NDArray[np.intp] = self._robots_of_bodies()[self.mj_model.geom_bodyid]
        return result

    @property
    def version(self) -> str:
        """Return MuJoCo's version."""
        return str(mujoco.__version__)

    @property
    def time_ns(self) -> int:
        """Return the simulated time since the start, ns."""
        return self.steps * self.step_ns

    @property
    def time_s(self) -> float:
        """Return the simulated time since the start, s."""
        return self.time_ns / NS_PER_S

    def apply(self, commands: ArrayLike, stamps_ns: Optional[ArrayLike] = None,
              robots: Optional[Sequence[int]] = None) -> None:
        """
        Take commands (K, width) of ``robots`` (K 0-based indices; default all N, in order).

        stamps_ns: (K,) the stamp of each command, ns of simulated time (default: now). The
        commands replace the robots' own. They are admitted ones (finite: the intake refused the
        others, ``core.rules.admission.command_refusal``); ValueError if one is not.
        """
        rows = (np.arange(self.num_robots) if robots is None
                else np.asarray(robots, dtype=np.intp))
        given = np.asarray(commands, dtype=float).reshape(len(rows), self.model.command_width)
        if not np.all(np.isfinite(given)):
            raise ValueError('Engine.apply takes admitted (finite) commands only')
        stamps = (np.full(len(rows), self.time_ns, dtype=np.int64) if stamps_ns is None
                  else np.asarray(stamps_ns, dtype=np.int64).reshape(len(rows)))
        self.command[rows] = given
        self.stamp_ns[rows] = stamps
        self.present[rows] = True
        self._changed = True

    def live(self) -> NDArray[np.bool_]:
        """Tell which robots' commands drive their motors now: given, not stale (N,)."""
        live: NDArray[np.bool_] = self.present & (self.time_ns - self.stamp_ns
                                                  <= self.timeout_ns)
        return live

    def _controls(self) -> None:
        """Set the motors' set points: from the live commands, zero for the others."""
        live = self.live()
        if not (self._changed or self.model.needs_yaw or np.any(live != self._live)):
            return
        self._changed, self._live = False, live
        held = np.where(live[:, None], self.command, 0.0)
        yaw = self.poses().headings if self.model.needs_yaw else self._no_yaw
        self.data.ctrl[:] = self.model.controls(held, yaw).ravel()

    def step(self, n_steps: int = 1) -> None:
        """
        Advance ``n_steps`` engine steps, each ``world.timestep``.

        Raises :class:`Unstable` at the first step that leaves a pose non-finite or absurd
        (then at every call: the engine does not step again).
        """
        if self.failure is not None:
            raise self.failure
        begun = time.perf_counter()
        try:
            for _ in range(int(n_steps)):
                self._controls()
                mujoco.mj_step(self.mj_model, self.data)
                self._check()
                self.steps += 1
                self._observe()
        finally:
            self.wall += time.perf_counter() - begun

    def _check(self) -> None:
        """After a step: raise :class:`Unstable` if the state is non-finite or absurd."""
        warnings = self.data.warning.number[list(BAD_STATE)]
        positions = self.data.xpos[self._pose_bodies, :self.dim]
        moves = np.abs(positions - self._last_positions)
        if np.array_equal(warnings, self._warnings) and np.all(moves <= self._max_move):
            self._last_positions = positions.copy()
            return
        t = (self.steps + 1) * self.step_ns / NS_PER_S
        changed = np.flatnonzero(warnings != self._warnings)
        if len(changed):
            kind = int(changed[0])
            self.failure = Unstable(self._robot_of_warning(kind), t,
                                    f'MuJoCo found {BAD_STATE_WORDS[kind]} non-finite or huge')
        else:
            worst = np.nan_to_num(moves, nan=np.inf).max(axis=1)
            robot = int(np.argmax(worst))
            self.failure = Unstable(robot + 1, t, 'its pose moved faster than '
                                                  f'{ABSURD_SPEED:g} m/s (or not finite)')
        raise self.failure

    def _robot_of_warning(self, kind: int) -> int:
        """Return the robot (1-based) of MuJoCo's last warning of bad state ``kind`` (0: none)."""
        where = int(self.data.warning.lastinfo[BAD_STATE[kind]])
        model = self.mj_model
        if BAD_STATE[kind] == int(mujoco.mjtWarning.mjWARN_BADQPOS):
            joint = max(int(np.searchsorted(model.jnt_qposadr, where, side='right')) - 1, 0)
            body = int(model.jnt_bodyid[joint])
        else:
            body = int(model.dof_bodyid[min(where, model.nv - 1)])
        return int(self._body_robot[body]) + 1

    def _observe(self) -> None:
        """After a step: odometry, contacts, the closest approaches (robots, obstacles)."""
        if self.odometer is not None and self.steps % self._odometry_steps == 0:
            self.odometer.advance(self.data.qpos[self._wheel_angles],
                                  self._odometry_steps * self.world.timestep)
        contact = self.data.contact
        robots = self._geom_robot[contact.geom]
        touching = contact.dist <= 0.0
        between = ((robots[:, 0] >= 0) & (robots[:, 1] >= 0) & (robots[:, 0] != robots[:, 1])
                   & touching)
        positions = self.data.xpos[self._pose_bodies, :self.dim]
        if np.any(between) or len(self.contacts.touching):
            self.contacts.update(robots[between, 0], robots[between, 1], positions,
                                 self.time_ns)
        self.closest.update(positions, self.time_ns)
        if not self.obstacles.count:
            return
        obstacles = self._geom_obstacle[contact.geom]
        robot = np.max(robots, axis=1)
        obstacle = np.max(obstacles, axis=1)
        hit = touching & (robot >= 0) & (obstacle >= 0)
        if np.any(hit) or len(self.obstacle_contacts.touching):
            self.obstacle_contacts.update(robot[hit], obstacle[hit], positions, self.time_ns)
        self.obstacle_approach.update(positions, self.time_ns)

    def poses(self) -> Poses:
        """Return the ground truth: every robot's pose body (the axle centre of a base)."""
        return Poses(self.data.xpos[self._pose_bodies].copy(),
                     self.data.xquat[self._pose_bodies][:, WXYZ_TO_XYZW])

    def measured_poses(self) -> Poses:
        """Return the ground truth with Gaussian noise of ``world.pose_noise`` m on positions."""
        truth = self.poses()
        if self.world.pose_noise <= 0.0:
            return truth
        noisy = truth.positions.copy()
        noisy[:, :self.dim] += self._noise.normal(0.0, self.world.pose_noise,
                                                  (self.num_robots, self.dim))
        return Poses(noisy, truth.orientations)

    def planar_state(self) -> Tuple[Float, Float]:
        """Return the true positions (N, dim), m, and headings (N,), rad."""
        truth = self.poses()
        return truth.positions[:, :self.dim], truth.headings

    def scans(self) -> Float:
        """
        Return every robot's laser scan now (N, world.scan_rays), m; +inf: no return.

        At the pose bodies' positions of :meth:`poses` (``physics.scanner``); ValueError without
        a scanner (3D flyers, ``world.scan_rate`` 0).
        """
        if self.scanner is None:
            raise ValueError('no scanner: only planar bodies with world.scan_rate > 0 have one')
        return self.scanner.scan(self.data)

    def odometry(self) -> Tuple[Float, Float]:
        """Return the wheel odometry's positions (N, 2), m, and headings (N,), rad."""
        if self.odometer is None:
            raise ValueError('only differential-drive bases have wheel odometry')
        return self.odometer.pose()

    def velocities(self) -> Float:
        """Return each pose body's world linear velocity (N, 3), m/s."""
        result = np.empty((self.num_robots, 6))
        for row, body in enumerate(self._pose_bodies):
            mujoco.mj_objectVelocity(self.mj_model, self.data, mujoco.mjtObj.mjOBJ_XBODY,
                                     int(body), result[row], 0)
        return result[:, 3:]

    def stats(self, wall_time: float, pacer: Optional[Pacer] = None,
              stale: Optional[Dict[int, int]] = None,
              refused: Optional[Dict[str, Dict[int, int]]] = None) -> WorldRunStats:
        """
        Return what the run did so far (``world_stats.json``).

        wall_time: wall-clock s since the first step; pacer: the world node's (the factor asked
        for, the ticks behind and the time let go), None for a run as fast as it can; stale:
        {robot (1-based): commands already stale when applied}; refused: {reason: {robot:
        cmd_vel refused}}.
        """
        simulated = self.time_s
        failure = self.failure
        return WorldRunStats(
            contacts=self.contacts.count, min_body_distance=self.closest.distance,
            min_footprint_gap=self.closest.distance - 2.0 * self.model.footprint,
            obstacle_contacts=self.obstacle_contacts.count,
            min_obstacle_gap=self.obstacle_approach.gap,
            steps=self.steps, engine_realtime_factor=ratio(simulated, self.wall),
            achieved_realtime_factor=ratio(simulated, wall_time),
            realtime_factor=None if pacer is None else pacer.factor, wall_time=wall_time,
            simulated_time=simulated, steps_per_second=ratio(self.steps, wall_time),
            ticks_behind=0 if pacer is None else pacer.falls,
            simulated_time_let_go=0.0 if pacer is None else pacer.dropped_s,
            contact_events=[Contact(event.i, event.j, event.t) for event in self.contacts.events],
            obstacle_contact_events=[ObstacleContact(event.robot, self.labels[event.obstacle],
                                                     event.t)
                                     for event in self.obstacle_contacts.events],
            stale_command_messages=dict(stale or {}), model=self.model.kind.value,
            timestep=self.world.timestep,
            unstable=None if failure is None else BlowUp(failure.robot, failure.t, failure.what),
            refused_command_messages=dict(refused or {}), engine_wall_time=self.wall,
            mujoco_version=self.version)
