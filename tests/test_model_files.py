"""Model files (issue 23, section 1; DESIGN.md, "Model files (contract)").

Four families:

- **Bad input.** One case per item of the issue's list (unknown name, function call, ``^``,
  exponents, states and equations that do not match, names declared twice, non-finite numbers,
  an equilibrium where the field does not vanish, sizes beyond the limits, division by zero, a
  disturbance in a denominator, unknown sections and keys, a bad domain, ``--set`` and
  ``--candidate``). Each runs through the command line (click's CliRunner; one end to end in a
  subprocess) and through the library, and asserts the contract: exit code 2 (the library:
  :class:`~lyapcheck.errors.ModelFileError`), exactly one line on stderr naming the file and the
  key, what is wrong, and no traceback.
- **Exactness.** Decimals are read from their text (``0.1`` is ``1/10``), units become SI
  exactly, ``Hz`` is refused as ambiguous (tests/test_model_units.py), the equilibrium is checked exactly.
- **Security.** Property-based (hypothesis, derandomized): random strings and random trees
  written as text (``__import__('os')``, attributes, lambdas, comprehensions, f-strings, walrus,
  starred, subscripts, very long and deeply nested inputs) either parse or raise
  :class:`~lyapcheck.models.language.expressions.ExpressionError`, one line (how quickly: benchmarks/
  bench_quick_paths.py), while ``eval``,
  ``exec``, ``compile`` (other than ``ast.parse``'s), ``sympy.sympify`` and ``parse_expr`` fail
  the test if anything calls them. A static test reads ``lyapcheck/models/`` with ``ast``: no call
  to any of them.
- **Round trip.** Every shipped example loads; the text is the file's, verbatim, and its SHA-256
  is the file's.
"""

from __future__ import annotations

import ast
import builtins
import hashlib
import importlib
import json
import os
import subprocess
import sys
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field
from fractions import Fraction
from pathlib import Path

import pytest
from click.testing import CliRunner, Result
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from lyapcheck.api import load_model_file
from lyapcheck.cli import app
from lyapcheck.errors import InvalidParameter, ModelFileError
from lyapcheck.models.surfaces.certify import parse_candidate
from lyapcheck.models.language.expressions import MAX_TOTAL_DEGREE, ExpressionError, Rational, parse_expression
from lyapcheck.models.language.modelfile import MAX_STATES, load_model, parse_model
from lyapcheck.sos.polynomials import Ring
from lyapcheck.units import parse_si_quantity
from tests.conftest import ROOT

app._register_commands()
RUNNER = CliRunner()
MODELS = ROOT / "examples" / "models"

#: a valid model: two states, a parameter, a disturbance; every bad case below changes one thing
VALID = """\
[model]
name = "two states"
states = ["x1", "x2"]

[parameters]
mu = 1

[disturbances]
d = 0.5

[dynamics]
x1 = "-x1 + x2"
x2 = "-mu*x2 + d"
"""

TWELVE = [f"x{i}" for i in range(1, 13)]


def twelve_states(x1: str) -> str:
    """A model with 12 states (the limit): ``x1'`` is the expression given, the others decay."""
    states = ", ".join(f'"{s}"' for s in TWELVE)
    rows = "\n".join(f'{s} = "-{s}"' for s in TWELVE[1:])
    return f'[model]\nstates = [{states}]\n[dynamics]\nx1 = "{x1}"\n{rows}\n'


def edit(old: str, new: str, text: str = VALID) -> str:
    assert text.count(old) == 1, old
    return text.replace(old, new)


# -- bad input: the cases --------------------------------------------------------------------------
@dataclass(frozen=True)
class Bad:
    """A model text (and ``--set`` / ``--candidate``) that must be refused at ``key``, the message
    containing every one of ``says``."""

    text: str
    key: str
    says: tuple[str, ...]
    sets: tuple[str, ...] = ()
    candidate: str | None = None
    marks: tuple[pytest.MarkDecorator, ...] = field(default=())


