"""``roa`` of a polynomial or rational loop by ball arithmetic: the loop as a recast loop with no
auxiliaries, the ball-arithmetic route on it, and the larger of that route's set and the SOS route's
(issue 41: "the ball-arithmetic region of attraction, the strongest route on small loops, is never
tried on a polynomial loop").

A polynomial or rational model file's ``[dynamics]``, read by the recasting's own parser
(:func:`lyapcheck.models.language.recast.recast_dynamics`), is a recast loop whose ring holds the states
alone (:func:`as_recast`, :func:`field_loop`): no function, so no auxiliary and no relation; a
rational field's denominators stay in its flows, as on a loop with functions, and ball arithmetic
evaluates the true field (a cell where a denominator may vanish is simply not proved). The route
(:func:`ball_region`) is the recast route's, unchanged: a ``V`` fitted to simulations of the true
loop, proved by python-flint's ``arb`` balls
(:func:`lyapcheck.models.classes.recast_interval.interval_roa`), the whole sublevel set proved to lie
in the proof's box (a polynomial ``roa`` states ``{V <= level}``), boxes of a ``[domain]`` proved to
flow into it (:func:`lyapcheck.models.classes.flow_region.extend`, 2 states), and the set simulated on
the true loop (:func:`lyapcheck.models.classes.recast_regions.simulated_check`).

Two callers: :func:`lyapcheck.models.classes.field_regions.run_roa`, where the SOS route certified a
set on a nominal loop of 1 to 3 states (:func:`larger_region`: the set covering more of the
simulated region of attraction is kept, the SOS set on a tie or whenever the ball route proves
less), and :mod:`lyapcheck.models.surfaces.ball_roa`, where the SOS route did not certify.
"""

from __future__ import annotations

import tomllib
from fractions import Fraction
from typing import TYPE_CHECKING, Any, Final

from lyapcheck.models.engines.search import Budget, BudgetExhausted
from lyapcheck.results import ConditionResult
from lyapcheck.timing import ClassTimeLimit
from lyapcheck.tolerances import (BALL_FALLBACK_FIT_STEPS, BALL_ROUTE_BESIDE_SHARE, BALL_ROUTE_MIN_SECONDS,
                                  INTERVAL_ATTEMPT_CELLS)

if TYPE_CHECKING:  # pragma: no cover
    import numpy as np

    from lyapcheck.models.classes.recast_classes import Loop
    from lyapcheck.models.language.modelfile import Model
    from lyapcheck.models.language.recast import RecastModel

#: the condition's ``engine`` (and ``route``) where the ball-arithmetic route proved the region
ENGINE: Final = "ball_arithmetic"
#: the condition's ``route`` where the SOS route's set was kept
SOS_ROUTE: Final = "sos"
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


def field_loop(model: "Model", time_limit_s: float) -> tuple["RecastModel", "Loop"]:
    """The model as a recast model (:func:`as_recast`) and its :class:`~lyapcheck.models.classes.recast_classes.Loop`
    in deviations (no auxiliary, so no square root's bound to prove: ``time_limit_s`` is never spent)."""
    from lyapcheck.models.classes.recast_regions import proved_loop

    recast = as_recast(model)
    return recast, proved_loop(recast, time_limit_s)


def ball_region(model: "Model", budget: Budget) -> tuple["Loop", ConditionResult | str]:
    """The ball-arithmetic region of attraction of the loop (with its disturbances: for every value of
    them first, :func:`~lyapcheck.models.classes.recast_regions.robust_of`), or why there is none (one line):
    a certified set is the whole sublevel set ``{V <= level}`` (``whole``), with a ``[domain]`` enlarged
    by boxes proved to flow into it, and simulated on the true loop; its numbers carry ``engine`` and
    ``degree``. Each trajectory simulated (the fit, the check) takes at most
    :data:`~lyapcheck.tolerances.BALL_FALLBACK_FIT_STEPS` steps (a rational loop's runs into a pole crawl)."""
    import time

    from lyapcheck.models.classes.recast_interval import claim_of, interval_roa
    from lyapcheck.models.classes.recast_regions import comparison_box, robust_of, simulated_check
    from lyapcheck.models.engines.interval_region import prove_bounded

    recast, loop = field_loop(model, budget.seconds)
    box = comparison_box(recast, loop)
    found = interval_roa(loop, budget, box, robust_of(recast), fit_steps=BALL_FALLBACK_FIT_STEPS)
    if isinstance(found, str):
        return loop, found
    if not found.certificate.get("whole"):
        # the whole set, with the work budget of an attempt (the certificate's own try had fewer cells)
        whole, why, cells, R = prove_bounded(loop.system, claim_of(loop, found.certificate),
                                             deadline=time.perf_counter() + max(budget.left(), 0.0),
                                             cell_limit=WHOLE_SET_CELLS)
        if not whole:
            return loop, (f"ball arithmetic: level {found.numbers['level']:.6g} was proved within a box, not the "
                          f"whole sublevel set {{V <= level}} that a polynomial loop's region states ({why}, within "
                          f"{WHOLE_SET_CELLS} cells)")
        found.certificate.update({"whole": True, "outer_radius": str(R), "outer_cells": cells})
    if recast.domain is not None:  # boxes of the domain proved to flow into the set (the region only grows)
        from lyapcheck.models.classes.flow_region import extend
        from lyapcheck.models.classes.recast_regions import certified_value

        extend(loop, found, budget, box, certified_value(loop, found)[0])
    simulated_check(loop, found, box, max_steps=BALL_FALLBACK_FIT_STEPS)
    terms = found.certificate["V"]["terms"]
    found.numbers.update({"engine": ENGINE, "degree": max(sum(e[:model.n]) for _, e in terms)})
    return loop, found


