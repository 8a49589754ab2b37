"""Sweeps of model files (``[sweep] model = FILE``): specs, statuses, resume, certificates, the
soundness alarm, the summary's shares and the report's map.

The models are one-state loops written in the test's directory, with known answers:
``x' = -a x`` is GES exactly when ``a > 0`` (and unstable, exactly, when ``a < 0``);
``x' = -a x + d`` with ``|d| <= 1`` has the exact worst case ``limsup |x| = 1/a``;
``x' = -a x + x**3`` has the region of attraction ``|x| < sqrt(a)``.
"""

from __future__ import annotations

import base64
import json
import math
import re
from fractions import Fraction
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from lyapcheck.errors import InputFileError

LINEAR = """[model]
name = "x' = -a x"
states = ["x"]
[parameters]
a = 1
[dynamics]
x = "-a*x"
"""
DISTURBED = """[model]
states = ["x"]
[parameters]
a = 2
[disturbances]
d = 1
[dynamics]
x = "-a*x + d"
"""
CUBIC = """[model]
states = ["x"]
[parameters]
a = 1
[dynamics]
x = "-a*x + x**3"
[domain]
x = [-2, 2]
"""
POINTS = """[sweep]
model = "m.toml"
classes = ["linearization", "quadratic"]
chunk_size = 3
[[sweep.axes]]
name = "a"
start = -0.9
stop = 2
num = 7
"""
BOXES = """[sweep]
model = "m.toml"
mode = "boxes"
classes = ["quadratic"]
chunk_size = 2
[[sweep.axes]]
name = "a"
start = -0.9
stop = 2
num = 4
[sweep.boxes]
min_relative_width = 0.1
max_boxes = 30
cross_check_points = 2
[simulation]
starts = 4
"""


def write(directory: Path, spec: str, model: str = LINEAR, name: str = "spec.toml") -> Path:
    directory.mkdir(parents=True, exist_ok=True)
    (directory / "m.toml").write_text(model)
    path = directory / name
    path.write_text(spec)
    return path


def run(spec: Path, out: Path, **kw: Any) -> Any:
    from lyapcheck.api import sweep

    return sweep(spec, out, workers=0, **kw)


def arrays(path: Path) -> dict[str, np.ndarray]:
    import zarr

    group = zarr.open_group(str(path), mode="r")
    return {name: np.asarray(group[name][...]) for name in group.array_keys()}


def cli(*args: str) -> Any:
    from click.testing import CliRunner

    from lyapcheck.cli import app

    app._register_commands()
    return CliRunner().invoke(app.cli, list(args), standalone_mode=False)


@pytest.fixture(scope="module")
def points_store(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Any]:
    directory = tmp_path_factory.mktemp("points")
    spec = write(directory, POINTS)
    return directory / "out.zarr", run(spec, directory / "out.zarr")


@pytest.fixture(scope="module")
def boxes_store(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Any]:
    directory = tmp_path_factory.mktemp("boxes")
    spec = write(directory, BOXES)
    return directory / "out.zarr", run(spec, directory / "out.zarr")


# -- the spec: every bad input is one line, exit 2, nothing written ----------------------------------
AXIS = '[[sweep.axes]]\nname = "a"\nstart = 0.5\nstop = 2\nnum = 3\n'


