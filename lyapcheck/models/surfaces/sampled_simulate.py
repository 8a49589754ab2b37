"""``simulate`` of a sampled-data loop (``[sampling]``, ``[controller]``): the true plant between samples,
each control held (zero-order hold) at its value computed from the state at the sampling instant.

The plant's loop :attr:`~lyapcheck.models.language.sampling.SampledModel.plant` is the continuous loop over
the states and then the controls, each control a constant state (``u' = 0``). Integrating *that* loop over
one period from ``(x_k, u_k = k(x_k))`` is exactly the held-control flow, so one period is one call of the
project's integrator (:mod:`lyapcheck.integrator`) on the plant's simulated loop
(:func:`lyapcheck.models.surfaces.simulate.prepare`: the true field of a plant with functions, each
function evaluated by numpy, as the continuous ``simulate`` does), every start a row of the call; between
the calls the controls are sampled again. ``t_k = k T``; the last interval ends at the horizon.

Everything is measured as for a continuous loop (:mod:`lyapcheck.models.surfaces.simulate`): the state
scale, the escape box (a row that leaves it, or whose integration fails, is ``diverged`` and stops),
``converged`` (the final state within :data:`~lyapcheck.models.surfaces.simulate.CONVERGENCE_RADIUS` state
scales of the equilibrium), the tail sup of ``|y|`` over the last
:data:`~lyapcheck.models.surfaces.simulate.TAIL_FRACTION` of the horizon for every state and every
control. One difference: a state the plant sees only through its sine and cosine is still not an angle
when a controller law uses it (``-Kp*theta`` tells ``theta`` from ``theta + 2 pi``), and is then measured
as it is.

The default horizon is :data:`~lyapcheck.models.surfaces.simulate.HORIZON_TIME_CONSTANTS` slowest time
constants of the sampled loop's linearization at the sampling instants (its Jacobian over one period,
``exp(A T) + Gamma(T) B K``, in floating point: a number of periods ``-40 / ln rho``), between
:data:`MIN_PERIODS` and :data:`MAX_DEFAULT_PERIODS` periods; :data:`FALLBACK_PERIODS` periods when that
spectral radius is not below 1 (nothing decays) or cannot be formed.
"""

from __future__ import annotations

import math
import time
from dataclasses import replace
from typing import TYPE_CHECKING, Any, Final, Sequence

import numpy as np

from lyapcheck.errors import InvalidParameter, ModelFileError
from lyapcheck.integrator import DEFAULT_RTOL, INTEGRATOR_NAME, STATUS_OK, Evaluation, integrate
from lyapcheck.models.surfaces.simulate import (
    ATOL_PER_RTOL, CONVERGENCE_RADIUS, ESCAPE_FACTOR, HORIZON_TIME_CONSTANTS, MAX_PLOTTED_ROWS, NEAR_START_FRACTION,
    PLOT_CLIP, PLOT_SAMPLES, STEPS_PER_TAIL, TAIL_FRACTION, CompiledPolys, ModelRun, Prepared, _TailObserver,
    prepare, state_scale,
)
from lyapcheck.sos.polynomials import Ring, degree_in
from lyapcheck.tolerances import SIM_MAX_STEPS

if TYPE_CHECKING:  # pragma: no cover
    from numpy.typing import NDArray

    from lyapcheck.models.language.sampling import SampledModel

    FloatArray = NDArray[np.float64]
    IntArray = NDArray[np.intp]

#: what the document's ``mode`` says
MODE: Final = "sampled"
#: default horizon, in sampling periods: at least MIN_PERIODS, at most MAX_DEFAULT_PERIODS; FALLBACK_PERIODS
#: when the sampled linearization has nothing that decays (spectral radius >= 1) or cannot be formed
MIN_PERIODS: Final = 20
MAX_DEFAULT_PERIODS: Final = 5000
FALLBACK_PERIODS: Final = 200
#: the most sampling periods a horizon may span (one integrator call per period)
MAX_PERIODS: Final = 100_000
#: the plot draws the held controls as an exact staircase (one value per period) up to this many
#: periods; beyond, from the resampled trajectory (a staircase finer than the figure's pixels)
MAX_STAIRCASE_PERIODS: Final = 5000
#: a sampling instant within this fraction of a period of the horizon is the horizon itself
INSTANT_FRACTION: Final = 1e-9
#: what the document's ``hold`` says
HOLD_TEXT: Final = "zero-order: each control computed from the state at t_k = k T and held until t_k + T"


