"""Regions of attraction of the robot examples of issue 42 on their true loops: status, time and size.

The six examples are closed loops on true nonlinear robot dynamics (sin, cos, mass-matrix
denominators): the cart-pole, the acrobot, the pendubot and the planar quadrotor balanced by LQR
gains from ``control.lqr`` (``examples/models/robot-*-lqr.toml``), the pendulum held upright by a
saturated PD law over its whole range of angles (``robot-pendulum-sat-pd.toml``) and the inverted
pendulum with a saturated state feedback (``recast-inverted-pendulum-sat.toml``).

For each example it runs, each in a fresh process timed as a whole (imports included):

* ``lyapcheck certify FILE --classes linearization,roa --json``;
* for the LQR examples, ``lyapcheck certify FILE --classes linearization,candidate --candidate
  "z' S z" --json`` with ``S`` the LQR cost-to-go of ``control.lqr`` on the robot's linearization
  (``benchmarks/robot_lqr.py``, rounded to 6 significant digits), a Lyapunov function on a
  neighbourhood of the equilibrium by construction;

each with ``--time-limit`` (a class that reaches it is ``inconclusive``). It prints one row per
class run: the example, its number of states, the class, its status, the process's wall time, the
share of the simulated region of attraction within the ``[domain]`` box that the certified set covers
(``roa_share`` of the condition's JSON: lyapcheck's own simulation of the true loop on a grid of the
set's box), the certified level of ``V`` and the largest ball ``|x - x_eq| <= r`` inside the set
(``ball_radius``, where the certificate states one), the share of the ``[domain]`` box inside the certified
set (uniform samples) and which V the class kept (``V_from``: at 4 to 6 states ``roa`` proves both a
quadratic V shaped to cover the simulated region, ``lyapcheck/models/classes/shaped_quadratic.py``, and
the linearization's, and keeps the set covering more). Then Drake's Taylor-model level of ``z' S z``
(issue 42's anchor, 3.97 for the cart-pole; ``benchmarks/drake_level_check.py``): the share of the box
inside it and a point of the true loop below it where ``V' > 0``, confirmed by ball arithmetic. Then, per
example, issue 42's targets (a certified region of attraction in under 120 s covering at least 25 % of the
simulated region), and the summary and the reason of each class that did not certify. A crash (exit 3) or
an unreadable output is printed with its command and its stderr.

With ``--drake-python PYTHON`` (a Python with ``pydrake``: ``pip install drake==1.51.1``, an optional
extra, never the tests'), it then runs Drake's ``RegionOfAttraction`` on each LQR example's cubic
Taylor model with the same ``V = z' S z`` (``benchmarks/drake_taylor_roa.py``) and prints, on one set
of uniform starts in the ``[domain]`` box simulated on the true loop, the share of the converging
ones inside Drake's set and inside lyapcheck's certified set, and how many starts in Drake's set do
not converge (its set is the Taylor model's, not proved for the true loop).

Run:  python benchmarks/bench_robot_roa.py [--only NAME ...] [--time-limit S] [--drake-python PYTHON]
The lyapcheck that runs is the one ``python -m lyapcheck`` imports from a scratch directory (the
editable install, or the checkout ``PYTHONPATH`` names); the first line printed says which.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass
from fractions import Fraction
from pathlib import Path
from typing import Any

sys.path.insert(0, str(Path(__file__).resolve().parent))
import drake_level_check  # noqa: E402  (beside this file)
import robot_lqr  # noqa: E402  (beside this file)

ROOT = Path(__file__).resolve().parents[1]
MODELS = ROOT / "examples" / "models"

#: (label, model file stem, number of states, the LQR cost-to-go is a candidate)
EXAMPLES: list[tuple[str, str, int, bool]] = [
    ("cart-pole", "robot-cart-pole-lqr", 4, True),
    ("acrobot", "robot-acrobot-lqr", 4, True),
    ("pendubot", "robot-pendubot-lqr", 4, True),
    ("planar-quadrotor", "robot-planar-quadrotor-lqr", 6, True),
    ("pendulum-sat-pd", "robot-pendulum-sat-pd", 2, False),
    ("inv-pendulum-sat", "recast-inverted-pendulum-sat", 2, False),
]
#: issue 42's targets for every example
TARGET_SECONDS, TARGET_SHARE = 120.0, 0.25


@dataclass
class Run:
    """One certify process: the class whose row it gives, its command, wall time and document."""

    label: str
    states: int
    klass: str
    command: list[str]
    wall: float
    exit: int
    doc: dict[str, Any] | None
    error: str = ""

    def condition(self) -> dict[str, Any]:
        return (self.doc or {}).get("conditions", {}).get(self.klass, {})


def lyapcheck(*args: str, timeout: float) -> subprocess.CompletedProcess[str]:
    """``python -m lyapcheck ARGS`` run from a scratch directory: ``-m`` puts the working directory first
    on the path, so running from ROOT would import ROOT's checkout whatever PYTHONPATH says."""
    with tempfile.TemporaryDirectory(prefix="bench-robot-") as cwd:
        return subprocess.run([sys.executable, "-m", "lyapcheck", *args], capture_output=True, text=True,
                              cwd=cwd, timeout=timeout)


