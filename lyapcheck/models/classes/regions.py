"""``roa`` and ``candidate``: sublevel sets ``{V <= c}`` proved inside the region of attraction, by SOS, on
both kinds of loop: a polynomial or rational loop (below), and a loop with functions, proved on its
recasting's relations by the same level program and V step with the relations' multipliers added (the last
part of this module, :func:`certify_region`, :func:`relations_enlarge`).
The ball-arithmetic route is another engine (:mod:`lyapcheck.models.classes.recast_interval`).

Certificate (kind Sublevel of :mod:`lyapcheck.sos.certificates`), in scaled coordinates:

    -grad V . g - s (c - V) = sigma,   Q_V > 0,  Q_s > 0,  Q_sigma > 0,  c > 0,

with ``V``'s basis holding every state, ``s`` without a constant term and a pure power of every
state in ``sigma``'s basis. On ``{V <= c}`` minus the equilibrium, ``-grad V . g >= sigma > 0``,
so ``V' < 0`` there (``D > 0``); the set is compact (``V >= lambda |z|^2``) and forward invariant,
and LaSalle's principle sends every trajectory that starts in it to the equilibrium.

The level (:func:`largest_level`): for a fixed ``V`` the condition is linear in ``(s, sigma)``
for each ``c``; ``c`` is bisected on the solver's feasibility up to :data:`LEVEL_REL_TOL`, and
the largest feasible ``c`` whose solution passes the exact check is the certified level (lower
ones are tried if it fails). A certified level never exceeds the true supremum (that is what the
exact check proves); the bisection's top is an estimate of that supremum from samples of
``V' >= 0``, so it is also reported.

``roa`` enlarges ``V`` iteratively from the linearization's quadratic Lyapunov function. Each
round: the level step above gives ``c`` and the multiplier ``s``; then ``V`` is rescaled to level
1 and, with ``s`` fixed, the condition is linear in ``V``: the V step minimizes the sum of ``V``
over sample points of the simulated region of attraction (or of a box around the current set)
that the set does not contain yet, with ``Q_V >= floor I``. The rounds stop when the covered share
stops growing or the class's time runs out; the best certified set is the answer.

``candidate`` is the user's own ``V``: first the global test (``-grad V . g = sigma``, GAS), then
its largest certified level.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field as dc_field, replace
from fractions import Fraction
from typing import TYPE_CHECKING, Any, Final, Sequence

import numpy as np

from lyapcheck import tolerances
from lyapcheck.degrees import searched_degrees
from lyapcheck.models.loop.field import ScaledField, Scaling, StateField, linear_images
from lyapcheck.models.classes.lyapunov import CANDIDATE_LIMIT, FACIAL_ROUNDS, TARGET_LIMIT, affordable, field_degree, \
    symmetry, vanishing_monomials, widen_by_derivative
from lyapcheck.models.engines.numeric import NumericPoly
from lyapcheck.models.classes.recast_classes import (EPSILONS, Loop, _dyadic, certificate_head, common_denominator,
                                                    lie, prove_denominators, prove_nonnegative, state_square, v_names)
from lyapcheck.models.engines import reasons
from lyapcheck.models.engines.recast_sos import ConditionCertificate, check_condition
from lyapcheck.models.engines.search import (EXACT_TRY_MARGIN, Budget, BudgetExhausted, ParameterValues, Search,
                                             SolvesSpent, box_multipliers, box_multipliers_of, box_support,
                                             multiplier_grams, one, param)
from lyapcheck.models.language.recast import written_poly
from lyapcheck.results import ConditionResult
from lyapcheck.sos import bases
from lyapcheck.sos.certificates import GramPoly, check_containment, check_lyapunov, check_sublevel, lie_derivative
from lyapcheck.sos.polynomials import Monomial, Poly, Ring, monomials, to_fmpq
from lyapcheck.sos.program import Gram, Identity, Scalar, Solution, Structure, Term

if TYPE_CHECKING:  # pragma: no cover
    from lyapcheck.models.classes.bounds import BoundField

#: relative width at which the level bisection stops (the certified level is within this of the
#: largest level the solver finds feasible)
LEVEL_REL_TOL: Final = 1e-3
#: a level counts as feasible in the bisection when the solve's margin (smallest eigenvalue of the
#: Gram matrices, scaled coordinates) exceeds this: at the supremum itself the margin is 0 and the
#: solver returns noise of either sign (1e-13 seen), which the exact check then refuses
LEVEL_MARGIN_MIN: Final = 1e-8
#: at most this many bisection solves per level
LEVEL_MAX_SOLVES: Final = 24
#: exact attempts at levels below the smallest numerically feasible one (each half the last), after
#: every feasible level failed its exact check
LEVEL_EXACT_HALVINGS: Final = 3
#: degrees of V that ``roa`` enlarges to after the quadratic start, in turn (rounds each)
ROA_DEGREES: Final = (4, 6, 8)
#: rounds of the V step per degree (stopped early when the covered share does not grow for
#: ROA_STALE_ROUNDS rounds)
ROA_ROUNDS: Final = 30
ROA_STALE_ROUNDS: Final = 3
#: over a box of parameters: V of degree 4 only, and this many rounds (a box's programs carry the
#: parameters and its multipliers: a solve costs 5-10 times a point's; on the reversed Van der Pol
#: over mu in [0.8, 1.2] the full search reached 88 % of the box's common region in 55 s)
BOX_ROA_DEGREES: Final = (4,)
BOX_ROA_ROUNDS: Final = 8
# the enlarging rounds spend at most lyapcheck.tolerances.ROA_ENLARGE_SOLVES solves (a count, the
# same rounds on any machine); the rest of the class's work is the exact check of the best set and its ball
#: the V step keeps Q_V >= ROA_FLOOR I (V positive definite with room for the exact check)
ROA_FLOOR: Final = 1e-6
#: extra half-degree of the multiplier s beyond the least that balances the degrees: on the
#: reversed Van der Pol oscillator the least one stalled the enlargement at 70 % of the simulated
#: region of attraction, one more reached 99.8 % (301 x 301 grid)
MULTIPLIER_EXTRA: Final = 1
#: the V step weighs the samples outside the current set nearest to it (this share of them, by V)
VSTEP_NEAREST: Final = 0.25
#: ... each sample's monomial vector normalized (far samples do not outweigh near ones); on the
#: reversed Van der Pol (101 x 101 grid) the two together took the covered share from 96.6 % in
#: 10.4 s (every outside sample, unnormalized) to 99.5 % in 4.8 s
VSTEP_NORMALIZE: Final = True
#: over a box, the multiplier s may carry the parameters up to this degree
MULTIPLIER_PARAM_DEGREE: Final = 1
#: the largest Gram basis the region searches build (rows)
MAX_GRAM_ROWS: Final = 120
#: sample points drawn to estimate the supremum of the level (per state: a grid of this many)
SUPREMUM_SAMPLES: Final = 4000


@dataclass
class LevelCertificate:
    V: GramPoly
    level: Fraction
    s: GramPoly
    sigma: GramPoly
    margin: float
    box: list[tuple[int, GramPoly]] = dc_field(default_factory=list)

    def to_json(self) -> dict[str, Any]:
        out: dict[str, Any] = {"kind": "sublevel", "level_scaled": str(self.level), "gram_V": self.V.to_json(),
                               "gram_s": self.s.to_json(), "gram_sigma": self.sigma.to_json()}
        if self.box:
            out["box_multipliers"] = [{"variable": j, "gram": r.to_json()} for j, r in self.box]
        return out


@dataclass
class BallCertificate:
    """A level of the linearization's quadratic ``V`` proved by norm bounds (kind QuadraticBall of
    :mod:`lyapcheck.sos.certificates`): the start of ``roa`` where the SOS level step does not fit
    (many states) or finds nothing. It has no multiplier, so it does not seed the V step."""

    V: GramPoly
    level: Fraction
    radius: Fraction
    lam: Fraction
    p_bar: Fraction
    m: Fraction
    margin: float = 0.0
    box: list[tuple[int, GramPoly]] = dc_field(default_factory=list)
    s: GramPoly | None = None

    def to_json(self) -> dict[str, Any]:
        return {"kind": "quadratic_ball", "level_scaled": str(self.level), "gram_V": self.V.to_json(),
                "radius_scaled": str(self.radius), "lambda": str(self.lam), "p_bar": str(self.p_bar), "m": str(self.m)}


#: the quadratic ball's radius is this share of the largest one the numerical bound allows
BALL_RADIUS_SHARE: Final = Fraction(99, 100)


def quadratic_ball(field: StateField, V: GramPoly) -> BallCertificate | None:
    """The largest level of the quadratic ``V`` that :func:`~lyapcheck.sos.certificates.check_quadratic_ball`
    proves (a point of parameters only: over a box the linear part depends on the parameters)."""
    from lyapcheck.sos.certificates import check_quadratic_ball, sphere_bound

    ring = field.ring
    n = field.n
    if ring.nvars != n or any(sum(m) != 1 for m in V.basis):
        return None
    idx = [V.basis.index(tuple(int(k == i) for k in range(n))) for i in range(n)]
    P = np.array([[float(V.Q[idx[i]][idx[j]]) for j in range(n)] for i in range(n)])
    L = np.zeros((n, n))
    coefficients: list[list[tuple[int, float]]] = []
    for i, gi in enumerate(field.g):
        row = []
        for mono, c in ring.terms(gi).items():
            if sum(mono) == 1:
                L[i, mono.index(1)] = float(c)
            elif sum(mono) >= 2:
                row.append((sum(mono), abs(float(c)) * float(sphere_bound(mono))))
        coefficients.append(row)
    M = -(P @ L + L.T @ P)
    eig_p = np.linalg.eigvalsh(P)
    eig_m = np.linalg.eigvalsh(M)
    if eig_p[0] <= 0 or eig_m[0] <= 0:
        return None

    def below(x: float) -> Fraction:
        return Fraction(x * (1 - 1e-6)).limit_denominator(10**9)

    lam, m = below(float(eig_p[0])), below(float(eig_m[0]))
    p_bar = Fraction(float(eig_p[-1]) * (1 + 1e-6)).limit_denominator(10**9) + Fraction(1, 10**9)

    def room(r: float) -> float:  # m r - 2 p_bar |b(r)|: positive while the decrease is proved
        b = [sum(c * r ** d for d, c in row) for row in coefficients]
        return float(m) * r - 2 * float(p_bar) * math.sqrt(sum(x * x for x in b))

    if not any(coefficients):  # a linear field: any radius; the level is a figure, pick a large one
        r_top = 1e6
    else:
        lo, hi = 0.0, 1.0
        while room(hi) > 0 and hi < 1e12:
            lo, hi = hi, hi * 2
        for _ in range(60):
            mid = (lo + hi) / 2
            lo, hi = (mid, hi) if room(mid) > 0 else (lo, mid)
        r_top = lo
    if not r_top > 0:
        return None
    for share in (BALL_RADIUS_SHARE, Fraction(9, 10), Fraction(1, 2)):
        radius = Fraction(r_top).limit_denominator(10**9) * share
        level = lam * radius * radius
        ok, _ = check_quadratic_ball(ring, field.g, V, level, radius, lam, p_bar, m)
        if ok:
            return BallCertificate(V, level, radius, lam, p_bar, m)
    return None


def multiplier_half_degree(field: StateField, v_degree: int, extra: int = MULTIPLIER_EXTRA) -> int:
    """``s`` of degree ``2k``: ``deg(s V) >= deg(grad V . g)`` at least, and ``k >= 1``, plus ``extra``."""
    dg = max((sum(m) for gi in field.g for m in field.ring.support(gi)), default=1)
    return max(1, math.ceil((dg - 1) / 2)) + extra


def level_structure(field: StateField, V: GramPoly, generators: Sequence[Sequence[int]],
                    drop: frozenset[Monomial] = frozenset()) -> Structure | None:
    """The level step's program; the multiplier one degree richer than needed where that fits in
    :data:`MAX_GRAM_ROWS` (many states), else the least."""
    for extra in sorted({MULTIPLIER_EXTRA, 0}, reverse=True):
        structure = _level_structure(field, V, generators, drop, extra)
        if structure is not None:
            return structure
    return None


def _level_structure(field: StateField, V: GramPoly, generators: Sequence[Sequence[int]],
                     drop: frozenset[Monomial], extra: int) -> Structure | None:
    ring = field.ring
    n = field.n
    nv = ring.nvars
    v_poly = V.poly(ring)
    v_degree = max(sum(m) for m in V.basis) * 2
    ks = multiplier_half_degree(field, v_degree, extra)
    pd = MULTIPLIER_PARAM_DEGREE if field.p else 0
    if bases.candidate_count(nv, max(v_degree - 1 + field_degree(field), v_degree + 2 * ks) + 2 * pd) > CANDIDATE_LIMIT:
        return None
    z_s = [m for m in monomials(nv, 1, ks + pd) if 1 <= sum(m[:n]) <= ks and sum(m[n:]) <= pd]
    s_blocks = bases.character_blocks(z_s, generators)
    lv = lie_derivative(ring, v_poly, field.g)
    v_support = set(ring.support(v_poly)) | {tuple([0] * nv)}
    s_products = {tuple(a + b for a, b in zip(z_s[i], z_s[j])) for idx in s_blocks for i in idx for j in idx}
    target = set(ring.support(lv)) | {tuple(a + b for a, b in zip(m, v)) for m in s_products for v in v_support}
    box_grams, box_terms = box_multipliers(nv, n, target, with_states=True, generators=generators)
    target |= box_support(box_grams, nv)
    if len(target) > TARGET_LIMIT:
        return None
    z_sigma = [m for m in bases.sos_basis(nv, target) if m not in drop]
    if not z_sigma or not bases.has_pure_powers(z_sigma, range(n)) or max(len(z_sigma), len(z_s)) > MAX_GRAM_ROWS:
        return None
    sigma_blocks = bases.character_blocks(z_sigma, generators)
    terms = (Term(param("Vc", v_support), "s"), *box_terms, Term(one(ring, -1), "sigma"))
    return affordable(Structure(nvars=nv, grams=(Gram("s", tuple(z_s), tuple(map(tuple, s_blocks))),
                                                 Gram("sigma", tuple(z_sigma), tuple(map(tuple, sigma_blocks))),
                                                 *box_grams),
                                scalars=(), identities=(Identity("sublevel", terms,
                                                                 param("LV", ring.support(lv) or [tuple([0] * nv)]),
                                                                 "sigma"),),
                                objective=("max_margin",)))


def level_values(field: StateField, structure: Structure, V: GramPoly, c: Fraction) -> ParameterValues:
    ring = field.ring
    v_poly = V.poly(ring)
    values = ParameterValues()
    ident = structure.identities[0]
    values.set_poly(ring, "LV", -lie_derivative(ring, v_poly, field.g), ident.constant.support)  # type: ignore[union-attr]
    values.set_poly(ring, "Vc", v_poly - ring.constant(c), ident.terms[0].coefficients.support)
    return values


def level_attempt(field: StateField, structure: Structure, V: GramPoly, c: Fraction, search: Search,
                  exact: bool) -> tuple[LevelCertificate | None, Solution]:
    values = level_values(field, structure, V, c)
    solution = search.solve(structure, values)
    if not solution.usable or solution.scalars.get("t", 0.0) < -EXACT_TRY_MARGIN or not exact:
        return None, solution
    point = search.exact(structure, solution, values)
    if point is None:
        return None, solution
    s = GramPoly.of(structure.gram("s").basis, point.grams["s"])
    sigma = GramPoly.of(structure.gram("sigma").basis, point.grams["sigma"])
    box = box_multipliers_of(point.grams, multiplier_grams(structure))
    ok, _ = check_sublevel(field.ring, field.g, V, c, s, sigma, box)
    return (LevelCertificate(V, c, s, sigma, solution.scalars["t"], box) if ok else None), solution


def supremum_estimate(field: StateField, V: GramPoly, radius: float) -> float | None:
    """``min V`` over sampled points with ``V' >= 0`` (a numerical upper bound of the true supremum
    of the certifiable level), sampling the ball of ``radius`` (scaled coordinates); None if no
    sample has ``V' >= 0``."""
    ring = field.ring
    v_poly = V.poly(ring)
    v_num = NumericPoly(ring, v_poly)
    dv_num = NumericPoly(ring, lie_derivative(ring, v_poly, field.g))
    rng = np.random.default_rng(20261125)
    n = field.n
    directions = rng.normal(size=(SUPREMUM_SAMPLES, n))
    directions /= np.linalg.norm(directions, axis=1, keepdims=True)
    radii = np.linspace(radius / 400, radius, 400)
    best = math.inf
    for u in box_samples(field.p):  # the parameters of a box at its corners and centre
        for chunk in np.array_split(directions, 8):
            pts = (chunk[:, None, :] * radii[None, :, None]).reshape(-1, n)
            full = np.hstack([pts, np.tile(u, (pts.shape[0], 1))]) if field.p else pts
            dv = dv_num(full)
            v = v_num(full)
            bad = dv >= 0
            if np.any(bad):
                best = min(best, float(np.min(v[bad])))
    return best if math.isfinite(best) else None


