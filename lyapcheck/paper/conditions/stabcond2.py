"""eq. ``eq:stabCond2``: the paper's simplified inequalities, in plain exact arithmetic.

The inequalities are decided on exact rationals at any scale: ``holds`` or ``fails``, never
``inconclusive``. Only the floating-point *view* of the left-hand side (``lhs_value``) can be
out of range; it is then ``None`` and ``lhs_exact`` still carries the number.
"""

from __future__ import annotations

from fractions import Fraction

from lyapcheck.paper.claims import significant  # noqa: F401 (where it was; claims writes the sentences)
from lyapcheck.results import ConditionResult


def float_or_none(value: Fraction) -> float | None:
    """``float(value)``, or ``None`` when it is beyond the largest double (no overflow)."""
    try:
        return float(value)
    except OverflowError:
        return None


def run(alpha_d: Fraction, sigma0: Fraction, k_d: Fraction, delta: Fraction,
        printed_ges_status: str) -> ConditionResult:
    """Evaluate eq. ``eq:stabCond2`` exactly (SI values) and say whether it implied eq. ``eq:stabCond``.

    The paper derived eq. ``eq:stabCond2`` for its printed ``A``; whether it implies
    eq. ``eq:stabCond`` at this gain set is read from ``prop41_ges`` on the printed dynamics.
    """
    alpha_d, sigma0, k_d, delta = (Fraction(x) for x in (alpha_d, sigma0, k_d, delta))
    first = k_d / alpha_d >= 0
    value = (sigma0 * alpha_d * delta) ** 2 + 2 * alpha_d * delta * (1 + k_d / alpha_d)
    holds = bool(first and value <= 1)
    if holds and printed_ges_status == "refuted":
        implication = "fails"  # holds, yet eq:stabCond is exactly infeasible
    elif holds and printed_ges_status == "certified":
        implication = "consistent"
    else:
        implication = "not_applicable" if not holds else "undecided"
    from lyapcheck.paper import claims

    return claims.decided(ConditionResult(
        "stabcond2", "holds" if holds else "fails", "",
        numbers={"lhs_value": float_or_none(value), "lhs_exact": str(value),
                 "implies_stabcond_here": implication, "printed_prop41_ges": printed_ges_status},
    ))
