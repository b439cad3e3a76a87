# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
``formation_sim --engine mujoco``: the law at the control rate on the physics engine, no ROS.

Every control period (``--dt``, a whole number of ``world.timestep``) each robot senses the
measured poses (ground truth with ``world.pose_noise``) of the others within its R_i and the
obstacles (``FormationConfig.law_obstacles``: grown by the footprint, as every run's law sees
them; the world builds the real ones as geoms), the law gives its control point's velocity u
(eq. 14, 25; the hand point of a unicycle), and the command it stands for ((v, w) of a
unicycle, u itself or turned into the body's frame for a point) is applied to the engine,
stamped, and held over the period (zero-order hold) while the engine steps. The samples are
those of every other run (``trajectory.npz``: the control points, the commands as sent, the
headings, axle centres and (v, w) of unicycles); the engine's own counts (contacts between
robots and, apart, with obstacles, the closest approaches, steps, real-time factors) go into
``world_stats.json`` beside ``world.xml``, in the world node's schema
(``core.runs.world_stats``).
"""

from dataclasses import dataclass, replace
import math
import time
from typing import Any, Dict, List, Optional

from formation_ros.core.maths.frames import FrameSample
from formation_ros.core.maths.law import team_command
from formation_ros.core.maths.obstacle_tracking import tracking_command
from formation_ros.core.model.bodies import make_bodies
from formation_ros.core.runs.output import finite_record
from formation_ros.core.runs.timeline import Shape, Timeline
from formation_ros.core.runs.trajectory import Trajectory
from formation_ros.core.runs.world_stats import WorldRunStats
from formation_ros.core.settings.declarations import CommandFrame
from formation_ros.core.settings.params import FormationConfig, world_size_problem, WorldSettings
import numpy as np

DEFAULT_CONTROL_DT = 0.02
"""The control period of an engine run without ``--dt``, s (the robots' default 50 Hz)."""
STEP_TOLERANCE = 1e-9
"""A control period is a whole number of engine steps when within this fraction of one."""


@dataclass(frozen=True)
class EngineRun:
    """
    A run on the engine: its samples and what the engine did.

    trajectory: the samples; stats: what the run did (``world_stats.json``; its wall_time is
    the loop of law and engine); failure: the one line of an engine that blew up
    (``physics.engine.unstable_line``: the run stops there), None if none; note: a line on
    bodies larger than the law keeps off the obstacles (``physics.obstacles.footprint_note``),
    None if none.
    """

    trajectory: Trajectory
    stats: WorldRunStats
    failure: Optional[str] = None
    note: Optional[str] = None


def engine_problem(config: FormationConfig, control_dt: float) -> Optional[str]:
    """Say why ``config`` cannot run on the engine with ``control_dt`` s, or None."""
    world = config.world or WorldSettings()
    too_many = world_size_problem(config.num_robots)
    if too_many:
        return f'num_robots: {too_many}'
    steps = control_dt / world.timestep
    if steps < 1.0 - STEP_TOLERANCE or abs(steps - round(steps)) > STEP_TOLERANCE * steps:
        return (f'--dt {control_dt:g} s must be a whole number of world.timestep = '
                f'{world.timestep:g} s')
    if control_dt >= world.cmd_timeout:
        return (f'--dt {control_dt:g} s would let every command go stale: it must be less '
                f'than world.cmd_timeout = {world.cmd_timeout:g} s')
    if not config.imperfections.is_ideal:
        return ('plant.actuator_lag, plant.max_acceleration, plant.pose_noise and '
                "plant.state_delay are the plant model's; on the engine the bodies have their "
                'own physics (world.*: world.pose_noise for noisy poses)')
    return None


def run_on_engine(config: FormationConfig, duration: float, control_dt: float,
                  sample_dt: float, shapes: Timeline[Shape], progress: Any) -> EngineRun:
    """
    Run the law every ``control_dt`` s on the engine for ``duration`` s; return the run.

    sample_dt: spacing of the samples, s (rounded to whole control periods, at least one);
    shapes: the shape in force at each time (``simulate.shapes_of``); progress: a
    ``simulate.Progress``. The engine's ``world.output_dir`` is not used.
    """
    from formation_ros.physics.engine import Engine, Unstable, unstable_line
    from formation_ros.physics.obstacles import footprint_note
    engine = Engine(config)
    begun = time.perf_counter()
    failure: Optional[str] = None
    law, reference = config.law(), config.reference()
    obstacles = config.law_obstacles()
    bodies = make_bodies(config.body, body_frame=config.command.frame is CommandFrame.BODY
                         and not config.body.is_unicycle)
    steps_per_control = int(round(control_dt / engine.world.timestep))
    controls = int(round(duration / control_dt))
    stride = max(1, int(round(sample_dt / control_dt)))
    n, dim = config.num_robots, config.dim
    times: List[float] = []
    points_kept, applied, headings, q_body, held = [], [], [], [], []
    frames: List[FrameSample] = []
    vertices_kept = []
    for k in range(controls + 1):
        t = engine.time_s
        measured = engine.measured_poses()
        heading = measured.headings
        points = bodies.control_points(measured.positions[:, :dim], heading)
        frame = reference.sample(t)
        vertices = shapes.at(engine.time_ns).vertices
        u = tracking_command(team_command(points, vertices, config.sensing_radii, law, frame,
                                          obstacles=obstacles),
                             points, frame, law, obstacles, config.sensing_radii).u
        command = bodies.body_command(u, heading)
        if k % stride == 0 or k == controls:
            truth = engine.poses()
            true_heading = truth.headings
            times.append(t)
            points_kept.append(bodies.control_points(truth.positions[:, :dim], true_heading))
            applied.append(u)
            frames.append(frame)
            vertices_kept.append(vertices)
            headings.append(true_heading)
            q_body.append(truth.positions[:, :dim])
            held.append(command)
        if k == controls:
            break
        progress.update(t)
        engine.apply(command, np.full(n, engine.time_ns, dtype=np.int64))
        try:
            engine.step(steps_per_control)
        except Unstable as exc:
            failure = unstable_line(exc, engine.world, config.body.is_unicycle)
            break
    trajectory = Trajectory.from_frames(times, points_kept, applied, frames, vertices_kept,
                                        config.feed_forward_guard())
    if bodies.has_heading:
        trajectory = replace(trajectory, heading=np.array(headings), q_body=np.array(q_body),
                             body_command=np.array(held))
    return EngineRun(trajectory, engine.stats(time.perf_counter() - begun), failure,
                     footprint_note(engine.obstacles, config.body.radius,
                                    engine.model.footprint))


def engine_metrics(run: EngineRun) -> Dict[str, Any]:
    """Return the metrics.json keys of an engine run: world_stats.json's under ``world``."""
    world = finite_record(run.stats.record())
    world.pop('contact_events')
    world.pop('obstacle_contact_events')
    return {'engine': 'mujoco', 'mujoco_version': run.stats.mujoco_version, 'world': world}


def engine_summary(run: EngineRun) -> str:
    """Return the summary line of the engine's counts."""
    stats = run.stats
    obstacles = ('' if not math.isfinite(stats.min_obstacle_gap) else
                 f', {stats.obstacle_contacts} with obstacles (closest body '
                 f'{stats.min_obstacle_gap:+.4g} m from an obstacle)')
    return (f'  physics (MuJoCo {stats.mujoco_version}): {stats.contacts} contact '
            'event(s) between robots, closest approach of two bodies '
            f'{stats.min_body_distance:.4g} m (footprints '
            f'{stats.min_footprint_gap:+.4g} m apart){obstacles}, {stats.steps} steps at '
            f'{stats.achieved_realtime_factor:.1f}x real time'
            + (f'\n  note: {run.note}' if run.note else ''))
