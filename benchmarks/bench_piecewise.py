"""How long ``linearization``'s piecewise-linear route takes (issue 44, item 3;
:mod:`lyapcheck.models.classes.piecewise_linearization`): the first-order part derived from the model, the
S-procedure LMI (Clarabel) and the exact check, on the shipped ReLU pendulum (continuous and its Euler map)
and on the same pendulum under ReLU copies of wider bias-free policies: the 2 x 32 policy of ysa-pendulum
(64 kinks, above PIECEWISE_PAIR_FORMS: only each kink's own products) with its last layer scaled by each
``--scales`` factor.

    python benchmarks/bench_piecewise.py [--scales 1,2]

Prints one row per model: kinks, products, status, seconds of the route (the model's loading excluded): a
report, not an assertion (this machine is shared; the tests assert behaviour, never a time). Measured on the
development machine (2 shared cores): the shipped pendulum 2.2 s (8 kinks, 276 products, certified), its map
0.07 s; the 2 x 32 ReLU copies 28 s each (6 s deriving the first-order part, two infeasible solves of about
11 s), not_certified, rightly: simulated from 1e-3 off upright, both grow over 1000-fold in 40 s.
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from lyapcheck.models.classes import piecewise_linearization as pw  # noqa: E402
from lyapcheck.models.classes.recast_classes import base_loop  # noqa: E402
from lyapcheck.models.language.modelfile import load_any_model  # noqa: E402
from lyapcheck.models.language.recast import RecastModel  # noqa: E402

MODELS = ROOT / "examples" / "models"


def row(name: str, path: Path, discrete: bool) -> None:
    model = load_any_model(path)
    assert isinstance(model, RecastModel)
    start = time.perf_counter()
    result = pw.run_map(model, "no Jacobian") if discrete else pw.run(base_loop(model.system), "no Jacobian")
    seconds = time.perf_counter() - start
    pl = pw.derive(pw.map_loop(model) if discrete else base_loop(model.system))
    kinks = len(pl.kinks) if isinstance(pl, pw.PiecewiseLinear) else 0
    products = len(pw.pairs(pl)) if isinstance(pl, pw.PiecewiseLinear) else 0
    status = result.status if result is not None else "not taken"
    print(f"{name:44s} {kinks:6d} {products:9d}  {status:14s} {seconds:8.2f}")


def ysa_relu(folder: Path, scale: float) -> Path:
    """The pendulum of pendulum-relu-policy.toml under ysa-pendulum's 2 x 32 policy, activation relu, last layer
    times ``scale``."""
    data = np.load(ROOT / "examples" / "networks" / "ysa_pendulum_tanh.npz", allow_pickle=False)
    arrays = {k: np.array(data[k]) for k in data.files}
    last = max(int(k[1:]) for k in arrays if k.startswith("W"))
    arrays[f"W{last}"] = arrays[f"W{last}"] * scale
    arrays["activation"] = np.array("relu")
    np.savez(folder / f"ysa_relu_{scale}.npz", **arrays)
    text = (MODELS / "pendulum-relu-policy.toml").read_text()
    text = text.replace("../networks/pendulum_relu_policy.npz", f"ysa_relu_{scale}.npz")
    path = folder / f"ysa_relu_{scale}.toml"
    path.write_text(text)
    return path


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scales", default="1,2")
    args = parser.parse_args()
    print(f"{'model':44s} {'kinks':>6s} {'products':>9s}  {'status':14s} {'seconds':>8s}")
    row("pendulum-relu-policy", MODELS / "pendulum-relu-policy.toml", False)
    row("discrete-pendulum-relu-policy", MODELS / "discrete-pendulum-relu-policy.toml", True)
    with tempfile.TemporaryDirectory() as tmp:
        for scale in (float(s) for s in args.scales.split(",")):
            row(f"pendulum under ysa's 2 x 32 policy as ReLU, x{scale:g}", ysa_relu(Path(tmp), scale), False)


if __name__ == "__main__":
    main()
