# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""Two teams on one domain: refused at the plant's start, named while running, or avoided."""

from collections import Counter
import os
import re
from signal import SIGCONT, SIGSTOP
import socket
import subprocess
import time

from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus
from formation_ros.ros import messages, qos
from formation_ros.tools import domain
from geometry_msgs.msg import PoseStamped, TwistStamped
from helpers import (launch, LAUNCHER, logged, node, said_once, SimClock, SQUARE, Statuses,
                     stop_when, wait_exit, write_params)
from nav_msgs.msg import Odometry
import pytest
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
from rosgraph_msgs.msg import Clock as ClockMsg
import wire

pytestmark = pytest.mark.faults
START_UP = 90.0
HOST = socket.gethostname()


def value(statuses, name, key):
    """Return value ``key`` of status ``name`` if that status is an ERROR, else ''."""
    status = statuses.get(name)
    if status is None or status.level != DiagnosticStatus.ERROR:
        return ''
    return {kv.key: kv.value for kv in status.values}.get(key, '')


def error_lines(log):
    return [line for line in log.splitlines() if '[ERROR]' in line]


def test_a_second_plant_refuses_to_start_naming_the_first(processes, install, probe):
    clock = SimClock(probe)
    statuses = Statuses(probe)
    first = processes.start(node(install, 'plant', SQUARE, '-p', 'plant.wait_for_robots:=false'))
    assert probe.spin_until(lambda: clock.seconds > 0.5, START_UP), processes.log('plant')
    second = processes.start(node(install, 'plant', SQUARE, process='plant_2'))
    info = wait_exit(probe, processes, 'plant_2', START_UP)
    assert info is not None and info.returncode == 2, processes.log('plant_2')
    log = processes.log('plant_2')
    lines = error_lines(log)
    assert len(lines) == 1, log
    line = lines[0]
    assert f'another plant is on ROS_DOMAIN_ID {os.environ["ROS_DOMAIN_ID"]}' in line, line
    assert f'/plant on host {HOST} (process {first.pid})' in line, line
    assert 'Traceback' not in log and 'stopped before the first step' not in log, log
    named = f'another plant runs on this domain: /plant on host {HOST} (process {second.pid})'
    assert probe.spin_until(lambda: named in processes.log('plant'), 30), processes.log('plant')
    assert processes.running('plant')
    assert probe.spin_until(lambda: 'the other plant is gone' in processes.log('plant'), 60)
    assert processes.log('plant').count(named) == 1, processes.log('plant')
    assert probe.spin_until(lambda: statuses.get('formation_ros/plant') is not None
                            and statuses['formation_ros/plant'].level != DiagnosticStatus.ERROR,
                            30)


def test_a_plant_refuses_a_domain_with_another_clock(processes, install, probe):
    publisher = probe.create_publisher(ClockMsg, '/clock', qos.CLOCK)
    processes.start(node(install, 'plant', SQUARE))

    def tick():
        publisher.publish(ClockMsg())
        return not processes.running('plant')

    assert probe.spin_until(tick, START_UP), processes.log('plant')
    info = processes.exit_info('plant')
    assert info is not None and info.returncode == 2, processes.log('plant')
    lines = error_lines(processes.log('plant'))
    assert len(lines) == 1, processes.log('plant')
    assert 'another /clock publisher' in lines[0] and '/probe (host unknown' in lines[0], lines


def start_plant_and_robot_1(processes, install, probe):
    """Start a plant that does not wait for robots and robot 1; return robot 1 once time runs."""
    processes.start(node(install, 'plant', SQUARE, '-p', 'plant.wait_for_robots:=false'))
    robot = processes.start(node(install, 'robot', SQUARE, '-r', '__ns:=/robot_1',
                                 '-p', 'use_sim_time:=true', process='robot_1'))
    clock = SimClock(probe)
    assert probe.spin_until(lambda: clock.seconds > 0.5, START_UP), processes.log('plant')
    return robot


