"""Sweeps cross-check certified ``barrier`` and ``reach_avoid`` points by simulation (issue 41).

Two loops with known answers, each swept at one point (module fixtures, certified once):

* polynomial: ``x1' = x2, x2' = -a x1 - x2`` (a = 1, damped, rate 1/2) from the disk of radius 0.2 at
  ``(1, 0)``: it never comes near ``x1 = -1`` and reaches the disk of radius 0.5 at the origin within about
  2 s;
* with functions: ``x1' = x2, x2' = -k sin(x1) - x1 - x2`` (k = 1) from the disk of radius 0.5 at
  ``(2, 0)``: it overshoots to ``x1 = -0.7`` or so (``tests/test_recast_reach_avoid.py``), crosses
  ``x1 = -0.5``, never ``x1 = -3``.

A certificate the truth contradicts is made by moving the unsafe set into the path of the trajectories
(``x2 <= -0.3``, ``x1 <= -0.5``) or by shrinking the certified time bound, and calling the cross-check directly with
the stored document, as ``tests/test_model_sweeps.py`` does for a region of attraction.
"""

from __future__ import annotations

import json
import math
from fractions import Fraction
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from lyapcheck.tolerances import TRAJECTORY_CHECK_REL_TOL

POLYNOMIAL = """[model]
states = ["x1", "x2"]
[parameters]
a = 1
[dynamics]
x1 = "x2"
x2 = "-a*x1 - x2"
[sets]
initial = ["(x1 - 1)**2 + x2**2 <= 0.04"]
unsafe = [UNSAFE]
goal = ["x1**2 + x2**2 <= 0.25"]
"""
WITH_FUNCTIONS = """[model]
states = ["x1", "x2"]
[parameters]
k = 1
[dynamics]
x1 = "x2"
x2 = "-k*sin(x1) - x1 - x2"
[sets]
initial = ["(x1 - 2)**2 + x2**2 <= 0.25"]
unsafe = [UNSAFE]
goal = ["x1**2 + x2**2 <= 0.1"]
"""
FAR = '"x1 <= -3"'
#: unsafe sets in the trajectories' path before they reach the goal: the polynomial loop's x2 falls to
#: -0.44 to -0.66 before |x| <= 0.5; the other's x1 swings to -0.7 (|x| >= 0.5 there, outside its goal)
CROSSED = {"polynomial": '"x2 <= -0.3"', "with_functions": '"x1 <= -0.5"'}
STARTS = 4


def sweep_one(directory: Path, model: str, parameter: str) -> tuple[dict[str, np.ndarray], Any]:
    """A one-point sweep of ``model`` over ``parameter`` = 1 with the safety classes: its arrays and summary."""
    import zarr

    from lyapcheck.api import sweep

    directory.mkdir(parents=True, exist_ok=True)
    (directory / "m.toml").write_text(model.replace("UNSAFE", FAR))
    spec = directory / "spec.toml"
    spec.write_text(f'[sweep]\nmodel = "m.toml"\nclasses = ["barrier", "reach_avoid"]\n[[sweep.axes]]\n'
                    f'name = "{parameter}"\nvalues = [1]\n[simulation]\nstarts = {STARTS}\n')
    summary = sweep(spec, directory / "out.zarr", workers=0)
    group = zarr.open_group(str(directory / "out.zarr"), mode="r")
    return {name: np.asarray(group[name][...]).ravel()  # type: ignore[index]
            for name in group.array_keys()}, summary


@pytest.fixture(scope="module")
def polynomial(tmp_path_factory: pytest.TempPathFactory) -> tuple[dict[str, np.ndarray], Any]:
    return sweep_one(tmp_path_factory.mktemp("polynomial"), POLYNOMIAL, "a")


@pytest.fixture(scope="module")
def with_functions(tmp_path_factory: pytest.TempPathFactory) -> tuple[dict[str, np.ndarray], Any]:
    return sweep_one(tmp_path_factory.mktemp("functions"), WITH_FUNCTIONS, "k")


def assert_clean(data: dict[str, np.ndarray], summary: Any) -> None:
    from sweeps.schema import STATUS_CODES

    for cls in ("barrier", "reach_avoid"):
        assert data[f"status_{cls}"][0] == STATUS_CODES["certified"], data["note"][0]
    assert not data["soundness_violation"][0], data["violation_detail"][0]
    # every start, once (no disturbance), for both classes: the goal is reached within the horizon
    assert data["cross_check_trajectories"][0] == STARTS
    margin, ratio = float(data["cross_check_unsafe_margin"][0]), float(data["cross_check_reach_ratio"][0])
    assert -1 <= margin < -0.1  # none came near x1 = -3 (or -1)
    assert 0 < ratio < 1  # the goal reached before the certified bound, and not at the start
    cross = summary.to_json()["cross_check"] if hasattr(summary, "to_json") else summary["cross_check"]
    assert cross["worst_unsafe_margin"] == pytest.approx(margin) and cross["worst_reach_ratio"] == pytest.approx(ratio)


