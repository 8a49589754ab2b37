"""A discrete-time map with functions over a box of its parameters (``certify --box``; issues 44 and 41):
``linearization``, ``roa`` and ``candidate`` for every value of the box, in ball arithmetic (``quadratic``,
``sos_gas`` and ``sos_bound`` over a box: :func:`lyapcheck.models.classes.map_relations.on_relations_box` and
:func:`lyapcheck.models.classes.map_relations_bounds.disturbed_map`, the box's parameters bounded variables of
the recasting's relations, exact).

The map is recast again with the box's parameters as variables without a flow, after the states, at the box's
centre (:func:`boxed_system`); its true map is then evaluated with each parameter a ball covering its interval
(:class:`~lyapcheck.models.engines.interval_field.BallLoop` with ``fixed`` balls), so every enclosure holds for
every value of the box at once. The fixed point must stay put over the box: the displacement ``F(x_eq) - x_eq``
is proved 0 for every value (exactly by substitution, else each component's ball exactly 0); otherwise the box
is refused in one line (exit 2), as on a polynomial map.

``linearization`` (:func:`linearization`): ``P`` is the short dyadic rounding of the Stein solution of the exact
Jacobian at the box's centre (:func:`lyapcheck.models.classes.discrete_functions.rounded_p`), positive definite
(exact); where that one is not proved over the whole box, one proposed by a small SDP common to the Jacobians of
a grid of the box (:func:`common_p`: a solver's point, a proposal only). The Jacobians ``A(p) = I + Jd(p)`` over a
part of the box are enclosed by the chain rule in ball arithmetic (jets of the state deviations at the fixed
point, the parameters balls), and ``M(p) = P - A(p)^T P A(p)`` with them. ``M(p)`` is symmetric for every ``p``;
with ``C`` the midpoints of the entries' enclosures and ``R`` their radii (rationals, exact), ``M(p) = C + E``
with ``|E_ij| <= R_ij``, so ``lambda_min(M(p)) >= lambda_min(C) - rho(E)`` and ``rho(E) <= max_i sum_j R_ij``
(any induced norm bounds the spectral radius): ``C - r I`` positive definite (exact) with ``r`` that row sum
proves ``M(p) > 0`` for every ``p`` of the part, i.e. ``A(p)^T P A(p) - P < 0``: every ``A(p)`` is Schur stable
with the one ``P``, and the fixed point is locally exponentially stable for every value of the box. A part not
proved is halved at its widest parameter, at most :data:`~lyapcheck.tolerances.MAP_BOX_PIECES` parts in all (a
count, the same on any machine); ``verify`` runs the same deterministic splitting with the stated ``P``.

``roa`` (:func:`roa`): the level search of :func:`lyapcheck.models.classes.discrete_functions.level_search` with
``V = e^T P e`` (``P`` as above) and the true map with the parameters as balls: ``V(F(e)) < V(e)`` on ``{V <=
c}`` but at the fixed point, for every value of the box (``g(0) = 0`` and ``grad g(0) = 0`` hold for each value,
the fixed point staying put, so the cells' Hessian zone argument holds for each). A level is proved on each part
of the linearization's splitting of the box (on those, the Hessian of ``g`` at the fixed point, ``2 (A(p)^T P
A(p) - P)``, is negative definite in balls; on the whole box the balls' widening can hide that), the parts
covering the box. ``verify`` re-derives the parts from the stated ``P`` and proves the stated level again on the
same cells of each.

``refuted`` (:func:`refute_over_box`): where no ``P`` is proved over the box, the box's corners and centre are
tried one by one: at each, the ball Jacobian (the parameters exact, the functions' jets in balls) has its
characteristic polynomial mapped by the bilinear transform and Routh's first column computed in balls
(:func:`lyapcheck.models.classes.sampled.cayley_routh_column`); a sign change with no ball holding 0 is an
eigenvalue of modulus > 1 there, so the fixed point is unstable at that value and the claim for every value of
the box is false. The refutation states the point (method ``box_point``, as a polynomial map's) and the
precision; ``verify`` computes the column again there.

``candidate`` (:func:`candidate`): the user's quadratic ``V`` of the states, its ``A(p)^T P A(p) - P < 0``
proved on parts of the box as above, then its largest level as ``roa``'s.

``barrier`` and ``reach_avoid`` over a box: one ``B`` (``V``) of the states for every value, the box's parameters
bounded variables of the relations, refuted at a corner or the centre
(:mod:`lyapcheck.models.classes.map_relations_safety_box`).
"""

