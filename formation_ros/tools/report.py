# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
``formation_report``: metrics.json and figures of a recorded run.

They are computed by the same code as ``formation_sim``. Input:

* a rosbag2 directory written by ``record`` (or ``launch_formation.sh --record``): the
  trajectory is rebuilt from the recorded poses, commands and reference samples, and the
  parameters come from the bag itself (``/formation/params``, else ``params.yaml`` beside
  ``metadata.yaml``); the plant's counters come from its last ``/diagnostics`` status. A bag
  that is not whole (recorder killed: no metadata.yaml, MCAP cut short; or a damaged
  metadata.yaml) is recovered from its MCAP file, with one line saying how many messages were
  recovered; ``--repair`` rewrites it in place as a whole bag, keeping the damaged files;
* a single ``.mcap`` file of such a bag (recovered the same way);
* or a run directory holding ``trajectory.npz`` and ``params.yaml`` (``formation_sim`` output,
  or ``launch_formation.sh --out``; a ``plant_stats.json`` there is merged into the metrics).

``--animate`` writes ``animation.mp4`` (ffmpeg on PATH) or ``animation.gif`` of the run
(``figures.animate``) beside metrics.json, with or without the figures.

Unreadable input, or an ``--out`` that cannot be written, ends with exit code 2 and one line
that says what is wrong.
"""

import argparse
import json
import math
import os
import sys
import time
from typing import Any, Dict, List, Optional, Sequence, Tuple

from formation_ros.core.maths.frames import FrameSample
from formation_ros.core.model.plant import PLANT_STATS_FILE
from formation_ros.core.runs.events import Event, events_from_records
from formation_ros.core.runs.output import ChunkShapeError, FixedShape, trajectory_from_chunks
from formation_ros.core.runs.trajectory import CHUNKS_DIR, Trajectory, TRAJECTORY_FILE
from formation_ros.core.settings.declarations import ParamError
from formation_ros.core.settings.file_guard import ParamsFileError
from formation_ros.core.settings.params import FormationConfig, load_config, validate
from formation_ros.core.settings.params_file import parse_params_text
from formation_ros.figures.animate import (AnimationError, DEFAULT_DPI, DEFAULT_FPS, describe,
                                           FIGURE_WIDTH, GIF, MAX_FRAMES, MP4, plan_frames,
                                           write_animation)
from formation_ros.ros import topics as names
from formation_ros.ros.bag_writer import BagError, PARAMS_FILE
from formation_ros.simulation.simulate import format_summary, run_metrics, shaped
from formation_ros.tools.bag import (bag_params_text, EVENTS, mcap_files, METADATA, plant_status,
                                     read_or_recover, repair_bag, trajectory_from_topics)

Loaded = Tuple[Trajectory, FormationConfig, Dict[str, Any]]


class ReportError(Exception):
    """The input cannot be reported on; the message (one line) says why."""


def _one_line(text: str) -> str:
    return '; '.join(line.strip() for line in str(text).splitlines() if line.strip())


def _param_problem(exc: ParamError) -> str:
    """Return one line for invalid parameters: a refused file's own line, else every problem."""
    return exc.summary if isinstance(exc, ParamsFileError) else _one_line(str(exc))


def load_bag(path: str, notes: Optional[List[str]] = None) -> Loaded:
    """
    Return (Trajectory, FormationConfig, extra metrics) of a recorded bag (or MCAP file).

    A bag that is not whole is recovered; the line saying so is appended to ``notes``.
    """
    try:
        recorded, counts, note = read_or_recover(path)
    except BagError as exc:
        raise ReportError(f'cannot read the bag: {exc}') from None
    folder = path if os.path.isdir(path) else os.path.dirname(path)
    try:
        text = bag_params_text(folder, recorded)
    except ParamsFileError as exc:
        raise ReportError(exc.summary) from None
    if text is None:
        raise ReportError(f'{path}: the bag has no parameters (no {names.PARAMS} message and '
                          'no '
                          f'{PARAMS_FILE}); without the formation and the bound it cannot be '
                          'interpreted. Record with the record node (it stores them) or put '
                          f'the parameters file there as {PARAMS_FILE}.')
    try:
        config = validate(parse_params_text(text, f'{path} parameters'))
        trajectory, info = trajectory_from_topics(recorded, config)
    except ParamsFileError as exc:
        raise ReportError(exc.summary) from None
    except (ParamError, BagError) as exc:
        raise ReportError(f'{path}: {_one_line(str(exc))}') from None
    extra: Dict[str, Any] = {'source': 'rosbag2', 'integrator': 'recorded run (rosbag2)',
                             'messages': int(sum(counts.values()))}
    if note is not None:
        extra['recovered_messages'] = extra['messages']
        if notes is not None:
            notes.append(note)
    extra.update(info)
    extra.update(plant_status(recorded))
    return trajectory, config, extra


