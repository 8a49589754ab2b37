"""``sector_ges`` at sweep speed: the compiled conic data re-used, Clarabel called directly.

Why: for the 2x2 sector program cvxpy's per-solve overhead (~2 ms: parameter canonicalisation,
solution inversion) is ten times Clarabel's own solve (~0.15 ms). The program is DPP, so its
conic data ``(A, b, c)`` are an affine function of the parameter values. :class:`SectorBatchSolver`
asks cvxpy once for the data at the zero parameter and at each unit parameter
(``Problem.get_problem_data``), forms the data of any point as ``A0 + sum_k p_k A_k`` and calls
``clarabel.DefaultSolver`` itself. The map from Clarabel's primal vector back to ``(P, m)`` is
linear too and is probed once through cvxpy's own inversion (``Problem.unpack_results``). Both
affine maps are checked against cvxpy at a random point when the solver is built.

Nothing about the verdict changes: the solver's output is rounded to rationals and
:func:`lyapcheck.conditions.sector.exact_check` decides every ``certified``;
:func:`lyapcheck.conditions.sector.refutation` decides every ``refuted``. The decay rate handed to
the exact check is computed as a generalised eigenvalue problem in the scaled coordinates (the
condition ``A^T P + P A + 2 mu P < 0`` is invariant under the congruence of
:mod:`lyapcheck.conditions.scaling`), which is well conditioned, so the first exact check
usually passes; :func:`lyapcheck.conditions.sector.certify_polytope` bounds the rate through
eigenvalues in the original coordinates instead and may halve it many times.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass
from fractions import Fraction
from functools import lru_cache
from types import SimpleNamespace
from typing import Any, Final, Sequence

import numpy as np

from lyapcheck import exact
from lyapcheck import tolerances as tol
from lyapcheck.conditions import scaling, sector
from lyapcheck.conditions.base import ConditionResult, System
from lyapcheck.errors import SolverError

#: Clarabel's status names mapped to the outcomes of lyapcheck.conditions.sdp (explicit, so
#: that "AlmostSolved" can never count as a solution)
OUTCOMES: Final[dict[str, str]] = {
    "Solved": "optimal",
    "AlmostSolved": "inaccurate",
    "PrimalInfeasible": "infeasible",
    "DualInfeasible": "unbounded",
    "AlmostPrimalInfeasible": "inaccurate",
    "AlmostDualInfeasible": "inaccurate",
    "MaxIterations": "error",
    "MaxTime": "error",
    "NumericalError": "error",
    "InsufficientProgress": "error",
}
#: agreement required between the affine model of the conic data and cvxpy's own data
_AFFINE_CHECK_RTOL: Final = 1e-12
#: the rate handed to the exact check is this fraction of the floating-point optimum; halved
#: on failure at most this many times (as in sector.certify_polytope)
_RATE_BACKOFF: Final = 0.999
_RATE_HALVINGS: Final = 30
#: significant digits of the rounded certificate (see certify)
RATIONAL_DIGITS: Final = 10


@dataclass(frozen=True)
class RawSolve:
    """What Clarabel returned for one point, in the scaled coordinates."""

    outcome: str
    raw_status: str
    P_scaled: np.ndarray | None
    margin: float | None
    solve_seconds: float
    wall_seconds: float
    iterations: int

    def to_json(self) -> dict[str, Any]:
        objective = self.margin if self.outcome in ("optimal", "inaccurate") else None
        return {"solver": "CLARABEL (direct, compiled conic data)", "status": self.raw_status,
                "outcome": self.outcome, "objective": objective, "iterations": self.iterations,
                "solve_seconds": self.solve_seconds, "wall_seconds": self.wall_seconds}


class SectorBatchSolver:
    """The sector program's conic data as an affine function of ``(A_lo, A_hi)`` (module doc)."""

    def __init__(self) -> None:
        import clarabel
        import cvxpy as cp
        import scipy.sparse as sp
        from cvxpy.reductions.solvers.conic_solvers.clarabel_conif import dims_to_solver_cones

        self._clarabel = clarabel
        self._csc = sp.csc_matrix
        self._prog = sector.program()
        data0, chain, inverse = self._data_at(np.zeros(8))
        self._A0 = data0["A"].toarray()
        self._b0 = np.asarray(data0["b"], dtype=np.float64)
        self._c0 = np.asarray(data0["c"], dtype=np.float64)
        dA, db, dc = [], [], []
        for k in range(8):
            unit = np.zeros(8)
            unit[k] = 1.0
            d, _, _ = self._data_at(unit)
            dA.append(d["A"].toarray() - self._A0)
            db.append(np.asarray(d["b"]) - self._b0)
            dc.append(np.asarray(d["c"]) - self._c0)
        self._dA = np.array(dA)
        # a fixed sparsity pattern (the union over the parameters), so that each point only
        # forms the nonzero values: A = A0 + sum_k p_k dA_k restricted to the pattern
        pattern = sp.csc_matrix((np.abs(self._A0) + np.abs(self._dA).sum(axis=0)) != 0)
        pattern.sort_indices()
        cols = np.repeat(np.arange(pattern.shape[1]), np.diff(pattern.indptr))  # column of each entry
        self._indices, self._indptr, self._shape = pattern.indices.copy(), pattern.indptr.copy(), pattern.shape
        self._A0_nz = self._A0[pattern.indices, cols]
        self._dA_nz = self._dA[:, pattern.indices, cols]  # (8, nnz)
        if np.any(np.array(db)) or np.any(np.array(dc)):  # pragma: no cover - the program's b, c are constant
            raise SolverError("the sector program's b or c depend on the parameters; the direct path assumes not")
        self._cones = dims_to_solver_cones(data0["dims"])
        n = self._c0.size
        self._P = sp.csc_matrix((n, n))
        settings = clarabel.DefaultSettings()
        settings.verbose = False
        settings.tol_gap_abs = tol.SOLVER_TOL_GAP_ABS
        settings.tol_gap_rel = tol.SOLVER_TOL_GAP_REL
        settings.tol_feas = tol.SOLVER_TOL_FEAS
        settings.max_iter = tol.SOLVER_MAX_ITER
        self._settings = settings
        self._unpack = self._probe_unpack(chain, inverse, n, self._b0.size)
        self._check_affine(cp)

    def _data_at(self, p: np.ndarray) -> tuple[dict[str, Any], Any, Any]:
        import cvxpy as cp

        self._prog.A_lo.value = p[:4].reshape(2, 2)
        self._prog.A_hi.value = p[4:].reshape(2, 2)
        return self._prog.problem.get_problem_data(cp.CLARABEL)  # type: ignore[no-any-return]

    def _probe_unpack(self, chain: Any, inverse: Any, n: int, m: int) -> np.ndarray:
        """The linear map x -> (P00, P01, P11, m) through cvxpy's own inversion (once)."""
        # get_problem_data leaves the solver options unset; invert() reads them
        inverse[-1].solver_options = {}
        cols = []
        for j in range(n + 1):
            x = np.zeros(n)
            if j < n:
                x[j] = 1.0
            fake = SimpleNamespace(status="Solved", solve_time=0.0, iterations=0, x=x, z=np.zeros(m),
                                   s=np.zeros(m), obj_val=0.0)
            self._prog.problem.unpack_results(fake, chain, inverse)
            P = np.asarray(self._prog.P.value, dtype=np.float64)
            cols.append([P[0, 0], P[0, 1], P[1, 1], float(np.asarray(self._prog.m.value))])
        out = np.array(cols).T  # (4, n + 1): last column is the offset at x = 0
        offset = out[:, -1]
        if np.any(offset):  # pragma: no cover - variables map linearly in cvxpy's chain
            raise SolverError("the sector program's solution map is not linear; the direct path assumes it is")
        return out[:, :-1]

    def _check_affine(self, cp: Any) -> None:
        rng = np.random.default_rng(0)
        p = rng.normal(size=8)
        data, _, _ = self._data_at(p)
        formed = self._A0 + np.tensordot(p, self._dA, axes=1)
        ref = data["A"].toarray()
        if not np.allclose(formed, ref, rtol=_AFFINE_CHECK_RTOL, atol=_AFFINE_CHECK_RTOL * np.abs(ref).max()):
            raise SolverError("the sector program's conic data are not affine in its parameters as expected")

    def solve(self, a_lo: np.ndarray, a_hi: np.ndarray) -> RawSolve:
        """Solve the program for scaled vertex matrices (as ``sector.certify_polytope`` sets them)."""
        start = time.perf_counter()
        p = np.concatenate([np.asarray(a_lo, dtype=np.float64).ravel(), np.asarray(a_hi, dtype=np.float64).ravel()])
        A = self._csc((self._A0_nz + p @ self._dA_nz, self._indices, self._indptr), shape=self._shape)
        try:
            solver = self._clarabel.DefaultSolver(self._P, self._c0, A, self._b0, self._cones, self._settings)
            result = solver.solve()
        except (ValueError, ArithmeticError, RuntimeError) as exc:  # pragma: no cover - Clarabel data errors
            wall = time.perf_counter() - start
            return RawSolve("error", f"solver_error: {exc}", None, None, wall, wall, 0)
        raw = str(result.status)
        outcome = OUTCOMES.get(raw, "error")
        P_scaled, margin = None, None
        if outcome == "optimal":
            v = self._unpack @ np.asarray(result.x, dtype=np.float64)
            P_scaled = np.array([[v[0], v[1]], [v[1], v[2]]])
            margin = float(v[3])
        wall = time.perf_counter() - start
        return RawSolve(outcome, raw, P_scaled, margin, float(result.solve_time), wall, int(result.iterations))


