"""Point sweeps of a discrete-time map (``[sweep] model = FILE`` with ``[model] time = "discrete"``): each grid
point certified as ``certify FILE --set`` certifies the map, each certified point cross-checked by iterating
the map (sweeps.crosscheck._MapLoop), never by integrating it; ``mode = "boxes"`` refused in one line.

The shipped example examples/models/sweeps/points-discrete-map.toml sweeps the gain a of
discrete-gain-map.toml (Jacobian eigenvalues a and 3/5: stable for |a| < 1, unstable for a > 1).
"""

from __future__ import annotations

import copy
import json
from fractions import Fraction
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from lyapcheck.errors import InvalidParameter
from tests.conftest import ROOT
from tests.test_model_sweeps import arrays, assert_refused, run  # the model sweeps' own helpers

EXAMPLES = ROOT / "examples" / "models"
SPEC = EXAMPLES / "sweeps" / "points-discrete-map.toml"
GAIN_MAP = (EXAMPLES / "discrete-gain-map.toml").read_text()
CODES = {"certified": 1, "refuted": 2, "not_certified": 0}


def never_integrate(*args: Any, **kwargs: Any) -> Any:
    raise AssertionError("a discrete-time map was integrated as a field")


@pytest.fixture(scope="module")
def gain_sweep(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Any]:
    """The example spec run inline with the project's integrator replaced by a function that fails."""
    import lyapcheck.models.engines.trajectories as trajectories

    out = tmp_path_factory.mktemp("gain") / "gain.zarr"
    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(trajectories, "simulate", never_integrate)
        return out, run(SPEC, out)


@pytest.mark.slow
def test_the_gain_sweep_certifies_the_stable_range_and_refutes_the_unstable_one(gain_sweep: tuple[Path, Any]) -> None:
    from lyapcheck.api import verify

    path, result = gain_sweep
    data = arrays(path)
    a = data["a"]
    stable = np.abs(a) < 1
    assert stable.any() and (~stable).any()  # the example covers both ranges
    assert result.mode == "model_points" and result.summary.computed == len(a)
    assert list(data["status"]) == [CODES["certified"] if s else CODES["refuted"] for s in stable]
    assert list(data["status_linearization"]) == [CODES["certified"] if s else CODES["refuted"] for s in stable]
    assert all(data["status_roa"][stable] == CODES["certified"])
    for j in np.flatnonzero(~stable):
        assert "eigenvalue of modulus > 1" in str(data["note"][j]) and data["certificate"][j] == ""
    for j in np.flatnonzero(stable):
        doc = json.loads(str(data["certificate"][j]))
        assert Fraction(doc["overrides"]["a"]) == Fraction(float(a[j])) and verify(doc).valid
        assert doc["conditions"]["roa"]["certificate"]["kind"] == "discrete_sublevel"
        # the cross-check iterated the map from the certified set: no rise, no escape, no alarm
        assert data["cross_check_points"][j] == 1 and data["cross_check_trajectories"][j] > 0
        assert data["cross_check_worst_rise"][j] <= 1e-9 and not data["soundness_violation"][j]
    # the store's page says the map was iterated, in steps
    from reports.render import sweep_html

    page = sweep_html(str(path))
    assert "Cross-check by iterating the map" in page and "sequences of iterates iterated" in page
    assert "trajector" not in page and "Cross-check by simulation" not in page


@pytest.fixture(scope="module")
def local_doc() -> dict[str, Any]:
    from lyapcheck.api import certify

    found = certify(model=EXAMPLES / "discrete-local-map.toml", classes="linearization,roa")
    return dict(found.document)


