"""The paper's condition classes (the ILOS/ODS loop of ``lyapcheck certify paper.toml``).

Proposition 4.1 (``prop41_ges``, ``prop41_iss``: the certificate ``P`` with
``Gamma = -(A^T P + P A)`` derived on the spot), ``stabcond2``, ``sector_ges``, the ultimate
bounds (``ultimate_bound``, beside the paper's ball radius; ``sos_bound``), and the classes of a
box certificate (``ges``, ``sos_gas``, ``saturated_loop``, ...), which show their status,
summary, numbers and every rational matrix. The summary is the one
:func:`lyapcheck.paper.claims.summary` regenerates from the condition's data (as ``verify``
does), never the file's own text. A certified bound of a certificate made with
``--worst-case`` is shown against the worst simulated disturbance.
"""

from __future__ import annotations

import json
from fractions import Fraction
from typing import Any, Final

from reports.sections.base import PAPER, ClassContext, ClassView, Section
from reports.typeset import Equation, Equations, parse_matrix, typst_float
from reports.views import Item, as_dict, dict_items, fmt_float, matrix_item

#: condition classes that certify ``limsup |eps| <= eps_bound_m`` (the certified sets of the phase portrait)
BOUND_CLASSES: Final = ("ultimate_bound", "sos_bound")
#: numbers ``lyapcheck certify --worst-case`` puts on those classes, shown in their own table
TIGHTNESS_KEYS: Final = ("worst_case_sup_abs_eps_tail_m", "tightness_ratio", "soundness_violation")
#: said before the text of a decided class this version does not know (``verify`` fails it)
UNKNOWN_CLASS: Final = "(not checked: lyapcheck knows no such class) "


def text(value: object) -> str:
    """A document value as page text: strings as they are, anything else as JSON."""
    return value if isinstance(value, str) else json.dumps(value, default=str)


def number(value: object) -> float | None:
    """A JSON number as a float (not a bool), or None."""
    return float(value) if isinstance(value, (int, float)) and not isinstance(value, bool) else None


def describe_disturbance(desc: dict[str, Any]) -> str:
    """A short reading of a stored disturbance description (lyapcheck.paper.simulation.disturbances)."""
    kind = text(desc.get("kind", "unknown"))
    hz = number(desc.get("frequency_hz"))
    words = {"square_wave": "square wave of amplitude d* across the path",
             "sinusoid": "sinusoid across the path", "bang_bang": "bang-bang of amplitude d* across the path",
             "constant": "constant", "feedback": "state feedback of amplitude d* across the path",
             "none": "no disturbance"}.get(kind, kind.replace("_", " "))
    if hz is not None:
        words += f" at {hz:.3g} Hz"
    times = desc.get("switch_times_s")
    if kind == "bang_bang" and isinstance(times, list):
        words += f", {len(times)} switches"
    family = desc.get("family")
    return words + (f" (search family: {text(family)})" if family is not None else "")


def shown_summary(name: str, cond: dict[str, Any], doc: dict[str, Any]) -> str:
    """The sentence a reader sees: for a decided class, the one its data give
    (:func:`lyapcheck.paper.claims.summary`, as ``verify`` regenerates it), never the file's own
    text; for the others, the file's reason. A class this version does not know is shown as
    written, said to be unchecked."""
    from lyapcheck.paper import claims

    box = doc.get("box")
    if cond.get("status") in claims.DECIDED and not claims.known(name, isinstance(box, dict)):
        return UNKNOWN_CLASS + text(cond.get("summary", ""))
    try:
        sentence = claims.summary(name, cond, as_dict(as_dict(doc.get("inputs")).get("exact_si")),
                                  box if isinstance(box, dict) else None)
    except claims.MALFORMED:
        return "(no sentence: the data of this condition are malformed)"
    return sentence if sentence is not None else text(cond.get("summary", ""))


def gamma(doc: dict[str, Any], cond: dict[str, Any], eqs: Equations) -> list[Item]:
    """Gamma = -(A^T P + P A) of a Proposition 4.1 certificate, exactly (eq:stabCond)."""
    from lyapcheck import exact

    A = parse_matrix(as_dict(doc.get("system")).get("A"))
    P = parse_matrix(as_dict(cond.get("certificate")).get("P"))
    if A is None or P is None or len(A) != len(P):
        return []
    g = exact.scale(Fraction(-1), exact.lyapunov_form(exact.matrix(A), exact.matrix(P)))
    rows = [list(r) for r in g]
    return [matrix_item("Gamma = -(A^T P + P A)", rows, eqs, exact.to_json(g))]


