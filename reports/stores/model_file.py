"""The sweep of a model file (``[sweep] model = FILE``): the map of certified, refuted and undecided points or boxes.

A model sweep's store (:mod:`sweeps.schema`) holds, per grid point or per box of a
refinement tree, the status (``certified``: a class of the model proved its property, for every
parameter value of a box; ``refuted``: the equilibrium is proved unstable there, exactly, or a safety class's
claim is proved false there (an initial start reaching the unsafe set);
``not_certified``: nothing decided), each class's status and key figures, the certificate document
and the simulation cross-check. The page draws the map over the swept parameters:

* boxes, one or two parameters: every leaf of the tree as a rectangle (an interval of a strip
  with one parameter), coloured by status, with the SVG id ``box-<row>-<status>``;
* points, one to three parameters: :func:`reports.figures.category_map` (three: slices);
* boxes over three parameters: no map (a note), the leaves are listed instead;

then the summary table (the same numbers as ``lyapcheck sweep`` prints, from
:func:`sweeps.summary.summarize_dataset`), the classes' figures, the cross-check and its
violations, the model file verbatim with its SHA-256, and the spec.
"""

from __future__ import annotations

import hashlib
import math
from typing import Any, Final, Sequence

import numpy as np

from lyapcheck.models.language.parameter_box import box_text
from reports import figures
from reports.stores.common import LEAF_NAMES, BoxAxis, Leaves, box_map, mpl, provenance, window_percent
from reports.views import fmt_float
from sweeps.schema import BOX_STATUS_CODES, BOXES_MODE, is_map_store, json_list, model_box_variables as box_variables
from sweeps.summary import LEAF_STATUSES, ModelSweepSummary, stored_window, summarize_dataset, violation_count

#: what each status means on this page
MEANING: Final = {
    "certified": "a class of the model proved its property (a region of attraction, GAS, GES or an ultimate bound) "
                 "with a certificate checked exactly: at the grid point, or for every parameter value of the box",
    "not_certified": "no class certified; nothing is proved either way (the box may be at the minimum width or the "
                     "sweep at its box budget)",
    "refuted": "the equilibrium is proved unstable, exactly (the linearization has an eigenvalue with positive real "
               "part) at the point or at a corner of the box: no stability certificate can exist there; or a safety "
               "class (barrier, reach_avoid) is refuted: a start in the initial set is proved to reach the unsafe set "
               "at the point or at a value of the box (named in the note), so its claim for every value is false",
}
#: leaves listed when there is no map (three swept parameters)
MAX_LEAF_ROWS: Final = 200
MAX_VIOLATION_ROWS: Final = 50


def _span(values: list[float] | None, unit: str = "") -> str:
    if not values:
        return "—"
    lo, hi = values
    return f"{fmt_float(lo, 4)}{unit}" if lo == hi else f"{fmt_float(lo, 4)} … {fmt_float(hi, 4)}{unit}"


def _where_box(dims: Sequence[str], lo: Sequence[float], hi: Sequence[float]) -> str:
    return box_text(((d, float(a), float(b)) for d, a, b in zip(dims, lo, hi)), digits=5)


def _box_part(ds: Any, summary: ModelSweepSummary) -> dict[str, Any]:
    dims, classes, outputs = summary.dims, summary.classes, tuple(json_list(ds, "outputs"))
    # (a map's store has its figures per step: its columns are named after them)
    data = {v.name: np.asarray(ds[v.name].values) for v in box_variables(dims, classes, outputs, is_map_store(ds))}
    done = data["done"].astype(bool)
    leaf = done & (data["status"] != BOX_STATUS_CODES["split"])
    rows = np.flatnonzero(leaf)
    lo = np.column_stack([data[f"lo_{d}"][rows].astype(float) for d in dims]) if rows.size else np.zeros((0, len(dims)))
    hi = np.column_stack([data[f"hi_{d}"][rows].astype(float) for d in dims]) if rows.size else np.zeros((0, len(dims)))
    codes = data["status"][rows].astype(int)
    window = stored_window(ds, dims, data)
    partial = summary.share["not_computed"] > 1e-9
    figure = None
    if len(dims) <= 2 and all(math.isfinite(v) for w in window.values() for v in w):
        axes = [BoxAxis(d, mpl(d), 1.0, summary.scales[d], window[d]) for d in dims]
        svg = box_map(axes, Leaves(rows, codes, lo, hi), None, partial=partial,
                      title=mpl(f"{summary.model.get('name') or 'model'}: proved boxes of parameters"))
        scales = ", ".join(f"{d} {'logarithmic' if summary.scales[d] == 'log' else 'linear'}" for d in dims)
        figure = figures.Figure(svg, f"Every leaf of the refinement tree ({rows.size} boxes), coloured by status; the "
                                     f"black outline is the swept window; axes: {scales}."
                                     + (" Hatched: not computed yet (the store is partial)." if partial else ""),
                                "map of the boxes of parameters coloured by status",
                                {"leaf_rows": [int(r) for r in rows]})
    leaf_rows = []
    if figure is None:
        for row, code, a, b in list(zip(rows, codes, lo, hi))[:MAX_LEAF_ROWS]:
            leaf_rows.append((str(int(row)), LEAF_NAMES.get(int(code), "not_certified"), _where_box(dims, a, b),
                              str(data["note"][row])))
    return {"map": figure, "leaf_rows": leaf_rows, "leaf_rows_more": max(0, rows.size - MAX_LEAF_ROWS)
            if figure is None else 0,
            "tree": [("boxes computed", f"{summary.computed} (of {int(ds.sizes['box'])} rows in the store)"),
                     ("leaves (boxes not split further)", str(summary.leaves)),
                     ("deepest refinement level", str(int(data["level"][done].max())) if done.any() else "—")]}


