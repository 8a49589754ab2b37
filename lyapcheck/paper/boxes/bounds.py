"""A certified ultimate bound on ``|eps|`` for every gain set of a box (class ``sos_bound``).

The point certificate (:mod:`lyapcheck.paper.conditions.sos_bound`) proves ``limsup |eps| <= Delta
sqrt(B)`` from three exact identities in the balanced scaled coordinates. Over a box of gains:

* the field ``(g_y, g_r, q)`` is affine in ``(c, a, b)`` (:class:`ScaledDynamics.fields`), and the
  balancing ``r = beta r~``, time ``/ omega`` is linear for FIXED rationals ``beta, omega``
  (chosen once for the box);
* the disturbance enters as ``- tau (k^2 - w^2)`` with ``k = |E_0| d* / (Delta |a11| omega)``:
  affine in ``k^2`` for a fixed multiplier ``tau``;

so, for a fixed ``V``, ``tau``, ``lambda``, the dissipation polynomial is affine in
``(c, a, b, k^2)``. ``c, a, b`` and ``k`` are monomials in the gains (:mod:`lyapcheck.paper.boxes.quadratic`), so
over the box they range over the intervals spanned at its corners, and every gain set's
``(c, a, b, k^2)`` is a convex combination of the vertices of that product of intervals. One
``V`` (with ``tau``, ``lambda``, ``B`` and the output Gram matrix common) and, at each vertex, a
positive definite Gram matrix of the dissipation polynomial give the identity at every gain set
with the same convex combination of the Gram matrices, which is positive definite. Hence
``limsup |eps| <= Delta sqrt(B) <= Delta_max sqrt(B)`` for every gain set in the box, from every
initial condition and every ``|d_perp| <= d*`` (the unsaturated loop, as in the point class).

The search runs in the point class's conditioned coordinates (``sos_bound``'s "Conditioning":
``beta`` a fraction of the box's ``sqrt(b)``, the disturbance scaled by one ``kappa`` for the box,
the multipliers mapped back exactly), so the certificate and :func:`check` are in ``w``.
"""

from __future__ import annotations

import itertools
import math
from fractions import Fraction
from typing import Any, Mapping

import numpy as np

from lyapcheck import exact
from lyapcheck.paper import poly
from lyapcheck.paper.boxes.box import ParameterBox, corner_problems
from lyapcheck.paper.conditions.sos import ScaledDynamics, is_sign_symmetric
from lyapcheck.paper.params import Problem
from lyapcheck.paper.system import build_system


def _box_data(problem: Problem, box: ParameterBox, dynamics: str) -> dict[str, Any] | None:
    """Ranges of ``c, a, b, k`` over the box (exact), ``Delta_max`` and the box's ``root ~ sqrt(b)``."""
    from lyapcheck.paper.conditions.sos import scaled_dynamics

    rows = []
    for p in corner_problems(problem, box):
        system = build_system(p, dynamics)
        dyn = scaled_dynamics(system)
        if dyn is None or system.d_max <= 0:
            return None
        k = abs(system.E[0]) * system.d_max / (system.delta * dyn.time_scale)
        rows.append((dyn.c, dyn.a, dyn.b, k, system.delta))
    ranges = [(min(r[i] for r in rows), max(r[i] for r in rows)) for i in range(4)]
    b_lo, b_hi = ranges[2]
    root = exact.to_rational(math.sqrt(math.sqrt(float(b_lo) * float(b_hi))), 4)  # ~ sqrt(b), geometric middle
    return {"ranges": ranges, "delta_max": max(r[4] for r in rows), "root": max(root, Fraction(1))}


def _vertices(ranges: list[tuple[Fraction, Fraction]]) -> list[tuple[Fraction, ...]]:
    """The vertices of the product of the ``c, a, b, k`` intervals (``k`` stands for ``k^2``:
    ``k -> k^2`` is monotone on ``k >= 0``, so the end points are the same), repeats removed."""
    return list(dict.fromkeys(itertools.product(*((lo, hi) for lo, hi in ranges))))


