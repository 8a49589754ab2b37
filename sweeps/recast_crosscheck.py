"""The simulation cross-check of a certified grid point or box of a loop with functions (sin, sqrt, sat, ...).

A box (:func:`cross_check_recast_box`) is checked at random parameter points of it, each on the loop
read at that point; a point where the box's certificates are not functions of that loop's
variables (:func:`box_mismatch`) is not simulated, and the reason is returned to be stored.

The loop simulated is the true one: each function evaluated by numpy
(:func:`lyapcheck.models.engines.recast_numeric.field_values`), never the recast polynomial loop, which holds
only on its relations' set. Its starts come from ``numpy.random.default_rng([*seed, 0])`` (``seed``:
the sweep's ``[simulation] seed`` and the point's flat index), so a point's result does not depend
on the unit it was grouped in. Every certified class of the stored document is checked with the
checks of :mod:`lyapcheck.models.engines.crosscheck`, as :mod:`sweeps.crosscheck` does for a polynomial loop:

=====================  ==========================================  ==========================================
certificate            starts                                      must hold
=====================  ==========================================  ==========================================
``roa``, {V <= level}  random rays from the equilibrium, between   no escape; V never rises
                       half-way and just inside the set's
                       boundary (within the certificate's ``box``
                       for a ball-arithmetic one, else within the
                       comparison box of the classes)
``quadratic``,         uniform over the comparison box (the         no escape; V never rises; ``V(t) <= V(0)
``sos_gas``            model's ``[domain]``, else +-pi in an angle  exp(-rate t)`` with a certified rate of V;
                       and +-4 elsewhere)                           a GES certificate's envelope
``roa`` (its own)      the check ``recast_run.simulated_check``     none of its starts in the set failed to
                       made when certifying                         converge (``soundness_violation``)
``sos_bound``          uniform over the comparison box; each        the largest ``|y|`` after 60 s (stored as
                       disturbance bang-bang against ``y``'s sign   ``sim_worst_<y>``) within the certified
                       or a square wave at its bound, RK4, 120 s    bound
``barrier``,           random points of ``[sets] initial``, from    never in ``unsafe``; ``reach_avoid``: in
``reach_avoid``        ``[*seed, 2]`` (:func:`sweeps.crosscheck.     ``goal`` by ``reach_time_bound_s``, not in
                       check_sets`, the polynomial loop's check)    ``unsafe`` before it
=====================  ==========================================  ==========================================

V is the certificate's exact polynomial in its ``variables`` (the states, then the auxiliaries),
each shifted by the certificate's ``shift``, evaluated in floating point on the true auxiliaries of
the simulated states. An angle state (one the loop sees only through its sine and cosine) is never
an escape: on the cylinder the loop may turn several times before it settles. A trajectory is
converged when it ends within :data:`CONVERGED_FRACTION` of the starts' extent of the equilibrium,
modulo 2 pi in the angles the certificate's claim is modulo; those that are not are counted
(``not_converged``), not flagged: a finite simulation cannot refute convergence.
"""

from __future__ import annotations

from fractions import Fraction
from typing import TYPE_CHECKING, Any, Callable, Final, Mapping, Sequence

import numpy as np

from lyapcheck.models.engines.recast_numeric import TrueField
from sweeps.crosscheck import (CONVERGED_FRACTION, ESCAPE_EXTENTS, REGION_FRACTIONS, SAFETY_CLASSES, CrossCheck, Runs,
                               check_sets)

if TYPE_CHECKING:
    from lyapcheck.models.language.recast import RecastModel, RecastSystem

#: the classes whose certificates are simulated here (the global ones, then the region)
GLOBAL_CLASSES: Final = ("quadratic", "sos_gas")
REGION_CLASS: Final = "roa"
#: a float function of state deviations (rows ``(k, n)``): ``(k,)`` values
PointFunction = Callable[[np.ndarray], np.ndarray]