BAD: dict[str, Bad] = {
    # names
    "unknown name": Bad(edit('"-mu*x2 + d"', '"-mu*x2 + y"'), "[dynamics] x2", ("unknown name 'y'",)),
    "a text Python warns about": Bad(edit('"-x1 + x2"', '"-x1 + (1if x2 else 2)"'), "[dynamics] x1",
                                     ("'1if x2 else 2'", "not part of the language")),
    "unknown name (a constant)": Bad(edit('"-x1 + x2"', '"-z*x1"'), "[dynamics] x1", ("unknown name 'z'",)),
    # pi and function calls (a loop with functions, recast; this one also has disturbances): pi
    # outside sin and cos, a square root of something that can be negative (refused by certify when
    # its proof fails, by the polynomial-only loader at once), a function of the wrong arity
    "constant pi": Bad(edit('"-x1 + x2"', '"-pi*x1"'), "[dynamics] x1",
                       ("pi may appear only in an argument of sin or cos",)),
    "call sqrt": Bad(edit('"-mu*x2 + d"', '"-sqrt(x2)"'), "[dynamics] x2", ("sqrt(x2)",)),
    "call sin": Bad(edit('"-x1 + x2"', '"-x1 + sin(x2, x1)"'), "[dynamics] x1", ("'sin' takes 1 argument",)),
    # ^ says **
    "caret": Bad(edit('"-x1 + x2"', '"-x1^3 + x2"'), "[dynamics] x1", ("'^'", "'**'", "x1**3")),
    # exponents
    "exponent not an integer": Bad(edit('"-x1 + x2"', '"-x1**1.5"'), "[dynamics] x1", ("'1.5'", "not an integer")),
    "exponent a name": Bad(edit('"-x1 + x2"', '"-x1**mu"'), "[dynamics] x1", ("'mu'", "non-negative integer")),
    "exponent negative": Bad(edit('"-x1 + x2"', '"-x1**-3"'), "[dynamics] x1", ("'-3'", "negative")),
    "exponent huge": Bad(edit('"-x1 + x2"', '"-x1**100000000000000000000"'), "[dynamics] x1",
                         ("100000000000000000000", "MAX_EXPONENT")),
    # states and equations
    "state without an equation": Bad(edit('x1 = "-x1 + x2"\n', ""), "[dynamics]", ("'x1'", "no equation")),
    "equation without a state": Bad(edit('x2 = "-mu*x2 + d"\n', 'x2 = "-mu*x2 + d"\nx3 = "-x3"\n'),
                                    "[dynamics] x3", ("without a state", "'x3'")),
    # names declared twice
    "state twice": Bad(edit('["x1", "x2"]', '["x1", "x2", "x1"]'), "[model] states", ("'x1'", "declared twice")),
    "state and parameter": Bad(edit("mu = 1", "mu = 1\nx2 = 3"), "[parameters] x2", ("'x2'", "declared twice",
                                                                                      "a state")),
    "state and disturbance": Bad(edit("d = 0.5", "d = 0.5\nx1 = 1"), "[disturbances] x1",
                                 ("'x1'", "declared twice", "a state")),
    "parameter and disturbance": Bad(edit("d = 0.5", "d = 0.5\nmu = 1"), "[disturbances] mu",
                                     ("'mu'", "declared twice", "a parameter")),
    "output and parameter": Bad(VALID + '[outputs]\nmu = "x1"\n', "[outputs] mu", ("'mu'", "declared twice",
                                                                                   "parameter")),
    "output and disturbance": Bad(VALID + '[outputs]\nd = "x1"\n', "[outputs] d", ("'d'", "declared twice",
                                                                                   "disturbance")),
    # non-finite numbers
    "parameter inf (TOML)": Bad(edit("mu = 1", "mu = inf"), "[parameters] mu", ("finite", "inf")),
    "parameter nan (TOML)": Bad(edit("mu = 1", "mu = nan"), "[parameters] mu", ("finite", "nan")),
    "parameter -inf (text)": Bad(edit("mu = 1", 'mu = "-inf"'), "[parameters] mu", ("finite", "-inf")),
    "disturbance bound inf": Bad(edit("d = 0.5", "d = inf"), "[disturbances] d", ("finite",)),
    "1e999 in an expression": Bad(edit('"-x1 + x2"', '"-x1 + 1e999*x2"'), "[dynamics] x1",
                                  ("'1e999'", "not finite")),
    "inf as a TOML number in [dynamics]": Bad(edit('"-x1 + x2"', "inf"), "[dynamics] x1", ("inf", "not finite")),
    "1e-400 in an expression": Bad(edit('"-x1 + x2"', '"-x1 + 1e-400*x2"'), "[dynamics] x1",
                                   ("'1e-400'", "out of range")),
    # equilibrium, checked exactly: 0.1 + 0.2 == 0.30000000000000004 in doubles, not in rationals
    "equilibrium: field does not vanish": Bad(VALID + "[equilibrium]\nx1 = 1\n", "[equilibrium]",
                                              ("not an equilibrium", "x1' = -1")),
    "equilibrium: off by a double's rounding": Bad(
        edit('"-mu*x2 + d"', '"-mu*x2 + d + 0.1 + 0.2 - 0.30000000000000004"'),
        "[equilibrium] (default: every state 0)", ("not an equilibrium", "x2' = -1/25000000000000000", "exactly")),
    "equilibrium: unknown state": Bad(VALID + "[equilibrium]\nx9 = 0\n", "[equilibrium] x9", ("no state named 'x9'",)),
    # sizes
    "31 states": Bad("[model]\nstates = [" + ", ".join(f'"x{k}"' for k in range(1, 32)) + "]\n[dynamics]\n"
                     + "".join(f'x{k} = "-x{k}"\n' for k in range(1, 32)), "[model] states",
                     ("31 states", f"limit is {MAX_STATES}", "MAX_STATES")),
    "total degree 13": Bad(edit('"-x1 + x2"', '"-x1 - x1**7*x2**6"'), "[dynamics] x1",
                           (f"above {MAX_TOTAL_DEGREE}", "MAX_TOTAL_DEGREE")),
    "total degree 13 in a denominator": Bad(edit('"-x1 + x2"', '"-x1/(1 + x1**7*x2**6)"'), "[dynamics] x1",
                                            (f"above {MAX_TOTAL_DEGREE}", "MAX_TOTAL_DEGREE")),
    "exponent above MAX_EXPONENT": Bad(edit('"-x1 + x2"', '"-x1/(1 + x1**13)"'), "[dynamics] x1",
                                       ("exponent 13", "MAX_EXPONENT")),
    "(x1 + ... + x12)**12": Bad(twelve_states(f"-x1 + ({' + '.join(TWELVE)})**12"), "[dynamics] x1",
                                ("more than 2000 terms", "MAX_TERMS")),
    # division by zero: in the text, and once the parameters are set
    "division by zero": Bad(edit('"-x1 + x2"', '"-x1/(x2 - x2)"'), "[dynamics] x1", ("division by zero",)),
    "division by a zero parameter": Bad(edit("mu = 1", "mu = 0", edit('"-mu*x2 + d"', '"-x2/mu + d"')),
                                        "[dynamics] x2", ("division by zero", "mu = 0")),
    "disturbance in a denominator": Bad(edit('"-mu*x2 + d"', '"-mu*x2 + 1/(2 + d**2) - 1/2"'), "[dynamics] x2",
                                        ("disturbance 'd'", "denominator")),
    # unknown sections and keys
    "unknown section": Bad(VALID + "[controllers]\nk = 1\n", "[controllers]", ("unknown section",)),
    "unknown key in [model]": Bad(edit('name = "two states"', 'name = "two states"\nauthor = "me"'),
                                  "[model] author", ("unknown key",)),
    "a key with a line break": Bad(edit("mu = 1", 'mu = 1\n"a\\nb" = 2'), "[parameters] a\\nb",
                                   ("not a valid name",)),
    # domain
    "domain lo = hi": Bad(VALID + "[domain]\nx1 = [1, 1]\nx2 = [-1, 1]\n", "[domain] x1", ("lo < hi",)),
    "domain lo > hi": Bad(VALID + "[domain]\nx1 = [2, -2]\nx2 = [-1, 1]\n", "[domain] x1", ("lo < hi",)),
    "domain missing a state": Bad(VALID + "[domain]\nx1 = [-1, 1]\n", "[domain]", ("'x2'", "no interval")),
    "domain of an unknown state": Bad(VALID + "[domain]\nx1 = [-1, 1]\nx2 = [-1, 1]\nx3 = [0, 1]\n",
                                      "[domain] x3", ("no state named 'x3'",)),
    # --set
    "--set an unknown name": Bad(VALID, "--set nu", ("no parameter or disturbance named 'nu'", "mu, d"),
                                 sets=("nu=2",)),
    "--set a unit that is not one": Bad(VALID, "--set mu", ("'2 bananas'", "unit"), sets=("mu=2 bananas",)),
    "--set a non-finite value": Bad(VALID, "--set mu", ("finite", "'inf'"), sets=("mu=inf",)),
    "--set a negative disturbance bound": Bad(VALID, "--set d", (">= 0",), sets=("d=-1",)),
    "--set to a zero divisor": Bad(edit('"-mu*x2 + d"', '"-x2/mu + d"'), "[dynamics] x2",
                                   ("division by zero", "mu = 0"), sets=("mu=0",)),
    "--set a name with a line break": Bad(VALID, "--set a\\nb", ("no parameter or disturbance",), sets=("a\nb=1",)),
    "--set without '='": Bad(VALID, "set", ("NAME=VALUE",), sets=("mu",)),
    "--set without a name": Bad(VALID, "set", ("NAME=VALUE",), sets=("=2",)),
    # --candidate
    "--candidate not polynomial": Bad(VALID, "--candidate", ("polynomial",), candidate="x1**2/(1 + x2**2)"),
    "--candidate a function": Bad(VALID, "--candidate", ("'sqrt(...)'", "polynomial or rational"),
                                  candidate="sqrt(x1**2 + x2**2)"),
    "--candidate not 0 at the equilibrium": Bad(VALID, "--candidate", ("0 at the equilibrium", "it is 1 there"),
                                                candidate="x1**2 + x2**2 + 1"),
    "--candidate with a disturbance": Bad(VALID, "--candidate", ("disturbance",), candidate="x1**2 + d*x2"),
    # the file itself
    "not TOML": Bad(VALID + "[[[\n", "file", ("not valid TOML",)),
    "no [model]": Bad("[dynamics]\nx1 = \"-x1\"\n", "[model]", ("missing",)),
}


