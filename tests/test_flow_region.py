"""roa's ball-arithmetic set enlarged by boxes proved, by validated integration, to flow into it
(lyapcheck.models.classes.flow_region): the region grows, every start in a box converges in a simulation
independent of lyapcheck, and verify integrates every box again (a widened box or a changed time fails)."""

from __future__ import annotations

import copy
from fractions import Fraction
from pathlib import Path

import numpy as np
import pytest

from lyapcheck import api
from tests.recast_loops import rk4

ROOT = Path(__file__).resolve().parents[1]
INVERTED = ROOT / "examples" / "models" / "recast-inverted-pendulum-sat.toml"
SAT_PD = ROOT / "examples" / "models" / "robot-pendulum-sat-pd.toml"


def inverted_field(X: np.ndarray) -> np.ndarray:
    """theta'' = sin(theta) - 0.1 theta' + sat(-3 theta - 2 theta', 2), from the model file's comment."""
    return np.stack([X[:, 1], np.sin(X[:, 0]) - 0.1 * X[:, 1] + np.clip(-3 * X[:, 0] - 2 * X[:, 1], -2, 2)], axis=1)


def sat_pd_field(X: np.ndarray) -> np.ndarray:
    """(m g l sin(phi) - b omega + sat(-10 phi - 2 omega, 6)) / (m l^2), m = 1, l = 0.5, b = 0.1, g = 9.81."""
    u = np.clip(-10 * X[:, 0] - 2 * X[:, 1], -6, 6)
    return np.stack([X[:, 1], (4.905 * np.sin(X[:, 0]) - 0.1 * X[:, 1] + u) / 0.25], axis=1)


def box_starts(cert: dict, states: tuple[str, ...], per_box: int = 9) -> np.ndarray:
    """Each flow box's corners and a few random points of it (the equilibrium is the origin here)."""
    rng = np.random.default_rng(0)
    rows = []
    for entry in cert["flow"]["boxes"]:
        lo = np.array([float(Fraction(entry["box"][s][0])) for s in states])
        hi = np.array([float(Fraction(entry["box"][s][1])) for s in states])
        rows += [lo, hi, np.array([lo[0], hi[1]]), np.array([hi[0], lo[1]])]
        rows += list(lo + (hi - lo) * rng.random((per_box - 4, len(states))))
    return np.array(rows)


@pytest.fixture(scope="module")
def inverted() -> api.CertifyResult:
    return api.certify(model=INVERTED, classes="roa")


@pytest.mark.slow
def test_the_inverted_pendulums_region_grows_and_every_box_start_converges(inverted) -> None:
    roa = inverted.conditions["roa"]
    assert roa.status == "certified" and roa.certificate["kind"] == "interval"
    cert = roa.certificate
    assert roa.numbers["flow_boxes"] == len(cert["flow"]["boxes"]) > 0
    # the union covers more of the simulated region than the set alone (88.4 % before this route)
    assert roa.numbers["roa_share"] > 0.95
    assert roa.numbers["flow_box_starts_not_converged"] == 0
    assert "union of the set and the boxes" in roa.summary and "not a sublevel set" in roa.summary
    # outside lyapcheck: every start of every box converges to the equilibrium itself
    X = box_starts(cert, ("theta", "omega"))
    end = rk4(inverted_field, X, 40.0, step=0.01)
    assert np.all(np.hypot(end[:, 0], end[:, 1]) < 1e-3)
    # and some of those starts lie outside the certified sublevel set (the boxes add to it)
    from lyapcheck.models.classes.flow_region import in_boxes

    assert in_boxes(cert, ("theta", "omega"), X).all()
    assert api.verify(inverted).valid


@pytest.mark.slow
@pytest.mark.parametrize("change", ["widened", "earlier", "later", "pieces", "dropped", "step"])
def test_a_forged_flow_does_not_verify(inverted, change: str) -> None:
    doc = copy.deepcopy(inverted.document)
    cert = doc["conditions"]["roa"]["certificate"]
    boxes = cert["flow"]["boxes"]
    # the longest box: the one a forger would most like to stretch
    k = max(range(len(boxes)), key=lambda i: Fraction(boxes[i]["t"]))
    entry = boxes[k]
    if change == "widened":
        lo, hi = (Fraction(x) for x in entry["box"]["omega"])
        entry["box"]["omega"] = [str(lo - (hi - lo)), str(hi)]
    elif change == "earlier":
        entry["t"] = str(Fraction(entry["t"]) - Fraction(cert["flow"]["step"]) * 8)
    elif change == "later":
        entry["t"] = str(Fraction(entry["t"]) + Fraction(cert["flow"]["step"]))
    elif change == "pieces":
        entry["pieces"] = 10 ** 6
    elif change == "dropped":  # the boxes removed, the sentence left claiming them
        del cert["flow"]
    else:
        cert["flow"]["step"] = "1/3"
    assert not api.verify(doc).valid, change


@pytest.mark.slow
def test_the_saturated_pd_pendulums_box_starts_all_converge() -> None:
    result = api.certify(model=SAT_PD, classes="roa")
    roa = result.conditions["roa"]
    assert roa.status == "certified"
    assert roa.numbers["flow_box_starts_not_converged"] == 0
    if "flow" in roa.certificate:
        X = box_starts(roa.certificate, ("phi", "omega"))
        end = rk4(sat_pd_field, X, 30.0, step=0.002)
        assert np.all(np.hypot(end[:, 0], end[:, 1]) < 1e-3)