def box_samples(p: int) -> list[np.ndarray]:
    """The normalized parameters of a box at which numerical estimates are made: the centre and
    the corners (only the centre, an empty vector, without a box)."""
    import itertools

    if p == 0:
        return [np.zeros(0)]
    return [np.zeros(p)] + [np.array(c, dtype=float) for c in itertools.product((-1.0, 1.0), repeat=p)]


def on_states(field: StateField, points: np.ndarray) -> np.ndarray:
    """State points padded with the box's parameters at their centre (V of a box class is common)."""
    return np.hstack([points, np.zeros((points.shape[0], field.p))]) if field.p else points


#: the upward search of a level without a sampled top (:func:`largest_level` with ``grow``): the
#: level is multiplied by this while the solver finds it feasible, at most LEVEL_GROW_STEPS times
LEVEL_GROWTH: Final = 8.0
LEVEL_GROW_STEPS: Final = 16


def largest_level(field: StateField, V: GramPoly, search: Search, c_top: float,
                  generators: Sequence[Sequence[int]], grow: bool = False) -> LevelCertificate | None:
    """The largest certified level below ``c_top``: the levels the level program finds feasible (a margin
    above :data:`LEVEL_MARGIN_MIN`, floating point), searched by
    :func:`~lyapcheck.models.classes.level_search.largest_proved_level` (down by quarters from a failed
    ``c_top``, then a geometric bisection to :data:`LEVEL_REL_TOL`, :data:`LEVEL_MAX_SOLVES` solves at most),
    then every feasible level tried exactly, largest first.

    With ``grow``, ``c_top`` is only a first guess (no sample had ``V' >= 0``): while the level
    program is feasible there the level is multiplied by :data:`LEVEL_GROWTH`, and the bisection
    runs between the last feasible and the first infeasible level. Each feasible level is an SOS
    lower bound of ``min {V : V' >= 0, x != 0}``, so the set needs no sample of the boundary."""
    from lyapcheck.models.classes.level_search import LevelSteps, largest_proved_level

    first_program = level_structure(field, V, generators)
    if first_program is None or not c_top > 0:
        return None
    program: Structure = first_program
    drop: frozenset[Monomial] = frozenset()
    feasible: list[Fraction] = []
    # the bisection's solves (at most LEVEL_MAX_SOLVES; the steps upwards of ``grow`` are not counted), and
    # with ``grow`` the levels tried upwards so far (None once the search no longer goes up)
    solves = 0
    upwards: int | None = 0 if grow else None
    stopped: list[BudgetExhausted] = []  # what ended the search early, raised as it came

    def short(x: float) -> Fraction:
        return Fraction(x).limit_denominator(10**9)

    def attempt(c: Fraction) -> Fraction | None:
        """Whether level ``c`` is feasible (numerically; the exact checks come after); while no level is, the
        program reduced by the Gram monomials its solve found vanishing (facial reduction) and ``c`` tried
        again, :data:`FACIAL_ROUNDS` times at most."""
        nonlocal drop, program, solves, upwards
        while True:
            try:
                search.budget.check()
                _, solution = level_attempt(field, program, V, c, search, exact=False)
            except BudgetExhausted as exc:
                stopped.append(exc)
                raise
            solves += 1
            ok = bool(solution.usable and solution.scalars.get("t", 0.0) > LEVEL_MARGIN_MIN)
            if upwards is not None:  # going up: no reduction, and the bisection's solves start when it ends
                upwards += 1
                if ok and upwards < LEVEL_GROW_STEPS:
                    feasible.append(c)
                    return c
                # (where the first level failed, its solve counts as the bisection's first: it starts there)
                upwards, solves = None, 0 if ok or feasible else 1
                if ok:
                    feasible.append(c)
                    return c
            if not ok and not feasible and solves <= FACIAL_ROUNDS:
                vanishing = vanishing_monomials(program.gram("sigma"), solution)
                reduced = level_structure(field, V, generators, drop | vanishing) if vanishing else None
                if reduced is not None:
                    drop, program = drop | vanishing, reduced
                    if solves < LEVEL_MAX_SOLVES:
                        continue
            if ok:
                feasible.append(c)
            return c if ok else None

    def more(lo: Fraction | None, hi: Fraction | None) -> bool:
        low, high = float(lo or 0), float(c_top if hi is None else hi)
        return solves < LEVEL_MAX_SOLVES and (high - low) > LEVEL_REL_TOL * high and \
            not (low == 0 and high < c_top * 1e-6)

    steps = LevelSteps(up=lambda c: short(float(c) * LEVEL_GROWTH), down=lambda c: short(float(c) / 4),
                       between=lambda lo, hi: short(math.sqrt(float(lo) * float(hi))),
                       above=None if grow else Fraction(c_top), more=more)
    found = largest_proved_level(attempt, short(c_top), growth=Fraction(LEVEL_GROWTH),
                                 growth_steps=LEVEL_GROW_STEPS if grow else 1, halvings=LEVEL_MAX_SOLVES,
                                 bisections=LEVEL_MAX_SOLVES, steps=steps)
    if stopped:  # (out of time, or a budget of solves spent: the feasible levels are not proved, so none is lost)
        raise stopped[-1]
    # every feasible level, largest first, then levels below the smallest: a level that rounds to an exact
    # certificate is never lost because the larger ones (thinner margins) did not (issue 42, item 2)
    tries = sorted(feasible, reverse=True)
    if tries:
        tries += [tries[-1] / 2 ** (k + 1) for k in range(LEVEL_EXACT_HALVINGS)]
    for c in tries:
        cert, _ = level_attempt(field, program, V, c, search, exact=True)
        if cert is not None:
            return cert
    return None


