"""Certify one gain set: run every condition class on the chosen dynamics.

This is the library entry point behind ``lyapcheck certify``. It evaluates the structured
closed loop of :mod:`symbolic.closed_loop` exactly at the given parameters, runs the
condition classes, and assembles the certificate document (see :mod:`lyapcheck.paper.certificate`).
"""

from __future__ import annotations

import contextlib
import logging
from collections.abc import Callable
from fractions import Fraction
from typing import Any

import numpy as np

from lyapcheck.paper.conditions.base import STABILITY_CLASSES, System
from lyapcheck.results import ConditionResult
from lyapcheck.paper.params import Problem
from lyapcheck.paper.system import build_system, exact_values, system_from_values  # noqa: F401 (re-exported)
from lyapcheck.timing import ClassTimeLimit, time_limit  # noqa: F401 (re-exported: the paper's classes use them)

log = logging.getLogger(__name__)

CONDITION_ORDER = ("prop41_ges", "prop41_iss", "stabcond2", "sector_ges", "switched_ges", "ultimate_bound",
                   "sos_gas", "ges", "saturated_loop", "sos_bound")
#: the polynomial and state-dependent classes cost longer per point; these tens of milliseconds
QUICK_CLASSES = ("prop41_ges", "prop41_iss", "stabcond2", "sector_ges", "switched_ges", "ultimate_bound")


#: inputs a class needs beyond the gains and e11: (problem key, command-line flag)
NEEDS: dict[str, tuple[tuple[str, str], ...]] = {
    "ultimate_bound": (("disturbance.d_max", "--d-max"),),
    "sos_bound": (("disturbance.d_max", "--d-max"),),
    "saturated_loop": (("actuation.omega_so", "--omega-so"), ("disturbance.d_max", "--d-max")),
}


def not_applicable(name: str, missing: tuple[str, ...]) -> ConditionResult:
    """The result of a class whose inputs were not given: which flag (or TOML key) to add."""
    flags = [flag for key, flag in NEEDS[name] if key in missing]
    keys = [key for key, _ in NEEDS[name] if key in missing]
    return ConditionResult(name, "not_applicable",
                           f"needs {' and '.join(flags)} (or {', '.join(keys)} in the TOML file); not run",
                           numbers={"missing_inputs": keys})


def run_conditions(problem: Problem, dynamics: str,
                   classes: tuple[str, ...] = CONDITION_ORDER) -> dict[str, ConditionResult]:
    """Run the requested condition classes (all by default), in :data:`CONDITION_ORDER`."""
    # the polynomial classes' modules are imported where they run (--classes quick skips them)
    from lyapcheck.paper.conditions import prop41, sector, stabcond2, switching, ultimate
    from lyapcheck.errors import InvalidParameter

    unknown = [c for c in classes if c not in CONDITION_ORDER]
    if unknown:
        raise InvalidParameter("classes", f"names among {', '.join(CONDITION_ORDER)}", ",".join(unknown))
    missing = problem.missing_inputs()
    results: dict[str, ConditionResult] = {}
    for name, needs in NEEDS.items():
        if name in classes and any(key in missing for key, _ in needs):
            results[name] = not_applicable(name, missing)
    runnable = set(classes) - set(results)
    wanted = runnable | ({"sos_gas"} if "saturated_loop" in runnable else set())
    system = build_system(problem, dynamics)
    g = problem.gains

    def run(name: str, compute: Callable[[], ConditionResult]) -> None:
        results[name] = guarded(name, compute)

    if "prop41_ges" in wanted or "stabcond2" in wanted:
        run("prop41_ges", lambda: prop41.run(system, iss=False))
    if "prop41_iss" in wanted:
        run("prop41_iss", lambda: prop41.run(system, iss=True))
    if "stabcond2" in wanted:
        printed_status = (results["prop41_ges"].status if dynamics == "printed"
                          else guarded("prop41_ges", lambda: prop41.run(build_system(problem, "printed"),
                                                                        iss=False)).status)
        run("stabcond2", lambda: stabcond2.run(g.alpha_d, g.sigma0, g.k_d, g.delta_los, printed_status))
    if "sector_ges" in wanted:
        run("sector_ges", lambda: sector.run(system))
    if "switched_ges" in wanted:
        run("switched_ges", lambda: switching.run(system))
    if "ultimate_bound" in wanted:
        run("ultimate_bound", lambda: ultimate.run(system))
    if "sos_gas" in wanted:
        from lyapcheck.paper.conditions import sos
        run("sos_gas", lambda: sos.run(system))
    if "ges" in wanted:
        from lyapcheck.paper.conditions import ges
        run("ges", lambda: ges.run(system))
    if "saturated_loop" in wanted:
        from lyapcheck.paper.conditions import saturated
        run("saturated_loop", lambda: saturated.run(
            system, results["sos_gas"], alpha_d=g.alpha_d, e11=problem.swimmer.e11,
            e11_hat=problem.swimmer.e11_hat, omega_so=problem.actuation.step_out(), k_d=g.k_d))
    if "sos_bound" in wanted:
        from lyapcheck.paper.conditions import sos_bound
        run("sos_bound", lambda: sos_bound.run_class(system))
    if "ultimate_bound" in wanted and "prop41_iss" in wanted and problem.d_max is not None:
        with contextlib.suppress(ArithmeticError, ValueError, np.linalg.LinAlgError):  # a side figure only
            _add_paper_ball(results, problem)
    _real_loop_bound(results)
    return {name: results[name] for name in CONDITION_ORDER if name in results and name in classes}


