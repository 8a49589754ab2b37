"""The stability classes of a model file: linearization, quadratic, sos_gas, roa, candidate.

Their page view is the model file's common one (:class:`reports.sections.model_file.ModelFileSection`:
exact ``V``, level, ball, Jacobian and ``P``, Gram sizes); on a 2-state model's phase portrait
each certified ``roa`` and ``candidate`` draws its set ``{V <= c}`` (a region of attraction,
checked along every trajectory that starts in it), and each global ``V`` (``quadratic``,
``sos_gas``, a ``candidate`` without a level) is checked to decay along every trajectory.
"""

from __future__ import annotations

from fractions import Fraction
from typing import Any

from reports.polynomials import ExactPolynomial
from reports.sections.base import SET_COLOURS, GlobalV, LevelSet, PortraitPart
from reports.sections.model_file import ModelFileSection
from reports.views import as_dict, as_fraction, as_number, fmt_float


class StabilitySection(ModelFileSection):
    titles = {
        "linearization": "Linearization at the equilibrium",
        "quadratic": "Global quadratic Lyapunov function",
        "sos_gas": "Global polynomial Lyapunov function (sum of squares)",
        "roa": "Region of attraction: a certified sublevel set",
        "candidate": "Your candidate V",
    }

    def portrait(self, name: str, cond: dict[str, Any], n: int, time_scale: Fraction) -> PortraitPart:
        cert = as_dict(cond.get("certificate"))
        if name in ("roa", "candidate") and "level" in cert and "V" in cert:
            level = as_fraction(cert["level"])
            if level is None:
                raise ValueError("its level is not a rational")
            poly = ExactPolynomial.from_json(cert["V"], n)
            return PortraitPart(sets=(LevelSet(name, f"{name}: {{V ≤ {fmt_float(float(level))}}}", poly, level,
                                               "region", SET_COLOURS.get(name, "#1a7f37")),))
        if name in ("quadratic", "sos_gas", "candidate") and "V" in cert:
            rate = as_number(cond.get("decay_rate_V_per_s")) or 0.0
            return PortraitPart(globals=(GlobalV(name, ExactPolynomial.from_json(cert["V"], n), max(rate, 0.0)),))
        return PortraitPart()


__all__ = ["StabilitySection", "SET_COLOURS"]
