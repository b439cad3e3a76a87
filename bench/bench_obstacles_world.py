# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
Obstacles on the world (issue 36): Section 5's team among random pillars, through ROS.

Usage: python bench/bench_obstacles_world.py [--gains 0.5 2] [--clearances 0.25 0.5 1]
[--pillars 10 20 40] [--seed 0] [--duration 40] [--prefix INSTALL] [--out FILE] [--append]

For each gain c, b_o and number of pillars: Section 5's ten robots (config/paper_section5.yaml)
stabilising among the random pillar field of bench/bench_obstacles.py's ``--sweep`` (its
``field``: pillars of radius 0.3 m in a 20 m square around the team, none within b_o of a
start or a place; one field, ``--seed``), run by ``scripts/launch_formation.sh PARAMS
--world``: the MuJoCo world's holonomic bases (1 kg, 5 N per axis), the relay telling each
robot its pillars, the robots, all on the world's clock. The points get ``body.radius``
0.05 m, so that the law keeps the world's footprints off the pillars (the world would give
them 0.059 m: 0.4 of the closest two starts, 0.147 m). The same field is also run offline
with the ideal points (RK45) beside it.

Per run: settle time, closest approach of two bodies and of a body to a pillar, contacts with
robots and pillars (``world_stats.json``), stuck robots as ``formation_report`` names them,
the robots held far from their places (ended more than 0.05 m from their place, wandering
within 0.25 m over the last 5 s: a body held at a pillar may tremble more than the report's
0.05 m), and the real-time factor. Prints a Markdown table and writes OUT (default
docs/bench/obstacles_world.json; with ``--append``, its rows are kept and the new ones added
after them). ROS_DOMAIN_ID and ROS_AUTOMATIC_DISCOVERY_RANGE are taken
from the environment, as the launcher takes them.
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
from typing import Any, Dict, List, Optional, Sequence

BENCH = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(BENCH)
sys.path[:0] = [ROOT, BENCH]

from bench_obstacles import field  # noqa: E402
from bench_soak import write_json  # noqa: E402
from formation_ros.core.runs.obstacle_metrics import STILL_TIME, stuck_robots  # noqa: E402, I100
from formation_ros.core.runs.trajectory import Trajectory  # noqa: E402
from formation_ros.core.settings.params import FormationConfig, validate  # noqa: E402
from formation_ros.core.settings.params_file import load_params_file  # noqa: E402
from formation_ros.core.settings.params_file import write_params_file  # noqa: E402
from formation_ros.simulation.simulate import run_metrics, simulate  # noqa: E402
import numpy as np  # noqa: E402

LAUNCHER = os.path.join(ROOT, 'scripts', 'launch_formation.sh')
BODY_RADIUS = 0.05
"""Footprint radius of the Section 5 points on the world, m."""
START_UP = 6.0
"""Wall seconds the launcher's run is given beyond the simulated duration (nodes starting)."""
HELD_WANDER = 0.25
"""How far a held robot may wander over the last STILL_TIME seconds, m."""
HEADER = ('| c | b_o (m) | pillars | settle world / offline (s) | closest pair (m) | closest body '
          'to a pillar world / offline (m) | contacts robots, pillars | stuck (report) | held '
          'far from place (world; offline stuck) | real-time factor |\n'
          '|---:|---:|---:|---|---:|---|---|---|---|---:|')


def build_parser() -> argparse.ArgumentParser:
    """Return the command line parser."""
    parser = argparse.ArgumentParser(prog='bench_obstacles_world.py',
                                     description=__doc__.split('\n\n')[1].strip())
    parser.add_argument('--clearances', type=float, nargs='+', default=[0.25, 0.5, 1.0],
                        help='values of b_o, m (default 0.25 0.5 1)')
    parser.add_argument('--pillars', type=int, nargs='+', default=[10, 20, 40],
                        help='pillar counts in the 20 m square (default 10 20 40)')
    parser.add_argument('--gains', type=float, nargs='+', default=[0.5, 2.0],
                        help='values of the gain c (controller.gain; default 0.5 2: c M1 = '
                             "0.785 m/s and Section 5's 3.14 m/s)")
    parser.add_argument('--seed', type=int, default=0,
                        help="the field's seed, as bench_obstacles.py's (default 0)")
    parser.add_argument('--duration', type=float, default=40.0,
                        help='simulated seconds of each run, s (default 40)')
    parser.add_argument('--prefix', default=os.path.join(ROOT, 'install', 'formation_ros'),
                        help='install space of formation_ros (default ./install/formation_ros)')
    parser.add_argument('--out', default=os.path.join(ROOT, 'docs', 'bench',
                                                      'obstacles_world.json'),
                        help='JSON file of the rows (default docs/bench/obstacles_world.json)')
    parser.add_argument('--append', action='store_true',
                        help="keep OUT's rows and add this run's after them")
    return parser


def params_for(clearance: float, count: int, seed: int, duration: float,
               gain: float) -> Dict[str, Any]:
    """Return Section 5's flat parameters with its footprint among ``count`` random pillars."""
    raw = load_params_file(os.path.join(ROOT, 'config', 'paper_section5.yaml'))
    raw.update({'body.radius': BODY_RADIUS, 'duration': duration, 'controller.gain': gain})
    return field(raw, count, seed, clearance)


