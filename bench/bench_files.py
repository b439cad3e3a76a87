# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
Hostile parameters files: how long each program takes to refuse them, and its peak memory.

Usage: python bench/bench_files.py [--before DIR] [--programs guard sim plant] [--timeout 60]
[--cap-mb 1500] [--json docs/bench/files.json]

Each case (the files of test/integration/test_faults_files.py, and a 10,000-robot 3D file that
must pass) is given, in a fresh child process, to: ``guard`` (load_params_file alone, timed
in-process after the imports), ``sim`` (``python -m formation_ros.tools.sim FILE --check``)
and ``plant`` (``python -m formation_ros.nodes.plant --ros-args --params-file FILE``, on a
localhost-only domain). The child's wall time and peak resident memory (VmHWM, read from /proc
every 20 ms) are recorded; a child past --cap-mb or --timeout is killed and recorded so.
``--before DIR`` also runs another source tree (e.g. the commit before the guard, unpacked with
``git archive 9aa2501 | tar -x -C DIR``) with this interpreter. Writes the table as JSON (and
prints it). The valid file is not given to the plant (it would start a run).
"""

import argparse
import datetime
import itertools
import json
import os
import platform
import subprocess
import sys
import tempfile
import time
from typing import Any, Callable, Dict, List, Optional, Sequence

BENCH = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(BENCH)
SQUARE = os.path.join(ROOT, 'config', 'square_4.yaml')
PROGRAMS = ('guard', 'sim', 'plant')
PLANT = 'import sys; from formation_ros.nodes.plant import main; sys.exit(main())'
GUARD = """
import resource, sys, time
from formation_ros.core.settings.declarations import ParamError
from formation_ros.core.settings.params_file import load_params_file
start = time.perf_counter()
try:
    load_params_file(sys.argv[1])
    outcome = 'read'
except ParamError as exc:
    outcome = str(exc).splitlines()[0]
print(f'{time.perf_counter() - start:.4f} {outcome}', file=sys.stderr)
"""


def square_text() -> str:
    """Return the text of config/square_4.yaml."""
    with open(SQUARE, encoding='utf-8') as stream:
        return stream.read()


def with_vertices(values: str) -> str:
    """Return the square's file with ``formation.vertices`` replaced by ``values`` (YAML)."""
    text = square_text()
    start = text.index('      vertices: ')
    end = text.index('\n', start)
    return text[:start] + '      vertices: ' + values + text[end:]


def laughs() -> str:
    """Return the square's file with aliased mappings (10^9 names) under an unknown key."""
    keys = 'abcdefghij'
    lines = ['    lol:', '      l0: &l0 {' + ', '.join(f'{key}: lol' for key in keys) + '}']
    lines += [f'      l{k}: &l{k} {{' + ', '.join(f'{key}: *l{k - 1}' for key in keys) + '}'
              for k in range(1, 9)]
    return square_text() + '\n'.join(lines) + '\n'


def big_team() -> str:
    """Return a valid 10,000-robot 3D file as write_params_file writes it."""
    sys.path.insert(0, ROOT)
    import numpy as np
    from formation_ros.core.settings.params_file import dump_params_text
    rng = np.random.default_rng(1)
    n = 10_000
    lattice = 1.5 * np.indices((22, 22, 21)).reshape(3, -1).T[:n]
    return dump_params_text({
        'num_robots': n, 'dim': 3, 'sensing_radius': 2.0, 'repulsion_radius': 0.5,
        'formation.vertices': lattice.ravel().tolist(),
        'start.positions': (lattice + rng.uniform(-0.3, 0.3, size=lattice.shape)).ravel().tolist(),
        'sensing_radii': rng.uniform(1.0, 2.0, size=n).tolist(),
        'relay.source_names': [f'turtle_{i}' for i in range(n)], 'duration': 1.0})


CASES: Dict[str, Callable[[], str]] = {
    'expanding aliases (billion laughs, unknown key)': laughs,
    'two million vertex values (6 MB, flow list)':
        lambda: with_vertices('[' + ', '.join(['0.'] * 2_000_000) + ']'),
    'two million vertex values (27 MB, one per line)':
        lambda: with_vertices('\n' + '        - 0.0\n' * 2_000_000),
    'nesting 100,000 deep': lambda: square_text() + '    junk: ' + '[' * 100_000
    + ']' * 100_000 + '\n',
    'an anchor in a fine file': lambda: square_text().replace(
        'repulsion_radius: 1.0', 'repulsion_radius: &one 1.0').replace('kappa: 1.0',
                                                                       'kappa: *one'),
    'a list as a key': lambda: square_text().replace('    duration: 10.0\n',
                                                     '    [duration]: 10.0\n'),
    'valid: 10,000 robots in 3D': big_team,
}


