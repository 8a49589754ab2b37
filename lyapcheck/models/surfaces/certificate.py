"""Certificate files of model files: write, and re-check exactly without a solver.

Schema (version 1)::

    {
      "schema_version": 1,
      "kind": "lyapcheck-model-certificate",
      "model": {"name": .., "file": .., "sha256": .., "text": "<the model file, verbatim>",
                "networks": {"pi": {"file": .., "sha256": ..}}},   # only with [networks.NAME]
      "overrides": {"mu": "2"},                      # --set, as given
      "candidate": "x1**2 + x2**2" | null,            # --candidate, as given
      "states": [..], "equilibrium": {"x1": "0", ..}, "parameters": {"mu": "2"},  # exact SI
      "field": {"denominators": [..], "scaling": {..}},
      "conditions": {"linearization": {..}, "roa": {"status": .., "level": .., "disturbances": "all",
                     "certificate": {"V": {"terms": [["3/2", [2, 0]], ..]}, "variables": ["x1", "x2"],
                                     "V_text": "1.5*x1**2 - ...", "level": "p/q", ..}}, ..},
      "verdict": "certified" | "certified_nominal" | "certified_local" | "not_certified" | "unsafe" | "unstable",
      "answers": {"stability": {"answer": .., "by": .., "text": ..}, ..},   # lyapcheck.answers
      "versions": {..}
    }

Polynomials are exact (rationals as ``"p/q"``). ``V`` is in the states as declared, shifted so
that the equilibrium is 0 (the contract); the Gram matrices behind it are in the scaled states of
``field.scaling`` (powers of two), which :func:`verify_document` re-applies to the field it
re-derives from ``model.text``. The check fails when the text does not match its SHA-256, when a
coefficient, level or bound was changed, or when a stated figure claims more than the certificate
proves. It never imports cvxpy or calls a solver.
"""

from __future__ import annotations

import hashlib
from pathlib import Path
from typing import Any, Callable

from lyapcheck.errors import CertificateError, InputFileError
from lyapcheck.exact import refuse_oversized_numbers
from lyapcheck.fileio import read_json as read_json_file
from lyapcheck.models.surfaces.certify import ModelCertification
from lyapcheck.models.surfaces.counterexamples import check_counterexamples, describe_exception as _describe
from lyapcheck.models.surfaces.documents import KIND, SCHEMA_VERSION, with_verdict as _with_verdict
from lyapcheck.results import ConditionResult


Row = tuple[str, bool, str]


def build_document(result: ModelCertification) -> dict[str, Any]:
    """The certificate document of either kind of loop: a polynomial or rational loop states its
    cleared ``field`` (denominators' proofs, scaling), a loop with functions its ``recast`` table (the
    recasting's auxiliaries, flows and relations, and its angles); the rest is common."""
    from lyapcheck.answers import answers_of
    from lyapcheck.numerics import package_versions

    model = result.model
    recast: Any = model  # (a loop with functions has its recasting's loop; lyapcheck.models.language.recast
    #                      is not imported for a polynomial one)
    loop = ({"recast": {**recast.system.to_json(), "angles": {a: list(sc) for a, sc in result.loop.angles.items()}}}
            if result.loop is not None else
            {"field": {"denominators": result.denominators,
                       "scaling": result.scaling.to_json() if result.scaling is not None else None}})
    return {
        "schema_version": SCHEMA_VERSION,
        "kind": KIND,
        "model": {"name": model.name, "file": model.source, "sha256": model.sha256, "text": model.text,
                  **_network_files(model)},
        "overrides": dict(model.overrides),
        "candidate": result.candidate.text if result.candidate is not None else None,
        "states": list(model.states),
        "equilibrium": {s: str(v) for s, v in zip(model.states, model.equilibrium)},
        "parameters": {k: str(v) for k, v in model.parameters.items()},
        "disturbances": {k: str(v) for k, v in model.disturbances.items()},
        **loop,
        **({"box": result.box.to_json()} if result.box is not None else {}),
        "conditions": (conditions := {name: r.to_json() for name, r in result.results.items()}),
        "answers": answers_of(conditions),
        "verdict": result.verdict,
        "versions": package_versions(),
    }


