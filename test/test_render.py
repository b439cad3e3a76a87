# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""formation_render: a run replayed in its MuJoCo world by the offscreen renderer, as a GIF."""

from dataclasses import replace
import math
import os
import sys

import numpy as np
import pytest

mujoco = pytest.importorskip('mujoco')

from formation_ros.core.maths.obstacles import Obstacles  # noqa: E402, I100
from formation_ros.core.runs.trajectory import Trajectory, TRAJECTORY_FILE  # noqa: E402
from formation_ros.core.settings.params import load_config, validate  # noqa: E402
from formation_ros.core.settings.params_file import parse_params_text  # noqa: E402
from formation_ros.physics.scene import build_scene  # noqa: E402
from formation_ros.tools import render, sim  # noqa: E402
from PIL import Image  # noqa: E402

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
HEADER = '/**:\n  ros__parameters:\n'
UNICYCLES = HEADER + """    num_robots: 3
    dim: 2
    sensing_radius: 1.5
    repulsion_radius: 0.8
    controller: {gain: 0.15, kappa: 10.0, psi: tanh}
    body: {kind: unicycle, hand_distance: 0.08, radius: 0.11, max_linear: 0.22,
           max_angular: 2.84}
    formation:
      vertices: [1.0, 0.0, -0.5, 0.866, -0.5, -0.866]
    start:
      positions: [0.0, 0.0, 0.6, 0.0, 0.0, 0.6]
      headings: [0.0, 1.5, -2.0]
    duration: 4.0
"""
POINTS = HEADER + """    num_robots: 3
    dim: {dim}
    sensing_radius: 2.0
    repulsion_radius: 0.8
    controller: {{gain: 0.5, kappa: 1.0, psi: arctan}}
    body: {{radius: 0.15}}
    formation:
      vertices: {vertices}
    start:
      positions: {start}
    duration: 2.0
"""
SMALL = ['--width', '96', '--height', '72', '--quiet']


def write_params(folder, text):
    folder.mkdir(parents=True, exist_ok=True)
    path = folder / 'params.yaml'
    path.write_text(text)
    return str(path)


def simulate(folder, text):
    """Run formation_sim on a parameters file; return the run directory."""
    params = write_params(folder, text)
    out = str(folder / 'run')
    assert sim.main([params, '--out', out, '--no-plots', '--quiet', '--dt', '0.05']) == 0
    return out


@pytest.fixture(scope='module')
def backend():
    """Return the offscreen backend of this machine; skip the rendering tests without one."""
    try:
        chosen = render.choose_backend()
        render.open_context(chosen, 16, 16).free()
    except render.RenderError as exc:
        pytest.skip(f'no offscreen OpenGL backend here: {exc}')
    return chosen


@pytest.fixture(scope='module')
def unicycle_run(tmp_path_factory):
    return simulate(tmp_path_factory.mktemp('unicycles'), UNICYCLES)


def frames_of(path):
    with Image.open(path) as image:
        frames = []
        durations = []
        for index in range(image.n_frames):
            image.seek(index)
            durations.append(image.info.get('duration'))
            frames.append(np.asarray(image.convert('RGB')))
        return frames, durations


def test_a_run_becomes_a_gif_of_the_frames_and_size_asked(backend, unicycle_run, tmp_path,
                                                          capsys):
    out = tmp_path / 'picture.gif'
    code = render.main([unicycle_run, '--out', str(out), '--max-frames', '4', '--fps', '5']
                       + SMALL)
    printed = capsys.readouterr()
    assert code == 0, printed.err
    assert printed.out.startswith(f'formation_render: {out}: 4 frames at 5 fps')
    assert f'rendered with {backend}' in printed.out
    frames, durations = frames_of(out)
    assert len(frames) == 4 and frames[0].shape == (72, 96, 3)
    assert durations == [200] * 4
    for frame in frames:
        assert frame.reshape(-1, 3).std(axis=0).max() > 10.0, 'a uniform frame'
        colourful = frame.max(axis=2).astype(int) - frame.min(axis=2)
        assert colourful.max() > 80, 'no robot or decoration drawn in colour'
    assert np.abs(frames[0].astype(int) - frames[-1]).mean() > 1.0, 'nothing moved'
    assert not os.path.exists(str(out) + '.part')