def _real_loop_bound(results: dict[str, ConditionResult]) -> None:
    """With global reach (saturated_loop) the real loop ends inside an unsaturated invariant set,
    where it is the error dynamics: the sos_bound bound (from ANY start) is then its bound too.
    Both certificates are re-checked by verify; this is their conjunction, stated as a number."""
    sat, bound = results.get("saturated_loop"), results.get("sos_bound")
    if sat is None or bound is None or sat.status != "certified" or bound.status != "certified":
        return
    if sat.numbers.get("global_reach") == "proved":
        from lyapcheck.paper.claims import real_loop_clause

        sat.numbers["real_loop_limsup_eps_m"] = bound.numbers["eps_bound_m"]
        sat.summary += real_loop_clause(bound.numbers["eps_bound_m"])


def guarded(name: str, compute: Callable[[], ConditionResult]) -> ConditionResult:
    """Run one class; numerical trouble at extreme scales becomes ``inconclusive`` with its reason.

    Bad input has been rejected before any class runs, so what reaches here is a valid gain set
    that a floating-point search cannot handle (overflow, underflow to a singular problem, a
    solver failure) or a class that ran out of time. Those are honest "cannot decide here"
    answers, never a proof either way, and the other classes still run.
    """
    from lyapcheck import tolerances as tol
    from lyapcheck.errors import InputFileError, InvalidParameter, SolverError

    try:
        with time_limit(tol.CLASS_TIME_LIMIT_S):
            return compute()
    except (InvalidParameter, InputFileError):
        raise
    except ClassTimeLimit as exc:
        reason = f"{exc} (lyapcheck.tolerances.CLASS_TIME_LIMIT_S)"
    except (SolverError, ArithmeticError, ValueError, np.linalg.LinAlgError) as exc:
        reason = f"{type(exc).__name__}: {exc}"
    log.info("%s inconclusive: %s", name, reason)
    return ConditionResult(name, "inconclusive", f"could not be decided at these numbers: {reason}",
                           numbers={"reason": reason})


def _add_paper_ball(results: dict[str, ConditionResult], problem: Problem) -> None:
    """The paper's ultimate-bound formula, reported beside the certified bound where it applies."""
    import numpy as np

    from lyapcheck import exact

    iss = results["prop41_iss"]
    ub = results["ultimate_bound"]
    if iss.status == "certified":
        P = np.array(exact.to_float(exact.from_json(iss.certificate["P"])))
        eig = np.linalg.eigvalsh(P)
        ub.numbers["paper_ball_radius_as_printed"] = float(problem.disturbance_bound()) * float(eig.max() / eig.min())
        ub.numbers["paper_ball_note"] = ("d* lambda_max(P)/lambda_min(P) with the prop41_iss P; the formula's unit "
                                         "is that of d* (a velocity) and its derivation is flawed (see ledger prop:los)")
    else:
        ub.numbers["paper_ball_radius_as_printed"] = None
        ub.numbers["paper_ball_note"] = "not applicable: the paper's ISS condition has no solution here"


def verdict(results: dict[str, ConditionResult]) -> str:
    """``certified`` iff some stability certificate passed its exact check."""
    return "certified" if any(c in results and results[c].status == "certified" for c in STABILITY_CLASSES) \
        else "not_certified"
