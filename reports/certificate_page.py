"""The certificate report's content: inputs, conditions, ultimate bound, figures, ledger, provenance.

:func:`certificate_context` turns a certificate document (``lyapcheck.certificate`` schema)
into the data the template shows. Every string in it is plain text: the template escapes it.
"""

from __future__ import annotations

import hashlib
import json
import logging
from dataclasses import dataclass, field
from fractions import Fraction
from typing import Any

import numpy as np

from lyapcheck.errors import LyapcheckError
from reports import figures
from reports.typeset import Equation, Equations, parse_fraction, parse_matrix, typst_float, versions
from reports.views import Item, dict_items, fmt_float, matrix_item

log = logging.getLogger(__name__)

#: what a reader should call each known condition class (unknown ones keep their key)
CONDITION_TITLES = {
    "prop41_ges": "Proposition 4.1: global exponential stability (eq:stabCond)",
    "prop41_iss": "Proposition 4.1: input-to-state stability (eq:stabCond with the disturbance term)",
    "stabcond2": "The simpler sufficient condition eq:stabCond2",
    "sector_ges": "Common quadratic Lyapunov function over the sector of rho (GES)",
    "ultimate_bound": "Certified ultimate bound on the cross-track error",
}
#: one sentence per status (DESIGN.md)
STATUS_MEANING = {
    "certified": "a certificate exists and passed its exact check",
    "refuted": "proved exactly that no certificate of this class exists for these numbers",
    "not_certified": "none was found, and nothing is proved either way",
    "inconclusive": "numerical trouble: the solver's word alone, or an exact check that failed",
    "holds": "the arithmetic condition holds",
    "fails": "the arithmetic condition fails",
    "discrepancy": "the printed and the derived forms differ",
    "unverifiable": "neither equality nor difference could be established",
}
#: command-line flags of ``lyapcheck certify`` (for the reproducibility block)
FLAGS = {"gains.alpha_d": "--alpha-d", "gains.sigma0": "--sigma0", "gains.k_d": "--kd",
         "gains.delta_los": "--delta-los", "swimmer.e11": "--e11", "actuation.omega_so": "--omega-so",
         "disturbance.d_max": "--d-max"}


@dataclass
class ConditionView:
    name: str
    title: str
    status: str
    summary: str
    items: list[Item]
    extra: list[Item] = field(default_factory=list)
    comparison: list[tuple[str, Equation | None, str]] = field(default_factory=list)


@dataclass
class InputRow:
    key: str
    help: str
    given: str
    si: str
    exact: str


@dataclass
class LedgerCard:
    label: str
    anchor: str
    title: str
    status: str
    explanation: str
    printed: Equation | None
    derived: Equation | None
    printed_text: str
    derived_text: str
    same: bool


def _dict(value: object) -> dict[str, Any]:
    """``value`` if it is a mapping, else an empty one: a malformed section shows as empty."""
    return value if isinstance(value, dict) else {}


def canonical_json(value: object) -> bytes:
    """Sorted, compact JSON (keys made strings first: an input may mix key types)."""
    plain = json.loads(json.dumps(value, default=str))
    return json.dumps(plain, sort_keys=True, separators=(",", ":")).encode()


def _str(value: object) -> str:
    return value if isinstance(value, str) else json.dumps(value, default=str)


def _inputs(doc: dict[str, Any]) -> list[InputRow]:
    from lyapcheck.params import FIELD_BY_KEY, validate_field

    inputs = _dict(doc.get("inputs"))
    given, exact_si = _dict(inputs.get("given")), _dict(inputs.get("exact_si"))
    rows = []
    for key, raw in given.items():
        key = str(key)
        spec = FIELD_BY_KEY.get(key)
        short = key.split(".")[-1]
        exact = exact_si.get(short)
        value: Fraction | None = parse_fraction(exact) if exact is not None else None
        if value is None and spec is not None:
            try:
                value = validate_field(spec, raw)
            except (ValueError, TypeError):
                value = None
        unit = spec.kind.si_unit if spec is not None else ""
        si = "—" if value is None else f"{fmt_float(float(value))} {unit}".strip()
        rows.append(InputRow(key, spec.help if spec is not None else "", _str(raw), si,
                             "" if value is None or value.denominator == 1 else str(value)))
    return rows


