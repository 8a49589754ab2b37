"""``ultimate_bound``: a certified bound on ``limsup |eps|`` for ``|d_perp| <= d*``.

Stage 0 (box, comparison lemma; exact arithmetic, global). Write ``y = eps + sigma0 s``. Then
``rho(y) eps = psi(y) - sigma0 rho(y) s`` with ``psi(y) = U Delta y / (y^2 + Delta^2)``,
``|psi| <= U/2``. Hence ``D+|s| <= a22 |s| + U/2`` (``a22 < 0``, the ``-sigma0 rho s`` term only
helps), so ``|s| <= S = (U/2)/|a22|`` (inflated by a factor ``1 + 1e-6`` so that the box is reached
in finite time) is eventually invariant; then ``D+|eps| <= a11 |eps| + |a12| S + |e| d*`` gives
``|eps| <= Ebox = (|a12| S + |e| d*)/|a11|`` (inflated), also eventually invariant.

Stage k >= 1 (invariant ellipsoid, refined). On the eventually-invariant set ``K`` of the
previous stage, ``|y| <= ybar`` and so ``rho >= rho_lo = U Delta/(ybar^2 + Delta^2)``. If ``P > 0``,
``lambda > 0`` satisfy, at both vertices ``r in {rho_lo, rho_sup}``,

    [[ A_r^T P + P A_r + lambda P,  P e d* ],
     [ d* e^T P,                    -lambda ]]  <  0,

then along trajectories in ``K`` with ``|w| <= d*``, ``V_dot <= -lambda (V - 1)``; so ``V <= 1 + delta``
intersected with ``K`` is eventually invariant and ``limsup |eps| <= sqrt(e1^T P^-1 e1)``. Each stage
is checked exactly; the next stage uses ``ybar^2 <= c^T P^-1 c`` (``c = (1, sigma0)``). ``P`` is
found as ``Q^-1``, ``Q`` minimising ``Q11 = e1^T P^-1 e1`` under the same LMIs written in ``Q``
(:func:`build_program`), over a line search in ``lambda``.
"""

from __future__ import annotations

from collections.abc import Callable
from fractions import Fraction
from typing import Any

import numpy as np

from lyapcheck import exact
from lyapcheck.paper import claims
from lyapcheck.paper.conditions import scaling
from lyapcheck.paper.conditions.base import System
from lyapcheck.results import ConditionResult
from lyapcheck.sos.sdp import CompiledProgram

#: the eventually-invariant sets are inflated by this factor (exact, tiny)
INFLATE = Fraction(1_000_001, 1_000_000)
#: decay rates tried, in the scaled time unit (the fastest vertex entry is 1 there); the best
#: grid point is then refined by a few golden-section steps in log(lambda)
LAMBDA_GRID = np.geomspace(1e-6, 4.0, 16)
LAMBDA_REFINE_STEPS = 6
#: two values of Q11 within this relative difference are equal to the line search (then the
#: smaller lambda is taken): its steps then follow differences the solves resolve (their optima
#: agree to ~1e-9), not the last bits of two solves near the flat minimum
LINE_SEARCH_TIE = 1e-6
MAX_STAGES = 5
#: relative strictness built into the LMIs (see _EllipsoidProgram)
STRICTNESS = 1e-3


def box_stage(system: System) -> dict[str, Any] | None:
    """Exact stage-0 box (module docstring); None when the structure does not apply."""
    a = system.A
    if not (a[1][0] == 0 and a[0][0] < 0 and a[1][1] < 0 and system.B == ((0, 0), (1, 0))):
        return None
    s_bar = system.speed / 2 / (-a[1][1]) * INFLATE
    e_bar = (abs(a[0][1]) * s_bar + abs(system.E[0]) * system.d_max) / (-a[0][0]) * INFLATE
    y_bar = e_bar + system.sigma0 * s_bar
    return {"s_bound": str(s_bar), "eps_bound": str(e_bar), "y_bound": str(y_bar)}


def check_box(system: System, data: dict[str, Any]) -> bool:
    fresh = box_stage(system)
    return fresh is not None and all(Fraction(fresh[k]) <= Fraction(data[k]) for k in ("s_bound", "eps_bound", "y_bound"))


def rho_lower(system: System, y_bar: Fraction) -> Fraction:
    """``rho`` at ``|eps + sigma0 s| = y_bar``: its smallest value wherever ``|y| <= y_bar``."""
    from symbolic._generated import rho_of_y_sq

    return rho_of_y_sq(y_bar * y_bar, system.delta, system.speed)


