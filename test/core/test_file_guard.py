# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""The parameters-file guard (file_guard.py): what it refuses, where, and what it lets by."""

import glob
import os

from formation_ros.core.settings.declarations import ParamError
from formation_ros.core.settings.file_guard import (array_limit, check_params_text, FileLimits,
                                                    MAX_DEPTH, MAX_FILE_BYTES, MAX_VALUES,
                                                    MIN_ARRAY_VALUES, ParamsFileError,
                                                    read_params_file_text)
from formation_ros.core.settings.params_file import (_Loader, flatten, load_params_file, nest,
                                                     parse_params_text, write_params_file)
import numpy as np
import pytest
import yaml

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
CONFIGS = sorted(glob.glob(os.path.join(ROOT, 'config', '*.yaml')))
HEADER = '/**:\n  ros__parameters:\n'
LIBYAML_WORDS = ('did not find', 'while parsing', 'while scanning', 'expected <', 'parse.c',
                 'libyaml', 'rcl')


def refused(text, limits=FileLimits()):
    with pytest.raises(ParamsFileError) as caught:
        check_params_text(text, 'robots.yaml', limits)
    summary = caught.value.summary
    assert '\n' not in summary and summary.startswith('robots.yaml')
    assert not any(word in summary for word in LIBYAML_WORDS), summary
    return caught.value


def scalars(tree):
    """Count a document's scalars by walking it: each key, each item, each leaf value."""
    if isinstance(tree, dict):
        return sum(1 + scalars(value) for value in tree.values())
    if isinstance(tree, list):
        return sum(scalars(item) for item in tree)
    return 1


def flow_list(count):
    return '[' + ', '.join(['0.5'] * count) + ']'


@pytest.mark.parametrize('path', CONFIGS, ids=os.path.basename)
def test_shipped_configs_read_as_the_plain_loader_reads_them(path):
    with open(path, encoding='utf-8') as stream:
        document = yaml.load(stream.read(), Loader=_Loader)
    assert load_params_file(path) == flatten(document['/**']['ros__parameters'])


def test_a_10000_robot_3d_file_passes_well_within_the_limits(tmp_path):
    rng = np.random.default_rng(3)
    n = 10_000
    values = {'num_robots': n, 'dim': 3, 'sensing_radius': 2.0, 'repulsion_radius': 0.5,
              'formation.vertices': rng.normal(size=3 * n).tolist(),
              'start.positions': rng.normal(size=3 * n).tolist(),
              'sensing_radii': rng.uniform(1.0, 2.0, size=n).tolist(),
              'relay.source_names': [f'turtle_{i}' for i in range(n)]}
    path = tmp_path / 'big.yaml'
    write_params_file(str(path), values)
    text = path.read_text()
    assert os.path.getsize(path) * 3 < MAX_FILE_BYTES
    shape = check_params_text(text, str(path))
    assert (shape.root, shape.num_robots, shape.dim) == ('mapping', n, 3)
    assert shape.longest_array == 3 * n
    assert shape.values == scalars({'/**': {'ros__parameters': nest(values)}})
    assert shape.values * 4 < MAX_VALUES
    assert load_params_file(str(path)) == values


def test_array_limit_grows_with_the_team_within_the_declared_range():
    assert array_limit(4, 2) == MIN_ARRAY_VALUES
    assert array_limit(10_000, 3) == 30_000
    assert array_limit(10 ** 9, 7) == 300_000
    assert array_limit(None, None) == MIN_ARRAY_VALUES
    assert array_limit(50, 3, FileLimits(min_array_values=10)) == 150


@pytest.mark.parametrize('team_first', [True, False])
def test_an_array_longer_than_the_team_allows_is_refused_with_its_line(team_first):
    limits = FileLimits(min_array_values=10)
    team = '    num_robots: 4\n    dim: 3\n'
    for items in (12, 13):
        array = '    formation:\n      vertices:\n' + '      - 0.5\n' * items
        text = HEADER + (team + array if team_first else array + team)
        if items == 12:
            assert check_params_text(text, 'robots.yaml', limits).longest_array == 12
            continue
        error = refused(text, limits)
        assert 'formation.vertices has more than 12 values: 12 is the most' in error.summary
        assert 'num_robots 4, dim 3' in error.summary
        first_item = text.splitlines().index('      - 0.5') + 1
        assert error.line == first_item


def test_num_robots_only_in_flow_style_is_still_the_final_limit():
    limits = FileLimits(min_array_values=10)
    text = HEADER + '    vertices: ' + flow_list(13) + '\n    {num_robots: 4, dim: 3}: 1\n'
    refused(text, limits)
    text = HEADER + '    vertices: ' + flow_list(13) + '\n    other: {num_robots: 4}\n'
    error = refused(text, limits)
    assert 'vertices has 13 values' in error.summary and 'without num_robots' in error.summary


def test_num_robots_in_a_node_section_sets_the_limit_too():
    limits = FileLimits(min_array_values=10)
    text = ('plant:\n  ros__parameters:\n    num_robots: 5\n    dim: 2\n'
            '    formation:\n      vertices: ' + flow_list(10) + '\n')
    assert check_params_text(text, 'robots.yaml', limits).num_robots == 5
    longer = text.replace(flow_list(10), flow_list(11))
    assert 'has more than 10 values' in refused(longer, limits).summary


