# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
Sphinx extension: the reference parts of the docs, generated from the package's own definitions.

Directives (each writes MyST Markdown that the page then parses):

* ``formation-parameters [NAMES]``: the parameters of ``core/settings/declarations.py`` (name,
type,
  default, range, who reads it, meaning): those NAMES gives (``plant.`` a prefix, ``dim`` one
  name), or all of them. A parameter without a description, or one that no table of the docs
  lists, is a build warning (an error with ``-W``).
* ``formation-topics``: every topic of ``ros/topics.py`` with its type and the QoS profile of
  ``ros/qos.py``. The directive's body gives one line ``NAME: what it carries`` per topic; a
  topic without a line, or a line naming no topic, is a warning.
* ``formation-argparse MODULE:FUNCTION``: the options of an argparse parser that FUNCTION
  returns (MODULE is a dotted module or a file ``bench/NAME.py``).
* ``formation-usage MODULE:NAME`` or ``formation-usage scripts/NAME.sh``: a usage text, the
  module's string or what ``bash scripts/NAME.sh --help`` prints.
* ``formation-bench capacity|offline|robustness|switch``: a benchmark's table from its JSON
  file in ``docs/bench/``, formatted by the benchmark script's own table code.

The functions that make the Markdown are plain functions of the definitions (tested in
``test/test_docs.py``); the directives only find the inputs and report problems.
"""

import argparse
import importlib
import importlib.util
import json
import os
import re
import subprocess
import sys
from types import ModuleType
from typing import Any, Callable, Dict, Iterable, List, Mapping, Sequence, Tuple

from docutils import nodes
from docutils.parsers.rst import Directive
from docutils.statemachine import StringList
from sphinx.util import logging

DOCS = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
ROOT = os.path.dirname(DOCS)
LOG = logging.getLogger(__name__)
ROBOT_PLACEHOLDER = '/robot_<i>'
BENCH_FILES = {
    'capacity': ('capacity_process.json', 'capacity_fleet.json', 'capacity_lockstep.json',
                 'capacity_transports.json', 'capacity_lockstep_transports.json',
                 'capacity_team_large.json', 'capacity_targets.json',
                 'capacity_afternoon.json', 'capacity_evening.json',
                 'capacity_night.json'),
    'offline': ('offline.json',),
    'robustness': ('robustness.json',),
    'switch': ('switch.json',),
}


class DocsError(Exception):
    """A definition the docs cannot be generated from; the build warns with this message."""


def cell(text: object) -> str:
    """Return ``text`` fit for one cell of a Markdown table (pipes escaped, one line)."""
    return ' '.join(str(text).split()).replace('|', '\\|')


def table(header: Sequence[str], rows: Iterable[Sequence[object]]) -> List[str]:
    """Return the lines of a Markdown table."""
    lines = ['| ' + ' | '.join(cell(h) for h in header) + ' |',
             '|' + '---|' * len(header)]
    lines += ['| ' + ' | '.join(cell(c) for c in row) + ' |' for row in rows]
    return lines


def code(text: object) -> str:
    """Return ``text`` as inline code (backticks inside doubled away)."""
    text = str(text)
    fence = '``' if '`' in text else '`'
    return f'{fence}{text}{fence}' if text else ''


# --- parameters ------------------------------------------------------------------------------

def default_text(param: Any) -> str:
    """Say a parameter's default as a user writes it in a file."""
    from formation_ros.core.settings.declarations import REQUIRED
    value = param.default
    if value is REQUIRED:
        return 'required'
    if value is None:
        return 'none'
    if isinstance(value, bool):
        return code('true' if value else 'false')
    if value == '':
        return "empty (`''`)"
    return code(repr(value) if isinstance(value, float) else value)


def readers_text(param: Any) -> str:
    """Say which executables read a parameter (``fleet`` runs the robot's nodes)."""
    from formation_ros.core.settings.declarations import ALL, Exe
    if param.users == ALL:
        return 'all'
    names = [exe.value for exe in Exe if exe in param.users]
    if Exe.ROBOT in param.users:
        names.insert(names.index('robot') + 1, 'fleet')
    return ', '.join(names)


def parameter_problems(declarations: Sequence[Any]) -> List[str]:
    """Return what keeps the reference from being complete: names without a description."""
    return [f"parameter '{p.name}' has no description in core/settings/declarations.py"
            for p in declarations if not str(p.description or '').strip()]


def named(param: Any, name: str) -> bool:
    """Whether ``name`` gives ``param``: its name, or a prefix ending in a dot (``plant.``)."""
    return param.name == name or (name.endswith('.') and param.name.startswith(name))


