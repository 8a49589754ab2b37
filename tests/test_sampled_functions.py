"""Sampled-data loops whose controller law uses functions (issue 44, item 2): the law is recast by the
model language's builder, its value at the equilibrium is exact or the file is refused in one line, its
gain ``K = dk/dx`` is the chain rule through the functions (``not_applicable`` where one is not
differentiable), ``simulate`` evaluates the functions by numpy at every sample, and ``verify`` re-derives
everything from the model text."""

from __future__ import annotations

import json
from fractions import Fraction
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner
from scipy.integrate import solve_ivp

from tests.conftest import ROOT

MODELS = ROOT / "examples" / "models"
SATURATED = MODELS / "pendulum-digital-sat-pd.toml"
LINEAR = MODELS / "pendulum-digital-pd.toml"
LAW = 'u = "sat(-Kp*theta - Kd*omega, u_max)"'

#: a scalar plant at a non-zero equilibrium, for laws whose value there is not 0
OFFSET = ('[model]\nstates = ["x"]\n[parameters]\nk = 2\n[dynamics]\nx = "-x + u"\n[equilibrium]\nx = 1\n'
          '[sampling]\nperiod = "0.1 s"\n[controller]\nu = "LAW"\n')


def _invoke(*args: str) -> tuple[int, str]:
    from lyapcheck.cli import app

    app._register_commands()
    result = CliRunner().invoke(app.cli, list(args))
    return result.exit_code, result.output


def _with_law(tmp_path: Path, law: str) -> Path:
    path = tmp_path / "law.toml"
    text = SATURATED.read_text()
    assert LAW in text
    path.write_text(text.replace(LAW, f'u = "{law}"'))
    return path


def test_the_saturated_law_is_certified_with_the_linear_laws_gain() -> None:
    from lyapcheck.api import certify
    from lyapcheck.models.classes.sampled import linear_parts
    from lyapcheck.models.language.sampling import load_sampled

    saturated, linear = load_sampled(SATURATED), load_sampled(LINEAR)
    assert saturated.controller_system is not None and linear.controller_system is None
    assert saturated.control_equilibrium == (Fraction(0),)
    # inside its limits sat has slope 1: the same A, B, K as the unsaturated law, exactly
    assert linear_parts(saturated) == linear_parts(linear)
    assert linear_parts(saturated)[2] == [[Fraction(-30), Fraction(-5)]]
    doc = certify(model=SATURATED).document
    again = certify(model=LINEAR).document
    assert doc["verdict"] == again["verdict"] == "certified"  # (linearization and roa)
    # inside its limits near the equilibrium the saturation is the linear law: the same region of attraction
    assert doc["conditions"]["roa"]["certificate"]["P"] == again["conditions"]["roa"]["certificate"]["P"]
    ours, theirs = doc["conditions"]["linearization"], again["conditions"]["linearization"]
    assert ours["status"] == "certified" and ours["certificate"] == theirs["certificate"]
    assert doc["sampling"]["controller"] == {"u": "sat(-Kp*theta - Kd*omega, u_max)"}


def test_the_largest_period_is_the_unsaturated_laws() -> None:
    from lyapcheck.api import certify_extremum

    found = certify_extremum(SATURATED, "T=0.01..1", direction="max", steps=12)
    same = certify_extremum(LINEAR, "T=0.01..1", direction="max", steps=12)
    assert found.proved is not None and found.failed is not None and found.failed.outcome == "refuted"
    assert (found.proved, found.failed.value) == (same.proved, same.failed.value)  # type: ignore[union-attr]
    assert 0.379 < float(found.proved) < float(found.failed.value) < 0.381


def test_a_law_saturated_at_the_equilibrium_has_no_gain_and_is_refuted(tmp_path: Path) -> None:
    """Beyond its limit sat is locally constant (slope 0): the upright pendulum is then uncontrolled to
    first order, and unstable."""
    from lyapcheck.api import certify
    from lyapcheck.models.classes.sampled import linear_parts
    from lyapcheck.models.language.sampling import load_sampled

    path = _with_law(tmp_path, "sat(theta + 2, 1) - 1")
    assert linear_parts(load_sampled(path))[2] == [[Fraction(0), Fraction(0)]]
    doc = certify(model=path).document
    assert doc["conditions"]["linearization"]["status"] == "refuted" and doc["verdict"] == "unstable"