def test_a_running_plant_names_a_second_publisher_on_pose_and_cmd_vel(processes, install, probe):
    statuses = Statuses(probe)
    robot = start_plant_and_robot_1(processes, install, probe)
    commands = probe.create_publisher(TwistStamped, '/robot_1/cmd_vel', qos.COMMAND)
    poses = probe.create_publisher(PoseStamped, '/robot_1/pose', qos.STATE)

    def named():
        text = value(statuses, 'formation_ros/plant', 'topics with more than one publisher')
        return '/robot_1/cmd_vel: /probe' in text and '/robot_1/pose: /probe' in text

    assert probe.spin_until(named, 60), (statuses.get('formation_ros/plant'),
                                         processes.log('plant'))
    text = value(statuses, 'formation_ros/plant', 'topics with more than one publisher')
    assert '/robot_1/robot' in text.split('/robot_1/cmd_vel: ')[1], text
    lines = ('/robot_1/pose has more than one publisher: /probe',
             '/robot_1/cmd_vel has more than one publisher: /probe')
    for text in lines:
        assert said_once(probe, processes, 'plant', text, statuses,
                         'formation_ros/plant') == 1, processes.log('plant')

    def described(host):
        text = value(statuses, 'formation_ros/plant', 'topics with more than one publisher')
        return f'/robot_1/robot {host}' in text

    # A robot whose announcements lapse (a busy machine) is the same publisher still.
    os.kill(robot.pid, SIGSTOP)
    try:
        assert probe.spin_until(lambda: described('(silent on /diagnostics for'), 60), \
            processes.log('plant')
    finally:
        os.kill(robot.pid, SIGCONT)
    assert probe.spin_until(lambda: described(f'on host {HOST}'), 60), processes.log('plant')
    for text in lines:
        assert said_once(probe, processes, 'plant', text, statuses,
                         'formation_ros/plant') == 1, processes.log('plant')
    assert 'no longer publishing here' not in processes.log('plant')
    assert commands.topic_name == '/robot_1/cmd_vel' and poses.topic_name == '/robot_1/pose'


def test_the_clock_waits_for_its_subscribers_to_be_matched_then_not_for_ever(
        processes, install, probe):
    """A /clock reader asking for more than /clock offers is never matched: 5 s, then go."""
    unmatchable = QoSProfile(depth=1, reliability=ReliabilityPolicy.RELIABLE,
                             durability=DurabilityPolicy.TRANSIENT_LOCAL)
    probe.create_subscription(ClockMsg, '/clock', lambda message: None, unmatchable)
    clock = SimClock(probe)
    processes.start(node(install, 'plant', SQUARE))
    logged(probe, processes, 'plant', "subscription discovered on topic '/clock'",
           timeout=START_UP)
    processes.start(node(install, 'reference', SQUARE, '-p', 'use_sim_time:=true'))
    for i in range(1, 5):
        processes.start(node(install, 'robot', SQUARE, '-r', f'__ns:=/robot_{i}',
                             '-p', 'use_sim_time:=true', process=f'robot_{i}'))
    waiting = 'every robot is up: waiting for /clock to reach its subscribers'
    going = 'a /clock subscriber is still not matched after 5 s'
    log = logged(probe, processes, 'plant', waiting, going, timeout=START_UP)
    assert log.index(waiting) < log.index(going) < log.index('starting the clock'), log
    assert log.count(waiting) == 1 and log.count(going) == 1, log
    assert probe.spin_until(lambda: clock.seconds > 0.5, START_UP), processes.log('plant')


def test_a_robot_names_a_second_reference_publisher(processes, install, probe):
    statuses = Statuses(probe)
    processes.start(node(install, 'reference', SQUARE))
    processes.start(node(install, 'robot', SQUARE, '-r', '__ns:=/robot_1', process='robot_1'))
    forged = probe.create_publisher(Odometry, '/formation/reference', qos.REFERENCE)

    def named():
        forged.publish(wire.reference_odometry(None, probe.get_clock().now().nanoseconds, 2))
        text = value(statuses, 'formation_ros/robot_1', 'topics with more than one publisher')
        return '/formation/reference: /probe, /reference' in text

    assert probe.spin_until(named, START_UP), (statuses.get('formation_ros/robot_1'),
                                               processes.log('robot_1'))
    assert said_once(probe, processes, 'robot_1', '/formation/reference has more than one '
                     'publisher', statuses, 'formation_ros/robot_1') == 1, processes.log('robot_1')
    assert 'two teams on one domain' in processes.log('robot_1')


