"""``barrier`` of a model file: no trajectory from the initial set ever enters the unsafe set.

Its certificate holds the barrier ``B`` (declared, shifted states, exactly), the rate ``lambda`` of
``B' <= lambda B`` and, per piece of the initial and the unsafe set, the S-procedure multipliers.
The page shows ``B`` exactly, ``lambda``, the sets as the model states them and the Gram sizes. The
phase portrait does not draw ``{B <= 0}`` yet: it checks a drawn region by the convergence of the
trajectories in it, which a barrier does not claim.
"""

from __future__ import annotations

from fractions import Fraction
from typing import Any, Final

from reports.sections.base import ClassContext, ClassView, PortraitPart
from reports.sections.model_file import PROPERTY_MEANING, ModelFileSection, exact_row, gram_sizes, polynomial_view
from reports.views import as_dict, as_fraction

#: the safety property, in the words of the page's property column
SAFETY_MEANING: Final = ("no trajectory that starts in the initial set ever enters the unsafe set, for every "
                         "disturbance within its bounds")


class SafetySection(ModelFileSection):
    titles = {"barrier": "Barrier certificate: the unsafe set is never reached",
              "reach_avoid": "Reach-avoid certificate: the goal is reached, the unsafe set avoided"}

    def view(self, name: str, cond: Any, index: int, ctx: ClassContext) -> ClassView:
        view = super().view(name, cond, index, ctx)
        if not view.property_meaning:
            view.property_meaning = PROPERTY_MEANING.get(view.property, SAFETY_MEANING)
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
        sets = as_dict(as_dict(ctx.doc.get("model")).get("sets"))
        for key in ("initial", "unsafe", "goal"):
            if key in sets:
                view.notes.append(f"{key} set, as the model states it: {sets[key]}")
        view.grams.extend(gram_sizes(cert))

    def portrait(self, name: str, cond: dict[str, Any], n: int, time_scale: Fraction) -> PortraitPart:
        # the phase portrait checks a "region" by convergence of the trajectories that start in it,
        # which a barrier does not claim ({B <= 0} is only never left): no set until the portrait
        # has a kind for an invariant set with its own check
        return PortraitPart()


__all__ = ["SafetySection", "SAFETY_MEANING"]