@pytest.mark.parametrize("spec, model, needle", [
    ('[sweep]\nmodel = "m.toml"\n[[sweep.axes]]\nname = "b"\nstart = 1\nstop = 2\nnum = 2\n', LINEAR,
     "'sweep.axes[0].name' parameter must be a parameter declared in the model (a)"),
    ('[sweep]\nmodel = "m.toml"\n[sweep.set]\na = 2\n' + AXIS, LINEAR, "'sweep.set.a' parameter must be absent"),
    ('[sweep]\nmodel = "m.toml"\n[[sweep.axes]]\nname = "a"\nstart = 2\nstop = 1\nnum = 3\n', LINEAR,
     "'sweep.axes[0].stop' parameter must be larger than start"),
    ('[sweep]\nmodel = "m.toml"\n[[sweep.axes]]\nname = "a"\nstart = -1\nstop = 1\nnum = 3\nscale = "log"\n', LINEAR,
     "'sweep.axes[0].start' parameter must be positive on a log axis"),
    ('[sweep]\nmodel = "m.toml"\nclasses = ["candidate"]\n' + AXIS, LINEAR, 'add candidate = "..."'),
    ('[sweep]\nmodel = "m.toml"\nclasses = ["sos_bound"]\n' + AXIS, LINEAR, "sos_bound needs [disturbances]"),
    # a model without [sets] cannot ask the safety questions: refused by the spec, not at the first point
    ('[sweep]\nmodel = "m.toml"\nclasses = ["barrier"]\n' + AXIS, LINEAR, "'sweep.classes' parameter must be"),
    ('[sweep]\nmodel = "m.toml"\nclasses = ["reach_avoid"]\n' + AXIS, LINEAR, "'sweep.classes' parameter must be"),
    # (without [sweep] candidate = "...", in either mode: the refusal asks for the user's V)
    ('[sweep]\nmodel = "m.toml"\nmode = "boxes"\nclasses = ["candidate"]\n' + AXIS, LINEAR,
     "'sweep.classes' parameter must be classes without 'candidate' unless [sweep] gives your V: add candidate"),
    ('[sweep]\nmodel = "m.toml"\n[sweep.set]\nq = 1\n' + AXIS, LINEAR, "'sweep.set.q' parameter must be a parameter "
     "or disturbance declared in the model"),
    ('[sweep]\nmodel = "m.toml"\n[sweep.boxes]\nmax_boxes = 4\n' + AXIS, LINEAR, "'sweep.boxes' parameter must be "
     "absent unless mode"),
    ('[sweep]\nmodel = "m.toml"\nrefine = 1\n' + AXIS, LINEAR, "'sweep.refine' parameter must be a known key"),
    ('[sweep]\nmodel = "m.toml"\n[gains]\nk_d = 1\n' + AXIS, LINEAR, "'gains' parameter must be absent in a model sweep"),
    ('[sweep]\nmodel = "nope.toml"\n' + AXIS, LINEAR, "nope.toml: file: not found"),
    ('[sweep]\nmodel = "m.toml"\n[[sweep.axes]]\nname = "a"\nvalues = [-1, 0, 1]\n',
     LINEAR.replace('"-a*x"', '"-x/a"'), "sweep.axes at the grid point a = 0: the model is not defined there"),
    ('[sweep]\nmodel = "m.toml"\nmode = "boxes"\n[[sweep.axes]]\nname = "a"\nstart = -1\nstop = 1\nnum = 3\n',
     LINEAR.replace('"-a*x"', '"-x/a"'), "the box a in [-1, 0]: the model is not defined on all of it"),
])
def test_a_bad_spec_is_one_line_exit_2_and_writes_nothing(tmp_path: Path, spec: str, model: str, needle: str) -> None:
    assert_refused(write(tmp_path, spec, model), needle)


def test_a_spec_without_classes_asks_only_what_the_model_can_answer(tmp_path: Path) -> None:
    """Without ``classes`` a sweep runs every class the model can ask: no barrier or reach_avoid without
    ``[sets]`` (they used to be picked, and the first point refused them: the sweep exited 2)."""
    from sweeps.spec import load_model_spec

    spec = load_model_spec(write(tmp_path, '[sweep]\nmodel = "m.toml"\n' + AXIS, LINEAR))
    assert "quadratic" in spec.classes and not {"barrier", "reach_avoid"} & set(spec.classes)


def assert_refused(path: Path, needle: str) -> None:
    """``lyapcheck sweep PATH`` exits 2 with one line holding ``needle``, and writes no store."""
    out = path.parent / "out.zarr"
    result = cli("sweep", str(path), "--out", str(out), "--workers", "0", "--quiet")
    lines = result.stderr.strip().splitlines()
    assert result.exit_code == 2, result.output
    assert len(lines) == 1 and needle in lines[0], lines
    assert not out.exists() and not any(p.name.startswith(".out.zarr") for p in path.parent.iterdir())