def _refuted_words(ds: Any) -> str:
    """What a refuted point of this sweep is: unstable (a stability class asked), unsafe (a safety class), or
    either (both kinds asked)."""
    from lyapcheck.models.classes.registry import SAFETY, STABILITY

    classes = json_list(ds, "classes")
    unsafe, unstable = any(c in SAFETY for c in classes), any(c in STABILITY for c in classes)
    return "unstable or unsafe" if unsafe and unstable else "unsafe" if unsafe else "unstable"


def _point_part(ds: Any, summary: ModelSweepSummary) -> dict[str, Any]:
    dims = summary.dims
    axes = [figures.Axis(d, mpl(d), np.asarray(ds.coords[d].values, dtype=float), summary.scales[d] == "log")
            for d in dims]
    codes = np.asarray(ds["status"].transpose(*dims).values).astype(int)
    violation = np.asarray(ds["soundness_violation"].transpose(*dims).values).astype(bool)
    legend = [(1, "certified", figures.STATUS_COLOURS["certified"]),
              (0, "not certified", figures.STATUS_COLOURS["not_certified"]),
              (2, f"refuted ({_refuted_words(ds)})", figures.STATUS_COLOURS["refuted"]),
              (-1, "not computed", figures.STATUS_COLOURS["not_computed"])]
    present = [entry for entry in legend if np.any(codes == entry[0])] or legend[:1]
    svg = figures.category_map(codes, axes, title=mpl(f"{summary.model.get('name') or 'model'}: status at each grid "
                                                       "point"), legend=present,
                               marks=[(violation, "SOUNDNESS VIOLATION", "o")], paper=None)
    figure = figures.Figure(svg, "Status at each grid point (a certificate at that point only; the cells between "
                                 "the points are not proved); red rings: soundness violations"
                            + (". Three parameters: slices of the third." if len(dims) == 3 else "."),
                            "map of the grid points coloured by status", {"codes": codes.tolist()})
    return {"map": figure, "leaf_rows": [], "leaf_rows_more": 0,
            "tree": [("grid points", f"{summary.total} ({' x '.join(str(a.values.size) for a in axes)})"),
                     ("points computed", str(summary.computed))]}


def _violations(summary: ModelSweepSummary) -> tuple[list[tuple[str, str]], int]:
    rows, more = [], 0
    for entry in summary.violations:
        if "more" in entry:
            more += int(entry["more"])
            continue
        where = ", ".join(box_text([(k, float(v[0]), float(v[1]))], digits=5) if isinstance(v, list) else
                          f"{k} = {fmt_float(float(v), 6)}" for k, v in entry.items() if k not in ("box", "detail"))
        if "box" in entry:
            where = f"box {entry['box']}: {where}"
        rows.append((where, str(entry.get("detail", ""))))
    return rows[:MAX_VIOLATION_ROWS], more + max(0, len(rows) - MAX_VIOLATION_ROWS)


#: the cross-check's words for a loop integrated in time, and for a discrete-time map iterated step by step
FLOW_WORDS: Final = {"done": "simulated", "runs": "trajectories", "run": "a trajectory",
                     "envelope": "V(0) exp(-rate t)", "norm": "|x(t)|"}
MAP_WORDS: Final = {"done": "iterated", "runs": "sequences of iterates", "run": "the iterates",
                    "envelope": "(1 - mu)^k V(0)", "norm": "|x_k|"}


