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
