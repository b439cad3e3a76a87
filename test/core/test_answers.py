# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""The answer budget bounds a robot's answers in every window; duplicates are due as promised."""

from formation_ros.core.rules.answers import AnswerBudget, BURST, RATE_MARGIN
from formation_ros.core.settings.team import duplicate_due, DUPLICATE_GRACE
import numpy as np

PERIOD_NS = 20_000_000


def accepted_times(arrivals_ns):
    budget = AnswerBudget(PERIOD_NS)
    return np.array([t for t in arrivals_ns if budget.take(int(t))], dtype=np.int64)


def test_a_flood_is_answered_at_most_the_state_rate_in_every_window():
    rng = np.random.default_rng(3)
    arrivals = np.sort(rng.integers(0, 10 ** 10, 5000))
    answered = accepted_times(arrivals)
    for width in (PERIOD_NS, 10 * PERIOD_NS, 10 ** 9, 10 ** 10):
        for start in answered:
            inside = np.count_nonzero((answered >= start) & (answered < start + width))
            assert inside <= (1 + RATE_MARGIN) * width / PERIOD_NS + BURST, (width, inside)
    assert len(answered) >= 10 ** 10 / PERIOD_NS


def test_states_at_the_state_rate_with_jitter_are_all_answered():
    rng = np.random.default_rng(5)
    jitter = rng.integers(-PERIOD_NS // 2, PERIOD_NS // 2, 2000)
    arrivals = np.arange(1, 2001) * PERIOD_NS + jitter
    assert len(accepted_times(np.sort(arrivals))) == 2000


def test_a_clock_that_goes_back_neither_fails_nor_refills():
    budget = AnswerBudget(PERIOD_NS)
    assert all(budget.take(10 ** 12) for _ in range(int(BURST)))
    assert not budget.take(10 ** 12)
    assert not budget.take(0)
    assert budget.take(2 * PERIOD_NS)


def test_a_second_publisher_is_due_at_once_unless_it_has_the_expected_name():
    assert not duplicate_due(['/plant'], '/plant', 100.0)
    assert duplicate_due(['/plant', '/probe'], '/plant', 0.0)
    assert duplicate_due(['/probe', '/robot_1/robot'], None, 0.0)
    assert not duplicate_due(['/plant', '/plant'], '/plant', DUPLICATE_GRACE - 1.0)
    assert duplicate_due(['/plant', '/plant'], '/plant', DUPLICATE_GRACE)
    assert duplicate_due(['/plant', '/plant'], '/plant', 0.0, alive=True)
