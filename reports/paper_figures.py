"""The figures of the paper's closed loop on its certificate page (:mod:`reports.subjects.paper`).

Path in the plane (fig:path_nominal), ``eps(t)`` linear and logarithmic against the tightest
certified bound, the rotation against the step-out frequency, and the ``(eps, s)`` phase portrait
with the certified sets (:mod:`reports.certified_sets`) and, for a certificate made with
``--worst-case``, the worst disturbance found. The simulations are :mod:`reports.closed_loop`'s;
the shared machinery (SVG, compact paths, closed curves) is :mod:`reports.figures`'.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Sequence

import numpy as np

from reports.certified_sets import CertifiedSet
from reports.figures import Figure, FloatArray, _new, resample_closed, to_svg


def path_figure(run: Any) -> Figure:
    """The swimmer's path in the plane with the desired straight line (fig:path_nominal)."""
    fig, axes = _new(3.4)
    ax = axes[0, 0]
    for k, tr in enumerate(run.trajectories):
        ax.plot(tr.p[:, 0] * 1e3, tr.p[:, 1] * 1e3, lw=1.6 if k == 0 else 0.9, color="C0" if k == 0 else "0.6",
                label="swimmer (paper's start)" if k == 0 else ("other starts" if k == 1 else None), zorder=3 - k)
        ax.plot(tr.p[0, 0] * 1e3, tr.p[0, 1] * 1e3, "o", ms=4, color="C3" if k == 0 else "0.6", zorder=4)
    xs = np.array(ax.get_xlim())
    ax.plot(xs, math.tan(run.theta_r_rad) * xs, "k--", lw=1, label="desired path")
    ax.set_xlim(*xs)
    ax.set_xlabel("$p_x$ (mm)")
    ax.set_ylabel("$p_z$ (mm)")
    ax.grid(alpha=0.3)
    ax.legend(loc="best", fontsize=8)
    m = run.measurements[0]
    cap = (f"Path in the plane over {run.horizon_s:g} s from p(0) = (0, -40) mm (blue) and two other starts (grey); "
           f"final position ({m['final_position_m'][0] * 1e3:.3g}, {m['final_position_m'][1] * 1e3:.3g}) mm.")
    return Figure(to_svg(fig), cap, "path of the swimmer in the plane, converging to the dashed desired line")


def eps_figure(run: Any, eps_bound_m: float | None, bound_name: str = "") -> Figure:
    """Cross-track error over time, linear and logarithmic, against the tightest certified bound."""
    fig, axes = _new(4.6, nrows=2, sharex=True)
    tr, m = run.trajectories[0], run.measurements[0]
    tail0 = run.horizon_s - run.tail_s
    ax = axes[0, 0]
    ax.plot(tr.t, tr.eps * 1e3, color="C0", lw=1.3)
    ax.axhline(0, color="k", lw=0.6)
    ax.set_ylabel(r"$\varepsilon$ (mm)")
    ax.grid(alpha=0.3)
    ax = axes[1, 0]
    ax.semilogy(tr.t, np.maximum(np.abs(tr.eps), 1e-12) * 1e3, color="C0", lw=1.3, label=r"$|\varepsilon(t)|$")
    which = f" ({bound_name})" if bound_name else ""
    if eps_bound_m is not None and math.isfinite(eps_bound_m):
        for a in axes[:, 0]:
            a.axhline(eps_bound_m * 1e3, color="C2", ls="--", lw=1.2)
        axes[0, 0].axhline(-eps_bound_m * 1e3, color="C2", ls="--", lw=1.2)
        ax.axhline(eps_bound_m * 1e3, color="C2", ls="--", lw=1.2, label=f"certified ultimate bound{which}")
    ax.axvspan(tail0, run.horizon_s, color="C1", alpha=0.15, lw=0, label="tail window")
    ax.set_xlabel("t (s)")
    ax.set_ylabel(r"$|\varepsilon|$ (mm, log)")
    ax.grid(alpha=0.3, which="both")
    ax.legend(loc="upper right", fontsize=8)
    bound = "" if eps_bound_m is None else (f"; certified ultimate bound {eps_bound_m * 1e3:.4g} mm{which}, the "
                                            f"tightest certified (dashed green)")
    cap = (f"Cross-track error from the paper's start: sup |eps| over the tail window {tail0:g}-{run.horizon_s:g} s "
           f"= {m['sup_abs_eps_tail_m'] * 1e3:.4g} mm{bound}.")
    return Figure(to_svg(fig), cap, "cross-track error over time, linear and logarithmic",
                  {"eps_bound_m": eps_bound_m, "bound_class": bound_name})


