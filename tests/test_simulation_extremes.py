"""Issue 14: extreme but valid values end in a result or a named failure, quickly, never a crash.

The simulator at scales where double precision cannot follow the loop (a trial state that
overflows, a loop too fast for the resolution of ``t``, a stiff loop whose explicit step is
bounded by stability), and the python-control linear views beyond the double range.
"""

from __future__ import annotations

import inspect
import re
import time
from pathlib import Path

import numpy as np
import pytest

from lyapcheck.errors import InvalidParameter
from lyapcheck.integrator import (
    STATUS_MAX_ITERATIONS, STATUS_OK, IntegrationResult, integrate,
)
from lyapcheck.paper.simulation.runner import STEPS_PER_TAIL
from lyapcheck.tolerances import SIM_MAX_STEPS
from tests.conftest import DecaySystem

ROOT = Path(__file__).resolve().parents[1]

#: numpy's overflow warnings from the loop's formulas at 1e300 (the integrator rejects such steps)
FP_WARNINGS = pytest.mark.filterwarnings(
    "ignore:overflow encountered:RuntimeWarning", "ignore:invalid value encountered:RuntimeWarning",
    "ignore:divide by zero encountered:RuntimeWarning", "ignore:underflow encountered:RuntimeWarning")


def _scenario(tmp_path: Path, key: str, value: str) -> Path:
    """The paper's ILOS scenario over 1 s with one value replaced."""
    text = ((ROOT / "examples" / "scenario-paper-ilos.toml").read_text()
            .replace('horizon = "100 s"', 'horizon = "1 s"').replace('tail = "10 s"', 'tail = "0.5 s"'))
    text, n = re.subn(rf"(?m)^{key} = .*$", f"{key} = {value}", text)
    assert n == 1, key
    path = tmp_path / "scenario.toml"
    path.write_text(text)
    return path


# -- the integrator ------------------------------------------------------------------------------
def test_the_step_budget_is_the_named_limit() -> None:
    assert inspect.signature(integrate).parameters["max_iterations"].default == SIM_MAX_STEPS


def test_stiff_rows_stop_at_the_step_budget_and_the_others_finish() -> None:
    """A stiff row (rate 1e6/s over 1 s: ~3e5 explicit steps) stops at the budget (small here,
    to keep the test fast; SIM_MAX_STEPS by default), a mild one in the same batch finishes."""
    res = integrate(DecaySystem(np.array([1.0, 1e6])), 0.0, np.ones((2, 1)), 1.0, atol=1e-12, max_iterations=2000)
    assert res.status.tolist() == [STATUS_OK, STATUS_MAX_ITERATIONS]
    assert res.n_iterations == 2001 and res.max_iterations == 2000
    assert res.y[0, 0] == pytest.approx(np.exp(-1.0), rel=1e-6)
    assert res.failure(0, 1.0) is None
    message = res.failure(1, 1.0)
    assert message is not None
    assert message.startswith("step budget exhausted: 2000 steps (lyapcheck.tolerances.SIM_MAX_STEPS) at t = ")
    assert message.endswith("stiff at this scale")


@FP_WARNINGS
@pytest.mark.parametrize("lam", [1e300, 1e308])
def test_overflowing_first_step_fails_at_once(lam: float) -> None:
    """Before issue 14 the starting-step heuristic gave 0 (or NaN) when its scaled norms
    overflowed, and zero steps were accepted without advancing t until the iteration limit."""
    res = integrate(DecaySystem(np.array([lam])), 0.0, np.ones((1, 1)), 1.0, atol=1e-9)
    assert res.status[0] != STATUS_OK and res.n_iterations < 10
    assert res.failure(0, 1.0) is not None


def test_a_failure_message_names_each_status() -> None:
    def result(status: int) -> IntegrationResult:
        return IntegrationResult(t=np.array([0.25]), y=np.zeros((1, 1)), status=np.array([status], dtype=np.int8),
                                 n_accepted=np.zeros(1, dtype=np.int64), n_rejected=np.zeros(1, dtype=np.int64),
                                 monitor_max=np.zeros(1), n_iterations=1, n_rhs_rows=1, max_iterations=77)

    assert "not finite" in (result(1).failure(0, 2.0) or "")
    assert "step size below" in (result(2).failure(0, 2.0) or "")
    assert "step budget exhausted: 77 steps" in (result(3).failure(0, 2.0) or "")
    assert "t = 0.25 s of 2 s" in (result(3).failure(0, 2.0) or "")


