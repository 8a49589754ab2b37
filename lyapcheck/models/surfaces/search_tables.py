"""The tables a search adds to the certificate it writes, and what ``verify`` checks of them.

``lyapcheck tune --out`` writes the winner's certificate with a ``tune`` table
(:meth:`lyapcheck.models.surfaces.tune.Tuning.document`); ``certify --maximize/--minimize --out`` the
proved value's certificate with an ``extremum`` table
(:meth:`lyapcheck.models.surfaces.extremum.Extremum.document`). Both are model certificates: their
classes are re-checked as any other; the rows here check what the table states on top (the figure, the
point or value, the neighbourhood, the record's consistency). ``verify`` and the reports call
:func:`search_rows`, so both re-check the same things.
"""

from __future__ import annotations

from typing import Any, Final, Mapping

#: the tables of a search, in the order their rows come
SEARCH_TABLES: Final = ("tune", "extremum")


def search_table(doc: Mapping[str, Any]) -> str | None:
    """The search table a model certificate carries (``"tune"`` or ``"extremum"``), or None."""
    from lyapcheck.models.surfaces.certificate import is_model_document

    if not is_model_document(dict(doc)):
        return None
    return next((key for key in SEARCH_TABLES if key in doc), None)


def search_rows(doc: Mapping[str, Any]) -> list[tuple[str, bool, str]]:
    """``verify``'s rows for the search tables of a model certificate (none without one)."""
    rows: list[tuple[str, bool, str]] = []
    if search_table(doc) is None:
        return rows
    if "tune" in doc:
        from lyapcheck.models.surfaces.tune import check_tune

        rows.extend(check_tune(doc))
    if "extremum" in doc:
        from lyapcheck.models.surfaces.extremum import check_extremum

        rows.extend(check_extremum(doc))
    return rows


__all__ = ["SEARCH_TABLES", "search_table", "search_rows"]