def select_parameters(declarations: Sequence[Any], names: Sequence[str]) -> List[Any]:
    """Return the declarations ``names`` gives: ``plant.`` every plant.*, ``dim`` that one."""
    if not names:
        return list(declarations)
    unknown = [n for n in names if not any(named(p, n) for p in declarations)]
    if unknown:
        raise DocsError(f"no parameter named or starting with '{unknown[0]}'")
    return [p for p in declarations if any(named(p, n) for n in names)]


def unlisted_parameters(declarations: Sequence[Any], listed: Iterable[str]) -> List[str]:
    """Return the problems of a docs build whose tables leave parameters out."""
    shown = set(listed)
    return [f"parameter '{p.name}' is in no parameter table of the docs"
            for p in declarations if p.name not in shown]


def parameter_markdown(declarations: Sequence[Any]) -> List[str]:
    """Return the parameter reference table of ``declarations`` (``settings.declarations.Param``)."""
    rows = [(code(p.name), p.kind.value.replace('_', ' '), default_text(p),
             p.range_text(), readers_text(p), p.description) for p in declarations]
    return table(('name', 'type', 'default', 'allowed', 'read by', 'meaning'), rows)


# --- topics ----------------------------------------------------------------------------------

def qos_text(profile: Any) -> str:
    """Describe a QoS profile: reliability, history depth, durability, liveliness lease."""
    from rclpy.qos import LivelinessPolicy
    words = [profile.reliability.name.lower().replace('_', ' '), f'keep last {profile.depth}',
             profile.durability.name.lower().replace('_', ' ')]
    kept_by = {LivelinessPolicy.AUTOMATIC: 'DDS',
               LivelinessPolicy.MANUAL_BY_TOPIC: 'the messages'}.get(profile.liveliness)
    if kept_by is not None:
        words.append(f'liveliness lease {profile.liveliness_lease_duration.nanoseconds / 1e9:g} s'
                     f' kept by {kept_by}')
    return ', '.join(words)


def formation_topics() -> List[Tuple[str, str, str]]:
    """Return (name, type, QoS) of every topic of the formation, robot topics as /robot_<i>/."""
    from formation_ros.ros import qos, topics
    found = [(t.name.replace(topics.robot_namespace(1), ROBOT_PLACEHOLDER), t.type_name,
              qos_text(qos.BY_KIND[t.qos]))
             for t in (topics.recorded_topics(1, markers=True) + topics.team_topics()
                       + topics.obstacle_topics(1) + topics.world_topics(1, wheeled=True)
                       + [topics.scan_topic(1)])]
    found.append((topics.PARAMS, 'std_msgs/msg/String', 'bag only (written by the recorder)'))
    return found


def parse_descriptions(lines: Iterable[str]) -> Dict[str, str]:
    """Read ``NAME: text`` lines (a line starting with spaces continues the one before)."""
    found: Dict[str, str] = {}
    name = None
    for line in lines:
        if not line.strip():
            continue
        if line[0].isspace() and name is not None:
            found[name] += ' ' + line.strip()
            continue
        name, _, text = line.partition(': ')
        name = name.strip().strip('`')
        found[name] = text.strip()
    return found


def topic_markdown(described: Mapping[str, str]) -> Tuple[List[str], List[str]]:
    """Return the topic table and the problems: topics without a description, and extra ones."""
    listed = formation_topics()
    names = [name for name, _, _ in listed]
    problems = [f"topic '{name}' (ros/topics.py) has no description" for name in names
                if name not in described]
    problems += [f"'{name}' is described but is no topic of ros/topics.py" for name in described
                 if name not in names]
    rows = [(code(name), code(kind), quality, described.get(name, ''))
            for name, kind, quality in listed]
    return table(('topic', 'type', 'QoS (ros/qos.py)', 'what'), rows), problems


# --- command lines ---------------------------------------------------------------------------

def load(target: str) -> Any:
    """Return ``module:name`` (a dotted module, or a file under the repository such as bench/)."""
    where, _, name = target.partition(':')
    if where.endswith('.py'):
        path = os.path.join(ROOT, where)
        spec = importlib.util.spec_from_file_location(
            '_docs_' + os.path.basename(where)[:-3], path)
        if spec is None or spec.loader is None:
            raise DocsError(f'cannot load {where}')
        module: ModuleType = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(module)
    else:
        module = importlib.import_module(where)
    try:
        return getattr(module, name)
    except AttributeError:
        raise DocsError(f'{where} has no {name}') from None