from __future__ import annotations

from fractions import Fraction
from typing import TYPE_CHECKING, Any, Final

import flint

from lyapcheck import tolerances
from lyapcheck.errors import ModelFileError
from lyapcheck.models.classes import discrete_functions as dfn
from lyapcheck.models.classes import discrete_linearization
from lyapcheck.models.classes.claims import BOX_BALL_STEIN_METHOD, box_ball_stein_sentence, discrete_interval_sentence
from lyapcheck.models.engines.interval_field import BallLoop, Jet, ball
from lyapcheck.models.language.parameter_box import box_text
from lyapcheck.results import ConditionResult

if TYPE_CHECKING:  # pragma: no cover
    from lyapcheck.models.engines.search import Budget
    from lyapcheck.models.language.parameter_box import ModelBox
    from lyapcheck.models.language.recast import RecastModel, RecastSystem

#: the classes a map with functions decides over a box
BOX_CLASSES: Final = ("linearization", "quadratic", "sos_gas", "roa", "candidate", "sos_bound", "barrier",
                      "reach_avoid")
#: the method a map with functions' linearization over a box states
METHOD: Final = BOX_BALL_STEIN_METHOD
#: the reason of a class without a box route (none today: every class of a map with functions has one)
NOT_OVER_BOX: Final = ("over a box a discrete-time map with functions takes " + ", ".join(BOX_CLASSES)
                       + " (each for every value of the box); certify a point with --set NAME=VALUE")
#: the refutation at one value of the box (its method and sentence: the discrete-time linearization's module's)
BALL_ROUTH_METHOD: Final = discrete_linearization.BALL_ROUTH_METHOD
REFUTED_BALL_ROUTH: Final = discrete_linearization.REFUTED_BALL_ROUTH
#: the precisions (bits) Routh's column is computed at, in this order, until no ball of it holds 0
ROUTH_PRECISIONS: Final = (64, 128, 256, 512, 1024)

Interval = tuple[Fraction, Fraction]


def boxed_system(model: "RecastModel", box: "ModelBox") -> "RecastSystem":
    """The map's displacement ``F(x) - x`` recast with the box's parameters as variables without a flow (after
    the states, at the box's centre); a one-line :class:`~lyapcheck.errors.ModelFileError` naming ``--box``
    where the recasting cannot keep one a variable or the fixed point is not proved to stay put over the box."""
    from lyapcheck.models.classes.recast_interval import Robust
    from lyapcheck.models.language.recast import recast_dynamics

    where = f"--box {', '.join(box.names)}"
    names = tuple(box.names)
    constants = {k: v for k, v in model.parameters.items() if k not in names}
    constants.update({d: Fraction(0) for d in model.disturbances})
    texts: dict[str, object] = {s: f"({t}) - ({s})" for s, t in model.dynamics_text.items()}
    texts.update({name: "0" for name in names})
    try:
        system, _ = recast_dynamics(model.source, model.states + names, texts, constants,
                                    tuple(model.equilibrium) + tuple(box.center(n) for n in names),
                                    networks=model.networks, for_map=True)
    except ModelFileError as exc:
        why = str(exc).removeprefix(exc.source + ": ")
        raise ModelFileError(model.source, where, f"the map cannot be recast with the box's parameters as variables "
                                                  f"({why}): certify points with --set") from None
    if not Robust(system, {n: box.half(n) for n in names}, box).vanishes():
        raise ModelFileError(model.source, where, "the map's fixed point moves with the box's parameters: F(x_eq) = "
                                                  "x_eq is not proved for every value of the box (in ball arithmetic); "
                                                  "certify a point with --set NAME=VALUE")
    return system


def whole(box: "ModelBox") -> dict[str, Interval]:
    """The box as intervals, by name."""
    return {name: (lo, hi) for name, lo, hi in box.bounds}


def boxed_map(system: "RecastSystem", part: dict[str, Interval]) -> BallLoop:
    """The true map with the parameters of ``part`` as balls covering their intervals (exactly enclosed)."""
    return BallLoop(system, [ball(lo).union(ball(hi)) for lo, hi in part.values()])


def jacobian_balls(loop: BallLoop) -> list[list[Any]] | None:
    """``A = I + Jd`` at the fixed point, each entry a ball holding it for every parameter value of the loop's
    balls (the chain rule on jets); None where a function is not known differentiable there."""
    n = loop.n
    zero = flint.arb(0)
    D = loop.field([Jet.variable(zero, i, n, 1) for i in range(n)])
    rows = []
    for i, d in enumerate(D):
        grad = d.grad if isinstance(d, Jet) else [zero] * n
        if grad is None or not all(g.is_finite() for g in grad):
            return None
        rows.append([g + (1 if i == j else 0) for j, g in enumerate(grad)])
    return rows


