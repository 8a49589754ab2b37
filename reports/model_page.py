"""Deprecated import path, kept only for tests outside the report tests (``tests/test_claims.py``,
``tests/test_claims_words.py``) until they import :func:`reports.render.certificate_html`: the
model certificate's page is the one certificate page (:mod:`reports.certificate_page`)."""

from __future__ import annotations

from typing import Any


def model_html(doc: dict[str, Any], *, simulate: bool = True, recheck: bool = True) -> str:
    """:func:`reports.render.certificate_html` of a model certificate."""
    from reports.render import certificate_html

    return certificate_html(doc, simulate=simulate, recheck=recheck)


__all__ = ["model_html"]
