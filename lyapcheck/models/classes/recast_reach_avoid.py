"""``reach_avoid`` on a loop with functions: every trajectory of the true loop from the initial set reaches
the goal in a bounded time without entering the unsafe set before.

The polynomial reach-avoid's conditions (:func:`lyapcheck.models.classes.reach_avoid.conditions`, stated
once for both routes) on the recasting (:mod:`lyapcheck.models.language.recast`), as the recast barrier
(:mod:`lyapcheck.models.classes.recast_barrier`) takes the barrier's: ``V`` is a polynomial in the deviations
of the states and of the smooth auxiliaries, ``x' = N / D`` with ``D > 0`` proved on the relations,
and each condition is proved on the recasting's relations with a set's inequalities (and their
pairwise products) as further relations ``p >= 0`` (:mod:`lyapcheck.models.engines.recast_sos`):

    -V >= 0                      on the relations and each initial piece      (V <= 0 on the initial set)
    V - 1 >= 0                   on the relations and each unsafe piece       (V >= 1 on the unsafe set)
    -grad V . N - eps D >= 0     on the relations and -q_i >= 0, each goal inequality q_i
                                                                              (V' <= -eps outside the goal)
    V + C - delta |x|^2 >= 0     on the relations                             (V bounded below)

with ``eps, delta > 0`` and ``C >= 0``. Every point ``(x, a(x))`` of the true loop lies in the
relations' set, so along a trajectory ``v(t) = V(x(t), a(x(t)))`` falls at rate ``eps`` while the goal
is not reached: from ``v(0) <= 0`` it stays ``<= 0 < 1`` (the unsafe set is not entered), in the compact
``{|x|^2 <= C / delta}``, and above ``-C``, so the goal is reached by ``C / eps`` seconds. The angles are
ordinary states (no claim modulo 2 pi), the loop the nominal one (every disturbance at 0), and the
decrease is demanded outside the goal everywhere (a loop with another equilibrium outside the goal has
none: a sufficient, conservative form, as on polynomial loops).

Before the proof, the true loop (each function evaluated by numpy) is simulated from the initial set,
each trajectory until it reaches the goal (:func:`lyapcheck.models.classes.recast_barrier.falsification`): one
that enters the unsafe set first is a ``counterexample`` (no proof is then searched: none can exist).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from fractions import Fraction
from typing import Any, Callable, Final, Sequence

from lyapcheck.degrees import searched_degrees
from lyapcheck.models.classes.reach_avoid import (REACH_DEGREES, SCALARS, Condition, certified_numbers, conditions,
                                          goal_of_one_piece, linear_conditions, not_found, out_of_time, time_bound)
from lyapcheck.models.language.recast import RecastModel, Relation
from lyapcheck.models.classes.barrier import (SETS_USE_BOX, at_point, box_falsification, check_polynomial,
                                             counterexample, falsification, flat_loop, not_smooth_note,
                                             piece_relations, polynomial_json, recasting_json, sets_use_box,
                                             state_relation, templates)
from lyapcheck.models.language.parameter_box import ModelBox
from lyapcheck.models.classes.recast_classes import Loop, _set, lie, state_square
from lyapcheck.models.engines.recast_sos import (ConditionCertificate, ConditionProgram, check_condition, known_values,
                                         solve_on_faces)
from lyapcheck.models.engines.search import Budget, BudgetExhausted, ParameterValues, Search, SolvesSpent
from lyapcheck.results import ConditionResult
from lyapcheck.sos.polynomials import Poly, Ring, to_fmpq
from lyapcheck.exact import read_rational
from lyapcheck.models.classes.claims import RECAST_REACH_AVOID_KIND, recast_reach_time, sentence_of

#: the certificate's kind (``verify`` dispatches on it)
KIND: Final = RECAST_REACH_AVOID_KIND
#: the search's lower bounds on eps (1/s) and delta, and on C: the check needs eps, delta > 0 and C >= 0;
#: a small floor leaves the program free (a smaller eps only lengthens the time bound C / eps)
FLOORS: Final = {"eps": Fraction(1, 1000), "C": Fraction(0), "delta": Fraction(1, 1000)}
#: the time bound's tightening (:func:`tightened`): rounds after the first certificate, and the first step
TIGHTEN_ROUNDS: Final = 4
TIGHTEN_FACTOR: Final = Fraction(16)
#: a point is said to lie outside the goal (in a reason's words, read in floating point) when the goal's
#: margin there is below minus this
OUTSIDE_GOAL_MARGIN: Final = 1e-9
#: the turns of an angle tried for another equilibrium outside the goal (1, -1, 2, -2, ...)
PERIODS: Final = 8

Pieces = list[list[Relation]]


@dataclass
class Found:
    """A reach-avoid function that passed the exact check: ``V`` (deviations), its scalars, degree and
    each condition's proof by name."""

    V: Poly
    eps: Fraction
    C: Fraction
    delta: Fraction
    proofs: dict[str, ConditionCertificate]


