# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
Jump functions of Lemma 1 (eqs. 5-7) and the collision terms built from them (eq. 11).

A jump function ``h(x, a, b)`` is 0 for ``x <= a``, 1 for ``x >= b``, smooth in between.
The controller only ever needs it at ``a = 0``, ``b = b_ij**2 / 2`` and ``x = ||q_ij||**2 / 2``
(eq. 11 read as in docs/equations.md, slip 1), but the functions here take any ``0 <= a < b``.

Two kinds of ``g`` (eq. 7) are implemented:

* ``PolyJump(p)``: ``g(y) = y**p`` for an integer ``p >= 1``. Then ``h`` is the regularized
  incomplete beta function ``I_t(p + 1, p + 1)`` with ``t = (x - a) / (b - a)``
  (docs/equations.md, slip 4), written here as the finite binomial sum ``t**(p+1) * S(t)`` so
  that ``h'/h`` stays exact as ``t -> 0``.
* ``SmoothJump()``: ``g(y) = exp(-1/y)`` (Corollary 1). ``h`` needs an integral, evaluated by
  adaptive quadrature (``scipy.integrate.quad``, relative tolerance 1e-13) in a scaled form that
  cannot underflow; ``h'`` is closed form.

All functions are vectorised over ``x`` (any shape), never modify their inputs and return float
arrays of the shape of ``x``. Units: ``x``, ``a``, ``b`` in m**2 (half squared distances); ``h`` is
dimensionless; ``h'`` and ``h'/h`` are in 1/m**2.
"""

from functools import lru_cache
import math
from typing import Optional, Protocol, Union

from formation_ros.core.maths.choice import Choice
import numpy as np
from numpy.typing import ArrayLike, NDArray


class JumpKind(Choice):
    """Jump function of Lemma 1: ``jump.kind``."""

    POLY = 'poly'
    SMOOTH = 'smooth'


class JumpFunction(Protocol):
    """What the control law needs of a jump function: ``h``, ``dh`` and ``ratio`` (eqs. 5, 13)."""

    @property
    def kind(self) -> JumpKind:
        """Tell which function it is (``jump.kind``)."""

    @property
    def order(self) -> Optional[int]:
        """Return p of ``g(y) = y**p``; None for the smooth kind."""

    def h(self, x: ArrayLike, a: float, b: float) -> NDArray[np.float64]:
        """Evaluate the jump function of eq. (5) at x: shape of ``x``, values in [0, 1]."""

    def dh(self, x: ArrayLike, a: float, b: float) -> NDArray[np.float64]:
        """Evaluate dh/dx in 1/m**2, shape of ``x``."""

    def ratio(self, x: ArrayLike, a: float, b: float) -> NDArray[np.float64]:
        """Evaluate h'/h in 1/m**2, shape of ``x``; +inf for x <= a, 0 for x >= b."""


def _check_interval(a: float, b: float) -> None:
    if not (0.0 <= a < b):
        raise ValueError(f'jump function needs 0 <= a < b, got a={a!r}, b={b!r}')


