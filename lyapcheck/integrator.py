"""Batched adaptive Dormand–Prince 5(4) integration: many trajectories, one numpy call per stage.

Method
------
The explicit embedded Runge–Kutta pair of Dormand and Prince (order 5 with a 4th-order error
estimate, "first same as last"), the method of MATLAB's ``ode45`` and SciPy's ``RK45``. Every
trajectory of the batch has its *own* time and step size: one loop iteration advances each
active trajectory by its own step (a numpy array of steps), accepts or rejects it with its own
error estimate, and adapts its own next step. Nothing is shared but the numpy calls, so one
stiff or kinked trajectory does not slow the others down, and there is no Python loop over
trajectories.

Why this method: the closed loop of the paper is Lipschitz but only piecewise smooth (the ODS
saturation ``|u| = Omega_SO`` and ``|eps|`` in the tail integrals are kinks), and most
parameter sets are not stiff (the slowest rate is ``e11 alpha_d`` ~ 0.06 1/s, the fastest a
few 1/s). Local error control handles the kinks by shrinking the step only where one is
crossed, which a fixed-step RK4 cannot do (its global order falls to 2 at a kink, everywhere).
On stiff problems the explicit method stays accurate but its step is bounded by stability, so
its cost grows with the stiffness; it is tested against ``solve_ivp(method="Radau")`` on both.

Accuracy contract (tested in ``tests/test_simulation_integrator.py``): with ``rtol`` and the
per-component ``atol`` given, the global error on the paper's closed loop and on a stiff case
stays below :data:`lyapcheck.tolerances.SIM_REL_TOL` relative to the state scale for the
default ``rtol`` of :data:`DEFAULT_RTOL`.

Time breakpoints
----------------
A system may be discontinuous in time (tail-window indicator, random piecewise-constant
disturbance). It reports its next discontinuity per trajectory; steps never cross one, they
land on it exactly, and the derivative is re-evaluated there. Inside a step the system is
evaluated with the *segment time* (the step's start), so each step sees one smooth segment.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass
from typing import Any, Final, NamedTuple, Protocol

import numpy as np
import numpy.typing as npt

from lyapcheck.tolerances import SIM_MAX_STEPS

#: how simulation documents and reports name this integrator
INTEGRATOR_NAME: Final = ("Dormand-Prince 5(4), adaptive step per trajectory, batched "
                          "(lyapcheck.integrator)")

logger = logging.getLogger(__name__)

FloatArray = npt.NDArray[np.float64]
IntArray = npt.NDArray[np.intp]

#: default relative tolerance of the local error control (see the accuracy contract above)
DEFAULT_RTOL: Final = 1e-8
#: step-size controller: safety factor and bounds of the growth/shrink factor per step
_SAFETY: Final = 0.9
_MIN_FACTOR: Final = 0.2
_MAX_FACTOR: Final = 5.0
#: a trajectory whose step falls below this many ulps of its time is declared failed
_MIN_STEP_ULPS: Final = 16.0
#: compact the working set when this fraction of it has finished
_COMPACT_FRACTION: Final = 0.125
#: a switching function changing sign inside (EVENT_MARGIN, 1 - EVENT_MARGIN) of a step makes
#: the step retry up to the located zero; closer to an end the kink already sits at a boundary.
#: Tight because a retry may come from a rejected step, whose secant is less accurate: a retry
#: that lands a little short of or past the kink is retried again rather than accepted with the
#: kink inside (1e-3 lost an order of magnitude of accuracy in the kink test)
_EVENT_MARGIN: Final = 1e-6

# Dormand & Prince (1980) RK5(4)7M tableau
_C: Final = np.array([0.0, 1 / 5, 3 / 10, 4 / 5, 8 / 9, 1.0, 1.0])
_A: Final = (
    (),
    (1 / 5,),
    (3 / 40, 9 / 40),
    (44 / 45, -56 / 15, 32 / 9),
    (19372 / 6561, -25360 / 2187, 64448 / 6561, -212 / 729),
    (9017 / 3168, -355 / 33, 46732 / 5247, 49 / 176, -5103 / 18656),
    (35 / 384, 0.0, 500 / 1113, 125 / 192, -2187 / 6784, 11 / 84),
)
#: 5th-order weights minus the embedded 4th-order weights (the error estimator)
_E: Final = np.array([71 / 57600, 0.0, -71 / 16695, 71 / 1920, -17253 / 339200, 22 / 525, -1 / 40])

#: status codes of :class:`IntegrationResult`
STATUS_OK: Final = 0
STATUS_NONFINITE: Final = 1
STATUS_STEP_TOO_SMALL: Final = 2
STATUS_MAX_ITERATIONS: Final = 3


class BatchedSystem(Protocol):
    """A batch of ODEs ``y' = f(t, y)`` with one row per trajectory."""

    @property
    def size(self) -> int:
        """Number of trajectories (rows)."""

    def rhs(self, t: FloatArray, y: FloatArray, t_segment: FloatArray) -> "Evaluation":
        """Derivative, monitored scalar and switching functions at ``(t, y)``.

        ``t_segment`` is the start of the current step: quantities that are piecewise constant
        in time must be evaluated there, so that a step never straddles a discontinuity.
        """

    def take(self, index: IntArray) -> "BatchedSystem":
        """The sub-batch of the given rows (parameters sliced accordingly)."""

    def next_breakpoint(self, t: FloatArray) -> FloatArray:
        """Per trajectory, the first time-discontinuity strictly after ``t`` (``inf`` if none)."""


