"""A box sweep of a two-parameter model family, measured against issue 25's targets.

Runs a model box sweep (default ``examples/models/sweeps/boxes-oscillator.toml``: the damped
oscillator over its stiffness and damping, class ``quadratic``) into a temporary store and prints,
from this one run:

- the share of the window proved (log measure on log axes), against the target of 80 %;
- that every certified box's stored certificate re-checks exactly (``lyapcheck.api.verify``,
  no solver) and states the box the store says it proves;
- the time to certify a proved box (the corner linearizations and the box classes, measured in
  the worker; the median over the proved boxes) against the time to certify one point of the same
  model with the same classes (the median over random points of the window, after a warm-up),
  target within 5x; the mean, and the time of every box (failed and split ones too) per proved
  box, are printed beside it;
- soundness: at least 100 random parameter points drawn across the proved boxes (boxes chosen in
  proportion to their share of the window, points uniform in each axis's scale inside them),
  simulated against their box's certificate by the sweep's own cross-check, target 0 violations.

Each target is printed MET or NOT MET. Figures are timings of this machine at this moment: the
development machine has 2 cores shared with other jobs.

Run:  python benchmarks/bench_model_boxes.py [--spec SPEC] [--workers N] [--points 120] [--seed 0]
"""

from __future__ import annotations

import argparse
import json
import math
import statistics
import tempfile
import time
from fractions import Fraction
from pathlib import Path
from typing import Any

import numpy as np

SHARE_TARGET = 0.80
TIME_RATIO_TARGET = 5.0
MIN_SOUNDNESS_POINTS = 100


def verdict(ok: bool) -> str:
    return "MET" if ok else "NOT MET"


def point_seconds(spec: Any, rng: np.random.Generator, count: int) -> list[float]:
    """Wall time of certify_model at ``count`` random points of the window (each axis in its scale)."""
    from lyapcheck.models.surfaces.certify import certify_model

    out = []
    for _ in range(count):
        coords = []
        for axis in spec.axes:
            lo, hi = axis.values[0], axis.values[-1]
            u = rng.random()
            coords.append(math.exp(math.log(lo) + u * math.log(hi / lo)) if axis.measure == "log" else lo + u * (hi - lo))
        model = spec.model_at(coords)
        start = time.perf_counter()
        certify_model(model, classes=spec.classes)
        out.append(time.perf_counter() - start)
    return out


