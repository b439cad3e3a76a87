# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
Robots on their scanners: where avoiding what they see ends (issue 37, on demand, not in CI).

Usage: python bench/bench_scan.py [--duration 75] [--cases NAME ...] [--prefix INSTALL]
[--out docs/bench/scan.json]

Each case is one run of ``scripts/launch_formation.sh ROBOTS.yaml --world --world-params
WORLD.yaml --out DIR --duration S --no-plots``: the robots' file is
config/world_turtlebot3_scan.yaml (``obstacles.source: scan``; the map baseline:
config/world_turtlebot3_obstacles.yaml, told obstacles), the world's a temporary copy of
config/world_turtlebot3_chair.yaml (one more pillar, the chair, that no robot file maps) with
the case's ``world.*`` changed: the scan rate, the noise, the rays, a thin chair. A case may
also change the robots' file (``input_timeout``, against a slow scanner). It reads the world's
DIR/world_stats.json (contacts with obstacles and between bodies, closest gaps, simulated time)
and the report's DIR/metrics.json (settle time, stuck robots; its obstacle figures count only
the obstacles the robots' file lists, so the chair is the world's), counts the robots'
"holding still" lines in the launcher's output, reads from DIR/trajectory.npz the closest any
footprint came to the chair, which robots end at their places and how often each moves, prints a
Markdown row per case and writes every row so far into OUT (after each run; ``--append`` adds
to OUT's rows, ``--table`` prints OUT's). The runs use the caller's ROS_DOMAIN_ID.
"""

import argparse
import datetime
import json
import math
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

from bench_soak import write_json  # noqa: E402
from formation_ros.core.settings.params_file import (load_params_file,  # noqa: E402, I100
                                                     write_params_file)
import numpy as np  # noqa: E402, I201

LAUNCHER = os.path.join(ROOT, 'scripts', 'launch_formation.sh')
SCAN_ROBOTS = os.path.join(ROOT, 'config', 'world_turtlebot3_scan.yaml')
MAP_ROBOTS = os.path.join(ROOT, 'config', 'world_turtlebot3_obstacles.yaml')
CHAIR_WORLD = os.path.join(ROOT, 'config', 'world_turtlebot3_chair.yaml')
CHAIR = 2
"""Index of the chair among the world file's obstacles.circles (x, y, r triples)."""
SETTLE = 0.05
"""A robot is at its place when its hand point is this near it, m (the report's tolerance)."""
MOVING = 0.01
"""A body moves when its centre is faster than this, m/s."""
SPARE = 180.0
"""Wall seconds a run may take beyond --duration (start-up, report) before it counts as hung."""

CASES: List[Dict[str, Any]] = [
    {'name': 'map', 'robots': MAP_ROBOTS, 'world': {}, 'note': 'told obstacles (no chair)'},
    {'name': 'map_chair', 'robots': MAP_ROBOTS, 'world': {}, 'chair_mapped': True,
     'note': "told obstacles, the chair on the robots' map too"},
    {'name': 'default', 'world': {}, 'note': '5 Hz, 360 rays, noise 0'},
    {'name': 'no_chair', 'world': {}, 'no_chair': True, 'note': 'the world without the chair'},
    {'name': 'thin_360', 'world': {}, 'chair_radius': 0.02, 'note': 'chair r 0.02 m'},
    {'name': 'thin_36', 'world': {'world.scan_rays': 36}, 'chair_radius': 0.02,
     'note': 'chair r 0.02 m, 36 rays'},
    {'name': 'rays_90', 'world': {'world.scan_rays': 90}},
    {'name': 'rays_36', 'world': {'world.scan_rays': 36}},
    {'name': 'rays_12', 'world': {'world.scan_rays': 12}},
    {'name': 'rate_2', 'world': {'world.scan_rate': 2.0}},
    {'name': 'rate_1', 'world': {'world.scan_rate': 1.0}},
    {'name': 'rate_0.5', 'world': {'world.scan_rate': 0.5}},
    {'name': 'noise_0.02', 'world': {'world.scan_noise': 0.02}},
    {'name': 'noise_0.05', 'world': {'world.scan_noise': 0.05}},
    {'name': 'noise_0.1', 'world': {'world.scan_noise': 0.1}},
    {'name': 'rate_1_timeout_3', 'world': {'world.scan_rate': 1.0},
     'robot': {'input_timeout': 3.0}, 'note': 'input_timeout 3 s'},
    {'name': 'rate_0.5_timeout_5', 'world': {'world.scan_rate': 0.5},
     'robot': {'input_timeout': 5.0}, 'note': 'input_timeout 5 s'},
]
HEADER = ('| case | robots | world changed | contacts with obstacles (first: robot, obstacle, '
          'simulated s) | closest footprint to an obstacle (m) | closest footprint to the '
          'chair (m; robot, simulated s) | robot contacts | '
          'closest bodies (m) | settle (s) | '
          'stuck robots | robots at their place at the end | share of time moving | '
          '"holding still" lines | simulated (s) at x real time |\n'
          '|---|---|---|---:|---:|---|---:|---:|---:|---|---|---:|---:|---|')


