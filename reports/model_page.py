"""The report of a model certificate (``lyapcheck certify --model FILE``): its page content.

A model certificate (:mod:`lyapcheck.models.certificate`, kind ``lyapcheck-model-certificate``)
is about any polynomial or rational closed loop of a model file. Its page shows

- the verdict, and the result of re-checking the certificate exactly on the spot
  (:func:`lyapcheck.models.certificate.verify_document`: no solver, well under a second);
- a table of every class: status, property, summary and its key figures;
- the model as the certificate stores it: name, source, states, parameters (as given and SI),
  disturbances, equilibrium, outputs, domain, the dynamics as written, the SHA-256 of the text;
- the field the certificates use: each denominator's positivity certificate, and the scaling;
- each class on its own: the exact polynomial ``V`` (typeset, and as plain text in the model-file
  language), level, ball, the Jacobian and ``P`` of the linearization, the Gram matrices' sizes;
- for 2 states, the phase portrait with the certified sets and simulated trajectories, and the
  simulation cross-checks of the certificates (:mod:`reports.model_figures`); for other sizes,
  the tables alone, and the page says so;
- how to reproduce it: commands, the model file verbatim, fingerprints, solver outcomes, versions.

Every string from the document reaches the page as text (the template escapes it). The model
text is re-read only by the model-file parser (:func:`lyapcheck.models.modelfile.parse_model`,
a whitelist over Python's ``ast``) and by :mod:`tomllib`; nothing from it is evaluated.
"""

from __future__ import annotations

import hashlib
import logging
import shlex
import tomllib
from dataclasses import dataclass, field
from fractions import Fraction
from pathlib import Path
from typing import Any, Final

from lyapcheck.errors import InputFileError, LyapcheckError
from lyapcheck.models.certificate import KIND, SCHEMA_VERSION, is_model_document
from lyapcheck.models.certify import VERDICT_MEANING
from lyapcheck.models.modelfile import Model
from reports.certificate_page import STATUS_MEANING, canonical_json
from reports.figures import Figure
from reports.model_figures import CrossCheck, phase_portrait
from reports.model_polynomials import MAX_PLAIN_CHARS, ExactPolynomial
from reports.typeset import Equation, Equations, parse_matrix, typst_symbol, versions
from reports.views import Item, as_dict, as_fraction, as_number, fmt_float, matrix_item, scalar_text, value_items

log = logging.getLogger(__name__)

#: what a reader should call each class of a model file (DESIGN.md); unknown ones keep their key
CLASS_TITLES: Final = {
    "linearization": "Linearization at the equilibrium",
    "quadratic": "Global quadratic Lyapunov function",
    "sos_gas": "Global polynomial Lyapunov function (sum of squares)",
    "roa": "Region of attraction: a certified sublevel set",
    "candidate": "Your candidate V",
    "sos_bound": "Ultimate bound on each output under bounded disturbances",
}
#: one sentence per property a class can prove (DESIGN.md)
PROPERTY_MEANING: Final = {
    "LES": "local exponential stability of the equilibrium",
    "GES": "global exponential stability: |x(t)| <= k |x0| exp(-rate t) from every start",
    "GAS": "global asymptotic stability: every start converges to the equilibrium",
    "ROA": "every start in the stated set converges to the equilibrium",
    "ultimate_bound": "limsup |y| <= B for each output, from every start, for every disturbance within its bounds",
    "invariant_set": "a set that no trajectory leaves",
    "ISS": "input-to-state stability",
}
#: statuses of model classes beyond the paper's (DESIGN.md)
EXTRA_STATUS_MEANING: Final = {
    "not_applicable": "the class needs something the model or the command did not give (the summary says what)",
    "counterexample": "numerical evidence against the property (a reproducible trajectory), not an exact proof",
}
#: how the linearization decided (its certificate's "method")
METHODS: Final = {
    "lyapunov_equation": "Decided by the Lyapunov equation J^T P + P J = -I: P > 0 exactly, so J is Hurwitz.",
    "lyapunov_inertia": "Decided by the Lyapunov equation J^T P + P J = -I with P not positive definite (inertia "
                        "theorem): J has an eigenvalue with positive real part.",
}
#: keys of a class shown elsewhere on the page (solver outcomes under Reproducibility)
SHOWN_ELSEWHERE: Final = ("status", "summary", "property", "certificate", "refutation", "solver", "rounds", "history")


