# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""The docs build: no warning, every page reachable, and the generated parts follow the code."""

import dataclasses
import io
import json
import os
import re
import subprocess
import sys

from formation_ros.core.settings import declarations
import pytest

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
DOCS = os.path.join(ROOT, 'docs')
sys.path.insert(0, os.path.join(DOCS, '_ext'))

import formation_docs  # noqa: E402, I100


def pages():
    """Return the name of every page of docs/ (the Markdown files, without .md)."""
    return sorted(name[:-3] for name in os.listdir(DOCS) if name.endswith('.md'))


@pytest.fixture(scope='module')
def html(tmp_path_factory):
    """Build the docs as scripts/build_docs.sh does (-W -n) and return the HTML directory."""
    out = tmp_path_factory.mktemp('docs') / 'html'
    result = subprocess.run(
        ['bash', os.path.join(ROOT, 'scripts', 'build_docs.sh'), '--python', sys.executable,
         '--out', str(out)], capture_output=True, text=True, timeout=600)
    assert result.returncode == 0, result.stdout + result.stderr
    assert result.stdout.strip().endswith(f'open {out}/index.html'), result.stdout
    return out


def test_the_docs_build_without_a_warning_and_every_page_is_built(html):
    built = sorted(name[:-5] for name in os.listdir(html) if name.endswith('.html'))
    assert set(pages()) <= set(built), set(pages()) - set(built)


def test_every_parameter_is_in_the_built_reference(html):
    with open(html / 'parameters.html', encoding='utf-8') as stream:
        text = stream.read()
    missing = [p.name for p in declarations.DECLARATIONS
               if f'<code class="docutils literal notranslate"><span class="pre">'
                  f'{p.name.replace("<", "&lt;").replace(">", "&gt;")}</span>' not in text]
    assert not missing, missing


def test_every_option_of_formation_sim_is_in_the_built_cli_page(html):
    from formation_ros.tools.sim import build_parser
    with open(html / 'cli.html', encoding='utf-8') as stream:
        text = stream.read()
    options = [o for action in build_parser()._actions for o in action.option_strings]
    assert '--sample-dt' in options
    missing = [o for o in options if f'<span class="pre">{o}</span>' not in text]
    assert not missing, missing


def sphinx_build(source, out):
    """Build ``source`` in-process with docs/conf.py and warnings as errors; return warnings."""
    from sphinx.application import Sphinx
    warnings = io.StringIO()
    app = Sphinx(str(source), DOCS, str(out), str(out / '.doctrees'), 'html',
                 status=None, warning=warnings, warningiserror=True, keep_going=True,
                 freshenv=True)
    app.build()
    return app.statuscode, warnings.getvalue()


def write_pages(folder, **pages_text):
    """Write Markdown pages NAME.md into ``folder``."""
    folder.mkdir(exist_ok=True)
    for name, text in pages_text.items():
        (folder / f'{name}.md').write_text(text)
    return folder


INDEX = '# Home\n\n```{toctree}\nreference\n```\n'


def test_a_parameter_without_a_description_fails_the_build(tmp_path, monkeypatch):
    source = write_pages(tmp_path / 'src', index=INDEX,
                         reference='# Reference\n\n```{formation-parameters}\n```\n')
    assert sphinx_build(source, tmp_path / 'good') == (0, '')
    silent = dataclasses.replace(declarations.BY_NAME['controller.gain'], description=' ')
    monkeypatch.setattr(declarations, 'DECLARATIONS', declarations.DECLARATIONS + (silent,))
    status, warnings = sphinx_build(source, tmp_path / 'bad')
    assert status != 0
    assert "parameter 'controller.gain' has no description" in warnings, warnings


def test_a_parameter_in_no_table_fails_the_build(tmp_path):
    page = ('# Reference\n\n```{formation-parameters} plant.\n```\n\n'
            '```{formation-parameters} relay.\n```\n')
    source = write_pages(tmp_path / 'src', index=INDEX, reference=page)
    status, warnings = sphinx_build(source, tmp_path / 'out')
    assert status != 0
    assert "parameter 'controller.gain' is in no parameter table" in warnings, warnings
    assert "'plant.rate' is in no" not in warnings and "'relay.rate' is in no" not in warnings