def stein_margin_proved(P: list[list[Fraction]], A: list[list[Any]]) -> bool:
    """``P - A^T P A > 0`` for every matrix of the ball matrix ``A`` (module docstring: midpoints, radii, an
    induced norm's bound, then an exact test): the sampled-data loop's test
    (:func:`lyapcheck.models.classes.sampled_regions.stein_margin`) with no margin."""
    from lyapcheck.models.classes.sampled_regions import stein_margin

    return stein_margin(P, A, Fraction(0))


def _halves(part: dict[str, Interval]) -> tuple[dict[str, Interval], dict[str, Interval]]:
    """The part split at the middle of its widest parameter interval (exact; the first such name on a tie)."""
    name = max(part, key=lambda k: part[k][1] - part[k][0])
    lo, hi = part[name]
    mid = (lo + hi) / 2
    return {**part, name: (lo, mid)}, {**part, name: (mid, hi)}


def prove_over_box(system: "RecastSystem", box: "ModelBox", P: list[list[Fraction]]
                   ) -> tuple[bool, int, str, list[dict[str, Interval]]]:
    """``A(p)^T P A(p) - P < 0`` for every ``p`` of the box, deterministically: each part proved or halved,
    depth first, at most :data:`~lyapcheck.tolerances.MAP_BOX_PIECES` parts examined. (proved, parts examined,
    why not, the parts proved: they cover the box when it is proved)."""
    stack = [whole(box)]
    count = 0
    proved: list[dict[str, Interval]] = []
    while stack:
        part = stack.pop()
        count += 1
        if count > tolerances.MAP_BOX_PIECES:
            words = box_text((k, lo, hi) for k, (lo, hi) in part.items())
            return False, count - 1, (f"not proved on the part {words} after {tolerances.MAP_BOX_PIECES} parts of the "
                                      "box (lyapcheck.tolerances.MAP_BOX_PIECES)"), proved
        A = jacobian_balls(boxed_map(system, part))
        if A is None:
            return (False, count, "a function of the map is not known differentiable at the fixed point over the box",
                    proved)
        if stein_margin_proved(P, A):
            proved.append(part)
        else:
            stack.extend(reversed(_halves(part)))
    return True, count, "", proved


# -- an unstable value of the box: the claim for every value is false (refuted) ------------------------------

def routh_at(system: "RecastSystem", point: dict[str, Fraction], bits: int) -> tuple[int | None, list[Any]]:
    """At the parameter ``point`` (exact values of the box's parameters), the sign changes of Routh's first
    column of the bilinear transform of the characteristic polynomial of the ball Jacobian ``A = I + Jd``
    (:func:`lyapcheck.models.classes.sampled.cayley_routh_column`), at ``bits`` of precision: the number of
    eigenvalues of the true Jacobian of modulus > 1, or None where a ball of the column holds 0 (or a function
    is not known differentiable there); and the column."""
    from lyapcheck.models.classes.sampled import _sign_changes, cayley_routh_column

    saved = flint.ctx.prec
    flint.ctx.prec = bits
    try:
        A = jacobian_balls(boxed_map(system, {name: (value, value) for name, value in point.items()}))
        if A is None:
            return None, []
        column = cayley_routh_column(flint.arb_mat(A))
        return (_sign_changes(column) if len(column) == len(A) + 1 else None), column
    finally:
        flint.ctx.prec = saved


def unstable_at(system: "RecastSystem", point: dict[str, Fraction]) -> dict[str, Any] | None:
    """The refutation's data at ``point`` (:data:`BALL_ROUTH_METHOD`) where Routh's column proves an eigenvalue
    of modulus > 1, trying each precision of :data:`ROUTH_PRECISIONS`; None where none does (a stable or
    critical value, or one the balls leave undecided: nothing is claimed of it)."""
    for bits in ROUTH_PRECISIONS:
        changes, column = routh_at(system, point, bits)
        if changes is not None:
            if changes == 0:
                return None
            return {"time": "discrete", "method": BALL_ROUTH_METHOD, "precision_bits": bits,
                    "routh_first_column": [str(c) for c in column]}
    return None


