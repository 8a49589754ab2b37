"""One unit of sweep work, of every target: certify a batch of points or boxes, cross-check them by simulation.

Every unit runs in a worker process (local pool or Dask), receives the spec as text (never a
path; parsed once per process) and the points' coordinates or the boxes' exact edges, and returns
one array per variable of the target's store (:mod:`sweeps.schema`); :mod:`sweeps.run` writes it.
One unit at a time per process (:data:`UNIT_LOCK`).

The paper's model, points (:func:`evaluate_unit`). The certificate programs are the compiled
programs of :mod:`lyapcheck.paper.conditions.compiled` (read once per process, then solved by Clarabel
with new parameter values, no cvxpy); ``sector_ges`` goes through :mod:`sweeps.fast_sector`. The
simulation is one batched call of :func:`lyapcheck.paper.simulation.runner.simulate` per scenario for
the whole unit; its rows are independent of the batch they sit in, so a point's result does
not depend on how points were grouped (which is what makes a resumed sweep identical to an
uninterrupted one).

Scenarios (all with ``|d_perp| <= d*`` except ``nominal``, which has no disturbance):

``nominal``      no disturbance, started at ``[simulation] initial_position``: the divergence probe
                 (the simulator's own rule: failed, or the tail sup of ``|eps|`` exceeds
                 ``max(|eps(0)|, Delta_LOS)``);
``constant``     ``d* `` across the path, pointing like gravity for a horizontal path;
``weight``       the swimmer's weight mapped through ``D`` with the swimmer's axis along ``u``
                 (eq:tmp3, :class:`~lyapcheck.paper.simulation.disturbances.Weight`), scaled so that its
                 a-priori bound ``|d| <= W max(1/a1, 1/a2)`` equals ``d*``: the direction
                 dependence is the weight's, the size is the certificate's hypothesis;
``adversarial``  pushes ``V = x^T P x`` up as hard as ``|d_perp| <= d*`` allows, with ``P`` the last
                 ellipsoid stage of ``ultimate_bound``, else the ``sector_ges`` certificate, else
                 ``P = I`` (which pushes ``|eps|`` itself up); started one boundary-layer width off
                 the path (on it, the push is zero and the loop sits at its equilibrium).

The three disturbance scenarios start on the path, where every invariant set of the
certificates contains the state, so the certified bound holds over the whole tail window.

The paper's model, boxes (:func:`evaluate_boxes`): the box classes of
:mod:`lyapcheck.paper.boxes.classes`, cheapest first until one certifies with a GES envelope, whose
random points are simulated against it (:func:`lyapcheck.paper.boxes.cross_check.cross_check`).

A model file, points or boxes (:func:`evaluate_model_points`, :func:`evaluate_model_boxes`): the
classes of :data:`lyapcheck.models.classes.registry.CLASSES` the spec asks for, and the seconds each item
took (which the store does not keep: a wall time would make a resumed store differ from an
uninterrupted one).

* A point: :func:`lyapcheck.models.surfaces.certify.certify_model` on the model with the point's exact
  parameters (``Fraction`` of the stored float); for a loop with functions, on the model text read
  again with them (:meth:`sweeps.spec.ModelSweepSpec.model_at`); either cross-checked by
  :func:`sweeps.crosscheck.cross_check_point`. The spec's ``candidate`` (the user's V) is passed as
  ``certify --candidate`` passes it, at every point and over every box.
* A box: first the linearization, exactly, at the box's corners (milliseconds): an unstable corner
  proves that no stability class can certify the box (its status is ``refuted``, and the stability
  classes' too), so only ``sos_bound`` still runs there; otherwise ``certify_model`` over the box. A
  certified box of a polynomial discrete-time map (the classes of
  :data:`lyapcheck.models.classes.discrete_lyapunov.BOX_CLASSES`) is cross-checked by iterating the map at
  each corner of the box, then at its random points.
  A box of a loop with functions: ``certify_model`` over the box on the model read at its centre
  (what ``lyapcheck certify FILE --box`` runs), its corners checked only where the linearization over
  the box is refuted (whether to split it), cross-checked at random parameter points (a map with functions:
  its true map iterated at the box's corners too); either by :func:`sweeps.crosscheck.cross_check_box`.

A point or box is ``certified`` when any class certified; ``refuted`` when nothing certified and the
equilibrium is proved unstable there (the linearization, exactly) or a safety class (``barrier``,
``reach_avoid``: :data:`MODEL_SAFETY_CLASSES`) is refuted there (an unsafe trajectory proved at a value of it, named
in the note); else ``not_certified``. Every
certified one is cross-checked by simulation (:mod:`sweeps.crosscheck`) and its certificate
document is returned as JSON, without the solver logs (their wall times would make the store's
bytes depend on the machine's load; ``verify`` does not read them). A class's figures are stored
from the per-class tables of :mod:`sweeps.schema`, so a class registered in ``lyapcheck.models``
is swept without a change here.
"""

