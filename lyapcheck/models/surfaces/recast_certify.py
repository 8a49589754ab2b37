"""``verify`` of a loop with functions (sin, sqrt, sat, ...), and the sentences of its certificates.

The certificate document is a model certificate (``kind`` lyapcheck-model-certificate, schema 1;
:mod:`lyapcheck.models.surfaces.certificate`) with a ``"recast"`` table: the recasting's variables, each
auxiliary's definition in the model-file language (``{"s1": "sin(theta)", "c1": "cos(theta)"}``),
each relation and flow, as lyapcheck derived them. Each certified condition's certificate carries
``variables`` (the states, then the auxiliaries), ``auxiliaries`` (the same definitions), ``shift``
(the equilibrium value of each state and auxiliary: ``V`` is a polynomial in ``v - shift[v]``, the
constant roots ``rt2``, ``rt3`` unshifted), ``V``, ``V_text`` (V written with the functions),
``epsilon``, the proofs of the recasting (square roots' lower bounds, denominators' positivity) and
of each identity (:mod:`lyapcheck.models.engines.recast_sos`).

``verify`` re-reads the model text, recasts it again (each flow and relation re-derived from the
text, so a certificate cannot bring its own), re-checks every stored proof exactly and recomputes
the verdict. It never calls a solver.
"""

from __future__ import annotations

import re
from fractions import Fraction
from typing import Any, Final

from lyapcheck.errors import ModelFileError
from lyapcheck.models.language.parameter_box import ModelBox
from lyapcheck.models.language.recast import RecastModel
from lyapcheck.models.classes.bounds import KIND, OLD_KIND
from lyapcheck.models.classes.contexts import FunctionsCheck
from lyapcheck.models.classes.lyapunov import OLD_FORMAT, OLD_RELATIONS_KIND, RELATIONS_KIND, relations_claim
from lyapcheck.models.classes.recast_interval import box_units
from lyapcheck.models.classes.recast_classes import Loop, base_loop
from lyapcheck.models.classes.registry import ZERO_DISTURBANCE_ONLY, verify
from lyapcheck.models.classes.recast_regions import box_robust, boxed_loop, robust_of
from lyapcheck.models.engines.recast_sos import poly_from_json
from lyapcheck.models.classes.claims import box_prefix, nominal_coverage
from lyapcheck.models.classes.barrier import KIND as BARRIER_KIND, OLD_KIND as RECAST_BARRIER
from lyapcheck.models.classes.reach_avoid import KIND as RECAST_REACH_AVOID, OLD_KIND as OLD_REACH_AVOID
from lyapcheck.models.surfaces.stated import Stated, check_stated
from lyapcheck.exact import read_rational

Row = tuple[str, bool, str]


# -- verify ------------------------------------------------------------------------------------------

