"""``sos_bound`` on a discrete-time map with functions (issue 44, item 1): an ultimate bound on each output
under bounded disturbances, proved on the recasting's relations and checked exactly.

The map is recast again with its disturbances as bounded constants (:func:`disturbed_map`): the displacement
``F(x, d) - x`` with each ``d_k`` a variable of the ring after the states (its next value is no state's, it is
a bounded constant of the loop, :func:`~lyapcheck.models.classes.recast_classes.base_loop` with ``fixed``),
then the auxiliaries, whose arguments may use a disturbance (``tanh(y + d)``). Every auxiliary's relations
(:func:`lyapcheck.models.classes.map_relations.derived_relations`) hold at every true point ``(e, d, a(e, d))``,
and each disturbance adds ``b_k^2 - d_k^2 >= 0``. A map has no flow to differentiate, so an auxiliary of a
disturbance needs no care beyond its relations: the identities below are proved for every true point of the
disturbances' box, whatever the disturbance does from one step to the next.

The certificate (kind :data:`KIND`, the polynomial map's, with the recasting's ``variables`` and
``auxiliaries``), per output ``y`` (its deviation from its value at the fixed point), with ``V`` a free
polynomial of the states, ``lam`` a rational in ``[0, 1)`` and ``B >= 0``:

    (1 - lam) + lam V(e) - V(F(e, d, a)) - sum_i lambda_i h_i - sum_j tau_j g_j = sigma_D    (the step)
    B + V(e) - 1 - y(e)^2 = sigma_E                                                          (the output)

``lambda_i`` free polynomials on the equalities, ``tau_j`` sums of squares on the inequalities (a
disturbance's box among them), ``sigma_D``, ``sigma_E`` sums of squares (exact positive semidefinite Gram
matrices). At every true point the relations' terms are ``<= 0``, so ``V(F) - 1 <= lam (V - 1)`` for every
state and every disturbance within its bounds: the argument of the polynomial map's class
(:mod:`lyapcheck.models.classes.discrete_bounds`) then gives ``limsup_k |y_k| <= sqrt(B)`` along every
disturbance sequence, from every start. The output is a polynomial of the states, so its identity needs no
relation.

The search is the polynomial map's, without facial reduction: ``V`` of degree 2 then 4 (under ``--degree``'s
ceiling), each rate of :data:`~lyapcheck.models.classes.discrete_bounds.LAMBDAS`, ``B`` minimized, rounded and
checked exactly (:func:`check_bound_on_relations`); the smallest certified ``B`` over every degree is kept (on
the example a degree-4 ``V`` bounds ``|y|`` by 0.49 where a quadratic one gives 1.56). :func:`verify` re-derives the map, its relations and the outputs from the model text and
re-checks both identities exactly.
"""

from __future__ import annotations

import tomllib
from dataclasses import dataclass, replace
from fractions import Fraction
from typing import TYPE_CHECKING, Any, Final, Mapping, Sequence

from lyapcheck import tolerances
from lyapcheck.models.classes import discrete_bounds as db
from lyapcheck.models.classes import discrete_lyapunov as dl
from lyapcheck.models.classes.claims import DISCRETE_BOUND_KIND
from lyapcheck.models.classes.map_relations import NotTaken, derived_relations, next_state_of
from lyapcheck.models.engines import reasons
from lyapcheck.models.engines.reasons import size_limit
from lyapcheck.models.engines.search import Budget, BudgetExhausted, Search
from lyapcheck.results import ConditionResult
from lyapcheck.sos import bases
from lyapcheck.sos.certificates import GramPoly
from lyapcheck.sos.polynomials import Monomial, Poly, Ring, to_fmpq
from lyapcheck.sos.structure import Structure

if TYPE_CHECKING:  # pragma: no cover
    from lyapcheck.models.classes.bounds import BoundField
    from lyapcheck.models.engines.recast_sos import ConditionCertificate
    from lyapcheck.models.language.parameter_box import ModelBox
    from lyapcheck.models.language.recast import RecastModel, RecastSystem, Relation

#: the certificate kind: the polynomial map's (its sentence speaks of steps), stating the recasting's
#: variables and auxiliaries besides
KIND: Final = DISCRETE_BOUND_KIND


