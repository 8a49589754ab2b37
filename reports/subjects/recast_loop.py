"""A loop with functions (a model file whose ``[dynamics]`` use sin, sqrt, sat, ...) as a certificate page's subject.

Its document is a model certificate (``kind`` lyapcheck-model-certificate) with a ``"recast"``
table (:mod:`lyapcheck.models.surfaces.recast_certify`). The page shows: the model as stored (name,
source, states, equilibrium, parameters as given and exact, domain, the dynamics as written, the
SHA-256 of the text); the **recasting** the certificates are proved on (each auxiliary with its
definition, its value at the equilibrium and its flow; the relations between them; the states
taken modulo 2 pi); each class by :class:`reports.sections.recast.RecastSection`; for 2 states
the phase portrait in the loop's own states (:mod:`reports.recast_portrait`); the certificate
**re-checked exactly** on the spot (:func:`lyapcheck.models.surfaces.certificate.verify_document`, which
recasts the model text again; no solver); the command line and the model file verbatim.

The model text is read only by the project's parser (:func:`lyapcheck.models.language.modelfile.parse_any_model`)
and by :mod:`tomllib`; nothing from it is evaluated.
"""

from __future__ import annotations

import hashlib
import logging
import tomllib
from fractions import Fraction
from typing import Any

from lyapcheck.errors import InputFileError, LyapcheckError
from lyapcheck.models.surfaces.certificate import KIND, is_model_document
from lyapcheck.models.language.recast import RecastModel
from reports.figures import Figure
from reports.recast_portrait import recast_portrait
from reports.sections.base import ClassContext, text_of
from reports.sections.recast import RECAST_LOOP
from reports.subjects.base import Subject
from reports.subjects.model_file import ModelCertificateChecks, page_head, page_tail, quantities
from reports.typeset import Equations
from reports.views import as_dict, as_fraction

log = logging.getLogger(__name__)

#: what each kind of relation of the recasting says
RELATION_WORDS = {"eq": "= 0", "ge": "≥ 0"}


def is_recast_document(doc: object) -> bool:
    """A certificate of a loop with functions: a model certificate with a ``"recast"`` table."""
    return isinstance(doc, dict) and isinstance(doc.get("recast"), dict)


def auxiliary_rows(recast: dict[str, Any]) -> list[tuple[str, str, str, str]]:
    """(auxiliary, definition, value at the equilibrium, flow) per auxiliary of the recasting."""
    flows, values = as_dict(recast.get("flows")), as_dict(recast.get("values"))
    rows = []
    for name, definition in as_dict(recast.get("auxiliaries")).items():
        if name in values:
            value = text_of(values[name])
        else:
            value = "a constant (not shifted)"
        if name in flows:
            flow = text_of(flows[name])
        else:
            flow = "none: not differentiable here (a V may not use it)"
        rows.append((str(name), text_of(definition), value, flow))
    return rows


def relation_rows(recast: dict[str, Any]) -> list[tuple[str, str, str]]:
    """(polynomial, "= 0" or ">= 0", why it holds) per relation of the recasting."""
    rows = []
    relations = recast.get("relations")
    for rel in relations if isinstance(relations, list) else []:
        rel = as_dict(rel)
        kind = text_of(rel.get("kind"))
        rows.append((text_of(rel.get("poly")), RELATION_WORDS.get(kind, kind), text_of(rel.get("why", ""))))
    return rows


def angle_rows(recast: dict[str, Any]) -> list[tuple[str, str]]:
    """(state, the auxiliaries that carry it) for each state the loop sees only through sine and cosine."""
    rows = []
    for state, pair in as_dict(recast.get("angles")).items():
        names = ", ".join(map(text_of, pair)) if isinstance(pair, list) else text_of(pair)
        rows.append((str(state), names))
    return rows


