# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""The offline simulator (sim.py): Section 5 reproduced, tracking, the CLI."""

import json
import os
import subprocess
import sys

from formation_ros.core.maths.law import log_potential
from formation_ros.core.runs.metrics import formation_errors
from formation_ros.core.runs.trajectory import Trajectory
from formation_ros.core.settings.params import load_config, validate
from formation_ros.core.settings.params_file import load_params_file
from formation_ros.figures.plots import FIGURES
from formation_ros.simulation.simulate import run_metrics, simulate
import numpy as np
import pytest

ROOT = os.path.join(os.path.dirname(__file__), '..')
CONFIG = os.path.join(ROOT, 'config')
SECTION5 = os.path.join(CONFIG, 'paper_section5.yaml')


def section5(seed):
    raw = load_params_file(SECTION5)
    raw['start.seed'] = seed
    return validate(raw)


@pytest.mark.parametrize('seed', [1, 2, 3, 4, 5])
def test_section5_reproduced(seed):
    config = section5(seed)
    trajectory = simulate(config)
    metrics = run_metrics(trajectory, config, 'RK45')
    assert metrics['settle_time'] is not None and metrics['settle_time'] < 6.0
    assert metrics['min_pair_distance'] > 0.1
    assert metrics['max_abs_u_component'] < np.pi
    assert metrics['bound_violations'] == 0
    assert metrics['final_max_error'] < 1e-6


def test_lyapunov_function_non_increasing():
    config = section5(2)
    trajectory = simulate(config, duration=8.0, sample_dt=0.005)
    law = config.law()
    values = np.array([log_potential(q, config.vertices, law) for q in trajectory.q])
    assert np.all(np.isfinite(values))
    assert np.all(np.diff(values) <= 1e-9 * np.maximum(1.0, np.abs(values[1:])))
    assert values[-1] < 1e-3 * values[0]


@pytest.mark.parametrize('name', ['circle_2d.yaml', 'helix_3d.yaml', 'figure_eight_2d.yaml'])
def test_tracking_converges(name):
    config = load_config(os.path.join(CONFIG, name))
    trajectory = simulate(config)
    errors = formation_errors(trajectory.q, trajectory.q_desired)
    assert np.max(errors[-1]) < 1e-4
    assert np.max(np.abs(trajectory.u_hat)) <= config.law().u_bound
    assert np.ptp(trajectory.q_od, axis=0).max() > 5.0


def test_lyapunov_non_increasing_in_moving_frame():
    config = load_config(os.path.join(CONFIG, 'helix_3d.yaml'))
    trajectory = simulate(config, duration=6.0)
    reference, law = config.reference(), config.law()
    values = np.array([log_potential(q, config.vertices, law, reference.sample(t))
                       for t, q in zip(trajectory.t, trajectory.q)])
    assert np.all(np.diff(values) <= 1e-9 * np.maximum(1.0, np.abs(values[1:])))


def test_fixed_step_is_zero_order_hold():
    config = section5(3)
    dt = 0.01
    trajectory = simulate(config, duration=1.0, dt=dt, sample_dt=dt)
    assert len(trajectory.t) == 101
    step = trajectory.q[:-1] + dt * trajectory.u[:-1]
    assert np.max(np.abs(step - trajectory.q[1:])) < 1e-14


def test_fixed_step_approaches_continuous_time():
    config = section5(3)
    exact = simulate(config, duration=3.0, sample_dt=0.5)
    coarse = simulate(config, duration=3.0, dt=0.002, sample_dt=0.5)
    fine = simulate(config, duration=3.0, dt=0.0005, sample_dt=0.5)
    err_coarse = np.max(np.abs(coarse.q[-1] - exact.q[-1]))
    err_fine = np.max(np.abs(fine.q[-1] - exact.q[-1]))
    assert err_fine < err_coarse / 2.5