def _network_files(model: Any) -> dict[str, Any]:
    """``{"networks": ...}`` for a loop with ``[networks.NAME]`` (their files' SHA-256), else nothing: the
    documents of every other model stay as they were."""
    if not getattr(model, "networks", ()):
        return {}
    from lyapcheck.models.language.networks import stated_files

    return {"networks": stated_files(model.networks)}


def is_model_document(doc: Any) -> bool:
    return isinstance(doc, dict) and doc.get("kind") == KIND


def read_json(path: str | Path) -> Any:
    """A JSON file, with one-line errors (missing, not JSON, unreadable, a number written with an
    oversized exponent: :func:`lyapcheck.exact.refuse_oversized_numbers`)."""
    doc = read_json_file(path)
    refuse_oversized_numbers(doc)  # (before any reader of the file's numbers: a report, simulate --certificate)
    return doc


def verify_document(doc: dict[str, Any]) -> list[Row]:
    """Re-check every claim of a model certificate exactly; (check, ok, message) rows."""
    refuse_oversized_numbers(doc)
    if doc.get("schema_version") != SCHEMA_VERSION:
        raise InputFileError(f"model certificate has schema_version {doc.get('schema_version')!r}; this lyapcheck "
                             f"reads {SCHEMA_VERSION}")
    try:
        if isinstance(doc.get("sampling"), dict):  # a sampled-data loop (lyapcheck.models.surfaces.sampled_run)
            from lyapcheck.models.surfaces.sampled_run import verify_sampled

            return verify_sampled(doc)
        model, rows = _read_model(doc)
        if model is None:
            return rows
        if isinstance(doc.get("recast"), dict):  # a loop with functions (lyapcheck.models.surfaces.recast_certify)
            from lyapcheck.models.surfaces.recast_certify import verify_recast

            return verify_recast(doc, model, rows)
        return _verify(doc, model, rows)
    except (KeyError, ValueError, ArithmeticError, TypeError, IndexError, AttributeError, RecursionError) as exc:
        text = repr(exc)
        raise CertificateError(f"certificate is malformed: {text[:200]}") from None


def _read_model(doc: dict[str, Any]) -> tuple[Any, list[Row]]:
    """The document's model, read again from its text (with its ``--set`` overrides and, on a loop with
    functions, its candidate recast along), and the rows every document starts with: the text's
    SHA-256, its parse, its kind (a ``recast`` table exactly when the loop has functions), the stated
    parameters and equilibrium, and the declared figures; (None, rows) when the rest cannot be
    checked."""
    from lyapcheck.errors import ModelFileError
    from lyapcheck.models.language.modelfile import parse_any_model
    from lyapcheck.models.language.recast import RecastModel
    from lyapcheck.models.surfaces.stated import check_declared

    part = doc["model"]
    text = part["text"]
    if hashlib.sha256(text.encode()).hexdigest() != part["sha256"]:
        return None, [("model", False, "the model text does not match its SHA-256: the text was changed")]
    try:
        model = parse_any_model(text, part.get("file", "<certificate>"), doc.get("overrides") or {},
                                candidate=doc.get("candidate"))
    except ModelFileError as exc:
        return None, [("model", False, f"the stored model text no longer parses: {exc}")]
    recast = isinstance(doc.get("recast"), dict)
    if recast != isinstance(model, RecastModel):
        return None, [("model", False, "the stored model has no functions: it is not a recast loop" if recast else
                       "the stored model uses functions: its certificate must state its recasting ('recast')")]
    rows: list[Row] = [("model", True, "the model text matches its SHA-256, parses and is recast again from it"
                        if recast else "the model text matches its SHA-256 and parses")]
    same = ({k: str(v) for k, v in model.parameters.items()} == doc["parameters"]
            and {s: str(v) for s, v in zip(model.states, model.equilibrium)} == doc["equilibrium"])
    rows.append(("parameters", same, "parameters and equilibrium as stated" if same else
                 "the stated parameters or equilibrium differ from the model text's"))
    rows.append(check_declared(doc, model))
    if getattr(model, "networks", ()) or "networks" in part:
        from lyapcheck.models.language.networks import check_stated_files

        rows.append(("networks", *check_stated_files(part.get("networks"), getattr(model, "networks", ()))))
    return model, rows