def ultimate_comparison(cond: dict[str, Any], eqs: Equations) -> list[tuple[str, Equation | None, str]]:
    """The certified bound beside the paper's ball radius (ledger prop:los)."""
    out: list[tuple[str, Equation | None, str]] = []
    bound = cond.get("eps_bound_m")
    if isinstance(bound, (int, float)):
        eq = eqs.typst(f'limsup_(t -> infinity) abs(epsilon(t)) <= {typst_float(float(bound), 4)} "m"',
                       f"limsup |eps(t)| <= {fmt_float(float(bound))} m")
        out.append(("certified by lyapcheck (exact check)", eq, text(cond.get("eps_bound_exact", ""))))
    paper = eqs.typst('r = (d^* lambda_max (P))/(lambda_min (P))', "r = d* lambda_max(P) / lambda_min(P)")
    radius = cond.get("paper_ball_radius_as_printed")
    note = text(cond.get("paper_ball_note", ""))
    value = f"= {fmt_float(float(radius))} (in the unit of d*)" if isinstance(radius, (int, float)) else "not applicable"
    out.append((f"the paper's ball radius (Proposition 4.1): {value}", paper, note))
    return out


def tightness(cond: dict[str, Any]) -> tuple[list[tuple[str, str]], str]:
    """Rows comparing a certified bound with the worst simulated disturbance (``certify --worst-case``)."""
    bound = number(cond.get("eps_bound_m"))
    worst = number(cond.get("worst_case_sup_abs_eps_tail_m"))
    if bound is None or cond.get("status") != "certified":
        return [], ""
    if worst is None:
        return [], ("No worst-case search in this certificate: `lyapcheck certify --worst-case` adds the worst "
                    "disturbance found in simulation and the ratio certified / simulated.")
    ratio = number(cond.get("tightness_ratio"))
    if ratio is None and worst > 0:
        ratio = bound / worst
    desc = cond.get("worst_case_disturbance")
    how = describe_disturbance(desc) if isinstance(desc, dict) else "not stored"
    if ratio is None:
        verdict = "—"
    elif ratio < 1:
        verdict = f"{ratio:.4g}: BELOW 1, the simulation exceeds the certified bound"
    else:
        verdict = f"{ratio:.4g} (>= 1: the bound holds for every disturbance tried; 1 would be tight)"
    rows = [("certified limsup |eps|", f"{bound * 1e3:.4g} mm"),
            ("worst simulated tail sup |eps| (|d| <= d*, full saturated loop)", f"{worst * 1e3:.4g} mm"),
            ("worst disturbance found", how),
            ("tightness ratio = certified / worst simulated", verdict)]
    return rows, ""


class PaperSection(Section):
    """Every condition class of the paper's model (and the fallback for one this version does not know)."""

    model = PAPER
    titles = {
        "prop41_ges": "Proposition 4.1: global exponential stability (eq:stabCond)",
        "prop41_iss": "Proposition 4.1: input-to-state stability (eq:stabCond with the disturbance term)",
        "stabcond2": "The simpler sufficient condition eq:stabCond2",
        "sector_ges": "Common quadratic Lyapunov function over the sector of rho (GES)",
        "ultimate_bound": "Certified ultimate bound on the cross-track error",
        "sos_bound": "Certified ultimate bound on the cross-track error from a polynomial storage function (SOS)",
    }

    def view(self, name: str, cond: Any, index: int, ctx: ClassContext) -> ClassView:
        title, anchor = self.titles.get(name, name), f"cond-{index}"
        if not isinstance(cond, dict):
            return ClassView(name, anchor, title, "unknown", text(cond))
        status = text(cond.get("status", "unknown"))
        # solver metadata is listed once, under Reproducibility; the comparison block shows these
        shown_elsewhere = {"status", "summary", "solver"}
        if name == "ultimate_bound":
            shown_elsewhere |= {"paper_ball_note", "paper_ball_radius_as_printed"}
        rows, note = tightness(cond) if name in BOUND_CLASSES else ([], "")
        if rows:
            shown_elsewhere |= set(TIGHTNESS_KEYS)
        rest = {k: v for k, v in cond.items() if k not in shown_elsewhere}
        view = ClassView(name, anchor, title, status, shown_summary(name, cond, ctx.doc),
                         items=dict_items(rest, ctx.eqs), tightness=rows, tightness_note=note)
        if name.startswith("prop41") and status == "certified":
            view.extra = gamma(ctx.doc, cond, ctx.eqs)
        if name == "ultimate_bound":
            view.comparison = ultimate_comparison(cond, ctx.eqs)
        return view


__all__ = ["PaperSection", "BOUND_CLASSES", "TIGHTNESS_KEYS", "UNKNOWN_CLASS", "describe_disturbance",
           "shown_summary"]
