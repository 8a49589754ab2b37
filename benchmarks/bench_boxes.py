"""Box sweep against point certificates at equal wall time (class ges).

Runs the shipped box sweep ``examples/boxes-paper.toml`` (``mode = "boxes"``, in this process,
into a temporary store), then spends the same wall time certifying points of the same window one
at a time (a uniform random order over a log grid), and prints, from this one run:

- boxes per second (every box computed: leaves and split ones);
- the certified share of the window's area by boxes (each certified box is proved for every
  point in it), in the axes' log measure, as the sweep's summary reports it;
- the share of points certified by point certificates in the same time (each a proof for its own
  point only), and the ratio of the two shares.

Run:  python benchmarks/bench_boxes.py [--spec examples/boxes-paper.toml]
"""

from __future__ import annotations

import argparse
import tempfile
import time
from fractions import Fraction
from pathlib import Path

import numpy as np


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--spec", default="examples/boxes-paper.toml", help="a box sweep spec with two axes")
    args = parser.parse_args()

    from lyapcheck.paper.certification import build_system
    from lyapcheck.paper.conditions import ges
    from sweeps.run import run_boxes
    from sweeps.runners import InlineRunner
    from sweeps.spec import load_spec
    from sweeps.store import BoxStore
    from sweeps.summary import summarize_boxes

    spec = load_spec(args.spec)
    problem = spec.base
    ges.run(build_system(problem, "derived"))  # warm: imports and stored programs, for both sides

    with tempfile.TemporaryDirectory() as scratch:
        out = Path(scratch) / "boxes.zarr"
        start = time.perf_counter()
        report = run_boxes(spec, out, runner=InlineRunner())
        box_seconds = time.perf_counter() - start
        summary = summarize_boxes(BoxStore.open_or_create(out, spec))
    box_share = summary.area_fraction["certified"]

    (a_axis, k_axis) = spec.axes
    side = 100
    grid = [(a, k) for a in np.geomspace(a_axis.values[0], a_axis.values[-1], side)
            for k in np.geomspace(k_axis.values[0], k_axis.values[-1], side)]
    order = np.random.default_rng(0).permutation(len(grid))
    done = certified = 0
    start = time.perf_counter()
    for i in order:
        if time.perf_counter() - start >= box_seconds:
            break
        a, k = grid[i]
        gains = {a_axis.name: Fraction(a), k_axis.name: Fraction(k)}
        certified += ges.run(build_system(problem.with_gains(**gains), "derived")).status == "certified"
        done += 1
    point_share = certified / max(done, 1)
    print(f"spec {args.spec}: window {a_axis.name} {a_axis.values[0]:g}..{a_axis.values[-1]:g} x "
          f"{k_axis.name} {k_axis.values[0]:g}..{k_axis.values[-1]:g}")
    print(f"boxes: {report.boxes_in_tree} computed in {box_seconds:.1f} s = {report.boxes_in_tree / box_seconds:.2f} "
          f"boxes/s; {summary.leaves} leaves, {summary.certified_boxes} certified")
    print(f"certified share of the window (log-area), proved for every point: {box_share:.3f}")
    print(f"points in the same {box_seconds:.1f} s: {done} certified one by one, share certified {point_share:.3f} "
          "(each a proof for its own point only)")
    print(f"ratio proved-area share / sampled-point share: {box_share / point_share if point_share else float('nan'):.3f}")
    print(f"cross-check: {summary.cross_checked_points} simulated points, worst envelope ratio "
          f"{summary.worst_envelope_ratio:.3g}")


if __name__ == "__main__":
    main()
