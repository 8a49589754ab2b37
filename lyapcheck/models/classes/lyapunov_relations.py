"""``quadratic`` and ``sos_gas`` on a loop with functions: the program of
:mod:`lyapcheck.models.classes.lyapunov` with the recasting's relations (its search and exact check).

The loop (:class:`~lyapcheck.models.classes.recast_classes.Loop`, its square roots' bounds proved) is read as a
:class:`~lyapcheck.models.classes.bounds.BoundField` without disturbances: the variables ``V`` may use (the
states, an angle through its sine and cosine, the smooth auxiliaries) move as ``N / D``, every factor of
``D`` proved positive on the recasting's set S, and the identity of the polynomial case carries the
relations' multipliers (:func:`~lyapcheck.models.classes.bounds.relation_multipliers`: a free ``lambda_i``
per equality ``h_i = 0``, a sum of squares ``tau_j`` per inequality ``g_j >= 0``), unscaled (time in s):

    -grad V . N - mu V D - sum_i lambda_i h_i - sum_j tau_j g_j = z_W^T Q_W z_W,   Q_V, Q_W > 0,   mu >= 0.

Every point ``(z, a(z))`` of the true loop satisfies the relations, so there ``V' = grad V . N / D <= -mu V
- W / D``. The bases of ``V`` and ``W`` hold a pure power of every coordinate (each non-angle state, and
each angle's cosine deviation ``cos - 1``, which vanishes on the cylinder only at the angle's equilibrium):
``V`` is positive definite and radially unbounded in the states and ``V' < 0`` away from the equilibrium:
GAS (modulo 2 pi in the angles). A quadratic ``V`` in the states alone with ``mu > 0`` proves GES as on a
polynomial loop: ``|x(t)| <= sqrt(c2/c1) |x0| exp(-mu t / 2)`` with ``c1 I < P < c2 I`` exact.

The search is the polynomial one (maximize the Gram matrices' smallest eigenvalue with ``trace Q_V = 1``,
facial reduction, then the largest ``mu`` by :func:`~lyapcheck.models.classes.lyapunov.best_decay_rate`), over
templates tried in turn (:func:`relations_templates`), each with a budget of solves
(:data:`~lyapcheck.tolerances.TEMPLATE_SOLVES`) and a size limit (:data:`~lyapcheck.tolerances.TEMPLATE_GRAM_ROWS`),
counts that decide the same way on any machine. Another equilibrium of an angle loop refutes GAS first
(:func:`~lyapcheck.models.classes.recast_classes.refute_global`, called by the route).
"""

from __future__ import annotations

from dataclasses import replace
from fractions import Fraction
from typing import TYPE_CHECKING, Any, Mapping, Sequence

from lyapcheck.models.classes.lyapunov import (LYAPUNOV_FACIAL_ROUNDS,
                                               OLD_FORMAT, OLD_RELATIONS_KIND, RELATIONS_KIND, TARGET_LIMIT,
                                               gram_products, best_decay_rate, eigen_bounds, exact_try, failure,
                                               kernel_monomials, lyapunov_identity, relations_claim, relations_sentence,
                                               vanishing_monomials, widen_by_derivative)
from lyapcheck.models.engines import reasons
from lyapcheck.models.engines.reasons import size_limit
from lyapcheck.models.engines.search import BudgetExhausted, ParameterValues, Search, one, param
from lyapcheck.results import ConditionResult
from lyapcheck.sos import bases
from lyapcheck.sos.certificates import GramPoly
from lyapcheck.sos.polynomials import Monomial, Poly, monomials, to_fmpq
from lyapcheck.sos.structure import Gram, Structure, Term

if TYPE_CHECKING:  # pragma: no cover
    from lyapcheck.sos.program import Solution