def run_cli(*args):
    return subprocess.run([sys.executable, '-m', 'formation_ros.tools.sim', *args],
                          capture_output=True, text=True, cwd=ROOT, timeout=300)


def test_cli_writes_trajectory_metrics_and_figures(tmp_path):
    out = tmp_path / 'run'
    result = run_cli(SECTION5, '--out', str(out), '--duration', '8')
    assert result.returncode == 0, result.stderr
    assert 'settle time' in result.stdout and 'reference fixed' in result.stdout
    trajectory = Trajectory.load(str(out / 'trajectory.npz'))
    assert trajectory.q.shape == (801, 10, 2) and trajectory.t[-1] == pytest.approx(8.0)
    metrics = json.loads((out / 'metrics.json').read_text())
    for key in ('min_pair_distance', 'dis_all_final', 'final_max_error', 'settle_time',
                'max_abs_u_component', 'u_bound', 'num_robots', 'dim'):
        assert key in metrics
    assert metrics['u_bound'] == pytest.approx(np.pi)
    assert 4.0 < metrics['settle_time'] < 6.0
    for name in FIGURES:
        assert (out / name).read_bytes()[:8] == b'\x89PNG\r\n\x1a\n'
    assert (out / 'params.yaml').read_text() == open(SECTION5).read()


def test_cli_bad_parameters_exit_non_zero_and_write_nothing(tmp_path):
    bad = tmp_path / 'bad.yaml'
    bad.write_text(open(SECTION5).read().replace('gain: 2.0', 'gain: -2.0'))
    out = tmp_path / 'never'
    result = run_cli(str(bad), '--out', str(out))
    assert result.returncode == 2
    assert "parameter 'controller.gain'" in result.stderr
    assert not out.exists()


def test_cli_bad_option_and_help():
    assert run_cli(SECTION5, '--out', '/tmp/x', '--dt', '-1').returncode == 2
    result = run_cli('--help')
    assert result.returncode == 0 and '--dt' in result.stdout and 'RK45' in result.stdout
    assert '--overwrite' in result.stdout and '10,000,000' in result.stdout


def refusal(result):
    """Return the one line of a refused run, after checking how it was refused."""
    assert result.returncode == 2, result.stderr
    assert 'Traceback' not in result.stderr
    assert result.stdout == ''
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1, result.stderr
    assert lines[0].startswith('formation_sim: ')
    return lines[0]


def test_cli_refuses_a_non_empty_out_directory(tmp_path):
    out = tmp_path / 'run'
    out.mkdir()
    (out / 'notes.txt').write_text('mine')
    line = refusal(run_cli(SECTION5, '--out', str(out), '--dt', '0.01', '--duration', '0.5'))
    assert 'not empty' in line and '--overwrite' in line
    assert [p.name for p in out.iterdir()] == ['notes.txt']


def test_cli_overwrite_writes_into_a_non_empty_directory(tmp_path):
    out = tmp_path / 'run'
    out.mkdir()
    (out / 'notes.txt').write_text('mine')
    options = ('--out', str(out), '--dt', '0.01', '--duration', '0.5', '--no-plots',
               '--overwrite')
    first = run_cli(SECTION5, *options)
    assert first.returncode == 0, first.stderr
    assert Trajectory.load(str(out / 'trajectory.npz')).t[-1] == pytest.approx(0.5)
    assert (out / 'notes.txt').read_text() == 'mine'
    again = run_cli(str(out / 'params.yaml'), *options[:-2], '--duration', '0.25',
                    '--overwrite')
    assert again.returncode == 0, again.stderr
    assert Trajectory.load(str(out / 'trajectory.npz')).t[-1] == pytest.approx(0.25)
    assert (out / 'params.yaml').read_text() == open(SECTION5).read()


