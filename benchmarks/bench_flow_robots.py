"""Validated-flow boxes at 4 to 6 states (issue 42): how much of the domain the boxes proved to flow into a
certified set add, and what they cost.

For each robot: the certified ``roa`` set is read from a ``certify --json`` document (``--json-dir``, one
``<stem>.json`` per robot), the flow enlargement (:func:`lyapcheck.models.classes.flow_region.extend`) is run on
the ``[domain]`` with the states allowed, and the simulated share of the region of attraction is measured
before and after. ``--level`` replaces the proved level by another one (a SAMPLED level, never proved: the
figure then says what the boxes would add once the set grows, and is labelled "not proved").
``--per-box WIDTH``: instead, a few single boxes of that share of the domain's widths, centred at uniform
samples outside the set whose simulation enters it, each integrated alone (:func:`flow_into`) with a cap on
its steps: the outcome, the steps and seconds, against the simulated entry time (``--P`` a ``.npy`` matrix
for ``V = z^T P z`` in place of the certificate's, with ``--level``; also NOT proved).

    LYAPCHECK_CERTIFICATE_STORE=off python -m lyapcheck certify examples/models/robot-acrobot-lqr.toml \
        --classes roa --json > /tmp/robot-acrobot-lqr.json
    python benchmarks/bench_flow_robots.py --json-dir /tmp --only acrobot --seconds 60
    python benchmarks/bench_flow_robots.py --json-dir /tmp --only acrobot --level 1 --per-box 0.01
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from fractions import Fraction
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]
ROBOTS = {"cart-pole": "robot-cart-pole-lqr", "acrobot": "robot-acrobot-lqr", "pendubot": "robot-pendubot-lqr",
          "planar-quadrotor": "robot-planar-quadrotor-lqr"}


def robot(stem: str) -> Any:
    """The example's model (a loop with functions) and its loop in deviations."""
    from lyapcheck.models.classes.recast_classes import base_loop
    from lyapcheck.models.language.modelfile import load_any_model
    from lyapcheck.models.language.recast import RecastModel

    model = load_any_model(ROOT / "examples" / "models" / f"{stem}.toml")
    assert isinstance(model, RecastModel), stem
    return model, base_loop(model.system)


def step_timing(loop: Any, h: Fraction, box: Any, repeats: int = 20) -> float:
    """Seconds per validated step of a small box at the domain's centre."""
    from lyapcheck.models.engines.interval_field import ball
    from lyapcheck.models.engines.validated_flow import LipschitzLoop, precision, start, step

    field = LipschitzLoop(loop.system)
    lo = [Fraction(float(a) / 64).limit_denominator(1 << 20) for a in box[0]]
    hi = [Fraction(float(b) / 64).limit_denominator(1 << 20) for b in box[1]]
    with precision(53):
        s = start(lo, hi)
        t0 = time.perf_counter()
        for _ in range(repeats):
            nxt = step(field, s, ball(h))
            s = nxt if nxt is not None else s
        return (time.perf_counter() - t0) / repeats