def relations_field(loop: Any, names: Sequence[str], N: Mapping[str, Poly], D: Poly) -> Any:
    """The program's view of a loop with functions for ``V`` over the variables ``names`` (moving as
    ``N / D``): every relation multiplied, the coordinates V and W need pure powers of (non-angle states
    and the angles' cosines)."""
    from lyapcheck.models.classes.bounds import BoundField

    ring = loop.ring
    index = {name: i for i, name in enumerate(ring.names)}
    coordinates = tuple(index[s] for s in loop.states() if s not in loop.angles) + \
        tuple(index[cosine] for _, cosine in loop.angles.values())
    return BoundField(ring, len(loop.states()), tuple(index[name] for name in names), coordinates,
                      tuple((index[name], N[name]) for name in names if not N[name].is_zero()), D, (), (),
                      relations=tuple(loop.relations), multiplied=tuple(range(len(loop.relations))),
                      unused=loop.unused() | loop.roots(), square_free=loop.square_free())


def _relations_symmetry(field: Any) -> list[tuple[int, ...]]:
    ring = field.ring
    odd = [(ring.support(gi), i) for i, gi in field.flows] + [(ring.support(field.W), None)]
    odd += [(ring.support(field.relations[j].poly), None) for j in field.multiplied]
    return bases.sign_symmetries(ring.nvars, odd)


