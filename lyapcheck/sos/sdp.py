"""Thin, explicit layer over cvxpy + Clarabel: status mapping and metadata.

A solver's word is evidence only. This module reports what the solver said; the condition
classes then round to rationals and run the exact check. ``optimal_inaccurate`` is never
treated as success.

Two ways in, with one status map: :func:`solve` for a cvxpy problem, and
:class:`CompiledProgram` for a program compiled once by :mod:`lyapcheck.paper.conditions.compiled`,
which hands Clarabel the same data cvxpy would without importing cvxpy (see there for why).
"""

from __future__ import annotations

import importlib
import logging
import sys
import threading
import time
import types
import warnings
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any, Literal, Mapping

from lyapcheck import tolerances as tol

if TYPE_CHECKING:  # pragma: no cover
    import numpy as np

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


def solve(problem: Any, *, max_iter: int = tol.SOLVER_MAX_ITER) -> SolveReport:
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
                tol_feas=tol.SOLVER_TOL_FEAS, max_iter=max_iter,
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


#: Threads of Clarabel's factorisation in the direct path. One: these KKT systems are small
#: (at most a few hundred rows), so threads cost more than they save (the three sos_bound solves
#: at the paper's gains: 3.3 s with one thread, 4.1 s with Clarabel's default of every core, on 2
#: cores), sweeps already run one process per core, and a result cannot depend on the machine's
#: core count. The verdict snapshot (tests/test_verdicts_unchanged.py) is bit for bit the same
#: as with the default.
SOLVER_THREADS = 1

#: Clarabel's status names as cvxpy reports them (``cvxpy``'s ``CLARABEL.STATUS_MAP``), so that the
#: direct path records the same ``raw_status`` and maps it through :data:`_STATUS_MAP`
_CLARABEL_TO_CVXPY: dict[str, str] = {
    "Solved": "optimal",
    "PrimalInfeasible": "infeasible",
    "DualInfeasible": "unbounded",
    "AlmostSolved": "optimal_inaccurate",
    "AlmostPrimalInfeasible": "infeasible_inaccurate",
    "AlmostDualInfeasible": "unbounded_inaccurate",
    "MaxIterations": "user_limit",
    "MaxTime": "user_limit",
    "NumericalError": "solver_error",
    "InsufficientProgress": "solver_error",
    "Unsolved": "solver_error",
}


class _CSC:
    """The attributes of a canonical ``scipy.sparse.csc_matrix`` that Clarabel's binding reads.

    Importing ``scipy.sparse`` costs 0.1-0.2 s, a fifth of a whole ``certify``; the index
    arrays here are sorted and free of duplicates by construction (the generator checks it
    against cvxpy's own matrix). If a Clarabel version ever refuses this stand-in,
    :meth:`CompiledProgram.solve` falls back to a real ``csc_matrix``.
    """

    format = "csc"
    has_canonical_format = True
    has_sorted_indices = True

    def __init__(self, data: "np.ndarray", indices: "np.ndarray", indptr: "np.ndarray",
                 shape: tuple[int, int]) -> None:
        self.data, self.indices, self.indptr, self.shape = data, indices, indptr, shape
        self.nnz = int(data.size)

    def as_scipy(self) -> Any:
        import scipy.sparse as sp

        return sp.csc_matrix((self.data, self.indices, self.indptr), shape=self.shape)


def pack_parameters(slots: Mapping[str, tuple[int, tuple[int, ...]]], size: int, values: Mapping[str, Any],
                    key: str) -> "np.ndarray":
    """A program's parameter vector: each value flattened column-major at its slot ``(start, shape)``,
    then a 1 (``size`` counts it). A parameter of size 0 (a polynomial with no terms, e.g. a state
    whose derivative is 0) carries no data and may be left out; ValueError naming the program
    otherwise, for a missing, unknown or misshapen parameter."""
    import numpy as np

    given = {name for name in values if name in slots or np.asarray(values[name]).size}
    if given != set(slots):
        missing = sorted(set(slots) - given)
        extra = sorted(given - set(slots))
        raise ValueError(f"program {key}: parameters missing {missing}, unknown {extra}")
    vec = np.zeros(size)
    for name, (start, shape) in slots.items():
        v = np.asarray(values[name], dtype=np.float64)
        if v.shape != shape:
            raise ValueError(f"The '{name}' parameter of program {key} must have shape {shape}. Got {v.shape} instead.")
        vec[start:start + v.size] = v.ravel(order="F")
    vec[-1] = 1.0
    return vec


