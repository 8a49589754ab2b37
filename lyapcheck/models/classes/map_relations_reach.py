"""``reach_avoid`` on a discrete-time map with functions (issue 44): every start in the initial set has an
iterate in the goal within a number of steps, and no iterate before it is in the unsafe set, proved on the
recasting's relations and checked exactly.

The map is read as :mod:`lyapcheck.models.classes.map_relations_safety` reads it for ``barrier`` (deviations,
states ``e``, auxiliaries ``a``, ``F(e, a)`` polynomial, the relations ``h_i = 0``, ``g_j >= 0``; disturbances
at 0), the ``[sets]`` moved to the deviations, the goal of one piece ``{q_k >= 0}``. With ``V`` a free
polynomial of the states, the certificate (kind :data:`KIND`, the polynomial map's, with the recasting's
``variables`` and ``auxiliaries`` and each identity's multipliers by relation index) is the polynomial map's
(:mod:`lyapcheck.models.classes.discrete_safety`) with the relations' multipliers in every identity:

    -V - sum (relations' and the piece's multipliers) = R_I                each initial piece   (V <= 0)
    V - 1 - sum (relations' and the piece's multipliers) = R_U             each unsafe piece    (V >= 1)
    V - V(F(e, a)) - eps - sum (relations') - tau (-q_k) = R_G,k           each goal inequality (the step)
    V + C - sum (relations') = R_B                                         (V >= -C)

every remainder and ``tau`` a sum of squares, ``eps > 0``. At every true point the relations' terms are
``<= 0``; so wherever goal inequality ``k`` fails, ``V(F(e)) <= V(e) - eps``. A start with ``V <= 0`` falls
by ``eps`` per step while outside the goal and never below ``-C``: it is in the goal at a step at most
``floor(C / eps)`` (the figure ``reach_steps_bound``), and every iterate before it has ``V <= 0 < 1``, so
none is unsafe. (The identities' names and Gram names are the continuous loop with functions' reach-avoid
program's, :func:`lyapcheck.models.classes.reach_avoid.relation_proofs` reads its multipliers back.)

The refutation, before the search: a reach-avoid claim says that EVERY start in the initial set reaches the goal
without an unsafe iterate before, so one start that touches the unsafe set first refutes it. The true map is
iterated in floating point from starts sampled in the initial set (followed until an iterate is in the goal),
and an unsafe iterate is re-derived from its start rounded to a short rational
(:func:`~lyapcheck.models.classes.map_relations_safety.check_iterate_functions` with the goal): the start in the
initial set in rationals, every iterate in ball arithmetic through the true functions (256 bits), each earlier
iterate's ball proved outside the goal (some goal inequality ``< 0`` on all of it) and the last one's inside an
unsafe piece. Then ``refuted`` (kind ``discrete_iterate``, with the start and the step), which ``verify``
re-derives from the stated start. An iterate that stays out of the goal for many steps proves nothing (the
claim bounds no number of steps), and is not a refutation. The steps bound is then tightened as the polynomial map's (:func:`tighten`: the same structure with ``eps``
fixed and ``C`` minimised, :func:`lyapcheck.models.classes.discrete_safety.tightened_structure`), every
tighter certificate decided by :func:`check_map_reach`.
"""

from __future__ import annotations

from fractions import Fraction
from typing import TYPE_CHECKING, Any, Callable, Final, Mapping, Sequence

from lyapcheck.models.classes import discrete_lyapunov as dl
from lyapcheck.models.classes import discrete_safety as ds
from lyapcheck.models.classes.claims import DISCRETE_REACH_KIND, discrete_reach_sentence
from lyapcheck.models.classes.map_relations import MapOnRelations, NotTaken
from lyapcheck.models.classes.map_relations_safety import searched_on, sets_view, stated_map, step_multipliers, \
    step_program, step_values, verify_refuted
from lyapcheck.models.engines import reasons
from lyapcheck.models.engines.search import Budget, BudgetExhausted, ParameterValues, Search, one, param, why_none
from lyapcheck.results import ConditionResult
from lyapcheck.sos import bases
from lyapcheck.sos.polynomials import Poly
from lyapcheck.sos.structure import Gram, Identity, Scalar, Structure, Term, full_blocks

if TYPE_CHECKING:  # pragma: no cover
    from lyapcheck.models.engines.recast_sos import ConditionCertificate
    from lyapcheck.models.language.parameter_box import ModelBox
    from lyapcheck.models.language.recast import RecastModel, Relation

