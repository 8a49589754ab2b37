"""Trajectories of a model file's closed loop for the report's phase portrait.

The simulation lives in :mod:`lyapcheck.models.trajectories` (the core's cross-checks of
certificates use the same one); this module keeps the report's import path.
"""

from __future__ import annotations

from lyapcheck.models.trajectories import (
    CONVERGED_FRACTION, DENSE, ESCAPE_FACTOR, MIN_STEPS, RTOL, Trajectory, horizon, jacobian_eigenvalues, simulate,
)

__all__ = ["CONVERGED_FRACTION", "DENSE", "ESCAPE_FACTOR", "MIN_STEPS", "RTOL", "Trajectory", "horizon",
           "jacobian_eigenvalues", "simulate"]
