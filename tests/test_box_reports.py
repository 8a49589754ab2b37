"""The report of a box sweep (``mode = "boxes"``): the map of leaves, the certified share, broken stores.

A real box store is computed once per module (one cell of the (alpha_d, k_d) plane halved once:
one certified and one not certified leaf, about 5 s) and rendered through the command line.
Shapes a small run does not produce (one or three parameters, a partial store, a soundness
violation) are built as datasets by hand that pass :func:`sweeps.schema.check_dataset`.
"""

from __future__ import annotations

import base64
import json
import re
import shutil
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from click.testing import CliRunner, Result

from lyapcheck.cli import app  # type: ignore[attr-defined]  # the module, as tests/test_fuzz.py uses it
from reports.render import sweep_html
from sweeps.summary import summarize_box_arrays as summarize_arrays
from sweeps.schema import BOX_DIM, BOX_STATUS_CODES, box_variables, check_dataset
from tests.test_reports import Page

app._register_commands()
RUNNER = CliRunner()
#: one log-scale cell that the paper's other gains split into a certified and a not certified half
#: (min_relative_width 1: the cell, 4x wide in k_d, is halved there at 0.125; the budget of 3 boxes
#: stops there); ges certifies the upper half in k_d and finds no certificate for the lower one
#: (its corner alpha_d = 2000, k_d = 0.05 is past what ges's certificate form proves); the paper's
#: gains are outside the window
SPEC = """
[gains]
sigma0 = 0.01
delta_los = "0.75 mm"
los_speed = "1 m/s"
[swimmer]
e11 = "9.3e-5 m"
e11_hat = "1 m"
[sweep]
mode = "boxes"
classes = ["sector_ges", "ges"]
[[sweep.axes]]
name = "alpha_d"
start = 700
stop = 2000
num = 2
scale = "log"
[[sweep.axes]]
name = "k_d"
start = "0.05 1/s"
stop = "0.2 1/s"
num = 2
scale = "log"
[sweep.boxes]
min_relative_width = 1.0
max_boxes = 3
cross_check_points = 1
seed = 0
"""
LEAF_ID = re.compile(rb'id="box-(\d+)-([a-z_]+)"')
CERT = BOX_STATUS_CODES["certified"]
NOT = BOX_STATUS_CODES["not_certified"]
SPLIT = BOX_STATUS_CODES["split"]


def run(args: list[str]) -> Result:
    """``lyapcheck ARGS`` in-process; an exception other than the exit is a failure, not a result."""
    return RUNNER.invoke(app.cli, args, catch_exceptions=False)


def map_svg(html: str) -> bytes | None:
    """The SVG of the page's box map (figure#box-map), or None when the page has none."""
    m = re.search(r'<figure id="box-map"><img src="data:image/svg\+xml;base64,([^"]+)"', html)
    return None if m is None else base64.b64decode(m.group(1))


def drawn_leaves(svg: bytes) -> dict[int, str]:
    """Store row -> status of every rectangle drawn for a leaf."""
    found = LEAF_ID.findall(svg)
    rows = {int(r): s.decode() for r, s in found}
    assert len(rows) == len(found), "a row drawn twice"
    return rows


def store_leaves(status: np.ndarray, done: np.ndarray) -> dict[int, str]:
    names = {v: k for k, v in BOX_STATUS_CODES.items()}
    return {int(r): names[int(status[r])] for r in np.flatnonzero(done & (status != SPLIT))}


def certified_share(html: str) -> float:
    page = Page(html)
    (banner,) = [a for t, a in page.tags if a.get("id") == "certified-share"]
    return float(banner["data-certified-share"])


# -- a real store, through the command line ---------------------------------------------------------
@pytest.fixture(scope="module")
def box_store(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Any]:
    """(store path, the summary ``lyapcheck sweep`` printed) of the small real box sweep."""
    from lyapcheck import sweep

    root = tmp_path_factory.mktemp("boxes")
    (root / "spec.toml").write_text(SPEC, encoding="utf-8")
    result = sweep(root / "spec.toml", root / "boxes.zarr", workers=0)
    return root / "boxes.zarr", result.summary


