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
from lyapcheck.degrees import searched_degrees
from lyapcheck.errors import InvalidParameter, ModelFileError
from lyapcheck.models.classes.registry import CLEARED, NAMES
from lyapcheck.models.loop.field import ScaledField, Scaling, ShiftedField, StateField, active_disturbances, \
    apply_scaling, choose_scaling, clear, robust_field, shifted_field, state_field
from lyapcheck.models.language.modelfile import Model
from lyapcheck.models.engines import reasons
from lyapcheck.models.engines.search import Budget, BudgetExhausted, Search
from lyapcheck.results import ConditionResult, Disturbances
from lyapcheck.sos.polynomials import Poly
from lyapcheck.timing import ClassTimeLimit, time_limit

if TYPE_CHECKING:  # pragma: no cover
    import numpy as np  # imported where a class computes with floats: reading a model, or re-checking a
    # stored certificate (lyapcheck.models.engines.store), needs none of it

    from lyapcheck.models.engines.numeric import SetCrossCheck
    from lyapcheck.models.language.parameter_box import ModelBox
    from lyapcheck.models.language.recast import RecastModel

log = logging.getLogger(__name__)

#: the classes, in the order they run (:data:`lyapcheck.models.classes.registry.CLASSES`, where each is declared)
MODEL_CLASSES: Final = NAMES
#: the classes that need the field multiplied through (every denominator of one sign proved)
CLEARED_CLASSES: Final = CLEARED
#: grid of simulated starts per state for the roa share, by number of states (beyond: random starts)
ROA_GRID: Final = {1: 401, 2: 101, 3: 21}
ROA_RANDOM_STARTS: Final = 4000
#: simulated time of the roa cross-check, in units of the loop's typical time
ROA_HORIZON: Final = 60.0
#: over a box, sos_gas's V may depend on the parameters up to these degrees, in turn
BOX_PARAM_DEGREES: Final = (0, 1)
#: a class's hard stop (:func:`lyapcheck.timing.time_limit`) comes at its limit times this plus
#: HARD_STOP_GRACE_S: past the cooperative budget, for a solve, exact check or simulation that
#: overruns it. With the 60 s limit: 95 s
HARD_STOP_FACTOR: Final = 1.5
HARD_STOP_GRACE_S: Final = 5.0


@dataclass
class Candidate:
    """The user's ``V``: the text as given, and the polynomial in the declared (unshifted) states."""

    text: str
    poly: Poly


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


