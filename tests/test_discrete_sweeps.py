"""Sweeps of a discrete-time map (``[sweep] model = FILE`` with ``[model] time = "discrete"``): each grid point
certified as ``certify FILE --set`` certifies the map, each box as ``certify FILE --box`` does (a polynomial
map: linearization, quadratic, sos_gas, roa, sos_bound; a map with functions: linearization, roa), each certified
point or box cross-checked by iterating the map (sweeps.crosscheck._MapLoop; a map with functions' true map),
never by integrating it; a map's sos_bound iterated under disturbances within its bounds; classes a map does not
take over a box refused in one line.

The shipped examples examples/models/sweeps/points-discrete-map.toml and boxes-discrete-map.toml sweep the
gain a of discrete-gain-map.toml (Jacobian eigenvalues a and 3/5: stable for |a| < 1, unstable for a > 1);
boxes-discrete-tanh-map.toml the gain k of discrete-tanh-gain-map.toml (Schur stable exactly for |k| < 3/2).
"""

from __future__ import annotations

import copy
import json
import math
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


def test_classes_a_map_does_not_take_are_refused_in_one_line(tmp_path: Path) -> None:
    from sweeps.spec import load_model_spec

    (tmp_path / "m.toml").write_text(GAIN_MAP)
    boxes = tmp_path / "boxes.toml"
    boxes.write_text('[sweep]\nmodel = "m.toml"\nmode = "boxes"\n[[sweep.axes]]\nname = "a"\nstart = 0.3\n'
                     'stop = 0.9\nnum = 2\n')
    # what --box proves over a box of a map and the sweep cross-checks by iterating (sos_bound: no disturbance here)
    assert load_model_spec(boxes).classes == ("linearization", "quadratic", "sos_gas", "roa")
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


# -- a map's sos_bound, swept point by point: iterated under disturbances within its bounds ----------------
DISTURBED = (EXAMPLES / "discrete-disturbed-map.toml").read_text()
#: discrete-disturbed-map.toml with the gain of x made a parameter: x+ = a x + y^2/10, y+ = 3y/5 + d, |d| <= 1/2
GAINED = DISTURBED.replace('[disturbances]', '[parameters]\na = 0.5\n\n[disturbances]').replace(
    'x = "0.5*x + 0.1*y**2"', 'x = "a*x + 0.1*y**2"')


@pytest.mark.slow
def test_a_map_s_sos_bound_is_swept_and_its_bound_iterated_under_disturbances(tmp_path: Path) -> None:
    """At a = 1/4 and 1/2 each output's bound certifies and verifies; iterated under the three disturbance
    policies (the constant d = 1/2 drives y to (1/2)/(1 - 3/5) = 5/4 and x to (5/4)^2/10/(1 - a)), the tail sup
    stays under it, no alarm, and the constant policy reaches those limits (the check is not vacuous)."""
    import lyapcheck.models.engines.trajectories as trajectories
    from lyapcheck.api import verify

    (tmp_path / "m.toml").write_text(GAINED)
    spec = tmp_path / "bound.toml"
    spec.write_text('[sweep]\nmodel = "m.toml"\nclasses = ["sos_bound"]\nchunk_size = 1\n[[sweep.axes]]\nname = "a"\n'
                    'values = [0.25, 0.5]\n[simulation]\nstarts = 8\n')
    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(trajectories, "simulate", never_integrate)
        run(spec, tmp_path / "bound.zarr")
    data = arrays(tmp_path / "bound.zarr")
    assert list(data["status_sos_bound"]) == [CODES["certified"]] * 2
    for j, a in enumerate(data["a"]):
        doc = json.loads(str(data["certificate"][j]))
        assert verify(doc).valid and doc["conditions"]["sos_bound"]["disturbances"] == "all"
        limit_y, limit_x = 1.25, 1.25 ** 2 / 10 / (1 - a)
        assert limit_y * 0.99 <= data["sim_worst_y"][j] <= data["sos_bound_y"][j]
        assert limit_x * 0.99 <= data["sim_worst_x"][j] <= data["sos_bound_x"][j]
        assert data["tightness_x"][j] == pytest.approx(data["sos_bound_x"][j] / data["sim_worst_x"][j])
        # 1 + 8 starts, each under uniform, bang-bang and both constant vertices
        assert data["cross_check_trajectories"][j] == 9 * 4 and not data["soundness_violation"][j]