def imported_lyapcheck() -> str:
    with tempfile.TemporaryDirectory(prefix="bench-robot-") as cwd:
        done = subprocess.run([sys.executable, "-c", "import lyapcheck; print(lyapcheck.__file__)"],
                              capture_output=True, text=True, cwd=cwd, timeout=120)
    return done.stdout.strip() or done.stderr.strip()[-200:]


def run(label: str, stem: str, states: int, klass: str, extra: list[str], time_limit: float) -> Run:
    args = ["certify", str(MODELS / f"{stem}.toml"), "--classes", f"linearization,{klass}", *extra,
            "--time-limit", f"{time_limit:g}", "--json"]
    t0 = time.perf_counter()
    # each class stops at its time limit; the process's own limit is only against a hang
    done = lyapcheck(*args, timeout=10 * time_limit + 600)
    wall = time.perf_counter() - t0
    command = ["lyapcheck", *args]
    try:
        doc = json.loads(done.stdout)
    except json.JSONDecodeError:
        return Run(label, states, klass, command, wall, done.returncode, None,
                   (done.stderr.strip() or done.stdout.strip())[-600:])
    return Run(label, states, klass, command, wall, done.returncode, doc)


def figure(cond: dict[str, Any], key: str, fmt: str) -> str:
    value = cond.get(key)
    return "-" if value is None else format(float(value), fmt)


def ball_text(cond: dict[str, Any]) -> str:
    """The largest proved ball: the SOS route's ``ball_radius`` or the size figures' (``size.ball_radius``)."""
    radii = [float(r) for r in (cond.get("ball_radius"), (cond.get("size") or {}).get("ball_radius")) if r is not None]
    return format(max(radii), ".4g") if radii else "-"


#: uniform samples of the [domain] box for the share of it inside a certified set
BOX_SAMPLES = 400_000


def box_share(cond: dict[str, Any], stem: str) -> float | None:
    """The share of BOX_SAMPLES uniform points of the ``[domain]`` box (fixed seed) inside the certified set
    ``{V <= level}`` (within the certificate's box, where it states one), V read from the certificate's terms;
    None where the condition is not certified or its V involves more than the states."""
    import numpy as np

    cert = cond.get("certificate") or {}
    if cond.get("status") != "certified" or "V" not in cert or "level" not in cert:
        return None
    lo, hi = model_box(stem)
    n = len(lo)
    X = lo + (hi - lo) * np.random.default_rng(0).random((BOX_SAMPLES, n))
    value = np.zeros(len(X))
    for coefficient, exponents in cert["V"]["terms"]:
        if any(exponents[n:]):
            return None
        value += float(Fraction(coefficient)) * np.prod(X ** np.array(exponents[:n]), axis=1)
    inside = value <= float(Fraction(cert["level"]))
    states = cert.get("variables", [])[:n]
    if cert.get("box") and states:
        for i, name in enumerate(states):
            a, b = (float(Fraction(x)) for x in cert["box"][name])
            inside &= (X[:, i] >= a) & (X[:, i] <= b)
    return float(np.mean(inside))


