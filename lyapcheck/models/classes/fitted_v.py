"""A candidate V for a region of attraction, fitted to simulations of the true loop by a linear program.

This is the search half of the ball-arithmetic route (:mod:`lyapcheck.models.engines.interval_region` is
the proof half); nothing here is trusted. The true loop is simulated from a grid over a box twice
the size of the comparison box (the region of attraction of a damped machine is a long band that
leaves the box). ``V`` is the linearization's quadratic form ``alpha x^T P0 x`` (``J^T P0 + P0 J =
-I``, so ``V`` decreases near the equilibrium) plus free terms of degree 3 to ``d``; a linear
program (HiGHS, through SciPy) asks, at the samples:

* ``V' <= -eps |x|^2`` and ``V >= eps |x|^2`` where the simulated trajectory converges;
* ``V >= 1 + margin`` where it does not, and on the big box's edge (so that ``{V <= 1}`` closes
  inside it and leaves out what does not converge);
* ``V``'s top-degree form positive on the unit cube's faces (so that ``V`` grows in every
  direction and its sublevel sets can be proved bounded);

and minimizes the sum of ``V`` over the converging samples inside the comparison box, which pulls
as many of them as it can below 1. The level proposed (:func:`_level_and_box`, also for a user's
candidate, :func:`propose_level`) is a little under the largest at which the component of
``{V <= level}`` holding the equilibrium has no point of a fine grid where ``V' >= 0`` (away from
the equilibrium) or on the big box's edge, lowered again where random points of the set see
``V' >= 0``; the box proposed is that component's bounding box, widened. The proof then decides.
"""

from __future__ import annotations

from dataclasses import dataclass
from fractions import Fraction
from typing import Any, Callable, Final, Sequence

import numpy as np

from lyapcheck.models.engines.interval_region import IntervalClaim, dyadic_ceil, dyadic_floor
from lyapcheck.models.language.recast import RecastSystem
from lyapcheck.sos.polynomials import Poly, Ring

#: the sampled box is the comparison box scaled by this about its centre
FIT_GROWTH: Final = 2.0
#: samples per state of the grid over the sampled box, by number of states
FIT_GRID: Final = {1: 401, 2: 81, 3: 29, 4: 11}
#: the extra grid near the equilibrium (its half-width is this share of the box's smallest half-width)
FIT_LOCAL_SHARE: Final = 0.4
FIT_LOCAL_GRID: Final = {1: 101, 2: 31, 3: 11, 4: 7}
#: the decrease and positivity margin at the samples (times |x|^2)
FIT_EPSILON: Final = 0.02
#: V at a sample that does not converge (or on the edge) is at least 1 + this
FIT_OUTSIDE_MARGIN: Final = 0.05
#: V's top-degree form at points of the unit cube's faces is at least this over the box's largest
#: half-width to the degree (so V grows in every direction), at this many points per face side
FIT_TOP_MARGIN: Final = 1e-2
FIT_TOP_DIRECTIONS: Final = {1: 1, 2: 33, 3: 9, 4: 5}
#: the smallest alpha (V's quadratic part is alpha x^T P0 x)
FIT_MIN_ALPHA: Final = 1e-3
#: V's degree, by number of states
FIT_DEGREE: Final = {1: 8, 2: 6, 3: 4, 4: 4}
#: the fine grid on which the level is proposed (samples per state)
LEVEL_GRID: Final = {1: 4001, 2: 401, 3: 61, 4: 25}
#: the sizes the roa route fits a V at (the dictionaries above also hold 4 states, for
#: ``fit_v(..., any_size=True)``: issue 42's measurement of a quartic V at 4 states, whose proof at
#: that size does not fit the class's budget yet)
ROUTE_STATES: Final = (1, 2, 3)
#: the level proposed is this share of the smallest V where the fine grid sees V' >= 0
LEVEL_SHARE: Final = 0.98
#: random points of the proposed set checked in floating point before the proof (rounds, points)
LEVEL_CHECK_ROUNDS: Final = 4
LEVEL_CHECK_POINTS: Final = 20000
#: a simulated start that gets farther than this many times the sampled box's size from the
#: equilibrium is stopped there, as not converging
FIT_ESCAPE: Final = 5.0
#: the simulation's horizon (the loop's time unit) and the radius that counts as converged
FIT_HORIZON: Final = 30.0
FIT_CONVERGED: Final = 2e-2
#: a simulated start that comes this close to the equilibrium in every state stops being integrated (it
#: has converged: the linearization is Hurwitz, and this is a hundredth of FIT_CONVERGED); the rest of its
#: horizon at the error test's tightest steps was most of the fit's time (the fit only proposes a V, the
#: ball-arithmetic proof decides)
FIT_SETTLE: Final = 2e-4
#: the error test of the fit's simulations (relative, absolute per state): ten times looser than the
#: cross-checks' (:data:`lyapcheck.models.engines.recast_numeric.RTOL`), far below FIT_CONVERGED; on every
#: shipped loop the fit classifies every start as before and proposes the same V
FIT_RTOL: Final = 1e-6
FIT_ATOL: Final = 1e-8
#: V's coefficients are rounded to dyadic rationals with this many significant bits
COEFFICIENT_BITS: Final = 30


