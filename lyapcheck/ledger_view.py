"""Builds the claims ledger from every symbolic module and renders it for the terminal."""

from __future__ import annotations

from typing import TYPE_CHECKING

if TYPE_CHECKING:  # pragma: no cover
    from symbolic.ledger import LedgerEntry


def all_claims() -> list[object]:
    """Claims of every symbolic module, in the paper's order (Sections 2, 3, 4.1, 4.2)."""
    import importlib

    claims: list[object] = []
    for module_name in ("symbolic.rft", "symbolic.ilos", "symbolic.ods"):
        try:
            module = importlib.import_module(module_name)
        except ModuleNotFoundError as exc:
            if exc.name == module_name:  # a module not written yet is skipped, not hidden
                continue
            raise
        claims.extend(module.claims())
    return claims


def ledger_entries() -> "list[LedgerEntry]":
    from symbolic.ledger import build_ledger

    return build_ledger(all_claims())  # type: ignore[arg-type]


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
