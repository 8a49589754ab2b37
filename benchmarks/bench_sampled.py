"""The largest sampling period proved for a sampled-data loop, against its linearization's critical
period (issue 44's target: within 20 %).

For each sampled-data model file (default: the shipped pendulum under a digital PD law), runs
``lyapcheck certify FILE --maximize PARAM=LO..HI --steps N`` through the API (every value tried is
decided exactly, in ball arithmetic) and computes the critical period of the same linearization in
floating point (scipy's ``expm``, bisection on the spectral radius), then prints the proved period,
the first failed one, the critical period, their ratio and the time.

    python benchmarks/bench_sampled.py [--file F --param T --range 0.01..1] [--steps 12]
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np
from scipy.linalg import expm

ROOT = Path(__file__).resolve().parents[1]


def critical_period(A: np.ndarray, B: np.ndarray, K: np.ndarray, lo: float, hi: float) -> float:
    """The smallest period in (lo, hi] where the spectral radius of exp(AT) + Gamma(T)BK reaches 1."""
    n, m = B.shape

    def radius(T: float) -> float:
        M = np.zeros((n + m, n + m))
        M[:n, :n], M[:n, n:] = A * T, B * T
        E = expm(M)
        return float(max(abs(np.linalg.eigvals(E[:n, :n] + E[:n, n:] @ K))))

    for _ in range(60):
        mid = (lo + hi) / 2
        lo, hi = (mid, hi) if radius(mid) < 1 else (lo, mid)
    return hi


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--file", default=str(ROOT / "examples" / "models" / "pendulum-digital-pd.toml"))
    parser.add_argument("--param", default="T")
    parser.add_argument("--range", default="0.01..1")
    parser.add_argument("--steps", type=int, default=12)
    args = parser.parse_args()

    from lyapcheck.api import certify_extremum
    from lyapcheck.models.classes.sampled import linear_parts
    from lyapcheck.models.language.sampling import load_sampled

    lo, hi = (float(x) for x in args.range.split(".."))
    A, B, K = (np.array(M, dtype=float) for M in linear_parts(load_sampled(args.file)))  # type: ignore[misc]
    critical = critical_period(A, B, K, lo, hi)
    start = time.perf_counter()
    found = certify_extremum(args.file, f"{args.param}={args.range}", direction="max", steps=args.steps)
    seconds = time.perf_counter() - start
    proved = float(found.proved) if found.proved is not None else float("nan")
    failed = f"{float(found.failed.value):.6g} ({found.failed.outcome})" if found.failed is not None else "none"
    print("| file | proved period s | first failed s | critical period s (float) | proved / critical | "
          "values tried | wall s |")
    print("|---|---|---|---|---|---|---|")
    print(f"| {Path(args.file).name} | {proved:.6g} | {failed} | {critical:.6g} | {proved / critical:.4f} | "
          f"{len(found.steps)} | {seconds:.1f} |")


if __name__ == "__main__":
    main()
