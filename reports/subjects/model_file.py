"""A model file (``lyapcheck certify --model FILE``) as a certificate page's subject: a polynomial or
rational loop, or a loop with functions.

Its parts: the model as the certificate stores it (name, source, states, parameters as given and
SI, a box's ranges, disturbances, equilibrium, outputs, domain, the dynamics as written, the
SHA-256 of the text); the field the certificates use (each denominator's positivity certificate,
the scaling); for 2 states the phase portrait with the certified sets and simulated trajectories
and the simulation cross-checks of the certificates (:mod:`reports.phase_portrait`); the
certificate **re-checked exactly** on the spot (:func:`lyapcheck.models.surfaces.certificate.verify_document`,
no solver, well under a second; a failure is an alarm at the top); the command line and the
model file verbatim.

A **loop with functions** (a model certificate with a ``"recast"`` table,
:mod:`lyapcheck.models.surfaces.verify`) has the same page (:class:`ModelFileSubject`, with the
per-kind words of :data:`WITH_FUNCTIONS`), with the **recasting** the certificates are proved on in
place of the field (each auxiliary with its definition, its value at the equilibrium and its flow;
the relations between them; the states taken modulo 2 pi), its classes shown by the model file's
section made for :data:`~reports.sections.base.RECAST_LOOP`, and the portrait in the loop's own
states; its exact re-check recasts the model text again.

The model text is re-read only by the model-file parser (:func:`lyapcheck.models.language.modelfile.parse_model`,
or :func:`~lyapcheck.models.language.modelfile.parse_any_model` for a loop with functions, a whitelist
over Python's ``ast``) and by :mod:`tomllib`; nothing from it is evaluated.
"""

from __future__ import annotations

import hashlib
import logging
import shlex
import tomllib
from dataclasses import dataclass
from fractions import Fraction
from typing import Any, Final

from markupsafe import Markup

from lyapcheck.errors import InputFileError, LyapcheckError
from lyapcheck.models.surfaces.certificate import KIND, is_model_document
from lyapcheck.models.language.modelfile import Model
from lyapcheck.models.language.recast import RecastModel
from lyapcheck.models.loop.discrete import is_discrete
from reports.figures import Figure
from reports.phase_portrait import CrossCheck, phase_portrait
from reports.sections.base import MODEL_FILE, RECAST_LOOP, ClassContext, text_of
from reports.subjects.base import STATUS_MEANING, Glance, Quantity, Subject, verdict_head
from reports.typeset import Equations
from reports.views import as_dict, as_fraction, as_number, fmt_float

log = logging.getLogger(__name__)

#: statuses of model classes beyond the paper's (DESIGN.md)
EXTRA_STATUS_MEANING: Final = {
    "not_applicable": "the class needs something the model or the command did not give (the summary says what)",
    "counterexample": "numerical evidence against the property (a reproducible trajectory), not an exact proof",
}


#: what each kind of relation of a loop with functions' recasting says
RELATION_WORDS: Final = {"eq": "= 0", "ge": "≥ 0"}


@dataclass(frozen=True)
class LoopKind:
    """What the page of one kind of model loop says in its own words.

    ``model`` and ``template``: its classes' sections and its template of the subject's parts;
    ``second``: the table of contents' entry after the model (anchor, title: the field, or the
    recasting); ``unparsed`` why there is no portrait when the stored text does not parse, and
    ``failed`` what a portrait that raised is called.
    """

    model: str
    template: str
    second: tuple[str, str]
    unparsed: str
    failed: str


#: a polynomial or rational loop, and a loop with functions
POLYNOMIAL: Final = LoopKind(MODEL_FILE, "model_file.html.j2", ("field", "The field the certificates use"),
                             "nothing can be simulated", "the simulation failed")
WITH_FUNCTIONS: Final = LoopKind(RECAST_LOOP, "recast_loop.html.j2",
                                 ("recasting", "The recasting the certificates are proved on"),
                                 "its field cannot be drawn", "the portrait failed")


def is_map_document(doc: object) -> bool:
    """A certificate of a discrete-time map: its stored model text says ``[model] time = "discrete"``
    (read by :mod:`tomllib` only, so that a text that no longer parses is still known as a map)."""
    text = as_dict(as_dict(doc).get("model")).get("text") if isinstance(doc, dict) else None
    try:
        raw = tomllib.loads(text) if isinstance(text, str) else {}
    except tomllib.TOMLDecodeError:
        return False
    return as_dict(raw.get("model")).get("time") == "discrete"