def _build(cp: Any, tables: list[dict[str, Any]], k2s: list[float], beta: float) -> tuple[Any, dict, Any]:
    """The point program of ``sos_bound`` with one dissipation block per vertex (common V, tau, B),
    over sign-symmetric certificates as the point search (``sos_bound.build_parity_program``: at
    +-2 % around the paper the same bound to 9 digits, in 5.6 s instead of 10.1 s); the decay rate
    is a Parameter, so the program is compiled once for the rates of LAMBDA_GRID."""
    from lyapcheck.paper.conditions import sos_bound as sb

    # sign-symmetric certificates only (sos_bound.build_parity_program: the same optimum, Gram
    # matrices block diagonal by monomial parity, the odd monomials' identities hold by symmetry)
    cons: list[Any] = []
    blocks: dict[str, Any] = {}
    QV, T, QE = (sb.positive_parity_gram(cp, basis, name, cons, blocks)
                 for name, basis in (("Q_V", sb.Z_V), ("T", sb.Z_T), ("Q_E", sb.Z_E)))
    QDs = [sb.positive_parity_gram(cp, sb.Z_D, f"Q_D{i}", cons, blocks) for i in range(len(tables))]
    B = cp.Variable()
    lam = cp.Parameter(nonneg=True)
    for QD, table, k2 in zip(QDs, tables, k2s):  # one dissipation block per vertex
        cons += sb.dissipation_constraints(QD, QV, T, {m: table[sb._param_name(m)] for m in sb.EVEN_MONOS_D}, lam, k2,
                                           cp, monomials=sb.EVEN_MONOS_D)
    cons += sb.even_output_constraints(QE, QV, B, beta, beta * beta)
    problem = cp.Problem(cp.Minimize(B), cons)
    return problem, {"Q_V": QV, "T": T, "Q_E": QE, "Q_D": QDs, "B": B}, lam


def _fields(vertex: tuple[Fraction, ...], beta: Fraction, omega: Fraction) -> tuple[poly.Poly, poly.Poly, poly.Poly]:
    from lyapcheck.paper.conditions.sos_bound import balanced_fields

    c, a, b, _ = vertex
    return balanced_fields(ScaledDynamics(time_scale=Fraction(1), c=c, a=a, b=b), beta, omega)


class _Search:
    """The box program in one set of search coordinates (``sos_bound``'s "Conditioning"), compiled
    once, and the rounding of its solutions to exact certificates in ``w``."""

    def __init__(self, cp: Any, vertices: list[tuple[Fraction, ...]],
                 coords: tuple[Fraction, Fraction, Fraction]) -> None:
        from lyapcheck.paper.conditions import sos_bound as sb

        self.vertices = vertices
        self.beta, self.omega, self.kappa = coords
        # |w~| <= k / kappa at each vertex
        self.fields = [sb.search_fields(_fields(v, self.beta, self.omega), self.kappa) for v in vertices]
        # the program searches sign-symmetric certificates (_build): ScaledDynamics.fields are odd, q even
        assert all(is_sign_symmetric(f) for f in self.fields)
        self.k_scaled = [v[3] / self.omega / self.kappa for v in vertices]
        tables = [sb.dynamics_data(f, self.beta) for f in self.fields]
        self.program, self.variables, self.lam = _build(cp, tables, [float(k * k) for k in self.k_scaled],
                                                        float(self.beta))

    def attempt(self, lam: float, delta_max: Fraction) -> tuple[dict[str, Any] | None, str]:
        """Solve at decay rate ``lam``; the exactly checked certificate (or None) and the solver's word."""
        from lyapcheck import tolerances as tol
        from lyapcheck.sos import sdp
        from lyapcheck.paper.conditions import sos_bound as sb

        var = self.variables
        self.lam.value = lam
        outcome = sdp.solve(self.program, max_iter=tol.SOS_BOUND_MAX_ITER).raw_status
        # an inaccurate solution is still a candidate: the exact check below is the judge
        if var["B"].value is None or outcome == "solver_error":
            return None, outcome
        values = {name: var[name].value for name in ("B", "Q_V", "T", "Q_E")}
        r = sb.round_solution(values, [QD.value for QD in var["Q_D"]], lam, self.beta,
                              list(zip(self.fields, self.k_scaled)))
        if r is None:
            return None, outcome
        cert = {"lambda": str(r.lam), "B": str(r.B), "beta": str(self.beta), "omega": str(self.omega),
                "Q_V": exact.to_json(r.QV), "T": exact.to_json(sb.unscaled(r.T, sb.Z_T, self.kappa, 2)),
                "Q_E": exact.to_json(r.QE), "Q_D": [exact.to_json(sb.unscaled(QD, sb.Z_D, self.kappa, 0)) for QD in r.QDs],
                "vertices": [[str(x) for x in v] for v in self.vertices], "delta_max": str(delta_max)}
        return (cert, outcome) if check(cert)[0] else (None, outcome)


