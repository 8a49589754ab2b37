"""``[sweep] candidate = "V"`` (issue 41): the user's V in point and box sweeps.

The spec's V is read at load time by the reader ``certify --candidate`` uses (one line naming
``sweep.candidate``, exit 2, for a V that does not parse, names an unknown symbol or a swept parameter);
``classes`` may then name ``candidate``, which runs at every point (as ``certify --candidate`` at that value)
and over every box (as ``certify --box --candidate``), its level stored as roa's and its set cross-checked
from starts inside it. Without the key, naming ``candidate`` is refused; with the key and no class list it
runs with the default classes.
"""

from __future__ import annotations

import json
import math
from fractions import Fraction
from pathlib import Path

import numpy as np
import pytest

from tests.conftest import ROOT
from tests.test_discrete_sweeps import CODES
from tests.test_model_sweeps import arrays, assert_refused, run

VDP = ROOT / "examples" / "models" / "van-der-pol-reversed.toml"
TANH = ROOT / "examples" / "models" / "discrete-tanh-gain-map.toml"
#: a V the reversed Van der Pol oscillator's candidate class certifies (a level set inside its region)
VDP_V = "1.5*x1**2 - x1*x2 + x2**2"
#: the tanh map's V of its example (certified over k in [0.6, 0.95] by ball arithmetic)
TANH_V = "2*x**2 - 2*x*y + 4*y**2"


def spec(tmp: Path, model: Path, name: str, axis: str, *, candidate: str | None, classes: str,
         mode: str = "points") -> Path:
    (tmp / "m.toml").write_text(model.read_text())
    key = "" if candidate is None else f"candidate = {json.dumps(candidate)}\n"
    path = tmp / f"{name}.toml"
    path.write_text(f'[sweep]\nmodel = "m.toml"\nmode = "{mode}"\nclasses = {classes}\n{key}chunk_size = 1\n'
                    f"[[sweep.axes]]\n{axis}\n[simulation]\nstarts = 8\n"
                    + ("[sweep.boxes]\nmin_relative_width = 10\ncross_check_points = 2\n" if mode == "boxes" else ""))
    return path


@pytest.fixture(scope="module")
def vdp_points(tmp_path_factory: pytest.TempPathFactory) -> dict[str, np.ndarray]:
    tmp = tmp_path_factory.mktemp("vdp_points")
    path = spec(tmp, VDP, "p", 'name = "mu"\nvalues = [0.8, 1.2]', candidate=VDP_V, classes='["candidate"]')
    run(path, tmp / "p.zarr")
    return arrays(tmp / "p.zarr")


@pytest.mark.slow
def test_a_point_sweep_stores_each_points_candidate_level_and_cross_checks_it(vdp_points: dict[str, np.ndarray]
                                                                               ) -> None:
    data = vdp_points
    assert list(data["status_candidate"]) == [CODES["certified"]] * 2
    assert np.all(data["candidate_level"] > 0) and np.all(data["candidate_ball_radius"] > 0)
    assert data["candidate_level"][0] != data["candidate_level"][1]  # each point's own largest level
    assert list(data["cross_check_trajectories"]) == [8, 8] and not data["soundness_violation"].any()


@pytest.mark.slow
def test_a_points_candidate_certificate_is_re_derived(vdp_points: dict[str, np.ndarray]) -> None:
    """Each stored certificate verifies, states the spec's V, and is what ``certify --candidate`` finds at
    that value of mu (the stored float's exact decimal)."""
    from lyapcheck.api import certify, verify
    from sweeps.spec import exact_decimal

    data = vdp_points
    for j, mu in enumerate(data["mu"]):
        doc = json.loads(str(data["certificate"][j]))
        assert verify(doc).valid and doc["candidate"] == VDP_V
        level = Fraction(str(doc["conditions"]["candidate"]["level"]))
        assert math.isclose(float(level), float(data["candidate_level"][j]), rel_tol=1e-12)
        again = certify(model=str(VDP), settings=[f"mu={exact_decimal(float(mu))}"], candidate=VDP_V,
                        classes="candidate")
        assert again.conditions["candidate"].status == "certified"
        assert Fraction(str(again.document["conditions"]["candidate"]["level"])) == level


@pytest.mark.slow
def test_a_box_sweep_certifies_one_v_for_every_value_of_each_box(tmp_path: Path) -> None:
    from lyapcheck.api import verify

    path = spec(tmp_path, VDP, "b", 'name = "mu"\nstart = 0.8\nstop = 1.2\nnum = 2', candidate=VDP_V,
                classes='["candidate"]', mode="boxes")
    run(path, tmp_path / "b.zarr")
    data = arrays(tmp_path / "b.zarr")
    done = data["status"] != -1
    assert list(data["status_candidate"][done]) == [CODES["certified"]]
    assert data["candidate_level"][done][0] > 0
    doc = json.loads(str(data["certificate"][done][0]))
    assert verify(doc).valid and doc["candidate"] == VDP_V
    assert [Fraction(str(v)) for v in doc["box"]["mu"]] == [Fraction(0.8), Fraction(1.2)]
    assert data["cross_check_trajectories"][done][0] == 2 * 8 and not data["soundness_violation"].any()


