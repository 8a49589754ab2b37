"""``simulate`` of a discrete-time map (``[model] time = "discrete"``): the map iterated, ``x[k+1] = f(x[k])``.

A map has no time derivative to integrate: its simulation is the sequence of its iterates, a whole
number of steps (``--steps N``, default :data:`DEFAULT_STEPS`; ``--t-end`` is refused on a map). The
disturbances are held at 0 (the document says ``"disturbances": "zero"``; scenarios other than ``none``,
``--worst-case`` and ``--certificate`` are refused in one line). Everything is measured as in
continuous time (:mod:`lyapcheck.models.surfaces.simulate`): the state scale, ``converged`` (the last
iterate within :data:`~lyapcheck.models.surfaces.simulate.CONVERGENCE_RADIUS` state scales of the fixed
point), ``diverged`` (an iterate left :data:`~lyapcheck.models.surfaces.simulate.ESCAPE_FACTOR` state
scales, or is not finite; its iteration stops there), the tail sup of every output over the last
:data:`~lyapcheck.models.surfaces.simulate.TAIL_FRACTION` of the steps. The plot draws each output
against the step as a staircase (the value holds from one step to the next) and, for two states, the
iterates in the plane as dots.
"""

from __future__ import annotations

import time
from fractions import Fraction
from typing import TYPE_CHECKING, Any, Final, Sequence

import numpy as np

from lyapcheck.errors import InvalidParameter
from lyapcheck.models.language.modelfile import Model, field_at
from lyapcheck.models.surfaces.simulate import (CONVERGENCE_RADIUS, ESCAPE_FACTOR, MAX_PLOTTED_ROWS, TAIL_FRACTION,
                                                UNIT_SCALE, CompiledPolys, ModelRun, _output_poly)
from lyapcheck.sos.polynomials import Ring

if TYPE_CHECKING:  # pragma: no cover
    from numpy.typing import NDArray

    from lyapcheck.models.language.recast import RecastModel

    FloatArray = NDArray[np.float64]

#: iterations when ``--steps`` is not given
DEFAULT_STEPS: Final = 50
#: the most iterations (one row of states per step and start is kept)
MAX_STEPS: Final = 100_000
#: the most start x step rows kept in memory
MAX_CELLS: Final = 20_000_000
#: what the document's ``mode`` says
MODE: Final = "iteration"


def check_steps(steps: object) -> int:
    """``steps``: a whole number in ``1..MAX_STEPS`` (an ``int`` or its decimal text)."""
    value: object = steps
    if isinstance(steps, str) and steps.strip().isdigit():
        value = int(steps.strip())
    if isinstance(value, bool) or not isinstance(value, int) or not 1 <= value <= MAX_STEPS:
        raise InvalidParameter("steps", f"a whole number of iterations of the map in 1..{MAX_STEPS}", steps)
    return value


class MapIterator:
    """``f`` of a map at ``(batch, n)`` states, every disturbance 0: numerators and denominators in one
    evaluation. A map with functions (a :class:`~lyapcheck.models.language.recast.RecastModel`, whose
    system is the recast displacement ``F(x) - x``) is ``x`` plus that displacement, every function
    evaluated by numpy from its definition (:class:`~lyapcheck.models.engines.recast_numeric.FloatLoop`, as
    ``simulate`` evaluates a loop with functions)."""

    def __init__(self, model: "Model | RecastModel") -> None:
        self.n, self.m = model.n, len(model.disturbances)
        self.displacement = None
        if not isinstance(model, Model):
            from lyapcheck.models.engines.recast_numeric import FloatLoop

            self.displacement = FloatLoop(model.system)  # (its disturbances at 0: lyapcheck.models.language.recast)
            return
        rhs = field_at(model)
        self.polys = CompiledPolys(model.state_ring, [r.numerator for r in rhs] + [r.denominator for r in rhs])

    def __call__(self, x: "FloatArray") -> "FloatArray":
        if self.displacement is not None:
            with np.errstate(all="ignore"):  # an overflow or a pole: a non-finite iterate, diverged
                return x + self.displacement(x)
        xd = x if not self.m else np.concatenate([x, np.zeros((x.shape[0], self.m))], axis=1)
        values = self.polys(xd)
        with np.errstate(all="ignore"):  # a denominator 0 or an overflow: a non-finite iterate, diverged
            return values[:, :self.n] / values[:, self.n:]