@pytest.fixture(scope="module")
def bound_doc() -> tuple[Any, dict[str, Any]]:
    from lyapcheck.api import certify
    from lyapcheck.models.language.modelfile import parse_model

    doc = dict(certify(model=EXAMPLES / "discrete-disturbed-map.toml", classes="sos_bound").document)
    assert doc["conditions"]["sos_bound"]["status"] == "certified"
    return parse_model(DISTURBED, "disturbed"), doc


def test_the_map_bound_cross_check_passes_and_catches_a_bound_too_small(bound_doc: tuple[Any, dict[str, Any]],
                                                                        monkeypatch: pytest.MonkeyPatch) -> None:
    """The certified bounds pass; a bound stated below the constant disturbance's limit (|x| -> 0.3125) is
    contradicted by the iterates (its certificate's V and lam are the true ones), and so is a forged V of 0
    (whose envelope would be the bound itself from the first step)."""
    import lyapcheck.models.engines.trajectories as trajectories
    from sweeps.crosscheck import cross_check_point

    monkeypatch.setattr(trajectories, "simulate", never_integrate)
    model, doc = bound_doc
    found = cross_check_point(model, doc, {}, starts=8, seed=(0, 0))
    assert not found.violation and found.trajectories == 9 * 4
    assert 0.3125 * 0.99 <= found.sim_worst["x"] <= doc["conditions"]["sos_bound"]["bounds"]["x"]
    small = copy.deepcopy(doc)
    small["conditions"]["sos_bound"]["bounds"]["x"] = 0.3
    found = cross_check_point(model, small, {}, starts=8, seed=(0, 0))
    assert len(found.violations) == 1 and found.violations[0].startswith("sos_bound at")
    assert "|x - x_eq| reached" in found.violations[0] and "above the certified 0.3" in found.violations[0]
    flat = copy.deepcopy(doc)
    for cert in flat["conditions"]["sos_bound"]["certificate"]["outputs"].values():
        cert["V"] = {"terms": []}
    found = cross_check_point(model, flat, {}, starts=8, seed=(0, 0))  # starts outside the bound: above it at step 0
    assert found.violation and all(v.startswith("sos_bound at") for v in found.violations)


def test_the_map_bound_envelope_is_the_certificate_s_induction() -> None:
    """|y_k|^2 <= bound^2 + lam^k max(V(e_0) - 1, 0): V(e_0) = 5, lam = 1/2 gives bound^2 + 4, + 2, + 1, ...;
    a start inside {V <= 1} gets the bound at every step; an unreadable certificate, the bound on the tail only."""
    from sweeps.crosscheck import MAP_BOUND_TAIL_STEPS, _bound_envelope

    cert = {"lam": "1/2", "V": {"terms": [["1", [2, 0]]]}}  # V = x^2 (the ring: x, then the disturbance d)
    es = np.zeros((2, 4, 1))
    es[0, 0, 0], es[1, 0, 0] = math.sqrt(5.0), 0.5
    envelope = _bound_envelope(cert, 3.0, es, ["x"], ["d"])
    assert envelope[0] == pytest.approx(np.sqrt(9 + 4 * 0.5 ** np.arange(4)))
    assert envelope[1] == pytest.approx([3.0] * 4)
    blind = _bound_envelope(None, 3.0, np.zeros((1, MAP_BOUND_TAIL_STEPS + 5, 1)), ["x"], ["d"])
    assert np.all(np.isinf(blind[0, :5])) and np.all(blind[0, 5:] == 3.0)


