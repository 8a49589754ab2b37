"""Wall time against pydrake, the tool a Python user would pick instead (issue 30).

For each 2-3-state positive of the completeness suite (``benchmarks/completeness/index.toml``),
the runs alternate, each in a fresh process, whole process timed (interpreter start, imports,
model reading, build, solve):

* ``drake``: ``benchmarks/completeness/drake_lyapunov.py FILE`` under ``--drake-python``: a strict
  SOS Lyapunov search in pydrake's MathematicalProgram with Clarabel (``V - eps|x|^2`` and
  ``-V' - eps|x|^2`` SOS, degree 2 then 4), lyapcheck not imported; its answer is floating point;
* ``cold``: ``lyapcheck certify FILE --classes sos_gas --json`` with an empty
  ``LYAPCHECK_CACHE_DIR`` (a new user's first run: the whole search, solves, rounding and exact
  check; it leaves the certificate in the store, :mod:`lyapcheck.models.engines.store`);
* ``warm``: the same command again on that directory (what a user sees from the second run of a
  model on): the stored certificate checked exactly again against the field this run derives, no
  solve. Its ``certified`` is an exact check in rationals, as the cold run's.

Both tools run with Python's bytecode cache allowed (``PYTHONDONTWRITEBYTECODE`` is removed from
their environment), as on a user's machine.

Per system it prints the medians of ``--runs`` rounds, whether each certified, and the ratios
``cold/drake`` and ``warm/drake``; then the summary over the systems both certify against the
targets of issue 30: ``warm <= drake`` and ``cold <= 2 drake`` on every such system.

pydrake is not a dependency of lyapcheck: install it into a separate interpreter (wheels for
Python 3.11 stop at drake 1.51.1), e.g.

    python3.11 -m venv /work/drake-venv && /work/drake-venv/bin/pip install drake==1.51.1

Run:  .venv/bin/python benchmarks/bench_vs_drake.py --drake-python /work/drake-venv/bin/python
      [--runs 3] [--only STEM,...] [--eps 1e-3]
Exit 0 (a report; the targets are printed, not enforced), 2 when no Drake interpreter is found.
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
import tomllib
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]
SUITE = ROOT / "benchmarks" / "completeness"
DRAKE_SCRIPT = SUITE / "drake_lyapunov.py"
#: issue 30: lyapcheck's wall at most Drake's with a warm cache, at most twice with an empty one
TARGET_WARM, TARGET_COLD = 1.0, 2.0


def drake_python(requested: str | None) -> str | None:
    """The interpreter that runs the Drake side: --drake-python, else this one if it has pydrake."""
    candidates = [requested] if requested else [sys.executable]
    for python in candidates:
        probe = subprocess.run([python, "-c", "import pydrake.solvers"], capture_output=True)
        if probe.returncode == 0:
            return python
    return None


def timed(cmd: list[str], env: dict[str, str] | None = None, timeout: float = 300.0) -> tuple[float, str, int]:
    # as on a user's machine, Python keeps its bytecode (a CI or sandbox environment may forbid it
    # with PYTHONDONTWRITEBYTECODE, which makes every process compile its sources again)
    base = {k: v for k, v in os.environ.items() if k != "PYTHONDONTWRITEBYTECODE"}
    t0 = time.perf_counter()
    proc = subprocess.run(cmd, cwd=ROOT, capture_output=True, text=True, timeout=timeout,
                          env={**base, **(env or {})})
    return time.perf_counter() - t0, proc.stdout, proc.returncode


def run_drake(python: str, path: Path, eps: float) -> tuple[float, bool, str]:
    wall, out, rc = timed([python, str(DRAKE_SCRIPT), str(path), "--eps", repr(eps)])
    if rc != 0:
        return wall, False, f"exit {rc}"
    answer = json.loads(out)
    return wall, bool(answer["certified"]), str(answer["status"])


def run_lyapcheck(path: Path, cache: str) -> tuple[float, bool, str]:
    cmd = [sys.executable, "-m", "lyapcheck", "certify", str(path), "--classes", "sos_gas", "--json"]
    wall, out, rc = timed(cmd, env={"LYAPCHECK_CACHE_DIR": cache})
    try:
        cond = json.loads(out)["conditions"]["sos_gas"]
    except (json.JSONDecodeError, KeyError):
        return wall, False, f"exit {rc}"
    return wall, cond["status"] == "certified", f"{cond['status']} (degree {cond.get('degree')})"


def systems(only: set[str]) -> list[str]:
    index = tomllib.loads((SUITE / "index.toml").read_text())
    stems = [stem for stem, e in index["positive"].items() if int(e["states"]) in (2, 3)]
    if only:
        unknown = only - set(stems)
        if unknown:
            raise SystemExit(f"--only: not a 2-3-state positive of index.toml: {', '.join(sorted(unknown))}")
        stems = [s for s in stems if s in only]
    return stems


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--drake-python", help="interpreter with pydrake (default: this one, if it has pydrake)")
    parser.add_argument("--runs", type=int, default=3, help="rounds per system (medians; default 3)")
    parser.add_argument("--only", default="", help="comma-separated stems")
    parser.add_argument("--eps", type=float, default=1e-3, help="Drake's strictness margin (default 1e-3)")
    parser.add_argument("--json", type=Path, help="also write the rows as JSON here")
    args = parser.parse_args(argv)
    if args.runs < 1:
        parser.error(f"--runs must be at least 1; got {args.runs}")
    python = drake_python(args.drake_python)
    if python is None:
        print(f"no interpreter with pydrake: {args.drake_python or sys.executable} cannot import pydrake.solvers "
              "(pass --drake-python PATH; see this script's docstring)", file=sys.stderr)
        return 2
    rows: list[dict[str, Any]] = []
    for stem in systems({s for s in args.only.split(",") if s}):
        path = SUITE / "positive" / f"{stem}.toml"
        walls: dict[str, list[float]] = {"drake": [], "cold": [], "warm": []}
        said: dict[str, tuple[bool, str]] = {}
        for _ in range(args.runs):  # alternate, so a shared machine's load hits all three alike
            w, ok, what = run_drake(python, path, args.eps)
            walls["drake"].append(w)
            said["drake"] = (ok, what)
            with tempfile.TemporaryDirectory(prefix="lyapcheck-cold-") as cache:
                for label in ("cold", "warm"):
                    w, ok, what = run_lyapcheck(path, cache)
                    walls[label].append(w)
                    said[label] = (ok, what)
        med = {k: statistics.median(v) for k, v in walls.items()}
        row = {"system": stem, **{f"{k}_s": med[k] for k in med}, **{f"{k}_certified": said[k][0] for k in said},
               **{f"{k}_status": said[k][1] for k in said}}
        rows.append(row)
        print(f"  {stem}: drake {med['drake']:.2f} s ({said['drake'][1]}), cold {med['cold']:.2f} s, "
              f"warm {med['warm']:.2f} s ({said['warm'][1]})", file=sys.stderr, flush=True)
    width = max([len(r["system"]) for r in rows] + [6])
    print(f"\n{'system':{width}s} | drake s | cert | lyapcheck cold s | warm s | cert | cold/drake | warm/drake")
    print(f"{'-' * width}-+---------+------+------------------+--------+------+------------+-----------")
    yes = {True: "yes", False: "no"}
    for r in rows:
        print(f"{r['system']:{width}s} | {r['drake_s']:7.2f} | {yes[r['drake_certified']]:4s} | {r['cold_s']:16.2f} | "
              f"{r['warm_s']:6.2f} | {yes[r['warm_certified']]:4s} | {r['cold_s'] / r['drake_s']:10.2f} | "
              f"{r['warm_s'] / r['drake_s']:9.2f}")
    both = [r for r in rows if r["drake_certified"] and r["warm_certified"]]
    print(f"\ncertified: drake {sum(r['drake_certified'] for r in rows)}, lyapcheck {sum(r['warm_certified'] for r in rows)}"
          f", both {len(both)} of {len(rows)}")
    print(f"only lyapcheck: {', '.join(r['system'] for r in rows if r['warm_certified'] and not r['drake_certified']) or '-'}")
    print(f"only drake: {', '.join(r['system'] for r in rows if r['drake_certified'] and not r['warm_certified']) or '-'}")
    if both:
        cold = [r["cold_s"] / r["drake_s"] for r in both]
        warm = [r["warm_s"] / r["drake_s"] for r in both]
        print(f"on the {len(both)} both certify: cold/drake median {statistics.median(cold):.2f} (max {max(cold):.2f}, "
              f"target <= {TARGET_COLD}), warm/drake median {statistics.median(warm):.2f} (max {max(warm):.2f}, "
              f"target <= {TARGET_WARM})")
        print(f"targets met on every system both certify: warm {'yes' if max(warm) <= TARGET_WARM else 'NO'}, "
              f"cold {'yes' if max(cold) <= TARGET_COLD else 'NO'}")
    if args.json:
        args.json.write_text(json.dumps(rows, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