def _verify(doc: dict[str, Any], model: Any, rows: list[Row]) -> list[Row]:
    """The rest of a polynomial or rational loop's document (after :func:`_read_model`'s rows)."""
    from lyapcheck.errors import ModelFileError
    from lyapcheck.models.loop.field import Scaling, apply_scaling, clear, shifted_field

    box = None
    if "box" in doc:
        from lyapcheck.models.loop.boxes import ModelBox, check_box

        box = ModelBox.from_json(doc["box"])
        if not all(name in model.parameters and lo < hi for name, lo, hi in box.bounds) or \
                list(box.names) != [p for p in model.parameters if p in box.names]:
            return [*rows, ("box", False, "the box must name the model's parameters, in its order, with lo < hi")]
        try:
            check_box(model, box)
        except ModelFileError as exc:
            return [*rows, ("box", False, f"the box is not valid for the model: {exc}")]
        rows.append(("box", True, f"the box {box.describe()} is valid for the model"))
    from lyapcheck.models.loop.discrete import is_discrete

    if is_discrete(model):  # a map: only the classes with a discrete-time check, on the shifted map
        return _verify_map(doc, model, rows, box)
    from lyapcheck.models.classes.contexts import FieldCheck
    from lyapcheck.models.classes.registry import verify

    shifted = shifted_field(model, box=box)
    conditions: dict[str, Any] = doc["conditions"]

    def row(name: str, check: Callable[[], tuple[bool, str]]) -> None:
        ok, why = check()
        rows.append((name, ok, why if ok else f"{name}: {why}"))

    lin = conditions.get("linearization")
    if isinstance(lin, dict) and lin.get("status") in ("certified", "refuted"):
        data = lin.get("certificate") if lin["status"] == "certified" else lin.get("refutation")
        from lyapcheck.models.classes.discrete_linearization import is_discrete_certificate

        if is_discrete_certificate(data):  # a map's test never re-checks a field
            rows.append(("linearization", False, 'linearization: a discrete-time certificate ("time": "discrete"), '
                                                 "and the model is a continuous-time field"))
        else:  # (the field as it is: before its denominators' proofs)
            row("linearization", lambda: verify("linearization", lin, FieldCheck(shifted)))

    from lyapcheck.models.surfaces.ball_roa import is_ball_region, verify_ball_roa

    for name, c in conditions.items():  # a ball-arithmetic region: on the true field, not the cleared one
        if is_ball_region(name, c):
            try:
                ok, why = verify_ball_roa(name, c, model, box)
            except (KeyError, ValueError, ArithmeticError, TypeError, IndexError, AttributeError) as exc:
                ok, why = False, f"malformed certificate: {_describe(exc)}"
            rows.append((name, ok, why if ok else f"{name}: {why}"))
    needs_field = [n for n, c in conditions.items() if n != "linearization" and isinstance(c, dict)
                   and c.get("status") == "certified" and not is_ball_region(n, c)]
    if needs_field:
        from lyapcheck.models.loop.positivity import check_certificate

        distinct = shifted.distinct_denominators()
        stored = doc["field"]["denominators"]
        if len(stored) != len(distinct):
            rows.append(("denominators", False, "one positivity certificate per denominator is needed"))
            return _with_verdict(doc, rows)
        signs = []
        for d, cert in zip(distinct, stored):
            sign = cert["sign"]
            if isinstance(sign, bool) or not isinstance(sign, int) or sign not in (1, -1):
                rows.append(("denominators", False, "a denominator's sign must be +1 or -1"))
                return _with_verdict(doc, rows)
            ok, why = check_certificate(shifted.ring, d * sign, cert, _box_start(model, box))
            rows.append(("denominators", ok, f"denominator {cert.get('denominator')}: {why}"))
            if not ok:
                return _with_verdict(doc, rows)
            signs.append(sign)
        scaling = Scaling.from_json(doc["field"]["scaling"])
        if not scaling.positive() or len(scaling.states) != model.n or len(scaling.disturbances) != \
                len(model.disturbances) or len(scaling.outputs) != len(model.outputs):
            rows.append(("scaling", False, "the scaling must have one positive factor per state, disturbance, output"))
            return _with_verdict(doc, rows)
        scaled = apply_scaling(clear(shifted, signs), scaling)
        for name in needs_field:
            try:
                ok, why = verify(name, conditions[name], FieldCheck(shifted, scaled))
            except (KeyError, ValueError, ArithmeticError, TypeError, IndexError, AttributeError) as exc:
                ok, why = False, f"malformed certificate: {_describe(exc)}"
            rows.append((name, ok, why if ok else f"{name}: {why}"))
    from lyapcheck.models.classes.region_size import check_size_rows

    check_size_rows(model, conditions, rows, list(model.states) + (list(box.names) if box is not None else []))
    check_counterexamples(model, conditions, rows)
    _check_stated_v(model, box, conditions, rows)
    _check_disturbance_keys(model, conditions, rows)
    _check_candidate(doc, model, conditions, rows)
    _check_summaries(model, conditions, rows, doc.get("box"))
    _check_stated_claims(model, conditions, rows)
    return _with_verdict(doc, rows)