from __future__ import annotations

import json
import math
import threading
import time
from dataclasses import dataclass
from fractions import Fraction
from functools import lru_cache
from typing import Any, Callable, Final, Mapping, Sequence

import numpy as np
import numpy.typing as npt

from lyapcheck.models.classes import registry as model_classes
from lyapcheck.results import ConditionResult
from lyapcheck.paper.params import Problem
from lyapcheck.paper.boxes.box import ParameterBox
from sweeps.schema import (
    BOUND_CLASSES, BOX_STATUS_CODES, DISTURBANCE_SCENARIOS, MARGIN_SOURCE, OUTPUT_FIGURES, STATUS_CODES,
    VARIABLES, class_figures, point_variables, status_code,
)
from sweeps.crosscheck import CrossCheck
from sweeps.soundness import BOUND_REL_TOL, WORST_CASE_SCREENING_ONLY, violations
from sweeps.spec import ModelSweepSpec, SweepSpec, cached_model_spec, cached_spec, window_box

FloatArray = npt.NDArray[np.float64]
Result = dict[str, np.ndarray]

#: one unit at a time per process: the ``ges`` class still solves a cached cvxpy program, which
#: holds parameter values between "set" and "solve", so two threads of one Dask worker must not
#: interleave on it (the compiled programs are stateless)
UNIT_LOCK = threading.Lock()


def empty_result(n: int) -> Result:
    """Arrays of fill values for ``n`` points (every variable of the schema)."""
    return {v.name: np.full(n, v.fill, dtype=v.dtype) for v in VARIABLES}


def certify_point(problem: Problem, classes: tuple[str, ...]) -> dict[str, ConditionResult]:
    """The requested condition classes at one point, on the derived dynamics.

    Everything but ``sector_ges`` goes through :func:`lyapcheck.paper.certification.run_conditions` (which
    runs only the requested classes); ``sector_ges`` goes through the direct Clarabel path of
    :mod:`sweeps.fast_sector`, decided by the same exact check.
    """
    from lyapcheck.paper.certification import build_system, run_conditions
    from sweeps import fast_sector

    others = tuple(c for c in classes if c != "sector_ges")
    results = run_conditions(problem, "derived", others) if others else {}
    if "sector_ges" in classes:
        results["sector_ges"] = fast_sector.certify(build_system(problem, "derived"))
    return results


def _margin(cls: str, result: ConditionResult) -> float:
    key = MARGIN_SOURCE[cls]
    value = result.numbers.get(key) if key is not None else None
    if value is None:
        return math.nan
    return 1.0 - float(value) if cls == "stabcond2" else float(value)


def certified_bound(results: Mapping[str, ConditionResult]) -> float:
    """The tightest certified ultimate bound on ``|eps|`` (NaN if none): every class of
    :data:`BOUND_CLASSES` that is certified proves its bound, so the smallest one holds."""
    bounds = [float(results[c].numbers["eps_bound_m"]) for c in BOUND_CLASSES
              if c in results and results[c].status == "certified"]
    return min(bounds) if bounds else math.nan


def adversary_matrix(results: Mapping[str, ConditionResult]) -> FloatArray | None:
    """The quadratic ``V`` the adversarial disturbance pushes (see the module docstring)."""
    from lyapcheck import exact

    ub = results.get("ultimate_bound")
    if ub is not None and ub.status == "certified" and ub.certificate.get("stages"):
        return np.array(exact.to_float(exact.from_json(ub.certificate["stages"][-1]["P"])))
    sg = results.get("sector_ges")
    if sg is not None and sg.status == "certified":
        return np.array(exact.to_float(exact.from_json(sg.certificate["P"])))
    return None


def _usable(P: FloatArray | None) -> bool:
    """Symmetric positive definite in floating point (what the Adversarial model accepts)."""
    if P is None or not np.all(np.isfinite(P)):
        return False
    P = (P + P.T) / 2
    return bool(np.linalg.eigvalsh(P)[0] > 0)


@lru_cache(maxsize=4)
def _weight_constants(spec_text: str) -> tuple[float, float]:
    """Drag constants ``a1, a2`` of the swimmer (eq:tmp3) for the 'weight' scenario, per spec.

    Only their ratio matters once the weight is scaled to ``d*``; without ``[swimmer] xi_par``
    the scale ``xi_par = 1 N s/m^2`` is used (the ratio comes from ``e11`` and the geometry).
    """
    from lyapcheck.paper.simulation.scenarios import weight_disturbance

    problem = cached_spec(spec_text).base
    xi_par = None if problem.swimmer.xi_par is not None else 1.0
    w = weight_disturbance(problem, xi_par=xi_par)
    return float(w.a1[0]), float(w.a2[0])


