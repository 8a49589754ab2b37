"""A certified bound on ``limsup |eps|`` for every gain set of a box (class ``ultimate_bound``).

The point class (:mod:`lyapcheck.paper.conditions.ultimate`) proves the bound at one gain set ``theta``
in stages: an exact comparison-lemma box, then invariant ellipsoids. Over a box of gains each
stage is replaced by one that serves every ``theta`` of the box at once.

What the box rests on. :func:`lyapcheck.paper.certification.build_system` evaluates the generated
dynamics, whose entries ``a11``, ``a12``, ``a22``, ``E_0``, ``rho_sup`` and the speed ``U`` are
signed monomials in the positive parameters (``a21 = 0``, ``E_1 = 0`` and ``B = [[0, 0], [1, 0]]``
identically; ``d*`` is not a box parameter; ``tests/test_box_ultimate.py`` checks all of this on
the derivation). A monomial keeps its sign and is monotone in every parameter, so its range over
the box is the interval spanned by its values at the box's corners, and the structure the point
class needs (``a11, a22 < 0``) holds everywhere in the box iff it holds at every corner.

Stage 0 (exact). At ``theta`` the point class proves that ``K0(theta) = {|s| <= S(theta),
|eps| <= E(theta)}`` is eventually invariant (reached in finite time, then kept), with

    S = INFLATE U / (2 |a22|),   E = INFLATE (|a12| S + |E_0| d*) / |a11|,   Y = E + sigma0 S,

and ``|y| = |eps + sigma0 s| <= Y(theta)`` on it. ``S`` is a monomial and ``E``, ``Y`` are
posynomials (sums of monomials with positive coefficients) in the parameters. In logarithmic
coordinates ``u = log(theta)`` a posynomial is ``sum c_i exp(a_i . u)``, a convex function, and
the box is a box with the same corners; a convex function attains its maximum over a box at a
vertex. So the maxima over the corners, ``S*``, ``E*``, ``Y*``, bound ``S(theta)``, ``E(theta)``,
``Y(theta)`` at every gain set of the box (this is tighter than bounding each factor separately,
and just as exact). Hence ``limsup |eps| <= E*`` for every ``theta``, and eventually
``|y| <= Y*`` along every trajectory of every ``theta``; a larger level is reached no later than
the point's own, so these box-wide levels are eventually satisfied for good.

Ellipsoid stages (one ``P``, ``lambda`` for the whole box). On ``theta``'s eventually-invariant
set of the previous stage, ``|y| <= ybar`` (box-wide), so ``rho = U Delta/(y^2 + Delta^2) >=
rho_lo(theta) = U Delta/(ybar^2 + Delta^2)``. It increases with ``U``, and in ``Delta`` the factor
``Delta/(ybar^2 + Delta^2)`` rises up to ``Delta = ybar`` and falls after it (unimodal), so its
minimum over an interval is at an end: ``rho_lo(theta) >= rho_lo* = min`` over the corners
(only ``U`` and ``Delta`` enter). Likewise ``rho <= rho_sup(theta) <= rho_sup* = max`` over the
corners. So along ``theta``'s trajectories ``x' = A_r x + e d* w~`` with ``|w~| <= 1``,
``A_r = [[a11, a12], [r, a22]]`` and ``r = rho(x) in [rho_lo*, rho_sup*]``. For fixed ``P``,
``lambda`` the point class's LMI

    [[ A^T P + P A + lambda P,  P (e d*) ],
     [ (e d*)^T P,              -lambda  ]]  <  0

is affine in the pair ``(A, e d*)``, and every ``(A_r(theta), e(theta) d*)`` lies in the product
of the intervals of ``a11``, ``a12``, ``r``, ``a22``, ``E_0 d*``, ``E_1 d*`` (entries constant over
the box give no split), i.e. it is a convex combination of that product's vertices. A negative
definite LMI at every vertex is therefore negative definite at every gain set and every ``r``, and
the point class's argument goes through unchanged at each ``theta``: ``V_dot <= -lambda (V - 1)``
on its previous set, ``V <= INFLATE^2`` intersected with it is eventually invariant, and
``limsup |eps| <= sqrt(e1^T P^-1 e1)`` (``P`` common, so the bound is too). The next stage's
``ybar^2`` is ``max c^T P^-1 c`` over ``c = (1, sigma0)``: a convex quadratic in ``sigma0``, so its
maximum over ``sigma0``'s interval is at an end. ``P`` and ``lambda`` are rounded to rationals and
the LMI is checked exactly at every vertex (:func:`check_stage`); stages repeat, as in the point
class, while ``ybar`` improves by 1 %.

The search. One cvxpy program per vertex count, with the vertex matrices, the vectors ``e d*``
and ``lambda`` as parameters, written in ``Q = P^-1`` (:func:`build_program`), is compiled once
per box and re-solved along the point class's line search in ``lambda``
(:func:`lyapcheck.paper.conditions.ultimate.line_search`: its grid, golden-section refinement and
strictness margin). The data are
scaled by :func:`lyapcheck.paper.conditions.scaling.choose` applied to the box's vertex matrices: an exact
state scaling ``T = diag(1, beta)`` and time unit ``s`` fixed per stage, mapped back exactly
(``P = T^-T P~ T^-1``, ``lambda = s lambda~``) before the exact check in the original coordinates.

A box is never ``refuted`` by this class: a bound that is not proved is not disproved.
"""

