"""One call simulates a whole batch of closed loops and returns the measured quantities."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Final, Sequence

import numpy as np
import numpy.typing as npt

from lyapcheck.paper.simulation.disturbances import Disturbance, NoDisturbance
from lyapcheck.integrator import DEFAULT_RTOL, STATUS_OK, Fanout, IntegrationResult, integrate
from lyapcheck.paper.simulation.metrics import Recorder, TailObserver, Trajectory
from lyapcheck.paper.simulation.model import PX, PZ, Q_EPS, Q_U, Q_Z, ClosedLoop, Form, LoopParams

FloatArray = npt.NDArray[np.float64]

#: the largest step, as a fraction of the tail window: at least this many steps (x4 samples)
#: fall into the tail, which sets the sampling of the sup-norms there
STEPS_PER_TAIL: Final = 20


@dataclass(frozen=True)
class Measurements:
    """Measured quantities, one entry per trajectory, SI (rotation rates in rad/s)."""

    mean_abs_eps_tail_m: FloatArray
    sup_abs_eps_tail_m: FloatArray
    sup_norm_eps_s_tail_m: FloatArray
    sup_abs_eps_m: FloatArray
    max_rotation_rad_s: FloatArray
    steady_rotation_rad_s: FloatArray
    steady_speed_m_s: FloatArray
    speed_star_m_s: FloatArray
    final_eps_m: FloatArray
    final_s_m: FloatArray
    final_position_m: FloatArray
    convergence_time_s: FloatArray  # nan: |eps| was outside the band at the end
    band_m: FloatArray
    omega_so_rad_s: FloatArray
    diverged: npt.NDArray[np.bool_]
    status: npt.NDArray[np.int8]
    n_steps: npt.NDArray[np.int64]
    n_rejected: npt.NDArray[np.int64]

    def row(self, i: int) -> dict[str, Any]:
        """JSON-ready measurements of trajectory ``i`` (DESIGN.md keys, SI, units in names)."""
        conv = float(self.convergence_time_s[i])
        two_pi = 2 * math.pi
        return {
            "mean_abs_eps_tail_m": float(self.mean_abs_eps_tail_m[i]),
            "sup_abs_eps_tail_m": float(self.sup_abs_eps_tail_m[i]),
            "sup_norm_eps_s_tail_m": float(self.sup_norm_eps_s_tail_m[i]),
            "max_rotation_hz": float(self.max_rotation_rad_s[i]) / two_pi,
            "max_rotation_rad_s": float(self.max_rotation_rad_s[i]),
            "omega_so_hz": float(self.omega_so_rad_s[i]) / two_pi,
            "omega_so_rad_s": float(self.omega_so_rad_s[i]),
            "steady_rotation_hz": float(self.steady_rotation_rad_s[i]) / two_pi,
            "steady_rotation_rad_s": float(self.steady_rotation_rad_s[i]),
            "steady_speed_m_s": float(self.steady_speed_m_s[i]),
            "speed_star_m_s": float(self.speed_star_m_s[i]),
            "final_eps_m": float(self.final_eps_m[i]),
            "final_s_m": float(self.final_s_m[i]),
            "final_position_m": [float(v) for v in self.final_position_m[i]],
            "sup_abs_eps_m": float(self.sup_abs_eps_m[i]),
            "band_m": float(self.band_m[i]),
            "convergence_time_s": None if math.isnan(conv) else conv,
            "diverged": bool(self.diverged[i]),
            "integrator_status": int(self.status[i]),
            "steps_accepted": int(self.n_steps[i]),
            "steps_rejected": int(self.n_rejected[i]),
        }


@dataclass(frozen=True)
class SimulationResult:
    """Everything one batched simulation produced."""

    measurements: Measurements
    integration: IntegrationResult
    loop: ClosedLoop
    horizon_s: float
    tail_s: float
    rtol: float
    trajectories: Sequence[Trajectory] | None = None


def simulate(params: LoopParams, *, p0: npt.ArrayLike, s0: npt.ArrayLike = 0.0,
             disturbance: Disturbance | None = None, horizon: float = 100.0, tail: float = 10.0,
             band: npt.ArrayLike | None = None, form: Form = "derived", rtol: float = DEFAULT_RTOL,
             max_step: float | None = None, record: Sequence[int] | None = None,
             record_dt: float = 0.05) -> SimulationResult:
    """Simulate a batch of closed loops (one row of ``params`` per trajectory).

    Parameters
    ----------
    params
        Per-trajectory parameters (:class:`LoopParams`).
    p0, s0
        Initial positions ``(n, 2)`` or ``(2,)`` in m, and initial ``s`` in m (ignored by LOS).
    disturbance
        ``d_mu`` model (default none).
    horizon, tail
        Simulated time and the length of the final window over which means and sups are taken, s.
    band
        Band ``|eps| <= band`` for the convergence time, m (default ``Delta_LOS``).
    form
        ``"derived"`` (the toolkit's controller) or ``"printed"`` (eq:ODS2 as printed).
    rtol
        Relative tolerance of the integrator (its absolute tolerances scale with
        ``max(|p0|, Delta_LOS)``, see :meth:`ClosedLoop.atol`).
    max_step
        Largest step, s (default ``tail / STEPS_PER_TAIL``).
    record
        Indices of trajectories to keep in full (resampled every ``record_dt`` s) for plots.

    Returns
    -------
    SimulationResult
    """
    if not (math.isfinite(horizon) and horizon > 0):
        raise ValueError(f"The 'horizon' parameter must be a number in (0, inf). Got {horizon!r} instead.")
    if not (math.isfinite(tail) and 0 < tail <= horizon):
        raise ValueError(f"The 'tail' parameter must be a number in (0, horizon]. Got {tail!r} instead.")
    n = params.size
    loop = ClosedLoop(params, disturbance if disturbance is not None else NoDisturbance(),
                      np.full(n, horizon - tail), form)
    y0 = loop.initial_state(p0, s0)
    band_arr = np.broadcast_to(np.asarray(params.delta_los if band is None else band, dtype=np.float64), (n,)).copy()
    scale = np.maximum(np.hypot(y0[:, PX], y0[:, PZ]), params.delta_los)
    tails = TailObserver(loop, band_arr)
    recorder = Recorder(record, n) if record else None
    result = integrate(loop, 0.0, y0, horizon, rtol=rtol, atol=loop.atol(rtol, scale),
                       max_step=max_step if max_step is not None else tail / STEPS_PER_TAIL,
                       observer=Fanout(tails, recorder), switch_atol=loop.switch_atol(rtol, scale))
    y = result.y
    eps, _, s = loop.errors(y)
    final_abs = np.abs(eps)
    entry = np.where(final_abs > band_arr, np.nan, tails.band_entry_time)
    eps0 = np.abs(loop.errors(y0)[0])
    diverged = (result.status != STATUS_OK) | (tails.sup_abs_eps_tail > np.maximum(eps0, band_arr))
    m = Measurements(
        mean_abs_eps_tail_m=y[:, Q_EPS] / tail,
        sup_abs_eps_tail_m=tails.sup_abs_eps_tail,
        sup_norm_eps_s_tail_m=tails.sup_norm_x_tail,
        sup_abs_eps_m=tails.sup_abs_eps,
        max_rotation_rad_s=result.monitor_max,
        steady_rotation_rad_s=y[:, Q_U] / tail,
        steady_speed_m_s=y[:, Q_Z] / tail,
        speed_star_m_s=params.speed_star(),
        final_eps_m=eps,
        final_s_m=s,
        final_position_m=y[:, PX:PZ + 1].copy(),
        convergence_time_s=entry,
        band_m=band_arr,
        omega_so_rad_s=params.omega_so.copy(),
        diverged=np.asarray(diverged),
        status=result.status,
        n_steps=result.n_accepted,
        n_rejected=result.n_rejected,
    )
    trajectories = recorder.trajectories(loop, record_dt) if recorder is not None else None
    return SimulationResult(m, result, loop, float(horizon), float(tail), float(rtol), trajectories)
