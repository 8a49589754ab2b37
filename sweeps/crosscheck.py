"""The simulation cross-check of a certified point or box of a model file's sweep, on either loop kind.

One entry per job, each taking a polynomial or rational loop
(:class:`~lyapcheck.models.language.modelfile.Model`) or a loop with functions (sin, sqrt, sat, ...;
:class:`~lyapcheck.models.language.recast.RecastModel`): :func:`cross_check_point` (a grid point) and
:func:`cross_check_box` (random parameter points of a certified box, each simulated on the loop there; a
point of a loop with functions where the box's certificates are not functions of that loop's variables,
:func:`box_mismatch`, is not simulated, and the reason is returned to be stored). Every certified class of
the stored certificate is checked with the checks of :mod:`lyapcheck.models.engines.crosscheck`:

=====================  ===========================================  ==========================================
certificate            starts                                       must hold
=====================  ===========================================  ==========================================
``roa``, {V <= level}  random rays from the equilibrium, between    no escape; V never rises (on a polynomial
``candidate`` (alike)  half-way and just inside the set's boundary  loop, along every trajectory that starts
                       (with functions: within the certificate's    in the set, any start's)
                       ``box`` for a ball-arithmetic one, else
                       within the comparison box below)
``quadratic``,         uniform over the model's ``[domain]``; else  no escape; V never rises; ``V(t) <= V(0)
``sos_gas``            polynomial: twice the certificate's state    exp(-rate t)`` with a certified rate of V;
                       scales around x_eq; with functions: +-pi in  a GES certificate's ``|x(t) - x_eq| <= k
                       an angle and +-4 elsewhere (the comparison   |x0 - x_eq| exp(-rate t)``
                       box of the classes)
any class              its own simulation when it was certified     not flagged ``soundness_violation``
``sos_bound``          polynomial (with ``worst_case``): the        the tail sup of each output within its
                       worst-case disturbance search                certified bound (polynomial: beyond
                       (:func:`lyapcheck.models.surfaces.simulate.  :data:`sweeps.soundness.BOUND_REL_TOL`, and
                       search_worst_case`, its screening round);    no diverging disturbance; with functions:
                       with functions: uniform over the comparison  the largest ``|y|`` after 60 s, stored as
                       box, each disturbance bang-bang against      ``sim_worst_<y>``)
                       ``y``'s sign or a square wave at its bound,
                       RK4, 120 s
``barrier``,           random points of ``[sets] initial``          never in ``unsafe``; ``reach_avoid``: in
``reach_avoid``        (:func:`check_sets`: a quarter on its        ``goal`` by ``reach_time_bound_s``, not in
                       boundary), each at every disturbance 0 and,  ``unsafe`` before it
                       for a claim over every disturbance, at each
                       vertex of the disturbance box held constant
                       (at most :data:`MAX_VERTICES`)
=====================  ===========================================  ==========================================

A ``candidate`` (the user's V, a sweep's ``[sweep] candidate``) is checked as ``roa`` where it certified a
level, and as ``quadratic`` where it certified GAS (no level: a global V, with its certified rate of V).

Safety (:func:`check_sets`): simulated over the falsification's horizon
(:func:`lyapcheck.models.classes.falsify.default_horizon`; both classes read the same trajectories); when a
reach-avoid's trajectory is not in the goal by then and the bound is beyond it, all are simulated again to just
past the bound (:func:`lyapcheck.models.engines.crosscheck.check_safety`,
:func:`~lyapcheck.models.engines.crosscheck.check_reach_avoid`). Figures: ``unsafe_margin`` (the largest
unsafe margin reached, each inequality relative to the size of its terms:
:func:`~lyapcheck.models.engines.crosscheck.scaled_margin`; ``< 0`` none entered) and ``reach_ratio`` (the
latest time before the goal over the bound).

What differs between the kinds is how the loop is simulated and V evaluated in floating point, behind
:class:`SimulatedLoop` (:class:`_PolynomialLoop`, :class:`_FunctionsLoop`, :class:`_MapLoop`):

* a discrete-time map (``[model] time = "discrete"``, polynomial or with functions) is never integrated: it
  is iterated (:func:`lyapcheck.models.surfaces.iterate.iterate`, :data:`MAP_STEPS` steps), the step number
  standing for the time. The checks are the iterated analogues: from a start in a certified ``{V <= level}``
  V never rises from one step to the next and no iterate escapes; a global V (``quadratic``, ``sos_gas``
  on a map) never rises, ``V(e_k) <= (1 - mu)^k V(e_0)`` with its certified ``mu`` per step, and a GES
  map's ``|e_k| <= k |e_0| r^k``. ``barrier`` and ``reach_avoid`` on a map (:func:`check_sets`) read the
  iterates of starts in the initial set: no iterate in the unsafe set; some iterate ``e_k`` with ``k <=``
  the certified ``reach_steps_bound`` in the goal and none unsafe before it (:func:`map_reach_avoid`:
  steps are counted exactly), iterated on to the bound when :data:`MAP_STEPS` did not tell. A map's
  ``sos_bound`` (:meth:`_MapLoop.check_bound`) is iterated under disturbance sequences within its bounds
  (uniform random, bang-bang, each vertex held constant; :func:`map_disturbances`) from the fixed point and
  random starts (a map with functions: its true map, each function by numpy, :func:`iterate_disturbed`; its
  V read over the states from the certificate's ``variables``): each output stays within the certificate's envelope ``bound^2 + lam^k max(V(e_0) - 1, 0)``
  at every step, and ``sim_worst_<y>`` is the tail sup of ``|y - y_eq|``. Over a box (``mode = "boxes"``)
  the box's corners and random points are iterated alike (a box's V, its set {V <= c} and its bound's V are
  each one function of the states for every value of the box: ``roa`` from starts in the certified set,
  ``sos_bound`` within its envelope under disturbances), and a ``linearization`` over the box (one ``P`` for
  every Jacobian of the box) is checked along the iterates of the map's Jacobian at each of them
  (:meth:`_MapLoop.check_box_linearization`; on a map with functions, its true map iterated at each point,
  :meth:`_MapLoop.check_ball_linearization`: the exact Jacobian there, else the true map from tiny starts);

* a polynomial loop is integrated on its own field, over :func:`lyapcheck.models.engines.trajectories.horizon`
  of its linearization; a V is the certificate's exact polynomial (over a box, at the point's own
  parameter values) in the certificate's scaled states
  (:func:`lyapcheck.models.engines.crosscheck.certificate_function`). Its global starts are drawn once for
  all global certificates, and each certificate reads every trajectory that starts in its set;
* a loop with functions is integrated on its true field, each function evaluated by numpy
  (:class:`lyapcheck.models.engines.recast_numeric.TrueField`), never the recast polynomial loop, which
  holds only on its relations' set, over :func:`lyapcheck.models.surfaces.simulate.crosscheck_horizon`;
  a V is the certificate's polynomial in its ``variables`` (the states, then the auxiliaries), each
  shifted by the certificate's ``shift``, at the true auxiliaries of the simulated states. Each certificate
  reads its own starts. An angle state (one the loop sees only through its sine and cosine) is never an
  escape: on the cylinder the loop may turn several times before it settles; converged is taken modulo
  2 pi in the angles the certificate's claim is modulo.

The random starts of a point come from ``numpy.random.default_rng``: on a polynomial loop one stream,
``[*seed, k]`` for the ``k``-th point of a box (``[*seed, 0]`` at a grid point), read by the Lyapunov
classes then the safety ones; on a loop with functions three, ``[*prefix, 0]`` (Lyapunov classes),
``[*prefix, 1]`` (``sos_bound``) and ``[*prefix, 2]`` (safety), with ``prefix`` the grid point's seed or
``(*seed, k)`` in a box (the draws of the two modules this one replaced, so that a stored sweep
reproduces). A point's result does not depend on the unit it was grouped in.

Trajectories not at the equilibrium by the horizon are counted (``not_converged``): a finite simulation
cannot refute convergence, so this is a figure; a certified decay rate (V's, or a GES envelope) is what
makes slow convergence a violation. Any breach is a soundness violation, with a one-line detail.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from fractions import Fraction
from functools import cached_property
from typing import TYPE_CHECKING, Any, Callable, Final, Mapping, Optional, Protocol, Sequence

import numpy as np

from lyapcheck.models.language.modelfile import Model
from sweeps.soundness import BOUND_REL_TOL, WORST_CASE_SCREENING_ONLY

if TYPE_CHECKING:
    from lyapcheck.models.language.recast import RecastModel

#: trajectories leave the cross-check's box only this many start extents from the equilibrium (a
#: trajectory under a certificate stays in a sublevel set of V through its start, which may reach
#: well beyond the starts' box: the escape box is generous so that an escape means divergence)
ESCAPE_EXTENTS: Final = 30.0
#: converged: the final state within this fraction of the starts' extent of the equilibrium
CONVERGED_FRACTION: Final = 1e-3
#: starts of a region of attraction: between these fractions of the way to the set's boundary
REGION_FRACTIONS: Final = (0.5, 0.999)
#: the global starts' box of a polynomial loop without a [domain]: this many certificate state scales around x_eq
DEFAULT_REGION_SCALES: Final = 2.0
#: a discrete-time map's cross-check: the iterations from every start (its certified maps contract
#: geometrically; a sampled loop's map, which moves little per step, reaches the fixed point within them too)
MAP_STEPS: Final = 400
#: a map's ``reach_avoid`` whose goal an iterate has not reached within :data:`MAP_STEPS` steps is iterated
#: on to its certified ``reach_steps_bound``, at most this many steps (beyond it a late start is not seen:
#: a figure missed, never a false alarm)
MAP_REACH_MAX_STEPS: Final = 20_000
#: a map's ``sos_bound``: the steps of the tail whose sup of each output is ``sim_worst_<y>`` (the last ones
#: of :data:`MAP_STEPS`); the certified envelope is checked at every step
MAP_BOUND_TAIL_STEPS: Final = 200
#: a map's linearization over a box (``method`` ``box_stein``,
#: :data:`lyapcheck.models.classes.discrete_lyapunov.BOX_STEIN_METHOD`): its quadratic ``V = e^T P e`` is
#: checked along this many iterates of the map's Jacobian at each checked parameter point
MAP_LINEAR_STEPS: Final = 60
#: a map with functions' linearization over a box without an exact Jacobian: the true map is iterated from
#: starts this far from the fixed point (its nonlinear part changes V's steps by a relative ~1e-7 there)
MAP_TINY_START: Final = 1e-7
#: the classes whose V is simulated (the global ones, then the region), and those simulated from the
#: initial set (:func:`check_sets`)
GLOBAL_CLASSES: Final = ("quadratic", "sos_gas")
REGION_CLASS: Final = "roa"
#: the classes certifying a set {V <= level} (``candidate``: the user's V, a sweep's ``[sweep] candidate``),
#: each cross-checked as ``roa``'s: starts inside the set, none may leave it nor V rise
REGION_CLASSES: Final = (REGION_CLASS, "candidate")
SAFETY_CLASSES: Final = ("barrier", "reach_avoid")
#: the vertices of the disturbance box held constant for a claim over every disturbance (2**m, at most this many)
MAX_VERTICES: Final = 8
#: a loop with functions' ``sos_bound``: the disturbance signals (bang-bang against the sign of the
#: output, then square waves of these periods, s, each at the disturbance's bound), the simulation
#: (RK4): its horizon, step, and the time from which the tail sup is taken (s)
BOUND_SIGNAL_PERIODS: Final = (0.5, 2.0, 8.0)
BOUND_HORIZON_S: Final = 120.0
BOUND_STEP_S: Final = 0.02
BOUND_TAIL_FROM_S: Final = 60.0
#: a loop's simulation for :func:`check_sets`: ``run(starts, t_end, disturbances)`` with starts ``(k, n)``
#: (declared states), ``t_end`` in s (None: the loop's falsification horizon) and a constant disturbance
#: per row ``(k, m)`` (None: all 0); per row the times and states of the integrator's own points
Runs = Callable[[np.ndarray, Optional[float], Optional[np.ndarray]], list[tuple[np.ndarray, np.ndarray]]]
#: a float function of a batch of points ``(k, n)``: ``(k,)`` values
PointFunction = Callable[[np.ndarray], np.ndarray]
#: the end of trajectory ``i`` checked against a claim modulo 2 pi in the given angles: ``converged``,
#: ``escaped`` or ``other``
Outcome = Callable[[int, tuple[str, ...]], str]


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
    """A certified V of the document at one parameter point."""

    cls: str
    V: PointFunction  # of the loop's scaled deviations u (SimulatedLoop.scales)
    region: PointFunction | None = None  # roa: V where the rays look for the set's boundary
    level: float = math.nan  # roa
    rate: float = 0.0  # certified decay rate of V, 1/s
    k: float = math.nan  # GES envelope
    ges_rate: float = math.nan
    angles: tuple[str, ...] = ()  # the claim holds modulo 2 pi in these states

    @property
    def bounded(self) -> bool:
        """A set {V <= level} (roa; a candidate with a level), not a global V (a candidate may prove GAS)."""
        return not math.isnan(self.level)


class SimulatedLoop(Protocol):
    """One loop kind at one parameter point, in floating point: all that differs between the kinds.

    ``model`` is the loop there (``states``, ``n``, ``equilibrium``, ``domain``, ``disturbances``,
    ``sets``). V-s are functions of ``u = (x - x_eq) / scales`` (rays are drawn there); starts are rows
    in the loop's own frame (:meth:`start`, :meth:`global_box`), which :meth:`simulate` takes."""

    model: Any
    scales: np.ndarray
    #: True: the global starts are drawn once for every global V, and each V reads every trajectory that
    #: starts in its set; False: each V its own starts
    pooled: bool

    def streams(self, seed: Sequence[int], index: int | None) -> tuple[np.random.Generator, ...]:
        """The random streams (the Lyapunov classes', sos_bound's, the safety classes'; module doc) of the
        ``index``-th point of a box job, or of a grid point's job (None)."""

    def functions(self, cls: str, cert: Mapping[str, Any]) -> tuple[PointFunction, PointFunction | None,
                                                                     tuple[str, ...]]:
        """A certificate's V, the V its set's rays read (roa), and the angles its claim is modulo."""

    def start(self, u: np.ndarray) -> np.ndarray:
        """Starts at the scaled deviations ``u``."""

    def global_box(self) -> tuple[np.ndarray, np.ndarray]:
        """The box the global starts are drawn uniformly from."""

    def simulate(self, starts: np.ndarray) -> tuple[list[tuple[np.ndarray, np.ndarray]], Outcome]:
        """Per start the times and deviations ``x - x_eq`` of the integrator's own points, and how each ended."""

    def runs(self) -> Runs:
        """The simulation :func:`check_sets` takes."""

    def check_bound(self, cond: Mapping[str, Any], where: str, rng: np.random.Generator, starts: int,
                    worst_case: bool, out: CrossCheck) -> None:
        """A certified ``sos_bound`` against simulated disturbances."""