def build_parser() -> argparse.ArgumentParser:
    """Command line of the benchmark."""
    parser = argparse.ArgumentParser(prog='bench_files.py',
                                     description=__doc__.split('\n\n')[1].strip())
    parser.add_argument('--before', help='another source tree to run too (before the guard)')
    parser.add_argument('--programs', nargs='+', choices=PROGRAMS, default=list(PROGRAMS))
    parser.add_argument('--timeout', type=float, default=60.0,
                        help='seconds before a child is killed (default %(default)g)')
    parser.add_argument('--cap-mb', type=float, default=1500.0,
                        help='resident MB at which a child is killed (default %(default)g)')
    parser.add_argument('--json', default=os.path.join(ROOT, 'docs', 'bench', 'files.json'),
                        help='where to write the results (default: %(default)s)')
    return parser


def vm_hwm_mb(pid: int) -> Optional[float]:
    """Return the peak resident memory of process ``pid`` in MB (None once it is gone)."""
    try:
        with open(f'/proc/{pid}/status', encoding='ascii') as stream:
            for line in stream:
                if line.startswith('VmHWM:'):
                    return int(line.split()[1]) / 1024
    except (OSError, ValueError):
        return None
    return None


def measure(command: List[str], env: Dict[str, str], timeout: float,
            cap_mb: float) -> Dict[str, Any]:
    """Run ``command``; return its exit code, wall time, peak memory and first stderr line."""
    with tempfile.TemporaryFile('w+') as errors:
        start = time.monotonic()
        child = subprocess.Popen(command, env=env, stdout=subprocess.DEVNULL, stderr=errors,
                                 text=True)
        peak, killed = 0.0, ''
        while child.poll() is None:
            peak = max(peak, vm_hwm_mb(child.pid) or 0.0)
            elapsed = time.monotonic() - start
            if peak > cap_mb or elapsed > timeout:
                killed = f'killed at {peak:.0f} MB' if peak > cap_mb else f'killed after ' \
                    f'{timeout:g} s'
                child.kill()
                child.wait()
                break
            time.sleep(0.02)
        seconds = time.monotonic() - start
        errors.seek(0)
        lines = [line for line in errors.read().splitlines() if line.strip()]
    return {'code': child.returncode, 'seconds': round(seconds, 2), 'peak_mb': round(peak),
            'killed': killed, 'stderr_lines': len(lines),
            'first_line': (lines[0][:240] if lines else '')}


def command_of(program: str, path: str) -> List[str]:
    """Return the command line that gives ``path`` to ``program``."""
    if program == 'guard':
        return [sys.executable, '-c', GUARD, path]
    if program == 'sim':
        return [sys.executable, '-m', 'formation_ros.tools.sim', path, '--check']
    return [sys.executable, '-c', PLANT, '--ros-args', '--params-file', path]


def main(argv: Optional[Sequence[str]] = None) -> int:
    """Run every case through every program; print and write the results."""
    args = build_parser().parse_args(argv)
    trees = [('after', ROOT)] + ([('before', os.path.abspath(args.before))] if args.before else [])
    results: List[Dict[str, Any]] = []
    with tempfile.TemporaryDirectory() as folder:
        for case, make in CASES.items():
            path = os.path.join(folder, 'robots.yaml')
            with open(path, 'w', encoding='utf-8') as stream:
                stream.write(make())
            size = os.path.getsize(path)
            programs = [p for p in args.programs if not (case.startswith('valid') and
                                                         p == 'plant')]
            for (version, tree), program in itertools.product(trees, programs):
                env = dict(os.environ, PYTHONPATH=tree, PYTHONUNBUFFERED='1',
                           ROS_AUTOMATIC_DISCOVERY_RANGE='LOCALHOST')
                row = {'case': case, 'bytes': size, 'version': version, 'program': program,
                       **measure(command_of(program, path), env, args.timeout, args.cap_mb)}
                if program == 'guard' and row['first_line'].split(' ')[0].count('.') == 1:
                    row['in_process_s'] = float(row['first_line'].split(' ')[0])
                results.append(row)
                print(f"{case[:44]:44s} {version:6s} {program:5s} exit {row['code']!s:>4} "
                      f"{row['seconds']:6.2f} s {row['peak_mb']:5.0f} MB {row['killed']} "
                      f"| {row['first_line'][:100]}", flush=True)
    report = {'date': datetime.datetime.now().isoformat(timespec='seconds'),
              'trees': dict(trees), 'machine': platform.platform(),
              'cpus': os.cpu_count(), 'load_average': os.getloadavg(),
              'python': platform.python_version(), 'results': results}
    os.makedirs(os.path.dirname(os.path.abspath(args.json)), exist_ok=True)
    with open(args.json, 'w', encoding='utf-8') as stream:
        json.dump(report, stream, indent=1)
        stream.write('\n')
    return 0


if __name__ == '__main__':
    sys.exit(main())
