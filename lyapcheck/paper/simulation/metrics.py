"""Quantities measured on the fly while a batch is integrated (no trajectory kept in memory).

* tail means (``|eps|``, rotation ``|u|``, speed along the path) come from integrals carried in
  the state (:mod:`lyapcheck.paper.simulation.model`), hence exact up to the integration error;
* sup-norms over the tail and the convergence time to a band are sampled on every accepted
  step at five points (its ends and three interior points of the cubic Hermite interpolant);
  the step is capped by ``max_step``, so the sampling interval is at most ``max_step / 4``;
* ``max |u|`` is the maximum over *every* evaluation of the controller (each stage of each
  step, rejected ones included), so ``max |u| <= Omega_SO`` is checked on all commands issued.

:class:`Recorder` keeps a few full trajectories, resampled on a uniform grid, for plots.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Final

import numpy as np
import numpy.typing as npt

from lyapcheck.integrator import hermite
from lyapcheck.paper.simulation.model import PX, PZ, S, ClosedLoop

FloatArray = npt.NDArray[np.float64]
IntArray = npt.NDArray[np.intp]

#: interior sample points of each step (fractions of the step)
SAMPLE_THETAS: Final = (0.25, 0.5, 0.75)


class TailObserver:
    """Accumulates sup-norms over the tail window and the last exit from the band."""

    def __init__(self, loop: ClosedLoop, band: FloatArray) -> None:
        n = loop.size
        _, self._across = loop.frame()
        self._integral = loop.params.integral
        self._t_tail = loop.t_tail
        self._band = np.broadcast_to(np.asarray(band, dtype=np.float64), (n,)).copy()
        self.sup_abs_eps_tail = np.zeros(n)
        self.sup_norm_x_tail = np.zeros(n)
        self.sup_abs_eps = np.zeros(n)
        #: time after which |eps| <= band held so far (0 if never outside), per trajectory
        self.band_entry_time = np.zeros(n)

    def _sample(self, index: IntArray, y: FloatArray) -> tuple[FloatArray, FloatArray]:
        eps = np.einsum("ij,ij->i", self._across[index], y[:, PX:PZ + 1])
        s = y[:, S] * self._integral[index]
        return np.abs(eps), np.hypot(eps, s)

    def start(self, index: IntArray, t: FloatArray, y: FloatArray, f: FloatArray) -> None:
        a, x = self._sample(index, y)
        self.sup_abs_eps[index] = a
        tail = t >= self._t_tail[index]
        self.sup_abs_eps_tail[index] = np.where(tail, a, 0.0)
        self.sup_norm_x_tail[index] = np.where(tail, x, 0.0)
        self.band_entry_time[index] = np.where(a > self._band[index], np.inf, 0.0)

    def step(self, index: IntArray, t0: FloatArray, t1: FloatArray, y0: FloatArray, y1: FloatArray,
             f0: FloatArray, f1: FloatArray) -> None:
        h = t1 - t0
        thetas = (0.0, *SAMPLE_THETAS, 1.0)
        abs_eps = np.empty((index.size, len(thetas)))
        norm_x = np.empty_like(abs_eps)
        for j, th in enumerate(thetas):
            yj = y0 if th == 0.0 else (y1 if th == 1.0 else hermite(th, h, y0, y1, f0, f1))
            abs_eps[:, j], norm_x[:, j] = self._sample(index, yj)
        tail = (t0 >= self._t_tail[index])
        self.sup_abs_eps[index] = np.maximum(self.sup_abs_eps[index], abs_eps.max(axis=1))
        self.sup_abs_eps_tail[index] = np.where(tail, np.maximum(self.sup_abs_eps_tail[index], abs_eps.max(axis=1)),
                                                self.sup_abs_eps_tail[index])
        self.sup_norm_x_tail[index] = np.where(tail, np.maximum(self.sup_norm_x_tail[index], norm_x.max(axis=1)),
                                               self.sup_norm_x_tail[index])
        # band: find the last sample outside; the crossing back in lies between it and the next
        band = self._band[index][:, None]
        outside = abs_eps > band
        any_out = outside.any(axis=1)
        if not np.any(any_out):
            return
        k = len(thetas)
        last = k - 1 - np.argmax(outside[:, ::-1], axis=1)
        rows = np.flatnonzero(any_out)
        tt = np.asarray(thetas)
        entry = np.full(rows.size, np.inf)
        inside_after = last[rows] < k - 1
        r_in = rows[inside_after]
        if r_in.size:
            j = last[r_in]
            e_out, e_in = abs_eps[r_in, j], abs_eps[r_in, j + 1]
            b = band[r_in, 0]
            # linear interpolation of |eps| between the two samples for the crossing time
            frac = np.clip((e_out - b) / np.maximum(e_out - e_in, 1e-300), 0.0, 1.0)
            theta_cross = tt[j] + frac * (tt[j + 1] - tt[j])
            entry[inside_after] = t0[r_in] + theta_cross * h[r_in]
        self.band_entry_time[index[rows]] = entry


@dataclass(frozen=True)
class Trajectory:
    """One recorded trajectory on a uniform time grid (SI)."""

    t: FloatArray
    p: FloatArray  # (K, 2) m
    s: FloatArray  # m
    eps: FloatArray  # m
    u: FloatArray  # (K, 2) rad/s
    v: FloatArray  # (K, 2) m/s, p_dot
    d: FloatArray  # (K, 2) m/s


class Recorder:
    """Keeps the accepted steps of selected trajectories, then resamples them (for plots)."""

    def __init__(self, indices: npt.ArrayLike, n: int) -> None:
        self.indices = np.asarray(indices, dtype=np.intp)
        self._slot = np.full(n, -1, dtype=np.intp)
        self._slot[self.indices] = np.arange(self.indices.size)
        self._steps: list[list[tuple[float, float, FloatArray, FloatArray, FloatArray, FloatArray]]] = [
            [] for _ in self.indices]
        self._start: list[tuple[float, FloatArray] | None] = [None] * self.indices.size

    def start(self, index: IntArray, t: FloatArray, y: FloatArray, f: FloatArray) -> None:
        slots = self._slot[index]
        for row in np.flatnonzero(slots >= 0):
            self._start[slots[row]] = (float(t[row]), y[row].copy())

    def step(self, index: IntArray, t0: FloatArray, t1: FloatArray, y0: FloatArray, y1: FloatArray,
             f0: FloatArray, f1: FloatArray) -> None:
        slots = self._slot[index]
        for row in np.flatnonzero(slots >= 0):
            self._steps[slots[row]].append((float(t0[row]), float(t1[row]), y0[row].copy(), y1[row].copy(),
                                            f0[row].copy(), f1[row].copy()))

    def trajectories(self, loop: ClosedLoop, dt: float) -> list[Trajectory]:
        """Resample each recorded trajectory every ``dt`` seconds (Hermite inside steps)."""
        out = []
        for slot, gi in enumerate(self.indices):
            steps = self._steps[slot]
            start = self._start[slot]
            if start is None:
                raise RuntimeError("The recorder saw no start point. Got an empty integration instead.")
            if not steps:
                times = np.array([start[0]])
                ys = start[1][None, :]
            else:
                t0s = np.array([st[0] for st in steps])
                t1s = np.array([st[1] for st in steps])
                grid = np.arange(start[0], t1s[-1] + 0.5 * dt, dt)
                grid[-1] = min(grid[-1], t1s[-1])
                k = np.clip(np.searchsorted(t1s, grid, side="left"), 0, len(steps) - 1)
                Y0 = np.array([steps[i][2] for i in k])
                Y1 = np.array([steps[i][3] for i in k])
                F0 = np.array([steps[i][4] for i in k])
                F1 = np.array([steps[i][5] for i in k])
                h = t1s[k] - t0s[k]
                theta = np.where(h > 0, (grid - t0s[k]) / np.where(h > 0, h, 1.0), 0.0)
                ys = hermite(theta, h, Y0, Y1, F0, F1)
                times = grid
            sub = loop.take(np.full(times.size, gi, dtype=np.intp))
            dy = sub.rhs(times, ys, times).dy
            u, _, eps = sub.control(ys)
            d = sub.disturbance_at(times, ys)
            out.append(Trajectory(t=times, p=ys[:, PX:PZ + 1], s=ys[:, S] * loop.params.integral[gi], eps=eps,
                                  u=u, v=dy[:, PX:PZ + 1], d=d))
        return out