def _point_text(point: Mapping[str, Fraction]) -> str:
    return ", ".join(f"{k} = {float(v):.6g}" for k, v in point.items())


def _loop(model: Any, doc: Mapping[str, Any], point: Mapping[str, Fraction]) -> SimulatedLoop:
    from lyapcheck.models.loop.discrete import is_discrete

    if is_discrete(model):  # a map is iterated, never integrated as a field
        return _MapLoop(model, point, doc)
    return _PolynomialLoop(model, doc, point) if isinstance(model, Model) else _FunctionsLoop(model)


def cross_check_point(model: Model | RecastModel, doc: Mapping[str, Any], point: Mapping[str, Fraction], *,
                      starts: int, seed: Sequence[int], worst_case: bool = True) -> CrossCheck:
    """Simulate the loop ``model`` at the parameter point ``point`` against the certificate document ``doc``.

    Parameters
    ----------
    model
        A polynomial or rational loop (its parameters are set to ``point`` here), or a loop with
        functions read at the point (:meth:`sweeps.spec.ModelSweepSpec.model_at`).
    doc
        Its certificate document (:func:`lyapcheck.models.surfaces.certificate.build_document`,
        :func:`lyapcheck.models.surfaces.certify.certify_model`).
    point
        The swept parameters' exact values (named in a violation's detail).
    starts
        Starts per certified set.
    seed
        The random starts' seed (module doc).
    worst_case
        Run the worst-case disturbance search against a polynomial loop's ``sos_bound``.
    """
    out = CrossCheck()
    loop = _loop(model, doc, point)
    _check(loop, doc, _point_text(point), loop.streams(seed, None), starts, worst_case, out)
    return out