def build_program(cp: Any) -> tuple[Any, dict[str, Any], dict[str, Any]]:
    """min Q11  s.t. Q > 0 and the vertex LMIs in ``Q = P^-1`` (DPP, scaled data; compiled once).

    The congruence ``diag(Q, 1)`` turns each LMI of the module docstring into
    ``[[Q A_r^T + A_r Q + lambda Q, e d*], [d* e^T, -lambda]] < 0``, and ``e1^T P^-1 e1 = Q11``
    is linear: no Schur complement, and ``Q`` is of the order of the bound squared where ``P`` was
    of its inverse (the P-form's solves near the optimum ended "inaccurate", some at ``t < 0``).

    The LMIs are solved with ``lambda (1 + STRICTNESS)`` in the top block and
    ``lambda (1 - STRICTNESS)`` in the bottom one (:func:`lambda_values`); the exact check then
    uses ``lambda`` and ``P = Q^-1`` and finds the original LMI negative definite with margin
    ``STRICTNESS * lambda * diag(P, 1)``, far above the rounding error of the rational certificate.
    """
    A_lo = cp.Parameter((2, 2), name="A_lo")
    A_hi = cp.Parameter((2, 2), name="A_hi")
    e = cp.Parameter((2, 1), name="e_dstar")
    lam_top = cp.Parameter(nonneg=True, name="lambda_top")
    lam_bottom = cp.Parameter(nonneg=True, name="lambda_bottom")
    Q = cp.Variable((2, 2), symmetric=True, name="Q")
    lmis = []
    for a in (A_lo, A_hi):
        top = Q @ a.T + a @ Q + lam_top * Q
        lmi = cp.bmat([[top, e], [e.T, -lam_bottom * np.eye(1)]])
        lmis.append((lmi + lmi.T) / 2)
    problem = cp.Problem(cp.Minimize(Q[0, 0]), [Q >> 0] + [lmi << 0 for lmi in lmis])
    params = {"A_lo": A_lo, "A_hi": A_hi, "e_dstar": e, "lambda_top": lam_top, "lambda_bottom": lam_bottom}
    return problem, params, {"Q": Q}


def lambda_values(lam: float) -> dict[str, float]:
    """The two decay-rate parameters of the program at ``lambda`` (see :func:`build_program`)."""
    return {"lambda_top": lam * (1 + STRICTNESS), "lambda_bottom": lam * (1 - STRICTNESS)}


def program() -> CompiledProgram:
    from lyapcheck.paper.conditions import compiled

    return compiled.load("ultimate")


def lmi_matrix(a: exact.Matrix, P: exact.Matrix, lam: Fraction, e: tuple[Fraction, Fraction], d: Fraction) -> exact.Matrix:
    top = exact.add(exact.lyapunov_form(a, P), exact.scale(lam, P))
    pe = exact.matmul(P, ((e[0] * d,), (e[1] * d,)))
    return exact.block([[top, pe], [exact.transpose(pe), ((-lam,),)]])


def check_ellipsoid(system: System, stage: dict[str, Any], rho_lo: Fraction) -> tuple[bool, str]:
    """Exact check of one ellipsoid stage (module docstring)."""
    P = exact.from_json(stage["P"])
    lam = Fraction(stage["lambda"])
    if Fraction(stage["rho_lo"]) > rho_lo:
        return False, "stage uses a larger rho_lo than its predecessor proves"
    if lam <= 0 or not exact.is_positive_definite(P):
        return False, "lambda > 0 and P > 0 fail"
    for r in (Fraction(stage["rho_lo"]), system.rho_sup):
        if not exact.is_negative_definite(lmi_matrix(system.vertex(r), P, lam, system.E, system.d_max)):
            return False, f"the invariant-ellipsoid LMI fails at rho = {float(r):.6g}"
    det = P[0][0] * P[1][1] - P[0][1] ** 2
    eps_sq = P[1][1] / det  # e1^T P^-1 e1
    y_sq = (P[1][1] - 2 * system.sigma0 * P[0][1] + system.sigma0**2 * P[0][0]) / det  # c^T P^-1 c
    if Fraction(stage["eps_bound_sq"]) < eps_sq or Fraction(stage["y_bound_sq"]) < y_sq:
        return False, "stated bounds are smaller than e1^T P^-1 e1 or c^T P^-1 c"
    return True, "ok"


