"""
Parameter schema, YAML loading and validation shared by ``formation_sim`` and every node.

One standard ROS 2 parameters file drives everything::

    /**:
      ros__parameters:
        num_robots: 10
        controller:
          gain: 2.0

Nested keys are dotted names in ROS (``controller.gain``). ROS 2 parameters are typed, so a
``double`` must be written with a decimal point (``2.0``, not ``2``) and a list of doubles must
contain only such numbers; the same rule here means a file that passes ``formation_sim`` also
passes ``--ros-args --params-file``.

:data:`SCHEMA` is the single list of parameters: the nodes declare theirs from it (with
descriptions and ranges) and :func:`validate` applies the same checks everywhere.
"""

from dataclasses import dataclass, field
import difflib
import math
import re

from formation_ros.core.jump import JUMP_KINDS
from formation_ros.core.law import make_law, PSI_FUNCTIONS
from formation_ros.core.reference import Reference, REFERENCE_KINDS
import numpy as np
import yaml

MAX_START_TRIES = 20000


class ParamError(ValueError):
    """One or more invalid parameters; ``str()`` names each parameter and what is allowed."""

    def __init__(self, problems):
        """Keep the list of (parameter name, message) pairs."""
        self.problems = list(problems)
        super().__init__('\n'.join(f"parameter '{name}': {msg}" for name, msg in self.problems))


@dataclass(frozen=True)
class Param:
    """
    One entry of the schema.

    kind: 'int', 'double', 'string', 'bool' or 'double_array' (the ROS parameter type);
    default: value when absent (None: optional with no value; REQUIRED: must be given);
    low / high: inclusive numeric bounds (for arrays: of each element); choices: allowed strings;
    users: which executables read it.
    """

    name: str
    kind: str
    default: object
    description: str
    low: float = None
    high: float = None
    choices: tuple = ()
    users: tuple = ('formation_sim', 'robot', 'plant', 'reference', 'record')


REQUIRED = object()
START_USERS = ('formation_sim', 'plant', 'record')
PLANT_USERS = ('plant', 'record')

