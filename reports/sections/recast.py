"""The classes of a loop with functions (a model file whose ``[dynamics]`` use sin, sqrt, sat, ...).

Such a loop is certified on its *recasting* (:mod:`lyapcheck.models.language.recast`): each function is
an auxiliary variable with its definition, its flow and the relations it satisfies. A certified
condition's certificate is of one of two kinds, each with its own set:

================  =====================================  ==============================================
kind              V is a polynomial in                   the certified set (``roa``, ``candidate``)
================  =====================================  ==============================================
``"recast"``      the states and the auxiliaries, in     ``{x : V(x, a(x)) <= level}``, each auxiliary
                  deviations ``v - shift[v]``            replaced by its definition; modulo 2 pi in the
                                                         ``angles`` (V sees them only through sin, cos)
``"interval"``    the states only (same variables, the   ``{x : x - x_eq in box, V(x) <= level}``, proved
                  auxiliaries' exponents 0)              by ball arithmetic on the true field
================  =====================================  ==============================================

:class:`RecastSection` shows the linearization and every uncertified class as any model file's
(:class:`~reports.sections.model_file.ModelFileSection`), and a recast or interval certificate
from its own keys: the sentence it supports (:func:`lyapcheck.models.surfaces.recast_certify.sentence_of`,
as ``verify`` re-makes it, never the file's text), ``V`` typeset in the recasting's variables and
``V_text`` (V written with the functions), the level, the box, the exact proof's sizes. For the
phase portrait of a 2-state loop it names each certified set (:meth:`RecastSection.portrait_set`,
drawn by :mod:`reports.recast_portrait`).
"""

from __future__ import annotations

from dataclasses import dataclass
from fractions import Fraction
from typing import Any, Final

from reports.polynomials import MAX_PLAIN_CHARS, ExactPolynomial
from reports.sections.base import ClassContext, ClassView, PolynomialView, text_of
from reports.sections.model_file import (PROPERTY_MEANING, ModelFileSection, exact_row, key_figures, polynomial_view,
                                       shown_summary)
from reports.sections.stability import SET_COLOURS
from reports.views import as_dict, as_fraction, fmt_float, value_items

#: the model of these sections' documents (a model certificate with a ``"recast"`` table)
RECAST_LOOP: Final = "recast-loop"
#: the certificate kinds this section reads (lyapcheck.models.surfaces.recast_certify, recast_interval)
KINDS: Final = ("recast", "interval")
#: keys of a condition shown elsewhere on the page (the solver's outcomes under Reproducibility)
SHOWN_ELSEWHERE: Final = ("status", "summary", "property", "certificate", "refutation", "solver")


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


def figures(cond: dict[str, Any]) -> list[str]:
    """The key figures of a model file's class, the share of the simulated region of attraction
    said of the box the recast ``roa`` class simulates in (the ``[domain]``, else a default box)."""
    return [f.replace("simulated region of attraction in the domain",
                      "simulated region of attraction in the [domain] (without one: ±π in an angle, ±4 elsewhere)")
            for f in key_figures(cond)]


def sentence(cert: dict[str, Any], coverage: Any = None) -> str:
    """The claim a recast or interval certificate supports, made from the certificate alone (with
    ``(d = 0)`` in front where the condition says its disturbances were held at 0)."""
    from lyapcheck.models.classes.claims import covered
    from lyapcheck.models.surfaces.recast_certify import sentence_of

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