def test_a_certified_polynomial_point_cross_checks_clean(polynomial: tuple[dict[str, np.ndarray], Any]) -> None:
    assert_clean(*polynomial)


def test_a_certified_point_with_functions_cross_checks_clean(with_functions: tuple[dict[str, np.ndarray], Any]) -> None:
    assert_clean(*with_functions)


def doctored(data: dict[str, np.ndarray], shrink: float = 1.0) -> dict[str, Any]:
    """The stored certificate document, its reach_avoid's time bound divided by ``shrink``."""
    doc = json.loads(str(data["certificate"][0]))
    doc["conditions"]["reach_avoid"]["reach_time_bound_s"] /= shrink
    return doc


def check_polynomial(unsafe: str, doc: dict[str, Any]) -> Any:
    from lyapcheck.models.language.modelfile import parse_model
    from sweeps.crosscheck import cross_check_point

    model = parse_model(POLYNOMIAL.replace("UNSAFE", unsafe), "m.toml")
    return cross_check_point(model, doc, {"a": Fraction(1)}, starts=STARTS, seed=(0,), worst_case=False)


def recast(unsafe: str) -> Any:
    """The loop with functions, its unsafe set ``unsafe``, read as a loop with functions."""
    from lyapcheck.models.language.modelfile import parse_any_model
    from lyapcheck.models.language.recast import RecastModel

    model = parse_any_model(WITH_FUNCTIONS.replace("UNSAFE", unsafe), "m.toml")
    assert isinstance(model, RecastModel)
    return model


def check_with_functions(unsafe: str, doc: dict[str, Any]) -> Any:
    from sweeps.crosscheck import cross_check_point

    return cross_check_point(recast(unsafe), doc, {"k": Fraction(1)}, starts=STARTS, seed=(0,))


@pytest.mark.parametrize("loop, check", [("polynomial", check_polynomial), ("with_functions", check_with_functions)])
def test_a_safety_certificate_the_truth_contradicts_raises_the_alarm(loop: str, check: Any,
                                                                     request: pytest.FixtureRequest) -> None:
    data, _ = request.getfixturevalue(loop)
    # the stored documents, re-checked on the model they were certified for: clean, as in the sweep
    same = check(FAR, doctored(data))
    assert not same.violation and same.unsafe_margin < 0, same.violations
    # the unsafe set moved into the trajectories' swing: both claims are contradicted by an entry
    moved = check(CROSSED[loop], doctored(data))
    assert moved.unsafe_margin > TRAJECTORY_CHECK_REL_TOL
    assert any(v.startswith("barrier at k = 1" if loop == "with_functions" else "barrier at a = 1")
               and "entered the unsafe set" in v for v in moved.violations), moved.violations
    assert any(v.startswith("reach_avoid") and "entered the unsafe set before the goal" in v
               for v in moved.violations), moved.violations
    # a time bound below the time the trajectories take: reach_avoid is late, the barrier still holds
    late = check(FAR, doctored(data, shrink=1 / same.reach_ratio * 4))
    assert [v.split(" at ")[0] for v in late.violations] == ["reach_avoid"], late.violations
    assert "were not in the goal by the certified time bound" in late.violations[0]
    assert late.reach_ratio > 1 + TRAJECTORY_CHECK_REL_TOL


def test_a_box_s_safety_claims_are_simulated_at_a_point_where_its_v_is_not_the_point_s(
        with_functions: tuple[dict[str, np.ndarray], Any]) -> None:
    """A box certificate whose ``quadratic`` V is a function of the box's parameter is not simulated at a
    point of the box (``box_mismatch``); its barrier and reach_avoid, claims about the model's sets and
    its true loop, are, and a contradicted one raises the alarm there."""
    from sweeps.crosscheck import cross_check_box

    data, _ = with_functions
    doc = doctored(data)
    doc["conditions"]["quadratic"] = {"status": "certified", "certificate": {"variables": ["x1", "x2", "k"]}}

    def check(unsafe: str) -> tuple[Any, list[str]]:
        return cross_check_box([(recast(unsafe), {"k": Fraction(1)})], doc, starts=STARTS, seed=(0,))

    (clean, skipped), (moved, _) = check(FAR), check(CROSSED["with_functions"])
    assert len(skipped) == 1 and "V is a function of k" in skipped[0], skipped
    assert skipped[0].endswith("(barrier and reach_avoid simulated there all the same)"), skipped
    assert clean.points == 1 and clean.trajectories == STARTS and not clean.violation, clean.violations
    assert math.isnan(clean.worst_rise)  # the quadratic certificate was not simulated
    assert sorted(v.split(" at ")[0] for v in moved.violations) == ["barrier", "reach_avoid"], moved.violations