def run(stem: str, doc: dict, seconds: float, level: str | None, steps: int | None) -> None:
    from lyapcheck.models.classes import flow_region
    from lyapcheck.models.classes.recast_regions import certified_value, comparison_box, simulated_check
    from lyapcheck.models.engines.search import Budget
    from lyapcheck.results import ConditionResult

    model, loop = robot(stem)
    box = comparison_box(model, loop)
    roa = doc["conditions"]["roa"]
    cert = dict(roa["certificate"])
    label = "proved"
    if level is not None:
        cert["level"] = str(Fraction(level))
        cert.pop("box", None)  # (the proved set's box bounds the proved level only)
        cert["whole"] = True
        label = "SAMPLED, NOT PROVED"
    kind = cert.get("kind")
    # (extend enlarges ball-arithmetic sets only; a set proved on the recasting's relations is measured as one)
    cert["kind"] = "interval"
    result = ConditionResult("roa", "certified", "probe", numbers={}, certificate=cert)
    simulated_check(loop, result, box)
    before = result.numbers.get("roa_share")
    # (the route's gates opened for the measurement only: the shipped route stays at 2 states)
    setattr(flow_region, "FLOW_STATES", (2, 3, 4, 5, 6))
    if steps is not None:
        setattr(flow_region, "FLOW_STEP_BUDGET", steps)
    outcomes: list[tuple[int | None, str, int, float]] = []
    integrate = flow_region.flow_into

    def counted(*args, **kwargs):  # (each box's outcome and time, for the figures)
        t = time.perf_counter()
        out = integrate(*args, **kwargs)
        outcomes.append((out.steps, out.why.split(" at step")[0].split(" after")[0], out.taken,
                         time.perf_counter() - t))
        return out

    setattr(flow_region, "flow_into", counted)
    setattr(flow_region, "FLOW_INITIAL_CUTS", {**flow_region.FLOW_INITIAL_CUTS, 5: 2, 6: 2})
    h = flow_region.step_of(loop)
    assert h is not None, "the Jacobian at the equilibrium is not enclosed"
    per_step = step_timing(loop, h, box)
    t0 = time.perf_counter()
    flow_region.extend(loop, result, Budget(seconds, "probe"), box, certified_value(loop, result)[0])
    spent = time.perf_counter() - t0
    after = before
    if "flow" in result.certificate:
        simulated_check(loop, result, box)
        after = result.numbers.get("roa_share")
    boxes = result.certificate.get("flow", {}).get("boxes", [])
    widths = [max(float(Fraction(b[1]) - Fraction(b[0])) / float(hi - lo)
                  for b, lo, hi in zip(e["box"].values(), *box)) for e in boxes]
    print(json.dumps({"robot": stem, "level": float(Fraction(cert["level"])), "level_is": label,
                      "cert_kind": kind, "step": str(h), "s_per_step": round(per_step, 4),
                      "seconds": round(spent, 1), "flow_steps": result.numbers.get("flow_steps"),
                      "boxes": len(boxes), "largest_box_width_share": max(widths, default=None),
                      "share_before": before, "share_after": after,
                      "stopped": result.numbers.get("flow_stopped") or result.numbers.get("flow_skipped"),
                      "boxes_left": result.numbers.get("flow_boxes_left"), "boxes_tried": len(outcomes),
                      "why_not": {why: sum(1 for o in outcomes if o[1] == why) for why in {o[1] for o in outcomes}},
                      "steps_per_proved_box": [o[2] for o in outcomes if o[0] is not None][:10],
                      "validated_seconds": round(sum(o[3] for o in outcomes), 1)}), flush=True)


