"""``verify`` of a model certificate: one flow for every kind of loop.

:func:`lyapcheck.models.surfaces.certificate.verify_document` reads the model again from the document's text
and makes the rows every document starts with (its SHA-256, its parse, the stated parameters and
figures); :func:`verify_model` then runs the same steps on every loop, in this order:

1. the loop's own table against the model text (:attr:`LoopKind.prelude`: a loop with functions' recasting,
   re-derived from the text, so that a certificate cannot bring its own);
2. the box, read and held to the model (:attr:`LoopKind.read_box`);
3. each decided condition through its class's entry (:func:`lyapcheck.models.classes.registry.verify`, with
   the check context of the loop's kind; :attr:`LoopKind.conditions`); a ``certified`` or ``refuted`` one
   that no check re-derived fails (:func:`_unchecked_claims`). Where the mathematics differs it is a
   named step of this one: a polynomial or rational loop's cleared field (:func:`_cleared_field`: its
   denominators' positivity proofs and its scaling) under its SOS certificates, and its ball-arithmetic
   regions on the true field; a loop with functions' claim over a box, its disturbance coverage and its
   stated figures (:func:`~lyapcheck.models.surfaces.stated.proved_claims`) before the proof;
4. the sizes of the certified regions (:func:`lyapcheck.models.classes.region_size.check_size_rows`);
5. the counterexamples, re-simulated (:mod:`lyapcheck.models.surfaces.counterexamples`; on a loop with
   functions its true loop, at the point of the box where each was found);
6. what the document states beside its proofs: the stated V, the ``disturbances`` keys, the candidate
   text, the summaries and the stated figures (:mod:`lyapcheck.models.surfaces.stated`);
7. the verdict and the answers (:func:`lyapcheck.models.surfaces.documents.with_verdict`).

A kind of loop (:data:`FIELD`, :data:`MAP`, :data:`FUNCTIONS`, :data:`MAP_FUNCTIONS`, :data:`SAMPLED`;
:func:`loop_kind`) supplies its part of each step as a small function, or None where the step has nothing to
check on it (a map's counterexamples are its classes' own checks, step 3; a sampled-data loop's first step
is its ``sampling`` table, read by :func:`lyapcheck.models.surfaces.certificate.verify_document` with the
sampled-data reader). Nothing here calls a solver.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from fractions import Fraction
from typing import TYPE_CHECKING, Any, Callable, Final

from lyapcheck.models.surfaces.counterexamples import check_counterexamples, describe_exception as _describe
from lyapcheck.models.surfaces.documents import with_verdict
from lyapcheck.models.surfaces.stated import candidate_of_functions, candidate_of_polynomial, check_disturbance_keys, \
    check_stated, check_stated_claims, check_stated_v, check_summaries, proved_claims

if TYPE_CHECKING:  # pragma: no cover  (a loop with functions' modules are imported where one is checked)
    from lyapcheck.models.language.parameter_box import ModelBox
    from lyapcheck.models.language.recast import RecastModel
    from lyapcheck.models.surfaces.counterexamples import Check

#: verify's (check, ok, message) row
Row = tuple[str, bool, str]
#: what a malformed certificate raises inside one condition's check (verify reports it in that row)
MALFORMED: Final = (KeyError, ValueError, ArithmeticError, TypeError, IndexError, AttributeError)


@dataclass(frozen=True)
class Box:
    """The document's box as read (``box`` None: the document has none) and, on a loop with functions, the
    loop recast with the box's parameters as bounded constants (``boxed``)."""

    box: "ModelBox | None" = None
    boxed: Any = None


@dataclass(frozen=True)
class Stop:
    """The box cannot be checked: verify ends here, with the verdict row where ``verdict`` (a polynomial
    loop's document ends at its failed box row, as it always has)."""

    verdict: bool