def build_parser() -> argparse.ArgumentParser:
    """Return the command line parser."""
    parser = argparse.ArgumentParser(
        prog='bench_scan.py',
        description='Robots on their scanners around an unmapped chair: one world run per '
                    'scan rate, noise, ray count and chair width; writes a table.')
    parser.add_argument('--duration', type=float, default=75.0,
                        help='wall seconds of each run (default 75: the world starts the '
                             'robots about 10 s of simulated time in and may run slower than '
                             'real time on a busy machine)')
    parser.add_argument('--cases', nargs='*', metavar='NAME',
                        choices=[case['name'] for case in CASES],
                        help='run only these cases (default: all, in the order listed)')
    parser.add_argument('--prefix', default=os.path.join(ROOT, 'install', 'formation_ros'),
                        help='install space of formation_ros (default ./install/formation_ros)')
    parser.add_argument('--out', default=os.path.join(ROOT, 'docs', 'bench', 'scan.json'),
                        help='JSON file of the rows (default docs/bench/scan.json)')
    parser.add_argument('--append', action='store_true',
                        help="add the rows to OUT's (default: OUT holds this run's rows only)")
    parser.add_argument('--table', action='store_true',
                        help="print OUT's rows as the Markdown table and run nothing; figures "
                             'a row lacks are read from its kept run and written into OUT')
    parser.add_argument('--keep', help='keep the run directories under this folder')
    return parser


def world_values(case: Dict[str, Any]) -> Dict[str, Any]:
    """Return the chair world's flat parameters with the case's ``world.*`` and chair changed."""
    values = load_params_file(CHAIR_WORLD)
    values.update(case['world'])
    if 'chair_radius' in case:
        circles = list(values['obstacles.circles'])
        circles[3 * CHAIR + 2] = case['chair_radius']
        values['obstacles.circles'] = circles
    if case.get('no_chair'):
        circles = list(values['obstacles.circles'])
        values['obstacles.circles'] = circles[:3 * CHAIR] + circles[3 * CHAIR + 3:]
    return values


def run_case(case: Dict[str, Any], folder: str, duration: float,
             prefix: str) -> Dict[str, Any]:
    """Run one case in ``folder``; return its row (the figures, the command, the exit code)."""
    world = os.path.join(folder, 'world.yaml')
    write_params_file(world, world_values(case))
    robots = case.get('robots', SCAN_ROBOTS)
    if case.get('robot') or case.get('chair_mapped'):
        values = load_params_file(robots)
        values.update(case.get('robot', {}))
        if case.get('chair_mapped'):
            values['obstacles.circles'] = world_values(case)['obstacles.circles']
        robots = os.path.join(folder, 'robots.yaml')
        write_params_file(robots, values)
    out = os.path.join(folder, 'run')
    command = ['bash', LAUNCHER, robots, '--world', '--world-params', world, '--out', out,
               '--duration', f'{duration:g}', '--no-plots', '--prefix', prefix]
    chair = {'chair_radius': case['chair_radius']} if 'chair_radius' in case else {}
    load_before = os.getloadavg()
    begun = time.monotonic()
    with open(os.path.join(folder, 'launcher.log'), 'wb') as log:
        try:
            code: Optional[int] = subprocess.run(command, stdout=log, stderr=subprocess.STDOUT,
                                                 timeout=duration + SPARE).returncode
        except subprocess.TimeoutExpired:
            code = None
    wall = time.monotonic() - begun
    with open(os.path.join(folder, 'launcher.log'), encoding='utf-8', errors='replace') as log:
        lines = log.read().splitlines()
    row: Dict[str, Any] = {
        'case': case['name'],
        'robots_file': os.path.relpath(case.get('robots', SCAN_ROBOTS), ROOT),
        'source': 'map' if case.get('robots') == MAP_ROBOTS else 'scan',
        'world_changes': dict(case['world'], **chair),
        'robot_changes': case.get('robot', {}),
        'chair_mapped': bool(case.get('chair_mapped')),
        'no_chair': bool(case.get('no_chair')), 'note': case.get('note', ''),
        'exit_code': code, 'wall_s': wall, 'load_before': load_before,
        'load_after': os.getloadavg(),
        'holding_still_lines': sum('holding still' in line for line in lines),
        'publishing_zero_lines': sum('publishing zero' in line for line in lines),
        'command': ' '.join(command)}
    row.update(_world_stats(out))
    row.update(_metrics(out))
    row.update(trajectory_figures(out))
    if not case.get('no_chair'):
        row.update(chair_gap(out, _chair_circle(case)))
    return row