def per_box(stem: str, doc: dict, level: str, width: float, count: int, max_steps: int, P_file: Path | None
            ) -> None:
    """Single boxes outside ``{z^T P z <= level}`` (a sampled level: NOT proved), each integrated alone."""
    import flint
    import numpy as np

    from lyapcheck.models.classes.flow_region import step_of
    from lyapcheck.models.classes.recast_regions import comparison_box
    from lyapcheck.models.engines.interval_region import quadratic_form
    from lyapcheck.models.engines.recast_numeric import FloatLoop, rk4_step
    from lyapcheck.models.engines.recast_sos import poly_from_json
    from lyapcheck.models.engines.validated_flow import LipschitzLoop, flow_into, precision

    model, loop = robot(stem)
    n = loop.n
    lo, hi = (np.asarray(x, dtype=float) for x in comparison_box(model, loop))
    if P_file is not None:
        P = np.load(P_file)
    else:
        Q = quadratic_form(loop.ring, poly_from_json(loop.ring, doc["conditions"]["roa"]["certificate"]["V"], "V"), n)
        assert Q is not None, "the certified V is not a quadratic form of the states"
        P = np.array([[float(x) for x in row] for row in Q])
    c = float(Fraction(level))
    Pb = flint.arb_mat([[flint.arb(float(x)) for x in row] for row in P])

    def target(X: list) -> bool:
        v = flint.arb_mat([[x] for x in X])
        return bool((v.transpose() * Pb * v)[0, 0] <= flint.arb(c))

    h = step_of(loop)
    assert h is not None, "the Jacobian at the equilibrium is not enclosed"
    field = LipschitzLoop(loop.system)
    f = FloatLoop(loop.system)
    eq = np.array([float(loop.system.values[s]) for s in loop.system.states])
    Z = lo + (hi - lo) * np.random.default_rng(0).random((3000, n))
    X = Z + eq
    dt = max(float(h) * 4, 1 / 1024)  # (the simulation only picks the boxes and times their entry)
    entered = np.full(len(Z), -1.0)
    with np.errstate(all="ignore"):
        for k in range(int(12 / dt)):
            D = X - eq
            entered[(entered < 0) & (np.einsum("ni,ij,nj->n", D, P, D) <= c)] = k * dt
            if (entered >= 0).all():
                break
            X = rk4_step(f, X, dt)
    outside = entered > 0
    print(f"{stem}: step {h}, level {c:g} (SAMPLED, NOT PROVED), the set's share of the box "
          f"{np.mean(entered == 0):.3f}, starts entering within 12: {np.mean(entered >= 0):.3f}, median entry time of "
          f"the outside ones {np.median(entered[outside]):.3g}", flush=True)
    for i in np.where(outside)[0][:count]:
        half = width * (hi - lo) / 2
        blo = [Fraction(float(x)).limit_denominator(1 << 20) for x in Z[i] - half]
        bhi = [Fraction(float(x)).limit_denominator(1 << 20) for x in Z[i] + half]
        t0 = time.perf_counter()
        with precision(53):
            out = flow_into(field, blo, bhi, h, target, max_steps, float(max(hi - lo)), max_pieces=16)
        print(f"  box {width:g} of the domain, simulated entry t = {entered[i]:.3g} ({entered[i] / float(h):.0f} "
              f"steps): {'proved at step ' + str(out.steps) if out.steps is not None else out.why}; "
              f"{out.taken} steps in {out.pieces} pieces, {time.perf_counter() - t0:.1f} s", flush=True)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--json-dir", required=True, type=Path)
    parser.add_argument("--only", nargs="*", choices=sorted(ROBOTS), default=sorted(ROBOTS))
    parser.add_argument("--seconds", type=float, default=60.0)
    parser.add_argument("--level", type=Fraction, default=None, help="a sampled level in place of the proved one (not proved)")
    parser.add_argument("--steps", type=int, default=None, help="the step budget in place of FLOW_STEP_BUDGET")
    parser.add_argument("--per-box", type=float, default=None, metavar="WIDTH",
                        help="single boxes of this share of the domain's widths (needs --level)")
    parser.add_argument("--boxes", type=int, default=3, help="how many single boxes (--per-box)")
    parser.add_argument("--P", type=Path, default=None, help="a .npy matrix for V = z^T P z (--per-box)")
    args = parser.parse_args(argv)
    for name in args.only:
        path = args.json_dir / f"{ROBOTS[name]}.json"
        try:
            doc = json.loads(path.read_text())
        except (OSError, ValueError) as exc:
            print(f"bench_flow_robots: --json-dir: {path} is not a certify --json document ({exc})", file=sys.stderr)
            return 2
        if args.per_box is not None:
            if args.level is None:
                print("bench_flow_robots: --per-box needs --level (a sampled level)", file=sys.stderr)
                return 2
            per_box(ROBOTS[name], doc, args.level, args.per_box, args.boxes, args.steps or 12_000, args.P)
        else:
            run(ROBOTS[name], doc, args.seconds, args.level, args.steps)
    return 0


if __name__ == "__main__":
    sys.exit(main())
