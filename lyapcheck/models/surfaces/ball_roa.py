"""``roa`` of a polynomial or rational loop by ball arithmetic: the recast route's engine on the
loop read as a loop with no auxiliaries (issue 41).

The loop read as a loop with no auxiliaries and the route on it are
:mod:`lyapcheck.models.classes.field_ball_route`'s (:func:`~lyapcheck.models.classes.field_ball_route.as_recast`,
:func:`~lyapcheck.models.classes.field_ball_route.ball_region`); the exact re-check is the recast route's
(:func:`lyapcheck.models.classes.recast_interval.check_interval`). The sum-of-squares route and the
ball-arithmetic route are two engines of one class:

===================  ================================  ==============================================
engine               when                              what a ``certified`` proves
===================  ================================  ==============================================
``sos``              always first, on the field        ``{V <= level}`` (SOS multipliers, exact check)
                     multiplied through its
                     denominators
``ball_arithmetic``  1 to 3 states, no box, a Hurwitz  ``{V <= level}``, the whole sublevel set
                     Jacobian: where the SOS route     (``whole``: ``V > level`` outside the proof's
                     did not certify (here), and on a  box, ``V' < 0`` on the set but at the
                     nominal loop beside a certified   equilibrium), on the true field
                     SOS set, the larger kept
                     (field_ball_route.larger_region)
===================  ================================  ==============================================

Here, where the SOS route did not certify: the ball route is not tried where the SOS route stopped
at the class's time limit (the time is spent), only where it ended ``not_certified``,
``inconclusive`` on a work budget or numerical trouble, or ``not_applicable`` because a denominator
of the field is not proved of one sign (the field cannot be multiplied through; ball arithmetic
evaluates the true field, and a cell where a denominator may vanish is simply not proved). It has a
time budget of its own, the class's limit again. A region it proves is taken only when the whole
sublevel set is proved to lie in its box, so that the claim is ``{V <= level}`` as every polynomial
``roa`` states it (reports draw that set, sweeps simulate from it). The condition says which engine
proved it: ``engine`` = ``"ball_arithmetic"`` (the SOS route's conditions carry no ``engine`` key);
its sentence is the recast route's (:func:`lyapcheck.models.classes.claims.interval_sentence`).
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any, Callable

from lyapcheck.models.classes.field_ball_route import BALL_STATES, ENGINE, WHOLE_SET_CELLS, as_recast, ball_region
from lyapcheck.models.engines.search import Budget, BudgetExhausted, SolvesSpent
from lyapcheck.results import ConditionResult
from lyapcheck.timing import ClassTimeLimit

if TYPE_CHECKING:  # pragma: no cover
    from lyapcheck.models.language.modelfile import Model
    from lyapcheck.models.language.parameter_box import ModelBox


def recording(compute: Callable[[Budget], ConditionResult], stopped: list[BaseException]
              ) -> Callable[[Budget], ConditionResult]:
    """``compute``, noting in ``stopped`` what ended it when it raises (the class's guard then makes
    its ``inconclusive``), or when it returns ``inconclusive`` with the class's time spent (the region
    classes' driver, :func:`lyapcheck.models.classes.region_driver.drive`, words the time limit itself):
    :func:`sos_ended` reads whether that was the time limit."""
    def run(budget: Budget) -> ConditionResult:
        try:
            found = compute(budget)
        except BaseException as exc:
            stopped.append(exc)
            raise
        if found.status == "inconclusive" and budget.left() <= 0:
            stopped.append(BudgetExhausted(budget.reached()))
        return found
    return run


def sos_ended(sos: ConditionResult, stopped: list[BaseException]) -> bool:
    """Whether the SOS route's ``sos`` leaves the ball route a try: it did not certify and did not
    stop at the class's time limit (a work budget of solves or numerical trouble may end it: the
    ball route has budgets of its own); ``not_applicable`` only where the field's denominators are
    not proved of one sign (:func:`lyapcheck.models.surfaces.certify.certify_model` calls it then: ball
    arithmetic evaluates the true field and needs no such proof), not after GAS."""
    timed_out = any(isinstance(e, ClassTimeLimit) or (isinstance(e, BudgetExhausted) and not isinstance(e, SolvesSpent))
                    for e in stopped)
    return sos.status in ("not_certified", "inconclusive", "not_applicable") and not timed_out


def takes(model: "Model", box: "ModelBox | None") -> bool:
    """Whether the ball route takes the loop: 1 to 3 states, no box of parameters, and a Hurwitz
    Jacobian at the equilibrium, exactly (the recast route's quadratic start: the ball route, like
    the SOS route, starts from the linearization's quadratic V)."""
    from lyapcheck.errors import ModelFileError
    from lyapcheck.models.classes.recast_classes import base_loop, jacobian, quadratic_candidate

    if box is not None or model.n not in BALL_STATES:
        return False
    try:
        loop = base_loop(as_recast(model).system)
    except ModelFileError:  # (a text the recasting's parser reads otherwise: not for this route)
        return False
    J = jacobian(loop)
    return not isinstance(J, str) and quadratic_candidate(loop, J) is not None


def after_sos(model: "Model", sos: ConditionResult, budget: Budget) -> ConditionResult:
    """The ball-arithmetic region on the loop, tried after the SOS route's ``sos`` did not certify:
    ``certified`` (the condition says ``engine``, and ``tried`` starts with the SOS route's reason),
    or ``sos`` again with its reason saying that ball arithmetic proved none either (a
    ``not_applicable`` becomes ``not_certified``: the class was tried)."""
    from lyapcheck.models.classes.claims import covered, interval_sentence
    from lyapcheck.models.classes.recast_interval import METHOD

    _, found = ball_region(model, budget)
    if isinstance(found, str):
        head, sep, advice = sos.summary.partition("; try ")
        if sos.status == "not_applicable":
            sos.status = "not_certified"
            head = f"no region of attraction was proved: the SOS route does not apply ({head})"
        sos.summary = f"{head}; nor was one proved by {METHOD}{sep}{advice}"
        sos.numbers["detail"] = [*sos.numbers.get("detail", []), found]
        return sos
    if found.disturbances is None and model.disturbances:
        found.disturbances = "zero"  # proved on the loop with its disturbances at 0
    # the recast route's sentence, from the certificate as it now stands (whole), with the coverage
    found.summary = covered(found.disturbances, interval_sentence(found.certificate))
    found.numbers["tried"] = [f"sums of squares: {sos.summary}", *found.numbers.get("tried", [])]
    return found


def is_ball_region(name: str, c: Any) -> bool:
    """A certified condition whose certificate is a ball-arithmetic region (``verify`` re-checks it
    with :func:`verify_ball_roa`, apart from the SOS certificates and their cleared field)."""
    return isinstance(c, dict) and c.get("status") == "certified" and isinstance(c.get("certificate"), dict) \
        and c["certificate"].get("kind") == "interval"


def verify_ball_roa(name: str, c: dict[str, Any], model: "Model", box: Any) -> tuple[bool, str]:
    """``verify`` of a ball-arithmetic ``roa`` of a polynomial or rational loop: the model text's loop
    recast again (no auxiliary), and the same deterministic proof run again from the certificate
    alone (:func:`lyapcheck.models.classes.recast_interval.check_interval`, which also re-makes the
    sentence), the whole set included. It needs no proof of the field's denominators: ball
    arithmetic evaluates the true field, and a cell where a denominator may vanish is not proved.
    The document's ``V_text`` follows the polynomial documents' rule, which
    :mod:`lyapcheck.models.surfaces.certificate` checks beside this; it is put in the recast form here for
    the proof's own comparison."""
    from lyapcheck.models.classes.recast_classes import v_text
    from lyapcheck.models.classes.recast_interval import check_interval
    from lyapcheck.models.classes.recast_regions import proved_loop, robust_of
    from lyapcheck.models.engines.recast_sos import poly_from_json
    from lyapcheck.tolerances import MODEL_CLASS_TIME_LIMIT_S

    cert = c["certificate"]
    if name != "roa" or c.get("engine") != ENGINE:
        return False, f"a ball-arithmetic region is a roa condition with engine {ENGINE!r}"
    if box is not None:
        return False, "over a box of parameters roa is proved by sums of squares, not by ball arithmetic"
    if cert.get("whole") is not True:
        return False, "a region of attraction of a polynomial loop is a whole sublevel set {V <= level} (whole: true)"
    recast = as_recast(model)
    loop = proved_loop(recast, MODEL_CLASS_TIME_LIMIT_S)
    V = poly_from_json(loop.ring, cert["V"], "V")
    return check_interval(loop, {**c, "certificate": {**cert, "V_text": v_text(loop.system, V)}}, robust_of(recast))


__all__ = ["ENGINE", "BALL_STATES", "WHOLE_SET_CELLS", "as_recast", "recording", "sos_ended", "takes", "after_sos",
           "is_ball_region", "verify_ball_roa"]
