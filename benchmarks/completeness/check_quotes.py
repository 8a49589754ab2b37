"""Check every claim the completeness suite quotes, independently of the benchmark's verdicts.

For each positive of ``index.toml``:

* the quoted ``V`` and its derivative ``V' = grad(V) . f`` are computed with sympy, in exact
  rationals (decimals of the model files are read as the fractions they spell);
* a sufficient proof that ``V`` is a global Lyapunov function: lyapcheck's own ``candidate`` class
  (``lyapcheck certify FILE --classes candidate --candidate "V" --json``), which proves ``V``
  positive definite and radially unbounded and ``-V'`` positive away from 0 by an exact SOS check;
* linear systems (``v_rule = "lyapunov_equation"``): ``P`` solved exactly from
  ``A^T P + P A = -I`` and proved positive definite by its leading principal minors (then
  ``V' = -|x|^2`` is an identity); the candidate class runs too when the text fits its length limit;
* ``v_rule = "nonpolynomial"`` (Ahmadi, Krstic, Parrilo's system): the identity
  ``-V' = 2 (y - u/2)^2 + 2u - u^2/2`` with ``u = x^2/(1 + x^2)`` is checked symbolically.

For each negative, the evidence its ``check`` names:

* ``equilibrium``: ``f(point) = 0`` exactly at a point other than 0 (and ``H' = 0`` when ``H`` is given);
* ``conserved``: ``H' = 0`` identically with ``H`` non-constant (level sets are invariant);
* ``invariant_set``: ``g(0) != 0`` and ``g'`` a polynomial multiple of ``g`` (``{g = 0}`` is
  invariant and misses the origin);
* ``unstable_eigenvalue``: the Jacobian at 0 has an eigenvalue with positive real part;
* ``growing``: ``W`` positive definite and ``W'`` a sum of even monomials with positive
  coefficients (``W`` never decreases);
* ``solution``: an explicit solution satisfies the ODE identically;
* ``escape``: numerical: a SciPy integration from ``x0`` exceeds ``|x| = 1e6`` before ``t_max``
  (stated as numerical evidence, not a proof).

Run:  .venv/bin/python benchmarks/completeness/check_quotes.py [--only STEM,...] [--no-candidate]
Exit 0 when every check passes, 1 otherwise.
"""

from __future__ import annotations

import argparse
import ast
import json
import subprocess
import sys
import time
import tomllib
from pathlib import Path
from typing import Any

import sympy as sp

HERE = Path(__file__).resolve().parent
ROOT = HERE.parents[1]
#: the operators the quoted expressions use, to sympy (read by an ast whitelist: no string is
#: evaluated, as for every expression lyapcheck reads; this checker keeps its own reader so that
#: it does not share lyapcheck's parser)
BINARY = {ast.Add: lambda a, b: a + b, ast.Sub: lambda a, b: a - b, ast.Mult: lambda a, b: a * b,
          ast.Div: lambda a, b: a / b, ast.Pow: lambda a, b: a ** b}
FUNCTIONS = {"log": sp.log, "exp": sp.exp, "sqrt": sp.sqrt}


def to_sympy(node: ast.AST, names: dict[str, Any]) -> sp.Expr:
    """An expression tree of numbers, names, + - * / ** and log/exp/sqrt calls, exactly (decimals
    as the fractions they spell); ValueError for anything else."""
    if isinstance(node, ast.Expression):
        return to_sympy(node.body, names)
    if isinstance(node, ast.BinOp) and type(node.op) in BINARY:
        return BINARY[type(node.op)](to_sympy(node.left, names), to_sympy(node.right, names))
    if isinstance(node, ast.UnaryOp) and isinstance(node.op, (ast.USub, ast.UAdd)):
        inner = to_sympy(node.operand, names)
        return -inner if isinstance(node.op, ast.USub) else inner
    if isinstance(node, ast.Constant) and isinstance(node.value, (int, float)) and not isinstance(node.value, bool):
        return sp.Rational(ast.get_source_segment(SOURCE[-1], node) or repr(node.value))
    if isinstance(node, ast.Name):  # a declared name, else a free constant (a solution's a, b)
        return names.get(node.id, sp.Symbol(node.id))
    if isinstance(node, ast.Call) and isinstance(node.func, ast.Name) and node.func.id in FUNCTIONS \
            and len(node.args) == 1 and not node.keywords:
        return FUNCTIONS[node.func.id](to_sympy(node.args[0], names))
    raise ValueError(f"not in the checker's expression language: {ast.dump(node)[:80]}")


#: the text being read (for the exact spelling of decimal literals)
SOURCE: list[str] = []
#: the candidate class refuses longer expressions (MAX_EXPRESSION_LENGTH in docs/model-files.md)
CANDIDATE_MAX_CHARS = 4000


