"""Figures of a sweep of any target, read back from its store (or from the same arrays in a Dataset).

One summary per target and layout, on shared measures (:func:`leaf_fractions`, :func:`cell_fractions`)
and one count of soundness violations (:func:`violation_count`):

* **The paper's points** (:func:`summarize`). Per condition class: the fraction of the
  simulated-stable points (computed, ``sim_diverged`` false) where the class certifies
  (``stabcond2``: where it holds, which is not a certificate); the median of
  ``eps_bound_m / sim_eps_sup_m``; and every soundness violation with its coordinates.
* **Boxes, of the paper's model or of a model file** (:func:`summarize_boxes`,
  :func:`summarize_model_arrays`). The share of the parameter window each status covers is
  measured in the axes' own scale: a ``log`` axis by ``log(hi / lo)``, a ``linear`` (or listed)
  one by ``hi - lo``, the window being ``[first value, last value]`` of each axis (the gains span
  decades; on a log axis the window's decades count equally). Only leaves count (``done`` and not
  ``split``: a split box is covered by its halves), so the shares of ``certified``,
  ``not_certified`` and ``refuted`` sum to the share of the window computed so far. A certified
  leaf is a proved area: every parameter value in it is covered by one exactly checked certificate.
* **A model file's points** (:func:`summarize_model_arrays`). Each grid point stands for its cell,
  whose edges are the midpoints (in the axis's scale) between neighbouring values, clipped to the
  window; the shares are those of the cells. A certified point proves that point only: its cell's
  share is a sampled estimate, never a proof for the values between the points (the report says so).
  ``share_by_class`` is the share where each class certified, ``counts`` the leaves (or points) of
  each status, ``figures`` the range of each class's figures (:func:`sweeps.schema.class_figures`) over
  the certified ones, and the cross-check figures are the worst over the certified ones.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Final, Mapping, Sequence

import numpy as np

from sweeps.schema import (BOX_STATUS_CODES, BOXES_MODE, CLASSES, OUTPUT_FIGURES, POINTS_MODE, STATUS_CODES,
                           class_figures)
from sweeps.store import Store

#: soundness violations listed one by one (the rest counted)
MAX_LISTED: Final = 20
#: the statuses a leaf or a point can have, in the order they are reported
LEAF_STATUSES: Final = ("certified", "not_certified", "refuted")


def violation_count(summary: Any) -> int:
    """Soundness violations of a summary of any target: those listed, plus the ``more`` counted."""
    return sum(int(v.get("more", 1)) for v in summary.violations)


def _measure(values: np.ndarray, scale: str) -> np.ndarray:
    return np.log(values) if scale == "log" else np.asarray(values, dtype=np.float64)


# -- the paper's model, points --------------------------------------------------------------------
@dataclass
class Summary:
    dims: tuple[str, ...]
    points: int
    computed: int
    simulated_stable: int
    certified_fraction: dict[str, float]
    median_ratio: float
    violations: list[dict[str, Any]] = field(default_factory=list)

    def to_json(self) -> dict[str, Any]:
        return {"dims": list(self.dims), "points": self.points, "computed": self.computed,
                "simulated_stable": self.simulated_stable,
                "certified_fraction_of_simulated_stable": self.certified_fraction,
                "median_ratio_certified_over_simulated": None if math.isnan(self.median_ratio) else self.median_ratio,
                "soundness_violations": self.violations}


def summarize(store: Store, *, max_listed: int = MAX_LISTED) -> Summary:
    """Read the figures from ``store`` (only the variables needed, one array at a time)."""
    g = store.group
    done = np.asarray(g["done"][...], dtype=bool)
    stable = done & ~np.asarray(g["sim_diverged"][...], dtype=bool)
    n_stable = int(stable.sum())
    fractions: dict[str, float] = {}
    for cls in CLASSES:
        if cls not in store.spec.classes:
            continue
        status = np.asarray(g[f"status_{cls}"][...])
        code = STATUS_CODES["holds" if cls == "stabcond2" else "certified"]
        fractions[cls] = float(np.sum((status == code) & stable) / n_stable) if n_stable else math.nan
    ratio = np.asarray(g["ratio_certified_over_simulated"][...])[done]
    ratio = ratio[np.isfinite(ratio)]
    median = float(np.median(ratio)) if ratio.size else math.nan
    bad = np.argwhere(np.asarray(g["soundness_violation"][...], dtype=bool) & done)
    listed = []
    coords = [np.asarray(g[d][...]) for d in store.spec.dims]
    for idx in bad[:max_listed]:
        key = tuple(int(i) for i in idx)
        entry: dict[str, Any] = {d: float(c[i]) for d, c, i in zip(store.spec.dims, coords, key)}
        entry["eps_bound_m"] = float(g["eps_bound_m"][key])
        entry["sim_eps_sup_m"] = float(g["sim_eps_sup_m"][key])
        entry["sim_diverged"] = bool(g["sim_diverged"][key])
        listed.append(entry)
    summary = Summary(store.spec.dims, store.spec.n_points, int(done.sum()), n_stable, fractions, median, listed)
    summary.violations = listed
    if len(bad) > max_listed:
        summary.violations.append({"more": int(len(bad) - max_listed)})
    return summary


# -- the paper's model, boxes ---------------------------------------------------------------------
@dataclass
class BoxSummary:
    dims: tuple[str, ...]
    boxes: int
    leaves: int
    area_fraction: dict[str, float]
    certified_boxes: int
    cross_checked_points: int
    worst_envelope_ratio: float
    violations: list[dict[str, Any]] = field(default_factory=list)
    certified_by: dict[str, int] = field(default_factory=dict)
    #: with sos_bound: boxes bounded, range of their certified bounds and of bound / worst simulated
    bound: dict[str, Any] | None = None

    def to_json(self) -> dict[str, Any]:
        return {"mode": "boxes", "dims": list(self.dims), "boxes": self.boxes, "leaves": self.leaves,
                "area_fraction": self.area_fraction, "certified_boxes": self.certified_boxes,
                "certified_boxes_by_class": self.certified_by, **({"bound": self.bound} if self.bound else {}),
                "cross_checked_points": self.cross_checked_points,
                "worst_envelope_ratio": None if math.isnan(self.worst_envelope_ratio) else self.worst_envelope_ratio,
                "soundness_violations": self.violations}


def leaf_fractions(lo: Mapping[str, np.ndarray], hi: Mapping[str, np.ndarray], scales: Mapping[str, str],
                   window: Mapping[str, tuple[float, float]]) -> np.ndarray:
    """Each row's share of the window (product over the axes of its measured width)."""
    share = np.ones(len(next(iter(lo.values()))))
    for name, scale in scales.items():
        w_lo, w_hi = _measure(np.array(window[name], dtype=float), scale)
        share = share * (_measure(hi[name], scale) - _measure(lo[name], scale)) / (w_hi - w_lo)
    return share


