"""The simulation cross-check of a certified point or box of a model file's sweep.

At each parameter point (the point itself, or random points of a box drawn from ``(seed, box
id)`` so that a box's result does not depend on the unit it was grouped in), the model is
simulated with the project's integrator (:mod:`lyapcheck.models.engines.trajectories`) and every certified
class of the stored certificate is checked with :mod:`lyapcheck.models.engines.crosscheck`:

* ``roa``: starts drawn inside ``{V <= level}`` (random directions, between half the way and
  just inside the set's boundary, found by bisection along each ray) must not escape and V must
  not rise along them (so they stay in the set);
* ``quadratic`` and ``sos_gas``: starts across the model's ``[domain]`` (or, without one, the box
  of twice the certificate's state scales around the equilibrium) must not escape, V must not rise
  and must stay below ``V(0) exp(-rate t)`` (the certified rate of V); a GES certificate's
  ``|x(t) - x_eq| <= k |x0 - x_eq| exp(-rate t)`` too;
* ``barrier`` and ``reach_avoid`` (:func:`check_sets`, shared with :mod:`sweeps.recast_crosscheck`): starts
  drawn from the model's ``[sets] initial`` (:func:`lyapcheck.models.classes.falsify.sample_set`, a quarter on
  its boundary), each simulated with every disturbance at 0 and, for a claim over every disturbance
  (``"disturbances": "all"``), at each vertex of the disturbance box held constant (at most
  :data:`MAX_VERTICES`), over the falsification's horizon
  (:func:`lyapcheck.models.classes.falsify.default_horizon`; both classes read the same trajectories). A
  barrier's must not enter ``unsafe``; a reach-avoid's must be in ``goal`` by the certified
  ``reach_time_bound_s`` and not enter ``unsafe`` before it, and when one is not in the goal by the
  horizon and the bound is beyond it, all are simulated again to just past the bound
  (:func:`lyapcheck.models.engines.crosscheck.check_safety`,
  :func:`~lyapcheck.models.engines.crosscheck.check_reach_avoid`). Figures: ``unsafe_margin`` (the largest
  unsafe margin reached, each inequality relative to the size of its terms:
  :func:`~lyapcheck.models.engines.crosscheck.scaled_margin`; ``< 0`` none entered) and ``reach_ratio``
  (the latest time before the goal over the bound);
* ``sos_bound``: the worst-case disturbance search (:func:`lyapcheck.models.surfaces.simulate.search_worst_case`,
  its deterministic screening round) must not find a tail sup of an output above its certified
  bound beyond :data:`sweeps.soundness.BOUND_REL_TOL`, nor a diverging disturbance.

A V over a box may depend on the parameters: it is evaluated at each point's own values. The
horizon is :func:`lyapcheck.models.engines.trajectories.horizon` of the point's linearization. Trajectories
not at the equilibrium by then are counted (``not_converged``): a finite simulation cannot refute
convergence, so this is a figure; a certified decay rate (V's, or a GES envelope) is what makes
slow convergence a violation. Any breach is a soundness violation, with a one-line detail.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from fractions import Fraction
from typing import Any, Callable, Final, Mapping, Optional, Sequence

import numpy as np

from lyapcheck.models.language.modelfile import Model
from sweeps.soundness import BOUND_REL_TOL, WORST_CASE_SCREENING_ONLY

#: trajectories leave the cross-check's box only this many start extents from the equilibrium (a
#: trajectory under a certificate stays in a sublevel set of V through its start, which may reach
#: well beyond the starts' box: the escape box is generous so that an escape means divergence)
ESCAPE_EXTENTS: Final = 30.0
#: converged: the final state within this fraction of the starts' extent of the equilibrium
CONVERGED_FRACTION: Final = 1e-3
#: starts of a region of attraction: between these fractions of the way to the set's boundary
REGION_FRACTIONS: Final = (0.5, 0.999)
#: the global starts' box without a [domain]: this many certificate state scales around x_eq
DEFAULT_REGION_SCALES: Final = 2.0
#: the classes simulated from the initial set (:func:`check_sets`)
SAFETY_CLASSES: Final = ("barrier", "reach_avoid")
#: the vertices of the disturbance box held constant for a claim over every disturbance (2**m, at most this many)
MAX_VERTICES: Final = 8
#: a loop's simulation for :func:`check_sets`: ``run(starts, t_end, disturbances)`` with starts ``(k, n)``
#: (declared states), ``t_end`` in s (None: the loop's falsification horizon) and a constant disturbance
#: per row ``(k, m)`` (None: all 0); per row the times and states of the integrator's own points
Runs = Callable[[np.ndarray, Optional[float], Optional[np.ndarray]], list[tuple[np.ndarray, np.ndarray]]]

@dataclass
class CrossCheck:
    """The figures of one cross-check (NaN: nothing of that kind was checked)."""

    points: int = 0
    trajectories: int = 0
    worst_rise: float = math.nan
    worst_envelope: float = math.nan
    ges_ratio: float = math.nan
    not_converged: int = 0
    unsafe_margin: float = math.nan
    reach_ratio: float = math.nan
    sim_worst: dict[str, float] = field(default_factory=dict)
    violations: list[str] = field(default_factory=list)

    @property
    def violation(self) -> bool:
        return bool(self.violations)

    def worse(self, attr: str, value: float) -> None:
        current = getattr(self, attr)
        if math.isfinite(value) and (math.isnan(current) or value > current):
            setattr(self, attr, value)


@dataclass(frozen=True)
class _Set:
    """A certified function of the document at one parameter point."""

    cls: str
    V: Any  # a float function of the scaled states (lyapcheck.models.engines.crosscheck.certificate_function)
    level: float = math.nan  # roa
    rate: float = 0.0  # certified decay rate of V, 1/s
    k: float = math.nan  # GES envelope
    ges_rate: float = math.nan


def _point_text(point: Mapping[str, Fraction]) -> str:
    return ", ".join(f"{k} = {float(v):.6g}" for k, v in point.items())


def _sets(doc: Mapping[str, Any], model: Model, point: Mapping[str, Fraction], scales: Sequence[Fraction]) -> list[_Set]:
    from lyapcheck.models.engines.crosscheck import certificate_function

    box = list((doc.get("box") or {}).keys())
    names = list(model.states) + box
    out = []
    for cls, cond in (doc.get("conditions") or {}).items():
        if not isinstance(cond, dict) or cond.get("status") != "certified" or cls not in ("quadratic", "sos_gas", "roa"):
            continue
        cert = cond.get("certificate") or {}
        V = certificate_function(cert["V"], names, model.n, point, scales)
        if cls == "roa":
            out.append(_Set(cls, V, level=float(Fraction(str(cert["level"])))))
            continue
        rate = float(cond.get("decay_rate_V_per_s") or 0.0)
        if cond.get("property") == "GES" and cond.get("k") is not None and cond.get("decay_rate_per_s") is not None:
            out.append(_Set(cls, V, rate=rate, k=float(cond["k"]), ges_rate=float(cond["decay_rate_per_s"])))
        else:
            out.append(_Set(cls, V, rate=rate))
    return out


def cross_check(model: Model, doc: Mapping[str, Any], points: Sequence[Mapping[str, Fraction]], *, starts: int,
                seed: Sequence[int], worst_case: bool) -> CrossCheck:
    """Simulate ``model`` at each parameter point of ``points`` against the certificate ``doc``.

    Parameters
    ----------
    model
        The sweep's model (its other parameters as the spec sets them).
    doc
        The certificate document of the point or box (:func:`lyapcheck.models.surfaces.certificate.build_document`).
    points
        Exact values of the swept parameters, one mapping per point to simulate.
    starts
        Starts per point and certified set.
    seed
        The random starts come from ``numpy.random.default_rng([*seed, j])`` for the j-th point.
    worst_case
        Run the worst-case disturbance search against ``sos_bound``'s bounds.
    """
    from lyapcheck.models.language.modelfile import with_parameters

    out = CrossCheck()
    scaling = (doc.get("field") or {}).get("scaling") or {}
    scales = [Fraction(str(s)) for s in scaling.get("states", [])] or [Fraction(1)] * model.n
    bound_cond = (doc.get("conditions") or {}).get("sos_bound") or {}
    bounds = bound_cond.get("bounds") if bound_cond.get("status") == "certified" else None
    for j, point in enumerate(points):
        here = with_parameters(model, dict(point))
        sets = _sets(doc, model, point, scales)
        rng = np.random.default_rng([*seed, j])
        out.points += 1
        if sets:
            _trajectories(here, sets, scales, rng, starts, point, out)
        check_sets(here, doc, _point_text(point), rng, starts, _polynomial_runs(here), out)
        if bounds and worst_case:
            _bounds(here, bounds, point, out, bound_cond.get("bounds_reference") or {})
    return out


def _region_starts(V: Any, level: float, n: int, rng: np.random.Generator, count: int) -> np.ndarray | None:
    """``count`` starts (scaled states) inside ``{V <= level}``, or None when its boundary is not found."""
    from lyapcheck.models.engines.crosscheck import ray_boundary

    directions = rng.standard_normal((count, n))
    directions /= np.maximum(np.linalg.norm(directions, axis=1, keepdims=True), 1e-300)
    boundary = ray_boundary(V, level, directions)
    if boundary is None:
        return None
    return np.asarray(boundary * rng.uniform(*REGION_FRACTIONS, size=(count, 1)), dtype=np.float64)


def _global_starts(model: Model, eq: np.ndarray, s: np.ndarray, rng: np.random.Generator, count: int) -> np.ndarray:
    if model.domain:
        lo = np.array([float(model.domain[x][0]) for x in model.states])
        hi = np.array([float(model.domain[x][1]) for x in model.states])
    else:
        lo, hi = eq - DEFAULT_REGION_SCALES * s, eq + DEFAULT_REGION_SCALES * s
    return np.asarray(lo + (hi - lo) * rng.random((count, model.n)), dtype=np.float64)


def _trajectories(model: Model, sets: Sequence[_Set], scales: Sequence[Fraction], rng: np.random.Generator,
                  starts: int, point: Mapping[str, Fraction], out: CrossCheck) -> None:
    from lyapcheck.models.engines.crosscheck import check_ges_envelope, check_global, check_region
    from lyapcheck.models.engines.numeric import FieldEvaluator
    from lyapcheck.models.engines.trajectories import horizon, jacobian_eigenvalues, simulate

    n = model.n
    eq = np.array([float(v) for v in model.equilibrium])
    s = np.array([float(v) for v in scales])
    where = _point_text(point)
    blocks: list[np.ndarray] = []
    owner: list[int] = []  # which roa set a start was drawn for (-1: a global start)
    for k, st in enumerate(sets):
        if st.cls != "roa":
            continue
        u = _region_starts(st.V, st.level, n, rng, starts)
        if u is None:
            out.violations.append(f"roa at {where}: the certified set {{V <= {st.level:.6g}}} does not contain the "
                                  "equilibrium or is unbounded")
            continue
        blocks.append(eq + s * u)
        owner += [k] * len(u)
    if any(st.cls != "roa" for st in sets):
        blocks.append(_global_starts(model, eq, s, rng, starts))
        owner += [-1] * starts
    if not blocks:
        return
    x0 = np.vstack(blocks)
    half = np.maximum(np.max(np.abs(x0 - eq), axis=0), s * 1e-6)
    t_end = horizon(jacobian_eigenvalues(FieldEvaluator.of(model), eq, half))
    runs = simulate(model, x0, t_end=t_end, half_widths=half, escape_factor=ESCAPE_EXTENTS,
                    converged_fraction=CONVERGED_FRACTION)
    out.trajectories += len(runs)
    out.not_converged += sum(tr.outcome == "other" for tr in runs)
    nodes = [tr.nodes for tr in runs]
    u_paths = [(x - eq) / s for _, x in nodes]
    for k, st in enumerate(sets):
        if st.cls == "roa":
            inside = [i for i, u in enumerate(u_paths) if owner[i] == k or st.V(u[:1])[0] <= st.level]
            found = check_region([st.V(u_paths[i]) for i in inside], [runs[i].outcome for i in inside])
            out.worse("worst_rise", found.worst_rise)
            if not found.ok:
                out.violations.append(f"roa at {where}: of {found.starts} starts in {{V <= {st.level:.6g}}}, "
                                      f"{found.escaped} escaped; V rose by {found.worst_rise:.3g} of V(0)")
            continue
        series = [(t, st.V(u)) for (t, _), u in zip(nodes, u_paths)]
        glob = check_global(series, [tr.outcome for tr in runs], st.rate)
        out.worse("worst_rise", glob.worst_rise)
        if st.rate > 0:
            out.worse("worst_envelope", glob.worst_envelope)
        if not glob.ok:
            out.violations.append(f"{st.cls} at {where}: of {glob.trajectories} trajectories {glob.escaped} escaped; "
                                  f"V rose by {glob.worst_rise:.3g} and exceeded V(0) exp(-{st.rate:.4g} t) by "
                                  f"{glob.worst_envelope:.3g} of V(0)")
        if math.isfinite(st.k):
            ratio = check_ges_envelope([(t, np.linalg.norm(x - eq, axis=1)) for t, x in nodes], st.k, st.ges_rate)
            out.worse("ges_ratio", ratio)
            from lyapcheck.tolerances import TRAJECTORY_CHECK_REL_TOL

            if ratio > 1 + TRAJECTORY_CHECK_REL_TOL:
                out.violations.append(f"{st.cls} at {where}: |x(t)| reached {ratio:.6g} times the certified GES "
                                      f"envelope {st.k:.4g} |x0| exp(-{st.ges_rate:.4g} t)")


def _polynomial_runs(model: Model) -> Runs:
    """The polynomial loop's simulation for :func:`check_sets` (the project's integrator,
    :func:`lyapcheck.models.engines.trajectories.simulate`, escape as the falsification's)."""
    from lyapcheck.models.classes.falsify import ESCAPE_FACTOR, default_horizon
    from lyapcheck.models.engines.trajectories import simulate

    eq = np.array([float(v) for v in model.equilibrium])

    def run(x0: np.ndarray, t_end: float | None,
            disturbances: np.ndarray | None) -> list[tuple[np.ndarray, np.ndarray]]:
        half = np.maximum(np.max(np.abs(x0 - eq), axis=0), np.maximum(np.abs(eq), 1.0) * 1e-6)
        horizon = default_horizon(model, half) if t_end is None else t_end
        with np.errstate(all="ignore"):
            runs = simulate(model, x0, t_end=horizon, half_widths=half, disturbances=disturbances,
                            escape_factor=ESCAPE_FACTOR)
        return [tr.nodes for tr in runs]

    return run


