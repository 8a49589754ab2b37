"""Run a box sweep (``mode = "boxes"``): prove whole boxes of gain space, refine the rest.

The tree. The axes' values are the edges of the first boxes (``num - 1`` cells per axis, in C
order: ids ``0 .. n0 - 1``, level 0). Level by level, every box of the level is certified
(:func:`lyapcheck.paper.boxes.classes.certify_box`, one exact certificate for every gain set of the box) and
cross-checked (:func:`lyapcheck.paper.boxes.cross_check.cross_check`, random points of a certified box simulated
against its envelope); then, in id order, each box that is not certified, wider than
``min_relative_width`` and within the ``max_boxes`` budget is marked ``split`` and its two
halves (:meth:`~lyapcheck.paper.boxes.box.ParameterBox.split`) get the next two ids. The ids are
therefore a function of the spec and of earlier statuses alone, and a resumed run replays the
tree, reads the statuses of the boxes that are ``done`` and computes only the others.

Work units are small groups of boxes of one level (a box costs 0.3-2 s), run by the runners of
:mod:`sweeps.runners` (in-process, local processes, or Dask); each result is written to the
store as it arrives, so an interrupted sweep keeps every finished box.
"""

from __future__ import annotations

import itertools
import math
import time
from dataclasses import dataclass
from fractions import Fraction
from pathlib import Path
from typing import Any, Callable, Iterator, Sequence

import numpy as np

from lyapcheck.paper.boxes.box import ParameterBox
from sweeps.box_store import BoxStore
from sweeps.evaluate import UNIT_LOCK
from sweeps.runners import Runner
from sweeps.schema import BOX_STATUS_CODES
from sweeps.spec import SweepSpec, cached_spec
from sweeps.run import IN_FLIGHT_PER_WORKER, Progress

#: a box of the tree: (id, box, parent id, level)
Node = tuple[int, ParameterBox, int, int]


@dataclass
class BoxSweepReport:
    """What a run of a box sweep did (the store holds the results)."""

    path: Path
    boxes_computed_now: int
    boxes_in_tree: int
    wall_seconds: float


def initial_boxes(spec: SweepSpec) -> list[ParameterBox]:
    """The cells of the axes' grid, in C order (the edges taken exactly from the stored floats)."""
    edges = [[Fraction(v) for v in axis.values] for axis in spec.axes]
    cells = [list(zip(e[:-1], e[1:])) for e in edges]
    return [ParameterBox(tuple((axis.name, lo, hi) for axis, (lo, hi) in zip(spec.axes, combo)))
            for combo in itertools.product(*cells)]


