# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""formation_sim and the parameters with non-ideal bodies (plant.actuator_lag ...)."""

import json
import os
import subprocess
import sys

from formation_ros.core.settings.declarations import Exe, ParamError
from formation_ros.core.settings.params import load_config, validate
from formation_ros.core.settings.params_file import dump_params_text, load_params_file
from formation_ros.simulation.simulate import simulate
import pytest

ROOT = os.path.join(os.path.dirname(__file__), '..')
SECTION5 = os.path.join(ROOT, 'config', 'paper_section5.yaml')


def params_with(tmp_path, **values):
    raw = {**load_params_file(SECTION5), **{f'plant.{k}': v for k, v in values.items()}}
    path = tmp_path / 'bodies.yaml'
    path.write_text(dump_params_text(raw))
    return str(path)


def run_cli(*args):
    return subprocess.run([sys.executable, '-m', 'formation_ros.tools.sim', *args],
                          capture_output=True, text=True, cwd=ROOT, timeout=300)


def test_rk45_refuses_non_ideal_bodies_in_one_line_naming_dt(tmp_path):
    path = params_with(tmp_path, actuator_lag=0.2, state_delay=0.05)
    out = tmp_path / 'never'
    result = run_cli(path, '--out', str(out), '--duration', '1')
    assert result.returncode == 2 and not out.exists()
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and '--dt' in lines[0], result.stderr
    assert 'plant.actuator_lag = 0.2' in lines[0] and 'plant.state_delay = 0.05' in lines[0]
    with pytest.raises(ValueError, match='--dt'):
        simulate(load_config(path), duration=1.0)


def test_a_fixed_step_run_records_the_imperfections_it_had(tmp_path):
    path = params_with(tmp_path, actuator_lag=0.1, pose_noise=0.01, state_delay=0.03,
                       max_acceleration=20.0)
    out = tmp_path / 'run'
    result = run_cli(path, '--out', str(out), '--duration', '2', '--dt', '0.01', '--no-plots')
    assert result.returncode == 0, result.stderr
    metrics = json.loads((out / 'metrics.json').read_text())
    assert metrics['imperfections'] == {'plant.actuator_lag': 0.1,
                                        'plant.max_acceleration': 20.0,
                                        'plant.pose_noise': 0.01, 'plant.state_delay': 0.03}
    assert metrics['state_delay_steps'] == 3
    assert metrics['max_abs_u_hat_sent'] <= metrics['u_bound']
    assert all(0.0 < v <= metrics['u_bound'] for v in metrics['max_abs_body_velocity'])
    ideal = run_cli(SECTION5, '--out', str(tmp_path / 'ideal'), '--duration', '1', '--dt',
                    '0.01', '--no-plots')
    assert json.loads((tmp_path / 'ideal' / 'metrics.json').read_text())['imperfections'] == {
        'plant.actuator_lag': 0.0, 'plant.max_acceleration': 0.0, 'plant.pose_noise': 0.0,
        'plant.state_delay': 0.0}, ideal.stderr


def test_a_lockstep_plant_refuses_a_state_delay_and_a_free_one_takes_it():
    raw = {**load_params_file(SECTION5), 'plant.state_delay': 0.1}
    with pytest.raises(ParamError, match='plant.lockstep'):
        validate({**raw, 'plant.lockstep': True}, Exe.PLANT)
    assert validate(raw, Exe.PLANT).imperfections.state_delay == 0.1
    assert validate({**raw, 'plant.state_delay': 0.0, 'plant.lockstep': True, 'plant.pose_noise':
                     0.01}, Exe.PLANT).imperfections.pose_noise == 0.01
    with pytest.raises(ParamError, match='plant.input_timeout'):
        validate({**raw, 'plant.state_delay': 0.5}, Exe.PLANT)
    assert validate({**raw, 'plant.lockstep': True}, Exe.SIM).imperfections.state_delay == 0.1