class _Nodes:
    """The integrator's step observer: every row's own points (the start, then each accepted step)."""

    def __init__(self) -> None:
        self.index: list[np.ndarray] = []
        self.t: list[np.ndarray] = []
        self.y: list[np.ndarray] = []

    def start(self, index: np.ndarray, t: np.ndarray, y: np.ndarray, f: np.ndarray) -> None:
        self._keep(index, t, y)

    def step(self, index: np.ndarray, t0: np.ndarray, t1: np.ndarray, y0: np.ndarray, y1: np.ndarray,
             f0: np.ndarray, f1: np.ndarray) -> None:
        self._keep(index, t1, y1)

    def _keep(self, index: np.ndarray, t: np.ndarray, y: np.ndarray) -> None:
        self.index.append(np.array(index, copy=True))
        self.t.append(np.broadcast_to(np.asarray(t, dtype=np.float64), (len(index),)).copy())
        self.y.append(np.array(y, copy=True))

    def rows(self, count: int) -> list[tuple[np.ndarray, np.ndarray]]:
        index, t, y = np.concatenate(self.index), np.concatenate(self.t), np.concatenate(self.y)
        order = np.lexsort((t, index))
        index, t, y = index[order], t[order], y[order]
        cuts = np.searchsorted(index, np.arange(count + 1))
        return [(t[a:b], y[a:b]) for a, b in zip(cuts[:-1], cuts[1:])]


def _v_function(system: RecastSystem, cert: Mapping[str, Any]) -> PointFunction:
    """The certificate's V as a float function of state deviations (rows): its polynomial in its
    ``variables``, each minus its ``shift``, at the true auxiliaries of ``x_eq + z``."""
    from lyapcheck.models.engines.recast_numeric import poly_values, variable_values
    from lyapcheck.models.engines.recast_sos import poly_from_json
    from lyapcheck.sos.polynomials import Ring

    ring = Ring(tuple(str(v) for v in cert["variables"]))
    V = poly_from_json(ring, cert["V"], "V")
    shift = {str(k): float(Fraction(str(v))) for k, v in (cert.get("shift") or {}).items()}
    eq = np.array([float(system.values[s]) for s in system.states])

    def at(Z: np.ndarray) -> np.ndarray:
        Z = np.atleast_2d(np.asarray(Z, dtype=np.float64))
        cols = variable_values(system, Z + eq)
        return poly_values(ring, V, {n: cols[n] - shift.get(n, 0.0) for n in ring.names}, Z.shape[0])

    return at


def _within(V: PointFunction, lo: np.ndarray, hi: np.ndarray) -> PointFunction:
    """V inside the box ``[lo, hi]`` of deviations, +inf outside (a set ``{V <= level}`` cut by the box)."""
    def at(Z: np.ndarray) -> np.ndarray:
        values = np.asarray(V(Z), dtype=np.float64)
        return np.where(np.all((Z >= lo) & (Z <= hi), axis=1), values, np.inf)

    return at