# -- points and boxes on a model with a known answer --------------------------------------------------
def test_points_are_certified_exactly_where_the_loop_is_stable(points_store: tuple[Path, Any]) -> None:
    from lyapcheck.api import verify

    path, result = points_store
    data = arrays(path)
    a = data["a"]
    assert result.mode == "model_points" and result.summary.computed == 7
    assert np.array_equal(data["status"], np.where(a > 0, 1, 2))  # 1 certified, 2 refuted (unstable, exactly)
    assert np.array_equal(data["status_linearization"], np.where(a > 0, 1, 2))
    assert not np.any(data["status_quadratic"][a < 0] == 1)
    rate = data["quadratic_decay_rate_V_per_s"]
    assert np.all(np.isnan(rate[a < 0])) and np.all((rate[a > 0] > 0) & (rate[a > 0] <= 2 * a[a > 0] * (1 + 1e-12)))
    for cert, value in zip(data["certificate"], a):
        if value < 0:
            assert cert == ""
            continue
        doc = json.loads(str(cert))
        assert Fraction(doc["parameters"]["a"]) == Fraction(float(value))  # the stored float, exactly
        assert verify(doc).valid
    # the window [-0.9, 2] is cut at the midpoints: certified from (a_1 + a_2) / 2 on
    assert result.summary.share["certified"] == pytest.approx((2 - (a[1] + a[2]) / 2) / 2.9, rel=1e-12)
    assert not data["soundness_violation"].any() and data["cross_check_trajectories"][a > 0].min() > 0


def test_boxes_are_proved_on_the_stable_side_and_refuted_across_the_unstable_one(boxes_store: tuple[Path, Any]) -> None:
    from lyapcheck.api import verify

    path, result = boxes_store
    data = arrays(path)
    done = data["done"]
    leaf = done & (data["status"] != 3)
    certified = leaf & (data["status"] == 1)
    refuted = leaf & (data["status"] == 2)
    assert certified.any() and refuted.any()
    assert np.all(data["lo_a"][certified] > 0)  # never certified where a < 0
    assert np.all(data["lo_a"][refuted] < 0)
    # the certified share is the measure of the certified leaves, exactly as stored
    width = float(np.sum(data["hi_a"][certified] - data["lo_a"][certified]))
    assert result.summary.share["certified"] == pytest.approx(width / 2.9, rel=1e-12)
    assert sum(result.summary.share[s] for s in ("certified", "not_certified", "refuted")) == pytest.approx(1.0)
    for row in np.flatnonzero(certified):
        doc = json.loads(str(data["certificate"][row]))
        lo, hi = (Fraction(v) for v in doc["box"]["a"])
        assert (float(lo), float(hi)) == (data["lo_a"][row], data["hi_a"][row])
        assert verify(doc).valid
        assert data["cross_check_points"][row] == 2 and not data["soundness_violation"][row]
    # a certificate whose box is widened (into the unstable side) or whose rate is raised fails
    doc = json.loads(str(data["certificate"][np.flatnonzero(certified)[0]]))
    wide = json.loads(json.dumps(doc))
    wide["box"]["a"][0] = "-1/2"
    assert not verify(wide).valid
    faster = json.loads(json.dumps(doc))
    faster["conditions"]["quadratic"]["decay_rate_V_per_s"] *= 2
    assert not verify(faster).valid