def bad_cases() -> list[object]:
    return [pytest.param(case, id=name, marks=case.marks) for name, case in BAD.items()]


def cli_args(path: Path, case: Bad) -> list[str]:
    args = ["certify", "--model", str(path), "--classes", "linearization"]
    for item in case.sets:
        args += ["--set", item]
    if case.candidate is not None:
        args += ["--candidate", case.candidate]
    return args


def assert_one_line(message: str, source: str, case: Bad) -> None:
    """The contract's message: one line, naming the file and the key, saying what is wrong."""
    lines = message.strip().splitlines()
    assert len(lines) == 1, f"not one line: {message!r}"
    line = lines[0]
    assert "Traceback" not in line
    assert source in line, f"the file is not named: {line!r}"
    assert f"{case.key}:" in line, f"the key {case.key!r} is not named: {line!r}"
    for needle in case.says:
        assert needle in line, f"{needle!r} not said: {line!r}"


@pytest.mark.parametrize("case", bad_cases())
def test_bad_input_on_the_command_line(case: Bad, tmp_path: Path) -> None:
    path = tmp_path / "model.toml"
    path.write_text(case.text, encoding="utf-8")
    result: Result = RUNNER.invoke(app.cli, cli_args(path, case), catch_exceptions=True)
    assert result.exception is None or isinstance(result.exception, SystemExit), repr(result.exception)
    assert result.exit_code == 2, (result.exit_code, result.stdout[-500:], result.stderr)
    assert "Traceback" not in result.stdout + result.stderr
    assert result.stderr.startswith("lyapcheck: error: ")
    assert_one_line(result.stderr, str(path), case)