class Evaluation(NamedTuple):
    """One evaluation of a :class:`BatchedSystem`.

    Attributes
    ----------
    dy
        The derivative, ``(n, m)``.
    monitor
        A scalar per row whose maximum over every evaluation is reported (e.g. ``|u|``).
    switch
        Switching functions ``(n, k)`` (``k`` may be 0): continuous functions of the state
        whose zeros are the kinks of the right-hand side (e.g. the saturation boundary). A step
        over which one changes sign is retried so that it ends near the zero (located by the
        secant of the two end values), whether or not it passed the error test: the kink then
        sits at a step boundary and the method keeps its order, instead of falling to the
        O(h^2) local error of a step across a kink. The step after the kink starts from the
        size of the step the kink interrupted, not from the retry's (possibly tiny) piece.
    """

    dy: FloatArray
    monitor: FloatArray
    switch: FloatArray


class StepObserver(Protocol):
    """Receives the initial point and every accepted step, with global trajectory indices."""

    def start(self, index: IntArray, t: FloatArray, y: FloatArray, f: FloatArray) -> None: ...

    def step(self, index: IntArray, t0: FloatArray, t1: FloatArray, y0: FloatArray, y1: FloatArray,
             f0: FloatArray, f1: FloatArray) -> None: ...


class Fanout:
    """A :class:`StepObserver` that forwards every callback to several observers (None ones left out)."""

    def __init__(self, *observers: Any) -> None:
        self.observers = [o for o in observers if o is not None]

    def start(self, *args: Any) -> None:
        for o in self.observers:
            o.start(*args)

    def step(self, *args: Any) -> None:
        for o in self.observers:
            o.step(*args)


