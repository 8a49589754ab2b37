"""A region of attraction of a loop with functions, proved on the true field by ball arithmetic.

The claim: every trajectory of the true loop that starts in ``Omega = {x : x - x_eq in B,
V(x - x_eq) <= level}`` converges to the equilibrium ``x_eq``, for a polynomial ``V`` over the state
deviations, a rational ``level`` and a box ``B`` (dyadic corners). The proof has three parts, each a
finite computation that :func:`prove_region` runs and ``verify`` runs again:

1. **The boundary.** ``V > level`` on every face of ``B`` (ball arithmetic, faces bisected until
   each piece is proved). So ``Omega`` is compact and a trajectory cannot leave it without
   crossing ``{V > level}``: as long as ``V`` does not increase, ``Omega`` is invariant.
2. **The decrease.** ``B`` is bisected into cells; every cell on which ``V <= level`` somewhere
   either has ``g = grad V . f < 0`` on the whole cell, proved in ball arithmetic (the natural
   enclosure, else the second-order Taylor form ``g(m) + grad g(m) . t + t^T H(cell) t / 2``), or
   lies in the box ``N = [-r, r]^n`` of part 3. A cell whose centre has ``g >= 0`` proved and
   ``V <= level`` ends the proof at once: the claim is false at this level.
3. **The equilibrium, exactly.** ``V`` has no constant or linear term (checked on its exact
   coefficients; for a ``V`` that uses the loop's functions, ``V`` and its gradient in the states
   vanish at the equilibrium by the exact chain rule) and ``f(x_eq) = 0`` (checked exactly when the
   model is read), so ``g(0) = 0``
   and ``grad g(0) = 0``; the Hessian of ``g`` over ``N`` (chain rule in ball arithmetic, each
   function's exact derivatives) is negative definite for every matrix of its enclosure (Cholesky
   in ball arithmetic). Then ``g(z) = int_0^1 (1 - t) z^T H(t z) z dt < 0`` for every ``z != 0`` in
   ``N``: no ball around the equilibrium is left unproved, unlike a delta-complete check.

With ``g < 0`` on ``Omega`` except at the equilibrium and ``Omega`` compact and invariant, every
trajectory from ``Omega`` converges to the equilibrium (``V`` decreases at a rate bounded away from
0 near any other point of ``Omega``; ``V`` need not be positive). The claim is in the states
themselves, not modulo 2 pi. :func:`prove_bounded` (part 0, optional) proves ``V > level``
everywhere outside ``B``: then ``Omega`` is the whole sublevel set ``{V <= level}``.

Ball arithmetic is python-flint's ``arb``: each result encloses the exact one, outward rounding
included. The cells and bisections are deterministic (the same inputs give the same cells), so
``verify`` repeats the proof cell for cell; it stores no cell list.
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from fractions import Fraction
from typing import Any, Final

import flint

from lyapcheck.exact import DYADIC_BITS, dyadic_ceil, dyadic_floor
from lyapcheck.models.engines.interval_field import BallLoop, LieDerivative, negative_definite
from lyapcheck.models.language.recast import RecastSystem
from lyapcheck.sos.polynomials import Poly, Ring

#: the most cells a proof may examine in each part (the boundary, the decrease) before it gives up
#: (``verify``'s bound; a search's attempt has its own, smaller one: INTERVAL_ATTEMPT_CELLS)
INTERVAL_CELL_LIMIT: Final = 400_000
#: how a reason names the usual attempt's cell budget (a caller with another budget names its own)
ATTEMPT_CELLS_NAME: Final = "lyapcheck.tolerances.INTERVAL_ATTEMPT_CELLS"
#: why a proof stopped at its deadline: the class's wall-clock limit, a safety net only (the work
#: budgets above decide every outcome a test or a documented figure depends on)
SAFETY_NET: Final = "stopped by the class's time limit (a safety net; lyapcheck.tolerances.MODEL_CLASS_TIME_LIMIT_S)"
#: the finest bisection: a cell is not split below this fraction of the box's width in each state
#: (with MAGNITUDE_BITS + DYADIC_BITS + 13 + 1 <= 53 every corner and midpoint is an exact double)
INTERVAL_MIN_WIDTH: Final = Fraction(1, 2 ** 13)
#: the local box N = [-r, r]^n: the largest r tried is the box's smallest half-width over 2^this,
#: halved until the Hessian test passes, at most LOCAL_HALVINGS times
LOCAL_FIRST_SHIFT: Final = 3
LOCAL_HALVINGS: Final = 24
#: the outer radius (beyond which V > level in every direction) is sought within 2^this times the
#: box's size before a direction cell is accepted with a farther one
OUTER_RADIUS_SHIFT: Final = 3
#: a box corner's magnitude is below 2^this: with DYADIC_BITS after the point and the finest
#: bisection, every cell corner and midpoint is then exact in a double (53 bits)
MAGNITUDE_BITS: Final = 12


def is_dyadic(x: Fraction, bits: int = DYADIC_BITS) -> bool:
    """``x`` has at most ``bits`` bits after the binary point and magnitude below 2^MAGNITUDE_BITS."""
    return (x * 2 ** bits).denominator == 1 and abs(x) < 2 ** MAGNITUDE_BITS


@dataclass(frozen=True)
class IntervalClaim:
    """``{x : x - x_eq in [lo, hi], V(x - x_eq) <= level}``, with ``V`` in the ring's state deviations."""

    V: Poly
    level: Fraction
    lo: tuple[Fraction, ...]
    hi: tuple[Fraction, ...]
    #: ``V`` is a positive definite quadratic form over the states and the boundary is proved exactly
    #: (:func:`exact_faces`) instead of by bisecting the faces; a set that lies in the local box
    #: ``N`` (:func:`inside_local_box`) then needs no cell of the decrease (a certificate's
    #: ``"boundary": "exact"``)
    exact_boundary: bool = False