def refuse(source: str, surface: str, instead: str) -> ModelFileError:
    """The one-line refusal (exit 2) of what ``simulate`` does not take on a sampled-data loop."""
    return ModelFileError(source, surface, f"not taken for a sampled-data loop ([sampling]: a plant under controls "
                                           f"held between samples, without disturbances); {instead}")


def prepare_sampled(model: "SampledModel") -> Prepared:
    """The plant's simulated loop (:func:`~lyapcheck.models.surfaces.simulate.prepare` on
    :attr:`SampledModel.plant`), its angles left only where no controller law uses them (module
    docstring)."""
    prepared = prepare(model.plant)
    ring = Ring(model.states) if model.controller_system is None else model.controller_system.ring
    # (with functions, also every auxiliary's argument: each auxiliary comes from a law)
    used = {s for s in model.states for law in model.controller.values()
            if degree_in(ring, law.numerator, [s]) > 0 or degree_in(ring, law.denominator, [s]) > 0}
    if model.controller_system is not None:
        used |= {s for s in model.states for a in model.controller_system.auxiliaries
                 if a.argument is not None and degree_in(ring, a.argument, [s]) > 0}
    angles = tuple(i for i in prepared.angles if model.plant.states[i] not in used)
    keys = dict(prepared.document_keys)
    if "angles_modulo_2pi" in keys:
        keys["angles_modulo_2pi"] = [model.plant.states[i] for i in angles]
    return replace(prepared, angles=angles, document_keys=keys)


class ControlLaw:
    """Each controller law ``k(x)`` at ``(batch, n)`` states: numerators and denominators in one evaluation;
    a law with functions over its auxiliaries, each evaluated by numpy from its definition
    (:class:`~lyapcheck.models.engines.recast_numeric.FloatLoop`, as the continuous ``simulate`` evaluates a
    loop with functions)."""

    def __init__(self, model: "SampledModel") -> None:
        laws = [model.controller[u] for u in model.controls]
        self.m = len(laws)
        self.variables = None
        ring = Ring(model.states)
        if model.controller_system is not None:
            from lyapcheck.models.engines.recast_numeric import FloatLoop

            self.variables, ring = FloatLoop(model.controller_system), model.controller_system.ring
        self.polys = CompiledPolys(ring, [r.numerator for r in laws] + [r.denominator for r in laws])

    def __call__(self, x: "FloatArray") -> "FloatArray":
        if self.variables is not None:  # the states, then every auxiliary at them
            x = np.column_stack(self.variables.columns(np.atleast_2d(x)))
        values = self.polys(x)
        with np.errstate(all="ignore"):  # a denominator 0 or an overflow: a non-finite control, diverged
            return values[:, :self.m] / values[:, self.m:]


class _HeldPlant:
    """The plant's loop with the controls as constant states, one row per trajectory (the integrator's
    batched system); a row farther than ``escape`` from the equilibrium stops moving, as in
    :mod:`lyapcheck.models.surfaces.simulate`."""

    def __init__(self, prepared: Prepared, escape: "FloatArray", rows: int) -> None:
        self.prepared, self.escape, self.rows = prepared, escape, rows

    @property
    def size(self) -> int:
        return self.rows

    def take(self, index: "IntArray") -> "_HeldPlant":
        return _HeldPlant(self.prepared, self.escape, int(np.asarray(index).size))

    def rhs(self, t: "FloatArray", y: "FloatArray", t_segment: "FloatArray") -> Evaluation:
        return self.prepared.field_stopped_beyond(y, None, self.escape)

    def next_breakpoint(self, t: "FloatArray") -> "FloatArray":
        return np.full(t.shape, np.inf)


class _Rows:
    """Forwards one period's integrator callbacks to the run's observers in the run's row numbers
    (``rows``: the rows of this call); the start only for the first period (afterwards each period's
    first step starts at the sampled point, which the step callbacks see)."""

    def __init__(self, observers: Sequence[Any], rows: "IntArray", first: bool) -> None:
        self.observers, self.rows, self.first = [o for o in observers if o is not None], rows, first

    def start(self, index: "IntArray", *args: Any) -> None:
        if self.first:
            for o in self.observers:
                o.start(self.rows[index], *args)

    def step(self, index: "IntArray", *args: Any) -> None:
        for o in self.observers:
            o.step(self.rows[index], *args)