@dataclass(frozen=True)
class LoopKind:
    """What one kind of loop supplies to each step of :func:`verify_model` (None: the step has nothing to
    check on it)."""

    #: the kind's name (for a reader: no row prints it)
    what: str
    #: step 1: the rows of the loop's own table (``doc``, ``model``, ``rows``)
    prelude: "Callable[[dict[str, Any], Any, list[Row]], None] | None"
    #: step 2: the box as read (its rows appended), or :class:`Stop`
    read_box: "Callable[[dict[str, Any], Any, list[Row]], Box | Stop]"
    #: step 3: each decided condition's row; False when a prerequisite of them failed (verify then ends)
    conditions: "Callable[[dict[str, Any], Any, Box, list[Row]], bool]"
    #: step 4: the keywords of :func:`~lyapcheck.models.classes.region_size.check_size_rows` (V's variables or
    #: the recasting naming them)
    size: "Callable[[Any, Box], dict[str, Any]] | None"
    #: step 5: the re-simulation of a counterexample, given the model and the box (a result None: the
    #: polynomial field's, :func:`~lyapcheck.models.surfaces.counterexamples.verify_counterexample`)
    counterexamples: "Callable[[Any, Box], Check | None] | None"
    #: step 6: the candidate text against the certified candidate V
    candidate: "Callable[[dict[str, Any], Any, list[Row]], None] | None"
    #: step 6: the stated V's ``variables`` and ``V_text`` (:func:`check_stated_v`)
    stated_v: bool = False
    #: step 6: the ``disturbances`` keys, the summaries and the stated figures, checked apart from each
    #: condition's proof (a loop with functions checks its stated figures with the proof, in step 3)
    stated_figures: bool = False


def verify_model(doc: dict[str, Any], model: Any, rows: list[Row]) -> list[Row]:
    """The rest of a model certificate's rows, after the ones every document starts with (module docstring):
    the same steps for every kind of loop, each with the kind's part (:func:`loop_kind`)."""
    kind = loop_kind(model)
    if kind.prelude is not None:
        kind.prelude(doc, model, rows)
    box = kind.read_box(doc, model, rows)
    if isinstance(box, Stop):
        return with_verdict(doc, rows) if box.verdict else rows
    if not kind.conditions(doc, model, box, rows):
        return with_verdict(doc, rows)
    conditions: dict[str, Any] = doc["conditions"]
    _unchecked_claims(conditions, rows)
    if kind.size is not None:
        from lyapcheck.models.classes.region_size import check_size_rows

        check_size_rows(model, conditions, rows, **kind.size(model, box))
    if kind.counterexamples is not None:
        check_counterexamples(model, conditions, rows, kind.counterexamples(model, box))
    if kind.stated_v:
        check_stated_v(model, box.box, conditions, rows)
    if kind.stated_figures:
        check_disturbance_keys(model, conditions, rows)
    if kind.candidate is not None:
        kind.candidate(doc, model, rows)
    if kind.stated_figures:
        check_summaries(model, conditions, rows, doc.get("box"))
        check_stated_claims(model, conditions, rows)
    return with_verdict(doc, rows)


def _unchecked_claims(conditions: dict[str, Any], rows: list[Row]) -> None:
    """A ``certified`` or ``refuted`` condition that no check of step 3 re-derived fails: a document that says
    ``refuted`` where nothing proves it (a certified ``quadratic`` edited to ``refuted`` on a polynomial loop,
    whose refutations are the linearization's only) would otherwise show an unproved claim beside a verdict
    that ignores it."""
    checked = {name for name, _, _ in rows}
    for name, c in conditions.items():
        if isinstance(c, dict) and c.get("status") in ("certified", "refuted") and name not in checked:
            rows.append((name, False, f"{name}: a {c['status']} claim that no check of this kind of loop re-derives"))


def _each(conditions: dict[str, Any], rows: list[Row], decided: Callable[[str, Any], bool],
          check: Callable[[str, dict[str, Any]], tuple[bool, str]],
          malformed: Callable[[BaseException], str] | None = None) -> None:
    """Step 3's row for each condition ``decided`` selects: ``check`` (its class's entry, through the loop
    kind's context), the message naming the class where it failed. ``malformed``: the row's words for a
    malformed certificate (None: the exception ends verify, ``certificate is malformed``)."""
    for name, c in conditions.items():
        if not decided(name, c):
            continue
        if malformed is None:
            ok, why = check(name, c)
        else:
            try:
                ok, why = check(name, c)
            except MALFORMED as exc:
                ok, why = False, malformed(exc)
        rows.append((name, ok, why if ok else f"{name}: {why}"))


def _status_in(*statuses: str) -> Callable[[str, Any], bool]:
    return lambda name, c: isinstance(c, dict) and c.get("status") in statuses


def _malformed(exc: BaseException) -> str:
    return f"malformed certificate: {_describe(exc)}"


# -- a polynomial or rational loop, and a polynomial map -----------------------------------------------

