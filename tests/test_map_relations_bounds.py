"""``sos_bound`` on a discrete-time map with functions (:mod:`lyapcheck.models.classes.map_relations_bounds`):
the shipped example certified and its bounds checked by iterating the true map under random and bang-bang
disturbances, its step inequality checked on the true map at sampled points, verify, forged certificates
refused, a disturbance inside a function taken, and the cases that are not certified or not taken; then
``barrier`` on such a map (:mod:`lyapcheck.models.classes.map_relations_safety`): certified and checked on
the true map, verify and forgeries, an unsafe map refuted by an iterate proved in ball arithmetic, a barrier
that cannot exist not certified, no sets."""

from __future__ import annotations

import copy
import math
from fractions import Fraction
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from lyapcheck.models.classes import map_relations, map_relations_safety as mrs
from lyapcheck.models.classes import map_relations_bounds as mrb
from lyapcheck.models.engines import reasons
from lyapcheck.models.engines.recast_sos import poly_from_json
from lyapcheck.models.engines.search import Budget
from lyapcheck.models.language.modelfile import load_any_model, parse_any_model
from lyapcheck.models.language.recast import RecastModel

MODELS = Path(__file__).resolve().parent.parent / "examples" / "models"
EXAMPLE = MODELS / "discrete-tanh-disturbed-map.toml"
#: the example's disturbance bound (|d| <= 1/10)
D_MAX = 0.1


def _map(source: str | Path) -> RecastModel:
    model = load_any_model(source) if isinstance(source, Path) else parse_any_model(source)
    assert isinstance(model, RecastModel)
    return model


def _budget() -> Budget:
    return Budget(120.0, "test")


def _true_map(x: float, y: float, d: float) -> tuple[float, float]:
    return y, -0.5 * x + 0.8 * math.tanh(y) + d


@pytest.fixture(scope="module")
def certified() -> tuple[RecastModel, dict[str, Any]]:
    model = _map(EXAMPLE)
    result = mrb.run(model, _budget())
    assert result.status == "certified", result.summary
    return model, result.to_json()


def test_the_bounds_hold_along_iterates_under_random_and_bang_bang_disturbances(
        certified: tuple[RecastModel, dict[str, Any]]) -> None:
    _, data = certified
    bounds = data["bounds"]
    assert set(bounds) == {"x", "y"} and data["disturbances"] == "all"
    rng = np.random.default_rng(7)
    sequences = {"random": lambda k: rng.uniform(-D_MAX, D_MAX), "bang-bang +": lambda k: D_MAX,
                 "bang-bang alternating": lambda k: D_MAX * (-1) ** k,
                 "bang-bang by the sign of y": None}
    worst = {"x": 0.0, "y": 0.0}
    for name, seq in sequences.items():
        for x0, y0 in ((3.0, -4.0), (-20.0, 15.0), (0.0, 0.0)):
            x, y = x0, y0
            for k in range(400):
                d = D_MAX * math.copysign(1.0, y) if seq is None else seq(k)
                x, y = _true_map(x, y, d)
                if k >= 200:  # the limsup: every iterate after the transient
                    worst["x"], worst["y"] = max(worst["x"], abs(x)), max(worst["y"], abs(y))
                    assert abs(x) <= bounds["x"] and abs(y) <= bounds["y"], (name, x0, y0, k, x, y)
    # the bang-bang disturbance drives the map to a fixed point near y = 0.14: the bounds are within a small
    # factor of what the map reaches (a bound far too loose would say little)
    assert worst["y"] > 0.1 and bounds["y"] < 10 * worst["y"]


def test_the_step_inequality_holds_on_the_true_map(certified: tuple[RecastModel, dict[str, Any]]) -> None:
    # V(F(x, d)) <= lam V(x) + 1 - lam at sampled states and disturbances, with the true tanh
    model, data = certified
    m = mrb.disturbed_map(model)
    rng = np.random.default_rng(3)
    for out, c in data["certificate"]["outputs"].items():
        V = poly_from_json(m.ring, c["V"], "V")
        lam = float(Fraction(c["lam"]))

        def v(x: float, y: float) -> float:
            return float(m.ring.evaluate(V, [Fraction(x), Fraction(y)] + [Fraction(0)] * (m.ring.nvars - 2)))

        for x, y, d in zip(rng.uniform(-5, 5, 150), rng.uniform(-5, 5, 150), rng.uniform(-D_MAX, D_MAX, 150)):
            nx, ny = _true_map(x, y, d)
            assert v(nx, ny) <= lam * v(x, y) + 1 - lam + 1e-9 * (1 + abs(v(x, y))), (out, x, y, d)