def test_a_box_of_two_parameters_swept_out_of_the_models_order_verifies(tmp_path: Path) -> None:
    """The certificate states its box in the model's order of parameters (``verify`` checks it),
    whatever the order of the spec's axes."""
    from lyapcheck.api import verify

    model = '[model]\nstates = ["x", "y"]\n[parameters]\na = 1\nb = 1\n[dynamics]\nx = "-a*x"\ny = "-b*y"\n'
    spec = write(tmp_path, '[sweep]\nmodel = "m.toml"\nmode = "boxes"\nclasses = ["quadratic"]\n'
                           '[[sweep.axes]]\nname = "b"\nvalues = [1, 2]\n[[sweep.axes]]\nname = "a"\nvalues = [1, 2]\n'
                           "[sweep.boxes]\nmin_relative_width = 10\ncross_check_points = 1\n", model)
    result = run(spec, tmp_path / "out.zarr")
    data = arrays(tmp_path / "out.zarr")
    doc = json.loads(str(data["certificate"][0]))
    assert result.summary.proved_share == 1.0 and list(doc["box"]) == ["a", "b"] and verify(doc).valid


def test_rerunning_a_finished_store_computes_nothing(boxes_store: tuple[Path, Any]) -> None:
    path, first = boxes_store
    again = run(path.parent / "spec.toml", path)
    assert again.run.computed_now == 0 and again.summary.to_json() == first.summary.to_json()


# -- resume ------------------------------------------------------------------------------------------
class Interrupt(Exception):
    """Raised from the progress callback: the sweep stops between units, as after a kill."""


def interrupted(spec: Path, out: Path, after: int) -> None:
    seen = [0]

    def progress(done: int, total: int) -> None:
        seen[0] += done
        if seen[0] >= after:
            raise Interrupt()

    with pytest.raises(Interrupt):
        run(spec, out, progress=progress)


#: a discrete-time map's box sweep (examples/models/discrete-gain-map.toml: stable for |a| < 1): the same tree,
#: store and resume as a continuous loop's
MAP_BOXES = BOXES.replace('classes = ["quadratic"]', 'classes = ["linearization", "quadratic"]').replace(
    "start = -0.9", "start = 0.3").replace("stop = 2", "stop = 1.5").replace("num = 4", "num = 3")


@pytest.mark.parametrize("spec_text, model", [
    (BOXES, LINEAR), (POINTS.replace("num = 7", "num = 5"), LINEAR),
    (MAP_BOXES, (Path(__file__).resolve().parents[1] / "examples" / "models" / "discrete-gain-map.toml").read_text()),
], ids=["boxes", "points", "map-boxes"])
def test_a_resumed_sweep_is_byte_for_byte_an_uninterrupted_one(tmp_path: Path, spec_text: str, model: str) -> None:
    whole = write(tmp_path / "whole", spec_text, model)
    run(whole, tmp_path / "whole" / "out.zarr")
    parts = write(tmp_path / "parts", spec_text, model)
    interrupted(parts, tmp_path / "parts" / "out.zarr", after=2)
    partial = arrays(tmp_path / "parts" / "out.zarr")
    assert 0 < partial["done"].sum() < arrays(tmp_path / "whole" / "out.zarr")["done"].sum()
    resumed = run(parts, tmp_path / "parts" / "out.zarr")
    assert 0 < resumed.run.computed_now
    files_a = {p.relative_to(tmp_path / "whole"): p.read_bytes() for p in (tmp_path / "whole").rglob("*") if p.is_file()}
    files_b = {p.relative_to(tmp_path / "parts"): p.read_bytes() for p in (tmp_path / "parts").rglob("*") if p.is_file()}
    assert files_a.keys() == files_b.keys() and all(files_a[k] == files_b[k] for k in files_a)


def test_a_changed_model_file_is_not_resumed(tmp_path: Path) -> None:
    spec = write(tmp_path, BOXES)
    interrupted(spec, tmp_path / "out.zarr", after=1)
    (tmp_path / "m.toml").write_text(LINEAR.replace("a = 1", "a = 3"))
    with pytest.raises(InputFileError, match="another text of the model file m.toml"):
        run(spec, tmp_path / "out.zarr")


