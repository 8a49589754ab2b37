"""``quadratic`` and ``sos_gas`` on a discrete-time map: a global polynomial Lyapunov function of
``e+ = F(e)`` (the equilibrium shifted to 0, ``F(0) = 0``), found by SOS and checked exactly.

The certificate (kinds :data:`QUADRATIC_KIND` and :data:`SOS_KIND`), in the declared (shifted)
states: ``V = z_V^T Q_V z_V`` over the monomials of degree 1 to ``d``, ``Q_V > 0``, and

    V(e) - V(F(e)) - mu V(e) = z_W^T Q_W z_W,   Q_W > 0,   0 <= mu < 1,

with a pure power of every state in ``z_V`` and in ``z_W``. Then ``V >= lambda |e|-powers`` is
positive definite and radially unbounded, and ``V(F(e)) - V(e) <= -mu V(e) - W(e) < 0`` away from
0: the equilibrium of the map is globally asymptotically stable, and ``V(e_k) <= (1 - mu)^k V(e_0)``.
For a quadratic ``V = e^T P e`` with ``mu > 0`` this is GES of the map:
``|e_k| <= sqrt(c2/c1) |e_0| r^k`` with ``r = sqrt(1 - mu)`` and ``c1 I < P < c2 I`` (exact rational
bounds; ``k`` and ``r`` rounded up). For a linear map ``F(e) = A e`` the identity is the discrete
Lyapunov (Stein) inequality ``P - A^T P A - mu P > 0``.

Only the decrease polynomial differs from continuous time (``V(F(e)) - V(e)`` instead of
``grad V . f``), but it is not linear in ``Q_V`` through a derivative term of the program
language (:mod:`lyapcheck.sos.structure`): ``V(F(e))`` is a composition. So ``V`` is carried by
its coefficients ``c_a`` (free scalars, one per monomial ``e^a`` that ``z_V^T Q_V z_V`` can have),
and the program has two identities, both linear in the decisions:

    sum_a c_a e^a - z_V^T Q_V z_V = 0                                  (V is its Gram form)
    sum_a c_a ((1 - mu) e^a - F(e)^a) - z_W^T Q_W z_W = 0              (the decrease)

with the polynomials ``(1 - mu) e^a - F(e)^a`` as parameters (compiled once, re-solved for every
``mu``). Everything else is the continuous classes' machinery, called, not copied: the sign
symmetries and blocks (:func:`lyapcheck.models.classes.lyapunov.symmetry`), the Newton-reduced
remainder basis, the size limits, the rounding and projection (:mod:`lyapcheck.sos.rounding`),
facial reduction, the decay-rate search (:func:`~lyapcheck.models.classes.lyapunov.best_decay_rate`)
and the exact checks of ``V`` (:func:`~lyapcheck.sos.certificates.check_positive_definite_v`).

The map is the :class:`~lyapcheck.models.loop.field.ShiftedField` of a model whose ``[dynamics]``
give next values: its numerators are ``F`` (each denominator a constant, already divided out).
No scaling of the states is applied: the certificate is in the declared shifted states.

Over a box of parameters (``certify --box``, :mod:`lyapcheck.models.loop.boxes`) the ring holds the
states, then the box's parameters normalized to ``u in [-1, 1]`` (``F = F(e, u)``, the fixed point
proved not to move over the box when the box was read). ``V`` stays a polynomial of the states alone,
common to the box (as the continuous ``quadratic`` over a box, whose GES claim needs one ``V``), and
the decrease carries the S-procedure multipliers ``r_j (1 - u_j^2)``
(:func:`lyapcheck.models.engines.search.box_multipliers`):

    V(e) - V(F(e, u)) - mu V(e) - sum_j r_j(e, u) (1 - u_j^2) = z_W^T Q_W z_W,   Q_W > 0,  Q_rj >= 0,

so on the box (``1 - u_j^2 >= 0``) ``V(F(e, u)) - V(e) <= -mu V(e) - W(e, u) < 0`` away from 0 for
every parameter value of the box, and the GES figures hold with the same ``k`` and ``r`` for each.
A box widened after the fact changes the normalization, so the identity fails in ``verify``.
"""

from __future__ import annotations

from fractions import Fraction
from typing import Any, Callable, Final, Literal, Mapping, Sequence

from lyapcheck import tolerances as tol
from lyapcheck.models.classes import discrete_linearization, lyapunov
from lyapcheck.models.classes.claims import box_prefix, discrete_lyapunov_sentence
from lyapcheck.models.engines import reasons
from lyapcheck.models.engines.reasons import size_limit
from lyapcheck.models.engines.search import (Budget, BudgetExhausted, ParameterValues, Search,
                                             box_multipliers, box_multipliers_from_json, box_multipliers_of,
                                             literal, multiplier_grams, one, param)
from lyapcheck.models.loop.field import ShiftedField, StateField
from lyapcheck.results import ConditionResult
from lyapcheck.sos import bases
from lyapcheck.sos.certificates import BoxMultipliers, GramPoly, box_terms, check_positive_definite_v
from lyapcheck.sos.polynomials import Monomial, Poly, Ring, monomials, to_fmpq
from lyapcheck.sos.structure import Gram, Identity, Scalar, Structure, Term