@pytest.mark.slow
def test_verify_refuses_boxes_needing_more_steps_than_certify_may_spend(inverted, monkeypatch) -> None:
    from lyapcheck.models.classes import flow_region

    steps = inverted.conditions["roa"].numbers["flow_steps"]
    monkeypatch.setattr(flow_region, "FLOW_STEP_BUDGET", steps // 10)
    report = api.verify(inverted.document)
    assert not report.valid
    assert any("more than the" in check.message for check in report.checks if not check.ok)


POLE_WIDE = """[model]
name = "a rational loop with a pole at x1 = 2, over a domain wider than its ball-arithmetic set"
states = ["x1", "x2"]

[dynamics]
x1 = "-x1 + x2"
x2 = "-x1 - x2 + x1**2/(2 - x1)"

[domain]
x1 = [-3, 1.5]
x2 = [-3, 3]
"""


@pytest.mark.slow
def test_a_polynomial_loops_ball_region_gets_boxes_too(tmp_path: Path) -> None:
    """The rational loop no SOS class takes (tests/test_poly_ball_roa.py) gets its region by ball arithmetic,
    and boxes that flow into it, which verify integrates again."""
    path = tmp_path / "pole.toml"
    path.write_text(POLE_WIDE)
    result = api.certify(model=path, classes="roa")
    roa = result.conditions["roa"]
    assert roa.status == "certified" and roa.certificate["kind"] == "interval"
    assert roa.numbers["flow_boxes"] == len(roa.certificate["flow"]["boxes"]) > 0
    assert roa.numbers["flow_box_starts_not_converged"] == 0
    X = box_starts(roa.certificate, ("x1", "x2"))
    end = rk4(lambda Y: np.stack([-Y[:, 0] + Y[:, 1], -Y[:, 0] - Y[:, 1] + Y[:, 0] ** 2 / (2 - Y[:, 0])], axis=1),
              X, 40.0, step=0.01)
    assert np.all(np.hypot(end[:, 0], end[:, 1]) < 1e-3)
    assert api.verify(result).valid


def test_the_guide_simulation_stops_when_the_class_time_is_spent() -> None:
    """The floating-point guide of where to spend the validated steps (``_entry_steps``) reads the class's
    clock: with time left, a box around the equilibrium enters the set within the horizon and a far box's
    step is counted; with none left, it returns at once (nothing entered: None), so that the caller stops
    by the same budget instead of simulating its whole horizon first."""
    from lyapcheck.models.classes import flow_region
    from lyapcheck.models.classes.recast_classes import base_loop
    from lyapcheck.models.engines.search import Budget
    from lyapcheck.models.language.modelfile import load_any_model

    loop = base_loop(load_any_model(INVERTED).system)

    def value(X: np.ndarray) -> np.ndarray:
        return np.sum(X ** 2, axis=1)

    boxes = [((Fraction(-1, 100), Fraction(-1, 100)), (Fraction(1, 100), Fraction(1, 100))),
             ((Fraction(1, 2), Fraction(0)), (Fraction(6, 10), Fraction(1, 10)))]
    h = Fraction(1, 256)
    with_time = flow_region._entry_steps(loop, value, 1e-2, boxes, h, 4096, Budget(60.0, "test"))
    assert with_time[0] == 0 and with_time[1] is not None and with_time[1] > 0
    spent = flow_region._entry_steps(loop, value, 1e-2, boxes, h, 10 ** 9, Budget(0.0, "test"))
    assert spent == [0, None]  # (the horizon of 10^9 steps would take hours)


@pytest.mark.slow
def test_a_box_start_not_in_the_set_at_its_time_is_a_soundness_alarm(inverted) -> None:
    """The simulated check of a flow region follows a box's start that did not converge up to its box's
    stated time: with the true times none is outside the set then; a box claimed to reach the set at once
    from far outside it (a false time) gets every start that did not converge counted and the alarm. (This
    loop's starts all converge: a step budget of 5 stops every first simulation, so every start of a box
    counts as not converged and is followed up to its box's time.)"""
    from lyapcheck.models.classes import recast_regions
    from lyapcheck.models.classes.recast_classes import base_loop
    from lyapcheck.models.language.modelfile import load_any_model
    from lyapcheck.results import ConditionResult

    loop = base_loop(load_any_model(INVERTED).system)
    box = (np.array([-3.0, -3.0]), np.array([3.0, 3.0]))
    cert = copy.deepcopy(inverted.conditions["roa"].certificate)
    # a far box, (2.5, 2.5) to (3, 3), far outside the set: claimed to be in it after one step, t = 1/256
    cert["flow"]["boxes"].append({"box": {"theta": ["5/2", "3"], "omega": ["5/2", "3"]}, "t": "1/256", "pieces": 1})
    forged = ConditionResult("roa", "certified", "forged", certificate=cert, property="ROA")
    recast_regions.simulated_check(loop, forged, box, max_steps=5)
    assert forged.numbers["flow_box_starts_not_converged"] > 0
    # the far box's starts, and only they (the true boxes' starts are in the set at their times)
    grid = np.linspace(-3, 3, recast_regions.SIMULATED_GRID)
    far = int(np.sum((grid >= 2.5) & (grid <= 3))) ** 2
    assert forged.numbers["flow_box_starts_not_in_set_at_their_time"] == far > 0
    assert forged.numbers["soundness_violation"] is True
    honest = ConditionResult("roa", "certified", "honest",
                             certificate=copy.deepcopy(inverted.conditions["roa"].certificate), property="ROA")
    recast_regions.simulated_check(loop, honest, box, max_steps=5)
    assert honest.numbers["flow_box_starts_not_converged"] > 0
    assert "soundness_violation" not in honest.numbers
    assert honest.numbers.get("flow_box_starts_not_in_set_at_their_time", 0) == 0
