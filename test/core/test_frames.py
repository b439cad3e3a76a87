"""Moving references and the formation frame J (core/reference.py, core/frames.py)."""

import math

from formation_ros.core.frames import desired_positions, from_frame_velocity, to_frame
from formation_ros.core.reference import GERONO_LOOP_LENGTH, Reference
import numpy as np
import pytest

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
    with pytest.raises(ValueError, match='helix'):
        Reference('helix', 2)
    with pytest.raises(ValueError, match='unknown reference kind'):
        Reference('spiral', 2)
