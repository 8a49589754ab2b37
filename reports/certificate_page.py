"""The certificate report's content: inputs, conditions, ultimate bound, figures, ledger, provenance.

:func:`certificate_context` turns a certificate document (``lyapcheck.paper.certificate`` schema)
into the data the template shows. Every string in it is plain text: the template escapes it.
"""

from __future__ import annotations

import hashlib
import json
import logging
from dataclasses import dataclass, field
from fractions import Fraction
from typing import Any

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
    "sos_bound": "Certified ultimate bound on the cross-track error from a polynomial storage function (SOS)",
}
#: condition classes that certify ``limsup |eps| <= eps_bound_m`` (the certified sets of the phase portrait)
BOUND_CLASSES = ("ultimate_bound", "sos_bound")
#: numbers ``lyapcheck certify --worst-case`` puts on those classes, shown in their own table
TIGHTNESS_KEYS = ("worst_case_sup_abs_eps_tail_m", "tightness_ratio", "soundness_violation")
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
    #: certified against the worst simulated disturbance: (what, value) rows, or why there are none
    tightness: list[tuple[str, str]] = field(default_factory=list)
    tightness_note: str = ""


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
    from lyapcheck.paper.params import FIELD_BY_KEY, validate_field

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


def _number(value: object) -> float | None:
    return float(value) if isinstance(value, (int, float)) and not isinstance(value, bool) else None


def describe_disturbance(desc: dict[str, Any]) -> str:
    """A short reading of a stored disturbance description (lyapcheck.simulation.disturbances)."""
    kind = _str(desc.get("kind", "unknown"))
    hz = _number(desc.get("frequency_hz"))
    text = {"square_wave": "square wave of amplitude d* across the path",
            "sinusoid": "sinusoid across the path", "bang_bang": "bang-bang of amplitude d* across the path",
            "constant": "constant", "feedback": "state feedback of amplitude d* across the path",
            "none": "no disturbance"}.get(kind, kind.replace("_", " "))
    if hz is not None:
        text += f" at {hz:.3g} Hz"
    times = desc.get("switch_times_s")
    if kind == "bang_bang" and isinstance(times, list):
        text += f", {len(times)} switches"
    family = desc.get("family")
    return text + (f" (search family: {_str(family)})" if family is not None else "")


def _tightness(cond: dict[str, Any]) -> tuple[list[tuple[str, str]], str]:
    """Rows comparing a certified bound with the worst simulated disturbance (``certify --worst-case``)."""
    bound = _number(cond.get("eps_bound_m"))
    worst = _number(cond.get("worst_case_sup_abs_eps_tail_m"))
    if bound is None or cond.get("status") != "certified":
        return [], ""
    if worst is None:
        return [], ("No worst-case search in this certificate: `lyapcheck certify --worst-case` adds the worst "
                    "disturbance found in simulation and the ratio certified / simulated.")
    ratio = _number(cond.get("tightness_ratio"))
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


#: said before the text of a decided class this version does not know (``verify`` fails it)
UNKNOWN_CLASS = "(not checked: lyapcheck knows no such class) "


def shown_summary(name: str, cond: dict[str, Any], doc: dict[str, Any]) -> str:
    """The sentence a reader sees: for a decided class, the one its data give
    (:func:`lyapcheck.paper.claims.summary`, as ``verify`` regenerates it), never the file's own
    text; for the others, the file's reason. A class this version does not know is shown as
    written, said to be unchecked."""
    from lyapcheck.paper import claims

    box = doc.get("box")
    if cond.get("status") in claims.DECIDED and not claims.known(name, isinstance(box, dict)):
        return UNKNOWN_CLASS + _str(cond.get("summary", ""))
    try:
        text = claims.summary(name, cond, _dict(_dict(doc.get("inputs")).get("exact_si")),
                              box if isinstance(box, dict) else None)
    except claims.MALFORMED:
        return "(no sentence: the data of this condition are malformed)"
    return text if text is not None else _str(cond.get("summary", ""))


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
        tightness, tightness_note = _tightness(cond) if name in BOUND_CLASSES else ([], "")
        if tightness:
            shown_elsewhere |= set(TIGHTNESS_KEYS)
        rest = {k: v for k, v in cond.items() if k not in shown_elsewhere}
        view = ConditionView(name, CONDITION_TITLES.get(name, name), status, shown_summary(name, cond, doc),
                             dict_items(rest, eqs), tightness=tightness, tightness_note=tightness_note)
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
        from lyapcheck.paper.ledger_view import all_claims
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