def rotation_figure(run: Any) -> Figure:
    """Rotation command in Hz (revolutions per second) against the step-out frequency."""
    fig, axes = _new(3.2)
    ax = axes[0, 0]
    tr, m = run.trajectories[0], run.measurements[0]
    two_pi = 2 * math.pi
    so = run.omega_so_rad_s / two_pi
    ax.plot(tr.t, tr.u[:, 0] / two_pi, color="C0", lw=0.9, label="$u_x$")
    ax.plot(tr.t, tr.u[:, 1] / two_pi, color="C1", lw=0.9, label="$u_z$")
    ax.plot(tr.t, np.hypot(tr.u[:, 0], tr.u[:, 1]) / two_pi, color="k", lw=1.4, label="$|u|$")
    ax.axhline(so, color="C3", ls="--", lw=1.1, label=rf"step-out $\Omega_{{SO}}$ = {so:.3g} Hz")
    ax.axhline(-so, color="C3", ls="--", lw=1.1)
    ax.set_xlabel("t (s)")
    ax.set_ylabel("rotation (Hz = rev/s)")
    ax.grid(alpha=0.3)
    ax.legend(loc="lower left", bbox_to_anchor=(0.0, 1.01), fontsize=8, ncols=4, frameon=False)
    cap = (f"Rotation command from the paper's start: max |u| = {m['max_rotation_hz']:.4g} Hz over every controller "
           f"call (step-out {so:.4g} Hz), steady {m['steady_rotation_hz']:.4g} Hz over the tail window.")
    return Figure(to_svg(fig), cap, "rotation frequency over time with the step-out frequency as a dashed line")


#: a certified set is drawn in a panel when its box lies within the panel's data widened by this
#: multiple of their span on every side (so up to five times their size); otherwise the caption
#: names it (the paper's quadratic box, 70 mm x 6.7 m, would squeeze trajectories of 80 mm x 0.7 m
#: into a corner)
FIT_MARGIN = 2.0
#: the zoom panel is drawn when its view is below this fraction of the overview's along an axis
ZOOM_FRACTION = 0.3
#: seconds of the constant-disturbance trajectories drawn in the zoom, before the tail window
ZOOM_LEAD_S = 20.0
#: the worst-case trajectory: whole in a light line, its tail window emphasised
WORST_COLOUR = "C1"
#: the light line of the whole worst-case trajectory keeps at most this many samples: it winds
#: round its limit cycle for 100 s, so matplotlib's simplification keeps most of its 2001 (16 kB);
#: at this density (every 0.25 s at the paper's gains) the drawn curve is the same
WORST_LIGHT_POINTS = 400
#: line style of each kind of certified set
SET_STYLES = {"sublevel": "-", "ellipsoid": "--", "box": ":"}


def _within(lo: FloatArray, hi: FloatArray, view_lo: FloatArray, view_hi: FloatArray, margin: float) -> bool:
    pad = margin * np.maximum(view_hi - view_lo, 1e-300)
    return bool(np.all(lo >= view_lo - pad) and np.all(hi <= view_hi + pad))


