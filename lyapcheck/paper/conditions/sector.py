"""``sector_ges``: GES from a common quadratic Lyapunov function over the coefficient interval.

The argument (a valid proof, stated here and in reports):

The error dynamics are ``x_dot = (A + rho(x) B) x`` with ``rho(x) = U Delta / ((eps + sigma0 s)^2
+ Delta^2)``, and ``0 < rho(x) <= rho_sup = U/Delta`` for every ``x``. If a symmetric ``P > 0``
satisfies ``(A + r B)^T P + P (A + r B) < 0`` at both end points ``r = 0`` and ``r = rho_sup``,
the left-hand side is affine in ``r``, so it is negative definite for every ``r`` in between,
and in particular for ``r = rho(x)`` at each ``x``. Then ``V = x^T P x`` satisfies
``V_dot <= -2 mu V`` with ``mu = min_r lambda_min(Q_r) / (2 lambda_max(P)) > 0``, a global
exponential decay with rate ``mu`` (the toolkit certifies an exact rational ``mu``). The
dependence of ``rho`` on ``x`` is never used beyond its range, so the proof also covers any
time variation of ``rho`` inside the interval.

Refutation (exact): for two Hurwitz 2x2 matrices, a common quadratic Lyapunov function
exists if and only if neither ``A_0 A_1`` nor ``A_0 A_1^{-1}`` has a negative real eigenvalue
(Shorten and Narendra, 2003). When one of them has, no ``P`` of this class exists.
"""

from __future__ import annotations

from fractions import Fraction
from typing import Any

import numpy as np

from lyapcheck import exact
from lyapcheck.paper import claims
from lyapcheck.paper.conditions import scaling
from lyapcheck.paper.conditions.base import System
from lyapcheck.results import ConditionResult
from lyapcheck.sos.sdp import CompiledProgram, SolveReport


def vertex_names(vertices: int) -> list[str]:
    """Parameter names of the vertex matrices: ``A_lo, A_hi`` for the sector's two end points,
    ``A_0 .. A_{n-1}`` for a polytope of ``n`` (the box certificates of :mod:`lyapcheck.paper.boxes.quadratic`)."""
    return ["A_lo", "A_hi"] if vertices == 2 else [f"A_{i}" for i in range(vertices)]


def build_program(cp: Any, vertices: int = 2) -> tuple[Any, dict[str, Any], dict[str, Any]]:
    """max m s.t. -(A_i^T P + P A_i) >= m I at every vertex, P >= m I, trace P = 1 (DPP; compiled once)."""
    params = {name: cp.Parameter((2, 2), name=name) for name in vertex_names(vertices)}
    P = cp.Variable((2, 2), symmetric=True, name="P")
    m = cp.Variable(name="m")
    eye = np.eye(2)
    cons = [cp.trace(P) == 1, P >> m * eye, m <= 1]
    for a in params.values():
        q = -(a.T @ P + P @ a)
        cons.append((q + q.T) / 2 >> m * eye)
    return cp.Problem(cp.Maximize(m), cons), params, {"P": P, "m": m}


def program(vertices: int = 2) -> CompiledProgram:
    from lyapcheck.paper.conditions import compiled

    return compiled.load("sector" if vertices == 2 else compiled.key_of("sector", vertices))


def exact_check(vertices: list[exact.Matrix], P: exact.Matrix, rate: Fraction) -> tuple[bool, str]:
    """``P > 0`` and ``A_i^T P + P A_i + 2 rate P < 0`` at every vertex, exactly (``rate >= 0``:
    with a negative rate the inequality allows growth and proves nothing)."""
    if rate < 0:
        return False, "the decay rate must be >= 0"
    if not exact.is_positive_definite(P):
        return False, "P is not positive definite (leading minors)"
    for i, a in enumerate(vertices):
        q = exact.add(exact.lyapunov_form(a, P), exact.scale(2 * rate, P))
        if not exact.is_negative_definite(q):
            return False, f"A_{i}^T P + P A_{i} + 2 mu P is not negative definite at vertex {i}"
    return True, claims.lmi_decay(rate)


