"""``barrier`` and ``reach_avoid`` of a polynomial discrete-time map over a box of parameters: the refutation at
one value of the box, and its re-check.

Over a box (``certify --box``) the map's ring holds the states, then the box's parameters normalized to
``u in [-1, 1]`` (:func:`~lyapcheck.models.classes.discrete_lyapunov.map_polynomials`). The certificates are
the point classes' (:mod:`lyapcheck.models.classes.discrete_safety`) with ``B`` (``V``) of the states alone, one
for every value of the box, and box multipliers ``r_j (1 - u_j^2)`` in the step (goal) identities, checked
exactly there.

A claim for every value of the box is false as soon as it is false at one value. Before the search, the point
route's falsification (:func:`~lyapcheck.models.classes.discrete_safety.falsify_map`) runs at each corner of the
box, then at its centre (:func:`~lyapcheck.models.classes.discrete_linearization.box_points`): the map at that
value (exact rationals), iterated in floating point from starts in the initial set, and an unsafe iterate
re-derived exactly (the start in rationals, the iterates in ball arithmetic,
:func:`~lyapcheck.models.classes.discrete_safety.check_iterate`). The first one proved makes the class
``refuted`` for the box, naming the value; ``verify`` re-derives the map at the stated value (checked to lie
in the box) and the iterate from the stated start. A value where nothing is found proves nothing about the
rest of the box.
"""

from __future__ import annotations

from fractions import Fraction
from typing import TYPE_CHECKING, Any, Callable, Final, Mapping, Sequence

from lyapcheck.results import ConditionResult
from lyapcheck.sos.polynomials import Poly, Ring

if TYPE_CHECKING:  # pragma: no cover
    from lyapcheck.models.classes.discrete_safety import Counterexample
    from lyapcheck.models.language.recast import RecastModel
    from lyapcheck.models.engines.search import Budget
    from lyapcheck.models.language.modelfile import Model
    from lyapcheck.models.language.parameter_box import ModelBox
    from lyapcheck.models.loop.field import ShiftedField

#: the most values of a box the falsification visits (its corners then its centre, in that order): 2^k corners
#: grow with the box's parameters, and each value costs one falsification of the map
MAX_BOX_POINTS: Final = 17

Pieces = Sequence[Sequence[Poly]]


def map_at(ring: Ring, F: Sequence[Poly], box: "ModelBox", point: Mapping[str, Fraction]
           ) -> tuple[Ring, tuple[Poly, ...]]:
    """The map at one value of the box (``point``, by parameter name), exactly, in the ring of the states
    alone: each normalized parameter ``u = (p - centre) / half`` substituted."""
    n = len(F)
    states = Ring(ring.names[:n])
    at = {name: ((point[name] - box.center(name)) / box.half(name) if box.half(name) else Fraction(0))
          for name in box.names}
    return states, tuple(ring.restrict(ring.substitute(fi, at), states) for fi in F)


def refute(name: str, model: "Model", ring: Ring, F: Sequence[Poly], box: "ModelBox") -> ConditionResult | None:
    """``refuted`` for the box when the falsification finds an unsafe iterate proved at one of its corners or
    its centre (reach_avoid: before any iterate is in the goal), naming the value; None when none is found."""
    from lyapcheck.models.classes.discrete_safety import falsify_map, map_sets

    def at(point: Mapping[str, Fraction]) -> "Counterexample | None":
        states, F_at = map_at(ring, F, box, point)
        sets = map_sets(model, states)
        goal = sets["goal"][0] if name == "reach_avoid" else None
        return falsify_map(model, states, F_at, sets["initial"], sets["unsafe"], goal)

    return refute_at_points(name, model, box, at)


def refute_at_points(name: str, model: "Model | RecastModel", box: "ModelBox",
                     falsify_at: Callable[[Mapping[str, Fraction]], "Counterexample | None"]) -> ConditionResult | None:
    """``refuted`` for the box at the first of its corners, then its centre (at most :data:`MAX_BOX_POINTS`
    values), where ``falsify_at`` proves an unsafe iterate (reach_avoid: before any iterate is in the goal), the
    value named (``point``, ``parameter_box``); None when none is found. A polynomial map's (:func:`refute`) and
    a map with functions' (:func:`lyapcheck.models.classes.map_relations_safety_box.refute`)."""
    from lyapcheck.models.classes.discrete_linearization import box_point_sentence, box_points
    from lyapcheck.models.classes.discrete_safety import refuted_result

    points = box_points(box)
    for point in points[:-1][:MAX_BOX_POINTS - 1] + points[-1:]:  # (the centre is always visited)
        found = falsify_at(point)
        if found is None:
            continue
        result = refuted_result(name, model, found, " before any iterate is in the goal" if name == "reach_avoid"
                                else "")
        result.summary = box_point_sentence(point, result.summary)
        assert result.refutation is not None
        result.refutation["point"] = {k: str(v) for k, v in point.items()}
        result.refutation["parameter_box"] = box.to_json()
        return result
    return None


