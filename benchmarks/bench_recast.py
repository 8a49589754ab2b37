"""The non-polynomial example loops (``examples/models/recast-*.toml``): statuses, wall times, and an
independent simulation check of every certified set.

For each example it runs ``lyapcheck certify FILE --json`` (and ``--candidate`` where one is
listed) in a fresh process and times the whole process (imports included), then ``lyapcheck verify``
on the document it printed. It prints one row per run: each class's status (``C`` certified, ``R``
refuted, ``n`` not_certified, ``-`` not_applicable, ``?`` inconclusive, blank not run), the wall
time and the verify result.

Then, OUTSIDE lyapcheck's recasting (this file does not import ``lyapcheck`` at all), it checks
every certified ``sos_gas`` and ``roa`` (and ``candidate``) claim by simulating the TRUE field:

* the model file's ``[dynamics]`` strings and the certificate's auxiliary definitions are
  evaluated with numpy through a small ``ast`` whitelist (names, numbers, ``+ - * / **``, unary
  ``-``/``+``, calls to ``sin cos exp sqrt atan tanh abs min max sat``, the constant ``pi``);
* ``V`` is rebuilt from ``certificate.variables``, ``certificate.auxiliaries``,
  ``certificate.shift`` and ``certificate.V`` (a polynomial in ``v - shift[v]``; the constant roots
  ``rt2``, ``rt3`` are sqrt(2), sqrt(3) and not shifted);
* points are sampled in the model's ``[domain]`` box (``+-3`` around the equilibrium per state
  without one) and in the box twice as wide; those with ``V <= level`` (``roa``, ``candidate``;
  within the certificate's ``box`` for a region proved by ball arithmetic) or
  all of them (``sos_gas``) are integrated with RK4 (dt 0.01 s, 60 s) and each must end within
  ``1e-2`` of the equilibrium (modulo 2 pi in the angles the claim's summary names). Any failure is
  printed as a SOUNDNESS VIOLATION.

Last, the targets of the examples, with the figures measured in this run:

* ILOS course form: ``sos_gas`` certified (GAS exactly);
* damped pendulum: share of the ``[domain]`` box inside the certified ``roa`` set against the
  share inside the energy set ``{1 - cos(theta) + omega**2/2 < 2}`` (target: larger);
* two-machine power system: share of the simulated region of attraction (grid points of the
  ``[domain]`` box whose trajectory converges to the origin itself, not modulo 2 pi) inside the
  certified set, and the wall time, beside LyZNet's published figures (target: >= 82.3 % in < 10 s);
* lossless and unstable loops: no asymptotic claim (``sos_gas``, ``roa``, ``candidate`` not
  certified).

A certified ``sos_bound`` (the disturbed examples) is simulated too: starts in the box twice the
``[domain]``'s, each disturbance a bang-bang signal against the output's sign or a square wave at its
bound, and the largest ``|y|`` after 150 s must stay within the certified bound. A run with ``--box``
is simulated at every corner of its box (the claim holds for every value).

A missed target prints "target missed"; the script exits 1 only on a SOUNDNESS VIOLATION (or an
example that does not run at all).

Run:  python benchmarks/bench_recast.py [--only NAME ...] [--samples N] [--grid N]
The lyapcheck that runs is the one ``python -m lyapcheck`` imports from a scratch directory (the
editable install, or the checkout ``PYTHONPATH`` names); the first line printed says which.
"""

from __future__ import annotations

import argparse
import ast
import json
import math
import os
import re
import subprocess
import sys
import tempfile
import time
import tomllib
from fractions import Fraction
from pathlib import Path
from typing import Any, Callable

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
MODELS = ROOT / "examples" / "models"

