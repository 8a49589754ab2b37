"""lyapcheck: machine-checked stability and safety answers for polynomial and rational closed loops.

Any closed loop given as a model file (``docs/model-files.md``); the worked example is the ILOS/ODS
microswimmer paper's loop.

The Python API (``docs/api.md``)::

    from lyapcheck import certify, certify_box, verify, simulate, sweep, report

Each function does what the command of the same name does and returns a typed result with
``to_json()``; heavy libraries load only when a function runs.
"""

from lyapcheck.api import (
    CertifyResult, Check, SimulationReport, SweepResult, VerifyResult, certify, certify_box, report, simulate, sweep,
    verify,
)

__all__ = ["certify", "certify_box", "verify", "simulate", "sweep", "report", "CertifyResult", "VerifyResult", "Check",
           "SimulationReport", "SweepResult"]
