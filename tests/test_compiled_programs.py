"""The stored compiled programs are current, and solve exactly as cvxpy would (issue 11).

:mod:`lyapcheck.paper.conditions.compiled` stores each certificate program's conic data as arrays so
that ``certify`` needs no cvxpy at run time. These tests recompile every program with cvxpy:
the stored arrays must be the ones cvxpy produces now (else run
``python -m lyapcheck.paper.conditions.compiled``), and the compiler itself checks, on random data,
that Clarabel receives cvxpy's data bit for bit and that the variables read back as cvxpy reads
them.
"""

from __future__ import annotations

import numpy as np
import pytest

from lyapcheck.paper.conditions import compiled


@pytest.mark.parametrize("key", sorted(compiled.PROGRAMS))
def test_stored_program_is_current(key: str) -> None:
    path = compiled.STORE / f"{key}.npz"
    assert path.exists(), f"missing {path}: run python -m lyapcheck.paper.conditions.compiled"
    with np.load(path, allow_pickle=False) as stored:
        assert str(stored["source_hash"]) == compiled.source_hash(key), \
            f"{key} is stale: run python -m lyapcheck.paper.conditions.compiled"
        fresh = compiled.compile_program(key).arrays  # also checks itself against cvxpy
        assert set(fresh) == set(stored.files) - {"source_hash"}
        for name, value in fresh.items():
            assert np.array_equal(np.asarray(value), stored[name]), (key, name)


def test_loaded_program_solves_like_cvxpy() -> None:
    """The sector program at the paper's derived vertices: same status, same point, bit for bit."""
    from fractions import Fraction

    from lyapcheck.paper.certification import build_system
    from lyapcheck.paper.conditions import scaling, sector
    from lyapcheck.sos.sdp import solve
    from lyapcheck.paper.params import problem_from_sources
    from tests.conftest import EASY_GAINS, PAPER_TOML

    system = build_system(problem_from_sources(PAPER_TOML, EASY_GAINS), "derived")
    vertices = [system.vertex(Fraction(0)), system.vertex(system.rho_sup)]
    sc = scaling.choose(vertices)
    values = {"A_lo": sc.matrix_to_scaled(vertices[0]), "A_hi": sc.matrix_to_scaled(vertices[1])}
    direct = sector.program().solve(values)
    problem, params, variables = compiled.build("sector")
    for name, p in params.items():
        p.value = values[name]
    report = solve(problem)
    assert direct.report.raw_status == report.raw_status == "optimal"
    assert direct.values is not None
    for name, var in variables.items():
        assert np.array_equal(np.asarray(var.value), direct.values[name]), name
    assert direct.report.iterations == report.iterations


def test_parameters_are_checked_by_name_and_shape() -> None:
    from lyapcheck.paper.conditions import sector

    prog = sector.program()
    with pytest.raises(ValueError, match="missing"):
        prog.solve({"A_lo": np.eye(2)})
    with pytest.raises(ValueError, match="must have shape"):
        prog.solve({"A_lo": np.eye(2), "A_hi": np.eye(3)})


def test_a_stale_stored_program_is_recompiled(monkeypatch: pytest.MonkeyPatch) -> None:
    compiled.load.cache_clear()
    monkeypatch.setattr(compiled, "source_hash", lambda key: "not the stored hash")
    try:
        program = compiled.load("sector")  # compiled in-process with cvxpy, not read from the file
        assert program.data.key == "sector"
        stored = np.load(compiled.STORE / "sector.npz", allow_pickle=False)
        assert np.array_equal(program.data.arrays["R_data"], stored["R_data"])
    finally:
        compiled.load.cache_clear()


_LEAN_SOLVE = """
import json, sys
import numpy as np
from lyapcheck.sos import sdp
sdp.LEAN_LAPACK_IMPORT = {lean}
from lyapcheck.paper.certification import run_conditions
from lyapcheck.paper.params import problem_from_sources
# ultimate_bound solves 3x3 LMIs: Clarabel needs BLAS and LAPACK for them
result = run_conditions(problem_from_sources({toml!r}, {{}}), "derived", ("ultimate_bound",))["ultimate_bound"]
linalg_loaded = "scipy.linalg" in sys.modules
import scipy.linalg  # the real package still imports and works afterwards
eig = scipy.linalg.eigh(np.diag([2.0, 1.0]))[0].tolist()
print(json.dumps({{"linalg_loaded": linalg_loaded, "eig": eig, "status": result.status,
                  "numbers": result.numbers, "certificate": result.certificate}}, default=str))
"""


def test_the_command_lines_lean_lapack_import_solves_bit_for_bit_like_the_usual_one() -> None:
    """``certify`` on the command line loads SciPy's BLAS/LAPACK modules for Clarabel without the
    ``scipy.linalg`` package (sdp._load_lapack_modules): same solution bit for bit, scipy.linalg
    not imported by the solve, and a later ``import scipy.linalg`` still works."""
    import json
    import subprocess
    import sys

    from tests.conftest import PAPER_TOML

    runs = {lean: json.loads(subprocess.run([sys.executable, "-c", _LEAN_SOLVE.format(lean=lean, toml=str(PAPER_TOML))],
                                            check=True, capture_output=True, text=True).stdout)
            for lean in (True, False)}
    assert runs[True]["linalg_loaded"] is False and runs[False]["linalg_loaded"] is True
    assert runs[True]["eig"] == [1.0, 2.0]
    assert runs[True]["certificate"] and runs[True]["numbers"]["eps_bound_m"] > 0
    for key in ("status", "numbers", "certificate"):
        assert runs[True][key] == runs[False][key], key
