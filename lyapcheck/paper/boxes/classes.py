"""The box classes, one dispatch: certify or re-check a class for every gain set of a box.

Statuses of a box: ``certified`` (for every point), ``not_certified`` (no common certificate
found), ``refuted`` (a class's own condition is proved impossible at a point of the box: the
paper's eq. ``stabCond`` by the exact ``Gamma_22`` bound, ``sector_ges`` by Shorten-Narendra), and
in :func:`refine` a box that is not certified is split until its relative width is below the
given minimum. Each class lives in its own module (:data:`BOX_CLASSES`).
"""

from __future__ import annotations

from dataclasses import dataclass
from fractions import Fraction
from typing import Any, Mapping

from lyapcheck.errors import InvalidParameter
from lyapcheck.paper.boxes.box import ParameterBox, problem_at_point
from lyapcheck.paper.params import Problem
from lyapcheck.paper.system import build_system


#: classes with box certificates, in the order of :data:`lyapcheck.paper.certification.CONDITION_ORDER`:
#: ``prop41_*`` (:mod:`lyapcheck.paper.boxes.prop41`), ``sector_ges`` and ``ges`` (here), ``ultimate_bound``
#: (:mod:`lyapcheck.paper.boxes.ultimate`), ``sos_gas`` (:mod:`lyapcheck.paper.boxes.sos_gas`), ``saturated_loop``
#: (:mod:`lyapcheck.paper.boxes.saturated`) and ``sos_bound`` (:mod:`lyapcheck.paper.boxes.bounds`, 5-10 s a box)
BOX_CLASSES: tuple[str, ...] = ("prop41_ges", "prop41_iss", "sector_ges", "ultimate_bound", "sos_gas", "ges",
                                "saturated_loop", "sos_bound")


#: the classes whose certificate proves stability (GES, ISS or GAS): a box's verdict
BOX_STABILITY_CLASSES: tuple[str, ...] = ("prop41_ges", "prop41_iss", "sector_ges", "sos_gas", "ges")


#: run by ``certify --box`` unless ``--classes`` says otherwise (the cheap ones: well under a second)
DEFAULT_BOX_CLASSES: tuple[str, ...] = ("prop41_ges", "prop41_iss", "sector_ges", "ges")


def _class_functions(cls: str) -> tuple[Any, Any]:
    """``(certify(problem, box, dynamics), verify(problem, box, dynamics, result))`` of a box class."""
    from functools import partial

    if cls in ("prop41_ges", "prop41_iss"):
        from lyapcheck.paper.boxes.prop41 import certify_prop41_box, verify_prop41_box

        iss = cls == "prop41_iss"
        return partial(certify_prop41_box, iss=iss), partial(verify_prop41_box, iss=iss)
    if cls == "ultimate_bound":
        from lyapcheck.paper.boxes.ultimate import certify_ultimate_box, verify_ultimate_box

        return certify_ultimate_box, verify_ultimate_box
    if cls == "sos_gas":
        from lyapcheck.paper.boxes.sos_gas import certify_gas_box, verify_gas_box

        return certify_gas_box, verify_gas_box
    if cls == "saturated_loop":
        from lyapcheck.paper.boxes.saturated import certify_saturated_box, verify_saturated_box

        return certify_saturated_box, verify_saturated_box
    if cls == "sos_bound":
        from lyapcheck.paper.boxes.bounds import certify_bound_box, verify_bound_box

        return certify_bound_box, verify_bound_box
    from lyapcheck.paper.boxes.quadratic import certify_ges_box, certify_sector_box, verify_ges_box, verify_sector_box

    return {"sector_ges": (certify_sector_box, verify_sector_box),
            "ges": (certify_ges_box, verify_ges_box)}[cls]


