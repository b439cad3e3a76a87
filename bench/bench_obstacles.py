# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
Obstacles offline (issue 36): the cost among pillars and a sweep (on demand, not in CI).

Usage: python bench/bench_obstacles.py [--cost-sizes 1000] [--pillars 100] [--repeats 3]
[--sweep] [--out DIR]

Cost: for each N, the whole ``formation_sim PARAMS --out DIR --dt 0.01 --sample-dt 0.1
--no-plots --quiet`` command as a child process (as a user runs it), wall time and its CPU
time (user plus system: what other work on the machine does not stretch), with and
without ``--pillars`` pillars: Section 5 constants (``bench_core.params_for``: random start at
about 10 robots per m^2, lattice goal 2 m apart, 20 s), pillars of radius 0.2 m at the centres
of the goal lattice's cells (1.41 m from the nearest places) outside the start disc, b_o = 0.5 m.

Sweep (``--sweep``): Section 5's ten robots (config/paper_section5.yaml) stabilising among a
random pillar field, for each b_o, gain c and number of pillars in a 20 m square around the
team, a few seeds each, RK45: settle time, closest approach to a robot and to an obstacle,
obstacle contacts, stuck robots. Prints Markdown tables and writes OUT/obstacles.json.
"""

import argparse
import json
import math
import os
import resource
import subprocess
import sys
import tempfile
import time

BENCH = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(BENCH)
sys.path[:0] = [ROOT, BENCH]

from bench_core import params_for  # noqa: E402
from formation_ros.core.settings.params import validate  # noqa: E402, I100
from formation_ros.core.settings.params_file import load_params_file  # noqa: E402
from formation_ros.core.settings.params_file import write_params_file  # noqa: E402
from formation_ros.simulation.simulate import run_metrics, simulate  # noqa: E402
import numpy as np  # noqa: E402

PILLAR_RADIUS = 0.2
CLEARANCE = 0.5


def lattice_pillars(params, count):
    """Return ``count`` pillars (flat x, y, r) at goal-lattice cell centres outside the start."""
    places = np.array(params['formation.vertices']).reshape(-1, 2)
    start_reach = params['start.random_radius'] + PILLAR_RADIUS + CLEARANCE + 0.2
    centres = np.unique(np.round(places + 1.0, 9), axis=0)
    far = np.linalg.norm(centres, axis=1) > start_reach
    centres = centres[far]
    inside = np.all(centres < places.max(axis=0), axis=1)
    centres = centres[inside]
    pick = np.linspace(0, len(centres) - 1, min(count, len(centres))).astype(int)
    return [float(v) for x, y in centres[pick] for v in (x, y, PILLAR_RADIUS)]


def run_command(params, dt=0.01, sample_dt=0.1):
    """Run formation_sim on ``params`` as a child process; return (wall s, CPU s, metrics)."""
    with tempfile.TemporaryDirectory() as folder:
        path = os.path.join(folder, 'params.yaml')
        write_params_file(path, params)
        out = os.path.join(folder, 'run')
        command = [sys.executable, '-m', 'formation_ros.tools.sim', path, '--out', out,
                   '--dt', f'{dt:g}', '--sample-dt', f'{sample_dt:g}', '--no-plots', '--quiet']
        used = _child_cpu()
        begun = time.perf_counter()
        subprocess.run(command, check=True, cwd=ROOT, stdout=subprocess.DEVNULL,
                       env={**os.environ, 'PYTHONPATH': ROOT})
        wall = time.perf_counter() - begun
        cpu = _child_cpu() - used
        with open(os.path.join(out, 'metrics.json'), encoding='utf-8') as stream:
            return wall, cpu, json.load(stream)


def _child_cpu():
    """Return the user plus system CPU seconds of the children waited for so far."""
    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    return usage.ru_utime + usage.ru_stime


def cost(sizes, pillars, repeats):
    """Return the rows of the cost table: N, pillars, wall and CPU times, contacts, clearance."""
    rows = []
    for n in sizes:
        base = params_for(n)
        for count in (0, pillars):
            params = dict(base)
            if count:
                params.update({'obstacles.circles': lattice_pillars(base, count),
                               'obstacles.clearance': CLEARANCE})
            walls, cpus, metrics = [], [], {}
            for _ in range(repeats):
                wall, cpu, metrics = run_command(params)
                walls.append(wall)
                cpus.append(cpu)
            placed = len(params.get('obstacles.circles', ())) // 3
            rows.append({'robots': n, 'pillars': placed, 'walls': walls, 'cpu': cpus,
                         'obstacle_contacts': metrics.get('obstacle_contacts'),
                         'min_obstacle_clearance': metrics.get('min_obstacle_clearance'),
                         'settle_time': metrics.get('settle_time')})
            print(f'| {n} | {placed} | ' + ', '.join(f'{w:.2f}' for w in walls) + ' | '
                  + ', '.join(f'{c:.2f}' for c in cpus)
                  + f" | {metrics.get('obstacle_contacts')} | "
                  f"{_number(metrics.get('min_obstacle_clearance'))} |", flush=True)
    return rows


def field(raw, count, seed, clearance, radius=0.3):
    """Add ``count`` random pillars in a 20 m square to Section 5, off starts and places."""
    rng = np.random.default_rng(seed)
    config = validate(raw)
    keep_off = np.vstack([config.start, config.vertices])
    pillars, tries = [], 0
    while len(pillars) < 3 * count and tries < 100_000:
        tries += 1
        centre = rng.uniform(-10.0, 10.0, 2)
        if np.min(np.linalg.norm(keep_off - centre, axis=1)) > radius + clearance + 0.05:
            pillars += [float(centre[0]), float(centre[1]), radius]
    return {**raw, 'obstacles.circles': pillars, 'obstacles.clearance': clearance}


def sweep(seeds=3):
    """Return the rows of the sweep: b_o, gain and pillar density, RK45, Section 5's team."""
    base = load_params_file(os.path.join(ROOT, 'config', 'paper_section5.yaml'))
    cases = ([('b_o', b, {'obstacles.clearance': b}, 20) for b in (0.25, 0.5, 1.0, 2.0)]
             + [('gain', c, {'controller.gain': c}, 20) for c in (0.5, 2.0, 8.0)]
             + [('pillars', k, {}, k) for k in (10, 20, 40, 80)])
    rows = []
    for name, value, change, count in cases:
        for seed in range(seeds):
            raw = {**base, **change}
            raw = field(raw, count, seed, raw.get('obstacles.clearance', CLEARANCE))
            config = validate(raw)
            metrics = run_metrics(simulate(config), config, 'RK45')
            row = {'swept': name, 'value': value, 'seed': seed, 'pillars': count,
                   'settle_time': metrics['settle_time'],
                   'min_pair_distance': metrics['min_pair_distance'],
                   'min_obstacle_clearance': metrics['min_obstacle_clearance'],
                   'obstacle_contacts': metrics['obstacle_contacts'],
                   'stuck': [robot['robot'] for robot in metrics['stuck_robots']]}
            rows.append(row)
            print(f"| {name} = {value:g} | {seed} | {_number(row['settle_time'])} | "
                  f"{row['min_pair_distance']:.3f} | {row['min_obstacle_clearance']:.3f} | "
                  f"{row['obstacle_contacts']} | {row['stuck'] or '-'} |", flush=True)
    return rows