@dataclass(frozen=True)
class DisturbedMapOnRelations:
    """A map with functions with its disturbances as bounded constants: ``F`` (the states' next values) in
    the recasting's ring (states, disturbances, auxiliaries; deviations), every relation, and the
    multipliers' view of them."""

    system: "RecastSystem"
    ring: Ring
    F: tuple[Poly, ...]
    relations: tuple["Relation", ...]
    field: "BoundField"
    disturbances: dict[str, Fraction]
    #: over a box, the indices of its parameters (bounded constants after the disturbances)
    params: tuple[int, ...] = ()

    @property
    def n(self) -> int:
        return len(self.F)

    def output(self, model: "RecastModel", name: str) -> Poly:
        """The output ``name`` (a polynomial of the states) in this ring's deviations, less its value at the
        fixed point."""
        ring, states = self.ring, Ring(model.states)
        pad = [0] * (ring.nvars - len(model.states))
        embedded = ring.from_terms({tuple(list(q) + pad): c for q, c in states.terms(model.outputs[name]).items()})
        shifted = self.system.shift(embedded)
        return shifted - ring.constant(ring.terms(shifted).get(tuple([0] * ring.nvars), Fraction(0)))


def disturbed_map(model: "RecastModel", box: "ModelBox | None" = None) -> DisturbedMapOnRelations:
    """The map recast with its disturbances as bounded constants (module docstring); :class:`NotTaken` when
    the recasting cannot keep a disturbance a variable, or the map is not polynomial in its variables.
    ``box``: the box's parameters too, after the disturbances, each a bounded constant (``h^2 - u^2 >= 0``,
    ``u`` its deviation from the box's centre, where ``model`` is read): one ``V`` and one bound for every
    value of the box (its fixed point proved to stay put over it before,
    :func:`lyapcheck.models.classes.discrete_functions_box.boxed_system`)."""
    from lyapcheck.errors import ModelFileError
    from lyapcheck.models.classes.bounds import BoundField
    from lyapcheck.models.classes.recast_classes import base_loop
    from lyapcheck.models.language.recast import recast_dynamics

    table = tomllib.loads(model.text)["dynamics"]
    if any(isinstance(table[s], bool) or not isinstance(table[s], (str, int, float)) for s in model.states):
        raise NotTaken("a right-hand side that is not one expression (a table) is not recast with its disturbances")
    dists = dict(model.disturbances)
    names = tuple(box.names) if box is not None else ()
    texts: dict[str, object] = {**{s: f"({table[s]}) - ({s})" for s in model.states}, **{d: "0" for d in dists},
                                **{p: "0" for p in names}}
    constants = {k: v for k, v in model.parameters.items() if k not in names}
    centre = tuple(box.center(p) for p in names) if box is not None else ()
    try:
        system, _ = recast_dynamics(model.source, model.states + tuple(dists) + names, texts, constants,
                                    tuple(model.equilibrium) + (Fraction(0),) * len(dists) + centre,
                                    networks=model.networks, for_map=True)
    except ModelFileError as exc:
        raise NotTaken(f"the recasting could not keep the disturbances (and the box's parameters) as variables "
                       f"({exc})") from None
    fixed = {**dists, **({p: box.half(p) for p in names} if box is not None else {})}
    ring, F = next_state_of(system, fixed=fixed)
    loop = base_loop(replace(system, relations=derived_relations(system)), cylinder=False, fixed=fixed)
    relations = tuple(loop.relations)
    n = len(F)
    index = {name: i for i, name in enumerate(ring.names)}
    field = BoundField(ring, n, tuple(range(n)), tuple(range(n)), (), ring.constant(1),
                       tuple(index[d] for d in dists), tuple(dists.values()), relations=relations,
                       multiplied=tuple(range(len(relations))), unused=loop.roots(), square_free=loop.square_free())
    return DisturbedMapOnRelations(system, ring, F, relations, field, dists, tuple(index[p] for p in names))


# -- the exact check -------------------------------------------------------------------------------------

