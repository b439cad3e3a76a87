# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
formation_sim at scale: the default-sampling rule, lazy imports, and the exact fast paths.

The rule (``simulation.simulate.default_sample_dt``) is checked against a brute-force search over
the multiples of the default spacing; a thinned run must keep exactly the samples of the full run
at its own times; the fast paths of the law and of the admission must give the very numbers of
the general formulas, written out here once more.
"""

import json
import math
import os
import subprocess
import sys

from formation_ros.core.maths.law import make_law, team_command
from formation_ros.core.maths.reference import Reference
from formation_ros.core.model.plant import Commands, PlantModel
from formation_ros.core.runs.trajectory import Trajectory, TRAJECTORY_FILE
from formation_ros.core.settings.params import load_config
from formation_ros.simulation import simulate
from formation_ros.tools import sim
import numpy as np
import pytest
from scipy.spatial import cKDTree

ROOT = os.path.join(os.path.dirname(__file__), '..')
SECTION5 = os.path.join(ROOT, 'config', 'paper_section5.yaml')


def samples_of(duration, dt, sample_dt):
    """How many samples a run keeps, counted one by one as run_fixed_step / RK45 keep them."""
    if dt is None:
        return len(simulate.sample_times(duration, sample_dt))
    steps = int(round(duration / dt))
    stride = max(1, int(round(sample_dt / dt)))
    return sum(1 for k in range(steps) if k % stride == 0) + 1


@pytest.mark.parametrize('robots, duration, dt', [
    (10, 20.0, 0.01), (1000, 20.0, 0.01), (1000, 20.0, None), (2500, 20.0, 0.01),
    (10000, 20.0, 0.01), (10000, 20.0, None), (10000, 20.0, 0.025), (10000, 20.0, 0.05),
    (3000, 7.3, 0.003), (10 ** 7, 20.0, 0.01)])
def test_default_spacing_is_the_smallest_multiple_within_the_cap(robots, duration, dt):
    spacing = simulate.default_sample_dt(robots, duration, dt)
    multiples = [m for m in range(1, 3000)
                 if m * simulate.DEFAULT_SAMPLE_DT >= duration
                 or robots * samples_of(duration, dt, m * simulate.DEFAULT_SAMPLE_DT)
                 <= simulate.MAX_ROBOT_SAMPLES]
    wanted = min(multiples[0] * simulate.DEFAULT_SAMPLE_DT, duration)
    assert spacing == pytest.approx(wanted, rel=1e-12)
    assert simulate.sample_count(duration, dt, spacing) == samples_of(duration, dt, spacing)
    if spacing < duration:
        assert robots * samples_of(duration, dt, spacing) <= simulate.MAX_ROBOT_SAMPLES


def test_ten_thousand_robots_over_20_s_are_sampled_every_50_ms():
    assert simulate.default_sample_dt(10000, 20.0, 0.01) == 0.05
    assert simulate.default_sample_dt(1000, 20.0, 0.01) == simulate.DEFAULT_SAMPLE_DT
    meta = simulate.sampling_metadata(10000, 20.0, 0.01, None)
    assert meta == {'sample_dt': 0.05, 'sampling': 'default, thinned',
                    'max_robot_samples': simulate.MAX_ROBOT_SAMPLES}
    assert simulate.sampling_metadata(10000, 20.0, 0.01, 0.01)['sampling'] == 'given'
    assert simulate.sampling_metadata(10, 20.0, None, None)['sampling'] == 'default'


def test_help_states_the_rule():
    text = sim.build_parser().format_help()
    assert f'{simulate.MAX_ROBOT_SAMPLES:,}' in text
    assert 'robots x samples' in ' '.join(text.split())


def run_main(tmp_path, name, *options):
    out = tmp_path / name
    assert sim.main([SECTION5, '--out', str(out), '--no-plots', '--quiet', *options]) == 0
    return (Trajectory.load(str(out / TRAJECTORY_FILE)),
            json.loads((out / simulate.METRICS_FILE).read_text()))


@pytest.mark.parametrize('step', [('--dt', '0.01'), ()])
def test_a_thinned_run_keeps_the_full_runs_samples_at_its_times(tmp_path, monkeypatch, step):
    options = ('--duration', '2', *step)
    full, full_metrics = run_main(tmp_path, 'full', *options)
    assert full_metrics['sampling'] == 'default' and full_metrics['sample_dt'] == 0.01
    assert len(full.t) == 201
    monkeypatch.setattr(simulate, 'MAX_ROBOT_SAMPLES', 10 * 60)
    thin, thin_metrics = run_main(tmp_path, 'thin', *options)
    assert thin_metrics['sampling'] == 'default, thinned'
    assert thin_metrics['sample_dt'] == 0.04 and thin_metrics['max_robot_samples'] == 600
    assert len(thin.t) == 51 and thin.num_robots * len(thin.t) <= 600
    given, _ = run_main(tmp_path, 'given', *options, '--sample-dt', '0.04')
    for name in ('t', 'q', 'u', 'u_hat', 'q_desired', 'q_od'):
        assert np.array_equal(getattr(thin, name), getattr(given, name)), name
    if step:  # the same plant steps: the kept samples are the full run's, bit for bit
        for name in ('t', 'q', 'u', 'u_hat', 'q_desired', 'q_od'):
            assert np.array_equal(getattr(thin, name), getattr(full, name)[::4]), name


def test_a_small_run_without_sample_dt_is_the_run_at_the_default_spacing(tmp_path):
    default, metrics = run_main(tmp_path, 'default', '--duration', '1', '--dt', '0.01')
    given, _ = run_main(tmp_path, 'given', '--duration', '1', '--dt', '0.01', '--sample-dt',
                        '0.01')
    assert metrics['sampling'] == 'default'
    for name in ('t', 'q', 'u', 'u_hat', 'q_desired', 'q_od'):
        assert np.array_equal(getattr(default, name), getattr(given, name)), name


MODULES_AT_EXIT = ('import atexit, sys\n'
                   'atexit.register(lambda: print(sorted({m.split(".")[0] for m in sys.modules'
                   ' if m.split(".")[0] in ("scipy", "matplotlib", "rclpy")}), '
                   'file=sys.stderr))\n')


def loaded_by(code):
    result = subprocess.run([sys.executable, '-c', MODULES_AT_EXIT + code],
                            capture_output=True, text=True, cwd=ROOT, timeout=300)
    return result.stderr.strip().splitlines()[-1]


def test_importing_formation_sim_or_asking_for_help_loads_no_scipy_or_matplotlib():
    assert loaded_by('import formation_ros.tools.sim') == '[]'
    assert loaded_by('from formation_ros.tools.sim import main\nmain(["--help"])') == '[]'


def test_a_fixed_step_run_without_figures_loads_no_scipy_or_matplotlib(tmp_path):
    """The grid of core.maths.pairs searches every pair a --dt run needs: scipy stays unloaded."""
    out = str(tmp_path / 'run')
    code = ('from formation_ros.tools.sim import main\n'
            f"assert main([{SECTION5!r}, '--out', {out!r}, '--duration', '1', '--dt', '0.01', "
            "'--no-plots', '--quiet']) == 0")
    assert loaded_by(code) == '[]'
    assert Trajectory.load(os.path.join(out, TRAJECTORY_FILE)).q.shape == (101, 10, 2)


def test_the_command_gives_the_numbers_of_the_library_call(tmp_path):
    """The lazily importing command and an in-process run (scipy loaded first) agree exactly."""
    out = tmp_path / 'cli'
    result = subprocess.run([sys.executable, '-m', 'formation_ros.tools.sim', SECTION5, '--out',
                             str(out), '--duration', '2', '--dt', '0.01', '--no-plots',
                             '--quiet'], capture_output=True, text=True, cwd=ROOT, timeout=300)
    assert result.returncode == 0, result.stderr
    config = load_config(SECTION5)
    run = simulate.run_fixed_step(config, 2.0, 0.01, 0.01, simulate.Progress(2.0, quiet=True))
    written = Trajectory.load(str(out / TRAJECTORY_FILE))
    for name in ('t', 'q', 'u', 'u_hat', 'q_desired', 'q_od'):
        assert np.array_equal(getattr(written, name), getattr(run.trajectory, name)), name


def general_team_command(q, vertices, radii, law, pairs):
    """team_command of a fixed reference with every mask and overflow rule applied."""
    i, j = pairs[:, 0], pairs[:, 1]
    q_ij = q[i] - q[j]
    d2 = np.einsum('kd,kd->k', q_ij, q_ij)
    b = law.repulsion_radius
    with np.errstate(invalid='ignore', over='ignore', divide='ignore'):
        t = 0.5 * d2 / (0.5 * b * b)
        inside = (t > 0.0) & (t < 1.0)
        tc = np.where(inside, t, 0.5)
        ratio = ((1.0 - tc) ** law.jump.order * law.jump._inv_beta
                 / ((0.5 * b * b) * tc * law.jump._sum_s(tc)))
        weight = np.where(inside, ratio, np.where(t <= 0.0, np.inf, 0.0))
        terms = weight[:, None] * q_ij
    apart = np.any(q_ij != 0.0, axis=1)
    huge = apart & ((d2 == 0.0) | ~np.all(np.isfinite(terms), axis=1))
    if np.any(huge):
        rows = q_ij[huge] / np.max(np.abs(q_ij[huge]), axis=1, keepdims=True)
        terms[huge] = 1e200 * rows / np.linalg.norm(rows, axis=1, keepdims=True)
    terms[~apart] = 0.0
    by_i = terms * (d2 < radii[i] ** 2)[:, None]
    by_j = terms * (d2 < radii[j] ** 2)[:, None]
    n, dim = q.shape
    rep = np.stack([np.bincount(i, by_i[:, k], n) - np.bincount(j, by_j[:, k], n)
                    for k in range(dim)], axis=1)
    return -law.gain * np.arctan(q - vertices - law.kappa * rep)


@pytest.mark.parametrize('case', ['apart', 'short-sighted', 'coincident', 'at b'])
def test_team_command_fast_paths_give_the_general_numbers(case):
    rng = np.random.default_rng(7)
    law = make_law(2.0, 1.0, 'arctan', 'poly', 2, 1.0)
    q = rng.uniform(-3.0, 3.0, size=(200, 2))
    radii = np.full(200, 2.0)
    if case == 'short-sighted':
        radii[::3] = 0.3
    if case == 'coincident':
        q[5] = q[6]
    if case == 'at b':
        q[8] = q[9] + np.array([1.0, 0.0])
    tree = cKDTree(q)
    pairs = tree.query_pairs(1.0, output_type='ndarray').reshape(-1, 2)
    vertices = rng.uniform(-3.0, 3.0, size=(200, 2))
    wanted = general_team_command(q, vertices, radii, law, pairs)
    got = team_command(q, vertices, radii, law, None, tree, pairs).u_hat
    assert np.array_equal(got, wanted)


def test_poly_ratio_inside_and_outside_is_the_general_formula():
    law = make_law(2.0, 1.0, 'arctan', 'poly', 3, 1.0)
    jump = law.jump
    for x in (np.linspace(0.01, 0.49, 50), np.array([-1.0, 0.0, 0.2, 0.5, 0.7])):
        t = x / 0.5
        inside = (t > 0.0) & (t < 1.0)
        tc = np.where(inside, t, 0.5)
        with np.errstate(divide='ignore'):
            value = (1.0 - tc) ** 3 * jump._inv_beta / (0.5 * tc * jump._sum_s(tc))
        wanted = np.where(inside, value, np.where(t <= 0.0, np.inf, 0.0))
        assert np.array_equal(jump.ratio(x, 0.0, 0.5), wanted)
    assert isinstance(jump.ratio(0.2, 0.0, 0.5), np.ndarray)


def test_admission_of_fresh_commands_is_the_general_admission():
    law = make_law(2.0, 1.0, 'arctan', 'poly', 2, 1.0)
    rng = np.random.default_rng(3)
    q = rng.uniform(-5.0, 5.0, size=(50, 3))
    model = PlantModel(q, np.full(50, 2.0), 10_000_000, law, Reference('fixed', 3), 10_000_000,
                       1e-3)
    u = rng.uniform(-3.0, 3.0, size=(50, 3))
    commands = Commands.empty(50, 3)
    commands.store_all(u, 0)
    fresh = model.admit(commands)
    assert np.array_equal(fresh.largest_u_hat, np.max(np.abs(u), axis=1))
    assert np.all(fresh.status == 0) and np.array_equal(fresh.u, u) and fresh.u is not u
    commands.u[4] = math.nan  # one bad command: the general path, the others unchanged
    mixed = model.admit(commands)
    assert mixed.status[4] != 0 and np.all(mixed.u[4] == 0.0)
    others = np.arange(50) != 4
    assert np.array_equal(mixed.u[others], fresh.u[others])
    assert np.array_equal(mixed.largest_u_hat[others], fresh.largest_u_hat[others])