def _is_bag(path: str) -> bool:
    return os.path.isfile(os.path.join(path, METADATA)) or bool(mcap_files(path))


def _load_chunks(path: str, params: str, chunks: str, notes: Optional[List[str]]) -> Loaded:
    """Load a run whose plant was cut short: its trajectory from the chunks it wrote."""
    try:
        config = load_config(params)
        trajectory = trajectory_from_chunks(
            chunks, config.reference().sample, FixedShape(config.vertices),
            config.body.is_unicycle, (config.num_robots, config.dim),
            config.feed_forward_guard())
    except ParamError as exc:
        raise ReportError(_param_problem(exc)) from None
    except ChunkShapeError as exc:
        raise ReportError(f'{exc}, but params.yaml says {config.num_robots} in '
                          f'{config.dim}D') from None
    except ValueError as exc:
        raise ReportError(_one_line(str(exc))) from None
    samples = len(trajectory.t)
    if notes is not None:
        notes.append(f'{path}: no trajectory.npz (the plant did not finish): rebuilt '
                     f'{samples} samples up to t = {trajectory.t[-1]:.2f} s from {CHUNKS_DIR}/')
    return trajectory, config, {'recovered_samples': int(samples)}


def load_run(path: str, notes: Optional[List[str]] = None) -> Loaded:
    """Return (Trajectory, FormationConfig, extra metrics) of a bag or a run directory."""
    if not os.path.exists(path):
        raise ReportError(f'{path}: no such file or directory')
    if os.path.isfile(path):
        if path.endswith('.mcap'):
            return load_bag(path, notes)
        raise ReportError(f'{path}: a file, not a bag directory, an .mcap file or a run '
                          'directory')
    try:
        if _is_bag(path):
            return load_bag(path, notes)
    except OSError as exc:
        raise ReportError(f'{path}: cannot list it: {exc.strerror}') from None
    params = os.path.join(path, 'params.yaml')
    arrays = os.path.join(path, TRAJECTORY_FILE)
    chunks = os.path.join(path, CHUNKS_DIR)
    if not os.path.exists(arrays) and os.path.isdir(chunks) and os.path.exists(params):
        return _load_chunks(path, params, chunks, notes)
    if not os.path.exists(params) and not os.path.exists(arrays):
        raise ReportError(f'{path}: neither a bag ({METADATA} or an .mcap file) nor a run '
                          'directory (trajectory.npz and params.yaml)')
    if not os.path.exists(params):
        raise ReportError(f'{path}: no params.yaml: the run cannot be interpreted without the '
                          'parameters it ran with (formation, bound, reference)')
    try:
        config = load_config(params)
    except ParamError as exc:
        raise ReportError(_param_problem(exc)) from None
    try:
        trajectory = Trajectory.load(arrays)
    # trajectory.npz from the disk: numpy and zipfile raise many kinds of error on a bad file.
    except Exception as exc:
        raise ReportError(f'{arrays}: not a readable trajectory '
                          f'({_one_line(str(exc)) or type(exc).__name__})') from None
    samples = trajectory.t.shape[0] if trajectory.t.ndim == 1 else 0
    robots = (samples, config.num_robots, config.dim)
    expected = {'t': (samples,), 'q': robots, 'u': robots, 'u_hat': robots,
                'q_desired': robots, 'q_od': (samples, config.dim)}
    wrong = [f'{name} {getattr(trajectory, name).shape}' for name, shape in expected.items()
             if getattr(trajectory, name).shape != shape]
    if not samples or wrong:
        raise ReportError(f'{arrays}: arrays of the wrong shape for {config.num_robots} robots '
                          f'in {config.dim}D and {samples} samples: '
                          f'{", ".join(wrong) or "no samples"}')
    extra = {}
    stats = os.path.join(path, PLANT_STATS_FILE)
    if os.path.exists(stats):
        try:
            with open(stats, encoding='utf-8') as stream:
                extra = json.load(stream)
        except (OSError, ValueError) as exc:
            raise ReportError(f'{stats}: not readable JSON ({_one_line(str(exc))})') from None
        if not isinstance(extra, dict):
            raise ReportError(f'{stats}: not a JSON object')
    return trajectory, config, extra


