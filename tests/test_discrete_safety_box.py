"""``barrier`` and ``reach_avoid`` of a polynomial discrete-time map over a ``--box`` (issue 44):
:mod:`lyapcheck.models.classes.discrete_safety` with the box's multipliers and
:mod:`lyapcheck.models.classes.discrete_safety_box`.

What is asserted, on ``examples/models/discrete-rotation-map.toml`` (a rotation scaled by ``g sqrt(2)``): over
``g in [0.5, 0.65]`` both classes are certified for every value of the box (the sentence says so, the
certificate states the box, ``B`` and ``V`` are of the states alone and the step identities carry box
multipliers), ``verify`` re-checks them, and the map iterated in floating point at the box's corners and at
random values of it (independent of the class's code) keeps ``B <= 0`` and reaches the goal within the certified
number of steps with no unsafe iterate before; a widened box, a changed ``B`` coefficient, a changed
``parameter_box`` or dropped multipliers fail ``verify``. Over ``g in [0.6, 0.8]`` both are refuted at the corner
``g = 0.8`` (the value stated), ``verify`` re-derives the iterate there, and a changed start, a value outside
the box or a value of the box where the iterate is not unsafe fail it. Sets naming a parameter of the box stay
``not_applicable``.

A map with functions' ``reach_avoid`` (:mod:`lyapcheck.models.classes.map_relations_reach`): on
``examples/models/discrete-tanh-reach-unsafe-map.toml`` it is refuted by a start whose first iterate of the true
map (numpy's tanh here, independent of the class's code) is unsafe and which is outside the goal; ``verify``
re-derives it, and a changed start or step count fails; an iterate not proved outside the goal does not count.
"""

from __future__ import annotations

import copy
import json
from fractions import Fraction
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from click.testing import CliRunner

from lyapcheck.cli import app

app._register_commands()

ROTATION = Path(__file__).resolve().parents[1] / "examples" / "models" / "discrete-rotation-map.toml"
CLASSES = "barrier,reach_avoid"


def cli(*args: str) -> Any:
    done = CliRunner().invoke(app.cli, list(args))
    assert done.exception is None or isinstance(done.exception, SystemExit), done.output
    assert "Traceback" not in done.output
    return done


def certify(folder: Path, box: str, name: str, model: Path = ROTATION) -> tuple[Path, dict[str, Any], int]:
    out = folder / name
    done = cli("certify", str(model), "--classes", CLASSES, "--box", box, "--no-store", "--json", "--out", str(out))
    return out, json.loads(out.read_text()), done.exit_code


def verify_code(folder: Path, doc: dict[str, Any], name: str) -> int:
    path = folder / name
    path.write_text(json.dumps(doc))
    return int(cli("verify", str(path)).exit_code)


@pytest.fixture(scope="module")
def safe_box(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, dict[str, Any], int]:
    return certify(tmp_path_factory.mktemp("safe_box"), "g=0.5..0.65", "safe.json")


@pytest.fixture(scope="module")
def unsafe_box(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, dict[str, Any], int]:
    return certify(tmp_path_factory.mktemp("unsafe_box"), "g=0.6..0.8", "unsafe.json")


def _value(terms: dict[str, Any], points: np.ndarray) -> np.ndarray:
    """A stated polynomial (exact terms, exponents over the states then the box's coordinate) at points of the
    states, in floating point; its exponent of the box's coordinate must be 0 (asserted by the caller)."""
    total = np.zeros(len(points))
    for c, exponents in terms["terms"]:
        total += float(Fraction(c)) * np.prod(points ** np.array(exponents[:2]), axis=1)
    return total


def _starts(count: int, seed: int) -> np.ndarray:
    """Starts in the initial disc (x - 1)^2 + y^2 <= 0.04 (its boundary included)."""
    rng = np.random.default_rng(seed)
    r = 0.2 * np.sqrt(rng.random(count))
    t = 2 * np.pi * rng.random(count)
    return np.stack([1 + r * np.cos(t), r * np.sin(t)], axis=1)


