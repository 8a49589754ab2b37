"""Completeness and soundness of the global classes on systems from the literature (issue 30).

The suite is ``benchmarks/completeness/``: one model file per system, ``positive/`` (globally
asymptotically stable, a Lyapunov function quoted in the file's comments and checked by
``benchmarks/completeness/check_quotes.py``) and ``negative/`` (not GAS: a second equilibrium, a
limit cycle, a finite escape, a centre, a critical unstable point, a lossless mode), indexed by
``benchmarks/completeness/index.toml``.

Each system runs as ``lyapcheck certify FILE --json --classes quadratic,sos_gas`` in a fresh
process (``python -m lyapcheck``, imports included, the certificate store off so that every run
searches; a fair picture of what a user waits for at a model's first run, not of the engine alone). A positive is ``found`` when either
class is certified (the column ``class`` says which: ``quad``, ``gas`` or ``quad+gas``), ``missed``
otherwise (``timeout`` when the process overran ``--timeout``). A negative must get neither class:
a ``certified`` there is printed as ``SOUNDNESS VIOLATION`` and the script exits 1, whatever else
happened. The column ``today`` is the expectation recorded in the index (``expect_today``), so a
change in either direction shows as ``NEW FIND`` or ``REGRESSION``.

Run:  .venv/bin/python benchmarks/bench_completeness.py [--fast] [--only STEM,...] [--timeout 120]
      [--json OUT]
Exit 0, or 1 on a soundness violation (or, with --strict, on any difference from expect_today).
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import time
import tomllib
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]
SUITE = ROOT / "benchmarks" / "completeness"
GLOBAL_CLASSES = ("quadratic", "sos_gas")
SHORT = {"quadratic": "quad", "sos_gas": "gas"}


@dataclass
class Outcome:
    """One system's run: what the global classes gave and how long the process took."""

    stem: str
    kind: str  # "positive" or "negative"
    states: int
    seconds: float
    statuses: dict[str, str]  # class -> status ("timeout" / "error" for the whole run)
    expect_today: str | None

    @property
    def certified(self) -> list[str]:
        return [c for c in GLOBAL_CLASSES if self.statuses.get(c) == "certified"]

    @property
    def result(self) -> str:
        """``found`` / ``missed`` / ``timeout`` / ``error`` for a positive; ``none`` or
        ``VIOLATION`` for a negative."""
        if self.kind == "negative":
            return "VIOLATION" if self.certified else "none"
        if self.certified:
            return "found"
        if "timeout" in self.statuses.values() or "error" in self.statuses.values():
            return next(v for v in self.statuses.values() if v in ("timeout", "error"))
        return "missed"


def load_index() -> dict[str, dict[str, dict[str, Any]]]:
    """``index.toml`` as {kind: {stem: entry}}; every entry names a file that exists."""
    index = tomllib.loads((SUITE / "index.toml").read_text())
    for kind in ("positive", "negative"):
        for stem in index[kind]:
            path = SUITE / kind / f"{stem}.toml"
            if not path.is_file():
                raise FileNotFoundError(f"index.toml: [{kind}.{stem}]: no file {path}")
    return index


def run_system(kind: str, stem: str, entry: dict[str, Any], timeout: float,
               env: dict[str, str] | None = None) -> Outcome:
    """``lyapcheck certify FILE --json --classes quadratic,sos_gas`` in a fresh process."""
    path = SUITE / kind / f"{stem}.toml"
    cmd = [sys.executable, "-m", "lyapcheck", "certify", str(path), "--json", "--classes", ",".join(GLOBAL_CLASSES)]
    t0 = time.perf_counter()
    try:
        # the certificate store off: every run searches (a stored certificate would skip the search measured)
        proc = subprocess.run(cmd, cwd=ROOT, capture_output=True, text=True, timeout=timeout,
                              env={**os.environ, "LYAPCHECK_CERTIFICATE_STORE": "off", **(env or {})})
    except subprocess.TimeoutExpired:
        statuses = {c: "timeout" for c in GLOBAL_CLASSES}
    else:
        try:
            conditions = json.loads(proc.stdout)["conditions"]
            statuses = {c: conditions[c]["status"] for c in GLOBAL_CLASSES}
        except (json.JSONDecodeError, KeyError):
            print(f"{stem}: exit {proc.returncode}: {proc.stderr.strip()[-400:]}", file=sys.stderr)
            statuses = {c: "error" for c in GLOBAL_CLASSES}
    seconds = time.perf_counter() - t0
    return Outcome(stem, kind, int(entry["states"]), seconds, statuses, entry.get("expect_today"))


