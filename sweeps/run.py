"""Run a sweep of any target: hand units of work to a runner, stream each result into the store.

One loop for every target (the paper's model, a model file; :mod:`sweeps.targets`):

* :func:`pump` keeps the runner busy: at most :data:`IN_FLIGHT_PER_WORKER` units per worker are in
  flight, and a unit's results are written to the store (and dropped) as soon as it completes, so
  memory stays flat in the number of points or boxes.
* :func:`run_points`: every point of the grid, one Zarr chunk per unit of work (in C order); chunks
  already ``done`` are skipped. :func:`run_refined` is the paper's quadtree refinement on a 2-D
  slice (:mod:`sweeps.refine`): the same units over the points the quadtree asks for.
* :func:`run_box_tree`: the refinement tree of boxes. The axes' values are the edges of the first
  boxes (ids ``0 .. n0 - 1`` in C order, level 0). Level by level every box is certified and
  cross-checked by the target's unit; then, in id order, each box that the target calls undecided
  (:attr:`BoxTree.undecided`), wider than ``min_relative_width`` (:attr:`BoxTree.width`) and within
  the ``max_boxes`` budget is marked ``split`` and its halves (:attr:`BoxTree.split`) get the next
  two ids. The ids are therefore a function of the spec and of earlier statuses alone, and a
  resumed run replays the tree, reads the statuses of the boxes that are ``done`` and computes only
  the others. Units are small groups of boxes of one level (a box costs seconds).

Each target's entry point is a few lines on these: :func:`run_sweep` (the paper's points),
:func:`run_boxes` (the paper's boxes) and :func:`run_model_sweep` (a model file, points or boxes).
Work goes to the runners of :mod:`sweeps.runners` (in-process, local processes or Dask).
"""

from __future__ import annotations

import logging
import math
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable, Iterator, Mapping, Sequence

import numpy as np

from sweeps.evaluate import (
    MODEL_SAFETY_CLASSES, MODEL_STABILITY_CLASSES, Evaluator, evaluate_boxes, evaluate_model_boxes, evaluate_model_points, evaluate_unit,
)
from sweeps.refine import coarse_cells, coarse_points, split
from sweeps.runners import Runner, make_runner
from sweeps.schema import BOX_STATUS_CODES, BOXES_MODE, POINTS_MODE, STATUS_CODES
from sweeps.spec import ModelSweepSpec, SweepSpec, initial_boxes, initial_cells, relative_width, split_cell
from sweeps.store import (
    BoxStore, GridStore, ModelBoxStore, ModelPointStore, Region, Store, TreeStore, block_regions,
)

log = logging.getLogger(__name__)

#: units in flight per worker: one running, one queued, so no worker waits for the main process
IN_FLIGHT_PER_WORKER = 2

#: progress callback: (items just finished, current total of items to compute)
Progress = Callable[[int, int], None]
#: a unit of work: (key handed back to ``write``, the function a worker runs, its arguments)
Unit = tuple[Any, Callable[..., Any], tuple[Any, ...]]
#: called with every unit's result as it is written (a run's report keeps its timings)
OnResult = Callable[[Mapping[str, np.ndarray]], None]


# -- what a run did -------------------------------------------------------------------------------
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
    """What a run of the paper's points sweep did (the store holds the results)."""

    path: Path
    grid_points: int
    computed_now: int
    wall_seconds: float
    refinement: RefinementReport | None = None
    extra: dict[str, Any] = field(default_factory=dict)


@dataclass
class BoxSweepReport:
    """What a run of the paper's box sweep did (the store holds the results)."""

    path: Path
    boxes_computed_now: int
    boxes_in_tree: int
    wall_seconds: float