def module_file(target: str) -> str:
    """Return the file (relative to the repository) of ``module:name`` or of a script."""
    where = target.partition(':')[0]
    if where.endswith(('.py', '.sh')):
        return where
    return where.replace('.', os.sep) + '.py'


def option_row(action: argparse.Action) -> Tuple[str, str, str, str]:
    """Return (option, argument, default, help) of one argparse action."""
    names = ', '.join(code(name) for name in action.option_strings) or code(action.dest)
    if action.nargs == 0:
        argument = ''
    else:
        metavar = action.metavar or (action.dest if not action.option_strings
                                     else action.dest.upper())
        argument = code(f'{metavar} ...' if action.nargs in ('+', '*') else metavar)
    default = action.default
    shown = '' if default in (None, False, argparse.SUPPRESS) or action.nargs == 0 else \
        code(' '.join(map(str, default)) if isinstance(default, (list, tuple)) else default)
    help_text = (action.help or '') % {'default': default, 'prog': '', 'dest': action.dest}
    return names, argument, shown, help_text


def argparse_markdown(parser: argparse.ArgumentParser) -> List[str]:
    """Return the usage line, description, options table and epilog of ``parser``."""
    lines = ['```text', parser.format_usage().strip(), '```', '']
    if parser.description:
        lines += [parser.description, '']
    lines += table(('option', 'argument', 'default', 'meaning'),
                   [option_row(action) for action in parser._actions])
    if parser.epilog:
        lines += ['', parser.epilog]
    return lines


def usage_text(target: str) -> str:
    """Return a usage text: ``module:NAME`` (a string) or what ``scripts/X.sh --help`` prints."""
    if target.endswith('.sh'):
        result = subprocess.run(['bash', os.path.join(ROOT, target), '--help'],
                                capture_output=True, text=True, timeout=60)
        if result.returncode != 0 or not result.stdout.startswith('Usage:'):
            raise DocsError(f'bash {target} --help failed: {result.stderr.strip()}')
        return result.stdout
    text = load(target)
    if not isinstance(text, str):
        raise DocsError(f'{target} is not a string')
    return text


def usage_markdown(text: str) -> List[str]:
    """Return a usage text as a literal block."""
    return ['```text', *text.rstrip('\n').splitlines(), '```']


# --- benchmarks ------------------------------------------------------------------------------

def read_json(name: str) -> Dict[str, Any]:
    """Return docs/bench/NAME parsed."""
    with open(os.path.join(DOCS, 'bench', name), encoding='utf-8') as stream:
        data: Dict[str, Any] = json.load(stream)
        return data


def load_avg(values: Sequence[float]) -> str:
    """Format three load averages."""
    return ' / '.join(f'{v:.1f}' for v in values)


def machine_line(data: Mapping[str, Any], name: str) -> str:
    """Say where a JSON file's numbers were measured (its own fields)."""
    host = data.get('machine')
    if isinstance(host, Mapping):
        text = f"{host['nproc']} cores, {host['cpu']}, Python {host['python']}"
        load_before = host.get('load_before')
    else:
        text = f"{host}, {data['cores']} cores, Python {data['python']}"
        load_before = data.get('load_before', data.get('load'))
    if load_before:
        text += f'; load average (1, 5, 15 min) {load_avg(load_before)} before'
    if data.get('load_after'):
        text += f", {load_avg(data['load_after'])} after"
    return f'*{code(name)}: {text}.*'


def bench_capacity() -> List[str]:
    """Capacity rows of every capacity_*.json, formatted by bench_capacity.py."""
    header = load('bench/bench_capacity.py:HEADER')
    row = load('bench/bench_capacity.py:format_row')
    lines = header.splitlines()
    notes = []
    for name in BENCH_FILES['capacity']:
        data = read_json(name)
        lines += [row({**entry, 'mode': f"lockstep {entry['mode']}"} if entry.get('lockstep')
                      else entry) for entry in data['rows']]
        notes += ['', machine_line(data, name)]
    return lines + notes


def bench_offline() -> List[str]:
    """Offline rows of offline.json, formatted by bench_offline.py."""
    data = read_json('offline.json')
    row = load('bench/bench_offline.py:format_row')
    split = load('bench/bench_offline.py:format_split')
    lines = load('bench/bench_offline.py:HEADER').splitlines()
    lines += [row(entry) for entry in data['rows']]
    if any('split' in entry for entry in data['rows']):
        lines += ['', 'Each part in one process, wall (CPU) seconds:', '']
        lines += load('bench/bench_offline.py:SPLIT_HEADER').splitlines()
        lines += [split(entry) for entry in data['rows'] if 'split' in entry]
    arguments = data['arguments']
    return lines + ['', machine_line(data, 'offline.json')[:-2] +
                    f"; {arguments['duration']:g} s simulated, dt {arguments['dt']:g}.*"]