def _step(x: np.ndarray, g: float) -> np.ndarray:
    return np.stack([g * (x[:, 0] - x[:, 1]), g * (x[:, 0] + x[:, 1])], axis=1)


def _values_of_box(lo: float, hi: float) -> list[float]:
    return [lo, hi, *np.random.default_rng(7).uniform(lo, hi, 6)]


def test_both_classes_are_certified_for_every_value_of_the_box(safe_box: tuple[Path, dict[str, Any], int]) -> None:
    path, doc, code = safe_box
    assert code == 0
    for name in ("barrier", "reach_avoid"):
        c = doc["conditions"][name]
        assert c["status"] == "certified", c["summary"]
        assert c["summary"].startswith("for every g in [0.5, 0.65]: ")
        cert = c["certificate"]
        assert cert["parameter_box"] == {"g": ["1/2", "13/20"]} == doc["box"]
        poly = cert["B"] if name == "barrier" else cert["V"]
        assert all(exponents[2] == 0 for _, exponents in poly["terms"])  # of the states alone
    assert doc["conditions"]["barrier"]["certificate"]["box_multipliers"]
    assert all(g["box_multipliers"] for g in doc["conditions"]["reach_avoid"]["certificate"]["goal"])
    assert cli("verify", str(path)).exit_code == 0


def test_the_certified_b_and_steps_bound_hold_along_iterates_across_the_box(
        safe_box: tuple[Path, dict[str, Any], int]) -> None:
    _, doc, _ = safe_box
    B = doc["conditions"]["barrier"]["certificate"]["B"]
    bound = doc["conditions"]["reach_avoid"]["reach_steps_bound"]
    assert isinstance(bound, int) and bound > 0
    for g in _values_of_box(0.5, 0.65):
        x = _starts(300, 1)
        reached = np.zeros(len(x), dtype=bool)
        for k in range(bound + 1):
            assert np.all(_value(B, x) <= 1e-9), f"B > 0 at iterate {k}, g = {g}"
            assert not np.any(~reached & ((x[:, 0] + 1) ** 2 + (x[:, 1] - 1) ** 2 <= 0.04))
            reached |= x[:, 0] ** 2 + x[:, 1] ** 2 <= 0.01
            if reached.all():
                break
            x = _step(x, g)
        assert reached.all(), f"not every start reached the goal within {bound} steps at g = {g}"


@pytest.mark.parametrize("forge", ["widened box", "B coefficient", "parameter_box", "no multipliers",
                                   "V coefficient"])
def test_a_forged_certificate_over_the_box_fails_verify(safe_box: tuple[Path, dict[str, Any], int],
                                                        tmp_path: Path, forge: str) -> None:
    _, doc, _ = safe_box
    forged = copy.deepcopy(doc)
    barrier = forged["conditions"]["barrier"]["certificate"]
    reach = forged["conditions"]["reach_avoid"]["certificate"]
    if forge == "widened box":  # the document's box (and every statement of it) widened to g in [0.5, 0.7]
        forged["box"] = {"g": ["1/2", "7/10"]}
        barrier["parameter_box"] = reach["parameter_box"] = forged["box"]
    elif forge == "B coefficient":
        c, exponents = barrier["B"]["terms"][0]
        barrier["B"]["terms"][0] = [str(Fraction(c) + Fraction(1, 1000)), exponents]
    elif forge == "V coefficient":
        c, exponents = reach["V"]["terms"][-1]
        reach["V"]["terms"][-1] = [str(Fraction(c) * Fraction(101, 100)), exponents]
    elif forge == "parameter_box":
        barrier["parameter_box"] = {"g": ["1/2", "7/10"]}
    else:
        del barrier["box_multipliers"]
    assert verify_code(tmp_path, forged, "forged.json") == 1


