# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
The formation launcher: plant (or relay, or world and relay), reference, N robots, the recorder.

``scripts/launch_formation.sh`` runs this module (``python -m formation_ros.tools.launcher``)
with an interpreter that can import the installed package; the options and messages are those
of :data:`USAGE`. Every node runs under :class:`formation_ros.tools.supervise.Supervisor`, its
output prefixed with its name. The run ends when the duration is over, on SIGINT, SIGTERM or
SIGHUP (the terminal closed), when the plant (the relay), the reference node or the recorder
ends on its own, or when a robot does with ``--on-exit stop`` (a robot that ends on its own is
otherwise left out or restarted); the nodes are then stopped in order (robots, reference and
plant or relay together, the recorder last) and, with ``--out`` or ``--record``,
``formation_report`` writes the metrics and figures. A recorder that could not write its bag
(exit code :data:`RECORDING_FAILED`) ends the run only with ``--on-record-failure stop``.
Exit codes: 0 done, 1 a node died or the report failed, 2 bad usage or parameters, or another
team on the domain the user gave (:func:`domain_refusal`, before anything starts),
:data:`RECORDING_FAILED` (74) the recording stopped early.

The nodes watch the launcher through its process id and start time in their environment
(``formation_ros.ros.watch``), so they end on their own when it is killed with SIGKILL.
"""

import dataclasses
import glob
import os
import re
import shutil
import signal
import socket
import subprocess
import sys
import time
from typing import Callable, Mapping, Optional, Sequence, TextIO

from formation_ros.core.settings.exits import RECORDING_FAILED, REFUSED
from formation_ros.ros.watch import watch_environment
from formation_ros.tools.domain import choose_domain, TeamLook, TeamSeen
from formation_ros.tools.supervise import describe_returncode, ExitInfo, ProcessSpec, Supervisor
from formation_ros.tools.system import (DISCOVERY, DISCOVERY_ENV, discovery_problem, DOMAIN_ENV,
                                        domain_problem, ESSENTIAL, FLEET_REMAP, Formation,
                                        network_variables, NodePlan, ON_RECORD_FAILURE, plan,
                                        PlanError, read_formation, RECORDER, recorder_plan,
                                        ros_arguments, Run, stop_stages, with_variables,
                                        WORLD)

PROG = 'launch_formation.sh'
PACKAGE = 'formation_ros'
STOP_TIMEOUT = 10.0
RECORDER_START_TIMEOUT = 15.0
POLL = 0.2
ON_EXIT = ('continue', 'stop', 'respawn')
MAX_RESTARTS = 5
WORLD_PARAMS_COPY = 'world_params.yaml'
"""The name of ``--world-params``'s file in ``--out``."""

