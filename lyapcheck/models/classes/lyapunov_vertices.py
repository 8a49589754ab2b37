"""The vertex form of ``sos_gas`` over a box of parameters: ``V(z, u)`` affine in the
box's normalized parameters ``u in [-1, 1]^p``, proved at the box's vertices.

Where the field is multi-affine in ``u`` (a gain that multiplies a state, as in a PID loop), take
``V = V_0(z) + sum_j u_j V_j(z)`` with each ``V_j`` free of the states whose right-hand side holds
``u_j``: then ``-grad V . g - mu V D`` is multi-affine in ``u`` too, and both are positive on the whole
box when they are at every vertex (:func:`lyapcheck.sos.certificates.check_lyapunov_vertices`, which
checks the multi-affinity itself). The program is a point's program once per vertex, coupled through
``V_0`` and the free coefficients of the ``V_j``: the box form of :mod:`lyapcheck.models.classes.lyapunov`
instead needs one remainder over the states and the parameters together, with box multipliers. On
issue 45's PID loop (3 states, 2 gains) that form is infeasible at degree 4 and beyond the size limits
from degree 6, while a single point already needs a ``V`` of degree 8, whose exact cancellations depend
on the gains (``V`` common to the box, ``V_j = 0``, is infeasible even on a box 5 % wide).

The certificate is a ``lyapunov`` certificate (same claim, sentence and figures, GAS) with
``form = "vertices"``: ``V_scaled`` (the exact ``V(z, u)`` in the scaled states and the box's
normalized parameters), and per vertex, in :func:`~lyapcheck.sos.certificates.box_vertices` order, the
Gram matrix of ``V`` there (``gram_V_vertices``) and of ``sigma`` (``gram_sigma_vertices``).
"""

from __future__ import annotations

from fractions import Fraction
from typing import TYPE_CHECKING, Any, Final, Sequence

from lyapcheck.models.engines.search import ParameterValues, Search, literal, one, param
from lyapcheck.models.loop.field import StateField
from lyapcheck.sos import bases
from lyapcheck.sos.certificates import (GramPoly, at_vertex, box_vertices, check_lyapunov_vertices, lie_derivative,
                                       multi_affine)
from lyapcheck.sos.polynomials import Monomial, Poly, Ring, monomials, to_fmpq
from lyapcheck.sos.structure import Gram, Identity, Scalar, Structure, Term

if TYPE_CHECKING:  # pragma: no cover
    from lyapcheck.sos.program import Solution

#: the most vertices (2^p for p box coordinates) the vertex form takes: one remainder each
MAX_VERTICES: Final = 16


def applies(field: StateField) -> bool:
    """The field has a box of parameters and no disturbance among its box coordinates (a disturbed
    loop keeps the forms it had), at most :data:`MAX_VERTICES` vertices, and ``g`` and ``D``
    multi-affine in them."""
    return 0 < field.p and not field.disturbances and 2 ** field.p <= MAX_VERTICES and multi_affine(field.ring, [*field.g, field.D], field.n)


def vertex_fields(field: StateField) -> list[tuple[tuple[Poly, ...], Poly]]:
    """``(g, D)`` at each vertex of the box, in :func:`box_vertices` order."""
    ring, n = field.ring, field.n
    return [(tuple(at_vertex(ring, gi, n, v) for gi in field.g), at_vertex(ring, field.D, n, v))
            for v in box_vertices(ring, n)]


def moving_monomials(field: StateField, products: set[Monomial]) -> list[list[Monomial]]:
    """For each box coordinate ``u_j``, the monomials of ``V_j`` (``V``'s part proportional to ``u_j``):
    those of ``products`` free of every state whose ``g_i`` holds ``u_j`` (then ``grad V_j . g`` has no
    ``u_j^2``). None at all where ``D`` holds a box coordinate (``mu V D`` would have ``u_j^2``)."""
    ring, n = field.ring, field.n
    if any(any(m[n:]) for m in ring.support(field.D)):
        return [[] for _ in range(field.p)]
    out = []
    for j in range(field.p):
        moved = {i for i, gi in enumerate(field.g) if any(m[n + j] for m in ring.support(gi))}
        out.append(sorted(m for m in products if not any(m[i] for i in moved)))
    return out


