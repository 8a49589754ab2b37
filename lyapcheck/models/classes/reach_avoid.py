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

:func:`conditions` states these conditions once as polynomials (``F >= 0`` where a set holds): a
loop with functions (:mod:`lyapcheck.models.classes.recast_reach_avoid`) builds its program from them
(:func:`linear_conditions`) and proves each on its recasting's relations; the polynomial route here
writes the same conditions as the Gram identities above, which
:func:`~lyapcheck.sos.certificates.check_reach_avoid` checks (an engine below this package). Both routes
share the degrees :data:`REACH_DEGREES`, the goal's form (:func:`goal_of_one_piece`), the time bound
(:func:`time_bound`) and their results (:func:`not_found`, :func:`out_of_time`, :func:`certified_numbers`).
"""

from __future__ import annotations

from dataclasses import dataclass
from fractions import Fraction
from typing import Any, Callable, Final, Sequence

from lyapcheck.degrees import searched_degrees
from lyapcheck.models.classes.barrier import (BudgetExhausted, Pieces, _b_basis, _decrease_poly, _decrease_support,
                                      _shift, scaled_pieces, set_certificates, set_identities,
                                      set_values)
from lyapcheck.models.loop.field import ScaledField, StateField
from lyapcheck.models.engines import reasons
from lyapcheck.models.classes.lyapunov import BLOCK_COST_LIMIT, TARGET_LIMIT, affordable, on_remainder_faces
from lyapcheck.models.engines.reasons import size_limit
from lyapcheck.models.engines.search import (ParameterValues, Search, box_multipliers, box_multipliers_of, box_support,
                                     exact_grams, multiplier_grams, one, param, why_none)
from lyapcheck.results import ConditionResult
from lyapcheck.sos import bases
from lyapcheck.sos.certificates import check_reach_avoid
from lyapcheck.sos.polynomials import Monomial, Poly, Ring, monomials, to_fmpq
from lyapcheck.sos.program import Coefficients, Gram, Identity, Scalar, Solution, Structure, Term, full_blocks

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


def linear_conditions(ring: Ring, basis: Sequence[Poly], lie: Callable[[Poly], Poly], D: Poly, square: Poly,
                      initial: int, unsafe: int, goal: int) -> list[tuple[Condition, list[tuple[str, Poly]]]]:
    """:func:`conditions` with V, eps, C and delta unknown (``V = sum_k b_k basis[k]``): each condition
    at zero unknowns (its known part, ``F``) and its coefficient of each unknown (``b0, b1, ...``, then
    :data:`SCALARS`); the conditions are affine in the unknowns, so this is exact."""
    counts = (initial, unsafe, goal)
    zero = Fraction(0)
    known = conditions(ring, ring.zero(), lie, D, zero, zero, zero, square, *counts)
    units: list[tuple[str, list[Condition]]] = [
        (f"b{k}", conditions(ring, p, lie, D, zero, zero, zero, square, *counts)) for k, p in enumerate(basis)]
    for name in SCALARS:
        at = {s: Fraction(int(s == name)) for s in SCALARS}
        units.append((name, conditions(ring, ring.zero(), lie, D, at["eps"], at["C"], at["delta"], square, *counts)))
    return [(c, [(name, unit[i].F - c.F) for name, unit in units if not (unit[i].F - c.F).is_zero()])
            for i, c in enumerate(known)]


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


def reach_structure(field: StateField, initial: Pieces, unsafe: Pieces, goal: Sequence[Poly], degree: int,
                    drop: frozenset[tuple[str, Monomial]] = frozenset()) -> Structure | str:
    """The program for ``V`` of this degree, or why there is none (a size limit, named)."""
    ring = field.ring
    nv = ring.nvars
    n = field.n
    zero = tuple([0] * nv)
    v_basis = _b_basis(field, degree)
    grams: list[Gram] = []
    on_sets = set_identities(field, v_basis, degree, initial, unsafe, grams, drop)
    if isinstance(on_sets, str):
        return on_sets
    identities = list(on_sets)
    lie = [(i, _decrease_support(field, m, with_rate=False)) for i, m in enumerate(v_basis)]
    d_support = ring.support(field.D)
    for k, q in enumerate(goal):
        terms = [Term(param(f"L{i}", support), f"b{i}") for i, support in lie if support]
        terms.append(Term(param("negD", d_support), "eps"))
        target = {m for _, support in lie for m in support} | set(d_support)
        top = max((sum(m[:n]) for m in target), default=2)
        half = max(0, (top - max(sum(m) for m in ring.support(q))) // 2)
        s_basis = [tuple(list(m) + [0] * (nv - n)) for m in monomials(n, 0, half)]
        grams.append(Gram(f"sG{k}", tuple(s_basis), full_blocks(s_basis)))
        terms.append(Term(param(f"q{k}", ring.support(q)), f"sG{k}"))
        target |= _shift(ring.support(q), [tuple(a + b for a, b in zip(x, y)) for x in s_basis for y in s_basis])
        box_grams, box_terms = box_multipliers(nv, n, target, with_states=False, prefix=f"rG{k}_")
        target |= box_support(box_grams, nv)
        if len(target) > TARGET_LIMIT:
            return size_limit(len(target), "monomials in one polynomial identity", TARGET_LIMIT, "TARGET_LIMIT")
        name = f"RG{k}"
        basis = [m for m in bases.sos_basis(nv, target | {zero}) if (name, m) not in drop]
        if len(basis) > MAX_GRAM_ROWS:
            return size_limit(len(basis), "monomials per sum-of-squares matrix", MAX_GRAM_ROWS, "MAX_GRAM_ROWS")
        grams.append(Gram(name, tuple(basis), full_blocks(basis)))
        grams.extend(box_grams)
        terms.extend(box_terms)
        terms.append(Term(one(ring, -1), name))
        identities.append(Identity(f"goal{k}", tuple(terms), None, name))
    # V + C - delta |z|^2 = R_B
    terms = [Term(Coefficients.literal({m: 1}), f"b{i}") for i, m in enumerate(v_basis)]
    terms.append(Term(one(ring, 1), "C"))
    squares = {tuple(2 * int(j == i) for j in range(nv)): -1 for i in range(n)}
    terms.append(Term(Coefficients.literal(squares), "delta"))
    basis = [m for m in bases.sos_basis(nv, set(v_basis) | set(squares) | {zero}) if ("RB", m) not in drop]
    grams.append(Gram("RB", tuple(basis), full_blocks(basis)))
    terms.append(Term(one(ring, -1), "RB"))
    identities.append(Identity("bounded", tuple(terms), None, "RB"))
    scalars = tuple(Scalar(f"b{i}") for i in range(len(v_basis))) + (
        Scalar("eps", "margin"), Scalar("delta", "margin"), Scalar("C", "zero"))
    structure = Structure(nvars=nv, grams=tuple(grams), scalars=scalars, identities=tuple(identities),
                          objective=("max_margin",))
    if affordable(structure) is None:
        return size_limit(f"{structure.cost():.1e}", "work units of the program", f"{BLOCK_COST_LIMIT:.1e}",
                          "BLOCK_COST_LIMIT")
    return structure


def reach_values(field: StateField, degree: int, initial: Pieces, unsafe: Pieces, goal: Sequence[Poly]
                 ) -> ParameterValues:
    ring = field.ring
    values = ParameterValues()
    set_values(field, values, initial, unsafe)
    for i, m in enumerate(_b_basis(field, degree)):
        support = _decrease_support(field, m, with_rate=False)
        if support:
            values.set_poly(ring, f"L{i}", _decrease_poly(field, m, Fraction(0)), support)
    values.set_poly(ring, "negD", -field.D, ring.support(field.D))
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
    if len(target) > TARGET_LIMIT:
        return size_limit(len(target), "monomials in one polynomial identity", TARGET_LIMIT, "TARGET_LIMIT")
    basis = bases.sos_basis(nv, target | {zero})
    if len(basis) > MAX_GRAM_ROWS:
        return size_limit(len(basis), "monomials per sum-of-squares matrix", MAX_GRAM_ROWS, "MAX_GRAM_ROWS")
    grams.append(Gram("RW", tuple(basis), full_blocks(basis)))
    grams.extend(box_grams)
    terms += [*box_terms, Term(one(ring, -1), "RW")]
    identities.append(Identity("invariant", tuple(terms), param("muD0", ring.support(field.D)), "RW"))
    scalars = tuple(Scalar(f"b{k}") for k in range(len(w_basis)))
    structure = Structure(nvars=nv, grams=tuple(grams), scalars=scalars, identities=tuple(identities),
                          objective=("max_margin",))
    return structure if affordable(structure) is not None else \
        size_limit(f"{structure.cost():.1e}", "work units of the program", f"{BLOCK_COST_LIMIT:.1e}",
                   "BLOCK_COST_LIMIT")


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


__all__ = ["REACH_DEGREES", "SCALARS", "Condition", "conditions", "linear_conditions", "goal_of_one_piece",
           "time_bound", "not_found",
           "out_of_time", "certified_numbers", "reach_structure", "search_reach", "run", "certificate_json",
           "falsification", "counterexample"]