def run(name: str, model: "Model", shifted: "ShiftedField", budget: "Budget") -> ConditionResult:
    """``barrier`` or ``reach_avoid`` of the map over its box: :func:`refute` first, then the point class's search
    (:func:`~lyapcheck.models.classes.discrete_safety.run_barrier`,
    :func:`~lyapcheck.models.classes.discrete_safety.run_reach_avoid`, one certificate for every value of the
    box). Where the class is not taken (no sets, not a polynomial map, ...) the point class says why."""
    from lyapcheck.models.classes import discrete_safety as ds
    from lyapcheck.models.classes.discrete_lyapunov import NotAMap, map_polynomials

    decide = ds.run_barrier if name == "barrier" else ds.run_reach_avoid
    assert shifted.box is not None
    if ds.no_sets(name, model) is None and not (name == "reach_avoid" and (model.stay_in_goal
                                                                           or len(model.sets["goal"]) != 1)):
        try:
            ring, F = map_polynomials(shifted)
        except NotAMap:
            return decide(model, shifted, budget)  # (its not_applicable sentence)
        refuted = refute(name, model, ring, F, shifted.box)
        if refuted is not None:
            return refuted
    return decide(model, shifted, budget)


def verify(shifted: "ShiftedField", name: str, c: Mapping[str, Any], model: "Model") -> tuple[bool, str]:
    """Re-check a map's ``barrier`` or ``reach_avoid`` over its box: a certificate by the point class's check
    (:func:`lyapcheck.models.classes.discrete_safety.verify`, the box's multipliers and ``parameter_box``
    included), a refutation by :func:`verify_refutation`."""
    from lyapcheck.models.classes import discrete_safety as ds
    from lyapcheck.models.classes.discrete_lyapunov import NotAMap, map_polynomials

    if c.get("status") != "refuted":
        return ds.verify(shifted, name, c, model)
    prop = {"barrier": "safety", "reach_avoid": "reach_avoid"}.get(name)
    if prop is None or c.get("property") != prop:
        return False, f"a refuted {name} over a box is not a claim about {c.get('property')}"
    if ds.no_sets(name, model) is not None:
        return False, f"the model has no [sets] for {name}"
    if name == "reach_avoid" and (model.stay_in_goal or len(model.sets["goal"]) != 1):
        return False, "a map's reach_avoid takes a goal of one piece and no stay_in_goal"
    assert shifted.box is not None
    try:
        ring, F = map_polynomials(shifted)
        return verify_refutation(name, model, ring, F, shifted.box, c)
    except (KeyError, TypeError, ValueError, ZeroDivisionError, AttributeError, IndexError, NotAMap) as exc:
        return False, f"malformed refutation: {exc}"


def stated_point(box: "ModelBox", c: Mapping[str, Any]) -> tuple[dict[str, Fraction] | None, str]:
    """A refutation's value of the box (:func:`refute`), checked: the stated box the document's, every parameter
    named, exact and in the box, and the sentence naming it; None and why not otherwise."""
    from lyapcheck.models.classes.discrete_linearization import box_point_sentence, stated_box_point

    data = c["refutation"]
    if data.get("parameter_box") != box.to_json():
        return None, "the refutation's parameter_box is not the document's box"
    point = stated_box_point(data, box)
    if isinstance(point, str):
        return None, point
    head = box_point_sentence(point, "")
    if not str(c.get("summary", "")).startswith(head):
        return None, f"the refutation's sentence does not name its value of the box ({head.rstrip(', ')})"
    return point, ""


def verify_refutation(name: str, model: "Model", ring: Ring, F: Sequence[Poly], box: "ModelBox",
                      c: Mapping[str, Any]) -> tuple[bool, str]:
    """Re-check a refutation of :func:`refute`: the stated value in the box (every parameter named, exact), the
    stated box the document's, then the point route's check of the start and its iterate on the map at that
    value (:func:`~lyapcheck.models.classes.discrete_safety.check_iterate`); the sentence must name that value."""
    from lyapcheck.models.classes.discrete_safety import check_iterate, map_sets
    from lyapcheck.models.classes.discrete_safety import verify_refutation as verify_start

    point, why = stated_point(box, c)
    if point is None:
        return False, why
    states, F_at = map_at(ring, F, box, point)
    sets = map_sets(model, states)
    goal = sets["goal"][0] if name == "reach_avoid" else None
    ok, why = verify_start(model, c, lambda start, steps: check_iterate(states, F_at, sets["initial"],
                                                                        sets["unsafe"], start, steps, goal))
    return (True, f"at a value of the box: {why}") if ok else (False, f"at the stated value of the box: {why}")


__all__ = ["MAX_BOX_POINTS", "map_at", "refute", "refute_at_points", "run", "verify", "stated_point",
           "verify_refutation"]