def run_events(extra: Dict[str, Any]) -> Tuple[Event, ...]:
    """
    Take the run's events out of the loaded extra metrics (they are not metrics themselves).

    From a bag: the shape switches and stops recorded on ``/formation/shape`` and
    ``/formation/status``; from a run directory: the records of ``plant_stats.json``.
    """
    events = extra.pop(EVENTS, ())
    if events and not isinstance(events[0], Event):
        return events_from_records(events)
    return tuple(events)


def check_out(out: str) -> Optional[str]:
    """Return why the report cannot be written to directory ``out``, or None if it can."""
    if os.path.exists(out):
        if not os.path.isdir(out):
            return f'--out {out}: exists and is not a directory'
        if not os.access(out, os.W_OK | os.X_OK):
            return f'--out {out}: the directory is not writable'
        return None
    parent = os.path.dirname(os.path.abspath(out))
    while not os.path.exists(parent):
        parent = os.path.dirname(parent)
    if not os.path.isdir(parent):
        return f'--out {out}: cannot be created, {parent} is not a directory'
    if not os.access(parent, os.W_OK | os.X_OK):
        return f'--out {out}: cannot be created, {parent} is not writable'
    return None


def write_report(trajectory: Trajectory, config: FormationConfig, out_dir: str,
                 extra: Optional[Dict[str, Any]] = None, plots: bool = True,
                 events: Sequence[Event] = (),
                 frames: Optional[Sequence[FrameSample]] = None) -> dict:
    """
    Write metrics.json (and the figures) to ``out_dir``; return the metrics.

    events (``core.runs.events``): metrics.json gets the per-segment metrics under ``segments``.
    The trajectory's desired positions are those of the shape in force already (every loader
    builds them so); with ``frames`` (the reference at each sample) they are rebuilt from the
    events' shapes. ValueError when a shape does not fit.
    """
    extra = dict(extra or {})
    integrator = extra.pop('integrator', 'recorded run')
    if frames is not None:
        trajectory = shaped(trajectory, config, events, frames)
    metrics = run_metrics(trajectory, config, integrator, events)
    metrics.update(extra)
    os.makedirs(out_dir, exist_ok=True)
    with open(os.path.join(out_dir, 'metrics.json'), 'w', encoding='utf-8') as stream:
        json.dump(metrics, stream, indent=2)
        stream.write('\n')
    if plots:
        from formation_ros.figures import plots as figures
        figures.write_figures(trajectory, config.law(), metrics, out_dir, config.obstacles)
    return metrics


def _fail(message: str) -> int:
    print(f'formation_report: {message}', file=sys.stderr)
    return 2