@dataclass(frozen=True)
class FittedV:
    claim: IntervalClaim
    #: the share of the converging samples of the comparison box below the level (an estimate)
    sampled_share: float


def _grid(lo: np.ndarray, hi: np.ndarray, count: int) -> np.ndarray:
    axes = [np.linspace(a, b, count) for a, b in zip(lo, hi)]
    return np.column_stack([g.ravel() for g in np.meshgrid(*axes, indexing="ij")])


def _cube_faces(n: int, count: int) -> np.ndarray:
    """Points on the faces of the cube ``[-1, 1]^n`` (``count`` per side of each face)."""
    if n == 1:
        return np.array([[-1.0], [1.0]])
    points = []
    for i in range(n):
        for side in (-1.0, 1.0):
            face = _grid(-np.ones(n - 1), np.ones(n - 1), count)
            points.append(np.insert(face, i, side, axis=1))
    return np.vstack(points)


def _monomials(n: int, degree: int) -> list[tuple[int, ...]]:
    from itertools import product

    return sorted((m for m in product(range(degree + 1), repeat=n) if 3 <= sum(m) <= degree),
                  key=lambda m: (sum(m), m))


def _columns(Z: np.ndarray, F: np.ndarray, P0: np.ndarray, mons: list[tuple[int, ...]]
             ) -> tuple[np.ndarray, np.ndarray]:
    """The LP's columns at the samples: V's and V''s values for the quadratic form and each monomial."""
    n = Z.shape[1]
    top = max((max(m) for m in mons), default=1)
    powers = [[np.ones(len(Z))] for _ in range(n)]
    with np.errstate(over="ignore"):  # a far sample's powers: inf (see below)
        for i in range(n):
            for _ in range(top):
                powers[i].append(powers[i][-1] * Z[:, i])

    def monomial(e: Sequence[int]) -> np.ndarray:
        out = powers[0][e[0]]
        for i in range(1, n):
            if e[i]:
                out = out * powers[i][e[i]]
        return out

    # a far sample (or one where the field overflowed) gives inf or nan here: the callers keep only
    # finite rows (``good``; _level_and_box counts a non-finite V' as a violation)
    with np.errstate(over="ignore", invalid="ignore"):
        V = [np.einsum("ij,jk,ik->i", Z, P0, Z)]
        dV = [2 * np.einsum("ij,jk,ik->i", Z, P0, F)]
        for m in mons:
            V.append(monomial(m))
            d = np.zeros(len(Z))
            for i in range(n):
                if m[i]:
                    e = list(m)
                    e[i] -= 1
                    d += m[i] * monomial(e) * F[:, i]
            dV.append(d)
    return np.column_stack(V), np.column_stack(dV)