def test_workers_need_the_spec_text_only(tmp_path: Path) -> None:
    from sweeps.evaluate import evaluate_model_points
    from sweeps.spec import load_model_spec

    spec = load_model_spec(write(tmp_path, POINTS))
    (tmp_path / "m.toml").unlink()  # a worker on another machine has no model file
    out = evaluate_model_points(spec.worker_text, np.array([[0.5], [-0.5]]))
    assert list(out["status"]) == [1, 2] and json.loads(str(out["certificate"][0]))["model"]["text"] == LINEAR


# -- the soundness alarm: the detector on false certificates -------------------------------------------
def doc_with(conditions: dict[str, Any], scale: str = "1") -> dict[str, Any]:
    return {"conditions": conditions, "field": {"scaling": {"states": [scale]}}}


def check(model_text: str, doc: dict[str, Any], a: str = "1") -> Any:
    from lyapcheck.models.language.modelfile import parse_model
    from sweeps.crosscheck import cross_check_point

    model = parse_model(model_text, "m.toml")
    return cross_check_point(model, doc, {"a": Fraction(a)}, starts=6, seed=(0,), worst_case=True)


def test_a_region_of_attraction_too_large_raises_the_alarm() -> None:
    """``x' = -x + x**3``: the region of attraction is ``|x| < 1``; ``{x**2 <= 4}`` reaches ``|x| = 2``."""
    roa = {"status": "certified", "certificate": {"V": {"terms": [["1", [2]]]}, "level": "4"}}
    false = check(CUBIC, doc_with({"roa": roa}))
    assert false.violation and "roa" in false.violations[0]
    roa["certificate"]["level"] = "81/100"  # {|x| <= 0.9}: true
    true = check(CUBIC, doc_with({"roa": roa}))
    assert not true.violation and true.trajectories == 6 and true.worst_rise <= 1e-5


def test_a_bound_below_the_worst_case_raises_the_alarm() -> None:
    """``x' = -2 x + d``, ``|d| <= 1``: the worst case is ``limsup |x| = 1/2``."""
    false = check(DISTURBED, doc_with({"sos_bound": {"status": "certified", "bounds": {"x": 0.4}}}), a="2")
    assert false.violation and "exceeds the certified bound 0.4" in false.violations[0]
    assert false.sim_worst["x"] == pytest.approx(0.5, rel=1e-6)
    true = check(DISTURBED, doc_with({"sos_bound": {"status": "certified", "bounds": {"x": 0.5 * (1 + 1e-9)}}}), a="2")
    assert not true.violation


def test_a_decay_rate_too_fast_raises_the_alarm() -> None:
    """``x' = -x``: ``V = x**2`` decays at rate 2 exactly; a claim of 3 is contradicted, 2 is not."""
    def quadratic(rate: float, k: float) -> dict[str, Any]:
        return {"quadratic": {"status": "certified", "property": "GES", "decay_rate_V_per_s": rate, "k": k,
                              "decay_rate_per_s": rate / 2, "certificate": {"V": {"terms": [["1", [2]]]}}}}

    assert check(LINEAR, doc_with(quadratic(3.0, 1.0))).violation
    assert not check(LINEAR, doc_with(quadratic(2.0, 1.0))).violation
    false_k = check(LINEAR, doc_with(quadratic(1.0, 0.5)))  # |x(t)| <= 0.5 |x0| exp(-t/2): false at t = 0
    assert false_k.violation and false_k.ges_ratio == pytest.approx(2.0, rel=1e-6)