def cross_check_recast(model: RecastModel, doc: Mapping[str, Any], point: Mapping[str, Fraction], *, starts: int,
                       seed: Sequence[int]) -> CrossCheck:
    """Simulate the true loop of ``model`` (the point's own) against the certificate document ``doc``.

    Parameters
    ----------
    model
        The loop at the point (:meth:`sweeps.spec.ModelSweepSpec.model_at`).
    doc
        Its certificate document (:func:`lyapcheck.models.surfaces.recast_certify.certify_recast`).
    point
        The swept parameters' exact values (named in a violation's detail).
    starts
        Starts per certified class.
    seed
        The starts come from ``numpy.random.default_rng([*seed, 0])``.
    """
    from lyapcheck.models.engines.crosscheck import check_ges_envelope, check_global, check_region, ray_boundary
    from lyapcheck.models.classes.recast_classes import angle_states, base_loop
    from lyapcheck.models.surfaces.recast_run import comparison_box
    from lyapcheck.tolerances import TRAJECTORY_CHECK_REL_TOL

    out = CrossCheck(points=1)
    where = ", ".join(f"{k} = {float(v):.6g}" for k, v in point.items())
    system = model.system
    n = model.n
    conditions = {name: c for name, c in (doc.get("conditions") or {}).items()
                  if isinstance(c, dict) and c.get("status") == "certified"}
    for name, cond in conditions.items():
        if cond.get("soundness_violation"):
            out.violations.append(f"{name} at {where}: its own simulation when certified found "
                                  f"{cond.get('starts_in_set_not_converged', 'some')} starts in the set that did "
                                  "not converge")
    if "sos_bound" in conditions and model.robust is not None:
        _check_bound(model, conditions["sos_bound"], starts, seed, where, out)
    check_sets(model, doc, where, np.random.default_rng([*seed, 2]), starts, _recast_runs(model), out)
    checked = [c for c in (*GLOBAL_CLASSES, REGION_CLASS) if c in conditions]
    if not checked:
        return out
    rng = np.random.default_rng([*seed, 0])
    lo, hi = (np.asarray(b, dtype=np.float64) for b in comparison_box(model, base_loop(system)))
    blocks: list[np.ndarray] = []
    owner: list[str] = []
    functions: dict[str, PointFunction] = {}
    for cls in checked:
        cert = conditions[cls].get("certificate") or {}
        V = _v_function(system, cert)
        functions[cls] = V
        if cls in GLOBAL_CLASSES:
            blocks.append(lo + (hi - lo) * rng.random((starts, n)))
            owner += [cls] * starts
            continue
        level = float(Fraction(str(cert["level"])))
        box = cert.get("box")  # a ball-arithmetic region: the set within its box
        b_lo, b_hi = (lo, hi) if box is None else (np.array([float(Fraction(str(box[s][0]))) for s in model.states]),
                                                   np.array([float(Fraction(str(box[s][1]))) for s in model.states]))
        directions = rng.standard_normal((starts, n))
        directions /= np.maximum(np.linalg.norm(directions, axis=1, keepdims=True), 1e-300)
        boundary = ray_boundary(_within(V, b_lo, b_hi), level, directions)
        if boundary is None:
            out.violations.append(f"roa at {where}: the certified set {{V <= {level:.6g}}} does not contain the "
                                  "equilibrium")
            continue
        blocks.append(boundary * rng.uniform(*REGION_FRACTIONS, size=(starts, 1)))
        owner += [cls] * starts
    if not blocks:
        return out
    Z0 = np.vstack(blocks)
    extent = np.maximum(np.max(np.abs(Z0), axis=0), 1e-6)
    angles = angle_states(system)  # never an escape: on the cylinder the loop may turn before it settles
    escape = np.array([np.inf if s in angles else ESCAPE_EXTENTS * e for s, e in zip(model.states, extent)])
    runs = _simulate(model, Z0, escape, extent)
    out.trajectories += len(runs)
    for cls in checked:
        rows = [i for i, o in enumerate(owner) if o == cls]
        if not rows:
            continue
        cond = conditions[cls]
        modulo = tuple(str(a) for a in ((cond.get("certificate") or {}).get("angles") or ()))
        outcomes = [_outcome(system, runs[i][1][-1], escape, float(np.linalg.norm(extent)), modulo) for i in rows]
        out.not_converged += sum(o == "other" for o in outcomes)
        V = functions[cls]
        if cls == REGION_CLASS:
            found = check_region([V(runs[i][1]) for i in rows], outcomes)
            out.worse("worst_rise", found.worst_rise)
            if not found.ok:
                out.violations.append(f"roa at {where}: of {found.starts} starts in the certified set, {found.escaped} "
                                      f"escaped; V rose by {found.worst_rise:.3g} of V(0)")
            continue
        rate = float(cond.get("decay_rate_V_per_s") or 0.0)
        glob = check_global([(runs[i][0], V(runs[i][1])) for i in rows], outcomes, rate)
        out.worse("worst_rise", glob.worst_rise)
        if rate > 0:
            out.worse("worst_envelope", glob.worst_envelope)
        if not glob.ok:
            out.violations.append(f"{cls} at {where}: of {glob.trajectories} trajectories {glob.escaped} escaped; V "
                                  f"rose by {glob.worst_rise:.3g} and exceeded V(0) exp(-{rate:.4g} t) by "
                                  f"{glob.worst_envelope:.3g} of V(0)")
        if cond.get("property") == "GES" and cond.get("k") is not None and cond.get("decay_rate_per_s") is not None:
            k, ges_rate = float(cond["k"]), float(cond["decay_rate_per_s"])
            ratio = check_ges_envelope([(runs[i][0], np.linalg.norm(runs[i][1], axis=1)) for i in rows], k, ges_rate)
            out.worse("ges_ratio", ratio)
            if ratio > 1 + TRAJECTORY_CHECK_REL_TOL:
                out.violations.append(f"{cls} at {where}: |x(t)| reached {ratio:.6g} times the certified GES "
                                      f"envelope {k:.4g} |x0| exp(-{ges_rate:.4g} t)")
    return out