def refuse_candidate_over_box(source: str, candidate: str | None, box: object | None) -> None:
    """``--candidate`` with ``--box`` is bad input on every kind of loop (exit 2 naming ``--candidate``): the
    candidate class certifies a point (docs/model-files.md, "Boxes of parameters")."""
    if box is not None and candidate is not None:
        raise ModelFileError(source, "--candidate", "not over a --box (the candidate class certifies a point)")


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
    box's centre, :func:`lyapcheck.models.surfaces.recast_run.certify_box`)."""
    import time

    from lyapcheck import tolerances as tol

    limit = tol.MODEL_CLASS_TIME_LIMIT_S if time_limit_s is None else float(time_limit_s)
    refuse_candidate_over_box(model.source, candidate, box)
    from lyapcheck.models.loop.discrete import is_discrete

    if is_discrete(model):  # a map never reaches the classes that read [dynamics] as a field
        return _certify_map(model, classes, candidate, limit, box)  # type: ignore[arg-type]
    if not isinstance(model, Model):  # a loop with functions: its classes run on the recasting
        return _certify_functions(model, classes, candidate, limit, box)
    cand = parse_candidate(model, candidate) if candidate is not None else None
    chosen = class_selection(classes, model, cand)
    out = ModelCertification(model=model, candidate=cand, results={}, box=box)
    shifted = shifted_field(model, box=box)

    def run(name: str, compute: Callable[[Budget], ConditionResult]) -> None:
        start = time.perf_counter()
        budget = Budget(limit, "lyapcheck.tolerances.MODEL_CLASS_TIME_LIMIT_S")
        out.results[name] = _guarded(name, lambda: compute(budget), limit)
        out.seconds[name] = time.perf_counter() - start

    if "linearization" in chosen and box is not None:
        from lyapcheck.models.classes import linearization

        run("linearization", lambda budget: linearization.run_over_box(shifted))
    elif "linearization" in chosen:
        from lyapcheck.models.classes import linearization

        run("linearization", lambda budget: linearization.run(shifted))
    needing = [c for c in chosen if c in CLEARED_CLASSES]
    scaled: ScaledField | None = None
    from lyapcheck.models.surfaces import ball_roa

    roa_stopped: list[BaseException] = []  # what ended roa's SOS route, where it raised
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
            for name in needing:
                out.results[name] = ConditionResult(name, "not_applicable", why, numbers={"denominator":
                                                                                          _text(shifted, failed)})
        else:
            cleared = clear(shifted, signs)
            out.scaling = choose_scaling(cleared, model.domain)
            scaled = apply_scaling(cleared, out.scaling)
    if scaled is not None:
        sc = scaled
        from lyapcheck.models.classes import lyapunov

        robust = robust_field(sc)
        nominal = state_field(sc)
        enters = bool(active_disturbances(sc))
        #: what a claim on the nominal field covers
        nominal_covers: Disturbances | None = ("all" if not enters else "zero") if model.disturbances else None

        def stability(attempt: Callable[[StateField, Search], ConditionResult]) -> Callable[[Budget], ConditionResult]:
            return lambda budget: covering_disturbances(
                model, robust, nominal, enters, lambda f: attempt(f, Search(f.ring, budget)))

        if "quadratic" in chosen:
            run("quadratic", stability(lambda f, search: lyapunov.run(sc, "quadratic", (2,), search,
                                                                                   field=f)))
        if "sos_gas" in chosen:
            run("sos_gas", stability(lambda f, search: lyapunov.run(
                sc, "sos_gas", searched_degrees(lyapunov.SOS_GAS_DEGREES), search, param_degrees=BOX_PARAM_DEGREES, field=f)))
        if "roa" in chosen:
            lin = out.results.get("linearization")
            gas = {r.disturbances: name for name, r in out.results.items()
                   if name in ("quadratic", "sos_gas") and r.status == "certified"}
            covering = "all" if model.disturbances else None
            if covering in gas:
                out.results["roa"] = ConditionResult(
                    "roa", "not_applicable", f"global asymptotic stability is certified ({gas[covering]}): the region "
                    "of attraction is the whole state space", property="ROA", disturbances=covering)
            else:
                def roa(budget: Budget) -> ConditionResult:
                    memo: dict[str, Any] = {}
                    if robust is not None:
                        found = run_roa(sc, budget, lin, robust, memo)
                        if found.status == "certified":
                            return _covers(found, "all")
                    if "zero" in gas:
                        return ConditionResult("roa", "not_applicable", f"global asymptotic stability is certified "
                                               f"({gas['zero']}, d = 0): with every disturbance held at 0 the region "
                                               "of attraction is the whole state space", property="ROA",
                                               disturbances="zero")
                    return _covers(run_roa(sc, budget, lin, nominal, memo), nominal_covers)

                run("roa", ball_roa.recording(roa, roa_stopped))
        if "candidate" in chosen and cand is not None:  # without --candidate: not_applicable, below
            # the user's V is tried on the nominal loop (its global test has no box multipliers yet)
            run("candidate", lambda budget: _covers(run_candidate(sc, cand, budget), nominal_covers))
        if "barrier" in chosen and _has_safety_sets(model) and not _sets_use_box(model, box):
            from lyapcheck.models.classes import barrier

            run("barrier", lambda budget: barrier.run(sc, Search(sc.ring, budget)))
        if "reach_avoid" in chosen and _has_safety_sets(model, goal=True) and not _sets_use_box(model, box):
            from lyapcheck.models.classes import reach_avoid

            run("reach_avoid", lambda budget: reach_avoid.run(sc, Search(sc.ring, budget)))
        if "sos_bound" in chosen:
            from lyapcheck.models.classes import bounds

            if not model.disturbances:
                out.results["sos_bound"] = ConditionResult("sos_bound", "not_applicable",
                                                           "the model has no [disturbances]: add one (name = bound) to "
                                                           "bound its outputs")
            else:
                run("sos_bound", lambda budget: bounds.run(sc, Search(sc.ring, budget)))
    if "roa" in out.results:  # the ball-arithmetic engine, where the SOS route did not certify
        _ball_after_sos(out, model, box, roa_stopped, scaled is not None, run)
    if "linearization" in out.results and model.disturbances:
        from lyapcheck.models.classes.claims import nominal_coverage

        # the Jacobian at d = 0: every admissible disturbance where each bound is 0
        out.results["linearization"].disturbances = nominal_coverage(model.disturbances.values())
    if "sos_bound" in out.results and model.disturbances:
        out.results["sos_bound"].disturbances = "all"
    if "barrier" in chosen and "barrier" not in out.results:
        why = ("over a box the sets may not depend on a parameter of the box (they are read at the model's values)"
               if _has_safety_sets(model) and _sets_use_box(model, box) else
               "the model's [sets] needs 'initial' and 'unsafe' (docs/model-files.md, [sets])")
        out.results["barrier"] = ConditionResult("barrier", "not_applicable", why)
    if "reach_avoid" in chosen and "reach_avoid" not in out.results:
        why = ("over a box the sets may not depend on a parameter of the box (they are read at the model's values)"
               if _has_safety_sets(model, goal=True) and _sets_use_box(model, box) else
               "the model's [sets] needs 'initial', 'unsafe' and 'goal' (docs/model-files.md, [sets])")
        out.results["reach_avoid"] = ConditionResult("reach_avoid", "not_applicable", why)
    for name in ("barrier", "reach_avoid"):
        if name in out.results and model.disturbances:
            out.results[name].disturbances = "all"  # B or V serves every disturbance (the robust field)
    if "candidate" in chosen and box is not None:
        out.results["candidate"] = ConditionResult("candidate", "not_applicable", reasons.NOT_OVER_A_BOX["candidate"])
    elif "candidate" in chosen and cand is None:
        out.results["candidate"] = ConditionResult("candidate", "not_applicable", reasons.NEEDS_CANDIDATE)
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


