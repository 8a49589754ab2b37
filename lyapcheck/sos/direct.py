"""An SOS program's conic data for Clarabel, built from its :class:`~lyapcheck.sos.structure.Structure` alone.

The generic classes' programs are small (Gram blocks of a few to a hundred rows) and their
structure is known exactly, so nothing is gained by handing them to a modelling layer: cvxpy
took about a second to import and a fraction of one to canonicalize each new structure, more
than the solves themselves on the 2-3-state systems a user starts with (issue 30: a first run
was 0.8-1.3 s, pydrake's whole process 0.13-0.20 s). Here the structure becomes Clarabel's

    minimize q^T x   subject to   A x + s = b,   s in K

directly, with the parameters (the field's coefficients, a level, a floor) entering ``A`` and
``b`` linearly, as in :mod:`lyapcheck.sos.program`'s declaration:

* the decisions ``x``: every Gram block's entries ``X_ij``, ``i <= j`` (one variable per pair), the
  scalars, and the margin ``t``;
* zero cone: each identity's coefficient of each monomial (``sum(terms) + constant = 0``), the
  ``trace_one`` normalizations and the ``inner`` products;
* nonnegative cone: ``t <= 1`` and the scalars' lower bounds (``>= 0`` or ``>= t``);
* one PSD-triangle cone per Gram block: ``X - t I`` (or ``X - phi I``, or ``X``), the upper
  triangle column by column with off-diagonal entries times ``sqrt 2`` (Clarabel's convention);
* for a block whose :attr:`~lyapcheck.sos.structure.Gram.cone` is ``"sdd"`` or ``"dd"`` instead, the
  same ``X - t I`` in the scaled diagonally dominant cone (a second-order cone of dimension 3 per pair
  of rows, and the diagonals in the zero cone) or the diagonally dominant one (nonnegative rows), with
  auxiliary decisions per pair (:meth:`DirectProgram._cone_rows`), after every PSD cone.

A structure's data is built once per process (a few milliseconds) and kept in memory; each
solve fills in the parameter values (:meth:`DirectProgram.solve`). The answer is evidence only,
as every solver's: the classes round it and decide by exact checks.
"""

from __future__ import annotations

import math
from typing import Any, Mapping

import numpy as np

from lyapcheck import tolerances as tol
from lyapcheck.sos.sdp import _CSC, DirectSolve, SolveReport, _CLARABEL_TO_CVXPY, _STATUS_MAP, _load_lapack_modules, \
    _settings, pack_parameters
from lyapcheck.sos.structure import Structure

SQRT2 = math.sqrt(2.0)


