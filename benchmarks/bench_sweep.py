"""Sweep throughput and memory, every ratio measured in this one run.

1. ``sector_ges`` certified points per second: the sweep's path (compiled conic data, Clarabel
   called directly, exact check; :mod:`sweeps.fast_sector`, :mod:`lyapcheck.paper.conditions.compiled`) in one process and on every core,
   against a naive loop that builds a fresh cvxpy problem per point, solves it and runs the same
   rounding and exact check; and against Clarabel's own solve time per problem.
2. Simulated trajectories per second: one batched call of the toolkit's integrator against a
   per-point ``scipy.integrate.solve_ivp`` loop with the same method (Dormand-Prince 5(4),
   ``RK45``) and the same tolerances, on the same closed loops (the largest final-state
   difference is printed, relative to the state scale).
3. Peak memory of the storage path for a 10^4 and a 10^5 point sweep. The certificate and
   simulation work is replaced by a cheap stub (every variable filled from the coordinates),
   so that what is measured is the sweep loop and the Zarr store alone: streamed to disk, the
   peak should not grow with the grid.
4. Peak RSS of a REAL sweep (issue 11): 10^3 against 10^4 points, nothing stubbed, each in a
   fresh process with local worker processes (``--workers``). Configuration, said here because
   10^4 real points must finish in minutes: the shipped ``sweep-dmax-alpha.toml`` (its classes
   prop41_ges, prop41_iss, stabcond2, sector_ges, ultimate_bound and its d* x alpha_d axes) with
   a cheap simulation (one scenario, ``constant``, 2 s horizon, 1 s tail). Aim: the 10^4 peak
   within 10 % of the 10^3 one, for the main process and for the largest worker.

Run:  python benchmarks/bench_sweep.py [--points 400] [--trajectories 512] [--ivp 6] [--skip real-memory]
Note: on a shared machine the wall-clock figures depend on the load; CPU times are printed too.
"""

from __future__ import annotations

import argparse
import concurrent.futures as cf
import multiprocessing
import os
import resource
import tempfile
import time
import tracemalloc
from fractions import Fraction
from pathlib import Path
from typing import Any

import numpy as np

ROOT = Path(__file__).resolve().parents[1]


# -- 1. sector_ges -----------------------------------------------------------------------------

def _systems(n: int, seed: int) -> list[Any]:
    """Random gain sets around the paper's (alpha_d, k_d, sigma0, Delta_LOS), exact."""
    from lyapcheck.paper.certification import build_system
    from lyapcheck.paper.params import problem_from_sources

    base = problem_from_sources(ROOT / "examples" / "paper.toml", {})
    rng = np.random.default_rng(seed)
    out = []
    for _ in range(n):
        a, k, s, d = (float(x) for x in (rng.uniform(100, 3000), np.exp(rng.uniform(np.log(0.02), np.log(5))),
                                         np.exp(rng.uniform(np.log(1e-3), 0)), rng.uniform(2e-4, 4e-3)))
        problem = base.with_gains(alpha_d=Fraction(a), k_d=Fraction(k), sigma0=Fraction(s), delta_los=Fraction(d))
        out.append(build_system(problem, "derived"))
    return out


def _fast_chunk(seed_n: tuple[int, int]) -> tuple[float, float, int, float]:
    """Worker: warm up, then certify ``n`` points; (wall, clarabel seconds, certified, cpu)."""
    from sweeps import fast_sector

    seed, n = seed_n
    systems = _systems(n, seed)
    fast_sector.certify(systems[0])  # build the solver (first use in this process)
    start, cpu = time.perf_counter(), time.process_time()
    clarabel, certified = 0.0, 0
    for system in systems:
        result = fast_sector.certify(system)
        clarabel += result.solver["solve_seconds"]
        certified += result.status == "certified"
    return time.perf_counter() - start, clarabel, certified, time.process_time() - cpu