def vertex_program(field: StateField, degree: int, drop: frozenset[tuple[str, Monomial]] = frozenset()
                   ) -> Structure | str:
    """The program of ``V = V_0 + sum_j u_j V_j`` of this degree: a Gram ``V`` (``V_0``), free scalars
    ``c<j>_<k>`` (the coefficients of ``V_j``), and per vertex ``k`` a Gram ``P<k>`` (``V`` there) and a
    remainder ``W<k>`` (``-grad V . g - mu V D`` there); or why there is none (a size limit, named, or no
    strict certificate of the form). ``drop``: ``(gram, monomial)`` pairs left out (facial reduction)."""
    from lyapcheck.models.classes import lyapunov as L
    from lyapcheck.models.engines.reasons import size_limit

    ring, n, nv = field.ring, field.n, field.ring.nvars
    vertices = vertex_fields(field)
    signs = box_vertices(ring, n)
    generators = bases.sign_symmetries(nv, [(ring.support(gi), i) for g, _ in vertices for i, gi in enumerate(g)]
                                       + [(ring.support(D), None) for _, D in vertices])
    z_all = [m for m in monomials(nv, 1, degree // 2) if not any(m[n:])]
    z_v = [m for m in z_all if ("V", m) not in drop]
    if not bases.has_pure_powers(z_v, range(n)):
        return ("no strict certificate of this form exists (V's basis, reduced to the face the solver found, "
                "keeps no pure power of some state)")
    v_blocks = bases.character_blocks(z_v, generators)
    products = L.gram_products(z_v, v_blocks)
    moving = moving_monomials(field, products)
    scalars = [Scalar(f"c{j}_{a}") for j, ms in enumerate(moving) for a in range(len(ms))]
    grams = [Gram("V", tuple(z_v), tuple(map(tuple, v_blocks)))]
    identities = []
    for k, ((g, D), sign) in enumerate(zip(vertices, signs)):
        target = set(products)
        terms = [Term(param(f"g{i}v{k}", ring.support(gi)), "V", derivative=i) for i, gi in enumerate(g)]
        terms.append(Term(param(f"muDv{k}", ring.support(D)), "V"))
        positive = [Term(one(ring), "V")]
        for j, ms in enumerate(moving):
            for a, m in enumerate(ms):
                support = decrease_support(ring, g, D, m)
                target |= set(support)
                terms.append(Term(param(f"d{j}_{a}v{k}", support), f"c{j}_{a}"))
                positive.append(Term(literal(ring, {m: sign[j]}), f"c{j}_{a}"))
        for i, gi in enumerate(g):
            derived = {m[:i] + (m[i] - 1,) + m[i + 1:] for m in products if m[i] > 0}
            target |= {tuple(a + b for a, b in zip(m, s)) for m in derived for s in ring.support(gi)}
        target |= {tuple(a + b for a, b in zip(m, s)) for m in products for s in ring.support(D)}
        if len(target) > L.TARGET_LIMIT:
            return size_limit(len(target), "monomials in one polynomial identity", L.TARGET_LIMIT, "TARGET_LIMIT")
        z_w = [m for m in bases.sos_basis(nv, target) if (f"W{k}", m) not in drop]
        z_p = [m for m in z_all if (f"P{k}", m) not in drop]
        if max(len(z_w), len(z_v)) > L.MAX_GRAM_ROWS:
            return size_limit(max(len(z_w), len(z_v)), "monomials per sum-of-squares matrix", L.MAX_GRAM_ROWS,
                              "MAX_GRAM_ROWS")
        if not z_w or not bases.has_pure_powers(z_w, range(n)) or not bases.has_pure_powers(z_p, range(n)):
            return ("no strict certificate of this form exists (the Newton polytope of -V' at a vertex leaves no "
                    "pure power of every state in its basis)")
        grams.append(Gram(f"P{k}", tuple(z_p), tuple(map(tuple, bases.character_blocks(z_p, generators)))))
        grams.append(Gram(f"W{k}", tuple(z_w), tuple(map(tuple, bases.character_blocks(z_w, generators)))))
        terms.append(Term(one(ring, -1), f"W{k}"))
        positive.append(Term(one(ring, -1), f"P{k}"))
        identities.append(Identity(f"lyapunov{k}", tuple(terms), None, f"W{k}"))
        identities.append(Identity(f"positive{k}", tuple(positive), None, f"P{k}"))
    structure = Structure(nvars=nv, grams=tuple(grams), scalars=tuple(scalars), identities=tuple(identities),
                          objective=("max_margin",), trace_one=("V",))
    if L.affordable(structure) is None:
        return size_limit(f"{structure.cost():.1e}", "work units of the program", f"{L.BLOCK_COST_LIMIT:.1e}",
                          "BLOCK_COST_LIMIT")
    return structure


def decrease_poly(ring: Ring, g: Sequence[Poly], D: Poly, m: Monomial, mu: Fraction) -> Poly:
    """``-grad(z^m) . g - mu z^m D``: what the coefficient of ``V``'s monomial ``m`` multiplies in the
    identity at a vertex."""
    zm = ring.monomial(m)
    return -lie_derivative(ring, zm, g) - zm * D * to_fmpq(mu)


def decrease_support(ring: Ring, g: Sequence[Poly], D: Poly, m: Monomial) -> list[Monomial]:
    """The monomials :func:`decrease_poly` may have, whatever ``mu``."""
    return sorted(set(ring.support(decrease_poly(ring, g, D, m, Fraction(0)))) | {
        tuple(a + b for a, b in zip(m, s)) for s in ring.support(D)})


def vertex_values(field: StateField, structure: Structure, mu: Fraction) -> ParameterValues:
    """The program's parameters at decay rate ``mu``: ``-g`` and ``-mu D`` at each vertex, and what each
    free coefficient of ``V_j`` multiplies there."""
    values = ParameterValues()
    ring = field.ring
    moving = moving_of(structure, field.p)
    for k, ((g, D), sign) in enumerate(zip(vertex_fields(field), box_vertices(ring, field.n))):
        for i, gi in enumerate(g):
            values.set_poly(ring, f"g{i}v{k}", -gi, ring.support(gi))
        values.set_poly(ring, f"muDv{k}", D * to_fmpq(-mu), ring.support(D))
        for j, ms in enumerate(moving):
            for a, m in enumerate(ms):
                values.set_poly(ring, f"d{j}_{a}v{k}", decrease_poly(ring, g, D, m, mu) * sign[j],
                                decrease_support(ring, g, D, m))
    return values


def moving_of(structure: Structure, p: int) -> list[list[Monomial]]:
    """The monomials of each ``V_j`` in ``structure``, from its scalars' terms in the first positivity
    identity."""
    out: list[list[Monomial]] = [[] for _ in range(p)]
    ident = next(i for i in structure.identities if i.name == "positive0")
    for term in ident.terms:
        if term.decision.startswith("c"):
            j = int(term.decision[1:].split("_")[0])
            out[j].append(term.coefficients.support[0])
    return out


def exact_v(field: StateField, structure: Structure, point: Any) -> Poly:
    """``V = V_0 + sum_j u_j V_j`` exactly, from a rounded point."""
    ring, n = field.ring, field.n
    V = GramPoly.of(structure.gram("V").basis, point.grams["V"]).poly(ring)
    for j, ms in enumerate(moving_of(structure, field.p)):
        vj = ring.from_terms({m: point.scalars[f"c{j}_{a}"] for a, m in enumerate(ms)})
        V += vj * ring.gens()[n + j]
    return V


def vertex_attempt(field: StateField, structure: Structure, mu: Fraction, search: Search
                   ) -> tuple[dict[str, Any] | None, Solution]:
    """One solve at decay rate ``mu``; the exact certificate if it passes
    :func:`~lyapcheck.sos.certificates.check_lyapunov_vertices`."""
    from lyapcheck.models.classes.lyapunov import exact_try

    point, solution = exact_try(structure, vertex_values(field, structure, mu), search)
    if point is None:
        return None, solution
    V = exact_v(field, structure, point)
    count = len(box_vertices(field.ring, field.n))
    positive = [GramPoly.of(structure.gram(f"P{k}").basis, point.grams[f"P{k}"]) for k in range(count)]
    sigmas = [GramPoly.of(structure.gram(f"W{k}").basis, point.grams[f"W{k}"]) for k in range(count)]
    ok, _ = check_lyapunov_vertices(field.ring, field.g, field.D, V, positive, sigmas, mu)
    if not ok:
        return None, solution
    return {"V": None, "V_poly": V, "W": None, "positive": positive, "vertices": sigmas, "mu": mu,
            "margin": solution.scalars["t"], "box": []}, solution


def certificate_json(stated: dict[str, Any], field: StateField, found: dict[str, Any]) -> dict[str, Any]:
    """The certificate of a vertex-form ``found`` (``stated``: ``V`` in the declared states and the box's
    parameters, :func:`lyapcheck.models.classes.lyapunov.stated_v`)."""
    from lyapcheck.models.classes.lyapunov import terms_json

    return {"kind": "lyapunov", "form": "vertices", "degree": found["degree"], "mu_scaled": str(found["mu"]),
            "V": stated, "V_scaled": terms_json(field.ring, found["V_poly"]),
            "gram_V_vertices": [p.to_json() for p in found["positive"]],
            "gram_sigma_vertices": [w.to_json() for w in found["vertices"]]}


def search_vertices(field: StateField, degree: int, search: Search) -> tuple[dict[str, Any] | None, str]:
    """A vertex certificate with ``V`` of this degree (and its best decay rate), or None and why not,
    with the facial reduction of :func:`lyapcheck.models.classes.lyapunov.search_degree`."""
    from lyapcheck.models.classes import lyapunov as L

    label = f"degree {degree} (affine in the parameters, at the box's {2 ** field.p} vertices)"
    drop: frozenset[tuple[str, Monomial]] = frozenset()
    why = "none found"
    for _ in range(L.LYAPUNOV_FACIAL_ROUNDS + 1):
        structure = vertex_program(field, degree, drop)
        if isinstance(structure, str):
            return None, f"{label}: {structure}" + (f" (after facial reduction, where {why})" if drop else "")
        found, solution = vertex_attempt(field, structure, Fraction(0), search)
        if found is not None:
            break
        why = L.failure(solution, exact_tried=solution.usable and solution.scalars.get("t", -1.0) >= -L.EXACT_TRY_MARGIN)
        vanishing = frozenset((g.name, m) for g in structure.grams for m in L.vanishing_monomials(g, solution))
        if not vanishing:
            vanishing = frozenset((g.name, m) for g in structure.grams for m in L.kernel_monomials(g, solution))
        if not vanishing:
            return None, f"{label}: {why}"
        drop = drop | vanishing
    else:
        return None, f"{label}: {why} (after {L.LYAPUNOV_FACIAL_ROUNDS} rounds of facial reduction)"
    solved = structure
    found = L.best_decay_rate(lambda mu: vertex_attempt(field, solved, mu, search)[0], found)
    found["degree"] = degree
    found["param_degree"] = 1
    return found, f"{label}: found"
