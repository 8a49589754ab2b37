"""Issue 42: how much of a 4-state robot's simulated region of attraction a quartic V could cover, and
what its ball-arithmetic proof costs (a measurement, not a certificate).

For each LQR robot of ``bench_robot_roa.py`` with 4 states, it fits a degree-4 V to simulations of the
true loop (``lyapcheck.models.classes.fitted_v.fit_v(..., any_size=True)``: the LQR examples' quadratic
part from the Lyapunov equation plus free cubic and quartic terms, the route's linear program) and prints,
in floating point only (sampling; nothing here is proved):

* the level the fit proposes (V' < 0 at every sample of its set) and the share of uniform starts of the
  ``[domain]`` box below it (every start of these boxes converges in simulation, so this is the share of
  the simulated region of attraction);
* the same for the LQR cost-to-go ``z' S z``: the smallest ``z' S z`` where sampling sees ``V' >= 0``,
  and the share of the box below it;

then runs :func:`lyapcheck.models.engines.quartic_cells.prove_sublevel` on the quartic at the proposed
level times each ``--scales`` factor, within ``--cells`` cells, and prints its outcome, cells and time.

Run:  python benchmarks/bench_quartic_fit.py [--only NAME ...] [--cells N] [--scales 1/16,1/4,1]
"""

from __future__ import annotations

import argparse
import sys
import time
import tomllib
from fractions import Fraction
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import robot_lqr  # noqa: E402  (beside this file)

MODELS = Path(__file__).resolve().parents[1] / "examples" / "models"
STEMS = {"cart-pole": "robot-cart-pole-lqr", "acrobot": "robot-acrobot-lqr", "pendubot": "robot-pendubot-lqr"}
#: uniform starts of the [domain] box for the shares, and random points of the sampled box for V' >= 0
SHARE_SAMPLES, DECREASE_SAMPLES = 100_000, 400_000
#: the cells' box is that of {z' P z <= this times the largest z' P z sampled in the quartic's set}
BOX_ROOM = 1.3


def main() -> int:
    from lyapcheck.models.classes import fitted_v as fv
    from lyapcheck.models.engines import quartic_cells as qc
    from lyapcheck.models.engines.interval_field import BallLoop, LieDerivative
    from lyapcheck.models.engines.recast_numeric import field_values, v_values
    from lyapcheck.models.language.modelfile import load_any_model

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--only", nargs="+", default=["cart-pole"], choices=sorted(STEMS))
    parser.add_argument("--cells", type=int, default=60_000)
    parser.add_argument("--scales", default="1/16,1/4,1")
    parser.add_argument("--quadratic", choices=["lyapunov", "lqr"], default="lyapunov",
                        help="V's quadratic part: the Lyapunov equation's P (the route's) or the LQR cost-to-go S")
    args = parser.parse_args()
    for label in args.only:
        stem = STEMS[label]
        path = MODELS / f"{stem}.toml"
        model = load_any_model(path)
        system = model.system
        n = system.n
        dom = tomllib.loads(path.read_text())["domain"]
        lo = np.array([float(dom[s][0]) for s in system.states])
        hi = np.array([float(dom[s][1]) for s in system.states])
        rng = np.random.default_rng(0)
        starts = lo + (hi - lo) * rng.random((SHARE_SAMPLES, n))
        t0 = time.perf_counter()
        _, S = robot_lqr.lqr(stem)
        S = np.asarray(S, dtype=float)
        got = fv.fit_v(system, system.ring, (lo, hi), any_size=True,
                       quadratic=S / np.max(np.linalg.eigvalsh(S)) if args.quadratic == "lqr" else None)
        fit_s = time.perf_counter() - t0
        if isinstance(got, str):
            print(f"{label}: no quartic fitted ({got})")
            continue
        claim = got.claim
        v = v_values(system, claim.V, starts)
        print(f"{label}: quartic V fitted in {fit_s:.1f} s; proposed level {float(claim.level):.4g}; "
              f"share of the [domain] box below it {100 * np.mean(v <= float(claim.level)):.1f} %")
        # the quadratic z' S z: the smallest level where sampling sees V' >= 0 (random points of the box
        # scaled by 2, and along rays)
        X = 2 * lo + 4 * (hi - lo) * rng.random((DECREASE_SAMPLES, n)) / 2
        with np.errstate(all="ignore"):
            g = 2 * np.einsum("ij,jk,ik->i", X, S, field_values(system, X))
        q = np.einsum("ij,jk,ik->i", X, S, X)
        bad = ~(g < 0) & (np.sum(X ** 2, axis=1) > 1e-6)
        first = float(np.min(q[bad])) if bad.any() else float("inf")
        qs = np.einsum("ij,jk,ik->i", starts, S, starts)
        print(f"{label}: z' S z: sampling sees V' >= 0 from level {first:.4g}; share of the box below it "
              f"{100 * np.mean(qs <= first):.1f} %")
        parts = qc.split_quadratic(system.ring, claim.V, n)
        assert not isinstance(parts, str)
        P = np.array([[float(x) for x in row] for row in parts[0]])
        clo = np.array([float(x) for x in claim.lo])
        chi = np.array([float(x) for x in claim.hi])
        inner = clo + (chi - clo) * rng.random((DECREASE_SAMPLES, n))
        vin = v_values(system, claim.V, inner)
        lie = LieDerivative(BallLoop(system), system.ring, claim.V)
        for text in args.scales.split(","):
            level = claim.level * Fraction(text)
            qmax = float(np.max(np.einsum("ij,jk,ik->i", inner, P, inner)[vin <= float(level)]))
            box_level = Fraction(BOX_ROOM * qmax).limit_denominator(1000)
            t0 = time.perf_counter()
            proof = qc.prove_sublevel(lie, system.ring, claim.V, level, box_level, args.cells)
            print(f"  proof at level {float(level):.4g} (share {100 * np.mean(v <= float(level)):.1f} %): "
                  f"{'proved' if proof.ok else 'not proved'}, {proof.face_cells} face pieces, {proof.cells} cells, "
                  f"{time.perf_counter() - t0:.1f} s; {proof.why[:160]}", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