@pytest.fixture(scope="module")
def box_page(box_store: tuple[Path, Any], tmp_path_factory: pytest.TempPathFactory) -> str:
    out = tmp_path_factory.mktemp("page") / "boxes.html"
    result = run(["report", str(box_store[0]), "--html", str(out)])
    assert result.exit_code == 0, result.stderr
    return out.read_text(encoding="utf-8")


def _arrays(path: Path) -> dict[str, np.ndarray]:
    import xarray as xr

    ds = xr.open_zarr(path, consolidated=False).load()
    return {name: np.asarray(ds[name].values) for name in ds.data_vars}


@pytest.mark.slow
def test_one_rectangle_per_leaf_with_its_status(box_store: tuple[Path, Any], box_page: str) -> None:
    data = _arrays(box_store[0])
    expected = store_leaves(data["status"], data["done"].astype(bool))
    assert sorted(expected.values()) == ["certified", "not_certified"], "the spec no longer gives both statuses"
    svg = map_svg(box_page)
    assert svg is not None
    assert drawn_leaves(svg) == expected  # the split root (row 0) is not drawn: its halves cover it
    assert b'id="window"' in svg and b'id="not-computed"' not in svg  # complete: nothing hatched


@pytest.mark.slow
def test_certified_share_is_the_sweeps_summary(box_store: tuple[Path, Any], box_page: str) -> None:
    share = box_store[1].area_fraction["certified"]
    assert 0 < share < 1
    assert certified_share(box_page) == share
    text = Page(box_page).text
    assert f"Certified: {100 * share:.1f} % of the parameter window" in text
    for status, fraction in box_store[1].area_fraction.items():
        row = re.search(rf'<tr id="share-{status}">(.*?)</tr>', box_page, re.S)
        assert row is not None and f"{100 * fraction:.1f} %" in row.group(1), status
    assert "no soundness violation" in text.lower() and "SOUNDNESS VIOLATIONS" not in text


@pytest.mark.slow
def test_classes_table_is_the_summarys(box_store: tuple[Path, Any], box_page: str) -> None:
    data = _arrays(box_store[0])
    by_class = box_store[1].certified_by
    assert by_class == {"sector_ges": 0, "ges": 1}, "the spec no longer exercises both classes"
    for name in ("sector_ges", "ges"):
        row = re.search(rf'<tr id="class-{name}">(.*?)</tr>', box_page, re.S)
        assert row is not None
        cells = re.findall(r'<td class="num">(\d+)</td>', row.group(1))
        refuted = int(np.sum(data["done"] & (data[f"status_{name}"] == BOX_STATUS_CODES["refuted"])))
        assert cells == [str(by_class[name]), str(refuted)], name
    assert "no quadratic V common to the box" in Page(box_page).text  # sector_ges's refutation explained


@pytest.mark.slow
def test_paper_point_marked_even_outside_the_window(box_page: str) -> None:
    # the paper's alpha_d = 600 is left of this window (700 .. 2000): the view widens to show it
    svg = map_svg(box_page)
    assert svg is not None and svg.count(b'id="paper-point"') == 1
    text = Page(box_page).text
    assert "at the paper's gains outside the boxes computed" in text


@pytest.mark.slow
def test_pdf_of_the_box_page(box_store: tuple[Path, Any], tmp_path: Path) -> None:
    from tests.test_reports import _pdf_text

    pdf = tmp_path / "boxes.pdf"
    result = run(["report", str(box_store[0]), "--pdf", str(pdf)])
    assert result.exit_code == 0, result.stderr
    text = " ".join(" ".join(_pdf_text(pdf.read_bytes())).split())
    share = box_store[1].area_fraction["certified"]
    assert f"{100 * share:.1f} %" in text and "What a certified box means" in text


