"""``barrier`` on a discrete-time map with functions (issue 44, item 1): no iterate of a start in the initial
set is ever in the unsafe set, proved on the recasting's relations and checked exactly.

The map is read as :mod:`lyapcheck.models.classes.map_relations` reads it (deviations, states ``e``,
auxiliaries ``a``, ``F(e, a)`` polynomial, every auxiliary's relations ``h_i = 0``, ``g_j >= 0``), with its
disturbances at 0 (as a polynomial map's barrier: the claim says ``(d = 0)``). The ``[sets]`` are moved to
the deviations (:func:`lyapcheck.models.classes.barrier.relation_pieces`). With ``B`` a free polynomial of
the states, the certificate (kind :data:`KIND`, the polynomial map's, with the recasting's ``variables``
and ``auxiliaries``) is the continuous barrier's on relations
(:func:`lyapcheck.models.classes.barrier.conditions`) with the step condition of a map in place of ``B'``:

    -B - sum (relations' and the piece's multipliers) = R_I            each initial piece   (B <= 0 there)
    B - 1 - sum (relations' and the piece's multipliers) = R_U         each unsafe piece    (B >= 1 there)
    lam B - B(F(e, a)) - sum_i lambda_i h_i - sum_j tau_j g_j = R_D    (the step)

every remainder and ``tau`` a sum of squares, ``lam >= 0`` rational. At every true point the relations'
terms are ``<= 0``, so ``B(F(e)) <= lam B(e)`` for every state: ``{B <= 0}`` is forward invariant, holds on
the initial set and misses the unsafe set, so no iterate of an initial start is ever unsafe (the polynomial
map's argument, :mod:`lyapcheck.models.classes.discrete_safety`).

The search: ``B`` of degree 2 then 4, at the polynomial map's rates; the first certificate that passes
:func:`check_map_barrier` is the answer. Before it, the falsification (:func:`falsify`): the true map iterated
in floating point from starts sampled in the initial set, and an iterate found in the unsafe set re-derived
from its rounded start in ball arithmetic through the true functions (:func:`check_iterate_functions`): then
``refuted`` (kind ``discrete_iterate``, as a polynomial map's), which ``verify`` re-derives from the model.
"""

from __future__ import annotations

from dataclasses import dataclass
from fractions import Fraction
from typing import TYPE_CHECKING, Any, Callable, Final, Mapping, Sequence

from lyapcheck.models.classes import discrete_lyapunov as dl
from lyapcheck.models.classes import discrete_safety as ds
from lyapcheck.models.classes.claims import DISCRETE_BARRIER_KIND, DISCRETE_BARRIER_SENTENCE
from lyapcheck.models.classes.map_relations import MapOnRelations, NotTaken, on_relations, on_relations_box
from lyapcheck.models.engines import reasons
from lyapcheck.models.engines.search import Budget, BudgetExhausted, ParameterValues, Search, one, param, why_none
from lyapcheck.results import ConditionResult
from lyapcheck.sos import bases
from lyapcheck.sos.polynomials import Monomial, Poly, to_fmpq
from lyapcheck.sos.structure import Gram, Identity, Scalar, Structure, Term, full_blocks

if TYPE_CHECKING:  # pragma: no cover
    from lyapcheck.models.classes.bounds import BoundField
    from lyapcheck.models.language.parameter_box import ModelBox
    from lyapcheck.results import Property
    from lyapcheck.models.engines.recast_sos import ConditionCertificate
    from lyapcheck.models.language.recast import RecastModel

#: the certificate kind: the polynomial map's (its sentence), stating the recasting's variables besides
KIND: Final = DISCRETE_BARRIER_KIND

Pieces = Sequence[Sequence[Poly]]


def map_sets(model: "RecastModel", m: MapOnRelations, keys: Sequence[str] = ("initial", "unsafe"),
             box: "ModelBox | None" = None) -> dict[str, list[list[Poly]]]:
    """The model's sets named ``keys`` in the map's ring, in the deviations (``box``: the ring of
    :func:`~lyapcheck.models.classes.map_relations.on_relations_box`, the box's parameters after the states)."""
    from lyapcheck.models.classes.barrier import relation_pieces
    from lyapcheck.models.classes.recast_classes import base_loop

    fixed = {name: box.half(name) for name in box.names} if box is not None else None
    loop = base_loop(m.system, cylinder=False, fixed=fixed)
    return {key: relation_pieces(loop, model.state_ring, model.sets[key], key) for key in keys}


