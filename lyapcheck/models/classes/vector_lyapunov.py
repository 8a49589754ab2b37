"""``sos_gas`` in the compositional form: a vector Lyapunov function with an exact comparison system (issue 43).

A network of subsystems (groups of states) is proved GAS from one Lyapunov function per subsystem and a
linear comparison system between them, as LyZNet's compositional verification does (there with dReal,
here exactly). In the scaled coordinates of :mod:`lyapcheck.models.loop.field` (``z' = g / D``, ``D`` a
positive constant), with the states partitioned into groups ``I_1, ..., I_m``:

* ``V_i = z_Vi^T Q_i z_Vi`` over monomials of the states of group ``i`` alone, ``Q_i > 0`` and a pure
  power of each of those states in the basis: ``V_i >= lambda |z_Ii|^2``, positive definite and radially
  unbounded in ``z_Ii``;
* a rational ``m x m`` matrix ``A``, Metzler (``A_ij >= 0`` for ``i != j``), and a vector ``d > 0`` with
  ``d^T A < 0`` componentwise (for a Metzler matrix, a proof that it is Hurwitz);
* per group, the identity ``d_i (sum_j A_ij V_j D - grad V_i . g) = sigma_i`` with ``sigma_i`` a sum of
  Gram forms ``z_k^T R_ik z_k``, one per pair of group ``i`` and a group it reads (:func:`remainder_bases`),
  every ``R_ik >= 0`` (exact).

Then ``V_i' = grad V_i . g / D <= sum_j A_ij V_j`` everywhere: ``v = (V_1, ..., V_m)`` satisfies
``v' <= A v``, and the certified function is ``W = d^T v = sum_i d_i V_i``: ``W' <= (d^T A) v <= -c W``
with ``c = min_j -(d^T A)_j / d_j > 0``. ``W`` is positive definite and radially unbounded (the groups
partition the states): the equilibrium is globally asymptotically stable and ``W`` decays at least like
``exp(-c t)``. The claim is GAS with ``W``'s decay rate; it is a GAS claim even where every ``V_i`` is
quadratic (a GES figure would need ``W``'s eigenvalue bounds, not derived here).

The search, in two steps (each linear):

1. each group's ``V_i``: the dense ``sos_gas`` search (:func:`lyapcheck.models.classes.lyapunov.search_degree`)
   on the isolated subsystem (the group's equations with every other state at 0), with its best decay
   rate; groups whose isolated subsystems are the same polynomials (up to renaming) share one search;
2. with the ``V_i`` fixed, one SOS program in ``B_ij = d_i A_ij >= 0`` (``j`` a group that group ``i``'s
   equations read), ``d_i >= t``, ``s_j = -(d^T A)_j >= t`` and the Gram matrices ``R_ik >= t I``: the
   diagonal ``B_ii = -s_i - sum_k B_ki`` is written through the others, so that every constraint is linear
   (with the facial reduction of the clique form where the remainders must be singular).

It is ``sos_gas``'s last form but one (:func:`fallback`, which :func:`lyapcheck.models.classes.lyapunov.run`
calls after the dense and clique forms of each degree; the cascade form of
:mod:`lyapcheck.models.classes.cascade_lyapunov` follows it): tried once, where one of those reached a
size limit.

Groups (:func:`subsystem_groups`): the strongly connected components of the field's interaction graph
when there are at least two and each has at most :data:`MAX_GROUP_STATES` states (a cascade, e.g. the
platoon: each vehicle's spacing and speed); else, the pairs that a state whose equation reads exactly one
other state forms with it (``q' = p``: a position and its velocity), when they give at least two groups of
at most :data:`MAX_GROUP_STATES` states and every state is in one (e.g. the ring of oscillators). Nothing
else is tried: no group, no vector form.
"""

from __future__ import annotations

from fractions import Fraction
from typing import TYPE_CHECKING, Any, Final, Mapping, Sequence

from lyapcheck.models.engines.search import ParameterValues, Search, literal, one
from lyapcheck.models.loop.field import StateField
from lyapcheck.sos import bases
from lyapcheck.sos.certificates import GramPoly, lie_derivative
from lyapcheck.sos.polynomials import Monomial, Poly, Ring
from lyapcheck.sos.structure import Gram, Identity, Scalar, Structure, Term