@dataclass
class ModelSweepReport:
    """What a run of a model file's sweep did (the store holds the results). ``seconds_certify`` and
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


# -- the one loop -------------------------------------------------------------------------------
def pump(runner: Runner, units: Iterator[Unit], write: Callable[[Any, Mapping[str, np.ndarray]], int],
         progress: Progress | None, total: int) -> int:
    """Keep the runner busy with ``units``; write each result as it arrives (``write`` returns how
    many items it held). Returns the items finished."""
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
        # write in submission order among the finished ones: the store's bytes do not depend
        # on it (chunks are disjoint), but logs and progress read more naturally
        for future in [f for f in pending if f in done]:
            key = pending.pop(future)
            count = write(key, future.result())
            finished += count
            if progress is not None:
                progress(count, total)


def _running(runner: Runner, on_ready: Callable[[], None] | None, body: Callable[[], Any]) -> Any:
    """Start the runner, call ``on_ready`` (the workers are up), run ``body``; on any exception the
    runner is closed with its queued units cancelled."""
    runner.start()
    if on_ready is not None:
        on_ready()
    try:
        out = body()
    except BaseException:
        runner.close(cancel=True)
        raise
    runner.close()
    return out


# -- points ---------------------------------------------------------------------------------------
def region_coords(axes: Sequence[Any], region: Region) -> np.ndarray:
    """SI coordinates ``(n, ndim)`` of the points of ``region``, in C order."""
    grids = np.meshgrid(*[np.asarray(a.values)[s] for a, s in zip(axes, region)], indexing="ij")
    return np.stack([g.ravel() for g in grids], axis=1)


def _index_coords(axes: Sequence[Any], index: np.ndarray) -> np.ndarray:
    """SI coordinates ``(n, ndim)`` of integer grid indices ``(n, ndim)``."""
    values = [np.asarray(a.values) for a in axes]
    return np.stack([values[d][index[:, d]] for d in range(len(values))], axis=1)


def _size(region: Region) -> int:
    return int(np.prod([s.stop - s.start for s in region]))


def run_points(store: GridStore, runner: Runner, evaluator: Callable[..., Any], progress: Progress | None,
               on_result: OnResult | None = None) -> int:
    """Every point of the grid, one Zarr chunk per unit; chunks already ``done`` are skipped.
    ``evaluator(spec.worker_text, coords)`` runs in a worker. Returns the points computed."""
    spec = store.spec
    done = store.done()
    todo = [r for r in block_regions(spec.shape, store.chunks) if not np.all(done[r])]
    total = sum(_size(r) for r in todo)
    if progress is not None:
        progress(0, total)

    def write(region: Region, result: Mapping[str, np.ndarray]) -> int:
        store.write_region(region, result)
        if on_result is not None:
            on_result(result)
        return _size(region)

    units = ((r, evaluator, (spec.worker_text, region_coords(spec.axes, r))) for r in todo)
    return pump(runner, units, write, progress, total)


def run_refined(store: GridStore, runner: Runner, evaluator: Callable[..., Any], progress: Progress | None,
                ) -> tuple[int, RefinementReport]:
    """Quadtree refinement (:mod:`sweeps.refine`) of the paper's points; resumes by skipping points
    already done."""
    spec = store.spec
    assert spec.refine is not None
    shape = (spec.shape[0], spec.shape[1])
    status_name = f"status_{spec.refine.cls}"
    certified_code = STATUS_CODES["holds" if spec.refine.cls == "stabcond2" else "certified"]
    computed_now = 0
    total = 0

    def write(index: np.ndarray, result: Mapping[str, np.ndarray]) -> int:
        store.write_points(index, result)
        return len(index)

    def compute(points: np.ndarray) -> None:
        nonlocal computed_now, total
        done = store.done()
        todo = np.array([p for p in points if not done[tuple(p)]], dtype=np.intp).reshape(-1, 2)
        total += len(todo)
        if progress is not None:
            progress(0, total)
        chunks = [todo[i:i + spec.chunk_size] for i in range(0, len(todo), spec.chunk_size)]
        units = ((c, evaluator, (spec.worker_text, _index_coords(spec.axes, c))) for c in chunks)
        computed_now += pump(runner, units, write, progress, total)

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


# -- boxes ----------------------------------------------------------------------------------------
@dataclass(frozen=True)
class BoxTree:
    """What a target's box sweep gives the tree driver (:func:`run_box_tree`)."""

    #: the first boxes (the cells of the axes' grid, C order)
    initial: Sequence[Any]
    #: a box's two halves, exactly
    split: Callable[[Any], tuple[Any, Any]]
    #: a box's width, compared with ``min_relative_width``
    width: Callable[[Any], float]
    #: a box's edges as floats, by swept parameter (stored as ``lo_<p>``, ``hi_<p>``)
    edges: Callable[[Any], Mapping[str, tuple[float, float]]]
    #: what a worker receives for a box (picklable)
    payload: Callable[[Any], Any]
    #: the worker's function: ``unit(spec.worker_text, [(id, payload), ...])``
    unit: Callable[..., Any]
    #: the stored variables the split decision reads (kept in memory, updated as units end)
    tracked: tuple[str, ...]
    #: whether the box of row ``i`` is undecided (split further while wide enough and in budget)
    undecided: Callable[[Mapping[str, np.ndarray], int], bool]


