"""Run a sweep: hand units of work to a runner, stream each result into the store.

Memory stays flat in the number of points: at most ``2 * workers`` units are in flight, and a
unit's results are written to the store (and dropped) as soon as it completes. Only the grid's
``done`` flags (one byte per point) and, in refinement mode, one class's status per point are
held.
"""

from __future__ import annotations

import logging
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable, Iterator

import numpy as np

from sweeps.evaluate import Evaluator, Result, evaluate_unit
from sweeps.refine import coarse_cells, coarse_points, split
from sweeps.runners import Runner, make_runner
from sweeps.schema import STATUS_CODES
from sweeps.spec import SweepSpec
from sweeps.store import Region, Store, block_regions

log = logging.getLogger(__name__)

#: units in flight per worker: one running, one queued, so no worker waits for the main process
IN_FLIGHT_PER_WORKER = 2

#: progress callback: (points just finished, current total of points to compute)
Progress = Callable[[int, int], None]


@dataclass
class RefinementReport:
    """How many points the quadtree computed against the full grid of the same resolution."""

    cls: str
    levels: int
    points_computed: int
    full_grid_points: int

    @property
    def saved_fraction(self) -> float:
        return 1.0 - self.points_computed / self.full_grid_points


@dataclass
class SweepReport:
    """What a run did (the store holds the results)."""

    path: Path
    grid_points: int
    computed_now: int
    wall_seconds: float
    refinement: RefinementReport | None = None
    extra: dict[str, Any] = field(default_factory=dict)


def _coords(spec: SweepSpec, index: np.ndarray) -> np.ndarray:
    """SI coordinates ``(n, ndim)`` of integer grid indices ``(n, ndim)``."""
    values = [np.asarray(a.values) for a in spec.axes]
    return np.stack([values[d][index[:, d]] for d in range(len(values))], axis=1)


def _region_index(region: Region) -> np.ndarray:
    grids = np.meshgrid(*[np.arange(s.start, s.stop) for s in region], indexing="ij")
    return np.stack([g.ravel() for g in grids], axis=1)


def _pump(runner: Runner, units: Iterator[tuple[Any, np.ndarray]], spec: SweepSpec, evaluator: Evaluator,
          write: Callable[[Any, Result], None], progress: Progress | None, total: int) -> int:
    """Keep the runner busy with ``units``; write each result as it arrives. Returns points done."""
    limit = max(1, IN_FLIGHT_PER_WORKER * runner.workers)
    pending: dict[Any, tuple[Any, int]] = {}
    finished = 0
    exhausted = False
    while True:
        while not exhausted and len(pending) < limit:
            try:
                key, index = next(units)
            except StopIteration:
                exhausted = True
                break
            future = runner.submit(evaluator, spec.text, _coords(spec, index))
            pending[future] = (key, len(index))
        if not pending:
            return finished
        done, _ = runner.wait_any(pending)
        # write in submission order among the finished ones: the store's bytes do not depend
        # on it (chunks are disjoint), but logs and progress read more naturally
        for future in [f for f in pending if f in done]:
            key, n = pending.pop(future)
            write(key, future.result())
            finished += n
            if progress is not None:
                progress(n, total)


def run_grid(spec: SweepSpec, store: Store, runner: Runner, evaluator: Evaluator,
             progress: Progress | None) -> int:
    """Every point of the grid, one Zarr chunk per unit; chunks already ``done`` are skipped."""
    done = store.done()
    todo = [r for r in block_regions(spec.shape, store.chunks) if not np.all(done[r])]
    total = sum(int(np.prod([s.stop - s.start for s in r])) for r in todo)
    if progress is not None:
        progress(0, total)
    units = ((r, _region_index(r)) for r in todo)
    return _pump(runner, units, spec, evaluator, store.write_region, progress, total)


def run_refined(spec: SweepSpec, store: Store, runner: Runner, evaluator: Evaluator,
                progress: Progress | None) -> tuple[int, RefinementReport]:
    """Quadtree refinement (:mod:`sweeps.refine`); resumes by skipping points already done."""
    assert spec.refine is not None
    shape = (spec.shape[0], spec.shape[1])
    status_name = f"status_{spec.refine.cls}"
    certified_code = STATUS_CODES["holds" if spec.refine.cls == "stabcond2" else "certified"]
    computed_now = 0
    total = 0

    def compute(points: np.ndarray) -> None:
        nonlocal computed_now, total
        done = store.done()
        todo = np.array([p for p in points if not done[tuple(p)]], dtype=np.intp).reshape(-1, 2)
        total += len(todo)
        if progress is not None:
            progress(0, total)
        chunks = [todo[i:i + spec.chunk_size] for i in range(0, len(todo), spec.chunk_size)]
        units = ((c, c) for c in chunks)
        computed_now += _pump(runner, units, spec, evaluator, lambda idx, res: store.write_points(idx, res),
                              progress, total)

    compute(coarse_points(shape, spec.refine.levels))
    cells = coarse_cells(shape, spec.refine.levels)
    for _ in range(spec.refine.levels):
        certified = np.asarray(store.group[status_name][...]) == certified_code
        cells, points = split(cells, certified)
        if not len(points):
            break
        compute(points)
    report = RefinementReport(spec.refine.cls, spec.refine.levels, int(store.done().sum()),
                              int(np.prod(spec.shape)))
    return computed_now, report


def run_sweep(spec: SweepSpec, out: str | Path, *, runner: Runner | None = None, scheduler: str | None = None,
              workers: int | None = None, evaluator: Evaluator = evaluate_unit,
              progress: Progress | None = None, on_ready: Callable[[], None] | None = None) -> SweepReport:
    """Run (or resume) ``spec`` into the store at ``out``.

    Parameters
    ----------
    spec
        The validated sweep spec.
    out
        Path of the Zarr store; created, or resumed when it holds the same spec.
    runner, scheduler, workers
        Where units run: a given runner, else a Dask cluster at ``scheduler``, else ``workers``
        local processes (default: all cores; 0 runs in this process).
    evaluator
        The unit function (``evaluate_unit``; the memory benchmark passes a cheap stub).
    progress
        Called with (points finished, current total) as units complete.
    on_ready
        Called once the workers are up, before the first unit is handed out (the command line
        starts its progress bar there, after the worker processes were forked).
    """
    start = time.perf_counter()
    store = Store.open_or_create(out, spec)
    runner = runner if runner is not None else make_runner(scheduler=scheduler, workers=workers)
    runner.start()
    if on_ready is not None:
        on_ready()
    refinement = None
    try:
        if spec.refine is None:
            computed = run_grid(spec, store, runner, evaluator, progress)
        else:
            computed, refinement = run_refined(spec, store, runner, evaluator, progress)
    except BaseException:
        runner.close(cancel=True)
        raise
    runner.close()
    return SweepReport(path=Path(out), grid_points=spec.n_points, computed_now=computed,
                       wall_seconds=time.perf_counter() - start, refinement=refinement)