def default_periods(radius: float | None) -> int:
    """The default horizon in periods from the sampled linearization's spectral radius (module docstring)."""
    if radius is None or not math.isfinite(radius) or radius >= 1:
        return FALLBACK_PERIODS
    if radius <= 0:
        return MIN_PERIODS
    return int(min(MAX_DEFAULT_PERIODS, max(MIN_PERIODS, math.ceil(HORIZON_TIME_CONSTANTS / -math.log(radius)))))


def check_horizon(period: float, t_end: float | None, radius: float | None) -> float:
    """The horizon, s: ``t_end`` validated (at most :data:`MAX_PERIODS` periods), or the default."""
    if t_end is None:
        return default_periods(radius) * period
    top = MAX_PERIODS * period
    if isinstance(t_end, bool) or not isinstance(t_end, (int, float)) or not 0 < float(t_end) <= top:
        raise InvalidParameter("t_end", f"a number of seconds in (0, {top:.6g}] (MAX_PERIODS = {MAX_PERIODS} sampling "
                                        f"periods of {period:.6g} s)", t_end)
    return float(t_end)


def default_starts(model: "SampledModel") -> "tuple[FloatArray, str]":
    """The equilibrium and ``x_eq +- NEAR_START_FRACTION`` state scales along each state (a sampled-data
    file has no ``[domain]``: the scale is ``|x_eq|``, 1 where it is 0), and a sentence saying so."""
    eq = np.array([float(v) for v in model.equilibrium])
    scale = np.where(np.abs(eq) > 0, np.abs(eq), 1.0)
    near = [eq + sign * NEAR_START_FRACTION * scale[i] * np.eye(model.n)[i] for i in range(model.n) for sign in (1, -1)]
    return (np.vstack([eq[None, :], *near]),
            f"the equilibrium and x_eq +- {NEAR_START_FRACTION:g} x the state scale along each state (no [domain])")


def instants(period: float, horizon: float) -> "FloatArray":
    """The sampling instants ``k T`` before the horizon, then the horizon (a last period cut short when the
    horizon is not a whole number of periods)."""
    count = math.ceil(horizon / period * (1 - INSTANT_FRACTION))
    return np.append(np.arange(count) * period, horizon)