#: the certificate kinds (``verify`` dispatches on them)
QUADRATIC_KIND: Final = "discrete_quadratic"
SOS_KIND: Final = "discrete_sos"
#: degrees of V that ``sos_gas`` tries on a map, in turn (``quadratic`` is degree 2 alone): the
#: decrease has degree ``deg V * deg F``, so the programs grow faster than in continuous time
SOS_GAS_DEGREES: Final = (2, 4, 6)
#: the degrees ``sos_gas`` tries on a map over a box: the box's coordinates join the decrease and its
#: multipliers, and at degree 6 one solve of a cubic map over a one-parameter box took more than the class's
#: time limit (MODEL_CLASS_TIME_LIMIT_S, 60 s) where degree 4 takes about a second
BOX_SOS_GAS_DEGREES: Final = (2, 4)
#: the largest decay rate tried: ``V(F) <= (1 - mu) V`` with ``mu >= 1`` asks ``V(F) <= 0``, which
#: no ``F`` other than 0 meets; the search stays below 1 so that ``r = sqrt(1 - mu) > 0``
MU_CEILING: Final = Fraction(1)
#: significant digits of the upper-rounded figures ``k`` and ``r`` (:func:`lyapcheck.exact.sqrt_upper`)
FIGURE_DIGITS: Final = 12

ClassName = Literal["quadratic", "sos_gas"]
#: the S-procedure terms a map's decrease carries beyond ``V - V(F) - mu V`` (a box's ``r_j (1 - u_j^2)``, a map
#: with functions' relations): given the decrease's monomials, its Grams, scalars, terms and the monomials they add
Multipliers = Callable[[set[Monomial]], tuple[list[Gram], list[Scalar], list[Term], set[Monomial]]]
#: one solve at decay rate ``mu`` on a built program: the exact certificate (or None) and the solver's answer
Attempt = Callable[[Structure, Sequence[Monomial], Fraction], tuple["dict[str, Any] | None", Any]]


class NotAMap(ValueError):
    """The shifted loop is not a polynomial map this module can read (a non-constant denominator,
    or ``F(0) != 0``)."""


def map_polynomials(shifted: ShiftedField) -> tuple[Ring, tuple[Poly, ...]]:
    """``F`` of ``e+ = F(e)`` in the ring of the states alone (disturbances held at 0), exactly, then a
    box's normalized parameters if the map has one (``F(e, u)``); :class:`NotAMap` naming what is missing
    when the loop is not a polynomial map with ``F(0) = 0`` (for every ``u``)."""
    full = shifted.ring
    n = shifted.n
    kept = full.names[:n] + shifted.box_names
    ring = Ring(kept)
    zero = {name: Fraction(0) for name in full.names if name not in kept}
    F = []
    for name, num, den in zip(full.names, shifted.numerators, shifted.denominators):
        if not den.is_constant():
            raise NotAMap(f"the next value of {name} has a denominator depending on the states (a polynomial map "
                          "is needed)")
        F.append(full.restrict(full.substitute(num * (1 / den.leading_coefficient()), zero), ring))
    origin = {name: Fraction(0) for name in ring.names[:n]}
    if any(ring.substitute(fi, origin) != ring.zero() for fi in F):
        raise NotAMap("F(0) != 0: the equilibrium is not a fixed point of the map"
                      + (" for every value of the box" if shifted.box is not None else ""))
    return ring, tuple(F)


def compose(ring: Ring, p: Poly, F: Sequence[Poly]) -> Poly:
    """``p(F(e))`` exactly (``F`` one image per state, the states the ring's first variables; a box's
    parameters, the ring's last ones, are left as they are)."""
    return ring.compose(p, list(F) + list(ring.gens()[len(F):]))


def map_degree(ring: Ring, F: Sequence[Poly]) -> int:
    """The largest total degree of the map's components (at least 1)."""
    return max([sum(m) for fi in F for m in ring.support(fi)] + [1])


def symmetry(ring: Ring, F: Sequence[Poly]) -> list[tuple[int, ...]]:
    """The sign changes ``s`` of the states with ``F(s e) = s F(e)``: the condition of the
    continuous classes on ``g`` (:func:`lyapcheck.models.classes.lyapunov.symmetry`, called with
    ``F`` in place of ``g`` and ``D = 1``). ``V(s e) = V(e)`` then gives ``V(F(s e)) = V(F(e))``."""
    return lyapunov.symmetry(StateField(ring=ring, g=tuple(F), D=ring.constant(1)))


# -- the program --------------------------------------------------------------------------------------

def coefficient_name(k: int) -> str:
    return f"c{k}"


def decrease_name(k: int) -> str:
    return f"f{k}"