def test_the_map_cross_check_catches_a_false_region(local_doc: dict[str, Any], monkeypatch: pytest.MonkeyPatch
                                                    ) -> None:
    """The certified region passes; ten times its level reaches past the second fixed point (1/2, -1/2),
    whose iterates escape: a soundness violation, found by iterating (the integrator would raise)."""
    import lyapcheck.models.engines.trajectories as trajectories
    from lyapcheck.models.language.modelfile import parse_model
    from sweeps.crosscheck import cross_check_point

    monkeypatch.setattr(trajectories, "simulate", never_integrate)
    model = parse_model(local_doc["model"]["text"], "local")
    found = cross_check_point(model, local_doc, {}, starts=8, seed=(0, 0))
    assert not found.violation and found.trajectories >= 8 and found.worst_rise <= 1e-9
    false = copy.deepcopy(local_doc)
    cert = false["conditions"]["roa"]["certificate"]
    cert["level"] = str(Fraction(cert["level"]) * 10)
    found = cross_check_point(model, false, {}, starts=8, seed=(0, 0))
    assert found.violation and "roa at" in found.violations[0] and "escaped" in found.violations[0]


def test_a_global_map_certificate_is_checked_per_step(monkeypatch: pytest.MonkeyPatch) -> None:
    """sos_gas on fossil-dt-ahmadi: V(e_k) <= (1 - mu)^k V(e_0) holds along the iterates; a stated mu near 1
    (V divided by 100 at every step) does not, and the envelope check says so."""
    import lyapcheck.models.engines.trajectories as trajectories
    from lyapcheck.api import certify
    from lyapcheck.models.language.modelfile import parse_model
    from sweeps.crosscheck import cross_check_point

    monkeypatch.setattr(trajectories, "simulate", never_integrate)
    doc = dict(certify(model=EXAMPLES / "fossil-dt-ahmadi.toml", classes="sos_gas").document)
    assert doc["conditions"]["sos_gas"]["status"] == "certified"
    model = parse_model(doc["model"]["text"], "ahmadi")
    found = cross_check_point(model, doc, {}, starts=8, seed=(0, 0))
    assert not found.violation and found.trajectories == 8 and found.worst_envelope <= 1e-9
    false = copy.deepcopy(doc)
    false["conditions"]["sos_gas"]["decay_rate_V_per_step"] = 0.99
    found = cross_check_point(model, false, {}, starts=8, seed=(0, 0))
    assert found.violation and found.worst_envelope > 0.1 and "exceeded V(0) exp(-" in found.violations[0]


def test_boxes_and_classes_a_map_does_not_take_are_refused_in_one_line(tmp_path: Path) -> None:
    from sweeps.spec import load_model_spec

    (tmp_path / "m.toml").write_text(GAIN_MAP)
    boxes = tmp_path / "boxes.toml"
    boxes.write_text('[sweep]\nmodel = "m.toml"\nmode = "boxes"\n[[sweep.axes]]\nname = "a"\nstart = 0.3\n'
                     'stop = 0.9\nnum = 2\n')
    assert_refused(boxes, 'boxes are not taken on maps yet')
    barrier = tmp_path / "barrier.toml"
    barrier.write_text('[sweep]\nmodel = "m.toml"\nclasses = ["barrier"]\n[[sweep.axes]]\nname = "a"\n'
                       'start = 0.3\nstop = 0.9\nnum = 2\n')
    with pytest.raises(InvalidParameter, match=r"sweep.classes.*discrete-time map.*'linearization', 'quadratic', "
                                               r"'sos_gas', 'roa'"):
        load_model_spec(barrier)
    points = tmp_path / "points.toml"
    points.write_text('[sweep]\nmodel = "m.toml"\n[[sweep.axes]]\nname = "a"\nstart = 0.3\nstop = 0.9\nnum = 2\n')
    assert load_model_spec(points).classes == ("linearization", "quadratic", "sos_gas", "roa")


