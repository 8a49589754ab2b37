"""``simulate --model`` for a loop with functions: the true loop, integrated from its starts.

The field integrated is the model's own (each function evaluated by numpy:
:func:`lyapcheck.models.recast_numeric.field_values`), never the recast polynomial loop, which
only holds on its relations' set. Its declared disturbances are held at 0, as in its certificates
(``(d = 0)``), so there is one scenario, the undisturbed loop. The document says, for every start,
where it ended, how far from the equilibrium (modulo 2 pi in an angle) and whether it converged.
"""

from __future__ import annotations

from typing import Any, Final

import numpy as np

from lyapcheck.models.recast import RecastModel

#: a trajectory that leaves this box (times the largest start or 1) has diverged
ESCAPE_FACTOR: Final = 1e6
#: the default horizon in slowest time constants of the linearization (60 s without one)
HORIZON_TIME_CONSTANTS: Final = 40.0
#: a trajectory ends within this distance of the equilibrium (modulo 2 pi in an angle): converged
CONVERGED_TOLERANCE: Final = 1e-3
#: grid points per state over the [domain] when no start is given
DEFAULT_GRID: Final = 5


def default_starts(model: RecastModel) -> np.ndarray:
    """The equilibrium and a grid over the ``[domain]``, or a start on each side of the equilibrium
    along each state (half a unit) without one."""
    eq = np.array([float(v) for v in model.equilibrium])
    rows = [eq]
    if model.domain is not None:
        axes = [np.linspace(float(model.domain[s][0]), float(model.domain[s][1]), DEFAULT_GRID) for s in model.states]
        mesh = np.meshgrid(*axes, indexing="ij")
        rows += list(np.column_stack([g.ravel() for g in mesh]))
    else:
        for i in range(model.n):
            for sign in (-1, 1):
                x = eq.copy()
                x[i] += sign * 0.5
                rows.append(x)
    return np.array(rows)


def default_horizon(model: RecastModel) -> float:
    from lyapcheck.models.recast_classes import base_loop, jacobian

    J = jacobian(base_loop(model.system))
    if isinstance(J, str):
        return 60.0
    real = np.linalg.eigvals(np.array([[float(x) for x in row] for row in J])).real
    slowest = np.max(real)
    return float(HORIZON_TIME_CONSTANTS / -slowest) if slowest < 0 else 60.0


def simulate(model: RecastModel, starts: np.ndarray | None = None, t_end: float | None = None) -> dict[str, Any]:
    """Integrate the true loop from every start (the project's batched DOPRI5,
    :func:`lyapcheck.models.recast_numeric.simulate_ends`); the document."""
    from lyapcheck.models.recast_classes import angle_states
    from lyapcheck.models.recast_numeric import distances, simulate_ends

    system = model.system
    X0 = default_starts(model) if starts is None or len(starts) == 0 else np.atleast_2d(np.asarray(starts, float))
    horizon = default_horizon(model) if t_end is None else float(t_end)
    eq = np.array([float(v) for v in model.equilibrium])
    angles = tuple(angle_states(system))
    escape = ESCAPE_FACTOR * max(1.0, float(np.max(np.abs(X0 - eq))))
    dev, result = simulate_ends(system, X0, horizon, escape=escape)
    distance = distances(system, dev, angles)
    trajectories = []
    for k, x0 in enumerate(X0):
        diverged = not bool(result.ok[k]) or bool(np.any(np.abs(dev[k]) >= escape))
        trajectories.append({"start": dict(zip(model.states, map(float, x0))),
                             "final": dict(zip(model.states, map(float, dev[k] + eq))),
                             "t_final_s": float(result.t[k]),
                             "distance_to_equilibrium": float("inf") if diverged else float(distance[k]),
                             "converged": not diverged and bool(distance[k] < CONVERGED_TOLERANCE),
                             "diverged": diverged})
    return {"model": model.name, "kind": "recast",
            "field": "the true loop: each function evaluated by numpy, not the recast polynomial loop"
                     + (f"; the disturbances {', '.join(model.disturbances)} held at 0" if model.disturbances else ""),
            "angles_modulo_2pi": list(angles), "t_end_s": horizon,
            "trajectories": trajectories, "n_converged": sum(t["converged"] for t in trajectories),
            "diverged": any(t["diverged"] for t in trajectories)}