def _limits(ax: Any, lo: FloatArray, hi: FloatArray, pad: float) -> None:
    span = np.maximum(hi - lo, 1e-300)
    ax.set_xlim((lo[0] - pad * span[0]) * 1e3, (hi[0] + pad * span[0]) * 1e3)
    ax.set_ylim((lo[1] - pad * span[1]) * 1e3, (hi[1] + pad * span[1]) * 1e3)


@dataclass
class _PhaseViews:
    """What each panel of the phase portrait shows, and its limits (m)."""

    over: tuple[FloatArray, FloatArray]
    in_over: list[CertifiedSet]
    zoom: tuple[FloatArray, FloatArray] | None
    in_zoom: list[CertifiedSet]


def _phase_views(run: Any, sets: Sequence[CertifiedSet], worst_tail: FloatArray) -> _PhaseViews:
    """The transient's view with the sets that fit it; the zoom on the tightest set (or None)."""
    traj = np.vstack([np.column_stack([tr.eps, tr.s]) for tr in run.trajectories])
    over_lo, over_hi = traj.min(axis=0), traj.max(axis=0)
    in_over = [c for c in sets if _within(*c.bbox, over_lo, over_hi, FIT_MARGIN)]
    for c in in_over:
        over_lo, over_hi = np.minimum(over_lo, c.bbox[0]), np.maximum(over_hi, c.bbox[1])
    if not sets:
        return _PhaseViews((over_lo, over_hi), in_over, None, [])
    ends = np.array([[tr.eps[-1], tr.s[-1]] for tr in run.trajectories])
    base = np.vstack([np.array(sets[0].bbox), ends, worst_tail])
    lo, hi = base.min(axis=0), base.max(axis=0)
    in_zoom = [c for c in sets if _within(*c.bbox, lo, hi, FIT_MARGIN)]
    for c in in_zoom:
        lo, hi = np.minimum(lo, c.bbox[0]), np.maximum(hi, c.bbox[1])
    small = bool(np.any(hi - lo < ZOOM_FRACTION * (over_hi - over_lo)))
    return _PhaseViews((over_lo, over_hi), in_over, (lo, hi) if small else None, in_zoom if small else [])


def _draw_sets(ax: Any, shown: Sequence[CertifiedSet], filled: CertifiedSet) -> None:
    from matplotlib.colors import to_rgba

    for c in shown:
        style = SET_STYLES.get(c.kind, "-")
        for k, computed in enumerate(c.boundary):
            line = resample_closed(computed) * 1e3
            label = c.label if k == 0 else None
            if c is filled:  # one path for face and edge
                ax.fill(line[:, 0], line[:, 1], facecolor=to_rgba("C2", 0.18), edgecolor="C2", ls=style, lw=1.4,
                        label=label, zorder=1)
            else:
                ax.plot(line[:, 0], line[:, 1], color="#0b5d1e", ls=style, lw=1.1, label=label, zorder=2)


def _draw_trajectories(ax: Any, run: Any, from_s: float | None) -> None:
    """The constant-disturbance trajectories: whole with their starts, or from time ``from_s`` on."""
    for k, tr in enumerate(run.trajectories):
        sel = tr.t >= from_s if from_s is not None else slice(None)
        ax.plot(tr.eps[sel] * 1e3, tr.s[sel] * 1e3, color="C0" if k == 0 else "0.55", lw=1.2 if k == 0 else 0.8,
                label=("trajectories, constant $d^*$ across the path" if k == 0 else None), zorder=3)
        if from_s is None:
            ax.plot(tr.eps[0] * 1e3, tr.s[0] * 1e3, "o", ms=3.5, color="C3", zorder=4)
        ax.plot(tr.eps[-1] * 1e3, tr.s[-1] * 1e3, "s", ms=3.5, color="k", zorder=4)