def test_a_map_with_functions_is_cross_checked_by_iterating_its_true_map(monkeypatch: pytest.MonkeyPatch,
                                                                         tmp_path: Path) -> None:
    """roa of a map with functions (discrete_interval, V = e^T P e): the iterates of starts inside it, the
    functions evaluated by numpy; no integrator."""
    import lyapcheck.models.engines.trajectories as trajectories
    from lyapcheck.api import certify
    from lyapcheck.models.language.modelfile import parse_any_model
    from tests.test_discrete_reports import WITH_FUNCTIONS

    monkeypatch.setattr(trajectories, "simulate", never_integrate)
    path = tmp_path / "sine-map.toml"
    path.write_text(WITH_FUNCTIONS)
    doc = dict(certify(model=path, classes="linearization,roa").document)
    assert doc["conditions"]["roa"]["certificate"]["kind"] == "discrete_interval"
    from sweeps.crosscheck import cross_check_point

    found = cross_check_point(parse_any_model(WITH_FUNCTIONS, str(path)), doc, {}, starts=8, seed=(0, 0))
    assert not found.violation and found.trajectories == 8 and found.not_converged == 0


# -- the safety classes of a map, swept: iterated from the initial set -------------------------------------
SAFETY_SPEC = EXAMPLES / "sweeps" / "points-discrete-safety.toml"
ROTATION = (EXAMPLES / "discrete-rotation-map.toml").read_text()


@pytest.mark.slow
def test_a_map_s_barrier_and_reach_avoid_are_swept_and_cross_checked_by_iterating(tmp_path: Path) -> None:
    """The rotation map over g: barrier and reach_avoid certified where g sqrt(2) < 1, refuted at g = 0.8; each
    certified point's claims iterated from starts in the initial set (no integrator): none unsafe, each
    start in the goal within the certified number of steps, stored in a column that says steps."""
    import lyapcheck.models.engines.trajectories as trajectories
    from lyapcheck.api import verify

    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(trajectories, "simulate", never_integrate)
        result = run(SAFETY_SPEC, tmp_path / "rotation.zarr")
    data = arrays(tmp_path / "rotation.zarr")
    g = data["g"]
    contracting = g * np.sqrt(2) < 1
    assert contracting.any() and (~contracting).any() and result.summary.computed == len(g)
    for c in ("barrier", "reach_avoid"):
        assert list(data[f"status_{c}"]) == [CODES["certified"] if s else CODES["refuted"] for s in contracting]
    assert "reach_avoid_reach_time_bound_s" not in data and "barrier_lambda_per_s" not in data
    for j in np.flatnonzero(contracting):
        doc = json.loads(str(data["certificate"][j]))
        assert verify(doc).valid
        assert data["reach_avoid_reach_steps_bound"][j] == doc["conditions"]["reach_avoid"]["reach_steps_bound"]
        assert data["cross_check_trajectories"][j] == 16 and not data["soundness_violation"][j]
        assert data["cross_check_unsafe_margin"][j] < 0 and 0 <= data["cross_check_reach_ratio"][j] <= 1
    assert np.all(np.isnan(data["reach_avoid_reach_steps_bound"][~contracting]))


@pytest.fixture(scope="module")
def rotation_doc() -> tuple[Any, dict[str, Any]]:
    from lyapcheck.api import certify
    from lyapcheck.models.language.modelfile import parse_model

    found = certify(model=EXAMPLES / "discrete-rotation-map.toml", classes="barrier,reach_avoid")
    doc = dict(found.document)
    assert all(doc["conditions"][c]["status"] == "certified" for c in ("barrier", "reach_avoid"))
    return parse_model(ROTATION, "rotation"), doc