def iterate(model: "Model | RecastModel", starts: "FloatArray", steps: int) -> "FloatArray":
    """The iterates, ``(starts, steps + 1, n)`` (the start first); a row that leaves the escape box or is not
    finite keeps that iterate and NaN after it."""
    from lyapcheck.models.engines.iteration import iterate_map

    eq = np.array([float(v) for v in model.equilibrium])
    out = np.full((starts.shape[0], steps + 1, model.n), np.nan)
    out[:, 0] = starts

    def record(k: int, rows: "NDArray[np.intp]", x: "FloatArray") -> None:
        out[rows, k] = x

    iterate_map(MapIterator(model), starts, steps, center=eq, escape=ESCAPE_FACTOR * scale_of(model, starts),
                observe=record)
    return out


def scale_of(model: "Model | RecastModel", starts: "FloatArray") -> "FloatArray":
    """Per state, the natural scale: the largest of the fixed point's size, the starts' distance from it
    and the ``[domain]``'s half-width (:data:`UNIT_SCALE` where all are 0)."""
    eq = np.array([float(v) for v in model.equilibrium])
    parts = [np.abs(eq)]
    if len(starts):
        parts.append(np.max(np.abs(starts - eq), axis=0))
    if model.domain:
        parts.append(np.array([max(abs(float(model.domain[s][0]) - e), abs(float(model.domain[s][1]) - e))
                               for s, e in zip(model.states, eq)]))
    scale = np.max(np.vstack(parts), axis=0)
    return np.where(scale > 0, scale, UNIT_SCALE)


def default_starts(model: "Model | RecastModel") -> "tuple[FloatArray, str]":
    """The fixed point and a grid over the ``[domain]`` (as in continuous time:
    :func:`lyapcheck.models.surfaces.simulate.default_starts`), or without a domain the fixed point and
    ``x_eq +- NEAR_START_FRACTION`` state scales along each state; and a sentence saying which."""
    from lyapcheck.models.engines.numeric import grid_starts
    from lyapcheck.models.surfaces.simulate import (DEFAULT_GRID_LIMIT, DEFAULT_GRID_MAX, DEFAULT_GRID_MIN,
                                                    NEAR_START_FRACTION)

    eq = np.array([float(v) for v in model.equilibrium])
    if model.domain:
        fits = [k for k in range(DEFAULT_GRID_MIN, DEFAULT_GRID_MAX + 1) if k ** model.n <= DEFAULT_GRID_LIMIT]
        per_state = max(fits) if fits else DEFAULT_GRID_MIN
        grid = grid_starts(model.domain, model.states, per_state, DEFAULT_GRID_LIMIT)
        grid = grid[np.any(grid != eq, axis=1)]
        how = (f"the fixed point and a {per_state}-per-state grid over [domain]" if fits
               else f"the fixed point and {DEFAULT_GRID_LIMIT} seeded uniform points in [domain]")
        return np.vstack([eq[None, :], grid]), how
    scale = scale_of(model, np.zeros((0, model.n)))
    near = [eq + sign * NEAR_START_FRACTION * scale[i] * np.eye(model.n)[i] for i in range(model.n) for sign in (1, -1)]
    return (np.vstack([eq[None, :], *near]),
            f"the fixed point and x_eq +- {NEAR_START_FRACTION:g} x the state scale along each state (no [domain])")