from __future__ import annotations

import itertools
import time
from fractions import Fraction
from typing import Any, Mapping, Sequence

import numpy as np

from lyapcheck import exact
from lyapcheck import tolerances as tol
from lyapcheck.paper.boxes.box import ParameterBox, corner_problems
from lyapcheck.paper.conditions import scaling, ultimate
from lyapcheck.paper.conditions.base import System
from lyapcheck.paper.params import Problem
from lyapcheck.paper.system import build_system

#: a vertex of the box's (A_r, e d*) polytope: the matrix A_r and the vector e d*
Vertex = tuple[exact.Matrix, tuple[Fraction, Fraction]]

#: the box-stage keys, as in :func:`lyapcheck.paper.conditions.ultimate.box_stage`
BOX_KEYS = ("s_bound", "eps_bound", "y_bound")


# -- what the box implies, exactly --------------------------------------------------------------
def corner_systems(problem: Problem, box: ParameterBox, dynamics: str) -> list[System]:
    """The exact structured dynamics at every corner of the box."""

    return [build_system(p, dynamics) for p in corner_problems(problem, box)]


def box_stage(systems: Sequence[System]) -> dict[str, str] | None:
    """Stage 0 for the box: the maxima over the corners of the point class's stage-0 bounds
    (posynomials, so their maxima over the box are at corners; module docstring). None when
    the structure fails at some corner."""
    stages = [ultimate.box_stage(s) for s in systems]
    if any(st is None for st in stages):
        return None
    return {k: str(max(Fraction(st[k]) for st in stages if st is not None)) for k in BOX_KEYS}


def _interval(values: Sequence[Fraction]) -> tuple[Fraction, Fraction]:
    return min(values), max(values)


def entry_ranges(systems: Sequence[System]) -> dict[str, tuple[Fraction, Fraction]]:
    """Intervals of the monomial entries over the box (spanned by their values at the corners)."""
    return {
        "a11": _interval([s.A[0][0] for s in systems]),
        "a12": _interval([s.A[0][1] for s in systems]),
        "a22": _interval([s.A[1][1] for s in systems]),
        "e0_dstar": _interval([s.E[0] * s.d_max for s in systems]),
        "e1_dstar": _interval([s.E[1] * s.d_max for s in systems]),
        "rho_sup": _interval([s.rho_sup for s in systems]),
        "sigma0": _interval([s.sigma0 for s in systems]),
    }


def rho_lower_box(systems: Sequence[System], y_bar: Fraction) -> Fraction:
    """``min rho_lo(theta)`` over the box at ``|y| <= y_bar``: over its corners (module docstring:
    increasing in ``U``, unimodal in ``Delta``)."""
    return min(ultimate.rho_lower(s, y_bar) for s in systems)


def stage_vertices(ranges: Mapping[str, tuple[Fraction, Fraction]], rho_lo: Fraction) -> list[Vertex]:
    """The vertices of the product of the intervals of ``a11, a12, r, a22, E_0 d*, E_1 d*``
    with ``r in [rho_lo, rho_sup*]``; a constant entry gives no split (repeats removed)."""
    def ends(lo: Fraction, hi: Fraction) -> tuple[Fraction, ...]:
        return (lo,) if lo == hi else (lo, hi)

    axes = [ends(*ranges["a11"]), ends(*ranges["a12"]), ends(rho_lo, ranges["rho_sup"][1]),
            ends(*ranges["a22"]), ends(*ranges["e0_dstar"]), ends(*ranges["e1_dstar"])]
    out: list[Vertex] = []
    for a11, a12, r, a22, e0, e1 in itertools.product(*axes):
        out.append((((a11, a12), (r, a22)), (e0, e1)))
    return list(dict.fromkeys(out))


