"""The interface of a certificate page's subject (see :mod:`reports.subjects`), and what subjects share."""

from __future__ import annotations

import json
from dataclasses import dataclass
from typing import Any, Final

from reports.sections.base import ClassContext
from reports.typeset import Equations

#: one sentence per status (DESIGN.md)
STATUS_MEANING: Final = {
    "certified": "a certificate exists and passed its exact check",
    "refuted": "proved exactly that no certificate of this class exists for these numbers",
    "not_certified": "none was found, and nothing is proved either way",
    "inconclusive": "numerical trouble: the solver's word alone, or an exact check that failed",
    "holds": "the arithmetic condition holds",
    "fails": "the arithmetic condition fails",
    "discrepancy": "the printed and the derived forms differ",
    "unverifiable": "neither equality nor difference could be established",
}


def canonical_json(value: object) -> bytes:
    """Sorted, compact JSON (keys made strings first: an input may mix key types)."""
    plain = json.loads(json.dumps(value, default=str))
    return json.dumps(plain, sort_keys=True, separators=(",", ":")).encode()


@dataclass
class Quantity:
    """A row of an inputs table (a gain, a parameter, a disturbance bound): as given and in SI (exact)."""

    name: str
    given: str
    si: str
    exact: str
    note: str = ""


@dataclass(frozen=True)
class Glance:
    """The table of classes at the top: column heads, whether it shows the property and key
    figures columns, and the statuses explained under it."""

    head: tuple[str, ...]
    detail: bool
    statuses: tuple[str, ...]


class Subject:
    """A certificate page's account of its model (one instance per document).

    Attributes
    ----------
    model
        The model the document's classes belong to, for :func:`reports.sections.section_for`.
    template
        The template of the subject's own parts: macros ``header``, ``before_classes`` and
        ``after_classes``, imported by ``certificate.html.j2``.
    """

    model: str
    template: str

    def __init__(self, doc: dict[str, Any]) -> None:
        self.doc = doc

    def class_context(self, eqs: Equations) -> ClassContext:
        """What the sections read beside each condition."""
        return ClassContext(self.doc, eqs)

    def parts(self, eqs: Equations, *, ledger: bool, simulate: bool) -> dict[str, Any]:
        """The subject's entries of the page context, built after the classes' views (whose
        equations come first on the page's sheets). Equations go to ``eqs``; ``ledger`` and
        ``simulate`` ask for the parts that take time (a subject without them ignores them)."""
        raise NotImplementedError

    def fingerprints(self, context: dict[str, Any]) -> list[tuple[str, str]]:
        """(what, SHA-256) rows of the reproducibility block; ``context`` is the page's."""
        return [("SHA-256 of the whole certificate (canonical JSON)", context["hash_document"])]

    def checked(self, recheck: bool) -> dict[str, Any]:
        """Entries computed after the equations are typeset (an exact re-check, for instance)."""
        return {}


__all__ = ["STATUS_MEANING", "canonical_json", "Quantity", "Glance", "Subject"]
