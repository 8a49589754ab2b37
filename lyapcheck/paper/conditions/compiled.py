"""The certificate programs compiled once, stored, and solved without cvxpy at run time.

Why. Every program of the condition classes is written in cvxpy with ``cp.Parameter`` data
(DPP), and its conic form is an affine function of the parameter values. Importing cvxpy costs
0.9-1.2 s (it pulls in ``scipy.stats``), about as much as a whole ``certify`` may take, and its
per-solve overhead (parameter canonicalisation, solution inversion) is 5-50 times Clarabel's
own solve for these small programs. So each program is compiled by cvxpy ONCE, by
``python -m lyapcheck.paper.conditions.compiled`` (or on first use when no stored form matches),
into plain arrays:

* the map from the parameter vector to the data ``(A, b)`` that cvxpy hands to Clarabel
  (cvxpy's own reduced sparse tensor, rows ordered like the CSC matrix it builds), and the
  constant objective ``q`` with its offset;
* the cones; the linear map from Clarabel's primal vector to each named variable (probed
  through cvxpy's own inversion, ``Problem.unpack_results``).

At run time :class:`~lyapcheck.sos.sdp.CompiledProgram` forms the data with one sparse
product (the same additions, in the same order, as cvxpy's), calls ``clarabel.DefaultSolver``
and reads the variables back. Clarabel receives bit for bit the data cvxpy would give it, so
the solver's answer is the same as through cvxpy; the generator checks this on random data
(data equal, solutions equal) before it writes anything. Nothing about soundness changes: the
solver's answer is only a candidate, decided by the classes' exact rational checks.

Stored forms live in ``_compiled/<key>.npz`` beside this module; each carries a hash of the
module that defines the program, and a form whose hash does not match is ignored (the program
is then compiled in-process, with cvxpy, as before issue 11). ``tests/test_compiled_programs.py``
fails when a stored form is stale: regenerate with ``python -m lyapcheck.paper.conditions.compiled``.
"""

from __future__ import annotations

import hashlib
import importlib
import importlib.util
import logging
import sys
from functools import lru_cache
from pathlib import Path
from typing import Any, Callable, Final, Mapping

import numpy as np

from lyapcheck.sos.sdp import CompiledProgram, ProgramData

log = logging.getLogger(__name__)

STORE: Final = Path(__file__).with_name("_compiled")
#: bump when the stored layout changes (older files are then ignored)
FORMAT_VERSION: Final = 1

#: program family -> (module, builder function). A builder takes the cvxpy module and integer
#: arguments (a degree, a size) and returns ``(problem, {name: Parameter}, {name: Variable})``.
#: The key of one program is the family with its arguments: ``sos_6`` is ``sos``'s builder at 6.
FAMILIES: Final[dict[str, tuple[str, str]]] = {
    "prop41": ("lyapcheck.paper.conditions.prop41", "build_program"),
    "sector": ("lyapcheck.paper.conditions.sector", "build_program"),
    "ultimate": ("lyapcheck.paper.conditions.ultimate", "build_program"),
    "sos": ("lyapcheck.paper.conditions.sos", "build_program"),
    "sos_bound": ("lyapcheck.paper.conditions.sos_bound", "build_program"),
    "sos_bound_parity": ("lyapcheck.paper.conditions.sos_bound", "build_parity_program"),
    "level": ("lyapcheck.paper.conditions.saturated", "build_level_program"),
    "ges": ("lyapcheck.paper.conditions.ges", "build_program"),
}
#: the programs stored in ``_compiled/`` (others are compiled in-process on first use)
PROGRAMS: Final = ("prop41", "sector", "sector_8", "ultimate", "sos_4", "sos_6", "sos_bound", "sos_bound_parity", "level_4", "level_6", "ges_4_24_1")


def key_of(family: str, *args: int) -> str:
    """The key of ``family``'s program at ``args`` (``key_of("sos", 6) == "sos_6"``)."""
    return "_".join([family, *(str(int(a)) for a in args)])


def _resolve(key: str) -> tuple[str, str, tuple[int, ...]]:
    """(module, builder, arguments) of a key: the longest family name it starts with, then integers."""
    for family in sorted(FAMILIES, key=len, reverse=True):
        rest = key[len(family):]
        if key.startswith(family) and (rest == "" or rest.startswith("_")):
            parts = rest.split("_")[1:]
            if all(p.isdigit() for p in parts):
                return (*FAMILIES[family], tuple(int(p) for p in parts))
    raise KeyError(f"no compiled program family for '{key}' (families: {', '.join(FAMILIES)})")


def source_hash(key: str) -> str:
    """Hash of what the stored form was compiled from: the defining module's source and the arguments."""
    module_name, func, args = _resolve(key)
    spec = importlib.util.find_spec(module_name)
    origin = spec.origin if spec is not None else None
    if origin is None:  # pragma: no cover - the modules are plain source files
        raise FileNotFoundError(module_name)
    digest = hashlib.sha256(Path(origin).read_bytes())
    digest.update(repr((FORMAT_VERSION, func, args)).encode())
    return digest.hexdigest()


