"""A model's field in floating point, for simulation: vectorized over many states at once.

:class:`NumericPoly` evaluates an exact polynomial at a batch of points (one numpy expression per
monomial power); :class:`FieldEvaluator` gives ``x' = f(x, d)`` of a model (rational: numerator
over denominator, as declared, in the declared coordinates and SI units) for batches of states
and disturbances; :class:`ModelSystem` is the batched system the project's integrator
(:mod:`lyapcheck.integrator`) takes; :func:`converges` classifies starts by where
their trajectories end (the simulated region of attraction of the ``roa`` class).
Nothing here decides a status: simulations are evidence, and cross-checks of what was proved.
"""

from __future__ import annotations

from dataclasses import dataclass
from fractions import Fraction
from typing import Any, Callable, Mapping, Sequence

import numpy as np

from lyapcheck.models.language.modelfile import Model, field_at
from lyapcheck.integrator import Evaluation, integrate
from lyapcheck.sos.polynomials import MonomialPlan, Poly, Ring, monomial_plan, monomial_values
from lyapcheck.tolerances import SIM_MAX_STEPS


class NumericPoly:
    """A polynomial as exponent and coefficient arrays, evaluated at ``(batch, nvars)`` points."""

    def __init__(self, ring: Ring, p: Poly) -> None:
        terms = ring.float_terms(p)
        self.exponents = np.array(list(terms), dtype=np.int64).reshape(-1, ring.nvars)
        self.coefficients = np.array(list(terms.values()), dtype=np.float64)
        self.max_power = int(self.exponents.max()) if self.exponents.size else 0

    def __call__(self, x: np.ndarray) -> np.ndarray:
        x = np.atleast_2d(x)
        if not self.coefficients.size:
            return np.zeros(x.shape[0])
        powers = [np.ones_like(x)]
        for _ in range(self.max_power):
            powers.append(powers[-1] * x)
        out = np.zeros(x.shape[0])
        nv = x.shape[1]
        for e, c in zip(self.exponents, self.coefficients):
            term = np.full(x.shape[0], c)
            for k in range(nv):
                if e[k]:
                    term = term * powers[e[k]][:, k]
            out += term
        return out


@dataclass
class FieldEvaluator:
    """``x' = f(x, d)`` of a model at fixed parameters (declared coordinates, SI)."""

    model: Model
    numerators: list[NumericPoly]
    denominators: list[NumericPoly]

    def __post_init__(self) -> None:
        # every right-hand side at once: the monomials of all numerators (and denominators) evaluated
        # once per call, then one matrix product (the integrators call this thousands of times; a
        # loop over terms and states per polynomial was most of a stiff model's simulation)
        self._num = _stacked(self.numerators)
        self._den = None if all(_is_one(p) for p in self.denominators) else _stacked(self.denominators)

    @classmethod
    def of(cls, model: Model, parameters: Mapping[str, Fraction] | None = None) -> "FieldEvaluator":
        ring = model.state_ring
        rhs = field_at(model, parameters)
        return cls(model, [NumericPoly(ring, r.numerator) for r in rhs], [NumericPoly(ring, r.denominator) for r in rhs])

    def __call__(self, x: np.ndarray, d: np.ndarray | None = None) -> np.ndarray:
        x = np.atleast_2d(x)
        m = len(self.model.disturbances)
        if m:
            d = np.zeros((x.shape[0], m)) if d is None else np.broadcast_to(d, (x.shape[0], m))
            xd = np.hstack([x, d])
        else:
            xd = x
        out = _evaluate_stacked(self._num, xd)
        return out if self._den is None else out / _evaluate_stacked(self._den, xd)


def _is_one(p: NumericPoly) -> bool:
    return p.exponents.shape[0] == 1 and not p.exponents.any() and float(p.coefficients[0]) == 1.0