USAGE = """\
Usage: scripts/launch_formation.sh PARAMS.yaml [--duration S] [--out DIR] [--record DIR]
                                   [--on-exit continue|stop|respawn]
                                   [--on-record-failure continue|stop]
                                   [--robots-per-process K] [--prefix DIR] [--no-plots]
                                   [--discovery localhost|subnet] [--domain-id N]
                                   [--no-plant [--cmd-topic TEMPLATE] [--source-topic TEMPLATE]]
                                   [--world [--world-params WORLD.yaml]]

Starts the plant, the reference node and N robot nodes (N = num_robots in PARAMS.yaml), robot i
in namespace /robot_<i>, all with the same parameters file, the reference node and robots
on the plant's simulated time (/clock). With --no-plant (a lab), the relay instead of the
plant, and the reference node and the robots on wall-clock time. Output lines are prefixed with
the node's name. With --world, a simulated lab: the physics world (MuJoCo) and the relay on
its measured poses instead of the plant, every node on the world's /clock. Stops every process
it started when the duration ends, on Ctrl-C, SIGTERM or SIGHUP (then still writes the report
of --out / --record), and when the plant (the world, the relay), the reference node or the
recorder exits on its own; what happens when a robot exits on its own is
set by --on-exit. If the launcher itself is killed (even with kill -9), every node notices
within 0.1 s and stops as on Ctrl-C.

Options:
  --duration S   wall-clock seconds to run; 0 runs until Ctrl-C
                 (default: 'duration' in PARAMS.yaml divided by plant.realtime_factor;
                 with --no-plant, 'duration' itself; with --world, divided by
                 world.realtime_factor)
  --out DIR      run directory: the plant writes trajectory.npz and plant_stats.json there
                 (the world: trajectory.npz, world.xml and world_stats.json),
                 PARAMS.yaml is copied there, and formation_report writes metrics.json and the
                 figures there at the end (the directory must not exist yet, or be empty).
                 With --no-plant only together with --record: the report is made from the bag
  --record DIR   record every formation topic into a rosbag2 directory DIR (metadata.yaml +
                 MCAP; DIR must not exist yet), started before the other nodes and stopped
                 after them; at the end formation_report reads the bag and writes
                 metrics.json and the figures (into --out if given, else into DIR). With
                 --cmd-topic the recorder hears the remapped command topics and stores them
                 as /robot_<i>/cmd_vel
  --on-exit MODE what to do when a robot exits on its own (default: continue):
                 continue: the others go on, the dead robot's body stays where it is;
                 stop:     stop every node;
                 respawn:  start the robot again (at most 5 times per robot, then as
                           continue); it rejoins the formation
                 A plant, relay, reference or recorder exit always stops the run (but see
                 --on-record-failure). In every mode the exit code is 1 if any node exited
                 on its own, with a line naming it.
  --on-record-failure MODE
                 what to do when the recorder cannot write its bag (a full disk): it closes
                 the bag as it is (readable; its line says how many messages up to which
                 simulated time) and exits with code 74 (default: continue):
                 continue: the others go on to the end of the run (the control run is not
                           the recorder's to end);
                 stop:     stop every node.
                 Either way the report is made from the shorter bag and the exit code is 74
                 (unless another node failed: 1). A recorder that cannot write at all before
                 the others start stops the run
  --robots-per-process K
                 run the robots K to a process (executable 'fleet', processes fleet_1,
                 fleet_2, ...; each robot still its own node in /robot_<i>): ceil(N/K)
                 processes instead of N (default 1: one 'robot' process per robot). With
                 --on-exit, a fleet process counts as its robots: respawn restarts all of them
  --no-plots     the report at the end writes metrics.json without the figures (quicker)
  --prefix DIR   install space of formation_ros (default: found from 'ros2', AMENT_PREFIX_PATH
                 or ./install/formation_ros)
  --discovery RANGE
                 how far the nodes look for each other (sets ROS_AUTOMATIC_DISCOVERY_RANGE
                 in their environment): localhost: this computer only; subnet: every
                 computer on the local network (needed when nodes run on several
                 machines). Default: ROS_AUTOMATIC_DISCOVERY_RANGE as set in the
                 environment, else localhost
  --domain-id N  ROS 2 domain of the nodes, 0 to 232 (sets ROS_DOMAIN_ID; 0 to 101 is the
                 range that is safe on every Linux machine). Default: ROS_DOMAIN_ID as set
                 in the environment, else a free domain of the launcher's choosing (one
                 on which no DDS participant is seen), said in its first line with how to
                 join it (export ROS_DOMAIN_ID=N). A domain given here or in ROS_DOMAIN_ID
                 is looked at first (a few seconds at most): where another team runs (a
                 /clock publisher, a plant, a relay or a world) nothing starts, exit code 2
  --no-plant     a lab: no plant and no /clock. The relay (executable 'relay') reads every
                 robot's measured pose (relay.source_topic, relay.source_names and
                 relay.source_type in PARAMS.yaml) and publishes /robot_<i>/pose and
                 /robot_<i>/neighbors; the reference node and the robots run on wall-clock
                 time (use_sim_time false). A robot sends its first command once its base
                 driver subscribes to its command topic (wait_for_subscribers 1; 2 with
                 --record). The relay's exit stops the run, as the plant's does
  --world        a simulated lab: the world (executable 'world', MuJoCo: docs/physics.md)
                 publishes /clock and every robot's /robot_<i>/measured_pose and takes
                 /robot_<i>/cmd_vel; the relay reads those poses (the file's
                 relay.source_topic must be the world's, as by default) and, with the
                 reference node and the robots, runs on the world's /clock (use_sim_time
                 true; the robots are given relay.rate as the rate of their states:
                 plant.rate and plant.publish_rate). With --out the world writes its
                 outputs there and the report is made from them; its contacts and
                 closest approach end the output. Not with --no-plant, --cmd-topic or
                 plant.lockstep
  --world-params WORLD.yaml
                 (with --world) the world's own parameters file: the world starts from
                 WORLD.yaml (the lab as it is: its obstacles, start.*, world.*), the relay,
                 the reference node, the robots and the recorder from PARAMS.yaml (the
                 robots' map, which may lack an obstacle the world has: an unmapped
                 chair). Obstacles are not among the values the team must share; those
                 (num_robots, dim, the law, the sensing radii, the bodies, world_frame) must
                 be the same in both files, else nothing starts (exit code 2). The run's
                 default length is PARAMS.yaml's duration over WORLD.yaml's
                 world.realtime_factor; with --out WORLD.yaml is copied there as
                 world_params.yaml
  --cmd-topic TEMPLATE
                 (with --no-plant) remap each robot's cmd_vel onto its base's topic:
                 {i} is the robot id, {name} its entry of relay.source_names, e.g.
                 /tb{i}/cmd_vel or /{name}/cmd_vel; an absolute topic name per robot, one
                 topic per robot. Not with --robots-per-process above 1 (a fleet's
                 remappings apply to all its robots). Default: /robot_<i>/cmd_vel
  --source-topic TEMPLATE
                 (with --no-plant or --world) the relay's relay.source_topic instead of
                 PARAMS.yaml's,
                 e.g. /vrpn_mocap/{name}/pose: {i} and {name} as for --cmd-topic
  -h, --help     show this help

Executables: 'ros2 run formation_ros <exe>' where the ros2 command knows the package, else
<prefix>/lib/formation_ros/<exe> with the install's Python path set, as 'ros2 run' would.

Exit codes: 0 done, 1 a node exited on its own or the report failed, 2 bad usage or
parameters, or another team on the domain given, 74 the recording stopped early (the recorder
could not write; its bag is readable and shorter than the run).
"""


