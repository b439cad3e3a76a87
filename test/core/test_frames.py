# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""Moving references and the formation frame J (core/maths/reference.py, core/maths/frames.py)."""

import math
import os

from formation_ros.core.maths.frames import (_rotations, advance, desired_positions,
                                             frame_from_pose, frame_to_pose, from_frame_velocity,
                                             matrix_from_quaternion, quaternion_from_matrix,
                                             rotation_of_vector, to_frame)
from formation_ros.core.maths.reference import GERONO_LOOP_LENGTH, Reference
import numpy as np
import pytest

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

CASES = [
    ('fixed', 2), ('fixed', 3), ('line', 2), ('line', 3), ('circle', 2), ('circle', 3),
    ('figure_eight', 2), ('figure_eight', 3), ('helix', 3),
]


def make(kind, dim):
    velocity = np.array([0.4, -0.3, 0.2][:dim])
    return Reference(kind, dim, origin=np.array([1.0, -2.0, 0.5][:dim]), velocity=velocity,
                     radius=3.0, speed=0.7, pitch=2.5)


@pytest.mark.parametrize('kind,dim', CASES)
def test_frame_is_rotation_and_derivatives_match_finite_differences(kind, dim):
    reference = make(kind, dim)
    step = 1e-5
    for t in np.linspace(0.0, 17.0, 23):
        sample = reference.sample(t)
        assert np.allclose(sample.J @ sample.J.T, np.eye(dim), atol=1e-12)
        assert np.linalg.det(sample.J) == pytest.approx(1.0, abs=1e-12)
        before, after = reference.sample(t - step), reference.sample(t + step)
        assert np.allclose((after.J - before.J) / (2 * step), sample.Jdot, atol=1e-7)
        assert np.allclose((after.q_od - before.q_od) / (2 * step), sample.qdot_od, atol=1e-7)


def test_circle_starts_at_angle_zero_and_turns_counter_clockwise():
    reference = Reference('circle', 2, origin=np.array([1.0, 2.0]), radius=3.0, speed=0.6)
    start = reference.sample(0.0)
    assert np.allclose(start.q_od, [4.0, 2.0])
    assert start.qdot_od[1] > 0.0 and abs(start.qdot_od[0]) < 1e-15
    for t in (0.0, 3.0, 11.0):
        assert np.linalg.norm(reference.sample(t).qdot_od) == pytest.approx(0.6)
        assert np.linalg.norm(reference.sample(t).q_od - [1.0, 2.0]) == pytest.approx(3.0)


def test_helix_rises_by_pitch_per_turn_at_path_speed():
    reference = Reference('helix', 3, radius=2.0, speed=1.5, pitch=4.0)
    period = 2.0 * math.pi / reference.rate
    start, turn = reference.sample(0.0), reference.sample(period)
    assert np.allclose(turn.q_od - start.q_od, [0.0, 0.0, 4.0], atol=1e-12)
    assert np.linalg.norm(reference.sample(1.0).qdot_od) == pytest.approx(1.5)
    sample = reference.sample(0.7)
    tangent, normal, binormal = sample.J
    radial = (sample.q_od - [0.0, 0.0, sample.q_od[2]]) / 2.0
    assert np.allclose(tangent, sample.qdot_od / 1.5)
    assert np.allclose(normal, -radial, atol=1e-12)
    assert binormal[2] > 0.0


def test_figure_eight_mean_speed_and_crossing():
    reference = Reference('figure_eight', 2, radius=5.0, speed=0.5)
    period = 5.0 * GERONO_LOOP_LENGTH / 0.5
    assert reference.rate * period == pytest.approx(2.0 * math.pi)
    assert np.allclose(reference.sample(period / 2.0).q_od, [0.0, 0.0], atol=1e-12)


@pytest.mark.parametrize('dim', [2, 3])
def test_frame_continuous_through_inflection_points(dim):
    """At the crossing of the figure eight the curvature is zero and changes sign."""
    reference = Reference('figure_eight', dim, radius=5.0, speed=0.5)
    half = math.pi / reference.rate
    for t0 in (0.0, half):
        curvature_signs = []
        for eps in (1e-3, 1e-5):
            before, after = reference.sample(t0 - eps), reference.sample(t0 + eps)
            assert np.max(np.abs(after.J - before.J)) < 10 * eps
            curvature_signs.append(np.sign(before.Jdot[0, 1] * after.Jdot[0, 1]))
        assert all(sign < 0 for sign in curvature_signs)