@pytest.mark.parametrize("case", bad_cases())
def test_bad_input_through_the_library(case: Bad, tmp_path: Path) -> None:
    path = tmp_path / "model.toml"
    path.write_text(case.text, encoding="utf-8")
    with pytest.raises((ModelFileError, InvalidParameter)) as raised:
        if case.candidate is not None:
            parse_candidate(load_model(path), case.candidate)
        elif case.sets:
            load_model_file(path, list(case.sets))  # the API's reading of --set NAME=VALUE
        else:
            load_model(path)
    assert_one_line(str(raised.value), str(path), case)
    assert isinstance(raised.value, ModelFileError) and raised.value.key == case.key
    if not case.sets and case.candidate is None:  # the same from the text, under any source name
        with pytest.raises(ModelFileError, match="^<text>: "):
            parse_model(case.text, "<text>")


@pytest.mark.parametrize("name", ["call sin", "a text Python warns about"])
def test_bad_input_end_to_end_in_a_subprocess(name: str, tmp_path: Path) -> None:
    """The entry point in its own process, with Python's default warning filters (the suite turns
    warnings into errors: a SyntaxWarning printed beside the error line shows only here)."""
    path = tmp_path / "bad model.toml"
    path.write_text(BAD[name].text, encoding="utf-8")
    env = {k: v for k, v in os.environ.items() if k != "PYTHONWARNINGS"}
    done = subprocess.run([sys.executable, "-m", "lyapcheck", "certify", "--model", str(path)], capture_output=True,
                          text=True, timeout=120, env={**env, "COLUMNS": "200"})
    assert done.returncode == 2, done.stderr
    assert done.stdout == "" and "Traceback" not in done.stderr
    assert done.stderr.count("\n") == 1 and done.stderr.startswith("lyapcheck: error: "), done.stderr
    assert_one_line(done.stderr, str(path), BAD[name])


def test_a_huge_power_is_refused_before_it_is_expanded() -> None:
    """(x1 + ... + x12)**12 has 1,352,078 terms: refused at a product beyond MAX_TERMS (it took
    1.5 s when the power was expanded first; the time is benchmarks/bench_quick_paths.py's, no test
    asserts a wall time)."""
    ring = Ring(tuple(TWELVE))
    with pytest.raises(ExpressionError, match="MAX_TERMS"):
        parse_expression(f"({' + '.join(TWELVE)})**12", ring)
    with pytest.raises(ModelFileError, match="MAX_TERMS"):
        parse_model(BAD["(x1 + ... + x12)**12"].text, "twelve.toml")
    # at the limit, and within it, it is no refusal: 13 terms of degree 12
    assert len(parse_expression("(x1 + 1)**12", ring).numerator) == 13