def _edit_attr(store: Path, key: str, value: Any) -> None:
    meta = json.loads((store / "zarr.json").read_text())
    meta["attributes"][key] = value
    (store / "zarr.json").write_text(json.dumps(meta))


def _nan_edge(store: Path) -> None:
    import zarr

    lo = zarr.open_group(str(store), mode="r+")["lo_alpha_d"]
    assert isinstance(lo, zarr.Array)
    lo[1] = np.nan  # row 1 is a leaf


DAMAGE = {
    "status metadata deleted": lambda s: (s / "status" / "zarr.json").unlink(),
    "status array deleted": lambda s: shutil.rmtree(s / "status"),
    "dims not JSON": lambda s: _edit_attr(s, "dims", "alpha_d, k_d"),
    "dims unknown": lambda s: _edit_attr(s, "dims", json.dumps(["alpha_d", "speed"])),
    "mode says points": lambda s: _edit_attr(s, "mode", "points"),
    "leaf edge NaN": _nan_edge,
}


@pytest.mark.slow
@pytest.mark.parametrize("damage", sorted(DAMAGE))
def test_damaged_box_store_is_one_line_exit_2(box_store: tuple[Path, Any], tmp_path: Path, damage: str) -> None:
    store = tmp_path / "damaged.zarr"
    shutil.copytree(box_store[0], store)
    DAMAGE[damage](store)
    result = run(["report", str(store), "--html", str(tmp_path / "out.html")])
    assert result.exit_code == 2, (damage, result.exit_code, result.stderr)
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("lyapcheck: error: "), result.stderr
    assert not (tmp_path / "out.html").exists()


@pytest.mark.slow
def test_spec_edited_away_falls_back_on_the_stored_boxes(box_store: tuple[Path, Any], tmp_path: Path) -> None:
    """Without a readable spec the window is the first level's boxes: the same shares."""
    store = tmp_path / "nospec.zarr"
    shutil.copytree(box_store[0], store)
    _edit_attr(store, "spec_toml", "not = [toml")
    out = tmp_path / "out.html"
    assert run(["report", str(store), "--html", str(out)]).exit_code == 0
    assert certified_share(out.read_text()) == pytest.approx(box_store[1].area_fraction["certified"], rel=1e-12)


# -- hand-built stores: shapes a small run does not produce -----------------------------------------
def dataset(boxes: list[dict[str, Any]], dims: tuple[str, ...], scales: dict[str, str],
            paper: dict[str, float] | None = None) -> Any:
    """A box store as a Dataset: one row per entry of ``boxes`` (edges ``<dim>: (lo, hi)``, status, ...)."""
    import xarray as xr

    variables = box_variables(dims, ("ges",))
    n = len(boxes)
    arrays = {v.name: np.full(n, v.fill, dtype=v.dtype) for v in variables}
    for i, box in enumerate(boxes):
        for d in dims:
            arrays[f"lo_{d}"][i], arrays[f"hi_{d}"][i] = box[d]
        arrays["status_ges"][i] = box.get("status", -1) if box.get("status") != SPLIT else NOT
        for key in ("status", "level", "k", "decay_rate_per_s", "cross_check_runs", "cross_check_worst_ratio",
                    "soundness_violation"):
            if key in box:
                arrays[key][i] = box[key]
        arrays["done"][i] = box.get("done", True)
    attrs = {"mode": "boxes", "dims": json.dumps(list(dims)), "axis_scales": json.dumps(scales),
             "classes": json.dumps(["ges"]), "versions": json.dumps({"lyapcheck": "test"}),
             "paper_point": json.dumps(paper or {"alpha_d": 600.0, "k_d": 0.15, "sigma0": 0.01, "delta_los": 7.5e-4})}
    ds = xr.Dataset({name: ((BOX_DIM,), values) for name, values in arrays.items()}, attrs=attrs)
    check_dataset(ds, "hand-built")
    return ds


