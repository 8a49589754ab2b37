"""What every figure of the reports shares, and the region maps of sweep stores.

Figures are drawn with matplotlib's object interface and returned as SVG bytes. The figures of
one kind of page live with it: the paper's closed loop in :mod:`reports.paper_figures`, a model
file's phase portrait in :mod:`reports.phase_portrait`.

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
# closed curves (certified sets of the phase portraits)
# ----------------------------------------------------------------------------------------------
#: a certified set's boundary is drawn with this many points, evenly spaced along it (at the set's
#: own proportions): a smooth curve this fine deviates from the computed one by about a thousandth
#: of the panel, while the computed contour (about 1400 points at the paper's gains) would cost
#: 35 kB per fill, which matplotlib does not simplify (closed paths)
DRAW_POINTS = 240


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