def _draw_worst(ax: Any, worst: Any, tail: FloatArray, label: str) -> None:
    wt = worst.trajectory
    every = max(1, int(math.ceil(len(wt.t) / WORST_LIGHT_POINTS)))
    light = np.column_stack([wt.eps, wt.s])[np.r_[0:len(wt.t):every, len(wt.t) - 1]] * 1e3
    ax.plot(light[:, 0], light[:, 1], color=WORST_COLOUR, lw=0.6, alpha=0.45, zorder=5)
    ax.plot(tail[:, 0] * 1e3, tail[:, 1] * 1e3, color=WORST_COLOUR, lw=1.5, zorder=6,
            label=label or "worst case found by the search")


def phase_figure(run: Any, sets: Sequence[CertifiedSet], note: str, worst_label: str = "",
                 worst_text: str = "") -> Figure:
    """The (eps, s) phase portrait with the certified sets and the worst-case trajectory.

    Left, the transient of the constant-disturbance trajectories with the certified sets that fit
    beside them; right (when the sets are small beside the transient), a zoom on the tightest
    set with the others that fit, the trajectories' last seconds and the worst disturbance of the
    certificate's search (``run.worst``; whole trajectory light, tail window bold; ``worst_label``
    is its legend entry, ``worst_text`` its description in the caption). ``sets`` are
    tightest first; the first is filled. The figure's ``data`` holds the numbers it is drawn
    from: each set's drawn eps-extent against its certified bound, and the largest gauge (``V``
    for the sos_bound set, ``<= 1`` inside) over every tail window, the worst case's included.
    """
    worst = getattr(run, "worst", None)
    tail0 = run.horizon_s - run.tail_s
    worst_tail = np.empty((0, 2))
    if worst is not None:
        wt = worst.trajectory
        worst_tail = np.column_stack([wt.eps, wt.s])[wt.t >= tail0]
    views = _phase_views(run, sets, worst_tail)
    fig, axes = _new(4.3, ncols=2 if views.zoom is not None else 1)
    ax = axes[0, 0]
    _draw_trajectories(ax, run, None)
    if sets:
        _draw_sets(ax, views.in_over, sets[0])
    _limits(ax, *views.over, 0.05)
    if views.zoom is not None:
        ax.set_title("transient", fontsize=9)
        ax = axes[0, 1]
        _draw_trajectories(ax, run, tail0 - ZOOM_LEAD_S)
        _draw_sets(ax, views.in_zoom, sets[0])
        _limits(ax, *views.zoom, 0.08)
        ax.set_title("zoom on the certified set" + ("s" if len(views.in_zoom) > 1 else ""), fontsize=9)
    if worst is not None:  # in the zoom, else beside the transient
        _draw_worst(ax, worst, worst_tail, worst_label)
    for a in axes[0, :]:
        a.set_xlabel(r"$\varepsilon$ (mm)")
        a.set_ylabel("$s$ (mm)")
        a.grid(alpha=0.3)
    handles: dict[str, Any] = {}
    for a in axes[0, :]:
        for h, lab in zip(*a.get_legend_handles_labels()):
            handles.setdefault(lab, h)
    fig.legend(list(handles.values()), list(handles), loc="outside lower center", ncols=1 if len(handles) > 2 else 2,
               fontsize=7, frameon=False)

    drawn = {c.key for c in views.in_over} | {c.key for c in views.in_zoom}
    tails = [np.column_stack([tr.eps, tr.s])[tr.t >= tail0] for tr in run.trajectories]
    data: dict[str, Any] = {
        "sets": {c.key: {"label": c.label, "eps_bound_m": c.eps_bound_m, "max_abs_eps_m": c.max_abs_eps_m,
                         "resolution_eps_m": c.resolution_eps_m,
                         "panels": [p for p, shown in (("transient", views.in_over), ("zoom", views.in_zoom))
                                    if any(c is x for x in shown)]} for c in sets},
        "omitted": [c.key for c in sets if c.key not in drawn],
        "zoom": views.zoom is not None,
        "tails_max_gauge": {c.key: max(float(np.max(c.gauge(t))) for t in tails) for c in sets},
    }
    if worst is not None:
        data["worst_case"] = {
            "start": worst.start, "sup_abs_eps_tail_m": worst.sup_abs_eps_tail_m,
            "stored_sup_abs_eps_tail_m": worst.stored_sup_abs_eps_tail_m,
            "max_abs_eps_tail_samples_m": float(np.max(np.abs(worst_tail[:, 0]))) if len(worst_tail) else math.nan,
            "max_gauge_tail": {c.key: float(np.max(c.gauge(worst_tail))) for c in sets} if len(worst_tail) else {},
            "panel": "zoom" if views.zoom is not None else "transient",
        }
    cap = _phase_caption(run, sets, data, worst_text) + [note]
    return Figure(to_svg(fig), " ".join(cap), "phase portrait of the cross-track error against the integral state "
                                              "with the certified sets and the worst-case trajectory drawn", data)