def _read_box_polynomial(doc: dict[str, Any], model: Any, rows: list[Row]) -> Box | Stop:
    """The box names the model's parameters in its order with lo < hi, and the equilibrium stays one over it
    (:func:`lyapcheck.models.loop.boxes.check_box`; on a map, its fixed point)."""
    if "box" not in doc:
        return Box()
    from lyapcheck.errors import ModelFileError
    from lyapcheck.models.loop.boxes import ModelBox, check_box

    box = ModelBox.from_json(doc["box"])
    if not all(name in model.parameters and lo < hi for name, lo, hi in box.bounds) or \
            list(box.names) != [p for p in model.parameters if p in box.names]:
        rows.append(("box", False, "the box must name the model's parameters, in its order, with lo < hi"))
        return Stop(verdict=False)
    try:
        check_box(model, box)
    except ModelFileError as exc:
        rows.append(("box", False, f"the box is not valid for the model: {exc}"))
        return Stop(verdict=False)
    rows.append(("box", True, f"the box {box.describe()} is valid for the model"))
    return Box(box)


def _conditions_of_field(doc: dict[str, Any], model: Any, box: Box, rows: list[Row]) -> bool:
    """A polynomial or rational loop's conditions: the linearization on the field as it is, a ball-arithmetic
    region on the true field, then, under the cleared field (:func:`_cleared_field`), each SOS certificate
    by its class's entry with a :class:`~lyapcheck.models.classes.contexts.FieldCheck`."""
    from lyapcheck.models.classes.contexts import FieldCheck
    from lyapcheck.models.classes.discrete_linearization import is_discrete_certificate
    from lyapcheck.models.classes.registry import verify
    from lyapcheck.models.loop.field import shifted_field
    from lyapcheck.models.surfaces.ball_roa import is_ball_region, verify_ball_roa

    shifted = shifted_field(model, box=box.box)
    conditions: dict[str, Any] = doc["conditions"]

    def linearization(name: str, c: dict[str, Any]) -> tuple[bool, str]:
        data = c.get("certificate") if c["status"] == "certified" else c.get("refutation")
        if is_discrete_certificate(data):  # a map's test never re-checks a field
            return False, 'a discrete-time certificate ("time": "discrete"), and the model is a continuous-time field'
        return verify(name, c, FieldCheck(shifted))  # (the field as it is: before its denominators' proofs)

    _each(conditions, rows, lambda n, c: n == "linearization" and _status_in("certified", "refuted")(n, c),
          linearization)
    _each(conditions, rows, is_ball_region, lambda n, c: verify_ball_roa(n, c, model, box.box), _malformed)
    needs_field = [n for n, c in conditions.items() if n != "linearization" and isinstance(c, dict)
                   and c.get("status") == "certified" and not is_ball_region(n, c)]
    if not needs_field:
        return True
    scaled = _cleared_field(doc, model, shifted, box, rows)
    if scaled is None:
        return False
    _each(conditions, rows, lambda n, c: n in needs_field, lambda n, c: verify(n, c, FieldCheck(shifted, scaled)),
          _malformed)
    return True


def _cleared_field(doc: dict[str, Any], model: Any, shifted: Any, box: Box, rows: list[Row]) -> Any:
    """The field the SOS certificates are proved on: multiplied through by its denominators, each proved of its
    stated sign by its positivity certificate (a row each), then scaled by the stated powers of two; None
    (the failed row appended) when a proof or the scaling does not hold."""
    from lyapcheck.models.loop.field import Scaling, apply_scaling, clear
    from lyapcheck.models.loop.positivity import check_certificate

    distinct = shifted.distinct_denominators()
    stored = doc["field"]["denominators"]
    if len(stored) != len(distinct):
        rows.append(("denominators", False, "one positivity certificate per denominator is needed"))
        return None
    signs = []
    start = None if box.box is None else model.n + len(model.disturbances)  # (the box's parameters follow)
    for d, cert in zip(distinct, stored):
        sign = cert["sign"]
        if isinstance(sign, bool) or not isinstance(sign, int) or sign not in (1, -1):
            rows.append(("denominators", False, "a denominator's sign must be +1 or -1"))
            return None
        ok, why = check_certificate(shifted.ring, d * sign, cert, start)
        rows.append(("denominators", ok, f"denominator {cert.get('denominator')}: {why}"))
        if not ok:
            return None
        signs.append(sign)
    scaling = Scaling.from_json(doc["field"]["scaling"])
    if not scaling.positive() or len(scaling.states) != model.n or len(scaling.disturbances) != \
            len(model.disturbances) or len(scaling.outputs) != len(model.outputs):
        rows.append(("scaling", False, "the scaling must have one positive factor per state, disturbance, output"))
        return None
    return apply_scaling(clear(shifted, signs), scaling)