def summarize_box_arrays(dims: Sequence[str], scales: Mapping[str, str], window: Mapping[str, tuple[float, float]],
                         data: Mapping[str, np.ndarray]) -> BoxSummary:
    """The summary from the store's arrays (``data[name]`` for every box variable)."""
    done = np.asarray(data["done"], bool)
    status = np.asarray(data["status"])
    leaf = done & (status != BOX_STATUS_CODES["split"])
    share = np.zeros(len(done))
    if leaf.any():
        share[leaf] = leaf_fractions({d: np.asarray(data[f"lo_{d}"])[leaf] for d in dims},
                                     {d: np.asarray(data[f"hi_{d}"])[leaf] for d in dims}, scales, window)
    fractions = {name: float(share[leaf & (status == code)].sum())
                 for name, code in BOX_STATUS_CODES.items() if name != "split"}
    certified = done & (status == BOX_STATUS_CODES["certified"])
    runs = int(np.asarray(data["cross_check_runs"])[certified].sum())
    ratios = np.asarray(data["cross_check_worst_ratio"])[certified]
    ratios = ratios[np.isfinite(ratios)]
    bad = np.flatnonzero(np.asarray(data["soundness_violation"], bool) & done)
    listed: list[dict[str, Any]] = []
    for row in bad[:MAX_LISTED]:
        entry: dict[str, Any] = {"box": int(row)}
        for d in dims:
            entry[d] = [float(data[f"lo_{d}"][row]), float(data[f"hi_{d}"][row])]
        entry["envelope_ratio"] = float(data["cross_check_worst_ratio"][row])
        listed.append(entry)
    if len(bad) > MAX_LISTED:
        listed.append({"more": int(len(bad) - MAX_LISTED)})
    by_class = {name[len("status_"):]: int(np.sum(done & (np.asarray(values) == BOX_STATUS_CODES["certified"])))
                for name, values in data.items() if name.startswith("status_")}
    bound = None
    if "eps_bound_m" in data:
        eps = np.asarray(data["eps_bound_m"])[done]
        tight = np.asarray(data["tightness_ratio"])[done]
        eps, tight = eps[np.isfinite(eps)], tight[np.isfinite(tight)]
        bound = {"boxes_bounded": int(eps.size),
                 "eps_bound_m_range": [float(eps.min()), float(eps.max())] if eps.size else None,
                 "tightness_ratio_range": [float(tight.min()), float(tight.max())] if tight.size else None}
    return BoxSummary(tuple(dims), int(done.sum()), int(leaf.sum()), fractions, int(certified.sum()), runs,
                      float(ratios.max()) if ratios.size else math.nan, listed, by_class, bound)


