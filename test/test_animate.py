# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""formation_report --animate (figures/animate.py, figures/scene.py) and segments in the report."""

import json
import math
import os
import shutil

from formation_ros.core.maths.frames import stationary_frame
from formation_ros.core.runs.events import Event, EventKind
from formation_ros.core.settings.params import load_config
from formation_ros.figures.animate import (AnimationError, GIF, MAX_FRAMES, MP4, plan_frames,
                                           write_animation)
from formation_ros.figures.scene import Scene
from formation_ros.simulation.simulate import format_summary, run_metrics, shaped, simulate
from formation_ros.tools.report import main as report_main, write_report
from formation_ros.tools.sim import main as sim_main
import numpy as np
from PIL import Image
import pytest
from test_bag import write_run_as_bag

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SQUARE = os.path.join(ROOT, 'config', 'square_4.yaml')
UNICYCLES = os.path.join(ROOT, 'config', 'unicycle_2d.yaml')
TINY = ('--dpi', '30')


@pytest.fixture
def no_ffmpeg(monkeypatch, tmp_path):
    """Leave no ffmpeg on PATH: the animation is a GIF."""
    empty = tmp_path / 'no_ffmpeg'
    empty.mkdir()
    monkeypatch.setenv('PATH', str(empty))


@pytest.fixture(scope='module')
def square_run(tmp_path_factory):
    """Make a 3 s formation_sim run directory of config/square_4.yaml."""
    out = tmp_path_factory.mktemp('square') / 'run'
    assert sim_main([SQUARE, '--out', str(out), '--duration', '3', '--no-plots',
                     '--quiet']) == 0
    return out


def gif_frames(path):
    with open(path, 'rb') as stream:
        assert stream.read(6) in (b'GIF89a', b'GIF87a')
    with Image.open(path) as image:
        return image.n_frames


def test_frames_are_even_in_time_and_within_the_budget():
    t = np.linspace(0.0, 3600.0, 360_001)
    plan = plan_frames(t)
    assert len(plan.indices) == MAX_FRAMES
    assert plan.indices[0] == 0 and plan.indices[-1] == len(t) - 1
    assert np.ptp(np.diff(t[plan.indices])) <= 0.01 + 1e-9
    assert plan.speed == pytest.approx(3600.0 * 20.0 / (MAX_FRAMES - 1))
    short = plan_frames(np.arange(301) / 100.0, fps=10.0)
    assert short.speed == 1.0 and len(short.indices) == 31
    assert np.allclose(np.arange(301)[short.indices] / 100.0, np.arange(31) / 10.0)
    sparse = plan_frames(np.linspace(0.0, 100.0, 50))
    assert len(sparse.indices) == 50 and sparse.speed == pytest.approx(100.0 * 20.0 / 49)
    assert len(plan_frames(t, max_frames=7).indices) == 7
    with pytest.raises(AnimationError, match=f'give --speed {3600.0 * 20.0 / 599:.4g} or more'):
        plan_frames(t, speed=1.0)


def test_animation_of_a_run_directory(square_run, tmp_path, no_ffmpeg, capsys):
    out = tmp_path / 'report'
    assert report_main([str(square_run), '--out', str(out), '--animate', '--no-plots',
                        '--fps', '10', *TINY]) == 0
    assert sorted(os.listdir(out)) == [GIF, 'metrics.json']
    assert gif_frames(out / GIF) == 31
    assert '31 frames at 10 fps' in capsys.readouterr().out
    assert 'segments' not in json.loads((out / 'metrics.json').read_text())


def test_animation_of_a_bag(tmp_path, no_ffmpeg):
    config = load_config(SQUARE)
    trajectory = simulate(config, duration=2.0, dt=0.01, sample_dt=0.05)
    write_run_as_bag(str(tmp_path / 'bag'), config, trajectory)
    out = tmp_path / 'report'
    assert report_main([str(tmp_path / 'bag'), '--out', str(out), '--animate', '--no-plots',
                        '--fps', '5', *TINY]) == 0
    assert gif_frames(out / GIF) == 11


def ffmpeg_binary():
    found = shutil.which('ffmpeg')
    if found:
        return found
    try:
        import imageio_ffmpeg
    except ImportError:
        return None
    return imageio_ffmpeg.get_ffmpeg_exe()