#: a solve of the line search: (Q11, lambda, Q~ as the solver gave it, whether it ended "optimal")
Candidate = tuple[float, float, np.ndarray, bool]


def _less(a: Candidate | None, b: Candidate | None) -> bool:
    """``a`` is better than ``b``: a smaller ``Q11`` beyond :data:`LINE_SEARCH_TIE` (a missing solve is worst)."""
    if a is None:
        return False
    return b is None or a[0] < b[0] * (1 - LINE_SEARCH_TIE)


def _best(candidates: list[Candidate]) -> Candidate:
    """The candidate of smallest ``Q11``; among those within :data:`LINE_SEARCH_TIE` of it, the smallest lambda."""
    low = min(r[0] for r in candidates)
    return min((r for r in candidates if r[0] <= low * (1 + LINE_SEARCH_TIE)), key=lambda r: r[1])


def line_search(attempt: Callable[[float], Candidate | None]) -> list[Candidate]:
    """Minimise ``Q11`` over ``lambda``: :data:`LAMBDA_GRID`, then a golden-section refinement
    (log scale) between the neighbours of its best point; shared with the box class. Values within
    :data:`LINE_SEARCH_TIE` count as equal, the smaller lambda winning, in every comparison.

    An "inaccurate" solve steers the search too (refusing them lost the best decay rates where
    the solves stop just short of the tolerances: sweep-kd-delta@19,0's bound was 3.6e-3 m
    instead of 1.7e-3 m), but its ``Q`` may fail the exact check. So the candidates to check, in
    order, are the best solve and, if that one was inaccurate, the best "optimal" one.
    """
    tried = [attempt(float(lam)) for lam in LAMBDA_GRID]
    found = [r for r in tried if r is not None]
    if not found:
        return []
    i = tried.index(_best(found))
    lo = np.log(LAMBDA_GRID[max(i - 1, 0)])
    hi = np.log(LAMBDA_GRID[min(i + 1, len(LAMBDA_GRID) - 1)])
    ratio = (np.sqrt(5) - 1) / 2
    for _ in range(LAMBDA_REFINE_STEPS):
        a, b = hi - ratio * (hi - lo), lo + ratio * (hi - lo)
        ra, rb = attempt(float(np.exp(a))), attempt(float(np.exp(b)))
        found += [r for r in (ra, rb) if r is not None]
        if _less(rb, ra):
            lo = a
        else:  # a better, or a tie: the smaller lambdas
            hi = b
    best = _best(found)
    accurate = [r for r in found if r[3]]
    if best[3] or not accurate:
        return [best]
    return [best, _best(accurate)]


def p_from_q(sc: scaling.Scaling, kappa: Fraction, q_scaled: np.ndarray) -> exact.Matrix | None:
    """``P = Q^-1`` in the original coordinates, exactly, from the solver's ``Q~`` found with the
    disturbance divided by ``kappa`` (``Q = kappa^2 Q~``) in the scaled ones; None if the rounded
    ``Q`` is not invertible (the exact check would refuse it anyway)."""
    Q = exact.scale(kappa * kappa, exact.symmetrize(exact.rational_matrix(q_scaled)))
    det = Q[0][0] * Q[1][1] - Q[0][1] ** 2
    if det == 0:
        return None
    return sc.p_from_scaled(((Q[1][1] / det, -Q[0][1] / det), (-Q[0][1] / det, Q[0][0] / det)))


