"""One unit of work of a model sweep (runs in a worker): certify points or boxes, cross-check them.

A worker receives :attr:`sweeps.model_spec.ModelSweepSpec.worker_text` (the spec and the model's
text, never a path) and the points' coordinates or the boxes' exact edges, and returns one array
per variable of :mod:`sweeps.model_schema` (and the seconds each item took, which the store does
not keep: a wall time would make a resumed store differ from an uninterrupted one).

* A point: :func:`lyapcheck.models.certify.certify_model` on the model with the point's exact
  parameters (``Fraction`` of the stored float).
* A box: first the linearization, exactly, at the box's corners (milliseconds): an unstable corner
  proves that no stability class can certify the box (its status is ``refuted``, and the stability
  classes' too), so only ``sos_bound`` still runs there; otherwise ``certify_model`` over the box.

A point or box is ``certified`` when any class certified; ``refuted`` when the equilibrium is proved
unstable there (the linearization, exactly) and nothing certified; else ``not_certified``. Every
certified one is cross-checked by simulation (:mod:`sweeps.model_crosscheck`) and its certificate
document is returned as JSON, without the solver logs (their wall times would make the store's
bytes depend on the machine's load; ``verify`` does not read them).
"""

from __future__ import annotations

import json
import time
from fractions import Fraction
from typing import Any, Sequence

import numpy as np

from sweeps.evaluate import UNIT_LOCK
from sweeps.model_schema import FIGURES, point_variables
from sweeps.model_spec import ModelSweepSpec, cached_model_spec, window_box
from sweeps.schema import BOX_STATUS_CODES, STATUS_CODES

#: the classes whose certificate proves a stability property (an unstable point refutes them)
STABILITY_CLASSES = ("linearization", "quadratic", "sos_gas", "roa")


def _empty(spec: ModelSweepSpec, n: int) -> dict[str, np.ndarray]:
    out: dict[str, np.ndarray] = {}
    for var in point_variables(spec.classes, spec.outputs):
        if var.dtype.kind == "T":
            out[var.name] = np.full(n, "", dtype=object)
        else:
            out[var.name] = np.full(n, var.fill, dtype=var.dtype)
    out["seconds_certify"] = np.zeros(n)
    out["seconds_cross_check"] = np.zeros(n)
    return out


def certificate_json(document: dict[str, Any]) -> str:
    """The document as stored: its conditions without solver logs. Keys stay in the document's own
    order (deterministic: the builder's), never sorted: a box lists the model's parameters in the
    model's order, which ``verify`` checks."""
    doc = dict(document)
    doc["conditions"] = {name: {k: v for k, v in cond.items() if k != "solver"}
                         for name, cond in document["conditions"].items()}
    return json.dumps(doc, separators=(",", ":"))


def _record(spec: ModelSweepSpec, result: Any, out: dict[str, np.ndarray], j: int,
            refuted: dict[str, str] | None = None) -> str:
    """Statuses, figures and note of one point or box; returns its status name."""
    statuses = {name: r.status for name, r in result.results.items()}
    if refuted is not None:
        statuses.update({c: "refuted" for c in spec.classes if c in STABILITY_CLASSES})
    for c in spec.classes:
        if c in statuses:
            out[f"status_{c}"][j] = STATUS_CODES.get(statuses[c], STATUS_CODES["inconclusive"])
    certified = [c for c in spec.classes if statuses.get(c) == "certified"]
    for c in certified:
        numbers = result.results[c].numbers
        for suffix, key, _ in FIGURES.get(c, ()):
            if numbers.get(key) is not None:
                out[f"{c}_{suffix}"][j] = float(numbers[key])
        if c == "sos_bound":
            for y, value in (numbers.get("bounds") or {}).items():
                out[f"sos_bound_{y}"][j] = float(value)
    if certified:
        status = "certified"
        out["note"][j] = "certified by " + ", ".join(
            f"{c} ({result.results[c].proves()}{', d = 0' if result.results[c].disturbances == 'zero' else ''})"
            for c in certified)
    elif refuted is not None or statuses.get("linearization") == "refuted":
        status = "refuted"
        out["note"][j] = (refuted or {}).get("note") or result.results["linearization"].summary
    else:
        status = "not_certified"
        out["note"][j] = "no class certified: " + ", ".join(f"{c} {statuses.get(c, 'not computed')}"
                                                             for c in spec.classes)
    out["status"][j] = BOX_STATUS_CODES[status]
    return status


def _cross(spec: ModelSweepSpec, document: dict[str, Any], points: Sequence[dict[str, Fraction]], seed: Sequence[int],
           out: dict[str, np.ndarray], j: int) -> None:
    from sweeps.model_crosscheck import cross_check

    found = cross_check(spec.model, document, points, starts=spec.simulation.starts, seed=seed,
                        worst_case=spec.simulation.worst_case)
    out["cross_check_points"][j] = found.points
    out["cross_check_trajectories"][j] = found.trajectories
    out["cross_check_worst_rise"][j] = found.worst_rise
    out["cross_check_worst_envelope"][j] = found.worst_envelope
    out["cross_check_ges_ratio"][j] = found.ges_ratio
    out["cross_check_not_converged"][j] = found.not_converged
    for y, sup in found.sim_worst.items():
        if f"sim_worst_{y}" in out:
            out[f"sim_worst_{y}"][j] = sup
            bound = out[f"sos_bound_{y}"][j]
            out[f"tightness_{y}"][j] = bound / sup if sup > 0 else np.inf
    out["soundness_violation"][j] = found.violation
    out["violation_detail"][j] = "; ".join(found.violations)


