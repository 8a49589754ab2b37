"""The classes of a model file (``lyapcheck certify --model FILE``): the view every one of them shares.

:class:`ModelFileSection` shows any class of a model certificate from the keys its condition
holds: status, property, the summary regenerated from its figures (as ``verify`` does), the key
figures, the exact ``V`` (typeset, and as plain text in the model-file language), level, ball,
the constants of an exponential estimate, the Jacobian and ``P`` of a linearization, the Gram
matrices' sizes, and every other stored figure. It is the registry's fallback for a class of a
model file that no section names; the families (:mod:`reports.sections.stability`,
:mod:`reports.sections.output_bound`) add their titles, figures and portrait sets to it.

The same class, made for the model :data:`~reports.sections.base.RECAST_LOOP` (``ModelFileSection(RECAST_LOOP,
RECAST_TITLES)``), shows every class of a **loop with functions** (a model file whose ``[dynamics]`` use sin,
sqrt, sat, ...). Such a loop is certified on its *recasting* (:mod:`lyapcheck.models.language.recast`): each
function an auxiliary variable with its definition, its flow and the relations it satisfies. The
linearization and every class without a V of its own are shown as above; a certified condition's
certificate is of one of two kinds, each with its own set:

================  =====================================  ==============================================
kind              V is a polynomial in                   the certified set (``roa``, ``candidate``)
================  =====================================  ==============================================
``"recast"``      the states and the auxiliaries, in     ``{x : V(x, a(x)) <= level}``, each auxiliary
                  deviations ``v - shift[v]``            replaced by its definition; modulo 2 pi in the
                                                         ``angles`` (V sees them only through sin, cos)
``"interval"``    the states only (same variables, the   ``{x : x - x_eq in box, V(x) <= level}``, proved
                  auxiliaries' exponents 0)              by ball arithmetic on the true field
================  =====================================  ==============================================

Such a certificate is shown from its own keys (:meth:`ModelFileSection.recast_view`): the sentence it
supports (:func:`lyapcheck.models.classes.claims.sentence_of`, as ``verify`` re-makes it, never
the file's text), ``V`` typeset in the recasting's variables and ``V_text`` (V written with the
functions), the level, the box, the exact proof's sizes. For the phase portrait of a 2-state loop it
names each certified set (:meth:`ModelFileSection.portrait_set`, drawn by :mod:`reports.phase_portrait`).
"""

from __future__ import annotations

from dataclasses import dataclass
from fractions import Fraction
from typing import Any, Final

from lyapcheck.models.classes.claims import RATE_UNIT, deviation, rounded, size_words, with_unit
from reports.polynomials import MAX_PLAIN_CHARS, ExactPolynomial
from reports.sections.base import (MODEL_FILE, RECAST_LOOP, SET_COLOURS, ClassContext, ClassView, PolynomialView,
                                   Section, text_of)
from reports.typeset import Equations, parse_matrix
from reports.views import Item, as_dict, as_fraction, as_number, fmt_float, matrix_item, scalar_text, value_items

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
    "sampled_routh": "Decided on the Jacobian over one period of the sampled-data loop, exp(A T) + Gamma(T) B K: "
                     "its Cayley transform's characteristic polynomial, Routh's array in ball arithmetic (its "
                     "first column's sign changes count the eigenvalues outside the unit circle).",
}
#: keys of a class shown elsewhere on the page (solver outcomes under Reproducibility)
SHOWN_ELSEWHERE: Final = ("status", "summary", "property", "certificate", "refutation", "solver", "rounds", "history")
#: the certificate kinds of a loop with functions (lyapcheck.models.surfaces.verify, recast_interval)
RECAST_KINDS: Final = ("recast", "interval")
#: keys of a recast or interval certificate's condition shown elsewhere on the page (rounds of a search,
#: which its class does not keep today, would be shown among its stored figures)
RECAST_SHOWN_ELSEWHERE: Final = tuple(k for k in SHOWN_ELSEWHERE if k not in ("rounds", "history"))
#: the titles of a loop with functions' classes (the section of the model RECAST_LOOP)
RECAST_TITLES: Final = {
    "linearization": "Linearization at the equilibrium",
    "quadratic": "Global quadratic Lyapunov function on the recasting",
    "sos_gas": "Global Lyapunov function on the recasting (sum of squares)",
    "roa": "Region of attraction of the true loop",
    "candidate": "Your candidate V",
    "sos_bound": "Ultimate bound on each output under bounded disturbances (on the recasting)",
}


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
    size = size_words(cond)
    if size:
        out.append(size)
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
        elif isinstance(value, list) and str(key).startswith("gram") and value and \
                all(isinstance(v, dict) and isinstance(v.get("basis"), list) for v in value):
            largest = max(len(v["basis"]) for v in value)  # one Gram matrix per clique (kind lyapunov_cliques)
            per = "subsystem" if cert.get("kind") in ("lyapunov_vector", "lyapunov_cascade") else "clique"
            out.append(f"{prefix}{key}: {len(value)} matrices, one per {per}, the largest {largest} x {largest}")
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


