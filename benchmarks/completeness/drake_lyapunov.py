"""A strict SOS Lyapunov search in pydrake, the baseline of ``benchmarks/bench_vs_drake.py``.

What a Python user who picked Drake instead of lyapcheck would write: read a lyapcheck model
file (``tomllib`` and a small ``ast`` reader of its expression language; lyapcheck itself is not
imported, so the process pays only for Python, pydrake and the solve), then for ``V`` of degree 2,
then 4 (monomials of degree 2..d, free coefficients) solve with Clarabel

    V - eps * |x|^2          SOS
    -V' - eps * |x|^2        SOS,   V' = grad(V) . f

and stop at the first degree whose program Clarabel reports solved. Parameters are substituted
as doubles. A rational field is not attempted (``"status": "rational field"``): the denominators'
sign would have to be proved first, which this baseline does not do. The answer is Drake's
floating-point one: nothing is rounded or checked exactly (a ``success`` here is not a proof in
lyapcheck's sense).

Run:  PYTHON benchmarks/completeness/drake_lyapunov.py FILE [--eps 1e-3] [--degrees 2,4]
Prints one JSON object: {"certified": bool, "degree": int | null, "status": str, "seconds": float}
(seconds: build and solve, imports excluded; the benchmark measures the whole process itself).
"""

from __future__ import annotations

import argparse
import ast
import json
import sys
import time
import tomllib
from itertools import combinations_with_replacement
from pathlib import Path
from typing import Any

import numpy as np
from pydrake.solvers import ClarabelSolver, MathematicalProgram
from pydrake.symbolic import Expression, Variable


class RationalField(ValueError):
    """The field divides by a state: outside what this baseline attempts."""


def to_expression(text: str, names: dict[str, Any]) -> Any:
    """An expression of the model-file language as a pydrake Expression (``+ - * / **``,
    numbers, declared names); a division by anything holding a state raises RationalField."""

    def walk(node: ast.AST) -> Any:
        if isinstance(node, ast.Expression):
            return walk(node.body)
        if isinstance(node, ast.Constant) and isinstance(node.value, (int, float)) and not isinstance(node.value, bool):
            return float(node.value)
        if isinstance(node, ast.Name):
            if node.id not in names:
                raise ValueError(f"unknown name {node.id!r} in {text!r}")
            return names[node.id]
        if isinstance(node, ast.UnaryOp) and isinstance(node.op, (ast.USub, ast.UAdd)):
            value = walk(node.operand)
            return -value if isinstance(node.op, ast.USub) else value
        if isinstance(node, ast.BinOp):
            left, right = walk(node.left), walk(node.right)
            if isinstance(node.op, ast.Add):
                return left + right
            if isinstance(node.op, ast.Sub):
                return left - right
            if isinstance(node.op, ast.Mult):
                return left * right
            if isinstance(node.op, ast.Div):
                if isinstance(right, Expression) and not right.GetVariables().empty():
                    raise RationalField(f"division by {right} in {text!r}")
                return left / (right.Evaluate() if isinstance(right, Expression) else right)
            if isinstance(node.op, ast.Pow) and isinstance(node.right, ast.Constant) and isinstance(node.right.value, int):
                return left ** node.right.value
        raise ValueError(f"not part of the expression language: {ast.dump(node)} in {text!r}")

    return walk(ast.parse(text, mode="eval"))


def search(path: Path, eps: float, degrees: list[int]) -> dict[str, Any]:
    doc = tomllib.loads(path.read_text())
    states = list(doc["model"]["states"])
    x = [Variable(s) for s in states]
    names: dict[str, Any] = {s: Expression(v) for s, v in zip(states, x)}
    for name, value in doc.get("parameters", {}).items():
        names[name] = float(value)
    try:
        f = [to_expression(str(doc["dynamics"][s]), names) + Expression(0.0) for s in states]
    except RationalField as exc:
        return {"certified": False, "degree": None, "status": f"rational field ({exc})"}
    xe = np.array([Expression(v) for v in x])
    norm2 = xe.dot(xe)
    status = "no degree tried"
    for degree in degrees:
        prog = MathematicalProgram()
        prog.AddIndeterminates(x)
        monomials = [np.prod([xe[i] for i in combo]) for d in range(2, degree + 1)
                     for combo in combinations_with_replacement(range(len(x)), d)]
        c = prog.NewContinuousVariables(len(monomials), "c")
        V = sum(ci * m for ci, m in zip(c, monomials))
        Vdot = sum(V.Differentiate(xi) * fi for xi, fi in zip(x, f))
        prog.AddSosConstraint(V - eps * norm2)
        prog.AddSosConstraint(-Vdot - eps * norm2)
        result = ClarabelSolver().Solve(prog)
        status = f"degree {degree}: {result.get_solution_result()}"
        if result.is_success():
            return {"certified": True, "degree": degree, "status": status}
    return {"certified": False, "degree": None, "status": status}


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("model", type=Path)
    parser.add_argument("--eps", type=float, default=1e-3)
    parser.add_argument("--degrees", default="2,4")
    args = parser.parse_args(argv)
    t0 = time.perf_counter()
    answer = search(args.model, args.eps, [int(d) for d in args.degrees.split(",")])
    answer["seconds"] = time.perf_counter() - t0
    print(json.dumps(answer))
    return 0


if __name__ == "__main__":
    sys.exit(main())