class ProgramData:
    """A compiled program's arrays (see :mod:`lyapcheck.paper.conditions.compiled`), with the maps they define."""

    def __init__(self, key: str, arrays: Mapping[str, "np.ndarray"]) -> None:
        import numpy as np

        self.key = key
        self.arrays = dict(arrays)
        a = self.arrays
        self.n, self.m, self.param_size = int(a["n"]), int(a["m"]), int(a["param_size"])
        self.params: dict[str, tuple[int, tuple[int, ...]]] = {}
        for name, col, shape in zip(a["param_names"].tolist(), a["param_cols"].tolist(), a["param_shapes"].tolist()):
            self.params[str(name)] = (int(col), tuple(int(d) for d in shape if d >= 0))
        R_indptr = a["R_indptr"]
        # the row of each stored entry of the reduced tensor (a CSR matrix): values = R @ p
        self._rows = np.repeat(np.arange(R_indptr.size - 1), np.diff(R_indptr))
        self._n_values = int(R_indptr.size - 1)
        indptr = a["M_indptr"]
        self._split = int(indptr[self.n])
        self._a_order = a["A_order"]
        self._a_indices = a["M_indices"][:self._split][self._a_order]
        self._a_indptr = indptr[: self.n + 1].copy()
        self._b_rows = a["M_indices"][self._split:]
        self.q = a["q"]
        self.q_offset = float(a["q_offset"])
        self.objective_sign = float(a["objective_sign"])
        self.cones = (int(a["cone_zero"]), int(a["cone_nonneg"]), a["cone_soc"].tolist(), a["cone_psd"].tolist())
        self.variables = [str(v) for v in a["variables"].tolist()]

    @classmethod
    def from_arrays(cls, key: str, arrays: Mapping[str, "np.ndarray"]) -> "ProgramData":
        return cls(key, arrays)

    def parameter_vector(self, values: Mapping[str, Any]) -> "np.ndarray":
        """cvxpy's parameter vector: each value flattened column-major at its column, then a 1
        (cvxpy drops a parameter of size 0 from the compiled program)."""
        return pack_parameters(self.params, self.param_size, values, self.key)

    def matrices(self, param_vec: "np.ndarray") -> tuple[_CSC, "np.ndarray"]:
        """Clarabel's ``A`` and ``b`` (``A x + s = b``) at a parameter vector."""
        import numpy as np

        a = self.arrays
        # a CSR product, entry by entry in row order: the additions scipy's csr_matvec does
        values = np.bincount(self._rows, weights=a["R_data"] * param_vec[a["R_indices"]], minlength=self._n_values)
        A = _CSC(-values[: self._split][self._a_order], self._a_indices, self._a_indptr, (self.m, self.n))
        b = np.zeros(self.m)
        b[self._b_rows] = values[self._split:]
        return A, b

    def unpack(self, x: "np.ndarray") -> dict[str, "np.ndarray"]:
        import numpy as np

        a = self.arrays
        out = {}
        for name in self.variables:
            shape = tuple(int(d) for d in a[f"var_{name}_shape"])
            size = int(np.prod(shape)) if shape else 1
            flat = np.bincount(a[f"var_{name}_rows"], weights=a[f"var_{name}_coef"] * x[a[f"var_{name}_cols"]],
                               minlength=size)
            out[name] = flat.reshape(shape) if shape else flat.reshape(())
        return out


@dataclass(frozen=True)
class DirectSolve:
    """What :meth:`CompiledProgram.solve` returns: the report, and the variables when a point exists."""

    report: SolveReport
    values: dict[str, "np.ndarray"] | None


#: Set by ``lyapcheck certify`` on the command line only (see :func:`_load_lapack_modules`).
LEAN_LAPACK_IMPORT = False
_LAPACK_MODULES = ("scipy.linalg.cython_blas", "scipy.linalg.cython_lapack")
_lapack_lock = threading.Lock()


def _load_lapack_modules() -> None:
    """Load the two SciPy modules Clarabel takes BLAS and LAPACK from, without ``scipy.linalg``.

    Clarabel's first PSD-cone solve imports ``scipy.linalg.cython_blas`` and ``cython_lapack``
    for their function pointers. The usual import runs ``scipy.linalg``'s package first, 0.15-0.2 s
    (a third of ``certify --classes quick``) spent on a Python API nothing here uses. The two
    extension modules need nothing from that package, so they are imported under a bare stand-in
    for it, which is removed at once: a later ``import scipy.linalg`` runs as usual. What differs
    afterwards is only that ``scipy.linalg.cython_blas`` is not bound as an attribute of the
    package (``import scipy.linalg.cython_blas`` still works), which is why only the command
    line, whose process lyapcheck owns, turns this on (:data:`LEAN_LAPACK_IMPORT`). Any failure
    leaves the usual import to Clarabel.
    """
    if not LEAN_LAPACK_IMPORT:
        return
    with _lapack_lock:
        if "scipy.linalg" in sys.modules or all(name in sys.modules for name in _LAPACK_MODULES):
            return
        try:
            import scipy
        except ImportError:  # pragma: no cover - Clarabel will report it
            return
        stand_in = types.ModuleType("scipy.linalg")
        stand_in.__path__ = [str(Path(scipy.__file__).with_name("linalg"))]
        sys.modules["scipy.linalg"] = stand_in
        try:
            for name in _LAPACK_MODULES:
                importlib.import_module(name)
        except Exception as exc:  # noqa: BLE001 - any failure: the usual import happens later
            log.debug("lean LAPACK import failed (%s); Clarabel imports scipy.linalg itself", exc)
            for name in _LAPACK_MODULES:
                sys.modules.pop(name, None)
        finally:
            if sys.modules.get("scipy.linalg") is stand_in:
                del sys.modules["scipy.linalg"]
            # vars(), not getattr(): scipy's module __getattr__ would import scipy.linalg for real
            if vars(scipy).get("linalg") is stand_in:
                delattr(scipy, "linalg")