@pytest.mark.parametrize("law, function", [("-Kp*abs(theta) - Kd*omega", "abs(theta)"),
                                           ("sat(theta + 1, 1) - 1", "sat(theta + 1, 1)")])
def test_a_function_not_differentiable_at_the_equilibrium_is_not_applicable(tmp_path: Path, law: str,
                                                                            function: str) -> None:
    path = _with_law(tmp_path, law)
    out = tmp_path / "cert.json"
    code, text = _invoke("certify", str(path), "--out", str(out))
    assert "Traceback" not in text
    doc = json.loads(out.read_text())
    result = doc["conditions"]["linearization"]
    assert result["status"] == "not_applicable" and doc["verdict"] == "not_certified" and code == 1
    assert function in result["summary"] and "[controller] u" in result["summary"]
    assert "not differentiable" in result["summary"]
    assert _invoke("verify", str(out))[0] == 0


@pytest.mark.parametrize(("plant", "continuous_status"), [("-abs(x) + u", "not_certified"),
                                                       ("-x + sat(x + 1, 1) - 1 + u", "certified")])
def test_a_plant_not_differentiable_at_the_equilibrium_is_not_applicable_as_a_continuous_loop(
        tmp_path: Path, plant: str, continuous_status: str) -> None:
    """The plant's Jacobian cannot be formed exactly: the sampled-data linearization is ``not_applicable`` for the
    Jacobian's reason (not ``inconclusive``: no search was left undecided), and verify re-derives it. The
    continuous loop with the same field takes the kink's piecewise-linear route instead
    (:mod:`lyapcheck.models.classes.piecewise_linearization`): ``-abs(x) - x`` is 0 for every x < 0 (no
    exponential stability: not certified, never refuted), ``-2x + sat(x + 1, 1) - 1`` has slopes -1 and -2
    (certified)."""
    from lyapcheck.api import certify

    sampled = tmp_path / "sampled.toml"
    sampled.write_text(f'[model]\nstates = ["x"]\n[dynamics]\nx = "{plant}"\n[sampling]\nperiod = "0.1 s"\n'
                       '[controller]\nu = "-x"\n')
    continuous = tmp_path / "continuous.toml"
    continuous.write_text(f'[model]\nstates = ["x"]\n[dynamics]\nx = "{plant.replace("+ u", "- x")}"\n')
    field = certify(model=continuous, classes=["linearization"]).document["conditions"]["linearization"]
    assert field["status"] == continuous_status and field["property"] == "LES"
    out = tmp_path / "cert.json"
    code, text = _invoke("certify", str(sampled), "--out", str(out))
    assert "Traceback" not in text
    doc = json.loads(out.read_text())
    result = doc["conditions"]["linearization"]
    assert result["status"] == "not_applicable" and doc["verdict"] == "not_certified" and code == 1
    assert result["summary"].startswith("the plant's Jacobian at the equilibrium cannot be formed exactly: ")
    assert "not differentiable" in result["summary"] and result["property"] == "LES"
    assert _invoke("verify", str(out))[0] == 0


@pytest.mark.parametrize("law, says", [
    # each function's value is kept exactly: tanh(1) is transcendental even where the two cancel
    ("tanh(theta + 1) - tanh(1)", "tanh(1)"),
    ("tanh(theta + 1)", "tanh is transcendental"),
    ("-Kp*sin(theta + pi/4)", "irrational"),  # sqrt(2)/2 * -Kp: exact in Q(sqrt 2), not rational
    ("sqrt(2 + theta)", "square root is irrational"),
    ("-Kp*theta + pi", "pi may appear only"),
    ("-Kp*sinh(theta)", "unknown function 'sinh'"),
])
def test_a_law_without_an_exact_value_at_the_equilibrium_is_one_line_exit_2(tmp_path: Path, law: str,
                                                                            says: str) -> None:
    code, text = _invoke("certify", str(_with_law(tmp_path, law)))
    assert code == 2, text
    assert "Traceback" not in text and len(text.strip().splitlines()) == 1
    assert "[controller] u" in text and says in text


