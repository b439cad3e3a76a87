# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""Another team on a domain (occupants.py): the one rule of the plant and the launcher."""

from formation_ros.core.rules.occupants import is_hub, occupants

OWN = '/plant'


def test_the_plant_leaves_out_itself_and_a_killed_plants_silent_clock():
    assert occupants([], [OWN], OWN) == []
    assert occupants([OWN], [OWN], OWN) == []
    assert occupants([OWN], [OWN], OWN, running=[OWN]) == [OWN]
    assert occupants([OWN], [OWN], OWN, sent_clock=True) == [OWN]
    assert occupants(['/probe'], [OWN], OWN) == ['/probe']
    assert occupants([OWN, '/probe'], [], OWN) == ['/probe']


def test_a_plant_or_relay_counts_without_a_clock():
    assert occupants([], ['/relay', '/reference', '/robot_1/robot'], OWN) == ['/relay']
    assert occupants([], ['/lab/relay', '/other/plant'], OWN) == ['/lab/relay', '/other/plant']
    assert occupants([], [OWN], OWN, running=[OWN]) == [OWN]


def test_the_launcher_runs_nothing_yet_so_every_clock_plant_and_relay_counts():
    assert occupants([], ['/probe', '/reference', '/robot_1/robot', '/fleet_1']) == []
    assert occupants([OWN], [OWN, '/reference']) == [OWN]
    assert occupants(['/probe', '/probe'], ['/probe']) == ['/probe']
    assert occupants([], ['/relay']) == ['/relay']


def test_hubs_are_named_plant_relay_or_world_in_any_namespace():
    assert is_hub('/plant') and is_hub('/lab/relay')
    assert not is_hub('/plant_2') and not is_hub('/robot_1/robot') and not is_hub('/planter')


def test_a_world_is_a_team_with_or_without_its_clock():
    assert is_hub('/world') and is_hub('/lab/world') and not is_hub('/world_2')
    assert occupants([], ['/world']) == ['/world']
    assert occupants(['/world'], ['/world', '/relay']) == ['/relay', '/world']
    assert occupants([], ['/world'], OWN) == ['/world']
