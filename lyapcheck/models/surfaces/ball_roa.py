"""``roa`` of a polynomial or rational loop by ball arithmetic: the recast route's engine on the
loop read as a loop with no auxiliaries (issue 41).

A polynomial or rational model file's ``[dynamics]``, read by the recasting's own parser
(:func:`lyapcheck.models.language.recast.recast_dynamics`), is a recast loop whose ring holds the states
alone: no function, so no auxiliary and no relation. The ball-arithmetic region of attraction of
loops with functions (:func:`lyapcheck.models.classes.recast_interval.interval_roa`: a ``V`` fitted to
simulations, proved on the true field with python-flint's ``arb`` balls, within the work budget
:data:`~lyapcheck.tolerances.INTERVAL_ATTEMPT_CELLS`) then runs on it unchanged, and so does its
exact re-check (:func:`lyapcheck.models.classes.recast_interval.check_interval`). The sum-of-squares route
and the ball-arithmetic route are two engines of one class:

===================  ================================  ==============================================
engine               when                              what a ``certified`` proves
===================  ================================  ==============================================
``sos``              always first, on the field        ``{V <= level}`` (SOS multipliers, exact check)
                     multiplied through its
                     denominators
``ball_arithmetic``  1 to 3 states, no box, a Hurwitz  ``{V <= level}``, the whole sublevel set
                     Jacobian, where the SOS route     (``whole``: ``V > level`` outside the proof's
                     did not certify                   box, ``V' < 0`` on the set but at the
                                                       equilibrium), on the true field
===================  ================================  ==============================================

The ball route is a fallback: where the SOS route certifies, its figures stand as before. It is
not tried where the SOS route stopped at the class's time limit (the time is spent), only where
it ended ``not_certified``, ``inconclusive`` on a work budget or numerical trouble, or
``not_applicable`` because a denominator of the field is not proved of one sign (the field cannot
be multiplied through; ball arithmetic evaluates the true field, and a cell where a denominator may
vanish is simply not proved). It has a time budget of its own, the class's limit again. A region it
proves is taken only when the whole sublevel set is proved to lie in its box, so that the claim is
``{V <= level}`` as every polynomial ``roa`` states it (reports draw that set, sweeps simulate
from it). The condition says which engine proved it: ``engine`` = ``"ball_arithmetic"`` (the SOS
route's conditions carry no ``engine`` key, so that their documents stay as they were); its
sentence is the recast route's (:func:`lyapcheck.models.classes.claims.interval_sentence`).
"""

from __future__ import annotations

import tomllib
from fractions import Fraction
from typing import TYPE_CHECKING, Any, Callable, Final

from lyapcheck.models.engines.search import Budget, BudgetExhausted, SolvesSpent
from lyapcheck.results import ConditionResult
from lyapcheck.timing import ClassTimeLimit
from lyapcheck.tolerances import BALL_FALLBACK_FIT_STEPS, INTERVAL_ATTEMPT_CELLS

if TYPE_CHECKING:  # pragma: no cover
    from lyapcheck.models.language.modelfile import Model
    from lyapcheck.models.language.parameter_box import ModelBox
    from lyapcheck.models.language.recast import RecastModel

#: the condition's ``engine`` where the ball-arithmetic route proved the region
ENGINE: Final = "ball_arithmetic"
#: the numbers of states the ball route takes (its sampling grids: lyapcheck.models.classes.fitted_v.FIT_GRID)
BALL_STATES: Final = (1, 2, 3)
#: the cells the proof that the whole sublevel set lies in the box may take, where the certificate's
#: own try (WHOLE_SET_CELL_LIMIT) did not go through: a polynomial loop's region is that whole set.
#: A count, the work budget of one attempt of the region's proof, so the outcome is the same anywhere
WHOLE_SET_CELLS: Final = INTERVAL_ATTEMPT_CELLS


