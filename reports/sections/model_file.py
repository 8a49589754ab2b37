"""The classes of a model file (``lyapcheck certify --model FILE``): the view every one of them shares.

:class:`ModelFileSection` shows any class of a model certificate from the keys its condition
holds: status, property, the summary regenerated from its figures (as ``verify`` does), the key
figures, the exact ``V`` (typeset, and as plain text in the model-file language), level, ball,
the constants of an exponential estimate, the Jacobian and ``P`` of a linearization, the Gram
matrices' sizes, and every other stored figure. It is the registry's fallback for a class of a
model file that no section names; the families (:mod:`reports.sections.stability`,
:mod:`reports.sections.output_bound`) add their titles, figures and portrait sets to it.
"""

from __future__ import annotations

from fractions import Fraction
from typing import Any, Final

from lyapcheck.models.classes.claims import RATE_UNIT, deviation, rounded, with_unit
from reports.polynomials import MAX_PLAIN_CHARS, ExactPolynomial
from reports.sections.base import MODEL_FILE, ClassContext, ClassView, PolynomialView, Section, text_of
from reports.typeset import Equations, parse_matrix
from reports.views import as_dict, as_fraction, as_number, fmt_float, matrix_item, scalar_text, value_items

#: one sentence per property a class can prove (DESIGN.md)
PROPERTY_MEANING: Final = {
    "LES": "local exponential stability of the equilibrium",
    "GES": "global exponential stability: |x(t) - x_eq| <= k |x0 - x_eq| exp(-rate t) from every start",
    "GAS": "global asymptotic stability: every start converges to the equilibrium",
    "ROA": "every start in the stated set converges to the equilibrium",
    "ultimate_bound": "limsup |y - y_eq| <= B for each output (y_eq: its value at the equilibrium), from every start, "
                      "for every disturbance within its bounds",
    "invariant_set": "a set that no trajectory leaves",
    "ISS": "input-to-state stability",
    "safety": "no trajectory that starts in the initial set ever enters the unsafe set",
    "reach_avoid": "every trajectory that starts in the initial set reaches the goal, and does not enter the "
                   "unsafe set before",
}
#: how the linearization decided (its certificate's "method")
METHODS: Final = {
    "lyapunov_equation": "Decided by the Lyapunov equation J^T P + P J = -I: P > 0 exactly, so J is Hurwitz.",
    "lyapunov_inertia": "Decided by the Lyapunov equation J^T P + P J = -I with P not positive definite (inertia "
                        "theorem): J has an eigenvalue with positive real part.",
}
#: keys of a class shown elsewhere on the page (solver outcomes under Reproducibility)
SHOWN_ELSEWHERE: Final = ("status", "summary", "property", "certificate", "refutation", "solver", "rounds", "history")


def percent(value: float) -> str:
    return f"{100 * value:.3g} %"


def key_figures(cond: dict[str, Any]) -> list[str]:
    """The figures a reader looks for first, one short phrase each (the table of classes)."""
    out = []
    level = as_number(cond.get("level"))
    if level is not None:
        out.append(f"level c = {rounded(level, 6, 'down')}")
    radius = as_number(cond.get("ball_radius"))
    if radius is not None:
        unit = cond.get("ball_radius_unit")
        out.append(f"holds the ball |x - x_eq| <= {with_unit(radius, unit if isinstance(unit, str) else None, direction='down')}")
    share = as_number(cond.get("roa_share"))
    if share is not None:
        out.append(f"covers {percent(share)} of the simulated region of attraction in the domain")
    domain_share = as_number(cond.get("simulated_roa_share_of_domain"))
    if domain_share is not None:
        out.append(f"simulated region of attraction: {percent(domain_share)} of the domain")
    k, rate = as_number(cond.get("k")), as_number(cond.get("decay_rate_per_s"))
    if k is not None and rate is not None:
        out.append(f"|x(t) - x_eq| <= {rounded(k, 4, 'up')} |x0 - x_eq| exp(-r t), r = "
                   f"{with_unit(rate, RATE_UNIT, direction='down')}")
    rate_v = as_number(cond.get("decay_rate_V_per_s"))
    if rate_v is not None and rate_v > 0:
        out.append(f"V' <= -r V, r = {with_unit(rate_v, RATE_UNIT, direction='down')}")
    references, units = as_dict(cond.get("bounds_reference")), as_dict(cond.get("bounds_unit"))
    for output, bound in as_dict(cond.get("bounds")).items():
        b = as_number(bound)
        if b is not None:  # a bound on the deviation from the output's value at the equilibrium
            unit = units.get(output) if isinstance(units.get(output), str) else None
            out.append(f"limsup |{deviation(output, as_number(references.get(output)), unit)}| <= "
                       f"{with_unit(b, unit, 6, 'up')}")
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