def test_point_teams_in_2d_and_3d_render_too(backend, tmp_path):
    cases = {2: ('[1.0, 0.0, -0.5, 0.866, -0.5, -0.866]', '[0.0, 0.0, 0.5, 0.0, 0.0, 0.5]'),
             3: ('[1.0, 0.0, 0.0, -0.5, 0.866, 0.5, -0.5, -0.866, -0.5]',
                 '[0.0, 0.0, 0.0, 0.5, 0.0, 0.0, 0.0, 0.5, 0.0]')}
    for dim, (vertices, start) in cases.items():
        run = simulate(tmp_path / f'points{dim}',
                       POINTS.format(dim=dim, vertices=vertices, start=start))
        config = load_config(os.path.join(run, 'params.yaml'))
        trajectory = Trajectory.load(os.path.join(run, TRAJECTORY_FILE))
        out = str(tmp_path / f'points{dim}.gif')
        options = render.RenderOptions(width=64, height=48, max_frames=3, sensing=True,
                                       camera='fixed', shadows=False)
        rendered = render.render_run(trajectory, config, out, options, quiet=True,
                                     backend=backend)
        frames, _ = frames_of(out)
        assert rendered.frames == len(frames) == 3 and frames[0].shape == (48, 64, 3)
        assert frames[-1].reshape(-1, 3).std(axis=0).max() > 10.0


@pytest.mark.parametrize('kind', ['unicycle', 'holonomic', 'flyer'])
def test_the_bodies_are_put_where_the_run_had_them(kind):
    """The poser needs no OpenGL: bodies at the recorded positions and headings."""
    if kind == 'unicycle':
        text = UNICYCLES
    else:
        dim = 2 if kind == 'holonomic' else 3
        text = POINTS.format(dim=dim, vertices=[1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0,
                                                9.0][:3 * dim],
                             start=[0.0, 0.5, 1.0, 1.5, 2.0, 2.5, 3.0, 3.5, 4.0][:3 * dim])
    config = validate(parse_params_text(text, 'test'))
    scene = build_scene(config)
    model = mujoco.MjModel.from_xml_string(scene.xml)
    data = mujoco.MjData(model)
    poser = render.Poser(model, scene.names)
    rng = np.random.default_rng(1)
    positions = rng.uniform(-3.0, 3.0, (3, config.dim))
    headings = np.array([0.3, -2.0, 3.0])
    poser.put(data.qpos, positions, headings)
    mujoco.mj_forward(model, data)
    bodies = [mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, name) for name in scene.names]
    np.testing.assert_allclose(data.xpos[bodies][:, :config.dim], positions, atol=1e-12)
    yaw = [2.0 * math.atan2(q[3], q[0]) for q in data.xquat[bodies]]
    np.testing.assert_allclose(np.unwrap(yaw), np.unwrap(headings), atol=1e-9)


def one_line_failure(capsys, argv):
    code = render.main(argv)
    err = capsys.readouterr().err
    assert code == 2
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith('formation_render: '), err
    return lines[0]


def test_a_missing_or_corrupt_trajectory_is_one_line_and_exit_2(tmp_path, capsys):
    folder = tmp_path / 'run'
    write_params(folder, UNICYCLES)
    out = str(tmp_path / 'x.gif')
    assert 'no such file' in one_line_failure(capsys, [str(tmp_path / 'none'), '--out', out])
    line = one_line_failure(capsys, [str(folder), '--out', out])
    assert 'trajectory' in line or 'bag' in line
    (folder / 'trajectory.npz').write_bytes(b'not a numpy file')
    line = one_line_failure(capsys, [str(folder), '--out', out])
    assert 'not a readable trajectory' in line
    assert not os.path.exists(out)


def test_an_out_that_is_not_a_gif_is_refused(unicycle_run, tmp_path, capsys):
    line = one_line_failure(capsys, [unicycle_run, '--out', str(tmp_path / 'x.mp4')])
    assert 'give a .gif file' in line


def test_no_backend_is_one_line_naming_the_package_to_install(unicycle_run, tmp_path, capsys,
                                                              monkeypatch):
    import ctypes.util
    monkeypatch.delenv('MUJOCO_GL', raising=False)
    monkeypatch.delenv('PYOPENGL_PLATFORM', raising=False)
    monkeypatch.setattr(ctypes.util, 'find_library', lambda name: None)
    out = tmp_path / 'x.gif'
    line = one_line_failure(capsys, [unicycle_run, '--out', str(out)] + SMALL)
    assert line.startswith('formation_render: cannot render: no OpenGL backend')
    assert 'libosmesa6' in line
    assert not out.exists()