if TYPE_CHECKING:  # pragma: no cover
    from lyapcheck.models.loop.field import ScaledField
    from lyapcheck.results import ConditionResult
    from lyapcheck.sos.program import Solution

#: the certificate kind
KIND: Final = "lyapunov_vector"
#: the most states a group (subsystem) may have: its V_i is searched densely
MAX_GROUP_STATES: Final = 4
#: the degrees of the V_i tried, in turn (one degree for every group)
VECTOR_DEGREES: Final = (2, 4)
#: the largest comparison program solved (:meth:`~lyapcheck.sos.structure.Structure.cost`): the sum
#: over the groups' remainders; 15 groups of quartic V_i on a ring (30 states) cost about 1e9
VECTOR_COST_LIMIT: Final = 4_000_000_000
#: what the detail line of the vector form starts with (so that it is tried once per run)
LABEL: Final = "vector Lyapunov function"


# -- the groups ---------------------------------------------------------------------------------------

def couplings(field: StateField) -> list[set[int]]:
    """Per state ``i``, the other states ``g_i`` reads."""
    n = field.n
    return [{j for m in field.ring.support(gi) for j in range(n) if m[j] > 0 and j != i} for i, gi in enumerate(field.g)]


def strong_components(n: int, edges: Sequence[set[int]]) -> list[tuple[int, ...]]:
    """The strongly connected components of the graph ``i -> j`` for ``j`` in ``edges[i]`` (Tarjan's
    algorithm, iterative), each sorted, in the order of their smallest state."""
    index: dict[int, int] = {}
    low: dict[int, int] = {}
    on_stack: set[int] = set()
    stack: list[int] = []
    out: list[tuple[int, ...]] = []
    counter = 0
    for root in range(n):
        if root in index:
            continue
        work = [(root, iter(sorted(edges[root])))]
        index[root] = low[root] = counter
        counter += 1
        stack.append(root)
        on_stack.add(root)
        while work:
            v, children = work[-1]
            child = next(children, None)
            if child is not None:
                if child not in index:
                    index[child] = low[child] = counter
                    counter += 1
                    stack.append(child)
                    on_stack.add(child)
                    work.append((child, iter(sorted(edges[child]))))
                elif child in on_stack:
                    low[v] = min(low[v], index[child])
                continue
            work.pop()
            if work:
                low[work[-1][0]] = min(low[work[-1][0]], low[v])
            if low[v] == index[v]:
                comp = []
                while True:
                    w = stack.pop()
                    on_stack.discard(w)
                    comp.append(w)
                    if w == v:
                        break
                out.append(tuple(sorted(comp)))
    return sorted(out)


def _fits(groups: Sequence[tuple[int, ...]], n: int) -> bool:
    return len(groups) >= 2 and all(len(g) <= MAX_GROUP_STATES for g in groups) and \
        sorted(i for g in groups for i in g) == list(range(n))


def subsystem_groups(field: StateField) -> list[tuple[int, ...]] | None:
    """The states' partition into subsystems (see the module's docstring), or None."""
    n = field.n
    reads = couplings(field)
    components = strong_components(n, reads)
    if _fits(components, n):
        return components
    parent = list(range(n))

    def find(i: int) -> int:
        while parent[i] != i:
            parent[i] = parent[parent[i]]
            i = parent[i]
        return i

    for i, read in enumerate(reads):
        if len(read) == 1:  # an integrator: q' = p (up to a factor)
            parent[find(i)] = find(next(iter(read)))
    pairs: dict[int, list[int]] = {}
    for i in range(n):
        pairs.setdefault(find(i), []).append(i)
    groups = sorted(tuple(sorted(g)) for g in pairs.values())
    return groups if _fits(groups, n) else None


def neighbours(field: StateField, groups: Sequence[tuple[int, ...]]) -> list[list[int]]:
    """Per group ``i``, the other groups whose states the equations of group ``i`` read."""
    owner = {s: k for k, g in enumerate(groups) for s in g}
    reads = couplings(field)
    return [sorted({owner[j] for s in g for j in reads[s]} - {k}) for k, g in enumerate(groups)]


# -- step 1: each group's V_i from its isolated subsystem ---------------------------------------------

