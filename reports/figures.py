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
from dataclasses import dataclass
from typing import Any, Iterator, Sequence

import numpy as np
import numpy.typing as npt

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
    """One figure: SVG bytes, a caption (plain text, escaped by the template) and alt text."""

    svg: bytes
    caption: str
    alt: str


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
    return buf.getvalue()


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


def eps_figure(run: Any, eps_bound_m: float | None) -> Figure:
    """Cross-track error over time, linear and logarithmic, against the certified bound."""
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
    if eps_bound_m is not None and math.isfinite(eps_bound_m):
        for a in axes[:, 0]:
            a.axhline(eps_bound_m * 1e3, color="C2", ls="--", lw=1.2)
        axes[0, 0].axhline(-eps_bound_m * 1e3, color="C2", ls="--", lw=1.2)
        ax.axhline(eps_bound_m * 1e3, color="C2", ls="--", lw=1.2, label="certified ultimate bound")
    ax.axvspan(tail0, run.horizon_s, color="C1", alpha=0.15, lw=0, label="tail window")
    ax.set_xlabel("t (s)")
    ax.set_ylabel(r"$|\varepsilon|$ (mm, log)")
    ax.grid(alpha=0.3, which="both")
    ax.legend(loc="upper right", fontsize=8)
    bound = "" if eps_bound_m is None else f"; certified ultimate bound {eps_bound_m * 1e3:.4g} mm (dashed green)"
    cap = (f"Cross-track error from the paper's start: sup |eps| over the tail window {tail0:g}-{run.horizon_s:g} s "
           f"= {m['sup_abs_eps_tail_m'] * 1e3:.4g} mm{bound}.")
    return Figure(to_svg(fig), cap, "cross-track error over time, linear and logarithmic")


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


def ellipse_points(P: FloatArray, n: int = 361) -> FloatArray:
    """Boundary of ``{x : x^T P x <= 1}`` for a 2x2 positive definite ``P`` (rows of points)."""
    w, v = np.linalg.eigh(P)
    t = np.linspace(0.0, 2 * math.pi, n)
    return (v @ (np.vstack([np.cos(t), np.sin(t)]) / np.sqrt(w)[:, None])).T


def phase_figure(run: Any, ellipse_P: FloatArray | None, box: tuple[float, float] | None,
                 note: str) -> Figure:
    """The (eps, s) phase portrait with the certified set: the ellipsoid, or else the box.

    A second panel zooms on the certified set when it is small beside the transient.
    """
    eps_all = np.concatenate([tr.eps for tr in run.trajectories])
    s_all = np.concatenate([tr.s for tr in run.trajectories])
    shape: FloatArray | None = None
    if ellipse_P is not None:
        shape = ellipse_points(ellipse_P)
    elif box is not None:
        e, s = box
        shape = np.array([[-e, -s], [e, -s], [e, s], [-e, s], [-e, -s]])
    span_traj = np.array([np.ptp(eps_all), np.ptp(s_all)])
    zoom = shape is not None and bool(np.all(np.ptp(shape, axis=0) < 0.2 * np.maximum(span_traj, 1e-300)))
    fig, axes = _new(3.6, ncols=2 if zoom else 1)
    label = "certified ellipsoid $x^T P x \\leq 1$" if ellipse_P is not None else "certified box"

    def draw(ax: Any, tail_only: bool) -> None:
        for k, tr in enumerate(run.trajectories):
            sel = tr.t >= (run.horizon_s - run.tail_s - 20.0) if tail_only else slice(None)
            ax.plot(tr.eps[sel] * 1e3, tr.s[sel] * 1e3, color="C0" if k == 0 else "0.55", lw=1.2 if k == 0 else 0.8,
                    label=("trajectories" if k == 0 else None), zorder=3)
            if not tail_only:
                ax.plot(tr.eps[0] * 1e3, tr.s[0] * 1e3, "o", ms=3.5, color="C3", zorder=4)
            ax.plot(tr.eps[-1] * 1e3, tr.s[-1] * 1e3, "s", ms=3.5, color="k", zorder=4)
        if shape is not None:
            ax.fill(shape[:, 0] * 1e3, shape[:, 1] * 1e3, color="C2", alpha=0.18, lw=0, zorder=1)
            ax.plot(shape[:, 0] * 1e3, shape[:, 1] * 1e3, color="C2", lw=1.4, label=label, zorder=2)
        if ellipse_P is not None and box is not None and not tail_only:
            e, s = box
            ax.plot(np.array([-e, e, e, -e, -e]) * 1e3, np.array([-s, -s, s, s, -s]) * 1e3, color="C2", ls=":",
                    lw=1, label="certified box (stage 0)")
        ax.set_xlabel(r"$\varepsilon$ (mm)")
        ax.set_ylabel("$s$ (mm)")
        ax.grid(alpha=0.3)

    draw(axes[0, 0], tail_only=False)
    axes[0, 0].legend(loc="best", fontsize=7)
    if zoom and shape is not None:
        ax = axes[0, 1]
        draw(ax, tail_only=True)
        lo, hi = shape.min(axis=0), shape.max(axis=0)
        pts = np.vstack([shape] + [np.column_stack([tr.eps[-40:], tr.s[-40:]]) for tr in run.trajectories])
        lo, hi = np.minimum(lo, pts.min(axis=0)), np.maximum(hi, pts.max(axis=0))
        pad = 0.15 * (hi - lo)
        ax.set_xlim((lo[0] - pad[0]) * 1e3, (hi[0] + pad[0]) * 1e3)
        ax.set_ylim((lo[1] - pad[1]) * 1e3, (hi[1] + pad[1]) * 1e3)
        ax.set_title("zoom on the certified set", fontsize=9)
    cap = ("Phase portrait in (eps, s): circles mark the starts, squares the states at "
           f"{run.horizon_s:g} s; the green set is the {label.split(' $')[0]}. " + note)
    return Figure(to_svg(fig), cap, "phase portrait of the cross-track error against the integral state "
                                    "with the certified set drawn")


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