@pytest.mark.slow
def test_a_map_with_functions_takes_the_candidate_at_points_and_over_a_box(tmp_path: Path) -> None:
    """The tanh map: the candidate certified at k = 0.6 and 0.8 and over the box [0.6, 0.95] (ball arithmetic,
    k a ball), each set iterated on the true map from starts inside it, no alarm."""
    from lyapcheck.api import verify

    points = spec(tmp_path, TANH, "p", 'name = "k"\nvalues = [0.6, 0.8]', candidate=TANH_V, classes='["candidate"]')
    run(points, tmp_path / "p.zarr")
    data = arrays(tmp_path / "p.zarr")
    assert list(data["status_candidate"]) == [CODES["certified"]] * 2 and np.all(data["candidate_level"] > 0)
    assert not data["soundness_violation"].any() and np.all(data["cross_check_trajectories"] > 0)
    boxes = spec(tmp_path, TANH, "b", 'name = "k"\nstart = 0.6\nstop = 0.95\nnum = 2', candidate=TANH_V,
                 classes='["candidate"]', mode="boxes")
    run(boxes, tmp_path / "b.zarr")
    data = arrays(tmp_path / "b.zarr")
    done = data["status"] != -1
    assert list(data["status_candidate"][done]) == [CODES["certified"]] and data["candidate_level"][done][0] > 0
    doc = json.loads(str(data["certificate"][done][0]))
    assert verify(doc).valid
    assert not data["soundness_violation"].any() and data["cross_check_trajectories"][done][0] > 0


def test_the_candidate_runs_where_the_spec_gives_your_v(tmp_path: Path) -> None:
    """With the key and no class list, the default classes and candidate run; a class list naming candidate is
    kept as given; a list that leaves candidate out while the key is given is refused (the V would be unused);
    without the key candidate is never a default."""
    from sweeps.spec import load_model_spec

    path = spec(tmp_path, VDP, "d", 'name = "mu"\nvalues = [1]', candidate=VDP_V, classes='["roa"]')
    assert_refused(path, "'sweep.candidate' parameter must be given only where sweep.classes names 'candidate'")
    path.write_text(path.read_text().replace('classes = ["roa"]\n', ""))
    loaded = load_model_spec(path)
    assert "candidate" in loaded.classes and "roa" in loaded.classes and loaded.candidate == VDP_V
    named = load_model_spec(spec(tmp_path, VDP, "n", 'name = "mu"\nvalues = [1]', candidate=VDP_V,
                                 classes='["roa", "candidate"]'))
    assert named.classes == ("roa", "candidate")
    plain = spec(tmp_path, VDP, "p", 'name = "mu"\nvalues = [1]', candidate=None, classes='["roa"]')
    plain.write_text(plain.read_text().replace('classes = ["roa"]\n', ""))
    assert "candidate" not in load_model_spec(plain).classes


@pytest.mark.parametrize(("candidate", "classes", "mode", "needle"), [
    ("x1**", '["candidate"]', "points", "'sweep.candidate'"),
    ("mu*x1**2 + x2**2", '["candidate"]', "points", "names the swept parameter mu"),
    ("mu*x1**2 + x2**2", '["candidate"]', "boxes", "names the swept parameter mu"),
    ("z**2 + x1**2", '["candidate"]', "points", "unknown name 'z'"),
    ("x1**2 + x2**2 + 1", '["candidate"]', "points", "'sweep.candidate'"),
    (None, '["roa", "candidate"]', "points", 'add candidate = "..."'),
])
def test_bad_candidates_exit_2_in_one_line(tmp_path: Path, candidate: str | None, classes: str, mode: str,
                                           needle: str) -> None:
    axis = 'name = "mu"\nstart = 0.8\nstop = 1.2\nnum = 2'
    assert_refused(spec(tmp_path, VDP, "bad", axis, candidate=candidate, classes=classes, mode=mode), needle)


def test_a_candidate_of_a_map_with_functions_naming_the_swept_gain_is_refused(tmp_path: Path) -> None:
    assert_refused(spec(tmp_path, TANH, "bad", 'name = "k"\nvalues = [0.6, 0.8]', candidate="k*x**2 + y**2",
                        classes='["candidate"]'), "names the swept parameter k")


@pytest.mark.slow
def test_a_candidate_certified_globally_is_cross_checked_as_a_global_v(tmp_path: Path) -> None:
    """On a damped spiral the user's V = x1**2 + x2**2 proves GAS (no level): its cross-check draws global starts
    and checks V never rises at the certified rate (it used to look for a level and stop)."""
    from tests.feature_matrix import POLYNOMIAL

    model = tmp_path / "spiral.toml"
    model.write_text(POLYNOMIAL)
    path = spec(tmp_path, model, "g", 'name = "a"\nvalues = [0.8, 1.2]', candidate="x1**2 + x2**2",
                classes='["candidate"]')
    run(path, tmp_path / "g.zarr")
    data = arrays(tmp_path / "g.zarr")
    assert list(data["status_candidate"]) == [CODES["certified"]] * 2
    assert np.all(np.isnan(data["candidate_level"]))  # GAS: no level to store
    for j in range(2):
        assert json.loads(str(data["certificate"][j]))["conditions"]["candidate"]["property"] == "GAS"
    assert list(data["cross_check_trajectories"]) == [8, 8] and not data["soundness_violation"].any()
