"""The smallest tube around the path that ``barrier`` proves for the paper's loop (issue 32, item 6).

``examples/models/paper-tube.toml``: the paper's ILOS cross-track error dynamics (SI, the gains of
its Section 5) under every disturbance ``|d| <= d* = 0.088 mm/s``, starting within ``eps0 = 0.5 mm``
of the path with the integral state ``|s| <= s0 = 150 mm``; unsafe: ``|eps| >= w`` (two pieces,
``eps >= w`` and ``eps <= -w``). For each ``w`` this runs, in a fresh process (imports included),

    lyapcheck certify examples/models/paper-tube.toml --classes barrier --set "w=W mm" --json

and prints ``w -> status, degree of B, lambda, closest approach of the simulations beside it
(the largest simulated |eps| minus w: < 0, no simulated trajectory reached |eps| = w), wall time``:
first a coarse grid (to show the statuses are monotone in ``w``), then a bisection for the smallest
certified ``w`` to ``--tol`` mm. ``w <= eps0`` cannot be certified (the initial set meets the
unsafe set). The largest simulated ``|eps|`` is a lower bound on the true tube: the smallest
certified ``w`` is an upper bound; the gap between them is the proof's conservatism (or the
simulation's).

Run:  python benchmarks/bench_paper_tube.py [--lo 0.5] [--hi 1.0] [--tol 0.002]
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import time
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]
MODEL = ROOT / "examples" / "models" / "paper-tube.toml"


def run(w_mm: float) -> dict[str, Any]:
    """One certification at ``w = w_mm`` mm: status, degree, lambda, closest approach (mm), wall (s)."""
    t0 = time.perf_counter()
    proc = subprocess.run([sys.executable, "-m", "lyapcheck", "certify", str(MODEL), "--classes", "barrier",
                           "--set", f"w={w_mm!r} mm", "--json"], cwd=ROOT, capture_output=True, text=True)
    wall = time.perf_counter() - t0
    if proc.returncode not in (0, 1):
        raise RuntimeError(f"w = {w_mm} mm: exit {proc.returncode}: {proc.stderr.strip()}")
    barrier = json.loads(proc.stdout)["conditions"]["barrier"]
    trial = barrier.get("falsification") or {}
    closest = trial.get("closest_approach")
    return {"w_mm": w_mm, "status": barrier["status"], "degree": barrier.get("degree"),
            "lambda": barrier.get("lambda_per_s"), "closest_mm": None if closest is None else 1e3 * closest,
            "sim_max_eps_mm": None if closest is None else w_mm + 1e3 * closest, "wall": wall,
            "violation": bool(barrier.get("soundness_violation"))}


def show(row: dict[str, Any]) -> None:
    lam = f"{row['lambda']:.4g} 1/s" if row["lambda"] is not None else "-"
    closest = f"{row['closest_mm']:+.4f} mm" if row["closest_mm"] is not None else "-"
    print(f"  w = {row['w_mm']:7.4f} mm  {row['status']:15s} degree {row['degree'] or '-'!s:2s} lambda {lam:12s} "
          f"closest approach {closest:13s} wall {row['wall']:5.2f} s"
          + ("  SOUNDNESS: a simulated trajectory entered a set proved unreachable" if row["violation"] else ""),
          flush=True)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--lo", type=float, default=0.5, help="a w (mm) known not certified (default eps0)")
    parser.add_argument("--hi", type=float, default=1.0, help="a w (mm) to start the bisection from (certified)")
    parser.add_argument("--tol", type=float, default=0.002, help="bisection tolerance in mm")
    parser.add_argument("--grid", type=float, nargs="*", default=[0.5, 0.55, 0.6, 0.7, 1.0, 2.0],
                        help="coarse grid of w (mm)")
    args = parser.parse_args()
    rows: list[dict[str, Any]] = []
    print(f"{MODEL.relative_to(ROOT)}: barrier at w (mm), --classes barrier (falsification included)")
    print("coarse grid:")
    for w in args.grid:
        rows.append(run(w))
        show(rows[-1])
    certified = sorted(r["w_mm"] for r in rows if r["status"] == "certified")
    refused = sorted(r["w_mm"] for r in rows if r["status"] != "certified")
    monotone = all(c > r for c in certified for r in refused)
    print(f"monotone on the grid (every certified w above every other): {monotone}")
    lo = max([args.lo] + [w for w in refused if w < (certified[0] if certified else args.hi)])
    hi = min([args.hi] + certified)
    print(f"bisection between {lo} mm (not certified) and {hi} mm (certified), to {args.tol} mm:")
    while hi - lo > args.tol:
        mid = round((lo + hi) / 2, 6)
        row = run(mid)
        rows.append(row)
        show(row)
        if row["status"] == "certified":
            hi = mid
        else:
            lo = mid
    sims = [r["sim_max_eps_mm"] for r in rows if r["sim_max_eps_mm"] is not None]
    print(f"\nsmallest certified w: {hi:.4f} mm (largest w not certified: {lo:.4f} mm)")
    if sims:
        print(f"largest |eps| reached in the simulations beside the proofs: {max(sims):.4f} mm "
              "(a lower bound on the true tube)")
    bad = [r for r in rows if r["violation"]]
    print("soundness: " + ("no certified w reached by a simulated trajectory" if not bad
                           else f"VIOLATED at w = {[r['w_mm'] for r in bad]}"))
    return 0 if not bad else 1


if __name__ == "__main__":
    raise SystemExit(main())
