"""Simulated cross-check of a certified GES box: random gain sets of it against its envelope."""

from __future__ import annotations

import math
from typing import Any, Mapping, Sequence

from lyapcheck.paper.boxes.box import ParameterBox, problem_at_point, sample_points
from lyapcheck.paper.params import Problem
from lyapcheck.paper.system import build_system


#: starting radii (in x = (eps, sigma0 s)/Delta) and directions of the cross-check trajectories:
#: the claim is global, so from well inside the saturation of the LOS law to far outside it
CROSS_CHECK_RADII: tuple[float, ...] = (0.1, 1.0, 10.0, 100.0)


CROSS_CHECK_ANGLES = 6


#: the simulated time: until the envelope has decayed by exp(-CROSS_CHECK_DECAYS), at most
#: CROSS_CHECK_MAX_TAU time-scaled units
CROSS_CHECK_DECAYS = 4.0


CROSS_CHECK_MAX_TAU = 4000.0


def envelope_ratio(problem: Problem, k: float, rate_per_s: float, dynamics: str = "derived") -> float:
    """Largest ``|x(t)| / (k |x0| exp(-rate t))`` over simulated trajectories of the error dynamics.

    The dynamics are those of the point itself (derived from its own gains, not from the box's
    corners), integrated in time scaled by ``|a11|`` from :data:`CROSS_CHECK_RADII` x
    :data:`CROSS_CHECK_ANGLES` starts at ``rtol = 1e-10``. A value above
    ``1 + ENVELOPE_REL_TOL`` means the box's certificate is wrong at this point.
    """
    import numpy as np
    from scipy.integrate import solve_ivp

    from lyapcheck.paper.conditions.sos import scaled_dynamics

    dyn = scaled_dynamics(build_system(problem, dynamics))
    if dyn is None:
        return math.nan
    c, a, b, ts = float(dyn.c), float(dyn.a), float(dyn.b), float(dyn.time_scale)
    angles = np.linspace(0, 2 * np.pi, CROSS_CHECK_ANGLES, endpoint=False)
    starts = np.array([[r * np.cos(t), r * np.sin(t)] for r in CROSS_CHECK_RADII for t in angles])
    radius = np.linalg.norm(starts, axis=1)

    def field(_tau: float, z: np.ndarray) -> np.ndarray:
        e, r = z[0::2], z[1::2]
        out = np.empty_like(z)
        out[0::2] = -e + c * r
        out[1::2] = -a * r + b * e / (1.0 + (e + r) ** 2)
        return out

    rate_tau = rate_per_s / ts  # the envelope's rate per unit of scaled time tau = |a11| t
    horizon = min(CROSS_CHECK_DECAYS / rate_tau, CROSS_CHECK_MAX_TAU)
    sol = solve_ivp(field, (0.0, horizon), starts.ravel(), method="LSODA", rtol=1e-10,
                    atol=np.repeat(1e-13 * radius, 2))
    if not sol.success:
        return math.inf
    norms = np.hypot(sol.y[0::2], sol.y[1::2])
    envelope = k * radius[:, None] * np.exp(-rate_tau * sol.t)[None, :]
    return float(np.max(norms / envelope))


def cross_check(problem: Problem, box: ParameterBox, result: Mapping[str, Any], count: int,
                seed: Sequence[int], dynamics: str = "derived") -> tuple[int, float]:
    """Simulate ``count`` random points of a certified ``box`` (:func:`sample_points`) against
    its envelope; returns (points simulated, worst :func:`envelope_ratio`)."""
    worst = -math.inf
    points = sample_points(box, count, seed)
    for point in points:
        p = problem_at_point(problem, point)
        worst = max(worst, envelope_ratio(p, float(result["k"]), float(result["decay_rate_per_s"]), dynamics))
    return len(points), (worst if points else math.nan)
