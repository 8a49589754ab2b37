"""lyapcheck: machine-checked stability answers for the ILOS/ODS microswimmer paper.

The Python API (``docs/api.md``)::

    from lyapcheck import certify, certify_box, verify, simulate, sweep, report

Each function does what the command of the same name does and returns a typed result with
``to_json()``; heavy libraries load only when a function runs.

Importing the package pins the floating-point platform (:mod:`lyapcheck.numerics`) before
numpy loads, so that two x86-64 machines find the same certificates.
"""

from lyapcheck import numerics

numerics.pin()

from lyapcheck.api import (  # noqa: E402  (after the pin: numpy must not load before it)
    CertifyResult, Check, SimulationReport, SweepResult, VerifyResult, certify, certify_box, report, simulate, sweep,
    verify,
)

__all__ = ["certify", "certify_box", "verify", "simulate", "sweep", "report", "CertifyResult", "VerifyResult", "Check",
           "SimulationReport", "SweepResult"]