def simulate_points(spec: SweepSpec, coords: FloatArray, adversary: list[FloatArray | None],
                    storage: list[dict[str, Any] | None] | None = None) -> dict[str, Any]:
    """Tail sup of ``|eps|``, integrator status and divergence, per scenario, for every point.

    ``storage``: per point, the ``sos_bound`` certificate (for the worst-case search's
    storage-gradient family), or None.
    """
    from lyapcheck.paper.simulation.disturbances import (ADVERSARIAL_LAYER_FRACTION, Adversarial, Constant, NoDisturbance,
                                                   Stacked, Weight)
    from lyapcheck.integrator import STATUS_OK
    from lyapcheck.paper.simulation.model import LoopParams
    from lyapcheck.paper.simulation.runner import simulate

    n = coords.shape[0]
    sim = spec.simulation
    base = spec.base
    columns = {name: coords[:, i] for i, name in enumerate(spec.dims)}
    gains = {k: v for k, v in columns.items() if k != "d_max"}
    params = LoopParams.from_problem(base, controller="ilos", n=n, **gains)
    d_max = columns.get("d_max", np.full(n, float(base.disturbance_bound())))
    theta = float(base.theta_r)
    across = np.array([-math.sin(theta), math.cos(theta)])  # e_perp (eq:ehatThetarPerp)
    origin = np.zeros((n, 2))
    out: dict[str, Any] = {}

    # every simulated scenario in one batch: the integrator's cost is mostly per loop iteration
    # (numpy calls), and a batch runs as many iterations as its slowest row needs, so the
    # scenarios in one batch cost about what the slowest of them costs alone. Rows are
    # independent (own step sizes; tests/test_simulation_integrator.py), so every figure is the
    # one a separate run gives, bit for bit (tests/test_sweeps_end_to_end.py)
    batch: list[tuple[str, Any, FloatArray]] = []
    for name in sim.scenarios:
        if name == "nominal":
            batch.append((name, NoDisturbance(), np.broadcast_to(np.asarray(sim.initial_position, dtype=np.float64),
                                                                 (n, 2))))
        elif name == "constant":
            batch.append((name, Constant(-d_max[:, None] * across[None, :]), origin))
        elif name == "weight":
            a1, a2 = _weight_constants(spec.text)
            scale = max(1.0 / a1, 1.0 / a2)
            batch.append((name, Weight(d_max / scale, np.full(n, a1), np.full(n, a2), np.full(n, theta)), origin))
        elif name == "adversarial":
            P = np.stack([a if a is not None and _usable(a) else np.eye(2) for a in adversary])
            P = (P + np.swapaxes(P, 1, 2)) / 2
            layer = ADVERSARIAL_LAYER_FRACTION * params.delta_los
            batch.append((name, Adversarial(d_max, P, layer, np.full(n, theta)), layer[:, None] * across[None, :]))
    if batch:
        k = len(batch)
        res = simulate(LoopParams.concat([params] * k), p0=np.concatenate([p0 for _, _, p0 in batch]),
                       disturbance=Stacked.concat([(d, n) for _, d, _ in batch]),
                       horizon=sim.horizon, tail=sim.tail, rtol=sim.rtol)
        m = res.measurements
        failed_all = (m.status != STATUS_OK) | ~np.isfinite(m.sup_abs_eps_tail_m)
        diverged_all = np.asarray(m.diverged) | failed_all
        for j, (name, _, _) in enumerate(batch):
            rows = slice(j * n, (j + 1) * n)
            failed = failed_all[rows]
            out[name] = {"sup": np.where(failed, np.nan, m.sup_abs_eps_tail_m[rows]), "failed": failed,
                         "diverged": diverged_all[rows]}
    if "worst_case" in sim.scenarios:
        out["worst_case"] = _worst_case(spec, coords, storage or [None] * n)
    return out


def _worst_case(spec: SweepSpec, coords: FloatArray, storage: list[dict[str, Any] | None]) -> dict[str, Any]:
    """The worst-case disturbance search at every point, started on the path like the other
    disturbance scenarios (inside every invariant set of the certificates)."""
    from lyapcheck.errors import InvalidParameter
    from lyapcheck.paper.simulation.scenarios import Scenario
    from lyapcheck.paper.simulation.worst_case import search_worst_case

    sim = spec.simulation
    sups, failed = np.full(len(coords), np.nan), np.zeros(len(coords), dtype=bool)
    for i, point in enumerate(coords):
        scenario = Scenario(name="sweep-worst-case", problem=spec.problem_at(point), p0=(0.0, 0.0),
                            horizon=sim.horizon, tail=sim.tail, rtol=sim.rtol)
        try:
            found = search_worst_case(scenario, budget_s=WORST_CASE_SCREENING_ONLY, storage=storage[i])
        except InvalidParameter:  # an unusable storage certificate: search without that family
            found = search_worst_case(scenario, budget_s=WORST_CASE_SCREENING_ONLY)
        sups[i] = found.sup_abs_eps_tail_m
        failed[i] = not math.isfinite(found.sup_abs_eps_tail_m)
    return {"sup": np.where(failed, np.nan, sups), "failed": failed, "diverged": failed}