def is_recast_document(doc: object) -> bool:
    """A certificate of a loop with functions: a model certificate with a ``"recast"`` table."""
    return isinstance(doc, dict) and isinstance(doc.get("recast"), dict)


@dataclass
class Denominator:
    text: str
    how: str


def quantities(exact_si: dict[str, Any], given: dict[str, Any], overrides: dict[str, Any],
               box: dict[str, Any] | None = None) -> list[Quantity]:
    """One row per quantity; a parameter of the certificate's box shows its range (every value in
    it is covered), not the file's nominal value."""
    rows = []
    box = box or {}
    for name, value in exact_si.items():
        bounds = box.get(name)
        if isinstance(bounds, list) and len(bounds) == 2:
            lo, hi = (as_fraction(b) for b in bounds)
            if lo is not None and hi is not None:
                rows.append(Quantity(str(name), text_of(given.get(name, "—")), f"[{fmt_float(float(lo))}, "
                                     f"{fmt_float(float(hi))}]", f"[{lo}, {hi}]",
                                     f"the box: every value in this range is covered (--box {name}=...); the file's "
                                     "value is not used"))
                continue
        exact = as_fraction(value)
        note = ""
        if name in overrides:
            raw, note = overrides[name], f"set on the command line (--set {name}=...)"
        else:
            raw = given.get(name, "—")
        si = "—" if exact is None else fmt_float(float(exact))
        rows.append(Quantity(str(name), text_of(raw), si,
                             "" if exact is None or exact.denominator == 1 else str(exact), note))
    return rows


def denominators(fld: dict[str, Any]) -> list[Denominator]:
    out = []
    for cert in fld.get("denominators") or []:
        cert = as_dict(cert)
        text = text_of(cert.get("denominator", "a denominator"))
        sign = cert.get("sign", 1)
        kind = cert.get("kind")
        if kind == "constant":
            how = f"a positive constant ({text_of(cert.get('value'))}), exactly"
        elif kind == "sos":
            basis = as_dict(cert.get("gram_sigma")).get("basis")
            size = len(basis) if isinstance(basis, list) else 0
            scales = ", ".join(map(text_of, cert.get("scales") or []))
            c, norm = text_of(cert.get("c")), text_of(cert.get("normalization"))
            how = (f"positive everywhere: after the scaling of its variables by ({scales}) and division by {norm}, it "
                   f"equals c + sigma with c = {c} > 0 and sigma a sum of squares (its {size} x {size} Gram matrix "
                   "positive semidefinite); checked exactly")
        else:
            how = f"certificate of kind {kind!r}"
        if sign == -1:
            how = ("negative everywhere (the certificate is for its negative), so its sign moves to the "
                   "numerator: " + how)
        out.append(Denominator(text, how))
    return out


def scaling(fld: dict[str, Any], states: list[str], disturbances: list[str], outputs: list[str]) -> list[tuple[str, str]]:
    stored = as_dict(fld.get("scaling"))
    rows: list[tuple[str, str]] = []
    for key, names, what in (("states", states, "state"), ("disturbances", disturbances, "disturbance"),
                             ("outputs", outputs, "output")):
        values = stored.get(key)
        if isinstance(values, list):
            for name, value in zip(names, values):
                rows.append((f"{what} {name}", text_of(value)))
    for key, what in (("time", "time: t = T tau, T"), ("denominator", "denominator factor")):
        if key in stored:
            rows.append((what, text_of(stored[key])))
    return rows


