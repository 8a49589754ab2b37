"""``verify`` of a discrete-time map with functions (``[model] time = "discrete"`` with ``sin``, ``tanh``,
``[networks]``, ...; issue 44, item 1): its recasting as the model text gives it, and each decided condition
by its class's ``verify_map_functions`` entry (:mod:`lyapcheck.models.classes.discrete_functions`:
``linearization`` and ``roa``; :mod:`lyapcheck.models.classes.map_relations`: ``quadratic`` and ``sos_gas``). Called from :func:`lyapcheck.models.surfaces.recast_certify.verify_recast`
(one call site; this module does not import it). Such a map is certified by the one runner,
:func:`lyapcheck.models.surfaces.certify.certify_model`."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:  # pragma: no cover
    from lyapcheck.models.language.parameter_box import ModelBox
    from lyapcheck.models.language.recast import RecastModel

Row = tuple[str, bool, str]


def verify_map_functions(doc: dict[str, Any], model: "RecastModel", rows: list[Row]) -> list[Row]:
    """The rest of a map with functions' document: its recasting as the model text gives it, each decided
    claim checked by its class's entry (:func:`lyapcheck.models.classes.registry.verify` with a
    :class:`~lyapcheck.models.classes.contexts.MapFunctionsCheck`: the linearization re-derived, a
    ``discrete_interval`` region proved again, a ``discrete_relations`` identity re-checked on the relations
    derived again); any other decided claim fails (no check of this map
    re-derives it)."""
    from lyapcheck.models.classes.contexts import MapFunctionsCheck
    from lyapcheck.models.classes.registry import verify
    from lyapcheck.models.surfaces.documents import with_verdict

    stated = doc["recast"]
    derived = model.system.to_json()
    same = all(stated.get(k) == derived[k] for k in derived)
    rows.append(("recasting", same, "the stated recasting of the map's displacement F(x) - x is the one the model "
                                    "text gives" if same else "the stated recasting differs from the one the model "
                                                              "text gives"))
    box = None
    if "box" in doc:  # read at the box's centre, the fixed point staying put over it (re-derived here)
        box, why = _box_of(doc, model)
        rows.append(("box", box is not None, why))
        if box is None:
            return with_verdict(doc, rows)
    check = MapFunctionsCheck(model=model, box=box)
    for name, c in doc["conditions"].items():
        if not isinstance(c, dict) or c.get("status") not in ("certified", "refuted", "counterexample"):
            continue
        try:
            ok, why = verify(name, c, check)
        except (KeyError, ValueError, ArithmeticError, TypeError, IndexError, AttributeError,
                ZeroDivisionError) as exc:
            ok, why = False, f"malformed certificate: {type(exc).__name__}: {exc}"[:200]
        rows.append((name, ok, why if ok else f"{name}: {why}"))
    return with_verdict(doc, rows)


def _box_of(doc: dict[str, Any], model: "RecastModel") -> tuple["ModelBox | None", str]:
    """The document's box, its parameters the model's and read at its centre, and the map recast with them as
    balls keeping its fixed point (:func:`lyapcheck.models.classes.discrete_functions_box.boxed_system`); or
    (None, why not)."""
    from lyapcheck.errors import ModelFileError
    from lyapcheck.models.classes.discrete_functions_box import boxed_system
    from lyapcheck.models.language.parameter_box import ModelBox

    try:
        box = ModelBox.from_json(doc["box"])
    except (TypeError, ValueError, AttributeError, ZeroDivisionError) as exc:
        return None, f"malformed box: {exc}"
    for name, lo, hi in box.bounds:
        if name not in model.parameters or not lo < hi:
            return None, f"box: {name!r} is not a parameter of the model with lo < hi"
        if model.parameters[name] != box.center(name):
            return None, f"box: the model is not read at the box's centre ({name} = {model.parameters[name]})"
    try:
        boxed_system(model, box)
    except ModelFileError as exc:
        return None, f"box: {exc}"
    return box, ("each box parameter is read at the box's centre, and the map's fixed point is proved to stay put "
                 "over the box")


__all__ = ["verify_map_functions"]
