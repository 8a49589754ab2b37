"""Compiled-once re-solve versus fresh build-and-solve, for the certificate programs.

Prints, for the polytopic ``sector_ges`` program and the ``prop41`` program, the wall time per
re-solve of the DPP-compiled problem (new parameter values, same problem object) next to the
time of building a fresh cvxpy problem with constants and solving it, and their ratio, all
measured in this one run over the same random gain sets. Also prints the end-to-end time of
one ``certify`` call (all five classes) inside this process.

Run:  python benchmarks/bench_certify.py [--points 60]
"""

from __future__ import annotations

import argparse
import time
from fractions import Fraction

import numpy as np


def random_systems(n: int, seed: int) -> list:
    from lyapcheck.conditions.base import System

    rng = np.random.default_rng(seed)
    out = []
    for _ in range(n):
        kappa, sigma, k, delta = (Fraction(float(x)).limit_denominator(10**6) for x in
                                  (rng.uniform(0.02, 2), rng.uniform(0.005, 1), rng.uniform(0.1, 5), rng.uniform(0.05, 2)))
        A = ((-kappa, -kappa * sigma), (Fraction(0), -k))
        out.append(System("derived", A, ((Fraction(0), Fraction(0)), (Fraction(1), Fraction(0))), (Fraction(1), Fraction(0)),
                          1 / delta, sigma, delta, Fraction(1), Fraction(0)))
    return out


def fresh_sector(a_lo: np.ndarray, a_hi: np.ndarray) -> None:
    import cvxpy as cp

    P = cp.Variable((2, 2), symmetric=True)
    m = cp.Variable()
    cons = [cp.trace(P) == 1, P >> m * np.eye(2), m <= 1]
    for a in (a_lo, a_hi):
        q = -(a.T @ P + P @ a)
        cons.append((q + q.T) / 2 >> m * np.eye(2))
    cp.Problem(cp.Maximize(m), cons).solve(solver=cp.CLARABEL)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--points", type=int, default=60)
    args = parser.parse_args()

    from lyapcheck.conditions import scaling, sector
    from lyapcheck.conditions.sdp import solve

    systems = random_systems(args.points, seed=7)
    data = []
    for s in systems:
        verts = [s.vertex(Fraction(0)), s.vertex(s.rho_sup)]
        sc = scaling.choose(verts)
        data.append((sc.matrix_to_scaled(verts[0]), sc.matrix_to_scaled(verts[1])))

    prog = sector.program()  # compile once (first solve compiles)
    prog.A_lo.value, prog.A_hi.value = data[0]
    solve(prog.problem)

    t0 = time.perf_counter()
    clarabel = 0.0
    for a_lo, a_hi in data:
        prog.A_lo.value, prog.A_hi.value = a_lo, a_hi
        clarabel += solve(prog.problem).solve_seconds
    resolve = (time.perf_counter() - t0) / len(data)
    clarabel /= len(data)

    t0 = time.perf_counter()
    for a_lo, a_hi in data:
        fresh_sector(a_lo, a_hi)
    fresh = (time.perf_counter() - t0) / len(data)

    print(f"sector_ges program, {len(data)} gain sets")
    print(f"  re-solve of the compiled problem : {resolve * 1e3:8.2f} ms per point")
    print(f"  fresh build + solve              : {fresh * 1e3:8.2f} ms per point")
    print(f"  ratio fresh / re-solve           : {fresh / resolve:8.1f} x")
    print(f"  Clarabel's own solve time        : {clarabel * 1e3:8.2f} ms  (re-solve / Clarabel = {resolve / clarabel:.1f} x)")

    from lyapcheck.certification import CONDITION_ORDER, QUICK_CLASSES, run_conditions
    from lyapcheck.params import problem_from_sources

    problem = problem_from_sources("examples/paper.toml", {})
    for label, classes in (("quick classes (issue 3)", QUICK_CLASSES), ("all classes", CONDITION_ORDER)):
        run_conditions(problem, "derived", classes)  # warm: compile the programs
        t0 = time.perf_counter()
        run_conditions(problem, "derived", classes)
        print(f"certify, {label}, paper gains, warm process: {(time.perf_counter() - t0) * 1e3:.0f} ms")


if __name__ == "__main__":
    main()