def model_box(stem: str) -> tuple[Any, Any]:
    """The model file's ``[domain]`` box in its declared states' order (floats). Every example's equilibrium
    is the origin (checked: a file with an ``[equilibrium]`` table is refused), so the box is also the
    deviations' that the certificate's V is written in."""
    import tomllib

    import numpy as np

    data = tomllib.loads((MODELS / f"{stem}.toml").read_text())
    if "equilibrium" in data:
        raise SystemExit(f"{stem}: an [equilibrium] table; the box share reads V at the states themselves")
    states, domain = data["model"]["states"], data["domain"]
    return (np.array([float(domain[s][0]) for s in states]), np.array([float(domain[s][1]) for s in states]))


def box_text(value: float | None) -> str:
    return "-" if value is None else f"{100 * value:.3g} %"


def share_text(cond: dict[str, Any]) -> str:
    value = cond.get("roa_share")
    return "-" if value is None else f"{100 * float(value):.1f} %"


#: uniform starts in the [domain] box for the shares compared with Drake, the simulation's horizon (s),
#: step (s) and the radius counted as converged
COMPARE_SAMPLES, COMPARE_HORIZON_S, COMPARE_STEP_S, COMPARE_CONVERGED = 2000, 30.0, 0.01, 1e-3
#: how long Drake's run on one example may take
DRAKE_TIMEOUT_S = 1800.0


def converged_starts(stem: str, seed: int = 0) -> tuple["Any", "Any"]:
    """Uniform starts in the model's ``[domain]`` box and which of them converge on the true closed loop
    (RK4, :data:`COMPARE_HORIZON_S`; independent of lyapcheck: the field is ``robot_lqr``'s sympy one)."""
    import tomllib

    import numpy as np
    import sympy as sp

    z, f = robot_lqr.closed_loop(stem)
    domain = tomllib.loads((MODELS / f"{stem}.toml").read_text())["domain"]
    lo = np.array([float(domain[str(s)][0]) for s in z])
    hi = np.array([float(domain[str(s)][1]) for s in z])
    starts = lo + (hi - lo) * np.random.default_rng(seed).random((COMPARE_SAMPLES, len(z)))
    rhs = sp.lambdify(z, f, "numpy")

    def field(X: Any) -> Any:
        return np.stack([np.broadcast_to(np.asarray(c, dtype=float), X.shape[:1]) for c in rhs(*X.T)], axis=1)

    X = starts.copy()
    h = COMPARE_STEP_S
    with np.errstate(all="ignore"):
        for _ in range(int(COMPARE_HORIZON_S / h)):
            k1 = field(X)
            k2 = field(X + h / 2 * k1)
            k3 = field(X + h / 2 * k2)
            k4 = field(X + h * k3)
            X = X + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
            X[~np.isfinite(X).all(axis=1)] = np.inf  # diverged: stays out
    return starts, np.linalg.norm(X, axis=1) < COMPARE_CONVERGED


def rounded_cost_to_go(stem: str) -> "Any":
    """The ``S`` of the candidate text :func:`robot_lqr.cost_to_go` writes (6 significant digits)."""
    import numpy as np

    _, S = robot_lqr.lqr(stem)
    R = np.array([[float(f"{S[i, j] * (1 if i == j else 2):.6g}") / (1 if i == j else 2) for j in range(len(S))]
                  for i in range(len(S))])
    return np.triu(R) + np.triu(R, 1).T


def drake_levels(runs: list[Run], examples: list[tuple[str, str, int, bool]]) -> None:
    """Issue 42's Drake levels of ``z' S z`` (``drake_level_check.DRAKE_TAYLOR_LEVELS``, from the cubic Taylor
    model): the share of the [domain] box inside each, whether it is valid on the true loop (a point with
    ``V' > 0`` below it, confirmed by ball arithmetic) and the share of the box in lyapcheck's certified roa."""
    rows = [(label, stem) for label, stem, _, lqr in examples if lqr and stem in drake_level_check.DRAKE_TAYLOR_LEVELS]
    if not rows:
        return
    print("Drake's Taylor-model level of z' S z (issue 42's anchor) on the true loop:")
    for label, stem in rows:
        level = drake_level_check.DRAKE_TAYLOR_LEVELS[stem]
        S = rounded_cost_to_go(stem)
        share = drake_level_check.box_share(stem, S, level)
        found = drake_level_check.decrease_counterexample(stem, S)
        if found is None:
            valid = "no point with V' >= 0 found below it (not shown invalid)"
        elif found["V"] < level:
            valid = (f"NOT valid: V' in [{found['V_dot_ball'][0]:.4g}, {found['V_dot_ball'][1]:.4g}] > 0 (ball arithmetic) "
                     f"at z = ({', '.join(f'{float(Fraction(x)):.6g}' for x in found['point'])}), V = {float(found['V']):.4g}")
        else:
            valid = f"the lowest point found with V' > 0 has V = {float(found['V']):.4g} (above the level)"
        mine = next((r for r in runs if r.label == label and r.klass == "roa"), None)
        ours = None if mine is None else box_share(mine.condition(), stem)
        print(f"  {label:<17} level {level:g}: {100 * share:.3g} % of the box; {valid}; lyapcheck's certified roa: "
              f"{box_text(ours)} of the box")
    print()


