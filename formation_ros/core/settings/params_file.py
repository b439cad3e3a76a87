# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
Read and write ROS 2 parameters files (YAML): the one place that knows their layout.

One standard file drives the simulator and every node::

    /**:
      ros__parameters:
        num_robots: 10
        controller:
          gain: 2.0

Nested keys are dotted names in ROS (``controller.gain``). The reader follows ROS's YAML
dialect where PyYAML (YAML 1.1) does not: ``1e-3`` is a double, as ``--params-file`` reads it.
:func:`dump_params_text` writes the inverse, so text written here reads back to the same
values (bags store their parameters this way).
"""

import os
import re
from typing import Any, Dict, Mapping, Union

from formation_ros.core.settings.declarations import ParamError
from formation_ros.core.settings.file_guard import (check_params_text, ParamsFileError,
                                                    read_params_file_text, yaml_problem)
import yaml

PathText = Union[str, 'os.PathLike[str]']
NOT_PARAMETERS = ("expected a ROS 2 parameters file with a top-level '/**:' section holding "
                  "'ros__parameters:'")

_FLOAT_PATTERN = re.compile(
    r'^(?:[-+]?[0-9][0-9_]*\.[0-9_]*(?:[eE][-+]?[0-9]+)?'
    r'|[-+]?[0-9][0-9_]*[eE][-+]?[0-9]+'
    r'|[-+]?\.[0-9_]+(?:[eE][-+]?[0-9]+)?'
    r'|[-+]?\.(?:inf|Inf|INF)'
    r'|\.(?:nan|NaN|NAN))$')


class _Loader(getattr(yaml, 'CSafeLoader', yaml.SafeLoader)):  # type: ignore[misc]
    """
    Safe YAML loader that also reads ``1e-3`` as a float.

    libyaml's parser where PyYAML has it: the pure Python one took a second for the 20,000
    numbers of a 10,000-robot formation. The resolvers (what is a float) are the same Python
    ones either way.
    """


_Loader.yaml_implicit_resolvers = {
    key: [(tag, regexp) for tag, regexp in resolvers if tag != 'tag:yaml.org,2002:float']
    for key, resolvers in yaml.SafeLoader.yaml_implicit_resolvers.items()
}
_Loader.add_implicit_resolver('tag:yaml.org,2002:float', _FLOAT_PATTERN,
                              list('-+0123456789.'))


def flatten(tree: Mapping[str, Any], prefix: str = '') -> Dict[str, Any]:
    """Nested dict -> {dotted name: value}; ``{'a': {'b': 1}}`` -> ``{'a.b': 1}``."""
    flat: Dict[str, Any] = {}
    for key, value in tree.items():
        name = f'{prefix}{key}'
        if isinstance(value, dict):
            flat.update(flatten(value, name + '.'))
        else:
            flat[name] = value
    return flat


def nest(values: Mapping[str, Any]) -> Dict[str, Any]:
    """Inverse of :func:`flatten`: {dotted name: value} -> nested dict (None values dropped)."""
    tree: Dict[str, Any] = {}
    for name, value in sorted(values.items()):
        if value is None:
            continue
        node = tree
        parts = name.split('.')
        for part in parts[:-1]:
            node = node.setdefault(part, {})
        node[parts[-1]] = list(value) if isinstance(value, (list, tuple)) else value
    return tree


def load_params_file(path: PathText) -> Dict[str, Any]:
    """
    Read a ROS 2 parameters YAML file and return the flat ``/**`` parameters.

    The file is checked before it is parsed in full (:mod:`formation_ros.core.settings.file_guard`:
    size, anchors, depth, array lengths). Raises ParamError (naming the file; a
    ParamsFileError for the file as a whole) when the file is missing or unreadable, too
    large, is empty or not YAML, or has no ``/**: ros__parameters:`` section.
    """
    return parse_params_text(read_params_file_text(path), str(path))


def parse_params_text(text: str, source: str) -> Dict[str, Any]:
    """
    Parse ROS 2 parameters YAML text (``source`` names it in errors); return flat values.

    The text passes :func:`formation_ros.core.settings.file_guard.check_params_text` first.
    """
    check_params_text(text, source)
    try:
        document = yaml.load(text, Loader=_Loader)
    except yaml.YAMLError as exc:
        mark = getattr(exc, 'problem_mark', None)
        raise ParamsFileError(source, f'cannot read it as YAML: {yaml_problem(exc)}',
                              None if mark is None else mark.line + 1) from None
    except (ValueError, RecursionError) as exc:
        reason = ' '.join(str(exc).split()) or type(exc).__name__
        raise ParamsFileError(source, f'cannot read it as YAML: {reason[:300]}') from None
    section = document.get('/**') if isinstance(document, dict) else None
    if not isinstance(section, dict) or not isinstance(section.get('ros__parameters'), dict):
        raise ParamsFileError(source, NOT_PARAMETERS)
    try:
        return flatten(section['ros__parameters'])
    except RecursionError:
        raise ParamError([(source, 'its parameters nest too deep (or contain themselves)')]) \
            from None


class _Dumper(yaml.SafeDumper):
    """Safe YAML dumper that quotes a string the reader would take for a double (``'1e3'``)."""


_Dumper.yaml_implicit_resolvers = _Loader.yaml_implicit_resolvers


def dump_params_text(values: Mapping[str, Any]) -> str:
    """Return the ROS 2 parameters YAML (``/**: ros__parameters:``) of flat dotted values."""
    return str(yaml.dump({'/**': {'ros__parameters': nest(values)}}, Dumper=_Dumper,
                         sort_keys=True))


def write_params_file(path: PathText, values: Mapping[str, Any]) -> None:
    """Write flat dotted values as a ROS 2 parameters file at ``path``."""
    with open(path, 'w', encoding='utf-8') as stream:
        stream.write(dump_params_text(values))
