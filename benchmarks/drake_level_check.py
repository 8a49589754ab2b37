"""Is a level of ``V = z' S z`` (the LQR cost-to-go) valid on the true loop? Issue 42's anchor is Drake's
``RegionOfAttraction`` level 3.97 for the cart-pole, computed on the cubic Taylor model of the loop:
a region of attraction of the Taylor model, not proved for the true loop.

:func:`decrease_counterexample` looks for a point of the true loop where ``V' >= 0`` at the smallest
``V`` it can find (floating point: rays of ``S``'s whitened coordinates, the first level along each
where ``V' >= 0``, then a short random descent of ``V`` along the surface ``V' = 0``), moves it a
little outward so that ``V'`` is clearly positive, rounds it to a rational point and confirms
``V' > 0`` there by ball arithmetic (python-flint arb, lyapcheck's own enclosure of the model file's
true field, :class:`lyapcheck.models.engines.interval_field.LieDerivative`). A point found and
confirmed with ``V`` below a level shows that level is not one of a Lyapunov sublevel set on the
true loop (``{V <= level}`` contains a point where ``V`` does not decrease). The float search uses the
sympy field of ``benchmarks/robot_lqr.py`` (independent of lyapcheck), the confirmation lyapcheck's.

Run alone:  python benchmarks/drake_level_check.py [STEM] [LEVEL]
"""

from __future__ import annotations

import sys
from fractions import Fraction
from pathlib import Path
from typing import Any

import numpy as np
import sympy as sp

sys.path.insert(0, str(Path(__file__).resolve().parent))
import robot_lqr  # noqa: E402  (beside this file)

#: Drake 1.51's RegionOfAttraction level of z' S z on the cubic Taylor model (issue 42's anchor)
DRAKE_TAYLOR_LEVELS: dict[str, float] = {"robot-cart-pole-lqr": 3.97}
#: rays of the float search (fixed seed), the ratio of successive levels along them, the descent's steps
RAYS, RATIO, DESCENT_STEPS = 20000, 1.02, 400
#: the point confirmed is the one found moved outward by this factor (V' clearly positive), with this
#: many significant digits per coordinate
OUTWARD, DIGITS = 1.002, 8
#: uniform samples of the [domain] box for a level's share
BOX_SAMPLES = 400_000


def box_share(stem: str, S: np.ndarray, level: float, seed: int = 0) -> float:
    """The share of BOX_SAMPLES uniform points of the model's ``[domain]`` box inside ``{z' S z <= level}``."""
    lo, hi = domain_box(stem)
    X = lo + (hi - lo) * np.random.default_rng(seed).random((BOX_SAMPLES, len(lo)))
    return float(np.mean(np.sum((X @ S) * X, axis=1) <= level))


def domain_box(stem: str) -> tuple[np.ndarray, np.ndarray]:
    import tomllib

    z, _ = robot_lqr.closed_loop(stem)
    domain = tomllib.loads((robot_lqr.MODELS / f"{stem}.toml").read_text())["domain"]
    return (np.array([float(domain[str(s)][0]) for s in z]), np.array([float(domain[str(s)][1]) for s in z]))


def _float_derivative(stem: str, S: np.ndarray) -> Any:
    """``V'(Z) = 2 z' S f(z)`` on rows ``Z``, with the sympy field of robot_lqr (NaN-safe)."""
    z, f = robot_lqr.closed_loop(stem)
    rhs = sp.lambdify(z, f, "numpy")

    def derivative(Z: np.ndarray) -> np.ndarray:
        with np.errstate(all="ignore"):
            F = np.stack([np.broadcast_to(np.asarray(c, dtype=float), Z.shape[:1]) for c in rhs(*Z.T)], axis=1)
            return np.asarray(2 * np.sum((Z @ S) * F, axis=1))
    return derivative