def _settings(max_iter: int, time_limit: float | None = None) -> Any:
    """Clarabel's settings for a direct solve: the options :func:`solve` passes through cvxpy
    (the rest are Clarabel's defaults, as there)."""
    import clarabel

    settings = clarabel.DefaultSettings()
    settings.verbose = False
    settings.tol_gap_abs = tol.SOLVER_TOL_GAP_ABS
    settings.tol_gap_rel = tol.SOLVER_TOL_GAP_REL
    settings.tol_feas = tol.SOLVER_TOL_FEAS
    settings.max_iter = max_iter
    if time_limit is not None:
        settings.time_limit = float(time_limit)
    settings.max_threads = SOLVER_THREADS
    return settings


class CompiledProgram:
    """A program compiled once (:mod:`lyapcheck.paper.conditions.compiled`), solved by Clarabel directly.

    Stateless: :meth:`solve` takes every parameter value and returns every variable, so a
    result never depends on what was solved before (no warm start, a fresh solver each time).
    """

    def __init__(self, data: ProgramData) -> None:
        self.data = data
        self._cones: list[Any] | None = None
        self._settings: Any = None
        self._duck = True

    def _setup(self) -> None:
        import clarabel

        zero, nonneg, soc, psd = self.data.cones
        cones: list[Any] = []
        if zero:
            cones.append(clarabel.ZeroConeT(zero))
        if nonneg:
            cones.append(clarabel.NonnegativeConeT(nonneg))
        cones += [clarabel.SecondOrderConeT(d) for d in soc]
        cones += [clarabel.PSDTriangleConeT(d) for d in psd]
        if psd:
            _load_lapack_modules()
        self._cones = cones
        self._settings = _settings(tol.SOLVER_MAX_ITER)

    def solve(self, values: Mapping[str, Any], *, max_iter: int | None = None,
              time_limit: float | None = None) -> DirectSolve:
        """Solve at these parameter values; never raises for solver failures (as :func:`solve`).

        ``max_iter`` replaces :data:`~lyapcheck.tolerances.SOLVER_MAX_ITER` for this solve only;
        ``time_limit`` (seconds) makes Clarabel stop there (status ``user_limit``: no certificate).
        """
        import clarabel
        import numpy as np

        if self._cones is None:
            self._setup()
        settings = self._settings if max_iter is None and time_limit is None else \
            _settings(tol.SOLVER_MAX_ITER if max_iter is None else max_iter, time_limit)
        start = time.perf_counter()
        A, b = self.data.matrices(self.data.parameter_vector(values))
        n = self.data.n
        P = _CSC(np.zeros(0), np.zeros(0, dtype=np.int64), np.zeros(n + 1, dtype=np.int64), (n, n))
        result: Any = None
        try:
            try:
                if not self._duck:
                    raise TypeError("scipy matrices")
                solver = clarabel.DefaultSolver(P, self.data.q, A, b, self._cones, settings)
            except (TypeError, AttributeError):  # pragma: no cover - a binding that wants scipy itself
                self._duck = False
                solver = clarabel.DefaultSolver(P.as_scipy(), self.data.q, A.as_scipy(), b, self._cones, settings)
            result = solver.solve()
            raw = _CLARABEL_TO_CVXPY.get(str(result.status), "solver_error")
        except (ValueError, ArithmeticError, RuntimeError) as exc:
            log.debug("solver failure: %s", exc)
            raw = "solver_error"
        wall = time.perf_counter() - start
        outcome = _STATUS_MAP.get(raw, "error")
        objective = None
        variables = None
        if result is not None and raw in ("optimal", "optimal_inaccurate", "user_limit"):
            x = np.asarray(result.x, dtype=np.float64)
            variables = self.data.unpack(x)
            if raw != "user_limit":
                objective = self.data.objective_sign * (float(result.obj_val) + self.data.q_offset)
        report = SolveReport(
            outcome=outcome, raw_status=raw, objective=objective,
            iterations=int(result.iterations) if result is not None else None,
            solve_seconds=float(result.solve_time) if result is not None else wall, wall_seconds=wall,
        )
        return DirectSolve(report, variables)