class PolyJump:
    """Jump function of Lemma 1 with ``g(y) = y**p`` (docs/equations.md, slip 4)."""

    kind = JumpKind.POLY

    def __init__(self, order: int) -> None:
        """Build the jump function of order ``order`` (integer p >= 1)."""
        if isinstance(order, bool) or int(order) != order or order < 1:
            raise ValueError(f'jump order p must be an integer >= 1, got {order!r}')
        self.order = int(order)
        p = self.order
        n = 2 * p + 1
        # S(t) = sum_{k=0}^{p} C(n, p+1+k) t^k (1-t)^(p-k), so that h = t^(p+1) S(t).
        self._binomials = [float(math.comb(n, p + 1 + k)) for k in range(p + 1)]
        self._inv_beta = math.factorial(n) / math.factorial(p) ** 2  # 1 / B(p + 1, p + 1)

    def __repr__(self) -> str:
        """Return a short description."""
        return f'PolyJump(order={self.order})'

    def _sum_s(self, t: NDArray[np.float64]) -> NDArray[np.float64]:
        """
        S(t) by Horner's rule in t and 1 - t, t in [0, 1]: p steps of sums of positive terms.

        total_k = total_{k+1} t + C(n, p+1+k) (1-t)^(p-k), from k = p - 1 down to 0.
        """
        s = 1.0 - t
        s_power = s
        total: NDArray[np.float64] = np.full_like(t, self._binomials[-1])
        for k in range(self.order - 1, -1, -1):
            total = total * t + self._binomials[k] * s_power
            if k:
                s_power = s_power * s
        return total

    def h(self, x: ArrayLike, a: float, b: float) -> NDArray[np.float64]:
        """Evaluate the jump function of eq. (5) at x: shape of ``x``, values in [0, 1]."""
        _check_interval(a, b)
        t = np.clip((np.asarray(x, dtype=float) - a) / (b - a), 0.0, 1.0)
        return t ** (self.order + 1) * self._sum_s(t)

    def dh(self, x: ArrayLike, a: float, b: float) -> NDArray[np.float64]:
        """Closed-form dh/dx (docs/equations.md, slip 4), in 1/m**2; zero outside (a, b)."""
        _check_interval(a, b)
        x = np.asarray(x, dtype=float)
        p = self.order
        inside = (x > a) & (x < b)
        xc = np.where(inside, x, a)
        value = (xc - a) ** p * (b - xc) ** p * self._inv_beta / (b - a) ** (2 * p + 1)
        return np.where(inside, value, 0.0)

    def ratio(self, x: ArrayLike, a: float, b: float) -> NDArray[np.float64]:
        """
        Return betabar' = h'(x) / h(x) (eq. 13), in 1/m**2.

        Zero for ``x >= b``; ``+inf`` for ``x <= a`` (a collision). Near ``a`` it behaves like
        ``(p + 1) / (x - a)`` and is computed without forming the two tiny factors.
        """
        _check_interval(a, b)
        x = np.asarray(x, dtype=float)
        t = (x - a) / (b - a)
        inside = (t > 0.0) & (t < 1.0)
        every = bool(np.all(inside))
        tc = t if every else np.where(inside, t, 0.5)
        value = (1.0 - tc) ** self.order * self._inv_beta / ((b - a) * tc * self._sum_s(tc))
        if every:
            return np.asarray(value)
        return np.where(inside, value, np.where(t <= 0.0, np.inf, 0.0))