def test_cli_refuses_an_out_path_with_a_file_in_the_way(tmp_path):
    blocker = tmp_path / 'file'
    blocker.write_text('in the way')
    line = refusal(run_cli(SECTION5, '--out', str(blocker), '--duration', '0.5'))
    assert 'not a directory' in line and str(blocker) in line
    line = refusal(run_cli(SECTION5, '--out', str(blocker / 'run'), '--duration', '0.5'))
    assert 'cannot write' in line
    assert blocker.read_text() == 'in the way'
    assert [p.name for p in tmp_path.iterdir()] == ['file']


def test_cli_refuses_an_output_name_that_is_a_directory(tmp_path):
    out = tmp_path / 'run'
    (out / 'metrics.json').mkdir(parents=True)
    line = refusal(run_cli(SECTION5, '--out', str(out), '--duration', '0.5', '--overwrite'))
    assert 'metrics.json' in line
    assert [p.name for p in out.iterdir()] == ['metrics.json']


@pytest.mark.skipif(not os.path.isdir('/sys'), reason='needs /sys (Linux)')
def test_cli_finds_an_unwritable_out_before_simulating():
    out = '/sys/formation_sim_test_out'
    line = refusal(run_cli(SECTION5, '--out', out, '--duration', '100'))
    assert 'cannot write' in line and out in line
    assert not os.path.exists(out)


@pytest.mark.skipif(os.geteuid() == 0, reason='root writes into read-only directories')
def test_cli_refuses_a_read_only_out_directory(tmp_path):
    out = tmp_path / 'read_only'
    out.mkdir()
    out.chmod(0o500)
    try:
        line = refusal(run_cli(SECTION5, '--out', str(out), '--duration', '100'))
    finally:
        out.chmod(0o700)
    assert 'cannot write' in line
    assert list(out.iterdir()) == []


@pytest.mark.parametrize('options,words', [
    (('--duration', '10', '--dt', '15'), ('--dt 15 s', 'longer than the run (10 s)')),
    (('--duration', '10', '--dt', '1e-9'), ('--dt 1e-09 s', '1e+10 steps', '10,000,000')),
    (('--duration', '10', '--sample-dt', '30'), ('--sample-dt 30 s', 'longer than the run')),
    (('--duration', '10', '--sample-dt', '1e-9'), ('--sample-dt 1e-09 s', '1e+10 samples')),
    (('--duration', '1e6'), ('(the default)', '1e+08 samples')),
    (('--duration', '10', '--dt', '0.01', '--sample-dt', '11'), ('--sample-dt 11 s',)),
])
def test_cli_refuses_impossible_run_lengths(tmp_path, options, words):
    out = tmp_path / 'never'
    line = refusal(run_cli(SECTION5, '--out', str(out), *options))
    for word in words:
        assert word in line
    assert not out.exists()


def test_cli_accepts_a_step_equal_to_the_duration(tmp_path):
    out = tmp_path / 'run'
    result = run_cli(SECTION5, '--out', str(out), '--duration', '0.5', '--dt', '0.5',
                     '--sample-dt', '0.5', '--no-plots')
    assert result.returncode == 0, result.stderr
    assert Trajectory.load(str(out / 'trajectory.npz')).t.tolist() == [0.0, 0.5]


def test_body_frame_commands_move_the_bodies_as_world_ones_do():
    from formation_ros.simulation.simulate import Progress, simulate_fixed_step
    raw = load_params_file(os.path.join(ROOT, 'config', 'square_4.yaml'))
    world = validate(raw)
    body = validate({**raw, 'command.frame': 'body', 'start.headings': [0.5, 2.0, -1.0, 3.0]})
    runs = [simulate_fixed_step(config, 3.0, 0.01, 0.01, Progress(3.0, quiet=True))
            for config in (world, body)]
    assert np.allclose(runs[0].q, runs[1].q, atol=1e-12, rtol=0.0)
    assert np.allclose(runs[0].u, runs[1].u, atol=1e-12, rtol=0.0)
    assert np.ptp(runs[1].q[:, :, 0]) > 0.1