# -- reading -------------------------------------------------------------------------------------------
def read_certificate(path: str | Path) -> dict[str, Any]:
    """A certificate file of either kind: the paper's (read exactly as before), or a model certificate.

    Raises
    ------
    InputFileError
        One line: missing, not JSON, not a certificate, or a schema this version does not read.
    """
    from lyapcheck.paper.certificate import read_document
    from lyapcheck.models.certificate import read_json

    try:
        return read_document(path)
    except InputFileError as refused:
        # the paper's reader refuses any other kind; only a model certificate is read instead,
        # and any other file keeps the paper's reader's message
        try:
            doc = read_json(path)
        except InputFileError:
            raise refused from None
        if not isinstance(doc, dict) or not is_model_document(doc):
            raise
    if doc.get("schema_version") != SCHEMA_VERSION:
        raise InputFileError(f"'{path}' has schema_version {doc.get('schema_version')!r}; this lyapcheck reads "
                             f"model certificates of version {SCHEMA_VERSION}")
    return doc


def _str(value: object) -> str:
    return value if isinstance(value, str) else ("—" if value is None else str(value))


def _percent(value: float) -> str:
    return f"{100 * value:.3g} %"


# -- views ---------------------------------------------------------------------------------------------
@dataclass
class Quantity:
    """A parameter, disturbance bound or equilibrium coordinate: as given and in SI (exact)."""

    name: str
    given: str
    si: str
    exact: str
    note: str = ""


@dataclass
class PolynomialView:
    """An exact polynomial: typeset (maybe truncated), as plain text, and what was left out."""

    title: str
    eq: Equation | None
    plain: str
    notes: list[str]
    terms: int
    degree: int


@dataclass
class ClassView:
    name: str
    anchor: str
    title: str
    status: str
    property: str
    property_meaning: str
    summary: str
    figures: list[str]
    items: list[Item] = field(default_factory=list)
    polynomials: list[PolynomialView] = field(default_factory=list)
    exact: list[tuple[str, str, str]] = field(default_factory=list)
    matrices: list[Item] = field(default_factory=list)
    grams: list[str] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)


@dataclass
class Denominator:
    text: str
    how: str


def key_figures(cond: dict[str, Any]) -> list[str]:
    """The figures a reader looks for first, one short phrase each (the table of classes)."""
    out = []
    level = as_number(cond.get("level"))
    if level is not None:
        out.append(f"level c = {fmt_float(level)}")
    radius = as_number(cond.get("ball_radius"))
    if radius is not None:
        out.append(f"holds the ball |x - x_eq| <= {fmt_float(radius, 4)}")
    share = as_number(cond.get("roa_share"))
    if share is not None:
        out.append(f"covers {_percent(share)} of the simulated region of attraction in the domain")
    domain_share = as_number(cond.get("simulated_roa_share_of_domain"))
    if domain_share is not None:
        out.append(f"simulated region of attraction: {_percent(domain_share)} of the domain")
    k, rate = as_number(cond.get("k")), as_number(cond.get("decay_rate_per_s"))
    if k is not None and rate is not None:
        out.append(f"|x(t)| <= {fmt_float(k, 4)} |x0| exp(-{fmt_float(rate, 4)} t)")
    rate_v = as_number(cond.get("decay_rate_V_per_s"))
    if rate_v is not None and rate_v > 0:
        out.append(f"V' <= -{fmt_float(rate_v, 4)} V")
    for output, bound in as_dict(cond.get("bounds")).items():
        b = as_number(bound)
        if b is not None:
            out.append(f"limsup |{output}| <= {fmt_float(b)}")
    degree = cond.get("degree")
    if isinstance(degree, int) and not isinstance(degree, bool) and cond.get("status") == "certified":
        out.append(f"V of degree {degree}")
    supremum = as_number(cond.get("level_supremum_estimate"))
    if supremum is not None:
        out.append(f"sampled supremum of the level {fmt_float(supremum)}")
    real = as_number(cond.get("max_real_part_estimate"))
    if real is not None:
        out.append(f"largest real part of an eigenvalue {fmt_float(real, 4)}")
    return out


