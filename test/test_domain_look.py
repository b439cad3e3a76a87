# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""The launcher's look at a domain it was given, without DDS: the free shortcut and the line."""

import os

from formation_ros.tools import domain
from formation_ros.tools.launcher import refusal_line


def test_a_domain_with_no_participant_here_needs_no_look():
    free = next(d for d in domain.candidates(os.getuid()) if not domain.participants_here(d))
    look = domain.TeamLook(free, {'ROS_AUTOMATIC_DISCOVERY_RANGE': 'LOCALHOST'})
    assert look.child is None
    assert look.result() == domain.TeamSeen()


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