def _unique_with_inverse(keys: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``np.unique(keys, return_inverse=True)`` by a stable sort (``np.unique``'s first call imports
    ``numpy.ma``, 15-20 ms of a small model's whole run)."""
    order = np.argsort(keys, kind="stable")
    ordered = keys[order]
    first = np.ones(ordered.size, dtype=bool)
    first[1:] = ordered[1:] != ordered[:-1]
    inverse = np.empty(keys.size, dtype=np.int64)
    inverse[order] = np.cumsum(first) - 1
    return ordered[first], inverse


class _Entries:
    """Entries ``(row, column, factor, parameter slot)`` of a matrix linear in the parameters:
    the value is ``factor * p[slot]`` summed over duplicates, with ``p``'s last slot the constant 1."""

    def __init__(self) -> None:
        self.rows: list[int] = []
        self.cols: list[int] = []
        self.factors: list[float] = []
        self.slots: list[int] = []

    def add(self, row: int, col: int, factor: float, slot: int) -> None:
        self.rows.append(row)
        self.cols.append(col)
        self.factors.append(factor)
        self.slots.append(slot)


class DirectProgram:
    """A :class:`~lyapcheck.sos.structure.Structure` as Clarabel's data, re-solved at any parameters."""

    def __init__(self, structure: Structure) -> None:
        self.structure = structure
        shapes = structure.parameters()
        # the parameter vector: every parameter flattened (matrices column-major), then a 1
        self._slots: dict[str, tuple[int, tuple[int, ...]]] = {}
        at = 0
        for name, shape in shapes.items():
            self._slots[name] = (at, shape)
            at += int(np.prod(shape)) if shape else 1
        self._param_size = at + 1
        one = at  # the slot of the constant 1

        # -- the decisions ----------------------------------------------------------------------
        n_vars = 0
        #: per Gram, per block: (size, {(i, j) with i <= j within the block: column})
        self._blocks: dict[str, list[tuple[tuple[int, ...], dict[tuple[int, int], int]]]] = {}
        for g in structure.grams:
            blocks = []
            for idx in g.blocks:
                cols = {}
                for j in range(len(idx)):
                    for i in range(j + 1):
                        cols[(i, j)] = n_vars
                        n_vars += 1
                blocks.append((idx, cols))
            self._blocks[g.name] = blocks
        self._scalars = {s.name: n_vars + k for k, s in enumerate(structure.scalars)}
        n_vars += len(structure.scalars)
        self._t = n_vars
        n_vars += 1
        n_vars = self._allocate_cone_parts(n_vars)
        self.n = n_vars

        A = _Entries()
        b = _Entries()
        row = 0

        # -- zero cone: the identities, the normalizations, the inner products -------------------
        def slot_of(coeffs: Any, k: int) -> tuple[int, float]:
            if coeffs.param is None:
                return one, float(coeffs.values[k])
            return self._slots[coeffs.param][0] + k, 1.0

        for ident in structure.identities:
            rows: dict[tuple[int, ...], int] = {}

            def row_of(m: tuple[int, ...]) -> int:
                if m not in rows:
                    rows[m] = row + len(rows)
                return rows[m]

            for term in ident.terms:
                if term.decision in self._blocks:
                    entries = self._gram_entries(term.decision, term.derivative)
                    for k, a in enumerate(term.coefficients.support):
                        slot, scale = slot_of(term.coefficients, k)
                        for m, col, c in entries:
                            A.add(row_of(tuple(x + y for x, y in zip(m, a))), col, scale * c, slot)
                else:
                    if term.derivative is not None:
                        raise ValueError("a scalar has no derivative")
                    col = self._scalars[term.decision]
                    for k, a in enumerate(term.coefficients.support):
                        slot, scale = slot_of(term.coefficients, k)
                        A.add(row_of(tuple(a)), col, scale, slot)
            if ident.constant is not None:
                for k, a in enumerate(ident.constant.support):
                    slot, scale = slot_of(ident.constant, k)
                    b.add(row_of(tuple(a)), 0, -scale, slot)  # A x = -constant
            row += len(rows)
        for name in structure.trace_one:
            for idx, cols in self._blocks[name]:
                for j in range(len(idx)):
                    A.add(row, cols[(j, j)], 1.0, one)
            b.add(row, 0, 1.0, one)
            row += 1
        for scalar, gram, param in structure.inner:
            # scalar - <Q, P> = 0, P a symmetric parameter matrix over the Gram's whole basis
            A.add(row, self._scalars[scalar], 1.0, one)
            start, (size, _) = self._slots[param]
            for idx, cols in self._blocks[gram]:
                for (i, j), col in cols.items():
                    bi, bj = idx[i], idx[j]
                    if i == j:
                        A.add(row, col, -1.0, start + bi + bj * size)
                    else:  # X_ij and X_ji, one variable: P_ij + P_ji
                        A.add(row, col, -1.0, start + bi + bj * size)
                        A.add(row, col, -1.0, start + bj + bi * size)
            row += 1
        self._zero = row

        # -- nonnegative cone: t <= 1, the scalars' lower bounds ---------------------------------
        A.add(row, self._t, 1.0, one)
        b.add(row, 0, 1.0, one)
        row += 1
        for s in structure.scalars:
            if s.lower is None:
                continue
            A.add(row, self._scalars[s.name], -1.0, one)  # s = v (- t) >= 0
            if s.lower == "margin":
                A.add(row, self._t, 1.0, one)
            row += 1
        self._nonneg = row - self._zero

        # -- PSD cones: X - t I, X - phi I or X, per block ----------------------------------------
        self._psd: list[int] = []
        for g in structure.grams:
            if g.cone != "psd":
                continue  # its cones follow the PSD ones (:meth:`_cone_rows`)
            for idx, cols in self._blocks[g.name]:
                for j in range(len(idx)):
                    for i in range(j + 1):
                        if i < j:
                            A.add(row, cols[(i, j)], -SQRT2, one)
                        else:
                            A.add(row, cols[(j, j)], -1.0, one)
                            if g.margin is True:
                                A.add(row, self._t, 1.0, one)
                            elif isinstance(g.margin, str):
                                b.add(row, 0, -1.0, self._slots[g.margin][0])
                        row += 1
                self._psd.append(len(idx))
        row = self._cone_rows(A, b, row, one)
        self.m = row

        # -- the objective -------------------------------------------------------------------------
        self.q = np.zeros(self.n)
        kind = structure.objective[0]
        #: the objective as stated (``max`` ones are solved as ``min`` of the negative)
        self._sign = -1.0 if kind in ("max_margin", "max") else 1.0
        if kind == "max_margin":
            self.q[self._t] = -1.0
        elif kind == "min":
            self.q[self._scalars[structure.objective[1]]] = 1.0
        elif kind == "max":
            self.q[self._scalars[structure.objective[1]]] = -1.0
        else:  # pragma: no cover - a programming error
            raise ValueError(f"unknown objective {structure.objective}")

        # -- the sparsity of A once (column-major, rows sorted, duplicates merged) ---------------
        a_rows, a_cols = np.asarray(A.rows, dtype=np.int64), np.asarray(A.cols, dtype=np.int64)
        keys = a_cols * self.m + a_rows
        unique, self._a_slot = _unique_with_inverse(keys)
        self._a_indices = unique % self.m
        self._a_indptr = np.searchsorted(unique // self.m, np.arange(self.n + 1)).astype(np.int64)
        self._a_factors = np.asarray(A.factors)
        self._a_params = np.asarray(A.slots, dtype=np.int64)
        self._a_size = int(unique.size)
        self._b_rows = np.asarray(b.rows, dtype=np.int64)
        self._b_factors = np.asarray(b.factors)
        self._b_params = np.asarray(b.slots, dtype=np.int64)
        self._cones: list[Any] | None = None

    # -- the SDD and DD cones (Gram blocks with ``cone`` "sdd" or "dd") -------------------------------
    #
    # The block's entries ``X_ij`` stay the decisions (the identities, the rounding and the exact
    # checks read them as for a PSD block); the cone is stated on ``X - margin I`` with auxiliary
    # decisions per pair of rows ``i < j``:
    #
    # * "sdd": ``X - margin I = sum_(i<j) M_ij``, ``M_ij = [[a_ij, X_ij], [X_ij, c_ij]]`` on rows i, j
    #   PSD, i.e. ``(a + c, a - c, 2 X_ij)`` in the second-order cone of dimension 3; the diagonal
    #   ``X_ii - margin = sum of the a's and c's on row i`` (zero cone). A block of one row: ``X_00 >= margin``.
    # * "dd": ``u_ij >= |X_ij|`` (two linear rows) and ``X_ii - margin >= sum_j u_ij`` (nonnegative cone).

    def _allocate_cone_parts(self, n_vars: int) -> int:
        """Columns for the auxiliary decisions of every SDD and DD block; the next free column."""
        #: per (Gram, block): {(i, j): (columns of the pair's parts)} in block positions, i < j
        self._parts: dict[tuple[str, int], dict[tuple[int, int], tuple[int, ...]]] = {}
        for g in self.structure.grams:
            if g.cone == "psd":
                continue
            width = 2 if g.cone == "sdd" else 1
            for k, (idx, _) in enumerate(self._blocks[g.name]):
                pairs = {}
                for j in range(len(idx)):
                    for i in range(j):
                        pairs[(i, j)] = tuple(range(n_vars, n_vars + width))
                        n_vars += width
                self._parts[(g.name, k)] = pairs
        return n_vars

    def _cone_rows(self, A: _Entries, b: _Entries, row: int, one: int) -> int:
        """The rows of every SDD and DD block (after the PSD cones), grouped by cone; the next row.
        ``self._other_cones`` lists the cones in row order."""
        self._other_cones: list[tuple[str, int]] = []
        grams = [g for g in self.structure.grams if g.cone != "psd"]

        def margin(g: Any, r: int, sign: float) -> None:
            # the margin's part of a diagonal row: ``sign`` on t in A (-1 in a zero row, A x = b; +1
            # in a nonnegative row, b - A x >= 0), a floor parameter moved to b with the other sign
            if g.margin is True:
                A.add(r, self._t, sign, one)
            elif isinstance(g.margin, str):
                b.add(r, 0, -sign, self._slots[g.margin][0])

        start = row  # zero cone: the SDD blocks' diagonals (X_ii - margin - parts = 0)
        for g in grams:
            if g.cone != "sdd":
                continue
            for k, (idx, cols) in enumerate(self._blocks[g.name]):
                if len(idx) < 2:
                    continue
                for i in range(len(idx)):
                    A.add(row, cols[(i, i)], 1.0, one)
                    margin(g, row, -1.0)
                    for (p, q), (a, c) in self._parts[(g.name, k)].items():
                        if i in (p, q):
                            A.add(row, a if i == p else c, -1.0, one)
                    row += 1
        if row > start:
            self._other_cones.append(("zero", row - start))
        start = row  # nonnegative cone: 1-row SDD blocks, and the DD blocks' rows
        for g in grams:
            for k, (idx, cols) in enumerate(self._blocks[g.name]):
                if g.cone == "sdd" and len(idx) >= 2:
                    continue
                pairs = self._parts[(g.name, k)]
                for (p, q), (u,) in pairs.items():  # u - X_pq >= 0, u + X_pq >= 0
                    A.add(row, u, -1.0, one)
                    A.add(row, cols[(p, q)], 1.0, one)
                    A.add(row + 1, u, -1.0, one)
                    A.add(row + 1, cols[(p, q)], -1.0, one)
                    row += 2
                for i in range(len(idx)):  # X_ii - margin - sum_j u_ij >= 0
                    A.add(row, cols[(i, i)], -1.0, one)
                    margin(g, row, 1.0)
                    for (p, q), (u,) in pairs.items():
                        if i in (p, q):
                            A.add(row, u, 1.0, one)
                    row += 1
        if row > start:
            self._other_cones.append(("nonneg", row - start))
        for g in grams:  # second-order cones: (a + c, a - c, 2 X_ij) per pair of an SDD block
            if g.cone != "sdd":
                continue
            for k, (idx, cols) in enumerate(self._blocks[g.name]):
                for (p, q), (a, c) in self._parts[(g.name, k)].items():
                    A.add(row, a, -1.0, one)
                    A.add(row, c, -1.0, one)
                    A.add(row + 1, a, -1.0, one)
                    A.add(row + 1, c, 1.0, one)
                    A.add(row + 2, cols[(p, q)], -2.0, one)
                    row += 3
                    self._other_cones.append(("soc", 3))
        return row

    def _gram_entries(self, name: str, derivative: int | None) -> list[tuple[tuple[int, ...], int, float]]:
        """``(monomial, column, coefficient)`` of ``L(z^T X z)`` in the block variables."""
        gram = self.structure.gram(name)
        out = []
        for idx, cols in self._blocks[name]:
            for (i, j), col in cols.items():
                m = tuple(x + y for x, y in zip(gram.basis[idx[i]], gram.basis[idx[j]]))
                c = 1.0 if i == j else 2.0  # X_ij and X_ji
                if derivative is not None:
                    e = m[derivative]
                    if e == 0:
                        continue
                    c *= e
                    m = m[:derivative] + (e - 1,) + m[derivative + 1:]
                out.append((m, col, c))
        return out

    def parameter_vector(self, values: Mapping[str, Any]) -> np.ndarray:
        """The parameter values in their slots (matrices column-major), then the constant 1."""
        return pack_parameters(self._slots, self._param_size, values, self.structure.key())

    def matrices(self, p: np.ndarray) -> tuple[_CSC, np.ndarray]:
        """Clarabel's ``A`` and ``b`` at the parameter vector ``p``."""
        data = np.bincount(self._a_slot, weights=self._a_factors * p[self._a_params], minlength=self._a_size)
        b = np.bincount(self._b_rows, weights=self._b_factors * p[self._b_params], minlength=self.m)
        return _CSC(data, self._a_indices, self._a_indptr, (self.m, self.n)), b

    def unpack(self, x: np.ndarray) -> dict[str, np.ndarray]:
        """Every variable by the names :class:`~lyapcheck.sos.program.SOSProgram` reads: each Gram
        block as a symmetric matrix (``<gram>__b<k>``), the scalars, and ``t``."""
        out: dict[str, np.ndarray] = {}
        for name, blocks in self._blocks.items():
            for k, (idx, cols) in enumerate(blocks):
                X = np.zeros((len(idx), len(idx)))
                for (i, j), col in cols.items():
                    X[i, j] = X[j, i] = x[col]
                out[f"{name}__b{k}"] = X
        for name, col in self._scalars.items():
            out[name] = np.asarray(x[col])
        out["t"] = np.asarray(x[self._t])
        return out

    def solve(self, values: Mapping[str, Any], *, max_iter: int | None = None,
              time_limit: float | None = None) -> DirectSolve:
        """Solve at these parameter values; never raises for solver failures (as
        :meth:`lyapcheck.sos.sdp.CompiledProgram.solve`, whose statuses it records)."""
        import time

        import clarabel

        if self._cones is None:
            cones: list[Any] = []
            if self._zero:
                cones.append(clarabel.ZeroConeT(self._zero))
            if self._nonneg:
                cones.append(clarabel.NonnegativeConeT(self._nonneg))
            cones += [clarabel.PSDTriangleConeT(k) for k in self._psd]
            for kind, size in self._other_cones:
                if kind == "zero":
                    cones.append(clarabel.ZeroConeT(size))
                elif kind == "nonneg":
                    cones.append(clarabel.NonnegativeConeT(size))
                else:
                    cones.append(clarabel.SecondOrderConeT(size))
            if self._psd:
                _load_lapack_modules()
            self._cones = cones
        settings = _settings(tol.SOLVER_MAX_ITER if max_iter is None else max_iter, time_limit)
        start = time.perf_counter()
        A, b = self.matrices(self.parameter_vector(values))
        P = _CSC(np.zeros(0), np.zeros(0, dtype=np.int64), np.zeros(self.n + 1, dtype=np.int64), (self.n, self.n))
        result: Any = None
        try:
            try:
                solver = clarabel.DefaultSolver(P, self.q, A, b, self._cones, settings)
            except (TypeError, AttributeError):  # pragma: no cover - a binding that wants scipy itself
                solver = clarabel.DefaultSolver(P.as_scipy(), self.q, A.as_scipy(), b, self._cones, settings)
            result = solver.solve()
            raw = _CLARABEL_TO_CVXPY.get(str(result.status), "solver_error")
        except (ValueError, ArithmeticError, RuntimeError):
            raw = "solver_error"
        wall = time.perf_counter() - start
        variables = None
        objective = None
        if result is not None and raw in ("optimal", "optimal_inaccurate", "user_limit"):
            variables = self.unpack(np.asarray(result.x, dtype=np.float64))
            if raw != "user_limit":
                objective = self._sign * float(result.obj_val)
        report = SolveReport(outcome=_STATUS_MAP.get(raw, "error"), raw_status=raw, objective=objective,
                             iterations=int(result.iterations) if result is not None else None,
                             solve_seconds=float(result.solve_time) if result is not None else wall, wall_seconds=wall)
        return DirectSolve(report, variables)
