# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""The README stays short and true: CI's command, links into docs/, ros2 run lines that work."""

import os
import re
import shlex

from formation_ros.core.settings.declarations import Exe, is_known, ParamError
from formation_ros.core.settings.params import validate
from formation_ros.core.settings.params_file import load_params_file
import pytest
import yaml

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
DOCS = os.path.join(ROOT, 'docs')
MAX_README_LINES = 250
SHARE = 'install/formation_ros/share/formation_ros/'
PKG_PREFIX = '$(ros2 pkg prefix --share formation_ros)/'
NODES = {'plant': Exe.PLANT, 'robot': Exe.ROBOT, 'fleet': Exe.ROBOT, 'reference': Exe.REFERENCE,
         'record': Exe.RECORD, 'relay': Exe.RELAY, 'world': Exe.WORLD}
ON_SIM_TIME = ('robot', 'fleet', 'reference')


def read(name):
    with open(os.path.join(ROOT, name), encoding='utf-8') as stream:
        return stream.read()


def documents():
    """Return the README and every docs page, as paths relative to the repository."""
    return ['README.md'] + sorted(os.path.join('docs', name) for name in os.listdir(DOCS)
                                  if name.endswith('.md'))


def test_ci_runs_the_readme_test_command():
    lines = [line.strip() for line in read('.ci/run').splitlines()]
    command = [line for line in lines if line and not line.startswith('#')][-1]
    assert f'\n{command}\n' in read('README.md')


def test_the_readme_is_short_and_names_the_two_commands_and_the_docs_build():
    readme = read('README.md')
    assert len(readme.splitlines()) <= MAX_README_LINES, len(readme.splitlines())
    for command in ('bash scripts/demo.sh', 'bash scripts/run_tests.sh',
                    'bash scripts/build_docs.sh'):
        assert f'\n{command}' in readme, command


def slug(heading):
    """Return the anchor MyST and GitHub give a heading (lower case, punctuation dropped)."""
    text = re.sub(r'[^\w\- ]', '', heading.strip().lower())
    return text.replace(' ', '-')


def anchors(path):
    """Return the anchors of the headings of a Markdown file (outside code blocks)."""
    found, fenced = set(), False
    for line in read(path).splitlines():
        if line.startswith('```'):
            fenced = not fenced
        elif not fenced and re.match(r'#{1,6} ', line):
            found.add(slug(line.lstrip('#')))
    return found


def test_slug_follows_the_headings_rules():
    assert slug(' Running a lab (no plant)') == 'running-a-lab-no-plant'
    assert slug(' Slip 7: the exponent of dis_all (Section 5)') == \
        'slip-7-the-exponent-of-dis_all-section-5'


def test_the_readme_links_into_docs_resolve():
    links = re.findall(r'\]\((docs/[^)#\s]+)(?:#([^)\s]+))?\)', read('README.md'))
    assert len(links) >= 10, links
    broken = []
    for target, anchor in links:
        if not os.path.isfile(os.path.join(ROOT, target)):
            broken.append(target)
        elif anchor and anchor not in anchors(target):
            broken.append(f'{target}#{anchor}')
    assert not broken, broken


def test_scripts_are_strict_and_have_help():
    for name in ('setup_env.sh', 'demo.sh', 'run_tests.sh', 'build_docs.sh'):
        text = read(os.path.join('scripts', name))
        assert 'set -euo pipefail' in text and '--help' in text, name


def shell_blocks(path):
    """Yield the shell code blocks of a Markdown file, continuation lines joined."""
    for block in re.findall(r'```(?:bash|sh)\n(.*?)```', read(path), re.S):
        yield block.replace('\\\n', ' ')


def ros2_run_lines(path):
    """
    Return (command, variables) for each ``ros2 run formation_ros`` line of a file.

    A variable (``P=...``) holds from its assignment to the end of the file.
    """
    found = []
    variables = {}
    for block in shell_blocks(path):
        for line in block.splitlines():
            line = line.split(' #')[0].strip()
            assignment = re.fullmatch(r'([A-Z]+)=(\S+)', line)
            if assignment:
                variables[assignment.group(1)] = assignment.group(2)
            if 'ros2 run formation_ros ' in line:
                command = line[line.index('ros2 run formation_ros '):].rstrip('&; ')
                found.append((command, dict(variables)))
    return found


def resolve(path):
    """Return a parameters file named in the docs as a file of this repository."""
    for prefix in (SHARE, PKG_PREFIX):
        if path.startswith(prefix):
            path = path[len(prefix):]
    return os.path.join(ROOT, path)