def decrease_counterexample(stem: str, S: np.ndarray, seed: int = 0) -> dict[str, Any] | None:
    """The point of the module docstring: its coordinates (exact rationals as text), ``V`` (exact), ``V'``
    (float, sympy's field) and ``V'``'s ball enclosure (lyapcheck's), or None when no ray meets ``V' >= 0``
    or the ball arithmetic does not confirm ``V' > 0`` at the rounded point."""
    n = len(S)
    derivative = _float_derivative(stem, S)
    L = np.linalg.cholesky(np.linalg.inv(S))  # z = L y: V = |y|^2
    rng = np.random.default_rng(seed)
    U = rng.normal(size=(RAYS, n))
    U /= np.linalg.norm(U, axis=1)[:, None]
    D = U @ L.T
    first = np.full(RAYS, np.inf)
    level = 1e-4
    while level < 1e4 and np.isinf(first).any():
        bad = ~(derivative(D * np.sqrt(level)) < 0) & np.isinf(first)
        first[bad] = level
        level *= RATIO
    if not np.isfinite(first).any():
        return None
    k = int(np.argmin(first))
    best = D[k] * np.sqrt(first[k])
    # a random descent of V among points with V' >= 0 (each step a smaller V, V' still >= 0)
    step = 0.05
    for _ in range(DESCENT_STEPS):
        trial = best * (1 - step * rng.random()) + step * np.sqrt(first[k]) * (L @ rng.normal(size=n)) / np.sqrt(n)
        if float(trial @ S @ trial) < float(best @ S @ best) and derivative(trial[None, :])[0] >= 0:
            best = trial
        else:
            step *= 0.99
    point = [Fraction(format(float(x * OUTWARD), f".{DIGITS}g")) for x in best]
    exact = [[Fraction(format(float(S[i][j]), ".17g")) for j in range(n)] for i in range(n)]
    V = sum(point[i] * exact[i][j] * point[j] for i in range(n) for j in range(n))
    enclosure = ball_derivative(stem, exact, point)
    if enclosure is None:
        return None
    return {"point": [str(x) for x in point], "V": V,
            "V_dot_float": float(derivative(np.array([[float(x) for x in point]]))[0]),
            "V_dot_ball": enclosure}


def ball_derivative(stem: str, S: list[list[Fraction]], point: list[Fraction]) -> tuple[float, float] | None:
    """``V' = grad V . f`` at the rational ``point`` (deviations) on the model file's true loop, enclosed by
    ball arithmetic (lyapcheck's LieDerivative on python-flint arb balls): its lower and upper bound
    (floats rounded outward), or None when the enclosure's lower bound is not above 0."""
    import flint

    from lyapcheck.models.classes import recast_regions
    from lyapcheck.models.engines.interval_field import BallLoop, LieDerivative
    from lyapcheck.models.language.modelfile import load_any_model
    from lyapcheck.sos.polynomials import to_fmpq

    model = load_any_model(robot_lqr.MODELS / f"{stem}.toml")
    loop = recast_regions.proved_loop(model, 60)
    ring, n = loop.ring, loop.n
    z = [ring.gen(s) for s in loop.system.states]
    V = sum((z[i] * z[j] * to_fmpq(S[i][j]) for i in range(n) for j in range(n)), ring.zero())
    lie = LieDerivative(BallLoop(loop.system), ring, V)
    value = lie([flint.arb(flint.fmpq(x.numerator, x.denominator)) for x in point])
    lower, upper = value.lower(), value.upper()
    if not lower > 0:
        return None
    return float(lower), float(upper)  # (the document's figures: the enclosure's ends, the lower one > 0 exactly)


def main() -> int:
    import argparse

    parser = argparse.ArgumentParser(description="Whether a level of an LQR robot's z' S z is valid on its true loop.")
    parser.add_argument("stem", nargs="?", default="robot-cart-pole-lqr", choices=sorted(robot_lqr.PLANTS),
                        help="the example's file stem (default robot-cart-pole-lqr)")
    parser.add_argument("level", nargs="?", type=float, default=None,
                        help="the level of z' S z to check (default: Drake's Taylor-model level, 3.97 for the cart-pole)")
    args = parser.parse_args()  # (bad input: argparse's one-line error, exit 2)
    stem = args.stem
    sys.path.insert(0, str(Path(__file__).resolve().parent))
    from bench_robot_roa import rounded_cost_to_go

    S = rounded_cost_to_go(stem)
    level = args.level if args.level is not None else DRAKE_TAYLOR_LEVELS.get(stem, 3.97)
    print(f"{stem}: share of the [domain] box in {{z' S z <= {level:g}}}: {100 * box_share(stem, S, level):.4g} % "
          f"({BOX_SAMPLES} uniform samples)")
    found = decrease_counterexample(stem, S)
    if found is None:
        print("  no point with V' >= 0 found and confirmed")
        return 0
    print(f"  V' > 0 at z = ({', '.join(found['point'])}): V = {float(found['V']):.6g}, V' = {found['V_dot_float']:.4g} "
          f"(float), in [{found['V_dot_ball'][0]:.6g}, {found['V_dot_ball'][1]:.6g}] (ball arithmetic): level "
          f"{level:g} is " + ("shown invalid on the true loop" if found["V"] < level else "not shown invalid by this point"))
    return 0


if __name__ == "__main__":
    sys.exit(main())
