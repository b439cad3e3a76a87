# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
Robustness benchmark: where the paper's guarantees end for bodies that are not q' = u.

Usage: python bench/bench_robustness.py [--quick] [--seeds 3] [--jobs 1] [--out DIR]
       python bench/bench_robustness.py --physics [--only PART ...] [--teams TEAM ...] [...]

It sweeps each non-ideality of the plant model (plant.actuator_lag, plant.state_delay,
plant.pose_noise, plant.max_acceleration; core/model/dynamics.py), the step (plant.rate), a grid of
delay x lag and the gain c at fixed delays, on the paper's Section 5 team
(config/paper_section5.yaml) and on config/unicycle_2d.yaml, from several random starts
(start.seed, which also seeds the noise). Every run is formation_sim --dt 1/plant.rate
(formation_ros.simulation.simulate.run_fixed_step, in-process), sampled every step, and gives: the
closest approach of the control points and of the bodies, the collisions (approaches closer
than the bodies' size: 2 x body.radius = 0.22 m between the unicycles' axle centres; for the
Section 5 points, which have no radius and whose potential guarantees nothing from these
starts, the starts' own start.min_separation = 0.1 m), the settle time (every robot within
0.05 m of its place from then on, core/runs/metrics.py), the largest |u_hat| component against
c M1, the largest body velocity and whether the run converged (settled). Prints a Markdown
table per sweep and progress lines on stderr, writes OUT/bench/robustness.json and one figure
per sweep, OUT/robustness_<sweep>.png (OUT defaults to the repository's docs/).

--physics runs another family instead (bench/physics_robustness.py): the law on the MuJoCo
engine (formation_sim --engine mujoco) with one world knob at a time (the motors' torque or
force limit, the payload mass, the floor's friction, the control period, the pose noise), on
the TurtleBot3-like team of config/unicycle_2d.yaml (also started across its hexagon:
bench/physics_crossing.yaml) and the holonomic team of config/lab_holonomic.yaml, and the
plant model's lag fitted to the engine's step responses; it writes
OUT/bench/robustness_physics.json and OUT/robustness_physics_*.png and leaves robustness.json
alone.
"""

import argparse
from concurrent.futures import ProcessPoolExecutor
import json
import os
import platform
import sys
import time
from typing import Any, Dict, List, Optional, Sequence, Tuple

BENCH = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(BENCH)
sys.path[:0] = [ROOT, BENCH]

from formation_ros.core.maths.safety import guaranteed_min_distance  # noqa: E402
from formation_ros.core.maths.unicycle import hand_points  # noqa: E402
from formation_ros.core.runs.metrics import SETTLE_TOLERANCE  # noqa: E402
from formation_ros.core.settings.declarations import BY_NAME, ParamError  # noqa: E402
from formation_ros.core.settings.params import FormationConfig, validate  # noqa: E402
from formation_ros.core.settings.params_file import load_params_file  # noqa: E402
from formation_ros.simulation.simulate import Progress, run_fixed_step, run_metrics  # noqa: E402
import physics_robustness  # noqa: E402

CONFIGS = {'section5': 'config/paper_section5.yaml', 'unicycle': 'config/unicycle_2d.yaml'}
POINT_SIZE = 'start.min_separation'
SWEEPS: Dict[str, Dict[str, Any]] = {
    'lag': {'parameter': 'plant.actuator_lag', 'unit': 's',
            'values': [0.0, 0.05, 0.1, 0.2, 0.5, 1.0, 2.0], 'quick': [0.0, 0.2]},
    'delay': {'parameter': 'plant.state_delay', 'unit': 's',
              'values': [0.0, 0.05, 0.1, 0.2, 0.5, 1.0, 2.0], 'quick': [0.0, 0.2]},
    'noise': {'parameter': 'plant.pose_noise', 'unit': 'm',
              'values': [0.0, 0.01, 0.03, 0.1, 0.3], 'quick': [0.0, 0.05]},
    'acceleration': {'parameter': 'plant.max_acceleration', 'unit': 'm/s^2 (rad/s^2 for w)',
                     'values': [0.0, 10.0, 3.0, 1.0, 0.3, 0.1], 'quick': [0.0, 1.0],
                     'note': '0 is no limit; smaller values are harsher'},
    'rate': {'parameter': 'plant.rate', 'unit': 'Hz', 'values': [100.0, 50.0, 20.0, 10.0, 5.0],
             'quick': [100.0, 20.0], 'note': 'the step dt = 1 / rate; 100 Hz is the default'},
}
GRID = {'delays': [0.1, 0.5], 'lags': [0.1, 0.5], 'quick_delays': [0.2], 'quick_lags': [0.2]}
GAIN = {'factors': [0.25, 0.5, 1.0, 2.0], 'delays': [0.2, 0.5, 1.0], 'quick_factors': [0.5],
        'quick_delays': [0.2]}
COMBINED = {
    'delay_lag': {'parameter': 'plant.state_delay x plant.actuator_lag', 'unit': 's x s',
                  'note': 'value: (delay, lag)'},
    'gain': {'parameter': 'plant.state_delay x controller.gain', 'unit': 's x factor',
             'note': "value: (delay, gain / the file's gain)"},
}
QUICK_DURATION = 2.0
PHYSICS_PARTS = physics_robustness.PARTS
PHYSICS_TEAMS = tuple(physics_robustness.TEAMS)
Settings = Tuple[Tuple[str, float], ...]


def build_parser() -> argparse.ArgumentParser:
    """Command line of the robustness benchmark."""
    parser = argparse.ArgumentParser(
        prog='bench_robustness.py', description=__doc__.split('\n\n')[2].strip(),
        epilog='Quick check (seconds): python bench/bench_robustness.py --quick --out /tmp/r')
    parser.add_argument('--quick', action='store_true',
                        help=f'two values per sweep, one seed, {QUICK_DURATION:g} s runs: checks '
                             'the benchmark, measures nothing')
    parser.add_argument('--seeds', type=int,
                        help='random starts per setting: start.seed of the file, +1, ... '
                             '(default 3, with --physics 1; --quick: 1)')
    parser.add_argument('--jobs', type=int, default=1,
                        help='runs in parallel, one process each (default %(default)s)')
    parser.add_argument('--redraw', action='store_true',
                        help='run nothing: read OUT/bench/robustness.json of an earlier run, '
                             'recompute its limits and gain rule, rewrite it and the figures '
                             '(with --physics: robustness_physics.json and its figures)')
    parser.add_argument('--physics', action='store_true',
                        help='the sweeps on the physics engine and the lag fit instead '
                             '(bench/physics_robustness.py): OUT/bench/robustness_physics.json'
                             ', OUT/robustness_physics_{sweeps,fit}.png')
    parser.add_argument('--only', nargs='+', metavar='PART',
                        help='with --physics: run only these parts (of: '
                             f"{', '.join(PHYSICS_PARTS)}) and merge them into the earlier "
                             'robustness_physics.json')
    parser.add_argument('--teams', nargs='+', metavar='TEAM',
                        help=f"with --physics: the teams (of: {', '.join(PHYSICS_TEAMS)}; "
                             'default all)')
    parser.add_argument('--out', default=os.path.join(ROOT, 'docs'),
                        help='writes OUT/bench/robustness.json and OUT/robustness_<sweep>.png '
                             '(default: %(default)s)')
    return parser


def parse_args(argv: Optional[Sequence[str]] = None) -> argparse.Namespace:
    """Parse and check the command line (argparse exits 2 on a bad one)."""
    parser = build_parser()
    args = parser.parse_args(argv)
    if args.seeds is None:
        args.seeds = 1 if args.physics else 3
    if args.seeds < 1 or args.jobs < 1:
        parser.error('--seeds and --jobs must be >= 1')
    if (args.only or args.teams) and not args.physics:
        parser.error('--only and --teams go with --physics')
    unknown = sorted(set(args.only or ()) - set(PHYSICS_PARTS)) + sorted(
        set(args.teams or ()) - set(PHYSICS_TEAMS))
    if unknown:
        parser.error(f"no part or team {', '.join(unknown)}")
    if args.physics and not args.teams:
        args.teams = list(PHYSICS_TEAMS)
    if args.quick:
        args.seeds = 1
    return args


def load_raw(name: str) -> Dict[str, Any]:
    """Return the flat parameters of config ``name`` (a key of CONFIGS)."""
    return load_params_file(os.path.join(ROOT, CONFIGS[name]))


def body_size(name: str, raw: Dict[str, Any]) -> Tuple[float, str]:
    """Return the distance below which two bodies touch, m, and what it is."""
    config = validate(raw)
    if config.body.is_unicycle:
        return 2.0 * config.body.radius, '2 x body.radius (axle centres)'
    return float(raw[POINT_SIZE]), f'{POINT_SIZE} (points: no body.radius, no guarantee)'


def configure(name: str, settings: Settings,
              seed_offset: int) -> Tuple[FormationConfig, float]:
    """Return config ``name`` with ``settings`` (dotted names), start.seed moved on; and dt, s."""
    raw = load_raw(name)
    raw = {**raw, 'start.seed': int(raw.get('start.seed', 0)) + seed_offset}
    for key, value in settings:
        if key == 'controller.gain.factor':
            raw['controller.gain'] = float(raw['controller.gain']) * value
        else:
            raw[key] = value
    rate = float(raw.get('plant.rate', BY_NAME['plant.rate'].default))
    return validate(raw), 1.0 / rate


def run_one(job: Tuple[str, Settings, int, Optional[float]]) -> Dict[str, Any]:
    """Run one setting from one start; return its measures (or why it was refused)."""
    name, settings, seed_offset, duration = job
    started = time.monotonic()
    try:
        config, dt = configure(name, settings, seed_offset)
    except ParamError as exc:
        return {'refused': str(exc).strip().splitlines()[-1].strip()}
    size, _ = body_size(name, load_raw(name))
    length = config.duration if duration is None else duration
    run = run_fixed_step(config, length, dt, dt, Progress(length, quiet=True),
                         collision_distance=size)
    trajectory = run.trajectory
    metrics = run_metrics(trajectory, config, f'zero-order hold, dt = {dt:g} s')
    start = (config.start if config.start_headings is None
             else hand_points(config.start, config.start_headings, config.body.hand_distance))
    return {
        'seed': int(config.values['start.seed']),
        'closest_points': metrics['min_pair_distance'],
        'closest_bodies': metrics.get('min_body_distance', metrics['min_pair_distance']),
        'collisions': run.counts.collisions,
        'settle_time': metrics['settle_time'],
        'converged': metrics['settle_time'] is not None,
        'final_max_error': metrics['final_max_error'],
        'max_abs_u_hat': run.largest_u_hat,
        'u_bound': config.law().u_bound,
        'max_abs_body_velocity': run.largest_velocity.tolist(),
        'guaranteed_min_distance': guaranteed_min_distance(start, config.vertices, config.law()),
        'bound_violations': run.counts.bound_violations,
        'delay_steps': run.delay_steps,
        'wall_s': time.monotonic() - started,
    }


def summarise(runs: List[Dict[str, Any]], size: float) -> Dict[str, Any]:
    """Worst case over the starts of one setting (closest approach, settle time, speeds)."""
    done = [r for r in runs if 'refused' not in r]
    if not done:
        return {'refused': runs[0]['refused']}
    settles = [r['settle_time'] for r in done]
    closest = min(r['closest_bodies'] for r in done)
    return {
        'closest_points': min(r['closest_points'] for r in done),
        'closest_bodies': closest,
        'mean_closest_bodies': sum(r['closest_bodies'] for r in done) / len(done),
        'collisions': sum(r['collisions'] for r in done),
        'held': closest >= size and all(r['collisions'] == 0 for r in done),
        'converged': sum(r['converged'] for r in done),
        'starts': len(done),
        'settle_time': None if None in settles else max(settles),
        'final_max_error': max(r['final_max_error'] for r in done),
        'max_abs_u_hat': max(r['max_abs_u_hat'] for r in done),
        'u_bound': done[0]['u_bound'],
        'max_abs_body_velocity': [max(r['max_abs_body_velocity'][k] for r in done)
                                  for k in range(len(done[0]['max_abs_body_velocity']))],
    }


def settings_of(args: argparse.Namespace) -> Dict[str, List[Tuple[Any, Settings]]]:
    """Every sweep's settings: (label, settings) in order of harshness."""
    quick = args.quick
    sweeps: Dict[str, List[Tuple[Any, Settings]]] = {}
    for sweep, spec in SWEEPS.items():
        values = spec['quick'] if quick else spec['values']
        sweeps[sweep] = [(value, ((spec['parameter'], value),)) for value in values]
    delays = GRID['quick_delays'] if quick else GRID['delays']
    lags = GRID['quick_lags'] if quick else GRID['lags']
    sweeps['delay_lag'] = [((d, tau), (('plant.state_delay', d), ('plant.actuator_lag', tau)))
                           for d in [0.0] + delays for tau in [0.0] + lags]
    factors = GAIN['quick_factors'] if quick else GAIN['factors']
    gain_delays = GAIN['quick_delays'] if quick else GAIN['delays']
    sweeps['gain'] = [((d, f), (('plant.state_delay', d), ('controller.gain.factor', f)))
                      for d in gain_delays for f in factors]
    return sweeps


def canonical(settings: Settings) -> Settings:
    """Drop the ideal values from settings and sort them: one key per distinct run."""
    ideal = {'plant.rate': 100.0, 'controller.gain.factor': 1.0}
    return tuple(sorted((k, v) for k, v in settings if v != ideal.get(k, 0.0)))


def run_all(args: argparse.Namespace,
            sweeps: Dict[str, List[Tuple[Any, Settings]]]) -> Dict[Tuple[str, Settings, int],
                                                                   Dict[str, Any]]:
    """Run every distinct (config, settings, start) once; return the measures by key."""
    duration = QUICK_DURATION if args.quick else None
    jobs = sorted({(name, canonical(settings), seed)
                   for name in CONFIGS for entries in sweeps.values()
                   for _, settings in entries for seed in range(args.seeds)})
    results: Dict[Tuple[str, Settings, int], Dict[str, Any]] = {}
    started = time.monotonic()
    work = [(name, settings, seed, duration) for name, settings, seed in jobs]
    with ProcessPoolExecutor(max_workers=args.jobs) as pool:
        for count, (key, result) in enumerate(zip(jobs, pool.map(run_one, work)), start=1):
            results[key] = result
            name, settings, seed = key
            what = ', '.join(f'{k} = {v:g}' for k, v in settings) or 'ideal'
            outcome = result.get('refused') or (
                f"closest bodies {result['closest_bodies']:.3f} m, "
                f"{'settled' if result['converged'] else 'not settled'}")
            print(f'bench_robustness: {count}/{len(jobs)} {name} seed +{seed} ({what}): '
                  f'{outcome}; {time.monotonic() - started:.0f} s', file=sys.stderr, flush=True)
    return results


def first_failure(rows: List[Dict[str, Any]], key: str) -> Tuple[Any, Any]:
    """Return (last value that held, first that did not) along a sweep, for one config."""
    last, first = None, None
    for row in rows:
        summary = row['summary']
        if 'refused' in summary:
            continue
        ok = summary['held'] if key == 'held' else summary['converged'] == summary['starts']
        if ok and first is None:
            last = row['value']
        elif not ok and first is None:
            first = row['value']
    return last, first


def limits_of(table: Dict[str, Any]) -> Dict[str, Dict[str, Any]]:
    """Return the measured limits of every one-parameter sweep, per config."""
    limits: Dict[str, Dict[str, Any]] = {}
    for sweep in SWEEPS:
        limits[sweep] = {}
        for name in CONFIGS:
            rows = [row for row in table[sweep]['rows'] if row['config'] == name]
            held, broke = first_failure(rows, 'held')
            settled, unsettled = first_failure(rows, 'converged')
            limits[sweep][name] = {'held_up_to': held, 'first_below_size': broke,
                                   'converged_up_to': settled, 'first_not_converged': unsettled}
    return limits


def gain_rule(table: Dict[str, Any], sizes: Dict[str, float]) -> List[Dict[str, Any]]:
    """
    Return the gain sweep as c M1 d / b (how far a robot runs at full speed in the delay, in b).

    One entry per (config, delay, gain factor) that ran (the gain sweep, and the delay sweep at
    the file's gain), with that ratio and whether it held.
    """
    entries = []
    rows = table['gain']['rows'] + [{**row, 'value': (row['value'], 1.0)}
                                    for row in table['delay']['rows'] if row['value'] > 0.0]
    for row in sorted(rows, key=lambda r: (r['config'], tuple(r['value']))):
        summary = row['summary']
        if 'refused' in summary or (row in table['gain']['rows'] and row['value'][1] == 1.0):
            continue
        delay, factor = row['value']
        config, _ = configure(row['config'], (('controller.gain.factor', factor),), 0)
        law = config.law()
        entries.append({'config': row['config'], 'delay': delay, 'gain': law.gain,
                        'ratio': law.u_bound * delay / law.repulsion_radius,
                        'held': summary['held'],
                        'converged': summary['converged'] == summary['starts'],
                        'closest_bodies': summary['closest_bodies'], 'size': sizes[row['config']]})
    return entries


def machine() -> Dict[str, Any]:
    """nproc, the CPU model, the Python version, the load."""
    model = platform.processor() or platform.machine()
    try:
        with open('/proc/cpuinfo', encoding='utf-8') as stream:
            for line in stream:
                if line.startswith('model name'):
                    model = line.split(':', 1)[1].strip()
                    break
    except OSError:
        pass
    return {'nproc': os.cpu_count(), 'cpu': model, 'python': platform.python_version(),
            'load_before': list(os.getloadavg())}


def fmt(value: Any, digits: int = 3) -> str:
    """Format a number for a table (None: '-')."""
    if value is None:
        return '-'
    if isinstance(value, (list, tuple)):
        return ' x '.join(fmt(v, digits) for v in value)
    return f'{value:.{digits}g}'


def markdown(table: Dict[str, Any]) -> str:
    """Markdown tables of every sweep."""
    lines = []
    for sweep, entry in table.items():
        lines += [f"\n### {sweep} ({entry['parameter']}, {entry['unit']})\n",
                  '| config | value | closest points (m) | closest bodies (m) | size (m) | '
                  'collisions | settled | settle time (s) | max abs u_hat / c M1 | '
                  'max body velocity |', '|---|---|---:|---:|---:|---:|---|---:|---:|---|']
        for row in entry['rows']:
            s = row['summary']
            if 'refused' in s:
                lines.append(f"| {row['config']} | {fmt(row['value'])} | refused: "
                             f"{s['refused']} | | | | | | | |")
                continue
            lines.append(
                f"| {row['config']} | {fmt(row['value'])} | {s['closest_points']:.3f} | "
                f"{s['closest_bodies']:.3f} | {row['size']:.3g} | {s['collisions']} | "
                f"{s['converged']}/{s['starts']} | {fmt(s['settle_time'])} | "
                f"{s['max_abs_u_hat'] / s['u_bound']:.3f} | "
                f"{fmt(s['max_abs_body_velocity'])} |")
    return '\n'.join(lines)


COLOURS = {'section5': 'tab:blue', 'unicycle': 'tab:orange'}
STYLES = ('-', '--', ':', '-.')
NO_LIMIT_X = 100.0
"""Where the acceleration figure puts 'no limit' (plant.max_acceleration 0)."""
MARKERS = ('o', 's', '^', 'D')


def gain_figure(plt: Any, rule: List[Dict[str, Any]], path: str) -> None:
    """Closest approach / the bodies' size against c M1 d / b, both configs, every gain."""
    figure, axes = plt.subplots(figsize=(6.4, 4.2))
    for name in CONFIGS:
        for held, marker in ((True, 'o'), (False, 'x')):
            some = [e for e in rule if e['config'] == name and e['held'] == held]
            axes.scatter([e['ratio'] for e in some],
                         [e['closest_bodies'] / e['size'] for e in some], marker=marker,
                         color=COLOURS[name],
                         label=f"{name}: {'held' if held else 'bodies touched'}")
    axes.axhline(1.0, color='k', linestyle='--', linewidth=1.0, label='bodies touch')
    axes.set_xscale('log')
    axes.set_xlabel('c M1 d / b: how far a robot runs at full speed during the delay d, in b')
    axes.set_ylabel("closest approach / bodies' size")
    axes.set_ylim(bottom=0.0)
    axes.grid(True, alpha=0.3)
    axes.legend(fontsize=7)
    axes.set_title('Robustness: gain c and delay d (beyond the paper)')
    figure.tight_layout()
    figure.savefig(path, dpi=100)
    plt.close(figure)


def x_of(sweep: str, value: Any) -> float:
    """Where a setting goes on its figure's x axis (rate: the step dt; no limit: far left)."""
    if sweep == 'rate':
        return 1.0 / float(value)
    if sweep == 'acceleration' and float(value) == 0.0:
        return NO_LIMIT_X
    return float(value[1] if isinstance(value, (list, tuple)) else value)


def x_label(sweep: str, entry: Dict[str, Any]) -> str:
    """Return the x axis label of a sweep's figure."""
    return {'delay_lag': 'plant.actuator_lag (s), one line per plant.state_delay',
            'rate': 'step dt = 1 / plant.rate (s)',
            'acceleration': f'plant.max_acceleration (m/s^2, rad/s^2 for w; {NO_LIMIT_X:g}: '
                            'no limit), harsher to the right'}.get(
        sweep, f"{entry['parameter']} ({entry['unit']})")


def write_figures(table: Dict[str, Any], sizes: Dict[str, float], rule: List[Dict[str, Any]],
                  out: str) -> List[str]:
    """One PNG per sweep: the bodies' closest approach against the setting, with their size."""
    import matplotlib
    matplotlib.use('Agg')
    import matplotlib.pyplot as plt
    paths = []
    for sweep, entry in table.items():
        path = os.path.join(out, f'robustness_{sweep}.png')
        paths.append(path)
        if sweep == 'gain':
            gain_figure(plt, rule, path)
            continue
        figure, axes = plt.subplots(figsize=(6.4, 4.2))
        for name in CONFIGS:
            rows = [r for r in entry['rows'] if r['config'] == name and 'refused' not in
                    r['summary']]
            groups = sorted({r['value'][0] for r in rows}) if sweep == 'delay_lag' else [None]
            for index, group in enumerate(groups):
                some = [r for r in rows if group is None or r['value'][0] == group]
                axes.plot([x_of(sweep, r['value']) for r in some],
                          [r['summary']['closest_bodies'] for r in some],
                          marker=MARKERS[index % 4], linestyle=STYLES[index % 4],
                          color=COLOURS[name],
                          label=(f'{name} (worst of the starts)' if group is None
                                 else f'{name}, delay {group:g} s'))
            axes.axhline(sizes[name], color=COLOURS[name], linestyle='--', linewidth=1.0,
                         label=f'{name}: bodies touch ({sizes[name]:g} m)')
        axes.set_xlabel(x_label(sweep, entry))
        axes.set_ylabel('closest approach of two bodies (m)')
        xs = [x_of(sweep, r['value']) for r in entry['rows']]
        positive = [x for x in xs if x > 0.0]
        if sweep in ('rate', 'acceleration'):
            axes.set_xscale('log')
            if sweep == 'acceleration':
                axes.invert_xaxis()
        elif positive and max(positive) / min(positive) > 20.0:
            axes.set_xscale('symlog', linthresh=min(positive), linscale=0.5)
            axes.set_xlim(0.0, 1.5 * max(positive))
        axes.set_ylim(bottom=0.0)
        axes.grid(True, alpha=0.3)
        axes.legend(fontsize=7)
        axes.set_title(f'Robustness: {sweep} (beyond the paper)')
        figure.tight_layout()
        figure.savefig(path, dpi=100)
        plt.close(figure)
    return paths


def redraw(args: argparse.Namespace) -> int:
    """--redraw: the derived results and the figures again from an earlier JSON."""
    path = os.path.join(args.out, 'bench', 'robustness.json')
    try:
        with open(path, encoding='utf-8') as stream:
            result = json.load(stream)
        table = result['sweeps']
        sizes = {name: result['configs'][name]['size'] for name in CONFIGS}
    except (OSError, ValueError, KeyError, TypeError) as exc:
        print(f'bench_robustness.py: {path} is not a robustness.json ({exc})', file=sys.stderr)
        return 2
    result['limits'] = limits_of(table)
    result['gain_rule'] = gain_rule(table, sizes)
    write_result(path, result)
    figures = write_figures(table, sizes, result['gain_rule'], args.out)
    print(markdown(table))
    print(f'\nrewrote {path} and {len(figures)} figures')
    return 0


def write_result(path: str, result: Dict[str, Any]) -> None:
    """Write the JSON of the results."""
    with open(path, 'w', encoding='utf-8') as stream:
        json.dump(result, stream, indent=1)
        stream.write('\n')


def main(argv: Optional[Sequence[str]] = None) -> int:
    """Run the sweeps, print the tables, write the JSON and the figures; 0 on success."""
    args = parse_args(argv)
    if args.physics:
        return physics_robustness.main(args, machine)
    if args.redraw:
        return redraw(args)
    os.makedirs(os.path.join(args.out, 'bench'), exist_ok=True)
    started = time.monotonic()
    host = machine()
    sweeps = settings_of(args)
    results = run_all(args, sweeps)
    sizes, size_notes = {}, {}
    for name in CONFIGS:
        sizes[name], size_notes[name] = body_size(name, load_raw(name))
    table: Dict[str, Any] = {}
    for sweep, entries in sweeps.items():
        spec = SWEEPS.get(sweep) or COMBINED[sweep]
        rows = []
        for name in CONFIGS:
            for value, settings in entries:
                runs = [results[(name, canonical(settings), seed)] for seed in range(args.seeds)]
                rows.append({'config': name, 'value': value, 'size': sizes[name], 'runs': runs,
                             'summary': summarise(runs, sizes[name])})
        table[sweep] = {'parameter': spec['parameter'], 'unit': spec['unit'],
                        'note': spec.get('note', ''), 'rows': rows}
    result = {
        'machine': host, 'arguments': {**vars(args), 'out': os.path.relpath(args.out, ROOT)},
        'wall_s': time.monotonic() - started,
        'load_after': list(os.getloadavg()),
        'configs': {name: {'path': CONFIGS[name], 'size': sizes[name], 'size_is': size_notes[name],
                           'settle_tolerance': SETTLE_TOLERANCE} for name in CONFIGS},
        'sweeps': table, 'limits': limits_of(table), 'gain_rule': gain_rule(table, sizes),
    }
    path = os.path.join(args.out, 'bench', 'robustness.json')
    write_result(path, result)
    figures = write_figures(table, sizes, result['gain_rule'], args.out)
    print(f"machine: {host['nproc']} cores, {host['cpu']}, Python {host['python']}; "
          f"{result['wall_s']:.0f} s wall, {args.seeds} starts per setting")
    print(markdown(table))
    print(f'\nwrote {path} and {len(figures)} figures: '
          + ', '.join(os.path.basename(p) for p in figures))
    return 0


if __name__ == '__main__':
    sys.exit(main())
