"""Worst-case disturbance search: the ``|d_mu| <= d*`` that maximises the tail sup of ``|eps|``.

Certified ultimate bounds (``ultimate_bound``, ``sos_bound``) say ``limsup |eps| <= b`` for every
disturbance with ``|d_mu| <= d*``. To know how tight ``b`` is, it must be compared with the worst
thing that can really happen, not with the constant disturbance of the presets. This module
searches for that worst case on the full closed loop (saturated ODS, :mod:`.model`), measuring
``sup |eps|`` over the scenario's tail window with the batched integrator, from the scenario's
initial state and from the origin (``eps = 0``, ``s = 0``: the ultimate bound is about steady
forcing, and a forced response from rest is the cleanest witness of it).

Families of candidates (each a disturbance kind of :mod:`.disturbances`, so every result can be
re-simulated from its JSON description):

``constant``          ``d*`` at ``CONSTANT_ANGLES`` angles (the presets' kind);
``push_eps``          ``d* sat(eps/layer) e_perp``: pushes ``eps`` outward (the ``d`` maximising
                      ``d/dt eps^2``), ties at ``eps = 0`` broken towards ``+``;
``storage_gradient``  ``d* sat(sigma/layer) e_perp`` with ``sigma`` the gradient of the certified
                      polynomial storage function ``V`` of ``sos_bound`` along ``eps`` (pushes ``V``
                      up as hard as the bound allows; only when a certificate is given);
``sinusoid``          ``d* sin(omega t + phi) e_perp``;
``square_wave``       ``d* sign(sin(omega t + phi)) e_perp``;
``random_bang_bang``  ``+-d* e_perp`` with random dwell times (``numpy.random.default_rng(seed)``);
``costate``           Pontryagin's condition for maximising ``+-eps(T*)`` (``T*`` the time of the
                      tail's peak): ``d = d* sign(e_perp . lambda_p)`` with ``lambda`` the adjoint
                      of the closed loop linearised along the trajectory (forward-backward sweeps
                      started from the best candidates, a bang-bang with the zero crossings of the
                      switching function as switching times);
``optimised``         a batched pattern search over ``(log omega, phi)`` of the best square wave.

The frequencies scanned are placed around the imaginary parts of the eigenvalues of the loop
linearised at the origin and at the equilibrium under a constant ``d*`` across the path (the
lightly damped pair of the error dynamics moves from about ``0.86`` to ``0.31`` rad/s between
the two at the paper's gains, and the nonlinear resonance lies between).

Cost and determinism. The integrator's cost is per call (per step of the slowest row), hardly
per trajectory, so the search is a fixed plan of a few batched calls ("rounds"):

1. screening: every family; the constant and feedback laws from both initial states, the
   periodic and random ones from the origin (:data:`BOTH_STARTS_FAMILIES`);
2. up to :data:`MAX_ROUNDS` refinement rounds, each advancing every costate sweep by one
   iteration and the pattern search by one stencil (the first also runs each family's best
   from the other initial state);
3. final: the best candidate of each initial state, and the last costate iterates, at the
   scenario's own ``rtol`` with the runner's defaults.

Rounds 1-2 run at :data:`SEARCH_RTOL`; each :class:`Finding` states the ``rtol`` it was measured
with, and the reported worst case (``sup_abs_eps_tail_m``, ``per_start``) is always a figure of
the final call, which :func:`simulate_disturbance` reproduces from the JSON description. The
plan is fixed and the randomness seeded, so the result does not depend on the machine unless
``budget_s`` cuts refinement rounds off (reported as ``budget_exhausted``); the screening and
the final call always run, so the budget is a target, not a hard limit.
"""

from __future__ import annotations

import json
import logging
import math
import time
from dataclasses import dataclass, field
from fractions import Fraction
from typing import Any, Final, Mapping, Sequence

import numpy as np
import numpy.typing as npt

from lyapcheck.errors import InvalidParameter
from lyapcheck.tolerances import SIM_MAX_STEPS
from lyapcheck.paper.params import Problem
from lyapcheck.paper.simulation.disturbances import (
    ADVERSARIAL_LAYER_FRACTION, Constant, Disturbance, Feedback, NoDisturbance, Sinusoid, SquareWave, BangBang,
    from_description, stack_rows,
)
from lyapcheck.integrator import STATUS_OK
from lyapcheck.paper.simulation.metrics import Trajectory
from lyapcheck.paper.simulation.model import N_STATE, PX, PZ, S, ClosedLoop, LoopParams
from lyapcheck.paper.simulation.runner import SimulationResult, simulate
from lyapcheck.paper.simulation.scenarios import Scenario

