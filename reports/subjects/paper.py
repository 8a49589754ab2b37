"""The paper's ILOS/ODS loop as a certificate page's subject.

Its parts: the gains and swimmer (as given, in SI, exact) and the error dynamics ``A``, ``B``,
``E`` the conditions use; the closed loop in simulation (:mod:`reports.closed_loop`: path,
``eps(t)`` against the tightest certified bound, rotation, and the ``(eps, s)`` phase portrait
with the certified sets of :mod:`reports.certified_sets` and the worst case of
``--worst-case``), with a soundness alarm when a simulation exceeds a certified bound; the
claims ledger (the paper's equations as printed and as derived); the inputs TOML and command
line that reproduce the certificate.
"""

from __future__ import annotations

import hashlib
import json
import logging
import re
from dataclasses import dataclass
from fractions import Fraction
from typing import Any, Final

from markupsafe import Markup

from lyapcheck.errors import LyapcheckError
from reports import figures, paper_figures
from reports.sections.base import PAPER
from reports.sections.paper import BOUND_CLASSES, describe_disturbance, number, text
from reports.subjects.base import Glance, Quantity, Subject, canonical_json, verdict_head
from reports.typeset import Equation, Equations, parse_fraction, parse_matrix
from reports.views import Item, as_dict, dict_items, fmt_float, matrix_item

log = logging.getLogger(__name__)

#: command-line flags of ``lyapcheck certify`` (for the reproducibility block)
FLAGS: Final = {"gains.alpha_d": "--alpha-d", "gains.sigma0": "--sigma0", "gains.k_d": "--kd",
                "gains.delta_los": "--delta-los", "swimmer.e11": "--e11", "actuation.omega_so": "--omega-so",
                "disturbance.d_max": "--d-max"}


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


def inputs(doc: dict[str, Any]) -> list[Quantity]:
    """One row per input as given, with its SI value (exact where it is not an integer) and meaning."""
    from lyapcheck.paper.params import FIELD_BY_KEY, validate_field

    given_si = as_dict(doc.get("inputs"))
    given, exact_si = as_dict(given_si.get("given")), as_dict(given_si.get("exact_si"))
    rows = []
    for key, raw in given.items():
        key = str(key)
        spec = FIELD_BY_KEY.get(key)
        exact = exact_si.get(key.split(".")[-1])
        value: Fraction | None = parse_fraction(exact) if exact is not None else None
        if value is None and spec is not None:
            try:
                value = validate_field(spec, raw)
            except (ValueError, TypeError):
                value = None
        unit = spec.kind.si_unit if spec is not None else ""
        si = "—" if value is None else f"{fmt_float(float(value))} {unit}".strip()
        rows.append(Quantity(key, text(raw), si, "" if value is None or value.denominator == 1 else str(value),
                             spec.help if spec is not None else ""))
    return rows


def system(doc: dict[str, Any], eqs: Equations) -> list[Item]:
    """The error dynamics ``A``, ``B``, ``E`` (exact), then anything else the document stores with them."""
    stored = as_dict(doc.get("system"))
    items = []
    for name in ("A", "B"):
        rows = parse_matrix(stored.get(name))
        if rows is not None:
            items.append(matrix_item(name, rows, eqs, stored.get(name)))
    vec = stored.get("E")
    if isinstance(vec, list):
        rows = parse_matrix([[x] for x in vec])
        if rows is not None:
            items.append(matrix_item("E", rows, eqs, vec))
    rest = {k: v for k, v in stored.items() if k not in ("A", "B", "E")}
    return items + dict_items(rest, eqs)


def ledger_cards(eqs: Equations) -> tuple[list[LedgerCard], str]:
    """The claims ledger with typeset printed/derived forms; (cards, reason if unavailable)."""
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
        cond = as_dict(as_dict(doc.get("conditions")).get(name))
        bound = number(cond.get("eps_bound_m"))
        if cond.get("status") == "certified" and bound is not None and bound > 0:
            found.append((bound, name))
    return min(found, default=None)


def simulation_figures(doc: dict[str, Any]) -> tuple[list[figures.Figure], dict[str, Any], str]:
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
        kind = text(desc.get("kind", "")).replace("_", " ").replace("bang bang", "bang-bang")
        hz = number(desc.get("frequency_hz"))
        worst_label = (f"worst case found: {kind}{f' {hz:.3g} Hz' if hz is not None else ''}, "
                       f"tail sup $|\\varepsilon|$ = {run.worst.sup_abs_eps_tail_m * 1e3:.4g} mm")
    phase = paper_figures.phase_figure(run, sets, " ".join([note, *set_notes]), worst_label, worst_text)
    figs = [paper_figures.path_figure(run),
            paper_figures.eps_figure(run, tight[0] if tight else None, tight[1] if tight else ""),
            paper_figures.rotation_figure(run), phase]
    settings: dict[str, Any] = {**run.settings, "measurements": run.measurements[0]}
    if run.worst is not None:
        settings["worst_case_measured"] = {"start": run.worst.start,
                                           "sup_abs_eps_tail_m": run.worst.sup_abs_eps_tail_m}
    return figs, settings, ""