def _polynomial(title: str, data: object, lead: str, states: list[str], shifts: list[Fraction],
                eqs: Equations) -> PolynomialView:
    """An exact polynomial of the certificate, ready for the page (never raises on bad data)."""
    try:
        poly = ExactPolynomial.from_json(data, len(states))
    except ValueError as exc:
        return PolynomialView(title, None, "", [f"not shown: {exc}"], 0, 0)
    source, shown = poly.typst(states, shifts, lead)
    plain = poly.plain_text(states, shifts)
    notes = []
    if shown < len(poly.terms):
        notes.append(f"The typeset form shows the first {shown} of its {len(poly.terms)} terms (lowest degree "
                     "first); every term is in the exact text below and in the certificate file.")
    if len(plain) > MAX_PLAIN_CHARS:
        notes.append(f"The exact text has {len(plain)} characters; the first {MAX_PLAIN_CHARS} are shown here, all "
                     "of them are in the certificate file.")
        plain = plain[:MAX_PLAIN_CHARS] + " ..."
    eq = eqs.typst(source, plain[:4000])
    return PolynomialView(title, eq, plain, notes, len(poly.terms), poly.degree)


def _gram_sizes(cert: dict[str, Any], prefix: str = "") -> list[str]:
    out = []
    for key, value in cert.items():
        if isinstance(value, dict) and str(key).startswith("gram") and isinstance(value.get("basis"), list):
            n = len(value["basis"])
            out.append(f"{prefix}{key}: {n} x {n}")
        elif isinstance(value, dict) and key != "V" and not str(key).startswith("gram"):
            out.extend(_gram_sizes(value, f"{prefix}{key}."))
    return out


def shown_summary(name: str, cond: dict[str, Any], outputs: tuple[str, ...], box: Any = None) -> str:
    """The sentence a reader sees: for a decided class, the one its figures give
    (:func:`lyapcheck.models.claims.summary`, as ``verify`` regenerates it), never the file's own
    text; for the others, the file's reason."""
    from lyapcheck.models.claims import summary

    try:
        text = summary(name, cond, outputs, box if isinstance(box, dict) else None)
    except (KeyError, TypeError, ValueError, ArithmeticError):
        return "(no sentence: the figures of this condition are malformed)"
    return text if text is not None else _str(cond.get("summary", ""))


