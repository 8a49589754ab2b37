"""The report of a box sweep (``mode = "boxes"``): the map of boxes and the certified share of the window.

A box store (:class:`sweeps.store.BoxStore`) has one row per box of an adaptive refinement tree. A
``certified`` box carries one exactly checked certificate of global exponential stability that
holds at every gain set inside it, so the certified share of the window is a proved area, not a
fraction of sampled points. The page draws the leaves of the tree (rows that are ``done`` and not
``split``: a split box is covered by its halves), coloured by status, states each status's share
of the window as :func:`sweeps.summary.summarize_box_arrays` measures it (the same numbers as
``lyapcheck sweep`` prints), the range of the certificates' ``k`` and decay rate, and the
cross-check of certified boxes by simulation.

Figures follow :mod:`reports.figures` (matplotlib's object interface, :func:`reports.figures.to_svg`).
Each drawn leaf is an SVG group with the id ``box-<row>-<status>``, so a reader (or a test) can
tie every rectangle of the picture to its row of the store.
"""

from __future__ import annotations

import math
from typing import Any, Final, Mapping, Sequence

import numpy as np

from lyapcheck.errors import InputFileError, LyapcheckError
from lyapcheck.models.language.parameter_box import box_text
from reports import figures
from reports.stores.common import (
    LEAF_NAMES, LEAF_STATUSES, BoxAxis, Leaves, box_map, json_attr, mpl, provenance, value_range, window_percent,
)
from reports.stores.paper_grid import PARAMETERS
from reports.views import fmt_float
from sweeps.summary import BoxSummary, summarize_box_arrays as summarize_arrays, violation_count
from sweeps.schema import BOX_DIM, BOX_STATUS_CODES, box_variables

#: what each status means, in words (the page's legend)
STATUS_MEANING: Final = {
    "certified": "one exactly checked certificate proves GES at every gain set of the box",
    "not_certified": "no common certificate was found before the box reached the minimum width or the sweep its "
                     "box budget; this proves nothing either way",
    "refuted": "proved exactly that a gain set of the box is not GES (lyapcheck.paper.boxes.quadratic explains why no such "
               "obstruction exists for these dynamics)",
}
#: what a class's own ``refuted`` means over a box: that class's certificate cannot exist, not that GES fails
CLASS_REFUTED: Final = {"sector_ges": "no quadratic V common to the box's matrix polytope (exact, at a corner)",
                        "prop41_ges": "eq. stabCond has no solution at a corner of the box (exact Gamma_22 bound)"}
#: a partial store leaves part of the window uncovered; below this the rest is rounding
COVERED_TOL: Final = 1e-9
#: leaves listed row by row when there is no figure (three swept parameters)
MAX_LEAF_ROWS: Final = 200
# ----------------------------------------------------------------------------------------------
# reading the store
# ----------------------------------------------------------------------------------------------
def _dims(ds: Any) -> tuple[str, ...]:
    """The swept parameters (``check_box_dataset`` has validated the attribute already)."""
    dims, _ = json_attr(ds, "dims")
    return tuple(str(d) for d in dims)


def _classes(ds: Any) -> tuple[str, ...]:
    """The box classes run, cheapest first (``check_box_dataset`` has validated the attribute)."""
    classes, _ = json_attr(ds, "classes")
    return tuple(str(c) for c in classes) if isinstance(classes, list) else ()


def _class_rows(classes: Sequence[str], summary: BoxSummary, data: Mapping[str, np.ndarray],
                done: np.ndarray) -> list[tuple[str, str, str, str]]:
    """(class, boxes it certified, boxes where its own certificate is refuted, what that refutation means).

    The classes run cheapest first and the first certificate decides a box, so a later class
    is not run (-1) where an earlier one certified.
    """
    rows = []
    for c in classes:
        refuted = int(np.sum(done & (data[f"status_{c}"] == BOX_STATUS_CODES["refuted"])))
        rows.append((c, str(summary.certified_by.get(c, 0)), str(refuted),
                     CLASS_REFUTED.get(c, "its certificate cannot exist over the box") if refuted else ""))
    return rows


def _spec_window(ds: Any, dims: tuple[str, ...]) -> tuple[dict[str, tuple[float, float]], dict[str, str]] | None:
    """Window and scales from the stored spec, exactly as :func:`sweeps.summary.summarize_boxes` takes them.

    None when the stored spec does not parse or does not describe these parameters (an edited
    store, or one written by another version): the caller then falls back on the store itself.
    """
    from sweeps.spec import parse_spec

    text = ds.attrs.get("spec_toml")
    if not isinstance(text, str):
        return None
    try:
        spec = parse_spec(text, source="the stored spec")
    except LyapcheckError:
        return None
    if spec.mode != "boxes" or tuple(spec.dims) != dims:
        return None
    window = {a.name: (float(a.values[0]), float(a.values[-1])) for a in spec.axes}
    scales = {a.name: ("log" if a.scale == "log" else "linear") for a in spec.axes}
    return window, scales