def certify_box(problem: Problem, box: ParameterBox, dynamics: str = "derived", cls: str = "ges") -> dict[str, Any]:
    """Class ``cls`` (:data:`BOX_CLASSES`) for every gain set in ``box``; a JSON-ready result."""
    if cls not in BOX_CLASSES:
        raise InvalidParameter("classes", "box classes among " + ", ".join(BOX_CLASSES), cls)
    certify, _ = _class_functions(cls)
    try:
        result: dict[str, Any] = certify(problem, box, dynamics)
    except OverflowError:
        # the corners are exact, but the searches work in doubles: a box whose corners combine
        # into figures beyond 1.8e308 gets no search (claiming nothing is always sound)
        from lyapcheck.results import PROPERTY

        return {"status": "not_certified", "property": PROPERTY[cls], "box": box.to_json(),
                "summary": f"the box's data leave the double range ({box.describe()}): no search was run "
                           "(a narrower box may fit)"}
    return result


def verify_box(problem: Problem, box: ParameterBox, dynamics: str, result: Mapping[str, Any],
               cls: str = "ges") -> tuple[bool, str]:
    """Re-check a box certificate of class ``cls`` exactly (no solver)."""
    if cls not in BOX_CLASSES:
        return False, f"'{cls}' has no box certificates"
    _, verify = _class_functions(cls)
    checked: tuple[bool, str] = verify(problem, box, dynamics, result)
    return checked


def verify_box_refutation(problem: Problem, box: ParameterBox, dynamics: str, result: Mapping[str, Any],
                          cls: str) -> tuple[bool, str]:
    """Re-check a box's refutation: its point lies in the box and is refuted there, exactly."""
    from lyapcheck import exact
    from lyapcheck.paper.conditions import sector
    from lyapcheck.paper.conditions.sos import scaled_dynamics

    if cls not in ("sector_ges", "prop41_ges", "prop41_iss"):
        return False, f"'{cls}' has no box refutations"
    point = {name: Fraction(value) for name, value in result["refutation"]["point"].items()}
    bounds = {name: (lo, hi) for name, lo, hi in box.bounds}
    if set(point) != set(bounds) or any(not bounds[n][0] <= x <= bounds[n][1] for n, x in point.items()):
        return False, "the refuting point is not a point of the box"
    if cls != "sector_ges":
        from lyapcheck.paper.boxes.prop41 import verify_prop41_refutation

        return verify_prop41_refutation(problem, point, dynamics, result["refutation"])
    v = scaled_dynamics(build_system(problem_at_point(problem, point), dynamics))
    if v is None:
        return False, "the dynamics at the refuting point do not have the structure this class needs"
    refuted = sector.refutation([exact.matrix([[-1, v.c], [0, -v.a]]), exact.matrix([[-1, v.c], [v.b, -v.a]])])
    if refuted is None:
        return False, "the stated point is not refuted (Shorten-Narendra does not apply there)"
    if any(result["refutation"].get(key) != value for key, value in refuted.items()):
        return False, "the stated A0A1, A0A1inv or statement are not those re-derived at the point"
    return True, f"refuted at a point of the box: {refuted['statement']}"


@dataclass(frozen=True)
class BoxOutcome:
    box: ParameterBox
    status: str
    result: dict[str, Any]


def refine(problem: Problem, box: ParameterBox, *, min_relative_width: float, dynamics: str = "derived",
           max_boxes: int = 256) -> list[BoxOutcome]:
    """Certify ``box``; split what is not certified until its relative width is below the minimum.

    Returns the leaves: ``certified`` boxes (each with its own exact certificate) and
    ``not_certified`` boxes that reached the minimum width (or the ``max_boxes`` budget).
    """
    if not (min_relative_width > 0):
        raise InvalidParameter("min_relative_width", "a number > 0", min_relative_width)
    todo: list[ParameterBox] = [box]
    leaves: list[BoxOutcome] = []
    while todo:
        current = todo.pop(0)
        result = certify_box(problem, current, dynamics)
        if result["status"] == "certified" or current.relative_width() <= min_relative_width \
                or len(leaves) + len(todo) + 2 > max_boxes:
            leaves.append(BoxOutcome(current, result["status"], result))
        else:
            todo.extend(current.split())
    return leaves