def tightest_bound(doc: dict[str, Any]) -> tuple[float, str] | None:
    """The smallest certified ``limsup |eps|`` of the document and its class."""
    found = []
    for name in BOUND_CLASSES:
        cond = _dict(_dict(doc.get("conditions")).get(name))
        bound = _number(cond.get("eps_bound_m"))
        if cond.get("status") == "certified" and bound is not None and bound > 0:
            found.append((bound, name))
    return min(found, default=None)


def _figures(doc: dict[str, Any]) -> tuple[list[figures.Figure], dict[str, Any], str]:
    """Simulation figures (path, eps, rotation, phase portrait); (figures, settings, reason if none)."""
    from reports.certified_sets import certified_sets
    from reports.closed_loop import simulate_certificate

    try:
        run = simulate_certificate(doc)
    except (LyapcheckError, ValueError, ArithmeticError) as exc:
        log.warning("no simulation for the report: %s", exc)
        return [], {}, str(exc)
    tight = tightest_bound(doc)
    sets, set_notes = certified_sets(doc)
    if not sets:
        note = "No ultimate bound is certified for these numbers, so no set is drawn."
    elif doc.get("dynamics") == "printed":
        note = ("The certificates are for the dynamics as printed in the paper, while the simulation is of the real "
                "(derived) loop: the sets need not contain its trajectories.")
    else:
        note = ("Every trajectory must end inside every certified set (limsup: the certificates speak of the "
                "unsaturated error dynamics, which the simulated saturated loop follows once |u| stays below the "
                "step-out frequency); a tail outside the eps-extent of a set would be a soundness violation.")
    worst_label = worst_text = ""
    if run.worst is not None:
        desc = run.worst.disturbance
        worst_text = describe_disturbance(desc)
        kind = _str(desc.get("kind", "")).replace("_", " ").replace("bang bang", "bang-bang")
        hz = _number(desc.get("frequency_hz"))
        worst_label = (f"worst case found: {kind}{f' {hz:.3g} Hz' if hz is not None else ''}, "
                       f"tail sup $|\\varepsilon|$ = {run.worst.sup_abs_eps_tail_m * 1e3:.4g} mm")
    phase = figures.phase_figure(run, sets, " ".join([note, *set_notes]), worst_label, worst_text)
    figs = [figures.path_figure(run), figures.eps_figure(run, tight[0] if tight else None, tight[1] if tight else ""),
            figures.rotation_figure(run), phase]
    settings: dict[str, Any] = {**run.settings, "measurements": run.measurements[0]}
    if run.worst is not None:
        settings["worst_case_measured"] = {"start": run.worst.start,
                                           "sup_abs_eps_tail_m": run.worst.sup_abs_eps_tail_m}
    return figs, settings, ""


def _soundness(doc: dict[str, Any], settings: dict[str, Any]) -> str:
    """A loud message when a simulation exceeds a certified bound of the derived dynamics.

    Checked: the constant-disturbance tail from the paper's start and the re-simulated worst case
    against every certified bound, and the ratio ``lyapcheck certify --worst-case`` stored.
    """
    if doc.get("dynamics") != "derived":
        return ""
    m = settings.get("measurements")
    worst = settings.get("worst_case_measured")
    messages = []
    for name in BOUND_CLASSES:
        cond = _dict(_dict(doc.get("conditions")).get(name))
        bound = _number(cond.get("eps_bound_m"))
        if cond.get("status") != "certified" or bound is None:
            continue
        if m and m["sup_abs_eps_tail_m"] > bound:
            messages.append(f"the simulated sup |eps| over the tail ({m['sup_abs_eps_tail_m']:.6g} m) exceeds the "
                            f"certified ultimate bound of {name} ({bound:.6g} m)")
        if worst and worst["sup_abs_eps_tail_m"] > bound:
            messages.append(f"the re-simulated worst case's sup |eps| over the tail ({worst['sup_abs_eps_tail_m']:.6g} m) "
                            f"exceeds the certified ultimate bound of {name} ({bound:.6g} m)")
        ratio = _number(cond.get("tightness_ratio"))
        if cond.get("soundness_violation") is True or (ratio is not None and ratio < 1):
            found = f"tightness_ratio {ratio:.4g} < 1" if ratio is not None else "a soundness violation"
            messages.append(f"the certificate's own worst-case search found {found} for {name}")
    return ("SOUNDNESS VIOLATION: " + "; ".join(messages) + ".") if messages else ""


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
        A certificate document (``lyapcheck.paper.certificate`` schema, version 1); unknown keys and
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