SCHEMA = (
    Param('num_robots', 'int', REQUIRED, 'Number of robots N (robots are numbered 1..N).',
          low=2, high=100000),
    Param('dim', 'int', 2, 'Dimension n of the workspace: 2 or 3.', low=2, high=3),
    Param('sensing_radius', 'double', REQUIRED, 'Sensing radius R_i of every robot, m.',
          low=1e-9),
    Param('sensing_radii', 'double_array', None,
          'Optional sensing radius per robot (num_robots values, m); overrides sensing_radius.',
          low=1e-9),
    Param('repulsion_radius', 'double', REQUIRED,
          'Repulsion radius b_ij of eq. (11), m; at most every R_i and the closest vertex pair.',
          low=1e-9),
    Param('controller.gain', 'double', 2.0, 'Gain c of eq. (14), m/s.', low=1e-12),
    Param('controller.kappa', 'double', 1.0, 'Weight kappa of the collision term, eqs. (8), (13).',
          low=1e-12),
    Param('controller.psi', 'string', 'arctan', 'Bounded function psi of eq. (14).',
          choices=tuple(sorted(PSI_FUNCTIONS))),
    Param('jump.kind', 'string', 'poly',
          "Jump function of Lemma 1: 'poly' (g = y^p) or 'smooth' (g = exp(-1/y)).",
          choices=JUMP_KINDS),
    Param('jump.order', 'int', 2, "Order p of g(y) = y^p (kind 'poly').", low=1, high=50),
    Param('formation.vertices', 'double_array', REQUIRED,
          "Flat list of num_robots x dim values: robot i's place in the formation frame, m."),
    Param('start.positions', 'double_array', None,
          'Flat list of num_robots x dim start positions, m (or use start.random_*).',
          users=START_USERS),
    Param('start.random_radius', 'double', None,
          'Random start: radius of the disc (ball in 3D) about the origin, m.', low=1e-9,
          users=START_USERS),
    Param('start.min_separation', 'double', None,
          'Random start: smallest distance between two robots, m.', low=1e-9,
          users=START_USERS),
    Param('start.seed', 'int', 0, 'Random start: seed of the random generator.', low=0,
          high=2 ** 31 - 1, users=START_USERS),
    Param('reference.kind', 'string', 'fixed', 'Desired formation trajectory q_od(t).',
          choices=REFERENCE_KINDS),
    Param('reference.origin', 'double_array', None,
          'dim values: fixed point, start of a line, centre of a circle/figure eight/helix, m.'),
    Param('reference.velocity', 'double_array', None, "dim values: velocity of a 'line', m/s."),
    Param('reference.radius', 'double', 1.0, 'Radius of circle, figure eight and helix, m.',
          low=1e-9),
    Param('reference.speed', 'double', 0.5,
          'Path speed of circle and helix (mean speed of the figure eight), m/s.', low=0.0),
    Param('reference.pitch', 'double', 1.0, 'Helix rise per turn along +z, m.'),
    Param('duration', 'double', 20.0, 'Length of a run, s.', low=1e-9),
    Param('robot_id', 'int', REQUIRED, 'This robot: 1..num_robots (robot node only).', low=1,
          users=('robot',)),
    Param('control_rate', 'double', 50.0, 'Rate of the control timer, Hz (wall clock).',
          low=1e-3, high=10000.0, users=('robot', 'record')),
    Param('input_timeout', 'double', 0.5,
          'A robot publishes zero when no new pose, neighbours or reference arrived for this '
          'long, s (wall clock; not in lockstep).', low=1e-3, users=('robot', 'record')),
    Param('wait_for_subscribers', 'int', 1,
          'A robot sends its first command only once cmd_vel has this many subscribers (the '
          'plant; 2 when a recorder listens too).', low=0, high=1000, users=('robot', 'record')),
    Param('plant.rate', 'double', 100.0,
          'Integration rate of the plant, Hz of simulated time: step dt = 1 / rate.', low=1e-3,
          high=100000.0, users=PLANT_USERS),
    Param('plant.input_timeout', 'double', 0.5,
          'A command whose state stamp is older than this counts as zero, s (simulated time).',
          low=1e-6, users=PLANT_USERS),
    Param('plant.publish_rate', 'double', 50.0,
          'Rate of /robot_<i>/pose and /robot_<i>/neighbors, Hz of simulated time (at most '
          'plant.rate; every step in lockstep).', low=1e-3, high=100000.0, users=PLANT_USERS),
    Param('plant.realtime_factor', 'double', 1.0,
          'Simulated seconds per wall-clock second (an upper bound in lockstep).', low=1e-3,
          high=1000.0, users=PLANT_USERS),
    Param('plant.lockstep', 'bool', False,
          'Deterministic mode: the plant steps only when every robot answered the latest state.',
          users=('plant', 'robot', 'reference', 'record')),
    Param('plant.collision_distance', 'double', 1e-3,
          'Two robots closer than this are logged as a collision, m.', low=0.0,
          users=PLANT_USERS),
    Param('plant.wait_for_robots', 'bool', True,
          'Hold the clock at 0 (resending the start state) until every robot has sent a '
          'command, so that all robots start together.', users=PLANT_USERS),
    Param('plant.wait_for_subscribers', 'int', 1,
          'While waiting for the robots, also wait until every robot_<i>/pose topic has this '
          'many subscribers (2 when a recorder listens too).', low=0, high=1000,
          users=PLANT_USERS),
    Param('plant.marker_rate', 'double', 5.0,
          'Rate of /formation/markers for RViz, Hz (wall clock); 0 publishes none.', low=0.0,
          high=100.0, users=PLANT_USERS),
    Param('plant.output_dir', 'string', '',
          'If set, the plant writes trajectory.npz and plant_stats.json there when it stops.',
          users=PLANT_USERS),
    Param('record.path', 'string', REQUIRED,
          'Directory of the rosbag2 (MCAP) the recorder writes; must not exist yet.',
          users=('record',)),
    Param('record.overwrite', 'bool', False,
          'Let the recorder replace an existing bag directory at record.path.',
          users=('record',)),
    Param('record.markers', 'bool', False, 'Also record /formation/markers.',
          users=('record',)),
    Param('reference.rate', 'double', 50.0,
          'Publication rate of /formation/reference, Hz (wall clock).',
          low=1e-3, high=10000.0, users=('reference', 'record')),
)
SCHEMA_BY_NAME = {p.name: p for p in SCHEMA}
EXTRA_ALLOWED = {'use_sim_time'}