def discrete_program(ring: Ring, F: Sequence[Poly], degree: int, generators: Sequence[Sequence[int]],
                     drop: frozenset[Monomial] = frozenset(), drop_v: frozenset[Monomial] = frozenset(),
                     multipliers: Multipliers | None = None, allowed: Callable[[Monomial], bool] | None = None
                     ) -> tuple[Structure, list[Monomial]] | str:
    """The program for a ``V`` of this degree and the monomials ``e^a`` its coefficients stand for,
    or why there is none: a size limit (the continuous classes' constants, named), or no strict
    certificate of this form. ``drop``/``drop_v``: monomials the remainder's / ``V``'s basis leaves
    out (facial reduction, as :func:`lyapcheck.models.classes.lyapunov.lyapunov_program`).
    ``multipliers``: the decrease's S-procedure terms (default: a box's, none at a point; a map with
    functions: its relations', :mod:`lyapcheck.models.classes.map_relations`); ``allowed``: the monomials
    W's basis may hold (default: all; a relation may reduce some, as a cosine's square)."""
    nv = ring.nvars
    n = len(F)
    top = degree * map_degree(ring, F)
    if bases.candidate_count(nv, top) > lyapunov.CANDIDATE_LIMIT:
        return size_limit(bases.candidate_count(nv, top), "candidate monomials", lyapunov.CANDIDATE_LIMIT,
                          "CANDIDATE_LIMIT")
    # V is of the states alone (common to a box): its monomials carry no parameter
    z_v = [m + (0,) * (nv - n) for m in monomials(n, 1, degree // 2) if m + (0,) * (nv - n) not in drop_v]
    if not bases.has_pure_powers(z_v, range(n)):
        return ("no strict certificate of this form exists (V's basis, reduced to the face the solver found, "
                "keeps no pure power of some state)")
    v_blocks = bases.character_blocks(z_v, generators)
    alphas = sorted(lyapunov.gram_products(z_v, v_blocks))
    supports = [decrease_support(ring, F, a) for a in alphas]
    target = set().union(*supports)
    # over a box, the multipliers' bases lie in the half Newton polytope of the decrease; W's basis is not widened
    # by their products (as the continuous box form does): the monomials that adds (e.g. y^4 u where V(F) has no
    # y^8 u^2) are forced to 0 in W, and no strict certificate is left (tried on x+ = a x + y^2/5, y+ = y/2)
    if multipliers is None:
        box_grams, box_terms_ = box_multipliers(nv, n, target, with_states=True, generators=generators)
        extra_scalars: list[Scalar] = []
    else:
        box_grams, extra_scalars, box_terms_, added = multipliers(target)
        target |= added
    if len(target) > lyapunov.TARGET_LIMIT:
        return size_limit(len(target), "monomials in one polynomial identity", lyapunov.TARGET_LIMIT, "TARGET_LIMIT")
    z_w = [m for m in bases.sos_basis(nv, target) if m not in drop and (allowed is None or allowed(m))]
    if len(z_w) > lyapunov.MAX_GRAM_ROWS or len(z_v) > lyapunov.MAX_GRAM_ROWS:
        return size_limit(max(len(z_w), len(z_v)), "monomials per sum-of-squares matrix", lyapunov.MAX_GRAM_ROWS,
                          "MAX_GRAM_ROWS")
    if not z_w or not bases.has_pure_powers(z_w, range(n)):
        return ("no strict certificate of this form exists (the Newton polytope of V - V(F) leaves no pure power "
                "of every state in its basis)")
    w_blocks = bases.character_blocks(z_w, generators)
    # identity 1: V's coefficients are its Gram form's
    gram_terms = [Term(literal(ring, {a: 1}), coefficient_name(k)) for k, a in enumerate(alphas)]
    gram_terms.append(Term(one(ring, -1), "V"))
    # identity 2: sum_a c_a ((1 - mu) e^a - F^a) = W
    decrease_terms = [Term(param(decrease_name(k), s), coefficient_name(k)) for k, s in enumerate(supports)]
    decrease_terms.extend(box_terms_)  # over a box: - sum_j r_j (1 - u_j^2)
    decrease_terms.append(Term(one(ring, -1), "W"))
    structure = Structure(
        nvars=nv,
        grams=(Gram("V", tuple(z_v), tuple(map(tuple, v_blocks))), Gram("W", tuple(z_w), tuple(map(tuple, w_blocks))),
               *box_grams),
        scalars=tuple(Scalar(coefficient_name(k)) for k in range(len(alphas))) + tuple(extra_scalars),
        identities=(Identity("gram_V", tuple(gram_terms), None, "V"),
                    Identity("decrease", tuple(decrease_terms), None, "W")),
        objective=("max_margin",), trace_one=("V",))
    within = lyapunov.within_cost(structure)
    return within if isinstance(within, str) else (within, alphas)


def decrease_support(ring: Ring, F: Sequence[Poly], a: Monomial) -> set[Monomial]:
    """The monomials of ``(1 - mu) e^a - F(e)^a`` for any ``mu`` (``e^a`` always kept)."""
    return set(ring.support(compose(ring, ring.monomial(a), F))) | {tuple(a)}


def decrease_values(ring: Ring, F: Sequence[Poly], alphas: Sequence[Monomial], mu: Fraction) -> ParameterValues:
    values = ParameterValues()
    for k, a in enumerate(alphas):
        e_a = ring.monomial(a)
        values.set_poly(ring, decrease_name(k), e_a * to_fmpq(1 - mu) - compose(ring, e_a, F),
                        decrease_support(ring, F, a))
    return values


# -- the exact check (the certificate alone and the map) ---------------------------------------------

def check_forms(V: GramPoly, W: GramPoly, mu: Fraction, n: int) -> tuple[bool, str]:
    """What a map's certificate asks of its forms, exactly, whatever its identity: ``0 <= mu < 1``, ``V``
    positive definite, radially unbounded (:func:`~lyapcheck.sos.certificates.check_positive_definite_v`) and
    a polynomial of the ``n`` states alone (the ring's first variables), ``Q_W > 0`` with a pure power of every
    state in W's basis (``W > 0`` away from the fixed point, whatever the other variables)."""
    if not 0 <= mu < MU_CEILING:
        return False, "the decay rate mu must satisfy 0 <= mu < 1"
    ok, why = check_positive_definite_v(V, n)
    if not ok:
        return False, why
    if not bases.has_pure_powers(W.basis, range(n)):
        return False, "W's basis must hold a pure power of every state (so that V(F) - V < 0 away from 0)"
    if not W.positive_definite():
        return False, "Q_W is not positive definite (exact)"
    if any(any(m[n:]) for m in V.basis):
        return False, "V must be a polynomial of the states alone (one V for every value of the box)"
    return True, "the forms are"


def check_discrete_lyapunov(ring: Ring, F: Sequence[Poly], V: GramPoly, W: GramPoly, mu: Fraction,
                            box: BoxMultipliers = ()) -> tuple[bool, str]:
    """``V - V(F) - mu V - sum_j r_j (1 - u_j^2) = W`` exactly, ``0 <= mu < 1``, ``V`` positive definite,
    radially unbounded (:func:`~lyapcheck.sos.certificates.check_positive_definite_v`) and of the states
    alone, ``W`` with ``Q_W > 0`` and a pure power of every state, each multiplier ``r_j`` PSD on a box
    variable (none at a point): then ``V(F(e, u)) - V(e) <= -mu V(e) - W(e, u) < 0`` away from 0 for every
    ``u`` of the box."""
    n = len(F)
    ok, why = check_forms(V, W, mu, n)
    if not ok:
        return False, why
    if any(not n <= j < ring.nvars for j, _ in box):
        return False, "a box multiplier names a variable that is not one of the box's parameters"
    boxed, box_why = box_terms(ring, box)
    if box_why is not None:
        return False, box_why
    v = V.poly(ring)
    if v - compose(ring, v, F) - v * to_fmpq(mu) - boxed != W.poly(ring):
        return False, "the identity V - V(F) - mu V = W does not hold exactly" + (" (with the box's multipliers)"
                                                                                    if box else "")
    if box:
        return True, ("Q_V > 0, Q_W > 0, the box's multipliers PSD and V - V(F) - mu V - sum r_j (1 - u_j^2) = W, "
                      "exactly (discrete-time map, every value of the box)")
    return True, "Q_V > 0, Q_W > 0 and V - V(F) - mu V = W, exactly (discrete-time map)"


# -- the search ---------------------------------------------------------------------------------------

def attempt(ring: Ring, F: Sequence[Poly], structure: Structure, alphas: Sequence[Monomial], mu: Fraction,
            search: Search) -> tuple[dict[str, Any] | None, Any]:
    """One solve at decay rate ``mu``; the exact certificate if it passes the exact check."""
    if mu >= MU_CEILING:
        return None, None  # no solve: no map but 0 meets V(F) <= (1 - mu) V with mu >= 1
    point, solution = lyapunov.exact_try(structure, decrease_values(ring, F, alphas, mu), search)
    if point is None:
        return None, solution
    V = GramPoly.of(structure.gram("V").basis, point.grams["V"])
    W = GramPoly.of(structure.gram("W").basis, point.grams["W"])
    box = box_multipliers_of(point.grams, multiplier_grams(structure))
    ok, _ = check_discrete_lyapunov(ring, F, V, W, mu, box)
    if not ok:
        return None, solution
    return {"V": V, "W": W, "mu": mu, "margin": solution.scalars["t"], "box": box}, solution


def search_degree(ring: Ring, F: Sequence[Poly], degree: int, search: Search) -> tuple[dict[str, Any] | None, str]:
    """A certificate with ``V`` of this degree and its best decay rate, or None and why not (the
    loop of :func:`lyapcheck.models.classes.lyapunov.search_degree`, on the map's program)."""
    generators = symmetry(ring, F)
    return search_program(
        degree, lambda drop, drop_v: discrete_program(ring, F, degree, generators, drop, drop_v),
        lambda structure, alphas, mu: attempt(ring, F, structure, alphas, mu, search))


def search_program(degree: int,
                   build: Callable[[frozenset[Monomial], frozenset[Monomial]], tuple[Structure, list[Monomial]] | str],
                   solve: Attempt) -> tuple[dict[str, Any] | None, str]:
    """:func:`search_degree` on any map's program: ``build`` (the faces left out of W's and V's bases) and
    ``solve`` (one solve and its exact check at a decay rate): facial reduction at ``mu = 0``, then the best
    decay rate (:func:`~lyapcheck.models.classes.lyapunov.best_decay_rate`)."""
    drop: frozenset[Monomial] = frozenset()
    drop_v: frozenset[Monomial] = frozenset()
    label = f"degree {degree}"
    why = "none found"
    for _ in range(lyapunov.LYAPUNOV_FACIAL_ROUNDS + 1):
        built = build(drop, drop_v)
        if isinstance(built, str):
            return None, f"{label}: {built}" + (f" (after facial reduction, where {why})" if drop or drop_v else "")
        structure, alphas = built
        found, solution = solve(structure, alphas, Fraction(0))
        if found is not None:
            break
        why = lyapunov.failure(solution)
        vanishing = lyapunov.vanishing_monomials(structure.gram("W"), solution)
        vanishing_v = lyapunov.vanishing_monomials(structure.gram("V"), solution)
        if not vanishing and not vanishing_v:
            vanishing = lyapunov.kernel_monomials(structure.gram("W"), solution)
            vanishing_v = lyapunov.kernel_monomials(structure.gram("V"), solution)
        if not vanishing and not vanishing_v:
            return None, f"{label}: {why}"
        drop, drop_v = drop | vanishing, drop_v | vanishing_v
    else:
        return None, f"{label}: {why} (after {lyapunov.LYAPUNOV_FACIAL_ROUNDS} rounds of facial reduction)"
    found = lyapunov.best_decay_rate(lambda mu: solve(structure, alphas, mu)[0], found)
    found["degree"] = degree
    return found, f"{label}: found"


def run(shifted: ShiftedField, name: ClassName, search: Search | None = None,
        degrees: Sequence[int] | None = None, budget: Budget | None = None) -> ConditionResult:
    """``quadratic`` (degree 2) or ``sos_gas`` (the rising :data:`SOS_GAS_DEGREES`) on the map
    ``e+ = F(e)`` of ``shifted`` (its numerators read as next values). ``search``: the class's
    search (default: its own, on ``budget``, by default the continuous classes' safety net,
    MODEL_CLASS_TIME_LIMIT_S)."""
    if degrees is None and name == "sos_gas":
        from lyapcheck.degrees import searched_degrees

        # the ladder under certify's --degree, as every other sos_gas search (its not_certified sentence
        # suggests --degree); over a box it stops at 4 unless --degree asks for more, at its cost
        degrees = searched_degrees(BOX_SOS_GAS_DEGREES if shifted.box is not None else SOS_GAS_DEGREES)
    if degrees is None:
        degrees = (2,)
    try:
        ring, F = map_polynomials(shifted)
    except NotAMap as exc:
        return ConditionResult(name, "not_applicable", f"not a polynomial map: {exc}")
    if search is None:
        # the continuous classes' safety net (the work itself is bounded by counts: the facial-reduction
        # rounds and the decay-rate steps)
        search = Search(ring, budget if budget is not None else
                        Budget(tol.MODEL_CLASS_TIME_LIMIT_S, "lyapcheck.tolerances.MODEL_CLASS_TIME_LIMIT_S"))
    tried: list[str] = []
    try:
        for degree in degrees:
            search.budget.check()
            found, why = search_degree(ring, F, degree, search)
            tried.append(why)
            if found is not None:
                return certified(shifted, ring, name, found, {"solves": search.log})
    except BudgetExhausted as exc:
        late = reasons.out_of_time("a Lyapunov function of the map", search.budget.seconds, [str(exc), *tried])
        return ConditionResult(name, "inconclusive", late.summary,
                               numbers=late.numbers({"reason": str(exc), "tried": tried, "time": "discrete"}),
                               solver={"solves": search.log})
    # (a V the user knows is proved on a sublevel set by the candidate class, lyapcheck.models.classes.discrete_regions)
    steps = ("sos_gas", "candidate") if name == "quadratic" else ("degree", "candidate")
    none = reasons.not_found("Lyapunov function of the discrete-time map", degrees, tried, steps)
    return ConditionResult(name, "not_certified", none.summary,
                           numbers=none.numbers({"tried": tried, "time": "discrete"}),
                           solver={"solves": search.log}, property="GAS" if name != "quadratic" else None)


# -- the claim ----------------------------------------------------------------------------------------

def quadratic_matrix_of(V: GramPoly, n: int) -> list[list[Fraction]] | None:
    """``P`` of ``V = e^T P e`` when ``V``'s basis is exactly the ``n`` states' degree-1 monomials, else None
    (the monomials may carry a box's parameters after the states, at exponent 0)."""
    if len(V.basis) != n or any(sum(m) != 1 or any(m[n:]) for m in V.basis):
        return None
    nv = len(V.basis[0])
    order = [V.basis.index(tuple(int(k == i) for k in range(nv))) for i in range(n)]
    return [[V.Q[order[i]][order[j]] for j in range(n)] for i in range(n)]


def ges_figures(V: GramPoly, mu: Fraction, n: int) -> dict[str, Fraction] | None:
    """Exact ``c1, c2`` with ``c1 I < P < c2 I`` and upper roundings ``k >= sqrt(c2/c1)``,
    ``r >= sqrt(1 - mu)``: the figures of ``|e_k| <= k |e_0| r^k``; None unless ``V`` is quadratic
    with ``mu > 0``."""
    from lyapcheck import exact

    P = quadratic_matrix_of(V, n)
    if P is None or mu <= 0:
        return None
    bounds = lyapunov.eigen_bounds(P)
    if bounds is None:
        return None
    c1, c2 = bounds
    return {"c1": c1, "c2": c2, "k": exact.sqrt_upper(c2 / c1, FIGURE_DIGITS),
            "r": exact.sqrt_upper(1 - mu, FIGURE_DIGITS)}


def certified(shifted: ShiftedField, ring: Ring, name: ClassName, found: dict[str, Any], solver: dict[str, Any]
              ) -> ConditionResult:
    V, W, mu = found["V"], found["W"], found["mu"]
    n = shifted.n
    figures = ges_figures(V, mu, n) if name == "quadratic" else None
    kind = QUADRATIC_KIND if figures is not None else SOS_KIND
    cert: dict[str, Any] = {"kind": kind, "time": "discrete", "degree": found["degree"], "mu": str(mu),
                            "V": lyapunov.terms_json(ring, V.poly(ring)), "gram_V": V.to_json(),
                            "gram_W": W.to_json()}
    if found.get("box"):  # over a box: the S-procedure multipliers of 1 - u_j^2 (the box itself is the document's)
        cert["box_multipliers"] = [{"variable": j, "gram": r.to_json()} for j, r in found["box"]]
    numbers: dict[str, Any] = {"degree": found["degree"], "time": "discrete", "decay_rate_V_per_step": float(mu),
                               "relative_margin": found["margin"]}
    if figures is not None:
        cert.update({key: str(value) for key, value in figures.items()})
        numbers.update({"k": float(figures["k"]), "contraction_per_step": float(figures["r"])})
    return ConditionResult(name, "certified", discrete_lyapunov_sentence(kind, found["degree"], mu, figures), numbers=numbers,
                           certificate=cert, solver=solver, property="GES" if figures is not None else "GAS")


# -- verify -------------------------------------------------------------------------------------------

def _decrease_parts(ring: Ring, cert: Mapping[str, Any]) -> tuple[GramPoly, GramPoly, Fraction, BoxMultipliers]:
    """What :func:`check_discrete_lyapunov` takes, read from a certificate's JSON (``gram_V``, ``gram_W``,
    ``mu``, ``box_multipliers``) in the map's ring: every map's certificate of ``V(F) - V <= -mu V`` states
    them alike. Raises KeyError, TypeError or ValueError where they are malformed."""
    nv = ring.nvars
    return (GramPoly.from_json(cert["gram_V"], nv), GramPoly.from_json(cert["gram_W"], nv), Fraction(cert["mu"]),
            box_multipliers_from_json(cert.get("box_multipliers", []), nv))


def verify(shifted: ShiftedField, status: str, data: Mapping[str, Any]) -> tuple[bool, str]:
    """Re-check a condition of a discrete-time map from its JSON (``ConditionResult.to_json``) and the
    map alone, without a solver: the identity and the definiteness exactly, the stated ``V``, the
    figures (``c1 I < P < c2 I``, ``k^2 >= c2 / c1``, ``r^2 >= 1 - mu``), the stated property and the
    sentence. A status other than ``certified`` claims nothing to re-check."""
    if status != "certified":
        return True, f"status {status}: no certificate to check"
    try:
        cert = data["certificate"]
        kind = cert["kind"]
        if kind not in (QUADRATIC_KIND, SOS_KIND) or cert.get("time") != "discrete":
            return False, f"not a certificate of a discrete-time map (kind {kind!r})"
        ring, F = map_polynomials(shifted)
        n = len(F)
        V, W, mu, box = _decrease_parts(ring, cert)
        degree = int(cert["degree"])
    except (KeyError, TypeError, ValueError, ZeroDivisionError) as exc:
        return False, f"malformed certificate: {exc}"
    if box and shifted.box is None:
        return False, "box multipliers in the certificate of a map without a box"
    ok, why = check_discrete_lyapunov(ring, F, V, W, mu, box)
    if not ok:
        return False, why
    if lyapunov.terms_json(ring, V.poly(ring)) != cert.get("V"):
        return False, "the stated V is not the certificate's Gram V"
    if degree != 2 * max(sum(m) for m in V.basis):
        return False, "the stated degree is not V's"
    figures = None
    if kind == QUADRATIC_KIND:
        P = quadratic_matrix_of(V, n)
        if P is None or mu <= 0:
            return False, "GES needs a quadratic V (every state, degree 1) and mu > 0"
        try:
            figures = {key: Fraction(cert[key]) for key in ("c1", "c2", "k", "r")}
        except (KeyError, TypeError, ValueError, ZeroDivisionError) as exc:
            return False, f"malformed figures: {exc}"
        ok, why = _check_ges_figures(P, mu, figures)
        if not ok:
            return False, why
    ok, why_figures = _check_stated_figures(data, mu, figures)
    if not ok:
        return False, why_figures
    if data.get("property") != ("GES" if kind == QUADRATIC_KIND else "GAS"):
        return False, f"a {kind} certificate does not prove {data.get('property')}"
    prefix = box_prefix(shifted.box, "certified") if shifted.box is not None else ""
    if data.get("summary") != prefix + discrete_lyapunov_sentence(kind, degree, mu, figures):
        return False, "the stated sentence is not the certificate's"
    return True, why


def _check_stated_figures(data: Mapping[str, Any], mu: Fraction, figures: Mapping[str, Fraction] | None
                          ) -> tuple[bool, str]:
    """The figures beside the status (floats, for readers) say no more than the certificate proves:
    ``V``'s decay rate at most ``mu``, ``k`` and the contraction ``r`` at least the certificate's."""
    try:
        if float(data["decay_rate_V_per_step"]) > float(mu):
            return False, "the stated decay rate of V exceeds the certified one"
        if figures is not None and (float(data["k"]) < float(figures["k"])
                                    or float(data["contraction_per_step"]) < float(figures["r"])):
            return False, "the stated k or contraction per step is below the certified one"
    except (KeyError, TypeError, ValueError) as exc:
        return False, f"malformed figures: {exc}"
    return True, "the stated figures are the certificate's"


def _check_ges_figures(P: Sequence[Sequence[Fraction]], mu: Fraction, figures: Mapping[str, Fraction]
                       ) -> tuple[bool, str]:
    from lyapcheck.sos.definiteness import is_positive_definite

    n = len(P)
    c1, c2, k, r = figures["c1"], figures["c2"], figures["k"], figures["r"]
    eye = [[Fraction(int(i == j)) for j in range(n)] for i in range(n)]
    if not (c1 > 0 and is_positive_definite([[P[i][j] - c1 * eye[i][j] for j in range(n)] for i in range(n)])
            and is_positive_definite([[c2 * eye[i][j] - P[i][j] for j in range(n)] for i in range(n)])):
        return False, "c1 I < P < c2 I does not hold"
    if k < 0 or k * k < c2 / c1:
        return False, "k is below sqrt(c2/c1)"
    if r < 0 or r * r < 1 - mu:
        return False, "r is below sqrt(1 - mu)"
    return True, "a quadratic V with V(F) <= (1 - mu) V and c1 I < P < c2 I: GES of the map, exactly"


# -- a map over a box: what is taken ------------------------------------------------------------------

#: the classes a polynomial map takes over a box of parameters (``certify --box``): one V for every value
#: (``barrier`` and ``reach_avoid``: one B or V of the states, :mod:`lyapcheck.models.classes.discrete_safety`, with
#: the box's multipliers in its step identities; refuted at a value of the box,
#: :mod:`lyapcheck.models.classes.discrete_safety_box`)
BOX_CLASSES: Final = ("linearization", "quadratic", "sos_gas", "roa", "candidate", "barrier", "reach_avoid",
                      "sos_bound")


def not_over_box(name: str) -> str:
    """The ``not_applicable`` sentence of a class other than :data:`BOX_CLASSES` on a map over a box."""
    return (f"{name} is decided at one parameter value only on a map (certify a point with --set NAME=VALUE); "
            "over a box, linearization proves LES, quadratic GES, sos_gas GAS, roa and candidate a region of "
            "attraction, barrier safety, reach_avoid reach-avoid and sos_bound an ultimate bound for every value "
            "of the box")


# -- linearization over a box: one Stein certificate for every Jacobian of the box --------------------

#: the method a map's linearization over a box states (its certificate carries ``"time": "discrete"``)
BOX_STEIN_METHOD: Final = "box_stein"


def jacobian_map(ring: Ring, F: Sequence[Poly]) -> tuple[Poly, ...]:
    """``A(u) e``: each component's terms of degree exactly 1 in the states (any degree in a box's
    parameters), the linear map whose matrix is the Jacobian at the fixed point, exactly."""
    n = len(F)
    out = []
    for fi in F:
        linear = {m: c for m, c in ring.terms(fi).items() if sum(m[:n]) == 1}
        out.append(ring.from_terms(linear) if linear else ring.zero())
    return tuple(out)


def jacobian_at(ring: Ring, A: Sequence[Poly], shifted: ShiftedField, point: Mapping[str, Fraction]
                ) -> list[list[Fraction]]:
    """The exact Jacobian at the fixed point for one parameter value of the box (``point``, by name): the
    linear map ``A(u) e`` of :func:`jacobian_map` at that value's normalized ``u = (p - centre) / half``."""
    assert shifted.box is not None
    n = len(A)
    box = shifted.box
    at = {coordinate: (point[name] - box.center(name)) / box.half(name)
          for coordinate, name in zip(shifted.box_names, box.names)}
    units = [tuple(int(k == j) for k in range(ring.nvars)) for j in range(n)]
    return [[Fraction(ring.terms(ring.substitute(a, at)).get(unit, 0)) for unit in units] for a in A]


def run_linearization_box(shifted: ShiftedField, budget: Budget | None = None) -> ConditionResult:
    """``linearization`` of a map over a box: a quadratic ``V = e^T P e`` common to the box with
    ``V(A(u) e) - V(e) <= -mu V(e) - W(e, u)`` for every ``u`` (the quadratic class's program on the linear
    map ``A(u) e``, box multipliers and all). Then every ``A(u)`` has ``A(u)^T P A(u) - P < 0``: every
    eigenvalue of modulus < 1, so the fixed point is locally exponentially stable for every value of the
    box. First the box's corners and centre are decided exactly at their values
    (:func:`~lyapcheck.models.classes.discrete_linearization.refute_over_box`): an unstable one is ``refuted``
    for the box, naming it. None found is ``not_certified`` (a box reaching an unstable value strictly inside
    has none; a stable box may need a ``P`` that depends on the parameters, not taken here)."""
    from lyapcheck.models.classes.claims import DISCRETE_BOX_STEIN_SENTENCE

    try:
        ring, F = map_polynomials(shifted)
    except NotAMap as exc:
        return ConditionResult("linearization", "not_applicable", f"not a polynomial map: {exc}")
    A = jacobian_map(ring, F)
    assert shifted.box is not None
    # an unstable corner (or centre) first: exact and cheap, and it decides the box where no P could exist
    unstable = discrete_linearization.refute_over_box(lambda point: jacobian_at(ring, A, shifted, point), shifted.box)
    if unstable is not None:
        return unstable
    search = Search(ring, budget if budget is not None else
                    Budget(tol.MODEL_CLASS_TIME_LIMIT_S, "lyapcheck.tolerances.MODEL_CLASS_TIME_LIMIT_S"))
    try:
        found, why = search_degree(ring, A, 2, search)
    except BudgetExhausted as exc:
        late = reasons.out_of_time("a Stein certificate common to the box", search.budget.seconds, [str(exc)])
        return ConditionResult("linearization", "inconclusive", late.summary,
                               numbers=late.numbers({"reason": str(exc), "time": "discrete"}),
                               solver={"solves": search.log})
    if found is None:
        none = reasons.reason("no P > 0 with A(p)^T P A(p) - P < 0 for every p of the box was found (" + why + ")",
                              (), "a narrower box, or certify a point with --set NAME=VALUE")
        return ConditionResult("linearization", "not_certified", none.summary,
                               numbers=none.numbers({"time": "discrete"}), solver={"solves": search.log})
    V, W, mu = found["V"], found["W"], found["mu"]
    cert: dict[str, Any] = {"time": "discrete", "method": BOX_STEIN_METHOD, "mu": str(mu),
                            "jacobian_map": [lyapunov.terms_json(ring, a) for a in A],
                            "gram_V": V.to_json(), "gram_W": W.to_json(),
                            "box_multipliers": [{"variable": j, "gram": r.to_json()} for j, r in found["box"]]}
    return ConditionResult("linearization", "certified", DISCRETE_BOX_STEIN_SENTENCE, certificate=cert,
                           numbers={"time": "discrete"},
                           solver={"solves": search.log})


def verify_linearization_box(shifted: ShiftedField, status: str, data: Mapping[str, Any]) -> tuple[bool, str]:
    """Re-check a map's ``linearization`` over a box: ``A(u) e`` re-derived from the shifted map with the box's
    coordinates, the identity with its multipliers, ``V`` quadratic and positive definite, exactly; a
    refutation by the point decision at its stated value of the box
    (:func:`~lyapcheck.models.classes.discrete_linearization.verify_box_point`)."""
    if status == "refuted":
        try:
            ring, F = map_polynomials(shifted)
        except NotAMap as exc:
            return False, f"not a polynomial map: {exc}"
        A = jacobian_map(ring, F)
        assert shifted.box is not None
        return discrete_linearization.verify_box_point(lambda point: jacobian_at(ring, A, shifted, point),
                                                       shifted.box, dict(data))
    if status != "certified":
        return False, f"a {status} linearization over a box, which a map never states"
    try:
        if data.get("time") != "discrete" or data.get("method") != BOX_STEIN_METHOD:
            return False, f"not a map's linearization over a box (method {data.get('method')!r})"
        ring, F = map_polynomials(shifted)
        n = len(F)
        V, W, mu, box = _decrease_parts(ring, data)
    except (KeyError, TypeError, ValueError, ZeroDivisionError) as exc:
        return False, f"malformed certificate: {exc}"
    A = jacobian_map(ring, F)
    if data.get("jacobian_map") != [lyapunov.terms_json(ring, a) for a in A]:
        return False, "the stored Jacobian differs from the map's over the box"
    if quadratic_matrix_of(V, n) is None:
        return False, "V must be quadratic in the states (V = e^T P e)"
    ok, why = check_discrete_lyapunov(ring, A, V, W, mu, box)
    if not ok:
        return False, why
    return True, "one P > 0 with A(u)^T P A(u) - P < 0 for every u of the box (box multipliers), exactly"
