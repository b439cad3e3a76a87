# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
Soak benchmark: resident memory of every process of a long recorded run (on demand, not in CI).

Usage: python bench/bench_soak.py [--duration 1800] [--interval 5] [--prefix INSTALL]
[--params FILE] [--out DIR] [--json PATH] [--window 60]

Runs scripts/launch_formation.sh with 10 robots (Section 5 constants, as bench_core.py's
params_for(10), unless --params is given) and --record for DURATION wall-clock seconds. Every
INTERVAL seconds it reads VmRSS from /proc/<pid>/status of each process of the run: the
launcher and its plant, reference, robot and record processes (the descendants of the launcher
started from INSTALL/lib/formation_ros/). At the end it prints a table of the median RSS in the
first and in the last WINDOW seconds of each process and the growth between them, writes the
samples and the table as JSON (--json, default OUT/soak.json) and a figure of RSS over time
(OUT/soak_rss.png), then checks that the bag is readable with formation_report (its exit code)
and reports that too. Exit code: 0 when the run and the report succeeded, 1 otherwise.
"""

import argparse
import datetime
import json
import os
import platform
import random
import signal
import subprocess
import sys
import time
from typing import Any, Dict, List, Mapping, Optional, Sequence, Tuple

BENCH = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(BENCH)
sys.path[:0] = [ROOT, BENCH]

from bench_core import params_for  # noqa: E402
from formation_ros.core.settings.params_file import write_params_file  # noqa: E402, I100
from formation_ros.ros.watch import stat_fields  # noqa: E402

NODES = ('plant', 'reference', 'robot', 'record', 'fleet')
LAUNCHER = 'launcher'
DEFAULT_DURATION = 1800.0
DEFAULT_INTERVAL = 5.0
DEFAULT_WINDOW = 60.0
GROWTH_LIMIT = 5.0
STOP_GRACE = 60.0

Samples = Dict[str, List[Tuple[float, int]]]


def build_parser() -> argparse.ArgumentParser:
    """Command line of the soak benchmark."""
    parser = argparse.ArgumentParser(
        prog='bench_soak.py', description=__doc__.split('\n\n')[2].strip(),
        epilog='Quick check: python bench/bench_soak.py --duration 60')
    parser.add_argument('--duration', type=float, default=DEFAULT_DURATION,
                        help='wall-clock seconds of the run (default %(default)g: 30 minutes)')
    parser.add_argument('--interval', type=float, default=DEFAULT_INTERVAL,
                        help='seconds between two memory samples (default %(default)g)')
    parser.add_argument('--window', type=float, default=DEFAULT_WINDOW,
                        help='length of the first and last windows compared, s (default '
                             '%(default)g; a third of the duration when that is shorter)')
    parser.add_argument('--prefix', default=os.path.join(ROOT, 'install', 'formation_ros'),
                        help='install space of formation_ros (default: %(default)s)')
    parser.add_argument('--params', help='parameters file (default: Section 5 constants with '
                                         '10 robots, written into the output directory)')
    parser.add_argument('--out', help='output directory, must not exist yet (default: '
                                      'runs/soak-<date>-<time>)')
    parser.add_argument('--json', help='where to write the JSON results (default: '
                                       'OUT/soak.json)')
    return parser


def parse_args(argv: Optional[Sequence[str]] = None) -> argparse.Namespace:
    """Parse and check the command line (argparse exits 2 on a bad one)."""
    parser = build_parser()
    args = parser.parse_args(argv)
    for name in ('duration', 'interval', 'window'):
        if not getattr(args, name) > 0.0:
            parser.error(f'--{name} must be > 0')
    if args.out is None:
        stamp = datetime.datetime.now().strftime('%Y%m%d-%H%M%S')
        args.out = os.path.join(ROOT, 'runs', f'soak-{stamp}')
    if os.path.exists(args.out):
        parser.error(f"--out '{args.out}' exists already; choose a new directory")
    if args.json is None:
        args.json = os.path.join(args.out, 'soak.json')
    if not os.access(os.path.join(args.prefix, 'lib', 'formation_ros', 'plant'), os.X_OK):
        parser.error(f"no formation_ros install at --prefix '{args.prefix}' (build one with "
                     'colcon, see docs/ros_interface.md)')
    args.prefix = os.path.abspath(args.prefix)
    return args


def _proc_kib(pid: int, name: str, field: str) -> Optional[int]:
    """Return the KiB of ``field`` (e.g. 'VmRSS:') in ``/proc/<pid>/<name>``; None if absent."""
    try:
        with open(f'/proc/{pid}/{name}', encoding='ascii', errors='replace') as stream:
            for line in stream:
                if line.startswith(field):
                    return int(line.split()[1])
    except (FileNotFoundError, ProcessLookupError, PermissionError):
        return None
    return None


def read_rss_kib(pid: int) -> Optional[int]:
    """Return VmRSS of process ``pid`` in KiB, or None when it is gone (or a kernel thread)."""
    return _proc_kib(pid, 'status', 'VmRSS:')


def read_pss_kib(pid: int) -> Optional[int]:
    """
    Return the proportional set size of process ``pid`` in KiB, or None when it is gone.

    Its private pages and its share of the pages it shares (libraries, shared memory): the sum
    over processes is the memory they take from the machine, where the sum of their RSS counts
    each shared library once per process.
    """
    return _proc_kib(pid, 'smaps_rollup', 'Pss:')


def _process_table() -> Dict[int, Tuple[int, List[str]]]:
    """Map every visible pid to (parent pid, command line arguments)."""
    table: Dict[int, Tuple[int, List[str]]] = {}
    for entry in os.listdir('/proc'):
        if not entry.isdigit():
            continue
        try:
            parent = int(stat_fields(int(entry))[1])
            with open(f'/proc/{entry}/cmdline', 'rb') as stream:
                cmdline = stream.read()
        except (OSError, ValueError, IndexError):
            continue
        args = [arg.decode(errors='replace') for arg in cmdline.split(b'\0') if arg]
        table[int(entry)] = (parent, args)
    return table


def node_name(args: Sequence[str], prefix: str) -> Optional[str]:
    """
    Name the formation node started with command line ``args`` from install ``prefix``.

    Returns 'plant', 'reference', 'record', 'robot_<id>' (from ``robot_id:=<id>``, else the
    ``/robot_<id>`` namespace) or 'fleet_<ids>' (from ``--robots <ids>``), or None for any
    other process.
    """
    base = os.path.join(prefix, 'lib', 'formation_ros') + os.sep
    executable = next((arg[len(base):] for arg in args if arg.startswith(base)), None)
    if executable not in NODES:
        return None
    if executable == 'fleet':
        ids = next((b for a, b in zip(args, args[1:]) if a == '--robots'), '')
        return f'fleet_{ids}' if ids else 'fleet'
    if executable != 'robot':
        return executable
    for arg in args:
        for marker in ('robot_id:=', '__ns:=/robot_'):
            if arg.startswith(marker):
                return f'robot_{arg[len(marker):]}'
    return 'robot'


def find_run_processes(root_pid: int, prefix: str) -> Dict[str, int]:
    """Return {name: pid} of the formation nodes among the descendants of ``root_pid``."""
    table = _process_table()
    found: Dict[str, int] = {}
    for pid, (_, args) in table.items():
        name = node_name(args, prefix)
        if name is None:
            continue
        ancestor, seen = pid, set()
        while ancestor in table and ancestor not in seen and ancestor != root_pid:
            seen.add(ancestor)
            ancestor = table[ancestor][0]
        if ancestor == root_pid:
            found[name] = pid
    return found


def window_median(samples: Sequence[Tuple[float, int]], start: float,
                  end: float) -> Optional[float]:
    """Median of the sample values with start <= t <= end (KiB), or None if there are none."""
    values = sorted(value for t, value in samples if start <= t <= end)
    if not values:
        return None
    middle = len(values) // 2
    return float(values[middle]) if len(values) % 2 else 0.5 * (values[middle - 1] +
                                                                values[middle])


def summarise(samples: Mapping[str, Sequence[Tuple[float, int]]],
              window: float) -> Dict[str, Dict[str, Any]]:
    """
    Compare each process's RSS at the start and at the end of the run.

    samples: {name: [(t in s, RSS in KiB), ...]}, every process sampled at the same instants.
    The run proper is the span in which every process was there: the start-up and the shutdown
    around it are left out. Per process: the median RSS in the first and in the last ``window``
    seconds of that span (of its own samples when it was never there with all the others), in
    KiB, the growth between them in percent (None where a window holds no sample) and the
    largest sample.
    """
    rows_by_name = {name: rows for name, rows in samples.items() if rows}
    times = [{t for t, _ in rows} for rows in rows_by_name.values()]
    common = set.intersection(*times) if times else set()
    table: Dict[str, Dict[str, Any]] = {}
    for name, rows in rows_by_name.items():
        span = common or {t for t, _ in rows}
        start, end = min(span), max(span)
        first = window_median(rows, start, start + window)
        last = window_median(rows, end - window, end)
        growth = None if first is None or last is None else 100.0 * (last - first) / first
        table[name] = {'first_kib': first, 'last_kib': last, 'growth_percent': growth,
                       'max_kib': max(value for _, value in rows)}
    return table


def sort_key(name: str) -> Tuple[int, int, str]:
    """Order launcher, record, plant, reference, then robots by number."""
    order = (LAUNCHER, 'record', 'plant', 'reference')
    if name in order:
        return order.index(name), 0, name
    number = name.rpartition('_')[2]
    return len(order), int(number) if number.isdigit() else 0, name


def _mib(kib: Optional[float]) -> str:
    return '-' if kib is None else f'{kib / 1024.0:.1f}'


def format_table(table: Mapping[str, Mapping[str, Any]], window: float) -> str:
    """Markdown table: process, RSS in the first and last window (MiB), growth %."""
    lines = [f'| process | RSS first {window:g} s (MiB) | RSS last {window:g} s (MiB) | '
             'growth (%) |', '|---|---:|---:|---:|']
    for name in sorted(table, key=sort_key):
        row = table[name]
        growth = row['growth_percent']
        growth_text = '-' if growth is None else f'{growth:+.2f}'
        lines.append(f"| {name} | {_mib(row['first_kib'])} | {_mib(row['last_kib'])} | "
                     f'{growth_text} |')
    return '\n'.join(lines)


def write_json(path: str, result: Mapping[str, Any]) -> None:
    """Write ``result`` as indented JSON at ``path`` (creating its directory)."""
    os.makedirs(os.path.dirname(os.path.abspath(path)), exist_ok=True)
    with open(path, 'w', encoding='utf-8') as stream:
        json.dump(result, stream, indent=2)
        stream.write('\n')


def write_figure(path: str, samples: Mapping[str, Sequence[Tuple[float, int]]]) -> None:
    """Plot RSS (MiB) over time (s) per process into the PNG file ``path``."""
    import matplotlib
    matplotlib.use('Agg')
    import matplotlib.pyplot as plt
    figure, axes = plt.subplots(figsize=(10, 6))
    robots = [name for name in samples if name.startswith('robot')]
    shades = plt.get_cmap('viridis')
    colours = {LAUNCHER: 'black', 'record': 'tab:orange', 'plant': 'tab:red',
               'reference': 'tab:purple'}
    for name in sorted(samples, key=sort_key):
        rows = samples[name]
        if not rows:
            continue
        robot = name in robots
        colour = shades(robots.index(name) / max(1, len(robots))) if robot else colours.get(name)
        axes.plot([t for t, _ in rows], [value / 1024.0 for _, value in rows], color=colour,
                  linewidth=0.8 if robot else 1.8, label=name)
    axes.set_xlabel('time since start [s]')
    axes.set_ylabel('resident memory (VmRSS) [MiB]')
    axes.set_title('Soak run: resident memory per process')
    axes.grid(True, alpha=0.3)
    axes.legend(fontsize='small', ncol=2, loc='center left', bbox_to_anchor=(1.01, 0.5))
    figure.tight_layout()
    figure.savefig(path, dpi=110)
    plt.close(figure)


def bag_summary(bag: str) -> Dict[str, Any]:
    """Message count, duration (s) and size on disk (bytes) of the bag in directory ``bag``."""
    import yaml
    size = sum(os.path.getsize(os.path.join(folder, name))
               for folder, _, names in os.walk(bag) for name in names)
    summary: Dict[str, Any] = {'bytes': size, 'messages': None, 'duration': None}
    try:
        with open(os.path.join(bag, 'metadata.yaml'), encoding='utf-8') as stream:
            info = yaml.safe_load(stream)['rosbag2_bagfile_information']
        summary['messages'] = int(info['message_count'])
        summary['duration'] = info['duration']['nanoseconds'] / 1e9
    except (OSError, KeyError, TypeError, ValueError, yaml.YAMLError):
        pass
    return summary


def _stop_group(process: 'subprocess.Popen[bytes]') -> None:
    """Stop the launcher's process group: SIGINT as Ctrl-C would, then SIGKILL if it hangs."""
    for sig, wait in ((signal.SIGINT, STOP_GRACE), (signal.SIGKILL, 10.0)):
        if process.poll() is not None:
            return
        try:
            os.killpg(process.pid, sig)
        except ProcessLookupError:
            return
        try:
            process.wait(timeout=wait)
        except subprocess.TimeoutExpired:
            continue