class SmoothJump:
    """
    Smooth jump function with ``g(y) = exp(-1/y)`` (Corollary 1).

    With ``L = b - a``, ``s = (x - a) / L`` and ``Phi(s) = (1/L) / (s (1 - s))`` the integrand of
    eq. (5) is ``exp(-Phi(s))``. The code evaluates, for ``s <= 1/2``,
    ``K(s) = int_0^s exp(Phi(s) - Phi(sigma)) d sigma`` (an integrand in [0, 1], so nothing
    underflows) and writes ``h = exp(Phi(1/2) - Phi(s)) K(s) / (2 K(1/2))``,
    ``h'/h = 1 / (L K(s))``; for ``s > 1/2`` it uses the symmetry ``h(s) = 1 - h(1 - s)``.
    """

    kind = JumpKind.SMOOTH
    order = None

    def __repr__(self) -> str:
        """Return a short description."""
        return 'SmoothJump()'

    @staticmethod
    @lru_cache(maxsize=4096)
    def _k_scaled(s: float, inv_len: float) -> float:
        """
        K(s) for 0 < s <= 1/2 with Phi built from ``inv_len = 1 / (b - a)``.

        For s < 0.3 the integral is taken in ``w = Phi(sigma) - Phi(s)`` on [0, inf), where it
        reads ``int exp(-w) k / ((1 - 2 sigma) P**2) dw`` with ``P = Phi(s) + w``, ``k = 1/L``:
        smooth, with no boundary layer however small s is. Nearer 1/2 it is taken directly.
        """
        from scipy import integrate  # only the smooth kind integrates; robots need not load it
        k = inv_len
        phi_s = k / (s * (1.0 - s))
        if s < 0.3:
            def integrand_in_w(w: float) -> float:
                big_p = phi_s + w
                return math.exp(-w) * k / (math.sqrt(1.0 - 4.0 * k / big_p) * big_p * big_p)

            value, _ = integrate.quad(integrand_in_w, 0.0, math.inf, epsabs=0.0, epsrel=1e-13,
                                      limit=400)
            return float(value)

        def integrand_in_sigma(sigma: float) -> float:
            if sigma <= 0.0:
                return 0.0
            return math.exp(phi_s - k / (sigma * (1.0 - sigma)))

        width = s * s * (1.0 - s) ** 2 / (k * max(1.0 - 2.0 * s, 1e-300))
        points = [s - width] if width < 0.1 * s else None
        value, _ = integrate.quad(integrand_in_sigma, 0.0, s, epsabs=0.0, epsrel=1e-13, limit=400,
                                  points=points)
        return float(value)

    def _scaled(self, x: ArrayLike, a: float, b: float) -> tuple[
            NDArray[np.float64], NDArray[np.bool_], NDArray[np.float64], NDArray[np.float64],
            float, float]:
        """Return s, the mask 0 < s < 1, s clipped inside, Phi(1/2) - Phi(s), 1/L, K(1/2)."""
        _check_interval(a, b)
        inv_len = 1.0 / (b - a)
        s = (np.asarray(x, dtype=float) - a) * inv_len
        inside = (s > 0.0) & (s < 1.0)
        sc = np.where(inside, s, 0.5)
        log_f_rel = 4.0 * inv_len - inv_len / (sc * (1.0 - sc))
        return s, inside, sc, log_f_rel, inv_len, self._k_scaled(0.5, inv_len)

    def _k_near(self, sc: NDArray[np.float64], inv_len: float) -> NDArray[np.float64]:
        """K(min(s, 1 - s)) element by element, same shape as ``sc``."""
        near = np.minimum(sc, 1.0 - sc)
        values = [self._k_scaled(float(v), inv_len) for v in near.ravel()]
        return np.array(values, dtype=float).reshape(near.shape)

    def h(self, x: ArrayLike, a: float, b: float) -> NDArray[np.float64]:
        """Evaluate the jump function of eq. (5) at x: shape of ``x``, values in [0, 1]."""
        s, inside, sc, log_f_rel, inv_len, k_half = self._scaled(x, a, b)
        tail = np.exp(log_f_rel) * self._k_near(sc, inv_len) / (2.0 * k_half)
        value = np.where(sc <= 0.5, tail, 1.0 - tail)
        return np.where(inside, value, np.where(s <= 0.0, 0.0, 1.0))

    def dh(self, x: ArrayLike, a: float, b: float) -> NDArray[np.float64]:
        """Closed-form derivative dh/dx = f(x - a) f(b - x) / norm, in 1/m**2."""
        _, inside, _, log_f_rel, inv_len, k_half = self._scaled(x, a, b)
        return np.where(inside, np.exp(log_f_rel) * inv_len / (2.0 * k_half), 0.0)

    def ratio(self, x: ArrayLike, a: float, b: float) -> NDArray[np.float64]:
        """Return betabar' = h'(x) / h(x) (eq. 13), in 1/m**2; 0 for x >= b, +inf for x <= a."""
        s, inside, sc, log_f_rel, inv_len, k_half = self._scaled(x, a, b)
        k_near = self._k_near(sc, inv_len)
        tail = np.exp(log_f_rel) * k_near / (2.0 * k_half)
        high = np.exp(log_f_rel) * inv_len / (2.0 * k_half) / np.maximum(1.0 - tail, 1e-300)
        value = np.where(sc <= 0.5, inv_len / k_near, high)
        return np.where(inside, value, np.where(s <= 0.0, np.inf, 0.0))


def make_jump(kind: Union[JumpKind, str], order: int = 2) -> JumpFunction:
    """Return the jump function of kind ``jump.kind`` and order ``jump.order`` (poly only)."""
    try:
        kind = JumpKind(kind)
    except ValueError:
        raise ValueError(f'unknown jump kind {kind!r}; expected one of '
                         f'{[str(member) for member in JumpKind]}') from None
    if kind is JumpKind.SMOOTH:
        return SmoothJump()
    return PolyJump(order)
