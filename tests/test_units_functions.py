"""``[units]`` on a loop with functions (issue 41): the term-by-term dimension check takes functions.

Families (docs/model-files.md, "Units", "Functions"):

- **The same loop.** A pendulum with ``[units]`` (theta in rad or dimensionless, omega in 1/s,
  g in m/s^2, L in m) is read as the same recast loop as without ``[units]``, its parameters in SI
  exactly, and certifies as it does without them; its certificate verifies.
- **The rules.** ``sin cos exp tanh atan`` take a dimensionless argument; ``sqrt`` halves a
  dimension (an area gives a length) and refuses an odd power; ``abs`` keeps one; ``min``, ``max``,
  ``sat`` need two arguments of one dimension; ``pi`` is dimensionless. A refusal is exit 2, one
  line naming the file, the key, the term and the dimension, through the command line and the library.
- **The language first.** A text outside the expression language gets the parser's message, as
  without ``[units]``.
- **The page.** Each row of the "Functions" table of verdicts holds.
"""

from __future__ import annotations

import json
import re
from fractions import Fraction
from pathlib import Path

import pytest

from lyapcheck.models.language.dimensions import Named, check_output
from lyapcheck.models.language.modelfile import parse_any_model
from lyapcheck.models.language.recast import RecastModel
from lyapcheck.units import Dimension
from tests.conftest import ROOT
from tests.test_model_units import refused as refused_by
from tests.test_model_units import run

PAGE = ROOT / "docs" / "model-files.md"

LENGTH = Dimension.of({"[length]": 1})
PENDULUM_RHS = "-(g/L)*sin(theta) - b*omega"


def pendulum(omega: str = PENDULUM_RHS, units_table: str | None = 'theta = "rad"\nomega = "1/s"',
             extra: str = "") -> str:
    """A damped pendulum ``theta' = omega``, ``omega' = ...``; ``units_table`` None leaves [units] out."""
    declared = "" if units_table is None else f"\n[units]\n{units_table}\n"
    return (f'[model]\nname = "pendulum"\nstates = ["theta", "omega"]\n{declared}\n[parameters]\n'
            f'g = "9.81 m/s^2"\nL = "0.5 m"\nb = "0.5 1/s"\n\n[dynamics]\ntheta = "omega"\nomega = "{omega}"\n{extra}')


def refused(text: str, key: str, *says: str, source: str = "model.toml") -> str:
    """The library refuses ``text`` at ``key`` in one line that says every one of ``says``."""
    return refused_by(text, key, *says, source=source, parse=parse_any_model)


def write(tmp_path: Path, name: str, text: str) -> Path:
    path = tmp_path / name
    path.write_text(text, encoding="utf-8")
    return path


# -- the same loop --------------------------------------------------------------------------------------------
@pytest.mark.parametrize("units_table", ['theta = "rad"\nomega = "1/s"', 'omega = "1/s"', 'theta = "1"\nomega = "1/s"'])
def test_the_pendulum_with_units_is_the_loop_without_them(units_table: str) -> None:
    with_units = parse_any_model(pendulum(units_table=units_table), "with.toml")
    without = parse_any_model(pendulum(units_table=None), "without.toml")
    assert isinstance(with_units, RecastModel) and isinstance(without, RecastModel)
    assert with_units.system.to_json() == without.system.to_json()
    # parameters with units reach the recast loop in SI, exactly
    assert with_units.parameters == without.parameters == {"g": Fraction(981, 100), "L": Fraction(1, 2),
                                                          "b": Fraction(1, 2)}
    assert with_units.units == {k.strip(): v.strip().strip('"') for k, v in
                                (line.split("=") for line in units_table.splitlines())}
    assert without.units == {}


def test_the_pendulum_certifies_as_without_units(tmp_path: Path) -> None:
    outcomes = []
    for name, table in (("with.toml", 'theta = "rad"\nomega = "1/s"'), ("without.toml", None)):
        path = write(tmp_path, name, pendulum(units_table=table))
        done = run(["certify", "--model", str(path), "--classes", "linearization,quadratic", "--json"])
        assert done.exit_code == 0, (done.exit_code, done.stderr)
        result = json.loads(done.stdout)
        outcomes.append((result["verdict"], {k: (v["status"], v.get("certificate"), v.get("summary"))
                                             for k, v in result["conditions"].items()}))
    assert outcomes[0] == outcomes[1]
    verdict, conditions = outcomes[0]
    assert conditions["linearization"][0] == "certified" and verdict == "certified_local"
    # -g/L with g = 9.81 m/s^2 and L = 0.5 m, in SI exactly
    assert conditions["linearization"][1]["jacobian"][1][0] == "-981/50"


