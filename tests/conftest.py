"""Shared fixtures: the paper's problem and a gain set where Proposition 4.1 is certifiable."""

from __future__ import annotations

import importlib.util
import os
import sys
import tempfile
from pathlib import Path
from types import ModuleType

import numpy as np
import pytest

from lyapcheck.paper.params import Problem, problem_from_sources
from lyapcheck.integrator import Evaluation

# the suite's unit-factor memo (lyapcheck.units) lives in a fresh directory, not the user's cache:
# the fuzz tests parse hundreds of odd unit strings (subprocesses inherit this)
os.environ.setdefault("LYAPCHECK_CACHE_DIR", tempfile.mkdtemp(prefix="lyapcheck-test-cache-"))
# every test searches (a certificate stored by an earlier test would skip the solves some tests
# look at); tests/test_certificate_store.py turns the store on where it tests it
os.environ["LYAPCHECK_CERTIFICATE_STORE"] = "off"

ROOT = Path(__file__).resolve().parents[1]
PAPER_TOML = ROOT / "examples" / "paper.toml"

#: gains far from the paper's where eq:stabCond is feasible (k_d Delta large against 1/U)
EASY_GAINS = {"gains.alpha_d": "1", "gains.sigma0": "0.1", "gains.k_d": "5", "gains.delta_los": "1 m",
              "swimmer.e11": "1 m"}


def benchmark_module(stem: str) -> ModuleType:
    """``benchmarks/<stem>.py`` as a module, registered in ``sys.modules`` (a dataclass of it needs that),
    loaded once: the tests that check a benchmark's own derivations import it this way."""
    if stem not in sys.modules:
        spec = importlib.util.spec_from_file_location(stem, ROOT / "benchmarks" / f"{stem}.py")
        assert spec is not None and spec.loader is not None
        module = importlib.util.module_from_spec(spec)
        sys.modules[stem] = module
        spec.loader.exec_module(module)
    return sys.modules[stem]


@pytest.fixture(scope="session")
def paper_problem() -> Problem:
    return problem_from_sources(PAPER_TOML, {})


@pytest.fixture(scope="session")
def easy_problem() -> Problem:
    return problem_from_sources(PAPER_TOML, EASY_GAINS)

#: fixed (non-swept) parameters of the sweep test specs: the paper's values
SWEEP_FIXED = """
[gains]
sigma0 = 0.01
delta_los = "0.75 mm"
[swimmer]
e11 = "9.3e-5 m"
n_turns = 3.5
pitch_angle = "45 deg"
helix_radius = "420 um"
weight = "8.7e-5 N"
[actuation]
omega_so = "2.8 Hz"
[disturbance]
d_max = "0.088 mm/s"
"""


class DecaySystem:
    """``y' = -lam y``, one row per rate: a minimal batched system for the integrator's contract
    (stiff for a large ``lam``)."""

    def __init__(self, lam: np.ndarray) -> None:
        self.lam = lam

    @property
    def size(self) -> int:
        return int(self.lam.size)

    def rhs(self, t: np.ndarray, y: np.ndarray, t_segment: np.ndarray) -> Evaluation:
        return Evaluation(-self.lam[:, None] * y, np.abs(y[:, 0]), np.empty((y.shape[0], 0)))

    def take(self, index: np.ndarray) -> "DecaySystem":
        return DecaySystem(self.lam[index])

    def next_breakpoint(self, t: np.ndarray) -> np.ndarray:
        return np.full(t.shape, np.inf)