def test_a_box_reaching_an_unsafe_value_is_refuted_at_it(unsafe_box: tuple[Path, dict[str, Any], int]) -> None:
    path, doc, code = unsafe_box
    assert code == 1
    for name in ("barrier", "reach_avoid"):
        c = doc["conditions"][name]
        assert c["status"] == "refuted", c["summary"]
        assert c["refutation"]["point"] == {"g": "4/5"}
        assert c["refutation"]["parameter_box"] == {"g": ["3/5", "4/5"]}
        assert c["summary"].startswith("at g = 0.8, a value of the box")
        # the stated start, iterated at g = 0.8 in floating point, is unsafe at the stated step
        x = np.array([[float(Fraction(c["refutation"]["start"][s])) for s in ("x", "y")]])
        assert (x[0, 0] - 1) ** 2 + x[0, 1] ** 2 <= 0.04
        for _ in range(c["refutation"]["steps"]):
            x = _step(x, 0.8)
        assert (x[0, 0] + 1) ** 2 + (x[0, 1] - 1) ** 2 <= 0.04
    assert cli("verify", str(path)).exit_code == 0


@pytest.mark.parametrize("forge", ["start", "outside", "inside", "box", "sentence"])
def test_a_forged_refutation_over_the_box_fails_verify(unsafe_box: tuple[Path, dict[str, Any], int],
                                                       tmp_path: Path, forge: str) -> None:
    _, doc, _ = unsafe_box
    forged = copy.deepcopy(doc)
    data = forged["conditions"]["barrier"]["refutation"]
    if forge == "start":
        data["start"]["x"] = "1.19"  # still in the initial disc, three steps away from the unsafe one no more
        data["start"]["y"] = "0"
    elif forge == "outside":
        data["point"] = {"g": "9/10"}
    elif forge == "inside":
        data["point"] = {"g": "3/5"}  # a value of the box where that iterate is not unsafe
    elif forge == "sentence":
        forged["conditions"]["barrier"]["summary"] = forged["conditions"]["barrier"]["summary"].replace("g = 0.8",
                                                                                                      "g = 0.7")
    else:
        data["parameter_box"] = {"g": ["3/5", "9/10"]}
    assert verify_code(tmp_path, forged, "forged.json") == 1


def test_sets_naming_a_parameter_of_the_box_stay_not_applicable(tmp_path: Path) -> None:
    text = ROTATION.read_text().replace('unsafe = ["(x + 1)**2 + (y - 1)**2 <= 0.04"]',
                                        'unsafe = ["(x + 1)**2 + (y - 1)**2 <= g/15"]')
    assert "g/15" in text
    model = tmp_path / "sets-with-g.toml"
    model.write_text(text)
    _, doc, _ = certify(tmp_path, "g=0.5..0.65", "out.json", model)
    for name in ("barrier", "reach_avoid"):
        c = doc["conditions"][name]
        assert c["status"] == "not_applicable"
        assert "may not depend on a parameter of the box" in c["summary"]


TANH_UNSAFE = ROTATION.parent / "discrete-tanh-reach-unsafe-map.toml"


@pytest.fixture(scope="module")
def tanh_unsafe(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, dict[str, Any], int]:
    out = tmp_path_factory.mktemp("tanh_unsafe") / "out.json"
    done = cli("certify", str(TANH_UNSAFE), "--classes", "reach_avoid", "--no-store", "--json", "--out", str(out))
    return out, json.loads(out.read_text()), done.exit_code