def _system(doc: dict[str, Any], eqs: Equations) -> list[Item]:
    system = _dict(doc.get("system"))
    items = []
    for name in ("A", "B"):
        rows = parse_matrix(system.get(name))
        if rows is not None:
            items.append(matrix_item(name, rows, eqs, system.get(name)))
    vec = system.get("E")
    if isinstance(vec, list):
        rows = parse_matrix([[x] for x in vec])
        if rows is not None:
            items.append(matrix_item("E", rows, eqs, vec))
    rest = {k: v for k, v in system.items() if k not in ("A", "B", "E")}
    return items + dict_items(rest, eqs)


def _gamma(doc: dict[str, Any], cond: dict[str, Any], eqs: Equations) -> list[Item]:
    """Gamma = -(A^T P + P A) of a Proposition 4.1 certificate, exactly (eq:stabCond)."""
    from lyapcheck import exact

    A = parse_matrix(_dict(doc.get("system")).get("A"))
    P = parse_matrix(_dict(cond.get("certificate")).get("P"))
    if A is None or P is None or len(A) != len(P):
        return []
    gamma = exact.scale(Fraction(-1), exact.lyapunov_form(exact.matrix(A), exact.matrix(P)))
    rows = [list(r) for r in gamma]
    return [matrix_item("Gamma = -(A^T P + P A)", rows, eqs, exact.to_json(gamma))]


def _ultimate_comparison(cond: dict[str, Any], eqs: Equations) -> list[tuple[str, Equation | None, str]]:
    """The certified bound beside the paper's ball radius (ledger prop:los)."""
    out: list[tuple[str, Equation | None, str]] = []
    bound = cond.get("eps_bound_m")
    if isinstance(bound, (int, float)):
        eq = eqs.typst(f'limsup_(t -> infinity) abs(epsilon(t)) <= {typst_float(float(bound), 4)} "m"',
                       f"limsup |eps(t)| <= {fmt_float(float(bound))} m")
        out.append(("certified by lyapcheck (exact check)", eq, _str(cond.get("eps_bound_exact", ""))))
    paper = eqs.typst('r = (d^* lambda_max (P))/(lambda_min (P))', "r = d* lambda_max(P) / lambda_min(P)")
    radius = cond.get("paper_ball_radius_as_printed")
    note = _str(cond.get("paper_ball_note", ""))
    value = f"= {fmt_float(float(radius))} (in the unit of d*)" if isinstance(radius, (int, float)) else "not applicable"
    out.append((f"the paper's ball radius (Proposition 4.1): {value}", paper, note))
    return out


def _conditions(doc: dict[str, Any], eqs: Equations) -> list[ConditionView]:
    conditions = _dict(doc.get("conditions"))
    views = []
    for name, cond in conditions.items():
        name = str(name)
        if not isinstance(cond, dict):
            views.append(ConditionView(name, CONDITION_TITLES.get(name, name), "unknown", _str(cond), []))
            continue
        status = _str(cond.get("status", "unknown"))
        # solver metadata is listed once, under Reproducibility; the comparison block shows these
        shown_elsewhere = {"status", "summary", "solver"}
        if name == "ultimate_bound":
            shown_elsewhere |= {"paper_ball_note", "paper_ball_radius_as_printed"}
        rest = {k: v for k, v in cond.items() if k not in shown_elsewhere}
        view = ConditionView(name, CONDITION_TITLES.get(name, name), status, _str(cond.get("summary", "")),
                             dict_items(rest, eqs))
        if name.startswith("prop41") and status == "certified":
            view.extra = _gamma(doc, cond, eqs)
        if name == "ultimate_bound":
            view.comparison = _ultimate_comparison(cond, eqs)
        views.append(view)
    return views


