"""Run scenarios (a preset or a scenario TOML) and build the ``simulate`` JSON document.

The library side of ``lyapcheck simulate`` (the command line only prints what
:func:`simulation_document` returns). Exit-code meaning lives with the caller: a document with
``"diverged": true`` is the negative answer (the tail of ``|eps|`` went beyond the initial
error, or the integrator failed, e.g. the printed ODS controller).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from lyapcheck.errors import InvalidParameter
from lyapcheck.integrator import INTEGRATOR_NAME, STATUS_OK
from lyapcheck.paper.simulation.model import LoopParams
from lyapcheck.paper.simulation.runner import SimulationResult, simulate
from lyapcheck.paper.simulation.scenarios import PRESETS, Scenario, load_scenario, problem_summary
from lyapcheck.paper.simulation.scenarios import preset as preset_scenario

def run_scenarios(scenarios: list[Scenario], *, record: bool = False) -> SimulationResult:
    """Simulate several scenarios of the same ODS form and horizon in one batched call."""
    first = scenarios[0]
    if any(s.form != first.form or s.horizon != first.horizon or s.tail != first.tail for s in scenarios):
        raise ValueError("The 'scenarios' parameter must share form, horizon and tail. Got different ones instead.")
    params = LoopParams.concat([LoopParams.from_problem(s.problem, controller=s.controller, d_hat=s.d_hat)
                                for s in scenarios])
    dists = [s.disturbance.build(s.problem, n=1, horizon=s.horizon) for s in scenarios]
    disturbance = dists[0] if len(scenarios) == 1 else _stack_disturbances(dists)
    band = [s.band if s.band is not None else float(s.problem.gains.delta_los) for s in scenarios]
    return simulate(params, p0=np.array([s.p0 for s in scenarios]), s0=np.array([s.s0 for s in scenarios]),
                    disturbance=disturbance, horizon=first.horizon, tail=first.tail, band=np.array(band),
                    form=first.form,  # type: ignore[arg-type]
                    rtol=min(s.rtol for s in scenarios), record=list(range(len(scenarios))) if record else None)


def _stack_disturbances(dists: list[Any]) -> Any:
    """Stack one-row disturbances of the same kind (presets share theirs)."""
    from lyapcheck.paper.simulation.disturbances import Constant

    if all(isinstance(d, Constant) for d in dists):
        return Constant(np.array([np.broadcast_to(d.vector, (2,)) for d in dists]), note=dists[0].note)
    if all(d is dists[0] for d in dists) or all(type(d) is type(dists[0]) and d.describe() == dists[0].describe()
                                                 for d in dists):
        return dists[0]
    raise ValueError("The 'scenarios' parameter must share a disturbance kind. Got different ones instead.")


def simulation_document(scenario: Scenario, result: SimulationResult, i: int = 0) -> dict[str, Any]:
    """JSON-ready report of trajectory ``i`` (DESIGN.md keys first)."""
    m = result.measurements.row(i)
    out: dict[str, Any] = {
        "scenario": scenario.name,
        "controller": scenario.controller,
        "ods_form": scenario.form,
    }
    out.update(m)
    out["tail_window_s"] = [result.horizon_s - result.tail_s, result.horizon_s]
    out["horizon_s"] = result.horizon_s
    out["initial_position_m"] = list(scenario.p0)
    out["initial_s_m"] = scenario.s0
    out["disturbance"] = {**_describe(result, i)}
    out["parameters"] = problem_summary(scenario.problem)
    out["parameters"]["d_hat_m_s"] = list(scenario.d_hat)
    if scenario.reported:
        out["paper"] = {key: {"reported": rep, "simulated": m[key], "relative_deviation": m[key] / rep - 1.0}
                        for key, rep in scenario.reported.items()}
    # "failure" says which limit stopped a failed run (None when it reached the horizon): at
    # extreme scales the loop overflows or is too stiff, and "diverged" alone would not say so
    out["integrator"] = {"method": INTEGRATOR_NAME, "rtol": result.rtol,
                         "ok": bool(result.integration.status[i] == STATUS_OK),
                         "failure": result.integration.failure(i, result.horizon_s)}
    return out


def _describe(result: SimulationResult, i: int) -> dict[str, Any]:
    d = result.loop.disturbance
    sub = d.take(np.array([i])) if d.size is not None else d
    return sub.describe()


def scenario_batch(scenario: str | None, preset: str | None, *, with_all_presets: bool = False
                   ) -> tuple[Scenario, list[Scenario], int]:
    """The chosen scenario, the batch to integrate, and the chosen one's index in the batch.

    Exactly one of ``scenario`` (a TOML path) and ``preset`` (a name in ``PRESETS``) is given.
    With ``with_all_presets`` a preset runs beside the other presets (the Section 5 figure
    shows all three; one batched call costs little more than one trajectory).
    """
    if scenario is not None and preset is not None:
        raise InvalidParameter("preset", "given without a SCENARIO file (choose one)", preset)
    if scenario is None and preset is None:
        raise InvalidParameter("preset", "one of " + ", ".join(repr(p) for p in PRESETS) + " or a SCENARIO.toml", None)
    if preset is not None:
        chosen = preset_scenario(preset)
        batch = [preset_scenario(p) for p in PRESETS] if with_all_presets else [chosen]
        return chosen, batch, next(i for i, s in enumerate(batch) if s.name == chosen.name)
    chosen = load_scenario(scenario)  # type: ignore[arg-type]
    return chosen, [chosen], 0
