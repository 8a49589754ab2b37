"""Reasons a user can act on (issue 40, item 5): a class that is ``not_certified`` or ``inconclusive``
says in one sentence what it tried and what to try next, naming an option that exists; the solver's
words (statuses, size-limit constants, Gram rows, refusals of the exact check, the rates tried) are
in the condition's JSON under ``detail``, never in its summary.

The runs are cheap failing cases of both routes: a polynomial loop with no polynomial Lyapunov
function (Ahmadi, Krstic & Parrilo), an adaptive cruise control whose unsafe set is reached (its
barrier search fails beside a simulated counterexample), a loop with a saturation whose global
classes fail, a lossless pendulum whose roa has nothing to start from, and a limit of time reached
before the first solve.
"""

from __future__ import annotations

import re
from pathlib import Path
from typing import Any

import pytest

from lyapcheck import api
from lyapcheck.models.engines import reasons
from lyapcheck.models.engines.reasons import NEXT
from tests.acc_models import UNSAFE_ACC
from tests.conftest import ROOT

MODELS = ROOT / "examples" / "models"

#: the solver's words, which a summary must not carry
SOLVER_WORDS = re.compile(r"HiGHS|Status \d|status \w|Clarabel|solver|BLOCK_COST|MAX_[A-Z_]+|[A-Z]+_LIMIT|"
                          r"TEMPLATE_LIMIT_S|tolerances\.|Gram|facial|Newton polytope|lam =|eps 1/|"
                          r"exact check refused|(?<!unsafe )margin -?\d")
#: the option each suggestion names (the leading words of every phrase of NEXT)
OPTIONS = re.compile(r"--degree|--candidate|--time-limit|--classes|--box|\[domain\]|\[disturbances\]|"
                     r"\[outputs\]|initial set|goal set|fewer states")

ACC = UNSAFE_ACC  # (tests/acc_models.py)


def conditions(model: Path | str, **options: Any) -> dict[str, dict[str, Any]]:
    """``certify``'s conditions (their JSON form) for a model file."""
    return api.certify_model_file(model, **options).document["conditions"]


def assert_actionable(found: dict[str, dict[str, Any]]) -> None:
    """No summary speaks solver; every not_certified or inconclusive one is one sentence that names
    something to try, and its detail (the solver's words) is in the JSON."""
    for name, c in found.items():
        assert not SOLVER_WORDS.search(c["summary"]), (name, c["summary"])
        if c["status"] in ("not_certified", "inconclusive"):
            assert "; try " in c["summary"] and OPTIONS.search(c["summary"]), (name, c["summary"])
            assert c["summary"].count(";") == 1, (name, c["summary"])  # what was tried; what to try
            assert isinstance(c["detail"], list), (name, c)


def test_no_polynomial_lyapunov_function_names_a_higher_degree_and_a_candidate() -> None:
    found = conditions(MODELS / "ahmadi-no-polynomial-lyapunov.toml", classes="quadratic,sos_gas")
    assert_actionable(found)
    gas = found["sos_gas"]
    assert gas["status"] == "not_certified"
    assert gas["summary"].startswith("no Lyapunov function of degree 2, 4, 6 or 8 was found; try a higher degree "
                                     "(--degree 10)"), gas["summary"]
    assert "--candidate" in gas["summary"]
    # the search's own words, a line per degree, in the JSON (and the older key kept)
    assert [line.split(":")[0] for line in gas["detail"]] == ["degree 2", "degree 4", "degree 6", "degree 8"]
    assert any("solver" in line for line in gas["detail"]) and gas["tried"] == gas["detail"]
    quadratic = found["quadratic"]
    assert quadratic["summary"].startswith("no quadratic Lyapunov function was found; try a V of higher degree "
                                           "(--classes sos_gas --degree 4)"), quadratic["summary"]


def test_a_lower_degree_ceiling_is_what_the_summary_says_was_searched() -> None:
    """With ``degree=4`` sos_gas searches degrees 2 and 4, and says so; the next step is 6."""
    gas = conditions(MODELS / "ahmadi-no-polynomial-lyapunov.toml", classes="sos_gas", degree=4)["sos_gas"]
    assert gas["summary"].startswith("no quadratic or quartic Lyapunov function was found; try a higher degree "
                                     "(--degree 6)"), gas["summary"]