def _vertices(model: Any, cond: Mapping[str, Any]) -> list[np.ndarray]:
    """The constant disturbances a claim is simulated under: 0, then for a claim over every disturbance
    the box's vertices (the first :data:`MAX_VERTICES` in sign order)."""
    from itertools import islice, product

    bounds = np.array([float(b) for b in (getattr(model, "disturbances", None) or {}).values()])
    out = [np.zeros(bounds.size)]
    if bounds.size and cond.get("disturbances") == "all":
        out += [np.array(signs) * bounds for signs in islice(product((-1.0, 1.0), repeat=bounds.size), MAX_VERTICES)]
    return out


def check_sets(model: Any, doc: Mapping[str, Any], where: str, rng: np.random.Generator, starts: int, run: Runs,
               out: CrossCheck) -> None:
    """A certified ``barrier`` or ``reach_avoid`` of ``doc`` against trajectories of ``run`` from ``starts``
    random points of ``model``'s initial set (module doc). ``model``: a polynomial loop or a loop with
    functions at the point (its ``sets`` evaluated there; ``n``, ``equilibrium``, ``domain``,
    ``disturbances``); ``where`` names the point in a violation's detail."""
    from lyapcheck.models.classes.falsify import sample_set
    from lyapcheck.models.engines.crosscheck import check_reach_avoid, check_safety, reach_horizon, scaled_margin
    from lyapcheck.models.language.sets import margin

    sets = getattr(model, "sets", None) or {}
    conditions = doc.get("conditions") or {}
    certified = [cls for cls in SAFETY_CLASSES if isinstance(conditions.get(cls), dict)
                 and conditions[cls].get("status") == "certified" and sets.get("initial") and sets.get("unsafe")
                 and (cls == "barrier" or sets.get("goal"))]
    if not certified:
        return
    bound = float(conditions["reach_avoid"].get("reach_time_bound_s") or math.nan) \
        if "reach_avoid" in certified else math.nan
    if "reach_avoid" in certified and not (math.isfinite(bound) and bound > 0):
        out.violations.append(f"reach_avoid at {where}: the certified time bound {bound!r} s is not a positive number")
        certified.remove("reach_avoid")
    try:
        x0, _ = sample_set(model, sets["initial"], margin, starts, rng)
    except ValueError:  # no point of the initial set found: nothing to simulate
        return
    # one set of trajectories for both claims, under every disturbance either claims
    vertices = _vertices(model, {"disturbances": "all" if any(conditions[c].get("disturbances") == "all"
                                                               for c in certified) else "zero"})
    X0 = np.tile(x0, (len(vertices), 1))
    D = np.repeat(np.array(vertices), len(x0), axis=0) if vertices[0].size else None
    runs = run(X0, None, D)  # the falsification's horizon
    eq = np.array([float(v) for v in model.equilibrium])
    extent = np.max(np.abs(X0 - eq), axis=0)  # the problem's scale per state, for the margins' sizes
    extent = np.where(extent > 0, extent, np.maximum(np.abs(eq), 1.0))

    def at(key: str, x: np.ndarray) -> np.ndarray:
        return scaled_margin(sets[key], x, extent)
    out.trajectories += len(runs)

    def start(i: int) -> str:
        text = ", ".join(f"{x} = {v:.6g}" for x, v in zip(model.states, X0[i]))
        if D is not None:
            text += " with " + ", ".join(f"{d} = {v:+.6g}" for d, v in zip(model.disturbances, D[i]))
        return text

    def rows(cls: str) -> list[int]:  # a nominal claim's trajectories: those with every disturbance 0
        if D is None or conditions[cls].get("disturbances") == "all":
            return list(range(len(runs)))
        return list(range(len(x0)))

    if "barrier" in certified:
        mine = rows("barrier")
        safe = check_safety([at("unsafe", runs[i][1]) for i in mine])
        out.worse("unsafe_margin", safe.worst_margin)
        if not safe.ok:
            assert safe.first is not None
            out.violations.append(f"barrier at {where}: of {safe.trajectories} trajectories from the initial set "
                                  f"{safe.entered} entered the unsafe set (margin {safe.worst_margin:.3g} of its "
                                  "terms' size), "
                                  f"the first from {start(mine[safe.first])}")
    if "reach_avoid" not in certified:
        return
    mine = rows("reach_avoid")

    def reach(found_runs: list[tuple[np.ndarray, np.ndarray]]) -> Any:
        return check_reach_avoid([(found_runs[i][0], at("unsafe", found_runs[i][1]), at("goal", found_runs[i][1]))
                                  for i in mine], bound)

    found = reach(runs)
    end = reach_horizon(bound)
    if found.unreached and min(float(runs[i][0][-1]) for i in mine) < end:
        # some trajectory was not in the goal by the falsification's horizon, before the bound: on to the bound
        runs = run(X0, end, D)
        out.trajectories += len(runs)
        found = reach(runs)
    out.worse("unsafe_margin", found.worst_margin)
    out.worse("reach_ratio", found.reach_ratio)
    if found.entered:
        assert found.first_entered is not None
        out.violations.append(f"reach_avoid at {where}: of {found.trajectories} trajectories from the initial set "
                              f"{found.entered} entered the unsafe set before the goal (margin "
                              f"{found.worst_margin:.3g} of its terms' size), the first from "
                              f"{start(mine[found.first_entered])}")
    if found.late:
        assert found.first_late is not None
        out.violations.append(f"reach_avoid at {where}: of {found.trajectories} trajectories from the initial set "
                              f"{found.late} were not in the goal by the certified time bound {bound:.6g} s "
                              f"(one still out at {found.reach_ratio:.6g} times it), the first from "
                              f"{start(mine[found.first_late])}")


