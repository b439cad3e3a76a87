# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""The bounded control law (core/maths/law.py): eqs. (8)-(14), (25)."""

import math

from formation_ros.core.maths.frames import stationary_frame
from formation_ros.core.maths.law import (log_potential, make_law, potential, robot_command,
                                          team_command)
from formation_ros.core.maths.reference import Reference
import numpy as np
import pytest

LAWS = [
    make_law(2.0, 1.0, 'arctan', 'poly', 2, 1.0),
    make_law(1.5, 0.7, 'tanh', 'poly', 3, 0.8),
    make_law(2.0, 1.3, 'arctan', 'smooth', None, 1.0),
]
LAW_IDS = ['arctan-p2', 'tanh-p3', 'arctan-smooth']


def clustered(rng, n, dim, spread):
    """Random positions with several pairs closer than b (and none coincident)."""
    return rng.uniform(-spread, spread, size=(n, dim))


def numeric_gradient(func, q, step=1e-6):
    grad = np.zeros_like(q)
    for index in np.ndindex(q.shape):
        plus, minus = q.copy(), q.copy()
        plus[index] += step
        minus[index] -= step
        grad[index] = (func(plus) - func(minus)) / (2.0 * step)
    return grad


@pytest.mark.parametrize('law', LAWS, ids=LAW_IDS)
@pytest.mark.parametrize('dim', [2, 3])
def test_omega_is_gradient_of_log_potential(law, dim):
    """Omega_i = d log(phi + 1) / d q_i (eq. 12): the law descends the potential."""
    rng = np.random.default_rng(7 + dim)
    for trial in range(4):
        q = clustered(rng, 6, dim, 1.2)
        vertices = rng.uniform(-4.0, 4.0, size=(6, dim))
        radii = np.full(6, 2.0)
        omega = team_command(q, vertices, radii, law).omega
        grad = numeric_gradient(lambda x: log_potential(x, vertices, law), q)
        assert np.allclose(omega, grad, rtol=1e-5, atol=1e-6), trial


def test_omega_in_moving_frame_is_rotated_gradient():
    law = LAWS[0]
    reference = Reference('helix', 3, radius=3.0, speed=1.0, pitch=2.0)
    frame = reference.sample(1.3)
    rng = np.random.default_rng(3)
    q = frame.q_od + clustered(rng, 5, 3, 1.0)
    vertices = rng.uniform(-2.0, 2.0, size=(5, 3))
    omega_hat = team_command(q, vertices, np.full(5, 2.0), law, frame).omega
    grad_world = numeric_gradient(lambda x: log_potential(x, vertices, law, frame), q)
    assert np.allclose(omega_hat, grad_world @ frame.J.T, rtol=1e-5, atol=1e-6)


@pytest.mark.parametrize('law', LAWS, ids=LAW_IDS)
def test_command_bounded_by_c_m1_even_near_collision(law):
    rng = np.random.default_rng(11)
    bound = law.u_bound
    assert bound == pytest.approx(law.gain * (math.pi / 2 if law.psi == 'arctan' else 1.0))
    for gap in (1e-3, 1e-9, 1e-14, 0.0):
        q = clustered(rng, 8, 2, 2.0)
        q[1] = q[0] + gap * np.array([0.6, 0.8])
        q[3] = q[2] + gap * np.array([1.0, 0.0])
        command = team_command(q, rng.uniform(-9, 9, size=(8, 2)), np.full(8, 2.0), law)
        assert np.all(np.isfinite(command.u))
        assert np.max(np.abs(command.u)) <= bound
    for _ in range(200):
        q = clustered(rng, 10, 3, 3.0)
        command = team_command(q, rng.uniform(-20, 20, size=(10, 3)), np.full(10, 2.0), law)
        assert np.max(np.abs(command.u)) <= bound


def test_near_collision_pushes_robots_apart():
    law = LAWS[0]
    q = np.array([[0.0, 0.0], [1e-9, 0.0]])
    command = team_command(q, q.copy(), np.full(2, 2.0), law)
    assert command.u[0, 0] < 0.0 < command.u[1, 0]
    assert np.allclose(np.abs(command.u[:, 0]), law.u_bound, rtol=1e-6)


def test_neighbours_outside_sensing_radius_have_no_effect():
    law = make_law(2.0, 1.0, 'arctan', 'poly', 2, 1.0)
    own, vertex = np.array([0.3, -0.2]), np.array([2.0, 1.0])
    alone = robot_command(own, vertex, np.empty((0, 2)), 2.0, law).u
    far = own + np.array([[2.5, 0.0], [0.0, -7.0], [1.9, 1.9]])
    assert np.array_equal(robot_command(own, vertex, far, 2.0, law).u, alone)
    close = own + np.array([[0.7, 0.0]])
    assert not np.allclose(robot_command(own, vertex, close, 2.0, law).u, alone)
    # With R_i = 0.5 the same neighbour at 0.7 m is not sensed at all.
    assert np.array_equal(robot_command(own, vertex, close, 0.5, law).u, alone)


@pytest.mark.parametrize('law', LAWS, ids=LAW_IDS)
@pytest.mark.parametrize('kind,dim', [('fixed', 2), ('circle', 2), ('figure_eight', 3),
                                      ('helix', 3)])