def evaluate(spec: SweepSpec, coords: FloatArray) -> Result:
    """Every variable of the schema for the points ``coords`` (shape ``(n, len(spec.dims))``)."""
    coords = np.atleast_2d(np.asarray(coords, dtype=np.float64))
    n = coords.shape[0]
    out = empty_result(n)
    eps_bound = np.full(n, np.nan)
    adversary: list[FloatArray | None] = []
    storage: list[dict[str, Any] | None] = []
    for i in range(n):
        results = certify_point(spec.problem_at(coords[i]), spec.classes)
        for cls, res in results.items():
            out[f"status_{cls}"][i] = status_code(res.status)
            out[f"margin_{cls}"][i] = _margin(cls, res)
        eps_bound[i] = certified_bound(results)
        adversary.append(adversary_matrix(results))
        bound = results.get("sos_bound")
        storage.append(bound.certificate if bound is not None and bound.status == "certified" else None)
    out["eps_bound_m"] = eps_bound

    sims = simulate_points(spec, coords, adversary, storage)
    sups = [sims[s]["sup"] for s in DISTURBANCE_SCENARIOS if s in sims]
    for name, r in sims.items():
        out[f"sim_eps_sup_m_{name}"] = r["sup"]
    if sups:
        with np.errstate(invalid="ignore"):
            out["sim_eps_sup_m"] = np.fmax.reduce(np.stack(sups), axis=0)
    diverged = np.zeros(n, dtype=bool)
    for name, r in sims.items():
        diverged |= r["diverged"] if name == "nominal" else r["failed"]
    out["sim_diverged"] = diverged
    sim_sup = out["sim_eps_sup_m"]
    with np.errstate(invalid="ignore", divide="ignore"):
        out["ratio_certified_over_simulated"] = np.where(sim_sup > 0, eps_bound / sim_sup, np.nan)
    statuses = {c: out[f"status_{c}"] for c in spec.classes}
    out["soundness_violation"] = violations(eps_bound, sups, diverged, statuses)
    out["done"] = np.ones(n, dtype=bool)
    return out


def evaluate_unit(spec_text: str, coords: FloatArray) -> Result:
    """Worker entry point (picklable arguments only): parse the spec once per process, evaluate."""
    # one unit at a time per process (Dask may run several threads in one worker): see UNIT_LOCK
    with UNIT_LOCK:
        return evaluate(cached_spec(spec_text), coords)


#: signature of a unit evaluator (tests and the memory benchmark substitute a cheap one)
Evaluator = Callable[[str, FloatArray], Result]


# -- the paper's model, boxes ---------------------------------------------------------------------
def evaluate_boxes(spec_text: str, boxes: Sequence[tuple[int, dict[str, list[str]]]]) -> dict[str, np.ndarray]:
    """One unit of work (runs in a worker): certify and cross-check each ``(id, box)``.

    Returns per box: ``status`` code, ``status_<class>``, ``k``, ``decay_rate_per_s`` (of the
    certifying class), ``cross_check_runs``, ``cross_check_worst_ratio`` and ``soundness_violation``. A box's random points are drawn
    from ``(seed, id)``, so its result does not depend on the unit it was grouped in.
    """
    from lyapcheck.paper.boxes.classes import certify_box
    from lyapcheck.paper.boxes.cross_check import cross_check
    from lyapcheck.tolerances import ENVELOPE_REL_TOL

    spec = cached_spec(spec_text)
    assert spec.boxes is not None
    n = len(boxes)
    out = {"status": np.zeros(n, np.int8), "k": np.full(n, np.nan), "decay_rate_per_s": np.full(n, np.nan),
           "cross_check_runs": np.zeros(n, np.int16), "cross_check_worst_ratio": np.full(n, np.nan),
           "soundness_violation": np.zeros(n, bool),
           **{f"status_{c}": np.full(n, -1, np.int8) for c in spec.classes}}
    ges_classes = [c for c in spec.classes if c != "sos_bound"]
    if "sos_bound" in spec.classes:
        out.update({"eps_bound_m": np.full(n, np.nan), "sim_worst_eps_m": np.full(n, np.nan),
                    "tightness_ratio": np.full(n, np.nan)})
    for j, (box_id, data) in enumerate(boxes):
        box = ParameterBox.from_json(data)
        result: dict[str, Any] = {}
        envelope: dict[str, Any] | None = None
        for cls in ges_classes:  # cheapest first; the first certificate decides the box, and the
            # next classes run only while no certificate has given an envelope k, rate to
            # cross-check (eq. stabCond's, prop41_ges, gives none)
            with UNIT_LOCK:  # two threads of one Dask worker take turns
                here = certify_box(spec.base, box, cls=cls)
            out[f"status_{cls}"][j] = BOX_STATUS_CODES[here["status"]]
            if here["status"] == "certified":
                result = result if result.get("status") == "certified" else here
                if "k" in here:
                    envelope = here
                    break
            elif result.get("status") != "certified":
                result = here
        bound = _box_bound(spec, box, box_id, out, j) if "sos_bound" in spec.classes else None
        if not ges_classes:  # a bound-only sweep refines on the bound
            result = bound or {}
        # a class's refutation is of that class's certificate, not of GES: the box stays undecided
        status = "certified" if result.get("status") == "certified" else "not_certified"
        out["status"][j] = BOX_STATUS_CODES[status]
        if status != "certified" or envelope is None:
            continue
        out["k"][j], out["decay_rate_per_s"][j] = envelope["k"], envelope["decay_rate_per_s"]
        result = envelope
        runs, worst = cross_check(spec.base, box, result, spec.boxes.cross_check_points, (spec.boxes.seed, box_id))
        out["cross_check_runs"][j], out["cross_check_worst_ratio"][j] = runs, worst
        out["soundness_violation"][j] |= runs > 0 and not worst <= 1 + ENVELOPE_REL_TOL
    return out