@dataclass(frozen=True)
class IntervalProof:
    """What :func:`prove_region` established (``ok``) or why not, and what it took."""

    ok: bool
    why: str
    cells: int
    boundary_cells: int
    local_radius: Fraction | None
    seconds: float
    #: V at a point of the set where V' >= 0 was proved (the claim is then false at this level)
    counterexample_v: float | None = None


class _Cells:
    """Deterministic bisection of a box of floats (dyadic corners: exact as floats and as balls)."""

    def __init__(self, lo: tuple[Fraction, ...], hi: tuple[Fraction, ...]) -> None:
        self.widths = [float(h - l) for l, h in zip(lo, hi)]
        self.min_width = [w * float(INTERVAL_MIN_WIDTH) for w in self.widths]

    def balls(self, cell: tuple[tuple[float, float], ...]) -> list[Any]:
        return [flint.arb((a + b) / 2, (b - a) / 2) for a, b in cell]

    def centers(self, cell: tuple[tuple[float, float], ...]) -> list[Any]:
        return [flint.arb((a + b) / 2) for a, b in cell]

    def radii(self, cell: tuple[tuple[float, float], ...]) -> list[Any]:
        return [flint.arb(0, (b - a) / 2) for a, b in cell]  # exact: dyadic

    def split(self, cell: tuple[tuple[float, float], ...], fixed: int | None = None
              ) -> tuple[tuple[tuple[float, float], ...], ...] | None:
        """The two halves of ``cell`` across its widest side relative to the box (never ``fixed``), or
        ``None`` when every side is already at the finest width."""
        best, k = -1.0, -1
        for i, (a, b) in enumerate(cell):
            if i == fixed or (b - a) <= self.min_width[i]:
                continue
            rel = (b - a) / self.widths[i]
            if rel > best:
                best, k = rel, i
        if k < 0:
            return None
        a, b = cell[k]
        m = (a + b) / 2
        left = cell[:k] + ((a, m),) + cell[k + 1:]
        right = cell[:k] + ((m, b),) + cell[k + 1:]
        return left, right