#: (label, model file stem, extra certify arguments)
RUNS: list[tuple[str, str, list[str]]] = [
    ("pendulum", "recast-pendulum", []),
    ("pendulum+energy", "recast-pendulum", ["--candidate", "1 - cos(theta) + omega**2/2"]),
    ("lossless", "recast-lossless-pendulum", []),
    ("lossless+energy", "recast-lossless-pendulum",
     ["--candidate", "x2**2/2 + 10*(1 - cos(x1)) - sin(x1)**2/2"]),
    ("ilos-course", "recast-ilos-course", []),
    ("los-heading", "recast-los-heading", []),
    ("sat-double-int", "recast-saturated-double-integrator", []),
    ("inv-pendulum-sat", "recast-inverted-pendulum-sat", []),
    ("tanh-neuron", "recast-tanh-neuron", []),
    ("power-2machine", "recast-power-two-machine", []),
    ("pendulum-actuator", "recast-pendulum-actuator", []),
    ("unstable", "recast-unstable-pendulum", []),
    ("ilos-disturbed", "recast-ilos-course-disturbed", []),
    ("pendulum-torque", "recast-pendulum-torque", []),
    ("ilos-box", "recast-ilos-course", ["--box", "kappa=0.4..0.6"]),
    ("pendulum-box", "recast-pendulum", ["--box", "b=0.5..2", "--classes", "sos_gas,roa"]),
]
CLASSES = ("linearization", "quadratic", "sos_gas", "roa", "candidate", "sos_bound")
HEAD = {"linearization": "lin", "quadratic": "quad", "sos_gas": "gas", "roa": "roa", "candidate": "cand",
        "sos_bound": "bnd"}
SHORT = {"certified": "C", "refuted": "R", "not_certified": "n", "not_applicable": "-", "inconclusive": "?"}
ASYMPTOTIC = ("quadratic", "sos_gas", "roa", "candidate")
#: LyZNet's published figures for the two-machine power system (the target is the neural V's)
LYZNET_POWER = {"sos_share": 18.5, "neural_share": 82.3, "dreal_s": 3375.0, "training_s": 473.0}

DT, T_END, TOL = 0.01, 60.0, 1e-2


# -- a small evaluator, independent of lyapcheck -----------------------------------------------------------
def _sat(u: Any, limit: Any) -> Any:
    return np.clip(u, -limit, limit)


FUNCS: dict[str, Callable[..., Any]] = {"sin": np.sin, "cos": np.cos, "exp": np.exp, "sqrt": np.sqrt,
                                        "atan": np.arctan, "tanh": np.tanh, "abs": np.abs, "min": np.minimum,
                                        "max": np.maximum, "sat": _sat}
ARITY = {"sin": 1, "cos": 1, "exp": 1, "sqrt": 1, "atan": 1, "tanh": 1, "abs": 1, "min": 2, "max": 2, "sat": 2}


class Expr:
    """An expression of the model language, checked node by node, evaluated with numpy."""

    def __init__(self, text: str):
        self.text = text
        self.tree = ast.parse(text.strip(), mode="eval").body
        self._check(self.tree)

    def _check(self, node: ast.AST) -> None:
        if isinstance(node, ast.Constant):
            if isinstance(node.value, bool) or not isinstance(node.value, (int, float)):
                raise ValueError(f"{self.text!r}: not a number: {ast.dump(node)}")
        elif isinstance(node, ast.Name):
            pass
        elif isinstance(node, ast.BinOp):
            if not isinstance(node.op, (ast.Add, ast.Sub, ast.Mult, ast.Div, ast.Pow)):
                raise ValueError(f"{self.text!r}: operator {type(node.op).__name__} is not allowed")
            self._check(node.left)
            self._check(node.right)
        elif isinstance(node, ast.UnaryOp):
            if not isinstance(node.op, (ast.USub, ast.UAdd)):
                raise ValueError(f"{self.text!r}: unary {type(node.op).__name__} is not allowed")
            self._check(node.operand)
        elif isinstance(node, ast.Call):
            if not isinstance(node.func, ast.Name) or node.func.id not in FUNCS or node.keywords:
                raise ValueError(f"{self.text!r}: call {ast.dump(node.func)} is not allowed")
            if len(node.args) != ARITY[node.func.id]:
                raise ValueError(f"{self.text!r}: {node.func.id} takes {ARITY[node.func.id]} arguments")
            for a in node.args:
                self._check(a)
        else:
            raise ValueError(f"{self.text!r}: {type(node).__name__} is not part of the language")

    def __call__(self, names: dict[str, Any]) -> Any:
        return self._eval(self.tree, names)

    def _eval(self, node: ast.AST, names: dict[str, Any]) -> Any:
        if isinstance(node, ast.Constant):
            assert isinstance(node.value, (int, float))  # checked by _check
            return float(node.value)
        if isinstance(node, ast.Name):
            if node.id in names:
                return names[node.id]
            if node.id == "pi":
                return math.pi
            raise ValueError(f"{self.text!r}: unknown name {node.id!r}")
        if isinstance(node, ast.UnaryOp):
            v = self._eval(node.operand, names)
            return -v if isinstance(node.op, ast.USub) else v
        if isinstance(node, ast.BinOp):
            a, b = self._eval(node.left, names), self._eval(node.right, names)
            if isinstance(node.op, ast.Add):
                return a + b
            if isinstance(node.op, ast.Sub):
                return a - b
            if isinstance(node.op, ast.Mult):
                return a * b
            if isinstance(node.op, ast.Div):
                return a / b
            return a ** b
        assert isinstance(node, ast.Call) and isinstance(node.func, ast.Name)
        return FUNCS[node.func.id](*(self._eval(a, names) for a in node.args))