def _box_bound(spec: SweepSpec, box: ParameterBox, box_id: int, out: dict[str, np.ndarray], j: int) -> dict[str, Any]:
    """``sos_bound`` over the box, and the worst-case disturbance search at its random points.

    The search is its deterministic screening round only (a vanishing time budget: no
    refinement round fits), so a box's figures do not depend on the machine's speed.
    """
    from lyapcheck.paper.boxes.classes import certify_box
    from lyapcheck.paper.boxes.box import sample_points
    from lyapcheck.paper.simulation.worst_case import search_worst_case

    assert spec.boxes is not None
    with UNIT_LOCK:
        result = certify_box(spec.base, box, cls="sos_bound")
    out["status_sos_bound"][j] = BOX_STATUS_CODES.get(result["status"], BOX_STATUS_CODES["not_certified"])
    if result["status"] != "certified":
        return result
    bound = float(result["eps_bound_m"])
    out["eps_bound_m"][j] = bound
    worst = -math.inf
    for point in sample_points(box, spec.boxes.cross_check_points, (spec.boxes.seed, box_id, 1)):
        found = search_worst_case(spec.base.with_gains(**point), budget_s=WORST_CASE_SCREENING_ONLY)
        worst = max(worst, found.sup_abs_eps_tail_m)
    if math.isfinite(worst):
        out["sim_worst_eps_m"][j] = worst
        out["tightness_ratio"][j] = bound / worst if worst > 0 else math.inf
        out["soundness_violation"][j] |= worst > bound * (1 + BOUND_REL_TOL)
    return result


# -- a model file, points or boxes ----------------------------------------------------------------
#: the classes whose certificate proves a stability property (an unstable point refutes them), as
#: :data:`lyapcheck.models.classes.registry.CLASSES` declares them
MODEL_STABILITY_CLASSES: Final = model_classes.STABILITY
#: the classes whose ``refuted`` is a proved unsafe trajectory (:data:`lyapcheck.models.classes.registry.SAFETY`):
#: a point or box where one is refuted (and nothing certified) is ``refuted``, and a box is not split for it
MODEL_SAFETY_CLASSES: Final = model_classes.SAFETY


def _model_empty(spec: ModelSweepSpec, n: int) -> dict[str, np.ndarray]:
    out: dict[str, np.ndarray] = {}
    for var in point_variables(spec.classes, spec.outputs, spec.discrete):
        if var.dtype.kind == "T":
            out[var.name] = np.full(n, "", dtype=object)
        else:
            out[var.name] = np.full(n, var.fill, dtype=var.dtype)
    out["seconds_certify"] = np.zeros(n)
    out["seconds_cross_check"] = np.zeros(n)
    return out


#: keys of a condition that hold solver logs or wall times: left out of a stored document (they would
#: make the store's bytes depend on the machine's load; ``verify`` does not read them). ``proof_seconds``:
#: the ball-arithmetic proof of ``roa`` on a loop with functions
UNSTORED_KEYS: Final = ("solver", "proof_seconds")


def certificate_json(document: dict[str, Any]) -> str:
    """The document as stored: its conditions without solver logs and wall times. Keys stay in the
    document's own order (deterministic: the builder's), never sorted: a box lists the model's
    parameters in the model's order, which ``verify`` checks."""
    doc = dict(document)
    doc["conditions"] = {name: {k: v for k, v in cond.items() if k not in UNSTORED_KEYS}
                         for name, cond in document["conditions"].items()}
    return json.dumps(doc, separators=(",", ":"))


