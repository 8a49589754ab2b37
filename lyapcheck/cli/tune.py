"""``lyapcheck tune``: the gains in a box with the best certified figure (issue 45, item 2)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import click

from lyapcheck.cli.common import EXIT_NEGATIVE, EXIT_OK, emit_json, one_line_errors
from lyapcheck.errors import InvalidParameter


def _print(found: Any, out: str | None) -> None:
    """A table of the points tried (figure or outcome), the winner and its neighbourhood."""
    from rich.console import Console
    from rich.table import Table

    from lyapcheck.models.surfaces.tune import neighbourhood_sentence, weaker_float

    goal = found.objective
    console = Console()
    table = Table(title=f"tune: {goal.text} ({'maximized' if goal.sense == 'max' else 'minimized'}): "
                        f"{goal.words()}")
    table.add_column("phase")
    for name, _, _ in found.boxes:
        table.add_column(name, justify="right")
    table.add_column("figure or outcome", overflow="fold")
    table.add_column("s", justify="right")
    for p in found.tried:
        mark = " (winner)" if found.winner is p else ""
        figure = f"{weaker_float(p.value, goal.sense):.6g}{mark}" if p.value is not None else p.outcome
        table.add_row(p.phase, *(f"{float(v):.6g}" for v in p.values.values()), figure, f"{p.seconds:.1f}")
    console.print(table)
    click.echo(f"{len(found.tried)} points tried ({found.grid} per axis, then the refinement), "
               f"{sum(p.value is not None for p in found.tried)} certified")
    click.echo(found.sentence())
    if found.neighbourhood is not None:
        click.echo(neighbourhood_sentence(goal, found.neighbourhood))
    if out and found.result is not None:
        click.echo(f"certificate of the winner written to {out} (lyapcheck verify re-checks it and its tune table)")


def register(group: click.Group) -> None:
    @group.command()
    @click.argument("file", type=click.Path(dir_okay=False))
    @click.option("--box", "boxes", multiple=True, metavar="NAME=LO..HI",
                  help="A parameter to tune and its range, e.g. --box kp=0.5..4 (repeatable).")
    @click.option("--objective", required=True, metavar="OBJ",
                  help="decay_rate (GES rate, quadratic; max), local_decay_rate (every eigenvalue's real part < "
                       "-r, linearization; max), roa (radius of the largest ball proved inside the "
                       "region; max), bound:OUTPUT (sos_bound; min), safety:PARAM=LO..HI (the largest PARAM at which "
                       "barrier proves safety; max) or safety:min:PARAM=LO..HI (the smallest; min).")
    @click.option("--grid", "grid", metavar="N", help="Grid points per axis (1 to 9, default 3); then one refinement "
                  "of 2 points per axis around the best.")
    @click.option("--set", "settings", multiple=True, metavar="NAME=VALUE",
                  help="Another parameter or disturbance bound for every point (repeatable).")
    @click.option("--classes", help="Classes run at every point besides the objective's own (default: that one).")
    @click.option("--require", "require", metavar="PROPS", help="A point counts only if these are proved too, "
                  "e.g. --require GAS (with --classes sos_gas).")
    @click.option("--degree", "degree", metavar="N", help="The largest polynomial degree each class searches.")
    @click.option("--time-limit", "time_limit", metavar="SECONDS", help="Each class's time limit at each point "
                  "(default 60).")
    @click.option("--out", type=click.Path(dir_okay=False), help="Write the winner's certificate (with its tune "
                  "table) here.")
    @click.option("--report", type=click.Path(dir_okay=False), help="Write the search's report, HTML or PDF (by "
                  "extension): the box map with the winner and its neighbourhood, the objective along the search.")
    @click.option("--json", "as_json", is_flag=True, help="Print {\"tune\": ..., \"certificate\": ...} as JSON.")
    @one_line_errors
    def tune(file: str, boxes: tuple[str, ...], objective: str, grid: str | None, settings: tuple[str, ...],
             classes: str | None, require: str | None, degree: str | None, time_limit: str | None,
             out: str | None, report: str | None, as_json: bool) -> None:
        """Search a box of a model's parameters for the gains with the best certified figure: a grid,
        one refinement around its best point, the winner certified again exactly (--out), and a
        neighbourhood of the winner proved with a box certificate, where the figure stays within a
        factor 2 of the winner's. Every figure is read from an exact certificate.

        Exit 0 when a winner is certified, 1 when no point was, 2 for bad input."""
        from lyapcheck.api import tune as tune_model
        from lyapcheck.cli.certify import _time_limit
        from lyapcheck.cli.inputs import flag_names, split_model_argument
        from lyapcheck.degrees import check_degree
        from lyapcheck.sos import sdp

        sdp.LEAN_LAPACK_IMPORT = True  # this process is the command's own (see sdp._load_lapack_modules)
        model_file, other = split_model_argument(file, None)
        if model_file is None:
            raise InvalidParameter("FILE", "a model file (tune searches a model file's parameters; the paper's "
                                   "gain files are not searched: use certify --box for the paper's gains)", other)
        with flag_names():
            if report is not None and Path(report).suffix.lower() not in (".html", ".pdf"):
                raise InvalidParameter("report", "a file name ending in .html or .pdf", report)
            found = tune_model(model_file, list(boxes), objective, grid=grid, settings=list(settings),
                               classes=classes, require=require, degree=check_degree(degree),
                               time_limit_s=_time_limit(time_limit))
        if out and found.result is not None:
            import json

            from lyapcheck.fileio import atomic_write

            atomic_write(out, json.dumps(found.document(), indent=2) + "\n")
        document = found.document()  # None without a winner
        if report is not None and document is not None:  # the page lyapcheck report draws of that document
            from reports.render import certificate_report

            certificate_report(document, report)
        if as_json:
            emit_json({"tune": found.to_json(), "certificate": None if found.result is None else found.result.to_json()})
        else:
            _print(found, out)
            if report is not None:
                click.echo(f"report of the search written to {report}" if found.result is not None else
                           "no report: no point was proved (the points tried are listed above)")
        raise SystemExit(EXIT_OK if found.result is not None else EXIT_NEGATIVE)
