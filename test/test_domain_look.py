# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""The launcher's look at a domain it was given, without DDS: the free shortcut and the line."""

import os
import socket

from formation_ros.tools import domain, launcher
from formation_ros.tools.launcher import refusal_line

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SQUARE = os.path.join(ROOT, 'config', 'square_4.yaml')


def test_a_domain_with_no_participant_here_needs_no_look(monkeypatch):
    monkeypatch.setattr(domain, 'participants_here', lambda number: 0)
    look = domain.TeamLook(7, {'ROS_AUTOMATIC_DISCOVERY_RANGE': 'LOCALHOST'})
    assert look.child is None
    assert look.result() == domain.TeamSeen()


def test_participants_here_counts_the_ports_bound_on_this_host():
    free = next(d for d in domain.candidates(os.getuid()) if not domain.participants_here(d))
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as first, \
            socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as third:
        first.bind(('127.0.0.1', domain.participant_ports(free)[0]))
        third.bind(('127.0.0.1', domain.participant_ports(free, 3)[2]))
        assert domain.participants_here(free) == 2


def test_the_refusal_names_what_was_found_and_what_to_do():
    seen = domain.TeamSeen(('/plant', '/relay'), ('/plant',), 0.4, False)
    line = refusal_line(42, seen, True, 'vm')
    assert '\n' not in line
    assert line.startswith('refusing to start: another team runs on ROS_DOMAIN_ID 42 '
                           '(--domain-id 42): /plant (publishes /clock), /relay on this host '
                           '(vm); nothing was started.'), line
    assert 'give another --domain-id, or leave it out and the launcher runs on a free domain' \
        in line, line
    line = refusal_line(42, seen, False, None)
    assert '(ROS_DOMAIN_ID=42 in the environment)' in line, line
    assert 'on this host or another of the subnet' in line, line
    assert 'export another ROS_DOMAIN_ID, or unset it and the launcher runs on a free' in line


class StubLook:
    """A look that found ``seen`` (an exception: raised while waiting), and was it cancelled."""

    def __init__(self, seen):
        self.seen = seen
        self.cancelled = False

    def result(self):
        if isinstance(self.seen, BaseException):
            raise self.seen
        return self.seen

    def cancel(self):
        self.cancelled = True


def run_launcher(monkeypatch, tmp_path, look, *args):
    """Run the launcher's main on a fake install with ``look`` as its look; its exit code."""
    lib = tmp_path / 'lib' / 'formation_ros'
    lib.mkdir(parents=True)
    (lib / 'plant').write_text('#!/bin/sh\n')
    (lib / 'plant').chmod(0o755)
    monkeypatch.setattr(launcher, 'look_at_domain', lambda options: look)

    def make(*arguments):
        raise AssertionError('the launcher started its run')

    return launcher.main([SQUARE, '--prefix', str(tmp_path), *args], make=make)


def test_a_team_found_is_refused_in_one_line_before_the_run_is_made(monkeypatch, tmp_path,
                                                                    capsys):
    look = StubLook(domain.TeamSeen(('/plant',), ('/plant',), 0.1, False))
    assert run_launcher(monkeypatch, tmp_path, look, '--domain-id', '42') == 2
    captured = capsys.readouterr()
    assert captured.out == ''
    (line,) = captured.err.splitlines()
    assert line.startswith('launch_formation.sh: refusing to start: another team runs on '
                           'ROS_DOMAIN_ID 42 (--domain-id 42): /plant (publishes /clock)'), line


def test_ctrl_c_during_the_look_ends_it_and_starts_nothing(monkeypatch, tmp_path, capsys):
    look = StubLook(KeyboardInterrupt())
    assert run_launcher(monkeypatch, tmp_path, look, '--domain-id', '42') == 130
    assert look.cancelled
    assert 'nothing was started' in capsys.readouterr().err


def test_a_domain_of_the_launchers_choosing_is_not_looked_at(monkeypatch, tmp_path):
    monkeypatch.delenv('ROS_DOMAIN_ID', raising=False)
    options = launcher.parse_args([SQUARE])
    assert launcher.look_at_domain(options) is None
