# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
Hostile parameters files: every program refuses them in one line, exit 2, in bounded memory.

Each case is a file a lab could be handed (or make by mistake): aliases that expand a billion
times, two million vertex values, a file too large, nesting 100,000 deep, an anchor in an
otherwise fine file, a list used as a key. Each program that reads parameters files runs from
the colcon install in a fresh process: the plant and a robot (``--params-file``, checked before
rcl sees it), formation_sim, formation_report (a run directory's params.yaml) and the launcher.
The peak memory of that process is measured (``ru_maxrss`` of a wrapper's only child) and
bounded; the time is printed, not asserted (bench/bench_files.py measures it).
"""

import json
import os
import re
import subprocess
import sys

from helpers import exe, ROOT, SQUARE
import pytest

pytestmark = pytest.mark.faults
PEAK_MB = 200
"""Bound on a refusing program's peak memory. Before the guard, the two-million-value file
took the plant ~750 MB and formation_sim ~1 GB, and the expanding file took formation_sim past
1.4 GB; a refusing program now stays near its imports (about 100 MB for formation_sim)."""
PROGRAMS = ('plant', 'robot', 'formation_sim', 'formation_report', 'launcher')
LAUNCHER = os.path.join(ROOT, 'scripts', 'launch_formation.sh')
MEASURE = """
import json, resource, subprocess, sys, time
start = time.monotonic()
result = subprocess.run(sys.argv[1:], capture_output=True, text=True, timeout=300)
print(json.dumps({'code': result.returncode, 'stdout': result.stdout, 'stderr': result.stderr,
                  'seconds': time.monotonic() - start,
                  'peak_mb': resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss / 1024}))
"""


def square_text():
    with open(SQUARE, encoding='utf-8') as stream:
        return stream.read()


def with_vertices(values):
    """Return the square's file with ``formation.vertices`` replaced by ``values`` (YAML)."""
    text = square_text()
    start = text.index('      vertices: ')
    end = text.index('\n', start)
    return text[:start] + '      vertices: ' + values + text[end:]


def laughs():
    """Nine levels of ten aliased mappings (10^9 names) under a key the package does not know."""
    keys = 'abcdefghij'
    lines = ['    lol:', '      l0: &l0 {' + ', '.join(f'{key}: lol' for key in keys) + '}']
    lines += [f'      l{k}: &l{k} {{' + ', '.join(f'{key}: *l{k - 1}' for key in keys) + '}'
              for k in range(1, 9)]
    return square_text() + '\n'.join(lines) + '\n'


def numbered(text, needle):
    return text[:text.index(needle)].count('\n') + 1


def run_measured(program, path, tmp_path, install, env):
    """Run ``program`` on parameters file ``path`` in a fresh process; return what it did."""
    if program in ('plant', 'robot'):
        command = [exe(install, program), '--ros-args', '--params-file', path]
    elif program == 'formation_sim':
        command = [exe(install, program), path, '--out', str(tmp_path / 'sim')]
    elif program == 'formation_report':
        run = tmp_path / 'run'
        run.mkdir()
        (run / 'params.yaml').write_bytes(open(path, 'rb').read())
        (run / 'trajectory.npz').write_bytes(b'never read')
        command = [exe(install, program), str(run), '--out', str(tmp_path / 'report')]
        path = str(run / 'params.yaml')
    else:
        command = ['bash', LAUNCHER, path, '--prefix', install, '--duration', '5',
                   '--out', str(tmp_path / 'out')]
    result = subprocess.run([sys.executable, '-c', MEASURE, *command], env=env,
                            capture_output=True, text=True, timeout=360)
    assert result.returncode == 0, result.stderr
    measured = json.loads(result.stdout)
    print(f'{program}: exit {measured["code"]} in {measured["seconds"]:.2f} s, peak '
          f'{measured["peak_mb"]:.0f} MB: {measured["stderr"].strip()}')
    return measured, path


def refuses(program, text, tmp_path, install, env, problem, line=None):
    """Assert ``program`` refuses ``text``: exit 2, one line naming file and problem."""
    path = str(tmp_path / 'robots.yaml')
    with open(path, 'w', encoding='utf-8') as stream:
        stream.write(text)
    measured, named = run_measured(program, path, tmp_path, install, env)
    lines = [line for line in measured['stderr'].splitlines() if line.strip()]
    assert measured['code'] == 2, measured
    assert len(lines) == 1, lines
    assert named in lines[0] and problem in lines[0], lines
    if line is not None:
        assert f'{named} line {line}:' in lines[0], lines
    assert not measured['stdout'].strip(), measured['stdout']
    assert not re.search(r'\brcl\b|libyaml|Traceback|parse\.c', lines[0], re.IGNORECASE), lines
    assert measured['peak_mb'] < PEAK_MB, measured
    if program == 'launcher':
        assert not (tmp_path / 'out').exists()


@pytest.mark.parametrize('program', PROGRAMS)
def test_a_file_that_expands_is_refused_at_its_first_anchor(program, install, ros_env,
                                                            tmp_path):
    text = laughs()
    refuses(program, text, tmp_path, install, ros_env, 'YAML anchors are not allowed (&l0)',
            numbered(text, '&l0'))


@pytest.mark.parametrize('program', PROGRAMS)
def test_two_million_vertex_values_are_refused_by_the_team_size(program, install, ros_env,
                                                                tmp_path):
    text = with_vertices('[' + ', '.join(['0.'] * 2_000_000) + ']')
    assert len(text) < 8 * 2 ** 20
    refuses(program, text, tmp_path, install, ros_env,
            'formation.vertices has more than 10000 values', numbered(text, 'vertices: ['))


@pytest.mark.parametrize('program', PROGRAMS)
def test_a_file_too_large_is_refused_before_it_is_read(program, install, ros_env, tmp_path):
    text = with_vertices('\n' + '        - 0.0\n' * 2_000_000)
    refuses(program, text, tmp_path, install, ros_env, 'larger than the 8 MiB')


@pytest.mark.parametrize('program', PROGRAMS)
def test_deep_nesting_is_refused(program, install, ros_env, tmp_path):
    text = square_text() + '    junk: ' + '[' * 100_000 + ']' * 100_000 + '\n'
    refuses(program, text, tmp_path, install, ros_env, 'nested more than 16 levels deep',
            numbered(text, 'junk'))


@pytest.mark.parametrize('program', PROGRAMS)
def test_an_anchor_in_an_otherwise_fine_file_is_refused(program, install, ros_env, tmp_path):
    text = square_text().replace('repulsion_radius: 1.0', 'repulsion_radius: &one 1.0').replace(
        'kappa: 1.0', 'kappa: *one')
    refuses(program, text, tmp_path, install, ros_env, 'YAML anchors are not allowed (&one)',
            numbered(text, '&one'))


@pytest.mark.parametrize('program', PROGRAMS)
def test_malformed_yaml_is_said_in_our_words(program, install, ros_env, tmp_path):
    text = square_text().replace('    duration: 10.0\n', '    [duration]: 10.0\n')
    refuses(program, text, tmp_path, install, ros_env, 'a sequence cannot be a key',
            numbered(text, '[duration]'))