def _dyadic(x: float, bits: int = COEFFICIENT_BITS) -> Fraction:
    if x == 0 or not np.isfinite(x):
        return Fraction(0)
    e = int(np.floor(np.log2(abs(x))))
    scale = 2 ** (bits - 1 - e)
    return Fraction(round(x * scale)) / scale if scale >= 1 else Fraction(round(x * scale)) / Fraction(scale)


@dataclass(frozen=True)
class _Sampling:
    """Where a loop is sampled: its equilibrium, the comparison box (deviations ``lo..hi``), that
    box grown by FIT_GROWTH (``blo..bhi``) and the half-width of the extra grid at the equilibrium."""

    eq: np.ndarray
    lo: np.ndarray
    hi: np.ndarray
    blo: np.ndarray
    bhi: np.ndarray
    local: float


def _sampling(system: RecastSystem, box: tuple[Any, Any], growth: float = FIT_GROWTH) -> _Sampling:
    lo, hi = (np.asarray(b, dtype=float) for b in box)
    centre, half = (lo + hi) / 2, (hi - lo) / 2
    return _Sampling(np.array([float(system.values[s]) for s in system.states]), lo, hi,
                     centre - growth * half, centre + growth * half, FIT_LOCAL_SHARE * float(np.min(half)))


def _jacobian(system: RecastSystem) -> np.ndarray:
    """The field's Jacobian at the equilibrium: the exact one of the chain rule
    (:func:`lyapcheck.models.classes.recast_classes.jacobian`) in floats, or a central difference where that
    has none (an irrational entry)."""
    from lyapcheck.models.classes.recast_classes import base_loop, jacobian
    from lyapcheck.models.engines.recast_numeric import field_values

    exact = jacobian(base_loop(system))
    if not isinstance(exact, str):
        return np.array([[float(x) for x in row] for row in exact])
    eq = np.array([float(system.values[s]) for s in system.states])
    h = 1e-6
    return np.column_stack([(field_values(system, eq + h * e) - field_values(system, eq - h * e))[0] / (2 * h)
                            for e in np.eye(system.n)])


@dataclass(frozen=True)
class Corners:
    """Constants a V must serve at every value of (a box's parameters, disturbances): the loop recast
    with them as its last states, and the corners of their intervals (absolute values)."""

    system: RecastSystem
    points: list[np.ndarray]

    @classmethod
    def of(cls, system: RecastSystem, intervals: Sequence[tuple[Fraction, Fraction]]) -> "Corners":
        from itertools import product

        return cls(system, [np.array(c, dtype=float) for c in product(*[(float(a), float(b)) for a, b in intervals])])

    def fields(self, Z: np.ndarray, eq: np.ndarray, n: int) -> list[np.ndarray]:
        """The field at the state deviations ``Z`` at each corner."""
        from lyapcheck.models.engines.recast_numeric import FloatLoop

        loop = FloatLoop(self.system)
        return [loop(np.column_stack([Z + eq, np.tile(c, (len(Z), 1))]))[:, :n] for c in self.points]

    def jacobians(self, eq: np.ndarray, n: int) -> list[np.ndarray]:
        """The field's Jacobian at the equilibrium at each corner (central differences)."""
        h = 1e-6
        steps = np.eye(n)
        plus = [self.fields(h * e[None, :], eq, n) for e in steps]  # per step, the field at every corner
        minus = [self.fields(-h * e[None, :], eq, n) for e in steps]
        return [np.column_stack([(plus[i][k] - minus[i][k])[0] / (2 * h) for i in range(n)])
                for k in range(len(self.points))]

    def converge(self, Z: np.ndarray, eq: np.ndarray, n: int, escape: float) -> np.ndarray:
        """Which starts converge to the equilibrium at every corner (simulated)."""
        from lyapcheck.models.engines.recast_numeric import simulate_ends

        ok = np.ones(len(Z), dtype=bool)
        # the constants (the columns after the n states) do not move: only the states settle
        settle = np.array([FIT_SETTLE] * n + [np.inf] * (self.system.n - n))
        for c in self.points:
            dev, _ = simulate_ends(self.system, np.column_stack([Z + eq, np.tile(c, (len(Z), 1))]), FIT_HORIZON,
                                   escape=escape, settle=settle, rtol=FIT_RTOL, atol=FIT_ATOL)
            d = np.linalg.norm(dev[:, :n], axis=1)
            d[~np.all(np.isfinite(dev[:, :n]), axis=1)] = np.inf
            ok &= d < FIT_CONVERGED
        return ok