def run_sampled(model: "SampledModel", starts: "FloatArray", how: str, *, t_end: float | None = None,
                rtol: float = DEFAULT_RTOL, plot: str | None = None, series: bool = False) -> ModelRun:
    """Simulate the sampled-data loop from each start (module docstring).

    Parameters
    ----------
    model
        A loaded sampled-data model file (:func:`lyapcheck.models.language.sampling.load_sampled`).
    starts, how
        ``(k, n)`` initial states over ``model.states`` (SI), and a sentence saying where they come from.
    t_end
        The horizon, s (default: module docstring).
    rtol
        The integrator's relative tolerance (absolute: ``rtol`` times the state scale).
    plot
        Also draw the states against time, each control as a staircase, to this PNG.
    series
        Also sample the trajectories on a common time grid (:mod:`lyapcheck.models.engines.series`), with
        the held controls as ``u``.

    Returns
    -------
    ModelRun
        The ``--json`` document (``mode`` ``"sampled"``) and, with ``series``, the dataset.
    """
    begin = time.perf_counter()
    p = prepare_sampled(model)
    n, m = model.n, len(model.controls)
    T = float(model.period)
    from lyapcheck.models.classes.sampled import spectral_radius_estimate

    radius = spectral_radius_estimate(model)
    horizon = check_horizon(T, t_end, radius)
    grid_t = instants(T, horizon)
    law = ControlLaw(model)
    S = starts.shape[0]
    y = np.concatenate([starts, law(starts)], axis=1)
    scale = state_scale(p, y[np.all(np.isfinite(y), axis=1)])
    escape = p.box(ESCAPE_FACTOR, scale)
    t_tail = float(grid_t[min(len(grid_t) - 1, math.floor((1 - TAIL_FRACTION) * (len(grid_t) - 1)))])
    record = (sorted(set(np.linspace(0, S - 1, min(S, MAX_PLOTTED_ROWS)).round().astype(int).tolist()))
              if plot is not None else None)
    observer = _TailObserver(p, S, t_tail, None if record is None else np.asarray(record, dtype=np.intp))
    recorder = None
    if series:
        from lyapcheck.models.engines.series import SeriesRecorder, recorded_rows

        recorder = SeriesRecorder(recorded_rows(S), S, n + m, horizon)
    staircase = record is not None and len(grid_t) - 1 <= MAX_STAIRCASE_PERIODS
    held = np.full((S if staircase else 0, len(grid_t) - 1, m), np.nan)
    alive = np.ones(S, dtype=bool)
    failure: list[str | None] = [None] * S
    status = np.zeros(S, dtype=np.int8)
    accepted = np.zeros(S, dtype=np.int64)
    periods = np.zeros(S, dtype=np.int64)
    step = np.full(S, T)
    # 5 samples per step for the tail sup, as in continuous time; a step never crosses a sampling instant
    max_step = min(TAIL_FRACTION * horizon / STEPS_PER_TAIL, T)
    for k in range(len(grid_t) - 1):
        if k:  # sample and hold: each control from the state at t_k
            y[alive, n:] = law(y[alive, :n])
        bad = alive & ~np.all(np.isfinite(y), axis=1)
        for r in np.flatnonzero(bad):
            failure[r] = f"the control is not finite at t = {grid_t[k]:.6g} s (a denominator 0 or an overflow)"
        alive &= ~bad
        rows = np.flatnonzero(alive)
        if not rows.size:
            break
        if staircase:
            held[rows, k] = y[rows, n:]
        if recorder is not None and k:
            _sample_at_instant(recorder, rows, float(grid_t[k]), y[rows], T)
        result = integrate(_HeldPlant(p, escape, rows.size), float(grid_t[k]), y[rows], float(grid_t[k + 1]),
                           rtol=rtol, atol=ATOL_PER_RTOL * rtol * scale, max_step=max_step,
                           observer=_Rows([observer, recorder], rows, k == 0), max_iterations=SIM_MAX_STEPS,
                           first_step=None if k == 0 else step[rows])
        y[rows] = result.y
        accepted[rows] += result.n_accepted
        # the next period starts from this one's mean step (the integrator's heuristic would start each
        # period, the equilibrium's row above all, from a tiny step and grow it again)
        step[rows] = (grid_t[k + 1] - grid_t[k]) / np.maximum(result.n_accepted, 1)
        periods[rows] += 1
        failed = result.status != STATUS_OK
        for i in np.flatnonzero(failed):
            failure[rows[i]] = result.failure(int(i), horizon)
            status[rows[i]] = result.status[i]
        offset = np.abs(p.deviation(result.y))
        escaped = ~failed & (np.any(offset > escape, axis=1) | ~np.all(np.isfinite(result.y), axis=1))
        for i in np.flatnonzero(escaped):
            failure[rows[i]] = ("the state left the escape box (ESCAPE_FACTOR state scales from the equilibrium) "
                                f"by t = {grid_t[k + 1]:.6g} s: diverging")
        alive[rows[failed | escaped]] = False
    diverged = ~alive
    offset = np.abs(p.deviation(y))[:, :n]
    converged = ~diverged & np.all(offset <= CONVERGENCE_RADIUS * scale[:n], axis=1)
    sup = np.where(diverged[:, None], np.nan, observer.sup)
    names = p.output_names
    doc = _document(model, p, starts, how, horizon, t_tail, grid_t, radius, scale, y, sup, converged, diverged,
                    failure, status, accepted, periods, rtol)
    if plot is not None:
        plot_sampled(model, p, observer, record or [], held if staircase else None, grid_t, diverged, scale, t_tail,
                     str(plot))
        doc["plot"] = str(plot)
    doc["wall_time_s"] = time.perf_counter() - begin
    dataset = None
    if recorder is not None:
        dataset = _dataset(model, p, recorder, names, converged, diverged, scale, horizon, t_tail, rtol)
    return ModelRun(document=doc, series=dataset)