@pytest.mark.parametrize('kind,dim', [('line', 3), ('fixed', 3), ('line', 2)])
def test_frame_constant_where_path_is_straight(kind, dim):
    reference = make(kind, dim)
    first = reference.sample(0.0)
    for t in (1.0, 5.0, 50.0):
        assert np.allclose(reference.sample(t).J, first.J)
        assert np.allclose(reference.sample(t).Jdot, 0.0)


def test_vertical_line_has_a_frame():
    reference = Reference('line', 3, velocity=np.array([0.0, 0.0, 2.0]))
    sample = reference.sample(1.0)
    assert np.allclose(sample.J[0], [0.0, 0.0, 1.0])
    assert np.allclose(sample.J @ sample.J.T, np.eye(3))


@pytest.mark.parametrize('kind,dim', CASES)
def test_eq25_gives_qhat_dot_equal_u_hat(kind, dim):
    """Eq. (21) along u of eq. (25) gives qhat' = u_hat (eq. 24; docs/equations.md, slip 5)."""
    reference = make(kind, dim)
    rng = np.random.default_rng(1)
    q = rng.normal(size=(4, dim)) * 3.0
    u_hat = rng.normal(size=(4, dim))
    t, step = 2.3, 1e-6
    u = from_frame_velocity(u_hat, q, reference.sample(t))
    later = to_frame(q + step * u, reference.sample(t + step))
    earlier = to_frame(q - step * u, reference.sample(t - step))
    assert np.allclose((later - earlier) / (2 * step), u_hat, atol=1e-6)


def test_desired_positions_invert_eq_20():
    reference = make('helix', 3)
    sample = reference.sample(4.0)
    vertices = np.array([[0.0, 1.0, 0.0], [1.0, 0.0, 2.0]])
    assert np.allclose(to_frame(desired_positions(vertices, sample), sample), vertices)


def test_bad_reference_rejected():
    with pytest.raises(ValueError, match='^a helix needs dim 3$'):
        Reference('helix', 2)
    with pytest.raises(ValueError, match='unknown reference kind'):
        Reference('spiral', 2)


def test_reference_kinds_are_one_enum_and_the_file_check_says_what_the_reference_says():
    from formation_ros.core.settings.declarations import BY_NAME, ParamError
    from formation_ros.core.maths.reference import ReferenceKind
    from formation_ros.core.settings.params import validate
    from formation_ros.core.settings.params_file import load_params_file
    from formation_ros.core.maths.reference import PERIODIC
    assert set(BY_NAME['reference.kind'].choices) == {kind.value for kind in ReferenceKind}
    assert Reference('circle', 2, speed=1.0).kind is ReferenceKind.CIRCLE
    assert Reference(ReferenceKind.HELIX, 3, speed=1.0).kind is ReferenceKind.HELIX
    assert set(PERIODIC) == {ReferenceKind.CIRCLE, ReferenceKind.FIGURE_EIGHT,
                             ReferenceKind.HELIX}
    for kind in ReferenceKind:
        moves = Reference(kind, 3, velocity=[1.0, 0.0, 0.0], speed=1.0)
        assert moves.rate > 0.0 if kind in PERIODIC else moves.rate == 0.0
    values = load_params_file(os.path.join(ROOT, 'config', 'circle_2d.yaml'))
    values['reference.kind'] = 'helix'
    with pytest.raises(ParamError) as refused:
        validate(values)
    with pytest.raises(ValueError) as built:
        Reference('helix', 2)
    assert "'reference.kind': helix needs dim 3" in str(refused.value)
    assert str(built.value) == 'a helix needs dim 3'


def axis_angle_matrix(axis, angle):
    """Rotation by ``angle`` about the unit ``axis``, written out (Rodrigues)."""
    n = np.asarray(axis, dtype=float)
    cross = np.array([[0.0, -n[2], n[1]], [n[2], 0.0, -n[0]], [-n[1], n[0], 0.0]])
    return (math.cos(angle) * np.eye(3) + math.sin(angle) * cross
            + (1.0 - math.cos(angle)) * np.outer(n, n))


def axis_angle_quaternion(axis, angle):
    """Quaternion (x, y, z, w) of the rotation by ``angle`` in [0, pi] about the unit ``axis``."""
    return np.append(math.sin(angle / 2.0) * np.asarray(axis, dtype=float), math.cos(angle / 2.0))