def goal_relations(loop: Loop, state_ring: Ring, goal: Sequence[Poly]) -> list[Relation]:
    """Each goal inequality ``q_i >= 0`` failing, ``-q_i >= 0``, as a relation of the loop's ring."""
    return [state_relation(loop, state_ring, -q, f"goal inequality {i + 1} fails") for i, q in enumerate(goal)]


def where(loop: Loop, condition: Condition, initial: Pieces, unsafe: Pieces, outside: list[Relation]
          ) -> list[Relation]:
    """The relations a condition is proved on: the recasting's, and the set it holds on."""
    extra = {"initial": initial, "unsafe": unsafe, "outside_goal": [[r] for r in outside]}.get(condition.on)
    return list(loop.relations) + (list(extra[condition.index]) if extra is not None else [])


def formulation(loop: Loop, V: Poly, N: dict[str, Poly], D: Poly, eps: Fraction, C: Fraction, delta: Fraction,
                initial: Pieces, unsafe: Pieces, outside: list[Relation]) -> list[Condition]:
    """The reach-avoid conditions (:func:`lyapcheck.models.classes.reach_avoid.conditions`) on this loop."""
    return conditions(loop.ring, V, lambda p: lie(loop, p, N), D, eps, C, delta, state_square(loop), len(initial),
                      len(unsafe), len(outside))


def search_reach(loop: Loop, initial: Pieces, unsafe: Pieces, outside: list[Relation], search: Search
                 ) -> tuple[tuple[Found, Poly, list[Any]] | None, list[str]]:
    """The first reach-avoid function over :data:`~lyapcheck.models.classes.reach_avoid.REACH_DEGREES` (V in the
    states first, then with the smooth auxiliaries) that passes the exact check, its time bound then
    tightened (:func:`tightened`); with its denominator ``D`` and the proofs of ``D > 0``; and what was tried."""
    from lyapcheck import tolerances

    ring = loop.ring
    tried: list[str] = []
    zero = tuple([0] * ring.nvars)
    one = ring.constant(1)
    square = state_square(loop)
    for template in templates(loop, REACH_DEGREES, search, tried):
        dv, basis, label, N, D, dens = (template.degree, template.basis, template.label, template.N, template.D,
                                        template.dens)
        capped = search.within(tolerances.TEMPLATE_SOLVES, "per template", "lyapcheck.tolerances.TEMPLATE_SOLVES")
        monos = [ring.monomial(m) for m in basis]
        linear = linear_conditions(ring, monos, lambda p: lie(loop, p, N), D, square, len(initial), len(unsafe),
                                   len(outside))

        def build(drop: frozenset[Any], linear: Any = linear, within: Fraction | None = None
                  ) -> ConditionProgram | str:
            program = ConditionProgram(ring, loop.relations, drop, loop.unused(), roots=loop.roots(),
                                       square_free=loop.square_free())
            for k in range(len(basis)):
                program.free(f"b{k}")
            for name in SCALARS:
                program.free(name)
            for condition, free in linear:
                program.relations = where(loop, condition, initial, unsafe, outside)
                top = max((sum(m) for _, p in free for m in ring.support(p)), default=dv)
                why = program.condition(condition.name, sorted(set(ring.support(condition.F)) | {zero}), free,
                                        top, vanishing=False)
                if why is not None:
                    return why
            program.relations = []
            for name in SCALARS:  # each scalar at least its floor: a 1x1 remainder
                program.condition(f"floor_{name}", [zero], [(name, one)], 0, vanishing=False)
            if within is not None:  # C <= within eps: the time bound C / eps at most ``within``
                program.condition("within", [zero], [("eps", one * to_fmpq(within)), ("C", -one)], 0,
                                  vanishing=False)
            return program

        values = ParameterValues()
        for condition, _ in linear:
            _set(values, *known_values(ring, condition.name, condition.F,
                                       sorted(set(ring.support(condition.F)) | {zero})))
        for name in SCALARS:
            _set(values, *known_values(ring, f"floor_{name}", ring.constant(-FLOORS[name]), [zero]))

        def accept(program: ConditionProgram, point: Any, N: dict[str, Poly] = N, D: Poly = D) -> Found | None:
            V = sum((ring.monomial(m, point.scalars[f"b{k}"]) for k, m in enumerate(basis)), ring.zero())
            eps, C, delta = (Fraction(point.scalars[name]) for name in SCALARS)
            if not (eps > 0 and delta > 0 and C >= 0):
                return None
            proofs = {}
            for condition in formulation(loop, V, N, D, eps, C, delta, initial, unsafe, outside):
                proof = program.certificate(condition.name, point)
                if not check_condition(ring, condition.F, where(loop, condition, initial, unsafe, outside),
                                       proof)[0]:
                    return None
                proofs[condition.name] = proof
            return Found(V, eps, C, delta, proofs)

        try:
            found, why = solve_on_faces(capped, build, values, accept)
        except SolvesSpent as exc:
            tried.append(f"{label}: {exc}")
            continue
        if found is not None:
            tried.append(f"{label}: found")
            found = tightened(found, search, build, values, accept)
            return (found, D, dens), tried
        tried.append(f"{label}: {why}")
    return None, tried