def selected(index: dict[str, Any], only: set[str], fast: bool) -> list[tuple[str, str, dict[str, Any]]]:
    rows = [(kind, stem, entry) for kind in ("positive", "negative") for stem, entry in index[kind].items()]
    if only:
        unknown = only - {stem for _, stem, _ in rows}
        if unknown:
            raise SystemExit(f"--only: no system named {', '.join(sorted(unknown))} in index.toml")
        rows = [r for r in rows if r[1] in only]
    if fast:
        rows = [r for r in rows if r[2].get("fast")]
    return rows


def note(o: Outcome) -> str:
    if o.kind == "negative":
        return "SOUNDNESS VIOLATION: " + ", ".join(o.certified) + " certified" if o.certified else ""
    today = o.expect_today
    if today is None or o.result == today:
        return ""
    if o.result == "found":
        return f"NEW FIND (index says {today})"
    return f"REGRESSION (index says {today})"


def print_table(outcomes: list[Outcome]) -> None:
    width = max([len(o.stem) for o in outcomes] + [6])
    for kind in ("positive", "negative"):
        rows = [o for o in outcomes if o.kind == kind]
        if not rows:
            continue
        print(f"\n{kind}s" + ("" if kind == "positive" else " (must get no global class)"))
        print(f"{'system':{width}s} | states | {'result':9s} | seconds | class    | today  | note")
        print(f"{'-' * width}-+--------+-----------+---------+----------+--------+-----")
        for o in rows:
            cls = "+".join(SHORT[c] for c in o.certified) or "-"
            today = o.expect_today or "-"
            print(f"{o.stem:{width}s} | {o.states:6d} | {o.result:9s} | {o.seconds:7.2f} | {cls:8s} | {today:6s} | {note(o)}")
    pos = [o for o in outcomes if o.kind == "positive"]
    neg = [o for o in outcomes if o.kind == "negative"]
    if pos:
        found = [o for o in pos if o.result == "found"]
        print(f"\npositives: {len(found)} found / {len(pos) - len(found)} missed of {len(pos)}; "
              f"time {sum(o.seconds for o in pos):.1f} s (found ones {sum(o.seconds for o in found):.1f} s)")
    if neg:
        bad = [o for o in neg if o.certified]
        print(f"negatives: {len(neg) - len(bad)} of {len(neg)} got no global class; time {sum(o.seconds for o in neg):.1f} s")


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--only", default="", help="comma-separated stems of index.toml")
    parser.add_argument("--fast", action="store_true", help="only the fast subset (fast = true in index.toml)")
    parser.add_argument("--timeout", type=float, default=120.0, help="seconds per system (default 120)")
    parser.add_argument("--json", type=Path, help="also write the outcomes as JSON here")
    parser.add_argument("--strict", action="store_true", help="exit 1 on any difference from expect_today too")
    args = parser.parse_args(argv)
    if args.timeout <= 0:
        parser.error(f"--timeout must be a positive number of seconds; got {args.timeout}")
    index = load_index()
    rows = selected(index, {s for s in args.only.split(",") if s}, args.fast)
    outcomes = []
    for kind, stem, entry in rows:
        o = run_system(kind, stem, entry, args.timeout)
        outcomes.append(o)
        print(f"  {kind:8s} {stem}: {o.result} in {o.seconds:.2f} s", file=sys.stderr, flush=True)
    print_table(outcomes)
    if args.json:
        args.json.write_text(json.dumps([{**asdict(o), "result": o.result} for o in outcomes], indent=1))
    violations = [o for o in outcomes if o.kind == "negative" and o.certified]
    for o in violations:
        print(f"\n!!! SOUNDNESS VIOLATION: {o.stem} is not GAS, but {', '.join(o.certified)} certified it !!!")
    changed = [o for o in outcomes if o.kind == "positive" and o.expect_today and o.result != o.expect_today]
    if violations:
        return 1
    return 1 if args.strict and changed else 0


if __name__ == "__main__":
    sys.exit(main())