def test_verify_passes_and_forgeries_fail(certified: tuple[RecastModel, dict[str, Any]]) -> None:
    model, data = certified
    ok, why = mrb.verify(model, data)
    assert ok, why
    out = next(iter(data["certificate"]["outputs"]))
    smaller = copy.deepcopy(data)  # a smaller bound: B and the figure lowered together
    c = smaller["certificate"]["outputs"][out]
    c["B"] = str(Fraction(c["B"]) / 4)
    c["bound"] = str(Fraction(c["bound"]) / 2)
    smaller["bounds"][out] = data["bounds"][out] / 2
    ok, why = mrb.verify(model, smaller)
    assert not ok and "does not hold exactly" in why
    figure = copy.deepcopy(data)  # only the printed figure lowered
    figure["bounds"][out] = data["bounds"][out] / 2
    ok, why = mrb.verify(model, figure)
    assert not ok and "below the certified bound" in why
    rate = copy.deepcopy(data)
    rate["certificate"]["outputs"][out]["lam"] = "1"
    assert not mrb.verify(model, rate)[0]
    nominal = copy.deepcopy(data)
    nominal["disturbances"] = "zero"
    assert not mrb.verify(model, nominal)[0]
    dropped = copy.deepcopy(data)  # the disturbance's multiplier removed: the identity no longer holds
    step = dropped["certificate"]["outputs"][out]["step"]
    assert step["taus"]
    step["taus"] = {}
    assert not mrb.verify(model, dropped)[0]


def test_verify_refuses_a_certificate_of_another_map(certified: tuple[RecastModel, dict[str, Any]]) -> None:
    _, data = certified
    text = EXAMPLE.read_text().replace("d = 0.1", "d = 0.2")
    ok, why = mrb.verify(_map(text), data)
    assert not ok


DISTURBED_ARGUMENT = """
[model]
name = "a disturbance inside the function"
states = ["x", "y"]
time = "discrete"
source = "test"

[disturbances]
d = 0.2

[dynamics]
x = "0.5*y"
y = "-0.3*x + 0.6*tanh(y + d)"

[outputs]
y = "y"
"""