#: the certificate kind: the polynomial map's (its sentence), stating the recasting's variables besides
KIND: Final = DISCRETE_REACH_KIND

Pieces = Sequence[Sequence[Poly]]


def steps_bound(C: Fraction, eps: Fraction) -> int:
    """``floor(C / eps)`` (0 when ``C < 0``: then no state has ``V <= 0``, the initial set is empty)."""
    return max(0, (C / eps).__floor__())


def conditions(m: MapOnRelations, V: Poly, eps: Fraction, C: Fraction, initial: Pieces, unsafe: Pieces,
               goal: Sequence[Poly]) -> list[tuple[str, Poly, list["Relation"], str]]:
    """Each identity's name, its ``F >= 0``, the relations it is proved on (the recasting's, then a piece's
    generators or the failing goal inequality ``-q_k >= 0``) and what it says."""
    from lyapcheck.models.classes.barrier import SET_OWNER, _generator_relations
    from lyapcheck.models.language.recast import Relation

    ring, view = m.ring, m.field
    rels = list(view.relations)
    out = [(f"I{k}", -V, rels + _generator_relations(view, piece, f"initial piece {k}"), "V <= 0 on the initial set")
           for k, piece in enumerate(initial)]
    out += [(f"U{k}", V - ring.constant(1), rels + _generator_relations(view, piece, f"unsafe piece {k}"),
             "V >= 1 on the unsafe set") for k, piece in enumerate(unsafe)]
    step = V - dl.compose(ring, V, m.F) - ring.constant(eps)
    out += [(f"goal{k}", step, rels + [Relation("ge", -q, f"goal inequality {k + 1} fails", SET_OWNER)],
             f"V(F) <= V - eps where goal inequality {k + 1} fails") for k, q in enumerate(goal)]
    out.append(("bounded", V + ring.constant(C), rels, "V >= -C"))
    return out


# -- the exact check -------------------------------------------------------------------------------------

def check_map_reach(m: MapOnRelations, V: Poly, eps: Fraction, C: Fraction, initial: Pieces, unsafe: Pieces,
                    goal: Sequence[Poly], proofs: Mapping[str, "ConditionCertificate"]) -> tuple[bool, str]:
    """The identities of the module docstring, exactly: ``eps > 0``, ``V`` of the states alone, and each
    identity on its relations (:func:`~lyapcheck.models.engines.recast_sos.check_condition`)."""
    from lyapcheck.models.engines.recast_sos import check_condition

    if eps <= 0:
        return False, "the decrease per step eps must be > 0"
    if any(any(q[m.n:]) for q in m.ring.support(V)):
        return False, "V may depend on the states only"
    for name, F, relations, what in conditions(m, V, eps, C, initial, unsafe, goal):
        proof = proofs.get(name)
        if proof is None:
            return False, f"{name}: no proof"
        if proof.rho is not None:
            return False, f"{name}: a reach-avoid identity takes no region multiplier"
        ok, why = check_condition(m.ring, F, relations, proof)
        if not ok:
            return False, f"{what}: {why}"
    return True, (f"V <= 0 on the initial set, V >= 1 on the unsafe set, V(F) <= V - eps outside the goal "
                  f"(eps = {eps} > 0) and V >= -C (C = {C}) on the recasting's relations, exactly: the goal is "
                  f"reached within {steps_bound(C, eps)} steps, no iterate unsafe before (discrete-time map with "
                  "functions)")


# -- the program -----------------------------------------------------------------------------------------