def _model_record(spec: ModelSweepSpec, result: Any, out: dict[str, np.ndarray], j: int,
                  refuted: dict[str, str] | None = None) -> str:
    """Statuses, figures and note of one point or box; returns its status name."""
    statuses = {name: r.status for name, r in result.results.items()}
    if refuted is not None:
        statuses.update({c: "refuted" for c in spec.classes if c in MODEL_STABILITY_CLASSES})
    for c in spec.classes:
        if c in statuses:
            out[f"status_{c}"][j] = STATUS_CODES.get(statuses[c], STATUS_CODES["inconclusive"])
    certified = [c for c in spec.classes if statuses.get(c) == "certified"]
    # a safety class refuted is an unsafe trajectory proved at a value of the point or box: its claim for every
    # value is false there, as an unstable corner's is for the stability classes (the value is in its summary)
    unsafe = [c for c in spec.classes if c in MODEL_SAFETY_CLASSES and statuses.get(c) == "refuted"
              and c in result.results]
    for c in certified:
        numbers = result.results[c].numbers
        for suffix, key, _ in class_figures(c, spec.discrete):
            if numbers.get(key) is not None:
                out[f"{c}_{suffix}"][j] = float(numbers[key])
        if c in OUTPUT_FIGURES:
            for y, value in (numbers.get(OUTPUT_FIGURES[c][0]) or {}).items():
                out[f"{c}_{y}"][j] = float(value)
    if certified:
        status = "certified"
        out["note"][j] = "certified by " + ", ".join(
            f"{c} ({result.results[c].proves()}{', d = 0' if result.results[c].disturbances == 'zero' else ''})"
            for c in certified)
    elif refuted is not None or statuses.get("linearization") == "refuted" or unsafe:
        status = "refuted"
        notes = [(refuted or {}).get("note") or result.results["linearization"].summary] \
            if refuted is not None or statuses.get("linearization") == "refuted" else []
        out["note"][j] = "; ".join(notes + [f"{c} refuted: {result.results[c].summary}" for c in unsafe])
    else:
        status = "not_certified"
        out["note"][j] = "no class certified: " + ", ".join(f"{c} {statuses.get(c, 'not computed')}"
                                                             for c in spec.classes)
    out["status"][j] = BOX_STATUS_CODES[status]
    return status


def _store_cross(found: CrossCheck, out: dict[str, np.ndarray], j: int) -> None:
    """A cross-check's figures into row ``j``."""
    out["cross_check_points"][j] = found.points
    out["cross_check_trajectories"][j] = found.trajectories
    out["cross_check_worst_rise"][j] = found.worst_rise
    out["cross_check_worst_envelope"][j] = found.worst_envelope
    out["cross_check_ges_ratio"][j] = found.ges_ratio
    out["cross_check_not_converged"][j] = found.not_converged
    out["cross_check_unsafe_margin"][j] = found.unsafe_margin
    out["cross_check_reach_ratio"][j] = found.reach_ratio
    for y, sup in found.sim_worst.items():
        if f"sim_worst_{y}" in out:
            out[f"sim_worst_{y}"][j] = sup
            bound = out[f"sos_bound_{y}"][j]
            out[f"tightness_{y}"][j] = bound / sup if sup > 0 else np.inf
    out["soundness_violation"][j] = found.violation
    out["violation_detail"][j] = "; ".join(found.violations)


@dataclass(frozen=True)
class _Point:
    """One grid point certified: the model there (a polynomial
    :class:`~lyapcheck.models.language.modelfile.Model` or a loop with functions), the classes' results (what
    :func:`_model_record` reads), the builder of its certificate document, and the note to store
    instead of the usual one (None: that)."""

    model: Any
    results: Mapping[str, ConditionResult]
    document: Callable[[], dict[str, Any]]
    note: str | None = None


def _certify_point(spec: ModelSweepSpec, row: Sequence[float]) -> _Point:
    """Certify one grid point (``certify_model``, on either kind of loop)."""
    from lyapcheck.errors import ModelFileError
    from lyapcheck.models.engines import store
    from lyapcheck.models.surfaces.certificate import build_document
    from lyapcheck.models.surfaces.certify import certify_model
    from lyapcheck.models.language.modelfile import Model

    model = spec.model_at(row)
    classes, candidate, aside = spec.classes, spec.candidate, {}
    if candidate is not None and isinstance(model, Model):  # the spec's V was read at the file's values; where
        # it is not a V of this point (not 0 at an equilibrium that moves with the point), it does not apply here
        from lyapcheck.models.surfaces.certify import parse_candidate

        try:
            parse_candidate(model, candidate)
        except ModelFileError as exc:
            why = f"the spec's candidate is not a V of this point: {exc}"
            classes, candidate = tuple(c for c in classes if c != "candidate"), None
            aside = {"candidate": ConditionResult("candidate", "not_applicable", why)}
    try:
        with store.disabled():  # a point of its own (lyapcheck.models.engines.store.disabled)
            found = certify_model(model, classes=classes, candidate=candidate)
            found.results.update(aside)
    except ModelFileError as exc:  # the recasting's own proof (a square root's argument >= 0) failed here
        if isinstance(model, Model):
            raise
        why = f"the loop could not be recast at this point: {exc}"
        return _Point(model, {c: ConditionResult(c, "not_certified", why) for c in spec.classes}, dict, why)
    return _Point(model, found.results, lambda: build_document(found))


