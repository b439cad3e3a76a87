# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
Offline benchmark: the whole formation_sim command for N = 10 to 10,000 (on demand, not in CI).

Usage: python bench/bench_offline.py [--sizes 10 100 1000 10000] [--duration 20] [--dt 0.01]
[--sample-dt 0.1] [--out DIR]

For each team size N it writes a parameters file (Section 5 constants, random start at about 10
robots per m^2, lattice goal 2 m apart) and runs ``formation_sim PARAMS --out DIR --dt DT
--sample-dt SAMPLE_DT --no-plots --quiet`` as a child process, as a user would: wall time,
peak resident memory (the child's ru_maxrss), time per step, and the real-time factor. Prints a
Markdown table and writes OUT/offline.json.
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
from typing import Any, Dict, List, Optional, Sequence

BENCH = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(BENCH)
sys.path[:0] = [ROOT, BENCH]

from bench_core import params_for  # noqa: E402
from formation_ros.core.params_file import write_params_file  # noqa: E402, I100


def build_parser() -> argparse.ArgumentParser:
    """Command line of the offline benchmark."""
    parser = argparse.ArgumentParser(
        prog='bench_offline.py', description=__doc__.split('\n\n')[2].strip(),
        epilog='Quick check: python bench/bench_offline.py --sizes 10 100 --duration 2')
    parser.add_argument('--sizes', type=int, nargs='+', default=[10, 100, 1000, 10000],
                        help='team sizes N (default: %(default)s)')
    parser.add_argument('--duration', type=float, default=20.0,
                        help='simulated seconds (default %(default)g)')
    parser.add_argument('--dt', type=float, default=0.01, help='step, s (default %(default)g)')
    parser.add_argument('--sample-dt', type=float, default=0.1,
                        help='spacing of the saved samples, s (default %(default)g)')
    parser.add_argument('--out', help='output directory (default: runs/offline-<date>-<time>)')
    return parser


def parse_args(argv: Optional[Sequence[str]] = None) -> argparse.Namespace:
    """Parse and check the command line (argparse exits 2 on a bad one)."""
    parser = build_parser()
    args = parser.parse_args(argv)
    if min(args.sizes) < 1:
        parser.error('--sizes must be >= 1')
    if not (args.duration > 0.0 and args.dt > 0.0 and args.sample_dt >= args.dt):
        parser.error('--duration and --dt must be > 0, --sample-dt at least --dt')
    if args.out is None:
        stamp = datetime.datetime.now().strftime('%Y%m%d-%H%M%S')
        args.out = os.path.join(ROOT, 'runs', f'offline-{stamp}')
    return args


def run_case(args: argparse.Namespace, n: int, folder: str) -> Dict[str, Any]:
    """Run formation_sim once for N robots; return its row."""
    params = os.path.join(folder, 'params.yaml')
    values = params_for(n)
    values['duration'] = float(args.duration)
    write_params_file(params, values)
    command = [sys.executable, '-m', 'formation_ros.tools.sim', params, '--out',
               os.path.join(folder, 'run'), '--dt', repr(args.dt), '--sample-dt',
               repr(args.sample_dt), '--no-plots', '--quiet']
    log = os.path.join(folder, 'formation_sim.txt')
    with open(log, 'wb') as stream:
        started = time.monotonic()
        process = subprocess.Popen(command, stdout=stream, stderr=subprocess.STDOUT)
        _, status, usage = os.wait4(process.pid, 0)
        wall = time.monotonic() - started
    process.returncode = os.waitstatus_to_exitcode(status)
    with open(log, encoding='utf-8', errors='replace') as stream:
        output = stream.read()
    steps = int(round(args.duration / args.dt))
    row: Dict[str, Any] = {'robots': n, 'wall_s': wall, 'peak_rss_mib': usage.ru_maxrss / 1024.0,
                           'steps': steps, 'ms_per_step': 1e3 * wall / steps,
                           'realtime_factor': args.duration / wall}
    if process.returncode != 0:
        row['error'] = f'exit {process.returncode}: {output.strip().splitlines()[-1:]}'
        return row
    with open(os.path.join(folder, 'run', 'metrics.json'), encoding='utf-8') as stream:
        metrics = json.load(stream)
    row.update({'min_pair_distance': metrics['min_pair_distance'],
                'final_max_error': metrics['final_max_error'],
                'max_abs_u_hat_component': metrics['max_abs_u_hat_component'],
                'u_bound': metrics['u_bound']})
    return row


HEADER = ('| N | wall (s) | peak RSS (MiB) | ms per step (whole command) | real-time factor | '
          'min pair distance (m) | max abs u_hat (m/s) |\n|---:|---:|---:|---:|---:|---:|---|')


def format_row(row: Dict[str, Any]) -> str:
    """One Markdown table row."""
    if 'error' in row:
        return f"| {row['robots']} | {row['error']} | | | | | |"
    return (f"| {row['robots']} | {row['wall_s']:.1f} | {row['peak_rss_mib']:.0f} | "
            f"{row['ms_per_step']:.2f} | {row['realtime_factor']:.1f}x | "
            f"{row['min_pair_distance']:.3g} | {row['max_abs_u_hat_component']:.4g} "
            f"(bound {row['u_bound']:.4g}) |")


def main(argv: Optional[Sequence[str]] = None) -> int:
    """Run every size, print the table and write the JSON; 0 if every run succeeded."""
    args = parse_args(argv)
    os.makedirs(args.out, exist_ok=True)
    print(f'machine: {platform.machine()}, {os.cpu_count()} cores, Python '
          f'{platform.python_version()}; {args.duration:g} s simulated, dt {args.dt:g}, '
          f'samples every {args.sample_dt:g} s\n')
    print(HEADER, flush=True)
    rows: List[Dict[str, Any]] = []
    for n in args.sizes:
        with tempfile.TemporaryDirectory(dir=args.out) as folder:
            rows.append(run_case(args, n, folder))
        print(format_row(rows[-1]), flush=True)
    result = {'machine': platform.machine(), 'cores': os.cpu_count(),
              'python': platform.python_version(), 'load': os.getloadavg(),
              'arguments': vars(args), 'rows': rows}
    with open(os.path.join(args.out, 'offline.json'), 'w', encoding='utf-8') as stream:
        json.dump(result, stream, indent=2)
        stream.write('\n')
    print(f"\nwrote {os.path.join(args.out, 'offline.json')}")
    return 0 if all('error' not in row for row in rows) else 1


if __name__ == '__main__':
    sys.exit(main())