@lru_cache(maxsize=1)
def batch_solver() -> SectorBatchSolver:
    """One per process (built on first use, like the cvxpy programs it wraps)."""
    return SectorBatchSolver()


def _rate_upper(a_scaled: Sequence[np.ndarray], P_scaled: np.ndarray, time_scale: float) -> float:
    """Largest ``mu`` with ``A_i^T P + P A_i + 2 mu P < 0`` at every vertex, in floating point.

    In the scaled coordinates (``A = T A~ T^-1 s``, ``P = T^-T P~ T^-1``) the condition reads
    ``s (A~^T P~ + P~ A~) + 2 mu P~ < 0``: ``mu = s lambda_min(Q~, P~) / 2`` with
    ``Q~ = -(A~^T P~ + P~ A~)``, the smaller root of ``det(Q~ - lambda P~) = 0`` (2x2, closed form,
    well conditioned). Only a candidate: the exact check decides.
    """
    p00, p01, p11 = float(P_scaled[0, 0]), float(P_scaled[0, 1]), float(P_scaled[1, 1])
    det_p = p00 * p11 - p01 * p01
    if not (p00 > 0 and det_p > 0):
        return -math.inf
    best = math.inf
    for a in a_scaled:
        q = -(a.T @ P_scaled + P_scaled @ a)
        q00, q01, q11 = float(q[0, 0]), 0.5 * float(q[0, 1] + q[1, 0]), float(q[1, 1])
        b = q00 * p11 + q11 * p00 - 2 * q01 * p01
        c = q00 * q11 - q01 * q01
        root = math.sqrt(max(b * b - 4 * det_p * c, 0.0))
        best = min(best, (b - root) / (2 * det_p) * time_scale / 2)
    return best


