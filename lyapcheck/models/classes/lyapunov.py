"""``quadratic`` and ``sos_gas``: a global polynomial Lyapunov function, found by SOS and checked exactly.

The certificate (kind Lyapunov of :mod:`lyapcheck.sos.certificates`), in the scaled coordinates of
:mod:`lyapcheck.models.loop.field`: ``V = z_V^T Q_V z_V`` over the monomials of degree 1 to ``k``,
``Q_V > 0``, and

    -grad V . g - mu V D = z_W^T Q_W z_W,   Q_W > 0,   mu >= 0,

with a pure power of every state in ``z_W``. Then ``V >= lambda |z|^2`` (positive definite and
radially unbounded) and ``V' = grad V . g / D = -mu V - sigma / D < 0`` away from 0: the equilibrium
is globally asymptotically stable, and ``V`` decays at least like ``exp(-mu t)``. For a quadratic
``V = z^T P z`` with ``mu > 0`` this is GES: ``|x(t)| <= sqrt(c2/c1) |x0| exp(-mu t / 2)`` with
``c1 I <= P <= c2 I`` (exact rational bounds). For a ``V`` of higher degree the decay of ``V`` is not
a bound linear in ``|x0|``, so only GAS (and the decay rate of ``V``) is claimed.

The search (a cvxpy program per structure, :mod:`lyapcheck.sos.program`): maximize the smallest
eigenvalue ``t`` of ``Q_V`` and ``Q_W`` with ``trace Q_V = 1``; ``z_W`` is reduced by the Newton
polytope; where the field has sign symmetries the Gram matrices are block diagonal
(:mod:`lyapcheck.sos.bases`). First ``mu = 0`` (GAS), then the largest ``mu`` found by a geometric
search, each candidate decided by the exact check.

The certificate found is kept in the certificate store (:mod:`lyapcheck.models.engines.store`) under the
exact field and the degrees searched; a later run of the same problem checks it exactly again
(:func:`recall_certificate`) and, when it passes, uses it without a solve.
"""

from __future__ import annotations

import math
from fractions import Fraction
from typing import TYPE_CHECKING, Any, Callable, Final, Iterable, Literal, Mapping, Sequence

from lyapcheck.models.engines import reasons, store
from lyapcheck.models.loop.field import ScaledField, StateField, declared_quadratic, state_field, unscale_polynomial
from lyapcheck.models.engines.reasons import size_limit
from lyapcheck.models.engines.search import (EXACT_TRY_MARGIN, BudgetExhausted, ParameterValues, Search, box_multipliers, box_multipliers_of,
                                     estimated_seconds, literal, multiplier_grams, multiplier_variable, one, param)
from lyapcheck.results import ConditionResult
from lyapcheck.tolerances import (CONE_CANDIDATE_LIMIT, CONE_FALLBACK_SOLVES, CONE_GRAM_ROWS, CONE_SIZE_LIMIT,
                                  CONE_TARGET_LIMIT, FORM_SOLVES_ESTIMATE)
from lyapcheck.sos import bases
from lyapcheck.sos.certificates import (GramPoly, at_vertex, box_vertices, check_lyapunov, check_lyapunov_vertices,
                                       lie_derivative, multi_affine)
from lyapcheck.sos.polynomials import Monomial, Poly, Ring, monomials, to_fmpq
from lyapcheck.sos.structure import Gram, Identity, Scalar, Structure, Term

if TYPE_CHECKING:  # pragma: no cover
    from lyapcheck.sos.program import Solution

#: degrees of V that ``sos_gas`` tries, in turn (``quadratic`` is degree 2 alone)
SOS_GAS_DEGREES: Final = (2, 4, 6, 8)
#: the largest Gram basis a search builds (rows); a degree that needs more is skipped, named. A
#: solve with Gram matrices of 65 and 150 rows (degree 4 in 10 states) takes 5-7 s here
MAX_GRAM_ROWS: Final = 120
#: decay-rate search in scaled time: geometric steps down from MU_MAX to the first mu proved, then
#: MU_BISECTION_STEPS geometric bisections (the rate is a figure: a few per cent resolve it)
MU_MAX: Final = Fraction(4)
MU_MIN: Final = Fraction(1, 10**6)
MU_BISECTION_STEPS: Final = 4
#: facial reduction: a remainder's basis monomial whose diagonal is below this fraction of the
#: largest is dropped and the search repeated, at most FACIAL_ROUNDS times
FACIAL_TOL: Final = 1e-7
#: a remainder whose unreduced candidate basis (the monomials up to half the target's degree)
#: has more than this many monomials is not attempted: building its Newton-reduced basis alone
#: takes seconds, and its program could not be solved within the class's time
CANDIDATE_LIMIT: Final = 500
#: the most monomials an identity may have (one equality each): degree 4 in 10 states has about
#: 3000, and a solve took 6-20 s here
TARGET_LIMIT: Final = 1500
#: the largest program a search solves (:meth:`~lyapcheck.sos.program.Structure.cost`): degree 4
#: in 10 states, with two Gram matrices in PSD blocks of 47 and 18 rows (cost 2.9e9), took 12-21 s
#: a solve here; one such Gram matrix (the 10-state level step, 1.4e9) about 2 s
BLOCK_COST_LIMIT: Final = 2_000_000_000
FACIAL_ROUNDS: Final = 3
#: ... and only when the solve's margin is not clearly negative (an infeasible program has no face)
FACIAL_MARGIN: Final = 1e-6
#: rounds of facial reduction in the Lyapunov search (quadratic, sos_gas), where the programs
#: shrink with every round: on a 6-state system (Papachristodoulou & Prajna) the face of the
#: quartic V took 6 rounds
LYAPUNOV_FACIAL_ROUNDS: Final = 8


def symmetry(field: StateField) -> list[tuple[int, ...]]:
    """The sign changes of the states (and box parameters) that map the field to itself (``g_i``
    like ``z_i``, ``D`` invariant; a box's ``1 - u_j^2`` is invariant anyway)."""
    return bases.sign_symmetries(field.ring.nvars, [(field.ring.support(gi), i) for i, gi in enumerate(field.g)]
                                 + [(field.ring.support(field.D), None)])


def field_degree(field: StateField) -> int:
    """The largest total degree of ``g`` and ``D``."""
    return max([sum(m) for gi in field.g for m in field.ring.support(gi)]
               + [sum(m) for m in field.ring.support(field.D)] + [1])


def gram_products(basis: Sequence[Monomial], blocks: Sequence[Sequence[int]]) -> set[Monomial]:
    """Every monomial a Gram form over ``basis`` with these blocks can have."""
    return {tuple(a + b for a, b in zip(basis[i], basis[j])) for idx in blocks for i in idx for j in idx}


def widen_by_derivative(target: set[Monomial], ring: Ring, products: Iterable[Monomial],
                        flows: Iterable[tuple[int, Poly]], also: Iterable[Monomial] = ()) -> None:
    """Add to ``target`` the monomials ``grad(V) . g`` can have, ``V`` a Gram form of these ``products``
    (each flow ``g_i``, its state's index ``i`` with it, times ``dV/dx_i``'s monomials), then the products
    times each monomial of ``also`` (the identity's ``V D``, ``V W`` or ``V s`` term), in that order."""
    products = list(products)
    for i, gi in flows:
        derived = {m[:i] + (m[i] - 1,) + m[i + 1:] for m in products if m[i] > 0}
        target |= {tuple(a + b for a, b in zip(m, s)) for m in derived for s in ring.support(gi)}
    also = list(also)
    if also:
        target |= {tuple(a + b for a, b in zip(m, s)) for m in products for s in also}


def lyapunov_structure(field: StateField, degree: int, generators: Sequence[Sequence[int]],
                       drop: frozenset[Monomial] = frozenset(), param_degree: int = 0,
                       drop_v: frozenset[Monomial] = frozenset()) -> Structure | None:
    """The program for a ``V`` of this degree, or None (:func:`lyapunov_program` says why)."""
    found = lyapunov_program(field, degree, generators, drop, param_degree, drop_v)
    return found if isinstance(found, Structure) else None