def _class_view(name: str, cond: dict[str, Any], index: int, states: list[str], shifts: list[Fraction],
                eqs: Equations, outputs: tuple[str, ...] = (), box: Any = None) -> ClassView:
    status = _str(cond.get("status", "unknown"))
    prop = _str(cond.get("property") or "")
    view = ClassView(name, f"class-{index}", CLASS_TITLES.get(name, name), status, prop,
                     PROPERTY_MEANING.get(prop, ""), shown_summary(name, cond, outputs, box), key_figures(cond))
    rest = {k: v for k, v in cond.items() if k not in SHOWN_ELSEWHERE}
    for key, value in rest.items():
        view.items.extend(value_items(str(key), value, eqs))
    rounds = cond.get("rounds")
    if isinstance(rounds, list) and rounds:
        shares = [as_number(as_dict(r).get("share")) for r in rounds]
        known = [s for s in shares if s is not None]
        span = ""
        if known and max(known) > known[0]:
            span = (f"; the share of the simulated region of attraction it covers went from {_percent(known[0])} to "
                    f"{_percent(max(known))}")
        elif known:
            span = f"; it covered {_percent(known[0])} of the simulated region of attraction from the first round"
        view.notes.append(f"{len(rounds)} rounds of the search enlarged V{span}.")
    # a refutation carries its exact data as a certificate does; so does the critical case of the
    # linearization (its Jacobian and characteristic polynomial)
    cert = as_dict(cond.get("certificate")) or as_dict(cond.get("refutation"))
    if not cert:
        return view
    if "V" in cert:
        lead = "V(x)" if all(s == 0 for s in shifts) else "V"
        view.polynomials.append(_polynomial("V, exactly", cert["V"], lead, states, shifts, eqs))
    level = as_fraction(cert.get("level"))
    if level is not None:
        view.exact.append(("certified level c", f"≈ {fmt_float(float(level))}", str(level)))
    ball = as_dict(cert.get("ball"))
    radius = as_fraction(ball.get("radius"))
    if radius is not None:
        text, exact = scalar_text(str(radius))
        view.exact.append(("radius r of a ball |x - x_eq| <= r inside {V <= c}", text, exact))
    for key, what in (("c1", "c1 in c1 I < P"), ("c2", "c2 in P < c2 I"), ("k", "k = sqrt(c2 / c1), rounded up"),
                      ("mu_scaled", "mu in V' <= -mu V (scaled time)")):
        value = as_fraction(cert.get(key))
        if value is not None:
            text, exact = scalar_text(str(value))
            view.exact.append((what, text, exact))
    for key in ("jacobian", "P"):
        rows = parse_matrix(cert.get(key))
        if rows is not None:
            label = "J (Jacobian at the equilibrium, exact)" if key == "jacobian" else "P"
            view.matrices.append(matrix_item(label, rows, eqs, cert.get(key)))
    method = cert.get("method")
    if isinstance(method, str):
        view.notes.append(METHODS.get(method, f"method: {method}"))
    charpoly = cert.get("characteristic_polynomial")
    if charpoly is not None:
        view.items.extend(value_items("characteristic polynomial (coefficients, exact)", charpoly, eqs))
    for output, data in as_dict(cert.get("outputs")).items():
        data = as_dict(data)
        lead = typst_symbol(f"V_{output}") + ("(x)" if all(s == 0 for s in shifts) else "")
        view.polynomials.append(_polynomial(f"storage function for the output {output}, exactly", data.get("V"), lead,
                                            states, shifts, eqs))
        bound = as_fraction(data.get("bound"))
        if bound is not None:
            text, exact = scalar_text(str(bound))
            view.exact.append((f"certified limsup |{output}|", text, exact))
        for key, what in (("lam_scaled", f"lambda of {output} in V' <= -lambda (V - 1) (scaled time)"),
                          ("B_scaled", f"B of {output} in y^2 <= V + B - 1 (scaled)")):
            value = as_fraction(data.get(key))
            if value is not None:
                text, exact = scalar_text(str(value))
                view.exact.append((what, text, exact))
        view.grams.extend(_gram_sizes(data, f"{output}: "))
    if "outputs" not in cert:
        view.grams.extend(_gram_sizes(cert))
    return view