# PyYAML follows YAML 1.1, where 1e-3 is a string; ROS reads it as a double, and so do we.
_FLOAT_PATTERN = re.compile(
    r'^(?:[-+]?[0-9][0-9_]*\.[0-9_]*(?:[eE][-+]?[0-9]+)?'
    r'|[-+]?[0-9][0-9_]*[eE][-+]?[0-9]+'
    r'|[-+]?\.[0-9_]+(?:[eE][-+]?[0-9]+)?'
    r'|[-+]?\.(?:inf|Inf|INF)'
    r'|\.(?:nan|NaN|NAN))$')


class _Loader(yaml.SafeLoader):
    """Safe YAML loader that also reads ``1e-3`` as a float."""


_Loader.yaml_implicit_resolvers = {
    key: [(tag, regexp) for tag, regexp in resolvers if tag != 'tag:yaml.org,2002:float']
    for key, resolvers in yaml.SafeLoader.yaml_implicit_resolvers.items()
}
_Loader.add_implicit_resolver('tag:yaml.org,2002:float', _FLOAT_PATTERN,
                              list('-+0123456789.'))


def flatten(tree, prefix=''):
    """Nested dict -> {dotted name: value}; ``{'a': {'b': 1}}`` -> ``{'a.b': 1}``."""
    flat = {}
    for key, value in tree.items():
        name = f'{prefix}{key}'
        if isinstance(value, dict):
            flat.update(flatten(value, name + '.'))
        else:
            flat[name] = value
    return flat


def load_params_file(path):
    """
    Read a ROS 2 parameters YAML file and return the flat ``/**`` parameters.

    Raises ParamError (naming the file) when the file is missing, is not YAML, or has no
    ``/**: ros__parameters:`` section.
    """
    try:
        with open(path, encoding='utf-8') as stream:
            text = stream.read()
    except FileNotFoundError:
        raise ParamError([(str(path), 'file not found')]) from None
    except OSError as exc:
        raise ParamError([(str(path), f'cannot read it: {exc}')]) from None
    return parse_params_text(text, str(path))


def parse_params_text(text, source):
    """Parse ROS 2 parameters YAML text (``source`` names it in errors); return flat values."""
    path = source
    try:
        document = yaml.load(text, Loader=_Loader)
    except yaml.YAMLError as exc:
        raise ParamError([(str(path), f'cannot read it as YAML: {exc}')]) from None
    section = document.get('/**') if isinstance(document, dict) else None
    if not isinstance(section, dict) or not isinstance(section.get('ros__parameters'), dict):
        raise ParamError([(str(path), 'expected a ROS 2 parameters file with a top-level '
                                      "'/**:' section holding 'ros__parameters:'")])
    return flatten(section['ros__parameters'])


def _type_problem(param, value):
    kind = param.kind
    if kind == 'int':
        ok = isinstance(value, int) and not isinstance(value, bool)
        return None if ok else f'must be an integer, got {value!r}'
    if kind == 'double':
        if isinstance(value, int) and not isinstance(value, bool):
            return (f'must be a double: write {value}.0, not {value} '
                    '(ROS 2 parameters are typed)')
        ok = isinstance(value, float) and math.isfinite(value)
        return None if ok else f'must be a finite double, got {value!r}'
    if kind == 'string':
        return None if isinstance(value, str) else f'must be a string, got {value!r}'
    if kind == 'bool':
        return None if isinstance(value, bool) else f'must be true or false, got {value!r}'
    if not isinstance(value, (list, tuple)) or not value:
        return f'must be a non-empty list of doubles, got {value!r}'
    for item in value:
        if isinstance(item, int) and not isinstance(item, bool):
            return (f'must be a list of doubles: write {item}.0, not {item} '
                    '(ROS 2 parameters are typed)')
        if not (isinstance(item, float) and math.isfinite(item)):
            return f'must be a list of finite doubles, got element {item!r}'
    return None


def _range_problem(param, value):
    if param.choices and value not in param.choices:
        return f"must be one of {', '.join(param.choices)}; got {value!r}"
    values = value if param.kind == 'double_array' else [value]
    if param.kind not in ('int', 'double', 'double_array'):
        return None
    for item in values:
        if param.low is not None and item < param.low:
            return f'must be >= {param.low:g}, got {item!r}'
        if param.high is not None and item > param.high:
            return f'must be <= {param.high:g}, got {item!r}'
    return None