def _verify_map(doc: dict[str, Any], model: Any, rows: list[Row], box: Any) -> list[Row]:
    """The rest of a discrete-time map's document: each decided condition checked by its class's entry for a
    map (:func:`lyapcheck.models.classes.registry.verify` with a
    :class:`~lyapcheck.models.classes.contexts.MapCheck`: the discrete-time test on the shifted map re-derived
    from the model text); a decided claim of a class without a discrete-time check fails (it cannot be
    re-checked on a map, so it cannot stand), as does one over a box of a class a map decides at a point only."""
    from lyapcheck.models.classes.contexts import MapCheck
    from lyapcheck.models.classes.discrete_lyapunov import BOX_CLASSES
    from lyapcheck.models.classes.registry import verify
    from lyapcheck.models.loop.discrete import shifted_map

    conditions: dict[str, Any] = doc["conditions"]
    # over a box (checked above: the fixed point stays put), the map re-derived with the box's normalized
    # parameters: a box widened after the fact changes them and the identities fail
    check = MapCheck(shifted=shifted_map(model, box=box), model=model)
    for name, c in conditions.items():
        if not isinstance(c, dict) or c.get("status") not in ("certified", "refuted", "counterexample"):
            continue
        if box is not None and name not in BOX_CLASSES:  # decided at a point only: no claim over a box stands
            rows.append((name, False, f"{name}: a {c.get('status')} claim over a box, which a map decides at a "
                                      "point only"))
            continue
        ok, why = verify(name, c, check)
        rows.append((name, ok, why if ok else f"{name}: {why}"))
    from lyapcheck.models.classes.region_size import check_size_rows

    check_size_rows(model, conditions, rows, list(model.states) + (list(box.names) if box is not None else []))
    _check_candidate(doc, model, conditions, rows)
    _check_disturbance_keys(model, conditions, rows)
    _check_summaries(model, conditions, rows, doc.get("box"))
    _check_stated_claims(model, conditions, rows)
    return _with_verdict(doc, rows)


def _check_stated_v(model: Any, box: Any, conditions: dict[str, Any], rows: list[Row]) -> None:
    """A certified V's ``variables`` name its exponents (the states, then for ``sos_bound`` the
    disturbances, then a box's parameters) and its ``V_text`` is V written readably, as
    ``certify`` writes them: a V_text edited to show another V fails here (both are optional:
    the exact V is the one checked)."""
    from lyapcheck.models.surfaces.certify import readable_v, stated_polynomials

    for name, c in conditions.items():
        if not isinstance(c, dict) or c.get("status") != "certified" or not isinstance(c.get("certificate"), dict):
            continue
        try:
            for data, variables in stated_polynomials(model, box, name, c["certificate"]):
                if "variables" in data and data["variables"] != variables:
                    rows.append((name, False, f"{name}: 'variables' must be {variables}"))
                elif "V_text" in data and data["V_text"] != readable_v(model, data["V"], variables):
                    rows.append((name, False, f"{name}: V_text is not the certified V written out"))
        except (KeyError, ValueError, TypeError, ArithmeticError) as exc:
            rows.append((name, False, f"{name}: the stated V is malformed: {_describe(exc)}"))


