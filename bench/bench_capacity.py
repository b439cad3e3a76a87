# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
Capacity benchmark: how many robots, at what rate, on this machine (on demand, not in CI).

Usage: python bench/bench_capacity.py [--sizes 10 20 50 100] [--rates 20 50]
[--modes process fleet] [--transport robot team] [--robots-per-process 25] [--measure 20]
[--reference-rate 10] [--obstacles K] [--lockstep] [--prefix INSTALL] [--out DIR] [--keep]
or:    python bench/bench_capacity.py --figure JSON... --out DIR

For each transport, mode, team size N and control rate it runs scripts/launch_formation.sh on
the Section 5 constants with N robots (random start at about 10 robots per m^2, lattice goal 2 m
apart), control_rate and plant.publish_rate = RATE, reference.rate 10 Hz (robots on simulated
time evaluate the reference themselves and only check its samples), plant.rate 100 Hz, one
process per robot ('process') or --robots-per-process robots per 'fleet' process ('fleet'),
with the per-robot topics ('robot', the default) or the team messages ('team': one state message,
one command message per process per state; parameter transport). With --obstacles K it adds
K pillars of radius 0.2 m at the centres of the goal lattice's cells outside the start disc
(bench_obstacles.lattice_pillars: 1.41 m from the nearest places) with b_o = 0.5 m, so the
plant tells every robot its obstacles with every state. It byte-compiles the
install first, then measures the start-up (launch until the plant starts its clock: every
robot has answered; and the CPU time of every process until then), then for MEASURE wall
seconds the CPU time and memory of every process of the run (resident, RSS, and
proportional, PSS: shared libraries counted once over all processes), then stops the run
with Ctrl-C and reads the plant's plant_stats.json: the achieved step rate, the fraction of
steps at which every robot's applied command answered a state at most two control periods old
('fresh'), and the latency from the plant publishing a state to the answer arriving (p50, p99,
max). With --lockstep it runs lockstep instead (plant.lockstep, as fast as the robots answer)
and reports steps per second. Prints a Markdown table, writes OUT/capacity.json and one figure
of the fresh fraction against N for every transport, mode and rate side by side
(OUT/capacity_fresh.png); --figure draws that figure from the capacity.json files of earlier
runs (one per mode, say) and runs nothing.
"""

import argparse
import contextlib
import datetime
import json
import os
import platform
import signal
import subprocess
import sys
import tempfile
import time
from typing import Any, Dict, List, Mapping, Optional, Sequence, Tuple

BENCH = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(BENCH)
sys.path[:0] = [ROOT, BENCH]

from bench_core import params_for  # noqa: E402
from bench_obstacles import CLEARANCE, lattice_pillars  # noqa: E402
from bench_soak import (find_run_processes, LAUNCHER, read_pss_kib,  # noqa: E402
                        read_rss_kib)
from formation_ros.core.settings.declarations import BY_NAME  # noqa: E402, I100
from formation_ros.core.settings.params_file import write_params_file  # noqa: E402
from formation_ros.ros.watch import stat_fields  # noqa: E402

PLANT_RATE = 100.0
REFERENCE_RATE = 10.0
"""reference.rate, Hz: a check that the reference node runs, not a sample per state."""
INPUT_TIMEOUT = BY_NAME['input_timeout'].default
"""The robots' input_timeout in every case, s: a reference sample must come within it."""
MODES = ('process', 'fleet')
TRANSPORTS = ('robot', 'team')
CLOCK_STARTED = 'starting the clock'
STOP_TIMEOUT = 120.0
TICKS = os.sysconf('SC_CLK_TCK')