def check_bound_on_relations(m: DisturbedMapOnRelations, y: Poly, V: Poly, lam: Fraction, B: Fraction,
                             step: "ConditionCertificate", output: "ConditionCertificate") -> tuple[bool, str]:
    """The two identities of the module docstring, exactly: then ``limsup |y_k| <= sqrt(B)`` along every
    disturbance sequence within its bounds, from every start."""
    from lyapcheck.models.engines.recast_sos import check_condition

    ring = m.ring
    why_not = db.bound_preconditions(ring, m.n, V, lam, B)
    if why_not is not None:
        return False, why_not
    if step.rho is not None or output.rho is not None:
        return False, "a global bound has no region multiplier"
    if output.lambdas or output.taus:
        return False, "the output identity takes no relation (V and y are polynomials of the states)"
    ok, why = check_condition(ring, ring.constant(1) * to_fmpq(1 - lam) + V * to_fmpq(lam) - dl.compose(ring, V, m.F),
                              m.relations, step)
    if not ok:
        return False, f"(1 - lam) + lam V - V(F) = sigma_D on the map's relations: {why}"
    ok, why = check_condition(ring, ring.constant(B - 1) + V - y * y, m.relations, output)
    if not ok:
        return False, f"B + V - 1 - y^2 = sigma_E: {why}"
    return True, ("(1 - lam) + lam V - V(F) is a sum of squares on the recasting's relations and the disturbances' "
                  "box, and B + V - 1 - y^2 one, exactly (discrete-time map with functions)")


# -- the program -----------------------------------------------------------------------------------------

def bound_program(m: DisturbedMapOnRelations, y: Poly, degree: int) -> tuple[Structure, list[Monomial]] | str:
    """The program for a ``V`` of this degree (coefficients ``c_k`` on the states' monomials of degree 0 to
    ``degree``, returned with it), or why there is none (a size limit): the polynomial map's
    (:func:`~lyapcheck.models.classes.discrete_bounds.bound_structure`) with the relations' multipliers in the
    step identity, and none in the output's."""
    from lyapcheck.models.classes.bounds import relation_multipliers
    from lyapcheck.models.classes.lyapunov import TARGET_LIMIT

    ring, n, nv = m.ring, m.n, m.ring.nvars
    zero = tuple([0] * nv)
    alphas = db.state_monomials(ring, n, degree)
    steps = [set(ring.support(dl.compose(ring, ring.monomial(a), m.F))) | {a} for a in alphas]
    target: set[Monomial] = set().union(*steps) | {zero}
    if m.params:  # over a box: degrees in the states and functions (map_relations.box_multipliers)
        from lyapcheck.models.classes.map_relations import box_multipliers

        r_grams, r_scalars, r_terms, added = box_multipliers(m, target, [], "D", margin="floor", vanishing=False)
    else:
        r_grams, r_scalars, r_terms, added = relation_multipliers(m.field, "D", target, [], margin="floor")
    target |= added
    if len(target) > TARGET_LIMIT:
        return size_limit(len(target), "monomials in one polynomial identity", TARGET_LIMIT, "TARGET_LIMIT")
    e_target = set(alphas) | set(ring.support(y * y)) | {zero}
    z_d = [q for q in bases.sos_basis(nv, target) if m.field.allowed(q)]
    z_e = bases.sos_basis(nv, e_target)
    structure = db.bound_structure(ring, y, alphas, steps, z_d, z_e, r_grams, r_terms, scalars=r_scalars)
    if isinstance(structure, str):
        return structure
    return structure, alphas


def attempt(m: DisturbedMapOnRelations, y: Poly, structure: Structure, alphas: Sequence[Monomial], lam: Fraction,
            search: Search) -> tuple[dict[str, Any] | None, str]:
    """One solve at rate ``lam``: the exact certificate if it passes :func:`check_bound_on_relations`."""
    from lyapcheck.models.classes.bounds import relation_certificates
    from lyapcheck.models.engines.recast_sos import ConditionCertificate

    ring = m.ring
    values = db.step_values(ring, alphas, lam, lambda p: dl.compose(ring, p, m.F))
    solved = db.solve_bound(ring, structure, alphas, values, search)
    if isinstance(solved, str):
        return None, solved
    point, grams, V, B = solved
    step, = relation_certificates(m.field, structure, point, (("D", "sigD"),))
    output = ConditionCertificate({}, {}, grams["sigE"])
    ok, why = check_bound_on_relations(m, y, V, lam, B, step, output)
    if not ok:
        return None, f"the rounded point failed the exact check ({why})"
    return {"V": V, "lam": lam, "B": B, "step": step, "output": output}, "found"


