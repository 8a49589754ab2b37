"""``roa`` and ``candidate`` on every shipped example, both kinds of loop (issue 41, item 1: one SOS
implementation of the two classes for polynomial loops and loops with functions).

Each example of ``examples/models/*.toml`` is certified with the class ``roa`` alone, and with
``candidate`` where the tests give it a candidate (:data:`CANDIDATES`), in one process, with no stored
certificate reused. The table gives, per run, the loop's kind, the status, the certificate's kind (the
route that proved it), the level, the share of the simulated region of attraction covered (``roa_share``,
else the share of the comparison box, ``box_share_estimate``), the certified ball radius, the wall time
and the solves. A loop with functions' ``roa`` is also run by its SOS route alone (``run_roa`` with
``interval=False``: the class tries ball arithmetic first, and on the shipped loops that route proves a
set before the SOS route is reached). ``--json FILE`` keeps the figures; ``--compare FILE`` prints the
figures kept before beside them and flags:

* ``LOST``: a status that was ``certified`` and is not any more;
* ``WORSE``: a polynomial loop's level, share or ball radius that changed at all, or a loop with
  functions' share or ball radius that shrank (its level is of another V, not comparable);
* ``PROGRAMS``: a polynomial loop whose search solved other programs than before (the sequence of the
  structures' keys in the solver log, hashed: a polynomial loop's programs must be the same ones).

    python benchmarks/bench_roa_route.py [--json after.json] [--compare before.json] [--time-limit 60]
                                         [--robots] [--only TEXT] [FILE.toml ...]

Without files: every example but the paper's (``paper-*``, minutes each) and, unless ``--robots``, the
robots' (``robot-*``, which ``benchmarks/bench_robot_roa.py`` measures on their own: minutes each).
The time limit is each class's safety net (the searches stop by counts of work): a run that ends near
it (the actuator pendulum's ball route, about 55 s idle) can come out ``inconclusive`` on a loaded
machine; run such a row again with a larger ``--time-limit`` on both sides to compare its figures.
"""

from __future__ import annotations

import argparse
import hashlib
import json
import time
from pathlib import Path
from typing import Any

from route_runs import loop_kind, solve_log, timed_certify  # (beside this script)

from lyapcheck.models.language.modelfile import Model, parse_any_model
from lyapcheck.tolerances import MODEL_CLASS_TIME_LIMIT_S

ROOT = Path(__file__).resolve().parents[1]
SKIPPED = ("paper-",)
ROBOTS = ("robot-",)
#: the candidates the tests certify on the shipped examples (tests/test_docs_model_files.py,
#: tests/test_verify_tamper_recast.py, tests/test_recast_classes.py, tests/test_model_classes.py)
CANDIDATES: dict[str, list[str]] = {
    "drake-cubic-polynomial": ["x**2"],
    "fossil-poly2": ["x**2 + y**2"],
    "van-der-pol-reversed": ["x1**2 + x2**2 + 1"],
    "recast-pendulum": ["1 - cos(theta) + omega**2/2", "1 - cos(theta) + omega**2/2 + theta*omega/4"],
    "recast-ilos-course": ["2*y**2 + y*yi + yi**2"],
}
#: the figures compared (``numbers`` keys of the class's result)
FIGURES = ("level", "roa_share", "box_share_estimate", "ball_radius")


def run(path: Path, limit: float, name: str, candidate: str | None = None) -> dict[str, Any]:
    """The class's status, figures and wall time on one example."""
    start = time.perf_counter()
    try:
        kind = loop_kind(path.read_text(), str(path))
    except Exception as exc:  # (a file this reader refuses, a sampled-data loop: its row says why)
        return {"kind": "other", "status": f"refused: {str(exc)[:80]}", "route": None, "figures": {},
                "seconds": 0.0, "solves": 0, "programs": None}
    try:
        found, seconds = timed_certify(path, classes=name, time_limit_s=limit, candidate=candidate)
    except Exception as exc:  # (an example that refuses the class: its row says why)
        return {"kind": kind, "status": f"refused: {str(exc)[:80]}", "route": None, "figures": {},
                "seconds": round(time.perf_counter() - start, 1), "solves": 0, "programs": None}
    result = found.conditions[name]
    solves, programs = solve_log(result)
    numbers = result.numbers or {}
    figures = {k: numbers[k] for k in FIGURES if isinstance(numbers.get(k), (int, float))}
    return {"kind": kind, "status": result.status, "route": (result.certificate or {}).get("kind"),
            "figures": figures, "seconds": round(seconds, 1), "solves": solves, "programs": programs}


