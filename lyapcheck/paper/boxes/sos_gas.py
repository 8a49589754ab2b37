"""Global asymptotic stability for every gain set of a box (class ``sos_gas``, one polynomial V).

The point certificate (:mod:`lyapcheck.paper.conditions.sos`) works in the scaled coordinates

    e' = -e + c r,     r' = -a r + b e / q(y),     q(y) = y^2 + 1,

with the field cleared of ``q``: ``g = q (y', r')`` is polynomial in ``(y, r)`` and AFFINE in
``(c, a, b)`` (:meth:`ScaledDynamics.fields`). It is a pair of exact Gram matrices
``Q_V > 0``, ``Q_W > 0`` with the polynomial identity

    -grad V . g - mu V q = z_W^T Q_W z_W,     V = z_V^T Q_V z_V.

Over a box of gains. ``c``, ``a`` and ``b`` are monomials in the gains (:mod:`lyapcheck.paper.boxes.quadratic`),
so over the box they range over the intervals spanned at its corners, and every gain set's
``(c, a, b)`` is a convex combination ``sum_k w_k v_k`` of the vertices ``v_k`` of the product of
those intervals. For a FIXED ``V`` (``Q_V``) and ``mu`` the target ``p = -grad V . g - mu V q`` is
affine in ``(c, a, b)``, so ``p(sum_k w_k v_k) = sum_k w_k p(v_k)``. With one ``Q_W^k > 0`` per
vertex satisfying the identity exactly at ``v_k``, the combination ``sum_k w_k Q_W^k`` is positive
definite (a convex combination of positive definite matrices) and satisfies the identity at the
gain set. Hence ``V`` is a common Lyapunov function: at every gain set of the box
``V' = -mu V - W/q`` in scaled time ``tau = |a11| t``, the origin is globally asymptotically
stable, and ``V`` decays at least like ``exp(-mu |a11| t) <= exp(-mu min|a11| t)`` in seconds
(``mu >= 0``; the box's ``min |a11|`` is exact, over the corners, since ``a11`` is a monomial too).

As for the point class this is GAS with a decay rate of ``V``, not GES: the quartic ``V`` gives no
bound linear in ``|x0|`` (see :mod:`lyapcheck.paper.conditions.sos`). A box that is not certified is
just that: no common ``V`` of degree <= 6 was found, which is not a proof that GAS fails anywhere.

Exactness, as at a point: the solver's ``Q_V`` is rounded to rationals, which fixes ``V`` and the
exact target at every vertex; each vertex's rounded ``Q_W`` is projected exactly onto the affine
set of Gram matrices of that target (:func:`sos.project_gram`), and every vertex is checked with
:func:`sos.exact_check`. Only an exact pass at every vertex counts.
"""

from __future__ import annotations

from fractions import Fraction
from typing import Any, Mapping, Sequence

import numpy as np

from lyapcheck import exact
from lyapcheck.paper import poly
from lyapcheck.paper.boxes.box import ParameterBox, scaled_hull, stored_hull
from lyapcheck.paper.conditions import sos
from lyapcheck.paper.conditions.sos import ScaledDynamics
from lyapcheck.paper.params import Problem


def _coefficient_rows(dyn: ScaledDynamics, deg_v: int) -> np.ndarray:
    """Row ``m``: the coefficient of monomial ``m`` in ``-grad V . g`` as a linear map of ``vec(Q_V)``
    (``mu = 0``; row-major ``vec``), from the point class's :func:`sos.program_data` (floats)."""
    data = sos.program_data(dyn, deg_v, 0.0)
    return np.stack([data[sos._param_name(m)].ravel() for m in sos.target_monomials(deg_v)])


def _decay_rows(deg_v: int) -> np.ndarray:
    """Row ``m``: the coefficient of ``m`` in ``-V q`` as a linear map of ``vec(Q_V)``.

    The same at every vertex (``q`` does not depend on the gains), and computed apart from
    :func:`_coefficient_rows` so that ``mu`` can be a parameter of the program: the target's
    coefficients are ``(A_0 + mu A_1) vec(Q_V)``, which is DPP (a parameter times an affine
    expression), so the program is compiled once per degree and re-solved for every ``mu``.
    """
    z_v, _ = sos.bases(deg_v)
    q: poly.Poly = {(2, 0): 1.0, (0, 0): 1.0}
    monos = sos.target_monomials(deg_v)
    row = {m: k for k, m in enumerate(monos)}
    out = np.zeros((len(monos), len(z_v) ** 2))
    for i, zi in enumerate(z_v):
        for j, zj in enumerate(z_v):
            zz = poly.monomial((zi[0] + zj[0], zi[1] + zj[1]))
            for m, c in sos.target(zz, {}, {}, q, 1.0).items():
                out[row[m], i * len(z_v) + j] += c
    return out