# -- a map swept box by box ------------------------------------------------------------------------------
BOX_SPEC = EXAMPLES / "sweeps" / "boxes-discrete-map.toml"
#: a linear map whose gain a is Schur stable for a < 1.12 (the Jacobian's spectral radius < 1) and unstable beyond
LINEAR_MAP = ('[model]\nname = "a linear map with a gain a"\nstates = ["x", "y"]\ntime = "discrete"\n'
              '[parameters]\na = 0.5\n[dynamics]\nx = "a*x + 0.4*y"\ny = "-0.3*x + 0.6*y"\n')


@pytest.mark.slow
def test_the_gain_map_s_boxes_are_proved_below_one_and_refuted_above(tmp_path: Path) -> None:
    """The example: boxes inside a < 1 certified by linearization over the box (verify re-checks it), each
    iterated at its two corners and two random points (the Jacobian's iterates: no rise of V); boxes with a
    corner a > 1 refuted, exactly; no integrator anywhere; the store's report page is written."""
    import lyapcheck.models.engines.trajectories as trajectories
    from lyapcheck.api import verify

    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(trajectories, "simulate", never_integrate)
        result = run(BOX_SPEC, tmp_path / "boxes.zarr")
    data = arrays(tmp_path / "boxes.zarr")
    assert result.mode == "model_boxes"
    done = data["done"].astype(bool)
    leaf = done & (data["status"] != 3)
    certified = leaf & (data["status"] == CODES["certified"])
    refuted = leaf & (data["status"] == CODES["refuted"])
    assert certified.any() and refuted.any() and not (leaf & (data["status"] == CODES["not_certified"])).any()
    assert np.all(data["hi_a"][certified] < 1) and np.all(data["hi_a"][refuted] > 1)
    assert "quadratic_decay_rate_V_per_step" in data and "quadratic_decay_rate_V_per_s" not in data
    for j in np.flatnonzero(certified):
        doc = json.loads(str(data["certificate"][j]))
        assert verify(doc).valid and doc["conditions"]["linearization"]["status"] == "certified"
        # (a split box's exact edges, stored as floats)
        assert [float(Fraction(v)) for v in doc["box"]["a"]] == [data["lo_a"][j], data["hi_a"][j]]
        assert data["cross_check_points"][j] == 2 + 2 and data["cross_check_trajectories"][j] > 0
        assert data["cross_check_worst_rise"][j] <= 1e-9 and not data["soundness_violation"][j]
    for j in np.flatnonzero(refuted):
        assert "eigenvalue of modulus > 1" in str(data["note"][j]) and data["unstable_corners"][j] >= 1
    # the store's report reads the map's per-step columns (it once asked for the per-second ones: KeyError)
    from tests.test_discrete_reports import cli

    page = tmp_path / "boxes.html"
    assert cli("report", str(tmp_path / "boxes.zarr"), "--html", str(page)).exit_code == 0
    assert "Cross-check by iterating the map" in page.read_text()


@pytest.fixture(scope="module")
def linear_box_doc(tmp_path_factory: pytest.TempPathFactory) -> tuple[Any, dict[str, Any]]:
    from lyapcheck.api import certify
    from lyapcheck.models.language.modelfile import parse_model

    path = tmp_path_factory.mktemp("linear") / "linear.toml"
    path.write_text(LINEAR_MAP)
    doc = dict(certify(model=path, box=["a=0.3..0.6"], classes="linearization,quadratic").document)
    assert all(doc["conditions"][c]["status"] == "certified" for c in ("linearization", "quadratic"))
    return parse_model(LINEAR_MAP, "linear"), doc


