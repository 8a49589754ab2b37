"""``reach_avoid`` on every shipped example and test loop that asks it, both kinds of loop (issue 41,
item 1: one implementation of the class for polynomial loops and loops with functions).

Each loop is certified with the class ``reach_avoid`` alone, in one process, with no stored certificate
reused: the shipped examples with a ``goal`` in their ``[sets]`` (``examples/models/*.toml``) and the
loops the tests ask (``tests/test_reach_avoid*.py``, ``tests/test_recast_reach_avoid.py``,
``tests/test_recast_box_safety.py``, built from their own texts, over the tests' boxes). The table gives, per loop, its kind, the status, the certified time bound (s), the
wall time and the solves. ``--json FILE`` keeps the figures; ``--compare FILE`` prints beside each
figure the one kept before and flags:

* ``LOST``: a status that was ``certified`` (or ``counterexample``) and is not any more;
* ``WORSE``: a time bound that grew (a polynomial loop's must be identical, a loop with functions'
  equal or smaller);
* ``PROGRAMS``: a polynomial loop whose search solved other programs than before (the sequence of the
  structures' keys in the solver log, hashed) or wrote another certificate (its JSON, hashed): a
  polynomial loop's programs and certificates must be the same ones.

    python benchmarks/bench_reach_route.py [--json after.json] [--compare before.json] [--time-limit 120]
                                           [NAME ...]
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
sys.path.insert(0, str(ROOT))  # (the tests' loop texts: tests/ is a package of the checkout)


def test_loops() -> dict[str, tuple[str, list[str] | None]]:
    """The loops the tests ask ``reach_avoid`` of: name -> (model text, box or None)."""
    from tests import test_reach_avoid as poly
    from tests import test_reach_avoid_counterexample as cex
    from tests import test_recast_reach_avoid as fun
    from tests.recast_loops import PENDULUM, SPRING
    from tests.test_recast_box_safety import BOX, COUPLED, PULSE
    from tests.test_recast_barrier import ACC, NEAR, SATURATED, TOO_CLOSE

    spring = SPRING + f"[sets]\ninitial = [{fun.INITIAL}]\nunsafe = [{{unsafe}}]\ngoal = [{fun.GOAL}]\n"
    pendulum = PENDULUM + ('[sets]\ninitial = ["(theta - 1)**2 + omega**2 <= 0.04"]\nunsafe = ["theta <= -3"]\n'
                           'goal = ["{goal}"]\n')
    goal = 'goal = ["x1**2 + x2**2 <= 0.1"]'
    return {
        "spiral": (poly.SPIRAL, None),
        "spiral-away": ('[model]\nname = "away"\nstates = ["x"]\n[dynamics]\nx = "x"\n[sets]\ninitial = '
                        '["1 <= x <= 2"]\nunsafe = ["x <= -5"]\ngoal = ["x**2 <= 0.01"]\n', None),
        "spiral-k --box k=0.5..1.5": (poly.SPIRAL.replace('x2 = "-x1 - x2"', 'x2 = "-k*x1 - x2"')
                                      + "[parameters]\nk = 1\n", ["k=0.5..1.5"]),
        "spiral-stay": (poly.SPIRAL + "stay_in_goal = true\n", None),
        "spiral-stay-away": (poly.SPIRAL.replace(goal, 'goal = ["(x1 - 1)**2 + x2**2 <= 0.1"]')
                             + "stay_in_goal = true\n", None),
        "spiral-crossed": (cex.SPIRAL.format(d=""), None),
        "after-goal": (cex.AFTER_GOAL, None),
        "spring": (spring.format(unsafe=fun.FAR), None),
        "spring-crossed": (spring.format(unsafe=fun.CROSSED), None),
        "acc-saturated": (ACC.format(v=SATURATED, initial=NEAR, unsafe=TOO_CLOSE)
                          + 'goal = ["(h - 30)**2 + (v - 20)**2 <= 0.25"]\n', None),
        "pendulum": (pendulum.format(goal="theta**2 + omega**2 <= 0.1"), None),
        "pendulum-omega-goal": (pendulum.format(goal="omega**2 <= 0.1"), None),
        f"coupled --box {' '.join(BOX)}": (COUPLED, list(BOX)),
        "pulse --box a=0.5..2.5": (PULSE, ["a=0.5..2.5"]),
    }


def loops() -> dict[str, tuple[str, list[str] | None]]:
    """Every loop measured: the shipped examples with a goal, then the tests' loops."""
    out = {path.stem: (path.read_text(), None) for path in sorted((ROOT / "examples" / "models").glob("*.toml"))
           if "\ngoal = " in path.read_text()}
    return {**out, **test_loops()}


def run(name: str, text: str, limit: float, box: list[str] | None) -> dict[str, Any]:
    """The class's status, time bound, wall time, solves and hashes on one loop."""
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / f"{name.split()[0]}.toml"
        path.write_text(text)
        kind = loop_kind(text, str(path))
        found, seconds = timed_certify(path, classes="reach_avoid", time_limit_s=limit, box=box)
    result = found.conditions["reach_avoid"]
    solves, programs = solve_log(result)
    return {"kind": kind, "status": result.status,
            "bound": (result.numbers or {}).get("reach_time_bound_s"), "seconds": round(seconds, 1),
            "solves": solves, "programs": programs, "certificate": certificate_digest(result),
            "summary": result.summary}


def row(name: str, now: dict[str, Any], before: dict[str, Any] | None) -> str:
    flags: list[str] = []
    bound = "" if now["bound"] is None else f"{now['bound']:.6g}"
    if before is not None:
        if before["status"] in ("certified", "counterexample") and now["status"] != before["status"]:
            flags.append("LOST")
        old, new = before["bound"], now["bound"]
        if old is not None and (new is None or (new != old if now["kind"] == "polynomial" else new > old)):
            flags.append("WORSE")
        if now["kind"] == "polynomial" and (before["programs"], before["certificate"]) != \
                (now["programs"], now["certificate"]):
            flags.append("PROGRAMS")
        bound += f" (before: {before['status']}, " + ("none" if old is None else f"{old:.6g}") + ")"
    return (f"| {name} | {now['kind']} | {now['status']} | {bound} | {now['seconds']} | {now['solves']} | "
            f"{' '.join(flags)} |")


def main() -> None:
    parser = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    parser.add_argument("names", nargs="*", help="the loops to run (default: all)")
    parser.add_argument("--time-limit", type=float, default=120.0, help="the class's limit, s (default 120)")
    parser.add_argument("--json", type=Path, default=None, help="keep the figures in this file")
    parser.add_argument("--compare", type=Path, default=None, help="figures kept before (--json)")
    args = parser.parse_args()
    before = json.loads(args.compare.read_text()) if args.compare else {}
    every = loops()
    unknown = [n for n in args.names if n not in every]
    if unknown:
        parser.error(f"unknown loop(s) {', '.join(unknown)}; known: {', '.join(every)}")
    print("| loop | kind | status | time bound (s) | s | solves | flags |")
    print("|---|---|---|---|---|---|---|")
    kept: dict[str, Any] = {}
    for name, (text, box) in every.items():
        if args.names and name not in args.names:
            continue
        kept[name] = run(name, text, args.time_limit, box)
        print(row(name, kept[name], before.get(name)), flush=True)
    if args.json is not None:
        args.json.write_text(json.dumps(kept, indent=1))


if __name__ == "__main__":
    main()
