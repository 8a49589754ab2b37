"""The pinned floating-point platform (lyapcheck.numerics): on, off, and what it changes."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

from lyapcheck import numerics

ROOT = Path(__file__).resolve().parents[1]
X86_WITH_AVX2 = numerics._cpu_has_avx2_and_fma() and os.uname().machine == "x86_64"

#: prints what the pin decided, numpy's AVX-512 group as numpy sees it, OpenBLAS's kernel
#: variable, and whether an array power equals the scalar power at every node of ges's grid
PROBE = """
import json, sys
{before}
import lyapcheck, numpy as np, os
from numpy._core._multiarray_umath import __cpu_features__
from lyapcheck.paper.conditions import ges
w = ges._Program(ges.TERMS, ges.GRID_POINTS).nodes
same = all(bool(np.array_equal(w ** k, np.array([x ** k for x in w]))) for k in range(1, 9))
print(json.dumps({{"state": lyapcheck.numerics.describe(), "x86_v4": __cpu_features__.get("X86_V4"),
                  "openblas": os.environ.get("OPENBLAS_CORETYPE"), "power_same": same}}))
"""


def _probe(env_extra: dict[str, str], before: str = "") -> dict[str, object]:
    env = {k: v for k, v in os.environ.items()
           if k not in ("NPY_DISABLE_CPU_FEATURES", "OPENBLAS_CORETYPE", numerics.OPT_OUT)}
    env.update(env_extra)
    out = subprocess.run([sys.executable, "-c", PROBE.format(before=before)], cwd=ROOT, env=env,
                         capture_output=True, text=True, check=True)
    return json.loads(out.stdout)


@pytest.mark.skipif(not X86_WITH_AVX2, reason="the pin acts on x86-64 machines with AVX2 and FMA")
def test_importing_lyapcheck_pins_numpy_to_avx2_and_openblas_to_haswell() -> None:
    got = _probe({})
    assert str(got["state"]).startswith("pinned")
    assert got["x86_v4"] is False  # numpy's AVX-512 loops are off
    assert got["openblas"] == numerics.OPENBLAS_KERNEL
    assert got["power_same"] is True  # the AVX2 array power is the scalar one, bit for bit


@pytest.mark.skipif(not X86_WITH_AVX2, reason="the pin acts on x86-64 machines with AVX2 and FMA")
def test_the_pin_yields_to_the_user_unless_overridden_and_cannot_act_after_numpy() -> None:
    assert _probe({"OPENBLAS_CORETYPE": "Zen"})["openblas"] == "Zen"  # the user's choice stands
    # ... unless overridden, as the test suite does (its snapshot needs the pinned kernel)
    forced = _probe({"OPENBLAS_CORETYPE": "Zen"}, before="from lyapcheck import numerics; numerics.pin(override=True)")
    assert forced["openblas"] == numerics.OPENBLAS_KERNEL and str(forced["state"]).startswith("pinned")
    off = _probe({numerics.OPT_OUT: "1"})
    assert off["state"] == f"native ({numerics.OPT_OUT} is set)" and off["openblas"] is None
    late = _probe({}, before="import numpy")
    assert late["state"] == "native (numpy was imported before lyapcheck)" and late["openblas"] is None


def test_the_suite_runs_pinned_and_documents_say_on_what_platform() -> None:
    """conftest imports lyapcheck before numpy, so the verdict snapshot compares like with like;
    certificates and sweep stores record the platform beside the package versions."""
    from lyapcheck.certificate import package_versions
    from sweeps.store import versions

    if X86_WITH_AVX2:
        assert numerics.describe().startswith("pinned")
    assert package_versions()["floating_point"] == numerics.describe() == versions()["floating_point"]
