# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""The period a robot's answer budget expects: the plant's, the lab relay's, a world relay's."""

import os

from formation_ros.core.rules.answers import AnswerBudget
from formation_ros.core.settings.declarations import Exe
from formation_ros.core.settings.params import validate, world_robot_rates
from formation_ros.core.settings.params_file import load_params_file
import pytest

CONFIG = os.path.join(os.path.dirname(os.path.dirname(os.path.dirname(
    os.path.abspath(__file__)))), 'config')


def robot(source='square_4.yaml', **changes):
    raw = load_params_file(os.path.join(CONFIG, source))
    raw.update({'robot_id': 1}, **changes)
    settings = validate(raw, Exe.ROBOT).robot
    assert settings is not None
    return settings


def answered(period_s, state_period_s, seconds=10.0):
    """How many states, one every ``state_period_s`` s of the robot's clock, the budget takes."""
    budget = AnswerBudget(int(round(period_s * 1e9)))
    step = int(round(state_period_s * 1e9))
    return sum(budget.take(k * step) for k in range(int(round(seconds / state_period_s))))


def test_beside_a_plant_the_budget_keeps_the_plants_period():
    assert robot().answer_period(True) == pytest.approx(0.02)
    assert robot(**{'plant.publish_rate': 20.0}).answer_period(True) == pytest.approx(0.05)
    assert robot(**{'plant.lockstep': True, 'plant.rate': 200.0}).answer_period(True) == (
        pytest.approx(0.005))


def test_in_a_lab_the_budget_keeps_the_relays_wall_clock_period():
    assert robot('lab_turtlebot3.yaml').answer_period(False) == pytest.approx(0.02)
    assert robot(**{'relay.rate': 20.0,
                    'plant.publish_rate': 100.0}).answer_period(False) == pytest.approx(0.05)


@pytest.mark.parametrize('relay_rate', [20.0, 50.0, 100.0, 200.0])
def test_beside_a_world_every_relay_state_is_answered_on_simulated_time(relay_rate):
    settings = robot('world_turtlebot3.yaml', **{'relay.rate': relay_rate},
                     **dict(world_robot_rates(relay_rate)))
    period = settings.answer_period(True)
    assert period == pytest.approx(1.0 / relay_rate)
    plain = robot('world_turtlebot3.yaml', **{'relay.rate': relay_rate}).answer_period(True)
    assert plain == pytest.approx(0.02), 'without them, the plant period of the defaults'
    states = int(round(10.0 * relay_rate))
    assert answered(period, 1.0 / relay_rate) == states
    assert answered(period, 0.5 / relay_rate) < 0.6 * 2 * states + 3, 'a flood is still one'
