"""``quadratic`` and ``sos_gas`` on every shipped example, both kinds of loop (issue 41, item 1: one
implementation of the classes for polynomial loops and loops with functions).

Each example of ``examples/models/*.toml`` (and each loop with functions of ``tests/recast_loops.py``)
is certified with the classes ``quadratic`` and ``sos_gas``, in one process, with no stored certificate
reused. The table gives, per example and class, its kind, the status, the figures (``degree``,
``decay_rate_per_s`` and ``k`` of a GES bound, ``decay_rate_V_per_s``) and the wall time. ``--json FILE``
keeps the figures; ``--compare FILE`` prints beside each figure the one kept before and flags:

* ``LOST``: a status that was ``certified`` or ``refuted`` and is not any more;
* ``WORSE``: a figure that got worse (a polynomial loop's must be identical; on a loop with functions a
  decay rate may only grow, ``k`` and the degree only shrink), or a GES claim that became GAS;
* ``PROGRAMS``: a polynomial loop whose search solved other programs than before (the sequence of the
  structures' keys in the solver log, hashed: a polynomial loop's programs must be the same ones).

    python benchmarks/bench_gas_route.py [--json after.json] [--compare before.json] [--time-limit 60]
                                         [FILE.toml ...]

Without files: every example but the paper's (``paper-*``, minutes each) and the tests' loops.
"""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
from pathlib import Path
from typing import Any

from route_runs import loop_kind, solve_log, timed_certify  # (beside this script)


ROOT = Path(__file__).resolve().parents[1]
SKIPPED = ("paper-",)
CLASSES = ("quadratic", "sos_gas")
#: the figures compared, with the direction that is better on a loop with functions (+1: larger)
FIGURES = {"decay_rate_per_s": 1, "decay_rate_V_per_s": 1, "k": -1, "degree": -1}


def test_loops() -> dict[str, str]:
    """The loops with functions of ``tests/recast_loops.py`` (model texts), by name."""
    sys.path.insert(0, str(ROOT / "tests"))
    import recast_loops

    return {name: text for name, text in vars(recast_loops).items()
            if name.isupper() and isinstance(text, str) and "[dynamics]" in text}


def run(path: Path, limit: float) -> dict[str, Any]:
    """Each class's status, figures and wall time on one model file."""
    kind = loop_kind(path.read_text(), str(path))
    out: dict[str, Any] = {}
    found, wall = timed_certify(path, classes=",".join(CLASSES), time_limit_s=limit)
    seconds = round(wall, 1)
    for name in CLASSES:
        result = found.conditions[name]
        solves, programs = solve_log(result)
        out[name] = {"kind": kind, "status": result.status, "property": result.property,
                     "figures": {k: result.numbers.get(k) for k in FIGURES if result.numbers.get(k) is not None},
                     "seconds": seconds, "solves": solves, "programs": programs}
    return out


def flags_of(now: dict[str, Any], before: dict[str, Any]) -> list[str]:
    flags: list[str] = []
    if before["status"] in ("certified", "refuted") and now["status"] != before["status"]:
        flags.append("LOST")
    if before.get("property") == "GES" and now.get("property") != "GES":
        flags.append("WORSE GES")
    for k, old in before["figures"].items():
        new = now["figures"].get(k)
        if now["kind"] == "polynomial":
            bad = new != old
        else:
            bad = new is None or (new - old) * FIGURES[k] < 0
        if bad and before["status"] == "certified":
            flags.append(f"WORSE {k}")
    if now["kind"] == "polynomial" and before.get("programs") not in (None, now["programs"]):
        flags.append("PROGRAMS")
    return flags


def row(label: str, name: str, now: dict[str, Any], before: dict[str, Any] | None) -> str:
    figures = ", ".join(f"{k} {v:.6g}" for k, v in now["figures"].items())
    flags = flags_of(now, before) if before is not None else []
    if before is not None:
        figures += f" (before: {before['status']} " + \
            (", ".join(f"{k} {v:.6g}" for k, v in before["figures"].items()) or "none") + ")"
    return (f"| {label} | {name} | {now['kind']} | {now['status']} {now.get('property') or ''} | {figures} | "
            f"{now['seconds']} | {now['solves']} | {' '.join(flags)} |")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("files", nargs="*", type=Path)
    parser.add_argument("--time-limit", type=float, default=60.0, help="each class's limit, s (default 60)")
    parser.add_argument("--json", type=Path, default=None, help="keep the figures in this file")
    parser.add_argument("--compare", type=Path, default=None, help="figures kept before (--json)")
    args = parser.parse_args()
    runs: list[tuple[str, Path]] = [(p.stem, p) for p in args.files]
    scratch = tempfile.TemporaryDirectory()
    if not args.files:
        runs = [(p.stem, p) for p in sorted((ROOT / "examples" / "models").glob("*.toml"))
                if not p.stem.startswith(SKIPPED)]
        for name, text in test_loops().items():
            path = Path(scratch.name) / f"{name.lower()}.toml"
            path.write_text(text)
            runs.append((f"tests:{name}", path))
    before = json.loads(args.compare.read_text()) if args.compare else {}
    print("| example | class | kind | status | figures | s | solves | flags |")
    print("|---|---|---|---|---|---|---|---|")
    kept: dict[str, Any] = {}
    for label, path in runs:
        try:
            kept[label] = run(path, args.time_limit)
        except Exception as exc:  # a model this route cannot read: said, and the next one runs
            print(f"| {label} | | | error: {type(exc).__name__}: {exc} | | | | |", flush=True)
            continue
        for name in CLASSES:
            print(row(label, name, kept[label][name], before.get(label, {}).get(name)), flush=True)
    if args.json is not None:
        args.json.write_text(json.dumps(kept, indent=1))


if __name__ == "__main__":
    main()