def read_map(model: "RecastModel", box: "ModelBox | None" = None) -> MapOnRelations:
    """The map on its relations: at the model's point, or over ``box`` (its parameters bounded variables)."""
    return on_relations(model) if box is None else on_relations_box(model, box)


def relations_and_sets(name: str, model: "RecastModel", what: str, prop: "Property", keys: Sequence[str],
                       box: "ModelBox | None" = None
                       ) -> tuple[MapOnRelations, dict[str, list[list[Poly]]]] | ConditionResult:
    """What a safety class of a map with functions is searched on: the recasting's relations and the sets
    ``keys`` in its ring; or its result where it is not searched (``not_applicable``: a map the relations do
    not take, a set of a disturbance; ``not_certified``: more variables than
    :data:`~lyapcheck.tolerances.MAP_RELATIONS_VARIABLES`). ``what``: the certificate the reason names;
    ``box``: over that box of the map's parameters (:func:`read_map`)."""
    from lyapcheck import tolerances
    from lyapcheck.models.classes.barrier import SETS_USE_BOX, sets_use_box
    from lyapcheck.models.engines.reasons import size_limit

    if box is not None and sets_use_box(model, box):  # (the sets are read at the box's centre: refused)
        return ConditionResult(name, "not_applicable", SETS_USE_BOX)
    try:
        m = read_map(model, box)
    except NotTaken as exc:
        return ConditionResult(name, "not_applicable", f"not taken on this map with functions: {exc}")
    if m.ring.nvars > tolerances.MAP_RELATIONS_VARIABLES:
        none = reasons.reason(f"no {what} of the map was searched on the recasting's relations: "
                              + size_limit(m.ring.nvars, "variables (states and functions)",
                                           tolerances.MAP_RELATIONS_VARIABLES, "MAP_RELATIONS_VARIABLES"), ("fewer",))
        return ConditionResult(name, "not_certified", none.summary, property=prop,
                               numbers=none.numbers({"time": "discrete"}))
    try:
        return m, map_sets(model, m, keys, box)
    except ValueError as exc:  # (a set of a disturbance: the map is read with its disturbances at 0)
        return ConditionResult(name, "not_applicable", f"not taken on this map with functions: {exc}")


def sets_view(m: MapOnRelations) -> "BoundField":
    """The relations' view the identities on the sets (and reach_avoid's bound below) are searched with: the
    map's own at a point; over a box, its relations free of the box's parameters, every multiplier's and
    remainder's basis without them. ``B`` and the sets are of the states alone, so these identities are the
    point's: a multiplier of full total degree in the parameters would bring monomials (``u^2`` alone, ``u x``)
    whose squares nothing in the identity holds, and the remainder's margin would be 0 on them (the exact
    check then rejects the solver's point). Fewer relations multiplied is sound: the check takes every
    relation, a missing multiplier as 0."""
    from dataclasses import replace

    view = m.field
    if not m.params:
        return view
    ring, params = m.ring, set(m.params)
    free = tuple(i for i in view.multiplied
                 if not any(q[j] for q in ring.support(view.relations[i].poly) for j in params))
    return replace(view, multiplied=free, unused=view.unused | params)


