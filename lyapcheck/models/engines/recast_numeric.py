"""The true (non-polynomial) loop in floating point: its auxiliaries, field, a V on it, trajectories.

Used for figures and cross-checks only (which share of a box a certified set covers, whether a
simulated trajectory from a certified set converges), never for a verdict: those are exact
(:mod:`lyapcheck.models.classes.recast_classes`). The field integrated is the model's own, with each
function evaluated by numpy, not the recast polynomial one.
"""

from __future__ import annotations

from typing import Any, Callable, Final

import numpy as np

from lyapcheck.models.language.recast import RecastModel, RecastSystem
from lyapcheck.sos.polynomials import Poly, Ring
from lyapcheck.tolerances import SIM_MAX_STEPS

#: numpy's version of each function of the language
_NUMPY: Final[dict[str, Callable[[np.ndarray], np.ndarray]]] = {"sin": np.sin, "cos": np.cos, "exp": np.exp, "sqrt": lambda u: np.sqrt(np.maximum(u, 0.0)),
                 "atan": np.arctan, "tanh": np.tanh, "abs": np.abs}


def rk4_step(f: Callable[[np.ndarray], np.ndarray], X: np.ndarray, dt: float) -> np.ndarray:
    """One classical Runge-Kutta step of ``x' = f(x)`` for a batch of states (rows of ``X``): a fixed step
    for figures and for picking boxes, never for a verdict (the adaptive integrator of
    :mod:`lyapcheck.integrator` is the one that controls its error)."""
    k1 = f(X)
    k2 = f(X + dt / 2 * k1)
    k3 = f(X + dt / 2 * k2)
    return X + dt / 6 * (k1 + 2 * k2 + 2 * k3 + f(X + dt * k3))


def poly_values(ring: Ring, p: Poly, columns: dict[str, np.ndarray], rows: int) -> np.ndarray:
    """``p`` at many points: ``columns[name]`` the values of each variable it uses."""
    out = np.zeros(rows)
    for m, c in ring.float_terms(p).items():
        term = np.full(rows, c)
        for name, k in zip(ring.names, m):
            if k:
                term = term * columns[name] ** k
        out += term
    return out


class FloatLoop:
    """The true loop of a recast system in floating point, its polynomials' coefficients converted
    once (an integrator calls the field thousands of times)."""

    def __init__(self, system: RecastSystem) -> None:
        self.system = system
        ring = system.ring
        self.names = ring.names

        def compiled(p: Poly) -> list[tuple[float, list[tuple[int, int]]]]:
            return [(c, [(i, k) for i, k in enumerate(m) if k]) for m, c in ring.float_terms(p).items()]

        self.auxiliaries = [(a.function, a.limit, a.radicand, None if a.argument is None else compiled(a.argument))
                            for a in system.auxiliaries]
        self.field = [(compiled(r.numerator), compiled(r.denominator)) for r in system.field]

    @staticmethod
    def _value(terms: list[tuple[float, list[tuple[int, int]]]], cols: list[np.ndarray], rows: int) -> np.ndarray:
        out = np.zeros(rows)
        for c, factors in terms:
            term = np.full(rows, c)
            for i, k in factors:
                term = term * cols[i] ** k
            out += term
        return out

    def columns(self, X: np.ndarray) -> list[np.ndarray]:
        """Every variable of the recast ring at the states ``X`` (rows; not deviations), in its order."""
        rows = X.shape[0]
        cols = [X[:, i] for i in range(self.system.n)]
        for function, limit, radicand, argument in self.auxiliaries:
            if argument is None:  # rt2, rt3
                cols.append(np.full(rows, float(np.sqrt(float(radicand or 0)))))
                continue
            u = self._value(argument, cols, rows)
            if function == "sat":
                assert limit is not None
                cols.append(np.clip(u, -float(limit), float(limit)))
            else:
                # exp of a far sample overflows to inf: every caller treats a non-finite value as
                # an escape (the integrator, the fitted V's samples), so numpy need not warn
                with np.errstate(over="ignore", invalid="ignore"):
                    cols.append(_NUMPY[function](u))
        return cols

    def __call__(self, X: np.ndarray) -> np.ndarray:
        """The true field ``x'`` at the states ``X`` (rows)."""
        X = np.atleast_2d(np.asarray(X, dtype=np.float64))
        cols = self.columns(X)
        rows = X.shape[0]
        out = np.empty_like(X)
        # a rational field at a pole (a denominator 0 at a sample) is inf or nan there: every caller
        # treats a non-finite value as an escape, as for an overflow above, so numpy need not warn
        with np.errstate(divide="ignore", invalid="ignore"):
            for i, (num, den) in enumerate(self.field):
                out[:, i] = self._value(num, cols, rows) / self._value(den, cols, rows)
        return out


def variable_values(system: RecastSystem, X: np.ndarray) -> dict[str, np.ndarray]:
    """Every variable of the recast ring at the states ``X`` (rows; not deviations): the states,
    then each auxiliary from its definition (roots as their constants)."""
    X = np.atleast_2d(np.asarray(X, dtype=np.float64))
    return dict(zip(system.ring.names, FloatLoop(system).columns(X)))


def field_values(system: RecastSystem, X: np.ndarray) -> np.ndarray:
    """The true field ``x'`` at the states ``X`` (rows)."""
    return FloatLoop(system)(X)


