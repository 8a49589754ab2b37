"""A certificate written by a search, as a certificate page's subject: ``lyapcheck tune --out`` (the
winner's certificate with its ``tune`` table) and ``certify --maximize/--minimize --out`` (the proved
value's certificate with its ``extremum`` table).

The page is the model file's (:class:`~reports.subjects.model_file.ModelFileSubject`: the winner's
model, classes, portrait, exact re-check), with the search first (``search.html.j2`` wraps the model's
own template):

- **tune**: the objective, its sense and class, the box; the winner's point and certified figure with
  the sentence ``tune`` states, the certified neighbourhood's sentence; the box map (each point tried
  coloured by its proved figure or marked by its outcome, the winner, the neighbourhood as a rectangle;
  one parameter: a line plot) and the objective along the search (per attempt, best so far)
  (:mod:`reports.search_figures`); every point tried and every box tried around the winner.
- **extremum**: the parameter, the range, the answer (the value proved, the first that failed and
  how); every value tried with its outcome, as a table and a figure.

The exact re-check adds the search's own rows (:func:`lyapcheck.models.surfaces.search_tables.search_rows`,
which ``verify`` runs too): a table whose value, point, neighbourhood or record was changed raises
the page's alarm. The other figures of the record were proved when they were tried and are not
re-proved here; the page says so. The table is read defensively: a malformed one is said in one line,
never raised.
"""

from __future__ import annotations

import logging
from fractions import Fraction
from typing import Any, Final

from lyapcheck.errors import LyapcheckError
from reports.figures import Figure
from reports.subjects.model_file import ModelFileSubject
from reports.typeset import Equations
from reports.views import as_dict, fmt_float

log = logging.getLogger(__name__)

#: what a malformed table or a figure that cannot be drawn raises (said on the page, never raised)
MALFORMED: Final = (KeyError, TypeError, ValueError, ArithmeticError, IndexError, AttributeError)
#: the template that wraps the model's own (its macros call the model template's)
TEMPLATE: Final = "search.html.j2"


def _figure_text(value: Fraction | None, sense: str) -> tuple[str, str]:
    """(a float on the weaker side, the exact value) of a proved figure; dashes when there is none."""
    from lyapcheck.models.surfaces.tune import weaker_float

    if value is None:
        return "—", ""
    return fmt_float(weaker_float(value, sense), 6), "" if value.denominator == 1 else str(value)


class SearchSubject(ModelFileSubject):
    """The model page of a searched certificate with the search in front (subclasses: :class:`TuneSubject`,
    :class:`ExtremumSubject`). ``table`` is the document's key, ``heading`` the section's title."""

    table = ""
    heading = ""
    title_words = ""

    def __init__(self, doc: dict[str, Any]) -> None:
        super().__init__(doc)
        self.inner = self.template  # the model's own template: the wrapper calls its macros
        self.template = TEMPLATE

    def parts(self, eqs: Equations, *, ledger: bool, simulate: bool) -> dict[str, Any]:
        context = super().parts(eqs, ledger=ledger, simulate=simulate)
        try:
            search = self.search_part()
        except MALFORMED as exc:  # (each part reads defensively; this is the last guard of the page)
            search = {"error": f"the {self.table} table is malformed ({type(exc).__name__}: {exc})"}
        context.update({
            "inner": self.inner,
            "title": f"lyapcheck {self.title_words} report: {context.get('name', 'model')}",
            "toc": [("search", self.heading), *context["toc"]],
            "search": {"kind": self.table, "heading": self.heading, "error": "", "flag": "", **search},
        })
        return context

    def search_part(self) -> dict[str, Any]:
        raise NotImplementedError

    def checked(self, recheck: bool) -> dict[str, Any]:
        """The model's exact re-check and the search table's rows (as ``verify`` runs them)."""
        from lyapcheck.models.surfaces.search_tables import search_rows

        out = super().checked(recheck)
        if not recheck or out["recheck_error"]:
            return out
        try:
            extra = search_rows(self.doc)
        except LyapcheckError as exc:
            extra = [(self.table, False, f"the {self.table} table could not be re-checked: {exc}")]
        rows = [*out["recheck"], *extra]
        return {**out, "recheck": rows, "recheck_failed": [r for r in rows if not r[1]]}


