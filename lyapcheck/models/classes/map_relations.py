"""``quadratic`` and ``sos_gas`` on a discrete-time map with functions (``[model] time = "discrete"`` with
``sin``, ``tanh``, ``sat``, ``[networks]``, ...; issue 44, item 1): a global Lyapunov function of the states,
its step condition proved on the recasting's relations, checked exactly.

The map (:mod:`lyapcheck.models.classes.discrete_functions`: the recasting of its displacement) is read in
deviations: states ``e``, auxiliaries ``a`` (``tanh`` of each neuron's argument, ``sin x1``, ``cos x1``, a
saturation, ...) and the next state ``F(e, a) = e + d(e, a)``, polynomial in ``e`` and ``a`` (a displacement
with a denominator depending on them is not taken). A map's recasting does not derive its relations (a
network's would take minutes to move to the final ring), so this module derives them on the finished system,
each auxiliary's from the recasting's own table
(:func:`lyapcheck.models.language.recast.function_relations`): equalities ``h_i = 0`` (``s^2 + c^2 = 1``)
and inequalities ``g_j >= 0`` (sector bounds) that every true point ``(e, a(e))`` satisfies. With
``V = z_V^T Q_V z_V`` a polynomial of the states alone (``Q_V > 0``, a pure power of every state in its
basis) the certificate is

    V(e) - V(F(e, a)) - mu V(e) - sum_i lambda_i h_i - sum_j tau_j g_j = z_W^T Q_W z_W,

``lambda_i`` free polynomials, ``tau_j`` sums of squares, ``Q_W > 0`` with a pure power of every state in
``z_W``, ``0 <= mu < 1`` rational. At every true point the relations' terms are ``<= 0``, so
``V(F) <= (1 - mu) V - W`` with ``W >= lambda sum_i e_i^(2 k_i) > 0`` away from the fixed point whatever
``a`` is: ``V`` decreases strictly along every orbit, and is positive definite and radially unbounded: GAS.
A quadratic ``V = e^T P e`` with ``mu > 0`` proves GES: ``|e_k| <= sqrt(c2/c1) (1 - mu)^(k/2) |e_0|`` with
``c1 I < P < c2 I`` exact (the figures of a polynomial map,
:func:`lyapcheck.models.classes.discrete_lyapunov.ges_figures`).

The program and its search are the polynomial map's (:func:`~lyapcheck.models.classes.discrete_lyapunov.discrete_program`,
:func:`~lyapcheck.models.classes.discrete_lyapunov.search_program`: V carried by its coefficients, the
decrease a parameter of ``mu``, facial reduction, the best decay rate), with the relations' multipliers of the
continuous loops with functions (:func:`lyapcheck.models.classes.bounds.relation_multipliers`) as the
decrease's S-procedure terms. The exact check (:func:`check_map_relations`) is
:func:`~lyapcheck.models.engines.recast_sos.check_condition` on the identity, after the forms' checks of a
polynomial map (:func:`~lyapcheck.models.classes.discrete_lyapunov.check_forms`). The certificate (kind
:data:`KIND`) states ``V``, ``mu`` and the multipliers by relation index; :func:`verify` re-derives the map and
its relations from the model text and re-checks the identity exactly.

Size: a map's programs grow with its variables (a 2 x 32 network brings 64 auxiliaries); the polynomial
map's limits (:data:`~lyapcheck.models.classes.lyapunov.CANDIDATE_LIMIT` first, counted before any relation is
derived) refuse a program too large in one line, before any solve.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from fractions import Fraction
from typing import TYPE_CHECKING, Any, Final, Literal, Mapping, Sequence

from lyapcheck import tolerances
from lyapcheck.models.classes import discrete_lyapunov as dl
from lyapcheck.models.classes import lyapunov
from lyapcheck.models.classes.claims import DISCRETE_RELATIONS_KIND
from lyapcheck.models.engines import reasons
from lyapcheck.models.engines.reasons import size_limit
from lyapcheck.models.engines.search import Budget, BudgetExhausted, Search
from lyapcheck.results import ConditionResult
from lyapcheck.sos import bases
from lyapcheck.sos.certificates import GramPoly
from lyapcheck.sos.polynomials import Monomial, Poly, Ring, monomials, to_fmpq

if TYPE_CHECKING:  # pragma: no cover
    from lyapcheck.models.classes.bounds import BoundField
    from lyapcheck.models.engines.recast_sos import ConditionCertificate
    from lyapcheck.models.language.parameter_box import ModelBox
    from lyapcheck.models.language.recast import RecastModel, RecastSystem, Relation
    from lyapcheck.sos.structure import Gram, Scalar, Structure, Term

#: the certificate kind of ``quadratic`` and ``sos_gas`` on a map with functions
KIND: Final = DISCRETE_RELATIONS_KIND


class NotTaken(ValueError):
    """The map with functions is not one these classes read (a displacement with a denominator depending on
    the states or the auxiliaries)."""


@dataclass(frozen=True)
class MapOnRelations:
    """A map with functions as these classes read it: ``F`` in the recasting's ring (deviations), its
    relations, and the multipliers' view of them."""

    system: "RecastSystem"
    ring: Ring
    #: the next state of each state, ``e_i + d_i(e, a)``
    F: tuple[Poly, ...]
    relations: tuple["Relation", ...]
    #: the relations as :func:`~lyapcheck.models.classes.bounds.relation_multipliers` reads them
    field: "BoundField"
    #: over a box, the indices of its parameters (bounded constants, after the states; no next value)
    params: tuple[int, ...] = ()

    @property
    def n(self) -> int:
        return len(self.F)

    def moving(self, q: Monomial) -> bool:
        """``q`` holds a state or a function (it is not a monomial of the box's parameters alone, nor 1): a
        term of the identity that vanishes at the fixed point for every value of the box."""
        return any(e for i, e in enumerate(q) if i not in self.params)


