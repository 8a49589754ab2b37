"""SOS programs: a structure (:mod:`lyapcheck.sos.structure`) built into Clarabel's data once per
process (:mod:`lyapcheck.sos.direct`, kept in memory by the structure's hash) and re-solved with
each solve's parameters; and :func:`build_cvxpy`, the same program stated in cvxpy, which the
tests solve beside the direct data so that the construction is checked against an independent one.

The solver's answer is only a candidate: :mod:`lyapcheck.sos.rounding` turns it into exact
rationals that satisfy the identities exactly, and the classes decide with exact checks.
"""

from __future__ import annotations

import logging
import threading
from dataclasses import dataclass, field
from typing import Any, Mapping

import numpy as np

from lyapcheck.sos.direct import DirectProgram
from lyapcheck.sos.polynomials import Monomial
from lyapcheck.sos.sdp import SolveReport
# the structure's names, where the classes have always imported them from
from lyapcheck.sos.structure import (STRUCTURE_VERSION, Coefficients, Gram, Identity, Scalar, Structure, Term,
                                     full_blocks)

log = logging.getLogger(__name__)

# -- cvxpy construction ----------------------------------------------------------------------------

def _block_name(gram: str, b: int) -> str:
    return f"{gram}__b{b}"


def _gram_terms(gram: Gram, derivative: int | None) -> list[tuple[Monomial, int, int, float]]:
    """``(monomial, block, entry of vec(X_block), coefficient)`` of ``L(z^T Q z)``."""
    out = []
    for b, idx in enumerate(gram.blocks):
        k = len(idx)
        for jj, j in enumerate(idx):
            for ii, i in enumerate(idx):
                m = tuple(x + y for x, y in zip(gram.basis[i], gram.basis[j]))
                coef = 1.0
                if derivative is not None:
                    e = m[derivative]
                    if e == 0:
                        continue
                    coef = float(e)
                    m = m[:derivative] + (e - 1,) + m[derivative + 1:]
                out.append((m, b, ii + jj * k, coef))
    return out


def build_cvxpy(structure: Structure) -> tuple[Any, dict[str, Any], dict[str, Any]]:
    """The cvxpy problem of ``structure`` with its named parameters and variables (DPP)."""
    import cvxpy as cp
    import scipy.sparse as sp

    params = {name: cp.Parameter(shape, name=name) for name, shape in structure.parameters().items()}
    variables: dict[str, Any] = {}
    t = cp.Variable(name="t")
    variables["t"] = t
    cons: list[Any] = [t <= 1]
    blocks: dict[str, list[Any]] = {}
    for g in structure.grams:
        blocks[g.name] = []
        for b, idx in enumerate(g.blocks):
            X = cp.Variable((len(idx), len(idx)), symmetric=True, name=_block_name(g.name, b))
            variables[_block_name(g.name, b)] = X
            blocks[g.name].append(X)
            if g.cone != "psd":
                floor: Any = t if g.margin is True else params[g.margin] if isinstance(g.margin, str) else 0
                cons += _cone_constraints(g.cone, X, floor)
            elif g.margin is True:
                cons.append(X >> t * np.eye(len(idx)))
            elif isinstance(g.margin, str):
                cons.append(X >> params[g.margin] * np.eye(len(idx)))
            else:
                cons.append(X >> 0)
    scalars: dict[str, Any] = {}
    for s in structure.scalars:
        v = cp.Variable(name=s.name)
        variables[s.name] = v
        scalars[s.name] = v
        if s.lower == "zero":
            cons.append(v >= 0)
        elif s.lower == "margin":
            cons.append(v >= t)
    for name in structure.trace_one:
        cons.append(sum(cp.trace(X) for X in blocks[name]) == 1)
    for scalar, gram, param in structure.inner:
        g = structure.gram(gram)
        total = 0
        for b, idx in enumerate(g.blocks):
            sel = np.zeros((len(idx), len(g.basis)))
            sel[np.arange(len(idx)), idx] = 1.0
            total = total + cp.sum(cp.multiply(sel @ params[param] @ sel.T, blocks[gram][b]))
        cons.append(scalars[scalar] == total)

    for ident in structure.identities:
        rows: dict[Monomial, int] = {}

        def row(m: Monomial) -> int:
            return rows.setdefault(m, len(rows))

        # pass 1: every target monomial; pass 2: the expressions
        contributions: list[tuple[Coefficients, int, str, tuple[str, Any]]] = []  # (coefficients, k, kind, data)
        for term in ident.terms:
            if term.decision in blocks:
                base = _gram_terms(structure.gram(term.decision), term.derivative)
                for k, a in enumerate(term.coefficients.support):
                    entries = [(row(tuple(x + y for x, y in zip(m, a))), b, e, c) for m, b, e, c in base]
                    contributions.append((term.coefficients, k, "gram", (term.decision, entries)))
            else:
                if term.derivative is not None:
                    raise ValueError("a scalar has no derivative")
                for k, a in enumerate(term.coefficients.support):
                    contributions.append((term.coefficients, k, "scalar", (term.decision, row(a))))
        const_rows = [row(a) for a in ident.constant.support] if ident.constant else []
        n_rows = len(rows)
        literal_total: Any = 0
        param_terms: dict[tuple[str, int], Any] = {}
        for coeffs, k, kind, data in contributions:
            name, spec = data
            expr: Any = 0
            if kind == "gram":
                per_block: dict[int, list[tuple[int, int, float]]] = {}
                for r, b, e, c in spec:
                    per_block.setdefault(b, []).append((r, e, c))
                for b, block_entries in per_block.items():
                    X = blocks[name][b]
                    rr, ee, cc = zip(*block_entries)
                    M = sp.csr_matrix((cc, (rr, ee)), shape=(n_rows, X.shape[0] * X.shape[1]))
                    expr = expr + M @ cp.vec(X, order="F")
            else:
                e_row = np.zeros(n_rows)
                e_row[spec] = 1.0
                expr = e_row * scalars[name]
            if coeffs.param is None:
                literal_total = literal_total + float(coeffs.values[k]) * expr
            else:
                key = (coeffs.param, k)
                param_terms[key] = param_terms.get(key, 0) + expr
        identity_total: Any = literal_total
        for (pname, k), expr in param_terms.items():
            identity_total = identity_total + params[pname][k] * expr
        if ident.constant is not None:
            place = np.zeros((n_rows, len(const_rows)))
            place[const_rows, np.arange(len(const_rows))] = 1.0
            if ident.constant.param is None:
                identity_total = identity_total + place @ np.array([float(v) for v in ident.constant.values])
            else:
                identity_total = identity_total + place @ params[ident.constant.param]
        cons.append(identity_total == 0)

    kind = structure.objective[0]
    objective: Any
    if kind == "max_margin":
        objective = cp.Maximize(t)
    elif kind == "min":
        objective = cp.Minimize(scalars[structure.objective[1]])
    elif kind == "max":
        objective = cp.Maximize(scalars[structure.objective[1]])
    else:  # pragma: no cover - a programming error
        raise ValueError(f"unknown objective {structure.objective}")
    return cp.Problem(objective, cons), params, variables