def test_long_sums_are_not_deep_nesting() -> None:
    """A polynomial of many terms is one level of nesting, not one per term (70 terms were refused
    as 'nested deeper than 60'); real nesting beyond MAX_DEPTH still is."""
    ring = Ring(("x1", "x2"))
    terms = " + ".join(f"{k}*x1**{k % 5}*x2**{k % 7}" for k in range(1, 200))
    expected = sum(k for k in range(1, 200))
    value = parse_expression(terms, ring)
    assert sum(c for c in ring.terms(value.numerator).values()) == expected
    assert parse_expression(" - ".join(["x1"] * 700), ring).numerator == -698 * ring.gen("x1")
    with pytest.raises(ExpressionError, match="MAX_DEPTH"):
        parse_expression("-(" * 61 + "x1" + ")" * 61, ring)


# -- exactness -------------------------------------------------------------------------------------
def test_decimals_are_exact() -> None:
    ring = Ring(("x1", "x2"))

    def value(text: str) -> Fraction:
        r = parse_expression(text, ring)
        assert r.is_polynomial() and r.numerator.is_constant()
        return ring.terms(r.numerator).get((0, 0), Fraction(0))

    assert value("0.1") == Fraction(1, 10)
    assert value("0.1 + 0.2 - 0.3") == 0  # 5.551115123125783e-17 in doubles
    assert value("0.1 + 0.2 - 0.30000000000000004") == Fraction(-4, 10**17)
    assert value("1e-3") == Fraction(1, 1000)
    assert value("2.5E+2") == 250
    assert value("1_000.5") == Fraction(2001, 2)
    assert value("1/3") == Fraction(1, 3)
    assert value("2.5e-308") == Fraction(1, 4 * 10**307)
    assert value("0e9999999") == 0  # zero, instantly (Fraction("0e9999999") builds 10**9999999 first)
    assert parse_expression("0.1*x1 - 0.1*x1", ring).numerator.is_zero()
    assert parse_expression("x1*(x2 + 1)/(x2 + 1)", ring) == Rational.polynomial(ring, ring.gen("x1"))


def test_a_decimal_exponent_beyond_doubles_is_refused_without_building_it() -> None:
    """Fraction("1e-9999999") would build 10**9999999 (11 s here) before the range check (the
    time is benchmarks/bench_quick_paths.py's)."""
    ring = Ring(("x1",))
    for text in ("1e-9999999*x1", "-1.5e-9999999 + x1"):
        with pytest.raises(ExpressionError, match="out of range"):
            parse_expression(text, ring)
    assert parse_expression("0e9999999*x1 + x1", ring).numerator == ring.gen("x1")


def test_a_field_of_decimals_that_cancel_is_exactly_zero() -> None:
    model = parse_model(edit('"-x1 + x2"', '"0.1*x1 - 0.1*x1"', edit('"-mu*x2 + d"', '"-x2 + 0.1 + 0.2 - 0.3"')))
    assert model.dynamics[0].numerator.is_zero()
    assert model.ring.terms(model.dynamics[1].numerator) == {(0, 1, 0, 0): Fraction(-1)}


def test_parameters_with_units_are_si_exactly(tmp_path: Path) -> None:
    text = edit("mu = 1", 'mu = "0.75 mm"\nv = "0.088 mm/s"\nf = "2.8 1/s"\nc = 0.1')
    model = parse_model(text)
    assert model.parameters == {"mu": Fraction(3, 4000), "v": Fraction(11, 125000), "f": Fraction(14, 5),
                                "c": Fraction(1, 10)}
    assert model.parameters_given["mu"] == "0.75 mm"
    # --set with a unit, through the library and the command line (the JSON's exact parameters)
    path = tmp_path / "units.toml"
    path.write_text(text, encoding="utf-8")
    assert load_model(path, {"mu": "2.5 um", "d": "0.1 mm/s"}).parameters["mu"] == Fraction(1, 400000)
    assert load_model(path, {"d": "0.1 mm/s"}).disturbances["d"] == Fraction(1, 10000)
    done = RUNNER.invoke(app.cli, ["certify", "--model", str(path), "--set", "mu=2.5 um", "--classes",
                                   "linearization", "--json"])
    assert done.exit_code == 0, done.stderr
    doc = json.loads(done.stdout)
    assert doc["parameters"]["mu"] == "1/400000" and doc["parameters"]["f"] == "14/5"


