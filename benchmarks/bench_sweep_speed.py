"""Sweep points per second with every condition class, before and after issue 11, in one run.

The spec is ``examples/sweep-alpha-sigma.toml`` with ``classes`` set to every class, on a
sub-grid of its own grid (every other value of each 12-value axis: 6 x 6 = 36 points, one
unit of ``chunk_size = 36`` as shipped), so a point costs what it costs in the shipped sweep.
Units run in this process (``InlineRunner``), pinned to one CPU as a sweep worker's share of the
machine (``--cpus``), and the certificate and simulation shares of the time are printed apart.

"Before" is the same measurement on the code of an older commit: pass ``--before-tree DIR``
with a worktree of it (``git worktree add --detach /tmp/before 73f5967``); the measurement runs
there in a subprocess. Without it the figure stored in :data:`BEFORE` is printed (measured on
this machine at commit 73f5967, the parent of issue 11's changes, on one CPU of an idle machine).

Run:  python benchmarks/bench_sweep_speed.py [--before-tree /tmp/before] [--repeats 1] [--cpus 1]
Note: the machine is shared; the ratio of two medians measured back to back is the figure to read.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]

ALL_CLASSES = ["prop41_ges", "prop41_iss", "stabcond2", "sector_ges", "switched_ges", "ultimate_bound",
               "sos_gas", "ges", "saturated_loop", "sos_bound"]
#: measured by :func:`measure` on a worktree of commit 73f5967 (one run on one CPU, 2026-11-24, load
#: average 0.2, before any change of issue 11): points per second of the sweep and its two parts.
#: An earlier figure (0.263 points/s) was taken unpinned on a slower day; read ratios measured
#: back to back (``--before-tree``), not this stored figure, where it matters
BEFORE: dict[str, Any] = {"commit": "73f5967", "points": 36, "points_per_s": 0.607,
                          "certify_s_per_point": 1.033, "simulate_s_per_point": 0.610}


def spec_text(root: Path) -> str:
    """The shipped alpha-sigma spec with every class and a 6 x 6 sub-grid of its own grid."""
    import numpy as np

    text = (root / "examples" / "sweep-alpha-sigma.toml").read_text()
    head, _, rest = text.partition("[sweep]")
    sim = rest[rest.index("[simulation]"):]
    alpha = np.geomspace(150, 2400, 12)[::2]
    sigma = np.geomspace(0.001, 1, 12)[::2]
    fmt = ", ".join
    return (head + "[sweep]\nclasses = " + json.dumps(ALL_CLASSES) + "\nchunk_size = 36\n"
            + "[[sweep.axes]]\nname = \"alpha_d\"\nvalues = [" + fmt(repr(float(v)) for v in alpha) + "]\n"
            + "[[sweep.axes]]\nname = \"sigma0\"\nvalues = [" + fmt(repr(float(v)) for v in sigma) + "]\n\n" + sim)


def measure(root: Path) -> dict[str, Any]:
    """One sweep of the sub-grid in this process, with the certify and simulate shares apart."""
    sys.path.insert(0, str(root))
    from sweeps import evaluate
    from sweeps.run import run_sweep
    from sweeps.runners import InlineRunner
    from sweeps.spec import parse_spec

    spent = {"certify": 0.0, "simulate": 0.0}
    certify_point, simulate_points = evaluate.certify_point, evaluate.simulate_points

    def timed_certify(*args: Any, **kwargs: Any) -> Any:
        t0 = time.perf_counter()
        try:
            return certify_point(*args, **kwargs)
        finally:
            spent["certify"] += time.perf_counter() - t0

    def timed_simulate(*args: Any, **kwargs: Any) -> Any:
        t0 = time.perf_counter()
        try:
            return simulate_points(*args, **kwargs)
        finally:
            spent["simulate"] += time.perf_counter() - t0

    evaluate.certify_point, evaluate.simulate_points = timed_certify, timed_simulate  # type: ignore[assignment]
    spec = parse_spec(spec_text(root))
    with tempfile.TemporaryDirectory() as tmp:
        t0 = time.perf_counter()
        run_sweep(spec, Path(tmp) / "s.zarr", runner=InlineRunner())
        wall = time.perf_counter() - t0
        import xarray as xr

        ds = xr.open_zarr(str(Path(tmp) / "s.zarr"), consolidated=False)
        statuses = {c: ds[f"status_{c}"].values.ravel().tolist() for c in ALL_CLASSES}
        # the simulated figures (NaN where a run failed), compared as exact floats; a scenario the
        # spec does not ask for is a column of NaN in a newer schema and absent in an older one
        asked = {f"sim_eps_sup_m_{name}" for name in spec.simulation.scenarios}
        simulated = {str(v): [repr(float(x)) for x in ds[v].values.ravel()] for v in ds.data_vars if str(v) in asked}
        violations = int(ds["soundness_violation"].values.sum())
    n = spec.n_points
    return {"points": n, "wall_s": wall, "points_per_s": n / wall, "certify_s_per_point": spent["certify"] / n,
            "simulate_s_per_point": spent["simulate"] / n, "statuses": statuses, "simulated": simulated,
            "violations": violations}


def run_in(tree: Path, repeats: int, cpus: int) -> list[dict[str, Any]]:
    """``measure`` in a fresh interpreter whose imports come from ``tree``, on ``cpus`` CPUs.

    A sweep's worker processes each get a core; a measurement in one process that lets its
    threads (sos_bound solves its decay rates side by side) spread over every core would count
    the other workers' cores as its own. So by default the measuring process is pinned to one CPU.
    """
    out = []
    pin = sorted(os.sched_getaffinity(0))[:cpus]
    for _ in range(repeats):
        code = (f"import json, os, sys; os.sched_setaffinity(0, {pin!r}); sys.path.insert(0, {str(tree)!r}); "
                f"sys.path.insert(0, {str(ROOT / 'benchmarks')!r}); import bench_sweep_speed as b; "
                f"print(json.dumps(b.measure(__import__('pathlib').Path({str(tree)!r}))))")
        env = {**os.environ, "PYTHONPATH": str(tree)}
        proc = subprocess.run([sys.executable, "-c", code], cwd=tree, env=env, capture_output=True, text=True,
                              check=True)
        out.append(json.loads(proc.stdout.strip().splitlines()[-1]))
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--before-tree", type=Path, default=None,
                        help="a worktree of the 'before' commit (measured there in a subprocess)")
    parser.add_argument("--repeats", type=int, default=1)
    parser.add_argument("--cpus", type=int, default=1,
                        help="CPUs the measuring process may use (default 1: a sweep worker's share)")
    args = parser.parse_args()
    print(f"machine: {os.cpu_count()} cores, load average {os.getloadavg()[0]:.2f}; measured on {args.cpus} CPU(s)")
    after = run_in(ROOT, args.repeats, args.cpus)
    if args.before_tree is not None:
        before = run_in(args.before_tree.resolve(), args.repeats, args.cpus)
        label = f"measured now in {args.before_tree}"
    else:
        before = [BEFORE]
        label = f"stored figure, commit {BEFORE['commit']}"

    def med(runs: list[dict[str, Any]], key: str) -> float:
        return statistics.median(float(r[key]) for r in runs)

    for name, runs, where in (("before", before, label), ("after", after, "this tree")):
        print(f"{name:6}: {med(runs, 'points_per_s'):7.3f} points/s  (certify {med(runs, 'certify_s_per_point') * 1e3:7.1f} ms"
              f"/point, simulate {med(runs, 'simulate_s_per_point') * 1e3:6.1f} ms/point; {where})")
    print(f"ratio after/before: {med(after, 'points_per_s') / med(before, 'points_per_s'):.1f} x   aim >= 10 x")
    if args.before_tree is not None:
        from collections import Counter

        from sweeps.schema import STATUS_CODES

        names: dict[int, str] = {}
        for name, code in STATUS_CODES.items():  # the first name of a code (stabcond2's alias "holds" comes later)
            names.setdefault(code, name)
        b0, a0 = before[0], after[0]
        changed = {c: Counter(f"{names.get(x, x)} -> {names.get(y, y)}"
                              for x, y in zip(b0["statuses"][c], a0["statuses"][c]) if x != y) for c in ALL_CLASSES}
        print(f"statuses identical before/after on all {a0['points']} points and classes: {not any(changed.values())}"
              + "".join(f"; {c}: " + ", ".join(f"{k} point(s) {t}" for t, k in moves.items())
                        for c, moves in changed.items() if moves))
        before_sims = b0.get("simulated", {})
        # a scenario that only one side simulated counts as differing at every point
        sims = {v: (sum(x != y for x, y in zip(before_sims[v], a0["simulated"][v]))
                    if v in before_sims and v in a0["simulated"] else a0["points"])
                for v in sorted(set(a0["simulated"]) | set(before_sims))}
        # the integrator lands its steps on kinks since ecceee2, so figures move in the last digits:
        # the largest move, in metres and relative, says whether that is all
        moves = [(abs(float(y) - float(x)), abs(float(y) / float(x) - 1.0)) for v in sims
                 if v in before_sims and v in a0["simulated"]
                 for x, y in zip(before_sims[v], a0["simulated"][v]) if x != y and float(x) != 0.0]
        print(f"simulated sup |eps| identical bit for bit, every scenario: {not any(sims.values())}"
              + "".join(f"; {v}: {k} point(s) differ" for v, k in sims.items() if k)
              + (f"; largest difference {max(m[0] for m in moves):.1e} m, relative {max(m[1] for m in moves):.1e}"
                 if moves else ""))
    print(f"soundness violations (after): {after[0]['violations']}")


if __name__ == "__main__":
    main()
