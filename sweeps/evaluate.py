"""One unit of sweep work: certify and simulate a batch of grid points.

Runs in a worker process (local pool or Dask). The certificate programs are the compiled
programs of :mod:`lyapcheck.paper.conditions.compiled` (read once per process, then solved by Clarabel
with new parameter values, no cvxpy); ``sector_ges`` goes through :mod:`sweeps.fast_sector`. The
simulation is one batched call of :func:`lyapcheck.simulation.runner.simulate` per scenario for
the whole unit; its rows are independent of the batch they sit in, so a point's result does
not depend on how points were grouped (which is what makes a resumed sweep identical to an
uninterrupted one).

Scenarios (all with ``|d_perp| <= d*`` except ``nominal``, which has no disturbance):

``nominal``      no disturbance, started at ``[simulation] initial_position``: the divergence probe
                 (the simulator's own rule: failed, or the tail sup of ``|eps|`` exceeds
                 ``max(|eps(0)|, Delta_LOS)``);
``constant``     ``d* `` across the path, pointing like gravity for a horizontal path;
``weight``       the swimmer's weight mapped through ``D`` with the swimmer's axis along ``u``
                 (eq:tmp3, :class:`~lyapcheck.simulation.disturbances.Weight`), scaled so that its
                 a-priori bound ``|d| <= W max(1/a1, 1/a2)`` equals ``d*``: the direction
                 dependence is the weight's, the size is the certificate's hypothesis;
``adversarial``  pushes ``V = x^T P x`` up as hard as ``|d_perp| <= d*`` allows, with ``P`` the last
                 ellipsoid stage of ``ultimate_bound``, else the ``sector_ges`` certificate, else
                 ``P = I`` (which pushes ``|eps|`` itself up); started one boundary-layer width off
                 the path (on it, the push is zero and the loop sits at its equilibrium).

The three disturbance scenarios start on the path, where every invariant set of the
certificates contains the state, so the certified bound holds over the whole tail window.
"""

from __future__ import annotations

import math
import threading
from functools import lru_cache
from typing import Any, Callable, Mapping

import numpy as np
import numpy.typing as npt

from lyapcheck.results import ConditionResult
from lyapcheck.paper.params import Problem
from sweeps.schema import BOUND_CLASSES, DISTURBANCE_SCENARIOS, MARGIN_SOURCE, VARIABLES, status_code
from sweeps.soundness import violations
from sweeps.spec import SweepSpec, cached_spec

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
    from lyapcheck.simulation.scenarios import weight_disturbance

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
    from lyapcheck.simulation.disturbances import (ADVERSARIAL_LAYER_FRACTION, Adversarial, Constant, NoDisturbance,
                                                   Stacked, Weight)
    from lyapcheck.simulation.integrator import STATUS_OK
    from lyapcheck.simulation.model import LoopParams
    from lyapcheck.simulation.runner import simulate

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


#: the worst-case search's time budget in a sweep: below any refinement round's cost, so only its
#: deterministic screening round and final re-simulation run (a point's figure does not depend
#: on the machine's speed, which resuming a sweep byte-for-byte needs)
WORST_CASE_SCREENING_ONLY = 1e-9


def _worst_case(spec: SweepSpec, coords: FloatArray, storage: list[dict[str, Any] | None]) -> dict[str, Any]:
    """The worst-case disturbance search at every point, started on the path like the other
    disturbance scenarios (inside every invariant set of the certificates)."""
    from lyapcheck.errors import InvalidParameter
    from lyapcheck.simulation.scenarios import Scenario
    from lyapcheck.simulation.worst_case import search_worst_case

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

__all__ = ["evaluate", "evaluate_unit", "certify_point", "simulate_points", "empty_result", "Evaluator"]