class Model:
    """A model file read with tomllib: states, parameters, the true field, equilibrium, domain."""

    def __init__(self, path: Path):
        data = tomllib.loads(path.read_text(encoding="utf-8"))
        self.path = path
        self.states: list[str] = list(data["model"]["states"])
        self.params = {k: float(v) for k, v in data.get("parameters", {}).items()}
        self.rhs = [Expr(str(data["dynamics"][s])) for s in self.states]
        eq = data.get("equilibrium", {})
        self.eq = np.array([float(eq.get(s, 0)) for s in self.states])
        dom = data.get("domain")
        self.domain = (np.array([[float(dom[s][0]), float(dom[s][1])] for s in self.states]) if dom
                       else np.stack([self.eq - 3, self.eq + 3], axis=1))
        self.has_domain = dom is not None
        #: the disturbances' bounds; a simulation holds them at 0 unless it is given a signal
        self.dists = {k: float(v) for k, v in data.get("disturbances", {}).items()}
        outputs = data.get("outputs") or {s: s for s in self.states}
        self.outputs = {k: Expr(str(v)) for k, v in outputs.items()}

    def at(self, **params: float) -> "Model":
        """The same model with some parameters set (a box's corner)."""
        other = Model.__new__(Model)
        other.__dict__.update(self.__dict__)
        other.params = {**self.params, **params}
        return other

    def names(self, X: np.ndarray, d: dict[str, Any] | None = None) -> dict[str, Any]:
        out: dict[str, Any] = dict(self.params)
        out.update({k: 0.0 for k in self.dists})
        out.update(d or {})
        out.update({s: X[:, i] for i, s in enumerate(self.states)})
        return out

    def field(self, X: np.ndarray, d: dict[str, Any] | None = None) -> np.ndarray:
        names = self.names(X, d)
        return np.stack([np.broadcast_to(np.asarray(e(names), dtype=float), (len(X),)) for e in self.rhs], axis=1)

    def simulate(self, X0: np.ndarray, t_end: float = T_END, dt: float = DT,
                 signal: Callable[[np.ndarray, float], dict[str, Any]] | None = None,
                 tail: Callable[[np.ndarray], None] | None = None, tail_from: float = 0.0) -> np.ndarray:
        """RK4 on the true field; a state that blows up is frozen at nan (it does not converge).
        ``signal(X, t)``: the disturbances' values (held over each step); ``tail(X)`` is called at
        every step from ``tail_from`` on."""
        X = np.array(X0, dtype=float)
        with np.errstate(all="ignore"):
            for k in range(int(round(t_end / dt))):
                d = signal(X, k * dt) if signal is not None else None
                k1 = self.field(X, d)
                k2 = self.field(X + dt / 2 * k1, d)
                k3 = self.field(X + dt / 2 * k2, d)
                k4 = self.field(X + dt * k3, d)
                X = X + dt / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
                X[~np.isfinite(X).all(axis=1) | (np.abs(X) > 1e6).any(axis=1)] = np.nan
                if tail is not None and k * dt >= tail_from:
                    tail(X)
        return X

    def converged(self, X: np.ndarray, angles: tuple[str, ...] = ()) -> np.ndarray:
        d = X - self.eq
        for a in angles:
            i = self.states.index(a)
            d[:, i] = np.mod(d[:, i] + math.pi, 2 * math.pi) - math.pi
        return np.isfinite(d).all(axis=1) & (np.linalg.norm(np.nan_to_num(d, nan=1e9), axis=1) < TOL)