@pytest.mark.skipif(ffmpeg_binary() is None, reason='no ffmpeg executable here')
def test_an_mp4_where_ffmpeg_is_on_path(square_run, tmp_path, monkeypatch):
    folder = tmp_path / 'bin'
    folder.mkdir()
    os.symlink(ffmpeg_binary(), folder / 'ffmpeg')
    monkeypatch.setenv('PATH', str(folder))
    out = tmp_path / 'report'
    assert report_main([str(square_run), '--out', str(out), '--animate', '--no-plots',
                        '--fps', '10', *TINY]) == 0
    assert os.listdir(out) == [MP4] or sorted(os.listdir(out)) == [MP4, 'metrics.json']
    assert (out / MP4).read_bytes()[4:8] == b'ftyp'


def exit_code(argv):
    """Return what formation_report returns or exits with (argparse errors exit)."""
    try:
        return report_main(argv)
    except SystemExit as exc:
        return exc.code


@pytest.mark.parametrize('options, words', [
    (('--speed', '0.01'), 'give --speed'),
    (('--fps', '0'), '--fps must be'),
    (('--max-frames', str(MAX_FRAMES + 1)), '--max-frames must be'),
    (('--dpi', 'nan'), '--dpi must be'),
])
def test_impossible_animations_are_refused_in_one_line(square_run, tmp_path, capsys,
                                                       options, words):
    out = tmp_path / 'report'
    assert exit_code([str(square_run), '--out', str(out), '--animate', *options]) == 2
    error = capsys.readouterr().err.strip().splitlines()
    assert words in error[-1] and error[-1].startswith('formation_report: ')
    assert not out.exists() or not os.listdir(out)


def test_an_animation_that_cannot_be_written_is_one_line_and_exit_2(square_run, tmp_path,
                                                                    capsys, no_ffmpeg):
    out = tmp_path / 'report'
    (out / GIF).mkdir(parents=True)
    assert report_main([str(square_run), '--out', str(out), '--animate', '--no-plots',
                        *TINY]) == 2
    error = capsys.readouterr().err.strip().splitlines()
    assert len(error) == 1 and 'cannot write' in error[0] and GIF in error[0]


def unicycle_trajectory():
    config = load_config(UNICYCLES)
    return config, simulate(config, duration=1.0, dt=0.01, sample_dt=0.1)


def artist(scene, gid):
    found = [a for a in scene.ax.get_children() if a.get_gid() == gid]
    return found[0] if found else None


def test_unicycles_draw_their_headings_from_the_axles():
    config, trajectory = unicycle_trajectory()
    scene = Scene(trajectory, config.sensing_radii, config.repulsion_radius, config.body.radius,
                  (), 'unicycles', 3.0)
    try:
        pixels = scene.render(5, 0, 20)
        assert pixels.ndim == 3 and pixels.shape[2] == 4
        segments = artist(scene, 'headings').get_segments()
        assert len(segments) == config.num_robots
        for i, segment in enumerate(segments):
            assert segment[0] == pytest.approx(trajectory.q_body[5, i])
            direction = segment[1] - segment[0]
            heading = trajectory.heading[5, i]
            assert direction / np.linalg.norm(direction) == pytest.approx(
                [math.cos(heading), math.sin(heading)], abs=1e-9)
        assert artist(scene, 'bodies') is not None
    finally:
        scene.close()
    points = load_config(SQUARE)
    square = simulate(points, duration=1.0, dt=0.01, sample_dt=0.1)
    scene = Scene(square, points.sensing_radii, points.repulsion_radius, 0.0, (), 'points', 3.0)
    try:
        assert artist(scene, 'headings') is None and artist(scene, 'robots') is not None
    finally:
        scene.close()