def build_parser() -> argparse.ArgumentParser:
    """Command line of the capacity benchmark."""
    parser = argparse.ArgumentParser(
        prog='bench_capacity.py', description=__doc__.split('\n\n')[2].strip(),
        epilog='Quick check: python bench/bench_capacity.py --sizes 4 --rates 20 --measure 5')
    parser.add_argument('--sizes', type=int, nargs='+', default=[10, 20, 50, 100],
                        help='team sizes N (default: %(default)s)')
    parser.add_argument('--rates', type=float, nargs='+', default=[20.0, 50.0],
                        help='control rates, Hz (default: %(default)s)')
    parser.add_argument('--modes', nargs='+', choices=MODES, default=list(MODES),
                        help='process: one per robot; fleet: --robots-per-process per process')
    parser.add_argument('--transport', nargs='+', choices=TRANSPORTS, default=['robot'],
                        dest='transports',
                        help="robot: each robot's own topics; team: one message per state "
                             'each way per process (default: %(default)s)')
    parser.add_argument('--robots-per-process', type=int, default=25,
                        help='robots per fleet process (default: %(default)s)')
    parser.add_argument('--measure', type=float, default=20.0,
                        help='wall seconds measured after the clock starts (default %(default)g)')
    parser.add_argument('--startup-timeout', type=float, default=600.0,
                        help='wall seconds to wait for the clock to start (default %(default)g)')
    parser.add_argument('--no-parameter-services', action='store_false',
                        dest='parameter_services',
                        help="fleet.parameter_services false: a fleet's first robot alone "
                             'offers the parameter services (fewer DDS endpoints)')
    parser.add_argument('--reference-rate', type=float, default=REFERENCE_RATE,
                        help='reference.rate, Hz; 0: the control rate, a sample per state '
                             '(default: %(default)g)')
    parser.add_argument('--obstacles', type=int, default=0, metavar='K',
                        help='K pillars among the goal places, outside the start, b_o '
                             f'{CLEARANCE:g} m (default: %(default)s)')
    parser.add_argument('--lockstep', action='store_true',
                        help='run the plant in lockstep and report steps per second')
    parser.add_argument('--prefix', default=os.path.join(ROOT, 'install', 'formation_ros'),
                        help='install space of formation_ros (default: %(default)s)')
    parser.add_argument('--out', help='output directory (default: runs/capacity-<date>-<time>)')
    parser.add_argument('--keep', action='store_true',
                        help="keep each case's parameters, launcher log and run folder (the "
                             "plant's plant_stats.json, every node's log) in "
                             'OUT/<transport>-<mode>-<N>-<rate>/ instead of removing them')
    parser.add_argument('--figure', nargs='+', metavar='JSON',
                        help='run nothing: draw OUT/capacity_fresh.png from the rows of these '
                             'capacity.json files of earlier runs (e.g. one per mode)')
    return parser


def parse_args(argv: Optional[Sequence[str]] = None) -> argparse.Namespace:
    """Parse and check the command line (argparse exits 2 on a bad one)."""
    parser = build_parser()
    args = parser.parse_args(argv)
    if min(args.sizes) < 1 or args.robots_per_process < 1:
        parser.error('--sizes and --robots-per-process must be >= 1')
    if args.obstacles < 0:
        parser.error('--obstacles must be >= 0')
    if min(args.rates) <= 0.0 or max(args.rates) > PLANT_RATE:
        parser.error(f'--rates must be > 0 and at most the plant rate, {PLANT_RATE:g} Hz')
    if not args.measure > 0.0 or not args.startup_timeout > 0.0:
        parser.error('--measure and --startup-timeout must be > 0')
    if not (args.reference_rate == 0.0 or 1.0 / INPUT_TIMEOUT < args.reference_rate <= 1e4):
        parser.error(f'--reference-rate must be 0 (the control rate) or above '
                     f'{1.0 / INPUT_TIMEOUT:g} Hz (a sample within input_timeout, '
                     f'{INPUT_TIMEOUT:g} s) and at most 10000 Hz')
    if args.figure:
        unreadable = [path for path in args.figure if not os.path.isfile(path)]
        if unreadable:
            parser.error(f'--figure: no such file: {unreadable[0]}')
    elif not os.access(os.path.join(args.prefix, 'lib', 'formation_ros', 'plant'), os.X_OK):
        parser.error(f"no formation_ros install at --prefix '{args.prefix}' (build one with "
                     'colcon, see docs/ros_interface.md)')
    args.prefix = os.path.abspath(args.prefix)
    if args.out is None:
        stamp = datetime.datetime.now().strftime('%Y%m%d-%H%M%S')
        args.out = os.path.join(ROOT, 'runs', f'capacity-{stamp}')
    return args


def cpu_seconds(pid: int) -> Optional[float]:
    """Return the CPU time (user + system) of process ``pid`` so far, s; None if it is gone."""
    try:
        fields = stat_fields(pid)
    except (OSError, ValueError):
        return None
    return (int(fields[11]) + int(fields[12])) / TICKS