def summarize_boxes(store: Any) -> BoxSummary:
    """:func:`summarize_box_arrays` of a :class:`~sweeps.store.BoxStore`."""
    spec = store.spec
    window = {a.name: (a.values[0], a.values[-1]) for a in spec.axes}
    scales = {a.name: ("log" if a.scale == "log" else "linear") for a in spec.axes}
    data = {v.name: store.read(v.name) for v in store.variables}
    return summarize_box_arrays(spec.dims, scales, window, data)


# -- a model file, points or boxes ----------------------------------------------------------------
@dataclass
class ModelSweepSummary:
    """The figures of a model sweep (module docstring); :meth:`to_json` is what ``--json`` prints."""

    mode: str
    model: dict[str, str]
    dims: tuple[str, ...]
    scales: dict[str, str]
    classes: tuple[str, ...]
    total: int
    computed: int
    leaves: int
    share: dict[str, float]
    share_by_class: dict[str, float]
    counts: dict[str, int]
    counts_by_class: dict[str, int]
    figures: dict[str, list[float] | None]
    cross_check: dict[str, Any]
    violations: list[dict[str, Any]] = field(default_factory=list)

    @property
    def proved_share(self) -> float:
        return self.share["certified"]

    def to_json(self) -> dict[str, Any]:
        return {"mode": self.mode, "model": self.model, "dims": list(self.dims), "scales": self.scales,
                "classes": list(self.classes), ("boxes" if self.mode == BOXES_MODE else "points"): self.total,
                "computed": self.computed, "leaves": self.leaves, "proved_share": self.proved_share,
                "share_of_window": self.share, "share_by_class": self.share_by_class, "counts": self.counts,
                "counts_by_class": self.counts_by_class, "figures": self.figures, "cross_check": self.cross_check,
                "soundness_violations": self.violations}


def cell_fractions(coords: Sequence[np.ndarray], scales: Sequence[str]) -> np.ndarray:
    """Each grid point's share of the window: the product over the axes of its cell's measured width
    (edges at the midpoints between neighbours, in the axis's scale; an axis of one value counts 1)."""
    factors = []
    for values, scale in zip(coords, scales):
        v = _measure(np.asarray(values, dtype=np.float64), scale)
        if v.size == 1:
            factors.append(np.ones(1))
            continue
        edges = np.concatenate([[v[0]], (v[1:] + v[:-1]) / 2, [v[-1]]])
        factors.append(np.diff(edges) / (v[-1] - v[0]))
    share = factors[0]
    for f in factors[1:]:
        share = np.multiply.outer(share, f)
    return np.asarray(share, dtype=np.float64)


def _range(values: np.ndarray) -> list[float] | None:
    finite = values[np.isfinite(values)]
    return [float(finite.min()), float(finite.max())] if finite.size else None


def _worst(values: np.ndarray) -> float | None:
    finite = values[np.isfinite(values)]
    return float(finite.max()) if finite.size else None


