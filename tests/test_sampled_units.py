"""Sampled-data loops with ``[units]`` (issue 44, item 2): the plant is dimension-checked as a continuous
loop's, each control taking the dimension the plant's right-hand sides need for it, and each ``[controller]``
law is checked against that dimension (every function's argument dimensionless); a mismatch is one line,
exit 2, naming the key."""

from __future__ import annotations

from pathlib import Path

import pytest
from click.testing import CliRunner

from tests.conftest import ROOT

PD = ROOT / "examples" / "models" / "pendulum-digital-pd.toml"
SAT = ROOT / "examples" / "models" / "pendulum-digital-sat-pd.toml"
UNITS = '[units]\ntheta = "rad"\nomega = "rad/s"\n\n[sampling]'

#: a mass on a spring pushed by a force held between samples: F must be in newtons
CART = """
[model]
states = ["x", "v"]
[parameters]
m = "2 kg"
k = "8 N/m"
kp = "KP"
kd = "3 N*s/m"
T = "50 ms"
[units]
x = "m"
v = "m/s"
[dynamics]
x = "v"
v = "-k/m*x + F/m"
[sampling]
period = "T"
[controller]
F = "LAW"
"""


def _invoke(*args: str) -> tuple[int, str]:
    from lyapcheck.cli import app

    app._register_commands()
    result = CliRunner().invoke(app.cli, list(args))
    return result.exit_code, result.output


def _with_units(tmp_path: Path, source: Path = PD, *edits: tuple[str, str]) -> Path:
    text = source.read_text()
    assert "[units]" not in text and "\n[sampling]" in text
    text = text.replace("\n[sampling]", "\n" + UNITS)
    for old, new in edits:
        assert old in text, old
        text = text.replace(old, new)
    path = tmp_path / "units.toml"
    path.write_text(text)
    return path


def _cart(tmp_path: Path, law: str = "-kp*x - kd*v", kp: str = "20 N/m") -> Path:
    path = tmp_path / "cart.toml"
    path.write_text(CART.replace("LAW", law).replace("KP", kp))
    return path


def _refused(path: Path) -> str:
    code, text = _invoke("certify", str(path), "--classes", "linearization")
    assert code == 2, text
    assert "Traceback" not in text and len(text.strip().splitlines()) == 1
    return text


@pytest.mark.parametrize("source", [PD, SAT])
def test_units_change_nothing_in_the_answer(tmp_path: Path, source: Path) -> None:
    from lyapcheck.api import certify, verify

    plain = certify(model=source, classes="linearization").document
    checked = certify(model=_with_units(tmp_path, source), classes="linearization").document
    assert checked["verdict"] == plain["verdict"] == "certified_local"
    assert checked["conditions"]["linearization"]["certificate"] == plain["conditions"]["linearization"]["certificate"]
    assert verify(checked).valid


def test_a_force_in_newtons_is_inferred_and_the_law_checked_against_it(tmp_path: Path) -> None:
    from lyapcheck.api import certify
    from lyapcheck.models.language.sampling import load_sampled

    assert certify(model=_cart(tmp_path), classes="linearization").document["verdict"] == "certified_local"
    assert load_sampled(_cart(tmp_path)).period == pytest.approx(0.05)
    # a gain in 1/s^2 gives an acceleration, not a force
    text = _refused(_cart(tmp_path, kp="20 1/s^2"))
    assert "[controller] F" in text and "the term '-kp*x'" in text and "[length] / [time] ** 2" in text
    assert "[length] * [mass] / [time] ** 2" in text and "kp = '20 1/s^2'" in text


