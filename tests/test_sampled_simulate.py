"""``simulate`` of a sampled-data loop (issue 44): the true plant between samples, each control held at its
value computed from the state at the sampling instant (zero-order hold), one integrator call per period."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner
from scipy.linalg import expm

from tests.conftest import ROOT

MODELS = ROOT / "examples" / "models"
STABLE = MODELS / "pendulum-digital-pd.toml"
SLOW = MODELS / "pendulum-digital-pd-slow.toml"

#: a polynomial plant whose sampled loop is linear: x_{k+1} = A_T x_k exactly, A_T from a matrix exponential
DOUBLE_INTEGRATOR = """
[model]
name = "double integrator, digital PD"
states = ["x", "v"]

[parameters]
kp = 1
kd = 1
T = "100 ms"

[dynamics]
x = "v"
v = "u"

[sampling]
period = "T"

[controller]
u = "-kp*x - kd*v"
"""


def _invoke(*args: str) -> tuple[int, str, str]:
    from lyapcheck.cli import app

    app._register_commands()
    result = CliRunner().invoke(app.cli, list(args))
    return result.exit_code, result.stdout, result.stderr


def _sampled_map(A: np.ndarray, B: np.ndarray, K: np.ndarray, T: float) -> np.ndarray:
    """The held-control flow over one period, exp(A T) + Gamma(T) B K, from one matrix exponential."""
    n, m = B.shape
    M = np.zeros((n + m, n + m))
    M[:n, :n], M[:n, n:] = A * T, B * T
    E = expm(M)
    return E[:n, :n] + E[:n, n:] @ K


def test_the_stable_example_converges_and_the_slow_one_diverges() -> None:
    code, out, err = _invoke("simulate", str(STABLE), "--json")
    assert code == 0, err
    doc = json.loads(out)
    assert doc["mode"] == "sampled" and doc["period_s"] == 0.02 and doc["sampling"]["period"] == "1/50"
    assert doc["controls"] == ["u"] and doc["outputs"]["u"] == "-Kp*theta - Kd*omega"
    assert doc["n_trajectories"] == 5 and doc["n_converged"] == 5 and not doc["diverged"]
    assert doc["t_end_s"] == pytest.approx(doc["periods"] * 0.02)
    for row in doc["trajectories"]:
        assert row["converged"] and not row["diverged"] and row["periods"] == doc["periods"]
        assert abs(row["final_state"]["theta"]) < 1e-3 * doc["state_scale"]["theta"]
    # the pendulum's theta is not an angle of the sampled loop: the controller's -Kp*theta tells it apart
    assert doc["angles_modulo_2pi"] == []

    code, out, err = _invoke("simulate", str(SLOW), "--json")
    assert code == 1, err
    doc = json.loads(out)
    assert doc["period_s"] == 0.5 and doc["diverged"]
    moved = [row for row in doc["trajectories"] if row["start"] != 0]  # start 0 is the equilibrium itself
    assert moved and all(row["diverged"] and "escape box" in row["failure"] for row in moved)
    assert all(v is None for row in moved for v in row["sup_abs_output_tail"].values())


@pytest.mark.parametrize("period, stable", [("0.3 s", True), ("0.45 s", False)])
def test_the_simulated_loop_changes_stability_at_the_exact_critical_period(period: str, stable: bool) -> None:
    from lyapcheck.api import certify, simulate

    exact = certify(model=STABLE, classes="linearization", settings={"T": period})
    assert exact.conditions["linearization"].status == ("certified" if stable else "refuted")
    result = simulate(model=STABLE, settings={"T": period}, x0="theta=0.05 omega=0", series=False)
    doc = result.document
    assert doc["period_s"] == pytest.approx(float(period.split()[0]))
    assert doc["trajectories"][0]["converged"] is stable and result.diverged is not stable


@pytest.mark.parametrize("period, grows", [(0.37, False), (0.39, True)])
def test_near_the_critical_period_small_oscillations_decay_below_and_grow_above(period: float, grows: bool) -> None:
    """0.380 s is the critical period of the linearization (tests/test_sampled_loops.py): over 150 periods
    from 1e-3 rad, a start 3 % below it shrinks and 3 % above it grows, by the factor rho^150 the
    spectral radius predicts (0.975^150 ~ 0.02, 1.025^150 ~ 40)."""
    from lyapcheck.api import simulate

    doc = simulate(model=STABLE, settings={"T": f"{period} s"}, x0="theta=0.001 omega=0", t_end=150 * period,
                   series=False).document
    rho = doc["spectral_radius_estimate"]
    assert (rho > 1) is grows
    tail = doc["sup_abs_output_tail"]["theta"]
    assert (tail > 0.01) if grows else (tail < 1e-4), tail  # a tenfold move either way, in the linear regime


def test_the_held_control_flow_is_the_exact_sampled_map(tmp_path: Path) -> None:
    """A linear plant: the state at every sampling instant is A_T^k x_0 (not the emulated loop u = k(x(t)))."""
    from lyapcheck.api import simulate

    path = tmp_path / "double.toml"
    path.write_text(DOUBLE_INTEGRATOR)
    result = simulate(model=path, x0=[[1.0, 0.0], [0.0, -0.5]], t_end=2.0)
    A, B, K = np.array([[0.0, 1.0], [0.0, 0.0]]), np.array([[0.0], [1.0]]), np.array([[-1.0, -1.0]])
    AT = _sampled_map(A, B, K, 0.1)
    series = result.series
    time = series.time.values
    for row, x0 in enumerate(([1.0, 0.0], [0.0, -0.5])):
        exact = np.linalg.matrix_power(AT, 20) @ np.array(x0)
        final = result.document["trajectories"][row]["final_state"]
        assert np.allclose([final["x"], final["v"]], exact, rtol=1e-6, atol=1e-8)
        # the series: at each instant k T the control is k(x(kT)) and it holds until the next
        x = series.x.isel(trajectory=row).values
        u = series.u.isel(trajectory=row, control=0).values
        for k in range(20):
            at = np.flatnonzero(np.isclose(time, 0.1 * k, rtol=0, atol=1e-12))
            inside = (time >= 0.1 * k) & (time < 0.1 * (k + 1) - 1e-12)
            assert at.size == 1
            assert u[at[0]] == pytest.approx(-x[at[0], 0] - x[at[0], 1], abs=1e-9)
            assert np.ptp(u[inside]) <= 1e-12  # held (the dense output of a constant, to rounding)
        # the emulated continuous loop (x'' = -x - x') is another system: it ends elsewhere
        emulated = expm(np.array([[0.0, 1.0], [-1.0, -1.0]]) * 2.0) @ np.array(x0)
        assert not np.allclose(exact, emulated, rtol=1e-3, atol=1e-6)
    assert set(series.data_vars) == {"x", "y", "u"} and list(series.control.values) == ["u"]


def test_plot_repr_and_api_arguments(tmp_path: Path) -> None:
    from lyapcheck.api import simulate

    plot = tmp_path / "sampled.png"
    result = simulate(model=STABLE, x0={"theta": 0.2}, t_end="1 s", plot=plot)
    assert plot.stat().st_size > 10_000 and result.document["plot"] == str(plot)
    text = repr(result)
    assert "sampled every 0.02 s (zero-order hold), 50 periods" in text and "x, u" in text
    assert result.document["periods"] == 50 and result.document["tail_window_s"] == pytest.approx([0.8, 1.0])
    # a horizon that is not a whole number of periods: the last one is cut at the horizon
    doc = simulate(model=STABLE, x0={"theta": 0.2}, t_end=0.05, series=False).document
    assert doc["periods"] == 3 and doc["t_end_s"] == 0.05


@pytest.mark.parametrize("flags, field", [
    (("--worst-case",), "worst_case (--worst-case)"),
    (("--scenario", "square"), "scenarios (--scenario)"),
    (("--frequencies", "1..2"), "frequencies (--frequencies)"),
    (("--worst-case", "--certificate", "c.json"), "worst_case (--worst-case)"),
    (("--steps", "10"), "steps (--steps)"),
    (("--grid", "3"), "grid (--grid)"),
])
def test_what_does_not_apply_is_refused_in_one_line(flags: tuple[str, ...], field: str) -> None:
    code, out, err = _invoke("simulate", str(STABLE), *flags)
    assert code == 2, out
    assert field in err and "sampled-data loop" in err
    assert "Traceback" not in err and len(err.strip().splitlines()) == 1


def test_the_api_refuses_a_certificate_by_its_argument_name() -> None:
    from lyapcheck.api import simulate
    from lyapcheck.errors import ModelFileError

    with pytest.raises(ModelFileError, match=r"certificate \(--certificate\): not taken for a sampled-data loop"):
        simulate(model=STABLE, certificate="c.json")


def test_the_default_horizon_follows_the_sampled_linearization() -> None:
    from lyapcheck.models.language.sampling import load_sampled
    from lyapcheck.models.classes.sampled import spectral_radius_estimate as spectral_radius
    from lyapcheck.models.surfaces.sampled_simulate import FALLBACK_PERIODS, MIN_PERIODS, default_periods
    from lyapcheck.models.surfaces.simulate import HORIZON_TIME_CONSTANTS

    rho = spectral_radius(load_sampled(STABLE))
    A, B, K = np.array([[0.0, 1.0], [9.81, -0.1]]), np.array([[0.0], [1.0]]), np.array([[-30.0, -5.0]])
    assert rho == pytest.approx(max(abs(np.linalg.eigvals(_sampled_map(A, B, K, 0.02)))), rel=1e-9)
    assert default_periods(rho) == math.ceil(HORIZON_TIME_CONSTANTS / -math.log(rho))
    assert default_periods(1.2) == FALLBACK_PERIODS and default_periods(None) == FALLBACK_PERIODS
    assert default_periods(0.0) == MIN_PERIODS


def test_the_continuous_readers_name_simulate_among_the_commands_that_take_it() -> None:
    from lyapcheck.errors import ModelFileError
    from lyapcheck.models.language.modelfile import load_model

    with pytest.raises(ModelFileError, match=r"'certify' and 'verify'.*'simulate'"):
        load_model(STABLE)


def test_the_integrators_first_step_continues_a_trajectory_to_the_same_answer() -> None:
    """``integrate(first_step=...)`` (one call per period starts from the last period's step): the error
    control still decides, so y' = -y from 1 ends at exp(-2) either way; a step <= 0 is refused."""
    from lyapcheck.integrator import Evaluation, integrate

    class Decay:
        size = 2

        def take(self, index: np.ndarray) -> "Decay":
            return self

        def rhs(self, t: np.ndarray, y: np.ndarray, t_segment: np.ndarray) -> Evaluation:
            return Evaluation(-y, np.zeros(y.shape[0]), np.empty((y.shape[0], 0)))

        def next_breakpoint(self, t: np.ndarray) -> np.ndarray:
            return np.full(t.shape, np.inf)

    y0 = np.ones((2, 1))
    for first in (None, np.array([1.0, 1e-3])):
        result = integrate(Decay(), 0.0, y0, 2.0, rtol=1e-10, atol=1e-12, first_step=first)
        assert np.allclose(result.y[:, 0], math.exp(-2.0), rtol=1e-8)
    with pytest.raises(ValueError, match="first_step"):
        integrate(Decay(), 0.0, y0, 2.0, atol=1e-12, first_step=0.0)
