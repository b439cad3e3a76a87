# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""Jump functions of Lemma 1 (core/maths/jump.py)."""

import math

from formation_ros.core.maths.jump import make_jump, PolyJump, SmoothJump
import numpy as np
import pytest
from scipy import integrate, special

A, B = 0.0, 0.5
KINDS = [PolyJump(1), PolyJump(2), PolyJump(3), PolyJump(6), SmoothJump()]


def eq5_by_quadrature(x, a, b, g):
    """Evaluate eq. (5) directly with scipy's adaptive quadrature."""
    def integrand(tau):
        return g(tau - a) * g(b - tau) if a < tau < b else 0.0
    norm = integrate.quad(integrand, a, b, epsabs=0.0, epsrel=1e-13, limit=200)[0]
    return integrate.quad(integrand, a, min(x, b), epsabs=0.0, epsrel=1e-13, limit=200)[0] / norm


@pytest.mark.parametrize('jump', KINDS, ids=repr)
def test_end_values_and_monotone(jump):
    x = np.linspace(-0.2, 0.8, 2001)
    h = jump.h(x, A, B)
    assert jump.h(np.array([A]), A, B)[0] == 0.0
    assert jump.h(np.array([B]), A, B)[0] == pytest.approx(1.0, abs=1e-15)
    assert np.all(h[x <= A] == 0.0) and np.all(h[x >= B] == pytest.approx(1.0, abs=1e-15))
    assert np.all((h >= 0.0) & (h <= 1.0))
    inside = (x > A + 0.25 * B) & (x < 0.75 * B)
    assert np.all((h[inside] > 0.0) & (h[inside] < 1.0))
    assert np.all(np.diff(h) >= 0.0)


@pytest.mark.parametrize('p', [1, 2, 3, 5, 9])
def test_poly_closed_form_matches_quadrature_and_incomplete_beta(p):
    jump = PolyJump(p)
    a, b = 0.2, 1.7
    x = np.linspace(a - 0.1, b + 0.1, 41)
    closed = jump.h(x, a, b)
    quad = np.array([eq5_by_quadrature(v, a, b, lambda y: y ** p) for v in x])
    assert np.max(np.abs(closed - quad)) < 1e-12
    beta_inc = special.betainc(p + 1, p + 1, np.clip((x - a) / (b - a), 0.0, 1.0))
    assert np.max(np.abs(closed - beta_inc)) < 1e-14


@pytest.mark.parametrize('b', [0.05, 0.5, 4.0])
def test_smooth_h_matches_direct_quadrature(b):
    jump = SmoothJump()
    x = np.linspace(0.1 * b, 0.9 * b, 17)
    direct = np.array([eq5_by_quadrature(v, 0.0, b, lambda y: math.exp(-1.0 / y)) for v in x])
    assert np.max(np.abs(jump.h(x, 0.0, b) - direct)) < 1e-10


@pytest.mark.parametrize('jump', KINDS, ids=repr)
def test_derivative_closed_form_matches_finite_differences(jump):
    x = np.linspace(0.02, 0.48, 24)
    step = 1e-6
    numeric = (jump.h(x + step, A, B) - jump.h(x - step, A, B)) / (2.0 * step)
    assert np.allclose(jump.dh(x, A, B), numeric, rtol=1e-6, atol=1e-9)


@pytest.mark.parametrize('p', [1, 2, 3, 4])
def test_poly_derivatives_continuous_to_order_p(p):
    """The derivative h' vanishes like delta**p at both ends: h, ..., h^(p) are continuous."""
    jump = PolyJump(p)
    deltas = np.array([1e-2, 1e-3]) * (B - A)
    for side in (A + deltas, B - deltas):
        values = jump.dh(side, A, B)
        slope = np.log(values[0] / values[1]) / np.log(deltas[0] / deltas[1])
        assert slope == pytest.approx(p, abs=0.02)