def _store_window(ds: Any, dims: tuple[str, ...], data: Mapping[str, np.ndarray]
                  ) -> tuple[dict[str, tuple[float, float]], dict[str, str]]:
    """Window and scales without a usable spec: the level-0 boxes tile the window (the axes' grid)."""
    raw, _ = json_attr(ds, "axis_scales")
    if not isinstance(raw, dict) or any(d not in raw for d in dims):
        raise InputFileError("the box store has neither a readable spec nor an 'axis_scales' attribute naming "
                             f"{', '.join(dims)}: its window cannot be measured")
    first = np.asarray(data["done"], bool) & (np.asarray(data["level"]) == 0)
    if not first.any():
        raise InputFileError("the box store has no computed box of the first level: its window is unknown")
    window = {d: (float(np.min(data[f"lo_{d}"][first])), float(np.max(data[f"hi_{d}"][first]))) for d in dims}
    return window, {d: ("log" if raw[d] == "log" else "linear") for d in dims}


def _check_edges(axes: Sequence[BoxAxis], data: Mapping[str, np.ndarray], leaf: np.ndarray) -> None:
    """Every leaf a non-empty box inside the measurable range: an edited store fails here, in one line."""
    for ax in axes:
        lo, hi = np.asarray(data[f"lo_{ax.name}"])[leaf], np.asarray(data[f"hi_{ax.name}"])[leaf]
        bad = ~(np.isfinite(lo) & np.isfinite(hi) & (lo < hi))
        if ax.log:
            bad |= ~(lo > 0)
        w_lo, w_hi = ax.window
        if not (math.isfinite(w_lo) and math.isfinite(w_hi) and w_lo < w_hi and (w_lo > 0 or not ax.log)):
            raise InputFileError(f"the box store's window in {ax.name} is [{w_lo:g}, {w_hi:g}]: not a {ax.scale} range")
        if bad.any():
            row = int(np.flatnonzero(leaf)[np.argmax(bad)])
            raise InputFileError(f"box {row} of the store has edges [{float(data[f'lo_{ax.name}'][row]):g}, "
                                 f"{float(data[f'hi_{ax.name}'][row]):g}] in {ax.name}: not a {ax.scale} interval")


def _axes(dims: tuple[str, ...], window: Mapping[str, tuple[float, float]], scales: Mapping[str, str]) -> list[BoxAxis]:
    out = []
    for d in dims:
        label, factor = PARAMETERS.get(d, (mpl(d), 1.0))
        out.append(BoxAxis(d, label, factor, scales[d], window[d]))
    return out


def _leaves(axes: Sequence[BoxAxis], data: Mapping[str, np.ndarray], leaf: np.ndarray) -> Leaves:
    rows = np.flatnonzero(leaf)
    lo = np.column_stack([np.asarray(data[f"lo_{a.name}"], float)[rows] * a.factor for a in axes])
    hi = np.column_stack([np.asarray(data[f"hi_{a.name}"], float)[rows] * a.factor for a in axes])
    return Leaves(rows, np.asarray(data["status"]).astype(int)[rows], lo, hi)


def _paper(axes: Sequence[BoxAxis], paper: Any) -> list[float] | None:
    """The paper's gains in display units, or None when the attribute does not name every swept parameter."""
    if not isinstance(paper, dict):
        return None
    point = []
    for ax in axes:
        value = paper.get(ax.name)
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
            return None
        if ax.log and value <= 0:
            return None  # cannot be placed on a log axis
        point.append(float(value) * ax.factor)
    return point


# ----------------------------------------------------------------------------------------------
# the figure
# ----------------------------------------------------------------------------------------------
# ----------------------------------------------------------------------------------------------
# the page's text
# ----------------------------------------------------------------------------------------------
def _box_text(axes: Sequence[BoxAxis], lo: Sequence[float], hi: Sequence[float]) -> str:
    """``alpha_d (1/s) in [150, 375], ...`` (display units)."""
    return box_text(((a.label, float(l), float(h)) for a, l, h in zip(axes, lo, hi)), digits=5)