def vertices_to_json(vertices: Sequence[Vertex]) -> list[dict[str, Any]]:
    return [{"A": exact.to_json(a), "e_dstar": [str(e[0]), str(e[1])]} for a, e in vertices]


def _bounds_of(P: exact.Matrix, sigma0: tuple[Fraction, Fraction]) -> tuple[Fraction, Fraction]:
    """``e1^T P^-1 e1`` and ``max c^T P^-1 c`` over ``c = (1, sigma0)``, ``sigma0`` at its ends
    (a convex quadratic in ``sigma0``, module docstring)."""
    det = P[0][0] * P[1][1] - P[0][1] ** 2
    eps_sq = P[1][1] / det
    y_sq = max((P[1][1] - 2 * s * P[0][1] + s * s * P[0][0]) / det for s in sigma0)
    return eps_sq, y_sq


def check_stage(stage: Mapping[str, Any], vertices: Sequence[Vertex], rho_lo: Fraction,
                sigma0: tuple[Fraction, Fraction]) -> tuple[bool, str]:
    """Exact check of one ellipsoid stage at the box's vertices (``rho_lo`` is what the previous
    stage proves; the vertices are those of the stage's own, possibly smaller, ``rho_lo``)."""
    P = exact.from_json(stage["P"])
    lam = Fraction(stage["lambda"])
    if Fraction(stage["rho_lo"]) > rho_lo:
        return False, "stage uses a larger rho_lo than its predecessor proves"
    if len(P) != 2 or lam <= 0 or not exact.is_positive_definite(P):
        return False, "lambda > 0 and a 2x2 P > 0 fail"
    for a, e in vertices:
        if not exact.is_negative_definite(ultimate.lmi_matrix(a, P, lam, e, Fraction(1))):
            return False, (f"the invariant-ellipsoid LMI fails at the vertex A = {exact.to_float(a)}, "
                           f"e d* = ({float(e[0]):.6g}, {float(e[1]):.6g})")
    eps_sq, y_sq = _bounds_of(P, sigma0)
    if Fraction(stage["eps_bound_sq"]) < eps_sq or Fraction(stage["y_bound_sq"]) < y_sq:
        return False, "stated bounds are smaller than e1^T P^-1 e1 or max c^T P^-1 c"
    return True, "ok"


# -- the search ----------------------------------------------------------------------------------
def build_program(cp: Any, count: int) -> tuple[Any, dict[str, Any], dict[str, Any]]:
    """min Q11  s.t. ``Q > 0`` and the LMI at ``count`` vertices written in ``Q = P^-1`` (DPP: the
    vertex data and the two decay-rate parameters of :func:`ultimate.lambda_values` are parameters).

    As in :func:`lyapcheck.paper.conditions.ultimate.build_program`: the congruence ``diag(Q, 1)`` gives
    ``[[Q A^T + A Q + lambda Q, e d*], [(e d*)^T, -lambda]] < 0``, still affine in ``(A, e d*)``
    for fixed ``Q``, so the vertex argument of the module docstring holds for it as it is."""
    As = [cp.Parameter((2, 2), name=f"A_{i}") for i in range(count)]
    es = [cp.Parameter((2, 1), name=f"e_dstar_{i}") for i in range(count)]
    lam_top = cp.Parameter(nonneg=True, name="lambda_top")
    lam_bottom = cp.Parameter(nonneg=True, name="lambda_bottom")
    Q = cp.Variable((2, 2), symmetric=True, name="Q")
    constraints = [Q >> 0]
    for a, e in zip(As, es):
        top = Q @ a.T + a @ Q + lam_top * Q
        lmi = cp.bmat([[top, e], [e.T, -lam_bottom * np.eye(1)]])
        constraints.append((lmi + lmi.T) / 2 << 0)
    problem = cp.Problem(cp.Minimize(Q[0, 0]), constraints)
    params = {"A": As, "e": es, "lambda_top": lam_top, "lambda_bottom": lam_bottom}
    return problem, params, {"Q": Q}


