"""eq. ``eq:stabCond2``: the paper's simplified inequalities, in plain exact arithmetic."""

from __future__ import annotations

from fractions import Fraction

from lyapcheck.conditions.base import ConditionResult


def run(alpha_d: Fraction, sigma0: Fraction, k_d: Fraction, delta: Fraction,
        printed_ges_status: str) -> ConditionResult:
    """Evaluate eq. ``eq:stabCond2`` exactly (SI values) and say whether it implied eq. ``eq:stabCond``.

    The paper derived eq. ``eq:stabCond2`` for its printed ``A``; whether it implies
    eq. ``eq:stabCond`` at this gain set is read from ``prop41_ges`` on the printed dynamics.
    """
    first = k_d / alpha_d >= 0
    value = (sigma0 * alpha_d * delta) ** 2 + 2 * alpha_d * delta * (1 + k_d / alpha_d)
    holds = bool(first and value <= 1)
    if holds and printed_ges_status == "refuted":
        implication = "fails"  # holds, yet eq:stabCond is exactly infeasible
    elif holds and printed_ges_status == "certified":
        implication = "consistent"
    else:
        implication = "not_applicable" if not holds else "undecided"
    return ConditionResult(
        "stabcond2", "holds" if holds else "fails",
        f"(sigma0 alpha_d Delta)^2 + 2 alpha_d Delta (1 + k_d/alpha_d) = {float(value):.6g} "
        + ("<= 1" if value <= 1 else "> 1"),
        numbers={"lhs_value": float(value), "lhs_exact": str(value),
                 "implies_stabcond_here": implication, "printed_prop41_ges": printed_ges_status},
    )