def exact_rows(values: dict[str, Any], named: tuple[tuple[str, str], ...]) -> list[tuple[str, str, str]]:
    """:func:`exact_row` for each ``(key, what)`` of ``named`` whose value in ``values`` is a rational."""
    rows = []
    for key, what in named:
        value = as_fraction(values.get(key))
        if value is not None:
            rows.append(exact_row(what, value))
    return rows


def size_rows(cert: dict[str, Any]) -> list[tuple[str, str, str]]:
    """A certified region's size, exactly (:mod:`lyapcheck.models.classes.region_size`): the largest
    ball's radius, the bound ``mu`` behind it, and the reach along each state's axis."""
    size = as_dict(cert.get("size"))
    rows = exact_rows(size, (("ball_radius", "size: radius r of a ball |x - x_eq| <= r inside the set"),
                             ("ball_mu", "size: mu >= the largest eigenvalue of V's quadratic part (mu I - P >= 0)")))
    for state, value in as_dict(size.get("axis_extents")).items():
        exact = as_fraction(value)
        if exact is not None:
            rows.append(exact_row(f"size: reach along {state} (|t| <= a with x_eq + t e_{state} in the set)", exact))
    return rows


def level_rows(cert: dict[str, Any]) -> list[tuple[str, str, str]]:
    """The certified level of a certificate, approximately and exactly (none when it has none)."""
    level = as_fraction(cert.get("level"))
    return [] if level is None else [("certified level c", f"≈ {fmt_float(float(level))}", str(level))]