def test_hz_is_refused_in_a_model_file() -> None:
    """A model file does not say which parameter is a rotation: "2.8 Hz" is refused, the message
    giving both readings (2.8 1/s, or 2 pi 2.8 rad/s); tests/test_model_units.py has the rest."""
    with pytest.raises(InvalidParameter, match=r"'2\.8 1/s'.*'17\.5929188601028 rad/s'"):
        parse_si_quantity("f", "2.8 Hz")
    doc = " ".join((parse_si_quantity.__doc__ or "").split())
    assert "``Hz``" in doc and "refused" in doc


def test_the_equilibrium_is_checked_exactly() -> None:
    at = edit('"-x1 + x2"', '"0.1 - x1 + x2"') + "[equilibrium]\nx1 = 0.1\n"
    assert parse_model(at).equilibrium == (Fraction(1, 10), Fraction(0))
    # the double nearest 0.1 is not 0.1: the field does not vanish there, exactly
    near = at.replace("x1 = 0.1\n", 'x1 = "0.1000000000000000055511151231257827"\n')
    with pytest.raises(ModelFileError, match=r"\[equilibrium\]: is not an equilibrium: x1' = "):
        parse_model(near)
    # a rational field whose denominator vanishes at the point is no equilibrium either
    with pytest.raises(ModelFileError, match="not defined there"):
        parse_model(edit('"-x1 + x2"', '"-x1/x2 + x2"'))


# -- security --------------------------------------------------------------------------------------
#: what no user's string may reach; ``compile`` only as the builtin (a method of that name is no
#: evaluator: the static test flags ``x.compile(...)`` only for the others)
FORBIDDEN = ("eval", "exec", "compile", "sympify", "parse_expr")


@contextmanager
def no_code_execution() -> Iterator[list[str]]:
    """``eval``, ``exec``, ``compile`` (unless it only builds an AST, as ``ast.parse`` does),
    ``sympy.sympify`` and ``parse_expr`` replaced by traps: each call is recorded (and raises).
    Restored on exit; the list of calls is the caller's to assert empty."""
    calls: list[str] = []
    real_compile = builtins.compile

    def trap(name: str):  # type: ignore[no-untyped-def]
        def called(*args: object, **kwargs: object) -> None:
            calls.append(name)
            raise AssertionError(f"{name} was called on a user's expression")
        return called

    def compile_ast_only(source, filename, mode, flags=0, *args, **kwargs):  # type: ignore[no-untyped-def]
        if not flags & ast.PyCF_ONLY_AST:
            calls.append("compile")
            raise AssertionError("compile was asked for code, not a tree")
        return real_compile(source, filename, mode, flags, *args, **kwargs)

    import sympy
    import sympy.parsing.sympy_parser

    sympify_module = importlib.import_module("sympy.core.sympify")
    targets = [(builtins, "eval", trap("eval")), (builtins, "exec", trap("exec")),
               (builtins, "compile", compile_ast_only), (sympy, "sympify", trap("sympify")),
               (sympify_module, "sympify", trap("sympify")), (sympy, "parse_expr", trap("parse_expr")),
               (sympy.parsing.sympy_parser, "parse_expr", trap("parse_expr"))]
    saved = [(obj, name, getattr(obj, name)) for obj, name, _ in targets]
    try:
        for obj, name, replacement in targets:
            setattr(obj, name, replacement)
        yield calls
    finally:
        for obj, name, original in saved:
            setattr(obj, name, original)


def test_the_traps_catch_what_they_guard() -> None:
    import sympy

    with no_code_execution() as calls:
        for attempt in (lambda: eval("1"), lambda: exec("x = 1"), lambda: compile("1", "<s>", "eval"),
                        lambda: sympy.sympify("x"), lambda: sympy.parsing.sympy_parser.parse_expr("x")):
            with pytest.raises(AssertionError):
                attempt()
        assert ast.parse("1 + 2", mode="eval")  # the AST-only compile of ast.parse is let through
    assert calls == ["eval", "exec", "compile", "sympify", "parse_expr"]
    assert eval("1") == 1  # restored


SECURITY_RING = Ring(("x1", "x2", "mu", "d"))
SECURITY_SETTINGS = settings(max_examples=400, derandomize=True, deadline=None, database=None,
                             suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])