def read_parameters(options: 'Options') -> Formation:
    """
    Validate PARAMS (and ``--world-params``) for every program the launcher starts.

    Return what the run needs of them: the number of robots, the default duration of a run
    (``duration`` divided by ``plant.realtime_factor``; in a lab, ``duration``; on a world,
    by the world's ``world.realtime_factor``) and the command topics of ``--cmd-topic``. This
    and :func:`read_world_parameters` are the launcher's only use of the parameter code.
    Raises UsageError listing every problem, or naming the option at fault.
    """
    # Imported here so that --help and usage errors need nothing but the standard library.
    from formation_ros.core.settings.declarations import ParamError
    from formation_ros.core.settings.file_guard import ParamsFileError
    try:
        formation = read_formation(options.params,
                                   plant=not (options.no_plant or options.world),
                                   cmd_topic=options.cmd_topic,
                                   source_topic=options.source_topic,
                                   robots_per_process=options.robots_per_process,
                                   cmd_option='--cmd-topic', source_option='--source-topic',
                                   world=options.world)
    except ParamsFileError as exc:
        raise UsageError(f'parameters file {exc.summary}') from None
    except ParamError as exc:
        raise UsageError(f'invalid parameters in {options.params}:\n{exc}') from None
    except PlanError as exc:
        raise UsageError(str(exc)) from None
    if options.world_params is None:
        return formation
    return read_world_parameters(options, formation)


def read_world_parameters(options: 'Options', formation: Formation) -> Formation:
    """
    Validate ``--world-params`` for the world; return ``formation`` with the world's run length.

    ``formation``: what :func:`read_parameters` read of PARAMS. The run's default length is
    PARAMS's ``duration`` over the world file's ``world.realtime_factor``. Raises UsageError for
    a file the world would refuse, and for one that gives another value of what the team must
    share (``core.settings.team.team_values`` but the shape: the world announces none of them,
    so no running node would compare them; obstacles are not among them).
    """
    from formation_ros.core.settings.declarations import Exe, ParamError
    from formation_ros.core.settings.file_guard import ParamsFileError
    from formation_ros.core.settings.params import validate
    from formation_ros.core.settings.params_file import load_params_file
    from formation_ros.core.settings.team import team_values
    assert options.world_params is not None
    try:
        world = validate(load_params_file(options.world_params), Exe.WORLD)
    except ParamsFileError as exc:
        raise UsageError(f'--world-params file {exc.summary}') from None
    except ParamError as exc:
        raise UsageError(f'invalid parameters in {options.world_params}:\n{exc}') from None
    robots = validate(load_params_file(options.params), Exe.RELAY)
    theirs = team_values(world, world.vertices)
    ours = team_values(robots, robots.vertices)
    differ = [f'{name} {theirs[name]} (PARAMS: {ours[name]})' for name in ours
              if name != 'shape in force' and name in theirs and theirs[name] != ours[name]]
    if differ:
        raise UsageError(f'--world-params {options.world_params} gives the world another '
                         f"{'; '.join(differ)}: the world and the team must share them")
    assert world.world is not None
    return dataclasses.replace(formation,
                               wall_seconds=robots.duration / world.world.realtime_factor)


class UsageError(Exception):
    """Bad command line, files or parameters: the launcher exits 2 with this message."""


@dataclasses.dataclass(frozen=True)
class Options:
    """The command line; paths as given (``None``: option not given)."""

    params: str
    duration: Optional[float] = None
    out: Optional[str] = None
    record: Optional[str] = None
    prefix: Optional[str] = None
    on_exit: str = 'continue'
    on_record_failure: str = 'continue'
    robots_per_process: int = 1
    discovery: Optional[str] = None
    domain_id: Optional[int] = None
    no_plant: bool = False
    plots: bool = True
    cmd_topic: Optional[str] = None
    source_topic: Optional[str] = None
    cmd_topics: tuple[str, ...] = ()
    """Robot i's command topic at index i - 1, from ``cmd_topic`` (:func:`read_parameters`)."""
    world: bool = False
    relay_rate: float = 50.0
    """``relay.rate`` of PARAMS (:func:`read_parameters`): the robots' state rate on a world."""
    world_params: Optional[str] = None
    """The world's own parameters file (``--world-params``; None: the world reads PARAMS)."""