def ros2_run_problem(command, variables):
    """Say why ``ros2 run formation_ros EXE ...`` would not start as written, or None."""
    for name, value in variables.items():
        command = command.replace(f'${name}', value)
    words = shlex.split(command.replace('$i', '1'))
    executable = words[3]
    if executable not in NODES:
        return None if f"'{executable} = " in read('setup.py') else 'no such executable'
    ros = words[words.index('--ros-args') + 1:] if '--ros-args' in words else []
    files, overrides, namespace = [], {}, None
    for flag, value in zip(ros, ros[1:]):
        if flag == '--params-file':
            files.append(resolve(value))
        elif flag == '-p':
            name, _, text = value.partition(':=')
            if not is_known(name):
                return f'unknown parameter {name}'
            overrides[name] = yaml.safe_load(text)
        elif flag == '-r' and value.startswith('__ns:='):
            namespace = value[len('__ns:='):]
    if len(files) != 1 or not os.path.isfile(files[0]):
        return f'no parameters file: {files}'
    raw = load_params_file(files[0])
    world = any(name.startswith('world.') for name in raw)
    lab = any(name.startswith('relay.') for name in raw) and not world
    sim_time = overrides.pop('use_sim_time', False)
    on_sim_time = ON_SIM_TIME + (('relay',) if world else ())
    if executable in on_sim_time and sim_time is lab:
        return 'a lab runs on wall-clock time' if lab else 'needs -p use_sim_time:=true'
    if executable not in on_sim_time and sim_time:
        return 'the plant, world, recorder and lab relay must not wait for /clock'
    raw.update(overrides)
    if executable == 'robot':
        match = re.fullmatch(r'/robot_([0-9]+)', namespace or '')
        if match is None:
            return 'a robot needs -r __ns:=/robot_<i>'
        raw.setdefault('robot_id', int(match.group(1)))
        if raw['robot_id'] != int(match.group(1)):
            return 'robot_id and namespace disagree'
    if executable == 'fleet':
        raw['robot_id'] = int(re.match(r'[0-9]+', words[words.index('--robots') + 1]).group())
    try:
        validate(raw, NODES[executable])
    except ParamError as exc:
        return str(exc)
    return None


def test_the_docs_have_ros2_run_lines_of_every_node():
    executables = {command.split()[3] for path in documents()
                   for command, _ in ros2_run_lines(path)}
    assert {'plant', 'robot', 'reference', 'record', 'fleet', 'relay'} <= executables


@pytest.mark.parametrize('path', documents())
def test_every_ros2_run_line_starts_as_written(path):
    problems = [f'{command}: {problem}' for command, variables in ros2_run_lines(path)
                for problem in [ros2_run_problem(command, variables)] if problem]
    assert not problems, problems


@pytest.mark.parametrize('command, says', [
    ('ros2 run formation_ros robot --ros-args -r __ns:=/robot_1 '
     '--params-file config/square_4.yaml', 'needs -p use_sim_time:=true'),
    ('ros2 run formation_ros plant --ros-args --params-file config/square_4.yaml '
     '-p use_sim_time:=true', 'must not wait for /clock'),
    ('ros2 run formation_ros robot --ros-args --params-file config/lab_turtlebot3.yaml '
     '-r __ns:=/robot_1 -p use_sim_time:=true', 'wall-clock'),
    ('ros2 run formation_ros robot --ros-args --params-file config/square_4.yaml '
     '-p use_sim_time:=true', '__ns'),
    ('ros2 run formation_ros plant --ros-args --params-file config/square_4.yaml '
     '-p controller.gian:=2.0', 'unknown parameter'),
    ('ros2 run formation_ros relay --ros-args --params-file config/world_3d.yaml',
     'needs -p use_sim_time:=true'),
    ('ros2 run formation_ros relay --ros-args --params-file config/lab_holonomic.yaml '
     '-p use_sim_time:=true', 'must not wait for /clock'),
    ('ros2 run formation_ros world --ros-args --params-file config/world_3d.yaml '
     '-p use_sim_time:=true', 'must not wait for /clock'),
    ('ros2 run formation_ros plant --ros-args --params-file config/square_4.yaml '
     '-p controller.gain:=2', 'must be a double'),
    ('ros2 run formation_ros robot --ros-args -r __ns:=/robot_9 --params-file $P '
     '-p use_sim_time:=true', 'robot_id'),
    ('ros2 run formation_ros planet --ros-args --params-file config/square_4.yaml',
     'no such executable'),
])
def test_a_wrong_ros2_run_line_is_found(command, says):
    problem = ros2_run_problem(command, {'P': SHARE + 'config/square_4.yaml'})
    assert problem is not None and says in problem, problem