class ModelFileSection(Section):
    """Any class of a model file, shown from the keys its condition and certificate hold; made for
    :data:`~reports.sections.base.RECAST_LOOP`, any class of a loop with functions (its recast and
    interval certificates from their own keys, :meth:`recast_view`)."""

    model = MODEL_FILE
    titles: dict[str, str] = {}

    def __init__(self, model: str | None = None, titles: dict[str, str] | None = None) -> None:
        if model is not None:
            self.model = model
        if titles is not None:
            self.titles = titles

    def head(self, name: str, cond: dict[str, Any], index: int, summary: str, figures: list[str]) -> ClassView:
        """The view's title, status, summary, property and key figures."""
        prop = text_of(cond.get("property") or "")
        return ClassView(name, f"class-{index}", self.titles.get(name, name), text_of(cond.get("status", "unknown")),
                         summary, property=prop, property_meaning=PROPERTY_MEANING.get(prop, ""), figures=figures,
                         items_title="Every figure of the class, as stored")

    def view(self, name: str, cond: Any, index: int, ctx: ClassContext) -> ClassView:
        cond = as_dict(cond)
        functions = self.model == RECAST_LOOP
        kind = as_dict(cond.get("certificate")).get("kind")
        if functions and cond.get("status") == "certified" and kind in RECAST_KINDS:
            return self.recast_view(name, cond, index, ctx)
        summary = shown_summary(name, cond, ctx.outputs, ctx.box)
        if functions and cond.get("status") in ("certified", "refuted") and isinstance(ctx.box, dict) and ctx.box:
            # over a box a loop with functions says where its claim holds (verify's own prefix)
            summary = box_words_of(ctx.box, str(cond["status"])) + shown_summary(name, cond, ctx.outputs)
        view = self.head(name, cond, index, summary, recast_figures(cond) if functions else key_figures(cond))
        view.items.extend(stored_items(cond, SHOWN_ELSEWHERE, ctx))
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
        if cert:
            self.exact_parts(view, cert, ctx)
        point = as_dict(as_dict(cond.get("refutation")).get("point"))
        if functions and point:
            view.notes.append("The refutation: another equilibrium of the true loop at "
                              + ", ".join(f"{k} = {text_of(v)}" for k, v in point.items())
                              + " (re-checked exactly by 'lyapcheck verify').")
        return view

    def exact_parts(self, view: ClassView, cert: dict[str, Any], ctx: ClassContext) -> None:
        """A certificate's (or a refutation's) exact data: V, level, ball, constants, J and P, the family's parts."""
        eqs, states, shifts = ctx.eqs, ctx.states, ctx.shifts
        if "V" in cert:
            lead = "V(x)" if all(s == 0 for s in shifts) else "V"
            view.polynomials.append(polynomial_view("V, exactly", cert["V"], lead, states, shifts, eqs))
        view.exact.extend(level_rows(cert))
        view.exact.extend(exact_rows(as_dict(cert.get("ball")), (
            ("radius", "radius r of a ball |x - x_eq| <= r inside {V <= c}"),)))
        view.exact.extend(size_rows(cert))
        view.exact.extend(exact_rows(cert, (
            ("c1", "c1 in c1 I < P"), ("c2", "c2 in P < c2 I"), ("k", "k = sqrt(c2 / c1), rounded up"),
            ("mu_scaled", "mu in V' <= -mu V (scaled time)"))))
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

    def certificate_parts(self, view: ClassView, cert: dict[str, Any], ctx: ClassContext) -> None:
        """What the family adds from its certificate after the common parts (default: the Gram sizes)."""
        view.grams.extend(gram_sizes(cert))

    def recast_view(self, name: str, cond: dict[str, Any], index: int, ctx: ClassContext) -> ClassView:
        """A certified recast or interval certificate of a loop with functions, from its own keys."""
        cert = as_dict(cond.get("certificate"))
        kind = str(cert["kind"])
        angles = angles_of(cert)
        said = recast_sentence(cert, cond.get("disturbances"))
        if isinstance(ctx.box, dict) and ctx.box:
            said = box_words_of(ctx.box, "certified") + said
        view = self.head(name, cond, index, said, recast_figures(cond))
        view.items.extend(stored_items(cond, RECAST_SHOWN_ELSEWHERE, ctx))
        if angles:
            view.figures.append(modulo_words(angles))
        box = box_of(cert)
        if box:
            view.figures.append("within the box " + ", ".join(
                f"{s} - eq in [{fmt_float(float(lo), 4)}, {fmt_float(float(hi), 4)}]" for s, (lo, hi) in box.items()))
        view.polynomials.append(v_view(cert, ctx))
        view.exact.extend(level_rows(cert))
        for state, (lo, hi) in (box or {}).items():
            view.exact.append((f"box: {state} - {state}_eq in", f"[{fmt_float(float(lo))}, {fmt_float(float(hi))}]",
                               f"[{lo}, {hi}]"))
        view.exact.extend(size_rows(cert))
        view.exact.extend(exact_rows(cert, (
            ("epsilon", "epsilon in V' <= -epsilon |dx|^2 / D"),
            ("positivity_epsilon", "epsilon in V >= epsilon |dx|^2"),
            ("local_radius", "half-width of the equilibrium's box (the Hessian argument)"))))
        view.notes.extend(recast_set_notes(kind, as_fraction(cert.get("level")), box, angles))
        if kind == "interval":
            cells, boundary = cert.get("cells"), cert.get("boundary_cells")
            method = text_of(cert.get("method", "ball arithmetic"))
            view.notes.append(f"Proved by {method}: {text_of(cells)} cells of the box ({text_of(boundary)} on its "
                              "boundary); 'lyapcheck verify' runs the same proof again from the certificate.")
        else:
            sizes = proof_sizes(cert)
            if sizes:
                view.notes.append("The exact proof behind it (each identity holds exactly on the recasting's relations "
                                  "and every Gram matrix is positive semidefinite; re-checked by 'lyapcheck verify', "
                                  "no solver): " + "; ".join(sizes) + ".")
        return view

    def portrait_set(self, name: str, cond: dict[str, Any]) -> RecastSet | None:
        """The set a certified recast or interval certificate puts on the phase portrait of a loop with
        functions, or None (another kind of certificate; no level: a global claim)."""
        cert = as_dict(cond.get("certificate"))
        kind = cert.get("kind")
        level = as_fraction(cert.get("level"))
        if cond.get("status") != "certified" or kind not in RECAST_KINDS or level is None or "V" not in cert:
            return None
        box = box_of(cert) if kind == "interval" else None
        if kind == "interval" and box is None:
            raise ValueError("its box is missing or malformed")
        angles = angles_of(cert) if kind == "recast" else ()
        return RecastSet(name, str(kind), f"{name}: {set_words(str(kind), level, angles)}", cert["V"], level, box,
                         angles, SET_COLOURS.get(name, "#1a7f37"))