def solvers(conditions: dict[str, Any]) -> list[tuple[str, str]]:
    """Per class: how many solves, their outcomes and the solver time (the full log is in the file)."""
    out = []
    for name, cond in conditions.items():
        solver = as_dict(as_dict(cond).get("solver"))
        solves = solver.get("solves")
        stored = as_dict(solver.get("stored"))
        if stored:  # lyapcheck.models.engines.store: no solve in this run
            # (an entry's own record of its search is not re-provable: not shown)
            out.append((str(name), "no solve: the certificate its search found in an earlier run, re-checked exactly"))
            continue
        if not isinstance(solves, list) or not solves:
            continue
        outcomes: dict[str, int] = {}
        seconds = 0.0
        names = set()
        for s in solves:
            s = as_dict(s)
            outcome = text_of(s.get("outcome", s.get("status", "?")))
            outcomes[outcome] = outcomes.get(outcome, 0) + 1
            seconds += as_number(s.get("solve_seconds")) or 0.0
            names.add(text_of(s.get("solver", "?")))
        counts = ", ".join(f"{n} {k}" for k, n in sorted(outcomes.items()))
        out.append((str(name), f"{len(solves)} solves with {', '.join(sorted(names))} ({counts}), "
                               f"{fmt_float(seconds, 3)} s in the solver"))
    return out


def exact_decimal(value: Fraction | None) -> str:
    """A box bound as the command line reads it: the exact decimal where it terminates (every box
    that ``--box`` or a sweep makes), else 17 significant digits."""
    from decimal import Decimal, localcontext

    if value is None:
        return "?"
    rest = value.denominator
    for p in (2, 5):
        while rest % p == 0:
            rest //= p
    if rest != 1:
        return f"{float(value):.17g}"
    with localcontext() as ctx:  # a terminating decimal: enough digits to be exact
        ctx.prec = len(str(value.numerator)) + 2 * len(str(value.denominator)) + 2
        return format((Decimal(value.numerator) / Decimal(value.denominator)).normalize(), "f")


def command(doc: dict[str, Any]) -> str:
    model = as_dict(doc.get("model"))
    file = text_of(model.get("file") or "model.toml")
    parts = ["lyapcheck", "certify", "--model", shlex.quote(file)]
    for name, value in as_dict(doc.get("overrides")).items():
        parts += ["--set", shlex.quote(f"{name}={value}")]
    if isinstance(doc.get("candidate"), str):
        parts += ["--candidate", shlex.quote(doc["candidate"])]
    for name, bounds in as_dict(doc.get("box")).items():
        if isinstance(bounds, list) and len(bounds) == 2:
            lo, hi = (exact_decimal(as_fraction(b)) for b in bounds)
            parts += ["--box", shlex.quote(f"{name}={lo}..{hi}")]
    names = [str(n) for n in as_dict(doc.get("conditions"))]
    if names:
        parts += ["--classes", shlex.quote(",".join(names))]
    parts += ["--out", "certificate.json"]
    return (" ".join(parts) + "\nlyapcheck verify certificate.json   # exact re-check, no solver\n"
            "lyapcheck report certificate.json --html report.html --pdf report.pdf")


def model_text_fingerprints(context: dict[str, Any]) -> list[tuple[str, str]]:
    """The fingerprints a model certificate's page shows: the model text's SHA-256 as stored and as
    recomputed, and the whole certificate's (every model page: a loop's and a sampled-data loop's)."""
    return [("SHA-256 of the model text (stored)", context["sha256_stated"]),
            ("SHA-256 of the model text (recomputed)", context["sha256_text"]),
            ("SHA-256 of the whole certificate (canonical JSON)", context["hash_document"])]


def model_recheck(doc: dict[str, Any], recheck: bool) -> dict[str, Any]:
    """The page's exact re-check of a model certificate (:func:`recheck_rows`), or "not requested"."""
    rows, error = recheck_rows(doc) if recheck else ([], "not requested")
    return {"recheck": rows, "recheck_error": error, "recheck_failed": [r for r in rows if not r[1]]}


def recheck_rows(doc: dict[str, Any]) -> tuple[list[tuple[str, bool, str]], str]:
    """Re-check every claim exactly (no solver); (rows, error if it could not run)."""
    from lyapcheck.models.surfaces.certificate import verify_document

    try:
        return verify_document(doc), ""
    except LyapcheckError as exc:
        return [], str(exc)


def portrait(doc: dict[str, Any], model: Model | RecastModel | None, simulate: bool,
             kind: LoopKind = POLYNOMIAL) -> tuple[Figure | None, str, list[CrossCheck]]:
    if not simulate:
        return None, "not requested", []
    if model is None:
        return None, f"the stored model text does not parse, so {kind.unparsed}", []
    try:
        drawn = phase_portrait(doc, model)
    except (LyapcheckError, ValueError, ArithmeticError, FloatingPointError) as exc:
        log.warning("no phase portrait for the report: %s", exc)
        return None, f"{kind.failed}: {exc}", []
    return drawn.figure, drawn.reason, drawn.checks