def test_the_pendulums_region_of_attraction_certifies_and_verifies_with_units(tmp_path: Path) -> None:
    path = write(tmp_path, "pendulum.toml", pendulum(extra="\n[domain]\ntheta = [-1, 1]\nomega = [-1, 1]\n"))
    out = tmp_path / "roa.json"
    done = run(["certify", "--model", str(path), "--classes", "roa", "--out", str(out)])
    assert done.exit_code == 0, (done.exit_code, done.stderr)
    certificate = json.loads(out.read_text(encoding="utf-8"))
    roa = certificate["conditions"]["roa"]
    assert roa["status"] == "certified"
    checked = run(["verify", str(out)])
    assert checked.exit_code == 0, (checked.exit_code, checked.stdout[-500:], checked.stderr)
    # the proved box is printed in the states' units, and verify holds the units to the model's
    assert roa["certificate"]["kind"] == "interval" and roa["certificate"]["units"] == {"theta": "rad", "omega": "1/s"}
    assert re.search(r"theta - eq in \[-[0-9.]+, [0-9.]+\] rad, omega - eq in \[-[0-9.]+, [0-9.]+\] 1/s", roa["summary"])
    roa["certificate"]["units"]["theta"] = "deg"
    out.write_text(json.dumps(certificate), encoding="utf-8")
    tampered = run(["verify", str(out)])
    assert tampered.exit_code == 1 and "the units its box is printed in" in tampered.stdout, tampered.stdout[-500:]


ILOS_WITH_UNITS = """[model]
name = "ILOS cross-track error with units"
states = ["y", "yi"]

[units]
y = "m"
yi = "m"
time = "s"

[parameters]
U = "1 m/s"
Delta = "2 m"
kappa = 0.5

[disturbances]
d = "0.05 m/s"

[dynamics]
y = "-U*(y + kappa*yi)/sqrt(Delta**2 + (y + kappa*yi)**2) + d"
yi = "U*y/sqrt(Delta**2 + (y + kappa*yi)**2)"
"""


def test_a_bound_of_a_loop_with_functions_carries_its_unit(tmp_path: Path) -> None:
    """sos_bound on a loop with functions prints each bound in its output's unit (``bounds_unit``, as a
    polynomial loop's), and verify re-makes the units from the model text."""
    path = write(tmp_path, "ilos.toml", ILOS_WITH_UNITS)
    out = tmp_path / "bound.json"
    done = run(["certify", "--model", str(path), "--classes", "sos_bound", "--out", str(out)])
    assert done.exit_code == 0, (done.exit_code, done.stderr)
    certificate = json.loads(out.read_text(encoding="utf-8"))
    bound = certificate["conditions"]["sos_bound"]
    assert bound["status"] == "certified" and bound["bounds_unit"] == {"y": "m", "yi": "m"}
    assert re.search(r"limsup \|y\| <= [0-9.]+ m, limsup \|yi\| <= [0-9.]+ m", bound["summary"]), bound["summary"]
    assert run(["verify", str(out)]).exit_code == 0
    for edit in ({"y": "mm", "yi": "m"}, None):
        if edit is None:
            del bound["bounds_unit"]
        else:
            bound["bounds_unit"] = edit
        out.write_text(json.dumps(certificate), encoding="utf-8")
        tampered = run(["verify", str(out)])
        assert tampered.exit_code == 1 and "bounds_unit" in tampered.stdout, tampered.stdout[-500:]


# -- the rules ------------------------------------------------------------------------------------------------
def test_sin_of_a_length_is_exit_2_naming_the_term(tmp_path: Path) -> None:
    path = write(tmp_path, "pendulum.toml", pendulum("-(g/L)*sin(L*theta) - b*omega"))
    done = run(["certify", "--model", str(path), "--classes", "linearization"])
    assert done.exit_code == 2, (done.exit_code, done.stdout[-300:], done.stderr)
    assert "Traceback" not in done.stdout + done.stderr
    lines = done.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("lyapcheck: error: "), done.stderr
    assert (f"{path}: [dynamics] omega: the argument of sin(L*theta) must be dimensionless, it has [length]"
            in lines[0]), lines[0]
    assert "L = '0.5 m'" in lines[0]