class Model:
    """A model file read with tomllib; its expressions as exact sympy expressions."""

    def __init__(self, path: Path) -> None:
        doc = tomllib.loads(path.read_text())
        self.path = path
        self.states = [sp.Symbol(s) for s in doc["model"]["states"]]
        self.names: dict[str, Any] = {str(s): s for s in self.states}
        for name, value in doc.get("parameters", {}).items():
            self.names[name] = sp.Rational(str(value))
        self.names.update({"t": sp.Symbol("t")})
        self.f = [self.parse(str(doc["dynamics"][str(s)])) for s in self.states]

    def parse(self, text: str) -> sp.Expr:
        SOURCE.append(text.strip())
        try:
            return to_sympy(ast.parse(SOURCE[-1], mode="eval"), self.names)
        finally:
            SOURCE.pop()

    def derivative(self, expr: sp.Expr) -> sp.Expr:
        return sp.cancel(sum(sp.diff(expr, s) * fi for s, fi in zip(self.states, self.f)))

    def origin(self) -> dict[sp.Symbol, int]:
        return {s: 0 for s in self.states}


def candidate_certifies(path: Path, v_text: str, timeout: float = 120.0) -> tuple[bool, str]:
    """lyapcheck's ``candidate`` class on ``V``: (GAS certified, status and summary)."""
    cmd = [sys.executable, "-m", "lyapcheck", "certify", str(path), "--classes", "candidate",
           "--candidate", v_text, "--json"]
    proc = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout, cwd=ROOT)
    try:
        cond = json.loads(proc.stdout)["conditions"]["candidate"]
    except (json.JSONDecodeError, KeyError):
        return False, f"exit {proc.returncode}: {proc.stderr.strip()[-300:]}"
    ok = cond.get("status") == "certified" and cond.get("property") == "GAS"
    return ok, f"{cond.get('status')} {cond.get('property')}: {cond.get('summary')}"


def lyapunov_equation_v(model: Model) -> tuple[sp.Expr, list[str]]:
    """V = x^T P x with A^T P + P A = -I solved exactly; notes on the minors."""
    x = sp.Matrix(model.states)
    A = sp.Matrix(model.f).jacobian(x)
    if A.free_symbols:
        raise ValueError(f"{model.path.name}: v_rule lyapunov_equation needs a linear field")
    n = len(model.states)
    P = sp.Matrix(n, n, lambda i, j: sp.Symbol(f"p{min(i, j)}_{max(i, j)}"))
    sol = sp.solve(list(A.T * P + P * A + sp.eye(n)), list(P.free_symbols), dict=True)[0]
    P = P.subs(sol)
    minors = [P[:k, :k].det() for k in range(1, n + 1)]
    if not all(m > 0 for m in minors):
        raise ValueError(f"{model.path.name}: P is not positive definite (minors {minors})")
    V = sp.expand((x.T * P * x)[0])
    notes = [f"P solved exactly; leading minors > 0 (smallest {float(min(minors)):.3g})"]
    return V, notes


def check_positive(stem: str, entry: dict[str, Any], run_candidate: bool) -> tuple[bool, list[str]]:
    model = Model(HERE / "positive" / f"{stem}.toml")
    notes: list[str] = []
    rule = entry.get("v_rule")
    if rule == "lyapunov_equation":
        V, more = lyapunov_equation_v(model)
        notes += more
        vdot = model.derivative(V)
        target = -sum(s**2 for s in model.states)
        if sp.expand(vdot - target) != 0:
            return False, notes + [f"V' = {vdot} is not -|x|^2"]
        notes.append("V' = -|x|^2 (identity)")
        text = str(V)
        if run_candidate and len(text) <= CANDIDATE_MAX_CHARS:
            ok, what = candidate_certifies(model.path, text)
            notes.append(f"candidate: {what}")
            return ok, notes
        if run_candidate:
            notes.append(f"candidate skipped: V has {len(text)} characters (> {CANDIDATE_MAX_CHARS})")
        return True, notes
    V = model.parse(entry["v"])
    vdot = model.derivative(V)
    notes.append(f"V' = {sp.factor(vdot)}")
    if V.subs(model.origin()) != 0 or sp.simplify(vdot.subs(model.origin())) != 0:
        return False, notes + ["V or V' is not 0 at the origin"]
    if rule == "nonpolynomial":
        x, y = model.states
        u = x**2 / (1 + x**2)
        identity = -vdot - (2 * (y - u / 2) ** 2 + 2 * u - u**2 / 2)
        if sp.simplify(identity) != 0:
            return False, notes + ["the identity -V' = 2(y - u/2)^2 + 2u - u^2/2 fails"]
        notes.append("-V' = 2(y - u/2)^2 + 2u - u^2/2, u = x^2/(1+x^2) in [0, 1): > 0 away from 0 (identity checked)")
        return True, notes
    if run_candidate:
        ok, what = candidate_certifies(model.path, entry["v"])
        notes.append(f"candidate: {what}")
        return ok, notes
    return True, notes


