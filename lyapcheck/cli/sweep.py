"""``lyapcheck sweep SPEC.toml --out RESULTS.zarr`` (contract in DESIGN.md).

Runs or resumes a parameter sweep (:mod:`sweeps`, of any target: a model file's parameters when the
spec's ``[sweep]`` names one, else the paper's; :mod:`sweeps.targets`), shows a progress bar with rate
and ETA on stderr (unless ``--quiet``), prints the summary, and exits with 1 when any soundness violation
is in the store (printed loudly on stderr even with ``--quiet``), else 0. Running the same
command again on a finished store computes nothing and prints the summary again; with
``--export FILE.nc`` / ``--export FILE.csv`` it also writes those files.
"""

from __future__ import annotations

import math
from typing import Any

import click

from lyapcheck.cli.common import EXIT_NEGATIVE, EXIT_OK, emit_json, one_line_errors


def _progress_bar() -> Any:
    from rich.console import Console
    from rich.progress import (
        BarColumn, MofNCompleteColumn, Progress, ProgressColumn, TaskProgressColumn, TextColumn,
        TimeElapsedColumn, TimeRemainingColumn,
    )
    from rich.text import Text

    class RateColumn(ProgressColumn):
        """Points per second: rich's recent-window estimate, else the mean since the start (units
        complete in chunks, so the window often holds too few samples)."""

        def render(self, task: Any) -> Text:
            speed = task.finished_speed or task.speed
            if speed is None and task.elapsed:
                speed = task.completed / task.elapsed
            return Text("-- pts/s" if not speed else f"{speed:.2f} pts/s", style="cyan")

    return Progress(TextColumn("sweep"), BarColumn(), MofNCompleteColumn(), TaskProgressColumn(), RateColumn(),
                    TimeElapsedColumn(), TextColumn("ETA"), TimeRemainingColumn(),
                    console=Console(stderr=True), transient=False)


def _print_summary(summary: Any, report: Any) -> None:
    from rich.console import Console
    from rich.table import Table

    console = Console()
    console.print(f"[bold]{report.path}[/]: {summary.computed} of {summary.points} points stored "
                  f"({report.computed_now} computed in this run, {report.wall_seconds:.1f} s)")
    if report.refinement is not None:
        r = report.refinement
        console.print(f"refinement on '{r.cls}', {r.levels} levels: {r.points_computed} points computed against "
                      f"{r.full_grid_points} for the full grid ({100 * r.saved_fraction:.1f}% saved)")
    table = Table(title=f"certified among the {summary.simulated_stable} simulated-stable points")
    table.add_column("class", style="cyan")
    table.add_column("fraction", justify="right")
    for cls, frac in summary.certified_fraction.items():
        label = cls + (" (holds)" if cls == "stabcond2" else "")
        table.add_row(label, "n/a" if math.isnan(frac) else f"{frac:.3f}")
    console.print(table)
    med = summary.median_ratio
    console.print("median certified/simulated ultimate bound: " + ("n/a" if math.isnan(med) else f"{med:.3g}"))


def _print_box_summary(summary: Any, report: Any) -> None:
    from rich.console import Console
    from rich.table import Table

    console = Console()
    console.print(f"[bold]{report.path}[/]: {summary.boxes} boxes stored, {summary.leaves} leaves "
                  f"({report.boxes_computed_now} computed in this run, {report.wall_seconds:.1f} s)")
    table = Table(title="share of the parameter window (log measure on log axes)")
    table.add_column("status", style="cyan")
    table.add_column("share", justify="right")
    for status, share in summary.area_fraction.items():
        table.add_row(status + (" (GES proved for every point)" if status == "certified" else ""), f"{share:.3f}")
    console.print(table)
    worst = summary.worst_envelope_ratio
    console.print(f"cross-check: {summary.cross_checked_points} random points of {summary.certified_boxes} certified "
                  "boxes simulated; worst |x(t)| / envelope = " + ("n/a" if math.isnan(worst) else f"{worst:.3g}"))


