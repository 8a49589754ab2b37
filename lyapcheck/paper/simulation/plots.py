"""The figures of Section 5 (fig:path_nominal and fig:path_nominal2) as one PNG.

One column per simulation (the paper's order: LOS alpha_d = 1200, LOS alpha_d = 600, ILOS):

1. the path in the plane (mm) with the desired line, and the speed |p_dot| over time as an
   inset (fig:path_nominal);
2. the cross-track error eps over time, with the tail window magnified in an inset;
3. the rotation command u (components and magnitude, in Hz = revolutions per second) against
   the step-out frequency, and the integral state s on a second axis for ILOS
   (fig:path_nominal2).
"""

from __future__ import annotations

import math
from typing import Sequence

import numpy as np

from lyapcheck.paper.simulation.runner import SimulationResult
from lyapcheck.paper.simulation.scenarios import Scenario

#: the paper's column order
_ORDER = ("paper-los-1200", "paper-los-600", "paper-ilos")


def _title(s: Scenario) -> str:
    law = "ILOS" if s.controller == "ilos" else "conventional LOS"
    return f"{law}, alpha_d = {s.alpha_d:g}" + ("" if s.form == "derived" else " (printed ODS)")


def section5_figure(scenarios: Sequence[Scenario], result: SimulationResult, path: str) -> None:
    """Write the Section 5 figures for the recorded trajectories of ``result`` to ``path``."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    if result.trajectories is None:
        raise ValueError("The 'result' parameter must hold recorded trajectories. Got none instead.")
    order = sorted(range(len(scenarios)),
                   key=lambda i: _ORDER.index(scenarios[i].name) if scenarios[i].name in _ORDER else i)
    ncol = len(order)
    fig, axes = plt.subplots(3, ncol, figsize=(5.2 * ncol, 11.5), squeeze=False)
    tail0 = result.horizon_s - result.tail_s
    for col, i in enumerate(order):
        sc, tr, m = scenarios[i], result.trajectories[i], result.measurements
        two_pi = 2 * math.pi
        # 1. path with the desired line, speed inset
        ax = axes[0, col]
        ax.plot(tr.p[:, 0] * 1e3, tr.p[:, 1] * 1e3, color="C0", lw=1.5, label="swimmer")
        th = float(sc.problem.theta_r)
        xs = np.array([tr.p[:, 0].min(), tr.p[:, 0].max()]) * 1e3
        ax.plot(xs, np.tan(th) * xs, "k--", lw=1, label="desired path")
        ax.plot(tr.p[0, 0] * 1e3, tr.p[0, 1] * 1e3, "o", color="C3", ms=4, label="start")
        ax.set_xlabel("p_x (mm)")
        ax.set_ylabel("p_z (mm)")
        ax.set_title(_title(sc), fontsize=11)
        ax.legend(loc="lower right", fontsize=8)
        ax.grid(alpha=0.3)
        ins = ax.inset_axes((0.47, 0.36, 0.48, 0.32))
        ins.plot(tr.t, np.hypot(tr.v[:, 0], tr.v[:, 1]) * 1e3, color="C2", lw=1)
        ins.axhline(m.speed_star_m_s[i] * 1e3, color="k", ls=":", lw=0.8)
        ins.set_title("|v| (mm/s) vs t (s); dotted: e11 alpha_d Delta", fontsize=7)
        ins.tick_params(labelsize=7)
        # 2. cross-track error with the tail magnified
        ax = axes[1, col]
        ax.plot(tr.t, tr.eps * 1e3, color="C0", lw=1.2)
        ax.axhline(0, color="k", lw=0.6)
        ax.axvspan(tail0, result.horizon_s, color="C1", alpha=0.12, lw=0)
        ax.set_xlabel("t (s)")
        ax.set_ylabel("cross-track error eps (mm)")
        ax.set_title(f"mean |eps| over {tail0:g}-{result.horizon_s:g} s = "
                     f"{m.mean_abs_eps_tail_m[i] * 1e3:.3g} mm", fontsize=10)
        ax.grid(alpha=0.3)
        tail = tr.t >= tail0
        ins = ax.inset_axes((0.45, 0.12, 0.5, 0.4))
        ins.plot(tr.t[tail], tr.eps[tail] * 1e3, color="C0", lw=1)
        ins.set_title("tail window (mm)", fontsize=7)
        ins.tick_params(labelsize=7)
        # 3. rotation command (Hz) and s
        ax = axes[2, col]
        # |u| underneath as a wide grey band: u_z nearly equals it and would hide behind it
        ax.plot(tr.t, np.hypot(tr.u[:, 0], tr.u[:, 1]) / two_pi, color="0.6", lw=4, alpha=0.7, label="|u|")
        ax.plot(tr.t, tr.u[:, 0] / two_pi, color="C0", lw=1.2, label="u_x")
        ax.plot(tr.t, tr.u[:, 1] / two_pi, color="C1", lw=1.2, label="u_z")
        so = float(sc.problem.actuation.step_out()) / two_pi
        ax.axhline(so, color="C3", ls="--", lw=1, label=f"Omega_SO = {so:g} Hz")
        ax.axhline(-so, color="C3", ls="--", lw=1)
        ax.set_xlabel("t (s)")
        ax.set_ylabel("rotation command (Hz = rev/s)")
        ax.set_title(f"steady |u| = {m.steady_rotation_rad_s[i] / two_pi:.3g} Hz, "
                     f"max |u| = {m.max_rotation_rad_s[i] / two_pi:.3g} Hz", fontsize=10)
        ax.grid(alpha=0.3)
        handles, labels = ax.get_legend_handles_labels()
        if sc.controller == "ilos":
            ax2 = ax.twinx()
            ax2.plot(tr.t, tr.s * 1e3, color="C2", lw=1.2, label="s (right axis)")
            ax2.set_ylabel("integral state s (mm)", color="C2")
            ax2.tick_params(axis="y", colors="C2")
            h2, l2 = ax2.get_legend_handles_labels()
            handles, labels = handles + h2, labels + l2
        ax.legend(handles, labels, loc="lower right", fontsize=8)  # u >= -Omega_SO leaves room there
    dist = result.loop.disturbance.describe()
    fig.suptitle("Section 5 reproduced (lyapcheck simulate); disturbance: "
                 + ", ".join(f"{k} = {v}" for k, v in dist.items() if k != "note"), fontsize=10)
    fig.tight_layout(rect=(0, 0, 1, 0.97))
    fig.savefig(path, dpi=110)
    plt.close(fig)