def isolated_field(field: StateField, group: Sequence[int]) -> StateField:
    """The subsystem of ``group``: its equations with every other state at 0, in the ring of its states."""
    ring = field.ring
    sub = Ring(tuple(ring.names[i] for i in group))
    zero = {ring.names[i]: Fraction(0) for i in range(field.n) if i not in group}
    g = tuple(ring.restrict(ring.substitute(field.g[i], zero), sub) for i in group)
    return StateField(ring=sub, g=g, D=ring.restrict(field.D, sub))


def subsystem_shape(sub: StateField) -> tuple[Any, ...]:
    """The isolated subsystem as data without its names (equal subsystems share one search)."""
    ring = sub.ring
    return (tuple(tuple(sorted(ring.terms(gi).items())) for gi in sub.g), tuple(sorted(ring.terms(sub.D).items())))


def embed_gram(V: GramPoly, group: Sequence[int], nv: int) -> GramPoly:
    """A Gram polynomial over the group's ring as one over the whole ring (same matrix)."""
    def lift(m: Monomial) -> Monomial:
        e = [0] * nv
        for k, i in enumerate(group):
            e[i] = m[k]
        return tuple(e)

    return GramPoly(tuple(lift(m) for m in V.basis), V.Q)


def local_functions(field: StateField, groups: Sequence[tuple[int, ...]], degree: int, search: Search
                    ) -> tuple[list[GramPoly] | None, str]:
    """Each group's ``V_i`` of this degree (over the whole ring), or None and why not."""
    from lyapcheck.models.classes.lyapunov import search_degree

    found: dict[tuple[Any, ...], GramPoly | None] = {}
    out: list[GramPoly] = []
    for group in groups:
        sub = isolated_field(field, group)
        key = subsystem_shape(sub)
        if key not in found:
            local, why = search_degree(sub, degree, search.over(sub.ring))
            names = ", ".join(sub.ring.names)
            if local is None:
                return None, f"no V of degree {degree} for the isolated subsystem of {names} ({why})"
            if local["mu"] <= 0:
                # a Hurwitz Metzler A has A_ii < 0, and where the other groups' states are 0 the comparison
                # says V_i' <= A_ii V_i along the isolated subsystem: V_i must decay exponentially there
                return None, (f"the isolated subsystem of {names} has a V of degree {degree} but none found with "
                              "V' <= -mu V, mu > 0, which a Hurwitz comparison matrix needs (A_ii < 0)")
            found[key] = local["V"]
        V = found[key]
        assert V is not None
        out.append(embed_gram(V, group, field.ring.nvars))
    return out, "found"


# -- step 2: the comparison system --------------------------------------------------------------------

def comparison_program(field: StateField, groups: Sequence[tuple[int, ...]], Vs: Sequence[GramPoly],
                       drop: frozenset[tuple[str, Monomial]] = frozenset()) -> Structure | str:
    """The program of step 2 (see the module's docstring) for fixed ``V_i``, or why there is none;
    ``drop``: (Gram, monomial) pairs the remainders' bases leave out (facial reduction)."""
    from lyapcheck.models.classes.lyapunov import symmetry
    from lyapcheck.models.engines.reasons import size_limit

    ring, nv = field.ring, field.ring.nvars
    near = neighbours(field, groups)
    readers = [[k for k in range(len(groups)) if j in near[k]] for j in range(len(groups))]
    polys = [V.poly(ring) for V in Vs]
    generators = symmetry(field)
    grams, identities, scalars = [], [], []
    scalars += [Scalar(f"d{i}", "margin") for i in range(len(groups))]
    scalars += [Scalar(f"s{i}", "margin") for i in range(len(groups))]
    scalars += [Scalar(f"B{i}_{j}", "zero") for i in range(len(groups)) for j in near[i]]
    for i in range(len(groups)):
        decrease = -lie_derivative(ring, polys[i], field.g)
        own = -polys[i] * field.D
        terms = [Term(literal(ring, ring.terms(decrease)), f"d{i}"), Term(literal(ring, ring.terms(own)), f"s{i}")]
        terms += [Term(literal(ring, ring.terms(polys[j] * field.D)), f"B{i}_{j}") for j in near[i]]
        terms += [Term(literal(ring, ring.terms(own)), f"B{k}_{i}") for k in readers[i]]
        target = set(ring.support(decrease)) | set(ring.support(own))
        for j in near[i]:
            target |= set(ring.support(polys[j] * field.D))
        parts = []
        for k, basis in enumerate(remainder_bases(groups, i, near[i], nv, target)):
            kept = [m for m in basis if (f"R{i}_{k}", m) not in drop]
            if kept:
                parts.append(Gram(f"R{i}_{k}", tuple(kept), tuple(map(tuple, bases.character_blocks(kept, generators)))))
        if not parts:
            return "no strict certificate of this form exists (a comparison identity has an empty basis)"
        grams += parts
        terms += [Term(one(ring, -1), part.name) for part in parts]
        identities.append(Identity(f"comparison{i}", tuple(terms), None, parts[0].name,
                                   shared=tuple(part.name for part in parts[1:])))
    structure = Structure(nvars=nv, grams=tuple(grams), scalars=tuple(scalars), identities=tuple(identities),
                          objective=("max_margin",))  # homogeneous: t <= 1 fixes the scale
    if structure.cost() > VECTOR_COST_LIMIT:
        return size_limit(f"{structure.cost():.1e}", "work units of the comparison program", f"{VECTOR_COST_LIMIT:.1e}",
                          "VECTOR_COST_LIMIT")
    return structure