def _ledger(eqs: Equations) -> tuple[list[LedgerCard], str]:
    """The claims ledger with typeset printed/derived forms; (cards, reason if unavailable)."""
    import re

    try:
        from lyapcheck.ledger_view import all_claims
        from symbolic.ledger import build_ledger

        claims = all_claims()
        entries = build_ledger(claims)  # type: ignore[arg-type]
    except Exception as exc:  # noqa: BLE001 - the report still shows the certificate
        log.warning("claims ledger unavailable", exc_info=True)
        return [], f"the claims ledger could not be built: {exc}"
    cards = []
    seen: dict[str, int] = {}
    for claim, entry in zip(claims, entries):
        base = re.sub(r"[^A-Za-z0-9]+", "-", entry.label).strip("-") or "claim"
        seen[base] = seen.get(base, 0) + 1
        anchor = f"ledger-{base}-{seen[base]}"
        typeset = getattr(claim, "check", None) is None and getattr(claim, "printed", None) is not None
        printed = eqs.sympy(claim.printed, entry.printed) if typeset else None  # type: ignore[attr-defined]
        same = typeset and entry.printed == entry.derived
        derived = None
        if typeset and not same:
            derived = eqs.sympy(claim.derived, entry.derived)  # type: ignore[attr-defined]
        cards.append(LedgerCard(entry.label, anchor, entry.title, entry.status, entry.explanation,
                                printed, derived, entry.printed, entry.derived, same))
    return cards, ""


def _figures(doc: dict[str, Any]) -> tuple[list[figures.Figure], dict[str, Any], str]:
    """Simulation figures (path, eps, rotation, phase portrait); (figures, settings, reason if none)."""
    from reports.closed_loop import simulate_certificate

    try:
        run = simulate_certificate(doc)
    except (LyapcheckError, ValueError, ArithmeticError) as exc:
        log.warning("no simulation for the report: %s", exc)
        return [], {}, str(exc)
    ub = _dict(_dict(doc.get("conditions")).get("ultimate_bound"))
    certified = ub.get("status") == "certified"
    bound = ub.get("eps_bound_m") if certified and isinstance(ub.get("eps_bound_m"), (int, float)) else None
    cert = _dict(ub.get("certificate"))
    stages = cert.get("stages") if isinstance(cert.get("stages"), list) else []
    ellipse = None
    if certified and stages and isinstance(stages[-1], dict):
        P = parse_matrix(stages[-1].get("P"))
        if P is not None and len(P) == 2 and len(P[0]) == 2:
            ellipse = np.array([[float(x) for x in r] for r in P])
    box = None
    box_data = _dict(cert.get("box"))
    e_box, s_box = parse_fraction(box_data.get("eps_bound")), parse_fraction(box_data.get("s_bound"))
    if certified and e_box is not None and s_box is not None:
        box = (float(e_box), float(s_box))
    if not certified:
        note = "No ultimate bound is certified for these numbers, so no set is drawn."
    elif doc.get("dynamics") == "printed":
        note = ("The certificate is for the dynamics as printed in the paper, while the simulation is of the real "
                "(derived) loop: the set need not contain its trajectories.")
    else:
        note = "Every trajectory must end inside the certified set; one that does not would be a soundness violation."
    figs = [figures.path_figure(run), figures.eps_figure(run, bound), figures.rotation_figure(run),
            figures.phase_figure(run, ellipse, box, note)]
    return figs, {**run.settings, "measurements": run.measurements[0]}, ""


def _soundness(doc: dict[str, Any], settings: dict[str, Any]) -> str:
    """A loud message when the simulated tail leaves the certified bound of the derived dynamics."""
    ub = _dict(_dict(doc.get("conditions")).get("ultimate_bound"))
    bound = ub.get("eps_bound_m")
    m = settings.get("measurements")
    if doc.get("dynamics") != "derived" or ub.get("status") != "certified" or not m or not isinstance(bound, float):
        return ""
    if m["sup_abs_eps_tail_m"] > bound:
        return (f"SOUNDNESS VIOLATION: the simulated sup |eps| over the tail ({m['sup_abs_eps_tail_m']:.6g} m) exceeds "
                f"the certified ultimate bound ({bound:.6g} m).")
    return ""