@pytest.mark.parametrize("law, value, gain", [
    ("1 - k*tanh(x - 1)", 1, -2),
    ("sat(1 - k*(x - 1), 3)", 1, -2),
    ("1 - k*tanh(sat(x - 1, 1))", 1, -2),  # nested: the chain rule through both
    # the quotient rule with a value and a slope in the denominator: (-2*2 - 2*1)/2^2
    ("(2 - k*tanh(x - 1))/(2 + tanh(x - 1))", 1, Fraction(-3, 2)),
    ("max(x, 2) - 1", 1, 0),  # max(x, 2) = 2 near x = 1: constant there
])
def test_the_value_and_gain_at_a_non_zero_equilibrium(law: str, value: Fraction, gain: Fraction) -> None:
    from lyapcheck.models.classes.sampled import linear_parts
    from lyapcheck.models.language.sampling import parse_sampled
    from lyapcheck.models.surfaces.sampled_simulate import ControlLaw

    model = parse_sampled(OFFSET.replace("LAW", law))
    assert model.control_equilibrium == (Fraction(value),)
    parts = linear_parts(model)
    assert not isinstance(parts, str) and parts[2] == [[Fraction(gain)]]
    # the numeric law agrees with the exact value, and its slope with the exact gain
    h = 1e-6
    u = ControlLaw(model)(np.array([[1.0], [1.0 + h], [1.0 - h]]))[:, 0]
    assert u[0] == pytest.approx(float(value), abs=1e-15)
    assert (u[1] - u[2]) / (2 * h) == pytest.approx(float(gain), abs=1e-6)


def test_simulate_holds_the_clipped_torque(tmp_path: Path) -> None:
    """One period from theta = 1: the law asks -30, the held torque is -20, and the state after one period
    is the pendulum's flow under u = -20 (an independent integration)."""
    from lyapcheck.models.language.sampling import load_sampled
    from lyapcheck.models.surfaces.sampled_simulate import ControlLaw, run_sampled

    model = load_sampled(SATURATED)
    start = np.array([[1.0, 0.0], [0.1, 0.0]])
    assert ControlLaw(model)(start)[:, 0] == pytest.approx([-20.0, -3.0])
    doc = run_sampled(model, start, "two starts", t_end=0.02).document
    assert doc["periods"] == 1
    for row, u in zip(doc["trajectories"], (-20.0, -3.0)):
        exact = solve_ivp(lambda t, x: [x[1], 9.81 * np.sin(x[0]) - 0.1 * x[1] + u], (0.0, 0.02),
                          start[row["start"]], rtol=1e-11, atol=1e-13).y[:, -1]
        assert [row["final_state"]["theta"], row["final_state"]["omega"]] == pytest.approx(exact, abs=1e-7)
        assert row["final_control"]["u"] == pytest.approx(u)
    # the whole command: every start converges, the plot is written, theta is not taken modulo 2 pi
    plot = tmp_path / "sat.png"
    code, text = _invoke("simulate", str(SATURATED), "--x0", "theta=1", "--x0", "theta=-1.2,omega=1", "--t-end", "4",
                         "--json", "--plot", str(plot))
    assert code == 0, text
    doc = json.loads(text)
    assert doc["n_converged"] == 2 and not doc["diverged"] and doc["angles_modulo_2pi"] == []
    assert plot.stat().st_size > 0


def test_verify_passes_and_a_tampered_certificate_fails() -> None:
    from lyapcheck.api import certify, verify

    doc = certify(model=SATURATED).document
    assert verify(doc).valid
    for change in ("K", "controller", "text"):
        bad = json.loads(json.dumps(doc))
        if change == "K":
            bad["conditions"]["linearization"]["certificate"]["K"] = [["-30", "-6"]]
        elif change == "controller":  # the law as stated, not the model text's
            bad["sampling"]["controller"]["u"] = "-Kp*theta - Kd*omega"
        else:  # the law in the model text itself, its hash updated: another gain, another answer's data
            import hashlib

            bad["model"]["text"] = bad["model"]["text"].replace("sat(-Kp*theta - Kd*omega, u_max)",
                                                                "sat(-Kp*theta - 2*Kd*omega, u_max)")
            bad["model"]["sha256"] = hashlib.sha256(bad["model"]["text"].encode()).hexdigest()
        assert not verify(bad).valid, change
