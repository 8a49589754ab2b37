"""Loops with functions over a box of parameters (``--box``): one certificate for every value.

What is certified is checked against the true loop at the box's corners, simulated here with
numpy's own functions; a certificate whose box, centre or sentence is changed does not verify;
bad boxes are one-line exit-2 errors.
"""

from __future__ import annotations

import copy
import math
import subprocess
import sys
from fractions import Fraction
from pathlib import Path

import numpy as np
import pytest

from lyapcheck import api
from tests.recast_loops import rk4

EXAMPLES = Path(__file__).resolve().parents[1] / "examples" / "models"


def v_of_states(cert: dict, X: np.ndarray) -> np.ndarray:
    """V of a certificate whose V uses the states alone (the first variables), at the states X."""
    shift = [float(Fraction(cert["shift"].get(name, "0"))) for name in cert["variables"][:X.shape[1]]]
    total = np.zeros(len(X))
    for coefficient, exponents in cert["V"]["terms"]:
        assert not any(exponents[X.shape[1]:]), "V uses more than the states"
        term = np.full(len(X), float(Fraction(coefficient)))
        for k, e in enumerate(exponents[:X.shape[1]]):
            term = term * (X[:, k] - shift[k]) ** e
        total += term
    return total


def pendulum_converges(X: np.ndarray, dampings: tuple[float, ...], steps: int) -> None:
    """Every start of X (inside a certified set) ends within 1e-2 of the equilibrium itself, not a
    neighbouring well, for each damping (numpy's RK4 on theta'' = -sin(theta) - b theta')."""
    assert len(X) > 50
    for b in dampings:
        x = X.copy()
        for _ in range(steps):
            x = rk4(lambda z, b=b: np.column_stack([z[:, 1], -np.sin(z[:, 0]) - b * z[:, 1]]), x, 0.02)
        assert np.abs(x).max() < 1e-2, b


@pytest.fixture(scope="module")
def ilos_box() -> api.ModelCertification:
    return api.certify(model=EXAMPLES / "recast-ilos-course.toml", box=["kappa=0.4..0.6"])


def test_ilos_over_a_box_of_its_integral_gain_is_gas_for_every_value_with_one_v(ilos_box) -> None:
    result = ilos_box
    assert result.document["box"] == {"kappa": ["2/5", "3/5"]}
    assert result.document["overrides"] == {"kappa": "0.5"}  # read at the box's centre
    lin = result.conditions["linearization"]  # the Jacobian of every kappa of the box (issue 45): LES for each
    assert lin.status == "certified" and lin.summary.startswith("for every kappa in [0.4, 0.6]: the Jacobian")
    for name in ("quadratic", "sos_gas"):
        c = result.conditions[name]
        assert c.status == "certified"
        assert c.summary.startswith("for every kappa in [0.4, 0.6]: GAS: ")
        assert "kappa" in c.certificate["variables"]  # the parameter is a variable of the identities
    assert api.verify(result).valid
    # the one V decreases along the true loop at both ends of the box
    cert = result.conditions["quadratic"].certificate
    rng = np.random.default_rng(0)
    for kappa in (0.4, 0.6):
        def field(x: np.ndarray, kappa: float = kappa) -> np.ndarray:
            u = x[:, 0] + kappa * x[:, 1]
            r = np.sqrt(4 + u * u)
            return np.column_stack([-u / r, x[:, 0] / r])

        x = rng.uniform(-10, 10, (200, 2))
        previous = v_of_states(cert, x)
        for _ in range(300):
            x = rk4(field, x, 0.05)
            now = v_of_states(cert, x)
            assert np.all(now <= previous + 1e-9)
            previous = now


def test_a_changed_box_centre_or_sentence_does_not_verify(ilos_box) -> None:
    for change in ("wider", "centre", "prefix", "dropped"):
        doc = copy.deepcopy(ilos_box.document)
        if change == "wider":
            doc["box"] = {"kappa": ["1/10", "9/10"]}
        elif change == "centre":
            doc["overrides"] = {"kappa": "0.45"}
            doc["parameters"]["kappa"] = "9/20"
        elif change == "prefix":
            c = doc["conditions"]["sos_gas"]
            c["summary"] = c["summary"].removeprefix("for every kappa in [0.4, 0.6]: ")
        else:
            del doc["box"]
        assert not api.verify(doc).valid, change