class _Programs:
    """The compiled programs of one box, one per vertex count (cvxpy caches the compilation of a
    DPP problem, so every re-solve only substitutes the parameters). Not shared between boxes:
    a module-level cache would be shared by sweep threads."""

    def __init__(self) -> None:
        self._by_count: dict[int, tuple[Any, dict[str, Any], dict[str, Any]]] = {}

    def get(self, count: int) -> tuple[Any, dict[str, Any], dict[str, Any]]:
        if count not in self._by_count:
            import cvxpy as cp

            self._by_count[count] = build_program(cp, count)
        return self._by_count[count]


def _ellipsoid_stage(programs: _Programs, vertices: list[Vertex], rho_lo: Fraction,
                     sigma0: tuple[Fraction, Fraction]) -> tuple[dict[str, Any] | None, dict[str, Any]]:
    """One common ellipsoid for the box's vertices (the point class's line search in lambda)."""
    from lyapcheck.sos import sdp

    start = time.perf_counter()
    sc = scaling.choose([a for a, _ in vertices])
    problem, params, var = programs.get(len(vertices))
    # solved with the longest disturbance column of unit length (Q = kappa^2 Q~), as the point class
    norm = max(float(np.linalg.norm(sc.vector_to_scaled(e))) for _, e in vertices)
    kappa = exact.to_rational(norm, 6) if norm > 0 else Fraction(1)
    for (a, e), pa, pe in zip(vertices, params["A"], params["e"]):
        pa.value = sc.matrix_to_scaled(a)
        pe.value = (sc.vector_to_scaled(e) / float(kappa)).reshape(2, 1)
    solves = 0
    outcomes: dict[str, int] = {}

    def attempt(lam: float) -> ultimate.Candidate | None:
        nonlocal solves
        for name, value in ultimate.lambda_values(lam).items():
            params[name].value = value
        report = sdp.solve(problem)
        solves += 1
        outcomes[report.outcome] = outcomes.get(report.outcome, 0) + 1
        Q = var["Q"].value
        if report.outcome in ("optimal", "inaccurate") and Q is not None and float(Q[0, 0]) > 0:
            return float(Q[0, 0]), lam, np.array(Q), report.outcome == "optimal"
        return None

    candidates = ultimate.line_search(attempt)
    meta: dict[str, Any] = {"solves": solves, "outcomes": outcomes, "vertices": len(vertices),
                            "beta": str(sc.beta), "time_scale": str(sc.time)}
    stage: dict[str, Any] | None = None
    # as solved first; then, where every candidate failed the exact check by a hair (on some
    # floating-point platforms the rounded Q's top block sits at +1e-11 relative), each Q inflated
    # by 1 + d: that keeps the LMI's top block negative and shrinks the disturbance term, at a cost
    # of sqrt(1 + d) on this stage's bound. The exact check decides every candidate
    for inflation in (0.0, *tol.BOX_STAGE_Q_INFLATIONS):
        for _, lam, q_scaled, _ in candidates:
            P = ultimate.p_from_q(sc, kappa, q_scaled * (1 + inflation))
            if P is None or P[0][0] * P[1][1] - P[0][1] ** 2 <= 0:
                continue
            eps_sq, y_sq = _bounds_of(P, sigma0)
            candidate = {"P": exact.to_json(P), "lambda": str(exact.to_rational(lam, 6) * sc.time),
                         "rho_lo": str(rho_lo), "eps_bound_sq": str(eps_sq), "y_bound_sq": str(y_sq),
                         "vertices": vertices_to_json(vertices)}
            ok, why = check_stage(candidate, vertices, rho_lo, sigma0)
            meta["exact_check"] = why
            if ok:
                stage = candidate
                if inflation:
                    meta["q_inflation"] = inflation
                break
        if stage is not None:
            break
    meta["wall_seconds"] = time.perf_counter() - start
    return stage, meta


def _advance(stage: Mapping[str, Any], eps_bound: Fraction, y_bar: Fraction) -> tuple[Fraction, Fraction, bool]:
    """The chain's next (eps bound, ybar) and whether ybar improved by 1 % (as ultimate.run)."""
    new_eps = exact.sqrt_upper(Fraction(stage["eps_bound_sq"]))
    new_y = exact.sqrt_upper(Fraction(stage["y_bound_sq"])) * ultimate.INFLATE
    return min(eps_bound, new_eps), min(y_bar, new_y), new_y < y_bar * Fraction(99, 100)


