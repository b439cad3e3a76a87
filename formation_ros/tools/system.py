# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
What a formation run starts, in one place: the launcher and the launch files plan from here.

A run is the simulated system (``plant``, ``reference`` and the robots on the plant's simulated
time), a lab (``relay`` instead of the plant, turning measured poses into each robot's pose
and neighbours; reference and robots on wall-clock time, as there is no ``/clock``) or a
simulated lab (the physics ``world`` with the relay on its measured poses; relay, reference
and robots on the world's ``/clock``), with the recorder in front when recording.
:func:`plan` returns its nodes as :class:`NodePlan` s: the executable, namespace, own
arguments, parameter overrides (on top of the one parameters file) and remappings.
``formation_ros.tools.launcher`` turns them into command lines (:func:`ros_arguments`),
``launch/formation.launch.py``, ``launch/lab.launch.py`` and ``launch/world.launch.py`` into
``launch_ros`` nodes (:func:`launch_nodes`), so that the two ways to start a run cannot drift
apart. The discovery settings of the nodes (:func:`network_variables`), which processes end the
run (:data:`ESSENTIAL`) and the order of stopping (:func:`stop_stages`) are also shared; a
launch file ends on any node's exit and ``ros2 launch`` signals every node at once.

Only the standard library and ``formation_ros.ros.topics`` (the topic names, no ROS) are
imported at the top (the launcher's ``--help`` needs no more); the parameter code and
``launch_ros`` are imported where they are used.
"""

import dataclasses
import os
import re
from typing import Any, Dict, List, Mapping, Optional, Sequence, Tuple

from formation_ros.core.settings.exits import RECORDING_FAILED
from formation_ros.core.settings.names import robot_name
from formation_ros.ros.topics import CMD_VEL, robot_namespace, robot_topic

PACKAGE = 'formation_ros'
SHARED_LAUNCH_ARGUMENTS = (
    ('discovery', '', "'localhost' or 'subnet' (empty: the environment's "
                      'ROS_AUTOMATIC_DISCOVERY_RANGE, else localhost)'),
    ('domain_id', '', "ROS_DOMAIN_ID of the nodes (empty: the environment's)"),
    ('record', '', 'rosbag2 directory to record into (empty: none)'),
    ('on_record_failure', 'continue', "'continue' or 'stop': whether the team goes on when "
                                      'the recorder cannot write its bag (a full disk)'),
)
"""(name, default, description) of the launch arguments both launch files take."""
ON_RECORD_FAILURE = ('continue', 'stop')
"""What a run does when its recorder exits RECORDING_FAILED; the first is the default."""
DISCOVERY = ('localhost', 'subnet')
DISCOVERY_ENV = 'ROS_AUTOMATIC_DISCOVERY_RANGE'
DOMAIN_ENV = 'ROS_DOMAIN_ID'
LOCALHOST_ONLY_ENV = 'ROS_LOCALHOST_ONLY'
MAX_DOMAIN_ID = 232
TOPIC_NAME = re.compile(r'(/[A-Za-z_][A-Za-z0-9_]*)+')
"""An absolute ROS 2 topic name: tokens of letters, digits and '_', none starting with a digit."""
FLEET_REMAP = ('cannot be used with more than one robot per process: the ROS arguments of a '
               "fleet apply to all of its robots (each named 'robot'), so their cmd_vel "
               'cannot be remapped one by one')
RECORDER = 'record'
WORLD = 'world'
ESSENTIAL = ('plant', WORLD, 'relay', 'reference', RECORDER)
"""The processes whose end ends a run; the launcher's ``--on-exit`` says what a robot's does."""


class PlanError(ValueError):
    """A run that cannot be planned as asked: one line that names the option at fault."""


@dataclasses.dataclass(frozen=True)
class NodePlan:
    """
    One process of a run.

    name: the process's name for the launcher's output (``robot_3``, ``fleet_2``, ``relay``);
    namespace: absolute (``/robot_3``) or None; arguments: the executable's own arguments,
    before ``--ros-args``; parameters: (name, value) overrides on top of the parameters file,
    in order; remappings: (from, to) topic remappings.
    """

    name: str
    executable: str
    namespace: Optional[str] = None
    arguments: Tuple[str, ...] = ()
    parameters: Tuple[Tuple[str, Any], ...] = ()
    remappings: Tuple[Tuple[str, str], ...] = ()


@dataclasses.dataclass(frozen=True)
class Run:
    """
    What to start.

    plant: the simulated system (False: a lab, the relay instead of the plant); world: a
    simulated lab (with ``plant`` False: the world and the relay on its measured poses, every
    node on the world's /clock); record: bag directory of the recorder (None: no recorder);
    output_dir: where the plant or the world writes its trajectory (None: nowhere);
    robots_per_process: above 1, ``fleet`` processes;
    cmd_topics: robot i's command topic at index i - 1 (empty: ``/robot_<i>/cmd_vel``, no
    remapping); source_topic: ``relay.source_topic`` for the relay (None: the file's);
    relay_rate: ``relay.rate`` of the file (Hz), the rate of the robots' states beside a world.
    """

    num_robots: int
    plant: bool = True
    world: bool = False
    record: Optional[str] = None
    output_dir: Optional[str] = None
    robots_per_process: int = 1
    cmd_topics: Tuple[str, ...] = ()
    source_topic: Optional[str] = None
    relay_rate: float = 50.0


@dataclasses.dataclass(frozen=True)
class Formation:
    """What a run needs of its parameters file: robots, default length, command topics."""

    num_robots: int
    wall_seconds: float
    """Default length of a run, s: ``duration`` / ``plant.realtime_factor`` (a lab: real time;
    a world: ``duration`` / ``world.realtime_factor``)."""
    cmd_topics: Tuple[str, ...] = ()
    relay_rate: float = 50.0


def plan(run: Run) -> List[NodePlan]:
    """
    Return the nodes of ``run`` in the order they start.

    The recorder first (it must hear everything), then the plant, the world and the relay,
    or the relay, the reference node and the robots. With the plant the reference and the
    robots run on its ``/clock``; beside a world the relay does too, and the robots are given
    the relay's rate as that of their states (``core.settings.params.world_robot_rates``); in a lab
    they are told ``use_sim_time: false`` (a file that says otherwise would stop them). A robot's
    first command waits for 1 subscriber of its cmd_vel (the plant, the world, or in a lab the
    base driver on the remapped topic), 2 when the recorder listens too (remapped onto the
    same topics). Raises PlanError for remapped commands in fleets.
    """
    nodes = [] if run.record is None else [recorder_plan(run.record, run.cmd_topics)]
    if run.plant:
        plant: List[Tuple[str, Any]] = []
        if run.output_dir is not None:
            plant.append(('plant.output_dir', run.output_dir))
        if run.record is not None:
            plant.append(('plant.wait_for_subscribers', 2))
        nodes.append(NodePlan('plant', 'plant', parameters=tuple(plant)))
    else:
        if run.world:
            world = (() if run.output_dir is None
                     else (('world.output_dir', run.output_dir),))
            nodes.append(NodePlan(WORLD, WORLD, parameters=world))
        relay: Tuple[Tuple[str, Any], ...] = (() if run.source_topic is None
                                              else (('relay.source_topic', run.source_topic),))
        if run.world:
            relay += (('use_sim_time', True),)
        nodes.append(NodePlan('relay', 'relay', parameters=relay))
    sim_time = ('use_sim_time', run.plant or run.world)
    nodes.append(NodePlan('reference', 'reference', parameters=(sim_time,)))
    robot: Tuple[Tuple[str, Any], ...] = (
        ('wait_for_subscribers', 2 if run.record is not None else 1), sim_time)
    if run.world:
        from formation_ros.core.settings.params import world_robot_rates
        robot += world_robot_rates(run.relay_rate)
    per_process = run.robots_per_process
    if per_process == 1:
        for i in range(1, run.num_robots + 1):
            remaps = (((CMD_VEL, run.cmd_topics[i - 1]),) if run.cmd_topics else ())
            nodes.append(NodePlan(robot_name(i), 'robot', namespace=robot_namespace(i),
                                  parameters=(('robot_id', i),) + robot, remappings=remaps))
        return nodes
    if run.cmd_topics:
        raise PlanError(f'remapped commands {FLEET_REMAP}')
    for k, first in enumerate(range(1, run.num_robots + 1, per_process), start=1):
        last = min(first + per_process - 1, run.num_robots)
        nodes.append(NodePlan(f'fleet_{k}', 'fleet', arguments=('--robots', f'{first}-{last}'),
                              parameters=robot))
    return nodes


def recorder_plan(record: str, cmd_topics: Sequence[str] = ()) -> NodePlan:
    """
    Return the recorder writing into ``record``, hearing robot i's commands on cmd_topics[i-1].

    It subscribes to ``/robot_<i>/cmd_vel`` (and stores it under that name, which
    ``formation_report`` reads); with command topics that is remapped onto each of them.
    """
    remaps = tuple((robot_topic(i, CMD_VEL), topic)
                   for i, topic in enumerate(cmd_topics, start=1))
    return NodePlan(RECORDER, RECORDER, parameters=(('record.path', record),),
                    remappings=remaps)


def stop_stages(names: Sequence[str]) -> List[List[str]]:
    """
    Return the processes ``names`` in the order to stop them: groups stopped together.

    Every node but the recorder first, then the recorder, so that it still hears their last
    messages.
    """
    stages = [[name for name in names if name != RECORDER]]
    if RECORDER in names:
        stages.append([RECORDER])
    return stages


def ros_value(value: Any) -> str:
    """Return ``value`` as ``-p name:=value`` writes it (``true``/``false`` for booleans)."""
    if isinstance(value, bool):
        return 'true' if value else 'false'
    return str(value)


def ros_arguments(node: NodePlan, params_file: str) -> List[str]:
    """Return the arguments after the executable that start ``node`` with ``params_file``."""
    args = list(node.arguments) + ['--ros-args']
    if node.namespace is not None:
        args += ['-r', f'__ns:={node.namespace}']
    args += ['--params-file', params_file]
    for name, value in node.parameters:
        args += ['-p', f'{name}:={ros_value(value)}']
    for source, target in node.remappings:
        args += ['-r', f'{source}:={target}']
    return args


def launch_file_nodes(arguments: Mapping[str, str], plant: bool = True,
                      world: bool = False) -> List[Any]:
    """
    Return the ``launch_ros`` nodes of a launch file for its launch arguments' values.

    arguments: ``params_file``, ``record``, ``robots_per_process``, ``discovery``,
    ``domain_id``, and ``output_dir`` (with the plant: ``launch/formation.launch.py``; with
    ``world``: ``launch/world.launch.py``) or ``cmd_topic`` and ``source_topic`` (a lab:
    ``launch/lab.launch.py``); '' is not given. The parameters file is checked as the launcher
    checks it. Raises ValueError (ParamError, PlanError) with what is wrong.
    """
    params_file = arguments['params_file']
    per_process = int(arguments.get('robots_per_process') or 1)
    if per_process < 1:
        raise PlanError(f'robots_per_process must be >= 1, got {per_process}')
    on_record_failure = arguments.get('on_record_failure') or ON_RECORD_FAILURE[0]
    if on_record_failure not in ON_RECORD_FAILURE:
        raise PlanError(f"on_record_failure must be one of {', '.join(ON_RECORD_FAILURE)}, "
                        f"got '{on_record_failure}'")
    domain_id = arguments.get('domain_id') or None
    if domain_id is not None and domain_problem(domain_id):
        raise PlanError(f'domain_id {domain_problem(domain_id)}')
    env = network_variables(arguments.get('discovery') or None,
                            None if domain_id is None else int(domain_id), os.environ)
    formation = read_formation(params_file, plant=plant and not world,
                               cmd_topic=arguments.get('cmd_topic') or None,
                               source_topic=arguments.get('source_topic') or None,
                               robots_per_process=per_process, world=world)
    run = Run(formation.num_robots, plant=plant and not world, world=world,
              record=arguments.get('record') or None,
              output_dir=arguments.get('output_dir') or None, robots_per_process=per_process,
              cmd_topics=formation.cmd_topics,
              source_topic=arguments.get('source_topic') or None,
              relay_rate=formation.relay_rate)
    return launch_nodes(plan(run), params_file, env, on_record_failure)


def launch_nodes(nodes: Sequence[NodePlan], params_file: str, env: Mapping[str, Optional[str]],
                 on_record_failure: str = ON_RECORD_FAILURE[0]) -> List[Any]:
    """
    Return the ``launch`` actions that start ``nodes``: what the launch files start.

    Each node with the parameters file and its overrides, a relative namespace (so that a
    ``PushRosNamespace`` around the launch file still applies), its remappings, ``env`` added
    to its environment, and a Shutdown when it exits: the first node to end ends the launch.
    The recorder's exit with RECORDING_FAILED ends it only with ``on_record_failure`` 'stop'.
    The variables that ``env`` maps to None are unset first (UnsetEnvironmentVariable).
    """
    from launch.actions import Shutdown, UnsetEnvironmentVariable
    from launch_ros.actions import Node
    launched: List[Any] = [UnsetEnvironmentVariable(name)
                           for name, value in env.items() if value is None]
    added = {name: value for name, value in env.items() if value is not None}
    for node in nodes:
        on_exit: Any = Shutdown(reason=f'{node.executable} exited')
        if node.executable == RECORDER and on_record_failure == 'continue':
            on_exit = RecorderExit(on_exit)
        parameters: List[Any] = [params_file]
        if node.parameters:
            parameters.append(dict(node.parameters))
        launched.append(Node(
            package=PACKAGE, executable=node.executable,
            namespace=None if node.namespace is None else node.namespace.lstrip('/'),
            arguments=list(node.arguments) or None, parameters=parameters,
            remappings=list(node.remappings) or None, additional_env=dict(added),
            output='screen', on_exit=on_exit))
    return launched


@dataclasses.dataclass(frozen=True)
class RecorderExit:
    """
    The recorder's ``on_exit`` in a launch file that goes on after a failed recording.

    Called by launch with the ProcessExited event: ``shutdown`` (the launch's end) unless the
    recorder exited RECORDING_FAILED, when launch has already printed the exit code and the
    recorder its one line, and the team goes on.
    """

    shutdown: Any

    def __call__(self, event: Any, context: Any) -> Optional[Any]:
        """Return the actions to take when the recorder has exited."""
        return None if event.returncode == RECORDING_FAILED else self.shutdown


def discovery_problem(discovery: str) -> Optional[str]:
    """Return what is wrong with a discovery range ('' and None are not checked here)."""
    if discovery in DISCOVERY:
        return None
    return f"must be one of {', '.join(DISCOVERY)}, got {discovery!r}"


def domain_problem(domain_id: str) -> Optional[str]:
    """Return what is wrong with a ROS_DOMAIN_ID given as text, or None."""
    if re.fullmatch(r'[0-9]{1,3}', domain_id) and int(domain_id) <= MAX_DOMAIN_ID:
        return None
    return f'must be a whole number from 0 to {MAX_DOMAIN_ID}, got {domain_id!r}'


def network_variables(discovery: Optional[str], domain_id: Optional[int],
                      base: Mapping[str, str]) -> Dict[str, Optional[str]]:
    """
    Return the variables to set (None: to unset) in the nodes' environment ``base``.

    ``discovery`` sets ROS_AUTOMATIC_DISCOVERY_RANGE (LOCALHOST or SUBNET) and unsets the
    deprecated ROS_LOCALHOST_ONLY, which rcl would honour over it; without it a range already
    in ``base`` is kept, and LOCALHOST is set where there is none (so that a run on one
    computer stays there; ROS's own default is SUBNET). ``domain_id`` sets ROS_DOMAIN_ID.
    Raises PlanError for a range other than :data:`DISCOVERY`.
    """
    env: Dict[str, Optional[str]] = {}
    if discovery:
        problem = discovery_problem(discovery)
        if problem:
            raise PlanError(f'discovery {problem}')
        env[DISCOVERY_ENV] = discovery.upper()
        if LOCALHOST_ONLY_ENV in base:
            env[LOCALHOST_ONLY_ENV] = None
    elif not base.get(DISCOVERY_ENV):
        env[DISCOVERY_ENV] = 'LOCALHOST'
    if domain_id is not None:
        env[DOMAIN_ENV] = str(domain_id)
    return env


def with_variables(base: Mapping[str, str], variables: Mapping[str, Optional[str]]
                   ) -> Dict[str, str]:
    """Return ``base`` with ``variables`` set, those mapped to None removed."""
    env = {name: value for name, value in base.items() if variables.get(name, '') is not None}
    env.update({name: value for name, value in variables.items() if value is not None})
    return env


def topics_of(template: str, num_robots: int, names: Sequence[str],
              option: str) -> Tuple[str, ...]:
    """
    Return robot 1..N's topics from a template (``{i}`` id, ``{name}`` relay.source_names).

    The same checks as ``relay.source_topic`` (``core.settings.params.template_problems``), and
    every topic must be an absolute ROS name. Raises PlanError naming ``option``, one line.
    """
    from formation_ros.core.settings.params import fill_template, template_problems
    problems = template_problems(template, names, num_robots, template_key=option)
    if problems:
        key, message = problems[0]
        raise PlanError(f'{key} {message}')
    topics = tuple(fill_template(template, i, names) for i in range(1, num_robots + 1))
    for i, topic in enumerate(topics, start=1):
        if not TOPIC_NAME.fullmatch(topic):
            raise PlanError(f'{option} {template!r} gives robot {i} {topic!r}, not an absolute '
                            "ROS topic name ('/', then letters, digits and '_', no token "
                            'starting with a digit)')
    return topics


def read_formation(params_file: str, plant: bool = True, cmd_topic: Optional[str] = None,
                   source_topic: Optional[str] = None, robots_per_process: int = 1,
                   cmd_option: str = 'cmd_topic', source_option: str = 'source_topic',
                   world: bool = False) -> Formation:
    """
    Check ``params_file`` for every program a run starts; return what the run needs of it.

    cmd_topic: template of the robots' command topics (None: no remapping); source_topic:
    ``relay.source_topic`` instead of the file's (None: the file's); cmd_option /
    source_option: how the caller spells them (``--cmd-topic``); world: a simulated lab (the
    world node too; ``plant`` is then False). Raises ParamError for the file, PlanError (one
    line, naming the option) for the templates, for a lab (no ``plant``) with ``transport:
    team`` and for a world whose relay would not read it (:func:`world_problem`).
    """
    from formation_ros.core.settings.declarations import Exe, ParamError
    from formation_ros.core.settings.params import validate, validate_for_every_executable
    from formation_ros.core.settings.params_file import load_params_file
    raw = load_params_file(params_file)
    if source_topic is not None:
        raw['relay.source_topic'] = source_topic
    try:
        checked = validate_for_every_executable(raw)
        if world:
            checked[Exe.WORLD] = validate(raw, Exe.WORLD)
    except ParamError as exc:
        mine = [line for line in (f'{key} {message}' for key, message in exc.problems)
                if 'relay.source_topic' in line]
        if source_topic is not None and mine:
            raise PlanError(mine[0].replace('relay.source_topic', source_option)) from None
        raise
    config = checked[Exe.PLANT]
    assert config.plant is not None
    relay = checked[Exe.RELAY].relay
    assert relay is not None
    if not plant and config.team_transport:
        raise PlanError("transport team needs the plant: the relay serves each robot's own "
                        'topics (set transport: robot in a lab)')
    if source_topic is not None:
        topics_of(source_topic, config.num_robots, relay.source_names, source_option)
    cmd_topics: Tuple[str, ...] = ()
    if cmd_topic is not None:
        if robots_per_process > 1:
            raise PlanError(f'{cmd_option} {FLEET_REMAP}')
        cmd_topics = topics_of(cmd_topic, config.num_robots, relay.source_names, cmd_option)
    factor = config.plant.realtime_factor if plant else 1.0
    if world:
        settings = checked[Exe.WORLD].world
        assert settings is not None
        factor = settings.realtime_factor
        problem = world_problem(checked[Exe.RELAY], config.lockstep, source_option)
        if problem is not None:
            raise PlanError(problem)
    return Formation(config.num_robots, config.duration / factor, cmd_topics, relay.rate)


def world_problem(config: Any, lockstep: bool = False,
                  source_option: str = 'source_topic') -> Optional[str]:
    """
    Return why the relay of ``config`` (a FormationConfig of the relay) cannot run on a world.

    lockstep: ``plant.lockstep`` of the file.
    The world publishes robot i's pose on ``/robot_<i>/measured_pose`` and, for unicycles, its
    wheel odometry on ``/robot_<i>/odom``: the relay must read one of them with its type. A
    lockstep file does not fit either: the world runs free.
    """
    from formation_ros.ros.topics import MEASURED_POSE, ODOM
    relay = config.relay
    assert relay is not None
    kind = relay.source_type.value
    topics = {'pose': MEASURED_POSE}
    if config.body.is_unicycle:
        topics['odometry'] = ODOM
    wanted = topics.get(kind)
    given = [relay.source(i) for i in range(1, config.num_robots + 1)]
    if wanted is None or given != [robot_topic(i, wanted)
                                   for i in range(1, config.num_robots + 1)]:
        first = robot_topic(1, wanted or MEASURED_POSE)
        return (f"the world's relay reads the world: relay.source_topic gives {given[0]!r} "
                f'({kind}) for robot 1, not {first!r}; remove relay.source_topic (and '
                f'relay.source_names, relay.source_type) from the file or pass {source_option} '
                f"'/robot_{{i}}/measured_pose'")
    if lockstep:
        return 'plant.lockstep does not fit a world: the world runs free (set it false)'
    return None