def cross_check_box(points: Sequence[tuple[Model | RecastModel, Mapping[str, Fraction]]], doc: Mapping[str, Any], *,
                    starts: int, seed: Sequence[int], worst_case: bool = True) -> tuple[CrossCheck, list[str]]:
    """A certified box: :func:`cross_check_point` at each of its random parameter points (``(the loop
    there, the point)``, as that function takes them; the ``k``-th point's starts from ``seed`` and ``k``,
    module doc), the figures merged (the worst of each, counts summed). Returns the merged check and,
    for every point where :func:`box_mismatch` says the certificates do not apply, why (those points are
    not simulated and not counted, except for a certified ``barrier`` or ``reach_avoid``: a claim about
    the model's sets and its true loop, which names no certificate function, is simulated there all the
    same, and the reason says so)."""
    out = CrossCheck()
    skipped: list[str] = []
    for k, (model, point) in enumerate(points):
        where = _point_text(point)
        checked = doc
        why = box_mismatch(model, doc)
        if why is not None:
            safety = {c: v for c, v in (doc.get("conditions") or {}).items()
                      if c in SAFETY_CLASSES and isinstance(v, dict) and v.get("status") == "certified"}
            if safety:
                checked = {**doc, "conditions": safety}
                why += f" ({' and '.join(safety)} simulated there all the same)"
            skipped.append(f"at {where}: {why}")
            if not safety:
                continue
        loop = _loop(model, checked, point)
        _check(loop, checked, where, loop.streams(seed, k), starts, worst_case, out)
    return out, skipped


def _check(loop: SimulatedLoop, doc: Mapping[str, Any], where: str, streams: tuple[np.random.Generator, ...],
           starts: int, worst_case: bool, out: CrossCheck) -> None:
    """Every certified class of ``doc`` at one point of ``loop`` (module doc), into ``out``."""
    lyapunov, bound, safety = streams
    conditions = {name: c for name, c in (doc.get("conditions") or {}).items()
                  if isinstance(c, dict) and c.get("status") == "certified"}
    out.points += 1
    for name, cond in conditions.items():  # the simulation beside the proof contradicted it
        if cond.get("soundness_violation"):
            found = ("a trajectory into the unsafe set" if name in SAFETY_CLASSES else
                     f"{cond.get('starts_in_set_not_converged', 'some')} starts in the set that did not converge")
            out.violations.append(f"{name} at {where}: its own simulation when certified found {found}")
    sets = [_certified_set(loop, cls, conditions[cls]) for cls in (*GLOBAL_CLASSES, *REGION_CLASSES) if cls in conditions]
    if sets:
        _trajectories(loop, sets, lyapunov, starts, where, out)
    check_sets(loop.model, doc, where, safety, starts, loop.runs(), out)
    if "sos_bound" in conditions:
        loop.check_bound(conditions["sos_bound"], where, bound, starts, worst_case, out)
    if isinstance(loop, _MapLoop) and "linearization" in conditions:
        from lyapcheck.models.classes.discrete_functions_box import METHOD as BALL_STEIN_METHOD
        from lyapcheck.models.classes.discrete_lyapunov import BOX_STEIN_METHOD

        method = (conditions["linearization"].get("certificate") or {}).get("method")
        if method == BOX_STEIN_METHOD:
            loop.check_box_linearization(conditions["linearization"], where, lyapunov, starts, out)
        elif method == BALL_STEIN_METHOD:
            loop.check_ball_linearization(conditions["linearization"], where, lyapunov, starts, out)


def _certified_set(loop: SimulatedLoop, cls: str, cond: Mapping[str, Any]) -> _Set:
    cert = cond.get("certificate") or {}
    V, region, angles = loop.functions(cls, cert)
    if cls in REGION_CLASSES and "level" in cert:  # (a candidate certified globally has none: a global V)
        return _Set(cls, V, region, level=float(Fraction(str(cert["level"]))), angles=angles)
    if isinstance(loop, _MapLoop):  # per step: V(e_k) <= (1 - mu)^k V(e_0), |e_k| <= k |e_0| r^k, as exp(-rate k)
        rate = _per_step_rate(1 - float(cond.get("decay_rate_V_per_step") or 0.0))
        if cond.get("property") == "GES" and cond.get("k") is not None and cond.get("contraction_per_step") is not None:
            return _Set(cls, V, rate=rate, k=float(cond["k"]),
                        ges_rate=_per_step_rate(float(cond["contraction_per_step"])))
        return _Set(cls, V, rate=rate)
    rate = float(cond.get("decay_rate_V_per_s") or 0.0)
    if cond.get("property") == "GES" and cond.get("k") is not None and cond.get("decay_rate_per_s") is not None:
        return _Set(cls, V, rate=rate, k=float(cond["k"]), ges_rate=float(cond["decay_rate_per_s"]), angles=angles)
    return _Set(cls, V, rate=rate, angles=angles)


def _uniform(box: tuple[np.ndarray, np.ndarray], rng: np.random.Generator, count: int) -> np.ndarray:
    lo, hi = box
    return np.asarray(lo + (hi - lo) * rng.random((count, lo.size)), dtype=np.float64)


def _trajectories(loop: SimulatedLoop, sets: Sequence[_Set], rng: np.random.Generator, starts: int, where: str,
                  out: CrossCheck) -> None:
    """The Lyapunov-type certificates (``roa``, ``quadratic``, ``sos_gas``) against trajectories of ``loop``."""
    from lyapcheck.models.engines.crosscheck import check_ges_envelope, check_global, check_region, ray_boundary
    from lyapcheck.tolerances import TRAJECTORY_CHECK_REL_TOL

    n = loop.model.n
    blocks: list[np.ndarray] = []
    owner: list[int] = []  # which set a start was drawn for (-1: a global start of every global set)
    for k, st in enumerate(sets):
        if not st.bounded:
            if not loop.pooled:
                blocks.append(_uniform(loop.global_box(), rng, starts))
                owner += [k] * starts
            continue
        assert st.region is not None
        directions = rng.standard_normal((starts, n))
        directions /= np.maximum(np.linalg.norm(directions, axis=1, keepdims=True), 1e-300)
        boundary = ray_boundary(st.region, st.level, directions)
        if boundary is None:
            out.violations.append(f"{st.cls} at {where}: the certified set {{V <= {st.level:.6g}}} does not contain the "
                                  "equilibrium or is unbounded")
            continue
        blocks.append(loop.start(np.asarray(boundary * rng.uniform(*REGION_FRACTIONS, size=(starts, 1)),
                                            dtype=np.float64)))
        owner += [k] * starts
    if loop.pooled and any(not st.bounded for st in sets):
        blocks.append(_uniform(loop.global_box(), rng, starts))
        owner += [-1] * starts
    if not blocks:
        return
    nodes, outcome = loop.simulate(np.vstack(blocks))
    out.trajectories += len(nodes)
    out.not_converged += sum(outcome(i, sets[k].angles if k >= 0 else ()) == "other" for i, k in enumerate(owner))
    u_paths = [z / loop.scales for _, z in nodes]
    for k, st in enumerate(sets):
        if not loop.pooled:
            rows = [i for i, mine in enumerate(owner) if mine == k]
        elif st.bounded:  # every trajectory that starts in the set
            rows = [i for i, u in enumerate(u_paths) if owner[i] == k or st.V(u[:1])[0] <= st.level]
        else:
            rows = list(range(len(nodes)))
        if not rows:
            continue
        outcomes = [outcome(i, st.angles) for i in rows]
        if st.bounded:
            found = check_region([st.V(u_paths[i]) for i in rows], outcomes)
            out.worse("worst_rise", found.worst_rise)
            if not found.ok:
                out.violations.append(f"{st.cls} at {where}: of {found.starts} starts in {{V <= {st.level:.6g}}}, "
                                      f"{found.escaped} escaped; V rose by {found.worst_rise:.3g} of V(0)")
            continue
        glob = check_global([(nodes[i][0], st.V(u_paths[i])) for i in rows], outcomes, st.rate)
        out.worse("worst_rise", glob.worst_rise)
        if st.rate > 0:
            out.worse("worst_envelope", glob.worst_envelope)
        if not glob.ok:
            out.violations.append(f"{st.cls} at {where}: of {glob.trajectories} trajectories {glob.escaped} escaped; "
                                  f"V rose by {glob.worst_rise:.3g} and exceeded V(0) exp(-{st.rate:.4g} t) by "
                                  f"{glob.worst_envelope:.3g} of V(0)")
        if math.isfinite(st.k):
            ratio = check_ges_envelope([(nodes[i][0], np.linalg.norm(nodes[i][1], axis=1)) for i in rows], st.k,
                                       st.ges_rate)
            out.worse("ges_ratio", ratio)
            if ratio > 1 + TRAJECTORY_CHECK_REL_TOL:
                out.violations.append(f"{st.cls} at {where}: |x(t)| reached {ratio:.6g} times the certified GES "
                                      f"envelope {st.k:.4g} |x0| exp(-{st.ges_rate:.4g} t)")


