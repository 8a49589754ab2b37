"""``certify`` and ``verify`` of a discrete-time map with functions (``[model] time = "discrete"`` with ``sin``,
``tanh``, ``[networks]``, ...; issue 44, item 1): the classes of
:mod:`lyapcheck.models.classes.discrete_functions` (``linearization`` and ``roa``), every other class
``not_applicable`` in one line. Called from :func:`lyapcheck.models.surfaces.certify.certify_model` and
:func:`lyapcheck.models.surfaces.recast_certify.verify_recast` (one call site each; this module imports
neither)."""

from __future__ import annotations

import time
from typing import TYPE_CHECKING, Any, Callable, Sequence

from lyapcheck.results import ConditionResult

if TYPE_CHECKING:  # pragma: no cover
    from lyapcheck.models.language.recast import RecastModel

Row = tuple[str, bool, str]


def map_results(model: "RecastModel", chosen: Sequence[str], limit: float,
                guarded: Callable[[str, Callable[[], ConditionResult], float], ConditionResult]
                ) -> tuple[dict[str, ConditionResult], dict[str, float], Any]:
    """The ``chosen`` classes on the map (results and seconds, in the order chosen) and the loop the document
    states: ``linearization`` and ``roa`` (:mod:`lyapcheck.models.classes.discrete_functions`), each under
    ``guarded`` (certify's: numerical trouble or the time limit become ``inconclusive``); every other class
    ``not_applicable`` in one line (:data:`~lyapcheck.models.classes.discrete_functions.NOT_YET`)."""
    from lyapcheck.models.classes import discrete_functions
    from lyapcheck.models.classes.recast_classes import base_loop
    from lyapcheck.models.engines.search import Budget

    results: dict[str, ConditionResult] = {}
    seconds: dict[str, float] = {}
    for name in chosen:
        if name not in discrete_functions.TAKEN:
            results[name] = ConditionResult(name, "not_applicable", discrete_functions.NOT_YET)
    if "linearization" in chosen:
        start = time.perf_counter()
        results["linearization"] = guarded("linearization", lambda: discrete_functions.linearization(model), limit)
        seconds["linearization"] = time.perf_counter() - start
    if "roa" in chosen:
        start = time.perf_counter()
        budget = Budget(limit, "lyapcheck.tolerances.MODEL_CLASS_TIME_LIMIT_S")
        results["roa"] = guarded("roa", lambda: discrete_functions.roa(model, budget), limit)
        seconds["roa"] = time.perf_counter() - start
    if model.disturbances:
        for r in results.values():  # the map is read with its disturbances at 0
            r.disturbances = "zero"
    return {name: results[name] for name in chosen}, seconds, base_loop(model.system, cylinder=False)


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


__all__ = ["map_results", "verify_map_functions"]