def as_recast(model: "Model") -> "RecastModel":
    """The polynomial or rational loop as a loop with functions that has none: its ``[dynamics]``
    texts recast at the model's parameter values (``model.parameters``, which a sweep may have
    replaced), every disturbance at 0; and, with disturbances, the loop with them as its last
    states without a flow (:attr:`~lyapcheck.models.language.recast.RecastModel.robust`), as
    :mod:`lyapcheck.models.language.modelfile` reads a loop with functions."""
    from lyapcheck.errors import ModelFileError
    from lyapcheck.models.language.recast import RecastModel, recast_dynamics

    table = tomllib.loads(model.text)["dynamics"]
    texts = {s: table[s] for s in model.states}
    zero = {d: Fraction(0) for d in model.disturbances}
    system, _ = recast_dynamics(model.source, model.states, texts, {**model.parameters, **zero}, model.equilibrium)
    robust = None
    if model.disturbances:
        try:
            robust, _ = recast_dynamics(model.source, model.states + tuple(model.disturbances),
                                        {**texts, **{d: "0" for d in model.disturbances}}, dict(model.parameters),
                                        tuple(model.equilibrium) + (Fraction(0),) * len(model.disturbances))
        except ModelFileError:  # (a disturbance the recasting cannot keep: claims with it at 0 only)
            robust = None
    return RecastModel(source=model.source, text=model.text, name=model.name, origin=model.origin,
                       states=model.states, parameters=dict(model.parameters), equilibrium=model.equilibrium,
                       domain=model.domain, system=system, overrides=dict(model.overrides),
                       disturbances=dict(model.disturbances), robust=robust)


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
    from lyapcheck.models.classes.claims import covered
    from lyapcheck.models.engines.interval_region import prove_bounded
    from lyapcheck.models.classes.claims import interval_sentence
    from lyapcheck.models.classes.recast_interval import METHOD, claim_of, interval_roa
    from lyapcheck.models.classes.recast_regions import comparison_box, proved_loop, robust_of, simulated_check

    recast = as_recast(model)
    loop = proved_loop(recast, budget.seconds)  # (no square root to prove: the loop has no auxiliary)
    box = comparison_box(recast, loop)
    found = interval_roa(loop, budget, box, robust_of(recast), fit_steps=BALL_FALLBACK_FIT_STEPS)
    if isinstance(found, ConditionResult) and not found.certificate.get("whole"):
        import time

        # the whole set, with the work budget of an attempt (the certificate's own try had fewer cells)
        whole, why, cells, R = prove_bounded(loop.system, claim_of(loop, found.certificate),
                                             deadline=time.perf_counter() + max(budget.left(), 0.0),
                                             cell_limit=WHOLE_SET_CELLS)
        if whole:
            found.certificate.update({"whole": True, "outer_radius": str(R), "outer_cells": cells})
        else:
            found = (f"ball arithmetic: level {found.numbers['level']:.6g} was proved within a box, not the whole "
                     f"sublevel set {{V <= level}} that a polynomial loop's region states ({why}, within "
                     f"{WHOLE_SET_CELLS} cells)")
    if isinstance(found, str):
        head, sep, advice = sos.summary.partition("; try ")
        if sos.status == "not_applicable":
            sos.status = "not_certified"
            head = f"no region of attraction was proved: the SOS route does not apply ({head})"
        sos.summary = f"{head}; nor was one proved by {METHOD}{sep}{advice}"
        sos.numbers["detail"] = [*sos.numbers.get("detail", []), found]
        return sos
    if recast.domain is not None:  # boxes of the domain proved to flow into the set (the region only grows)
        from lyapcheck.models.classes.flow_region import extend
        from lyapcheck.models.classes.recast_regions import certified_value

        extend(loop, found, budget, box, certified_value(loop, found)[0])
    simulated_check(loop, found, box, max_steps=BALL_FALLBACK_FIT_STEPS)
    if found.disturbances is None and model.disturbances:
        found.disturbances = "zero"  # proved on the loop with its disturbances at 0
    # the recast route's sentence, from the certificate as it now stands (whole), with the coverage
    found.summary = covered(found.disturbances, interval_sentence(found.certificate))
    V = found.certificate["V"]["terms"]
    found.numbers.update({"engine": ENGINE, "degree": max(sum(e[:model.n]) for _, e in V),
                          "tried": [f"sums of squares: {sos.summary}", *found.numbers.get("tried", [])]})
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


__all__ = ["ENGINE", "BALL_STATES", "as_recast", "recording", "sos_ended", "takes", "after_sos", "is_ball_region", "verify_ball_roa"]