def evaluate_boxes(spec_text: str, boxes: Sequence[tuple[int, dict[str, list[str]]]]) -> dict[str, np.ndarray]:
    """One unit of work (runs in a worker): certify and cross-check each ``(id, box)``.

    Returns per box: ``status`` code, ``status_<class>``, ``k``, ``decay_rate_per_s`` (of the
    certifying class), ``cross_check_runs``, ``cross_check_worst_ratio`` and ``soundness_violation``. A box's random points are drawn
    from ``(seed, id)``, so its result does not depend on the unit it was grouped in.
    """
    from lyapcheck.paper.boxes.classes import certify_box
    from lyapcheck.paper.boxes.cross_check import cross_check
    from lyapcheck.tolerances import ENVELOPE_REL_TOL

    spec = cached_spec(spec_text)
    assert spec.boxes is not None
    n = len(boxes)
    out = {"status": np.zeros(n, np.int8), "k": np.full(n, np.nan), "decay_rate_per_s": np.full(n, np.nan),
           "cross_check_runs": np.zeros(n, np.int16), "cross_check_worst_ratio": np.full(n, np.nan),
           "soundness_violation": np.zeros(n, bool),
           **{f"status_{c}": np.full(n, -1, np.int8) for c in spec.classes}}
    ges_classes = [c for c in spec.classes if c != "sos_bound"]
    if "sos_bound" in spec.classes:
        out.update({"eps_bound_m": np.full(n, np.nan), "sim_worst_eps_m": np.full(n, np.nan),
                    "tightness_ratio": np.full(n, np.nan)})
    for j, (box_id, data) in enumerate(boxes):
        box = ParameterBox.from_json(data)
        result: dict[str, Any] = {}
        envelope: dict[str, Any] | None = None
        for cls in ges_classes:  # cheapest first; the first certificate decides the box, and the
            # next classes run only while no certificate has given an envelope k, rate to
            # cross-check (eq. stabCond's, prop41_ges, gives none)
            with UNIT_LOCK:  # two threads of one Dask worker take turns (as sweeps.evaluate does)
                here = certify_box(spec.base, box, cls=cls)
            out[f"status_{cls}"][j] = BOX_STATUS_CODES[here["status"]]
            if here["status"] == "certified":
                result = result if result.get("status") == "certified" else here
                if "k" in here:
                    envelope = here
                    break
            elif result.get("status") != "certified":
                result = here
        bound = _bound(spec, box, box_id, out, j) if "sos_bound" in spec.classes else None
        if not ges_classes:  # a bound-only sweep refines on the bound
            result = bound or {}
        # a class's refutation is of that class's certificate, not of GES: the box stays undecided
        status = "certified" if result.get("status") == "certified" else "not_certified"
        out["status"][j] = BOX_STATUS_CODES[status]
        if status != "certified" or envelope is None:
            continue
        out["k"][j], out["decay_rate_per_s"][j] = envelope["k"], envelope["decay_rate_per_s"]
        result = envelope
        runs, worst = cross_check(spec.base, box, result, spec.boxes.cross_check_points, (spec.boxes.seed, box_id))
        out["cross_check_runs"][j], out["cross_check_worst_ratio"][j] = runs, worst
        out["soundness_violation"][j] |= runs > 0 and not worst <= 1 + ENVELOPE_REL_TOL
    return out


def _bound(spec: SweepSpec, box: ParameterBox, box_id: int, out: dict[str, np.ndarray], j: int) -> dict[str, Any]:
    """``sos_bound`` over the box, and the worst-case disturbance search at its random points.

    The search is its deterministic screening round only (a vanishing time budget: no
    refinement round fits), so a box's figures do not depend on the machine's speed.
    """
    from lyapcheck.paper.boxes.classes import certify_box
    from lyapcheck.paper.boxes.box import sample_points
    from lyapcheck.simulation.worst_case import search_worst_case
    from sweeps.soundness import BOUND_REL_TOL

    assert spec.boxes is not None
    with UNIT_LOCK:
        result = certify_box(spec.base, box, cls="sos_bound")
    out["status_sos_bound"][j] = BOX_STATUS_CODES.get(result["status"], BOX_STATUS_CODES["not_certified"])
    if result["status"] != "certified":
        return result
    bound = float(result["eps_bound_m"])
    out["eps_bound_m"][j] = bound
    worst = -math.inf
    for point in sample_points(box, spec.boxes.cross_check_points, (spec.boxes.seed, box_id, 1)):
        found = search_worst_case(spec.base.with_gains(**point), budget_s=WORST_CASE_SCREENING_ONLY)
        worst = max(worst, found.sup_abs_eps_tail_m)
    if math.isfinite(worst):
        out["sim_worst_eps_m"][j] = worst
        out["tightness_ratio"][j] = bound / worst if worst > 0 else math.inf
        out["soundness_violation"][j] |= worst > bound * (1 + BOUND_REL_TOL)
    return result


#: the worst-case search's time budget in a box sweep: below any round's cost, so only its
#: (deterministic) screening round and final re-simulation run (about 8 s a point)
WORST_CASE_SCREENING_ONLY = 1e-9