def lyapunov_quadratic(field: StateField) -> GramPoly | None:
    """``V = z^T P z`` with ``J^T P + P J = -I`` (``J`` the scaled field's Jacobian at 0), exact."""
    from lyapcheck.models.classes.linearization import lyapunov_solution
    from lyapcheck.sos.definiteness import is_positive_definite

    ring = field.ring
    n = field.n
    nv = ring.nvars
    origin = [Fraction(0)] * nv  # the states at the equilibrium, a box's parameters at its centre
    d0 = ring.evaluate(field.D, origin)
    J = [[ring.evaluate(gi.derivative(j), origin) / d0 for j in range(n)] for gi in field.g]
    P = lyapunov_solution(J)
    if P is None or not is_positive_definite(P):
        return None
    scale = max(abs(x) for row in P for x in row)
    P = [[x / scale for x in row] for row in P]
    basis = [m for m in monomials(nv, 1, 1) if any(m[:n])]
    order = [basis.index(tuple(int(k == i) for k in range(nv))) for i in range(n)]
    Q = [[P[order.index(a)][order.index(b)] for b in range(n)] for a in range(n)]
    return GramPoly.of(basis, Q)


def robust_quadratic(field: StateField, search: Search) -> GramPoly | None:
    """The quadratic start of ``roa``: :func:`lyapunov_quadratic` at a point; over a box, a quadratic
    ``V`` whose decrease along the linearized field is proved for every parameter of the box (the
    Lyapunov class of degree 2 on the field's part of degree 1 in the states). The centre's Lyapunov
    function need not decrease at the box's corners."""
    if field.p == 0:
        return lyapunov_quadratic(field)
    from lyapcheck.models.classes.lyapunov import search_degree

    ring = field.ring
    n = field.n

    def part(p: Poly, degree: int) -> Poly:
        return ring.from_terms({m: c for m, c in ring.terms(p).items() if sum(m[:n]) == degree})

    linear = StateField(ring, tuple(part(gi, 1) for gi in field.g), part(field.D, 0))
    found, _ = search_degree(linear, 2, search)
    return None if found is None else found["V"]


# -- roa: enlarging V --------------------------------------------------------------------------------

