# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
The offline simulator: the closed loop q' = u of eqs. (1), (14), (25), without ROS.

``simulate`` integrates the paper's continuous-time system (adaptive RK45 at rtol 1e-8; the
unicycles' own equations with the law on their hand points); ``run_fixed_step`` steps the plant
model every ``dt`` with the command held (zero-order hold), as the plant node does, including
the bodies' imperfections (``core.model.dynamics``); ``run_metrics`` and ``format_summary`` make
metrics.json and its summary. With obstacles (beyond the paper) the law keeps the control points
off the obstacles grown by the footprint, a moving reference's feed-forward is guarded near them
(``core.maths.obstacle_tracking``), and RK45's step is capped (:func:`obstacle_step`).
``formation_sim`` (``tools.sim``) is the command line over it; the benches and the report use
it too.
"""

from dataclasses import dataclass, replace
import math
import sys
import time
from typing import Callable, Optional, Sequence, TextIO, Tuple

from formation_ros.core.maths.frames import desired_positions, FrameSample, from_frame_velocity
from formation_ros.core.maths.law import Command, LawParams, team_command
from formation_ros.core.maths.obstacle_tracking import tracking_command
from formation_ros.core.maths.obstacles import Obstacles
from formation_ros.core.maths.safety import body_clearance, guaranteed_min_distance
from formation_ros.core.maths.unicycle import unicycle_rates
from formation_ros.core.maths.units import NS_PER_S
from formation_ros.core.model.bodies import make_bodies, UnicycleBodies
from formation_ros.core.model.plant import Commands, PlantCounts, PlantModel
from formation_ros.core.runs.events import Event, EventKind, timeline_events, with_shapes
from formation_ros.core.runs.metrics import (body_metrics, compute_metrics, held_metrics,
                                             segment_metrics)
from formation_ros.core.runs.obstacle_metrics import (obstacle_metrics, STILL_SPEED, STILL_TIME,
                                                      stuck_line, stuck_robots)
from formation_ros.core.runs.timeline import Mode, scheduled_shapes, Shape, TeamState, Timeline
from formation_ros.core.runs.trajectory import Trajectory
from formation_ros.core.settings.declarations import CommandFrame, DEFAULT_COLLISION_DISTANCE
from formation_ros.core.settings.params import FormationConfig
import numpy as np


RTOL = 1e-8
ATOL = 1e-10
DEFAULT_SAMPLE_DT = 0.01
MAX_ROBOT_SAMPLES = 5_000_000
"""Without ``--sample-dt`` a run saves at most this many robot-samples (robots x samples): a
larger team is sampled at the smallest whole multiple of :data:`DEFAULT_SAMPLE_DT` that keeps
within it (:func:`default_sample_dt`), so 10,000 robots over 20 s are saved every 0.05 s and
the samples stay well under a gigabyte; smaller runs are sampled as before."""
MAX_STEPS = 10_000_000
METRICS_FILE = 'metrics.json'
PARAMS_COPY = 'params.yaml'


class Progress:
    """Prints how far a long run is, at most every 10 % of simulated time, once past 2 s wall."""

    def __init__(self, duration: float, stream: TextIO = sys.stderr, quiet: bool = False,
                 name: str = 'formation_sim', what: str = 't'):
        """Track a run of ``duration`` simulated seconds; lines read '<name>: <what> = ...'."""
        self.duration = duration
        self.stream = stream
        self.quiet = quiet
        self.name = name
        self.what = what
        self.start = time.monotonic()
        self.next_mark = 0.1

    def update(self, t: float) -> None:
        """Report simulated time t if a new 10 % mark was passed and the run is slow enough."""
        fraction = t / self.duration
        if self.quiet or fraction < self.next_mark:
            return
        elapsed = time.monotonic() - self.start
        self.next_mark = math.floor(fraction * 10.0 + 1.0) / 10.0
        if elapsed > 2.0:
            print(f'{self.name}: {self.what} = {t:.2f} / {self.duration:.2f} s '
                  f'({100.0 * fraction:.0f} %), {elapsed:.1f} s elapsed',
                  file=self.stream, flush=True)

    @property
    def elapsed(self) -> float:
        """Wall-clock seconds since the start."""
        return time.monotonic() - self.start


def sample_times(duration: float, sample_dt: float) -> np.ndarray:
    """Sample times 0, sample_dt, ..., duration (the end always included): (T,)."""
    count = int(math.floor(duration / sample_dt + 1e-9))
    times = np.arange(count + 1) * sample_dt
    if duration - times[-1] > 1e-9 * max(1.0, duration):
        times = np.append(times, duration)
    return times


def sample_count(duration: float, dt: Optional[float], sample_dt: float) -> int:
    """
    How many samples a run of ``duration`` s saves at ``sample_dt`` s (the end included).

    dt: the fixed step of a ``--dt`` run (whose samples are every round(sample_dt / dt) steps,
    at least one), None for RK45 (:func:`sample_times`).
    """
    if dt is None:
        count = int(math.floor(duration / sample_dt + 1e-9))
        return count + 1 + int(duration - count * sample_dt > 1e-9 * max(1.0, duration))
    steps = int(round(duration / dt))
    stride = max(1, int(round(sample_dt / dt)))
    return -(-steps // stride) + 1


def default_sample_dt(num_robots: int, duration: float, dt: Optional[float]) -> float:
    """
    Return the sample spacing of a run without ``--sample-dt``, s (:data:`MAX_ROBOT_SAMPLES`).

    :data:`DEFAULT_SAMPLE_DT`, or, when ``num_robots`` times the samples it gives
    (:func:`sample_count`) would exceed :data:`MAX_ROBOT_SAMPLES`, the smallest whole multiple
    of it that keeps them within (at most the duration: then only the start and the end).
    """
    def fits(multiple: int) -> bool:
        spacing = multiple * DEFAULT_SAMPLE_DT
        return (spacing >= duration
                or num_robots * sample_count(duration, dt, spacing) <= MAX_ROBOT_SAMPLES)

    if fits(1):
        return DEFAULT_SAMPLE_DT
    multiple = max(2, int(num_robots * duration / (DEFAULT_SAMPLE_DT * MAX_ROBOT_SAMPLES)) - 1)
    while not fits(multiple):
        multiple += 1
    return min(float(f'{multiple * DEFAULT_SAMPLE_DT:.12g}'), duration)


def sampling_metadata(num_robots: int, duration: float, dt: Optional[float],
                      given: Optional[float]) -> dict:
    """
    metrics.json keys that say how the run was sampled.

    ``sample_dt``: the spacing asked for, s (``--sample-dt``, else :func:`default_sample_dt`);
    ``sampling``: 'given', 'default', or 'default, thinned' when the rule of
    :data:`MAX_ROBOT_SAMPLES` widened the default; ``max_robot_samples``: that cap.
    """
    spacing = default_sample_dt(num_robots, duration, dt) if given is None else given
    rule = ('given' if given is not None else 'default' if spacing == DEFAULT_SAMPLE_DT
            else 'default, thinned')
    return {'sample_dt': spacing, 'sampling': rule, 'max_robot_samples': MAX_ROBOT_SAMPLES}


def shapes_of(config: FormationConfig) -> Timeline[Shape]:
    """Return the shape in force at each time: the file's, then its scheduled switches."""
    return scheduled_shapes(Shape(config.shape_name, config.vertices), config.schedule,
                            config.shapes)


