"""``sos_gas`` in the cascade form: one ISS-Lyapunov function per subsystem of an acyclic network (issue 43).

Where the interaction graph's strongly connected components (the subsystems, :mod:`vector_lyapunov`'s
groups) are at least two, their condensation is acyclic: ordered topologically, ``I_1, ..., I_m``, the
equations of group ``i`` read only its own states ``x_i`` and states ``u_i`` of earlier groups (its
inputs). No comparison system (small gain) is needed then: in the scaled coordinates of
:mod:`lyapcheck.models.loop.field` (``z' = g / D``, ``D`` a positive constant), per group

* ``V_i = z_Vi^T Q_Vi z_Vi`` over monomials of ``x_i`` alone, no constant, every ``x_ij`` itself in the
  basis and ``Q_Vi > 0``: ``V_i - eps_i |x_i|^2`` is SOS (``eps_i`` the smallest eigenvalue), so ``V_i``
  is positive definite and radially unbounded, ``V_i(0) = 0``;
* ``W_i = sum_j c_ij Phi_ij(x_i)^2`` with every ``c_ij > 0`` and ``Phi_i`` a triangular polynomial
  automorphism of the group's states fixing 0 (component ``j``: ``x_(v_j) + h_j`` of the later components'
  states, :func:`check_coordinates`), so ``W_i >= min_j c_ij |Phi_i(x_i)|^2``, positive definite and
  radially unbounded (``Phi_i``'s inverse is polynomial): bounded below by a class-K-infinity function of
  ``|x_i|``. With ``Phi_i`` the identity this is ``W_i - eps_i |x_i|^2`` SOS; the search also tries the
  coordinates of the group's slow manifold (:func:`coordinates`): on the cubic-drag platoon's vehicle no
  ``W_i >= eps |x_i|^2`` has a certificate of this form (on the weighted face where the spacing ``e ~ w^3``
  the identity's top part must be PSD, and ``-V_i'`` grows there like ``w^4`` only), while
  ``W_i = c_1 (e - (kd w + w^3) / kp)^2 + c_2 w^2`` does;
* ``R_i = z_Ri^T Q_Ri z_Ri`` over monomials of ``u_i`` alone of degree at least 1, ``Q_Ri >= 0``: SOS
  with ``R_i(0) = 0`` (``R_i = 0`` for a group without inputs, the first one);
* the identity, exactly in rationals, ``(R_i - W_i) D - grad V_i . g = sigma_i`` with
  ``sigma_i = z_i^T S_i z_i``, ``S_i >= 0`` (the dissipation form of ISS).

Then ``V_i' = grad V_i . g / D <= -W_i(x_i) + R_i(u_i)`` along every trajectory of the whole network:
``V_i`` is an ISS-Lyapunov function of group ``i`` with respect to its inputs (Sontag & Wang,
"On characterizations of the input-to-state stability property", Systems & Control Letters 24, 1995:
the dissipation characterization: ``W_i`` bounded below by a class-K-infinity function of ``|x_i|``,
``R_i`` above by a class-K function of ``|u_i|``), group 1 (no input) is GAS, and a cascade of ISS
systems driven by a GAS system is GAS (Sontag, "Smooth stabilization implies coprime factorization",
IEEE TAC 34, 1989; by induction along the order: each group's ISS estimate bounds its states by its
inputs', which converge, so no solution escapes and every group converges). The equilibrium of the whole network is globally
asymptotically stable. The claim is GAS without a rate: the ISS estimates give no uniform exponential
one (on the platoon none exists with polynomial ``V_i``: :mod:`vector_lyapunov`'s docstring).

The search: one small SOS program per group, in the group's states and its inputs only, maximizing
the smallest eigenvalue of every Gram matrix and every ``c_ij`` with ``trace Q_Vi = 1``, in each of the
group's coordinates for ``W_i`` and with ``V_i`` of each degree of :data:`CASCADE_DEGREES` in turn (each
group its own) and facial reduction (:func:`search_group`); groups whose equations are the same
polynomials up to renaming (:func:`vector_lyapunov.subsystem_shape`) share one solve. Each group's
certificate is checked exactly on its own ring, then the whole certificate on the network's
(:func:`check_cascade`), and ``verify`` re-checks it from the document alone. The work grows linearly
with the number of groups (and not at all with copies of one group).

It is a form of ``sos_gas`` (:func:`fallback`), tried once per run where the dense and clique forms of
a degree found nothing and one reached a size limit, right after the vector form.
"""

