# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""formation_sim --engine mujoco: the law on the physics engine, the outputs of every run."""

import json
import os

import numpy as np
import pytest

mujoco = pytest.importorskip('mujoco')

from formation_ros.core.runs.metrics import formation_errors  # noqa: E402, I100
from formation_ros.core.runs.trajectory import Trajectory  # noqa: E402
from formation_ros.core.settings.exits import ENGINE_FAILED  # noqa: E402
from formation_ros.core.settings.params_file import (load_params_file,  # noqa: E402
                                                     write_params_file)
from formation_ros.tools.report import main as report_main  # noqa: E402
from formation_ros.tools.sim import main as sim_main  # noqa: E402

UNICYCLES = 'config/unicycle_2d.yaml'


def test_unicycles_on_the_engine_write_what_every_run_writes_and_close_in(tmp_path, capsys):
    out = tmp_path / 'run'
    assert sim_main([UNICYCLES, '--engine', 'mujoco', '--out', str(out), '--duration', '8',
                     '--no-plots', '--quiet']) == 0
    assert sorted(os.listdir(out)) == ['metrics.json', 'params.yaml', 'trajectory.npz',
                                       'world.xml', 'world_stats.json']
    trajectory = Trajectory.load(str(out / 'trajectory.npz'))
    assert trajectory.heading is not None and trajectory.q_body.shape[1:] == (6, 2)
    assert trajectory.t[0] == 0.0 and trajectory.t[-1] == pytest.approx(8.0)
    errors = formation_errors(trajectory.q, trajectory.q_desired)
    assert np.mean(errors[-1]) < 0.8 * np.mean(errors[0])
    metrics = json.loads((out / 'metrics.json').read_text())
    assert metrics['engine'] == 'mujoco' and metrics['mujoco_version'] == mujoco.__version__
    assert metrics['bound_violations'] == 0
    assert metrics['max_abs_v'] <= metrics['v_bound'] + 1e-12
    stats = json.loads((out / 'world_stats.json').read_text())
    assert stats['contacts'] == 0 and stats['contact_events'] == []
    assert stats['steps'] == 4000 and stats['min_body_distance'] > 0.22
    assert stats['achieved_realtime_factor'] > 0.0
    assert metrics['world']['contacts'] == 0
    model = mujoco.MjModel.from_xml_path(str(out / 'world.xml'))
    assert model.nu == 12
    assert 'physics (MuJoCo' in capsys.readouterr().out
    assert report_main([str(out), '--out', str(tmp_path / 'report'), '--no-plots']) == 0
    assert 'closest body approach: 0.6' in capsys.readouterr().out


def test_points_on_the_engine_close_in_without_touching(tmp_path):
    params = load_params_file('config/square_4.yaml')
    params.update({'start.positions': [-0.5, 0.0, 0.5, 0.0, 0.0, 3.0, 0.0, -3.0],
                   'start.random_radius': None, 'start.min_separation': None,
                   'body.radius': 0.2, 'world.force_limit': 2.0})
    params = {name: value for name, value in params.items() if value is not None}
    write_params_file(str(tmp_path / 'p.yaml'), params)
    out = tmp_path / 'run'
    assert sim_main([str(tmp_path / 'p.yaml'), '--engine', 'mujoco', '--dt', '0.01', '--out',
                     str(out), '--duration', '3', '--no-plots', '--quiet']) == 0
    stats = json.loads((out / 'world_stats.json').read_text())
    assert stats['steps'] == 1500
    assert stats['min_body_distance'] >= 0.39
    trajectory = Trajectory.load(str(out / 'trajectory.npz'))
    assert trajectory.heading is None
    errors = formation_errors(trajectory.q, trajectory.q_desired)
    assert np.max(errors[-1]) < 0.5 * np.max(errors[0])


@pytest.mark.parametrize('options, text', [
    (['--dt', '0.003'], 'whole number of world.timestep'),
    (['--dt', '0.6'], 'world.cmd_timeout'),
])
def test_a_control_period_the_engine_cannot_hold_is_refused(tmp_path, capsys, options, text):
    out = tmp_path / 'run'
    assert sim_main([UNICYCLES, '--engine', 'mujoco', '--out', str(out), '--quiet']
                    + options) == 2
    assert text in capsys.readouterr().err
    assert not out.exists()


def test_the_plant_model_s_imperfections_are_refused_on_the_engine(tmp_path, capsys):
    params = {**load_params_file(UNICYCLES), 'plant.actuator_lag': 0.1}
    write_params_file(str(tmp_path / 'p.yaml'), params)
    assert sim_main([str(tmp_path / 'p.yaml'), '--engine', 'mujoco', '--out',
                     str(tmp_path / 'run'), '--quiet']) == 2
    assert 'world.pose_noise' in capsys.readouterr().err


def test_the_ideal_engine_is_the_default_bit_for_bit(tmp_path):
    runs = []
    for extra in ([], ['--engine', 'ideal']):
        out = tmp_path / f'run{len(runs)}'
        assert sim_main(['config/square_4.yaml', '--dt', '0.01', '--duration', '1', '--out',
                         str(out), '--no-plots', '--quiet'] + extra) == 0
        runs.append((out / 'trajectory.npz').read_bytes())
        assert sorted(os.listdir(out)) == ['metrics.json', 'params.yaml', 'trajectory.npz']
    assert runs[0] == runs[1]


def test_an_engine_that_blows_up_stops_the_run_in_one_line_and_keeps_it(tmp_path, capsys):
    # the world's unstable case (test_world_faults): a long step, a light body, strong motors
    values = load_params_file('config/world_turtlebot3.yaml')
    values.update({'world.timestep': 0.05, 'world.mass': 1.0, 'world.wheel_torque': 1e4,
                   'world.wheel_radius': 1.0, 'world.floor_friction': 0.1,
                   'world.pose_rate': 10.0})
    write_params_file(str(tmp_path / 'p.yaml'), values)
    out = tmp_path / 'run'
    assert sim_main([str(tmp_path / 'p.yaml'), '--engine', 'mujoco', '--dt', '0.05', '--out',
                     str(out), '--no-plots', '--quiet']) == ENGINE_FAILED
    err = capsys.readouterr().err
    lines = [line for line in err.splitlines() if 'blew up' in line]
    assert len(lines) == 1 and 'Traceback' not in err, err
    assert 'robot ' in lines[0] and 'at t = ' in lines[0] and 'world.timestep 0.05' in lines[0]
    run = Trajectory.load(str(out / 'trajectory.npz'))
    assert 0.0 < run.t[-1] < 30.0 and np.all(np.isfinite(run.q))
