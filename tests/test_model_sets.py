"""``[sets]`` in model files (issue 32 item 1): initial, unsafe and goal sets of states.

The issue's example parses into the exact polynomials ``p >= 0``; a chain ``a <= x <= b`` is two
inequalities; strict inequalities are read closed; every bad value is one line naming ``[sets]
KEY`` (through the library and the command line, exit 2, no traceback); ``contains`` and
``margin`` on sample points; parameters are substituted, and re-substituted by
``with_parameters`` and ``--set``; with ``[units]`` the two sides of a comparison share a
dimension. An initial set that meets the unsafe set is valid input.
"""

from __future__ import annotations

from fractions import Fraction
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner

from lyapcheck.cli import app
from lyapcheck.errors import ModelFileError
from lyapcheck.models.language import sets as S
from lyapcheck.models.language.modelfile import parse_model, with_parameters

app._register_commands()
RUNNER = CliRunner()

HEAD = """\
[model]
states = ["x", "y"]

[parameters]
r = 0.5

[disturbances]
d = 0.1

[dynamics]
x = "-x + y + d"
y = "-x - y"
"""

EXAMPLE = HEAD + """
[sets]
initial = ["(x - 1.5)**2 + y**2 <= 0.25"]
unsafe = [["(x + 1)**2 + (y + 1)**2 <= 0.16"], ["0.4 <= x", "x <= 0.6", "0.1 <= y", "y <= 0.5"]]
"""


def with_sets(body: str) -> str:
    return HEAD + "\n[sets]\n" + body + "\n"


def poly(model_text: str, text: str):  # type: ignore[no-untyped-def]
    """``text`` as a polynomial of the model's state ring."""
    from lyapcheck.models.language.expressions import parse_expression

    model = parse_model(model_text, "m.toml")
    e = parse_expression(text, model.state_ring)
    assert e.is_polynomial()
    return e.numerator


def test_the_issues_example_parses_exactly() -> None:
    model = parse_model(EXAMPLE, "m.toml")
    assert set(model.sets) == {"initial", "unsafe"}
    p = lambda t: poly(EXAMPLE, t)  # noqa: E731
    assert model.sets["initial"] == ((p("1/4 - (x - 3/2)**2 - y**2"),),)
    assert model.sets["unsafe"] == ((p("4/25 - (x + 1)**2 - (y + 1)**2"),),
                                    (p("x - 2/5"), p("3/5 - x"), p("y - 1/10"), p("1/2 - y")))
    assert model.set_text["unsafe"] == (("(x + 1)**2 + (y + 1)**2 <= 0.16",),
                                        ("0.4 <= x", "x <= 0.6", "0.1 <= y", "y <= 0.5"))
    assert S.sets_json(model) == {"initial": [["(x - 1.5)**2 + y**2 <= 0.25"]],
                                  "unsafe": [["(x + 1)**2 + (y + 1)**2 <= 0.16"],
                                             ["0.4 <= x", "x <= 0.6", "0.1 <= y", "y <= 0.5"]]}
    # polynomials of the state ring (states, then the disturbance at exponent 0)
    ring = model.state_ring
    assert all(ring.support(q) and all(m[2] == 0 for m in ring.support(q))
               for pieces in model.sets.values() for piece in pieces for q in piece)
    assert parse_model(HEAD, "m.toml").sets == {}


def test_a_chain_is_two_inequalities_and_strict_is_closed() -> None:
    model = parse_model(with_sets('goal = ["-0.5 <= x <= 0.5", "y > -1", "1 >= y"]'), "m.toml")
    text = with_sets('goal = ["x >= -0.5", "x <= 0.5", "y >= -1", "y <= 1"]')
    assert model.sets["goal"] == parse_model(text, "m.toml").sets["goal"]
    p = lambda t: poly(text, t)  # noqa: E731
    assert model.sets["goal"] == ((p("x + 1/2"), p("1/2 - x"), p("y + 1"), p("1 - y")),)
    assert model.set_text["goal"] == (("-0.5 <= x <= 0.5", "y > -1", "1 >= y"),)
    assert S.split_inequality("0 <= (x + 1)*y <= r") == (("0", "<=", "(x + 1)*y"), ("(x + 1)*y", "<=", "r"))


def test_parameters_are_substituted_and_re_substituted() -> None:
    text = with_sets('initial = ["x**2 + y**2 <= r**2"]')
    model = parse_model(text, "m.toml")
    p = lambda t: poly(text, t)  # noqa: E731
    assert model.sets["initial"] == ((p("1/4 - x**2 - y**2"),),)
    other = with_parameters(model, {"r": Fraction(2)})
    assert other.sets["initial"] == ((p("4 - x**2 - y**2"),),)
    assert model.sets["initial"] == ((p("1/4 - x**2 - y**2"),),)  # the original is unchanged
    assert parse_model(text, "m.toml", {"r": "3"}).sets["initial"] == ((p("9 - x**2 - y**2"),),)
    assert S.evaluate_sets(model, {"r": Fraction(1)}) == {"initial": ((p("1 - x**2 - y**2"),),)}