class Lyapunov:
    """V of a certified condition, from the certificate's variables, auxiliaries, shift and terms."""

    def __init__(self, model: Model, cert: dict[str, Any]):
        self.model = model
        self.variables: list[str] = list(cert["variables"])
        self.aux = {k: Expr(v) for k, v in cert.get("auxiliaries", {}).items()}
        shift = cert.get("shift", {})
        self.shift = {v: (None if shift.get(v) is None else float(Fraction(shift[v]))) for v in self.variables}
        self.terms = [(float(Fraction(c)), list(e)) for c, e in cert["V"]["terms"]]
        self.level = float(Fraction(cert["level"])) if cert.get("level") is not None else None
        # a ball-arithmetic region ("kind" interval) is the set within its box of state deviations
        self.box = None
        if isinstance(cert.get("box"), dict):
            eq = [float(Fraction(shift.get(s, "0"))) for s in model.states]
            self.box = (np.array([float(Fraction(cert["box"][s][0])) for s in model.states]) + eq,
                        np.array([float(Fraction(cert["box"][s][1])) for s in model.states]) + eq)

    def members(self, X: np.ndarray) -> np.ndarray:
        """The starts inside the certified set: ``V <= level`` (and within the box, where there is one)."""
        with np.errstate(all="ignore"):
            v = self(X)
        keep = np.isfinite(v) & (v <= (self.level if self.level is not None else -np.inf))
        if self.box is not None:
            keep &= np.all((X >= self.box[0]) & (X <= self.box[1]), axis=1)
        return keep

    def columns(self, X: np.ndarray) -> list[np.ndarray]:
        names = self.model.names(X)
        cols = []
        for v in self.variables:
            col: Any
            if v in self.model.states:
                col = X[:, self.model.states.index(v)]
            elif v in self.aux:
                col = self.aux[v](names)
            elif v in ("rt2", "rt3"):
                col = math.sqrt(int(v[2:]))
            elif v in self.model.params or v in self.model.dists:  # a box's parameter (a constant of the loop)
                col = names[v]
            else:
                raise ValueError(f"V's variable {v!r} is neither a state nor an auxiliary")
            col = np.broadcast_to(np.asarray(col, dtype=float), (len(X),))
            s = self.shift.get(v)
            cols.append(col - s if s is not None and v not in ("rt2", "rt3") else col)
        return cols

    def __call__(self, X: np.ndarray) -> np.ndarray:
        cols = self.columns(X)
        out = np.zeros(len(X))
        for c, e in self.terms:
            term = np.full(len(X), c)
            for col, k in zip(cols, e):
                if k:
                    term = term * col ** k
            out += term
        return out


def angles_of(summary: str, states: list[str]) -> tuple[str, ...]:
    m = re.search(r"modulo 2 pi in ([A-Za-z_][\w, ]*?)(?:\s*\(|:|;|$)", summary)
    if not m:
        return ()
    return tuple(n.strip() for n in m.group(1).split(",") if n.strip() in states)


# -- running lyapcheck ----------------------------------------------------------------------------------
def lyapcheck(*args: str) -> subprocess.CompletedProcess[str]:
    """``python -m lyapcheck ARGS`` run from a scratch directory: ``-m`` puts the working directory first
    on the path, so running from ROOT would import ROOT's checkout whatever PYTHONPATH says."""
    with tempfile.TemporaryDirectory(prefix="bench-recast-") as cwd:
        return subprocess.run([sys.executable, "-m", "lyapcheck", *args], capture_output=True, text=True,
                              cwd=cwd, timeout=1800)


def imported_lyapcheck() -> str:
    with tempfile.TemporaryDirectory(prefix="bench-recast-") as cwd:
        done = subprocess.run([sys.executable, "-c", "import lyapcheck; print(lyapcheck.__file__)"],
                              capture_output=True, text=True, cwd=cwd, timeout=120)
    return done.stdout.strip() or done.stderr.strip()[-200:]


