# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
``formation_report``: metrics.json and figures of a recorded run.

They are computed by the same code as ``formation_sim``. Input:

* a rosbag2 directory written by ``record`` (or ``launch_formation.sh --record``): the
  trajectory is rebuilt from the recorded poses, commands and reference samples, and the
  parameters come from the bag itself (``/formation/params``, else ``params.yaml`` beside
  ``metadata.yaml``); the plant's counters come from its last ``/diagnostics`` status;
* or a run directory holding ``trajectory.npz`` and ``params.yaml`` (``formation_sim`` output,
  or ``launch_formation.sh --out``; a ``plant_stats.json`` there is merged into the metrics).
"""

import argparse
import json
import os
import sys
from typing import Any, Dict, Optional, Tuple

from formation_ros.core.declarations import ParamError
from formation_ros.core.params import FormationConfig, load_config, validate
from formation_ros.core.params_file import parse_params_text
from formation_ros.core.plant import PLANT_STATS_FILE
from formation_ros.core.trajectory import Trajectory
from formation_ros.ros import topics as names
from formation_ros.ros.bag_writer import BagError, PARAMS_FILE
from formation_ros.tools.bag import (bag_params_text, plant_status, read_messages,
                                     trajectory_from_topics)
from formation_ros.tools.sim import format_summary, run_metrics

Loaded = Tuple[Trajectory, FormationConfig, Dict[str, Any]]


class ReportError(Exception):
    """The input cannot be reported on; the message says why."""


def load_bag(path: str) -> Loaded:
    """Return (Trajectory, FormationConfig, extra metrics) of a recorded bag."""
    try:
        recorded, counts = read_messages(path)
    except (BagError, OSError, ValueError) as exc:
        raise ReportError(f'{path}: cannot read the bag: {exc}') from None
    text = bag_params_text(path, recorded)
    if text is None:
        raise ReportError(f'{path}: the bag has no parameters (no {names.PARAMS} message and '
                          'no '
                          f'{PARAMS_FILE}); without the formation and the bound it cannot be '
                          'interpreted. Record with the record node (it stores them) or put '
                          f'the parameters file there as {PARAMS_FILE}.')
    try:
        config = validate(parse_params_text(text, f'{path} parameters'))
        trajectory, info = trajectory_from_topics(recorded, config)
    except (ParamError, BagError) as exc:
        raise ReportError(f'{path}: {exc}') from None
    extra = {'source': 'rosbag2', 'integrator': 'recorded run (rosbag2)',
             'messages': int(sum(counts.values()))}
    extra.update(info)
    extra.update(plant_status(recorded))
    return trajectory, config, extra


def load_run(path: str) -> Loaded:
    """Return (Trajectory, FormationConfig, extra metrics) of a bag or a run directory."""
    if not os.path.isdir(path):
        raise ReportError(f'{path}: not a directory')
    if os.path.isfile(os.path.join(path, 'metadata.yaml')):
        return load_bag(path)
    params = os.path.join(path, 'params.yaml')
    if not os.path.exists(params):
        raise ReportError(f'{path}: no params.yaml: the run cannot be interpreted without the '
                          'parameters it ran with (formation, bound, reference)')
    try:
        config = load_config(params)
    except ParamError as exc:
        raise ReportError(f'{params}: {exc}') from None
    try:
        trajectory = Trajectory.load(os.path.join(path, 'trajectory.npz'))
    except ValueError as exc:
        raise ReportError(str(exc)) from None
    if trajectory.q.shape[1:] != (config.num_robots, config.dim):
        raise ReportError(f'{path}: trajectory has {trajectory.q.shape[1]} robots in '
                          f'{trajectory.q.shape[2]}D but params.yaml says {config.num_robots} '
                          f'in {config.dim}D')
    extra = {}
    stats = os.path.join(path, PLANT_STATS_FILE)
    if os.path.exists(stats):
        with open(stats, encoding='utf-8') as stream:
            extra = json.load(stream)
    return trajectory, config, extra


def write_report(trajectory: Trajectory, config: FormationConfig, out_dir: str,
                 extra: Optional[Dict[str, Any]] = None, plots: bool = True) -> dict:
    """Write metrics.json (and the figures) to ``out_dir``; return the metrics."""
    extra = dict(extra or {})
    integrator = extra.pop('integrator', 'recorded run')
    metrics = run_metrics(trajectory, config, integrator)
    metrics.update(extra)
    os.makedirs(out_dir, exist_ok=True)
    with open(os.path.join(out_dir, 'metrics.json'), 'w', encoding='utf-8') as stream:
        json.dump(metrics, stream, indent=2)
        stream.write('\n')
    if plots:
        from formation_ros.tools import plots as figures
        figures.write_figures(trajectory, config.law(), metrics, out_dir)
    return metrics


def main(argv: Optional[list] = None) -> int:
    """Entry point of ``formation_report``; returns the exit code."""
    parser = argparse.ArgumentParser(
        prog='formation_report',
        description='Metrics and figures of a recorded formation run.',
        epilog='Example: formation_report runs/demo/bag --out runs/demo')
    parser.add_argument('input', help='rosbag2 directory (metadata.yaml + MCAP) or run '
                                      'directory with trajectory.npz and params.yaml')
    parser.add_argument('--out', required=True, help='where to write metrics.json and figures')
    parser.add_argument('--no-plots', action='store_true', help='skip the figures')
    args = parser.parse_args(argv)
    try:
        trajectory, config, extra = load_run(args.input)
    except ReportError as exc:
        print(f'formation_report: {exc}', file=sys.stderr)
        return 2
    metrics = write_report(trajectory, config, args.out, extra, plots=not args.no_plots)
    print(f'formation_report: {args.input}')
    print(format_summary(metrics, args.out))
    return 0


if __name__ == '__main__':
    sys.exit(main())