def next_state(model: "RecastModel") -> tuple["RecastSystem", Ring, tuple[Poly, ...]]:
    """``F(e, a) = e + d(e, a)`` in deviations, exactly; :class:`NotTaken` when a displacement has a
    denominator depending on the variables, or a square root of an expression (its argument's sign unproved)."""
    system = model.system
    ring, F = next_state_of(system)
    return system, ring, F


def next_state_of(system: "RecastSystem", fixed: Mapping[str, Fraction] | None = None
                  ) -> tuple[Ring, tuple[Poly, ...]]:
    """:func:`next_state` of a recast displacement; ``fixed``: its last "states" that are bounded constants
    (a map's disturbances, :mod:`lyapcheck.models.classes.map_relations_bounds`), which get no next value."""
    from lyapcheck.models.classes.recast_classes import base_loop

    for a in system.auxiliaries:
        if a.function == "sqrt" and a.radicand is None:
            # (r^2 = q has no real point where q < 0: the identity would say nothing there, and the claim "from
            # every start" is only sound once q >= 0 is proved along the orbits, which is not built for a map)
            raise NotTaken(f"'{a.written_as}' is a square root of an expression of the states, whose argument is "
                           "not proved non-negative on a map")
    loop = base_loop(system, cylinder=False, fixed=fixed)
    ring = loop.ring
    F = []
    for s in loop.states():
        d = loop.flow(s)
        if not d.denominator.is_constant():
            raise NotTaken(f"the next value of {s} divides by an expression of the states or functions (a "
                           "polynomial map in the states and the functions is needed)")
        F.append(ring.gen(s) + d.numerator * (1 / d.denominator.leading_coefficient()))
    return ring, tuple(F)


