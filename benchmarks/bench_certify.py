"""Wall time of ``lyapcheck certify examples/paper.toml``, imports included, before and after issue 11.

Prints the median of ``--runs`` fresh processes of

* ``lyapcheck certify examples/paper.toml``                  (all classes, derived dynamics; aim < 1 s)
* ``lyapcheck certify examples/paper.toml --classes quick``  (aim < 0.4 s)

for this tree and, with ``--before-tree DIR`` (a worktree of the commit before issue 11:
``git worktree add --detach /tmp/before 73f5967``), for that tree, runs interleaved so that the
load of a shared machine hits both alike; without it the medians stored in :data:`BEFORE` are
printed. Then where the time goes in this tree: the import time of the heavy packages (each in a
fresh interpreter, numpy subtracted), and the time of each class in a warm process (imports and
one-time setup excluded).

Run:  python benchmarks/bench_certify.py [--runs 7] [--before-tree /tmp/before]
"""

from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys
import time
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]
COMMANDS = {"all": ["certify", "examples/paper.toml"], "quick": ["certify", "examples/paper.toml", "--classes", "quick"]}
AIM = {"all": 1.0, "quick": 0.4}
#: medians of 3 runs at commit 73f5967 (before issue 11) on this 2-core machine, load 0.5-1
BEFORE: dict[str, Any] = {"commit": "73f5967", "all": 4.79, "quick": 1.56}


def wall(tree: Path, args: list[str]) -> float:
    """One fresh ``python -m lyapcheck ...`` in ``tree`` (its own sources first on the path)."""
    env = {**os.environ, "PYTHONPATH": str(tree)}
    t0 = time.perf_counter()
    proc = subprocess.run([sys.executable, "-m", "lyapcheck", *args], cwd=tree, env=env, capture_output=True)
    elapsed = time.perf_counter() - t0
    if proc.returncode not in (0, 1):
        raise RuntimeError(f"{' '.join(args)} in {tree} exited {proc.returncode}: {proc.stderr.decode()[-500:]}")
    return elapsed


def import_cost(module: str) -> float:
    """Seconds to import ``module`` in a fresh interpreter, beyond numpy (median of 3)."""
    code = ("import time, numpy; t = time.perf_counter(); import {m}; print(time.perf_counter() - t)").format(m=module)
    runs = [float(subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True,
                                 cwd=ROOT).stdout) for _ in range(3)]
    return statistics.median(runs)


def class_times() -> dict[str, float]:
    """Seconds per class at the paper's gains (derived), warm process, median of 3."""
    sys.path.insert(0, str(ROOT))
    from lyapcheck.paper import certification
    from lyapcheck.paper.params import problem_from_sources

    problem = problem_from_sources(ROOT / "examples" / "paper.toml", {})
    spent: dict[str, list[float]] = {}
    guarded = certification.guarded

    def timed(name: str, compute: Any) -> Any:
        t0 = time.perf_counter()
        try:
            return guarded(name, compute)
        finally:
            spent.setdefault(name, []).append(time.perf_counter() - t0)

    certification.run_conditions(problem, "derived")  # one-time: programs, solver, imports
    certification.guarded = timed  # type: ignore[assignment]
    try:
        for _ in range(3):
            certification.run_conditions(problem, "derived")
    finally:
        certification.guarded = guarded  # type: ignore[assignment]
    return {name: statistics.median(t) for name, t in spent.items()}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=7)
    parser.add_argument("--before-tree", type=Path, default=None)
    args = parser.parse_args()
    print(f"machine: {os.cpu_count()} cores, load average {os.getloadavg()[0]:.2f}")
    trees = {"after": ROOT} | ({"before": args.before_tree.resolve()} if args.before_tree else {})
    times: dict[tuple[str, str], list[float]] = {}
    for tree in trees.values():  # warm the file cache and the bytecode of both trees
        wall(tree, COMMANDS["quick"])
    for _ in range(args.runs):
        for label, tree in trees.items():
            for name, command in COMMANDS.items():
                times.setdefault((label, name), []).append(wall(tree, command))
    for name in COMMANDS:
        after = statistics.median(times[("after", name)])
        before = statistics.median(times[("before", name)]) if args.before_tree else BEFORE[name]
        where = "measured now" if args.before_tree else f"stored, commit {BEFORE['commit']}"
        print(f"certify {name:5}: median {after:5.2f} s after, {before:5.2f} s before ({where}); "
              f"before/after {before / after:4.1f} x; after/aim {after / AIM[name]:4.2f} (aim < {AIM[name]} s)")

    print("import cost in a fresh interpreter, beyond numpy (median of 3):")
    for module, why in (("cvxpy", "no longer imported by certify (compiled programs)"),
                        ("pint", "first run only: lyapcheck.units remembers pint's unit factors (it pulls in dask)"),
                        ("scipy.linalg.cython_blas", "Clarabel loads it at its first PSD-cone solve"),
                        ("scipy.sparse", "not imported: Clarabel is handed index arrays")):
        print(f"  {module:26} {import_cost(module) * 1e3:6.0f} ms  {why}")
    print("per class, paper gains, derived, warm process (median of 3):")
    for name, seconds in class_times().items():
        print(f"  {name:16} {seconds * 1e3:8.1f} ms")


if __name__ == "__main__":
    main()