def _units(todo: list[Node], workers: int, largest: int) -> Iterator[list[Node]]:
    """Groups of boxes: small enough that every worker has two in flight."""
    size = max(1, min(largest, math.ceil(len(todo) / (IN_FLIGHT_PER_WORKER * max(workers, 1)))))
    for i in range(0, len(todo), size):
        yield todo[i:i + size]


def _compute(store: BoxStore, runner: Runner, spec: SweepSpec, todo: list[Node], status: np.ndarray,
             progress: Progress | None, total: int) -> int:
    """Hand ``todo`` to the runner, writing each unit's rows (geometry, results, done) as it ends."""
    limit = max(1, IN_FLIGHT_PER_WORKER * runner.workers)
    units = _units(todo, runner.workers, spec.chunk_size)
    pending: dict[Any, list[Node]] = {}
    finished = 0
    exhausted = False
    while True:
        while not exhausted and len(pending) < limit:
            unit = next(units, None)
            if unit is None:
                exhausted = True
                break
            payload = [(node[0], node[1].to_json()) for node in unit]
            pending[runner.submit(evaluate_boxes, spec.text, payload)] = unit
        if not pending:
            return finished
        done, _ = runner.wait_any(pending)
        for future in [f for f in pending if f in done]:
            unit = pending.pop(future)
            result = future.result()
            rows = np.array([node[0] for node in unit])
            values: dict[str, np.ndarray] = dict(result)
            for d, axis in enumerate(spec.axes):
                values[f"lo_{axis.name}"] = np.array([float(node[1].bounds[d][1]) for node in unit])
                values[f"hi_{axis.name}"] = np.array([float(node[1].bounds[d][2]) for node in unit])
            values["parent"] = np.array([node[2] for node in unit], np.int32)
            values["level"] = np.array([node[3] for node in unit], np.int16)
            values["done"] = np.ones(len(unit), bool)
            store.write_rows(rows, values)
            status[rows] = result["status"]
            finished += len(unit)
            if progress is not None:
                progress(len(unit), total)


def run_boxes(spec: SweepSpec, out: str | Path, *, runner: Runner, progress: Progress | None = None,
              on_ready: Callable[[], None] | None = None) -> BoxSweepReport:
    """Run (or resume) the box sweep ``spec`` into the store at ``out`` (module docstring)."""
    assert spec.boxes is not None
    start = time.perf_counter()
    store = BoxStore.open_or_create(out, spec)
    status = store.read("status")
    done = store.read("done")
    level: list[Node] = [(i, box, -1, 0) for i, box in enumerate(initial_boxes(spec))]
    next_id = len(level)
    computed = 0
    total = 0
    runner.start()
    if on_ready is not None:
        on_ready()
    try:
        while level:
            todo = [node for node in level if not done[node[0]]]
            total += len(todo)
            if progress is not None:
                progress(0, total)
            computed += _compute(store, runner, spec, todo, status, progress, total)
            children: list[Node] = []
            marked = []
            for box_id, box, _, depth in level:
                undecided = status[box_id] in (BOX_STATUS_CODES["not_certified"], BOX_STATUS_CODES["split"])
                if undecided and box.relative_width() > spec.boxes.min_relative_width \
                        and next_id + 2 <= spec.boxes.max_boxes:
                    left, right = box.split()
                    children += [(next_id, left, box_id, depth + 1), (next_id + 1, right, box_id, depth + 1)]
                    next_id += 2
                    if status[box_id] != BOX_STATUS_CODES["split"]:
                        marked.append(box_id)
            if marked:
                codes = np.full(len(marked), BOX_STATUS_CODES["split"], np.int8)
                store.write_rows(np.array(marked), {"status": codes})
                status[marked] = codes
            level = children
    except BaseException:
        runner.close(cancel=True)
        raise
    runner.close()
    return BoxSweepReport(path=Path(out), boxes_computed_now=computed, boxes_in_tree=next_id,
                          wall_seconds=time.perf_counter() - start)
