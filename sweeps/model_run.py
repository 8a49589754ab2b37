"""Run (or resume) a model sweep: a grid of points, or a refinement tree of boxes.

Points. The grid is cut into Zarr chunks (:func:`sweeps.store.block_regions`), one unit of work
each; chunks already ``done`` are skipped, and each unit's results are written as it arrives.

Boxes. The tree of :mod:`sweeps.boxes_run`: the axes' values are the edges of the first boxes
(ids ``0 .. n0 - 1`` in C order, level 0). Level by level every box is certified and cross-checked
(:func:`sweeps.model_evaluate.evaluate_model_boxes`); then, in id order, each box that is undecided
(``not_certified``, or ``refuted`` with a corner that is not unstable: the part that is stable may
still be proved), wider than ``min_relative_width`` (:func:`relative_width`) and within the
``max_boxes`` budget is marked ``split`` and its halves (:func:`split`) get the next two ids. The ids
are therefore a function of the spec and of earlier statuses alone, and a resumed run replays the
tree, reads the statuses of the boxes that are ``done`` and computes only the others.

Work goes to the runners of :mod:`sweeps.runners` (in-process, local processes or Dask), at most
two units in flight per worker; the progress callback is :data:`sweeps.run.Progress`.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from fractions import Fraction
from pathlib import Path
from typing import Any, Callable, Iterator, Mapping, Sequence

import numpy as np

from sweeps.model_schema import BOXES_MODE, POINTS_MODE
from sweeps.model_spec import ModelAxis, ModelSweepSpec, initial_cells
from sweeps.model_store import ModelBoxStore, ModelPointStore
from sweeps.run import IN_FLIGHT_PER_WORKER, Progress
from sweeps.runners import Runner
from sweeps.schema import BOX_STATUS_CODES
from sweeps.store import Region, block_regions

#: exact edges of a box, by swept parameter (spec order)
Cell = dict[str, tuple[Fraction, Fraction]]
#: a box of the tree: (id, edges, parent id, level)
Node = tuple[int, Cell, int, int]


@dataclass
class ModelSweepReport:
    """What a run of a model sweep did (the store holds the results). ``seconds_certify`` and
    ``seconds_cross_check`` are per item computed in this run, with its ``statuses_now`` (codes)."""

    path: Path
    mode: str
    computed_now: int
    total: int
    wall_seconds: float
    model_sha256: str
    seconds_certify: list[float] = field(default_factory=list)
    seconds_cross_check: list[float] = field(default_factory=list)
    statuses_now: list[int] = field(default_factory=list)

    def keep(self, result: Mapping[str, np.ndarray]) -> None:
        self.seconds_certify += [float(s) for s in result["seconds_certify"]]
        self.seconds_cross_check += [float(s) for s in result["seconds_cross_check"]]
        self.statuses_now += [int(s) for s in result["status"]]


def relative_width(cell: Cell, axes: Sequence[ModelAxis]) -> dict[str, float]:
    """Each axis's width of a box: ``hi / lo - 1`` on a log axis, ``(hi - lo)`` over the window's
    width on a linear one (a parameter may be 0 or negative there, so no ratio to it is taken)."""
    out = {}
    for axis in axes:
        lo, hi = cell[axis.name]
        if axis.measure == "log":
            out[axis.name] = float(hi / lo) - 1.0
        else:
            out[axis.name] = float((hi - lo) / (Fraction(axis.values[-1]) - Fraction(axis.values[0])))
    return out


def split(cell: Cell, axes: Sequence[ModelAxis]) -> tuple[Cell, Cell]:
    """Halve the axis of the largest :func:`relative_width` (the first such axis on a tie), exactly."""
    widths = relative_width(cell, axes)
    name = max(widths, key=lambda k: widths[k])
    lo, hi = cell[name]
    mid = (lo + hi) / 2
    return {**cell, name: (lo, mid)}, {**cell, name: (mid, hi)}


def _pump(runner: Runner, units: Iterator[tuple[Any, Callable[..., Any], tuple[Any, ...]]],
          write: Callable[[Any, Mapping[str, np.ndarray]], int], progress: Progress | None, total: int) -> int:
    """Keep the runner busy with ``units`` (key, function, arguments); write each result as it
    arrives (``write`` returns how many items it held). Returns the items finished."""
    limit = max(1, IN_FLIGHT_PER_WORKER * runner.workers)
    pending: dict[Any, Any] = {}
    finished = 0
    exhausted = False
    while True:
        while not exhausted and len(pending) < limit:
            unit = next(units, None)
            if unit is None:
                exhausted = True
                break
            key, fn, args = unit
            pending[runner.submit(fn, *args)] = key
        if not pending:
            return finished
        done, _ = runner.wait_any(pending)
        for future in [f for f in pending if f in done]:
            key = pending.pop(future)
            count = write(key, future.result())
            finished += count
            if progress is not None:
                progress(count, total)


def _region_coords(spec: ModelSweepSpec, region: Region) -> np.ndarray:
    grids = np.meshgrid(*[np.asarray(a.values)[s] for a, s in zip(spec.axes, region)], indexing="ij")
    return np.stack([g.ravel() for g in grids], axis=1)


def _run_points(spec: ModelSweepSpec, store: ModelPointStore, runner: Runner, progress: Progress | None,
                report: ModelSweepReport) -> None:
    from sweeps.model_evaluate import evaluate_model_points

    done = store.done()
    todo = [r for r in block_regions(spec.shape, store.chunks) if not np.all(done[r])]
    total = sum(int(np.prod([s.stop - s.start for s in r])) for r in todo)
    report.total = spec.n_points
    if progress is not None:
        progress(0, total)

    def write(region: Region, result: Mapping[str, np.ndarray]) -> int:
        store.write_region(region, result)
        report.keep(result)
        return len(result["status"])

    units = ((r, evaluate_model_points, (spec.worker_text, _region_coords(spec, r))) for r in todo)
    report.computed_now = _pump(runner, units, write, progress, total)


def _to_json(cell: Cell) -> dict[str, list[str]]:
    return {name: [str(lo), str(hi)] for name, (lo, hi) in cell.items()}


def _run_boxes(spec: ModelSweepSpec, store: ModelBoxStore, runner: Runner, progress: Progress | None,
               report: ModelSweepReport) -> None:
    from sweeps.model_evaluate import evaluate_model_boxes

    assert spec.boxes is not None
    status = store.read("status")
    corners = store.read("unstable_corners")
    done = store.read("done")
    level: list[Node] = [(i, cell, -1, 0) for i, cell in enumerate(initial_cells(spec))]
    next_id = len(level)
    total = 0
    all_corners = 2 ** len(spec.axes)
    undecided = (BOX_STATUS_CODES["not_certified"], BOX_STATUS_CODES["split"])

    def write(unit: list[Node], result: Mapping[str, np.ndarray]) -> int:
        rows = np.array([node[0] for node in unit])
        values: dict[str, Any] = dict(result)
        for axis in spec.axes:
            values[f"lo_{axis.name}"] = np.array([float(node[1][axis.name][0]) for node in unit])
            values[f"hi_{axis.name}"] = np.array([float(node[1][axis.name][1]) for node in unit])
        values["parent"] = np.array([node[2] for node in unit], np.int32)
        values["level"] = np.array([node[3] for node in unit], np.int16)
        values["done"] = np.ones(len(unit), bool)
        store.write_rows(rows, values)
        status[rows] = result["status"]
        corners[rows] = result["unstable_corners"]
        report.keep(result)
        return len(unit)

    while level:
        todo = [node for node in level if not done[node[0]]]
        total += len(todo)
        if progress is not None:
            progress(0, total)
        size = max(1, min(spec.chunk_size, math.ceil(len(todo) / (IN_FLIGHT_PER_WORKER * max(runner.workers, 1)))))
        groups = [todo[i:i + size] for i in range(0, len(todo), size)]
        units = ((g, evaluate_model_boxes, (spec.worker_text, [(node[0], _to_json(node[1])) for node in g]))
                 for g in groups)
        report.computed_now += _pump(runner, units, write, progress, total)
        children: list[Node] = []
        marked = []
        for box_id, cell, _, depth in level:
            open_ = status[box_id] in undecided or (status[box_id] == BOX_STATUS_CODES["refuted"]
                                                    and 0 <= corners[box_id] < all_corners)
            if open_ and max(relative_width(cell, spec.axes).values()) > spec.boxes.min_relative_width \
                    and next_id + 2 <= spec.boxes.max_boxes:
                left, right = split(cell, spec.axes)
                children += [(next_id, left, box_id, depth + 1), (next_id + 1, right, box_id, depth + 1)]
                next_id += 2
                if status[box_id] != BOX_STATUS_CODES["split"]:
                    marked.append(box_id)
        if marked:
            codes = np.full(len(marked), BOX_STATUS_CODES["split"], np.int8)
            store.write_rows(np.array(marked), {"status": codes})
            status[marked] = codes
        level = children
    report.total = next_id


def run_model_sweep(spec: ModelSweepSpec, out: str | Path, *, runner: Runner, progress: Progress | None = None,
                    on_ready: Callable[[], None] | None = None) -> ModelSweepReport:
    """Run (or resume) the model sweep ``spec`` into the store at ``out`` (module docstring).

    Parameters
    ----------
    spec
        The validated spec (:func:`sweeps.model_spec.load_model_spec`).
    out
        The Zarr store: created, or resumed when it holds the same spec, model and versions.
    runner
        Where units run (:func:`sweeps.runners.make_runner`).
    progress, on_ready
        Called with (items finished, current total) as units complete; and once the workers are up.
    """
    start = time.perf_counter()
    points = spec.mode == "points"
    store: ModelPointStore | ModelBoxStore = (ModelPointStore.open_or_create(out, spec) if points
                                              else ModelBoxStore.open_or_create(out, spec))
    report = ModelSweepReport(path=Path(out), mode=POINTS_MODE if points else BOXES_MODE, computed_now=0, total=0,
                              wall_seconds=0.0, model_sha256=spec.model_sha256)
    runner.start()
    if on_ready is not None:
        on_ready()
    try:
        if isinstance(store, ModelPointStore):
            _run_points(spec, store, runner, progress, report)
        else:
            _run_boxes(spec, store, runner, progress, report)
    except BaseException:
        runner.close(cancel=True)
        raise
    runner.close()
    report.wall_seconds = time.perf_counter() - start
    return report


__all__ = ["ModelSweepReport", "run_model_sweep", "relative_width", "split"]