def _certify_map(model: Model, classes: str | Sequence[str] | None, candidate: str | None, limit: float,
                 box: "ModelBox | None") -> ModelCertification:
    """:func:`certify_model` on a discrete-time map (``[model] time = "discrete"``): the one place where a
    map's classes are chosen. A class with a discrete-time condition
    (:data:`lyapcheck.models.classes.registry.DISCRETE`) runs on the shifted map; every other one asked for
    is ``not_applicable`` (:func:`lyapcheck.models.loop.discrete.not_decided`), never run on the map as if
    it were a field. ``--box`` is refused in one line (exit 2)."""
    import time

    from lyapcheck.models.classes.registry import DISCRETE
    from lyapcheck.models.loop.discrete import not_decided, refuse, shifted_map

    if box is not None:
        refuse(model, "--box", "certify a point (--set NAME=VALUE)")
    cand = parse_candidate(model, candidate) if candidate is not None else None
    chosen = class_selection(classes, model, cand)
    out = ModelCertification(model=model, candidate=cand, results={})
    for name in chosen:
        if name not in DISCRETE:
            out.results[name] = ConditionResult(name, "not_applicable", not_decided(name, DISCRETE))
    if "linearization" in chosen:
        from lyapcheck.models.classes import discrete_linearization

        start = time.perf_counter()
        shifted = shifted_map(model)
        out.results["linearization"] = _guarded("linearization", lambda: discrete_linearization.run(shifted), limit)
        out.seconds["linearization"] = time.perf_counter() - start
    for name in ("quadratic", "sos_gas"):
        if name in chosen and name in DISCRETE:
            from lyapcheck.models.classes import discrete_lyapunov

            start = time.perf_counter()
            shifted = shifted_map(model)
            out.results[name] = _guarded(name, lambda: discrete_lyapunov.run(shifted, name), limit)  # type: ignore[arg-type]
            out.seconds[name] = time.perf_counter() - start
    out.results = {name: out.results[name] for name in MODEL_CLASSES if name in out.results}
    for r in out.results.values():  # the linearization is the Jacobian at d = 0
        if model.disturbances:
            r.disturbances = "zero"
    from lyapcheck.models.classes.claims import summary

    for name, r in out.results.items():
        text = summary(name, r.to_json(), tuple(model.outputs), None)
        if text is not None:
            r.summary = text
    return out


