"""lyapcheck leaves its host's floating-point platform alone, and records it for information only."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
#: the variables that select numpy's SIMD loops and OpenBLAS's kernel (the sandbox sets some)
PLATFORM_VARIABLES = ("NPY_DISABLE_CPU_FEATURES", "OPENBLAS_CORETYPE", "OPENBLAS_L2_SIZE", "LYAPCHECK_NATIVE_FLOATS")

#: numpy's view of the platform, from a process that imported numpy only or lyapcheck first
PROBE = """
import json, os, sys
{first}
import numpy as np
from numpy._core._multiarray_umath import __cpu_features__
{after}
print(json.dumps({{"features": __cpu_features__, "environ": {{k: os.environ.get(k) for k in {variables!r}}},
                  "errstate": np.geterr(), "printoptions": {{k: str(v) for k, v in np.get_printoptions().items()}},
                  "platform": __import__("lyapcheck.numerics", fromlist=["describe"]).describe()}}))
"""


def _probe(first: str = "", after: str = "", env_extra: dict[str, str] | None = None) -> dict[str, object]:
    env = {k: v for k, v in os.environ.items() if k not in PLATFORM_VARIABLES}
    env.update(env_extra or {})
    code = PROBE.format(first=first, after=after, variables=PLATFORM_VARIABLES)
    out = subprocess.run([sys.executable, "-c", code], cwd=ROOT, env=env, capture_output=True, text=True, check=True)
    return json.loads(out.stdout)


@pytest.mark.slow
def test_importing_and_running_lyapcheck_changes_neither_the_environment_nor_numpy() -> None:
    """Issue 24: importing lyapcheck used to pin numpy to its AVX2 loops and OpenBLAS to its
    Haswell kernel for the whole process, which slowed the user's own numpy code."""
    plain = _probe()
    certify = "from lyapcheck import certify; certify('examples/paper.toml', classes='quick')"
    with_lyapcheck = _probe(first="import lyapcheck", after=certify)
    assert with_lyapcheck["features"] == plain["features"]  # the same SIMD loops are dispatched
    assert with_lyapcheck["environ"] == plain["environ"] == {k: None for k in PLATFORM_VARIABLES}
    assert with_lyapcheck["errstate"] == plain["errstate"]
    assert with_lyapcheck["printoptions"] == plain["printoptions"]


def test_the_platform_description_follows_the_host_settings() -> None:
    """``describe`` reports what numpy and OpenBLAS run on, as the process's own settings chose it."""
    native = _probe(after="np.ones((3, 3)) @ np.ones((3, 3))")
    assert str(native["platform"]).startswith("numpy ") and " SIMD " in str(native["platform"])
    emulated = _probe(after="np.ones((3, 3)) @ np.ones((3, 3))",
                      env_extra={"NPY_DISABLE_CPU_FEATURES": "X86_V3 X86_V4 AVX512_ICL", "OPENBLAS_CORETYPE": "Nehalem"})
    if os.uname().machine == "x86_64":
        assert "X86_V3" not in str(emulated["platform"]) and "Nehalem (numpy)" in str(emulated["platform"])


def test_certificates_and_stores_record_the_platform_beside_the_versions() -> None:
    from lyapcheck import numerics
    from lyapcheck.paper.certificate import package_versions
    from sweeps.store import versions

    assert package_versions()["floating_point"] == numerics.describe() == versions()["floating_point"]


def test_a_sweep_store_resumes_on_another_floating_point_platform_but_not_with_other_packages(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """The platform is information: a sweep started on one machine may be finished on another.
    A package version still decides (it may change what a search finds)."""
    import zarr

    from sweeps import store
    from sweeps.spec import parse_spec
    from tests.test_sweeps import spec_text

    spec = parse_spec(spec_text())
    target = tmp_path / "store.zarr"
    store.Store.open_or_create(target, spec)
    written = json.loads(str(zarr.open_group(str(target), mode="r").attrs["versions"]))
    assert written["floating_point"] == store.versions()["floating_point"]
    real = store.versions
    monkeypatch.setattr(store, "versions", lambda: {**real(), "floating_point": "numpy 9 SIMD NEON; OpenBLAS ARMV8"})
    store.Store.open_or_create(target, spec)  # resumes
    monkeypatch.setattr(store, "versions", lambda: {**real(), "numpy": "0.0"})
    with pytest.raises(Exception, match=r"other package versions \(numpy\)"):
        store.Store.open_or_create(target, spec)
