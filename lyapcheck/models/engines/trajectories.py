"""Recorded trajectories of a model file's closed loop: the report's phase portrait and the
simulation cross-checks of certificates (:mod:`lyapcheck.models.engines.crosscheck`, sweeps of model files).

The field is the model's own (:func:`lyapcheck.models.language.modelfile.parse_model`: the whitelist parser,
nothing evaluated), in floating point (:class:`lyapcheck.models.engines.numeric.FieldEvaluator`) and
integrated by the project's batched Dormand-Prince integrator (:mod:`lyapcheck.integrator`),
every start in one call. A start that runs away (finite escape, as outside the reversed Van der Pol
cycle) is frozen once it is :data:`ESCAPE_FACTOR` view widths from the equilibrium, so one diverging
row neither overflows nor slows the others. Every trajectory keeps the integrator's own points
(:attr:`Trajectory.nodes`, what checks read) and, for drawing, :data:`DENSE` interpolated points
per step.

Simulations here are pictures and cross-checks, never evidence for a status. (Moved here from the
reports, so that the core's cross-checks and the report share one simulation.)
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Callable, Final

import numpy as np
import numpy.typing as npt

from lyapcheck.models.language.modelfile import Model
from lyapcheck.models.language.recast import RecastModel
from lyapcheck.models.engines.numeric import FieldEvaluator, ModelSystem
from lyapcheck.integrator import integrate

FloatArray = npt.NDArray[np.float64]
IntArray = npt.NDArray[np.intp]

#: a trajectory farther than this many view half-widths from the equilibrium is stopped (escaped)
ESCAPE_FACTOR: Final = 3.0
#: it has converged when it ends within this fraction of the view's half-width of the equilibrium
CONVERGED_FRACTION: Final = 1e-2
#: the integrator's steps are capped at horizon / this (a step never jumps over a whole turn of a
#: spiral), and each step is drawn through this many interpolated points besides its ends
MIN_STEPS: Final = 150
DENSE: Final = 3
#: horizon: this many time constants of the slowest eigenvalue of an exponentially stable
#: equilibrium (e^-12: any converging start is at the equilibrium to plotting accuracy) ...
SLOW_TIME_CONSTANTS: Final = 12.0
#: ... but at most this many of the fastest (a very slow mode must not cost a long stiff run);
#: without exponential stability (critical or unstable Jacobian), this many of the fastest
FAST_TIME_CONSTANTS_MAX: Final = 400.0
FAST_TIME_CONSTANTS_CRITICAL: Final = 25.0
#: relative tolerance of the integrator (a picture and a cross-check: 1e-7 is far below a pixel
#: and below the cross-checks' tolerance)
RTOL: Final = 1e-7


@dataclass(frozen=True)
class Trajectory:
    """One simulated trajectory: times ``(k,)``, states ``(k, n)`` in declared coordinates, and
    how it ended: ``converged``, ``escaped`` or ``other`` (neither, e.g. on a limit cycle)."""

    t: FloatArray
    x: FloatArray
    outcome: str
    #: which samples are the integrator's own points (the others are interpolated for drawing):
    #: cross-checks read these only
    node: npt.NDArray[np.bool_]

    @property
    def nodes(self) -> tuple[FloatArray, FloatArray]:
        """Times and states of the integrator's own points."""
        return self.t[self.node], self.x[self.node]


@dataclass
class _Recorder:
    """The integrator's step observer: every accepted step's end point per row, and between them
    :data:`DENSE` points of the step's cubic Hermite interpolant (from the derivatives at both
    ends, which the integrator hands over), so the drawn curves are smooth without small steps."""

    rows: int
    index: list[IntArray] = field(default_factory=list)
    t: list[FloatArray] = field(default_factory=list)
    y: list[FloatArray] = field(default_factory=list)
    node: list[npt.NDArray[np.bool_]] = field(default_factory=list)

    def start(self, index: IntArray, t: FloatArray, y: FloatArray, f: FloatArray) -> None:
        self._keep(index, t, y, True)

    def _keep(self, index: IntArray, t: FloatArray, y: FloatArray, node: bool) -> None:
        self.index.append(np.array(index, copy=True))
        self.t.append(np.array(t, copy=True))
        self.y.append(np.array(y, copy=True))
        self.node.append(np.full(len(index), node))

    def step(self, index: IntArray, t0: FloatArray, t1: FloatArray, y0: FloatArray, y1: FloatArray,
             f0: FloatArray, f1: FloatArray) -> None:
        h = (t1 - t0)[:, None]
        for s in np.arange(1, DENSE + 1) / (DENSE + 1):
            # cubic Hermite basis on [0, 1]
            h00, h10 = 2 * s**3 - 3 * s**2 + 1, s**3 - 2 * s**2 + s
            h01, h11 = -2 * s**3 + 3 * s**2, s**3 - s**2
            self._keep(index, t0 + s * (t1 - t0), h00 * y0 + h10 * h * f0 + h01 * y1 + h11 * h * f1, False)
        self._keep(index, t1, y1, True)

    def trajectories(self) -> list[tuple[FloatArray, FloatArray, npt.NDArray[np.bool_]]]:
        index = np.concatenate(self.index)
        t = np.concatenate(self.t)
        y = np.concatenate(self.y)
        node = np.concatenate(self.node)
        order = np.lexsort((t, index))
        index, t, y, node = index[order], t[order], y[order], node[order]
        cuts = np.searchsorted(index, np.arange(self.rows + 1))
        return [(t[a:b], y[a:b], node[a:b]) for a, b in zip(cuts[:-1], cuts[1:])]


