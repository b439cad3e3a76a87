"""
``formation_report``: metrics.json and figures of a recorded run.

They are computed by the same code as ``formation_sim``.

Input: a directory holding ``trajectory.npz`` and ``params.yaml`` (a ``formation_sim`` output
directory, or the output of ``scripts/launch_formation.sh --out``; a ``plant_stats.json``
there is merged into the metrics).
"""

import argparse
import json
import os
import sys

from formation_ros.core.params import load_config, ParamError
from formation_ros.sim import format_summary, run_metrics
from formation_ros.trajectory import Trajectory

PLANT_STATS = 'plant_stats.json'


class ReportError(Exception):
    """The input cannot be reported on; the message says why."""


def load_run(path):
    """Return (Trajectory, FormationConfig, extra metrics) of a run directory."""
    if not os.path.isdir(path):
        raise ReportError(f'{path}: not a directory')
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
    stats = os.path.join(path, PLANT_STATS)
    if os.path.exists(stats):
        with open(stats, encoding='utf-8') as stream:
            extra = json.load(stream)
    return trajectory, config, extra


def write_report(trajectory, config, out_dir, extra=None, plots=True):
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
        from formation_ros import plots as figures
        figures.write_figures(trajectory, config.law(), metrics, out_dir)
    return metrics


def main(argv=None):
    """Entry point of ``formation_report``; returns the exit code."""
    parser = argparse.ArgumentParser(
        prog='formation_report',
        description='Metrics and figures of a recorded formation run.',
        epilog='Example: formation_report runs/demo --out runs/demo')
    parser.add_argument('input', help='run directory with trajectory.npz and params.yaml')
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