def _certify_functions(model: "RecastModel", classes: str | Sequence[str] | None, candidate: str | None,
                       limit: float, box: "ModelBox | None") -> ModelCertification:
    """:func:`certify_model` on a loop with functions: the classes run on its recasting
    (:func:`lyapcheck.models.surfaces.recast_run.certify`), each certified one's sentence made from its
    certificate; with ``box`` (``model`` read at its centre), every certified claim holds for every value
    of it and says so first, and a refutation is the centre's and says so."""
    from lyapcheck.models.classes import region_size
    from lyapcheck.models.classes.claims import box_prefix, covered, nominal_coverage, sentence_of
    from lyapcheck.models.classes.recast_interval import box_units
    from lyapcheck.models.surfaces import recast_run

    cand = Candidate(candidate, model.candidate_v) if candidate is not None else None
    chosen = class_selection(classes, model, cand)
    results, loop, seconds = recast_run.certify(model, chosen, model.candidate_v if cand is not None else None,
                                                limit, box)
    if "candidate" in chosen and "candidate" not in results:  # asked for without --candidate
        results["candidate"] = ConditionResult("candidate", "not_applicable", reasons.NEEDS_CANDIDATE)
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
            if r.status in ("certified", "refuted"):
                r.summary = box_prefix(box, r.status) + r.summary
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


def covering_disturbances(model: Model, robust: StateField | None, nominal: StateField, enters: bool,
                          attempt: Callable[[StateField], ConditionResult]) -> ConditionResult:
    """A stability class on a model, saying which disturbances its claim covers (DESIGN.md,
    "Disturbances in claims"): without disturbances, the plain claim; where no disturbance enters
    the field (``enters`` false: a bound of 0, or one that acts on an output only), the nominal claim,
    which then covers them all; with disturbances that vanish at the equilibrium (``robust``), first
    the robust claim (``V`` common to every disturbance value, so it holds for every disturbance
    signal: ``"all"``), and only if that is not found the nominal one (``"zero"``, saying that the
    robust one was tried); otherwise (a disturbance moves the equilibrium) the nominal one
    (``"zero"``)."""
    if not model.disturbances:
        return attempt(nominal)
    if not enters:
        return _covers(attempt(nominal), "all")
    if robust is not None:
        found = attempt(robust)
        if found.status in ("certified", "inconclusive"):
            return _covers(found, "all")
        fallback = _covers(attempt(nominal), "zero")
        if fallback.status == "certified":
            fallback.numbers["robust_attempt"] = found.summary
        return fallback
    return _covers(attempt(nominal), "zero")


def _covers(result: ConditionResult, disturbances: "Disturbances | None") -> ConditionResult:
    result.disturbances = disturbances
    return result


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


# -- roa and candidate -------------------------------------------------------------------------------

