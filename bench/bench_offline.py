# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
Offline benchmark: the whole formation_sim command for N = 10 to 10,000 (on demand, not in CI).

Usage: python bench/bench_offline.py [--sizes 100 1000 10000] [--duration 20] [--dt 0.01]
[--sample-dt 0.1 default] [--no-split] [--out DIR]

For each team size N and each sample spacing (seconds, or ``default``: no ``--sample-dt``,
formation_sim's own rule) it writes a parameters file (Section 5 constants, random start at
about 10 robots per m^2, lattice goal 2 m apart) and runs ``formation_sim PARAMS --out DIR --dt
DT [--sample-dt SAMPLE_DT] --no-plots --quiet`` as a child process, as a user would: wall time,
CPU time, peak resident memory (the child's ru_maxrss), time per step, the real-time factor.
Then, unless --no-split, a second child does what formation_sim's main does for a --dt run one
part at a time and reports the wall time of each: Python's own start, imports, start-up
(reading and checking the parameters, the random start), integration (the plant model, the law,
the samples' arrays), metrics, writing. Prints Markdown tables and writes OUT/offline.json.
"""

import argparse
import datetime
import json
import os
import platform
import subprocess
import sys
import tempfile
import time
from typing import Any, Dict, List, Optional, Sequence, Tuple

BENCH = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(BENCH)
sys.path[:0] = [ROOT, BENCH]

from bench_core import params_for  # noqa: E402
from formation_ros.core.settings.params_file import write_params_file  # noqa: E402, I100

SPLIT_CHILD = """
import json, os, resource, shutil, sys, time
begun, cpu_begun = time.perf_counter(), time.process_time()
from formation_ros.core.runs.trajectory import TRAJECTORY_FILE
from formation_ros.core.settings.params import load_config
from formation_ros.simulation import simulate
imported, cpu_imported = time.perf_counter(), time.process_time()
params, out, dt, sample_dt = sys.argv[1], sys.argv[2], float(sys.argv[3]), sys.argv[4]
config = load_config(params)
duration = config.duration
given = None if sample_dt == 'default' else float(sample_dt)
sampling = simulate.sampling_metadata(config.num_robots, duration, dt, given)
events = simulate.schedule_events(config)
progress = simulate.Progress(duration, quiet=True)
started, cpu_started = time.perf_counter(), time.process_time()
run = simulate.run_fixed_step(config, duration, dt, sampling['sample_dt'], progress)
integrated, cpu_integrated = time.perf_counter(), time.process_time()
metrics = simulate.run_metrics(run.trajectory, config, f'zero-order hold, dt = {dt:g} s', events)
metrics.update(simulate.plant_metrics(run, config))
metrics.update(sampling)
measured, cpu_measured = time.perf_counter(), time.process_time()
os.makedirs(out, exist_ok=True)
run.trajectory.save(os.path.join(out, TRAJECTORY_FILE))
shutil.copyfile(params, os.path.join(out, simulate.PARAMS_COPY))
with open(os.path.join(out, simulate.METRICS_FILE), 'w', encoding='utf-8') as stream:
    json.dump(metrics, stream, indent=2)
written, cpu_written = time.perf_counter(), time.process_time()
print(json.dumps({'imports_s': imported - begun, 'start_up_s': started - imported,
                  'integration_s': integrated - started, 'metrics_s': measured - integrated,
                  'writing_s': written - measured, 'in_script_s': written - begun,
                  'cpu_imports_s': cpu_imported - cpu_begun,
                  'cpu_start_up_s': cpu_started - cpu_imported,
                  'cpu_integration_s': cpu_integrated - cpu_started,
                  'cpu_metrics_s': cpu_measured - cpu_integrated,
                  'cpu_writing_s': cpu_written - cpu_measured,
                  'peak_rss_mib': resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0}))
"""
"""What formation_sim's main does for a --dt run, timed part by part (stdout: one JSON line)."""

SPLIT_PARTS = ('python_s', 'imports_s', 'start_up_s', 'integration_s', 'metrics_s', 'writing_s')


def build_parser() -> argparse.ArgumentParser:
    """Command line of the offline benchmark."""
    parser = argparse.ArgumentParser(
        prog='bench_offline.py', description=__doc__.split('\n\n')[2].strip(),
        epilog='Quick check: python bench/bench_offline.py --sizes 10 100 --duration 2')
    parser.add_argument('--sizes', type=int, nargs='+', default=[100, 1000, 10000],
                        help='team sizes N (default: %(default)s)')
    parser.add_argument('--duration', type=float, default=20.0,
                        help='simulated seconds (default %(default)g)')
    parser.add_argument('--dt', type=float, default=0.01, help='step, s (default %(default)g)')
    parser.add_argument('--sample-dt', nargs='+', default=['0.1'],
                        help="spacings of the saved samples, s, or 'default' for "
                             "formation_sim's own rule (default: %(default)s)")
    parser.add_argument('--no-split', action='store_true',
                        help='skip the runs that time imports, start-up, integration, writing')
    parser.add_argument('--out', help='output directory (default: runs/offline-<date>-<time>)')
    return parser


def parse_args(argv: Optional[Sequence[str]] = None) -> argparse.Namespace:
    """Parse and check the command line (argparse exits 2 on a bad one)."""
    parser = build_parser()
    args = parser.parse_args(argv)
    if min(args.sizes) < 1:
        parser.error('--sizes must be >= 1')
    try:
        spacings = [None if text == 'default' else float(text) for text in args.sample_dt]
    except ValueError:
        parser.error("--sample-dt takes numbers of seconds or 'default'")
    if not (args.duration > 0.0 and args.dt > 0.0
            and all(value is None or value >= args.dt for value in spacings)):
        parser.error('--duration and --dt must be > 0, --sample-dt at least --dt')
    args.sample_dt = spacings
    if args.out is None:
        stamp = datetime.datetime.now().strftime('%Y%m%d-%H%M%S')
        args.out = os.path.join(ROOT, 'runs', f'offline-{stamp}')
    return args


def run_child(command: List[str], log: str) -> Tuple[int, float, Any, str]:
    """Run a child process to its end: (exit code, wall s, its rusage, its output)."""
    with open(log, 'wb') as stream:
        started = time.monotonic()
        process = subprocess.Popen(command, stdout=stream, stderr=subprocess.STDOUT)
        _, status, usage = os.wait4(process.pid, 0)
        wall = time.monotonic() - started
    process.returncode = os.waitstatus_to_exitcode(status)
    with open(log, encoding='utf-8', errors='replace') as stream:
        output = stream.read()
    return process.returncode, wall, usage, output


def run_split(args: argparse.Namespace, params: str, sample_dt: Optional[float],
              folder: str) -> Dict[str, Any]:
    """Run :data:`SPLIT_CHILD`: the wall time of each part, or the error."""
    command = [sys.executable, '-c', SPLIT_CHILD, params, os.path.join(folder, 'split'),
               repr(args.dt), 'default' if sample_dt is None else repr(sample_dt)]
    code, wall, usage, output = run_child(command, os.path.join(folder, 'split.txt'))
    if code != 0:
        return {'error': f'exit {code}: {output.strip().splitlines()[-1:]}'}
    split: Dict[str, Any] = json.loads(output.strip().splitlines()[-1])
    split.update({'python_s': wall - split['in_script_s'], 'wall_s': wall,
                  'cpu_s': usage.ru_utime + usage.ru_stime})
    return split


def run_case(args: argparse.Namespace, n: int, sample_dt: Optional[float],
             folder: str) -> Dict[str, Any]:
    """Run formation_sim once for N robots (and the split run); return its row."""
    params = os.path.join(folder, 'params.yaml')
    values = params_for(n)
    values['duration'] = float(args.duration)
    write_params_file(params, values)
    spacing = [] if sample_dt is None else ['--sample-dt', repr(sample_dt)]
    command = [sys.executable, '-m', 'formation_ros.tools.sim', params, '--out',
               os.path.join(folder, 'run'), '--dt', repr(args.dt), *spacing, '--no-plots',
               '--quiet']
    code, wall, usage, output = run_child(command, os.path.join(folder, 'formation_sim.txt'))
    steps = int(round(args.duration / args.dt))
    row: Dict[str, Any] = {'robots': n, 'sample_dt_given': sample_dt, 'wall_s': wall,
                           'cpu_s': usage.ru_utime + usage.ru_stime,
                           'peak_rss_mib': usage.ru_maxrss / 1024.0, 'steps': steps,
                           'ms_per_step': 1e3 * wall / steps,
                           'realtime_factor': args.duration / wall}
    if code != 0:
        row['error'] = f'exit {code}: {output.strip().splitlines()[-1:]}'
        return row
    with open(os.path.join(folder, 'run', 'metrics.json'), encoding='utf-8') as stream:
        metrics = json.load(stream)
    row.update({key: metrics.get(key) for key in (
        'min_pair_distance', 'final_max_error', 'max_abs_u_hat_component', 'u_bound',
        'num_samples', 'sample_dt', 'sampling')})
    if not args.no_split:
        row['split'] = run_split(args, params, sample_dt, folder)
    return row


HEADER = ('| N | sample dt, s (samples) | wall (s) | CPU (s) | peak RSS (MiB) | ms per step '
          '(whole command) | real-time factor | min pair distance (m) | max abs u_hat (m/s) |'
          '\n|---:|---:|---:|---:|---:|---:|---:|---:|---|')
"""The Markdown header of :func:`format_row`'s table."""
SPLIT_HEADER = ('| N | sample dt (s) | Python | imports | start-up | integration | metrics | '
                'writing | whole | peak RSS (MiB) |\n'
                '|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|')
"""The Markdown header of :func:`format_split`'s table: wall (CPU) seconds of each part."""


def _spacing(row: Dict[str, Any]) -> str:
    """Return the sample spacing of a row (a formation_sim before the rule does not say it)."""
    spacing = row['sample_dt'] if row['sample_dt'] is not None else row['sample_dt_given']
    return 'default' if spacing is None else f'{spacing:g}'


def format_row(row: Dict[str, Any]) -> str:
    """One Markdown table row of the whole command."""
    if 'error' in row:
        return f"| {row['robots']} | {row['error']} | | | | | | | |"
    return (f"| {row['robots']} | {_spacing(row)} ({row['num_samples']}) | "
            f"{row['wall_s']:.2f} | {row['cpu_s']:.2f} | {row['peak_rss_mib']:.0f} | "
            f"{row['ms_per_step']:.2f} | {row['realtime_factor']:.1f}x | "
            f"{row['min_pair_distance']:.3g} | {row['max_abs_u_hat_component']:.4g} "
            f"(bound {row['u_bound']:.4g}) |")


def _part(split: Dict[str, Any], name: str) -> str:
    """Return one part's wall time, and its CPU time when measured, as table text."""
    cpu = split.get('cpu_' + name)
    return f'{split[name]:.2f}' + ('' if cpu is None else f' ({cpu:.2f})')


def format_split(row: Dict[str, Any]) -> str:
    """One Markdown table row of the split run."""
    split = row.get('split', {'error': row.get('error', 'not run')})
    if 'error' in split:
        return f"| {row['robots']} | {split['error']} | | | | | | | | |"
    parts = ' | '.join(_part(split, name) for name in SPLIT_PARTS)
    return (f"| {row['robots']} | {_spacing(row)} | {parts} | {split['wall_s']:.2f} "
            f"({split['cpu_s']:.2f}) | {split['peak_rss_mib']:.0f} |")


def main(argv: Optional[Sequence[str]] = None) -> int:
    """Run every size, print the tables and write the JSON; 0 if every run succeeded."""
    args = parse_args(argv)
    os.makedirs(args.out, exist_ok=True)
    load = os.getloadavg()
    print(f'machine: {platform.machine()}, {os.cpu_count()} cores, Python '
          f'{platform.python_version()}; load {load[0]:.2f} {load[1]:.2f} {load[2]:.2f}; '
          f'{args.duration:g} s simulated, dt {args.dt:g}\n')
    print(HEADER, flush=True)
    rows: List[Dict[str, Any]] = []
    for n in args.sizes:
        for sample_dt in args.sample_dt:
            with tempfile.TemporaryDirectory(dir=args.out) as folder:
                rows.append(run_case(args, n, sample_dt, folder))
            print(format_row(rows[-1]), flush=True)
    if not args.no_split:
        print(f'\nwall (CPU) seconds:\n\n{SPLIT_HEADER}')
        for row in rows:
            print(format_split(row))
    result = {'machine': platform.machine(), 'cores': os.cpu_count(),
              'python': platform.python_version(), 'load_before': load,
              'load_after': os.getloadavg(), 'arguments': vars(args), 'rows': rows}
    with open(os.path.join(args.out, 'offline.json'), 'w', encoding='utf-8') as stream:
        json.dump(result, stream, indent=2)
        stream.write('\n')
    print(f"\nwrote {os.path.join(args.out, 'offline.json')}")
    failed = [row for row in rows if 'error' in row or 'error' in row.get('split', {})]
    return 1 if failed else 0


if __name__ == '__main__':
    sys.exit(main())