def tightened(found: Found, search: Search, build: Callable[..., ConditionProgram | str], values: ParameterValues,
              accept: Callable[[ConditionProgram, Any], Found | None]) -> Found:
    """The same template solved again with ``C <= T eps`` for shorter bounds ``T`` (the search maximizes
    the Gram margin, not the time: its first bound is loose): :data:`TIGHTEN_ROUNDS` rounds, each ``T``
    the best bound over :data:`TIGHTEN_FACTOR`, or (after a ``T`` not reached) the geometric mean of the
    two; the last certificate that passed its exact check is kept."""
    from lyapcheck import tolerances

    tight = ParameterValues(dict(values.floats), dict(values.exact))  # and the parameter of C <= T eps
    _set(tight, *known_values(search.ring, "within", search.ring.zero(), [tuple([0] * search.ring.nvars)]))
    best, lo = found, None
    for _ in range(TIGHTEN_ROUNDS):
        hi = found_bound(best)
        within = hi / TIGHTEN_FACTOR if lo is None else _dyadic_mean(lo, hi)
        capped = search.within(tolerances.TEMPLATE_SOLVES, "per template", "lyapcheck.tolerances.TEMPLATE_SOLVES")
        try:
            better, _ = solve_on_faces(capped, lambda drop: build(drop, within=within), tight, accept)
        except SolvesSpent:
            better = None
        if better is not None and found_bound(better) < hi:
            best = better
        else:  # not reached: the next try lies between it and the best bound
            lo = within
    return best


def found_bound(found: Found) -> Fraction:
    """A found certificate's time bound ``C / eps`` (s)."""
    return time_bound(found.C, found.eps)


def _dyadic_mean(a: Fraction, b: Fraction) -> Fraction:
    """About the geometric mean of ``a`` and ``b`` (a short rational: it enters the program)."""
    return Fraction(math.sqrt(float(a) * float(b))).limit_denominator(1 << 20)


def certificate_json(loop: Loop, found: Found, D: Poly, dens: list[Any]) -> dict[str, Any]:
    """The exact certificate: V in the deviations (``shift``), written with the functions too, its
    scalars (``eps`` per second), its degree, and every proof (the recasting's, each condition's)."""
    ring = loop.ring
    return {**polynomial_json(loop, KIND, "V", found.V), "eps_per_s": str(found.eps), "C": str(found.C),
            "delta": str(found.delta), **recasting_json(loop, D, dens),
            "proofs": {name: proof.to_json(ring) for name, proof in found.proofs.items()}}


# -- the class ----------------------------------------------------------------------------------------

def run(model: RecastModel, loop: Loop, budget: Budget, box: ModelBox | None = None) -> ConditionResult:
    """The ``reach_avoid`` class on a loop with functions (module docstring). With ``box``, ``loop`` is
    the loop with the box's parameters as bounded constants (``model`` read at the box's centre): one
    V for every value of the box, as the recast barrier's
    (:func:`lyapcheck.models.classes.recast_barrier.run`)."""
    refused = goal_of_one_piece(model.sets["goal"])
    if refused is not None:
        return refused
    if box is not None and sets_use_box(model, box):
        return ConditionResult("reach_avoid", "not_applicable", SETS_USE_BOX)
    trial, at = box_falsification(model, box, goal=True) if box is not None else \
        (falsification(model, stop=model.sets["goal"]), None)
    if trial is not None and trial.entry is not None:  # entered before the goal: no V can exist
        return at_point(counterexample(model, trial, "reach_avoid", "reach_avoid", " before it reaches the goal"), at)
    simulated = {} if trial is None else {"falsification": trial.to_dict()}
    periodic = periodic_notes(model, loop)
    if periodic:  # an equilibrium outside the goal: no V of this form exists, and none is searched
        return not_found(periodic, [], searched_degrees(REACH_DEGREES), simulated,
                         f"no reach-avoid function of this form can exist: {periodic[0]}")
    flat = flat_loop(loop)
    initial = piece_relations(flat, model.state_ring, model.sets["initial"], "initial")
    unsafe = piece_relations(flat, model.state_ring, model.sets["unsafe"], "unsafe")
    outside = goal_relations(flat, model.state_ring, model.sets["goal"][0])
    search = Search(flat.ring, budget)
    try:
        result, tried = search_reach(flat, initial, unsafe, outside, search)
    except BudgetExhausted as exc:
        return out_of_time(budget.seconds, exc, search.log, simulated)
    if result is None:
        rough = not_smooth_note(flat, "V", "V' <= -eps outside the goal")
        if rough:
            tried.append(rough)
        return not_found(tried, search.log, searched_degrees(REACH_DEGREES), simulated)
    found, D, dens = result
    certificate = certificate_json(flat, found, D, dens)
    return ConditionResult("reach_avoid", "certified", sentence_of(certificate),  # (V's degree, not its template's)
                           numbers=certified_numbers(certificate["degree"], recast_reach_time(certificate), trial),
                           certificate=certificate, solver={"solves": search.log}, property="reach_avoid")