def test_a_map_s_box_certificates_are_iterated_at_its_corners_and_false_ones_caught(
        linear_box_doc: tuple[Any, dict[str, Any]], monkeypatch: pytest.MonkeyPatch) -> None:
    """The box's quadratic (GES, per step) and linearization (one P for every Jacobian) pass at the box's
    corners; the same certificates at a = 1.2 (outside the box, the map unstable there), a contraction per step
    forged to 0.5 and a linearization's mu forged to 0.9 are each caught by iterating."""
    import lyapcheck.models.engines.trajectories as trajectories
    from sweeps.crosscheck import cross_check_box

    monkeypatch.setattr(trajectories, "simulate", never_integrate)
    model, doc = linear_box_doc
    corners = [(model, {"a": Fraction(3, 10)}), (model, {"a": Fraction(3, 5)})]
    found, skipped = cross_check_box(corners, doc, starts=8, seed=(0, 0))
    assert not found.violation and not skipped and found.points == 2
    assert found.worst_rise <= 1e-9 and found.ges_ratio <= 1 and found.trajectories == 2 * (8 + 8)
    found, _ = cross_check_box([(model, {"a": Fraction(6, 5)})], doc, starts=8, seed=(0, 0))
    assert any(v.startswith("quadratic at a = 1.2") for v in found.violations)
    assert any(v.startswith("linearization at a = 1.2") and "Jacobian" in v for v in found.violations)
    fast = copy.deepcopy(doc)
    fast["conditions"]["quadratic"]["contraction_per_step"] = 0.5
    found, _ = cross_check_box(corners, fast, starts=8, seed=(0, 0))
    assert found.ges_ratio > 1 and any("GES envelope" in v for v in found.violations)
    steep = copy.deepcopy(doc)
    steep["conditions"]["linearization"]["certificate"]["mu"] = "9/10"
    found, _ = cross_check_box(corners, steep, starts=8, seed=(0, 0))
    assert [v for v in found.violations if v.startswith("linearization at")] and found.worst_envelope > 0.1


def test_a_map_s_box_sweep_refuses_classes_it_does_not_take(tmp_path: Path) -> None:
    """Over boxes a polynomial map takes linearization, quadratic, sos_gas, roa, sos_bound, and barrier and
    reach_avoid with their sets: barrier on a map without sets is refused in one line naming the field, the
    accepted classes and what was given (exit 2, nothing written); a map with functions takes linearization,
    quadratic, sos_gas and roa (its default), and barrier over boxes is refused alike."""
    from sweeps.spec import load_model_spec
    from tests.test_discrete_reports import WITH_FUNCTIONS

    (tmp_path / "m.toml").write_text(GAIN_MAP)
    barrier = tmp_path / "barrier.toml"
    barrier.write_text('[sweep]\nmodel = "m.toml"\nmode = "boxes"\nclasses = ["linearization", "barrier"]\n'
                       '[[sweep.axes]]\nname = "a"\nstart = 0.3\nstop = 0.9\nnum = 2\n')
    assert_refused(barrier, "'sweep.classes' parameter must be in a boxes sweep of a discrete-time map")
    with pytest.raises(InvalidParameter) as refused:
        load_model_spec(barrier)
    line = str(refused.value)
    assert "'linearization', 'quadratic', 'sos_gas', 'roa', 'sos_bound' (" in line and "'barrier'" in line
    functions = tmp_path / "functions"
    functions.mkdir()
    (functions / "f.toml").write_text(WITH_FUNCTIONS.replace("0.5*tanh(y)", "k*tanh(y)").replace(
        "[dynamics]", "[parameters]\nk = 0.5\n[dynamics]"))
    boxes = functions / "boxes.toml"
    boxes.write_text('[sweep]\nmodel = "f.toml"\nmode = "boxes"\n[[sweep.axes]]\nname = "k"\nstart = 0.3\n'
                     'stop = 0.4\nnum = 2\n')
    assert load_model_spec(boxes).classes == ("linearization", "quadratic", "sos_gas", "roa")
    refused_class = functions / "barrier.toml"
    refused_class.write_text(boxes.read_text().replace('mode = "boxes"', 'mode = "boxes"\nclasses = ["barrier"]'))
    assert_refused(refused_class, "'sweep.classes' parameter must be in a boxes sweep of a discrete-time map with "
                                  "functions, a list of distinct names from 'linearization', 'quadratic', 'sos_gas', "
                                  "'roa', 'sos_bound' (")