def test_contains_and_margin() -> None:
    model = parse_model(EXAMPLE, "m.toml")
    initial, unsafe = model.sets["initial"], model.sets["unsafe"]
    assert S.contains(initial, [1.5, 0.0]) and S.contains(initial, [1.5, 0.5])  # the centre, the boundary
    assert not S.contains(initial, [0.0, 0.0])
    assert S.contains(unsafe, [-1.0, -1.0]) and S.contains(unsafe, [0.5, 0.3]) and not S.contains(unsafe, [0.5, 0.6])
    got = S.margin(unsafe, np.array([[-1.0, -1.0], [0.5, 0.3], [0.5, 0.6], [0.0, 0.0]]))
    # disc: 0.16 - |x + (1, 1)|^2; box: the smallest of the four slacks
    assert np.allclose(got, [0.16, 0.1, -0.1, max(0.16 - 2.0, min(-0.4, 0.6, -0.1, 0.5))])
    assert S.margin(initial, np.array([1.5, 0.0])).shape == (1,)
    assert S.margin((), np.zeros((2, 2))).tolist() == [-np.inf, -np.inf]


def test_an_initial_set_meeting_the_unsafe_set_is_valid_input(tmp_path: Path) -> None:
    text = with_sets('initial = ["x**2 + y**2 <= 1"]\nunsafe = ["x**2 + y**2 <= 4"]\ngoal = ["x**2 <= 1"]')
    model = parse_model(text, "m.toml")
    assert S.contains(model.sets["initial"], [0, 0]) and S.contains(model.sets["unsafe"], [0, 0])
    path = tmp_path / "m.toml"
    path.write_text(text)
    done = RUNNER.invoke(app.cli, ["certify", str(path), "--classes", "linearization"])
    assert done.exit_code == 0, done.output


def test_a_class_without_its_sets_is_refused_in_one_line() -> None:
    model = parse_model(with_sets('initial = ["x <= 1"]'), "m.toml")
    with pytest.raises(ModelFileError) as raised:
        S.require_sets(model, "barrier")
    assert str(raised.value) == ("m.toml: [sets]: the class barrier needs the sets initial and unsafe; unsafe is "
                                 "missing (the file gives: initial)")
    with pytest.raises(ModelFileError, match="initial, unsafe and goal; initial, unsafe and goal are missing"):
        S.require_sets(parse_model(HEAD, "m.toml"), "reach_avoid")
    S.require_sets(parse_model(EXAMPLE, "m.toml"), "barrier")


#: (the [sets] lines, the key the message names, what it says)
BAD = {
    "unknown name": ('initial = ["x + z <= 1"]', "[sets] initial", ("in 'x + z <= 1'", "unknown name 'z'")),
    "incomplete chain": ('initial = ["x < y < "]', "[sets] initial", ("not a valid inequality",)),
    "equality": ('unsafe = ["x == 1"]', "[sets] unsafe", ("'=='", "not an inequality")),
    "not equal": ('unsafe = ["x != 1"]', "[sets] unsafe", ("'!='", "not an inequality")),
    "not a comparison": ('goal = ["x + y"]', "[sets] goal", ("not an inequality",)),
    "and": ('goal = ["x <= 1 and y <= 1"]', "[sets] goal", ("'and'",)),
    "a function": ('goal = ["sqrt(x) <= 1"]', "[sets] goal", ("'sqrt(...)'",)),
    "a number": ("initial = 3", "[sets] initial", ("must be a list of inequalities", "got the number 3")),
    "a string": ('initial = "x <= 1"', "[sets] initial", ("must be a list", 'write it in a list: ["x <= 1"]')),
    "an empty list": ("initial = []", "[sets] initial", ("must be a list", "got an empty list")),
    "an empty piece": ('initial = [["x <= 1"], []]', "[sets] initial", ("an empty list as piece 2",)),
    "mixed": ('initial = ["x <= 1", ["y <= 1"]]', "[sets] initial", ("strings and lists mixed",)),
    "a number in a piece": ('initial = [["x <= 1", 2]]', "[sets] initial", ("piece 1 holding the number 2",)),
    "a dict": ("initial = {x = 1}", "[sets] initial", ("must be a list", "got a table")),
    "a disturbance": ('unsafe = ["x + d <= 1"]', "[sets] unsafe", ("the disturbance 'd'", "over the states")),
    "a state denominator": ('unsafe = ["1/(1 + x**2) >= 0.5"]', "[sets] unsafe",
                            ("polynomial in the states", "denominator")),
    "no state": ('goal = ["r <= 1"]', "[sets] goal", ("involves no state",)),
    "unknown key": ('target = ["x <= 1"]', "[sets] target", ("unknown key", "initial, unsafe, goal")),
    "a line break": ('initial = ["x <= 1\\n + y"]', "[sets] initial", ("one line",)),
    "too many pieces": ("initial = [" + ", ".join(['["x <= 1"]'] * 17) + "]", "[sets] initial",
                        ("17 pieces", "MAX_SET_PIECES")),
    "not a table": (None, "[sets]", ("must be a table",)),
}