def rotation_cases():
    """Axis-angle pairs: random ones, tiny angles, and angles at and near 180 degrees."""
    rng = np.random.default_rng(7)
    axes = [np.eye(3)[k] for k in range(3)] + [v / np.linalg.norm(v)
                                               for v in rng.normal(size=(6, 3))]
    angles = [0.0, 1e-9, 0.3, 1.5, 2.5, math.pi - 1e-4, math.pi - 1e-9, math.pi]
    cases = [(axis, angle) for axis in axes for angle in angles]
    random_axes = rng.normal(size=(40, 3))
    random_angles = rng.uniform(0.0, math.pi, 40)
    cases += [(v / np.linalg.norm(v), a) for v, a in zip(random_axes, random_angles)]
    return cases


def test_quaternion_from_matrix_matches_axis_angle_with_w_non_negative():
    for axis, angle in rotation_cases():
        quat = quaternion_from_matrix(axis_angle_matrix(axis, angle))
        expected = axis_angle_quaternion(axis, angle)
        assert quat.shape == (4,) and np.linalg.norm(quat) == pytest.approx(1.0, abs=1e-14)
        assert quat[3] >= 0.0
        if angle < math.pi - 1e-6:
            assert np.allclose(quat, expected, atol=1e-12), (axis, angle)
        else:
            # at 180 degrees w is 0 and q, -q both have w >= 0
            assert min(np.max(np.abs(quat - expected)),
                       np.max(np.abs(quat + expected))) < 1e-8, (axis, angle)


def test_matrix_from_quaternion_matches_axis_angle_and_normalises():
    for axis, angle in rotation_cases():
        quat = axis_angle_quaternion(axis, angle)
        expected = axis_angle_matrix(axis, angle)
        assert np.allclose(matrix_from_quaternion(quat), expected, atol=1e-13)
        assert np.allclose(matrix_from_quaternion(-2.5 * quat), expected, atol=1e-13)


def test_quaternion_round_trip_keeps_the_rotation_and_its_input():
    for axis, angle in rotation_cases():
        matrix = axis_angle_matrix(axis, angle)
        before = matrix.copy()
        back = matrix_from_quaternion(quaternion_from_matrix(matrix))
        assert np.allclose(back, matrix, atol=1e-12), (axis, angle)
        assert np.array_equal(matrix, before)


def test_stationary_pose_is_identity_at_rest():
    for dim in (2, 3):
        position, quat, linear, angular = frame_to_pose(None, dim)
        assert np.array_equal(position, np.zeros(3)) and np.array_equal(quat, [0, 0, 0, 1.0])
        assert np.array_equal(linear, np.zeros(3)) and np.array_equal(angular, np.zeros(3))


def test_pose_of_2d_frame_is_heading_about_z():
    reference = make('figure_eight', 2)
    for t in np.linspace(0.0, 40.0, 17):
        sample = reference.sample(t)
        position, quat, linear, angular = frame_to_pose(sample, 2)
        heading = math.atan2(sample.qdot_od[1], sample.qdot_od[0])
        assert np.allclose(quat, [0.0, 0.0, math.sin(heading / 2), math.cos(heading / 2)])
        assert np.allclose(position, np.append(sample.q_od, 0.0))
        assert np.allclose(linear, np.append(sample.qdot_od, 0.0))
        step = 1e-6
        headings = [math.atan2(f.qdot_od[1], f.qdot_od[0])
                    for f in (reference.sample(t - step), reference.sample(t + step))]
        turn_rate = math.remainder(headings[1] - headings[0], 2 * math.pi) / (2 * step)
        assert np.allclose(angular, [0.0, 0.0, turn_rate], atol=1e-6)


@pytest.mark.parametrize('kind,dim', [('circle', 2), ('circle', 3), ('helix', 3)])
def test_pose_angular_velocity_of_circle_and_helix(kind, dim):
    """The frame turns about +z at the rate the path point goes round: speed / hypot(r, rise)."""
    reference = make(kind, dim)
    rise = 2.5 / (2 * math.pi) if kind == 'helix' else 0.0
    for t in (0.0, 3.3, 12.0):
        _, _, _, angular = frame_to_pose(reference.sample(t), dim)
        assert np.allclose(angular, [0.0, 0.0, 0.7 / math.hypot(3.0, rise)], atol=1e-12)


