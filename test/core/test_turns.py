# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""Bounded looks in turn (``rules.turns``): every item within ceil(n / limit) calls, no more."""

import math

from formation_ros.core.rules.turns import Turns
import pytest


def test_limit_items_a_call_in_turn_each_once_a_round():
    turns = Turns(3)
    calls = [turns.due(7) for _ in range(7)]
    assert calls[:3] == [[0, 1, 2], [3, 4, 5], [6, 0, 1]]
    assert all(len(call) == 3 for call in calls)
    flat = [i for call in calls for i in call]
    assert sorted(flat) == sorted(list(range(7)) * 3)


@pytest.mark.parametrize('n, limit', [(1, 1), (25, 10), (1000, 50), (7, 3), (10, 10)])
def test_every_item_is_looked_at_within_the_bound_from_any_start(n, limit):
    turns = Turns(limit)
    bound = math.ceil(n / limit)
    for skip in range(n):
        turns.due(n)
        seen = set()
        for _ in range(bound):
            seen.update(turns.due(n))
        assert seen == set(range(n)), (skip, bound)


def test_without_a_limit_or_with_a_large_one_every_item_every_call():
    assert Turns(None).due(5) == [0, 1, 2, 3, 4]
    large = Turns(8)
    assert large.due(5) == large.due(5) == [0, 1, 2, 3, 4]
    assert Turns(4).due(0) == []


def test_the_turn_goes_on_when_the_number_of_items_changes():
    turns = Turns(2)
    assert turns.due(5) == [0, 1]
    assert turns.due(3) == [2, 0]
    assert turns.due(6) == [1, 2]


def test_a_limit_below_one_is_refused():
    with pytest.raises(ValueError):
        Turns(0)