def box_mismatch(model: RecastModel, doc: Mapping[str, Any]) -> str | None:
    """Why the certificates of a box's document cannot be simulated on the loop ``model`` of one
    point of the box (None: they can). The check evaluates each ``V`` on the point's own auxiliaries,
    shifted by the certificate's ``shift`` (the box centre's values at the equilibrium); that is the
    certificate's function only when every auxiliary it names is defined alike at the point and
    has the same value at the equilibrium (an auxiliary with a box parameter in it, such as
    ``sin(b*x)``, is not)."""
    definitions = model.system.definitions()
    values = {k: Fraction(v) for k, v in model.system.values.items()}
    for name, cond in (doc.get("conditions") or {}).items():
        if not isinstance(cond, dict) or cond.get("status") != "certified" or \
                name not in (*GLOBAL_CLASSES, REGION_CLASS):
            continue
        cert = cond.get("certificate") or {}
        missing = [str(v) for v in cert.get("variables") or () if str(v) not in model.system.ring.names]
        if missing:  # a box parameter kept as a bounded variable of the recasting
            return (f"the {name} certificate's V is a function of {', '.join(missing)}, not a variable of the "
                    "point's loop")
        for aux, text in (cert.get("auxiliaries") or {}).items():
            if definitions.get(aux) != text:
                return f"the auxiliary {aux} = {text} of the {name} certificate is not one of the point's recasting"
        for var, shift in (cert.get("shift") or {}).items():
            if var in values and values[var] != Fraction(str(shift)):
                return (f"the {name} certificate's {var} is shifted by {shift} (the box centre's value at the "
                        "equilibrium), not by the point's own value")
    return None


def cross_check_recast_box(points: Sequence[tuple[RecastModel, Mapping[str, Fraction]]], doc: Mapping[str, Any], *,
                           starts: int, seed: Sequence[int]) -> tuple[CrossCheck, list[str]]:
    """A certified box of a loop with functions: :func:`cross_check_recast` at each of its random
    parameter points (``(the loop there, the point)``; the ``k``-th point's starts from
    ``[*seed, k]``), the figures merged (the worst of each, counts summed). Returns the merged check
    and, for every point where :func:`box_mismatch` says the certificates do not apply, why (those
    points are not simulated and not counted, except for a certified ``barrier`` or ``reach_avoid``:
    a claim about the model's sets and its true loop, which names no certificate function, is
    simulated there all the same, and the reason says so)."""
    out = CrossCheck()
    skipped: list[str] = []

    def merge(found: CrossCheck) -> None:
        out.points += found.points
        out.trajectories += found.trajectories
        out.not_converged += found.not_converged
        for attr in ("worst_rise", "worst_envelope", "ges_ratio", "unsafe_margin", "reach_ratio"):
            out.worse(attr, getattr(found, attr))
        for y, sup in found.sim_worst.items():
            out.sim_worst[y] = max(out.sim_worst.get(y, 0.0), sup)
        out.violations += found.violations

    for k, (model, point) in enumerate(points):
        why = box_mismatch(model, doc)
        if why is not None:
            where = ", ".join(f"{name} = {float(v):.6g}" for name, v in point.items())
            safety = {c: v for c, v in (doc.get("conditions") or {}).items()
                      if c in SAFETY_CLASSES and isinstance(v, dict) and v.get("status") == "certified"}
            if safety:
                merge(cross_check_recast(model, {**doc, "conditions": safety}, point, starts=starts, seed=(*seed, k)))
                why += f" ({' and '.join(safety)} simulated there all the same)"
            skipped.append(f"at {where}: {why}")
            continue
        merge(cross_check_recast(model, doc, point, starts=starts, seed=(*seed, k)))
    return out, skipped