def relations_program(field: Any, degree: int, generators: Sequence[Sequence[int]],
                      drop: frozenset[tuple[str, Monomial]] = frozenset()) -> Structure | str:
    """The program of :func:`lyapunov_program` on a loop with functions (the comment above), or why there
    is none (a size limit, named; no strict certificate of the form). ``drop``: (Gram, monomial) pairs left
    out (facial reduction)."""
    from lyapcheck import tolerances
    from lyapcheck.models.classes.bounds import _embed, relation_multipliers

    ring = field.ring
    nv = ring.nvars
    z_v = [q for q in (_embed(a, field.v_vars, nv) for a in monomials(len(field.v_vars), 1, degree // 2))
           if ("V", q) not in drop]
    if not bases.has_pure_powers(z_v, field.coordinates):
        return ("no strict certificate of this form exists (V's basis, reduced to the face the solver found, "
                "keeps no pure power of some state)")
    v_blocks = bases.character_blocks(z_v, generators)
    products = gram_products(z_v, v_blocks)
    target: set[Monomial] = set()
    widen_by_derivative(target, ring, products, field.flows, ring.support(field.W))
    rel_grams, rel_scalars, rel_terms, added = relation_multipliers(field, "W", target, generators)
    target |= added
    # each multiplier a sum of squares with the program's margin, on the face the solver found (a
    # multiplier whose whole basis vanished is left out with its term)
    rel_grams = [_reduced(replace(g, margin=True), drop) for g in rel_grams]
    kept = {g.name for g in rel_grams if g.basis}
    rel_grams = [g for g in rel_grams if g.basis]
    rel_terms = [t for t in rel_terms if not t.decision.startswith("TW_") or t.decision in kept]
    if len(target) > TARGET_LIMIT:
        return size_limit(len(target), "monomials in one polynomial identity", TARGET_LIMIT, "TARGET_LIMIT")
    # every term vanishes at the equilibrium, so W(0) = 0: the constant monomial has no place in W's
    # basis (with it no Q_W > 0 exists; the relations' monomials would put it there)
    z_w = [q for q in bases.sos_basis(nv, target) if ("W", q) not in drop and field.allowed(q) and any(q)]
    rows = max([len(z_w), len(z_v)] + [len(g.basis) for g in rel_grams])
    if rows > tolerances.TEMPLATE_GRAM_ROWS:
        return size_limit(rows, "rows of one sum-of-squares matrix", tolerances.TEMPLATE_GRAM_ROWS,
                          "TEMPLATE_GRAM_ROWS")
    if not z_w or not bases.has_pure_powers(z_w, field.coordinates):
        return ("no strict certificate of this form exists (the Newton polytope of -V' leaves no pure power of "
                "every state in its basis)")
    terms = [Term(param(f"g{i}", ring.support(gi)), "V", derivative=i) for i, gi in field.flows]
    terms.append(Term(param("muD", ring.support(field.W)), "V"))
    terms.extend(rel_terms)
    terms.append(Term(one(ring, -1), "W"))
    return lyapunov_identity(nv, (Gram("V", tuple(z_v), tuple(map(tuple, v_blocks))),
                                  Gram("W", tuple(z_w), tuple(map(tuple, bases.character_blocks(z_w, generators)))),
                                  *rel_grams), rel_scalars, terms)


def _reduced(gram: Gram, drop: frozenset[tuple[str, Monomial]]) -> Gram:
    """``gram`` without the monomials ``drop`` names for it (its blocks renumbered)."""
    keep = [k for k, q in enumerate(gram.basis) if (gram.name, q) not in drop]
    new = {k: j for j, k in enumerate(keep)}
    blocks = tuple(b for b in (tuple(new[k] for k in block if k in new) for block in gram.blocks) if b)
    return replace(gram, basis=tuple(gram.basis[k] for k in keep), blocks=blocks)


def relations_values(field: Any, mu: Fraction) -> ParameterValues:
    values = ParameterValues()
    ring = field.ring
    for i, gi in field.flows:
        values.set_poly(ring, f"g{i}", -gi, ring.support(gi))
    values.set_poly(ring, "muD", field.W * to_fmpq(-mu), ring.support(field.W))
    return values


def relations_attempt(field: Any, structure: Structure, mu: Fraction, search: Search
                      ) -> tuple[dict[str, Any] | None, Solution]:
    """One solve at decay rate ``mu`` on a loop with functions; the certificate if it passes the exact
    check (:func:`check_relations`)."""
    from lyapcheck.models.classes.bounds import relation_certificates
    from lyapcheck.models.engines.search import exact_grams

    point, solution = exact_try(structure, relations_values(field, mu), search)
    if point is None:
        return None, solution
    V = exact_grams(structure, point)["V"]
    decrease, = relation_certificates(field, structure, point, (("W", "W"),))
    ok, _ = check_relations(field, V, mu, decrease)
    if not ok:
        return None, solution
    return {"V": V, "W": decrease.sigma, "mu": mu, "margin": solution.scalars["t"], "decrease": decrease}, solution


def check_relations(field: Any, V: GramPoly, mu: Fraction, decrease: Any) -> tuple[bool, str]:
    """Exactly, on a loop with functions: ``mu >= 0``, ``V``'s basis in ``V``'s variables with a pure power
    of every coordinate and ``Q_V > 0``, the remainder's basis with a pure power of every coordinate and
    ``Q_W > 0``, and the identity on the recasting's relations
    (:func:`~lyapcheck.models.engines.recast_sos.check_condition`)."""
    from lyapcheck.models.engines.recast_sos import check_condition

    ring = field.ring
    if mu < 0:
        return False, "the decay rate mu must be >= 0"
    if not V.basis or any(q[i] for q in V.basis for i in range(ring.nvars) if i not in field.v_vars) \
            or any(sum(q) == 0 for q in V.basis):
        return False, "V's basis may hold non-constant monomials of V's variables only"
    W = decrease.sigma
    if not bases.has_pure_powers(V.basis, field.coordinates) or not bases.has_pure_powers(W.basis, field.coordinates):
        return False, "the bases of V and W must hold a pure power of every state (and of each angle's cosine)"
    if not V.positive_definite() or not W.positive_definite():
        return False, "Q_V or Q_W is not positive definite (exact)"
    v = V.poly(ring)
    flow = ring.zero()
    for i, gi in field.flows:
        flow += v.derivative(i) * gi
    ok, why = check_condition(ring, -flow - v * field.W * to_fmpq(mu), field.relations, decrease)
    if not ok:
        return False, f"decrease: {why}"
    return True, ("Q_V > 0, Q_W > 0 and -grad V . N - mu V D = W on the recasting's relations, D > 0 proved: "
                  "exactly")


def relations_search_degree(field: Any, degree: int, search: Search, rates: Search | None = None
                            ) -> tuple[dict[str, Any] | None, str]:
    """:func:`search_degree` on a loop with functions: a certificate with ``V`` of this degree over the
    field's variables (and its best decay rate, searched with ``rates``, default ``search``: a
    certificate found is kept whatever the template's budget of solves), or None and why not."""
    generators = _relations_symmetry(field)
    drop: frozenset[tuple[str, Monomial]] = frozenset()
    why = "none found"
    for _ in range(LYAPUNOV_FACIAL_ROUNDS + 1):
        structure = relations_program(field, degree, generators, drop)
        if isinstance(structure, str):
            return None, structure + (f" (after facial reduction, where {why})" if drop else "")
        found, solution = relations_attempt(field, structure, Fraction(0), search)
        if found is not None:
            break
        why = failure(solution)
        vanishing = frozenset((g.name, m) for g in structure.grams for m in vanishing_monomials(g, solution))
        if not vanishing:  # no zero diagonal: try the kernels' supports
            vanishing = frozenset((g.name, m) for g in structure.grams for m in kernel_monomials(g, solution))
        if not vanishing or vanishing <= drop:
            return None, why
        drop = drop | vanishing
    else:
        return None, f"{why} (after {LYAPUNOV_FACIAL_ROUNDS} rounds of facial reduction)"
    found = best_decay_rate(lambda mu: relations_attempt(field, structure, mu, rates or search)[0], found)
    found["degree"] = degree
    return found, "found"


def relations_templates(loop: Any, degrees: Sequence[int], states_only: bool) -> list[tuple[int, list[int]]]:
    """The (degree, variables of V) tried in turn on a loop with functions: per degree, the states alone
    (cheaper, and their denominator has lower degree), then with the smooth auxiliaries; with an angle,
    the second only (an angle enters through its sine and cosine)."""
    all_vars = loop.v_variables()
    coordinates = loop.coordinates()
    if loop.angles:
        return [(dv, all_vars) for dv in degrees]
    choices = [coordinates] if len(all_vars) == len(coordinates) or states_only else [coordinates, all_vars]
    return [(dv, vs) for dv in degrees for vs in choices if vs]


def run_relations(loop: Any, budget: Any, name: str, degrees: Sequence[int]) -> ConditionResult:
    """``quadratic`` (degrees ``(2,)``, ``V`` in the states alone) or ``sos_gas`` on a loop with functions
    (its square roots' bounds proved): each template of :func:`relations_templates` in turn, with a budget
    of solves each (:data:`~lyapcheck.tolerances.TEMPLATE_SOLVES`, a count: one large program leaves the
    others their turn the same way on any machine)."""
    from lyapcheck import tolerances
    from lyapcheck.models.classes.recast_classes import common_denominator, prove_denominators
    from lyapcheck.models.engines.search import SolvesSpent
    from lyapcheck.models.language.recast import written_poly

    if name == "quadratic" and loop.angles:
        return ConditionResult(name, "not_applicable", f"{', '.join(loop.angles)} enters the loop only through "
                               "its sine and cosine: a quadratic in it is not periodic (sos_gas uses the sine and "
                               "cosine)", property="GAS")
    ring = loop.ring
    search = Search(ring, budget)
    tried: list[str] = []
    spent: list[str] = []  # the templates whose budget of solves ended their search
    try:
        for dv, v_vars in relations_templates(loop, degrees, name == "quadratic"):
            names = [ring.names[i] for i in v_vars]
            label = f"degree {dv} in {', '.join(names)}"
            N, D, distinct = common_denominator(loop, names)
            dens, failed = prove_denominators(loop, distinct, search)
            if failed is not None:
                return ConditionResult(name, "not_applicable", f"the denominator {written_poly(ring, failed)} could "
                                       "not be proved positive on the recasting's set", property="GAS")
            field = relations_field(loop, names, N, D)
            search.budget.check()
            capped = search.within(tolerances.TEMPLATE_SOLVES, "per template", "lyapcheck.tolerances.TEMPLATE_SOLVES")
            try:
                found, why = relations_search_degree(field, dv, capped, search)
            except SolvesSpent as exc:
                tried.append(f"{label}: {exc}")
                spent.append(exc.limit.words())
                continue
            tried.append(f"{label}: {why}")
            if found is not None:
                return _certified_relations(loop, field, dens, name, found, {"solves": search.log})
    except BudgetExhausted as exc:
        late = reasons.out_of_time("a Lyapunov function", budget.seconds, [str(exc), *tried])
        return ConditionResult(name, "inconclusive", late.summary, numbers=late.numbers({"reason": str(exc),
                                                                                        "tried": tried}),
                               property="GAS", solver={"solves": search.log})
    steps = ("sos_gas", "candidate") if name == "quadratic" else ("degree", "candidate")
    none = reasons.not_found("Lyapunov function", degrees, tried, steps)
    if spent:
        none = reasons.with_budget(none, spent[0])
    return ConditionResult(name, "not_certified", none.summary, numbers=none.numbers({"reason": "; ".join(tried)}),
                           solver={"solves": search.log}, property="GAS")


def relations_ges(loop: Any, V: Poly, mu: Fraction) -> tuple[Fraction, Fraction] | None:
    """Exact ``c1 <= lambda_min(P) <= lambda_max(P) <= c2`` of a quadratic ``V = z^T P z`` in the state
    deviations alone with ``mu > 0`` (None otherwise): with ``V' <= -mu V``, GES."""
    from lyapcheck.models.engines.interval_region import quadratic_form

    if mu <= 0 or loop.angles:
        return None
    n = loop.n_states
    P = quadratic_form(loop.ring, V, n)
    return None if P is None else eigen_bounds(P)


def relations_certificate(loop: Any, field: Any, dens: Sequence[Any], found: Mapping[str, Any]) -> dict[str, Any]:
    """The certificate of a loop with functions (kind :data:`RELATIONS_KIND`): the recasting it lives on,
    ``V`` (its Gram matrix, as a polynomial and written with the functions), the flows' denominators with
    their proofs, ``mu`` (1/s) and the identity's multipliers by relation index; for GES ``c1``, ``c2``, ``k``."""
    from lyapcheck.models.classes.recast_classes import root_proofs_json, v_text
    from lyapcheck.models.engines.recast_sos import poly_to_json

    ring = loop.ring
    system = loop.system
    V = found["V"].poly(ring)
    return {"kind": RELATIONS_KIND, "variables": list(ring.names), "auxiliaries": system.definitions(),
            "angles": list(loop.angles), "shift": {k: str(v) for k, v in system.values.items()},
            "v_variables": [ring.names[i] for i in field.v_vars], "degree": found["degree"], "mu": str(found["mu"]),
            "gram_V": found["V"].to_json(), "V": poly_to_json(ring, V), "V_text": v_text(system, V),
            "recasting": {"roots": root_proofs_json(loop),
                          "denominators": [{"poly": poly_to_json(ring, d), "bound": str(c), "proof": cert.to_json(ring)}
                                           for d, c, cert in dens]},
            "decrease": found["decrease"].to_json(ring)}


def _certified_relations(loop: Any, field: Any, dens: Sequence[Any], name: str, found: dict[str, Any],
                         solver: dict[str, Any]) -> ConditionResult:
    from lyapcheck import exact

    cert = relations_certificate(loop, field, dens, found)
    if name == "quadratic":
        bounds = relations_ges(loop, found["V"].poly(loop.ring), found["mu"])
        if bounds is not None:
            c1, c2 = bounds
            cert.update({"c1": str(c1), "c2": str(c2), "k": str(exact.sqrt_upper(c2 / c1, 12))})
    prop, figures = relations_claim(cert)
    numbers: dict[str, Any] = {k: (v if isinstance(v, int) else float(v)) for k, v in figures.items()}
    numbers["relative_margin"] = found["margin"]
    return ConditionResult(name, "certified", relations_sentence(cert), numbers=numbers, certificate=cert,
                           solver=solver, property=prop)


def check_relations_certificate(name: str, c: Mapping[str, Any], loop: Any) -> tuple[bool, str]:
    """Re-check a certificate of :data:`RELATIONS_KIND` exactly on ``loop`` (the model text's recasting
    with its square roots' bounds re-proved): V's variables, the denominators' proofs, the identity
    (:func:`check_relations`) and a GES claim's ``c1``, ``c2``, ``k`` (the caller compares the sentence,
:func:`~lyapcheck.models.classes.lyapunov.relations_sentence`). A certificate these
    classes wrote before (:data:`OLD_RELATIONS_KIND`) is refused in one line."""
    from lyapcheck.exact import read_rational
    from lyapcheck.models.classes.recast_classes import check_denominator_proofs, common_denominator, v_text
    from lyapcheck.models.engines.recast_sos import ConditionCertificate, poly_from_json

    cert = c["certificate"]
    if cert.get("kind") == OLD_RELATIONS_KIND:
        return False, OLD_FORMAT
    if cert.get("kind") != RELATIONS_KIND:
        return False, f"a {name} certificate of a loop with functions has kind {RELATIONS_KIND!r}"
    ring = loop.ring
    if cert.get("angles") != list(loop.angles):
        return False, "the angles taken modulo 2 pi are not the loop's"
    names = cert["v_variables"]
    allowed = [ring.names[i] for i in loop.v_variables()]
    if not isinstance(names, list) or not set(names) <= set(allowed) or len(set(names)) != len(names):
        return False, "V's variables must be ones a Lyapunov function may use (no angle, root or non-smooth function)"
    if name == "quadratic" and (loop.angles or set(names) - {ring.names[i] for i in loop.coordinates()}):
        return False, "quadratic: V is a quadratic form in the states alone"
    ok, why, _ = check_denominator_proofs(loop, names, cert["recasting"]["denominators"])
    if not ok:
        return False, why
    N, D, _ = common_denominator(loop, names)
    field = relations_field(loop, names, N, D)
    V = GramPoly.from_json(cert["gram_V"], ring.nvars)
    degree = int(cert["degree"])
    if degree != 2 * max(sum(m) for m in V.basis) or (name == "quadratic" and degree != 2):
        return False, "the stated degree is not V's"
    v = V.poly(ring)
    if poly_from_json(ring, cert["V"], "V") != v or cert.get("V_text") != v_text(loop.system, v):
        return False, "V or V_text is not the Gram matrix's polynomial"
    mu = read_rational(cert["mu"])
    decrease = ConditionCertificate.from_json(ring, cert["decrease"], len(loop.relations))
    if decrease.rho is not None:
        return False, "a global decrease has no region multiplier"
    ok, why = check_relations(field, V, mu, decrease)
    if not ok:
        return False, why
    if any(key in cert for key in ("c1", "c2", "k")):
        from lyapcheck.models.engines.interval_region import quadratic_form
        from lyapcheck.sos.definiteness import is_positive_definite

        P = quadratic_form(ring, v, loop.n_states)
        if name != "quadratic" or mu <= 0 or loop.angles or P is None:
            return False, "GES is claimed for a quadratic V in the states alone with mu > 0"
        c1, c2, k = (read_rational(cert[key]) for key in ("c1", "c2", "k"))
        n = len(P)
        if not (c1 > 0 and is_positive_definite([[P[i][j] - c1 * int(i == j) for j in range(n)] for i in range(n)])
                and is_positive_definite([[c2 * int(i == j) - P[i][j] for j in range(n)] for i in range(n)])):
            return False, "c1 I < P < c2 I does not hold"
        if k < 0 or k * k < c2 / c1:
            return False, "k is below sqrt(c2/c1)"
    modulo = " (modulo 2 pi in the angles)" if loop.angles else ""
    return True, f"{why}{modulo}"