def _phase_caption(run: Any, sets: Sequence[CertifiedSet], data: dict[str, Any], worst_text: str) -> list[str]:
    """The phase portrait's caption, sentence by sentence, from the numbers it is drawn from."""
    n_zoom = sum(1 for d in data["sets"].values() if "zoom" in d["panels"])
    cap = [f"Phase portrait in (eps, s): the simulated loop from three starts (circles) under a constant "
           f"disturbance d* across the path, to its states at {run.horizon_s:g} s (squares)"
           + (f"; right, a zoom on the certified set{'s' if n_zoom > 1 else ''}" if data["zoom"] else "") + "."]
    if sets:
        cap.append(f"Filled green: {sets[0].description}.")
        others = [c.description for c in sets[1:] if c.key not in data["omitted"]]
        if others:
            cap.append("Dark green outline" + ("s" if len(others) > 1 else "") + ": " + "; ".join(others) + ".")
        omitted = [c.description for c in sets if c.key in data["omitted"]]
        if omitted:
            cap.append("Not drawn, far larger than the view: " + "; ".join(omitted) + ".")
        gauges = data["tails_max_gauge"]
        inside = [c.short for c in sets if gauges[c.key] <= 1.0]
        outside = [c.short for c in sets if gauges[c.key] > 1.0]
        where = ("inside every certified set" if not outside else
                 f"inside {' and '.join(inside)} but not inside {' or '.join(outside)}" if inside else
                 "inside none of the certified sets")
        name = "V" if sets[0].kind == "sublevel" else "gauge"
        cap.append(f"The tail windows of the three trajectories lie {where} (largest {name} of the filled set over "
                   f"them: {gauges[sets[0].key]:.3g}).")
    worst = getattr(run, "worst", None)
    if worst is None:
        if getattr(run, "worst_reason", ""):
            cap.append(f"No worst-case trajectory: {run.worst_reason}.")
        return cap
    tail0 = run.horizon_s - run.tail_s
    start = "the origin" if worst.start == "origin" else "the paper's start"
    stored = worst.stored_sup_abs_eps_tail_m
    if stored is None:
        same = ""
    elif math.isclose(worst.sup_abs_eps_tail_m, stored, rel_tol=1e-6):
        same = ", as stored in the certificate"
    else:
        same = f" (the certificate stores {stored * 1e3:.4g} mm: NOT reproduced)"
    cap.append(f"Orange: the worst disturbance found by the certificate's search, {worst_text or 'as stored'}, "
               f"re-simulated from {start} (light: the whole trajectory; bold: the tail window "
               f"{tail0:g}-{run.horizon_s:g} s); its tail sup |eps| = {worst.sup_abs_eps_tail_m * 1e3:.4g} mm{same}.")
    if sets and data["worst_case"]["max_gauge_tail"]:
        g = data["worst_case"]["max_gauge_tail"][sets[0].key]
        name = "V" if sets[0].kind == "sublevel" else "gauge of the filled set"
        cap.append(f"Largest {name} over its tail: {g:.4g} "
                   + ("<= 1, inside the filled set." if g <= 1 else "> 1: the tail leaves the filled set."))
    return cap
