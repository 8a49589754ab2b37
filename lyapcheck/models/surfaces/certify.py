"""Certify a model file: every generic class that applies, each bounded in time, each checked exactly.

The classes (DESIGN.md, "Model files"), in this order:

==============  ===========  =============================================================
class           property     what a ``certified`` proves
==============  ===========  =============================================================
linearization   LES          the Jacobian at the equilibrium is Hurwitz (``refuted``: it has an
                             eigenvalue with positive real part, so the equilibrium is unstable)
quadratic       GES or GAS   a quadratic ``V`` decreasing everywhere (GES when ``V' <= -mu V``)
sos_gas         GAS          a polynomial ``V`` decreasing everywhere (and the decay rate of ``V``)
roa             ROA          ``{V <= c}`` lies in the region of attraction
candidate       ROA or GAS   the same for the user's ``V`` (``--candidate``); GAS when it holds
                             everywhere
sos_bound       ult. bound   ``limsup |y - y_eq| <= B`` for each output (``y_eq``: its value at the
                             equilibrium), every start, every disturbance within its bounds
==============  ===========  =============================================================

Every class but ``linearization`` needs the field multiplied through by its denominators, which
needs each denominator proved of one sign everywhere (:mod:`lyapcheck.models.loop.positivity`); if one
cannot be, those classes are ``not_applicable`` and name it. A class that cannot apply for another
reason (no disturbances for ``sos_bound``, no ``--candidate``) says so. Each class runs within
:data:`~lyapcheck.tolerances.MODEL_CLASS_TIME_LIMIT_S`; past it, it is ``inconclusive`` naming the
limit, and the others still run.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass, field
from fractions import Fraction
from typing import TYPE_CHECKING, Any, Callable, Final, Sequence

from lyapcheck import answers as _answers
from lyapcheck.errors import InvalidParameter, ModelFileError
from lyapcheck.models.classes.contexts import Candidate, FieldRun
from lyapcheck.models.classes.registry import CLEARED, NAMES, ModelClass
from lyapcheck.models.loop.field import Scaling, ShiftedField, active_disturbances, apply_scaling, choose_scaling, \
    clear, robust_field, shifted_field, state_field
from lyapcheck.models.language.modelfile import Model
from lyapcheck.models.engines import reasons
from lyapcheck.models.engines.search import Budget, BudgetExhausted
from lyapcheck.results import ConditionResult, Disturbances
from lyapcheck.sos.polynomials import Poly
from lyapcheck.timing import ClassTimeLimit, time_limit

if TYPE_CHECKING:  # pragma: no cover
    from lyapcheck.models.language.parameter_box import ModelBox
    from lyapcheck.models.language.recast import RecastModel

log = logging.getLogger(__name__)

#: the classes, in the order they run (:data:`lyapcheck.models.classes.registry.CLASSES`, where each is declared)
MODEL_CLASSES: Final = NAMES
#: the classes that need the field multiplied through (every denominator of one sign proved)
CLEARED_CLASSES: Final = CLEARED
#: a class's hard stop (:func:`lyapcheck.timing.time_limit`) comes at its limit times this plus
#: HARD_STOP_GRACE_S: past the cooperative budget, for a solve, exact check or simulation that
#: overruns it. With the 60 s limit: 95 s
HARD_STOP_FACTOR: Final = 1.5
HARD_STOP_GRACE_S: Final = 5.0


@dataclass
class ModelCertification:
    """What ``certify --model`` found, on either kind of loop (the document is
    :func:`lyapcheck.models.surfaces.certificate.build_document`).

    A polynomial or rational loop carries its cleared field's ``denominators`` and ``scaling``; a loop
    with functions (``model`` a :class:`~lyapcheck.models.language.recast.RecastModel`) carries its
    recasting's ``loop`` (its angles, the document's ``recast`` table)."""

    model: "Model | RecastModel"
    candidate: Candidate | None
    results: dict[str, ConditionResult]
    denominators: list[dict[str, Any]] = field(default_factory=list)
    scaling: Scaling | None = None
    seconds: dict[str, float] = field(default_factory=dict)
    box: "ModelBox | None" = None
    loop: Any = None

    @property
    def verdict(self) -> str:
        """:func:`verdict_of` the results."""
        return verdict_of({name: r.to_json() for name, r in self.results.items()})


#: the verdict (one rule for every loop and the paper's; :mod:`lyapcheck.answers`)
VERDICTS, OK_VERDICTS, VERDICT_MEANING, verdict_of = _answers.VERDICTS, _answers.OK_VERDICTS, \
    _answers.VERDICT_MEANING, _answers.verdict_of


def parse_candidate(model: Model, text: str) -> Candidate:
    """The user's ``V`` (``--candidate``): an expression in the states and parameters, polynomial in
    the states, zero at the equilibrium (one-line errors naming ``--candidate``)."""
    from lyapcheck.models.language.expressions import ExpressionError, parse_expression

    try:
        expr = parse_expression(text, model.ring)
    except ExpressionError as exc:
        raise ModelFileError(model.source, "--candidate", str(exc)) from None
    ring = model.ring
    num = ring.substitute(expr.numerator, model.parameters)
    den = ring.substitute(expr.denominator, model.parameters)
    state_ring = model.state_ring
    if not den.is_constant():
        raise ModelFileError(model.source, "--candidate", "V must be a polynomial in the states (no state in a "
                                                          "denominator)")
    try:
        poly = ring.restrict(num * (1 / den.leading_coefficient()), state_ring)
    except ValueError:
        raise ModelFileError(model.source, "--candidate", "V may depend on the states and parameters only, not on a "
                                                          "disturbance") from None
    value = state_ring.evaluate(poly, list(model.equilibrium) + [Fraction(0)] * len(model.disturbances))
    if value != 0:
        raise ModelFileError(model.source, "--candidate", f"V must be 0 at the equilibrium; it is {value} there")
    if any(any(m[model.n:]) for m in state_ring.support(poly)):
        raise ModelFileError(model.source, "--candidate", "V may not depend on a disturbance")
    return Candidate(text=text, poly=poly)


def _has_safety_sets(model: "Model | RecastModel", goal: bool = False) -> bool:
    """The model's ``[sets]`` has the two a barrier needs, ``initial`` and ``unsafe`` (and, with
    ``goal``, the ``goal`` that reach_avoid needs too)."""
    sets = getattr(model, "sets", None) or {}
    return bool(sets.get("initial")) and bool(sets.get("unsafe")) and (not goal or bool(sets.get("goal")))


def _sets_use_box(model: Model, box: "ModelBox | None") -> bool:
    """Some ``[sets]`` inequality names a parameter of ``box`` (the sets are evaluated at the model's
    values, so a class over the box would prove them at one value only)."""
    from lyapcheck.models.language.sets import forms_name

    return box is not None and forms_name(model.ring, getattr(model, "set_forms", None) or {}, set(box.names))


def refuse_box_in_candidate(model: "Model | RecastModel", candidate: str, box: "ModelBox") -> None:
    """A candidate over a box is one ``V`` for every value of the box, on every kind of loop: a text naming a
    parameter of the box (which would be read at the model's value, :func:`parse_candidate`, or at the box's
    centre on a loop with functions) is bad input (exit 2 naming ``--candidate``). A loop with functions'
    candidate is read in its recasting, whose ring has no parameter: its names are read off the text's syntax
    tree (never evaluated)."""
    from lyapcheck.models.language.expressions import ExpressionError, parse_expression

    if not isinstance(model, Model):
        import ast

        from lyapcheck.models.language.expressions import parse_quietly

        try:
            tree = parse_quietly(candidate)
        except (SyntaxError, ValueError, RecursionError, ExpressionError):
            return  # (the candidate's reading words the error)
        named = sorted({node.id for node in ast.walk(tree) if isinstance(node, ast.Name)} & set(box.names))
        if named:
            raise ModelFileError(model.source, "--candidate", "over a --box V must be of the states alone (one V for "
                                 f"every value of the box); it names the box's parameter {', '.join(named)}")
        return
    try:
        expr = parse_expression(candidate, model.ring)
    except ExpressionError:
        return  # (parse_candidate words the error)
    ring = model.ring
    named = sorted({ring.names[k] for p in (expr.numerator, expr.denominator) for m in ring.support(p)
                    for k, e in enumerate(m) if e and ring.names[k] in box.names})
    if named:
        raise ModelFileError(model.source, "--candidate", "over a --box V must be of the states alone (one V for "
                             f"every value of the box); it names the box's parameter {', '.join(named)}")


def class_selection(classes: str | Sequence[str] | None, model: "Model | RecastModel", candidate: Candidate | None
                    ) -> tuple[str, ...]:
    """The classes to run on either kind of loop: ``None`` (every class that applies: ``candidate``
    with ``--candidate``, ``sos_bound`` with disturbances, ``barrier`` with ``[sets]`` initial and
    unsafe, ``reach_avoid`` with a goal too), a comma-separated string or names (a safety class named
    needs its sets: one line at ``[sets]`` otherwise)."""
    if classes is None or classes == "all":
        chosen = [c for c in MODEL_CLASSES if (c != "candidate" or candidate is not None)
                  and (c != "sos_bound" or model.disturbances) and (c != "barrier" or _has_safety_sets(model))
                  and (c != "reach_avoid" or _has_safety_sets(model, goal=True))]
        return tuple(chosen)
    names = [c.strip() for c in (classes.split(",") if isinstance(classes, str) else classes) if c and c.strip()]
    unknown = [c for c in names if c not in MODEL_CLASSES]
    if not names or unknown:
        paper = " ('quick' is the paper's selection of its own classes)" if "quick" in unknown else ""
        raise InvalidParameter("classes", "names among " + ", ".join(MODEL_CLASSES) + paper,
                               ",".join(unknown) or classes)
    from lyapcheck.models.language.sets import require_sets

    for name in names:  # a safety class asked for by name needs its sets (one line at [sets], exit 2)
        require_sets(model, name)  # type: ignore[arg-type]  # (a loop with functions too: it reads source and sets)
    return tuple(c for c in MODEL_CLASSES if c in names)


def certify_model(model: "Model | RecastModel", *, classes: str | Sequence[str] | None = None,
                  candidate: str | None = None, time_limit_s: float | None = None, box: "ModelBox | None" = None
                  ) -> ModelCertification:
    """Run the chosen classes on ``model``, a polynomial or rational loop or a loop with functions
    (see the module docstring); with a ``box`` of parameters, each certified class holds for every
    parameter value in it (:mod:`lyapcheck.models.loop.boxes`; a loop with functions is read at the
    box's centre, :func:`lyapcheck.models.classes.recast_regions.functions_run`).

    Every kind of loop runs its classes through one runner (:func:`_run_classes`; a sampled-data loop's too,
    :func:`lyapcheck.models.surfaces.sampled_run.certify_sampled`): each class of
    :data:`lyapcheck.models.classes.registry.CLASSES` in order, by its entry for the kind of loop, given
    one context object (:mod:`lyapcheck.models.classes.contexts`); the rules every class shares
    (:func:`_needs_input`, :func:`_field_rule`, :func:`_discrete_rule`,
    :func:`lyapcheck.models.classes.claims.roa_after_gas`, the disturbances each claim covers, the
    ball-arithmetic engine after ``roa``'s SOS route) are applied here."""
    from lyapcheck import tolerances as tol

    limit = tol.MODEL_CLASS_TIME_LIMIT_S if time_limit_s is None else float(time_limit_s)
    from lyapcheck.models.loop.discrete import is_discrete

    if candidate is not None and box is not None and not is_discrete(model):  # (a map's runner checks its own)
        refuse_box_in_candidate(model, candidate, box)
    if is_discrete(model):  # a map never reaches the classes that read [dynamics] as a field
        if not isinstance(model, Model):  # a map with functions (lyapcheck.models.classes.discrete_functions)
            return _certify_map_functions(model, classes, candidate, limit, box)
        return _certify_map(model, classes, candidate, limit, box)
    if not isinstance(model, Model):  # a loop with functions: its classes run on the recasting
        return _certify_functions(model, classes, candidate, limit, box)
    cand = parse_candidate(model, candidate) if candidate is not None else None
    chosen = class_selection(classes, model, cand)
    out = ModelCertification(model=model, candidate=cand, results={}, box=box)
    shifted = shifted_field(model, box=box)
    ctx = FieldRun(model=model, shifted=shifted, box=box, candidate=cand, results=out.results)

    def run(name: str, compute: Callable[[Budget], ConditionResult]) -> None:
        _timed(name, compute, out.results, out.seconds, limit)

    needing = [c for c in chosen if c in CLEARED_CLASSES]
    uncleared: tuple[str, str] | None = None  # why the classes needing the cleared field cannot run; the denominator
    if needing:
        from lyapcheck.models.loop.positivity import prove_denominators

        distinct = shifted.distinct_denominators()
        budget = Budget(limit, "lyapcheck.tolerances.MODEL_CLASS_TIME_LIMIT_S")
        try:
            with time_limit(limit * HARD_STOP_FACTOR + HARD_STOP_GRACE_S):
                signs, certs, failed = prove_denominators(shifted.ring, distinct, budget, box_start(model, box))
        except (BudgetExhausted, ClassTimeLimit) as exc:
            signs, certs, failed = [], [], distinct[0] if distinct else None
            log.info("denominators: %s", exc)
        out.denominators = [{"denominator": _text(shifted, d), **cert} for d, cert in zip(distinct, certs)]
        if failed is not None:
            why = (f"the denominator {_text(shifted, failed)} (in x - x_eq) could not be proved of one sign for every "
                   "state, so the field cannot be multiplied through")
            uncleared = why, _text(shifted, failed)
        else:
            cleared = clear(shifted, signs)
            out.scaling = choose_scaling(cleared, model.domain)
            sc = ctx.scaled = apply_scaling(cleared, out.scaling)
            ctx.robust = robust_field(sc)
            ctx.nominal = state_field(sc)
            ctx.enters = bool(active_disturbances(sc))
            #: what a claim on the nominal field covers
            ctx.nominal_covers = ("all" if not ctx.enters else "zero") if model.disturbances else None

    def decide(entry: ModelClass) -> ConditionResult | None:
        given = _needs_input(entry.name, cand)  # (the user's V is proved over a box too)
        if given is not None:
            return given
        if entry.cleared and uncleared is not None:
            return ConditionResult(entry.name, "not_applicable", uncleared[0], numbers={"denominator": uncleared[1]})
        return _field_rule(entry.name, model, box, out.results)

    from lyapcheck.models.surfaces import ball_roa

    roa_stopped: list[BaseException] = []  # what ended roa's SOS route, where it raised

    def compute(entry: ModelClass) -> Callable[[Budget], ConditionResult] | None:
        run_field = entry.run_field
        if run_field is None:
            return None

        def found(budget: Budget) -> ConditionResult:
            return run_field(ctx, budget)

        # the ball-arithmetic engine runs after roa's SOS route (below) where that did not certify
        return ball_roa.recording(found, roa_stopped) if entry.name == "roa" else found

    _run_classes(chosen, out.results, out.seconds, limit, decide, compute)
    if "roa" in out.results:  # the ball-arithmetic engine, where the SOS route did not certify
        _ball_after_sos(out, model, box, roa_stopped, ctx.scaled is not None, run)
    if "linearization" in out.results and model.disturbances:
        from lyapcheck.models.classes.claims import nominal_coverage

        # the Jacobian at d = 0: every admissible disturbance where each bound is 0
        out.results["linearization"].disturbances = nominal_coverage(model.disturbances.values())
    for name in ("sos_bound", "barrier", "reach_avoid"):
        if name in out.results and model.disturbances:
            out.results[name].disturbances = "all"  # (B or V serves every disturbance: the robust field)
    out.results = {name: out.results[name] for name in MODEL_CLASSES if name in out.results}
    for r in out.results.values():  # every condition of a disturbed model says which it covers
        if model.disturbances and r.disturbances is None:
            r.disturbances = "all" if r.name == "sos_bound" else "zero"  # e.g. not_applicable ones
    from lyapcheck.models.classes import region_size
    from lyapcheck.models.classes.claims import state_unit_figures, summary

    for name, r in out.results.items():
        if r.status == "certified":
            for data, variables in stated_polynomials(model, box, name, r.certificate):
                data["variables"] = variables
                data["V_text"] = readable_v(model, data["V"], variables)
            r.numbers.update(state_unit_figures(model.units, model.states, r.numbers))
            if name in region_size.SIZED_CLASSES:
                _attach_size(r, model, list(model.states) + (list(box.names) if box is not None else []))
        text = summary(name, r.to_json(), tuple(model.outputs), box.to_json() if box is not None else None)
        if text is not None:
            r.summary = text
    return out


def _run_classes(chosen: Sequence[str], results: dict[str, ConditionResult], seconds: dict[str, float], limit: float,
                 decide: Callable[[ModelClass], ConditionResult | None],
                 compute: Callable[[ModelClass], Callable[[Budget], ConditionResult] | None]) -> None:
    """The one runner: each chosen class of :data:`lyapcheck.models.classes.registry.CLASSES`, in its order,
    decided by a rule every class shares (``decide``: an input that was not given, ``roa`` once GAS is
    certified, ...) or else run by its entry for this kind of loop (``compute``; None: the class has no
    search on it, and the caller says so), each with a budget of its own, guarded and timed (:func:`_timed`),
    on every kind of loop alike."""
    from lyapcheck.models.classes import registry

    for entry in registry.CLASSES:
        if entry.name not in chosen or entry.name in results:
            continue
        ruled = decide(entry)
        if ruled is not None:
            results[entry.name] = ruled
            continue
        found = compute(entry)
        if found is not None:
            _timed(entry.name, found, results, seconds, limit)


def _timed(name: str, compute: Callable[[Budget], ConditionResult], results: dict[str, ConditionResult],
           seconds: dict[str, float], limit: float) -> None:
    """One class run with a budget of its own, guarded (its numerical trouble, its budget or its hard time
    limit becomes ``inconclusive``, :func:`_guarded`), its seconds recorded."""
    import time

    start = time.perf_counter()
    budget = Budget(limit, "lyapcheck.tolerances.MODEL_CLASS_TIME_LIMIT_S")
    results[name] = _guarded(name, lambda: compute(budget), limit)
    seconds[name] = time.perf_counter() - start


#: why a safety class over a box does not take sets naming a parameter of the box
SETS_NAME_BOX = "over a box the sets may not depend on a parameter of the box (they are read at the model's values)"


def _needs_input(name: str, cand: object | None) -> ConditionResult | None:
    """``candidate`` is ``not_applicable`` without ``--candidate``, on every kind of loop (at a point and over
    a box alike: every kind proves the user's V over a box); None otherwise."""
    if name == "candidate" and cand is None:
        return ConditionResult("candidate", "not_applicable", reasons.NEEDS_CANDIDATE)
    return None


def _field_rule(name: str, model: Model, box: "ModelBox | None", results: dict[str, ConditionResult]
                ) -> ConditionResult | None:
    """What a polynomial or rational loop decides before a class runs: ``roa`` once GAS is certified
    covering what its claim would (every disturbance, or none declared), a safety class without its
    sets (or with sets naming a parameter of the box), ``sos_bound`` without disturbances; None: run it."""
    if name == "roa":
        from lyapcheck.models.classes.claims import roa_after_gas

        return roa_after_gas(results, "all" if model.disturbances else None, over_box=box is not None)
    if name in ("barrier", "reach_avoid"):
        goal = name == "reach_avoid"
        if not _has_safety_sets(model, goal=goal) or _sets_use_box(model, box):
            why = (SETS_NAME_BOX
                   if _has_safety_sets(model, goal=goal) and _sets_use_box(model, box) else
                   "the model's [sets] needs 'initial', 'unsafe' and 'goal' (docs/model-files.md, [sets])" if goal else
                   "the model's [sets] needs 'initial' and 'unsafe' (docs/model-files.md, [sets])")
            return ConditionResult(name, "not_applicable", why)
    if name == "sos_bound" and not model.disturbances:
        return ConditionResult("sos_bound", "not_applicable", reasons.NO_DISTURBANCES)
    return None


def _certify_map(model: Model, classes: str | Sequence[str] | None, candidate: str | None, limit: float,
                 box: "ModelBox | None") -> ModelCertification:
    """:func:`certify_model` on a discrete-time map (``[model] time = "discrete"``): the one place where a
    map's classes are chosen. A class with a discrete-time condition (its ``run_map`` entry;
    :data:`lyapcheck.models.classes.registry.DISCRETE`) runs on the shifted map through the one runner
    (:func:`_run_classes`); every other one asked for is ``not_applicable``
    (:func:`lyapcheck.models.loop.discrete.not_decided`), never run on the map as if it were a field. A
    certified region's size is attached as in continuous time. Over a ``box`` (checked when it was read: the
    fixed point does not move over it) the map's ring carries the box's normalized parameters, the classes of
    :data:`lyapcheck.models.classes.discrete_lyapunov.BOX_CLASSES` prove one V (one set) for every value of the box
    (``candidate`` too: the user's V is of the states alone) and every other class is ``not_applicable``
    (:func:`~lyapcheck.models.classes.discrete_lyapunov.not_over_box`)."""
    from lyapcheck.models.classes import region_size
    from lyapcheck.models.classes.claims import summary
    from lyapcheck.models.classes.contexts import MapRun
    from lyapcheck.models.classes.discrete_lyapunov import BOX_CLASSES, not_over_box
    from lyapcheck.models.classes.registry import DISCRETE
    from lyapcheck.models.loop.discrete import not_decided, shifted_map

    if candidate is not None and box is not None:
        refuse_box_in_candidate(model, candidate, box)
    cand = parse_candidate(model, candidate) if candidate is not None else None
    chosen = class_selection(classes, model, cand)
    out = ModelCertification(model=model, candidate=cand, results={}, box=box)
    ctx = MapRun(model=model, shifted=shifted_map(model, box=box), candidate=cand, results=out.results)

    def decide(entry: ModelClass) -> ConditionResult | None:
        # over a box, a class a map takes at a point only is named; a map's candidate is taken over a box (its V
        # is common to the box: one set for every value), without --candidate it is not run, as at a point
        if box is not None and entry.run_map is not None and entry.name not in BOX_CLASSES:
            return ConditionResult(entry.name, "not_applicable", not_over_box(entry.name))
        if entry.name in ("barrier", "reach_avoid") and _sets_use_box(model, box):
            return ConditionResult(entry.name, "not_applicable", SETS_NAME_BOX)
        return _discrete_rule(entry, entry.run_map, not_decided(entry.name, DISCRETE), out.results, cand,
                              bool(model.disturbances), over_box=box is not None)

    def compute(entry: ModelClass) -> Callable[[Budget], ConditionResult] | None:
        run_map = entry.run_map
        return None if run_map is None else lambda budget: run_map(ctx, budget)

    _run_classes(chosen, out.results, out.seconds, limit, decide, compute)
    for name, r in out.results.items():
        if model.disturbances:  # (every class of a map is decided with its disturbances at 0, but sos_bound,
            # whose V serves every disturbance sequence within the bounds)
            r.disturbances = "all" if name == "sos_bound" else "zero"
        if r.status == "certified" and name in region_size.SIZED_CLASSES:  # (V's exponents: states, box's parameters)
            _attach_size(r, model, list(model.states) + (list(box.names) if box is not None else []))
        text = summary(name, r.to_json(), tuple(model.outputs), box.to_json() if box is not None else None)
        if text is not None:
            r.summary = text
    return out


def _certify_map_functions(model: "RecastModel", classes: str | Sequence[str] | None, candidate: str | None,
                           limit: float, box: "ModelBox | None") -> ModelCertification:
    """:func:`certify_model` on a discrete-time map with functions: each class with a ``run_map_functions``
    entry (:mod:`lyapcheck.models.classes.discrete_functions`: ``linearization``, ``roa`` and ``candidate``;
    :mod:`lyapcheck.models.classes.map_relations`: ``quadratic`` and ``sos_gas``;
    :mod:`lyapcheck.models.classes.map_relations_bounds`: ``sos_bound``;
    :mod:`lyapcheck.models.classes.map_relations_safety` and ``map_relations_reach``: ``barrier`` and
    ``reach_avoid``) through the one runner, any other one ``not_applicable`` in one line
    (:data:`~lyapcheck.models.classes.discrete_functions.NOT_YET`); the document states the map's recasting
    (the loop of its displacement). Over a ``box`` (``model`` read at its centre) ``linearization`` and ``roa``
    hold for every value of it (:mod:`lyapcheck.models.classes.discrete_functions_box`: a box moving the fixed
    point is refused in one line, exit 2); ``quadratic``, ``sos_gas``, ``sos_bound``, ``barrier`` and
    ``reach_avoid`` with the box's parameters bounded variables of the relations."""
    from lyapcheck.models.classes.claims import summary
    from lyapcheck.models.classes.contexts import MapFunctionsRun
    from lyapcheck.models.classes.discrete_functions import NOT_YET
    from lyapcheck.models.classes.discrete_functions_box import BOX_CLASSES, NOT_OVER_BOX, boxed_system
    from lyapcheck.models.classes.recast_classes import base_loop

    if box is not None:  # the fixed point must stay put over the box (one line, exit 2, before any class runs)
        boxed_system(model, box)
        if candidate is not None:  # one V for every value of the box: of the states alone
            refuse_box_in_candidate(model, candidate, box)
    cand = Candidate(candidate, model.candidate_v) if candidate is not None else None
    chosen = class_selection(classes, model, cand)
    results: dict[str, ConditionResult] = {}
    seconds: dict[str, float] = {}
    ctx = MapFunctionsRun(model=model, box=box)

    def decide(entry: ModelClass) -> ConditionResult | None:
        if box is not None:
            given = _needs_input(entry.name, cand)  # (a candidate over a box: one V for every value)
            if given is not None:
                return given
            if entry.run_map_functions is not None and entry.name not in BOX_CLASSES:
                return ConditionResult(entry.name, "not_applicable", NOT_OVER_BOX)
        return _discrete_rule(entry, entry.run_map_functions, NOT_YET, results, cand, bool(model.disturbances),
                              over_box=box is not None)

    def compute(entry: ModelClass) -> Callable[[Budget], ConditionResult] | None:
        run_map_functions = entry.run_map_functions
        return None if run_map_functions is None else lambda budget: run_map_functions(ctx, budget)

    _run_classes(chosen, results, seconds, limit, decide, compute)
    for name, r in results.items():
        if model.disturbances:  # the map is read with its disturbances at 0, but by sos_bound
            # (lyapcheck.models.classes.map_relations_bounds: its V serves every disturbance sequence)
            r.disturbances = "all" if name == "sos_bound" else "zero"
        # the sentence verify re-makes (lyapcheck.models.classes.claims), with the disturbances it covers and the box
        text = summary(name, r.to_json(), tuple(model.outputs), box.to_json() if box is not None else None)
        if text is not None:
            r.summary = text
    return ModelCertification(model=model, candidate=cand, results=results, seconds=seconds, box=box,
                              loop=base_loop(model.system, cylinder=False))


def _discrete_rule(entry: ModelClass, run: object, not_taken: str, results: dict[str, ConditionResult],
                   cand: object | None, disturbed: bool, over_box: bool = False) -> ConditionResult | None:
    """What every discrete-time kind of loop (a map, a map with functions, a sampled-data loop) decides before
    a class runs: a class without an entry for the kind (``run`` None) is ``not_applicable`` (``not_taken``:
    the kind's sentence); ``candidate`` without ``--candidate`` (:func:`_needs_input`); ``roa`` once GAS is
    certified with the disturbances at 0, which is what a map's classes are decided with
    (:func:`~lyapcheck.models.classes.claims.roa_after_gas`; ``over_box``: for every value of a map's box);
    None: run it."""
    from lyapcheck.models.classes.claims import roa_after_gas

    if run is None:
        return ConditionResult(entry.name, "not_applicable", not_taken)
    zero: Disturbances | None = "zero" if disturbed else None
    return _needs_input(entry.name, cand) or (roa_after_gas(results, zero, nominal=zero, over_box=over_box)
                                                    if entry.name == "roa" else None)


def _certify_functions(model: "RecastModel", classes: str | Sequence[str] | None, candidate: str | None,
                       limit: float, box: "ModelBox | None") -> ModelCertification:
    """:func:`certify_model` on a loop with functions: the classes run on its recasting
    (:func:`lyapcheck.models.classes.recast_regions.functions_run`, the one runner), each certified one's
    sentence made from its certificate; with ``box`` (``model`` read at its centre), every certified claim
    holds for every value of it and says so first, and a refutation is the centre's and says so."""
    from lyapcheck.models.classes import region_size
    from lyapcheck.models.classes.claims import box_prefix, covered, nominal_coverage, roa_after_gas, sentence_of
    from lyapcheck.models.classes.recast_interval import box_units
    from lyapcheck.models.classes.recast_regions import functions_run

    cand = Candidate(candidate, model.candidate_v) if candidate is not None else None
    chosen = class_selection(classes, model, cand)
    results: dict[str, ConditionResult] = {}
    seconds: dict[str, float] = {}
    ctx = functions_run(model, chosen, model.candidate_v if cand is not None else None, limit, box, results)
    nominal = nominal_coverage(model.disturbances.values())  # what a claim on the recasting covers (d = 0)

    def decide(entry: ModelClass) -> ConditionResult | None:
        # roa after GAS, weighed as on a polynomial loop; GAS with d = 0 answers at once here (this loop's roa
        # has no route that tries a region for every disturbance alone first)
        return _needs_input(entry.name, cand) or (  # (the user's V is proved over a box too)
            roa_after_gas(results, "all" if model.disturbances else None, nominal, box is not None)
            or roa_after_gas(results, "zero", nominal, box is not None) if entry.name == "roa" else None)

    def compute(entry: ModelClass) -> Callable[[Budget], ConditionResult] | None:
        run_functions = entry.run_functions
        return None if run_functions is None else lambda budget: run_functions(ctx, budget)

    # guarded as a polynomial loop's: a hard stop at the time limit, numerical trouble inconclusive
    _run_classes(chosen, results, seconds, limit, decide, compute)
    loop = ctx.loop
    for name in chosen:
        if name not in results:  # (the sentence never lists the class it refuses)
            where = " over a box: certify a point (--set NAME=VALUE)" if box is not None else ""
            results[name] = ConditionResult(name, "not_applicable", "not taken yet for a loop with functions (sin, "
                                            "sqrt, sat, ...)" + where)
    results = {name: results[name] for name in chosen}
    # the loop is recast with every disturbance at 0 (which covers them all where each bound is 0)
    coverage = nominal_coverage(model.disturbances.values())
    units = box_units(model)
    for name, r in results.items():
        if r.status == "certified" and name not in ("linearization", "sos_bound"):  # (sos_bound's is its own)
            if units is not None and r.certificate.get("kind") == "interval":
                r.certificate["units"] = units  # (the box it prints, in the states' units)
            r.summary = sentence_of(r.certificate)
            if name in region_size.SIZED_CLASSES:
                _attach_size(r, model, r.certificate.get("variables", []), model.system)
        if coverage is not None and name != "sos_bound":
            if r.disturbances is None:  # ("all": a region proved for every disturbance value)
                r.disturbances = coverage
            if r.status in ("certified", "refuted"):
                r.summary = covered(r.disturbances, r.summary)
    if box is not None:
        for name, r in results.items():
            if r.status in ("certified", "refuted") and not (name == "linearization" and r.status == "refuted"):
                r.summary = box_prefix(box, r.status) + r.summary  # (a linearization's refutation names its point)
    return ModelCertification(model=model, candidate=cand, results=results, seconds=seconds, box=box, loop=loop)


def _ball_after_sos(out: ModelCertification, model: Model, box: "ModelBox | None", stopped: list[BaseException],
                    cleared: bool, run: Callable[[str, Callable[[Budget], ConditionResult]], None]) -> None:
    """``roa`` by ball arithmetic on the true field (:mod:`lyapcheck.models.surfaces.ball_roa`) where its SOS
    route did not certify and did not stop at the time limit, on a loop the ball route takes; with
    a budget of its own (the class's seconds add up). Not where ``roa`` is ``not_applicable`` after
    GAS (``cleared``: the field was multiplied through, so that is the reason)."""
    from lyapcheck.models.surfaces import ball_roa

    sos = out.results["roa"]
    if (sos.status == "not_applicable" and cleared) or not ball_roa.sos_ended(sos, stopped) \
            or not ball_roa.takes(model, box):
        return
    seconds = out.seconds.get("roa", 0.0)
    run("roa", lambda budget: ball_roa.after_sos(model, sos, budget))
    out.seconds["roa"] += seconds


def _attach_size(r: ConditionResult, model: "Model | RecastModel", variables: Sequence[str], system: Any = None
                 ) -> None:
    """A certified region's largest ball and axis extents (:mod:`lyapcheck.models.classes.region_size`),
    into its certificate and figures; a certificate without a V and a level has none."""
    from lyapcheck.models.classes import region_size

    if "V" not in r.certificate or "level" not in r.certificate:
        return
    region_size.attach(r, model.states, region_size.extras_of(variables, model.states, system), model.units)


def stated_polynomials(model: Model, box: "ModelBox | None", name: str, certificate: dict[str, Any]
                       ) -> list[tuple[dict[str, Any], list[str]]]:
    """The parts of a certified condition's certificate that state a ``V`` (``sos_bound``: one per
    output), each with the names of its exponents: the states, then (``sos_bound``) the
    disturbances, then a box's parameters."""
    box_names = list(box.names) if box is not None else []
    if name == "sos_bound":
        outputs = certificate.get("outputs")
        if not isinstance(outputs, dict):
            return []
        names = list(model.states) + list(model.disturbances) + box_names
        return [(data, names) for data in outputs.values() if isinstance(data, dict) and "V" in data]
    return [(certificate, list(model.states) + box_names)] if "V" in certificate else []


def readable_v(model: Model, terms: dict[str, Any], variables: list[str]) -> str:
    """``V_text``: :func:`lyapcheck.models.classes.claims.v_text` in the declared states (shifted where the
    equilibrium is not 0)."""
    from lyapcheck.models.classes.claims import v_text

    return v_text(terms, variables, dict(zip(model.states, model.equilibrium)))


def box_start(model: Model, box: "ModelBox | None") -> int | None:
    """The index of a box's first parameter in the shifted field's ring (after the states and the
    disturbances), or None without a box."""
    return None if box is None else model.n + len(model.disturbances)


def _text(shifted: ShiftedField, p: Poly) -> str:
    return str(p).replace("^", "**")


def _numerical_errors() -> tuple[type[BaseException], ...]:
    """The errors of numerical trouble (evaluated when one propagates: numpy's only where loaded)."""
    import sys

    from lyapcheck.errors import SolverError

    numpy = sys.modules.get("numpy")
    linalg = (numpy.linalg.LinAlgError,) if numpy is not None else ()
    return (SolverError, ArithmeticError, OverflowError, *linalg)


def _guarded(name: str, compute: Callable[[], ConditionResult], limit: float) -> ConditionResult:
    """Numerical trouble or the time limit becomes ``inconclusive`` with its reason; bad input and
    bugs propagate (the command line reports them)."""
    from lyapcheck.models.engines import reasons

    try:
        # a hard stop a little beyond the cooperative budget (a solve or check that overruns it)
        with time_limit(limit * HARD_STOP_FACTOR + HARD_STOP_GRACE_S):
            return compute()
    except BudgetExhausted as exc:
        reason = str(exc)
        why = reasons.out_of_time(reasons.searched_for(name), limit, reason)
    except ClassTimeLimit as exc:
        reason = f"{exc} (lyapcheck.tolerances.MODEL_CLASS_TIME_LIMIT_S, hard stop)"
        why = reasons.out_of_time(reasons.searched_for(name), limit, reason,
                                  hard_stop=limit * HARD_STOP_FACTOR + HARD_STOP_GRACE_S)
    except _numerical_errors() as exc:
        reason = f"{type(exc).__name__}: {exc}"
        why = reasons.numerical_trouble(reasons.searched_for(name), reason)
    log.info("%s inconclusive: %s", name, reason)
    return ConditionResult(name, "inconclusive", why.summary, numbers=why.numbers({"reason": reason}))


__all__ = ["MODEL_CLASSES", "ModelCertification", "certify_model", "parse_candidate", "class_selection",
           "refuse_box_in_candidate"]