class TuneSubject(SearchSubject):
    """``lyapcheck tune --out``: the winner's certificate and its search."""

    table = "tune"
    heading = "The search (lyapcheck tune)"
    title_words = "tune"

    def search_part(self) -> dict[str, Any]:
        from lyapcheck.models.surfaces.extremum import decimal
        from lyapcheck.models.surfaces.tune import Tuning, neighbourhood_sentence, winner_sentence

        t = as_dict(self.doc.get("tune"))
        try:
            found = Tuning.from_json(t)
        except MALFORMED as exc:
            return {"error": f"the tune table is malformed ({type(exc).__name__}: {exc})"}
        goal, sense = found.objective, found.objective.sense
        names = [n for n, _, _ in found.boxes]
        point = as_dict(t.get("point"))
        if found.value is not None and point:
            sentence = winner_sentence(goal, {str(k): Fraction(str(v)) for k, v in point.items()}, found.value)
        else:
            sentence = f"no winner: {found.why or 'no point was certified'} ({goal.words()})"
        nb = as_dict(t.get("neighbourhood"))
        try:
            nb_sentence = neighbourhood_sentence(goal, nb) if nb else "no neighbourhood was searched"
        except MALFORMED:
            nb_sentence = "the neighbourhood's entry is malformed"
        value, exact = _figure_text(found.value, sense)
        rows = []
        for i, p in enumerate(found.tried, start=1):
            rows.append({"index": i, "phase": p.phase, "coords": [decimal(p.values[n]) for n in names],
                         "figure": _figure_text(p.value, sense)[0], "outcome": p.outcome,
                         "seconds": fmt_float(p.seconds, 3), "winner": p is found.winner})
        tries = [{"box": ", ".join(map(str, tr.get("box") or [])), "outcome": str(tr.get("outcome", "")),
                  "figure": "—" if tr.get("value") is None else fmt_float(float(tr["value"]), 6)}
                 for tr in (as_dict(x) for x in nb.get("tries") or [])]
        box_map, trace, reason = self.figures(found, nb)
        return {
            "objective": goal.text, "words": goal.words(), "sense": "maximized" if sense == "max" else "minimized",
            "cls": goal.cls, "names": names,
            "box": [(n, decimal(lo), decimal(hi)) for n, lo, hi in found.boxes],
            "grid": found.grid, "points": len(found.tried),
            "certified_points": sum(p.value is not None for p in found.tried),
            "point": [(str(k), str(v)) for k, v in point.items()], "value": value, "value_exact": exact,
            "sentence": sentence, "neighbourhood_sentence": nb_sentence,
            "neighbourhood_certified": bool(nb.get("certified")),
            "threshold": "" if nb.get("threshold") is None else fmt_float(float(nb["threshold"]), 6),
            "rows": rows, "tries": tries, "settings": list(found.settings),
            "box_map": box_map, "trace": trace, "figure_reason": reason,
        }

    def figures(self, found: Any, nb: dict[str, Any]) -> tuple[Figure | None, Figure | None, str]:
        """The box map and the objective along the search (None and why when they cannot be drawn)."""
        from lyapcheck.models.surfaces.extremum import parse_range
        from lyapcheck.models.surfaces.tune import weaker_float
        from reports.search_figures import Tried, box_map, objective_trace

        goal, sense = found.objective, found.objective.sense
        names = [n for n, _, _ in found.boxes]
        if not names or not found.tried:
            return None, None, "the search has no points to draw"
        try:
            tried = [Tried(tuple(float(p.values[n]) for n in names), p.phase,
                           None if p.value is None else weaker_float(p.value, sense), p.outcome) for p in found.tried]
            winner = next((i for i, p in enumerate(found.tried) if p is found.winner), None)
            boxes = []
            for tr in (as_dict(x) for x in nb.get("tries") or []):
                ranges = {name: (float(lo), float(hi)) for name, lo, hi in
                          (parse_range(str(text), "box") for text in tr.get("box") or [])}
                boxes.append([ranges[n] for n in names])
            proved_box = None
            if nb.get("certified"):
                stated = as_dict(nb.get("box"))
                proved_box = [(float(Fraction(str(stated[n][0]))), float(Fraction(str(stated[n][1])))) for n in names]
                boxes = [b for b in boxes if b != proved_box]
            label = f"{goal.text} ({'maximized' if sense == 'max' else 'minimized'})"
            value = nb.get("value") if nb.get("certified") else None
            drawn = box_map(names, [(float(lo), float(hi)) for _, lo, hi in found.boxes], tried, winner, proved_box,
                            boxes, label=label, sense=sense, title=f"tune: {goal.text}, the box searched",
                            neighbourhood_value=None if value is None else float(value))
            trace = objective_trace(tried, winner, label=label, sense=sense, title=f"tune: {goal.text} along the search")
        except (LyapcheckError, *MALFORMED) as exc:
            log.warning("no figures of the tune search for the report: %s", exc)
            return None, None, f"the search's figures could not be drawn: {exc}"
        return drawn, trace, ""


class ExtremumSubject(SearchSubject):
    """``certify --maximize/--minimize --out``: the proved value's certificate and its bisection."""

    table = "extremum"
    heading = "The search (certify --maximize / --minimize)"
    title_words = "certify --maximize/--minimize"

    def search_part(self) -> dict[str, Any]:
        from lyapcheck.models.surfaces.extremum import Extremum, decimal
        from reports.search_figures import bisection

        try:
            found = Extremum.from_json(as_dict(self.doc.get("extremum")))
        except MALFORMED as exc:
            return {"error": f"the extremum table is malformed ({type(exc).__name__}: {exc})"}
        flag = "--maximize" if found.direction == "max" else "--minimize"
        rows = [{"index": i, "value": decimal(s.value), "outcome": s.outcome, "verdict": s.verdict,
                 "seconds": fmt_float(s.seconds, 3), "proved": s.value == found.proved and s.passed,
                 "failed": found.failed is not None and s is found.failed} for i, s in enumerate(found.steps, start=1)]
        try:
            drawn: Figure | None = bisection(
                found.parameter, found.direction, float(found.low), float(found.high),
                [(float(s.value), s.outcome) for s in found.steps],
                None if found.proved is None else float(found.proved),
                None if found.failed is None else float(found.failed.value),
                title=f"certify {flag} {found.parameter}={decimal(found.low)}..{decimal(found.high)}")
            reason = ""
        except MALFORMED as exc:
            log.warning("no figure of the bisection for the report: %s", exc)
            drawn, reason = None, f"the figure could not be drawn: {exc}"
        return {
            "parameter": found.parameter, "flag": flag,
            "word": "largest" if found.direction == "max" else "smallest",
            "range": (decimal(found.low), decimal(found.high)), "sentence": found.sentence(),
            "proved": found.proved_text(),
            "failed": "" if found.failed is None else decimal(found.failed.value),
            "failed_outcome": "" if found.failed is None else found.failed.outcome,
            "rows": rows, "figure": drawn, "figure_reason": reason,
        }


__all__ = ["SearchSubject", "TuneSubject", "ExtremumSubject", "TEMPLATE"]