def check_values(raw, executable='formation_sim'):
    """
    Check names, types and ranges; return {name: value} with defaults filled in.

    raw: flat {dotted name: value}. Raises ParamError listing every problem found.
    """
    problems = []
    for name in raw:
        if name in SCHEMA_BY_NAME or name in EXTRA_ALLOWED:
            continue
        close = difflib.get_close_matches(name, list(SCHEMA_BY_NAME), n=1)
        hint = f" (did you mean '{close[0]}'?)" if close else ''
        problems.append((name, f'unknown parameter{hint}'))
    values = {}
    for param in SCHEMA:
        if executable not in param.users:
            continue
        if raw.get(param.name) is None:
            if param.default is REQUIRED:
                problems.append((param.name, f'is required: {param.description}'))
            else:
                values[param.name] = param.default
            continue
        value = raw[param.name]
        problem = _type_problem(param, value) or _range_problem(param, value)
        if problem:
            problems.append((param.name, problem))
        else:
            values[param.name] = list(value) if param.kind == 'double_array' else value
    if problems:
        raise ParamError(problems)
    return values


@dataclass(frozen=True)
class FormationConfig:
    """
    Validated parameters of one formation run (see :data:`SCHEMA` for meanings and units).

    Arrays: sensing_radii (N,), vertices (N, dim), start (N, dim) (None for the nodes other than
    the plant, which need no start), reference_origin (dim,), reference_velocity (dim,).
    """

    num_robots: int
    dim: int
    sensing_radii: np.ndarray
    repulsion_radius: float
    gain: float
    kappa: float
    psi: str
    jump_kind: str
    jump_order: int
    vertices: np.ndarray
    start: np.ndarray
    reference_kind: str
    reference_origin: np.ndarray
    reference_velocity: np.ndarray
    reference_radius: float
    reference_speed: float
    reference_pitch: float
    duration: float
    values: dict = field(default_factory=dict, repr=False)

    def law(self):
        """Return the control law constants (``core.law.LawParams``)."""
        return make_law(self.gain, self.kappa, self.psi, self.jump_kind, self.jump_order,
                        self.repulsion_radius)

    def reference(self):
        """Build the moving desired trajectory (``core.reference.Reference``)."""
        return Reference(self.reference_kind, self.dim, self.reference_origin,
                         self.reference_velocity, self.reference_radius, self.reference_speed,
                         self.reference_pitch)


def _points(values, name, n, dim, problems):
    flat = values.get(name)
    if flat is None:
        return None
    if len(flat) != n * dim:
        problems.append((name, f'must hold num_robots x dim = {n} x {dim} = {n * dim} values '
                               f'(robot after robot), got {len(flat)}'))
        return None
    return np.array(flat, dtype=float).reshape(n, dim)


def _closest_pair(points):
    diff = points[:, None, :] - points[None, :, :]
    dist = np.sqrt(np.einsum('ijd,ijd->ij', diff, diff))
    np.fill_diagonal(dist, np.inf)
    i, j = np.unravel_index(np.argmin(dist), dist.shape)
    return float(dist[i, j]), int(min(i, j)) + 1, int(max(i, j)) + 1


def random_start(n, dim, radius, min_separation, seed):
    """
    Uniform random positions in the disc/ball of ``radius`` about 0, pairwise >= separation.

    Returns (n, dim), or None when the points do not fit after many tries.
    """
    rng = np.random.default_rng(seed)
    placed = np.empty((n, dim))
    count = 0
    tries = 0
    while count < n:
        tries += 1
        if tries > MAX_START_TRIES * n:
            return None
        direction = rng.normal(size=dim)
        direction /= np.linalg.norm(direction)
        candidate = direction * radius * rng.random() ** (1.0 / dim)
        if count and np.min(np.sum((placed[:count] - candidate) ** 2, axis=1)) \
                < min_separation ** 2:
            continue
        placed[count] = candidate
        count += 1
    return placed


def _start_positions(values, n, dim, problems):
    given = _points(values, 'start.positions', n, dim, problems)
    random_keys = ('start.random_radius', 'start.min_separation')
    random_given = [values.get(key) is not None for key in random_keys]
    if values.get('start.positions') is not None and any(random_given):
        problems.append(('start.positions', 'give either start.positions or start.random_radius '
                                            '+ start.min_separation, not both'))
        return None
    if values.get('start.positions') is not None:
        return given
    if not all(random_given):
        problems.append(('start.positions', 'is required (or start.random_radius and '
                                            'start.min_separation for a random start)'))
        return None
    radius, separation = values['start.random_radius'], values['start.min_separation']
    start = random_start(n, dim, radius, separation, values['start.seed'])
    if start is None:
        problems.append(('start.min_separation', f'{n} robots {separation:g} m apart do not fit '
                                                 f'in start.random_radius = {radius:g} m'))
    return start


