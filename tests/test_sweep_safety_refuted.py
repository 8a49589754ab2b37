"""A box sweep's safety class refuted at a value of a box (issue 44, found not fixed): the box is ``refuted``, not
split for that class, and counted in the summary's ``refuted``.

What is asserted. On ``examples/models/discrete-unsafe-map.toml`` with its gain ``0.3`` made a parameter ``a``
(the start ``(3, 0)`` maps into the unsafe disc around ``(0.9, 0.5)`` for ``a`` near ``0.3``), swept over two boxes
of ``a`` with ``barrier``: both are refuted at a value of the box (the falsification's iterate, proved exactly);
each is stored ``refuted`` overall and for ``barrier``, its note names the value, neither is split although both are
wider than ``min_relative_width`` and the budget allows halves, and the summary counts two refuted leaves. The
split rule itself (:func:`sweeps.run.model_box_tree`): a refuted box is still split while another class over it is
open (a safety class not refuted beside a refuted one; a stability class with a corner not unstable, as before),
and not when every class is refuted (every corner unstable for the stability classes).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from sweeps.schema import BOX_STATUS_CODES, STATUS_CODES

EXAMPLES = Path(__file__).resolve().parents[1] / "examples" / "models"
UNSAFE = (EXAMPLES / "discrete-unsafe-map.toml").read_text()


def _with_gain(text: str) -> str:
    """The unsafe map with its gain ``0.3`` a parameter ``a`` (the shipped file, its one line changed)."""
    assert 'x = "0.3*x"' in text
    return text.replace('x = "0.3*x"', 'x = "a*x"').replace("[dynamics]", "[parameters]\na = 0.3\n\n[dynamics]")


SPEC = """[sweep]
model = "m.toml"
mode = "boxes"
classes = {classes}
chunk_size = 1

[[sweep.axes]]
name = "a"
start = 0.28
stop = 0.32
num = 3

[sweep.boxes]
min_relative_width = 0.01
max_boxes = 9
cross_check_points = 0
seed = 0
"""


def _spec(tmp_path: Path, classes: str) -> Path:
    from tests.test_model_sweeps import write

    return write(tmp_path, SPEC.format(classes=classes), model=_with_gain(UNSAFE))


def test_a_box_refuted_by_its_barrier_is_stored_refuted_not_split_and_counted(tmp_path: Path) -> None:
    from tests.test_model_sweeps import arrays, run

    result = run(_spec(tmp_path, '["barrier"]'), tmp_path / "out.zarr")
    data = arrays(tmp_path / "out.zarr")
    done = data["done"].astype(bool)
    # the two boxes of the axes' grid, and no halves: a refutation decides the claim for every value of the box
    assert list(np.flatnonzero(done)) == [0, 1]
    assert list(data["status"][:2]) == [BOX_STATUS_CODES["refuted"]] * 2
    assert list(data["status_barrier"][:2]) == [STATUS_CODES["refuted"]] * 2
    assert not (data["status"] == BOX_STATUS_CODES["split"]).any() and list(data["level"][:2]) == [0, 0]
    for j in range(2):
        note = str(data["note"][j])
        assert note.startswith("barrier refuted: at a = ") and "a value of the box" in note
        assert data["certificate"][j] == ""
    assert result.summary.counts == {"certified": 0, "not_certified": 0, "refuted": 2}


@pytest.mark.parametrize("others, open_", [
    ((STATUS_CODES["refuted"], STATUS_CODES["refuted"]), False),
    ((STATUS_CODES["refuted"], STATUS_CODES["not_certified"]), True),
    ((STATUS_CODES["not_applicable"], STATUS_CODES["refuted"]), False),
])
def test_a_refuted_box_is_split_only_while_another_class_over_it_is_open(
        tmp_path: Path, others: tuple[int, int], open_: bool) -> None:
    """The split rule on the rotation map's two safety classes, and with a stability class beside them."""
    from sweeps.run import model_box_tree
    from sweeps.spec import load_model_spec

    (tmp_path / "m.toml").write_text((EXAMPLES / "discrete-rotation-map.toml").read_text())
    spec_text = SPEC.replace('name = "a"', 'name = "g"').replace("0.28", "0.6").replace("0.32", "0.8")
    (tmp_path / "safety.toml").write_text(spec_text.format(classes='["barrier", "reach_avoid"]'))
    (tmp_path / "both.toml").write_text(spec_text.format(classes='["linearization", "barrier", "reach_avoid"]'))
    refuted = np.array([BOX_STATUS_CODES["refuted"]])
    held = {"status": refuted, "status_barrier": np.array([others[0]]), "status_reach_avoid": np.array([others[1]])}
    safety = model_box_tree(load_model_spec(tmp_path / "safety.toml"))
    assert safety.undecided({**held, "unstable_corners": np.array([-1])}, 0) is open_
    both = model_box_tree(load_model_spec(tmp_path / "both.toml"))
    # with a stability class: split while a corner is not unstable (as before), else as the safety classes say
    assert both.undecided({**held, "unstable_corners": np.array([1])}, 0) is True
    assert both.undecided({**held, "unstable_corners": np.array([2])}, 0) is open_
    # an undecided box is split whatever its classes; a certified one never
    for status, split in (("not_certified", True), ("certified", False)):
        code = np.array([BOX_STATUS_CODES[status]])
        assert safety.undecided({**held, "status": code, "unstable_corners": np.array([-1])}, 0) is split


def test_a_point_refuted_by_its_barrier_is_refuted_and_the_page_says_unsafe(tmp_path: Path) -> None:
    """The same map over points: each point's barrier refuted makes the point ``refuted`` (counted); the page says
    what such a refutation is, and the map's legend calls the points unsafe (no stability class was asked)."""
    from reports.render import sweep_html
    from reports.stores.model_file import _refuted_words
    from sweeps.store import open_results
    from tests.test_model_sweeps import arrays, run, write

    spec = SPEC.format(classes='["barrier"]').replace('mode = "boxes"', 'mode = "points"')
    spec = spec[:spec.index("[sweep.boxes]")]
    result = run(write(tmp_path, spec, model=_with_gain(UNSAFE)), tmp_path / "points.zarr")
    data = arrays(tmp_path / "points.zarr")
    assert list(data["status"]) == [STATUS_CODES["refuted"]] * 3 == list(data["status_barrier"])
    assert all(str(note).startswith("barrier refuted: ") for note in data["note"])
    assert result.summary.counts["refuted"] == 3
    page = sweep_html(str(tmp_path / "points.zarr"))  # (the map's legend is drawn, not text: its words are asked)
    assert "a safety class (barrier, reach_avoid) is refuted" in page
    assert _refuted_words(open_results(tmp_path / "points.zarr")) == "unsafe"


@pytest.mark.parametrize("classes, words", [(["linearization", "roa"], "unstable"), (["barrier", "reach_avoid"], "unsafe"),
                                            (["quadratic", "barrier"], "unstable or unsafe"),
                                            (["sos_bound", "barrier"], "unsafe")])
def test_the_legend_names_what_a_refuted_point_can_be(classes: list[str], words: str) -> None:
    import json
    from types import SimpleNamespace

    from reports.stores.model_file import _refuted_words

    assert _refuted_words(SimpleNamespace(attrs={"classes": json.dumps(classes)})) == words
