"""``simulate --model``: a model file's closed loop from many starts under bounded disturbances.

Every start meets every disturbance of the chosen scenarios, one row of one batched
Dormand-Prince call (:mod:`lyapcheck.integrator`) per (start, disturbance). Every
disturbance respects the model's bounds ``|d_k| <= b_k`` at every instant:

==========  ================================================================================
scenario    disturbances (``m`` disturbances, bounds ``b_k``)
==========  ================================================================================
none        ``d = 0``
constant    ``d_k = s_k b_k`` for every sign pattern ``s`` in ``{-1, 1}^m``
bang-bang   per output ``y`` and direction ``beta = +-1``, a feedback that pushes ``|y|`` up:
            ``w = y(x) + beta delta_y`` (``delta_y`` a thin layer, :data:`FEEDBACK_LAYER` of the
            output's scale; ``beta`` breaks the tie at ``y = 0``, where the law would be silent);
            where ``y'`` depends on ``d_k`` (``G_k = dy'/dd_k`` at ``d = 0`` is not identically 0)
            ``d_k = b_k sat(w / delta_y) sat(G_k(x) / gamma_k)``, i.e. ``b_k sign(y G_k)``, the
            ``d_k`` that maximises ``d|y|/dt``; otherwise ``d_k = b_k sigma_k sat(w / delta_y)``
            with ``sigma_k`` the sign of the first non-zero Markov parameter ``c A^j B_k`` of the
            loop linearised at the equilibrium (the sign with which ``d_k`` first moves ``y``;
            ``+1`` when they all vanish)
square      ``d_k = s_k b_k sign(sin(omega t))``, ``s_1 = +1`` (the other half of the patterns
            is the same wave half a period later), ``omega`` log-spaced over the frequency range
==========  ================================================================================

The saturations (boundary layers) keep the feedback Lipschitz, as the paper's adversarial
disturbance does (:mod:`lyapcheck.paper.simulation.disturbances`); a square wave's switching times
are breakpoints the integrator lands on exactly.

What is measured, per row: the sup of ``|y|`` over the tail window (the last
:data:`TAIL_FRACTION` of the horizon) for every output, sampled at the ends and three interior
points (cubic Hermite) of every step, with the step at most ``tail / STEPS_PER_TAIL`` and landing
on the tail's start; the final state; ``converged`` (the final state within
:data:`CONVERGENCE_RADIUS` of the state scale of the equilibrium); ``diverged`` (the state left
the box of :data:`ESCAPE_FACTOR` times the state scale around the equilibrium, where the row is
stopped, or the integrator failed: overflow, a step too small, the step budget). The state scale
is, per state, the largest of: the starts' distance from the equilibrium, the domain's
half-width, the steady response of the linearisation to the bounds, ``|x_eq|``; 1 if all vanish.

Both loop kinds are simulated by this one module over one object, the simulated loop
(:class:`Prepared`), built once per model by :func:`prepare`, which has one constructor per kind.
What differs between the kinds sits behind it: the float field (:class:`LoopField`, ``x' = f(x, d)``
row by row), each output's gain ``G_k = dy'/dd_k`` (:class:`OutputGain`), the linearisation at the
equilibrium, the angles and the document's extra keys:

- a polynomial (rational) loop (:func:`prepare_polynomial`): the field :class:`_Field`, from its
  exact polynomials; the gains and the linearisation exact (:class:`_OutputFeedback`);
- a loop with functions (sin, sqrt, sat, ...) (:func:`prepare_true_loop`): its true loop
  (:class:`lyapcheck.models.engines.recast_numeric.TrueField`), each function evaluated by numpy,
  never the recast polynomial loop, which only holds on its relations' set; under a disturbance,
  the loop recast with its disturbances as variables
  (:attr:`~lyapcheck.models.language.recast.RecastModel.robust`), and where the recasting could not
  keep a disturbance a variable, the loop is simulated with it held at 0 (scenario ``none`` only)
  and the document says so. The gains (:class:`TrueOutputGain`): ``dy/dx`` exact (the outputs are
  polynomials in the states), ``df/dd_k`` a central difference of the true field. The
  linearisation: the exact Jacobian of the true field at the equilibrium
  (:func:`lyapcheck.models.classes.recast_classes.jacobian`), central differences where it has none
  (a function not differentiable there). The document adds ``kind`` ("recast"), ``field`` (what
  was integrated) and ``angles_modulo_2pi``.

Everything else (scenarios, starts, horizons, tail sups, the series, the plots, the worst-case
search, the ultimate bounds' tightness) is written once; an angle that enters the loop only through
its sine and cosine (:func:`lyapcheck.models.classes.recast_classes.angle_states`) is measured
modulo 2 pi (its deviation from the equilibrium wrapped into ``(-pi, pi]``, and it never leaves the
escape box).

:func:`search_worst_case` searches the disturbance ``|d_k| <= b_k`` that maximises each output's
tail sup: constant, feedback, square waves over the frequency range, then a local pattern search
(constant amplitudes inside the box; square-wave frequency and phase), within a time budget.
:func:`tightness` compares it with a certified bound (class ``sos_bound``). Simulations are
evidence, never proofs: a certified bound below a simulated figure is a soundness violation.
"""

from __future__ import annotations

import dataclasses
import itertools
import logging
import math
import time
from dataclasses import dataclass, field, replace
from fractions import Fraction
from pathlib import Path
from typing import Any, Final, Mapping, Protocol, Sequence

import numpy as np
import numpy.typing as npt

from lyapcheck.errors import InvalidParameter
from lyapcheck.models.engines.recast_numeric import TrueField
from lyapcheck.models.language.modelfile import Model, field_at
from lyapcheck.models.language.recast import RecastModel, RecastSystem
from lyapcheck.integrator import (
    DEFAULT_RTOL, INTEGRATOR_NAME, STATUS_OK, Evaluation, IntegrationResult, hermite, integrate,
)
from lyapcheck.sos.polynomials import Poly, Ring, degree_in
from lyapcheck.tolerances import SIM_MAX_STEPS, SIM_REL_TOL

logger = logging.getLogger(__name__)

FloatArray = npt.NDArray[np.float64]
IntArray = npt.NDArray[np.intp]
BoolArray = npt.NDArray[np.bool_]

#: scenario names, in the order they are simulated and reported
SCENARIOS: Final = ("none", "constant", "bang-bang", "square")
#: the tail window is the last TAIL_FRACTION of the horizon
TAIL_FRACTION: Final = 0.2
#: the largest step is tail / STEPS_PER_TAIL (5 samples per step: the sup's sampling interval)
STEPS_PER_TAIL: Final = 20
#: default horizon in slowest time constants of the linearisation (exp(-32) ~ 1e-14 at the tail)
HORIZON_TIME_CONSTANTS: Final = 40.0
#: a real part below this fraction of the largest |eigenvalue| counts as zero (a centre direction)
CENTRE_FRACTION: Final = 1e-6
#: the state scale's fallback, SI, when nothing else gives one
UNIT_SCALE: Final = 1.0
#: absolute tolerance of the integrator, as a fraction of the state scale (times rtol)
ATOL_PER_RTOL: Final = 1.0
#: a row farther than ESCAPE_FACTOR state scales from the equilibrium is stopped there and diverged
ESCAPE_FACTOR: Final = 1e3
#: converged: the final state within CONVERGENCE_RADIUS state scales of the equilibrium
CONVERGENCE_RADIUS: Final = 1e-3
#: the feedback's boundary layers, as fractions of the output's and of G_k's scales
FEEDBACK_LAYER: Final = 1e-3
#: square waves: this many log-spaced frequencies; the default range spans from one period per
#: tail window to FREQUENCY_HIGH times the largest |eigenvalue| of the linearisation (rad/s)
N_FREQUENCIES: Final = 8
FREQUENCY_HIGH: Final = 4.0
#: a square wave switching more often than this over the horizon is refused (each switch restarts
#: the integrator's step; the step budget per trajectory is SIM_MAX_STEPS)
MAX_SWITCHES: Final = SIM_MAX_STEPS // 4
#: starts: the most a grid (--grid N gives N**n) or --x0 may give, and the most rows in one call
MAX_STARTS: Final = 4096
MAX_ROWS: Final = 100_000
MAX_GRID_PER_STATE: Final = 201
#: default starts with a [domain]: the equilibrium and a grid over it with the most points per state
#: in [DEFAULT_GRID_MIN, DEFAULT_GRID_MAX] that keeps it within DEFAULT_GRID_LIMIT points (5 per state
#: for 1 or 2 states, 4 for 3, 3 for 4), beyond that DEFAULT_GRID_LIMIT seeded uniform points in it;
#: without a domain: the equilibrium and x_eq +- NEAR_START_FRACTION * scale along each state
DEFAULT_GRID_MIN: Final = 3
DEFAULT_GRID_MAX: Final = 5
DEFAULT_GRID_LIMIT: Final = 81
NEAR_START_FRACTION: Final = 0.5
#: the longest horizon accepted, in units of the slowest time constant (a user's --t-end)
MAX_HORIZON_TIME_CONSTANTS: Final = 1e6
#: worst-case search: tolerance of the search rounds (the reported figures use DEFAULT_RTOL)
SEARCH_RTOL: Final = 1e-6
#: worst-case search: square-wave phases of the screening (rad), rounds after it, pattern steps in
#: (log omega, phase) and in constant amplitude (fraction of b_k), shrink factor, smallest steps
SEARCH_PHASES: Final = (0.0, math.pi / 2)
MAX_ROUNDS: Final = 8
PATTERN_STEP_LOG_OMEGA: Final = 0.2
PATTERN_STEP_PHASE: Final = math.pi / 4
PATTERN_STEP_AMPLITUDE: Final = 0.25
PATTERN_SHRINK: Final = 0.5
PATTERN_MIN_STEP: Final = 1e-3
#: the final call at DEFAULT_RTOL is guessed to cost this many screening calls
FINAL_COST_FACTOR: Final = 2.0
#: the budget accepted, seconds
MAX_BUDGET_S: Final = 3600.0
#: time histories drawn by --plot: at most this many rows, resampled at PLOT_SAMPLES points
MAX_PLOTTED_ROWS: Final = 200
PLOT_SAMPLES: Final = 1500
#: a plotted trajectory is cut where it is farther than this many state scales from the equilibrium (a
#: sampled-data loop's plot draws it whole and clips its views at this box instead: sampled_simulate)
PLOT_CLIP: Final = 2.0
#: the worst-case document lists at most this many diverged candidates (disturbance, start, why)
MAX_EXAMPLES: Final = 5
#: the square waves' switching-time table (rows x switches) may hold at most this many entries
MAX_SWITCH_TABLE: Final = 20_000_000
#: sample points inside each step for the sups (fractions of the step)
SAMPLE_THETAS: Final = (0.0, 0.25, 0.5, 0.75, 1.0)
#: a loop with functions: the central differences of its gains, the step in a disturbance as a
#: fraction of its bound; of its linearisation where the exact Jacobian does not exist, the step
#: as a fraction of max(1, |x_eq|) (a state) or of the bound (a disturbance)
GAIN_STEP: Final = 1e-3
JACOBIAN_STEP: Final = 1e-6
#: a loop with functions: what the document's ``field`` says was integrated
FIELD_TEXT: Final = "the true loop: each function evaluated by numpy, not the recast polynomial loop"
#: the sweeps' cross-checks of a loop with functions (:func:`crosscheck_horizon`): HORIZON_TIME_CONSTANTS
#: slowest time constants of the exact linearisation, this many seconds without a decaying one
CROSSCHECK_FALLBACK_HORIZON_S: Final = 60.0

