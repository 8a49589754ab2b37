"""The simulations a certificate report shows: the full saturated ILOS/ODS loop at its gains.

The figures are of the real closed loop (the toolkit's derived ODS controller, saturated at the
step-out frequency), whatever dynamics the certificate was computed for: a certificate of the
dynamics *as printed* is thereby confronted with the loop it claims to describe.

Initial conditions: the paper's start ``p0 = (0, -40 mm)`` (Section 5), plus its mirror image
and a start at half the distance, all with ``s(0) = 0``; the first is the one the time plots show.
The disturbance is constant, of the certificate's bound ``d*`` and perpendicular to the path,
pushing to the right of it (for ``theta_r = 0``: the paper's sinking velocity ``(0, -d*)``).
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass, field
from typing import Any, Final, Sequence

import numpy as np

from lyapcheck.errors import LyapcheckError

log = logging.getLogger(__name__)

#: initial positions (m), the paper's first
INITIAL_POSITIONS: Final = ((0.0, -0.040), (0.0, 0.040), (0.0, -0.020))
HORIZON_S: Final = 100.0
TAIL_S: Final = 10.0
RTOL: Final = 1e-8
RECORD_DT_S: Final = 0.05


@dataclass(frozen=True)
class LoopRun:
    """Recorded trajectories (``trajectories[0]`` is the paper's start) and their measurements."""

    trajectories: Sequence[Any]
    measurements: Sequence[dict[str, Any]]
    omega_so_rad_s: float
    theta_r_rad: float
    horizon_s: float
    tail_s: float
    settings: dict[str, Any] = field(default_factory=dict)


def simulate_certificate(doc: dict[str, Any]) -> LoopRun:
    """Simulate the closed loop at the inputs of a certificate document.

    Raises
    ------
    LyapcheckError
        When the inputs do not describe a problem the simulator accepts (the report shows why).
    """
    from lyapcheck.params import build_problem
    from lyapcheck.simulation.integrator import INTEGRATOR_NAME
    from lyapcheck.simulation.disturbances import Constant
    from lyapcheck.simulation.model import LoopParams
    from lyapcheck.simulation.runner import simulate

    inputs = doc.get("inputs")
    given = inputs.get("given") if isinstance(inputs, dict) else None
    if not isinstance(given, dict):
        raise LyapcheckError("the certificate has no 'inputs.given' table to simulate")
    try:
        problem = build_problem({str(k): v for k, v in given.items()}, source="the certificate's inputs")
    except ValueError as exc:
        raise LyapcheckError(f"cannot simulate the certificate's inputs: {exc}") from None
    theta = float(problem.theta_r)
    d_max = float(problem.disturbance_bound())
    # perpendicular to the path, to its right: (sin theta, -cos theta) d*
    push = (d_max * math.sin(theta), -d_max * math.cos(theta))
    n = len(INITIAL_POSITIONS)
    params = LoopParams.from_problem(problem, controller="ilos", n=n)
    p0 = np.array([[x * math.cos(theta) - z * math.sin(theta), x * math.sin(theta) + z * math.cos(theta)]
                   for x, z in INITIAL_POSITIONS])
    result = simulate(params, p0=p0, s0=np.zeros(n), disturbance=Constant(np.array(push)),
                      horizon=HORIZON_S, tail=TAIL_S, form="derived", rtol=RTOL,
                      record=list(range(n)), record_dt=RECORD_DT_S)
    assert result.trajectories is not None  # recorded above; for the type checker
    rows = [result.measurements.row(i) for i in range(n)]
    settings = {
        "controller": "ILOS with the derived ODS law, saturated at the step-out frequency",
        "integrator": f"{INTEGRATOR_NAME}, rtol = {RTOL:g}",
        "initial_positions_m": [list(p) for p in p0.tolist()],
        "initial_s_m": 0.0,
        "horizon_s": HORIZON_S,
        "tail_window_s": [HORIZON_S - TAIL_S, HORIZON_S],
        "disturbance_m_per_s": list(push),
    }
    return LoopRun(result.trajectories, rows, float(problem.actuation.step_out()), theta, HORIZON_S, TAIL_S,
                   settings)