def _stacked(polys: list[NumericPoly]) -> tuple[np.ndarray, np.ndarray, MonomialPlan]:
    """The union of the polynomials' monomials (rows of exponents) and each polynomial's coefficients
    over it (a matrix, one row per polynomial)."""
    index: dict[tuple[int, ...], int] = {}
    for p in polys:
        for e in p.exponents:
            index.setdefault(tuple(int(k) for k in e), len(index))
    nvars = polys[0].exponents.shape[1] if polys and polys[0].exponents.size else 0
    exponents = np.array(list(index), dtype=np.int64).reshape(len(index), nvars)
    coefficients = np.zeros((len(polys), len(index)))
    for i, p in enumerate(polys):
        for e, c in zip(p.exponents, p.coefficients):
            coefficients[i, index[tuple(int(k) for k in e)]] += c
    return exponents, coefficients, monomial_plan(exponents)


def _evaluate_stacked(stacked: tuple[np.ndarray, np.ndarray, MonomialPlan], x: np.ndarray) -> np.ndarray:
    exponents, coefficients, plan = stacked
    if not exponents.size:
        return np.zeros((x.shape[0], coefficients.shape[0]))
    return monomial_values(x, plan) @ coefficients.T


class ModelSystem:
    """The model as the integrator's batched system, with a disturbance per row: ``disturbance(t, x,
    rows)`` returns ``(batch, m)`` values (None: no disturbance). With ``escape`` (per state), a row
    farther than that from ``center`` stops moving there (a diverging start, counted as such); with
    ``settle`` (per state), a row closer than that to ``center`` in every state stops moving there (a
    converged start: its step then grows at once and it ends, instead of being integrated to the horizon
    at the error test's tightest steps; only for simulations that propose, never for a cross-check)."""

    def __init__(self, field: FieldEvaluator, rows: int,
                 disturbance: Callable[[np.ndarray, np.ndarray, np.ndarray], np.ndarray] | None = None,
                 index: np.ndarray | None = None, escape: np.ndarray | None = None,
                 center: np.ndarray | None = None, settle: np.ndarray | None = None) -> None:
        self.field = field
        self.rows = rows
        self.disturbance = disturbance
        self.index = np.arange(rows) if index is None else index
        self.escape = escape
        self.center = center
        self.settle = settle

    @property
    def size(self) -> int:
        return int(self.index.size)

    def rhs(self, t: np.ndarray, y: np.ndarray, t_segment: np.ndarray) -> Evaluation:
        d = None if self.disturbance is None else self.disturbance(t_segment, y, self.index)
        dy = self.field(y, d)
        if self.escape is not None:
            far = np.any(np.abs(y - self.center) > self.escape, axis=1)
            dy[far] = 0.0
        if self.settle is not None:
            dy[np.all(np.abs(y - self.center) < self.settle, axis=1)] = 0.0
        return Evaluation(dy, np.sqrt(np.sum(y * y, axis=1)), np.empty((y.shape[0], 0)))

    def take(self, index: np.ndarray) -> "ModelSystem":
        return ModelSystem(self.field, self.rows, self.disturbance, self.index[index], self.escape, self.center,
                           self.settle)

    def next_breakpoint(self, t: np.ndarray) -> np.ndarray:
        return np.full(t.shape, np.inf)


@dataclass(frozen=True)
class Convergence:
    """Per start: converged to the equilibrium (within ``radius``), and the integrator's status."""

    converged: np.ndarray
    final: np.ndarray
    status: np.ndarray


def converges(model: Model, starts: np.ndarray, *, t_end: float, radius: np.ndarray, escape: np.ndarray,
              parameters: Mapping[str, Fraction] | None = None, max_iterations: int = 20_000) -> Convergence:
    """Simulate every start (declared coordinates) with the disturbances 0 until ``t_end``; a start
    converges when its final state is within ``radius`` (per state) of the equilibrium. Rows that
    leave the box ``|x - x_eq| <= escape`` are stopped there as diverging."""
    field = FieldEvaluator.of(model, parameters)
    eq = np.array([float(v) for v in model.equilibrium])
    starts = np.atleast_2d(np.asarray(starts, dtype=np.float64))
    system = ModelSystem(field, starts.shape[0], escape=np.asarray(escape, dtype=np.float64), center=eq)
    result = integrate(system, 0.0, starts, t_end, rtol=1e-6, atol=np.maximum(radius * 1e-3, 1e-12),
                       max_iterations=max_iterations)
    final = result.y
    converged = np.all(np.abs(final - eq) <= radius, axis=1) & result.ok
    return Convergence(converged=converged, final=final, status=result.status)