def test_a_backend_that_cannot_load_is_one_line(unicycle_run, tmp_path, capsys, monkeypatch):
    monkeypatch.setenv('MUJOCO_GL', 'osmesa')
    monkeypatch.setitem(sys.modules, 'mujoco.osmesa', None)
    out = tmp_path / 'x.gif'
    line = one_line_failure(capsys, [unicycle_run, '--out', str(out)] + SMALL)
    assert 'no OpenGL backend' in line and 'osmesa failed' in line
    assert not out.exists() and not os.path.exists(str(out) + '.part')
    monkeypatch.setenv('MUJOCO_GL', 'glfw')
    line = one_line_failure(capsys, [unicycle_run, '--out', str(out)] + SMALL)
    assert 'MUJOCO_GL=osmesa or MUJOCO_GL=egl' in line


def test_help_names_the_options(capsys):
    with pytest.raises(SystemExit) as exited:
        render.main(['--help'])
    assert exited.value.code == 0
    text = capsys.readouterr().out
    for option in ('--out', '--fps', '--width', '--height', '--max-frames', '--camera',
                   '--sensing'):
        assert option in text


@pytest.mark.parametrize('mode', render.CAMERAS)
def test_the_camera_keeps_every_point_it_frames_in_the_picture(mode):
    rng = np.random.default_rng(4)
    frames = 30
    spread = np.linspace(0.5, 8.0, frames)[:, None, None]
    points = rng.uniform(-1.0, 1.0, (frames, 10, 3)) * spread + (3.0, -2.0, 0.0)
    points[..., 2] = 0.05
    fovy, aspect = 45.0, 4.0 / 3.0
    lookat, distance = render.plan_camera(points, mode, 3, fovy, aspect, 1.0)
    right, up, forward = render.camera_axes()
    tan_y = math.tan(math.radians(0.5 * fovy))
    for k in range(frames):
        shown = points.reshape(-1, 3) if mode == 'fixed' else points[k]
        eye = lookat[k] - distance[k] * forward
        relative = shown - eye
        depth = relative @ forward
        assert np.all(depth > 0.0)
        assert np.all(np.abs(relative @ up) / depth <= tan_y)
        assert np.all(np.abs(relative @ right) / depth <= tan_y * aspect)
    if mode == 'follow':
        assert distance[0] < 0.5 * distance[-1], 'the camera does not follow the team'


def test_the_obstacles_of_the_parameters_are_drawn(backend, unicycle_run, tmp_path):
    config = load_config(os.path.join(unicycle_run, 'params.yaml'))
    trajectory = Trajectory.load(os.path.join(unicycle_run, TRAJECTORY_FILE))
    among = replace(config, obstacles=Obstacles([0.3, -0.5, 0.15],
                                                [-0.6, -0.3, -0.6, 0.4, 0.05], [], 0.2, 2))
    options = render.RenderOptions(width=96, height=72, max_frames=2, camera='fixed',
                                   shadows=False)
    pictures = {}
    for name, each in (('bare', config), ('among', among)):
        out = str(tmp_path / f'{name}.gif')
        render.render_run(trajectory, each, out, options, quiet=True, backend=backend)
        pictures[name] = frames_of(out)[0][0].astype(int)
    changed = np.abs(pictures['among'] - pictures['bare']).max(axis=2) > 30
    assert changed.sum() > 40, 'no obstacle drawn'
    with render.Frames(trajectory, among, options, backend, trajectory.t[:1]) as drawer:
        names = [mujoco.mj_id2name(drawer.model, mujoco.mjtObj.mjOBJ_GEOM, k)
                 for k in range(drawer.model.ngeom)]
        assert {'obstacle_circle_1', 'obstacle_wall_1'} <= set(names)
        pillar = drawer.model.geom('obstacle_circle_1')
        assert np.allclose(pillar.pos[:2], [0.3, -0.5]) and pillar.rgba[3] == 1.0


def test_a_flying_team_s_obstacles_are_see_through(backend, tmp_path):
    run = simulate(tmp_path / 'flyers', POINTS.format(
        dim=3, vertices='[1.0, 0.0, 0.0, -0.5, 0.866, 0.5, -0.5, -0.866, -0.5]',
        start='[0.0, 0.0, 0.0, 0.5, 0.0, 0.0, 0.0, 0.5, 0.0]'))
    config = replace(load_config(os.path.join(run, 'params.yaml')),
                     obstacles=Obstacles([2.0, 2.0, 0.2], [], [-2.0, -2.0, 0.0, 0.3], 0.2, 3))
    trajectory = Trajectory.load(os.path.join(run, TRAJECTORY_FILE))
    options = render.RenderOptions(width=32, height=24, max_frames=1, shadows=False)
    with render.Frames(trajectory, config, options, backend, trajectory.t[:1]) as drawer:
        for name in ('obstacle_circle_1', 'obstacle_sphere_1'):
            assert drawer.model.geom(name).rgba[3] == render.OBSTACLE_ALPHA_3D
