"""A sampled-data loop (``[sampling]``, ``[controller]``; ``lyapcheck certify FILE``) as a certificate page's subject.

The page of a model certificate (:mod:`reports.subjects.model_file`) in the parts that apply: the verdict,
the answers and the table of classes, the model as the certificate stores it (name, source, states,
equilibrium, the plant's dynamics as written, the parameters as given and SI, the SHA-256 of the text),
the certificate **re-checked exactly** on the spot
(:func:`lyapcheck.models.surfaces.certificate.verify_document`), the command line and the model file
verbatim. Its own parts: the sampling period (as given and exact), the hold and the controller's laws
with the controls at the equilibrium (the document's ``sampling`` table), and the staircase simulation
that ``lyapcheck simulate --plot`` draws (:mod:`reports.sampled_figures`). No phase portrait and no drawn
region: the loop is a plant under held controls, whose claims are about its states at the sampling
instants (a certified ``roa``'s set and inter-sample bound are stated in its sentence, in the table).

The model text is re-read only by the sampled-data parser
(:func:`lyapcheck.models.language.sampling.parse_sampled`, the model file's whitelist over Python's ``ast``)
and by :mod:`tomllib`; nothing from it is evaluated.
"""

from __future__ import annotations

import hashlib
import logging
import tomllib
from fractions import Fraction
from typing import TYPE_CHECKING, Any

from lyapcheck.errors import InputFileError, LyapcheckError
from lyapcheck.models.surfaces.certificate import KIND, is_model_document
from reports.sections.base import MODEL_FILE, ClassContext, text_of
from reports.subjects.base import Subject
from reports.subjects.model_file import model_recheck, model_text_fingerprints, page_head, page_tail, quantities
from reports.typeset import Equations
from reports.views import as_dict, as_fraction, fmt_float

if TYPE_CHECKING:  # pragma: no cover
    from lyapcheck.models.language.sampling import SampledModel

log = logging.getLogger(__name__)


def is_sampled_document(doc: object) -> bool:
    """A certificate of a sampled-data loop: a model certificate with a ``"sampling"`` table."""
    return isinstance(doc, dict) and isinstance(doc.get("sampling"), dict)


class SampledSubject(Subject):
    """The page of a sampled-data loop's certificate (module doc)."""

    model = MODEL_FILE
    template = "sampled_loop.html.j2"

    def __init__(self, doc: dict[str, Any]) -> None:
        if not is_model_document(doc) or not is_sampled_document(doc):
            raise InputFileError(f"not a sampled-data loop's model certificate (kind '{KIND}' with a 'sampling' table)")
        super().__init__(doc)
        stored = as_dict(doc.get("model")).get("text")
        self.text = stored if isinstance(stored, str) else ""
        self.overrides = {str(k): v for k, v in as_dict(doc.get("overrides")).items()}
        self.parsed, self.error = self.read_model()
        try:
            self.raw = tomllib.loads(self.text)
        except tomllib.TOMLDecodeError:
            self.raw = {}
        states = doc.get("states")
        self.states = [str(s) for s in states] if isinstance(states, list) else (
            list(self.parsed.states) if self.parsed is not None else [])

    def read_model(self) -> tuple["SampledModel | None", str]:
        """The stored model text, parsed as a sampled-data loop, or None and why not."""
        from lyapcheck.models.language.sampling import parse_sampled

        file = text_of(as_dict(self.doc.get("model")).get("file", "<certificate>"))
        try:
            return parse_sampled(self.text, file, self.overrides), ""
        except LyapcheckError as exc:
            return None, str(exc)

    def class_context(self, eqs: Equations) -> ClassContext:
        equilibrium = as_dict(self.doc.get("equilibrium"))
        shifts = [as_fraction(equilibrium.get(s)) or Fraction(0) for s in self.states]
        return ClassContext(self.doc, eqs, self.states, shifts, (), None, {})

    def staircase(self, simulate: bool) -> tuple[Any, str]:
        """The staircase simulation (:func:`reports.sampled_figures.staircase_figure`), or None and why not."""
        from reports.sampled_figures import staircase_figure

        if not simulate:
            return None, "not requested"
        if self.parsed is None:
            return None, "the stored model text does not parse, so nothing can be simulated"
        try:
            return staircase_figure(self.parsed), ""
        except (LyapcheckError, ValueError, ArithmeticError, FloatingPointError) as exc:
            log.warning("no staircase simulation for the report: %s", exc)
            return None, f"the simulation failed: {exc}"

    def parts(self, eqs: Equations, *, ledger: bool, simulate: bool) -> dict[str, Any]:
        doc, raw = self.doc, self.raw
        model_part = as_dict(doc.get("model"))
        sampling = as_dict(doc.get("sampling"))
        equilibrium = as_dict(doc.get("equilibrium"))
        digest = hashlib.sha256(self.text.encode()).hexdigest()
        name = text_of(model_part.get("name", "model"))
        origin = self.parsed.plant.origin if self.parsed is not None else text_of(
            as_dict(raw.get("model")).get("source", ""))
        head = page_head(name, text_of(model_part.get("file", "")), origin, doc, ("sampling", "Sampling and controller"))
        head["toc"] = [("model", "The model"), ("sampling", "Sampling and controller"),
                       ("classes", "Classes, one by one"), ("simulation", "Simulation, sampled and held"),
                       ("recheck", "Exact re-check"), ("reproduce", "Reproducibility")]
        period = as_fraction(sampling.get("period"))
        figure, reason = self.staircase(simulate)
        from lyapcheck.models.surfaces.sampled_simulate import HOLD_TEXT

        return {
            **head,
            "discrete": False,
            "box_words": "",
            "states": self.states,
            "equilibrium": [(s, text_of(equilibrium.get(s, "0"))) for s in self.states],
            "parameters": quantities(as_dict(doc.get("parameters")), as_dict(raw.get("parameters")), self.overrides),
            "dynamics": [(s, text_of(as_dict(raw.get("dynamics")).get(s, "—"))) for s in self.states],
            "period_given": text_of(sampling.get("period_given", sampling.get("period", "?"))),
            "period_exact": text_of(sampling.get("period", "?")),
            "period_si": "?" if period is None else fmt_float(float(period)),
            "hold": HOLD_TEXT,
            "controller": [(str(u), text_of(law)) for u, law in as_dict(sampling.get("controller")).items()],
            "control_equilibrium": {str(u): text_of(v) for u, v in as_dict(sampling.get("control_equilibrium")).items()},
            "model_error": self.error,
            "sha256_stated": text_of(model_part.get("sha256", "")),
            "sha256_text": digest,
            "sha256_matches": digest == text_of(model_part.get("sha256", "")),
            "series_figure": figure,
            "series_reason": reason,
            "soundness": "",
            **page_tail(doc, self.text),
        }

    def fingerprints(self, context: dict[str, Any]) -> list[tuple[str, str]]:
        return model_text_fingerprints(context)

    def checked(self, recheck: bool) -> dict[str, Any]:
        return model_recheck(self.doc, recheck)


__all__ = ["SampledSubject", "is_sampled_document"]