@pytest.mark.parametrize(("omega", "says"), [
    ("-(g/L)*sin(theta + L) - b*omega", ("the term 'L' has dimension [length], expected dimensionless, for the "
                                         "argument of 'sin(theta + L)' to be dimensionless",)),
    ("-(g/L)*cos(omega) - b*omega", ("the argument of cos(omega) must be dimensionless, it has 1 / [time]",
                                     "omega is in 1/s")),
    ("-(g/L)*exp(L) - b*omega", ("the argument of exp(L) must be dimensionless, it has [length]",)),
    ("-(g/L)*tanh(g*theta) - b*omega", ("the argument of tanh(g*theta) must be dimensionless, it has [length] / "
                                        "[time] ** 2",)),
    ("-(g/L)*atan(b) - b*omega", ("the argument of atan(b) must be dimensionless, it has 1 / [time]",)),
    # the value of sin is dimensionless: without g/L the term is not an acceleration
    ("-sin(theta) - b*omega", ("the term 'sin(theta)' has dimension dimensionless, expected 1 / [time] ** 2",)),
    ("-(g/L)*sin(theta) - b*omega*sqrt(L)", ("the argument of sqrt(L) has dimension [length], which has no square "
                                             "root: the power of [length] is odd (1)",)),
    ("-(g/L)*sin(theta) - abs(b*theta)", ("the term 'b*theta' has dimension 1 / [time], expected 1 / [time] ** 2",)),
    ("-(g/L)*sat(theta, L) - b*omega", ("the term 'L' has dimension [length], expected dimensionless, that of "
                                        "'theta', the first argument of 'sat(theta, L)'", "L = '0.5 m'")),
    ("-(g/L)*sin(theta) - b*min(omega, theta)", ("the term 'theta' has dimension dimensionless, expected 1 / [time], "
                                                 "that of 'omega', the first argument of 'min(omega, theta)'",)),
    ("-(g/L)*sin(theta) - max(b*omega, omega)", ("the term 'omega' has dimension 1 / [time], expected 1 / [time] ** 2",
                                                 )),
    ("-(g/L)*sin(theta) - b*omega + pi", ("the term 'pi' has dimension dimensionless, expected 1 / [time] ** 2",)),
])
def test_each_function_has_its_rule(omega: str, says: tuple[str, ...]) -> None:
    refused(pendulum(omega), "[dynamics] omega", *says)


@pytest.mark.parametrize("omega", [
    "-(g/L)*sin(theta + pi) - b*omega",  # pi is dimensionless: an angle
    "-(g/L)*sin(theta) - b*abs(omega)",
    "-(g/L)*sin(theta) - b*max(omega, 0)",  # the literal 0 fits any dimension
    "-(g/L)*sin(theta) - b*sat(omega, b)",
    "-(g/L)*atan(sin(theta)) - b*omega",
    "-(g/L)*sin(theta) - b*omega*exp(theta**2)",
])
def test_consistent_functions_load(omega: str) -> None:
    assert isinstance(parse_any_model(pendulum(omega), "model.toml"), RecastModel)


def area_model(area: str) -> str:
    return (f'[model]\nstates = ["x"]\n\n[units]\nx = "m"\n\n[parameters]\nk = "1 1/s"\nA = "{area}"\n\n'
            '[equilibrium]\nx = "2 m"\n\n[dynamics]\nx = "-k*(x - sqrt(A))"\n')


def test_sqrt_of_an_area_is_a_length() -> None:
    model = parse_any_model(area_model("4 m^2"), "area.toml")
    assert isinstance(model, RecastModel) and model.parameters["A"] == 4
    area = Named("parameter", LENGTH ** 2, "4 m^2", True)
    assert check_output("y", "sqrt(A)", {"A": area}) == LENGTH
    assert check_output("y", "sqrt(A*A)", {"A": area}) == LENGTH ** 2
    assert check_output("y", "sqrt(sqrt(A*A))", {"A": area}) == LENGTH
    assert check_output("y", "sin(pi/2)*sqrt(A)", {"A": area}) == LENGTH
    # a fourth power has a square root, but it is an area, not the length x - sqrt(A) needs
    refused(area_model("16 m^4"), "[dynamics] x", "the term 'sqrt(A)' has dimension [length] ** 2, expected "
                                                  "[length]", "A = '16 m^4'")
    refused(area_model("8 m^3"), "[dynamics] x", "the argument of sqrt(A) has dimension [length] ** 3, which has no "
                                                 "square root: the power of [length] is odd (3)")
    refused(area_model("4"), "[dynamics] x", "the term 'sqrt(A)' has dimension dimensionless, expected [length]",
            "A = 4 is a plain number (dimensionless)")


