"""Box sweeps of a loop with functions (``mode = "boxes"`` with a ``[sweep] model`` whose ``[dynamics]``
use sin, sqrt, ...): each box certified as ``lyapcheck certify FILE --box`` certifies it, stored like
a polynomial model's box, its certificate re-checked by ``verify``, cross-checked at random parameter
points of the box on the true loop.

The loop is the damped pendulum (``recast-pendulum.toml``) over its damping b in [0.5, 2], two boxes.
Over a box only ``roa`` certifies it (the ball-arithmetic region; no global V exists because of the
saddle at theta = pi), a few seconds a box.
"""

from __future__ import annotations

import json
from fractions import Fraction
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from tests.conftest import ROOT
from tests.test_model_sweeps import arrays, run  # the model sweeps' own helpers
from tests.test_recast_sweep import write  # a spec beside its model file

PENDULUM = (ROOT / "examples" / "models" / "recast-pendulum.toml").read_text()
BOXES = """[sweep]
model = "m.toml"
mode = "boxes"
classes = ["roa"]
chunk_size = 1
[[sweep.axes]]
name = "b"
start = 0.5
stop = 2
num = 3
[sweep.boxes]
max_boxes = 2
cross_check_points = 1
[simulation]
starts = 4
"""



@pytest.fixture(scope="module")
def box_store(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, dict[str, np.ndarray]]:
    directory = tmp_path_factory.mktemp("recast-boxes")
    out = directory / "out.zarr"
    run(write(directory, BOXES), out)
    return out, arrays(out)


def test_both_boxes_of_the_pendulum_are_certified_by_roa_for_every_damping_of_the_box(
        box_store: tuple[Path, dict[str, np.ndarray]]) -> None:
    from sweeps.schema import BOX_STATUS_CODES, STATUS_CODES

    _, data = box_store
    assert len(data["status"]) == 2
    assert list(data["status"]) == [BOX_STATUS_CODES["certified"]] * 2, list(data["note"])
    assert list(data["status_roa"]) == [STATUS_CODES["certified"]] * 2
    assert list(data["lo_b"]) == [0.5, 1.25] and list(data["hi_b"]) == [1.25, 2.0]
    assert list(data["level"]) == [0, 0] and list(data["parent"]) == [-1, -1]
    for note, lo, hi in zip(data["note"], data["lo_b"], data["hi_b"]):
        assert str(note).startswith("certified by roa"), note
    assert list(data["unstable_corners"]) == [0, 0]  # checked as on a polynomial loop: b > 0 at every corner


def test_each_box_certificate_is_the_box_claim_and_passes_verify(box_store: tuple[Path, dict[str, np.ndarray]]) -> None:
    from lyapcheck.api import verify

    _, data = box_store
    for text, lo, hi in zip(data["certificate"], data["lo_b"], data["hi_b"]):
        doc = json.loads(str(text))
        assert doc["box"] == {"b": [str(Fraction(lo)), str(Fraction(hi))]}
        # the model read at the box's centre, as `certify --box` reads it
        assert Fraction(doc["overrides"]["b"]) == (Fraction(lo) + Fraction(hi)) / 2
        roa = doc["conditions"]["roa"]
        assert roa["status"] == "certified" and roa["summary"].startswith("for every b in")
        assert roa["certificate"]["parameter_box"] == doc["box"]
        checked = verify(doc)
        assert checked.valid, [c for c in checked.checks if not c.ok]
        tampered = json.loads(str(text))
        tampered["box"]["b"][1] = "3"  # a wider box than the one proved
        assert not verify(tampered).valid


def test_certified_boxes_are_simulated_at_random_parameter_points_on_the_true_loop(
        box_store: tuple[Path, dict[str, np.ndarray]]) -> None:
    _, data = box_store
    assert list(data["cross_check_points"]) == [1, 1]
    assert all(data["cross_check_trajectories"] >= 4)
    assert not data["soundness_violation"].any(), list(data["violation_detail"])
    assert all(np.isfinite(data["cross_check_worst_rise"]))


