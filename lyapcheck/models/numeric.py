"""A model's field in floating point, for simulation: vectorized over many states at once.

:class:`NumericPoly` evaluates an exact polynomial at a batch of points (one numpy expression per
monomial power); :class:`FieldEvaluator` gives ``x' = f(x, d)`` of a model (rational: numerator
over denominator, as declared, in the declared coordinates and SI units) for batches of states
and disturbances; :class:`ModelSystem` is the batched system the project's integrator
(:mod:`lyapcheck.simulation.integrator`) takes; :func:`converges` classifies starts by where
their trajectories end (the simulated region of attraction of the ``roa`` class).
Nothing here decides a status: simulations are evidence, and cross-checks of what was proved.
"""

from __future__ import annotations

from dataclasses import dataclass
from fractions import Fraction
from typing import Any, Callable, Mapping, Sequence

import numpy as np

from lyapcheck.models.modelfile import Model, field_at
from lyapcheck.simulation.integrator import Evaluation, integrate
from lyapcheck.sos.polynomials import MonomialPlan, Poly, Ring, monomial_plan, monomial_values


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
    farther than that from ``center`` stops moving there (a diverging start, counted as such)."""

    def __init__(self, field: FieldEvaluator, rows: int,
                 disturbance: Callable[[np.ndarray, np.ndarray, np.ndarray], np.ndarray] | None = None,
                 index: np.ndarray | None = None, escape: np.ndarray | None = None,
                 center: np.ndarray | None = None) -> None:
        self.field = field
        self.rows = rows
        self.disturbance = disturbance
        self.index = np.arange(rows) if index is None else index
        self.escape = escape
        self.center = center

    @property
    def size(self) -> int:
        return int(self.index.size)

    def rhs(self, t: np.ndarray, y: np.ndarray, t_segment: np.ndarray) -> Evaluation:
        d = None if self.disturbance is None else self.disturbance(t_segment, y, self.index)
        dy = self.field(y, d)
        if self.escape is not None:
            far = np.any(np.abs(y - self.center) > self.escape, axis=1)
            dy[far] = 0.0
        return Evaluation(dy, np.sqrt(np.sum(y * y, axis=1)), np.empty((y.shape[0], 0)))

    def take(self, index: np.ndarray) -> "ModelSystem":
        return ModelSystem(self.field, self.rows, self.disturbance, self.index[index], self.escape, self.center)

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
