# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
Switch benchmark: the settle time after a shape switch, offline and over ROS; and its GIF.

Usage: python bench/bench_switch.py [--quick] [--offline] [--prefix INSTALL] [--out DIR]
[--work DIR]; python bench/bench_switch.py --gif [--prefix INSTALL] [--out DIR]

The paper's Section 5 team (config/paper_section5.yaml: 10 robots, a circle of radius 8 m) with
a second named shape, ``line``: 10 vertices 1.5 m apart on the x axis, robot i at the rank of
its circle vertex's x (so the upper and lower halves each keep their order and no two straight
paths cross; every robot moves about 8 m, the circle's radius). Once the team has settled on the
circle it switches to the line, and the settle time of the segment after the switch (every
robot within 0.05 m of its place from then on, metrics.json ``segments``) is measured in
formation_sim (RK45, and --dt 0.01), both with the switch in the schedule
(formation.schedule.times / formation.schedule.names); and over ROS with
scripts/launch_formation.sh --record: free-running (the switch made when the team has settled,
through /reference/set_parameters as ``ros2 param set /reference formation.name line`` makes
it; Ctrl-C once the line has settled; formation_report on the bag gives the segments) and in
lockstep (plant.lockstep, the switch in the schedule: equal to formation_sim --dt to the step).
Prints a Markdown table and progress lines on stderr, writes OUT/bench/switch.json (OUT
defaults to the repository's docs/). Without --prefix the package is built with colcon into a
temporary directory. --gif instead makes OUT/changes.gif: config/square_4.yaml with named
shapes line and wedge, converge, switch to the line, switch to the wedge, /formation/stop in
the middle of the move, /formation/start, converge; formation_report BAG --animate.
"""

import argparse
import contextlib
import json
import os
import random
import shutil
import signal
import subprocess
import sys
import tempfile
import time
from typing import Any, Callable, Dict, Iterator, List, Optional, Sequence, Tuple

BENCH = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(BENCH)
sys.path[:0] = [ROOT, BENCH]

from bench_robustness import machine  # noqa: E402
from formation_ros.core.maths.frames import desired_positions  # noqa: E402, I100
from formation_ros.core.runs.metrics import SETTLE_TOLERANCE  # noqa: E402
from formation_ros.core.settings.params import FormationConfig, validate  # noqa: E402
from formation_ros.core.settings.params_file import (load_params_file,  # noqa: E402
                                                     write_params_file)
import numpy as np  # noqa: E402, I100
from numpy.typing import NDArray  # noqa: E402

SECTION5 = 'config/paper_section5.yaml'
SQUARE = 'config/square_4.yaml'
LAUNCHER = os.path.join(ROOT, 'scripts', 'launch_formation.sh')
SPACING = 1.5
"""Distance between neighbours on the line, m (b = 1 m, R = 2 m)."""
SWITCH_AT, DURATION = 10.0, 20.0
"""The scheduled switch and the run's length, s (the circle settles in about 5 s)."""
QUICK_SWITCH_AT, QUICK_DURATION = 6.0, 11.0
DT = 0.01
FACTOR = 1000.0
"""plant.realtime_factor in lockstep: an upper bound, the robots set the pace."""
SETTLED = 0.01
"""A ROS run is taken as settled when every robot is this close to its place, m."""
TAIL = 1.0
"""Simulated seconds recorded after the team has settled on the line, before Ctrl-C."""
START_TIMEOUT = 180.0
RUN_TIMEOUT = 300.0
GIF_LINE = [-3.0, 0.0, -1.0, 0.0, 1.0, 0.0, 3.0, 0.0]
GIF_WEDGE = [0.0, 1.5, -1.5, 0.0, 1.5, 0.0, 0.0, -1.5]
GIF_OPTIONS = ['--fps', '15', '--speed', '1', '--dpi', '100']
GIF_MOVE, GIF_HOLD = 0.6, 2.0
"""--gif: stop this long after the switch to the wedge, s; stay stopped this long, s."""


def say(text: str) -> None:
    """Print a progress line on stderr."""
    print(f'bench_switch: {text}', file=sys.stderr, flush=True)


def build_parser() -> argparse.ArgumentParser:
    """Command line of the switch benchmark."""
    parser = argparse.ArgumentParser(
        prog='bench_switch.py', description=__doc__.split('\n\n')[2].strip(),
        epilog='Quick check (seconds): python bench/bench_switch.py --quick --offline '
               '--out /tmp/s')
    parser.add_argument('--quick', action='store_true',
                        help=f'switch at {QUICK_SWITCH_AT:g} s of {QUICK_DURATION:g} s instead '
                             f'of {SWITCH_AT:g} s of {DURATION:g} s: checks the benchmark')
    parser.add_argument('--offline', action='store_true',
                        help='formation_sim only: no ROS run, no colcon build')
    parser.add_argument('--gif', action='store_true',
                        help='make OUT/changes.gif (a real ROS run) instead of the benchmark')
    parser.add_argument('--prefix',
                        help='install space of formation_ros (default: build one with colcon '
                             'into a temporary directory)')
    parser.add_argument('--out', default=os.path.join(ROOT, 'docs'),
                        help='writes OUT/bench/switch.json, or OUT/changes.gif with --gif '
                             '(default: %(default)s)')
    parser.add_argument('--work',
                        help='keep the runs (parameters, bags, logs, reports) in this new '
                             'directory (default: a temporary one, removed)')
    return parser


def parse_args(argv: Optional[Sequence[str]] = None) -> argparse.Namespace:
    """Parse and check the command line (argparse exits 2 on a bad one)."""
    parser = build_parser()
    args = parser.parse_args(argv)
    if args.gif and args.offline:
        parser.error('--gif makes a ROS run: not with --offline')
    if args.prefix is not None:
        if not os.access(os.path.join(args.prefix, 'lib', 'formation_ros', 'plant'), os.X_OK):
            parser.error(f"no formation_ros install at --prefix '{args.prefix}'")
        args.prefix = os.path.abspath(args.prefix)
    if args.work is not None:
        if os.path.exists(args.work):
            parser.error(f"--work '{args.work}' exists already; choose a new directory")
        args.work = os.path.abspath(args.work)
    args.out = os.path.abspath(args.out)
    return args


def line_shape(circle: NDArray[np.float64], spacing: float = SPACING) -> NDArray[np.float64]:
    """
    Return the line (N, 2), m: N vertices ``spacing`` apart on the x axis, centred on 0.

    Robot i gets the slot of the rank of circle[i]'s x (ties: the lower one first), so each
    half of the circle keeps its order along x and no two straight paths cross.
    """
    order = sorted(range(len(circle)), key=lambda i: (round(float(circle[i, 0]), 9),
                                                      float(circle[i, 1])))
    line = np.zeros((len(circle), 2))
    for slot, robot in enumerate(order):
        line[robot, 0] = (slot - (len(circle) - 1) / 2.0) * spacing
    return line


def section5(switch_at: Optional[float], duration: float,
             lockstep: bool = False) -> Dict[str, Any]:
    """Return Section 5's parameters with the line as a named shape (and the switch scheduled)."""
    raw = load_params_file(os.path.join(ROOT, SECTION5))
    circle = np.reshape(raw['formation.vertices'], (-1, 2))
    raw.update({'formations.names': ['line'],
                'formations.line.vertices': line_shape(circle).ravel().tolist(),
                'duration': float(duration)})
    if switch_at is not None:
        raw.update({'formation.schedule.times': [float(switch_at)],
                    'formation.schedule.names': ['line']})
    if lockstep:
        raw.update({'plant.lockstep': True, 'plant.realtime_factor': FACTOR})
    validate(raw)
    return raw


def write(folder: str, name: str, raw: Dict[str, Any]) -> str:
    """Write parameters ``raw`` as FOLDER/NAME.yaml; return its path."""
    path = os.path.join(folder, f'{name}.yaml')
    write_params_file(path, raw)
    return path


def after_switch(metrics: Dict[str, Any], label: str = 'line') -> Dict[str, Any]:
    """Return the segment of metrics.json opened by the switch to ``label`` (KeyError if none)."""
    rows = [row for row in metrics.get('segments', ())
            if row['kind'] == 'shape' and row['label'] == label]
    if not rows:
        raise KeyError(f"no segment after a switch to '{label}' in metrics.json")
    return rows[0]


def summary(metrics: Dict[str, Any]) -> Dict[str, Any]:
    """Return the numbers of one run: the switch, the settle times, the safety after it."""
    segment = after_switch(metrics)
    first = metrics['segments'][0]
    return {'switch_at': segment['start'], 'settle_time': segment['settle_time'],
            'settle_time_before': first['settle_time'] if first['kind'] is None else None,
            'closest_after': segment['min_pair_distance'],
            'max_abs_u_hat_after': segment['max_abs_u_hat_component'],
            'final_max_error': segment['final_max_error'], 'end': segment['end'],
            'u_bound': metrics['u_bound'], 'collisions': metrics.get('collisions')}


def run_sim(params: str, out: str, dt: Optional[float]) -> Dict[str, Any]:
    """Run formation_sim PARAMS (RK45, or --dt) as a user would; return its numbers."""
    command = [sys.executable, '-m', 'formation_ros.tools.sim', params, '--out', out,
               '--sample-dt', repr(DT), '--no-plots', '--quiet']
    if dt is not None:
        command += ['--dt', repr(dt)]
    started = time.monotonic()
    done = subprocess.run(command, capture_output=True, text=True, timeout=RUN_TIMEOUT)
    if done.returncode != 0:
        raise RuntimeError(f'formation_sim failed: {done.stdout[-2000:]}{done.stderr[-2000:]}')
    with open(os.path.join(out, 'metrics.json'), encoding='utf-8') as stream:
        result = summary(json.load(stream))
    result['wall_s'] = time.monotonic() - started
    return result


def build_install(folder: str) -> str:
    """Build the package with colcon into FOLDER (as the integration tests do); its prefix."""
    os.makedirs(folder, exist_ok=True)
    done = subprocess.run(
        [sys.executable, '-m', 'colcon', '--log-base', os.path.join(folder, 'log'), 'build',
         '--base-paths', ROOT, '--build-base', os.path.join(folder, 'build'),
         '--install-base', os.path.join(folder, 'install')],
        cwd=folder, capture_output=True, text=True, timeout=600)
    if done.returncode != 0:
        raise RuntimeError(f'colcon build failed: {done.stdout[-2000:]}{done.stderr[-2000:]}')
    return os.path.join(folder, 'install', 'formation_ros')


class Probe:
    """An rclpy node of the benchmark: the robots' poses, /clock, the reference's services."""

    def __init__(self, config: FormationConfig, domain: int) -> None:
        """Join ROS domain ``domain`` (this host only) and hear the team of ``config``."""
        import rclpy
        from rclpy.executors import SingleThreadedExecutor
        from formation_ros.ros import fields, qos
        from geometry_msgs.msg import PoseStamped
        from rcl_interfaces.srv import SetParameters
        from rosgraph_msgs.msg import Clock
        from std_srvs.srv import Trigger
        self.config = config
        self.context = rclpy.Context()
        rclpy.init(context=self.context, domain_id=domain)
        self.node = rclpy.create_node('bench_switch', context=self.context)
        self.executor = SingleThreadedExecutor(context=self.context)
        self.executor.add_node(self.node)
        self.poses: Dict[int, Tuple[float, ...]] = {}
        self.seconds = -1.0
        for i in range(1, config.num_robots + 1):
            self.node.create_subscription(
                PoseStamped, f'/robot_{i}/pose',
                lambda m, i=i: self.poses.__setitem__(i, (m.pose.position.x, m.pose.position.y,
                                                          m.pose.position.z)),
                qos.STATE_INPUT)
        self.node.create_subscription(
            Clock, '/clock', lambda m: setattr(self, 'seconds',
                                               fields.stamp_to_ns(m.clock) * 1e-9), qos.CLOCK)
        self.parameters = self.node.create_client(SetParameters, '/reference/set_parameters')
        self.triggers = {name: self.node.create_client(Trigger, f'/formation/{name}')
                         for name in ('stop', 'start')}

    def spin_until(self, condition: Callable[[], bool], timeout: float) -> bool:
        """Spin until ``condition()`` holds or ``timeout`` wall seconds pass; whether it held."""
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            if condition():
                return True
            self.executor.spin_once(timeout_sec=0.05)
        return condition()

    def error(self, vertices: NDArray[np.float64]) -> float:
        """Largest distance of a robot from its place in ``vertices`` (m); inf before all."""
        n, dim = self.config.num_robots, self.config.dim
        if len(self.poses) < n or self.seconds < 0.0:
            return float('inf')
        q = np.array([self.poses[i][:dim] for i in range(1, n + 1)])
        desired = desired_positions(vertices, self.config.reference().sample(self.seconds))
        return float(np.max(np.linalg.norm(q - desired, axis=1)))

    def _call(self, client: Any, request: Any) -> Any:
        if not self.spin_until(client.service_is_ready, 60.0):
            raise RuntimeError(f'{client.srv_name} is not served')
        future = client.call_async(request)
        if not self.spin_until(future.done, 60.0):
            raise RuntimeError(f'{client.srv_name}: no answer')
        return future.result()

    def set_shape(self, name: str) -> None:
        """``ros2 param set /reference formation.name NAME`` (RuntimeError if refused)."""
        from rcl_interfaces.msg import Parameter, ParameterType, ParameterValue
        from rcl_interfaces.srv import SetParameters
        value = ParameterValue(type=ParameterType.PARAMETER_STRING, string_value=name)
        request = SetParameters.Request(parameters=[Parameter(name='formation.name',
                                                              value=value)])
        result = self._call(self.parameters, request).results[0]
        if not result.successful:
            raise RuntimeError(f'formation.name {name} refused: {result.reason}')

    def trigger(self, name: str) -> str:
        """``ros2 service call /formation/NAME std_srvs/srv/Trigger``; return its message."""
        from std_srvs.srv import Trigger
        response = self._call(self.triggers[name], Trigger.Request())
        if not response.success:
            raise RuntimeError(f'/formation/{name}: {response.message}')
        return str(response.message)

    def close(self) -> None:
        """Leave ROS."""
        import rclpy
        self.executor.shutdown()
        self.node.destroy_node()
        rclpy.shutdown(context=self.context)


def stop_group(process: 'subprocess.Popen[bytes]', grace: float = 120.0) -> None:
    """Ctrl-C the launcher's process group, as a terminal would; SIGKILL if it hangs."""
    for sig, wait in ((signal.SIGINT, grace), (signal.SIGKILL, 10.0)):
        if process.poll() is not None:
            return
        with contextlib.suppress(ProcessLookupError):
            os.killpg(process.pid, sig)
        with contextlib.suppress(subprocess.TimeoutExpired):
            process.wait(timeout=wait)


@contextlib.contextmanager
def ros_run(prefix: str, params: str, folder: str,
            config: FormationConfig) -> Iterator[Tuple[Probe, 'subprocess.Popen[bytes]']]:
    """
    Start the launcher on PARAMS with --out FOLDER/out --record FOLDER/bag; give a probe.

    On leaving, the launcher is Ctrl-C'd (if it still runs) and waited for: it writes the
    report of the bag into FOLDER/out.
    """
    domain = random.SystemRandom().randint(1, 101)
    env = dict(os.environ, ROS_DOMAIN_ID=str(domain), ROS_AUTOMATIC_DISCOVERY_RANGE='LOCALHOST')
    os.environ['ROS_AUTOMATIC_DISCOVERY_RANGE'] = 'LOCALHOST'
    command = ['bash', LAUNCHER, params, '--duration', '0', '--prefix', prefix,
               '--out', os.path.join(folder, 'out'), '--record', os.path.join(folder, 'bag')]
    probe = Probe(config, domain)
    with open(os.path.join(folder, 'launcher.log'), 'wb') as log:
        process = subprocess.Popen(command, env=env, stdout=log, stderr=subprocess.STDOUT,
                                   stdin=subprocess.DEVNULL, start_new_session=True)
        try:
            yield probe, process
        finally:
            stop_group(process)
            probe.close()


def wait(probe: Probe, process: 'subprocess.Popen[bytes]', condition: Callable[[], bool],
         what: str, folder: str, timeout: float = RUN_TIMEOUT) -> None:
    """Spin until ``condition`` holds; RuntimeError naming ``what`` if the run ends first."""
    if not probe.spin_until(lambda: condition() or process.poll() is not None, timeout) \
            or not condition():
        with open(os.path.join(folder, 'launcher.log'), encoding='utf-8',
                  errors='replace') as stream:
            tail = stream.read()[-3000:]
        raise RuntimeError(f'{what}: not reached within {timeout:g} s\n{tail}')


def report(folder: str, process: 'subprocess.Popen[bytes]') -> Dict[str, Any]:
    """End the run; return formation_report's metrics.json of the bag (the launcher wrote it)."""
    stop_group(process)
    if process.returncode != 0:
        raise RuntimeError(f'launcher exit {process.returncode}; see {folder}/launcher.log')
    with open(os.path.join(folder, 'out', 'metrics.json'), encoding='utf-8') as stream:
        metrics: Dict[str, Any] = json.load(stream)
    if metrics.get('source') != 'rosbag2':
        raise RuntimeError(f"{folder}/out/metrics.json is not the bag's report")
    return metrics


def ros_free_running(prefix: str, folder: str) -> Dict[str, Any]:
    """Section 5 over ROS in real time: switch to the line once settled, Ctrl-C once settled."""
    os.makedirs(folder)
    raw = section5(None, 1000.0)
    params = write(folder, 'params', raw)
    config = validate(raw)
    circle, line = config.vertices, config.shapes['line']
    started = time.monotonic()
    with ros_run(prefix, params, folder, config) as (probe, process):
        wait(probe, process, lambda: probe.error(circle) < SETTLED, 'settled on the circle',
             folder)
        switched = probe.seconds
        say(f'free-running: settled on the circle at t = {switched:.2f} s; switching to the '
            'line (formation.name)')
        probe.set_shape('line')
        wait(probe, process, lambda: probe.error(line) < SETTLED, 'settled on the line', folder)
        settled = probe.seconds
        wait(probe, process, lambda: probe.seconds >= settled + TAIL, 'the tail', folder)
        say(f'free-running: settled on the line at t = {settled:.2f} s; Ctrl-C')
        metrics = report(folder, process)
    result = summary(metrics)
    result.update({'wall_s': time.monotonic() - started, 'how': 'ros2 param set /reference '
                   'formation.name line once every robot was within '
                   f'{SETTLED:g} m of the circle; Ctrl-C {TAIL:g} s after the line'})
    return result


def ros_lockstep(prefix: str, folder: str, switch_at: float, duration: float) -> Dict[str, Any]:
    """Section 5 over ROS in lockstep with the switch in the schedule; compared to --dt."""
    from formation_ros.core.runs.trajectory import Trajectory, TRAJECTORY_FILE
    from formation_ros.simulation.simulate import simulate
    os.makedirs(folder)
    raw = section5(switch_at, duration, lockstep=True)
    params = write(folder, 'params', raw)
    config = validate(raw)
    started = time.monotonic()
    with ros_run(prefix, params, folder, config) as (probe, process):
        wait(probe, process, lambda: probe.seconds >= duration, f't = {duration:g} s', folder)
        say(f'lockstep: t = {probe.seconds:.2f} s after {time.monotonic() - started:.0f} s; '
            'Ctrl-C')
        metrics = report(folder, process)
    result = summary(metrics)
    plant = Trajectory.load(os.path.join(folder, 'out', TRAJECTORY_FILE))
    sim = simulate(config, duration=float(plant.t[-1]), dt=DT, sample_dt=DT)
    same = len(sim.t) == len(plant.t)
    result.update({'wall_s': time.monotonic() - started, 'steps': len(plant.t),
                   'max_abs_q_difference_to_sim_dt': float(np.max(np.abs(sim.q - plant.q)))
                   if same else None,
                   'max_abs_u_difference_to_sim_dt': float(np.max(np.abs(sim.u - plant.u)))
                   if same else None})
    return result


def gif_params() -> Dict[str, Any]:
    """Return config/square_4.yaml's parameters with the named shapes line and wedge."""
    raw = load_params_file(os.path.join(ROOT, SQUARE))
    raw.update({'formations.names': ['line', 'wedge'], 'formations.line.vertices': GIF_LINE,
                'formations.wedge.vertices': GIF_WEDGE, 'duration': 1000.0})
    validate(raw)
    return raw


def make_gif(args: argparse.Namespace, work: str) -> int:
    """
    Make OUT/changes.gif from a real run: two shape switches and a stop in the middle of a move.

    Square -> ``formation.name line`` once settled -> ``formation.name wedge`` once settled ->
    /formation/stop GIF_MOVE s later -> /formation/start GIF_HOLD s later -> settled on the
    wedge; Ctrl-C, then ``formation_report BAG --out DIR --animate`` with GIF_OPTIONS.
    """
    from PIL import Image
    prefix = args.prefix
    if prefix is None:
        say('building the package with colcon')
        prefix = build_install(os.path.join(work, 'colcon'))
    folder = os.path.join(work, 'gif')
    os.makedirs(folder)
    raw = gif_params()
    params = write(folder, 'params', raw)
    config = validate(raw)
    shapes = {'square': config.vertices, **config.shapes}
    steps: List[str] = []
    with ros_run(prefix, params, folder, config) as (probe, process):
        def settle(name: str) -> None:
            wait(probe, process, lambda: probe.error(shapes[name]) < SETTLED,
                 f'settled on the {name}', folder)
            steps.append(f't = {probe.seconds:.2f} s: settled on the {name}')
            say(steps[-1])

        def after(seconds: float) -> None:
            since = probe.seconds
            wait(probe, process, lambda: probe.seconds >= since + seconds, f'+{seconds:g} s',
                 folder)

        settle('square')
        for name in ('line', 'wedge'):
            probe.set_shape(name)
            steps.append(f't = {probe.seconds:.2f} s: formation.name {name}')
            say(steps[-1])
            if name == 'line':
                settle(name)
        after(GIF_MOVE)
        steps.append(f't = {probe.seconds:.2f} s: {probe.trigger("stop")}')
        say(steps[-1])
        after(GIF_HOLD)
        steps.append(f't = {probe.seconds:.2f} s: {probe.trigger("start")}')
        say(steps[-1])
        settle('wedge')
        after(TAIL)
        metrics = report(folder, process)
    animation = os.path.join(folder, 'animation')
    done = subprocess.run([sys.executable, '-m', 'formation_ros.tools.report',
                           os.path.join(folder, 'bag'), '--out', animation, '--animate',
                           *GIF_OPTIONS], capture_output=True, text=True, timeout=RUN_TIMEOUT)
    if done.returncode != 0:
        raise RuntimeError(f'formation_report --animate failed: {done.stderr[-2000:]}')
    made = os.path.join(animation, 'animation.gif')
    if not os.path.exists(made):
        raise RuntimeError(f'no GIF in {animation} (an mp4 where ffmpeg is on PATH?)')
    target = os.path.join(args.out, 'changes.gif')
    os.makedirs(args.out, exist_ok=True)
    shutil.copyfile(made, target)
    with Image.open(target) as image:
        frames = image.n_frames
    size = os.path.getsize(target)
    print('\n'.join(steps))
    settles = [f"{row['label']} {fmt(row['settle_time'])} s" for row in metrics['segments']]
    print(f"settle time of each segment: {', '.join(settles)}")
    print(f'wrote {target}: {frames} frames, {size / 1e6:.2f} MB (formation_report BAG --out DIR '
          f"--animate {' '.join(GIF_OPTIONS)})")
    return 0


def machine_line(host: Dict[str, Any]) -> str:
    """Return the machine as a line above the table."""
    return (f"machine: {host['nproc']} cores, {host['cpu']}, Python {host['python']}; load "
            f"{' '.join(f'{v:.2f}' for v in host['load_before'])}")


def fmt(value: Optional[float], digits: int = 4) -> str:
    """Format a number for the table ('-' for None)."""
    return '-' if value is None else f'{value:.{digits}g}'


def markdown(rows: Dict[str, Dict[str, Any]]) -> str:
    """Markdown table of the runs."""
    lines = ['| run | switch at (s) | settle after the switch (s) | settle from the start (s) | '
             'closest after (m) | max abs u_hat after (m/s) | wall (s) |',
             '|---|---:|---:|---:|---:|---:|---:|']
    for name, row in rows.items():
        lines.append(f"| {name} | {row['switch_at']:.2f} | {fmt(row['settle_time'])} | "
                     f"{fmt(row['settle_time_before'])} | {fmt(row['closest_after'])} | "
                     f"{fmt(row['max_abs_u_hat_after'])} (bound {row['u_bound']:.4g}) | "
                     f"{row['wall_s']:.0f} |")
    return '\n'.join(lines)


def benchmark(args: argparse.Namespace, work: str) -> int:
    """Every run of the benchmark; write OUT/bench/switch.json; 0 when every run worked."""
    host = machine()
    switch_at, duration = ((QUICK_SWITCH_AT, QUICK_DURATION) if args.quick
                           else (SWITCH_AT, DURATION))
    started = time.monotonic()
    scheduled = write(work, 'scheduled', section5(switch_at, duration))
    rows: Dict[str, Dict[str, Any]] = {}
    for name, dt in (('formation_sim RK45', None), (f'formation_sim --dt {DT:g}', DT)):
        rows[name] = run_sim(scheduled, os.path.join(work, name.split()[-1]), dt)
        say(f"{name}: settled {fmt(rows[name]['settle_time'])} s after the switch")
    if not args.offline:
        prefix = args.prefix
        if prefix is None:
            say('building the package with colcon')
            prefix = build_install(os.path.join(work, 'colcon'))
        rows['ROS free-running'] = ros_free_running(prefix, os.path.join(work, 'free'))
        say(f"ROS free-running: settled {fmt(rows['ROS free-running']['settle_time'])} s "
            'after the switch')
        rows['ROS lockstep'] = ros_lockstep(prefix, os.path.join(work, 'lockstep'), switch_at,
                                            duration)
        say(f"ROS lockstep: settled {fmt(rows['ROS lockstep']['settle_time'])} s after the "
            'switch')
    raw = section5(switch_at, duration)
    result = {
        'machine': host, 'arguments': {**{k: v for k, v in vars(args).items() if k != 'work'},
                                       'out': os.path.relpath(args.out, ROOT)},
        'team': SECTION5, 'shape': {
            'name': 'line', 'vertices': raw['formations.line.vertices'], 'spacing': SPACING,
            'why': "each robot gets the slot of its circle vertex's rank along x: the upper "
                   'and lower halves keep their order, no two straight paths cross, and every '
                   "robot moves about the circle's radius (8 m), so the settle time measures "
                   'the switch, not a crossing; 1.5 m apart > b = 1 m'},
        'schedule': {'times': [switch_at], 'names': ['line'], 'duration': duration},
        'settle_tolerance': SETTLE_TOLERANCE, 'runs': rows,
        'wall_s': time.monotonic() - started}
    if 'ROS lockstep' in rows:
        result['lockstep_equals_sim_dt'] = (
            rows['ROS lockstep']['settle_time'] == rows[f'formation_sim --dt {DT:g}']
            ['settle_time'])
    path = os.path.join(args.out, 'bench', 'switch.json')
    os.makedirs(os.path.dirname(path), exist_ok=True)
    with open(path, 'w', encoding='utf-8') as stream:
        json.dump(result, stream, indent=2)
        stream.write('\n')
    print(machine_line(host) + '\n')
    print(markdown(rows))
    print(f'\nwrote {path}')
    return 0


def main(argv: Optional[Sequence[str]] = None) -> int:
    """Run the benchmark (or make the GIF); the exit code."""
    args = parse_args(argv)
    work = args.work or tempfile.mkdtemp(prefix='bench_switch-')
    os.makedirs(work, exist_ok=True)
    try:
        return make_gif(args, work) if args.gif else benchmark(args, work)
    except RuntimeError as exc:
        print(f'bench_switch: {exc}', file=sys.stderr)
        return 1
    finally:
        if args.work is None:
            shutil.rmtree(work, ignore_errors=True)


if __name__ == '__main__':
    sys.exit(main())
