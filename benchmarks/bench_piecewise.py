"""How long ``linearization``'s piecewise-linear route takes (issue 44, item 3;
:mod:`lyapcheck.models.classes.piecewise_linearization`): the first-order part derived from the model, the
S-procedure LMI (Clarabel) and the exact check, on the shipped ReLU pendulum (continuous and its Euler map)
and on the same pendulum under ReLU copies of wider bias-free policies: the 2 x 32 policy of ysa-pendulum
(64 kinks, above PIECEWISE_PAIR_FORMS: only each kink's own products) with its last layer scaled by each
``--scales`` factor, and (``--widths``) the same policy cut to its first ``h`` neurons per layer (``2 h`` kinks).

    python benchmarks/bench_piecewise.py [--scales 1,2] [--widths 16,12,8] [--discrete]

Prints one row per model: kinks, products, status, seconds of the route (the model's loading excluded): a
report, not an assertion (this machine is shared; the tests assert behaviour, never a time). Measured on the
development machine (2 shared cores): the shipped pendulum 2.2 s (8 kinks, 276 products, certified), its map
0.07 s; the 2 x 32 ReLU copies 28 s each (6 s deriving the first-order part, two infeasible solves of about
11 s), not_certified, rightly: simulated from 1e-3 off upright, both grow over 1000-fold in 40 s. Since
PIECEWISE_MAX_KINKS (32) those 64-kink copies are refused by their count before the chain rule's walk (0.5 s); the
figures of the cut policies are in the tolerance's comment.
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


def ysa_relu(folder: Path, scale: float, width: int | None = None, discrete: bool = False) -> Path:
    """The pendulum of pendulum-relu-policy.toml (``discrete``: of discrete-pendulum-relu-policy.toml) under
    ysa-pendulum's 2 x 32 policy, activation relu, last layer times ``scale``; ``width``: each hidden layer
    cut to its first ``width`` neurons."""
    data = np.load(ROOT / "examples" / "networks" / "ysa_pendulum_tanh.npz", allow_pickle=False)
    arrays = {k: np.array(data[k]) for k in data.files}
    last = max(int(k[1:]) for k in arrays if k.startswith("W"))
    if width is not None:
        for i in range(1, last + 1):
            W = arrays[f"W{i}"]
            arrays[f"W{i}"] = W[:width if i < last else None, :width if i > 1 else None]
            if i < last:
                arrays[f"b{i}"] = arrays[f"b{i}"][:width]
    arrays[f"W{last}"] = arrays[f"W{last}"] * scale
    arrays["activation"] = np.array("relu")
    stem = f"ysa_relu_{scale}_{width}_{int(discrete)}"
    np.savez(folder / f"{stem}.npz", **arrays)
    source = "discrete-pendulum-relu-policy.toml" if discrete else "pendulum-relu-policy.toml"
    text = (MODELS / source).read_text()
    assert "../networks/pendulum_relu_policy.npz" in text
    text = text.replace("../networks/pendulum_relu_policy.npz", f"{stem}.npz")
    path = folder / f"{stem}.toml"
    path.write_text(text)
    return path


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scales", default="1,2")
    parser.add_argument("--widths", default="", help="hidden neurons per layer of cut copies (2 h kinks each)")
    parser.add_argument("--discrete", action="store_true", help="the cut copies as the Euler map too")
    args = parser.parse_args()
    print(f"{'model':44s} {'kinks':>6s} {'products':>9s}  {'status':14s} {'seconds':>8s}")
    row("pendulum-relu-policy", MODELS / "pendulum-relu-policy.toml", False)
    row("discrete-pendulum-relu-policy", MODELS / "discrete-pendulum-relu-policy.toml", True)
    with tempfile.TemporaryDirectory() as tmp:
        for scale in (float(s) for s in args.scales.split(",")):
            row(f"pendulum under ysa's 2 x 32 policy as ReLU, x{scale:g}", ysa_relu(Path(tmp), scale), False)
        for width in (int(w) for w in args.widths.split(",") if w):
            row(f"pendulum under ysa's policy cut to 2 x {width}", ysa_relu(Path(tmp), 1.0, width), False)
            if args.discrete:
                row(f"its Euler map, 2 x {width}", ysa_relu(Path(tmp), 1.0, width, True), True)


if __name__ == "__main__":
    main()
