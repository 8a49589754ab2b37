"""Certify one gain set: run every condition class on the chosen dynamics.

This is the library entry point behind ``lyapcheck certify``. It evaluates the structured
closed loop of :mod:`symbolic.closed_loop` exactly at the given parameters, runs the
condition classes, and assembles the certificate document (see :mod:`lyapcheck.certificate`).
"""

from __future__ import annotations

import logging
from fractions import Fraction
from typing import Any

from lyapcheck.conditions.base import STABILITY_CLASSES, ConditionResult, System
from lyapcheck.params import Problem

log = logging.getLogger(__name__)

CONDITION_ORDER = ("prop41_ges", "prop41_iss", "stabcond2", "sector_ges", "ultimate_bound", "sos_gas",
                   "saturated_loop", "sos_bound")
#: the polynomial classes cost seconds per point; everything else tens of milliseconds
QUICK_CLASSES = ("prop41_ges", "prop41_iss", "stabcond2", "sector_ges", "ultimate_bound")


def exact_values(problem: Problem) -> dict[str, Any]:
    g, sw = problem.gains, problem.swimmer
    return {"alpha_d": g.alpha_d, "sigma0": g.sigma0, "k_d": g.k_d, "delta_los": g.delta_los,
            "los_speed": g.los_speed, "e11": sw.e11, "e11_hat": sw.e11_hat}


def system_from_values(dynamics: str, values: dict[str, Any], d_max: Any) -> System:
    """Exact structured error dynamics from the code generated out of the sympy derivation."""
    from symbolic import _generated

    if dynamics not in ("derived", "printed"):
        from lyapcheck.errors import InvalidParameter

        raise InvalidParameter("dynamics", "one of 'derived', 'printed'", dynamics)
    data = getattr(_generated, dynamics)(**values)
    return System(dynamics=dynamics, A=data["A"], B=data["B"], E=data["E"], rho_sup=data["rho_sup"],
                  sigma0=values["sigma0"], delta=values["delta_los"],
                  speed=values["los_speed"] if dynamics == "derived" else Fraction(1), d_max=d_max)


def build_system(problem: Problem, dynamics: str) -> System:
    """The exact structured error dynamics at this parameter point."""
    return system_from_values(dynamics, exact_values(problem), problem.d_max)


def run_conditions(problem: Problem, dynamics: str,
                   classes: tuple[str, ...] = CONDITION_ORDER) -> dict[str, ConditionResult]:
    """Run the requested condition classes (all by default), in :data:`CONDITION_ORDER`."""
    from lyapcheck.conditions import prop41, saturated, sector, sos, sos_bound, stabcond2, ultimate
    from lyapcheck.errors import InvalidParameter

    unknown = [c for c in classes if c not in CONDITION_ORDER]
    if unknown:
        raise InvalidParameter("classes", f"names among {', '.join(CONDITION_ORDER)}", ",".join(unknown))
    wanted = set(classes) | ({"sos_gas"} if "saturated_loop" in classes else set())
    system = build_system(problem, dynamics)
    g = problem.gains
    results: dict[str, ConditionResult] = {}
    if "prop41_ges" in wanted or "stabcond2" in wanted:
        results["prop41_ges"] = prop41.run(system, iss=False)
    if "prop41_iss" in wanted:
        results["prop41_iss"] = prop41.run(system, iss=True)
    if "stabcond2" in wanted:
        printed_status = (results["prop41_ges"].status if dynamics == "printed"
                          else prop41.run(build_system(problem, "printed"), iss=False).status)
        results["stabcond2"] = stabcond2.run(g.alpha_d, g.sigma0, g.k_d, g.delta_los, printed_status)
    if "sector_ges" in wanted:
        results["sector_ges"] = sector.run(system)
    if "ultimate_bound" in wanted:
        results["ultimate_bound"] = ultimate.run(system)
    if "sos_gas" in wanted:
        results["sos_gas"] = sos.run(system)
    if "saturated_loop" in wanted:
        results["saturated_loop"] = saturated.run(
            system, results["sos_gas"], alpha_d=g.alpha_d, e11=problem.swimmer.e11,
            e11_hat=problem.swimmer.e11_hat, omega_so=problem.actuation.omega_so, k_d=g.k_d)
    if "sos_bound" in wanted:
        results["sos_bound"] = sos_bound.run_class(system)
    if "ultimate_bound" in results and "prop41_iss" in results:
        _add_paper_ball(results, problem)
    return {name: results[name] for name in CONDITION_ORDER if name in results and name in wanted}


def _add_paper_ball(results: dict[str, ConditionResult], problem: Problem) -> None:
    """The paper's ultimate-bound formula, reported beside the certified bound where it applies."""
    import numpy as np

    from lyapcheck import exact

    iss = results["prop41_iss"]
    ub = results["ultimate_bound"]
    if iss.status == "certified":
        P = np.array(exact.to_float(exact.from_json(iss.certificate["P"])))
        eig = np.linalg.eigvalsh(P)
        ub.numbers["paper_ball_radius_as_printed"] = float(problem.d_max) * float(eig.max() / eig.min())
        ub.numbers["paper_ball_note"] = ("d* lambda_max(P)/lambda_min(P) with the prop41_iss P; the formula's unit "
                                         "is that of d* (a velocity) and its derivation is flawed (see ledger prop:los)")
    else:
        ub.numbers["paper_ball_radius_as_printed"] = None
        ub.numbers["paper_ball_note"] = "not applicable: the paper's ISS condition has no solution here"


def verdict(results: dict[str, ConditionResult]) -> str:
    """``certified`` iff some stability certificate passed its exact check."""
    return "certified" if any(c in results and results[c].status == "certified" for c in STABILITY_CLASSES) \
        else "not_certified"
