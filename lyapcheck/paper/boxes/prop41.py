"""Proposition 4.1's conditions (eq. ``eq:stabCond`` and its ISS variant) for every gain set of a box.

The point classes (:mod:`lyapcheck.paper.conditions.prop41`) ask for ``P > 0`` with

    f(A, g, e) = lambda_min(-(A^T P + P A)) - g p12 - sqrt(p12^2 + p22^2) (g + e)  >  0,

``g = rho_sup = U/Delta`` and ``e = |E_0|`` (``e = 0`` for ``prop41_ges``). For a FIXED ``P``,
``f`` is concave in ``(A, g, e)``: ``lambda_min`` of a matrix affine in ``A`` is concave, and the
rest is affine. A concave function that is positive at the vertices of a polytope is positive on
all of it. Over a box of gains, ``A = [[a11, a12], [0, a22]]``, ``g`` and ``e`` have entries that
are signed monomials in the positive parameters (``tests/test_box_prop41.py`` checks this on the
derivation), so each ranges over the interval spanned by its values at the box's corners, and
every gain set's ``(a11, a12, a22, g, e)`` lies in the product of those intervals. One ``P``
checked exactly at every vertex of that product (:func:`prop41.exact_check`) therefore satisfies
the proposition's condition at every gain set of the box.

Refutation is by a point: a corner of the box is a gain set of the box, and where the exact
``Gamma_22`` bound (:func:`prop41.refutation`) shows that no ``P`` exists at that corner, no ``P``
serves the box. ``verify`` re-derives that refutation at the stated point.
"""

from __future__ import annotations

import itertools
import warnings
from dataclasses import replace
from fractions import Fraction
from typing import Any, Mapping

import numpy as np

from lyapcheck import exact
from lyapcheck.paper import claims
from lyapcheck.paper.boxes.box import ParameterBox, corner_problems, problem_at_point
from lyapcheck.paper.conditions.base import System
from lyapcheck.paper.params import Problem
from lyapcheck.paper.system import build_system

#: the entries that vary over a box, in the order a stored vertex lists them
VERTEX_KEYS: tuple[str, ...] = ("a11", "a12", "a22", "g", "e")
#: the program maximises the margin m up to this (relative to the data's scale), as the point class does
MARGIN_CAP = 10.0


def _entries(system: System, iss: bool) -> tuple[Fraction, ...]:
    a = system.A
    return (a[0][0], a[0][1], a[1][1], system.rho_sup, abs(system.E[0]) if iss else Fraction(0))


def _corner_systems(problem: Problem, box: ParameterBox, dynamics: str) -> list[System] | None:
    """The exact system at every corner, or None where ``A`` is not upper triangular."""

    systems = [build_system(p, dynamics) for p in corner_problems(problem, box)]
    return None if any(s.A[1][0] != 0 for s in systems) else systems


def box_vertices(systems: list[System], iss: bool) -> list[tuple[Fraction, ...]]:
    """The vertices of the product of the entries' intervals over the corners (repeats removed)."""
    rows = [_entries(s, iss) for s in systems]
    ranges = [(min(r[i] for r in rows), max(r[i] for r in rows)) for i in range(len(VERTEX_KEYS))]
    return list(dict.fromkeys(itertools.product(*ranges)))


def vertex_system(template: System, vertex: tuple[Fraction, ...]) -> System:
    """A :class:`System` whose ``A``, ``rho_sup`` and ``E_0`` are the vertex's (the rest as ``template``)."""
    a11, a12, a22, g, e = vertex
    return replace(template, A=((a11, a12), (Fraction(0), a22)), rho_sup=g, E=(e, template.E[1]))


def _solve(vertices: list[tuple[Fraction, ...]]) -> tuple[np.ndarray | None, float | None, str]:
    """``max m`` over ``trace P = 1``, ``P >= 0``, ``t >= ||(p12, p22)||`` and, at every vertex,
    ``Gamma_v - (g_v p12 + (g_v + e_v) t + m) I >= 0`` (data divided by their largest entry)."""
    import cvxpy as cp

    data = np.array([[float(x) for x in v] for v in vertices])
    scale = max(float(np.abs(data[:, :4]).max()), 1e-300)
    P = cp.Variable((2, 2), symmetric=True)
    t, m = cp.Variable(), cp.Variable()
    cons = [cp.trace(P) == 1, P >> 0, cp.SOC(t, cp.hstack([P[0, 1], P[1, 1]])), m <= MARGIN_CAP]
    for a11, a12, a22, g, e in data / scale:
        A = np.array([[a11, a12], [0.0, a22]])
        gamma = -(A.T @ P + P @ A)
        cons.append((gamma + gamma.T) / 2 - (g * P[0, 1] + (g + e) * t + m) * np.eye(2) >> 0)
    problem = cp.Problem(cp.Maximize(m), cons)
    try:
        with warnings.catch_warnings():  # "may be inaccurate": the exact check is the judge
            warnings.simplefilter("ignore", UserWarning)
            problem.solve(solver=cp.CLARABEL)
    except cp.error.SolverError as exc:
        return None, None, f"solver error: {exc}"
    if P.value is None or m.value is None:
        return None, None, str(problem.status)
    return np.array(P.value), float(m.value), str(problem.status)