def _ellipsoid_stage(system: System, rho_lo: Fraction) -> tuple[dict[str, Any] | None, dict[str, Any]]:
    vertices = [system.vertex(rho_lo), system.vertex(system.rho_sup)]
    sc = scaling.choose(vertices)
    prog = program()
    e_scaled = sc.vector_to_scaled((system.E[0] * system.d_max, system.E[1] * system.d_max))
    # the LMIs are homogeneous of degree 2 in (Q, e d*): solved with the disturbance column of unit
    # length, Q~ = Q / kappa^2 is of the order of (bound / kappa)^2, not of bound^2 (1e-8 and less,
    # under the solver's absolute tolerances, which then ate the strictness margin)
    norm = float(np.linalg.norm(e_scaled))
    kappa = exact.to_rational(norm, 6) if norm > 0 else Fraction(1)
    data = {"A_lo": sc.matrix_to_scaled(vertices[0]), "A_hi": sc.matrix_to_scaled(vertices[1]),
            "e_dstar": (e_scaled / float(kappa)).reshape(2, 1)}
    solves = 0

    def attempt(lam: float) -> Candidate | None:
        nonlocal solves
        solved = prog.solve({**data, **lambda_values(lam)})
        solves += 1
        v = solved.values
        if solved.report.outcome in ("optimal", "inaccurate") and v is not None and v["Q"][0][0] > 0:
            return float(v["Q"][0][0]), lam, np.array(v["Q"]), solved.report.outcome == "optimal"
        return None

    candidates = line_search(attempt)
    meta: dict[str, Any] = {"solves": solves, "beta": str(sc.beta), "time_scale": str(sc.time)}
    for _, lam, q_scaled, _ in candidates:
        P = p_from_q(sc, kappa, q_scaled)
        if P is None:
            continue
        det = P[0][0] * P[1][1] - P[0][1] ** 2
        if det <= 0:
            continue
        stage = {
            "P": exact.to_json(P), "lambda": str(exact.to_rational(lam, 6) * sc.time), "rho_lo": str(rho_lo),
            "eps_bound_sq": str(P[1][1] / det),
            "y_bound_sq": str((P[1][1] - 2 * system.sigma0 * P[0][1] + system.sigma0**2 * P[0][0]) / det),
        }
        if check_ellipsoid(system, stage, rho_lo)[0]:
            return stage, meta
    return None, meta


def run(system: System) -> ConditionResult:
    """Certified ultimate bound on ``|eps|`` (metres), tightened stage by stage."""
    box = box_stage(system)
    if box is None:
        return ConditionResult("ultimate_bound", "not_certified",
                               "the comparison-lemma box needs A = [[a11, a12], [0, a22]] with a11, a22 < 0")
    stages: list[dict[str, Any]] = []
    metas: list[dict[str, Any]] = []
    eps_bound = Fraction(box["eps_bound"])
    y_bar = Fraction(box["y_bound"])
    if system.d_max > 0:
        for _ in range(MAX_STAGES):
            rho_lo = rho_lower(system, y_bar)
            stage, meta = _ellipsoid_stage(system, rho_lo)
            metas.append(meta)
            if stage is None:
                break
            stages.append(stage)
            new_eps = exact.sqrt_upper(Fraction(stage["eps_bound_sq"]))
            new_y = exact.sqrt_upper(Fraction(stage["y_bound_sq"])) * INFLATE
            improved = new_y < y_bar * Fraction(99, 100)
            eps_bound = min(eps_bound, new_eps)
            y_bar = min(y_bar, new_y)
            if not improved:
                break
    numbers = {
        "eps_bound_m": float(eps_bound), "eps_bound_exact": str(eps_bound),
        "box_eps_bound_m": float(Fraction(box["eps_bound"])), "box_s_bound": float(Fraction(box["s_bound"])),
        "ellipsoid_stages": len(stages), "d_max_m_per_s": float(system.d_max),
    }
    return claims.decided(ConditionResult(
        "ultimate_bound", "certified", "",
        numbers=numbers, certificate={"box": box, "stages": stages, "eps_bound": str(eps_bound)},
        solver={"stages": metas},
    ))


def verify(system: System, cert: dict[str, Any]) -> tuple[bool, str]:
    """Re-check the whole chain exactly (used by ``lyapcheck verify``)."""
    box = cert["box"]
    if not check_box(system, box):
        return False, "box bounds do not follow from the system (comparison lemma)"
    y_bar = Fraction(box["y_bound"])
    best = Fraction(box["eps_bound"])
    for i, stage in enumerate(cert["stages"]):
        ok, why = check_ellipsoid(system, stage, rho_lower(system, y_bar))
        if not ok:
            return False, f"ellipsoid stage {i + 1}: {why}"
        best = min(best, exact.sqrt_upper(Fraction(stage["eps_bound_sq"])))
        y_bar = min(y_bar, exact.sqrt_upper(Fraction(stage["y_bound_sq"])) * INFLATE)
    claimed = Fraction(cert["eps_bound"])
    if claimed < best:
        return False, f"stated eps bound {float(claimed):.6g} m is below what the stages prove ({float(best):.6g} m)"
    return True, f"limsup |eps| <= {float(claimed):.6g} m follows exactly"
