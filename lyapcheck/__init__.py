"""lyapcheck: machine-checked stability and safety answers for polynomial and rational closed loops.

Any closed loop given as a model file (``docs/model-files.md``); the worked example is the ILOS/ODS
microswimmer paper's loop.

The Python API (``docs/api.md``)::

    from lyapcheck import certify, certify_box, verify, simulate, sweep, report
    from lyapcheck import Model, close_loop    # a model built in Python (sympy, python-control)

Each function does what the command of the same name does and returns a typed result with
``to_json()``; heavy libraries load only when a function runs.
"""

from lyapcheck.api import (
    CertifyResult, Check, SimulationReport, SweepResult, VerifyResult, certify, certify_box, report, simulate, sweep,
    verify,
)

from typing import Any

__all__ = ["certify", "certify_box", "verify", "simulate", "sweep", "report", "CertifyResult", "VerifyResult", "Check",
           "SimulationReport", "SweepResult", "Model", "close_loop"]


def __getattr__(name: str) -> Any:
    """``Model`` and ``close_loop``, imported on first use (the command line's start stays light)."""
    if name == "Model":
        from lyapcheck.models.language.build import Model

        return Model
    if name == "close_loop":
        from lyapcheck.models.language.build import close_loop

        return close_loop
    raise AttributeError(f"module 'lyapcheck' has no attribute {name!r}")