def fresh_fraction(age_steps: Sequence[int], max_age: int) -> Optional[float]:
    """
    Fraction of steps whose oldest command was at most ``max_age`` steps old.

    The last entry of ``age_steps`` counts steps without a usable command: never fresh.
    """
    total = sum(age_steps)
    kept = min(max_age, len(age_steps) - 2)
    return sum(age_steps[:kept + 1]) / total if total else None


def case_params(n: int, rate: float, lockstep: bool, transport: str = 'robot',
                parameter_services: bool = True,
                reference_rate: float = REFERENCE_RATE, obstacles: int = 0) -> Dict[str, Any]:
    """
    Parameters of one case (Section 5 constants, N robots, control and publish at RATE).

    reference_rate: reference.rate, Hz (0: RATE). obstacles: pillars among the goal places
    (fewer where the lattice has fewer cells outside the start; none for 0).
    """
    params = params_for(n)
    params.update({'control_rate': float(rate), 'plant.publish_rate': float(rate),
                   'reference.rate': float(reference_rate or rate), 'plant.rate': PLANT_RATE,
                   'duration': 1e4,
                   'transport': transport, 'fleet.parameter_services': parameter_services})
    if obstacles:
        params.update({'obstacles.circles': lattice_pillars(params, obstacles),
                       'obstacles.clearance': CLEARANCE})
    if lockstep:
        params.update({'plant.lockstep': True, 'plant.realtime_factor': 1e3})
    return params


def wait_for_text(path: str, text: str, process: 'subprocess.Popen[bytes]',
                  timeout: float) -> bool:
    """Wait until the file ``path`` holds ``text``; False if the process ends or time is up."""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline and process.poll() is None:
        with open(path, 'rb') as stream:
            if text.encode() in stream.read():
                return True
        time.sleep(0.1)
    return False


Snapshot = Tuple[Optional[float], Optional[int], Optional[int]]


def snapshot(pids: Mapping[str, int]) -> Dict[str, Snapshot]:
    """Return {name: (CPU seconds, RSS KiB, PSS KiB)} of the processes."""
    return {name: (cpu_seconds(pid), read_rss_kib(pid), read_pss_kib(pid))
            for name, pid in pids.items()}


def stop(process: 'subprocess.Popen[bytes]') -> None:
    """Ctrl-C the launcher (it stops its nodes and writes the run), SIGKILL if it hangs."""
    if process.poll() is None:
        process.send_signal(signal.SIGINT)
    try:
        process.wait(STOP_TIMEOUT)
    except subprocess.TimeoutExpired:
        os.killpg(process.pid, signal.SIGKILL)
        process.wait()


