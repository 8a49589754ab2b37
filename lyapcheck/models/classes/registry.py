"""The classes of a model file, each declared once: what it proves, where it runs, what a sweep stores.

:data:`CLASSES` is the one list of the condition classes of ``certify --model`` (DESIGN.md, "Model
files"), in the order they run (cheapest first) and are listed in a certificate. These names are
derived from it:

================================================  =================================================
name                                              derived from
================================================  =================================================
:data:`lyapcheck.models.surfaces.certify.MODEL_CLASSES`    :data:`NAMES`: the selection and its order
:data:`lyapcheck.models.surfaces.certify.CLEARED_CLASSES`  :data:`CLEARED`: the field multiplied through
:data:`sweeps.spec.MODEL_USER_CLASSES`            :data:`USER_GIVEN`: swept only with ``[sweep] candidate``
:data:`sweeps.spec.MODEL_POINT_ONLY_CLASSES`      :data:`POINT_ONLY`: ``not_applicable`` over a box
:data:`sweeps.spec.MODEL_POINT_CLASSES`           every class but :data:`USER_GIVEN`
:data:`sweeps.spec.MODEL_BOX_CLASSES`             :data:`OVER_BOX`: those with box certificates
:data:`sweeps.evaluate.MODEL_STABILITY_CLASSES`   :data:`STABILITY`: an unstable point refutes them
:data:`sweeps.evaluate.MODEL_SAFETY_CLASSES`      :data:`SAFETY`: a refutation is a proved unsafe trajectory
:data:`sweeps.schema.FIGURES`                     each class's ``figures``, stored per point or box
:data:`sweeps.schema.OUTPUT_FIGURES`              each class's ``output_figure``
:data:`ZERO_DISTURBANCE_ONLY`                     ``zero_disturbance_only``: ``verify`` refuses their
                                                  ``"all"`` claims (on both kinds of loop)
:data:`DISCRETE`, :data:`MAP_FUNCTIONS`,          the classes with a ``run_map``, ``run_map_functions``,
:data:`SAMPLED`                                   ``run_sampled`` entry: those that run on a map, a map
                                                  with functions, a sampled-data loop
================================================  =================================================

so the sweeps of model files (store variables, units of work, summaries, the report of a store) take a
new class from its entry alone.

**A new family of classes** (a later issue adds ``barrier`` and ``reach_avoid``) is:

1. one :class:`ModelClass` entry per class in :data:`CLASSES` (here; its place is its place in the
   order of ``certify --model``);
2. its implementation module, ``lyapcheck/models/classes/<family>.py``: the search, returning a
   :class:`~lyapcheck.results.ConditionResult`, and the exact check of its certificate, named by the
   entry for each kind of loop:

   - ``run_field`` and ``run_functions`` (:mod:`~lyapcheck.models.classes.runs`): its search, given
     the loop's run context and the class's budget. The one runner,
     :func:`lyapcheck.models.surfaces.certify.certify_model`, runs the chosen classes in the order of
     :data:`CLASSES` by these entries and applies the rules every class shares (an input that was not
     given, ``roa`` once GAS is certified, the disturbances a claim covers, the ball-arithmetic engine
     after ``roa``'s SOS route); a class without ``run_functions`` is ``not_applicable`` on a loop with
     functions, naming the loop;
   - ``verify_field`` and ``verify_functions`` (:mod:`~lyapcheck.models.classes.verify_field`,
     :mod:`~lyapcheck.models.classes.verify_functions`): its exact check, given the condition as stored
     and a check context; :func:`verify` is the one dispatch of ``verify``, by the type of the check
     context (a certificate under a name that is no class fails);
   - where the class has a discrete-time condition, its search and exact check on each discrete-time
     kind of loop (:mod:`~lyapcheck.models.classes.runs_discrete`,
     :mod:`~lyapcheck.models.classes.verify_discrete`), in pairs: ``run_map`` and ``verify_map`` on a
     polynomial map (``[model] time = "discrete"``; :data:`DISCRETE` is derived from them),
     ``run_map_functions`` and ``verify_map_functions`` on a map with functions (:data:`MAP_FUNCTIONS`),
     ``run_sampled`` and ``verify_sampled`` on a sampled-data loop (:data:`SAMPLED`). The same runner
     runs them with the rules of those loops (an input that was not given, ``roa`` once GAS is
     certified with the disturbances at 0); a class without the entry is ``not_applicable`` there,
     naming the loop, and a decided claim of it fails ``verify`` (never given the map as a field);

   (the contexts: :mod:`~lyapcheck.models.classes.contexts`);
3. one module in ``reports/sections/``, the one the entries' ``family`` names (a
   :class:`reports.sections.base.Section` naming the classes in its ``titles``), and that section in
   :data:`reports.sections.SECTIONS` (``reports/README.md``).

What else must change today, because those places name each class rather than read this list:

4. :mod:`lyapcheck.models.classes.claims`: the sentence a ``certified`` condition states, ``summary``
   (and ``sentence_of`` for a loop with functions' certificate kinds); verify compares it with the
   document's summary;
5. :data:`lyapcheck.results.PROPERTY`: the class's default property, equal to ``proves``
   (``tests/test_model_class_registry.py`` checks it); a new property (``safety``, ``reach_avoid``) is
   also one more value of :data:`lyapcheck.results.Property`.

Nothing in ``sweeps/`` changes. :mod:`sweeps.crosscheck` cross-checks by simulation the Lyapunov-type
certificates (``quadratic``, ``sos_gas``, ``roa``) and ``sos_bound``; a new family is stored and
summarised, and simulated against its claim only once the cross-check learns that claim.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Callable, Final, NamedTuple, TypeVar

from lyapcheck.models.classes import runs as _runs, runs_discrete as _discrete, verify_discrete as _vdiscrete, \
    verify_field as _field, verify_functions as _functions
from lyapcheck.models.classes.contexts import FieldCheck, FieldRun, FunctionsCheck, FunctionsRun, MapCheck, \
    MapFunctionsCheck, MapFunctionsRun, MapRun, SampledCheck, SampledRun
from lyapcheck.results import Property

if TYPE_CHECKING:  # pragma: no cover  (the search engine is imported where a class runs)
    from lyapcheck.models.engines.search import Budget
    from lyapcheck.results import ConditionResult

    _Check = TypeVar("_Check", FieldCheck, FunctionsCheck, MapCheck, MapFunctionsCheck, SampledCheck)
    _Run = TypeVar("_Run", FieldRun, FunctionsRun, MapRun, MapFunctionsRun, SampledRun)
    #: a class's exact check of a decided condition (its name, the condition as stored, what verify
    #: re-derived from the model text) -> (ok, why)
    Verify = Callable[[str, dict[str, Any], _Check], tuple[bool, str]]
    #: a class's search on one kind of loop (the loop's run context, the class's budget) -> its result
    Run = Callable[[_Run, Budget], ConditionResult]


class Figure(NamedTuple):
    """One key figure of a certified class, stored by sweeps as the float ``<class>_<suffix>``."""

    #: the store variable's suffix
    suffix: str
    #: the key of the class's ``numbers`` holding the figure
    key: str
    #: what the figure is (the store variable's description)
    text: str


class OutputFigure(NamedTuple):
    """A figure per output of the model, stored by sweeps as ``<class>_<output>``."""

    #: the key of the class's ``numbers`` holding ``{output: value}``
    key: str
    #: what the figure is, with ``{y}`` for the output's name
    text: str


@dataclass(frozen=True)
class ModelClass:
    """One condition class of a model file."""

    #: its name in ``--classes``, in a certificate's ``conditions``, in a store's ``status_<name>``
    name: str
    #: its family: the module of ``reports/sections/`` that shows it (``stability``, ``output_bound``)
    family: str
    #: what a ``certified`` proves by default (a result may state another: ``quadratic`` GES or GAS)
    proves: Property
    #: it certifies every parameter value of a ``--box`` (:mod:`lyapcheck.models.loop.boxes`) and a box sweep
    #: runs it; else it certifies a point only and is ``not_applicable`` over a box (a polynomial map's own
    #: list is :data:`lyapcheck.models.classes.discrete_lyapunov.BOX_CLASSES`). ``candidate`` is the one class
    #: needing the user's input: False here (a sweep runs it only where its spec gives the V, ``[sweep]
    #: candidate``), yet ``certify --box`` takes it on every kind of loop (the user's V for every value of the box)
    over_box: bool
    #: it proves a stability property of the equilibrium: an unstable equilibrium (the linearization
    #: refuted, exactly) refutes it
    stability: bool
    #: it needs the field multiplied through by its denominators (each proved of one sign)
    cleared: bool = True
    #: it needs the user's input (``--candidate``): a sweep runs it only with its spec's ``candidate`` key
    user_given: bool = False
    #: it proves its claim with the disturbances at 0 only: a certified claim of it covering every
    #: disturbance (``"all"``) is refused by ``verify`` where a disturbance enters the loop
    zero_disturbance_only: bool = False
    #: its key figures, stored by sweeps per point or box
    figures: tuple[Figure, ...] = ()
    #: its figure per output of the model, if any
    output_figure: OutputFigure | None = None
    #: its search on a polynomial or rational loop (:mod:`lyapcheck.models.classes.runs`)
    run_field: "Run[FieldRun] | None" = None
    #: its search on a loop with functions (None: ``not_applicable`` there, naming the loop)
    run_functions: "Run[FunctionsRun] | None" = None
    #: its exact check on a polynomial or rational loop (:mod:`lyapcheck.models.classes.verify_field`)
    verify_field: "Verify[FieldCheck] | None" = None
    #: its exact check on a loop with functions (:mod:`lyapcheck.models.classes.verify_functions`)
    verify_functions: "Verify[FunctionsCheck] | None" = None
    #: its search on a polynomial discrete-time map (``[model] time = "discrete"``;
    #: :mod:`lyapcheck.models.classes.runs_discrete`): a class with one has a discrete-time condition
    #: (:data:`DISCRETE`); a class without one is ``not_applicable`` on a map
    #: (:func:`lyapcheck.models.loop.discrete.not_decided`), never given the map as a field
    run_map: "Run[MapRun] | None" = None
    #: its exact check on such a map (:mod:`lyapcheck.models.classes.verify_discrete`)
    verify_map: "Verify[MapCheck] | None" = None
    #: its search on a discrete-time map with functions (None: ``not_applicable`` there,
    #: :data:`lyapcheck.models.classes.discrete_functions.NOT_YET`)
    run_map_functions: "Run[MapFunctionsRun] | None" = None
    #: its exact check on such a map
    verify_map_functions: "Verify[MapFunctionsCheck] | None" = None
    #: its search on a sampled-data loop (None: ``not_applicable`` there, naming the loop)
    run_sampled: "Run[SampledRun] | None" = None
    #: its exact check on a sampled-data loop
    verify_sampled: "Verify[SampledCheck] | None" = None

    @property
    def point_only(self) -> bool:
        """It certifies a point only (``not_applicable`` over a ``--box``)."""
        return not self.over_box


_V_RATE: Final = Figure("decay_rate_V_per_s", "decay_rate_V_per_s", "certified decay rate of V: V' <= -rate V, 1/s")

#: every class of a model file, in the order ``certify --model`` runs them (cheapest first)
CLASSES: Final[tuple[ModelClass, ...]] = (
    ModelClass("linearization", "stability", "LES", over_box=True, stability=True, cleared=False,
               zero_disturbance_only=True,
               run_field=_runs.linearization_field, run_functions=_runs.linearization_functions,
               verify_field=_field.verify_linearization, verify_functions=_functions.verify_linearization,
               run_map=_discrete.linearization_map, verify_map=_vdiscrete.verify_linearization_map,
               run_map_functions=_discrete.linearization_map_functions,
               verify_map_functions=_vdiscrete.verify_linearization_map_functions,
               run_sampled=_discrete.linearization_sampled, verify_sampled=_vdiscrete.verify_linearization_sampled),
    ModelClass("quadratic", "stability", "GES", over_box=True, stability=True,
               run_field=_runs.quadratic_field, run_functions=_runs.quadratic_functions,
               verify_field=_field.verify_lyapunov, verify_functions=_functions.verify_lyapunov,
               run_map=_discrete.quadratic_map, verify_map=_vdiscrete.verify_lyapunov_map,
               run_map_functions=_discrete.quadratic_map_functions,
               verify_map_functions=_vdiscrete.verify_lyapunov_map_functions,
               figures=(_V_RATE, Figure("k", "k", "GES constant: |x(t) - x_eq| <= k |x0 - x_eq| exp(-rate t)"),
                        Figure("decay_rate_per_s", "decay_rate_per_s", "GES decay rate of |x|, 1/s"))),
    ModelClass("sos_gas", "stability", "GAS", over_box=True, stability=True, figures=(_V_RATE,),
               run_field=_runs.sos_gas_field, run_functions=_runs.sos_gas_functions,
               verify_field=_field.verify_lyapunov, verify_functions=_functions.verify_lyapunov,
               run_map=_discrete.sos_gas_map, verify_map=_vdiscrete.verify_lyapunov_map,
               run_map_functions=_discrete.sos_gas_map_functions,
               verify_map_functions=_vdiscrete.verify_lyapunov_map_functions),
    ModelClass("roa", "stability", "ROA", over_box=True, stability=True,
               run_field=_runs.roa_field, run_functions=_runs.roa_functions,
               verify_field=_field.verify_lyapunov, verify_functions=_functions.verify_region,
               run_map=_discrete.roa_map, verify_map=_vdiscrete.verify_region_map,
               run_map_functions=_discrete.roa_map_functions, verify_map_functions=_vdiscrete.verify_roa_map_functions,
               run_sampled=_discrete.roa_sampled, verify_sampled=_vdiscrete.verify_roa_sampled,
               figures=(Figure("level", "level", "the certified region of attraction is {V <= level}"),
                        Figure("ball_radius", "ball_radius", "largest ball |x - x_eq| <= r certified inside it, SI"))),
    ModelClass("candidate", "stability", "ROA", over_box=False, stability=True, user_given=True,
               zero_disturbance_only=True,
               run_field=_runs.candidate_field, run_functions=_runs.candidate_functions,
               verify_field=_field.verify_lyapunov, verify_functions=_functions.verify_region,
               run_map=_discrete.candidate_map, verify_map=_vdiscrete.verify_region_map,
               run_map_functions=_discrete.candidate_map_functions,
               verify_map_functions=_vdiscrete.verify_candidate_map_functions,
               # (stored by a sweep with the spec's V as roa's are: the certified set {V <= level})
               figures=(Figure("level", "level", "the certified region of attraction is {V <= level} (your V)"),
                        Figure("ball_radius", "ball_radius", "largest ball |x - x_eq| <= r certified inside it, SI"))),
    ModelClass("sos_bound", "output_bound", "ultimate_bound", over_box=True, stability=False,
               run_field=_runs.sos_bound_field, run_functions=_runs.sos_bound_functions,
               verify_field=_field.verify_sos_bound, verify_functions=_functions.verify_sos_bound,
               run_map=_discrete.sos_bound_map, verify_map=_vdiscrete.verify_bound_map,
               run_map_functions=_discrete.sos_bound_map_functions,
               verify_map_functions=_vdiscrete.verify_bound_map_functions,
               output_figure=OutputFigure("bounds", "limsup |{y} - {y}_eq| <= this, SI ({y}_eq: bounds_reference)")),
    ModelClass("barrier", "safety", "safety", over_box=True, stability=False,
               run_field=_runs.barrier_field, run_functions=_runs.barrier_functions,
               verify_field=_field.verify_barrier, verify_functions=_functions.verify_barrier,
               run_map=_discrete.barrier_map, verify_map=_vdiscrete.verify_safety_map,
               run_map_functions=_discrete.barrier_map_functions,
               verify_map_functions=_vdiscrete.verify_barrier_map_functions,
               figures=(Figure("lambda_per_s", "lambda_per_s", "the barrier's rate: B' <= lambda B, 1/s"),)),
    ModelClass("reach_avoid", "safety", "reach_avoid", over_box=True, stability=False,
               run_field=_runs.reach_avoid_field, run_functions=_runs.reach_avoid_functions,
               verify_field=_field.verify_reach_avoid, verify_functions=_functions.verify_reach_avoid,
               run_map=_discrete.reach_avoid_map, verify_map=_vdiscrete.verify_safety_map,
               run_map_functions=_discrete.reach_avoid_map_functions,
               verify_map_functions=_vdiscrete.verify_reach_avoid_map_functions,
               figures=(Figure("reach_time_bound_s", "reach_time_bound_s",
                               "the goal is reached within this time, s"),)),
)


def _names(**want: bool) -> tuple[str, ...]:
    return tuple(c.name for c in CLASSES if all(getattr(c, k) == v for k, v in want.items()))


#: the classes' names, in order
NAMES: Final = _names()
#: the classes that need the field multiplied through (every denominator of one sign proved)
CLEARED: Final = _names(cleared=True)
#: the classes with a box version (they certify every parameter value of a ``--box``)
OVER_BOX: Final = _names(over_box=True)
#: the classes that certify a point only (``not_applicable`` over a box)
POINT_ONLY: Final = _names(point_only=True)
#: the classes whose certificate proves a stability property (an unstable point refutes them)
STABILITY: Final = _names(stability=True)
#: the classes of the ``safety`` family: their ``refuted`` is a proved counterexample to their own claim (an
#: unsafe trajectory from the initial set, at a value of the box), which refutes it for a box containing the value
SAFETY: Final = tuple(c.name for c in CLASSES if c.family == "safety")
#: the classes that need the user's input (``--candidate``)
USER_GIVEN: Final = _names(user_given=True)
#: the classes with a discrete-time condition (they run on a polynomial map: their ``run_map``)
DISCRETE: Final = tuple(c.name for c in CLASSES if c.run_map is not None)
#: the classes that run on a discrete-time map with functions (their ``run_map_functions``)
MAP_FUNCTIONS: Final = tuple(c.name for c in CLASSES if c.run_map_functions is not None)
#: the classes that run on a sampled-data loop (their ``run_sampled``)
SAMPLED: Final = tuple(c.name for c in CLASSES if c.run_sampled is not None)
#: the classes that prove their claim with the disturbances at 0 only (never ``"all"`` where one enters)
ZERO_DISTURBANCE_ONLY: Final = _names(zero_disturbance_only=True)
#: class name -> its entry
BY_NAME: Final[dict[str, ModelClass]] = {c.name: c for c in CLASSES}


#: the discrete-time kinds of loop: each one's search and exact check, as :class:`ModelClass` fields
_DISCRETE_KINDS: Final = (("run_map", "verify_map"), ("run_map_functions", "verify_map_functions"),
                          ("run_sampled", "verify_sampled"))
#: the entry field that checks a condition, by the type of verify's check context
_VERIFY_FIELD: Final[dict[type, str]] = {FieldCheck: "verify_field", FunctionsCheck: "verify_functions",
                                         MapCheck: "verify_map", MapFunctionsCheck: "verify_map_functions",
                                         SampledCheck: "verify_sampled"}


def _check() -> None:
    if len(BY_NAME) != len(CLASSES):
        raise RuntimeError("two model classes share a name")
    for c in CLASSES:
        if c.user_given and c.over_box:
            raise RuntimeError(f"{c.name}: a class needing the user's input certifies a point only")
        if c.run_field is None or c.verify_field is None or c.verify_functions is None:
            raise RuntimeError(f"{c.name}: every class has a search on a polynomial loop and an exact check on "
                               "each kind of loop")
        for run, check in _DISCRETE_KINDS:  # (a claim verify could not re-check would be printed)
            if (getattr(c, run) is None) != (getattr(c, check) is None):
                raise RuntimeError(f"{c.name}: a class with {run} has {check}, and only such a class")


_check()


def verify(name: str, c: dict[str, Any],
           check: FieldCheck | FunctionsCheck | MapCheck | MapFunctionsCheck | SampledCheck) -> tuple[bool, str]:
    """Re-check one decided condition exactly: the one dispatch of ``verify``, by the class's entry for the
    kind of loop ``check`` is the context of (its ``verify_field``, ``verify_functions``, ``verify_map``,
    ``verify_map_functions`` or ``verify_sampled``); a name that is no class fails, as does a class without a
    check on that kind of loop (in the context's words: ``check.not_checked``). A malformed certificate
    raises (verify reports it in one row)."""
    entry = BY_NAME.get(name)
    if entry is None:
        return False, f"no class named {name!r} (the classes: {', '.join(NAMES)})"
    check_of: "Verify[Any] | None" = getattr(entry, _VERIFY_FIELD[type(check)])
    if check_of is None:
        # (never on the continuous kinds: _check; on a map or a sampled-data loop, a class without its condition)
        assert not isinstance(check, (FieldCheck, FunctionsCheck))
        return False, check.not_checked(c.get("status"))
    return check_of(name, c, check)


__all__ = ["Figure", "OutputFigure", "ModelClass", "CLASSES", "NAMES", "CLEARED", "OVER_BOX", "POINT_ONLY",
           "STABILITY", "SAFETY", "USER_GIVEN", "DISCRETE", "MAP_FUNCTIONS", "SAMPLED", "ZERO_DISTURBANCE_ONLY", "BY_NAME",
           "verify"]
