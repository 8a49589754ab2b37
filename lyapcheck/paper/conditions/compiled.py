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
from typing import Any, Callable, Final

import numpy as np

from lyapcheck.sos.compile import FORMAT_VERSION, compile_problem
from lyapcheck.sos.sdp import CompiledProgram, ProgramData

log = logging.getLogger(__name__)

STORE: Final = Path(__file__).with_name("_compiled")

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
    "sos_bound_fixed": ("lyapcheck.paper.conditions.sos_bound", "build_fixed_program"),
    "sos_bound_parity_fixed": ("lyapcheck.paper.conditions.sos_bound", "build_parity_fixed_program"),
    "level": ("lyapcheck.paper.conditions.saturated", "build_level_program"),
    "level_margin": ("lyapcheck.paper.conditions.saturated", "build_level_margin_program"),
    "ges": ("lyapcheck.paper.conditions.ges", "build_program"),
    "ges_param": ("lyapcheck.paper.boxes.ges_param", "build_program"),
}
#: the programs stored in ``_compiled/`` (others are compiled in-process on first use)
PROGRAMS: Final = ("prop41", "sector", "sector_8", "ultimate", "sos_4", "sos_6", "sos_bound", "sos_bound_parity",
                   "sos_bound_fixed", "sos_bound_parity_fixed", "level_4", "level_6",
                   "level_margin_4", "level_margin_6", "ges_4_1",
                   "ges_param_6_1_1", "ges_param_6_1_2")
# (ges_param_6_1_3, a box over three of the ges entries, is 1.1 MB stored and compiles in about 6 s
# on first use: it is left to that)


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


def compile_program(key: str) -> ProgramData:
    """Compile ``key`` with cvxpy into :class:`ProgramData`, checked against cvxpy on random data."""
    problem, params, variables = build(key)
    return compile_problem(key, problem, params, variables)


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
