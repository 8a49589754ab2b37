"""Simulated trajectories checked against what a model certificate proves.

The one home of these checks: the report's phase portrait (:mod:`reports.phase_portrait`),
``simulate --model --worst-case --certificate`` (:func:`lyapcheck.models.surfaces.simulate.tightness`) and
the sweeps of model files (:mod:`sweeps.crosscheck`) all call them.

==================  ===================================================  ========================
certificate         what must hold along a simulated trajectory           check
==================  ===================================================  ========================
``roa`` {V <= c}    a start in the set stays in it: V never rises, and     :func:`check_region`
                    the trajectory does not escape
``quadratic``,      V never rises, and ``V(t) <= V(0) exp(-rate t)`` with   :func:`check_global`
``sos_gas``         the certified decay rate of V (0: none claimed)
``quadratic`` GES   ``|x(t) - x_eq| <= k |x0 - x_eq| exp(-rate t)``        :func:`check_ges_envelope`
``sos_bound``       the storage function stays below its envelope          :func:`check_storage`
                    ``1 + (V(0) - 1) exp(-lam t)``; the tail sup of each
                    output stays below its certified bound                  :func:`bound_exceeded`
``barrier``         a start in the initial set never enters the unsafe     :func:`check_safety`
                    set
``reach_avoid``     a start in the initial set is in the goal by the       :func:`check_reach_avoid`
                    certified time bound, and does not enter the unsafe
                    set before it reaches the goal
==================  ===================================================  ========================

A rise, an excess or a ratio counts only beyond
:data:`~lyapcheck.tolerances.TRAJECTORY_CHECK_REL_TOL` (relative), which absorbs the integrator's
error, never a modelling slack. Every check reads the integrator's own points
(:attr:`lyapcheck.models.engines.trajectories.Trajectory.nodes`).

The two set checks read a set's margin along a trajectory, each inequality relative to the size of its
terms there (:func:`scaled_margin`: ``>= 0`` inside, in ``[-1, 1]``, independent of the states' units):
the unsafe set is entered only where it exceeds the tolerance, the goal is reached where it is above
minus the tolerance. A time is read as the last point before the goal was
reached (a lower bound of the time it was reached, up to a graze between two points), and the time
bound is exceeded only beyond the tolerance, relative to the bound.

Two helpers feed them: :func:`certificate_function` turns a certificate's exact ``V`` (in the
declared states shifted to the equilibrium; over a box also in the box's parameters) into a float
function of the scaled states ``u = (x - x_eq) / s`` at given parameter values, with every
coefficient rounded once from its exact value there; :func:`ray_boundary` finds where a set
``{V <= c}`` ends along rays from the equilibrium (bisection on the first crossing).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from fractions import Fraction
from typing import Any, Callable, Final, Mapping, Sequence

import numpy as np
import numpy.typing as npt

from lyapcheck.tolerances import TRAJECTORY_CHECK_REL_TOL
from lyapcheck.exact import read_rational

FloatArray = npt.NDArray[np.float64]
#: a float function of a batch of points ``(k, n)`` (scaled states): ``(k,)`` values
PointFunction = Callable[[FloatArray], FloatArray]

#: radii tried along each ray, in scaled states (where certified sets are of order 1), and the
#: bisection steps on the first crossing (2**-48 of a bracket: far below any drawn or simulated scale)
RAY_RADII: Final = np.geomspace(1e-6, 1e4, 400)
BISECTIONS: Final = 48


def rise(values: FloatArray) -> float:
    """The largest rise of a sequence above its running minimum so far, relative to its first value."""
    values = np.asarray(values, dtype=np.float64)
    if values.size < 2:
        return 0.0
    before = np.minimum.accumulate(values)[:-1]
    return float(np.max(values[1:] - before) / max(abs(values[0]), 1e-300))


@dataclass(frozen=True)
class RegionCheck:
    """Trajectories from inside a certified region of attraction ``{V <= c}``."""

    starts: int
    worst_rise: float
    escaped: int
    converged: int

    @property
    def ok(self) -> bool:
        return self.escaped == 0 and self.worst_rise <= TRAJECTORY_CHECK_REL_TOL


def check_region(values: Sequence[FloatArray], outcomes: Sequence[str]) -> RegionCheck:
    """``values[i]``: V along trajectory ``i`` (which started in the set), ``outcomes[i]`` how it ended
    (``converged``, ``escaped`` or ``other``, :class:`~lyapcheck.models.engines.trajectories.Trajectory`)."""
    rises = [max(rise(v), 0.0) for v in values]
    return RegionCheck(len(values), max(rises, default=0.0), sum(o == "escaped" for o in outcomes),
                       sum(o == "converged" for o in outcomes))


@dataclass(frozen=True)
class GlobalCheck:
    """Trajectories under a global Lyapunov function: V's largest rise and its largest excess over the
    certified decay envelope, both relative to V(0), and how many trajectories escaped."""

    trajectories: int
    worst_rise: float
    worst_envelope: float
    escaped: int

    @property
    def ok(self) -> bool:
        return (self.escaped == 0 and self.worst_rise <= TRAJECTORY_CHECK_REL_TOL
                and self.worst_envelope <= TRAJECTORY_CHECK_REL_TOL)


def check_global(series: Sequence[tuple[FloatArray, FloatArray]], outcomes: Sequence[str], rate: float) -> GlobalCheck:
    """``series[i] = (t, V(x(t)))`` of trajectory ``i``; ``rate`` the certified decay rate of V per
    second (``V' <= -rate V``; 0 when only ``V' < 0`` is certified)."""
    worst_rise, worst_envelope = 0.0, 0.0
    for t, v in series:
        worst_rise = max(worst_rise, rise(v))
        if rate > 0 and v.size:
            envelope = v[0] * np.exp(-rate * t)
            worst_envelope = max(worst_envelope, float(np.max(v - envelope) / max(abs(v[0]), 1e-300)))
    return GlobalCheck(len(series), worst_rise, worst_envelope, sum(o == "escaped" for o in outcomes))


def check_storage(series: Sequence[tuple[FloatArray, FloatArray]], rate: float) -> float:
    """The largest excess of a storage function over its certified envelope ``1 + (V(0) - 1) exp(-rate t)``
    (``sos_bound``: every trajectory enters ``{V <= 1}`` at that rate), relative to ``max(1, |V(0)|)``;
    0 when it holds everywhere. Compare with :data:`~lyapcheck.tolerances.TRAJECTORY_CHECK_REL_TOL`."""
    worst = 0.0
    for t, v in series:
        if not v.size:
            continue
        envelope = 1.0 + (v[0] - 1.0) * np.exp(-rate * t)
        worst = max(worst, float(np.max(v - envelope) / max(1.0, abs(v[0]))))
    return worst


def check_ges_envelope(series: Sequence[tuple[FloatArray, FloatArray]], k: float, rate: float) -> float:
    """The largest ``|x(t) - x_eq| / (k |x0 - x_eq| exp(-rate t))`` over trajectories given as
    ``(t, |x(t) - x_eq|)`` (a GES certificate's envelope; at most 1 when it holds, NaN with none)."""
    worst = math.nan
    for t, norm in series:
        if not norm.size or not norm[0] > 0:
            continue
        ratio = float(np.max(norm / (k * norm[0] * np.exp(-rate * t))))
        worst = ratio if math.isnan(worst) else max(worst, ratio)
    return worst


def bound_exceeded(bound: float, simulated: float, rel_tol: float) -> bool:
    """A simulated tail sup beyond a certified bound, past the relative tolerance ``rel_tol`` (the
    caller's named one: the simulator's accuracy contract, or a sweep's bound tolerance)."""
    return bool(simulated > bound * (1 + rel_tol))


def scaled_margin(state_set: Sequence[Sequence[Any]], points: FloatArray, scale: FloatArray) -> FloatArray:
    """A set's margin at each row of ``points`` (``(k, n)``, the declared states), each inequality
    ``p >= 0`` divided by the size of its terms there: ``p(x) / sum_m |c_m| prod_i (|x_i| + scale_i)**m_i``,
    in ``[-1, 1]``; a piece's the smallest of its inequalities', the set's the largest of its pieces'
    (``>= 0`` exactly where :func:`lyapcheck.models.language.sets.margin` is). The denominator bounds
    what rounding and the integrator's error (relative to the states, or to ``scale``: the problem's
    extent per state) can do to ``p(x)``, so that a figure above a small tolerance is conclusive, and
    the figure does not depend on the states' units nor shrink along a trajectory that runs far away.
    ``state_set``: pieces of polynomials of a state ring (the states first, any others at exponent 0)."""
    x = np.atleast_2d(np.asarray(points, dtype=np.float64))
    ax = np.abs(x) + np.asarray(scale, dtype=np.float64)[None, :]
    n = x.shape[1]
    out = np.full(x.shape[0], -np.inf)
    with np.errstate(all="ignore"):
        for piece in state_set:
            inner = np.full(x.shape[0], np.inf)
            for p in piece:
                exponents = np.array([tuple(int(e) for e in m) for m in p.monoms()], dtype=np.int64)
                coefficients = np.array([float(Fraction(int(c.p), int(c.q))) for c in p.coeffs()])
                if not coefficients.size:
                    inner = np.minimum(inner, 0.0)
                    continue
                exponents = exponents.reshape(len(coefficients), -1)
                if exponents.shape[1] < n or exponents[:, n:].any():
                    raise ValueError(f"a point has {n} coordinates; the set's polynomial {p} needs the states of "
                                     "its ring")
                e = exponents[:, :n]
                value = np.prod(x[:, None, :] ** e[None, :, :], axis=2) @ coefficients
                size = np.prod(ax[:, None, :] ** e[None, :, :], axis=2) @ np.abs(coefficients)
                inner = np.minimum(inner, np.where(size > 0, value / size, 0.0))
            out = np.maximum(out, inner)
    return np.asarray(np.where(np.isnan(out), -np.inf, out), dtype=np.float64)


@dataclass(frozen=True)
class SafetyCheck:
    """Trajectories from the initial set under a barrier certificate (the unsafe set is never entered):
    how many, how many entered the unsafe set, which first (index, None: none) and the largest
    unsafe margin reached (:func:`scaled_margin`; ``< 0``: none came inside; NaN: none)."""

    trajectories: int
    entered: int
    first: int | None
    worst_margin: float

    @property
    def ok(self) -> bool:
        return self.entered == 0


def check_safety(unsafe_margins: Sequence[FloatArray]) -> SafetyCheck:
    """``unsafe_margins[i]``: the unsafe set's margin (:func:`scaled_margin`) at the points of trajectory
    ``i`` (which started in the initial set); it entered where that exceeds
    :data:`~lyapcheck.tolerances.TRAJECTORY_CHECK_REL_TOL`."""
    entered, first, worst = 0, None, math.nan
    for i, values in enumerate(unsafe_margins):
        rel = np.asarray(values, dtype=np.float64)
        if not rel.size:
            continue
        top = float(np.nanmax(rel)) if np.any(np.isfinite(rel)) else math.nan
        if math.isfinite(top):
            worst = top if math.isnan(worst) else max(worst, top)
        if top > TRAJECTORY_CHECK_REL_TOL:
            entered += 1
            first = i if first is None else first
    return SafetyCheck(len(unsafe_margins), entered, first, worst)


@dataclass(frozen=True)
class ReachAvoidCheck:
    """Trajectories from the initial set under a reach-avoid certificate: how many entered the unsafe set
    before the goal (``entered``, the first of them ``first_entered``), how many were not in the goal by
    the time bound (``late``, the first ``first_late``), the largest unsafe margin before the goal
    (:func:`scaled_margin`, as :class:`SafetyCheck`) and the largest time before the goal over the bound
    (``reach_ratio``, a trajectory that never reached it counting its whole simulated time; NaN: none); ``unreached``:
    the trajectories not in the goal at any of their points (late, or simulated too briefly to tell)."""

    trajectories: int
    entered: int
    late: int
    unreached: int
    first_entered: int | None
    first_late: int | None
    worst_margin: float
    reach_ratio: float

    @property
    def ok(self) -> bool:
        return self.entered == 0 and self.late == 0


def check_reach_avoid(series: Sequence[tuple[FloatArray, FloatArray, FloatArray]], bound_s: float) -> ReachAvoidCheck:
    """``series[i] = (t, unsafe margin, goal margin)`` at the points of trajectory ``i`` (which started
    in the initial set; margins of :func:`scaled_margin`), simulated beyond ``bound_s (1 +
    TRAJECTORY_CHECK_REL_TOL)`` (:func:`reach_horizon`). The goal is reached at the first point whose
    goal margin is at least ``-TRAJECTORY_CHECK_REL_TOL``; the time before it is the point before that
    one (a lower bound of the time it was reached). Late: that time beyond ``bound_s (1 +
    TRAJECTORY_CHECK_REL_TOL)``; entered: an unsafe margin above ``TRAJECTORY_CHECK_REL_TOL`` at a point
    before the goal."""
    entered = late = unreached = 0
    first_entered: int | None = None
    first_late: int | None = None
    worst, ratio = math.nan, math.nan
    for i, (t, unsafe, goal) in enumerate(series):
        t = np.asarray(t, dtype=np.float64)
        if not t.size:
            continue
        reached = np.flatnonzero(np.asarray(goal, dtype=np.float64) >= -TRAJECTORY_CHECK_REL_TOL)
        k = int(reached[0]) if reached.size else t.size  # the first point in the goal (t.size: none)
        unreached += not reached.size
        before = 0.0 if k == 0 else float(t[k - 1])
        ratio = before / bound_s if math.isnan(ratio) else max(ratio, before / bound_s)
        if before > bound_s * (1 + TRAJECTORY_CHECK_REL_TOL):
            late += 1
            first_late = i if first_late is None else first_late
        rel = np.asarray(unsafe, dtype=np.float64)[:k]
        top = float(np.nanmax(rel)) if np.any(np.isfinite(rel)) else math.nan
        if math.isfinite(top):
            worst = top if math.isnan(worst) else max(worst, top)
        if top > TRAJECTORY_CHECK_REL_TOL:
            entered += 1
            first_entered = i if first_entered is None else first_entered
    return ReachAvoidCheck(len(series), entered, late, unreached, first_entered, first_late, worst, ratio)


def reach_horizon(bound_s: float) -> float:
    """How long a reach-avoid cross-check simulates: past the certified time bound by twice the
    tolerance, so that a trajectory not in the goal by then is conclusively late."""
    return bound_s * (1 + 2 * TRAJECTORY_CHECK_REL_TOL)


def certificate_function(terms: Mapping[str, Any], names: Sequence[str], n: int, values: Mapping[str, Fraction],
                         scales: Sequence[Fraction]) -> PointFunction:
    """A certificate's exact polynomial as a float function of the scaled states ``u``.

    Parameters
    ----------
    terms
        ``{"terms": [["p/q", [e_1, ..., e_k]], ...]}``: the contract's exact polynomial, one exponent
        per name of ``names``.
    names
        The variables of the exponents: the ``n`` states first, then any others (a storage
        function's disturbances, a box certificate's parameters).
    values
        Exact values of every variable after the states (a disturbance 0, a parameter its value).
    scales
        ``s_i > 0``: the polynomial is returned in ``u_i = (x_i - x_eq,i) / s_i``, where its
        coefficients are of moderate size, each rounded to a float once from its exact value.

    Raises
    ------
    ValueError
        When the terms are not such a polynomial (a term of the wrong length, a bad coefficient).
    """
    from lyapcheck.models.engines.numeric import NumericPoly
    from lyapcheck.sos.polynomials import Ring

    raw = terms.get("terms") if isinstance(terms, Mapping) else None
    if not isinstance(raw, list):
        raise ValueError("a polynomial must be {'terms': [[coefficient, exponents], ...]}")
    merged: dict[tuple[int, ...], Fraction] = {}
    for term in raw:
        if not isinstance(term, (list, tuple)) or len(term) != 2 or len(term[1]) != len(names):
            raise ValueError(f"a term must be [coefficient, {len(names)} exponents], got {str(term)[:80]}")
        key = tuple(int(e) for e in term[1])
        merged[key] = merged.get(key, Fraction(0)) + read_rational(term[0])
    ring = Ring(tuple(names))
    poly = ring.from_terms(merged)
    others = {name: values[name] for name in names[n:]}
    if others:
        poly = ring.substitute(poly, others)
    states = Ring(tuple(names[:n]))
    poly = ring.restrict(poly, states)
    images = [states.gen(name) * states.constant(Fraction(s)) for name, s in zip(names[:n], scales)]
    poly = states.compose(poly, images)
    return NumericPoly(states, poly)


def ray_boundary(function: PointFunction, level: float, directions: FloatArray,
                 radii: FloatArray = RAY_RADII, bisections: int = BISECTIONS) -> FloatArray | None:
    """Where ``{function <= level}`` ends along each ray from 0 (``directions``: ``(rays, n)`` unit
    vectors), as ``(rays, n)`` points just inside; None when 0 is not in the set or a ray does not
    leave it within the largest radius (an unbounded set, or one far larger than its scale)."""
    directions = np.asarray(directions, dtype=np.float64)
    n = directions.shape[1]

    def at(points: FloatArray) -> FloatArray:
        return np.asarray(function(points.reshape(-1, n)), dtype=np.float64).reshape(points.shape[:-1])

    if not at(np.zeros((1, n)))[0] <= level:
        return None
    outside = ~(at(radii[:, None, None] * directions[None, :, :]) <= level)  # NaN counts as outside
    if not outside.any(axis=0).all():
        return None
    first = np.argmax(outside, axis=0)
    lo = np.where(first > 0, radii[np.maximum(first - 1, 0)], 0.0)
    hi = radii[first]
    for _ in range(bisections):
        mid = 0.5 * (lo + hi)
        inside = at(mid[:, None] * directions) <= level
        lo = np.where(inside, mid, lo)
        hi = np.where(inside, hi, mid)
    return np.asarray(lo[:, None] * directions, dtype=np.float64)


__all__ = ["rise", "RegionCheck", "check_region", "GlobalCheck", "check_global", "check_storage",
           "check_ges_envelope", "scaled_margin", "SafetyCheck", "check_safety", "ReachAvoidCheck",
           "check_reach_avoid", "reach_horizon", "bound_exceeded", "certificate_function", "ray_boundary", "RAY_RADII",
           "BISECTIONS"]