def _check_disturbance_keys(model: Any, conditions: dict[str, Any], rows: list[Row]) -> None:
    """Every condition of a model with disturbances says which it covers, and only such a model's
    conditions carry the key (DESIGN.md, "Disturbances in claims"). Whether an ``"all"`` claim
    holds is checked with its class (:func:`lyapcheck.models.classes.registry.verify`); a class that proves
    its claim with the disturbances at 0 only (:data:`~lyapcheck.models.classes.registry.ZERO_DISTURBANCE_ONLY`)
    may not claim them all where one enters."""
    from lyapcheck.models.classes.registry import ZERO_DISTURBANCE_ONLY

    for name, c in conditions.items():
        if not isinstance(c, dict):
            continue
        stated = c.get("disturbances")
        if model.disturbances and stated not in ("zero", "all"):
            rows.append((name, False, f"{name}: the model has disturbances, so the key 'disturbances' must be 'zero' "
                                      f"or 'all'; it is {stated!r}"))
        elif not model.disturbances and stated is not None:
            rows.append((name, False, f"{name}: the key 'disturbances' is {stated!r}, but the model has none"))
        elif name in ZERO_DISTURBANCE_ONLY and stated == "all" and c.get("status") == "certified" \
                and _disturbances_enter(model):
            rows.append((name, False, f"{name}: this class proves its claim with the disturbances at 0 only, not "
                                      "'all'"))


def _disturbances_enter(model: Any) -> bool:
    """Whether a disturbance with a bound > 0 occurs in the field (:func:`field.entering`)."""
    from lyapcheck.models.loop.field import entering, shifted_field

    shifted = shifted_field(model)
    return bool(entering(shifted.ring, model.n, (*shifted.numerators, *shifted.denominators),
                         list(model.disturbances.values())))


def _check_candidate(doc: dict[str, Any], model: Any, conditions: dict[str, Any], rows: list[Row]) -> None:
    """The top-level ``candidate`` text is the user's V: parsed with the model's expression rules,
    it must be the ``V`` of a certified ``candidate`` condition (shifted to the equilibrium)."""
    from lyapcheck.errors import ModelFileError
    from lyapcheck.models.surfaces.certify import parse_candidate
    from lyapcheck.models.classes.lyapunov import terms_json
    from lyapcheck.sos.polynomials import to_fmpq

    c = conditions.get("candidate")
    text = doc.get("candidate")
    certified = isinstance(c, dict) and c.get("status") == "certified"
    if text is None and not certified:
        return
    if not isinstance(text, str):
        rows.append(("candidate", False, "candidate: the candidate text must be text"
                     + (", and a certified candidate condition needs it" if certified else "")))
        return
    try:  # a text the report shows must be a candidate of this model, even where nothing certified it
        cand = parse_candidate(model, text)
    except ModelFileError as exc:
        rows.append(("candidate", False, f"candidate: the candidate text does not parse: {exc}"))
        return
    if not isinstance(c, dict) or not certified:
        return
    ring = model.state_ring
    gens = ring.gens()
    images = [g + to_fmpq(e) for g, e in zip(gens[:model.n], model.equilibrium)] + list(gens[model.n:])
    shifted_v = ring.compose(cand.poly, images)
    from lyapcheck.sos.polynomials import Ring

    # (a map's candidate over a box states V in the states and the box's parameters, at exponent 0: one V)
    box_names = tuple(str(k) for k in doc["box"]) if isinstance(doc.get("box"), dict) else ()
    states = Ring(ring.names[:model.n])
    on = Ring(ring.names[:model.n] + box_names)
    v = ring.restrict(shifted_v, states)
    stated = (c.get("certificate") or {}).get("V")
    same = terms_json(states, v) == stated or (bool(box_names) and terms_json(on, on.from_terms(
        {m + (0,) * len(box_names): k for m, k in states.terms(v).items()})) == stated)
    rows.append(("candidate", same, "the candidate text is the certified V" if same else
                 "candidate: the candidate text is not the V of the certified candidate condition"))


