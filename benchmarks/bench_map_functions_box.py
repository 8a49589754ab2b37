"""A discrete-time map with functions over boxes of its gain (issues 44 and 41): every class ``certify --box``
takes on ``examples/models/discrete-tanh-gain-map.toml`` (``x+ = y``, ``y+ = -x/2 + k tanh(y)``; its ``barrier``
on ``discrete-tanh-safety-map.toml``, the same map with safety sets), each box
certified in a fresh process (``lyapcheck certify FILE --box ... --no-store --out CERT``) and its document
verified (``lyapcheck verify CERT``), both timed as whole processes (start-up included); then each class's
status and figures.

    python benchmarks/bench_map_functions_box.py
"""

from __future__ import annotations

import json
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
MAP = ROOT / "examples" / "models" / "discrete-tanh-gain-map.toml"
SAFETY = ROOT / "examples" / "models" / "discrete-tanh-safety-map.toml"
#: (the model, the box, any further arguments): a stable box, a narrower one (a common quadratic V exists), one
#: reaching the unstable gains k > 3/2, the user's V over the first; the safety map's barrier over two boxes
RUNS: tuple[tuple[Path, str, tuple[str, ...]], ...] = (
    (MAP, "k=0.6..0.95", ()),
    (MAP, "k=0.6..0.85", ()),
    (MAP, "k=1..1.8", ()),
    (MAP, "k=0.6..0.95", ("--classes", "candidate", "--candidate", "2*x**2 - 2*x*y + 4*y**2")),
    (SAFETY, "k=0.6..0.85", ("--classes", "barrier")),
    (SAFETY, "k=0.6..1.1", ("--classes", "barrier")),
)


def run(args: list[str]) -> tuple[int, float]:
    start = time.perf_counter()
    done = subprocess.run([sys.executable, "-m", "lyapcheck", *args], capture_output=True, text=True)
    return done.returncode, time.perf_counter() - start


def figures(c: dict[str, object]) -> str:
    """The figures a decided class states (GES's k and r, a level, the box's parts)."""
    numbers = c.get("numbers") if isinstance(c.get("numbers"), dict) else c
    assert isinstance(numbers, dict)
    shown = {key: numbers[key] for key in ("k", "contraction_per_step", "level", "box_parts", "degree", "lambda")
             if key in numbers}
    return ", ".join(f"{key} {value:.4g}" if isinstance(value, float) else f"{key} {value}"
                     for key, value in shown.items())


def main() -> None:
    print("| model | box | arguments | statuses | certify s (process) | verify s (process) |")
    print("|---|---|---|---|---|---|")
    with tempfile.TemporaryDirectory() as scratch:
        for k, (path, box, extra) in enumerate(RUNS):
            cert = Path(scratch) / f"box{k}.json"
            code, certify_s = run(["certify", str(path), "--box", box, *extra, "--no-store", "--out", str(cert)])
            doc = json.loads(cert.read_text()) if cert.exists() else {"conditions": {}}
            checked, verify_s = run(["verify", str(cert)]) if cert.exists() else (1, float("nan"))
            statuses = "; ".join(f"{name} {c['status']}" + (f" ({figures(c)})" if figures(c) else "")
                                 for name, c in doc["conditions"].items())
            print(f"| {path.name} | {box} | {' '.join(extra) or '(all)'} | {statuses} (exit {code}, verify exit {checked}) | "
                  f"{certify_s:.2f} | {verify_s:.2f} |")


if __name__ == "__main__":
    main()