class _PolynomialLoop:
    """A polynomial or rational loop at a parameter point (module doc)."""

    pooled = True

    def __init__(self, model: Model, doc: Mapping[str, Any], point: Mapping[str, Fraction]) -> None:
        from lyapcheck.models.language.modelfile import with_parameters

        self.model = with_parameters(model, dict(point))
        self.point = point
        #: the certificate's variables: the states, then a box's parameters
        self.names = list(model.states) + list((doc.get("box") or {}).keys())
        scaling = (doc.get("field") or {}).get("scaling") or {}
        self.exact_scales = [Fraction(str(s)) for s in scaling.get("states", [])] or [Fraction(1)] * model.n
        self.scales = np.array([float(v) for v in self.exact_scales])
        self.eq = np.array([float(v) for v in self.model.equilibrium])

    def streams(self, seed: Sequence[int], index: int | None) -> tuple[np.random.Generator, ...]:
        rng = np.random.default_rng([*seed, 0 if index is None else index])
        return rng, rng, rng

    def functions(self, cls: str, cert: Mapping[str, Any]) -> tuple[PointFunction, PointFunction | None,
                                                                     tuple[str, ...]]:
        from lyapcheck.models.engines.crosscheck import certificate_function

        V = certificate_function(cert["V"], self.names, self.model.n, self.point, self.exact_scales)
        return V, V, ()

    def start(self, u: np.ndarray) -> np.ndarray:
        return self.eq + self.scales * u

    def global_box(self) -> tuple[np.ndarray, np.ndarray]:
        model = self.model
        if model.domain:
            return (np.array([float(model.domain[x][0]) for x in model.states]),
                    np.array([float(model.domain[x][1]) for x in model.states]))
        return self.eq - DEFAULT_REGION_SCALES * self.scales, self.eq + DEFAULT_REGION_SCALES * self.scales

    def simulate(self, starts: np.ndarray) -> tuple[list[tuple[np.ndarray, np.ndarray]], Outcome]:
        from lyapcheck.models.engines.numeric import FieldEvaluator
        from lyapcheck.models.engines.trajectories import horizon, jacobian_eigenvalues, simulate

        eq = self.eq
        half = np.maximum(np.max(np.abs(starts - eq), axis=0), self.scales * 1e-6)
        t_end = horizon(jacobian_eigenvalues(FieldEvaluator.of(self.model), eq, half))
        runs = simulate(self.model, starts, t_end=t_end, half_widths=half, escape_factor=ESCAPE_EXTENTS,
                        converged_fraction=CONVERGED_FRACTION)
        return [(t, x - eq) for t, x in (tr.nodes for tr in runs)], lambda i, angles: runs[i].outcome

    def runs(self) -> Runs:
        """The project's integrator (:func:`lyapcheck.models.engines.trajectories.simulate`), escape as
        the falsification's."""
        from lyapcheck.models.classes.falsify import ESCAPE_FACTOR, default_horizon
        from lyapcheck.models.engines.trajectories import simulate

        model, eq = self.model, self.eq

        def run(x0: np.ndarray, t_end: float | None,
                disturbances: np.ndarray | None) -> list[tuple[np.ndarray, np.ndarray]]:
            half = np.maximum(np.max(np.abs(x0 - eq), axis=0), np.maximum(np.abs(eq), 1.0) * 1e-6)
            horizon = default_horizon(model, half) if t_end is None else t_end
            with np.errstate(all="ignore"):
                runs = simulate(model, x0, t_end=horizon, half_widths=half, disturbances=disturbances,
                                escape_factor=ESCAPE_FACTOR)
            return [tr.nodes for tr in runs]

        return run

    def check_bound(self, cond: Mapping[str, Any], where: str, rng: np.random.Generator, starts: int,
                    worst_case: bool, out: CrossCheck) -> None:
        """The worst case found against each bound (with ``worst_case``). A bound is on ``|y - y_eq|``
        (``bounds_reference``: each ``y_eq``), the search's figure on ``|y|``: by the triangle inequality
        ``|y| <= |y_eq| + bound`` is what the bound implies, so only beyond that is a violation shown
        (never a false alarm)."""
        from lyapcheck.models.engines.crosscheck import bound_exceeded
        from lyapcheck.models.surfaces.simulate import search_worst_case

        bounds = cond.get("bounds")
        if not bounds or not worst_case:
            return
        references = cond.get("bounds_reference") or {}
        found = search_worst_case(self.model, budget_s=WORST_CASE_SCREENING_ONLY)
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
                out.violations.append(f"sos_bound at {where}: the worst case found, limsup |{name}| >= "
                                      f"{float(sup):.6g}, exceeds the certified bound {float(bound):.6g}{extra}")


def _per_step_rate(factor: float) -> float:
    """A certified factor per step (``0 < factor <= 1``) as the rate of ``exp(-rate k)``; 0 when none."""
    return -math.log(factor) if 0 < factor < 1 else 0.0