def reach_structure(m: MapOnRelations, initial: Pieces, unsafe: Pieces, goal: Sequence[Poly], degree: int
                    ) -> Structure | str:
    """The program for ``V`` of this degree (the sets' identities a barrier's on relations, each goal
    inequality's step identity with the relations' and the failing inequality's multipliers, the bound
    below), or why there is none (a size limit, named)."""
    from lyapcheck.models.classes.bounds import relation_multipliers
    from lyapcheck.models.classes.lyapunov import TARGET_LIMIT
    from lyapcheck.models.classes.reach_avoid import outside_goal_view
    from lyapcheck.models.engines.reasons import size_limit
    from lyapcheck.models.engines.search import literal

    ring, view = m.ring, m.field
    nv = ring.nvars
    zero = tuple([0] * nv)
    program = step_program(m, initial, unsafe, degree)
    if isinstance(program, str):
        return program
    v_basis, scalars, grams, identities, step_support = (program.basis, program.scalars, program.grams,
                                                          program.identities, program.supports)
    for k, q in enumerate(goal):
        terms = [Term(param(f"sV{i}", support), f"b{i}") for i, support in step_support.items()]
        terms.append(Term(one(ring, -1), "eps"))
        target = {x for support in step_support.values() for x in support} | {zero}
        rel_grams, rel_scalars, rel_terms, added = step_multipliers(m, outside_goal_view(view, q, k), f"goal{k}",
                                                                    target)
        target |= added
        if len(target) > TARGET_LIMIT:
            return size_limit(len(target), "monomials in one polynomial identity", TARGET_LIMIT, "TARGET_LIMIT")
        basis = [x for x in bases.sos_basis(nv, target) if view.allowed(x)]
        if len(basis) > ds.MAX_GRAM_ROWS:
            return size_limit(len(basis), "monomials per sum-of-squares matrix", ds.MAX_GRAM_ROWS, "MAX_GRAM_ROWS")
        grams += [*rel_grams, Gram(f"RG{k}", tuple(basis), full_blocks(basis))]
        scalars += rel_scalars
        identities.append(Identity(f"goal{k}", (*terms, *rel_terms, Term(one(ring, -1), f"RG{k}")), None, f"RG{k}"))
    terms = [Term(literal(ring, {x: 1}), f"b{i}") for i, x in enumerate(v_basis)]
    target = set(v_basis) | {zero}
    rel_grams, rel_scalars, rel_terms, added = relation_multipliers(sets_view(m), "bounded", target, (), margin=True)
    basis = [x for x in bases.sos_basis(nv, target | added) if view.allowed(x)]
    grams += [*rel_grams, Gram("RB", tuple(basis), full_blocks(basis))]
    scalars += [*rel_scalars, Scalar("eps", lower="margin"), Scalar("C")]
    identities.append(Identity("bounded", (*terms, Term(one(ring), "C"), *rel_terms, Term(one(ring, -1), "RB")),
                               None, "RB"))
    return ds._affordable_program(nv, grams, scalars, identities)


def reach_values(m: MapOnRelations, degree: int, initial: Pieces, unsafe: Pieces) -> ParameterValues:
    """The program's parameters: the sets' inequalities and each of V's monomials' step ``e^q - (e^q)(F)``
    (:func:`~lyapcheck.models.classes.map_relations_safety.step_values` at rate 1)."""
    return step_values(m, degree, initial, unsafe, "sV", Fraction(1))


def attempt(m: MapOnRelations, structure: Structure, degree: int, sets: Mapping[str, Any], search: Search,
            eps_fixed: Fraction | None = None) -> tuple[dict[str, Any] | None, Any]:
    """One solve: the exact certificate if it passes :func:`check_map_reach` (``eps_fixed``: a solve of
    :func:`~lyapcheck.models.classes.discrete_safety.tightened_structure` at that ``eps``)."""
    from lyapcheck import tolerances as tol
    from lyapcheck.models.classes.barrier import _b_basis
    from lyapcheck.models.classes.reach_avoid import relation_proofs

    initial, unsafe, goal = sets["initial"], sets["unsafe"], sets["goal"][0]
    values = reach_values(m, degree, initial, unsafe)
    if eps_fixed is not None:
        values.set_poly(m.ring, "eps_fixed", m.ring.constant(-eps_fixed), [tuple([0] * m.ring.nvars)])
        values.set_scalar("floor", tol.REACH_TIGHTEN_FLOOR * float(eps_fixed))
    point, solution = search.solve_exact(structure, values)
    if point is None:
        return None, solution
    V = m.ring.from_terms({q: point.scalars[f"b{i}"] for i, q in enumerate(_b_basis(m.field, degree))})
    eps = Fraction(point.scalars["eps"]) if eps_fixed is None else eps_fixed
    C = Fraction(point.scalars["C"])
    proofs = relation_proofs(m.field, structure, point, (initial, unsafe, goal))
    if not check_map_reach(m, V, eps, C, initial, unsafe, goal, proofs)[0]:
        return None, solution
    return {"V": V, "eps": eps, "C": C, "proofs": proofs}, solution