def soundness_alarm(checks: list[CrossCheck], what: str) -> str:
    """The alarm at the top of the page when ``what`` (a simulation, an iteration) contradicts a
    certificate, or ``""``."""
    failed = [c for c in checks if not c.ok]
    if not failed:
        return ""
    return f"SOUNDNESS: {what} contradicts a certificate: " + "; ".join(f"{c.what} ({c.detail})" for c in failed) + "."


#: a map's page: the toc's entries whose words differ from a continuous model's
MAP_TOC: Final = {"phase": "Iterates of the map", "size": "The certified region, iterated",
                  "recasting": "The functions of the map"}


def map_figures_of(doc: dict[str, Any], model: Model | RecastModel | None, simulate: bool
                   ) -> tuple[Any, str]:
    """A map's figures (:func:`reports.map_figures.map_figures`), or None and why not."""
    from reports.map_figures import map_figures

    if not simulate:
        return None, "not requested"
    if model is None:
        return None, "the stored model text does not parse, so nothing can be iterated"
    try:
        return map_figures(doc, model), ""
    except (LyapcheckError, ValueError, ArithmeticError, FloatingPointError, KeyError, TypeError) as exc:
        log.warning("no iterates for the report: %s", exc)
        return None, f"the iteration failed: {exc}"


def region_slices(doc: dict[str, Any], model: Model | RecastModel | None, simulate: bool
                  ) -> tuple[Figure | None, str]:
    """The certified region against the simulated one, in 2-D slices (:mod:`reports.region_slices`),
    or None and why not."""
    from reports.region_slices import size_figure

    if not simulate:
        return None, "not requested"
    if model is None:
        return None, "the stored model text does not parse"
    try:
        return size_figure(doc, model)
    except (LyapcheckError, ValueError, ArithmeticError, FloatingPointError, KeyError, TypeError) as exc:
        log.warning("no slices of the certified region for the report: %s", exc)
        return None, f"the slices could not be drawn: {exc}"


def auxiliary_rows(recast: dict[str, Any]) -> list[tuple[str, str, str, str]]:
    """(auxiliary, definition, value at the equilibrium, flow) per auxiliary of the recasting."""
    flows, values = as_dict(recast.get("flows")), as_dict(recast.get("values"))
    rows = []
    for name, definition in as_dict(recast.get("auxiliaries")).items():
        value = text_of(values[name]) if name in values else "a constant (not shifted)"
        flow = text_of(flows[name]) if name in flows else "none: not differentiable here (a V may not use it)"
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


def page_head(name: str, file: str, origin: str, doc: dict[str, Any], second: tuple[str, str]) -> dict[str, Any]:
    """What the page of every model certificate opens with: title, the verdict with the answer to
    each question (:func:`reports.subjects.base.verdict_head`), the glance table, and the table of
    contents, whose second entry (``second``: anchor, title) is the field or the recasting."""
    return {
        "kind": "model-certificate",
        "title": f"lyapcheck model certificate report: {name}",
        "name": name,
        "file": file,
        "origin": origin,
        **verdict_head(doc),
        "status_meaning": {**STATUS_MEANING, **EXTRA_STATUS_MEANING},
        "glance": Glance(("class", "status", "property", "what it found", "key figures"), True,
                         ("certified", "refuted", "counterexample", "not_certified", "inconclusive",
                          "not_applicable")),
        "toc": [("model", "The model"), second, ("classes", "Classes, one by one"), ("phase", "Phase portrait"),
                ("size", "Size of the certified region"),
                ("recheck", "Exact re-check"), ("reproduce", "Reproducibility")],
        "classes_anchor": "classes",
        "classes_heading": "Classes, one by one",
    }


