"""What every model certificate document shares: its kind, its schema and the verdict row.

Kept apart from :mod:`lyapcheck.models.surfaces.certificate` (which writes such documents),
:mod:`lyapcheck.models.surfaces.verify` (which re-checks them) and
:mod:`lyapcheck.models.surfaces.sampled_run` (a sampled-data loop's), so that none imports another's module to
learn them.
"""

from __future__ import annotations

from typing import Any

SCHEMA_VERSION = 1
KIND = "lyapcheck-model-certificate"

Row = tuple[str, bool, str]


def with_verdict(doc: dict[str, Any], rows: list[Row]) -> list[Row]:
    """The verdict row and the answers row: the stated verdict and answers against the ones the
    re-checked conditions support (:func:`checked_conditions`)."""
    from lyapcheck.answers import answers_row, checked_conditions
    from lyapcheck.answers import verdict_of

    prerequisites = all(ok for n, ok, _ in rows if n in ("model", "parameters", "box", "denominators", "scaling",
                                                         "recasting", "states"))
    checked = checked_conditions(doc["conditions"], rows, prerequisites)
    expected = verdict_of(checked)
    stated = doc.get("verdict")
    rows.append(("verdict", stated == expected, f"verdict '{stated}' is supported" if stated == expected else
                 f"verdict: stated '{stated}' but the re-checked conditions support '{expected}'"))
    rows.append(answers_row(doc, checked))
    return rows