# -- a polynomial map's roa and sos_bound over boxes: a set and a bound for every value of the box -----------
@pytest.mark.slow
def test_a_polynomial_map_s_roa_and_sos_bound_are_swept_over_boxes(tmp_path: Path) -> None:
    """The gained disturbed map (x+ = a x + y^2/10, y+ = 3y/5 + d) over a in [0.3, 0.6]: roa (one {V <= c}) and
    sos_bound (one bound) certified for every a of the box (verify re-checks them), each iterated at the box's
    two corners and two random points, no alarm; the bound's tail sup reaches the constant-disturbance limit."""
    import lyapcheck.models.engines.trajectories as trajectories
    from lyapcheck.api import verify

    (tmp_path / "m.toml").write_text(GAINED)
    spec = tmp_path / "boxes.toml"
    spec.write_text('[sweep]\nmodel = "m.toml"\nmode = "boxes"\nclasses = ["roa", "sos_bound"]\n[[sweep.axes]]\n'
                    'name = "a"\nstart = 0.3\nstop = 0.6\nnum = 2\n[sweep.boxes]\nmax_boxes = 1\n'
                    'cross_check_points = 2\n[simulation]\nstarts = 8\n')
    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(trajectories, "simulate", never_integrate)
        run(spec, tmp_path / "boxes.zarr")
    data = arrays(tmp_path / "boxes.zarr")
    assert data["status_roa"][0] == CODES["certified"] and data["status_sos_bound"][0] == CODES["certified"]
    doc = json.loads(str(data["certificate"][0]))
    assert verify(doc).valid and [float(Fraction(v)) for v in doc["box"]["a"]] == [0.3, 0.6]
    assert data["cross_check_points"][0] == 2 + 2 and not data["soundness_violation"][0]
    assert data["cross_check_worst_rise"][0] <= 1e-9
    assert 1.25 * (1 - 1e-6) <= data["sim_worst_y"][0] <= data["sos_bound_y"][0]


@pytest.fixture(scope="module")
def gain_box_docs(tmp_path_factory: pytest.TempPathFactory) -> tuple[Any, dict[str, Any], Any, dict[str, Any]]:
    """(the gain map, its roa over a in [0.3, 0.9]; the gained disturbed map, its sos_bound over a in [0.3, 0.6])."""
    from lyapcheck.api import certify
    from lyapcheck.models.language.modelfile import parse_model

    roa = dict(certify(model=EXAMPLES / "discrete-gain-map.toml", box=["a=0.3..0.9"], classes="roa").document)
    path = tmp_path_factory.mktemp("gained") / "gained.toml"
    path.write_text(GAINED)
    bound = dict(certify(model=path, box=["a=0.3..0.6"], classes="sos_bound").document)
    assert roa["conditions"]["roa"]["status"] == bound["conditions"]["sos_bound"]["status"] == "certified"
    return parse_model(GAIN_MAP, "gain"), roa, parse_model(GAINED, "gained"), bound