@dataclass(frozen=True)
class IntegrationResult:
    """Final states and bookkeeping of one batched integration."""

    t: FloatArray
    y: FloatArray
    status: npt.NDArray[np.int8]
    n_accepted: npt.NDArray[np.int64]
    n_rejected: npt.NDArray[np.int64]
    monitor_max: FloatArray
    n_iterations: int
    n_rhs_rows: int
    n_events: int = 0
    #: the ``max_iterations`` of the call (the step budget a ``STATUS_MAX_ITERATIONS`` row hit)
    max_iterations: int = SIM_MAX_STEPS

    @property
    def ok(self) -> npt.NDArray[np.bool_]:
        return np.asarray(self.status == STATUS_OK)

    def failure(self, i: int, t_end: float) -> str | None:
        """Why trajectory ``i`` stopped before ``t_end`` (None when it reached it).

        Parameters
        ----------
        i
            Row of the batch.
        t_end
            The end time that row was integrated to, s (for the message only).

        Returns
        -------
        str or None
            One sentence naming the limit that was hit, the time reached and what it means.
        """
        status, t = int(self.status[i]), float(self.t[i])
        reached = f"at t = {t:.6g} s of {t_end:g} s"
        if status == STATUS_OK:
            return None
        if status == STATUS_NONFINITE:
            return (f"state or derivative not finite in double precision {reached} (overflow): "
                    "the loop cannot be simulated numerically at this scale")
        if status == STATUS_STEP_TOO_SMALL:
            return (f"step size below {_MIN_STEP_ULPS:g} ulps of t {reached}: "
                    "the loop is too fast (stiff) to simulate at this scale")
        if status == STATUS_MAX_ITERATIONS:
            return (f"step budget exhausted: {self.max_iterations} steps (lyapcheck.tolerances.SIM_MAX_STEPS) "
                    f"{reached}, stiff at this scale")
        return f"integrator status {status} {reached}"


def _rms(x: FloatArray) -> FloatArray:
    return np.sqrt(np.mean(x * x, axis=1))


def _min_step(t: FloatArray) -> FloatArray:
    """The smallest step a trajectory may take at ``t`` (below it, it is declared failed)."""
    return _MIN_STEP_ULPS * np.spacing(np.maximum(np.abs(t), 1.0))


def _initial_step(system: BatchedSystem, t0: FloatArray, y0: FloatArray, f0: FloatArray,
                  atol: FloatArray, rtol: float, max_step: FloatArray) -> FloatArray:
    """Hairer–Nørsett–Wanner's starting-step heuristic (Solving ODEs I, II.4), per row.

    At extreme scales the scaled norms overflow (``|f| / atol`` beyond the double range, or
    ``|f(y0 + h0 f0) - f0| / h0`` for a very stiff row): the heuristic then gives 0 or NaN. A
    zero step has zero error and would be accepted forever without advancing ``t``, a NaN step
    poisons the state; such rows start at the smallest allowed step instead, where the step
    control either proceeds or declares the row failed (step too small / not finite).
    """
    with np.errstate(over="ignore", invalid="ignore", divide="ignore", under="ignore"):
        scale = atol + rtol * np.abs(y0)
        d0, d1 = _rms(y0 / scale), _rms(f0 / scale)
        h0 = np.where((d0 < 1e-5) | (d1 < 1e-5), 1e-6, 0.01 * d0 / np.maximum(d1, 1e-300))
        h0 = np.minimum(h0, max_step)
        h0 = np.where(np.isfinite(h0) & (h0 > 0), h0, np.minimum(_min_step(t0), max_step))
        f1 = system.rhs(t0 + h0, y0 + h0[:, None] * f0, t0).dy
        d2 = _rms((f1 - f0) / scale) / h0
        dmax = np.maximum(d1, d2)
        h1 = np.where(dmax <= 1e-15, np.maximum(1e-6, 1e-3 * h0), (0.01 / dmax) ** 0.2)
        h = np.minimum(np.minimum(100 * h0, h1), max_step)
    return np.where(np.isfinite(h) & (h > 0), h, np.minimum(_min_step(t0), max_step))