from __future__ import annotations

import heapq
from fractions import Fraction
from typing import TYPE_CHECKING, Any, Final, Mapping, Sequence

from lyapcheck.models.engines.search import ParameterValues, Search, literal, one
from lyapcheck.models.loop.field import StateField
from lyapcheck.sos import bases
from lyapcheck.sos.certificates import GramPoly, lie_derivative
from lyapcheck.sos.polynomials import Monomial, Poly, Ring, monomials
from lyapcheck.sos.structure import Gram, Identity, Scalar, Structure, Term

if TYPE_CHECKING:  # pragma: no cover
    from lyapcheck.models.loop.field import ScaledField
    from lyapcheck.results import ConditionResult
    from lyapcheck.sos.program import Solution

#: the certificate kind
KIND: Final = "lyapunov_cascade"
#: the degrees of each V_i tried, in turn (each group stops at its first certified degree); not 6: on
#: lyznet-10d (not GAS) its 4-state group's sextic programs cost enough to move the cheaper cones ahead of
#: degree 8 (lyapunov.cones_first) and end sos_gas inconclusive where it was not_certified
CASCADE_DEGREES: Final = (2, 4)
#: the largest program of one group solved (:meth:`~lyapcheck.sos.structure.Structure.cost`): the platoon's
#: follower (two states, one input) with a quartic V_i costs about 1e5; the dense form's limit (2e9) is
#: about 15 s a solve
CASCADE_COST_LIMIT: Final = 2_000_000_000
#: what the detail line of the cascade form starts with (so that it is tried once per run)
LABEL: Final = "cascade of ISS subsystems"


# -- the groups, in a topological order ---------------------------------------------------------------

def cascade_groups(field: StateField) -> tuple[list[tuple[int, ...]], list[list[int]]] | None:
    """The strongly connected components of the field's interaction graph in a topological order (each
    group after every group it reads; ties by the smallest state) and, per group, the states of earlier
    groups its equations read (its inputs, sorted); None where there are fewer than two components or
    one has more than :data:`vector_lyapunov.MAX_GROUP_STATES` states."""
    from lyapcheck.models.classes.vector_lyapunov import MAX_GROUP_STATES, couplings, strong_components

    n = field.n
    reads = couplings(field)
    components = strong_components(n, reads)
    if len(components) < 2 or any(len(c) > MAX_GROUP_STATES for c in components):
        return None
    owner = {s: k for k, c in enumerate(components) for s in c}
    needs = [{owner[j] for s in c for j in reads[s]} - {k} for k, c in enumerate(components)]
    ready = [(components[k][0], k) for k in range(len(components)) if not needs[k]]
    heapq.heapify(ready)
    order: list[int] = []
    while ready:  # Kahn's algorithm: the condensation of the components is acyclic
        _, k = heapq.heappop(ready)
        order.append(k)
        for j in range(len(components)):
            if k in needs[j]:
                needs[j].discard(k)
                if not needs[j]:
                    heapq.heappush(ready, (components[j][0], j))
    groups = [components[k] for k in order]
    inputs = [sorted({j for s in g for j in reads[s]} - set(g)) for g in groups]
    return groups, inputs


def group_field(field: StateField, group: Sequence[int], inputs: Sequence[int]) -> StateField:
    """Group ``group``'s equations in the ring of its states then its inputs (nothing else: they read
    nothing else), ``D`` likewise (a constant)."""
    ring = field.ring
    sub = Ring(tuple(ring.names[i] for i in (*group, *inputs)))
    return StateField(ring=sub, g=tuple(ring.restrict(field.g[i], sub) for i in group), D=ring.restrict(field.D, sub))