def derived_relations(system: "RecastSystem") -> tuple["Relation", ...]:
    """Every auxiliary's relations (a sine's with its cosine, which follows it), in the finished system's
    ring and not shifted, each owned by its auxiliary: what a loop's recasting derives while it builds, which a
    map's does not (:func:`lyapcheck.models.language.recast.recast_dynamics`, ``for_map``)."""
    from lyapcheck.models.language.recast import Relation, function_relations, root_relations

    ring = system.ring
    out: list[Relation] = []
    auxes = system.auxiliaries
    for k, a in enumerate(auxes):
        x = ring.gen(a.name)
        if a.radicand is not None:
            made = root_relations(x, a.radicand)
        elif a.function == "cos":
            continue  # with its sine
        elif a.argument is None:  # pragma: no cover - every other auxiliary has an argument
            raise ValueError(f"the auxiliary {a.name} has no argument")
        elif a.function == "sin":
            pair = auxes[k + 1] if k + 1 < len(auxes) else None
            if pair is None or pair.function != "cos" or pair.argument != a.argument:  # pragma: no cover
                raise ValueError(f"the sine {a.name} is not followed by its cosine")
            made = function_relations(ring, "sin", x, a.argument, cosine=ring.gen(pair.name))
        else:
            made = function_relations(ring, a.function, x, a.argument, limit=a.limit)
        out += [Relation(r.kind, r.poly, r.why, a.name) for r in made]
    return tuple(out)


def on_relations(model: "RecastModel") -> MapOnRelations:
    """The map, its relations derived and shifted to the deviations (the loop of
    :func:`~lyapcheck.models.classes.recast_classes.base_loop`, without angles: a map's angle is a state)."""
    from lyapcheck.models.classes.bounds import BoundField
    from lyapcheck.models.classes.recast_classes import base_loop

    system, ring, F = next_state(model)
    loop = base_loop(replace(system, relations=derived_relations(system)), cylinder=False)
    relations = tuple(loop.relations)
    n = len(F)
    field = BoundField(ring, n, tuple(range(n)), tuple(range(n)), (), ring.constant(1), (), (),
                       relations=relations, multiplied=tuple(range(len(relations))),
                       unused=loop.roots(), square_free=loop.square_free())
    return MapOnRelations(system, ring, F, relations, field)


def on_relations_box(model: "RecastModel", box: "ModelBox") -> MapOnRelations:
    """:func:`on_relations` over a box of the map's parameters: the map recast with the box's parameters as
    variables after the states (:func:`lyapcheck.models.classes.discrete_functions_box.boxed_system`, read at
    the box's centre, its fixed point proved to stay put), each a bounded constant of the map (no next value;
    :func:`~lyapcheck.models.classes.recast_classes.base_loop` with ``fixed`` adds ``h^2 - u^2 >= 0``, ``u`` its
    deviation from the centre and ``h`` the box's half-width) among the relations. ``V`` stays a polynomial of
    the states: one ``V`` for every value of the box."""
    from lyapcheck.models.classes.bounds import BoundField
    from lyapcheck.models.classes.discrete_functions_box import boxed_system
    from lyapcheck.models.classes.recast_classes import base_loop

    system = boxed_system(model, box)
    halves = {name: box.half(name) for name in box.names}
    ring, F = next_state_of(system, fixed=halves)
    loop = base_loop(replace(system, relations=derived_relations(system)), cylinder=False, fixed=halves)
    relations = tuple(loop.relations)
    n = len(F)
    field = BoundField(ring, n, tuple(range(n)), tuple(range(n)), (), ring.constant(1), (), (),
                       relations=relations, multiplied=tuple(range(len(relations))),
                       unused=loop.roots(), square_free=loop.square_free())
    index = {name: i for i, name in enumerate(ring.names)}
    params = tuple(index[name] for name in box.names)
    if params != tuple(range(n, n + len(params))):  # pragma: no cover - boxed_system puts them after the states
        raise ValueError("the box's parameters do not follow the states in the recasting's ring")
    return MapOnRelations(system, ring, F, relations, field, params)


# -- the program ----------------------------------------------------------------------------------------

