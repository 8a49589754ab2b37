"""``sos_bound``'s search in conditioned coordinates against its search before issue 11's change.

Both searches run in this process, one after the other at each point, on a 6 x 6 sub-grid
(evenly spaced indices) of each shipped sweep spec's own grid, on the derived dynamics:

* before: ``r = sqrt(b) r~``, the disturbance unscaled, Clarabel's 200-iteration cap
  (``sos_bound.run(system, ((1, None),), 200)``, the code of commit d5dfacf);
* after: :data:`lyapcheck.conditions.sos_bound.SEARCH_SCALES` with the cap
  :data:`lyapcheck.tolerances.SOS_BOUND_MAX_ITER` (``sos_bound.run(system)``).

Printed from this one run: the points each certifies (and those only one does), the ratio of
the bounds where both certify (after / before: below 1 is tighter), and the ratio of the
wall times. Every certificate counted passed the exact check.

Run:  python benchmarks/bench_sos_bound.py [--per-axis 6]
"""

from __future__ import annotations

import argparse
import statistics
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


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--per-axis", type=int, default=6, help="sub-grid size per axis of each spec")
    args = parser.parse_args()
    sys.path.insert(0, str(ROOT))
    from lyapcheck.certification import build_system
    from lyapcheck.conditions import sos_bound

    sos_bound.program()  # loaded once, outside the timings
    wall = {"before": 0.0, "after": 0.0}
    bounds: dict[str, dict[str, float | None]] = {"before": {}, "after": {}}
    for label, problem in points(args.per_axis):
        system = build_system(problem, "derived")
        for side, call in (("before", lambda: sos_bound.run(system, BEFORE_SEARCH, BEFORE_MAX_ITER)),
                           ("after", lambda: sos_bound.run(system))):
            t0 = time.perf_counter()
            cert = call()
            wall[side] += time.perf_counter() - t0
            bounds[side][label] = float(Fraction(cert["eps_bound"])) if cert else None
    labels = list(bounds["before"])
    b, a = bounds["before"], bounds["after"]
    both = [x for x in labels if b[x] is not None and a[x] is not None]
    ratios = sorted(a[x] / b[x] for x in both)  # type: ignore[operator]
    print(f"points: {len(labels)} ({args.per_axis} x {args.per_axis} of each of {', '.join(SPECS)}), derived dynamics")
    print(f"certified: before {sum(v is not None for v in b.values())}, after {sum(v is not None for v in a.values())}")
    print(f"  only before: {[x for x in labels if b[x] is not None and a[x] is None]}")
    print(f"  only after : {len([x for x in labels if a[x] is not None and b[x] is None])} points")
    if ratios:
        print(f"bound after / before where both certify ({len(ratios)} points): min {ratios[0]:.3f}, "
              f"median {statistics.median(ratios):.3f}, max {ratios[-1]:.4f}; "
              f"{sum(r > 1 for r in ratios)} above 1")
    print(f"wall time: before {wall['before']:.1f} s, after {wall['after']:.1f} s; "
          f"before / after {wall['before'] / wall['after']:.2f} x")


if __name__ == "__main__":
    main()