class RecastLoopSubject(ModelCertificateChecks, Subject):
    model = RECAST_LOOP
    template = "recast_loop.html.j2"

    def __init__(self, doc: dict[str, Any]) -> None:
        from lyapcheck.models.language.modelfile import parse_any_model

        if not is_model_document(doc) or not is_recast_document(doc):
            raise InputFileError(f"not a certificate of a loop with functions (kind '{KIND}' with a 'recast' table)")
        super().__init__(doc)
        part = as_dict(doc.get("model"))
        stored = part.get("text")
        self.text = stored if isinstance(stored, str) else ""
        self.overrides = {str(k): v for k, v in as_dict(doc.get("overrides")).items()}
        candidate = doc.get("candidate")
        self.parsed: RecastModel | None = None
        self.error = ""
        try:
            parsed = parse_any_model(self.text, text_of(part.get("file", "<certificate>")), self.overrides,
                                     candidate=candidate if isinstance(candidate, str) else None)
            if isinstance(parsed, RecastModel):
                self.parsed = parsed
            else:
                self.error = "it has no functions, so it is not the loop with functions this certificate is about"
        except LyapcheckError as exc:
            self.error = str(exc)
        try:
            self.raw = tomllib.loads(self.text)
        except tomllib.TOMLDecodeError:
            self.raw = {}
        states = doc.get("states")
        self.states = [str(s) for s in states] if isinstance(states, list) else []
        if not self.states and self.parsed is not None:
            self.states = list(self.parsed.states)

    def class_context(self, eqs: Equations) -> ClassContext:
        equilibrium = as_dict(self.doc.get("equilibrium"))
        shifts = [as_fraction(equilibrium.get(s)) or Fraction(0) for s in self.states]
        outputs = tuple(getattr(self.parsed, "outputs", None) or ())  # sos_bound names those it did not bound
        return ClassContext(self.doc, eqs, self.states, shifts, outputs, self.doc.get("box"))

    def portrait(self, simulate: bool) -> tuple[Figure | None, str]:
        if not simulate:
            return None, "not requested"
        if self.parsed is None:
            return None, "the stored model text does not parse, so its field cannot be drawn"
        try:
            drawn = recast_portrait(self.doc, self.parsed)
        except (LyapcheckError, ValueError, ArithmeticError, FloatingPointError) as exc:
            log.warning("no phase portrait for the report: %s", exc)
            return None, f"the portrait failed: {exc}"
        return drawn.figure, drawn.reason

    def parts(self, eqs: Equations, *, ledger: bool, simulate: bool) -> dict[str, Any]:
        doc, raw = self.doc, self.raw
        part = as_dict(doc.get("model"))
        recast = as_dict(doc.get("recast"))
        figure, figure_reason = self.portrait(simulate)
        digest = hashlib.sha256(self.text.encode()).hexdigest()
        stated = text_of(part.get("sha256", ""))
        equilibrium = as_dict(doc.get("equilibrium"))
        name = text_of(part.get("name", "model"))
        variables = recast.get("variables")
        return {
            **page_head(name, text_of(part.get("file", "")),
                        self.parsed.origin if self.parsed is not None
                        else text_of(as_dict(raw.get("model")).get("source", "")),
                        doc, ("recasting", "The recasting the certificates are proved on")),
            "states": self.states,
            "equilibrium": [(s, text_of(equilibrium.get(s, "0"))) for s in self.states],
            "parameters": quantities(as_dict(doc.get("parameters")), as_dict(raw.get("parameters")), self.overrides),
            "domain": [(str(k), text_of(v)) for k, v in as_dict(raw.get("domain")).items()],
            "dynamics": [(s, text_of(as_dict(raw.get("dynamics")).get(s, "—"))) for s in self.states],
            "candidate": doc.get("candidate") if isinstance(doc.get("candidate"), str) else "",
            "model_error": self.error,
            "sha256_stated": stated,
            "sha256_text": digest,
            "sha256_matches": digest == stated,
            "variables": [text_of(v) for v in variables] if isinstance(variables, list) else [],
            "auxiliaries": auxiliary_rows(recast),
            "relations": relation_rows(recast),
            "angles": angle_rows(recast),
            "portrait": figure,
            "figure_reason": figure_reason,
            **page_tail(doc, self.text),
        }


__all__ = ["RecastLoopSubject", "is_recast_document", "auxiliary_rows", "relation_rows", "angle_rows"]