KIND_NONE, KIND_CONSTANT, KIND_FEEDBACK, KIND_SQUARE = 0, 1, 2, 3


# -- the model in floating point ----------------------------------------------------------------

@dataclass(frozen=True)
class Linearization:
    """The loop linearised at the equilibrium (``d = 0``): exact ``A``, ``B``, ``C`` as floats."""

    A: FloatArray
    B: FloatArray
    C: dict[str, FloatArray]
    eigenvalues: npt.NDArray[np.complex128]
    #: per output and disturbance: sign of the first non-zero Markov parameter c A^j B_k (j >= 1)
    markov_sign: dict[str, tuple[float, ...]]

    def slowest_time(self) -> float | None:
        """``1 / min |Re lambda|`` over the eigenvalues off the imaginary axis (None: none)."""
        if not self.eigenvalues.size:
            return None
        top = float(np.max(np.abs(self.eigenvalues)))
        re = np.abs(self.eigenvalues.real)
        useful = re[re > CENTRE_FRACTION * top]
        return 1.0 / float(useful.min()) if useful.size else None

    def steady_response(self, bounds: FloatArray) -> FloatArray:
        """``|A^-1 B| b``: the size of the linearisation's steady response to the bounds (0 when
        ``A`` is singular)."""
        n = self.A.shape[0]
        if not self.B.size or not bounds.any():
            return np.zeros(n)
        try:
            if np.linalg.cond(self.A) > 1e12:
                return np.zeros(n)
            gain = np.linalg.solve(self.A, self.B)
        except np.linalg.LinAlgError:
            return np.zeros(n)
        return np.abs(gain) @ bounds


class CompiledPolys:
    """Several polynomials of one ring evaluated together at ``(batch, nvars)`` points: the union
    of their monomials is evaluated once (a power table per variable), then one matrix product."""

    def __init__(self, ring: Ring, polys: Sequence[Poly]) -> None:
        terms = [ring.float_terms(p) for p in polys]
        monos = sorted({mono for t in terms for mono in t})
        self.nvars = ring.nvars
        self.count = len(polys)
        self.exponents = np.array(monos, dtype=np.intp).reshape(-1, ring.nvars)
        where = {mono: i for i, mono in enumerate(monos)}
        self.coefficients = np.zeros((len(monos), len(polys)))
        for j, t in enumerate(terms):
            for mono, c in t.items():
                self.coefficients[where[mono], j] = c
        self.max_power = [int(self.exponents[:, k].max(initial=0)) for k in range(ring.nvars)]

    def __call__(self, x: FloatArray) -> FloatArray:
        """``(batch, len(polys))`` values."""
        batch = x.shape[0]
        if not self.exponents.shape[0]:
            return np.zeros((batch, self.count))
        monos = np.ones((batch, self.exponents.shape[0]))
        for k in range(self.nvars):
            top = self.max_power[k]
            if top == 0:
                continue
            table = np.empty((batch, top + 1))
            table[:, 0] = 1.0
            for e in range(1, top + 1):
                table[:, e] = table[:, e - 1] * x[:, k]
            monos *= table[:, self.exponents[:, k]]
        return monos @ self.coefficients


class LoopField(Protocol):
    """The field a simulation integrates: ``x'`` at ``(batch, n)`` states under ``(batch, m)``
    disturbances (None: every disturbance 0). Two implementations: :class:`_Field` (a polynomial
    loop) and :class:`lyapcheck.models.engines.recast_numeric.TrueField` (a loop with functions)."""

    def __call__(self, x: FloatArray, d: FloatArray | None) -> FloatArray: ...


class OutputGain(Protocol):
    """Per output, ``G_k = dy'/dd_k`` at ``d = 0`` (the bang-bang law's direction)."""

    def depends(self, k: int) -> bool:
        """Whether ``y'`` depends on ``d_k`` (otherwise the law takes the linearisation's Markov sign)."""
        ...

    def gain(self, k: int, x: FloatArray) -> FloatArray: ...


@dataclass(frozen=True)
class _Field:
    """``x' = N(x, d) / D(x)`` row by row, every numerator and denominator in one evaluation."""

    polys: CompiledPolys
    n: int
    m: int

    def __call__(self, x: FloatArray, d: FloatArray | None) -> FloatArray:
        xd = x if not self.m else np.concatenate([x, np.zeros((x.shape[0], self.m)) if d is None else d], axis=1)
        values = self.polys(xd)
        return values[:, :self.n] / values[:, self.n:]


@dataclass(frozen=True)
class _OutputFeedback:
    """``G_k = dy'/dd_k`` at ``d = 0``, sum_i dy/dx_i dN_i/dd_k / D_i, per disturbance (None where it
    is identically 0): three columns per term in ``polys``."""

    polys: CompiledPolys | None
    terms: tuple[tuple[int, ...] | None, ...]  # per k: the indices of its terms

    def depends(self, k: int) -> bool:
        return self.terms[k] is not None

    def gain(self, k: int, x: FloatArray) -> FloatArray:
        idx = self.terms[k]
        assert idx is not None and self.polys is not None
        values = self.polys(x)
        total = np.zeros(x.shape[0])
        for t in idx:
            total += values[:, 3 * t] * values[:, 3 * t + 1] / values[:, 3 * t + 2]
        return total


@dataclass(frozen=True)
class Prepared:
    """The simulated loop: a model's field, outputs, gains and linearisation in floating point,
    built once per model by :func:`prepare` (one constructor per loop kind: :func:`prepare_polynomial`,
    :func:`prepare_true_loop`); everything else in this module reads the loop through it."""

    model: "Model | RecastModel"
    field: LoopField
    output_polys: CompiledPolys
    output_names: tuple[str, ...]
    feedback: Mapping[str, OutputGain]
    linearization: Linearization
    equilibrium: FloatArray
    bounds: FloatArray
    #: each output's text as the file writes it (the document's ``outputs``)
    output_text: Mapping[str, str] = dataclasses.field(default_factory=dict)
    #: the states measured modulo 2 pi (their indices): an angle the loop sees only through its sine
    #: and cosine; convergence, escape and plots take its deviation in (-pi, pi]
    angles: tuple[int, ...] = ()
    #: why this loop cannot take a disturbance (then only the scenario ``none`` runs); None: it can
    undisturbed_only: str | None = None
    #: the keys this loop adds to the document (a loop with functions: ``kind``, ``field``, ...)
    document_keys: Mapping[str, Any] = dataclasses.field(default_factory=dict)

    def output_values(self, x: FloatArray) -> FloatArray:
        """``(batch, outputs)`` values of every output at ``(batch, n)`` states."""
        return self.output_polys(x)

    def output(self, name: str, x: FloatArray) -> FloatArray:
        return self.output_polys(x)[:, self.output_names.index(name)]

    def deviation(self, x: FloatArray) -> FloatArray:
        """``x - x_eq`` row by row, each angle's wrapped into ``(-pi, pi]``."""
        dev = np.asarray(x, dtype=np.float64) - self.equilibrium
        if self.angles:
            dev = dev.copy()
            a = list(self.angles)
            dev[..., a] = np.angle(np.exp(1j * dev[..., a]))
        return dev

    def field_stopped_beyond(self, y: FloatArray, d: FloatArray | None, escape: FloatArray) -> Evaluation:
        """The integrator's evaluation of the field at ``(batch, n)`` states: ``x' = f(x, d)``, 0 on a row
        farther than ``escape`` from the equilibrium (it stops there: one diverging row neither
        overflows nor slows the others)."""
        with np.errstate(over="ignore", invalid="ignore"):
            dy = self.field(y, d)
        far = np.any(np.abs(y - self.equilibrium) > escape, axis=1)
        if far.any():
            dy[far] = 0.0
        return Evaluation(dy, np.zeros(y.shape[0]), np.empty((y.shape[0], 0)))

    def box(self, factor: float, scale: FloatArray) -> FloatArray:
        """Half-widths ``factor * scale`` around the equilibrium, infinite along an angle (a
        pendulum that turns over has not left anything)."""
        out = factor * np.asarray(scale, dtype=np.float64)
        if self.angles:
            out = out.copy()
            out[list(self.angles)] = np.inf
        return out


def _output_poly(model: Model, name: str) -> Poly:
    """The output with the parameters set, a polynomial of :attr:`Model.state_ring`."""
    expr = model.outputs[name]
    ring, target = model.ring, model.state_ring
    num = ring.restrict(ring.substitute(expr.numerator, model.parameters), target)
    den = ring.restrict(ring.substitute(expr.denominator, model.parameters), target)
    return num * (1 / den.leading_coefficient())


def prepare(model: "Model | RecastModel") -> Prepared:
    """The simulated loop of a model, once per model: :func:`prepare_polynomial` for a polynomial
    (rational) loop, :func:`prepare_true_loop` for a loop with functions."""
    return prepare_polynomial(model) if isinstance(model, Model) else prepare_true_loop(model)


def _prepared(model: "Model | RecastModel", field_: LoopField, outputs: Sequence[Poly],
              feedback: Mapping[str, OutputGain], A: Sequence[Sequence[Fraction | float]],
              B: Sequence[Sequence[Fraction | float]], C: Mapping[str, Sequence[Fraction | float]], **kind: Any) -> Prepared:
    """The :class:`Prepared` of either kind from what differs between them (the field, the outputs as
    polynomials of the states, the gains, ``A``, ``B``, ``C``; ``kind``: the angles, ...)."""
    return Prepared(model=model, field=field_, output_polys=CompiledPolys(Ring(model.states), outputs),
                    output_names=tuple(model.outputs), feedback=feedback, linearization=linearization(A, B, C),
                    equilibrium=np.array([float(v) for v in model.equilibrium]),
                    bounds=np.array([float(b) for b in model.disturbances.values()]),
                    output_text=dict(model.output_text), **kind)