class _MapLoop:
    """A discrete-time map (``[model] time = "discrete"``, polynomial or with functions) at a parameter point:
    iterated by :func:`lyapcheck.models.surfaces.iterate.iterate` (the iterator of ``simulate``), never
    integrated. A "trajectory" is the sequence of iterates over :data:`MAP_STEPS` steps, its "times" the step
    numbers, so the checks of :func:`_trajectories` read as their iterated analogues: V never rises from one
    step to the next, a certified rate per step bounds ``V(e_k)`` (and a GES map's ``|e_k|``), none escapes.
    V-s are in the declared shifted states (a map's certificates have no scaling): ``discrete_sublevel``,
    ``discrete_quadratic`` and ``discrete_sos`` polynomials, ``discrete_interval``'s ``e^T P e``."""

    pooled = True

    def __init__(self, model: Model | RecastModel, point: Mapping[str, Fraction],
                 doc: Mapping[str, Any] | None = None) -> None:
        from lyapcheck.models.language.modelfile import with_parameters

        self.model = with_parameters(model, dict(point)) if isinstance(model, Model) else model
        self.point = point
        #: a certificate's variables: the states, then a box's parameters (at exponent 0 in a map's V: one V
        #: for every value of the box)
        self.names = list(model.states) + [str(k) for k in (doc or {}).get("box") or {}]
        self.scales = np.ones(model.n)
        self.eq = np.array([float(v) for v in self.model.equilibrium])

    def streams(self, seed: Sequence[int], index: int | None) -> tuple[np.random.Generator, ...]:
        rng = np.random.default_rng([*seed, 0 if index is None else index])
        return rng, rng, rng

    def functions(self, cls: str, cert: Mapping[str, Any]) -> tuple[PointFunction, PointFunction | None,
                                                                     tuple[str, ...]]:
        from lyapcheck.models.engines.crosscheck import certificate_function

        if cert.get("kind") == "discrete_interval":
            P = np.array([[float(Fraction(str(v))) for v in row] for row in cert["P"]], dtype=np.float64)

            def quadratic(e: np.ndarray) -> np.ndarray:
                return np.asarray(np.einsum("ki,ij,kj->k", e, P, e), dtype=np.float64)
            return quadratic, quadratic, ()
        n = self.model.n
        V = certificate_function(cert["V"], self.names, n, {k: self.point[k] for k in self.names[n:]},
                                 [Fraction(1)] * n)
        return V, V, ()

    def start(self, u: np.ndarray) -> np.ndarray:
        return self.eq + u

    def global_box(self) -> tuple[np.ndarray, np.ndarray]:
        model = self.model
        if model.domain:
            return (np.array([float(model.domain[x][0]) for x in model.states]),
                    np.array([float(model.domain[x][1]) for x in model.states]))
        return self.eq - DEFAULT_REGION_SCALES, self.eq + DEFAULT_REGION_SCALES

    def simulate(self, starts: np.ndarray) -> tuple[list[tuple[np.ndarray, np.ndarray]], Outcome]:
        """The iterates over :data:`MAP_STEPS` steps: escaped where the iterator stopped a row (it left
        :data:`~lyapcheck.models.surfaces.simulate.ESCAPE_FACTOR` state scales or is not finite), converged
        within :data:`CONVERGED_FRACTION` of the starts' extent."""
        from lyapcheck.models.surfaces.iterate import iterate

        paths = iterate(self.model, starts, MAP_STEPS)
        eq = self.eq
        radius = CONVERGED_FRACTION * float(np.linalg.norm(np.maximum(np.max(np.abs(starts - eq), axis=0), 1e-6)))
        nodes = []
        for path in paths:
            finite = path[np.all(np.isfinite(path), axis=1)]
            nodes.append((np.arange(len(finite), dtype=np.float64), finite - eq))
        escaped = [not np.all(np.isfinite(path[-1])) for path in paths]

        def outcome(i: int, angles: tuple[str, ...]) -> str:
            if escaped[i]:
                return "escaped"
            return "converged" if float(np.linalg.norm(nodes[i][1][-1])) <= radius else "other"

        return nodes, outcome

    def runs(self) -> Runs:
        """The iterates of each start (:func:`lyapcheck.models.engines.iteration.iterate_map` through
        :func:`lyapcheck.models.surfaces.iterate.iterate`, every disturbance 0: a map's claims are nominal),
        the step numbers standing for the times: over :data:`MAP_STEPS` steps (``t_end`` None), else
        ``ceil(t_end)`` steps, at most :data:`MAP_REACH_MAX_STEPS`. A row that left the escape box or is not
        finite ends at its last finite iterate."""
        from lyapcheck.models.surfaces.iterate import iterate

        model = self.model

        def run(x0: np.ndarray, t_end: float | None,
                disturbances: np.ndarray | None) -> list[tuple[np.ndarray, np.ndarray]]:
            if disturbances is not None and np.any(disturbances != 0):
                raise ValueError("a discrete-time map is iterated with every disturbance 0")
            steps = MAP_STEPS if t_end is None else min(max(int(math.ceil(t_end)), 1), MAP_REACH_MAX_STEPS)
            out = []
            for path in iterate(model, x0, steps):
                finite = path[np.all(np.isfinite(path), axis=1)]
                out.append((np.arange(len(finite), dtype=np.float64), finite))
            return out
        return run

    def check_bound(self, cond: Mapping[str, Any], where: str, rng: np.random.Generator, starts: int,
                    worst_case: bool, out: CrossCheck) -> None:
        """A map's certified ``sos_bound`` (``limsup_k |y_k - y_eq| <= bound`` for every disturbance sequence
        within its bounds) against the map iterated :data:`MAP_STEPS` steps, always (iterating is cheap:
        ``worst_case`` is the continuous loop's search), from the fixed point and ``starts`` uniform points of
        :meth:`global_box`, under each disturbance policy of :func:`map_disturbances` (uniform random,
        bang-bang at the bounds, each vertex held constant). Along every sequence each output must stay within
        the certified envelope ``|y_k - y_eq|^2 <= bound^2 + lam^k max(V(e_0) - 1, 0)`` (the certificate's step
        identity by induction; ``bound^2`` alone on its tail when its ``V`` or ``lam`` cannot be read), up to
        :data:`~lyapcheck.tolerances.TRAJECTORY_CHECK_REL_TOL`; ``sim_worst_<y>`` is the largest
        ``|y_k - y_eq|`` over the last :data:`MAP_BOUND_TAIL_STEPS` steps. A map with functions is its true map
        (:func:`iterate_disturbed`), its ``V`` read over the states from the certificate's ``variables``
        (:func:`_over_states`)."""
        from lyapcheck.models.classes.map_relations import NotTaken
        from lyapcheck.tolerances import TRAJECTORY_CHECK_REL_TOL

        if not cond.get("bounds"):
            return
        model = self.model
        bounds = np.array([float(b) for b in model.disturbances.values()])
        lo, hi = self.global_box()
        X0 = np.vstack([self.eq[None, :], lo + (hi - lo) * rng.random((max(starts, 1), model.n))])
        policies = map_disturbances(bounds, len(X0), MAP_STEPS, rng)
        X = np.tile(X0, (len(policies), 1))
        D = np.concatenate(policies, axis=1)  # (steps, rows, m)
        try:
            xs = iterate_disturbed(model, X, D)
        except NotTaken as exc:  # (the class that certified it recast the map so: a document of another map)
            out.violations.append(f"sos_bound at {where}: certified, but its map cannot be iterated under its "
                                  f"disturbances ({exc})")
            return
        out.trajectories += len(X)
        ys = map_outputs(model, xs)
        cert = cond.get("certificate") or {}
        certs = cert.get("outputs") or {}
        dists, box = list(model.disturbances), {k: self.point[k] for k in self.names[model.n:]}
        if not isinstance(model, Model):  # V over the recasting's variables: read over the states alone
            certs = {name: _over_states(c, cert.get("variables") or (), model.states) for name, c in certs.items()}
            dists, box = [], {}
        references = cond.get("bounds_reference") or {}
        for name, stated in cond["bounds"].items():
            if name not in ys:
                continue
            y = np.abs(ys[name] - float(references.get(name) or 0.0))  # (rows, steps + 1)
            envelope = _bound_envelope(certs.get(name), float(stated), xs - self.eq, list(model.states), dists, box)
            tail = y[:, -MAP_BOUND_TAIL_STEPS:]
            finite = np.where(np.isfinite(tail), tail, -np.inf)
            worst = float(np.max(finite)) if finite.size else -math.inf
            if math.isfinite(worst):
                out.sim_worst[name] = max(out.sim_worst.get(name, -math.inf), worst)
            with np.errstate(invalid="ignore"):
                excess = np.where(np.isfinite(y) & np.isfinite(envelope),
                                  y - envelope * (1 + TRAJECTORY_CHECK_REL_TOL), -1.0)
            if np.any(excess > 0):
                r, k = (int(i) for i in np.unravel_index(int(np.argmax(excess)), excess.shape))
                start = ", ".join(f"{s} = {v:.6g}" for s, v in zip(model.states, X[r]))
                policy = MAP_POLICY_NAMES[min(r // len(X0), len(MAP_POLICY_NAMES) - 1)]
                out.violations.append(f"sos_bound at {where}: under a disturbance sequence within its bounds "
                                      f"({policy}) "
                                      f"|{name} - {name}_eq| reached {y[r, k]:.6g} at step {k} from {start}, above "
                                      f"the certified {float(stated):.6g}" + (
                                          f" (its envelope there {envelope[r, k]:.6g})"
                                          if envelope[r, k] > float(stated) * (1 + 1e-9) else ""))

    def check_box_linearization(self, cond: Mapping[str, Any], where: str, rng: np.random.Generator, starts: int,
                                out: CrossCheck) -> None:
        """A map's ``linearization`` over a box (one ``V = e^T P e`` with ``V(A e) <= (1 - mu) V(e)`` for the
        Jacobian ``A`` of every value of the box) at this parameter point: the Jacobian of the map here
        (exact, :func:`lyapcheck.models.classes.linearization.jacobian`, then floats) iterated
        :data:`MAP_LINEAR_STEPS` steps from ``starts`` random directions; ``V`` may never rise from one step to
        the next nor leave ``(1 - mu)^k V(e_0)``, as a global V's check (the same figures and messages)."""
        from lyapcheck.models.classes.linearization import jacobian
        from lyapcheck.models.loop.discrete import shifted_map

        if not isinstance(self.model, Model):
            return
        cert = cond.get("certificate") or {}
        n = self.model.n
        try:
            P = _stein_matrix(cert["gram_V"], n)
            mu = float(Fraction(str(cert["mu"])))
        except (KeyError, TypeError, ValueError, ZeroDivisionError) as exc:
            out.violations.append(f"linearization at {where}: its certificate cannot be read ({exc})")
            return
        A = np.array([[float(v) for v in row] for row in jacobian(shifted_map(self.model))], dtype=np.float64)
        e = rng.standard_normal((max(starts, 1), n))
        self._stein_along(P, _linear_iterates(A, e), _per_step_rate(1 - mu), where, "the map's Jacobian", out)

    def check_ball_linearization(self, cond: Mapping[str, Any], where: str, rng: np.random.Generator, starts: int,
                                 out: CrossCheck) -> None:
        """A map with functions' ``linearization`` over a box (method
        :data:`lyapcheck.models.classes.discrete_functions_box.METHOD`: one ``P`` with ``A(p)^T P A(p) - P < 0``
        for every Jacobian of the box, no rate) at this parameter point, ``V = e^T P e`` never rising along:

        * the iterates of the map's exact Jacobian at its fixed point here
          (:func:`lyapcheck.models.classes.discrete_functions.exact_jacobian`, then floats), from ``starts``
          random directions, when there is one;
        * else (a function not differentiable there, an irrational entry) the iterates of the true map from
          ``starts`` random starts :data:`MAP_TINY_START` from the fixed point. The true map is its linearization
          there up to ``o(|e|)``, so ``V``'s step changes by a relative ``O(|e|)`` (about 1e-7, far below
          :data:`~lyapcheck.tolerances.TRAJECTORY_CHECK_REL_TOL`): a ``P`` that some Jacobian of the box makes
          rise shows as a rise here too. It is an alarm only, never a proof (a rise smaller than that tolerance
          is not seen), as every cross-check is."""
        from lyapcheck.models.classes.discrete_functions import exact_jacobian

        if isinstance(self.model, Model):
            return
        cert = cond.get("certificate") or {}
        n = self.model.n
        try:
            P = np.array([[float(Fraction(str(v))) for v in row] for row in cert["P"]], dtype=np.float64)
            if P.shape != (n, n):
                raise ValueError(f"P is {P.shape[0]} x {P.shape[1] if P.ndim == 2 else 0}, not over the {n} states")
        except (KeyError, TypeError, ValueError, ZeroDivisionError) as exc:
            out.violations.append(f"linearization at {where}: its certificate cannot be read ({exc})")
            return
        directions = rng.standard_normal((max(starts, 1), n))
        A = exact_jacobian(self.model)
        if not isinstance(A, str):
            es = _linear_iterates(np.array([[float(v) for v in row] for row in A], dtype=np.float64), directions)
            self._stein_along(P, es, 0.0, where, "the map's Jacobian", out)
            return
        from lyapcheck.models.surfaces.iterate import iterate

        unit = directions / np.maximum(np.linalg.norm(directions, axis=1, keepdims=True), 1e-300)
        paths = iterate(self.model, self.eq + MAP_TINY_START * unit, MAP_LINEAR_STEPS) - self.eq
        self._stein_along(P, paths, 0.0, where, f"the true map from starts {MAP_TINY_START:g} from its fixed point",
                          out)

    def _stein_along(self, P: np.ndarray, es: np.ndarray, rate: float, where: str, along: str,
                     out: CrossCheck) -> None:
        """``V = e^T P e`` along the deviations ``es`` (``(rows, steps + 1, n)``): never rising, and within
        ``V(e_0) exp(-rate k)`` when ``rate > 0``, as a global V's check (the same figures and messages). A row
        that left the escape box (NaN after it) is an escape."""
        from lyapcheck.models.engines.crosscheck import check_global

        V = np.einsum("rki,ij,rkj->rk", es, P, es)
        steps = np.arange(es.shape[1], dtype=np.float64)
        finite = [bool(np.all(np.isfinite(v))) for v in V]
        glob = check_global([(steps[np.isfinite(v)], v[np.isfinite(v)]) for v in V],
                            ["converged" if ok else "escaped" for ok in finite], rate)
        out.trajectories += len(V)
        out.worse("worst_rise", glob.worst_rise)
        if rate > 0:
            out.worse("worst_envelope", glob.worst_envelope)
        if not glob.ok:
            out.violations.append(f"linearization at {where}: along the iterates of {along} V = e^T P e rose by "
                                  f"{glob.worst_rise:.3g}" + (f" and exceeded V(0) exp(-{rate:.4g} k) by "
                                                              f"{glob.worst_envelope:.3g} of V(0)" if rate > 0 else "")
                                  + (f"; {glob.escaped} escaped" if glob.escaped else ""))


def _linear_iterates(A: np.ndarray, e: np.ndarray) -> np.ndarray:
    """The iterates ``e_{k+1} = A e_k`` of the rows of ``e`` over :data:`MAP_LINEAR_STEPS` steps:
    ``(rows, steps + 1, n)``."""
    path = [e]
    for _ in range(MAP_LINEAR_STEPS):
        path.append(path[-1] @ A.T)
    return np.stack(path, axis=1)


#: the disturbance policies of a map's ``sos_bound`` cross-check (:func:`map_disturbances`), in order
MAP_POLICY_NAMES: Final = ("uniform random", "bang-bang at the bounds", "constant at a vertex of the bounds")


def map_disturbances(bounds: np.ndarray, rows: int, steps: int, rng: np.random.Generator) -> list[np.ndarray]:
    """Disturbance sequences within ``|d_j| <= bounds_j`` for ``rows`` starts, each ``(steps, rows, m)``: uniform
    random, bang-bang (each step's sign random, at the bound), then each vertex of the bounds' box held constant
    (the first :data:`MAX_VERTICES` in sign order)."""
    from itertools import islice, product

    m = bounds.size
    out = [rng.uniform(-1.0, 1.0, size=(steps, rows, m)) * bounds,
           rng.choice([-1.0, 1.0], size=(steps, rows, m)) * bounds]
    for signs in islice(product((-1.0, 1.0), repeat=m), MAX_VERTICES):
        out.append(np.broadcast_to(np.array(signs) * bounds, (steps, rows, m)))
    return out


def iterate_disturbed(model: Model | RecastModel, starts: np.ndarray, disturbances: np.ndarray) -> np.ndarray:
    """The iterates ``x_{k+1} = f(x_k, d_k)`` of a map with ``d_k = disturbances[k]`` (``(steps, rows, m)``):
    ``(rows, steps + 1, n)``, the start first. A polynomial (rational) map is its exact field in floats; a map
    with functions is its true map, ``x + (F(x, d) - x)`` with every function evaluated by numpy from its
    definition (:class:`~lyapcheck.models.engines.recast_numeric.FloatLoop` of the displacement recast with its
    disturbances as variables, :func:`lyapcheck.models.classes.map_relations_bounds.disturbed_map`: the map its
    ``sos_bound`` is proved on; ``simulate``'s iterator holds them at 0). No escape box (a bound holds from every
    start); a row that overflows stays non-finite, which the checks skip. Raises
    :class:`~lyapcheck.models.classes.map_relations.NotTaken` where a map with functions cannot be recast with
    its disturbances as variables."""
    n = model.n
    out = np.empty((starts.shape[0], disturbances.shape[0] + 1, n))
    x = np.array(starts, dtype=np.float64)
    out[:, 0] = x
    step = _disturbed_step(model)
    with np.errstate(all="ignore"):
        for k in range(disturbances.shape[0]):
            x = step(x, disturbances[k])
            out[:, k + 1] = x
    return out


def _disturbed_step(model: Model | RecastModel) -> Callable[[np.ndarray, np.ndarray], np.ndarray]:
    """``f(x, d)`` of a map at rows of states and disturbances (:func:`iterate_disturbed`)."""
    n = model.n
    if not isinstance(model, Model):
        from lyapcheck.models.classes.map_relations_bounds import disturbed_map
        from lyapcheck.models.engines.recast_numeric import FloatLoop

        displacement = FloatLoop(disturbed_map(model).system)  # (its variables: the states, then the disturbances)
        return lambda x, d: x + displacement(np.concatenate([x, d], axis=1))[:, :n]
    from lyapcheck.models.language.modelfile import field_at
    from lyapcheck.models.surfaces.simulate import CompiledPolys

    rhs = field_at(model)
    polys = CompiledPolys(model.state_ring, [r.numerator for r in rhs] + [r.denominator for r in rhs])

    def step(x: np.ndarray, d: np.ndarray) -> np.ndarray:
        values = polys(np.concatenate([x, d], axis=1))
        return np.asarray(values[:, :n] / values[:, n:], dtype=np.float64)

    return step


def map_outputs(model: Model | RecastModel, xs: np.ndarray) -> dict[str, np.ndarray]:
    """Each output of a map at the iterates ``xs`` (``(rows, steps + 1, n)``), its parameters set (an output
    never reads a disturbance; a map with functions' outputs are polynomials of its states already):
    ``{name: (rows, steps + 1)}``."""
    from lyapcheck.models.surfaces.simulate import CompiledPolys
    from lyapcheck.sos.polynomials import Ring

    states = Ring(model.states)
    flat = np.where(np.isfinite(xs), xs, np.nan).reshape(-1, model.n)
    out = {}
    with np.errstate(all="ignore"):
        if not isinstance(model, Model):
            for name, poly in model.outputs.items():
                out[name] = CompiledPolys(states, [poly])(flat)[:, 0].reshape(xs.shape[:2])
            return out
        ring = model.ring
        for name, expr in model.outputs.items():
            num = ring.restrict(ring.substitute(expr.numerator, model.parameters), states)
            den = ring.restrict(ring.substitute(expr.denominator, model.parameters), states)
            values = CompiledPolys(states, [num, den])(flat)
            out[name] = (values[:, 0] / values[:, 1]).reshape(xs.shape[:2])
    return out


def _over_states(cert: Any, variables: Any, states: Sequence[str]) -> dict[str, Any] | None:
    """A map with functions' output certificate (``lam``, ``V`` over the certificate's ``variables``: the
    states, the disturbances, then the auxiliaries, in deviations) with ``V``'s terms over the states alone,
    as :func:`_bound_envelope` reads a polynomial map's; None when ``V`` cannot be read so (its variables do not
    begin with the states, a term names another variable or is malformed): the bound on its tail alone."""
    n = len(states)
    try:
        names = [str(v) for v in variables]
        if names[:n] != list(states) or not isinstance(cert, Mapping):
            return None
        terms = []
        for coefficient, exponents in cert["V"]["terms"]:
            exps = [int(e) for e in exponents]
            if len(exps) != len(names) or any(exps[n:]):  # (V is of the states: an auxiliary's term is no V)
                return None
            terms.append([coefficient, exps[:n]])
    except (KeyError, TypeError, ValueError):
        return None
    return {"lam": cert.get("lam"), "V": {"terms": terms}}


def _bound_envelope(cert: Mapping[str, Any] | None, bound: float, es: np.ndarray, states: list[str],
                    disturbances: list[str], box: Mapping[str, Fraction] | None = None) -> np.ndarray:
    """The certified envelope of ``|y_k - y_eq|`` along the deviations ``es`` (``(rows, steps + 1, n)``):
    ``sqrt(bound^2 + lam^k max(V(e_0) - 1, 0))`` with the output's certificate ``V`` and ``lam``; when they
    cannot be read, ``bound`` on the last :data:`MAP_BOUND_TAIL_STEPS` steps and no limit before. Over a box
    ``V``'s variables are the states, the disturbances, then the box's parameters (``box``: their values at
    this point; ``V`` is of the states alone, the others at exponent 0, so one envelope for the whole box)."""
    from lyapcheck.models.engines.crosscheck import certificate_function

    rows, count, n = es.shape
    tail_only = np.full((rows, count), np.inf)
    tail_only[:, -MAP_BOUND_TAIL_STEPS:] = bound
    if cert is None:
        return tail_only
    try:
        lam = float(Fraction(str(cert["lam"])))
        V = certificate_function(cert["V"], states + disturbances + list(box or {}), n,
                                 {**{d: Fraction(0) for d in disturbances}, **(box or {})}, [Fraction(1)] * n)
        excess = np.maximum(np.asarray(V(es[:, 0]), dtype=np.float64) - 1.0, 0.0)
    except (KeyError, TypeError, ValueError, ZeroDivisionError):
        return tail_only
    if not 0 <= lam < 1 or not np.all(np.isfinite(excess)):  # (no induction to read: the claim on its tail alone)
        return tail_only
    with np.errstate(over="ignore"):
        return np.sqrt(bound ** 2 + excess[:, None] * lam ** np.arange(count, dtype=np.float64)[None, :])


def _stein_matrix(gram: Mapping[str, Any], n: int) -> np.ndarray:
    """``P`` of a quadratic ``V = e^T P e`` given as a Gram matrix over the states' linear monomials (a box's
    parameters at exponent 0); ValueError otherwise."""
    basis = gram["basis"]
    Q = np.array([[float(Fraction(str(v))) for v in row] for row in gram["Q"]], dtype=np.float64)
    index = []
    for mono in basis:
        exps = [int(e) for e in mono]
        if sum(exps[:n]) != 1 or any(exps[n:]) or len(exps) < n:
            raise ValueError(f"the monomial {mono} of V's basis is not a state")
        index.append(exps.index(1))
    P = np.zeros((n, n))
    for a, i in enumerate(index):
        for b, j in enumerate(index):
            P[i, j] += Q[a, b]
    return P


class _FunctionsLoop:
    """A loop with functions read at a parameter point, simulated on its true field (module doc)."""

    pooled = False

    def __init__(self, model: RecastModel) -> None:
        from lyapcheck.models.classes.recast_classes import angle_states

        self.model = model
        self.system = model.system
        self.scales = np.ones(model.n)
        self.eq = np.array([float(v) for v in model.equilibrium])
        self.angles = angle_states(self.system)

    def streams(self, seed: Sequence[int], index: int | None) -> tuple[np.random.Generator, ...]:
        prefix = tuple(seed) if index is None else (*seed, index)
        return tuple(np.random.default_rng([*prefix, stream]) for stream in range(3))

    @cached_property
    def comparison(self) -> tuple[np.ndarray, np.ndarray]:
        """The comparison box of the classes (deviations): the model's ``[domain]``, else +-pi in an
        angle and +-4 elsewhere (:func:`lyapcheck.models.classes.recast_regions.comparison_box`)."""
        from lyapcheck.models.classes.recast_classes import base_loop
        from lyapcheck.models.classes.recast_regions import comparison_box

        lo, hi = comparison_box(self.model, base_loop(self.system))
        return np.asarray(lo, dtype=np.float64), np.asarray(hi, dtype=np.float64)

    def functions(self, cls: str, cert: Mapping[str, Any]) -> tuple[PointFunction, PointFunction | None,
                                                                     tuple[str, ...]]:
        """V (:func:`_v_function`); a set's rays read it within the certificate's ``box`` (a
        ball-arithmetic region) or else the comparison box."""
        V = _v_function(self.model, cert)
        angles = tuple(str(a) for a in (cert.get("angles") or ()))
        if cls not in REGION_CLASSES:
            return V, None, angles
        box = cert.get("box")
        lo, hi = self.comparison if box is None else (
            np.array([float(Fraction(str(box[s][0]))) for s in self.model.states]),
            np.array([float(Fraction(str(box[s][1]))) for s in self.model.states]))
        return V, _within(V, lo, hi), angles

    def start(self, u: np.ndarray) -> np.ndarray:
        return u  # deviations (scales 1)

    def global_box(self) -> tuple[np.ndarray, np.ndarray]:
        return self.comparison

    def _escape(self, factor: float) -> np.ndarray:
        """Escape factors per state: ``factor``, never in an angle (on the cylinder the loop may turn before it settles)."""
        return np.array([np.inf if s in self.angles else factor for s in self.model.states])

    def _integrate(self, deviations: np.ndarray, factors: np.ndarray, extent: np.ndarray, t_end: float,
                   disturbances: np.ndarray | None = None) -> list[tuple[np.ndarray, np.ndarray]]:
        """The true loop from ``x_eq + deviations`` (rows), escape ``factors * extent``, over ``t_end``:
        per row, its own points' times and deviations. ``disturbances``: a constant value of each
        disturbance per row (None: all 0; ignored where the recasting kept no disturbance)."""
        from lyapcheck.models.engines.trajectories import simulate

        eq = self.eq
        with np.errstate(all="ignore"):
            runs = simulate(self.model, deviations + eq, t_end=t_end, half_widths=extent, escape_factor=factors,
                            disturbances=None if self.model.robust is None else disturbances)
        return [(t, x - eq) for t, x in (tr.nodes for tr in runs)]

    def simulate(self, starts: np.ndarray) -> tuple[list[tuple[np.ndarray, np.ndarray]], Outcome]:
        """Over :func:`lyapcheck.models.surfaces.simulate.crosscheck_horizon`; converged within
        :data:`CONVERGED_FRACTION` of the starts' extent, modulo 2 pi in a claim's angles."""
        from lyapcheck.models.engines.recast_numeric import distances
        from lyapcheck.models.surfaces.simulate import crosscheck_horizon

        extent = np.maximum(np.max(np.abs(starts), axis=0), 1e-6)
        factors = self._escape(ESCAPE_EXTENTS)
        nodes = self._integrate(starts, factors, extent, crosscheck_horizon(self.model))
        escape, radius = factors * extent, CONVERGED_FRACTION * float(np.linalg.norm(extent))

        def outcome(i: int, angles: tuple[str, ...]) -> str:
            end = nodes[i][1][-1]
            if not np.all(np.isfinite(end)) or np.any(np.abs(end) >= escape * (1 - 1e-9)):
                return "escaped"
            return "converged" if distances(self.system, end[None, :], angles)[0] <= radius else "other"

        return nodes, outcome

    def runs(self) -> Runs:
        """Escape as the falsification's (never in an angle), the horizon the falsification's of the true field."""
        from lyapcheck.models.classes.falsify import ESCAPE_FACTOR, default_horizon
        from lyapcheck.models.engines.recast_numeric import TrueField

        eq, factors = self.eq, self._escape(ESCAPE_FACTOR)

        def run(x0: np.ndarray, t_end: float | None,
                disturbances: np.ndarray | None) -> list[tuple[np.ndarray, np.ndarray]]:
            Z0 = x0 - eq
            extent = np.maximum(np.max(np.abs(Z0), axis=0), np.maximum(np.abs(eq), 1.0) * 1e-6)
            horizon = default_horizon(self.model, extent, TrueField(self.model)) if t_end is None else t_end  # type: ignore[arg-type]
            return [(t, z + eq) for t, z in self._integrate(Z0, factors, extent, horizon, disturbances)]

        return run

    def check_bound(self, cond: Mapping[str, Any], where: str, rng: np.random.Generator, starts: int,
                    worst_case: bool, out: CrossCheck) -> None:
        """The true loop (``model.robust``, its disturbances as the last columns) from random starts of
        the comparison box, each disturbance a bang-bang or square-wave signal at its bound; the largest
        ``|y|`` after BOUND_TAIL_FROM_S is ``sim_worst`` and may not exceed the certified bound (beyond
        TRAJECTORY_CHECK_REL_TOL)."""
        from lyapcheck.models.engines.recast_numeric import FloatLoop, poly_values
        from lyapcheck.sos.polynomials import Ring
        from lyapcheck.tolerances import TRAJECTORY_CHECK_REL_TOL

        model, robust = self.model, self.model.robust
        if robust is None:
            return
        state_ring = Ring(model.states)
        bounds = np.array([float(b) for b in model.disturbances.values()])
        lo, hi = self.comparison
        Z0 = lo + (hi - lo) * rng.random((max(starts, 1), model.n))
        loop_field = FloatLoop(robust)
        for name, bound in (cond.get("bounds") or {}).items():
            y = model.outputs.get(name)
            if y is None:
                continue
            y_eq = float((cond.get("bounds_reference") or {}).get(name) or 0.0)  # the bound is on |y - y_eq|

            def output(X: np.ndarray) -> np.ndarray:
                return poly_values(state_ring, y, {s: X[:, k] for k, s in enumerate(model.states)}, len(X)) - y_eq

            policies = 1 + len(BOUND_SIGNAL_PERIODS)
            X = np.tile(Z0 + self.eq, (policies, 1))
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
                        return loop_field(np.column_stack([Y, D]))[:, :model.n]

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


def _v_function(model: RecastModel, cert: Mapping[str, Any]) -> PointFunction:
    """A loop with functions' certificate V as a float function of state deviations (rows): its
    polynomial in its ``variables``, each minus its ``shift``, at the true auxiliaries of ``x_eq + z``."""
    from lyapcheck.models.engines.recast_numeric import poly_values, variable_values
    from lyapcheck.models.engines.recast_sos import poly_from_json
    from lyapcheck.sos.polynomials import Ring

    system = model.system
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


def box_mismatch(model: Model | RecastModel, doc: Mapping[str, Any]) -> str | None:
    """Why the certificates of a box's document cannot be simulated on the loop ``model`` of one
    point of the box (None: they can; always on a polynomial loop, whose box certificates are functions
    of the box's parameters). A loop with functions' check evaluates each ``V`` on the point's own
    auxiliaries, shifted by the certificate's ``shift`` (the box centre's values at the equilibrium);
    that is the certificate's function only when every auxiliary it names is defined alike at the point
    and has the same value at the equilibrium (an auxiliary with a box parameter in it, such as
    ``sin(b*x)``, is not). A map's (with functions or not) always can: its certificates' ``V`` are of the states
    alone (a map with functions' over a box names the box's parameters among its variables, at exponent 0 in
    ``V``), evaluated on the states by :class:`_MapLoop`, never on the point's auxiliaries."""
    if isinstance(model, Model) or getattr(model, "time", "continuous") == "discrete":
        return None
    definitions = model.system.definitions()
    values = {k: Fraction(v) for k, v in model.system.values.items()}
    for name, cond in (doc.get("conditions") or {}).items():
        if not isinstance(cond, dict) or cond.get("status") != "certified" or \
                name not in (*GLOBAL_CLASSES, *REGION_CLASSES):
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
    from lyapcheck.models.loop.discrete import is_discrete

    sets = getattr(model, "sets", None) or {}
    conditions = doc.get("conditions") or {}
    certified = [cls for cls in SAFETY_CLASSES if isinstance(conditions.get(cls), dict)
                 and conditions[cls].get("status") == "certified" and sets.get("initial") and sets.get("unsafe")
                 and (cls == "barrier" or sets.get("goal"))]
    if not certified:
        return
    steps = is_discrete(model)  # a map's reach_avoid bounds the steps to the goal, not a time
    key, unit = ("reach_steps_bound", "steps") if steps else ("reach_time_bound_s", "s")
    raw = conditions["reach_avoid"].get(key) if "reach_avoid" in certified else None
    bound = float(raw) if isinstance(raw, (int, float)) and not isinstance(raw, bool) else math.nan
    if "reach_avoid" in certified and not (math.isfinite(bound) and (bound >= 0 if steps else bound > 0)):
        out.violations.append(f"reach_avoid at {where}: the certified bound {raw!r} {unit} is not a "
                              f"{'whole number >= 0' if steps else 'positive number'}")
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
        check = map_reach_avoid if steps else check_reach_avoid
        return check([(found_runs[i][0], at("unsafe", found_runs[i][1]), at("goal", found_runs[i][1]))
                      for i in mine], bound)

    found = reach(runs)
    end = bound if steps else reach_horizon(bound)  # (a map: the iterates e_0, ..., e_bound tell)
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
                              f"{found.late} were not in the goal by the certified "
                              f"{f'{bound:.0f} steps' if steps else f'time bound {bound:.6g} s'} "
                              f"(one still out at {found.reach_ratio:.6g} times it), the first from "
                              f"{start(mine[found.first_late])}")


def map_reach_avoid(series: Sequence[tuple[np.ndarray, np.ndarray, np.ndarray]], bound: float) -> Any:
    """A map's reach-avoid against its iterates: ``series[i] = (steps, unsafe margin, goal margin)`` at the
    iterates ``e_0, e_1, ...`` of start ``i`` (margins of
    :func:`lyapcheck.models.engines.crosscheck.scaled_margin`). The claim counts steps exactly (some iterate
    ``e_k``, ``k <= bound``, is in the goal, none before it unsafe), so unlike a sampled trajectory's time
    there is no point between two iterates to allow for: late is a first goal iterate beyond ``bound`` (or
    none among iterates beyond it); ``reach_ratio`` is the first goal step over the bound (a start never in
    the goal counting its last step; a bound 0: 0 when every start is in the goal, else inf). Entering
    and reaching read :data:`~lyapcheck.tolerances.TRAJECTORY_CHECK_REL_TOL`, as in continuous time. Returns
    a :class:`lyapcheck.models.engines.crosscheck.ReachAvoidCheck`."""
    from lyapcheck.models.engines.crosscheck import ReachAvoidCheck
    from lyapcheck.tolerances import TRAJECTORY_CHECK_REL_TOL

    entered = late = unreached = 0
    first_entered: int | None = None
    first_late: int | None = None
    worst, ratio = math.nan, math.nan
    for i, (k_steps, unsafe, goal) in enumerate(series):
        k_steps = np.asarray(k_steps, dtype=np.float64)
        if not k_steps.size:
            continue
        reached = np.flatnonzero(np.asarray(goal, dtype=np.float64) >= -TRAJECTORY_CHECK_REL_TOL)
        k = int(reached[0]) if reached.size else k_steps.size  # the first iterate in the goal (size: none)
        unreached += not reached.size
        step = float(k_steps[k]) if reached.size else float(k_steps[-1])
        this = step / bound if bound > 0 else (0.0 if step == 0 else math.inf)
        ratio = this if math.isnan(ratio) else max(ratio, this)
        if step > bound if reached.size else step >= bound:  # (never in e_0..e_bound: late too)
            late += 1
            first_late = i if first_late is None else first_late
        rel = np.asarray(unsafe, dtype=np.float64)[:k]
        top = float(np.nanmax(rel)) if np.any(np.isfinite(rel)) else math.nan
        if math.isfinite(top):
            worst = top if math.isnan(worst) else max(worst, top)
        if top > TRAJECTORY_CHECK_REL_TOL:
            entered += 1
            first_entered = i if first_entered is None else first_entered
    return ReachAvoidCheck(len(series), entered, late, unreached, first_entered, first_late, worst, ratio)


__all__ = ["CrossCheck", "map_reach_avoid", "cross_check_point", "cross_check_box", "box_mismatch", "check_sets", "SimulatedLoop",
           "GLOBAL_CLASSES", "REGION_CLASS", "REGION_CLASSES", "SAFETY_CLASSES", "WORST_CASE_SCREENING_ONLY"]