def test_a_map_s_box_set_and_bound_are_iterated_and_forged_ones_caught(
        gain_box_docs: tuple[Any, dict[str, Any], Any, dict[str, Any]], monkeypatch: pytest.MonkeyPatch) -> None:
    """At the box's corners the region (starts in {V <= c}) and the bound (under disturbances, within its
    envelope: read over the box, so finite from the first step) pass; a level forged 100 times larger (starts
    past the second fixed point escape) and a bound forged to half are caught by iterating."""
    import lyapcheck.models.engines.trajectories as trajectories
    from sweeps.crosscheck import _bound_envelope, cross_check_box

    monkeypatch.setattr(trajectories, "simulate", never_integrate)
    gain, roa, gained, bound = gain_box_docs
    corners = [(gain, {"a": Fraction(3, 10)}), (gain, {"a": Fraction(9, 10)})]
    found, skipped = cross_check_box(corners, roa, starts=8, seed=(0, 0))
    assert not found.violation and not skipped and found.trajectories == 16 and found.worst_rise <= 1e-9
    forged = copy.deepcopy(roa)
    cert = forged["conditions"]["roa"]["certificate"]
    cert["level"] = str(Fraction(cert["level"]) * 100)
    found, _ = cross_check_box(corners, forged, starts=8, seed=(0, 0))
    assert found.violation and all(v.startswith("roa at a = ") for v in found.violations)
    corners = [(gained, {"a": Fraction(3, 10)}), (gained, {"a": Fraction(3, 5)})]
    found, _ = cross_check_box(corners, bound, starts=8, seed=(0, 0))
    assert not found.violation and found.sim_worst["y"] >= 1.25 * (1 - 1e-6)
    cond = bound["conditions"]["sos_bound"]
    es = np.zeros((1, 5, 2))
    es[0, 0] = [3.0, 3.0]  # a start outside {V <= 1}: the envelope is above the bound at first, then decays to it
    envelope = _bound_envelope(cond["certificate"]["outputs"]["y"], cond["bounds"]["y"], es, ["x", "y"], ["d"],
                               {"a": Fraction(1, 2)})
    assert np.all(np.isfinite(envelope)) and envelope[0, 0] > envelope[0, -1] >= cond["bounds"]["y"]
    halved = copy.deepcopy(bound)
    halved["conditions"]["sos_bound"]["bounds"]["y"] = cond["bounds"]["y"] / 2
    found, _ = cross_check_box(corners, halved, starts=8, seed=(0, 0))
    assert any(v.startswith("sos_bound at a = ") and "above the certified" in v for v in found.violations)


# -- a map with functions over boxes: linearization and roa, its true map iterated ---------------------------
TANH_SPEC = EXAMPLES / "sweeps" / "boxes-discrete-tanh-map.toml"
TANH_MAP = (EXAMPLES / "discrete-tanh-gain-map.toml").read_text()