def step_multipliers(m: MapOnRelations, view: "BoundField", name: str, target: set[Monomial],
                     vanishing: bool = False) -> tuple[list[Gram], list[Scalar], list[Term], set[Monomial]]:
    """The relations' terms of a step identity (``view``: the map's relations, or reach_avoid's with the
    failing goal inequality after them): every relation's multiplier of the identity's degree at a point; over a
    box, :func:`~lyapcheck.models.classes.map_relations.box_multipliers` (degrees in the states and functions,
    ``tau(e, a) (h^2 - u^2)`` for each parameter; ``vanishing``: a step with no constant, whose multipliers
    vanish at the fixed point where their relations do not, as a decrease's)."""
    from dataclasses import replace

    from lyapcheck.models.classes.bounds import relation_multipliers
    from lyapcheck.models.classes.map_relations import box_multipliers

    if not m.params:
        return relation_multipliers(view, name, target, (), margin=True)
    # (the parameters' degree in the step: B(F) of a quartic B holds u^4 t^4, which only a box multiplier
    # holding u itself covers; of a quadratic one, u^2 t^2, which tau(e, a) (h^2 - u^2) covers)
    top = max((sum(q[i] for i in m.params) for q in target), default=0)
    return box_multipliers(replace(m, relations=view.relations, field=view), target, (), name, margin=True,
                           vanishing=vanishing, param_degree=max(0, (top - 1) // 2))


def step_supports(m: MapOnRelations, basis: Sequence[Monomial]) -> dict[int, list[Monomial]]:
    """Each monomial ``e^q`` of ``B``'s (``V``'s) basis: the support of its step, ``e^q`` and ``(e^q)(F)``."""
    ring = m.ring
    return {i: sorted(set(ring.support(dl.compose(ring, ring.monomial(q), m.F))) | {q}) for i, q in enumerate(basis)}


def step_of(m: MapOnRelations, B: Poly, lam: Fraction) -> Poly:
    """``lam B - B(F)``: the step condition's left side."""
    return B * to_fmpq(lam) - dl.compose(m.ring, B, m.F)


@dataclass
class StepProgram:
    """What a step program of ``barrier`` and of ``reach_avoid`` starts from (:func:`step_program`): the basis of
    ``B`` (``V``), its coefficients ``b<k>``, the sets' identities with their Gram matrices, and each basis
    monomial's step support (:func:`step_supports`); each class adds its step identities to these lists."""

    basis: list[Monomial]
    scalars: list[Scalar]
    grams: list[Gram]
    identities: list[Identity]
    supports: dict[int, list[Monomial]]


def step_program(m: MapOnRelations, initial: Pieces, unsafe: Pieces, degree: int) -> StepProgram | str:
    """The set-up both safety classes of a map with functions share: ``B`` (``V``) of this degree on the map's
    view, its coefficients, ``B <= 0`` on the initial set and ``B >= 1`` on the unsafe set on the relations' view
    (:func:`sets_view`), and its monomials' steps; or why there is none (a size limit, named)."""
    from lyapcheck.models.classes.barrier import _b_basis, set_identities

    basis = _b_basis(m.field, degree)
    scalars = [Scalar(f"b{k}") for k in range(len(basis))]
    grams: list[Gram] = []
    on_sets = set_identities(sets_view(m), basis, degree, initial, unsafe, grams, frozenset(), scalars)
    if isinstance(on_sets, str):
        return on_sets
    return StepProgram(basis, scalars, grams, list(on_sets), step_supports(m, basis))


def step_values(m: MapOnRelations, degree: int, initial: Pieces, unsafe: Pieces, prefix: str, lam: Fraction
                ) -> ParameterValues:
    """A step program's parameters: the sets' inequalities, and for each monomial ``e^q`` of ``B``'s (``V``'s)
    basis its step ``lam e^q - (e^q)(F)`` as ``<prefix><i>`` (``barrier``: ``sB`` at its rate; ``reach_avoid``:
    ``sV`` at 1)."""
    from lyapcheck.models.classes.barrier import _b_basis, set_values

    ring = m.ring
    values = ParameterValues()
    set_values(m.field, values, initial, unsafe)
    for i, q in enumerate(_b_basis(m.field, degree)):
        zq = ring.monomial(q)
        after = dl.compose(ring, zq, m.F)
        values.set_poly(ring, f"{prefix}{i}", zq * to_fmpq(lam) - after, sorted(set(ring.support(after)) | {q}))
    return values


# -- the exact check -------------------------------------------------------------------------------------

def check_map_barrier(m: MapOnRelations, B: Poly, lam: Fraction, initial: Pieces, unsafe: Pieces,
                      proofs: dict[str, "ConditionCertificate"]) -> tuple[bool, str]:
    """The identities of the module docstring, exactly: ``lam >= 0``, ``B`` of the states alone, and each
    identity on its relations (:func:`lyapcheck.models.classes.barrier.check_on_relations` with the map's step)."""
    from lyapcheck.models.classes.barrier import check_on_relations

    if lam < 0:
        return False, "the rate lambda must be >= 0 (for {B <= 0} to be invariant)"
    if any(any(q[m.n:]) for q in m.ring.support(B)):
        return False, "B may depend on the states only"
    ok, why = check_on_relations(m.field, B, lam, initial, unsafe, proofs, decrease=step_of(m, B, lam))
    if not ok:
        return False, why
    return True, ("B <= 0 on the initial set, B >= 1 on the unsafe set and lambda B - B(F) >= 0 on the recasting's "
                  f"relations with lambda = {lam} >= 0, exactly: {{B <= 0}} holds at every step (discrete-time map "
                  "with functions)")


# -- the program -----------------------------------------------------------------------------------------

def barrier_structure(m: MapOnRelations, initial: Pieces, unsafe: Pieces, degree: int, at_fixed: bool = False
                      ) -> Structure | str:
    """The program for ``B`` of this degree (the sets' identities of a loop with functions, the map's step
    with the relations' multipliers), or why there is none (a size limit, named). ``at_fixed``: the step at
    ``lam = 1`` over a box, ``B - B(F)``, which is 0 at the fixed point for every value of the box: its
    remainder's basis holds no constant and the multipliers vanish there (facial reduction by construction:
    else the remainder's constant diagonal is 0 and so is the program's margin, which the exact check
    rejects)."""
    from lyapcheck.models.classes.lyapunov import TARGET_LIMIT
    from lyapcheck.models.engines.reasons import size_limit

    ring, view = m.ring, m.field
    nv = ring.nvars
    zero = tuple([0] * nv)
    program = step_program(m, initial, unsafe, degree)
    if isinstance(program, str):
        return program
    grams, scalars, supports = program.grams, program.scalars, program.supports
    terms = [Term(param(f"sB{i}", support), f"b{i}") for i, support in supports.items()]
    target = {q for support in supports.values() for q in support}
    rel_grams, rel_scalars, rel_terms, added = step_multipliers(m, view, "D", target, vanishing=at_fixed)
    grams.extend(rel_grams)
    scalars.extend(rel_scalars)
    terms.extend(rel_terms)
    target |= added
    if len(target) > TARGET_LIMIT:
        return size_limit(len(target), "monomials in one polynomial identity", TARGET_LIMIT, "TARGET_LIMIT")
    step_basis = [q for q in bases.sos_basis(nv, target | {zero}) if view.allowed(q) and not (at_fixed and q == zero)]
    if len(step_basis) > ds.MAX_GRAM_ROWS:
        return size_limit(len(step_basis), "monomials per sum-of-squares matrix", ds.MAX_GRAM_ROWS, "MAX_GRAM_ROWS")
    grams.append(Gram("RD", tuple(step_basis), full_blocks(step_basis)))
    terms.append(Term(one(ring, -1), "RD"))
    return ds._affordable_program(nv, grams, scalars, [*program.identities, Identity("D", tuple(terms), None, "RD")])


def barrier_values(m: MapOnRelations, degree: int, initial: Pieces, unsafe: Pieces, lam: Fraction
                   ) -> ParameterValues:
    """The barrier program's parameters at rate ``lam`` (:func:`step_values`, ``sB``)."""
    return step_values(m, degree, initial, unsafe, "sB", lam)


def attempt(m: MapOnRelations, structure: Structure, degree: int, initial: Pieces, unsafe: Pieces, lam: Fraction,
            search: Search) -> tuple[dict[str, Any] | None, Any]:
    """One solve at rate ``lam``: the exact certificate if it passes :func:`check_map_barrier`."""
    from lyapcheck.models.classes.barrier import _b_basis, relation_proofs

    point, solution = search.solve_exact(structure, barrier_values(m, degree, initial, unsafe, lam))
    if point is None:
        return None, solution
    B = m.ring.from_terms({q: point.scalars[f"b{i}"] for i, q in enumerate(_b_basis(m.field, degree))})
    proofs = relation_proofs(m.field, structure, point, initial, unsafe)
    if not check_map_barrier(m, B, lam, initial, unsafe, proofs)[0]:
        return None, solution
    return {"B": B, "lam": lam, "proofs": proofs}, solution


def search_barrier(m: MapOnRelations, initial: Pieces, unsafe: Pieces, search: Search
                   ) -> tuple[dict[str, Any] | None, list[str]]:
    """The first certificate over the degrees and rates, and what was tried."""
    from lyapcheck.degrees import searched_degrees

    tried: list[str] = []
    for degree in searched_degrees(ds.BARRIER_DEGREES):
        search.budget.check()
        structure = barrier_structure(m, initial, unsafe, degree)
        if isinstance(structure, str):
            tried.append(f"degree {degree}: {structure}")
            continue
        outcomes: dict[str, int] = {}
        for lam in ds.LAMBDAS:
            at: Structure | str = structure
            if m.params and lam == 1:  # (over a box, B - B(F) vanishes at the fixed point: barrier_structure)
                at = barrier_structure(m, initial, unsafe, degree, at_fixed=True)
            if isinstance(at, str):
                outcomes[at] = outcomes.get(at, 0) + 1
                continue
            found, solution = attempt(m, at, degree, initial, unsafe, lam, search)
            if found is not None:
                tried.append(f"degree {degree}: found at lambda = {lam}")
                return {**found, "degree": degree}, tried
            why = why_none(solution) if solution is not None else "none"
            outcomes[why] = outcomes.get(why, 0) + 1
        tried.append(f"degree {degree}: none at lambda = {', '.join(str(x) for x in ds.LAMBDAS)}: "
                     + ", ".join(f"{why} ({count})" for why, count in outcomes.items()))
    return None, tried


# -- the falsification and its re-derivation in ball arithmetic -------------------------------------------

def check_iterate_functions(model: "RecastModel", m: MapOnRelations, initial: Pieces, unsafe: Pieces,
                            start: Sequence[Fraction], steps: int, goal: Sequence[Poly] | None = None
                            ) -> tuple[bool, str]:
    """Whether the start ``e_0`` (deviations, exact) lies in the initial set (rationals) and its iterate
    ``e_steps`` of the TRUE map in the unsafe set: the iterates in ball arithmetic through the recasting's
    true functions (:class:`~lyapcheck.models.engines.interval_field.BallLoop` of the displacement,
    ``e+ = e + d(e)``, every function an outward-rounded ``arb`` ball, :data:`ITERATE_BITS` bits), every
    inequality of one unsafe piece ``>= 0`` on the whole final ball: a proof that the property fails. With
    ``goal`` (reach_avoid's one piece) every iterate before, ``e_0 .. e_(steps - 1)``, must also be proved
    outside the goal (some goal inequality ``< 0`` on its whole ball): then that start touches the unsafe set
    before any of its iterates is in the goal, which refutes "every start reaches the goal without an unsafe
    iterate before"."""
    import flint

    from lyapcheck.models.engines.interval_field import BallLoop

    if not 1 <= steps <= ds.MAX_STEPS:
        return False, f"the step count must be in [1, {ds.MAX_STEPS}], not {steps}"
    ring = m.ring
    if len(start) != m.n:
        return False, "the start must give one value per state"
    if not any(ds.in_piece_exact(ring, piece, start) for piece in initial):
        return False, "the start is not in the initial set (exact)"
    saved = flint.ctx.prec
    flint.ctx.prec = ds.ITERATE_BITS
    try:
        loop = BallLoop(m.system)  # (built at this precision: its constants' balls are)
        z: list[Any] = [flint.arb(flint.fmpq(v.numerator, v.denominator)) for v in start]
        for k in range(steps):
            if goal is not None and not any(ds.ball_value(ring, q, z) < 0 for q in goal):  # (arb: True if certain)
                return False, f"iterate {k} of the start is not proved to lie outside the goal (ball arithmetic)"
            z = [zi + di for zi, di in zip(z, loop.field(z))]
        for k, piece in enumerate(unsafe):
            if all(ds.ball_value(ring, p, z) >= 0 for p in piece):  # (arb: True only when certain)
                before = "" if goal is None else ", every iterate before it outside the goal"
                return True, (f"the start is in the initial set (exact) and its iterate {steps} of the true map lies "
                              f"in piece {k + 1} of the unsafe set{before} (ball arithmetic through the functions, "
                              f"{ds.ITERATE_BITS} bits)")
    finally:
        flint.ctx.prec = saved
    return False, f"iterate {steps} of the start is not proved to lie in the unsafe set (ball arithmetic)"


def refuted_first(name: str, model: "RecastModel", m: MapOnRelations, sets: Mapping[str, Any],
                  refute: "Callable[[], ConditionResult | None] | None") -> ConditionResult | None:
    """A safety class's refutation before its search: over a box ``refute`` (its corners and centre), else the
    point's falsification (:func:`falsify`; for ``reach_avoid`` an unsafe iterate before any in the goal),
    each re-derived in ball arithmetic; None where none was found."""
    if refute is not None:
        return refute()
    goal = sets["goal"][0] if name == "reach_avoid" else None
    found = falsify(model, m, sets["initial"], sets["unsafe"], goal)
    if found is None:
        return None
    return ds.refuted_result(name, model, found, " before any iterate is in the goal" if goal is not None else "")


def searched_on(name: str, model: "RecastModel", what: str, prop: "Property", keys: Sequence[str],
                box: "ModelBox | None", refute: "Callable[[], ConditionResult | None] | None"
                ) -> tuple[MapOnRelations, dict[str, list[list[Poly]]]] | ConditionResult:
    """The first steps of both safety classes of a map with functions: the relations and the sets
    (:func:`relations_and_sets`), then the refutation (:func:`refuted_first`); what the search runs on, or the
    class's result where it does not run (not taken, too large, refuted)."""
    ready = relations_and_sets(name, model, what, prop, keys, box)
    if isinstance(ready, ConditionResult):
        return ready
    refuted = refuted_first(name, model, ready[0], ready[1], refute)
    return ready if refuted is None else refuted


def verify_refuted(model: "RecastModel", c: Mapping[str, Any], box: "ModelBox | None", keys: Sequence[str]
                   ) -> tuple[bool, str]:
    """Re-check a refuted ``barrier`` (``keys`` initial, unsafe) or ``reach_avoid`` (initial, unsafe, goal: no
    iterate in the goal before the unsafe one) of a map with functions at the model's point: the stated start's
    iterate re-derived in ball arithmetic (:func:`check_iterate_functions`). Over a box the refutation is
    re-checked at its value of the box (:mod:`lyapcheck.models.classes.map_relations_safety_box`), not here."""
    if box is not None:  # (verify_discrete sends it to map_relations_safety_box)
        return False, "a refutation over a box is re-checked at its value of the box"
    try:
        m = on_relations(model)
        sets = map_sets(model, m, keys)
        goal = sets["goal"][0] if "goal" in keys else None
        return ds.verify_refutation(model, c, lambda start, steps: check_iterate_functions(
            model, m, sets["initial"], sets["unsafe"], start, steps, goal))
    except NotTaken as exc:
        return False, str(exc)
    except (KeyError, TypeError, ValueError, ZeroDivisionError, AttributeError) as exc:
        return False, f"malformed refutation: {exc}"


def falsify(model: "RecastModel", m: MapOnRelations, initial: Pieces, unsafe: Pieces,
            goal: Sequence[Poly] | None = None) -> ds.Counterexample | None:
    """The true map iterated in floating point (each function by numpy,
    :class:`~lyapcheck.models.engines.recast_numeric.TrueField` of the displacement) from starts sampled in
    the initial set, as a polynomial map's :func:`~lyapcheck.models.classes.discrete_safety.falsify_map`; the
    first iterate in the unsafe set is re-derived by :func:`check_iterate_functions`, its start rounded to
    :data:`~lyapcheck.models.classes.discrete_safety.START_DIGITS` digits. None when none is proved. With
    ``goal`` (reach_avoid), a start is followed only until an iterate is in the goal, and the re-derivation
    proves every earlier iterate outside it."""
    import numpy as np

    from lyapcheck.exact import to_rational
    from lyapcheck.models.classes.falsify import sample_set
    from lyapcheck.models.engines.iteration import BoolArray, FloatArray, IntArray, iterate_map
    from lyapcheck.models.engines.recast_numeric import TrueField
    from lyapcheck.models.language.sets import margin

    rng = np.random.default_rng(20261130)
    try:
        starts = sample_set(model, model.sets["initial"], margin, ds.FALSIFY_STARTS, rng)[0]  # type: ignore[arg-type]
    except ValueError:
        return None
    eq = np.array([float(v) for v in model.equilibrium])
    displacement = TrueField(model.system)
    found: list[ds.Counterexample] = []

    def step(e: FloatArray) -> FloatArray:
        with np.errstate(all="ignore"):  # (an overflow gives a row that is not finite: that start is done)
            return np.asarray(e + displacement(e + eq), dtype=np.float64)

    def stop(x: FloatArray) -> BoolArray:
        """A row that is not finite is done; so is one in the goal (reach_avoid holds for that start)."""
        done = ~np.all(np.isfinite(x), axis=1)
        if goal is not None:
            done |= margin(model.sets["goal"], x + eq) >= 0
        return np.asarray(done)

    def unsafe_hit(k_step: int, rows: IntArray, x: FloatArray) -> bool:
        hit = np.all(np.isfinite(x), axis=1) & (margin(model.sets["unsafe"], x + eq) >= 0)
        for k in rows[hit]:
            start = tuple(to_rational(float(v), ds.START_DIGITS) - xe for v, xe in zip(starts[k], model.equilibrium))
            if check_iterate_functions(model, m, initial, unsafe, start, k_step, goal)[0]:
                found.append(ds.Counterexample(start, k_step))
                return True
        return False

    iterate_map(step, starts - eq, ds.FALSIFY_STEPS, observe=unsafe_hit, stop=stop)
    return found[0] if found else None


# -- the class -------------------------------------------------------------------------------------------

def stated_map(model: "RecastModel", c: Mapping[str, Any], box: "ModelBox | None", kind: str, name: str,
               keys: Sequence[str]) -> tuple[Mapping[str, Any], MapOnRelations, dict[str, list[list[Poly]]]] | str:
    """The first steps of re-checking a certified safety class of a map with functions (``barrier``, ``reach_avoid``):
    the certificate (of ``kind``, a discrete-time one), its ``parameter_box`` (:func:`stated_box`), the map read on
    its relations again (over ``box``), the certificate's variables and functions the map's, and the sets named
    ``keys`` in its ring; or why not (one line)."""
    cert = c["certificate"]
    if cert.get("kind") != kind or cert.get("time") != "discrete":
        return f"not a {name} certificate of a discrete-time map (kind {cert.get('kind')!r})"
    ok, why = stated_box(cert, box, model)
    if not ok:
        return why
    m = read_map(model, box)
    if cert.get("variables") != list(m.ring.names) or cert.get("auxiliaries") != m.system.definitions():
        return "the certificate's variables or functions are not the map's"
    return cert, m, map_sets(model, m, keys, box)


def stated_box(cert: Mapping[str, Any], box: "ModelBox | None", model: "RecastModel") -> tuple[bool, str]:
    """A certificate's ``parameter_box``: the document's box over a box (whose parameters no set names),
    absent at a point."""
    from lyapcheck.models.classes.barrier import SETS_USE_BOX, sets_use_box

    if box is not None and sets_use_box(model, box):
        return False, SETS_USE_BOX
    if box is not None and cert.get("parameter_box") != box.to_json():
        return False, "a certificate over a box states that box (parameter_box) as the document's"
    if box is None and "parameter_box" in cert:
        return False, "a certificate over a box (parameter_box) in a document without that box"
    return True, ""


def without_box_words(c: Mapping[str, Any], box: "ModelBox | None") -> object:
    """A claim's sentence without the box's words in front (``for every k in [...]: ``), then a disturbed
    map's ``(d = 0) `` after them (claims.summary puts them in that order)."""
    text = c.get("summary")
    if box is None or not isinstance(text, str):
        return text
    from lyapcheck.models.classes.claims import DISTURBANCE_PREFIX, box_words

    text = text.removeprefix(f"for every {box_words(box.to_json())}: ")
    return text.removeprefix(DISTURBANCE_PREFIX["zero"]) if c.get("disturbances") == "zero" else text


def _proofs_json(m: MapOnRelations, proofs: Mapping[str, "ConditionCertificate"]) -> dict[str, Any]:
    return {name: proof.to_json(m.ring) for name, proof in proofs.items()}


def run_barrier(model: "RecastModel", budget: Budget, box: "ModelBox | None" = None,
                refute: "Callable[[], ConditionResult | None] | None" = None) -> ConditionResult:
    """``barrier`` on a map with functions (module docstring): the falsification first (``refuted`` with an
    iterate proved unsafe), then ``certified`` only after :func:`check_map_barrier`. ``box``: one ``B`` for
    every value of that box of the map's parameters (:func:`read_map`), the falsification ``refute`` at its
    corners and centre instead of the point's (:func:`lyapcheck.models.classes.map_relations_safety_box.refute`,
    which imports this module)."""
    from lyapcheck.models.classes.lyapunov import terms_json

    ruled = ds.no_sets("barrier", model)
    if ruled is not None:
        return ruled
    ready = searched_on("barrier", model, "barrier", "safety", ("initial", "unsafe"), box, refute)
    if isinstance(ready, ConditionResult):
        return ready
    m, sets = ready
    search = Search(m.ring, budget)
    try:
        found, tried = search_barrier(m, sets["initial"], sets["unsafe"], search)
    except BudgetExhausted as exc:
        late = reasons.out_of_time("a barrier of the discrete-time map", budget.seconds, str(exc))
        return ConditionResult("barrier", "inconclusive", late.summary, solver={"solves": search.log},
                               numbers=late.numbers({"reason": str(exc), "time": "discrete"}), property="safety")
    if found is None:
        from lyapcheck.degrees import searched_degrees

        none = reasons.not_found("barrier on the recasting's relations", searched_degrees(ds.BARRIER_DEGREES), tried,
                                 ("degree", "sets", "time"))
        return ConditionResult("barrier", "not_certified", none.summary, solver={"solves": search.log}, numbers=none.numbers({"tried": tried, "time": "discrete"}),
                               property="safety")
    ring = m.ring
    cert = {"kind": KIND, "time": "discrete", "coordinates": "shifted", "variables": list(ring.names),
            "auxiliaries": m.system.definitions(), "degree": found["degree"], "lambda": str(found["lam"]),
            "B": terms_json(ring, found["B"]), "proofs": _proofs_json(m, found["proofs"])}
    if box is not None:  # (the box's parameters are among the variables, bounded: one B for every value)
        cert["parameter_box"] = box.to_json()
    return ConditionResult("barrier", "certified", DISCRETE_BARRIER_SENTENCE,
                           numbers={"degree": found["degree"], "lambda": float(found["lam"]), "time": "discrete"},
                           certificate=cert, solver={"solves": search.log}, property="safety")


def verify_barrier(model: "RecastModel", c: Mapping[str, Any], box: "ModelBox | None" = None) -> tuple[bool, str]:
    """Re-check a certified ``barrier`` of a map with functions from its JSON and the model text alone: the map,
    its relations and the sets re-derived, every identity exactly, the stated degree, rate and sentence.
    ``box``: the document's box, which a certificate states (``parameter_box``) and whose parameters are
    bounded variables of its relations (a refutation over a box:
    :func:`lyapcheck.models.classes.map_relations_safety_box.verify_refutation`)."""
    from lyapcheck.exact import read_rational
    from lyapcheck.models.classes.barrier import conditions
    from lyapcheck.models.engines.recast_sos import ConditionCertificate, poly_from_json

    if c.get("property") != "safety":
        return False, f"a barrier claim is about safety, not {c.get('property')}"
    if ds.no_sets("barrier", model) is not None:
        return False, "the model has no [sets] initial and unsafe for barrier"
    if c.get("status") == "refuted":
        return verify_refuted(model, c, box, ("initial", "unsafe"))
    try:
        read = stated_map(model, c, box, KIND, "barrier", ("initial", "unsafe"))
        if isinstance(read, str):
            return False, read
        cert, m, sets = read
        ring = m.ring
        B = poly_from_json(ring, cert["B"], "B")
        lam = read_rational(cert["lambda"], "lambda")
        wanted = conditions(m.field, B, lam, sets["initial"], sets["unsafe"], step_of(m, B, lam))
        stated = cert["proofs"]
        if set(stated) != {name for name, _, _ in wanted}:
            return False, "the certificate's identities are not the sets' pieces and the step"
        proofs = {name: ConditionCertificate.from_json(ring, stated[name], len(relations))
                  for name, _, relations in wanted}
    except NotTaken as exc:
        return False, str(exc)
    except (KeyError, TypeError, ValueError, ZeroDivisionError, AttributeError, IndexError) as exc:
        return False, f"malformed certificate: {exc}"
    ok, why = check_map_barrier(m, B, lam, sets["initial"], sets["unsafe"], proofs)
    if not ok:
        return False, why
    degree = ds.poly_degree(ring, B)
    if cert.get("degree") != degree or c.get("degree") != degree:
        return False, "the stated degree is not the certificate's polynomial's"
    if c.get("lambda") != float(lam):
        return False, "the stated lambda is not the certificate's"
    if without_box_words(c, box) != DISCRETE_BARRIER_SENTENCE:
        return False, "the stated sentence is not the certificate's"
    return True, why


__all__ = ["KIND", "map_sets", "read_map", "relations_and_sets", "searched_on", "verify_refuted", "StepProgram",
           "step_program", "step_values", "sets_view", "step_multipliers", "step_supports",
           "stated_box", "without_box_words", "step_of", "check_map_barrier", "barrier_structure", "search_barrier",
           "check_iterate_functions", "falsify", "run_barrier", "verify_barrier"]