def schedule_events(config: FormationConfig) -> Tuple[Event, ...]:
    """Return the events of the file's switch schedule (``formation.schedule.*``)."""
    start = TeamState.of(Mode.RUNNING, config.shape_name, config.reference())
    return timeline_events(shapes_of(config), Timeline(start))


def vertices_at(shapes: Timeline[Shape], t: float) -> np.ndarray:
    """Return the vertices (N, dim) in force at t in s."""
    return shapes.at(int(round(t * NS_PER_S))).vertices


def integrate_segments(rhs: Callable[[float, np.ndarray, np.ndarray], np.ndarray],
                       start: np.ndarray, times: np.ndarray,
                       shapes: Timeline[Shape],
                       max_step: float = math.inf) -> Tuple[np.ndarray, np.ndarray]:
    """
    RK45 from one shape switch to the next, each segment with its shape's vertices.

    rhs(t, y, vertices); times: the sample times (T,). A switch makes the right-hand side jump,
    so each segment is integrated on its own from where the last ended. max_step: the longest
    step RK45 may take, s (:func:`obstacle_step`). Returns (t (T,), y (T, len(start))).
    """
    from scipy.integrate import solve_ivp  # RK45 only: a --dt run does not load it
    ends = [stamp / NS_PER_S for stamp, _ in shapes.changes() if 0.0 < stamp / NS_PER_S
            < times[-1]] + [float(times[-1])]
    t_out, y_out, begin, y0 = [], [], 0.0, start
    for end in ends:
        vertices = vertices_at(shapes, begin)
        inside = times[(times >= begin) & ((times < end) | (end == times[-1]))]
        solution = solve_ivp(lambda t, y: rhs(t, y, vertices), (begin, end), y0,
                             method='RK45', t_eval=np.append(inside, end)
                             if not len(inside) or inside[-1] < end else inside,
                             rtol=RTOL, atol=ATOL, max_step=max_step)
        if not solution.success:
            raise RuntimeError(f'RK45 failed: {solution.message}')
        keep = np.isin(solution.t, inside)
        t_out.append(solution.t[keep])
        y_out.append(solution.y.T[keep])
        begin, y0 = end, solution.y[:, -1]
    return np.concatenate(t_out), np.concatenate(y_out)


