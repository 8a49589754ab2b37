"""FOSSIL 2.0's discrete-time benchmarks, certified exactly (issue 44's target: under 2 s each).

Each shipped map (``examples/models/fossil-dt-*.toml``) is certified in a fresh process
(``lyapcheck certify FILE --no-store --out CERT``: every class searches, nothing is reused) and its
certificate verified (``lyapcheck verify CERT``), both timed as whole processes (start-up included),
and certified once more in this process (the API, store off: the work without Python's start-up and
imports); then the certified classes and their figures are printed. FOSSIL's own figures (neural V and an SMT
check, delta-complete) are the ones its paper reports: 0.21-2.66 s mean.

    python benchmarks/bench_discrete.py [FILE ...]
"""

from __future__ import annotations

import json
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def run(args: list[str]) -> tuple[int, float]:
    start = time.perf_counter()
    done = subprocess.run([sys.executable, "-m", "lyapcheck", *args], capture_output=True, text=True)
    return done.returncode, time.perf_counter() - start


def main() -> None:
    files = [Path(a) for a in sys.argv[1:]] or sorted((ROOT / "examples" / "models").glob("fossil-dt-*.toml"))
    sys.path.insert(0, str(ROOT / "benchmarks"))
    from route_runs import timed_certify

    timed_certify(files[0])  # the imports and the solver's first call, once, before any row
    print("| map | certified | figures | certify s (process) | certify s (in process) | verify s (process) |")
    print("|---|---|---|---|---|---|")
    with tempfile.TemporaryDirectory() as scratch:
        for path in files:
            cert = Path(scratch) / f"{path.stem}.json"
            code, certify_s = run(["certify", str(path), "--no-store", "--out", str(cert)])
            doc = json.loads(cert.read_text()) if cert.exists() else {"conditions": {}}
            checked, verify_s = run(["verify", str(cert)]) if cert.exists() else (1, float("nan"))
            _, inside_s = timed_certify(path)
            proved = [n for n, c in doc["conditions"].items() if c.get("status") == "certified"]
            figures = []
            for name in proved:
                c = doc["conditions"][name]
                if c.get("property") == "GES":
                    figures.append(f"{name}: GES, k = {c['k']:.4g}, r = {c['contraction_per_step']:.4g}")
                elif "degree" in c:
                    figures.append(f"{name}: {c.get('property')}, degree {c['degree']}")
            print(f"| {path.stem} | {', '.join(proved) or 'none'} (exit {code}, verify exit {checked}) | "
                  f"{'; '.join(figures)} | {certify_s:.2f} | {inside_s:.2f} | {verify_s:.2f} |")


if __name__ == "__main__":
    main()
