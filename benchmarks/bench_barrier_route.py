"""``barrier`` on every shipped example with ``[sets]`` and the tests' loops with functions, both kinds of
loop (issue 41, item 1: one implementation of the class for polynomial loops and loops with functions).

Each example of ``examples/models/*.toml`` with ``[sets]`` (an initial and an unsafe set) and each loop with
functions of the tests that asks the safety question (:data:`FUNCTION_LOOPS`: no shipped example is a loop
with functions with ``[sets]``) is certified with the class ``barrier`` alone, in one process, with no
stored certificate reused. The table gives, per loop, its kind, the status, the figures (B's degree and its
rate ``lambda_per_s``), the wall time and the solves. ``--json FILE`` keeps the figures; ``--compare FILE``
prints beside each figure the one kept before and flags:

* ``LOST``: a status that was ``certified`` (or ``counterexample``) and is not any more;
* ``WORSE``: a certified barrier of higher degree than before (a polynomial loop's figures must be
  identical: any change is flagged);
* ``PROGRAMS``: a polynomial loop whose search solved other programs than before (the sequence of the
  structures' keys in the solver log, hashed: a polynomial loop's programs must be the same ones);
* ``CERT``: a polynomial loop whose certificate is not byte-identical (its JSON, hashed).

    python benchmarks/bench_barrier_route.py [--json after.json] [--compare before.json] [--time-limit 120]
                                             [FILE.toml ...]

Without files: every example with ``[sets]`` but the paper's (``paper-*``, minutes each), then the loops
with functions of :data:`FUNCTION_LOOPS` (the ones with a box also over it).
"""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
from pathlib import Path
from typing import Any

from route_runs import certificate_digest, loop_kind, solve_log, timed_certify  # (beside this script)

ROOT = Path(__file__).resolve().parents[1]
SKIPPED = ("paper-",)


def function_loops() -> dict[str, tuple[str, list[str] | None]]:
    """The tests' loops with functions that ask the safety question (name -> model text, box), read from
    the tests themselves so that the benchmark follows them."""
    sys.path.insert(0, str(ROOT))
    from tests.feature_matrix import FUNCTIONS
    from tests.test_recast_barrier import FAST, NEAR, SATURATED, write
    from tests.test_recast_box_safety import PULSE

    folder = Path(tempfile.mkdtemp(prefix="bench-barrier-"))
    acc = {"acc-sine-near": write(folder, "sine", v="kp*(h - h0) + kd*(vL - v) + sin(h - h0)/5", initial=NEAR),
           "acc-saturated-near": write(folder, "near", initial=NEAR),
           "acc-saturated-fast": write(folder, "fast", v=SATURATED, initial=FAST)}
    out = {name: (path.read_text(), None) for name, path in acc.items()}
    out["feature-matrix-functions"] = (FUNCTIONS, None)
    out["feature-matrix-functions --box a=0.8..1.2"] = (FUNCTIONS, ["a=0.8..1.2"])
    out["pulse --box a=0.5..2.5"] = (PULSE, ["a=0.5..2.5"])
    out["pulse"] = (PULSE, None)
    return out


def run(path: Path, limit: float, box: list[str] | None = None) -> dict[str, Any]:
    """The class's status, figures and wall time on one model file (over ``box``, a box of its parameters)."""
    found, seconds = timed_certify(path, classes="barrier", time_limit_s=limit, box=box)
    result = found.conditions["barrier"]
    solves, programs = solve_log(result)
    return {"kind": loop_kind(path.read_text(), str(path)), "status": result.status,
            "degree": result.numbers.get("degree"), "lambda_per_s": result.numbers.get("lambda_per_s"),
            "seconds": round(seconds, 1), "solves": solves, "programs": programs,
            "certificate": certificate_digest(result)}


def row(name: str, now: dict[str, Any], before: dict[str, Any] | None) -> str:
    flags: list[str] = []
    figures = f"degree {now['degree']}, lambda {now['lambda_per_s']}" if now["status"] == "certified" else ""
    if before is not None:
        if before["status"] in ("certified", "counterexample") and now["status"] != before["status"]:
            flags.append("LOST")
        if before["status"] == "certified" and now["status"] == "certified":
            if now["kind"] == "polynomial":
                if (before["degree"], before["lambda_per_s"]) != (now["degree"], now["lambda_per_s"]):
                    flags.append("WORSE")
            elif now["degree"] > before["degree"]:
                flags.append("WORSE")
        if now["kind"] == "polynomial" and before.get("programs") not in (None, now["programs"]):
            flags.append("PROGRAMS")
        if now["kind"] == "polynomial" and before.get("certificate") not in (None, now["certificate"]):
            flags.append("CERT")
        old = f"degree {before['degree']}, lambda {before['lambda_per_s']}" if before["status"] == "certified" else ""
        figures += f" (before: {before['status']} {old}, {before['solves']} solves)"
    return (f"| {name} | {now['kind']} | {now['status']} | {figures} | {now['seconds']} | {now['solves']} | "
            f"{' '.join(flags)} |")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("files", nargs="*", type=Path)
    parser.add_argument("--time-limit", type=float, default=120.0, help="the class's limit, s (default 120)")
    parser.add_argument("--json", type=Path, default=None, help="keep the figures in this file")
    parser.add_argument("--compare", type=Path, default=None, help="figures kept before (--json)")
    parser.add_argument("--only", choices=("polynomial", "functions"), default=None, help="one kind of loop only")
    args = parser.parse_args()
    runs: list[tuple[str, Path, list[str] | None]] = []
    if args.files:
        runs = [(path.stem, path, None) for path in args.files]
    else:
        if args.only != "functions":
            runs += [(p.stem, p, None) for p in sorted((ROOT / "examples" / "models").glob("*.toml"))
                     if "\n[sets]" in p.read_text() and "unsafe" in p.read_text() and not p.stem.startswith(SKIPPED)]
        if args.only != "polynomial":
            folder = Path(tempfile.mkdtemp(prefix="bench-barrier-"))
            for name, (text, box) in function_loops().items():
                path = folder / f"{name.split()[0]}.toml"
                path.write_text(text)
                runs.append((name, path, box))
    before = json.loads(args.compare.read_text()) if args.compare else {}
    print("| loop | kind | status | figures | s | solves | flags |")
    print("|---|---|---|---|---|---|---|")
    kept: dict[str, Any] = {}
    for label, path, box in runs:
        kept[label] = run(path, args.time_limit, box)
        print(row(label, kept[label], before.get(label)), flush=True)
    if args.json is not None:
        args.json.write_text(json.dumps(kept, indent=1))


if __name__ == "__main__":
    main()
