"""``lyapcheck report``: a certificate or a sweep store as a self-contained HTML page and/or PDF."""

from __future__ import annotations

import click

from lyapcheck.cli.common import one_line_errors


def register(group: click.Group) -> None:
    @group.command()
    @click.argument("source", type=click.Path(dir_okay=True))
    @click.option("--html", "html", type=click.Path(dir_okay=False), help="Write the HTML report here.")
    @click.option("--pdf", "pdf", type=click.Path(dir_okay=False), help="Write the PDF report here.")
    @one_line_errors
    def report(source: str, html: str | None, pdf: str | None) -> None:
        """Report on CERT.json (from certify --out), RESULTS.zarr (from sweep), or a model file
        (certified first with every class).

        Without --html or --pdf, writes SOURCE's name with .html in the current directory.
        """
        from lyapcheck.api import report as write_report

        for path in write_report(source, html=html, pdf=pdf):
            click.echo(f"wrote {path}")