# -- one group's program ------------------------------------------------------------------------------

def coordinates(sub: StateField, k: int) -> list[list[tuple[int, Poly]]]:
    """The coordinates ``Phi`` in which a group's ``W = sum_j c_j Phi_j^2`` is tried, in turn (``sub``: the
    group's ``k`` states first, then its inputs): each a list of ``(state, Phi_j)`` in a triangular order
    (:func:`check_coordinates`). First, where one state's equation at zero input is ``c x_t + h`` with ``c``
    a constant, ``h`` nonlinear and free of ``x_t``, the slow manifold's coordinate ``x_t + h / c`` (the
    others themselves): on the platoon's vehicle (``w' = kp e - kd w - w^3`` at zero input) ``e - (kd w +
    w^3) / kp``, which vanishes where the drag balances the spacing, so that ``W`` needs no ``e^2`` there,
    where ``-V'`` grows only like ``e^(4/3)``; then the states themselves (``W >= min c |x|^2``)."""
    ring = sub.ring
    gens = ring.gens()
    zero = {ring.names[i]: Fraction(0) for i in range(k, ring.nvars)}
    identity = [(i, gens[i]) for i in range(k)]
    out: list[list[tuple[int, Poly]]] = []
    for s in range(k):
        g0 = ring.substitute(sub.g[s], zero)
        terms = ring.terms(g0)
        for t in range(k):
            if t == s:
                continue
            with_t = [m for m in terms if m[t] > 0]
            if with_t != [_unit(t, ring.nvars)]:
                continue  # x_t enters other than once, linearly, with a constant coefficient
            c = terms[with_t[0]]
            h = g0 - gens[t] * ring.constant(c)
            if h == ring.zero() or max(sum(m) for m in ring.terms(h)) < 2:
                continue  # a linear h: the states themselves do as well
            phi = gens[t] + h * ring.constant(1 / c)
            out.append([(t, phi)] + [(i, gens[i]) for i in range(k) if i != t])
            break
        if out:
            break
    return out + [identity]


