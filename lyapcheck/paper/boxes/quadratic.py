"""``ges`` and ``sector_ges`` for every gain set of a box.

``ges`` first searches a certificate whose matrices are polynomials in the gains
(:mod:`lyapcheck.paper.boxes.ges_param`, the stronger form), then one certificate common to the
whole box (below); ``verify`` re-checks either form. ``sector_ges`` is one quadratic ``V`` for the
whole box.

Why the common certificate is exact. In the scaled coordinates of :mod:`lyapcheck.paper.conditions.ges` the error dynamics
depend on the gains only through three numbers,

    c = a12/(sigma0 |a11|),   a = -a22/|a11|,   b = sigma0 U/(Delta |a11|),

and the generated dynamics (:mod:`symbolic._generated`) make each entry ``a11``, ``a12``,
``a22`` a signed monomial in the positive parameters (``tests/test_boxes.py`` checks this on the
derivation). So ``c``, ``a`` and ``b`` are monomials too, hence monotone in every parameter, and
over a box their ranges are the intervals spanned by their values at the box's corners. The
``ges`` conditions are affine in ``(c, a, b)`` for a fixed certificate (``A(w)`` is affine in
them, ``M(w)`` does not depend on them), and positive definiteness is preserved by convex
combinations, so a certificate checked exactly at the eight corners of the ``(c, a, b)`` box
holds at every gain set of the parameter box. The decay rate in seconds is
``mu |a11| / 2 >= mu min|a11| / 2`` and ``k = sqrt(c2/c1)`` does not depend on the point.

No box is ever ``refuted`` for GES itself, and that is a fact of the model, not a gap:
``c = -1`` identically (``tests/test_boxes.py`` checks it on the derivation), so the
linearisation ``[[-1, c], [b, -a]]`` at the origin has ``det = a + b > 0`` at every positive gain
set, and the one exact local obstruction to GES (a non-Hurwitz linearisation) never occurs. A
refutation would need a global argument (trajectories whose decay has no uniform exponential
envelope); none is known for these dynamics. ``sector_ges`` is refuted over a box when a corner's
own sector matrices have no common quadratic Lyapunov function (Shorten-Narendra).
"""

from __future__ import annotations

import math
from fractions import Fraction
from typing import Any, Mapping, Sequence

from lyapcheck.paper import claims
from lyapcheck.paper.boxes.box import ParameterBox, corner_problems, scaled_hull, stored_hull
from lyapcheck.paper.conditions.base import sector_polytope
from lyapcheck.paper.params import Problem
from lyapcheck.paper.system import build_system


def certify_ges_box(problem: Problem, box: ParameterBox, dynamics: str) -> dict[str, Any]:
    """``ges`` over ``box``: a certificate polynomial in the gains, else a common one (module docstring)."""
    from lyapcheck.paper.boxes import ges_param

    result = ges_param.certify(problem, box, dynamics)
    if result["status"] == "certified":
        return result
    common = certify_common_ges_box(problem, box, dynamics)
    if common["status"] != "certified":
        common["summary"] = f"{result['summary']}; {common['summary']}"
        common.setdefault("solver", {}).setdefault("solves", [])[:0] = result.get("solver", {}).get("solves", [])
    return common


def certify_common_ges_box(problem: Problem, box: ParameterBox, dynamics: str) -> dict[str, Any]:
    """``ges`` over ``box`` with one state-dependent quadratic ``V`` common to the whole box."""
    from lyapcheck.paper.conditions import ges

    hull = scaled_hull(problem, box, dynamics)
    if hull is None:
        return {"status": "not_certified", "property": "GES",
                "summary": "the dynamics at some corner do not have the structure this class needs"}
    vertices, ts_min = hull
    log: list[dict[str, Any]] = []
    cert = ges.search(vertices, log)
    if cert is None:
        return {"status": "not_certified", "property": "GES", "box": box.to_json(),
                "summary": f"no state-dependent quadratic V common to the box was found ({box.describe()}); "
                           "this is not a proof that GES fails anywhere in it", "solver": {"solves": log}}
    mu, c1, c2 = (Fraction(cert[k]) for k in ("mu_scaled", "c1", "c2"))
    k = math.sqrt(float(c2 / c1))
    rate = float(mu * ts_min) / 2
    return claims.decided_box("ges", {
        "status": "certified", "property": "GES", "summary": "", "box": box.to_json(), "k": k,
        "decay_rate_per_s": rate,
        "certificate": {**cert, "vertices": [[str(v.c), str(v.a), str(v.b)] for v in vertices],
                        "time_scale_min": str(ts_min)},
        "solver": {"solves": log}}, box)