def parse_args(argv: Sequence[str]) -> Optional[Options]:
    """Parse the command line as the shell launcher always has; None for --help."""
    needs = {'duration': 'seconds', 'out': 'a directory', 'record': 'a directory',
             'prefix': 'a directory', 'on-exit': '|'.join(ON_EXIT),
             'on-record-failure': '|'.join(ON_RECORD_FAILURE),
             'robots-per-process': 'a number of robots', 'discovery': '|'.join(DISCOVERY),
             'domain-id': 'a number', 'cmd-topic': 'a topic template',
             'source-topic': 'a topic template', 'world-params': 'a parameters file'}
    values: dict[str, Optional[str]] = dict.fromkeys(needs)
    params = None
    no_plant = False
    world = False
    plots = True
    args = list(argv)
    while args:
        arg = args.pop(0)
        name = arg[2:]
        if arg in ('-h', '--help'):
            return None
        if arg == '--no-plant':
            no_plant = True
        elif arg == '--world':
            world = True
        elif arg == '--no-plots':
            plots = False
        elif arg.startswith('--') and name in values:
            value = args.pop(0) if args else ''
            if not value:
                raise UsageError(f'--{name} needs {needs[name]}')
            values[name] = value
        elif arg.startswith('-') and arg != '-':
            raise UsageError(f"unknown option '{arg}' (see --help)")
        elif params is not None:
            raise UsageError(f"only one parameters file, got '{params}' and '{arg}'")
        else:
            params = arg
    if params is None:
        raise UsageError(None)
    duration = values['duration']
    if duration is not None and not re.fullmatch(r'[0-9]+([.][0-9]+)?', duration):
        raise UsageError(f"--duration must be a number of seconds >= 0, got '{duration}'")
    on_exit = values['on-exit'] or ON_EXIT[0]
    if on_exit not in ON_EXIT:
        raise UsageError(f"--on-exit must be one of {', '.join(ON_EXIT)}, got '{on_exit}'")
    on_record_failure = values['on-record-failure'] or ON_RECORD_FAILURE[0]
    if on_record_failure not in ON_RECORD_FAILURE:
        raise UsageError(f"--on-record-failure must be one of {', '.join(ON_RECORD_FAILURE)}, "
                         f"got '{on_record_failure}'")
    per_process = values['robots-per-process'] or '1'
    if not re.fullmatch(r'[1-9][0-9]*', per_process):
        raise UsageError('--robots-per-process must be a whole number >= 1, '
                         f"got '{per_process}'")
    discovery = values['discovery']
    if discovery is not None and discovery_problem(discovery):
        raise UsageError(f'--discovery {discovery_problem(discovery)}')
    domain_id = values['domain-id']
    if domain_id is not None and domain_problem(domain_id):
        raise UsageError(f'--domain-id {domain_problem(domain_id)}')
    _check_lab_options(no_plant, values, world)
    prefix = values['prefix'] or os.environ.get('FORMATION_PREFIX') or None
    return Options(params, None if duration is None else float(duration), values['out'],
                   values['record'], prefix, on_exit, on_record_failure, int(per_process),
                   discovery, None if domain_id is None else int(domain_id), no_plant,
                   plots, values['cmd-topic'], values['source-topic'], world=world,
                   world_params=values['world-params'])


def _check_lab_options(no_plant: bool, values: Mapping[str, Optional[str]],
                       world: bool = False) -> None:
    """Refuse the options that a run with (or without) the plant or with a world cannot honour."""
    if values.get('world-params') is not None and not world:
        raise UsageError("--world-params needs --world: it is the world's own parameters file")
    if world:
        if no_plant:
            raise UsageError('--world is a lab of its own: leave out --no-plant (the world '
                             'replaces the plant, the relay reads the world)')
        if values['cmd-topic'] is not None:
            raise UsageError("--cmd-topic does not fit --world: the world reads every robot's "
                             'command on /robot_<i>/cmd_vel')
        return
    if not no_plant:
        if values['cmd-topic'] is not None:
            raise UsageError("--cmd-topic needs --no-plant: the plant reads every robot's "
                             'command on /robot_<i>/cmd_vel')
        if values['source-topic'] is not None:
            raise UsageError('--source-topic needs --no-plant: it is where the relay reads '
                             'the measured poses')
        return
    if values['out'] is not None and values['record'] is None:
        raise UsageError('--out with --no-plant needs --record: without a plant nothing '
                         'writes trajectory.npz, the report is made from the bag')
    if values['cmd-topic'] is not None and values['robots-per-process'] not in (None, '1'):
        raise UsageError(f'--cmd-topic {FLEET_REMAP}')


def discovery_environment(options: Options, base: Mapping[str, str]) -> dict[str, str]:
    """
    Return ``base`` with the nodes' discovery range and domain set as ``options`` say.

    ``--discovery`` sets ROS_AUTOMATIC_DISCOVERY_RANGE (LOCALHOST or SUBNET) and drops the
    deprecated ROS_LOCALHOST_ONLY, which would contradict it; without it a range already in
    ``base`` is kept, and LOCALHOST is set where there is none (so a run on one computer stays
    there; ROS's own default is SUBNET). ``--domain-id`` sets ROS_DOMAIN_ID.
    """
    return with_variables(base, network_variables(options.discovery, options.domain_id, base))


def check_paths(options: Options) -> Options:
    """Check the files and directories of ``options`` (changing nothing); return them absolute."""
    if not os.path.isfile(options.params):
        raise UsageError(f"parameters file '{options.params}' not found")
    world_params = options.world_params
    if world_params is not None:
        if not os.path.isfile(world_params):
            raise UsageError(f"--world-params file '{world_params}' not found")
        world_params = os.path.abspath(world_params)
    out, record = options.out, options.record
    if out is not None:
        if os.path.isdir(out) and os.listdir(out):
            raise UsageError(f"--out directory '{out}' is not empty; choose a new one")
        if os.path.exists(out) and not os.path.isdir(out):
            raise UsageError(f"--out '{out}' is not a directory")
        out = os.path.abspath(out)
    if record is not None:
        if os.path.exists(record) and not (os.path.isdir(record) and not os.listdir(record)):
            raise UsageError(f"--record directory '{record}' exists already; choose a new one")
        record = os.path.abspath(record)
    return dataclasses.replace(options, params=os.path.abspath(options.params), out=out,
                               record=record, world_params=world_params)


