"""``barrier`` and ``reach_avoid`` of a discrete-time map with functions over a ``--box`` (issue 44 / 41): one B
(one V) of the states for every value of the box, the box's parameters bounded variables of the recasting's
relations, every identity checked exactly; ``refuted`` at a corner or the centre of the box by an unsafe iterate
proved in ball arithmetic at that exact value; ``verify`` re-checks each, and forged documents fail.

The map is examples/models/discrete-tanh-safety-map.toml (``x+ = y``, ``y+ = -x/2 + k tanh(y)``) with the
reach-avoid example's goal."""

from __future__ import annotations

import copy
import math
from fractions import Fraction
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from tests.conftest import ROOT

EXAMPLE = ROOT / "examples" / "models" / "discrete-tanh-safety-map.toml"
#: the example (its tanh gain the parameter k) with a goal disc around the fixed point
GAINED = EXAMPLE.read_text() + 'goal = ["x**2 + y**2 <= 0.04"]\n'
assert 'y = "-0.5*x + k*tanh(y)"' in GAINED
#: the unsafe set moved into the iterates' way (x about -0.27 at step 2 from near (0.5, 0))
UNSAFE = GAINED.replace('unsafe = ["1.5 <= x"]', 'unsafe = ["x <= -0.2"]')
BOX = "k=0.6..0.85"


def _model(tmp: Path, text: str, name: str = "m.toml") -> Path:
    path = tmp / name
    path.write_text(text)
    return path


def _certify(path: Path, box: str = BOX, classes: str = "barrier,reach_avoid") -> dict[str, Any]:
    from lyapcheck.api import certify

    return dict(certify(model=path, box=[box], classes=classes).document)


def _verify(doc: dict[str, Any]) -> Any:
    from lyapcheck.api import verify

    return verify(doc)


@pytest.fixture(scope="module")
def safe_doc(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Any]:
    return _certify(_model(tmp_path_factory.mktemp("safe"), GAINED))


@pytest.fixture(scope="module")
def unsafe_doc(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Any]:
    return _certify(_model(tmp_path_factory.mktemp("unsafe"), UNSAFE))


def _true_map(x: float, y: float, k: float) -> tuple[float, float]:
    return y, -0.5 * x + k * math.tanh(y)


def test_both_are_certified_for_every_gain_and_verified(safe_doc: dict[str, Any]) -> None:
    """One B and one V of the states (no k in them), the box stated, the sentence naming the box; verify passes;
    iterating the true map from the initial disc at the box's corners and random gains: B <= 0 at every iterate
    and no iterate unsafe; the goal reached within the certified steps."""
    conds = safe_doc["conditions"]
    for name in ("barrier", "reach_avoid"):
        c = conds[name]
        assert c["status"] == "certified", c
        assert c["certificate"]["parameter_box"] == {"k": ["3/5", "17/20"]}
        assert c["summary"].startswith("for every k in [0.6, 0.85]: ")
        variables = c["certificate"]["variables"]
        assert "k" in variables  # (a bounded variable of the relations)
    assert _verify(safe_doc).valid
    B = _poly(conds["barrier"]["certificate"]["B"], conds["barrier"]["certificate"]["variables"])
    bound = conds["reach_avoid"]["reach_steps_bound"]
    rng = np.random.default_rng(3)
    for k in [0.6, 0.85, *rng.uniform(0.6, 0.85, 3)]:
        for _ in range(40):
            r, a = 0.1 * math.sqrt(rng.uniform()), rng.uniform(0, 2 * math.pi)
            x, y = 0.5 + r * math.cos(a), r * math.sin(a)
            reached = None
            for step in range(max(60, bound + 1)):
                assert B(x, y) <= 1e-9 and x < 1.5
                if reached is None and x * x + y * y <= 0.04:
                    reached = step
                x, y = _true_map(x, y, k)
            assert reached is not None and reached <= bound


def _poly(stated: Any, variables: list[str]) -> Any:
    """B of the certificate (``{"terms": [[coefficient, exponents], ...]}`` over its variables; the fixed point
    is the origin, so the deviations are the states) as a function of the states."""
    assert all(not any(e[2:]) for _, e in stated["terms"])  # (of the states alone: no k, no tanh)

    def value(x: float, y: float) -> float:
        return sum(float(Fraction(c)) * x ** e[0] * y ** e[1] for c, e in stated["terms"])
    return value


def _failing(doc: dict[str, Any]) -> set[str]:
    """The checks of verify that fail on ``doc``."""
    return {c["check"] for c in _verify(doc).to_dict()["checks"] if not c["ok"]}


