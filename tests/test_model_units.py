"""Units in model files are converted exactly and, with ``[units]``, dimension-checked (issue 29, item 3).

Families (docs/model-files.md (its Units section)):

- **Exact conversion.** ``1/min`` is 1/60, ``mm`` 1/1000, the litre 1/1000 m^3, a furlong
  792000/3937 m: pint's decimal definitions read as fractions, never a double's neighbour.
- **Refusals without [units].** An unknown unit (``"3 furlongz"``), ``Hz`` (ambiguous: the message
  gives both readings), units defined through pi (``deg``, ``rpm``), the litre's ``l``, offset and
  non-integer units: one line, exit 2, naming the key and what to write. The paper's flags keep
  reading ``"2.8 Hz"`` as 2 pi 2.8 rad/s.
- **[units] and the term-by-term rule.** A consistent damped oscillator in m and s certifies
  (exit 0) and verifies; a mismatched term is exit 2 naming the equation, the term and both
  dimensions, through the command line and through the library; bare numbers, nested sums,
  outputs, equilibrium, domain and ``--set`` follow the documented rules.
- **The page.** Every TOML block of docs/model-files.md (its Units section) loads, or is refused with the text
  its ``# refused:`` line quotes.
"""

from __future__ import annotations

import json
import math
import re
from fractions import Fraction
from pathlib import Path
from typing import Any

import pytest
from click.testing import CliRunner, Result

from lyapcheck import units
from lyapcheck.cli import app
from lyapcheck.errors import InvalidParameter, ModelFileError
from lyapcheck.models.language.dimensions import DimensionError, Named, check_output
from lyapcheck.models.language.modelfile import load_model, parse_model
from lyapcheck.units import DIMENSIONLESS, Dimension, Kind, parse_quantity, parse_si_quantity, parse_si_with_dimension
from tests.conftest import ROOT

app._register_commands()
RUNNER = CliRunner()
EXAMPLE = ROOT / "examples" / "models" / "damped-oscillator-units.toml"
PAGE = ROOT / "docs" / "model-files.md"

LENGTH = Dimension.of({"[length]": 1})
TIME = Dimension.of({"[time]": 1})


def oscillator(k: object = '"2 1/s^2"', c: object = '"0.5 1/s"', v: str = "-k*x - c*v", units_table: str | None =
               'x = "m"\nv = "m/s"', extra: str = "") -> str:
    """A damped oscillator ``x' = v``, ``v' = ...``; ``units_table`` None leaves [units] out."""
    declared = "" if units_table is None else f"\n[units]\n{units_table}\n"
    return (f'[model]\nname = "oscillator"\nstates = ["x", "v"]\n{declared}\n[parameters]\nk = {k}\nc = {c}\n\n'
            f'[dynamics]\nx = "v"\nv = "{v}"\n{extra}')


def refused(text: str, key: str, *says: str, source: str = "model.toml", parse: Any = None) -> str:
    """The library refuses ``text`` at ``key`` in one line that says every one of ``says`` (read by
    ``parse``, default :func:`parse_model`; a loop with functions: ``parse_any_model``)."""
    with pytest.raises(ModelFileError) as raised:
        (parse or parse_model)(text, source)
    message = str(raised.value)
    assert raised.value.key == key, message
    assert "\n" not in message and message.startswith(f"{source}: {key}: "), message
    for needle in says:
        assert needle in message, f"{needle!r} not in {message!r}"
    return message


def run(args: list[str]) -> Result:
    return RUNNER.invoke(app.cli, args, catch_exceptions=True)


def cli_refused(path: Path, key: str, *says: str, extra: tuple[str, ...] = ()) -> str:
    """``certify --model`` exits 2 with one line on stderr naming the file and the key."""
    done = run(["certify", "--model", str(path), "--classes", "linearization", *extra])
    assert done.exit_code == 2, (done.exit_code, done.stdout[-300:], done.stderr)
    assert done.exception is None or isinstance(done.exception, SystemExit), repr(done.exception)
    assert "Traceback" not in done.stdout + done.stderr
    lines = done.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("lyapcheck: error: "), done.stderr
    assert f"{path}: {key}: " in lines[0], lines[0]
    for needle in says:
        assert needle in lines[0], f"{needle!r} not in {lines[0]!r}"
    return lines[0]