def _conditions_of_map(doc: dict[str, Any], model: Any, box: Box, rows: list[Row]) -> bool:
    """A polynomial map's decided conditions, each by its class's entry for a map (a
    :class:`~lyapcheck.models.classes.contexts.MapCheck`: the discrete-time test on the shifted map
    re-derived from the model text); a decided claim of a class without a discrete-time check fails (it
    cannot be re-checked on a map, so it cannot stand), as does one over a box of a class a map decides at
    a point only."""
    from lyapcheck.models.classes.contexts import MapCheck
    from lyapcheck.models.classes.discrete_lyapunov import BOX_CLASSES
    from lyapcheck.models.classes.registry import verify
    from lyapcheck.models.loop.discrete import shifted_map

    conditions: dict[str, Any] = doc["conditions"]
    # over a box (checked in step 2: the fixed point stays put), the map re-derived with the box's normalized
    # parameters: a box widened after the fact changes them and the identities fail
    check = MapCheck(shifted=shifted_map(model, box=box.box), model=model)

    def on_map(name: str, c: dict[str, Any]) -> tuple[bool, str]:
        if box.box is not None and name not in BOX_CLASSES:  # decided at a point only: no claim over a box stands
            return False, f"a {c.get('status')} claim over a box, which a map decides at a point only"
        return verify(name, c, check)

    _each(conditions, rows, _status_in("certified", "refuted", "counterexample"), on_map)
    return True


#: with the certificate itself, each in the direction that keeps the claim true (a stated rate or level at
#: most the certified one, a bound or a time at least it); a GES claim adds ``k`` and its rate
#: :func:`lyapcheck.models.classes.verify_field._verify_ges` passed)
# -- a loop with functions, and a map with functions ----------------------------------------------------

def _recasting(same_words: str) -> Callable[[dict[str, Any], Any, list[Row]], None]:
    """Step 1 of a loop with functions: the stated ``recast`` table (auxiliaries, flows, relations) is the one
    the model text gives (``same_words``: the row's message when it is)."""
    def check(doc: dict[str, Any], model: Any, rows: list[Row]) -> None:
        stated = doc["recast"]
        derived = model.system.to_json()
        same = all(stated.get(k) == derived[k] for k in derived)
        rows.append(("recasting", same, same_words if same else
                     "the stated recasting differs from the one the model text gives"))
    return check


def _prelude_of_functions(doc: dict[str, Any], model: Any, rows: list[Row]) -> None:
    """The recasting, and the stated disturbances' bounds as the model text declares them."""
    _recasting("the stated auxiliaries, flows and relations are the ones the model text gives")(doc, model, rows)
    if doc.get("disturbances", {}) != {d: str(b) for d, b in model.disturbances.items()}:
        rows.append(("disturbances", False, "the stated disturbances are not the model text's"))


def _read_box_at_centre(doc: dict[str, Any], model: "RecastModel", rows: list[Row],
                        recast: Callable[["RecastModel", "ModelBox"], Any], done: str) -> Box | Stop:
    """A loop with functions' or a map with functions' box: the document's box, each parameter the model's and
    read at its centre, and ``recast(model, box)`` (the loop with the box's parameters as bounded constants, or
    the map with them as balls keeping its fixed point), its row saying ``done``; or a failed row and
    :class:`Stop` (a parameter not read at the centre, a box the loop cannot take)."""
    if "box" not in doc:
        return Box()
    from lyapcheck.errors import ModelFileError
    from lyapcheck.models.language.parameter_box import ModelBox

    def refused(why: str) -> Stop:
        rows.append(("box", False, why))
        return Stop(verdict=True)

    try:
        box = ModelBox.from_json(doc["box"])
    except (TypeError, ValueError, AttributeError, ZeroDivisionError) as exc:
        return refused(f"malformed box: {exc}")
    for name, lo, hi in box.bounds:
        if name not in model.parameters or not lo < hi:
            return refused(f"box: {name!r} is not a parameter of the model with lo < hi")
        if model.parameters[name] != box.center(name):
            return refused(f"box: the model is not read at the box's centre ({name} = {model.parameters[name]})")
    try:
        recast_again = recast(model, box)
    except ModelFileError as exc:
        return refused(f"box: {exc}")
    rows.append(("box", True, done))
    return Box(box, recast_again)


