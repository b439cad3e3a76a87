# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
Offline simulator ``formation_sim``: the closed loop q' = u of eqs. (1), (14), (25).

Default: adaptive RK45 at rtol 1e-8 (the paper's continuous-time system). ``--dt`` switches to a
fixed step with the command held over each step (zero-order hold), which is what the plant node
does. Writes trajectory.npz, metrics.json, a copy of the parameters and the figures.

Unicycles (``body.kind: unicycle``): RK45 integrates the unicycles' own equations (U1) with the
law acting on their hand points (the ideal continuous-time system: no actuator caps); ``--dt``
steps the plant model, which holds (v, w) over each step, integrates the arcs exactly and
clips to ``body.max_linear`` / ``body.max_angular``.

Non-ideal bodies (``plant.actuator_lag``, ``plant.max_acceleration``, ``plant.pose_noise``,
``plant.state_delay``; ``core.model.dynamics``, beyond the paper) exist only in the plant model, so
only ``--dt`` runs have them: without ``--dt`` a file that sets any of them is refused. In a
``--dt`` run the law acts on what the robots sense (noisy, late), the bodies move with their
lagged velocity, and trajectory.npz holds the true states.

``--engine mujoco`` runs the law every ``--dt`` (default 0.02 s) on the physics engine
(``formation_ros.physics``, ``simulation.engine_run``: bodies with mass, motors and contacts) and
also writes world.xml and world_stats.json; ``--engine ideal`` (the default) is all of the
above.
"""

import argparse
import json
import math
import os
import shutil
import sys
import tempfile
from typing import Optional, Sequence, Tuple

from formation_ros.core.runs.output import stats_text
from formation_ros.core.runs.trajectory import TRAJECTORY_FILE
from formation_ros.core.runs.world_stats import WORLD_STATS_FILE
from formation_ros.core.settings.declarations import Exe, ObstacleSource, ParamError
from formation_ros.core.settings.exits import ENGINE_FAILED
from formation_ros.core.settings.file_guard import ParamsFileError
from formation_ros.core.settings.params import (FormationConfig, load_config,
                                                validate_for_every_executable)
from formation_ros.core.settings.params_file import load_params_file
from formation_ros.simulation.engine_run import (DEFAULT_CONTROL_DT, engine_metrics,
                                                 engine_problem, engine_summary, run_on_engine)
from formation_ros.simulation.simulate import (continuous_time_problem, DEFAULT_SAMPLE_DT,
                                               format_summary, MAX_ROBOT_SAMPLES, MAX_STEPS,
                                               METRICS_FILE, PARAMS_COPY, plant_metrics, Progress,
                                               run_fixed_step, run_metrics, sampling_metadata,
                                               schedule_events, shapes_of, simulate)

ENGINES = ('ideal', 'mujoco')
"""formation_sim's bodies: the paper's (RK45 or the plant model) or the physics engine's."""


def build_parser() -> argparse.ArgumentParser:
    """Command-line interface of formation_sim."""
    parser = argparse.ArgumentParser(
        prog='formation_sim',
        description='Simulate the bounded formation controller offline (no ROS needed) and '
                    'write trajectory.npz, metrics.json and figures.',
        epilog='Example: formation_sim config/paper_section5.yaml --out /tmp/section5')
    parser.add_argument('params', help='ROS 2 parameters YAML file (/**: ros__parameters: ...)')
    parser.add_argument('--out', help='output directory (created if missing; must be empty '
                                      'unless --overwrite); required unless --check')
    parser.add_argument('--overwrite', action='store_true',
                        help='write into a non-empty --out directory, replacing the files '
                             'formation_sim writes there and leaving the others')
    parser.add_argument('--check', action='store_true',
                        help='only validate the parameters as the simulator and every node '
                             'read them, say so and exit (0 valid, 2 not)')
    parser.add_argument('--duration', type=float, help='simulated seconds (default: duration '
                                                       'in the parameters file)')
    parser.add_argument('--dt', type=float, help='fixed step with zero-order hold, s, at most '
                                                 'the duration and at most '
                                                 f'{MAX_STEPS:,} steps per run (default: '
                                                 'adaptive RK45 at rtol 1e-8)')
    parser.add_argument('--sample-dt', type=float,
                        help='spacing of saved samples, s, at most the duration and at most '
                             f'{MAX_STEPS:,} samples per run (default {DEFAULT_SAMPLE_DT:g}, '
                             'or for a team that would then save more than '
                             f'{MAX_ROBOT_SAMPLES:,} robots x samples the smallest multiple '
                             f'of {DEFAULT_SAMPLE_DT:g} s that keeps within it; metrics.json '
                             'says which under sample_dt and sampling)')
    parser.add_argument('--engine', choices=ENGINES, default='ideal',
                        help="the bodies: 'ideal' (default: q' = u by RK45, or the plant "
                             "model with --dt) or 'mujoco' (the physics engine, world.*: the "
                             'law every --dt s, default '
                             f'{DEFAULT_CONTROL_DT:g}, held while the engine steps; also '
                             f'writes world.xml and {WORLD_STATS_FILE})')
    parser.add_argument('--no-plots', action='store_true', help='skip the figures')
    parser.add_argument('--quiet', action='store_true', help='print no progress')
    return parser


def run_length_problem(duration: float, dt: Optional[float],
                       sample_dt: Optional[float]) -> Optional[str]:
    """
    Say what is wrong with ``--dt`` and ``--sample-dt`` for a run of ``duration`` s, or None.

    Either step must not exceed the duration, a run has at most :data:`MAX_STEPS` fixed steps,
    and an RK45 run at most as many samples. ``sample_dt`` None is the default spacing.
    """
    if dt is not None:
        if dt > duration:
            return f'--dt {dt:g} s is longer than the run ({duration:g} s); give at most that'
        if duration / dt > MAX_STEPS:
            return (f'--dt {dt:g} s makes {duration / dt:.3g} steps of a {duration:g} s run, '
                    f'more than {MAX_STEPS:,}; choose a larger --dt or a shorter --duration')
    if sample_dt is not None and sample_dt > duration:
        return (f'--sample-dt {sample_dt:g} s is longer than the run ({duration:g} s); give at '
                'most that')
    spacing = DEFAULT_SAMPLE_DT if sample_dt is None else sample_dt
    if dt is None and duration / spacing > MAX_STEPS:
        given = '' if sample_dt is not None else ' (the default)'
        return (f'--sample-dt {spacing:g} s{given} makes {duration / spacing:.3g} samples of a '
                f'{duration:g} s run, more than {MAX_STEPS:,}; choose a larger --sample-dt or a '
                'shorter --duration')
    return None


def prepare_out(path: str, overwrite: bool, names: Sequence[str]) -> Optional[str]:
    """
    Make sure the results can be written to directory ``path``; return a problem or None.

    Creates ``path`` (and its parents) if missing and writes and removes a temporary file in
    it. An existing directory must be empty unless ``overwrite``; then each of ``names`` (the
    files of a run) already there must be a file that can be replaced. Nothing is created when
    a problem is found before the directory exists.
    """
    if os.path.lexists(path) and not os.path.isdir(path):
        return f"--out '{path}' is a file, not a directory"
    try:
        if os.path.isdir(path):
            entries = set(os.listdir(path))
            if entries and not overwrite:
                return (f"--out directory '{path}' is not empty; pass --overwrite to write "
                        'into it anyway, or choose a new one')
            for name in sorted(entries.intersection(names)):
                if not os.path.isfile(os.path.join(path, name)):
                    return f"--out '{path}' holds '{name}', which is not a file it can replace"
        os.makedirs(path, exist_ok=True)
        with tempfile.TemporaryFile(dir=path):
            pass
    except OSError as exc:
        return f"cannot write into --out '{path}': {exc.strerror or exc}"
    return None


def output_names(plots_wanted: bool, engine: str = 'ideal') -> Tuple[str, ...]:
    """Return the names of the files a run writes into its output directory."""
    names: Tuple[str, ...] = (TRAJECTORY_FILE, METRICS_FILE, PARAMS_COPY)
    if engine == 'mujoco':
        from formation_ros.physics.scene import WORLD_FILE
        names += (WORLD_FILE, WORLD_STATS_FILE)
    if plots_wanted:
        from formation_ros.figures.plots import FIGURES
        names += tuple(FIGURES)
    return names


def _copy_params(source: str, out_dir: str) -> None:
    """Copy the parameters file into the run directory (nothing to do if it is already there)."""
    target = os.path.join(out_dir, PARAMS_COPY)
    if os.path.exists(target) and os.path.samefile(source, target):
        return
    shutil.copyfile(source, target)


def main(argv: Optional[list] = None) -> int:
    """Entry point of ``formation_sim``; returns the exit code."""
    parser = build_parser()
    args = parser.parse_args(argv)
    for name in ('duration', 'dt', 'sample_dt'):
        value = getattr(args, name)
        if value is not None and not (math.isfinite(value) and value > 0.0):
            parser.error(f"--{name.replace('_', '-')} must be a number > 0, got {value}")
    if not args.check and not args.out:
        parser.error('--out is required (or --check)')
    try:
        if args.check:
            config = validate_for_every_executable(load_params_file(args.params))[Exe.SIM]
        else:
            config = load_config(args.params)
    except ParamsFileError as exc:
        print(f'formation_sim: {exc.summary}', file=sys.stderr)
        return 2
    except ParamError as exc:
        print(f'formation_sim: invalid parameters in {args.params}:\n{exc}', file=sys.stderr)
        return 2
    if args.check:
        print(f'{config.num_robots} robots in {config.dim}D: {args.params} is valid for '
              'formation_sim, plant, reference and robot')
        return 0
    duration = config.duration if args.duration is None else args.duration
    if config.values.get('obstacles.source') == ObstacleSource.SCAN.value:
        print('formation_sim: obstacles.source is scan, but the simulator has no scanner: the '
              'law is given the map (obstacles.*), as robots told their obstacles; the scan '
              'runs through the robot nodes (launch_formation.sh --world)', file=sys.stderr)
    if args.engine == 'mujoco':
        return run_engine_command(args, config, duration)
    problem = ((continuous_time_problem(config) if args.dt is None else None)
               or run_length_problem(duration, args.dt, args.sample_dt)
               or prepare_out(args.out, args.overwrite, output_names(not args.no_plots)))
    if problem:
        print(f'formation_sim: {problem}', file=sys.stderr)
        return 2
    sampling = sampling_metadata(config.num_robots, duration, args.dt, args.sample_dt)
    sample_dt = sampling['sample_dt']
    integrator = 'RK45' if args.dt is None else f'zero-order hold, dt = {args.dt:g} s'
    progress = Progress(duration, quiet=args.quiet)
    events = schedule_events(config)
    if args.dt is None:
        trajectory = simulate(config, duration, None, sample_dt, progress)
        metrics = run_metrics(trajectory, config, integrator, events)
    else:
        run = run_fixed_step(config, duration, args.dt, sample_dt, progress)
        trajectory = run.trajectory
        metrics = run_metrics(trajectory, config, integrator, events)
        metrics.update(plant_metrics(run, config))
    metrics.update(sampling)
    metrics['wall_time'] = progress.elapsed
    trajectory.save(os.path.join(args.out, TRAJECTORY_FILE))
    _copy_params(args.params, args.out)
    with open(os.path.join(args.out, METRICS_FILE), 'w', encoding='utf-8') as stream:
        json.dump(metrics, stream, indent=2)
        stream.write('\n')
    if not args.no_plots:
        from formation_ros.figures import plots
        plots.write_figures(trajectory, config.law(), metrics, args.out, config.obstacles)
    print(f'formation_sim: {integrator}, {duration:g} s simulated in {progress.elapsed:.1f} s')
    print(format_summary(metrics, args.out))
    return 0


def run_engine_command(args: argparse.Namespace, config: FormationConfig,
                       duration: float) -> int:
    """Run ``formation_sim --engine mujoco`` (``simulation.engine_run``); return the exit code."""
    dt = DEFAULT_CONTROL_DT if args.dt is None else args.dt
    problem = (engine_problem(config, dt) or run_length_problem(duration, dt, args.sample_dt)
               or prepare_out(args.out, args.overwrite,
                              output_names(not args.no_plots, args.engine)))
    if problem:
        print(f'formation_sim: {problem}', file=sys.stderr)
        return 2
    try:
        from formation_ros.physics.scene import build_scene
    except ImportError as exc:
        print(f'formation_sim: --engine mujoco needs MuJoCo 3 (pip install mujoco): {exc}',
              file=sys.stderr)
        return 2
    sampling = sampling_metadata(config.num_robots, duration, dt, args.sample_dt)
    progress = Progress(duration, quiet=args.quiet)
    run = run_on_engine(config, duration, dt, sampling['sample_dt'], shapes_of(config),
                        progress)
    world = config.world
    assert world is not None
    integrator = (f'MuJoCo {run.stats.mujoco_version}, timestep {world.timestep:g} s, '
                  f'the law every {dt:g} s held (zero-order hold)')
    metrics = run_metrics(run.trajectory, config, integrator, schedule_events(config))
    metrics.update(engine_metrics(run))
    metrics.update(sampling)
    metrics['wall_time'] = progress.elapsed
    run.trajectory.save(os.path.join(args.out, TRAJECTORY_FILE))
    _copy_params(args.params, args.out)
    build_scene(config).write(args.out)
    with open(os.path.join(args.out, METRICS_FILE), 'w', encoding='utf-8') as stream:
        json.dump(metrics, stream, indent=2)
        stream.write('\n')
    with open(os.path.join(args.out, WORLD_STATS_FILE), 'wb') as binary:
        binary.write(stats_text(run.stats.record()))
    if not args.no_plots:
        from formation_ros.figures import plots
        plots.write_figures(run.trajectory, config.law(), metrics, args.out,
                            config.obstacles)
    simulated = duration if run.failure is None else float(run.trajectory.t[-1])
    print(f'formation_sim: {integrator}, {simulated:g} s simulated in {progress.elapsed:.1f} s')
    print(format_summary(metrics, args.out))
    print(engine_summary(run))
    if run.failure is not None:
        print(f'formation_sim: {run.failure}; wrote the run up to there to {args.out}',
              file=sys.stderr)
        return ENGINE_FAILED
    return 0


if __name__ == '__main__':
    sys.exit(main())