def summarize_model_arrays(mode: str, dims: Sequence[str], scales: Mapping[str, str], classes: Sequence[str],
                           outputs: Sequence[str], data: Mapping[str, np.ndarray], *,
                           window: Mapping[str, tuple[float, float]] | None = None,
                           coords: Mapping[str, np.ndarray] | None = None, model: Mapping[str, str] | None = None,
                           total: int | None = None) -> ModelSweepSummary:
    """The summary from a store's arrays: ``data[name]`` for every variable (flat per box, or over
    the grid), with the window (boxes) or the coordinates (points)."""
    done = np.asarray(data["done"], bool).ravel()
    status = np.asarray(data["status"]).ravel()
    leaf = done & (status != BOX_STATUS_CODES["split"])
    share_of = np.zeros(done.size)
    if mode == BOXES_MODE:
        assert window is not None
        if leaf.any():
            share_of[leaf] = leaf_fractions({d: np.asarray(data[f"lo_{d}"]).ravel()[leaf] for d in dims},
                                            {d: np.asarray(data[f"hi_{d}"]).ravel()[leaf] for d in dims},
                                            {d: scales[d] for d in dims}, window)
    else:
        assert coords is not None
        share_of = cell_fractions([coords[d] for d in dims], [scales[d] for d in dims]).ravel()
    share = {s: float(share_of[leaf & (status == BOX_STATUS_CODES[s])].sum()) for s in LEAF_STATUSES}
    share["not_computed"] = max(0.0, 1.0 - sum(share.values()))
    certified = leaf & (status == BOX_STATUS_CODES["certified"])
    by_class: dict[str, float] = {}
    counts_by_class: dict[str, int] = {}
    for c in classes:
        mine = leaf & (np.asarray(data[f"status_{c}"]).ravel() == STATUS_CODES["certified"])
        by_class[c] = float(share_of[mine].sum())
        counts_by_class[c] = int(mine.sum())
    figures: dict[str, list[float] | None] = {}
    for c in classes:
        for suffix, _, _ in class_figures(c, (model or {}).get("time") == "discrete"):
            figures[f"{c}_{suffix}"] = _range(np.asarray(data[f"{c}_{suffix}"], float).ravel()[certified])
        if c in OUTPUT_FIGURES:
            for y in outputs:
                figures[f"{c}_{y}"] = _range(np.asarray(data[f"{c}_{y}"], float).ravel()[certified])
    cross: dict[str, Any] = {
        "checked": int(np.sum(certified & (np.asarray(data["cross_check_points"]).ravel() > 0))),
        "parameter_points": int(np.asarray(data["cross_check_points"]).ravel()[certified].sum()),
        "trajectories": int(np.asarray(data["cross_check_trajectories"]).ravel()[certified].sum()),
        "worst_rise": _worst(np.asarray(data["cross_check_worst_rise"], float).ravel()[certified]),
        "worst_envelope": _worst(np.asarray(data["cross_check_worst_envelope"], float).ravel()[certified]),
        "worst_ges_ratio": _worst(np.asarray(data["cross_check_ges_ratio"], float).ravel()[certified]),
        "not_converged": int(np.asarray(data["cross_check_not_converged"]).ravel()[certified].sum()),
    }
    for key, name in (("worst_unsafe_margin", "cross_check_unsafe_margin"),
                      ("worst_reach_ratio", "cross_check_reach_ratio")):
        if name in data:  # (a store written before these figures has none)
            cross[key] = _worst(np.asarray(data[name], float).ravel()[certified])
    if "sos_bound" in classes:
        cross["sim_worst"] = {y: _range(np.asarray(data[f"sim_worst_{y}"], float).ravel()[certified]) for y in outputs}
        cross["tightness"] = {y: _range(np.asarray(data[f"tightness_{y}"], float).ravel()[certified]) for y in outputs}
    return ModelSweepSummary(
        mode=mode, model=dict(model or {}), dims=tuple(dims), scales={d: scales[d] for d in dims},
        classes=tuple(classes), total=int(total if total is not None else done.size), computed=int(done.sum()),
        leaves=int(leaf.sum()), share=share, share_by_class=by_class,
        counts={s: int(np.sum(leaf & (status == BOX_STATUS_CODES[s]))) for s in LEAF_STATUSES},
        counts_by_class=counts_by_class, figures=figures, cross_check=cross,
        violations=_violations(mode, dims, data, done, coords))


def _violations(mode: str, dims: Sequence[str], data: Mapping[str, np.ndarray], done: np.ndarray,
                coords: Mapping[str, np.ndarray] | None) -> list[dict[str, Any]]:
    flag = np.asarray(data["soundness_violation"], bool)
    detail = np.asarray(data["violation_detail"])
    listed: list[dict[str, Any]] = []
    if mode == BOXES_MODE:
        bad = np.flatnonzero(flag.ravel() & done)
        for row in bad[:MAX_LISTED]:
            entry: dict[str, Any] = {"box": int(row)}
            entry.update({d: [float(data[f"lo_{d}"][row]), float(data[f"hi_{d}"][row])] for d in dims})
            entry["detail"] = str(detail[row])
            listed.append(entry)
        count = len(bad)
    else:
        assert coords is not None
        idx = np.argwhere(flag & np.asarray(data["done"], bool))
        for key in idx[:MAX_LISTED]:
            entry = {d: float(coords[d][int(i)]) for d, i in zip(dims, key)}
            entry["detail"] = str(detail[tuple(int(i) for i in key)])
            listed.append(entry)
        count = len(idx)
    if count > MAX_LISTED:
        listed.append({"more": int(count - MAX_LISTED)})
    return listed


