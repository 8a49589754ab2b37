"""What an API result shows in a notebook: a few lines of ``repr`` and a small HTML table.

The results of :mod:`lyapcheck.api` carry whole documents (certificates with their exact
polynomials, every simulated trajectory); their ``repr`` says only what was found, one line per
condition class (or per output), well under :data:`REPR_LIMIT` characters whatever the model's
size, and their ``_repr_html_`` is an escaped table of the same (with the classes' summaries).
``to_dict()`` gives the whole document. Each function here takes the document (JSON-shaped).
"""

from __future__ import annotations

import html
from typing import Any, Mapping, Sequence

#: a repr stays within this many characters (names and lists are shortened to fit)
REPR_LIMIT = 1000
#: the most outputs (or failed checks) listed one per line; the rest are counted
MAX_LISTED = 12
#: a free-text name (a model's) is cut at a word boundary beyond this many characters
NAME_LIMIT = 80


def _short(text: str, limit: int = NAME_LIMIT) -> str:
    text = " ".join(str(text).split())
    if len(text) <= limit:
        return text
    cut = text[:limit].rsplit(" ", 1)[0] or text[:limit]
    return cut + " ..."


def _figure(x: Any) -> str:
    return "-" if x is None else format(x, ".6g") if isinstance(x, (int, float)) else str(x)


def _bounded(lines: list[str]) -> str:
    """The lines, dropping whole lines from the end (and saying how many) beyond :data:`REPR_LIMIT`."""
    kept, dropped = list(lines), 0
    while len("\n".join(kept)) > REPR_LIMIT and len(kept) > 1:
        kept.pop()
        dropped += 1
        tail = f"  ... ({dropped} more lines: to_dict() has everything)"
        if len("\n".join([*kept, tail])) <= REPR_LIMIT:
            return "\n".join([*kept, tail])
    return "\n".join(kept)


# -- certify -------------------------------------------------------------------------------------

def _box_text(box: Mapping[str, Sequence[Any]]) -> str:
    return ", ".join(f"{name} in [{lo}, {hi}]" for name, (lo, hi) in box.items())


def certify_subject(doc: Mapping[str, Any]) -> str:
    """What was certified: the model's name (or the paper's loop) and the parameter box, if any."""
    subject = (f"model '{_short(doc['model']['name'])}'" if "model" in doc
               else f"the paper's loop, {doc.get('dynamics', 'derived')} dynamics")
    if doc.get("box"):
        subject += f", over the box {_short(_box_text(doc['box']), 200)}"
    return subject


def _claim(cond: Mapping[str, Any]) -> str:
    parts = [str(cond.get("property", ""))]
    if cond.get("disturbances") == "zero":
        parts.append("(d = 0)")
    elif cond.get("disturbances") == "all":
        parts.append("(every d)")
    return " ".join(p for p in parts if p)


def certify_repr(doc: Mapping[str, Any]) -> str:
    """``CertifyResult``: the verdict, then one line per class (status, property, disturbances)."""
    conditions: Mapping[str, Mapping[str, Any]] = doc["conditions"]
    width = max([len(n) for n in conditions] + [9])
    answers = ", ".join(f"{q} {a.get('answer')}" for q, a in (doc.get("answers") or {}).items() if isinstance(a, Mapping))
    lines = [f"CertifyResult: {doc['verdict']} ({certify_subject(doc)})" + (f": {answers}" if answers else "")]
    lines += [f"  {name:<{width}}  {str(c['status']):<14}  {_claim(c)}".rstrip() for name, c in conditions.items()]
    return _bounded(lines)


def _table(caption: str, header: Sequence[str], rows: Sequence[Sequence[Any]]) -> str:
    e = html.escape
    head = "".join(f"<th style=\"text-align:left\">{e(h)}</th>" for h in header)
    body = "".join("<tr>" + "".join(f"<td style=\"text-align:left\">{e(str(c))}</td>" for c in row) + "</tr>"
                   for row in rows)
    return (f"<table><caption style=\"text-align:left\">{caption}</caption><thead><tr>{head}</tr></thead>"
            f"<tbody>{body}</tbody></table>")