def _number(value):
    return '-' if value is None or (isinstance(value, float) and math.isnan(value)) \
        else f'{value:.3g}'


def build_parser():
    """Command-line interface of bench_obstacles."""
    parser = argparse.ArgumentParser(
        prog='bench_obstacles.py',
        description='Obstacles offline: formation_sim among pillars, and a sweep of b_o, gain '
                    'and pillar density.')
    parser.add_argument('--cost-sizes', type=int, nargs='*', default=[1000],
                        help='team sizes N of the cost table (default 1000; none: no table)')
    parser.add_argument('--pillars', type=int, default=100,
                        help='pillars of the cost table, at goal-lattice cell centres outside '
                             'the start (default 100)')
    parser.add_argument('--repeats', type=int, default=3,
                        help='runs of each command (default 3)')
    parser.add_argument('--sweep', action='store_true',
                        help="also sweep b_o, gain and pillar density with Section 5's team "
                             '(RK45)')
    parser.add_argument('--seeds', type=int, default=3,
                        help='random pillar fields of each sweep value (default 3)')
    parser.add_argument('--out', default=os.path.join(ROOT, 'docs', 'bench'),
                        help='where to write obstacles.json (default docs/bench)')
    return parser


def main(argv=None):
    """Run the benchmark; print its tables and write OUT/obstacles.json."""
    args = build_parser().parse_args(argv)
    result = {'machine': os.uname().machine, 'cpus': os.cpu_count(),
              'load': os.getloadavg()}
    print('| N | pillars | wall time of formation_sim (s) | its CPU time (s) | contacts | '
          'closest approach (m) |')
    print('|---:|---:|---|---|---:|---:|')
    result['cost'] = cost(args.cost_sizes, args.pillars, args.repeats)
    if args.sweep:
        print('\n| swept | seed | settle (s) | closest pair (m) | closest to an obstacle (m) '
              '| contacts | stuck robots |')
        print('|---|---:|---:|---:|---:|---:|---|')
        result['sweep'] = sweep(args.seeds)
    os.makedirs(args.out, exist_ok=True)
    with open(os.path.join(args.out, 'obstacles.json'), 'w', encoding='utf-8') as stream:
        json.dump(result, stream, indent=2)
        stream.write('\n')


if __name__ == '__main__':
    main()
