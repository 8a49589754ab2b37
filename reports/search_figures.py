"""The figures of a search's report: ``lyapcheck tune``'s box map and its objective along the search,
and the values ``certify --maximize/--minimize`` tried.

Each figure draws what the certificate's search table states (:mod:`reports.subjects.search` reads
it), through :mod:`reports.figures` (matplotlib's object interface, compact SVG). Every artist a
reader or a test looks for has an SVG id (``gid``): ``search-box``, ``winner``, ``neighbourhood``,
``neighbourhood-try-<i>`` (a box tried around the winner and not proved), ``tried-grid`` and
``tried-refine`` (the points whose figure was proved), ``unproved-refuted`` and ``unproved-other``,
``best-so-far``; for a bisection ``step-proved``, ``step-refuted``, ``step-not-proved``, ``proved``,
``failed`` and ``gap``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Final, Sequence

from lyapcheck.models.language.parameter_box import box_text, interval_ends
from reports import figures
from reports.figures import Figure
from reports.stores.common import mpl

#: the marker of each phase of a tune search
PHASE_MARKERS: Final = {"grid": "o", "refine": "D"}
#: a point whose figure was not proved: refuted (a question answered negatively) or anything else
REFUTED_COLOUR: Final = figures.STATUS_COLOURS["refuted"]
UNPROVED_COLOUR: Final = "#6e7781"
PROVED_COLOUR: Final = figures.STATUS_COLOURS["certified"]
WINNER_FACE: Final = "#ffd33d"
#: the certified neighbourhood's colour (the certified green, as a light fill)
NEIGHBOURHOOD_ALPHA: Final = 0.15


@dataclass(frozen=True)
class Tried:
    """One point a tune search tried: its values (one per parameter, in the box's order), its phase,
    its proved figure (None: not proved) and its outcome's word."""

    values: tuple[float, ...]
    phase: str
    value: float | None
    outcome: str

    @property
    def refuted(self) -> bool:
        return self.outcome.startswith("refuted")


def _margin(lo: float, hi: float, share: float = 0.06) -> tuple[float, float]:
    pad = (hi - lo) * share if hi > lo else max(abs(lo), 1.0) * share
    return lo - pad, hi + pad


def _unproved(ax: Any, xs: Sequence[float], ys: Sequence[float] | None, refuted: Sequence[bool]) -> None:
    """Points without a proved figure: crosses (red: refuted; grey: not proved), on the axis's floor when
    they have no y (a 1-parameter map, the objective's trace)."""
    from matplotlib.transforms import blended_transform_factory

    for flag, colour, gid in ((True, REFUTED_COLOUR, "unproved-refuted"), (False, UNPROVED_COLOUR, "unproved-other")):
        pick = [i for i, r in enumerate(refuted) if r == flag]
        if not pick:
            continue
        px = [xs[i] for i in pick]
        if ys is None:
            ax.plot(px, [0.04] * len(px), "x", color=colour, ms=7, mew=1.6, zorder=4, gid=gid,
                    transform=blended_transform_factory(ax.transData, ax.transAxes), clip_on=False)
        else:
            ax.plot(px, [ys[i] for i in pick], "x", color=colour, ms=7, mew=1.6, zorder=4, gid=gid)


def _legend(fig: Any, has: dict[str, bool], neighbourhood: bool, tries: bool) -> None:
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch

    handles: list[Any] = []
    if has.get("grid"):
        handles.append(Line2D([], [], marker="o", ls="", color="0.35", ms=6, label="grid point, figure proved"))
    if has.get("refine"):
        handles.append(Line2D([], [], marker="D", ls="", color="0.35", ms=5, label="refinement, figure proved"))
    if has.get("refuted"):
        handles.append(Line2D([], [], marker="x", ls="", color=REFUTED_COLOUR, mew=1.6, ms=7, label="refuted"))
    if has.get("other"):
        handles.append(Line2D([], [], marker="x", ls="", color=UNPROVED_COLOUR, mew=1.6, ms=7, label="not proved"))
    if has.get("winner"):
        handles.append(Line2D([], [], marker="*", ls="", mfc=WINNER_FACE, mec="k", ms=12, label="winner"))
    if neighbourhood:
        handles.append(Patch(facecolor=PROVED_COLOUR, alpha=0.3, edgecolor=PROVED_COLOUR, ls="--",
                             label="certified neighbourhood"))
    if tries:
        handles.append(Patch(fill=False, edgecolor=UNPROVED_COLOUR, ls=":", label="neighbourhood tried, not proved"))
    fig.legend(handles=handles, loc="outside lower center", ncols=min(4, max(1, len(handles))), fontsize=7,
               frameon=False)


def box_map(names: Sequence[str], box: Sequence[tuple[float, float]], tried: Sequence[Tried], winner: int | None,
            neighbourhood: Sequence[tuple[float, float]] | None, failed_tries: Sequence[Sequence[tuple[float, float]]],
            *, label: str, sense: str, title: str, neighbourhood_value: float | None = None) -> Figure:
    """The searched box with every point tried, the winner and its certified neighbourhood.

    Two or more parameters: the first two as axes (more are projected, and the caption says so), each
    proved point coloured by its figure (better is always yellow: ``viridis`` for a maximized figure,
    reversed for a minimized one), the neighbourhood a dashed rectangle. One parameter: a line plot of
    the figure against it, the neighbourhood a band with its proved figure as a dashed segment.

    Parameters
    ----------
    winner
        The index in ``tried`` of the winner (None: no winner).
    neighbourhood
        Its box, one interval per parameter (None: none certified); ``neighbourhood_value`` its figure.
    failed_tries
        The boxes tried around the winner that were not proved.
    """
    from matplotlib.colors import Normalize
    from matplotlib.patches import Rectangle

    one_d = len(names) == 1
    fig, grid = figures._new(2.9 if one_d else 3.9)
    ax = grid[0, 0]
    proved = [i for i, p in enumerate(tried) if p.value is not None]
    unproved = [i for i, p in enumerate(tried) if p.value is None]
    has = {"grid": any(tried[i].phase == "grid" for i in proved), "refine": any(tried[i].phase == "refine" for i in proved),
           "refuted": any(tried[i].refuted for i in unproved), "other": any(not tried[i].refuted for i in unproved),
           "winner": winner is not None}
    (x_lo, x_hi) = box[0]
    if one_d:
        for edge in (x_lo, x_hi):
            ax.axvline(edge, color="k", lw=0.8, ls=":", gid="search-box")
        for n, tried_box in enumerate(failed_tries):
            ax.axvspan(tried_box[0][0], tried_box[0][1], fill=False, edgecolor=UNPROVED_COLOUR, ls=":", lw=0.8,
                       gid=f"neighbourhood-try-{n}")
        if neighbourhood is not None:
            ax.axvspan(neighbourhood[0][0], neighbourhood[0][1], color=PROVED_COLOUR, alpha=NEIGHBOURHOOD_ALPHA, lw=0,
                       gid="neighbourhood")
            if neighbourhood_value is not None:
                ax.hlines(neighbourhood_value, neighbourhood[0][0], neighbourhood[0][1], colors=PROVED_COLOUR, ls="--",
                          lw=1.2, gid="neighbourhood-figure")
        order = sorted(proved, key=lambda i: tried[i].values[0])
        if order:
            ax.plot([tried[i].values[0] for i in order], [tried[i].value for i in order], "-", color="0.7", lw=0.8)
        for phase, marker in PHASE_MARKERS.items():
            pick = [i for i in proved if tried[i].phase == phase]
            if pick:
                ax.plot([tried[i].values[0] for i in pick], [tried[i].value for i in pick], marker, color="C0",
                        ms=6 if marker == "o" else 5, zorder=3, gid=f"tried-{phase}")
        _unproved(ax, [tried[i].values[0] for i in unproved], None, [tried[i].refuted for i in unproved])
        if winner is not None and tried[winner].value is not None:
            ax.plot([tried[winner].values[0]], [tried[winner].value], "*", ms=16, mfc=WINNER_FACE, mec="k", zorder=5,
                    gid="winner")
        ax.set_xlim(*_margin(x_lo, x_hi))
        ax.margins(y=0.15)  # the winner's star at the lowest or highest figure stays whole
        ax.set_ylabel(mpl(label))
    else:
        (y_lo, y_hi) = box[1]
        ax.add_patch(Rectangle((x_lo, y_lo), x_hi - x_lo, y_hi - y_lo, fill=False, edgecolor="k", lw=0.8, ls=":",
                               zorder=1, gid="search-box"))
        for n, tried_box in enumerate(failed_tries):
            (a, b), (c, d) = tried_box[0], tried_box[1]
            ax.add_patch(Rectangle((a, c), b - a, d - c, fill=False, edgecolor=UNPROVED_COLOUR, ls=":", lw=0.8,
                                   zorder=1, gid=f"neighbourhood-try-{n}"))
        if neighbourhood is not None:
            (a, b), (c, d) = neighbourhood[0], neighbourhood[1]
            ax.add_patch(Rectangle((a, c), b - a, d - c, facecolor=PROVED_COLOUR, alpha=NEIGHBOURHOOD_ALPHA, lw=0,
                                   zorder=1))
            ax.add_patch(Rectangle((a, c), b - a, d - c, fill=False, edgecolor=PROVED_COLOUR, ls="--", lw=1.4,
                                   zorder=2, gid="neighbourhood"))
        values = [v for v in (tried[i].value for i in proved) if v is not None]
        lo_v, hi_v = (min(values), max(values)) if values else (0.0, 1.0)
        norm = Normalize(vmin=lo_v, vmax=hi_v if hi_v > lo_v else lo_v + max(abs(lo_v), 1.0) * 1e-6)
        cmap = "viridis" if sense == "max" else "viridis_r"
        mappable = None
        for phase, marker in PHASE_MARKERS.items():
            pick = [i for i in proved if tried[i].phase == phase]
            if pick:
                mappable = ax.scatter([tried[i].values[0] for i in pick], [tried[i].values[1] for i in pick],
                                      c=[tried[i].value for i in pick], cmap=cmap, norm=norm, marker=marker,
                                      s=46 if marker == "o" else 36, edgecolors="k", linewidths=0.5, zorder=3,
                                      gid=f"tried-{phase}")
        _unproved(ax, [tried[i].values[0] for i in unproved], [tried[i].values[1] for i in unproved],
                  [tried[i].refuted for i in unproved])
        if winner is not None:
            ax.plot([tried[winner].values[0]], [tried[winner].values[1]], "*", ms=18, mfc=WINNER_FACE, mec="k",
                    mew=1.0, zorder=5, gid="winner")
        if mappable is not None:
            fig.colorbar(mappable, ax=ax, label=mpl(label), shrink=0.9)
        ax.set_xlim(*_margin(x_lo, x_hi))
        ax.set_ylim(*_margin(y_lo, y_hi))
        ax.set_ylabel(mpl(names[1]))
    ax.set_xlabel(mpl(names[0]))
    _legend(fig, has, neighbourhood is not None, bool(failed_tries))
    fig.suptitle(mpl(title), fontsize=10)
    shown = box_text(((n, lo, hi) for n, (lo, hi) in zip(names, box)), " x ")
    if one_d:
        caption = (f"The figure proved at each point tried over {shown} (a line between the proved points only "
                   "guides the eye: nothing is claimed between them). The star is the winner"
                   + ("; the green band is the certified neighbourhood, the dashed segment the figure its box "
                      "certificate proves for every value in it" if neighbourhood is not None else "")
                   + "; crosses on the floor are points whose figure was not proved.")
    else:
        caption = (f"The search box {shown}: each point tried, coloured by the figure proved there (yellow is "
                   "better), the star the winner"
                   + ("; the dashed green rectangle the certified neighbourhood, where one box certificate "
                      "proves the figure for every gain in it" if neighbourhood is not None else "")
                   + ("; dotted grey boxes were tried around the winner and not proved" if failed_tries else "")
                   + "; crosses are points whose figure was not proved (red: refuted).")
        if len(names) > 2:
            caption += (f" Projected onto {names[0]} and {names[1]}: the other parameters' values are in the table "
                        "below.")
    data: dict[str, Any] = {"points": len(tried), "proved": len(proved),
                            "winner": None if winner is None else list(tried[winner].values),
                            "neighbourhood": None if neighbourhood is None else [list(b) for b in neighbourhood],
                            "projected": len(names) > 2}
    return Figure(figures.to_svg(fig), caption, f"Box map of the search over {shown}", data)


def objective_trace(tried: Sequence[Tried], winner: int | None, *, label: str, sense: str, title: str) -> Figure:
    """The figure proved at each attempt, in the order tried, with the best so far as a step line; the
    refinement's attempts after a dotted line."""
    from matplotlib.transforms import blended_transform_factory

    fig, grid = figures._new(2.6)
    ax = grid[0, 0]
    n = len(tried)
    xs = list(range(1, n + 1))
    best: list[float] = []
    so_far: float | None = None
    for p in tried:
        if p.value is not None and (so_far is None or (p.value > so_far if sense == "max" else p.value < so_far)):
            so_far = p.value
        best.append(math.nan if so_far is None else so_far)
    if any(not math.isnan(b) for b in best):
        ax.step(xs, best, where="post", color=PROVED_COLOUR, lw=1.3, gid="best-so-far",
                label="best so far" + (" (largest)" if sense == "max" else " (smallest)"))
    for phase, marker in PHASE_MARKERS.items():
        pick = [i for i, p in enumerate(tried) if p.value is not None and p.phase == phase]
        if pick:
            ax.plot([xs[i] for i in pick], [tried[i].value for i in pick], marker, color="C0",
                    ms=6 if marker == "o" else 5, zorder=3, gid=f"tried-{phase}",
                    label="grid point" if phase == "grid" else "refinement")
    unproved = [i for i, p in enumerate(tried) if p.value is None]
    _unproved(ax, [xs[i] for i in unproved], None, [tried[i].refuted for i in unproved])
    first_refine = next((i for i, p in enumerate(tried) if p.phase == "refine"), None)
    if first_refine is not None:
        ax.axvline(first_refine + 0.5, color="0.5", ls=":", lw=0.8)
        ax.text(first_refine + 0.6, 0.95, "refinement", transform=blended_transform_factory(ax.transData, ax.transAxes),
                fontsize=7, va="top", color="0.35")
    if winner is not None and tried[winner].value is not None:
        ax.plot([xs[winner]], [tried[winner].value], "*", ms=15, mfc=WINNER_FACE, mec="k", zorder=5, gid="winner",
                label="winner")
    ax.set_xlim(0.5, n + 0.5)
    ax.margins(y=0.15)
    ax.set_xticks(xs if n <= 30 else xs[:: max(1, n // 15)])
    ax.set_xlabel("attempt, in the order tried")
    ax.set_ylabel(mpl(label))
    if ax.get_legend_handles_labels()[0]:
        ax.legend(fontsize=7, loc="best")
    fig.suptitle(mpl(title), fontsize=10)
    caption = ("The objective's figure at each attempt (crosses on the floor: not proved, red when refuted) and the "
               "best figure proved so far. Each figure was proved at its own point when it was tried; the winner "
               "was then certified again, and that certificate is this document.")
    return Figure(figures.to_svg(fig), caption, "The objective's value along the search",
                  {"best_so_far": best, "attempts": n})


#: a bisection step's marker, colour and SVG id by its outcome
STEP_STYLE: Final = {"proved": ("o", PROVED_COLOUR, "step-proved"), "refuted": ("x", REFUTED_COLOUR, "step-refuted"),
                     "not proved": ("s", UNPROVED_COLOUR, "step-not-proved")}


def bisection(parameter: str, direction: str, low: float, high: float, steps: Sequence[tuple[float, str]],
              proved: float | None, failed: float | None, *, title: str) -> Figure:
    """The values ``certify --maximize/--minimize`` tried, in order, each marked by its outcome, with the
    proved value, the first value that failed and the gap between them (not decided)."""
    fig, grid = figures._new(2.8)
    ax = grid[0, 0]
    xs = list(range(1, len(steps) + 1))
    ax.plot(xs, [v for v, _ in steps], "-", color="0.75", lw=0.8)
    for outcome, (marker, colour, gid) in STEP_STYLE.items():
        pick = [i for i, (_, o) in enumerate(steps) if o == outcome]
        if pick:
            ax.plot([xs[i] for i in pick], [steps[i][0] for i in pick], marker, ms=6, zorder=3, gid=gid, label=outcome,
                    **({"color": colour, "mew": 1.6} if marker == "x" else {"mfc": colour, "mec": "k", "mew": 0.5}))
    if proved is not None:
        ax.axhline(proved, color=PROVED_COLOUR, lw=1.2, gid="proved", label=f"proved: {proved:.6g}")
    if failed is not None:
        ax.axhline(failed, color=REFUTED_COLOUR, lw=1.0, ls="--", gid="failed", label=f"first failed: {failed:.6g}")
    if proved is not None and failed is not None:
        ax.axhspan(min(proved, failed), max(proved, failed), color="0.5", alpha=0.15, lw=0, gid="gap")
    for edge in (low, high):
        ax.axhline(edge, color="k", lw=0.6, ls=":")
    ax.set_ylim(*_margin(low, high))
    ax.set_xlim(0.5, len(steps) + 0.5)
    ax.set_xticks(xs)
    ax.set_xlabel("value tried, in the order tried")
    ax.set_ylabel(mpl(parameter))
    ax.legend(fontsize=7, loc="best")
    fig.suptitle(mpl(title), fontsize=10)
    word = "largest" if direction == "max" else "smallest"
    caption = (f"Each value of {parameter} tried in [{', '.join(interval_ends(low, high))}], in order, with its outcome: proved "
               "(certify succeeds there, exactly), refuted (a question answered negatively, exactly) or not proved. "
               f"The {word} value proved and the first value that failed beyond it bound the answer; the grey band "
               "between them was not decided.")
    return Figure(figures.to_svg(fig), caption, f"The values of {parameter} tried",
                  {"values": [v for v, _ in steps], "proved": proved, "failed": failed})


__all__ = ["Tried", "box_map", "objective_trace", "bisection", "PHASE_MARKERS", "STEP_STYLE"]
