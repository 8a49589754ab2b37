"""Exact real roots of a univariate rational polynomial: the first positive one, in an exact bracket.

A polynomial is a list of :class:`~fractions.Fraction` coefficients, lowest degree first. The roots
are isolated by FLINT's ball arithmetic (python-flint's ``fmpz_poly.complex_roots``), whose balls
are rigorous; their endpoints are exact dyadic rationals, so the bracket ``lo <= root <= hi`` is
exact and no float enters a result.
"""

from __future__ import annotations

from fractions import Fraction
from typing import Any, Final, Sequence, cast

import flint

Univariate = list[Fraction]

#: the relative width of :func:`first_positive_root`'s bracket: below ``2**-ROOT_BITS`` of its upper end
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


def _exact(x: "flint.arb") -> Fraction:
    """An exact ball endpoint (an arb of radius 0: ``lower()``/``upper()``) as a Fraction."""
    mantissa, exponent = x.man_exp()
    return Fraction(int(mantissa)) * Fraction(2) ** int(exponent)


def first_positive_root(p: Sequence[Fraction], bits: int = ROOT_BITS) -> tuple[Fraction, Fraction] | None:
    """An exact bracket ``(lo, hi)`` of ``p``'s smallest positive real root ``rho``:
    ``0 < lo <= rho <= hi`` with ``hi - lo <= hi 2**-bits``, and no root of ``p`` in ``(0, lo)``;
    None when ``p`` has no positive root. ``p(0) != 0`` is required (ValueError).

    The roots are FLINT's (``arb_fmpz_poly_complex_roots``: every root in an isolating ball, the real
    ones first with an imaginary part exactly 0), of ``p`` scaled to integer coefficients; the
    working precision grows until the smallest positive root's ball is as narrow as asked."""
    q = trim(p)
    if not q or q[0] == 0:
        raise ValueError("the polynomial must not vanish at 0")
    if len(q) == 1:
        return None
    scaled = flint.fmpq_poly([flint.fmpq(c.numerator, c.denominator) for c in q])
    integer = flint.fmpz_poly([int(c * scaled.denom()) for c in scaled.coeffs()])
    prec = max(flint.ctx.prec, bits + 16)
    while True:
        saved, flint.ctx.prec = flint.ctx.prec, prec
        try:
            # (python-flint types the result as acb; it is a list of (root, multiplicity))
            roots = cast(list[tuple[Any, int]], integer.complex_roots())
        finally:
            flint.ctx.prec = saved
        real = [c.real for c, _ in roots if c.imag.is_zero()]
        if any(not (r > 0) and not (r < 0) for r in real):
            prec *= 2  # a ball around 0 (p(0) != 0: more precision decides its side)
            continue
        positive = [r for r in real if r > 0]
        if not positive:
            return None
        rho = min(positive, key=lambda r: _exact(r.lower()))
        lo, hi = _exact(rho.lower()), _exact(rho.upper())
        if hi - lo <= hi / 2 ** bits:
            return lo, hi
        prec *= 2


__all__ = ["ROOT_BITS", "Univariate", "evaluate", "first_positive_root", "trim"]