def verify_recast(doc: dict[str, Any], model: RecastModel, rows: list[Row]) -> list[Row]:
    """The rest of a loop with functions' document, after the rows every document starts with
    (:func:`lyapcheck.models.surfaces.certificate.verify_document` reads the model again and makes them):
    the recasting, the box, every decided condition's proof, the counterexamples and the candidate."""
    from lyapcheck.models.surfaces.documents import with_verdict as _with_verdict

    if getattr(model, "time", "continuous") == "discrete":  # a map with functions: its own checks
        from lyapcheck.models.surfaces.map_functions import verify_map_functions

        return verify_map_functions(doc, model, rows)
    stated = doc["recast"]
    derived = model.system.to_json()
    recast_ok = all(stated.get(k) == derived[k] for k in derived)
    rows.append(("recasting", recast_ok, "the stated auxiliaries, flows and relations are the ones the model text "
                                         "gives" if recast_ok else "the stated recasting differs from the one the "
                                                                   "model text gives"))
    base = base_loop(model.system)
    coverage = nominal_coverage(model.disturbances.values())
    declared = {d: str(b) for d, b in model.disturbances.items()}
    if doc.get("disturbances", {}) != declared:
        rows.append(("disturbances", False, "the stated disturbances are not the model text's"))
    box, boxed, why_not = _box_of(doc, model)
    if why_not:
        rows.append(("box", False, why_not))
        return _with_verdict(doc, rows)
    if box is not None:
        rows.append(("box", True, "each box parameter is read at the box's centre, and the loop is recast with them "
                                  "as bounded constants again"))
    for name, c in doc["conditions"].items():
        if not isinstance(c, dict) or c.get("status") not in ("certified", "refuted"):
            continue
        if box is not None:  # the claim over the box says so first; the rest is the class's own sentence
            prefix = box_prefix(box, c["status"])
            if name == "linearization" and c["status"] == "refuted":  # (it names its own point of the box)
                prefix = ""
            if not str(c.get("summary", "")).startswith(prefix) or name == "candidate":
                rows.append((name, False, f"{name}: over a box a claim begins '{prefix}' (and candidate certifies "
                                          "a point)"))
                continue
            c = {**c, "summary": c["summary"][len(prefix):]}
        # a claim for every disturbance value: by ball arithmetic or sos_bound's kind, of a class that can make one
        robust_claim = (coverage is not None and c.get("disturbances") == "all" and name not in ZERO_DISTURBANCE_ONLY
                        and isinstance(c.get("certificate"), dict)
                        and (c["certificate"].get("kind") == "interval"
                             or (name == "sos_bound" and c["certificate"].get("kind") in (KIND, OLD_KIND))))
        if c.get("disturbances") != coverage and not robust_claim:
            rows.append((name, False, f"{name}: a loop with functions is certified with its disturbances at 0 (or, by "
                                      "ball arithmetic, for every value of them); the stated coverage "
                                      f"{c.get('disturbances')!r} is neither"))
            continue
        if name in ("quadratic", "sos_gas") and (c.get("certificate") or {}).get("kind") == OLD_RELATIONS_KIND:
            rows.append((name, False, f"{name}: {OLD_FORMAT}"))  # (its figures are not this format's either)
            continue
        try:
            # what the condition states beside its proof, from the certificate (cheap: before the proof is re-run)
            ok, claims = check_stated(c, proved_claims(name, c, model))
            if not ok:
                rows.append((name, False, f"{name}: {claims}"))
                continue
            interval = c["status"] == "certified" and (c.get("certificate") or {}).get("kind") == "interval"
            if interval and c["certificate"].get("units") != box_units(model):
                ok, why = False, "the units its box is printed in are not the states' units of the model text"
            elif name == "sos_bound":
                ok, why = verify(name, c, FunctionsCheck(base, model=model, box=box))
            elif box is not None and name == "linearization":
                assert boxed is not None
                ok, why = _verify_box_linearization(c, boxed, box)
            elif box is not None and c["status"] == "certified" and name == "roa":
                # the set covers the disturbances too where its certificate says so (else d = 0)
                disturbed = "disturbances" in (c.get("certificate") or {})
                ok, why = verify(name, c, FunctionsCheck(base, box_robust(model, box, disturbed=disturbed)))
                if c["certificate"].get("kind") != "interval":
                    ok, why = False, "over a box, roa is proved by ball arithmetic"
            elif box is not None and c["status"] == "certified" and name in ("barrier", "reach_avoid"):
                assert boxed is not None
                ok, why = _verify_box_safety(name, c, boxed, model, box)
            elif box is not None and c["status"] == "certified":
                assert boxed is not None
                ok, why = verify(name, c, FunctionsCheck(boxed))
            else:
                ok, why = verify(name, c, FunctionsCheck(base, robust_of(model), model))
        except (KeyError, ValueError, ArithmeticError, TypeError, IndexError, AttributeError) as exc:
            ok, why = False, f"malformed certificate: {str(exc)[:200]}"
        rows.append((name, ok, f"{why}; {claims}" if ok else f"{name}: {why}"))
    from lyapcheck.models.classes.region_size import check_size_rows

    check_size_rows(model, doc["conditions"], rows, system=model.system)
    _check_true_counterexamples(doc, model, box, rows)
    rows.extend(_check_candidate(doc, model))
    return _with_verdict(doc, rows)