def summary_of(ds: Any, dims: tuple[str, ...], scales: dict[str, str],
               window: dict[str, tuple[float, float]]) -> Any:
    return summarize_arrays(dims, scales, window, {v.name: ds[v.name].values for v in box_variables(dims, ("ges",))})


CERTIFIED = {"status": CERT, "k": 12.0, "decay_rate_per_s": 0.05, "cross_check_runs": 2,
             "cross_check_worst_ratio": 0.5}


def test_one_parameter_draws_intervals() -> None:
    dims, scales = ("k_d",), {"k_d": "linear"}
    ds = dataset([{"k_d": (0.1, 0.5), "status": SPLIT, "level": 0},
                  {"k_d": (0.1, 0.3), "level": 1, **CERTIFIED},
                  {"k_d": (0.3, 0.5), "status": NOT, "level": 1}], dims, scales)
    html = sweep_html(ds)
    svg = map_svg(html)
    assert svg is not None and drawn_leaves(svg) == {1: "certified", 2: "not_certified"}
    assert svg.count(b'id="paper-point"') == 1
    share = summary_of(ds, dims, scales, {"k_d": (0.1, 0.5)}).area_fraction["certified"]
    assert share == pytest.approx(0.5) and certified_share(html) == share


def test_partial_store_hatches_what_is_not_computed() -> None:
    dims, scales = ("alpha_d", "k_d"), {"alpha_d": "log", "k_d": "log"}
    ds = dataset([{"alpha_d": (100.0, 400.0), "k_d": (0.1, 0.4), "level": 0, **CERTIFIED},
                  {"alpha_d": (400.0, 1600.0), "k_d": (0.1, 0.4), "level": 0, "status": NOT},
                  {"alpha_d": (100.0, 400.0), "k_d": (0.4, 1.6), "level": 0, "status": NOT, "done": False},
                  {"alpha_d": (400.0, 1600.0), "k_d": (0.4, 1.6), "level": 0, "status": SPLIT},
                  {"alpha_d": (np.nan, np.nan), "k_d": (np.nan, np.nan), "done": False}],  # a spare row
                 dims, scales)
    html = sweep_html(ds)
    svg = map_svg(html)
    # row 3 is split but its halves are not computed: drawn as neither, so the hatch shows there
    assert svg is not None and drawn_leaves(svg) == {0: "certified", 1: "not_certified"}
    assert svg.count(b'id="not-computed"') == 1
    assert certified_share(html) == pytest.approx(0.25)
    text = Page(html).text
    assert "not computed 50.0 %" in text and "This store is partial" in text


def test_three_parameters_list_the_leaves_instead_of_a_map() -> None:
    dims = ("alpha_d", "k_d", "sigma0")
    scales = {d: "log" for d in dims}
    edges = {"alpha_d": (100.0, 400.0), "k_d": (0.1, 0.4), "sigma0": (0.01, 0.04)}
    ds = dataset([{**edges, "level": 0, **CERTIFIED}], dims, scales)
    html = sweep_html(ds)
    assert map_svg(html) is None and "no map is drawn" in Page(html).text
    assert re.search(r"<td class=\"num\">0</td><td><span class=\"badge certified\">", html)
    assert certified_share(html) == 1.0


def test_soundness_violation_is_loud() -> None:
    dims, scales = ("alpha_d", "k_d"), {"alpha_d": "log", "k_d": "linear"}
    ds = dataset([{"alpha_d": (100.0, 400.0), "k_d": (0.1, 0.4), "level": 0, **CERTIFIED,
                   "cross_check_worst_ratio": 1.7, "soundness_violation": True}], dims, scales)
    page = Page(sweep_html(ds))
    assert page.find("div", "alarm") and "SOUNDNESS VIOLATIONS: 1 box(es)" in page.text
    assert "1.7" in page.text and "alpha_d (1/s) in [100, 400]" in page.text