def vstep_structure(field: StateField, v_degree: int, s: GramPoly, generators: Sequence[Sequence[int]]
                    ) -> Structure | None:
    """With ``s`` fixed: ``-grad V . g - s (1 - V) = sigma``, ``Q_V >= floor I``, minimize ``<Q_V, M>``
    (over a box, ``V`` common to it and the box's multipliers in the identity)."""
    ring = field.ring
    n = field.n
    nv = ring.nvars
    s_degree = 2 * max((sum(m) for m in s.basis), default=0)
    if bases.candidate_count(nv, max(v_degree - 1 + field_degree(field), v_degree + s_degree)) > CANDIDATE_LIMIT:
        return None
    z_v = [m for m in monomials(nv, 1, v_degree // 2) if not any(m[n:])]
    v_blocks = bases.character_blocks(z_v, generators)
    s_poly = s.poly(ring)
    s_support = ring.support(s_poly) or [tuple([0] * nv)]
    products = {tuple(a + b for a, b in zip(z_v[i], z_v[j])) for idx in v_blocks for i in idx for j in idx}
    target: set[Monomial] = set(s_support)
    widen_by_derivative(target, ring, products, enumerate(field.g), s_support)
    box_grams, box_terms = box_multipliers(nv, n, target, with_states=True, generators=generators,
                                           margin="floor")  # its objective is J, not the margin
    target |= box_support(box_grams, nv)
    if len(target) > TARGET_LIMIT:
        return None
    z_sigma = bases.sos_basis(nv, target)
    if not z_sigma or len(z_sigma) > MAX_GRAM_ROWS or len(z_v) > MAX_GRAM_ROWS:
        return None
    sigma_blocks = bases.character_blocks(z_sigma, generators)
    terms = [Term(param(f"g{i}", ring.support(gi)), "V", derivative=i) for i, gi in enumerate(field.g)]
    terms += [Term(param("s1", s_support), "V"), *box_terms, Term(one(ring, -1), "sigma")]
    return affordable(Structure(nvars=nv,
                     grams=(Gram("V", tuple(z_v), tuple(map(tuple, v_blocks)), margin="floor"),
                            Gram("sigma", tuple(z_sigma), tuple(map(tuple, sigma_blocks)), margin=False), *box_grams),
                     scalars=(Scalar("J"),),
                     identities=(Identity("sublevel_1", tuple(terms), param("negs1", s_support), "sigma"),),
                     objective=("min", "J"), inner=(("J", "V", "M"),)))


def _monomial_vectors(basis: Sequence[Monomial], points: np.ndarray) -> np.ndarray:
    out = np.ones((points.shape[0], len(basis)))
    for k, m in enumerate(basis):
        for i, e in enumerate(m):
            if e:
                out[:, k] *= points[:, i] ** e
    return out


def vstep(field: StateField, v_degree: int, current: LevelCertificate, samples: np.ndarray, search: Search,
          generators: Sequence[Sequence[int]]) -> GramPoly | None:
    """One V step (see the module docstring); the new ``V`` (floats, level 1) or None."""
    ring = field.ring
    structure = vstep_structure(field, v_degree, current.s, generators)
    if structure is None:
        return None
    s_poly = current.s.poly(ring)
    values = ParameterValues()
    for i, gi in enumerate(field.g):
        values.set_poly(ring, f"g{i}", -gi, ring.support(gi))
    s_support = structure.identities[0].constant.support  # type: ignore[union-attr]
    values.set_poly(ring, "s1", s_poly, s_support)
    values.set_poly(ring, "negs1", -s_poly, s_support)
    z_v = structure.gram("V").basis
    samples = on_states(field, samples)
    # the samples the current set does not hold yet weigh; the others (already in) a little
    v_now = NumericPoly(ring, current.V.poly(ring))(samples) / float(current.level)
    values.set_matrix("M", sample_moments(_monomial_vectors(z_v, samples), v_now))
    values.set_scalar("floor", ROA_FLOOR)
    solution = search.solve(structure, values)
    if not solution.usable:
        return None
    from lyapcheck.sos.rounding import round_matrix

    return GramPoly.of(z_v, round_matrix(solution.grams["V"]))


@dataclass
class RegionOutcome:
    certificate: LevelCertificate | BallCertificate | None
    share: float | None = None
    supremum: float | None = None
    history: list[dict[str, Any]] = dc_field(default_factory=list)


def covered(field: StateField, cert: LevelCertificate, samples: np.ndarray) -> np.ndarray:
    v = NumericPoly(field.ring, cert.V.poly(field.ring))(on_states(field, samples))
    return v <= float(cert.level)


def enlarge(field: StateField, search: Search, samples: np.ndarray, converged: np.ndarray | None,
            degrees: Sequence[int] | None = None, rounds: int | None = None) -> RegionOutcome:
    """The ``roa`` search: quadratic start, then rounds of (level-1 step for ``s``, V step) at each
    degree, the best set certified exactly (module docstring). Over a box (its programs are larger
    and one box must cost a few points' time) :data:`BOX_ROA_DEGREES` and :data:`BOX_ROA_ROUNDS`."""
    if degrees is None:
        degrees = searched_degrees(BOX_ROA_DEGREES if field.p else ROA_DEGREES)
    if rounds is None:
        rounds = BOX_ROA_ROUNDS if field.p else ROA_ROUNDS
    generators = symmetry(field)
    V0 = robust_quadratic(field, search)
    if V0 is None:
        return RegionOutcome(None)
    radius = float(np.max(np.linalg.norm(samples, axis=1))) if samples.size else 1.0
    top = supremum_estimate(field, V0, 4 * radius)
    if top is None:
        top = float(np.max(NumericPoly(field.ring, V0.poly(field.ring))(on_states(field, samples)))) * 4 \
            if samples.size else 10.0
    best: LevelCertificate | BallCertificate | None = largest_level(field, V0, search, top, generators)
    if best is None:
        # no SOS level (its program is too large at many states, or the solves found none): the
        # linearization's V with a level proved by norm bounds; it carries no multiplier for the V step
        best = quadratic_ball(field, V0) if field.p == 0 else None
        if best is None:
            return RegionOutcome(None)
    target = samples[converged] if converged is not None else samples
    if not target.shape[0]:
        target = samples

    def share_of(V: GramPoly, level: Fraction) -> float:
        v = NumericPoly(field.ring, V.poly(field.ring))(on_states(field, target))
        return float(np.mean(v <= float(level)))

    outcome = RegionOutcome(best, share_of(best.V, best.level))
    outcome.history.append({"degree": 2, "level": float(best.level), "share": outcome.share})
    V = _scaled(best.V, 1 / best.level)
    s = best.s
    candidate: tuple[GramPoly, float] | None = None
    rounds_search = search.within(tolerances.ROA_ENLARGE_SOLVES, "for the enlarging rounds",
                                  "lyapcheck.tolerances.ROA_ENLARGE_SOLVES")
    try:
        for degree in degrees:
            if degree <= 2 or s is None:
                continue
            stale = 0
            for _ in range(rounds):
                new_V = vstep(field, degree, LevelCertificate(V, Fraction(1), s, s, 0.0), target, rounds_search,
                              generators)
                if new_V is None:
                    break
                new_s = multiplier_at(field, new_V, Fraction(1), rounds_search, generators)
                if new_s is None:
                    break
                V, s = new_V, new_s
                share = share_of(V, Fraction(1))
                outcome.history.append({"degree": degree, "level": 1.0, "share": share})
                if candidate is None or share > candidate[1] + 1e-4:
                    candidate, stale = (V, share), 0
                else:
                    stale += 1
                    if stale >= ROA_STALE_ROUNDS:
                        break
    except SolvesSpent as exc:
        outcome.history.append({"stopped": str(exc)})
    except BudgetExhausted:
        outcome.history.append({"stopped": "time limit (the safety net)"})
    if candidate is not None and candidate[1] > (outcome.share or 0.0):
        try:
            V, _ = candidate
            top = supremum_estimate(field, V, 4 * radius) or 2.0
            cert = largest_level(field, V, search, max(top, 1.0), generators)
            if cert is not None:
                share = share_of(cert.V, cert.level)
                outcome.history.append({"certified_share": share, "level": float(cert.level)})
                if share > (outcome.share or 0.0):
                    outcome.certificate, outcome.share = cert, share
        except BudgetExhausted:
            outcome.history.append({"stopped": "time limit before the final exact check"})
    return outcome


def _scaled(V: GramPoly, factor: Fraction) -> GramPoly:
    return GramPoly(V.basis, tuple(tuple(x * factor for x in row) for row in V.Q))


def multiplier_at(field: StateField, V: GramPoly, c: Fraction, search: Search,
                  generators: Sequence[Sequence[int]]) -> GramPoly | None:
    """The level step at one level (no exact check): the multiplier ``s`` the solver centres."""
    from lyapcheck.sos.rounding import round_matrix

    structure = level_structure(field, V, generators)
    if structure is None:
        return None
    _, solution = level_attempt(field, structure, V, c, search, exact=False)
    if not solution.usable or solution.scalars.get("t", 0.0) < -EXACT_TRY_MARGIN:
        return None
    return GramPoly.of(structure.gram("s").basis, round_matrix(solution.grams["s"]))


# -- the largest ball inside a certified set --------------------------------------------------------

def ball_radius(scaled: ScaledField, field: StateField, cert: LevelCertificate | BallCertificate, search: Search
                ) -> tuple[float | None, dict[str, Any] | None]:
    """The radius (declared states, SI, Euclidean) of the largest ball around the equilibrium in
    ``{V <= c}``: a numerical estimate along rays, and a certified lower bound (Containment, exact)
    just below it, or None (``V`` over ``field``'s ring)."""
    ring = field.ring
    n = field.n
    v_num = NumericPoly(ring, cert.V.poly(ring))
    to_scaled = scaled.scaling.to_scaled
    level = float(cert.level)
    rng = np.random.default_rng(7)
    directions = rng.normal(size=(2000, n))
    directions /= np.linalg.norm(directions, axis=1, keepdims=True)
    # along each ray in declared coordinates x = r d, scaled z = r d / s: the first r with V = c
    lo = np.zeros(len(directions))
    hi = np.full(len(directions), 1.0)
    for _ in range(60):  # grow hi until outside
        out = v_num(on_states(field, to_scaled(hi[:, None] * directions))) > level
        if np.all(out):
            break
        hi = np.where(out, hi, hi * 2)
    for _ in range(50):
        mid = (lo + hi) / 2
        inside = v_num(on_states(field, to_scaled(mid[:, None] * directions))) <= level
        lo, hi = np.where(inside, mid, lo), np.where(inside, hi, mid)
    estimate = float(np.min(lo))
    if not estimate > 0:  # (at most three containment solves follow: a spent budget ends them, below)
        return None, None
    p = radius_polynomial(ring, scaled.scaling)
    for factor in (Fraction(99, 100), Fraction(9, 10), Fraction(1, 2)):
        r = Fraction(estimate).limit_denominator(10**9) * factor
        try:
            found = _containment(field, cert, p, r * r, search)
        except BudgetExhausted:
            return estimate, None
        if found is not None:
            return estimate, {"radius": str(r), **found}
    return estimate, None


def _containment(field: StateField, cert: LevelCertificate | BallCertificate, p: Poly, r2: Fraction, search: Search
                 ) -> dict[str, Any] | None:
    """Containment in the ring of the states alone (``V`` and the ball do not depend on a box's
    parameters)."""
    n = field.n
    ring = Ring(field.ring.names[:n])
    search = Search(ring, search.budget, search.log)  # this program lives in the states' ring
    V = states_only(cert.V, n)
    v_poly = V.poly(ring)
    p = field.ring.restrict(p, ring)
    kv = max(sum(m) for m in cert.V.basis)
    z_s = monomials(n, 0, max(kv - 1, 0))
    p_support = set(ring.support(p)) | {tuple([0] * n)}
    s_products = {tuple(a + b for a, b in zip(x, y)) for x in z_s for y in z_s}
    target = set(ring.support(v_poly)) | {tuple([0] * n)} | {tuple(a + b for a, b in zip(m, q))
                                                             for m in s_products for q in p_support}
    z_sigma = bases.sos_basis(n, target)
    if not z_sigma or len(z_sigma) > MAX_GRAM_ROWS:
        return None
    # c - V - s (r^2 - p) - sigma = 0
    structure = Structure(nvars=n, grams=(Gram("s", tuple(z_s), bases_full(z_s)),
                                          Gram("sigma", tuple(z_sigma), bases_full(z_sigma))), scalars=(),
                          identities=(Identity("containment", (Term(param("pr", p_support), "s"),
                                                               Term(one(ring, -1), "sigma")),
                                               param("cV", set(ring.support(v_poly)) | {tuple([0] * n)}),
                                               "sigma"),),
                          objective=("max_margin",))
    values = ParameterValues()
    values.set_poly(ring, "pr", p - ring.constant(r2), structure.identities[0].terms[0].coefficients.support)
    values.set_poly(ring, "cV", ring.constant(cert.level) - v_poly, structure.identities[0].constant.support)  # type: ignore[union-attr]
    point, _ = search.solve_exact(structure, values, near_only=True)
    if point is None:
        return None
    s = GramPoly.of(z_s, point.grams["s"])
    sigma = GramPoly.of(z_sigma, point.grams["sigma"])
    ok, _ = check_containment(ring, V, cert.level, p, r2, s, sigma)
    return {"gram_s": s.to_json(), "gram_sigma": sigma.to_json()} if ok else None


def states_only(V: GramPoly, n: int) -> GramPoly:
    """A Gram polynomial whose basis carries no box parameter, in the ring of the states alone."""
    if any(any(m[n:]) for m in V.basis):
        raise ValueError("V depends on the box's parameters")
    return GramPoly(tuple(m[:n] for m in V.basis), V.Q)


def bases_full(basis: Sequence[Monomial]) -> tuple[tuple[int, ...], ...]:
    return (tuple(range(len(basis))),)


def radius_polynomial(ring: Ring, scaling: Scaling) -> Poly:
    """``|x - x_eq|^2`` (declared states) in the scaled coordinates: ``|A w~|^2``."""
    n = len(scaling.states)
    p = ring.zero()
    for component in linear_images(ring, n, scaling.matrix())[:n]:
        p += component * component
    return p


# -- the classes -------------------------------------------------------------------------------------

def level_result(name: str, scaled: ScaledField, field: StateField, cert: LevelCertificate | BallCertificate, search: Search,
                 numbers: dict[str, Any], what: str) -> ConditionResult:
    """A certified ``roa`` / ``candidate``: the set, its level, V in declared states, the ball."""
    from lyapcheck.models.classes.lyapunov import stated_v

    certificate = {**cert.to_json(), "V": stated_v(scaled, field, cert.V.poly(field.ring)), "level": str(cert.level)}
    estimate, ball = ball_radius(scaled, field, cert, search)
    numbers = {"level": float(cert.level), **numbers}
    if ball is not None:
        certificate["ball"] = ball
        numbers["ball_radius"] = float(Fraction(ball["radius"]))
    if estimate is not None:
        numbers["ball_radius_estimate"] = estimate
    from lyapcheck.models.classes.claims import rounded

    ball_text = (f"; it holds the ball |x - x_eq| <= {rounded(numbers['ball_radius'], 4, 'down')}"
                 if "ball_radius" in numbers else "")
    return ConditionResult(name, "certified", f"{what}: every start in {{V <= {rounded(cert.level, 6, 'down')}}} "
                                              f"converges to the equilibrium (checked exactly){ball_text}",
                           numbers=numbers, certificate=certificate, solver={"solves": search.log}, property="ROA")


@dataclass(frozen=True)
class GlobalDecrease:
    """A fixed ``V``'s decrease everywhere, proved exactly: ``sigma`` and, over a box of parameters, the
    box's multipliers (``-grad V . g - mu V D - sum_j r_j (1 - u_j^2) = sigma``; none at a point)."""

    sigma: GramPoly
    box: tuple[tuple[int, GramPoly], ...] = ()


def global_decrease(field: StateField, V: GramPoly, mu: Fraction, search: Search) -> GlobalDecrease | None:
    """For a fixed ``V``: ``sigma`` with ``-grad V . g - mu V D = sigma`` exactly (kind Lyapunov), or None.
    Over a box (the ring's variables after the states, :attr:`StateField.p`) the box's multipliers join the
    identity, so that one ``sigma`` proves the decrease for every value of it."""
    ring = field.ring
    nv = ring.nvars
    v_poly = V.poly(ring)
    target_poly = -lie_derivative(ring, v_poly, field.g) - v_poly * field.D * to_fmpq(mu)
    support = set(ring.support(target_poly))
    if not support:
        return None
    n = field.n
    generators = symmetry(field)
    box_grams, box_terms = box_multipliers(nv, n, support, with_states=True, generators=generators)
    drop: frozenset[Monomial] = frozenset()
    for _ in range(FACIAL_ROUNDS + 1):
        target = support | box_support(box_grams, nv)
        z_sigma = [m for m in bases.sos_basis(nv, target) if m not in drop]
        if not z_sigma or not bases.has_pure_powers(z_sigma, range(n)) or len(z_sigma) > MAX_GRAM_ROWS:
            return None
        structure = Structure(nvars=nv, grams=(Gram("sigma", tuple(z_sigma),
                                                    tuple(map(tuple, bases.character_blocks(z_sigma, generators)))),
                                               *box_grams),
                              scalars=(), identities=(Identity("decrease", (*box_terms, Term(one(ring, -1), "sigma")),
                                                               param("LV", support), "sigma"),),
                              objective=("max_margin",))
        values = ParameterValues()
        values.set_poly(ring, "LV", target_poly, structure.identities[0].constant.support)  # type: ignore[union-attr]
        solution = search.solve(structure, values)
        if solution.usable and solution.scalars.get("t", 0.0) > 0:
            point = search.exact(structure, solution, values)
            if point is not None:
                sigma = GramPoly.of(z_sigma, point.grams["sigma"])
                box = box_multipliers_of(point.grams, multiplier_grams(structure))
                if check_lyapunov(ring, field.g, field.D, V, sigma, mu, box)[0]:
                    return GlobalDecrease(sigma, tuple(box))
        vanishing = vanishing_monomials(structure.gram("sigma"), solution)
        # a box multiplier's monomial the identity forces to 0 (its square appears in no other term: the
        # half-polytope test is approximate) keeps the margin at 0 too: dropped the same way
        reduced = [_without(g, vanishing_monomials(g, solution), generators) for g in box_grams]
        if not vanishing and all(len(r.basis) == len(g.basis) for r, g in zip(reduced, box_grams)):
            return None
        drop = drop | vanishing
        box_grams = [r for r in reduced if r.basis]
        box_terms = [t for t in box_terms if any(t.decision == r.name for r in box_grams)]
    return None


def _without(gram: Gram, monomials_: frozenset[Monomial], generators: Sequence[Sequence[int]]) -> Gram:
    """``gram`` with the given monomials left out of its basis (its blocks made again)."""
    basis = tuple(m for m in gram.basis if m not in monomials_)
    return Gram(gram.name, basis, tuple(map(tuple, bases.character_blocks(basis, generators))), margin=gram.margin)


def gram_of(field: StateField, p: Poly, search: Search) -> GramPoly | None:
    """``p = z^T Q z`` with ``Q > 0`` over the reduced basis of ``p`` (exactly), or None: how a
    user's candidate ``V`` is shown positive definite and radially unbounded."""
    ring = field.ring
    n = field.n
    support = set(ring.support(p))
    # (over a box the ring has the box's parameters after the states; V of the states alone keeps them at
    # exponent 0 in its support, so its reduced basis does too)
    basis = bases.sos_basis(ring.nvars, support)
    if not basis or not bases.has_pure_powers(basis, range(n)) or any(sum(m) == 0 for m in basis):
        return None
    structure = Structure(nvars=ring.nvars, grams=(Gram("V", tuple(basis), bases_full(basis)),), scalars=(),
                          identities=(Identity("gram", (Term(one(ring, -1), "V"),), param("P", support), "V"),),
                          objective=("max_margin",))
    values = ParameterValues()
    values.set_poly(ring, "P", p, structure.identities[0].constant.support)  # type: ignore[union-attr]
    point, _ = search.solve_exact(structure, values, near_only=True)
    if point is None:
        return None
    V = GramPoly.of(basis, point.grams["V"])
    return V if V.poly(ring) == p and V.positive_definite() else None


# -- loops with functions: the same classes on the recasting's relations ------------------------------
#
# A loop with functions (:class:`~lyapcheck.models.classes.recast_classes.Loop`) is proved on the set of its
# recasting's relations, which holds every point ``(z, a(z))`` of the true loop: positivity
# ``V - eps |z|^2 >= 0`` (:func:`~lyapcheck.models.classes.recast_classes.prove_nonnegative`) and the decrease
# ``-grad V . N - eps |z|^2 - rho (level - V) >= 0`` there, with ``x' = N / D`` and each factor of ``D``
# proved positive. The decrease is the polynomial loops' level program with the relations' multipliers
# added (:func:`relations_level_structure`: a free ``lambda_i`` per equality, a sum of squares ``tau_j`` per
# inequality, as every class builds them, :func:`~lyapcheck.models.classes.bounds.relation_multipliers`),
# checked exactly by :func:`~lyapcheck.models.engines.recast_sos.check_condition` (the check verify runs).
# The level step is the monotone search of :func:`~lyapcheck.models.classes.level_search.largest_proved_level`
# (each level's certificate checked exactly before it counts); the V step, with ``rho`` fixed and ``V``
# scaled to level 1, is the polynomial loops' V step (:func:`vstep`) with the same multipliers
# (:func:`relations_vstep_structure`), the V-s iteration of Jarvis-Wloszek et al. ("Some controls
# applications of sum of squares programming", CDC 2003; Topcu, Packard & Seiler, Automatica 2008) on sample
# states whose simulated trajectories of the true loop converge. Its answer is only a candidate: rounded to
# short rationals, the level step certifies it from scratch.

#: the level search of a fixed V on the recasting's relations
#: (:func:`~lyapcheck.models.classes.level_search.largest_proved_level`): halvings of the level's bracket
RELATIONS_LEVEL_BISECTIONS: Final = 7
#: levels tried upwards (each the previous times this) before the bisection
RELATIONS_LEVEL_GROWTH: Final = 4
#: at most this many levels upwards
RELATIONS_LEVEL_GROWTH_STEPS: Final = 10
#: at most this many levels downwards (each half the last) from a first level that failed, before the
#: bisection between the proved and the failed level: a strict local Lyapunov function's small levels
#: are provable, so the search goes down far enough to reach one (2^-16 of the first level)
RELATIONS_LEVEL_HALVINGS: Final = 16


@dataclass(frozen=True)
class LevelPlan:
    """The steps of :func:`relations_level`'s search
    (:func:`~lyapcheck.models.classes.level_search.largest_proved_level`): the ratio of the levels tried
    upwards and their count, the halvings from a failed first level and the bisections of the bracket."""

    growth: Fraction = Fraction(RELATIONS_LEVEL_GROWTH)
    growth_steps: int = RELATIONS_LEVEL_GROWTH_STEPS
    halvings: int = RELATIONS_LEVEL_HALVINGS
    bisections: int = RELATIONS_LEVEL_BISECTIONS


#: the search from a level near the largest (issue 42: a V whose sampled critical level is known, the shaped
#: quadratic V at 4 to 6 states, where each attempt is a solve of seconds): the first level is
#: RELATIONS_CRITICAL_START times that critical level, the next ones double (the critical level next, which
#: sampling says fails: then the bracket is one doubling wide), and 6 bisections put the level within 1/64
#: of the largest provable one anywhere from 2^-16 to 2^7 times the first level (the halvings are the
#: default's: a sampled level far too high still reaches a provable one; 8 levels upwards: one far too low
#: is not a ceiling). The quadrotor's shaped V (its invariant part): 9 solves, 2.4 s, level 0.9525; the default
#: plan from V at a tenth of a state (growth 4, 7 bisections: within 3/128) 17 solves, 7.6 s, level 0.9402
#: (2026-11-30, load about 3; with the coupling entries 18 solves of 10 to 48 s each)
RELATIONS_CRITICAL_START: Final = Fraction(1, 2)
CRITICAL_PLAN: Final = LevelPlan(growth=Fraction(2), growth_steps=8, halvings=RELATIONS_LEVEL_HALVINGS, bisections=6)


def critical_start(critical: float) -> Fraction:
    """The first level of :data:`CRITICAL_PLAN`'s search from a sampled critical level (floats: it only
    orders the attempts, every level reported is proved)."""
    return _dyadic(Fraction(critical) * RELATIONS_CRITICAL_START)


@dataclass
class Region:
    """A certified sublevel set ``{V <= level}``: its V, its certificate (JSON) and its multiplier rho."""

    label: str
    V: Poly
    level: Fraction
    certificate: dict[str, Any]
    rho: Poly
    #: what ended the level search before its bisection did (a budget's words), "" otherwise: the
    #: level is then the largest proved before it (:func:`~lyapcheck.models.classes.level_search.largest_proved_level`)
    stopped: str = ""


def certify_region(loop: Loop, V: Poly, search: Search, label: str, start: Fraction | None = None,
                   plan: LevelPlan = LevelPlan()) -> Region | str:
    """The largest certified level of a fixed ``V`` (from ``start``, by ``plan``'s steps), or why there is none."""
    found = relations_level(loop, V, search, state_square(loop), start, plan)
    if isinstance(found, str):
        return found
    level, cert = found
    rho = cert.pop("_rho")
    return Region(label, V, level, cert, rho, cert.pop("_stopped", ""))


def box_share(loop: Loop, region: Region, box: tuple[Any, Any]) -> float:
    """The share of fixed uniform samples of the box (deviations ``lo..hi``) inside the region."""
    import numpy as np

    from lyapcheck.models.engines.recast_numeric import v_values

    lo, hi = box
    Z = lo + (hi - lo) * np.random.default_rng(0).random((4000, loop.n))
    return float(np.mean(v_values(loop.system, region.V, Z) <= float(region.level)))


def best_region(loop: Loop, regions: Sequence[Region], tried: Sequence[str], box: tuple[Any, Any],
                search: Search, name: str = "roa") -> ConditionResult:
    """The region covering the largest share of the box, as the class's result."""
    if not regions and search.budget.left() <= 0:
        # the class's time ran out before a level was proved: the search was cut short, so the answer is
        # inconclusive (a class at its limit), not a "not found"
        late = reasons.out_of_time("a region of attraction", search.budget.seconds, tried,
                                   ("time", "domain") if name != "candidate" else ("time", "other_candidate"))
        return ConditionResult(name, "inconclusive", late.summary, property="ROA",
                               numbers=late.numbers({"reason": search.budget.reached()}),
                               solver={"solves": search.log})
    if not regions:
        which = "the candidate V" if name == "candidate" else "the V functions tried"
        none = reasons.reason(f"no region of attraction was proved: no level set of {which} could be proved to shrink",
                              ("domain", "candidate", "time") if name != "candidate"
                              else ("other_candidate", "domain", "time"), tried)
        return ConditionResult(name, "not_certified", none.summary, property="ROA",
                               numbers=none.numbers({"reason": "; ".join(tried)}), solver={"solves": search.log})
    shares = [box_share(loop, r, box) for r in regions]
    k = max(range(len(regions)), key=lambda i: shares[i])
    best = regions[k]
    modulo = (f" (modulo 2 pi in {', '.join(loop.angles)}: the loop is periodic in "
              f"{'it' if len(loop.angles) == 1 else 'them'})") if loop.angles else ""
    return ConditionResult(name, "certified",
                           f"every trajectory of the true loop starting where V(x, a(x)) <= {float(best.level):.6g} "
                           f"converges to the equilibrium{modulo} (V from {best.label}; positivity and decrease on the "
                           "recasting's relations, exact)",
                           numbers={"level": float(best.level), "V_from": best.label, "tried": list(tried),
                                    "box_share_estimate": shares[k]},
                           certificate=dict(best.certificate), property="ROA", solver={"solves": search.log})


def region_of_attraction(loop: Loop, budget: Budget, candidates: Sequence[tuple[str, Poly]], box: tuple[Any, Any],
                         name: str = "roa", start: Fraction | None = None, plan: LevelPlan = LevelPlan()
                         ) -> ConditionResult:
    """Each fixed ``V``'s largest certified level on the recasting's relations (the search from ``start`` by
    ``plan``'s steps, as :func:`certify_region`'s); the region covering most of the box is the answer
    (``candidate``: the user's V alone)."""
    search = Search(loop.ring, budget)
    regions: list[Region] = []
    tried: list[str] = []
    for label, V in candidates:
        try:
            found = certify_region(loop, V, search, label, start, plan)
        except BudgetExhausted as exc:
            tried.append(f"{label}: {exc}")
            break
        if isinstance(found, str):
            tried.append(f"{label}: {found}")
            continue
        tried.append(f"{label}: level {float(found.level):.6g}")
        regions.append(found)
    return best_region(loop, regions, tried, box, search, name)


#: the positivity margin ``V - eps |z|^2 >= 0`` a loop with functions' level step tries last, after
#: :data:`~lyapcheck.models.classes.recast_classes.EPSILONS`: half the V step's :data:`ROA_FLOOR`
#: (``Q_V >= ROA_FLOOR I``), so that a V the V step found keeps a proof of its positivity (the inverted
#: pendulum's second V had none at 1e-4; a floor of 1/50 instead shrank the pendulum's set, 72 % -> 57 %)
POSITIVITY_LAST_EPSILON: Final = Fraction(1, 2 * 10**6)
#: extra half-degree of the level step's multiplier ``s`` on a loop with functions (the polynomial loops'
#: is :data:`MULTIPLIER_EXTRA`)
RELATIONS_MULTIPLIER_EXTRA: Final = 0


def level_field(loop: Loop, names: Sequence[str], N: dict[str, Poly], D: Poly) -> "BoundField":
    """The level step's and the V step's view of a loop with functions
    (:func:`~lyapcheck.models.classes.lyapunov_relations.relations_field`), with two differences: a constant
    root (``rt3``, ``rt3^2 = 3``) is a variable of the bases, each at most once, as the identity's terms hold
    it; and the squares a relation reduces (a cosine's ``c^2 = -s^2 - 2 c``) stay in the bases, the remainder
    here need only be a sum of squares (the margin is ``eps |z|^2`` in ``F``; without ``c^2`` the pendulum's
    V-s candidates got no level at all, its free multiplier then cannot trade ``c^2`` for ``-s^2 - 2 c``)."""
    from lyapcheck.models.classes.lyapunov_relations import relations_field

    return replace(relations_field(loop, names, N, D), unused=loop.unused(), square_free=loop.roots())


def relations_level_symmetry(field: "BoundField", V: Poly, F: Poly) -> list[tuple[int, ...]]:
    """The sign changes that leave the level program of a loop with functions invariant: each flow changes
    like its variable, and ``D``, every relation, ``V`` and ``F`` are invariant."""
    ring = field.ring
    odd = [(ring.support(gi), i) for i, gi in field.flows] + [(ring.support(field.W), None)]
    odd += [(ring.support(field.relations[j].poly), None) for j in field.multiplied]
    odd += [(ring.support(V), None), (ring.support(F), None)]
    return bases.sign_symmetries(ring.nvars, odd)


def state_characters(loop: Loop) -> list[tuple[int, ...]]:
    """How each state changes under the sign changes of the loop's variables that leave its level program
    invariant for every V invariant under them (:func:`relations_level_symmetry` with ``V = |z|^2``, which
    any sign change keeps): one GF(2) character per state, in the states' order. A quadratic form of the
    states couples two states only where their characters agree, or the program loses that symmetry."""
    ring = loop.ring
    z = [ring.gen(s) for s in loop.system.states]
    V = sum((zi * zi for zi in z), ring.zero())
    names = v_names(loop, V)
    N, D, _ = common_denominator(loop, names)
    generators = relations_level_symmetry(level_field(loop, names, N, D), V, ring.zero())
    return [bases.character(tuple(int(k == ring.names.index(s)) for k in range(ring.nvars)), generators)
            for s in loop.system.states]


def relations_level_structure(field: "BoundField", V: Poly, F: Poly, generators: Sequence[Sequence[int]],
                              drop: frozenset[tuple[str, Monomial]] = frozenset(), extra: int = 0,
                              roots: frozenset[int] = frozenset()) -> Structure | str:
    """The level step's program of :func:`_level_structure` on a loop with functions: the same identity with
    the relations' multipliers (:func:`~lyapcheck.models.classes.bounds.relation_multipliers`: a free
    ``lambda_i`` per equality, a sum of squares ``tau_j`` per inequality) and the known part ``F`` in place
    of ``-grad V . g``:

        F + s (V - c) - sum_i lambda_i h_i - sum_j tau_j g_j = sigma,

    ``F = -grad V . N - eps |z|^2`` (the margin is in ``F``: ``sigma`` need only be a sum of squares). Every
    term vanishes at the equilibrium: ``s`` and ``sigma`` have no constant, nor a ``tau_j`` whose ``g_j``
    does not vanish to second order there. ``drop``: (Gram, monomial) pairs left out (the zero face a
    solve found); ``extra``: as :func:`multiplier_half_degree`'s; ``roots``: the constant roots' variables
    (``rt3``: constants, of no degree in the deviations). Returns why not (a size) when too large."""
    from lyapcheck.models.classes.bounds import relation_multipliers
    from lyapcheck.models.classes.lyapunov_relations import _reduced
    from lyapcheck.models.engines.reasons import size_limit
    from lyapcheck.models.engines.recast_sos import MAX_RECAST_GRAM_ROWS, mdeg, order_at_origin

    ring = field.ring
    nv = ring.nvars
    zero = tuple([0] * nv)
    dg = max((sum(m) for _, gi in field.flows for m in ring.support(gi)), default=1)
    ks = max(1, math.ceil((dg - 1) / 2)) + extra  # (multiplier_half_degree's rule, over the flows N)
    z_s = [m for m in monomials(nv, 1, ks + len(roots)) if 1 <= mdeg(m, roots) <= ks and field.allowed(m)
           and ("s", m) not in drop]
    if not z_s:
        return "the multiplier s has no monomial left"
    s_blocks = bases.character_blocks(z_s, generators)
    v_support = set(ring.support(V)) | {zero}
    s_products = {tuple(a + b for a, b in zip(z_s[i], z_s[j])) for idx in s_blocks for i in idx for j in idx}
    target = set(ring.support(F)) | {tuple(a + b for a, b in zip(m, v)) for m in s_products for v in v_support}
    rel_grams, rel_scalars, rel_terms, added = relation_multipliers(field, "R", target, generators, margin=True)
    target |= added
    # tau_j(0) g_j(0) would be the identity's only constant term where g_j(0) != 0: no constant there
    constants = {(g.name, q) for g in rel_grams for q in g.basis if mdeg(q, roots) == 0
                 and order_at_origin(ring, field.relations[int(g.name.split("_")[1])].poly, roots) < 2}
    rel_grams = [_reduced(g, drop | constants) for g in rel_grams]
    kept = {g.name for g in rel_grams if g.basis}
    rel_grams = [g for g in rel_grams if g.basis]
    rel_terms = [t for t in rel_terms if not t.decision.startswith("TR_") or t.decision in kept]
    if len(target) > TARGET_LIMIT:
        return size_limit(len(target), "monomials in one polynomial identity", TARGET_LIMIT, "TARGET_LIMIT")
    z_sigma = [q for q in bases.sos_basis(nv, target) if mdeg(q, roots) >= 1 and field.allowed(q)
               and ("sigma", q) not in drop]
    rows = max([len(z_sigma), len(z_s)] + [len(g.basis) for g in rel_grams])
    if not z_sigma or rows > MAX_RECAST_GRAM_ROWS:
        return size_limit(rows, "rows of one sum-of-squares matrix", MAX_RECAST_GRAM_ROWS, "MAX_RECAST_GRAM_ROWS")
    terms = (Term(param("Vc", v_support), "s"), *rel_terms, Term(one(ring, -1), "sigma"))
    # (the size limit is the rows' alone, not the polynomial loops' BLOCK_COST_LIMIT: a degree-4 V of the
    # saturated inverted pendulum exceeds that one and its level step, within the rows, is solved in seconds)
    return Structure(nvars=nv, grams=(Gram("s", tuple(z_s), tuple(map(tuple, s_blocks))),
                                      Gram("sigma", tuple(z_sigma),
                                           tuple(map(tuple, bases.character_blocks(z_sigma, generators)))),
                                      *rel_grams),
                     scalars=tuple(rel_scalars),
                     identities=(Identity("R", terms, param("LV", ring.support(F) or [zero]), "sigma"),),
                     objective=("max_margin",))


def relations_level_certificate(field: "BoundField", structure: Structure, point: Any) -> ConditionCertificate:
    """The multipliers of a solved :func:`relations_level_structure` by relation index, ``rho`` the
    multiplier ``s`` (the form :func:`~lyapcheck.models.engines.recast_sos.check_condition` reads)."""
    from lyapcheck.models.classes.bounds import relation_certificates

    cert, = relation_certificates(field, structure, point, (("R", "sigma"),))
    return replace(cert, rho=GramPoly.of(structure.gram("s").basis, point.grams["s"]))


def relations_level_attempt(field: "BoundField", V: Poly, F: Poly, level: Fraction, search: Search,
                            build: Any) -> ConditionCertificate | None:
    """:func:`level_attempt` on a loop with functions: one solve of the level program at ``level``, its exact
    rounding and the exact check (:func:`~lyapcheck.models.engines.recast_sos.check_condition`, the one
    verify runs); where the check refuses a point on a face of the cone, that face is dropped and the
    program solved again (at most :data:`~lyapcheck.models.engines.recast_sos.FACE_ROUNDS` times).
    ``build(drop)``: the program (:func:`relations_level_structure`) or why not."""
    from lyapcheck.models.engines.recast_sos import FACE_ROUNDS, zero_face

    ring = field.ring
    region = V - to_fmpq(level)
    drop: frozenset[tuple[str, Monomial]] = frozenset()
    for _ in range(FACE_ROUNDS + 1):
        structure = build(drop)
        if isinstance(structure, str):
            return None
        values = ParameterValues()
        ident = structure.identities[0]
        values.set_poly(ring, "LV", F, ident.constant.support)
        values.set_poly(ring, "Vc", region, ident.terms[0].coefficients.support)
        point, solution = search.solve_exact(structure, values)
        if point is not None:
            cert = relations_level_certificate(field, structure, point)
            if check_condition(ring, F, field.relations, cert, region=region)[0]:
                return cert
        if not solution.usable:
            return None
        face = zero_face(structure, solution.grams) - drop  # type: ignore[arg-type]  # (its grams, by name)
        if not face:
            return None
        drop = drop | face
    return None


def relations_level(loop: Loop, V: Poly, search: Search, l2: Poly, start: Fraction | None = None,
                    plan: LevelPlan = LevelPlan()) -> tuple[Fraction, dict[str, Any]] | str:
    """``V``'s largest level proved on the recasting's relations (its positivity, then the level program
    at each level :func:`~lyapcheck.models.classes.level_search.largest_proved_level` tries from ``start``,
    V at a tenth of a state by default, with ``plan``'s steps): the level and its certificate, or why none."""
    ring = loop.ring
    names = v_names(loop, V)
    N, D, distinct = common_denominator(loop, names)
    dens, failed = prove_denominators(loop, distinct, search)
    if failed is not None:
        return f"the denominator {written_poly(ring, failed)} could not be proved positive"
    # positivity of V itself
    eps_pos = None
    pos = None
    for eps in (*EPSILONS, POSITIVITY_LAST_EPSILON):
        pos = prove_nonnegative(loop, V - l2 * to_fmpq(eps), search, "Pv")
        if pos is not None:
            eps_pos = eps
            break
    if pos is None or eps_pos is None:
        return "V could not be proved positive definite in the states on the recasting's set"
    dV = lie(loop, V, N)
    eps = EPSILONS[-1]
    F = -dV - l2 * to_fmpq(eps)
    field = level_field(loop, names, N, D)
    generators = relations_level_symmetry(field, V, F)
    programs: dict[frozenset[tuple[str, Monomial]], Structure | str] = {}

    def build(drop: frozenset[tuple[str, Monomial]]) -> Structure | str:
        if drop not in programs:  # (the program does not depend on the level: built once per face)
            programs[drop] = relations_level_structure(field, V, F, generators, drop, RELATIONS_MULTIPLIER_EXTRA,
                                                       loop.roots())
        return programs[drop]

    def attempt(level: Fraction) -> ConditionCertificate | None:
        return relations_level_attempt(field, V, F, level, search, build)

    # a program too large to build is too large at every level: say so, not "no level found"
    program = build(frozenset())
    if isinstance(program, str):
        return f"the level program was not built: {program}"
    from lyapcheck.models.classes.level_search import largest_proved_level

    found = largest_proved_level(attempt, _scale_of(loop, V) if start is None else start, growth=plan.growth,
                                 growth_steps=plan.growth_steps, halvings=plan.halvings,
                                 bisections=plan.bisections, rounded=_dyadic)
    if found.level is None or found.proof is None:
        return f"no level found (the smallest tried was {float(found.failed or 0):.3g})"
    best = (found.level, found.proof)
    level, cert = best
    out = certificate_head(loop, V, eps, D, dens)
    out.update({"level": str(level), "positivity_epsilon": str(eps_pos), "positivity": pos.to_json(ring),
                "decrease": cert.to_json(ring)})
    assert cert.rho is not None
    out["_rho"] = cert.rho.poly(ring)
    if found.stopped:
        out["_stopped"] = found.stopped
    return level, out


def _scale_of(loop: Loop, V: Poly) -> Fraction:
    """A first level to try: V's value at a small state deviation (a tenth in each state)."""
    import numpy as np

    from lyapcheck.models.engines.recast_numeric import v_values

    pts = np.eye(loop.n) * 0.1
    vals = v_values(loop.system, V, pts)
    return _dyadic(Fraction(max(float(np.min(vals)), 1e-6)))


#: V-s iterations at most (each a level step and a V step)
VS_ITERATIONS: Final = 4
#: degrees of the improved V, in turn
VS_DEGREES: Final = (2, 4)
#: sample states for the V step's objective (those that converge in simulation)
VS_SAMPLES: Final = 200
#: the V step's margin of the decrease (times |z|^2): the level step's smallest (a larger one
#: shrinks the set the V step can find, 63 % -> 40 % of the pendulum's box)
VS_MARGIN: Final = Fraction(1, 10000)
#: how long each sample is simulated (the loop's time unit)
VS_HORIZON_S: Final = 25.0
#: bits kept of the V step's coefficients (short certificates; the level step decides)
VS_ROUND_BITS: Final = 20
#: a step that adds less than this share of the converging samples ends the iteration at its degree
VS_MIN_GAIN: Final = 0.01
# The iteration's work is counted, not timed (the same regions on any machine): a V step is one
# solve (its length bounded by SOLVER_MAX_ITER), a level step at most
# lyapcheck.tolerances.VS_LEVEL_SOLVES solves, the whole iteration at most VS_SOLVES.


def relations_samples(loop: Loop, box: tuple[np.ndarray, np.ndarray], rng: np.random.Generator) -> np.ndarray:
    """Deviations in the box whose simulated trajectories of the true loop converge (modulo 2 pi in
    the angles): the region the V step pulls ``{V <= 1}`` towards."""
    from lyapcheck.models.engines.recast_numeric import converges_modulo

    lo, hi = box
    Z = lo + (hi - lo) * rng.random((VS_SAMPLES * 3, loop.n))
    eq = np.array([float(loop.system.values[s]) for s in loop.system.states])
    ok = converges_modulo(loop.system, Z + eq, tuple(loop.angles), horizon=VS_HORIZON_S)
    return Z[ok][:VS_SAMPLES]


def relations_enlarge(loop: Loop, first: Region, budget: Budget, box: tuple[np.ndarray, np.ndarray]
                     ) -> tuple[list[Region], list[str]]:
    """Regions from the V-s iteration started at ``first`` (each certified exactly by the level
    step), and what was tried."""
    from lyapcheck.models.engines.recast_numeric import v_values

    samples = relations_samples(loop, box, np.random.default_rng(1))
    tried: list[str] = []
    if len(samples) == 0:
        return [], ["the V-s iteration: no sample of the box converges in simulation"]
    out: list[Region] = []
    # the whole iteration's budget of solves: what is left of the class's work goes to the exact
    # checks of the regions found, whatever the machine's speed
    search = Search(loop.ring, budget).within(tolerances.VS_SOLVES, "for the V-s iteration",
                                              "lyapcheck.tolerances.VS_SOLVES")

    def covered(r: Region) -> float:
        """The share of the converging samples inside a region (the iteration's progress)."""
        return float(np.mean(v_values(loop.system, r.V, samples) <= float(r.level)))

    best, best_share = first, covered(first)
    for degree in searched_degrees(VS_DEGREES):
        region = best
        for k in range(VS_ITERATIONS):
            label = f"the V-s iteration (degree {degree}, step {k + 1})"
            try:
                outside = samples[v_values(loop.system, region.V, samples) > float(region.level)]
                V = relations_v_step(loop, region.V * to_fmpq(1 / region.level), region.rho, degree,
                           outside if len(outside) else samples, search)
                if isinstance(V, str):
                    tried.append(f"{label}: {V}")
                    break
                # each level step gets a budget of solves (a count: the same steps on any machine)
                level_search = search.within(tolerances.VS_LEVEL_SOLVES, "per level step",
                                             "lyapcheck.tolerances.VS_LEVEL_SOLVES")
                found = certify_region(loop, V, level_search, label, start=Fraction(1, 2))
            except BudgetExhausted as exc:  # a budget of solves spent, or the class's time limit (the safety net)
                tried.append(f"{label}: {exc}")
                return out, tried
            if isinstance(found, str):
                tried.append(f"{label}: {found}")
                break
            share = covered(found)
            stopped = f" (the largest proved when {found.stopped})" if found.stopped else ""
            tried.append(f"{label}: level {float(found.level):.6g}{stopped}, {100 * share:.1f} % of the converging "
                         "samples")
            out.append(found)
            region = found
            if share < best_share + VS_MIN_GAIN:  # no longer growing: the next degree, from the best set
                break
            best, best_share = found, share
    return out, tried


def relations_vstep_structure(field: "BoundField", v_degree: int, s: Poly, known: Poly,
                              generators: Sequence[Sequence[int]], roots: frozenset[int] = frozenset()
                              ) -> Structure | str:
    """:func:`vstep_structure` on a loop with functions: with ``s`` fixed, ``V = z^T Q_V z`` over the field's
    variables (``Q_V >= floor I``) and the relations' multipliers
    (:func:`~lyapcheck.models.classes.bounds.relation_multipliers`) in the identity

        -grad V . N - s (1 - V) - eps |z|^2 - sum_i lambda_i h_i - sum_j tau_j g_j = sigma,

    ``known`` its constant part ``-s - eps |z|^2``; minimize ``<Q_V, M>``; ``roots`` as
    :func:`relations_level_structure`'s. Returns why not (a size)."""
    from lyapcheck.models.classes.bounds import _embed, relation_multipliers
    from lyapcheck.models.engines.reasons import size_limit
    from lyapcheck.models.engines.recast_sos import MAX_RECAST_GRAM_ROWS, mdeg

    ring = field.ring
    nv = ring.nvars
    z_v = [_embed(a, field.v_vars, nv) for a in monomials(len(field.v_vars), 1, v_degree // 2)]
    v_blocks = bases.character_blocks(z_v, generators)
    s_support = ring.support(s) or [tuple([0] * nv)]
    products = {tuple(a + b for a, b in zip(z_v[i], z_v[j])) for idx in v_blocks for i in idx for j in idx}
    target: set[Monomial] = set(ring.support(known))
    widen_by_derivative(target, ring, products, field.flows, s_support)
    rel_grams, rel_scalars, rel_terms, added = relation_multipliers(field, "D", target, generators, margin=False)
    target |= added
    if len(target) > TARGET_LIMIT:
        return size_limit(len(target), "monomials in one polynomial identity", TARGET_LIMIT, "TARGET_LIMIT")
    z_sigma = [q for q in bases.sos_basis(nv, target | {tuple([0] * nv)}) if mdeg(q, roots) >= 1 and field.allowed(q)]
    rows = max([len(z_sigma), len(z_v)] + [len(g.basis) for g in rel_grams])
    if not z_sigma or rows > MAX_RECAST_GRAM_ROWS:
        return size_limit(rows, "rows of one sum-of-squares matrix", MAX_RECAST_GRAM_ROWS, "MAX_RECAST_GRAM_ROWS")
    terms = [Term(param(f"g{i}", ring.support(gi)), "V", derivative=i) for i, gi in field.flows]
    terms += [Term(param("s1", s_support), "V"), *rel_terms, Term(one(ring, -1), "sigma")]
    return Structure(nvars=nv, grams=(Gram("V", tuple(z_v), tuple(map(tuple, v_blocks)), margin="floor"),
                                      Gram("sigma", tuple(z_sigma),
                                           tuple(map(tuple, bases.character_blocks(z_sigma, generators))),
                                           margin=False), *rel_grams),
                     scalars=(Scalar("J"), *rel_scalars),
                     identities=(Identity("sublevel_1", tuple(terms), param("negs1", ring.support(known)),
                                          "sigma"),),
                     objective=("min", "J"), inner=(("J", "V", "M"),))


def relations_v_step(loop: Loop, V_scaled: Poly, rho: Poly, degree: int, samples: np.ndarray, search: Any
                     ) -> Poly | str:
    """One V step (see the module docstring): a new V of ``degree`` in the loop's V variables, or why none:
    the polynomial loops' V step (:func:`vstep`) on the recasting's relations
    (:func:`relations_vstep_structure`), its objective the samples' moments as :func:`vstep` weighs them.
    ``V_scaled``: the current V at level 1, which picks the samples outside its set."""
    from lyapcheck.models.engines.recast_numeric import poly_values, variable_values
    from lyapcheck.models.engines.search import why_none
    from lyapcheck.sos.rounding import round_matrix

    ring = loop.ring
    names = [ring.names[i] for i in loop.v_variables()]
    N, D, _ = common_denominator(loop, names)
    field = level_field(loop, names, N, D)
    known = -rho - state_square(loop) * to_fmpq(VS_MARGIN)
    generators = relations_level_symmetry(field, rho, known)
    structure = relations_vstep_structure(field, degree, rho, known, generators, loop.roots())
    if isinstance(structure, str):
        return f"the V step was not built: {structure}"
    system = loop.system
    eq = np.array([float(system.values[s]) for s in system.states])
    cols = variable_values(system, samples + eq)
    shifted = {n: v - float(system.values[n]) if n in system.values else v for n, v in cols.items()}
    z_v = structure.gram("V").basis
    Z = np.column_stack([poly_values(ring, ring.monomial(m), shifted, len(samples)) for m in z_v])
    v_now = poly_values(ring, V_scaled, shifted, len(samples))
    values = ParameterValues()
    for i, gi in field.flows:
        values.set_poly(ring, f"g{i}", -gi, ring.support(gi))
    values.set_poly(ring, "s1", rho, ring.support(rho) or [tuple([0] * ring.nvars)])
    values.set_poly(ring, "negs1", known, ring.support(known))
    values.set_matrix("M", sample_moments(Z, v_now))
    values.set_scalar("floor", ROA_FLOOR)
    solution = search.solve(structure, values)
    if not solution.usable:
        return f"the V step found no V ({why_none(solution)})"
    V = GramPoly.of(z_v, round_matrix(solution.grams["V"], VS_ROUND_BITS)).poly(ring)
    return V if not V.is_zero() else "the V step gave V = 0"


def sample_moments(Z: np.ndarray, v_now: np.ndarray, nearest: float = VSTEP_NEAREST,
                   normalize: bool = VSTEP_NORMALIZE) -> np.ndarray:
    """The V step's objective matrix ``M`` (``<Q_V, M>``, the weighted mean of ``V`` over samples): ``Z`` the
    samples' monomial vectors (rows), ``v_now`` the current ``V`` at level 1 there. The samples outside the
    current set weigh (this share of them, the nearest to it), each vector normalized where ``normalize``;
    all samples where none is outside."""
    outside = v_now > 1
    weighted = Z[outside] if np.any(outside) else Z
    if nearest < 1.0 and np.any(outside):
        order = np.argsort(v_now[outside])
        weighted = weighted[order[:max(1, int(np.ceil(nearest * weighted.shape[0])))]]
    count = weighted.shape[0]
    if normalize:
        norms = np.linalg.norm(weighted, axis=1, keepdims=True)
        weighted = weighted[norms[:, 0] > 0] / norms[norms[:, 0] > 0]
    M = weighted.T @ weighted / max(count, 1)
    return (M + M.T) / 2
