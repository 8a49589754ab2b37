"""``simulate --model``: a model file's loop under bounded disturbances, and the worst-case search.

Figures are checked against closed forms where the model has one: the linear cascade of
``examples/models/linear-disturbed-l1.toml`` (worst case ``limsup |x1| = 1/2`` exactly, attained by
``d = 1``; a square wave of half period ``tau`` drives ``x2' = -2 x2 + d`` to the periodic peak
``tanh(tau) / 2``), the reversed Van der Pol oscillator (the start (0.5, 0) lies inside its unstable
limit cycle, (2.5, 0) outside) and a rational field against scipy's Radau.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner, Result

from lyapcheck.cli import app  # type: ignore[attr-defined]  # the module, as tests/test_fuzz.py uses it
from lyapcheck.errors import InvalidParameter
from lyapcheck.models.surfaces import simulate as sim
from lyapcheck.models.language.modelfile import load_model, parse_model
from lyapcheck.tolerances import SIM_REL_TOL
from tests.conftest import ROOT

app._register_commands()
RUNNER = CliRunner()
MODELS = ROOT / "examples" / "models"
LINEAR = MODELS / "linear-disturbed-l1.toml"
VDP = MODELS / "van-der-pol-reversed.toml"
#: the exact worst case of the linear cascade, and the integration slack allowed above it
LINEAR_WORST = 0.5
INTEGRATION_SLACK = 1e-6

#: the cascade with the disturbance entering with the other sign: y = x1 then moves against d
NEGATIVE_CASCADE = """
[model]
name = "cascade, disturbance with a negative gain"
states = ["x1", "x2"]
[disturbances]
d = 1
[dynamics]
x1 = "-x1 + x2"
x2 = "-2*x2 - d"
[outputs]
y = "x1"
"""


def invoke(*args: str) -> Result:
    return RUNNER.invoke(app.cli, list(args), catch_exceptions=False)


@pytest.fixture(scope="module")
def linear() -> sim.Prepared:
    return sim.prepare(load_model(LINEAR))


# -- the linear cascade: exact figures ----------------------------------------------------------

def test_constant_disturbance_drives_the_cascade_to_its_exact_worst_case(linear: sim.Prepared) -> None:
    doc = sim.simulate_model(linear.model, starts=[[0.0, 0.0]], scenarios=["none", "constant"], prepared=linear)
    none, constant = doc["scenarios"]["none"], doc["scenarios"]["constant"]
    assert none["sup_abs_output_tail"]["y"] < 1e-9 and none["converged"] == 1
    for y in ("y", "w"):  # d = +-1 gives x = +-(1/2, 1/2): the tail sup is the DC gain 1/2
        assert constant["sup_abs_output_tail"][y] == pytest.approx(LINEAR_WORST, rel=SIM_REL_TOL)
    assert [d["d"]["d"] for d in constant["disturbances"]] == [1.0, -1.0]
    assert not doc["diverged"] and doc["n_trajectories"] == 3


def test_square_wave_reaches_the_periodic_peak_of_the_first_order_lag(linear: sim.Prepared) -> None:
    omega = 2.0  # rad/s: half period tau = pi / omega; x2' = -2 x2 +- 1 peaks at tanh(tau) / 2
    doc = sim.simulate_model(linear.model, starts=[[0.0, 0.0]], scenarios=["square"], frequencies=(omega, omega),
                             prepared=linear)
    (row,) = doc["trajectories"]
    assert row["disturbance"]["angular_frequency_rad_s"] == omega
    expected = math.tanh(math.pi / omega) / 2
    assert row["sup_abs_output_tail"]["w"] == pytest.approx(expected, rel=1e-6)
    assert row["sup_abs_output_tail"]["y"] < LINEAR_WORST


def test_the_worst_case_search_finds_the_exact_worst_case_and_never_exceeds_it(linear: sim.Prepared) -> None:
    doc = sim.search_worst_case(linear.model, budget_s=1.0, prepared=linear)
    for y in ("y", "w"):
        worst = doc["sup_abs_output_tail"][y]
        assert 0.49 <= worst <= LINEAR_WORST + INTEGRATION_SLACK
        assert doc["worst"][y]["sup_abs_output_tail"] == worst
        # every family's figure is a lower estimate of the exact worst case, too
        assert all(f[y] <= LINEAR_WORST + INTEGRATION_SLACK for f in doc["per_family"].values())
    assert doc["worst"]["y"]["disturbance"]["kind"] in ("constant", "bang-bang")
    assert doc["diverged"] is False and doc["candidates_tried"] >= 22
    assert set(doc) >= {"sup_abs_output_tail", "worst", "per_family", "diverged", "candidates_tried", "rounds",
                        "budget_s", "budget_exhausted", "t_end_s", "tail_window_s", "rtol", "search_rtol"}


def test_bang_bang_feedback_uses_the_gradient_or_the_first_markov_parameter(linear: sim.Prepared) -> None:
    # w = x2 sees d at once (dw'/dd = 1); y = x1 only through x2: c A B = 1 > 0
    assert linear.feedback["w"].terms[0] is not None and linear.feedback["y"].terms[0] is None
    assert linear.linearization.markov_sign["y"] == (1.0,)
    flipped = sim.prepare(parse_model(NEGATIVE_CASCADE))
    assert flipped.linearization.markov_sign["y"] == (-1.0,)
    doc = sim.simulate_model(flipped.model, starts=[[0.0, 0.0]], scenarios=["bang-bang"], prepared=flipped)
    # both directions push |y| up to the worst case 1/2, with the opposite sign of d
    ups = [row["sup_abs_output_tail"]["y"] for row in doc["trajectories"]]
    assert ups == pytest.approx([LINEAR_WORST, LINEAR_WORST], rel=SIM_REL_TOL)
    assert [row["final_state"]["x1"] > 0 for row in doc["trajectories"]] == [True, False]


def test_tightness_ratio_and_soundness_violation() -> None:
    out = sim.tightness({"y": 0.6, "w": 0.4, "z": 1.0}, {"y": 0.5, "w": 0.5})
    assert set(out) == {"y", "w"}
    assert out["y"]["tightness_ratio"] == pytest.approx(1.2) and not out["y"]["soundness_violation"]
    assert out["w"]["tightness_ratio"] == pytest.approx(0.8) and out["w"]["soundness_violation"]
    # within the simulator's accuracy contract a bound equal to the worst case is not a violation
    assert not sim.tightness({"y": 0.5}, {"y": 0.5 * (1 + SIM_REL_TOL / 10)})["y"]["soundness_violation"]
    assert sim.tightness({"y": 0.5}, {"y": 0.0})["y"]["tightness_ratio"] is None


# -- convergence and divergence -----------------------------------------------------------------

def test_reversed_van_der_pol_converges_inside_its_cycle_and_diverges_outside() -> None:
    inside = invoke("simulate", "--model", str(VDP), "--x0", "x1=0.5,x2=0", "--json")
    assert inside.exit_code == 0, inside.output
    doc = json.loads(inside.stdout)
    (row,) = doc["trajectories"]
    assert row["converged"] and not row["diverged"] and row["failure"] is None
    assert doc["starts"] == [{"x1": 0.5, "x2": 0.0}] and list(doc["scenarios"]) == ["none"]
    outside = invoke("simulate", "--model", str(VDP), "--x0", "x1=2.5,x2=0", "--json")
    assert outside.exit_code == 1
    (row,) = json.loads(outside.stdout)["trajectories"]
    assert row["diverged"] and not row["converged"] and "escape" in row["failure"]
    assert row["sup_abs_output_tail"] == {"x1": None, "x2": None}


def test_rational_field_matches_an_independent_integrator() -> None:
    from scipy.integrate import solve_ivp

    model = load_model(MODELS / "sosdemo2-rational.toml")
    x0 = np.array([0.8, -0.5, 1.2])
    doc = sim.simulate_model(model, starts=[x0], t_end=5.0)
    final = np.array(list(doc["trajectories"][0]["final_state"].values()))

    def f(t: float, x: np.ndarray) -> list[float]:
        x1, x2, x3 = x
        return [-x1**3 - x1 * x3**2, -x2 - x1**2 * x2, -x3 - 3 * x3 / (x3**2 + 1) + 3 * x1**2 * x3]

    ref = solve_ivp(f, (0.0, 5.0), x0, method="Radau", rtol=1e-11, atol=1e-13).y[:, -1]
    assert np.max(np.abs(final - ref)) < 1e-7


def test_default_starts_are_documented() -> None:
    p = sim.prepare(load_model(VDP))
    starts, how = sim.default_starts(p)
    assert starts.shape == (25, 2) and np.all(starts[0] == 0) and "5-per-state grid" in how
    assert len({tuple(s) for s in starts}) == 25  # the equilibrium once
    q = sim.prepare(load_model(LINEAR))  # no [domain]: the equilibrium and +-1/2 scale along each state
    starts, how = sim.default_starts(q)
    assert starts.tolist() == [[0, 0], [0.25, 0], [-0.25, 0], [0, 0.25], [0, -0.25]] and "no [domain]" in how


def test_starts_from_x0_and_grid(linear: sim.Prepared) -> None:
    assert sim.parse_start(linear.model, "x2=0.25").tolist() == [0.0, 0.25]  # x1: the equilibrium's
    assert sim.parse_start(linear.model, "x1=1 mm, x2=2 cm").tolist() == pytest.approx([1e-3, 2e-2])  # SI inside
    grid = sim.grid_over_domain(load_model(VDP), 3)
    assert grid.shape == (9, 2) and grid.min(axis=0).tolist() == [-2.5, -3.5]


# -- the command line ---------------------------------------------------------------------------

def test_json_document_keys_are_stable() -> None:
    done = invoke("simulate", "--model", str(LINEAR), "--x0", "x1=0", "--scenario", "constant", "--json")
    assert done.exit_code == 0, done.output
    doc = json.loads(done.stdout)
    assert set(doc) >= {"mode", "model", "states", "equilibrium", "disturbance_bounds", "outputs", "starts",
                        "t_end_s", "tail_window_s", "sup_abs_output_tail", "scenarios", "diverged", "n_diverged",
                        "trajectories", "rtol", "integrator"}
    assert set(doc["scenarios"]["constant"]) >= {"disturbances", "sup_abs_output_tail", "diverged", "converged"}
    assert set(doc["trajectories"][0]) >= {"start", "scenario", "disturbance", "sup_abs_output_tail", "final_state",
                                           "converged", "diverged", "failure"}
    assert doc["mode"] == "scenarios" and doc["tail_window_s"] == [32.0, 40.0]


def test_worst_case_with_certificate_flags_a_violation_loudly(monkeypatch: pytest.MonkeyPatch,
                                                              tmp_path: Path) -> None:
    # a certified bound below what simulation reaches can only come from a bug: simulate one
    monkeypatch.setattr(sim, "certified_bounds_of", lambda model, path: {"y": 0.3, "w": 0.6})
    args = ["simulate", "--model", str(LINEAR), "--worst-case", "--budget", "1", "--t-end", "10", "--certificate",
            str(tmp_path / "cert.json")]
    done = invoke(*args)
    assert done.exit_code == 1
    assert "SOUNDNESS VIOLATION" in done.stdout and "SOUNDNESS VIOLATION" in done.stderr
    done = invoke(*args, "--json")
    doc = json.loads(done.stdout)
    assert done.exit_code == 1 and doc["soundness_violation"] is True
    assert doc["tightness_ratio"]["y"] == pytest.approx(0.6, rel=1e-3)
    assert doc["tightness_ratio"]["w"] == pytest.approx(1.2, rel=1e-3)
    assert doc["tightness"]["y"]["soundness_violation"] and not doc["tightness"]["w"]["soundness_violation"]


@pytest.mark.slow
def test_worst_case_against_a_real_certificate(tmp_path: Path) -> None:
    cert = tmp_path / "cert.json"
    made = invoke("certify", "--model", str(LINEAR), "--classes", "sos_bound", "--out", str(cert), "--json")
    assert made.exit_code == 0, made.output
    done = invoke("simulate", "--model", str(LINEAR), "--worst-case", "--budget", "2", "--certificate", str(cert),
                  "--json")
    assert done.exit_code == 0, done.output
    doc = json.loads(done.stdout)
    bounds = json.loads(cert.read_text())["conditions"]["sos_bound"]["bounds"]
    for y in ("y", "w"):
        assert doc["tightness_ratio"][y] == pytest.approx(bounds[y] / doc["sup_abs_output_tail"][y])
        assert 1.0 <= doc["tightness_ratio"][y] < 1.5  # the issue's target for sos_bound on this system
    assert doc["soundness_violation"] is False
    # a certificate for other parameters does not apply
    other = invoke("simulate", "--model", str(LINEAR), "--set", "d=2", "--worst-case", "--certificate", str(cert))
    assert other.exit_code == 2 and "certificate" in other.stderr


@pytest.mark.slow
def test_the_paper_loop_as_a_model_reaches_the_papers_worst_case() -> None:
    path = MODELS / "paper-error-dynamics.toml"
    if not path.exists():
        pytest.skip("examples/models/paper-error-dynamics.toml is not shipped yet")
    doc = sim.search_worst_case(load_model(path), budget_s=5.0)
    # lyapcheck simulate --preset paper-ilos --worst-case: 0.278 mm (a square wave at 0.40 rad/s);
    # the paper's certified sos_bound is 0.333 mm
    assert 0.27e-3 <= doc["sup_abs_output_tail"]["eps"] <= 0.333e-3


def test_plot_writes_a_png(tmp_path: Path) -> None:
    out = tmp_path / "vdp.png"
    done = invoke("simulate", "--model", str(VDP), "--x0", "x1=0.5", "--x0", "x1=2.5", "--t-end", "20", "--plot",
                  str(out))
    assert done.exit_code == 1  # (2.5, 0) diverges
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


BAD_INPUTS: list[tuple[list[str], str]] = [
    (["--model", str(LINEAR), "--x0", "x9=1"], "'x0'"),
    (["--model", str(LINEAR), "--x0", "x1=abc"], "'x0'"),
    (["--model", str(LINEAR), "--x0", "x1=1,x1=2"], "'x0'"),
    (["--model", str(LINEAR), "--grid", "3"], "[domain]"),
    (["--model", str(VDP), "--grid", "1"], "'grid'"),
    (["--model", str(VDP), "--grid", "100"], "MAX_STARTS"),
    (["--model", str(VDP), "--grid", "abc"], "--grid"),
    (["--model", str(LINEAR), "--t-end", "-1"], "'t-end'"),
    (["--model", str(LINEAR), "--t-end", "5 m"], "'t-end'"),
    (["--model", str(LINEAR), "--frequencies", "10..1"], "'frequencies'"),
    (["--model", str(LINEAR), "--frequencies", "1e9"], "MAX_SWITCHES"),
    (["--model", str(LINEAR), "--scenario", "storm"], "--scenario"),
    (["--model", str(VDP), "--scenario", "constant"], "[disturbances]"),
    (["--model", str(VDP), "--worst-case"], "[disturbances]"),
    (["--model", str(LINEAR), "--worst-case", "--budget", "0"], "'budget'"),
    (["--model", str(LINEAR), "--certificate", "cert.json"], "--worst-case"),
    (["--model", str(LINEAR), "--plot", "out.pdf"], ".png"),
    (["--model", str(LINEAR), "--preset", "paper-ilos"], "--preset: is a flag of the paper's loop"),
    (["--model", str(LINEAR), "--set", "q=1"], "--set q"),
    (["--model", "missing.toml"], "not found"),
    (["--preset", "paper-ilos", "--x0", "x1=1"], "--model"),
]


@pytest.mark.parametrize("args,names", BAD_INPUTS, ids=[" ".join(a[2:] or a) for a, _ in BAD_INPUTS])
def test_bad_input_is_exit_2_with_one_line(args: list[str], names: str) -> None:
    done = invoke("simulate", *args)
    assert done.exit_code == 2, done.output
    lines = done.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("lyapcheck: error:") and names in lines[0]
    assert "Traceback" not in done.output


def test_library_checks_its_arguments(linear: sim.Prepared) -> None:
    with pytest.raises(InvalidParameter, match="'starts'"):
        sim.simulate_model(linear.model, starts=[[0.0, 0.0, 0.0]], prepared=linear)
    with pytest.raises(InvalidParameter, match="'scenarios'"):
        sim.simulate_model(linear.model, scenarios=["gusts"], prepared=linear)
    with pytest.raises(InvalidParameter, match="'t_end'"):
        sim.simulate_model(linear.model, t_end=-1.0, prepared=linear)