def v_values(system: RecastSystem, V: Poly, Z: np.ndarray) -> np.ndarray:
    """A V in deviations at the state deviations ``Z`` (rows): ``V(z, a(x) - a(x_eq))``."""
    Z = np.atleast_2d(np.asarray(Z, dtype=np.float64))
    eq = np.array([float(system.values[s]) for s in system.states])
    cols = variable_values(system, Z + eq)
    shifted = {n: v - float(system.values[n]) if n in system.values else v for n, v in cols.items()}
    return poly_values(system.ring, V, shifted, Z.shape[0])


#: the box of deviations in which certified sets are compared when the model gives no [domain]
DEFAULT_HALF_WIDTH: Final = 4.0


#: the integrator's relative tolerance for these figures and cross-checks (far below their 2e-2
#: convergence radius)
RTOL: Final = 1e-7
#: the absolute tolerance, per state
ATOL: Final = 1e-9


def simulate_ends(system: RecastSystem, X0: np.ndarray, horizon: float, escape: float | None = None,
                  max_steps: int | None = None, settle: float | np.ndarray | None = None, rtol: float = RTOL,
                  atol: float = ATOL) -> tuple[np.ndarray, Any]:
    """Integrate the true field from every start at once with the project's batched DOPRI5
    (:func:`lyapcheck.integrator.integrate`, through the model files' batched system
    :class:`lyapcheck.models.engines.numeric.ModelSystem`); a row farther than ``escape`` from the
    equilibrium in a state stops moving there, and one closer than ``settle`` in every state too (a
    converged start: for simulations that only propose; per state, or one for all); ``rtol``, ``atol``: the
    error test's (:data:`RTOL`, :data:`ATOL` by default); ``max_steps``: each row's step budget (default
    :data:`~lyapcheck.tolerances.SIM_MAX_STEPS`). The final deviations from the equilibrium, and the
    integrator's result (per row: ``t``, ``status``, ``failure``)."""
    from lyapcheck.models.engines.numeric import ModelSystem
    from lyapcheck.integrator import integrate

    X0 = np.atleast_2d(np.asarray(X0, dtype=np.float64))
    eq = np.array([float(system.values[s]) for s in system.states])
    batch = ModelSystem(TrueField(system), len(X0),  # type: ignore[arg-type]
                        escape=None if escape is None else np.full(system.n, escape), center=eq,
                        settle=None if settle is None else
                        np.broadcast_to(np.asarray(settle, dtype=np.float64), (system.n,)))
    with np.errstate(all="ignore"):
        result = integrate(batch, 0.0, X0, horizon, rtol=rtol, atol=atol,
                           max_iterations=SIM_MAX_STEPS if max_steps is None else max_steps)
    return result.y - eq, result


class TrueField:
    """The true field of a loop with functions, ``(x, d) -> x'`` row by row, each function evaluated by
    numpy (:class:`FloatLoop`), never the recast polynomial loop: the batched system's field of every
    simulation of such a loop (and :class:`lyapcheck.models.surfaces.simulate.LoopField`). From a
    :class:`~lyapcheck.models.language.recast.RecastModel` the disturbances ``d`` (rows, None: all 0)
    enter through the loop recast with them as variables; from a bare
    :class:`~lyapcheck.models.language.recast.RecastSystem` there are none."""

    def __init__(self, loop: RecastModel | RecastSystem) -> None:
        if isinstance(loop, RecastSystem):
            self.n, self.nominal, self.disturbed = loop.n, FloatLoop(loop), None
            return
        self.n = loop.n
        self.nominal = FloatLoop(loop.system)
        # the loop with the disturbances as variables (the last "states", without a flow)
        self.disturbed = FloatLoop(loop.robust) if loop.disturbances and loop.robust is not None else None

    def __call__(self, x: np.ndarray, d: np.ndarray | None = None) -> np.ndarray:
        x = np.atleast_2d(np.asarray(x, dtype=np.float64))
        with np.errstate(all="ignore"):  # a far start overflows: the integrator treats it as an escape
            if d is None or self.disturbed is None or not d.size:
                return self.nominal(x)
            return self.disturbed(np.concatenate([x, np.asarray(d, dtype=np.float64)], axis=1))[:, :self.n]


def distances(system: RecastSystem, deviations: np.ndarray, angles: tuple[str, ...] = ()) -> np.ndarray:
    """Each row's distance to the equilibrium, every angle in ``angles`` taken modulo 2 pi (inf for a
    row that is not finite)."""
    dev = np.array(deviations, dtype=np.float64, copy=True)
    for i, s in enumerate(system.states):
        if s in angles:
            dev[:, i] = np.angle(np.exp(1j * dev[:, i]))
    out = np.linalg.norm(dev, axis=1)
    out[~np.all(np.isfinite(dev), axis=1)] = np.inf
    return out


def converges_modulo(system: RecastSystem, X0: np.ndarray, angles: tuple[str, ...] = (), horizon: float = 60.0,
                     tolerance: float = 2e-2) -> np.ndarray:
    """Whether each start's simulated trajectory of the true field ends within ``tolerance`` of the
    equilibrium, each angle taken modulo 2 pi."""
    dev, result = simulate_ends(system, X0, horizon)
    return result.ok & (distances(system, dev, angles) < tolerance)
