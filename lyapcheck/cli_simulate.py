"""``lyapcheck simulate``: thin wrapper over :mod:`lyapcheck.simulation.command`."""

from __future__ import annotations

import click

from lyapcheck.cli import one_line_errors


def register(group: click.Group) -> None:
    @group.command()
    @click.argument("scenario", required=False, type=click.Path(dir_okay=False))
    @click.option("--preset", type=click.Choice(["paper-ilos", "paper-los-600", "paper-los-1200"]),
                  help="One of the paper's Section 5 simulations.")
    @click.option("--json", "as_json", is_flag=True, help="Print the measured quantities as JSON (SI units).")
    @click.option("--plot", type=click.Path(dir_okay=False), help="Write the Section 5 figures to this PNG.")
    @one_line_errors
    def simulate(scenario: str | None, preset: str | None, as_json: bool, plot: str | None) -> None:
        """Simulate the saturated ILOS/ODS closed loop (or a paper preset)."""
        from lyapcheck.simulation.command import run

        raise SystemExit(run(scenario=scenario, preset=preset, as_json=as_json, plot=plot))