def certify(stem: str, extra: list[str]) -> dict[str, Any]:
    path = MODELS / f"{stem}.toml"
    t0 = time.perf_counter()
    done = lyapcheck("certify", str(path), "--json", *extra)
    wall = time.perf_counter() - t0
    try:
        doc = json.loads(done.stdout)
    except json.JSONDecodeError:
        return {"error": f"exit {done.returncode}: {done.stderr.strip()[-400:] or done.stdout[-400:]}", "wall": wall}
    with tempfile.NamedTemporaryFile("w", suffix=".json", delete=False) as fh:
        json.dump(doc, fh)
    try:
        ver = lyapcheck("verify", fh.name)
    finally:
        os.unlink(fh.name)
    fails = [line for line in ver.stdout.splitlines() if line.startswith("FAIL")]
    return {"doc": doc, "wall": wall, "exit": done.returncode, "verify_exit": ver.returncode, "verify_fails": fails}


# -- the checks ---------------------------------------------------------------------------------------
def sample(model: Model, n: int, rng: np.random.Generator) -> np.ndarray:
    lo, hi = model.domain[:, 0], model.domain[:, 1]
    mid, half = (lo + hi) / 2, (hi - lo) / 2
    inner = rng.uniform(lo, hi, (n, len(lo)))
    outer = rng.uniform(mid - 2 * half, mid + 2 * half, (n, len(lo)))
    return np.concatenate([inner, outer])


def grid(model: Model, n: int) -> np.ndarray:
    axes = [np.linspace(lo, hi, n) for lo, hi in model.domain]
    mesh = np.meshgrid(*axes, indexing="ij")
    return np.stack([m.ravel() for m in mesh], axis=1)


def soundness(label: str, model: Model, doc: dict[str, Any], n: int, rng: np.random.Generator) -> tuple[int, list[str]]:
    """Simulate sampled starts inside each certified set; returns (violations, lines)."""
    lines, bad = [], 0
    for name in ASYMPTOTIC:
        cond = doc["conditions"].get(name)
        if not cond or cond.get("status") != "certified":
            continue
        cert = cond["certificate"]
        V = Lyapunov(model, cert)
        angles = angles_of(cond.get("summary", ""), model.states)
        X = sample(model, n, rng)
        with np.errstate(all="ignore"):
            v = V(X)
        if cert.get("level") is None:  # quadratic, sos_gas, a candidate's global claim
            keep = np.isfinite(v)
            what = "all sampled starts (GAS)"
        else:
            keep = V.members(X)
            what = f"starts with V <= {V.level:.6g}" + (" in the certificate's box" if V.box is not None else "")
            if cert.get("whole"):
                what += " (the whole set: the box is the proof's)"
        starts = X[keep]
        if len(starts) == 0:
            lines.append(f"  {label} {name}: no sampled start in the certified set (nothing to check)")
            continue
        end = model.simulate(starts)
        ok = model.converged(end, angles)
        fails = int((~ok).sum())
        mod = f", modulo 2 pi in {', '.join(angles)}" if angles else ""
        lines.append(f"  {label} {name}: {len(starts)} {what}{mod}: {fails} fail to converge")
        if fails:
            bad += fails
            for x0 in starts[~ok][:5]:
                lines.append(f"    SOUNDNESS VIOLATION: {label} {name}: start {np.round(x0, 5).tolist()} "
                             f"(V = {float(V(x0[None])[0]):.6g}) does not converge in {T_END:g} s")
    return bad, lines


def box_corners(extra: list[str]) -> list[dict[str, float]]:
    """The corners of a run's ``--box`` arguments (one empty corner without a box)."""
    from itertools import product

    ranges = []
    for flag, value in zip(extra, extra[1:]):
        if flag == "--box":
            name, _, interval = value.partition("=")
            lo, _, hi = interval.partition("..")
            ranges.append([(name, float(lo)), (name, float(hi))])
    return [dict(c) for c in product(*ranges)] if ranges else [{}]


#: the disturbance signals an ultimate bound is simulated under: bang-bang against an output's sign
#: and square waves of several periods (each value at a bound)
BOUND_PERIODS = (0.5, 2.0, 6.0, 20.0)
BOUND_T_END, BOUND_TAIL = 300.0, 150.0