def build_parser() -> argparse.ArgumentParser:
    """Command-line interface of formation_report."""
    parser = argparse.ArgumentParser(
        prog='formation_report',
        description='Metrics and figures of a recorded formation run.',
        epilog='Examples: formation_report runs/demo/bag --out runs/demo; '
               'formation_report runs/cut_bag --repair (a bag whose recorder was killed: '
               'rewritten in place as a whole bag, the damaged files kept as *.damaged); '
               'formation_report runs/demo/bag --out runs/demo --animate (and a GIF or MP4 '
               'of the run)')
    parser.add_argument('input', help='rosbag2 directory (metadata.yaml + MCAP), .mcap file, '
                                      'or run directory with trajectory.npz and params.yaml')
    parser.add_argument('--out', help='where to write metrics.json and figures (required '
                                      'unless --repair)')
    parser.add_argument('--repair', action='store_true',
                        help='make a bag that is not whole (recorder killed, MCAP cut short) '
                             'whole again in place, keeping the damaged files as *.damaged; '
                             'then report if --out is given')
    parser.add_argument('--no-plots', action='store_true', help='skip the figures')
    parser.add_argument('--animate', action='store_true',
                        help=f'also write {MP4} or {GIF} of the run (mp4 where an ffmpeg '
                             'executable is on PATH, else a GIF through Pillow)')
    parser.add_argument('--fps', type=float, default=DEFAULT_FPS,
                        help=f'frames per second of the animation (default {DEFAULT_FPS:g}; '
                             'a GIF holds each frame a whole number of 1/100 s)')
    parser.add_argument('--speed', type=float,
                        help='simulated seconds per second of animation (default: real time, '
                             f'faster where the run would need more than {MAX_FRAMES} frames)')
    parser.add_argument('--max-frames', type=int, default=MAX_FRAMES,
                        help=f'at most this many frames, 2 to {MAX_FRAMES} (default '
                             f'{MAX_FRAMES}); never more than the run has samples')
    parser.add_argument('--dpi', type=float, default=DEFAULT_DPI,
                        help=f'resolution of the animation: {FIGURE_WIDTH:g} inches wide '
                             f'at this many dots per inch (default {DEFAULT_DPI}), 20 to 300')
    return parser


def main(argv: Optional[list] = None) -> int:
    """Entry point of ``formation_report``; returns the exit code."""
    parser = build_parser()
    args = parser.parse_args(argv)
    if args.out is None and not args.repair:
        parser.error('the following arguments are required: --out (or give --repair)')
    for option, value, low, high in (('--fps', args.fps, 0.0, 100.0),
                                     ('--speed', args.speed, 0.0, math.inf),
                                     ('--dpi', args.dpi, 19.999, 300.0)):
        if value is not None and not (math.isfinite(value) and low < value <= high):
            parser.error(f'{option} must be a number in ({low:g}, {high:g}], got {value}')
    if not 2 <= args.max_frames <= MAX_FRAMES:
        parser.error(f'--max-frames must be 2 to {MAX_FRAMES}, got {args.max_frames}')
    if args.out is not None:
        problem = check_out(args.out)
        if problem is not None:
            return _fail(problem)
    if args.repair:
        try:
            print(f'formation_report: {repair_bag(args.input)}')
        except BagError as exc:
            return _fail(f'cannot repair {args.input}: {_one_line(str(exc))}')
        except OSError as exc:
            return _fail(f'cannot repair {args.input}: {exc.strerror or exc}'
                         f'{f" ({exc.filename})" if exc.filename else ""}')
        if args.out is None:
            return 0
    notes: List[str] = []
    try:
        trajectory, config, extra = load_run(args.input, notes)
    except ReportError as exc:
        return _fail(_one_line(str(exc)))
    for note in notes:
        print(f'formation_report: {note}', file=sys.stderr)
    try:
        events = run_events(extra)
    except ValueError as exc:
        return _fail(f'{args.input}: {PLANT_STATS_FILE} events: {_one_line(str(exc))}')
    plan = None
    if args.animate:
        try:
            plan = plan_frames(trajectory.t, args.fps, args.speed, args.max_frames)
        except AnimationError as exc:
            return _fail(str(exc))
    try:
        metrics = write_report(trajectory, config, args.out, extra, plots=not args.no_plots,
                               events=events)
    except OSError as exc:
        return _fail(f'cannot write the report to {args.out}: {exc.strerror or exc}')
    except ValueError as exc:
        return _fail(f'{args.input}: {_one_line(str(exc))}')
    print(f'formation_report: {args.input}')
    print(format_summary(metrics, args.out))
    if plan is not None:
        start = time.monotonic()
        try:
            path = write_animation(trajectory, config, args.out, events, plan, args.dpi)
        except AnimationError as exc:
            return _fail(str(exc))
        print(f'  {describe(path, plan, time.monotonic() - start)}')
    return 0


if __name__ == '__main__':
    sys.exit(main())