def test_frames_show_the_shape_in_force_and_stop_go():
    config = load_config(SQUARE)
    trajectory = simulate(config, duration=2.0, dt=0.01, sample_dt=0.1)
    wedge = np.array([[0.0, 2.0], [-1.5, 0.0], [0.0, 0.0], [1.5, 0.0]])
    events = [Event(0.5, EventKind.SHAPE, 'wedge', wedge), Event(1.0, EventKind.STOP, 'stop'),
              Event(1.5, EventKind.START, 'start')]
    scene = Scene(shaped(trajectory, config, events), config.sensing_radii,
                  config.repulsion_radius, 0.0, events, 'switch', 3.0)
    try:
        texts = []
        for k in (0, 6, 12, 18):
            scene.render(k, 0, 20)
            texts.append(artist(scene, 'clock').get_text())
            x, y = artist(scene, 'desired').get_data()
            expected = config.vertices if k == 0 else wedge
            assert np.column_stack([x, y]) == pytest.approx(np.vstack([expected,
                                                                       expected[:1]]))
        assert 'running' in texts[0] and 'as started' in texts[0]
        assert 'running' in texts[1] and 'wedge since 0.50 s' in texts[1]
        assert 'STOPPED' in texts[2] and 'running' in texts[3]
    finally:
        scene.close()


def test_metrics_of_segments_only_with_events():
    config = load_config(SQUARE)
    trajectory = simulate(config, duration=3.0, dt=0.01, sample_dt=0.05)
    plain = run_metrics(trajectory, config, 'x')
    assert 'segments' not in plain and run_metrics(trajectory, config, 'x', ()) == plain
    stop_go = [Event(1.0, EventKind.STOP, 'stop'), Event(2.0, EventKind.START, 'start')]
    metrics = run_metrics(trajectory, config, 'x', stop_go)
    assert {key: value for key, value in metrics.items() if key != 'segments'} == plain
    assert [s['label'] for s in metrics['segments']] == ['start of the run', 'stop', 'start']
    assert metrics['segments'][0]['min_pair_distance'] >= plain['min_pair_distance']
    assert min(s['min_pair_distance'] for s in metrics['segments']) == \
        plain['min_pair_distance']
    moved = config.vertices + np.array([3.0, 0.0])
    switch = [Event(2.5, EventKind.SHAPE, 'moved', moved)]
    switched = run_metrics(shaped(trajectory, config, switch), config, 'x', switch)
    assert switched['final_max_error'] == pytest.approx(3.0, abs=0.05)
    assert switched['segments'][1]['settle_time'] is None
    lines = format_summary(switched).splitlines()
    assert any(line.startswith("  segment 2.50-3.00 s after shape 'moved': not settled")
               for line in lines)
    before = trajectory.t < 2.5
    errors = np.linalg.norm(trajectory.q - trajectory.q_desired, axis=2)[before]
    brute = next(t for k, t in enumerate(trajectory.t[before]) if np.all(errors[k:] <= 0.05))
    assert any(line.startswith(f'  segment 0.00-2.50 s from the start: settled in {brute:.2f} s')
               for line in lines)


def test_a_shape_of_another_team_is_refused_before_anything_is_written(tmp_path):
    config = load_config(SQUARE)
    trajectory = simulate(config, duration=1.0, dt=0.01, sample_dt=0.1)
    three = [Event(0.5, EventKind.SHAPE, 'three', np.zeros((3, 2)))]
    with pytest.raises(AnimationError, match="shape event 'three' at t = 0.5 s"):
        write_animation(trajectory, config, str(tmp_path), three)
    assert os.listdir(tmp_path) == []


def test_the_report_writes_segments_and_places_shapes_by_the_frames_given(tmp_path):
    config = load_config(SQUARE)
    trajectory = simulate(config, duration=2.0, dt=0.01, sample_dt=0.1)
    switch = [Event(1.0, EventKind.SHAPE, 'same', config.vertices)]
    metrics = write_report(trajectory, config, str(tmp_path / 'a'), plots=False, events=switch)
    written = json.loads((tmp_path / 'a' / 'metrics.json').read_text())
    assert [s['label'] for s in written['segments']] == ['start of the run', 'same']
    assert written['final_max_error'] == metrics['final_max_error'] == \
        run_metrics(trajectory, config, 'x')['final_max_error']
    away = [stationary_frame(2, origin=[10.0, 0.0], t=float(t)) for t in trajectory.t]
    moved = write_report(trajectory, config, str(tmp_path / 'b'), plots=False, events=switch,
                         frames=away)
    final = np.linalg.norm(trajectory.q[-1] - (config.vertices + [10.0, 0.0]), axis=1)
    assert moved['final_max_error'] == pytest.approx(np.max(final))