logger = logging.getLogger(__name__)

FloatArray = npt.NDArray[np.float64]
IntArray = npt.NDArray[np.intp]

#: integrator tolerance of the search rounds (the reported figures use the scenario's rtol): at
#: the paper's gains the tail sups agree with rtol = 1e-8 to 3e-4 (mostly the sampling of the
#: sup), ample to rank candidates, at 0.4 times the steps
SEARCH_RTOL: Final = 1e-5
#: a refinement round is guessed to cost this fraction of the screening round until one has run,
#: and the final re-simulation at the scenario's rtol this many refinement rounds (measured
#: 1.2-1.7 at the paper's gains: more steps at rtol 1e-8, but fewer rows)
ROUND_COST_GUESS: Final = 0.5
FINAL_COST_FACTOR: Final = 2.0
#: constant disturbances: this many directions, evenly spaced, including +-e_perp
CONSTANT_ANGLES: Final = 24
#: periodic families: frequencies (geometric grid) and phases (evenly spaced) of the screening;
#: the phase matters through the tail window only (periods reach 5x the 10 s tail), and the
#: square wave, whose fundamental is 4/pi times the sine's, gets the finer phase grid
N_FREQUENCIES: Final = 12
N_PHASES: Final = 4
N_PHASES_SINE: Final = 2
#: the frequency grid spans [LOW * smallest, HIGH * largest] resonance of the linearisations
FREQUENCY_SPAN: Final = (0.35, 1.6)
#: random bang-bang candidates per initial state
N_RANDOM: Final = 16
#: a periodic or random switching disturbance is a candidate only if it switches at most this many
#: times over the horizon: each switch restarts the integrator, whose step budget per trajectory
#: is lyapcheck.tolerances.SIM_MAX_STEPS (at extreme gains the loop's resonances are so fast that
#: a switching table would not even fit in memory)
MAX_SWITCHES: Final = SIM_MAX_STEPS // 4
#: rounds after the screening (each one batched call)
MAX_ROUNDS: Final = 3
#: costate sweeps run in parallel, started from the best candidates of these families
COSTATE_SEEDS: Final = ("square_wave", "sinusoid", "constant", "random_bang_bang")
#: sampling interval of the recorded trajectories the adjoint is integrated on, s
COSTATE_DT: Final = 0.02
#: pattern search: initial steps in log(omega) and in phase (rad), shrink factor on failure
PATTERN_STEP: Final = (0.08, 0.6)
PATTERN_SHRINK: Final = 0.5
#: relative step of the central differences of the loop's Jacobian (times max(Delta, |state|))
JACOBIAN_STEP: Final = 1e-6

#: families screened from both initial states (the others from the origin, then their best from
#: the preset's state too): the constant and feedback laws, whose response depends on the start
BOTH_STARTS_FAMILIES: Final = ("constant", "push_eps", "storage_gradient")
FAMILIES: Final = ("constant", "push_eps", "storage_gradient", "sinusoid", "square_wave", "random_bang_bang",
                   "costate", "optimised")
START_PRESET, START_ORIGIN = "preset", "origin"


@dataclass(frozen=True)
class Finding:
    """The best candidate of one family (or one initial state)."""

    sup_abs_eps_tail_m: float
    disturbance: dict[str, Any]
    start: str
    #: integrator tolerance the figure was measured with
    rtol: float

    def to_json(self) -> dict[str, Any]:
        return {"sup_abs_eps_tail_m": self.sup_abs_eps_tail_m, "initial_state": self.start, "rtol": self.rtol,
                "disturbance": self.disturbance}