def prepare_polynomial(model: Model) -> Prepared:
    """A polynomial (rational) loop's field, outputs, feedback gains and linearisation, all from its
    exact polynomials."""
    full = model.state_ring
    states = Ring(model.states)
    rhs = field_at(model)
    zero_d = {d: Fraction(0) for d in model.disturbances}
    eq = list(model.equilibrium)
    point = eq + [Fraction(0)] * len(model.disturbances)
    n, m = model.n, len(model.disturbances)

    def on_states(p: Poly) -> Poly:
        return full.restrict(full.substitute(p, zero_d), states)

    def value(p: Poly) -> Fraction:
        return full.evaluate(p, point)

    # at the equilibrium every numerator vanishes (checked exactly on loading), so
    # d(N/D)/dv = (dN/dv) / D there; a disturbance never enters a denominator
    dens = [value(r.denominator) for r in rhs]
    A = [[value(r.numerator.derivative(s)) / dens[i] for s in model.states] for i, r in enumerate(rhs)]
    B = [[value(r.numerator.derivative(d)) / dens[i] for d in model.disturbances] for i, r in enumerate(rhs)]
    feedback: dict[str, _OutputFeedback] = {}
    C: dict[str, list[Fraction]] = {}
    output_polys: list[Poly] = []
    for name in model.outputs:
        y = _output_poly(model, name)
        output_polys.append(on_states(y))
        C[name] = [value(y.derivative(s)) for s in model.states]
        columns: list[Poly] = []
        per_k: list[tuple[int, ...] | None] = []
        for k, d in enumerate(model.disturbances):
            pieces = []
            for s, r in zip(model.states, rhs):
                dy, dn = on_states(y.derivative(s)), on_states(r.numerator.derivative(d))
                if not dy.is_zero() and not dn.is_zero():
                    pieces.append((dy, dn, on_states(r.denominator)))
            if _sums_to_zero(pieces):
                per_k.append(None)
            else:
                first = len(columns) // 3
                per_k.append(tuple(range(first, first + len(pieces))))
                columns += [q for piece in pieces for q in piece]
        feedback[name] = _OutputFeedback(CompiledPolys(states, columns) if columns else None, tuple(per_k))
    field_ = _Field(CompiledPolys(full, [r.numerator for r in rhs] + [r.denominator for r in rhs]), n, m)
    return _prepared(model, field_, output_polys, feedback, A, B, C)


def prepare_true_loop(model: RecastModel) -> Prepared:
    """A loop with functions' true field, outputs, bang-bang gains, linearisation and angles (the
    module docstring)."""
    from lyapcheck.models.classes.recast_classes import angle_states

    states = Ring(model.states)
    eq = np.array([float(v) for v in model.equilibrium])
    bounds = np.array([float(b) for b in model.disturbances.values()])
    field_ = TrueField(model)
    feedback: dict[str, TrueOutputGain] = {}
    C: dict[str, list[Fraction]] = {}
    for name in model.outputs:
        y = model.outputs[name]
        grad = [y.derivative(s) for s in model.states]
        C[name] = [states.evaluate(g, list(model.equilibrium)) for g in grad]
        feedback[name] = TrueOutputGain(field_, CompiledPolys(states, grad), _dependence(model, grad), bounds)
    A, B = _true_jacobian(model, field_, eq, bounds)
    angles = tuple(angle_states(model.system))
    held = None
    text = FIELD_TEXT
    if model.disturbances and model.robust is None:
        held = ("its disturbances cannot be kept as variables of the recast loop: it is simulated with "
                f"{', '.join(model.disturbances)} held at 0")
        text += f"; the disturbances {', '.join(model.disturbances)} held at 0 (scenario none only)"
    return _prepared(model, field_, list(model.outputs.values()), feedback, A, B, C,
                     angles=tuple(model.states.index(a) for a in angles), undisturbed_only=held,
                     document_keys={"kind": "recast", "field": text, "angles_modulo_2pi": list(angles)})


@dataclass(frozen=True)
class TrueOutputGain:
    """``G_k = dy'/dd_k`` at ``d = 0`` on the true loop of a loop with functions: ``sum_i dy/dx_i
    df_i/dd_k``, the first factor exact, the second a central difference (an :class:`OutputGain`)."""

    field: TrueField
    gradient: CompiledPolys
    dependent: tuple[bool, ...]
    bounds: Any

    def depends(self, k: int) -> bool:
        return self.dependent[k]

    def gain(self, k: int, x: FloatArray) -> FloatArray:
        h = GAIN_STEP * float(self.bounds[k])
        step = np.zeros((x.shape[0], len(self.bounds)))
        step[:, k] = h
        slope = (self.field(x, step) - self.field(x, -step)) / (2 * h)
        return np.sum(self.gradient(x) * slope, axis=1)


def _moved_by(system: RecastSystem, disturbance: str) -> list[str]:
    """The disturbance and every auxiliary whose argument depends on it (through earlier ones)."""
    ring = system.ring
    moved = [disturbance]
    for a in system.auxiliaries:
        if a.argument is not None and degree_in(ring, a.argument, moved) > 0:
            moved.append(a.name)
    return moved


def _dependence(model: RecastModel, output_gradient: Sequence[Any]) -> tuple[bool, ...]:
    """Per disturbance, whether ``y'`` may depend on it: a state whose rate ``y`` feels (its
    ``dy/dx_i`` is not identically 0) has a field that uses the disturbance or a function of it.
    (Structural: a term that cancels still counts, and its gain is then 0.)"""
    robust = model.robust
    if robust is None:
        return tuple(False for _ in model.disturbances)
    ring = robust.ring
    out = []
    for d in model.disturbances:
        moved = _moved_by(robust, d)
        out.append(any(not dy.is_zero() and (degree_in(ring, r.numerator, moved) > 0
                                             or degree_in(ring, r.denominator, moved) > 0)
                       for dy, r in zip(output_gradient, robust.field[:model.n])))
    return tuple(out)


def _true_jacobian(model: RecastModel, field_: TrueField, equilibrium: FloatArray, bounds: FloatArray
                   ) -> tuple[list[list[Any]], list[list[Any]]]:
    """A loop with functions' ``A = df/dx``, ``B = df/dd`` at the equilibrium (``d = 0``): exact (the
    chain rule through the auxiliaries, :func:`lyapcheck.models.classes.recast_classes.jacobian`),
    else central differences of the true field."""
    from lyapcheck.models.classes.recast_classes import base_loop, jacobian

    n, m = model.n, len(model.disturbances)
    system = model.robust if m and model.robust is not None else model.system
    exact = jacobian(base_loop(system))
    if not isinstance(exact, str):
        A = [row[:n] for row in exact[:n]]
        B = [row[n:n + m] if system is model.robust else [Fraction(0)] * m for row in exact[:n]]
        return A, B
    x0, d0 = equilibrium[None, :], np.zeros((1, m))
    A_num = np.zeros((n, n))
    for j in range(n):
        h = JACOBIAN_STEP * max(1.0, abs(float(equilibrium[j])))
        e = np.zeros((1, n))
        e[0, j] = h
        with np.errstate(all="ignore"):
            A_num[:, j] = (field_(x0 + e, d0 if m else None) - field_(x0 - e, d0 if m else None))[0] / (2 * h)
    B_num = np.zeros((n, m))
    if field_.disturbed is not None:
        for k in range(m):
            h = JACOBIAN_STEP * float(bounds[k])
            e = np.zeros((1, m))
            e[0, k] = h
            with np.errstate(all="ignore"):
                B_num[:, k] = (field_(x0, e) - field_(x0, -e))[0] / (2 * h)
    A_num[~np.isfinite(A_num)] = 0.0
    B_num[~np.isfinite(B_num)] = 0.0
    return A_num.tolist(), B_num.tolist()


def linearization(A: Sequence[Sequence[Fraction | float]], B: Sequence[Sequence[Fraction | float]],
                  C: Mapping[str, Sequence[Fraction | float]]) -> Linearization:
    """The :class:`Linearization` of ``x' = A x + B d``, ``y = C x`` (exact entries where the loop
    gives them, so that the Markov signs are exact; floats otherwise)."""
    n = len(A)
    m = len(B[0]) if n and len(B) else 0
    markov = {name: tuple(_markov_sign(A, [row[k] for row in B], c, n) for k in range(m)) for name, c in C.items()}
    A_float = np.array([[float(v) for v in row] for row in A]).reshape(n, n)
    B_float = np.array([[float(v) for v in row] for row in B]).reshape(n, m)
    eig = np.linalg.eigvals(A_float) if n else np.zeros(0, dtype=complex)
    return Linearization(A=A_float, B=B_float, C={name: np.array([float(v) for v in c]) for name, c in C.items()},
                         eigenvalues=eig, markov_sign=markov)


def _sums_to_zero(pieces: Sequence[tuple[Poly, Poly, Poly]]) -> bool:
    """Whether sum_i a_i b_i / e_i is identically 0 (exactly, over a common denominator)."""
    if not pieces:
        return True
    total = None
    for i, (a, b, _) in enumerate(pieces):
        term = a * b
        for j, (_, _, e) in enumerate(pieces):
            if j != i:
                term = term * e
        total = term if total is None else total + term
    return bool(total is not None and total.is_zero())


def _markov_sign(A: Sequence[Sequence[Fraction | float]], b: Sequence[Fraction | float],
                 c: Sequence[Fraction | float], n: int) -> float:
    """Sign of the first non-zero ``c A^j b`` for j = 1..n-1 (exact for exact entries), else +1."""
    v = list(b)
    for _ in range(1, max(n, 1)):
        v = [sum((A[i][j] * v[j] for j in range(n)), Fraction(0)) for i in range(n)]
        markov = sum((ci * vi for ci, vi in zip(c, v)), Fraction(0))
        if markov != 0:
            return 1.0 if markov > 0 else -1.0
    return 1.0


def state_scale(prepared: Prepared, starts: FloatArray | None = None) -> FloatArray:
    """Per state, the natural scale (module docstring): what tolerances, escape and convergence
    are measured against."""
    model = prepared.model
    eq = prepared.equilibrium
    parts = [np.abs(eq), prepared.linearization.steady_response(prepared.bounds)]
    if starts is not None and len(starts):
        parts.append(np.max(np.abs(np.asarray(starts) - eq), axis=0))
    if model.domain:
        parts.append(np.array([max(abs(float(model.domain[s][0]) - e), abs(float(model.domain[s][1]) - e))
                               for s, e in zip(model.states, eq)]))
    scale = np.max(np.vstack(parts), axis=0)
    return np.where(scale > 0, scale, UNIT_SCALE)


def default_horizon(prepared: Prepared) -> float:
    """``HORIZON_TIME_CONSTANTS`` slowest time constants of the linearisation (s); without one
    (every eigenvalue on the imaginary axis) as many of its fastest, 1 s when A = 0."""
    lin = prepared.linearization
    slow = lin.slowest_time()
    if slow is None:
        top = float(np.max(np.abs(lin.eigenvalues))) if lin.eigenvalues.size else 0.0
        slow = 1.0 / top if top > 0 else 1.0
    return HORIZON_TIME_CONSTANTS * slow


def crosscheck_horizon(model: RecastModel) -> float:
    """The horizon of the sweeps' cross-checks of a loop with functions (:mod:`sweeps.crosscheck`):
    ``HORIZON_TIME_CONSTANTS`` slowest time constants of the exact linearisation of its loop without
    disturbances, ``CROSSCHECK_FALLBACK_HORIZON_S`` without a decaying one (or without an exact
    Jacobian). ``simulate`` itself takes :func:`default_horizon`, for either kind."""
    from lyapcheck.models.classes.recast_classes import base_loop, jacobian

    J = jacobian(base_loop(model.system))
    if isinstance(J, str):
        return CROSSCHECK_FALLBACK_HORIZON_S
    real = np.linalg.eigvals(np.array([[float(x) for x in row] for row in J])).real
    slowest = np.max(real)
    return float(HORIZON_TIME_CONSTANTS / -slowest) if slowest < 0 else CROSSCHECK_FALLBACK_HORIZON_S