def run_sos_route(path: Path, limit: float) -> dict[str, Any]:
    """A loop with functions' ``roa`` by the SOS route alone (the ball-arithmetic route, tried first by
    the class, not run: on the shipped loops it proves a set first and the SOS route is not reached)."""
    from lyapcheck.models.classes.recast_classes import linearization
    from lyapcheck.models.classes.recast_regions import class_budget, comparison_box, proved_loop, run_roa

    model = parse_any_model(path.read_text(), str(path))
    start = time.perf_counter()
    loop = proved_loop(model, limit)  # type: ignore[arg-type]
    box = comparison_box(model, loop)  # type: ignore[arg-type]
    result = run_roa(loop, linearization(loop), class_budget(limit), box, interval=False)
    numbers = result.numbers or {}
    keys = [entry.get("program") for entry in (result.solver or {}).get("solves", [])]
    return {"kind": "functions", "status": result.status, "route": (result.certificate or {}).get("kind"),
            "figures": {k: numbers[k] for k in FIGURES if isinstance(numbers.get(k), (int, float))},
            "seconds": round(time.perf_counter() - start, 1), "solves": len(keys),
            "programs": hashlib.sha256(json.dumps(keys).encode()).hexdigest()[:16]}


def with_functions(path: Path) -> bool:
    """A loop with functions (a file the ``roa`` route of loops with functions reads; a sampled-data
    loop, which that parser refuses, is not one)."""
    try:
        return not isinstance(parse_any_model(path.read_text(), str(path)), Model)
    except Exception:  # (a file this reader refuses: its ``roa`` row says why)
        return False


def flags_of(now: dict[str, Any], before: dict[str, Any]) -> list[str]:
    flags: list[str] = []
    if before["status"] == "certified" and now["status"] != "certified":
        flags.append("LOST")
    for k, old in before["figures"].items():
        new = now["figures"].get(k)
        if now["kind"] == "polynomial":
            worse = new != old
        else:
            worse = k != "level" and (new is None or new < old)
        if worse:
            flags.append(f"WORSE {k}")
    if now["kind"] == "polynomial" and before.get("programs") not in (None, now["programs"]):
        flags.append("PROGRAMS")
    return flags


def row(label: str, now: dict[str, Any], before: dict[str, Any] | None) -> str:
    figures = ", ".join(f"{k} {v:.6g}" for k, v in now["figures"].items())
    flags: list[str] = []
    if before is not None:
        flags = flags_of(now, before)
        figures += (f" (before: {before['status']}, " +
                    (", ".join(f"{k} {v:.6g}" for k, v in before["figures"].items()) or "none") + ")")
    return (f"| {label} | {now['kind']} | {now['status']} | {now['route']} | {figures} | {now['seconds']} | "
            f"{now['solves']} | {' '.join(flags)} |")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("files", nargs="*", type=Path)
    parser.add_argument("--time-limit", type=float, default=MODEL_CLASS_TIME_LIMIT_S,
                        help=f"each class's limit, s (default {MODEL_CLASS_TIME_LIMIT_S:g}, the classes' own)")
    parser.add_argument("--robots", action="store_true", help="the robot-* examples too (minutes each)")
    parser.add_argument("--only", default=None, help="the runs whose label holds this text only")
    parser.add_argument("--json", type=Path, default=None, help="keep the figures in this file")
    parser.add_argument("--compare", type=Path, default=None, help="figures kept before (--json)")
    args = parser.parse_args()
    skipped = SKIPPED + (() if args.robots else ROBOTS)
    files = args.files or [p for p in sorted((ROOT / "examples" / "models").glob("*.toml"))
                           if not p.stem.startswith(skipped)]
    before = json.loads(args.compare.read_text()) if args.compare else {}
    print("| run | kind | status | route | figures | s | solves | flags |")
    print("|---|---|---|---|---|---|---|---|")
    kept: dict[str, Any] = {}
    runs: list[tuple[str, Path, str, str | None]] = [(f"{path.stem} roa", path, "roa", None) for path in files]
    runs += [(f"{path.stem} roa, SOS route alone", path, "sos_route", None) for path in files
             if with_functions(path)]
    runs += [(f"{path.stem} candidate {v}", path, "candidate", v) for path in files
             for v in CANDIDATES.get(path.stem, [])]
    for label, path, name, candidate in runs:
        if args.only is not None and args.only not in label:
            continue
        kept[label] = run_sos_route(path, args.time_limit) if name == "sos_route" else \
            run(path, args.time_limit, name, candidate)
        print(row(label, kept[label], before.get(label)), flush=True)
        if args.json is not None:  # (kept after each run: a long benchmark stopped early keeps what it measured)
            args.json.write_text(json.dumps(kept, indent=1))


if __name__ == "__main__":
    main()