@pytest.fixture(scope="module")
def tanh_sweep(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The example run inline, with the integrator replaced by a function that fails."""
    import lyapcheck.models.engines.trajectories as trajectories

    out = tmp_path_factory.mktemp("tanh") / "whole" / "out.zarr"
    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(trajectories, "simulate", never_integrate)
        run(TANH_SPEC, out)
    return out


@pytest.mark.slow
def test_the_tanh_map_s_boxes_are_proved_below_three_halves_and_refuted_above(tanh_sweep: Path) -> None:
    """Boxes below k = 3/2 certified (linearization; roa on the narrower ones), each iterated on its true map at
    its two corners and two random points without an alarm; boxes with a corner k > 3/2 refuted, exactly; the
    store's report page is written."""
    from lyapcheck.api import verify
    from tests.test_discrete_reports import cli

    data = arrays(tanh_sweep)
    done = data["done"].astype(bool)
    leaf = done & (data["status"] != 3)
    certified = leaf & (data["status"] == CODES["certified"])
    refuted = leaf & (data["status"] == CODES["refuted"])
    assert certified.any() and refuted.any() and (data["status_roa"][certified] == CODES["certified"]).any()
    # (a refuted box's upper corner is a hair above 3/2: the split of [1.2000000000000002, 1.8], stored as 1.5)
    assert np.all(data["hi_k"][certified] < 1.5) and np.all(data["hi_k"][refuted] >= 1.5)
    for j in np.flatnonzero(certified):
        assert data["cross_check_points"][j] == 2 + 2 and data["cross_check_trajectories"][j] > 0
        assert data["cross_check_worst_rise"][j] <= 1e-9 and not data["soundness_violation"][j]
    for j in np.flatnonzero(refuted):
        assert "eigenvalue of modulus > 1" in str(data["note"][j]) and data["unstable_corners"][j] >= 1
    j = int(np.flatnonzero(certified & (data["status_roa"] == CODES["certified"]))[0])
    doc = json.loads(str(data["certificate"][j]))
    assert doc["conditions"]["linearization"]["certificate"]["method"] == "box_ball_stein"
    assert verify(doc).valid
    page = tanh_sweep.parent / "boxes.html"
    assert cli("report", str(tanh_sweep), "--html", str(page)).exit_code == 0
    assert "Cross-check by iterating the map" in page.read_text()


@pytest.mark.slow
def test_the_tanh_map_s_box_sweep_resumes_byte_for_byte(tanh_sweep: Path, tmp_path: Path) -> None:
    from tests.test_model_sweeps import interrupted

    out = tmp_path / "out.zarr"
    interrupted(TANH_SPEC, out, after=2)
    assert 0 < arrays(out)["done"].sum() < arrays(tanh_sweep)["done"].sum()
    assert 0 < run(TANH_SPEC, out).run.computed_now
    whole = {p.relative_to(tanh_sweep): p.read_bytes() for p in tanh_sweep.rglob("*") if p.is_file()}
    parts = {p.relative_to(out): p.read_bytes() for p in out.rglob("*") if p.is_file()}
    assert whole.keys() == parts.keys() and all(whole[k] == parts[k] for k in whole)


@pytest.fixture(scope="module")
def tanh_box_doc(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Any]:
    from lyapcheck.api import certify

    doc = dict(certify(model=EXAMPLES / "discrete-tanh-gain-map.toml", box=["k=0.6..0.95"],
                       classes="linearization,roa").document)
    assert all(doc["conditions"][c]["status"] == "certified" for c in ("linearization", "roa"))
    return doc


@pytest.mark.slow
def test_a_map_with_functions_box_certificates_are_iterated_and_forged_ones_caught(
        tanh_box_doc: dict[str, Any], monkeypatch: pytest.MonkeyPatch) -> None:
    """At the box's corners (the true map read there) the ellipsoid and the one P pass; a level forged 1000 times
    larger, a P forged to the identity (it rises along the Jacobian) and the certificates at k = 1.6 (outside the
    box, unstable) are caught. Without an exact Jacobian the true map is iterated from tiny starts: the same
    verdicts."""
    import lyapcheck.models.classes.discrete_functions as dfn
    import lyapcheck.models.engines.trajectories as trajectories
    from lyapcheck.models.language.modelfile import parse_any_model
    from sweeps.crosscheck import cross_check_box

    monkeypatch.setattr(trajectories, "simulate", never_integrate)

    def at(k: str) -> tuple[Any, dict[str, Fraction]]:
        return parse_any_model(TANH_MAP, "tanh", {"k": k}), {"k": Fraction(k)}

    corners = [at("0.6"), at("0.95")]
    found, skipped = cross_check_box(corners, tanh_box_doc, starts=8, seed=(0, 0))
    assert not found.violation and not skipped and found.points == 2 and found.worst_rise <= 1e-9
    assert found.trajectories == 2 * (8 + 8)  # the ellipsoid's starts, then the Jacobian's directions
    level = copy.deepcopy(tanh_box_doc)
    level["conditions"]["roa"]["certificate"]["level"] = str(Fraction(level["conditions"]["roa"]["certificate"]
                                                                      ["level"]) * 1000)
    found, _ = cross_check_box(corners, level, starts=8, seed=(0, 0))
    assert found.violation and all(v.startswith("roa at k = ") for v in found.violations)
    identity = copy.deepcopy(tanh_box_doc)
    identity["conditions"]["linearization"]["certificate"]["P"] = [["1", "0"], ["0", "1"]]
    found, _ = cross_check_box(corners, identity, starts=8, seed=(0, 0))
    assert [v for v in found.violations if v.startswith("linearization at k = ") and "Jacobian" in v]
    found, _ = cross_check_box([at("1.6")], tanh_box_doc, starts=8, seed=(0, 0))
    assert any(v.startswith("linearization at k = 1.6") for v in found.violations)
    monkeypatch.setattr(dfn, "exact_jacobian", lambda model: "no exact Jacobian (test)")
    found, _ = cross_check_box(corners, tanh_box_doc, starts=8, seed=(0, 0))
    assert not found.violation and found.worst_rise <= 1e-5
    found, _ = cross_check_box(corners, identity, starts=8, seed=(0, 0))
    assert [v for v in found.violations if v.startswith("linearization at k = ") and "true map from starts" in v]