def run_case(args: argparse.Namespace, mode: str, n: int, rate: float,
             folder: str, transport: str = 'robot') -> Dict[str, Any]:
    """Run one case and return its row."""
    params = os.path.join(folder, 'params.yaml')
    case = case_params(n, rate, args.lockstep, transport, args.parameter_services,
                       args.reference_rate, args.obstacles)
    write_params_file(params, case)
    run_dir = os.path.join(folder, 'run')
    log = os.path.join(folder, 'launcher.txt')
    command = ['bash', os.path.join(ROOT, 'scripts', 'launch_formation.sh'), params,
               '--duration', '0', '--out', run_dir, '--prefix', args.prefix, '--no-plots']
    if mode == 'fleet':
        command += ['--robots-per-process', str(args.robots_per_process)]
    row: Dict[str, Any] = {'transport': transport, 'mode': mode, 'robots': n, 'rate_hz': rate,
                           'lockstep': args.lockstep,
                           'reference_rate_hz': args.reference_rate or rate,
                           'parameter_services': args.parameter_services,
                           'obstacles': len(case.get('obstacles.circles', ())) // 3}
    with open(log, 'wb') as output:
        started = time.monotonic()
        process = subprocess.Popen(command, stdout=output, stderr=subprocess.STDOUT,
                                   start_new_session=True)
    try:
        if not wait_for_text(log, CLOCK_STARTED, process, args.startup_timeout):
            row['error'] = 'the clock did not start (see launcher.txt)'
            return row
        row['startup_s'] = time.monotonic() - started
        pids = find_run_processes(process.pid, args.prefix)
        pids[LAUNCHER] = process.pid
        before, t0 = snapshot(pids), time.monotonic()
        time.sleep(args.measure)
        after, t1 = snapshot(pids), time.monotonic()
    finally:
        stop(process)
    row['processes'] = len(pids) - 1
    row['startup_cpu_s'] = {name: before[name][0] for name in pids
                            if before[name][0] is not None}
    row['cpu_percent'] = {name: 100.0 * (after[name][0] - before[name][0]) / (t1 - t0)
                          for name in pids
                          if before[name][0] is not None and after[name][0] is not None}
    row['rss_mib'] = {name: after[name][1] / 1024.0 for name in pids
                      if after[name][1] is not None}
    row['pss_mib'] = {name: after[name][2] / 1024.0 for name in pids
                      if after[name][2] is not None}
    stats_path = os.path.join(run_dir, 'plant_stats.json')
    if not os.path.isfile(stats_path):
        row['error'] = 'no plant_stats.json (see launcher.txt)'
        return row
    with open(stats_path, encoding='utf-8') as stream:
        stats = json.load(stream)
    row['step_rate'] = stats['achieved_step_rate']
    row['steps'] = stats['steps']
    two_periods = int(round(2.0 * PLANT_RATE / rate))
    row['fresh_fraction'] = fresh_fraction(stats['command_age_steps'], two_periods)
    row['latency_ms'] = stats['answer_latency']
    if row['obstacles']:
        row['obstacle_contacts'] = stats.get('obstacle_contacts')
        row['min_obstacle_gap'] = stats.get('min_obstacle_gap')
    return row


def _sum_where(values: Mapping[str, float], robots: bool) -> float:
    return sum(v for name, v in values.items()
               if name.startswith(('robot', 'fleet')) == robots and name != LAUNCHER)


def format_row(row: Mapping[str, Any]) -> str:
    """
    One Markdown table row (mode 'fleet -ps': without its robots' parameter services).

    The rate reads '50, reference 10' where reference.rate was not the control rate (rows of
    runs before --reference-rate have none: it was the control rate).
    """
    lean = ' -ps' if row.get('parameter_services') is False else ''
    rate = row['rate_hz']
    reference = row.get('reference_rate_hz', rate)
    shown = f'{rate:g}' + (f', reference {reference:g}' if reference != rate else '')
    head = f"| {row['mode']}{lean} | {row['robots']} | {shown} |"
    pillars = row.get('obstacles', 0)
    contacts = row.get('obstacle_contacts')
    transport = (f" {row.get('transport', 'robot')}"
                 + (f', {pillars} pillars' if pillars else '')
                 + ('' if contacts is None else f', {contacts} contacts') + ' |')
    if 'error' in row:
        return head + f" {row['error']} |" + ' |' * 9 + transport
    latency = row['latency_ms']
    fresh = row['fresh_fraction']
    cpu, rss = row['cpu_percent'], row['rss_mib']
    pss = f"{sum(row['pss_mib'].values()) / 1024.0:.2f}" if 'pss_mib' in row else '-'
    return (head + f" {row['processes']} | {row['startup_s']:.1f} | {row['step_rate']:.1f} | "
            f"{'-' if fresh is None else f'{100.0 * fresh:.1f}'} | "
            f"{latency['p50_ms'] or 0:.1f} / {latency['p99_ms'] or 0:.1f} / "
            f"{latency['max_ms']:.0f} | {cpu.get('plant', 0.0):.0f} | "
            f'{_sum_where(cpu, True):.0f} | {rss.get("plant", 0.0):.0f} | '
            f'{sum(rss.values()) / 1024.0:.2f} | {pss} |' + transport)


HEADER = ('| mode | N | rate (Hz) | processes | start-up (s) | plant steps/s | fresh (%) | '
          'latency p50 / p99 / max (ms) | plant CPU (%) | robots CPU (%) | plant RSS (MiB) | '
          'all RSS (GiB) | all PSS (GiB) | transport |\n'
          '|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---|')


def write_figure(path: str, rows: Sequence[Mapping[str, Any]]) -> None:
    """Plot the fresh fraction against N per transport, mode and rate into PNG file ``path``."""
    import matplotlib
    matplotlib.use('Agg')
    import matplotlib.pyplot as plt
    figure, axes = plt.subplots(figsize=(7, 4.5))

    def key(row: Mapping[str, Any]) -> Tuple[str, str, float]:
        return row.get('transport', 'robot'), row['mode'], row['rate_hz']

    for transport, mode, rate in sorted({key(row) for row in rows}):
        points = sorted((row['robots'], 100.0 * row['fresh_fraction']) for row in rows
                        if key(row) == (transport, mode, rate)
                        and row.get('fresh_fraction') is not None)
        if points:
            axes.plot(*zip(*points), marker='o' if transport == 'robot' else 's',
                      linestyle='-' if transport == 'robot' else '--',
                      label=f'{transport} transport, {mode}, {rate:g} Hz')
    axes.axhline(99.0, color='grey', linestyle='--', linewidth=0.8)
    axes.set_xscale('log')
    axes.set_xlabel('robots N')
    axes.set_ylabel('fresh steps [%] (every command <= 2 control periods old)')
    axes.set_ylim(0, 101)
    axes.grid(True, alpha=0.3)
    axes.legend()
    figure.tight_layout()
    figure.savefig(path, dpi=110)
    plt.close(figure)


def redraw(paths: Sequence[str], figure: str) -> int:
    """Draw ``figure`` from the rows of the capacity.json files ``paths``; 2 if one is bad."""
    rows: List[Dict[str, Any]] = []
    for path in paths:
        try:
            with open(path, encoding='utf-8') as stream:
                rows.extend(json.load(stream)['rows'])
        except (OSError, ValueError, KeyError, TypeError) as exc:
            print(f'bench_capacity.py: {path} is not a capacity.json: {exc}', file=sys.stderr)
            return 2
    write_figure(figure, rows)
    print(f'wrote {figure} from {len(rows)} rows')
    return 0


def byte_compile(prefix: str) -> None:
    """
    Byte-compile the install's Python files, as a normal install does, before any run.

    Where ``PYTHONDONTWRITEBYTECODE`` is set, neither setuptools nor Python writes them, and
    every process of a run would compile the package again (a quarter of a second of CPU
    each, 10 s for the 42 processes of 1000 robots). A symlink install's package is the
    source tree's, which is compiled too. A folder that cannot be written is left as it is.
    """
    import formation_ros
    for folder in (os.path.realpath(prefix), os.path.dirname(formation_ros.__file__)):
        subprocess.run([sys.executable, '-m', 'compileall', '-q', folder], check=False,
                       stdout=subprocess.DEVNULL)


def main(argv: Optional[Sequence[str]] = None) -> int:
    """Run every case, print the table, write JSON and the figure; 0 if every case ran."""
    args = parse_args(argv)
    os.makedirs(args.out, exist_ok=True)
    if args.figure:
        return redraw(args.figure, os.path.join(args.out, 'capacity_fresh.png'))
    machine = {'machine': platform.machine(), 'cores': os.cpu_count(),
               'python': platform.python_version(), 'load_before': os.getloadavg()}
    print(f"machine: {machine['machine']}, {machine['cores']} cores, Python "
          f"{machine['python']}; plant.rate {PLANT_RATE:g} Hz, {args.measure:g} s measured"
          + (', lockstep' if args.lockstep else '') + '\n')
    print(HEADER, flush=True)
    byte_compile(args.prefix)
    rows: List[Dict[str, Any]] = []
    os.environ.setdefault('ROS_AUTOMATIC_DISCOVERY_RANGE', 'LOCALHOST')
    for mode in args.modes:
        for rate in args.rates:
            for n in args.sizes:
                for transport in args.transports:
                    kept = os.path.join(args.out, f'{transport}-{mode}-{n}-{rate:g}')
                    if args.keep:
                        os.makedirs(kept, exist_ok=True)
                    with (contextlib.nullcontext(kept) if args.keep
                          else tempfile.TemporaryDirectory(dir=args.out)) as folder:
                        row = run_case(args, mode, n, rate, folder, transport)
                    rows.append(row)
                    print(format_row(row), flush=True)
    result = {**machine, 'load_after': os.getloadavg(), 'arguments': vars(args), 'rows': rows}
    with open(os.path.join(args.out, 'capacity.json'), 'w', encoding='utf-8') as stream:
        json.dump(result, stream, indent=2, default=str)
        stream.write('\n')
    write_figure(os.path.join(args.out, 'capacity_fresh.png'), rows)
    print(f'\nwrote {os.path.join(args.out, "capacity.json")} and capacity_fresh.png')
    return 0 if all('error' not in row for row in rows) else 1


if __name__ == '__main__':
    sys.exit(main())