def _gram_rows(deg_v: int) -> np.ndarray:
    """Row ``m``: the 0/1 map ``vec(Q_W) -> `` coefficient of ``m`` in ``z_W^T Q_W z_W`` (row-major)."""
    _, z_w = sos.bases(deg_v)
    classes = poly.gram_classes(z_w)
    monos = sos.target_monomials(deg_v)
    out = np.zeros((len(monos), len(z_w) ** 2))
    for k, m in enumerate(monos):
        for i, j in classes.get(m, []):
            out[k, i * len(z_w) + j] = 1.0
    return out


def _build(cp: Any, vertices: Sequence[ScaledDynamics], deg_v: int) -> tuple[Any, dict[str, Any]]:
    """max t s.t. trace Q_V = 1, Q_V >= tI, Q_W^k >= tI and the identity at every vertex k, t <= 1."""
    z_v, z_w = sos.bases(deg_v)
    nv, nw = len(z_v), len(z_w)
    QV = cp.Variable((nv, nv), symmetric=True, name="Q_V")
    QWs = [cp.Variable((nw, nw), symmetric=True, name=f"Q_W_{k}") for k in range(len(vertices))]
    t = cp.Variable(name="t")
    mu = cp.Parameter(nonneg=True, name="mu")
    gram, decay = _gram_rows(deg_v), _decay_rows(deg_v)
    vec_v = cp.vec(QV, order="C")
    cons = [cp.trace(QV) == 1, QV >> t * np.eye(nv), t <= 1]
    for QW, v in zip(QWs, vertices):  # one Gram matrix of W per vertex, V common
        cons.append(QW >> t * np.eye(nw))
        cons.append(gram @ cp.vec(QW, order="C") == _coefficient_rows(v, deg_v) @ vec_v + mu * (decay @ vec_v))
    return cp.Problem(cp.Maximize(t), cons), {"Q_V": QV, "Q_W": QWs, "t": t, "mu": mu}


def _trial(prog: Any, var: Mapping[str, Any], vertices: Sequence[ScaledDynamics], deg_v: int,
           mu: Fraction, log: list[dict[str, Any]]) -> sos.Trial:
    """Solve at ``mu``: the solver's margin, and the exact check at every vertex of the rounded
    solution (:func:`_checked`), run when called (:func:`sos.best_decay_rate`)."""
    from lyapcheck.sos import sdp

    var["mu"].value = float(mu)
    report = sdp.solve(prog)  # Clarabel, no warm start, "may be inaccurate" warnings recorded as status
    entry: dict[str, Any] = {"degree": deg_v, "mu_scaled": str(mu), **report.to_json()}
    log.append(entry)
    # an inaccurate solution is still worth rounding: the exact check is the judge
    t = var["t"].value
    if report.raw_status not in ("optimal", "optimal_inaccurate") or t is None:
        entry["exact_check"] = "not attempted: the solver returned no point"
        return None, lambda: None
    entry["exact_check"] = "not run: a larger decay rate passed first"
    # the program's variables are overwritten by the next solve: the check keeps its own copies
    solution = {"t": float(t), "Q_V": np.array(var["Q_V"].value), "Q_W": [np.array(QW.value) for QW in var["Q_W"]]}
    return float(t), lambda: _checked(solution, vertices, deg_v, mu, entry)


def _checked(solution: Mapping[str, Any], vertices: Sequence[ScaledDynamics], deg_v: int, mu: Fraction,
             entry: dict[str, Any]) -> dict[str, Any] | None:
    """Round and project a solution, and check every vertex exactly (None unless all pass)."""
    t = solution["t"]
    if not t > 0:
        entry["exact_check"] = "not attempted: the solver returned no point with t > 0"
        return None
    z_v, z_w = sos.bases(deg_v)
    QV = exact.symmetrize(exact.rational_matrix(solution["Q_V"]))
    V = poly.gram_form(z_v, QV)
    grams = []
    for v, QW_value in zip(vertices, solution["Q_W"]):
        g_y, g_r, q = v.fields()
        QW = sos.project_gram(z_w, exact.symmetrize(exact.rational_matrix(QW_value)), sos.target(V, g_y, g_r, q, mu))
        if QW is None:
            entry["exact_check"] = "the target is not representable in the W basis"
            return None
        ok, why = sos.exact_check(v, deg_v, QV, QW, mu)
        if not ok:
            entry["exact_check"] = f"at (c, a, b) = ({float(v.c):.6g}, {float(v.a):.6g}, {float(v.b):.6g}): {why}"
            return None
        grams.append(QW)
    entry["exact_check"] = "passed"
    return {"degree": deg_v, "mu_scaled": str(mu), "Q_V": exact.to_json(QV),
            "Q_W": [exact.to_json(QW) for QW in grams],
            "basis_V": [list(m) for m in z_v], "basis_W": [list(m) for m in z_w], "margin": float(t)}


def _search(cp: Any, vertices: Sequence[ScaledDynamics], deg_v: int,
            log: list[dict[str, Any]]) -> dict[str, Any] | None:
    """A common V at ``mu = 0``, then the largest decay rate found as in :func:`sos.run`."""
    prog, var = _build(cp, vertices, deg_v)
    _, check = _trial(prog, var, vertices, deg_v, Fraction(0), log)
    cert = check()
    if cert is None:
        return None
    return sos.best_decay_rate(lambda mu: _trial(prog, var, vertices, deg_v, mu, log), cert)