def test_a_claim_over_every_disturbance_is_simulated_at_the_vertices_of_the_disturbance_box() -> None:
    """``x' = -x + d``, ``|d| <= 1``, from ``[0, 0.5]``: with ``d = 0`` or ``-1`` nothing reaches 1.5, and
    ``d = 1`` does not either (it tends to 1); the unsafe set ``x >= 0.9`` is reached with ``d = 1`` only, so a
    claim over every disturbance is contradicted there, a nominal one (``d = 0``) is not."""
    from lyapcheck.models.language.modelfile import parse_model
    from sweeps.crosscheck import cross_check_point

    text = ('[model]\nstates = ["x"]\n[parameters]\na = 1\n[disturbances]\nd = 1\n[dynamics]\nx = "-a*x + d"\n'
            '[sets]\ninitial = ["0 <= x <= 0.5"]\nunsafe = [UNSAFE]\n')

    def check(unsafe: str, disturbances: str) -> Any:
        model = parse_model(text.replace("UNSAFE", unsafe), "m.toml")
        doc = {"conditions": {"barrier": {"status": "certified", "disturbances": disturbances}}}
        return cross_check_point(model, doc, {"a": Fraction(1)}, starts=STARTS, seed=(0,), worst_case=False)

    nominal, every = check('"x >= 0.9"', "zero"), check('"x >= 0.9"', "all")
    assert nominal.trajectories == STARTS and not nominal.violation, nominal.violations
    assert every.trajectories == 3 * STARTS  # d = 0, then the vertices -1 and +1
    assert every.violation and "with d = +1" in every.violations[0], every.violations
    assert not check('"x >= 1.5"', "all").violation


def test_a_goal_not_reached_by_the_horizon_is_simulated_on_to_the_certified_bound() -> None:
    """``x' = -x`` from ``[1, 2]`` never reaches ``x <= -1``: with the bound beyond the falsification's
    horizon (12 s) the trajectories are simulated again to just past it, and are late there; with ``x <= 0.5``
    (reached by ``t = ln 4``) one simulation is enough."""
    from lyapcheck.models.language.modelfile import parse_model
    from sweeps.crosscheck import cross_check_point

    def check(goal: str) -> Any:
        model = parse_model('[model]\nstates = ["x"]\n[parameters]\na = 1\n[dynamics]\nx = "-a*x"\n[sets]\n'
                            f'initial = ["1 <= x <= 2"]\nunsafe = ["x >= 3"]\ngoal = ["{goal}"]\n', "m.toml")
        doc = {"conditions": {"reach_avoid": {"status": "certified", "reach_time_bound_s": 100.0}}}
        return cross_check_point(model, doc, {"a": Fraction(1)}, starts=STARTS, seed=(0,), worst_case=False)

    never, reached = check("x <= -1"), check("x <= 0.5")
    assert never.trajectories == 2 * STARTS and never.reach_ratio > 1 + TRAJECTORY_CHECK_REL_TOL
    assert len(never.violations) == 1, never.violations
    assert "were not in the goal by the certified time bound 100 s" in never.violations[0]
    assert reached.trajectories == STARTS and not reached.violation
    # the last point before the goal: every start takes between ln 2 and ln 4 s (less a step, 12/150 s at most)
    assert (np.log(2) - 0.08) / 100 <= reached.reach_ratio <= np.log(4) / 100


