"""Exact real roots of a univariate rational polynomial: the first positive one, bracketed by Sturm's theorem.

A polynomial is a list of :class:`~fractions.Fraction` coefficients, lowest degree first. Every
decision is a count of sign changes of a Sturm sequence at rational points (Sturm's theorem: for a
square-free ``q`` and ``q(a) != 0``, the number of distinct real roots in ``(a, b]`` is
``V(a) - V(b)``), so no float enters a result: the bracket ``lo < root <= hi`` is exact.
"""

from __future__ import annotations

from fractions import Fraction
from typing import Final, Sequence

Univariate = list[Fraction]

#: bisection steps of :func:`first_positive_root` after the root is bracketed: the bracket's width is
#: then below ``2**-ROOT_BITS`` of its upper end
ROOT_BITS: Final = 40


def trim(p: Sequence[Fraction]) -> Univariate:
    """``p`` without its zero leading coefficients (``[]`` for the zero polynomial)."""
    out = list(p)
    while out and out[-1] == 0:
        out.pop()
    return out


def evaluate(p: Sequence[Fraction], x: Fraction) -> Fraction:
    value = Fraction(0)
    for c in reversed(p):
        value = value * x + c
    return value


def derivative(p: Sequence[Fraction]) -> Univariate:
    return trim([k * c for k, c in enumerate(p)][1:])


def remainder(a: Sequence[Fraction], b: Sequence[Fraction]) -> Univariate:
    """The remainder of ``a`` divided by ``b`` (``b`` not zero)."""
    r, b = trim(a), trim(b)
    while len(r) >= len(b):
        f = r[-1] / b[-1]
        shift = len(r) - len(b)
        for k, c in enumerate(b):
            r[shift + k] -= f * c
        r = trim(r[:-1])
    return r


def gcd(a: Sequence[Fraction], b: Sequence[Fraction]) -> Univariate:
    a, b = trim(a), trim(b)
    while b:
        a, b = b, remainder(a, b)
    return a


def quotient(a: Sequence[Fraction], b: Sequence[Fraction]) -> Univariate:
    """``a / b`` where ``b`` divides ``a`` exactly."""
    r, b = trim(a), trim(b)
    q = [Fraction(0)] * max(len(r) - len(b) + 1, 0)
    while len(r) >= len(b) and r:
        f = r[-1] / b[-1]
        shift = len(r) - len(b)
        q[shift] = f
        for k, c in enumerate(b):
            r[shift + k] -= f * c
        r = trim(r[:-1])
    return q


def square_free(p: Sequence[Fraction]) -> Univariate:
    """``p / gcd(p, p')``: the same distinct roots, each simple."""
    g = gcd(p, derivative(p))
    return trim(p) if len(g) <= 1 else quotient(p, g)


def sturm_sequence(p: Sequence[Fraction]) -> list[Univariate]:
    chain = [trim(p), derivative(p)]
    while chain[-1]:
        r = remainder(chain[-2], chain[-1])
        if not r:
            break
        chain.append([-c for c in r])
    return [q for q in chain if q]


def _changes(values: Sequence[Fraction]) -> int:
    signs = [v > 0 for v in values if v != 0]
    return sum(1 for a, b in zip(signs, signs[1:]) if a != b)


def sign_changes(chain: Sequence[Sequence[Fraction]], x: Fraction | None) -> int:
    """Sign changes of the chain at ``x`` (``None``: at ``+inf``, the leading coefficients' signs)."""
    return _changes([q[-1] if x is None else evaluate(q, x) for q in chain])


def first_positive_root(p: Sequence[Fraction], bits: int = ROOT_BITS) -> tuple[Fraction, Fraction] | None:
    """An exact bracket ``(lo, hi)`` of ``p``'s smallest positive real root ``rho``:
    ``0 < lo < rho <= hi`` with ``hi - lo <= hi 2**-bits``, and no root of ``p`` in ``(0, lo]``;
    None when ``p`` has no positive root. ``p(0) != 0`` is required (ValueError)."""
    q = square_free(p)
    if not q or evaluate(q, Fraction(0)) == 0:
        raise ValueError("the polynomial must not vanish at 0")
    chain = sturm_sequence(q)
    at_zero = sign_changes(chain, Fraction(0))
    if at_zero - sign_changes(chain, None) == 0:
        return None
    # Cauchy's bound: every root is below 1 + max |q_k / q_top|
    hi = 1 + max(abs(c / q[-1]) for c in q[:-1])
    lo = Fraction(0)
    while True:  # the first root is in (lo, hi]; bracket it below from 0 by halving (a root near 0)
        mid = hi / 2
        if at_zero - sign_changes(chain, mid) > 0:
            hi = mid
        else:
            lo = mid
            break
        if hi < Fraction(1, 2**200):  # (cannot happen for q(0) != 0; a guard against a loop without end)
            raise ArithmeticError("no bracket of the first positive root")
    while hi - lo > hi / 2**bits:
        mid = (lo + hi) / 2
        if at_zero - sign_changes(chain, mid) > 0:
            hi = mid
        else:
            lo = mid
    return lo, hi


__all__ = ["ROOT_BITS", "Univariate", "derivative", "evaluate", "first_positive_root", "gcd", "quotient",
           "remainder", "square_free", "sturm_sequence", "trim"]
