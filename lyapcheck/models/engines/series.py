"""A model simulation's time series as an :class:`xarray.Dataset` (``simulate(model=...).series``).

The batched integrator (:mod:`lyapcheck.integrator`) hands every accepted step to
:class:`SeriesRecorder`, which samples the recorded trajectories at one common time grid as the
steps come (cubic Hermite inside a step: the integrator's own dense output, no extra evaluation of
the field). Memory is therefore rows x samples x states, whatever the number of steps.

The dataset (:func:`model_dataset`):

==============  ==================================  =============================================
name            dimensions                          what
==============  ==================================  =============================================
``x``           (trajectory, time, state)           the state, SI, in the declared coordinates
``y``           (trajectory, time, output)          each ``[outputs]`` expression along it
``time``        (time,)                             s, from 0 to the horizon, :data:`SERIES_SAMPLES`
``trajectory``  (trajectory,)                       the row of ``document["trajectories"]``
``start``       (trajectory,)                       the row of ``document["starts"]``
``scenario``    (trajectory,)                       ``none``, ``constant``, ``bang-bang``, ``square``
``converged``   (trajectory,)                       as in the document
``diverged``    (trajectory,)                       as in the document
==============  ==================================  =============================================

A trajectory stopped early is NaN after the sample where it stopped: the integrator failed, or it
left the escape box (``escape`` state scales around the equilibrium), where the simulation holds
it still (:mod:`lyapcheck.models.surfaces.simulate`) and the series ends it. With more than :data:`MAX_SERIES_ROWS` trajectories, evenly spaced ones are kept (the
first and the last among them) and ``attrs["note"]`` says so.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any, Final, Sequence

import numpy as np
import numpy.typing as npt

from lyapcheck.integrator import hermite

if TYPE_CHECKING:  # pragma: no cover
    import xarray as xr

FloatArray = npt.NDArray[np.float64]
IntArray = npt.NDArray[np.intp]

#: samples of the common time grid (the horizon in SERIES_SAMPLES - 1 equal intervals; the largest
#: step is a hundredth of the horizon, so each step holds about five samples)
SERIES_SAMPLES: Final = 501
#: the most trajectories a series holds (rows x samples x (states + outputs) floats)
MAX_SERIES_ROWS: Final = 1024


def recorded_rows(rows_total: int, limit: int = MAX_SERIES_ROWS) -> list[int]:
    """Every row, or ``limit`` evenly spaced ones (the first and the last among them)."""
    if rows_total <= limit:
        return list(range(rows_total))
    return sorted(set(np.linspace(0, rows_total - 1, limit).round().astype(int).tolist()))


class SeriesRecorder:
    """An integrator observer sampling the chosen rows at ``time`` (see the module's docstring)."""

    def __init__(self, rows: Sequence[int], rows_total: int, n: int, t_end: float,
                 samples: int = SERIES_SAMPLES) -> None:
        self.rows = np.asarray(rows, dtype=np.intp)
        self.slot = np.full(rows_total, -1, dtype=np.intp)
        self.slot[self.rows] = np.arange(self.rows.size)
        self.time = np.linspace(0.0, float(t_end), samples)
        self.x = np.full((self.rows.size, samples, n), np.nan)

    def start(self, index: IntArray, t: FloatArray, y: FloatArray, f: FloatArray) -> None:
        slots = self.slot[index]
        at_zero = (slots >= 0) & (t == self.time[0])
        self.x[slots[at_zero], 0] = y[at_zero]

    def step(self, index: IntArray, t0: FloatArray, t1: FloatArray, y0: FloatArray, y1: FloatArray,
             f0: FloatArray, f1: FloatArray) -> None:
        slots = self.slot[index]
        mine = np.flatnonzero(slots >= 0)
        if not mine.size:
            return
        # the grid points in (t0, t1] of each recorded row (t0's own was sampled by the step before)
        first = np.searchsorted(self.time, t0[mine], side="right")
        last = np.searchsorted(self.time, t1[mine], side="right")
        counts = last - first
        keep = counts > 0
        if not keep.any():
            return
        rows = np.repeat(mine[keep], counts[keep])
        offsets = np.arange(rows.size) - np.repeat(np.cumsum(counts[keep]) - counts[keep], counts[keep])
        k = np.repeat(first[keep], counts[keep]) + offsets
        h = t1[rows] - t0[rows]
        theta = np.where(h > 0, (self.time[k] - t0[rows]) / np.where(h > 0, h, 1.0), 1.0)
        self.x[slots[rows], k] = hermite(theta, h, y0[rows], y1[rows], f0[rows], f1[rows])


def model_dataset(recorder: SeriesRecorder, *, states: Sequence[str], outputs: Sequence[str],
                  output_values: Any, starts_per_row: npt.ArrayLike, scenarios_per_row: Sequence[str],
                  converged: npt.ArrayLike, diverged: npt.ArrayLike, escape: tuple[FloatArray, FloatArray],
                  attrs: dict[str, Any]) -> "xr.Dataset":
    """The recorded rows as a dataset (``output_values`` maps ``(k, n)`` states to ``(k, outputs)``;
    ``escape`` is the escape box, its centre and half-widths)."""
    import xarray as xr

    rows = recorder.rows
    centre, half = escape
    with np.errstate(invalid="ignore"):
        out = np.any(np.abs(recorder.x - centre) > half, axis=2)  # (rows, samples)
    for r in np.flatnonzero(out.any(axis=1)):
        recorder.x[r, int(np.argmax(out[r])) + 1:] = np.nan  # held still outside the box: ended there
    flat = recorder.x.reshape(-1, len(states))
    with np.errstate(over="ignore", invalid="ignore", divide="ignore"):
        y = (np.asarray(output_values(flat), dtype=np.float64) if len(outputs)
             else np.zeros((flat.shape[0], 0))).reshape(rows.size, recorder.time.size, len(outputs))
    if rows.size < len(scenarios_per_row):
        attrs = {**attrs, "note": f"{rows.size} of {len(scenarios_per_row)} trajectories, evenly spaced "
                                  f"(MAX_SERIES_ROWS = {MAX_SERIES_ROWS})"}
    return xr.Dataset(
        data_vars={"x": (("trajectory", "time", "state"), recorder.x, {"long_name": "state"}),
                   "y": (("trajectory", "time", "output"), y, {"long_name": "output"})},
        coords={"trajectory": rows, "time": ("time", recorder.time, {"units": "s"}),
                "state": list(states), "output": list(outputs),
                "start": ("trajectory", np.asarray(starts_per_row, dtype=np.intp)[rows]),
                "scenario": ("trajectory", np.asarray(scenarios_per_row, dtype=object)[rows].astype(str)),
                "converged": ("trajectory", np.asarray(converged, dtype=bool)[rows]),
                "diverged": ("trajectory", np.asarray(diverged, dtype=bool)[rows])},
        attrs=attrs)


__all__ = ["SERIES_SAMPLES", "MAX_SERIES_ROWS", "SeriesRecorder", "recorded_rows", "model_dataset"]
