"""The paper's loop at one parameter point: its exact structured error dynamics.

Its own module, below the condition classes and the box classes, so that every one of them can
import :func:`build_system` at its top (it used to live in :mod:`lyapcheck.paper.certification`, which
runs the classes, so the box classes imported it inside functions to hide the cycle).
"""

from __future__ import annotations

from fractions import Fraction
from typing import Any

from lyapcheck.paper.conditions.base import System
from lyapcheck.paper.params import Problem


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
    # without a disturbance bound only the d-free classes run (NEEDS); d* = 0 in their System
    # changes nothing they compute
    d_max = problem.d_max if problem.d_max is not None else Fraction(0)
    return system_from_values(dynamics, exact_values(problem), d_max)


__all__ = ["build_system", "exact_values", "system_from_values"]
