# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
Check a parameters file before anything parses it in full: the one guard every program uses.

A YAML file can cost far more than its size once parsed: aliases expand (the "billion laughs":
a few hundred bytes that name a list of lists of ... ), and every value becomes a node and then
a Python object of a few hundred bytes (a 4 MB list of two million zeros took 12 s and 1 GB to
load). :func:`check_params_text` therefore streams the file's YAML *events* once (libyaml's
parser, one event at a time: no tree, no Python objects of the file) and refuses, at the first
event that breaks one, a file that

- is larger than :data:`MAX_FILE_BYTES` (for a file, told by its size before it is read),
- has a YAML anchor (``&name``) or alias (``*name``), which no parameters file needs,
- nests deeper than :data:`MAX_DEPTH`,
- has an array of more than :func:`array_limit` values (from ``num_robots`` and ``dim``),
- has more than :data:`MAX_VALUES` values in all,
- is not YAML (libyaml's reason translated: :func:`yaml_problem`), has a list or a mapping as
  a key, or holds more than one YAML document.

Each refusal is a :class:`ParamsFileError` whose :attr:`ParamsFileError.summary` is one line
naming the file, the line and the problem. The work is bounded whatever the file holds: at most
MAX_FILE_BYTES are read and at most MAX_VALUES events are streamed (about a second at 2 us per
event on a busy 2-core machine); memory holds the text and a stack of MAX_DEPTH frames.
"""

from dataclasses import dataclass
import os
import re
from typing import List, Optional, Tuple, Union

from formation_ros.core.settings.declarations import DECLARATIONS, ParamError
import yaml

MAX_FILE_BYTES = 8 * 1024 * 1024
"""8 MiB: four times a 10,000-robot 3D file as ``write_params_file`` writes it (2.1 MB with
vertices, start positions, sensing radii and relay names, one value per line); a file in flow
style holds the same team in a third of that."""
MAX_DEPTH = 16
"""Collections within collections: the deepest declared parameter (``/**: ros__parameters:
formations: <name>: vertices: [...]``) is 6 deep counting the document's own mapping."""
MIN_ARRAY_VALUES = 10_000
"""Every array may hold this many values whatever the team: arrays that do not grow with it
(``formation.schedule.times``, ``formations.names``) have room for 10,000 entries."""
MAX_VALUES = 400_000
"""Values (scalars) in the whole file: five times a 10,000-robot 3D file's 80,000. Bounds the
guard's time (one event each) and what the full parse of a file that passes may cost."""
PARAMETERS_KEY = 'ros__parameters'

PathText = Union[str, 'os.PathLike[str]']
_HINT = re.compile(r'\n[ \t]*(num_robots|dim)[ \t]*:[ \t]*([0-9]{1,9})[ \t]*(?:#[^\n]*)?'
                   r'(?=\n)')
_EventLoader = getattr(yaml, 'CSafeLoader', yaml.SafeLoader)


def _declared_range(name: str) -> Tuple[int, int]:
    param = next(param for param in DECLARATIONS if param.name == name)
    assert param.low is not None and param.high is not None
    return int(param.low.value), int(param.high.value)


ROBOTS_RANGE = _declared_range('num_robots')
DIM_RANGE = _declared_range('dim')


@dataclass(frozen=True)
class FileLimits:
    """What a parameters file may hold (defaults: the module's constants)."""

    max_bytes: int = MAX_FILE_BYTES
    max_depth: int = MAX_DEPTH
    min_array_values: int = MIN_ARRAY_VALUES
    max_values: int = MAX_VALUES


DEFAULT_LIMITS = FileLimits()


def array_limit(num_robots: Optional[int], dim: Optional[int],
                limits: FileLimits = DEFAULT_LIMITS) -> int:
    """
    Return the most values one array may hold: ``max(num_robots * dim, min_array_values)``.

    ``num_robots`` and ``dim`` are taken within their declared ranges; None (not in the file)
    is the declared minimum (``dim`` 2 is also its default). ``formation.vertices`` and
    ``start.positions`` hold num_robots x dim values, the other arrays num_robots or fewer.
    """
    robots = min(max(num_robots or ROBOTS_RANGE[0], ROBOTS_RANGE[0]), ROBOTS_RANGE[1])
    dims = min(max(dim or DIM_RANGE[0], DIM_RANGE[0]), DIM_RANGE[1])
    return max(robots * dims, limits.min_array_values)


class ParamsFileError(ParamError):
    """
    A parameters file refused as a whole: :attr:`summary` is the one line to show.

    Still a :class:`ParamError` (``str()`` reads ``parameter '<file>': <problem>``), so code
    that reports invalid parameters reports these too; programs print :attr:`summary`.
    """

    def __init__(self, source: str, problem: str, line: Optional[int] = None) -> None:
        """Keep the file (``source``), the problem and the line (1-based) it is on, if one."""
        where = '' if line is None else f'line {line}: '
        super().__init__([(source, where + problem)])
        self.source = source
        self.problem = problem
        self.line = line
        self.summary = f'{source}{"" if line is None else f" line {line}"}: {problem}'


@dataclass(frozen=True)
class FileShape:
    """What the guard saw of a file that passed: its top node, team and size."""

    root: Optional[str]
    """'mapping', 'sequence' or 'scalar'; None for a file without a document (empty)."""
    num_robots: Optional[int]
    dim: Optional[int]
    values: int
    longest_array: int


def read_params_file_text(path: PathText, limits: FileLimits = DEFAULT_LIMITS) -> str:
    """
    Return the text of the file at ``path``, refusing it before reading if it is too large.

    At most ``limits.max_bytes + 1`` bytes are read (a file that grows, or /dev/zero, is
    refused too); line ends are read as Python's text mode reads them (universal newlines).
    Raises ParamsFileError: not found, unreadable, too large, not UTF-8.
    """
    source = str(path)
    try:
        with open(path, 'rb') as stream:
            size = os.fstat(stream.fileno()).st_size
            if size > limits.max_bytes:
                raise ParamsFileError(source, _too_large(size, limits))
            data = stream.read(limits.max_bytes + 1)
    except FileNotFoundError:
        raise ParamsFileError(source, 'file not found') from None
    except OSError as exc:
        raise ParamsFileError(source, f'cannot read it: {exc.strerror or exc}') from None
    if len(data) > limits.max_bytes:
        raise ParamsFileError(source, _too_large(len(data), limits))
    try:
        text = data.decode('utf-8')
    except UnicodeDecodeError as exc:
        line = data.count(b'\n', 0, exc.start) + 1
        raise ParamsFileError(source, f'cannot read it: not UTF-8 text (byte {exc.start})',
                              line) from None
    return text.replace('\r\n', '\n').replace('\r', '\n')


def _too_large(size: float, limits: FileLimits) -> str:
    more = '' if size <= limits.max_bytes + 1 else f'{size / 2 ** 20:.1f} MiB, '
    return (f'{more}larger than the {limits.max_bytes / 2 ** 20:g} MiB a parameters file may '
            'have')


class _Frame:
    """An open collection while streaming: what it is, where, its key now, how many items."""

    __slots__ = ('kind', 'line', 'key', 'want_key', 'items')

    def __init__(self, kind: str, line: int) -> None:
        self.kind = kind
        self.line = line
        self.key: Optional[str] = None
        self.want_key = kind == 'mapping'
        self.items = 0


def _hints(text: str) -> Tuple[Optional[int], Optional[int]]:
    """Return the largest ``num_robots: N`` and ``dim: D`` written one per line, if any."""
    found = {'num_robots': 0, 'dim': 0}
    for match in _HINT.finditer(f'\n{text}\n'):
        found[match.group(1)] = max(found[match.group(1)], int(match.group(2)))
    return found['num_robots'] or None, found['dim'] or None


def _parameter_name(stack: List[_Frame]) -> str:
    keys = [frame.key or '?' for frame in stack[:-1] if frame.kind == 'mapping']
    if PARAMETERS_KEY in keys:
        keys = keys[len(keys) - keys[::-1].index(PARAMETERS_KEY):]
    return '.'.join(keys) or 'the top-level list'


def _team_value(stack: List[_Frame], key: str, value: str) -> Optional[int]:
    """Return ``value`` if ``key`` is ``num_robots`` or ``dim`` right in a ros__parameters."""
    if key not in ('num_robots', 'dim') or len(stack) < 2 or stack[-2].key != PARAMETERS_KEY:
        return None
    return int(value) if value.isdigit() and len(value) < 10 else None


def check_params_text(text: str, source: str,
                      limits: FileLimits = DEFAULT_LIMITS) -> FileShape:
    """
    Stream the YAML events of ``text`` once; refuse it (ParamsFileError) or return its shape.

    ``source`` names the text in messages (the file's path). The checks are those of the
    module docstring, each at the first event that breaks it; an array longer than the
    limit of the ``num_robots`` and ``dim`` found later in the file is refused at the end.
    """
    size = len(text) if len(text) * 4 <= limits.max_bytes else len(text.encode('utf-8'))
    if size > limits.max_bytes:
        raise ParamsFileError(source, _too_large(size, limits))
    hint_robots, hint_dim = _hints(text)
    robots: Optional[int] = None
    dim: Optional[int] = None
    team = (hint_robots, hint_dim)
    cap = array_limit(hint_robots or ROBOTS_RANGE[1], hint_dim or DIM_RANGE[1], limits)
    stack: List[_Frame] = []
    root: Optional[str] = None
    values = documents = 0
    longest = (0, 0, '')
    loader = _EventLoader(text)
    line = 1
    try:
        while loader.check_event():
            event = loader.get_event()
            line = event.start_mark.line + 1
            if isinstance(event, yaml.AliasEvent):
                raise ParamsFileError(source, f'YAML aliases are not allowed (*{event.anchor})',
                                      line)
            if isinstance(event, yaml.NodeEvent) and event.anchor is not None:
                raise ParamsFileError(source, f'YAML anchors are not allowed (&{event.anchor})',
                                      line)
            if isinstance(event, yaml.DocumentStartEvent):
                documents += 1
                if documents > 1:
                    raise ParamsFileError(source, 'more than one YAML document (---)', line)
                continue
            if isinstance(event, yaml.CollectionEndEvent):
                frame = stack.pop()
                if frame.kind == 'sequence' and frame.items > longest[0]:
                    stack.append(frame)
                    longest = (frame.items, frame.line, _parameter_name(stack))
                    stack.pop()
                continue
            if not isinstance(event, yaml.NodeEvent):
                continue
            kind = ('scalar' if isinstance(event, yaml.ScalarEvent) else
                    'sequence' if isinstance(event, yaml.SequenceStartEvent) else 'mapping')
            parent = stack[-1] if stack else None
            if kind == 'scalar':
                values += 1
                if values > limits.max_values:
                    raise ParamsFileError(source, f'more than {limits.max_values} values in '
                                                  'all', line)
            if parent is None:
                root = root or kind
            elif parent.kind == 'mapping' and parent.want_key:
                if kind != 'scalar':
                    raise ParamsFileError(source, f'cannot read it as YAML: a {kind} cannot be '
                                                  'a key', line)
                parent.key = event.value
                parent.want_key = False
                continue
            elif parent.kind == 'mapping':
                parent.want_key = True
                if kind == 'scalar' and parent.key is not None:
                    found = _team_value(stack, parent.key, event.value)
                    if found is not None and parent.key == 'num_robots':
                        robots = max(robots or 0, found)
                    elif found is not None:
                        dim = max(dim or 0, found)
                    if found is not None:
                        team = (robots or hint_robots, dim or hint_dim)
                        cap = array_limit(team[0] or ROBOTS_RANGE[1], team[1] or DIM_RANGE[1],
                                          limits)
            else:
                parent.items += 1
                if parent.items > cap:
                    raise _too_long(source, stack, cap, *team)
            if kind != 'scalar':
                stack.append(_Frame(kind, line))
                if len(stack) > limits.max_depth:
                    raise ParamsFileError(source, f'nested more than {limits.max_depth} levels '
                                                  'deep', line)
    except yaml.MarkedYAMLError as exc:
        mark = exc.problem_mark or exc.context_mark
        at = None if mark is None else mark.line + 1
        if 'nesting depth' in str(exc.problem):
            raise ParamsFileError(source, f'nested more than {limits.max_depth} levels deep',
                                  at) from None
        raise ParamsFileError(source, 'cannot read it as YAML: ' + yaml_problem(exc), at) \
            from None
    except yaml.YAMLError as exc:
        raise ParamsFileError(source, 'cannot read it as YAML: ' + yaml_problem(exc), line) \
            from None
    finally:
        loader.dispose()
    final = array_limit(robots, dim, limits)
    if longest[0] > final:
        raise ParamsFileError(source, f'{longest[2]} has {longest[0]} values: {final} is '
                                      f'{_allowed(robots, dim)}', longest[1])
    return FileShape(root, robots, dim, values, longest[0])


def _allowed(robots: Optional[int], dim: Optional[int]) -> str:
    if robots is None:
        return 'the most an array may have without num_robots'
    return f'the most an array may have with num_robots {robots}, dim {dim or DIM_RANGE[0]}'


def _too_long(source: str, stack: List[_Frame], cap: int, robots: Optional[int],
              dim: Optional[int]) -> ParamsFileError:
    why = (_allowed(robots, dim) if robots is not None else
           f'the most any array may have (num_robots is {ROBOTS_RANGE[1]} at most)')
    return ParamsFileError(source, f'{_parameter_name(stack)} has more than {cap} values: '
                                   f'{cap} is {why}', stack[-1].line)


_PROBLEMS = (
    ("did not find expected ',' or ']'", "a '[' list is not closed, or lacks a ','"),
    ("did not find expected ',' or '}'", "a '{' mapping is not closed, or lacks a ','"),
    ('did not find expected key', "an entry that is not 'key: value' at this indentation"),
    ("could not find expected ':'", "a key without ':'"),
    ('mapping values are not allowed', "a ':' where no mapping can start (quote a value that "
                                       "holds ': ')"),
    ('did not find expected node content', 'a value is missing'),
    ('found character that cannot start any token', 'a character that cannot start a value '
                                                    '(a tab, or one of @ ` %)'),
    ('found a tab character', 'a tab where YAML needs spaces'),
    ('found unexpected end of stream', 'the file ends inside a quoted string'),
    ('found unknown escape character', 'an unknown escape in a double-quoted string'),
    ('did not find expected <document start>', 'text after the end of the document'),
    ('did not find expected comment or line break', 'text after a value on the same line'),
    ("did not find expected '-' indicator", "a list entry without '-' at this indentation"),
    ('control characters are not allowed', 'a control character (not text)'),
    ("found unexpected ':'", "a ':' that is neither a key's nor inside a value"),
    ('while scanning a block scalar', "a '|' or '>' text block is not well formed"),
    ('found undefined tag handle', "an unknown '!' tag"),
    ('while scanning an anchor', "a '&' or '*' not followed by a name"),
    ('while scanning an alias', "a '&' or '*' not followed by a name"),
    ('found duplicate anchor', 'YAML anchors are not allowed'),
    ('while scanning a directive', "a '%' directive line"),
    ('found incompatible YAML document', "a '%YAML' directive of another YAML version"),
    ('could not determine a constructor', "an unknown '!' tag"),
    ('found unhashable key', 'a list or a mapping as a key'),
    ('timestamp', 'a date or time that is not one'),
)


def yaml_problem(exc: yaml.YAMLError) -> str:
    """
    Return libyaml's (or PyYAML's) reason for ``exc`` in this package's own words.

    The reason and its context are matched against the problems a hand-written file has; any
    other is said as 'not valid YAML here', with the column.
    """
    problem = str(getattr(exc, 'problem', None) or '')
    context = str(getattr(exc, 'context', None) or '')
    mark = getattr(exc, 'problem_mark', None)
    column = '' if mark is None else f' (column {mark.column + 1})'
    for pattern, words in _PROBLEMS:
        if pattern in problem or pattern in context:
            return words + column
    return 'not valid YAML here' + column
