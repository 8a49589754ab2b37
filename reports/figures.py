"""Figures of the reports, drawn with matplotlib's object interface and returned as SVG bytes.

No pyplot: figures are :class:`matplotlib.figure.Figure` objects saved through the SVG backend,
so drawing a report neither selects a GUI backend nor touches global figure state. Text is
converted to paths (the default ``svg.fonttype``), so each SVG is self-contained and reads the
same in a browser and in the PDF; ids are salted with a fixed string so that the same figure
gives the same bytes. Dense lines (simulated trajectories) are decimated by matplotlib's path
simplification, pinned in :func:`to_svg`; nothing is rasterised.
"""

from __future__ import annotations

import io
import math
import re
from dataclasses import dataclass, field
from typing import Any, Iterator, Sequence

import numpy as np
import numpy.typing as npt

from reports.certified_sets import CertifiedSet

FloatArray = npt.NDArray[np.float64]

#: one colour per status, the same in every figure and in the page's badges (report.css)
STATUS_COLOURS = {
    "certified": "#1a7f37", "not_certified": "#d0d7de", "refuted": "#cf222e", "inconclusive": "#8250df",
    "not_computed": "#ffffff", "unstable": "#000000",
}
#: the width a figure is drawn for: the report's text column (A4 less margins), inches
WIDTH_IN = 6.6
#: matplotlib's path simplification, pinned (it is an rcParam a user's matplotlibrc may turn
#: off): a vertex is dropped where the line moves less than this, in pt at the saved size (1/9
#: is matplotlib's default; on a phone that is about a quarter of a device pixel). A simulated
#: trajectory has 2001 samples; simplified, it keeps 30 to 60 vertices and the paper's four
#: figures weigh 150 kB; unsimplified, 670 kB (SVG grows with vertices: each is text)
SIMPLIFY_THRESHOLD = 1 / 9


@dataclass(frozen=True)
class Figure:
    """One figure: SVG bytes, a caption (plain text, escaped by the template) and alt text.

    ``data`` holds the numbers a figure is drawn from, for checks (not shown on the page).
    """

    svg: bytes
    caption: str
    alt: str
    data: dict[str, Any] = field(default_factory=dict)


def _new(height_in: float, ncols: int = 1, nrows: int = 1, **kw: Any) -> tuple[Any, Any]:
    from matplotlib.figure import Figure as MplFigure

    fig = MplFigure(figsize=(WIDTH_IN, height_in), layout="constrained")
    axes = fig.subplots(nrows, ncols, squeeze=False, **kw)
    return fig, axes


def to_svg(fig: Any) -> bytes:
    """SVG bytes of a matplotlib figure: reproducible (fixed id salt, no date), lines simplified.

    The rcParams that decide the output are set here, at save time (when matplotlib reads them),
    so no user configuration changes what a report contains or how large it is.
    """
    import matplotlib

    buf = io.BytesIO()
    with matplotlib.rc_context({"svg.hashsalt": "lyapcheck-report", "svg.fonttype": "path", "path.simplify": True,
                                "path.simplify_threshold": SIMPLIFY_THRESHOLD}):
        fig.savefig(buf, format="svg", metadata={"Date": None})
    return compact_svg(buf.getvalue())


#: decimals kept in path coordinates: matplotlib writes 6 (a millionth of a pt); 2 is 1/7200 inch
PATH_DECIMALS = 2
_PATH_DATA = re.compile(rb' d="([^"]*)"')
_DECIMAL = re.compile(rb"-?\d+\.\d+")


def _round(match: re.Match[bytes]) -> bytes:
    text = b"%.*f" % (PATH_DECIMALS, float(match.group(0)))
    text = text.rstrip(b"0").rstrip(b".")
    return b"0" if text in (b"-0", b"") else text


def compact_svg(svg: bytes) -> bytes:
    """Matplotlib's SVG without comments and indentation, path coordinates to 0.01 pt.

    The same drawing (rasterised, pixels differ by antialiasing only) in 15 % fewer bytes: of a
    figure's weight, half is path data written to a millionth of a point, one coordinate pair per
    indented line. Only ``d`` attributes and the text between elements change.
    """
    svg = re.sub(rb"<!--.*?-->", b"", svg, flags=re.S)
    svg = _PATH_DATA.sub(lambda m: b' d="' + b" ".join(_DECIMAL.sub(_round, m.group(1)).split()) + b'"', svg)
    return re.sub(rb"\n\s+", b"\n", svg)


# ----------------------------------------------------------------------------------------------
# certificate report: trajectories of the closed loop
# ----------------------------------------------------------------------------------------------
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
#: a certified set's boundary is drawn with this many points, evenly spaced along it (at the set's
#: own proportions): a smooth curve this fine deviates from the computed one by about a thousandth
#: of the panel, while the computed contour (about 1400 points at the paper's gains) would cost
#: 35 kB per fill, which matplotlib does not simplify (closed paths)
DRAW_POINTS = 240
#: line style of each kind of certified set
SET_STYLES = {"sublevel": "-", "ellipsoid": "--", "box": ":"}