def _second_order_negative(lie: LieDerivative, cells: _Cells, cell: tuple[tuple[float, float], ...]) -> bool | None:
    """``g < 0`` on the cell by the second-order form ``g(m) + grad g(m) . t + t^T H(cell) t / 2`` with
    ``|t_i| <= r_i`` (``H`` enclosed over the cell: Taylor's theorem with the Lagrange remainder);
    ``None`` when ``g(m) >= 0`` is proved at the centre ``m`` itself (no bisection can help there)."""
    at = lie.jet(cells.centers(cell), 1)
    if at.value >= 0 and any(a + b != 0 for a, b in cell):  # (at the equilibrium g = 0: no counterexample)
        return None
    hess = lie.jet(cells.balls(cell), 2).hess
    if hess is None or at.grad is None:
        return False
    radii = [flint.arb((b - a) / 2) for a, b in cell]  # exact: dyadic
    zero = flint.arb(0)
    total = at.value
    for i, gi in enumerate(at.grad):
        total = total + gi * zero.union(radii[i]).union(-radii[i])
        # t_i^2 / 2 in [0, r_i^2 / 2]; t_i t_j for i < j in [-r_i r_j, r_i r_j] (H_ij + H_ji, halved)
        total = total + hess[i][i] * zero.union(radii[i] * radii[i] / 2)
        for j in range(i + 1, len(radii)):
            p = radii[i] * radii[j]
            total = total + hess[i][j] * p.union(-p)
    return bool(total < 0)


def _v_above(lie: LieDerivative, cells: _Cells, cell: tuple[tuple[float, float], ...], level: Any,
             mean_value: bool) -> bool:
    """``V > level`` on the cell (natural enclosure, then the mean-value form if asked)."""
    if lie.value_of_v(cells.balls(cell)) > level:
        return True
    if not mean_value:
        return False
    grads = lie.gradient_of_v(cells.balls(cell))
    total = lie.value_of_v(cells.centers(cell))
    for gi, ri in zip(grads, cells.radii(cell)):
        total = total + gi * ri
    return bool(total > level)


def local_radius(lie: LieDerivative, lo: tuple[Fraction, ...], hi: tuple[Fraction, ...]) -> Fraction | None:
    """The largest ``r`` (a power of 2 below the box's smallest half-width) for which the Hessian of
    ``g`` on ``[-r, r]^n`` is negative definite, or ``None``."""
    half = min(min(-l, h) for l, h in zip(lo, hi))
    if half <= 0:
        return None
    r = Fraction(1)
    while r > half:
        r /= 2
    while r * 2 <= half:
        r *= 2
    r /= 2 ** LOCAL_FIRST_SHIFT
    for _ in range(LOCAL_HALVINGS):
        z = [flint.arb(0, float(r)) for _ in range(lie.n)]
        jet = lie.jet(z, 2)
        if jet.hess is not None and negative_definite(jet.hess):
            return r
        r /= 2
    return None


def quadratic_form(ring: Ring, V: Poly, n: int) -> list[list[Fraction]] | None:
    """``P`` with ``V = z^T P z`` (exact) when ``V`` is a quadratic form in the first ``n`` variables, else None."""
    P = [[Fraction(0)] * n for _ in range(n)]
    for m, c in ring.terms(V).items():
        if sum(m) != 2 or any(m[n:]):
            return None
        i = next(k for k in range(n) if m[k])
        j = next(k for k in range(n - 1, -1, -1) if m[k])
        if i == j:
            P[i][i] = Fraction(c)
        else:
            P[i][j] = P[j][i] = Fraction(c) / 2
    return P


def inverse_diagonal(P: list[list[Fraction]]) -> list[Fraction] | None:
    """The diagonal of ``P^-1`` (exact, Gauss-Jordan in rationals), or None when ``P`` is not
    positive definite (checked exactly). ``min {z^T P z : z_i = h} = h^2 / (P^-1)_ii``: the
    smallest value of ``V`` on the hyperplane of a face, hence on the face."""
    from lyapcheck.exact import inverse
    from lyapcheck.sos.definiteness import is_positive_definite

    if not is_positive_definite(P):
        return None
    return [row[i] for i, row in enumerate(inverse(P))]


