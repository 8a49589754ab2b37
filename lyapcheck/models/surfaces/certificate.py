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
import json
from fractions import Fraction
from pathlib import Path
from typing import Any, Callable

from lyapcheck.errors import CertificateError, InputFileError
from lyapcheck.exact import refuse_oversized_numbers
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
    p = Path(path)
    try:
        doc = json.loads(p.read_text())
    except FileNotFoundError:
        raise InputFileError(f"certificate file '{p}' does not exist") from None
    except (json.JSONDecodeError, UnicodeDecodeError) as exc:
        raise InputFileError(f"certificate file '{p}' is not valid JSON: {exc}") from None
    except (ValueError, RecursionError) as exc:
        raise InputFileError(f"certificate file '{p}' cannot be read: {exc}") from None
    except OSError as exc:
        raise InputFileError(f"certificate file '{p}' cannot be read: {exc.strerror or exc}") from None
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
    shifted = shifted_field(model, box=box)
    conditions: dict[str, Any] = doc["conditions"]

    def row(name: str, check: Callable[[], tuple[bool, str]]) -> None:
        ok, why = check()
        rows.append((name, ok, why if ok else f"{name}: {why}"))

    lin = conditions.get("linearization")
    if isinstance(lin, dict) and lin.get("status") in ("certified", "refuted"):
        from lyapcheck.models.classes import linearization

        data = lin.get("certificate") if lin["status"] == "certified" else lin.get("refutation")
        from lyapcheck.models.classes.discrete_linearization import is_discrete_certificate

        if is_discrete_certificate(data):  # a map's test never re-checks a field
            rows.append(("linearization", False, 'linearization: a discrete-time certificate ("time": "discrete"), '
                                                 "and the model is a continuous-time field"))
        elif shifted.box is not None:  # the Jacobian for every value of the box
            row("linearization", lambda: linearization.verify_over_box(shifted, lin["status"], data or {}))
        else:
            row("linearization", lambda: linearization.verify(shifted, lin["status"], data or {}))

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
                ok, why = _verify_class(name, conditions[name], scaled)
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
    """The rest of a discrete-time map's document: the linearization re-derived with the discrete-time
    test on the shifted map; a certified condition of a class without a discrete-time check fails (it
    cannot be re-checked on a map, so it cannot stand), as does a box (refused on a map)."""
    from lyapcheck.models.classes import discrete_linearization
    from lyapcheck.models.classes.registry import DISCRETE
    from lyapcheck.models.loop.discrete import shifted_map

    if box is not None:
        return _with_verdict(doc, [*rows, ("box", False, 'a box is not taken on a discrete-time map ([model] time = '
                                                         '"discrete")')])
    conditions: dict[str, Any] = doc["conditions"]
    for name, c in conditions.items():
        if not isinstance(c, dict) or c.get("status") not in ("certified", "refuted", "counterexample"):
            continue
        if name not in DISCRETE or c["status"] == "counterexample" or (name != "linearization"
                                                                        and c["status"] != "certified"):
            rows.append((name, False, f"{name}: a {c.get('status')} claim on a discrete-time map that no "
                                      "discrete-time check re-derives"))
            continue
        if name == "linearization":
            data = c.get("certificate") if c["status"] == "certified" else c.get("refutation")
            ok, why = discrete_linearization.verify(shifted_map(model), c["status"], data or {})
        else:  # quadratic, sos_gas: V(F(e)) - V(e) <= -mu V(e) - W(e), checked from the condition's JSON
            from lyapcheck.models.classes import discrete_lyapunov

            ok, why = discrete_lyapunov.verify(shifted_map(model), c["status"], c)
        rows.append((name, ok, why if ok else f"{name}: {why}"))
    _check_disturbance_keys(model, conditions, rows)
    _check_summaries(model, conditions, rows, None)
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
    holds is checked with its class (:func:`_verify_class`)."""
    for name, c in conditions.items():
        if not isinstance(c, dict):
            continue
        stated = c.get("disturbances")
        if model.disturbances and stated not in ("zero", "all"):
            rows.append((name, False, f"{name}: the model has disturbances, so the key 'disturbances' must be 'zero' "
                                      f"or 'all'; it is {stated!r}"))
        elif not model.disturbances and stated is not None:
            rows.append((name, False, f"{name}: the key 'disturbances' is {stated!r}, but the model has none"))
        elif name in ("linearization", "candidate") and stated == "all" and c.get("status") == "certified" \
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

    states = Ring(ring.names[:model.n])
    same = terms_json(states, ring.restrict(shifted_v, states)) == (c.get("certificate") or {}).get("V")
    rows.append(("candidate", same, "the candidate text is the certified V" if same else
                 "candidate: the candidate text is not the V of the certified candidate condition"))


#: the figures the exact check of each certificate kind (:func:`_verify_class`) compares with the
#: certificate itself, each in the direction that keeps the claim true (a stated rate or level at
#: most the certified one, a bound or a time at least it); a GES claim adds ``k`` and its rate
_CHECKED_FIGURES: dict[str, tuple[str, ...]] = {
    "lyapunov": ("decay_rate_V_per_s",), "lyapunov_cliques": ("decay_rate_V_per_s",), "sublevel": ("level", "ball_radius", "size"),
    "quadratic_ball": ("level", "ball_radius", "size"), "barrier": ("lambda_per_s",), "reach_avoid": ("reach_time_bound_s",),
    "sos_bound": ("bounds", "bounds_reference"), "interval": ("level", "size"),
}
#: what a certificate of each kind proves (a Lyapunov certificate: GAS, or GES where
#: :func:`_verify_ges` passed)
_KIND_PROPERTY: dict[str, str] = {"lyapunov": "GAS", "lyapunov_cliques": "GAS", "sublevel": "ROA", "quadratic_ball": "ROA", "barrier": "safety",
                                  "reach_avoid": "reach_avoid", "sos_bound": "ultimate_bound", "interval": "ROA"}


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


def _multipliers(data: Any, nvars: int, first: int) -> list[tuple[int, Any]]:
    """A certificate's box multipliers, each on a box parameter (index >= ``first``): a multiplier on
    a state would restrict the states, so any other index makes the certificate malformed."""
    from lyapcheck.models.engines.search import box_multipliers_from_json

    out = box_multipliers_from_json(data or [], nvars)
    if any(not first <= j < nvars for j, _ in out):
        raise ValueError("a box multiplier must act on a box parameter")
    return out


def _gram(data: dict[str, Any], nvars: int) -> Any:
    from lyapcheck.sos.certificates import GramPoly

    return GramPoly.from_json(data, nvars)


def _v_matches(scaled: Any, field: Any, V: Any, stated: dict[str, Any], v0: Fraction = Fraction(0)) -> bool:
    """The stated V (declared states) is the Gram V (scaled states, plus a constant) unscaled, exactly,
    and its exponents are integers (a JSON ``2.0`` equals ``2`` in Python; it is refused here)."""
    from lyapcheck.models.classes.lyapunov import stated_v

    _check_terms(stated)
    return stated_v(scaled, field, V.poly(field.ring) + field.ring.constant(v0)) == stated


def _check_terms(stated: Any) -> None:
    """A stated polynomial's form: ``{"terms": [[coefficient, [exponent, ...]], ...]}`` with
    non-negative integer exponents (ValueError naming the key otherwise)."""
    from lyapcheck.sos.certificates import exponent

    if not isinstance(stated, dict) or not isinstance(stated.get("terms"), list):
        raise ValueError("V must be a table with a list 'terms'")
    for term in stated["terms"]:
        if not isinstance(term, list) or len(term) != 2 or not isinstance(term[1], list):
            raise ValueError(f"V: a term must be [coefficient, [exponents]], got {term!r}")
        for e in term[1]:
            exponent(e, "V.terms")


def _at_most(stated: Any, proved: Fraction) -> bool:
    return stated is None or Fraction(float(stated)) <= proved + abs(proved) / 10**12


def _at_least(stated: Any, proved: Fraction) -> bool:
    return stated is None or Fraction(float(stated)) >= proved - abs(proved) / 10**12


def _verify_vertices(c: dict[str, Any], cert: dict[str, Any], scaled: Any, field: Any) -> tuple[bool, str]:
    """A Lyapunov certificate in the vertex form (``form = "vertices"``, the vertex form of
    :mod:`lyapcheck.models.classes.lyapunov`): ``V(z, u)`` exact (``V_scaled``), a Gram matrix of ``V`` and of the remainder at
    each vertex of the box, checked exactly (:func:`~lyapcheck.sos.certificates.check_lyapunov_vertices`)."""
    from lyapcheck.models.classes.lyapunov import stated_v
    from lyapcheck.sos.certificates import check_lyapunov_vertices, exponent

    if not field.p or field.disturbances:
        return False, "a certificate in the vertex form is for a box of parameters (and no disturbance)"
    if not isinstance(cert.get("gram_V_vertices"), list) or not isinstance(cert.get("gram_sigma_vertices"), list):
        return False, "a certificate in the vertex form has lists 'gram_V_vertices' and 'gram_sigma_vertices'"
    ring, nv = field.ring, field.ring.nvars
    _check_terms(cert["V_scaled"])
    if any(len(m) != nv for _, m in cert["V_scaled"]["terms"]):
        return False, f"V_scaled: a monomial must have {nv} exponents"
    V = ring.from_terms({tuple(exponent(e, "V_scaled") for e in m): Fraction(v) for v, m in cert["V_scaled"]["terms"]})
    _check_terms(cert["V"])
    if stated_v(scaled, field, V) != cert["V"]:
        return False, "the stated V (declared states) is not the certificate's V_scaled unscaled"
    positive = [_gram(part, nv) for part in cert["gram_V_vertices"]]
    sigmas = [_gram(part, nv) for part in cert["gram_sigma_vertices"]]
    mu = Fraction(cert["mu_scaled"])
    ok, why = check_lyapunov_vertices(ring, field.g, field.D, V, positive, sigmas, mu)
    if not ok:
        return False, why
    if not _at_most(c.get("decay_rate_V_per_s"), mu / scaled.scaling.time):
        return False, "the stated decay rate of V exceeds the certified one"
    if c.get("property") not in ("GAS", None):
        return False, f"a Lyapunov certificate in the vertex form proves GAS, not {c.get('property')}"
    return True, why


def _verify_cliques(c: dict[str, Any], cert: dict[str, Any], scaled: Any, field: Any) -> tuple[bool, str]:
    """A Lyapunov certificate in the clique form (kind ``lyapunov_cliques``, :func:`lyapcheck.models.
    classes.lyapunov.clique_search`): ``V`` and the remainder sums of Gram matrices, checked exactly
    (:func:`~lyapcheck.sos.certificates.check_lyapunov_cliques`)."""
    from lyapcheck.sos.certificates import GramSum, check_lyapunov_cliques

    if field.p:
        return False, "a certificate in the clique form is for a field without box coordinates"
    if not isinstance(cert.get("gram_V"), list) or not isinstance(cert.get("gram_sigma"), list):
        return False, "a certificate in the clique form has lists 'gram_V' and 'gram_sigma'"
    nv = field.ring.nvars
    V = GramSum(tuple(_gram(part, nv) for part in cert["gram_V"]))
    sigma = GramSum(tuple(_gram(part, nv) for part in cert["gram_sigma"]))
    if not _v_matches(scaled, field, V, cert["V"]):
        return False, "the stated V (declared states) is not the certificate's Gram V unscaled"
    mu = Fraction(cert["mu_scaled"])
    ok, why = check_lyapunov_cliques(field.ring, field.g, field.D, V, sigma, mu)
    if not ok:
        return False, why
    if not isinstance(cert.get("cliques"), list) or len(cert["cliques"]) != len(V.parts):
        return False, "'cliques' must name the states of each of V's Gram matrices"
    if not _at_most(c.get("decay_rate_V_per_s"), mu / scaled.scaling.time):
        return False, "the stated decay rate of V exceeds the certified one"
    if c.get("property") not in ("GAS", None):
        return False, f"a Lyapunov certificate in the clique form proves GAS, not {c.get('property')}"
    return True, why


def _verify_class(name: str, c: dict[str, Any], scaled: Any) -> tuple[bool, str]:
    from lyapcheck.models.loop.field import StateField, state_field
    from lyapcheck.sos.certificates import check_containment, check_dissipation, check_lyapunov, check_output_bound, \
        check_quadratic_ball, check_sublevel

    cert = c["certificate"]
    if name == "sos_bound":
        from lyapcheck.models.classes.bounds import bound_figures, output_deviation

        ring = scaled.ring
        nv = ring.nvars
        names = list(scaled.outputs)
        for out, data in cert["outputs"].items():
            if out not in scaled.outputs:
                return False, f"no output named {out}"
            y, _ = output_deviation(scaled, out)  # y - y_eq, as the sentence says (lyapcheck.models.classes.bounds)
            s_y = scaled.scaling.outputs[names.index(out)]
            V = _gram(data["gram_V"], nv)
            taus = [_gram(t, nv) for t in data["gram_tau"]]
            lam, B = Fraction(data["lam_scaled"]), Fraction(data["B_scaled"])
            v0 = Fraction(data.get("V_constant", "0"))
            first = scaled.n + scaled.m
            box_d = _multipliers(data.get("box_multipliers_D"), nv, first)
            box_e = _multipliers(data.get("box_multipliers_E"), nv, first)
            if any(any(m[scaled.n:]) for m in V.basis):
                return False, f"output {out}: V may depend on the states only"
            ok, why = check_dissipation(ring, scaled.g, scaled.D, scaled.bounds, V, lam, taus,
                                        _gram(data["gram_sigma_D"], nv), box_d, v0)
            if not ok:
                return False, f"output {out}: {why}"
            ok, why = check_output_bound(ring, V, y, B, _gram(data["gram_sigma_E"], nv), box_e, v0)
            if not ok:
                return False, f"output {out}: {why}"
            bound = Fraction(data["bound"])
            if bound < 0 or bound * bound < B * s_y * s_y:
                return False, f"output {out}: the stated bound {data['bound']} is below s_y sqrt(B)"
            if not _at_least(c.get("bounds", {}).get(out), bound):
                return False, f"output {out}: the stated figure is below the certified bound"
            if not _v_matches(scaled, StateField(ring=ring, g=scaled.g, D=scaled.D), V, data["V"], v0):
                return False, f"output {out}: the stated V is not the certificate's"
        figures = bound_figures(scaled, list(cert["outputs"]))
        if set(c.get("bounds", {})) != set(cert["outputs"]):
            return False, "a bound is stated for an output the certificate does not bound"
        if any(c.get(key) != figures.get(key) for key in ("bounds_reference", "bounds_unit")):
            return False, "the bounds' reference points (bounds_reference) or units (bounds_unit) are not the model's"
        return True, "every output's dissipation and output identities hold exactly"
    if name == "barrier":
        return _verify_barrier(c, cert, scaled)
    if name == "reach_avoid":
        return _verify_reach_avoid(c, cert, scaled)
    field = state_field(scaled)
    if c.get("disturbances") == "all":
        from lyapcheck.models.surfaces.certify import robust_field
        from lyapcheck.models.loop.field import active_disturbances

        if active_disturbances(scaled):
            robust = robust_field(scaled)
            if robust is None:
                return False, ("'disturbances': 'all' is claimed, but a disturbance moves the equilibrium, so no "
                               "stability claim can hold for every disturbance")
            field = robust
    if cert.get("kind") == "lyapunov_cliques":
        return _verify_cliques(c, cert, scaled, field)
    if cert.get("kind") == "lyapunov" and cert.get("form") == "vertices":
        return _verify_vertices(c, cert, scaled, field)
    ring, n = field.ring, field.n
    nv = ring.nvars
    V = _gram(cert["gram_V"], nv)
    box = _multipliers(cert.get("box_multipliers"), nv, n)
    if any(any(m[n:n + field.disturbances]) for m in V.basis):
        return False, "V may not depend on a disturbance"
    if not _v_matches(scaled, field, V, cert["V"]):
        return False, "the stated V (declared states) is not the certificate's Gram V unscaled"
    kind = cert.get("kind")
    T = scaled.scaling.time
    if kind == "lyapunov":
        mu = Fraction(cert["mu_scaled"])
        ok, why = check_lyapunov(ring, field.g, field.D, V, _gram(cert["gram_sigma"], nv), mu, box)
        if not ok:
            return False, why
        if not _at_most(c.get("decay_rate_V_per_s"), mu / T):
            return False, "the stated decay rate of V exceeds the certified one"
        if c.get("property") == "GES":
            return _verify_ges(scaled, V, mu, cert, c)
        if c.get("property") not in ("GAS", None):
            return False, f"a Lyapunov certificate proves GAS (or GES), not {c.get('property')}"
        return True, why
    if kind in ("sublevel", "quadratic_ball"):
        level = Fraction(cert["level_scaled"])
        if Fraction(cert["level"]) != level or not _at_most(c.get("level"), level):
            return False, "the stated level is not the certified one"
        if kind == "sublevel":
            ok, why = check_sublevel(ring, field.g, V, level, _gram(cert["gram_s"], nv), _gram(cert["gram_sigma"], nv),
                                     box)
        elif box:
            return False, "a quadratic-ball certificate has no box multipliers"
        else:
            ok, why = check_quadratic_ball(ring, field.g, V, level, Fraction(cert["radius_scaled"]),
                                           Fraction(cert["lambda"]), Fraction(cert["p_bar"]), Fraction(cert["m"]))
        if not ok:
            return False, why
        if "ball" in cert:
            from lyapcheck.models.classes.regions import radius_polynomial, states_only
            from lyapcheck.sos.polynomials import Ring

            sring = Ring(ring.names[:n])
            r = Fraction(cert["ball"]["radius"])
            ok, why2 = check_containment(sring, states_only(V, n), level, radius_polynomial(sring, scaled.scaling), r * r,
                                         _gram(cert["ball"]["gram_s"], n), _gram(cert["ball"]["gram_sigma"], n))
            if not ok or not _at_most(c.get("ball_radius"), r):
                return False, f"the ball: {why2 if not ok else 'the stated radius exceeds the certified one'}"
        elif c.get("ball_radius") is not None:
            return False, "a ball radius is stated without its certificate"
        if c.get("property") != "ROA":
            return False, f"a {kind} certificate proves a region of attraction (ROA)"
        return True, why
    return False, f"unknown certificate kind {kind!r}"


def _verify_barrier(c: dict[str, Any], cert: dict[str, Any], scaled: Any) -> tuple[bool, str]:
    """A barrier certificate on the robust field (every disturbance that enters a box coordinate),
    with the sets re-read from the model (a widened initial set or a shrunk unsafe set in the
    model's text makes an identity fail), B stated in the declared states as its scaled form."""
    from lyapcheck.models.classes.barrier import scaled_pieces
    from lyapcheck.models.loop.field import state_field
    from lyapcheck.models.classes.lyapunov import stated_v
    from lyapcheck.sos.certificates import check_barrier, exponent

    if cert.get("kind") != "barrier":
        return False, f"a barrier's certificate kind must be 'barrier', not {cert.get('kind')!r}"
    if c.get("property") != "safety":
        return False, "a barrier certificate proves safety"
    model = scaled.cleared.shifted.model
    sets = getattr(model, "sets", None) or {}
    if not sets.get("initial") or not sets.get("unsafe"):
        return False, "the model has no [sets] initial and unsafe for a barrier"
    field = state_field(scaled, robust=True)
    ring, n = field.ring, field.n
    nv = ring.nvars
    initial = scaled_pieces(scaled, field, sets["initial"])
    unsafe = scaled_pieces(scaled, field, sets["unsafe"])
    terms = cert["B_scaled"]["terms"]
    B = ring.from_terms({tuple(exponent(e, "B_scaled") for e in m): Fraction(v) for v, m in terms})
    _check_terms(cert["B"])
    if stated_v(scaled, field, B) != cert["B"]:
        return False, "the stated B (declared states) is not the certificate's B unscaled"

    def pieces(key: str, count: int) -> list[tuple[list[Any], Any]]:
        data = cert[key]
        if not isinstance(data, list) or len(data) != count:
            raise ValueError(f"{key}: one entry per piece of the set is needed")
        return [([_gram(g, nv) for g in item["multipliers"]], _gram(item["remainder"], nv)) for item in data]

    lam = Fraction(cert["lambda_scaled"])
    box = _multipliers(cert.get("box_multipliers"), nv, n)
    ok, why = check_barrier(ring, field.g, field.D, B, lam, initial, pieces("initial", len(initial)), unsafe,
                            pieces("unsafe", len(unsafe)), _gram(cert["gram_decrease"], nv), box)
    if not ok:
        return False, why
    stated = c.get("lambda_per_s")
    if stated is not None and abs(float(stated) - float(lam / scaled.scaling.time)) > 1e-9 * (1 + abs(float(stated))):
        return False, "the stated rate lambda_per_s is not the certificate's"
    return True, why


def _verify_reach_avoid(c: dict[str, Any], cert: dict[str, Any], scaled: Any) -> tuple[bool, str]:
    """A reach-avoid certificate on the robust field, the sets re-read from the model's text, V
    stated in the declared states as its scaled form, and the stated time bound the certified one."""
    from lyapcheck.models.classes.barrier import scaled_pieces
    from lyapcheck.models.loop.field import state_field
    from lyapcheck.models.classes.lyapunov import stated_v
    from lyapcheck.sos.certificates import check_reach_avoid, exponent

    if cert.get("kind") != "reach_avoid":
        return False, f"a reach_avoid certificate's kind must be 'reach_avoid', not {cert.get('kind')!r}"
    if c.get("property") != "reach_avoid":
        return False, "a reach_avoid certificate proves reach_avoid"
    model = scaled.cleared.shifted.model
    sets = getattr(model, "sets", None) or {}
    if not sets.get("initial") or not sets.get("unsafe") or len(sets.get("goal") or ()) != 1:
        return False, "the model has no [sets] initial, unsafe and a one-piece goal for reach_avoid"
    field = state_field(scaled, robust=True)
    ring, n = field.ring, field.n
    nv = ring.nvars
    initial = scaled_pieces(scaled, field, sets["initial"])
    unsafe = scaled_pieces(scaled, field, sets["unsafe"])
    (goal,) = scaled_pieces(scaled, field, sets["goal"])
    V = ring.from_terms({tuple(exponent(e, "V_scaled") for e in m): Fraction(v) for v, m in cert["V_scaled"]["terms"]})
    _check_terms(cert["V"])
    if stated_v(scaled, field, V) != cert["V"]:
        return False, "the stated V (declared states) is not the certificate's V unscaled"

    def pieces(key: str, count: int) -> list[tuple[list[Any], Any]]:
        data = cert[key]
        if not isinstance(data, list) or len(data) != count:
            raise ValueError(f"{key}: one entry per piece of the set is needed")
        return [([_gram(g, nv) for g in item["multipliers"]], _gram(item["remainder"], nv)) for item in data]

    if "stay" in cert:  # reach {W <= 0}, inside the goal and never left, instead of the goal itself
        from lyapcheck.sos.certificates import check_goal_invariant

        stay = cert["stay"]
        W = ring.from_terms({tuple(exponent(e, "W_scaled") for e in m): Fraction(v)
                             for v, m in stay["W_scaled"]["terms"]})
        _check_terms(stay["W"])
        if stated_v(scaled, field, W) != stay["W"]:
            return False, "the stated W (declared states) is not the certificate's W unscaled"
        ok, why = check_goal_invariant(ring, field.g, field.D, W, Fraction(stay["mu_scaled"]), goal,
                                       [_gram(g, nv) for g in stay["inside"]], _gram(stay["gram_invariant"], nv),
                                       _multipliers(stay.get("box_multipliers"), nv, n))
        if not ok:
            return False, f"stay_in_goal: {why}"
        goal = [-W]
    elif getattr(model, "stay_in_goal", False):
        return False, "the model asks to stay in the goal, and the certificate does not prove it"
    goal_certs = [(_gram(item["multiplier"], nv), _gram(item["remainder"], nv)) for item in cert["goal"]]
    boxes = [_multipliers(box, nv, n) for box in cert.get("box_multipliers") or [[] for _ in goal]]
    eps, delta, C = Fraction(cert["eps_scaled"]), Fraction(cert["delta_scaled"]), Fraction(cert["C_scaled"])
    ok, why = check_reach_avoid(ring, field.g, field.D, V, eps, C, delta, initial, pieces("initial", len(initial)),
                                unsafe, pieces("unsafe", len(unsafe)), goal, goal_certs,
                                _gram(cert["gram_bounded"], nv), boxes)
    if not ok:
        return False, why
    if not _at_least(c.get("reach_time_bound_s"), C / eps * scaled.scaling.time):
        return False, "the stated time bound is below the certified one"
    return True, why


def _verify_ges(scaled: Any, V: Any, mu: Fraction, cert: dict[str, Any], c: dict[str, Any]) -> tuple[bool, str]:
    from lyapcheck.sos.definiteness import is_positive_definite

    n = scaled.n
    if mu <= 0 or any(sum(m) != 1 or any(m[n:]) for m in V.basis) or len(V.basis) != n:
        return False, "GES needs a quadratic V (every state, degree 1, common to a box) and mu > 0"
    from lyapcheck.models.loop.field import declared_quadratic

    nv = len(V.basis[0])
    order = [V.basis.index(tuple(int(k == i) for k in range(nv))) for i in range(n)]
    P = declared_quadratic(scaled.scaling, [[V.Q[order[i]][order[j]] for j in range(n)] for i in range(n)])
    c1, c2, k = Fraction(cert["c1"]), Fraction(cert["c2"]), Fraction(cert["k"])
    eye = [[Fraction(int(i == j)) for j in range(n)] for i in range(n)]
    if not (c1 > 0 and is_positive_definite([[P[i][j] - c1 * eye[i][j] for j in range(n)] for i in range(n)])
            and is_positive_definite([[c2 * eye[i][j] - P[i][j] for j in range(n)] for i in range(n)])):
        return False, "c1 I < P < c2 I does not hold"
    if k * k < c2 / c1 or not _at_least(c.get("k"), k):
        return False, "k is below sqrt(c2/c1)"
    if not _at_most(c.get("decay_rate_per_s"), mu / scaled.scaling.time / 2):
        return False, "the stated decay rate of |x| exceeds mu / 2"
    return True, "a quadratic V with V' <= -mu V and c1 I < P < c2 I: GES, exactly"


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