@dataclass(frozen=True)
class WorstCaseResult:
    """Outcome of :func:`search_worst_case` (SI; every figure measured at the scenario's rtol).

    Attributes
    ----------
    sup_abs_eps_tail_m
        The largest tail sup of ``|eps|`` found, m.
    disturbance
        JSON description of the disturbance that produced it (``kind`` + parameters; rebuild
        with :func:`lyapcheck.paper.simulation.disturbances.from_description`), with its ``family``.
    start
        ``"preset"`` (the scenario's initial state) or ``"origin"``.
    initial_states
        ``{name: {"position_m": [x, z], "s_m": s}}`` of both initial states.
    per_family
        Best finding per family (``None`` with a reason in ``skipped`` when not run).
    per_start
        Best finding per initial state.
    candidates_tried
        Number of simulated candidate trajectories (every round, both initial states).
    """

    sup_abs_eps_tail_m: float
    disturbance: dict[str, Any]
    start: str
    initial_states: dict[str, dict[str, Any]]
    per_family: dict[str, Finding | None]
    per_start: dict[str, Finding]
    candidates_tried: int
    d_max_m_s: float
    horizon_s: float
    tail_s: float
    rtol: float
    search_rtol: float
    wall_time_s: float
    budget_s: float
    budget_exhausted: bool
    seed: int
    skipped: dict[str, str] = field(default_factory=dict)
    rounds: list[dict[str, Any]] = field(default_factory=list)
    resonances_rad_s: dict[str, list[float]] = field(default_factory=dict)

    @property
    def constant_sup_abs_eps_tail_m(self) -> float:
        """The best constant disturbance's figure (what the presets measure)."""
        best = self.per_family.get("constant")
        return best.sup_abs_eps_tail_m if best is not None else math.nan

    def build_disturbance(self) -> Disturbance:
        """The worst disturbance, rebuilt from its description."""
        return from_description(self.disturbance)

    def tightness_ratio(self, certified_bound_m: float) -> float:
        """``certified / worst simulated`` (>= 1 unless the bound is violated)."""
        return certified_bound_m / self.sup_abs_eps_tail_m if self.sup_abs_eps_tail_m > 0 else math.inf

    def to_json(self) -> dict[str, Any]:
        return {
            "sup_abs_eps_tail_m": self.sup_abs_eps_tail_m,
            "disturbance": self.disturbance,
            "initial_state": self.start,
            "initial_states": self.initial_states,
            "constant_sup_abs_eps_tail_m": self.constant_sup_abs_eps_tail_m,
            "per_family": {k: (v.to_json() if v is not None else None) for k, v in self.per_family.items()},
            "per_start": {k: v.to_json() for k, v in self.per_start.items()},
            "skipped": dict(self.skipped),
            "candidates_tried": self.candidates_tried,
            "d_max_m_s": self.d_max_m_s,
            "horizon_s": self.horizon_s,
            "tail_s": self.tail_s,
            "rtol": self.rtol,
            "search_rtol": self.search_rtol,
            "resonances_rad_s": self.resonances_rad_s,
            "rounds": self.rounds,
            "wall_time_s": self.wall_time_s,
            "budget_s": self.budget_s,
            "budget_exhausted": self.budget_exhausted,
            "seed": self.seed,
        }


def _a(x: float | FloatArray) -> FloatArray:
    return np.asarray(x, dtype=np.float64)


# -- setting ------------------------------------------------------------------------------------
@dataclass(frozen=True)
class _Setting:
    scenario: Scenario
    params: LoopParams  # one row
    d_star: float
    theta_r: float
    delta: float
    starts: dict[str, tuple[tuple[float, float], float]]

    @property
    def across(self) -> FloatArray:
        return np.array([-math.sin(self.theta_r), math.cos(self.theta_r)]) + 0.0  # + 0.0: no "-0.0" in JSON

    @property
    def t_tail(self) -> float:
        return self.scenario.horizon - self.scenario.tail


def _setting(target: Problem | Scenario) -> _Setting:
    scenario = target if isinstance(target, Scenario) else Scenario(name="worst-case", problem=target)
    problem = scenario.problem
    if problem.actuation.omega_so is None:
        raise InvalidParameter("omega_so", "given ([actuation] omega_so) for a closed-loop simulation", None)
    d_star = float(problem.disturbance_bound())
    params = LoopParams.from_problem(problem, controller=scenario.controller, d_hat=scenario.d_hat)
    starts = {START_PRESET: ((float(scenario.p0[0]), float(scenario.p0[1])), float(scenario.s0)),
              START_ORIGIN: ((0.0, 0.0), 0.0)}
    return _Setting(scenario, params, d_star, float(problem.theta_r), float(problem.gains.delta_los), starts)


@dataclass(frozen=True)
class _Candidate:
    family: str
    start: str
    disturbance: Disturbance  # one row


@dataclass
class _Evaluated:
    candidate: _Candidate
    sup: float
    rtol: float
    trajectory: Trajectory | None = None


def _run(setting: _Setting, cands: Sequence[_Candidate], *, rtol: float, record_rows: Sequence[int] = ()
         ) -> list[_Evaluated]:
    """One batched simulation of the candidates (runner defaults, the scenario's horizon/tail);
    the rows ``record_rows`` keep their trajectory (sampled every :data:`COSTATE_DT`)."""
    return _simulate(setting, cands, rtol=rtol, record_rows=record_rows)[0]