def default_frequencies(prepared: Prepared, t_end: float) -> FloatArray:
    """``N_FREQUENCIES`` log-spaced angular frequencies (rad/s): from one period per tail window to
    ``FREQUENCY_HIGH`` times the largest |eigenvalue| of the linearisation."""
    low = 2 * math.pi / (TAIL_FRACTION * t_end)
    eig = prepared.linearization.eigenvalues
    top = float(np.max(np.abs(eig))) if eig.size else 0.0
    high = max(FREQUENCY_HIGH * top, 10 * low)
    return np.geomspace(low, high, N_FREQUENCIES)


# -- disturbances -------------------------------------------------------------------------------

@dataclass(frozen=True)
class ModelDisturbance:
    """One disturbance law of a row (see the module docstring); every value within the bounds.

    ``values`` are SI: the constant's ``d_k``, or the square wave's signed amplitudes; a feedback
    uses the bounds themselves with ``output`` and ``direction``.
    """

    kind: str
    values: tuple[float, ...] = ()
    angular_frequency: float = 0.0
    phase: float = 0.0
    output: str = ""
    direction: int = 1

    def describe(self, model: "Model | RecastModel") -> dict[str, Any]:
        """JSON description (SI; ``kind`` is the scenario name)."""
        names = list(model.disturbances)
        if self.kind == "none":
            return {"kind": "none"}
        if self.kind == "constant":
            return {"kind": "constant", "d": dict(zip(names, self.values))}
        if self.kind == "square":
            return {"kind": "square", "amplitude": dict(zip(names, self.values)),
                    "angular_frequency_rad_s": self.angular_frequency,
                    "frequency_hz": self.angular_frequency / (2 * math.pi), "phase_rad": self.phase}
        return {"kind": "bang-bang", "output": self.output, "direction": self.direction,
                "bound": {k: float(b) for k, b in model.disturbances.items()},
                "law": "d_k = b_k sign((y + direction*layer) * G_k), G_k = dy'/dd_k, or the sign of the "
                       "linearisation's first Markov parameter where y' does not depend on d_k"}


def _sign_patterns(m: int, first_positive: bool = False) -> list[tuple[float, ...]]:
    patterns = [tuple(float(s) for s in p) for p in itertools.product((1.0, -1.0), repeat=m)]
    return [p for p in patterns if not first_positive or not p or p[0] > 0]


def scenario_disturbances(prepared: Prepared, scenarios: Sequence[str], frequencies: FloatArray,
                          phases: Sequence[float] = (0.0,)) -> list[ModelDisturbance]:
    """The concrete disturbances of the named scenarios (module docstring), in order."""
    model = prepared.model
    b = prepared.bounds
    out: list[ModelDisturbance] = []
    for name in scenarios:
        if name == "none":
            out.append(ModelDisturbance("none"))
        elif name == "constant":
            out += [ModelDisturbance("constant", tuple(float(v) for v in np.array(s) * b))
                    for s in _sign_patterns(len(b))]
        elif name == "bang-bang":
            out += [ModelDisturbance("bang-bang", output=y, direction=beta)
                    for y in model.outputs for beta in (1, -1)]
        elif name == "square":
            out += [ModelDisturbance("square", tuple(float(v) for v in np.array(s) * b), float(w), float(ph))
                    for s in _sign_patterns(len(b), first_positive=True) for w in frequencies for ph in phases]
        else:
            raise InvalidParameter("scenarios", "one of " + ", ".join(SCENARIOS), name)
    return out


# -- the batched system -------------------------------------------------------------------------

@dataclass(frozen=True)
class _Rows:
    """Per-row disturbance data of a batch (global rows)."""

    kind: IntArray
    constant: FloatArray  # (R, m)
    amplitude: FloatArray  # (R, m) square waves
    switch_times: FloatArray  # (R, K), inf-padded, sorted
    feedback_output: IntArray  # (R,) index into the outputs, -1 for none
    feedback_direction: FloatArray  # (R,)
    output_layer: FloatArray  # (R,)


def _switch_table(disturbances: Sequence[ModelDisturbance], t_end: float) -> FloatArray:
    """Square waves' switching times ``(j pi - phase) / omega`` in ``(0, t_end]``, one row each."""
    rows: list[FloatArray] = []
    for dist in disturbances:
        if dist.kind != "square":
            rows.append(np.zeros(0))
            continue
        w, ph = dist.angular_frequency, math.fmod(dist.phase, 2 * math.pi)
        first = math.floor(ph / math.pi) + 1
        last = math.floor((w * t_end + ph) / math.pi)
        times = np.asarray((np.arange(first, last + 1) * math.pi - ph) / w, dtype=np.float64)
        rows.append(times[(times > 0) & (times <= t_end)])
    width = max((r.size for r in rows), default=0)
    table = np.full((len(rows), max(width, 1)), np.inf)
    for i, r in enumerate(rows):
        table[i, :r.size] = r
    return table


def _initial_square_sign(dist: ModelDisturbance) -> float:
    return 1.0 if math.fmod(dist.phase, 2 * math.pi) % (2 * math.pi) < math.pi else -1.0


class _ScenarioSystem:
    """The model with one disturbance law per row, as the integrator's batched system.

    Square waves are evaluated at the step's segment time and their switches are breakpoints, as
    is the tail window's start; a row farther than ``escape`` from the equilibrium stops moving.
    The per-row data of the working set is sliced once per :meth:`take` (the integrator calls it
    when rows finish), not at every evaluation.
    """

    def __init__(self, prepared: Prepared, rows: _Rows, initial_sign: FloatArray, t_tail: float,
                 escape: FloatArray, gain_scale: FloatArray, index: IntArray | None = None) -> None:
        self.prepared = prepared
        self.rows = rows
        self.initial_sign = initial_sign
        self.t_tail = t_tail
        self.escape = escape
        self.gain_scale = gain_scale  # (outputs, m)
        self.index = np.arange(rows.kind.size) if index is None else index
        idx = self.index
        kind = rows.kind[idx]
        self.base = rows.constant[idx]
        self.square = np.flatnonzero(kind == KIND_SQUARE)
        g = idx[self.square]
        self.square_table = rows.switch_times[g]
        self.square_amplitude = rows.amplitude[g]
        self.square_sign = initial_sign[g]
        fb = np.flatnonzero(kind == KIND_FEEDBACK)
        self.feedback: list[tuple[str, int, IntArray, FloatArray, FloatArray]] = []
        for o in np.unique(rows.feedback_output[idx[fb]]):
            sel = fb[rows.feedback_output[idx[fb]] == o]
            layer = rows.output_layer[idx[sel]]
            self.feedback.append((prepared.output_names[o], int(o), sel, layer,
                                  rows.feedback_direction[idx[sel]] * layer))

    @property
    def size(self) -> int:
        return int(self.index.size)

    def take(self, index: IntArray) -> "_ScenarioSystem":
        return _ScenarioSystem(self.prepared, self.rows, self.initial_sign, self.t_tail, self.escape,
                               self.gain_scale, self.index[index])

    def disturbance(self, t_segment: FloatArray, x: FloatArray) -> FloatArray:
        p = self.prepared
        if not self.square.size and not self.feedback:
            return self.base
        d = self.base.copy()
        if self.square.size:
            count = np.count_nonzero(self.square_table <= t_segment[self.square, None], axis=1)
            d[self.square] = self.square_amplitude * (self.square_sign * (1 - 2 * (count % 2)))[:, None]
        for name, o, sel, layer, offset in self.feedback:
            xs = x[sel]
            push = np.clip((p.output(name, xs) + offset) / layer, -1.0, 1.0)
            fbk = p.feedback[name]
            for k, b in enumerate(p.bounds):
                if not fbk.depends(k):
                    d[sel, k] = b * p.linearization.markov_sign[name][k] * push
                else:
                    d[sel, k] = b * push * np.clip(fbk.gain(k, xs) / self.gain_scale[o, k], -1.0, 1.0)
        return d

    def rhs(self, t: FloatArray, y: FloatArray, t_segment: FloatArray) -> Evaluation:
        d = self.disturbance(t_segment, y) if self.prepared.bounds.size else None
        return self.prepared.field_stopped_beyond(y, d, self.escape)

    def next_breakpoint(self, t: FloatArray) -> FloatArray:
        out = np.where(t < self.t_tail, self.t_tail, np.inf)
        if self.square.size:
            table = self.square_table
            nxt = np.where(table > t[self.square, None], table, np.inf).min(axis=1)
            out[self.square] = np.minimum(out[self.square], nxt)
        return out


class _TailObserver:
    """Sup of ``|y|`` over the tail per row and output; optionally every accepted step (plots)."""

    def __init__(self, prepared: Prepared, rows: int, t_tail: float, record: IntArray | None) -> None:
        self.prepared = prepared
        self.t_tail = t_tail
        self.sup = np.zeros((rows, len(prepared.output_names)))
        self.record = set(int(i) for i in record) if record is not None else set()
        self.steps: dict[int, list[tuple[float, float, FloatArray, FloatArray, FloatArray, FloatArray]]] = {
            i: [] for i in self.record}
        self.first: dict[int, tuple[float, FloatArray]] = {}

    def start(self, index: IntArray, t: FloatArray, y: FloatArray, f: FloatArray) -> None:
        tail = t >= self.t_tail
        if tail.any():
            self.sup[index[tail]] = np.abs(self.prepared.output_values(y[tail]))
        for r, g in enumerate(index):
            if int(g) in self.record:
                self.first[int(g)] = (float(t[r]), y[r].copy())

    def step(self, index: IntArray, t0: FloatArray, t1: FloatArray, y0: FloatArray, y1: FloatArray,
             f0: FloatArray, f1: FloatArray) -> None:
        tail = np.flatnonzero(t0 >= self.t_tail)
        if tail.size:
            h = t1[tail] - t0[tail]
            best = self.sup[index[tail]]
            for th in SAMPLE_THETAS:
                if th == 0.0:
                    ys = y0[tail]
                elif th == 1.0:
                    ys = y1[tail]
                else:
                    ys = hermite(th, h, y0[tail], y1[tail], f0[tail], f1[tail])
                best = np.maximum(best, np.abs(self.prepared.output_values(ys)))
            self.sup[index[tail]] = best
        if self.record:
            for r, g in enumerate(index):
                if int(g) in self.record:
                    self.steps[int(g)].append((float(t0[r]), float(t1[r]), y0[r].copy(), y1[r].copy(),
                                               f0[r].copy(), f1[r].copy()))

    def trajectory(self, row: int, samples: int, center: FloatArray | None = None,
                   box: FloatArray | None = None) -> tuple[FloatArray, FloatArray]:
        """Times and states of a recorded row, resampled (Hermite inside the steps); with ``box``,
        only up to the first step that ends farther than ``box`` from ``center``."""
        t_start, y_start = self.first[row]
        steps = self.steps[row]
        if box is not None and center is not None:
            out = [i for i, s in enumerate(steps) if np.any(np.abs(s[3] - center) > box)]
            steps = steps[:out[0] + 1] if out else steps
        if not steps:
            return np.array([t_start]), y_start[None, :]
        t0s = np.array([s[0] for s in steps])
        t1s = np.array([s[1] for s in steps])
        grid = np.linspace(t_start, t1s[-1], samples)
        k = np.clip(np.searchsorted(t1s, grid, side="left"), 0, len(steps) - 1)
        Y0, Y1 = np.array([steps[i][2] for i in k]), np.array([steps[i][3] for i in k])
        F0, F1 = np.array([steps[i][4] for i in k]), np.array([steps[i][5] for i in k])
        h = t1s[k] - t0s[k]
        theta = np.clip(np.where(h > 0, (grid - t0s[k]) / np.where(h > 0, h, 1.0), 0.0), 0.0, 1.0)
        return grid, hermite(theta, h, Y0, Y1, F0, F1)


