"""``reach_avoid``: every trajectory from the initial set reaches the goal, in a bounded time, without
entering the unsafe set; found by SOS and checked exactly.

The certificate (kind ReachAvoid of :mod:`lyapcheck.sos.certificates`), in the scaled coordinates
and on the robust field of :mod:`lyapcheck.models.classes.barrier` (a disturbance that enters is a box
coordinate), with a free polynomial ``V`` of the states, scalars ``eps, delta > 0`` and ``C``:

    -V - sum_i s_i h_i = r_I                          each initial piece      (V <= 0 there)
    V - 1 - sum_j t_j h_j = r_U                       each unsafe piece       (V >= 1 there)
    -grad V . g - eps D + s_k q_k - sum r (1 - u^2) = r_k   each goal inequality q_k (V' <= -eps where q_k <= 0)
    V + C - delta |z|^2 = r_B                                                  (V >= delta |z|^2 - C)

The goal is one piece ``{q_1 >= 0, ..., q_m >= 0}``: outside it some ``q_k < 0``, where ``V`` falls
at rate ``eps`` at least. From a start with ``V <= 0`` the trajectory keeps ``V <= 0`` (so it never
meets the unsafe set, where ``V >= 1``) and stays in the compact ``{V <= 0}``; ``V`` cannot fall
below ``-C``, so the goal is reached by the time ``C / eps``. The decrease is demanded outside the
goal everywhere, not only on ``{V <= 0}`` (that would make the program bilinear): a sufficient,
conservative form. The claim is reach-while-avoid; staying in the goal afterwards is not claimed.

One program for both kinds of loop (issue 41: one implementation of the class): :func:`reach_structure`
reads a polynomial loop's robust field or a loop with functions' view of the same shape
(:class:`~lyapcheck.models.classes.bounds.BoundField`, as ``barrier``'s program does). A polynomial or
rational loop (:func:`run`) is the case without relations: its program is the one this class has always
built, checked by :func:`~lyapcheck.sos.certificates.check_reach_avoid` (an engine below this package).
A loop with functions (:func:`run_functions`, the section "loops with functions" below) is the same
program with the recasting's relations' multipliers in every identity
(:func:`~lyapcheck.models.classes.bounds.relation_multipliers`; the goal's failing inequality one more
relation there), each identity's proof stored by relation index and re-checked exactly
(:func:`check_functions`) against :func:`conditions`, which states the conditions once as polynomials
(``F >= 0`` where a set holds); its certificate is of kind :data:`KIND`. Both share the degrees
:data:`REACH_DEGREES`, the goal's form (:func:`goal_of_one_piece`), the time bound (:func:`time_bound`),
their results (:func:`not_found`, :func:`out_of_time`, :func:`certified_numbers`) and the sentence
(:func:`lyapcheck.models.classes.claims.summary`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from fractions import Fraction
from typing import TYPE_CHECKING, Any, Callable, Final, Sequence

from lyapcheck.degrees import searched_degrees
from lyapcheck.models.classes.barrier import (BudgetExhausted, Pieces, _b_basis, _decrease_poly, _decrease_support,
                                      _shift, add_piece_multipliers, as_barrier_field, remainder_basis, scaled_pieces,
                                      set_certificates, set_identities, set_values)
from lyapcheck.models.loop.field import ScaledField, StateField
from lyapcheck.models.engines import reasons
from lyapcheck.models.classes.lyapunov import on_remainder_faces, within_cost
from lyapcheck.models.engines.search import (ParameterValues, Search, box_multipliers, box_multipliers_of, box_support,
                                     exact_grams, multiplier_grams, one, param, why_none)
from lyapcheck.results import ConditionResult
from lyapcheck.sos import bases
from lyapcheck.sos.certificates import check_reach_avoid
from lyapcheck.sos.polynomials import Monomial, Poly, Ring, monomials, to_fmpq
from lyapcheck.sos.program import Coefficients, Gram, Identity, Scalar, Solution, Structure, Term, full_blocks
from lyapcheck.models.classes.claims import RECAST_REACH_AVOID_KIND

if TYPE_CHECKING:
    from lyapcheck.models.classes.barrier import Template
    from lyapcheck.models.classes.bounds import BoundField
    from lyapcheck.models.classes.recast_classes import Loop
    from lyapcheck.models.engines.recast_sos import ConditionCertificate
    from lyapcheck.models.engines.search import Budget
    from lyapcheck.models.language.parameter_box import ModelBox
    from lyapcheck.models.language.recast import RecastModel, Relation

    #: a set's pieces as relations of a loop with functions (one list per piece)
    RelationPieces = list[list[Relation]]

#: degrees of V tried, in turn
REACH_DEGREES: Final = (2, 4)
#: the largest Gram basis the search builds (rows)
MAX_GRAM_ROWS: Final = 120
#: why stay_in_goal cannot hold: the set it needs contains the equilibrium
NOT_IN_GOAL: Final = "the equilibrium is not inside the goal (some goal inequality is not > 0 there)"
#: the program's unknowns besides V's coefficients ``b0, b1, ...`` (the time bound is ``C / eps``)
SCALARS: Final = ("eps", "C", "delta")


# -- the formulation, once for every route ----------------------------------------------------------

@dataclass(frozen=True)
class Condition:
    """One condition of the certificate (module docstring): ``F >= 0`` wherever ``on`` holds:
    ``initial`` or ``unsafe`` (piece ``index`` of the set), ``outside_goal`` (where goal inequality
    ``index`` is ``<= 0``) or ``everywhere``; ``what`` says it in words."""

    name: str
    F: Poly
    on: str
    index: int
    what: str


def conditions(ring: Ring, V: Poly, lie: Callable[[Poly], Poly], D: Poly, eps: Fraction, C: Fraction,
               delta: Fraction, square: Poly, initial: int, unsafe: int, goal: int) -> list[Condition]:
    """The conditions of a reach-avoid certificate with ``V``, ``x' = N / D`` (``lie(V)``: ``grad V . N``,
    ``D > 0``), ``square`` the states' ``|z|^2``, and the number of initial and unsafe pieces and of
    goal inequalities: ``-V`` on each initial piece, ``V - 1`` on each unsafe piece, ``-lie(V) - eps D``
    outside each goal inequality, ``V + C - delta |z|^2`` everywhere."""
    one = ring.constant(1)
    out = [Condition(f"I{k}", -V, "initial", k, "V <= 0 on the initial set") for k in range(initial)]
    out += [Condition(f"U{k}", V - one, "unsafe", k, "V >= 1 on the unsafe set") for k in range(unsafe)]
    decrease = -lie(V) - D * to_fmpq(eps)
    out += [Condition(f"goal{i}", decrease, "outside_goal", i, f"V' <= -eps where goal inequality {i + 1} fails")
            for i in range(goal)]
    out.append(Condition("bounded", V + one * to_fmpq(C) - square * to_fmpq(delta), "everywhere", 0,
                         "V >= delta |z|^2 - C"))
    return out


def goal_of_one_piece(goal: Sequence[Any]) -> ConditionResult | None:
    """``not_applicable`` when the goal is a union of several pieces (the decrease is demanded where
    one piece's inequality fails); None for one piece."""
    if len(goal) == 1:
        return None
    return ConditionResult("reach_avoid", "not_applicable",
                           f"the goal must be one piece (an intersection of inequalities); it has {len(goal)}",
                           property="reach_avoid")


def time_bound(C: Fraction, eps: Fraction, time_unit: Fraction = Fraction(1)) -> Fraction:
    """The time by which the goal is reached: ``C / eps`` (in the route's time, times its unit in seconds)."""
    return C / eps * time_unit


def not_found(tried: list[str], log: Any, degrees: Sequence[int] = REACH_DEGREES,
              numbers: dict[str, Any] | None = None, cause: str | None = None) -> ConditionResult:
    """``not_certified``: no certificate passed the exact check (what was tried, and why; ``cause``:
    why none can exist, said instead of what to try next)."""
    none = reasons.reason(cause, (), tried) if cause else \
        reasons.not_found("reach-avoid function", degrees, tried, ("degree", "sets", "time"))
    return ConditionResult("reach_avoid", "not_certified", none.summary,
                           numbers={**none.numbers({"tried": tried}), **(numbers or {})}, solver={"solves": log},
                           property="reach_avoid")


def out_of_time(seconds: float, exc: Exception, log: Any, numbers: dict[str, Any] | None = None) -> ConditionResult:
    """``inconclusive``: the search ran out of its budget."""
    late = reasons.out_of_time("a reach-avoid function", seconds, str(exc))
    return ConditionResult("reach_avoid", "inconclusive", late.summary,
                           numbers={**late.numbers({"reason": str(exc)}), **(numbers or {})}, solver={"solves": log},
                           property="reach_avoid")


def certified_numbers(degree: int, bound_s: Fraction, trial: Any, margin: float | None = None) -> dict[str, Any]:
    """A certified reach-avoid's figures: V's degree, the time bound (s), the search's margin, and the
    simulation beside the proof (the avoid half: a simulated trajectory into the unsafe set beside a
    certificate is a soundness alarm)."""
    numbers: dict[str, Any] = {"degree": degree, "reach_time_bound_s": float(bound_s)}
    if margin is not None:
        numbers["relative_margin"] = margin
    if trial is not None:
        numbers["falsification"] = trial.to_dict()
        numbers["closest_approach"] = trial.closest_approach
        if trial.entered:
            numbers["soundness_violation"] = True
    return numbers


def reach_structure(field: "StateField | BoundField", initial: Pieces, unsafe: Pieces, goal: Sequence[Poly],
                    degree: int, drop: frozenset[tuple[str, Monomial]] = frozenset(), within: bool = False
                    ) -> Structure | str:
    """The program for ``V`` of this degree, or why there is none (a size limit, named). ``field``: a
    polynomial loop's robust field, or a loop with functions' view
    (:func:`~lyapcheck.models.classes.barrier.relations_field`), whose relations get their multipliers
    (:func:`~lyapcheck.models.classes.bounds.relation_multipliers`) in every identity; a polynomial loop's
    program is the one this class has always built. ``within``: also ``T eps - C >= 0`` (``T`` the
    parameter ``within``: the time bound ``C / eps`` at most ``T``, :func:`tightened`)."""
    from lyapcheck.models.classes.bounds import relation_multipliers

    view = as_barrier_field(field)
    ring = field.ring
    nv = ring.nvars
    n = view.n
    zero = tuple([0] * nv)
    v_basis = _b_basis(view, degree)
    grams: list[Gram] = []
    relation_scalars: list[Scalar] = []
    on_sets = set_identities(view, v_basis, degree, initial, unsafe, grams, drop, relation_scalars)
    if isinstance(on_sets, str):
        return on_sets
    identities = list(on_sets)
    lie = [(i, _decrease_support(view, m, with_rate=False)) for i, m in enumerate(v_basis)]
    d_support = ring.support(view.W)
    for k, q in enumerate(goal):
        terms = [Term(param(f"L{i}", support), f"b{i}") for i, support in lie if support]
        terms.append(Term(param("negD", d_support), "eps"))
        target = {m for _, support in lie for m in support} | set(d_support)
        goal_view = view
        if view.relations:  # a loop with functions: the failing goal inequality, -q >= 0, is one more relation
            goal_view = outside_goal_view(view, q, k)
        else:
            top = max((sum(m[:n]) for m in target), default=2)
            half = max(0, (top - max(sum(m) for m in ring.support(q))) // 2)
            s_basis = [tuple(list(m) + [0] * (nv - n)) for m in monomials(n, 0, half)]
            grams.append(Gram(f"sG{k}", tuple(s_basis), full_blocks(s_basis)))
            terms.append(Term(param(f"q{k}", ring.support(q)), f"sG{k}"))
            target |= _shift(ring.support(q), [tuple(a + b for a, b in zip(x, y)) for x in s_basis for y in s_basis])
        box_grams, box_terms = box_multipliers(nv, n, target, with_states=False, prefix=f"rG{k}_",
                                               box_vars=view.box_vars)
        target |= box_support(box_grams, nv)
        rel_grams, rel_scalars, rel_terms, added = relation_multipliers(goal_view, f"goal{k}", target, (),
                                                                        margin=True)
        target |= added
        name = f"RG{k}"
        basis = remainder_basis(nv, target, name, drop, view.allowed, MAX_GRAM_ROWS)
        if isinstance(basis, str):
            return basis
        grams.append(Gram(name, tuple(basis), full_blocks(basis)))
        grams.extend(box_grams)
        terms.extend(box_terms)
        grams.extend(rel_grams)
        terms.extend(rel_terms)
        relation_scalars.extend(rel_scalars)
        terms.append(Term(one(ring, -1), name))
        identities.append(Identity(f"goal{k}", tuple(terms), None, name))
    # V + C - delta |z|^2 = R_B
    terms = [Term(Coefficients.literal({m: 1}), f"b{i}") for i, m in enumerate(v_basis)]
    terms.append(Term(one(ring, 1), "C"))
    squares = {tuple(2 * int(j == i) for j in range(nv)): -1 for i in range(n)}
    terms.append(Term(Coefficients.literal(squares), "delta"))
    target = set(v_basis) | set(squares) | {zero}
    rel_grams, rel_scalars, rel_terms, added = relation_multipliers(view, "bounded", target, (), margin=True)
    basis = [m for m in bases.sos_basis(nv, target | added) if ("RB", m) not in drop and view.allowed(m)]
    grams.append(Gram("RB", tuple(basis), full_blocks(basis)))
    grams.extend(rel_grams)
    terms.extend(rel_terms)
    relation_scalars.extend(rel_scalars)
    terms.append(Term(one(ring, -1), "RB"))
    identities.append(Identity("bounded", tuple(terms), None, "RB"))
    if within:  # T eps - C = s >= 0
        grams.append(Gram("RT", (zero,), full_blocks([zero])))
        identities.append(Identity("within", (Term(param("within", [zero]), "eps"), Term(one(ring, -1), "C"),
                                              Term(one(ring, -1), "RT")), None, "RT"))
    scalars = tuple(Scalar(f"b{i}") for i in range(len(v_basis))) + (
        Scalar("eps", "margin"), Scalar("delta", "margin"), Scalar("C", "zero")) + tuple(relation_scalars)
    structure = Structure(nvars=nv, grams=tuple(grams), scalars=scalars, identities=tuple(identities),
                          objective=("max_margin",))
    return within_cost(structure)


def outside_goal_view(view: "BoundField", q: Poly, k: int) -> "BoundField":
    """A loop with functions' view for goal inequality ``k``'s identity: its relations and ``-q >= 0`` (the
    inequality failing) after them, every one multiplied (its multiplier is built as the recasting's are,
    :func:`~lyapcheck.models.classes.bounds.relation_multipliers`, and stored at that index, as
    :func:`where` lists the relations)."""
    from dataclasses import replace

    from lyapcheck.models.classes.barrier import SET_OWNER
    from lyapcheck.models.language.recast import Relation

    failing = Relation("ge", -q, f"goal inequality {k + 1} fails", SET_OWNER)
    return replace(view, relations=view.relations + (failing,), multiplied=view.multiplied + (len(view.relations),))


def reach_values(field: "StateField | BoundField", degree: int, initial: Pieces, unsafe: Pieces,
                 goal: Sequence[Poly]) -> ParameterValues:
    view = as_barrier_field(field)
    ring = field.ring
    values = ParameterValues()
    set_values(view, values, initial, unsafe)
    for i, m in enumerate(_b_basis(view, degree)):
        support = _decrease_support(view, m, with_rate=False)
        if support:
            values.set_poly(ring, f"L{i}", _decrease_poly(view, m, Fraction(0)), support)
    values.set_poly(ring, "negD", -view.W, ring.support(view.W))
    for k, q in enumerate(goal):
        values.set_poly(ring, f"q{k}", q, ring.support(q))
    return values


def attempt(field: StateField, structure: Structure, degree: int, initial: Pieces, unsafe: Pieces,
            goal: Sequence[Poly], search: Search) -> tuple[dict[str, Any] | None, Solution]:
    point, solution = search.solve_exact(structure, reach_values(field, degree, initial, unsafe, goal))
    if point is None:
        return None, solution
    ring = field.ring
    V = ring.from_terms({m: point.scalars[f"b{i}"] for i, m in enumerate(_b_basis(field, degree))})
    grams = exact_grams(structure, point)
    initial_certs, unsafe_certs = set_certificates(structure, grams, initial, unsafe)
    goal_certs = [(grams[f"sG{k}"], grams[f"RG{k}"]) for k in range(len(goal))]
    boxes = [box_multipliers_of(point.grams, multiplier_grams(structure, f"rG{k}_")) for k in range(len(goal))]
    eps, delta, C = point.scalars["eps"], point.scalars["delta"], point.scalars["C"]
    ok, _ = check_reach_avoid(ring, field.g, field.D, V, eps, C, delta, initial, initial_certs, unsafe, unsafe_certs,
                              goal, goal_certs, grams["RB"], boxes)
    if not ok:
        return None, solution
    return {"V": V, "eps": eps, "delta": delta, "C": C, "initial": initial_certs, "unsafe": unsafe_certs,
            "goal": goal_certs, "bounded": grams["RB"], "boxes": boxes,
            "margin": solution.scalars.get("t", 0.0)}, solution


def search_reach(field: StateField, initial: Pieces, unsafe: Pieces, goal: Sequence[Poly], search: Search
                 ) -> tuple[dict[str, Any] | None, list[str]]:
    tried: list[str] = []
    for degree in searched_degrees(REACH_DEGREES):
        structure: Structure | str = reach_structure(field, initial, unsafe, goal, degree)
        if isinstance(structure, str):
            tried.append(f"degree {degree}: {structure}")
            continue
        # (the lambdas run within this iteration: degree is this iteration's)
        found, solution = on_remainder_faces(
            structure, lambda drop: reach_structure(field, initial, unsafe, goal, degree, drop),
            lambda program: attempt(field, program, degree, initial, unsafe, goal, search), search)
        if found is not None:
            found["degree"] = degree
            tried.append(f"degree {degree}: found")
            return found, tried
        tried.append(f"degree {degree}: {why_none(solution)}")
    return None, tried


#: degrees of W (the invariant set {W <= 0} inside the goal) and its rates mu, for stay_in_goal
STAY_DEGREES: Final = (2, 4)
STAY_RATES: Final = (Fraction(-1, 4), Fraction(0), Fraction(1))


def stay_structure(field: StateField, goal: Sequence[Poly], degree: int) -> Structure | str:
    """The program for W: ``W + q_i = R_i`` for each goal inequality (so ``q_i >= -W >= 0`` where
    ``W <= 0``), ``-grad W . g + mu W D - box = R_W``, and W's constant fixed to ``-w0`` (a
    parameter: the equilibrium inside ``{W <= 0}``; ``w0`` half the smallest ``q_i(0)``)."""
    ring = field.ring
    nv = ring.nvars
    zero = tuple([0] * nv)
    w_basis = [m for m in _b_basis(field, degree) if any(m)]  # the constant is -w0, not a decision
    grams: list[Gram] = []
    identities: list[Identity] = []
    for i, q in enumerate(goal):
        terms = [Term(Coefficients.literal({m: 1}), f"b{k}") for k, m in enumerate(w_basis)]
        target = set(w_basis) | set(ring.support(q)) | {zero}
        basis = bases.sos_basis(nv, target)
        grams.append(Gram(f"RQ{i}", tuple(basis), full_blocks(basis)))
        terms.append(Term(one(ring, -1), f"RQ{i}"))
        # the constant: q_i - w0 (-w0 is W's constant, fixed)
        identities.append(Identity(f"inside{i}", tuple(terms), param(f"q{i}", set(ring.support(q)) | {zero}),
                                   f"RQ{i}"))
    terms = [Term(param(f"dW{k}", support), f"b{k}") for k, m in enumerate(w_basis)
             if (support := _decrease_support(field, m))]
    target = {mm for t in terms for mm in t.coefficients.support} | set(ring.support(field.D))
    box_grams, box_terms = box_multipliers(nv, field.n, target, with_states=False, prefix="rW")
    target |= box_support(box_grams, nv)
    w_remainder = remainder_basis(nv, target, "RW", frozenset(), max_rows=MAX_GRAM_ROWS)
    if isinstance(w_remainder, str):
        return w_remainder
    grams.append(Gram("RW", tuple(w_remainder), full_blocks(w_remainder)))
    grams.extend(box_grams)
    terms += [*box_terms, Term(one(ring, -1), "RW")]
    identities.append(Identity("invariant", tuple(terms), param("muD0", ring.support(field.D)), "RW"))
    scalars = tuple(Scalar(f"b{k}") for k in range(len(w_basis)))
    structure = Structure(nvars=nv, grams=tuple(grams), scalars=scalars, identities=tuple(identities),
                          objective=("max_margin",))
    return within_cost(structure)


def find_goal_invariant(field: StateField, goal: Sequence[Poly], search: Search
                        ) -> tuple[dict[str, Any] | None, list[str]]:
    """A W with ``{W <= 0}`` inside the goal, containing the equilibrium, that no trajectory leaves."""
    from lyapcheck.sos.certificates import check_goal_invariant

    ring = field.ring
    zero = tuple([0] * ring.nvars)
    tried: list[str] = []
    at_equilibrium = [ring.evaluate(q, [Fraction(0)] * ring.nvars) for q in goal]
    if min(at_equilibrium) <= 0:
        return None, [NOT_IN_GOAL]
    w0 = min(at_equilibrium) / 2
    for degree in searched_degrees(STAY_DEGREES):
        structure = stay_structure(field, goal, degree)
        if isinstance(structure, str):
            tried.append(f"W of degree {degree}: {structure}")
            continue
        w_basis = [m for m in _b_basis(field, degree) if any(m)]
        for mu in STAY_RATES:
            search.budget.check()
            values = ParameterValues()
            for i, q in enumerate(goal):
                values.set_poly(ring, f"q{i}", q - ring.constant(w0), set(ring.support(q)) | {zero})
            for k, m in enumerate(w_basis):
                support = _decrease_support(field, m)
                if support:
                    values.set_poly(ring, f"dW{k}", _decrease_poly(field, m, mu), support)
            # W's constant -w0 in the invariance identity: -grad(-w0) . g + mu (-w0) D = -mu w0 D
            values.set_poly(ring, "muD0", field.D * _q(-mu * w0), ring.support(field.D))
            point, _ = search.solve_exact(structure, values)
            if point is None:
                continue
            W = ring.from_terms({m: point.scalars[f"b{k}"] for k, m in enumerate(w_basis)}) - ring.constant(w0)
            grams = exact_grams(structure, point)
            box = box_multipliers_of(point.grams, multiplier_grams(structure, "rW"))
            inside = [grams[f"RQ{i}"] for i in range(len(goal))]
            ok, _ = check_goal_invariant(ring, field.g, field.D, W, mu, goal, inside, grams["RW"], box)
            if ok:
                tried.append(f"W of degree {degree}: found at mu = {mu}")
                return {"W": W, "mu": mu, "inside": inside, "decrease": grams["RW"], "box": box,
                        "degree": degree}, tried
        tried.append(f"W of degree {degree}: none at mu = {', '.join(str(x) for x in STAY_RATES)}")
    return None, tried


def _q(x: Fraction) -> Any:
    return to_fmpq(x)


def certificate_json(scaled: ScaledField, field: StateField, found: dict[str, Any]) -> dict[str, Any]:
    from lyapcheck.models.classes.lyapunov import stated_v

    def piece(cert: Any) -> dict[str, Any]:
        multipliers, remainder = cert
        return {"multipliers": [s.to_json() for s in multipliers], "remainder": remainder.to_json()}

    out: dict[str, Any] = {
        "kind": "reach_avoid", "degree": found["degree"], "eps_scaled": str(found["eps"]),
        "delta_scaled": str(found["delta"]), "C_scaled": str(found["C"]),
        "V": stated_v(scaled, field, found["V"]),
        "V_scaled": {"terms": [[str(c), list(m)] for m, c in sorted(field.ring.terms(found["V"]).items())]},
        "initial": [piece(c) for c in found["initial"]], "unsafe": [piece(c) for c in found["unsafe"]],
        "goal": [{"multiplier": s.to_json(), "remainder": r.to_json()} for s, r in found["goal"]],
        "gram_bounded": found["bounded"].to_json()}
    if any(found["boxes"]):
        out["box_multipliers"] = [[{"variable": j, "gram": r.to_json()} for j, r in box] for box in found["boxes"]]
    return out


def falsification(model: Any) -> Any:
    """Trajectories from the initial set under every disturbance scenario, as beside a barrier
    (:func:`lyapcheck.models.classes.barrier._falsification`'s starts), each watched until it reaches the
    goal (:func:`lyapcheck.models.classes.falsify.falsify`'s ``stop``): an entry into the unsafe set after
    the goal does not count (the claim is reach-while-avoid). None when the simulation cannot run."""
    from lyapcheck.models.classes.barrier import FALSIFICATION_FEW_ABOVE, FALSIFICATION_SAMPLES
    from lyapcheck.models.classes.falsify import falsify
    from lyapcheck.models.language.sets import margin

    samples = FALSIFICATION_SAMPLES if model.n <= FALSIFICATION_FEW_ABOVE else FALSIFICATION_SAMPLES // 2
    try:
        return falsify(model, model.sets["initial"], model.sets["unsafe"], margin, samples=samples,
                       stop=model.sets["goal"])
    except ValueError:
        return None


def counterexample(model: Any, trial: Any) -> ConditionResult:
    """``counterexample``: a simulated trajectory from the initial set enters the unsafe set before it
    reaches the goal (``verify`` re-simulates it from its start and disturbance)."""
    entry = trial.entry.describe(list(model.states), list(model.disturbances), model.units)
    return ConditionResult("reach_avoid", "counterexample",
                           f"a simulated trajectory from the initial set enters the unsafe set before it reaches "
                           f"the goal: {entry} (simulation, reproducible from its start and disturbance)",
                           numbers={"falsification": trial.to_dict()},
                           refutation={"kind": "trajectory", **trial.entry.to_dict()}, property="reach_avoid")


def run(scaled: ScaledField, search: Search) -> ConditionResult:
    """The ``reach_avoid`` class on the model's ``[sets]`` (``initial``, ``unsafe``, ``goal``; the
    goal one piece), for every disturbance within its bounds. Trajectories from the initial set are
    simulated first (:func:`falsification`): one into the unsafe set before the goal is a
    ``counterexample`` (no certificate is then searched: none can exist); beside a certificate, the same
    simulation is the soundness alarm."""
    from lyapcheck.models.loop.field import state_field

    model = scaled.cleared.shifted.model
    refused = goal_of_one_piece(model.sets["goal"])
    if refused is not None:
        return refused
    trial = falsification(model)
    if trial is not None and trial.entry is not None:  # entered before the goal: no V can exist
        return counterexample(model, trial)
    simulated = {} if trial is None else {"falsification": trial.to_dict()}
    field = state_field(scaled, robust=True)
    # the program lives in the robust field's ring, which drops every disturbance with bound 0 or that
    # does not enter (the scaled ring the caller's search was made for keeps them all)
    search = search.over(field.ring)
    initial = scaled_pieces(scaled, field, model.sets["initial"])
    unsafe = scaled_pieces(scaled, field, model.sets["unsafe"])
    (goal,) = scaled_pieces(scaled, field, model.sets["goal"])
    invariant: dict[str, Any] | None = None
    try:
        target = list(goal)
        if model.stay_in_goal:  # reach {W <= 0}: inside the goal, and never left
            invariant, stay_tried = find_goal_invariant(field, goal, search)
            if invariant is None:
                none = (reasons.reason("stay_in_goal: the equilibrium is not inside the goal, so no set around it "
                                       "inside the goal can hold the trajectories", ("goal",), stay_tried)
                        if stay_tried == [NOT_IN_GOAL] else
                        reasons.not_found("set inside the goal around the equilibrium that no trajectory leaves "
                                          "(stay_in_goal)", STAY_DEGREES, stay_tried, ("degree", "time")))
                return ConditionResult("reach_avoid", "not_certified", none.summary,
                                       numbers={**none.numbers({"tried": stay_tried}), **simulated},
                                       solver={"solves": search.log}, property="reach_avoid")
            target = [-invariant["W"]]
        found, tried = search_reach(field, initial, unsafe, target, search)
    except BudgetExhausted as exc:
        return out_of_time(search.budget.seconds, exc, search.log, simulated)
    if found is None:
        return not_found(tried, search.log, numbers=simulated)
    bound = time_bound(found["C"], found["eps"], scaled.scaling.time)
    # the avoid half beside the proof: no simulated trajectory may enter the unsafe set before the goal
    numbers = certified_numbers(found["degree"], bound, trial, found["margin"])
    certificate = certificate_json(scaled, field, found)
    if invariant is not None:
        from lyapcheck.models.classes.lyapunov import stated_v

        certificate["stay"] = {
            "degree": invariant["degree"], "mu_scaled": str(invariant["mu"]),
            "W": stated_v(scaled, field, invariant["W"]),
            "W_scaled": {"terms": [[str(c), list(m)] for m, c in sorted(field.ring.terms(invariant["W"]).items())]},
            "inside": [g.to_json() for g in invariant["inside"]], "gram_invariant": invariant["decrease"].to_json()}
        if invariant["box"]:
            certificate["stay"]["box_multipliers"] = [{"variable": j, "gram": r.to_json()} for j, r in invariant["box"]]
    return ConditionResult("reach_avoid", "certified", "", numbers=numbers, certificate=certificate,
                           solver={"solves": search.log}, property="reach_avoid")



# -- loops with functions ---------------------------------------------------------------------------------
#
# The same program (:func:`reach_structure`) on the recasting (:mod:`lyapcheck.models.language.recast`),
# unscaled, as a barrier's (:func:`~lyapcheck.models.classes.barrier.relations_field`): ``V`` is a
# polynomial in the deviations of the states and of the smooth auxiliaries, ``x' = N / D`` with ``D > 0``
# proved on the relations, each identity subtracts its relations' multipliers
# (:func:`~lyapcheck.models.classes.bounds.relation_multipliers`), a set's inequalities (and their pairwise
# products) are its pieces' S-procedure terms as on a polynomial loop, and the goal's failing inequality
# ``-q_i >= 0`` is one more relation of its identity. The exact check (:func:`check_functions`) re-reads
# the conditions of :func:`conditions` with the sets as relations ``p >= 0`` after the recasting's
# (:func:`where`, :func:`~lyapcheck.models.engines.recast_sos.check_condition`):
#
#     -V >= 0                      on the relations and each initial piece      (V <= 0 on the initial set)
#     V - 1 >= 0                   on the relations and each unsafe piece       (V >= 1 on the unsafe set)
#     -grad V . N - eps D >= 0     on the relations and -q_i >= 0, each goal inequality q_i
#                                                                               (V' <= -eps outside the goal)
#     V + C - delta |x|^2 >= 0     on the relations                             (V bounded below)
#
# with ``eps, delta > 0`` and ``C >= 0``. Every point ``(x, a(x))`` of the true loop lies in the
# relations' set, so along a trajectory ``v(t) = V(x(t), a(x(t)))`` falls at rate ``eps`` while the goal
# is not reached: from ``v(0) <= 0`` it stays ``<= 0 < 1`` (the unsafe set is not entered), in the compact
# ``{|x|^2 <= C / delta}``, and above ``-C``, so the goal is reached by ``C / eps`` seconds (the loop is
# not scaled). The angles are ordinary states (no claim modulo 2 pi), the loop the nominal one (every
# disturbance at 0). Before the proof, the true loop (each function evaluated by numpy) is simulated
# from the initial set, each trajectory until it reaches the goal: one that enters the unsafe set first
# is a ``counterexample``. The certificate is of kind :data:`KIND`; one of the kind the loops with
# functions' own module wrote before the class had one implementation (:data:`OLD_KIND`) is refused in
# one line, with the advice to certify again.

#: the certificate kind of a loop with functions (``verify`` dispatches on it; its sentence:
#: :func:`lyapcheck.models.classes.claims.sentence_of`)
KIND: Final = RECAST_REACH_AVOID_KIND
#: the kind written before ``reach_avoid`` had one implementation for every loop (issue 41): refused
OLD_KIND: Final = "recast_reach_avoid"
OLD_FORMAT: Final = ("a certificate of an older format (kind recast_reach_avoid, written before reach_avoid had one "
                     "implementation for every loop): run lyapcheck certify again to get one that verify checks")
#: the time bound's tightening (:func:`tightened`): rounds after the first certificate, and the first step
#: (8 rounds: the bounds of the tests' loops with functions are then at least as short as the relational
#: route's, which took 4 rounds on its program; benchmarks/bench_reach_route.py)
TIGHTEN_ROUNDS: Final = 8
TIGHTEN_FACTOR: Final = Fraction(16)
#: a point is said to lie outside the goal (in a reason's words, read in floating point) when the goal's
#: margin there is below minus this
OUTSIDE_GOAL_MARGIN: Final = 1e-9
#: the turns of an angle tried for another equilibrium outside the goal (1, -1, 2, -2, ...)
PERIODS: Final = 8


@dataclass
class FoundOnRelations:
    """A reach-avoid function of a loop with functions that passed the exact check: ``V`` (deviations),
    its scalars and each condition's proof by name."""

    V: Poly
    eps: Fraction
    C: Fraction
    delta: Fraction
    proofs: dict[str, "ConditionCertificate"]


def goal_relations(loop: "Loop", state_ring: Ring, goal: Sequence[Poly]) -> list["Relation"]:
    """Each goal inequality ``q_i >= 0`` failing, ``-q_i >= 0``, as a relation of the loop's ring."""
    from lyapcheck.models.classes.barrier import state_relation

    return [state_relation(loop, state_ring, -q, f"goal inequality {i + 1} fails") for i, q in enumerate(goal)]


def where(loop: "Loop", condition: Condition, initial: "RelationPieces", unsafe: "RelationPieces",
          outside: list["Relation"]) -> list["Relation"]:
    """The relations a condition is proved on: the recasting's, and the set it holds on."""
    extra = {"initial": initial, "unsafe": unsafe, "outside_goal": [[r] for r in outside]}.get(condition.on)
    return list(loop.relations) + (list(extra[condition.index]) if extra is not None else [])


def formulation(loop: "Loop", V: Poly, N: dict[str, Poly], D: Poly, eps: Fraction, C: Fraction, delta: Fraction,
                initial: "RelationPieces", unsafe: "RelationPieces", outside: list["Relation"]) -> list[Condition]:
    """:func:`conditions` on this loop (``lie``: ``grad V . N``; ``|z|^2`` its states' squares)."""
    from lyapcheck.models.classes.recast_classes import lie, state_square

    return conditions(loop.ring, V, lambda p: lie(loop, p, N), D, eps, C, delta, state_square(loop), len(initial),
                      len(unsafe), len(outside))


def search_on_relations(loop: "Loop", pieces: tuple[Pieces, Pieces, Sequence[Poly]], initial: "RelationPieces",
                        unsafe: "RelationPieces", outside: list["Relation"], search: Search
                        ) -> tuple[tuple[FoundOnRelations, "Template"] | None, list[str]]:
    """The first reach-avoid function over :data:`REACH_DEGREES` (V in the states first, then with the
    smooth auxiliaries, :func:`~lyapcheck.models.classes.barrier.templates`) that passes the exact check,
    its time bound then tightened (:func:`tightened`); with its template (``D`` and the proofs of
    ``D > 0``); and what was tried. The program is :func:`reach_structure` on the loop's view
    (:func:`~lyapcheck.models.classes.barrier.relations_field`), on the sets' ``pieces`` (initial, unsafe,
    goal; polynomials of the loop's ring), its faces reduced as a barrier's
    (:func:`~lyapcheck.models.classes.barrier.on_zero_faces`), each template with a budget of
    :data:`~lyapcheck.tolerances.TEMPLATE_SOLVES` solves; ``initial``, ``unsafe`` and ``outside``: the same
    sets as relations, which the exact check reads (:func:`where`)."""
    from lyapcheck import tolerances
    from lyapcheck.models.classes.barrier import on_zero_faces, relations_field, templates
    from lyapcheck.models.engines.search import SolvesSpent

    ring = loop.ring
    tried: list[str] = []
    for template in templates(loop, REACH_DEGREES, search, tried):
        names = [ring.names[i] for i in range(ring.nvars) if any(m[i] for m in template.basis)]
        view = relations_field(loop, names, template.N, template.D)
        full = reach_structure(view, *pieces, template.degree)
        if isinstance(full, str):
            tried.append(f"{template.label}: {full}")
            continue
        capped = search.within(tolerances.TEMPLATE_SOLVES, "per template", "lyapcheck.tolerances.TEMPLATE_SOLVES")

        def attempt(structure: Structure, view: "BoundField" = view, template: "Template" = template,
                    within: Fraction | None = None, solver: Search = capped
                    ) -> tuple[FoundOnRelations | None, Solution]:
            return attempt_on_relations(loop, view, template, structure, pieces, initial, unsafe, outside, solver,
                                        within)

        try:
            found, solution = on_zero_faces(full, attempt, capped)
        except SolvesSpent as exc:
            tried.append(f"{template.label}: {exc}")
            continue
        if found is not None:
            tried.append(f"{template.label}: found")
            return (tightened(found, search, view, template, pieces, attempt), template), tried
        tried.append(f"{template.label}: {why_none(solution)}")
    return None, tried


def attempt_on_relations(loop: "Loop", view: "BoundField", template: "Template", structure: Structure,
                         pieces: tuple[Pieces, Pieces, Sequence[Poly]], initial: "RelationPieces",
                         unsafe: "RelationPieces", outside: list["Relation"], search: Search,
                         within: Fraction | None = None) -> tuple[FoundOnRelations | None, Solution]:
    """One solve of a loop with functions' program (``within``: its bound ``T`` on ``C / eps``); the
    certificate if every condition passes its exact check on its relations (:func:`where`)."""
    from lyapcheck.models.engines.recast_sos import check_condition

    ring = view.ring
    values = reach_values(view, template.degree, *pieces)
    if within is not None:
        values.set_poly(ring, "within", ring.constant(within), [tuple([0] * ring.nvars)])
    kept = structure.parameters()  # (a multiplier a facial reduction left out takes its parameter with it)
    values.floats = {k: v for k, v in values.floats.items() if k in kept}
    values.exact = {k: v for k, v in values.exact.items() if k in kept}
    point, solution = search.solve_exact(structure, values)
    if point is None:
        return None, solution
    V = ring.from_terms({m: point.scalars[f"b{i}"] for i, m in enumerate(_b_basis(view, template.degree))})
    eps, C, delta = (Fraction(point.scalars[name]) for name in SCALARS)
    if not (eps > 0 and delta > 0 and C >= 0):
        return None, solution
    proofs = relation_proofs(view, structure, point, pieces)
    for condition in formulation(loop, V, template.N, template.D, eps, C, delta, initial, unsafe, outside):
        if not check_condition(ring, condition.F, where(loop, condition, initial, unsafe, outside),
                               proofs[condition.name])[0]:
            return None, solution
    return FoundOnRelations(V, eps, C, delta, proofs), solution


def relation_proofs(view: "BoundField", structure: Structure, point: Any, pieces: tuple[Pieces, Pieces, Sequence[Poly]]
                    ) -> dict[str, "ConditionCertificate"]:
    """Each condition's multipliers of a solved program on a loop with functions, by relation index (the
    recasting's relations' by :func:`~lyapcheck.models.classes.bounds.relation_certificates`, then the set's:
    a piece's generators' S-procedure multipliers, or the goal's failing inequality's, which
    :func:`outside_goal_view` put there), with its remainder, by condition name (:func:`conditions`)."""
    from lyapcheck.models.classes.bounds import relation_certificates

    initial, unsafe, goal = pieces
    sets = [(f"I{k}", p) for k, p in enumerate(initial)] + [(f"U{k}", p) for k, p in enumerate(unsafe)]
    names = [name for name, _ in sets] + [f"goal{k}" for k in range(len(goal))] + ["bounded"]
    remainders = {**{name: f"R{name}" for name, _ in sets}, **{f"goal{k}": f"RG{k}" for k in range(len(goal))},
                  "bounded": "RB"}
    proofs = dict(zip(names, relation_certificates(view, structure, point, [(n, remainders[n]) for n in names])))
    add_piece_multipliers(proofs, sets, view, structure, point)
    return proofs


def tightened(found: FoundOnRelations, search: Search, view: "BoundField", template: "Template",
              pieces: tuple[Pieces, Pieces, Sequence[Poly]], attempt: Callable[..., Any]) -> FoundOnRelations:
    """The same program solved again with ``C <= T eps`` (:func:`reach_structure`'s ``within``) for shorter
    bounds ``T`` (the search maximizes the Gram margin, not the time: its first bound is loose):
    :data:`TIGHTEN_ROUNDS` rounds, each ``T`` the best bound over :data:`TIGHTEN_FACTOR`, or (after a ``T``
    not reached) the geometric mean of the two, each with a budget of
    :data:`~lyapcheck.tolerances.TEMPLATE_SOLVES` solves; the last certificate that passed its exact check
    is kept."""
    from lyapcheck import tolerances
    from lyapcheck.models.classes.barrier import on_zero_faces
    from lyapcheck.models.engines.search import SolvesSpent

    structure = reach_structure(view, *pieces, template.degree, within=True)
    if isinstance(structure, str):
        return found
    best, lo = found, None
    for _ in range(TIGHTEN_ROUNDS):
        hi = time_bound(best.C, best.eps)
        within = hi / TIGHTEN_FACTOR if lo is None else _dyadic_mean(lo, hi)
        capped = search.within(tolerances.TEMPLATE_SOLVES, "per template", "lyapcheck.tolerances.TEMPLATE_SOLVES")
        try:
            better, _ = on_zero_faces(structure, lambda s: attempt(s, within=within, solver=capped), capped)
        except SolvesSpent:
            better = None
        if better is not None and time_bound(better.C, better.eps) < hi:
            best = better
        else:  # not reached: the next try lies between it and the best bound
            lo = within
    return best


def _dyadic_mean(a: Fraction, b: Fraction) -> Fraction:
    """About the geometric mean of ``a`` and ``b`` (a short rational: it enters the program)."""
    return Fraction(math.sqrt(float(a) * float(b))).limit_denominator(1 << 20)


def relations_certificate_json(loop: "Loop", found: FoundOnRelations, D: Poly, dens: list[Any]) -> dict[str, Any]:
    """The exact certificate of a loop with functions: V in the deviations (``shift``), written with the
    functions too, its scalars (``eps`` per second), its degree, and every proof (the recasting's, each
    condition's)."""
    from lyapcheck.models.classes.barrier import polynomial_json, recasting_json

    ring = loop.ring
    return {**polynomial_json(loop, KIND, "V", found.V), "eps_per_s": str(found.eps), "C": str(found.C),
            "delta": str(found.delta), **recasting_json(loop, D, dens),
            "proofs": {name: proof.to_json(ring) for name, proof in found.proofs.items()}}


def run_functions(model: "RecastModel", loop: "Loop", budget: "Budget", box: "ModelBox | None" = None
                  ) -> ConditionResult:
    """The class on a loop with functions (the section's comment above). With ``box``, ``loop`` is the
    loop with the box's parameters as bounded constants (``model`` read at the box's centre): one V for
    every value of the box, as a barrier's."""
    from lyapcheck.models.classes.claims import recast_reach_time, sentence_of
    from lyapcheck.models.classes.barrier import (SETS_USE_BOX, at_point, box_falsification,
                                                         counterexample as true_counterexample,
                                                         falsification as true_falsification, flat_loop,
                                                         not_smooth_note, piece_relations, relation_pieces,
                                                         sets_use_box)

    refused = goal_of_one_piece(model.sets["goal"])
    if refused is not None:
        return refused
    if box is not None and sets_use_box(model, box):
        return ConditionResult("reach_avoid", "not_applicable", SETS_USE_BOX)
    trial, at = box_falsification(model, box, goal=True) if box is not None else \
        (true_falsification(model, stop=model.sets["goal"]), None)
    if trial is not None and trial.entry is not None:  # entered before the goal: no V can exist
        return at_point(true_counterexample(model, trial, "reach_avoid", "reach_avoid", " before it reaches the goal"),
                        at)
    simulated = {} if trial is None else {"falsification": trial.to_dict()}
    periodic = periodic_notes(model, loop)
    if periodic:  # an equilibrium outside the goal: no V of this form exists, and none is searched
        return not_found(periodic, [], searched_degrees(REACH_DEGREES), simulated,
                         f"no reach-avoid function of this form can exist: {periodic[0]}")
    flat = flat_loop(loop)
    initial = piece_relations(flat, model.state_ring, model.sets["initial"], "initial")
    unsafe = piece_relations(flat, model.state_ring, model.sets["unsafe"], "unsafe")
    outside = goal_relations(flat, model.state_ring, model.sets["goal"][0])
    # the program's pieces: the same sets as polynomials of the loop's ring (the goal, one piece)
    pieces = (relation_pieces(flat, model.state_ring, model.sets["initial"], "initial"),
              relation_pieces(flat, model.state_ring, model.sets["unsafe"], "unsafe"),
              relation_pieces(flat, model.state_ring, model.sets["goal"], "goal")[0])
    search = Search(flat.ring, budget)
    try:
        result, tried = search_on_relations(flat, pieces, initial, unsafe, outside, search)
    except BudgetExhausted as exc:
        return out_of_time(budget.seconds, exc, search.log, simulated)
    if result is None:
        rough = not_smooth_note(flat, "V", "V' <= -eps outside the goal")
        if rough:
            tried.append(rough)
        return not_found(tried, search.log, searched_degrees(REACH_DEGREES), simulated)
    found, template = result
    certificate = relations_certificate_json(flat, found, template.D, template.dens)
    return ConditionResult("reach_avoid", "certified", sentence_of(certificate),  # (V's degree, not its template's)
                           numbers=certified_numbers(certificate["degree"], recast_reach_time(certificate), trial),
                           certificate=certificate, solver={"solves": search.log}, property="reach_avoid")


def periodic_notes(model: "RecastModel", loop: "Loop") -> list[str]:
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


def check_functions(model: "RecastModel", proved: "Loop", c: dict[str, Any]) -> tuple[bool, str]:
    """Re-check a reach-avoid certificate of a loop with functions exactly from the certificate and the
    model text: ``proved`` is the loop with the certificate's square-root bounds already re-checked; the
    sets are the model's. A certificate of :data:`OLD_KIND` is refused in one line."""
    from lyapcheck.exact import read_rational
    from lyapcheck.models.classes.barrier import check_polynomial, flat_loop, piece_relations
    from lyapcheck.models.engines.recast_sos import ConditionCertificate, check_condition

    cert = c["certificate"]
    if cert.get("kind") == OLD_KIND:
        return False, OLD_FORMAT
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

__all__ = ["REACH_DEGREES", "SCALARS", "Condition", "conditions", "goal_of_one_piece",
           "time_bound", "not_found",
           "out_of_time", "certified_numbers", "reach_structure", "search_reach", "run", "certificate_json",
           "falsification", "counterexample",
           "KIND", "OLD_KIND", "OLD_FORMAT", "goal_relations", "run_functions", "check_functions",
           "relations_certificate_json", "outside_goal_view", "relation_proofs"]