def certify(system: System, solver: SectorBatchSolver | None = None,
            rho_lo: Fraction = Fraction(0)) -> ConditionResult:
    """``sector_ges`` for one point through the direct path (same statuses as ``sector.run``)."""
    solver = solver or batch_solver()
    vertices = [system.vertex(rho_lo), system.vertex(system.rho_sup)]
    sc = scaling.choose(vertices)
    scaled = [sc.matrix_to_scaled(v) for v in vertices]
    raw = solver.solve(scaled[0], scaled[1])
    numbers: dict[str, Any] = {"relative_margin": raw.margin, "rho_interval": [str(rho_lo), str(system.rho_sup)]}
    if raw.outcome == "optimal" and raw.margin is not None and raw.margin > 0 and raw.P_scaled is not None:
        # 10 significant digits (sector.certify_polytope keeps 15): the solver's P has a relative
        # margin far above 1e-10, and shorter rationals make the exact check cheaper
        P_tilde = exact.symmetrize(exact.rational_matrix(raw.P_scaled, RATIONAL_DIGITS))
        P = sc.p_from_scaled(P_tilde)
        mu = _rate_upper(scaled, np.array(exact.to_float(P_tilde)), float(sc.time))
        if math.isfinite(mu) and mu > 0:
            rate = exact.to_rational(mu * _RATE_BACKOFF, 6)
            for _ in range(_RATE_HALVINGS):
                ok, why = sector.exact_check(vertices, P, rate)  # also checks P > 0
                if ok:
                    return sector.certified_result(P, rate, rho_lo, why, numbers, raw.to_json())
                rate /= 2
    return sector.uncertified_result(vertices, numbers, raw.outcome, raw.margin, raw.to_json())