def escapes(model: Model, x0: dict[str, str], t_max: float) -> tuple[bool, str]:
    import numpy as np
    from scipy.integrate import solve_ivp

    f = sp.lambdify([model.states], model.f, "numpy")
    start = np.array([float(sp.Rational(x0.get(str(s), "0"))) for s in model.states])

    def blow(_t: float, z: Any) -> float:
        return float(np.linalg.norm(z)) - 1e6

    blow.terminal = True  # type: ignore[attr-defined]
    sol = solve_ivp(lambda _t, z: f(z), (0.0, t_max), start, events=blow, rtol=1e-9, atol=1e-9,
                    method="LSODA")
    if sol.t_events[0].size:
        return True, f"|x| > 1e6 at t = {sol.t_events[0][0]:.3f} from {x0} (numerical)"
    return False, f"no escape before t = {t_max} from {x0} (|x| = {np.linalg.norm(sol.y[:, -1]):.3g})"


def check_negative(stem: str, entry: dict[str, Any]) -> tuple[bool, list[str]]:
    model = Model(HERE / "negative" / f"{stem}.toml")
    check = entry["check"]
    kind = check["kind"]
    notes: list[str] = []
    ok = True
    if "H" in check or kind == "conserved":
        H = model.parse(check["H"])
        hdot = sp.simplify(model.derivative(H))
        good = hdot == 0 and not H.is_constant()
        notes.append(f"H = {H}: H' = {hdot}" + ("" if good else "  FAILED"))
        ok &= good
    if kind == "equilibrium":
        point = {sp.Symbol(k): model.parse(v) for k, v in check["point"].items()}
        point = {s: point.get(s, sp.Integer(0)) for s in model.states}
        values = [sp.simplify(fi.subs(point)) for fi in model.f]
        good = all(v == 0 for v in values) and any(p != 0 for p in point.values())
        notes.append(f"f({tuple(point.values())}) = {tuple(values)}" + ("" if good else "  FAILED"))
        ok &= good
    elif kind == "invariant_set":
        g = model.parse(check["g"])
        num, den = sp.fraction(sp.together(model.derivative(g)))
        quotient, remainder = sp.div(sp.expand(num), sp.expand(g), *model.states)
        good = remainder == 0 and g.subs(model.origin()) != 0 and den.free_symbols == set()
        notes.append(f"g = {g}: g' = ({sp.factor(quotient / den)}) * g, g(0) = {g.subs(model.origin())}"
                     + ("" if good else f"  FAILED (remainder {remainder})"))
        ok &= good
    elif kind == "unstable_eigenvalue":
        J = sp.Matrix(model.f).jacobian(model.states).subs(model.origin())
        eig = J.eigenvals()
        worst = max(sp.re(sp.N(e, 30)) for e in eig)
        good = bool(worst > 0)
        notes.append(f"Jacobian eigenvalues {[sp.nsimplify(e) for e in eig]}; max real part {float(worst):.4g}"
                     + ("" if good else "  FAILED"))
        ok &= good
    elif kind == "growing":
        W = model.parse(check["W"])
        wdot = sp.Poly(sp.expand(model.derivative(W)), *model.states)
        good = all(c > 0 and all(e % 2 == 0 for e in m) for m, c in wdot.terms())
        notes.append(f"W = {W}: W' = {wdot.as_expr()} (even monomials, positive coefficients)"
                     + ("" if good else "  FAILED"))
        ok &= good
    elif kind == "solution":
        t = sp.Symbol("t")
        sol = {sp.Symbol(k): model.parse(v) for k, v in check["solution"].items()}
        residuals = [sp.simplify(sp.diff(sol[s], t) - fi.subs(sol)) for s, fi in zip(model.states, model.f)]
        good = all(r == 0 for r in residuals)
        notes.append(f"solution {check['solution']} satisfies the ODE" + ("" if good else f"  FAILED {residuals}"))
        ok &= good
    elif kind == "escape":
        good, what = escapes(model, check["x0"], float(check["t_max"]))
        notes.append(what + ("" if good else "  FAILED"))
        ok &= good
    elif kind != "conserved":
        return False, [f"unknown check kind {kind!r}"]
    return ok, notes


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--only", default="", help="comma-separated stems")
    parser.add_argument("--no-candidate", action="store_true", help="sympy checks only (no lyapcheck runs)")
    args = parser.parse_args(argv)
    index = tomllib.loads((HERE / "index.toml").read_text())
    only = {s for s in args.only.split(",") if s}
    failures = 0
    for kind in ("positive", "negative"):
        for stem, entry in index[kind].items():
            if only and stem not in only:
                continue
            t0 = time.perf_counter()
            ok, notes = (check_positive(stem, entry, not args.no_candidate) if kind == "positive"
                         else check_negative(stem, entry))
            failures += not ok
            print(f"{'ok  ' if ok else 'FAIL'} {kind:8s} {stem}  ({time.perf_counter() - t0:.1f} s)")
            for note in notes:
                print(f"       {note}")
    print(f"\n{failures} failed" if failures else "\nevery quoted claim checked")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
