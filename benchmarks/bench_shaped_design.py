"""The shaped quadratic V's design (``lyapcheck/models/classes/shaped_quadratic.py``) on the LQR robots of
issue 42, floating point only: what the proposal reaches before any proof.

For each robot (``examples/models/robot-*-lqr.toml``) it runs :func:`shaped_quadratic` with the class's
60 s as its deadline and prints: the design's wall time, its rounds, the start it kept (``start``), the
sampled critical level of the proposed ``P`` (the smallest ``V`` at which a ray of its whitened
coordinates sees ``V' >= 0``, the design's own sampler, rate 0), and, inside ``{V <= c}`` for ``c`` the
critical level and a quarter of it (the proof reaches only part of the sampled level): the share of the
``[domain]`` box (the design's 50 000 uniform samples) and the share of the box's CONVERGING starts, i.e. of
the simulated region of attraction, which is what issue 42 counts (``roa_share``: the same 1 600 uniform
starts, seed 0, simulated on the true loop as :func:`recast_regions.simulated_check` does). The same figures
for the linearization's ``P`` (``J'P + PJ = -I``) come first.

Run:  PYTHONPATH=. python benchmarks/bench_shaped_design.py [--only cart-pole ...] [--save DIR]
(``--save``: each proposed ``P`` as ``DIR/<stem>.npy``, e.g. to prove it with ``ball_level`` separately).
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path
from typing import Any

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
ROBOTS = {"cart-pole": "robot-cart-pole-lqr", "acrobot": "robot-acrobot-lqr", "pendubot": "robot-pendubot-lqr",
          "planar-quadrotor": "robot-planar-quadrotor-lqr"}


def converging(loop: Any, box: tuple[Any, Any]) -> tuple[np.ndarray, np.ndarray]:
    """The starts ``simulated_check`` simulates (deviations) and which of them converge."""
    from lyapcheck.models.classes.recast_regions import (CONVERGED_RADIUS, SIMULATED_ESCAPE, SIMULATED_GRID,
                                                         SIMULATED_HORIZON)
    from lyapcheck.models.engines.recast_numeric import distances, simulate_ends

    lo, hi = box
    Z = lo + (hi - lo) * np.random.default_rng(0).random((SIMULATED_GRID ** 2, loop.n))
    eq = np.array([float(loop.system.values[s]) for s in loop.system.states])
    dev, sim = simulate_ends(loop.system, Z + eq, SIMULATED_HORIZON,
                             escape=SIMULATED_ESCAPE * float(np.max(np.asarray(hi) - np.asarray(lo))))
    return Z, sim.ok & (distances(loop.system, dev) < CONVERGED_RADIUS)


def figures(sampler: Any, P: np.ndarray, Z: np.ndarray, conv: np.ndarray) -> str:
    c = sampler.critical_level(P)
    out = [f"crit {c:8.4g}"]
    for frac in (1.0, 0.25):
        inside = np.sum((Z @ P) * Z, axis=1) <= frac * c
        out.append(f"at {frac:4}: box {100 * sampler.share(P, frac * c):5.1f} % roa {100 * np.mean(inside[conv]):5.1f} %")
    return "  ".join(out)


def main() -> None:
    from lyapcheck.models.classes import recast_classes as rc
    from lyapcheck.models.classes import shaped_quadratic as sq
    from lyapcheck.models.classes.linearization import lyapunov_solution
    from lyapcheck.models.classes.recast_regions import comparison_box
    from lyapcheck.models.language.modelfile import load_any_model

    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--only", nargs="*", choices=sorted(ROBOTS), default=list(ROBOTS))
    parser.add_argument("--save", type=Path, default=None, help="a directory for the proposed P's (.npy)")
    args = parser.parse_args()
    for name in args.only:
        model = load_any_model(str(ROOT / "examples" / "models" / f"{ROBOTS[name]}.toml"))
        loop = rc.base_loop(model.system)
        J = rc.jacobian(loop)
        assert not isinstance(J, str), J
        box = comparison_box(model, loop)
        Z, conv = converging(loop, box)
        sampler = sq.Sampler(loop, box)
        exact = lyapunov_solution(J)
        assert exact is not None
        P0 = np.array([[float(x) for x in row] for row in exact])
        print(f"{name} ({loop.n} states, {100 * np.mean(conv):.1f} % of the box converges)")
        print(f"  linearization's P            {figures(sampler, P0, Z, conv)}")
        start = time.perf_counter()
        shaped = sq.shaped_quadratic(loop, J, box, deadline=time.perf_counter() + 60)
        took = time.perf_counter() - start
        assert shaped is not None
        print(f"  shaped ({took:5.1f} s, {shaped.rounds:2d} rounds)  {figures(sampler, shaped.P, Z, conv)}")
        print(f"    start: {shaped.start} (scored share {shaped.start_share:.4g}), final scored share {shaped.share:.4g}")
        for note in shaped.notes:
            print(f"    {note}")
        if args.save is not None:
            args.save.mkdir(parents=True, exist_ok=True)
            np.save(args.save / f"{ROBOTS[name]}.npy", shaped.P)


if __name__ == "__main__":
    main()