@dataclasses.dataclass(frozen=True)
class Install:
    """Where the executables come from: ``ros2 run`` (prefix None) or an install prefix."""

    prefix: Optional[str]

    def command(self, executable: str) -> list[str]:
        """Return the argv that starts ``executable`` of the package."""
        if self.prefix is None:
            return ['ros2', 'run', PACKAGE, executable]
        return [os.path.join(self.prefix, 'lib', PACKAGE, executable)]

    def environment(self, base: Mapping[str, str]) -> dict[str, str]:
        """Return ``base`` with what sourcing the install sets, and unbuffered Python output."""
        env = dict(base, PYTHONUNBUFFERED='1')
        if self.prefix is not None:
            sites = sorted(glob.glob(os.path.join(self.prefix, 'lib', 'python3*',
                                                  'site-packages')))
            env['PYTHONPATH'] = _join_paths(sites, base.get('PYTHONPATH'))
            env['AMENT_PREFIX_PATH'] = _join_paths([self.prefix], base.get('AMENT_PREFIX_PATH'))
        return env

    def describe(self) -> str:
        """Say where the executables come from, for the start-up line."""
        return 'ros2 run' if self.prefix is None else self.prefix


def find_install(prefix: Optional[str], env: Mapping[str, str]) -> Install:
    """
    Find the executables: ``prefix`` if given, else ``ros2 run`` where ros2 knows the package.

    Else the first that holds ``lib/formation_ros/plant`` of: AMENT_PREFIX_PATH, the install
    this module was imported from, ./install/formation_ros and ./install, and the same two in
    the source tree this module was imported from.
    """
    if prefix is None:
        if shutil.which('ros2', path=env.get('PATH')) and _ros2_knows_package(env):
            return Install(None)
        package = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
        candidates = [p for p in env.get('AMENT_PREFIX_PATH', '').split(os.pathsep) if p]
        candidates += [os.path.join(package, *['..'] * 4)]
        for root in ('.', os.path.dirname(package)):
            candidates += [os.path.join(root, 'install', PACKAGE), os.path.join(root, 'install')]
        prefix = next((p for p in candidates if _has_plant(p)), None)
        if prefix is None:
            raise UsageError("formation_ros is not installed: build it with 'colcon build' "
                             '(docs/ros_interface.md) or pass --prefix INSTALL_DIR')
    if not _has_plant(prefix):
        raise UsageError(f'no {os.path.join(prefix, "lib", PACKAGE, "plant")}')
    return Install(os.path.abspath(prefix))


def run_of(options: Options, num_robots: int) -> Run:
    """Return what ``options`` start for ``num_robots`` robots (``formation_ros.tools.system``)."""
    return Run(num_robots, plant=not (options.no_plant or options.world), world=options.world,
               record=options.record, output_dir=options.out if not options.no_plant else None,
               robots_per_process=options.robots_per_process, cmd_topics=options.cmd_topics,
               source_topic=options.source_topic, relay_rate=options.relay_rate)


def node_specs(install: Install, options: Options, num_robots: int,
               env: Mapping[str, str]) -> list[ProcessSpec]:
    """Return the specs of plant (or world, relay), reference and robots, in starting order."""
    return [_spec(install, node, options, env) for node in plan(run_of(options, num_robots))
            if node.name != RECORDER]


def recorder_spec(install: Install, options: Options, env: Mapping[str, str]) -> ProcessSpec:
    """Return the spec of the recorder writing into ``options.record``."""
    assert options.record is not None
    return _spec(install, recorder_plan(options.record, options.cmd_topics), options, env)


def _spec(install: Install, node: NodePlan, options: Options,
          env: Mapping[str, str]) -> ProcessSpec:
    params = (options.world_params if node.executable == WORLD and options.world_params
              else options.params)
    return ProcessSpec(node.name, install.command(node.executable) +
                       ros_arguments(node, params), env)