def trajectory_figures(out: str) -> Dict[str, Any]:
    """
    Return, from OUT/trajectory.npz, which robots end at their places and how often each moves.

    at_place: the robots (1-based) whose hand point is within SETTLE m of its place at the
    last sample; moving_share: (N,) the share of samples at which each body's centre moves
    faster than MOVING m/s (a robot held still by a stale scan does not).
    """
    try:
        with np.load(os.path.join(out, 'trajectory.npz')) as data:
            hands, places = data['q'], data['q_desired']
            bodies, times = data['q_body'], data['t']
    except (OSError, KeyError, ValueError):
        return {'at_place': None}
    errors = np.linalg.norm(hands[-1] - places[-1], axis=1)
    speeds = np.linalg.norm(np.diff(bodies, axis=0), axis=2) / np.diff(times)[:, None]
    return {'at_place': [int(k) + 1 for k in np.flatnonzero(errors <= SETTLE)],
            'moving_share': (speeds > MOVING).mean(axis=0).tolist()}


def chair_gap(out: str, chair: Sequence[float]) -> Dict[str, Any]:
    """
    Return the closest any body's footprint came to the chair, from OUT/trajectory.npz.

    chair: (x, y, r) m. The gap is the distance of a body's centre (q_body) to the chair's
    surface less body.radius, m (negative: overlap), at the trajectory's samples; with the
    robot and the simulated time (s) of the closest sample.
    """
    try:
        with np.load(os.path.join(out, 'trajectory.npz')) as data:
            bodies, times = data['q_body'], data['t']
    except (OSError, KeyError, ValueError):
        return {'chair_gap': None}
    radius = load_params_file(SCAN_ROBOTS)['body.radius']
    gaps = np.linalg.norm(bodies - np.asarray(chair[:2]), axis=2) - chair[2] - radius
    sample, robot = np.unravel_index(int(np.argmin(gaps)), gaps.shape)
    return {'chair_gap': float(gaps[sample, robot]), 'chair_gap_robot': int(robot) + 1,
            'chair_gap_time': float(times[sample])}


def _load(path: str) -> Optional[Dict[str, Any]]:
    try:
        with open(path, encoding='utf-8') as stream:
            loaded: Dict[str, Any] = json.load(stream)
    except (OSError, ValueError):
        return None
    return loaded


def _world_stats(out: str) -> Dict[str, Any]:
    stats = _load(os.path.join(out, 'world_stats.json'))
    if stats is None:
        return {'world_stats': None}
    events = stats.get('obstacle_contact_events') or []
    return {'obstacle_contacts': stats['obstacle_contacts'],
            'min_obstacle_gap': stats['min_obstacle_gap'],
            'obstacle_contact_events': events,
            'contacts': stats['contacts'], 'min_body_distance': stats['min_body_distance'],
            'simulated_time': stats['simulated_time'],
            'simulated_time_let_go': stats.get('simulated_time_let_go'),
            'achieved_realtime_factor': stats['achieved_realtime_factor']}


def _metrics(out: str) -> Dict[str, Any]:
    metrics = _load(os.path.join(out, 'metrics.json'))
    if metrics is None:
        return {'metrics': None}
    return {'settle_time': metrics['settle_time'],
            'final_max_error': metrics['final_max_error'],
            'stuck_robots': metrics['stuck_robots'],
            'min_mapped_obstacle_clearance': metrics.get('min_obstacle_clearance'),
            'max_abs_v': metrics.get('max_abs_v')}


def _first_contact(events: List[Any]) -> str:
    timed = [event for event in events if isinstance(event, dict) and 't' in event]
    if not timed:
        return ''
    first = min(timed, key=lambda event: event['t'])
    return f" (robot {first['robot']}, {first['obstacle']}, {first['t']:.1f} s)"