def simulated_region(scaled: ScaledField, samples_declared: np.ndarray) -> np.ndarray:
    """Which declared starts converge to the equilibrium (disturbances 0); over a box, at every
    parameter point of :func:`parameter_points` (its centre and corners)."""
    import numpy as np

    from lyapcheck.models.engines.numeric import converges, typical_time

    model = scaled.cleared.shifted.model
    half = _half_widths(model)
    converged = np.ones(len(samples_declared), dtype=bool)
    for params in parameter_points(scaled):
        T = typical_time(model, params)
        converged &= converges(model, samples_declared, t_end=ROA_HORIZON * T, radius=half * 1e-3, escape=half * 1e3,
                               parameters=params).converged
    return converged


def parameter_points(scaled: ScaledField) -> list[dict[str, Fraction]]:
    """The model's parameters, and over a box those at its centre and corners."""
    model = scaled.cleared.shifted.model
    box = scaled.cleared.shifted.box
    if box is None:
        return [dict(model.parameters)]
    centre = {name: box.center(name) for name in box.names}
    return [{**model.parameters, **centre}] + [{**model.parameters, **corner} for corner in box.corners()]


def _half_widths(model: Model) -> np.ndarray:
    import numpy as np

    if model.domain:
        return np.array([max(abs(float(model.domain[s][0] - e)), abs(float(model.domain[s][1] - e)))
                         for s, e in zip(model.states, model.equilibrium)])
    return np.ones(model.n)


def roa_starts(model: Model, seed: int = 0) -> np.ndarray:
    import numpy as np

    from lyapcheck.models.engines.numeric import grid_starts

    assert model.domain is not None
    per_axis = ROA_GRID.get(model.n)
    if per_axis is None:  # beyond ROA_GRID: random starts (two per axis would be the domain's corners alone)
        return grid_starts(model.domain, model.states, ROA_RANDOM_STARTS, ROA_RANDOM_STARTS, seed=seed)
    return grid_starts(model.domain, model.states, per_axis, per_axis ** model.n, seed=seed)


def run_roa(scaled: ScaledField, budget: Budget, linearization: ConditionResult | None,
            field_: StateField | None = None, memo: dict[str, Any] | None = None) -> ConditionResult:
    """The ``roa`` class on ``field_`` (default: the nominal :func:`state_field`; the robust one
    proves a set common to every disturbance value). ``memo`` keeps the simulated starts between
    the robust and the nominal attempt (they simulate the same loop, with the disturbances at 0)."""
    import numpy as np

    from lyapcheck.models.engines import reasons
    from lyapcheck.models.classes import regions

    model = scaled.cleared.shifted.model
    if field_ is None:
        field_ = state_field(scaled)
    search = Search(field_.ring, budget)
    A = np.array([[float(x) for x in row] for row in scaled.scaling.matrix()])
    eq = np.array([float(v) for v in model.equilibrium])
    if regions.lyapunov_quadratic(field_) is None:
        why = reasons.reason("the Jacobian at the equilibrium is not Hurwitz"
                             + (" at the box's centre" if field_.p > field_.disturbances
                                else " with the disturbances at 0" if field_.p else "")
                             + ", so no quadratic Lyapunov function starts the search (see linearization)",
                             ("candidate",))
        return ConditionResult("roa", "not_certified", why.summary, numbers=why.numbers(), property="ROA")
    memo = {} if memo is None else memo
    if "starts" not in memo:
        if model.domain:
            starts = roa_starts(model)
        else:
            rng = np.random.default_rng(0)
            starts = eq + rng.uniform(-4, 4, size=(ROA_RANDOM_STARTS if model.n > 2 else 2500, model.n)) @ A.T
        memo["starts"], memo["converged"] = starts, simulated_region(scaled, starts)
    starts, converged = memo["starts"], memo["converged"]
    samples = scaled.scaling.to_scaled(starts - eq)
    outcome = regions.enlarge(field_, search, samples, converged)
    if outcome.certificate is None:
        why = reasons.reason("no region of attraction was proved: no level set of the linearization's quadratic V "
                             "could be proved to shrink", ("domain", "candidate", "time"),
                             "no sublevel set passed the exact check")
        return ConditionResult("roa", "not_certified", why.summary, property="ROA",
                               solver={"solves": search.log}, numbers=why.numbers({"history": outcome.history}))
    cert = outcome.certificate
    inside = regions.NumericPoly(field_.ring, cert.V.poly(field_.ring))(regions.on_states(field_, samples)) \
        <= float(cert.level)
    numbers: dict[str, Any] = {"degree": 2 * max(sum(m) for m in cert.V.basis), "simulated_starts": int(len(starts))}
    if model.domain:
        if converged.any():  # (no simulated start converged in the horizon: no share to state, not a share of 0)
            numbers["roa_share"] = float(np.mean(inside[converged]))
        numbers["simulated_roa_share_of_domain"] = float(np.mean(converged))
    suspicious = inside & ~converged
    if suspicious.any():  # a start in a proved set that did not converge: simulate it far longer, V watched
        V = regions.NumericPoly(field_.ring, cert.V.poly(field_.ring))

        def value(X: np.ndarray) -> np.ndarray:
            return V(regions.on_states(field_, scaled.scaling.to_scaled(np.atleast_2d(X) - eq)))

        try:
            again = simulated_region_long(scaled, starts[suspicious], value, float(cert.level))
        except ClassTimeLimit:  # the hard stop may end this check, never the proof before it
            numbers["long_simulation"] = "stopped by the class's hard time limit"
        else:
            numbers.update(again.numbers())
    numbers["rounds"] = outcome.history
    return regions.level_result("roa", scaled, field_, cert, search, numbers, "region of attraction")