def certify_ultimate_box(problem: Problem, box: ParameterBox, dynamics: str = "derived") -> dict[str, Any]:
    """``limsup |eps| <= bound`` for every gain set in ``box`` (module docstring); a JSON-ready result."""
    if problem.d_max is None:
        return {"status": "not_applicable", "property": "ultimate_bound",
                "summary": "needs the disturbance bound d* (--d-max or [disturbance] d_max)"}
    start = time.perf_counter()
    systems = corner_systems(problem, box, dynamics)
    box0 = box_stage(systems)
    if box0 is None:
        return {"status": "not_certified", "property": "ultimate_bound", "box": box.to_json(),
                "summary": "the comparison-lemma box needs A = [[a11, a12], [0, a22]] with a11, a22 < 0 "
                           "at every corner of the box"}
    ranges = entry_ranges(systems)
    eps_bound, y_bar = Fraction(box0["eps_bound"]), Fraction(box0["y_bound"])
    stages: list[dict[str, Any]] = []
    metas: list[dict[str, Any]] = []
    if problem.d_max > 0:  # as the point class: with d* = 0 the stage-0 box is the answer
        programs = _Programs()
        for _ in range(ultimate.MAX_STAGES):
            rho_lo = rho_lower_box(systems, y_bar)
            stage, meta = _ellipsoid_stage(programs, stage_vertices(ranges, rho_lo), rho_lo, ranges["sigma0"])
            metas.append(meta)
            if stage is None:
                break
            stages.append(stage)
            eps_bound, y_bar, improved = _advance(stage, eps_bound, y_bar)
            if not improved:
                break
    from lyapcheck.paper import claims

    return claims.decided_box("ultimate_bound", {
        "status": "certified", "property": "ultimate_bound", "box": box.to_json(), "summary": "",
        "eps_bound_m": float(eps_bound), "eps_bound_exact": str(eps_bound),
        "box_eps_bound_m": float(Fraction(box0["eps_bound"])), "ellipsoid_stages": len(stages),
        "certificate": {"box_stage": box0, "stages": stages, "eps_bound": str(eps_bound)},
        "solver": {"stages": metas, "wall_seconds": time.perf_counter() - start}}, box)


def verify_ultimate_box(problem: Problem, box: ParameterBox, dynamics: str,
                        result: Mapping[str, Any]) -> tuple[bool, str]:
    """Re-derive stage 0 and every stage's vertices from the box; re-check everything exactly."""
    if problem.d_max is None:
        return False, "the certificate's inputs have no d*"
    if "box" in result and result["box"] != box.to_json():
        return False, "the result is for a different box"
    cert = result["certificate"]
    systems = corner_systems(problem, box, dynamics)
    fresh = box_stage(systems)
    if fresh is None:
        return False, "the dynamics at some corner do not have the structure this class needs"
    box0 = cert["box_stage"]
    if any(Fraction(box0[k]) < Fraction(fresh[k]) for k in BOX_KEYS):
        return False, "the box-stage bounds are below the maxima of the point bounds over the box's corners"
    ranges = entry_ranges(systems)
    best, y_bar = Fraction(box0["eps_bound"]), Fraction(box0["y_bound"])
    if cert["stages"] and problem.d_max == 0:
        return False, "ellipsoid stages need d* > 0"
    for i, stage in enumerate(cert["stages"]):
        vertices = stage_vertices(ranges, Fraction(stage["rho_lo"]))
        if stage.get("vertices") is not None and stage["vertices"] != vertices_to_json(vertices):
            return False, f"ellipsoid stage {i + 1}: the stored vertices are not those of the box"
        ok, why = check_stage(stage, vertices, rho_lower_box(systems, y_bar), ranges["sigma0"])
        if not ok:
            return False, f"ellipsoid stage {i + 1}: {why}"
        best, y_bar, _ = _advance(stage, best, y_bar)
    claimed = Fraction(cert["eps_bound"])
    if claimed < best:
        return False, f"stated eps bound {float(claimed):.6g} m is below what the stages prove ({float(best):.6g} m)"
    if "eps_bound_exact" in result and Fraction(result["eps_bound_exact"]) < best:
        return False, "the stated eps_bound_exact is below what the stages prove"
    if "eps_bound_m" in result and not float(result["eps_bound_m"]) >= float(best) * (1 - 1e-15):
        return False, "the stated eps_bound_m is below what the stages prove"
    return True, (f"limsup |eps| <= {float(claimed):.6g} m for every gain set of the box follows exactly "
                  f"(box stage + {len(cert['stages'])} ellipsoid stage(s))")