class RunningMaxima:
    """An integrator step observer (:class:`lyapcheck.integrator.StepObserver`): per
    trajectory, the largest value of each column of ``function(y)`` (``(rows, columns)``) over its
    start and every accepted step's end (the integrator's own points, as the trajectory checks of
    :mod:`lyapcheck.models.engines.crosscheck` read them). NaN counts as +inf."""

    def __init__(self, function: Callable[[np.ndarray], np.ndarray], rows: int, columns: int) -> None:
        self.function = function
        self.maxima = np.full((rows, columns), -np.inf)

    def _see(self, index: np.ndarray, y: np.ndarray) -> None:
        with np.errstate(all="ignore"):
            values = np.asarray(self.function(y), dtype=np.float64).reshape(len(index), -1)
        values = np.where(np.isnan(values), np.inf, values)
        self.maxima[index] = np.maximum(self.maxima[index], values)

    def start(self, index: np.ndarray, t: np.ndarray, y: np.ndarray, f: np.ndarray) -> None:
        self._see(index, y)

    def step(self, index: np.ndarray, t0: np.ndarray, t1: np.ndarray, y0: np.ndarray, y1: np.ndarray,
             f0: np.ndarray, f1: np.ndarray) -> None:
        self._see(index, y1)


@dataclass(frozen=True)
class CertifiedDecrease:
    """What a region certificate proves of ``V'`` on its set: ``V' <= -epsilon q / D`` with ``q`` a
    squared distance to the equilibrium and ``D > 0`` (the recast classes' decrease, with ``q`` their
    :func:`~lyapcheck.models.classes.recast_classes.state_square`). Both are float functions of the states
    (rows, not deviations). With ``V >= 0``, a trajectory that stays in the set and outside
    ``{q < r^2}`` for a time ``T`` has ``0 <= V(T) <= V(0) - T epsilon r^2 / max D``: by
    ``T = V(0) max D / (epsilon r^2)`` it must have entered the ball."""

    epsilon: float
    q: Callable[[np.ndarray], np.ndarray]
    D: Callable[[np.ndarray], np.ndarray]


@dataclass(frozen=True)
class SetCrossCheck:
    """Starts in a certified set ``{V <= level}`` that had not converged in the first simulation,
    simulated again with V watched along each trajectory (:func:`check_certified_set`). Per start:

    ``left``
        V rose above the level (beyond :data:`~lyapcheck.tolerances.TRAJECTORY_CHECK_REL_TOL`, relative): the set is
        invariant under its certificate, so this contradicts the proof (or the simulation).
    ``overdue``
        integrated past the time by which the certificate's own decrease forces entry into the
        small ball (:class:`CertifiedDecrease`), and never entered it: a contradiction too.
    ``converged``
        ended at the equilibrium.

    The others are still converging slowly, or their integration stopped early: not checked
    (a finite simulation cannot refute convergence without a certified rate)."""

    left: np.ndarray
    overdue: np.ndarray
    converged: np.ndarray

    @property
    def violated(self) -> np.ndarray:
        return self.left | self.overdue

    @property
    def not_checked(self) -> np.ndarray:
        return ~(self.violated | self.converged)

    def numbers(self) -> dict[str, Any]:
        """The figures a region result carries: the starts checked again (those of the set not
        converged in the first simulation), those that left the set, those past the certified time,
        those not checked, and ``soundness_violation`` only when the check is conclusive."""
        out: dict[str, Any] = {"starts_in_set_not_converged": int(self.converged.size),
                               "starts_left_set": int(np.sum(self.left)),
                               "starts_not_checked_slow_convergence": int(np.sum(self.not_checked))}
        if self.overdue.any():
            out["starts_past_certified_convergence_time"] = int(np.sum(self.overdue))
        if self.violated.any():
            out["soundness_violation"] = True
        return out