def evaluate_model_points(worker_text: str, coords: np.ndarray) -> dict[str, np.ndarray]:
    """Certify and cross-check each grid point (rows of ``coords``, SI, in the spec's axis order)."""
    from lyapcheck.models.certificate import build_document
    from lyapcheck.models.certify import certify_model

    spec = cached_model_spec(worker_text)
    coords = np.atleast_2d(np.asarray(coords, dtype=np.float64))
    out = _empty(spec, len(coords))
    for j, row in enumerate(coords):
        begin = time.perf_counter()
        with UNIT_LOCK:  # two threads of one Dask worker take turns (as sweeps.evaluate does)
            result = certify_model(spec.model_at(row), classes=spec.classes)
        middle = time.perf_counter()
        if _record(spec, result, out, j) == "certified":
            document = build_document(result)
            out["certificate"][j] = certificate_json(document)
            index = int(np.ravel_multi_index(tuple(int(np.searchsorted(a.values, v)) for a, v in zip(spec.axes, row)),
                                             spec.shape))
            _cross(spec, document, [spec.parameters_at(row)], (spec.simulation.seed, index), out, j)
        out["seconds_certify"][j] = middle - begin
        out["seconds_cross_check"][j] = time.perf_counter() - middle
        out["done"][j] = True
    return out


def unstable_corners(spec: ModelSweepSpec, box: Any) -> tuple[int, dict[str, str] | None]:
    """How many corners of ``box`` have an unstable equilibrium (the linearization refuted, exactly),
    and the first as ``{"note": ...}`` (None when none); ``(-1, None)`` when no stability class is asked."""
    from lyapcheck.models.certify import certify_model
    from lyapcheck.models.modelfile import with_parameters

    if not any(c in STABILITY_CLASSES for c in spec.classes):
        return -1, None
    count, first = 0, None
    for corner in box.corners():
        lin = certify_model(with_parameters(spec.model, corner), classes=("linearization",)).results["linearization"]
        if lin.status == "refuted":
            count += 1
            if first is None:
                where = ", ".join(f"{k} = {float(v):.6g}" for k, v in corner.items())
                first = {"note": f"unstable at the corner {where}: {lin.summary}"}
    return count, first


def box_seed(seed: int, box_id: int) -> int:
    """The seed of a box's random parameter points: a function of ``(seed, box id)`` alone."""
    return int(np.random.SeedSequence([seed, box_id]).generate_state(1, dtype=np.uint64)[0])


def evaluate_model_boxes(worker_text: str, boxes: Sequence[tuple[int, dict[str, list[str]]]]) -> dict[str, np.ndarray]:
    """Certify and cross-check each ``(id, {name: [lo, hi]})`` box (exact edges as ``"p/q"`` text)."""
    from lyapcheck.models.certificate import build_document
    from lyapcheck.models.certify import certify_model

    spec = cached_model_spec(worker_text)
    assert spec.boxes is not None
    out = _empty(spec, len(boxes))
    out["unstable_corners"] = np.full(len(boxes), -1, dtype=np.int8)
    for j, (box_id, edges) in enumerate(boxes):
        begin = time.perf_counter()
        box = window_box(spec, {name: (Fraction(lo), Fraction(hi)) for name, (lo, hi) in edges.items()})
        with UNIT_LOCK:
            corners, unstable = unstable_corners(spec, box)
            classes = spec.classes if unstable is None else tuple(c for c in spec.classes if c == "sos_bound")
            result = certify_model(spec.model, classes=classes, box=box) if classes else None
        middle = time.perf_counter()
        if result is None:  # only stability classes, refuted at a corner
            for c in spec.classes:
                out[f"status_{c}"][j] = STATUS_CODES["refuted"]
            out["status"][j] = BOX_STATUS_CODES["refuted"]
            out["note"][j] = (unstable or {}).get("note", "")
        elif _record(spec, result, out, j, unstable) == "certified":
            document = build_document(result)
            out["certificate"][j] = certificate_json(document)
            points = box.points(spec.boxes.cross_check_points, box_seed(spec.boxes.seed, box_id))
            if points:
                _cross(spec, document, points, (spec.simulation.seed, box_id), out, j)
        out["unstable_corners"][j] = corners
        out["seconds_certify"][j] = middle - begin
        out["seconds_cross_check"][j] = time.perf_counter() - middle
        out["done"][j] = True
    return out


__all__ = ["evaluate_model_points", "evaluate_model_boxes", "certificate_json", "box_seed", "unstable_corners",
           "STABILITY_CLASSES"]