def summarize_model_store(store: Any) -> ModelSweepSummary:
    """:func:`summarize_model_arrays` of an open :class:`~sweeps.store.ModelPointStore` or
    :class:`~sweeps.store.ModelBoxStore`."""
    spec = store.spec
    scales = {a.name: a.measure for a in spec.axes}
    data = {v.name: store.read(v.name) for v in store.variables}
    model = {"name": spec.model.name, "file": spec.model_file, "sha256": spec.model_sha256,
             "time": str(getattr(spec.model, "time", "continuous"))}
    if spec.mode == "boxes":
        window = {a.name: (a.values[0], a.values[-1]) for a in spec.axes}
        return summarize_model_arrays(BOXES_MODE, spec.dims, scales, spec.classes, spec.outputs, data, window=window,
                                model=model, total=int(np.sum(data["done"])))
    coords = {a.name: np.asarray(a.values) for a in spec.axes}
    return summarize_model_arrays(POINTS_MODE, spec.dims, scales, spec.classes, spec.outputs, data, coords=coords,
                            model=model, total=spec.n_points)


def summarize_dataset(ds: Any) -> ModelSweepSummary:
    """The summary of a store loaded as an xarray Dataset (the report), from its attributes alone."""
    from sweeps.schema import is_map_store, json_list, model_box_variables, point_variables

    dims, classes, outputs = (json_list(ds, k) for k in ("dims", "classes", "outputs"))
    raw = json.loads(str(ds.attrs.get("axis_scales", "{}")))
    scales = {d: ("log" if raw.get(d) == "log" else "linear") for d in dims}
    model = {"name": str(ds.attrs.get("model_name", "")), "file": str(ds.attrs.get("model_file", "")),
             "sha256": str(ds.attrs.get("model_sha256", "")), "time": "discrete" if is_map_store(ds) else "continuous"}
    if ds.attrs["mode"] == BOXES_MODE:
        data = {v.name: np.asarray(ds[v.name].values)
                for v in model_box_variables(dims, classes, outputs, model["time"] == "discrete")}
        window = stored_window(ds, dims, data)
        return summarize_model_arrays(BOXES_MODE, dims, scales, classes, outputs, data, window=window, model=model,
                                total=int(np.sum(data["done"])))
    data = {v.name: np.asarray(ds[v.name].transpose(*dims).values)
            for v in point_variables(classes, outputs, model["time"] == "discrete")}
    coords = {d: np.asarray(ds.coords[d].values) for d in dims}
    return summarize_model_arrays(POINTS_MODE, dims, scales, classes, outputs, data, coords=coords, model=model)


def stored_window(ds: Any, dims: Sequence[str], data: Mapping[str, np.ndarray]) -> dict[str, tuple[float, float]]:
    """A box store's window: from its stored spec (and model text), else the extent of its first-level
    boxes (a store whose spec this lyapcheck no longer reads)."""
    from lyapcheck.errors import LyapcheckError
    from sweeps.spec import parse_model_spec

    try:
        spec = parse_model_spec(str(ds.attrs["spec_toml"]), source="the stored spec",
                                model_text=str(ds.attrs["model_toml"]), check=False)
        if spec.dims == tuple(dims):
            return {a.name: (a.values[0], a.values[-1]) for a in spec.axes}
    except (LyapcheckError, KeyError):
        pass
    first = np.asarray(data["done"], bool) & (np.asarray(data["level"]) == 0)
    return {d: (float(np.min(data[f"lo_{d}"][first])), float(np.max(data[f"hi_{d}"][first])))
            if first.any() else (math.nan, math.nan) for d in dims}


def open_summary(path: str | Path, spec: Any) -> ModelSweepSummary:
    """The summary of the store at ``path`` made from ``spec``."""
    from sweeps.store import open_model_store

    return summarize_model_store(open_model_store(path, spec))


__all__ = ["Summary", "summarize", "BoxSummary", "summarize_box_arrays", "summarize_boxes", "leaf_fractions",
           "ModelSweepSummary", "summarize_model_arrays", "summarize_model_store", "summarize_dataset",
           "cell_fractions", "stored_window", "open_summary", "violation_count", "MAX_LISTED", "LEAF_STATUSES"]