def kth_derivative_jumps(jump, k, spacing):
    """Largest change of the k-th derivative between grid neighbours around x = a and x = b."""
    worst = 0.0
    for centre in (A, B):
        grid = np.arange(-200, 201) * spacing + centre
        deriv = jump.dh(grid, A, B)
        for _ in range(k - 1):
            deriv = np.gradient(deriv, grid)
        worst = max(worst, float(np.max(np.abs(np.diff(deriv[5:-5])))))
    return worst


@pytest.mark.parametrize('p', [1, 2, 3, 4])
def test_poly_kth_derivative_continuous_up_to_p_and_not_beyond(p):
    """Refining the grid shrinks the jumps of h^(k) for k <= p; h^(p+1) keeps a jump."""
    jump = PolyJump(p)
    for k in range(1, p + 1):
        coarse, fine = (kth_derivative_jumps(jump, k, s) for s in (1e-4, 1e-5))
        assert fine < coarse / 5.0, (k, coarse, fine)
    coarse, fine = (kth_derivative_jumps(jump, p + 1, s) for s in (1e-4, 1e-5))
    assert fine > coarse / 2.0


def test_smooth_derivative_flatter_than_any_power():
    jump = SmoothJump()
    for delta in (1e-2, 5e-3):
        assert jump.dh(np.array([A + delta * B]), A, B)[0] < (delta * B) ** 8
        assert jump.dh(np.array([B - delta * B]), A, B)[0] < (delta * B) ** 8


@pytest.mark.parametrize('jump', KINDS, ids=repr)
def test_ratio_is_derivative_over_value(jump):
    x = np.linspace(0.01, 0.49, 30)
    assert np.allclose(jump.ratio(x, A, B), jump.dh(x, A, B) / jump.h(x, A, B), rtol=1e-9)
    ends = jump.ratio(np.array([-1.0, 0.0, B, 2.0]), A, B)
    assert ends[0] == np.inf and ends[1] == np.inf and ends[2] == 0.0 and ends[3] == 0.0


@pytest.mark.parametrize('p', [1, 2, 5])
def test_poly_ratio_exact_near_collision(p):
    """Near x = a, h'/h -> (p + 1) / (x - a), with no underflow even at 1e-300."""
    x = np.array([1e-300, 1e-100, 1e-18])
    assert np.allclose(PolyJump(p).ratio(x, 0.0, B) * x, p + 1, rtol=1e-12)


def test_smooth_ratio_finite_near_collision():
    ratio = SmoothJump().ratio(np.array([1e-18, 1e-9, 1e-4]), 0.0, B)
    assert np.all(np.isfinite(ratio)) and np.all(np.diff(ratio) < 0.0)


def test_inputs_not_modified_and_shapes_kept():
    x = np.linspace(0.0, 0.6, 12).reshape(3, 4)
    before = x.copy()
    for jump in KINDS:
        for func in (jump.h, jump.dh, jump.ratio):
            assert func(x, A, B).shape == (3, 4)
    assert np.array_equal(x, before)


def test_bad_arguments_rejected():
    with pytest.raises(ValueError, match='order'):
        PolyJump(0)
    with pytest.raises(ValueError, match='order'):
        PolyJump(2.5)
    with pytest.raises(ValueError, match='a < b'):
        PolyJump(2).h(np.array([0.1]), 0.5, 0.5)
    with pytest.raises(ValueError, match='unknown jump kind'):
        make_jump('cubic', 2)


def test_jump_kinds_are_one_enum_and_make_jump_dispatches_on_it():
    from formation_ros.core.settings.declarations import BY_NAME
    from formation_ros.core.maths.jump import JumpKind, make_jump, PolyJump, SmoothJump
    assert set(BY_NAME['jump.kind'].choices) == {kind.value for kind in JumpKind}
    for kind, cls in ((JumpKind.POLY, PolyJump), (JumpKind.SMOOTH, SmoothJump)):
        assert isinstance(make_jump(kind), cls) and isinstance(make_jump(kind.value), cls)
        assert make_jump(kind).kind is kind
    assert make_jump('poly', 3).order == 3