def certify_gas_box(problem: Problem, box: ParameterBox, dynamics: str = "derived") -> dict[str, Any]:
    """GAS for every gain set in ``box`` by one polynomial V (module docstring); a JSON-ready result.

    Parameters
    ----------
    problem
        The problem; the parameters of ``box`` replace its values, the others are fixed.
    box
        The box of gains.
    dynamics
        Which error dynamics (as :func:`lyapcheck.paper.certification.build_system`).

    Returns
    -------
    dict
        ``status`` ``certified`` (with ``certificate``, ``degree`` and ``decay_rate_V_per_s``, a
        lower bound in 1/s on the decay rate of V at every gain set) or ``not_certified``; never
        ``refuted``.
    """
    import cvxpy as cp

    hull = scaled_hull(problem, box, dynamics)
    if hull is None:
        return {"status": "not_certified", "property": "GAS", "box": box.to_json(),
                "summary": "the dynamics at some corner do not have the structure this class needs"}
    vertices, ts_min = hull
    log: list[dict[str, Any]] = []
    for deg_v in sos.DEGREES:
        cert = _search(cp, vertices, deg_v, log)
        if cert is None:
            continue
        from lyapcheck.paper import claims

        return claims.decided_box("sos_gas", {
            "status": "certified", "property": "GAS", "box": box.to_json(), "summary": "",
            "decay_rate_V_per_s": float(Fraction(cert["mu_scaled"]) * ts_min), "degree": deg_v,
            "certificate": {**cert, "vertices": [[str(v.c), str(v.a), str(v.b)] for v in vertices],
                            "time_scale_min": str(ts_min)},
            "solver": {"solves": log}}, box)
    return {"status": "not_certified", "property": "GAS", "box": box.to_json(),
            "summary": f"no polynomial V of degree <= {sos.DEGREES[-1]} common to the box was found "
                       f"({box.describe()}); this is not a proof that GAS fails anywhere in it",
            "solver": {"solves": log}}


def _is_square(m: exact.Matrix, n: int) -> bool:
    return len(m) == n and all(len(row) == n for row in m)


def verify_gas_box(problem: Problem, box: ParameterBox, dynamics: str,
                   result: Mapping[str, Any]) -> tuple[bool, str]:
    """Re-derive the ``(c, a, b)`` vertices from the box and re-check the certificate exactly (no solver).

    Parameters
    ----------
    problem, box, dynamics
        As given to :func:`certify_gas_box`.
    result
        Its result (``status`` ``certified``).

    Returns
    -------
    tuple
        ``(valid, why)``.
    """
    cert = result["certificate"]
    hull = stored_hull(problem, box, dynamics, cert)
    if isinstance(hull, str):
        return False, hull
    _, ts_min = hull
    deg_v, why = sos.stored_degree_and_bases(cert)
    if why is not None:
        return False, why
    z_v, z_w = sos.bases(deg_v)
    mu = Fraction(cert["mu_scaled"])
    # with mu < 0 the identity would not make V decrease (sos.exact_check refuses it too; said here first)
    if mu < 0:
        return False, "the decay rate mu must be >= 0"
    if len(cert["Q_W"]) != len(cert["vertices"]):
        return False, "one Gram matrix of W per vertex is needed"
    QV = exact.from_json(cert["Q_V"])
    QWs = [exact.from_json(QW) for QW in cert["Q_W"]]
    # a malformed matrix must be an invalid certificate, not an IndexError in the Gram form
    if not _is_square(QV, len(z_v)) or not all(_is_square(QW, len(z_w)) for QW in QWs):
        return False, f"Q_V must be {len(z_v)}x{len(z_v)} and every Q_W {len(z_w)}x{len(z_w)}"
    # stored_hull checked the stored vertices are the box's, as a set: each is checked with its own Q_W
    for vertex, QW in zip(cert["vertices"], QWs):
        c, a, b = (Fraction(x) for x in vertex)
        ok, why = sos.exact_check(ScaledDynamics(time_scale=Fraction(1), c=c, a=a, b=b), deg_v, QV, QW, mu)
        if not ok:
            return False, f"at (c, a, b) = ({float(c):.6g}, {float(a):.6g}, {float(b):.6g}): {why}"
    certified = float(mu * ts_min)
    if "decay_rate_V_per_s" in result and not float(result["decay_rate_V_per_s"]) <= certified * (1 + 1e-12):
        return False, f"the stated decay rate {result['decay_rate_V_per_s']} exceeds the certified {certified}"
    if "degree" in result and (isinstance(result["degree"], bool) or result["degree"] != deg_v
                               or not isinstance(result["degree"], int)):
        return False, f"the stated degree must be the certificate's, the integer {deg_v}; got {result['degree']!r}"
    return True, (f"one V of degree {deg_v} with Q_V > 0 and, at all {len(cert['vertices'])} vertices of the "
                  "(c, a, b) box, Q_W > 0 and the SOS identity, exactly")