def proved_claims(name: str, c: dict[str, Any], model: RecastModel) -> Stated:
    """The property and the figures a decided condition's certificate proves, read from the
    certificate (which its class's check then re-checks) and the model: a figure beside the status
    is compared with these, and any other is refused unless it is a declared estimate
    (:func:`lyapcheck.models.surfaces.stated.check_stated`)."""
    if name == "linearization":
        return Stated("LES")
    if c["status"] == "refuted":  # another equilibrium, exactly: no global asymptotic stability
        return Stated("GAS")
    cert = c["certificate"]
    if not isinstance(cert, dict):
        raise ValueError("certificate: must be a table")
    kind = cert.get("kind")
    if kind in (KIND, OLD_KIND):  # (an older one is refused by its check, with the advice to certify again)
        from lyapcheck.models.classes.bounds import bound_claim

        claim = bound_claim(model, {out: read_rational(item["bound"]) for out, item in cert["outputs"].items()})
        return Stated("ultimate_bound", {k: v for k, v in claim.items() if k != "status"})
    if kind == RELATIONS_KIND and name in ("quadratic", "sos_gas"):
        return Stated(*relations_claim(cert))
    if kind == "interval":  # (its size: re-derived in a row of its own, check_size_rows)
        return Stated("ROA", {"level": read_rational(cert["level"])}, frozenset({"size"}))
    if kind in (BARRIER_KIND, RECAST_BARRIER):  # (an older one is refused by its check, with the advice)
        if name != "barrier":
            raise ValueError(f"a barrier certificate under the class {name}")
        B = cert["B"]["terms"]
        degree = max((sum(e) for _, e in B), default=0)
        if isinstance(degree, bool) or not isinstance(degree, int):
            raise ValueError("B: exponents must be integers")
        return Stated("safety", {"degree": degree, "lambda_per_s": read_rational(cert["lambda_per_s"])})
    if kind in (RECAST_REACH_AVOID, OLD_REACH_AVOID):  # (an older one is refused by its check)
        from lyapcheck.models.classes.claims import recast_reach_time as reach_time

        if name != "reach_avoid":
            raise ValueError(f"a reach-avoid certificate under the class {name}")
        degree = max((sum(e) for _, e in cert["V"]["terms"]), default=0)
        if isinstance(degree, bool) or not isinstance(degree, int):
            raise ValueError("V: exponents must be integers")
        return Stated("reach_avoid", {"degree": degree, "reach_time_bound_s": reach_time(cert)})
    degree = max(sum(e) for _, e in cert["V"]["terms"])
    if isinstance(degree, bool) or not isinstance(degree, int):
        raise ValueError("V: exponents must be integers")
    if "level" in cert:
        return Stated("ROA", {"degree": degree, "level": read_rational(cert["level"])}, frozenset({"size"}))
    return Stated("GAS", {"degree": degree})


def _check_true_counterexamples(doc: dict[str, Any], model: RecastModel, box: ModelBox | None, rows: list[Row]
                                ) -> None:
    """A ``counterexample`` of barrier or reach_avoid re-simulated on the true loop, as certify's falsification
    simulated it (:func:`lyapcheck.models.classes.barrier.falsification`): the polynomial loops' checks
    (:func:`lyapcheck.models.surfaces.counterexamples.check_counterexamples`) with the true loop's field, its
    disturbances at 0, and over a box at the point of the box where it was found."""
    from lyapcheck.models.classes.barrier import true_field
    from lyapcheck.models.surfaces.counterexamples import check_counterexamples, verify_counterexample

    def check(name: str, c: dict[str, Any], model: RecastModel) -> tuple[bool, str]:
        ref = c.get("refutation") or {}
        there, where = _counterexample_loop(ref, model, box)
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

    check_counterexamples(model, doc["conditions"], rows, check)


