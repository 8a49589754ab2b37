"""What every ``simulate --plot`` figure shares: a column of panels, time histories with the tail window
shaded, the phase plane, axes that clip at a view box, and a title that fits the figure.

The figures of :mod:`~lyapcheck.models.surfaces.simulate` (a continuous loop, its worst cases),
:mod:`~lyapcheck.models.surfaces.sampled_simulate` (a sampled-data loop) and
:mod:`~lyapcheck.models.surfaces.iterate` (a discrete-time map) differ in what they draw; the frame
around it is written here once. matplotlib is imported by the first figure (a run without ``--plot``
never loads it), always on the Agg backend (files only, no display).
"""

from __future__ import annotations

import textwrap
from typing import TYPE_CHECKING, Any, Final, Sequence

import numpy as np

if TYPE_CHECKING:  # pragma: no cover
    from numpy.typing import NDArray

#: figure width, inches (each caller chooses its panels' height)
FIGURE_WIDTH: Final = 8.5
#: the figure's height is the panels' plus this (the title's room), inches
TITLE_ROOM: Final = 0.6
#: the title's font size, pt, and the resolution of the saved PNG, dots per inch
TITLE_FONTSIZE: Final = 10
DPI: Final = 110
#: the title keeps this fraction of the figure's width free on each side
TITLE_MARGIN: Final = 0.02
#: rewrapping or shrinking a title that is still too wide stops after this many tries (each try
#: measures the text: a title wider than the figure after them keeps its last, smallest form)
TITLE_TRIES: Final = 8
#: a view clipped to a box shows the data's range within it, widened by this fraction on each side
VIEW_PAD: Final = 0.05


def new_figure(panels: int, panel_height: float) -> tuple[Any, Any]:
    """A figure of ``panels`` panels in one column (``axes[i, 0]``), on the Agg backend."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt.subplots(panels, 1, figsize=(FIGURE_WIDTH, panel_height * panels + TITLE_ROOM), squeeze=False)


def history_panel(ax: Any, tail: tuple[float, float], xlabel: str, ylabel: str, ylabel_size: float | None = None
                  ) -> None:
    """A time (or step) history's frame: the tail window ``tail`` shaded, the labels, a light grid."""
    ax.axvspan(tail[0], tail[1], color="0.85", alpha=0.5, lw=0)
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel, fontsize=ylabel_size)
    ax.grid(alpha=0.3)


def phase_plane(ax: Any, point: "Sequence[float] | NDArray[np.float64]", states: Sequence[str], *,
                label: str | None = None, title: str | None = None) -> None:
    """The phase plane's frame: the equilibrium (or fixed point) marked, the two states as labels, the
    title and the legend."""
    ax.plot(*[float(v) for v in point[:2]], "k+", ms=10, label=label)
    ax.set_xlabel(states[0])
    ax.set_ylabel(states[1])
    if title is not None:
        ax.set_title(title, fontsize=9)
    ax.grid(alpha=0.3)
    ax.legend(loc="upper right", fontsize=7)


def clip_view(ax: Any, axis: str, values: "NDArray[np.float64]", lo: float, hi: float) -> None:
    """Limit ``axis`` ("x" or "y") of ``ax`` to the finite ``values``' range within ``[lo, hi]`` (padded by
    :data:`VIEW_PAD`): what leaves the box is clipped at the axes by matplotlib, and a curve that leaves and
    comes back is drawn whole (a diverging row would otherwise flatten every other curve)."""
    if not lo < hi:  # no box to clip at: matplotlib's own limits
        return
    v = np.asarray(values, dtype=np.float64)
    v = v[np.isfinite(v)]
    low, high = (max(float(v.min()), lo), min(float(v.max()), hi)) if v.size else (lo, hi)
    if not low < high:  # one value (a row at rest), or nothing inside the box: the box itself
        low, high = lo, hi
    pad = VIEW_PAD * (high - low)
    (ax.set_xlim if axis == "x" else ax.set_ylim)(low - pad, high + pad)


def fit_title(fig: Any, text: str, fontsize: float = TITLE_FONTSIZE) -> Any:
    """The figure's title, wrapped at spaces (and, where one word is wider than the figure, its font
    shrunk) until its rendered extent fits the figure's width less :data:`TITLE_MARGIN` on each side:
    a long model name never pushes the title past the figure's edges, where a centred title is cut."""
    title = fig.suptitle(text, fontsize=fontsize)
    renderer = fig.canvas.get_renderer()
    room = fig.bbox.width * (1 - 2 * TITLE_MARGIN)
    shown, size = text, float(fontsize)
    for _ in range(TITLE_TRIES):
        width = title.get_window_extent(renderer).width
        if width <= room:
            break
        longest = max(len(line) for line in shown.split("\n"))
        chars = max(1, int(longest * room / width))
        wrapped = "\n".join(textwrap.fill(line, width=chars, break_long_words=False, break_on_hyphens=False)
                            for line in text.split("\n"))
        if max(len(line) for line in wrapped.split("\n")) < longest:
            shown = wrapped
        else:  # no space left to break at: a smaller font
            size *= room / width
        title.set_text(shown)
        title.set_fontsize(size)
    return title


def finish_figure(fig: Any, title: str, path: str) -> None:
    """Title the figure (:func:`fit_title`), lay its panels out below it, save it as a PNG and close it."""
    import matplotlib.pyplot as plt

    fit_title(fig, title)
    fig.tight_layout()  # (which keeps the title's lines clear of the panels)
    fig.savefig(path, dpi=DPI)
    plt.close(fig)


__all__ = ["new_figure", "history_panel", "phase_plane", "clip_view", "fit_title", "finish_figure"]