def remainder_bases(groups: Sequence[tuple[int, ...]], i: int, near: Sequence[int], nv: int,
                    target: set[Monomial]) -> list[list[Monomial]]:
    """The bases of group ``i``'s remainder, a sum of Gram forms, one per pair of group ``i`` and a group
    its equations read (correlative sparsity, :mod:`lyapcheck.sos.sparsity`): the identity's terms read
    group ``i`` and one other group at a time where the couplings are sums of one-neighbour terms, and a
    single Gram form over every neighbour's states would grow with their number (at 20 states of the
    all-to-all swarm, 3.7e10 work units). A restriction: a remainder that needs products across two
    neighbours is not found."""
    from lyapcheck.sos import sparsity

    cliques = [tuple(sorted({*groups[i], *groups[j]})) for j in near] or [tuple(groups[i])]
    half = max(sum(m) for m in target) // 2
    return sparsity.reduce_clique_bases(cliques, [sparsity.clique_candidates(c, nv, 1, half) for c in cliques], target)


def comparison_attempt(field: StateField, groups: Sequence[tuple[int, ...]], Vs: Sequence[GramPoly],
                       structure: Structure, search: Search) -> tuple[dict[str, Any] | None, "Solution"]:
    """One solve of the comparison program; the exact certificate if it passes :func:`check_vector_lyapunov`."""
    from lyapcheck.models.classes.lyapunov import exact_try

    point, solution = exact_try(structure, ParameterValues(), search)
    if point is None:
        return None, solution
    m = len(groups)
    near = neighbours(field, groups)
    d = [point.scalars[f"d{i}"] for i in range(m)]
    B = [[Fraction(0)] * m for _ in range(m)]
    for i in range(m):
        for j in near[i]:
            B[i][j] = point.scalars[f"B{i}_{j}"]
    for j in range(m):
        B[j][j] = -point.scalars[f"s{j}"] - sum((B[k][j] for k in range(m) if k != j), Fraction(0))
    if any(x <= 0 for x in d):
        return None, solution
    A = [[B[i][j] / d[i] for j in range(m)] for i in range(m)]
    sigmas = [[GramPoly.of(structure.gram(name).basis, point.grams[name]) for name in ident.remainders()]
              for ident in structure.identities]
    ok, _ = check_vector_lyapunov(field.ring, field.g, field.D, groups, Vs, A, d, sigmas)
    if not ok:
        return None, solution
    return {"groups": [list(g) for g in groups], "parts": list(Vs), "A": A, "d": d, "sigmas": sigmas,
            "mu": decay_rate(A, d), "margin": solution.scalars["t"]}, solution


def decay_rate(A: Sequence[Sequence[Fraction]], d: Sequence[Fraction]) -> Fraction:
    """``c = min_j -(d^T A)_j / d_j``: ``W = d^T v`` has ``W' <= -c W``."""
    m = len(d)
    return min(-sum((d[i] * A[i][j] for i in range(m)), Fraction(0)) / d[j] for j in range(m))