def bound_check(label: str, model: Model, doc: dict[str, Any], n: int, rng: np.random.Generator
                ) -> tuple[int, list[str]]:
    """A certified ``sos_bound``: starts in the box twice the [domain]'s, each disturbance a bang-bang or
    square-wave signal at its bound; the largest ``|y|`` after BOUND_TAIL s must stay within the bound."""
    cond = doc["conditions"].get("sos_bound")
    if not cond or cond.get("status") != "certified":
        return 0, []
    lines, bad = [], 0
    X0 = sample(model, n // 10, rng)
    for name, bound in cond["bounds"].items():
        y = model.outputs[name]
        worst = 0.0

        def track(X: np.ndarray) -> None:
            nonlocal worst
            values = np.abs(np.broadcast_to(np.asarray(y(model.names(X)), dtype=float), (len(X),)))
            worst = max(worst, float(np.nanmax(values)))

        policies: list[Callable[[np.ndarray, float], dict[str, Any]]] = [
            lambda X, t: {d: b * np.sign(np.broadcast_to(np.asarray(y(model.names(X)), dtype=float), (len(X),))
                                         + 1e-12) for d, b in model.dists.items()}]
        policies += [lambda X, t, T=T: {d: b * np.sign(np.sin(2 * math.pi * t / T) + 1e-12)
                                        for d, b in model.dists.items()} for T in BOUND_PERIODS]
        for policy in policies:
            model.simulate(X0, BOUND_T_END, 0.02, signal=policy, tail=track, tail_from=BOUND_TAIL)
        ok = worst <= bound
        bad += 0 if ok else 1
        lines.append(f"  {label} sos_bound: limsup |{name}| <= {bound:.4g} certified; simulated tail sup {worst:.4g} "
                     f"({len(X0)} starts, {len(policies)} disturbance signals, {BOUND_T_END:g} s)"
                     + ("" if ok else "  SOUNDNESS VIOLATION"))
    return bad, lines


def status(doc: dict[str, Any] | None, name: str) -> str:
    if not doc:
        return "!"
    cond = doc["conditions"].get(name)
    return SHORT.get(cond["status"], cond["status"]) if cond else ""


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--only", nargs="+", metavar="NAME",
                        help="labels or file stems (e.g. pendulum, recast-power-two-machine)")
    parser.add_argument("--samples", type=int, default=1500, help="random starts per box (default 1500)")
    parser.add_argument("--grid", type=int, default=100, help="grid points per axis for the shares (default 100)")
    args = parser.parse_args()
    runs = [r for r in RUNS if not args.only or r[0] in args.only or r[1] in args.only]
    if not runs:
        print("no example matches --only", args.only)
        return 2

    print(f"lyapcheck: {lyapcheck('--version').stdout.strip() or '(no --version)'}, imported from "
          f"{imported_lyapcheck()}")
    print(f"machine: {os.cpu_count()} cores, load average {os.getloadavg()[0]:.2f} at start\n")
    results: dict[str, dict[str, Any]] = {}
    print(f"{'model':<18} " + " ".join(f"{HEAD[c]:>4}" for c in CLASSES) + f" {'wall s':>7}  verify  verdict")
    for label, stem, extra in runs:
        r = certify(stem, extra)
        results[label] = r
        doc = r.get("doc")
        cells = " ".join(f"{status(doc, c):>4}" for c in CLASSES)
        if doc is None:
            print(f"{label:<18} {cells} {r['wall']:7.2f}  ERROR  {r['error']}")
            continue
        ver = "ok" if r["verify_exit"] == 0 else "FAIL"
        print(f"{label:<18} {cells} {r['wall']:7.2f}  {ver:<6}  {doc.get('verdict')}")
        for line in r["verify_fails"]:
            print(f"{'':<18}   verify: {line}")
    print("(C certified, R refuted, n not_certified, - not_applicable, ? inconclusive, blank not run; wall: the "
          "whole certify process, imports included)\n")

    print(f"Simulation of the true field (RK4, dt {DT}, {T_END:g} s, converged: within {TOL} of the equilibrium), "
          f"{args.samples} starts in the [domain] box and {args.samples} in the box twice as wide:")
    rng = np.random.default_rng(20240531)
    violations = 0
    for label, stem, extra in runs:
        doc = results[label].get("doc")
        if doc is None:
            continue
        for corner in box_corners(extra):  # a claim over a box holds at its corners
            model = Model(MODELS / f"{stem}.toml").at(**corner)
            tag = label + ("" if not corner else " at " + ", ".join(f"{k} = {v:g}" for k, v in corner.items()))
            bad, lines = soundness(tag, model, doc, args.samples, rng)
            more, bound_lines = bound_check(tag, model, doc, args.samples, rng)
            violations += bad + more
            for line in lines + bound_lines:
                print(line)
    print()

    print("Targets (figures measured in this run):")
    errors = sum(1 for r in results.values() if r.get("doc") is None)
    if "ilos-course" in results and results["ilos-course"].get("doc"):
        gas = results["ilos-course"]["doc"]["conditions"].get("sos_gas", {}).get("status")
        print(f"  ILOS course form: sos_gas {gas} in {results['ilos-course']['wall']:.2f} s (target: GAS certified): "
              f"{'target met' if gas == 'certified' else 'target missed'}")
    if "pendulum" in results and results["pendulum"].get("doc"):
        model = Model(MODELS / "recast-pendulum.toml")
        G = grid(model, 2 * args.grid)
        th, om = G[:, 0], G[:, 1]
        energy = float(np.mean(1 - np.cos(th) + om ** 2 / 2 < 2))
        cond = results["pendulum"]["doc"]["conditions"].get("roa", {})
        if cond.get("status") == "certified":
            V = Lyapunov(model, cond["certificate"])
            share = float(np.mean(V.members(G)))
            verdict = "target met" if share > energy else "target missed"
            print(f"  damped pendulum: certified roa set covers {100 * share:.1f} % of the [domain] box, the energy "
                  f"set {{1 - cos(theta) + omega**2/2 < 2}} {100 * energy:.1f} % (ratio {share / energy:.2f}; "
                  f"{2 * args.grid}x{2 * args.grid} grid; target: larger): {verdict}")
        else:
            print(f"  damped pendulum: roa {cond.get('status')}; the energy set covers {100 * energy:.1f} % of the "
                  f"box: target missed")
    if "power-2machine" in results and results["power-2machine"].get("doc"):
        model = Model(MODELS / "recast-power-two-machine.toml")
        G = grid(model, args.grid)
        t0 = time.perf_counter()
        roa = model.converged(model.simulate(G))  # the origin itself, not modulo 2 pi
        sim_s = time.perf_counter() - t0
        r = results["power-2machine"]
        cond = r["doc"]["conditions"].get("roa", {})
        line = (f"  power system: simulated region of attraction {100 * roa.mean():.1f} % of the [domain] box "
                f"({args.grid}x{args.grid} grid, {sim_s:.1f} s to simulate); ")
        if cond.get("status") == "certified":
            V = Lyapunov(model, cond["certificate"])
            inside = V.members(G)
            covered = float((inside & roa).sum() / max(roa.sum(), 1))
            stray = int((inside & ~roa).sum())
            share_ok = 100 * covered >= LYZNET_POWER["neural_share"]
            time_ok = r["wall"] < 10
            note = (f" ({stray} grid points of the set do not reach the origin itself; the claim is modulo 2 pi)"
                    if stray else "")
            line += (f"certified set covers {100 * covered:.1f} % of it in {r['wall']:.2f} s wall{note}; "
                     f"LyZNet (published): SOS V {LYZNET_POWER['sos_share']} %, neural V "
                     f"{LYZNET_POWER['neural_share']} % (dReal check {LYZNET_POWER['dreal_s']:,.0f} s, training "
                     f"{LYZNET_POWER['training_s']:.0f} s); target >= {LYZNET_POWER['neural_share']} % in < 10 s: ")
            line += ("target met" if share_ok and time_ok else
                     f"target missed (share {'ok' if share_ok else 'short'}, time {'ok' if time_ok else 'over'})")
        else:
            line += f"roa {cond.get('status')}: target missed"
        print(line)
    for label in ("lossless", "lossless+energy", "unstable"):
        if label in results and results[label].get("doc"):
            conds = results[label]["doc"]["conditions"]
            claimed = [n for n in ASYMPTOTIC if conds.get(n, {}).get("status") == "certified"]
            ran = ", ".join(f"{n} {conds[n]['status']}" for n in ASYMPTOTIC if n in conds)
            if claimed:
                violations += 1
                print(f"  {label}: SOUNDNESS VIOLATION: asymptotic claim certified ({', '.join(claimed)})")
            else:
                print(f"  {label}: no asymptotic claim ({ran}; target: none): target met")
    if violations:
        print(f"\n{violations} SOUNDNESS VIOLATION(S)")
    print(f"\nload average {os.getloadavg()[0]:.2f} at the end")
    return 1 if violations or errors else 0


if __name__ == "__main__":
    sys.exit(main())