def _at_paper(axes: Sequence[BoxAxis], leaves: Leaves, paper: Sequence[float] | None,
              data: Mapping[str, np.ndarray]) -> tuple[str, str]:
    """(status, detail) of the leaves that contain the paper's gains (a closed box: an edge counts)."""
    if paper is None:
        return "—", "the store's paper_point does not name every swept parameter"
    p = np.asarray(paper)
    inside = np.all((leaves.lo <= p * (1 + 1e-12)) & (p <= leaves.hi * (1 + 1e-12)), axis=1)
    if not inside.any():
        return "—", "outside the boxes computed (outside the window, or in a part not computed)"
    codes = leaves.codes[inside]
    rows = leaves.rows[inside]
    if np.any(codes == BOX_STATUS_CODES["certified"]):
        row = int(rows[np.argmax(codes == BOX_STATUS_CODES["certified"])])
        return "certified", (f"in certified box {row}: k = {fmt_float(float(data['k'][row]), 4)}, decay rate "
                             f"{fmt_float(float(data['decay_rate_per_s'][row]), 4)} 1/s")
    # on a shared edge, name the more informative box: a refuted one before one where nothing was found
    pick = int(np.argmax(codes == BOX_STATUS_CODES["refuted"])) if np.any(codes == BOX_STATUS_CODES["refuted"]) else 0
    name = LEAF_NAMES.get(int(codes[pick]), "not_certified")
    return name, f"in box {int(rows[pick])} ({name.replace('_', ' ')})"


def _violation_rows(axes: Sequence[BoxAxis], summary: BoxSummary) -> tuple[list[tuple[str, str, str]], int]:
    """(box, where, envelope ratio) of the violations the summary lists, and how many more it counts."""
    rows, more = [], 0
    for entry in summary.violations:
        if "more" in entry:
            more += int(entry["more"])
            continue
        lo = [entry[a.name][0] * a.factor for a in axes]
        hi = [entry[a.name][1] * a.factor for a in axes]
        rows.append((str(entry["box"]), _box_text(axes, lo, hi), fmt_float(float(entry["envelope_ratio"]), 4)))
    return rows, more


def _leaf_rows(axes: Sequence[BoxAxis], leaves: Leaves,
               data: Mapping[str, np.ndarray]) -> list[tuple[str, str, str, str, str]]:
    """The table that stands in for the map with three parameters (first MAX_LEAF_ROWS leaves)."""
    out = []
    for row, code, lo, hi in list(zip(leaves.rows, leaves.codes, leaves.lo, leaves.hi))[:MAX_LEAF_ROWS]:
        certified = int(code) == BOX_STATUS_CODES["certified"]
        out.append((str(int(row)), LEAF_NAMES.get(int(code), "not_certified"), _box_text(axes, lo, hi),
                    fmt_float(float(data["k"][row]), 4) if certified else "—",
                    fmt_float(float(data["decay_rate_per_s"][row]), 4) if certified else "—"))
    return out


def _figure(axes: Sequence[BoxAxis], leaves: Leaves, paper: Sequence[float] | None, partial: bool,
            at_paper: str) -> figures.Figure | None:
    if len(axes) > 2:
        return None
    scales = ", ".join(f"{a.label} {'logarithmic' if a.log else 'linear'}" for a in axes)
    outside = paper is not None and any(not a.window[0] * a.factor <= v <= a.window[1] * a.factor
                                        for a, v in zip(axes, paper))
    caption = (f"Every leaf of the refinement tree ({leaves.rows.size} boxes), coloured by status; the black "
               f"outline is the swept window; axes: {scales}."
               + (" Hatched: part of the window not computed yet (the store is partial)." if partial else "")
               + (" Star: the paper's gains" + (f" ({at_paper.replace('_', ' ')} box)." if at_paper != "—" else
                                                 ", outside the swept window (the view is widened to show them)."
                                                 if outside else ".")
                  if paper is not None else ""))
    return figures.Figure(box_map(axes, leaves, paper, partial=partial, title="GES certified for whole boxes of gains"), caption,
                          "map of the boxes of gain space coloured by certification status",
                          {"leaf_rows": [int(r) for r in leaves.rows], "paper": paper, "partial": partial})