def test_a_box_whose_certificate_does_not_apply_at_a_point_says_so() -> None:
    """A certificate whose auxiliaries or shifts are not the point's own (an auxiliary with the box's
    parameter in it, such as ``sin(b*theta)``): the cross-check names the point and the reason and
    simulates nothing there."""
    from lyapcheck.models.language.modelfile import parse_any_model
    from sweeps.crosscheck import box_mismatch, cross_check_box

    model = parse_any_model(PENDULUM, "m.toml", {"b": "1"})
    cert = {"variables": ["theta", "omega", "s1", "c1"], "auxiliaries": model.system.definitions(),
            "shift": {"theta": "0", "omega": "0", "s1": "0", "c1": "1"}}
    doc: dict[str, Any] = {"conditions": {"roa": {"status": "certified", "certificate": cert}}}
    assert box_mismatch(model, doc) is None
    doc["conditions"]["roa"]["certificate"] = {**cert, "shift": {**cert["shift"], "c1": "1/2"}}
    found, skipped = cross_check_box([(model, {"b": Fraction(1)})], doc, starts=2, seed=(0, 0))
    assert found.points == 0 and found.trajectories == 0
    assert len(skipped) == 1 and skipped[0].startswith("at b = 1: the roa certificate's c1 is shifted by 1/2")
    doc["conditions"]["roa"]["certificate"] = {**cert, "auxiliaries": {"s1": "sin(2*theta)"}}
    assert "the auxiliary s1 = sin(2*theta) of the roa certificate" in str(box_mismatch(model, doc))


def test_a_box_sweep_of_a_loop_with_functions_is_no_longer_refused_and_takes_the_box_classes(tmp_path: Path) -> None:
    from lyapcheck.errors import InvalidParameter
    from sweeps.spec import load_model_spec

    spec = load_model_spec(write(tmp_path, BOXES.replace('classes = ["roa"]\n', "")))
    assert spec.mode == "boxes" and spec.has_functions
    assert spec.classes == ("linearization", "quadratic", "sos_gas", "roa")  # no [disturbances]: no sos_bound
    with pytest.raises(InvalidParameter, match="in a boxes sweep of a loop with functions"):
        load_model_spec(write(tmp_path, BOXES.replace('["roa"]', '["roa", "sos_bound_x"]')))
    with pytest.raises(InvalidParameter, match='unless \\[sweep\\] gives your V: add candidate = "..."'):
        load_model_spec(write(tmp_path, BOXES.replace('["roa"]', '["candidate"]')))  # (the user's V: the key)


def test_a_box_whose_parameter_stays_a_variable_of_the_certificate_is_stored_with_why_it_is_not_simulated(
        tmp_path: Path) -> None:
    """The ILOS loop over its lookahead Delta: ``sos_gas`` certifies the box with a V in which Delta is
    a bounded variable (the loop recast with Delta as a constant of the box), which no loop read at
    one point has: the box is certified, no point is simulated, and the note says why."""
    from sweeps.schema import BOX_STATUS_CODES

    ilos = (ROOT / "examples" / "models" / "recast-ilos-course.toml").read_text()
    spec = ('[sweep]\nmodel = "m.toml"\nmode = "boxes"\nclasses = ["sos_gas"]\n[[sweep.axes]]\nname = "Delta"\n'
            'start = 1\nstop = 2\nnum = 2\n[sweep.boxes]\ncross_check_points = 2\n')
    out = tmp_path / "out.zarr"
    run(write(tmp_path, spec, ilos), out)
    data = arrays(out)
    assert int(data["done"].sum()) == 1  # one box, certified: nothing to split
    assert data["status"][0] == BOX_STATUS_CODES["certified"] and data["cross_check_points"][0] == 0
    note = str(data["note"][0])
    assert "cross-check not applicable at 2 of 2 random points of the box (not simulated)" in note, note
    assert "the sos_gas certificate's V is a function of Delta, not a variable of the point's loop" in note


