"""What every sweep store's page shares: reading the store, its provenance, shares of a window, the map of boxes.

- :func:`open_store` loads a Zarr store with one-line errors;
- :func:`json_attr`, :func:`provenance`: the stored attributes (the spec and its SHA-256, the
  package versions), read without trusting them;
- :func:`window_percent`, :func:`value_range`: the page's numbers;
- :func:`box_map`: the leaves of a refinement tree over one or two parameters, one rectangle per
  leaf with the SVG id ``box-<row>-<status>`` (the paper's gains as a star where given), used by
  the box stores of the paper's loop and of model files alike.

Figures follow :mod:`reports.figures` (matplotlib's object interface, :func:`reports.figures.to_svg`).
"""

from __future__ import annotations

import hashlib
import json
import math
import warnings
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Final, Sequence

import numpy as np

from lyapcheck.errors import InputFileError
from reports import figures
from reports.views import fmt_float
from sweeps.schema import BOX_STATUS_CODES

#: the statuses a leaf can have, in the order the pages list them
LEAF_STATUSES: Final = ("certified", "not_certified", "refuted")
#: code -> status name, for leaves
LEAF_NAMES: Final = {BOX_STATUS_CODES[s]: s for s in LEAF_STATUSES}
#: empty margin around the drawn window, as a fraction of its extent in the axis's scale
VIEW_PAD: Final = 0.04
#: the hatched background of a partial store
NOT_COMPUTED_STYLE: Final[dict[str, Any]] = {"facecolor": "white", "edgecolor": "#8c959f", "hatch": "///", "lw": 0.0}


def open_store(path: str | Path) -> Any:
    """Open a sweep store (Zarr), with one-line errors for a missing or unreadable one."""
    import xarray as xr

    p = Path(path)
    if not p.exists():
        raise InputFileError(f"sweep store '{p}' does not exist")
    try:
        # zarr warns (e.g. an array directory without metadata) before it fails or skips: the
        # checks after loading say what is wrong in one line, so its warnings are not printed
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            return xr.open_zarr(p, consolidated=False).load()
    except Exception as exc:  # noqa: BLE001 - zarr/xarray raise many types for a corrupt store
        first = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
        raise InputFileError(f"'{p}' is not a readable sweep store (Zarr): {first}") from None


def mpl(text: str) -> str:
    """Text for a matplotlib label: a '$' from input must not switch on mathtext."""
    return text.replace("$", r"\$")


def json_attr(ds: Any, key: str) -> tuple[Any, str]:
    """(parsed JSON attribute or None, raw text)."""
    raw = ds.attrs.get(key)
    if raw is None:
        return None, ""
    text = raw if isinstance(raw, str) else json.dumps(raw, default=str)
    try:
        return json.loads(text), text
    except (json.JSONDecodeError, TypeError):
        return None, text


def provenance(ds: Any) -> dict[str, Any]:
    """The reproducibility block's entries: the stored spec, its SHA-256, the package versions."""
    versions_raw, versions_text = json_attr(ds, "versions")
    spec = ds.attrs.get("spec_toml", "")
    spec_text = spec if isinstance(spec, str) else json.dumps(spec, default=str)
    return {
        "spec_toml": spec_text,
        "spec_hash": hashlib.sha256(spec_text.encode()).hexdigest(),
        "versions": ({str(k): str(v) for k, v in versions_raw.items()} if isinstance(versions_raw, dict)
                     else ({"versions": versions_text} if versions_text else {})),
    }


def window_percent(share: float) -> str:
    """A share of the window for reading; a tiny non-zero share is not rounded to 0 %."""
    if 0 < share < 0.0005:
        return "< 0.1 %"
    return f"{100 * share:.1f} %"


def value_range(values: np.ndarray, unit: str = "") -> str:
    """``min … max`` of the finite values (a dash when there are none)."""
    finite = values[np.isfinite(values)]
    if not finite.size:
        return "—"
    return f"{fmt_float(float(finite.min()), 4)} … {fmt_float(float(finite.max()), 4)}{unit}"


@dataclass(frozen=True)
class BoxAxis:
    """A swept parameter of a box store, in display units (``factor`` from SI)."""

    name: str
    label: str
    factor: float
    scale: str  # "log" or "linear": how the summary measures it and how it is drawn
    window: tuple[float, float]  # SI

    @property
    def log(self) -> bool:
        return self.scale == "log"


@dataclass(frozen=True)
class Leaves:
    """The drawable leaves of the tree: store rows, status codes and edges (display units)."""

    rows: np.ndarray
    codes: np.ndarray
    lo: np.ndarray  # (n, dims)
    hi: np.ndarray


