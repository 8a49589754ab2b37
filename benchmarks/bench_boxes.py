"""Box certificates against point certificates at equal wall time (class ges).

Refines a window of (alpha_d, k_d) around the paper's gains into boxes (lyapcheck.boxes.refine),
then spends the same wall time certifying grid points one at a time, and prints:

- boxes per second;
- the certified share of the window's area by boxes (every point of a certified box is proved),
  measured in log(alpha_d) x log(k_d) coordinates because the window spans decades;
- the share of grid points certified by the point certificates in the same time (each proves
  only its own point).

Run:  python benchmarks/bench_boxes.py [--min-width 1.0]
"""

from __future__ import annotations

import argparse
import math
import time
from fractions import Fraction

import numpy as np

WINDOW = ["alpha_d=150..2400", "k_d=0.05..0.8"]


def log_area(box) -> float:  # type: ignore[no-untyped-def]
    return math.prod(math.log(float(hi / lo)) for _, lo, hi in box.bounds)


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--min-width", type=float, default=1.0, help="minimum relative width of a box")
    args = parser.parse_args()

    from lyapcheck import boxes
    from lyapcheck.certification import build_system
    from lyapcheck.conditions import ges
    from lyapcheck.params import problem_from_sources

    problem = problem_from_sources("examples/paper.toml", {})
    window = boxes.parse_box(WINDOW)
    ges.run(build_system(problem, "derived"))  # warm: imports and program compilation, for both sides
    boxes.certify_box(problem, window)

    start = time.perf_counter()
    leaves = boxes.refine(problem, window, min_relative_width=args.min_width)
    box_seconds = time.perf_counter() - start
    certified_area = sum(log_area(leaf.box) for leaf in leaves if leaf.status == "certified")
    box_share = certified_area / log_area(window)

    (_, a_lo, a_hi), (_, k_lo, k_hi) = window.bounds
    side = 1
    while (side + 1) ** 2 <= 10**4:
        side += 1
    grid = [(a, k) for a in np.geomspace(float(a_lo), float(a_hi), side) for k in np.geomspace(float(k_lo), float(k_hi), side)]
    order = np.random.default_rng(0).permutation(len(grid))  # a uniform sample of the window in the time budget
    done = certified = 0
    start = time.perf_counter()
    for i in order:
        if time.perf_counter() - start >= box_seconds:
            break
        a, k = grid[i]
        system = build_system(problem.with_gains(alpha_d=Fraction(a).limit_denominator(10**6),
                                                 k_d=Fraction(k).limit_denominator(10**6)), "derived")
        certified += ges.run(system).status == "certified"
        done += 1
    print(f"window {', '.join(WINDOW)}; minimum relative box width {args.min_width}")
    print(f"boxes: {len(leaves)} leaves in {box_seconds:.1f} s = {len(leaves) / box_seconds:.2f} leaf boxes/s "
          f"(split boxes cost one call each too; {sum(leaf.status == 'certified' for leaf in leaves)} certified)")
    print(f"certified share of the window (log-area), proved for every point: {box_share:.3f}")
    print(f"points in the same {box_seconds:.1f} s: {done} certified one by one, share certified "
          f"{certified / max(done, 1):.3f} (each a proof for its own point only)")


if __name__ == "__main__":
    main()