# -- exact conversion ------------------------------------------------------------------------------
@pytest.mark.parametrize(("text", "value", "dimension"), [
    ("0.5 1/min", Fraction(1, 120), TIME ** -1),
    ("1 1/min", Fraction(1, 60), TIME ** -1),
    ("1 mm", Fraction(1, 1000), LENGTH),
    ("0.75 mm", Fraction(3, 4000), LENGTH),
    ("0.088 mm/s", Fraction(11, 125000), LENGTH / TIME),
    ("10 cm", Fraction(1, 10), LENGTH),
    ("0.5 L/s", Fraction(1, 2000), LENGTH ** 3 / TIME),
    ("1 litre", Fraction(1, 1000), LENGTH ** 3),
    ("1 inch", Fraction(127, 5000), LENGTH),
    ("3 furlongs", 3 * 660 * Fraction(1200, 3937), LENGTH),  # pint's furlong: 660 US survey feet
    ("2 h", Fraction(7200), TIME),
    ("0.4 N*s/m", Fraction(2, 5), Dimension.of({"[mass]": 1, "[time]": -1})),
    ("2 1/s^2", Fraction(2), TIME ** -2),
    ("3.14159265358979 rad/s", Fraction("3.14159265358979"), TIME ** -1),
    ("5 percent", Fraction(1, 20), DIMENSIONLESS),
    ("1e-3", Fraction(1, 1000), DIMENSIONLESS),
])
def test_units_become_si_exactly(text: str, value: Fraction, dimension: Dimension) -> None:
    quantity = parse_si_with_dimension("a", text)
    assert quantity.value == value and isinstance(quantity.value, Fraction)
    assert quantity.dimension == dimension
    assert parse_si_quantity("a", text) == value


def test_one_per_minute_is_not_a_doubles_neighbour() -> None:
    """The old conversion took pint's float factor's shortest decimal: 0.016666666666666666."""
    assert parse_si_quantity("a", "1 1/min") != Fraction("0.016666666666666666")
    assert parse_si_quantity("a", "0.5 1/min") * 120 == 1