def run_box_tree(store: TreeStore, runner: Runner, tree: BoxTree, progress: Progress | None,
                 on_result: OnResult | None = None) -> tuple[int, int]:
    """The refinement tree of boxes (module docstring). Returns (boxes computed, boxes in the tree)."""
    spec = store.spec
    assert spec.boxes is not None
    tracked = {name: store.read(name) for name in tree.tracked}
    done = store.read("done")
    level: list[tuple[int, Any, int, int]] = [(i, cell, -1, 0) for i, cell in enumerate(tree.initial)]
    next_id = len(level)
    computed = 0
    total = 0
    split_code = BOX_STATUS_CODES["split"]

    def write(unit: list[tuple[int, Any, int, int]], result: Mapping[str, np.ndarray]) -> int:
        rows = np.array([node[0] for node in unit])
        values: dict[str, Any] = dict(result)
        edges = [tree.edges(node[1]) for node in unit]
        for axis in spec.axes:
            values[f"lo_{axis.name}"] = np.array([e[axis.name][0] for e in edges])
            values[f"hi_{axis.name}"] = np.array([e[axis.name][1] for e in edges])
        values["parent"] = np.array([node[2] for node in unit], np.int32)
        values["level"] = np.array([node[3] for node in unit], np.int16)
        values["done"] = np.ones(len(unit), bool)
        store.write_rows(rows, values)
        for name, held in tracked.items():
            held[rows] = result[name]
        if on_result is not None:
            on_result(result)
        return len(unit)

    while level:
        todo = [node for node in level if not done[node[0]]]
        total += len(todo)
        if progress is not None:
            progress(0, total)
        size = max(1, min(spec.chunk_size, math.ceil(len(todo) / (IN_FLIGHT_PER_WORKER * max(runner.workers, 1)))))
        groups = [todo[i:i + size] for i in range(0, len(todo), size)]
        units = ((g, tree.unit, (spec.worker_text, [(node[0], tree.payload(node[1])) for node in g])) for g in groups)
        computed += pump(runner, units, write, progress, total)
        children: list[tuple[int, Any, int, int]] = []
        marked = []
        for box_id, cell, _, depth in level:
            if tree.undecided(tracked, box_id) and tree.width(cell) > spec.boxes.min_relative_width \
                    and next_id + 2 <= spec.boxes.max_boxes:
                left, right = tree.split(cell)
                children += [(next_id, left, box_id, depth + 1), (next_id + 1, right, box_id, depth + 1)]
                next_id += 2
                if tracked["status"][box_id] != split_code:
                    marked.append(box_id)
        if marked:
            codes = np.full(len(marked), split_code, np.int8)
            store.write_rows(np.array(marked), {"status": codes})
            tracked["status"][marked] = codes
        level = children
    return computed, next_id


# -- the paper's model ----------------------------------------------------------------------------
def run_sweep(spec: SweepSpec, out: str | Path, *, runner: Runner | None = None, scheduler: str | None = None,
              workers: int | None = None, evaluator: Evaluator = evaluate_unit,
              progress: Progress | None = None, on_ready: Callable[[], None] | None = None) -> SweepReport:
    """Run (or resume) the paper's points sweep ``spec`` into the store at ``out``.

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

    def body() -> tuple[int, RefinementReport | None]:
        if spec.refine is None:
            return run_points(store, runner, evaluator, progress), None
        return run_refined(store, runner, evaluator, progress)

    computed, refinement = _running(runner, on_ready, body)
    return SweepReport(path=Path(out), grid_points=spec.n_points, computed_now=computed,
                       wall_seconds=time.perf_counter() - start, refinement=refinement)


def paper_box_tree(spec: SweepSpec) -> BoxTree:
    """The paper's boxes: :class:`~lyapcheck.paper.boxes.box.ParameterBox` halves, undecided while
    ``not_certified`` (a class's refutation is of that class's certificate, never of GES)."""
    undecided = (BOX_STATUS_CODES["not_certified"], BOX_STATUS_CODES["split"])
    return BoxTree(
        initial=initial_boxes(spec), split=lambda box: box.split(), width=lambda box: box.relative_width(),
        edges=lambda box: {name: (float(lo), float(hi)) for name, lo, hi in box.bounds},
        payload=lambda box: box.to_json(), unit=evaluate_boxes, tracked=("status",),
        undecided=lambda held, i: held["status"][i] in undecided)


def run_boxes(spec: SweepSpec, out: str | Path, *, runner: Runner, progress: Progress | None = None,
              on_ready: Callable[[], None] | None = None) -> BoxSweepReport:
    """Run (or resume) the paper's box sweep ``spec`` into the store at ``out`` (module docstring)."""
    assert spec.boxes is not None
    start = time.perf_counter()
    store = BoxStore.open_or_create(out, spec)
    computed, in_tree = _running(runner, on_ready, lambda: run_box_tree(store, runner, paper_box_tree(spec), progress))
    return BoxSweepReport(path=Path(out), boxes_computed_now=computed, boxes_in_tree=in_tree,
                          wall_seconds=time.perf_counter() - start)