def _simulate(setting: _Setting, cands: Sequence[_Candidate], *, rtol: float, record_rows: Sequence[int] = ()
              ) -> tuple[list[_Evaluated], SimulationResult]:
    sc = setting.scenario
    n = len(cands)
    params = setting.params.take(np.zeros(n, dtype=np.intp))
    p0 = np.array([setting.starts[c.start][0] for c in cands])
    s0 = np.array([setting.starts[c.start][1] for c in cands])
    dist = stack_rows([c.disturbance for c in cands])
    res = simulate(params, p0=p0, s0=s0, disturbance=dist, horizon=sc.horizon, tail=sc.tail,
                   band=sc.band, form=sc.form, rtol=rtol, record=list(record_rows) or None, record_dt=COSTATE_DT)
    m = res.measurements
    recorded = dict(zip(record_rows, res.trajectories or []))
    out = []
    for i, c in enumerate(cands):
        # a failed integration measured nothing: it cannot be a witness
        ok = m.status[i] == STATUS_OK and np.isfinite(m.sup_abs_eps_tail_m[i])
        out.append(_Evaluated(c, float(m.sup_abs_eps_tail_m[i]) if ok else -math.inf, rtol, recorded.get(i)))
    return out, res


# -- linearisation: resonances and the adjoint ------------------------------------------------------
def _loop_jacobian(setting: _Setting, y: FloatArray) -> FloatArray:
    """``d f / d (p_x, p_z, s)`` of the closed loop without disturbance at states ``y`` (K, N_STATE),
    by central differences of :meth:`ClosedLoop.rhs` (the loop's own formulas, saturation included)."""
    k = y.shape[0]
    loop = ClosedLoop(setting.params.take(np.zeros(k, dtype=np.intp)), NoDisturbance(), np.full(k, np.inf),
                      setting.scenario.form)
    t = np.zeros(k)
    cols = (PX, PZ, S)
    J = np.empty((k, 3, 3))
    for j, c in enumerate(cols):
        h = JACOBIAN_STEP * np.maximum(setting.delta, np.abs(y[:, c]))
        yp, ym = y.copy(), y.copy()
        yp[:, c] += h
        ym[:, c] -= h
        diff = loop.rhs(t, yp, t).dy[:, list(cols)] - loop.rhs(t, ym, t).dy[:, list(cols)]
        J[:, :, j] = diff / (2 * h)[:, None]
    return J


def _error_rates(setting: _Setting, x: FloatArray, d_perp: float) -> FloatArray:
    """``(eps_dot, s_dot)`` of the closed loop at ``(eps, s)`` rows ``x`` under a constant ``d_perp``."""
    k = x.shape[0]
    across = setting.across
    loop = ClosedLoop(setting.params.take(np.zeros(k, dtype=np.intp)), Constant(d_perp * across),
                      np.full(k, np.inf), setting.scenario.form)
    y = np.zeros((k, N_STATE))
    y[:, PX:PZ + 1] = x[:, :1] * across
    y[:, S] = x[:, 1]
    t = np.zeros(k)
    dy = loop.rhs(t, y, t).dy
    return np.stack([dy[:, PX:PZ + 1] @ across, dy[:, S] * setting.params.integral[0]], axis=1)


def _resonances(setting: _Setting) -> dict[str, list[float]]:
    """Eigenvalues' imaginary parts (rad/s) of the loop linearised at rest and at the equilibrium
    under a constant ``d*`` across the path (``|eigenvalue|`` for a real pair)."""
    from scipy.optimize import root

    out: dict[str, list[float]] = {}
    scale = np.array([setting.delta, 1.0])
    for name, d in (("origin", 0.0), ("constant_d_max", setting.d_star)):
        x = np.zeros(2)
        if d > 0:
            guess = np.array([d / float(setting.params.e11[0] * setting.params.alpha_d[0]), 0.0])
            sol = root(lambda z: _error_rates(setting, (z * scale)[None], d)[0] / scale, guess / scale, tol=1e-13)
            if not sol.success:
                continue
            x = sol.x * scale
        h = JACOBIAN_STEP * np.maximum(scale, np.abs(x))
        J = np.stack([(_error_rates(setting, (x + h[j] * e)[None], d)[0] - _error_rates(setting, (x - h[j] * e)[None], d)[0])
                      / (2 * h[j]) for j, e in enumerate(np.eye(2))], axis=1)
        if setting.params.integral[0] == 0:
            J = J[:1, :1]
        eig = np.linalg.eigvals(J)
        freq = [abs(float(v.imag)) if abs(v.imag) > 1e-12 else abs(float(v.real)) for v in eig]
        out[name] = sorted(set(round(f, 12) for f in freq if f > 0))
    return out