def common_lyapunov(jacobians: Sequence[np.ndarray], discrete: bool = False, floor: float = 1e-6
                    ) -> np.ndarray | None:
    """A ``P >= floor I`` with ``J^T P + P J <= -I`` (``discrete``: ``J^T P J - P <= -I``) for every
    Jacobian (a small SDP, least trace; None where the solver finds none or its point misses half the
    margin): the quadratic part of a V common to a box, whose Jacobian is affine in the parameters there.
    A proposal only: the proof decides."""
    import cvxpy as cp

    def decrease(J: Any, P: Any) -> Any:
        return J.T @ P @ J - P if discrete else J.T @ P + P @ J

    n = jacobians[0].shape[0]
    P = cp.Variable((n, n), symmetric=True)
    cons = [P >> floor * np.eye(n)] + [decrease(J, P) << -np.eye(n) for J in jacobians]
    problem = cp.Problem(cp.Minimize(cp.trace(P)), cons)
    try:
        problem.solve(solver=cp.CLARABEL)
    except cp.error.SolverError:
        return None
    if problem.status != "optimal" or P.value is None:
        return None
    value = (P.value + P.value.T) / 2
    if any(np.max(np.linalg.eigvalsh(decrease(J, value))) >= -0.5 for J in jacobians):
        return None  # (the solver's point, checked: the proof decides in any case)
    return np.asarray(value)


def fit_excluded(system: RecastSystem, any_size: bool = False) -> str | None:
    """Why no V is fitted to this loop whatever the box (one line), or None: the route takes 1 to 3
    states (``any_size``: every size of FIT_GRID), and a linearization that is Hurwitz (the V's
    quadratic part comes from it)."""
    n = system.n
    if n not in (FIT_GRID if any_size else ROUTE_STATES):
        return f"the ball-arithmetic route takes loops of 1 to 3 states, not {n}"
    J = _jacobian(system)
    if not np.all(np.isfinite(J)) or np.max(np.linalg.eigvals(J).real) >= -1e-9:
        return "the linearization is not Hurwitz: no quadratic V to start from"
    return None