def certify_html(doc: Mapping[str, Any]) -> str:
    """``CertifyResult._repr_html_``: the verdict and one row per class, with its summary (escaped)."""
    caption = f"<strong>{html.escape(str(doc['verdict']))}</strong>: {html.escape(certify_subject(doc))}"
    answers = [f"{html.escape(q)}: <strong>{html.escape(str(a.get('answer')))}</strong> ({html.escape(str(a.get('text')))})"
               for q, a in (doc.get("answers") or {}).items() if isinstance(a, Mapping)]
    if answers:
        caption += "<br>" + "<br>".join(answers)
    rows = [[name, c["status"], _claim(c), c.get("summary", "")] for name, c in doc["conditions"].items()]
    return _table(caption, ["condition", "status", "property", "what it means"], rows)


# -- verify --------------------------------------------------------------------------------------

def verify_repr(doc: Mapping[str, Any]) -> str:
    """``VerifyResult``: valid or not, the count, and the failing checks (each on one line)."""
    checks = doc["checks"]
    failed = [c for c in checks if not c["ok"]]
    if not failed:
        return f"VerifyResult: valid (all {len(checks)} exact checks pass)"
    lines = [f"VerifyResult: NOT valid ({len(failed)} of {len(checks)} exact checks fail)"]
    lines += [f"  FAIL {c['check']}: {_short(c['message'], 120)}" for c in failed[:MAX_LISTED]]
    if len(failed) > MAX_LISTED:
        lines.append(f"  ... and {len(failed) - MAX_LISTED} more")
    return _bounded(lines)


def verify_html(doc: Mapping[str, Any]) -> str:
    caption = "<strong>valid</strong>" if doc["valid"] else "<strong>NOT valid</strong>"
    rows = [["ok" if c["ok"] else "FAIL", c["check"], c["message"]] for c in doc["checks"]]
    return _table(caption, ["", "check", "message"], rows)


# -- simulate ------------------------------------------------------------------------------------
# Every key is read with a default: a document of any shape (a model's scenarios or worst case, the
# paper's loop, an older or hand-made one) gives its lines, never an exception.

def _per_output(values: Any) -> list[str]:
    items = [f"{name} {_figure(v)}" for name, v in (values.items() if isinstance(values, Mapping) else ())]
    if not items:
        return []
    lines = ["  tail sup |y|: " + ", ".join(items[:MAX_LISTED])]
    if len(items) > MAX_LISTED:
        lines[0] += f", ... ({len(items) - MAX_LISTED} more outputs)"
    return lines


def _model_name(doc: Mapping[str, Any]) -> str:
    """The model's name: ``model`` is ``{"name": ...}`` (any model file), or a bare name."""
    model = doc.get("model")
    return _short(str(model.get("name", "?") if isinstance(model, Mapping) else model))


def _mapping(value: Any) -> Mapping[str, Any]:
    return value if isinstance(value, Mapping) else {}


def _window(doc: Mapping[str, Any]) -> str:
    window = doc.get("tail_window_s")
    if isinstance(window, (list, tuple)) and len(window) == 2:
        return f", tail window {_figure(window[0])}-{_figure(window[1])} s"
    return ""


