# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
Benchmark of the team on the physics world through ROS (on demand, not in CI).

Usage: python bench/bench_world.py [--robots 20] [--rate 20] [--robots-per-process 5]
[--measure 30] [--prefix INSTALL] [--json FILE]

It runs ``scripts/launch_formation.sh PARAMS --world`` with N TurtleBot3-like bases
(config/world_turtlebot3.yaml's gains and bodies) on a square lattice 1.2 m apart, each about
0.15 m from its place at a random heading, the control at RATE Hz (``relay.rate`` and
``control_rate``: the relay's states on the world's /clock, every robot's answer), the world at
its defaults (2 ms steps, poses at 50 Hz, real time asked). Once every robot has been heard
commanding it watches, for MEASURE wall seconds, from a node of its own on the run's domain:
``/clock`` (the world's real-time factor: simulated over wall time), every state the relay
sends (``/robot_<i>/pose``) and every command (``/robot_<i>/cmd_vel``, stamped with the state
it answers). A state is answered fresh when a command with its stamp arrives while the world's
clock is at most two state periods past it (the states of the last moments too: answers are
heard 0.5 s longer). Then it stops the run with Ctrl-C and reads the
world's world_stats.json. Prints a Markdown row and the load averages before and after.
"""

import argparse
import datetime
import json
import math
import os
import platform
import signal
import subprocess
import sys
import tempfile
import time
from typing import Any, Dict, List, Optional, Sequence, Set

BENCH = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(BENCH)
sys.path[:0] = [ROOT]

from formation_ros.core.settings.params_file import (load_params_file,  # noqa: E402
                                                     write_params_file)
import numpy as np  # noqa: E402

LAUNCHER = os.path.join(ROOT, 'scripts', 'launch_formation.sh')
SPACING = 1.2
"""Distance between neighbouring places of the lattice, m."""
OFFSET = 0.15
"""How far each robot's hand point starts from its place, m."""
FRESH_PERIODS = 2
"""A state is answered fresh when its answer arrives within this many state periods (clock)."""
START_UP = 120.0
HEADER = ('| N | control (Hz) | processes | measured (s wall) | real-time factor (measured) | '
          'real-time factor (world, since start) | states | answered fresh | contacts | '
          'load before / after |\n'
          '|---:|---:|---:|---:|---:|---:|---:|---:|---:|---|')


def build_parser() -> argparse.ArgumentParser:
    """Return the command line parser."""
    parser = argparse.ArgumentParser(description=__doc__.split('\n\n')[0].strip())
    parser.add_argument('--robots', type=int, default=20, help='team size N (default 20)')
    parser.add_argument('--rate', type=float, default=20.0,
                        help='control rate, Hz of simulated time: relay.rate and control_rate '
                             '(default 20)')
    parser.add_argument('--robots-per-process', type=int, default=5,
                        help="robots per 'fleet' process (default 5; 1: a process each)")
    parser.add_argument('--measure', type=float, default=30.0,
                        help='wall seconds watched once every robot commands (default 30)')
    parser.add_argument('--prefix', default=os.path.join(ROOT, 'install', 'formation_ros'),
                        help='install space of formation_ros (default ./install/formation_ros)')
    parser.add_argument('--json', help='also write the row as JSON into this file')
    return parser


def params_for(n: int, rate: float, seed: int = 1) -> Dict[str, Any]:
    """Return N TurtleBot3-like bases of config/world_turtlebot3.yaml on a lattice."""
    values = load_params_file(os.path.join(ROOT, 'config', 'world_turtlebot3.yaml'))
    values = {name: value for name, value in values.items() if not name.startswith('start.')}
    side = math.ceil(math.sqrt(n))
    grid = np.array([(i % side, i // side) for i in range(n)], dtype=float) * SPACING
    vertices = grid - grid.mean(axis=0)
    rng = np.random.default_rng(seed)
    angles = rng.uniform(-math.pi, math.pi, n)
    headings = rng.uniform(-math.pi, math.pi, n)
    hand = values['body.hand_distance']
    hands = vertices + OFFSET * np.stack((np.cos(angles), np.sin(angles)), axis=1)
    axles = hands - hand * np.stack((np.cos(headings), np.sin(headings)), axis=1)
    values.update({'num_robots': n, 'formation.vertices': vertices.ravel().tolist(),
                   'start.positions': axles.ravel().tolist(),
                   'start.headings': headings.tolist(), 'relay.rate': rate,
                   'control_rate': rate, 'duration': 3600.0})
    return values


class Watch:
    """The run as a node of its own sees it: clock, states and answers."""

    def __init__(self, n: int, period_ns: int) -> None:
        """Subscribe to /clock and every robot's pose and cmd_vel."""
        import rclpy
        from formation_ros.ros import qos
        from geometry_msgs.msg import PoseStamped, TwistStamped
        from rosgraph_msgs.msg import Clock
        rclpy.init()
        self.rclpy = rclpy
        self.node = rclpy.create_node('bench_world')
        self.period_ns = period_ns
        self.clock_ns = -1
        self.measuring = False
        self.answers = False
        """Whether answers are counted (a little longer than states: the last ones' too)."""
        self.clock_samples: List[tuple] = []
        self.states: List[Set[int]] = [set() for _ in range(n)]
        self.answered: List[Set[int]] = [set() for _ in range(n)]
        self.commanded = [False] * n
        self.node.create_subscription(Clock, '/clock', self._clock, qos.CLOCK)
        for i in range(n):
            self.node.create_subscription(PoseStamped, f'/robot_{i + 1}/pose',
                                          lambda m, k=i: self._state(k, m), qos.STATE)
            self.node.create_subscription(TwistStamped, f'/robot_{i + 1}/cmd_vel',
                                          lambda m, k=i: self._command(k, m), qos.COMMAND)

    @staticmethod
    def _ns(stamp: Any) -> int:
        return stamp.sec * 1_000_000_000 + stamp.nanosec

    def _clock(self, message: Any) -> None:
        self.clock_ns = self._ns(message.clock)
        if self.measuring:
            self.clock_samples.append((time.monotonic(), self.clock_ns))

    def _state(self, k: int, message: Any) -> None:
        if self.measuring:
            self.states[k].add(self._ns(message.header.stamp))

    def _command(self, k: int, message: Any) -> None:
        self.commanded[k] = True
        stamp = self._ns(message.header.stamp)
        if self.answers and 0 <= self.clock_ns - stamp <= FRESH_PERIODS * self.period_ns:
            self.answered[k].add(stamp)

    def spin(self, seconds: float) -> None:
        """Spin the node for ``seconds`` of wall time."""
        end = time.monotonic() + seconds
        while time.monotonic() < end:
            self.rclpy.spin_once(self.node, timeout_sec=0.05)

    def figures(self) -> Dict[str, Any]:
        """Return the real-time factor watched and the share of states answered fresh."""
        (wall0, sim0), (wall1, sim1) = self.clock_samples[0], self.clock_samples[-1]
        states = sum(len(s) for s in self.states)
        fresh = sum(len(s & a) for s, a in zip(self.states, self.answered))
        return {'measured_wall_s': wall1 - wall0, 'clock_samples': len(self.clock_samples),
                'realtime_factor_measured': (sim1 - sim0) / 1e9 / (wall1 - wall0),
                'states': states, 'answered_fresh': fresh,
                'fresh_fraction': fresh / states if states else None}

    def close(self) -> None:
        """Destroy the node, shut rclpy down."""
        self.node.destroy_node()
        self.rclpy.shutdown()


def free_domain() -> int:
    """Return a free ROS_DOMAIN_ID on this host (the launcher's own choice)."""
    from formation_ros.tools.domain import choose_domain
    return choose_domain(dict(os.environ, ROS_AUTOMATIC_DISCOVERY_RANGE='LOCALHOST'))[0]


def main(argv: Optional[Sequence[str]] = None) -> int:
    """Run the benchmark once; print its row."""
    args = build_parser().parse_args(argv)
    load_before = os.getloadavg()
    domain = free_domain()
    os.environ.update({'ROS_DOMAIN_ID': str(domain), 'ROS_AUTOMATIC_DISCOVERY_RANGE': 'LOCALHOST'})
    folder = tempfile.mkdtemp(prefix='bench_world_')
    params = os.path.join(folder, 'params.yaml')
    write_params_file(params, params_for(args.robots, args.rate))
    out = os.path.join(folder, 'run')
    log = open(os.path.join(folder, 'launcher.log'), 'wb')
    watch = Watch(args.robots, int(round(1e9 / args.rate)))
    process = subprocess.Popen(
        ['bash', LAUNCHER, params, '--world', '--duration', '0', '--out', out, '--no-plots',
         '--prefix', args.prefix, '--robots-per-process', str(args.robots_per_process)],
        stdout=log, stderr=subprocess.STDOUT, start_new_session=True)
    try:
        deadline = time.monotonic() + START_UP
        while not all(watch.commanded):
            if process.poll() is not None or time.monotonic() > deadline:
                print(f'bench_world: the run did not start (see {log.name})', file=sys.stderr)
                return 1
            watch.spin(0.2)
        watch.measuring = watch.answers = True
        watch.spin(args.measure)
        watch.measuring = False
        watch.spin(0.5)
        figures = watch.figures()
    finally:
        if process.poll() is None:
            os.killpg(process.pid, signal.SIGINT)
        process.wait(timeout=120)
        watch.close()
        log.close()
    with open(os.path.join(out, 'world_stats.json'), encoding='utf-8') as stream:
        stats = json.load(stream)
    load_after = os.getloadavg()
    processes = 3 + math.ceil(args.robots / args.robots_per_process)
    row = dict(figures, robots=args.robots, rate=args.rate, processes=processes,
               robots_per_process=args.robots_per_process,
               realtime_factor_world=stats['achieved_realtime_factor'],
               contacts=stats['contacts'], ticks_behind=stats['ticks_behind'],
               load_before=load_before, load_after=load_after, machine=platform.machine(),
               cpus=os.cpu_count(), date=datetime.date.today().isoformat(), run=folder)
    print(HEADER)
    print(f"| {args.robots} | {args.rate:g} | {processes} | {row['measured_wall_s']:.1f} | "
          f"{row['realtime_factor_measured']:.4f} | {row['realtime_factor_world']:.4f} | "
          f"{row['states']} | {100 * (row['fresh_fraction'] or 0):.2f} % | {row['contacts']} | "
          f'{load_before[0]:.2f} / {load_after[0]:.2f} |')
    if args.json:
        with open(args.json, 'w', encoding='utf-8') as stream:
            json.dump(row, stream, indent=2)
            stream.write('\n')
    return 0


if __name__ == '__main__':
    sys.exit(main())
