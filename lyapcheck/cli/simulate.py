"""``lyapcheck simulate``: run a preset or a scenario TOML through :func:`lyapcheck.api.simulate`.

Exit codes (DESIGN.md): 0 the simulation ran and the loop did not diverge; 1 it ran but the
loop diverged (the tail of ``|eps|`` went beyond the initial error, or the integrator failed,
e.g. the printed ODS controller); 2 bad input.
"""

from __future__ import annotations

from typing import Any

import click

from lyapcheck.cli.common import EXIT_NEGATIVE, EXIT_OK, emit_json, one_line_errors


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


def _print_worst_case(doc: dict[str, Any]) -> None:
    from rich.console import Console

    console = Console()
    console.print(f"[bold]worst disturbance found[/] ({doc['scenario']}, |d| <= {doc['d_max_m_s'] * 1e3:.4g} mm/s): "
                  f"tail sup |eps| = {doc['sup_abs_eps_tail_m'] * 1e3:.4g} mm "
                  f"(constant d*: {doc['constant_sup_abs_eps_tail_m'] * 1e3:.4g} mm)")
    console.print(f"disturbance: {_disturbance_text(doc['disturbance'])}")
    console.print(f"{doc['candidates_tried']} candidates; a search, not a proof: the certified bound is the proof")


def register(group: click.Group) -> None:
    @group.command()
    @click.argument("scenario", required=False, type=click.Path(dir_okay=False))
    @click.option("--preset", type=click.Choice(["paper-ilos", "paper-los-600", "paper-los-1200"]),
                  help="One of the paper's Section 5 simulations.")
    @click.option("--json", "as_json", is_flag=True, help="Print the measured quantities as JSON (SI units).")
    @click.option("--plot", type=click.Path(dir_okay=False), help="Write the Section 5 figures to this PNG.")
    @click.option("--worst-case", is_flag=True, help="Search the worst disturbance |d| <= d* (tail sup |eps|).")
    @click.option("--budget", type=float, default=20.0, show_default=True,
                  help="Wall-time target of --worst-case, seconds.")
    @one_line_errors
    def simulate(scenario: str | None, preset: str | None, as_json: bool, plot: str | None, worst_case: bool,
                 budget: float) -> None:
        """Simulate the saturated ILOS/ODS closed loop (or a paper preset)."""
        from lyapcheck.api import simulate as run_simulation

        result = run_simulation(scenario, preset=preset, plot=plot, worst_case=worst_case, budget_s=budget)
        if as_json:
            emit_json(result.to_json())
        elif worst_case:
            _print_worst_case(result.to_json())
        else:
            _print_table(result.to_json())
        raise SystemExit(EXIT_NEGATIVE if result.diverged else EXIT_OK)
