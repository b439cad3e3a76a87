# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""The benchmarks' command lines and helpers (soak, orphans, capacity), and a tiny offline run."""

import importlib.util
import json
import os
import subprocess
import sys
import time

from formation_ros.core.settings.params import validate
import numpy as np
import pytest

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SOAK = os.path.join(ROOT, 'bench', 'bench_soak.py')


def load_bench(path):
    """Import a benchmark script (bench/ is not a package) as a module."""
    name = os.path.splitext(os.path.basename(path))[0]
    spec = importlib.util.spec_from_file_location(name, path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@pytest.fixture(scope='module')
def soak():
    return load_bench(SOAK)


@pytest.fixture
def fake_install(tmp_path):
    """Make an install prefix whose node executables are Python scripts that read stdin."""
    prefix = tmp_path / 'install' / 'formation_ros'
    lib = prefix / 'lib' / 'formation_ros'
    lib.mkdir(parents=True)
    for name in ('plant', 'robot', 'formation_report'):
        path = lib / name
        path.write_text('import sys\nsys.stdin.read()\n')
        path.chmod(0o755)
    return prefix


def test_help_runs_without_an_install():
    result = subprocess.run([sys.executable, SOAK, '--help'], capture_output=True, text=True,
                            timeout=120)
    assert result.returncode == 0, result.stderr
    for option in ('--duration', '--interval', '--prefix', '--json', 'VmRSS'):
        assert option in result.stdout


def test_arguments_defaults_and_quick_check(soak, fake_install, tmp_path):
    args = soak.parse_args(['--prefix', str(fake_install), '--out', str(tmp_path / 'soak')])
    assert args.duration == 1800.0 and args.interval == 5.0
    assert args.json == os.path.join(str(tmp_path / 'soak'), 'soak.json')
    quick = soak.parse_args(['--duration', '60', '--prefix', str(fake_install), '--out',
                             str(tmp_path / 'quick'), '--json', str(tmp_path / 'q.json')])
    assert quick.duration == 60.0 and quick.json == str(tmp_path / 'q.json')
    assert not (tmp_path / 'soak').exists()


@pytest.mark.parametrize('options', [
    ['--duration', '0'], ['--interval', '-1'], ['--prefix', '/nonexistent/install'],
])
def test_bad_arguments_exit_2(soak, fake_install, tmp_path, options):
    argv = ['--prefix', str(fake_install), '--out', str(tmp_path / 'soak'), *options]
    with pytest.raises(SystemExit) as info:
        soak.parse_args(argv)
    assert info.value.code == 2


def test_existing_out_directory_is_refused(soak, fake_install, tmp_path):
    with pytest.raises(SystemExit) as info:
        soak.parse_args(['--prefix', str(fake_install), '--out', str(tmp_path)])
    assert info.value.code == 2


def test_node_names_from_command_lines(soak):
    prefix = '/opt/x/formation_ros'
    exe = prefix + '/lib/formation_ros/'
    assert soak.node_name(['python3', exe + 'plant', '--ros-args'], prefix) == 'plant'
    assert soak.node_name(['python3', exe + 'robot', '--ros-args', '-r', '__ns:=/robot_7',
                           '-p', 'robot_id:=7'], prefix) == 'robot_7'
    assert soak.node_name(['python3', exe + 'record'], prefix) == 'record'
    assert soak.node_name(['python3', exe + 'fleet', '--robots', '1-5', '--ros-args'],
                          prefix) == 'fleet_1-5'
    assert soak.node_name(['python3', exe + 'formation_report', 'bag'], prefix) is None
    assert soak.node_name(['python3', '/other/lib/formation_ros/plant'], prefix) is None


def test_finds_the_nodes_a_process_started_and_reads_their_memory(soak, fake_install):
    exe = fake_install / 'lib' / 'formation_ros'
    children = [subprocess.Popen([sys.executable, str(exe / 'robot'), '--ros-args', '-p',
                                  'robot_id:=3'], stdin=subprocess.PIPE),
                subprocess.Popen([sys.executable, str(exe / 'plant')], stdin=subprocess.PIPE),
                subprocess.Popen([sys.executable, str(exe / 'formation_report')],
                                 stdin=subprocess.PIPE)]
    try:
        found = soak.find_run_processes(os.getpid(), str(fake_install))
        assert found == {'robot_3': children[0].pid, 'plant': children[1].pid}
        assert soak.find_run_processes(children[2].pid, str(fake_install)) == {}
        assert soak.read_rss_kib(children[0].pid) > 1000
        # a child's share of the pages it shares with the others is less than all of them
        assert 0 < soak.read_pss_kib(children[0].pid) < soak.read_rss_kib(children[0].pid)
    finally:
        for child in children:
            child.stdin.close()
            child.wait(timeout=30)
    assert soak.read_rss_kib(children[0].pid) is None
    assert soak.read_pss_kib(children[0].pid) is None


def test_summary_compares_first_and_last_window(soak):
    samples = {
        'launcher': [(float(t), 1000) for t in range(0, 200, 5)],
        'plant': [(float(t), 2000 + 10 * t) for t in range(5, 200, 5)],
        'robot_1': [(float(t), 3000) for t in range(5, 180, 5)],
    }
    table = soak.summarise(samples, 60.0)
    assert table['launcher']['growth_percent'] == 0.0
    assert table['plant']['first_kib'] == 2000 + 10 * 35
    assert table['plant']['last_kib'] == 2000 + 10 * 145
    assert table['plant']['growth_percent'] == pytest.approx(100.0 * 1100 / 2350)
    assert table['robot_1']['growth_percent'] == 0.0
    ramp = {'launcher': [(0.0, 10)] + samples['launcher'][1:], 'plant': samples['plant']}
    assert soak.summarise(ramp, 5.0)['launcher']['first_kib'] == 1000
    text = soak.format_table(table, 60.0)
    assert text.splitlines()[2].startswith('| launcher |')
    assert '| plant | 2.3 | 3.4 | +46.81 |' in text


def test_json_and_figure_are_written(soak, tmp_path):
    samples = {'plant': [(0.0, 2048), (5.0, 2048)], 'robot_2': [(5.0, 4096)]}
    path = tmp_path / 'deep' / 'soak.json'
    soak.write_json(str(path), {'processes': soak.summarise(samples, 60.0), 'samples': samples})
    written = json.loads(path.read_text())
    assert written['processes']['plant']['growth_percent'] == 0.0
    assert written['samples']['robot_2'] == [[5.0, 4096]]
    figure = tmp_path / 'rss.png'
    soak.write_figure(str(figure), samples)
    assert figure.read_bytes()[:8] == b'\x89PNG\r\n\x1a\n'


def test_sampling_ends_with_the_launcher(soak, fake_install):
    process = subprocess.Popen([sys.executable, '-c', 'import time; time.sleep(1.0)'])
    samples, pids = soak.sample_run(process, str(fake_install), 0.05, time.monotonic())
    assert process.returncode == 0
    assert set(samples) == {'launcher'} and pids == {'launcher': [process.pid]}
    times = [t for t, _ in samples['launcher']]
    assert times == sorted(times) and all(kib > 0 for _, kib in samples['launcher'])


ORPHANS = os.path.join(ROOT, 'bench', 'bench_orphans.py')


@pytest.fixture(scope='module')
def orphans():
    return load_bench(ORPHANS)


def test_orphans_help_and_arguments(orphans, fake_install, tmp_path):
    result = subprocess.run([sys.executable, ORPHANS, '--help'], capture_output=True, text=True,
                            timeout=120)
    assert result.returncode == 0, result.stderr
    for option in ('--runs', '--busy', '--record', '--prefix', '--params', '--json', 'SIGKILL'):
        assert option in result.stdout
    args = orphans.parse_args(['--prefix', str(fake_install), '--out', str(tmp_path / 'o')])
    assert args.runs == 10 and args.busy == 2 and not args.record and args.limit == 2.0
    assert args.params.endswith(os.path.join('config', 'square_4.yaml'))
    assert args.json == os.path.join(str(tmp_path / 'o'), 'orphans.json')
    for bad in (['--runs', '0'], ['--busy', '-1'], ['--limit', '0'], ['--params', '/no/file']):
        with pytest.raises(SystemExit) as info:
            orphans.parse_args(['--prefix', str(fake_install), '--out', str(tmp_path / 'o'),
                                *bad])
        assert info.value.code == 2


def test_orphans_expected_nodes_and_clock_line(orphans):
    assert orphans.expected_nodes(2, False) == ['plant', 'reference', 'robot_1', 'robot_2']
    assert orphans.expected_nodes(1, True) == ['record', 'plant', 'reference', 'robot_1']
    line = '[plant] [INFO] [1.5] [plant]: all 4 robots are up: starting the clock'
    assert orphans.clock_started('[robot_1] [INFO] waiting\n' + line + '\n')
    assert not orphans.clock_started('[robot_1] [INFO] waiting for reference\n')
    assert not orphans.clock_started('[robot_1] starting the clock\n')


def test_orphans_follows_a_process_until_it_ends(orphans):
    child = subprocess.Popen([sys.executable, '-c', 'import sys; print(1, flush=True); '
                              'sys.stdin.read()'], stdin=subprocess.PIPE, stdout=subprocess.PIPE,
                             env=dict(os.environ, FORMATION_LAUNCHER_PID='999999999',
                                      FORMATION_LAUNCHER_START='42'))
    assert child.stdout.readline() == b'1\n'  # it runs Python: its environment is the new one
    start = orphans.process_start(child.pid)
    assert start is not None and orphans.alive(child.pid, start)
    assert not orphans.alive(child.pid, start + 1)
    assert orphans.launched_by(child.pid) == ('999999999', '42')
    assert orphans.run_processes_left(999999999, 42) == [child.pid]
    assert orphans.run_processes_left(999999999, 43) == []
    since = time.monotonic()
    child.stdin.close()
    ends = orphans.watch_ends({'robot_1': (child.pid, start)}, since, 0.005, 30.0)
    assert 0.0 < ends['robot_1'] < 30.0
    assert orphans.process_start(child.pid) is None  # a zombie counts as ended
    child.wait(timeout=30)
    child.stdout.close()
    assert orphans.run_processes_left(999999999, 42) == []
    stuck = subprocess.Popen([sys.executable, '-c', 'import time; time.sleep(30)'])
    try:
        ends = orphans.watch_ends({'plant': (stuck.pid, orphans.process_start(stuck.pid))},
                                  time.monotonic(), 0.005, 0.05)
        assert ends == {'plant': None}
    finally:
        stuck.kill()
        stuck.wait(timeout=30)


def test_orphans_summary_and_table(orphans):
    runs = [{'run': 1, 'ends': {'plant': 0.2, 'robot_1': 0.4}, 'failures': [],
             'load_at_kill': [3.0, 2.0, 1.0]},
            {'run': 2, 'ends': {'plant': 2.5, 'robot_1': None}, 'failures': ['robot_1 ...'],
             'load_at_kill': [4.25, 2.0, 1.0]}]
    summary = orphans.summarise_runs(runs, 2.0)
    assert summary['max_s'] == 2.5 and summary['median_s'] == pytest.approx(0.4)
    assert summary['node_ends'] == 3 and summary['not_ended'] == 1
    assert summary['over_limit'] == 2 and summary['failures'] == 1
    assert summary['max_per_node_s'] == {'plant': 2.5, 'robot_1': 0.4}
    text = orphans.format_table(runs, ['plant', 'robot_1'])
    lines = text.splitlines()
    assert lines[0] == '| run | load | slowest (s) | plant | robot_1 |'
    assert lines[2] == '| 1 | 3.0 | 0.400 | 0.200 | 0.400 |'
    assert lines[3] == '| 2 | 4.2 | not ended | 2.500 | not ended |'


def test_orphans_reads_how_a_child_ended(orphans):
    code = subprocess.Popen([sys.executable, '-c', 'raise SystemExit(3)'])
    killed = subprocess.Popen([sys.executable, '-c', 'import time; time.sleep(30)'])
    killed.kill()
    assert orphans.reap(code.pid) == 'exit 3'
    assert orphans.reap(killed.pid) == 'SIGKILL'
    assert orphans.reap(os.getpid()) is None  # not a child
    assert orphans.describe_status(0) == 'exit 0'


def test_offline_benchmark_runs_a_tiny_size_and_writes_its_json(tmp_path):
    result = subprocess.run([sys.executable, os.path.join(ROOT, 'bench', 'bench_offline.py'),
                             '--sizes', '3', '5', '--duration', '0.2', '--out',
                             str(tmp_path / 'out')], capture_output=True, text=True, timeout=300)
    assert result.returncode == 0, result.stdout + result.stderr
    rows = json.loads((tmp_path / 'out' / 'offline.json').read_text())['rows']
    assert [row['robots'] for row in rows] == [3, 5]
    for row in rows:
        assert row['steps'] == 20 and row['wall_s'] > 0.0 and row['peak_rss_mib'] > 10.0
        assert row['max_abs_u_hat_component'] <= row['u_bound'] + 1e-9
    assert '| 5 |' in result.stdout


def test_capacity_benchmark_refuses_bad_arguments(fake_install, tmp_path):
    script = os.path.join(ROOT, 'bench', 'bench_capacity.py')
    lib = fake_install / 'lib' / 'formation_ros'
    (lib / 'plant').chmod(0o755)
    for args, says in ((['--rates', '0'], '--rates must be > 0'),
                       (['--rates', '500'], '--rates must be > 0'),
                       (['--sizes', '0'], '--sizes and --robots-per-process must be >= 1'),
                       (['--measure', '0'], '--measure and --startup-timeout must be > 0'),
                       (['--reference-rate', '-1'], '--reference-rate must be 0'),
                       (['--reference-rate', '2'], 'above 2 Hz'),
                       (['--obstacles', '-1'], '--obstacles must be >= 0')):
        result = subprocess.run([sys.executable, script, *args, '--prefix', str(fake_install),
                                 '--out', str(tmp_path / 'out')],
                                capture_output=True, text=True, timeout=120)
        assert result.returncode == 2 and says in result.stderr, (args, result.stderr)
    assert 'fresh' in subprocess.run([sys.executable, script, '--help'], capture_output=True,
                                     text=True, timeout=120).stdout


def test_capacity_rows_name_a_reference_rate_other_than_the_control_rate():
    capacity = load_bench(os.path.join(ROOT, 'bench', 'bench_capacity.py'))
    row = {'mode': 'process', 'robots': 20, 'rate_hz': 50.0, 'processes': 22, 'startup_s': 7.0,
           'step_rate': 97.5, 'fresh_fraction': 0.991, 'cpu_percent': {'plant': 24.0},
           'rss_mib': {'plant': 116.0},
           'latency_ms': {'p50_ms': 12.7, 'p99_ms': 26.3, 'max_ms': 234.0}}
    assert capacity.format_row(row).startswith('| process | 20 | 50 | 22 |')
    same = capacity.format_row({**row, 'reference_rate_hz': 50.0})
    assert same.startswith('| process | 20 | 50 | 22 |')
    assert capacity.format_row({**row, 'reference_rate_hz': 10.0}).startswith(
        '| process | 20 | 50, reference 10 | 22 |')
    assert capacity.case_params(20, 50.0, False)['reference.rate'] == 10.0
    assert capacity.case_params(20, 50.0, False, reference_rate=0.0)['reference.rate'] == 50.0


def test_capacity_pillars_are_valid_among_the_team_and_named_in_the_row():
    capacity = load_bench(os.path.join(ROOT, 'bench', 'bench_capacity.py'))
    assert 'obstacles.circles' not in capacity.case_params(100, 50.0, False, 'team')
    params = capacity.case_params(100, 50.0, False, 'team', obstacles=20)
    config = validate(params)  # no start touching, no place within b_o
    assert config.obstacles is not None and config.obstacles.count == 20
    centres = np.array(params['obstacles.circles']).reshape(-1, 3)[:, :2]
    places = np.array(params['formation.vertices']).reshape(-1, 2)
    assert np.all(np.abs(centres) <= np.abs(places).max())  # among the places
    row = {'mode': 'fleet', 'robots': 100, 'rate_hz': 50.0, 'processes': 6, 'startup_s': 4.0,
           'step_rate': 99.8, 'fresh_fraction': 1.0, 'cpu_percent': {'plant': 16.0},
           'rss_mib': {'plant': 132.0}, 'transport': 'team', 'obstacles': 20,
           'obstacle_contacts': 0,
           'latency_ms': {'p50_ms': 3.5, 'p99_ms': 10.0, 'max_ms': 45.0}}
    assert capacity.format_row(row).endswith('| team, 20 pillars, 0 contacts |')


def test_capacity_figure_is_drawn_from_earlier_results_alone(tmp_path):
    script = os.path.join(ROOT, 'bench', 'bench_capacity.py')
    rows = [{'mode': mode, 'robots': n, 'rate_hz': 20.0, 'fresh_fraction': 0.5 + n / 400.0}
            for mode in ('process', 'fleet') for n in (10, 20)]
    paths = []
    for mode in ('process', 'fleet'):
        paths.append(tmp_path / f'{mode}.json')
        paths[-1].write_text(json.dumps({'rows': [r for r in rows if r['mode'] == mode]}))
    result = subprocess.run([sys.executable, script, '--figure', *map(str, paths), '--out',
                             str(tmp_path / 'out')], capture_output=True, text=True, timeout=120)
    assert result.returncode == 0, result.stderr
    assert (tmp_path / 'out' / 'capacity_fresh.png').stat().st_size > 1000
    assert 'from 4 rows' in result.stdout
    (tmp_path / 'bad.json').write_text('[1, 2]')
    result = subprocess.run([sys.executable, script, '--figure', str(tmp_path / 'bad.json'),
                             '--out', str(tmp_path / 'out')], capture_output=True, text=True,
                            timeout=120)
    assert result.returncode == 2 and 'is not a capacity.json' in result.stderr
    assert len(result.stderr.strip().splitlines()) == 1


def test_robustness_benchmark_quick_run_writes_complete_results_and_figures(tmp_path):
    script = os.path.join(ROOT, 'bench', 'bench_robustness.py')
    robustness = load_bench(script)
    result = subprocess.run([sys.executable, script, '--quick', '--out', str(tmp_path)],
                            capture_output=True, text=True, timeout=300)
    assert result.returncode == 0, result.stdout + result.stderr
    data = json.loads((tmp_path / 'bench' / 'robustness.json').read_text())
    sweeps = data['sweeps']
    assert set(sweeps) == set(robustness.SWEEPS) | {'delay_lag', 'gain'}
    for name, sweep in sweeps.items():
        assert (tmp_path / f'robustness_{name}.png').stat().st_size > 1000
        assert {row['config'] for row in sweep['rows']} == set(robustness.CONFIGS)
        for row in sweep['rows']:
            summary = row['summary']
            assert summary['starts'] == len(row['runs']) == 1
            assert 0.0 < summary['closest_bodies'] <= summary['closest_points'] + 0.2
            assert summary['max_abs_u_hat'] <= summary['u_bound'] * (1.0 + 1e-9)
            assert summary['held'] == (summary['closest_bodies'] >= row['size']
                                       and summary['collisions'] == 0)
    ideal = sweeps['lag']['rows'][0]['runs'][0]
    assert sweeps['noise']['rows'][0]['runs'][0] == ideal  # one run per distinct setting
    assert ideal['delay_steps'] == 0 and sweeps['delay']['rows'][1]['runs'][0]['delay_steps'] == 20
    assert data['configs']['unicycle']['size'] == 0.22
    assert data['configs']['section5']['size'] == 0.1
    assert set(data['limits']['delay']) == set(robustness.CONFIGS)
    assert data['machine']['nproc'] == os.cpu_count() and data['machine']['python']
    assert '| section5 | 0.2 |' in result.stdout and 'bench_robustness: 1/' in result.stderr
    (tmp_path / 'robustness_gain.png').unlink()
    again = subprocess.run([sys.executable, script, '--redraw', '--out', str(tmp_path)],
                           capture_output=True, text=True, timeout=120)
    assert again.returncode == 0 and (tmp_path / 'robustness_gain.png').stat().st_size > 1000
    assert json.loads((tmp_path / 'bench' / 'robustness.json').read_text())['limits'] == data[
        'limits']
    (tmp_path / 'bench' / 'robustness.json').write_text('[1, 2]')
    again = subprocess.run([sys.executable, script, '--redraw', '--out', str(tmp_path)],
                           capture_output=True, text=True, timeout=120)
    assert again.returncode == 2 and len(again.stderr.strip().splitlines()) == 1
    for bad in (['--seeds', '0'], ['--jobs', '0']):
        with pytest.raises(SystemExit) as info:
            robustness.parse_args(bad)
        assert info.value.code == 2
    assert robustness.parse_args(['--quick', '--seeds', '5']).seeds == 1


def test_switch_benchmark_offline_quick_run_measures_the_settle_after_the_switch(tmp_path):
    script = os.path.join(ROOT, 'bench', 'bench_switch.py')
    switch = load_bench(script)
    result = subprocess.run([sys.executable, script, '--quick', '--offline', '--out',
                             str(tmp_path)], capture_output=True, text=True, timeout=300)
    assert result.returncode == 0, result.stdout + result.stderr
    data = json.loads((tmp_path / 'bench' / 'switch.json').read_text())
    runs = data['runs']
    assert set(runs) == {'formation_sim RK45', 'formation_sim --dt 0.01'}
    for row in runs.values():
        assert row['switch_at'] == switch.QUICK_SWITCH_AT
        assert row['settle_time_before'] < switch.QUICK_SWITCH_AT
        assert 0.0 < row['settle_time'] < switch.QUICK_DURATION - switch.QUICK_SWITCH_AT
        assert row['max_abs_u_hat_after'] <= row['u_bound'] * (1.0 + 1e-9)
        assert row['closest_after'] >= 1.0
    rk45, fixed = runs['formation_sim RK45'], runs['formation_sim --dt 0.01']
    assert abs(rk45['settle_time'] - fixed['settle_time']) <= 0.05
    line = np.reshape(data['shape']['vertices'], (10, 2))
    gaps = [np.linalg.norm(line[i] - line[j]) for i in range(10) for j in range(i)]
    assert min(gaps) == pytest.approx(1.5) and np.all(line[:, 1] == 0.0)
    assert data['machine']['nproc'] == os.cpu_count()
    assert '| formation_sim RK45 | 6.00 |' in result.stdout
    assert 'bench_switch: formation_sim RK45: settled' in result.stderr
    for bad in (['--gif', '--offline'], ['--prefix', str(tmp_path)], ['--work', str(tmp_path)]):
        with pytest.raises(SystemExit) as info:
            switch.parse_args(bad)
        assert info.value.code == 2


def test_switch_benchmark_line_keeps_each_half_of_the_circle_in_order():
    switch = load_bench(os.path.join(ROOT, 'bench', 'bench_switch.py'))
    angles = np.arange(10) * 2.0 * np.pi / 10.0
    circle = 8.0 * np.stack([np.sin(angles), np.cos(angles)], axis=1)
    line = switch.line_shape(circle)
    assert sorted(line[:, 0].tolist()) == pytest.approx([-6.75 + 1.5 * k for k in range(10)])
    for half in (circle[:, 1] > 1e-9, circle[:, 1] < -1e-9):
        order = np.argsort(circle[half, 0])
        assert np.all(np.diff(line[half, 0][order]) > 0.0)
    assert line[0, 0] == pytest.approx(0.75) and line[5, 0] == pytest.approx(-0.75)


def test_lag_fit_recovers_the_lag_and_the_limit_of_its_own_model():
    lag_fit = load_bench(os.path.join(ROOT, 'bench', 'lag_fit.py'))
    t = np.arange(1, 301) * 0.002
    measured = lag_fit.model_response(t, 0.2, 0.03, 4.0)
    fit = lag_fit.fit_lag([(t, measured, 0.2)])
    assert fit.lag == pytest.approx(0.03, abs=1e-4)
    assert fit.max_acceleration == pytest.approx(4.0, rel=1e-3)
    assert fit.rms < 1e-6 and fit.relative_rms < 1e-5
    pure = lag_fit.fit_lag([(t, lag_fit.model_response(t, 2.0, 0.05, 0.0), 2.0)])
    assert pure.lag == pytest.approx(0.05, abs=1e-4) and pure.max_acceleration == 0.0
    both = lag_fit.fit_lag([(t, measured, 0.2), (t, lag_fit.model_response(t, 2.0, 0.03, 4.0),
                                                 2.0)])
    assert both.lag == pytest.approx(0.03, abs=1e-3) and both.relative_rms == both.rms
    with pytest.raises(ValueError):
        lag_fit.fit_lag([(t, measured, 0.0)])


def test_robustness_benchmark_on_the_physics_engine_quick_run(tmp_path):
    script = os.path.join(ROOT, 'bench', 'bench_robustness.py')
    robustness = load_bench(script)
    result = subprocess.run([sys.executable, script, '--physics', '--quick', '--only', 'torque',
                             'fit', '--out', str(tmp_path)], capture_output=True, text=True,
                            timeout=300, env=dict(os.environ, MPLBACKEND='Agg'))
    assert result.returncode == 0, result.stdout + result.stderr
    assert not (tmp_path / 'bench' / 'robustness.json').exists()
    path = tmp_path / 'bench' / 'robustness_physics.json'
    data = json.loads(path.read_text())
    rows = data['sweeps']['torque']['rows']
    assert {row['team'] for row in rows} == {'turtlebot3', 'crossing', 'holonomic'}
    assert {row['parameter'] for row in rows} == {'world.wheel_torque', 'world.force_limit'}
    for row in rows:
        summary = row['summary']
        assert summary['starts'] == 1 and summary['contacts'] == 0 and summary['held']
        assert summary['closest_bodies'] == pytest.approx(row['size'] + summary['footprint_gap'])
        assert summary['max_abs_u_hat'] <= summary['u_bound'] * (1.0 + 1e-9)
    fits = data['fit']['fits']
    for team, entries in fits.items():
        for entry in entries:
            for fit in entry['fit'].values():
                assert 0.0 <= fit['lag'] < 0.1 and fit['relative_rms'] < 0.05
    assert set(fits) == {'turtlebot3', 'holonomic'}  # the crossing team's bases are the same
    assert len(data['fit']['side_by_side']) == 3 * 2
    assert data['runs'][0]['machine']['nproc'] == os.cpu_count()
    for name in ('sweeps', 'fit'):
        assert (tmp_path / f'robustness_physics_{name}.png').stat().st_size > 1000
    assert '| turtlebot3 | `world.wheel_torque` | 0.2 |' in result.stdout
    assert 'bench_robustness --physics: 1/' in result.stderr
    again = subprocess.run([sys.executable, script, '--physics', '--quick', '--only', 'noise',
                            '--teams', 'holonomic', '--out', str(tmp_path)],
                           capture_output=True, text=True, timeout=300)
    assert again.returncode == 0, again.stderr
    merged = json.loads(path.read_text())
    assert merged['sweeps']['torque'] == data['sweeps']['torque']
    assert {row['team'] for row in merged['sweeps']['noise']['rows']} == {'holonomic'}
    assert len(merged['runs']) == 2 and merged['fit'] == data['fit']
    redrawn = subprocess.run([sys.executable, script, '--physics', '--redraw', '--out',
                              str(tmp_path)], capture_output=True, text=True, timeout=120)
    assert redrawn.returncode == 0 and '| holonomic | `world.pose_noise` |' in redrawn.stdout
    path.write_text('[1, 2]')
    bad = subprocess.run([sys.executable, script, '--physics', '--redraw', '--out',
                          str(tmp_path)], capture_output=True, text=True, timeout=120)
    assert bad.returncode == 2 and len(bad.stderr.strip().splitlines()) == 1
    for options in (['--only', 'fit'], ['--physics', '--only', 'gravity'],
                    ['--physics', '--teams', 'drones']):
        with pytest.raises(SystemExit) as info:
            robustness.parse_args(options)
        assert info.value.code == 2
    assert robustness.parse_args(['--physics']).seeds == 1
    assert robustness.parse_args([]).seeds == 3


def test_bench_obstacles_places_pillars_off_the_team_and_runs_without_contact(tmp_path):
    bench = load_bench(os.path.join(ROOT, 'bench', 'bench_obstacles.py'))
    params = bench.params_for(100)
    pillars = np.array(bench.lattice_pillars(params, 10)).reshape(-1, 3)
    assert len(pillars) == 10
    places = np.array(params['formation.vertices']).reshape(-1, 2)
    nearest = np.min(np.linalg.norm(places[:, None] - pillars[None, :, :2], axis=2), axis=0)
    assert np.all(nearest - pillars[:, 2] > bench.CLEARANCE)
    assert np.all(np.linalg.norm(pillars[:, :2], axis=1) > params['start.random_radius'])
    bench.main(['--cost-sizes', '20', '--pillars', '6', '--repeats', '1', '--out',
                str(tmp_path)])
    with open(tmp_path / 'obstacles.json', encoding='utf-8') as stream:
        rows = json.load(stream)['cost']
    assert [row['pillars'] for row in rows] == [0, 6]
    assert rows[1]['obstacle_contacts'] == 0 and rows[0]['min_obstacle_clearance'] is None