def _vector(values, name, dim, problems):
    vec = values.get(name)
    if vec is None:
        return np.zeros(dim)
    if len(vec) != dim:
        problems.append((name, f'must hold dim = {dim} values, got {len(vec)}'))
        return np.zeros(dim)
    return np.array(vec, dtype=float)


def validate(raw, executable='formation_sim'):
    """
    Check a flat parameter dict and build a :class:`FormationConfig`.

    executable: 'formation_sim', 'robot', 'plant', 'reference' or 'record'; only the parameters
    that one reads are required (a robot needs no start positions). Raises ParamError.
    """
    values = check_values(raw, executable)
    problems = []
    n, dim = values['num_robots'], values['dim']
    radii = np.full(n, values['sensing_radius'], dtype=float)
    if values.get('sensing_radii') is not None:
        if len(values['sensing_radii']) != n:
            problems.append(('sensing_radii', f'must hold num_robots = {n} values, '
                                              f"got {len(values['sensing_radii'])}"))
        else:
            radii = np.array(values['sensing_radii'], dtype=float)
    vertices = _points(values, 'formation.vertices', n, dim, problems)
    start = None
    if executable in START_USERS:
        start = _start_positions(values, n, dim, problems)
    b = values['repulsion_radius']
    if b > float(np.min(radii)):
        name = 'repulsion_radius'
        problems.append((name, f'b = {b:g} m must not exceed any sensing radius '
                               f'(smallest R_i = {float(np.min(radii)):g} m): eq. (11) needs '
                               'b_ij <= min(R_i, R_j)'))
    if vertices is not None:
        gap, i, j = _closest_pair(vertices)
        if gap == 0.0:
            problems.append(('formation.vertices', f'robots {i} and {j} have the same vertex'))
        elif b > gap:
            problems.append(('repulsion_radius', f'b = {b:g} m must not exceed the distance '
                                                 f'between the closest vertices ({i} and {j}: '
                                                 f'{gap:g} m): eq. (11) needs b_ij <= eps_2'))
    if start is not None:
        gap, i, j = _closest_pair(start)
        if gap == 0.0:
            problems.append(('start.positions', f'robots {i} and {j} start at the same point'))
    kind = values['reference.kind']
    if kind == 'helix' and dim != 3:
        problems.append(('reference.kind', 'helix needs dim 3'))
    if kind == 'line' and values.get('reference.velocity') is None:
        problems.append(('reference.velocity', f'is required for a line (dim = {dim} values)'))
    if kind in ('circle', 'figure_eight', 'helix') and values['reference.speed'] <= 0.0:
        problems.append(('reference.speed', f'must be > 0 for a {kind}'))
    if values.get('robot_id', 1) > n:
        problems.append(('robot_id', f'must be between 1 and num_robots = {n}, '
                                     f"got {values['robot_id']}"))
    if values.get('plant.publish_rate', 0.0) > values.get('plant.rate', math.inf):
        problems.append(('plant.publish_rate', 'must not exceed plant.rate = '
                                               f"{values['plant.rate']:g} Hz"))
    origin = _vector(values, 'reference.origin', dim, problems)
    velocity = _vector(values, 'reference.velocity', dim, problems)
    if problems:
        raise ParamError(problems)
    return FormationConfig(
        num_robots=n, dim=dim, sensing_radii=radii, repulsion_radius=b,
        gain=values['controller.gain'], kappa=values['controller.kappa'],
        psi=values['controller.psi'], jump_kind=values['jump.kind'],
        jump_order=values['jump.order'], vertices=vertices, start=start,
        reference_kind=kind, reference_origin=origin, reference_velocity=velocity,
        reference_radius=values['reference.radius'], reference_speed=values['reference.speed'],
        reference_pitch=values['reference.pitch'], duration=values['duration'], values=values)


def load_config(path, executable='formation_sim'):
    """Load and validate a parameters file: :func:`load_params_file` then :func:`validate`."""
    return validate(load_params_file(path), executable)