#: the figures the exact check of each certificate kind (:mod:`lyapcheck.models.classes.verify_field`) compares with the
#: certificate itself, each in the direction that keeps the claim true (a stated rate or level at
#: most the certified one, a bound or a time at least it); a GES claim adds ``k`` and its rate
_CHECKED_FIGURES: dict[str, tuple[str, ...]] = {
    "lyapunov": ("decay_rate_V_per_s",), "lyapunov_cliques": ("decay_rate_V_per_s",),
    "lyapunov_vector": ("decay_rate_V_per_s",), "sublevel": ("level", "ball_radius", "size"),
    "quadratic_ball": ("level", "ball_radius", "size"), "barrier": ("lambda_per_s",), "reach_avoid": ("reach_time_bound_s",),
    "sos_bound": ("bounds", "bounds_reference"), "interval": ("level", "size"),
    "discrete_sublevel": ("level", "size"),
}
#: what a certificate of each kind proves (a Lyapunov certificate: GAS, or GES where
#: :func:`lyapcheck.models.classes.verify_field._verify_ges` passed)
_KIND_PROPERTY: dict[str, str] = {"lyapunov": "GAS", "lyapunov_cliques": "GAS", "lyapunov_vector": "GAS", "sublevel": "ROA",
                                  "quadratic_ball": "ROA", "barrier": "safety", "reach_avoid": "reach_avoid",
                                  "sos_bound": "ultimate_bound", "interval": "ROA", "discrete_sublevel": "ROA"}


def _check_stated_claims(model: Any, conditions: dict[str, Any], rows: list[Row]) -> None:
    """Each decided condition's property and figures against what its certificate proves, by the
    rule every loop shares (:func:`lyapcheck.models.surfaces.stated.check_stated`): a figure is one its
    class's exact check compared, one re-derived here (the degree of the stated polynomial), or a
    declared estimate; anything else (a ``k`` beside a region, a decay rate beside the
    linearization) is refused."""
    from lyapcheck.models.surfaces.stated import Stated, check_stated

    for name, c in conditions.items():
        if not isinstance(c, dict) or not (c.get("status") == "certified" or
                                           (name == "linearization" and c.get("status") == "refuted")):
            continue
        try:
            if name == "linearization":
                proved = Stated("LES")
            else:
                cert = c["certificate"]
                kind = "sos_bound" if name == "sos_bound" else cert.get("kind")
                if kind not in _KIND_PROPERTY:
                    continue  # an unknown kind already fails its class's check
                prop = "GES" if kind == "lyapunov" and c.get("property") == "GES" else _KIND_PROPERTY[kind]
                checked = _CHECKED_FIGURES[kind] + (("k", "decay_rate_per_s") if prop == "GES" else ())
                stated = cert.get("B" if kind == "barrier" else "V")
                figures = {} if stated is None else {"degree": max(sum(e[:model.n]) for _, e in stated["terms"])}
                proved = Stated(prop, figures, frozenset(checked))
            ok, why = check_stated(c, proved)
        except (KeyError, ValueError, TypeError, ArithmeticError) as exc:
            ok, why = False, f"the stated figures are malformed: {_describe(exc)}"
        if not ok:
            rows.append((name, False, f"{name}: {why}"))


def _check_summaries(model: Any, conditions: dict[str, Any], rows: list[Row], box: Any) -> None:
    """Each decided condition's summary is the one its checked figures (and the checked box) give
    (:mod:`lyapcheck.models.classes.claims`), and its figures' units are the model's."""
    from lyapcheck.models.classes.claims import state_unit_figures, summary

    for name, c in conditions.items():
        if not isinstance(c, dict):
            continue
        try:
            expected = summary(name, c, tuple(model.outputs), box)
        except (KeyError, ValueError, TypeError, ArithmeticError) as exc:
            rows.append((name, False, f"{name}: the summary's figures are malformed: {_describe(exc)}"))
            continue
        if expected is not None and c.get("summary") != expected:
            rows.append((name, False, f"{name}: the summary is not what the checked figures say; they say: "
                                      f"{expected!r}"))
        elif expected is not None and ({k: c[k] for k in ("ball_radius_unit",) if k in c}
                                       != state_unit_figures(model.units, model.states, c)):
            rows.append((name, False, f"{name}: ball_radius_unit is not the states' unit"))


def _box_start(model: Any, box: Any) -> int | None:
    return None if box is None else model.n + len(model.disturbances)


def result_conditions(doc: dict[str, Any]) -> dict[str, ConditionResult]:
    """The document's conditions as results (for the API's typed view)."""
    out = {}
    for name, c in doc["conditions"].items():
        numbers = {k: v for k, v in c.items() if k not in ("status", "summary", "property", "certificate",
                                                           "refutation", "solver")}
        out[name] = ConditionResult(name, c["status"], c["summary"], numbers=numbers,
                                    certificate=c.get("certificate") or {}, refutation=c.get("refutation") or {},
                                    solver=c.get("solver") or {}, property=c.get("property"))
    return out