def test_a_robot_on_two_clocks_names_them_instead_of_advising_use_sim_time(
        processes, install, probe):
    """
    A second team's plant (its /clock and a pose 1000 s on) meets robot 1 of the first.

    The robot's clock follows the poses it accepted, not /clock: the other team's /clock
    leaves it alone, and its pose is refused as stamped on another clock, naming both clocks.
    """
    statuses = Statuses(probe)
    start_plant_and_robot_1(processes, install, probe)

    def pose_age():
        status = statuses.get('formation_ros/robot_1')
        values = {} if status is None else {kv.key: kv.value for kv in status.values}
        return values.get('pose message age [s]', 'never')

    assert probe.spin_until(lambda: pose_age() != 'never', START_UP), processes.log('robot_1')
    other = probe.create_publisher(ClockMsg, '/clock', qos.CLOCK)
    far = ClockMsg()
    far.clock = messages.ns_to_stamp(1000 * 10 ** 9)
    forged = probe.create_publisher(PoseStamped, '/robot_1/pose', qos.STATE)

    def refused():
        other.publish(far)
        forged.publish(wire.pose_stamped((0.0, 0.0), 1000 * 10 ** 9, 2))
        return 'stamps from another clock' in processes.log('robot_1')

    assert probe.spin_until(refused, START_UP), processes.log('robot_1')
    lines = [line for line in processes.log('robot_1').splitlines()
             if 'stamps from another clock' in line]
    for line in lines:
        assert '/clock has 2 publishers (/plant, /probe)' in line, line
        assert 'use_sim_time' not in line, line
    assert probe.spin_until(lambda: '/clock has more than one publisher: /plant, /probe'
                            in processes.log('robot_1'), 30), processes.log('robot_1')
    assert probe.spin_until(lambda: float(pose_age()) < 0.4, 30), (pose_age(),
                                                                   processes.log('robot_1'))


def test_the_launcher_runs_on_a_free_domain_of_its_own(processes, install, probe, tmp_path):
    """Without ROS_DOMAIN_ID the launcher takes a domain no participant of this host is on."""
    import rclpy
    held = next(d for d in domain.candidates(os.getuid()) if not domain.ports_busy(d))
    holder = rclpy.Context()
    rclpy.init(context=holder, domain_id=held)
    holder_node = rclpy.create_node('holder', context=holder)
    try:
        assert domain.ports_busy(held)
        env = dict(processes.env)
        env.pop('ROS_DOMAIN_ID')
        params = write_params(tmp_path, 'square_4.yaml', {})
        launch(processes, install, params, env=env, per_process=4)
        found = []

        def said():
            match = re.search(r'ROS_DOMAIN_ID ([0-9]+) \(a free domain of its own: [^;]+; to '
                              r'join it: export ROS_DOMAIN_ID=([0-9]+) before ros2 topic echo',
                              processes.log('launcher'))
            if match and not found:
                found.append(int(match.group(1)))
            return bool(found)

        assert probe.spin_until(said, START_UP), processes.log('launcher')
        first = processes.log('launcher').splitlines()[0]
        assert f'ROS_DOMAIN_ID {found[0]} (a free domain' in first, first
        assert found[0] != held and found[0] != int(os.environ['ROS_DOMAIN_ID'])
        joined = rclpy.Context()
        rclpy.init(context=joined, domain_id=found[0])
        listener = rclpy.create_node('listener', context=joined)
        heard = []
        listener.create_subscription(ClockMsg, '/clock', heard.append, qos.CLOCK)
        from rclpy.executors import SingleThreadedExecutor
        executor = SingleThreadedExecutor(context=joined)
        executor.add_node(listener)

        def joined_heard():
            executor.spin_once(timeout_sec=0.05)
            return len(heard) > 10

        try:
            info = stop_when(probe, processes, joined_heard)
        finally:
            executor.shutdown()
            listener.destroy_node()
            rclpy.shutdown(context=joined)
        assert info.returncode == 0, processes.log('launcher')[-3000:]
    finally:
        holder_node.destroy_node()
        rclpy.shutdown(context=holder)