def run_map(model: "Model | RecastModel", starts: "FloatArray", how: str, *, steps: int | str | None = None, plot: str | None = None,
            series: bool = False) -> ModelRun:
    """Iterate the map from each start (see the module docstring); the document and, with ``series``, the
    iterates as an :class:`xarray.Dataset` over ``step``."""
    begin = time.perf_counter()
    count = DEFAULT_STEPS if steps is None else check_steps(steps)
    if starts.shape[0] * (count + 1) > MAX_CELLS:
        raise InvalidParameter("steps", f"at most {MAX_CELLS} starts x steps (MAX_CELLS); {starts.shape[0]} starts",
                               count)
    xs = iterate(model, starts, count)
    eq = np.array([float(v) for v in model.equilibrium])
    scale = scale_of(model, starts)
    names = tuple(model.outputs)
    out_polys = CompiledPolys(Ring(model.states), [_without_disturbances(model, y) for y in names])
    flat = xs.reshape(-1, model.n)
    finite = np.all(np.isfinite(flat), axis=1)
    values = np.full((flat.shape[0], len(names)), np.nan)
    if finite.any():
        values[finite] = out_polys(flat[finite])
    ys = values.reshape(xs.shape[0], count + 1, len(names))
    y_eq = out_polys(eq[None, :])[0]
    first_tail = int(np.floor((1 - TAIL_FRACTION) * count))
    final = xs[:, -1]
    diverged = ~np.all(np.isfinite(final), axis=1)
    converged = ~diverged & np.all(np.abs(final - eq) <= CONVERGENCE_RADIUS * scale, axis=1)
    with np.errstate(invalid="ignore"):
        tail = np.abs(ys[:, first_tail:] - y_eq)
    sup = np.where(diverged[:, None], np.inf, np.nanmax(np.where(np.isnan(tail), -np.inf, tail), axis=1))

    def point(x: "FloatArray") -> dict[str, float | None]:
        return {s: (float(v) if np.isfinite(v) else None) for s, v in zip(model.states, x)}

    def last(r: int) -> "FloatArray":
        rows = xs[r][np.all(np.isfinite(xs[r]), axis=1)]
        return rows[-1] if len(rows) else xs[r, 0]

    trajectories = []
    for r in range(xs.shape[0]):
        left = int(np.argmax(~np.all(np.isfinite(xs[r]), axis=1))) if diverged[r] else None
        trajectories.append({
            "start": r, "scenario": "none", "disturbance": {"kind": "none"},
            "sup_abs_output_tail": {y: (float(sup[r, o]) if np.isfinite(sup[r, o]) else None)
                                    for o, y in enumerate(names)},
            "final_state": point(last(r)), "converged": bool(converged[r]), "diverged": bool(diverged[r]),
            "failure": (f"left the escape box ({ESCAPE_FACTOR:g} state scales) or not finite after step {left - 1}"
                        if left is not None else None),
        })
    ok = ~diverged
    sups = {y: (float(np.max(sup[ok, o])) if ok.any() else None) for o, y in enumerate(names)}
    doc: dict[str, Any] = {
        "mode": MODE,
        "time": "discrete",
        "model": {"name": model.name, "file": model.source, "sha256": model.sha256, "overrides": dict(model.overrides)},
        "states": list(model.states),
        "equilibrium": point(eq),
        "disturbance_bounds": {k: float(b) for k, b in model.disturbances.items()},
        "disturbances": "zero",
        "outputs": dict(model.output_text),
        "starts": [point(x) for x in starts],
        "starts_from": how,
        "steps": count,
        "tail_window_steps": [first_tail, count],
        "state_scale": point(scale),
        "sup_abs_output_tail": sups,
        "scenarios": {"none": {"disturbances": [{"kind": "none"}], "trajectories": int(xs.shape[0]),
                               "sup_abs_output_tail": sups, "diverged": int(diverged.sum()),
                               "converged": int(converged.sum())}},
        "diverged": bool(diverged.any()),
        "n_diverged": int(diverged.sum()),
        "n_converged": int(converged.sum()),
        "n_trajectories": int(xs.shape[0]),
        "trajectories": trajectories,
    }
    if plot is not None:
        plot_iterates(model, xs, ys, names, diverged, first_tail, str(plot))
        doc["plot"] = str(plot)
    doc["wall_time_s"] = time.perf_counter() - begin
    return ModelRun(document=doc, series=_dataset(model, xs, ys, names, converged, diverged) if series else None)