def evaluate_model_points(worker_text: str, coords: np.ndarray) -> dict[str, np.ndarray]:
    """Certify and cross-check each grid point (rows of ``coords``, SI, in the spec's axis order)."""
    spec = cached_model_spec(worker_text)
    coords = np.atleast_2d(np.asarray(coords, dtype=np.float64))
    out = _model_empty(spec, len(coords))
    for j, row in enumerate(coords):
        begin = time.perf_counter()
        with UNIT_LOCK:  # two threads of one Dask worker take turns
            point = _certify_point(spec, row)
        middle = time.perf_counter()
        status = _model_record(spec, point, out, j)
        if point.note is not None:
            out["note"][j] = point.note
        if status == "certified":
            document = point.document()
            out["certificate"][j] = certificate_json(document)
            index = int(np.ravel_multi_index(tuple(int(np.searchsorted(a.values, v)) for a, v in zip(spec.axes, row)),
                                             spec.shape))
            from sweeps.crosscheck import cross_check_point

            _store_cross(cross_check_point(point.model, document, spec.parameters_at(row),
                                           starts=spec.simulation.starts, seed=(spec.simulation.seed, index),
                                           worst_case=spec.simulation.worst_case), out, j)
        out["seconds_certify"][j] = middle - begin
        out["seconds_cross_check"][j] = time.perf_counter() - middle
        out["done"][j] = True
    return out


def unstable_corners(spec: ModelSweepSpec, box: Any) -> tuple[int, dict[str, str] | None]:
    """How many corners of ``box`` have an unstable equilibrium (the linearization refuted, exactly),
    and the first as ``{"note": ...}`` (None when none); ``(-1, None)`` when no stability class is asked.
    On either kind of loop: a loop with functions is read again at each corner, and a corner where it
    cannot be read counts as not unstable (so the box may still be split)."""
    from lyapcheck.errors import ModelFileError
    from lyapcheck.models.surfaces.certify import certify_model
    from lyapcheck.models.language.modelfile import with_parameters

    if not any(c in MODEL_STABILITY_CLASSES for c in spec.classes):
        return -1, None
    count, first = 0, None
    for corner in box.corners():
        try:
            at = spec.recast_at(corner) if spec.has_functions else with_parameters(spec.polynomial, corner)
        except ModelFileError:
            continue
        lin = certify_model(at, classes=("linearization",)).results["linearization"]
        if lin.status == "refuted":
            count += 1
            if first is None:
                where = ", ".join(f"{k} = {value_text(v)}" for k, v in corner.items())
                first = {"note": f"unstable at the corner {where}: {lin.summary}"}
    return count, first


def value_text(value: Fraction) -> str:
    """A parameter value as a note prints it: six significant digits where they are the value exactly, else the
    exact fraction and its decimal (a split box's edge just above 3/2 must not read "1.5", a value that was not
    refuted)."""
    short = f"{float(value):.6g}"
    if Fraction(short) == value:
        return short
    return f"{value.numerator}/{value.denominator} (about {float(value):.10g})"


def classes_left(spec: ModelSweepSpec, unstable: dict[str, str] | None) -> tuple[str, ...]:
    """The classes still run on a box, on either kind of loop: all of them, or where a corner is unstable
    (:func:`unstable_corners`) those that prove no stability property (an unstable point of the box refutes
    every stability class over it: they are stored ``refuted``, not run)."""
    return spec.classes if unstable is None else tuple(c for c in spec.classes if c not in MODEL_STABILITY_CLASSES)


def box_seed(seed: int, box_id: int) -> int:
    """The seed of a box's random parameter points: a function of ``(seed, box id)`` alone."""
    return int(np.random.SeedSequence([seed, box_id]).generate_state(1, dtype=np.uint64)[0])