def test_an_undecided_box_is_split_in_halves_as_a_polynomial_models_box(tmp_path: Path) -> None:
    """``sos_gas`` can never certify the pendulum (the saddle at theta = pi): the box is split into its
    halves while the budget lasts, each half decided alike."""
    from sweeps.schema import BOX_STATUS_CODES

    spec = BOXES.replace('["roa"]', '["sos_gas"]').replace("num = 3", "num = 2").replace("max_boxes = 2",
                                                                                          "max_boxes = 3")
    out = tmp_path / "out.zarr"
    run(write(tmp_path, spec), out)
    data = arrays(out)
    assert int(data["done"].sum()) == 3
    assert list(data["status"]) == [BOX_STATUS_CODES["split"]] + [BOX_STATUS_CODES["not_certified"]] * 2
    assert list(data["parent"]) == [-1, 0, 0] and list(data["level"]) == [0, 1, 1]
    assert list(data["lo_b"]) == [0.5, 0.5, 1.25] and list(data["hi_b"]) == [2.0, 1.25, 2.0]
    assert all(str(c) == "" for c in data["certificate"])


def test_random_points_of_a_box_with_decimal_edges_are_read_again_from_the_model_text() -> None:
    """The cross-check reads a loop with functions again at each random point of a box, as ``--set
    NAME=VALUE``; with edges such as 0.8 (not dyadic) a float's exact value had dozens of digits and
    every point was refused, so the box was never simulated. The points are short decimals now."""
    from lyapcheck.exact import exact_decimal
    from lyapcheck.models.language.modelfile import parse_any_model
    from lyapcheck.models.language.parameter_box import ModelBox
    from lyapcheck.models.language.recast import RecastModel
    from tests.feature_matrix import FUNCTIONS

    box = ModelBox((("a", Fraction(4, 5), Fraction(6, 5)),))
    points = box.points(8, 7)
    assert len({p["a"] for p in points}) == 8
    for point in points:
        written = exact_decimal(point["a"])
        assert Fraction(4, 5) <= point["a"] <= Fraction(6, 5) and len(written) <= 10, written
        model = parse_any_model(FUNCTIONS, "functions.toml", {"a": written})
        assert isinstance(model, RecastModel) and model.parameters["a"] == point["a"]


#: the pendulum's linear part, a polynomial loop with the same damping b
LINEAR_PENDULUM = """[model]
name = "the damped pendulum's linearization"
states = ["x1", "x2"]
[parameters]
b = 1
[dynamics]
x1 = "x2"
x2 = "-x1 - b*x2"
[domain]
x1 = [-3, 3]
x2 = [-4, 4]
"""


@pytest.mark.parametrize("kind", ["functions", "polynomial"])
def test_a_box_with_an_unstable_corner_skips_the_stability_classes_on_both_kinds_of_loop(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch, kind: str) -> None:
    """b in [-0.5, 0.5]: at the corner b = -0.5 the equilibrium is unstable (the linearization refuted,
    exactly), so no stability class can hold over the box: on a loop with functions as on a polynomial
    loop, the box is refuted naming that corner, and ``roa`` is stored refuted without being run."""
    import dataclasses

    from lyapcheck.models.classes import registry
    from sweeps.schema import BOX_STATUS_CODES, STATUS_CODES

    def never(ctx: Any, budget: Any) -> Any:
        raise AssertionError("roa ran over a box with an unstable corner")

    monkeypatch.setattr(registry, "CLASSES", tuple(
        dataclasses.replace(c, run_field=never, run_functions=never) if c.name == "roa" else c
        for c in registry.CLASSES))
    spec = BOXES.replace('["roa"]', '["linearization", "roa"]').replace("start = 0.5", "start = -0.5") \
        .replace("stop = 2", "stop = 0.5").replace("num = 3", "num = 2").replace("max_boxes = 2", "max_boxes = 1")
    out = tmp_path / "out.zarr"
    run(write(tmp_path, spec, PENDULUM if kind == "functions" else LINEAR_PENDULUM), out)
    data = arrays(out)
    assert list(data["status"]) == [BOX_STATUS_CODES["refuted"]], list(data["note"])
    assert list(data["status_linearization"]) == list(data["status_roa"]) == [STATUS_CODES["refuted"]]
    assert list(data["unstable_corners"]) == [1]
    assert str(data["note"][0]).startswith("unstable at the corner b = -0.5: "), data["note"][0]