def _sample_at_instant(recorder: Any, rows: "IntArray", instant: float, y: "FloatArray", period: float) -> None:
    """A series' sample that falls on a sampling instant takes the state with the new control (a staircase
    is right-continuous: ``u(t_k) = k(x(t_k))``); the period before wrote the value held until then."""
    hit = np.flatnonzero(np.abs(recorder.time - instant) <= INSTANT_FRACTION * period)
    slots = recorder.slot[rows]
    keep = slots >= 0
    if hit.size and keep.any():
        recorder.x[slots[keep][:, None], hit[None, :]] = y[keep][:, None, :]


def _document(model: "SampledModel", p: Prepared, starts: "FloatArray", how: str, horizon: float, t_tail: float,
              grid_t: "FloatArray", radius: float | None, scale: "FloatArray", y: "FloatArray", sup: "FloatArray",
              converged: "NDArray[np.bool_]", diverged: "NDArray[np.bool_]", failure: Sequence[str | None],
              status: "NDArray[np.int8]", accepted: "NDArray[np.int64]", periods: "NDArray[np.int64]",
              rtol: float) -> dict[str, Any]:
    """The ``--json`` document of :func:`run_sampled` (the keys of a continuous model's where they apply)."""
    n = model.n
    names = p.output_names
    outputs = {y_: model.controller_text.get(y_, p.output_text.get(y_, y_)) for y_ in names}

    def point(x: "FloatArray", over: Sequence[str] = model.states) -> dict[str, float | None]:
        return {s: (float(v) if math.isfinite(v) else None) for s, v in zip(over, x)}

    def figure(v: float) -> float | None:
        return float(v) if math.isfinite(v) else None

    trajectories = [{
        "start": r, "scenario": "none", "disturbance": {"kind": "none"},
        "sup_abs_output_tail": {y_: figure(sup[r, o]) for o, y_ in enumerate(names)},
        "final_state": point(y[r, :n]), "final_control": point(y[r, n:], model.controls),
        "converged": bool(converged[r]), "diverged": bool(diverged[r]), "failure": failure[r],
        "integrator_status": int(status[r]), "steps_accepted": int(accepted[r]), "periods": int(periods[r]),
    } for r in range(y.shape[0])]
    ok = ~diverged
    sups = {y_: (float(np.max(sup[ok, o])) if ok.any() else None) for o, y_ in enumerate(names)}
    return {
        "mode": MODE,
        "model": {"name": model.name, "file": model.source, "sha256": model.sha256, "overrides": dict(model.overrides)},
        **p.document_keys,
        "states": list(model.states),
        "controls": list(model.controls),
        "sampling": model.to_json(),
        "period_s": float(model.period),
        "hold": HOLD_TEXT,
        "spectral_radius_estimate": radius,
        "equilibrium": point(p.equilibrium[:n]),
        "disturbance_bounds": {},
        "outputs": outputs,
        "starts": [point(x) for x in starts],
        "starts_from": how,
        "t_end_s": horizon,
        "periods": len(grid_t) - 1,
        "tail_window_s": [t_tail, horizon],
        "state_scale": point(scale[:n]),
        "sup_abs_output_tail": sups,
        "scenarios": {"none": {"disturbances": [{"kind": "none"}], "trajectories": int(y.shape[0]),
                               "sup_abs_output_tail": sups, "diverged": int(diverged.sum()),
                               "converged": int(converged.sum())}},
        "diverged": bool(diverged.any()),
        "n_diverged": int(diverged.sum()),
        "n_converged": int(converged.sum()),
        "n_trajectories": int(y.shape[0]),
        "trajectories": trajectories,
        "rtol": rtol,
        "integrator": INTEGRATOR_NAME + "; one call per sampling period, the controls held as constant states",
    }