def certify_bound_box(problem: Problem, box: ParameterBox, dynamics: str = "derived") -> dict[str, Any]:
    """``limsup |eps| <= bound`` for every gain set in ``box`` (module docstring); a JSON-ready result."""
    import cvxpy as cp

    from lyapcheck.paper.conditions import sos_bound as sb

    if problem.d_max is None:
        return {"status": "not_applicable", "property": "ultimate_bound",
                "summary": "needs the disturbance bound d* (--d-max or [disturbance] d_max)"}
    try:
        data = _box_data(problem, box, dynamics)
        if data is None:
            return {"status": "not_certified", "property": "ultimate_bound",
                    "summary": "d* is zero or the dynamics at some corner do not have the structure this class needs"}
        vertices = _vertices(data["ranges"])

        def search_at(scale: sb.SearchScale) -> _Search:
            return _Search(cp, vertices, sb.coordinates_at(data["root"], data["ranges"][3][1], scale))

        # the first is built here, so that a box out of the double range is said so
        searches = {sb.SEARCH_SCALES[0]: search_at(sb.SEARCH_SCALES[0])}
    except OverflowError:  # the solver works in doubles; the exact data are fine, the search is not
        return {"status": "not_certified", "property": "ultimate_bound", "box": box.to_json(),
                "summary": f"the box's scaled dynamics leave the double range ({box.describe()}); no search was "
                           "run (a narrower box may fit)"}
    best: dict[str, Any] | None = None
    log: list[dict[str, Any]] = []
    # as the point class: per decay rate, the coordinates of SEARCH_SCALES in order until one
    # certifies; each program is compiled once (the rate is a Parameter)
    for lam in sb.LAMBDA_GRID:
        for scale in sb.SEARCH_SCALES:
            if scale not in searches:
                try:
                    searches[scale] = search_at(scale)
                except OverflowError:
                    continue
            cert, outcome = searches[scale].attempt(lam, data["delta_max"])
            log.append({"lambda": lam, "beta": str(searches[scale].beta), "outcome": outcome})
            if cert is None:
                continue
            bound = data["delta_max"] * exact.sqrt_upper(Fraction(cert["B"]))
            if best is None or bound < Fraction(best["eps_bound"]):
                best = {**cert, "eps_bound": str(bound)}
            break
    if best is None:
        return {"status": "not_certified", "property": "ultimate_bound", "box": box.to_json(),
                "summary": f"no polynomial dissipation certificate common to the box was found ({box.describe()}); "
                           "this is not a proof that the bound fails", "solver": {"solves": log}}
    from lyapcheck.paper import claims

    bound = Fraction(best["eps_bound"])
    return claims.decided_box("sos_bound", {
        "status": "certified", "property": "ultimate_bound", "box": box.to_json(), "summary": "",
        "eps_bound_m": float(bound), "eps_bound_exact": str(bound), "certificate": best,
        "solver": {"solves": log}}, box)


def check(cert: Mapping[str, Any]) -> tuple[bool, str]:
    """Exact re-check of the common certificate at every stored vertex (no solver)."""
    from lyapcheck.paper.conditions import sos_bound as sb

    vertices = [tuple(Fraction(x) for x in v) for v in cert["vertices"]]
    if len(cert["Q_D"]) != len(vertices):
        return False, "one dissipation Gram matrix per vertex is needed"
    for vertex, QD in zip(vertices, cert["Q_D"]):
        c, a, b, k = vertex
        point = {**cert, "Q_D": QD}
        ok, why = sb.check(ScaledDynamics(time_scale=Fraction(1), c=c, a=a, b=b), k, point)
        if not ok:
            return False, f"at (c, a, b, k) = ({float(c):.6g}, {float(a):.6g}, {float(b):.6g}, {float(k):.6g}): {why}"
    return True, f"the dissipation and output identities hold with positive definite Gram matrices at all {len(vertices)} vertices"


def verify_bound_box(problem: Problem, box: ParameterBox, dynamics: str, result: Mapping[str, Any]) -> tuple[bool, str]:
    """Re-derive the vertices and ``Delta_max`` from the box, re-check exactly, and the stated bound."""
    cert = result["certificate"]
    if problem.d_max is None:
        return False, "the certificate's inputs have no d*"
    data = _box_data(problem, box, dynamics)
    if data is None:
        return False, "d* is zero or the dynamics at some corner do not have the structure this class needs"
    stored = {tuple(Fraction(x) for x in v) for v in cert["vertices"]}
    if stored != set(_vertices(data["ranges"])) or Fraction(cert["delta_max"]) != data["delta_max"]:
        return False, "the stored (c, a, b, k) vertices or Delta_max do not match the box"
    ok, why = check(cert)
    if not ok:
        return False, why
    if Fraction(cert["eps_bound"]) < data["delta_max"] * exact.sqrt_upper(Fraction(cert["B"])):
        return False, "the stated eps bound is below Delta_max sqrt(B)"
    if "eps_bound_m" in result and not float(result["eps_bound_m"]) >= float(Fraction(cert["eps_bound"])) * (1 - 1e-15):
        return False, "the stated eps_bound_m is below the certificate's bound"
    return True, why