def jacobian_eigenvalues(evaluate: FieldEvaluator, equilibrium: FloatArray, scales: FloatArray) -> npt.NDArray[Any]:
    """Eigenvalues of the Jacobian at the equilibrium (central differences, steps of the scale)."""
    n = equilibrium.size
    h = np.maximum(np.abs(scales), 1e-300) * 1e-6
    J = np.zeros((n, n))
    for j in range(n):
        e = np.zeros(n)
        e[j] = h[j]
        J[:, j] = (evaluate(equilibrium + e)[0] - evaluate(equilibrium - e)[0]) / (2 * h[j])
    if not np.all(np.isfinite(J)):
        return np.array([], dtype=complex)
    return np.linalg.eigvals(J)


def horizon(eigenvalues: npt.NDArray[Any], fast_cap: float = FAST_TIME_CONSTANTS_MAX) -> float:
    """How long to simulate: :data:`SLOW_TIME_CONSTANTS` of the slowest mode of an exponentially
    stable equilibrium, capped at ``fast_cap`` (default :data:`FAST_TIME_CONSTANTS_MAX`) of the
    fastest; otherwise :data:`FAST_TIME_CONSTANTS_CRITICAL` of the fastest (1 s when the Jacobian
    is 0, or has no finite eigenvalues). :func:`lyapcheck.models.classes.falsify.default_horizon`
    is the same rule with its own cap."""
    magnitudes = np.abs(eigenvalues) if eigenvalues.size else np.array([0.0])
    fastest = float(magnitudes.max())
    fast_time = 1.0 / fastest if fastest > 0 else 1.0
    real = eigenvalues.real if eigenvalues.size else np.array([0.0])
    if np.all(real < 0):
        return float(min(SLOW_TIME_CONSTANTS / float(np.min(-real)), fast_cap * fast_time))
    return FAST_TIME_CONSTANTS_CRITICAL * fast_time


def _per_row(values: FloatArray) -> Callable[[FloatArray, FloatArray, IntArray], FloatArray]:
    """A disturbance that keeps row ``i`` at ``values[i]`` (one entry per disturbance) at every time."""
    table = np.asarray(values, dtype=np.float64)

    def push(t: FloatArray, y: FloatArray, index: IntArray) -> FloatArray:
        return table[index]

    return push


def simulate(model: Model | RecastModel, starts: FloatArray, *, t_end: float, half_widths: FloatArray,
             disturbances: FloatArray | None = None, escape_factor: float | FloatArray = ESCAPE_FACTOR,
             converged_fraction: float = CONVERGED_FRACTION) -> list[Trajectory]:
    """Simulate every start (rows of ``starts``, declared coordinates) until ``t_end``, in one batch.

    Parameters
    ----------
    model
        The parsed model (parameters at the certificate's values); a loop with functions is simulated
        on its true field (:class:`lyapcheck.models.engines.recast_numeric.TrueField`).
    starts
        ``(k, n)`` initial states.
    t_end
        The horizon, s.
    half_widths
        The view's half-width per state: sets the escape box (:data:`ESCAPE_FACTOR`), the
        convergence radius (:data:`CONVERGED_FRACTION`) and the integrator's absolute tolerance.
    disturbances
        ``(k, m)``: a constant value of every disturbance per start; None for all 0.
    escape_factor, converged_fraction
        The escape box and the convergence radius in half-widths (defaults :data:`ESCAPE_FACTOR`,
        :data:`CONVERGED_FRACTION`: the phase portrait's view); ``escape_factor`` may be one per state
        (inf: that state never escapes, such as an angle of a loop with functions).
    """
    from lyapcheck.models.engines.recast_numeric import TrueField

    # (either is the batched system's field, (x, d) -> x')
    evaluate: Any = TrueField(model) if isinstance(model, RecastModel) else FieldEvaluator.of(model)
    eq = np.array([float(v) for v in model.equilibrium])
    starts = np.atleast_2d(np.asarray(starts, dtype=np.float64))
    rows = starts.shape[0]
    escape = escape_factor * np.asarray(half_widths, dtype=np.float64)
    push = None if disturbances is None or not len(model.disturbances) else _per_row(disturbances)
    system = ModelSystem(evaluate, rows, disturbance=push, escape=escape, center=eq)
    recorder = _Recorder(rows)
    atol = np.maximum(np.asarray(half_widths, dtype=np.float64) * 1e-7, 1e-300)
    integrate(system, 0.0, starts, t_end, rtol=RTOL, atol=atol, max_step=t_end / MIN_STEPS, observer=recorder)
    out = []
    radius = converged_fraction * np.asarray(half_widths, dtype=np.float64)
    for t, y, node in recorder.trajectories():
        end = y[-1] - eq
        if np.any(~np.isfinite(end)) or np.any(np.abs(end) >= escape * (1 - 1e-9)):
            outcome = "escaped"
        elif np.all(np.abs(end) <= radius):
            outcome = "converged"
        else:
            outcome = "other"
        out.append(Trajectory(t, y, outcome, node))
    return out
