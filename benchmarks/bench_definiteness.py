"""Exact positive definiteness: the SOS engine's strategies against the pure-Python LDL.

Every exact certificate ends in "this rational Gram matrix is positive definite". The engine
(:mod:`lyapcheck.sos.definiteness`) picks Bareiss elimination on integers for small blocks and a
FLINT congruence (with the characteristic polynomial as fallback) for large ones. This script
times each strategy, in this one run, on the kind of matrix the rounding produces (a random
positive definite matrix rounded to dyadic rationals 2^-30, margin 1e-3 of its scale), against
:func:`lyapcheck.exact.ldl_pivots` (the Fraction ``L D L^T``, the tests' independent second opinion),
and checks that all of them agree, also on a matrix made indefinite by one rank-one change.

Run:  python benchmarks/bench_definiteness.py [--sizes 10 20 40 80 120]
"""

from __future__ import annotations

import argparse
import time
from fractions import Fraction
from typing import Callable

import numpy as np


def dyadic_matrix(n: int, seed: int, indefinite: bool = False) -> tuple[tuple[Fraction, ...], ...]:
    rng = np.random.default_rng(seed)
    B = rng.normal(size=(n, n))
    A = B @ B.T / n + 1e-3 * np.eye(n)
    if indefinite:
        v = rng.normal(size=n)
        A = A - 2 * float(np.linalg.eigvalsh(A)[-1]) * np.outer(v, v) / float(v @ v)
    scale = 2**30
    rounded = np.round(A * scale).astype(np.int64)
    rounded = (rounded + rounded.T) // 2
    return tuple(tuple(Fraction(int(v), scale) for v in row) for row in rounded)


def timed(check: Callable[[tuple[tuple[Fraction, ...], ...]], bool],
          m: tuple[tuple[Fraction, ...], ...]) -> tuple[bool, float]:
    start = time.perf_counter()
    verdict = check(m)
    return verdict, time.perf_counter() - start


def _ldl_positive_definite(m: tuple[tuple[Fraction, ...], ...]) -> bool:
    """The pure-Python second opinion: every pivot of the exact ``L D L^T`` positive."""
    from lyapcheck import exact

    pivots = exact.ldl_pivots(m)
    return pivots is not None and all(p > 0 for p in pivots)


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--sizes", type=int, nargs="+", default=[10, 20, 40, 80, 120])
    parser.add_argument("--ldl-max", type=int, default=80, help="largest size given to the pure-Python LDL")
    args = parser.parse_args()

    from lyapcheck import exact
    from lyapcheck.sos import definiteness as d

    strategies: dict[str, Callable[[tuple[tuple[Fraction, ...], ...]], bool]] = {
        "engine (auto)": d.is_positive_definite,
        "Bareiss (integers)": exact.leading_minors_positive,
        "FLINT congruence": lambda m: bool(d._congruence_positive_definite(m)),
        "FLINT charpoly": d._charpoly_positive_definite,
        "Fraction LDL": _ldl_positive_definite,
    }
    print(f"{'size':>5} " + " ".join(f"{name:>20}" for name in strategies) + "   LDL / engine")
    for n in args.sizes:
        row, verdicts = [], set()
        times: dict[str, float] = {}
        for name, check in strategies.items():
            if name == "Fraction LDL" and n > args.ldl_max:
                row.append(f"{'(skipped)':>20}")
                continue
            if name == "Bareiss (integers)" and n > 80:
                row.append(f"{'(skipped)':>20}")
                continue
            for indefinite in (False, True):
                verdict, elapsed = timed(check, dyadic_matrix(n, n, indefinite))
                verdicts.add((indefinite, verdict))
                if not indefinite:
                    times[name] = elapsed
            row.append(f"{times[name]:>19.4f}s")
        agree = verdicts == {(False, True), (True, False)}
        ratio = times["Fraction LDL"] / times["engine (auto)"] if "Fraction LDL" in times else float("nan")
        print(f"{n:>5} " + " ".join(row) + f"   {ratio:10.1f}x" + ("" if agree else "   DISAGREE"))
    print("every strategy says definite for the PD matrix and not for the indefinite one, unless marked DISAGREE")


if __name__ == "__main__":
    main()
