# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""Property tests of the plant model: whatever the commands, what is applied stays bounded."""

from formation_ros.core.maths.frames import to_frame_velocity
from formation_ros.core.maths.law import make_law
from formation_ros.core.maths.reference import Reference
from formation_ros.core.model.plant import Commands, CommandStatus, PlantModel
from hypothesis import given, settings, strategies as st
import numpy as np

LAW = make_law(2.0, 1.0, 'arctan', 'poly', 2, 0.5)
MS = 10_000_000
ANY_FLOAT = st.one_of(st.floats(allow_nan=True, allow_infinity=True),
                      st.sampled_from([1e300, -1e300, 5e-324, -5e-324, 0.0, 3.0, -3.2]))
POSITION = st.floats(min_value=-1e6, max_value=1e6, allow_nan=False)
N = 5


@st.composite
def situations(draw):
    q = np.array(draw(st.lists(st.tuples(POSITION, POSITION), min_size=N, max_size=N)))
    if draw(st.booleans()):
        q[1] = q[0]
    u = np.array(draw(st.lists(st.tuples(ANY_FLOAT, ANY_FLOAT), min_size=N, max_size=N)))
    steps = draw(st.integers(min_value=0, max_value=8))
    offsets = draw(st.lists(st.integers(min_value=-3 * MS, max_value=2 * 10 ** 18),
                            min_size=N, max_size=N))
    present = draw(st.lists(st.booleans(), min_size=N, max_size=N))
    max_speed = draw(st.sampled_from([0.0, 0.5, 10.0]))
    return q, u, steps, offsets, present, max_speed


def run(reference, situation):
    q, u, steps, offsets, present, max_speed = situation
    plant = PlantModel(q, np.full(N, 1.0), MS, LAW, reference, 5 * MS, 1e-3, max_speed)
    for _ in range(steps):
        plant.advance(Commands.empty(N, 2))
    commands = Commands(u.copy(), plant.t_ns - np.array(offsets, dtype=np.int64),
                        np.array(present))
    before = commands.u.copy()
    report = plant.advance(commands)
    assert np.array_equal(commands.u, before, equal_nan=True)
    return plant, commands, report


@settings(max_examples=300, deadline=None)
@given(situations())
def test_applied_commands_are_finite_and_within_the_bound_fixed_reference(situation):
    plant, commands, report = run(Reference('fixed', 2), situation)
    applied = report.admission.u
    assert np.all(np.isfinite(applied)) and np.all(np.isfinite(plant.q))
    assert np.all(np.abs(applied) <= LAW.u_bound)
    max_speed = situation[5]
    if max_speed > 0.0:
        assert np.all(np.abs(applied) <= max_speed)
    zeroed = ~np.isin(report.admission.status, (CommandStatus.APPLIED, CommandStatus.SATURATED))
    assert np.all(applied[zeroed] == 0.0)
    kept = report.admission.status == CommandStatus.APPLIED
    assert np.array_equal(applied[kept], commands.u[kept])


@settings(max_examples=200, deadline=None)
@given(situations())
def test_applied_commands_are_within_the_bound_in_the_moving_frame(situation):
    circle = Reference('circle', 2, radius=3.0, speed=0.5)
    plant, commands, report = run(circle, situation)
    applied = report.admission.u
    assert np.all(np.isfinite(applied))
    frame = circle.sample(report.t_ns / 1e9)
    counted = np.isin(report.admission.status, (CommandStatus.APPLIED, CommandStatus.SATURATED))
    fresh = counted & (commands.stamp_ns == report.t_ns)
    if np.any(fresh) and situation[5] == 0.0:
        u_hat = to_frame_velocity(applied[fresh], report.q[fresh], frame)
        assert np.all(np.abs(u_hat) <= LAW.u_bound * (1.0 + 1e-9) + 1e-3)
