"""Thin, explicit layer over cvxpy + Clarabel: status mapping and metadata.

A solver's word is evidence only. This module reports what the solver said; the condition
classes then round to rationals and run the exact check. ``optimal_inaccurate`` is never
treated as success.
"""

from __future__ import annotations

import logging
import time
import warnings
from dataclasses import dataclass
from typing import Any, Literal

from lyapcheck import tolerances as tol

log = logging.getLogger(__name__)

SolverOutcome = Literal["optimal", "infeasible", "unbounded", "inaccurate", "error"]

_STATUS_MAP: dict[str, SolverOutcome] = {
    "optimal": "optimal",
    "infeasible": "infeasible",
    "unbounded": "unbounded",
    "optimal_inaccurate": "inaccurate",
    "infeasible_inaccurate": "inaccurate",
    "unbounded_inaccurate": "inaccurate",
    "user_limit": "error",
    "solver_error": "error",
}


@dataclass(frozen=True)
class SolveReport:
    outcome: SolverOutcome
    raw_status: str
    objective: float | None
    iterations: int | None
    solve_seconds: float
    wall_seconds: float

    def to_json(self) -> dict[str, Any]:
        return {
            "solver": "CLARABEL", "status": self.raw_status, "outcome": self.outcome,
            "objective": self.objective, "iterations": self.iterations,
            "solve_seconds": self.solve_seconds, "wall_seconds": self.wall_seconds,
        }


def solve(problem: Any) -> SolveReport:
    """Solve a compiled cvxpy problem with Clarabel; never raises for solver failures."""
    import cvxpy as cp

    start = time.perf_counter()
    try:
        # cvxpy warns about inaccurate solutions; the status map below records that instead
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            problem.solve(
                solver=cp.CLARABEL,
                # cvxpy warm-starts re-solves by default; a certificate search must not depend on
                # what this process solved before (results must be reproducible point by point)
                warm_start=False,
                tol_gap_abs=tol.SOLVER_TOL_GAP_ABS, tol_gap_rel=tol.SOLVER_TOL_GAP_REL,
                tol_feas=tol.SOLVER_TOL_FEAS, max_iter=tol.SOLVER_MAX_ITER,
            )
        raw = str(problem.status)
    except (cp.error.SolverError, ValueError, ArithmeticError) as exc:
        log.debug("solver failure: %s", exc)
        raw = "solver_error"
    wall = time.perf_counter() - start
    stats = getattr(problem, "solver_stats", None)
    iterations = getattr(stats, "num_iters", None) if stats is not None else None
    solve_time = getattr(stats, "solve_time", None) if stats is not None else None
    objective = None
    if raw in ("optimal", "optimal_inaccurate"):
        try:
            objective = float(problem.value)
        except (TypeError, ValueError):
            objective = None
    return SolveReport(
        outcome=_STATUS_MAP.get(raw, "error"), raw_status=raw, objective=objective,
        iterations=int(iterations) if iterations is not None else None,
        solve_seconds=float(solve_time) if solve_time is not None else wall, wall_seconds=wall,
    )
