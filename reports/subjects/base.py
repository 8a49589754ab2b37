"""The interface of a certificate page's subject (see :mod:`reports.subjects`), and what subjects share."""

from __future__ import annotations

import json
from dataclasses import dataclass
from typing import Any, Final, Mapping, Sequence

from lyapcheck.answers import NEGATIVE, QUESTIONS, VERDICT_MEANING, answers_of
from reports.sections.base import ClassContext
from reports.typeset import Equations
from reports.views import as_dict

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


#: the questions' names in the head of a page (:data:`lyapcheck.answers.QUESTIONS`)
QUESTION_TITLES: Final = {"stability": "Stability", "safety": "Safety", "reach_avoid": "Reach-avoid",
                          "bounds": "Bounds"}
#: the verdicts a page shows as "bad" (red) and the one it shows as "ok" (green); every other
#: verdict, and one this version does not know, is "warn" (amber): a page is green only when
#: every asked question has a positive answer that covers the declared disturbances
BAD_VERDICTS: Final = frozenset({"unsafe", "unstable"})
OK_VERDICT: Final = "certified"
#: an answer's tone: the negative answers are bad, "local" (LES only) and "undecided" are warn,
#: every other positive answer is ok (shown green only on a page whose verdict is ok)
WARN_ANSWERS: Final = frozenset({"local", "undecided"})


@dataclass(frozen=True)
class Answer:
    """One line of a page's head: the question, the answer word, its tone and the sentence."""

    question: str
    title: str
    answer: str
    tone: str
    text: str


def verdict_tone(verdict: str, answers: Sequence[Answer] = ()) -> str:
    """``ok`` (green) only for ``certified`` with no negative answer, ``bad`` (red) for ``unsafe`` /
    ``unstable`` or any negative answer (a document whose stated verdict contradicts its answers
    is never shown green), ``warn`` (amber) otherwise."""
    if verdict in BAD_VERDICTS or any(a.answer in NEGATIVE for a in answers):
        return "bad"
    return "ok" if verdict == OK_VERDICT else "warn"


def answer_lines(doc: Mapping[str, Any], verdict: str) -> list[Answer]:
    """The document's answers (its ``answers`` table; a document from before answers were
    written gets those of its conditions, :func:`lyapcheck.answers.answers_of`, the rule
    ``verify`` checks stated answers against), one per question in the order of
    :data:`~lyapcheck.answers.QUESTIONS`. A positive answer is green only under a green verdict:
    an unsafe model's page is never green in its head."""
    stated = doc.get("answers")
    found = stated if isinstance(stated, dict) else answers_of(as_dict(doc.get("conditions")))
    ok_page = verdict == OK_VERDICT and not any(as_dict(a).get("answer") in NEGATIVE for a in found.values())
    out = []
    for question in [*QUESTIONS, *sorted(q for q in found if q not in QUESTIONS)]:
        if question not in found:
            continue
        entry = as_dict(found[question])
        word = str(entry.get("answer", "undecided"))
        if word in NEGATIVE:
            tone = "bad"
        elif word in WARN_ANSWERS:
            tone = "warn"
        else:
            tone = "ok" if ok_page else "plain"
        out.append(Answer(question, QUESTION_TITLES.get(question, question), word, tone, str(entry.get("text", ""))))
    return out


def verdict_head(doc: Mapping[str, Any]) -> dict[str, Any]:
    """The head of every certificate page: the verdict, what it means, its tone and the answers."""
    raw = doc.get("verdict", "unknown")
    verdict = raw if isinstance(raw, str) else str(raw)
    answers = answer_lines(doc, verdict)
    return {"verdict": verdict,
            "verdict_meaning": VERDICT_MEANING.get(verdict, "a verdict this version of lyapcheck does not know"),
            "verdict_tone": verdict_tone(verdict, answers),
            "answers": answers}


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


__all__ = ["STATUS_MEANING", "canonical_json", "Quantity", "Glance", "Subject", "Answer", "QUESTION_TITLES",
           "verdict_tone", "answer_lines", "verdict_head"]
