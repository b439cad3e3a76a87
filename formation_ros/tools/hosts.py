# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
Several hosts on one computer: network namespaces joined by a switch, for multi-host runs.

:class:`Hosts` makes one network namespace per host and one more for the switch, a Linux bridge
with a veth pair to every host (``eth0`` inside the host, port ``p<k>`` on the bridge), and gives
each host an address of ``10.77.0.0/24`` inside its namespace. Nothing is added to the
computer's own network namespace: no link, no address, no route, no nftables rule. Processes
run in a host with ``ip netns exec`` under a :class:`~formation_ros.tools.supervise.Supervisor`;
their DDS traffic to other hosts can only cross the veth links, so it can be cut
(:meth:`Hosts.cut`: the switch port goes down) or thinned (:meth:`Hosts.set_loss`: an
nftables ``netdev`` table in the host's namespace drops a random share of the packets that
leave and enter ``eth0``).

Two settings make that true for ROS 2 nodes, and :meth:`Hosts.environment` sets both:

* ``ROS_AUTOMATIC_DISCOVERY_RANGE=SUBNET``: with ``LOCALHOST`` a node looks for peers on its
  own host only.
* ``FASTDDS_BUILTIN_TRANSPORTS=UDPv4``: processes in different network namespaces share
  ``/dev/shm``, and Fast DDS's shared-memory transport would carry their samples past the
  links, so that a cut link or packet loss changed nothing. With UDP only, every sample crosses
  the links (``test_hosts.py`` checks it: a cut stops the samples).

Names: every namespace of a run is called ``frh-<pid>-<n>-<host>`` (``<pid>`` the process that
made it, ``<n>`` its count of runs), so leftovers of a run whose process was killed with
SIGKILL can be told from live runs and removed (:func:`remove_stale`, done before every new
run, and ``scripts/hosts.sh --cleanup``). Deleting the namespaces deletes their links and
nftables tables with them; processes still inside are killed first, since a process keeps its
namespace alive. :class:`Hosts` cleans up on leaving its ``with`` block, whatever the cause,
and turns SIGTERM into an exception while it is active (SIGINT already is one), so that a
terminated or interrupted test run removes what it made too.