def test_a_parameter_group_is_its_prefix_or_its_name():
    chosen = formation_docs.select_parameters(declarations.DECLARATIONS, ['dim', 'jump.'])
    assert [p.name for p in chosen] == ['dim', 'jump.kind', 'jump.order']
    with pytest.raises(formation_docs.DocsError, match='nothing.'):
        formation_docs.select_parameters(declarations.DECLARATIONS, ['nothing.'])


@pytest.mark.parametrize('page, says', [
    ('# Reference\n\nSee [the lab](lab.md).\n', 'lab'),
    ('# Reference\n\nSee [the lab](#no-such-heading).\n', 'no-such-heading'),
    ('# Reference\n\n```{formation-topics}\n/clock: the time\n```\n', '/robot_<i>/pose'),
    ('# Reference\n\n```{formation-bench} nothing\n```\n', 'nothing'),
])
def test_a_broken_reference_fails_the_build(tmp_path, page, says):
    source = write_pages(tmp_path / 'src', index=INDEX, reference=page)
    status, warnings = sphinx_build(source, tmp_path / 'out')
    assert status != 0 and says in warnings, warnings


def test_a_page_outside_every_toctree_fails_the_build(tmp_path):
    source = write_pages(tmp_path / 'src', index=INDEX, reference='# Reference\n',
                         orphan='# Nobody links here\n')
    status, warnings = sphinx_build(source, tmp_path / 'out')
    assert status != 0 and "document isn't included in any toctree" in warnings, warnings


def test_the_parameter_table_has_one_row_per_declaration_with_its_range_and_default():
    lines = formation_docs.parameter_markdown(declarations.DECLARATIONS)
    rows = lines[2:]
    assert len(rows) == len(declarations.DECLARATIONS)
    gain = next(row for row in rows if row.startswith('| `controller.gain` |'))
    assert gain == ('| `controller.gain` | double | `2.0` | > 0, <= 1e+06 | all | '
                    'Gain c of eq. (14), m/s. |')
    robot_id = next(row for row in rows if row.startswith('| `robot_id` |'))
    assert '| required | >= 1 | robot, fleet |' in robot_id
    assert formation_docs.parameter_problems(declarations.DECLARATIONS) == []


def test_the_topic_table_names_every_topic_with_its_qos():
    table, problems = formation_docs.topic_markdown({'/clock': 'the time', '/nowhere': 'x'})
    assert "'/nowhere' is described but is no topic of ros/topics.py" in problems
    assert "topic '/robot_<i>/cmd_vel' (ros/topics.py) has no description" in problems
    cmd_vel = next(row for row in table if row.startswith('| `/robot_<i>/cmd_vel` |'))
    assert ('reliable, keep last 10, volatile, liveliness lease 1 s kept by the messages'
            in cmd_vel)
    clock = next(row for row in table if row.startswith('| `/clock` |'))
    assert clock == ('| `/clock` | `rosgraph_msgs/msg/Clock` | reliable, keep last 1, volatile '
                     '| the time |')


def test_the_capacity_table_has_every_row_of_the_json_files():
    lines = formation_docs.bench_capacity()
    rows = [line for line in lines if re.match(r'\| (lockstep )?(process|fleet)( -ps)? \|', line)]
    expected = []
    for name in formation_docs.BENCH_FILES['capacity']:
        with open(os.path.join(DOCS, 'bench', name), encoding='utf-8') as stream:
            expected += json.load(stream)['rows']
    assert len(rows) == len(expected)
    first = expected[0]
    assert f"{100.0 * first['fresh_fraction']:.1f}" in rows[0].split('|')[7]


def test_the_robustness_limits_are_those_of_the_sweeps():
    with open(os.path.join(DOCS, 'bench', 'robustness.json'), encoding='utf-8') as stream:
        data = json.load(stream)
    rows = data['sweeps']['delay']['rows']
    held = [r['value'] for r in rows if r['config'] == 'section5' and r['summary']['held']]
    broke = [r['value'] for r in rows if r['config'] == 'section5' and not r['summary']['held']]
    line = next(line for line in formation_docs.robustness_limits(data)
                if line.startswith('| delay'))
    assert f'held through {max(v for v in held if v < min(broke))}; first below at ' \
           f'{min(broke)}' in line.split(' | ')[1]
