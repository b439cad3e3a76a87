"""
Plant node (executable ``plant``): the robots' bodies, q_i' = u_i (eq. 1), and their sensors.

It holds every robot's true position, integrates with the latest command of each robot held
over the step (zero-order hold, step 1 / ``plant.rate`` of simulated time), and publishes:

* ``robot_<i>/pose`` (PoseStamped) and ``robot_<i>/neighbors`` (PoseArray: the robots within
  R_i of robot i, its simulated range sensor) at ``plant.publish_rate``;
* ``/clock``, the simulated time, starting at 0, for nodes run with ``use_sim_time``.

A command whose state stamp is older than ``plant.input_timeout`` counts as zero. Collisions
(pairs closer than ``plant.collision_distance``) are logged as errors; commands whose bounded
part u_hat exceeds c * M1 are counted and logged, never clipped. With ``plant.lockstep`` the
plant advances only when every robot has answered the latest state, which makes a run
reproduce ``formation_sim --dt 1/plant.rate``. With ``plant.output_dir`` it writes
``trajectory.npz`` and ``plant_stats.json`` (step rate, collisions, stale and bad commands,
bound violations) when it stops; ``formation_report`` turns them into metrics and figures.
"""

from collections import deque, OrderedDict
import json
import os
import time

from diagnostic_msgs.msg import DiagnosticArray
from formation_ros.ros import fields, messages, qos
from formation_ros.core.frames import desired_positions, to_frame_velocity
from formation_ros.core.metrics import closest_pair_distance, compute_metrics
from formation_ros.ros.markers import formation_markers
from formation_ros.nodes.common import (declare_and_validate, diagnostics, DIAGNOSTICS_PERIOD,
                                        OnceLog, run)
from formation_ros.tools.report import PLANT_STATS
from formation_ros.core.trajectory import Trajectory
from geometry_msgs.msg import PoseArray, PoseStamped, TwistStamped
import numpy as np
from rclpy.clock import Clock, ClockType
from rclpy.node import Node
from rosgraph_msgs.msg import Clock as ClockMsg
from scipy.spatial import cKDTree
from visualization_msgs.msg import MarkerArray

LOCKSTEP_POLL = 0.001
RESEND_AFTER = 0.05
STATE_BUFFER = 512
BOUND_TOLERANCE_FIXED = 1e-9
BOUND_TOLERANCE_MOVING = 1e-3
PATH_LENGTH = 100