def test_per_robot_and_vectorised_forms_agree(law, kind, dim):
    rng = np.random.default_rng(5)
    n = 40
    reference = Reference(kind, dim, origin=np.full(dim, 0.5), radius=4.0, speed=0.8, pitch=3.0)
    frame = reference.sample(2.1)
    q = frame.q_od + clustered(rng, n, dim, 3.0)
    vertices = rng.uniform(-5.0, 5.0, size=(n, dim))
    radii = rng.uniform(1.0, 2.5, size=n)
    team = team_command(q, vertices, radii, law, frame)
    for i in range(n):
        others = np.delete(q, i, axis=0)
        sensed = others[np.linalg.norm(others - q[i], axis=1) < 3.0]
        single = robot_command(q[i], vertices[i], sensed, radii[i], law, frame)
        assert np.max(np.abs(single.u - team.u[i])) < 1e-12
        assert np.max(np.abs(single.u_hat - team.u_hat[i])) < 1e-12


def test_stationary_frame_equals_no_frame():
    law = LAWS[0]
    rng = np.random.default_rng(2)
    q = clustered(rng, 7, 2, 1.5)
    vertices = rng.uniform(-3, 3, size=(7, 2))
    plain = team_command(q, vertices, np.full(7, 2.0), law)
    framed = team_command(q, vertices, np.full(7, 2.0), law, stationary_frame(2))
    assert np.array_equal(plain.u, framed.u)


def test_inputs_not_modified():
    law = LAWS[0]
    q = np.array([[0.0, 0.0], [0.5, 0.1], [3.0, 3.0]])
    vertices = np.array([[1.0, 0.0], [0.0, 1.0], [-1.0, 0.0]])
    radii = np.full(3, 2.0)
    copies = [q.copy(), vertices.copy(), radii.copy()]
    team_command(q, vertices, radii, law)
    robot_command(q[0], vertices[0], q[1:], 2.0, law)
    assert all(np.array_equal(a, b) for a, b in zip(copies, [q, vertices, radii]))


def test_bad_law_constants_rejected():
    with pytest.raises(ValueError, match='psi'):
        make_law(2.0, 1.0, 'sigmoid', 'poly', 2, 1.0)
    with pytest.raises(ValueError, match='gain'):
        make_law(-2.0, 1.0, 'arctan', 'poly', 2, 1.0)


def test_potential_is_zero_only_at_the_formation_and_infinite_at_collision():
    """Eqs. (8)-(11): phi = e^gamma / beta^kappa - 1 >= 0, 0 at q = q_f, +inf when q_i = q_j."""
    law = LAWS[0]
    vertices = np.array([[0.0, 0.0], [2.0, 0.0], [0.0, 2.0]])
    assert potential(vertices, vertices, law) == 0.0
    moved = vertices + np.array([[0.1, 0.0], [0.0, 0.0], [0.0, 0.0]])
    assert potential(moved, vertices, law) == pytest.approx(np.expm1(0.5 * 0.01))
    close = np.array([[0.0, 0.0], [0.3, 0.0], [0.0, 2.0]])
    assert potential(close, vertices, law) == pytest.approx(
        np.expm1(log_potential(close, vertices, law)))
    assert potential(close, vertices, law) > potential(moved, vertices, law)
    collided = np.array([[0.0, 0.0], [0.0, 0.0], [0.0, 2.0]])
    assert potential(collided, vertices, law) == np.inf


def test_team_command_with_the_callers_tree_is_the_same_command():
    from scipy.spatial import cKDTree
    rng = np.random.default_rng(11)
    q = rng.uniform(-3.0, 3.0, (60, 2))
    vertices = rng.uniform(-3.0, 3.0, (60, 2))
    radii = np.full(60, 2.0)
    law = make_law(2.0, 1.0, 'arctan', 'poly', 2, 1.0)
    alone = team_command(q, vertices, radii, law)
    shared = team_command(q, vertices, radii, law, tree=cKDTree(q))
    assert np.array_equal(alone.u, shared.u) and np.array_equal(alone.omega, shared.omega)


def test_every_psi_kind_has_its_function_and_bound_and_strings_name_them():
    from formation_ros.core.settings.declarations import BY_NAME
    from formation_ros.core.maths.law import psi, PSI_FUNCTIONS, PsiKind
    assert set(PSI_FUNCTIONS) == set(PsiKind)
    assert set(BY_NAME['controller.psi'].choices) == {kind.value for kind in PsiKind}
    omega = np.array([-1e6, -0.7, 0.0, 0.3, 1e6])
    for kind, (function, bound) in PSI_FUNCTIONS.items():
        law = make_law(2.0, 1.0, kind.value, 'poly', 2, 1.0)
        assert law.psi is kind and law.psi_bound == bound
        assert np.array_equal(psi(omega, law), function(omega))
        assert np.max(np.abs(function(omega))) <= bound
    assert make_law(2.0, 1.0, PsiKind.TANH, 'poly', 2, 1.0).psi is PsiKind.TANH
    assert (PSI_FUNCTIONS[PsiKind.ARCTAN][1], PSI_FUNCTIONS[PsiKind.TANH][1]) == (math.pi / 2,
                                                                                  1.0)