def refute_over_box(system: "RecastSystem", box: "ModelBox") -> ConditionResult | None:
    """``refuted`` for the whole box when the Jacobian at one of its corners or its centre
    (:func:`lyapcheck.models.classes.discrete_linearization.box_points`) has an eigenvalue of modulus > 1,
    proved in ball arithmetic (:func:`unstable_at`): there the fixed point is unstable (Lyapunov's indirect
    method for maps; the map's functions are smooth at the fixed point, their jets exist), so "locally
    exponentially stable for every value of the box" is false. The certificate states the point, as a
    polynomial map's (method ``box_point``); None when no such value is found."""
    from lyapcheck.models.classes.discrete_linearization import BOX_POINT_METHOD, box_point_sentence, box_points

    for point in box_points(box):
        at = unstable_at(system, point)
        if at is not None:
            data = {"time": "discrete", "method": BOX_POINT_METHOD, "point": {k: str(v) for k, v in point.items()},
                    "at_point": at}
            return ConditionResult("linearization", "refuted", box_point_sentence(point, REFUTED_BALL_ROUTH),
                                   property="LES", refutation=data)
    return None


def verify_refutation(model: "RecastModel", box: "ModelBox", data: dict[str, Any]) -> tuple[bool, str]:
    """A refutation over a box decided again: the stated point is a value of the box naming every parameter,
    and Routh's column at the stated precision shows an eigenvalue of modulus > 1 there again."""
    from lyapcheck.models.classes.discrete_linearization import BOX_POINT_METHOD, stated_box_point

    if data.get("time") != "discrete" or data.get("method") != BOX_POINT_METHOD:
        return False, f"not a map's refutation at a value of the box (method {data.get('method')!r})"
    point = stated_box_point(data, box)
    if isinstance(point, str):
        return False, point
    at = data.get("at_point")
    if not isinstance(at, dict) or at.get("method") != BALL_ROUTH_METHOD:
        return False, f"the refutation at the point states method {BALL_ROUTH_METHOD!r}"
    bits = at.get("precision_bits")
    if not isinstance(bits, int) or bits not in ROUTH_PRECISIONS:
        return False, f"precision_bits must be one of {', '.join(map(str, ROUTH_PRECISIONS))}"
    changes, _ = routh_at(boxed_system(model, box), point, bits)
    if not changes:
        return False, "at the stated point Routh's first column shows no eigenvalue of modulus > 1 (ball arithmetic)"
    return True, (f"at a value of the box: {changes} sign change(s) in Routh's first column of the Jacobian's "
                  "bilinear transform, in ball arithmetic (an eigenvalue of modulus > 1)")


def _centre_p(model: "RecastModel", name: str) -> list[list[Fraction]] | ConditionResult:
    """``P`` from the exact Jacobian at the box's centre (the model is read there), or ``name``'s result
    saying why there is none."""
    from lyapcheck.sos.definiteness import is_positive_definite

    A = dfn.exact_jacobian(model)
    if isinstance(A, str):
        return ConditionResult(name, "not_applicable", f"the map's Jacobian at the fixed point: {A}")
    P = dfn.rounded_p(A)
    if P is None or not is_positive_definite(P):
        return ConditionResult(name, "not_certified", "at the box's centre the discrete Lyapunov equation A^T P A - P "
                               "= -I of the exact Jacobian has no positive definite solution (rounded): no P to prove "
                               "over the box (the centre's linearization is not Schur stable)")
    return P


def grid_points(box: "ModelBox") -> list[dict[str, Interval]]:
    """The box's grid of :data:`~lyapcheck.tolerances.MAP_BOX_GRID` values per parameter (its ends included),
    each as a part of zero width."""
    from itertools import product

    count = tolerances.MAP_BOX_GRID
    axes = [[lo + (hi - lo) * Fraction(i, count - 1) for i in range(count)] for _, lo, hi in box.bounds]
    return [{name: (v, v) for name, v in zip(box.names, values)} for values in product(*axes)]


def common_p(system: "RecastSystem", box: "ModelBox") -> list[list[Fraction]] | None:
    """A ``P`` with ``A^T P A - P <= -I`` at every Jacobian of the box's grid (a small SDP; None where the
    solver finds none: :func:`~lyapcheck.models.classes.fitted_v.common_lyapunov`), rounded to short dyadics: a
    proposal only, which :func:`prove_over_box` decides over the whole box."""
    import numpy as np

    from lyapcheck.models.engines.ellipsoid_cells import _short

    jacobians = []
    for point in grid_points(box):
        A = jacobian_balls(boxed_map(system, point))
        if A is None:
            return None
        jacobians.append(np.array([[float(a.mid()) for a in row] for row in A]))
    from lyapcheck.models.classes.fitted_v import common_lyapunov

    value = common_lyapunov(jacobians, discrete=True, floor=1.0)
    if value is None:
        return None
    n = value.shape[0]
    return [[_short(Fraction(float(value[min(i, j), max(i, j)])), tolerances.P_BITS) for j in range(n)]
            for i in range(n)]