def drake_comparison(drake_python: str, runs: list[Run], examples: list[tuple[str, str, int, bool]]) -> None:
    """Drake 1.51's ``RegionOfAttraction`` on the cubic Taylor model of each LQR example, V = z' S z, and
    the share of the same simulated starts (true loop) inside each tool's set {z' S z <= level}."""
    import numpy as np

    print("Drake's RegionOfAttraction on the cubic Taylor model (floating point, for the Taylor model only), "
          "V = z' S z as lyapcheck's candidate:")
    head = (f"  {'example':<17} {'Drake level':>11} {'Drake s':>8} {'Drake share':>11} {'non-conv. in':>12}  "
            f"{'lyapcheck level':>15} {'lyapcheck s':>11} {'lyapcheck share':>15}")
    print(head)
    for label, stem, _, lqr in examples:
        if not lqr:
            continue
        S = rounded_cost_to_go(stem)
        states = list(robot_lqr.PLANTS[stem].states)
        payload = json.dumps({"states": states, "field": robot_lqr.taylor_terms(stem), "S": S.tolist()})
        t0 = time.perf_counter()
        try:
            done = subprocess.run([drake_python, str(Path(__file__).with_name("drake_taylor_roa.py"))],
                                  input=payload, capture_output=True, text=True, timeout=DRAKE_TIMEOUT_S)
        except subprocess.TimeoutExpired:
            print(f"  {label:<17} Drake gave no level within {DRAKE_TIMEOUT_S:g} s (stopped)", flush=True)
            continue
        try:
            drake = json.loads(done.stdout)
        except json.JSONDecodeError:
            print(f"  {label:<17} Drake gave no level (exit {done.returncode}): {done.stderr.strip()[-300:]}")
            continue
        drake_wall = time.perf_counter() - t0
        starts, converged = converged_starts(stem)
        V = np.einsum("ni,ij,nj->n", starts, S, starts)
        mine = next((r for r in runs if r.label == label and r.klass == "candidate"), None)
        level = float(mine.condition().get("level") or 0) if mine and mine.condition().get("status") == "certified" \
            else None

        def share(c: float | None) -> str:
            return "-" if c is None else f"{100 * np.mean(V[converged] <= c):.1f} %"

        bad = int(np.sum((V <= drake["level"]) & ~converged))
        print(f"  {label:<17} {drake['level']:11.4g} {drake_wall:8.1f} {share(drake['level']):>11} {bad:>12}  "
              f"{'-' if level is None else format(level, '.4g'):>15} "
              f"{'-' if mine is None else format(mine.wall, '.1f'):>11} {share(level):>15}", flush=True)
    print(f"  (shares: of {COMPARE_SAMPLES} uniform starts in the [domain] box, those that converge on the true loop "
          f"(RK4, {COMPARE_HORIZON_S:g} s), the share inside each set; 'non-conv. in': starts in Drake's set that do "
          "not converge on the true loop; times: Drake's whole process, imports included, run after lyapcheck's)\n")


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--only", nargs="+", metavar="NAME",
                        help="labels or file stems (e.g. cart-pole, robot-acrobot-lqr)")
    parser.add_argument("--time-limit", type=float, default=60.0, metavar="S",
                        help="each class's time limit in seconds, passed to certify (default 60, certify's own)")
    parser.add_argument("--drake-python", metavar="PYTHON",
                        help="a Python with pydrake (pip install drake==1.51.1): also run Drake's region of "
                             "attraction on each LQR example's cubic Taylor model and compare the shares")
    args = parser.parse_args()
    if args.time_limit <= 0:
        parser.error(f"--time-limit must be a number of seconds > 0, got {args.time_limit:g}")
    examples = [e for e in EXAMPLES if not args.only or e[0] in args.only or e[1] in args.only]
    if not examples:
        parser.error(f"no example matches --only {' '.join(args.only)} (examples: "
                     f"{', '.join(e[0] for e in EXAMPLES)})")

    print(f"lyapcheck: {lyapcheck('--version', timeout=120).stdout.strip() or '(no --version)'}, imported from "
          f"{imported_lyapcheck()}")
    print(f"machine: {os.cpu_count()} cores, load average {os.getloadavg()[0]:.2f} at start; "
          f"--time-limit {args.time_limit:g} s per class\n")
    head = (f"{'example':<17} {'states':>6}  {'class':<9}  {'status':<13} {'time s':>7}  {'share of sim. ROA':>17}  "
            f"{'share of box':>12}  {'level':>9}  {'ball radius':>11}  V kept")
    print(head)
    print("-" * len(head))
    runs: list[Run] = []
    for label, stem, states, lqr in examples:
        plan: list[tuple[str, list[str]]] = [("roa", [])]
        if lqr:
            plan.append(("candidate", ["--candidate", robot_lqr.cost_to_go(stem)]))
        for klass, extra in plan:
            r = run(label, stem, states, klass, extra, args.time_limit)
            runs.append(r)
            cond = r.condition()
            status = cond.get("status", f"exit {r.exit}" if r.doc is None else "absent")
            v_from = str(cond.get("V_from", "-"))
            kept = "shaped" if "shaped" in v_from else "linearization" if v_from.startswith("the linearization") \
                else v_from.split(" (")[0].split(",")[0]
            print(f"{label:<17} {states:>6}  {klass:<9}  {status:<13} {r.wall:7.1f}  {share_text(cond):>17}  "
                  f"{box_text(box_share(cond, stem)):>12}  {figure(cond, 'level', '.4g'):>9}  {ball_text(cond):>11}  "
                  f"{kept[:30]}", flush=True)
    print("(time: the whole certify process with --classes linearization,CLASS, imports included; share: roa_share, "
          "the share of lyapcheck's simulated region of attraction in the [domain] box inside the certified set; share "
          f"of box: of {BOX_SAMPLES} uniform points of the [domain] box)\n")
    drake_levels(runs, examples)

    if args.drake_python:
        drake_comparison(args.drake_python, runs, examples)

    print(f"Targets of issue 42 (a certified region of attraction on the true loop in < {TARGET_SECONDS:g} s, "
          f"covering >= {100 * TARGET_SHARE:g} % of the simulated region):")
    for label, *_ in examples:
        mine = [r for r in runs if r.label == label]
        met = [r for r in mine if r.condition().get("status") == "certified" and r.wall < TARGET_SECONDS
               and float(r.condition().get("roa_share") or 0) >= TARGET_SHARE]
        lin = {r.doc["conditions"].get("linearization", {}).get("status") for r in mine if r.doc is not None}
        best = max((float(r.condition().get("roa_share") or 0) for r in mine
                    if r.condition().get("status") == "certified"), default=None)
        print(f"  {label:<17} linearization {', '.join(sorted(s for s in lin if s)) or '-'}; "
              f"best certified share {'-' if best is None else f'{100 * best:.1f} %'}: "
              f"{'target met' if met else 'target missed'}")
    print()

    print("Classes that did not certify, with their summaries:")
    problems = 0
    for r in runs:
        cond = r.condition()
        if r.doc is None:
            problems += 1
            print(f"  {r.label} {r.klass}: EXIT {r.exit}, no JSON. Command: {' '.join(r.command)}\n    {r.error}")
        elif cond.get("status") != "certified":
            summary = str(cond.get("summary", "(no summary)"))
            print(f"  {r.label} {r.klass} ({cond.get('status')}): {summary[:400]}{'...' if len(summary) > 400 else ''}")
            if cond.get("reason"):  # the technical detail (--verbose's)
                print(f"    reason: {str(cond['reason'])[:400]}")
    if all(r.doc is not None and r.condition().get("status") == "certified" for r in runs):
        print("  (none)")
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