#: the longest decimal a counterexample's point of the box may be written with (the box's centre or a
#: corner, as exact decimals of the box's edges: far shorter)
MAX_POINT_TEXT: Final = 200


def _counterexample_loop(ref: dict[str, Any], model: RecastModel, box: ModelBox | None
                         ) -> tuple[RecastModel | None, str]:
    """The model a counterexample is re-simulated on, and the words for the point of the box (empty when
    there is no box): over a box, the model text read again at the refutation's ``parameters`` (the point
    of the box where it was found, :func:`lyapcheck.models.classes.barrier.at_point`), which must lie
    in the box; else the model itself. (None, why) when it cannot be."""
    from lyapcheck.exact import exact_decimal
    from lyapcheck.models.language.modelfile import parse_any_model

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


def _check_candidate(doc: dict[str, Any], model: RecastModel) -> list[Row]:
    """The top-level ``candidate`` text is the user's V: recast with the model's functions (the text
    parsed with it, else verify stopped at the model row), it must be the ``V`` of a certified
    ``candidate`` condition, and a certified one needs it."""
    c = doc["conditions"].get("candidate")
    certified = isinstance(c, dict) and c.get("status") == "certified"
    text = doc.get("candidate")
    if not certified:
        return [] if text is None or isinstance(text, str) else \
            [("candidate", False, "candidate: the candidate text must be text")]
    if not isinstance(text, str) or model.candidate_v is None:
        return [("candidate", False, "candidate: a certified candidate condition needs the candidate text")]
    try:
        same = poly_from_json(model.system.ring, c["certificate"]["V"], "V") == model.candidate_v
    except (KeyError, ValueError, TypeError, ArithmeticError) as exc:
        return [("candidate", False, f"candidate: the certified V is malformed: {str(exc)[:200]}")]
    return [("candidate", same, "the candidate text is the certified V" if same else
             "candidate: the candidate text is not the V of the certified candidate condition")]


def _box_of(doc: dict[str, Any], model: RecastModel) -> tuple[ModelBox | None, Loop | None, str]:
    """The document's box, and the loop with its parameters as bounded constants; or why not (a box
    parameter not read at the box's centre, a box the loop cannot take)."""
    if "box" not in doc:
        return None, None, ""
    try:
        box = ModelBox.from_json(doc["box"])
    except (TypeError, ValueError, AttributeError, ZeroDivisionError) as exc:
        return None, None, f"malformed box: {exc}"
    for name, lo, hi in box.bounds:
        if name not in model.parameters or not lo < hi:
            return None, None, f"box: {name!r} is not a parameter of the model with lo < hi"
        if model.parameters[name] != box.center(name):
            return None, None, f"box: the model is not read at the box's centre ({name} = {model.parameters[name]})"
    try:
        boxed = boxed_loop(model, box)
    except ModelFileError as exc:
        return None, None, f"box: {exc}"
    return box, boxed, ""



def _verify_box_linearization(c: dict[str, Any], boxed: Loop, box: ModelBox) -> tuple[bool, str]:
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

def _verify_box_safety(name: str, c: dict[str, Any], boxed: Loop, model: RecastModel, box: ModelBox
                       ) -> tuple[bool, str]:
    """A barrier or a reach-avoid function over a box: its proofs re-checked on the loop recast again
    with the box's parameters as bounded constants (``boxed``), so one B or V serves every value of it,
    with the sets the model text gives (none of which may name a box parameter)."""
    from lyapcheck.models.classes.barrier import SETS_USE_BOX, sets_use_box

    if sets_use_box(model, box):
        return False, SETS_USE_BOX
    ok, why = verify(name, c, FunctionsCheck(boxed, None, model))
    return ok, (f"{why}, for every value of the box (its parameters bounded constants of the recasting)" if ok
                else why)


__all__ = ["verify_recast", "proved_claims"]