def _costate_bang_bang(setting: _Setting, traj: Trajectory) -> BangBang | None:
    """Pontryagin's bang-bang for maximising ``sign * eps(T*)``, ``T*`` the tail peak of ``traj``.

    The adjoint ``lambda' = -J(t)^T lambda`` of the loop linearised along ``traj`` is integrated
    backwards from ``lambda(T*) = sign * (e_perp, 0)`` (Heun's method on the recorded grid);
    ``d = d* sign(e_perp . lambda_p)`` maximises the Hamiltonian's ``lambda . d`` over the disc,
    and its switching times are the zero crossings of ``e_perp . lambda_p`` (linear
    interpolation). After ``T*`` the last sign is kept.
    """
    t = traj.t
    tail = np.flatnonzero(t >= setting.t_tail)
    if tail.size == 0:
        return None
    k = int(tail[np.argmax(np.abs(traj.eps[tail]))])
    sign = 1.0 if traj.eps[k] >= 0 else -1.0
    y = np.zeros((k + 1, N_STATE))
    y[:, PX:PZ + 1] = traj.p[:k + 1]
    y[:, S] = traj.s[:k + 1]
    J = _loop_jacobian(setting, y)
    lam = np.zeros((k + 1, 3))
    lam[k, :2] = sign * setting.across
    for i in range(k, 0, -1):
        h = t[i] - t[i - 1]
        f1 = J[i].T @ lam[i]
        f2 = J[i - 1].T @ (lam[i] + h * f1)
        lam[i - 1] = lam[i] + 0.5 * h * (f1 + f2)
    g = lam[:, :2] @ setting.across
    sg = np.where(g >= 0, 1.0, -1.0)
    idx = np.flatnonzero(sg[1:] != sg[:-1])
    with np.errstate(divide="ignore", invalid="ignore"):
        frac = np.where(g[idx + 1] != g[idx], g[idx] / (g[idx] - g[idx + 1]), 0.5)
    times = t[idx] + np.clip(frac, 0.0, 1.0) * (t[idx + 1] - t[idx])
    times = np.unique(times[times > 0])
    if times.size == 0:
        times = np.array([np.inf])
    return BangBang(_a(setting.d_star), setting.across, times, _a(sg[0]), note="costate (Pontryagin) sweep")


# -- candidate generators -------------------------------------------------------------------------
def _frequency_grid(resonances: Mapping[str, list[float]]) -> FloatArray:
    freqs = [f for fs in resonances.values() for f in fs]
    lo, hi = (min(freqs), max(freqs)) if freqs else (0.1, 1.0)
    return np.geomspace(FREQUENCY_SPAN[0] * lo, FREQUENCY_SPAN[1] * hi, N_FREQUENCIES)


def _feedback(setting: _Setting, exponents: npt.ArrayLike, coefficients: FloatArray, note: str) -> Feedback:
    return Feedback(_a(setting.d_star), coefficients, np.asarray(exponents, dtype=np.intp), _a(setting.delta),
                    _a(ADVERSARIAL_LAYER_FRACTION * setting.delta), _a(setting.theta_r), note=note)


def storage_switching(storage: Mapping[str, Any], sigma0: Fraction) -> tuple[IntArray, FloatArray]:
    """Exponents and coefficients, in ``(eps/Delta, s/Delta)``, of ``dV/d eps`` (up to a positive
    factor) for the ``sos_bound`` certificate ``storage``.

    ``V = z^T Q_V z`` is a polynomial in ``y = (eps + sigma0 s)/Delta`` and ``r~ = sigma0 s/(Delta beta)``
    (:mod:`lyapcheck.paper.conditions.sos_bound`); ``eps`` enters ``y`` only, so ``dV/d eps = (1/Delta)
    dV/dy``. The polynomial is composed exactly and normalised so that the coefficient of ``eps``
    is ``+-1`` (the switching function is then ``eps`` near the origin, in metres).
    """
    from lyapcheck import exact
    from lyapcheck.paper import poly
    from lyapcheck.paper.conditions.sos_bound import Z_V

    missing = [key for key in ("Q_V", "beta") if key not in storage]
    if missing:
        raise InvalidParameter("storage", f"an sos_bound certificate with '{missing[0]}'", sorted(storage))
    V = poly.gram_form(Z_V, exact.from_json(storage["Q_V"]))
    beta = Fraction(storage["beta"])
    dV = poly.deriv(V, 0)
    subs: list[poly.Poly] = [{(1, 0): Fraction(1), (0, 1): sigma0}, {(0, 1): sigma0 / beta}]
    composed: poly.Poly = {}
    for mono, c in dV.items():
        term: poly.Poly = {(0, 0): c}
        for var, power in enumerate(mono):
            for _ in range(power):
                term = poly.mul(term, subs[var])
        composed = poly.add(composed, term)
    composed = {m: c for m, c in composed.items() if c != 0}
    if not composed:
        raise InvalidParameter("storage", "a certificate whose V depends on eps", "dV/d eps = 0")
    norm = abs(composed.get((1, 0), Fraction(0))) or max(abs(c) for c in composed.values())
    exps = sorted(composed)
    return np.array(exps, dtype=np.intp), np.array([float(composed[m] / norm) for m in exps])