def team_endpoints(probe, topics):
    """Return how many publishers and subscriptions each node has on each of ``topics``."""
    found = Counter()
    for topic in topics:
        for kind, infos in (('publisher', probe.get_publishers_info_by_topic(topic)),
                            ('subscription', probe.get_subscriptions_info_by_topic(topic))):
            found.update((topic, kind, info.node_namespace, info.node_name) for info in infos)
    return found


def children(pid):
    """Return the command lines of the running processes whose parent is ``pid``."""
    found = []
    for entry in os.listdir('/proc'):
        try:
            with open(f'/proc/{entry}/stat', encoding='ascii', errors='replace') as stream:
                parent = int(stream.read().rsplit(')', 1)[1].split()[1])
            if parent == pid:
                with open(f'/proc/{entry}/cmdline', 'rb') as stream:
                    found.append(stream.read().replace(b'\0', b' ').decode(errors='replace'))
        except (OSError, ValueError, IndexError):
            continue
    return found


def test_a_second_launcher_on_a_given_domain_refuses_before_starting_anything(
        processes, install, probe, tmp_path):
    """
    A team runs on the test's domain; a second launcher is given that domain twice.

    Once with --domain-id, once through ROS_DOMAIN_ID. Each looks at the graph before anything
    starts and exits 2 with one line naming the team's plant: no node process of its own, no
    --out directory, no publisher or subscription on the team's topics meanwhile, and the
    team's plant hears of nothing and ends normally.
    """
    clock = SimClock(probe)
    shared = []
    probe.create_subscription(DiagnosticArray, '/diagnostics', lambda message: shared.extend(
        kv.value for status in message.status for kv in status.values
        if kv.key == 'topics with more than one publisher'), qos.DIAGNOSTICS)
    launch(processes, install, SQUARE, per_process=4)
    assert probe.spin_until(lambda: clock.seconds > 1.0, START_UP), processes.log('launcher')
    topics = [name for name, _ in probe.get_topic_names_and_types()
              if name not in ('/parameter_events', '/rosout')]
    assert '/clock' in topics and '/robot_4/cmd_vel' in topics, topics
    before = team_endpoints(probe, topics)
    domain = os.environ['ROS_DOMAIN_ID']
    without = {k: v for k, v in processes.env.items() if k != 'ROS_DOMAIN_ID'}
    for option, env in ((['--domain-id', domain], without), ([], dict(processes.env))):
        out = tmp_path / f'out{len(option)}'
        second = subprocess.Popen(
            ['bash', LAUNCHER, SQUARE, '--duration', '0', '--no-plots', '--prefix', install,
             '--robots-per-process', '4', '--out', str(out), *option], env=env,
            stdin=subprocess.DEVNULL, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        started = time.monotonic()
        spawned, extra = set(), Counter()

        def looked():
            spawned.update(line for line in children(second.pid)
                           if f'{install}/lib/formation_ros/' in line)
            extra.update(team_endpoints(probe, topics) - before)
            return second.poll() is not None

        assert probe.spin_until(looked, 60), 'the second launcher did not end'
        out_text, err_text = second.communicate()
        took = time.monotonic() - started
        assert second.returncode == 2, (out_text, err_text)
        assert out_text == '', out_text
        lines = err_text.splitlines()
        assert len(lines) == 1, err_text
        how = f'--domain-id {domain}' if option else f'ROS_DOMAIN_ID={domain} in the environment'
        assert lines[0].startswith(f'launch_formation.sh: refusing to start: another team runs '
                                   f'on ROS_DOMAIN_ID {domain} ({how}): /plant (publishes '
                                   f'/clock) on this host ({HOST}); nothing was started.'), lines
        assert not spawned, spawned
        assert not extra, extra
        assert not out.exists()
        print(f'second launcher ({how}) refused in {took:.2f} s')
    seconds = clock.seconds
    info = stop_when(probe, processes, lambda: clock.seconds > seconds + 1.0)
    assert info.returncode == 0, processes.log('launcher')[-3000:]
    log = processes.log('launcher')
    assert 'more than one publisher' not in log and 'another plant' not in log, log[-3000:]
    assert not any(shared), shared
