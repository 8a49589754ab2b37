"""The true (non-polynomial) loop in floating point: its auxiliaries, field, a V on it, trajectories.

Used for figures and cross-checks only (which share of a box a certified set covers, whether a
simulated trajectory from a certified set converges), never for a verdict: those are exact
(:mod:`lyapcheck.models.recast_classes`). The field integrated is the model's own, with each
function evaluated by numpy, not the recast polynomial one.
"""

from __future__ import annotations

from typing import Callable, Final

import numpy as np

from lyapcheck.models.recast import RecastSystem
from lyapcheck.sos.polynomials import Poly, Ring

#: numpy's version of each function of the language
_NUMPY: Final[dict[str, Callable[[np.ndarray], np.ndarray]]] = {"sin": np.sin, "cos": np.cos, "exp": np.exp, "sqrt": lambda u: np.sqrt(np.maximum(u, 0.0)),
                 "atan": np.arctan, "tanh": np.tanh, "abs": np.abs}


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


def variable_values(system: RecastSystem, X: np.ndarray) -> dict[str, np.ndarray]:
    """Every variable of the recast ring at the states ``X`` (rows; not deviations): the states,
    then each auxiliary from its definition (roots as their constants)."""
    X = np.atleast_2d(np.asarray(X, dtype=np.float64))
    rows = X.shape[0]
    cols: dict[str, np.ndarray] = {s: X[:, i] for i, s in enumerate(system.states)}
    ring = system.ring
    for a in system.auxiliaries:
        if a.argument is None:  # rt2, rt3
            cols[a.name] = np.full(rows, float(np.sqrt(float(a.radicand or 0))))
            continue
        u = poly_values(ring, a.argument, cols, rows)
        if a.function == "sat":
            assert a.limit is not None
            L = float(a.limit)
            cols[a.name] = np.clip(u, -L, L)
        else:
            cols[a.name] = _NUMPY[a.function](u)
    return cols


def field_values(system: RecastSystem, X: np.ndarray) -> np.ndarray:
    """The true field ``x'`` at the states ``X`` (rows)."""
    X = np.atleast_2d(np.asarray(X, dtype=np.float64))
    cols = variable_values(system, X)
    rows = X.shape[0]
    ring = system.ring
    out = np.empty_like(X)
    for i, r in enumerate(system.field):
        out[:, i] = poly_values(ring, r.numerator, cols, rows) / poly_values(ring, r.denominator, cols, rows)
    return out


def v_values(system: RecastSystem, V: Poly, Z: np.ndarray) -> np.ndarray:
    """A V in deviations at the state deviations ``Z`` (rows): ``V(z, a(x) - a(x_eq))``."""
    Z = np.atleast_2d(np.asarray(Z, dtype=np.float64))
    eq = np.array([float(system.values[s]) for s in system.states])
    cols = variable_values(system, Z + eq)
    shifted = {n: v - float(system.values[n]) if n in system.values else v for n, v in cols.items()}
    return poly_values(system.ring, V, shifted, Z.shape[0])


#: the box of deviations in which certified sets are compared when the model gives no [domain]
DEFAULT_HALF_WIDTH: Final = 4.0


def integrate(system: RecastSystem, X0: np.ndarray, horizon: float, step: float = 0.02) -> np.ndarray:
    """Classical Runge-Kutta on the true field, every start at once; the final states."""
    X = np.atleast_2d(np.asarray(X0, dtype=np.float64)).copy()
    steps = int(np.ceil(horizon / step))
    for _ in range(steps):
        k1 = field_values(system, X)
        k2 = field_values(system, X + step / 2 * k1)
        k3 = field_values(system, X + step / 2 * k2)
        k4 = field_values(system, X + step * k3)
        X = X + step / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
        X[~np.isfinite(X)] = np.inf
    return X


def converges_modulo(system: RecastSystem, X0: np.ndarray, angles: tuple[str, ...] = (), horizon: float = 60.0,
                     tolerance: float = 2e-2, step: float = 0.02) -> np.ndarray:
    """Whether each start's simulated trajectory of the true field ends within ``tolerance`` of the
    equilibrium, each angle taken modulo 2 pi."""
    eq = np.array([float(system.values[s]) for s in system.states])
    with np.errstate(all="ignore"):
        end = integrate(system, X0, horizon, step) - eq
    for i, s in enumerate(system.states):
        if s in angles:
            end[:, i] = np.angle(np.exp(1j * end[:, i]))
    return np.all(np.isfinite(end), axis=1) & (np.linalg.norm(end, axis=1) < tolerance)