def sample_points(spec: Any, boxes: list[dict[str, tuple[float, float]]], weights: np.ndarray, count: int,
                  rng: np.random.Generator) -> dict[int, list[dict[str, Fraction]]]:
    """``count`` points across ``boxes``: a box drawn in proportion to ``weights``, then a point uniform in
    each axis's scale inside it; grouped by box index."""
    chosen = rng.choice(len(boxes), size=count, p=weights / weights.sum())
    out: dict[int, list[dict[str, Fraction]]] = {}
    for b in chosen:
        point = {}
        for axis in spec.axes:
            lo, hi = boxes[b][axis.name]
            u = rng.random()
            value = math.exp(math.log(lo) + u * math.log(hi / lo)) if axis.measure == "log" else lo + u * (hi - lo)
            point[axis.name] = Fraction(min(max(value, lo), hi))
        out.setdefault(int(b), []).append(point)
    return out


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--spec", default="examples/models/sweeps/boxes-oscillator.toml",
                        help="a model box sweep spec with two axes")
    parser.add_argument("--workers", type=int, default=0, help="local worker processes (0: in this process)")
    parser.add_argument("--points", type=int, default=120, help="random parameter points for the soundness check")
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args()

    from lyapcheck.api import verify
    from sweeps.crosscheck import cross_check_box
    from sweeps.run import run_model_sweep
    from sweeps.runners import make_runner
    from sweeps.schema import BOX_STATUS_CODES
    from sweeps.spec import load_model_spec
    from sweeps.store import ModelBoxStore
    from sweeps.summary import leaf_fractions, summarize_model_store, violation_count

    spec = load_model_spec(args.spec)
    if spec.mode != "boxes" or len(spec.axes) != 2:
        raise SystemExit(f"{args.spec}: a box sweep over two parameters is needed")
    rng = np.random.default_rng(args.seed)
    point_seconds(spec, rng, 2)  # warm-up: imports and the stored programs, for both sides
    points = point_seconds(spec, rng, 10)
    point_median = statistics.median(points)

    with tempfile.TemporaryDirectory() as scratch:
        out = Path(scratch) / "boxes.zarr"
        start = time.perf_counter()
        report = run_model_sweep(spec, out, runner=make_runner(workers=args.workers))
        wall = time.perf_counter() - start
        store = ModelBoxStore.open_or_create(out, spec)
        summary = summarize_model_store(store)
        data = {v.name: store.read(v.name) for v in store.variables}

    certified_code = BOX_STATUS_CODES["certified"]
    leaf = data["done"].astype(bool) & (data["status"] != BOX_STATUS_CODES["split"])
    rows = np.flatnonzero(leaf & (data["status"] == certified_code))
    # 1. re-check every certified box's certificate, and that it states the stored box
    valid = 0
    for row in rows:
        doc = json.loads(str(data["certificate"][row]))
        same = all((float(Fraction(doc["box"][a.name][0])), float(Fraction(doc["box"][a.name][1])))
                   == (data[f"lo_{a.name}"][row], data[f"hi_{a.name}"][row]) for a in spec.axes)
        valid += bool(same and verify(doc).valid)
    # 2. time per proved box against one point
    statuses = np.asarray(report.statuses_now)
    seconds = np.asarray(report.seconds_certify)
    proved = seconds[statuses == certified_code]
    per_proved = float(np.median(proved)) if proved.size else math.nan
    mean_proved = float(proved.mean()) if proved.size else math.nan
    amortized = float(seconds.sum() / max(proved.size, 1))
    # 3. soundness over random points of the proved boxes
    window = {a.name: (a.values[0], a.values[-1]) for a in spec.axes}
    scales = {a.name: a.measure for a in spec.axes}
    boxes = [{a.name: (float(data[f"lo_{a.name}"][r]), float(data[f"hi_{a.name}"][r])) for a in spec.axes} for r in rows]
    weights = leaf_fractions({a.name: np.array([b[a.name][0] for b in boxes]) for a in spec.axes},
                             {a.name: np.array([b[a.name][1] for b in boxes]) for a in spec.axes}, scales, window) \
        if boxes else np.zeros(0)
    simulated = trajectories = violations = 0
    details: list[str] = []
    start = time.perf_counter()
    if boxes:
        for b, pts in sorted(sample_points(spec, boxes, weights, args.points, rng).items()):
            doc = json.loads(str(data["certificate"][rows[b]]))
            found, _ = cross_check_box([(spec.model, p) for p in pts], doc, starts=spec.simulation.starts,
                                       seed=(args.seed, int(rows[b])), worst_case=spec.simulation.worst_case)
            simulated += found.points
            trajectories += found.trajectories
            violations += len(found.violations)
            details += found.violations
    soundness_seconds = time.perf_counter() - start

    (x, y) = spec.axes
    share = summary.proved_share
    print(f"spec {args.spec}: model {spec.model_file} (SHA-256 {spec.model_sha256[:12]}...), classes "
          f"{', '.join(spec.classes)}")
    print(f"window {x.name} {x.values[0]:g}..{x.values[-1]:g} ({x.measure}) x {y.name} {y.values[0]:g}..{y.values[-1]:g} "
          f"({y.measure}); min_relative_width {spec.boxes.min_relative_width if spec.boxes else '-'}, max_boxes "
          f"{spec.boxes.max_boxes if spec.boxes else '-'}, workers {args.workers}")
    print(f"sweep: {report.total} boxes in the tree, {report.computed_now} computed in {wall:.1f} s wall; {summary.leaves} "
          f"leaves: {summary.counts['certified']} certified, {summary.counts['not_certified']} not certified, "
          f"{summary.counts['refuted']} refuted; in-sweep cross-check: {summary.cross_check['parameter_points']} points, "
          f"{violation_count(summary)} violations")
    print(f"[target] share of the window proved (log measure): {share:.4f} (target >= {SHARE_TARGET:.2f}): "
          f"{verdict(share >= SHARE_TARGET)}")
    print(f"[target] certified boxes whose stored certificate re-checks exactly (verify) and states its box: "
          f"{valid} of {rows.size}: {verdict(rows.size > 0 and valid == rows.size)}")
    ratio = per_proved / point_median if point_median > 0 else math.nan
    print(f"[target] time per proved box {per_proved * 1e3:.1f} ms (median over {proved.size}; corner linearizations and "
          f"the box classes) vs one point {point_median * 1e3:.1f} ms (median of {len(points)} random points, same "
          f"classes): ratio {ratio:.2f} (target <= {TIME_RATIO_TARGET:g}): {verdict(ratio <= TIME_RATIO_TARGET)}")
    print(f"         mean per proved box {mean_proved * 1e3:.1f} ms (ratio {mean_proved / point_median:.2f}; with workers the "
          "mean carries each worker's first box, which loads the stored programs)")
    print(f"         every box computed (failed and split ones too) per proved box: {amortized * 1e3:.1f} ms, ratio "
          f"{amortized / point_median:.2f} to one point; cross-check by simulation in the sweep: "
          f"{float(np.sum(report.seconds_cross_check)):.1f} s in all")
    print(f"[target] soundness: {simulated} random parameter points across {len(boxes)} proved boxes, {trajectories} "
          f"trajectories ({soundness_seconds:.1f} s): {violations} violations (target 0 over >= {MIN_SOUNDNESS_POINTS} "
          f"points): {verdict(violations == 0 and simulated >= MIN_SOUNDNESS_POINTS)}")
    for line in details[:10]:
        print(f"  VIOLATION {line}")


if __name__ == "__main__":
    main()
