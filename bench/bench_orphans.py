# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
Orphan benchmark: how fast the nodes end after kill -9 of their launcher (on demand, not in CI).

Usage: python bench/bench_orphans.py [--params config/square_4.yaml] [--runs 10] [--busy 2]
[--record] [--hold 1] [--prefix INSTALL] [--out DIR] [--json PATH]

Each run starts scripts/launch_formation.sh PARAMS (in a session of its own, with a --duration
far longer than the run, and --record into the run's directory with --record) and waits until
every node process of the run exists (plant, reference, every robot, the recorder with
--record: the launcher's descendants started from INSTALL/lib/formation_ros/) and the plant
has started its clock (its 'starting the clock' line in the launcher's output, which the plant
prints once every robot has sent a command). After HOLD more seconds of running formation it
sends SIGKILL to the launcher process alone (not its group) and reads /proc/<pid>/stat of every
node every 5 ms until each has ended (gone, or a zombie): the seconds from the kill to each
node's end (the clock is read after each look, so a time is an upper bound). The benchmark
adopts the orphaned nodes (PR_SET_CHILD_SUBREAPER) and reads how each ended: anything but
exit code 0 counts as a failure. So does a node still there TIMEOUT s after the kill (it is
killed), any process of the run left afterwards (a process whose environment names the
killed launcher in FORMATION_LAUNCHER_PID) and, with --record, a bag without metadata.yaml.
BUSY busy loops (sh -c 'while :; do :; done') run during the whole measurement and are killed
at the end. Prints a table (per run the load, the slowest node and every node's time) and a
summary, and writes the times, the machine and the load averages as JSON (--json, default
OUT/orphans.json). Exit code: 0 when every node of every run ended within LIMIT s and nothing
failed, 1 otherwise.
"""

import argparse
import collections
import ctypes
import datetime
import os
import platform
import random
import signal
import statistics
import subprocess
import sys
import time
from typing import Any, Dict, List, Mapping, Optional, Sequence, Tuple

BENCH = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(BENCH)
sys.path[:0] = [ROOT, BENCH]

from bench_soak import find_run_processes, sort_key, write_json  # noqa: E402
from formation_ros.core.settings.params_file import load_params_file  # noqa: E402, I100
from formation_ros.ros.watch import LAUNCHER_PID_ENV, LAUNCHER_START_ENV  # noqa: E402
from formation_ros.ros.watch import process_start  # noqa: E402

DEFAULT_PARAMS = os.path.join(ROOT, 'config', 'square_4.yaml')
DEFAULT_RUNS = 10
DEFAULT_BUSY = 2
DEFAULT_HOLD = 1.0
DEFAULT_LIMIT = 2.0
DEFAULT_TIMEOUT = 10.0
DEFAULT_START_TIMEOUT = 180.0
POLL = 0.005
READY_POLL = 0.05
RUN_DURATION = 3600
CLOCK_LINE = 'starting the clock'
BUSY_LOOP = ['sh', '-c', 'while :; do :; done']
PR_SET_CHILD_SUBREAPER = 36


def build_parser() -> argparse.ArgumentParser:
    """Command line of the orphan benchmark."""
    parser = argparse.ArgumentParser(
        prog='bench_orphans.py', description=__doc__.split('\n\n')[2].strip(),
        epilog='Examples: python bench/bench_orphans.py --runs 10 --busy 2; '
               'python bench/bench_orphans.py --params config/paper_section5.yaml --runs 5 '
               '--record')
    parser.add_argument('--params', default=DEFAULT_PARAMS,
                        help='parameters file of the formation (default: %(default)s)')
    parser.add_argument('--runs', type=int, default=DEFAULT_RUNS,
                        help='number of launcher kills (default %(default)d)')
    parser.add_argument('--busy', type=int, default=DEFAULT_BUSY, metavar='K',
                        help='busy loops kept running during the measurement (default '
                             '%(default)d: both cores of a 2-core machine busy)')
    parser.add_argument('--record', action='store_true',
                        help='run with --record (the recorder is one of the nodes; its bag '
                             'must have metadata.yaml after the kill)')
    parser.add_argument('--hold', type=float, default=DEFAULT_HOLD,
                        help='seconds the formation runs after its clock started, before the '
                             'kill (default %(default)g)')
    parser.add_argument('--limit', type=float, default=DEFAULT_LIMIT,
                        help='seconds within which every node must end (default %(default)g)')
    parser.add_argument('--timeout', type=float, default=DEFAULT_TIMEOUT,
                        help='seconds after the kill after which a node still there is killed '
                             'and counts as a failure (default %(default)g)')
    parser.add_argument('--start-timeout', type=float, default=DEFAULT_START_TIMEOUT,
                        help='seconds a run may take to start (default %(default)g)')
    parser.add_argument('--prefix', default=os.path.join(ROOT, 'install', 'formation_ros'),
                        help='install space of formation_ros (default: %(default)s)')
    parser.add_argument('--out', help='directory of the runs (launcher output, bags), must not '
                                      'exist yet (default: runs/orphans-<date>-<time>)')
    parser.add_argument('--json', help='where to write the JSON results (default: '
                                       'OUT/orphans.json)')
    return parser


def parse_args(argv: Optional[Sequence[str]] = None) -> argparse.Namespace:
    """Parse and check the command line (argparse exits 2 on a bad one)."""
    parser = build_parser()
    args = parser.parse_args(argv)
    if args.runs < 1:
        parser.error('--runs must be >= 1')
    if args.busy < 0:
        parser.error('--busy must be >= 0')
    for name in ('hold', 'limit', 'timeout', 'start_timeout'):
        value = getattr(args, name)
        if not (value >= 0.0 if name == 'hold' else value > 0.0):
            parser.error(f"--{name.replace('_', '-')} must be {'>=' if name == 'hold' else '>'} 0")
    if not os.path.isfile(args.params):
        parser.error(f"parameters file '{args.params}' not found")
    if args.out is None:
        stamp = datetime.datetime.now().strftime('%Y%m%d-%H%M%S')
        args.out = os.path.join(ROOT, 'runs', f'orphans-{stamp}')
    if os.path.exists(args.out):
        parser.error(f"--out '{args.out}' exists already; choose a new directory")
    if args.json is None:
        args.json = os.path.join(args.out, 'orphans.json')
    if not os.access(os.path.join(args.prefix, 'lib', 'formation_ros', 'plant'), os.X_OK):
        parser.error(f"no formation_ros install at --prefix '{args.prefix}' (build one with "
                     'colcon, see docs/ros_interface.md)')
    args.prefix = os.path.abspath(args.prefix)
    args.params = os.path.abspath(args.params)
    return args


def expected_nodes(num_robots: int, record: bool) -> List[str]:
    """Names of the node processes of a run, as bench_soak.node_name gives them."""
    names = ['plant', 'reference'] + [f'robot_{i}' for i in range(1, num_robots + 1)]
    return (['record'] if record else []) + names


def clock_started(text: str) -> bool:
    """Tell whether launcher output ``text`` has the plant's line that its clock started."""
    return any(line.startswith('[plant] ') and CLOCK_LINE in line
               for line in text.splitlines())


def alive(pid: int, start: int) -> bool:
    """Tell whether the process ``pid`` that started at ``start`` ticks still runs."""
    return process_start(pid) == start


def launched_by(pid: int) -> Tuple[Optional[str], Optional[str]]:
    """Return the launcher pid and start time in process ``pid``'s environment (or None)."""
    try:
        with open(f'/proc/{pid}/environ', 'rb') as stream:
            entries = stream.read().split(b'\0')
    except OSError:
        return None, None
    env = dict(entry.decode(errors='replace').partition('=')[::2] for entry in entries if entry)
    return env.get(LAUNCHER_PID_ENV), env.get(LAUNCHER_START_ENV)


def become_subreaper() -> bool:
    """
    Adopt the orphans among this process's descendants (Linux); True if it worked.

    The nodes of a killed launcher then become this benchmark's children, so it can read how
    each one ended (exit code or signal) when it reaps them.
    """
    try:
        libc = ctypes.CDLL(None, use_errno=True)
        return libc.prctl(PR_SET_CHILD_SUBREAPER, 1, 0, 0, 0) == 0
    except (OSError, AttributeError):
        return False


def describe_status(status: int) -> str:
    """Describe a wait status: 'exit N' or the signal's name."""
    if os.WIFSIGNALED(status):
        number = os.WTERMSIG(status)
        try:
            return signal.Signals(number).name
        except ValueError:
            return f'signal {number}'
    return f'exit {os.WEXITSTATUS(status)}'


def reap(pid: int) -> Optional[str]:
    """Wait for child ``pid`` and describe how it ended; None if it is not this one's child."""
    try:
        _, status = os.waitpid(pid, 0)
    except ChildProcessError:
        return None
    return describe_status(status)


def run_processes_left(launcher_pid: int, launcher_start: Optional[int]) -> List[int]:
    """Pids of the live processes whose environment names this launcher (its nodes, theirs)."""
    left = []
    for entry in os.listdir('/proc'):
        if not entry.isdigit() or int(entry) == os.getpid():
            continue
        pid, start = launched_by(int(entry))
        if pid == str(launcher_pid) and (launcher_start is None or start is None
                                         or start == str(launcher_start)):
            if process_start(int(entry)) is not None:
                left.append(int(entry))
    return sorted(left)


def watch_ends(nodes: Mapping[str, Tuple[int, int]], since: float, poll: float,
               timeout: float, tick: Any = None) -> Dict[str, Optional[float]]:
    """
    Poll ``nodes`` {name: (pid, start)} every ``poll`` s until each has ended.

    Returns {name: seconds from ``since`` (monotonic clock) to the moment a look at /proc found
    it gone}, None for a node still there ``timeout`` s after ``since``. The clock is read
    after each look, so a benchmark descheduled between two looks (a busy machine) makes a
    time longer, never shorter: each time is an upper bound of when the node ended. ``tick``
    (optional) is called once per poll (the benchmark reaps the killed launcher there).
    """
    ends: Dict[str, Optional[float]] = {}
    waiting = dict(nodes)
    while waiting:
        for name, (pid, start) in list(waiting.items()):
            if not alive(pid, start):
                ends[name] = time.monotonic() - since
                del waiting[name]
        if not waiting or time.monotonic() - since > timeout:
            break
        if tick is not None:
            tick()
        time.sleep(poll)
    for name in waiting:
        ends[name] = None
    return ends


def summarise_runs(runs: Sequence[Mapping[str, Any]], limit: float) -> Dict[str, Any]:
    """
    Overall numbers of the runs: max and median end time, nodes over ``limit``, failures.

    Each run is {'ends': {name: seconds or None}, 'failures': [text, ...]}; a None end (a node
    that did not end by itself) counts as over the limit and as a failure.
    """
    times = [t for run in runs for t in run['ends'].values() if t is not None]
    missing = sum(1 for run in runs for t in run['ends'].values() if t is None)
    per_node: Dict[str, float] = {}
    for run in runs:
        for name, value in run['ends'].items():
            if value is not None:
                per_node[name] = max(per_node.get(name, 0.0), value)
    return {
        'runs': len(runs), 'node_ends': len(times), 'not_ended': missing,
        'max_s': max(times) if times else None,
        'median_s': statistics.median(times) if times else None,
        'limit_s': limit, 'over_limit': sum(1 for t in times if t > limit) + missing,
        'failures': sum(len(run['failures']) for run in runs),
        'max_per_node_s': {name: per_node[name] for name in sorted(per_node, key=sort_key)},
    }


def _seconds(value: Optional[float]) -> str:
    return 'not ended' if value is None else f'{value:.3f}'


def format_table(runs: Sequence[Mapping[str, Any]], names: Sequence[str]) -> str:
    """Markdown table: run, 1-minute load, slowest node (s), every node's end (s)."""
    lines = ['| run | load | slowest (s) | ' + ' | '.join(names) + ' |',
             '|---:|---:|---:|' + '---:|' * len(names)]
    for run in runs:
        ends = run['ends']
        values = list(ends.values())
        slowest = None if not values or None in values else max(values)
        cells = [_seconds(ends[name]) if name in ends else '-' for name in names]
        load = run.get('load_at_kill')
        lines.append(f"| {run['run']} | {'-' if load is None else f'{load[0]:.1f}'} | "
                     f"{_seconds(slowest) if values else '-'} | " + ' | '.join(cells) + ' |')
    return '\n'.join(lines)


def start_busy(count: int) -> List['subprocess.Popen[bytes]']:
    """Start ``count`` busy loops, each in a session of its own."""
    return [subprocess.Popen(BUSY_LOOP, stdin=subprocess.DEVNULL, start_new_session=True)
            for _ in range(count)]


def stop_busy(loops: Sequence['subprocess.Popen[bytes]']) -> None:
    """Kill the busy loops and reap them."""
    for loop in loops:
        try:
            os.killpg(loop.pid, signal.SIGKILL)
        except ProcessLookupError:
            pass
    for loop in loops:
        loop.wait()


def _terminate(signum: int, frame: Any) -> None:
    raise SystemExit(128 + signum)


def _kill_pids(pids: Sequence[int]) -> None:
    for pid in pids:
        try:
            os.kill(pid, signal.SIGKILL)
        except ProcessLookupError:
            pass


def _bag_check(bag: str) -> Dict[str, Any]:
    """Tell what the recorder left: metadata.yaml or not, its message count and MCAP files."""
    import yaml
    path = os.path.join(bag, 'metadata.yaml')
    info: Dict[str, Any] = {'metadata': os.path.isfile(path), 'messages': None, 'files': None}
    if info['metadata']:
        try:
            with open(path, encoding='utf-8') as stream:
                data = yaml.safe_load(stream)['rosbag2_bagfile_information']
            info['messages'] = int(data['message_count'])
            info['files'] = list(data['relative_file_paths'])
        except (OSError, KeyError, TypeError, ValueError, yaml.YAMLError) as exc:
            info['error'] = str(exc)
    return info


def _tail(path: str, lines: int = 5) -> str:
    try:
        with open(path, encoding='utf-8', errors='replace') as stream:
            return ' / '.join(stream.read().splitlines()[-lines:])
    except OSError:
        return ''


def one_run(number: int, args: argparse.Namespace, names: Sequence[str],
            env: Mapping[str, str]) -> Dict[str, Any]:
    """Start a formation, wait until it runs, kill -9 its launcher, time its nodes' ends."""
    folder = os.path.join(args.out, f'run_{number}')
    os.makedirs(folder)
    log_path = os.path.join(folder, 'launcher.log')
    bag = os.path.join(folder, 'bag')
    command = ['bash', os.path.join(ROOT, 'scripts', 'launch_formation.sh'), args.params,
               '--duration', str(RUN_DURATION), '--prefix', args.prefix]
    if args.record:
        command += ['--record', bag]
    result: Dict[str, Any] = {'run': number, 'ends': {}, 'failures': [], 'pids': {},
                              'left_over': [], 'log': log_path}
    began = time.monotonic()
    with open(log_path, 'wb') as log:
        process = subprocess.Popen(command, env=dict(env), stdout=log, stderr=subprocess.STDOUT,
                                   stdin=subprocess.DEVNULL, start_new_session=True)
    launcher_start = process_start(process.pid)
    nodes: Dict[str, Tuple[int, int]] = {}
    try:
        while True:
            if process.poll() is not None:
                result['failures'].append(f'the launcher ended before the clock started '
                                          f'(exit {process.returncode}): {_tail(log_path)}')
                return result
            found = find_run_processes(process.pid, args.prefix)
            with open(log_path, encoding='utf-8', errors='replace') as stream:
                started = clock_started(stream.read())
            if started and set(names) <= set(found):
                break
            if time.monotonic() - began > args.start_timeout:
                result['failures'].append(
                    f'not started within {args.start_timeout:g} s (nodes: '
                    f"{', '.join(sorted(found, key=sort_key))}; clock started: {started})")
                return result
            time.sleep(READY_POLL)
        result['start_s'] = time.monotonic() - began
        for name in names:
            start = process_start(found[name])
            if start is not None:
                nodes[name] = (found[name], start)
        result['pids'] = {name: pid for name, (pid, _) in nodes.items()}
        time.sleep(args.hold)
        gone_early = [name for name, (pid, start) in nodes.items() if not alive(pid, start)]
        for name in sorted(set(names) - set(nodes)) + gone_early:
            result['failures'].append(f'{name} ended before the kill')
        result['load_at_kill'] = list(os.getloadavg())
        since = time.monotonic()
        os.kill(process.pid, signal.SIGKILL)
        result['ends'] = watch_ends({n: v for n, v in nodes.items() if n not in gone_early},
                                    since, POLL, args.timeout, process.poll)
        for name, end in result['ends'].items():
            if end is None:
                result['failures'].append(f'{name} still ran {args.timeout:g} s after the kill')
    finally:
        if process.poll() is None:
            os.killpg(process.pid, signal.SIGKILL)
        process.wait()
        left = sorted(set(run_processes_left(process.pid, launcher_start)) |
                      {pid for pid, start in nodes.values() if alive(pid, start)})
        _kill_pids(left)
        exits = {name: reap(pid) for name, (pid, _) in nodes.items()}
        result['exits'] = exits
        for name, how in exits.items():
            if how is not None and how != 'exit 0' and result['ends'].get(name) is not None:
                result['failures'].append(f'{name} ended with {how}')
        if left:
            result['left_over'] = left
            result['failures'].append(f'{len(left)} processes of the run left (killed): {left}')
    if args.record:
        result['bag'] = _bag_check(bag)
        if not result['bag']['metadata']:
            result['failures'].append(f'no {os.path.join(bag, "metadata.yaml")} after the kill')
    return result


def machine_info() -> Dict[str, Any]:
    """Describe the machine the benchmark runs on."""
    memory = None
    try:
        with open('/proc/meminfo', encoding='ascii') as stream:
            memory = int(stream.readline().split()[1]) / 1024.0 ** 2
    except (OSError, IndexError, ValueError):
        pass
    return {'machine': platform.machine(), 'cores': os.cpu_count(),
            'memory_gib': None if memory is None else round(memory, 1),
            'python': platform.python_version(), 'platform': platform.platform()}


def main(argv: Optional[Sequence[str]] = None) -> int:
    """Run the benchmark; return the exit code."""
    args = parse_args(argv)
    num_robots = int(load_params_file(args.params)['num_robots'])
    names = expected_nodes(num_robots, args.record)
    os.makedirs(args.out)
    domain = random.randint(1, 101)
    env = dict(os.environ, ROS_DOMAIN_ID=str(domain), ROS_AUTOMATIC_DISCOVERY_RANGE='LOCALHOST')
    env['PATH'] = os.pathsep.join([os.path.dirname(sys.executable), env.get('PATH', '')])
    machine = machine_info()
    recorded = ', recorded' if args.record else ''
    print(f'orphans: {args.runs} runs of {os.path.basename(args.params)} ({len(names)} nodes'
          f'{recorded}), {args.busy} busy loops, ROS domain {domain}; '
          f"{machine['machine']}, {machine['cores']} cores; output in {args.out}",
          flush=True)
    load_start = list(os.getloadavg())
    runs: List[Dict[str, Any]] = []
    previous = signal.signal(signal.SIGTERM, _terminate)
    subreaper = become_subreaper()
    loops = start_busy(args.busy)
    try:
        for number in range(1, args.runs + 1):
            run = one_run(number, args, names, env)
            runs.append(run)
            ends = [t for t in run['ends'].values() if t is not None]
            print(f"run {number}: slowest {max(ends) if ends else float('nan'):.3f} s of "
                  f"{len(ends)} node ends; load {run.get('load_at_kill', [float('nan')])[0]:.1f}"
                  + ''.join(f'; FAILED: {text}' for text in run['failures']), flush=True)
    finally:
        stop_busy(loops)
        signal.signal(signal.SIGTERM, previous)
    summary = summarise_runs(runs, args.limit)
    result = {
        'date': datetime.datetime.now().isoformat(timespec='seconds'), 'machine': machine,
        'load_average_start': load_start, 'load_average_end': list(os.getloadavg()),
        'params': args.params, 'prefix': args.prefix, 'record': args.record,
        'busy_loops': args.busy, 'hold_s': args.hold, 'poll_s': POLL, 'ros_domain_id': domain,
        'nodes': names, 'subreaper': subreaper, 'summary': summary, 'runs': runs,
    }
    write_json(args.json, result)
    print(format_table(runs, names))
    if summary['max_s'] is not None:
        print(f"orphans: {summary['node_ends']} node ends in {len(runs)} runs: max "
              f"{summary['max_s']:.3f} s, median {summary['median_s']:.3f} s; over "
              f"{args.limit:g} s: {summary['over_limit']}; failures: {summary['failures']}")
    else:
        print(f"orphans: no node end measured; failures: {summary['failures']}")
    exits = collections.Counter(str(how) for run in runs for how in run.get('exits', {}).values())
    ended = ', '.join(f'{how} x{count}' for how, count in sorted(exits.items()))
    print(f'orphans: how the nodes ended: {ended}')
    print(f'orphans: load average (1, 5, 15 min) at the start {load_start[0]:.2f} '
          f'{load_start[1]:.2f} {load_start[2]:.2f}, at the end '
          f"{' '.join(f'{v:.2f}' for v in result['load_average_end'])}; wrote {args.json}")
    return 0 if summary['over_limit'] == 0 and summary['failures'] == 0 else 1


if __name__ == '__main__':
    sys.exit(main())