def integrate(system: BatchedSystem, t0: float | FloatArray, y0: FloatArray, t_end: float | FloatArray,
              *, rtol: float = DEFAULT_RTOL, atol: FloatArray | float, max_step: float | FloatArray = np.inf,
              observer: StepObserver | None = None, switch_atol: FloatArray | float = 0.0,
              max_iterations: int = SIM_MAX_STEPS, first_step: FloatArray | float | None = None
              ) -> IntegrationResult:
    """Integrate every row of ``system`` from ``t0`` to ``t_end`` with DOPRI5 (see module doc).

    Parameters
    ----------
    system
        The batched right-hand side.
    t0, t_end
        Start and end times, scalars or ``(n,)``.
    y0
        Initial states, ``(n, m)``.
    rtol
        Relative tolerance of the local error test (same for every component).
    atol
        Absolute tolerance: scalar, ``(m,)`` or ``(n, m)``, in the units of each component.
    max_step
        Upper bound on the step, scalar or ``(n,)`` (bounds the sampling interval seen by
        observers, e.g. for sup-norm measurements).
    observer
        Receives the initial point and each accepted step (global indices).
    switch_atol
        Crossings of a switching function are ignored while it stays within this magnitude at
        both ends of the step (a kink that small is below the tolerance; without it a state
        converging to a switching surface, e.g. eps -> 0, would trigger endless retries).
        Scalar, ``(k,)`` or ``(n, k)``.
    first_step
        The first step to try, scalar or ``(n,)`` (bounded by ``max_step``; the error test still
        decides it), for a caller that continues a trajectory in several calls and knows its step
        size (a sampled-data loop, one call per period); default: Hairer–Nørsett–Wanner's heuristic.
    max_iterations
        Step budget: bound on loop iterations, i.e. on the steps (accepted, rejected or retried
        at a kink) of any one trajectory; rows unfinished after it get ``STATUS_MAX_ITERATIONS``.
        The default :data:`~lyapcheck.tolerances.SIM_MAX_STEPS` bounds the cost of a loop that
        is stiff at extreme scales (its explicit step is bounded by stability, not accuracy).

    Returns
    -------
    IntegrationResult
    """
    y0 = np.array(y0, dtype=np.float64, copy=True)
    if y0.ndim != 2:
        raise ValueError(f"The 'y0' parameter must be an array of shape (n, m). Got shape {y0.shape} instead.")
    n, m = y0.shape
    if not 0 < rtol < 1:
        raise ValueError(f"The 'rtol' parameter must be a number in (0, 1). Got {rtol!r} instead.")
    t_all = np.broadcast_to(np.asarray(t0, dtype=np.float64), (n,)).copy()
    end_all = np.broadcast_to(np.asarray(t_end, dtype=np.float64), (n,)).copy()
    if np.any(end_all < t_all):
        raise ValueError("The 't_end' parameter must not be before 't0'. Got an earlier end time instead.")
    atol_all = np.broadcast_to(np.asarray(atol, dtype=np.float64), (n, m)).copy()
    if np.any(~(atol_all > 0)):
        raise ValueError("The 'atol' parameter must be positive. Got a non-positive entry instead.")
    hmax_all = np.broadcast_to(np.asarray(max_step, dtype=np.float64), (n,)).copy()
    sw_all = np.asarray(switch_atol, dtype=np.float64)

    y_all = y0
    status = np.zeros(n, dtype=np.int8)
    n_acc = np.zeros(n, dtype=np.int64)
    n_rej = np.zeros(n, dtype=np.int64)
    monitor = np.full(n, -np.inf)
    rows_evaluated = 0

    # working set (compressed copies)
    gidx = np.arange(n)
    sys_w = system
    t, y, t_end_w, atol_w, hmax = t_all, y_all.copy(), end_all, atol_all, hmax_all
    ev = sys_w.rhs(t, y, t)
    f, g = ev.dy, ev.switch
    sw_tol = np.broadcast_to(sw_all, g.shape).copy()
    rows_evaluated += n
    # fmax: a row whose trial state overflowed has a NaN monitor, which must not stick
    monitor = np.fmax(monitor, ev.monitor)
    n_events = 0
    if observer is not None:
        observer.start(gidx, t, y, f)
    if first_step is None:
        h = _initial_step(sys_w, t, y, f, atol_w, rtol, hmax)
    else:
        h = np.minimum(np.broadcast_to(np.asarray(first_step, dtype=np.float64), (n,)), hmax)
        if np.any(~(h > 0)):
            raise ValueError("The 'first_step' parameter must be positive. Got a non-positive entry instead.")
    # per row, the step size to resume after a retry up to a kink (0: none pending)
    resume = np.zeros(n)
    rows_evaluated += n
    done = t >= t_end_w
    iterations = 0

    def write_back(rows: npt.NDArray[np.bool_]) -> None:
        g = gidx[rows]
        t_all[g], y_all[g] = t[rows], y[rows]

    while gidx.size:
        iterations += 1
        if iterations > max_iterations:
            status[gidx[~done]] = STATUS_MAX_ITERATIONS
            write_back(np.ones(gidx.size, dtype=bool))
            break
        bp = np.minimum(sys_w.next_breakpoint(t), t_end_w)
        if ((bp <= t) & ~done).any():
            raise RuntimeError("The system's 'next_breakpoint' must return times after t. Got one at or before t instead.")
        step = np.minimum(h, hmax)
        # land exactly on a breakpoint when the step would reach it (or nearly)
        land = t + step * (1 + 1e-12) >= bp
        step = np.where(land, bp - t, step)
        step = np.where(done, 0.0, step)

        k = [f]
        stage_monitor = np.full(gidx.size, -np.inf)
        for i in range(1, 7):
            yi = y.copy()
            for j, a in enumerate(_A[i]):
                if a != 0.0:
                    yi += (step * a)[:, None] * k[j]
            ev = sys_w.rhs(t + _C[i] * step, yi, t)
            stage_monitor = np.fmax(stage_monitor, ev.monitor)
            k.append(ev.dy)
        # one update per step (fmax is associative and ignores NaN like the per-stage updates did)
        monitor[gidx] = np.fmax(monitor[gidx], np.where(done, -np.inf, stage_monitor))
        rows_evaluated += 6 * gidx.size
        y_new = yi  # the 7th stage point is the 5th-order solution (FSAL)
        f_new, g_new = k[6], ev.switch
        err = step[:, None] * sum(e * ki for e, ki in zip(_E, k) if e != 0.0)
        scale = atol_w + rtol * np.maximum(np.abs(y), np.abs(y_new))
        with np.errstate(over="ignore", invalid="ignore"):
            err_norm = _rms(err / scale)
        finite = np.isfinite(err_norm) & np.isfinite(y_new).all(axis=1)
        accept = finite & (err_norm <= 1.0) & ~done
        with np.errstate(divide="ignore", over="ignore", invalid="ignore"):
            factor = np.where(err_norm > 0, _SAFETY * err_norm ** -0.2, _MAX_FACTOR)
        factor = np.clip(np.where(finite, factor, _MIN_FACTOR), _MIN_FACTOR, _MAX_FACTOR)
        factor = np.where(accept, factor, np.minimum(factor, 1.0))

        # kinks: retry a step that crosses a switching surface well inside it, up to the crossing,
        # whether or not it passed the error test. A step across a kink has a local error of
        # O(h^2), so shrinking it by the error controller (a factor of about 0.8 per try, the
        # error falling only like h) costs a run of rejections before the step leaves the kink
        # out; the secant's zero is where the smooth segment ends
        event_step = np.full(step.shape, np.inf)
        if g.shape[1]:
            crossed = (np.sign(g) * np.sign(g_new) < 0) & (np.maximum(np.abs(g), np.abs(g_new)) > sw_tol)
            with np.errstate(divide="ignore", invalid="ignore"):
                theta = np.where(crossed, g / (g - g_new), np.inf)
            theta = theta.min(axis=1)
            event = finite & ~done & (theta > _EVENT_MARGIN) & (theta < 1 - _EVENT_MARGIN)
            if event.any():
                accept = accept & ~event
                event_step = np.where(event, np.where(event, theta, 0.0) * step, np.inf)
                n_events += int(event.sum())
                # the step to return to once the kink is passed: the retry's piece (theta * step,
                # tiny where the kink sits near the start) says nothing about the smooth side
                resume = np.where(event, np.maximum(resume, step * np.minimum(factor, 1.0)), resume)

        if observer is not None and accept.any():
            rows = accept
            t_next = np.where(land[rows], bp[rows], t[rows] + step[rows])
            observer.step(gidx[rows], t[rows], t_next, y[rows], y_new[rows], f[rows], f_new[rows])

        t_next = np.where(land, bp, t + step)
        new_h = step * factor
        # a step shortened to land on a breakpoint says little about the next step size
        new_h = np.where(accept & land, np.maximum(new_h, h), new_h)
        # nor does one shortened to land on a kink: go on with the step the kink interrupted
        new_h = np.where(accept, np.maximum(new_h, resume), new_h)
        resume = np.where(accept, 0.0, resume)
        retry = np.isfinite(event_step)
        new_h = np.where(retry, event_step, new_h)
        t = np.where(accept, t_next, t)
        y = np.where(accept[:, None], y_new, y)
        f = np.where(accept[:, None], f_new, f)
        g = np.where(accept[:, None], g_new, g)
        h = np.where(done, h, new_h)
        n_acc[gidx[accept]] += 1
        n_rej[gidx[~accept & ~done & ~retry]] += 1

        # after a breakpoint the segment changed: re-evaluate f there with the new segment time
        fresh = accept & land
        if fresh.any():
            sel = np.flatnonzero(fresh)
            sub = sys_w.take(sel)
            ev = sub.rhs(t[sel], y[sel], t[sel])
            rows_evaluated += sel.size
            f[sel] = ev.dy
            g[sel] = ev.switch
            monitor[gidx[sel]] = np.fmax(monitor[gidx[sel]], ev.monitor)

        too_small = ~accept & ~done & ~retry & (h < _min_step(t))
        status[gidx[too_small & finite]] = STATUS_STEP_TOO_SMALL
        status[gidx[too_small & ~finite]] = STATUS_NONFINITE
        done = done | (t >= t_end_w) | too_small

        if done.any() and (done.mean() >= _COMPACT_FRACTION or done.all()):
            write_back(done)
            keep = np.flatnonzero(~done)
            gidx = gidx[keep]
            if gidx.size == 0:
                break
            sys_w = sys_w.take(keep)
            t, y, f, g, h, sw_tol, resume = t[keep], y[keep], f[keep], g[keep], h[keep], sw_tol[keep], resume[keep]
            t_end_w, atol_w, hmax = t_end_w[keep], atol_w[keep], hmax[keep]
            done = done[keep]

    if gidx.size:
        write_back(np.ones(gidx.size, dtype=bool))
    return IntegrationResult(t=t_all, y=y_all, status=status, n_accepted=n_acc, n_rejected=n_rej,
                             monitor_max=monitor, n_iterations=iterations, n_rhs_rows=rows_evaluated,
                             n_events=n_events, max_iterations=max_iterations)


def hermite(theta: float | FloatArray, h: FloatArray, y0: FloatArray, y1: FloatArray, f0: FloatArray,
            f1: FloatArray) -> FloatArray:
    """Cubic Hermite interpolant at ``t0 + theta h`` (4th-order accurate on a smooth step).

    Used to sample states inside accepted steps (sup-norm measurements, recorded trajectories)
    without extra evaluations of the right-hand side. ``theta`` is a scalar or one per row.
    """
    th = np.asarray(theta, dtype=np.float64)
    if th.ndim:
        th = th[:, None]
    h00 = (1 + 2 * th) * (1 - th) ** 2
    h10 = th * (1 - th) ** 2
    h01 = th * th * (3 - 2 * th)
    h11 = th * th * (th - 1)
    hh = h[:, None]
    return h00 * y0 + h10 * hh * f0 + h01 * y1 + h11 * hh * f1