def test_forged_certificates_fail_verify(safe_doc: dict[str, Any]) -> None:
    """A certificate stating a wider box than the document's; the document's box widened about its centre (the
    model still read there: the identities with h^2 - u^2 of the wider box do not hold); a B coefficient changed;
    V's eps doubled: each fails, on that class's own check."""
    for name in ("barrier", "reach_avoid"):
        wider = copy.deepcopy(safe_doc)
        wider["conditions"][name]["certificate"]["parameter_box"] = {"k": ["3/5", "19/20"]}
        assert name in _failing(wider)
    widened = copy.deepcopy(safe_doc)
    widened["box"] = {"k": ["1/2", "19/20"]}  # (centre 29/40, as the box's)
    for name in ("barrier", "reach_avoid"):
        widened["conditions"][name]["certificate"]["parameter_box"] = {"k": ["1/2", "19/20"]}
    assert {"barrier", "reach_avoid"} <= _failing(widened) and "box" not in _failing(widened)
    forged = copy.deepcopy(safe_doc)
    first = forged["conditions"]["barrier"]["certificate"]["B"]["terms"][0]
    first[0] = str(Fraction(first[0]) + 1)
    assert "barrier" in _failing(forged)
    eps = copy.deepcopy(safe_doc)
    cert = eps["conditions"]["reach_avoid"]["certificate"]
    cert["eps"] = str(2 * Fraction(cert["eps"]))
    assert "reach_avoid" in _failing(eps)


def test_refuted_at_a_value_of_the_box_and_verified(unsafe_doc: dict[str, Any]) -> None:
    """The unsafe set in the iterates' way: both refuted at a corner, the value and the start stated, the
    iterate proved unsafe in ball arithmetic there; verify re-derives it; the value moved outside the box, or the
    start moved off the initial set, fails."""
    for name in ("barrier", "reach_avoid"):
        c = unsafe_doc["conditions"][name]
        assert c["status"] == "refuted", c
        ref = c["refutation"]
        point = Fraction(ref["point"]["k"])
        assert Fraction(3, 5) <= point <= Fraction(17, 20) and ref["parameter_box"] == {"k": ["3/5", "17/20"]}
        assert c["summary"].startswith("at k = ")
        # the stated start's iterate of the true map at that gain is unsafe (floating point agrees)
        x, y = (float(Fraction(ref["start"][s])) for s in ("x", "y"))
        for _ in range(ref["steps"]):
            x, y = _true_map(x, y, float(point))
        assert x <= -0.2
    assert _verify(unsafe_doc).valid
    for name in ("barrier", "reach_avoid"):
        outside = copy.deepcopy(unsafe_doc)
        outside["conditions"][name]["refutation"]["point"] = {"k": "0.95"}
        assert name in _failing(outside)
        moved = copy.deepcopy(unsafe_doc)
        moved["conditions"][name]["refutation"]["start"] = {"x": "2", "y": "0"}
        assert name in _failing(moved)


def test_sets_naming_a_box_parameter_are_refused(tmp_path: Path) -> None:
    """The sets are read at the box's centre: a set naming k over a box of k is not_applicable, as on a
    polynomial map."""
    doc = _certify(_model(tmp_path, GAINED.replace('unsafe = ["1.5 <= x"]', 'unsafe = ["1.5*k <= x"]')))
    for name in ("barrier", "reach_avoid"):
        c = doc["conditions"][name]
        assert c["status"] == "not_applicable" and "parameter of the box" in c["summary"], c


@pytest.mark.slow
def test_a_box_sweep_takes_both_and_iterates_them(tmp_path: Path) -> None:
    """A box sweep of the gain: barrier and reach_avoid certified over each box, each box cross-checked by
    iterating the true map from the initial set at its corners and random gains, without an alarm."""
    from tests.test_model_sweeps import arrays, run

    _model(tmp_path, GAINED)
    spec = tmp_path / "boxes.toml"
    spec.write_text('[sweep]\nmodel = "m.toml"\nmode = "boxes"\nclasses = ["barrier", "reach_avoid"]\n'
                    '[[sweep.axes]]\nname = "k"\nstart = 0.6\nstop = 0.9\nnum = 3\n[sweep.boxes]\nmax_boxes = 2\n'
                    'cross_check_points = 2\n')
    run(spec, tmp_path / "boxes.zarr")
    data = arrays(tmp_path / "boxes.zarr")
    done = np.asarray(data["done"], dtype=bool)
    assert done.sum() == 2
    from tests.test_discrete_sweeps import CODES

    for name in ("barrier", "reach_avoid"):
        assert np.all(np.asarray(data[f"status_{name}"])[done] == CODES["certified"])
    assert not np.asarray(data["soundness_violation"])[done].any()
    assert np.all(np.asarray(data["cross_check_trajectories"])[done] > 0)


def test_a_disturbed_map_s_claims_over_a_box_say_d_0_and_verify(tmp_path: Path) -> None:
    """With a disturbance (read at 0 by these classes) the sentence carries the box's words, then ``(d = 0)``;
    verify takes both off before it compares the barrier's sentence."""
    text = GAINED.replace('"-0.5*x + k*tanh(y)"', '"-0.5*x + k*tanh(y) + d"').replace(
        "\n[dynamics]\n", "\n[disturbances]\nd = 0.05\n\n[dynamics]\n")
    doc = _certify(_model(tmp_path, text))
    for name in ("barrier", "reach_avoid"):
        c = doc["conditions"][name]
        assert c["status"] == "certified" and c["summary"].startswith("for every k in [0.6, 0.85]: (d = 0) "), c
    assert _verify(doc).valid
