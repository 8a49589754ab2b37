"""A sampled-data loop's region of attraction on its true flow (``roa``,
lyapcheck.models.classes.sampled_regions): the proved figures, the time to prove and to verify them, and
the simulated true loop from starts drawn in the certified set.

For each sampled-data model file (default: the shipped ones), prints the level ``c`` of ``{V <= c}``, the
ball radius it lies in, the inter-sample factor ``Ce``, the remainder bound ``L2``, the seconds of the
search and of ``verify``'s re-derivation, then simulates the true loop (``simulate``'s engine) from
``--starts`` points drawn uniformly in the set: the share that converge within the default horizon, and
the alarms (a start whose state at a sampling instant has ``V > c``, or whose excursion between two instants
exceeds ``Ce |x(t_k) - x_eq|``; a proved claim makes this 0).

    LYAPCHECK_CERTIFICATE_STORE=off python benchmarks/bench_sampled_regions.py [FILE ...] [--starts 200]
"""

from __future__ import annotations

import argparse
import math
import time
from fractions import Fraction
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
DEFAULT = [ROOT / "examples" / "models" / f"pendulum-digital-{name}.toml" for name in ("pd", "sat-pd", "tanh-policy")]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("files", nargs="*", default=[str(p) for p in DEFAULT])
    parser.add_argument("--starts", type=int, default=200)
    parser.add_argument("--seed", type=int, default=1)
    args = parser.parse_args()

    from lyapcheck.models.classes import sampled_regions
    from lyapcheck.models.language.sampling import load_sampled
    from lyapcheck.models.surfaces.sampled_simulate import run_sampled

    rng = np.random.default_rng(args.seed)
    for path in args.files:
        model = load_sampled(path)
        begin = time.perf_counter()
        result = sampled_regions.roa(model)
        search = time.perf_counter() - begin
        print(f"{Path(path).name}: roa {result.status} in {search:.2f} s")
        if result.status != "certified":
            print(f"  {result.summary}")
            continue
        c = result.to_json()
        begin = time.perf_counter()
        ok, _ = sampled_regions.verify(model, c)
        checked = time.perf_counter() - begin
        cert = c["certificate"]
        P = np.array([[float(Fraction(x)) for x in row] for row in cert["P"]])
        level, Ce = float(Fraction(cert["level"])), float(Fraction(cert["flow"]["Ce"]))
        print(f"  level c = {level:.6g}, ball radius r = {float(Fraction(cert['radius'])):.6g}, Ce = {Ce:.4g}, "
              f"L2 = {float(Fraction(cert['flow']['L2'])):.4g}; verify {ok} in {checked:.3f} s")
        # uniform in the ellipsoid {e^T P e <= c}: a uniform point of the unit ball mapped by (P / c)^(-1/2)
        n = model.n
        d = rng.normal(size=(args.starts, n))
        d /= np.linalg.norm(d, axis=1, keepdims=True)
        d *= rng.uniform(size=(args.starts, 1)) ** (1 / n)
        w, U = np.linalg.eigh(P / level)
        x_eq = np.array([float(q) for q in model.equilibrium])
        starts = x_eq + d @ (U @ np.diag(w ** -0.5) @ U.T) * 0.999999
        begin = time.perf_counter()
        document = run_sampled(model, starts, "the certified set").document
        periods = 100
        series = run_sampled(model, starts, "the certified set", t_end=periods * float(model.period), series=True).series
        simulated = time.perf_counter() - begin
        x = series["x"].transpose("trajectory", "time", "state").values - x_eq
        V = np.einsum("rti,ij,rtj->rt", x, P, x)
        norms = np.linalg.norm(x, axis=2)
        leave = int(np.sum(np.any(V[:, ::5] > level * (1 + 1e-9), axis=1)))
        excursion = 0
        for k in range(0, norms.shape[1] - 1, 5):
            excursion += int(np.sum(np.any(norms[:, k:k + 6] > Ce * norms[:, k:k + 1] * (1 + 1e-9) + 1e-12, axis=1)))
        share = document["n_converged"] / document["n_trajectories"]
        print(f"  {args.starts} starts in the set: {share:.1%} converge within {document['t_end_s']:.3g} s "
              f"({document['n_diverged']} diverge); alarms over {periods} periods: {leave} left the set, "
              f"{excursion} excursions above Ce ({simulated:.1f} s of simulation)")
        if leave or excursion:
            raise SystemExit("ALARM: a simulated start contradicts the certified claim")
        assert math.isfinite(level)


if __name__ == "__main__":
    main()