def robustness_limits(data: Mapping[str, Any]) -> List[str]:
    """The limits of each one-parameter sweep per team, as bench_robustness.py finds them."""
    module_limits: Callable[[Any], Dict[str, Dict[str, Any]]] = load(
        'bench/bench_robustness.py:limits_of')
    sweeps = data['sweeps']
    limits = module_limits(sweeps)
    configs = list(data['configs'])
    rows = []
    for sweep, per_config in limits.items():
        entry = sweeps[sweep]
        values = [row['value'] for row in entry['rows'] if row['config'] == configs[0]]
        cells = [f"{sweep} ({code(entry['parameter'])}, {entry['unit']}; the ideal "
                 f'{values[0]}, then {values[1]} to {values[-1]})']
        for config in configs:
            found = per_config[config]
            broke = [row for row in entry['rows'] if row['config'] == config
                     and row['value'] == found['first_below_size']]
            held = f"held through {found['held_up_to']}" if found['held_up_to'] is not None \
                else 'held at no value'
            if broke:
                summary = broke[0]['summary']
                count = summary['collisions']
                held += (f"; first below at {found['first_below_size']} "
                         f"({summary['closest_bodies']:.3g} m, {count} "
                         f"collision{'' if count == 1 else 's'})")
            settle = f"settles through {found['converged_up_to']}"
            if found['first_not_converged'] is not None:
                settle += f", not at {found['first_not_converged']}"
            cells.append(f'{held}; {settle}')
        rows.append(cells)
    header = ['sweep'] + [f"{name} (size {data['configs'][name]['size']:g} m)"
                          for name in configs]
    return table(header, rows)


def bench_robustness() -> List[str]:
    """The robustness limits and every sweep's table, from robustness.json."""
    data = read_json('robustness.json')
    markdown: Callable[[Any], str] = load('bench/bench_robustness.py:markdown')
    lines = robustness_limits(data)
    lines += ['', machine_line(data, 'robustness.json')[:-2] +
              f"; {data['wall_s']:.0f} s for every run.*", '']
    for line in markdown(data['sweeps']).splitlines():
        heading = re.fullmatch(r'#+ (.*)', line)
        lines.append(f'**{heading.group(1)}**' if heading else line)
    return lines


def bench_switch() -> List[str]:
    """The shape-switch runs of switch.json, formatted by bench_switch.py."""
    data = read_json('switch.json')
    markdown: Callable[[Any], str] = load('bench/bench_switch.py:markdown')
    return markdown(data['runs']).splitlines() + [
        '', machine_line(data, 'switch.json')[:-2] +
        f"; lockstep equals --dt: {str(data['lockstep_equals_sim_dt']).lower()}.*"]


BENCHES: Dict[str, Callable[[], List[str]]] = {
    'capacity': bench_capacity, 'offline': bench_offline, 'robustness': bench_robustness,
    'switch': bench_switch}


# --- directives ------------------------------------------------------------------------------

class Generated(Directive):
    """A directive whose body is Markdown made by :meth:`markdown`; problems become warnings."""

    has_content = True
    optional_arguments = 1
    final_argument_whitespace = False
    reads: Tuple[str, ...] = ()
    """Files (relative to the repository) the output depends on: a change rebuilds the page."""
    kind = 'table'
    """The HTML class ``formation-<kind>`` of the generated part (docs/_static/formation.css)."""

    def markdown(self) -> Tuple[List[str], List[str]]:
        """Return the Markdown lines and the problems found."""
        raise NotImplementedError

    def inputs(self) -> Tuple[str, ...]:
        """Return the files this use of the directive reads."""
        return self.reads

    def run(self) -> List[nodes.Node]:
        """Parse the generated Markdown into the page."""
        try:
            lines, problems = self.markdown()
        except (DocsError, OSError, KeyError, ValueError, ImportError) as exc:
            lines, problems = [], [f'{self.name}: {type(exc).__name__}: {exc}']
        source, line = self.state_machine.get_source_and_line(self.lineno)
        env = self.state.document.settings.env
        for path in self.inputs():
            env.note_dependency(os.path.join(ROOT, path))
        for problem in problems:
            LOG.warning(problem, location=(env.docname, line), type='formation_docs')
        container = nodes.container(classes=['formation-generated', f'formation-{self.kind}'])
        self.state.nested_parse(StringList(lines, source=source), self.content_offset,
                                container)
        return container.children