def resample_closed(line: FloatArray, n: int = DRAW_POINTS) -> FloatArray:
    """``n + 1`` points evenly spaced by arc length along the closed polyline ``line`` (first = last).

    Lengths are measured with each coordinate divided by the line's extent, so a set 0.7 mm wide
    and 430 mm tall is sampled evenly as drawn, not along its long side only.
    """
    pts = np.asarray(line, dtype=np.float64)
    if len(pts) <= n:
        return pts
    if not np.array_equal(pts[0], pts[-1]):
        pts = np.vstack([pts, pts[:1]])
    scale = np.maximum(np.ptp(pts, axis=0), 1e-300)
    seg = np.hypot(*(np.diff(pts, axis=0) / scale).T)
    arc = np.concatenate([[0.0], np.cumsum(seg)])
    at = np.linspace(0.0, arc[-1], n + 1)
    return np.column_stack([np.interp(at, arc, pts[:, 0]), np.interp(at, arc, pts[:, 1])])


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


# ----------------------------------------------------------------------------------------------
# sweep report: maps over the swept parameters
# ----------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class Axis:
    """A swept parameter as plotted: display name, unit, scale from SI, values in display units."""

    name: str
    label: str
    values: FloatArray
    log: bool


def _edges(values: FloatArray, log: bool) -> FloatArray:
    """Cell edges around sorted centres (geometric midpoints on a log axis)."""
    v = np.log10(values) if log else values
    if v.size == 1:
        e = np.array([v[0] - 0.5, v[0] + 0.5]) if not log else np.array([v[0] - 0.1, v[0] + 0.1])
    else:
        mid = (v[1:] + v[:-1]) / 2
        e = np.concatenate([[v[0] - (mid[0] - v[0])], mid, [v[-1] + (v[-1] - mid[-1])]])
    return 10 ** e if log else e


def _slices(n: int, limit: int = 6) -> list[int]:
    """Indices of at most ``limit`` evenly spread slices of a third dimension."""
    if n <= limit:
        return list(range(n))
    return sorted({int(round(i)) for i in np.linspace(0, n - 1, limit)})


def _panels(axes_info: Sequence[Axis]) -> Iterator[tuple[int | None, str]]:
    if len(axes_info) < 3:
        yield None, ""
        return
    third = axes_info[2]
    for k in _slices(third.values.size):
        yield k, f"{third.label} = {third.values[k]:.4g}"


def _grid(n_panels: int) -> tuple[int, int]:
    ncols = min(3, n_panels)
    return int(math.ceil(n_panels / ncols)), ncols


