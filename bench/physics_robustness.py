# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
Robustness on the physics engine: ``bench_robustness.py --physics`` (issue 30, item 6).

Two parts, each selectable with ``--only``:

* the sweeps: the law on the MuJoCo engine (formation_sim --engine mujoco, in-process:
  ``simulation.engine_run.run_on_engine``), one world knob at a time from the defaults: the motors'
  limit (``world.wheel_torque`` for the differential-drive bases, ``world.force_limit`` for
  the holonomic ones), the payload (``world.mass``), the floor (``world.floor_friction``:
  the wheels slip), the control period (the law's dt, held while the engine steps) and the
  measured poses' noise (``world.pose_noise``). Teams: the six TurtleBot3-like bases of
  config/unicycle_2d.yaml, the same bases started across their hexagon
  (bench/physics_crossing.yaml: they all cross the middle, so the closest approach comes
  mid-run) and the four holonomic bases of config/lab_holonomic.yaml. Each run
  gives the engine's closest approach of two bodies (every engine step) and its footprints'
  gap, the contact events between robots, the settle time (every error <= 0.05 m from then
  on) and the final error;
* the fit: a lone base on the engine commanded a step from rest (v and w of a unicycle, a
  velocity of a point), its velocity recorded every engine step, and the plant model's lag
  (``plant.actuator_lag`` tau, ``plant.max_acceleration`` a: D1) fitted to it
  (bench/lag_fit.py) for the default world and a few torque / mass / friction settings; then
  the same team on the plant model with those tau and a (``formation_sim --engine ideal --dt``)
  against the engine: does the lag model predict the physics?

Writes OUT/bench/robustness_physics.json, OUT/robustness_physics_sweeps.png and
OUT/robustness_physics_fit.png, prints a Markdown table per sweep and the fit's tables.
"""

import argparse
from concurrent.futures import ProcessPoolExecutor
import json
import math
import os
import sys
import time
from typing import Any, Callable, Dict, Iterator, List, Optional, Tuple

BENCH = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(BENCH)
sys.path[:0] = [ROOT, BENCH]

from formation_ros.core.runs.metrics import SETTLE_TOLERANCE  # noqa: E402
from formation_ros.core.settings.params import (FormationConfig, validate,  # noqa: E402
                                                WorldSettings)
from formation_ros.core.settings.params_file import load_params_file  # noqa: E402
from lag_fit import fit_lag, model_response  # noqa: E402
import numpy as np  # noqa: E402

RESULT = 'robustness_physics.json'
FIGURE = 'robustness_physics_{}.png'
TEAMS: Dict[str, Dict[str, Any]] = {
    'turtlebot3': {'path': 'config/unicycle_2d.yaml', 'duration': 90.0,
                   'what': 'six TurtleBot3-like differential-drive bases'},
    'crossing': {'path': 'bench/physics_crossing.yaml', 'duration': 120.0,
                 'what': 'the same bases started across the hexagon from their places'},
    'holonomic': {'path': 'config/lab_holonomic.yaml', 'duration': 60.0,
                  'what': 'four holonomic bases, commands in their body frame'},
}
CONTROL_DT = 'control.dt'
"""The law's period on the engine (formation_sim --dt), s; not a parameter of the file."""
DEFAULT_CONTROL_DT = 0.02
DEFAULTS = {**{f'world.{name}': getattr(WorldSettings(), name)
               for name in ('wheel_torque', 'force_limit', 'mass', 'floor_friction',
                            'pose_noise')}, CONTROL_DT: DEFAULT_CONTROL_DT}
PHYSICS_SWEEPS: Dict[str, Dict[str, Any]] = {
    'torque': {'parameter': {'turtlebot3': 'world.wheel_torque', 'crossing': 'world.wheel_torque',
                             'holonomic': 'world.force_limit'},
               'unit': 'N m per wheel (holonomic: N per axis)',
               'values': {'turtlebot3': [0.2, 0.1, 0.05, 0.02, 0.01, 0.005],
                          'crossing': [0.2, 0.1, 0.05, 0.02, 0.01, 0.005],
                          'holonomic': [5.0, 2.0, 1.0, 0.5, 0.2, 0.1]},
               'quick': {'turtlebot3': [0.2, 0.02], 'crossing': [0.2, 0.02],
                         'holonomic': [5.0, 0.5]},
               'note': "the motors' limit; the first value is the default"},
    'mass': {'parameter': 'world.mass', 'unit': 'kg', 'values': [1.0, 2.0, 5.0, 10.0, 20.0, 50.0],
             'quick': [1.0, 10.0], 'note': 'the whole base; the motors stay the same'},
    'friction': {'parameter': 'world.floor_friction', 'unit': 'sliding coefficient',
                 'values': [1.0, 0.3, 0.1, 0.03, 0.01], 'quick': [1.0, 0.03],
                 'note': 'lower: the wheels slip'},
    'rate': {'parameter': CONTROL_DT, 'unit': 's', 'values': [0.02, 0.05, 0.1, 0.2, 0.3, 0.4],
             'quick': [0.02, 0.2],
             'note': 'the law every dt, held while the engine steps; world.cmd_timeout 0.5 s'},
    'noise': {'parameter': 'world.pose_noise', 'unit': 'm', 'values': [0.0, 0.01, 0.03, 0.1, 0.3],
              'quick': [0.0, 0.1], 'note': 'Gaussian on every measured position'},
}
FIT_SETTINGS: Dict[str, List[Tuple[str, Dict[str, float]]]] = {
    'turtlebot3': [('default', {}), ('torque 0.05 N m', {'world.wheel_torque': 0.05}),
                   ('mass 5 kg', {'world.mass': 5.0}),
                   ('friction 0.1', {'world.floor_friction': 0.1})],
    'holonomic': [('default', {}), ('force 1 N', {'world.force_limit': 1.0}),
                  ('mass 5 kg', {'world.mass': 5.0})],
}
STEPS = {'turtlebot3': {'v': 0.2, 'w': 2.0}, 'holonomic': {'x': 0.2}}
BODY_OF = {'turtlebot3': 'turtlebot3', 'crossing': 'turtlebot3', 'holonomic': 'holonomic'}
"""Whose bodies a team has: the fit is one per body (the crossing team's are the same)."""
"""The commanded steps: v (m/s) and w (rad/s) of a base, a velocity along x of a point."""
STEP_DURATION = 1.0
QUICK_DURATION = 2.0
QUICK_STEP_DURATION = 0.3
PARTS = tuple(PHYSICS_SWEEPS) + ('fit',)
Settings = Tuple[Tuple[str, float], ...]


def sweep_parameter(sweep: str, team: str) -> str:
    """Return the parameter a sweep changes for a team."""
    parameter = PHYSICS_SWEEPS[sweep]['parameter']
    return parameter[team] if isinstance(parameter, dict) else parameter


def sweep_values(sweep: str, team: str, quick: bool) -> List[float]:
    """Return a sweep's values for a team, the default first, harsher after."""
    values = PHYSICS_SWEEPS[sweep]['quick' if quick else 'values']
    return list(values[team] if isinstance(values, dict) else values)


def canonical(settings: Settings) -> Settings:
    """Drop the default values and sort: one key per distinct run."""
    return tuple(sorted((k, float(v)) for k, v in settings if v != DEFAULTS.get(k)))


def team_config(team: str, settings: Settings, seed_offset: int = 0,
                extra: Optional[Dict[str, Any]] = None) -> Tuple[FormationConfig, float]:
    """Return the team's config with ``settings`` (world.*, control.dt), start.seed moved on."""
    raw = load_params_file(os.path.join(ROOT, TEAMS[team]['path']))
    raw = {**raw, 'start.seed': int(raw.get('start.seed', 0)) + seed_offset, **(extra or {})}
    control_dt = DEFAULT_CONTROL_DT
    for key, value in settings:
        if key == CONTROL_DT:
            control_dt = float(value)
        else:
            raw[key] = value
    return validate(raw), control_dt


def footprint_size(config: FormationConfig) -> float:
    """Return the distance below which two robots' footprints touch: 2 x body.radius, m."""
    return 2.0 * float(config.body.radius)


def engine_job(job: Tuple[str, Settings, int, float]) -> Dict[str, Any]:
    """Run one team on the engine with one setting from one start; return its measures."""
    from formation_ros.simulation.engine_run import engine_problem, run_on_engine
    from formation_ros.simulation.simulate import Progress, run_metrics, shapes_of
    team, settings, seed_offset, duration = job
    started = time.monotonic()
    config, control_dt = team_config(team, settings, seed_offset)
    problem = engine_problem(config, control_dt)
    if problem:
        return {'refused': problem}
    run = run_on_engine(config, duration, control_dt, control_dt, shapes_of(config),
                        Progress(duration, quiet=True))
    metrics = run_metrics(run.trajectory, config, f'MuJoCo, the law every {control_dt:g} s')
    stats = run.stats.record()
    return {
        'seed': int(config.values['start.seed']),
        'closest_bodies': stats['min_body_distance'],
        'footprint_gap': stats['min_footprint_gap'],
        'contacts': stats['contacts'],
        'first_contact': stats['contact_events'][0] if stats['contact_events'] else None,
        'settle_time': metrics['settle_time'],
        'converged': metrics['settle_time'] is not None,
        'final_max_error': metrics['final_max_error'],
        'closest_control_points': metrics['min_pair_distance'],
        'max_abs_u_hat': metrics['max_abs_u_hat_component'],
        'u_bound': metrics['u_bound'],
        'max_abs_v': metrics.get('max_abs_v'),
        'max_abs_omega': metrics.get('max_abs_omega'),
        'realtime_factor': stats['engine_realtime_factor'],
        'wall_s': time.monotonic() - started,
    }


def ideal_job(job: Tuple[str, float, float, float, float]) -> Dict[str, Any]:
    """Run one team on the plant model with a lag tau and a limit a; return its measures."""
    from formation_ros.simulation.simulate import Progress, run_fixed_step, run_metrics
    team, lag, acceleration, duration, control_dt = job
    started = time.monotonic()
    config, _ = team_config(team, (), 0, {'plant.actuator_lag': lag,
                                          'plant.max_acceleration': acceleration})
    size = footprint_size(config)
    run = run_fixed_step(config, duration, control_dt, control_dt,
                         Progress(duration, quiet=True), collision_distance=size)
    metrics = run_metrics(run.trajectory, config, f'zero-order hold, dt = {control_dt:g} s')
    closest = metrics.get('min_body_distance', metrics['min_pair_distance'])
    return {'closest_bodies': closest, 'footprint_gap': closest - size,
            'contacts': run.counts.collisions, 'settle_time': metrics['settle_time'],
            'converged': metrics['settle_time'] is not None,
            'final_max_error': metrics['final_max_error'],
            'max_abs_v': metrics.get('max_abs_v'), 'max_abs_omega': metrics.get('max_abs_omega'),
            'wall_s': time.monotonic() - started}


def pool_map(function: Callable[[Any], Dict[str, Any]], work: List[Any],
             jobs: int) -> Iterator[Dict[str, Any]]:
    """Map in this process (one job) or in a pool of ``jobs`` processes."""
    if jobs <= 1:
        return map(function, work)
    with ProcessPoolExecutor(max_workers=jobs) as pool:
        return iter(list(pool.map(function, work)))


def summarise(runs: List[Dict[str, Any]]) -> Dict[str, Any]:
    """Worst case over the starts of one setting."""
    done = [r for r in runs if 'refused' not in r]
    if not done:
        return {'refused': runs[0]['refused']}
    settles = [r['settle_time'] for r in done]
    gap = min(r['footprint_gap'] for r in done)
    contacts = sum(r['contacts'] for r in done)
    firsts = [r['first_contact'] for r in done if r['first_contact']]
    return {
        'closest_bodies': min(r['closest_bodies'] for r in done),
        'footprint_gap': gap, 'contacts': contacts,
        'first_contact': min(firsts, key=lambda e: e['t']) if firsts else None,
        'held': contacts == 0 and gap >= 0.0,
        'converged': sum(r['converged'] for r in done), 'starts': len(done),
        'settle_time': None if None in settles else max(settles),
        'final_max_error': max(r['final_max_error'] for r in done),
        'max_abs_u_hat': max(r['max_abs_u_hat'] for r in done), 'u_bound': done[0]['u_bound'],
        'max_abs_v': (None if done[0]['max_abs_v'] is None
                      else max(r['max_abs_v'] for r in done)),
        'max_abs_omega': (None if done[0]['max_abs_omega'] is None
                          else max(r['max_abs_omega'] for r in done)),
    }


def run_sweeps(sweeps: List[str], teams: List[str], seeds: int, quick: bool,
               jobs: int) -> Dict[str, Any]:
    """Run every distinct (team, settings, start) of the sweeps once; return the tables."""
    entries = {sweep: {team: [(value, ((sweep_parameter(sweep, team), value),))
                              for value in sweep_values(sweep, team, quick)]
                       for team in teams} for sweep in sweeps}
    keys = sorted({(team, canonical(settings), seed) for sweep in sweeps for team in teams
                   for _, settings in entries[sweep][team] for seed in range(seeds)})
    durations = {team: QUICK_DURATION if quick else TEAMS[team]['duration'] for team in teams}
    work = [(team, settings, seed, durations[team]) for team, settings, seed in keys]
    results: Dict[Tuple[str, Settings, int], Dict[str, Any]] = {}
    started = time.monotonic()
    for count, (key, result) in enumerate(zip(keys, pool_map(engine_job, work, jobs)), 1):
        results[key] = result
        team, settings, seed = key
        what = ', '.join(f'{k} = {v:g}' for k, v in settings) or 'defaults'
        outcome = result.get('refused') or (
            f"closest bodies {result['closest_bodies']:.3f} m, {result['contacts']} contact(s), "
            f"{'settled' if result['converged'] else 'not settled'}")
        print(f'bench_robustness --physics: {count}/{len(keys)} {team} seed +{seed} ({what}): '
              f'{outcome}; {time.monotonic() - started:.0f} s', file=sys.stderr, flush=True)
    table: Dict[str, Any] = {}
    for sweep in sweeps:
        spec = PHYSICS_SWEEPS[sweep]
        rows = []
        for team in teams:
            size = footprint_size(team_config(team, ())[0])
            for value, settings in entries[sweep][team]:
                runs = [results[(team, canonical(settings), seed)] for seed in range(seeds)]
                rows.append({'team': team, 'parameter': sweep_parameter(sweep, team),
                             'value': value, 'size': size, 'runs': runs,
                             'summary': summarise(runs)})
        table[sweep] = {'unit': spec['unit'], 'note': spec['note'],
                        'wall_s': sum(r.get('wall_s', 0.0) for row in rows
                                      for r in row['runs']), 'rows': rows}
    return table


def limits_of(table: Dict[str, Any]) -> Dict[str, Dict[str, Any]]:
    """Return, per sweep and team, the last value that held (no contact) and the first not."""
    limits: Dict[str, Dict[str, Any]] = {}
    for sweep, entry in table.items():
        limits[sweep] = {}
        for team in sorted({row['team'] for row in entry['rows']}):
            found: Dict[str, Any] = {'held_up_to': None, 'first_contact_at': None,
                                     'settled_up_to': None, 'first_not_settled': None}
            for row in (r for r in entry['rows'] if r['team'] == team):
                summary = row['summary']
                if 'refused' in summary:
                    continue
                settled = summary['converged'] == summary['starts']
                for good, ok, bad in (('held_up_to', summary['held'], 'first_contact_at'),
                                      ('settled_up_to', settled, 'first_not_settled')):
                    if found[bad] is None:
                        found[good if ok else bad] = row['value']
            limits[sweep][team] = found
    return limits


def step_response(team: str, overrides: Dict[str, float],
                  duration: float) -> Dict[str, Dict[str, List[float]]]:
    """
    Command a lone base a step from rest on the engine; record its velocity every step.

    Two robots 20 m apart (a team has at least two): a unicycle team's first base gets
    (v, 0) and its second (0, w); a point team's first base a velocity along x (its heading
    0, so body and world frames agree). Returns, per component, the times and the velocity.
    """
    import mujoco
    from formation_ros.physics.engine import Engine
    raw = load_params_file(os.path.join(ROOT, TEAMS[team]['path']))
    raw = {k: v for k, v in raw.items() if not k.startswith('start.')}
    raw.update({'num_robots': 2, 'formation.vertices': [0.0, 0.0, 20.0, 0.0],
                'start.positions': [0.0, 0.0, 20.0, 0.0], 'start.headings': [0.0, 0.0],
                **overrides})
    engine = Engine(validate(raw))
    steps = STEPS[BODY_OF[team]]
    unicycle = 'v' in steps
    command = ([[steps['v'], 0.0], [0.0, steps['w']]] if unicycle
               else [[steps['x'], 0.0], [0.0, 0.0]])
    bodies = [int(mujoco.mj_name2id(engine.mj_model, mujoco.mjtObj.mjOBJ_BODY, name))
              for name in engine.scene.names]
    velocity = np.zeros(6)
    times: List[float] = []
    first: List[float] = []
    second: List[float] = []
    for _ in range(int(round(duration / engine.world.timestep))):
        engine.apply(command)
        engine.step(1)
        times.append(engine.time_s)
        mujoco.mj_objectVelocity(engine.mj_model, engine.data, mujoco.mjtObj.mjOBJ_XBODY,
                                 bodies[0], velocity, 0)
        heading = float(engine.poses().headings[0])
        first.append(float(velocity[3] * math.cos(heading) + velocity[4] * math.sin(heading)))
        if unicycle:
            mujoco.mj_objectVelocity(engine.mj_model, engine.data, mujoco.mjtObj.mjOBJ_XBODY,
                                     bodies[1], velocity, 0)
            second.append(float(velocity[2]))
    if unicycle:
        return {'v': {'t': times, 'velocity': first, 'step': steps['v']},
                'w': {'t': times, 'velocity': second, 'step': steps['w']}}
    return {'x': {'t': times, 'velocity': first, 'step': steps['x']}}


def run_fit(teams: List[str], quick: bool, jobs: int,
            sweeps: Dict[str, Any]) -> Dict[str, Any]:
    """Fit (D1) to the engine's step responses; run the team on both bodies side by side."""
    duration = QUICK_STEP_DURATION if quick else STEP_DURATION
    fits: Dict[str, Any] = {}
    side: List[Tuple[str, str, Settings]] = []
    for team in teams:
        body = BODY_OF[team]
        settings_list = FIT_SETTINGS[body][:2] if quick else FIT_SETTINGS[body]
        for label, overrides in settings_list:
            side.append((team, label, canonical(tuple(overrides.items()))))
            if body in fits and any(f['label'] == label for f in fits[body]):
                continue
            response = step_response(team, overrides, duration)
            each = {name: fit_lag([(r['t'], r['velocity'], r['step'])]).as_dict()
                    for name, r in response.items()}
            joint = fit_lag([(r['t'], r['velocity'], r['step'])
                             for r in response.values()]).as_dict()
            model = joint if len(each) > 1 else next(iter(each.values()))
            fits.setdefault(body, []).append({
                'label': label, 'settings': overrides, 'response': response, 'fit': each,
                'joint': joint, 'used': {'lag': model['lag'],
                                         'max_acceleration': model['max_acceleration']}})
            print(f'bench_robustness --physics: fit {body} {label}: '
                  + ', '.join(f"{name} tau {f['lag']:.4f} s a {f['max_acceleration']:.3g} "
                              f"rms {f['rms']:.2g}" for name, f in each.items()),
                  file=sys.stderr, flush=True)
    cached = {}
    for entry in sweeps.values():
        for row in entry['rows']:
            key = (row['team'], canonical(((row['parameter'], row['value']),)))
            cached[key] = row['runs'][0]
    durations = {team: QUICK_DURATION if quick else TEAMS[team]['duration'] for team in teams}
    missing = [(team, settings, 0, durations[team]) for team, _, settings in side
               if (team, settings) not in cached]
    for job, result in zip(missing, pool_map(engine_job, missing, jobs)):
        cached[(job[0], job[1])] = result
    used = {(team, label): next(f for f in fits[BODY_OF[team]] if f['label'] == label)['used']
            for team, label, _ in side}
    ideal_work = [(team, used[(team, label)]['lag'], used[(team, label)]['max_acceleration'],
                   durations[team], DEFAULT_CONTROL_DT) for team, label, _ in side]
    plain = [(team, 0.0, 0.0, durations[team], DEFAULT_CONTROL_DT) for team in teams]
    results = list(pool_map(ideal_job, ideal_work + plain, jobs))
    rows = []
    for (team, label, settings), ideal in zip(side, results):
        rows.append({'team': team, 'label': label, 'engine': cached[(team, settings)],
                     'lag_model': ideal,
                     'ideal': results[len(ideal_work) + teams.index(team)],
                     'used': used[(team, label)]})
    return {'step_duration': duration, 'control_dt': DEFAULT_CONTROL_DT, 'fits': fits,
            'side_by_side': rows}


def fmt(value: Any, digits: int = 3) -> str:
    """Format a number for a table (None: '-')."""
    if value is None:
        return '-'
    return f'{value:.{digits}g}'


def markdown(table: Dict[str, Any]) -> str:
    """Markdown tables of every physics sweep."""
    lines = []
    for sweep, entry in table.items():
        lines += [f"\n### {sweep} ({entry['unit']}; {entry['note']})\n",
                  "| team | parameter | value | closest bodies (m) | footprints' gap (m) | "
                  'contacts | settled | settle time (s) | final error (m) | max \\|v\\| | '
                  'max \\|w\\| |', '|---|---|---:|---:|---:|---:|---|---:|---:|---:|---:|']
        for row in entry['rows']:
            s = row['summary']
            if 'refused' in s:
                lines.append(f"| {row['team']} | {row['parameter']} | {fmt(row['value'])} | "
                             f"refused: {s['refused']} | | | | | | | |")
                continue
            first = s['first_contact']
            contacts = (str(s['contacts']) if first is None
                        else f"{s['contacts']} (first at {first['t']:.1f} s)")
            lines.append(
                f"| {row['team']} | `{row['parameter']}` | {fmt(row['value'])} | "
                f"{s['closest_bodies']:.3f} | {s['footprint_gap']:+.3f} | {contacts} | "
                f"{s['converged']}/{s['starts']} | {fmt(s['settle_time'], 4)} | "
                f"{fmt(s['final_max_error'], 2)} | {fmt(s['max_abs_v'])} | "
                f"{fmt(s['max_abs_omega'])} |")
    return '\n'.join(lines)


def fit_markdown(fit: Dict[str, Any]) -> str:
    """Markdown tables of the fits and of the side-by-side runs."""
    lines = ['\n### the lag model fitted to the step responses\n',
             '| bases | world | step | tau (s) | a | RMS error | RMS / step |',
             '|---|---|---|---:|---:|---:|---:|']
    units = {'v': 'm/s', 'w': 'rad/s', 'x': 'm/s'}
    for team, entries in fit['fits'].items():
        for entry in entries:
            for name, f in list(entry['fit'].items()) + (
                    [('v and w, one tau and a', entry['joint'])] if len(entry['fit']) > 1
                    else []):
                step = entry['response'].get(name, {}).get('step')
                step_text = f'{name} {step:g} {units[name]}' if step is not None else name
                unit = units.get(name, '')
                a_text = ('no limit' if f['max_acceleration'] == 0.0
                          else f"{f['max_acceleration']:.3g} {unit}/s")
                rms_text = (f"{f['rms']:.2g} {unit}" if unit else f"{f['rms']:.2g} of a step")
                lines.append(f"| {team} | {entry['label']} | {step_text} | {f['lag']:.4f} | "
                             f"{a_text} | {rms_text} | {100.0 * f['relative_rms']:.1f} % |")
    lines += ['\n### the team on the fitted lag model against the engine\n',
              '| team | world | plant model: tau (s), a | bodies | settle time (s) | '
              'closest bodies (m) | contacts | final error (m) |',
              '|---|---|---|---|---:|---:|---:|---:|']
    for row in fit['side_by_side']:
        used = row['used']
        for what, run in (('engine', row['engine']), ('lag model', row['lag_model']),
                          ('ideal, no lag', row['ideal'])):
            if 'refused' in run:
                continue
            model = (f"{used['lag']:.3f}, {fmt(used['max_acceleration'])}"
                     if what == 'lag model' else '')
            lines.append(f"| {row['team']} | {row['label']} | {model} | {what} | "
                         f"{fmt(run['settle_time'], 4)} | {run['closest_bodies']:.4f} | "
                         f"{run['contacts']} | {fmt(run['final_max_error'], 2)} |")
    return '\n'.join(lines)


COLOURS = {'turtlebot3': 'tab:orange', 'crossing': 'tab:blue', 'holonomic': 'tab:green'}


NOISE_ZERO_X = 1e-3
"""Where the noise panel draws no noise (log axis), m."""
TICKS = {'torque': [1.0, 0.5, 0.2, 0.1, 0.05, 0.02], 'mass': [1.0, 2.0, 5.0, 10.0, 20.0, 50.0],
         'friction': [1.0, 0.3, 0.1, 0.03, 0.01], 'rate': [0.02, 0.05, 0.1, 0.2, 0.4],
         'noise': [NOISE_ZERO_X, 0.01, 0.03, 0.1, 0.3]}
X_LABELS = {'torque': "the motors' limit / the default (0.2 N m per wheel; holonomic: 5 N)",
            'mass': 'world.mass (kg)', 'friction': 'world.floor_friction',
            'rate': 'control period dt (s)', 'noise': 'world.pose_noise (m)'}


def x_of(sweep: str, team: str, value: float) -> float:
    """Where a value goes on its panel's log x axis (torque: over the default; no noise)."""
    if sweep == 'torque':
        return float(value) / DEFAULTS[sweep_parameter(sweep, team)]
    return NOISE_ZERO_X if sweep == 'noise' and value == 0.0 else float(value)


def sweeps_figure(plt: Any, table: Dict[str, Any], path: str) -> None:
    """Draw the closest approach over the footprints' size and the settle time per knob."""
    sweeps = list(table)
    figure, axes = plt.subplots(2, len(sweeps), figsize=(3.2 * len(sweeps), 6.2),
                                squeeze=False)
    for column, sweep in enumerate(sweeps):
        top, bottom = axes[0][column], axes[1][column]
        for team in [t for t in TEAMS if any(r['team'] == t for r in table[sweep]['rows'])]:
            rows = [r for r in table[sweep]['rows'] if r['team'] == team
                    and 'refused' not in r['summary']]
            xs = [x_of(sweep, team, r['value']) for r in rows]
            ratio = [r['summary']['closest_bodies'] / r['size'] for r in rows]
            top.plot(xs, ratio, marker='o', color=COLOURS[team], label=team)
            touched = [(x, y) for x, y, r in zip(xs, ratio, rows) if r['summary']['contacts']]
            if touched:
                top.scatter(*zip(*touched), marker='x', s=80, color='k', zorder=3,
                            label=f'{team}: contact')
            settle = [(x, r['summary']['settle_time']) for x, r in zip(xs, rows)
                      if r['summary']['settle_time'] is not None]
            if settle:
                bottom.plot(*zip(*settle), marker='o', color=COLOURS[team], label=team)
            unsettled = [(x, r['summary'].get('duration', 0.0)) for x, r in zip(xs, rows)
                         if r['summary']['settle_time'] is None]
            if unsettled:
                bottom.scatter(*zip(*unsettled), marker='v', s=50, color=COLOURS[team],
                               label=f'{team}: not settled by the end')
        top.axhline(1.0, color='k', linestyle='--', linewidth=1.0)
        for axis in (top, bottom):
            axis.set_xscale('log')
            axis.set_xticks(TICKS[sweep])
            axis.set_xticklabels(['0' if sweep == 'noise' and x == NOISE_ZERO_X else f'{x:g}'
                                  for x in TICKS[sweep]], fontsize=7)
            axis.minorticks_off()
            axis.grid(True, alpha=0.3)
            if sweep in ('torque', 'friction'):
                axis.invert_xaxis()
        bottom.set_xlabel(X_LABELS[sweep], fontsize=7)
        top.set_title(f'{sweep} (harsher to the right)', fontsize=9)
        top.set_ylim(bottom=0.0)
        bottom.set_ylim(bottom=0.0)
        if column == 0:
            top.set_ylabel("closest approach / footprints' size 2 r")
            bottom.set_ylabel('settle time (s); v: not settled')
            top.legend(fontsize=7, loc='lower left')
        if column == len(sweeps) - 1:
            bottom.legend(fontsize=6, loc='lower left')
    figure.suptitle('On the physics engine: closest approach of two bodies (dashed: their '
                    'footprints touch) and settle time, one knob at a time', fontsize=10)
    figure.tight_layout()
    figure.savefig(path, dpi=90)
    plt.close(figure)


def fit_figure(plt: Any, fit: Dict[str, Any], path: str) -> None:
    """Draw the engine's step responses (solid) and the fitted lag model's (dashed)."""
    panels = [(team, name) for team, entries in fit['fits'].items()
              for name in entries[0]['response']]
    figure, axes = plt.subplots(1, len(panels), figsize=(4.6 * len(panels), 3.8), squeeze=False)
    units = {'v': 'v (m/s)', 'w': 'w (rad/s)', 'x': 'velocity along x (m/s)'}
    colours = ('tab:blue', 'tab:red', 'tab:purple', 'tab:brown')
    for axis, (team, name) in zip(axes[0], panels):
        for colour, entry in zip(colours, fit['fits'][team]):
            response = entry['response'][name]
            f = entry['fit'][name]
            t = np.asarray(response['t'])
            axis.plot(t, response['velocity'], color=colour, linewidth=1.6,
                      label=f"{entry['label']}: engine")
            axis.plot(t, model_response(t, response['step'], f['lag'], f['max_acceleration']),
                      color=colour, linestyle='--', linewidth=1.0,
                      label=f"fit tau {f['lag']:.3f} s, a {fmt(f['max_acceleration'])}")
        axis.set_title(f'{team}: a step of {name} from rest', fontsize=9)
        axis.set_xlabel('time (s)')
        axis.set_ylabel(units[name])
        axis.set_xlim(0.0, min(0.6, float(np.max(t))))
        axis.grid(True, alpha=0.3)
        axis.legend(fontsize=6)
    figure.suptitle('Step responses on the engine (solid) and the lag model D1 fitted to them '
                    '(dashed)', fontsize=10)
    figure.tight_layout()
    figure.savefig(path, dpi=90)
    plt.close(figure)


def write_figures(result: Dict[str, Any], out: str) -> List[str]:
    """Write the figures of the parts present; return their paths."""
    import matplotlib
    matplotlib.use('Agg')
    import matplotlib.pyplot as plt
    paths = []
    if result.get('sweeps'):
        paths.append(os.path.join(out, FIGURE.format('sweeps')))
        sweeps_figure(plt, result['sweeps'], paths[-1])
    if result.get('fit'):
        paths.append(os.path.join(out, FIGURE.format('fit')))
        fit_figure(plt, result['fit'], paths[-1])
    return paths


def read_result(path: str) -> Dict[str, Any]:
    """Read an earlier robustness_physics.json (ValueError when it is not one)."""
    with open(path, encoding='utf-8') as stream:
        result = json.load(stream)
    if not isinstance(result, dict) or not isinstance(result.get('sweeps', {}), dict):
        raise ValueError('not a JSON object with sweeps')
    return result


def main(args: argparse.Namespace, machine: Callable[[], Dict[str, Any]]) -> int:
    """Run the selected parts (merged into an earlier JSON with --only), write, print."""
    path = os.path.join(args.out, 'bench', RESULT)
    earlier: Dict[str, Any] = {}
    if args.redraw or args.only:
        try:
            earlier = read_result(path)
        except FileNotFoundError:
            if args.redraw:
                print(f'bench_robustness.py: no {path} to redraw', file=sys.stderr)
                return 2
        except (OSError, ValueError, KeyError, TypeError) as exc:
            print(f'bench_robustness.py: {path} is not a {RESULT} ({exc})', file=sys.stderr)
            return 2
    if args.redraw:
        result = earlier
    else:
        os.makedirs(os.path.join(args.out, 'bench'), exist_ok=True)
        parts = args.only or list(PARTS)
        teams = args.teams
        started = time.monotonic()
        host = machine()
        sweeps = run_sweeps([p for p in parts if p in PHYSICS_SWEEPS], teams, args.seeds,
                            args.quick, args.jobs)
        sweeps_wall = time.monotonic() - started
        for row in (row for entry in sweeps.values() for row in entry['rows']):
            row['summary']['duration'] = (QUICK_DURATION if args.quick
                                          else TEAMS[row['team']]['duration'])
        result = {**earlier}
        result['sweeps'] = {**earlier.get('sweeps', {})}
        for name, entry in sweeps.items():
            kept = [row for row in result['sweeps'].get(name, {}).get('rows', ())
                    if row['team'] not in teams]
            result['sweeps'][name] = {**entry, 'rows': kept + entry['rows']}
        if 'fit' in parts:
            fit_started = time.monotonic()
            fit = run_fit(teams, args.quick, args.jobs, result['sweeps'])
            fit['wall_s'] = time.monotonic() - fit_started
            before = earlier.get('fit') or {'fits': {}, 'side_by_side': []}
            fit['fits'] = {**{team: entries for team, entries in before['fits'].items()
                              if team not in teams}, **fit['fits']}
            fit['side_by_side'] = [row for row in before['side_by_side']
                                   if row['team'] not in teams] + fit['side_by_side']
            result['fit'] = fit
        import mujoco
        runs = {'machine': host, 'mujoco': mujoco.__version__, 'parts': parts,
                'arguments': {**vars(args), 'out': os.path.relpath(args.out, ROOT)},
                'sweeps_wall_s': sweeps_wall, 'wall_s': time.monotonic() - started,
                'load_after': list(os.getloadavg())}
        result['runs'] = earlier.get('runs', []) + [runs]
        result['teams'] = {team: {**TEAMS[team],
                                  'size': footprint_size(team_config(team, ())[0]),
                                  'settle_tolerance': SETTLE_TOLERANCE}
                           for team in TEAMS}
        result['defaults'] = DEFAULTS
    result['limits'] = limits_of(result.get('sweeps', {}))
    with open(path, 'w', encoding='utf-8') as stream:
        json.dump(result, stream, indent=1)
        stream.write('\n')
    figures = write_figures(result, args.out)
    if not args.redraw:
        last = result['runs'][-1]
        host = last['machine']
        print(f"machine: {host['nproc']} cores, {host['cpu']}, Python {host['python']}, "
              f"MuJoCo {last['mujoco']}; {last['wall_s']:.0f} s wall, {args.seeds} start(s) "
              'per setting')
    print(markdown(result.get('sweeps', {})))
    if result.get('fit'):
        print(fit_markdown(result['fit']))
    print(f'\nwrote {path} and ' + ', '.join(os.path.basename(p) for p in figures))
    return 0