def _naive(system: Any) -> str:
    """Fresh cvxpy problem per point (constants, no parameters), then the same exact check."""
    import cvxpy as cp

    from lyapcheck import exact
    from lyapcheck import tolerances as tol
    from lyapcheck.paper.conditions import scaling, sector

    vertices = [system.vertex(Fraction(0)), system.vertex(system.rho_sup)]
    sc = scaling.choose(vertices)
    P = cp.Variable((2, 2), symmetric=True)
    m = cp.Variable()
    cons = [cp.trace(P) == 1, P >> m * np.eye(2), m <= 1]
    for a in (sc.matrix_to_scaled(v) for v in vertices):
        q = -(a.T @ P + P @ a)
        cons.append((q + q.T) / 2 >> m * np.eye(2))
    problem = cp.Problem(cp.Maximize(m), cons)
    problem.solve(solver=cp.CLARABEL, tol_gap_abs=tol.SOLVER_TOL_GAP_ABS, tol_gap_rel=tol.SOLVER_TOL_GAP_REL,
                  tol_feas=tol.SOLVER_TOL_FEAS, max_iter=tol.SOLVER_MAX_ITER)
    if problem.status != "optimal" or m.value is None or m.value <= 0:
        return "refuted" if sector.refutation(vertices) is not None else "not_certified"
    Pq = sc.p_from_scaled(exact.symmetrize(exact.rational_matrix(P.value)))
    rate = Fraction(1, 10**9)
    return "certified" if sector.exact_check(vertices, Pq, rate)[0] else "inconclusive"