def sample_run(process: 'subprocess.Popen[bytes]', prefix: str, interval: float,
               start: float) -> Tuple[Samples, Dict[str, List[int]]]:
    """
    Sample the RSS of the launcher and its nodes every ``interval`` s until the launcher ends.

    Returns the samples {name: [(t, KiB)]} with t in s since ``start`` (monotonic clock) and
    {name: [pids]} (more than one pid means the name was restarted).
    """
    samples: Samples = {}
    pids: Dict[str, List[int]] = {}
    while True:
        now = time.monotonic() - start
        processes = {LAUNCHER: process.pid, **find_run_processes(process.pid, prefix)}
        for name, pid in processes.items():
            rss = read_rss_kib(pid)
            if rss is None:
                continue
            samples.setdefault(name, []).append((round(now, 3), rss))
            if pid not in pids.setdefault(name, []):
                pids[name].append(pid)
        try:
            process.wait(timeout=interval)
            return samples, pids
        except subprocess.TimeoutExpired:
            continue


def check_bag(prefix: str, bag: str, out: str) -> int:
    """Run formation_report on ``bag`` (writing into ``out``); return its exit code."""
    sites = [os.path.join(prefix, 'lib', name, 'site-packages')
             for name in os.listdir(os.path.join(prefix, 'lib')) if name.startswith('python3')]
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(
        sites + [p for p in [os.environ.get('PYTHONPATH')] if p]))
    command = [os.path.join(prefix, 'lib', 'formation_ros', 'formation_report'), bag,
               '--out', out]
    return subprocess.call(command, env=env, stdout=subprocess.DEVNULL)