@dataclass
class _Batch:
    """What one batched call measured; rows are start-major: row = start * len(disturbances) + j."""

    starts: FloatArray
    disturbances: list[ModelDisturbance]
    sup: FloatArray  # (R, outputs); NaN for a diverged row
    final: FloatArray  # (R, n)
    diverged: BoolArray
    converged: BoolArray
    result: IntegrationResult
    t_end: float
    t_tail: float
    rtol: float
    seconds: float
    observer: _TailObserver
    scale: FloatArray

    def failure(self, row: int) -> str | None:
        why = self.result.failure(row, self.t_end)
        if why is None and self.diverged[row]:
            return "the state left the escape box (ESCAPE_FACTOR state scales from the equilibrium): diverging"
        return why


def _run(prepared: Prepared, starts: FloatArray, disturbances: Sequence[ModelDisturbance], *, t_end: float,
         rtol: float, scale: FloatArray, record: Sequence[int] | None = None, series: Any | None = None) -> _Batch:
    """Integrate every (start, disturbance) pair in one call and measure it (``series``: a
    :class:`lyapcheck.models.engines.series.SeriesRecorder` that also watches the steps)."""
    begin = time.perf_counter()
    starts = np.atleast_2d(np.asarray(starts, dtype=np.float64))
    dists = list(disturbances)
    S, J = starts.shape[0], len(dists)
    R = S * J
    if R > MAX_ROWS:
        raise InvalidParameter("grid", f"at most {MAX_ROWS} trajectories (starts x disturbances, MAX_ROWS)",
                               f"{S} starts x {J} disturbances")
    m = prepared.bounds.size
    kind_of = {"none": KIND_NONE, "constant": KIND_CONSTANT, "bang-bang": KIND_FEEDBACK, "square": KIND_SQUARE}
    kinds = np.array([kind_of[dd.kind] for dd in dists], dtype=np.intp)
    constant = np.array([dd.values if dd.kind == "constant" else (0.0,) * m for dd in dists]).reshape(J, m)
    amplitude = np.array([dd.values if dd.kind == "square" else (0.0,) * m for dd in dists]).reshape(J, m)
    names = prepared.output_names
    fb_out = np.array([names.index(dd.output) if dd.kind == "bang-bang" else -1 for dd in dists], dtype=np.intp)
    fb_dir = np.array([float(dd.direction) for dd in dists])
    table = _switch_table(dists, t_end)
    squares = sum(dd.kind == "square" for dd in dists)
    if S * squares * table.shape[1] > MAX_SWITCH_TABLE:
        raise InvalidParameter("frequencies", f"fewer switches: {S} starts x {squares} square waves x "
                                              f"{table.shape[1]} switches exceed MAX_SWITCH_TABLE = {MAX_SWITCH_TABLE} "
                                              "(lower the frequencies, the horizon or the number of starts)",
                               f"up to {max((dd.angular_frequency for dd in dists), default=0.0):.6g} rad/s")
    init = np.array([_initial_square_sign(dd) for dd in dists])
    # output scales: the feedback's layer (|y| at the starts and the equilibrium, the linear steady
    # response, the slope of y times the state scale)
    y_starts = np.abs(prepared.output_values(starts)) if len(names) else np.zeros((S, 0))
    y_eq = np.abs(prepared.output_values(prepared.equilibrium[None, :]))[0] if len(names) else np.zeros(0)
    steady = prepared.linearization.steady_response(prepared.bounds)
    y_scale = np.array([max(float(y_starts[:, o].max(initial=0.0)), float(y_eq[o]),
                            float(np.abs(prepared.linearization.C[y]) @ steady),
                            float(np.abs(prepared.linearization.C[y]) @ scale)) for o, y in enumerate(names)])
    y_scale = np.where(y_scale > 0, y_scale, UNIT_SCALE)
    layer = np.where(fb_out >= 0, FEEDBACK_LAYER * y_scale[np.maximum(fb_out, 0)] if len(names) else 1.0, 1.0)
    gain_scale = _gain_scales(prepared, starts, scale)
    rows = _Rows(kind=np.tile(kinds, S), constant=np.tile(constant, (S, 1)), amplitude=np.tile(amplitude, (S, 1)),
                 switch_times=np.tile(table, (S, 1)), feedback_output=np.tile(fb_out, S),
                 feedback_direction=np.tile(fb_dir, S), output_layer=np.tile(layer, S))
    t_tail = (1 - TAIL_FRACTION) * t_end
    escape = prepared.box(ESCAPE_FACTOR, scale)
    system = _ScenarioSystem(prepared, rows, np.tile(init, S), t_tail, escape, gain_scale)
    y0 = np.repeat(starts, J, axis=0)
    observer = _TailObserver(prepared, R, t_tail, None if record is None else np.asarray(record, dtype=np.intp))
    if series is not None:
        from lyapcheck.integrator import Fanout
    result = integrate(system, 0.0, y0, t_end, rtol=rtol, atol=ATOL_PER_RTOL * rtol * scale,
                       max_step=TAIL_FRACTION * t_end / STEPS_PER_TAIL,
                       observer=observer if series is None else Fanout(observer, series),
                       max_iterations=SIM_MAX_STEPS)
    final = result.y
    offset = np.abs(prepared.deviation(final))
    escaped = np.any(offset > escape, axis=1) | ~np.all(np.isfinite(final), axis=1)
    diverged = escaped | (result.status != STATUS_OK)
    converged = ~diverged & np.all(offset <= CONVERGENCE_RADIUS * scale, axis=1)
    sup = np.where(diverged[:, None], np.nan, observer.sup)
    return _Batch(starts=starts, disturbances=dists, sup=sup, final=final, diverged=diverged, converged=converged,
                  result=result, t_end=t_end, t_tail=t_tail, rtol=rtol, seconds=time.perf_counter() - begin,
                  observer=observer, scale=scale)


def _gain_scales(prepared: Prepared, starts: FloatArray, scale: FloatArray) -> FloatArray:
    """Per output and disturbance, the layer of ``sat(G_k / gamma_k)``: FEEDBACK_LAYER times the
    largest |G_k| at the starts, the equilibrium and the corners of the state scale's box."""
    names = prepared.output_names
    m = prepared.bounds.size
    out = np.ones((len(names), m))
    eq = prepared.equilibrium
    probes = np.vstack([starts, eq[None, :], eq + scale, eq - scale])
    for o, y in enumerate(names):
        for k in range(m):
            if not prepared.feedback[y].depends(k):
                continue
            with np.errstate(over="ignore", invalid="ignore", divide="ignore"):
                g = np.abs(prepared.feedback[y].gain(k, probes))
            top = float(np.max(g[np.isfinite(g)], initial=0.0))
            out[o, k] = FEEDBACK_LAYER * top if top > 0 else 1.0
    return out


# -- inputs -------------------------------------------------------------------------------------

def parse_start(model: "Model | RecastModel", text: str) -> FloatArray:
    """One ``--x0`` start, ``"x1=1,x2=0"`` or ``"x1=1 x2=0"``: values are numbers or unit strings
    (SI inside; ``"x1=1 mm x2=0"`` splits before each ``NAME=``); missing states take the
    equilibrium's value."""
    import re

    from lyapcheck.units import parse_si_quantity

    expected = (f"NAME=VALUE pairs separated by commas or spaces naming the model's states "
                f"({', '.join(model.states)})")
    if not isinstance(text, str) or not text.strip():
        raise InvalidParameter("x0", expected, text)
    values = dict(zip(model.states, model.equilibrium))
    seen: set[str] = set()
    for item in re.split(r"\s*,\s*|\s+(?=[A-Za-z_]\w*\s*=)", text.strip()):
        name, sep, value = item.partition("=")
        name = name.strip()
        if not sep or not name or not value.strip():
            raise InvalidParameter("x0", expected, text)
        if name not in model.states:
            raise InvalidParameter("x0", expected + f"; '{name}' is not one", text)
        if name in seen:
            raise InvalidParameter("x0", expected + f", each once ('{name}' twice)", text)
        seen.add(name)
        try:
            values[name] = parse_si_quantity(name, value.strip())
        except InvalidParameter as exc:
            raise InvalidParameter("x0", f"{exc.expected} for the state '{name}'", text) from None
    return np.array([float(values[s]) for s in model.states])


def grid_over_domain(model: "Model | RecastModel", per_state: int) -> FloatArray:
    """``per_state`` evenly spaced points per state over the model's ``[domain]`` (every combination)."""
    if model.domain is None:
        raise InvalidParameter("grid", "used with a model that has a [domain] (this one has none: give the starts "
                                       "as x0)", per_state)
    n = model.n
    if isinstance(per_state, bool) or not isinstance(per_state, int) or not 2 <= per_state <= MAX_GRID_PER_STATE:
        raise InvalidParameter("grid", f"an integer in [2, {MAX_GRID_PER_STATE}] (points per state)", per_state)
    if per_state ** n > MAX_STARTS:
        top = int(math.floor(MAX_STARTS ** (1 / n) + 1e-9))
        raise InvalidParameter("grid", f"an integer in [2, {max(top, 1)}] for {n} states (N**{n} starts, at most "
                                       f"MAX_STARTS = {MAX_STARTS})", per_state)
    axes = [np.linspace(float(model.domain[s][0]), float(model.domain[s][1]), per_state) for s in model.states]
    mesh = np.meshgrid(*axes, indexing="ij")
    return np.column_stack([g.ravel() for g in mesh])


def default_starts(prepared: Prepared) -> tuple[FloatArray, str]:
    """The equilibrium and a small grid over the ``[domain]`` (``DEFAULT_GRID`` per state, or
    ``DEFAULT_GRID_LIMIT`` seeded uniform points for many states), or without a domain the
    equilibrium and ``x_eq +- NEAR_START_FRACTION * scale`` along each state. Returns the starts and
    a sentence saying which."""
    from lyapcheck.models.engines.numeric import grid_starts

    model = prepared.model
    eq = prepared.equilibrium
    if model.domain:
        fits = [k for k in range(DEFAULT_GRID_MIN, DEFAULT_GRID_MAX + 1) if k ** model.n <= DEFAULT_GRID_LIMIT]
        per_state = max(fits) if fits else DEFAULT_GRID_MIN
        grid = grid_starts(model.domain, model.states, per_state, DEFAULT_GRID_LIMIT)
        how = (f"the equilibrium and a {per_state}-per-state grid over [domain]" if fits
               else f"the equilibrium and {DEFAULT_GRID_LIMIT} seeded uniform points in [domain]")
        grid = grid[np.any(grid != eq, axis=1)]  # the equilibrium once
        return np.vstack([eq[None, :], grid]), how
    scale = state_scale(prepared)
    near = [eq + sign * NEAR_START_FRACTION * scale[i] * np.eye(model.n)[i] for i in range(model.n) for sign in (1, -1)]
    return (np.vstack([eq[None, :], *near]),
            f"the equilibrium and x_eq +- {NEAR_START_FRACTION:g} x the state scale along each state (no [domain])")