#: atoms of the hostile grammar: the language's own, and what must never run or pass
ATOMS = ("x1", "x2", "mu", "d", "y", "pi", "e", "os", "__import__", "__builtins__", "True", "None", "...",
         "0", "1", "2", "0.1", "1e999", "1e-400", "1e-9999999", "0e9999999", "0x1F", "1_000.5", "1j", "'s'",
         "b'x'", "__import__('os')", "__import__('os').system('echo pwned')", "open('/etc/passwd').read()",
         "().__class__.__bases__[0].__subclasses__()", "globals()", "breakpoint()", "eval('1')",
         "exec('import os')", "compile('1', '', 'eval')", "lambda: 0", "[i for i in (1, 2)]",
         "{i: i for i in (1,)}", "(i for i in ())", "f'{x1}'", "f'{__import__(\"os\")}'", "(y := 1)", "*x1",
         "x1[0]", "x1.real", "x1.__class__", "x1 if x2 else 1", "await x1", "(yield)", "not x1", "x1 < x2",
         "{1, 2}", "[x1, x2]", "(x1, x2)")
BINARY = (" + ", " - ", " * ", " / ", " ** ", "**", " ^ ", " // ", " % ", " @ ", " << ", " & ", " | ", " and ",
          " or ", " < ", " == ", " if x1 else ", ", ")
EXPRESSION_CHARS = "x12 +-*/().e_^[]{}:,;'\"@%<>=!~&|lambdforinimpt.\\#\t\n0123456789jJ"


def _tree(children: st.SearchStrategy[str]) -> st.SearchStrategy[str]:
    """One level of a random tree, written as text."""
    pair = st.tuples(children, children)
    return st.one_of(
        st.builds(lambda ab, op: f"{ab[0]}{op}{ab[1]}", pair, st.sampled_from(BINARY)),
        st.builds(lambda a, op: f"{op}{a}", children, st.sampled_from(("-", "+", "~", "not ", "*", "**"))),
        st.builds(lambda a: f"({a})", children),
        st.builds(lambda fn, a: f"{fn}({a})", st.sampled_from(("sin", "sqrt", "exp", "f", "x1", "__import__",
                                                               "getattr", "(lambda q: q)")), children),
        st.builds(lambda a, k: f"({a})**{k}", children,
                  st.one_of(st.integers(-5, 40).map(str), st.sampled_from(("1.5", "x1", "-1", "1e999", "10**10",
                                                                           "True", "(2)", "0x3")))),
        st.builds(lambda ab: f"{ab[0]}[{ab[1]}]", pair),
        st.builds(lambda a, attr: f"({a}).{attr}", children, st.sampled_from(("real", "__class__", "__dict__"))),
        st.builds(lambda a: f"(lambda: {a})", children),
        st.builds(lambda ab: f"[{ab[0]} for x1 in ({ab[1]},)]", pair),
        st.builds(lambda a: f"f'{{{a}}}'", children),
        st.builds(lambda a: f"(x1 := {a})", children),
        st.builds(lambda a: f"(*{a},)", children),
    )


TREES = st.recursive(st.sampled_from(ATOMS), _tree, max_leaves=12)


def _long_or_deep(kind: str, n: int) -> str:
    return {"parens": "(" * n + "x1" + ")" * n, "unary": "-" * n + "x1", "power chain": "x1" + "**x1" * n,
            "attribute chain": "x1" + ".a" * n, "subscripts": "x1" + "[0]" * n, "brackets": "[" * n + "]" * n,
            "calls": "f(" * n + ")" * n, "lambdas": "lambda: " * n + "1", "sum": " + ".join(["x1"] * n),
            "product": "*".join(["x1"] * n), "quotient": "/".join(["x1"] * n),
            "decimals": " - ".join(["0.1"] * n), "walrus": "(x1 := " * n + "1" + ")" * n}[kind]


LONG_OR_DEEP = st.builds(_long_or_deep, st.sampled_from(("parens", "unary", "power chain", "attribute chain",
                                                         "subscripts", "brackets", "calls", "lambdas", "sum",
                                                         "product", "quotient", "decimals", "walrus")),
                         st.integers(0, 2100))

HOSTILE = st.one_of(st.text(alphabet=EXPRESSION_CHARS, max_size=120), st.text(max_size=60), TREES, LONG_OR_DEEP)


def check_refused_or_parsed(text: str) -> None:
    """parse_expression(text) returns an exact rational function or raises ExpressionError, with a
    one-line message, and nothing is evaluated (how quickly is benchmarks/bench_quick_paths.py's figure:
    no test asserts a wall time, which a loaded machine decides)."""
    with no_code_execution() as calls:
        try:
            result = parse_expression(text, SECURITY_RING)
        except ExpressionError as exc:
            message = str(exc)
            assert message and len(message.splitlines()) == 1, f"{text[:200]!r}: {message!r}"
        except BaseException as exc:  # noqa: BLE001 - any other exception is the failure sought
            pytest.fail(f"{text[:200]!r} raised {type(exc).__name__}: {str(exc)[:300]}")
        else:
            assert isinstance(result, Rational) and not result.denominator.is_zero()
    assert calls == [], f"{text[:200]!r} called {calls}"