def symmetry(m: MapOnRelations) -> list[tuple[int, ...]]:
    """The sign changes of all the variables under which each state's next value changes like the state and
    every relation is invariant: the identity's solutions map to solutions, so an invariant one exists."""
    ring = m.ring
    odd: list[tuple[Any, int | None]] = [(ring.support(fi), i) for i, fi in enumerate(m.F)]
    odd += [(ring.support(r.poly), None) for r in m.relations]
    return bases.sign_symmetries(ring.nvars, odd)


def _vanishes_at_origin(ring: Ring, p: Poly, params: Sequence[int] = ()) -> bool:
    """``p`` is 0 at the fixed point (the states and the functions 0) for every value of the box's ``params``."""
    return ring.substitute(p, {name: Fraction(0) for i, name in enumerate(ring.names) if i not in params}).is_zero()


def multipliers(m: MapOnRelations, generators: Sequence[Sequence[int]]) -> dl.Multipliers:
    """The relations' S-procedure terms of the decrease (free ``lambda_i``, SOS ``tau_j`` with the program's
    margin). The other terms vanish at the fixed point and ``W >= 0``, so ``tau_j(0) g_j(0) = 0``: a relation
    not tight there (``1 - t^2 >= 0``) keeps no constant in its multiplier's basis (the solver would find
    that diagonal 0 and no strict certificate). Over a box: :func:`box_multipliers`."""
    from lyapcheck.models.classes.bounds import relation_multipliers

    ring = m.ring
    if m.params:
        return lambda target: box_multipliers(m, target, generators)

    def terms(target: set[Monomial]) -> tuple[list["Gram"], list["Scalar"], list["Term"], set[Monomial]]:
        grams, scalars, terms_, added = relation_multipliers(m.field, "W", target, generators, margin=True)
        kept = []
        for g in grams:
            j = int(g.name.split("_")[1])
            if not _vanishes_at_origin(ring, m.relations[j].poly):
                g = _kept(g, [k for k, q in enumerate(g.basis) if any(q)])
            kept.append(g)
        names = {g.name for g in kept if g.basis}
        return ([g for g in kept if g.basis], scalars,
                [t for t in terms_ if not t.decision.startswith("TW_") or t.decision in names], added)

    return terms