def _command(doc: dict[str, Any]) -> tuple[str, str]:
    """A command line and TOML file that reproduce the certificate."""
    given = _dict(_dict(doc.get("inputs")).get("given"))
    sections: dict[str, list[str]] = {}
    for key, raw in given.items():
        section, _, name = str(key).partition(".")
        sections.setdefault(section, []).append(f"{name} = {json.dumps(_str(raw))}")
    toml = "\n\n".join(f"[{s}]\n" + "\n".join(lines) for s, lines in sections.items())
    dynamics = doc.get("dynamics", "derived")
    command = f"lyapcheck certify inputs.toml --dynamics {_str(dynamics)} --out certificate.json"
    flags = " ".join(f"{FLAGS[k]} {json.dumps(_str(v))}" for k, v in given.items() if k in FLAGS)
    if flags:
        command += f"\n# or, with the gains as flags (other values at their defaults or from a TOML):\n" \
                   f"lyapcheck certify {flags} --dynamics {_str(dynamics)}"
    return command + "\nlyapcheck verify certificate.json   # exact re-check, no solver", toml


def _solvers(doc: dict[str, Any]) -> list[tuple[str, str]]:
    out = []
    for name, cond in _dict(doc.get("conditions")).items():
        solver = cond.get("solver") if isinstance(cond, dict) else None
        if isinstance(solver, dict):
            out.append((str(name), canonical_json(solver).decode()))
    return out


def certificate_context(doc: dict[str, Any], *, ledger: bool = True, simulate: bool = True) -> dict[str, Any]:
    """Everything the certificate template shows (strings unescaped; the template escapes).

    Parameters
    ----------
    doc
        A certificate document (``lyapcheck.certificate`` schema, version 1); unknown keys and
        condition classes are shown generically.
    ledger, simulate
        Include the claims ledger and the simulation figures (both on for real reports).
    """
    eqs = Equations()
    conditions = _conditions(doc, eqs)
    system = _system(doc, eqs)
    cards, ledger_reason = _ledger(eqs) if ledger else ([], "not requested")
    figs, sim_settings, sim_reason = _figures(doc) if simulate else ([], {}, "not requested")
    eqs.typeset()
    canonical = canonical_json(doc)
    inputs = canonical_json(doc.get("inputs"))
    command, toml = _command(doc)
    counts: dict[str, int] = {}
    for card in cards:
        counts[card.status] = counts.get(card.status, 0) + 1
    verdict = _str(doc.get("verdict", "unknown"))
    return {
        "kind": "certificate",
        "title": "lyapcheck certificate report",
        "verdict": verdict,
        "verdict_meaning": ("an exact check of a stability certificate passed" if verdict == "certified"
                            else "no stability certificate passed an exact check"),
        "dynamics": _str(doc.get("dynamics", "unknown")),
        "conditions": conditions,
        "status_meaning": STATUS_MEANING,
        "inputs": _inputs(doc),
        "system": system,
        "figures": figs,
        "simulation_reason": sim_reason,
        "simulation_settings": {k: v for k, v in sim_settings.items() if k != "measurements"},
        "soundness": _soundness(doc, sim_settings),
        "ledger": cards,
        "ledger_reason": ledger_reason,
        "ledger_counts": counts,
        "discrepancies": [c for c in cards if c.status == "discrepancy"],
        "versions": {**{str(k): _str(v) for k, v in _dict(doc.get("versions")).items()}, **versions()},
        "solvers": _solvers(doc),
        "hash_document": hashlib.sha256(canonical).hexdigest(),
        "hash_inputs": hashlib.sha256(inputs).hexdigest(),
        "command": command,
        "toml": toml,
        # every typeset equation, for reports.html to put on shared sheets (one glyph set per sheet)
        "equations": [eq.result for eq in eqs.items if eq.result is not None],
    }