def simulation_lines(doc: Mapping[str, Any]) -> list[str]:
    """What a simulation found, in a few lines (a model's scenarios or worst case, or the paper's loop)."""
    if "model" in doc:
        name = _model_name(doc)
        if doc.get("mode") == "worst_case":
            lines = [f"worst case of model '{name}' ({doc.get('candidates_tried', '?')} candidates; a search, not a "
                     "proof)"]
            tight = _mapping(doc.get("tightness"))
            worst = _mapping(doc.get("worst"))
            for y, found in list(worst.items())[:MAX_LISTED]:
                found = _mapping(found)
                ratio = _mapping(tight.get(y)).get("tightness_ratio")
                extra = f", tightness_ratio {_figure(ratio)}" if y in tight else ""
                lines.append(f"  {y}: worst tail sup {_figure(found.get('sup_abs_output_tail'))} "
                             f"({_mapping(found.get('disturbance')).get('kind', '?')}){extra}")
            if len(worst) > MAX_LISTED:
                lines.append(f"  ... ({len(worst) - MAX_LISTED} more outputs)")
            return lines
        trajectories = doc.get("trajectories")
        count = doc.get("n_trajectories", len(trajectories) if isinstance(trajectories, list) else "?")
        counts = f"{count} trajectories ({doc.get('n_converged', '?')} converged"
        counts += f", {doc['n_diverged']} diverged)" if "n_diverged" in doc else ")"
        scenarios = doc.get("scenarios")
        which = f", scenarios {', '.join(map(str, scenarios))}" if isinstance(scenarios, (Mapping, list)) else ""
        angles = doc.get("angles_modulo_2pi")
        modulo = (f", converged modulo 2 pi in {', '.join(map(str, angles))}" if isinstance(angles, list) and angles
                  else "")
        lines = [f"model '{name}': {counts}{which}{_window(doc)}{modulo}"]
        if doc.get("mode") == "sampled":  # a sampled-data loop: its period and the number of periods
            lines.append(f"  sampled every {_figure(doc.get('period_s'))} s (zero-order hold), "
                         f"{doc.get('periods', '?')} periods")
        return lines + _per_output(doc.get("sup_abs_output_tail"))
    if doc.get("mode") == "worst_case":
        return [f"worst case of {doc.get('scenario', '?')}: tail sup |eps| {_figure(doc.get('sup_abs_eps_tail_m'))} m "
                f"({doc.get('candidates_tried', '?')} candidates; a search, not a proof)"]
    return [f"{doc.get('scenario', '?')} ({doc.get('controller', '?')}, ODS {doc.get('ods_form', '?')}): "
            f"{'diverged' if doc.get('diverged') else 'did not diverge'}",
            f"  mean |eps| {_figure(doc.get('mean_abs_eps_tail_m'))} m, sup |eps| "
            f"{_figure(doc.get('sup_abs_eps_tail_m'))} m{_window(doc).replace(', tail window', ' over')}; steady "
            f"rotation {_figure(doc.get('steady_rotation_hz'))} Hz, max {_figure(doc.get('max_rotation_hz'))} Hz"]


def series_line(series: Any) -> str:
    """One line on a result's time series (an xarray Dataset, or None)."""
    if series is None:
        return "  series: none (worst-case searches and series=False keep no time series)"
    sizes = dict(series.sizes)
    shape = [f"{sizes['trajectory']} trajectories"] if "trajectory" in sizes else []
    # (a discrete-time map's iterates are over steps, not times: lyapcheck.models.surfaces.iterate)
    shape.append(f"{sizes['step']} steps" if "step" in sizes else f"{sizes.get('time', 0)} times")
    names = ", ".join(str(v) for v in series.data_vars)
    return f"  series: xarray.Dataset of {_short(names, 60)} over {' x '.join(shape)} (result.series)"


def simulation_repr(doc: Mapping[str, Any], series: Any) -> str:
    lines = simulation_lines(doc)
    return _bounded(["SimulationReport: " + lines[0], *lines[1:], series_line(series)])


def simulation_html(doc: Mapping[str, Any]) -> str:
    """``SimulationReport._repr_html_``: the headline and, per output, its tail sup (per scenario)."""
    lines = simulation_lines(doc)
    caption = html.escape(lines[0])
    if "model" in doc and doc.get("mode") != "worst_case":
        scenarios = _mapping(doc.get("scenarios"))
        names = list(scenarios)
        rows = [[y] + [_figure(_mapping(_mapping(scenarios[s]).get("sup_abs_output_tail")).get(y)) for s in names]
                + [_figure(v)] for y, v in _mapping(doc.get("sup_abs_output_tail")).items()]
        return _table(caption, ["tail sup of |output|", *names, "all"], rows)
    if "model" in doc:  # a model's worst case: one row per output
        tight = _mapping(doc.get("tightness"))
        rows = [[y, _figure(_mapping(found).get("sup_abs_output_tail")),
                 _mapping(_mapping(found).get("disturbance")).get("kind", "?"),
                 _figure(_mapping(tight[y]).get("tightness_ratio")) if y in tight else "-"]
                for y, found in _mapping(doc.get("worst")).items()]
        return _table(caption, ["output", "worst tail sup", "disturbance", "tightness_ratio"], rows)
    keys = ["mean_abs_eps_tail_m", "sup_abs_eps_tail_m", "final_eps_m", "steady_rotation_hz", "max_rotation_hz",
            "convergence_time_s", "constant_sup_abs_eps_tail_m"]
    rows = [[k, _figure(doc[k])] for k in keys if k in doc]
    return _table(caption, ["quantity (SI, the unit in the name)", "value"], rows)


__all__ = ["certify_repr", "certify_html", "certify_subject", "verify_repr", "verify_html", "simulation_repr",
           "simulation_html", "simulation_lines", "series_line", "REPR_LIMIT"]