def _stored_quadratic(problem: Problem, box: ParameterBox, dynamics: str,
                      result: Mapping[str, Any]) -> tuple[Mapping[str, Any], list[Any], Fraction, Any] | str:
    """The certificate, its ``(c, a, b)`` vertices re-derived from the box, ``min |a11|`` and ``P``
    (the common start of the ``ges`` and ``sector_ges`` box checks), or why the hull differs."""
    from lyapcheck import exact

    cert = result["certificate"]
    hull = stored_hull(problem, box, dynamics, cert)
    if isinstance(hull, str):
        return hull
    vertices, ts_min = hull
    return cert, vertices, ts_min, exact.from_json(cert["P"])


def verify_ges_box(problem: Problem, box: ParameterBox, dynamics: str, result: Mapping[str, Any]) -> tuple[bool, str]:
    """Re-check a ``ges`` box certificate exactly: a parametric one over the whole box
    (:func:`lyapcheck.paper.boxes.ges_param.verify`), a common one at every vertex of the
    ``(c, a, b)`` box re-derived from the parameter box."""
    from lyapcheck.paper.conditions import ges

    cert = result.get("certificate")
    if isinstance(cert, Mapping) and cert.get("form") == "parametric":
        from lyapcheck.paper.boxes import ges_param

        return ges_param.verify(problem, box, dynamics, result)

    stored = _stored_quadratic(problem, box, dynamics, result)
    if isinstance(stored, str):
        return False, stored
    cert, vertices, ts_min, P = stored
    ells = [[Fraction(x) for x in ell] for ell in cert["l"]]
    mu, c1, c2 = (Fraction(cert[k]) for k in ("mu_scaled", "c1", "c2"))
    for v in vertices:
        ok, why = ges.exact_check(v, P, ells, mu, c1, c2)
        if not ok:
            return False, f"at (c, a, b) = ({float(v.c):.6g}, {float(v.a):.6g}, {float(v.b):.6g}): {why}"
    # the stated envelope is the claim users read: k no smaller, the rate no larger than proved
    if "k" in result and not Fraction(float(result["k"])) ** 2 >= c2 / c1 * (1 - Fraction(1, 10**12)):
        return False, f"the stated k = {result['k']} is below sqrt(c2/c1) = {math.sqrt(float(c2 / c1))}"
    if "decay_rate_per_s" in result and \
            not Fraction(float(result["decay_rate_per_s"])) <= mu * ts_min / 2 * (1 + Fraction(1, 10**12)):
        return False, f"the stated decay rate {result['decay_rate_per_s']} exceeds the certified {float(mu * ts_min) / 2}"
    return True, f"the ges conditions hold exactly at all {len(vertices)} vertices of the (c, a, b) box"


# -- sector_ges over a box: one quadratic V for the whole polytope ------------------------------------
#: vertices of the box's matrix polytope handed to the solver (repeated to this count: the
#: stored program ``sector_8`` has eight vertex parameters)
SECTOR_BOX_VERTICES = 8


def _eigen_bounds(P: Any) -> tuple[Fraction, Fraction] | None:
    """Rationals ``c1 <= lambda_min(P)``, ``c2 >= lambda_max(P)``, checked exactly (``c1 > 0``)."""
    import numpy as np

    from lyapcheck import exact

    lam = np.linalg.eigvalsh(np.array(exact.to_float(P)))
    c1 = exact.to_rational(float(lam[0]) * (1 - 1e-6), 8)
    c2 = exact.to_rational(float(lam[1]) * (1 + 1e-6), 8)
    eye = exact.matrix([[1, 0], [0, 1]])
    if c1 <= 0 or not exact.is_positive_definite(exact.add(P, exact.scale(-c1, eye))) \
            or not exact.is_positive_definite(exact.add(exact.scale(c2, eye), exact.scale(Fraction(-1), P))):
        return None
    return c1, c2


