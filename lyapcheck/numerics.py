"""The floating-point platform the searches run on, pinned so that machines agree.

Why: every ``certified`` is decided by an exact rational check, so it is sound on any
machine. But *which* certificate a search finds, and so a figure or, at a marginal gain set,
a status, follows the solver's floating-point path, and that path starts from numbers that
differ in the last bit between x86-64 machines:

- numpy dispatches its array loops by CPU: with AVX-512 (numpy's ``X86_V4``,
  ``AVX512_ICL``, ``AVX512_SPR`` groups) ``w**k`` over an array is a SIMD power that differs
  in the last bit from the scalar one, and from the AVX2 loop;
- OpenBLAS (bundled with numpy and with scipy) picks a kernel by CPU, and its small products
  round differently with the SkylakeX kernel than with the Haswell one.

Measured with ``tests/test_verdicts_unchanged.py`` (every class at 29 cases: the paper's gains,
the test suite's gain sets, 15 sweep points), against the figures of an AVX2 machine: an Intel
AVX-512 machine (numpy's AVX-512 loops, OpenBLAS's SkylakeX kernel) differed in 6 statuses
and 47 figures, an AMD AVX-512 machine (numpy's AVX-512 loops, the Haswell kernel) in 19
figures. The statuses were all ``sos_gas`` (and ``saturated_loop``, which quotes it) refusing a
solve that ended "inaccurate" on one machine only; it now lets the exact check judge such a
solve, and no status differs. With the pin below, the AMD machine gives every figure of the
AVX2 one; the Intel machine then runs the same numpy loops and the same OpenBLAS kernel.

So, before numpy is first imported, :func:`pin` asks numpy for its AVX2 (``X86_V3``) loops
and OpenBLAS for its Haswell kernel, which every x86-64 machine with AVX2 and FMA runs. An
environment variable the user has set is kept (the test suite alone overrides it:
``pin(override=True)``); ``LYAPCHECK_NATIVE_FLOATS=1`` turns the pin off. When numpy was
imported before lyapcheck (a notebook, a Dask worker), the pin cannot act and
:func:`describe` says so; results stay sound, figures may then differ from another machine's
in the ways above.
"""

from __future__ import annotations

import os
import platform
import sys
from importlib import metadata
from pathlib import Path

#: numpy's dispatch groups above AVX2 (numpy >= 2.4 names them so; naming one numpy does not
#: dispatch makes it warn at import, so older numpy is left alone)
NUMPY_GROUPS_ABOVE_AVX2 = "X86_V4 AVX512_ICL AVX512_SPR"
#: the OpenBLAS kernel every AVX2 + FMA machine runs
OPENBLAS_KERNEL = "Haswell"
OPT_OUT = "LYAPCHECK_NATIVE_FLOATS"

_state = "not pinned yet"


def _numpy_at_least_2_4() -> bool:
    try:
        major, minor = (int(part) for part in metadata.version("numpy").split(".")[:2])
    except (metadata.PackageNotFoundError, ValueError):
        return False
    return (major, minor) >= (2, 4)


def _cpu_has_avx2_and_fma() -> bool:
    """From ``/proc/cpuinfo`` (Linux); elsewhere unknown, so False and nothing is pinned."""
    try:
        text = Path("/proc/cpuinfo").read_text(errors="replace")
    except OSError:
        return False
    for line in text.splitlines():
        if line.startswith("flags"):
            flags = set(line.split(":", 1)[1].split())
            return {"avx2", "fma"} <= flags
    return False


def pin(*, override: bool = False) -> str:
    """Pin numpy's SIMD loops and OpenBLAS's kernel, if it can still take effect.

    Returns the state, also given by :func:`describe`. Called when :mod:`lyapcheck` is
    imported; a second call does nothing unless ``override``, which also replaces values the
    environment already holds (the test suite compares figures with a snapshot, so it must not
    take a kernel from the machine's environment: a sandbox may set ``OPENBLAS_CORETYPE``).
    """
    global _state
    if _state != "not pinned yet" and (not override or "numpy" in sys.modules):
        return _state  # once numpy runs, its platform is what the first call decided
    put = os.environ.__setitem__ if override else os.environ.setdefault
    if os.environ.get(OPT_OUT, "") not in ("", "0"):
        _state = f"native ({OPT_OUT} is set)"
    elif "numpy" in sys.modules:
        _state = "native (numpy was imported before lyapcheck)"
    elif platform.machine().lower() not in ("x86_64", "amd64") or not _cpu_has_avx2_and_fma():
        _state = "native (not an x86-64 machine with AVX2 and FMA)"
    else:
        pinned = []
        if _numpy_at_least_2_4():
            put("NPY_DISABLE_CPU_FEATURES", NUMPY_GROUPS_ABOVE_AVX2)
            pinned.append(f"numpy NPY_DISABLE_CPU_FEATURES={os.environ['NPY_DISABLE_CPU_FEATURES']!r}")
        put("OPENBLAS_CORETYPE", OPENBLAS_KERNEL)
        pinned.append(f"OpenBLAS OPENBLAS_CORETYPE={os.environ['OPENBLAS_CORETYPE']!r}")
        _state = "pinned: " + ", ".join(pinned)
    return _state


def describe() -> str:
    """One line: whether the floating-point platform is pinned, and how (or why not)."""
    return _state