def soundness(doc: dict[str, Any], settings: dict[str, Any]) -> str:
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
        cond = as_dict(as_dict(doc.get("conditions")).get(name))
        bound = number(cond.get("eps_bound_m"))
        if cond.get("status") != "certified" or bound is None:
            continue
        if m and m["sup_abs_eps_tail_m"] > bound:
            messages.append(f"the simulated sup |eps| over the tail ({m['sup_abs_eps_tail_m']:.6g} m) exceeds the "
                            f"certified ultimate bound of {name} ({bound:.6g} m)")
        if worst and worst["sup_abs_eps_tail_m"] > bound:
            messages.append(f"the re-simulated worst case's sup |eps| over the tail ({worst['sup_abs_eps_tail_m']:.6g} m) "
                            f"exceeds the certified ultimate bound of {name} ({bound:.6g} m)")
        ratio = number(cond.get("tightness_ratio"))
        if cond.get("soundness_violation") is True or (ratio is not None and ratio < 1):
            found = f"tightness_ratio {ratio:.4g} < 1" if ratio is not None else "a soundness violation"
            messages.append(f"the certificate's own worst-case search found {found} for {name}")
    return ("SOUNDNESS VIOLATION: " + "; ".join(messages) + ".") if messages else ""


def command(doc: dict[str, Any]) -> tuple[str, str]:
    """A command line and TOML file that reproduce the certificate."""
    given = as_dict(as_dict(doc.get("inputs")).get("given"))
    sections: dict[str, list[str]] = {}
    for key, raw in given.items():
        section, _, name = str(key).partition(".")
        sections.setdefault(section, []).append(f"{name} = {json.dumps(text(raw))}")
    toml = "\n\n".join(f"[{s}]\n" + "\n".join(lines) for s, lines in sections.items())
    dynamics = doc.get("dynamics", "derived")
    line = f"lyapcheck certify inputs.toml --dynamics {text(dynamics)} --out certificate.json"
    flags = " ".join(f"{FLAGS[k]} {json.dumps(text(v))}" for k, v in given.items() if k in FLAGS)
    if flags:
        line += f"\n# or, with the gains as flags (other values at their defaults or from a TOML):\n" \
                f"lyapcheck certify {flags} --dynamics {text(dynamics)}"
    return line + "\nlyapcheck verify certificate.json   # exact re-check, no solver", toml


def solvers(doc: dict[str, Any]) -> list[tuple[str, str]]:
    """Per condition, its solver settings and outcomes as canonical JSON."""
    out = []
    for name, cond in as_dict(doc.get("conditions")).items():
        solver = cond.get("solver") if isinstance(cond, dict) else None
        if isinstance(solver, dict):
            out.append((str(name), canonical_json(solver).decode()))
    return out


class PaperSubject(Subject):
    model = PAPER
    template = "paper.html.j2"

    def parts(self, eqs: Equations, *, ledger: bool, simulate: bool) -> dict[str, Any]:
        doc = self.doc
        dynamics = system(doc, eqs)
        cards, ledger_reason = ledger_cards(eqs) if ledger else ([], "not requested")
        figs, sim_settings, sim_reason = simulation_figures(doc) if simulate else ([], {}, "not requested")
        line, toml = command(doc)
        counts: dict[str, int] = {}
        for card in cards:
            counts[card.status] = counts.get(card.status, 0) + 1
        return {
            "kind": "certificate",
            "title": "lyapcheck certificate report",
            **verdict_head(doc),
            "dynamics": text(doc.get("dynamics", "unknown")),
            "glance": Glance(("condition", "status", "what it means"), False,
                             ("certified", "refuted", "not_certified", "inconclusive")),
            # Markup: the page's own words (not input), printed as written
            "toc": [("inputs", "Gains and swimmer"), ("conditions", "Conditions, one by one"),
                    ("simulation", "The closed loop in simulation"),
                    ("ledger", Markup("Claims ledger: the paper's equations")), ("reproduce", "Reproducibility")],
            "classes_anchor": "conditions",
            "classes_heading": "Conditions, one by one",
            "inputs": inputs(doc),
            "system": dynamics,
            "figures": figs,
            "simulation_reason": sim_reason,
            "simulation_settings": {k: v for k, v in sim_settings.items() if k != "measurements"},
            "soundness": soundness(doc, sim_settings),
            "ledger": cards,
            "ledger_reason": ledger_reason,
            "ledger_counts": counts,
            "discrepancies": [c for c in cards if c.status == "discrepancy"],
            "command": line,
            "toml": toml,
            "hash_inputs": hashlib.sha256(canonical_json(doc.get("inputs"))).hexdigest(),
            "verbatim_title": "inputs.toml (the inputs exactly as given)",
            "verbatim": toml,
            "solvers": solvers(doc),
            "solvers_title": "Solver settings and outcomes",
            "solvers_exact": True,
            "solvers_note": "",
        }

    def fingerprints(self, context: dict[str, Any]) -> list[tuple[str, str]]:
        return [("SHA-256 of the inputs (canonical JSON)", context["hash_inputs"]),
                ("SHA-256 of the whole certificate (canonical JSON)", context["hash_document"])]


__all__ = ["PaperSubject", "LedgerCard", "inputs", "system", "ledger_cards", "tightest_bound", "simulation_figures",
           "soundness", "command", "solvers"]