def search_reach(m: MapOnRelations, sets: Mapping[str, Any], search: Search) -> tuple[dict[str, Any] | None, list[str]]:
    """The first certificate over the polynomial map's degrees
    (:data:`~lyapcheck.models.classes.discrete_safety.REACH_DEGREES`), and what was tried."""
    from lyapcheck.degrees import searched_degrees

    tried: list[str] = []
    for degree in searched_degrees(ds.REACH_DEGREES):
        search.budget.check()
        structure = reach_structure(m, sets["initial"], sets["unsafe"], sets["goal"][0], degree)
        if isinstance(structure, str):
            tried.append(f"degree {degree}: {structure}")
            continue
        found, solution = attempt(m, structure, degree, sets, search)
        if found is not None:
            tighter = tighten(m, structure, degree, sets, found, search)
            before, after = steps_bound(found["C"], found["eps"]), steps_bound(tighter["C"], tighter["eps"])
            tried.append(f"degree {degree}: found" + ("" if after == before else
                                                      f", its steps bound {before} tightened to {after}"))
            return {**tighter, "degree": degree}, tried
        tried.append(f"degree {degree}: {why_none(solution) if solution is not None else 'none'}")
    return None, tried


def tighten(m: MapOnRelations, structure: Structure, degree: int, sets: Mapping[str, Any], found: dict[str, Any],
            search: Search) -> dict[str, Any]:
    """The certificate with the smallest steps bound among ``found`` and the tighter solves (the polynomial
    map's way, the comment above :func:`~lyapcheck.models.classes.discrete_safety.tightened_structure`: ``eps``
    fixed, ``C`` minimised, ``eps`` grown while the bound falls); ``found`` itself when none is smaller."""
    from lyapcheck import tolerances as tol

    tight = ds.tightened_structure(structure)
    best, eps = found, found["eps"]
    try:
        for _ in range(tol.REACH_TIGHTEN_SOLVES):
            search.budget.check()
            cert, _ = attempt(m, tight, degree, sets, search, eps)
            if cert is None or steps_bound(cert["C"], cert["eps"]) >= steps_bound(best["C"], best["eps"]):
                break
            best, eps = cert, eps * tol.REACH_TIGHTEN_GROWTH
    except BudgetExhausted:
        pass  # the time limit ends the tightening, never the proof: the best certificate so far stands
    return best


# -- the class -------------------------------------------------------------------------------------------

def run(model: "RecastModel", budget: Budget, box: "ModelBox | None" = None,
        refute: "Callable[[], ConditionResult | None] | None" = None) -> ConditionResult:
    """``reach_avoid`` on a map with functions (module docstring): the falsification first (``refuted`` with an
    iterate proved unsafe before any is in the goal), then ``certified`` only after :func:`check_map_reach`, with
    the steps bound ``floor(C / eps)``. ``box``: one ``V`` for every value of that box of the map's parameters
    (:func:`~lyapcheck.models.classes.map_relations_safety.read_map`), the falsification ``refute`` at its
    corners and centre instead of the point's (:func:`lyapcheck.models.classes.map_relations_safety_box.refute`)."""
    from lyapcheck.models.classes.claims import summary
    from lyapcheck.models.classes.lyapunov import terms_json
    from lyapcheck.models.classes.reach_avoid import goal_of_one_piece

    ruled = ds.no_sets("reach_avoid", model)
    if ruled is not None:
        return ruled
    # (``[sets] stay_in_goal`` is refused when a model with functions is read: no such model reaches here)
    one_piece = goal_of_one_piece(model.sets["goal"])
    if one_piece is not None:
        return one_piece
    ready = searched_on("reach_avoid", model, "reach-avoid certificate", "reach_avoid", ("initial", "unsafe", "goal"),
                        box, refute)
    if isinstance(ready, ConditionResult):
        return ready
    m, sets = ready
    search = Search(m.ring, budget)
    try:
        found, tried = search_reach(m, sets, search)
    except BudgetExhausted as exc:
        late = reasons.out_of_time("a reach-avoid certificate of the discrete-time map", budget.seconds, str(exc))
        return ConditionResult("reach_avoid", "inconclusive", late.summary, solver={"solves": search.log},
                               numbers=late.numbers({"reason": str(exc), "time": "discrete"}), property="reach_avoid")
    if found is None:
        from lyapcheck.degrees import searched_degrees

        none = reasons.not_found("reach-avoid certificate on the recasting's relations",
                                 searched_degrees(ds.REACH_DEGREES), tried, ("degree", "sets", "time"))
        return ConditionResult("reach_avoid", "not_certified", none.summary, solver={"solves": search.log},
                               numbers=none.numbers({"tried": tried, "time": "discrete"}), property="reach_avoid")
    ring = m.ring
    bound = steps_bound(found["C"], found["eps"])
    cert = {"kind": KIND, "time": "discrete", "coordinates": "shifted", "variables": list(ring.names),
            "auxiliaries": m.system.definitions(), "degree": found["degree"], "eps": str(found["eps"]),
            "C": str(found["C"]), "reach_steps_bound": bound, "V": terms_json(ring, found["V"]),
            "proofs": {name: proof.to_json(ring) for name, proof in found["proofs"].items()}}
    if box is not None:  # (the box's parameters are among the variables, bounded: one V for every value)
        cert["parameter_box"] = box.to_json()
    numbers = {"degree": found["degree"], "reach_steps_bound": bound, "time": "discrete"}
    sentence = summary("reach_avoid", {"status": "certified", "certificate": cert, **numbers})
    assert sentence is not None  # (a certified reach_avoid of this kind always has one)
    return ConditionResult("reach_avoid", "certified", sentence, numbers=numbers, certificate=cert,
                           solver={"solves": search.log}, property="reach_avoid")


