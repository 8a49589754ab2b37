"""``barrier`` and ``reach_avoid`` of a model file: the safety classes.

``barrier``: no trajectory from the initial set ever enters the unsafe set. Its certificate holds
the barrier ``B`` (declared, shifted states, exactly), the rate ``lambda`` of ``B' <= lambda B``
and, per piece of the initial and the unsafe set, the S-procedure multipliers.
``reach_avoid``: every trajectory from the initial set reaches the goal, not entering the unsafe
set before; its certificate holds ``V`` (``V <= 0`` on the initial set, ``V >= 1`` on the unsafe
set), ``eps`` and ``C``.

The page shows the polynomial exactly, the constants, a table of the sets the class is about as
the model states them (each piece's inequalities), a table of the falsification run beside the
search (closest approach to the unsafe set, starts, trajectories, horizon, whether one entered)
and the Gram sizes. On a 2-state model's phase portrait each certified class draws its invariant
set (kind ``"invariant"``): ``{B <= 0}``, which no trajectory leaves, and ``{V <= 0}``, which no
trajectory leaves before it reaches the goal; the portrait checks both along the simulated
trajectories, and that none from the initial set enters the unsafe set.
"""

from __future__ import annotations

from fractions import Fraction
from typing import Any, Final

from reports.polynomials import ExactPolynomial
from reports.sections.base import ClassContext, ClassView, LevelSet, PortraitPart, TableView
from reports.sections.model_file import PROPERTY_MEANING, ModelFileSection, exact_row, gram_sizes, polynomial_view
from reports.views import as_dict, as_fraction, as_number, fmt_float

#: the safety property, in the words of the page's property column
SAFETY_MEANING: Final = ("no trajectory that starts in the initial set ever enters the unsafe set, for every "
                         "disturbance within its bounds")
#: the sets each class is about (lyapcheck.models.language.sets.CLASS_SETS), in the page's order
CLASS_SETS: Final = {"barrier": ("initial", "unsafe"), "reach_avoid": ("initial", "unsafe", "goal")}
#: each class's invariant set on the phase portrait: (function, certificate key, colour, until)
INVARIANT: Final = {"barrier": ("B", "B", "#6e40c9", ""), "reach_avoid": ("V", "V", "#6e40c9", "goal")}
#: keys of the condition shown in the falsification table (not again under "every figure")
FALSIFICATION_KEYS: Final = ("falsification", "closest_approach")


def _point(value: object) -> str:
    if isinstance(value, list) and value and all(as_number(v) is not None for v in value):
        return "(" + ", ".join(fmt_float(float(as_number(v) or 0.0), 4) for v in value) + ")"
    return "—"


def sets_table(name: str, set_text: dict[str, tuple[tuple[str, ...], ...]]) -> TableView | None:
    """The sets ``name`` is about, as the model states them: one row per piece (a set is the union
    of its pieces, a piece the intersection of its inequalities)."""
    rows: list[tuple[str, ...]] = []
    for key in CLASS_SETS.get(name, ()):
        pieces = set_text.get(key, ())
        for i, piece in enumerate(pieces, start=1):
            rows.append((key if i == 1 else "", f"{i} of {len(pieces)}", "  and  ".join(piece)))
    if not rows:
        return None
    return TableView("The sets, as the model states them", ("set", "piece", "inequalities (all hold)"), rows,
                     "A set is the union of its pieces; a piece is every inequality of its row at once "
                     "(< and > are read as <= and >=: each set is closed).")


def falsification_table(cond: dict[str, Any]) -> TableView | None:
    """The falsification beside the search (lyapcheck.models.classes.falsify): what was simulated and how
    near the unsafe set it came."""
    trial = as_dict(cond.get("falsification"))
    closest = as_number(cond.get("closest_approach"))
    if closest is None:
        closest = as_number(trial.get("closest_approach"))
    if not trial and closest is None:
        return None
    rows: list[tuple[str, ...]] = []
    samples, runs, horizon = (as_number(trial.get(k)) for k in ("samples", "trajectories", "horizon"))
    if samples is not None:
        rows.append(("starts sampled in the initial set", f"{samples:.0f}"))
    if runs is not None:
        scenarios = as_number(trial.get("disturbance_scenarios"))
        per = (f" ({samples:.0f} starts x {scenarios:.0f} disturbance scenarios)"
               if samples is not None and scenarios is not None and scenarios > 1 else "")
        rows.append(("trajectories simulated", f"{runs:.0f}{per}"))
    if horizon is not None:
        rows.append(("horizon", f"{fmt_float(horizon, 4)} s"))
    if closest is not None:
        meaning = ("no trajectory entered; the nearest came this far outside, in the units of the set's "
                   "polynomials" if closest < 0 else "a trajectory reached the unsafe set")
        rows.append(("closest approach (largest unsafe margin reached)", f"{fmt_float(closest, 4)}: {meaning}"))
    near = as_dict(trial.get("closest"))
    if near.get("point") is not None:
        when = as_number(near.get("time"))
        rows.append(("where the nearest came", f"{_point(near.get('point'))}"
                              + (f" at t = {fmt_float(when, 4)} s" if when is not None else "")
                              + f", from {_point(near.get('start'))}"))
    if isinstance(trial.get("entered"), bool):
        entry = as_dict(trial.get("entry"))
        text = "no" if not trial["entered"] else "YES"
        if trial["entered"] and entry:
            when = as_number(entry.get("time"))
            text += (f": first from {_point(entry.get('start'))}"
                     + (f" at t = {fmt_float(when, 4)} s" if when is not None else ""))
        rows.append(("a trajectory entered the unsafe set", text))
    for key, what in (("escaped", "trajectories that ran away"), ("failed", "trajectories the integrator could not "
                                                                            "finish")):
        value = as_number(trial.get(key))
        if value:
            rows.append((what, f"{value:.0f}"))
    if cond.get("soundness_violation") is True:
        rows.append(("SOUNDNESS VIOLATION", "a simulated trajectory contradicts the certified claim"))
    return TableView("Falsification beside the search (simulated, never a proof)", ("what", "value"), rows,
                     "Trajectories from starts sampled over the initial set (with disturbances: each vertex of "
                     "their box held, and switched at random); the claim itself rests on the exact check above.")