def test_the_memo_gives_back_the_exact_factor_and_dimension(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("LYAPCHECK_CACHE_DIR", str(tmp_path))
    units._remembered_factors.cache_clear()
    try:
        first = units.model_unit("a", "furlong/min", "1 furlong/min")
        stored = json.loads(next(tmp_path.glob("unit-factors-*.json")).read_text())
        assert stored["SI_EXACT|furlong/min"] == f"{first[0]}|{first[1].serialized()}"
        units._remembered_factors.cache_clear()  # a new run reads the file
        assert units.model_unit("a", "furlong/min", "1 furlong/min") == first
        with pytest.raises(InvalidParameter):
            units.model_unit("a", "Hz", "1 Hz")
        stored = json.loads(next(tmp_path.glob("unit-factors-*.json")).read_text())
        assert not any("Hz" in key for key in stored)  # refusals are never remembered
    finally:
        units._remembered_factors.cache_clear()


def test_a_model_files_parameters_are_exact() -> None:
    model = parse_model(oscillator(k='"1 1/min^2"', c='"0.5 1/min"'), "m.toml")
    assert model.parameters == {"k": Fraction(1, 3600), "c": Fraction(1, 120)}
    assert model.parameters_given == {"k": "1 1/min^2", "c": "0.5 1/min"}


# -- refusals without [units] ------------------------------------------------------------------------
NO_UNITS = None


@pytest.mark.parametrize(("value", "says"), [
    ('"3 furlongz"', ("'furlongz' is not one", "unit pint knows", "'3 furlongz'")),
    ('"2 bananas"', ("'bananas' is not one",)),
    ('"0.5 Hz"', ("not Hz", "'0.5 1/s' for cycles per second", "'3.14159265358979 rad/s' for the angular rate",
                  "irrational")),
    ('"2 kHz"', ("not Hz", "'2000 1/s'", "'12566.3706143592 rad/s'")),
    ('"45 deg"', ("not 'deg'", "defined through pi", "'0.785398163397448 rad'")),
    ('"60 rpm"', ("not 'rpm'", "defined through pi", "'6.28318530717959 rad/s'")),
    ('"1 cycle/s"', ("defined through pi", "'6.28318530717959 rad/s'")),
    ('"0.5 l/s"', ("symbol 'l'", "litre", "reads like the digit 1", "'1/s' for a rate", "'L' or 'litre'")),
    ('"20 degC"', ("offset or logarithmic",)),
    ('"1 m**0.5"', ("integer exponents",)),
    ('"1 m**13"', ("integer exponents of at most 12", "MAX_UNIT_EXPONENT")),
    ('"1 m**9**9**9"', ("integer exponents",)),
])
def test_bad_units_are_refused_naming_the_parameter(value: str, says: tuple[str, ...], tmp_path: Path) -> None:
    text = oscillator(c=value, units_table=NO_UNITS)
    refused(text, "[parameters] c", *says)
    path = tmp_path / "model.toml"
    path.write_text(text, encoding="utf-8")
    cli_refused(path, "[parameters] c", *says)


def test_hz_is_refused_everywhere_a_model_file_reads_a_quantity(tmp_path: Path) -> None:
    base = oscillator(units_table=NO_UNITS)
    refused(base + '\n[disturbances]\nd = "0.5 Hz"\n', "[disturbances] d", "not Hz")
    refused(base + '\n[domain]\nx = ["-1 Hz", "1 Hz"]\nv = [-1, 1]\n', "[domain] x", "not Hz")
    path = tmp_path / "model.toml"
    path.write_text(base, encoding="utf-8")
    cli_refused(path, "--set c", "not Hz", "'0.5 1/s'", extra=("--set", "c=0.5 Hz"))
    # what the message says to write is accepted, exactly
    for written, value in (("0.5 1/s", Fraction(1, 2)), ("3.14159265358979 rad/s", Fraction("3.14159265358979"))):
        assert load_model(path, {"c": written}).parameters["c"] == value


def test_the_papers_flags_keep_hz_as_an_angular_rate() -> None:
    """The paper's quantities are declared rotations: "2.8 Hz" is 2 pi 2.8 rad/s (2 pi as the double
    nearest to it), unchanged by the model-file rule."""
    value = parse_quantity("omega_so", "2.8 Hz", Kind.ROTATION)
    assert value == Fraction(14, 5) * Fraction(2 * math.pi)
    assert f"{float(value):.2f}" == "17.59"
    assert parse_quantity("omega_so", "17.6 rad/s", Kind.ROTATION) == Fraction("17.6")


def test_without_units_nothing_is_dimension_checked() -> None:
    """The lax reading the docs warn about: a length as a rate, a plain k, litres, furlongs."""
    model = parse_model(oscillator(k="2", c='"0.5 mm"', units_table=NO_UNITS), "m.toml")
    assert model.units == {} and model.parameters["c"] == Fraction(1, 2000)
    model = parse_model(oscillator(k='"3 furlongs"', c='"0.5 L/s"', units_table=NO_UNITS), "m.toml")
    assert model.parameters == {"k": Fraction(2376000, 3937), "c": Fraction(1, 2000)}


# -- [units]: a consistent model certifies ----------------------------------------------------------------
def test_a_consistent_model_in_m_and_s_certifies_and_verifies(tmp_path: Path) -> None:
    model = load_model(EXAMPLE)
    assert model.units == {"x": "m", "v": "m/s", "time": "s"}
    assert model.parameters == {"m": Fraction(1, 2), "k": Fraction(2), "c": Fraction(2, 5)}
    assert model.disturbances == {"f": Fraction(1, 10)}
    assert model.domain == {"x": (Fraction(-1, 10), Fraction(1, 10)), "v": (Fraction(-1, 2), Fraction(1, 2))}
    out = tmp_path / "cert.json"
    done = run(["certify", "--model", str(EXAMPLE), "--json", "--out", str(out)])
    assert done.exit_code == 0, done.stderr
    doc = json.loads(done.stdout)
    assert doc["verdict"] == "certified"
    conditions = doc["conditions"]
    assert conditions["linearization"]["status"] == "certified" and conditions["quadratic"]["status"] == "certified"
    # the exact worst case of limsup |x| is 0.1 N times the L1 norm of the impulse response: 0.16125 m
    assert conditions["sos_bound"]["status"] == "certified"
    assert conditions["sos_bound"]["bounds"]["x"] >= 0.1612
    verified = run(["verify", str(out)])
    assert verified.exit_code == 0, verified.stderr


@pytest.mark.parametrize(("k", "found"), [("2", "[length]"), ('"2 N"', "[length] ** 2 * [mass] / [time] ** 2")])
def test_the_example_with_a_wrong_spring_names_its_term(k: str, found: str) -> None:
    """What the example's comment and examples/models/README.md promise: the sum inside '(...)/m'
    must be a force, and '-k*x' is named."""
    text = EXAMPLE.read_text(encoding="utf-8").replace('k = "2 N/m"', f"k = {k}")
    refused(text, "[dynamics] v", f"the term '-k*x' has dimension {found}, expected [length] * [mass] / [time] ** 2, "
            "for '(-k*x - c*v + f)/m' to have [length] / [time] ** 2")


def test_the_papers_loop_is_dimensionally_consistent() -> None:
    """The paper's error dynamics (SI throughout) pass the check with eps and s in m: the ODS
    term U*delta*eps/((eps + sigma0*s)**2 + delta**2) included."""
    text = (ROOT / "examples" / "models" / "paper-error-dynamics.toml").read_text(encoding="utf-8")
    model = parse_model(text + '\n[units]\neps = "m"\ns = "m"\n', "paper.toml")
    assert model.units == {"eps": "m", "s": "m"}
    refused(text.replace('U = "1 m/s"', "U = 1") + '\n[units]\neps = "m"\ns = "m"\n', "[dynamics] s",
            "'U*delta*eps/((eps + sigma0*s)**2 + delta**2)'", "U = 1 is a plain number")


@pytest.mark.parametrize("v", ["-k*x - c*v", "-(k*x + c*v)", "-c*v - k*x + 0", "-k*x/(1 + x**2/L**2) - c*v",
                               "-k*(x - x0) - c*v", "-k*x*(x**2 + L**2)/(L**2 + x**2) - c*v",
                               "-(k*x + c*v)**3/(k*L + c*v + k*x)**2 - 0.5*c*v"])
def test_consistent_right_hand_sides_load(v: str) -> None:
    text = oscillator(v=v).replace("[dynamics]", 'L = "1 m"\nx0 = "0 m"\n\n[dynamics]')
    model = parse_model(text, "m.toml")
    assert model.units == {"x": "m", "v": "m/s"}


# -- [units]: mismatches ------------------------------------------------------------------------------------
def test_a_mismatched_term_names_the_equation_the_term_and_both_dimensions(tmp_path: Path) -> None:
    text = oscillator(k="2", v="-c*v - k*x")
    says = ("the term 'k*x' has dimension [length], expected [length] / [time] ** 2", "v'",
            "k = 2 is a plain number (dimensionless)", "x is in m")
    message = refused(text, "[dynamics] v", *says)
    assert message == ("model.toml: [dynamics] v: the term 'k*x' has dimension [length], expected [length] / "
                       "[time] ** 2, the dimension of v' (v in m/s, per s); k = 2 is a plain number "
                       "(dimensionless), x is in m")
    path = tmp_path / "mismatch.toml"
    path.write_text(text, encoding="utf-8")
    cli_refused(path, "[dynamics] v", *says)
    # verify, simulate and report read the model the same way: the same refusal
    done = run(["simulate", "--model", str(path)])
    assert done.exit_code == 2 and "the term 'k*x'" in done.stderr


@pytest.mark.parametrize(("c", "found"), [
    ('"0.5 mm"', "[length] ** 2 / [time]"),     # a length where a rate was meant
    ('"0.5 L/s"', "[length] ** 4 / [time] ** 2"),  # litres per second where 1/s was meant
    ('"3 furlongs"', "[length] ** 2 / [time]"),
    ("0.5", "[length] / [time]"),                # a plain number
])
def test_a_rate_with_the_wrong_unit_is_a_mismatch(c: str, found: str, tmp_path: Path) -> None:
    text = oscillator(c=c)
    says = (f"the term 'c*v' has dimension {found}, expected [length] / [time] ** 2",)
    refused(text, "[dynamics] v", *says)
    path = tmp_path / "model.toml"
    path.write_text(text, encoding="utf-8")
    cli_refused(path, "[dynamics] v", *says)


@pytest.mark.parametrize(("v", "says"), [
    # bare numbers: dimensionless, a mismatch in a sum unless 0
    ("-k*x - c*v + 1", ("the term '1' has dimension dimensionless, expected [length] / [time] ** 2",
                        "a number is dimensionless")),
    ("-k*(x + 1) - c*v", ("the term '1' has dimension dimensionless, expected [length], for '-k*(x + 1)' to have "
                          "[length] / [time] ** 2",)),
    # a sum in a denominator
    ("-k*x/(1 + x**2) - c*v", ("the term 'x**2' has dimension [length] ** 2, expected dimensionless",)),
    # a sum under a product whose co-factors fix it
    ("-(k*x + c*x)", ("the term 'c*x' has dimension [length] / [time], expected [length] / [time] ** 2",
                      "c = '0.5 1/s'")),
    # a power of a sum: each term is the root's dimension
    ("-k*x - c*v + (x + v)**2/x", ("the term 'x' has dimension [length], expected [length] / [time], for "
                                   "'(x + v)**2' to have",)),
    # a sum that agrees with itself under a co-factor of the wrong unit: the whole term is named
    ("-k*x*(x + x) - c*v", ("the term '-k*x*(x + x)' has dimension [length] ** 2 / [time] ** 2",)),
    # checked as written, though it cancels after expansion
    ("-k*x - c*v + x - x", ("the term 'x' has dimension [length]",)),
])
def test_the_term_by_term_rule(v: str, says: tuple[str, ...]) -> None:
    refused(oscillator(v=v), "[dynamics] v", *says)


def test_a_state_without_a_unit_is_dimensionless() -> None:
    # v not in [units]: dimensionless, so x' = v has dimension 1 where [length] / [time] is expected
    refused(oscillator(units_table='x = "m"'), "[dynamics] x",
            "the term 'v' has dimension dimensionless, expected [length] / [time]",
            "v is dimensionless (not in [units])")
    # an empty [units] switches the check on with every state dimensionless
    refused(oscillator(units_table=""), "[dynamics] x", "the term 'v' has dimension dimensionless, expected "
            "1 / [time], the dimension of x' (x dimensionless, per s)", "v is dimensionless (not in [units])")


def test_a_disturbance_takes_its_unit_from_its_bound() -> None:
    with_d = oscillator(v="-k*x - c*v + d", extra='\n[disturbances]\nd = "{bound}"\n')
    parse_model(with_d.format(bound="0.1 m/s^2"), "m.toml")
    refused(with_d.format(bound="0.1 N"), "[dynamics] v", "the term 'd' has dimension [length] * [mass] / [time] ** 2",
            "|d| <= '0.1 N'")
    refused(with_d.format(bound="0.1"), "[dynamics] v", "|d| <= 0.1 is a plain number (dimensionless)")


def test_outputs_are_checked_for_consistency_only() -> None:
    assert parse_model(oscillator(extra='\n[outputs]\ny = "x"\nw = "x*v/v"\n'), "m.toml").outputs
    refused(oscillator(extra='\n[outputs]\ny = "x + v"\n'), "[outputs] y",
            "the term 'v' has dimension [length] / [time], expected [length], that of 'x', the first term of 'x + v'")
    # the walker alone: an output's dimension, its sums agreeing with their first terms
    with pytest.raises(DimensionError, match="the term '1'"):
        check_output("y", "x + 1", {"x": _state(LENGTH)})
    assert check_output("y", "0 + x*x", {"x": _state(LENGTH)}) == LENGTH ** 2


def _state(dimension: Dimension) -> Named:
    return Named("state", dimension, "m", True)


def test_equilibrium_domain_and_set_must_have_the_declared_dimension(tmp_path: Path) -> None:
    domain = '\n[domain]\nx = ["-10 cm", "{hi}"]\nv = [-1, 1]\n'
    parse_model(oscillator(extra=domain.format(hi="10 cm")), "m.toml")
    refused(oscillator(extra=domain.format(hi="1 s")), "[domain] x", "'1 s' has dimension [time]",
            "the state x (in m) has [length]")
    refused(oscillator(v="-k*(x - x0) - c*v", extra='\n[equilibrium]\nx = "2 kg"\n').replace(
        "[dynamics]", 'x0 = "2 m"\n\n[dynamics]'), "[equilibrium] x", "'2 kg' has dimension [mass]")
    path = tmp_path / "model.toml"
    path.write_text(oscillator(), encoding="utf-8")
    assert load_model(path, {"k": "3"}).parameters["k"] == 3  # a plain --set is SI in the file's dimension
    assert load_model(path, {"k": "3 1/min^2"}).parameters["k"] == Fraction(3, 3600)
    cli_refused(path, "--set k", "'3 m' has dimension [length]", "k (given as '2 1/s^2' in the file) has "
                "1 / [time] ** 2", extra=("--set", "k=3 m"))


@pytest.mark.parametrize(("table", "key", "says"), [
    ('x = "mm"\nv = "m/s"', "[units] x", ("must be an SI unit, got 'mm' (1/1000 m)", "write 'm'")),
    ('x = "m"\nv = "km/h"', "[units] v", ("must be an SI unit, got 'km/h' (5/18 m/s)",)),
    ('x = "m"\nv = "m/s"\ntime = "min"', "[units] time", ("must be 's'", "'min'")),
    ('x = "m"\nv = "m/s"\ntime = "m"', "[units] time", ("must be 's'",)),
    ('x = "m"\nv = "m/s"\nk = "1/s^2"', "[units] k", ("no state named 'k'", "takes its unit from its value")),
    ('x = "m"\nv = "m/s"\ny = "m"', "[units] y", ("no state named 'y'",)),
    ('x = 1\nv = "m/s"', "[units] x", ("must be a unit in a string",)),
    ('x = "furlongz"\nv = "m/s"', "[units] x", ("'furlongz' is not one",)),
    ('x = "m"\nv = "Hz"', "[units] v", ("not Hz",)),
    ('x = "m"\nv = "l/s"', "[units] v", ("symbol 'l'",)),
])
def test_the_units_table_is_refused_where_it_is_wrong(table: str, key: str, says: tuple[str, ...]) -> None:
    refused(oscillator(units_table=table), key, *says)


def test_a_state_named_time() -> None:
    text = '[model]\nstates = ["time"]\n[units]\ntime = "s"\n[dynamics]\ntime = "-time"\n'
    refused(text, "[units] time", "ambiguous", "a state is named 'time'")
    assert parse_model(text.replace('[units]\ntime = "s"\n', ""), "m.toml").units == {}


def test_the_units_section_is_known_and_kept() -> None:
    model = parse_model(oscillator(units_table='x = "m"\nv = "m/s"\ntime = "s"'), "m.toml")
    assert model.units == {"x": "m", "v": "m/s", "time": "s"}
    # "1" and "" declare a dimensionless state: a rate parameter needs its 1/s
    scalar = '[model]\nstates = ["x"]\n[units]\nx = "{unit}"\n[parameters]\na = {a}\n[dynamics]\nx = "-a*x"\n'
    for unit in ("1", ""):
        assert parse_model(scalar.format(unit=unit, a='"2 1/s"'), "m.toml").units == {"x": unit}
        refused(scalar.format(unit=unit, a="2"), "[dynamics] x", "the term '-a*x' has dimension dimensionless, "
                "expected 1 / [time]", "a = 2 is a plain number")


# -- the dimension algebra ------------------------------------------------------------------------------------
def test_dimensions_print_as_pint_does_and_round_trip() -> None:
    accel = LENGTH / TIME ** 2
    assert str(accel) == "[length] / [time] ** 2" and str(TIME ** -1) == "1 / [time]"
    assert str(DIMENSIONLESS) == "dimensionless" and (LENGTH / LENGTH).is_dimensionless
    assert accel.si_unit() == "m/s^2" and Dimension.of({"[mass]": 1, "[length]": 1, "[time]": -2}).si_unit() == \
        "m*kg/s^2"
    assert Dimension.parse(accel.serialized()) == accel and Dimension.parse("") == DIMENSIONLESS
    assert str(LENGTH ** Fraction(1, 2)) == "[length] ** (1/2)"


# -- the page ---------------------------------------------------------------------------------------------------
def test_every_toml_block_of_the_page_loads_or_is_refused_as_it_says() -> None:
    blocks = re.findall(r"```toml\n(.*?)```", PAGE.read_text(encoding="utf-8"), flags=re.S)
    assert len(blocks) >= 4
    for block in blocks:
        said = re.search(r"^# refused: (.*)$", block, flags=re.M)
        if said is None:
            parse_model(block, "page.toml")
            continue
        with pytest.raises(ModelFileError) as raised:
            parse_model(block, "page.toml")
        assert said.group(1) in str(raised.value), (said.group(1), str(raised.value))


def test_the_shipped_example_is_listed() -> None:
    readme = (ROOT / "examples" / "models" / "README.md").read_text(encoding="utf-8")
    assert f"`{EXAMPLE.name}`" in readme


def test_a_set_value_keeps_the_dimension_the_file_gives_even_without_units(tmp_path: Path) -> None:
    """``k = "2 1/s^2"`` in the file: ``--set k="2 mm"`` is refused naming both, ``"3 1/s^2"`` and a
    plain number (read in SI) are taken."""
    text = oscillator(units_table=None)
    with pytest.raises(ModelFileError, match=r"--set k: must be a value of dimension 1 / \[time\] \*\* 2"):
        parse_model(text, "model.toml", {"k": "2 mm"})
    assert parse_model(text, "model.toml", {"k": "3 1/s^2"}).parameters["k"] == 3
    assert parse_model(text, "model.toml", {"k": "3"}).parameters["k"] == 3