#: the disturbance signals a certified ``sos_bound`` is simulated under: bang-bang against the sign
#: of the output, then square waves of these periods (s), each at the disturbance's bound
BOUND_SIGNAL_PERIODS: Final = (0.5, 2.0, 8.0)
#: the simulation (RK4): its horizon, step, and the time from which the tail sup is taken (s)
BOUND_HORIZON_S: Final = 120.0
BOUND_STEP_S: Final = 0.02
BOUND_TAIL_FROM_S: Final = 60.0


def _check_bound(model: RecastModel, cond: Mapping[str, Any], starts: int, seed: Sequence[int], where: str,
                 out: CrossCheck) -> None:
    """A certified ``sos_bound``: the true loop (``model.robust``, its disturbances as the last
    columns) from random starts of the comparison box, each disturbance a bang-bang or square-wave
    signal at its bound; the largest ``|y|`` after BOUND_TAIL_FROM_S is ``sim_worst`` and may not
    exceed the certified bound (beyond TRAJECTORY_CHECK_REL_TOL)."""
    from lyapcheck.models.classes.recast_classes import base_loop
    from lyapcheck.models.engines.recast_numeric import FloatLoop, poly_values
    from lyapcheck.models.surfaces.recast_run import comparison_box
    from lyapcheck.sos.polynomials import Ring
    from lyapcheck.tolerances import TRAJECTORY_CHECK_REL_TOL

    state_ring = Ring(model.states)

    robust = model.robust
    assert robust is not None
    bounds = np.array([float(b) for b in model.disturbances.values()])
    eq = np.array([float(v) for v in model.equilibrium])
    lo, hi = comparison_box(model, base_loop(model.system))
    rng = np.random.default_rng([*seed, 1])
    Z0 = lo + (hi - lo) * rng.random((max(starts, 1), model.n))
    field = FloatLoop(robust)
    for name, bound in (cond.get("bounds") or {}).items():
        y = model.outputs.get(name)
        if y is None:
            continue
        y_eq = float((cond.get("bounds_reference") or {}).get(name) or 0.0)  # the bound is on |y - y_eq|

        def output(X: np.ndarray) -> np.ndarray:
            return poly_values(state_ring, y, {s: X[:, k] for k, s in enumerate(model.states)}, len(X)) - y_eq

        policies = 1 + len(BOUND_SIGNAL_PERIODS)
        X = np.tile(Z0 + eq, (policies, 1))
        period = np.repeat([0.0, *BOUND_SIGNAL_PERIODS], len(Z0))
        worst = 0.0
        steps = int(round(BOUND_HORIZON_S / BOUND_STEP_S))
        with np.errstate(all="ignore"):
            for k in range(steps):
                t = k * BOUND_STEP_S
                wave = np.sign(np.sin(2 * np.pi * t / np.where(period > 0, period, 1.0)) + 1e-12)
                sign = np.where(period > 0, wave, np.sign(output(X) + 1e-12))
                D = sign[:, None] * bounds[None, :]

                def f(Y: np.ndarray) -> np.ndarray:
                    return field(np.column_stack([Y, D]))[:, :model.n]

                k1 = f(X)
                k2 = f(X + BOUND_STEP_S / 2 * k1)
                k3 = f(X + BOUND_STEP_S / 2 * k2)
                k4 = f(X + BOUND_STEP_S * k3)
                X = X + BOUND_STEP_S / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
                if t >= BOUND_TAIL_FROM_S:
                    values = np.abs(output(X))
                    worst = max(worst, float(np.max(np.where(np.isfinite(values), values, np.inf))))
        out.trajectories += len(X)
        out.sim_worst[name] = max(out.sim_worst.get(name, 0.0), worst)
        if worst > float(bound) * (1 + TRAJECTORY_CHECK_REL_TOL):
            out.violations.append(f"sos_bound at {where}: under a disturbance at its bounds "
                                  f"|{name}{f' - {y_eq:.6g}' if y_eq else ''}| reached "
                                  f"{worst:.6g} after {BOUND_TAIL_FROM_S:g} s, above the certified limsup "
                                  f"{float(bound):.6g}")