def polynomial_view(title: str, data: object, lead: str, states: list[str], shifts: list[Fraction],
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


def gram_sizes(cert: dict[str, Any], prefix: str = "") -> list[str]:
    """``name: n x n`` for every Gram matrix of a certificate (nested ones prefixed with their path)."""
    out = []
    for key, value in cert.items():
        if isinstance(value, dict) and str(key).startswith("gram") and isinstance(value.get("basis"), list):
            n = len(value["basis"])
            out.append(f"{prefix}{key}: {n} x {n}")
        elif isinstance(value, dict) and key != "V" and not str(key).startswith("gram"):
            out.extend(gram_sizes(value, f"{prefix}{key}."))
    return out


def shown_summary(name: str, cond: dict[str, Any], outputs: tuple[str, ...], box: Any = None) -> str:
    """The sentence a reader sees: for a decided class, the one its figures give
    (:func:`lyapcheck.models.classes.claims.summary`, as ``verify`` regenerates it), never the file's own
    text; for the others, the file's reason."""
    from lyapcheck.models.classes.claims import summary

    try:
        text = summary(name, cond, outputs, box if isinstance(box, dict) else None)
    except (KeyError, TypeError, ValueError, ArithmeticError):
        return "(no sentence: the figures of this condition are malformed)"
    return text if text is not None else text_of(cond.get("summary", ""))


def exact_row(what: str, value: Fraction) -> tuple[str, str, str]:
    text, exact = scalar_text(str(value))
    return what, text, exact


class ModelFileSection(Section):
    """Any class of a model file, shown from the keys its condition and certificate hold."""

    model = MODEL_FILE
    titles: dict[str, str] = {}

    def view(self, name: str, cond: Any, index: int, ctx: ClassContext) -> ClassView:
        cond = as_dict(cond)
        eqs, states, shifts = ctx.eqs, ctx.states, ctx.shifts
        status = text_of(cond.get("status", "unknown"))
        prop = text_of(cond.get("property") or "")
        view = ClassView(name, f"class-{index}", self.titles.get(name, name), status,
                         shown_summary(name, cond, ctx.outputs, ctx.box), property=prop,
                         property_meaning=PROPERTY_MEANING.get(prop, ""), figures=key_figures(cond),
                         items_title="Every figure of the class, as stored")
        rest = {k: v for k, v in cond.items() if k not in SHOWN_ELSEWHERE}
        for key, value in rest.items():
            view.items.extend(value_items(str(key), value, eqs))
        rounds = cond.get("rounds")
        if isinstance(rounds, list) and rounds:
            shares = [as_number(as_dict(r).get("share")) for r in rounds]
            known = [s for s in shares if s is not None]
            span = ""
            if known and max(known) > known[0]:
                span = (f"; the share of the simulated region of attraction it covers went from {percent(known[0])} "
                        f"to {percent(max(known))}")
            elif known:
                span = f"; it covered {percent(known[0])} of the simulated region of attraction from the first round"
            view.notes.append(f"{len(rounds)} rounds of the search enlarged V{span}.")
        # a refutation carries its exact data as a certificate does; so does the critical case of the
        # linearization (its Jacobian and characteristic polynomial)
        cert = as_dict(cond.get("certificate")) or as_dict(cond.get("refutation"))
        if not cert:
            return view
        if "V" in cert:
            lead = "V(x)" if all(s == 0 for s in shifts) else "V"
            view.polynomials.append(polynomial_view("V, exactly", cert["V"], lead, states, shifts, eqs))
        level = as_fraction(cert.get("level"))
        if level is not None:
            view.exact.append(("certified level c", f"≈ {fmt_float(float(level))}", str(level)))
        radius = as_fraction(as_dict(cert.get("ball")).get("radius"))
        if radius is not None:
            view.exact.append(exact_row("radius r of a ball |x - x_eq| <= r inside {V <= c}", radius))
        for key, what in (("c1", "c1 in c1 I < P"), ("c2", "c2 in P < c2 I"), ("k", "k = sqrt(c2 / c1), rounded up"),
                          ("mu_scaled", "mu in V' <= -mu V (scaled time)")):
            value = as_fraction(cert.get(key))
            if value is not None:
                view.exact.append(exact_row(what, value))
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
        self.certificate_parts(view, cert, ctx)
        return view

    def certificate_parts(self, view: ClassView, cert: dict[str, Any], ctx: ClassContext) -> None:
        """What the family adds from its certificate after the common parts (default: the Gram sizes)."""
        view.grams.extend(gram_sizes(cert))


__all__ = ["ModelFileSection", "PROPERTY_MEANING", "METHODS", "key_figures", "polynomial_view", "gram_sizes",
           "shown_summary", "exact_row", "percent"]