def best_bound(m: DisturbedMapOnRelations, y: Poly, search: Search) -> tuple[dict[str, Any] | None, list[str]]:
    """The smallest certified ``B`` over the rates and every degree (a degree-2 ``V`` meets the relations with
    constant multipliers only, and its bound is often several times a degree-4 one's), and what each degree
    met. Once one bound is certified, running out of time at a later degree keeps it."""
    from lyapcheck.degrees import searched_degrees

    tried: list[str] = []
    best: dict[str, Any] | None = None
    for degree in searched_degrees(db.BOUND_DEGREES):
        try:
            search.budget.check()
            built = bound_program(m, y, degree)
            if isinstance(built, str):
                tried.append(f"degree {degree}: {built}")
                continue
            structure, alphas = built
            whys: list[str] = []
            before = best
            for lam in db.LAMBDAS:
                found, why = attempt(m, y, structure, alphas, lam, search)
                if found is None:
                    whys.append(f"lam {lam}: {why}")
                elif best is None or found["B"] < best["B"]:
                    best = {**found, "degree": degree}
        except BudgetExhausted:
            if best is None:
                raise
            tried.append(f"degree {degree}: out of time (the bound of degree {best['degree']} is kept)")
            break
        if best is not before:
            tried.append(f"degree {degree}: found")
        else:
            tried.append(f"degree {degree}: none smaller at any rate ({'; '.join(whys)})")
    return best, tried


# -- the class -------------------------------------------------------------------------------------------

def run(model: "RecastModel", budget: Budget, box: "ModelBox | None" = None) -> ConditionResult:
    """Every output's certified ``limsup`` over the steps on a map with functions, one certificate each;
    ``box``: for every value of that box of its parameters (:func:`disturbed_map`)."""
    from lyapcheck import exact
    from lyapcheck.models.classes.bounds import bound_claim
    from lyapcheck.models.classes.claims import summary
    from lyapcheck.models.classes.lyapunov import terms_json

    if not model.disturbances:
        return ConditionResult("sos_bound", "not_applicable", reasons.NO_DISTURBANCES)
    try:
        m = disturbed_map(model, box)
    except NotTaken as exc:
        return ConditionResult("sos_bound", "not_applicable", f"not taken on this map with functions: {exc}")
    ring = m.ring
    if ring.nvars > tolerances.MAP_RELATIONS_VARIABLES:
        none = reasons.reason("no bound of the map was searched on the recasting's relations: "
                              + size_limit(ring.nvars, "variables (states, disturbances and functions)",
                                           tolerances.MAP_RELATIONS_VARIABLES, "MAP_RELATIONS_VARIABLES"), ("fewer",))
        return ConditionResult("sos_bound", "not_certified", none.summary,
                               numbers=none.numbers({"time": "discrete"}))
    search = Search(ring, budget)
    bounds: dict[str, Fraction] = {}
    certs: dict[str, Any] = {}
    detail: list[str] = []
    try:
        for name in model.outputs:
            found, tried = best_bound(m, m.output(model, name), search)
            if found is None:
                detail.extend(f"{name}: {line}" for line in tried)
                continue
            bound = exact.sqrt_upper(found["B"], db.BOUND_DIGITS)
            bounds[name] = bound
            certs[name] = {"degree": found["degree"], "lam": str(found["lam"]), "B": str(found["B"]),
                           "bound": str(bound), "V": terms_json(ring, found["V"]),
                           "step": found["step"].to_json(ring), "gram_sigma_E": found["output"].sigma.to_json()}
    except BudgetExhausted as exc:
        late = reasons.out_of_time("a bound on every output", search.budget.seconds,
                                   [str(exc), f"bounds found so far: {sorted(bounds)}", *detail])
        return ConditionResult("sos_bound", "inconclusive", late.summary,
                               numbers=late.numbers({"reason": str(exc), "time": "discrete"}),
                               solver={"solves": search.log})
    if not bounds:
        none = reasons.not_found("storage function V with V(F) <= lam V + 1 - lam on the recasting's relations "
                                 "that bounds an output", db.BOUND_DEGREES, detail, ("degree", "disturbances"))
        return ConditionResult("sos_bound", "not_certified", none.summary,
                               numbers=none.numbers({"tried": detail, "time": "discrete"}),
                               solver={"solves": search.log})
    claim = bound_claim(model, {k: float(v) for k, v in bounds.items()})
    numbers: dict[str, Any] = {key: value for key, value in claim.items() if key != "status"}
    numbers["time"] = "discrete"
    certificate = {"kind": KIND, "time": "discrete", "variables": list(ring.names),
                   "auxiliaries": m.system.definitions(), "outputs": certs}
    if box is not None:  # (the box's parameters are among the variables, bounded: one bound for every value)
        certificate["parameter_box"] = box.to_json()
    text = summary("sos_bound", {"status": "certified", **numbers, "certificate": certificate},
                   list(model.outputs)) or ""
    return ConditionResult("sos_bound", "certified", text, numbers=numbers, certificate=certificate,
                           solver={"solves": search.log}, disturbances="all")