def stored_items(cond: dict[str, Any], shown_elsewhere: tuple[str, ...], ctx: ClassContext) -> list[Item]:
    """Every figure of a condition not shown elsewhere on the page, as stored."""
    items: list[Item] = []
    for key, value in cond.items():
        if key not in shown_elsewhere:
            items.extend(value_items(str(key), value, ctx.eqs))
    return items


# -- loops with functions: their certificates' sentences, sets and V ----------------------------------
@dataclass(frozen=True)
class RecastSet:
    """A certified set of a loop with functions, for its phase portrait.

    ``V`` is the certificate's exact polynomial (JSON terms over the recasting's variables, in
    deviations); the set is ``{V <= level}`` with the auxiliaries at their definitions, and within
    ``box`` (deviations from the equilibrium, per state) when there is one (an ``"interval"``
    certificate). ``angles`` are the states the claim takes modulo 2 pi.
    """

    name: str
    kind: str
    label: str
    V: Any
    level: Fraction
    box: dict[str, tuple[Fraction, Fraction]] | None
    angles: tuple[str, ...]
    colour: str


def recast_figures(cond: dict[str, Any]) -> list[str]:
    """The key figures of a loop with functions' class, the share of the simulated region of attraction
    said of the box the recast ``roa`` class simulates in (the ``[domain]``, else a default box)."""
    return [f.replace("simulated region of attraction in the domain",
                      "simulated region of attraction in the [domain] (without one: ±π in an angle, ±4 elsewhere)")
            for f in key_figures(cond)]


def recast_sentence(cert: dict[str, Any], coverage: Any = None) -> str:
    """The claim a recast or interval certificate supports, made from the certificate alone (with
    ``(d = 0)`` in front where the condition says its disturbances were held at 0)."""
    from lyapcheck.models.classes.claims import covered
    from lyapcheck.models.classes.claims import sentence_of

    try:
        return covered(coverage if coverage in ("zero", "all") else None, sentence_of(cert))
    except (KeyError, TypeError, ValueError, ArithmeticError, ZeroDivisionError):
        return "(no sentence: the figures of this certificate are malformed)"


def box_words_of(box: dict[str, Any], status: str) -> str:
    """What a claim of a loop with functions over a box of parameters says first
    (:func:`lyapcheck.models.classes.claims.box_prefix`), or nothing when the box is malformed."""
    from lyapcheck.models.language.parameter_box import ModelBox
    from lyapcheck.models.classes.claims import box_prefix

    try:
        return box_prefix(ModelBox.from_json(box), status)
    except (KeyError, TypeError, ValueError, ArithmeticError, ZeroDivisionError):
        return "(over a malformed box) "


def box_of(cert: dict[str, Any]) -> dict[str, tuple[Fraction, Fraction]] | None:
    """An interval certificate's box (deviations, exact), or None when it has none or it is malformed."""
    box = cert.get("box")
    if not isinstance(box, dict) or not box:
        return None
    out = {}
    for state, bounds in box.items():
        if not isinstance(bounds, list) or len(bounds) != 2:
            return None
        lo, hi = (as_fraction(b) for b in bounds)
        if lo is None or hi is None or not lo < hi:
            return None
        out[str(state)] = (lo, hi)
    return out


def angles_of(cert: dict[str, Any]) -> tuple[str, ...]:
    angles = cert.get("angles")
    return tuple(str(a) for a in angles) if isinstance(angles, list) else ()


def modulo_words(angles: tuple[str, ...]) -> str:
    return f"modulo 2 pi in {', '.join(angles)}" if angles else ""


def set_words(kind: str, level: Fraction, angles: tuple[str, ...]) -> str:
    """What the certified set is, in a few words (the portrait's legend)."""
    if kind == "interval":
        return f"{{V(x) ≤ {fmt_float(float(level))}}} ∩ box"
    modulo = f", modulo 2π in {', '.join(angles)}" if angles else ""
    return f"{{V(x, a(x)) ≤ {fmt_float(float(level))}}}{modulo}"