@SECURITY_SETTINGS
@given(HOSTILE)
def test_any_text_is_parsed_or_refused_never_run(text: str) -> None:
    check_refused_or_parsed(text)


DEEP_CHAINS = [pytest.param(_long_or_deep(kind, n), id=f"{kind} {n}")
               for kind in ("parens", "unary", "power chain", "attribute chain", "subscripts", "calls", "sum",
                            "walrus") for n in (59, 61, 200, 790)]


@pytest.mark.parametrize("text", [*ATOMS, *DEEP_CHAINS])
def test_hostile_atoms_and_deep_chains(text: str) -> None:
    """The grammar's atoms and the deep chains at fixed sizes, every run whatever hypothesis draws."""
    check_refused_or_parsed(text)


def test_hostile_text_is_refused_with_what_it_is() -> None:
    ring = SECURITY_RING
    for text, says in (("__import__('os').system('true')", "function call"), ("x1.real", "not part of the language"),
                       ("lambda: 0", "not part of the language"), ("[i for i in ()]", "not part of the language"),
                       ("f'{x1}'", "not part of the language"), ("(y := 1)", "not part of the language"),
                       ("x1[0]", "not part of the language"), ("*x1", "not a valid expression"),
                       ("x1 // 2", "'//'"), ("'x1'", "not a number")):
        with pytest.raises(ExpressionError, match=f".*{says}"):
            parse_expression(text, ring)


def test_the_model_package_calls_no_evaluator() -> None:
    """Read lyapcheck/models/ with ast: no call of eval/exec/compile/sympify/parse_expr, under
    any spelling (a name or an attribute), and no import of sympify or parse_expr."""
    package = ROOT / "lyapcheck" / "models"
    sources = sorted(package.rglob("*.py"))
    assert sources, package
    found = []
    for path in sources:
        tree = ast.parse(path.read_text(encoding="utf-8"), filename=str(path))
        for node in ast.walk(tree):
            if isinstance(node, ast.Call):
                func = node.func
                if isinstance(func, ast.Name):
                    name = func.id
                elif isinstance(func, ast.Attribute):
                    name = func.attr if func.attr != "compile" else ""
                else:
                    name = ""
                if name in FORBIDDEN:
                    found.append(f"{path.name}:{node.lineno} calls {name}")
            elif isinstance(node, ast.ImportFrom):
                found += [f"{path.name}:{node.lineno} imports {a.name}" for a in node.names
                          if a.name in ("sympify", "parse_expr")]
    assert found == []


# -- round trip ------------------------------------------------------------------------------------
EXAMPLES = sorted(MODELS.glob("*.toml"))


def test_there_are_examples() -> None:
    assert len(EXAMPLES) >= 8


@pytest.mark.parametrize("path", EXAMPLES, ids=[p.stem for p in EXAMPLES])
def test_every_example_loads_with_its_text_and_hash(path: Path) -> None:
    from lyapcheck.models.language.modelfile import load_any_model, parse_any_model
    from lyapcheck.models.language.recast import RecastModel

    raw = path.read_bytes()
    from lyapcheck.models.language.sampling import file_is_sampled, load_sampled

    if file_is_sampled(path):  # a sampled-data loop has its own reader (tests/test_sampled_loops.py)
        sampled = load_sampled(path)
        assert sampled.text == raw.decode("utf-8") and sampled.sha256 == hashlib.sha256(raw).hexdigest()
        return
    model = load_any_model(path)
    assert model.text == raw.decode("utf-8")
    assert model.sha256 == hashlib.sha256(raw).hexdigest()
    again = parse_any_model(model.text, model.source)
    if isinstance(model, RecastModel):  # a loop with functions: recast again, the same
        assert isinstance(again, RecastModel) and again.system.to_json() == model.system.to_json()
        assert len(model.system.field) == model.n == len(model.states) and model.name
        return
    assert not isinstance(again, RecastModel)
    assert again.dynamics == model.dynamics and again.sha256 == model.sha256
    assert len(model.dynamics) == model.n == len(model.states) and model.name


def test_the_text_is_the_files_verbatim_with_crlf_line_ends(tmp_path: Path) -> None:
    """The SHA-256 a certificate carries is the file's own (a universal-newline read gave LF's)."""
    path = tmp_path / "crlf.toml"
    path.write_bytes(VALID.replace("\n", "\r\n").encode("utf-8"))
    model = load_model(path)
    assert model.text == VALID.replace("\n", "\r\n")
    assert model.sha256 == hashlib.sha256(path.read_bytes()).hexdigest()
    assert model.dynamics == parse_model(VALID).dynamics
