"""The simulations a certificate report shows: the full saturated ILOS/ODS loop at its gains.

The figures are of the real closed loop (the toolkit's derived ODS controller, saturated at the
step-out frequency), whatever dynamics the certificate was computed for: a certificate of the
dynamics *as printed* is thereby confronted with the loop it claims to describe.

Initial conditions: the paper's start ``p0 = (0, -40 mm)`` (Section 5), plus its mirror image
and a start at half the distance, all with ``s(0) = 0``; the first is the one the time plots show.
The disturbance is constant, of the certificate's bound ``d*`` and perpendicular to the path,
pushing to the right of it (for ``theta_r = 0``: the paper's sinking velocity ``(0, -d*)``).

The worst case. A certificate made with ``lyapcheck certify --worst-case`` carries, beside each
certified ultimate bound, the worst disturbance the search of
:mod:`lyapcheck.paper.simulation.worst_case` found (its JSON description) and its tail
``sup |eps|``. It is re-simulated here, from both of the search's initial states (the origin
and the paper's start; the document does not say which one won), in the same batched call as
the three trajectories above when the settings agree (they do: the search uses the
``paper-ilos`` settings, which are these). That adds about 1.6 s at the paper's gains (the call
takes 0.7 s for the three converging trajectories alone; the square wave's rows need many more
steps). Each trajectory of the batch has its own steps, so the figure is the search's own: the
worse of the two starts is drawn and its tail ``sup |eps|`` set beside the stored one. Without those numbers no search is
run (even the smallest one takes 6-7 s at the paper's gains, as long as the whole report):
the figure says how to get it.
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
class WorstCaseRun:
    """The worst disturbance of a certificate's search, re-simulated (SI).

    Attributes
    ----------
    disturbance
        Its JSON description as stored (``kind``, parameters, ``family``).
    trajectory
        The recorded trajectory from ``start``.
    start
        ``"origin"`` or ``"preset"`` (the paper's start): the one with the larger tail sup.
    sup_abs_eps_tail_m
        Tail ``sup |eps|`` of that trajectory, measured here.
    stored_sup_abs_eps_tail_m
        What the certificate says (``worst_case_sup_abs_eps_tail_m``), None if absent.
    per_start
        Tail ``sup |eps|`` from each initial state.
    """

    disturbance: dict[str, Any]
    trajectory: Any
    start: str
    sup_abs_eps_tail_m: float
    stored_sup_abs_eps_tail_m: float | None
    per_start: dict[str, float]


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
    worst: WorstCaseRun | None = None
    #: why there is no worst-case trajectory (when ``worst`` is None)
    worst_reason: str = ""


#: the bound classes whose numbers may carry the worst case (lyapcheck.api.add_tightness)
BOUND_CLASSES: Final = ("sos_bound", "ultimate_bound")


def stored_worst_case(doc: dict[str, Any]) -> tuple[dict[str, Any], float | None] | None:
    """The worst disturbance stored in a certificate (description, its tail sup), or None."""
    conditions = doc.get("conditions")
    for name in BOUND_CLASSES:
        cond = conditions.get(name) if isinstance(conditions, dict) else None
        if not isinstance(cond, dict):
            continue
        desc, sup = cond.get("worst_case_disturbance"), cond.get("worst_case_sup_abs_eps_tail_m")
        if isinstance(desc, dict) and isinstance(desc.get("kind"), str):
            return desc, float(sup) if isinstance(sup, (int, float)) and not isinstance(sup, bool) else None
    return None


def simulate_certificate(doc: dict[str, Any]) -> LoopRun:
    """Simulate the closed loop at the inputs of a certificate document.

    Raises
    ------
    LyapcheckError
        When the inputs do not describe a problem the simulator accepts (the report shows why).
    """
    from lyapcheck.paper.params import build_problem
    from lyapcheck.integrator import INTEGRATOR_NAME, STATUS_OK
    from lyapcheck.paper.simulation.disturbances import Constant, Disturbance, from_description, stack_rows
    from lyapcheck.paper.simulation.model import LoopParams
    from lyapcheck.paper.simulation.runner import simulate
    from lyapcheck.paper.simulation.scenarios import Scenario

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
    p0 = [[x * math.cos(theta) - z * math.sin(theta), x * math.sin(theta) + z * math.cos(theta)]
          for x, z in INITIAL_POSITIONS]
    s0 = [0.0] * n
    dists: list[Disturbance] = [Constant(np.array(push))] * n
    # the worst case of the certificate's search, from the search's two initial states (module docstring)
    stored = stored_worst_case(doc)
    worst_reason = ("the certificate carries no worst-case search (make it with `lyapcheck certify --worst-case` "
                    "to draw the worst disturbance found)")
    starts: dict[str, tuple[list[float], float]] = {}
    if stored is not None:
        scenario = Scenario(name="worst-case", problem=problem)  # what search_worst_case uses for a Problem
        same = (scenario.controller, scenario.form, scenario.horizon, scenario.tail, scenario.rtol, scenario.band,
                tuple(scenario.d_hat)) == ("ilos", "derived", HORIZON_S, TAIL_S, RTOL, None, (0.0, 0.0))
        try:
            worst_dist = from_description(stored[0])
        except (LyapcheckError, ValueError, TypeError, KeyError) as exc:
            worst_reason = f"the stored worst-case disturbance cannot be rebuilt: {exc}"
        else:
            if same:
                starts = {"origin": ([0.0, 0.0], 0.0), "preset": ([float(v) for v in scenario.p0], float(scenario.s0))}
                for p, s in starts.values():
                    p0.append(p)
                    s0.append(s)
                    dists.append(worst_dist)
            else:
                worst_reason = "the worst-case search used settings other than this simulation's"
    total = len(p0)
    params = LoopParams.from_problem(problem, controller="ilos", n=total)
    result = simulate(params, p0=np.array(p0), s0=np.array(s0), disturbance=stack_rows(dists),
                      horizon=HORIZON_S, tail=TAIL_S, form="derived", rtol=RTOL,
                      record=list(range(total)), record_dt=RECORD_DT_S)
    assert result.trajectories is not None  # recorded above; for the type checker
    rows = [result.measurements.row(i) for i in range(n)]
    worst = None
    if starts and stored is not None:
        m = result.measurements
        sups = {name: float(m.sup_abs_eps_tail_m[n + k]) for k, name in enumerate(starts)}
        # a failed integration measured nothing: it cannot be a witness (as in the search)
        finite = {name: sups[name] for k, name in enumerate(starts)
                  if m.status[n + k] == STATUS_OK and math.isfinite(sups[name])}
        if finite:
            start = max(finite, key=lambda k: finite[k])
            worst = WorstCaseRun(dict(stored[0]), result.trajectories[n + list(starts).index(start)], start,
                                 finite[start], stored[1], sups)
        else:
            worst_reason = "the re-simulation of the stored worst-case disturbance failed"
    settings = {
        "controller": "ILOS with the derived ODS law, saturated at the step-out frequency",
        "integrator": f"{INTEGRATOR_NAME}, rtol = {RTOL:g}",
        "initial_positions_m": [list(p) for p in p0[:n]],
        "initial_s_m": 0.0,
        "horizon_s": HORIZON_S,
        "tail_window_s": [HORIZON_S - TAIL_S, HORIZON_S],
        "disturbance_m_per_s": list(push),
    }
    if worst is not None:
        settings["worst_case_disturbance"] = worst.disturbance
        settings["worst_case_initial_states_m"] = {k: {"position": p, "s": s} for k, (p, s) in starts.items()}
    return LoopRun(result.trajectories[:n], rows, float(problem.actuation.step_out()), theta, HORIZON_S, TAIL_S,
                   settings, worst, "" if worst is not None else worst_reason)