def cart(limit: str) -> str:
    return ('[model]\nstates = ["x", "v"]\n\n[units]\nx = "m"\nv = "m/s"\n\n[parameters]\nk = "2 1/s^2"\n'
            f'c = "1 1/s"\numax = "{limit}"\n\n[dynamics]\nx = "v"\nv = "-k*sat(x, umax) - c*v"\n')


def test_sat_with_mismatched_dimensions_is_exit_2(tmp_path: Path) -> None:
    assert isinstance(parse_any_model(cart("0.5 m"), "cart.toml"), RecastModel)
    path = write(tmp_path, "cart.toml", cart("0.5 m/s"))
    done = run(["certify", "--model", str(path), "--classes", "linearization"])
    assert done.exit_code == 2, (done.exit_code, done.stdout[-300:], done.stderr)
    lines = done.stderr.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in done.stdout + done.stderr, done.stderr
    assert (f"{path}: [dynamics] v: the term 'umax' has dimension [length] / [time], expected [length], that of "
            "'x', the first argument of 'sat(x, umax)'; umax = '0.5 m/s'") in lines[0], lines[0]


def test_the_rest_of_units_holds_on_a_loop_with_functions(tmp_path: Path) -> None:
    """--set, [equilibrium] and [outputs] are checked as on a polynomial loop."""
    path = write(tmp_path, "pendulum.toml", pendulum())
    done = run(["certify", "--model", str(path), "--classes", "linearization", "--set", "L=2 s"])
    assert done.exit_code == 2 and f"{path}: --set L: '2 s' has dimension [time]" in done.stderr, done.stderr
    refused(pendulum(extra='\n[equilibrium]\ntheta = "1 m"\n'), "[equilibrium] theta", "'1 m' has dimension [length]")
    refused(pendulum(extra='\n[outputs]\ny = "theta + omega"\n'), "[outputs] y", "the term 'omega'")
    assert parse_any_model(pendulum(), "p.toml", {"L": "25 cm"}).parameters["L"] == Fraction(1, 4)


# -- the language first ---------------------------------------------------------------------------------------
@pytest.mark.parametrize(("omega", "says"), [
    ("-(g/L)*sin(thta) - b*omega", "unknown name 'thta'"),
    ("-(g/L)*sin(theta)^2 - b*omega", "'^' in"),
    ("-(g/L)*foo(L*theta) - b*omega", "unknown function 'foo'"),
    ("-(g/L)*sin(L*theta, 2) - b*omega", "sin"),
    ("-(g/L)*math.sin(L*theta) - b*omega", "attribute access"),
])
def test_a_text_outside_the_language_gets_the_parsers_message(omega: str, says: str) -> None:
    with_units = refused(pendulum(omega), "[dynamics] omega", says)
    without = refused(pendulum(omega, units_table=None), "[dynamics] omega", says)
    assert with_units == without
    assert "dimension" not in with_units


# -- the page -------------------------------------------------------------------------------------------------
def test_the_pages_table_of_functions_holds() -> None:
    text = PAGE.read_text(encoding="utf-8")
    section = text[text.index("### Functions"):]
    section = section[:section.index("\n### ", 1)]
    rows = re.findall(r"^\| `([^`|]+)` \| (accepted|refused)(?:, [^|]*|: `([^`]+)`) \|$", section, flags=re.M)
    assert len(rows) >= 5 and {verdict for _, verdict, _ in rows} == {"accepted", "refused"}
    for omega, verdict, says in rows:
        if verdict == "accepted":
            assert isinstance(parse_any_model(pendulum(omega), "page.toml"), RecastModel)
        else:
            refused(pendulum(omega), "[dynamics] omega", says)