# -- a model file ---------------------------------------------------------------------------------
def model_box_tree(spec: ModelSweepSpec) -> BoxTree:
    """A model file's boxes: the widest axis halved (:func:`sweeps.spec.split_cell`), undecided while
    ``not_certified``, or ``refuted`` with a class still open: a stability class where a corner is not unstable
    (the part that is stable may still be proved, as before), or a safety class neither certified nor refuted
    (beside a refuted one, or beside unstable corners). A safety class refuted at a value of the box
    (:data:`sweeps.evaluate.MODEL_SAFETY_CLASSES`) has its claim for every value of the box decided: the box is not
    split for it. (``sos_bound`` beside a refutation does not split a box: as before, it is not a reason.)"""
    undecided = (BOX_STATUS_CODES["not_certified"], BOX_STATUS_CODES["split"])
    all_corners = 2 ** len(spec.axes)
    stability = [c for c in spec.classes if c in MODEL_STABILITY_CLASSES]
    safety = [c for c in spec.classes if c in MODEL_SAFETY_CLASSES]
    # (not_applicable is not open: splitting the box does not make the class apply)
    open_codes = (STATUS_CODES["not_certified"], STATUS_CODES["inconclusive"])

    def is_undecided(held: Mapping[str, np.ndarray], i: int) -> bool:
        status = held["status"][i]
        if status in undecided:
            return True
        if status != BOX_STATUS_CODES["refuted"]:
            return False
        return bool((stability and 0 <= held["unstable_corners"][i] < all_corners)
                    or any(held[f"status_{c}"][i] in open_codes for c in safety))

    return BoxTree(
        initial=initial_cells(spec), split=lambda cell: split_cell(cell, spec.axes),
        width=lambda cell: max(relative_width(cell, spec.axes).values()),
        edges=lambda cell: {name: (float(lo), float(hi)) for name, (lo, hi) in cell.items()},
        payload=lambda cell: {name: [str(lo), str(hi)] for name, (lo, hi) in cell.items()},
        unit=evaluate_model_boxes, tracked=("status", "unstable_corners", *(f"status_{c}" for c in safety)),
        undecided=is_undecided)


def run_model_sweep(spec: ModelSweepSpec, out: str | Path, *, runner: Runner, progress: Progress | None = None,
                    on_ready: Callable[[], None] | None = None) -> ModelSweepReport:
    """Run (or resume) a model file's sweep ``spec`` into the store at ``out``: its grid of points
    (:func:`run_points`) or its tree of boxes (:func:`run_box_tree`).

    Parameters
    ----------
    spec
        The validated spec (:func:`sweeps.spec.load_model_spec`).
    out
        The Zarr store: created, or resumed when it holds the same spec, model and versions.
    runner
        Where units run (:func:`sweeps.runners.make_runner`).
    progress, on_ready
        Called with (items finished, current total) as units complete; and once the workers are up.
    """
    start = time.perf_counter()
    points = spec.mode == "points"
    report = ModelSweepReport(path=Path(out), mode=POINTS_MODE if points else BOXES_MODE, computed_now=0, total=0,
                              wall_seconds=0.0, model_sha256=spec.model_sha256)
    if points:
        grid = ModelPointStore.open_or_create(out, spec)
        report.total = spec.n_points
        report.computed_now = _running(runner, on_ready,
                                       lambda: run_points(grid, runner, evaluate_model_points, progress, report.keep))
    else:
        table = ModelBoxStore.open_or_create(out, spec)
        report.computed_now, report.total = _running(
            runner, on_ready, lambda: run_box_tree(table, runner, model_box_tree(spec), progress, report.keep))
    report.wall_seconds = time.perf_counter() - start
    return report


__all__ = ["pump", "run_points", "run_refined", "run_box_tree", "BoxTree", "run_sweep", "run_boxes", "run_model_sweep",
           "paper_box_tree", "model_box_tree", "SweepReport", "BoxSweepReport", "ModelSweepReport", "RefinementReport",
           "IN_FLIGHT_PER_WORKER", "Progress", "region_coords"]
