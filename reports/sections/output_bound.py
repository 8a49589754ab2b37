"""``sos_bound`` of a model file: an ultimate bound on each output under bounded disturbances.

Its certificate holds one storage function ``V_y`` per output, with ``limsup |y - y_eq| <= B``. The
page shows each ``V_y`` exactly, the certified bound, ``lambda`` and ``B`` of its identities and
the Gram sizes; on a 2-state model's phase portrait each ``{V_y <= 1}`` is an attracting set
(every trajectory enters it, for every admissible disturbance), checked against the envelope
``1 + (V(0) - 1) exp(-lam t)`` along every simulated trajectory.
"""

from __future__ import annotations

from fractions import Fraction
from typing import Any, Final

from reports.polynomials import ExactPolynomial
from reports.sections.base import ClassContext, ClassView, LevelSet, PortraitPart
from reports.sections.model_file import ModelFileSection, exact_row, gram_sizes, polynomial_view
from reports.typeset import typst_symbol
from reports.views import as_dict, as_fraction, as_number

#: one colour per output bound on the phase portrait
OUTPUT_COLOURS: Final = ("#8250df", "#bc4c00", "#bf3989", "#116329", "#0550ae", "#953800")


class OutputBoundSection(ModelFileSection):
    titles = {"sos_bound": "Ultimate bound on each output under bounded disturbances"}

    def certificate_parts(self, view: ClassView, cert: dict[str, Any], ctx: ClassContext) -> None:
        if "outputs" not in cert:
            super().certificate_parts(view, cert, ctx)
            return
        states, shifts = ctx.states, ctx.shifts
        for output, data in as_dict(cert.get("outputs")).items():
            data = as_dict(data)
            lead = typst_symbol(f"V_{output}") + ("(x)" if all(s == 0 for s in shifts) else "")
            view.polynomials.append(polynomial_view(f"storage function for the output {output}, exactly",
                                                    data.get("V"), lead, states, shifts, ctx.eqs))
            bound = as_fraction(data.get("bound"))
            if bound is not None:  # a bound on the deviation from the output's value at the equilibrium
                from lyapcheck.models.classes.claims import deviation

                sos_bound = as_dict(as_dict(ctx.doc.get("conditions")).get("sos_bound"))
                y_eq = as_number(as_dict(sos_bound.get("bounds_reference")).get(output))
                unit = as_dict(sos_bound.get("bounds_unit")).get(output)
                unit = unit if isinstance(unit, str) else None
                view.exact.append(exact_row(f"certified limsup |{deviation(str(output), y_eq, unit)}|"
                                            + (f", in {unit}" if unit else ""), bound))
            for key, what in (("lam_scaled", f"lambda of {output} in V' <= -lambda (V - 1) (scaled time)"),
                              ("B_scaled", f"B of {output} in y^2 <= V + B - 1 (scaled)")):
                value = as_fraction(data.get(key))
                if value is not None:
                    view.exact.append(exact_row(what, value))
            view.grams.extend(gram_sizes(data, f"{output}: "))

    def portrait(self, name: str, cond: dict[str, Any], n: int, time_scale: Fraction) -> PortraitPart:
        sets = []
        for k, (output, data) in enumerate(as_dict(as_dict(cond.get("certificate")).get("outputs")).items()):
            data = as_dict(data)
            lam = as_fraction(data.get("lam_scaled"))
            poly = ExactPolynomial.from_json(data.get("V"), n)
            bound = as_number(as_dict(cond.get("bounds")).get(output))
            sets.append(LevelSet(name, f"{name} ({output}): {{V ≤ 1}}", poly, Fraction(1), "attracting",
                                 OUTPUT_COLOURS[k % len(OUTPUT_COLOURS)],
                                 rate=float(lam / time_scale) if lam is not None and lam > 0 else 0.0,
                                 output=str(output), bound=bound))
        return PortraitPart(sets=tuple(sets))


__all__ = ["OutputBoundSection", "OUTPUT_COLOURS"]