class Launch:
    """One run: starts the nodes, watches them and the clock, stops them in order."""

    def __init__(self, options: Options, install: Install, num_robots: int,
                 wall_seconds: float) -> None:
        """Prepare the run; nothing is started yet."""
        self.options = options
        self.install = install
        self.num_robots = num_robots
        self.wall_seconds = wall_seconds
        self.env = discovery_environment(options, install.environment(os.environ))
        self.env.update(watch_environment(os.getpid()))
        self.supervisor = Supervisor(echo=sys.stdout, env=self.env)
        self.interrupted: Optional[str] = None
        self.failure: Optional[str] = None
        self.record_failure: Optional[str] = None
        self.starting = False
        """What stopped the recording early (the recorder exited RECORDING_FAILED), or None."""
        self.restarts: dict[str, int] = {}

    def on_signal(self, signum: int, frame: object) -> None:
        """Note SIGINT, SIGTERM or SIGHUP; the main loop then stops the nodes."""
        self.interrupted = signal.Signals(signum).name

    def run(self) -> int:
        """Run the nodes until the end, stop them, write the report; return the exit code."""
        previous = {sig: signal.signal(sig, self.on_signal)
                    for sig in (signal.SIGINT, signal.SIGTERM, signal.SIGHUP)}
        try:
            self._start_and_watch()
            if self.interrupted:
                say(f'stopping ({self.interrupted})')
            self.stop()
            self._note_recording_failed_at_stop()
            if self.failure is not None:
                say(f'{self.failure}; stopped the others')
                return 1
            code = self.report()
            died = self.died_on_their_own()
            if died:
                say(f'exit code 1: {died}')
                return 1
            if self.record_failure is not None and code == 0:
                ran = ('the others were stopped then (--on-record-failure stop)'
                       if self.options.on_record_failure == 'stop' else
                       'the others ran to the end of the run')
                say(f'exit code {RECORDING_FAILED}: {self.record_failure}; {ran}')
                return RECORDING_FAILED
            return code
        finally:
            self.supervisor.close()
            for sig, handler in previous.items():
                signal.signal(sig, handler)

    def died_on_their_own(self) -> str:
        """Name the nodes that ended on their own and why ('' if none did)."""
        deaths: dict[str, list[str]] = {}
        for info in self.supervisor.exits():
            if not info.stopped and not _recording_failed(info):
                deaths.setdefault(info.name, []).append(info.reason)
        parts = []
        for name, reasons in deaths.items():
            restarts = self.restarts.get(name, 0)
            restarted = (', restarted once' if restarts == 1
                         else f', restarted {restarts} times' if restarts else '')
            parts.append(f"{name} ended on its own ({', '.join(reasons)}{restarted})")
        return '; '.join(parts)

    def stop(self) -> None:
        """Stop robots, reference and plant together, then the recorder."""
        self.supervisor.stop_all(stop_stages(self.supervisor.names()), STOP_TIMEOUT)

    def _start_and_watch(self) -> None:
        specs = node_specs(self.install, self.options, self.num_robots, self.env)
        if self.options.record is not None:
            specs.insert(0, recorder_spec(self.install, self.options, self.env))
        for spec in specs:
            if self.interrupted or not self._start(spec):
                return
            if spec.name == RECORDER and not self._wait_for_recorder():
                return
        deadline = time.monotonic() + self.wall_seconds if self.wall_seconds > 0 else None
        while not self.interrupted:
            left = POLL if deadline is None else min(POLL, deadline - time.monotonic())
            if left <= 0:
                return
            if self._died(left):
                return

    def place(self, spec: ProcessSpec) -> ProcessSpec:
        """Return the spec to start for node ``spec`` (itself; hosts.py runs it elsewhere)."""
        return spec

    def _start(self, spec: ProcessSpec) -> bool:
        try:
            self.supervisor.start(self.place(spec))
        except OSError as exc:
            self.failure = f'cannot start {spec.name}: {exc}'
            return False
        return True

    def _died(self, timeout: float) -> bool:
        """
        Wait up to ``timeout`` s for a node to end on its own; True if the run must stop.

        A plant, reference or recorder exit stops the run, and so does a robot's with
        ``--on-exit stop`` (noted in :attr:`failure`); otherwise the robot is left out or
        restarted (``--on-exit respawn``, at most :data:`MAX_RESTARTS` times), saying so.
        """
        ended = self.supervisor.wait_exit(timeout)
        if ended is None or ended.stopped:
            return False
        if _recording_failed(ended):
            return self._recording_stopped()
        name, mode = ended.name, self.options.on_exit
        if name in ESSENTIAL or mode == 'stop':
            self.failure = f'{name} ended on its own ({ended.reason})'
            return True
        restarts = self.restarts.get(name, 0)
        if mode == 'respawn' and restarts < MAX_RESTARTS:
            self.restarts[name] = restarts + 1
            say(f'{name} ended on its own ({ended.reason}); starting it again '
                f'(restart {restarts + 1} of {MAX_RESTARTS})')
            try:
                self.supervisor.restart(name)
                return False
            except OSError as exc:
                say(f'cannot start {name} again: {exc}')
        elif mode == 'respawn':
            say(f'{name} ended on its own ({ended.reason}) after {MAX_RESTARTS} restarts; '
                'not starting it again, the others go on')
        else:
            say(f'{name} ended on its own ({ended.reason}); the others go on '
                '(--on-exit continue)')
        if not any(self.supervisor.running(other) for other in self.supervisor.names()
                   if other not in ESSENTIAL):
            self.failure = 'every robot has ended'
            return True
        return False

    def _recording_stopped(self) -> bool:
        """
        Note that the recorder could not write its bag; True if the run must stop.

        Said once, here; the recorder's own line says what the bag holds. With
        ``--on-record-failure continue`` the others go on; a recorder that fails before the
        others are started stops the run (robots wait for it before their first command).
        """
        if self.starting:
            self.failure = (f'the recorder could not begin to write {self.options.record} '
                            f'(exit code {RECORDING_FAILED}, see its line above)')
            return True
        self.record_failure = self._recording_failure()
        said = f'{self.record_failure} (exit code {RECORDING_FAILED})'
        if self.options.on_record_failure == 'stop':
            say(f'{said}; stopping the others (--on-record-failure stop)')
            return True
        say(f'{said}; the others go on (--on-record-failure continue)')
        return False

    def _note_recording_failed_at_stop(self) -> None:
        """Say so, once, if the recorder could not write while the run was being stopped."""
        if self.record_failure is not None or not any(
                _recording_failed(info) for info in self.supervisor.exits()):
            return
        self.record_failure = self._recording_failure()
        say(f'{self.record_failure} (exit code {RECORDING_FAILED}), as the run was stopping')

    def _recording_failure(self) -> str:
        return f'the recording stopped early: the recorder could not write {self.options.record}'

    def _wait_for_recorder(self) -> bool:
        """Wait until the recorder has created its bag directory; False if it did not."""
        assert self.options.record is not None
        deadline = time.monotonic() + RECORDER_START_TIMEOUT
        self.starting = True
        while not os.path.isdir(self.options.record):
            if self.interrupted or self._died(POLL):
                return False
            if time.monotonic() > deadline:
                self.failure = ('the recorder did not start within '
                                f'{RECORDER_START_TIMEOUT:g} s (see its output above)')
                return False
        self.starting = False
        return True

    def report(self) -> int:
        """Run formation_report on the bag or the run directory, if any; return the exit code."""
        from formation_ros.core.runs.trajectory import TRAJECTORY_FILE  # numpy: not for --help
        options = self.options
        if options.record is not None:
            source, target = options.record, options.out or options.record
        elif options.out is not None:
            from formation_ros.core.runs.trajectory import CHUNKS_DIR
            if not any(os.path.exists(os.path.join(options.out, name))
                       for name in (TRAJECTORY_FILE, CHUNKS_DIR)):
                maker = 'world' if options.world else 'plant'
                say(f'the {maker} wrote no trajectory to {options.out}')
                return 1
            source, target = options.out, options.out
        else:
            return 0
        sys.stdout.flush()
        code = subprocess.call(self.install.command('formation_report')
                               + [source, '--out', target]
                               + ([] if options.plots else ['--no-plots']), env=self.env)
        if code != 0:
            say(f'formation_report failed ({describe_returncode(code)})')
            return 1
        if options.world and options.out is not None:
            say(world_summary(options.out), sys.stdout)
        return 0