def _screening(setting: _Setting, freqs: FloatArray, storage: Mapping[str, Any] | None, seed: int,
               skipped: dict[str, str]) -> list[_Candidate]:
    d, across, H = setting.d_star, setting.across, setting.scenario.horizon
    rng = np.random.default_rng(seed)
    # with d_hat = 0 the cross-track loop is odd in (eps, s, d_perp): from the origin the phases
    # phi and phi + pi give mirror-image responses, so half a turn of phase suffices
    span = math.pi if not np.any(setting.params.d_hat) else 2 * math.pi
    phases = np.linspace(0.0, span, N_PHASES, endpoint=False)
    angles = setting.theta_r + math.pi / 2 + np.linspace(0.0, 2 * math.pi, CONSTANT_ANGLES, endpoint=False)
    per_start: list[_Candidate] = []
    for a in angles:
        vector = d * np.array([math.cos(a), math.sin(a)])
        vector[np.abs(vector) < 1e-12 * d] = 0.0  # exact zeros where the angle is a multiple of pi/2
        per_start.append(_Candidate("constant", "", Constant(vector)))
    # push eps outward: sigma = eps + layer (ties at eps = 0 broken towards +)
    layer_frac = ADVERSARIAL_LAYER_FRACTION
    per_start.append(_Candidate("push_eps", "", _feedback(setting, np.array([[1, 0], [0, 0]]),
                                                         np.array([1.0, layer_frac]), "push eps outward")))
    if storage is not None:
        if setting.params.integral[0] == 0 or float(setting.scenario.problem.gains.sigma0) <= 0:
            skipped["storage_gradient"] = "the sos_bound storage function is for the ILOS error dynamics (sigma0 > 0)"
        else:
            exps, coefs = storage_switching(storage, setting.scenario.problem.gains.sigma0)
            per_start.append(_Candidate("storage_gradient", "", _feedback(
                setting, exps, coefs, "pushes the certified storage function V of sos_bound up")))
    else:
        skipped["storage_gradient"] = "no sos_bound storage certificate was given (storage=None)"
    resolvable = freqs[freqs * H / math.pi <= MAX_SWITCHES]
    if resolvable.size < freqs.size:
        why = (f"{freqs.size - resolvable.size} of {freqs.size} resonance frequencies switch more than "
               f"{MAX_SWITCHES} times over the horizon (the integrator's step budget)")
        for family in ("sinusoid", "square_wave", "random_bang_bang"):
            skipped[family] = why
    freqs = resolvable
    for om in freqs:
        for ph in np.linspace(0.0, span, N_PHASES_SINE, endpoint=False):
            per_start.append(_Candidate("sinusoid", "", Sinusoid(np.zeros(2), d * across, np.array(om), np.array(ph))))
        for ph in phases:
            per_start.append(_Candidate("square_wave", "", SquareWave(_a(d), across, _a(om), _a(ph), H)))
    out: list[_Candidate] = []
    for start in setting.starts:
        out.extend(_Candidate(c.family, start, c.disturbance) for c in per_start
                   if start == START_ORIGIN or c.family in BOTH_STARTS_FAMILIES)
    for _ in range(N_RANDOM if freqs.size else 0):
        half_period = math.pi / float(rng.choice(freqs))
        dwell = half_period * rng.uniform(0.5, 1.5, size=int(2 * H / half_period) + 2)
        times = np.cumsum(dwell)
        times = times[times <= H]
        sign = float(rng.choice([-1.0, 1.0]))
        out.append(_Candidate("random_bang_bang", START_ORIGIN, BangBang(
            _a(d), across, times if times.size else np.array([np.inf]), _a(sign),
            note=f"random dwell times, numpy.random.default_rng({seed})")))
    return out


def _stencil(setting: _Setting, centre: SquareWave, step: tuple[float, float], start: str) -> list[_Candidate]:
    om, ph = float(centre.angular_frequency[0]), float(centre.phase[0])
    out = []
    for a in (-1, 0, 1):
        for b in (-1, 0, 1):
            if a == 0 and b == 0:
                continue
            new_om = om * math.exp(a * step[0])
            new_ph = math.remainder(ph + b * step[1], 2 * math.pi) % (2 * math.pi)
            out.append(_Candidate("optimised", start, SquareWave(_a(setting.d_star), setting.across, _a(new_om),
                                                                 _a(new_ph), setting.scenario.horizon)))
    return out