def certify_sector_box(problem: Problem, box: ParameterBox, dynamics: str) -> dict[str, Any]:
    """``sector_ges`` for every gain set in ``box``: a common ``P`` over :func:`sector_polytope`.

    Refuted (exactly) when a corner's own two sector matrices have no common quadratic Lyapunov
    function (Shorten-Narendra): that corner is a gain set of the box, so no ``P`` serves the box.
    """
    from lyapcheck import exact
    from lyapcheck.paper.conditions import sector
    from lyapcheck.paper.conditions.sos import scaled_dynamics

    hull = scaled_hull(problem, box, dynamics)
    if hull is None:
        return {"status": "not_certified", "property": "GES",
                "summary": "the dynamics at some corner do not have the structure this class needs"}
    vertices, ts_min = hull
    # the corners of the parameter box are gain sets of the box (the (c, a, b) hull's vertices
    # need not be: they combine the ranges independently)
    for corner, p in zip(box.corners(), corner_problems(problem, box)):
        v = scaled_dynamics(build_system(p, dynamics))
        assert v is not None  # scaled_hull succeeded at every corner
        refuted = sector.refutation([exact.matrix([[-1, v.c], [0, -v.a]]), exact.matrix([[-1, v.c], [v.b, -v.a]])])
        if refuted is not None:
            return claims.decided_box("sector_ges", {
                "status": "refuted", "property": "GES", "box": box.to_json(),
                "refutation": {**refuted, "point": {name: str(value) for name, value in corner.items()}},
                "summary": ""}, box)
    polytope = sector_polytope(vertices)
    padded = (polytope * SECTOR_BOX_VERTICES)[:SECTOR_BOX_VERTICES]
    P, rate, margin, report = sector.certify_polytope(padded)
    bounds = None if P is None or not rate else _eigen_bounds(P)
    if P is None or not rate or bounds is None:
        return {"status": "not_certified", "property": "GES", "box": box.to_json(),
                "summary": f"no quadratic V common to the box was found ({box.describe()}, margin "
                           f"{margin if margin is not None else 'n/a'}); this is not a proof that GES fails",
                "solver": {"solves": [report.to_json()]}}
    c1, c2 = bounds
    return claims.decided_box("sector_ges", {
        "status": "certified", "property": "GES", "summary": "", "box": box.to_json(),
        "k": math.sqrt(float(c2 / c1)), "decay_rate_per_s": float(rate * ts_min),
        "certificate": {"P": exact.to_json(P), "decay_rate_scaled": str(rate), "c1": str(c1), "c2": str(c2),
                        "vertices": [[str(v.c), str(v.a), str(v.b)] for v in vertices],
                        "time_scale_min": str(ts_min)},
        "solver": {"solves": [report.to_json()]}}, box)


def verify_sector_box(problem: Problem, box: ParameterBox, dynamics: str,
                       result: Mapping[str, Any]) -> tuple[bool, str]:
    from lyapcheck import exact
    from lyapcheck.paper.conditions import sector

    stored = _stored_quadratic(problem, box, dynamics, result)
    if isinstance(stored, str):
        return False, stored
    cert, vertices, ts_min, P = stored
    if len(P) != 2 or not exact.is_symmetric(P):
        return False, "P must be a symmetric 2x2 matrix"
    rate, c1, c2 = (Fraction(cert[k]) for k in ("decay_rate_scaled", "c1", "c2"))
    if rate <= 0 or c1 <= 0:
        return False, "the decay rate and c1 must be positive"
    eye = exact.matrix([[1, 0], [0, 1]])
    if not (exact.is_positive_definite(exact.add(P, exact.scale(-c1, eye)))
            and exact.is_positive_definite(exact.add(exact.scale(c2, eye), exact.scale(Fraction(-1), P)))):
        return False, "c1 I < P < c2 I does not hold"
    polytope = sector_polytope(vertices)
    ok, why = sector.exact_check(polytope, P, rate)
    if not ok:
        return False, why
    k = math.sqrt(float(c2 / c1))
    if "k" in result and not float(result["k"]) >= k * (1 - 1e-12):
        return False, f"the stated k = {result['k']} is below sqrt(c2/c1) = {k}"
    if "decay_rate_per_s" in result and not float(result["decay_rate_per_s"]) <= float(rate * ts_min) * (1 + 1e-12):
        return False, f"the stated decay rate {result['decay_rate_per_s']} exceeds the certified {float(rate * ts_min)}"
    return True, f"one P > 0 decreases at all {len(polytope)} vertices of the box's matrix polytope, exactly"