def test_a_false_certificate_in_a_sweep_is_shouted_and_exits_1(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """The classes certify honestly; here a wrapper halves every certified bound before the document
    is built, so the sweep's own cross-check must find the worst case above it."""
    import lyapcheck.models.surfaces.certify as certify

    honest = certify.certify_model

    def halved(*args: Any, **kwargs: Any) -> Any:
        result = honest(*args, **kwargs)
        bound = result.results.get("sos_bound")
        if bound is not None and bound.status == "certified":
            bound.numbers["bounds"] = {y: b / 2 for y, b in bound.numbers["bounds"].items()}
        return result

    monkeypatch.setattr(certify, "certify_model", halved)
    spec = write(tmp_path, '[sweep]\nmodel = "m.toml"\nmode = "boxes"\nclasses = ["sos_bound"]\n'
                           '[[sweep.axes]]\nname = "a"\nstart = 2\nstop = 4\nnum = 2\n'
                           "[sweep.boxes]\nmin_relative_width = 10\ncross_check_points = 1\n", DISTURBED)
    result = cli("sweep", str(spec), "--out", str(tmp_path / "out.zarr"), "--workers", "0", "--quiet")
    assert result.exit_code == 1, result.output
    assert "SOUNDNESS VIOLATION" in result.stderr and "exceeds the certified bound" in result.stderr


# -- the summary, from hand-made arrays ----------------------------------------------------------------
def hand_made(mode: str, status: list[int], n: int, **extra: Any) -> dict[str, np.ndarray]:
    data: dict[str, np.ndarray] = {
        "done": np.ones(n, bool), "status": np.array(status, np.int8), "status_roa": np.array(status, np.int8),
        "roa_level": np.where(np.array(status) == 1, 1.0, np.nan), "roa_ball_radius": np.full(n, np.nan),
        "cross_check_points": np.zeros(n, np.int16), "cross_check_trajectories": np.zeros(n, np.int32),
        "cross_check_worst_rise": np.full(n, np.nan), "cross_check_worst_envelope": np.full(n, np.nan),
        "cross_check_ges_ratio": np.full(n, np.nan), "cross_check_not_converged": np.zeros(n, np.int32),
        "soundness_violation": np.zeros(n, bool), "violation_detail": np.array([""] * n, dtype=object),
    }
    data.update({k: np.asarray(v) for k, v in extra.items()})
    return data


def test_box_shares_are_measured_exactly_in_each_axis_scale() -> None:
    from sweeps.summary import summarize_model_arrays as summarize_arrays

    # window [1, 16] on a log axis; leaves [1, 4] certified, [4, 8] refuted, [8, 16] not certified; [4, 16] split
    data = hand_made("boxes", [1, 3, 2, 0], 4, lo_p=[1.0, 4.0, 4.0, 8.0], hi_p=[4.0, 16.0, 8.0, 16.0])
    summary = summarize_arrays("model_boxes", ("p",), {"p": "log"}, ("roa",), (), data, window={"p": (1.0, 16.0)})
    assert summary.share == pytest.approx({"certified": 0.5, "refuted": 0.25, "not_certified": 0.25,
                                           "not_computed": 0.0}, abs=1e-15)
    assert summary.leaves == 3 and summary.counts == {"certified": 1, "not_certified": 1, "refuted": 1}
    assert summary.share_by_class == {"roa": pytest.approx(0.5, abs=1e-15)}
    linear = summarize_arrays("model_boxes", ("p",), {"p": "linear"}, ("roa",), (), data, window={"p": (1.0, 16.0)})
    assert linear.share["certified"] == pytest.approx(3 / 15, abs=1e-15)


def test_point_shares_are_their_cells_in_each_axis_scale() -> None:
    from sweeps.summary import cell_fractions, summarize_model_arrays as summarize_arrays

    # log values 1, 2, 4: cell edges at sqrt(2) and 2 sqrt(2), so the cells are 1/4, 1/2, 1/4 of log(4)
    assert cell_fractions([np.array([1.0, 2.0, 4.0])], ["log"]) == pytest.approx([0.25, 0.5, 0.25], abs=1e-15)
    grid = cell_fractions([np.array([1.0, 2.0, 4.0]), np.array([0.0, 1.0])], ["log", "linear"])
    assert grid.shape == (3, 2) and grid.sum() == pytest.approx(1.0) and grid[1, 0] == pytest.approx(0.25)
    status = np.array([[1, 1], [0, 1], [2, 2]])
    n = status.size
    data = {k: (v.reshape(3, 2) if v.ndim == 1 and v.size == n else v)
            for k, v in hand_made("points", list(status.ravel()), n).items()}
    summary = summarize_arrays("model_points", ("p", "q"), {"p": "log", "q": "linear"}, ("roa",), (), data,
                               coords={"p": np.array([1.0, 2.0, 4.0]), "q": np.array([0.0, 1.0])})
    assert summary.share["certified"] == pytest.approx(0.25 + 0.25, abs=1e-15)
    assert summary.share["not_certified"] == pytest.approx(0.25, abs=1e-15)
    assert summary.share["refuted"] == pytest.approx(0.25, abs=1e-15)


# -- the report ----------------------------------------------------------------------------------------
def figure_svgs(html: str) -> list[str]:
    return [base64.b64decode(m).decode() for m in re.findall(r'src="data:image/svg\+xml;base64,([^"]+)"', html)]


def test_the_report_draws_every_leaf_of_the_boxes(boxes_store: tuple[Path, Any], tmp_path: Path) -> None:
    from lyapcheck.api import report

    path, result = boxes_store
    (page,) = report(path, html=tmp_path / "boxes.html")
    html = page.read_text()
    data = arrays(path)
    leaves = np.flatnonzero(data["done"] & (data["status"] != 3))
    svg = "".join(figure_svgs(html))
    names = {1: "certified", 0: "not_certified", 2: "refuted"}
    for row in leaves:
        assert f'id="box-{row}-{names[int(data["status"][row])]}"' in svg
    share = float(re.search(r'data-proved-share="([^"]+)"', html).group(1))  # type: ignore[union-attr]
    assert share == result.summary.proved_share
    assert "Proved parameter regions" in html and "x&#39; = -a x" in html and "No soundness violation" in html
    assert LINEAR.splitlines()[-1].replace('"', "&#34;") in html  # the model file, verbatim


def test_the_report_maps_the_grid_points(points_store: tuple[Path, Any], tmp_path: Path) -> None:
    from lyapcheck.api import report

    path, _ = points_store
    (page,) = report(path, html=tmp_path / "points.html")
    html = page.read_text()
    assert "Status at each grid point" in html and len(figure_svgs(html)) == 1
    assert "a sampled estimate, not a proof" in html


def test_a_region_of_attraction_family_is_proved_box_by_box(tmp_path: Path) -> None:
    """``x' = -a x + x**3`` over ``a in [1, 2]``: one certified box whose set lies inside ``|x| < 1``
    (the smallest region of attraction of the box), cross-checked at random values of ``a``."""
    spec = write(tmp_path, '[sweep]\nmodel = "m.toml"\nmode = "boxes"\nclasses = ["roa"]\n'
                           '[[sweep.axes]]\nname = "a"\nstart = 1\nstop = 2\nnum = 2\n'
                           "[sweep.boxes]\nmin_relative_width = 10\ncross_check_points = 2\n"
                           "[simulation]\nstarts = 6\n", CUBIC)
    result = run(spec, tmp_path / "out.zarr")
    data = arrays(tmp_path / "out.zarr")
    assert data["status"][0] == 1 and result.summary.proved_share == 1.0
    assert 0 < data["roa_ball_radius"][0] <= 1.0
    assert data["cross_check_trajectories"][0] == 12 and not data["soundness_violation"][0]
    assert data["cross_check_worst_rise"][0] <= 1e-5 and not math.isnan(data["cross_check_worst_rise"][0])


def test_a_box_note_never_rounds_a_corner_onto_another_value() -> None:
    """A split box's edge just above 3/2 is printed exactly, not as "1.5" (a value that was not refuted);
    values that six digits state exactly stay short."""
    from fractions import Fraction

    from sweeps.evaluate import value_text

    assert value_text(Fraction(3, 2)) == "1.5"
    assert value_text(Fraction(-1, 2)) == "-0.5"
    above = Fraction(3, 2) + Fraction(1, 2**30)
    text = value_text(above)
    assert text.startswith(f"{above.numerator}/{above.denominator}") and "1.5" != text
    assert Fraction(text.split(" ")[0]) == above