def _dataset(model: "SampledModel", p: Prepared, recorder: Any, names: Sequence[str], converged: Any, diverged: Any,
             scale: "FloatArray", horizon: float, t_tail: float, rtol: float) -> Any:
    """The series (:func:`lyapcheck.models.engines.series.model_dataset` over the plant's loop), the states
    as ``x`` and the held controls as ``u`` (trajectory, time, control)."""
    from lyapcheck.models.engines.series import model_dataset

    S = len(converged)
    full = model_dataset(recorder, states=p.model.states, outputs=names, output_values=p.output_values,
                         starts_per_row=np.arange(S), scenarios_per_row=["none"] * S, converged=converged,
                         diverged=diverged, escape=(p.equilibrium, p.box(ESCAPE_FACTOR, scale)),
                         attrs={"model": model.name, "file": str(model.source), "t_end_s": horizon,
                                "tail_window_start_s": t_tail, "integrator": INTEGRATOR_NAME, "rtol": rtol,
                                "period_s": float(model.period), "hold": HOLD_TEXT})
    x = full["x"].sel(state=list(model.states))
    u = full["x"].sel(state=list(model.controls)).rename(state="control")
    u.attrs = {"long_name": "control, held between samples"}
    return full.drop_vars("x").drop_dims("state").assign(x=x, u=u)


def plot_sampled(model: "SampledModel", p: Prepared, observer: _TailObserver, rows: Sequence[int],
                 held: "FloatArray | None", grid_t: "FloatArray", diverged: Any, scale: "FloatArray", t_tail: float,
                 path: str) -> None:
    """Each state against time and each held control as a staircase (the tail window shaded); for two
    states also the phase plane, dots at the starts. Every recorded trajectory is drawn whole; each view
    is the data's range within :data:`~lyapcheck.models.surfaces.simulate.PLOT_CLIP` state scales of the
    equilibrium, and matplotlib clips a curve at the axes (one that leaves that box and comes back is
    drawn on both sides of its excursion; a diverging one does not flatten the others)."""
    from lyapcheck.models.surfaces.plotting import clip_view, finish_figure, history_panel, new_figure, phase_plane

    n, m = model.n, len(model.controls)
    fig, axes = new_figure(n + m + (1 if n == 2 else 0), 2.6)
    box = p.box(PLOT_CLIP, scale)
    lo, hi = p.equilibrium - box, p.equilibrium + box
    drawn: list["FloatArray"] = []  # every drawn state and control, per column, for the views
    for i, r in enumerate(rows):
        colour, style = f"C{i % 10}", "--" if diverged[r] else "-"
        t, xs = observer.trajectory(r, PLOT_SAMPLES)
        for j in range(n):
            axes[j, 0].plot(t, xs[:, j], color=colour, lw=0.9, alpha=0.8, ls=style)
        for c in range(m):
            if held is not None:
                values = held[r, :, c]
                axes[n + c, 0].step(grid_t, np.append(values, values[-1]), where="post", color=colour, lw=0.9,
                                    alpha=0.8, ls=style)
            else:
                axes[n + c, 0].step(t, xs[:, n + c], where="post", color=colour, lw=0.9, alpha=0.8, ls=style)
        drawn.append(xs)  # (the controls are constant states of the plant's loop: their held values)
        if n == 2:
            axes[-1, 0].plot(xs[:, 0], xs[:, 1], color=colour, lw=0.8, alpha=0.8, ls=style)
            axes[-1, 0].plot(xs[0, 0], xs[0, 1], ".", color=colour, ms=3)
    every = np.vstack(drawn) if drawn else np.empty((0, n + m))
    labels = [*model.states, *(f"{u} = {model.controller_text[u]} (held)" for u in model.controls)]
    for j, label in enumerate(labels):
        history_panel(axes[j, 0], (t_tail, float(grid_t[-1])), "t (s)", label, 8 if j >= n else None)
        clip_view(axes[j, 0], "y", every[:, j], float(lo[j]), float(hi[j]))
    if n == 2:
        ax = axes[-1, 0]
        phase_plane(ax, p.equilibrium[:2], model.states, label="equilibrium",
                    title="phase plane (dots: starts; dashed: diverged)")
        for j, axis in enumerate("xy"):
            clip_view(ax, axis, every[:, j], float(lo[j]), float(hi[j]))
    finish_figure(fig, f"lyapcheck simulate: {model.name}, sampled every {float(model.period):.6g} s, zero-order "
                       f"hold\n(tail window shaded: the last {TAIL_FRACTION:.0%})", path)

__all__ = ["MODE", "MIN_PERIODS", "MAX_DEFAULT_PERIODS", "FALLBACK_PERIODS", "MAX_PERIODS", "ControlLaw",
           "check_horizon", "default_periods", "default_starts", "instants", "plot_sampled", "prepare_sampled",
           "refuse", "run_sampled"]