def test_the_barrier_counterexample_keeps_its_simulation_and_drops_the_solver(tmp_path: Path) -> None:
    path = tmp_path / "acc.toml"
    path.write_text(ACC)
    found = conditions(path, classes="barrier")
    assert_actionable(found)
    barrier = found["barrier"]
    assert barrier["status"] == "counterexample"
    assert barrier["summary"].startswith("a simulated trajectory from the initial set enters the unsafe set: from h = ")
    assert barrier["summary"].endswith("(simulation, reproducible from its start and disturbance)")
    assert "no barrier was found" not in barrier["summary"]
    assert barrier["detail"] and all(line.startswith("no barrier was found: degree ") for line in barrier["detail"])
    assert any("lam =" in line for line in barrier["detail"])


def test_a_loop_with_functions_whose_global_classes_fail() -> None:
    found = conditions(MODELS / "recast-saturated-double-integrator.toml", classes="quadratic,sos_gas")
    assert_actionable(found)
    assert found["sos_gas"]["status"] == "not_certified"
    assert found["sos_gas"]["summary"].startswith("no quadratic or quartic Lyapunov function was found; try a "
                                                  "higher degree (--degree 6)"), found["sos_gas"]["summary"]
    assert all(line.startswith("degree ") and " in x1, x2" in line for line in found["sos_gas"]["detail"])
    assert found["sos_gas"]["reason"] == "; ".join(found["sos_gas"]["detail"])  # the older key, kept


def test_a_region_with_nothing_to_start_from_names_a_candidate() -> None:
    found = conditions(MODELS / "recast-lossless-pendulum.toml", classes="linearization,roa")
    assert_actionable(found)
    roa = found["roa"]
    assert roa["status"] == "not_certified" and roa["summary"].endswith('try a candidate V (--candidate "...")')


def test_a_time_limit_names_more_time() -> None:
    """A limit reached before the first solve: inconclusive, saying so in words, the constant's name
    in the detail."""
    found = conditions(MODELS / "ahmadi-no-polynomial-lyapunov.toml", classes="sos_gas", time_limit_s=1e-9)
    assert_actionable(found)
    gas = found["sos_gas"]
    assert gas["status"] == "inconclusive"
    assert gas["summary"] == ("the time limit of 1e-09 s was reached while searching for a Lyapunov function; try "
                              "more time (--time-limit SECONDS)")
    assert "MODEL_CLASS_TIME_LIMIT_S" in " ".join(gas["detail"]) and "MODEL_CLASS_TIME_LIMIT_S" in gas["reason"]


# -- the helper itself, on detail lines as the searches write them -----------------------------------

def test_a_size_limit_at_the_first_degree_is_a_problem_too_large() -> None:
    line = "degree 4: " + reasons.size_limit(67, "rows of one sum-of-squares matrix", 60, "MAX_RECAST_GRAM_ROWS")
    why = reasons.not_found("Lyapunov function", (4, 6), [line, "degree 6: " + line[10:]], ("degree", "candidate"))
    assert why.summary == ("the problem is too large for this class at degree 4: 67 rows of one sum-of-squares "
                           "matrix where the limit is 60; try a smaller degree (--degree 2) or fewer states or "
                           "functions (each function adds an auxiliary variable)")
    assert "MAX_RECAST_GRAM_ROWS" in why.detail[0] and not SOLVER_WORDS.search(why.summary)


def test_a_size_limit_above_searched_degrees_suggests_no_higher_degree() -> None:
    lines = ["degree 2: the solver proved the program infeasible",
             "degree 4: " + reasons.size_limit("3.1e+09", "work units of the program", "2.0e+09", "BLOCK_COST_LIMIT")]
    why = reasons.not_found("barrier", (2, 4, 6), lines, ("degree", "sets", "time"))
    assert why.summary == ("no quadratic barrier was found, and at degree 4 the problem is too large for this class "
                           "(3.1e+09 work units of the program where the limit is 2.0e+09); try an initial set "
                           "farther from the unsafe set or more time (--time-limit SECONDS)")
    assert why.numbers({"tried": lines}) == {"tried": lines, "detail": lines}


def test_every_suggestion_names_an_option_of_the_command_or_a_table_of_the_file() -> None:
    from lyapcheck.cli import app

    app._register_commands()
    command = app.cli.commands["certify"]
    flags = {opt for param in command.params for opt in getattr(param, "opts", ())}
    for key, phrase in NEXT.items():
        for flag in re.findall(r"--[a-z-]+", phrase):
            assert flag in flags, (key, flag)
        assert OPTIONS.search(phrase.format(degree=4)), (key, phrase)


@pytest.mark.parametrize("degrees, words", [((2,), "quadratic barrier"), ((2, 4), "quadratic or quartic barrier"),
                                            ((2, 4, 6), "barrier of degree 2, 4 or 6")])
def test_degree_words(degrees: tuple[int, ...], words: str) -> None:
    assert reasons.degree_words("barrier", degrees) == words