def group_program(sub: StateField, k: int, degree: int, phi: Sequence[tuple[int, Poly]],
                  drop: frozenset[tuple[str, Monomial]] = frozenset()) -> Structure | str:
    """The program of one group (its ``k`` states first in ``sub``'s ring, then its inputs): ``V`` of this
    degree, ``W = sum_j c_j Phi_j^2`` (``c_j`` scalars, ``phi`` the coordinates), ``U`` (the certificate's
    ``R_i``) over the inputs' monomials and the remainder ``R`` over the identity's Newton basis (less
    ``drop``); or why there is none (a size limit, named)."""
    from lyapcheck.models.classes.lyapunov import field_degree, gram_products, symmetry, widen_by_derivative
    from lyapcheck.models.engines.reasons import size_limit

    ring, nv = sub.ring, sub.ring.nvars
    generators = symmetry(sub)
    z_v = [m for m in monomials(nv, 1, degree // 2) if not any(m[k:]) and ("V", m) not in drop]
    if any(_unit(i, nv) not in z_v for i in range(k)):
        return ("no strict certificate of this form exists (V's basis, reduced to the face the solver found, keeps "
                "no state itself)")
    v_blocks = bases.character_blocks(z_v, generators)
    products = gram_products(z_v, v_blocks)
    target: set[Monomial] = set()
    widen_by_derivative(target, ring, products, enumerate(sub.g))
    squares = [p * p * sub.D for _, p in phi]
    for sq in squares:
        target |= set(ring.support(sq))
    grams = [Gram("V", tuple(z_v), tuple(map(tuple, v_blocks)))]
    scalars = [Scalar(f"c{j}", "margin") for j in range(len(phi))]
    terms = [Term(literal(ring, ring.terms(-gi)), "V", derivative=i) for i, gi in enumerate(sub.g)]
    terms += [Term(literal(ring, ring.terms(-sq)), f"c{j}") for j, sq in enumerate(squares)]
    if nv > k:
        # the inputs' gain R_i(u_i), up to the identity's half degree times the field's degree: where the
        # group rests at x*(u) for a constant input, V_i' = 0 and R_i(u) must dominate sigma_i(x*(u), u),
        # whose terms grow like the states of x*(u), as fast as u^(field's degree) (the platoon's spacing
        # rests at e = w^3 / kp): with a lower degree no strictly positive sigma_i exists
        half = max(sum(m) for m in target) // 2 * field_degree(sub)
        z_u = [m for m in monomials(nv, 1, max(half, 1)) if not any(m[:k]) and ("U", m) not in drop]
        if z_u:
            u_blocks = bases.character_blocks(z_u, generators)
            target |= {tuple(a + b for a, b in zip(m, s)) for m in gram_products(z_u, u_blocks)
                       for s in ring.support(sub.D)}
            grams.append(Gram("U", tuple(z_u), tuple(map(tuple, u_blocks))))
            terms.append(Term(literal(ring, ring.terms(sub.D)), "U"))
    z_r = [m for m in bases.sos_basis(nv, target) if ("R", m) not in drop]
    if not z_r:
        return "no strict certificate of this form exists (the remainder's basis is empty)"
    grams.append(Gram("R", tuple(z_r), tuple(map(tuple, bases.character_blocks(z_r, generators)))))
    terms.append(Term(one(ring, -1), "R"))
    structure = Structure(nvars=nv, grams=tuple(grams), scalars=tuple(scalars),
                          identities=(Identity("dissipation", tuple(terms), None, "R"),),
                          objective=("max_margin",), trace_one=("V",))
    if structure.cost() > CASCADE_COST_LIMIT:
        return size_limit(f"{structure.cost():.1e}", "work units of a subsystem's program", f"{CASCADE_COST_LIMIT:.1e}",
                          "CASCADE_COST_LIMIT")
    return structure


def group_attempt(sub: StateField, k: int, phi: Sequence[tuple[int, Poly]], structure: Structure, search: Search
                  ) -> tuple[dict[str, Any] | None, "Solution"]:
    """One solve of a group's program; its exact parts (on the group's ring) if they pass :func:`check_group`."""
    from lyapcheck.models.classes.lyapunov import exact_try

    point, solution = exact_try(structure, ParameterValues(), search)
    if point is None:
        return None, solution
    parts = {name: GramPoly.of(structure.gram(name).basis, point.grams[name])
             for name in ("V", "U", "R") if any(g.name == name for g in structure.grams)}
    V, R, sigma = parts["V"], parts.get("U"), parts["R"]
    weights = [Fraction(point.scalars[f"c{j}"]) for j in range(len(phi))]
    ok, _ = check_group(sub.ring, sub.g, sub.D, range(k), range(k, sub.ring.nvars), V, phi, weights, R, sigma, 1)
    return ({"V": V, "phi": list(phi), "c": weights, "R": R, "sigma": sigma} if ok else None), solution


def search_group(sub: StateField, k: int, search: Search) -> tuple[dict[str, Any] | None, str]:
    """A group's certificate (in each of its :func:`coordinates` in turn, its ``V`` of each of
    :data:`CASCADE_DEGREES`), or None and why not; at each degree, while the exact check refuses, the
    facial reduction of ``V``, ``R_i`` and the remainder (their vanishing rows or kernels' supports left out,
    at most :data:`~lyapcheck.models.classes.lyapunov.LYAPUNOV_FACIAL_ROUNDS` times, as the dense form does:
    on the platoon the spacing's quartic term of ``V_i`` must vanish)."""
    from lyapcheck.models.classes.lyapunov import LYAPUNOV_FACIAL_ROUNDS, failure, gram_faces

    whys = []
    choices = coordinates(sub, k)
    for number, phi in enumerate(choices):
        # (the last choice is always the states themselves; an earlier one, the slow manifold's)
        words = "" if len(choices) == 1 else " (W in the states)" if number == len(choices) - 1 \
            else " (W in the slow manifold's coordinates)"
        for degree in CASCADE_DEGREES:
            drop: frozenset[tuple[str, Monomial]] = frozenset()
            why = "none found"
            for _ in range(LYAPUNOV_FACIAL_ROUNDS + 1):
                search.budget.check()
                structure = group_program(sub, k, degree, phi, drop)
                if isinstance(structure, str):
                    why = structure + (f" (after facial reduction, where {why})" if drop else "")
                    break
                found, solution = group_attempt(sub, k, phi, structure, search)
                if found is not None:
                    return {**found, "degree": degree, "margin": solution.scalars.get("t")}, "found"
                why = failure(solution)
                vanishing = gram_faces(structure.grams, solution)
                if not vanishing:
                    break
                drop = drop | vanishing
            whys.append(f"degree {degree}{words}: {why}")
    return None, "; ".join(whys)


def lift(P: GramPoly | None, where: Sequence[int], nv: int) -> GramPoly | None:
    """A Gram form of a group's ring (its variables at ``where`` in the network's ring) over the network's."""
    from lyapcheck.models.classes.vector_lyapunov import embed_gram

    return None if P is None else embed_gram(P, where, nv)


def lift_poly(sub: Ring, p: Poly, where: Sequence[int], ring: Ring) -> Poly:
    """A polynomial of a group's ring over the network's (its variables at ``where``)."""
    def moved(m: Monomial) -> Monomial:
        e = [0] * ring.nvars
        for k, i in enumerate(where):
            e[i] = m[k]
        return tuple(e)

    return ring.from_terms({moved(m): c for m, c in sub.terms(p).items()})


def search_cascade(field: StateField, search: Search) -> tuple[dict[str, Any] | None, str]:
    """A cascade certificate (the module's docstring), or None and why not."""
    from lyapcheck.models.classes.vector_lyapunov import subsystem_shape

    if field.p or field.disturbances:
        return None, f"{LABEL}: not for a field with box coordinates"
    found_groups = cascade_groups(field)
    if found_groups is None:
        return None, (f"{LABEL}: no cascade (the interaction graph's strongly connected components are fewer than "
                      "two, or one has more states than MAX_GROUP_STATES)")
    groups, inputs = found_groups
    label = f"{LABEL} ({len(groups)} subsystems)"
    ring, nv = field.ring, field.ring.nvars
    solved: dict[tuple[Any, ...], dict[str, Any]] = {}
    parts: list[dict[str, Any]] = []
    for group, read in zip(groups, inputs):
        sub = group_field(field, group, read)
        key = (len(group), subsystem_shape(sub))
        if key not in solved:
            local, why = search_group(sub, len(group), search.over(sub.ring))
            if local is None:
                return None, (f"{label}: no ISS-Lyapunov function for the subsystem of "
                              f"{', '.join(sub.ring.names[:len(group)])} with inputs "
                              f"{', '.join(sub.ring.names[len(group):]) or 'none'} ({why})")
            solved[key] = local
        local = solved[key]
        where = [*group, *read]
        phi = [(where[i], lift_poly(sub.ring, p, where, ring)) for i, p in local["phi"]]
        parts.append({"V": lift(local["V"], where, nv), "phi": phi, "c": local["c"],
                      "R": lift(local["R"], where, nv), "sigma": lift(local["sigma"], where, nv),
                      "degree": local["degree"], "margin": local["margin"]})
    ok, why = check_cascade(ring, field.g, field.D, groups, [p["V"] for p in parts], [p["phi"] for p in parts],
                            [p["c"] for p in parts], [p["R"] for p in parts], [p["sigma"] for p in parts])
    if not ok:  # (each group's identity passed on its own ring: the lifted ones are the same polynomials)
        return None, f"{label}: the whole certificate failed its exact check ({why})"
    return {"groups": groups, "parts": parts, "solves": len(solved)}, f"{label}: found ({len(solved)} distinct solved)"


def fallback(scaled: "ScaledField", field: StateField, name: str, search: Search, detail: list[str]
             ) -> "ConditionResult | None":
    """``sos_gas``'s cascade form, as :func:`vector_lyapunov.fallback` (and right after it): once per run,
    where a dense or clique form reached a size limit; its line joins ``detail``; the certified result
    or None."""
    from lyapcheck.models.engines import reasons

    if field.p or field.disturbances or any(line.startswith(LABEL) for line in detail) \
            or not reasons.size_limits(detail) or cascade_groups(field) is None:
        return None
    found, why = search_cascade(field, search)
    detail.append(why)
    return None if found is None else certified(scaled, field, name, found, {"solves": search.log})


# -- the exact check ----------------------------------------------------------------------------------

def _unit(i: int, nv: int) -> Monomial:
    return tuple(int(j == i) for j in range(nv))


def check_coordinates(ring: Ring, group: Sequence[int], phi: Sequence[tuple[int, Poly]]) -> tuple[bool, str]:
    """``phi`` is a triangular polynomial automorphism of the group's states fixing 0: one component per
    state ``v_j`` (each state once), ``Phi_j = x_(v_j) + h_j`` with ``h_j`` free of a constant and a
    polynomial in the states of the later components only. Its inverse is polynomial too (solve from the
    last component up), so ``|Phi(x)|`` is positive definite and radially unbounded in ``x``."""
    if sorted(v for v, _ in phi) != sorted(group):
        return False, "the coordinates of W must have one component per state of the group"
    for j, (v, p) in enumerate(phi):
        later = {w for w, _ in phi[j + 1:]}
        h = p - ring.gens()[v]
        for m in ring.support(h):
            if sum(m) == 0 or any(m[i] and i not in later for i in range(ring.nvars)):
                return False, (f"the coordinate of W for {ring.names[v]} is not {ring.names[v]} plus a polynomial "
                               "of the later coordinates' states without a constant (not triangular)")
    return True, "triangular"


def check_group(ring: Ring, g: Sequence[Poly], D: Poly, group: Sequence[int], inputs: Sequence[int],
                V: GramPoly, phi: Sequence[tuple[int, Poly]], weights: Sequence[Fraction], R: GramPoly | None,
                sigma: GramPoly, k: int) -> tuple[bool, str]:
    """One group's part of the certificate, exactly (``g``: the field of ``ring``'s first ``len(g)``
    variables; ``k``: the group's number, 1-based, for the words): ``V`` over the group's states with no
    constant, each state itself in its basis and ``Q_V > 0``; ``W = sum_j c_j Phi_j^2`` with every
    ``c_j > 0`` and ``Phi`` triangular (:func:`check_coordinates`); ``R`` over the states of ``inputs``
    alone (the earlier groups') with no constant and ``Q_R >= 0``, or absent; ``S >= 0`` and
    ``(R - W) D - grad V . g = z^T S z``."""
    from lyapcheck.sos.definiteness import is_positive_semidefinite

    nv = ring.nvars
    others = [i for i in range(nv) if i not in group]
    if not V.basis or any(m[i] for m in V.basis for i in others) or any(sum(m) == 0 for m in V.basis):
        return False, f"V_{k} may depend on the states of its group only, with no constant"
    if any(_unit(i, nv) not in V.basis for i in group):
        return False, f"V_{k}'s basis must hold each state of its group (so that V_{k} >= eps |x_{k}|^2)"
    if not V.positive_definite():
        return False, f"Q_V{k} is not positive definite (exact)"
    ok, why = check_coordinates(ring, group, phi)
    if not ok:
        return False, f"group {k}: {why}"
    if len(weights) != len(phi) or any(c <= 0 for c in weights):
        return False, f"W_{k}'s weights must be positive, one per coordinate"
    if R is not None:
        if any(sum(m) == 0 for m in R.basis) or any(m[i] for m in R.basis for i in range(nv) if i not in inputs):
            return False, (f"R_{k} may depend on the states of earlier groups only, with no constant (R_{k}(0) = 0; "
                           "the first group has no inputs)")
        if not is_positive_semidefinite(R.Q):
            return False, f"Q_R{k} is not positive semidefinite (exact)"
    if not is_positive_semidefinite(sigma.Q):
        return False, f"the Gram matrix of sigma_{k} is not positive semidefinite (exact)"
    W = sum((p * p * ring.constant(c) for (_, p), c in zip(phi, weights)), ring.zero())
    supply = (R.poly(ring) if R is not None else ring.zero()) - W
    if supply * D - lie_derivative(ring, V.poly(ring), g) != sigma.poly(ring):
        return False, f"the dissipation identity of group {k} does not hold exactly"
    return True, "found"


def check_cascade(ring: Ring, g: Sequence[Poly], D: Poly, groups: Sequence[Sequence[int]], Vs: Sequence[GramPoly],
                  phis: Sequence[Sequence[tuple[int, Poly]]], weights: Sequence[Sequence[Fraction]],
                  Rs: Sequence[GramPoly | None], sigmas: Sequence[GramPoly]) -> tuple[bool, str]:
    """The cascade certificate (the module's docstring), exactly: the groups partition the states, at least
    two; ``D`` is a positive constant; the order is topological (group ``i``'s equations read only its
    own states and earlier groups'); each group passes :func:`check_group` with its ``R_i`` over earlier
    groups' states (group 1: none)."""
    n, m = len(g), len(groups)
    if sorted(i for group in groups for i in group) != list(range(n)) or m < 2:
        return False, "the groups must partition the states (each state in exactly one group), at least two of them"
    if not (len(Vs) == len(phis) == len(weights) == len(Rs) == len(sigmas) == m):
        return False, "one V, one W (coordinates and weights), one R and one sigma per group"
    terms = ring.terms(D)
    if set(terms) != {tuple([0] * ring.nvars)} or terms[tuple([0] * ring.nvars)] <= 0:
        return False, "the cascade form is for a field whose denominator D is a positive constant"
    seen: list[int] = []
    for k, group in enumerate(groups):
        reads = {j for s in group for mono in ring.support(g[s]) for j in range(ring.nvars) if mono[j] > 0}
        if not reads <= set(group) | set(seen):
            return False, (f"the groups are not in a topological order: group {k + 1}'s equations read states of "
                           "a later group, so the network is not this cascade")
        ok, why = check_group(ring, g, D, group, seen, Vs[k], phis[k], weights[k], Rs[k], sigmas[k], k + 1)
        if not ok:
            return False, why
        seen += list(group)
    return True, (f"{m} V_i > 0 with V_i' <= -W_i + R_i(earlier groups' states), W_i = sum_j c_j Phi_j^2 "
                  "(c_j > 0, Phi triangular), R_i >= 0 with R_i(0) = 0, in a topological order: a cascade of ISS "
                  "subsystems driven by a GAS one, exactly")


# -- the certificate, its claim and its check -----------------------------------------------------

def certificate_json(scaled: "ScaledField", field: StateField, found: Mapping[str, Any]) -> dict[str, Any]:
    """The certificate: the groups in their order (names), each ``V_i`` in the declared states
    (``V_groups``), and in the scaled states each ``V_i`` (``gram_V``), ``W_i``'s coordinates
    (``W_coordinates``: per group, ``[state, Phi_j]`` pairs in their triangular order) and weights
    (``W_weights``), ``R_i`` (``gram_R``, None for a group without inputs) and remainder (``gram_sigma``),
    over the network's ring."""
    from lyapcheck.models.classes.lyapunov import stated_v, terms_json

    ring, names = field.ring, field.ring.names
    parts = found["parts"]
    return {"kind": KIND, "degree": max(p["degree"] for p in parts),
            "groups": [[names[i] for i in g] for g in found["groups"]],
            "V_groups": [stated_v(scaled, field, p["V"].poly(ring)) for p in parts],
            "gram_V": [p["V"].to_json() for p in parts],
            "W_coordinates": [[[names[v], terms_json(ring, q)] for v, q in p["phi"]] for p in parts],
            "W_weights": [[str(c) for c in p["c"]] for p in parts],
            "gram_R": [None if p["R"] is None else p["R"].to_json() for p in parts],
            "gram_sigma": [p["sigma"].to_json() for p in parts]}


def sentence(groups: int, degree: int) -> str:
    """The claim's words, the same from the search and from the document."""
    what = "quadratic" if degree == 2 else f"of degree up to {degree}"
    return (f"GAS: a cascade of {groups} subsystems, each with an ISS-Lyapunov function ({what}) V_i' <= -W_i + "
            "R_i(inputs) with W_i positive definite and radially unbounded and R_i(0) = 0, the first with no inputs: "
            "a cascade of ISS systems driven by a GAS one is GAS (no decay rate is claimed; checked exactly)")


def certified(scaled: "ScaledField", field: StateField, name: str, found: Mapping[str, Any],
              solver: dict[str, Any]) -> "ConditionResult":
    from lyapcheck.results import ConditionResult

    degree = max(p["degree"] for p in found["parts"])
    margins = [p["margin"] for p in found["parts"] if p["margin"] is not None]
    numbers = {"degree": degree, "relative_margin": min(margins) if margins else None}
    return ConditionResult(name, "certified", sentence(len(found["groups"]), degree), numbers=numbers,
                           certificate=certificate_json(scaled, field, found), solver=solver, property="GAS")


def verify(c: Mapping[str, Any], cert: Mapping[str, Any], scaled: "ScaledField", field: StateField
           ) -> tuple[bool, str]:
    """The exact re-check of a certificate of :data:`KIND` on the field verify re-derived."""
    from lyapcheck.models.classes.lyapunov import stated_v
    from lyapcheck.models.classes.vector_lyapunov import stated_groups
    from lyapcheck.models.engines.recast_sos import poly_from_json

    if field.p or field.disturbances:
        return False, "a cascade certificate is for a field without box coordinates or disturbances"
    ring, nv = field.ring, field.ring.nvars
    names = list(ring.names[:field.n])
    groups, Vs = stated_groups(cert, field, ("V_groups", "W_coordinates", "W_weights", "gram_R", "gram_sigma"),
                               "a cascade certificate")
    phis = []
    for coords in cert["W_coordinates"]:
        if not isinstance(coords, list) or any(not isinstance(x, list) or len(x) != 2 or x[0] not in names
                                               for x in coords):
            raise ValueError("W_coordinates: per group, a list of [state, polynomial] pairs")
        phis.append([(names.index(x[0]), poly_from_json(ring, x[1], "W_coordinates")) for x in coords])
    if any(not isinstance(ws, list) for ws in cert["W_weights"]):
        raise ValueError("W_weights: per group, a list of rationals")
    weights = [[Fraction(x) for x in ws] for ws in cert["W_weights"]]
    Rs = [None if part is None else GramPoly.from_json(part, nv) for part in cert["gram_R"]]
    sigmas = [GramPoly.from_json(part, nv) for part in cert["gram_sigma"]]
    ok, why = check_cascade(ring, field.g, field.D, groups, Vs, phis, weights, Rs, sigmas)
    if not ok:
        return False, why
    if [stated_v(scaled, field, V.poly(ring)) for V in Vs] != cert["V_groups"]:
        return False, "the stated V_groups are not the certificate's Gram V_i unscaled"
    if int(cert["degree"]) != 2 * max(max(sum(mono) for mono in V.basis) for V in Vs):
        return False, "the stated degree is not the V_i's"
    if c.get("degree") is not None and c.get("degree") != int(cert["degree"]):
        return False, "the condition's degree is not the certificate's"
    if c.get("property") not in ("GAS", None):
        return False, f"a cascade certificate proves GAS, not {c.get('property')}"
    return True, why