# -- the exact check ----------------------------------------------------------------------------------

def check_vector_lyapunov(ring: Ring, g: Sequence[Poly], D: Poly, groups: Sequence[Sequence[int]],
                          Vs: Sequence[GramPoly], A: Sequence[Sequence[Fraction]], d: Sequence[Fraction],
                          sigmas: Sequence[Sequence[GramPoly]]) -> tuple[bool, str]:
    """The vector Lyapunov certificate (the module's docstring), exactly: the groups partition the
    states, ``D`` is a positive constant, each ``V_i`` is over its group's states with ``Q_i > 0``, no
    constant and a pure power of each of them, ``A`` is Metzler, ``d > 0``, ``d^T A < 0``, each
    ``R_i >= 0`` and ``d_i (sum_j A_ij V_j D - grad V_i . g) = sigma_i``, ``sigma_i`` a sum of Gram
    forms (``sigmas[i]``, one per pair of groups), each matrix positive semidefinite."""
    from lyapcheck.sos.definiteness import is_positive_semidefinite

    n, m = len(g), len(groups)
    if sorted(i for group in groups for i in group) != list(range(n)) or m < 1:
        return False, "the groups must partition the states (each state in exactly one group)"
    if len(Vs) != m or len(sigmas) != m or len(d) != m or len(A) != m or any(len(row) != m for row in A):
        return False, "one V, one sigma, one d and one row and column of A per group"
    terms = ring.terms(D)
    if set(terms) != {tuple([0] * ring.nvars)} or terms[tuple([0] * ring.nvars)] <= 0:
        return False, "the vector form is for a field whose denominator D is a positive constant"
    for k, (group, V) in enumerate(zip(groups, Vs)):
        outside = [i for i in range(ring.nvars) if i not in group]
        if not V.basis or any(m_[i] for m_ in V.basis for i in outside):
            return False, f"V_{k + 1} may depend on the states of its group only"
        if not bases.has_pure_powers(V.basis, list(group)) or any(sum(m_) == 0 for m_ in V.basis):
            return False, f"V_{k + 1}'s basis must hold a pure power of each state of its group and no constant"
        if not V.positive_definite():
            return False, f"Q_V{k + 1} is not positive definite (exact)"
    if any(A[i][j] < 0 for i in range(m) for j in range(m) if i != j):
        return False, "A is not Metzler (an off-diagonal entry is negative)"
    if any(x <= 0 for x in d):
        return False, "d must be positive"
    if decay_rate(A, d) <= 0:
        return False, "d^T A < 0 does not hold componentwise (A is not proved Hurwitz)"
    polys = [V.poly(ring) for V in Vs]
    for i in range(m):
        if not sigmas[i] or not all(is_positive_semidefinite(part.Q) for part in sigmas[i]):
            return False, f"a Gram matrix of sigma_{i + 1} is not positive semidefinite (exact)"
        bound = sum((polys[j] * D * ring.constant(A[i][j]) for j in range(m) if A[i][j]), ring.zero())
        sigma = sum((part.poly(ring) for part in sigmas[i]), ring.zero())
        if (bound - lie_derivative(ring, polys[i], g)) * ring.constant(d[i]) != sigma:
            return False, f"the comparison identity of group {i + 1} does not hold exactly"
    return True, (f"{m} V_i > 0, A Metzler with d^T A < 0 (d > 0) and d_i (sum_j A_ij V_j D - grad V_i . g) = "
                  "sigma_i >= 0, exactly")


# -- the search ---------------------------------------------------------------------------------------

def search_vector(field: StateField, search: Search) -> tuple[dict[str, Any] | None, str]:
    """A vector Lyapunov certificate (each of :data:`VECTOR_DEGREES` in turn), or None and why not."""
    if field.p or field.disturbances:
        return None, f"{LABEL}: not for a field with box coordinates"
    groups = subsystem_groups(field)
    if groups is None:
        return None, (f"{LABEL}: no subsystems (no partition of the states into at least two groups of at most "
                      f"{MAX_GROUP_STATES} (MAX_GROUP_STATES): strongly connected components or position-velocity pairs)")
    label = f"{LABEL} over {len(groups)} subsystems"
    whys = []
    for degree in VECTOR_DEGREES:
        search.budget.check()
        Vs, why = local_functions(field, groups, degree, search)
        if Vs is None:
            whys.append(f"V_i of degree {degree}: {why}")
            continue
        structure = comparison_program(field, groups, Vs)
        if isinstance(structure, str):
            whys.append(f"V_i of degree {degree}: {structure}")
            continue
        found, why = comparison_search(field, groups, Vs, structure, search)
        if found is None:
            whys.append(f"V_i of degree {degree}, the comparison system: {why}")
            continue
        found["degree"] = degree
        return found, f"{label}, V_i of degree {degree}: found"
    return None, f"{label}: " + "; ".join(whys)