def box_p(model: "RecastModel", system: "RecastSystem", box: "ModelBox", name: str
          ) -> tuple[list[list[Fraction]], int, list[dict[str, Interval]]] | ConditionResult:
    """The ``P`` proved over the box, the parts examined and the parts proved: the centre's ``P`` first, then,
    where that is not proved over the whole box, one common to the box's grid (:func:`common_p`); or
    ``name``'s not_certified result saying why neither is."""
    from lyapcheck.sos.definiteness import is_positive_definite

    P = _centre_p(model, name)
    if isinstance(P, ConditionResult):
        return P
    ok, parts, why, proved = prove_over_box(system, box, P)
    if ok:
        return P, parts, proved
    other = common_p(system, box)
    if other is not None and is_positive_definite(other):
        ok, parts, also, proved = prove_over_box(system, box, other)
        if ok:
            return other, parts, proved
        why = f"{why}; nor the one common to the box's grid ({also})"
    else:
        why = f"{why}; and no P common to the box's grid was found"
    return ConditionResult(name, "not_certified", "no P was proved with A(p)^T P A(p) - P < 0 for every value of the "
                           f"box in ball arithmetic: the centre's {why}")


def _prefix(box: "ModelBox") -> str:
    from lyapcheck.models.classes.claims import box_prefix

    return box_prefix(box, "certified")


def linearization(model: "RecastModel", box: "ModelBox") -> ConditionResult:
    """One ``P`` with ``A(p)^T P A(p) - P < 0`` for every ``p`` of the box (module docstring)."""
    system = boxed_system(model, box)
    found = box_p(model, system, box, "linearization")
    if isinstance(found, ConditionResult):
        if found.status == "not_certified":  # no P for the whole box: an unstable value of it refutes the claim
            unstable = refute_over_box(system, box)
            if unstable is not None:
                return unstable
        found.property = "LES"
        return found
    P, parts, _ = found
    cert = {"time": "discrete", "method": METHOD, "P": [[str(x) for x in row] for row in P], "box_parts": parts,
            "parameter_box": box.to_json()}
    summary = _prefix(box) + box_ball_stein_sentence(parts)
    return ConditionResult("linearization", "certified", summary, property="LES", certificate=cert,
                           numbers={"box_parts": parts})


def verify_linearization(model: "RecastModel", box: "ModelBox", status: str, data: dict[str, Any]
                         ) -> tuple[bool, str]:
    """A linearization over a box decided again: ``P`` symmetric and positive definite (exact), then the same
    splitting of the box re-derived from the model text."""
    from lyapcheck.sos.definiteness import is_positive_definite

    if status == "refuted":
        return verify_refutation(model, box, data)
    if status != "certified" or data.get("method") != METHOD:
        return False, f"a {status} linearization over a box of a map with functions states method {METHOD!r}"
    n = len(model.states)
    P = [[Fraction(str(x)) for x in row] for row in data["P"]]
    if len(P) != n or any(len(row) != n for row in P) or any(P[i][j] != P[j][i] for i in range(n) for j in range(n)):
        return False, "P must be a symmetric matrix over the states"
    if not is_positive_definite(P):
        return False, "P must be positive definite (checked exactly)"
    ok, parts, why, _ = prove_over_box(boxed_system(model, box), box, P)
    if not ok:
        return False, f"A(p)^T P A(p) - P < 0 is not proved over the box: {why}"
    return True, f"A(p)^T P A(p) - P < 0 proved again for every value of the box ({parts} part(s), ball arithmetic)"


def roa(model: "RecastModel", box: "ModelBox", budget: "Budget") -> ConditionResult:
    """The largest sublevel set of the centre's ``V = e^T P e`` proved a region of attraction for every value of
    the box (module docstring)."""
    system = boxed_system(model, box)
    chosen = box_p(model, system, box, "roa")  # (its parts: there the Hessian of g at 0 is negative definite in balls)
    if isinstance(chosen, ConditionResult):
        chosen.property = "ROA"
        chosen.summary = f"no region over the box: V = e^T P e does not decrease to first order ({chosen.summary})"
        return chosen
    P, _, parts = chosen
    found = dfn.level_search(model, P, budget, "roa", [boxed_map(system, part) for part in parts])
    if isinstance(found, ConditionResult):
        return found
    cert = {**dfn.region_certificate(model, P, found), "parameter_box": box.to_json(), "box_parts": len(parts)}
    return dfn.certified_region("roa", P, found, cert,
                                _prefix(box) + discrete_interval_sentence("roa", found.level, over_box=True))