def main(argv: Optional[Sequence[str]] = None) -> int:
    """Run the soak benchmark; return the exit code."""
    args = parse_args(argv)
    os.makedirs(args.out)
    params = args.params or os.path.join(args.out, 'params.yaml')
    if args.params is None:
        write_params_file(params, params_for(10))
    bag = os.path.join(args.out, 'bag')
    window = min(args.window, args.duration / 3.0)
    env = dict(os.environ, ROS_DOMAIN_ID=str(random.randint(1, 101)),
               ROS_AUTOMATIC_DISCOVERY_RANGE='LOCALHOST')
    command = ['bash', os.path.join(ROOT, 'scripts', 'launch_formation.sh'), params,
               '--duration', f'{args.duration:g}', '--record', bag, '--prefix', args.prefix]
    print(f'soak: {args.duration:g} s, RSS every {args.interval:g} s, output in {args.out} '
          f'(launcher output in launcher.log)', flush=True)
    start = time.monotonic()
    with open(os.path.join(args.out, 'launcher.log'), 'wb') as log:
        process = subprocess.Popen(command, env=env, stdout=log, stderr=subprocess.STDOUT,
                                   stdin=subprocess.DEVNULL, start_new_session=True)
        try:
            samples, pids = sample_run(process, args.prefix, args.interval, start)
        except KeyboardInterrupt:
            print('soak: interrupted; stopping the run', flush=True)
            _stop_group(process)
            raise
        finally:
            _stop_group(process)
    wall = time.monotonic() - start
    table = summarise(samples, window)
    report_code = check_bag(args.prefix, bag, os.path.join(args.out, 'report'))
    bag_info = bag_summary(bag)
    figure = os.path.join(args.out, 'soak_rss.png')
    write_figure(figure, samples)
    above = sorted((name for name, row in table.items()
                    if row['growth_percent'] is not None and row['growth_percent'] > GROWTH_LIMIT),
                   key=sort_key)
    result = {
        'machine': f'{platform.machine()}, {os.cpu_count()} cores, Python '
                   f'{platform.python_version()}',
        'duration': args.duration, 'interval': args.interval, 'window': window,
        'wall_time': wall, 'prefix': args.prefix, 'params': os.path.abspath(params),
        'bag': os.path.abspath(bag), 'launcher_exit_code': process.returncode,
        'report_exit_code': report_code, 'bag_readable': report_code == 0, 'bag_info': bag_info,
        'growth_limit_percent': GROWTH_LIMIT, 'above_limit': above, 'processes': table,
        'pids': pids, 'samples': {name: [list(row) for row in rows]
                                  for name, rows in samples.items()},
        'figure': os.path.abspath(figure),
    }
    write_json(args.json, result)
    print(format_table(table, window))
    print(f'soak: {len(table)} processes sampled over {wall:.0f} s; growth above '
          f"{GROWTH_LIMIT:g} %: {', '.join(above) or 'none'}")
    print(f'soak: launcher exit code {process.returncode}; bag {bag}: '
          f"{bag_info['messages']} messages, {bag_info['bytes'] / 1e6:.1f} MB, "
          f"{'readable' if report_code == 0 else 'NOT readable'} by formation_report "
          f'(exit code {report_code})')
    print(f'soak: wrote {args.json} and {figure}')
    return 0 if process.returncode == 0 and report_code == 0 else 1


if __name__ == '__main__':
    sys.exit(main())