def comparison_search(field: StateField, groups: Sequence[tuple[int, ...]], Vs: Sequence[GramPoly],
                      structure: Structure, search: Search) -> tuple[dict[str, Any] | None, str]:
    """Solve the comparison program and, while the exact check refuses, its facial reductions (the
    remainders' vanishing rows or kernels' supports left out, at most
    :data:`~lyapcheck.models.classes.lyapunov.LYAPUNOV_FACIAL_ROUNDS` times, as the clique form does):
    where an isolated ``V_i``'s remainder needed a reduced face, the whole Newton basis of the coupled
    one has monomials that must vanish."""
    from lyapcheck.models.classes.lyapunov import LYAPUNOV_FACIAL_ROUNDS, failure, gram_faces

    drop: frozenset[tuple[str, Monomial]] = frozenset()
    why = "none found"
    for _ in range(LYAPUNOV_FACIAL_ROUNDS + 1):
        found, solution = comparison_attempt(field, groups, Vs, structure, search)
        if found is not None:
            return found, "found"
        why = failure(solution)
        vanishing = gram_faces(structure.grams, solution)
        if not vanishing:
            break
        drop = drop | vanishing
        reduced = comparison_program(field, groups, Vs, drop)
        if isinstance(reduced, str):
            return None, f"{reduced} (after facial reduction, where {why})"
        structure = reduced
    return None, why


def fallback(scaled: "ScaledField", field: StateField, name: str, search: Search, detail: list[str]
             ) -> "ConditionResult | None":
    """``sos_gas``'s vector form (:func:`lyapcheck.models.classes.lyapunov.run` calls it after the dense and
    clique forms of each degree found nothing): once per run, and only where one of them reached a size
    limit (a network too large for them), a vector Lyapunov function of the network's subsystems. Its
    line joins ``detail`` (what was tried); the certified result, or None. The class's time limit
    (:class:`~lyapcheck.models.engines.search.BudgetExhausted`) ends it as it ends the other forms."""
    from lyapcheck.models.engines import reasons

    if field.p or field.disturbances or any(line.startswith(LABEL) for line in detail) \
            or not reasons.size_limits(detail):
        return None
    found, why = search_vector(field, search)
    detail.append(why)
    return None if found is None else certified(scaled, field, name, found, {"solves": search.log})


# -- the certificate, its claim and its check -----------------------------------------------------

def certificate_json(scaled: "ScaledField", field: StateField, found: Mapping[str, Any]) -> dict[str, Any]:
    """The certificate: ``V`` (``W = sum_i d_i V_i`` in the declared states), the groups (names), each
    ``V_i``'s Gram matrix (``gram_V``), ``A``, ``d`` and each comparison remainder (``gram_sigma``), in
    the scaled states (``gram_sigma``: per group, a list of Gram matrices, one per pair of the group and
    a group it reads, :func:`remainder_bases`)."""
    from lyapcheck.models.classes.lyapunov import stated_v

    ring = field.ring
    W = sum((V.poly(ring) * ring.constant(di) for V, di in zip(found["parts"], found["d"])), ring.zero())
    names = ring.names
    return {"kind": KIND, "degree": found["degree"], "mu_scaled": str(found["mu"]), "V": stated_v(scaled, field, W),
            "groups": [[names[i] for i in g] for g in found["groups"]],
            "gram_V": [V.to_json() for V in found["parts"]],
            "A": [[str(x) for x in row] for row in found["A"]], "d": [str(x) for x in found["d"]],
            "gram_sigma": [[part.to_json() for part in s] for s in found["sigmas"]]}