def check_certified_set(system: ModelSystem, starts: np.ndarray, t_end: float, *,
                        value: Callable[[np.ndarray], np.ndarray], level: float,
                        converged: Callable[[np.ndarray], np.ndarray], rtol: float,
                        atol: np.ndarray | float, max_iterations: int = SIM_MAX_STEPS,
                        decrease: CertifiedDecrease | None = None) -> SetCrossCheck:
    """Simulate ``starts`` (states, rows; each in ``{value <= level}``) on ``system`` until ``t_end``,
    with ``value`` (the certificate's V, of the states; +inf outside a set cut by a box) watched
    along every trajectory; ``converged(final_states)`` says which ended at the equilibrium. A
    start is a violation only when the check is conclusive (:class:`SetCrossCheck`)."""
    from lyapcheck.tolerances import CONVERGED_BALL_RADIUS, TRAJECTORY_CHECK_REL_TOL

    starts = np.atleast_2d(np.asarray(starts, dtype=np.float64))
    with np.errstate(all="ignore"):
        v0 = np.asarray(value(starts), dtype=np.float64)

    def watched(y: np.ndarray) -> np.ndarray:
        columns = [value(y)]
        if decrease is not None:
            columns += [-decrease.q(y), decrease.D(y)]
        return np.column_stack(columns)

    watch = RunningMaxima(watched, len(starts), 1 if decrease is None else 3)
    with np.errstate(all="ignore"):
        result = integrate(system, 0.0, starts, t_end, rtol=rtol, atol=atol, max_iterations=max_iterations,
                           observer=watch)
    top = watch.maxima[:, 0]
    left = ~(top <= level + TRAJECTORY_CHECK_REL_TOL * max(abs(level), 1e-300))
    done = result.ok & np.isfinite(result.y).all(axis=1)
    ended = done & np.asarray(converged(result.y), dtype=bool)
    overdue = np.zeros(len(starts), dtype=bool)
    if decrease is not None and decrease.epsilon > 0:
        r2 = CONVERGED_BALL_RADIUS ** 2
        q_min, d_max = -watch.maxima[:, 1], watch.maxima[:, 2]
        # never within twice the ball's radius at the integrator's points (a dip between two of
        # them stays outside the ball itself), for longer than the certified decrease allows
        outside = q_min >= 4 * r2
        forced = t_end * decrease.epsilon * r2 / np.where(d_max > 0, d_max, np.inf) >= v0
        overdue = done & ~left & ~ended & outside & forced
    return SetCrossCheck(left=left, overdue=overdue, converged=ended & ~left)


def grid_starts(domain: Mapping[str, tuple[Fraction, Fraction]], states: Sequence[str], per_axis: int,
                limit: int, seed: int = 0) -> np.ndarray:
    """A grid over the domain box (``per_axis`` points per state) or, past ``limit`` points, that many
    points drawn uniformly (seeded)."""
    lows = np.array([float(domain[s][0]) for s in states])
    highs = np.array([float(domain[s][1]) for s in states])
    n = len(states)
    if per_axis ** n <= limit:
        axes = [np.linspace(lo, hi, per_axis) for lo, hi in zip(lows, highs)]
        mesh = np.meshgrid(*axes, indexing="ij")
        return np.column_stack([m.ravel() for m in mesh])
    rng = np.random.default_rng(seed)
    return lows + (highs - lows) * rng.random((limit, n))


def typical_time(model: Model, parameters: Mapping[str, Fraction] | None = None) -> float:
    """A time scale of the loop near its equilibrium: 1 / the largest |eigenvalue| estimate of the
    Jacobian (finite differences of the field), at least 1e-9 s."""
    field = FieldEvaluator.of(model, parameters)
    eq = np.array([float(v) for v in model.equilibrium])
    n = eq.size
    h = np.maximum(np.abs(eq) * 1e-6, 1e-9)
    J = np.zeros((n, n))
    for j in range(n):
        e = np.zeros(n)
        e[j] = h[j]
        J[:, j] = (field(eq + e)[0] - field(eq - e)[0]) / (2 * h[j])
    spectral = float(np.max(np.abs(np.linalg.eigvals(J)))) if n else 1.0
    return 1.0 / max(spectral, 1e-9) if spectral > 0 else 1.0


def as_float_point(values: Mapping[str, Any], states: Sequence[str]) -> np.ndarray:
    return np.array([float(values[s]) for s in states])