def exact_faces(ring: Ring, claim: IntervalClaim, n: int) -> str | None:
    """Part 1 exactly, for a positive definite quadratic form ``V = z^T P z``: ``V > level`` on the face
    ``z_i = c`` because ``level (P^-1)_ii < c^2`` (rational arithmetic); None when every face is
    proved, else why not."""
    P = quadratic_form(ring, claim.V, n)
    diagonal = None if P is None else inverse_diagonal(P)
    if diagonal is None:
        return "an exact boundary needs V a positive definite quadratic form over the states"
    for i in range(n):
        for side in (claim.lo[i], claim.hi[i]):
            if not claim.level * diagonal[i] < side * side:
                return f"V > level is not proved on the face where {ring.names[i]} - eq is {side} (exactly)"
    return None


def inside_local_box(ring: Ring, claim: IntervalClaim, n: int, radii: list[Fraction]) -> bool:
    """The whole set ``{V <= level}`` lies in ``prod [-r_i, r_i]``, exactly: ``level (P^-1)_ii <= r_i^2`` for
    each state (``V = z^T P z`` positive definite; ``max {z_i : z^T P z <= level} = sqrt(level (P^-1)_ii)``)."""
    P = quadratic_form(ring, claim.V, n)
    diagonal = None if P is None else inverse_diagonal(P)
    return diagonal is not None and all(claim.level * d <= r * r for d, r in zip(diagonal, radii))


def local_box(lie: LieDerivative, lo: tuple[Fraction, ...], hi: tuple[Fraction, ...]) -> list[Fraction] | None:
    """For an exact-boundary claim: the local box ``N`` is the claim's box (its symmetric part) shrunk by the
    first power of 2 (from 1, at most LOCAL_HALVINGS halvings) on which the Hessian of ``g`` is negative
    definite, its half-widths; None when none is. Shaped like the box, so like the ellipsoid of a
    quadratic ``V`` (an ill-conditioned ``P`` fits no cube)."""
    halves = [min(-l, h) for l, h in zip(lo, hi)]
    if min(halves) <= 0:
        return None
    for j in range(LOCAL_HALVINGS):
        radii = [h / 2 ** j for h in halves]
        jet = lie.jet([flint.arb(0, float(r)) for r in radii], 2)
        if jet.hess is not None and negative_definite(jet.hess):
            return radii
    return None


def low_order_terms(ring: Ring, V: Poly, n: int) -> bool:
    """Whether ``V`` has a constant or linear term, or uses a variable beyond the first ``n`` (exact)."""
    for m in ring.terms(V):
        if sum(m) < 2 or any(m[n:]):
            return True
    return False


#: the least number of states at which an exact-boundary claim's decrease is proved on cells of the
#: ellipsoid's own coordinates (:mod:`lyapcheck.models.engines.ellipsoid_cells`); below it on the box's cells
ELLIPSOID_MIN_STATES: Final = 4


def _prove_on_ellipsoid(lie: LieDerivative, ring: Ring, claim: IntervalClaim, n: int, radii: list[Fraction],
                        cell_budget: int | None, deadline: float | None, boundary: int, r: Fraction | None,
                        start: float, budget_name: str) -> IntervalProof:
    """Part 2 of an exact-boundary claim at ELLIPSOID_MIN_STATES states or more: ``V' < 0`` on the whole
    ellipsoid ``{V <= level}`` (which the exact faces put inside the box) except at the equilibrium."""
    from lyapcheck.models.engines.ellipsoid_cells import prove_ellipsoid

    P = quadratic_form(ring, claim.V, n)
    assert P is not None  # (exact_faces proved it a positive definite quadratic form)
    diagonal = inverse_diagonal(P)
    assert diagonal is not None
    found = prove_ellipsoid(lie, P, diagonal, claim.level, radii, cell_budget, INTERVAL_CELL_LIMIT, deadline,
                            SAFETY_NET, budget_name=budget_name)
    return IntervalProof(found.ok, found.why, found.cells, boundary, r, time.perf_counter() - start,
                         found.counterexample_v)


