"""The floating-point platform a search ran on: recorded beside a result, for information only.

Every ``certified`` is decided by an exact rational check, so it is sound on any machine. The
searches that find the certificates start from floating-point numbers whose last bits differ
between machines: numpy dispatches its array loops by CPU (SSE, AVX2, AVX-512), and OpenBLAS
(bundled with numpy and with scipy, whose copy Clarabel uses for its PSD cones) picks a kernel by
CPU (Nehalem, Haswell, SkylakeX, an ARM one, ...). lyapcheck leaves both as the host process has
them: it sets no environment variable and no numpy option. Instead each search is built so that
its status does not depend on those last bits and its figures move at most by the tolerances of
:mod:`lyapcheck.tolerances` (``tests/test_verdicts_unchanged.py`` runs the verdict snapshot on a
second, emulated platform). A certificate file, re-checked exactly by ``lyapcheck verify``, is
what reproduces a result on another machine.

:func:`describe` names the platform for certificates and sweep stores (``versions.floating_point``):
numpy's SIMD groups in use and the kernel of numpy's OpenBLAS (scipy's copy, loaded later if at
all, picks its kernel by the same rules). Nothing compares it.
"""

from __future__ import annotations

import importlib
import os
import sys
from pathlib import Path
from typing import Sequence

#: OpenBLAS's "which kernel" function in the libraries numpy and scipy bundle (and plain OpenBLAS)
_CORENAME_FUNCTIONS = ("scipy_openblas_get_corename64_", "scipy_openblas_get_corename", "openblas_get_corename")


def _numpy_simd() -> str:
    """numpy's baseline and the dispatched SIMD groups this CPU (and ``NPY_DISABLE_CPU_FEATURES``) enables."""
    try:
        umath = importlib.import_module("numpy._core._multiarray_umath")
    except ImportError:  # pragma: no cover - numpy < 2 or an unusual build
        return "unknown"
    features = getattr(umath, "__cpu_features__", {})
    used = [*getattr(umath, "__cpu_baseline__", []),
            *(name for name in getattr(umath, "__cpu_dispatch__", []) if features.get(name))]
    return "+".join(used) or "none"


def _openblas_kernels() -> list[str]:
    """The kernel of the OpenBLAS bundled with numpy (loaded with numpy itself).

    Only a library this process has loaded is asked (``RTLD_NOLOAD``): describing the platform
    loads nothing, and says the same whatever else was imported before (a sweep store records it,
    and its bytes must not depend on that). Empty where the names or the flag do not exist (another
    BLAS, macOS' Accelerate).
    """
    import ctypes

    noload = getattr(os, "RTLD_NOLOAD", None)
    location = getattr(sys.modules.get("numpy"), "__file__", None)
    if noload is None or location is None:  # pragma: no cover - not on Linux or macOS
        return []
    out = []
    for lib in sorted(Path(location).parent.parent.joinpath("numpy.libs").glob("lib*openblas*")):
        try:
            handle = ctypes.CDLL(str(lib), mode=noload)
        except OSError:
            continue  # not loaded in this process
        for name in _CORENAME_FUNCTIONS:
            function = getattr(handle, name, None)
            if function is not None:
                function.restype = ctypes.c_char_p
                out.append(f"{function().decode(errors='replace')} (numpy)")
                break
    return out


def describe() -> str:
    """One line: numpy's SIMD groups in use and the OpenBLAS kernels (for information only)."""
    if "numpy" not in sys.modules:
        return "numpy not loaded"
    import numpy

    kernels = _openblas_kernels()
    return f"numpy {numpy.__version__} SIMD {_numpy_simd()}; OpenBLAS " + (", ".join(kernels) or "not identified")


def installed_versions(names: Sequence[str]) -> dict[str, str | None]:
    """The installed version of each distribution, read from the name of its ``.dist-info``
    directory on ``sys.path`` (``numpy-2.4.6.dist-info``: the wheel format fixes that name), None
    where there is none. ``importlib.metadata`` answers the same but its import alone (the email
    parser it reads METADATA with) took 60 ms, a sixth of a whole ``certify`` of a small model."""
    wanted = {name.replace("-", "_").lower(): name for name in names}
    found: dict[str, str | None] = {name: None for name in names}
    for entry in sys.path:
        try:
            listing = os.listdir(entry or ".")
        except OSError:
            continue
        for item in listing:
            if not item.endswith(".dist-info"):
                continue
            dist, _, version = item[: -len(".dist-info")].partition("-")
            key = dist.replace("-", "_").replace(".", "_").lower()
            if key in wanted and found[wanted[key]] is None and version:
                found[wanted[key]] = version
    return found


def package_versions() -> dict[str, str]:
    """The packages whose versions decide what a search finds, and the floating-point platform
    (:func:`lyapcheck.numerics.describe`), for information only: a certificate re-checks exactly
    anywhere, and figures from two platforms agree within :mod:`lyapcheck.tolerances`."""
    names = ("lyapcheck", "sympy", "numpy", "cvxpy", "clarabel", "control")
    found = installed_versions(names)
    out = {"floating_point": describe()}
    for name in names:
        version = found[name]
        if version is None:  # not installed as a wheel's directory (an egg, a zip): ask importlib
            from importlib import metadata

            try:
                version = metadata.version(name)
            except metadata.PackageNotFoundError:  # pragma: no cover
                version = "absent"
        out[name] = version
    return out
