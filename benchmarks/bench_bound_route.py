"""``sos_bound`` on every shipped example it runs on, both kinds of loop (issue 41, item 1: one
implementation of the class for polynomial loops and loops with functions).

Each example of ``examples/models/*.toml`` with ``[disturbances]`` is certified with the class
``sos_bound`` alone, in one process, with no stored certificate reused. The table gives, per example,
its kind, the status, each output's certified bound and the wall time. ``--json FILE`` keeps the
figures; ``--compare FILE`` prints beside each figure the one kept before and flags:

* ``LOST``: a status that was ``certified`` and is not any more;
* ``WORSE``: a bound that grew (a polynomial loop's must be identical, a loop with functions' equal or
  smaller);
* ``PROGRAMS``: a polynomial loop whose search solved other programs than before (the sequence of the
  structures' keys in the solver log, hashed: a polynomial loop's programs must be the same ones).

    python benchmarks/bench_bound_route.py [--json after.json] [--compare before.json] [--time-limit 120]
                                           [FILE.toml ...]

Without files: every example with disturbances but the paper's (``paper-*``, minutes each); the ones in
:data:`BOXES` also over the box the tests use.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path
from typing import Any

from route_runs import loop_kind, solve_log, timed_certify  # (beside this script)

ROOT = Path(__file__).resolve().parents[1]
SKIPPED = ("paper-",)
#: the examples also certified over a box of their parameters (the tests' boxes)
BOXES = {"recast-ilos-course-disturbed": ["kappa=0.4..0.6"], "linear-scalar-disturbed": ["a=1.5..2.5"]}


def run(path: Path, limit: float, box: list[str] | None = None) -> dict[str, Any]:
    """The class's status, bounds and wall time on one example (over ``box``, a box of its parameters)."""
    found, seconds = timed_certify(path, classes="sos_bound", time_limit_s=limit, box=box)
    result = found.conditions["sos_bound"]
    solves, programs = solve_log(result)
    return {"kind": loop_kind(path.read_text(), str(path)), "status": result.status,
            "bounds": result.numbers.get("bounds") or {}, "seconds": round(seconds, 1),
            "solves": solves, "programs": programs}


def row(name: str, now: dict[str, Any], before: dict[str, Any] | None) -> str:
    flags: list[str] = []
    bounds = ", ".join(f"{k} {v:.6g}" for k, v in now["bounds"].items())
    if before is not None:
        if before["status"] == "certified" and now["status"] != "certified":
            flags.append("LOST")
        for k, old in before["bounds"].items():
            new = now["bounds"].get(k)
            if new is None or (new != old if now["kind"] == "polynomial" else new > old):
                flags.append(f"WORSE {k}")
        if now["kind"] == "polynomial" and before.get("programs") not in (None, now["programs"]):
            flags.append("PROGRAMS")
        bounds += " (before: " + (", ".join(f"{k} {v:.6g}" for k, v in before["bounds"].items()) or "none") + ")"
    return (f"| {name} | {now['kind']} | {now['status']} | {bounds} | {now['seconds']} | {now['solves']} | "
            f"{' '.join(flags)} |")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("files", nargs="*", type=Path)
    parser.add_argument("--time-limit", type=float, default=120.0, help="the class's limit, s (default 120)")
    parser.add_argument("--json", type=Path, default=None, help="keep the figures in this file")
    parser.add_argument("--compare", type=Path, default=None, help="figures kept before (--json)")
    args = parser.parse_args()
    files = args.files or [p for p in sorted((ROOT / "examples" / "models").glob("*.toml"))
                           if "\n[disturbances]" in p.read_text() and not p.stem.startswith(SKIPPED)]
    before = json.loads(args.compare.read_text()) if args.compare else {}
    print("| example | kind | status | bounds | s | solves | flags |")
    print("|---|---|---|---|---|---|---|")
    kept: dict[str, Any] = {}
    runs: list[tuple[str, Path, list[str] | None]] = [(path.stem, path, None) for path in files]
    runs += [(f"{path.stem} --box {' '.join(BOXES[path.stem])}", path, BOXES[path.stem]) for path in files
             if BOXES.get(path.stem)]
    for label, path, box in runs:
        kept[label] = run(path, args.time_limit, box)
        print(row(label, kept[label], before.get(label)), flush=True)
    if args.json is not None:
        args.json.write_text(json.dumps(kept, indent=1))


if __name__ == "__main__":
    main()