def refutation(vertices: list[exact.Matrix]) -> dict[str, Any] | None:
    """Shorten-Narendra: no common quadratic Lyapunov function for two Hurwitz 2x2 matrices."""
    a0, a1 = vertices
    if not (exact.is_hurwitz_2x2(a0) and exact.is_hurwitz_2x2(a1)):
        return None
    prod = exact.matmul(a0, a1)
    quot = exact.matmul(a0, exact.inverse_2x2(a1))
    bad = [name for name, m in (("A0 A1", prod), ("A0 A1^-1", quot)) if exact.has_negative_real_eigenvalue_2x2(m)]
    if not bad:
        return None
    return {
        "argument": "shorten_narendra_2x2",
        "statement": claims.shorten_narendra(prod, quot),
        "A0A1": exact.to_json(prod), "A0A1inv": exact.to_json(quot),
    }


def certify_polytope(vertices: list[exact.Matrix]) -> tuple[exact.Matrix | None, Fraction | None, float | None, Any]:
    """Search and exactly check a common quadratic Lyapunov function; returns (P, rate, margin, report).

    Two vertices (the sector's end points) or eight (a box's polytope, repeated vertices allowed).
    """
    sc = scaling.choose(vertices)
    names = vertex_names(len(vertices))
    solved = program(len(vertices)).solve({n: sc.matrix_to_scaled(v) for n, v in zip(names, vertices)})
    report: SolveReport = solved.report
    if report.outcome != "optimal" or solved.values is None:
        return None, None, None, report
    margin = float(solved.values["m"])
    if margin <= 0:
        return None, None, margin, report
    P = sc.p_from_scaled(exact.symmetrize(exact.rational_matrix(solved.values["P"])))
    Pf = np.array(exact.to_float(P))
    lam_max = float(np.linalg.eigvalsh(Pf).max())
    rate_f = min(float(np.linalg.eigvalsh(-np.array(exact.to_float(exact.lyapunov_form(a, P)))).min())
                 for a in vertices) / (2 * lam_max)
    # back off the floating-point rate so the exact check has room; halve until it passes
    rate = exact.to_rational(max(rate_f, 0.0) * 0.999, 6)
    for _ in range(30):
        if exact_check(vertices, P, rate)[0]:
            return P, rate, margin, report
        rate /= 2
    return (P if exact_check(vertices, P, Fraction(0))[0] else None), Fraction(0), margin, report


def certified_result(P: exact.Matrix, rate: Fraction, rho_lo: Fraction, why: str, numbers: dict[str, Any],
                     solver: dict[str, Any]) -> ConditionResult:
    """The ``certified`` result; call only with ``why`` from a passed :func:`exact_check` (its
    summary is :mod:`lyapcheck.paper.claims`' sentence, the same text for the same rate)."""
    numbers["decay_rate_per_s"] = float(rate)
    return claims.decided(ConditionResult("sector_ges", "certified", why, numbers=numbers,
                                          certificate={"P": exact.to_json(P), "decay_rate": str(rate),
                                                       "rho_lo": str(rho_lo)},
                                          solver=solver))


def uncertified_result(vertices: list[exact.Matrix], numbers: dict[str, Any], outcome: str,
                       margin: float | None, solver: dict[str, Any]) -> ConditionResult:
    """No certificate passed its exact check: refuted (exactly), inconclusive or not_certified."""
    refuted = refutation(vertices)
    if refuted is not None:
        return claims.decided(ConditionResult("sector_ges", "refuted", "", numbers=numbers,
                                              refutation=refuted, solver=solver))
    if outcome != "optimal":
        return ConditionResult("sector_ges", "inconclusive", f"solver outcome '{outcome}', nothing proved",
                               numbers=numbers, solver=solver)
    status = "not_certified" if (margin is not None and margin <= 0) else "inconclusive"
    return ConditionResult("sector_ges", status,  # type: ignore[arg-type]
                           "no common quadratic Lyapunov function was found; this is not a proof of instability",
                           numbers=numbers, solver=solver)


def run(system: System, rho_lo: Fraction = Fraction(0)) -> ConditionResult:
    """GES of the error dynamics from the polytope ``rho in [rho_lo, rho_sup]``."""
    vertices = [system.vertex(rho_lo), system.vertex(system.rho_sup)]
    P, rate, margin, report = certify_polytope(vertices)
    numbers: dict[str, Any] = {"relative_margin": margin, "rho_interval": [str(rho_lo), str(system.rho_sup)]}
    if P is not None and rate is not None and rate > 0:
        ok, why = exact_check(vertices, P, rate)
        if ok:
            if refutation(vertices) is not None:  # pragma: no cover - both exact: a bug in one of them
                raise AssertionError("a certificate and a refutation both passed their exact checks")
            return certified_result(P, rate, rho_lo, why, numbers, report.to_json())
    return uncertified_result(vertices, numbers, report.outcome, margin, report.to_json())