def refreshed(row: Dict[str, Any]) -> Dict[str, Any]:
    """Return the row with its chair gap read from its kept run if it has none yet."""
    if not os.path.isdir(row.get('folder', '')):
        return row
    out = os.path.join(row['folder'], 'run')
    case = next(case for case in CASES if case['name'] == row['case'])
    row = dict(row)
    if 'at_place' not in row:
        row.update(trajectory_figures(out))
    if 'chair_gap' not in row and not case.get('no_chair'):
        row.update(chair_gap(out, _chair_circle(case)))
    return row


def _chair_circle(case: Dict[str, Any]) -> List[float]:
    circles = world_values(case)['obstacles.circles']
    return list(circles[3 * CHAIR:3 * CHAIR + 3])


def _chair(row: Dict[str, Any]) -> str:
    if row.get('chair_gap') is None:
        return '-'
    return (f"{row['chair_gap']:.3f} (robot {row['chair_gap_robot']}, "
            f"{row['chair_gap_time']:.1f})")


def _robots(robots: Optional[List[int]]) -> str:
    if robots is None:
        return '?'
    return ', '.join(str(robot) for robot in robots) or 'none'


def _share(shares: Optional[List[float]]) -> str:
    return '?' if shares is None else f'{100 * float(np.mean(shares)):.0f} %'


def _number(value: Any, digits: int = 3) -> str:
    if value is None or (isinstance(value, float) and math.isnan(value)):
        return '-'
    return f'{value:.{digits}f}'


def markdown_row(row: Dict[str, Any]) -> str:
    """Return the Markdown table row of one case."""
    changes = dict(row['world_changes'], **row['robot_changes'])
    changed = ', '.join(f'{name.replace("world.", "")} {value:g}'
                        for name, value in changes.items())
    changed = changed or ('no chair' if row.get('no_chair') else '-')
    robots = row.get('source') or ('map' if 'obstacles' in row['robots_file'] else 'scan')
    if row.get('chair_mapped'):
        robots = 'map with the chair'
    if row.get('world_stats', 0) is None:
        return f"| {row['case']} | {robots} | {changed} | no world_stats.json (exit " \
               f"{row['exit_code']}) |"
    stuck = ', '.join(str(robot['robot']) for robot in row.get('stuck_robots') or []) or '-'
    settle = row.get('settle_time')
    return (f"| {row['case']} | {robots} | {changed} | {row['obstacle_contacts']}"
            f"{_first_contact(row['obstacle_contact_events'])} | "
            f"{_number(row['min_obstacle_gap'])} | {_chair(row)} | {row['contacts']} | "
            f"{_number(row['min_body_distance'])} | "
            f"{'not settled' if settle is None else _number(settle, 1)} | {stuck} | "
            f"{_robots(row.get('at_place'))} | {_share(row.get('moving_share'))} | "
            f"{row['holding_still_lines']} | {row['simulated_time']:.1f} at "
            f"{row['achieved_realtime_factor']:.2f} |")


def main(argv: Optional[Sequence[str]] = None) -> int:
    """Run the cases one after another; print a row each and write OUT after each."""
    args = build_parser().parse_args(argv)
    chosen = [case for case in CASES if not args.cases or case['name'] in args.cases]
    result: Dict[str, Any] = {
        'machine': platform.machine(), 'cpus': os.cpu_count(),
        'date': datetime.date.today().isoformat(), 'duration_wall_s': args.duration,
        'ros_domain_id': os.environ.get('ROS_DOMAIN_ID'), 'rows': []}
    if args.append and os.path.exists(args.out):
        with open(args.out, encoding='utf-8') as stream:
            result['rows'] = [refreshed(row) for row in json.load(stream)['rows']]
    print(HEADER, flush=True)
    if args.table:
        with open(args.out, encoding='utf-8') as stream:
            kept = json.load(stream)
        kept['rows'] = [refreshed(row) for row in kept['rows']]
        for row in kept['rows']:
            print(markdown_row(row))
        with open(args.out, 'w', encoding='utf-8') as stream:
            json.dump(kept, stream, indent=2)
            stream.write('\n')
        return 0
    keep = args.keep
    for number, case in enumerate(chosen, 1):
        print(f'bench_scan: case {number}/{len(chosen)} {case["name"]} '
              f'({args.duration:g} s wall, load {os.getloadavg()[0]:.2f})',
              file=sys.stderr, flush=True)
        if keep:
            folder = os.path.join(keep, case['name'])
            os.makedirs(folder)
        else:
            folder = tempfile.mkdtemp(prefix=f'bench_scan_{case["name"]}_')
        row = run_case(case, folder, args.duration, args.prefix)
        row['folder'] = folder
        result['rows'].append(row)
        print(markdown_row(row), flush=True)
        write_json(args.out, result)
    return 0


if __name__ == '__main__':
    sys.exit(main())