def _read_box_functions(doc: dict[str, Any], model: "RecastModel", rows: list[Row]) -> Box | Stop:
    """A loop with functions' box (:func:`_read_box_at_centre`), the loop recast with its parameters as bounded
    constants (:func:`lyapcheck.models.classes.recast_regions.boxed_loop`)."""
    from lyapcheck.models.classes.recast_regions import boxed_loop

    return _read_box_at_centre(doc, model, rows, boxed_loop, "each box parameter is read at the box's centre, and "
                               "the loop is recast with them as bounded constants again")


def _conditions_of_functions(doc: dict[str, Any], model: "RecastModel", box: Box, rows: list[Row]) -> bool:
    """A loop with functions' decided conditions: over a box the claim's prefix, then the disturbances it
    covers, then its stated figures (:func:`~lyapcheck.models.surfaces.stated.proved_claims`, cheap: before the proof is run again), then its
    proof by its class's entry with a :class:`~lyapcheck.models.classes.contexts.FunctionsCheck` on the loop
    recast from the text (over a box: its parameters bounded constants, or balls for a region)."""
    from lyapcheck.models.classes import registry
    from lyapcheck.models.classes.bounds import KIND, OLD_KIND
    from lyapcheck.models.classes.claims import box_prefix, nominal_coverage
    from lyapcheck.models.classes.contexts import FunctionsCheck
    from lyapcheck.models.classes.lyapunov import OLD_FORMAT, OLD_RELATIONS_KIND
    from lyapcheck.models.classes.recast_classes import base_loop
    from lyapcheck.models.classes.recast_interval import box_units
    from lyapcheck.models.classes.recast_regions import box_robust, robust_of

    verify = registry.verify
    base = base_loop(model.system)
    coverage = nominal_coverage(model.disturbances.values())

    def proof(name: str, c: dict[str, Any]) -> tuple[bool, str]:
        interval = c["status"] == "certified" and (c.get("certificate") or {}).get("kind") == "interval"
        if interval and c["certificate"].get("units") != box_units(model):
            return False, "the units its box is printed in are not the states' units of the model text"
        if name == "sos_bound":
            return verify(name, c, FunctionsCheck(base, model=model, box=box.box))
        if box.box is None:
            return verify(name, c, FunctionsCheck(base, robust_of(model), model))
        if name == "linearization":
            return _verify_box_linearization(c, box.boxed, box.box)
        if c["status"] != "certified":
            return verify(name, c, FunctionsCheck(base, robust_of(model), model))
        if name == "roa" or (name == "candidate" and c["certificate"].get("kind") == "interval"):
            # the set covers the disturbances too where its certificate says so (else d = 0)
            disturbed = "disturbances" in (c.get("certificate") or {})
            ok, why = verify(name, c, FunctionsCheck(base, box_robust(model, box.box, disturbed=disturbed)))
            return (ok, why) if c["certificate"].get("kind") == "interval" else \
                (False, "over a box, roa is proved by ball arithmetic")
        if name == "candidate" and c["certificate"].get("parameter_box") != box.box.to_json():
            return False, "a candidate over a box states that box (parameter_box) as the document's"
        if name in ("barrier", "reach_avoid"):
            return _verify_box_safety(name, c, box.boxed, model, box.box)
        return verify(name, c, FunctionsCheck(box.boxed))

    def check(name: str, c: dict[str, Any]) -> tuple[bool, str]:
        if box.box is not None:  # the claim over the box says so first; the rest is the class's own sentence
            prefix = box_prefix(box.box, c["status"])
            if name == "linearization" and c["status"] == "refuted":  # (it names its own point of the box)
                prefix = ""
            if not str(c.get("summary", "")).startswith(prefix):
                return False, f"over a box a claim begins '{prefix}'"
            c = {**c, "summary": c["summary"][len(prefix):]}
        # a claim for every disturbance value: by ball arithmetic or sos_bound's kind, of a class that can make one
        robust_claim = (coverage is not None and c.get("disturbances") == "all"
                        and name not in registry.ZERO_DISTURBANCE_ONLY and isinstance(c.get("certificate"), dict)
                        and (c["certificate"].get("kind") == "interval"
                             or (name == "sos_bound" and c["certificate"].get("kind") in (KIND, OLD_KIND))))
        if c.get("disturbances") != coverage and not robust_claim:
            return False, ("a loop with functions is certified with its disturbances at 0 (or, by ball arithmetic, "
                           f"for every value of them); the stated coverage {c.get('disturbances')!r} is neither")
        if name in ("quadratic", "sos_gas") and (c.get("certificate") or {}).get("kind") == OLD_RELATIONS_KIND:
            return False, OLD_FORMAT  # (its figures are not this format's either)
        try:
            ok, claims = check_stated(c, proved_claims(name, c, model))
            if not ok:
                return False, claims
            ok, why = proof(name, c)
        except MALFORMED as exc:
            return False, f"malformed certificate: {str(exc)[:200]}"
        return (True, f"{why}; {claims}") if ok else (False, why)

    _each(doc["conditions"], rows, _status_in("certified", "refuted"), check)
    return True


