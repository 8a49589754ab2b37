"""The type checker is part of the suite (STYLE.md): every package must pass mypy."""

from __future__ import annotations

import subprocess
import sys

import pytest

from tests.conftest import ROOT


@pytest.mark.slow
def test_mypy_passes_on_every_package() -> None:
    done = subprocess.run(
        [sys.executable, "-m", "mypy", "symbolic", "lyapcheck", "sweeps", "reports"],
        capture_output=True, text=True, cwd=ROOT, timeout=900,
    )
    assert done.returncode == 0, done.stdout[-4000:] + done.stderr[-2000:]