def obstacle_step(config: FormationConfig, times: np.ndarray) -> float:
    """
    Return the longest RK45 step of a run among obstacles, s (inf without obstacles).

    Far from obstacles and neighbours the closed loop can be exactly linear (robots holding
    their places on a line), RK45's error estimate vanishes and its steps grow until one jumps
    over a wall. A step here moves no robot more than about a quarter of b_o: at most
    sqrt(dim) c M1 from the bounded command plus twice the fastest feed-forward of eq. (25) at
    the places of the formation, the reference sampled at up to 200 of ``times`` (T,) s.
    """
    obstacles = config.obstacles
    if obstacles is None:
        return math.inf
    reference = config.reference()
    fastest = 0.0
    for t in times[::max(1, len(times) // 200)]:
        frame = reference.sample(float(t))
        places = desired_positions(config.vertices, frame)
        feed_forward = from_frame_velocity(np.zeros_like(places), places, frame)
        fastest = max(fastest, float(np.max(np.linalg.norm(feed_forward, axis=1))))
    speed = math.sqrt(config.dim) * config.law().u_bound + 2.0 * fastest
    return 0.25 * obstacles.clearance / speed


def law_command(q: np.ndarray, vertices: np.ndarray, sensing_radii: np.ndarray, law: LawParams,
                frame: FrameSample, obstacles: Optional[Obstacles], tree=None,
                pairs: Optional[np.ndarray] = None) -> Command:
    """
    Return the team's command at q: ``team_command`` with the obstacles, feed-forward guarded.

    obstacles: as the law sees them (``FormationConfig.law_obstacles``) or None; near them a
    moving reference's feed-forward loses its component into them
    (``core.maths.obstacle_tracking``). Without obstacles exactly ``team_command``.
    """
    command = team_command(q, vertices, sensing_radii, law, frame, tree, pairs, obstacles)
    return tracking_command(command, q, frame, law, obstacles, sensing_radii)


def _assemble(times, states, config, law, reference, shapes):
    obstacles = config.law_obstacles()
    commands, desired, centres = [], [], []
    for t, q in zip(times, states):
        frame = reference.sample(t)
        vertices = vertices_at(shapes, t)
        commands.append(law_command(q, vertices, config.sensing_radii, law, frame, obstacles))
        desired.append(desired_positions(vertices, frame))
        centres.append(frame.q_od)
    return Trajectory(t=np.asarray(times, dtype=float), q=np.asarray(states),
                      u=np.array([c.u for c in commands]),
                      u_hat=np.array([c.u_hat for c in commands]),
                      q_desired=np.array(desired), q_od=np.array(centres))


def simulate(config: FormationConfig, duration: Optional[float] = None,
             dt: Optional[float] = None, sample_dt: float = DEFAULT_SAMPLE_DT,
             progress: Optional[Progress] = None) -> Trajectory:
    """
    Run the closed loop from ``config.start`` and return a :class:`Trajectory`.

    duration: s (default ``config.duration``). dt: None for RK45 (rtol 1e-8, atol 1e-10), else
    the fixed zero-order-hold step in s. sample_dt: spacing of the returned samples in s (with
    ``dt`` it is rounded to a whole number of steps, at least one).
    """
    duration = config.duration if duration is None else float(duration)
    progress = progress or Progress(duration, quiet=True)
    if dt is not None:
        return simulate_fixed_step(config, duration, dt, sample_dt, progress)
    problem = continuous_time_problem(config)
    if problem:
        raise ValueError(problem)
    if config.body.is_unicycle:
        return simulate_unicycles(config, duration, sample_dt, progress)
    law = config.law()
    reference = config.reference()
    shapes = shapes_of(config)
    n, dim = config.num_robots, config.dim
    obstacles = config.law_obstacles()
    assert config.start is not None

    def rhs(t: float, y: np.ndarray, vertices: np.ndarray) -> np.ndarray:
        progress.update(t)
        frame = reference.sample(t)
        return law_command(y.reshape(n, dim), vertices, config.sensing_radii, law, frame,
                           obstacles).u.ravel()

    times = sample_times(duration, sample_dt)
    times, y = integrate_segments(rhs, config.start.ravel(), times, shapes,
                                  obstacle_step(config, times))
    return _assemble(times, y.reshape(-1, n, dim), config, law, reference, shapes)


def simulate_unicycles(config: FormationConfig, duration: float, sample_dt: float,
                       progress: Progress) -> Trajectory:
    """
    Integrate the unicycles (U1) with RK45, each commanded through its hand point (U4).

    The state is every axle centre and heading; the law sees the hand points (U2), mapped
    by ``core.model.bodies`` without the actuator caps (the ideal system). In
    continuous time the hand points then move exactly as the paper's points, p' = u (U3).
    """
    law = config.law()
    reference = config.reference()
    shapes = shapes_of(config)
    n = config.num_robots
    bodies = UnicycleBodies(config.body.hand_distance)
    obstacles = config.law_obstacles()
    assert config.start is not None and config.start_headings is not None

    def rhs(t: float, y: np.ndarray, vertices: np.ndarray) -> np.ndarray:
        progress.update(t)
        q, heading = y[:2 * n].reshape(n, 2), y[2 * n:]
        u = law_command(bodies.control_points(q, heading), vertices, config.sensing_radii,
                        law, reference.sample(t), obstacles).u
        q_rate, heading_rate = unicycle_rates(heading, bodies.body_command(u, heading))
        return np.concatenate([q_rate.ravel(), heading_rate])

    start = np.concatenate([config.start.ravel(), config.start_headings])
    times = sample_times(duration, sample_dt)
    times, y = integrate_segments(rhs, start, times, shapes, obstacle_step(config, times))
    q_body = y[:, :2 * n].reshape(-1, n, 2)
    heading = y[:, 2 * n:]
    trajectory = _assemble(times, bodies.control_points(q_body, heading), config, law,
                           reference, shapes)
    return replace(trajectory, heading=heading, q_body=q_body,
                   body_command=bodies.body_command(trajectory.u, heading))


def continuous_time_problem(config: FormationConfig) -> Optional[str]:
    """Say why RK45 (no ``--dt``) cannot run ``config``: its bodies are not ideal; or None."""
    imperfections = config.imperfections
    if imperfections.is_ideal:
        return None
    given = ', '.join(f'{name} = {value:g}' for name, value in imperfections.as_dict().items()
                      if value != 0.0)
    return (f"{given}: bodies that are not the paper's q' = u exist only in the fixed-step "
            'plant model, not in RK45; give --dt (e.g. --dt 0.01)')


@dataclass(frozen=True)
class FixedStepRun:
    """
    A ``--dt`` run: its samples and what the plant model counted over every step.

    trajectory: the samples (true states); counts: the model's counters (collisions below the
    model's contact distance, ...); largest_u_hat: the largest |u_hat| component of any command
    as sent, m/s (against c M1); largest_velocity: the largest |component| of the bodies'
    velocity over the run, per command component ((dim,) world m/s for points, (2,) |v| in m/s
    and |w| in rad/s for unicycles); delay_steps: the state delay in whole steps.
    """

    trajectory: Trajectory
    counts: PlantCounts
    largest_u_hat: float
    largest_velocity: np.ndarray
    delay_steps: int


def simulate_fixed_step(config: FormationConfig, duration: float, dt: float,
                        sample_dt: float, progress: Progress) -> Trajectory:
    """Step the plant model with the law's commands (:func:`run_fixed_step`): its samples."""
    return run_fixed_step(config, duration, dt, sample_dt, progress).trajectory


def run_fixed_step(config: FormationConfig, duration: float, dt: float, sample_dt: float,
                   progress: Progress,
                   collision_distance: float = DEFAULT_COLLISION_DISTANCE) -> FixedStepRun:
    """
    Step the plant model (``core.model.plant``) with the law's commands, as the plant node does.

    Every robot answers every state it is sent at once (a lockstep run without the network):
    the law acts on what the robots sense (:meth:`PlantModel.sensed`: with the reference at the
    sensed state's stamp), the model admits the commands, audits the bound and steps the bodies
    over ``dt``. With ``plant.state_delay`` the commands answer states that much older, so the
    model's input timeout is one step more than the delay. collision_distance: pairs of bodies
    closer than this (or twice ``body.radius``) count as collisions, m.
    """
    law = config.law()
    reference = config.reference()
    step_ns = int(round(dt * NS_PER_S))
    bodies = make_bodies(config.body, body_frame=config.command.frame is CommandFrame.BODY
                         and not config.body.is_unicycle)
    imperfections = config.imperfections
    delay_ns = imperfections.delay_steps(step_ns) * step_ns
    model = PlantModel(config.start, config.sensing_radii, step_ns, law, reference,
                       input_timeout_ns=step_ns + delay_ns, collision_distance=collision_distance,
                       bodies=bodies, headings=config.start_headings,
                       pair_radius=law.repulsion_radius, imperfections=imperfections,
                       obstacles=config.law_obstacles())
    commands = Commands.empty(config.num_robots, bodies.command_width(config.dim))
    shapes = shapes_of(config)
    obstacles = model.obstacles
    steps = int(round(duration / dt))
    stride = max(1, int(round(sample_dt / dt)))
    largest_u_hat = 0.0
    largest_velocity = np.zeros(bodies.command_width(config.dim))
    times, states, applied, frames, headings, q_body, held = [], [], [], [], [], [], []
    for k in range(steps + 1):
        frame = reference.sample(model.t)
        sensed = model.sensed(trees=False)
        seen_frame = (frame if sensed.stamp_ns == model.t_ns
                      else reference.sample(sensed.stamp_ns / NS_PER_S))
        u = law_command(sensed.points, shapes.at(sensed.stamp_ns).vertices,
                        config.sensing_radii, law, seen_frame, obstacles, sensed.tree,
                        sensed.pairs).u
        commands.store_all(bodies.body_command(u, sensed.heading), sensed.stamp_ns)
        if k == steps:
            times.append(model.t)
            states.append(model.points)
            admission = model.admit(commands)
            command = admission.u
            applied.append(admission.velocity)
            frames.append(frame)
            headings.append(model.heading)
            q_body.append(model.q)
            held.append(command)
            break
        progress.update(model.t)
        report = model.advance(commands)
        largest_u_hat = max(largest_u_hat, float(np.max(report.admission.largest_u_hat)))
        if report.velocity is not None:
            np.maximum(largest_velocity, np.max(np.abs(report.velocity), axis=0),
                       out=largest_velocity)
        if k % stride == 0:
            times.append(report.t_ns / NS_PER_S)
            states.append(report.points)
            applied.append(report.admission.velocity)
            frames.append(frame)
            headings.append(report.heading)
            q_body.append(report.q)
            held.append(report.admission.u)
    trajectory = Trajectory.from_frames(times, states, applied, frames,
                                        [vertices_at(shapes, t) for t in times],
                                        config.feed_forward_guard())
    if bodies.has_heading:
        trajectory = replace(trajectory, heading=np.array(headings), q_body=np.array(q_body),
                             body_command=np.array(held))
    return FixedStepRun(trajectory, model.counts, largest_u_hat, largest_velocity,
                        model.delay_steps)


def shaped(trajectory: Trajectory, config: FormationConfig, events: Sequence[Event],
           frames: Optional[Sequence[FrameSample]] = None) -> Trajectory:
    """
    Return the trajectory with its desired positions from the shape in force at each sample.

    frames: the reference at each sample (e.g. as recorded in a bag); default: the configured
    reference's (``events.with_shapes``). The trajectory itself when no event is a shape;
    ValueError when a shape does not fit the team.
    """
    if not any(event.kind is EventKind.SHAPE for event in events):
        return trajectory
    if frames is None:
        reference = config.reference()
        frames = [reference.sample(float(t)) for t in trajectory.t]
    return with_shapes(trajectory, events, frames)


def run_metrics(trajectory: Trajectory, config: FormationConfig, integrator: str,
                events: Sequence[Event] = ()) -> dict:
    """
    metrics.json content for a simulated or recorded trajectory.

    With events (``core.runs.events``) the key ``segments`` holds
    :func:`core.runs.metrics.segment_metrics`; without, it is left out. The errors are against
    ``trajectory.q_desired``: give a trajectory of :func:`shaped` for the shape in force.
    """
    extra = {'reference_kind': config.reference_kind.value, 'integrator': integrator}
    if config.body.radius > 0.0:
        extra['body_radius'] = config.body.radius
    if trajectory.q_body is not None and trajectory.body_command is not None:
        body = config.body
        extra.update(body_metrics(trajectory.q_body, trajectory.body_command,
                                  config.law().u_bound, body.hand_distance, body.radius))
        extra.update({'max_linear': body.max_linear, 'max_angular': body.max_angular,
                      'guaranteed_min_hand_point_distance': guaranteed_min_distance(
                          trajectory.q[0], config.vertices, config.law(),
                          config.reference().sample(float(trajectory.t[0])))})
    if trajectory.u_hat_held is not None:
        extra.update(held_metrics(trajectory.u_hat_held, config.law().u_bound))
    metrics = compute_metrics(trajectory.t, trajectory.q, trajectory.u, trajectory.u_hat,
                              trajectory.q_desired, config.law().u_bound, extra)
    if metrics.get('unknown_commands'):
        metrics['unknown_commands_reason'] = (
            'the states they answered were not heard' if config.command.stamped
            else 'unstamped commands do not say which state they answered')
    metrics.update(obstacle_keys(trajectory, config))
    if events:
        metrics['segments'] = segment_metrics(trajectory, events)
    return metrics


def obstacle_keys(trajectory: Trajectory, config: FormationConfig) -> dict:
    """
    metrics.json keys of the obstacles (``core.runs.obstacle_metrics``), with or without any.

    ``min_obstacle_clearance`` (m, None without obstacles) and ``obstacle_contacts`` of the real
    bodies (a unicycle's axle centre, ``body.radius`` subtracted) against the real obstacles;
    ``stuck_robots``: the robots hardly moving at the end, far from their places (records of
    ``Stuck``), with the rule's ``stuck_still_time`` (s) and ``stuck_still_speed`` (m/s).
    """
    bodies = trajectory.q if trajectory.q_body is None else trajectory.q_body
    radius = config.body.radius
    keys = obstacle_metrics(bodies, config.obstacles, radius)
    stuck = stuck_robots(trajectory.t, trajectory.q, trajectory.q_desired, config.obstacles,
                         bodies=bodies, body_radius=radius)
    keys.update({'stuck_robots': [robot.record() for robot in stuck],
                 'stuck_still_time': STILL_TIME, 'stuck_still_speed': STILL_SPEED})
    if config.obstacles is not None:
        keys.update({'obstacle_count': config.obstacles.count,
                     'obstacle_clearance_b_o': config.obstacles.clearance,
                     'body_footprint': config.body.footprint})
    return keys


def plant_metrics(run: FixedStepRun, config: FormationConfig) -> dict:
    """metrics.json keys of a ``--dt`` run: the bodies' imperfections and what they did."""
    return {'imperfections': config.imperfections.as_dict(),
            'state_delay_steps': run.delay_steps,
            'max_abs_u_hat_sent': run.largest_u_hat,
            'max_abs_body_velocity': run.largest_velocity.tolist(),
            'plant_collisions': run.counts.collisions}


def _u_hat_line(metrics: dict) -> str:
    """Return the summary line of u_hat: what the robots commanded, and what it cannot tell."""
    unknown = metrics.get('unknown_commands', 0)
    largest = metrics['max_abs_u_hat_component']
    why = (f"{unknown} of the {metrics['num_samples'] * metrics['num_robots']} sampled "
           f"commands not known: {metrics.get('unknown_commands_reason', 'not recorded')}")
    if largest is None:
        return (f'  max |u_hat| component: not known ({why}; bound c*M1 = '
                f"{metrics['u_bound']:.4g} m/s)")
    return (f'  max |u_hat| component: {largest:.4g} m/s (bound c*M1 = '
            f"{metrics['u_bound']:.4g} m/s, {metrics['bound_violations']} above"
            + (f'; {why})' if unknown else ')'))


def _limit(metrics: dict, name: str, unit: str) -> str:
    value = metrics.get(name)
    return '' if value is None else f', body.{name} = {value:g} {unit}'


def _measured(value: Optional[float], unit: str) -> str:
    return 'none' if value is None else f'{value:.4g} {unit}'


def _segment_line(segment: dict) -> str:
    """One summary line of a segment of ``core.runs.metrics.segment_metrics``."""
    opened = ('from the start' if segment['kind'] is None
              else f"after {segment['kind']} '{segment['label']}'")
    settle = segment['settle_time']
    settled = ('not settled' if settle is None else f'settled in {settle:.2f} s')
    body = ('' if 'min_body_distance' not in segment
            else f", bodies {_measured(segment['min_body_distance'], 'm')}")
    if not segment['num_samples']:
        settled = 'no sample'
    return (f"  segment {segment['start']:.2f}-{segment['end']:.2f} s {opened}: {settled}, "
            f"closest {_measured(segment['min_pair_distance'], 'm')}{body}, max |u_hat| "
            f"{_measured(segment['max_abs_u_hat_component'], 'm/s')}, final max error "
            f"{_measured(segment['final_max_error'], 'm')}")


def _obstacle_lines(metrics: dict) -> list:
    """Summary lines of the obstacles and of the stuck robots (:func:`obstacle_keys`)."""
    lines = []
    clearance = metrics.get('min_obstacle_clearance')
    if clearance is not None:
        contacts = metrics['obstacle_contacts']
        what = 'no contact' if not contacts else f'{contacts} CONTACTS'
        lines.append(f"  obstacles: {metrics.get('obstacle_count', '?')}, closest approach of a "
                     f'body {clearance:.4g} m ({what}; footprint subtracted, b_o = '
                     f"{metrics.get('obstacle_clearance_b_o', math.nan):g} m)")
    stuck = metrics.get('stuck_robots') or ()
    if stuck:
        lines.append(f'  stuck ({len(stuck)}: within '
                     f"{metrics['stuck_still_speed'] * metrics['stuck_still_time']:g} m of where "
                     f"it ended for the last {metrics['stuck_still_time']:g} s and no nearer its "
                     f"place, farther than {metrics['settle_tolerance']:g} m from it):")
        lines += [f'    {stuck_line(robot)}' for robot in stuck]
    return lines


def format_summary(metrics: dict, out_dir: Optional[str] = None) -> str:
    """Human-readable summary lines of a metrics dictionary."""
    settle = metrics['settle_time']
    stuck = len(metrics.get('stuck_robots') or ())
    settle_text = (f'{settle:.2f} s' if settle is not None else 'not settled by the end'
                   + (f': {stuck} robot{"s" if stuck > 1 else ""} stuck (below)' if stuck
                      else ''))
    touching = (0.0 if metrics.get('body_kind') == 'unicycle'
                else 2.0 * metrics.get('body_radius', 0.0))
    collision = 'no collision' if metrics['min_pair_distance'] > touching else 'COLLISION'
    if touching > 0.0:
        collision += f'; 2 x body.radius = {touching:.4g} m'
    lines = [
        f"  robots: {metrics['num_robots']} in {metrics['dim']}D, "
        f"{metrics['duration']:.2f} s, reference {metrics.get('reference_kind', '?')}",
        f"  settle time (every error <= {metrics['settle_tolerance']} m): {settle_text}",
        f"  final max error: {metrics['final_max_error']:.3g} m",
        f"  min pair distance: {metrics['min_pair_distance']:.4g} m ({collision})",
        _u_hat_line(metrics),
        f"  max |u| component: {_measured(metrics['max_abs_u_component'], 'm/s')}",
    ]
    if 'max_abs_u_hat_held_component' in metrics:
        lines.append(
            '  max |u_hat_held| component (each held command read at the heading the body had '
            'at the sample, not the one it answered): '
            f"{_measured(metrics['max_abs_u_hat_held_component'], 'm/s')} (bound sqrt(2) c M1 = "
            f"{metrics['u_hat_held_bound']:.4g} m/s, {metrics['u_hat_held_above_bound']} above)")
    if metrics.get('body_kind') == 'unicycle':
        touching = 2.0 * metrics['body_radius']
        guaranteed = metrics['guaranteed_min_hand_point_distance']
        contact = 'bodies touched' if metrics['min_body_distance'] < touching else 'no contact'
        lines[3] = lines[3].replace('min pair distance', 'min hand-point distance')
        lines += [
            f"  closest body approach: {metrics['min_body_distance']:.4g} m ({contact}; "
            f'2 x body.radius = {touching:.4g} m)',
            '  guaranteed by the potential from this start (docs/equations.md, U6): hand '
            f'points >= {guaranteed:.4g} m apart, so bodies >= '
            f"{body_clearance(guaranteed, metrics['hand_distance']):.4g} m",
            f"  max |v|: {metrics['max_abs_v']:.4g} m/s (sqrt(2) c M1 = "
            f"{metrics['v_bound']:.4g} m/s{_limit(metrics, 'max_linear', 'm/s')}), "
            f"max |w|: {metrics['max_abs_omega']:.4g} rad/s (sqrt(2) c M1 / l = "
            f"{metrics['omega_bound']:.4g} rad/s{_limit(metrics, 'max_angular', 'rad/s')})",
        ]
    lines += [_segment_line(segment) for segment in metrics.get('segments', ())]
    lines += _obstacle_lines(metrics)
    if out_dir:
        lines.append(f'  results in {out_dir}')
    return '\n'.join(lines)