def _without_disturbances(model: "Model | RecastModel", name: str) -> Any:
    """An output as a polynomial of the states alone (outputs never depend on a disturbance)."""
    if not isinstance(model, Model):  # a map with functions: its outputs are read over the states already
        return model.outputs[name]
    full = model.state_ring
    y = _output_poly(model, name)
    return full.restrict(full.substitute(y, {d: Fraction(0) for d in model.disturbances}), Ring(model.states))


def _dataset(model: "Model | RecastModel", xs: "FloatArray", ys: "FloatArray", names: Sequence[str], converged: "FloatArray",
             diverged: "FloatArray") -> Any:
    """The iterates as an :class:`xarray.Dataset`: ``x`` (trajectory, step, state) and ``y`` (trajectory,
    step, output), ``step`` a coordinate (a map has steps, not seconds)."""
    import xarray as xr

    steps = np.arange(xs.shape[1])
    return xr.Dataset(
        {"x": (("trajectory", "step", "state"), xs), "y": (("trajectory", "step", "output"), ys),
         "converged": (("trajectory",), np.asarray(converged)), "diverged": (("trajectory",), np.asarray(diverged))},
        coords={"trajectory": np.arange(xs.shape[0]), "step": steps, "state": list(model.states),
                "output": list(names)},
        attrs={"model": model.name, "file": str(model.source), "time": "discrete", "steps": int(steps[-1])})


def plot_iterates(model: "Model | RecastModel", xs: "FloatArray", ys: "FloatArray", names: Sequence[str], diverged: "FloatArray",
                  first_tail: int, path: str) -> None:
    """Each output against the step as a staircase (the tail steps shaded) and, for two states, the
    iterates in the plane (dots joined by thin lines)."""
    from lyapcheck.models.surfaces.plotting import finish_figure, history_panel, new_figure, phase_plane

    rows = sorted(set(np.linspace(0, xs.shape[0] - 1, min(xs.shape[0], MAX_PLOTTED_ROWS)).round().astype(int)))
    fig, axes = new_figure(len(names) + (1 if model.n == 2 else 0), 3.0)
    steps = np.arange(xs.shape[1])
    for o, y in enumerate(names):
        ax = axes[o, 0]
        for i, r in enumerate(rows):
            ax.step(steps, ys[r, :, o], where="post", color=f"C{i % 10}", lw=0.9, alpha=0.8,
                    ls="--" if diverged[r] else "-")
        text = model.output_text.get(y, y)
        history_panel(ax, (first_tail, steps[-1]), "step k", y if text == y else f"{y} = {text}")
    if model.n == 2:
        ax = axes[-1, 0]
        for i, r in enumerate(rows):
            ax.plot(xs[r, :, 0], xs[r, :, 1], ".-", color=f"C{i % 10}", lw=0.4, ms=3, alpha=0.8)
        phase_plane(ax, [float(v) for v in model.equilibrium], model.states, label="fixed point",
                    title="iterates in the plane")
    finish_figure(fig, f"lyapcheck simulate: {model.name}, a discrete-time map iterated (tail steps shaded: the last "
                       f"{TAIL_FRACTION:.0%})", path)


__all__ = ["DEFAULT_STEPS", "MAX_STEPS", "MODE", "check_steps", "MapIterator", "iterate", "scale_of", "default_starts",
           "run_map",
           "plot_iterates"]