def world_summary(out: str) -> str:
    """Return the line of the world's contacts and closest approach from its world_stats.json."""
    import json
    where = os.path.join(out, 'world_stats.json')
    try:
        with open(where, encoding='utf-8') as stream:
            stats = json.load(stream)
        closest = stats['min_body_distance']
        approach = ('no two bodies measured' if closest is None else
                    f'closest approach of two bodies {closest:.4g} m (footprints '
                    f"{stats['min_footprint_gap']:+.4g} m apart)")
        gap = stats.get('min_obstacle_gap')
        obstacles = ('' if gap is None else
                     f", {stats['obstacle_contacts']} with obstacles (closest footprint "
                     f'{gap:+.4g} m from a surface)')
        return (f"world: {stats['contacts']} contacts between robots, {approach}{obstacles}, "
                f"{stats['simulated_time']:.2f} s simulated at "
                f"{stats['achieved_realtime_factor']:.3g} x real time ({where})")
    except (OSError, ValueError, KeyError, TypeError) as exc:
        return f'world: no statistics in {where} ({exc})'


def _recording_failed(info: ExitInfo) -> bool:
    """Tell whether ``info`` is the recorder ending because it could not write its bag."""
    return info.name == 'record' and info.returncode == RECORDING_FAILED


def look_at_domain(options: Options) -> Optional[TeamLook]:
    """
    Start looking at the domain the user gave for another team (``tools.domain.TeamLook``).

    None when the launcher chooses the domain itself, or ROS_DOMAIN_ID is not a domain (the
    nodes refuse it). The look reads the graph only; nothing of the run has started.
    """
    env = discovery_environment(options, os.environ)
    text = env.get(DOMAIN_ENV, '')
    if not text or domain_problem(text):
        return None
    return TeamLook(int(text), env)


def domain_refusal(options: Options, look: TeamLook) -> Optional[str]:
    """
    Return the line refusing the domain where ``look`` found another team, or None.

    A look that cannot tell is said, and the run starts: its plant still looks.
    """
    env = discovery_environment(options, os.environ)
    domain = int(env[DOMAIN_ENV])
    seen = look.result()
    if seen is None:
        say(f'could not look at ROS_DOMAIN_ID {domain} for another team (no rclpy?); starting, '
            'its plant refuses one it finds')
        return None
    if not seen.found:
        return None
    local = env.get(DISCOVERY_ENV, '').upper() == 'LOCALHOST'
    return refusal_line(domain, seen, options.domain_id is not None,
                        socket.gethostname() if local else None)


def refusal_line(domain: int, seen: TeamSeen, option: bool, host: Optional[str]) -> str:
    """
    Return the line refusing ``domain``, where the look ``seen`` found another team.

    option: whether ``--domain-id`` gave the domain (else ROS_DOMAIN_ID); host: where the nodes
    found are (None: not known, discovery reaches other computers).
    """
    nodes = ', '.join(name + (' (publishes /clock)' if name in seen.clock else '')
                      for name in seen.found)
    where = f'on this host ({host})' if host else 'on this host or another of the subnet'
    if option:
        how, other = f'--domain-id {domain}', 'give another --domain-id, or leave it out'
    else:
        how, other = f'ROS_DOMAIN_ID={domain} in the environment', ('export another '
                                                                    'ROS_DOMAIN_ID, or unset it')
    return (f'refusing to start: another team runs on ROS_DOMAIN_ID {domain} ({how}): {nodes} '
            f'{where}; nothing was started. Stop that team, or {other} and the launcher runs '
            'on a free domain of its own')