def _verify_box_linearization(c: dict[str, Any], boxed: Any, box: "ModelBox") -> tuple[bool, str]:
    """A linearization over a box (its summary without the box's words): the Jacobian of every value
    built again from the loop recast with the box's parameters as bounded constants
    (:func:`lyapcheck.models.classes.recast_classes.jacobian_over_box`) and re-checked as a polynomial
    loop's is (:func:`lyapcheck.models.classes.linearization.verify_jacobian_over_box`)."""
    from lyapcheck.models.classes.claims import summary
    from lyapcheck.models.classes.linearization import verify_jacobian_over_box
    from lyapcheck.models.classes.recast_classes import jacobian_over_box

    built = jacobian_over_box(boxed)
    if isinstance(built, str):
        return False, f"the model's Jacobian over the box is not exact here: {built}"
    J, ring = built
    data = c.get("certificate") if c["status"] == "certified" else c.get("refutation")
    ok, why = verify_jacobian_over_box(J, ring, box, c["status"], data or {})
    if ok and c.get("summary") != summary("linearization", c):
        return False, "the printed sentence is not the one the certificate supports"
    return ok, why


def _verify_box_safety(name: str, c: dict[str, Any], boxed: Any, model: "RecastModel", box: "ModelBox"
                       ) -> tuple[bool, str]:
    """A barrier or a reach-avoid function over a box: its proofs re-checked on the loop recast again
    with the box's parameters as bounded constants (``boxed``), so one B or V serves every value of it,
    with the sets the model text gives (none of which may name a box parameter)."""
    from lyapcheck.models.classes.barrier import SETS_USE_BOX, sets_use_box
    from lyapcheck.models.classes.contexts import FunctionsCheck
    from lyapcheck.models.classes.registry import verify

    if sets_use_box(model, box):
        return False, SETS_USE_BOX
    ok, why = verify(name, c, FunctionsCheck(boxed, None, model))
    return ok, (f"{why}, for every value of the box (its parameters bounded constants of the recasting)" if ok
                else why)


def _true_loop_replay(model: "RecastModel", box: Box) -> "Check":
    """A ``counterexample`` of barrier or reach_avoid re-simulated on the true loop, as certify's falsification
    simulated it (:func:`lyapcheck.models.classes.barrier.falsification`): the polynomial loops' checks with
    the true loop's field, its disturbances at 0, and over a box at the point of the box where it was found."""
    from lyapcheck.models.classes.barrier import true_field
    from lyapcheck.models.surfaces.counterexamples import verify_counterexample

    def check(name: str, c: dict[str, Any], model: "RecastModel") -> tuple[bool, str]:
        ref = c.get("refutation") or {}
        there, where = _counterexample_loop(ref, model, box.box)
        if there is None:
            return False, where
        disturbance = ref.get("disturbance")
        kind = disturbance.get("kind") if isinstance(disturbance, dict) else disturbance
        if there.disturbances and kind != "none":
            # the claims are the nominal loop's (d = 0), the one certify simulated; without disturbances the
            # shared check says a disturbance is none
            return False, (f"a loop with functions is simulated with its disturbances at 0 (d = 0): the "
                           f"counterexample's disturbance must be of kind 'none', not {kind!r}")
        ok, why = verify_counterexample(name, c, there, evaluate=true_field(there))
        return ok, f"{why} (the true loop at {where})" if where else why

    return check


#: the longest decimal a counterexample's point of the box may be written with (the box's centre or a
#: corner, as exact decimals of the box's edges: far shorter)
MAX_POINT_TEXT: Final = 200