def _print_model_summary(summary: Any, report: Any) -> None:
    from rich.console import Console
    from rich.table import Table

    console = Console()
    boxes = summary.mode == "model_boxes"
    what = "boxes" if boxes else "points"
    console.print(f"[bold]{report.path}[/]: model {summary.model.get('name') or summary.model.get('file')} "
                  f"(SHA-256 {summary.model.get('sha256', '')[:12]}...), {summary.computed} {what} stored, "
                  f"{summary.leaves} {'leaves' if boxes else 'points'} ({report.computed_now} computed in this run, "
                  f"{report.wall_seconds:.1f} s)")
    measure = ", ".join(f"{d} {'log' if s == 'log' else 'linear'}" for d, s in summary.scales.items())
    table = Table(title=f"share of the parameter window ({measure})")
    table.add_column("status", style="cyan")
    table.add_column("share", justify="right")
    table.add_column(what, justify="right")
    for status, share in summary.share.items():
        label = status + (" (proved for every value of its box)" if boxes and status == "certified" else
                          " (at the grid point)" if status == "certified" else "")
        table.add_row(label, f"{share:.3f}", str(summary.counts.get(status, "")))
    console.print(table)
    by_class = Table(title="certified, per class")
    by_class.add_column("class", style="cyan")
    by_class.add_column("share", justify="right")
    by_class.add_column(what, justify="right")
    for cls, share in summary.share_by_class.items():
        by_class.add_row(cls, f"{share:.3f}", str(summary.counts_by_class.get(cls, 0)))
    console.print(by_class)
    cross = summary.cross_check
    # a map's cross-check iterates it (sweeps.crosscheck._MapLoop): its sequences of iterates, never trajectories
    runs = "sequences of iterates" if summary.model.get("time") == "discrete" else "trajectories"
    done = "iterated" if summary.model.get("time") == "discrete" else "simulated"
    console.print(f"cross-check: {cross['parameter_points']} parameter points and {cross['trajectories']} {runs} "
                  f"of {cross['checked']} certified {what} {done}; worst V rise "
                  + ("n/a" if cross["worst_rise"] is None else f"{cross['worst_rise']:.3g}") + " of V(0)")


def _shout(summary: Any) -> None:
    from rich.console import Console

    err = Console(stderr=True)
    listed = [v for v in summary.violations if "more" not in v]
    more = sum(v.get("more", 0) for v in summary.violations)
    mode = summary.to_json().get("mode")
    what = ("box(es) where a simulated point leaves the certified GES envelope" if mode == "boxes"
            else "certified point(s) or box(es) of the model where a simulated trajectory leaves a certified set, "
                 "envelope or bound" if mode in ("model_points", "model_boxes")
            else "point(s) where simulation leaves a certified bound or diverges under a stability certificate")
    err.print(f"[bold white on red] SOUNDNESS VIOLATION [/] {len(listed) + more} {what}:")
    for v in listed:
        err.print("[bold red]  " + ", ".join(f"{k}={val:.6g}" if isinstance(val, float) else f"{k}={val}"
                                             for k, val in v.items()) + "[/]")
    if more:
        err.print(f"[bold red]  ... and {more} more[/]")


def register(group: click.Group) -> None:
    @group.command()
    @click.argument("spec", type=click.Path(dir_okay=False))
    @click.option("--out", required=True, type=click.Path(), help="Zarr store to create or resume.")
    @click.option("--scheduler", help="Address of an existing Dask scheduler, e.g. tcp://10.0.0.5:8786.")
    @click.option("--workers", type=int, help="Local worker processes (default: all cores; 0: in this process).")
    @click.option("--export", "exports", multiple=True, type=click.Path(dir_okay=False),
                  help="Also write the results to FILE.nc (NetCDF) or FILE.csv; repeatable.")
    @click.option("--json", "as_json", is_flag=True, help="Print the summary as JSON.")
    @click.option("--quiet", is_flag=True, help="No progress bar and no summary (violations are still printed).")
    @one_line_errors
    def sweep(spec: str, out: str, scheduler: str | None, workers: int | None, exports: tuple[str, ...],
              as_json: bool, quiet: bool) -> None:
        """Map certified regions over 1-3 parameters and cross-check them with simulation."""
        from lyapcheck.api import sweep as run_sweep

        bar = None if quiet else _progress_bar()
        task: list[Any] = []

        def on_ready() -> None:
            if bar is not None:
                bar.start()
                task.append(bar.add_task("sweep", total=None))

        def progress(advance: int, total: int) -> None:
            if bar is not None and task:
                bar.update(task[0], advance=advance, total=total)

        try:
            result = run_sweep(spec, out, scheduler=scheduler, workers=workers, exports=exports, progress=progress,
                               on_ready=on_ready)
        finally:
            if bar is not None and task:  # a bar that never started would still print a newline
                bar.stop()
        if as_json:
            emit_json(result.to_json())
        elif not quiet:
            if result.mode in ("model_points", "model_boxes"):
                _print_model_summary(result.summary, result.run)
            elif result.mode == "boxes":
                _print_box_summary(result.summary, result.run)
            else:
                _print_summary(result.summary, result.run)
        if result.violations:
            _shout(result.summary)
            raise SystemExit(EXIT_NEGATIVE)
        raise SystemExit(EXIT_OK)