@pytest.mark.parametrize('text,line,word', [
    (HEADER + '    gain: &g 2.0\n    kappa: *g\n', 3, '&g'),
    (HEADER + '    num_robots: 4\n    lol:\n      a: &a [x, x]\n      b: [*a, *a]\n', 5, '&a'),
    ('a: 1\nb: *nothing\n', 2, '*nothing'),
    (HEADER + '    base: &b {x: 1}\n    other:\n      <<: *b\n', 3, '&b'),
])
def test_anchors_and_aliases_are_refused_at_their_line(text, line, word):
    error = refused(text)
    assert error.line == line and word in error.summary and 'not allowed' in error.summary


def test_nesting_is_refused_one_level_beyond_the_limit():
    def nested(levels):
        return HEADER + '    junk: ' + '[' * levels + ']' * levels + '\n'
    # The document's mapping, '/**' and 'ros__parameters' are three levels.
    assert check_params_text(nested(MAX_DEPTH - 3), 'robots.yaml').root == 'mapping'
    error = refused(nested(MAX_DEPTH - 2))
    assert error.line == 3 and f'nested more than {MAX_DEPTH} levels' in error.summary
    assert 'nested more than' in refused(nested(200_000)).summary


def test_values_in_all_are_bounded():
    limits = FileLimits(max_values=102)
    lists = ''.join(f'    a{k}: {flow_list(9)}\n' for k in range(10))
    assert check_params_text(HEADER + lists, 'robots.yaml', limits).values == 102
    error = refused(HEADER + lists + '    one_more: 1\n', limits)
    assert 'more than 102 values in all' in error.summary and error.line == 13


def test_a_file_too_large_is_refused_before_it_is_read(tmp_path):
    limits = FileLimits(max_bytes=1000)
    path = tmp_path / 'big.yaml'
    path.write_text(HEADER + '    x: ' + 'y' * 1000 + '\n')
    with pytest.raises(ParamsFileError, match='larger than'):
        read_params_file_text(str(path), limits)
    path.write_text(HEADER + '    x: y\n')
    assert read_params_file_text(str(path), limits) == HEADER + '    x: y\n'
    with pytest.raises(ParamsFileError, match='larger than'):
        read_params_file_text('/dev/zero', limits)
    with pytest.raises(ParamsFileError, match='larger than'):
        check_params_text(HEADER + '    x: ' + 'y' * 1000 + '\n', 'big.yaml', limits)


def test_missing_unreadable_and_binary_files_are_one_line(tmp_path):
    with pytest.raises(ParamsFileError, match='file not found'):
        read_params_file_text(str(tmp_path / 'none.yaml'))
    with pytest.raises(ParamsFileError, match='cannot read it'):
        read_params_file_text(str(tmp_path))
    path = tmp_path / 'binary.yaml'
    path.write_bytes(b'a: 1\nb: \xff\xfe\n')
    with pytest.raises(ParamsFileError, match='not UTF-8') as caught:
        read_params_file_text(str(path))
    assert caught.value.line == 2


def test_windows_line_ends_read_as_before(tmp_path):
    path = tmp_path / 'crlf.yaml'
    path.write_bytes(b'/**:\r\n  ros__parameters:\r\n    name: "a\r\n      b"\r\n    x: 1\r\n')
    with open(path, encoding='utf-8') as stream:
        before = flatten(yaml.load(stream.read(), Loader=_Loader)['/**']['ros__parameters'])
    assert load_params_file(str(path)) == before == {'name': 'a b', 'x': 1}


@pytest.mark.parametrize('text,line,words', [
    (HEADER + '    [a, b]: 1\n', 3, 'a sequence cannot be a key'),
    (HEADER + '    ? {a: 1}\n    : 2\n', 3, 'a mapping cannot be a key'),
    (HEADER + '    num_robots: [4\n    dim: 2\n', 4, "'[' list is not closed"),
    (HEADER + '    x: {a: 1\n', 4, "'{' mapping is not closed"),
    (HEADER + '\tnum_robots: 4\n', 3, 'cannot start a value'),
    (HEADER + '    a: b: c\n', 3, "a ':' where no mapping can start"),
    (HEADER + '    a: "abc\n', 4, 'ends inside a quoted string'),
    (HEADER + '    a: 1\n---\nb: 2\n', 4, 'more than one YAML document'),
    (HEADER + '    a: 1\n   b: 2\n', 4, 'cannot read it as YAML'),
    (HEADER + '    a: "\\q"\n', 3, 'unknown escape'),
    ('a: \x07\n', 1, 'cannot read it as YAML'),
])
def test_yaml_errors_are_said_in_our_words_with_the_line(text, line, words):
    error = refused(text)
    assert words in error.summary and error.line == line
    assert isinstance(error, ParamError)
    assert str(error).startswith("parameter 'robots.yaml': line ")


def test_the_loader_refuses_what_the_guard_refuses():
    with pytest.raises(ParamsFileError, match='anchors are not allowed'):
        parse_params_text(HEADER + '    a: &x 1\n    b: *x\n', 'robots.yaml')
    with pytest.raises(ParamsFileError) as caught:
        parse_params_text('- a list\n', 'robots.yaml')
    assert "'/**:'" in caught.value.summary


def test_what_only_the_full_parse_finds_is_one_line_in_our_words_too():
    with pytest.raises(ParamsFileError) as caught:
        parse_params_text(HEADER + '    a: !!python/object:os.system 1\n', 'robots.yaml')
    assert caught.value.summary == ("robots.yaml line 3: cannot read it as YAML: an unknown '!' "
                                    'tag (column 8)')