def box_multipliers(m: Any, target: set[Monomial], generators: Sequence[Sequence[int]], name: str = "W",
                    margin: bool | str = True, vanishing: bool = True, param_degree: int = 0
                    ) -> tuple[list["Gram"], list["Scalar"], list["Term"], set[Monomial]]:
    """:func:`multipliers` over a box, degrees counted in the states and functions alone (the "moving"
    variables; the box's parameters ``u`` are bounded constants). The point's terms are kept as they are (each
    relation's multiplier of the moving degree the decrease reaches, without the parameters), and the box's
    own ``h^2 - u^2 >= 0`` gets a sum of squares of the moving monomials of half that degree: ``tau(e, a)
    (h^2 - u^2)`` absorbs the ``u^2 a^2`` the parameter brings (``V(F)`` with ``F = ... + (c + u) t``). A
    multiplier of full total degree would bring products (``x^2 y t``, ``u^2`` alone) whose squares nothing in
    the identity holds, and W's margin would be 0 on them. Every multiplier vanishes at the fixed point where
    its relation does not (``tau(0, u) g(0, u) = 0`` for every ``u``, as ``W(0, u) = 0``; ``vanishing`` False:
    an identity with a constant, as ``sos_bound``'s step, needs no such care). ``m``: a map read on its relations
    with ``ring``, ``relations``, ``field`` and the box's ``params`` (:class:`MapOnRelations`, or
    :class:`lyapcheck.models.classes.map_relations_bounds.DisturbedMapOnRelations`); ``name`` and ``margin``:
    the identity's and the Grams' (:func:`lyapcheck.models.classes.bounds.relation_multipliers`).
    ``param_degree``: the box's own multipliers' basis also holds each of its monomials times the parameters'
    monomials up to this degree: a ``B`` of degree 4 brings ``u^4 t^4`` (``(c + u)^4 t^4`` in ``B(F)``), which
    only ``tau(e, a, u) (h^2 - u^2)`` with ``u t^2`` in ``tau``'s basis holds (a safety class's step,
    :func:`lyapcheck.models.classes.map_relations_safety.step_multipliers`)."""
    from lyapcheck.sos.program import Coefficients, Gram, Scalar, Term

    ring = m.ring
    nv = ring.nvars
    params = set(m.params)

    def moving(q: Monomial) -> bool:
        return not vanishing or any(e for i, e in enumerate(q) if i not in params)

    def moving_degree(q: Monomial) -> int:
        return sum(e for i, e in enumerate(q) if i not in params)

    top = max((moving_degree(q) for q in target), default=2)
    top += top % 2
    field = m.field
    plain = [q for q in monomials(nv, 0, top) if not any(q[i] for i in params) and field.allowed(q)]
    grams: list[Gram] = []
    scalars: list[Scalar] = []
    terms: list[Term] = []
    added: set[Monomial] = set()
    for i, rel in enumerate(m.relations):
        support = ring.support(rel.poly)
        d = max((moving_degree(q) for q in support), default=0)
        tight = _vanishes_at_origin(ring, rel.poly, m.params)
        if rel.kind == "eq":
            for k, q in enumerate(q for q in plain if moving_degree(q) <= top - d and (tight or moving(q))):
                scalar = f"L{name}_{i}_{k}"
                scalars.append(Scalar(scalar))
                product = ring.monomial(q) * rel.poly
                terms.append(Term(Coefficients.literal(ring.terms(-product)), scalar))
                added |= set(ring.support(product))
            continue
        if top - d < 0:
            continue
        basis = [q for q in plain if moving_degree(q) <= (top - d) // 2 and (tight or moving(q))]
        if param_degree and d == 0:  # (the box's own h^2 - u^2 >= 0: its multiplier may hold the parameters too)
            powers = [p for p in monomials(nv, 1, param_degree)
                      if not any(e for i, e in enumerate(p) if i not in params)]
            basis += [tuple(a + b for a, b in zip(q, p)) for q in basis for p in powers]
        if not basis:
            continue
        gram = f"T{name}_{i}"
        grams.append(Gram(gram, tuple(basis), tuple(map(tuple, bases.character_blocks(basis, generators))),
                          margin=margin))
        terms.append(Term(Coefficients.literal(ring.terms(-rel.poly)), gram))
        added |= {tuple(a + b + c for a, b, c in zip(x, z, w)) for x in basis for z in basis for w in support}
    return grams, scalars, terms, added


def _kept(g: "Gram", keep: Sequence[int]) -> "Gram":
    """The Gram ``g`` with only the basis monomials at ``keep`` (its blocks cut the same way)."""
    new = {k: i for i, k in enumerate(keep)}
    blocks = tuple(b for b in (tuple(new[k] for k in block if k in new) for block in g.blocks) if b)
    return replace(g, basis=tuple(g.basis[k] for k in keep), blocks=blocks)


def attempt(m: MapOnRelations, structure: "Structure", alphas: Sequence[Monomial], mu: Fraction, search: Search
            ) -> tuple[dict[str, Any] | None, Any]:
    """One solve at decay rate ``mu``; the exact certificate if it passes :func:`check_map_relations`."""
    from lyapcheck.models.classes.bounds import relation_certificates
    from lyapcheck.models.engines.search import exact_grams

    if mu >= dl.MU_CEILING:
        return None, None  # (no map but 0 meets V(F) <= (1 - mu) V with mu >= 1)
    point, solution = lyapunov.exact_try(structure, dl.decrease_values(m.ring, m.F, alphas, mu), search)
    if point is None:
        return None, solution
    V = exact_grams(structure, point)["V"]
    decrease, = relation_certificates(m.field, structure, point, (("W", "W"),))
    ok, _ = check_map_relations(m, V, mu, decrease)
    if not ok:
        return None, solution
    return {"V": V, "W": decrease.sigma, "mu": mu, "margin": solution.scalars["t"], "decrease": decrease}, solution


def search_degree(m: MapOnRelations, degree: int, search: Search) -> tuple[dict[str, Any] | None, str]:
    """A certificate with ``V`` of this degree and its best decay rate, or None and why not."""
    generators = symmetry(m)
    extra = multipliers(m, generators)
    field = m.field
    return dl.search_program(
        degree,
        lambda drop, drop_v: dl.discrete_program(m.ring, m.F, degree, generators, drop, drop_v, multipliers=extra,
                                                 allowed=lambda q: field.allowed(q) and m.moving(q)),
        lambda structure, alphas, mu: attempt(m, structure, alphas, mu, search))


# -- the exact check ------------------------------------------------------------------------------------

def check_map_relations(m: MapOnRelations, V: GramPoly, mu: Fraction, decrease: "ConditionCertificate"
                        ) -> tuple[bool, str]:
    """Exactly: the forms (``0 <= mu < 1``, ``V`` of the states alone, positive definite and radially
    unbounded, ``Q_W > 0`` with a pure power of every state) and the identity on the map's relations, every
    ``tau_j`` a sum of squares on an inequality, every ``lambda_i`` on an equality."""
    from lyapcheck.models.engines.recast_sos import check_condition

    if decrease.rho is not None:
        return False, "a global decrease has no region multiplier"
    ok, why = dl.check_forms(V, decrease.sigma, mu, m.n)
    if not ok:
        return False, why
    ring = m.ring
    v = V.poly(ring)
    ok, why = check_condition(ring, v - dl.compose(ring, v, m.F) - v * to_fmpq(mu), m.relations, decrease)
    if not ok:
        return False, f"V - V(F) - mu V = W on the map's relations: {why}"
    return True, ("Q_V > 0, Q_W > 0 and V - V(F) - mu V - sum lambda_i h_i - sum tau_j g_j = W on the recasting's "
                  "relations, exactly (discrete-time map with functions)")


# -- the class --------------------------------------------------------------------------------------------

def run(model: "RecastModel", name: dl.ClassName, budget: Budget, degrees: Sequence[int] | None = None,
        box: "ModelBox | None" = None) -> ConditionResult:
    """``quadratic`` (degree 2) or ``sos_gas`` (the searched degrees of a polynomial map) on a map with
    functions (module docstring); ``box``: one ``V`` for every value of that box of the map's parameters
    (:func:`on_relations_box`)."""
    if degrees is None:
        if name == "sos_gas":
            from lyapcheck.degrees import searched_degrees

            degrees = searched_degrees(dl.SOS_GAS_DEGREES)
        else:
            degrees = (2,)
    # (as a polynomial map's: a quadratic's failure claims nothing, sos_gas's is about GAS)
    prop: Literal["GAS"] | None = "GAS" if name == "sos_gas" else None
    try:
        if box is None:
            system, ring, F = next_state(model)
        else:
            boxed = on_relations_box(model, box)
            system, ring, F = boxed.system, boxed.ring, boxed.F
    except NotTaken as exc:
        return ConditionResult(name, "not_applicable", f"not taken on this map with functions: {exc}")
    if ring.nvars > tolerances.MAP_RELATIONS_VARIABLES:  # (before any relation is derived: a network's are many)
        none = reasons.reason("no Lyapunov function of the map on the recasting's relations was searched: "
                              + size_limit(ring.nvars, "variables (states and functions)",
                                           tolerances.MAP_RELATIONS_VARIABLES, "MAP_RELATIONS_VARIABLES")
                              + " (roa proves a region on the true map by ball arithmetic)", ("fewer",))
        return ConditionResult(name, "not_certified", none.summary, numbers=none.numbers({"time": "discrete"}),
                               property=prop)
    search = Search(ring, budget)
    tried: list[str] = []
    m: MapOnRelations | None = None
    try:
        for degree in degrees:
            top = degree * dl.map_degree(ring, F)
            count = bases.candidate_count(ring.nvars, top)
            if count > lyapunov.CANDIDATE_LIMIT:  # (before any relation is derived: a network's are many)
                tried.append(f"degree {degree}: " + size_limit(count, "candidate monomials in "
                                                                f"{ring.nvars} variables (states and functions)",
                                                                lyapunov.CANDIDATE_LIMIT, "CANDIDATE_LIMIT"))
                continue
            search.budget.check()
            m = m or (on_relations(model) if box is None else boxed)
            found, why = search_degree(m, degree, search)
            tried.append(why)
            if found is not None:
                return certified(m, name, found, {"solves": search.log}, box)
    except BudgetExhausted as exc:
        late = reasons.out_of_time("a Lyapunov function of the map", search.budget.seconds, [str(exc), *tried])
        return ConditionResult(name, "inconclusive", late.summary,
                               numbers=late.numbers({"reason": str(exc), "tried": tried, "time": "discrete"}),
                               solver={"solves": search.log})
    steps = ("sos_gas",) if name == "quadratic" else ("degree",)
    none = reasons.not_found("Lyapunov function of the discrete-time map on the recasting's relations", degrees,
                             tried, steps)
    return ConditionResult(name, "not_certified", none.summary, numbers=none.numbers({"tried": tried,
                                                                                      "time": "discrete"}),
                           solver={"solves": search.log}, property=prop)


def v_of_states(m: MapOnRelations, v: Poly) -> dict[str, Any]:
    """``V``'s exact terms over the states alone (exponents per state, as a polynomial map's certificate
    states its V, which sweeps and reports read): V is a polynomial of the states. Over a box, over the states
    and then the box's parameters (each at exponent 0), as a polynomial map's V over a box."""
    states = Ring(m.ring.names[:m.n + len(m.params)])  # (the box's parameters follow the states)
    return lyapunov.terms_json(states, m.ring.restrict(v, states))


def certified(m: MapOnRelations, name: dl.ClassName, found: dict[str, Any], solver: dict[str, Any],
              box: "ModelBox | None" = None) -> ConditionResult:
    from lyapcheck.models.classes.claims import discrete_lyapunov_sentence
    from lyapcheck.models.classes.recast_classes import v_text

    V, mu = found["V"], found["mu"]
    ring = m.ring
    figures = dl.ges_figures(V, mu, m.n) if name == "quadratic" else None
    v = V.poly(ring)
    cert: dict[str, Any] = {"kind": KIND, "time": "discrete", "variables": list(ring.names),
                            "auxiliaries": m.system.definitions(), "degree": found["degree"], "mu": str(mu),
                            "V": v_of_states(m, v), "V_text": v_text(m.system, v), "gram_V": V.to_json(),
                            "decrease": found["decrease"].to_json(ring)}
    if box is not None:  # (the box's parameters are among the variables, bounded: one V for every value)
        cert["parameter_box"] = box.to_json()
    numbers: dict[str, Any] = {"degree": found["degree"], "time": "discrete", "decay_rate_V_per_step": float(mu),
                               "relative_margin": found["margin"]}
    if figures is not None:
        cert.update({key: str(value) for key, value in figures.items()})
        numbers.update({"k": float(figures["k"]), "contraction_per_step": float(figures["r"])})
    kind = dl.QUADRATIC_KIND if figures is not None else dl.SOS_KIND
    return ConditionResult(name, "certified", discrete_lyapunov_sentence(kind, found["degree"], mu, figures),
                           numbers=numbers, certificate=cert, solver=solver,
                           property="GES" if figures is not None else "GAS")


def verify(model: "RecastModel", name: str, data: Mapping[str, Any], box: "ModelBox | None" = None
           ) -> tuple[bool, str]:
    """Re-check a certified ``quadratic`` or ``sos_gas`` of a map with functions from its JSON and the model
    text alone, without a solver: the map and its relations re-derived, the identity and the forms exactly,
    the stated ``V``, the GES figures, the property and the sentence. ``box``: the document's box, whose
    parameters (bounded by it, :func:`on_relations_box`) the certificate states among its variables and whose
    ``parameter_box`` it states; the sentence is compared without the box's words in front."""
    from lyapcheck.models.classes.claims import discrete_lyapunov_sentence
    from lyapcheck.models.engines.recast_sos import ConditionCertificate

    try:
        cert = data["certificate"]
        if cert.get("kind") != KIND or cert.get("time") != "discrete":
            return False, f"a {name} certificate of a map with functions has kind {KIND!r}"
        if box is not None and cert.get("parameter_box") != box.to_json():
            return False, "a certificate over a box states that box (parameter_box) as the document's"
        if box is None and "parameter_box" in cert:
            return False, "a certificate over a box (parameter_box) in a document without that box"
        m = on_relations(model) if box is None else on_relations_box(model, box)
        ring = m.ring
        if cert.get("variables") != list(ring.names) or cert.get("auxiliaries") != m.system.definitions():
            return False, "the certificate's variables or functions are not the map's"
        V = GramPoly.from_json(cert["gram_V"], ring.nvars)
        mu = Fraction(cert["mu"])
        degree = int(cert["degree"])
        decrease = ConditionCertificate.from_json(ring, cert["decrease"], len(m.relations))
    except NotTaken as exc:
        return False, str(exc)
    except (KeyError, TypeError, ValueError, ZeroDivisionError, AttributeError) as exc:
        return False, f"malformed certificate: {exc}"
    ok, why = check_map_relations(m, V, mu, decrease)
    if not ok:
        return False, why
    if v_of_states(m, V.poly(ring)) != cert.get("V"):
        return False, "the stated V is not the certificate's Gram V"
    if degree != 2 * max(sum(q) for q in V.basis) or (name == "quadratic" and degree != 2):
        return False, "the stated degree is not V's"
    figures = None
    if any(key in cert for key in ("c1", "c2", "k", "r")):
        P = dl.quadratic_matrix_of(V, m.n)
        if name != "quadratic" or P is None or mu <= 0:
            return False, "GES needs a quadratic V (every state, degree 1) and mu > 0"
        try:
            figures = {key: Fraction(cert[key]) for key in ("c1", "c2", "k", "r")}
        except (KeyError, TypeError, ValueError, ZeroDivisionError) as exc:
            return False, f"malformed figures: {exc}"
        ok, why_ges = dl._check_ges_figures(P, mu, figures)
        if not ok:
            return False, why_ges
    ok, why_figures = dl._check_stated_figures(data, mu, figures)
    if not ok:
        return False, why_figures
    if data.get("property") != ("GES" if figures is not None else "GAS"):
        return False, f"this certificate does not prove {data.get('property')}"
    kind = dl.QUADRATIC_KIND if figures is not None else dl.SOS_KIND
    text = data.get("summary")
    if box is not None and isinstance(text, str):
        from lyapcheck.models.classes.claims import DISTURBANCE_PREFIX, box_words

        # the box's words come first, then a disturbed map's "(d = 0) " (claims.summary)
        text = text.removeprefix(f"for every {box_words(box.to_json())}: ")
        if data.get("disturbances") == "zero":
            text = text.removeprefix(DISTURBANCE_PREFIX["zero"])
    if text != discrete_lyapunov_sentence(kind, degree, mu, figures):
        return False, "the stated sentence is not the certificate's"
    return True, why


__all__ = ["KIND", "NotTaken", "MapOnRelations", "next_state", "derived_relations", "on_relations", "on_relations_box",
           "box_multipliers", "check_map_relations", "run", "certified", "verify"]
