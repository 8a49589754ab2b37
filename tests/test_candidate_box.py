"""``certify --candidate "V" --box NAME=LO..HI`` on continuous-time loops (issues 41 and 42): the user's V, of
the states alone, proved for every value of the box at once.

A polynomial loop: GAS with the box's multipliers in the decrease identity, or the largest level of the level
program with them; a loop with functions: GAS on the recasting's relations with the box's parameters bounded,
else a level by ball arithmetic with the parameters as balls. Each claim is re-checked here independently of
lyapcheck's own arithmetic (the derivative of V written out by hand from the test's model strings, sampled at
values across the box), and ``verify`` is shown to refuse a document whose box was widened after the fact.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from click.testing import CliRunner

from lyapcheck.cli import app
from tests.conftest import ROOT

app._register_commands()

SPIRAL = """[model]
name = "a damped spiral with a cubic damping"
states = ["x1", "x2"]
[parameters]
a = 1
[dynamics]
x1 = "-a*x1 + x2"
x2 = "-x1 - a*x2 - x2**3"
[domain]
x1 = [-3, 3]
x2 = [-3, 3]
"""
#: V = x1^2 + x2^2 decreases for a > 0 only: at a = -0.2 V' = 0.4 x1^2 - 2 x2^2 > 0 along the x1 axis
TILTED = """[model]
name = "V decreases at a = 0.1, not at a = -0.2 (the loop is stable at both)"
states = ["x1", "x2"]
[parameters]
a = 0.1
[dynamics]
x1 = "-a*x1 + x2"
x2 = "-x1 - x2"
[domain]
x1 = [-3, 3]
x2 = [-3, 3]
"""
FUNCTIONS = """[model]
name = "two units coupled through a sine and a saturation"
states = ["x1", "x2"]
[parameters]
a = 1
[dynamics]
x1 = "-a*x1 + sin(x2)/2"
x2 = "-x2 + sat(x1, 1)/2"
[domain]
x1 = [-3, 3]
x2 = [-3, 3]
"""
PENDULUM = ROOT / "examples" / "models" / "recast-pendulum.toml"
VDP = ROOT / "examples" / "models" / "van-der-pol-reversed.toml"


def cli(*args: str) -> Any:
    done = CliRunner().invoke(app.cli, list(args))
    assert done.exception is None or isinstance(done.exception, SystemExit), done.output
    assert "Traceback" not in done.output
    return done


def certify(path: Path, box: str, candidate: str) -> tuple[int, dict[str, Any]]:
    done = cli("certify", str(path), "--box", box, "--candidate", candidate, "--classes", "candidate", "--no-store",
               "--json")
    assert done.exit_code in (0, 1), done.output
    return done.exit_code, json.loads(done.stdout)


def write(folder: Path, text: str, name: str = "loop.toml") -> Path:
    path = folder / name
    path.write_text(text)
    return path


def verify(doc: dict[str, Any], folder: Path, name: str = "c.json") -> Any:
    path = folder / name
    path.write_text(json.dumps(doc))
    return cli("verify", str(path))


def widened(doc: dict[str, Any], name: str, old: str, new: str, lo: str, hi: str, stamp: bool = True
            ) -> dict[str, Any]:
    """The document with its box widened to ``[lo, hi]`` (same centre, so the model is still read there), the
    claim's sentence saying so, and (``stamp``) the certificate's ``parameter_box`` too: a forger's edit."""
    forged = json.loads(json.dumps(doc))
    forged["box"][name] = [lo, hi]
    cond = forged["conditions"]["candidate"]
    cond["summary"] = cond["summary"].replace(old, new)
    if stamp:
        cond["certificate"]["parameter_box"][name] = [lo, hi]
    return forged


def sublevel_points(V: Any, level: float, half: tuple[float, float], count: int = 4000) -> np.ndarray:
    """Random points of the domain ``[-half, half]`` inside ``{V <= level}``."""
    rng = np.random.default_rng(3)
    X = rng.uniform(-1, 1, size=(count, 2)) * np.array(half)
    return X[V(X[:, 0], X[:, 1]) <= level]