def verify_roa(model: "RecastModel", box: "ModelBox", c: dict[str, Any]) -> tuple[bool, str]:
    """A region over a box proved again: the certificate's box is the document's, then the level on the same
    cells with the box's parameters as balls (:func:`lyapcheck.models.classes.discrete_functions.verify_roa`)."""
    cert = c.get("certificate")
    if not isinstance(cert, dict) or cert.get("parameter_box") != box.to_json():
        return False, "a region over a box states that box (parameter_box) as the document's"
    P = [[Fraction(str(x)) for x in row] for row in cert["P"]]
    n = len(model.states)
    if len(P) != n or any(len(row) != n for row in P):
        return False, "P must be a matrix over the states"
    system = boxed_system(model, box)
    ok, _, why, parts = prove_over_box(system, box, P)  # the same parts as certify's (deterministic)
    if not ok:
        return False, f"the box's parts are not re-derived from P: {why}"
    return dfn.verify_roa(model, c, [boxed_map(system, part) for part in parts])


def candidate(model: "RecastModel", box: "ModelBox", budget: "Budget") -> ConditionResult:
    """The user's quadratic ``V = e^T P e`` (of the states alone: a text naming a box parameter is refused
    before, :func:`lyapcheck.models.surfaces.certify.refuse_box_in_candidate`): its largest level proved a
    region of attraction for every value of the box, as :func:`roa` does with its own ``P``. ``A(p)^T P A(p) -
    P < 0`` is proved on the parts of the box first (:func:`prove_over_box`: the level search's Hessian zone
    needs it on each part); a ``P`` for which it is not proved is ``not_certified`` saying so."""
    P = dfn.candidate_p(model)
    if isinstance(P, ConditionResult):
        return P
    system = boxed_system(model, box)
    ok, _, why, parts = prove_over_box(system, box, P)
    if not ok:
        return ConditionResult("candidate", "not_certified", "the candidate V does not decrease to first order for "
                               "every value of the box: A(p)^T P A(p) - P < 0 was not proved in ball arithmetic "
                               f"({why})", property="ROA")
    found = dfn.level_search(model, P, budget, "candidate", [boxed_map(system, part) for part in parts])
    if isinstance(found, ConditionResult):
        return found
    cert = {**dfn.region_certificate(model, P, found), "V_from": "candidate", "parameter_box": box.to_json(),
            "box_parts": len(parts)}
    return dfn.certified_region("candidate", P, found, cert,
                                _prefix(box) + discrete_interval_sentence("candidate", found.level, over_box=True))


def verify_candidate(model: "RecastModel", box: "ModelBox", c: dict[str, Any]) -> tuple[bool, str]:
    """A candidate's region over a box: its ``P`` is the document's candidate's (exactly, ``"V_from":
    "candidate"``), then the region proved again as :func:`verify_roa` does (the box stated, the parts
    re-derived from ``P``, the level on the same cells of each)."""
    cert = c.get("certificate")
    if not isinstance(cert, dict) or cert.get("V_from") != "candidate":
        return False, "a certified candidate on a map with functions states the user's V (\"V_from\": \"candidate\")"
    P = dfn.candidate_matrix(model)
    if isinstance(P, str):
        return False, f"the document's candidate: {P}"
    if [[Fraction(str(x)) for x in row] for row in cert.get("P", [])] != P:
        return False, "the stated P is not the candidate's (V = e^T P e of the document's candidate text)"
    return verify_roa(model, box, c)


__all__ = ["BOX_CLASSES", "METHOD", "BALL_ROUTH_METHOD", "ROUTH_PRECISIONS", "REFUTED_BALL_ROUTH", "routh_at",
           "unstable_at", "refute_over_box", "verify_refutation", "NOT_OVER_BOX", "boxed_system", "whole",
           "boxed_map", "jacobian_balls", "stein_margin_proved", "prove_over_box", "grid_points", "common_p",
           "box_p", "linearization", "verify_linearization", "roa", "verify_roa", "candidate", "verify_candidate"]
