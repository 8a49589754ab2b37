"""Issue 45's first target: the PID loop's box sweep proves GAS on at least 80 % of the stable part of
the window.

Runs ``examples/models/sweeps/boxes-pid.toml`` (``examples/models/pid-hardening-spring.toml`` over kp in
[0.5, 4] x ki in [0.25, 2], log axes, 40 boxes, class ``sos_gas``) into a temporary store and prints,
from this one run: the boxes certified (GAS for every gain of the box), not certified and refuted, the
share of the window's stable part (ki < 1.5 kp, the Routh-Hurwitz condition with kd = 1.5) covered by
certified boxes, in log measure, against the target of 80 %, the wall time of the sweep and the time
of each certified box, and that every certified box's certificate re-checks exactly (``verify``) and
lies in the stable part. The certificate store is switched off so that every box is searched.

Run:  python benchmarks/bench_pid_boxes.py [--spec SPEC] [--workers N]
"""

from __future__ import annotations

import argparse
import json
import math
import os
import statistics
import tempfile
import time
from collections import Counter
from pathlib import Path

import numpy as np

SHARE_TARGET = 0.80
#: the stable part of the window: ki < KI_OVER_KP * kp
KI_OVER_KP = 1.5


def stable_log_area(kp: tuple[float, float], ki: tuple[float, float], samples: int = 4000) -> float:
    """The log measure of ``{ki < 1.5 kp}`` inside the box (midpoint rule along ln kp: the stable
    interval of ln ki at each ln kp is exact)."""
    x = np.log(kp[0]) + (np.arange(samples) + 0.5) / samples * math.log(kp[1] / kp[0])
    top = np.clip(x + math.log(KI_OVER_KP), math.log(ki[0]), math.log(ki[1]))
    return float(np.sum(top - math.log(ki[0])) * math.log(kp[1] / kp[0]) / samples)


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--spec", default="examples/models/sweeps/boxes-pid.toml")
    parser.add_argument("--workers", type=int, default=0, help="local worker processes (0: in this process)")
    args = parser.parse_args()
    os.environ["LYAPCHECK_CERTIFICATE_STORE"] = "off"

    from lyapcheck.api import verify
    from sweeps.run import run_model_sweep
    from sweeps.runners import make_runner
    from sweeps.schema import BOX_STATUS_CODES
    from sweeps.spec import load_model_spec
    from sweeps.store import ModelBoxStore

    spec = load_model_spec(args.spec)
    names = {code: name for name, code in BOX_STATUS_CODES.items()}
    with tempfile.TemporaryDirectory() as scratch:
        out = Path(scratch) / "boxes.zarr"
        start = time.perf_counter()
        report = run_model_sweep(spec, out, runner=make_runner(workers=args.workers))
        wall = time.perf_counter() - start
        store = ModelBoxStore.open_or_create(out, spec)
        data = {v.name: store.read(v.name) for v in store.variables}

    (x, y) = spec.axes
    window_x, window_y = (x.values[0], x.values[-1]), (y.values[0], y.values[-1])
    stable = stable_log_area(window_x, window_y)
    window = math.log(window_x[1] / window_x[0]) * math.log(window_y[1] / window_y[0])
    leaf = data["done"].astype(bool) & (data["status"] != BOX_STATUS_CODES["split"])
    counts = Counter(names[int(s)] for s in data["status"][leaf])
    proved = 0.0
    valid = inside = 0
    rows = np.flatnonzero(leaf & (data["status"] == BOX_STATUS_CODES["certified"]))
    for row in rows:
        bx = (float(data[f"lo_{x.name}"][row]), float(data[f"hi_{x.name}"][row]))
        by = (float(data[f"lo_{y.name}"][row]), float(data[f"hi_{y.name}"][row]))
        area = math.log(bx[1] / bx[0]) * math.log(by[1] / by[0])
        inside += by[1] < KI_OVER_KP * bx[0]  # its worst corner is stable
        proved += area
        valid += bool(verify(json.loads(str(data["certificate"][row]))).valid)
    statuses = np.asarray(report.statuses_now)
    seconds = np.asarray(report.seconds_certify)
    certified_seconds = seconds[statuses == BOX_STATUS_CODES["certified"]]
    share = proved / stable
    print(f"spec {args.spec}: classes {', '.join(spec.classes)}; window {x.name} {window_x[0]:g}..{window_x[1]:g} x "
          f"{y.name} {window_y[0]:g}..{window_y[1]:g} (log axes); stable part {stable / window:.3f} of the window")
    print(f"sweep: {report.computed_now} boxes computed in {wall:.1f} s wall (workers {args.workers}); leaves: "
          + ", ".join(f"{counts[k]} {k}" for k in ("certified", "not_certified", "refuted", "inconclusive") if counts[k]))
    if certified_seconds.size:
        print(f"time per certified box: median {statistics.median(certified_seconds):.1f} s, max "
              f"{certified_seconds.max():.1f} s; all boxes {seconds.sum():.1f} s")
    print(f"certified boxes inside the stable part: {inside} of {rows.size}; certificates re-checked by verify: "
          f"{valid} of {rows.size}")
    print(f"[target] share of the stable part proved GAS (log measure): {share:.3f} (target >= {SHARE_TARGET:.2f}): "
          f"{'MET' if share >= SHARE_TARGET else 'NOT MET'}")


if __name__ == "__main__":
    main()