def test_a_polynomial_loop_s_candidate_is_gas_for_every_value_of_the_box(tmp_path: Path) -> None:
    code, doc = certify(write(tmp_path, SPIRAL), "a=0.8..1.2", "x1**2 + x2**2")
    cond = doc["conditions"]["candidate"]
    assert code == 0 and cond["status"] == "certified" and cond["property"] == "GAS", cond
    assert cond["summary"].startswith("for every a in [0.8, 1.2]: GAS")
    cert = cond["certificate"]
    assert cert["parameter_box"] == {"a": ["4/5", "6/5"]} and cert["box_multipliers"]
    # V' = -2a (x1^2 + x2^2) - 2 x2^4 <= -2a V: the best rate for every a of the box is 2 * 0.8
    rate = cond["decay_rate_V_per_s"]
    assert 0 < rate <= 1.6 + 1e-12
    assert verify(doc, tmp_path).exit_code == 0
    # a box widened after the fact: the identities in the normalized parameter fail, or the box stated differs
    forged = widened(doc, "a", "[0.8, 1.2]", "[0.5, 1.5]", "1/2", "3/2")
    done = verify(forged, tmp_path, "forged.json")
    assert done.exit_code != 0 and "identity" in done.stdout, done.stdout
    done = verify(widened(doc, "a", "[0.8, 1.2]", "[0.5, 1.5]", "1/2", "3/2", stamp=False), tmp_path, "doc.json")
    assert done.exit_code != 0 and "parameter_box" in done.stdout, done.stdout


def test_a_candidate_that_decreases_at_the_centre_but_not_at_a_corner_is_not_certified(tmp_path: Path) -> None:
    path = write(tmp_path, TILTED)
    done = cli("certify", str(path), "--candidate", "x1**2 + x2**2", "--classes", "candidate", "--no-store", "--json")
    at_centre = json.loads(done.stdout)["conditions"]["candidate"]
    assert done.exit_code == 0 and at_centre["status"] == "certified" and at_centre["property"] == "GAS"
    # at the corner a = -0.2: V'(1, 0) = -2 a = 0.4 > 0, so no claim for the whole box can hold near 0
    a, x1, x2 = -0.2, 1.0, 0.0
    assert 2 * x1 * (-a * x1 + x2) + 2 * x2 * (-x1 - x2) > 0
    code, doc = certify(path, "a=-0.2..0.4", "x1**2 + x2**2")
    cond = doc["conditions"]["candidate"]
    assert code == 1 and cond["status"] == "not_certified", cond
    assert "for every value of the box" in cond["summary"] and "V' >= 0" in cond["summary"]
    assert verify(doc, tmp_path).exit_code == 0


def test_a_polynomial_loop_s_candidate_level_holds_for_every_value_of_the_box(tmp_path: Path) -> None:
    code, doc = certify(VDP, "mu=0.9..1.1", "1.5*x1**2 - x1*x2 + x2**2")
    cond = doc["conditions"]["candidate"]
    assert code == 0 and cond["status"] == "certified" and cond["property"] == "ROA", cond
    assert cond["summary"].startswith("for every mu in [0.9, 1.1]: the user's V")
    level = cond["level"]
    assert level > 0 and cond["certificate"]["parameter_box"] == {"mu": ["9/10", "11/10"]}

    def V(x1: np.ndarray, x2: np.ndarray) -> np.ndarray:
        return 1.5 * x1 ** 2 - x1 * x2 + x2 ** 2

    X = sublevel_points(V, level, (2.5, 3.5))
    assert len(X) > 100
    x1, x2 = X[:, 0], X[:, 1]
    for mu in (0.9, 1.0, 1.1):  # x1' = -x2, x2' = x1 - mu (1 - x1^2) x2 (the example's strings)
        dV = (3 * x1 - x2) * (-x2) + (2 * x2 - x1) * (x1 - mu * (1 - x1 ** 2) * x2)
        assert np.all(dV < 0), mu
    assert verify(doc, tmp_path).exit_code == 0
    forged = widened(doc, "mu", "[0.9, 1.1]", "[0.8, 1.2]", "4/5", "6/5")
    assert verify(forged, tmp_path, "forged.json").exit_code != 0