def say(message: str, stream: Optional[TextIO] = None) -> None:
    """Print one launcher message (on stderr unless ``stream`` is given), if it still can."""
    try:
        sys.stdout.flush()
        print(f'{PROG}: {message}', file=stream or sys.stderr, flush=True)
    except OSError:
        pass


def main(argv: Optional[Sequence[str]] = None, make: Optional[Callable[..., 'Launch']] = None,
         usage: str = USAGE, look: bool = True) -> int:
    """
    Run the launcher with ``argv`` (default: the command line); return the exit code.

    make: the class of the run (default :class:`Launch`; ``formation_ros.tools.hosts`` runs
    the nodes on several hosts with a subclass), usage: the text of ``--help``; look: whether a
    domain the user gave is looked at for another team first (:func:`domain_refusal`; hosts.py's
    hosts have a network of their own).
    """
    team_look = None
    try:
        options = parse_args(sys.argv[1:] if argv is None else argv)
        if options is None:
            print(usage, end='')
            return 0
        options = check_paths(options)
        install = find_install(options.prefix, os.environ)
        if options.no_plant and install.prefix is not None and not _has(install.prefix, 'relay'):
            raise UsageError(f'--no-plant needs the relay: no '
                             f'{os.path.join(install.prefix, "lib", PACKAGE, "relay")}')
        for needed in ('world', 'relay'):
            if options.world and install.prefix is not None and not _has(install.prefix,
                                                                         needed):
                raise UsageError(f'--world needs the {needed}: no '
                                 f'{os.path.join(install.prefix, "lib", PACKAGE, needed)}')
        team_look = look_at_domain(options) if look else None
        formation = read_parameters(options)
    except UsageError as exc:
        if team_look is not None:
            team_look.cancel()
        if exc.args[0] is None:
            print(usage, end='', file=sys.stderr)
        else:
            say(exc.args[0])
        return 2
    options = dataclasses.replace(options, cmd_topics=formation.cmd_topics,
                                  relay_rate=formation.relay_rate)
    chosen = ''
    if options.domain_id is None and not os.environ.get(DOMAIN_ENV):
        try:
            domain, chosen = choose_domain(discovery_environment(options, os.environ))
        except LookupError as exc:
            say(f'{exc}: set ROS_DOMAIN_ID or --domain-id')
            return 2
        options = dataclasses.replace(options, domain_id=domain)
    elif team_look is not None:
        try:
            refusal = domain_refusal(options, team_look)
        except KeyboardInterrupt:
            team_look.cancel()
            say('stopped (SIGINT) while looking at the domain; nothing was started')
            return 128 + signal.SIGINT
        if refusal is not None:
            say(refusal)
            return REFUSED
    num_robots = formation.num_robots
    wall_seconds = formation.wall_seconds if options.duration is None else options.duration
    try:
        if options.out is not None:
            os.makedirs(options.out, exist_ok=True)
            shutil.copyfile(options.params, os.path.join(options.out, 'params.yaml'))
            if options.world_params is not None:
                shutil.copyfile(options.world_params,
                                os.path.join(options.out, WORLD_PARAMS_COPY))
        if options.record is not None:
            if os.path.isdir(options.record):
                os.rmdir(options.record)
            os.makedirs(os.path.dirname(options.record), exist_ok=True)
    except OSError as exc:
        say(f'cannot prepare {exc.filename or options.out}: {exc.strerror or exc}')
        return 1
    span = 'until Ctrl-C' if wall_seconds == 0 else f'for {wall_seconds:g} s'
    per_process = options.robots_per_process
    processes = ('' if per_process == 1 else
                 f' in {-(-num_robots // per_process)} fleet processes of up to {per_process}')
    network = discovery_environment(options, os.environ)
    lab = (', no plant (relay, wall-clock time)' if options.no_plant else
           ", on the world (world and relay, the world's /clock)" if options.world else '')
    if options.world_params is not None:
        lab += f', the world from {options.world_params}'
    domain = network.get(DOMAIN_ENV) or '0'
    join = (f' (a free domain of its own: {chosen}; to join it: export ROS_DOMAIN_ID={domain} '
            'before ros2 topic echo ...)' if chosen else '')
    say(f'{num_robots} robots{processes}{lab} from {options.params} ({install.describe()}), '
        f'{span}; ROS_DOMAIN_ID {domain}{join}, discovery {network[DISCOVERY_ENV].lower()}',
        sys.stdout)
    return (make or Launch)(options, install, num_robots, wall_seconds).run()


def _ros2_knows_package(env: Mapping[str, str]) -> bool:
    try:
        result = subprocess.run(['ros2', 'pkg', 'prefix', PACKAGE], env=dict(env),
                                stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL,
                                stderr=subprocess.DEVNULL, timeout=60)
    except (OSError, subprocess.TimeoutExpired):
        return False
    return result.returncode == 0


def _has_plant(prefix: str) -> bool:
    return _has(prefix, 'plant')


def _has(prefix: str, executable: str) -> bool:
    return os.access(os.path.join(prefix, 'lib', PACKAGE, executable), os.X_OK)


def _join_paths(first: Sequence[str], rest: Optional[str]) -> str:
    return os.pathsep.join(list(first) + ([rest] if rest else []))


if __name__ == '__main__':
    sys.exit(main())