class ModelFileSubject(Subject):
    """The page of a model certificate: a polynomial or rational loop's, or a loop with functions'
    (:func:`is_recast_document`; :data:`WITH_FUNCTIONS`)."""

    def __init__(self, doc: dict[str, Any]) -> None:
        if not is_model_document(doc):
            raise InputFileError(f"not a model certificate (missing kind '{KIND}')")
        if isinstance(doc.get("sampling"), dict):  # its loop is a plant under held controls, not a field to integrate
            raise InputFileError("a sampled-data loop's certificate ([sampling]) is the subject of "
                                 "reports.subjects.sampled, not of a model file's page")
        super().__init__(doc)
        self.kind = WITH_FUNCTIONS if is_recast_document(doc) else POLYNOMIAL
        self.model, self.template = self.kind.model, self.kind.template
        stored = as_dict(doc.get("model")).get("text")
        self.text = stored if isinstance(stored, str) else ""
        self.overrides = {str(k): v for k, v in as_dict(doc.get("overrides")).items()}
        self.parsed, self.error = self.read_model()
        # a map is never integrated as a field: its page iterates it instead (reports.map_figures)
        self.discrete = is_map_document(doc) or is_discrete(self.parsed)
        try:
            self.raw = tomllib.loads(self.text)
        except tomllib.TOMLDecodeError:
            self.raw = {}
        states = [str(s) for s in doc.get("states") or []] if isinstance(doc.get("states"), list) else []
        if self.parsed is not None and not states:
            states = list(self.parsed.states)
        self.states = states

    def read_model(self) -> tuple[Model | RecastModel | None, str]:
        """The stored model text, parsed as its kind of loop, or None and why not."""
        from lyapcheck.models.language.modelfile import parse_any_model, parse_model

        file = text_of(as_dict(self.doc.get("model")).get("file", "<certificate>"))
        try:
            if self.kind is POLYNOMIAL:
                return parse_model(self.text, file, self.overrides), ""
            candidate = self.doc.get("candidate")
            parsed = parse_any_model(self.text, file, self.overrides,
                                     candidate=candidate if isinstance(candidate, str) else None)
        except LyapcheckError as exc:
            return None, str(exc)
        if isinstance(parsed, RecastModel):
            return parsed, ""
        return None, "it has no functions, so it is not the loop with functions this certificate is about"

    def class_context(self, eqs: Equations) -> ClassContext:
        equilibrium = as_dict(self.doc.get("equilibrium"))
        shifts = [as_fraction(equilibrium.get(s)) or Fraction(0) for s in self.states]
        outputs = tuple(self.parsed.outputs) if self.parsed is not None else ()
        set_text = dict(self.parsed.set_text) if self.parsed is not None else {}
        return ClassContext(self.doc, eqs, self.states, shifts, outputs, self.doc.get("box"), set_text)

    def parts(self, eqs: Equations, *, ledger: bool, simulate: bool) -> dict[str, Any]:
        doc, model, raw = self.doc, self.parsed, self.raw
        model_part = as_dict(doc.get("model"))
        # a map is iterated, never integrated: its own figures stand where the portrait and the slices do
        visuals = self.map_visuals(simulate) if self.discrete else self.flow_visuals(simulate)
        digest = hashlib.sha256(self.text.encode()).hexdigest()
        equilibrium = as_dict(doc.get("equilibrium"))
        name = text_of(model_part.get("name", "model"))
        box = None if self.kind is WITH_FUNCTIONS else as_dict(doc.get("box"))
        head = page_head(name, text_of(model_part.get("file", "")),
                         model.origin if model is not None else text_of(as_dict(raw.get("model")).get("source", "")),
                         doc, self.kind.second)
        if self.discrete:
            head["toc"] = [(anchor, MAP_TOC.get(anchor, title)) for anchor, title in head["toc"]]
        return {
            **head,
            "discrete": self.discrete,
            "states": self.states,
            "equilibrium": [(s, text_of(equilibrium.get(s, "0"))) for s in self.states],
            "parameters": quantities(as_dict(doc.get("parameters")), as_dict(raw.get("parameters")), self.overrides,
                                     box),
            "domain": [(str(k), text_of(v)) for k, v in as_dict(raw.get("domain")).items()],
            "dynamics": [(s, text_of(as_dict(raw.get("dynamics")).get(s, "—"))) for s in self.states],
            "candidate": doc.get("candidate") if isinstance(doc.get("candidate"), str) else "",
            "model_error": self.error,
            "sha256_stated": text_of(model_part.get("sha256", "")),
            "sha256_text": digest,
            "sha256_matches": digest == text_of(model_part.get("sha256", "")),
            **visuals,
            **(self.recasting() if self.kind is WITH_FUNCTIONS else self.field()),
            "soundness": soundness_alarm(visuals["checks"], "an iteration" if self.discrete else "a simulation"),
            **page_tail(doc, self.text),
        }

    def flow_visuals(self, simulate: bool) -> dict[str, Any]:
        """A continuous loop's figures: the phase portrait with its cross-checks, and the region's slices."""
        figure, figure_reason, checks = portrait(self.doc, self.parsed, simulate, self.kind)
        slices, slices_reason = region_slices(self.doc, self.parsed, simulate)
        return {"portrait": figure, "figure_reason": figure_reason, "size_figure": slices,
                "size_reason": slices_reason, "checks": checks}

    def map_visuals(self, simulate: bool) -> dict[str, Any]:
        """A discrete-time map's figures (:mod:`reports.map_figures`): the iterates, the certified region with
        the iterates of starts inside it, the staircase, and the checks of those iterates."""
        figures, reason = map_figures_of(self.doc, self.parsed, simulate)
        if figures is None:
            return {"portrait": None, "figure_reason": reason, "size_figure": None, "size_reason": reason,
                    "series_figure": None, "series_reason": reason, "checks": []}
        return {"portrait": figures.iterates, "figure_reason": figures.iterates_reason,
                "size_figure": figures.region, "size_reason": figures.region_reason,
                "series_figure": figures.series, "series_reason": figures.series_reason, "checks": figures.checks}

    def field(self) -> dict[str, Any]:
        """A polynomial loop's own parts: its box, disturbances, outputs and field."""
        doc, model, raw = self.doc, self.parsed, self.raw
        try:
            from lyapcheck.models.classes.claims import box_words

            box_text = box_words(as_dict(doc.get("box"))) if as_dict(doc.get("box")) else ""
        except (TypeError, ValueError, ArithmeticError):
            box_text = "a box of parameters (its bounds are malformed)"
        fld = as_dict(doc.get("field"))
        disturbances = [str(d) for d in as_dict(doc.get("disturbances"))]
        outputs_text = dict(model.output_text) if isinstance(model, Model) else {
            str(k): text_of(v) for k, v in as_dict(raw.get("outputs")).items()}
        return {
            "box_words": box_text,
            "disturbances": quantities(as_dict(doc.get("disturbances")), as_dict(raw.get("disturbances")),
                                       self.overrides),
            "outputs": list(outputs_text.items()),
            "model_text": self.text,
            "denominators": denominators(fld),
            "scaling": scaling(fld, self.states, disturbances, list(outputs_text)),
        }

    def recasting(self) -> dict[str, Any]:
        """A loop with functions' own part: the recasting its certificates are proved on."""
        recast = as_dict(self.doc.get("recast"))
        variables = recast.get("variables")
        return {"variables": [text_of(v) for v in variables] if isinstance(variables, list) else [],
                "auxiliaries": auxiliary_rows(recast), "relations": relation_rows(recast),
                "angles": angle_rows(recast)}

    def fingerprints(self, context: dict[str, Any]) -> list[tuple[str, str]]:
        return model_text_fingerprints(context)

    def checked(self, recheck: bool) -> dict[str, Any]:
        return model_recheck(self.doc, recheck)


def page_tail(doc: dict[str, Any], text: str) -> dict[str, Any]:
    """The end of a model page, the same for both kinds of model: the command that re-makes it, the
    model file verbatim, and the solvers' outcomes (never a verdict)."""
    return {
        "command": command(doc),
        "verbatim_title": "The model file, verbatim (as stored in the certificate)",
        "verbatim": text,
        "solvers": solvers(as_dict(doc.get("conditions"))),
        "solvers_title": "Solver outcomes",
        "solvers_exact": False,
        # Markup: the page's own words (not input), printed as written
        "solvers_note": Markup("A solver's outcome is never a verdict: every status above comes from an exact check. "
                               "The full solver log of each class is in the certificate file."),
    }


__all__ = ["ModelFileSubject", "is_map_document", "map_figures_of", "soundness_alarm", "MAP_TOC", "page_tail",
           "page_head", "EXTRA_STATUS_MEANING", "quantities", "LoopKind",
           "POLYNOMIAL", "WITH_FUNCTIONS", "is_recast_document", "denominators", "scaling", "solvers", "command",
           "recheck_rows", "model_recheck", "model_text_fingerprints", "portrait", "auxiliary_rows", "relation_rows", "angle_rows"]