def _quantities(exact_si: dict[str, Any], given: dict[str, Any], overrides: dict[str, Any],
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
                rows.append(Quantity(str(name), _str(given.get(name, "—")), f"[{fmt_float(float(lo))}, "
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
        rows.append(Quantity(str(name), _str(raw), si, "" if exact is None or exact.denominator == 1 else str(exact),
                             note))
    return rows


def _denominators(fld: dict[str, Any]) -> list[Denominator]:
    out = []
    for cert in fld.get("denominators") or []:
        cert = as_dict(cert)
        text = _str(cert.get("denominator", "a denominator"))
        sign = cert.get("sign", 1)
        kind = cert.get("kind")
        if kind == "constant":
            how = f"a positive constant ({_str(cert.get('value'))}), exactly"
        elif kind == "sos":
            basis = as_dict(cert.get("gram_sigma")).get("basis")
            size = len(basis) if isinstance(basis, list) else 0
            scales = ", ".join(map(_str, cert.get("scales") or []))
            c, norm = _str(cert.get("c")), _str(cert.get("normalization"))
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


def _scaling(fld: dict[str, Any], states: list[str], disturbances: list[str],
             outputs: list[str]) -> list[tuple[str, str]]:
    scaling = as_dict(fld.get("scaling"))
    rows: list[tuple[str, str]] = []
    for key, names, what in (("states", states, "state"), ("disturbances", disturbances, "disturbance"),
                             ("outputs", outputs, "output")):
        values = scaling.get(key)
        if isinstance(values, list):
            for name, value in zip(names, values):
                rows.append((f"{what} {name}", _str(value)))
    for key, what in (("time", "time: t = T tau, T"), ("denominator", "denominator factor")):
        if key in scaling:
            rows.append((what, _str(scaling[key])))
    return rows


def _solvers(conditions: dict[str, Any]) -> list[tuple[str, str]]:
    """Per class: how many solves, their outcomes and the solver time (the full log is in the file)."""
    out = []
    for name, cond in conditions.items():
        solves = as_dict(as_dict(cond).get("solver")).get("solves")
        if not isinstance(solves, list) or not solves:
            continue
        outcomes: dict[str, int] = {}
        seconds = 0.0
        solvers = set()
        for s in solves:
            s = as_dict(s)
            outcomes[_str(s.get("outcome", s.get("status", "?")))] = outcomes.get(
                _str(s.get("outcome", s.get("status", "?"))), 0) + 1
            seconds += as_number(s.get("solve_seconds")) or 0.0
            solvers.add(_str(s.get("solver", "?")))
        counts = ", ".join(f"{n} {k}" for k, n in sorted(outcomes.items()))
        out.append((str(name), f"{len(solves)} solves with {', '.join(sorted(solvers))} ({counts}), "
                               f"{fmt_float(seconds, 3)} s in the solver"))
    return out


def _decimal(value: Fraction | None) -> str:
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


def _command(doc: dict[str, Any]) -> str:
    model = as_dict(doc.get("model"))
    file = _str(model.get("file") or "model.toml")
    parts = ["lyapcheck", "certify", "--model", shlex.quote(file)]
    for name, value in as_dict(doc.get("overrides")).items():
        parts += ["--set", shlex.quote(f"{name}={value}")]
    if isinstance(doc.get("candidate"), str):
        parts += ["--candidate", shlex.quote(doc["candidate"])]
    for name, bounds in as_dict(doc.get("box")).items():
        if isinstance(bounds, list) and len(bounds) == 2:
            lo, hi = (_decimal(as_fraction(b)) for b in bounds)
            parts += ["--box", shlex.quote(f"{name}={lo}..{hi}")]
    names = [str(n) for n in as_dict(doc.get("conditions"))]
    if names:
        parts += ["--classes", shlex.quote(",".join(names))]
    parts += ["--out", "certificate.json"]
    return (" ".join(parts) + "\nlyapcheck verify certificate.json   # exact re-check, no solver\n"
            "lyapcheck report certificate.json --html report.html --pdf report.pdf")


def _recheck(doc: dict[str, Any]) -> tuple[list[tuple[str, bool, str]], str]:
    """Re-check every claim exactly (no solver); (rows, error if it could not run)."""
    from lyapcheck.models.certificate import verify_document

    try:
        return verify_document(doc), ""
    except LyapcheckError as exc:
        return [], str(exc)


def _figure(doc: dict[str, Any], model: Model | None, simulate: bool) -> tuple[Figure | None, str, list[CrossCheck]]:
    if not simulate:
        return None, "not requested", []
    if model is None:
        return None, "the stored model text does not parse, so nothing can be simulated", []
    try:
        portrait = phase_portrait(doc, model)
    except (LyapcheckError, ValueError, ArithmeticError, FloatingPointError) as exc:
        log.warning("no phase portrait for the report: %s", exc)
        return None, f"the simulation failed: {exc}", []
    return portrait.figure, portrait.reason, portrait.checks


def model_context(doc: dict[str, Any], *, simulate: bool = True, recheck: bool = True) -> dict[str, Any]:
    """Everything the model template shows (strings unescaped; the template escapes).

    Parameters
    ----------
    doc
        A model certificate (``lyapcheck.models.certificate``, kind ``lyapcheck-model-certificate``).
    simulate
        Draw the phase portrait of a 2-state model (simulations, 2 to 5 s).
    recheck
        Re-check the certificate exactly (no solver; under a second for the shipped examples).
    """
    from lyapcheck.models.modelfile import parse_model

    if not is_model_document(doc):
        raise InputFileError(f"not a model certificate (missing kind '{KIND}')")
    eqs = Equations()
    model_part = as_dict(doc.get("model"))
    stored_text = model_part.get("text")
    text = stored_text if isinstance(stored_text, str) else ""
    overrides = {str(k): v for k, v in as_dict(doc.get("overrides")).items()}
    model: Model | None = None
    model_error = ""
    try:
        model = parse_model(text, _str(model_part.get("file", "<certificate>")), overrides)
    except LyapcheckError as exc:
        model_error = str(exc)
    try:
        raw = tomllib.loads(text)
    except tomllib.TOMLDecodeError:
        raw = {}
    states = [str(s) for s in doc.get("states") or []] if isinstance(doc.get("states"), list) else []
    if model is not None and not states:
        states = list(model.states)
    equilibrium = as_dict(doc.get("equilibrium"))
    shifts = [as_fraction(equilibrium.get(s)) or Fraction(0) for s in states]
    conditions = as_dict(doc.get("conditions"))
    outputs = tuple(model.outputs) if model is not None else ()
    try:
        from lyapcheck.models.claims import box_words

        box_text = box_words(as_dict(doc.get("box"))) if as_dict(doc.get("box")) else ""
    except (TypeError, ValueError, ArithmeticError):
        box_text = "a box of parameters (its bounds are malformed)"
    classes = [_class_view(str(name), as_dict(cond), k + 1, states, shifts, eqs, outputs, doc.get("box"))
               for k, (name, cond) in enumerate(conditions.items())]
    figure, figure_reason, checks = _figure(doc, model, simulate)
    eqs.typeset()
    rows, recheck_error = _recheck(doc) if recheck else ([], "not requested")
    digest = hashlib.sha256(text.encode()).hexdigest()
    stated = _str(model_part.get("sha256", ""))
    fld = as_dict(doc.get("field"))
    disturbances = [str(d) for d in as_dict(doc.get("disturbances"))]
    outputs_text = dict(model.output_text) if model is not None else {
        str(k): _str(v) for k, v in as_dict(raw.get("outputs")).items()}
    dynamics = [(s, _str(as_dict(raw.get("dynamics")).get(s, "—"))) for s in states]
    domain = [(str(k), _str(v)) for k, v in as_dict(raw.get("domain")).items()]
    verdict = _str(doc.get("verdict", "unknown"))
    failed_checks = [c for c in checks if not c.ok]
    soundness = ""
    if failed_checks:
        soundness = ("SOUNDNESS: a simulation contradicts a certificate: "
                     + "; ".join(f"{c.what} ({c.detail})" for c in failed_checks) + ".")
    recheck_failed = [r for r in rows if not r[1]]
    return {
        "kind": "model-certificate",
        "title": f"lyapcheck model certificate report: {_str(model_part.get('name', 'model'))}",
        "name": _str(model_part.get("name", "model")),
        "file": _str(model_part.get("file", "")),
        "origin": model.origin if model is not None else _str(as_dict(raw.get("model")).get("source", "")),
        "verdict": verdict,
        "verdict_meaning": VERDICT_MEANING.get(verdict, "no stability certificate passed an exact check"),
        "classes": classes,
        "status_meaning": {**STATUS_MEANING, **EXTRA_STATUS_MEANING},
        "states": states,
        "equilibrium": [(s, _str(equilibrium.get(s, "0"))) for s in states],
        "parameters": _quantities(as_dict(doc.get("parameters")), as_dict(raw.get("parameters")), overrides,
                                  as_dict(doc.get("box"))),
        "box_words": box_text,
        "disturbances": _quantities(as_dict(doc.get("disturbances")), as_dict(raw.get("disturbances")), overrides),
        "outputs": list(outputs_text.items()),
        "domain": domain,
        "dynamics": dynamics,
        "candidate": doc.get("candidate") if isinstance(doc.get("candidate"), str) else "",
        "model_error": model_error,
        "model_text": text,
        "sha256_stated": stated,
        "sha256_text": digest,
        "sha256_matches": digest == stated,
        "denominators": _denominators(fld),
        "scaling": _scaling(fld, states, disturbances, list(outputs_text)),
        "portrait": figure,
        "figure_reason": figure_reason,
        "checks": checks,
        "soundness": soundness,
        "recheck": rows,
        "recheck_error": recheck_error,
        "recheck_failed": recheck_failed,
        "solvers": _solvers(conditions),
        "command": _command(doc),
        "hash_document": hashlib.sha256(canonical_json(doc)).hexdigest(),
        "versions": {**{str(k): _str(v) for k, v in as_dict(doc.get("versions")).items()}, **versions()},
        # every typeset equation, for reports.html to put on shared sheets (one glyph set per sheet)
        "equations": [eq.result for eq in eqs.items if eq.result is not None],
    }


def model_html(doc: dict[str, Any], *, simulate: bool = True, recheck: bool = True) -> str:
    """The model certificate's report as one self-contained HTML page."""
    from reports.html import render_html

    return render_html("model.html.j2", model_context(doc, simulate=simulate, recheck=recheck))