def sentence(groups: int, degree: int, rate: str) -> str:
    """The claim's words (``rate``: ``W``'s decay rate as :mod:`lyapcheck.models.classes.claims` writes a
    rate), the same from the search and from the document."""
    what = "quadratic" if degree == 2 else f"degree-{degree}"
    return (f"GAS: a vector Lyapunov function, {groups} {what} V_i of the subsystems with V_i' <= sum_j A_ij V_j "
            f"for a Metzler A with d^T A < 0 (d > 0, so A is Hurwitz); W = sum_i d_i V_i has W' <= -r W with r = "
            f"{rate} (W decays exponentially from every start; checked exactly)")


def certified(scaled: "ScaledField", field: StateField, name: str, found: Mapping[str, Any],
              solver: dict[str, Any]) -> "ConditionResult":
    from lyapcheck.results import ConditionResult

    rate = float(found["mu"] / scaled.scaling.time)
    words = sentence(len(found["groups"]), found["degree"], f"{rate:.4g} 1/s")  # (the runner restates it: claims)
    numbers = {"degree": found["degree"], "decay_rate_V_per_s": rate, "relative_margin": found["margin"]}
    return ConditionResult(name, "certified", words, numbers=numbers,
                           certificate=certificate_json(scaled, field, found), solver=solver, property="GAS")


def stated_groups(cert: Mapping[str, Any], field: StateField, keys: Sequence[str], what: str
                  ) -> tuple[list[list[int]], list[GramPoly]]:
    """A certificate's subsystems (``groups``: lists of the model's states, as indices) and their ``V_i``
    (``gram_V``), read for the exact re-check of a vector or a cascade certificate; ``keys``: the other lists
    it must have. ValueError (the verify row's words) on a malformed one."""
    names = list(field.ring.names[:field.n])
    for key in ("groups", "gram_V", *keys):
        if not isinstance(cert.get(key), list):
            raise ValueError(f"{key}: {what} has a list '{key}'")
    groups = []
    for group in cert["groups"]:
        if not isinstance(group, list) or any(s not in names for s in group):
            raise ValueError(f"groups: {group!r} is not a list of the model's states")
        groups.append([names.index(s) for s in group])
    return groups, [GramPoly.from_json(part, field.ring.nvars) for part in cert["gram_V"]]


def verify(c: Mapping[str, Any], cert: Mapping[str, Any], scaled: "ScaledField", field: StateField
           ) -> tuple[bool, str]:
    """The exact re-check of a certificate of :data:`KIND` on the field verify re-derived."""
    from lyapcheck.models.classes.lyapunov import stated_v

    if field.p or field.disturbances:
        return False, "a vector Lyapunov certificate is for a field without box coordinates or disturbances"
    ring, nv = field.ring, field.ring.nvars
    groups, Vs = stated_groups(cert, field, ("A", "d", "gram_sigma"), "a vector Lyapunov certificate")
    if any(not isinstance(parts, list) for parts in cert["gram_sigma"]):
        raise ValueError("gram_sigma: one list of Gram matrices per group")
    sigmas = [[GramPoly.from_json(part, nv) for part in parts] for parts in cert["gram_sigma"]]
    A = [[Fraction(x) for x in row] for row in cert["A"]]
    d = [Fraction(x) for x in cert["d"]]
    ok, why = check_vector_lyapunov(ring, field.g, field.D, groups, Vs, A, d, sigmas)
    if not ok:
        return False, why
    mu = Fraction(cert["mu_scaled"])
    if mu != decay_rate(A, d):
        return False, "mu_scaled is not min_j -(d^T A)_j / d_j"
    W = sum((V.poly(ring) * ring.constant(di) for V, di in zip(Vs, d)), ring.zero())
    if stated_v(scaled, field, W) != cert["V"]:
        return False, "the stated V is not sum_i d_i V_i unscaled"
    if int(cert["degree"]) != 2 * max(max(sum(m) for m in V.basis) for V in Vs):
        return False, "the stated degree is not the V_i's"
    stated = c.get("decay_rate_V_per_s")
    if stated is not None and Fraction(float(stated)) > mu / scaled.scaling.time * (1 + Fraction(1, 10**12)):
        return False, "the stated decay rate of W exceeds the certified one"
    if c.get("property") not in ("GAS", None):
        return False, f"a vector Lyapunov certificate proves GAS, not {c.get('property')}"
    return True, why