# -- the search -----------------------------------------------------------------------------------
def search_worst_case(target: Problem | Scenario, *, budget_s: float = 20.0, seed: int = 0,
                      storage: Mapping[str, Any] | None = None) -> WorstCaseResult:
    """Search the disturbance ``|d_mu| <= d*`` that maximises the tail sup of ``|eps|``.

    Parameters
    ----------
    target
        A :class:`~lyapcheck.paper.simulation.scenarios.Scenario` (its controller, ODS form, horizon,
        tail, initial state, ``d_hat`` and ``rtol`` are used) or a
        :class:`~lyapcheck.paper.params.Problem` (then the ``paper-ilos`` preset's settings: ILOS,
        ``p(0) = (0, -40 mm)``, 100 s, tail 10 s, ``rtol = 1e-8``). ``d*`` is the problem's
        ``d_max``.
    budget_s
        Wall-time budget, s. A refinement round starts only if it and the final re-simulation,
        estimated from the rounds so far, fit in what is left; the screening round and the
        final re-simulation always run.
    seed
        Seed of the random bang-bang candidates (``numpy.random.default_rng``).
    storage
        The ``sos_bound`` certificate (the dict under ``certificate`` of that condition) of the
        derived dynamics of the same problem, for the ``storage_gradient`` family; see
        :func:`storage_certificate`. Without it that family is skipped (said in ``skipped``).

    Returns
    -------
    WorstCaseResult

    Raises
    ------
    InvalidParameter
        ``d_max`` or ``omega_so`` not given, a bad budget or seed, an unusable certificate.
    """
    if isinstance(budget_s, bool) or not isinstance(budget_s, (int, float)) or not (math.isfinite(budget_s)
                                                                                  and budget_s > 0):
        raise InvalidParameter("budget_s", "a number of seconds in (0, inf)", budget_s)
    if isinstance(seed, bool) or not isinstance(seed, int) or seed < 0:
        raise InvalidParameter("seed", "an integer in [0, inf)", seed)
    t_start = time.perf_counter()
    setting = _setting(target)
    rtol = setting.scenario.rtol
    skipped: dict[str, str] = {}
    rounds: list[dict[str, Any]] = []
    evaluated: list[_Evaluated] = []
    resonances: dict[str, list[float]] = {}

    def run_round(name: str, cands: list[_Candidate], *, recorded: int = 0,
                  tol: float = SEARCH_RTOL) -> list[_Evaluated]:
        if not cands:  # nothing left to refine (e.g. every periodic family was skipped)
            return []
        t0 = time.perf_counter()
        ev = _run(setting, cands, rtol=tol, record_rows=range(recorded))
        rounds.append({"round": name, "candidates": len(cands), "rtol": tol,
                       "time_s": round(time.perf_counter() - t0, 3)})
        logger.info("worst-case round %s: %d candidates in %.2f s", name, len(cands), rounds[-1]["time_s"])
        return ev

    pending: list[_Candidate] = []
    budget_exhausted = False
    if setting.d_star == 0:
        skipped.update({f: "d_max = 0: the only admissible disturbance is zero" for f in FAMILIES if f != "constant"})
        evaluated += run_round("screening", [_Candidate("constant", s, Constant(np.zeros(2))) for s in setting.starts])
    else:
        resonances = _resonances(setting)
        evaluated += run_round("screening", _screening(setting, _frequency_grid(resonances), storage, seed, skipped))
        best = _best_by(evaluated, lambda e: e.candidate.family)
        # every family's best also from the other initial state (the screening ran the periodic
        # families from the origin only: their response from the preset's state differs by the
        # transient left at the tail, ~1 % at the paper's gains)
        other = [_Candidate(e.candidate.family, s, e.candidate.disturbance) for e in best.values()
                 for s in setting.starts if s != e.candidate.start]
        sweeps = [best[f].candidate for f in COSTATE_SEEDS if f in best]
        centre = best["square_wave"].candidate if "square_wave" in best else None
        centre_sup = best["square_wave"].sup if "square_wave" in best else -math.inf
        step = PATTERN_STEP
        round_s = ROUND_COST_GUESS * rounds[0]["time_s"]
        for r in range(MAX_ROUNDS):
            left = budget_s - (time.perf_counter() - t_start)
            if round_s * (1 + FINAL_COST_FACTOR) > left:
                budget_exhausted = True
                break
            stencil = _stencil(setting, centre.disturbance, step, centre.start) if centre is not None else []  # type: ignore[arg-type]
            n_sw, n_st = len(sweeps), len(stencil)
            ev = run_round(f"refine-{r + 1}", sweeps + stencil + (other if r == 0 else []), recorded=n_sw)
            round_s = rounds[-1]["time_s"]
            evaluated += ev
            sweeps = []
            for e in ev[:n_sw]:
                nxt = _costate_bang_bang(setting, e.trajectory) if e.trajectory is not None else None
                if nxt is not None:
                    sweeps.append(_Candidate("costate", e.candidate.start, nxt))
            if stencil:
                top = max(ev[n_sw:n_sw + n_st], key=lambda e: e.sup)
                if top.sup > centre_sup:
                    centre, centre_sup = top.candidate, top.sup
                else:
                    step = (step[0] * PATTERN_SHRINK, step[1] * PATTERN_SHRINK)
        pending = sweeps  # the last sweep iterates, not simulated yet: measured in the final call

    # final: the best candidate of each initial state (and the pending sweep iterates) again at
    # the scenario's rtol with the runner's defaults: the reported worst case is what
    # `simulate_disturbance` (and `lyapcheck simulate` on the same scenario) reproduces
    finalists: list[_Candidate] = []
    for e in _best_by(evaluated, lambda e: e.candidate.start).values():
        if all(e.candidate is not c for c in finalists):
            finalists.append(e.candidate)
    final = run_round("final", finalists + pending, tol=rtol)
    # candidates are compared by what they are (start and description): the pattern search may
    # regenerate a disturbance already simulated
    remeasured = {_identity(e.candidate): e for e in final}
    combined = [remeasured.get(_identity(e.candidate), e) for e in evaluated] + final[len(finalists):]

    def finding(e: _Evaluated) -> Finding:
        c = e.candidate
        return Finding(e.sup, {"family": c.family, **c.disturbance.describe()}, c.start, e.rtol)

    per_family: dict[str, Finding | None] = {f: None for f in FAMILIES}
    for fam, e in _best_by(combined, lambda e: e.candidate.family).items():
        per_family[fam] = finding(e)
    for fam in FAMILIES:
        if per_family[fam] is None and fam not in skipped:
            skipped[fam] = "not reached within the budget"
    per_start = {s: finding(e) for s, e in _best_by(final, lambda e: e.candidate.start).items()}
    overall = max(per_start.values(), key=lambda f: f.sup_abs_eps_tail_m)
    sc = setting.scenario
    return WorstCaseResult(
        sup_abs_eps_tail_m=overall.sup_abs_eps_tail_m, disturbance=overall.disturbance, start=overall.start,
        initial_states={k: {"position_m": list(p), "s_m": s} for k, (p, s) in setting.starts.items()},
        per_family=per_family, per_start=per_start,
        candidates_tried=sum(r["candidates"] for r in rounds), d_max_m_s=setting.d_star,
        horizon_s=sc.horizon, tail_s=sc.tail, rtol=rtol, search_rtol=SEARCH_RTOL,
        wall_time_s=time.perf_counter() - t_start, budget_s=float(budget_s), budget_exhausted=budget_exhausted,
        seed=seed, skipped=skipped, rounds=rounds, resonances_rad_s=resonances,
    )


