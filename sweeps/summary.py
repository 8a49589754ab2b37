"""Figures of a finished sweep, read back from its store.

Per condition class: the fraction of the simulated-stable points (computed, ``sim_diverged``
false) where the class certifies (``stabcond2``: where it holds, which is not a certificate);
the median of ``eps_bound_m / sim_eps_sup_m``; and every soundness violation with its
coordinates.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from sweeps.schema import CLASSES, STATUS_CODES
from sweeps.store import Store


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


def summarize(store: Store, *, max_listed: int = 20) -> Summary:
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


def violation_count(summary: Summary) -> int:
    extra = sum(v.get("more", 0) for v in summary.violations)
    return sum(1 for v in summary.violations if "more" not in v) + int(extra)
