"""The frame every ``simulate --plot`` figure shares (:mod:`lyapcheck.models.surfaces.plotting`): a title
that stays whole inside the figure however long the model's name, and a sampled-data loop's trajectory
drawn whole when it leaves the view and comes back (the axes clip it, not the data)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pytest

from tests.test_sampled_simulate import DOUBLE_INTEGRATOR

#: a name long enough that the title on one line is wider than the figure (asserted below)
LONG_NAME = "a linear loop whose name is " + "very " * 20 + "long indeed"

LINEAR = f"""
[model]
name = "{LONG_NAME}"
states = ["x1", "x2"]

[dynamics]
x1 = "x2"
x2 = "-x1 - x2"

[outputs]
y = "x1"
"""

#: x'' = -x - x' sampled every 0.1 s (test_sampled_simulate's loop): from x = 0.05, v = 1 the position swings
#: out to about 0.5 and back to 0, while its state scale is the start's 0.05 (the view box: PLOT_CLIP = 2
#: scales, x in [-0.1, 0.1])
SAMPLED = DOUBLE_INTEGRATOR


@pytest.fixture
def saved(monkeypatch: pytest.MonkeyPatch) -> list[Any]:
    """Every figure saved, kept after it is closed (its artists stay readable)."""
    from matplotlib.figure import Figure

    figures: list[Any] = []
    save = Figure.savefig

    def keep(self: Any, *args: Any, **kwargs: Any) -> None:
        save(self, *args, **kwargs)
        figures.append(self)

    monkeypatch.setattr(Figure, "savefig", keep)
    return figures


def renderer_of(fig: Any) -> Any:
    """A renderer for a saved figure (closing it left it a canvas that cannot measure text)."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    return FigureCanvasAgg(fig).get_renderer()


def test_a_long_title_lies_whole_inside_the_figure(tmp_path: Path, saved: list[Any]) -> None:
    from lyapcheck.api import simulate

    path = tmp_path / "long.toml"
    path.write_text(LINEAR)
    plot = tmp_path / "long.png"
    simulate(model=path, x0={"x1": 1.0}, t_end=5.0, plot=plot, series=False)
    assert plot.stat().st_size > 10_000
    (fig,) = saved
    title = fig._suptitle
    renderer = renderer_of(fig)
    box, frame = title.get_window_extent(renderer), fig.bbox
    assert frame.x0 <= box.x0 and box.x1 <= frame.x1 and frame.y0 <= box.y0 and box.y1 <= frame.y1
    assert LONG_NAME in title.get_text().replace("\n", " ")  # wrapped at spaces, nothing dropped
    # the case is real: the same title on one line at the usual size is wider than the figure
    whole = fig.text(0.5, 0.5, title.get_text().replace("\n", " "), fontsize=10, ha="center")
    assert whole.get_window_extent(renderer).width > frame.width
    # and the panels stay below the title
    assert all(ax.get_window_extent(renderer).y1 <= box.y0 + 1 for ax in fig.axes)


def test_a_short_title_is_left_on_one_line_at_its_size(tmp_path: Path, saved: list[Any]) -> None:
    from lyapcheck.models.surfaces.plotting import TITLE_FONTSIZE, finish_figure, new_figure

    fig, _ = new_figure(1, 3.0)
    finish_figure(fig, "lyapcheck simulate: short", str(tmp_path / "short.png"))
    assert fig._suptitle.get_text() == "lyapcheck simulate: short"
    assert fig._suptitle.get_fontsize() == TITLE_FONTSIZE


def test_a_sampled_trajectory_that_leaves_the_view_and_comes_back_is_drawn_whole(tmp_path: Path,
                                                                                  saved: list[Any]) -> None:
    from lyapcheck.api import simulate

    path = tmp_path / "sampled.toml"
    path.write_text(SAMPLED)
    result = simulate(model=path, x0={"x": 0.05, "v": 1.0}, t_end=20.0, plot=tmp_path / "s.png", series=False)
    assert result.document["state_scale"]["x"] == pytest.approx(0.05)
    (fig,) = saved
    ax = fig.axes[0]  # x against time
    t, x = (np.asarray(v, dtype=float) for v in ax.lines[0].get_data())
    low, high = ax.get_ylim()
    assert not np.isnan(x).any() and t[-1] == pytest.approx(20.0)  # the whole horizon, nothing cut
    assert x.max() > 4 * high  # it leaves the view (about 0.5 against 0.1) ...
    outside = np.flatnonzero(x > high)
    assert abs(x[-1]) < high and outside[-1] < len(x) - 1  # ... and is drawn again after it comes back
    assert low < 0.05 < high  # the view is the clip box around the equilibrium, not the excursion