def box_context(ds: Any) -> dict[str, Any]:
    """Everything the box template (``boxes.html.j2``) shows, as plain strings (the template escapes them).

    ``ds`` is a box store loaded as an xarray Dataset and checked by
    :func:`sweeps.schema.check_box_dataset`. An edited store whose window or leaves cannot be
    measured raises :class:`~lyapcheck.errors.InputFileError` (one line).
    """
    dims, classes = _dims(ds), _classes(ds)
    data = {v.name: np.asarray(ds[v.name].values) for v in box_variables(dims, classes)}
    window, scales = _spec_window(ds, dims) or _store_window(ds, dims, data)
    axes = _axes(dims, window, scales)
    done = data["done"].astype(bool)
    leaf = done & (data["status"] != BOX_STATUS_CODES["split"])
    _check_edges(axes, data, leaf)
    summary = summarize_arrays(dims, scales, window, data)
    leaves = _leaves(axes, data, leaf)
    covered = sum(summary.area_fraction.values())
    partial = covered < 1 - COVERED_TOL
    paper_raw, paper_text = json_attr(ds, "paper_point")
    paper = _paper(axes, paper_raw)
    at_paper, at_paper_detail = _at_paper(axes, leaves, paper, data)
    certified = done & (data["status"] == BOX_STATUS_CODES["certified"])
    violations, violations_more = _violation_rows(axes, summary)
    worst = summary.worst_envelope_ratio
    share = summary.area_fraction["certified"]
    shares = [(s, window_percent(summary.area_fraction[s]), fmt_float(summary.area_fraction[s], 4),
               int(np.sum(leaves.codes == BOX_STATUS_CODES[s]))) for s in LEAF_STATUSES]
    return {
        "kind": "boxes",
        "title": "lyapcheck box sweep report",
        "dims": [a.label for a in axes],
        "certified_share": share,
        "certified_percent": window_percent(share),
        "certified_fraction": fmt_float(share, 4),
        "shares": shares,
        "not_computed": window_percent(max(0.0, 1 - covered)) if partial else "",
        "measure": ", ".join(f"{a.label}: {'log(hi/lo)' if a.log else 'hi - lo'}" for a in axes),
        "overall": [
            ("swept window", "; ".join(f"{a.label} from {fmt_float(a.window[0] * a.factor, 5)} to "
                                       f"{fmt_float(a.window[1] * a.factor, 5)} ({a.scale})" for a in axes)),
            ("condition classes, cheapest first", ", ".join(classes) or "—"),
            ("boxes computed", f"{summary.boxes} (of {int(ds.sizes[BOX_DIM])} rows in the store)"),
            ("leaves (boxes not split further)", str(summary.leaves)),
            ("deepest refinement level", str(int(data["level"][done].max())) if done.any() else "—"),
            ("certified boxes", str(summary.certified_boxes)),
            ("k over certified boxes", value_range(np.where(certified, data["k"], np.nan))),
            ("decay rate over certified boxes", value_range(np.where(certified, data["decay_rate_per_s"], np.nan), " 1/s")),
        ],
        "at_paper": at_paper,
        "at_paper_detail": at_paper_detail,
        "box_figure": _figure(axes, leaves, paper, partial, at_paper),
        "leaf_rows": _leaf_rows(axes, leaves, data) if len(axes) > 2 else [],
        "leaf_rows_more": max(0, leaves.rows.size - MAX_LEAF_ROWS) if len(axes) > 2 else 0,
        "cross_check": [
            ("certified boxes cross-checked", f"{int(np.sum(certified & (data['cross_check_runs'] > 0)))} of "
                                              f"{summary.certified_boxes}"),
            ("random gain sets simulated", str(summary.cross_checked_points)),
            ("worst |x(t)| / (k |x0| exp(-rate t))", "—" if math.isnan(worst) else fmt_float(worst, 4)),
            *_bound_rows(summary),
        ],
        "violation_count": violation_count(summary),
        "violations": violations,
        "violations_more": violations_more,
        "status_meaning": STATUS_MEANING,
        "class_rows": _class_rows(classes, summary, data, done),
        "paper_text": paper_text,
        **provenance(ds),
        "summary": summary,
    }


def _bound_rows(summary: Any) -> list[tuple[str, str]]:
    """With ``sos_bound`` in the sweep: the certified bounds over boxes and their tightness against
    the worst-case disturbance search at the boxes' random gain sets."""
    bound = summary.bound
    if not bound:
        return []
    rows = [("boxes with a certified limsup |eps| (sos_bound)", str(bound["boxes_bounded"]))]
    if bound["eps_bound_m_range"]:
        lo, hi = bound["eps_bound_m_range"]
        rows.append(("certified limsup |eps| over those boxes", f"{fmt_float(lo * 1e3, 4)} to {fmt_float(hi * 1e3, 4)} mm"))
    if bound["tightness_ratio_range"]:
        lo, hi = bound["tightness_ratio_range"]
        rows.append(("certified bound / worst simulated (tightness)", f"{fmt_float(lo, 4)} to {fmt_float(hi, 4)}"))
    return rows
