"""The answer to each question a model asks, the verdict and the exit code built on them (issue 40).

Each test runs a model nobody in lyapcheck's examples tuned for it: an adaptive cruise control whose
unsafe set IS reached, an unstable equilibrium, a loop asked only for its linearization; and checks
the headline, the JSON, the exit code, ``--require``, and that ``verify`` recomputes the answers."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import pytest
from click.testing import CliRunner

from lyapcheck.answers import answers_of, parse_requirements, unmet_requirements, verdict_of
from lyapcheck.api import certify, verify
from lyapcheck.cli import app
from lyapcheck.errors import InvalidParameter
from tests.acc_models import UNSAFE_ACC

#: the README's oscillator: GAS with a quartic V, no quadratic one
OSCILLATOR = '''
[model]
name = "oscillator with nonlinear damping"
states = ["x", "v"]

[parameters]
k = "2 1/s^2"
c = "0.5 1/s"

[dynamics]
x = "v"
v = "-k*x - c*(1 + x**2)*v"
'''

app._register_commands()


def _cli(args: list[str]) -> Any:
    return CliRunner().invoke(app.cli, args)


EXAMPLES = Path(__file__).resolve().parents[1] / "examples" / "models"


@pytest.fixture(scope="module")
def acc_file(tmp_path_factory: pytest.TempPathFactory) -> Path:
    path = tmp_path_factory.mktemp("acc") / "acc.toml"
    path.write_text(UNSAFE_ACC)
    return path


@pytest.fixture(scope="module")
def acc_doc(acc_file: Path) -> dict[str, Any]:
    return certify(model=acc_file, classes="linearization,quadratic,barrier").to_json()


def test_an_unsafe_model_is_never_certified(acc_doc: dict[str, Any]) -> None:
    assert acc_doc["conditions"]["quadratic"]["status"] == "certified"  # stable, and yet unsafe
    assert acc_doc["conditions"]["barrier"]["status"] == "counterexample"
    assert acc_doc["verdict"] == "unsafe"
    answers = acc_doc["answers"]
    assert answers["stability"]["answer"] == "global" and answers["stability"]["property"] == "GES"
    assert answers["safety"]["answer"] == "unsafe" and answers["safety"]["by"] == "barrier"
    assert answers["safety"]["text"].startswith("UNSAFE: ")


def test_the_unsafe_model_exits_1_with_the_answers_in_the_headline(acc_file: Path) -> None:
    run = _cli(["certify", str(acc_file), "--classes", "quadratic,barrier"])
    assert run.exit_code == 1, run.output
    out = " ".join(run.output.split())
    assert "stability: global" in out and "safety: unsafe - UNSAFE" in out
    assert "verdict: unsafe" in out and "verdict: certified" not in out


def test_a_barrier_asked_alone_speaks_of_safety_not_stability(acc_file: Path) -> None:
    run = _cli(["certify", str(acc_file), "--classes", "barrier"])
    assert run.exit_code == 1
    out = " ".join(run.output.split())
    assert "safety: unsafe" in out and "stability" not in out.split("verdict")[-1]
    assert "stability certificate" not in out


def test_verify_recomputes_the_answers_and_the_verdict(acc_doc: dict[str, Any], tmp_path: Path) -> None:
    assert verify(acc_doc).valid
    for edit in ({"verdict": "certified"},
                 {"answers": {**acc_doc["answers"], "safety": {**acc_doc["answers"]["safety"], "answer": "safe"}}},
                 {"answers": {"stability": acc_doc["answers"]["stability"]}}):
        forged = {**acc_doc, **edit}
        result = verify(forged)
        assert not result.valid, edit
        assert any(not c.ok and c.check in ("verdict", "answers") for c in result.checks)


def test_an_unstable_equilibrium_is_a_negative_answer() -> None:
    result = certify(model=EXAMPLES / "unstable-van-der-pol.toml", classes="linearization")
    assert result.verdict == "unstable"
    assert result.answers["stability"]["answer"] == "unstable"
    run = _cli(["certify", str(EXAMPLES / "unstable-van-der-pol.toml"), "--classes",
                                    "linearization"])
    assert run.exit_code == 1 and "stability: unstable" in " ".join(run.output.split())


def test_the_linearization_alone_says_local(tmp_path: Path) -> None:
    path = tmp_path / "osc.toml"
    path.write_text(OSCILLATOR)
    result = certify(model=path, classes="linearization")
    assert result.verdict == "certified_local"
    assert result.answers["stability"]["answer"] == "local"
    assert "neighbourhood it holds in is unknown" in result.answers["stability"]["text"]
    run = _cli(["certify", str(path), "--classes", "linearization"])
    assert run.exit_code == 0
    assert "locally stable only" in " ".join(run.output.split())
    # LES is not GAS: a CI job that needs a global answer gets exit 1
    run = _cli(["certify", str(path), "--classes", "linearization", "--require", "GAS"])
    assert run.exit_code == 1 and "required but not proved: GAS" in " ".join(run.output.split())


def test_require_is_met_by_a_stronger_property_and_not_by_a_weaker(tmp_path: Path) -> None:
    path = tmp_path / "osc.toml"
    path.write_text(OSCILLATOR)
    base = ["certify", str(path), "--classes", "sos_gas", "--no-store"]
    assert _cli([*base, "--require", "GAS,ROA"]).exit_code == 0
    run = _cli([*base, "--require", "GES", "--json"])
    assert run.exit_code == 1 and json.loads(run.output)["verdict"] == "certified"


def test_degree_caps_the_search_and_the_reason_names_the_next_degree(tmp_path: Path) -> None:
    path = tmp_path / "osc.toml"
    path.write_text(OSCILLATOR)
    capped = certify(model=path, classes="sos_gas", degree=2).conditions["sos_gas"]
    assert capped.status == "not_certified"
    assert "--degree 4" in capped.summary
    found = certify(model=path, classes="sos_gas").conditions["sos_gas"]
    assert found.status == "certified" and found.numbers["degree"] == 4


@pytest.mark.parametrize("flag, value, field", [("--degree", "1", "degree"), ("--degree", "x", "degree"),
                                                ("--time-limit", "0", "time-limit"),
                                                ("--time-limit", "nan", "time-limit"),
                                                ("--require", "stable", "require")])
def test_bad_options_are_one_line_errors(tmp_path: Path, flag: str, value: str, field: str) -> None:
    path = tmp_path / "osc.toml"
    path.write_text(OSCILLATOR)
    run = _cli(["certify", str(path), flag, value])
    assert run.exit_code == 2
    lines = [line for line in run.output.splitlines() if line.strip()]
    assert len(lines) == 1 and f"'{field}'" in lines[0] and repr(value) in lines[0]


def test_time_limit_reaches_the_classes(tmp_path: Path) -> None:
    path = tmp_path / "osc.toml"
    path.write_text(OSCILLATOR)
    # a limit no search can meet: each searching class is inconclusive and says it was the time
    result = certify(model=path, classes="quadratic,sos_gas", time_limit_s=1e-9)
    for name in ("quadratic", "sos_gas"):
        assert result.conditions[name].status == "inconclusive", result.conditions[name].summary
        assert "time" in result.conditions[name].summary


def test_answers_from_conditions_alone() -> None:
    region = {"status": "certified", "property": "ROA", "roa_share": 0.5, "ball_radius": 0.25}
    refuted_global = {"status": "refuted", "property": "GAS"}
    les = {"status": "certified", "property": "LES"}
    answers = answers_of({"linearization": les, "sos_gas": refuted_global, "roa": region})
    # a class refuted inside a positive answer is part of it, not a negative one
    assert answers["stability"]["answer"] == "region" and answers["stability"]["by"] == "roa"
    assert "50 % of the simulated region of attraction" in answers["stability"]["text"]
    assert verdict_of({"linearization": les, "sos_gas": refuted_global, "roa": region}) == "certified"
    nominal = {"status": "certified", "property": "GAS", "disturbances": "zero"}
    assert "with every disturbance held at 0" in answers_of({"sos_gas": nominal})["stability"]["text"]
    assert verdict_of({"sos_gas": nominal}) == "certified_nominal"
    assert answers_of({"sos_bound": {"status": "not_applicable"}}) == {}
    assert verdict_of({}) == "not_certified"


def test_requirements_are_a_ladder() -> None:
    gas = {"sos_gas": {"status": "certified", "property": "GAS"}}
    assert unmet_requirements(gas, parse_requirements("GAS,ROA")) == []
    assert unmet_requirements(gas, parse_requirements("GES, LES")) == ["GES", "LES"]
    with pytest.raises(InvalidParameter, match="'require'"):
        parse_requirements("GAS,bogus")
