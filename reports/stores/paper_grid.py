"""The paper's point sweep (a grid of gains): region maps, ratio map, soundness violations, summary table.

Store schema (issue 5): an xarray Dataset (Zarr) with 1 to 3 dimensions named after swept
parameters (``alpha_d``, ``sigma0``, ``k_d``, ``delta_los``, ``d_max``; SI coordinates) and

* ``status_<class>`` int8: 0 not certified, 1 certified, 2 refuted, 3 inconclusive, -1 not computed;
* ``margin_<class>``, ``eps_bound_m``, ``sim_eps_sup_m``, ``ratio_certified_over_simulated`` floats;
* ``sim_diverged``, ``soundness_violation``, ``done`` booleans;
* attributes ``spec_toml`` (text), ``versions`` and ``paper_point`` (JSON text).

Missing optional variables are reported as missing, never guessed.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Final

import numpy as np

from lyapcheck.errors import InputFileError
from reports import figures
from reports.stores.common import json_attr, mpl, provenance, value_range
from reports.views import fmt_float

#: status codes of the store -> (name used by certificates, colour)
STATUS_CODES: Final = {1: "certified", 0: "not_certified", 2: "refuted", 3: "inconclusive", -1: "not_computed"}
#: how each swept parameter is shown: label and factor from SI
PARAMETERS: Final = {
    "alpha_d": ("alpha_d (1/s)", 1.0), "sigma0": ("sigma0", 1.0), "k_d": ("k_d (1/s)", 1.0),
    "delta_los": ("Delta_LOS (mm)", 1e3), "d_max": ("d* (mm/s)", 1e3),
}
MAX_VIOLATION_ROWS: Final = 50
#: classes that are arithmetic conditions: their codes 1/0 mean holds/fails
ARITHMETIC_CLASSES: Final = ("stabcond2",)


@dataclass
class ClassSummary:
    name: str
    counts: dict[str, int]
    margin_range: str
    at_paper: str


def _classes(ds: Any) -> list[str]:
    return [str(v)[len("status_"):] for v in ds.data_vars if str(v).startswith("status_")]


def _axes(ds: Any, dims: tuple[str, ...]) -> list[figures.Axis]:
    out = []
    for d in dims:
        label, factor = PARAMETERS.get(d, (mpl(d), 1.0))
        values = np.asarray(ds[d].values, dtype=float) * factor if d in ds.coords else np.arange(ds.sizes[d], dtype=float)
        positive = values.size > 1 and bool(np.all(values > 0))
        log = positive and float(values.max() / values.min()) >= 20.0
        out.append(figures.Axis(d, label, values, log))
    return out


def _paper(axes: list[figures.Axis], paper: Any) -> list[float] | None:
    if not isinstance(paper, dict):
        return None
    point = []
    for ax in axes:
        value = paper.get(ax.name)
        if not isinstance(value, (int, float)) or isinstance(value, bool):
            return None
        point.append(float(value) * PARAMETERS.get(ax.name, ("", 1.0))[1])
    return point


def _nearest(axes: list[figures.Axis], point: list[float] | None) -> tuple[int, ...] | None:
    if point is None:
        return None
    idx = []
    for ax, v in zip(axes, point):
        lo, hi = ax.values.min(), ax.values.max()
        if not (lo * (1 - 1e-9) <= v <= hi * (1 + 1e-9)):
            return None  # outside the swept range: no nearest point to speak of
        dist = np.abs(np.log(ax.values / v)) if ax.log else np.abs(ax.values - v)
        idx.append(int(np.argmin(dist)))
    return tuple(idx)


def _bool(ds: Any, name: str, dims: tuple[str, ...], shape: tuple[int, ...]) -> np.ndarray:
    if name not in ds:
        return np.zeros(shape, dtype=bool)
    return np.asarray(ds[name].transpose(*dims).values).astype(bool)


def _float(ds: Any, name: str, dims: tuple[str, ...], shape: tuple[int, ...]) -> np.ndarray:
    if name not in ds:
        return np.full(shape, np.nan)
    return np.asarray(ds[name].transpose(*dims).values, dtype=float)


def sweep_context(ds: Any) -> dict[str, Any]:
    """Everything the sweep template shows (plain strings; the template escapes them)."""
    classes = _classes(ds)
    if not classes:
        raise InputFileError("the sweep store has no 'status_<class>' variable: nothing to report")
    dims = tuple(str(d) for d in ds[f"status_{classes[0]}"].dims)
    if not 1 <= len(dims) <= 3:
        raise InputFileError(f"a sweep store must have 1 to 3 swept parameters; this one has {len(dims)}: {dims}")
    shape = tuple(int(ds.sizes[d]) for d in dims)
    axes = _axes(ds, dims)
    paper_raw, paper_text = json_attr(ds, "paper_point")
    paper = _paper(axes, paper_raw)
    nearest = _nearest(axes, paper)
    diverged = _bool(ds, "sim_diverged", dims, shape)
    violation = _bool(ds, "soundness_violation", dims, shape)
    done = _bool(ds, "done", dims, shape) if "done" in ds else np.ones(shape, dtype=bool)
    ratio = _float(ds, "ratio_certified_over_simulated", dims, shape)
    eps_bound = _float(ds, "eps_bound_m", dims, shape)
    sim_sup = _float(ds, "sim_eps_sup_m", dims, shape)

    legend = [(1, "certified", figures.STATUS_COLOURS["certified"]),
              (0, "not certified", figures.STATUS_COLOURS["not_certified"]),
              (2, "refuted", figures.STATUS_COLOURS["refuted"]),
              (3, "inconclusive", figures.STATUS_COLOURS["inconclusive"]),
              (-1, "not computed", figures.STATUS_COLOURS["not_computed"]),
              (99, "unknown code", "#f0a000")]
    marks = [(diverged, "unstable in simulation", "x"), (violation, "SOUNDNESS VIOLATION", "o")]
    maps, summaries = [], []
    for cls in classes:
        codes = np.asarray(ds[f"status_{cls}"].transpose(*dims).values).astype(int)
        codes = np.where(np.isin(codes, list(STATUS_CODES)), codes, 99)
        names = dict(STATUS_CODES)
        shown = legend
        if cls in ARITHMETIC_CLASSES:  # plain arithmetic: 1 holds, 0 fails (sweeps.schema)
            names.update({1: "holds", 0: "fails"})
            shown = [(1, "holds", figures.STATUS_COLOURS["certified"]), (0, "fails", figures.STATUS_COLOURS["refuted"])] \
                + legend[4:]
        present = [entry for entry in shown if np.any(codes == entry[0])] or shown[:1]
        svg = figures.category_map(codes, axes, title=mpl(f"{cls}: where a certificate exists"), legend=present,
                                   marks=marks, paper=paper)
        counts = {STATUS_CODES.get(c, "unknown"): int(np.sum(codes == c)) for c in (1, 0, 2, 3, -1, 99)}
        margin = _float(ds, f"margin_{cls}", dims, shape)
        at_paper = "—" if nearest is None else names.get(int(codes[nearest]), "unknown")
        summaries.append(ClassSummary(cls, counts, value_range(np.where(codes == 1, margin, np.nan)), at_paper))
        maps.append(figures.Figure(
            svg, f"{cls}: status at each grid point; crosses: the simulated loop diverged; red rings: soundness "
                 "violations; star: the paper's gains" + (" (filled on the slice that contains them)." if len(dims) == 3 else "."),
            f"map of the status of {cls} over the swept parameters"))
    ratio_fig = None
    if "ratio_certified_over_simulated" in ds:
        ratio_fig = figures.Figure(
            figures.value_map(ratio, axes, title="certified ultimate bound / simulated ultimate bound",
                              label="ratio", paper=paper, log_colour=True),
            "How conservative the certified bound is: the certified ultimate bound on |eps| divided by the largest "
            "simulated one (over the disturbance scenarios). Below 1 would be a soundness violation; grey: no "
            "certified bound.", "map of the ratio of certified to simulated ultimate bounds")
    violations = []
    for idx in np.argwhere(violation)[:MAX_VIOLATION_ROWS]:
        where = ", ".join(f"{ax.label} = {fmt_float(float(ax.values[i]), 6)}" for ax, i in zip(axes, idx))
        t = tuple(idx)
        violations.append((where, fmt_float(float(eps_bound[t])), fmt_float(float(sim_sup[t])), fmt_float(float(ratio[t]))))
    finite_ratio = ratio[np.isfinite(ratio)]
    overall = [
        ("grid points", str(int(np.prod(shape)))),
        ("swept parameters", ", ".join(f"{ax.label}: {ax.values.size} values, {value_range(ax.values)}" for ax in axes)),
        ("points done", f"{int(done.sum())} of {int(np.prod(shape))}"),
        ("diverged in simulation", str(int(diverged.sum()))),
        ("soundness violations", str(int(violation.sum()))),
        ("certified / simulated ratio", "—" if not finite_ratio.size else
         f"min {fmt_float(float(finite_ratio.min()), 4)}, median {fmt_float(float(np.median(finite_ratio)), 4)}, "
         f"max {fmt_float(float(finite_ratio.max()), 4)}"),
        ("certified ultimate bound (m)", value_range(eps_bound)),
        ("simulated ultimate bound (m)", value_range(sim_sup)),
    ]
    if nearest is not None:
        where = ", ".join(f"{ax.label} = {fmt_float(float(ax.values[i]), 4)}" for ax, i in zip(axes, nearest))
        overall.append(("nearest grid point to the paper's gains", where))
    return {
        "kind": "sweep",
        "title": "lyapcheck sweep report",
        "dims": [ax.label for ax in axes],
        "classes": summaries,
        "maps": maps,
        "ratio": ratio_fig,
        "violation_count": int(violation.sum()),
        "violations": violations,
        "violations_more": max(0, int(violation.sum()) - MAX_VIOLATION_ROWS),
        "overall": overall,
        "paper_text": paper_text,
        "paper_marked": paper is not None,
        **provenance(ds),
        "missing": [v for v in ("sim_diverged", "soundness_violation", "ratio_certified_over_simulated", "done",
                                "eps_bound_m", "sim_eps_sup_m") if v not in ds],
        "status_meaning": {"certified": "a certificate exists and passed its exact check",
                           "refuted": "proved exactly that none of this class exists",
                           "not_certified": "none found, nothing proved",
                           "inconclusive": "numerical trouble"},
    }