def test_a_disturbance_inside_a_function_is_taken() -> None:
    # tanh(y + d): the auxiliary's relations hold at every true point (y, d), a map has no flow to differentiate
    model = _map(DISTURBED_ARGUMENT)
    result = mrb.run(model, _budget())
    assert result.status == "certified", result.summary
    data = result.to_json()
    assert mrb.verify(model, data)[0]
    bound = data["bounds"]["y"]
    x, y = 2.0, -3.0
    for k in range(300):
        x, y = 0.5 * y, -0.3 * x + 0.6 * math.tanh(y + 0.2 * (-1) ** (k // 3))
        if k >= 100:
            assert abs(y) <= bound


DRIFTING = """
[model]
name = "a map the disturbance drives away"
states = ["x"]
time = "discrete"
source = "test"

[disturbances]
d = 0.5

[dynamics]
x = "x - 0.1*tanh(x) + d"
"""


def test_an_unbounded_map_is_not_certified_with_a_reason() -> None:
    # |d| = 1/2 outruns the restoring 0.1 tanh(x): x drifts to infinity under d = 1/2, no bound exists
    result = mrb.run(_map(DRIFTING), _budget())
    assert result.status == "not_certified"
    assert "no quadratic or quartic storage function" in result.summary and "[disturbances]" in result.summary
    tried = result.numbers["tried"]
    assert any("degree 2" in line for line in tried) and any("degree 4" in line for line in tried)


def test_without_disturbances_and_with_a_square_root_it_is_not_applicable() -> None:
    result = mrb.run(_map(MODELS / "discrete-tanh-map.toml"), _budget())
    assert result.status == "not_applicable" and result.summary == reasons.NO_DISTURBANCES
    text = DISTURBED_ARGUMENT.replace('"0.5*y"', '"0.5*y + 0.1*(sqrt(1 + y**2) - 1)"')
    result = mrb.run(_map(text), _budget())
    assert result.status == "not_applicable" and "sqrt(1 + y**2)" in result.summary


# -- barrier on a map with functions (lyapcheck.models.classes.map_relations_safety) -------------------------

SAFETY = MODELS / "discrete-tanh-safety-map.toml"


@pytest.fixture(scope="module")
def barrier_certified() -> tuple[RecastModel, dict[str, Any]]:
    model = _map(SAFETY)
    result = mrs.run_barrier(model, _budget())
    assert result.status == "certified", result.summary
    return model, result.to_json()


def _b_value(model: RecastModel, data: dict[str, Any], x: float, y: float) -> float:
    m = map_relations.on_relations(model)
    B = poly_from_json(m.ring, data["certificate"]["B"], "B")
    return float(m.ring.evaluate(B, [Fraction(x), Fraction(y)] + [Fraction(0)] * (m.ring.nvars - 2)))


def test_barrier_certified_holds_on_the_true_map(barrier_certified: tuple[RecastModel, dict[str, Any]]) -> None:
    # B <= 0 on sampled initial points, B >= 1 on sampled unsafe points, B(F) <= lam B with the true tanh, and
    # the iterates of initial starts never unsafe
    model, data = barrier_certified
    lam = float(Fraction(data["certificate"]["lambda"]))
    rng = np.random.default_rng(5)
    for r, t in zip(0.1 * np.sqrt(rng.random(60)), rng.uniform(0, 2 * math.pi, 60)):
        x, y = 0.5 + r * math.cos(t), r * math.sin(t)
        assert _b_value(model, data, x, y) <= 1e-9
        for _ in range(60):
            x, y = y, -0.5 * x + 0.8 * math.tanh(y)
            assert x < 1.5
    for x, y in zip(rng.uniform(1.5, 6, 60), rng.uniform(-6, 6, 60)):
        assert _b_value(model, data, x, y) >= 1 - 1e-9
    for x, y in zip(rng.uniform(-4, 4, 100), rng.uniform(-4, 4, 100)):
        b = _b_value(model, data, x, y)
        assert _b_value(model, data, y, -0.5 * x + 0.8 * math.tanh(y)) <= lam * b + 1e-9 * (1 + abs(b))


def test_barrier_verify_passes_and_forgeries_fail(barrier_certified: tuple[RecastModel, dict[str, Any]]) -> None:
    model, data = barrier_certified
    ok, why = mrs.verify_barrier(model, data)
    assert ok, why
    rate = copy.deepcopy(data)
    rate["certificate"]["lambda"] = "1/10"
    rate["lambda"] = 0.1
    ok, why = mrs.verify_barrier(model, rate)
    assert not ok and "does not hold exactly" in why
    shifted = copy.deepcopy(data)  # B's constant moved: B <= 0 on the initial set no longer follows
    constant = next(t for t in shifted["certificate"]["B"]["terms"] if not any(t[1]))
    constant[0] = str(Fraction(constant[0]) + 1)
    assert not mrs.verify_barrier(model, shifted)[0]
    other = _map(SAFETY.read_text().replace('unsafe = ["1.5 <= x"]', 'unsafe = ["0.55 <= x"]'))
    assert not mrs.verify_barrier(other, data)[0]


def test_an_unsafe_map_is_refuted_by_an_iterate_proved_in_balls() -> None:
    # from (0.5, 0): x2 = y1 = -1/4 + 0.8 tanh(y0) < -0.2, an unsafe iterate of the true map, proved in ball
    # arithmetic through tanh; verify re-derives it, and a forged step count fails
    text = SAFETY.read_text().replace('unsafe = ["1.5 <= x"]', 'unsafe = ["x <= -0.2"]')
    model = _map(text)
    result = mrs.run_barrier(model, _budget())
    assert result.status == "refuted", result.summary
    data = result.to_json()
    steps = data["refutation"]["steps"]
    x, y = (float(Fraction(data["refutation"]["start"][s])) for s in ("x", "y"))
    assert (x - 0.5) ** 2 + y ** 2 <= 0.01
    for _ in range(steps):
        x, y = y, -0.5 * x + 0.8 * math.tanh(y)
    assert x <= -0.2
    ok, why = mrs.verify_barrier(model, data)
    assert ok and "ball arithmetic through the functions" in why
    forged = copy.deepcopy(data)
    forged["refutation"]["steps"] = steps + 1
    forged["steps_to_unsafe"] = steps + 1
    assert not mrs.verify_barrier(model, forged)[0]
    moved = copy.deepcopy(data)
    moved["refutation"]["start"]["x"] = "0.3"  # outside the initial disc
    ok, why = mrs.verify_barrier(model, moved)
    assert not ok and "initial set" in why


def test_a_barrier_that_cannot_exist_is_not_certified_with_a_reason() -> None:
    # the initial disc touches the unsafe half-plane at (0.6, 0): no B is <= 0 and >= 1 there, and no iterate
    # of the map (x1 = y0, |y0| <= 0.1, then |x| stays small) is unsafe: not_certified, naming the degrees
    text = SAFETY.read_text().replace('unsafe = ["1.5 <= x"]', 'unsafe = ["0.6 <= x"]')
    result = mrs.run_barrier(_map(text), _budget())
    assert result.status == "not_certified"
    assert "barrier" in result.summary and any("degree 4" in line for line in result.numbers["tried"])


def test_barrier_without_sets_is_not_applicable() -> None:
    result = mrs.run_barrier(_map(EXAMPLE), _budget())
    assert result.status == "not_applicable" and "[sets]" in result.summary
