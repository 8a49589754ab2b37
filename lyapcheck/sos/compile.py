"""cvxpy programs compiled once into plain arrays, and solved by Clarabel without cvxpy.

Why. A certificate program is written in cvxpy with ``cp.Parameter`` data (DPP), and its conic
form is an affine function of the parameter values. Importing cvxpy costs 0.9-1.5 s and its
per-solve overhead is 5-50 times Clarabel's own solve for these small programs. So a program is
compiled by cvxpy once into :class:`~lyapcheck.sos.sdp.ProgramData`:

* the map from the parameter vector to the data ``(A, b)`` that cvxpy hands to Clarabel
  (cvxpy's own reduced sparse tensor, rows ordered like the CSC matrix it builds), and the
  constant objective ``q`` with its offset;
* the cones; the linear map from Clarabel's primal vector to each named variable (probed
  through cvxpy's own inversion, ``Problem.unpack_results``).

At run time :class:`~lyapcheck.sos.sdp.CompiledProgram` forms the data with one sparse product
(the additions cvxpy does, in its order), calls Clarabel and reads the variables back. Clarabel
receives the data cvxpy would give it; :func:`check_against_cvxpy` verifies this on random data
(data equal, one solve both ways equal). Nothing about soundness depends on it: a solver's answer
is only a candidate for the exact checks.

The paper's fixed programs are stored with the package (:mod:`lyapcheck.paper.conditions.compiled`);
the programs of a model file are compiled per structure and kept in the user's cache
(:mod:`lyapcheck.sos.program`).
"""

from __future__ import annotations

from typing import Any, Mapping

import numpy as np

from lyapcheck.sos.sdp import CompiledProgram, ProgramData, solve

#: bump when the stored layout changes (older files are then ignored)
FORMAT_VERSION = 1


def _random_values(params: Mapping[str, Any], rng: np.random.Generator) -> dict[str, np.ndarray]:
    out = {}
    for name, p in params.items():
        v = rng.uniform(0.5, 1.5, size=p.shape) if p.is_nonneg() else rng.normal(size=p.shape)
        out[name] = np.asarray(v, dtype=np.float64)
    return out


def compile_problem(key: str, problem: Any, params: Mapping[str, Any], variables: Mapping[str, Any], *,
                    check: bool = True) -> ProgramData:
    """Compile a cvxpy DPP problem into :class:`ProgramData` (named parameters and variables).

    With ``check``, the stored form is compared with cvxpy's own data on random parameter values
    and one solve both ways must agree (:func:`check_against_cvxpy`).
    """
    import cvxpy as cp
    from cvxpy.lin_ops import lin_op
    from types import SimpleNamespace

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

    def probe(x: np.ndarray) -> dict[str, np.ndarray]:
        fake = SimpleNamespace(status="Solved", solve_time=0.0, iterations=0, x=x, z=zeros, s=zeros, obj_val=0.0)
        problem.unpack_results(fake, chain, inverse)
        return {name: np.asarray(var.value, dtype=np.float64).ravel(order="C") for name, var in variables.items()}

    maps = _direct_maps(inverse, variables, n, probe, rng)
    if maps is None:  # one probe per coordinate of x (each inverts every constraint's dual: slow)
        columns: dict[str, list[np.ndarray]] = {name: [] for name in variables}
        for j in range(n + 1):
            x = np.zeros(n)
            if j < n:
                x[j] = 1.0
            for name, value in probe(x).items():
                columns[name].append(value)
        maps = {name: np.array(cols).T for name, cols in columns.items()}
    unpack: dict[str, np.ndarray] = {}
    for name, mat in maps.items():  # (size of var, n + 1)
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
    if check:
        check_against_cvxpy(key, program, problem, params, variables, rng, chain, inverse)
    return program


def _direct_maps(inverse: Any, variables: Mapping[str, Any], n: int, probe: Any,
                 rng: np.random.Generator) -> dict[str, np.ndarray] | None:
    """The variables' maps from the solver's ``x`` when each is a plain block of it, or None.

    A variable that no reduction rewrote sits at an offset of ``x`` in column-major order
    (the stuffing's ``var_offsets``): then its map is a selection, confirmed by probing ``x = 0``
    and one random ``x`` through cvxpy's own inversion (a different linear map agrees with a
    selection on a random vector with probability 0). Probing each coordinate instead costs a
    full inversion per coordinate, minutes for programs with a few thousand of them.
    """
    offsets = None
    for data in reversed(list(inverse)):
        found = getattr(data, "var_offsets", None)
        if found is not None:
            offsets = found
            break
    if offsets is None or any(var.id not in offsets for var in variables.values()):
        return None
    maps: dict[str, np.ndarray] = {}
    for name, var in variables.items():
        size = int(np.prod(var.shape)) if var.shape else 1
        start = int(offsets[var.id])
        if start + size > n:
            return None
        # entry i of the C-order ravel is x[start + (its column-major index)]
        column_major = np.arange(size).reshape(var.shape or (1,), order="F").ravel(order="C")
        mat = np.zeros((size, n + 1))
        mat[np.arange(size), start + column_major] = 1.0
        maps[name] = mat
    x = rng.normal(size=n)
    at_zero, at_x = probe(np.zeros(n)), probe(x)
    for name, mat in maps.items():
        if np.any(at_zero[name]) or not np.array_equal(at_x[name], mat[:, :n] @ x):
            return None
    return maps


def check_against_cvxpy(key: str, program: ProgramData, problem: Any, params: Mapping[str, Any],
                         variables: Mapping[str, Any], rng: np.random.Generator, chain: Any, inverse: Any) -> None:
    """The stored form gives Clarabel cvxpy's data bit for bit, reads variables back as cvxpy does,
    and one solve both ways gives the same status and point."""
    import cvxpy as cp
    from types import SimpleNamespace

    
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