def bench_sector(points: int, workers: int) -> None:
    print(f"1. sector_ges, {points} random gain sets around the paper's")
    wall1, clarabel, certified, cpu1 = _fast_chunk((7, points))
    per_point = wall1 / points
    per_clarabel = clarabel / points
    print(f"   sweep path, 1 process      : {points / wall1:9.0f} points/s  ({per_point * 1e3:.3f} ms/point, "
          f"cpu {cpu1 / points * 1e3:.3f} ms; {certified} certified)")
    share = [(7, points // workers)] * workers
    with cf.ProcessPoolExecutor(workers, mp_context=multiprocessing.get_context("fork")) as pool:
        t0 = time.perf_counter()
        results = list(pool.map(_fast_chunk, share))
        wall_n = max(r[0] for r in results)
    done_n = sum(n for _, n in share)
    rate_n = done_n / wall_n
    print(f"   sweep path, {workers} processes    : {rate_n:9.0f} points/s  ({1e3 / rate_n:.3f} ms/point of wall; "
          f"pool start-up excluded, {time.perf_counter() - t0:.2f} s in all)")
    n_naive = max(20, points // 10)
    systems = _systems(n_naive, 7)
    _naive(systems[0])
    t0, c0 = time.perf_counter(), time.process_time()
    for system in systems:
        _naive(system)
    naive = (time.perf_counter() - t0) / n_naive
    print(f"   naive fresh cvxpy loop     : {1 / naive:9.0f} points/s  ({naive * 1e3:.3f} ms/point, "
          f"cpu {(time.process_time() - c0) / n_naive * 1e3:.3f} ms; {n_naive} points)")
    print(f"   Clarabel's own solve time  : {per_clarabel * 1e3:9.3f} ms/problem")
    print(f"   ratio sweep/naive          : {naive / per_point:9.1f} x (1 process)   "
          f"{naive * rate_n:.1f} x ({workers} processes)   aim >= 20 x")
    print(f"   ratio time/Clarabel        : {per_point / per_clarabel:9.1f} x (1 process)   "
          f"{1 / rate_n / per_clarabel:.1f} x ({workers} processes)   aim <= 3 x")


# -- 2. simulation -----------------------------------------------------------------------------

def bench_simulation(trajectories: int, ivp: int) -> None:
    from scipy.integrate import solve_ivp

    from lyapcheck.paper.params import problem_from_sources
    from lyapcheck.paper.simulation.disturbances import Constant
    from lyapcheck.integrator import DEFAULT_RTOL
    from lyapcheck.paper.simulation.model import ClosedLoop, LoopParams
    from lyapcheck.paper.simulation.runner import simulate

    problem = problem_from_sources(ROOT / "examples" / "paper.toml", {})
    rng = np.random.default_rng(3)
    n = trajectories
    params = LoopParams.from_problem(problem, alpha_d=rng.uniform(300, 1500, n), k_d=rng.uniform(0.05, 0.5, n))
    sink = Constant(np.array([0.0, -0.088e-3]))
    horizon, tail = 100.0, 10.0
    p0 = (0.0, -0.040)
    simulate(params.take(np.arange(2)), p0=p0, disturbance=sink, horizon=horizon, tail=tail)  # warm caches
    t0, c0 = time.perf_counter(), time.process_time()
    res = simulate(params, p0=p0, disturbance=sink, horizon=horizon, tail=tail, rtol=DEFAULT_RTOL)
    batched = (time.perf_counter() - t0) / n
    batched_cpu = (time.process_time() - c0) / n
    loop = ClosedLoop(params, sink, np.full(n, horizon - tail))
    y0 = loop.initial_state(p0)
    atol = loop.atol(DEFAULT_RTOL, np.maximum(np.hypot(y0[:, 0], y0[:, 1]), params.delta_los))
    t0, c0 = time.perf_counter(), time.process_time()
    worst = 0.0
    for i in range(ivp):
        sub = loop.take(np.array([i]))
        y = y0[i]
        for a, b in ((0.0, horizon - tail), (horizon - tail, horizon)):  # restart at the tail breakpoint
            def fun(t: float, x: np.ndarray, a: float = a) -> np.ndarray:
                return sub.rhs(np.array([t]), x[None], np.array([a])).dy[0]

            sol = solve_ivp(fun, (a, b), y, method="RK45", rtol=DEFAULT_RTOL, atol=atol[i], max_step=tail / 20)
            y = sol.y[:, -1]
        scale = loop.atol(1.0, np.full(1, 0.04))[0]
        worst = max(worst, float(np.max(np.abs(y - res.integration.y[i]) / scale)))
    per_ivp = (time.perf_counter() - t0) / ivp
    per_ivp_cpu = (time.process_time() - c0) / ivp
    print(f"2. simulation, paper loop with a constant disturbance, {horizon:g} s, rtol {DEFAULT_RTOL:g}")
    print(f"   batched ({n} trajectories) : {1 / batched:9.1f} trajectories/s (cpu {batched_cpu * 1e3:.1f} ms each)")
    print(f"   solve_ivp RK45 per point   : {1 / per_ivp:9.2f} trajectories/s (cpu {per_ivp_cpu * 1e3:.0f} ms each, "
          f"{ivp} points; largest final-state difference {worst:.1e} of the state scale)")
    print(f"   ratio batched/solve_ivp    : {per_ivp / batched:9.1f} x   aim >= 50 x")


# -- 3. memory ---------------------------------------------------------------------------------

def _stub(text: str, coords: np.ndarray) -> dict[str, np.ndarray]:
    """Every schema variable from the coordinates, no certificate, no simulation."""
    from sweeps.evaluate import empty_result

    out = empty_result(len(coords))
    x = coords[:, 0]
    out["status_sector_ges"] = (x < np.median(x)).astype(np.int8)
    out["eps_bound_m"] = 1e-3 + x * 1e-6
    out["sim_eps_sup_m"] = 1e-4 + x * 1e-7
    out["ratio_certified_over_simulated"] = out["eps_bound_m"] / out["sim_eps_sup_m"]
    out["done"] = np.ones(len(coords), dtype=bool)
    return out


def _memory_spec(points: int) -> str:
    text = (ROOT / "examples" / "sweep-dmax-alpha.toml").read_text()
    head = text[:text.index("[sweep]")]
    side = int(round(np.sqrt(points)))
    return head + f"""[sweep]
chunk_size = 1000
[[sweep.axes]]
name = "d_max"
start = "0 mm/s"
stop = "0.5 mm/s"
num = {side}
[[sweep.axes]]
name = "alpha_d"
start = 150
stop = 2400
num = {points // side}
"""


def bench_memory() -> None:
    from sweeps.run import run_sweep
    from sweeps.runners import InlineRunner
    from sweeps.spec import parse_spec

    print("3. peak memory of the storage path (certify/simulate stubbed by a cheap function)")
    with tempfile.TemporaryDirectory() as tmp:  # one-time imports and caches out of the figures
        run_sweep(parse_spec(_memory_spec(100)), Path(tmp) / "w.zarr", runner=InlineRunner(), evaluator=_stub)
    for points in (10**4, 10**5):
        spec = parse_spec(_memory_spec(points))
        with tempfile.TemporaryDirectory() as tmp:
            tracemalloc.start()
            t0 = time.perf_counter()
            run_sweep(spec, Path(tmp) / "m.zarr", runner=InlineRunner(), evaluator=_stub)
            _, peak = tracemalloc.get_traced_memory()
            tracemalloc.stop()
            wall = time.perf_counter() - t0
        rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
        print(f"   {spec.n_points:>7} points: peak traced {peak / 2**20:6.2f} MiB, process max RSS so far "
              f"{rss:6.0f} MiB, {wall:5.1f} s ({spec.n_points / wall:.0f} points/s through the store)")


def _real_spec(points: int) -> str:
    text = (ROOT / "examples" / "sweep-dmax-alpha.toml").read_text()
    head = text[:text.index("[sweep]")]
    side = int(round(np.sqrt(points)))
    return head + f"""[sweep]
classes = ["prop41_ges", "prop41_iss", "stabcond2", "sector_ges", "ultimate_bound"]
chunk_size = 100
[[sweep.axes]]
name = "d_max"
start = "0 mm/s"
stop = "0.5 mm/s"
num = {side}
[[sweep.axes]]
name = "alpha_d"
start = 150
stop = 2400
num = {points // side}
scale = "log"
[simulation]
horizon = "2 s"
tail = "1 s"
scenarios = ["constant"]
initial_position = ["0 mm", "-40 mm"]
"""


def real_sweep_rss(points: int, workers: int) -> dict[str, Any]:
    """Run a real sweep of ``points`` points in this process; peak RSS of this process and its workers."""
    from sweeps.run import run_sweep
    from sweeps.spec import parse_spec

    spec = parse_spec(_real_spec(points))
    with tempfile.TemporaryDirectory() as tmp:
        t0 = time.perf_counter()
        run_sweep(spec, Path(tmp) / "r.zarr", workers=workers)
        wall = time.perf_counter() - t0
    return {"points": spec.n_points, "wall_s": wall,
            "self_max_rss_mib": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024,
            "worker_max_rss_mib": resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss / 1024}


def bench_real_memory(workers: int) -> None:
    import json
    import subprocess
    import sys

    print(f"4. peak RSS of a real sweep (dmax-alpha classes, 'constant' scenario, 2 s horizon; {workers} workers)")
    runs = {}
    for points in (10**3, 10**4):
        code = (f"import json, sys; sys.path.insert(0, {str(ROOT)!r}); sys.path.insert(0, {str(ROOT / 'benchmarks')!r}); "
                f"import bench_sweep as b; print(json.dumps(b.real_sweep_rss({points}, {workers})))")
        out = subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True, check=True)
        r = json.loads(out.stdout.strip().splitlines()[-1])
        runs[points] = r
        print(f"   {r['points']:>6} points: main process {r['self_max_rss_mib']:6.0f} MiB, largest worker "
              f"{r['worker_max_rss_mib']:6.0f} MiB, {r['wall_s']:6.1f} s ({r['points'] / r['wall_s']:.1f} points/s)")
    small, big = runs[10**3], runs[10**4]
    for key, label in (("self_max_rss_mib", "main process"), ("worker_max_rss_mib", "largest worker")):
        print(f"   ratio 10^4/10^3 peak RSS, {label:14}: {big[key] / small[key]:5.3f}   aim <= 1.10")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--points", type=int, default=400, help="gain sets for the sector_ges rate")
    parser.add_argument("--trajectories", type=int, default=512, help="batch size of the simulation rate")
    parser.add_argument("--ivp", type=int, default=6, help="trajectories of the solve_ivp loop")
    parser.add_argument("--workers", type=int, default=os.cpu_count() or 1)
    parser.add_argument("--skip", nargs="*", default=[], choices=["sector", "simulation", "memory", "real-memory"])
    args = parser.parse_args()
    print(f"machine: {os.cpu_count()} cores, load average {os.getloadavg()[0]:.2f}")
    if "sector" not in args.skip:
        bench_sector(args.points, args.workers)
    if "simulation" not in args.skip:
        bench_simulation(args.trajectories, args.ivp)
    if "memory" not in args.skip:
        bench_memory()
    if "real-memory" not in args.skip:
        bench_real_memory(args.workers)


if __name__ == "__main__":
    main()
