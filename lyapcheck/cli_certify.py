"""``lyapcheck certify`` and ``lyapcheck verify`` (filled in by the certificate work)."""

from __future__ import annotations

import click


def register(group: click.Group) -> None:
    return None