def simulated_region_long(scaled: ScaledField, starts: np.ndarray, value: Callable[[np.ndarray], np.ndarray],
                          level: float) -> SetCrossCheck:
    """Starts (declared states, rows) in the certified set ``{value <= level}`` that did not converge
    in the first simulation, simulated twenty times longer at every parameter point with V watched
    (:func:`lyapcheck.models.engines.numeric.check_certified_set`): a violation only where one leaves the
    set (the certificate gives no decrease rate to bound the time to converge); the others, still
    converging, are not checked."""
    import numpy as np

    from lyapcheck.models.engines.numeric import FieldEvaluator, ModelSystem, SetCrossCheck, check_certified_set, typical_time
    from lyapcheck.models.engines.trajectories import RTOL

    model = scaled.cleared.shifted.model
    half = _half_widths(model)
    eq = np.array([float(v) for v in model.equilibrium])
    left = np.zeros(len(starts), dtype=bool)
    converged = np.ones(len(starts), dtype=bool)
    for params in parameter_points(scaled):
        system = ModelSystem(FieldEvaluator.of(model, params), len(starts), escape=half * 1e3, center=eq)
        found = check_certified_set(system, starts, 20 * ROA_HORIZON * typical_time(model, params), value=value,
                                    level=level, converged=lambda X: np.all(np.abs(X - eq) <= half * 1e-3, axis=1),
                                    rtol=RTOL, atol=half * 1e-6, max_iterations=200_000)
        left |= found.left
        converged &= found.converged
    return SetCrossCheck(left=left, overdue=np.zeros(len(starts), dtype=bool), converged=converged & ~left)