def test_the_pendulum_region_holds_for_every_damping_of_the_box() -> None:
    result = api.certify(model=EXAMPLES / "recast-pendulum.toml", box=["b=0.5..2"], classes="sos_gas,roa")
    refuted = result.conditions["sos_gas"]
    assert refuted.status == "refuted"  # the saddle at theta = pi: at the box's centre, said so
    assert refuted.summary.startswith("at the box's centre (b = 1.25), so not for every value of the box: ")
    roa = result.conditions["roa"]
    assert roa.status == "certified" and roa.summary.startswith("for every b in [0.5, 2]: region of attraction")
    assert roa.certificate["parameter_box"] == {"b": ["1/2", "2"]}
    assert api.verify(result).valid
    # outside lyapcheck: starts in the set (within its box) converge at both ends of the box
    cert = roa.certificate
    level = float(Fraction(cert["level"]))
    lo = np.array([float(Fraction(a)) for a, _ in cert["box"].values()])
    hi = np.array([float(Fraction(b)) for _, b in cert["box"].values()])
    rng = np.random.default_rng(1)
    X = lo + (hi - lo) * rng.random((4000, 2))
    pendulum_converges(X[v_of_states(cert, X) <= level][:300], (0.5, 2.0), 2500)


def test_the_bound_under_disturbances_holds_for_every_gain_of_the_box() -> None:
    # (a safety-net time limit: the search's solves decide, about 20 s idle, and a loaded machine must not cut them)
    result = api.certify(model=EXAMPLES / "recast-ilos-course-disturbed.toml", box=["kappa=0.4..0.6"],
                         classes="sos_bound", time_limit_s=900)
    bound = result.conditions["sos_bound"]
    assert bound.status == "certified" and bound.certificate["parameter_box"] == {"kappa": ["2/5", "3/5"]}
    assert bound.summary.startswith("for every kappa in [0.4, 0.6]: for every disturbance within its bounds")
    assert api.verify(result).valid
    # a constant d = 0.05 at kappa = 0.4 settles at yi = d Delta / (kappa sqrt(U^2 - d^2)): inside the bound
    assert bound.numbers["bounds"]["yi"] >= 0.05 * 2 / (0.4 * math.sqrt(1 - 0.05 ** 2))


@pytest.mark.parametrize(("args", "fragment"), [
    (["--box", "q=0.1..0.2"], "--box q: no parameter named 'q'"),
    (["--box", "kappa=0.6..0.4"], "--box kappa: an empty range"),
    (["--box", "kappa=0.4..0.6", "--set", "kappa=0.5"], "--box kappa: also given with --set"),
])
def test_a_bad_box_is_one_line_exit_2(args: list[str], fragment: str) -> None:
    run = subprocess.run([sys.executable, "-m", "lyapcheck", "certify", "--model",
                          str(EXAMPLES / "recast-ilos-course.toml"), *args], capture_output=True, text=True)
    assert run.returncode == 2 and fragment in run.stderr and "\n" not in run.stderr.strip(), run.stderr


def test_a_box_that_moves_the_equilibrium_or_is_not_proved_not_to_is_refused(tmp_path: Path) -> None:
    path = tmp_path / "shifted.toml"
    path.write_text('[model]\nname = "shifted"\nstates = ["x", "v"]\n[parameters]\np = 0\n[dynamics]\nx = "v"\n'
                    'v = "-v - sin(x) + p"\n')
    run = subprocess.run([sys.executable, "-m", "lyapcheck", "certify", "--model", str(path), "--box", "p=-0.1..0.1"],
                         capture_output=True, text=True)
    assert run.returncode == 2 and "the equilibrium is not proved to stay put over the box" in run.stderr
    assert "\n" not in run.stderr.strip()