class Parameters(Generated):
    """``formation-parameters [NAMES]``: the parameter reference, or a part of it."""

    has_content = False
    final_argument_whitespace = True
    reads = ('formation_ros/core/settings/declarations.py',)
    kind = 'parameters'

    def markdown(self) -> Tuple[List[str], List[str]]:
        """Return the table of the parameters named (all without a name)."""
        from formation_ros.core.settings.declarations import DECLARATIONS
        chosen = select_parameters(DECLARATIONS, self.arguments[0].split() if self.arguments
                                   else [])
        env = self.state.document.settings.env
        listed = getattr(env, 'formation_parameters', {})
        listed.setdefault(env.docname, set()).update(p.name for p in chosen)
        env.formation_parameters = listed
        return parameter_markdown(chosen), parameter_problems(chosen)


def purge_parameters(app: Any, env: Any, docname: str) -> None:
    """Forget the parameters a page listed before it is read again."""
    getattr(env, 'formation_parameters', {}).pop(docname, None)


def merge_parameters(app: Any, env: Any, docnames: Any, other: Any) -> None:
    """Take the parameters listed by pages read in another process (parallel builds)."""
    listed = getattr(env, 'formation_parameters', {})
    listed.update(getattr(other, 'formation_parameters', {}))
    env.formation_parameters = listed


def check_parameters(app: Any, env: Any) -> None:
    """Warn about parameters that no table lists, once some page has parameter tables."""
    from formation_ros.core.settings.declarations import DECLARATIONS
    listed = getattr(env, 'formation_parameters', {})
    if listed:
        for problem in unlisted_parameters(DECLARATIONS, set().union(*listed.values())):
            LOG.warning(problem, type='formation_docs')


class Topics(Generated):
    """``formation-topics``: the topic table; the body describes each topic."""

    reads = ('formation_ros/ros/topics.py', 'formation_ros/ros/qos.py')
    kind = 'topics'

    def markdown(self) -> Tuple[List[str], List[str]]:
        """Return the topic table and the topics that lack (or have a stray) description."""
        return topic_markdown(parse_descriptions(self.content))


class _OneArgument(Generated):
    """A generated table of one ``MODULE:NAME`` (or script) argument, without content."""

    has_content = False
    required_arguments = 1
    optional_arguments = 0

    def inputs(self) -> Tuple[str, ...]:
        """Return the module's (or the script's) file."""
        return (module_file(self.arguments[0]),)


class Arguments(_OneArgument):
    """``formation-argparse MODULE:FUNCTION``: the options of a command line."""

    def markdown(self) -> Tuple[List[str], List[str]]:
        """Return the options of the parser FUNCTION builds."""
        parser = load(self.arguments[0])()
        if not isinstance(parser, argparse.ArgumentParser):
            raise DocsError(f'{self.arguments[0]} did not return an ArgumentParser')
        return argparse_markdown(parser), []


class Usage(_OneArgument):
    """``formation-usage MODULE:NAME`` or ``formation-usage scripts/X.sh``: a usage text."""

    def markdown(self) -> Tuple[List[str], List[str]]:
        """Return the usage text as a literal block."""
        return usage_markdown(usage_text(self.arguments[0])), []


class Bench(Generated):
    """``formation-bench NAME``: a benchmark's table from docs/bench/."""

    has_content = False
    required_arguments = 1
    optional_arguments = 0

    def inputs(self) -> Tuple[str, ...]:
        """Return the JSON files and the benchmark script."""
        name = self.arguments[0]
        return tuple(os.path.join('docs', 'bench', json_name)
                     for json_name in BENCH_FILES.get(name, ())) + (f'bench/bench_{name}.py',)

    def markdown(self) -> Tuple[List[str], List[str]]:
        """Return the benchmark's table."""
        name = self.arguments[0]
        if name not in BENCHES:
            raise DocsError(f"no benchmark '{name}' (one of {', '.join(BENCHES)})")
        return BENCHES[name](), []


def setup(app: Any) -> Dict[str, Any]:
    """Register the directives; the generated parts depend on the code and JSON they read."""
    if ROOT not in sys.path:
        sys.path.insert(0, ROOT)
    for name, directive in (('formation-parameters', Parameters), ('formation-topics', Topics),
                            ('formation-argparse', Arguments), ('formation-usage', Usage),
                            ('formation-bench', Bench)):
        app.add_directive(name, directive)
    app.connect('env-purge-doc', purge_parameters)
    app.connect('env-merge-info', merge_parameters)
    app.connect('env-check-consistency', check_parameters)
    return {'version': '1', 'parallel_read_safe': True, 'parallel_write_safe': True,
            'env_version': 1}