def _recast_runs(model: RecastModel) -> Runs:
    """The true loop's simulation for :func:`sweeps.crosscheck.check_sets`: escape as the
    falsification's (never in an angle), the barrier's horizon the falsification's of the true field."""
    from lyapcheck.models.classes.falsify import ESCAPE_FACTOR, default_horizon
    from lyapcheck.models.classes.recast_classes import angle_states

    eq = np.array([float(v) for v in model.equilibrium])
    angles = angle_states(model.system)

    def run(x0: np.ndarray, t_end: float | None,
            disturbances: np.ndarray | None) -> list[tuple[np.ndarray, np.ndarray]]:
        Z0 = x0 - eq
        extent = np.maximum(np.max(np.abs(Z0), axis=0), np.maximum(np.abs(eq), 1.0) * 1e-6)
        escape = np.array([np.inf if s in angles else ESCAPE_FACTOR * e for s, e in zip(model.states, extent)])
        horizon = default_horizon(model, extent, TrueField(model)) if t_end is None else t_end  # type: ignore[arg-type]
        if model.robust is None:  # no disturbance kept by the recasting: the nominal loop only
            disturbances = None
        runs = _simulate(model, Z0, escape, extent, t_end=horizon, disturbances=disturbances)
        return [(t, z + eq) for t, z in runs]

    return run


def _simulate(model: RecastModel, Z0: np.ndarray, escape: np.ndarray, extent: np.ndarray, *, t_end: float | None = None,
              disturbances: np.ndarray | None = None) -> list[tuple[np.ndarray, np.ndarray]]:
    """Integrate the true loop from the deviations ``Z0`` (rows) with the project's batched DOPRI5 over
    ``t_end`` (default :func:`lyapcheck.models.surfaces.simulate.crosscheck_horizon`): per row, its own
    points' times and deviations. A row farther than ``escape`` from the equilibrium in a state stops
    moving there. ``disturbances``: a constant value of each disturbance per row (None: all 0)."""
    from lyapcheck.models.engines.numeric import ModelSystem
    from lyapcheck.models.surfaces.simulate import crosscheck_horizon as default_horizon
    from lyapcheck.models.engines.trajectories import MIN_STEPS, RTOL
    from lyapcheck.integrator import integrate

    eq = np.array([float(v) for v in model.equilibrium])
    t_end = default_horizon(model) if t_end is None else t_end
    # the true field, with each row's disturbance where the recasting kept the disturbances
    field = TrueField(model)
    if disturbances is None or model.robust is None:
        batch = ModelSystem(field, len(Z0), escape=escape, center=eq)  # type: ignore[arg-type]
    else:
        table = np.asarray(disturbances, dtype=np.float64)
        batch = ModelSystem(field, len(Z0), disturbance=lambda t, y, index: table[index],  # type: ignore[arg-type]
                            escape=escape, center=eq)
    nodes = _Nodes()
    with np.errstate(all="ignore"):
        integrate(batch, 0.0, Z0 + eq, t_end, rtol=RTOL, atol=np.maximum(extent * 1e-7, 1e-300),
                  max_step=t_end / MIN_STEPS, observer=nodes)
    return [(t, y - eq) for t, y in nodes.rows(len(Z0))]


def _outcome(system: RecastSystem, end: np.ndarray, escape: np.ndarray, extent: float, modulo: tuple[str, ...]) -> str:
    """How a trajectory ended (its final deviation ``end``): ``escaped``, ``converged`` (within
    :data:`CONVERGED_FRACTION` of the starts' extent, modulo 2 pi in ``modulo``) or ``other``."""
    from lyapcheck.models.engines.recast_numeric import distances

    if not np.all(np.isfinite(end)) or np.any(np.abs(end) >= escape * (1 - 1e-9)):
        return "escaped"
    return "converged" if distances(system, end[None, :], modulo)[0] <= CONVERGED_FRACTION * extent else "other"


__all__ = ["cross_check_recast", "cross_check_recast_box", "box_mismatch", "GLOBAL_CLASSES", "REGION_CLASS"]
