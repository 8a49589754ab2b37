"""Exact positivity of a polynomial on a box by its Bernstein coefficients (issue 45, item 1).

On a box ``B = prod [lo_j, hi_j]`` a polynomial ``q`` of degree ``d_j`` in variable ``j`` is
``q(u) = sum_I b_I prod_j C(d_j, i_j) t_j^i_j (1 - t_j)^(d_j - i_j)`` with ``u_j = lo_j + (hi_j -
lo_j) t_j``, ``t in [0, 1]^m``: the Bernstein basis is non-negative and sums to 1, so ``min_I b_I <=
q <= max_I b_I`` on ``B``, and the corner coefficients are ``q``'s values at the corners (Garloff,
"Convergent bounds for the range of multivariate polynomials", 1985). So every ``b_I > 0``
proves ``q > 0`` on ``B``, exactly (rational arithmetic throughout); a corner coefficient ``<= 0`` is a
point of ``B`` where ``q <= 0``; otherwise the box is halved along its widest side and each half
tried, within :data:`MAX_BOXES` boxes. The coefficients converge to the range as the boxes shrink,
so a polynomial positive on the closed box is proved with enough boxes.
"""

from __future__ import annotations

from dataclasses import dataclass
from fractions import Fraction
from math import comb
from typing import Final, Mapping, Sequence

Exponents = tuple[int, ...]
Terms = Mapping[Exponents, Fraction]
Box = tuple[tuple[Fraction, Fraction], ...]

#: the most boxes one proof may examine (each costs one Bernstein transform)
MAX_BOXES: Final = 2048


@dataclass(frozen=True)
class Positivity:
    """The answer: ``proved`` (``q > 0`` on the whole box), the boxes examined, and a point of the
    box where ``q <= 0`` exactly (a corner of some sub-box), if one was met."""

    proved: bool
    boxes: int
    witness: tuple[Fraction, ...] | None = None


def _shift_to_unit(terms: Terms, box: Box) -> dict[Exponents, Fraction]:
    """``q(lo + (hi - lo) t)`` as terms in ``t``."""
    out: dict[Exponents, Fraction] = dict(terms)
    for j, (lo, hi) in enumerate(box):
        width = hi - lo
        nxt: dict[Exponents, Fraction] = {}
        for e, c in out.items():
            for k in range(e[j] + 1):
                coef = c * comb(e[j], k) * lo ** (e[j] - k) * width ** k
                if coef:
                    key = e[:j] + (k,) + e[j + 1:]
                    nxt[key] = nxt.get(key, Fraction(0)) + coef
        out = nxt
    return out


def bernstein_coefficients(terms: Terms, box: Box, degrees: Sequence[int]) -> dict[Exponents, Fraction]:
    """Every Bernstein coefficient of ``q`` on ``box`` (degrees ``degrees`` per variable)."""
    coeffs = _shift_to_unit(terms, box)

    def indices(j: int) -> list[Exponents]:
        if j == len(degrees):
            return [()]
        return [(i,) + rest for i in range(degrees[j] + 1) for rest in indices(j + 1)]

    everything = indices(0)
    grid = {I: coeffs.get(I, Fraction(0)) for I in everything}
    for j, d in enumerate(degrees):  # b_I = sum_{k <= i_j} C(i_j, k) / C(d, k) a_{..k..}, one variable at a time
        grid = {I: sum((Fraction(comb(I[j], k), comb(d, k)) * grid[I[:j] + (k,) + I[j + 1:]]
                        for k in range(I[j] + 1)), Fraction(0)) for I in everything}
    return grid


def positive_on_box(terms: Terms, box: Box, max_boxes: int = MAX_BOXES) -> Positivity:
    """Whether ``q > 0`` on the closed ``box`` is proved (the module docstring)."""
    m = len(box)
    degrees = [max((e[j] for e in terms), default=0) for j in range(m)]
    if not terms:
        return Positivity(False, 0, tuple(lo for lo, _ in box))  # q = 0
    pending: list[Box] = [box]
    examined = 0
    full = [hi - lo for lo, hi in box]
    while pending:
        if examined >= max_boxes:
            return Positivity(False, examined)
        sub = pending.pop()
        examined += 1
        b = bernstein_coefficients(terms, sub, degrees)
        if min(b.values()) > 0:
            continue
        for I, value in b.items():  # a corner coefficient is q's value at that corner
            if value <= 0 and all(i in (0, d) for i, d in zip(I, degrees)):
                corner = tuple(lo if i == 0 or d == 0 else hi for i, d, (lo, hi) in zip(I, degrees, sub))
                return Positivity(False, examined, corner)
        # halve along the side that is widest relative to the whole box, among variables q depends on
        j = max((k for k in range(m) if degrees[k] > 0), key=lambda k: (sub[k][1] - sub[k][0]) / full[k])
        lo, hi = sub[j]
        mid = (lo + hi) / 2
        pending.append(sub[:j] + ((lo, mid),) + sub[j + 1:])
        pending.append(sub[:j] + ((mid, hi),) + sub[j + 1:])
    return Positivity(True, examined)


__all__ = ["MAX_BOXES", "Positivity", "bernstein_coefficients", "positive_on_box"]