def is_map_text(model_text: str) -> bool:
    """Whether a stored model text is a discrete-time map (``[model] time = "discrete"``; :mod:`tomllib` only)."""
    import tomllib

    try:
        model = tomllib.loads(model_text).get("model")
    except tomllib.TOMLDecodeError:
        return False
    return isinstance(model, dict) and model.get("time") == "discrete"


def model_store_context(ds: Any) -> dict[str, Any]:
    """Everything ``model_sweep.html.j2`` shows, as plain strings (the template escapes them). ``ds``
    is a model sweep store, loaded and checked by :func:`sweeps.schema.check_model_dataset`."""
    summary = summarize_dataset(ds)
    boxes = summary.mode == BOXES_MODE
    part = _box_part(ds, summary) if boxes else _point_part(ds, summary)
    cross = summary.cross_check
    model_text = str(ds.attrs.get("model_toml", ""))
    # a map's cross-check iterated it (sweeps.crosscheck._MapLoop): its figures in steps, not seconds
    words = MAP_WORDS if is_map_text(model_text) else FLOW_WORDS
    cross_rows = [
        ("certified " + ("boxes" if boxes else "points") + " cross-checked", f"{cross['checked']} of "
                                                                              f"{summary.counts['certified']}"),
        (f"parameter points {words['done']}", str(cross["parameter_points"])),
        (f"{words['runs']} {words['done']}", str(cross["trajectories"])),
        (f"largest rise of a certified V along {words['run']} (of V(0))",
         "—" if cross["worst_rise"] is None else fmt_float(cross["worst_rise"], 3)),
        (f"largest excess of V over {words['envelope']} (of V(0))",
         "—" if cross["worst_envelope"] is None else fmt_float(cross["worst_envelope"], 3)),
        (f"largest {words['norm']} / GES envelope",
         "—" if cross["worst_ges_ratio"] is None else fmt_float(cross["worst_ges_ratio"], 6)),
        (f"{words['runs']} not at the equilibrium by the horizon (a figure, not a violation)",
         str(cross["not_converged"])),
    ]
    if "worst_unsafe_margin" in cross and {"barrier", "reach_avoid"} & set(summary.classes):
        # (>= 0: a trajectory entered the unsafe set; a store written before these figures has none)
        margin = cross["worst_unsafe_margin"]
        cross_rows.append(("largest margin of the unsafe set reached (>= 0: inside; < 0: none entered)",
                           "—" if margin is None else fmt_float(margin, 3)))
    if "worst_reach_ratio" in cross and "reach_avoid" in summary.classes:
        ratio = cross["worst_reach_ratio"]
        cross_rows.append(("latest time to the goal / certified time bound",
                           "—" if ratio is None else fmt_float(ratio, 3)))
    for y, span in (cross.get("sim_worst") or {}).items():
        cross_rows.append((f"worst-case search: tail sup of |{y}|", _span(span)))
    for y, span in (cross.get("tightness") or {}).items():
        cross_rows.append((f"certified bound on |{y}| / worst found", _span(span)))
    violations, more = _violations(summary)
    sha_ok = hashlib.sha256(model_text.encode()).hexdigest() == str(ds.attrs.get("model_sha256"))
    what = "boxes" if boxes else "points"
    return {
        "kind": "model_sweep",
        "discrete": words is MAP_WORDS,
        "title": "lyapcheck model sweep report",
        "boxes": boxes,
        "what": what,
        "model_name": summary.model.get("name") or str(ds.attrs.get("model_file", "")),
        "model_file": str(ds.attrs.get("model_file", "")),
        "model_sha256": str(ds.attrs.get("model_sha256", "")),
        "model_sha_ok": sha_ok,
        "model_toml": model_text,
        "dims": list(summary.dims),
        "classes": list(summary.classes),
        "proved_share": summary.proved_share,
        "proved_percent": window_percent(summary.proved_share),
        "measure": ", ".join(f"{d}: {'log(hi/lo)' if s == 'log' else 'hi - lo'}" for d, s in summary.scales.items()),
        "shares": [(s, window_percent(summary.share[s]), fmt_float(summary.share[s], 4), summary.counts[s])
                   for s in LEAF_STATUSES],
        "not_computed": window_percent(summary.share["not_computed"]) if summary.share["not_computed"] > 1e-9 else "",
        "class_rows": [(c, window_percent(summary.share_by_class[c]), str(summary.counts_by_class[c]))
                       for c in summary.classes],
        "figure_rows": [(k, _span(v)) for k, v in summary.figures.items()],
        "meaning": MEANING,
        "cross_check": cross_rows,
        "violation_count": violation_count(summary),
        "violations": violations,
        "violations_more": more,
        **provenance(ds),
        "summary": summary,
        **part,
    }


__all__ = ["model_store_context"]
