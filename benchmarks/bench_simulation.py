"""Simulated trajectories per second: one batched call against a per-trajectory solve_ivp loop.

    python benchmarks/bench_simulation.py [--n 10000] [--subset 20] [--rtol 1e-8]

Workload: ``n`` parameter sets around the paper's (alpha_d, sigma0, k_d, Delta_LOS, initial
cross-track error drawn at random, ILOS and conventional LOS alternating), the saturated ODS
loop with the paper's constant sinking disturbance, 100 s each with the tail integrals.

* batched: :func:`lyapcheck.paper.simulation.runner.simulate`, all ``n`` in one call (Dormand-Prince
  5(4), a step per trajectory, measurements accumulated on the fly);
* loop: ``scipy.integrate.solve_ivp(method="RK45")`` (the same Dormand-Prince pair) with the
  same ``rtol`` and per-component ``atol``, one trajectory at a time, on the same right-hand
  side (the model called with a batch of one), split at the tail start like the batched run.
  The loop is timed on a random subset and extrapolated per trajectory (said in the output).

Both are checked against a tight reference (LSODA, rtol 1e-11) on the subset, so the ratio is
quoted together with the accuracy each side achieved. Everything is measured in this one run.
"""

from __future__ import annotations

import argparse
import time

import numpy as np
from scipy.integrate import solve_ivp

from lyapcheck.paper.simulation.disturbances import Constant
from lyapcheck.paper.simulation.model import ClosedLoop, LoopParams
from lyapcheck.paper.simulation.runner import simulate
from lyapcheck.paper.simulation.scenarios import paper_problem

HORIZON, TAIL = 100.0, 10.0


def workload(n: int, seed: int) -> tuple[LoopParams, np.ndarray]:
    rng = np.random.default_rng(seed)
    params = LoopParams.from_problem(
        paper_problem(), controller="ilos",
        alpha_d=rng.uniform(300, 1500, n), sigma0=rng.uniform(0.005, 0.05, n), k_d=rng.uniform(0.05, 0.5, n),
        delta_los=rng.uniform(0.3e-3, 2e-3, n), integral=(np.arange(n) % 2 == 0).astype(float),
    )
    p0 = np.c_[np.zeros(n), rng.uniform(-0.05, 0.05, n)]
    return params, p0


def solve_one(loop: ClosedLoop, y0: np.ndarray, *, method: str, rtol: float, atol: np.ndarray) -> np.ndarray:
    """One trajectory with solve_ivp, restarted at the tail start (a time discontinuity)."""
    y = y0
    for a, b in ((0.0, HORIZON - TAIL), (HORIZON - TAIL, HORIZON)):
        def fun(t: float, x: np.ndarray, mid: float = 0.5 * (a + b)) -> np.ndarray:
            return loop.rhs(np.array([t]), x[None], np.array([mid])).dy[0]

        sol = solve_ivp(fun, (a, b), y, method=method, rtol=rtol, atol=atol)
        if not sol.success:
            raise RuntimeError(sol.message)
        y = sol.y[:, -1]
    return y


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--n", type=int, default=10_000, help="parameter sets in the batch")
    parser.add_argument("--subset", type=int, default=20, help="trajectories timed with the solve_ivp loop")
    parser.add_argument("--rtol", type=float, default=1e-8)
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args()

    dist = Constant(np.array([0.0, -0.088e-3]))
    params, p0 = workload(args.n, args.seed)
    # warm-up (lambdify compilation, imports) outside both timings
    simulate(params.take(np.arange(2)), p0=p0[:2], disturbance=dist, horizon=1.0, tail=0.5)

    t0 = time.perf_counter()
    res = simulate(params, p0=p0, disturbance=dist, horizon=HORIZON, tail=TAIL, rtol=args.rtol)
    t_batch = time.perf_counter() - t0
    ok = int(np.sum(res.measurements.status == 0))

    rng = np.random.default_rng(args.seed + 1)
    subset = np.sort(rng.choice(args.n, size=min(args.subset, args.n), replace=False))
    loop = res.loop
    y0 = loop.initial_state(p0)
    scale = np.maximum(np.hypot(p0[:, 0], p0[:, 1]), params.delta_los)
    atol = loop.atol(args.rtol, scale)
    t0 = time.perf_counter()
    loop_states = [solve_one(loop.take(np.array([i])), y0[i], method="RK45", rtol=args.rtol, atol=atol[i])
                   for i in subset]
    t_loop = time.perf_counter() - t0
    per_traj_loop = t_loop / subset.size

    # solve_ivp reaches less accuracy than the batched integrator at the same tolerance (it
    # steps across the saturation kink); a second loop with rtol / 100 shows the cost of at least
    # matching the batched accuracy
    t0 = time.perf_counter()
    tight_states = [solve_one(loop.take(np.array([i])), y0[i], method="RK45", rtol=args.rtol / 100,
                              atol=atol[i] / 100) for i in subset]
    per_traj_tight = (time.perf_counter() - t0) / subset.size

    refs = np.array([solve_one(loop.take(np.array([i])), y0[i], method="LSODA", rtol=1e-11, atol=atol[i] * 1e-4)
                     for i in subset])
    unit = loop.atol(1.0, scale)[subset]  # natural scale of each component
    err_batch = np.max(np.abs(res.integration.y[subset] - refs) / unit)
    err_loop = np.max(np.abs(np.array(loop_states) - refs) / unit)
    err_tight = np.max(np.abs(np.array(tight_states) - refs) / unit)

    rate_batch = args.n / t_batch
    rate_loop = 1.0 / per_traj_loop
    print(f"workload: {args.n} parameter sets (ILOS and LOS), saturated ODS loop, {HORIZON:g} s each, rtol {args.rtol:g}")
    print(f"batched (one call, {ok}/{args.n} ok):  {t_batch:8.2f} s  -> {rate_batch:10.1f} trajectories/s")
    print(f"solve_ivp RK45 loop: {subset.size} trajectories timed in {t_loop:.2f} s, extrapolated per trajectory "
          f"-> {rate_loop:10.2f} trajectories/s ({per_traj_loop * args.n:.0f} s for all {args.n})")
    print(f"solve_ivp RK45 loop at rtol {args.rtol / 100:g}: extrapolated -> {1.0 / per_traj_tight:10.2f} trajectories/s")
    print(f"accuracy on the {subset.size} timed trajectories, max error / natural scale vs LSODA rtol 1e-11: "
          f"batched {err_batch:.1e}, solve_ivp loop {err_loop:.1e}, solve_ivp loop at rtol/100 {err_tight:.1e}")
    print(f"speed-up (batched / loop, same rtol and atol, measured in this run): {rate_batch / rate_loop:.0f}x")
    print(f"speed-up against the loop at rtol/100 (error at or below the batched one): {rate_batch * per_traj_tight:.0f}x")


if __name__ == "__main__":
    main()