def prove_region(system: RecastSystem, claim: IntervalClaim, deadline: float | None = None,
                 lie: Any = None, flat: bool | None = None, cell_budget: int | None = None,
                 budget_name: str = ATTEMPT_CELLS_NAME) -> IntervalProof:
    """Prove the claim's three parts (module docstring) on the true field; deterministic.

    ``V`` over the states alone by default; for a ``V`` that uses auxiliaries, ``lie`` is its
    :class:`~lyapcheck.models.engines.interval_field.RecastLieDerivative` and ``flat`` whether ``V`` and its
    gradient in the states vanish at the equilibrium, decided exactly by the caller (part 3 needs it).
    ``cell_budget`` bounds the cells of the boundary and the decrease together (a search's work budget,
    :data:`~lyapcheck.tolerances.INTERVAL_ATTEMPT_CELLS`: the outcome is the same on any machine and
    under any load; ``budget_name``: the constant the caller set it from, named when it is spent); each
    part is also bounded by INTERVAL_CELL_LIMIT. ``deadline`` (a
    ``time.perf_counter()`` value) is only a safety net: the class's time limit, named as such when
    it stops the proof.
    """
    start = time.perf_counter()
    ring = system.ring
    n = system.n if lie is None else lie.n  # (a robust evaluator's system also has the disturbances)

    def failed(why: str, cells: int = 0, boundary: int = 0, r: Fraction | None = None) -> IntervalProof:
        return IntervalProof(False, why, cells, boundary, r, time.perf_counter() - start)

    if len(claim.lo) != n or len(claim.hi) != n:
        return failed("the box does not have one side per state")
    if not all(is_dyadic(x) for x in claim.lo + claim.hi) or not all(l < 0 < h for l, h in zip(claim.lo, claim.hi)):
        return failed(f"the box's corners must be dyadic (at most {DYADIC_BITS} bits after the point) with the "
                      "equilibrium strictly inside")
    if claim.level <= 0:
        return failed("the level must be > 0")
    if lie is None:
        if low_order_terms(ring, claim.V, n):
            return failed("V must be a polynomial in the state deviations without constant or linear terms")
        lie = LieDerivative(BallLoop(system), ring, claim.V)
    elif not flat:
        return failed("V and its gradient in the states must vanish at the equilibrium (checked exactly)")
    level = flint.arb(flint.fmpq(claim.level.numerator, claim.level.denominator))
    cells = _Cells(claim.lo, claim.hi)
    box = tuple((float(l), float(h)) for l, h in zip(claim.lo, claim.hi))
    count = 0

    def out_of_cells(part: int, total: int) -> str | None:
        """Why the proof stops at this many cells of the part and of both parts, or None."""
        if cell_budget is not None and total > cell_budget:
            return f"more than the attempt's {cell_budget} cells ({budget_name})"
        return f"more than {INTERVAL_CELL_LIMIT} cells" if part > INTERVAL_CELL_LIMIT else None

    # 1. the boundary: V > level on each face (exactly for a quadratic form, if the claim says so)
    if claim.exact_boundary and (why := exact_faces(ring, claim, n)) is not None:
        return failed(why)
    for i in range(n if not claim.exact_boundary else 0):
        for side in (box[i][0], box[i][1]):
            stack = [box[:i] + ((side, side),) + box[i + 1:]]
            while stack:
                cell = stack.pop()
                count += 1
                if (why := out_of_cells(count, count)) is not None:
                    return failed(why, boundary=count)
                if deadline is not None and time.perf_counter() > deadline:
                    return failed(SAFETY_NET + " on the boundary", boundary=count)
                if _v_above(lie, cells, cell, level, mean_value=True):
                    continue
                halves = cells.split(cell, fixed=i)
                if halves is None:
                    where = ", ".join(f"{s} - eq in [{a:.6g}, {b:.6g}]" for s, (a, b) in zip(system.states, cell))
                    return failed(f"V > level is not proved on the box's boundary at {where}", boundary=count)
                stack.extend(reversed(halves))
    boundary = count
    # 3. the local box around the equilibrium
    radii = local_box(lie, claim.lo, claim.hi) if claim.exact_boundary else None
    r = min(radii) if radii is not None else None if claim.exact_boundary else local_radius(lie, claim.lo, claim.hi)
    if r is None:
        return failed("the Hessian of V' is not proved negative definite on any box around the equilibrium",
                      boundary=boundary)
    local = [float(x) for x in radii] if radii is not None else [float(r)] * n  # N's half-widths
    if radii is not None and inside_local_box(ring, claim, n, radii):  # the set lies in N: part 3 covers it
        return IntervalProof(True, "proved", 0, boundary, r, time.perf_counter() - start)
    if claim.exact_boundary and radii is not None and n >= ELLIPSOID_MIN_STATES and isinstance(lie, LieDerivative):
        proof = _prove_on_ellipsoid(lie, ring, claim, n, radii, cell_budget, deadline, boundary, r, start,
                                    budget_name)
        if proof.ok or cell_budget is not None or proof.counterexample_v is not None:
            return proof
        # verify (no budget) of a certificate proved on the box's cells before issue 42: that proof, below
    # 2. the decrease on every cell of B that meets {V <= level}
    stack = [box]
    count = 0
    while stack:
        cell = stack.pop()
        count += 1
        if (why := out_of_cells(count, boundary + count)) is not None:
            return failed(why, count, boundary, r)
        if deadline is not None and count % 256 == 0 and time.perf_counter() > deadline:
            return failed(SAFETY_NET, count, boundary, r)
        if all(-x <= a and b <= x for (a, b), x in zip(cell, local)):
            continue  # inside N: part 3
        if _v_above(lie, cells, cell, level, mean_value=False):
            continue
        if lie(cells.balls(cell)) < 0:
            continue
        second = _second_order_negative(lie, cells, cell)
        if second:
            continue
        if second is None:
            centre = cells.centers(cell)
            v = lie.value_of_v(centre)
            if v <= level:  # a point of the set where V' >= 0: the claim is false at this level
                where = ", ".join(f"{s} - eq = {(a + b) / 2:.6g}" for s, (a, b) in zip(system.states, cell))
                return IntervalProof(False, f"V' >= 0 at {where}, where V = {float(v.mid()):.6g} <= level (proved): "
                                     "V does not decrease on the whole set at this level", count, boundary, r,
                                     time.perf_counter() - start, float(v.mid()))
        if _v_above(lie, cells, cell, level, mean_value=True):
            continue
        halves = cells.split(cell)
        if halves is None:
            where = ", ".join(f"{s} - eq in [{a:.6g}, {b:.6g}]" for s, (a, b) in zip(system.states, cell))
            return failed(f"V' < 0 is not proved at {where} (at the finest cells)", count, boundary, r)
        stack.extend(reversed(halves))
    return IntervalProof(True, "proved", count, boundary, r, time.perf_counter() - start)