def category_map(codes: FloatArray, axes_info: Sequence[Axis], *, title: str, legend: Sequence[tuple[int, str, str]],
                 marks: Sequence[tuple[FloatArray, str, str]], paper: Sequence[float] | None) -> bytes:
    """A categorical map over 1 to 3 swept parameters.

    Parameters
    ----------
    codes
        Integer category per grid point (array with one axis per entry of ``axes_info``).
    legend
        ``(code, label, colour)`` for every category shown.
    marks
        ``(mask, label, marker)`` overlays (e.g. diverged in simulation, soundness violations).
    paper
        The paper's point in display units (one value per axis), drawn as a star when given.
    """
    from matplotlib.colors import BoundaryNorm, ListedColormap
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch

    order = [c for c, _, _ in legend]
    cmap = ListedColormap([col for _, _, col in legend])
    norm = BoundaryNorm(np.arange(len(order) + 1) - 0.5, len(order))
    index = np.full(codes.shape, np.nan)
    for i, c in enumerate(order):
        index[codes == c] = i
    panels = list(_panels(axes_info))
    nrows, ncols = _grid(len(panels))
    one_d = len(axes_info) == 1
    height = 1.9 if one_d else (3.3 if len(panels) == 1 else 2.5 * nrows + 0.6)
    fig, axes = _new(height, ncols=ncols, nrows=nrows)
    x = axes_info[0]
    for p, (k, sub) in enumerate(panels):
        ax = axes[p // ncols, p % ncols]
        if one_d:
            img = index[None, :]
            ax.pcolormesh(_edges(x.values, x.log), [0, 1], img, cmap=cmap, norm=norm, edgecolors="white",
                          linewidth=0.3)
            ax.set_yticks([])
        else:
            y = axes_info[1]
            grid = index if k is None else index[:, :, k]
            ax.pcolormesh(_edges(x.values, x.log), _edges(y.values, y.log), grid.T, cmap=cmap, norm=norm,
                          edgecolors="white", linewidth=0.3)
            ax.set_ylabel(y.label)
            if y.log:
                ax.set_yscale("log")
        if x.log:
            ax.set_xscale("log")
        ax.set_xlabel(x.label)
        for mask, _, marker in marks:
            m = mask if k is None else mask[:, :, k]
            if not np.any(m):
                continue
            idx = np.argwhere(m)
            xs = x.values[idx[:, 0]]
            ys = np.full(xs.shape, 0.5) if one_d else axes_info[1].values[idx[:, 1]]
            style = dict(color="k", ms=5, lw=0) if marker == "x" else dict(mfc="none", mec="#cf222e", mew=1.8, ms=9, lw=0)
            ax.plot(xs, ys, marker, **style)
        if paper is not None:
            on_slice = k is None or math.isclose(paper[2], axes_info[2].values[k], rel_tol=1e-9)
            if on_slice or k is not None:
                py = 0.5 if one_d else paper[1]
                ax.plot([paper[0]], [py], "*", ms=13, mfc="#ffd33d" if on_slice else "none", mec="k", mew=1.0)
        if sub:
            ax.set_title(sub, fontsize=8)
    for p in range(len(panels), nrows * ncols):
        axes[p // ncols, p % ncols].set_visible(False)
    handles: list[Any] = [Patch(facecolor=col, edgecolor="0.5", label=lab) for _, lab, col in legend]
    handles += [Line2D([], [], marker=mk, ls="", color="k" if mk == "x" else "none", mec="k" if mk == "x" else "#cf222e",
                       mew=1.8 if mk != "x" else 1, ms=7, label=lab) for _, lab, mk in marks]
    if paper is not None:
        handles.append(Line2D([], [], marker="*", ls="", mfc="#ffd33d", mec="k", ms=11, label="paper's gains"))
    fig.legend(handles=handles, loc="outside lower center", ncols=min(4, len(handles)), fontsize=7, frameon=False)
    fig.suptitle(title, fontsize=10)
    return to_svg(fig)


def value_map(values: FloatArray, axes_info: Sequence[Axis], *, title: str, label: str,
              paper: Sequence[float] | None, log_colour: bool) -> bytes:
    """A continuous map (e.g. the certified/simulated ratio); NaN cells hatched grey."""
    from matplotlib.colors import LogNorm, Normalize

    finite = values[np.isfinite(values)]
    wide = finite.size and np.all(finite > 0) and float(finite.max() / finite.min()) >= 10.0
    if log_colour and wide:
        norm: Any = LogNorm(vmin=float(finite.min()), vmax=float(max(finite.max(), finite.min() * 1.0001)))
    else:
        lo = float(finite.min()) if finite.size else 0.0
        hi = float(finite.max()) if finite.size else 1.0
        norm = Normalize(vmin=lo, vmax=hi if hi > lo else lo + 1)
    panels = list(_panels(axes_info))
    nrows, ncols = _grid(len(panels))
    one_d = len(axes_info) == 1
    fig, axes = _new(2.6 if one_d else (3.3 if len(panels) == 1 else 2.5 * nrows + 0.6), ncols=ncols, nrows=nrows)
    x = axes_info[0]
    mesh = None
    for p, (k, sub) in enumerate(panels):
        ax = axes[p // ncols, p % ncols]
        ax.set_facecolor("#eeeeee")
        if one_d:
            ax.plot(x.values, values, "o-", color="C0", ms=3)
            ax.axhline(1.0, color="#cf222e", ls="--", lw=1, label="ratio 1: simulation reaches the bound")
            if log_colour and wide:
                ax.set_yscale("log")
            ax.set_ylabel(label)
            ax.legend(fontsize=7)
            if paper is not None:
                ax.axvline(paper[0], color="k", ls=":", lw=1)
        else:
            y = axes_info[1]
            grid = values if k is None else values[:, :, k]
            mesh = ax.pcolormesh(_edges(x.values, x.log), _edges(y.values, y.log), np.ma.masked_invalid(grid.T),
                                 cmap="viridis", norm=norm, edgecolors="white", linewidth=0.3)
            ax.set_ylabel(y.label)
            if y.log:
                ax.set_yscale("log")
            if paper is not None:
                on_slice = k is None or math.isclose(paper[2], axes_info[2].values[k], rel_tol=1e-9)
                ax.plot([paper[0]], [paper[1]], "*", ms=13, mfc="#ffd33d" if on_slice else "none", mec="k")
        if x.log:
            ax.set_xscale("log")
        ax.set_xlabel(x.label)
        if sub:
            ax.set_title(sub, fontsize=8)
    for p in range(len(panels), nrows * ncols):
        axes[p // ncols, p % ncols].set_visible(False)
    if mesh is not None:
        fig.colorbar(mesh, ax=axes.ravel().tolist(), label=label, shrink=0.9)
    fig.suptitle(title, fontsize=10)
    return to_svg(fig)
