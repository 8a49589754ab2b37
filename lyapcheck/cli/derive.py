"""``lyapcheck derive``: the claims ledger, the paper's equations as printed against as derived."""

from __future__ import annotations

from typing import TYPE_CHECKING

import click

from lyapcheck.cli.common import emit_json, one_line_errors

if TYPE_CHECKING:  # pragma: no cover
    from symbolic.ledger import LedgerEntry

STATUS_STYLE = {"holds": "green", "discrepancy": "bold red", "unverifiable": "yellow"}


def print_ledger(entries: "list[LedgerEntry]") -> None:
    from rich.console import Console
    from rich.table import Table

    table = Table(title="Claims ledger: the paper's equations, as printed vs as derived", show_lines=True)
    table.add_column("label", style="cyan", no_wrap=True)
    table.add_column("claim")
    table.add_column("status", no_wrap=True)
    table.add_column("explanation")
    for e in entries:
        table.add_row(e.label, e.title, f"[{STATUS_STYLE[e.status]}]{e.status}[/]", e.explanation)
    console = Console()
    console.print(table)
    counts = {s: sum(1 for e in entries if e.status == s) for s in STATUS_STYLE}
    console.print(", ".join(f"{n} {s}" for s, n in counts.items()))


def register(group: click.Group) -> None:
    @group.command()
    @click.option("--json", "as_json", is_flag=True, help="Print the claims ledger as JSON.")
    @one_line_errors
    def derive(as_json: bool) -> None:
        """Derive the paper's equations and compare them with the printed ones."""
        from lyapcheck.paper.ledger_view import ledger_entries

        entries = ledger_entries()
        if as_json:
            emit_json({"ledger": [e.to_json() for e in entries]})
        else:
            print_ledger(entries)