def parse_frequencies(text: str) -> tuple[float, float]:
    """``--frequencies "LO..HI"`` (or one value): angular frequencies, bare numbers in rad/s,
    ``Hz`` as cycles per second (``"0.1 Hz..2 Hz"``); returns (lo, hi) in rad/s."""
    from lyapcheck.units import Kind, parse_quantity

    expected = "'LO..HI' with 0 < LO <= HI (bare numbers in rad/s, or with a unit: '0.1 Hz..10 Hz')"
    if not isinstance(text, str) or not text.strip():
        raise InvalidParameter("frequencies", expected, text)
    lo_text, sep, hi_text = text.partition("..")
    try:
        lo = float(parse_quantity("frequencies", lo_text.strip(), Kind.ROTATION, bare_allowed=True))
        hi = float(parse_quantity("frequencies", hi_text.strip(), Kind.ROTATION, bare_allowed=True)) if sep else lo
    except InvalidParameter:
        raise InvalidParameter("frequencies", expected, text) from None
    if not (math.isfinite(lo) and math.isfinite(hi) and 0 < lo <= hi):
        raise InvalidParameter("frequencies", expected, text)
    return lo, hi


def parse_horizon(text: str) -> float:
    """``--t-end``: seconds, a bare number or a duration with its unit (``"2 min"``)."""
    from lyapcheck.units import Kind, parse_quantity

    try:
        value = float(parse_quantity("t_end", text, Kind.TIME, bare_allowed=True))
    except InvalidParameter:
        raise InvalidParameter("t_end", "a duration in seconds, e.g. 100 or '2 min'", text) from None
    if not (math.isfinite(value) and value > 0):
        raise InvalidParameter("t_end", "a duration in seconds in (0, inf)", text)
    return value


def check_horizon(prepared: Prepared, t_end: float | None) -> float:
    """The horizon: ``t_end`` validated, or :func:`default_horizon`."""
    if t_end is None:
        return default_horizon(prepared)
    slow = prepared.linearization.slowest_time() or default_horizon(prepared) / HORIZON_TIME_CONSTANTS
    top = MAX_HORIZON_TIME_CONSTANTS * slow
    if isinstance(t_end, bool) or not isinstance(t_end, (int, float)) or not (0 < float(t_end) <= top):
        raise InvalidParameter("t_end", f"a number of seconds in (0, {top:.6g}] ({MAX_HORIZON_TIME_CONSTANTS:g} "
                                        "slowest time constants)", t_end)
    return float(t_end)


def _frequency_grid(prepared: Prepared, t_end: float, frequencies: tuple[float, float] | None) -> FloatArray:
    if frequencies is None:
        grid = default_frequencies(prepared, t_end)
    else:
        lo, hi = frequencies
        grid = np.geomspace(lo, hi, N_FREQUENCIES) if hi > lo else np.array([lo])
    switches = grid * t_end / math.pi
    if np.any(switches > MAX_SWITCHES):
        top = MAX_SWITCHES * math.pi / t_end
        if frequencies is not None:
            raise InvalidParameter("frequencies", f"at most {top:.6g} rad/s over a horizon of {t_end:.6g} s "
                                                  f"(MAX_SWITCHES = {MAX_SWITCHES} switches)",
                                   f"{frequencies[0]:g}..{frequencies[1]:g} rad/s")
        grid = grid[switches <= MAX_SWITCHES]
    return grid


def _check_scenarios(prepared: Prepared, scenarios: Sequence[str] | None) -> tuple[str, ...]:
    model = prepared.model
    if scenarios is None or not len(scenarios):
        return SCENARIOS if model.disturbances and prepared.undisturbed_only is None else ("none",)
    chosen = []
    for s in scenarios:
        if s not in SCENARIOS:
            raise InvalidParameter("scenarios", "one of " + ", ".join(SCENARIOS), s)
        if s != "none" and not model.disturbances:
            raise InvalidParameter("scenarios", "'none' for a model without [disturbances] (add one, name = bound)", s)
        if s != "none" and prepared.undisturbed_only is not None:
            raise InvalidParameter("scenarios", f"'none' for this loop ({prepared.undisturbed_only})", s)
        if s not in chosen:
            chosen.append(s)
    return tuple(c for c in SCENARIOS if c in chosen)


def _check_starts(model: "Model | RecastModel", starts: Any) -> FloatArray:
    arr = np.atleast_2d(np.asarray(starts, dtype=np.float64))
    if arr.ndim != 2 or arr.shape[1] != model.n or arr.shape[0] == 0:
        raise InvalidParameter("starts", f"an array of shape (k, {model.n}) (one row per start)", arr.shape)
    if arr.shape[0] > MAX_STARTS:
        raise InvalidParameter("x0", f"at most {MAX_STARTS} starts (MAX_STARTS)", arr.shape[0])
    if not np.all(np.isfinite(arr)):
        raise InvalidParameter("starts", "finite numbers", "a non-finite value")
    return arr


def _point(model: "Model | RecastModel", x: FloatArray) -> dict[str, float]:
    return {s: float(v) for s, v in zip(model.states, x)}


def _model_header(model: "Model | RecastModel") -> dict[str, Any]:
    return {"name": model.name, "file": model.source, "sha256": model.sha256, "overrides": dict(model.overrides)}


def _finite_or_none(x: float) -> float | None:
    return float(x) if math.isfinite(x) else None


# -- simulate -----------------------------------------------------------------------------------

@dataclass(frozen=True)
class ModelRun:
    """A scenarios run: its ``--json`` document and, when asked, its time series (an
    :class:`xarray.Dataset`, :mod:`lyapcheck.models.engines.series`)."""

    document: dict[str, Any]
    series: Any | None = None


def simulate_model(model: "Model | RecastModel", *, starts: Any | None = None, scenarios: Sequence[str] | None = None,
                   t_end: float | None = None, frequencies: tuple[float, float] | None = None,
                   rtol: float = DEFAULT_RTOL, plot: str | Path | None = None,
                   prepared: Prepared | None = None) -> dict[str, Any]:
    """The ``--json`` document of :func:`run_model` (the same arguments, without the series)."""
    return run_model(model, starts=starts, scenarios=scenarios, t_end=t_end, frequencies=frequencies, rtol=rtol,
                     plot=plot, prepared=prepared).document


def run_model(model: "Model | RecastModel", *, starts: Any | None = None, scenarios: Sequence[str] | None = None,
              t_end: float | None = None, frequencies: tuple[float, float] | None = None,
              rtol: float = DEFAULT_RTOL, plot: str | Path | None = None,
              prepared: Prepared | None = None, series: bool = False) -> ModelRun:
    """Simulate every start under every disturbance of the chosen scenarios, in one batched call.

    Parameters
    ----------
    model
        A loaded model (:func:`lyapcheck.models.language.modelfile.load_model`), or a loop with functions
        (:func:`lyapcheck.models.language.modelfile.load_any_model`: its true loop is integrated).
    starts
        ``(k, n)`` initial states in the declared coordinates, SI (:func:`parse_start`,
        :func:`grid_over_domain`); default :func:`default_starts`.
    scenarios
        Names among :data:`SCENARIOS`; default every one that applies (``none`` only without
        disturbances).
    t_end
        Horizon, s; default :func:`default_horizon`. The tail window is its last ``TAIL_FRACTION``.
    frequencies
        ``(lo, hi)`` angular frequencies of the square waves, rad/s (:func:`parse_frequencies`);
        default :func:`default_frequencies`.
    rtol
        The integrator's relative tolerance (absolute: ``rtol`` times the state scale).
    plot
        Also write the time histories (and for two states the phase plane) to this PNG.
    series
        Also sample the trajectories on a common time grid (:mod:`lyapcheck.models.engines.series`).

    Returns
    -------
    ModelRun
        ``document``: the ``--json`` document (SI): ``sup_abs_output_tail`` per output overall and
        per scenario, ``trajectories`` (one entry per start and disturbance: its tail sups,
        ``final_state``, ``converged``, ``diverged``, ``failure``), ``diverged`` (any row), and the
        settings; ``series``: the :class:`xarray.Dataset` with ``series``, else None.
    """
    begin = time.perf_counter()
    p = prepared if prepared is not None else prepare(model)
    chosen = _check_scenarios(p, scenarios)
    if starts is None:
        start_arr, how = default_starts(p)
    else:
        start_arr, how = _check_starts(model, starts), "given"
    horizon = check_horizon(p, t_end)
    grid = _frequency_grid(p, horizon, frequencies) if "square" in chosen else np.zeros(0)
    dists = scenario_disturbances(p, chosen, grid)
    scale = state_scale(p, start_arr)
    J = len(dists)
    rows_total = start_arr.shape[0] * J
    record = (sorted(set(np.linspace(0, rows_total - 1, min(rows_total, MAX_PLOTTED_ROWS)).round().astype(int).tolist()))
              if plot is not None else None)
    recorder = None
    if series:
        from lyapcheck.models.engines.series import SeriesRecorder, recorded_rows

        recorder = SeriesRecorder(recorded_rows(rows_total), rows_total, model.n, horizon)
    batch = _run(p, start_arr, dists, t_end=horizon, rtol=rtol, scale=scale, record=record, series=recorder)
    names = p.output_names
    per_scenario: dict[str, Any] = {}
    for sc in chosen:
        cols = [j for j, dd in enumerate(dists) if dd.kind == sc]
        rows = np.array([i * J + j for i in range(start_arr.shape[0]) for j in cols], dtype=np.intp)
        ok = rows[~batch.diverged[rows]]
        per_scenario[sc] = {
            "disturbances": [dists[j].describe(model) for j in cols],
            "trajectories": int(rows.size),
            "sup_abs_output_tail": {y: (float(np.max(batch.sup[ok, o])) if ok.size else None)
                                    for o, y in enumerate(names)},
            "diverged": int(np.sum(batch.diverged[rows])),
            "converged": int(np.sum(batch.converged[rows])),
        }
    ok_all = ~batch.diverged
    trajectories = []
    for r in range(batch.sup.shape[0]):
        i, j = divmod(r, J)
        trajectories.append({
            "start": i, "scenario": dists[j].kind, "disturbance": dists[j].describe(model),
            "sup_abs_output_tail": {y: _finite_or_none(batch.sup[r, o]) for o, y in enumerate(names)},
            "final_state": _point(model, batch.final[r]), "converged": bool(batch.converged[r]),
            "diverged": bool(batch.diverged[r]), "failure": batch.failure(r),
            "integrator_status": int(batch.result.status[r]), "steps_accepted": int(batch.result.n_accepted[r]),
        })
    doc: dict[str, Any] = {
        "mode": "scenarios",
        "model": _model_header(model),
        **p.document_keys,
        "states": list(model.states),
        "equilibrium": _point(model, p.equilibrium),
        "disturbance_bounds": {k: float(b) for k, b in model.disturbances.items()},
        "outputs": dict(p.output_text),
        "starts": [_point(model, x) for x in start_arr],
        "starts_from": how,
        "t_end_s": horizon,
        "tail_window_s": [batch.t_tail, horizon],
        "frequencies_rad_s": [float(w) for w in grid],
        "state_scale": _point(model, scale),
        "sup_abs_output_tail": {y: (float(np.max(batch.sup[ok_all, o])) if ok_all.any() else None)
                                for o, y in enumerate(names)},
        "scenarios": per_scenario,
        "diverged": bool(batch.diverged.any()),
        "n_diverged": int(batch.diverged.sum()),
        "n_converged": int(batch.converged.sum()),
        "n_trajectories": int(batch.sup.shape[0]),
        "trajectories": trajectories,
        "rtol": rtol,
        "integrator": INTEGRATOR_NAME,
    }
    if plot is not None:
        labels = [f"{dists[r % J].kind}" for r in record or []]
        plot_batch(p, batch, record or [], labels, str(plot),
                   title=f"lyapcheck simulate --model: {model.name}")
        doc["plot"] = str(plot)
    doc["wall_time_s"] = time.perf_counter() - begin
    dataset = None
    if recorder is not None:
        from lyapcheck.models.engines.series import model_dataset

        dataset = model_dataset(recorder, states=model.states, outputs=names, output_values=p.output_values,
                                starts_per_row=np.arange(rows_total) // J,
                                scenarios_per_row=[dists[r % J].kind for r in range(rows_total)],
                                converged=batch.converged, diverged=batch.diverged,
                                escape=(p.equilibrium, p.box(ESCAPE_FACTOR, scale)),
                                attrs={"model": model.name, "file": str(model.source), "t_end_s": horizon,
                                       "tail_window_start_s": batch.t_tail, "integrator": INTEGRATOR_NAME,
                                       "rtol": rtol})
    return ModelRun(document=doc, series=dataset)