def _path(key: str) -> Path:
    return STORE / f"{key}.npz"


@lru_cache(maxsize=None)
def load(key: str) -> CompiledProgram:
    """The program ``key`` (:func:`key_of`): its stored form if current, else compiled now (cvxpy)."""
    path = _path(key)
    expected = source_hash(key)
    if path.exists():
        with np.load(path, allow_pickle=False) as f:
            stored = {name: f[name] for name in f.files}
        if str(stored.pop("source_hash")) == expected:
            return CompiledProgram(ProgramData.from_arrays(key, stored))
        log.warning("stored program %s is stale (its module changed): compiling it with cvxpy; "
                    "regenerate with python -m lyapcheck.paper.conditions.compiled", key)
    return CompiledProgram(compile_program(key))


# -- compilation (cvxpy) -------------------------------------------------------------------------

def build(key: str) -> tuple[Any, dict[str, Any], dict[str, Any]]:
    """The cvxpy problem of ``key`` with its named parameters and variables."""
    import cvxpy as cp

    module_name, func, args = _resolve(key)
    builder: Callable[..., tuple[Any, dict[str, Any], dict[str, Any]]] = getattr(
        importlib.import_module(module_name), func)
    return builder(cp, *args)


def _random_values(params: Mapping[str, Any], rng: np.random.Generator) -> dict[str, np.ndarray]:
    out = {}
    for name, p in params.items():
        v = rng.uniform(0.5, 1.5, size=p.shape) if p.is_nonneg() else rng.normal(size=p.shape)
        out[name] = np.asarray(v, dtype=np.float64)
    return out


def compile_program(key: str) -> ProgramData:
    """Compile ``key`` with cvxpy into :class:`ProgramData`, checked against cvxpy on random data."""
    import cvxpy as cp
    from cvxpy.lin_ops import lin_op
    from types import SimpleNamespace

    problem, params, variables = build(key)
    if not problem.is_dpp():
        raise ValueError(f"program {key} is not DPP")
    rng = np.random.default_rng(20240611)
    values = _random_values(params, rng)
    for name, p in params.items():
        p.value = values[name]
    data, chain, inverse = problem.get_problem_data(cp.CLARABEL)
    pp = data[cp.settings.PARAM_PROB]
    n = int(data["c"].size)
    by_id = {p.id: name for name, p in params.items()}
    layout: list[tuple[str, int, tuple[int, ...]]] = []
    constant_col = -1
    for pid, col in pp.param_id_to_col.items():
        if pid == lin_op.CONSTANT_ID:
            constant_col = int(col)
            continue
        if pid not in by_id:
            raise ValueError(f"program {key}: a parameter without a name")
        layout.append((by_id[pid], int(col), tuple(params[by_id[pid]].shape)))
    size = int(pp.total_param_size) + 1
    if constant_col != size - 1:
        raise ValueError(f"program {key}: unexpected parameter layout")

    # the data tensor, reduced as cvxpy reduces it: values = R @ param_vec, placed by (indices, indptr)
    pp.reduced_A.cache(False)
    R = pp.reduced_A.reduced_mat.tocsr()
    indices, indptr, shape = pp.reduced_A.problem_data_index
    indices, indptr = np.asarray(indices, dtype=np.int64), np.asarray(indptr, dtype=np.int64)
    m = int(shape[0])
    if int(shape[1]) != n + 1:
        raise ValueError(f"program {key}: unexpected data shape")
    split = int(indptr[n])  # entries before: A's columns; from there: the offset column b
    a_order = np.arange(split)
    # cvxpy hands Clarabel A = -M[:, :n] (re-sorted by scipy if needed) and b = M[:, n]
    for j in range(n):
        seg = slice(int(indptr[j]), int(indptr[j + 1]))
        a_order[seg] = a_order[seg][np.argsort(indices[seg], kind="stable")]
    cones = data["dims"]
    if cones.exp or cones.p3d or cones.pnd:
        raise ValueError(f"program {key}: only zero, nonnegative, second-order and PSD cones are supported")

    q_tensor = pp.q.tocsc() if hasattr(pp.q, "tocsc") else pp.q
    q_full = np.asarray(q_tensor[:, [size - 1]].toarray()).ravel()
    if q_tensor[:, : size - 1].count_nonzero():
        raise ValueError(f"program {key}: a parameter enters the objective; not supported")

    # variables: the linear map from Clarabel's x, probed through cvxpy's own inversion
    inverse[-1].solver_options = {}
    zeros = np.zeros(m)
    columns: dict[str, list[np.ndarray]] = {name: [] for name in variables}
    for j in range(n + 1):
        x = np.zeros(n)
        if j < n:
            x[j] = 1.0
        fake = SimpleNamespace(status="Solved", solve_time=0.0, iterations=0, x=x, z=zeros, s=zeros, obj_val=0.0)
        problem.unpack_results(fake, chain, inverse)
        for name, var in variables.items():
            columns[name].append(np.asarray(var.value, dtype=np.float64).ravel(order="C"))
    unpack: dict[str, np.ndarray] = {}
    for name, cols in columns.items():
        mat = np.array(cols).T  # (size of var, n + 1)
        if np.any(mat[:, -1]):
            raise ValueError(f"program {key}: variable {name} is not linear in the solver's x")
        rows, xs = np.nonzero(mat[:, :-1])
        unpack[f"var_{name}_rows"] = rows.astype(np.int64)
        unpack[f"var_{name}_cols"] = xs.astype(np.int64)
        unpack[f"var_{name}_coef"] = mat[rows, xs]
        unpack[f"var_{name}_shape"] = np.array(variables[name].shape, dtype=np.int64)

    arrays: dict[str, np.ndarray] = {
        "format": np.array(FORMAT_VERSION),
        "n": np.array(n), "m": np.array(m), "param_size": np.array(size),
        "param_names": np.array([name for name, _, _ in layout]),
        "param_cols": np.array([col for _, col, _ in layout], dtype=np.int64),
        "param_shapes": np.array([list(s) + [-1] * (2 - len(s)) for _, _, s in layout], dtype=np.int64).reshape(-1, 2),
        "R_data": np.asarray(R.data, dtype=np.float64), "R_indices": np.asarray(R.indices, dtype=np.int64),
        "R_indptr": np.asarray(R.indptr, dtype=np.int64),
        "M_indices": indices, "M_indptr": indptr, "A_order": a_order,
        "q": q_full[:n].astype(np.float64), "q_offset": np.array(float(q_full[n])),
        "objective_sign": np.array(-1.0 if isinstance(problem.objective, cp.Maximize) else 1.0),
        "cone_zero": np.array(int(cones.zero)), "cone_nonneg": np.array(int(cones.nonneg)),
        "cone_soc": np.array(list(cones.soc), dtype=np.int64), "cone_psd": np.array(list(cones.psd), dtype=np.int64),
        "variables": np.array(list(variables)),
        **unpack,
    }
    program = ProgramData.from_arrays(key, arrays)
    _check_against_cvxpy(key, program, problem, params, variables, rng, chain, inverse)
    return program