#: a class's title when it found a counterexample (its usual title says what it would have proved)
COUNTEREXAMPLE_TITLES: Final = {
    "barrier": "Barrier certificate: none, and the unsafe set IS reached (counterexample)",
    "reach_avoid": "Reach-avoid certificate: none, and a trajectory defeats it (counterexample)",
}
#: the note under a counterexample: where the page shows it
COUNTEREXAMPLE_NOTE: Final = ("The counterexample (a simulated trajectory, reproducible from its start and "
                              "disturbance) is drawn in the phase portrait, or against time for a model of other than "
                              "2 states: simulated again from its stored start, up to where it enters the unsafe set.")


class SafetySection(ModelFileSection):
    titles = {"barrier": "Barrier certificate: the unsafe set is never reached",
              "reach_avoid": "Reach-avoid certificate: the goal is reached, the unsafe set avoided"}

    def view(self, name: str, cond: Any, index: int, ctx: ClassContext) -> ClassView:
        view = super().view(name, cond, index, ctx)
        if not view.property_meaning:
            view.property_meaning = PROPERTY_MEANING.get(view.property, SAFETY_MEANING)
        cond = as_dict(cond)
        if cond.get("status") == "counterexample":
            view.title = COUNTEREXAMPLE_TITLES.get(name, view.title)
            view.notes.insert(0, COUNTEREXAMPLE_NOTE)
        table = sets_table(name, ctx.set_text)
        if table is not None:
            view.tables.append(table)
        trial = falsification_table(cond)
        if trial is not None:
            view.tables.append(trial)
            view.items = [item for item in view.items if item.key not in FALSIFICATION_KEYS]
        return view

    def certificate_parts(self, view: ClassView, cert: dict[str, Any], ctx: ClassContext) -> None:
        if "B" in cert:
            lead = "B(x)" if all(s == 0 for s in ctx.shifts) else "B"
            view.polynomials.append(polynomial_view("the barrier B, exactly (B <= 0 on the initial set, B >= 1 on "
                                                    "the unsafe set)", cert["B"], lead, ctx.states, ctx.shifts,
                                                    ctx.eqs))
        for key, what in (("eps_scaled", "eps in V' <= -eps outside the goal (scaled time)"),
                          ("C_scaled", "C in V >= delta |z|^2 - C (scaled)")):
            value = as_fraction(cert.get(key))
            if value is not None:
                view.exact.append(exact_row(what, value))
        lam = as_fraction(cert.get("lambda_scaled"))
        if lam is not None:
            view.exact.append(exact_row("lambda in B' <= lambda B (scaled time)", lam))
        view.grams.extend(gram_sizes(cert))

    def portrait(self, name: str, cond: dict[str, Any], n: int, time_scale: Fraction) -> PortraitPart:
        if name not in INVARIANT:
            return PortraitPart()
        symbol, key, colour, until = INVARIANT[name]
        cert = as_dict(cond.get("certificate"))
        if key not in cert:
            return PortraitPart()
        poly = ExactPolynomial.from_json(cert[key], n)
        return PortraitPart(sets=(LevelSet(name, f"{name}: {{{symbol} ≤ 0}}", poly, Fraction(0), "invariant",
                                           colour, until=until, symbol=symbol),))


__all__ = ["SafetySection", "SAFETY_MEANING", "COUNTEREXAMPLE_TITLES", "COUNTEREXAMPLE_NOTE", "CLASS_SETS", "INVARIANT",
           "sets_table", "falsification_table"]