# -- verify ----------------------------------------------------------------------------------------------

def verify(model: "RecastModel", c: Mapping[str, Any], box: "ModelBox | None" = None) -> tuple[bool, str]:
    """Re-check a certified ``sos_bound`` of a map with functions from its JSON and the model text alone,
    without a solver: the map, its relations and outputs re-derived, each output's two identities exactly,
    its bound ``>= sqrt(B)``, the stated figures (at least the certified bound) and reference points.
    ``box``: the document's box, which the certificate states (``parameter_box``) and whose parameters are
    bounded variables of its relations."""
    from lyapcheck.models.classes.bounds import bound_claim
    from lyapcheck.models.engines.recast_sos import ConditionCertificate, poly_from_json

    try:
        cert = c["certificate"]
        if cert.get("kind") != KIND or cert.get("time") != "discrete":
            return False, f"not a certificate of a discrete-time map's bound (kind {cert.get('kind')!r})"
        if cert.get("parameter_box") != (box.to_json() if box is not None else None):
            return False, "the certificate's box (parameter_box) is not the document's"
        m = disturbed_map(model, box)
        ring = m.ring
        if cert.get("variables") != list(ring.names) or cert.get("auxiliaries") != m.system.definitions():
            return False, "the certificate's variables or functions are not the map's"
        stated = c.get("bounds")
        if not isinstance(stated, dict) or set(stated) != set(cert["outputs"]) or not stated:
            return False, "the stated bounds are not the certificate's outputs"
        for out, data in cert["outputs"].items():
            if out not in model.outputs:
                return False, f"no output named {out}"
            V = poly_from_json(ring, data["V"], "V")
            lam, B = Fraction(data["lam"]), Fraction(data["B"])
            step = ConditionCertificate.from_json(ring, data["step"], len(m.relations))
            output = ConditionCertificate({}, {}, GramPoly.from_json(data["gram_sigma_E"], ring.nvars))
            ok, why = check_bound_on_relations(m, m.output(model, out), V, lam, B, step, output)
            if not ok:
                return False, f"output {out}: {why}"
            why_not = db.stated_bound_wrong(out, data, B, stated)
            if why_not is not None:
                return False, why_not
        claim = bound_claim(model, stated)
    except NotTaken as exc:
        return False, str(exc)
    except (KeyError, TypeError, ValueError, ZeroDivisionError, AttributeError) as exc:
        return False, f"malformed certificate: {exc}"
    why_not = db.stated_claim_wrong(c, claim)
    if why_not is not None:
        return False, why_not
    return True, ("every output's step identity holds exactly on the recasting's relations and the disturbances' "
                  "box, and its output identity exactly")


__all__ = ["KIND", "DisturbedMapOnRelations", "disturbed_map", "check_bound_on_relations", "bound_program",
           "best_bound", "run", "verify"]