def _bounds(model: Model, bounds: Mapping[str, Any], point: Mapping[str, Fraction], out: CrossCheck,
            references: Mapping[str, Any]) -> None:
    """The worst case found against each bound. A bound is on ``|y - y_eq|`` (``references``: each
    ``y_eq``), the search's figure on ``|y|``: by the triangle inequality ``|y| <= |y_eq| + bound``
    is what the bound implies, so only beyond that is a violation shown (never a false alarm)."""
    from lyapcheck.models.engines.crosscheck import bound_exceeded
    from lyapcheck.models.surfaces.simulate import search_worst_case

    found = search_worst_case(model, budget_s=WORST_CASE_SCREENING_ONLY)
    where = _point_text(point)
    if found.get("diverged"):
        out.violations.append(f"sos_bound at {where}: a disturbance within its bounds made the loop diverge")
    for name, bound in bounds.items():
        sup = (found.get("sup_abs_output_tail") or {}).get(name)
        if sup is None:
            continue
        out.sim_worst[name] = max(out.sim_worst.get(name, -math.inf), float(sup))
        reference = abs(float(references.get(name) or 0.0))
        extra = f" plus |{name}_eq| = {reference:.6g}" if reference else ""
        if bound_exceeded(float(bound) + reference, float(sup), BOUND_REL_TOL):
            out.violations.append(f"sos_bound at {where}: the worst case found, limsup |{name}| >= {float(sup):.6g}, "
                                  f"exceeds the certified bound {float(bound):.6g}{extra}")


__all__ = ["CrossCheck", "cross_check", "check_sets", "SAFETY_CLASSES", "WORST_CASE_SCREENING_ONLY"]