def _identity(c: _Candidate) -> str:
    return json.dumps([c.start, c.disturbance.describe()], sort_keys=True)


def _best_by(evaluated: Sequence[_Evaluated], key: Any) -> dict[str, _Evaluated]:
    out: dict[str, _Evaluated] = {}
    for e in evaluated:
        k = key(e)
        if e.sup > -math.inf and (k not in out or e.sup > out[k].sup):
            out[k] = e
    return out


def simulate_disturbance(target: Problem | Scenario, disturbance: Disturbance | Mapping[str, Any], *,
                         start: str = START_ORIGIN, record: bool = False) -> SimulationResult:
    """Simulate one disturbance (object or JSON description) from ``"preset"`` or ``"origin"``,
    with the settings :func:`search_worst_case` reports its figures with."""
    setting = _setting(target)
    if start not in setting.starts:
        raise InvalidParameter("start", "one of " + ", ".join(repr(s) for s in setting.starts), start)
    dist = disturbance if isinstance(disturbance, Disturbance) else from_description(disturbance)
    return _simulate(setting, [_Candidate("given", start, dist)], rtol=setting.scenario.rtol,
                     record_rows=[0] if record else [])[1]


def storage_certificate(problem: Problem) -> dict[str, Any] | None:
    """The ``sos_bound`` certificate of the derived dynamics of ``problem`` (seconds of SDP)."""
    from lyapcheck.paper.certification import build_system
    from lyapcheck.paper.conditions import sos_bound

    return sos_bound.run(build_system(problem, "derived"))