# -- the shared checks, on hand-made margins -------------------------------------------------------------
def test_an_entry_counts_only_beyond_the_tolerance_of_the_size_of_the_set_s_terms() -> None:
    from lyapcheck.models.engines.crosscheck import check_safety, scaled_margin
    from lyapcheck.models.language.modelfile import parse_model

    tol = TRAJECTORY_CHECK_REL_TOL

    def unsafe(bound: str) -> Any:  # {x >= bound} of a one-state loop
        return parse_model(f'[model]\nstates = ["x"]\n[dynamics]\nx = "-x"\n[sets]\ninitial = ["x <= 0"]\n'
                           f'unsafe = ["x >= {bound}"]\n', "m.toml").sets["unsafe"]

    # x - 2 >= 0 at x: (x - 2) / (|x| + s + 2) with the extent s = 1, about 5 near x = 2
    x = np.array([[2 + 0.5 * tol * 5], [2 + 2 * tol * 5], [1.0], [1e6]])
    margins = scaled_margin(unsafe("2"), x, np.array([1.0]))
    assert margins == pytest.approx([0.5 * tol, 2 * tol, -1 / 4, (1e6 - 2) / (1e6 + 3)], rel=1e-4)
    # the same points and set in other units (mm): the same figures
    assert scaled_margin(unsafe("0.002"), x * 1e-3, np.array([1e-3])) == pytest.approx(margins, rel=1e-9)
    graze, enter = margins[[2, 0]], margins[[2, 1]]  # from x = 1 to just inside by half and twice the tolerance
    assert check_safety([graze]).ok and check_safety([graze]).worst_margin == margins[0]
    found = check_safety([graze, enter, enter])
    assert (found.entered, found.first) == (2, 1) and not found.ok
    # a union of pieces: the largest of its pieces
    union = unsafe("2") + unsafe("-1")
    assert scaled_margin(union, np.array([[0.0]]), np.array([1.0]))[0] == pytest.approx(1 / 2)


def test_reach_avoid_reads_the_time_before_the_goal_and_the_unsafe_set_before_it_only() -> None:
    from lyapcheck.models.engines.crosscheck import check_reach_avoid, reach_horizon

    t = np.array([0.0, 1.0, 2.0, 3.0])
    outside = np.array([-1.0, -1.0, -1.0, -1.0])
    goal_at_3 = np.array([-1.0, -0.5, -0.2, 0.1])  # first in the goal at t = 3: reached after t = 2
    ok = check_reach_avoid([(t, outside, goal_at_3)], bound_s=2.0)
    assert ok.ok and ok.reach_ratio == pytest.approx(1.0)
    late = check_reach_avoid([(t, outside, goal_at_3)], bound_s=1.9)
    assert (late.late, late.first_late, late.entered) == (1, 0, 0) and late.reach_ratio == pytest.approx(2 / 1.9)
    # an entry into the unsafe set after the goal does not count, one before it does
    after = check_reach_avoid([(t, np.array([-1.0, -1.0, -1.0, 1.0]), goal_at_3)], bound_s=2.0)
    before = check_reach_avoid([(t, np.array([-1.0, 1.0, -1.0, -1.0]), goal_at_3)], bound_s=2.0)
    assert after.ok and after.worst_margin == pytest.approx(-1.0)
    assert (before.entered, before.first_entered) == (1, 0) and not before.ok
    never = check_reach_avoid([(np.array([0.0, 1.0, 2.0 * (1 + 2e-5)]), outside[:3], outside[:3])], bound_s=2.0)
    assert never.late == 1 and reach_horizon(2.0) > 2.0 * (1 + TRAJECTORY_CHECK_REL_TOL)


@pytest.mark.parametrize("loop", ["polynomial", "with_functions"])
def test_a_barrier_its_certifier_s_own_simulation_contradicted_raises_the_alarm_on_either_loop(
        loop: str, request: pytest.FixtureRequest) -> None:
    """A certified barrier whose falsification beside the proof entered the unsafe set
    (``soundness_violation`` in its document) is a violation of the sweep on either loop kind, though the
    sweep's own trajectories (the unsafe set far away) are clean; without the flag there is none."""
    data, _ = request.getfixturevalue(loop)
    check = check_polynomial if loop == "polynomial" else check_with_functions
    doc = doctored(data)
    doc["conditions"] = {"barrier": {**doc["conditions"]["barrier"], "soundness_violation": True}}
    flagged = check(FAR, doc)
    assert flagged.unsafe_margin < 0
    assert len(flagged.violations) == 1 and flagged.violations[0].startswith("barrier at "), flagged.violations
    assert "its own simulation when certified found a trajectory into the unsafe set" in flagged.violations[0]
    del doc["conditions"]["barrier"]["soundness_violation"]
    assert not check(FAR, doc).violation


def test_the_store_report_shows_the_safety_cross_check(tmp_path: Path) -> None:
    """The HTML report of a safety sweep's store states the two figures the cross-check stores for it:
    the largest margin of the unsafe set reached and the latest time to the goal over its bound."""
    from reports.render import read_store, sweep_html
    from reports.views import fmt_float
    from sweeps.summary import summarize_dataset

    sweep_one(tmp_path / "p", POLYNOMIAL, "a")
    page = sweep_html(tmp_path / "p" / "out.zarr")
    cross = summarize_dataset(read_store(tmp_path / "p" / "out.zarr")).cross_check
    assert "largest margin of the unsafe set reached" in page and fmt_float(cross["worst_unsafe_margin"], 3) in page
    assert "latest time to the goal / certified time bound" in page and fmt_float(cross["worst_reach_ratio"], 3) in page