def _counterexample_loop(ref: dict[str, Any], model: "RecastModel", box: "ModelBox | None"
                         ) -> "tuple[RecastModel | None, str]":
    """The model a counterexample is re-simulated on, and the words for the point of the box (empty when
    there is no box): over a box, the model text read again at the refutation's ``parameters`` (the point
    of the box where it was found, :func:`lyapcheck.models.classes.barrier.at_point`), which must lie
    in the box; else the model itself. (None, why) when it cannot be."""
    from lyapcheck.errors import ModelFileError
    from lyapcheck.exact import exact_decimal
    from lyapcheck.models.language.modelfile import parse_any_model
    from lyapcheck.models.language.recast import RecastModel

    stated = ref.get("parameters")
    if box is None:
        if stated is not None:
            return None, "a counterexample's parameters name a point of a box, and the document has no box"
        return model, ""
    if not isinstance(stated, dict) or set(stated) != set(box.names):
        return None, (f"over a box a counterexample names the point of the box where it was found: parameters "
                      f"{', '.join(box.names)}")
    values = {}
    for name, lo, hi in box.bounds:
        text = str(stated[name])
        # a point of the box is written as a plain decimal (barrier.at_point); anything else, as
        # "1e999999999" whose exact value would take minutes to build, is refused before it is read
        if len(text) > MAX_POINT_TEXT or not re.fullmatch(r"-?[0-9]+(\.[0-9]+)?", text):
            return None, f"the parameter {name} = {text!r} of the counterexample is not a plain decimal number"
        value = Fraction(text)
        if not lo <= value <= hi:
            return None, f"the parameter {name} = {stated[name]} is not a point of the box [{lo}, {hi}]"
        values[name] = exact_decimal(value)
    try:
        there = parse_any_model(model.text, model.source, {**model.overrides, **values})
    except ModelFileError as exc:
        return None, f"the model cannot be read at the point {values} of the box: {exc}"
    if not isinstance(there, RecastModel):
        return None, f"the model read at the point {values} of the box is not a loop with functions"
    return there, ", ".join(f"{name} = {text}" for name, text in values.items())


def _read_box_map_functions(doc: dict[str, Any], model: Any, rows: list[Row]) -> Box | Stop:
    """A map with functions' box (:func:`_read_box_at_centre`), the map recast with its parameters as balls
    keeping its fixed point (:func:`lyapcheck.models.classes.discrete_functions_box.boxed_system`)."""
    from lyapcheck.models.classes.discrete_functions_box import boxed_system

    box = _read_box_at_centre(doc, model, rows, boxed_system, "each box parameter is read at the box's centre, "
                              "and the map's fixed point is proved to stay put over the box")
    return box if isinstance(box, Stop) else Box(box.box)


def _conditions_of_map_functions(doc: dict[str, Any], model: Any, box: Box, rows: list[Row]) -> bool:
    """A map with functions' decided claims, each by its class's entry (a
    :class:`~lyapcheck.models.classes.contexts.MapFunctionsCheck`: the linearization re-derived, a
    ``discrete_interval`` region proved again, a ``discrete_relations`` identity re-checked on the relations
    derived again; over a box, with its parameters as balls); any other decided claim fails (no check of this
    map re-derives it)."""
    from lyapcheck.models.classes.contexts import MapFunctionsCheck
    from lyapcheck.models.classes.registry import verify

    check = MapFunctionsCheck(model=model, box=box.box)
    _each(doc["conditions"], rows, _status_in("certified", "refuted", "counterexample"),
          lambda n, c: verify(n, c, check),
          lambda exc: f"malformed certificate: {type(exc).__name__}: {exc}"[:200])
    return True


# -- a sampled-data loop ---------------------------------------------------------------------------------

def _prelude_of_sampled(doc: dict[str, Any], model: Any, rows: list[Row]) -> None:
    """The ``sampling`` table is the model text's: the period, the controller's laws as written and the
    controls' values at the equilibrium."""
    same = doc["sampling"] == model.to_json()
    rows.append(("sampling", same, "the period, the controller and its equilibrium values as stated" if same else
                 "sampling: the stated period or controller differs from the model text's"))


def _read_box_sampled(doc: dict[str, Any], model: Any, rows: list[Row]) -> Box | Stop:
    """A sampled-data loop is certified at its parameters' values only: a document with a box fails."""
    if "box" in doc:
        rows.append(("box", False, "a sampled-data loop is certified at a point: its document has no box"))
        return Stop(verdict=False)
    return Box()