# -- worst case ---------------------------------------------------------------------------------

@dataclass
class _Incumbent:
    """The best candidate of one (output, family) and its pattern-search steps."""

    sup: float
    disturbance: ModelDisturbance
    start: int
    steps: list[float] = field(default_factory=list)


def _stencil(inc: _Incumbent, bounds: FloatArray) -> list[ModelDisturbance]:
    """The pattern search's neighbours of an incumbent (inside the bounds)."""
    d = inc.disturbance
    out: list[ModelDisturbance] = []
    if d.kind == "constant":
        a = np.divide(np.array(d.values), bounds, out=np.zeros(len(bounds)), where=bounds > 0)
        for k, step in enumerate(inc.steps):
            for sign in (1.0, -1.0):
                b = a.copy()
                b[k] = float(np.clip(b[k] + sign * step, -1.0, 1.0))
                if b[k] != a[k]:
                    out.append(replace(d, values=tuple(float(v) for v in b * bounds)))
    elif d.kind == "square":
        dlog, dphase = inc.steps
        for factor in (math.exp(dlog), math.exp(-dlog)):
            out.append(replace(d, angular_frequency=d.angular_frequency * factor))
        for shift in (dphase, -dphase):
            out.append(replace(d, phase=math.fmod(d.phase + shift, 2 * math.pi) % (2 * math.pi)))
    return out


def _initial_steps(d: ModelDisturbance, m: int) -> list[float]:
    if d.kind == "constant":
        return [PATTERN_STEP_AMPLITUDE] * m
    if d.kind == "square":
        return [PATTERN_STEP_LOG_OMEGA, PATTERN_STEP_PHASE]
    return []