def verify(model: "RecastModel", c: Mapping[str, Any], box: "ModelBox | None" = None) -> tuple[bool, str]:
    """Re-check a certified ``reach_avoid`` of a map with functions from its JSON and the model text alone: the
    map, its relations and the sets re-derived, every identity exactly, the stated degree and steps bound.
    ``box``: the document's box, which a certificate states (``parameter_box``) (a refutation over a box:
    :func:`lyapcheck.models.classes.map_relations_safety_box.verify_refutation`)."""
    from lyapcheck.exact import read_rational
    from lyapcheck.models.engines.recast_sos import ConditionCertificate, poly_from_json

    if c.get("property") != "reach_avoid":
        return False, f"a reach_avoid claim is about reach_avoid, not {c.get('property')}"
    if ds.no_sets("reach_avoid", model) is not None:
        return False, "the model has no [sets] initial, unsafe and goal for reach_avoid"
    if len(model.sets["goal"]) != 1:
        return False, "a map's reach_avoid takes a goal of one piece"
    if c.get("status") == "refuted":  # the stated start's unsafe iterate before the goal, re-derived
        return verify_refuted(model, c, box, ("initial", "unsafe", "goal"))
    if c.get("status") != "certified":
        return False, f"a map with functions' reach_avoid is certified or refuted, not {c.get('status')}"
    try:
        read = stated_map(model, c, box, KIND, "reach_avoid", ("initial", "unsafe", "goal"))
        if isinstance(read, str):
            return False, read
        cert, m, sets = read
        ring = m.ring
        V = poly_from_json(ring, cert["V"], "V")
        eps, C = read_rational(cert["eps"], "eps"), read_rational(cert["C"], "C")
        wanted = conditions(m, V, eps, C, sets["initial"], sets["unsafe"], sets["goal"][0])
        stated = cert["proofs"]
        if not isinstance(stated, dict) or set(stated) != {name for name, _, _, _ in wanted}:
            return False, "the certificate's identities are not the sets' pieces, the goal's steps and the bound below"
        proofs = {name: ConditionCertificate.from_json(ring, stated[name], len(relations))
                  for name, _, relations, _ in wanted}
    except NotTaken as exc:
        return False, str(exc)
    except (KeyError, TypeError, ValueError, ZeroDivisionError, AttributeError, IndexError) as exc:
        return False, f"malformed certificate: {exc}"
    ok, why = check_map_reach(m, V, eps, C, sets["initial"], sets["unsafe"], sets["goal"][0], proofs)
    if not ok:
        return False, why
    degree = ds.poly_degree(ring, V)
    if cert.get("degree") != degree or c.get("degree") != degree:
        return False, "the stated degree is not the certificate's polynomial's"
    bound = steps_bound(C, eps)
    if cert.get("reach_steps_bound") != bound or c.get("reach_steps_bound") != bound:
        return False, "the stated reach_steps_bound is not floor(C / eps)"
    return True, why


__all__ = ["KIND", "steps_bound", "conditions", "check_map_reach", "reach_structure", "search_reach",
           "tighten", "run", "verify"]