def view(lo: float, hi: float, log: bool) -> tuple[float, float]:
    """Limits around ``[lo, hi]`` with a small margin, measured in the axis's own scale."""
    if log:
        a, b = math.log10(lo), math.log10(hi)
        pad = VIEW_PAD * (b - a)
        return 10 ** (a - pad), 10 ** (b + pad)
    pad = VIEW_PAD * (hi - lo)
    return lo - pad, hi + pad


def extent(ax: BoxAxis, paper: float | None) -> tuple[float, float]:
    """The window in display units, widened to the paper's value so that its marker is always shown."""
    lo, hi = ax.window[0] * ax.factor, ax.window[1] * ax.factor
    if paper is not None:
        lo, hi = min(lo, paper), max(hi, paper)
    return view(lo, hi, ax.log)


def box_map(axes: Sequence[BoxAxis], leaves: Leaves, paper: Sequence[float] | None, *, partial: bool,
            title: str) -> bytes:
    """SVG of the leaves over one or two swept parameters (one rectangle per leaf, id ``box-<row>-<status>``).

    With one parameter the boxes are intervals drawn as a strip; the window is outlined, the paper's
    gains (when given) are a star, and the part of the window a partial store has not covered yet is
    hatched. ``title`` is matplotlib text (pass input through :func:`mpl`).
    """
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch, Rectangle

    one_d = len(axes) == 1
    # figures._new: the same column width and constrained layout as every figure of the reports
    fig, grid = figures._new(1.9 if one_d else 3.6)
    ax = grid[0, 0]
    x = axes[0]
    y_lo, y_hi = (0.0, 1.0) if one_d else (axes[1].window[0] * axes[1].factor, axes[1].window[1] * axes[1].factor)
    x_lo, x_hi = x.window[0] * x.factor, x.window[1] * x.factor
    if partial:  # under the leaves: what shows through is the window not computed yet
        ax.add_patch(Rectangle((x_lo, y_lo), x_hi - x_lo, y_hi - y_lo, zorder=0, gid="not-computed",
                               **NOT_COMPUTED_STYLE))
    for row, code, lo, hi in zip(leaves.rows, leaves.codes, leaves.lo, leaves.hi):
        name = LEAF_NAMES.get(int(code), "not_certified")
        b_lo, b_hi = (0.0, 1.0) if one_d else (lo[1], hi[1])
        ax.add_patch(Rectangle((lo[0], b_lo), hi[0] - lo[0], b_hi - b_lo, facecolor=figures.STATUS_COLOURS[name],
                               edgecolor="white", lw=0.4, zorder=1, gid=f"box-{int(row)}-{name}"))
    ax.add_patch(Rectangle((x_lo, y_lo), x_hi - x_lo, y_hi - y_lo, fill=False, edgecolor="k", lw=0.8, zorder=2,
                           gid="window"))
    if x.log:
        ax.set_xscale("log")
    ax.set_xlim(*extent(x, None if paper is None else paper[0]))
    ax.set_xlabel(x.label)
    if one_d:
        ax.set_ylim(-0.15, 1.15)
        ax.set_yticks([])
    else:
        y = axes[1]
        if y.log:
            ax.set_yscale("log")
        ax.set_ylim(*extent(y, None if paper is None else paper[1]))
        ax.set_ylabel(y.label)
    if paper is not None:
        ax.plot([paper[0]], [0.5 if one_d else paper[1]], "*", ms=13, mfc="#ffd33d", mec="k", mew=1.0, zorder=3,
                gid="paper-point")
    present = [s for s in LEAF_STATUSES if np.any(leaves.codes == BOX_STATUS_CODES[s])] or ["certified"]
    handles: list[Any] = [Patch(facecolor=figures.STATUS_COLOURS[s], edgecolor="0.5", label=s.replace("_", " "))
                          for s in present]
    if partial:
        handles.append(Patch(label="not computed", **{**NOT_COMPUTED_STYLE, "lw": 0.5}))
    if paper is not None:
        handles.append(Line2D([], [], marker="*", ls="", mfc="#ffd33d", mec="k", ms=11, label="paper's gains"))
    fig.legend(handles=handles, loc="outside lower center", ncols=min(5, len(handles)), fontsize=7, frameon=False)
    fig.suptitle(title, fontsize=10)
    return figures.to_svg(fig)


__all__ = ["LEAF_STATUSES", "LEAF_NAMES", "BoxAxis", "Leaves", "open_store", "mpl", "json_attr", "provenance",
           "window_percent", "value_range", "view", "extent", "box_map"]