def test_the_map_safety_cross_check_catches_false_claims(rotation_doc: tuple[Any, dict[str, Any]],
                                                         monkeypatch: pytest.MonkeyPatch) -> None:
    """The certified claims pass; the same claims stated of the expanding map (g = 0.8, whose third iterate
    enters the unsafe disc) are contradicted, and a steps bound of 1 (the goal is 6 or more steps away) is
    late, all found by iterating."""
    import lyapcheck.models.engines.trajectories as trajectories
    from sweeps.crosscheck import cross_check_point

    monkeypatch.setattr(trajectories, "simulate", never_integrate)
    model, doc = rotation_doc
    found = cross_check_point(model, doc, {}, starts=16, seed=(0, 0))
    assert not found.violation and found.trajectories == 16 and found.unsafe_margin < 0 and found.reach_ratio <= 1
    found = cross_check_point(model, doc, {"g": Fraction(4, 5)}, starts=16, seed=(0, 0))
    assert any(v.startswith("barrier at g = 0.8") and "entered the unsafe set" in v for v in found.violations)
    assert any(v.startswith("reach_avoid at g = 0.8") and "before the goal" in v for v in found.violations)
    late = copy.deepcopy(doc)
    late["conditions"]["reach_avoid"]["reach_steps_bound"] = 1
    found = cross_check_point(model, late, {}, starts=16, seed=(0, 0))
    assert len(found.violations) == 1 and "not in the goal by the certified 1 steps" in found.violations[0]
    assert found.reach_ratio > 1


def test_map_reach_counts_steps_exactly() -> None:
    """A first goal iterate at step k is late only beyond the bound; a start never in the goal is late once
    iterated to the bound; an unsafe iterate counts only before the goal."""
    from sweeps.crosscheck import map_reach_avoid

    steps = np.arange(5, dtype=np.float64)
    out = np.full(5, -0.5)
    goal_at_3 = np.where(steps >= 3, 0.1, -0.2)
    assert map_reach_avoid([(steps, out, goal_at_3)], 3).late == 0
    assert map_reach_avoid([(steps, out, goal_at_3)], 2).late == 1
    never = np.full(5, -0.2)
    assert map_reach_avoid([(steps, out, never)], 4).late == 1  # e_0..e_4 all out of the goal
    assert map_reach_avoid([(steps, out, never)], 5).late == 0  # e_5 not seen: not conclusive
    unsafe_after = np.where(steps == 4, 0.3, -0.5)
    assert map_reach_avoid([(steps, unsafe_after, goal_at_3)], 3).entered == 0
    assert map_reach_avoid([(steps, unsafe_after, never)], 9).entered == 1
    assert map_reach_avoid([(steps, out, goal_at_3)], 6).reach_ratio == pytest.approx(0.5)


def test_a_map_s_rates_are_stored_per_step(tmp_path: Path) -> None:
    """quadratic and sos_gas on the (linear) rotation map: their rates per step in columns that say so, as the
    certificate states them; no per-second column on a map."""
    (tmp_path / "rotation.toml").write_text(ROTATION)
    spec = tmp_path / "rates.toml"
    spec.write_text('[sweep]\nmodel = "rotation.toml"\nclasses = ["quadratic", "sos_gas"]\n[[sweep.axes]]\n'
                    'name = "g"\nstart = 0.4\nstop = 0.6\nnum = 2\n[simulation]\nstarts = 4\n')
    run(spec, tmp_path / "rates.zarr")
    data = arrays(tmp_path / "rates.zarr")
    assert not any(k.endswith("_per_s") for k in data)
    for j in range(2):
        doc = json.loads(str(data["certificate"][j]))
        for c in ("quadratic", "sos_gas"):
            cond = doc["conditions"][c]
            assert cond["status"] == "certified"
            assert data[f"{c}_decay_rate_V_per_step"][j] == cond["decay_rate_V_per_step"] > 0
        if doc["conditions"]["quadratic"].get("contraction_per_step") is not None:
            assert data["quadratic_contraction_per_step"][j] == doc["conditions"]["quadratic"]["contraction_per_step"]
            assert data["quadratic_k"][j] == doc["conditions"]["quadratic"]["k"]
        assert not data["soundness_violation"][j]
    from reports.render import sweep_html

    assert "decay_rate_V_per_step" in sweep_html(str(tmp_path / "rates.zarr"))