def _conditions_of_sampled(doc: dict[str, Any], model: Any, box: Box, rows: list[Row]) -> bool:
    """A sampled-data loop's conditions, each named by a class; each decided one's property, figures and
    sentence held to its certificate (:func:`~lyapcheck.models.surfaces.stated.check_stated`,
    :func:`~lyapcheck.models.classes.claims.summary`), then its proof by its class's entry with a
    :class:`~lyapcheck.models.classes.contexts.SampledCheck` (the linear parts, the period and, for ``roa``,
    the flow's bounds re-derived from the model text). A class without a sampled-data check fails its claim."""
    from lyapcheck.models.classes.claims import SAMPLED_REGION_KIND, summary
    from lyapcheck.models.classes.contexts import SampledCheck
    from lyapcheck.models.classes.registry import NAMES, verify
    from lyapcheck.models.surfaces.stated import Stated, check_stated

    conditions = doc["conditions"]
    if not isinstance(conditions, dict) or any(name not in NAMES or not isinstance(c, dict)
                                               for name, c in conditions.items()):
        rows.append(("conditions", False, "the conditions must be named by classes"))
        return False
    check = SampledCheck(model=model)

    def claims(name: str, c: dict[str, Any]) -> Stated:
        if name == "linearization":
            return Stated("LES", {"period_s": model.period})
        cert = c.get("certificate") or {}
        if name == "roa" and cert.get("kind") == SAMPLED_REGION_KIND:  # its check compares every figure
            from lyapcheck.models.classes.sampled_regions import FIGURES

            return Stated("ROA", {}, frozenset(FIGURES))
        return Stated(str(c.get("property")))  # (its class's entry then says no check re-derives it)

    def one(name: str, c: dict[str, Any]) -> tuple[bool, str]:
        ok, stated = check_stated(c, claims(name, c))
        if not ok:
            return False, stated
        if c.get("summary") != summary(name, c):
            return False, "the summary is not what the checked figures say"
        ok, why = verify(name, c, check)
        return (True, f"{why}; {stated}") if ok else (False, why)

    _each(conditions, rows, _status_in("certified", "refuted"), one, _malformed)
    return True


# -- the kinds ------------------------------------------------------------------------------------------

#: a polynomial or rational loop
FIELD: Final = LoopKind(
    "polynomial or rational loop", None, _read_box_polynomial, _conditions_of_field,
    size=lambda model, box: {"variables": list(model.states) + (list(box.box.names) if box.box is not None else [])},
    counterexamples=lambda model, box: None, candidate=candidate_of_polynomial, stated_v=True,
    stated_figures=True)
#: a polynomial discrete-time map (``[model] time = "discrete"``; its counterexamples: its classes' checks)
MAP: Final = LoopKind(
    "polynomial map", None, _read_box_polynomial, _conditions_of_map,
    size=lambda model, box: {"variables": list(model.states) + (list(box.box.names) if box.box is not None else [])},
    counterexamples=None, candidate=candidate_of_polynomial, stated_figures=True)
#: a loop with functions (sin, sqrt, sat, ...; its document states its recasting)
FUNCTIONS: Final = LoopKind(
    "loop with functions", _prelude_of_functions, _read_box_functions, _conditions_of_functions,
    size=lambda model, box: {"system": model.system}, counterexamples=_true_loop_replay,
    candidate=candidate_of_functions)
#: a discrete-time map with functions (issue 44; the recasting of its displacement F(x) - x)
MAP_FUNCTIONS: Final = LoopKind(
    "map with functions", _recasting("the stated recasting of the map's displacement F(x) - x is the one the model text gives"), _read_box_map_functions,
    _conditions_of_map_functions, size=None, counterexamples=None, candidate=None, stated_figures=True)

#: a sampled-data loop (a continuous plant under controls held between samples; its document states its
#: ``sampling`` table)
SAMPLED: Final = LoopKind(
    "sampled-data loop", _prelude_of_sampled, _read_box_sampled, _conditions_of_sampled, size=None,
    counterexamples=None, candidate=None)


def loop_kind(model: Any) -> LoopKind:
    """The kind of loop ``model`` is (a sampled-data loop is a :class:`SampledModel`; a loop with functions
    a :class:`RecastModel`; a map's ``time`` is ``"discrete"``)."""
    from lyapcheck.models.language.recast import RecastModel
    from lyapcheck.models.language.sampling import SampledModel
    from lyapcheck.models.loop.discrete import is_discrete

    if isinstance(model, SampledModel):
        return SAMPLED
    if isinstance(model, RecastModel):
        return MAP_FUNCTIONS if is_discrete(model) else FUNCTIONS
    return MAP if is_discrete(model) else FIELD


__all__ = ["Box", "Stop", "LoopKind", "FIELD", "MAP", "FUNCTIONS", "MAP_FUNCTIONS", "SAMPLED", "loop_kind", "verify_model",
           "MAX_POINT_TEXT"]