class RecastSection(ModelFileSection):
    """Every class of a loop with functions (the registry's only section, and fallback, for its model)."""

    model = RECAST_LOOP
    titles = {
        "linearization": "Linearization at the equilibrium",
        "quadratic": "Global quadratic Lyapunov function on the recasting",
        "sos_gas": "Global Lyapunov function on the recasting (sum of squares)",
        "roa": "Region of attraction of the true loop",
        "candidate": "Your candidate V",
        "sos_bound": "Ultimate bound on each output under bounded disturbances (on the recasting)",
    }

    def view(self, name: str, cond: Any, index: int, ctx: ClassContext) -> ClassView:
        cond = as_dict(cond)
        cert = as_dict(cond.get("certificate"))
        if cond.get("status") != "certified" or cert.get("kind") not in KINDS:
            view = super().view(name, cond, index, ctx)  # the linearization, and the classes without a V
            if cond.get("status") in ("certified", "refuted") and isinstance(ctx.box, dict) and ctx.box:
                # over a box a loop with functions says where its claim holds (verify's own prefix)
                view.summary = box_words_of(ctx.box, str(cond["status"])) + shown_summary(name, cond, ctx.outputs)
            view.figures = figures(cond)
            point = as_dict(as_dict(cond.get("refutation")).get("point"))
            if point:
                view.notes.append("The refutation: another equilibrium of the true loop at "
                                  + ", ".join(f"{k} = {text_of(v)}" for k, v in point.items())
                                  + " (re-checked exactly by 'lyapcheck verify').")
            return view
        kind = str(cert["kind"])
        prop = text_of(cond.get("property") or "")
        angles = angles_of(cert)
        said = sentence(cert, cond.get("disturbances"))
        if isinstance(ctx.box, dict) and ctx.box:
            said = box_words_of(ctx.box, "certified") + said
        view = ClassView(name, f"class-{index}", self.titles.get(name, name), "certified", said,
                         property=prop, property_meaning=PROPERTY_MEANING.get(prop, ""), figures=figures(cond),
                         items_title="Every figure of the class, as stored")
        if angles:
            view.figures.append(modulo_words(angles))
        box = box_of(cert)
        if box:
            view.figures.append("within the box " + ", ".join(
                f"{s} - eq in [{fmt_float(float(lo), 4)}, {fmt_float(float(hi), 4)}]" for s, (lo, hi) in box.items()))
        view.polynomials.append(v_view(cert, ctx))
        level = as_fraction(cert.get("level"))
        if level is not None:
            view.exact.append(("certified level c", f"≈ {fmt_float(float(level))}", str(level)))
        for state, (lo, hi) in (box or {}).items():
            view.exact.append((f"box: {state} - {state}_eq in", f"[{fmt_float(float(lo))}, {fmt_float(float(hi))}]",
                               f"[{lo}, {hi}]"))
        for key, what in (("epsilon", "epsilon in V' <= -epsilon |dx|^2 / D"),
                          ("positivity_epsilon", "epsilon in V >= epsilon |dx|^2"),
                          ("local_radius", "half-width of the equilibrium's box (the Hessian argument)")):
            value = as_fraction(cert.get(key))
            if value is not None:
                view.exact.append(exact_row(what, value))
        ges = as_dict(cert.get("ges"))
        for key, what in (("c1", "c1 in c1 |z|^2 <= V"), ("c2", "c2 in V <= c2 |z|^2"),
                          ("k", "k in |x(t) - x_eq| <= k |x0 - x_eq| exp(-rate t)"), ("rate", "rate (per unit time)")):
            value = as_fraction(ges.get(key))
            if value is not None:
                view.exact.append(exact_row(what, value))
        view.notes.extend(self.set_notes(kind, level, box, angles))
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
        for key, value in cond.items():
            if key not in SHOWN_ELSEWHERE:
                view.items.extend(value_items(str(key), value, ctx.eqs))
        return view

    @staticmethod
    def set_notes(kind: str, level: Fraction | None, box: dict[str, tuple[Fraction, Fraction]] | None,
                  angles: tuple[str, ...]) -> list[str]:
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

    def portrait_set(self, name: str, cond: dict[str, Any]) -> RecastSet | None:
        """The set a certified condition puts on the phase portrait, or None (no level: a global claim)."""
        cert = as_dict(cond.get("certificate"))
        kind = cert.get("kind")
        level = as_fraction(cert.get("level"))
        if cond.get("status") != "certified" or kind not in KINDS or level is None or "V" not in cert:
            return None
        box = box_of(cert) if kind == "interval" else None
        if kind == "interval" and box is None:
            raise ValueError("its box is missing or malformed")
        angles = angles_of(cert) if kind == "recast" else ()
        return RecastSet(name, str(kind), f"{name}: {set_words(str(kind), level, angles)}", cert["V"], level, box,
                         angles, SET_COLOURS.get(name, "#1a7f37"))


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


__all__ = ["RECAST_LOOP", "RecastSection", "RecastSet", "sentence", "box_of", "set_words", "proof_sizes", "v_view"]