class PlantNode(Node):
    """Integrates every robot, simulates their range sensors, publishes the simulated clock."""

    def __init__(self, **kwargs):
        """Declare and check parameters, then set up topics and the step timer."""
        super().__init__('plant', **kwargs)
        config = declare_and_validate(self, 'plant')
        values = config.values
        self.config = config
        self.law = config.law()
        self.reference = config.reference()
        self.n, self.dim = config.num_robots, config.dim
        self.radii = config.sensing_radii
        self.q = config.start.copy()
        self.tree = cKDTree(self.q)
        self.step_ns = int(round(1e9 / values['plant.rate']))
        self.t_ns = 0
        self.steps = 0
        self.lockstep = values['plant.lockstep']
        self.publish_every = 1 if self.lockstep else max(
            1, int(round(values['plant.rate'] / values['plant.publish_rate'])))
        self.timeout_ns = int(values['plant.input_timeout'] * 1e9)
        self.collision_distance = values['plant.collision_distance']
        self.realtime_factor = values['plant.realtime_factor']
        self.output_dir = values['plant.output_dir']
        self.bound_tolerance = (BOUND_TOLERANCE_FIXED if self.reference.is_stationary
                                else BOUND_TOLERANCE_MOVING)
        self.once = OnceLog(self.get_logger())
        self.steady = Clock(clock_type=ClockType.STEADY_TIME)

        self.commands = [None] * self.n
        self.checked = [None] * self.n
        self.states = OrderedDict()
        self.history = []
        self.counts = {'stale_command_steps': 0, 'bound_violations': 0, 'collisions': 0,
                       'bad_command_steps': 0}
        self.colliding = set()
        self.last_publish_wall = None
        self.started_wall = None
        self.waiting = values['plant.wait_for_robots'] or self.lockstep
        self.wait_subscribers = values['plant.wait_for_subscribers']
        self.paths = deque(maxlen=PATH_LENGTH)
        self.rate_window = (time.monotonic(), 0)

        self.pose_pubs, self.neighbor_pubs = [], []
        for i in range(1, self.n + 1):
            self.pose_pubs.append(self.create_publisher(PoseStamped, f'robot_{i}/pose',
                                                        qos.STATE))
            self.neighbor_pubs.append(self.create_publisher(PoseArray, f'robot_{i}/neighbors',
                                                            qos.STATE))
            self.create_subscription(TwistStamped, f'robot_{i}/cmd_vel',
                                     lambda msg, index=i - 1: self.on_command(index, msg),
                                     qos.COMMAND)
        self.clock_pub = self.create_publisher(ClockMsg, '/clock', qos.CLOCK)
        self.diagnostics_pub = self.create_publisher(DiagnosticArray, '/diagnostics',
                                                     qos.DIAGNOSTICS)
        period = LOCKSTEP_POLL if self.lockstep else self.step_ns / 1e9 / self.realtime_factor
        self.timer = self.create_timer(period, self.on_timer, clock=self.steady)
        self.diagnostics_timer = self.create_timer(DIAGNOSTICS_PERIOD, self.on_diagnostics,
                                                   clock=self.steady)
        if values['plant.marker_rate'] > 0.0:
            self.marker_pub = self.create_publisher(MarkerArray, '/formation/markers',
                                                    qos.MARKERS)
            self.marker_timer = self.create_timer(1.0 / values['plant.marker_rate'],
                                                  self.on_markers, clock=self.steady)
        self.get_logger().info(
            f'plant: {self.n} robots in {self.dim}D, dt = {self.step_ns / 1e9:g} s, '
            f'reference {self.reference.kind}, '
            + ('lockstep' if self.lockstep else f'realtime factor {self.realtime_factor:g}'))

    def on_command(self, index, msg):
        """Store robot ``index``'s latest command."""
        self.commands[index] = msg

    def _command_array(self):
        """Commands held over the coming step: (N, dim); stale or bad ones count as zero."""
        u = np.zeros((self.n, self.dim))
        for i, msg in enumerate(self.commands):
            if msg is None:
                continue
            age = self.t_ns - fields.stamp_to_ns(msg.header.stamp)
            velocity = fields.velocity_of(msg, self.dim)
            if not np.all(np.isfinite(velocity)):
                self.counts['bad_command_steps'] += 1
                self.once.start(f'bad-{i}', f'robot {i + 1} sent a non-finite command; using '
                                            'zero (logged once; counted in bad_command_steps)',
                                'error')
                continue
            if age > self.timeout_ns:
                self.counts['stale_command_steps'] += 1
                self.once.start(f'stale-{i}', f'robot {i + 1}: latest command is '
                                              f'{age / 1e9:.3g} s old; using zero')
                continue
            self.once.end(f'stale-{i}', f'robot {i + 1}: commands fresh again')
            u[i] = velocity
            self._check_bound(i, msg, velocity)
        return u

    def _check_bound(self, index, msg, velocity):
        """Count a new command whose bounded part u_hat (eq. 14) exceeds c * M1."""
        stamp = fields.stamp_to_ns(msg.header.stamp)
        if self.checked[index] == stamp:
            return
        self.checked[index] = stamp
        if self.reference.is_stationary:
            u_hat = velocity
        else:
            q = self.states.get(stamp)
            if q is None:
                return
            frame = self.reference.sample(stamp / fields.NS_PER_S)
            u_hat = to_frame_velocity(velocity[None, :], q[index][None, :], frame)[0]
        excess = float(np.max(np.abs(u_hat))) - self.law.u_bound
        if excess > self.bound_tolerance:
            self.counts['bound_violations'] += 1
            self.get_logger().error(
                f'robot {index + 1}: command component {excess + self.law.u_bound:.6g} m/s '
                f'above the bound c*M1 = {self.law.u_bound:.6g} m/s '
                f"({self.counts['bound_violations']} so far)", throttle_duration_sec=1.0)

    def _check_collisions(self):
        pairs = {tuple(p) for p in self.tree.query_pairs(self.collision_distance)}
        for i, j in pairs - self.colliding:
            self.counts['collisions'] += 1
            self.get_logger().error(
                f'collision: robots {i + 1} and {j + 1} are '
                f'{np.linalg.norm(self.q[i] - self.q[j]):.3g} m apart at t = '
                f'{self.t_ns / 1e9:.3f} s (< plant.collision_distance)')
        self.colliding = pairs

    def _publish_state(self):
        stamp = self.t_ns
        self.states[stamp] = self.q.copy()
        while len(self.states) > STATE_BUFFER:
            self.states.popitem(last=False)
        seen = self.tree.query_ball_point(self.q, r=self.radii)
        for i in range(self.n):
            others = [j for j in seen[i]
                      if j != i and np.sum((self.q[j] - self.q[i]) ** 2) < self.radii[i] ** 2]
            self.pose_pubs[i].publish(messages.pose_stamped(self.q[i], stamp, self.dim))
            self.neighbor_pubs[i].publish(messages.pose_array(self.q[others], stamp, self.dim))
        self.last_publish_wall = time.monotonic()

    def _publish_clock(self):
        self.clock_pub.publish(ClockMsg(clock=messages.ns_to_stamp(self.t_ns)))

    def _advance(self, u):
        """One zero-order-hold step of q' = u, then the collision check."""
        if self.steps % self.publish_every == 0:
            self.history.append((self.t_ns, self.q.copy(), u.copy()))
        self.q = self.q + (self.step_ns / 1e9) * u
        self.tree = cKDTree(self.q)
        self.t_ns += self.step_ns
        self.steps += 1
        self._check_collisions()

    def _resend_if_due(self):
        if time.monotonic() - self.last_publish_wall > RESEND_AFTER:
            self._publish_clock()
            self._publish_state()

    def _all_robots_up(self):
        """While waiting: start the clock once every robot has sent a command."""
        missing = [i + 1 for i, msg in enumerate(self.commands) if msg is None]
        unheard = [i + 1 for i, pub in enumerate(self.pose_pubs)
                   if pub.get_subscription_count() < self.wait_subscribers]
        if missing or unheard:
            self.once.start('waiting', f'waiting for {len(missing)} of {self.n} robots to send '
                                       f'a command (robots {missing[:10]}'
                                       f"{'...' if len(missing) > 10 else ''}) and for "
                                       f'{self.wait_subscribers} subscribers on every pose '
                                       'topic', 'info')
            self._resend_if_due()
            return False
        self.waiting = False
        self.started_wall = time.monotonic()
        self.rate_window = (self.started_wall, self.steps)
        self.once.end('waiting', f'all {self.n} robots are up: starting the clock')
        self._publish_clock()
        self._publish_state()
        return True

    def on_timer(self):
        """Free-running: one step per tick. Lockstep: step when every robot has answered."""
        if self.started_wall is None:
            self.started_wall = time.monotonic()
            self._publish_clock()
            self._publish_state()
            return
        if self.waiting and not self._all_robots_up():
            return
        if self.lockstep:
            self._lockstep_tick()
            return
        u = self._command_array()
        self._advance(u)
        self._publish_clock()
        if self.steps % self.publish_every == 0:
            self._publish_state()

    def _lockstep_tick(self):
        answered = all(msg is not None and fields.stamp_to_ns(msg.header.stamp) == self.t_ns
                       for msg in self.commands)
        ahead = (self.t_ns / 1e9) > self.realtime_factor * (time.monotonic() - self.started_wall)
        if answered and not ahead:
            self._advance(self._command_array())
            self._publish_clock()
            self._publish_state()
        else:
            self._resend_if_due()

    def on_diagnostics(self):
        """Publish the plant's status: step rate, stale commands, distances, bound, collisions."""
        now = time.monotonic()
        since, steps = self.rate_window
        rate = (self.steps - steps) / (now - since) if now > since else 0.0
        self.rate_window = (now, self.steps)
        target = self.realtime_factor / (self.step_ns / 1e9)
        closest = closest_pair_distance(self.q)
        values = {'simulated time [s]': self.t_ns / 1e9, 'steps': self.steps,
                  'step rate achieved [Hz]': rate,
                  'step rate target [Hz]': 'lockstep' if self.lockstep else target,
                  'min pair distance [m]': closest,
                  'bound c*M1 [m/s]': self.law.u_bound}
        values.update(self.counts)
        if self.counts['collisions'] or self.counts['bound_violations']:
            level, message = 'error', (f"{self.counts['collisions']} collisions, "
                                       f"{self.counts['bound_violations']} commands above "
                                       'the bound')
        elif self.waiting:
            level, message = 'ok', 'waiting for the robots'
        elif not self.lockstep and rate < 0.9 * target:
            level, message = 'warn', f'stepping at {rate:.1f} Hz of {target:.1f} Hz'
        else:
            level, message = 'ok', 'running'
        self.diagnostics_pub.publish(diagnostics(self.get_clock().now().to_msg(),
                                                 'formation_ros/plant', level, message, values))

    def on_markers(self):
        """Publish the RViz picture: robots, sensing and repulsion zones, formation, paths."""
        self.paths.append(self.q.copy())
        frame = self.reference.sample(self.t_ns / fields.NS_PER_S)
        desired = desired_positions(self.config.vertices, frame)
        self.marker_pub.publish(formation_markers(self.q, self.radii, self.law.repulsion_radius,
                                                  desired, np.array(self.paths), self.t_ns))

    def trajectory(self):
        """Return the run so far as a Trajectory (a sample per published state)."""
        if not self.history:
            return None
        t = np.array([entry[0] for entry in self.history]) / 1e9
        frames = [self.reference.sample(time_s) for time_s in t]
        return Trajectory.from_frames(t, [entry[1] for entry in self.history],
                                      [entry[2] for entry in self.history], frames,
                                      self.config.vertices)

    def finish(self):
        """Log a summary of the run; with ``plant.output_dir`` write trajectory and counters."""
        trajectory = self.trajectory()
        if trajectory is None:
            self.get_logger().info('plant: stopped before the first step')
            return
        wall = time.monotonic() - self.started_wall
        stats = {'integrator': f'plant, zero-order hold, dt = {self.step_ns / 1e9:g} s'
                               + (', lockstep' if self.lockstep else ''),
                 'steps': self.steps, 'simulated_time': self.t_ns / 1e9, 'wall_time': wall,
                 'achieved_step_rate': self.steps / wall if wall > 0 else None}
        stats.update(self.counts)
        metrics = compute_metrics(trajectory.t, trajectory.q, trajectory.u, trajectory.u_hat,
                                  trajectory.q_desired, self.law.u_bound)
        self.get_logger().info(
            f'plant: {self.steps} steps ({self.t_ns / 1e9:.2f} s simulated in {wall:.1f} s), '
            f"final max error {metrics['final_max_error']:.3g} m, min pair distance "
            f"{metrics['min_pair_distance']:.4g} m, max |u_hat| "
            f"{metrics['max_abs_u_hat_component']:.4g} m/s (bound {self.law.u_bound:.4g}), "
            f"{self.counts['collisions']} collisions, {self.counts['bound_violations']} "
            f"commands above the bound, {self.counts['stale_command_steps']} stale commands")
        if self.output_dir:
            os.makedirs(self.output_dir, exist_ok=True)
            trajectory.save(os.path.join(self.output_dir, 'trajectory.npz'))
            with open(os.path.join(self.output_dir, PLANT_STATS), 'w',
                      encoding='utf-8') as stream:
                json.dump(stats, stream, indent=2)
                stream.write('\n')
            self.get_logger().info(f'plant: wrote trajectory.npz and {PLANT_STATS} to '
                                   f'{self.output_dir}')


def main(args=None):
    """Entry point of ``ros2 run formation_ros plant``."""
    return run(PlantNode, args, name='plant')