def takes(model: "Model", nominal: bool) -> bool:
    """Whether :func:`larger_region` tries the ball route: 1 to 3 states, no box of parameters and no
    disturbances (a robust field stays with the SOS route), ``nominal`` (the field the SOS route ran on
    has the disturbances at 0)."""
    return nominal and model.n in BALL_STATES and not model.disturbances


def larger_region(model: "Model", sos: ConditionResult, budget: Budget, starts: "np.ndarray",
                  converged: "np.ndarray") -> ConditionResult:
    """Of the SOS route's certified set ``sos`` and the ball route's (:func:`ball_region`), the one
    covering more of the simulated region of attraction: the share of the converging simulated starts
    (``starts``, declared states, rows; ``converged``: which converged, the SOS route's own simulation)
    in each set; where none converged, the larger ball ``|x - x_eq| <= r`` each set is proved to hold
    (:mod:`lyapcheck.models.classes.region_size`). The SOS set is kept on a tie and whenever the ball
    route proves less or nothing, so a loop only gains. The kept condition says ``route`` and, in
    ``other_route``, the other route's figures (or why it proved none or was not tried: a model without
    a ``[domain]``, an SOS set holding :data:`~lyapcheck.tolerances.BALL_ROUTE_BESIDE_SHARE` of the
    simulated region); the ball route is skipped, saying so in ``tried``, where less than
    :data:`~lyapcheck.tolerances.BALL_ROUTE_MIN_SECONDS` of the class's budget is left."""
    import numpy as np

    sos.numbers["route"] = SOS_ROUTE
    if not model.domain:  # (no simulated region to compare the two sets by)
        sos.numbers["other_route"] = "ball arithmetic: not tried beside a certified SOS set without a [domain]"
        return sos
    share = sos.numbers.get("roa_share")
    if share is not None and share >= BALL_ROUTE_BESIDE_SHARE:  # (little left to gain for its cost)
        sos.numbers["other_route"] = (f"ball arithmetic: not tried, the SOS set holds {100 * share:.4g} % of the "
                                      "converging simulated starts (lyapcheck.tolerances.BALL_ROUTE_BESIDE_SHARE = "
                                      f"{BALL_ROUTE_BESIDE_SHARE:g})")
        return sos
    left = budget.left()
    if left < BALL_ROUTE_MIN_SECONDS:
        sos.numbers.setdefault("tried", []).append(
            f"ball arithmetic: not tried, {max(left, 0.0):.0f} s of the class's time limit left (it takes "
            f"lyapcheck.tolerances.BALL_ROUTE_MIN_SECONDS = {BALL_ROUTE_MIN_SECONDS:g} s)")
        return sos
    try:
        loop, found = ball_region(model, budget)
    except (ClassTimeLimit, BudgetExhausted) as exc:  # (the hard stop may end this route, never the SOS set)
        sos.numbers["other_route"] = f"ball arithmetic: stopped ({exc or type(exc).__name__})"
        return sos
    if isinstance(found, str):
        sos.numbers["other_route"] = found
        return sos
    from lyapcheck.models.classes.flow_region import in_boxes
    from lyapcheck.models.classes.recast_regions import certified_value
    from lyapcheck.models.classes.region_size import condition_size

    cert = found.certificate
    eq = np.array([float(v) for v in model.equilibrium])
    inside = certified_value(loop, found)[0](starts) <= float(Fraction(cert["level"]))
    if "flow" in cert:
        inside |= in_boxes(cert, model.states, starts - eq)
    # each set's ball by the one exact method (region_size), the figure certify then states for either
    radii = [condition_size(c, model.states, ()).ball_radius for c in (cert, sos.certificate)]
    ball: dict[str, Any] = {"route": ENGINE, "level": found.numbers["level"],
                            "ball_radius": None if radii[0] is None else float(radii[0])}
    mine: dict[str, Any] = {"route": SOS_ROUTE, "level": sos.numbers.get("level"),
                            "ball_radius": None if radii[1] is None else float(radii[1])}
    if converged.any():  # (model.domain is given: the route is not tried without one)
        ball["roa_share"] = float(np.mean(inside[converged]))
        mine["roa_share"] = sos.numbers.get("roa_share")
        gains = mine["roa_share"] is None or ball["roa_share"] > mine["roa_share"]
    else:  # no converging start to share: the larger ball each set is proved to hold
        gains = ball["ball_radius"] is not None and ball["ball_radius"] > (mine["ball_radius"] or 0.0)
    if not gains:
        sos.numbers["other_route"] = ball
        return sos
    from lyapcheck.models.classes.claims import interval_sentence

    found.summary = interval_sentence(cert)
    if "roa_share" in ball:  # the kept set's share over the same starts as the SOS route's figures
        found.numbers.update({"roa_share": ball["roa_share"], "simulated_starts": int(len(starts)),
                              "simulated_roa_share_of_domain": sos.numbers.get("simulated_roa_share_of_domain")})
        found.numbers.pop("simulated_roa_share_of_box", None)
    found.numbers.update({"route": ENGINE, "other_route": mine,
                          "tried": [f"sums of squares: {sos.summary}", *found.numbers.get("tried", [])]})
    return found


__all__ = ["ENGINE", "SOS_ROUTE", "BALL_STATES", "WHOLE_SET_CELLS", "as_recast", "field_loop", "ball_region", "takes",
           "larger_region"]