def _cone_constraints(cone: str, X: Any, floor: Any) -> list[Any]:
    """``X - floor I`` scaled diagonally dominant (``"sdd"``: a sum of 2x2 PSD matrices, one per pair
    of rows, as second-order cones) or diagonally dominant (``"dd"``), stated independently of
    :mod:`lyapcheck.sos.direct`'s construction."""
    import cvxpy as cp

    k = X.shape[0]
    pairs = [(i, j) for j in range(k) for i in range(j)]
    if not pairs:
        return [X[0, 0] >= floor]
    if cone == "sdd":
        a = cp.Variable(len(pairs))
        c = cp.Variable(len(pairs))
        cons: list[Any] = [cp.SOC(a[p] + c[p], cp.hstack([a[p] - c[p], 2 * X[i, j]])) for p, (i, j) in enumerate(pairs)]
        for r in range(k):
            parts = [a[p] if i == r else c[p] for p, (i, j) in enumerate(pairs) if r in (i, j)]
            cons.append(X[r, r] - floor == cp.sum(cp.hstack(parts)))
        return cons
    u = cp.Variable(len(pairs))
    cons = [u >= cp.hstack([X[i, j] for i, j in pairs]), u >= -cp.hstack([X[i, j] for i, j in pairs])]
    for r in range(k):
        cons.append(X[r, r] - floor >= cp.sum(cp.hstack([u[p] for p, (i, j) in enumerate(pairs) if r in (i, j)])))
    return cons


# -- the program, built once per process -------------------------------------------------------------

_memory: dict[str, "SOSProgram"] = {}
_lock = threading.Lock()


@dataclass
class Solution:
    """A solve: the report, and the decision values (full Gram matrices, scalars, ``t``) when the
    solver returned a point."""

    report: SolveReport
    grams: dict[str, np.ndarray] = field(default_factory=dict)
    scalars: dict[str, float] = field(default_factory=dict)

    @property
    def usable(self) -> bool:
        """A point the exact checks may judge: 'optimal' or 'inaccurate' (never a proof by itself)."""
        return self.report.outcome in ("optimal", "inaccurate") and bool(self.grams or self.scalars)


class SOSProgram:
    """A :class:`Structure` as Clarabel's data (:class:`~lyapcheck.sos.direct.DirectProgram`);
    :meth:`solve` takes every parameter value, returns every variable."""

    def __init__(self, structure: Structure, compiled: Any) -> None:
        self.structure = structure
        self.compiled = compiled

    @classmethod
    def of(cls, structure: Structure) -> "SOSProgram":
        """The program of ``structure``: from memory, or built now."""
        key = structure.key()
        with _lock:
            hit = _memory.get(key)
        if hit is not None:
            return hit
        program = cls(structure, DirectProgram(structure))
        with _lock:
            _memory[key] = program
        return program

    def solve(self, values: Mapping[str, Any], *, max_iter: int | None = None,
              time_limit: float | None = None) -> Solution:
        solved = self.compiled.solve(values, max_iter=max_iter, time_limit=time_limit)
        out = Solution(solved.report)
        if solved.values is None:
            return out
        v = solved.values
        for g in self.structure.grams:
            Q = np.zeros((len(g.basis), len(g.basis)))
            for b, idx in enumerate(g.blocks):
                Q[np.ix_(idx, idx)] = v[_block_name(g.name, b)]
            out.grams[g.name] = (Q + Q.T) / 2
        out.scalars = {s.name: float(v[s.name]) for s in self.structure.scalars}
        out.scalars["t"] = float(v["t"])
        return out


__all__ = ["STRUCTURE_VERSION", "Coefficients", "Gram", "Identity", "Scalar", "Structure", "Term", "full_blocks",
           "build_cvxpy", "Solution", "SOSProgram"]
