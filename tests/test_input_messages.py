"""Messages for input a new user writes: each says what was written and what to write instead,
without contradicting itself (issue 40, item 10).

What is asserted, through ``lyapcheck certify`` (exit 2, one line on stderr, no traceback):
``math.sin(x)`` in ``[dynamics]`` is refused as attribute access with ``sin(x)`` to write (not
"functions are taken in [dynamics]", where it stands); a bare ``t`` says time is not a name of the
model (not "functions and constants such as pi are not part of the language"); ``[model] time``
takes ``"continuous"`` and ``"discrete"`` (a map, issue 44: tests/test_discrete_maps.py) and refuses
anything else naming both.
"""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from click.testing import CliRunner

from lyapcheck.cli import app
from lyapcheck.models.language.modelfile import TIME_KINDS

app._register_commands()


def model_file(folder: Path, rhs: str, head: str = "", extra: str = "") -> Path:
    """A two-state loop ``x' = y, y' = rhs`` with extra ``[model]`` lines and extra sections."""
    path = folder / "m.toml"
    path.write_text(f'[model]\nname = "m"\nstates = ["x", "y"]\n{head}\n[dynamics]\nx = "y"\ny = "{rhs}"\n{extra}')
    return path


def refusal(path: Path) -> str:
    """The one line ``certify`` prints for a refused file (after ``lyapcheck: error: FILE: ``)."""
    done = CliRunner().invoke(app.cli, ["certify", str(path), "--classes", "quadratic", "--no-store"])
    assert done.exit_code == 2, done.output
    assert "Traceback" not in done.output and done.stdout == ""
    [line] = done.stderr.splitlines()
    prefix = f"lyapcheck: error: {path}: "
    assert line.startswith(prefix), line
    return line[len(prefix):]


@pytest.mark.parametrize(("rhs", "said"), [
    pytest.param("-math.sin(x) - y", "[dynamics] y: function call 'math.sin(x)': attribute access ('math.') is "
                                     "not part of the language: write 'sin(x)'", id="math.sin"),
    pytest.param("-x - y + 0*np.pi", "[dynamics] y: 'np.pi': attribute access ('np.') is not part of the "
                                     "language: write 'pi'", id="np.pi"),
    pytest.param("-x - numpy.foo(x)", "[dynamics] y: function call 'numpy.foo(x)': attribute access ('numpy.') is "
                                      "not part of the language (functions: sin, cos, exp, sqrt, atan, tanh, abs, "
                                      "min, max, sat; and the constant pi)", id="unknown function"),
    pytest.param("-x - y + t", "[dynamics] y: unknown name 't' (declared names: x, y): time is not a name of the "
                               "model; the loop must be autonomous (for a time dependence, make time a state t "
                               "with [dynamics] t = \"1\")", id="time"),
    pytest.param("-sin(x) - y*t", "[dynamics] y: unknown name 't' (declared names: x, y): time is not a name of the "
                                  "model; the loop must be autonomous (for a time dependence, make time a state t "
                                  "with [dynamics] t = \"1\")", id="time in a loop with functions"),
    pytest.param("-x - k*y", "[dynamics] y: unknown name 'k' (declared names: x, y; a constant is declared in "
                             "[parameters])", id="undeclared constant"),
])
def test_a_refused_expression_says_what_to_write(tmp_path: Path, rhs: str, said: str) -> None:
    assert refusal(model_file(tmp_path, rhs)) == said


def test_outside_dynamics_a_function_or_pi_gets_the_sections_rule(tmp_path: Path) -> None:
    """In ``[sets]`` functions are refused, so the attribute message says that too."""
    sets = '[domain]\nx = [-1, 1]\ny = [-1, 1]\n[sets]\ninitial = ["x**2 + y**2 <= 0.01"]\nunsafe = ["{}"]\n'
    line = refusal(model_file(tmp_path, "-x - y", extra=sets.format("x >= math.sin(y)")))
    assert line.startswith("[sets] unsafe: in 'x >= math.sin(y)': function call 'math.sin(y)': attribute access "
                           "('math.') is not part of the language, and here the expression must be polynomial")
    line = refusal(model_file(tmp_path, "-x - y", extra=sets.format("x >= pi")))
    assert line == ("[sets] unsafe: in 'x >= pi': the constant 'pi' is not allowed here: the expression must be "
                    "polynomial or rational in the states (pi is taken in [dynamics], in an argument of sin or cos)")


def test_a_discrete_time_map_is_read_as_a_map_not_as_an_ode(tmp_path: Path) -> None:
    """``x+ = y, y+ = -x/2``: quadratic is decided with its discrete-time condition (GES of the map, eigenvalues of
    modulus 1/sqrt(2)); roa is then the whole state space, as in continuous time; sos_bound (its discrete-time
    condition: tests/test_discrete_bounds.py) is not_applicable for want of [disturbances], never run as an ODE."""
    done = CliRunner().invoke(app.cli, ["certify", str(model_file(tmp_path, "-x/2", head='time = "discrete"')),
                                        "--classes", "quadratic,roa,sos_bound", "--no-store", "--json"])
    assert done.exit_code == 0, done.output
    quadratic, roa, bound = (json.loads(done.stdout)["conditions"][name] for name in ("quadratic", "roa", "sos_bound"))
    assert quadratic["status"] == "certified" and quadratic["summary"].startswith("GES of the discrete-time map")
    assert roa["status"] == "not_applicable" and "the region of attraction is the whole state space" in roa["summary"]
    assert bound["status"] == "not_applicable" and "the model has no [disturbances]" in bound["summary"]


@pytest.mark.parametrize(("time", "got"), [('"sampled"', "'sampled'"), ("1", "1"),
                                           ('["continuous"]', "['continuous']"), ('"Discrete-time"', "'Discrete-time'")])
def test_another_time_is_refused_naming_the_supported_ones(tmp_path: Path, time: str, got: str) -> None:
    assert refusal(model_file(tmp_path, "-x - y", head=f"time = {time}")) == \
        f'[model] time: must be one of "continuous", "discrete", got {got}'


def test_continuous_time_is_the_default_and_is_accepted(tmp_path: Path) -> None:
    assert TIME_KINDS == ("continuous", "discrete")
    for head in ("", 'time = "continuous"'):
        done = CliRunner().invoke(app.cli, ["certify", str(model_file(tmp_path, "-x - y", head=head)), "--classes",
                                            "quadratic", "--no-store", "--json"])
        assert done.exit_code == 0, done.output
        assert json.loads(done.stdout)["conditions"]["quadratic"]["status"] == "certified"