def run_candidate(scaled: ScaledField, cand: Candidate | None, budget: Budget) -> ConditionResult:
    import numpy as np

    from lyapcheck.models.engines import reasons
    from lyapcheck.models.classes import regions
    from lyapcheck.models.classes.lyapunov import best_decay_rate, stated_v
    from lyapcheck.sos.polynomials import to_fmpq

    assert cand is not None
    model = scaled.cleared.shifted.model
    field_ = state_field(scaled)
    ring = field_.ring
    search = Search(ring, budget)
    full = model.state_ring
    # V(x_eq + S z): the candidate in the scaled states
    from lyapcheck.models.loop.field import linear_images

    images = linear_images(full, model.n, scaled.scaling.matrix())
    images = [im + to_fmpq(e) for im, e in zip(images[:model.n], model.equilibrium)] + images[model.n:]
    v_scaled = full.restrict(full.compose(cand.poly, images), ring)
    V = regions.gram_of(field_, v_scaled, search)
    if V is None:
        why = reasons.reason("the candidate V could not be proved positive definite and radially unbounded",
                             ("other_candidate",), "no positive definite Gram matrix over its reduced basis with a "
                             "pure power of every state")
        return ConditionResult("candidate", "not_certified", why.summary, numbers=why.numbers(),
                               solver={"solves": search.log}, property="ROA")
    sigma = regions.global_decrease(field_, V, Fraction(0), search)
    if sigma is not None:
        def attempt(mu: Fraction) -> dict[str, Any] | None:
            s = regions.global_decrease(field_, V, mu, search)
            return None if s is None else {"sigma": s, "mu": mu}

        best = best_decay_rate(attempt, {"sigma": sigma, "mu": Fraction(0)})
        rate = float(best["mu"] / scaled.scaling.time)
        tail = f", V' <= -{rate:.4g} V" if best["mu"] > 0 else ""
        return ConditionResult("candidate", "certified", f"GAS: V' < 0 away from the equilibrium everywhere{tail} "
                                                         "(checked exactly)",
                               numbers={"decay_rate_V_per_s": rate},
                               certificate={"kind": "lyapunov", "mu_scaled": str(best["mu"]),
                                            "V": stated_v(scaled, field_, V.poly(ring)), "gram_V": V.to_json(),
                                            "gram_sigma": best["sigma"].to_json()},
                               solver={"solves": search.log}, property="GAS")
    radius = float(np.max(np.abs(scaled.scaling.to_scaled(np.diag(_half_widths(model)))))) * 4
    top = regions.supremum_estimate(field_, V, radius)
    if top is None:
        # no sample with V' >= 0 out to 4 half-widths: search the level upwards from V's largest
        # value there, each step an SOS lower bound of min {V : V' >= 0} (no sample needed)
        rng = np.random.default_rng(0)
        ball = rng.normal(size=(200, field_.n))
        ball *= radius / np.linalg.norm(ball, axis=1, keepdims=True)
        guess = float(np.max(regions.NumericPoly(ring, V.poly(ring))(regions.on_states(field_, ball))))
        cert = regions.largest_level(field_, V, search, guess, regions.symmetry(field_), grow=True)
        if cert is None:
            why = reasons.reason("V' < 0 could not be proved everywhere, nor on any level set {V <= c} (no point with "
                                 "V' >= 0 was sampled)", ("other_candidate", "domain", "time"),
                                 f"no level from {guess:.6g} upwards passed the level program")
            return ConditionResult("candidate", "not_certified", why.summary, numbers=why.numbers(),
                                   solver={"solves": search.log}, property="ROA")
        return regions.level_result("candidate", scaled, field_, cert, search, {"level_search": "upwards, by SOS"},
                                    "the user's V")
    cert = regions.largest_level(field_, V, search, top, regions.symmetry(field_))
    if cert is None:
        why = reasons.reason("V' < 0 could not be proved everywhere, nor on any level set {V <= c} below the "
                             f"sampled points where V' >= 0 (V = {top:.6g})", ("other_candidate", "time"),
                             f"no level of V passed the exact check (sampled supremum {top:.6g})")
        return ConditionResult("candidate", "not_certified", why.summary,
                               numbers=why.numbers({"level_supremum_estimate": top}),
                               solver={"solves": search.log}, property="ROA")
    return regions.level_result("candidate", scaled, field_, cert, search,
                                {"level_supremum_estimate": top, "level_ratio_to_estimate": float(cert.level) / top},
                                "the user's V")


__all__ = ["MODEL_CLASSES", "ModelCertification", "certify_model", "parse_candidate", "class_selection",
           "refuse_candidate_over_box"]