def test_a_loop_with_functions_candidate_is_gas_on_the_relations_for_every_value_of_the_box(tmp_path: Path) -> None:
    code, doc = certify(write(tmp_path, FUNCTIONS), "a=0.8..1.2", "x1**2 + x2**2")
    cond = doc["conditions"]["candidate"]
    assert code == 0 and cond["status"] == "certified" and cond["property"] == "GAS", cond
    assert cond["summary"].startswith("for every a in [0.8, 1.2]: globally asymptotically stable")
    cert = cond["certificate"]
    assert cert["kind"] == "recast" and cert["parameter_box"] == {"a": ["4/5", "6/5"]} and "a" in cert["variables"]
    # V' = 2 x1 (-a x1 + sin(x2)/2) + 2 x2 (-x2 + sat(x1)/2) < 0 away from 0, sampled at the box's ends
    rng = np.random.default_rng(5)
    X = rng.uniform(-5, 5, size=(20000, 2))
    x1, x2 = X[:, 0], X[:, 1]
    for a in (0.8, 1.2):
        dV = 2 * x1 * (-a * x1 + np.sin(x2) / 2) + 2 * x2 * (-x2 + np.clip(x1, -1, 1) / 2)
        assert np.all(dV < 0), a
    assert verify(doc, tmp_path).exit_code == 0
    forged = widened(doc, "a", "[0.8, 1.2]", "[0.5, 1.5]", "1/2", "3/2")
    done = verify(forged, tmp_path, "forged.json")
    assert done.exit_code != 0 and "identity" in done.stdout, done.stdout
    done = verify(widened(doc, "a", "[0.8, 1.2]", "[0.5, 1.5]", "1/2", "3/2", stamp=False), tmp_path, "doc.json")
    assert done.exit_code != 0 and "parameter_box" in done.stdout, done.stdout


def test_a_loop_with_functions_candidate_level_by_ball_arithmetic_for_every_value_of_the_box(tmp_path: Path
                                                                                            ) -> None:
    # the pendulum is not GAS (other wells): only a level of V can be proved, here over the damping's box
    code, doc = certify(PENDULUM, "b=0.8..1.2", "theta**2 + theta*omega + 2*omega**2")
    cond = doc["conditions"]["candidate"]
    assert code == 0 and cond["status"] == "certified" and cond["property"] == "ROA", cond
    cert = cond["certificate"]
    assert cert["kind"] == "interval" and cert["parameter_box"] == {"b": ["4/5", "6/5"]}
    assert cond["summary"].startswith("for every b in [0.8, 1.2]: ")
    level = cond["level"]

    def V(t: np.ndarray, w: np.ndarray) -> np.ndarray:
        return t ** 2 + t * w + 2 * w ** 2

    X = sublevel_points(V, level, (3.14159, 4.0))
    X = X[np.linalg.norm(X, axis=1) > 1e-3]
    assert len(X) > 100
    t, w = X[:, 0], X[:, 1]
    for b in (0.8, 1.0, 1.2):  # theta' = omega, omega' = -sin(theta) - b omega (the example's strings)
        dV = (2 * t + w) * w + (t + 4 * w) * (-np.sin(t) - b * w)
        assert np.all(dV < 0), b
    assert verify(doc, tmp_path).exit_code == 0
    forged = widened(doc, "b", "[0.8, 1.2]", "[0.5, 1.5]", "1/2", "3/2")
    assert verify(forged, tmp_path, "forged.json").exit_code != 0


@pytest.mark.parametrize("text", [SPIRAL, FUNCTIONS])
def test_a_candidate_naming_a_parameter_of_the_box_is_bad_input(tmp_path: Path, text: str) -> None:
    path = write(tmp_path, text)
    done = cli("certify", str(path), "--box", "a=0.8..1.2", "--candidate", "x1**2 + a*x2**2", "--no-store")
    assert done.exit_code == 2 and len(done.stderr.strip().splitlines()) == 1, done.output
    assert "--candidate" in done.stderr and "parameter a" in done.stderr


def test_a_disturbed_loop_with_functions_candidate_over_a_box_is_claimed_with_the_disturbance_at_0(tmp_path: Path
                                                                                                   ) -> None:
    # as at a point, a candidate's claim is the nominal loop's (d = 0); the document must say so and verify it
    text = PENDULUM.read_text().replace("[dynamics]", "[disturbances]\nd = 0.05\n\n[dynamics]")
    text = text.replace('omega = "-sin(theta) - b*omega"', 'omega = "-sin(theta) - b*omega + d"')
    assert "+ d" in text
    code, doc = certify(write(tmp_path, text), "b=0.8..1.2", "theta**2 + theta*omega + 2*omega**2")
    cond = doc["conditions"]["candidate"]
    assert code == 0 and cond["status"] == "certified" and cond["disturbances"] == "zero", cond
    assert "(d = 0)" in cond["summary"] and "disturbances" not in cond["certificate"]
    assert verify(doc, tmp_path).exit_code == 0