def held_robots(trajectory: Trajectory, config: FormationConfig) -> List[Dict[str, Any]]:
    """
    Return the robots ended far from their places, wandering within HELD_WANDER (records).

    Each is ``Stuck.record()`` with ``wander``: how far it came from where it ended over the
    last STILL_TIME seconds, m (the report names it stuck below 0.05 m).
    """
    held = stuck_robots(trajectory.t, trajectory.q, trajectory.q_desired, config.obstacles,
                        still_speed=HELD_WANDER / STILL_TIME, body_radius=config.body.radius)
    window = trajectory.t >= trajectory.t[-1] - STILL_TIME
    ends = trajectory.q[window] - trajectory.q[-1]
    return [{**robot.record(),
             'wander': float(np.max(np.linalg.norm(ends[:, robot.robot], axis=1)))}
            for robot in held]


def offline(config: FormationConfig) -> Dict[str, Any]:
    """Return the ideal points' run of ``config`` (RK45): settle, closest approaches, stuck."""
    metrics = run_metrics(simulate(config), config, 'RK45')
    return {key: metrics[key] for key in ('settle_time', 'min_pair_distance',
                                          'min_obstacle_clearance', 'obstacle_contacts',
                                          'stuck_robots')}


def on_world(params: Dict[str, Any], config: FormationConfig, duration: float, prefix: str,
             folder: str) -> Dict[str, Any]:
    """Run ``params`` with ``launch_formation.sh --world``; return the world's and report's."""
    path = os.path.join(folder, 'params.yaml')
    write_params_file(path, params)
    out = os.path.join(folder, 'run')
    with open(os.path.join(folder, 'launcher.log'), 'wb') as log:
        done = subprocess.run(['bash', LAUNCHER, path, '--world', '--out', out, '--no-plots',
                               '--prefix', prefix, '--duration', f'{duration + START_UP:g}'],
                              stdout=log, stderr=subprocess.STDOUT, check=False)
    if done.returncode != 0:
        raise RuntimeError(f'the launcher ended with {done.returncode} (see {log.name})')
    with open(os.path.join(out, 'world_stats.json'), encoding='utf-8') as stream:
        stats = json.load(stream)
    with open(os.path.join(out, 'metrics.json'), encoding='utf-8') as stream:
        metrics = json.load(stream)
    trajectory = Trajectory.load(os.path.join(out, 'trajectory.npz'))
    return {'settle_time': metrics['settle_time'],
            'final_max_error': metrics['final_max_error'],
            'min_pair_distance': metrics['min_pair_distance'],
            'min_obstacle_clearance': metrics['min_obstacle_clearance'],
            'stuck_robots': metrics['stuck_robots'],
            'held_robots': held_robots(trajectory, config),
            'bound_violations': metrics['bound_violations'],
            **{key: stats[key] for key in (
                'contacts', 'obstacle_contacts', 'min_body_distance', 'min_footprint_gap',
                'min_obstacle_gap', 'simulated_time', 'achieved_realtime_factor',
                'ticks_behind', 'obstacle_contact_events', 'contact_events')},
            'run': out}


def row_line(row: Dict[str, Any]) -> str:
    """Return one Markdown row of the table."""
    world, ideal = row['world'], row['offline']

    def names(records: Sequence[Dict[str, Any]]) -> str:
        return ', '.join(str(record['robot']) for record in records) or '-'

    return (f"| {row['gain']:g} | {row['clearance']:g} | {row['pillars']} | "
            f"{_number(world['settle_time'])} / "
            f"{_number(ideal['settle_time'])} | {world['min_body_distance']:.3f} | "
            f"{world['min_obstacle_gap']:.3f} / {ideal['min_obstacle_clearance']:.3f} | "
            f"{world['contacts']}, {world['obstacle_contacts']} | {names(world['stuck_robots'])} "
            f"| {names(world['held_robots'])}; {names(ideal['stuck_robots'])} | "
            f"{world['achieved_realtime_factor']:.3f} |")


def _number(value: Optional[float]) -> str:
    return '-' if value is None or (isinstance(value, float) and math.isnan(value)) \
        else f'{value:.2f}'


def main(argv: Optional[Sequence[str]] = None) -> int:
    """Run every case once; print the table and write the JSON."""
    args = build_parser().parse_args(argv)
    folder = tempfile.mkdtemp(prefix='bench_obstacles_world_')
    rows = []
    print(HEADER, flush=True)
    cases = [(gain, clearance, count) for gain in args.gains for clearance in args.clearances
             for count in args.pillars]
    for gain, clearance, count in cases:
        params = params_for(clearance, count, args.seed, args.duration, gain)
        config = validate(params)
        case = os.path.join(folder, f'c{gain:g}_b{clearance:g}_p{count}')
        os.makedirs(case)
        load_before = os.getloadavg()
        world = on_world(params, config, args.duration, args.prefix, case)
        row = {'gain': gain, 'clearance': clearance, 'pillars': count, 'seed': args.seed,
               'world': world, 'offline': offline(config),
               'load_before': load_before, 'load_after': os.getloadavg()}
        rows.append(row)
        print(row_line(row), flush=True)
    run = {'date': datetime.date.today().isoformat(), 'machine': platform.machine(),
           'cpus': os.cpu_count(), 'body_radius': BODY_RADIUS, 'duration': args.duration,
           'command': ' '.join(sys.argv)}
    runs = [{**run, 'rows': rows}]
    if args.append and os.path.exists(args.out):
        with open(args.out, encoding='utf-8') as stream:
            runs = json.load(stream)['runs'] + runs
    write_json(args.out, {'runs': runs})
    return 0


if __name__ == '__main__':
    sys.exit(main())
