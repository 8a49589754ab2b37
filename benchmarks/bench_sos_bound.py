"""``sos_bound``'s search in conditioned coordinates against its search before issue 11's change.

Both searches run on a 6 x 6 sub-grid (evenly spaced indices) of each shipped sweep spec's own
grid, on the derived dynamics:

* before: with ``--before-tree DIR`` (``git worktree add --detach DIR d5dfacf``, the commit
  before the change), that tree's ``sos_bound.run`` in a subprocess: ``r = sqrt(b) r~``, the
  disturbance unscaled, Clarabel's 200-iteration cap, every candidate checked exactly, solves in
  sequence. Without it, the same coordinates and cap in this tree
  (``sos_bound.run(system, ((1, None),), 200)``): the same certificates, but the float screen
  and the threaded solves of this tree make it faster than the old code was;
* after: ``sos_bound.run(system)`` of this tree.

Printed from this one run: the points each certifies (and those only one does), the ratio of
the bounds where both certify (after / before: below 1 is tighter), and the ratio of the
wall times. Every certificate counted passed the exact check.

Run:  python benchmarks/bench_sos_bound.py [--per-axis 6] [--before-tree /tmp/before]
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import time
from fractions import Fraction
from pathlib import Path
from typing import Any

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
SPECS = ("sweep-alpha-sigma.toml", "sweep-kd-delta.toml", "sweep-dmax-alpha.toml")
BEFORE_SEARCH = ((Fraction(1), None),)
BEFORE_MAX_ITER = 200


def points(per_axis: int) -> list[tuple[str, Any]]:
    """(label, problem) on a ``per_axis`` x ``per_axis`` sub-grid of each shipped spec."""
    from sweeps.spec import load_spec

    out = []
    for name in SPECS:
        spec = load_spec(ROOT / "examples" / name)
        picks = [np.unique(np.linspace(0, a.size - 1, per_axis).round().astype(int)) for a in spec.axes]
        for i in picks[0]:
            for j in picks[1]:
                out.append((f"{name}@{i},{j}", spec.problem_at([spec.axes[0].values[i], spec.axes[1].values[j]])))
    return out


def bounds_in(tree: Path, per_axis: int, before: bool) -> tuple[dict[str, float | None], float]:
    """Per point the certified bound (None if none) and the total wall time of the search, with
    the code of ``tree`` (``before``: the old coordinates and cap, in this tree only)."""
    sys.path.insert(0, str(tree))
    from lyapcheck.paper.certification import build_system
    from lyapcheck.paper.conditions import sos_bound

    sos_bound.program()  # loaded once, outside the timing
    systems = [(label, build_system(problem, "derived")) for label, problem in points(per_axis)]
    bounds: dict[str, float | None] = {}
    t0 = time.perf_counter()
    for label, system in systems:
        cert = sos_bound.run(system, BEFORE_SEARCH, BEFORE_MAX_ITER) if before else sos_bound.run(system)
        bounds[label] = float(Fraction(cert["eps_bound"])) if cert else None
    return bounds, time.perf_counter() - t0


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--per-axis", type=int, default=6, help="sub-grid size per axis of each spec")
    parser.add_argument("--before-tree", type=Path, default=None, help="a worktree of commit d5dfacf")
    args = parser.parse_args()
    if args.before_tree is not None:
        tree = args.before_tree.resolve()
        code = (f"import json, sys; sys.path.insert(0, {str(ROOT / 'benchmarks')!r}); import bench_sos_bound as b; "
                f"print(json.dumps(b.bounds_in(__import__('pathlib').Path({str(tree)!r}), {args.per_axis}, False)))")
        proc = subprocess.run([sys.executable, "-c", code], cwd=tree, env={**os.environ, "PYTHONPATH": str(tree)},
                              capture_output=True, text=True, check=True)
        b, wall_before = json.loads(proc.stdout.strip().splitlines()[-1])
        where = f"the code of {tree}"
    else:
        b, wall_before = bounds_in(ROOT, args.per_axis, True)
        where = "this tree in the old coordinates"
    a, wall_after = bounds_in(ROOT, args.per_axis, False)
    labels = list(a)
    both = [x for x in labels if b[x] is not None and a[x] is not None]
    ratios = sorted(a[x] / b[x] for x in both)  # type: ignore[operator]
    print(f"points: {len(labels)} ({args.per_axis} x {args.per_axis} of each of {', '.join(SPECS)}), derived dynamics")
    print(f"before: {where}")
    print(f"certified: before {sum(v is not None for v in b.values())}, after {sum(v is not None for v in a.values())}")
    print(f"  only before: {[x for x in labels if b[x] is not None and a[x] is None]}")
    print(f"  only after : {len([x for x in labels if a[x] is not None and b[x] is None])} points")
    if ratios:
        print(f"bound after / before where both certify ({len(ratios)} points): min {ratios[0]:.3f}, "
              f"median {statistics.median(ratios):.3f}, max {ratios[-1]:.4f}; "
              f"{sum(r > 1 for r in ratios)} above 1")
    print(f"wall time: before {wall_before:.1f} s, after {wall_after:.1f} s; before / after {wall_before / wall_after:.2f} x")


if __name__ == "__main__":
    main()