@pytest.mark.parametrize('kind,dim', CASES)
def test_pose_round_trip_gives_the_frame_back(kind, dim):
    reference = make(kind, dim)
    for t in np.linspace(0.0, 30.0, 11):
        sample = reference.sample(t)
        back = frame_from_pose(t, *frame_to_pose(sample, dim), dim)
        assert back.t == t
        for name in ('q_od', 'qdot_od', 'J', 'Jdot'):
            value, expected = getattr(back, name), getattr(sample, name)
            assert value.shape == expected.shape
            assert np.allclose(value, expected, atol=1e-12), name


def test_advance_by_nothing_returns_the_frame():
    sample = make('helix', 3).sample(2.0)
    assert advance(sample, 0.0) is sample
    assert advance(None, 0.5) is None


@pytest.mark.parametrize('kind,dim', [('fixed', 2), ('fixed', 3), ('line', 2), ('line', 3)])
def test_advance_exact_for_fixed_and_line(kind, dim):
    reference = make(kind, dim)
    for dt in (-0.7, 0.01, 2.5):
        moved, true = advance(reference.sample(1.2), dt), reference.sample(1.2 + dt)
        assert moved.t == pytest.approx(1.2 + dt, abs=1e-15)
        for name in ('q_od', 'qdot_od', 'J', 'Jdot'):
            assert np.allclose(getattr(moved, name), getattr(true, name), atol=1e-12), name


@pytest.mark.parametrize('kind,dim', [('circle', 2), ('circle', 3), ('helix', 3)])
def test_advance_circle_and_helix_exact_rotation_first_order_position(kind, dim):
    """Constant angular velocity: J exact; q_od by its tangent, error ~ |q_od''| dt**2 / 2."""
    reference = make(kind, dim)
    start = reference.sample(4.0)
    before = {name: getattr(start, name).copy() for name in ('q_od', 'qdot_od', 'J', 'Jdot')}
    acceleration = float(np.linalg.norm(reference.derivatives(4.0)[2]))
    errors = []
    for dt in (0.2, 0.1, 0.05):
        moved, true = advance(start, dt), reference.sample(4.0 + dt)
        assert np.allclose(moved.J, true.J, atol=1e-12)
        assert np.allclose(moved.Jdot, true.Jdot, atol=1e-12)
        assert np.array_equal(moved.qdot_od, start.qdot_od)
        error = float(np.linalg.norm(moved.q_od - true.q_od))
        assert error <= 0.5 * acceleration * dt ** 2 * 1.01
        errors.append(error)
    assert errors[0] / errors[1] == pytest.approx(4.0, rel=0.05)
    assert errors[1] / errors[2] == pytest.approx(4.0, rel=0.05)
    for name, value in before.items():
        assert np.array_equal(getattr(start, name), value)


@pytest.mark.parametrize('dim', [2, 3])
def test_advance_figure_eight_first_order_in_dt(dim):
    """Where the angular velocity changes, J is right to first order: its error goes as dt**2."""
    reference = make('figure_eight', dim)
    start = reference.sample(6.0)
    errors = []
    for dt in (0.04, 0.02, 0.01):
        moved, true = advance(start, dt), reference.sample(6.0 + dt)
        assert np.allclose(moved.J @ moved.J.T, np.eye(dim), atol=1e-12)
        assert np.linalg.det(moved.J) == pytest.approx(1.0, abs=1e-12)
        errors.append((float(np.max(np.abs(moved.J - true.J))),
                       float(np.linalg.norm(moved.q_od - true.q_od))))
    for coarse, fine in zip(errors, errors[1:]):
        for k in range(2):
            assert coarse[k] / fine[k] == pytest.approx(4.0, rel=0.1)


def test_rotation_of_a_vector_matches_axis_angle_down_to_tiny_angles():
    cases = rotation_cases() + [(np.array([0.0, 0.6, 0.8]), a) for a in (1e-3, 1e-5, 1e-9)]
    for axis, angle in cases:
        rotvec = axis * angle
        before = rotvec.copy()
        assert np.allclose(rotation_of_vector(rotvec), axis_angle_matrix(axis, angle),
                           atol=1e-14), (axis, angle)
        assert np.array_equal(rotvec, before)
    assert np.array_equal(rotation_of_vector(np.zeros(3)), np.eye(3))


def test_one_quaternions_matrix_has_the_bits_of_the_vectorised_one():
    rng = np.random.default_rng(5)
    quats = np.vstack([rng.normal(size=(200, 4)), [[0.0, 0.0, 0.0, 1.0], [0.0, 0.0, 0.6, 0.8]]])
    for quat in quats:
        assert np.array_equal(matrix_from_quaternion(quat), _rotations(quat)[0]), quat