def lyapunov_program(field: StateField, degree: int, generators: Sequence[Sequence[int]],
                     drop: frozenset[Monomial] = frozenset(), param_degree: int = 0,
                     drop_v: frozenset[Monomial] = frozenset(), cone: str = "psd") -> Structure | str:
    """The program for a ``V`` of this degree, or why there is none: a size limit (named), or no
    strict certificate can exist in this form (the remainder's reduced basis lacks a pure power of
    some state: the Newton polytope of ``-V'`` leaves no room for one). ``drop``: monomials the
    remainder's basis leaves out, ``drop_v`` those ``V``'s basis leaves out (facial reduction,
    :func:`vanishing_monomials`: a ``V`` whose Gram matrix must be singular over the full basis,
    e.g. one without ``x1^4`` where an ``x1^4`` would leave odd terms in ``-V'``). Over a box of
    parameters (the ring's variables after the states) ``V``'s basis monomials may carry the
    parameters up to ``param_degree`` and the box's multipliers join the identity. ``cone``
    ``"sdd"`` or ``"dd"``: every Gram block in that cone (SDSOS, DSOS), with the cones' size
    limits (:data:`CONE_LIMITS`) instead of the semidefinite ones."""
    n = field.n
    ring = field.ring
    nv = ring.nvars
    candidate_limit, target_limit, rows_limit = (CANDIDATE_LIMIT, TARGET_LIMIT, MAX_GRAM_ROWS) if cone == "psd" \
        else CONE_LIMITS
    limit_names = ("CANDIDATE_LIMIT", "TARGET_LIMIT", "MAX_GRAM_ROWS") if cone == "psd" \
        else ("CONE_CANDIDATE_LIMIT", "CONE_TARGET_LIMIT", "CONE_GRAM_ROWS")
    if bases.candidate_count(nv, degree - 1 + field_degree(field) + 2 * param_degree) > candidate_limit:
        return size_limit(bases.candidate_count(nv, degree - 1 + field_degree(field) + 2 * param_degree),
                          "candidate monomials", candidate_limit, limit_names[0])
    z_v = [m for m in monomials(nv, 1, degree // 2 + param_degree)
           if 1 <= sum(m[:n]) <= degree // 2 and sum(m[n:]) <= param_degree and m not in drop_v]
    if not bases.has_pure_powers(z_v, range(n)):
        return ("no strict certificate of this form exists (V's basis, reduced to the face the solver found, "
                "keeps no pure power of some state)")
    v_blocks = bases.character_blocks(z_v, generators)
    products = gram_products(z_v, v_blocks)
    target: set[Monomial] = set()
    widen_by_derivative(target, ring, products, enumerate(field.g), ring.support(field.D))
    box_grams, box_terms = box_multipliers(nv, n, target, with_states=True, generators=generators)
    # W's basis is widened by the multipliers' products (with and without u_j^2). A map's box form leaves it
    # alone (there the widening forced monomials of W to 0 and left no strict certificate); here it is needed:
    # without it the damped oscillator's and linear-scalar-disturbed's quadratic and van-der-pol-reversed's roa
    # over their boxes of docs/model-files.md are no longer certified, and no shipped --box run gains one
    for g in box_grams:
        sq = {tuple(2 * int(k == multiplier_variable(g.name)) for k in range(nv)), tuple([0] * nv)}
        target |= {tuple(a + b for a, b in zip(m, s)) for m in gram_products(g.basis, g.blocks) for s in sq}
    if len(target) > target_limit:
        return size_limit(len(target), "monomials in one polynomial identity", target_limit, limit_names[1])
    z_w = [m for m in bases.sos_basis(nv, target) if m not in drop]
    if len(z_w) > rows_limit or len(z_v) > rows_limit:
        return size_limit(max(len(z_w), len(z_v)), "monomials per sum-of-squares matrix", rows_limit,
                          limit_names[2])
    if not z_w or not bases.has_pure_powers(z_w, range(n)):
        return ("no strict certificate of this form exists (the Newton polytope of -V' leaves no pure power of "
                "every state in its basis)")
    w_blocks = bases.character_blocks(z_w, generators)
    terms = [Term(param(f"g{i}", ring.support(gi)), "V", derivative=i) for i, gi in enumerate(field.g)]
    terms.append(Term(param("muD", ring.support(field.D)), "V"))
    terms.extend(box_terms)
    terms.append(Term(one(ring, -1), "W"))
    grams = (Gram("V", tuple(z_v), tuple(map(tuple, v_blocks))), Gram("W", tuple(z_w), tuple(map(tuple, w_blocks))),
             *box_grams)
    if cone != "psd":
        return cone_identity(nv, grams, terms, cone)
    return lyapunov_identity(nv, grams, (), terms)


def lyapunov_identity(nv: int, grams: Sequence[Gram], scalars: Sequence[Any], terms: Sequence[Term]) -> Structure | str:
    """The program of ``terms`` (``-grad V . g - mu V D``, the multipliers' terms and ``-W``) ``= 0``, the
    smallest eigenvalue of every Gram matrix maximized with ``trace Q_V = 1``, or the size limit it
    exceeds (:data:`BLOCK_COST_LIMIT`): polynomial loops and loops with functions alike."""
    structure = Structure(
        nvars=nv,
        grams=tuple(grams),
        scalars=tuple(scalars),
        identities=(Identity("lyapunov", tuple(terms), None, "W"),),
        objective=("max_margin",), trace_one=("V",))
    return within_cost(structure)


def affordable(structure: Structure) -> Structure | None:
    """``structure`` unless its blocks cost more than :data:`BLOCK_COST_LIMIT`."""
    return structure if structure.cost() <= BLOCK_COST_LIMIT else None


def within_cost(structure: Structure) -> Structure | str:
    """``structure``, or the size limit it passes (its blocks cost more than :data:`BLOCK_COST_LIMIT`), named
    as every class's detail line names it."""
    if affordable(structure) is None:
        return size_limit(f"{structure.cost():.1e}", "work units of the program", f"{BLOCK_COST_LIMIT:.1e}",
                          "BLOCK_COST_LIMIT")
    return structure


def lyapunov_values(field: StateField, structure: Structure, mu: Fraction) -> ParameterValues:
    values = ParameterValues()
    ring = field.ring
    for i, gi in enumerate(field.g):
        values.set_poly(ring, f"g{i}", -gi, ring.support(gi))
    values.set_poly(ring, "muD", field.D * to_fmpq(-mu), ring.support(field.D))
    return values


def attempt(field: StateField, structure: Structure, mu: Fraction, search: Search) -> dict[str, Any] | None:
    """One solve at decay rate ``mu``; the exact certificate if it passes the exact check."""
    return attempt_with_solution(field, structure, mu, search)[0]


def attempt_with_solution(field: StateField, structure: Structure, mu: Fraction, search: Search
                          ) -> tuple[dict[str, Any] | None, Solution]:
    point, solution = exact_try(structure, lyapunov_values(field, structure, mu), search)
    if point is None:
        return None, solution
    V = GramPoly.of(structure.gram("V").basis, point.grams["V"])
    W = GramPoly.of(structure.gram("W").basis, point.grams["W"])
    box = box_multipliers_of(point.grams, multiplier_grams(structure))
    ok, _ = check_lyapunov(field.ring, field.g, field.D, V, W, mu, box)
    if not ok:
        return None, solution
    return {"V": V, "W": W, "mu": mu, "margin": solution.scalars["t"], "box": box}, solution


def exact_try(structure: Structure, values: ParameterValues, search: Search) -> tuple[Any, Solution]:
    """One solve, and its exact rounding when the solver's margin is not clearly negative (else None):
    what every Lyapunov attempt does before its exact check (:meth:`Search.solve_exact`, near only: an unusable
    solution has no rounding either)."""
    return search.solve_exact(structure, values, near_only=True)


def gram_faces(grams: Iterable[Gram], solution: Solution) -> frozenset[tuple[str, Monomial]]:
    """Facial reduction of a failed solve: each Gram's vanishing rows (:func:`vanishing_monomials`), else its
    kernel's support (:func:`kernel_monomials`), as (Gram, monomial) pairs to leave out."""
    return frozenset((g.name, m) for g in grams
                     for m in (vanishing_monomials(g, solution) or kernel_monomials(g, solution)))


def vanishing_monomials(gram: Gram, solution: Solution) -> frozenset[Monomial]:
    """Facial reduction: the basis monomials whose diagonal entry the solver drove to (nearly) 0.

    A positive semidefinite Gram matrix with a zero diagonal entry has a zero row, so its monomial
    contributes nothing and keeps the matrix from being positive definite, which the exact check
    needs; the search is repeated without it (the generic Newton polytope cannot see cancellations
    that the identity forces, e.g. a coefficient that must vanish with another)."""
    import numpy as np

    Q = solution.grams.get(gram.name)
    if Q is None or not solution.usable or solution.scalars.get("t", 0.0) < -FACIAL_MARGIN:
        return frozenset()  # infeasible (a clearly negative margin): no face to reduce to
    diag = np.abs(np.diag(Q))
    peak = float(diag.max()) if diag.size else 0.0
    if peak <= 0:
        return frozenset()
    return frozenset(m for m, d in zip(gram.basis, diag) if d <= FACIAL_TOL * peak)


def face_probe(structure: Structure, normalized: str) -> Structure:
    """``structure`` with every Gram matrix's floor replaced by the program's margin and the margin
    maximized (``normalized``'s trace 1): its solution lies in the relative interior of the face of
    the feasible set, where the diagonal entries that must vanish are (nearly) 0, so that
    :func:`vanishing_monomials` can name them; a program with floors that is infeasible only
    because some Gram matrix must be singular is infeasible, and shows no face."""
    from dataclasses import replace

    return replace(structure, grams=tuple(replace(g, margin=True) for g in structure.grams),
                   objective=("max_margin",), trace_one=(normalized,))


#: the kernel of a Gram matrix at the solver's point: eigenvalues below this share of the largest
KERNEL_TOL: Final = 1e-7
#: ... and a kernel vector's support: its entries above this share of its largest
KERNEL_SUPPORT_TOL: Final = 1e-3


def kernel_monomials(gram: Gram, solution: Solution) -> frozenset[Monomial]:
    """The basis monomials in the support of the numerical kernel of ``gram``'s matrix, when the
    solve ends on the boundary (margin about 0) with no vanishing diagonal entry: a face that is
    not a coordinate one (e.g. ``-V'`` whose quadratic part must be a multiple of ``(x1 + x2)^2``).
    Leaving the whole support out asks for a smaller, coordinate face inside it (there, the
    quadratic part 0), which a certificate may well have; if none does, the next solve says so."""
    import numpy as np

    Q = solution.grams.get(gram.name)
    if Q is None or not solution.usable or abs(solution.scalars.get("t", 1.0)) > FACIAL_MARGIN:
        return frozenset()
    w, U = np.linalg.eigh(Q)
    if not w.size or w[-1] <= 0:
        return frozenset()
    out: set[Monomial] = set()
    for k in np.flatnonzero(w <= KERNEL_TOL * w[-1]):
        v = np.abs(U[:, k])
        out |= {m for m, x in zip(gram.basis, v) if x > KERNEL_SUPPORT_TOL * v.max()}
    return frozenset(out)


def on_remainder_faces(structure: Structure, rebuild: Callable[[frozenset[tuple[str, Monomial]]], "Structure | str"],
                       attempt: Callable[[Structure], tuple[Any, Solution]], search: Search
                       ) -> tuple[Any, Solution]:
    """Solve ``structure`` and, while its exact check refuses, its facial reductions: the remainders'
    (the Gram matrices named ``R...``) vanishing rows, else their kernels' supports
    (:func:`vanishing_monomials`, :func:`kernel_monomials`), left out by ``rebuild(drop)``, at most
    :data:`FACIAL_ROUNDS` times (a remainder that must be singular, e.g. ``-B'`` where ``B``'s top
    degree meets the field's). What ``attempt`` found (None when nothing passed) and the last solve."""
    drop: frozenset[tuple[str, Monomial]] = frozenset()
    for _ in range(FACIAL_ROUNDS + 1):
        search.budget.check()
        found, solution = attempt(structure)
        if found is not None:
            return found, solution
        vanishing = gram_faces((g for g in structure.grams if g.name.startswith("R")), solution)
        reduced = rebuild(drop | vanishing) if vanishing else None
        if not isinstance(reduced, Structure):
            break
        drop, structure = drop | vanishing, reduced
    return None, solution


def best_decay_rate(attempt_at: Callable[[Fraction], dict[str, Any] | None], found: dict[str, Any]) -> dict[str, Any]:
    """The certificate of the largest ``mu`` found, starting from ``found`` (``mu = 0``): step down
    geometrically from :data:`MU_MAX` to the first ``mu`` proved (none when :data:`MU_MIN` is not
    proved either), then bisect geometrically. The
    time limit ends the search, never the proof: the best certificate proved so far is kept (its
    rate is a lower bound of the best, as every rate here is)."""
    lo, hi = Fraction(0), MU_MAX
    candidate = MU_MAX
    try:
        while candidate >= MU_MIN:
            better = attempt_at(candidate)
            if better is not None:
                found, lo = better, candidate
                break
            hi = candidate
            if candidate == MU_MAX and attempt_at(MU_MIN) is None:
                break  # no exponential rate at all (a critical case): one solve, not a dozen steps down
            candidate = candidate / 4
        if lo > 0:
            for _ in range(MU_BISECTION_STEPS):
                mid = Fraction(math.sqrt(float(lo) * float(hi))).limit_denominator(10**6)
                if not lo < mid < hi:
                    break
                better = attempt_at(mid)
                if better is not None:
                    found, lo = better, mid
                else:
                    hi = mid
    except BudgetExhausted:
        pass  # the time limit: keep the best certificate proved so far
    return found


#: a solve's margin (the smallest Gram eigenvalue it maximized) below minus this says the strict
#: program is infeasible: no certificate of this form; between it and 0 the program sits on the
#: boundary of feasibility, where only a certificate with a singular Gram matrix might exist
INFEASIBLE_MARGIN: Final = FACIAL_MARGIN


def failure(solution: Solution) -> str:
    """Why one solve gave no certificate, in the words of the not-certified reasons: the solver
    failed, the program is infeasible (margin clearly negative), it sits on the boundary of
    feasibility, or its solution failed the exact check (which :func:`exact_try` tries where the margin is
    not below ``-EXACT_TRY_MARGIN``)."""
    margin = solution.scalars.get("t")
    if not solution.usable or margin is None:
        return f"the solver returned no usable point (status {solution.report.raw_status})"
    if margin < -INFEASIBLE_MARGIN:
        return f"the solver proved the program infeasible (best margin {margin:.2g} < 0)"
    if margin >= -EXACT_TRY_MARGIN:
        return f"the solver's solution failed the exact check (margin {margin:.2g})"
    return (f"the program is on the boundary of feasibility (best margin {margin:.2g}): no strictly positive "
            "certificate of this form was found")


def search_degree(field: StateField, degree: int, search: Search, param_degree: int = 0, cone: str = "psd"
                  ) -> tuple[dict[str, Any] | None, str]:
    """A certificate with ``V`` of this degree (and its best decay rate), or None and why not: the
    size limit that was reached, no strict certificate of the form, the solver's verdict on the
    program, or the exact check that refused its solution. ``cone``: the Gram blocks' cone
    (:data:`CONE_WORDS`; the certificate then names it)."""
    generators = symmetry(field)
    drop: frozenset[Monomial] = frozenset()
    drop_v: frozenset[Monomial] = frozenset()
    label = f"degree {degree}" + (f" ({param_degree} in the parameters)" if field.p > field.disturbances else "")
    if cone != "psd":
        label += f" ({CONE_WORDS[cone]})"
    why = "none found"
    for _ in range(LYAPUNOV_FACIAL_ROUNDS + 1):
        structure = lyapunov_program(field, degree, generators, drop, param_degree, drop_v, cone)
        if isinstance(structure, str):
            return None, f"{label}: {structure}" + (f" (after facial reduction, where {why})" if drop or drop_v else "")
        found, solution = attempt_with_solution(field, structure, Fraction(0), search)
        if found is not None:
            break
        why = failure(solution)
        vanishing = vanishing_monomials(structure.gram("W"), solution)
        vanishing_v = vanishing_monomials(structure.gram("V"), solution)
        if not vanishing and not vanishing_v:  # no zero diagonal: try the kernels' supports
            vanishing = kernel_monomials(structure.gram("W"), solution)
            vanishing_v = kernel_monomials(structure.gram("V"), solution)
        if not vanishing and not vanishing_v:
            return None, f"{label}: {why}"
        drop = drop | vanishing
        drop_v = drop_v | vanishing_v
    else:
        return None, f"{label}: {why} (after {LYAPUNOV_FACIAL_ROUNDS} rounds of facial reduction)"
    found = best_decay_rate(lambda mu: attempt(field, structure, mu, search), found)
    found["degree"] = degree
    found["param_degree"] = param_degree
    if cone != "psd":
        found["cone"] = cone
    return found, f"{label}: found"


def stated_v(scaled: ScaledField, field: StateField, v_scaled: Poly) -> dict[str, Any]:
    """The contract's ``V``: the scaled ``V`` in the declared (shifted) states and a box's
    parameters (never a disturbance: :attr:`StateField.claim_ring`)."""
    v_orig = unscale_polynomial(field.ring, v_scaled, scaled.scaling, field.n, scaled.cleared.shifted.box)
    return terms_json(field.claim_ring, field.ring.restrict(v_orig, field.claim_ring))


def certificate_json(scaled: ScaledField, field: StateField, found: dict[str, Any]) -> dict[str, Any]:
    """The exact certificate: V in the declared (shifted) states, and the Gram matrices in the
    scaled ones (the scaling is at the document's top) over ``field``'s ring. In the clique form
    (kind ``lyapunov_cliques``) ``gram_V`` and ``gram_sigma`` are lists, one Gram matrix per clique,
    and ``cliques`` names each clique's states."""
    v_scaled = found["V_poly"] if "V_poly" in found else found["V"].poly(field.ring)
    if "cliques" in found:
        names = field.ring.names
        cliques = {"kind": "lyapunov_cliques", "degree": found["degree"], "mu_scaled": str(found["mu"]),
                   "V": stated_v(scaled, field, v_scaled), "form": found["form"],
                   "cliques": [[names[i] for i in c] for c in found["cliques"]],
                   "gram_V": [part.to_json() for part in found["V"].parts],
                   "gram_sigma": [part.to_json() for part in found["W"].parts]}
        if "cone" in found:  # only then: a certificate of the semidefinite forms is as before
            cliques["cone"] = found["cone"]
        return cliques
    if "vertices" in found:  # the vertex form (below)
        return vertex_certificate_json(stated_v(scaled, field, v_scaled), field, found)
    out = {"kind": "lyapunov", "degree": found["degree"], "mu_scaled": str(found["mu"]),
           "V": stated_v(scaled, field, v_scaled), "gram_V": found["V"].to_json(),
           "gram_sigma": found["W"].to_json()}
    if found.get("box"):
        out["box_multipliers"] = [{"variable": j, "gram": r.to_json()} for j, r in found["box"]]
        out["param_degree"] = found.get("param_degree", 0)
    if "cone" in found:
        out["cone"] = found["cone"]
    return out


def terms_json(ring: Ring, p: Poly) -> dict[str, Any]:
    """The contract's exact polynomial: ``{"terms": [["3/2", [2, 0]], ...]}``."""
    return {"terms": [[str(c), list(m)] for m, c in sorted(ring.terms(p).items(), key=lambda t: (sum(t[0]), t[0]),
                                                          reverse=False)]}


def ges_bounds(scaled: ScaledField, found: dict[str, Any]) -> tuple[Fraction, Fraction] | None:
    """Exact ``c1 <= lambda_min(P) <= lambda_max(P) <= c2`` of the quadratic ``V = x^T P x`` in the
    declared (shifted) states, or None (only for degree 2)."""
    n = scaled.n
    if "cliques" in found or "vertices" in found:
        return None  # GES figures are derived for one Gram matrix (a clique form states GAS and V's rate)
    basis = found["V"].basis
    if found["degree"] != 2 or any(any(m[n:]) for m in basis):
        return None  # GES is claimed for a quadratic V common to the box only
    nv = len(basis[0])
    Qv = found["V"].Q
    order = [basis.index(tuple(int(k == i) for k in range(nv))) for i in range(n)]
    P = declared_quadratic(scaled.scaling, [[Qv[order[i]][order[j]] for j in range(n)] for i in range(n)])
    return eigen_bounds(P)


def eigen_bounds(P: Sequence[Sequence[Fraction]]) -> tuple[Fraction, Fraction] | None:
    """Exact ``c1 > 0`` and ``c2`` with ``c1 I < P < c2 I`` (checked in rationals), or None: the
    bounds of a GES claim, on either kind of loop."""
    import numpy as np

    from lyapcheck.sos.definiteness import is_positive_definite

    n = len(P)
    lam = np.linalg.eigvalsh(np.array([[float(x) for x in row] for row in P]))
    c1 = Fraction(float(lam[0]) * (1 - 1e-6)).limit_denominator(10**12) if lam[0] > 0 else Fraction(0)
    c2 = Fraction(float(lam[-1]) * (1 + 1e-6))
    if c1 <= 0:
        return None
    eye = [[Fraction(int(i == j)) for j in range(n)] for i in range(n)]
    if not is_positive_definite([[P[i][j] - c1 * eye[i][j] for j in range(n)] for i in range(n)]):
        return None
    if not is_positive_definite([[c2 * eye[i][j] - P[i][j] for j in range(n)] for i in range(n)]):
        return None
    return c1, c2


def run(scaled: ScaledField, name: str, degrees: Sequence[int], search: Search,
        param_degrees: Sequence[int] = (0,), field: StateField | None = None,
        fallback: Callable[[list[str]], ConditionResult | None] | None = None) -> ConditionResult:
    """``quadratic`` (degrees ``(2,)``) or ``sos_gas`` (rising degrees) on ``field`` (default: the
    nominal :func:`state_field`; the robust one makes every disturbance a box coordinate); over a
    box, ``V`` may depend on the parameters up to each of ``param_degrees`` in turn (not with
    disturbances in the ring: the basis' parameter degree counts them too, and V must not depend
    on a disturbance). ``fallback``: a further form the caller tries after the dense and clique forms
    of each degree found nothing, given what was tried (it may add lines): its result when it
    certifies (``sos_gas``: :func:`lyapcheck.models.classes.vector_lyapunov.fallback`)."""
    if field is None:
        field = state_field(scaled)
    # a benchmark's knob (LYAPCHECK_FORCE_CONE): sos_gas's programs in one of the cheaper cones only
    # (the store, which keeps semidefinite certificates, is then neither read nor written)
    forced = forced_cone() if name == "sos_gas" and field.p == 0 else "psd"
    key = (store.problem_key("lyapunov", stored_problem(field, name, degrees, param_degrees))
           if store.enabled() and forced == "psd" else None)
    if key is not None:
        recalled = recall_certificate(field, key, degrees)
        if recalled is not None:
            return _certified(scaled, field, name, recalled, {"solves": [], "stored": {
                "key": key, "check": "exact, in this run"}})
    tried: list[str] = []
    limited: list[tuple[int, bool]] = []  # degrees whose dense form was too large: (degree, cliques too large)
    cone_lines: list[str] = []
    # one budget of solves for the cheaper cones, whether they run before a later degree or at the end
    cones = search.within(CONE_FALLBACK_SOLVES, "in the cheaper cones' fallback", "CONE_FALLBACK_SOLVES")
    try:
        for degree in degrees:
            for param_degree in (param_degrees if field.p and not field.disturbances else (0,)):
                search.budget.check()  # also before a degree whose program is skipped unsolved
                first = cones_first(field, degree, limited[0], search) if limited else None
                if first is not None:
                    # this degree's semidefinite forms would not leave the cones their time: the cones
                    # of the degrees already too large first, then this degree's forms all the same
                    found, more = cone_fallbacks(field, limited, cones)
                    cone_lines.extend([first, *more])
                    limited = []
                    if found is not None:
                        return _certified(scaled, field, name, found, {"solves": search.log})
                found, why = search_degree(field, degree, search, param_degree, forced)
                tried.append(why)
                dense_too_large = bool(reasons.size_limits([why]))
                clique_why = ""
                if found is None and field.p == 0 and dense_too_large:
                    # the dense form is too large: V and -V' as sums over cliques of the states
                    found, clique_why = clique_search(field, degree, search, forced)
                    tried.append(clique_why)
                if found is None and fallback is not None:
                    last = fallback(tried)
                    if last is not None:
                        return last
                if found is None and name == "sos_gas" and field.p == 0 and dense_too_large and forced == "psd":
                    # the dense form too large, the cliques' too large or failed: the cheaper cones'
                    # turn comes after every semidefinite form of every degree (below)
                    limited.append((degree, bool(reasons.size_limits([clique_why]))))
                if found is not None:
                    if key is not None and "cliques" not in found and "cone" not in found:
                        store.keep(key, {"found": found_json(found), "solves": len(search.log)})
                    return _certified(scaled, field, name, found, {"solves": search.log})
            if name == "sos_gas" and applies(field):
                # the box form failed at this degree: V affine in the parameters, proved at the box's
                # vertices (not kept in the certificate store: a later run searches again). Not for
                # quadratic, whose claim over a box is GES with one V and its bounds
                search.budget.check()
                found, why = search_vertices(field, degree, search)
                tried.append(why)
                if found is not None:
                    return _certified(scaled, field, name, found, {"solves": search.log})
    except BudgetExhausted as exc:
        late = reasons.out_of_time("a Lyapunov function", search.budget.seconds, [str(exc), *tried, *cone_lines])
        return ConditionResult(name, "inconclusive", late.summary,
                               numbers=late.numbers({"reason": str(exc), "tried": tried + cone_lines}),
                               solver={"solves": search.log})
    # the semidefinite forms found nothing: the sentence says so, as before the cones, whatever they do
    steps = ("sos_gas", "candidate") if name == "quadratic" else ("degree", "candidate")
    none = reasons.not_found("Lyapunov function", degrees, tried, steps)
    if limited:
        found, more = cone_fallbacks(field, limited, cones)
        cone_lines.extend(more)
        if found is not None:
            return _certified(scaled, field, name, found, {"solves": search.log})
    return ConditionResult(name, "not_certified", none.summary,
                           numbers={**none.numbers({"tried": tried + cone_lines}),
                                    "detail": [*none.detail, *cone_lines]},
                           solver={"solves": search.log}, property="GAS" if name != "quadratic" else None)


def stored_problem(field: StateField, name: str, degrees: Sequence[int], param_degrees: Sequence[int]
                   ) -> dict[str, Any]:
    """What decides the search of :func:`run`, for the certificate store's key: the class, its
    degrees and the exact field (ring, ``g``, ``D``, how many disturbances)."""
    return {"class": name, "degrees": list(degrees), "param_degrees": list(param_degrees),
            "ring": list(field.ring.names), "disturbances": field.disturbances,
            "g": [store.polynomial_json(field.ring, gi) for gi in field.g],
            "D": store.polynomial_json(field.ring, field.D)}


def found_json(found: dict[str, Any]) -> dict[str, Any]:
    """A found certificate (:func:`attempt`'s, with its degrees) as the store keeps it."""
    return {"degree": found["degree"], "param_degree": found.get("param_degree", 0), "mu": str(found["mu"]),
            "margin": found["margin"], "V": found["V"].to_json(), "W": found["W"].to_json(),
            "box": [[j, r.to_json()] for j, r in found["box"]]}


def recall_certificate(field: StateField, key: str, degrees: Sequence[int]) -> dict[str, Any] | None:
    """The stored certificate of ``key``, when it passes the exact
    check on ``field`` (the one this run derived) now, with a ``V`` of one of ``degrees``; None
    otherwise (no entry, a malformed one, or one that fails: the search runs as if there were none)."""
    entry = store.recall(key)
    if entry is None:
        return None
    try:
        data = entry["found"]
        nv = field.ring.nvars
        V = GramPoly.from_json(data["V"], nv)
        W = GramPoly.from_json(data["W"], nv)
        box = [(int(j), GramPoly.from_json(r, nv)) for j, r in data["box"]]
        mu = Fraction(data["mu"])
        # the entry's margin (a solver's figure) and solve count are not re-provable: not read, so
        # that nothing unchecked reaches the output (no solve ran: relative_margin is None)
        found = {"V": V, "W": W, "mu": mu, "margin": None, "box": box,
                 "degree": int(data["degree"]), "param_degree": int(data["param_degree"])}
    except (KeyError, TypeError, ValueError, ZeroDivisionError):
        return None
    # the degree the claim states is V's own (the search's basis reaches it with a positive diagonal),
    # and V, as the search's, never depends on a disturbance (the claim states it without them)
    n, d = field.n, field.disturbances
    if found["degree"] not in degrees or not V.basis or found["degree"] != 2 * max(sum(m[:n]) for m in V.basis) \
            or any(any(m[n:n + d]) for m in V.basis):
        return None
    ok, _ = check_lyapunov(field.ring, field.g, field.D, V, W, mu, box)
    return found if ok else None


def _certified(scaled: ScaledField, field: StateField, name: str, found: dict[str, Any], solver: dict[str, Any]
               ) -> ConditionResult:
    mu = found["mu"]
    T = scaled.scaling.time
    rate_v = float(mu / T)
    cert = certificate_json(scaled, field, found)
    numbers: dict[str, Any] = {"degree": found["degree"], "decay_rate_V_per_s": rate_v,
                               "relative_margin": found["margin"]}
    if name == "quadratic" and mu > 0:
        bounds = ges_bounds(scaled, found)
        if bounds is not None:
            from lyapcheck import exact

            c1, c2 = bounds
            k_bound = exact.sqrt_upper(c2 / c1, 12)
            cert.update({"c1": str(c1), "c2": str(c2), "k": str(k_bound)})
            numbers.update({"k": float(k_bound), "decay_rate_per_s": rate_v / 2})
            return ConditionResult(name, "certified",
                                   f"GES: |x(t)| <= {float(k_bound):.4g} |x0| exp(-{rate_v / 2:.4g} t) from every start "
                                   "(a quadratic V with V' <= -mu V, checked exactly)", numbers=numbers,
                                   certificate=cert, solver=solver, property="GES")
    tail = f", and V' <= -{rate_v:.4g} V (V decays exponentially from every start)" if mu > 0 else ""
    what = "a quadratic V" if found["degree"] == 2 else f"a polynomial V of degree {found['degree']}"
    if "cliques" in found:
        what += f", a sum over {len(found['cliques'])} cliques of the states,"
    if "cone" in found:
        numbers["cone"] = found["cone"]
    return ConditionResult(name, "certified", f"GAS: {what} with V' < 0 away from the equilibrium{tail} "
                                              f"(checked exactly{cone_words(found.get('cone'))})",
                           numbers=numbers, certificate=cert, solver=solver, property="GAS")


# -- a loop with functions: the same program with the recasting's relations ------------------------------
#
# (its search and exact check are :mod:`lyapcheck.models.classes.lyapunov_relations`, which reads the loop
# through :mod:`lyapcheck.models.classes.bounds`, itself built on this module; here the kinds, the claim
# and the sentence, which :mod:`lyapcheck.models.classes.claims` and verify read)
#
# A loop with functions (:class:`~lyapcheck.models.classes.recast_classes.Loop`) is read as a
# :class:`~lyapcheck.models.classes.bounds.BoundField` without disturbances: the variables V may use (the
# states, an angle through its sine and cosine, the smooth auxiliaries) move as ``N / D`` with every factor
# of ``D`` proved positive on the recasting's set S, and the identity of the polynomial case carries the
# relations' multipliers (:func:`~lyapcheck.models.classes.bounds.relation_multipliers`):
#
#     -grad V . N - mu V D - sum_i lambda_i h_i - sum_j tau_j g_j = z_W^T Q_W z_W,   Q_V, Q_W > 0,
#
# unscaled (time in seconds). On every point (z, a(z)) of the true loop the relations hold, so
# ``V' = grad V . N / D <= -mu V - W / D``. ``V`` and ``W``'s bases hold a pure power of every
# coordinate (each non-angle state, and each angle's cosine deviation ``cos - 1``, zero on the cylinder
# only at the angle's equilibrium): ``V`` is positive definite and radially unbounded in the states and
# ``V' < 0`` away from the equilibrium: GAS (modulo 2 pi in the angles). A quadratic ``V`` in the states
# alone with ``mu > 0`` gives GES as on a polynomial loop (``c1 I <= P <= c2 I``).

#: degrees of V that ``sos_gas`` tries on a loop with functions (its programs carry the relations'
#: multipliers: degree 6 would exceed TEMPLATE_GRAM_ROWS on every shipped loop)
RELATIONS_GAS_DEGREES: Final = (2, 4)
#: the certificate kind of ``quadratic`` and ``sos_gas`` on a loop with functions
RELATIONS_KIND: Final = "lyapunov_relations"
#: the kind those classes wrote on a loop with functions before they had one implementation for every loop
OLD_RELATIONS_KIND: Final = "recast"
OLD_FORMAT: Final = ("a certificate of an older format (kind recast, written before quadratic and sos_gas had one "
                     "implementation for every loop): run lyapcheck certify again to get one that verify checks")


def relations_claim(cert: Mapping[str, Any]) -> tuple[Literal["GES", "GAS"], dict[str, Any]]:
    """The property and figures a certificate of :data:`RELATIONS_KIND` proves, exactly, from the
    certificate (after its check): GES with ``k`` and the rate of ``|x|`` where it states ``c1``,
    ``c2`` and ``k``, else GAS; the degree and ``V``'s decay rate (1/s)."""
    from lyapcheck.exact import read_rational

    mu = read_rational(cert["mu"])
    figures: dict[str, Any] = {"degree": int(cert["degree"]), "decay_rate_V_per_s": mu}
    if "k" in cert:
        figures.update({"k": read_rational(cert["k"]), "decay_rate_per_s": mu / 2})
        return "GES", figures
    return "GAS", figures


def relations_sentence(cert: Mapping[str, Any]) -> str:
    """The sentence of a certificate of :data:`RELATIONS_KIND`, from the certificate alone (``verify``
    re-makes it and compares): the polynomial loops' words, and modulo 2 pi in the angles."""
    from lyapcheck.exact import read_rational

    mu = read_rational(cert["mu"])
    angles = list(cert["angles"])
    modulo = (f" modulo 2 pi in {', '.join(angles)} (the loop is periodic in {'it' if len(angles) == 1 else 'them'})"
              if angles else "")
    if "k" in cert:
        k = read_rational(cert["k"])
        return (f"GES: |x(t)| <= {float(k):.4g} |x0| exp(-{float(mu / 2):.4g} t) from every start (a quadratic V "
                "with V' <= -mu V, checked exactly on the recasting's relations)")
    degree = int(cert["degree"])
    tail = f", and V' <= -{float(mu):.4g} V (V decays exponentially from every start)" if mu > 0 else ""
    what = "a quadratic V" if degree == 2 else f"a polynomial V of degree {degree}"
    functions = [v for v in cert["v_variables"] if v in cert["auxiliaries"]]
    if functions:
        what += f" in the states and {', '.join(cert['auxiliaries'][v] for v in functions)}"
    return (f"GAS{modulo}: {what} with V' < 0 away from the equilibrium{tail} (checked exactly on the recasting's "
            "relations)")


# -- correlative sparsity: V and -V' as sums over cliques of the states (issue 43) -----------------

#: the most monomials the identity of the clique form may have (one equality each); the clique form
#: exists for networks, whose identities are long but whose Gram matrices are small
CLIQUE_TARGET_LIMIT: Final = 40_000
#: the clique forms tried, in turn: the states' closed neighbourhoods in the field's interaction
#: graph (small: a subsystem and its neighbours), then the cliques of its chordal completion
CLIQUE_FORMS: Final = ("neighbourhoods", "chordal")


def field_couplings(field: StateField) -> list[set[int]]:
    """Per state ``i``, the states ``g_i`` depends on (the field's interaction graph)."""
    n = field.n
    return [{j for m in field.ring.support(gi) for j in range(n) if m[j] > 0} for gi in field.g]


def clique_cover(field: StateField, form: str) -> list[tuple[int, ...]]:
    """The cliques of the states of one of :data:`CLIQUE_FORMS` (:mod:`lyapcheck.sos.sparsity`)."""
    from lyapcheck.sos import sparsity

    couplings = field_couplings(field)
    if form == "neighbourhoods":
        return sparsity.neighbourhood_cliques(field.n, couplings)
    return sparsity.chordal_cliques(field.n, couplings)


def clique_program(field: StateField, degree: int, generators: Sequence[Sequence[int]],
                   cliques: Sequence[tuple[int, ...]], drop: frozenset[tuple[str, Monomial]] = frozenset(),
                   cone: str = "psd") -> Structure | str:
    """The Lyapunov identity with ``V = sum_k V_k`` and ``-V' - mu V D = sum_k sigma_k``, each
    ``V_k`` (Gram ``V<k>``) and ``sigma_k`` (Gram ``W<k>``) over the monomials of clique ``k`` of
    the states (``V_k`` of degree 1 to ``degree / 2``, ``sigma_k`` Newton-reduced against the
    identity's support); ``drop``: (Gram, monomial) pairs left out (facial reduction). Or why there
    is none (a size limit, or no pure power of some state left)."""
    from lyapcheck.sos import sparsity

    ring = field.ring
    nv = ring.nvars
    v_grams: list[Gram] = []
    for k, clique in enumerate(cliques):
        basis = [m for m in sparsity.clique_candidates(clique, nv, 1, degree // 2) if (f"V{k}", m) not in drop]
        if basis:
            v_grams.append(Gram(f"V{k}", tuple(basis), tuple(map(tuple, bases.character_blocks(basis, generators)))))
    if not bases.has_pure_powers([m for g in v_grams for m in g.basis], range(field.n)):
        return ("no strict certificate of this form exists (V's bases, reduced to the face the solver found, "
                "keep no pure power of some state)")
    target: set[Monomial] = set()
    for gram in v_grams:
        widen_by_derivative(target, ring, gram_products(gram.basis, gram.blocks), enumerate(field.g),
                            ring.support(field.D))
    if len(target) > CLIQUE_TARGET_LIMIT:
        return size_limit(len(target), "monomials in one polynomial identity", CLIQUE_TARGET_LIMIT,
                          "CLIQUE_TARGET_LIMIT")
    half = max(sum(m) for m in target) // 2
    candidates = [sparsity.clique_candidates(c, nv, 1, half) for c in cliques]
    reduced = sparsity.reduce_clique_bases(cliques, candidates, target)
    w_grams = [Gram(f"W{k}", tuple(b), tuple(map(tuple, bases.character_blocks(b, generators))))
               for k, basis in enumerate(reduced) if (b := [m for m in basis if (f"W{k}", m) not in drop])]
    if any(len(g.basis) > MAX_GRAM_ROWS for g in (*v_grams, *w_grams)):
        return size_limit(max(len(g.basis) for g in (*v_grams, *w_grams)), "monomials per sum-of-squares matrix",
                          MAX_GRAM_ROWS, "MAX_GRAM_ROWS")
    if not w_grams or not bases.has_pure_powers([m for g in w_grams for m in g.basis], range(field.n)):
        return ("no strict certificate of this form exists (the Newton polytope of -V' leaves no pure power of "
                "every state in the cliques' bases)")
    terms = [Term(param(f"g{i}", ring.support(field.g[i])), gram.name, derivative=i)
             for gram in v_grams for i in sorted({i for m in gram.basis for i in range(field.n) if m[i] > 0})]
    terms += [Term(param("muD", ring.support(field.D)), gram.name) for gram in v_grams]
    terms += [Term(one(ring, -1), gram.name) for gram in w_grams]
    structure = Structure(
        nvars=nv, grams=(*v_grams, *w_grams), scalars=(),
        identities=(Identity("lyapunov", tuple(terms), None, w_grams[0].name,
                             shared=tuple(g.name for g in w_grams[1:])),),
        objective=("max_margin",))  # no trace normalization: t <= 1 fixes the scale (every Q >= t I)
    if cone != "psd":
        return cone_structure(structure, cone)
    return within_cost(structure)


def clique_attempt(field: StateField, structure: Structure, mu: Fraction, search: Search
                   ) -> tuple[dict[str, Any] | None, Solution]:
    """One solve of the clique form at decay rate ``mu``; the exact certificate if it passes."""
    from lyapcheck.sos.certificates import GramSum, check_lyapunov_cliques

    point, solution = exact_try(structure, lyapunov_values(field, structure, mu), search)
    if point is None:
        return None, solution
    parts = {g.name: GramPoly.of(g.basis, point.grams[g.name]) for g in structure.grams}
    V = GramSum(tuple(p for name, p in parts.items() if name.startswith("V")))
    W = GramSum(tuple(p for name, p in parts.items() if name.startswith("W")))
    ok, _ = check_lyapunov_cliques(field.ring, field.g, field.D, V, W, mu)
    if not ok:
        return None, solution
    # the margin relative to V's size, as the dense form's (whose V has trace 1)
    trace = sum(float(sum(Q[i][i] for i in range(len(Q)))) for name, Q in solution.grams.items() if name.startswith("V"))
    return {"V": V, "W": W, "mu": mu, "margin": solution.scalars["t"] / trace if trace > 0 else None, "box": []}, solution


def clique_search(field: StateField, degree: int, search: Search, cone: str = "psd"
                  ) -> tuple[dict[str, Any] | None, str]:
    """:func:`search_degree` in the clique form (each of :data:`CLIQUE_FORMS` in turn): a
    certificate whose ``V`` and remainder are sums over cliques of the states, or None and why.
    ``cone``: the Gram blocks' cone (:data:`CONE_WORDS`)."""
    generators = symmetry(field)
    whys: list[str] = []
    seen: list[list[tuple[int, ...]]] = []
    for form in CLIQUE_FORMS:
        cliques = clique_cover(field, form)
        if cliques in seen or len(cliques) < 2:
            continue  # the same cliques again, or one clique: the dense form, which was too large
        seen.append(cliques)
        label = f"degree {degree}, V a sum over {len(cliques)} cliques of the states ({form})"
        if cone != "psd":
            label += f" ({CONE_WORDS[cone]})"
        drop: frozenset[tuple[str, Monomial]] = frozenset()
        why = "none found"
        found = None
        for _ in range(LYAPUNOV_FACIAL_ROUNDS + 1):
            structure = clique_program(field, degree, generators, cliques, drop, cone)
            if isinstance(structure, str):
                why = structure + (f" (after facial reduction, where {why})" if drop else "")
                break
            solved = structure
            found, solution = clique_attempt(field, solved, Fraction(0), search)
            if found is not None:
                break
            why = failure(solution)
            vanishing = gram_faces(structure.grams, solution)
            if not vanishing:
                break
            drop = drop | vanishing
        if found is None:
            whys.append(f"{label}: {why}")
            continue
        found = best_decay_rate(lambda mu: clique_attempt(field, solved, mu, search)[0], found)
        found.update({"degree": degree, "param_degree": 0, "cliques": [list(c) for c in cliques], "form": form})
        if cone != "psd":
            found["cone"] = cone
        return found, f"{label}: found"
    return None, "; ".join(whys) if whys else f"degree {degree}: no clique form smaller than the whole"

# -- the vertex form of sos_gas over a box (issue 45) --------------------------------------------
#
# The vertex form of ``sos_gas`` over a box of parameters: ``V(z, u)`` affine in the
# box's normalized parameters ``u in [-1, 1]^p``, proved at the box's vertices.
#
# Where the field is multi-affine in ``u`` (a gain that multiplies a state, as in a PID loop), take
# ``V = V_0(z) + sum_j u_j V_j(z)`` with each ``V_j`` free of the states whose right-hand side holds
# ``u_j``: then ``-grad V . g - mu V D`` is multi-affine in ``u`` too, and both are positive on the whole
# box when they are at every vertex (:func:`lyapcheck.sos.certificates.check_lyapunov_vertices`, which
# checks the multi-affinity itself). The program is a point's program once per vertex, coupled through
# ``V_0`` and the free coefficients of the ``V_j``: the box form of :mod:`lyapcheck.models.classes.lyapunov`
# instead needs one remainder over the states and the parameters together, with box multipliers. On
# issue 45's PID loop (3 states, 2 gains) that form is infeasible at degree 4 and beyond the size limits
# from degree 6, while a single point already needs a ``V`` of degree 8, whose exact cancellations depend
# on the gains (``V`` common to the box, ``V_j = 0``, is infeasible even on a box 5 % wide).
#
# The certificate is a ``lyapunov`` certificate (same claim, sentence and figures, GAS) with
# ``form = "vertices"``: ``V_scaled`` (the exact ``V(z, u)`` in the scaled states and the box's
# normalized parameters), and per vertex, in :func:`~lyapcheck.sos.certificates.box_vertices` order, the
# Gram matrix of ``V`` there (``gram_V_vertices``) and of ``sigma`` (``gram_sigma_vertices``).

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
    products = gram_products(z_v, v_blocks)
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
        widen_by_derivative(target, ring, products, enumerate(g), ring.support(D))
        if len(target) > TARGET_LIMIT:
            return size_limit(len(target), "monomials in one polynomial identity", TARGET_LIMIT, "TARGET_LIMIT")
        z_w = [m for m in bases.sos_basis(nv, target) if (f"W{k}", m) not in drop]
        z_p = [m for m in z_all if (f"P{k}", m) not in drop]
        if max(len(z_w), len(z_v)) > MAX_GRAM_ROWS:
            return size_limit(max(len(z_w), len(z_v)), "monomials per sum-of-squares matrix", MAX_GRAM_ROWS,
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
    return within_cost(structure)


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


def vertex_certificate_json(stated: dict[str, Any], field: StateField, found: dict[str, Any]) -> dict[str, Any]:
    """The certificate of a vertex-form ``found`` (``stated``: ``V`` in the declared states and the box's
    parameters, :func:`lyapcheck.models.classes.lyapunov.stated_v`)."""
    return {"kind": "lyapunov", "form": "vertices", "degree": found["degree"], "mu_scaled": str(found["mu"]),
            "V": stated, "V_scaled": terms_json(field.ring, found["V_poly"]),
            "gram_V_vertices": [p.to_json() for p in found["positive"]],
            "gram_sigma_vertices": [w.to_json() for w in found["vertices"]]}


def search_vertices(field: StateField, degree: int, search: Search) -> tuple[dict[str, Any] | None, str]:
    """A vertex certificate with ``V`` of this degree (and its best decay rate), or None and why not,
    with the facial reduction of :func:`lyapcheck.models.classes.lyapunov.search_degree`."""

    label = f"degree {degree} (affine in the parameters, at the box's {2 ** field.p} vertices)"
    drop: frozenset[tuple[str, Monomial]] = frozenset()
    why = "none found"
    for _ in range(LYAPUNOV_FACIAL_ROUNDS + 1):
        structure = vertex_program(field, degree, drop)
        if isinstance(structure, str):
            return None, f"{label}: {structure}" + (f" (after facial reduction, where {why})" if drop else "")
        found, solution = vertex_attempt(field, structure, Fraction(0), search)
        if found is not None:
            break
        why = failure(solution)
        vanishing = frozenset((g.name, m) for g in structure.grams for m in vanishing_monomials(g, solution))
        if not vanishing:
            vanishing = frozenset((g.name, m) for g in structure.grams for m in kernel_monomials(g, solution))
        if not vanishing:
            return None, f"{label}: {why}"
        drop = drop | vanishing
    else:
        return None, f"{label}: {why} (after {LYAPUNOV_FACIAL_ROUNDS} rounds of facial reduction)"
    solved = structure
    found = best_decay_rate(lambda mu: vertex_attempt(field, solved, mu, search)[0], found)
    found["degree"] = degree
    found["param_degree"] = 1
    return found, f"{label}: found"


# -- cheaper cones: SDSOS and DSOS programs where the semidefinite ones are too large (issue 43) ---------
#
# Where ``sos_gas``'s dense program is beyond its size limits and the clique form finds nothing (too
# large as well, or no certificate of its form), the dense program is solved again with every Gram
# block in a cheaper cone (:attr:`lyapcheck.sos.structure.Gram.cone`): scaled diagonally dominant
# ("sdd", SDSOS: second-order cones), then diagonally dominant ("dd", DSOS: a linear program), and,
# where the clique form was too large, the clique form in the same cones. Both are inner
# approximations of the semidefinite cone (Ahmadi & Majumdar), so a certificate found is an SOS
# certificate like any other: the exact check is the same (its Gram matrices proved positive definite
# exactly, :func:`lyapcheck.sos.definiteness.is_positive_definite`, whose diagonal-dominance tests
# decide these matrices in O(n^2)), and ``verify`` re-checks it without knowing the cone. The
# certificate names the cone (``"cone": "sdd"``), and only then, so that every other one is as before.
# They run after every semidefinite form, unless a later degree's semidefinite forms would not leave
# them their time: then before those (:func:`cones_first` states the rule).

#: the cheaper cones tried in turn, and their words in a sentence or a detail line
FALLBACK_CONES: Final = ("sdd", "dd")
CONE_WORDS: Final[Mapping[str, str]] = {"sdd": "SDSOS, scaled diagonally dominant Gram matrices",
                                        "dd": "DSOS, diagonally dominant Gram matrices"}
#: the cones' size limits and their budget of solves: :mod:`lyapcheck.tolerances` (``CONE_*``, with
#: the estimates that order the forms, :func:`cones_first`)
CONE_LIMITS: Final = (CONE_CANDIDATE_LIMIT, CONE_TARGET_LIMIT, CONE_GRAM_ROWS)
#: the benchmark knob: ``sdd`` or ``dd`` makes every program of sos_gas (dense and cliques) use that
#: cone, never the semidefinite one (for measuring the cones alone; not a user option)
FORCE_CONE_ENV: Final = "LYAPCHECK_FORCE_CONE"


def forced_cone() -> str:
    """The cone :data:`FORCE_CONE_ENV` forces (``"psd"`` when unset); InvalidParameter otherwise."""
    import os

    from lyapcheck.errors import InvalidParameter

    value = os.environ.get(FORCE_CONE_ENV, "").strip().lower()
    if not value:
        return "psd"
    if value not in ("psd", *FALLBACK_CONES):
        raise InvalidParameter(FORCE_CONE_ENV, "one of psd, sdd, dd (a benchmark knob)", value)
    return value


def cone_words(cone: str | None) -> str:
    """``, SDSOS: scaled diagonally dominant Gram matrices`` for a sentence's parenthesis ('' for psd)."""
    if cone is None or cone == "psd":
        return ""
    return f"; {CONE_WORDS[cone]}"


def cone_structure(structure: Structure, cone: str) -> Structure | str:
    """``structure`` with every Gram block in ``cone``, or the cone's size limit it exceeds."""
    from lyapcheck.sos.structure import with_cone

    out = with_cone(structure, cone)  # type: ignore[arg-type]
    if out.cone_size() > CONE_SIZE_LIMIT:
        return size_limit(out.cone_size(), "decisions of the cone program", CONE_SIZE_LIMIT, "CONE_SIZE_LIMIT")
    return out


def cone_identity(nv: int, grams: Sequence[Gram], terms: Sequence[Term], cone: str) -> Structure | str:
    """:func:`lyapunov_identity`'s program with every Gram block in ``cone`` (its size limit instead
    of :data:`BLOCK_COST_LIMIT`)."""
    structure = Structure(
        nvars=nv,
        grams=tuple(grams),
        scalars=(),
        identities=(Identity("lyapunov", tuple(terms), None, "W"),),
        objective=("max_margin",), trace_one=("V",))
    return cone_structure(structure, cone)


def cone_fallbacks(field: StateField, limited: Sequence[tuple[int, bool]], within: Search
                   ) -> tuple[dict[str, Any] | None, list[str]]:
    """:func:`cone_fallback` at each degree whose dense semidefinite form was too large (``limited``:
    ``(degree, the clique form too large as well)``, rising), ``within`` the run's budget of
    :data:`CONE_FALLBACK_SOLVES` solves (:meth:`~lyapcheck.models.engines.search.Search.within`, one for
    the whole run): a certificate or None, and the detail lines. Run after the semidefinite forms of
    those degrees have found nothing (and before a later degree's where :func:`cones_first` says so),
    so it can only add a certificate: where its budget (or the class's time limit, the safety net)
    ends it, the class's answer is the semidefinite forms' one, and a detail line says where the
    fallback stopped."""
    whys: list[str] = []
    try:
        for degree, cliques_too_large in limited:
            found, more = cone_fallback(field, degree, within, cliques_too_large)
            whys.extend(more)
            if found is not None:
                return found, whys
    except BudgetExhausted as exc:
        whys.append(f"the cheaper cones' fallback was stopped: {exc}")
    return None, whys


def cones_first(field: StateField, degree: int, pending: tuple[int, bool], search: Search) -> str | None:
    """Whether the cheaper cones of a degree already too large (``pending``, as :func:`cone_fallbacks`
    takes it) go before the semidefinite forms of ``degree``: the words of a detail line saying so, or
    None (the forms keep their order).

    The rule (issue 43: a limit falls through to the next method, never ends the search while one
    could still run): the semidefinite forms of ``degree`` (the dense program, and each clique form,
    where within their size limits) are estimated at :data:`~lyapcheck.tolerances.FORM_SOLVES_ESTIMATE`
    solves of their first program, and the cones' first form (the dense SDSOS program of the pending
    degree, or its clique form where the dense one is beyond the cones' limits) likewise
    (:func:`~lyapcheck.models.engines.search.estimated_seconds`). When the two together do not fit in
    the class's time limit less the estimates of the work already done
    (:meth:`~lyapcheck.models.engines.search.Budget.fits`: estimates only, never the clock, so that the
    order is the same on a loaded machine), the cones run first; the semidefinite forms run after them all the same (the time limit, never
    this rule, may end them). Where they fit, nothing changes: the cones come after every semidefinite
    form, as before. An order only: every certificate is decided by the same exact checks."""
    generators = symmetry(field)
    form = 0.0
    dense = lyapunov_program(field, degree, generators)
    if isinstance(dense, Structure):
        form += estimated_seconds(dense)
    for cover in CLIQUE_FORMS:
        cliques = clique_cover(field, cover)
        if len(cliques) >= 2:
            program = clique_program(field, degree, generators, cliques)
            if isinstance(program, Structure):
                form += estimated_seconds(program)
    if form == 0.0:
        return None  # every semidefinite form of this degree is refused by its size limits, at once
    cone_degree, cliques_too_large = pending
    cone = FALLBACK_CONES[0] if FALLBACK_CONES else None
    if cone is None:
        return None
    reserve = 0.0
    dense_cone = lyapunov_program(field, cone_degree, generators, cone=cone)
    if isinstance(dense_cone, Structure):
        reserve = estimated_seconds(dense_cone)
    elif cliques_too_large:
        for cover in CLIQUE_FORMS:
            cliques = clique_cover(field, cover)
            program = clique_program(field, cone_degree, generators, cliques, cone=cone) if len(cliques) >= 2 else ""
            if isinstance(program, Structure):
                reserve = estimated_seconds(program)
                break
    form, reserve = form * FORM_SOLVES_ESTIMATE, reserve * FORM_SOLVES_ESTIMATE
    budget = search.budget
    if budget.fits(form, reserve):
        return None
    return (f"the cheaper cones of degree {cone_degree} were tried before the semidefinite forms of degree {degree}: "
            f"those estimated at {form:.3g} s and the cones at {reserve:.3g} s exceed the time limit's "
            f"{max(budget.seconds - budget.estimated, 0.0):.3g} s left by the estimates of the work done")


def cone_fallback(field: StateField, degree: int, search: Search, cliques_too_large: bool
                  ) -> tuple[dict[str, Any] | None, list[str]]:
    """The dense program of this degree in each of :data:`FALLBACK_CONES` in turn, and the clique
    form in them where it was too large as a semidefinite program: a certificate (naming its cone)
    or None, and the detail lines of what was tried."""
    whys: list[str] = []
    for cone in FALLBACK_CONES:
        search.budget.check()
        found, why = search_degree(field, degree, search, 0, cone)
        whys.append(why)
        if found is None and cliques_too_large:
            found, why = clique_search(field, degree, search, cone)
            whys.append(why)
        if found is not None:
            return found, whys
    return None, whys
