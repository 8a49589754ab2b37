"""What every model certificate document shares: its kind, its schema and the verdict row.

Kept apart from :mod:`lyapcheck.models.certificate` (polynomial and rational loops) and
:mod:`lyapcheck.models.recast_certify` (loops with functions), which both write and re-check such
documents, so that neither imports the other's module to learn them.
"""

from __future__ import annotations

from typing import Any

SCHEMA_VERSION = 1
KIND = "lyapcheck-model-certificate"

Row = tuple[str, bool, str]


def with_verdict(doc: dict[str, Any], rows: list[Row]) -> list[Row]:
    """The verdict row: the stated verdict against the one the re-checked conditions support."""
    from lyapcheck.models.certify import verdict_of

    conditions = doc["conditions"]
    proven = {name: c for name, c in conditions.items()
              if isinstance(c, dict) and c.get("status") == "certified" and any(n == name for n, _, _ in rows)
              and all(ok for n, ok, _ in rows if n == name)}
    prerequisites = all(ok for n, ok, _ in rows if n in ("model", "parameters", "box", "denominators", "scaling",
                                                         "recasting"))
    expected = verdict_of(proven) if prerequisites else "not_certified"
    stated = doc.get("verdict")
    rows.append(("verdict", stated == expected, f"verdict '{stated}' is supported" if stated == expected else
                 f"verdict: stated '{stated}' but the re-checked conditions support '{expected}'"))
    return rows