def fit_v(system: RecastSystem, ring: Ring, box: tuple[Any, Any], corners: Corners | None = None,
          max_steps: int | None = None, growth: float = FIT_GROWTH, any_size: bool = False,
          quadratic: np.ndarray | None = None) -> FittedV | str:
    """A proposed claim (V, level, box) for the ball-arithmetic proof, or why none (one line). With
    ``corners``, V is asked to serve every corner of the constants (its quadratic part a common
    Lyapunov function of their linearizations, its decrease at the samples at each corner);
    ``max_steps``: each simulated row's step budget (a row stopped by it does not converge);
    ``growth``: the sampled box is ``box`` scaled by this about its centre; ``any_size``: also at the
    sizes beyond the route's (FIT_GRID's, issue 42's measurement at 4 states); ``quadratic``: V's
    quadratic part is ``alpha`` times this matrix (an LQR cost-to-go) instead of the Lyapunov equation's."""
    from scipy.linalg import solve_continuous_lyapunov

    from lyapcheck.models.engines.recast_numeric import distances, field_values, simulate_ends

    n = system.n
    unfit = fit_excluded(system, any_size)
    if unfit is not None:
        return unfit
    J = _jacobian(system)
    at = _sampling(system, box, growth)
    eq, lo, hi, blo, bhi, local = at.eq, at.lo, at.hi, at.blo, at.bhi, at.local
    if quadratic is not None:
        P0 = np.asarray(quadratic, dtype=float)
    elif corners is None:
        P0 = solve_continuous_lyapunov(J.T, -np.eye(n))
    else:
        common = common_lyapunov([J, *corners.jacobians(eq, n)])
        if common is None:
            return "no quadratic V is common to the linearizations at the corners (a box too wide for one V)"
        P0 = common
    half = (hi - lo) / 2
    Z = np.vstack([_grid(blo, bhi, FIT_GRID[n]), _grid(-local * np.ones(n), local * np.ones(n), FIT_LOCAL_GRID[n])])
    # a trajectory far outside the sampled box does not converge (and stopping it keeps a batch
    # with one finite escape time from crawling)
    escape = FIT_ESCAPE * float(np.max(bhi - blo))
    dev, _ = simulate_ends(system, Z + eq, FIT_HORIZON, escape=escape, max_steps=max_steps, settle=FIT_SETTLE,
                           rtol=FIT_RTOL, atol=FIT_ATOL)
    converges = distances(system, dev) < FIT_CONVERGED
    if corners is not None:
        converges &= corners.converge(Z, eq, n, escape)
    edge = np.any(np.isclose(Z, blo) | np.isclose(Z, bhi), axis=1)
    F = field_values(system, Z + eq)
    mons = _monomials(n, FIT_DEGREE[n])
    Vc, dVc = _columns(Z, F, P0, mons)
    corner_dV = [] if corners is None else [_columns(Z, Fc, P0, mons)[1] for Fc in corners.fields(Z, eq, n)]
    r2 = np.sum(Z ** 2, axis=1)
    good = converges & ~edge & (r2 > 1e-12) & np.all(np.isfinite(F), axis=1)
    bad = ~converges | edge
    # V's top-degree form positive on the faces of the unit cube (so V grows in every direction and a
    # sublevel set is bounded: the proof then claims the whole of it, not its part in a box)
    top = FIT_DEGREE[n]
    U = _cube_faces(n, FIT_TOP_DIRECTIONS[n])
    Ut = np.zeros((len(U), 1 + len(mons)))
    for k, mon in enumerate(mons):
        if sum(mon) == top:
            Ut[:, 1 + k] = np.prod(U ** np.array(mon), axis=1)
    A = np.vstack([dVc[good], *[d[good] for d in corner_dV], -Vc[good], -Vc[bad], -Ut])
    b = np.concatenate([-FIT_EPSILON * r2[good], *[-FIT_EPSILON * r2[good] for _ in corner_dV], -FIT_EPSILON * r2[good],
                        -(1 + FIT_OUTSIDE_MARGIN) * np.ones(int(bad.sum())),
                        -FIT_TOP_MARGIN / float(np.max(half)) ** top * np.ones(len(U))])
    inside = good & np.all((Z >= lo) & (Z <= hi), axis=1)
    if not inside.any():
        return "no simulated trajectory from the box converges"
    cost = Vc[inside].sum(axis=0)
    bounds = [(FIT_MIN_ALPHA, None)] + [(None, None)] * len(mons)
    lp = _solve_fit(cost / max(1.0, float(np.abs(cost).max())), A, b, bounds)
    if isinstance(lp, str):
        return f"the fitting linear program found no V ({lp})"
    w = lp
    # V exactly: dyadic coefficients, the quadratic part alpha P0 rounded as a whole
    terms: dict[tuple[int, ...], Fraction] = {}
    for i in range(n):
        for j in range(i, n):
            m = [0] * ring.nvars
            m[i] += 1
            m[j] += 1
            terms[tuple(m)] = _dyadic(w[0] * P0[i, j] * (1 if i == j else 2))
    for c, mon in zip(w[1:], mons):
        if abs(c) > 1e-12:
            terms[tuple(list(mon) + [0] * (ring.nvars - n))] = _dyadic(float(c))
    V: Poly = ring.from_terms({m: c for m, c in terms.items() if c})
    def values(Z: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        with np.errstate(all="ignore"):  # (a rational field at a pole: inf or nan, which fails the decrease)
            Vz, dVz = _columns(Z, field_values(system, Z + eq), P0, mons)
            return Vz @ w, dVz @ w

    proposal = _level_and_box(system, V, values, blo, bhi, local, 1.0)
    if isinstance(proposal, str):
        return proposal
    dev_in = converges & np.all((Z >= lo) & (Z <= hi), axis=1)
    sampled = float(np.mean((Vc[dev_in] @ w) <= float(proposal.level))) if dev_in.any() else 0.0
    return FittedV(proposal, sampled)


def _solve_fit(cost: np.ndarray, A: np.ndarray, b: np.ndarray, bounds: Sequence[tuple[float | None, float | None]]
               ) -> np.ndarray | str:
    """The fitting program's solution, or HiGHS's word on why there is none.

    The program's columns are V's monomials at the samples, up to about 1e8 apart on a wide box:
    on an infeasible program HiGHS's simplex then thrashes (a minute or more over a hundred
    iterations, to end "model_status is Unknown"). So feasibility is decided first on the same
    program with each column scaled to a largest entry of 1 (the same feasible set, conditioned; a
    second or so); only a feasible program is solved as it stands (the V proposed is the one it
    always was), and where that solve fails numerically, the conditioned program's optimum is taken.
    Nothing here is trusted: the proof decides.
    """
    from scipy.optimize import linprog

    scale = np.abs(A).max(axis=0)
    scale[~(scale > 0)] = 1.0
    scaled_bounds = [(None if lo is None else lo * s, None if hi is None else hi * s)
                     for (lo, hi), s in zip(bounds, scale)]
    feasible = linprog(np.zeros(len(scale)), A_ub=A / scale, b_ub=b, bounds=scaled_bounds, method="highs")
    if feasible.status == 2:  # proved infeasible (HiGHS Status 8)
        return feasible.message.strip()
    lp = linprog(cost, A_ub=A, b_ub=b, bounds=bounds, method="highs")
    if lp.status == 0:
        return np.asarray(lp.x)
    conditioned = linprog(cost / scale, A_ub=A / scale, b_ub=b, bounds=scaled_bounds, method="highs")
    if conditioned.status == 0:
        return np.asarray(conditioned.x) / scale
    return lp.message.strip()


def _level_and_box(system: RecastSystem, V: Poly, values: Callable[[np.ndarray], tuple[np.ndarray, np.ndarray]],
                   blo: np.ndarray, bhi: np.ndarray, local: float, cap: float | None) -> IntervalClaim | str:
    """The level proposed for ``V`` (``values(Z)``: V and V' at deviations, floats): a little under
    the smallest V where a fine grid of the box ``[blo, bhi]`` sees ``V' >= 0`` (away from the
    equilibrium) or on the box's edge, lowered again where random points of the set see it; and the
    box around the set, widened. ``cap``: the level is at most that."""
    from scipy.ndimage import label

    n = system.n
    count = LEVEL_GRID[n]
    fine = _grid(blo, bhi, count)
    vf, dvf = values(fine)
    rf = np.sum(fine ** 2, axis=1)
    fine_edge = np.any(np.isclose(fine, blo) | np.isclose(fine, bhi), axis=1)
    worst = (dvf >= 0) & (rf > (0.05 * local) ** 2) | ~np.isfinite(dvf) | ~np.isfinite(vf) | fine_edge
    centre = int(np.argmin(rf))

    def component(c: float) -> np.ndarray:
        """The grid points of {V <= c} connected to the equilibrium's."""
        labels, _ = label((np.nan_to_num(vf, nan=np.inf) <= c).reshape((count,) * n))
        flat = labels.ravel()
        return flat == flat[centre] if flat[centre] else np.zeros(len(flat), dtype=bool)

    # the largest level whose component holds no point where V' >= 0 (bisection: it grows with c)
    low, high = 0.0, float(np.nanmax(vf[np.isfinite(vf)])) if cap is None else cap
    if not component(high)[worst].any():
        low = high
    else:
        for _ in range(40):
            mid = (low + high) / 2
            low, high = (mid, high) if not component(mid)[worst].any() else (low, mid)
    level_f = LEVEL_SHARE * low
    if not level_f > 0:
        return "V decreases on no sampled level set"
    under = component(level_f)
    step = (bhi - blo) / (count - 1)
    zlo = np.maximum(fine[under].min(axis=0) - 2 * step, blo)
    zhi = np.minimum(fine[under].max(axis=0) + 2 * step, bhi)
    # random points of the set between the grid's: a V' >= 0 there lowers the level before any proof
    rng = np.random.default_rng(0)
    for _ in range(LEVEL_CHECK_ROUNDS):
        R = zlo + (zhi - zlo) * rng.random((LEVEL_CHECK_POINTS, n))
        vr, dvr = values(R)
        rr = np.sum(R ** 2, axis=1)
        violating = (vr <= level_f) & ((dvr >= -1e-9 * rr) | ~np.isfinite(dvr)) & (rr > (0.05 * local) ** 2)
        if not violating.any():
            break
        level_f = LEVEL_SHARE * float(np.min(vr[violating]))
        if not level_f > 0:
            return "V decreases on no sampled level set"
    return IntervalClaim(V, dyadic_floor(Fraction(level_f)), tuple(dyadic_floor(Fraction(float(x))) for x in zlo),
                         tuple(dyadic_ceil(Fraction(float(x))) for x in zhi))


def propose_robust_level(system: RecastSystem, robust: RecastSystem, intervals: Sequence[tuple[Fraction, Fraction]],
                         V: Poly, box: tuple[Any, Any], growth: float = FIT_GROWTH) -> IntervalClaim | str:
    """A claim for ``V`` (over the states) that should hold for every value of some constants: its
    level from sampling, with ``V'`` the largest over the corners of their ``intervals`` (a
    disturbance's ``+-b``, a box parameter's ``lo`` and ``hi``; the loop ``robust`` has them as its
    last states)."""
    from itertools import product

    from lyapcheck.models.engines.recast_numeric import FloatLoop, poly_values

    n = system.n
    if n not in ROUTE_STATES:
        return f"the ball-arithmetic route takes loops of 1 to 3 states, not {n}"
    at = _sampling(system, box, growth)
    field = FloatLoop(robust)
    corners = [np.array(c, dtype=float) for c in product(*[(float(lo), float(hi)) for lo, hi in intervals])]
    ring = system.ring
    gradient = [V.derivative(i) for i in range(n)]

    def values(Z: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        columns = dict(zip(ring.names, Z.T))  # V is over the states alone
        grad = np.column_stack([poly_values(ring, g, columns, len(Z)) for g in gradient])
        worst = np.full(len(Z), -np.inf)
        for d in corners:
            F = field(np.column_stack([Z + at.eq, np.tile(d, (len(Z), 1))]))[:, :n]
            worst = np.maximum(worst, np.sum(grad * F, axis=1))
        return poly_values(ring, V, columns, len(Z)), worst

    return _level_and_box(system, V, values, at.blo, at.bhi, at.local, 1.0)


def propose_level(system: RecastSystem, V: Poly, box: tuple[Any, Any]) -> IntervalClaim | str:
    """A claim for a given ``V`` (a user's candidate, over the states and the smooth auxiliaries, in
    deviations): its level and box from sampling (``V'`` by a central difference along the field)."""
    from lyapcheck.models.engines.recast_numeric import field_values, v_values

    n = system.n
    if n not in ROUTE_STATES:
        return f"the ball-arithmetic route takes loops of 1 to 3 states, not {n}"
    at = _sampling(system, box)

    def values(Z: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        F = field_values(system, Z + at.eq)
        h = 1e-6 * max(1.0, float(np.max(np.abs(at.bhi - at.blo))))
        with np.errstate(all="ignore"):
            dv = (v_values(system, V, Z + h * F) - v_values(system, V, Z - h * F)) / (2 * h)
        return v_values(system, V, Z), dv

    return _level_and_box(system, V, values, at.blo, at.bhi, at.local, None)


__all__ = ["FittedV", "Corners", "common_lyapunov", "fit_excluded", "fit_v", "propose_level", "propose_robust_level"]