def bad_text(body: str | None) -> str:
    return "sets = 1\n" + HEAD if body is None else with_sets(body)  # a top-level key comes before any table


@pytest.mark.parametrize("name", list(BAD))
def test_bad_sets_are_one_line_errors(name: str) -> None:
    body, key, says = BAD[name]
    with pytest.raises(ModelFileError) as raised:
        parse_model(bad_text(body), "m.toml")
    message = str(raised.value)
    assert len(message.splitlines()) == 1, message
    assert message.startswith(f"m.toml: {key}: "), message
    for needle in says:
        assert needle in message, (needle, message)


@pytest.mark.parametrize("name", ["unknown name", "incomplete chain", "a number", "a disturbance", "unknown key"])
def test_bad_sets_on_the_command_line(name: str, tmp_path: Path) -> None:
    body, key, says = BAD[name]
    assert body is not None
    path = tmp_path / "model.toml"
    path.write_text(with_sets(body))
    done = RUNNER.invoke(app.cli, ["certify", str(path)], catch_exceptions=True)
    assert done.exit_code == 2, done.output
    assert "Traceback" not in done.stdout + done.stderr
    lines = done.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("lyapcheck: error: ") and f"{path}: {key}: " in lines[0], lines
    assert all(needle in lines[0] for needle in says)


UNITS = """\
[model]
states = ["x", "v"]

[units]
x = "m"
v = "m/s"

[parameters]
k = "1 1/s^2"
x0 = "0.6 m"
t0 = "1 s"

[dynamics]
x = "v"
v = "-k*x - v/t0"
"""


def test_units_the_sides_of_a_comparison_share_a_dimension() -> None:
    base = UNITS
    model = parse_model(base + '[sets]\ninitial = ["x <= x0", "0 <= x", "x**2 <= x0**2", "-x0 <= x <= x0"]\n', "u.toml")
    assert len(model.sets["initial"][0]) == 5
    with pytest.raises(ModelFileError) as raised:
        parse_model(base + '[sets]\ninitial = ["x <= 0.6"]\n', "u.toml")
    message = str(raised.value)
    assert message.startswith("u.toml: [sets] initial: the sides of 'x <= 0.6' differ in dimension") and \
        "'0.6' is dimensionless" in message and len(message.splitlines()) == 1
    with pytest.raises(ModelFileError, match=r"\[sets\] unsafe: the term 'v'"):
        parse_model(base + '[sets]\nunsafe = ["x + v <= x0"]\n', "u.toml")
    with pytest.raises(ModelFileError, match=r"\[sets\] goal: the sides of 'x\*\*2 <= x0'"):
        parse_model(base + '[sets]\ngoal = ["x**2 <= x0"]\n', "u.toml")


def test_a_parameter_denominator_that_is_zero_is_one_line() -> None:
    text = with_sets('initial = ["x <= 1/r"]')
    assert parse_model(text, "m.toml").sets["initial"] == ((poly(text, "2 - x"),),)
    with pytest.raises(ModelFileError) as raised:
        parse_model(text, "m.toml", {"r": "0"})
    assert str(raised.value) == ("m.toml: [sets] initial: division by zero: a denominator is 0 with r = 0 "
                                 "(the parameters' values)")


def test_the_page_states_the_codes_limits_and_keys() -> None:
    from tests.conftest import ROOT

    page = " ".join((ROOT / "docs" / "model-files.md").read_text().split())
    assert (S.MAX_SET_PIECES, S.MAX_PIECE_INEQUALITIES) == (16, 32)
    for text in ("at most 16, `MAX_SET_PIECES`, of at most 32 inequalities each, `MAX_PIECE_INEQUALITIES`",
                 "| `barrier` | `initial` and `unsafe` |", "| `reach_avoid` | `initial`, `unsafe` and `goal` |",
                 "unknown key (keys: initial, unsafe, goal, stay_in_goal)", "outputs, domain, sets, units"):
        assert text in page, text
    assert S.SET_KEYS == ("initial", "unsafe", "goal")
    assert S.CLASS_SETS == {"barrier": ("initial", "unsafe"), "reach_avoid": ("initial", "unsafe", "goal")}