Needs root and ``ip`` (iproute2); ``nft`` (nftables) for the loss. :func:`unavailable` says why
not where they are missing. Offline tool: never imported by a node.
"""

import dataclasses
import functools
import itertools
import os
import re
import shutil
import signal
import subprocess
import sys
import threading
import time
from typing import IO, Mapping, Optional, Sequence

from formation_ros.tools import launcher
from formation_ros.tools.launcher import Install, Launch, main as launcher_main, Options
from formation_ros.tools.launcher import parse_args, say, UsageError
from formation_ros.tools.supervise import ProcessSpec, Supervisor
from formation_ros.tools.system import network_variables, with_variables

PROG = 'hosts.sh'
PREFIX = 'frh'
NAME = re.compile(r'^frh-(\d+)-(\d+)-([a-z][a-z0-9_]*)$')
SWITCH = 'switch'
BRIDGE = 'br0'
DEVICE = 'eth0'
NETWORK = '10.77.0'
LOSS_TABLE = 'frh_loss'
LOSS_HOOKS = ('ingress', 'egress')
TRANSPORT_ENV = {'FASTDDS_BUILTIN_TRANSPORTS': 'UDPv4'}
COMMAND_TIMEOUT = 30.0
KILL_WAIT = 5.0
MAX_HOSTS = 200
_RUNS = itertools.count(1)


class HostsError(Exception):
    """A command that sets up, changes or removes the network failed; the message says which."""


def unavailable(loss: bool = False) -> Optional[str]:
    """
    Return why :class:`Hosts` cannot run here (None if it can).

    Needs root, ``ip`` and a working ``ip netns``; with ``loss`` also ``nft``.
    """
    if os.geteuid() != 0:
        return 'network namespaces need root'
    if shutil.which('ip') is None:
        return "no 'ip' command (install iproute2)"
    probe = subprocess.run(['ip', 'netns', 'list'], capture_output=True, text=True,
                           timeout=COMMAND_TIMEOUT)
    if probe.returncode != 0:
        return f"'ip netns' does not work here: {probe.stderr.strip()}"
    if loss and shutil.which('nft') is None:
        return "no 'nft' command (scripts/setup_env.sh installs nftables when run as root)"
    return None


def run_command(argv: Sequence[str], stdin: Optional[str] = None) -> str:
    """Run ``argv``; return its output, or raise HostsError naming the command and its error."""
    result = subprocess.run(list(argv), input=stdin, capture_output=True, text=True,
                            timeout=COMMAND_TIMEOUT)
    if result.returncode != 0:
        raise HostsError(f"'{' '.join(argv)}' failed: {result.stderr.strip()}")
    return result.stdout


def namespaces() -> list[str]:
    """Return the names of the network namespaces that ``ip netns`` knows."""
    return [line.split()[0] for line in run_command(['ip', 'netns', 'list']).splitlines()
            if line.strip()]


def run_namespaces(tag: Optional[str] = None) -> list[str]:
    """Return the namespaces made by :class:`Hosts` (only those of run ``tag`` if given)."""
    return [name for name in namespaces() if NAME.match(name)
            and (tag is None or name.startswith(tag + '-'))]


def namespace_pids(namespace: str) -> list[int]:
    """Return the ids of the processes in ``namespace``."""
    result = subprocess.run(['ip', 'netns', 'pids', namespace], capture_output=True,
                            text=True, timeout=COMMAND_TIMEOUT)
    return [int(word) for word in result.stdout.split() if word.isdigit()]


def remove_namespace(namespace: str) -> None:
    """Kill the processes left in ``namespace``, then delete it with its links and tables."""
    pids = namespace_pids(namespace)
    for pid in pids:
        try:
            os.kill(pid, signal.SIGKILL)
        except ProcessLookupError:
            pass
    deadline = time.monotonic() + KILL_WAIT
    while pids and time.monotonic() < deadline:
        time.sleep(0.02)
        pids = namespace_pids(namespace)
    run_command(['ip', 'netns', 'delete', namespace])


def remove_stale() -> list[str]:
    """Remove the namespaces of runs whose process has ended; return their names."""
    stale = []
    for name in run_namespaces():
        match = NAME.match(name)
        assert match is not None
        if not _alive(int(match.group(1))):
            remove_namespace(name)
            stale.append(name)
    return stale


@dataclasses.dataclass(frozen=True)
class Host:
    """One host: its name, namespace, switch port and address (without the prefix length)."""

    name: str
    namespace: str
    port: str
    address: str


class Hosts:
    """
    Network namespaces as hosts on one switch; a context manager that removes them again.

    names: the hosts, lower-case words (``plant``, ``robots_a``, ...). env: the environment of
    the processes started in the hosts (default: this process's), to which
    :meth:`environment` adds the transport settings. log_dir, echo: as for
    :class:`~formation_ros.tools.supervise.Supervisor`.
    """

    def __init__(self, names: Sequence[str], env: Optional[Mapping[str, str]] = None,
                 log_dir: Optional[str] = None, echo: Optional[IO[str]] = None) -> None:
        """Plan the network; nothing is made before :meth:`create` (or ``with``)."""
        if not names or len(set(names)) != len(names) or len(names) > MAX_HOSTS:
            raise ValueError(f'give 1 to {MAX_HOSTS} distinct host names, got {list(names)}')
        bad = [name for name in names if not re.fullmatch(r'[a-z][a-z0-9_]*', name)
               or name == SWITCH]
        if bad:
            raise ValueError(f'host names must be lower-case words other than '
                             f"'{SWITCH}', got {bad}")
        self.tag = f'{PREFIX}-{os.getpid()}-{next(_RUNS)}'
        self.switch = f'{self.tag}-{SWITCH}'
        self.hosts = {name: Host(name, f'{self.tag}-{name}', f'p{k}', f'{NETWORK}.{k}')
                      for k, name in enumerate(names, start=1)}
        self.supervisor = Supervisor(echo=echo, log_dir=log_dir,
                                     env=self.environment(os.environ if env is None else env))
        self._previous: dict[int, object] = {}
        self._made: list[str] = []

    def __enter__(self) -> 'Hosts':
        """Make the network (removing stale runs first) and catch SIGTERM; return self."""
        self._catch_sigterm()
        try:
            self.create()
        except BaseException:
            self.close()
            raise
        return self

    def __exit__(self, *exc_info: object) -> None:
        """Stop every process, then remove every namespace with its links and tables."""
        self.close()

    @staticmethod
    def environment(base: Mapping[str, str]) -> dict[str, str]:
        """Return ``base`` with discovery across the subnet and Fast DDS on UDP only."""
        env = with_variables(base, network_variables('subnet', None, base))
        env.update(TRANSPORT_ENV)
        return env

    def create(self) -> None:
        """Make the switch namespace with its bridge, and each host with its link and address."""
        remove_stale()
        self._add_namespace(self.switch)
        switch = ['ip', '-n', self.switch]
        run_command(switch + ['link', 'add', BRIDGE, 'type', 'bridge', 'mcast_snooping', '0'])
        run_command(switch + ['link', 'set', BRIDGE, 'up'])
        for host in self.hosts.values():
            self._add_namespace(host.namespace)
            inside = ['ip', '-n', host.namespace]
            run_command(switch + ['link', 'add', host.port, 'type', 'veth', 'peer', 'name',
                                  DEVICE, 'netns', host.namespace])
            run_command(switch + ['link', 'set', host.port, 'master', BRIDGE, 'up'])
            run_command(inside + ['link', 'set', 'lo', 'up'])
            run_command(inside + ['addr', 'add', f'{host.address}/24', 'dev', DEVICE])
            run_command(inside + ['link', 'set', DEVICE, 'up'])
            run_command(inside + ['route', 'add', '224.0.0.0/4', 'dev', DEVICE])

    def wrap(self, host: str, spec: ProcessSpec) -> ProcessSpec:
        """Return ``spec`` run in ``host`` (its env, if given, gets the transport settings)."""
        env = None if spec.env is None else self.environment(spec.env)
        argv = ['ip', 'netns', 'exec', self.hosts[host].namespace, *spec.argv]
        return ProcessSpec(spec.name, argv, env, spec.cwd)

    def start(self, host: str, spec: ProcessSpec) -> 'subprocess.Popen[bytes]':
        """Start ``spec`` in ``host`` under :attr:`supervisor`; return its Popen."""
        return self.supervisor.start(self.wrap(host, spec))

    def cut(self, host: str) -> None:
        """Pull ``host``'s cable: its switch port goes down (and so its ``eth0`` carrier)."""
        run_command(['ip', '-n', self.switch, 'link', 'set', self.hosts[host].port, 'down'])

    def restore(self, host: str) -> None:
        """Plug ``host``'s cable back in."""
        run_command(['ip', '-n', self.switch, 'link', 'set', self.hosts[host].port, 'up'])

    def set_loss(self, host: str, percent: int) -> None:
        """
        Drop ``percent`` % of ``host``'s packets at random, each way (0: none, table removed).

        An nftables ``netdev`` table in the host's namespace drops packets on ``eth0``'s
        ingress and egress hooks (``numgen random mod 100 < percent drop``); sending
        processes get no error, as with a lossy cable. Counters count the packets that reach
        each hook and those dropped (:meth:`loss_counts`).
        """
        if not 0 <= percent <= 100:
            raise ValueError(f'loss must be 0 to 100 %, got {percent}')
        nft = ['ip', 'netns', 'exec', self.hosts[host].namespace, 'nft']
        tables = run_command(nft + ['list', 'tables'])
        if f'netdev {LOSS_TABLE}' in tables:
            run_command(nft + ['delete', 'table', 'netdev', LOSS_TABLE])
        if percent == 0:
            return
        chains = ''.join(
            f'  chain {hook} {{\n'
            f'    type filter hook {hook} device "{DEVICE}" priority 0; policy accept;\n'
            '    counter\n'
            f'    numgen random mod 100 < {percent} counter drop\n'
            '  }\n' for hook in LOSS_HOOKS)
        run_command(nft + ['-f', '-'], stdin=f'table netdev {LOSS_TABLE} {{\n{chains}}}\n')

    def loss_counts(self, host: str) -> dict[str, tuple[int, int]]:
        """Return {hook: (packets seen, packets dropped)} of ``host``'s loss table."""
        text = run_command(['ip', 'netns', 'exec', self.hosts[host].namespace, 'nft', 'list',
                            'table', 'netdev', LOSS_TABLE])
        counts = {}
        for hook in LOSS_HOOKS:
            chain = text.split(f'chain {hook} {{', 1)[1].split('}', 1)[0]
            seen, dropped = (int(n) for n in re.findall(r'counter packets (\d+)', chain))
            counts[hook] = (seen, dropped)
        return counts

    def rules(self, host: str) -> str:
        """Return the nftables rule set of ``host`` (empty when it has none)."""
        return run_command(['ip', 'netns', 'exec', self.hosts[host].namespace, 'nft',
                            'list', 'ruleset'])

    def pids(self) -> dict[str, list[int]]:
        """Return the process ids inside each namespace of this run (hosts and switch)."""
        return {name: namespace_pids(name) for name in run_namespaces(self.tag)}

    def close(self) -> None:
        """Stop the processes, remove the namespaces made, restore SIGTERM; safe to repeat."""
        try:
            self.supervisor.close()
        finally:
            errors = []
            for name in reversed(self._made):
                try:
                    remove_namespace(name)
                except HostsError as exc:
                    if name in namespaces():
                        errors.append(str(exc))
            self._made.clear()
            self._release_sigterm()
            if errors:
                raise HostsError('; '.join(errors))

    def _add_namespace(self, name: str) -> None:
        run_command(['ip', 'netns', 'add', name])
        self._made.append(name)

    def _catch_sigterm(self) -> None:
        if signal.getsignal(signal.SIGTERM) is signal.SIG_DFL and _main_thread():
            self._previous[signal.SIGTERM] = signal.signal(signal.SIGTERM, _terminate)

    def _release_sigterm(self) -> None:
        for number, handler in self._previous.items():
            signal.signal(number, handler)  # type: ignore[arg-type]
        self._previous.clear()


def host_names(robot_hosts: int) -> list[str]:
    """Return the host names of a run: ``plant`` and ``robots_1`` .. ``robots_<robot_hosts>``."""
    return ['plant'] + [f'robots_{k}' for k in range(1, robot_hosts + 1)]


def spread(num_robots: int, robot_hosts: int) -> list[list[int]]:
    """Return the robot ids (1..num_robots) of each robot host, dealt out in turn."""
    if robot_hosts < 1:
        raise ValueError(f'need at least one robot host, got {robot_hosts}')
    return [list(range(k, num_robots + 1, robot_hosts)) for k in range(1, robot_hosts + 1)]


def host_of(process: str, robot_hosts: int) -> str:
    """
    Return the host of a launcher process: ``plant`` for plant, reference and recorder.

    ``robot_<i>`` and ``fleet_<i>`` go to robot host ``(i - 1) % robot_hosts + 1``, as
    :func:`spread` deals them out.
    """
    kind, _, number = process.rpartition('_')
    if kind in ('robot', 'fleet') and number.isdigit():
        return f'robots_{(int(number) - 1) % robot_hosts + 1}'
    return 'plant'


class HostsLaunch(Launch):
    """The launcher's run with every node in its host's namespace, and lossy robot links."""

    def __init__(self, options: Options, install: Install, num_robots: int,
                 wall_seconds: float, robot_hosts: int = 2, loss: int = 0) -> None:
        """Prepare the run and plan the hosts; nothing is made before :meth:`run`."""
        super().__init__(options, install, num_robots, wall_seconds)
        self.env = Hosts.environment(self.env)
        self.supervisor = Supervisor(echo=sys.stdout, env=self.env)
        self.robot_hosts = robot_hosts
        self.loss = loss
        self.hosts = Hosts(host_names(robot_hosts))

    def place(self, spec: ProcessSpec) -> ProcessSpec:
        """Return ``spec`` run in its host (:func:`host_of`)."""
        return self.hosts.wrap(host_of(spec.name, self.robot_hosts), spec)

    def run(self) -> int:
        """Make the hosts, run the launcher's run in them, remove the hosts; the exit code."""
        with self.hosts:
            for k, robots in enumerate(spread(self.num_robots, self.robot_hosts), start=1):
                host = self.hosts.hosts[f'robots_{k}']
                if self.loss:
                    self.hosts.set_loss(host.name, self.loss)
                say(f'host {host.name} ({host.address}): robots '
                    f"{', '.join(map(str, robots)) or 'none'}"
                    + (f', {self.loss} % loss each way' if self.loss else ''), sys.stdout)
            say(f"host plant ({self.hosts.hosts['plant'].address}): plant, reference"
                + (', record' if self.options.record else '')
                + f' (namespaces {self.hosts.tag}-*)', sys.stdout)
            return super().run()


USAGE = """\
Usage: scripts/hosts.sh PARAMS.yaml [--robot-hosts K] [--loss P] [LAUNCHER OPTIONS]
       scripts/hosts.sh --cleanup

Runs a formation across hosts made on this computer (root only): network namespaces joined by
a bridge, with the plant, the reference node and the recorder on host 'plant' and the robots
dealt out in turn over K robot hosts 'robots_1' .. 'robots_K' (robot i on robots_((i-1)%K+1)).
The nodes run as scripts/launch_formation.sh runs them (same output, stop and report), with
ROS_AUTOMATIC_DISCOVERY_RANGE=SUBNET and FASTDDS_BUILTIN_TRANSPORTS=UDPv4, so that every
sample between hosts crosses their links (Fast DDS's shared memory would bypass them). Every
namespace, link and nftables table the run made is removed at its end, also after Ctrl-C or
SIGTERM; leftovers of a run killed with kill -9 are removed by the next run or --cleanup.

Options:
  --robot-hosts K  number of robot hosts, 1 to 100 (default 2)
  --loss P         drop P % (0 to 100) of the packets on every robot host's link, each way, at
                   random (nftables in the host's namespace; default 0)
  --cleanup        remove the namespaces of runs whose process is gone, then exit
  -h, --help       show this help
  LAUNCHER OPTIONS as for scripts/launch_formation.sh: --duration S, --out DIR, --record DIR,
                   --on-exit MODE, --robots-per-process K, --prefix DIR, --domain-id N
                   (--discovery is always subnet)

Needs root, iproute2 ('ip netns') and, for --loss, nftables ('nft'; scripts/setup_env.sh
installs it as root). Exit codes as the launcher's: 0 done, 1 a node ended on its own or the
report failed, 2 bad usage, parameters, or no namespaces here.
"""


def main(argv: Optional[Sequence[str]] = None) -> int:
    """Run ``scripts/hosts.sh`` with ``argv`` (default: the command line); the exit code."""
    args = list(sys.argv[1:] if argv is None else argv)
    os.environ.pop('FORMATION_LAUNCHER_MODULE', None)
    launcher.PROG = PROG
    if '-h' in args or '--help' in args:
        print(USAGE, end='')
        return 0
    try:
        robot_hosts, loss, cleanup, rest = _own_options(args)
        if not cleanup:
            parse_args(rest)
        reason = unavailable(loss=loss > 0)
        if reason is not None:
            raise UsageError(f'cannot make hosts here: {reason}')
        if cleanup:
            removed = remove_stale()
            say(f"removed {len(removed)} stale namespaces{': ' if removed else ''}"
                f"{' '.join(removed)}", sys.stdout)
            return 0
    except (UsageError, HostsError) as exc:
        if exc.args[0] is None:
            print(USAGE, end='', file=sys.stderr)
        else:
            say(str(exc))
        return 2
    make = functools.partial(HostsLaunch, robot_hosts=robot_hosts, loss=loss)
    try:
        return launcher_main(rest + ['--discovery', 'subnet'], make=make, usage=USAGE,
                             look=False)
    except HostsError as exc:
        say(str(exc))
        return 1


def _own_options(args: list[str]) -> tuple[int, int, bool, list[str]]:
    """Split off --robot-hosts, --loss and --cleanup; return them and the launcher's options."""
    robot_hosts, loss, cleanup, rest = 2, 0, False, []
    while args:
        arg = args.pop(0)
        if arg == '--cleanup':
            cleanup = True
        elif arg in ('--robot-hosts', '--loss'):
            value = args.pop(0) if args else ''
            top = 100
            if not (re.fullmatch(r'[0-9]{1,3}', value) and int(value) <= top
                    and (arg == '--loss' or int(value) >= 1)):
                low = 0 if arg == '--loss' else 1
                raise UsageError(f'{arg} must be a whole number from {low} to {top}, '
                                 f"got '{value}'")
            if arg == '--loss':
                loss = int(value)
            else:
                robot_hosts = int(value)
        elif arg == '--discovery':
            raise UsageError('--discovery cannot be given: hosts always discover across '
                             'their subnet')
        else:
            rest.append(arg)
    if cleanup and rest:
        raise UsageError(f"--cleanup takes no other arguments, got '{' '.join(rest)}'")
    return robot_hosts, loss, cleanup, rest


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    return True


def _main_thread() -> bool:
    return threading.current_thread() is threading.main_thread()


def _terminate(signum: int, frame: object) -> None:
    """Turn SIGTERM into SystemExit, so that ``with Hosts(...)`` blocks clean up."""
    raise SystemExit(128 + signum)


if __name__ == '__main__':
    sys.exit(main())