@pytest.mark.parametrize(("value", "text"), [(Fraction(5, 4), "1.25"), (Fraction(-1, 8), "-0.125"), (Fraction(3), "3"),
                                             (Fraction(41, 40), "1.025"), (Fraction(1, 1000), "0.001")])
def test_a_box_centre_is_written_as_an_exact_decimal(value: Fraction, text: str) -> None:
    from lyapcheck.exact import exact_decimal

    assert exact_decimal(value) == text and Fraction(text) == value
    with pytest.raises(ValueError):
        exact_decimal(Fraction(1, 3))


def test_a_box_parameter_inside_a_square_root_bounds_it_with_the_box() -> None:
    """sqrt(Delta^2 + e^2) >= 1 holds for Delta in [1.5, 2.5], not for every Delta: its proof uses the
    box's relation and says so (``constants``); without it the stored proof does not check."""
    result = api.certify(model=EXAMPLES / "recast-ilos-course.toml", box=["Delta=1.5..2.5"], classes="sos_gas")
    gas = result.conditions["sos_gas"]
    assert gas.status == "certified" and gas.summary.startswith("for every Delta in [1.5, 2.5]: ")
    roots = gas.certificate["recasting"]["roots"]
    assert roots["r1"]["constants"] is True and Fraction(roots["r1"]["bound"]) > 0
    assert api.verify(result).valid
    doc = copy.deepcopy(result.document)
    del doc["conditions"]["sos_gas"]["certificate"]["recasting"]["roots"]["r1"]["constants"]
    assert not api.verify(doc).valid


def test_a_gain_multiplying_the_whole_field_is_covered_with_the_square_root_square_free() -> None:
    """ILOS over its speed U in [0.5, 2]: V' is U times the nominal one, so one V serves every U > 0
    (the S-procedure with the box's multiplier is feasible exactly when U's lower end is > 0). With
    r^2 = q the bases' r^2 put a kernel into the remainder on the variety r^2 = q: square-free bases."""
    result = api.certify(model=EXAMPLES / "recast-ilos-course.toml", box=["U=0.5..2"], classes="quadratic")
    quad = result.conditions["quadratic"]
    assert quad.status == "certified" and quad.summary.startswith("for every U in [0.5, 2]: GAS: ")
    assert api.verify(result).valid


def test_a_wide_box_is_proved_on_its_halves_and_verify_splits_it_the_same_way() -> None:
    """b in [0.3, 3]: the local Hessian argument fails over the whole interval (the enclosure treats
    b's entries apart) and goes through on its halves; the claim is still one set for every b."""
    from lyapcheck.models.language.modelfile import load_any_model
    from lyapcheck.models.classes.recast_classes import base_loop
    from lyapcheck.models.classes.recast_interval import claim_of, prove
    from lyapcheck.models.classes.recast_regions import box_robust
    from lyapcheck.models.language.parameter_box import ModelBox

    result = api.certify(model=EXAMPLES / "recast-pendulum.toml", box=["b=0.3..3"], classes="roa")
    roa = result.conditions["roa"]
    assert roa.status == "certified" and roa.summary.startswith("for every b in [0.3, 3]: ")
    assert api.verify(result).valid
    model = load_any_model(EXAMPLES / "recast-pendulum.toml", {"b": "1.65"})
    box = ModelBox.from_json(result.document["box"])
    loop = base_loop(model.system)
    claim = claim_of(loop, roa.certificate)
    robust = box_robust(model, box)
    assert prove(loop, claim, robust=robust).ok
    # the same claim, without the halving: not proved over the whole interval at once
    from lyapcheck.models.classes import recast_interval
    whole = recast_interval._prove_parts(loop, claim, None, robust, 0)
    assert not whole.ok
    # outside lyapcheck: starts in the set converge at both ends of the box
    cert = roa.certificate
    level = float(Fraction(cert["level"]))
    rng = np.random.default_rng(2)
    X = rng.uniform(-4, 4, (6000, 2))
    pendulum_converges(X[v_of_states(cert, X) <= level][:200], (0.3, 3.0), 4000)
