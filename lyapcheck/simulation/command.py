"""``lyapcheck simulate``: run a preset or a scenario TOML, print JSON or a table, plot.

Exit codes (DESIGN.md): 0 the simulation ran and the loop did not diverge; 1 it ran but the
loop diverged (the tail of ``|eps|`` went beyond the initial error, or the integrator failed,
e.g. the printed ODS controller); 2 bad input (raised as ``InvalidParameter`` and mapped by
the CLI).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from lyapcheck.errors import InvalidParameter
from lyapcheck.simulation.integrator import STATUS_OK
from lyapcheck.simulation.model import LoopParams
from lyapcheck.simulation.runner import SimulationResult, simulate
from lyapcheck.simulation.scenarios import PRESETS, Scenario, load_scenario, problem_summary
from lyapcheck.simulation.scenarios import preset as preset_scenario

EXIT_OK, EXIT_DIVERGED = 0, 1

INTEGRATOR_NAME = "Dormand-Prince 5(4), adaptive step per trajectory, batched (lyapcheck.simulation.integrator)"


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
    from lyapcheck.simulation.disturbances import Constant

    if all(isinstance(d, Constant) for d in dists):
        return Constant(np.array([np.broadcast_to(d.vector, (2,)) for d in dists]), note=dists[0].note)
    if all(d is dists[0] for d in dists) or all(type(d) is type(dists[0]) and d.describe() == dists[0].describe()
                                                 for d in dists):
        return dists[0]
    raise ValueError("The 'scenarios' parameter must share a disturbance kind. Got different ones instead.")


def report(scenario: Scenario, result: SimulationResult, i: int = 0) -> dict[str, Any]:
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
    out["integrator"] = {"method": INTEGRATOR_NAME, "rtol": result.rtol,
                         "ok": bool(result.integration.status[i] == STATUS_OK)}
    return out


def _describe(result: SimulationResult, i: int) -> dict[str, Any]:
    d = result.loop.disturbance
    sub = d.take(np.array([i])) if d.size is not None else d
    return sub.describe()


def _print_table(doc: dict[str, Any]) -> None:
    from rich.console import Console
    from rich.table import Table

    console = Console()
    paper = doc.get("paper", {})
    table = Table(title=f"lyapcheck simulate: {doc['scenario']} ({doc['controller']}, ODS {doc['ods_form']})")
    table.add_column("quantity")
    table.add_column("value", justify="right")
    table.add_column("paper (deviation)" if paper else "reference", justify="right")

    def mm(x: float) -> str:
        return f"{x * 1e3:.4g} mm"

    def ref(key: str, fmt: Any) -> str:
        if key not in paper:
            return ""
        p = paper[key]
        return f"{fmt(p['reported'])} ({p['relative_deviation']:+.1%})"

    w0, w1 = doc["tail_window_s"]
    conv = doc["convergence_time_s"]
    table.add_row(f"mean |eps| over {w0:g}-{w1:g} s", mm(doc["mean_abs_eps_tail_m"]),
                  ref("mean_abs_eps_tail_m", mm))
    table.add_row(f"sup |eps| over {w0:g}-{w1:g} s", mm(doc["sup_abs_eps_tail_m"]), "")
    table.add_row(f"sup |(eps, s)| over {w0:g}-{w1:g} s", mm(doc["sup_norm_eps_s_tail_m"]), "")
    table.add_row("final eps", mm(doc["final_eps_m"]), "")
    table.add_row("steady rotation (mean |u| over the tail)", f"{doc['steady_rotation_hz']:.4g} Hz",
                  ref("steady_rotation_hz", lambda x: f"{x:.3g} Hz"))
    table.add_row("max rotation |u| (every controller call)",
                  f"{doc['max_rotation_hz']:.4g} Hz (limit {doc['omega_so_hz']:.4g} Hz)", "")
    table.add_row("steady speed along the path", f"{doc['steady_speed_m_s'] * 1e3:.4g} mm/s",
                  f"e11 alpha_d Delta = {doc['speed_star_m_s'] * 1e3:.4g} mm/s")
    table.add_row(f"convergence time to |eps| <= {mm(doc['band_m'])}",
                  "not converged" if conv is None else f"{conv:.4g} s", "")
    table.add_row("diverged", "yes" if doc["diverged"] else "no", "")
    console.print(table)
    console.print(f"disturbance: {_disturbance_text(doc['disturbance'])}")


def _disturbance_text(d: dict[str, Any]) -> str:
    parts = [d["kind"]]
    for key, value in d.items():
        if key in ("kind",):
            continue
        parts.append(f"{key} = {value}")
    return "; ".join(parts)


def run(*, scenario: str | None, preset: str | None, as_json: bool, plot: str | None) -> int:
    """Entry point of ``lyapcheck simulate`` (see the module docstring for exit codes)."""
    from lyapcheck.cli import emit_json

    if scenario is not None and preset is not None:
        raise InvalidParameter("preset", "given without a SCENARIO file (choose one)", preset)
    if scenario is None and preset is None:
        raise InvalidParameter("preset", "one of " + ", ".join(repr(p) for p in PRESETS) + " or a SCENARIO.toml", None)
    if preset is not None:
        chosen = preset_scenario(preset)
        # the Section 5 figures show all three simulations side by side: run them in one batch
        batch = [preset_scenario(p) for p in PRESETS] if plot else [chosen]
        index = batch.index(next(s for s in batch if s.name == chosen.name))
    else:
        chosen = load_scenario(scenario)  # type: ignore[arg-type]
        batch, index = [chosen], 0
    result = run_scenarios(batch, record=bool(plot))
    doc = report(chosen, result, index)
    if plot:
        from lyapcheck.simulation.plots import section5_figure

        section5_figure(batch, result, plot)
        doc["plot"] = plot
    if as_json:
        emit_json(doc)
    else:
        _print_table(doc)
    return EXIT_DIVERGED if doc["diverged"] else EXIT_OK
