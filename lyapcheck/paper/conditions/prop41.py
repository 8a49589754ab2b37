"""Proposition 4.1's conditions (eq. ``eq:stabCond`` and its ISS variant), as stated.

``prop41_ges``: find ``P > 0`` with ``Gamma = -(A^T P + P A)`` and
``lambda_min(Gamma) > (p12 + sqrt(p12^2 + p22^2)) * g``, ``g = U/Delta`` (``1/Delta`` in the
paper; ``U`` makes the units explicit, see :mod:`symbolic.ilos`).

``prop41_iss``: ``lambda_min(Gamma) > p12 g + sqrt(p12^2 + p22^2) (e + g)``, where ``e`` is the
disturbance input gain of the dynamics used (``alpha_d`` as printed, 1 as derived; the paper
writes ``alpha_d`` because its eq. ``eq:xCrossdyn`` has that gain).

Both are one convex program: with an epigraph variable ``t >= ||(p12, p22)||`` (a second-order
cone) the condition is the LMI ``Gamma - (g p12 + (g + e) t + m) I >= 0``; the problem is
homogeneous in ``P``, so ``trace P = 1`` normalises it and the margin ``m`` is maximised. The
data are divided by their own scale so that ``m`` is a relative margin. Certification is the
exact check of the rounded ``P``; refutation is an exact necessary condition (Gamma_22 bound).
"""

from __future__ import annotations

from fractions import Fraction
from typing import Any

import numpy as np

from lyapcheck import exact
from lyapcheck.paper import claims
from lyapcheck.paper.conditions.base import System
from lyapcheck.results import ConditionResult
from lyapcheck.sos.sdp import CompiledProgram


def build_program(cp: Any) -> tuple[Any, dict[str, Any], dict[str, Any]]:
    """The DPP program of the module docstring (compiled once: :mod:`lyapcheck.paper.conditions.compiled`)."""
    A = cp.Parameter((2, 2), name="A")
    g = cp.Parameter(nonneg=True, name="g")
    ge = cp.Parameter(nonneg=True, name="g_plus_e")
    P = cp.Variable((2, 2), symmetric=True, name="P")
    t = cp.Variable(name="t")
    m = cp.Variable(name="m")
    gamma = -(A.T @ P + P @ A)
    rhs = g * P[0, 1] + ge * t + m
    constraints = [
        cp.trace(P) == 1,
        P >> 0,
        cp.SOC(t, cp.hstack([P[0, 1], P[1, 1]])),
        (gamma + gamma.T) / 2 - rhs * np.eye(2) >> 0,
        m <= 10,  # keeps the program bounded when A is very stable
    ]
    return cp.Problem(cp.Maximize(m), constraints), {"A": A, "g": g, "g_plus_e": ge}, {"P": P, "t": t, "m": m}


def program() -> CompiledProgram:
    from lyapcheck.paper.conditions import compiled

    return compiled.load("prop41")


def exact_check(system: System, P: exact.Matrix, iss: bool) -> tuple[bool, str]:
    """Exactly check eq. ``eq:stabCond`` (or the ISS inequality) for a rational ``P``."""
    if not exact.is_positive_definite(P):
        return False, "P is not positive definite (leading minors)"
    gamma = exact.scale(Fraction(-1), exact.lyapunov_form(system.A, P))
    g = system.rho_sup
    e = abs(system.E[0]) if iss else Fraction(0)
    p12, p22 = P[0][1], P[1][1]
    if not exact.min_eig_exceeds_2x2(gamma, g * p12, g + e, p12 * p12 + p22 * p22):
        which = "p12 g + sqrt(p12^2+p22^2)(e+g)" if iss else "(p12 + sqrt(p12^2+p22^2)) g"
        return False, f"lambda_min(Gamma) > {which} fails"
    return True, claims.PROP41_HOLDS


def refutation(system: System) -> dict[str, Any] | None:
    """Exact proof that eq. ``eq:stabCond`` has no solution, when the Gamma_22 bound shows it."""
    from symbolic._generated import stabcond_gamma22_bound

    a = system.A
    if not (a[1][0] == 0 and a[0][1] < 0 and a[1][1] < 0):
        return None
    bound_q = stabcond_gamma22_bound(a[0][1], a[1][1])
    gain_q = system.rho_sup
    if gain_q < bound_q:
        return None
    return {
        "argument": "gamma22_bound",
        "statement": ("lambda_min(Gamma) <= Gamma_22 = 2 p22 (k - c t) with t = -p12/p22, and the right-hand side "
                      "is g p22/(t + sqrt(1+t^2)); a solution needs 2(k - c t)(t + sqrt(1+t^2)) > g for some t, "
                      "whose supremum is at most the bound below"),
        "k": str(-a[1][1]), "c": str(-a[0][1]), "sup_bound": str(bound_q), "g": str(gain_q),
    }


def check_refutation(system: System, data: dict[str, Any]) -> bool:
    """Re-derive the refutation from the system alone (used by ``verify``): every stated field
    (the bound, its data and the statement) is the fresh one's."""
    fresh = refutation(system)
    return fresh is not None and all(data.get(key) == value for key, value in fresh.items())


def run(system: System, *, iss: bool) -> ConditionResult:
    """Search, check exactly, or refute; see the module docstring."""
    name = "prop41_iss" if iss else "prop41_ges"
    refuted = refutation(system)
    g = float(system.rho_sup)
    e = float(abs(system.E[0])) if iss else 0.0
    numbers: dict[str, Any] = {"relative_margin": None, "rhs_gain_g": g, "iss_gain_e": e}
    if refuted is not None:
        # an exact refutation is final: no numerical search can change it
        return claims.decided(ConditionResult(name, "refuted", "", numbers=numbers, refutation=refuted))
    A = exact.to_float(system.A)
    scale = max(np.abs(A).max(), g, 1e-300)
    solved = program().solve({"A": np.array(A) / scale, "g": g / scale, "g_plus_e": (g + e) / scale})
    report = solved.report
    margin = float(solved.values["m"]) if report.outcome == "optimal" and solved.values is not None else None
    numbers["relative_margin"] = margin
    if report.outcome != "optimal" or margin is None:
        return ConditionResult(name, "inconclusive", f"solver outcome '{report.outcome}', nothing proved",
                               numbers=numbers, solver=report.to_json())
    if margin <= 0:
        return ConditionResult(name, "not_certified",
                               "no certificate of this class was found (best margin <= 0); this is not a proof of instability",
                               numbers=numbers, solver=report.to_json())
    assert solved.values is not None  # margin is not None
    P = exact.symmetrize(exact.rational_matrix(solved.values["P"]))
    ok, why = exact_check(system, P, iss)
    if not ok:
        return ConditionResult(name, "inconclusive", f"solver found a candidate but its exact check failed: {why}",
                               numbers=numbers, solver=report.to_json())
    numbers["lambda_max_over_min_P"] = float(np.linalg.cond(np.array(exact.to_float(P))))
    return claims.decided(ConditionResult(name, "certified", "", numbers=numbers,
                                          certificate={"P": exact.to_json(P)}, solver=report.to_json()))