def certify_prop41_box(problem: Problem, box: ParameterBox, dynamics: str = "derived", *,
                       iss: bool = False) -> dict[str, Any]:
    """Eq. ``eq:stabCond`` (or its ISS variant) for every gain set of ``box``; a JSON-ready result."""
    from lyapcheck.paper.conditions import prop41

    prop = "ISS" if iss else "GES"
    cls = "prop41_iss" if iss else "prop41_ges"
    systems = _corner_systems(problem, box, dynamics)
    if systems is None:
        return {"status": "not_certified", "property": prop,
                "summary": "the dynamics at some corner do not have the structure this class needs"}
    for corner, system in zip(box.corners(), systems):
        refuted = prop41.refutation(system)
        if refuted is not None:
            return claims.decided_box(cls, {
                "status": "refuted", "property": prop, "box": box.to_json(),
                "refutation": {**refuted, "point": {name: str(value) for name, value in corner.items()}},
                "summary": ""}, box)
    vertices = box_vertices(systems, iss)
    P_float, margin, outcome = _solve(vertices)
    log = [{"vertices": len(vertices), "outcome": outcome, "relative_margin": margin}]
    if P_float is None or margin is None or margin <= 0:
        return {"status": "not_certified", "property": prop, "box": box.to_json(),
                "summary": f"no P common to the box was found ({box.describe()}, best margin "
                           f"{margin if margin is not None else 'n/a'}); this is not a proof that the condition fails",
                "relative_margin": margin, "solver": {"solves": log}}
    P = exact.symmetrize(exact.rational_matrix(P_float))
    cert = {"P": exact.to_json(P), "iss": iss, "vertices": [[str(x) for x in v] for v in vertices]}
    ok, why = check(systems[0], cert)
    if not ok:
        return {"status": "inconclusive", "property": prop, "box": box.to_json(),
                "summary": f"the solver found a candidate but its exact check failed: {why}",
                "relative_margin": margin, "solver": {"solves": log}}
    return claims.decided_box(cls, {"status": "certified", "property": prop, "box": box.to_json(), "summary": "",
                                     "relative_margin": margin, "certificate": cert, "solver": {"solves": log}}, box)


def check(template: System, cert: Mapping[str, Any]) -> tuple[bool, str]:
    """Exact check of the common ``P`` at every stored vertex (no solver)."""
    from lyapcheck.paper.conditions import prop41

    P = exact.from_json(cert["P"])
    if len(P) != 2 or not exact.is_symmetric(P):
        return False, "P must be a symmetric 2x2 matrix"
    for v in cert["vertices"]:
        vertex = tuple(Fraction(x) for x in v)
        ok, why = prop41.exact_check(vertex_system(template, vertex), P, bool(cert["iss"]))
        if not ok:
            named = ", ".join(f"{k} = {float(x):.6g}" for k, x in zip(VERTEX_KEYS, vertex))
            return False, f"at ({named}): {why}"
    return True, f"P > 0 and lambda_min(Gamma) exceeds the right-hand side at all {len(cert['vertices'])} vertices, exactly"


def verify_prop41_box(problem: Problem, box: ParameterBox, dynamics: str, result: Mapping[str, Any],
                      *, iss: bool = False) -> tuple[bool, str]:
    """Re-derive the vertices from the box and re-check the stored ``P`` exactly at each."""
    cert = result["certificate"]
    if cert.get("iss") is not iss:  # a JSON true or false, as certify writes it ("no" is not false)
        which = "prop41_iss" if iss else "prop41_ges"
        return False, f"'iss' must be {str(iss).lower()} for {which}; got {cert.get('iss')!r}"
    systems = _corner_systems(problem, box, dynamics)
    if systems is None:
        return False, "the dynamics at some corner do not have the structure this class needs"
    stored = {tuple(Fraction(x) for x in v) for v in cert["vertices"]}
    if stored != set(box_vertices(systems, iss)):
        return False, "the stored vertices do not match the box"
    return check(systems[0], cert)


def verify_prop41_refutation(problem: Problem, point: Mapping[str, Fraction], dynamics: str,
                             data: Mapping[str, Any]) -> tuple[bool, str]:
    """The stated refutation, re-derived at ``point`` (a gain set the caller has checked is in the box)."""
    from lyapcheck.paper.conditions import prop41

    system = build_system(problem_at_point(problem, point), dynamics)
    if not prop41.check_refutation(system, dict(data)):
        return False, "the stated point is not refuted by the Gamma_22 bound"
    return True, "refuted at a point of the box: no P satisfies eq. stabCond there (exact Gamma_22 bound)"
