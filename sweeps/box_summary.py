"""Figures of a box sweep, read back from its store (or from the same arrays in a Dataset).

The share of the parameter window each status covers is measured in the axes' own scale: a
``log`` axis by ``log(hi / lo)``, a ``linear`` one by ``hi - lo`` (the gains span decades; on a
log axis the window's decades count equally). Only leaves count (``split`` boxes are covered by
their halves), so the shares of ``certified``, ``not_certified`` and ``refuted`` sum to the share
of the window computed so far (1 once the first level is done).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, Mapping, Sequence

import numpy as np

from sweeps.schema import BOX_STATUS_CODES

#: soundness violations listed by name (the rest counted)
MAX_LISTED = 20


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


def _measure(values: np.ndarray, scale: str) -> np.ndarray:
    return np.log(values) if scale == "log" else values


def leaf_fractions(lo: Mapping[str, np.ndarray], hi: Mapping[str, np.ndarray], scales: Mapping[str, str],
                   window: Mapping[str, tuple[float, float]]) -> np.ndarray:
    """Each row's share of the window (product over the axes of its measured width)."""
    share = np.ones(len(next(iter(lo.values()))))
    for name, scale in scales.items():
        w_lo, w_hi = _measure(np.array(window[name], dtype=float), scale)
        share = share * (_measure(hi[name], scale) - _measure(lo[name], scale)) / (w_hi - w_lo)
    return share


def summarize_arrays(dims: Sequence[str], scales: Mapping[str, str], window: Mapping[str, tuple[float, float]],
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
    """:func:`summarize_arrays` of a :class:`~sweeps.box_store.BoxStore`."""
    spec = store.spec
    window = {a.name: (a.values[0], a.values[-1]) for a in spec.axes}
    scales = {a.name: ("log" if a.scale == "log" else "linear") for a in spec.axes}
    data = {v.name: store.read(v.name) for v in store.variables}
    return summarize_arrays(spec.dims, scales, window, data)


def violation_count(summary: BoxSummary) -> int:
    return sum(v.get("more", 1) for v in summary.violations)