def search_worst_case(model: "Model | RecastModel", *, starts: Any | None = None, t_end: float | None = None,
                      frequencies: tuple[float, float] | None = None, budget_s: float = 20.0,
                      certified_bounds: Mapping[str, float] | None = None, plot: str | Path | None = None,
                      prepared: Prepared | None = None) -> dict[str, Any]:
    """Search, within ``budget_s`` seconds, the disturbance ``|d_k| <= b_k`` maximising each output's
    tail sup.

    Plan (each step one batched call, every start x candidate): screening of every constant sign
    pattern, the feedback of every output in both directions, and square waves (every sign
    pattern with ``s_1 = +1``, ``N_FREQUENCIES`` frequencies, the phases ``SEARCH_PHASES``) at
    ``SEARCH_RTOL``; then up to ``MAX_ROUNDS`` rounds of a pattern search around each output's best
    constant (amplitudes inside the box) and best square wave (log frequency and phase), steps
    halved where nothing improves, while the budget lasts; finally each output's best candidate
    again at ``DEFAULT_RTOL``, whose figures are the ones reported. The screening and the final
    call always run, so the budget is a target.

    Parameters
    ----------
    model
        A loaded model with ``[disturbances]``.
    starts
        ``(k, n)`` initial states; default the equilibrium alone (a forced response from rest is the
        cleanest witness of an ultimate bound).
    t_end, frequencies
        As in :func:`simulate_model`.
    budget_s
        Wall-time target, s, in (0, MAX_BUDGET_S].
    certified_bounds
        ``{output: bound}`` of a certificate (class ``sos_bound``): adds :func:`tightness`.
    plot
        Also draw each output's worst trajectory to this PNG.

    Returns
    -------
    dict
        ``sup_abs_output_tail`` (the worst found, per output), ``worst`` (per output: the figure,
        the ``disturbance`` and the ``start`` that produced it), ``per_family`` (search figures),
        ``diverged`` (a candidate diverged: no bound holds), and with ``certified_bounds``
        ``tightness`` and ``tightness_ratio``.
    """
    begin = time.perf_counter()
    if isinstance(budget_s, bool) or not isinstance(budget_s, (int, float)) or not 0 < budget_s <= MAX_BUDGET_S:
        raise InvalidParameter("budget_s", f"a number of seconds in (0, {MAX_BUDGET_S:g}]", budget_s)
    if not model.disturbances:
        raise InvalidParameter("worst_case", "used with a model that has [disturbances] (name = bound)",
                               model.source)
    p = prepared if prepared is not None else prepare(model)
    if p.undisturbed_only is not None:
        raise InvalidParameter("worst_case", f"left out for this loop ({p.undisturbed_only})", model.source)
    start_arr = p.equilibrium[None, :] if starts is None else _check_starts(model, starts)
    horizon = check_horizon(p, t_end)
    grid = _frequency_grid(p, horizon, frequencies)
    names = p.output_names
    m = p.bounds.size
    scale = state_scale(p, start_arr)
    S = start_arr.shape[0]
    candidates = scenario_disturbances(p, ("constant", "bang-bang", "square"), grid, SEARCH_PHASES)
    screen = _run(p, start_arr, candidates, t_end=horizon, rtol=SEARCH_RTOL, scale=scale)
    tried = screen.sup.shape[0]
    diverged_rows = int(screen.diverged.sum())
    family_best: dict[str, dict[str, float | None]] = {}
    incumbents: dict[tuple[int, str], _Incumbent] = {}
    best: dict[int, _Incumbent] = {}
    J = len(candidates)

    def consider(batch: _Batch, dists: Sequence[ModelDisturbance], rows_start: Sequence[int]) -> None:
        for r in range(batch.sup.shape[0]):
            if batch.diverged[r]:
                continue
            j = r % len(dists)
            start = rows_start[r // len(dists)]
            for o in range(len(names)):
                v = float(batch.sup[r, o])
                dd = dists[j]
                if o not in best or v > best[o].sup:
                    best[o] = _Incumbent(v, dd, start)
                key = (o, dd.kind)
                if dd.kind in ("constant", "square"):
                    inc = incumbents.get(key)
                    if inc is None or v > inc.sup:
                        steps = inc.steps if inc is not None else _initial_steps(dd, m)
                        incumbents[key] = _Incumbent(v, dd, start, list(steps))

    consider(screen, candidates, list(range(S)))
    examples = _divergences(model, screen)
    for family in ("constant", "bang-bang", "square"):
        cols = [j for j, dd in enumerate(candidates) if dd.kind == family]
        rows = np.array([i * J + j for i in range(S) for j in cols], dtype=np.intp)
        ok = rows[~screen.diverged[rows]]
        family_best[family] = {y: (float(np.max(screen.sup[ok, o])) if ok.size else None) for o, y in enumerate(names)}
    rounds: list[dict[str, Any]] = [{"round": 0, "candidates": tried, "seconds": screen.seconds,
                                     "best": {y: best[o].sup for o, y in enumerate(names) if o in best}}]
    final_guess = FINAL_COST_FACTOR * screen.seconds
    last_round = screen.seconds
    exhausted = False
    for k in range(1, MAX_ROUNDS + 1):
        elapsed = time.perf_counter() - begin
        if elapsed + last_round + final_guess > budget_s:
            exhausted = True
            break
        # one stencil per (output, family) incumbent, from its own start; steps halve on failure
        plan: list[tuple[tuple[int, str], ModelDisturbance]] = []
        for key, inc in incumbents.items():
            if max(inc.steps, default=0.0) < PATTERN_MIN_STEP:
                continue
            plan += [(key, dd) for dd in _stencil(inc, p.bounds)]
        if not plan:
            break
        by_start: dict[int, list[tuple[tuple[int, str], ModelDisturbance]]] = {}
        for key, dd in plan:
            by_start.setdefault(incumbents[key].start, []).append((key, dd))
        improved: set[tuple[int, str]] = set()
        spent = 0.0
        for start, items in by_start.items():
            unique = list(dict.fromkeys(dd for _, dd in items))
            batch = _run(p, start_arr[start:start + 1], unique, t_end=horizon, rtol=SEARCH_RTOL, scale=scale)
            spent += batch.seconds
            tried += len(unique)
            diverged_rows += int(batch.diverged.sum())
            examples += _divergences(model, batch)
            before = {key: inc.sup for key, inc in incumbents.items()}
            consider(batch, unique, [start])
            improved |= {key for key, inc in incumbents.items() if inc.sup > before.get(key, -math.inf)}
        for key, inc in incumbents.items():
            if key not in improved:
                inc.steps = [s * PATTERN_SHRINK for s in inc.steps]
        last_round = spent
        rounds.append({"round": k, "candidates": len(plan), "seconds": spent,
                       "best": {y: best[o].sup for o, y in enumerate(names) if o in best}})
    # final: each output's best at the reporting tolerance (figures reproducible from the description),
    # one call per start for the distinct disturbances (outputs often share their worst one)
    worst: dict[str, Any] = {}
    final_batches: list[tuple[_Batch, int, int]] = []
    for start in sorted({inc.start for inc in best.values()}):
        outs = [o for o, inc in best.items() if inc.start == start]
        unique = list(dict.fromkeys(best[o].disturbance for o in outs))
        batch = _run(p, start_arr[start:start + 1], unique, t_end=horizon, rtol=DEFAULT_RTOL, scale=scale,
                     record=list(range(len(unique))) if plot is not None else None)
        tried += len(unique)
        diverged_rows += int(batch.diverged.sum())
        examples += _divergences(model, batch)
        for o in outs:
            r = unique.index(best[o].disturbance)
            final_batches.append((batch, r, o))
            worst[names[o]] = {
                "sup_abs_output_tail": _finite_or_none(float(batch.sup[r, o])),
                "disturbance": best[o].disturbance.describe(model), "start": _point(model, start_arr[start]),
                "search_sup_abs_output_tail": best[o].sup, "rtol": DEFAULT_RTOL,
                "all_outputs": {z: _finite_or_none(float(batch.sup[r, q])) for q, z in enumerate(names)}}
    sups = {y: worst[y]["sup_abs_output_tail"] if y in worst else None for y in names}
    doc: dict[str, Any] = {
        "mode": "worst_case",
        "model": _model_header(model),
        **p.document_keys,
        "states": list(model.states),
        "equilibrium": _point(model, p.equilibrium),
        "disturbance_bounds": {k: float(b) for k, b in model.disturbances.items()},
        "outputs": dict(p.output_text),
        "starts": [_point(model, x) for x in start_arr],
        "sup_abs_output_tail": sups,
        "worst": worst,
        "per_family": family_best,
        "diverged": diverged_rows > 0,
        "n_diverged": diverged_rows,
        "divergence_examples": examples[:MAX_EXAMPLES],
        "candidates_tried": tried,
        "rounds": rounds,
        "t_end_s": horizon,
        "tail_window_s": [(1 - TAIL_FRACTION) * horizon, horizon],
        "frequencies_rad_s": [float(w) for w in grid],
        "search_rtol": SEARCH_RTOL,
        "rtol": DEFAULT_RTOL,
        "budget_s": float(budget_s),
        "budget_exhausted": exhausted,
        "note": "a search, not a proof: a lower estimate of the worst case; the certified bound is the proof",
        "integrator": INTEGRATOR_NAME,
    }
    if certified_bounds is not None:
        found = {y: v for y, v in sups.items() if v is not None}
        tight = tightness(certified_bounds, found)
        doc["tightness"] = tight
        doc["tightness_ratio"] = {y: t["tightness_ratio"] for y, t in tight.items()}
        doc["soundness_violation"] = any(t["soundness_violation"] for t in tight.values())
    if plot is not None and final_batches:
        _plot_worst(p, final_batches, str(plot))
        doc["plot"] = str(plot)
    doc["wall_time_s"] = time.perf_counter() - begin
    return doc


def _divergences(model: "Model | RecastModel", batch: _Batch) -> list[dict[str, Any]]:
    """The first MAX_EXAMPLES diverged rows of a batch: disturbance, start and why."""
    J = len(batch.disturbances)
    return [{"disturbance": batch.disturbances[r % J].describe(model), "start": _point(model, batch.starts[r // J]),
             "failure": batch.failure(r)} for r in np.flatnonzero(batch.diverged)[:MAX_EXAMPLES]]


def tightness(certified_bounds: Mapping[str, float], worst: Mapping[str, float]) -> dict[str, dict[str, Any]]:
    """Per output, ``tightness_ratio = certified bound / worst simulated tail sup``.

    A ratio below 1 means a simulated trajectory exceeded a certified bound: a soundness
    violation, flagged when the excess is beyond the simulator's accuracy contract
    (:data:`lyapcheck.tolerances.SIM_REL_TOL`, relative). Outputs missing from either side are
    left out; an output simulated at 0 gets ratio None (nothing to compare).

    Returns
    -------
    dict
        ``{output: {"certified_bound", "worst_simulated", "tightness_ratio", "soundness_violation"}}``.
    """
    from lyapcheck.models.engines.crosscheck import bound_exceeded

    out: dict[str, dict[str, Any]] = {}
    for name, bound in certified_bounds.items():
        if name not in worst:
            continue
        b, w = float(bound), float(worst[name])
        ratio = b / w if w > 0 else None
        out[name] = {"certified_bound": b, "worst_simulated": w, "tightness_ratio": ratio,
                     "soundness_violation": bound_exceeded(b, w, SIM_REL_TOL)}
    return out


def certified_bounds_of(model: "Model | RecastModel", path: str | Path) -> dict[str, float]:
    """The certified ``sos_bound`` figures of a model certificate file for this model (the same
    text and parameters), after re-checking the certificate exactly (no solver), as bounds on
    ``|y|`` (what a simulation measures): ``bound + |y_eq|`` for a bound on ``|y - y_eq|``."""
    from lyapcheck.models.surfaces.certificate import is_model_document, read_json, verify_document

    try:
        doc = read_json(path)
    except Exception as exc:  # noqa: BLE001 - any unreadable file is the user's input to fix
        raise InvalidParameter("certificate", "a readable model certificate JSON (one written by certify)",
                               f"{path} ({exc})") from None
    if not is_model_document(doc):
        raise InvalidParameter("certificate", "a model certificate (one written by certify for a model file)",
                               str(path))
    if doc.get("model", {}).get("sha256") != model.sha256:
        raise InvalidParameter("certificate", f"a certificate of this model file ({model.source}, same text)",
                               str(path))
    same = (doc.get("parameters") == {k: str(v) for k, v in model.parameters.items()}
            and doc.get("disturbances") == {k: str(v) for k, v in model.disturbances.items()})
    if not same:
        raise InvalidParameter("certificate", "a certificate for the same parameters and disturbance bounds "
                                              "(the same settings)", str(path))
    bound = doc.get("conditions", {}).get("sos_bound", {})
    if not isinstance(bound, dict) or bound.get("status") != "certified" or not isinstance(bound.get("bounds"), dict):
        raise InvalidParameter("certificate", "a certificate whose class sos_bound is certified", str(path))
    rows = verify_document(doc)
    failed = [why for name, ok, why in rows if not ok and name in ("model", "parameters", "denominators", "scaling",
                                                                    "recasting", "disturbances", "sos_bound")]
    if failed:
        raise InvalidParameter("certificate", "a certificate that passes its exact re-check (lyapcheck verify)",
                               f"{path}: {failed[0]}")
    # a bound is on |y - y_eq| (bounds_reference); the simulation measures |y|: compare with the bound
    # on |y| it implies, |y| <= bound + |y_eq| (else a loop resting at y_eq != 0 would raise a false alarm)
    given = bound.get("bounds_reference")
    reference: dict[str, Any] = given if isinstance(given, dict) else {}
    return {str(k): float(v) + abs(float(reference.get(k, 0.0))) for k, v in bound["bounds"].items()}


# -- plots --------------------------------------------------------------------------------------

def plot_batch(prepared: Prepared, batch: _Batch, rows: Sequence[int], labels: Sequence[str], path: str, *,
               title: str) -> None:
    """Time histories of every output for the recorded rows (colour per label), the tail window
    shaded; for two states also the phase plane."""
    from lyapcheck.models.surfaces.plotting import finish_figure, history_panel, new_figure, phase_plane

    names = prepared.output_names
    n = prepared.model.n
    fig, axes = new_figure(len(names) + (1 if n == 2 else 0), 3.0)
    colours = {lab: f"C{i % 10}" for i, lab in enumerate(dict.fromkeys(labels))}
    curves = [(r, lab, *_clipped(prepared, batch, r)) for r, lab in zip(rows, labels)]
    for o, y in enumerate(names):
        ax = axes[o, 0]
        seen: set[str] = set()
        for r, lab, t, xs in curves:
            vals = prepared.output(y, xs)
            ax.plot(t, vals, color=colours[lab], lw=0.9, alpha=0.8, label=None if lab in seen else lab,
                    ls="--" if batch.diverged[r] else "-")
            seen.add(lab)
        text = prepared.output_text.get(y, y)
        history_panel(ax, (batch.t_tail, batch.t_end), "t (s)", y if text == y else f"{y} = {text}")
        ax.legend(loc="upper right", fontsize=7)
    if n == 2:
        ax = axes[-1, 0]
        for r, lab, t, xs in curves:
            ax.plot(xs[:, 0], xs[:, 1], color=colours[lab], lw=0.8, alpha=0.8, ls="--" if batch.diverged[r] else "-")
            ax.plot(xs[0, 0], xs[0, 1], ".", color=colours[lab], ms=3)
        model = prepared.model
        if model.domain:
            (a0, a1), (b0, b1) = ([float(v) for v in model.domain[s]] for s in model.states)
            ax.set_xlim(a0 - 0.1 * (a1 - a0), a1 + 0.1 * (a1 - a0))
            ax.set_ylim(b0 - 0.1 * (b1 - b0), b1 + 0.1 * (b1 - b0))
        phase_plane(ax, prepared.equilibrium, model.states, label="equilibrium",
                    title="phase plane (dots: starts; dashed: diverged)")
    finish_figure(fig, title + f" (tail window shaded: the last {TAIL_FRACTION:.0%})", path)


def _clipped(prepared: Prepared, batch: _Batch, row: int, samples: int = PLOT_SAMPLES) -> tuple[FloatArray, FloatArray]:
    """A recorded row resampled, NaN where it is farther than PLOT_CLIP state scales from the
    equilibrium (a diverging row would flatten every other curve)."""
    box = prepared.box(PLOT_CLIP, batch.scale)
    t, xs = batch.observer.trajectory(row, samples, prepared.equilibrium, box)
    far = np.any(np.abs(xs - prepared.equilibrium) > box, axis=1)
    xs = xs.copy()
    xs[far] = np.nan
    return t, xs


def _plot_worst(prepared: Prepared, batches: Sequence[tuple[_Batch, int, int]], path: str) -> None:
    """Each output's worst trajectory: one figure, one panel per output (and the phase plane)."""
    from lyapcheck.models.surfaces.plotting import finish_figure, history_panel, new_figure, phase_plane

    names = prepared.output_names
    n = prepared.model.n
    fig, axes = new_figure(len(batches) + (1 if n == 2 else 0), 3.0)
    for i, (batch, row, o) in enumerate(batches):
        t, xs = _clipped(prepared, batch, row, PLOT_SAMPLES)
        y = names[o]
        ax = axes[i, 0]
        ax.plot(t, prepared.output(y, xs), color=f"C{i % 10}", lw=1.0)
        sup = batch.sup[row, o]
        if math.isfinite(sup):
            for s in (sup, -sup):
                ax.axhline(s, color="k", ls=":", lw=0.8)
        desc = batch.disturbances[row].describe(prepared.model)
        ax.set_title(f"worst {y}: tail sup {sup:.6g} ({desc['kind']})", fontsize=9)
        history_panel(ax, (batch.t_tail, batch.t_end), "t (s)", y)
        if n == 2:
            axes[-1, 0].plot(xs[:, 0], xs[:, 1], color=f"C{i % 10}", lw=0.8, label=f"worst {y}")
    if n == 2:
        phase_plane(axes[-1, 0], prepared.equilibrium, prepared.model.states)
    finish_figure(fig, f"lyapcheck simulate --model --worst-case: {prepared.model.name}", path)


__all__ = ["SCENARIOS", "ModelDisturbance", "Prepared", "prepare", "prepare_polynomial", "prepare_true_loop",
           "TrueOutputGain", "crosscheck_horizon", "simulate_model", "run_model", "ModelRun",
           "search_worst_case",
           "tightness", "certified_bounds_of", "parse_start", "parse_frequencies", "parse_horizon", "grid_over_domain",
           "default_starts", "default_horizon", "default_frequencies", "state_scale", "scenario_disturbances"]