def recast_set_notes(kind: str, level: Fraction | None, box: dict[str, tuple[Fraction, Fraction]] | None,
                     angles: tuple[str, ...]) -> list[str]:
    """What a recast or interval certificate's set is, in the words of the class's notes."""
    if level is None:
        if kind == "recast":
            return ["A global V: no set to draw, the claim is about every start"
                    + (f" ({modulo_words(angles)})." if angles else ".")]
        return []
    if kind == "interval":
        return ["The certified set is {x : x - x_eq in the box above, V(x) <= c}. V uses the states only (the "
                "auxiliaries' exponents are 0), so the set is drawn from V and the box alone."]
    note = ("The certified set is {x : V(x, a(x)) <= c}: each auxiliary of V replaced by its definition (the "
            "recasting's table above the classes).")
    if angles:
        note += (f" V sees {', '.join(angles)} only through sine and cosine, so the set repeats every 2 pi in "
                 f"{', '.join(angles)}, and the claim is {modulo_words(angles)}: a trajectory may end at the "
                 "equilibrium shifted by a multiple of 2 pi.")
    return [note]


def proof_sizes(cert: dict[str, Any]) -> list[str]:
    """One phrase per sum-of-squares identity of a recast certificate: its Gram matrices' sizes
    and multipliers (the matrices themselves are in the certificate file)."""
    out = []
    named = [("positivity", cert.get("positivity")), ("decrease", cert.get("decrease"))]
    recasting = as_dict(cert.get("recasting"))
    for root, item in as_dict(recasting.get("roots")).items():
        named.append((f"lower bound of the root {root}", as_dict(item).get("proof")))
    for k, item in enumerate(recasting.get("denominators") or []):
        named.append((f"positivity of denominator {k + 1}", as_dict(item).get("proof")))
    for what, proof in named:
        proof = as_dict(proof)
        if not proof:
            continue
        parts = []
        for key, word in (("sigma", "sum of squares"), ("rho", "multiplier of (V - level)")):
            basis = as_dict(proof.get(key)).get("basis")
            if isinstance(basis, list):
                parts.append(f"{word} with a {len(basis)} x {len(basis)} Gram matrix")
        lambdas, taus = as_dict(proof.get("lambdas")), as_dict(proof.get("taus"))
        if lambdas:
            parts.append(f"{len(lambdas)} multiplier(s) of the equality relations")
        if taus:
            parts.append(f"{len(taus)} sum-of-squares multiplier(s) of the inequality relations")
        out.append(f"{what}: " + ", ".join(parts))
    return out


def v_view(cert: dict[str, Any], ctx: ClassContext) -> PolynomialView:
    """V typeset in the recasting's variables (each in its deviation), and as ``V_text``: V written
    with the functions, in the model-file language."""
    variables = cert.get("variables")
    names = [str(v) for v in variables] if isinstance(variables, list) else list(ctx.states)
    shift = as_dict(cert.get("shift"))
    shifts = [as_fraction(shift.get(n)) or Fraction(0) for n in names]
    view = polynomial_view("V, exactly (in the states and the auxiliaries)", cert.get("V"), "V", names, shifts,
                           ctx.eqs)
    text = cert.get("V_text")
    if isinstance(text, str):
        plain = text if len(text) <= MAX_PLAIN_CHARS else text[:MAX_PLAIN_CHARS] + " ..."
        view.plain = plain
        view.notes = [n for n in view.notes if "exact text" not in n]
        if len(text) > MAX_PLAIN_CHARS:
            view.notes.append(f"V written with the functions has {len(text)} characters; the first {MAX_PLAIN_CHARS} "
                              "are shown here, all of them are in the certificate file (V_text).")
    auxiliaries = [n for n in names if n not in ctx.states]
    if auxiliaries:
        try:
            poly = ExactPolynomial.from_json(cert.get("V"), len(names))
            used = sorted({names[i] for _, m in poly.terms for i, e in enumerate(m) if e and names[i] in auxiliaries})
        except ValueError:
            used = []
        if used:
            view.notes.insert(0, "The typeset V uses the auxiliaries " + ", ".join(used) + " (their definitions are in "
                              "the recasting's table); below, V_text writes them as the functions they stand for.")
        else:
            view.notes.insert(0, "V uses the states only: no auxiliary appears in it.")
    return view


__all__ = ["ModelFileSection", "PROPERTY_MEANING", "METHODS", "key_figures", "polynomial_view", "gram_sizes",
           "shown_summary", "exact_row", "exact_rows", "level_rows", "size_rows", "percent", "RECAST_KINDS", "RECAST_TITLES",
           "RecastSet", "recast_sentence", "box_of", "set_words", "proof_sizes", "v_view"]
