"""``barrier`` and ``reach_avoid`` of a discrete-time map with functions over a box of its parameters: the
refutation at one value of the box, and its re-check.

Over a box (``certify --box``) the certificates are the point classes'
(:mod:`lyapcheck.models.classes.map_relations_safety`, :mod:`lyapcheck.models.classes.map_relations_reach`) on
the map recast with the box's parameters as bounded variables of its relations
(:func:`lyapcheck.models.classes.map_relations.on_relations_box`): one ``B`` (``V``) of the states for every
value of the box, checked exactly.

A claim for every value of the box is false as soon as it is false at one value. Before the search, the point
route's falsification (:func:`lyapcheck.models.classes.map_relations_safety.falsify`) runs at each corner of the
box, then at its centre (:func:`~lyapcheck.models.classes.discrete_linearization.box_points`), as a polynomial
map's (:mod:`lyapcheck.models.classes.discrete_safety_box`): the map recast at that value (exact rationals,
:func:`model_at`), iterated in floating point from starts in the initial set, and an unsafe iterate (reach_avoid:
before any iterate in the goal) re-derived from its rational start in ball arithmetic through the true functions.
The first one proved makes the class ``refuted`` for the box, naming the value; ``verify`` re-derives the map at
the stated value (checked to lie in the box) and the iterate from the stated start. A value where nothing is
found proves nothing about the rest of the box.
"""

from __future__ import annotations

from dataclasses import replace
from fractions import Fraction
from typing import TYPE_CHECKING, Any, Mapping

from lyapcheck.results import ConditionResult

if TYPE_CHECKING:  # pragma: no cover
    from lyapcheck.models.language.parameter_box import ModelBox
    from lyapcheck.models.language.recast import RecastModel


def model_at(model: "RecastModel", point: Mapping[str, Fraction]) -> "RecastModel":
    """The map with functions at one value of its box (``point``, by parameter name), exactly: its displacement
    ``F(x) - x`` recast with those values (as the model file's map is,
    :meth:`lyapcheck.models.language.modelfile.ModelFile.recast_map`; disturbances at 0). The fixed point stays
    put over the box (proved before: :func:`lyapcheck.models.classes.discrete_functions_box.boxed_system`)."""
    from lyapcheck.models.language.recast import recast_dynamics

    constants = {**model.parameters, **point, **{d: Fraction(0) for d in model.disturbances}}
    texts: dict[str, object] = {s: f"({t}) - ({s})" for s, t in model.dynamics_text.items()}
    system, _ = recast_dynamics(model.source, model.states, texts, constants, tuple(model.equilibrium),
                                networks=model.networks, for_map=True)
    return replace(model, system=system, parameters={**model.parameters, **point})


def _sets(name: str, model: "RecastModel") -> tuple[Any, dict[str, Any]]:
    from lyapcheck.models.classes.map_relations import on_relations
    from lyapcheck.models.classes.map_relations_safety import map_sets

    keys = ("initial", "unsafe", "goal") if name == "reach_avoid" else ("initial", "unsafe")
    m = on_relations(model)
    return m, map_sets(model, m, keys)


def refute(name: str, model: "RecastModel", box: "ModelBox") -> ConditionResult | None:
    """``refuted`` for the box when the falsification finds an unsafe iterate proved at one of its corners or
    its centre (reach_avoid: before any iterate is in the goal), naming the value; None when none is found."""
    from lyapcheck.models.classes.discrete_safety_box import refute_at_points
    from lyapcheck.models.classes.map_relations_safety import falsify

    def at(point: Mapping[str, Fraction]) -> Any:
        model_there = model_at(model, point)
        m, sets = _sets(name, model_there)
        goal = sets["goal"][0] if name == "reach_avoid" else None
        return falsify(model_there, m, sets["initial"], sets["unsafe"], goal)

    return refute_at_points(name, model, box, at)


def verify_refutation(name: str, model: "RecastModel", box: "ModelBox", c: Mapping[str, Any]) -> tuple[bool, str]:
    """Re-check a refutation of :func:`refute`: the stated box the document's, the stated value in it (every
    parameter named, exact), the sentence naming it
    (:func:`lyapcheck.models.classes.discrete_safety_box.stated_point`), then the point route's check of the
    start and its iterate on the map recast at that value
    (:func:`~lyapcheck.models.classes.map_relations_safety.check_iterate_functions`)."""
    from lyapcheck.models.classes.barrier import SETS_USE_BOX, sets_use_box
    from lyapcheck.models.classes.discrete_safety import verify_refutation as verify_start
    from lyapcheck.models.classes.discrete_safety_box import stated_point
    from lyapcheck.models.classes.map_relations import NotTaken
    from lyapcheck.models.classes.map_relations_safety import check_iterate_functions

    if sets_use_box(model, box):
        return False, SETS_USE_BOX
    try:
        point, why = stated_point(box, c)
    except (KeyError, TypeError, AttributeError) as exc:
        return False, f"malformed refutation: {exc}"
    if point is None:
        return False, why
    try:
        at = model_at(model, point)
        m, sets = _sets(name, at)
        goal = sets["goal"][0] if name == "reach_avoid" else None
        ok, why = verify_start(at, c, lambda start, steps: check_iterate_functions(
            at, m, sets["initial"], sets["unsafe"], start, steps, goal))
    except NotTaken as exc:
        return False, str(exc)
    except (KeyError, TypeError, ValueError, ZeroDivisionError, AttributeError, IndexError) as exc:
        return False, f"malformed refutation: {exc}"
    return (True, f"at a value of the box: {why}") if ok else (False, f"at the stated value of the box: {why}")


__all__ = ["model_at", "refute", "verify_refutation"]
