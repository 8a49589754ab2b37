"""``certify`` and ``verify`` of a discrete-time map with functions (``[model] time = "discrete"`` with ``sin``,
``tanh``, ``[networks]``, ...; issue 44, item 1): the classes of
:mod:`lyapcheck.models.classes.discrete_functions` (``linearization`` and ``roa``), every other class
``not_applicable`` in one line. Called from :func:`lyapcheck.models.surfaces.certify.certify_model` and
:func:`lyapcheck.models.surfaces.recast_certify.verify_recast` (one call site each)."""

from __future__ import annotations

import time
from typing import TYPE_CHECKING, Any, Sequence

from lyapcheck.results import ConditionResult

if TYPE_CHECKING:  # pragma: no cover
    from lyapcheck.models.language.recast import RecastModel
    from lyapcheck.models.loop.boxes import ModelBox
    from lyapcheck.models.surfaces.certify import ModelCertification

Row = tuple[str, bool, str]


def certify_map_functions(model: "RecastModel", classes: str | Sequence[str] | None, candidate: str | None,
                          limit: float, box: "ModelBox | None") -> "ModelCertification":
    """The chosen classes on the map: ``linearization``, then ``roa`` (``not_applicable`` once the map is
    refuted, as the region would be empty; by ball arithmetic otherwise); ``--box`` refused (exit 2)."""
    from lyapcheck.models.classes import discrete_functions
    from lyapcheck.models.classes.recast_classes import base_loop
    from lyapcheck.models.engines.search import Budget
    from lyapcheck.models.loop.discrete import refuse
    from lyapcheck.models.surfaces.certify import (Candidate, ModelCertification, _guarded, _needs_input,
                                                   class_selection)

    if box is not None:
        refuse(model, "--box", "certify a point (--set NAME=VALUE)")
    cand = Candidate(candidate, model.candidate_v) if candidate is not None else None
    chosen = class_selection(classes, model, cand)
    results: dict[str, ConditionResult] = {}
    seconds: dict[str, float] = {}
    for name in chosen:
        if name not in discrete_functions.TAKEN:
            results[name] = _needs_input(name, None, cand) or ConditionResult(name, "not_applicable",
                                                                              discrete_functions.NOT_YET)
    if "linearization" in chosen:
        start = time.perf_counter()
        results["linearization"] = _guarded("linearization", lambda: discrete_functions.linearization(model), limit)
        seconds["linearization"] = time.perf_counter() - start
    if "roa" in chosen:
        start = time.perf_counter()
        budget = Budget(limit, "lyapcheck.tolerances.MODEL_CLASS_TIME_LIMIT_S")
        results["roa"] = _guarded("roa", lambda: discrete_functions.roa(model, budget), limit)
        seconds["roa"] = time.perf_counter() - start
    if model.disturbances:
        for r in results.values():  # the map is read with its disturbances at 0
            r.disturbances = "zero"
    results = {name: results[name] for name in chosen}
    return ModelCertification(model=model, candidate=cand, results=results, seconds=seconds,
                              loop=base_loop(model.system, cylinder=False))


def verify_map_functions(doc: dict[str, Any], model: "RecastModel", rows: list[Row]) -> list[Row]:
    """The rest of a map with functions' document: its recasting as the model text gives it, the
    linearization re-derived, a ``discrete_interval`` region proved again; any other decided claim
    fails (no check of this map re-derives it)."""
    from lyapcheck.models.classes import discrete_functions
    from lyapcheck.models.surfaces.documents import with_verdict

    stated = doc["recast"]
    derived = model.system.to_json()
    same = all(stated.get(k) == derived[k] for k in derived)
    rows.append(("recasting", same, "the stated recasting of the map's displacement F(x) - x is the one the model "
                                    "text gives" if same else "the stated recasting differs from the one the model "
                                                              "text gives"))
    if "box" in doc:
        rows.append(("box", False, 'a box is not taken on a discrete-time map ([model] time = "discrete")'))
    for name, c in doc["conditions"].items():
        if not isinstance(c, dict) or c.get("status") not in ("certified", "refuted", "counterexample"):
            continue
        try:
            if name == "linearization" and c["status"] in ("certified", "refuted"):
                data = c.get("certificate") if c["status"] == "certified" else c.get("refutation")
                ok, why = discrete_functions.verify_linearization(model, c["status"], data or {})
            elif name == "roa" and c["status"] == "certified":
                ok, why = discrete_functions.verify_roa(model, c)
            else:
                ok, why = False, (f"a {c.get('status')} claim on a discrete-time map with functions that no check "
                                  "re-derives")
        except (KeyError, ValueError, ArithmeticError, TypeError, IndexError, AttributeError,
                ZeroDivisionError) as exc:
            ok, why = False, f"malformed certificate: {type(exc).__name__}: {exc}"[:200]
        rows.append((name, ok, why if ok else f"{name}: {why}"))
    return with_verdict(doc, rows)


__all__ = ["certify_map_functions", "verify_map_functions"]