def evaluate_model_boxes(worker_text: str, boxes: Sequence[tuple[int, dict[str, list[str]]]]) -> dict[str, np.ndarray]:
    """Certify and cross-check each ``(id, {name: [lo, hi]})`` box (exact edges as ``"p/q"`` text)."""
    from lyapcheck.models.engines import store
    from lyapcheck.models.surfaces.certificate import build_document
    from lyapcheck.models.surfaces.certify import certify_model

    spec = cached_model_spec(worker_text)
    assert spec.boxes is not None
    out = _model_empty(spec, len(boxes))
    out["unstable_corners"] = np.full(len(boxes), -1, dtype=np.int8)
    for j, (box_id, edges) in enumerate(boxes):
        begin = time.perf_counter()
        if spec.has_functions:
            _recast_box(spec, box_id, {name: (Fraction(lo), Fraction(hi)) for name, (lo, hi) in edges.items()}, out, j)
            out["done"][j] = True
            continue
        box = window_box(spec, {name: (Fraction(lo), Fraction(hi)) for name, (lo, hi) in edges.items()})
        with UNIT_LOCK:
            corners, unstable = unstable_corners(spec, box)
            classes = classes_left(spec, unstable)
            with store.disabled():
                result = certify_model(spec.polynomial, classes=classes, box=box,
                                       candidate=spec.candidate) if classes else None
        middle = time.perf_counter()
        if result is None:  # only stability classes, refuted at a corner
            for c in spec.classes:
                out[f"status_{c}"][j] = STATUS_CODES["refuted"]
            out["status"][j] = BOX_STATUS_CODES["refuted"]
            out["note"][j] = (unstable or {}).get("note", "")
        elif _model_record(spec, result, out, j, unstable) == "certified":
            document = build_document(result)
            out["certificate"][j] = certificate_json(document)
            points = box.points(spec.boxes.cross_check_points, box_seed(spec.boxes.seed, box_id))
            if spec.discrete:  # a map is iterated (milliseconds a point): at every corner of the box too
                points = box.corners() + points
            if points:
                from sweeps.crosscheck import cross_check_box

                found, _ = cross_check_box([(spec.polynomial, p) for p in points], document,
                                           starts=spec.simulation.starts, seed=(spec.simulation.seed, box_id),
                                           worst_case=spec.simulation.worst_case)
                _store_cross(found, out, j)
        out["unstable_corners"][j] = corners
        out["seconds_certify"][j] = middle - begin
        out["seconds_cross_check"][j] = time.perf_counter() - middle
        out["done"][j] = True
    return out


def _recast_box(spec: ModelSweepSpec, box_id: int, cell: Mapping[str, tuple[Fraction, Fraction]],
                out: dict[str, np.ndarray], j: int) -> None:
    """One box of a loop with functions, as ``lyapcheck certify FILE --box`` certifies it: the model
    read at the box's centre (:meth:`sweeps.spec.ModelSweepSpec.recast_box`), then ``certify_model``
    over the box; a certified box is simulated at its random parameter points
    (:func:`sweeps.crosscheck.cross_check_box`; a map with functions at the box's corners too), and the points
    where its certificates do not apply are named in the note. As a polynomial loop's box, its corners are checked first
    (:func:`unstable_corners`): where one is unstable, the stability classes are stored ``refuted`` and
    not run (:func:`classes_left`)."""
    from lyapcheck.errors import ModelFileError
    from lyapcheck.models.surfaces.certificate import build_document
    from lyapcheck.models.surfaces.certify import certify_model
    from sweeps.crosscheck import cross_check_box

    assert spec.boxes is not None
    begin = time.perf_counter()
    note = None
    unstable: dict[str, str] | None = None
    try:
        with UNIT_LOCK:
            model, box = spec.recast_box(cell)
            # (the tree splits a box not unstable throughout: how many corners are, before the classes)
            out["unstable_corners"][j], unstable = unstable_corners(spec, box)
            classes = classes_left(spec, unstable)
            certified = certify_model(model, classes=classes, box=box, candidate=spec.candidate) if classes else None
            results, document = ({}, {}) if certified is None else (certified.results, build_document(certified))
    except ModelFileError as exc:  # the recasting over this box (a square root's argument, the equilibrium) failed
        note = f"the loop could not be recast over this box: {exc}"
        model, results, document = None, {c: ConditionResult(c, "not_certified", note) for c in spec.classes}, {}
        unstable = None
    middle = time.perf_counter()
    status = _model_record(spec, _Point(model, results, lambda: document), out, j, unstable)
    if note is not None:
        out["note"][j] = note
    if status == "certified":
        out["certificate"][j] = certificate_json(document)
        points = box.points(spec.boxes.cross_check_points, box_seed(spec.boxes.seed, box_id))
        if spec.discrete:  # a map's true map is iterated (milliseconds a point): at every corner of the box too
            points = box.corners() + points
        loops, skipped = [], []
        for point in points:
            try:
                loops.append((spec.recast_at(point), point))
            except ModelFileError as exc:
                where = ", ".join(f"{name} = {float(v):.6g}" for name, v in point.items())
                skipped.append(f"at {where}: the loop could not be read there ({exc})")
        found, mismatched = cross_check_box(loops, document, starts=spec.simulation.starts,
                                            seed=(spec.simulation.seed, box_id), worst_case=spec.simulation.worst_case)
        skipped += mismatched
        _store_cross(found, out, j)
        if skipped:
            out["note"][j] = f"{out['note'][j]}; cross-check not applicable at {len(skipped)} of {len(points)} " \
                             "random points of the box (not simulated): " + "; ".join(skipped)
    out["seconds_certify"][j] = middle - begin
    out["seconds_cross_check"][j] = time.perf_counter() - middle


__all__ = ["evaluate", "evaluate_unit", "certify_point", "simulate_points", "empty_result", "Evaluator", "evaluate_boxes",
           "evaluate_model_points", "evaluate_model_boxes", "certificate_json", "box_seed", "unstable_corners",
           "classes_left", "MODEL_STABILITY_CLASSES", "MODEL_SAFETY_CLASSES", "UNIT_LOCK"]