def _check_against_cvxpy(key: str, program: ProgramData, problem: Any, params: Mapping[str, Any],
                         variables: Mapping[str, Any], rng: np.random.Generator, chain: Any, inverse: Any) -> None:
    """The stored form gives Clarabel cvxpy's data bit for bit, reads variables back as cvxpy does,
    and one solve both ways gives the same status and point."""
    import cvxpy as cp
    from types import SimpleNamespace

    from lyapcheck.sos.sdp import solve

    for _ in range(2):
        values = _random_values(params, rng)
        for name, p in params.items():
            p.value = values[name]
        data, _, _ = problem.get_problem_data(cp.CLARABEL)
        A, b = program.matrices(program.parameter_vector(values))
        ref = data["A"].tocsc()
        ref.sort_indices()
        same = (np.array_equal(A.indptr, ref.indptr) and np.array_equal(A.indices, ref.indices)
                and np.array_equal(A.data, ref.data) and np.array_equal(b, data["b"])
                and np.array_equal(program.q, data["c"]))
        if not same:
            raise ValueError(f"program {key}: the compiled data differ from cvxpy's")
    x = rng.normal(size=program.n)
    zeros = np.zeros(program.m)
    problem.unpack_results(SimpleNamespace(status="Solved", solve_time=0.0, iterations=0, x=x, z=zeros, s=zeros,
                                           obj_val=0.0), chain, inverse)
    mine = program.unpack(x)
    for name, var in variables.items():
        if not np.array_equal(np.asarray(var.value, dtype=np.float64), mine[name]):
            raise ValueError(f"program {key}: variable {name} is read back differently from cvxpy")
    report = solve(problem)
    direct = CompiledProgram(program).solve(values)
    if report.raw_status != direct.report.raw_status:
        raise ValueError(f"program {key}: status {direct.report.raw_status} directly, {report.raw_status} via cvxpy")
    if direct.values is not None and report.outcome in ("optimal", "inaccurate"):
        for name, var in variables.items():
            if not np.array_equal(np.asarray(var.value, dtype=np.float64), direct.values[name]):
                raise ValueError(f"program {key}: variable {name} differs from cvxpy's solution")


def write_all(keys: list[str] | None = None) -> list[Path]:
    """Compile and store every program of :data:`PROGRAMS` (or ``keys``)."""
    STORE.mkdir(exist_ok=True)
    written = []
    for key in keys or list(PROGRAMS):
        arrays: dict[str, Any] = {**compile_program(key).arrays, "source_hash": np.array(source_hash(key))}
        path = _path(key)
        np.savez_compressed(path, **arrays)
        written.append(path)
    load.cache_clear()
    return written


if __name__ == "__main__":  # pragma: no cover - the generator
    for written_path in write_all(sys.argv[1:] or None):
        print(f"wrote {written_path}")