def prove_bounded(system: RecastSystem, claim: IntervalClaim, deadline: float | None = None,
                  cell_limit: int = INTERVAL_CELL_LIMIT) -> tuple[bool, str, int, Fraction | None]:
    """Part 0, for a ``V`` over the states alone: ``V > level`` everywhere outside the box, so the
    whole sublevel set ``{V <= level}`` lies in it. On the faces of the unit cube (``u``, ball cells),
    ``V(t u) = sum_k t^k V_k(u)`` with ``V_k`` the homogeneous parts (even top degree ``d``), and
    ``V(t u)/t^d - level/t^d >= low(V_d(u)) - sum_{k<d} up(|V_k(u)|) t^(k-d) - level t^-d``, which
    grows with ``t``: once positive at ``t = R`` it is positive beyond, so ``V > level`` wherever
    ``|z|_inf >= R`` (R the largest over the cells, a power of 2). Between the box and
    ``[-R, R]^n`` cells are bisected until ``V > level`` is proved on each. Returns (proved, why,
    cells, R)."""
    ring = system.ring
    n = system.n
    terms = ring.terms(claim.V)
    if not terms or any(any(m[n:]) for m in terms) or low_order_terms(ring, claim.V, n):
        return False, "V must be over the states alone, without constant or linear terms", 0, None
    d = max(sum(m) for m in terms)
    if d % 2:
        return False, "V's degree is odd: V does not grow in every direction", 0, None
    loop = BallLoop(system)
    parts = [LieDerivative(loop, ring, ring.from_terms({m: c for m, c in terms.items() if sum(m) == k}))
             for k in range(2, d + 1)]
    level = flint.arb(flint.fmpq(claim.level.numerator, claim.level.denominator))
    smallest = Fraction(1)
    while smallest < max(max(-l, h) for l, h in zip(claim.lo, claim.hi)):
        smallest *= 2

    def radius(u: list[Any]) -> Fraction | None:
        """The smallest power of 2 (from ``smallest``) beyond which V > level along the cell's rays."""
        values = [part.value_of_v(u) for part in parts]
        top = values[-1]
        if not top > 0:
            return None
        R = smallest
        while R < 2 ** MAGNITUDE_BITS:
            t = flint.arb(flint.fmpq(R.numerator, R.denominator))
            margin = top - level / t ** d
            for k, v in zip(range(2, d), values[:-1]):
                margin = margin - abs(v) / t ** (d - k)
            if margin > 0:
                return R
            R *= 2
        return None

    unit = _Cells((Fraction(-1),) * n, (Fraction(1),) * n)
    R = smallest
    count = 0
    for i in range(n):
        for side in (-1.0, 1.0):
            stack = [tuple((side, side) if k == i else (-1.0, 1.0) for k in range(n))]
            while stack:
                cell = stack.pop()
                count += 1
                if count > cell_limit or (deadline is not None and time.perf_counter() > deadline):
                    return False, "out of cells or time on the unit cube's faces", count, None
                r = radius(unit.balls(cell))
                halves = unit.split(cell, fixed=i)
                # a far radius from a wide cell is mostly the enclosure's looseness: split it first
                if r is not None and (r <= smallest * 2 ** OUTER_RADIUS_SHIFT or halves is None):
                    R = max(R, r)
                    continue
                if halves is None:
                    return False, (f"V is not proved to exceed the level beyond |z|_inf = 2^{MAGNITUDE_BITS} in "
                                   "every direction"), count, None
                stack.extend(reversed(halves))
    lie = LieDerivative(BallLoop(system), ring, claim.V)
    outer = _Cells(claim.lo, claim.hi)  # cells as fine as the box's own near it
    inner = [(float(l), float(h)) for l, h in zip(claim.lo, claim.hi)]
    level_ball = level
    stack = [tuple((-float(R), float(R)) for _ in range(n))]
    while stack:
        cell = stack.pop()
        count += 1
        if count > cell_limit or (deadline is not None and count % 256 == 0 and time.perf_counter() > deadline):
            return False, "out of cells or time outside the box", count, R
        if all(a >= lo_ and b <= hi_ for (a, b), (lo_, hi_) in zip(cell, inner)):
            continue  # inside the box: the decrease part covers it
        overlaps = all(a < hi_ and b > lo_ for (a, b), (lo_, hi_) in zip(cell, inner))
        cut = next(((k, x) for k, ((a, b), (lo_, hi_)) in enumerate(zip(cell, inner)) for x in (lo_, hi_)
                    if a < x < b), None) if overlaps else None
        if cut is not None:  # split along the box's face: each piece is then inside or outside it
            k, x = cut
            stack.append(cell[:k] + ((cell[k][0], x),) + cell[k + 1:])
            stack.append(cell[:k] + ((x, cell[k][1]),) + cell[k + 1:])
            continue
        if _v_above(lie, outer, cell, level_ball, mean_value=True):
            continue
        halves = outer.split(cell)
        if halves is None:
            where = ", ".join(f"{s} - eq in [{a:.6g}, {b:.6g}]" for s, (a, b) in zip(system.states, cell))
            return False, f"V > level is not proved outside the box at {where}", count, R
        stack.extend(reversed(halves))
    return True, "proved", count, R


__all__ = ["IntervalClaim", "IntervalProof", "prove_region", "prove_bounded", "dyadic_floor", "dyadic_ceil",
           "is_dyadic",
           "INTERVAL_CELL_LIMIT"]