def test_a_map_with_functions_reach_avoid_is_refuted_by_an_unsafe_iterate_before_the_goal(
        tanh_unsafe: tuple[Path, dict[str, Any], int]) -> None:
    path, doc, code = tanh_unsafe
    c = doc["conditions"]["reach_avoid"]
    assert code == 1 and c["status"] == "refuted", c["summary"]
    assert "before any iterate is in the goal" in c["summary"]
    data = c["refutation"]
    x = np.array([float(Fraction(data["start"][s])) for s in ("x", "y")])
    assert (x[0] - 0.5) ** 2 + x[1] ** 2 <= 0.01
    for _ in range(data["steps"]):
        assert x[0] ** 2 + x[1] ** 2 > 0.04  # outside the goal before the unsafe iterate
        x = np.array([x[1], -0.5 * x[0] + 0.8 * np.tanh(x[1])])
    assert x[1] <= -0.2
    assert cli("verify", str(path)).exit_code == 0


@pytest.mark.parametrize("forge", ["start", "steps", "outside the initial set"])
def test_a_forged_refutation_of_a_map_with_functions_fails_verify(tanh_unsafe: tuple[Path, dict[str, Any], int],
                                                                  tmp_path: Path, forge: str) -> None:
    _, doc, _ = tanh_unsafe
    forged = copy.deepcopy(doc)
    data = forged["conditions"]["reach_avoid"]["refutation"]
    if forge == "start":
        data["start"] = {"x": "0.5", "y": "0.09"}  # in the initial disc; its first iterate has y > -0.2
    elif forge == "steps":
        data["steps"] = data["steps"] + 1
        forged["conditions"]["reach_avoid"]["steps_to_unsafe"] = data["steps"]
    else:
        data["start"] = {"x": "0.3", "y": "-0.1"}
    assert verify_code(tmp_path, forged, "forged.json") == 1


def test_an_iterate_not_proved_outside_the_goal_does_not_refute() -> None:
    from lyapcheck.models.classes import map_relations_safety as mrs
    from lyapcheck.models.classes.map_relations import on_relations
    from lyapcheck.models.language.modelfile import load_any_model

    model = load_any_model(str(TANH_UNSAFE))
    m = on_relations(model)
    sets = mrs.map_sets(model, m, ("initial", "unsafe", "goal"))
    start = [Fraction(1, 2), Fraction(0)]
    assert mrs.check_iterate_functions(model, m, sets["initial"], sets["unsafe"], start, 1, sets["goal"][0])[0]
    # a goal holding the start: the same unsafe iterate no longer comes before the goal
    wide_goal = [sets["goal"][0][0] + m.ring.constant(1)]
    ok, why = mrs.check_iterate_functions(model, m, sets["initial"], sets["unsafe"], start, 1, wide_goal)
    assert not ok and "outside the goal" in why


@pytest.mark.slow
def test_a_box_sweep_certifies_the_safe_boxes_and_iterates_them_at_their_corners(tmp_path: Path) -> None:
    """examples/models/sweeps/boxes-discrete-safety.toml: every box with g <= 0.7 is certified by both classes
    (verify re-checks its document), iterated at its two corners and two random values with no alarm; every
    box it refutes reaches g >= 0.725 (a corner where an iterate is proved unsafe)."""
    from lyapcheck.api import verify
    from tests.test_model_sweeps import arrays, run

    run(ROTATION.parent / "sweeps" / "boxes-discrete-safety.toml", tmp_path / "boxes.zarr")
    data = arrays(tmp_path / "boxes.zarr")
    done = data["done"].astype(bool)
    certified = done & (data["status_barrier"] == 1) & (data["status_reach_avoid"] == 1)
    assert certified.any() and np.all(data["hi_g"][certified] <= 0.7 + 1e-12)
    for j in np.flatnonzero(certified):
        doc = json.loads(str(data["certificate"][j]))
        assert verify(doc).valid
        assert data["cross_check_points"][j] == 2 + 2 and data["cross_check_trajectories"][j] > 0
        assert not data["soundness_violation"][j]
        assert data["reach_avoid_reach_steps_bound"][j] >= 1
    refuted = done & (data["status_barrier"] == 2)
    assert refuted.any() and np.all(data["hi_g"][refuted] >= 0.725 - 1e-12)