@pytest.mark.parametrize("law, says", [
    ("-Kp*theta - Kd*theta", "the term 'Kd*theta' has dimension 1 / [time], expected 1 / [time] ** 2"),
    ("-Kp*theta - Kd*omega + c", "the term 'c' has dimension 1 / [time]"),
    ("-Kp*sin(L*theta)", "the argument of sin(L*theta) must be dimensionless, it has [length]"),
    ("-Kp*theta - g_over_l*tanh(c*omega)", "the argument of tanh(c*omega) must be dimensionless"),
    ("sat(-Kp*theta - Kd*omega, Kd)", "the term 'Kd' has dimension 1 / [time]"),  # the limit
])
def test_a_law_of_another_dimension_is_one_line_exit_2(tmp_path: Path, law: str, says: str) -> None:
    path = _with_units(tmp_path, PD, ('u = "-Kp*theta - Kd*omega"', f'u = "{law}"'),
                       ('T = "20 ms"', 'T = "20 ms"\nL = "0.5 m"'))
    text = _refused(path)
    assert "[controller] u" in text and says in text


def test_a_plant_that_needs_two_dimensions_for_a_control_is_named(tmp_path: Path) -> None:
    text = _refused(_with_units(tmp_path, PD, ('theta = "omega"', 'theta = "omega + u"')))
    assert "[dynamics] omega" in text and "the term 'u'" in text and "u is in 1/s" in text


def test_a_plant_mismatch_is_the_continuous_loops_message(tmp_path: Path) -> None:
    text = _refused(_with_units(tmp_path, PD, ('- c*omega + u"', '- c*theta + u"')))
    assert "[dynamics] omega: the term 'c*theta' has dimension 1 / [time]" in text


@pytest.mark.parametrize("edit, key, says", [
    (('[units]\n', '[units]\nu = "1/s^2"\n'), "[units] u", "is a control"),
    (('T = "20 ms"', 'T = "20 m"'), "[sampling] period", "dimension [length]"),
    (('omega = "rad/s"', 'omega = "mm/s"'), "[units] omega", "must be an SI unit"),
])
def test_bad_units_input_is_one_line_naming_the_field(tmp_path: Path, edit: tuple[str, str], key: str,
                                                      says: str) -> None:
    text = _refused(_with_units(tmp_path, PD, edit))
    assert key in text and says in text


def test_units_with_a_network_are_refused(tmp_path: Path) -> None:
    import shutil

    models, networks = tmp_path / "models", tmp_path / "networks"
    models.mkdir()
    networks.mkdir()
    policy = ROOT / "examples" / "networks" / "pendulum_tanh_policy.npz"
    shutil.copy(policy, networks / policy.name)
    example = (ROOT / "examples" / "models" / "pendulum-digital-tanh-policy.toml").read_text()
    path = models / "policy.toml"
    path.write_text(example.replace("\n[sampling]", "\n" + UNITS))
    text = _refused(path)
    assert "[units]" in text and "[networks]" in text


@pytest.mark.parametrize("rhs, dimension", [
    ("-k/m*x + F/m", {"[length]": 1, "[mass]": 1, "[time]": -2}),
    ("-k/m*x + F**2/(m*k*x)", {"[length]": 1, "[mass]": 1, "[time]": -2}),  # solved through a power
    ("-k/m*x + k/m*x*tanh(F)", {}),  # an argument of tanh: dimensionless
])
def test_the_controls_dimension_is_solved_from_the_plant(rhs: str, dimension: dict[str, int]) -> None:
    from lyapcheck.models.language import dimensions as dims
    from lyapcheck.units import Dimension, parse_si_with_dimension

    units = dims.read_units({"x": "m", "v": "m/s"}, ["x", "v"])
    given = {"m": "2 kg", "k": "8 N/m"}
    names = dims.named_table(units, {k: ("parameter", parse_si_with_dimension(k, v)) for k, v in given.items()}, given)
    inferred = dims.infer_controls({"x": "v", "v": rhs}, units, names, ["F"])
    assert inferred == {"F": Dimension.of(dimension)}
    # and the plant checks with F in it
    with_f = dims.UnitTable({**units.states, "F": (inferred["F"].si_unit(), inferred["F"])}, units.time)
    named = {**names, "F": dims.Named("state", inferred["F"], inferred["F"].si_unit() or "1", True)}
    dims.check_dynamics("v", rhs, with_f, named)