def periodic_notes(model: RecastModel, loop: Loop) -> list[str]:
    """Why no V of this form can exist: an angle (a state that enters only through its sine and cosine)
    makes the equilibrium shifted by 2 pi in it an equilibrium too, where ``V' = 0``; outside the goal
    (read in floating point: these are words, not a status) ``V' <= -eps`` fails there."""
    import numpy as np

    from lyapcheck.models.language.sets import margin

    out = []
    for angle in loop.angles:
        for turns in (k * sign for k in range(1, PERIODS + 1) for sign in (1, -1)):
            point = np.array([float(v) for v in model.equilibrium])
            point[list(model.states).index(angle)] += 2 * math.pi * turns
            if margin(model.sets["goal"], point)[0] < -OUTSIDE_GOAL_MARGIN:
                out.append(f"{angle} enters only through its sine and cosine, so {angle} = {angle}_eq "
                           f"{'+' if turns > 0 else '-'} {2 * abs(turns)} pi (the other states at their equilibrium) "
                           "is an equilibrium too, outside the goal, where V' = 0: V' <= -eps is demanded outside the "
                           "goal on the whole state space")
                break
    return out


# -- verify -------------------------------------------------------------------------------------------

def check(model: RecastModel, proved: Loop, c: dict[str, Any]) -> tuple[bool, str]:
    """Re-check a recast reach-avoid certificate exactly from the certificate and the model text:
    ``proved`` is the loop with the certificate's square-root bounds already re-checked; the sets
    are the model's."""
    cert = c["certificate"]
    if c.get("property") != "reach_avoid":
        return False, "a reach_avoid certificate proves reach_avoid"
    sets = model.sets
    if not sets.get("initial") or not sets.get("unsafe") or len(sets.get("goal") or ()) != 1:
        return False, "the model has no [sets] initial, unsafe and a one-piece goal for reach_avoid"
    loop = flat_loop(proved)
    ring = loop.ring
    eps, C, delta = (read_rational(cert[key]) for key in ("eps_per_s", "C", "delta"))
    if not (eps > 0 and delta > 0 and C >= 0):
        return False, "eps and delta must be > 0 and C >= 0"
    head = check_polynomial(loop, cert, "V", "a reach-avoid function")
    if isinstance(head, str):
        return False, head
    V, N, D = head
    initial = piece_relations(loop, model.state_ring, sets["initial"], "initial")
    unsafe = piece_relations(loop, model.state_ring, sets["unsafe"], "unsafe")
    outside = goal_relations(loop, model.state_ring, sets["goal"][0])
    stated = cert["proofs"]
    formulated = formulation(loop, V, N, D, eps, C, delta, initial, unsafe, outside)
    if not isinstance(stated, dict) or set(stated) != {condition.name for condition in formulated}:
        return False, ("one proof per piece of the initial and of the unsafe set, per goal inequality and for the "
                       "lower bound is needed")
    for condition in formulated:
        relations = where(loop, condition, initial, unsafe, outside)
        proof = ConditionCertificate.from_json(ring, stated[condition.name], len(relations))
        if proof.rho is not None:
            return False, f"{condition.name}: a reach-avoid identity takes no region multiplier"
        ok, why = check_condition(ring, condition.F, relations, proof)
        if not ok:
            return False, f"{condition.what}: {why}"
    return True, ("V <= 0 on the initial set, V >= 1 on the unsafe set, V' <= -eps outside the goal and V >= "
                  "delta |x|^2 - C on the recasting's relations, exactly")


__all__ = ["KIND", "FLOORS", "run", "check", "certificate_json", "goal_relations"]