# -- the closed loop, through the scenario path of ``lyapcheck simulate`` -------------------------
@FP_WARNINGS
@pytest.mark.parametrize(("key", "value", "why"), [
    ("k_d", "1e300", "state or derivative not finite"),
    ("e11", '"1e300 m"', "step size below 16 ulps of t"),
    ("los_speed", '"1e300 m/s"', "step size below 16 ulps of t"),
])
def test_extreme_loops_fail_quickly_with_a_reason(tmp_path: Path, key: str, value: str, why: str) -> None:
    from lyapcheck.paper.simulation.scenario_run import run_scenarios, simulation_document
    from lyapcheck.paper.simulation.scenarios import load_scenario

    scenario = load_scenario(_scenario(tmp_path, key, value))
    results = run_scenarios([scenario])
    doc = simulation_document(scenario, results)
    # k_d = 1e300 took a million zero-length steps (~40 minutes) before issue 14: count steps, not seconds
    assert results.integration.n_iterations < 100
    assert doc["diverged"] is True and doc["integrator"]["ok"] is False
    assert doc["integrator"]["failure"].startswith(why), doc["integrator"]


@FP_WARNINGS
def test_a_huge_disturbance_runs_and_diverges(tmp_path: Path) -> None:
    from lyapcheck.paper.simulation.scenario_run import run_scenarios, simulation_document
    from lyapcheck.paper.simulation.scenarios import load_scenario

    scenario = load_scenario(_scenario(tmp_path, "velocity", '["1e300 m/s", "-1e300 m/s"]'))
    doc = simulation_document(scenario, run_scenarios([scenario]))
    assert doc["integrator"] == {**doc["integrator"], "ok": True, "failure": None}
    assert doc["diverged"] is True and abs(doc["final_eps_m"]) > 1e299


def test_paper_scenario_has_no_failure(tmp_path: Path) -> None:
    from lyapcheck.paper.simulation.scenario_run import run_scenarios, simulation_document
    from lyapcheck.paper.simulation.scenarios import load_scenario

    scenario = load_scenario(_scenario(tmp_path, "rtol", "1e-8"))
    doc = simulation_document(scenario, run_scenarios([scenario]))
    assert doc["integrator"]["ok"] is True and doc["integrator"]["failure"] is None
    assert doc["steps_accepted"] + doc["steps_rejected"] < SIM_MAX_STEPS // 10


def test_a_tail_too_short_for_the_step_budget_is_refused(tmp_path: Path) -> None:
    from lyapcheck.paper.simulation.scenarios import load_scenario

    shortest = 1.0 * STEPS_PER_TAIL / SIM_MAX_STEPS  # the scenario's horizon is 1 s
    with pytest.raises(InvalidParameter, match=rf"'tail' parameter must be at least horizon \* {STEPS_PER_TAIL} / "
                                               rf"{SIM_MAX_STEPS} = {re.escape(f'{shortest:.6g}')} s .*SIM_MAX_STEPS"):
        load_scenario(_scenario(tmp_path, "tail", '"1e-300 s"'))
    load_scenario(_scenario(tmp_path, "tail", f'"{shortest!r} s"'))  # the bound itself is accepted


# -- linear views (certify --linear-views) -------------------------------------------------------
def test_linear_views_beyond_the_double_range_are_not_computed_but_exact_hurwitz_is() -> None:
    from lyapcheck.api import problem_from
    from lyapcheck.paper.certification import build_system
    from lyapcheck.paper.linalg_views import linear_views

    views = linear_views(build_system(problem_from(ROOT / "examples" / "paper.toml",
                                                   {"alpha_d": "1e300", "e11": "1e300 m"}), "derived"))
    for name in ("A", "linearisation_at_0"):
        assert views[name]["computed"] is False and "beyond the largest double" in views[name]["reason"]
        assert views[name]["hurwitz_exact"] is True  # rational: decided at any scale
    assert views["lyap_gamma_identity"]["computed"] is False
    paper = linear_views(build_system(problem_from(ROOT / "examples" / "paper.toml"), "derived"))
    assert all(view["computed"] is True for view in paper.values())


@FP_WARNINGS
@pytest.mark.slow
@pytest.mark.parametrize(("key", "value"), [("k_d", "1e300"), ("e11", '"1e300 m"')])
def test_worst_case_search_at_extreme_scales_is_no_internal_error(tmp_path: Path, key: str, value: str) -> None:
    """The loop's resonances at these scales would need square waves with ~1e300 switches: those
    candidates are skipped with the reason (lyapcheck.paper.simulation.worst_case.MAX_SWITCHES)."""
    from click.testing import CliRunner

    from lyapcheck.cli import app

    app._register_commands()
    path = _scenario(tmp_path, key, value)
    result = CliRunner().invoke(app.cli, ["simulate", str(path), "--worst-case", "--budget", "1", "--json"])
    assert result.exit_code in (0, 1), result.output
    assert "Traceback" not in result.output and "internal error" not in result.output
