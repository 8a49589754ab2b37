"""``certify --maximize`` / ``--minimize`` (issue 45, item 3): the largest or smallest value of one
parameter at which certify succeeds, by bisection with an exact certification at each value."""

from __future__ import annotations

import json
from fractions import Fraction
from pathlib import Path

import pytest
from click.testing import CliRunner

from lyapcheck.cli import app
from lyapcheck.errors import InvalidParameter
from lyapcheck.models.surfaces import extremum

ROOT = Path(__file__).resolve().parents[1]
OSCILLATOR = ROOT / "examples" / "models" / "damped-oscillator.toml"  # LES exactly when c > 0 and k > 0
app._register_commands()
RUNNER = CliRunner()


def test_the_bisection_keeps_what_each_value_decided() -> None:
    """A property true exactly for values above 0.3: the answer brackets 0.3, every value tried was
    decided where it was tried, and the first value that failed is the closest one."""
    tried: list[str] = []

    def certify_at(value: str) -> tuple[dict, bool, str]:
        tried.append(value)
        ok = Fraction(value) > Fraction(3, 10)
        return {"verdict": "certified" if ok else "not_certified"}, ok, value

    found = extremum.search("c", Fraction(0), Fraction(1), "min", certify_at, steps=8)
    assert tried[:2] == ["0", "1"]  # the far end first (min: LO), then the near end
    assert found.proved is not None and found.failed is not None
    assert Fraction(3, 10) < found.proved <= Fraction(3, 10) + Fraction(1, 2 ** 8)
    assert found.failed.value <= Fraction(3, 10) and found.failed.outcome == "not proved"
    assert found.proved_result == extremum.decimal(found.proved)
    assert all(Fraction(s.value) > Fraction(3, 10) for s in found.steps if s.passed)


def test_a_far_end_that_passes_is_the_answer_and_one_that_is_refuted_is_said() -> None:
    found = extremum.search("k", Fraction(1), Fraction(2), "max", lambda v: ({"verdict": "certified"}, True, None))
    assert found.proved == 2 and found.failed is None and len(found.steps) == 1
    found = extremum.search("k", Fraction(1), Fraction(2), "max", lambda v: ({"verdict": "unstable"}, False, None))
    assert found.proved is None and found.failed is not None and found.failed.outcome == "refuted"
    assert "no value was proved" in found.sentence()


@pytest.mark.parametrize("text", ["c=1..0", "c=1/3..1", "c", "c=0..x", "=0..1"])
def test_a_bad_range_is_one_line_naming_the_flag(text: str) -> None:
    with pytest.raises(InvalidParameter) as raised:
        extremum.parse_range(text, "maximize")
    assert "maximize" in str(raised.value)


def test_the_smallest_damping_proved_on_the_oscillator(tmp_path: Path) -> None:
    out = tmp_path / "cert.json"
    done = RUNNER.invoke(app.cli, ["certify", str(OSCILLATOR), "--classes", "linearization", "--minimize", "c=-1..1",
                                   "--steps", "4", "--out", str(out), "--json"])
    assert done.exit_code == 0, done.output
    doc = json.loads(done.output)
    ext = doc["extremum"]
    assert ext["proved"] == "0.125" and ext["failed"] == "0"  # 1, then -1 (refuted), 0, 0.5, 0.25, 0.125
    outcomes = {s["value"]: s["outcome"] for s in ext["steps"]}
    assert outcomes["-1"] == "refuted" and outcomes["0"] == "not proved" and outcomes["1"] == "proved"
    cert = json.loads(out.read_text())
    assert cert["overrides"] == {"c": "0.125"} and cert["conditions"]["linearization"]["status"] == "certified"
    assert RUNNER.invoke(app.cli, ["verify", str(out)]).exit_code == 0


def test_bad_uses_exit_2_in_one_line() -> None:
    for args in (["--maximize", "c=0..1", "--minimize", "c=0..1"], ["--steps", "3"], ["--maximize", "c=0..1",
                 "--set", "c=2"], ["--maximize", "c=0..1", "--steps", "99"], ["--maximize", "nu=0..1"]):
        done = RUNNER.invoke(app.cli, ["certify", str(OSCILLATOR), "--classes", "linearization", *args])
        assert done.exit_code == 2, (args, done.output)
        assert len(done.output.strip().splitlines()) == 1, done.output


def test_an_unknown_searched_name_is_named_by_its_flag() -> None:
    done = RUNNER.invoke(app.cli, ["certify", str(OSCILLATOR), "--classes", "linearization", "--maximize", "nu=0..1"])
    assert done.exit_code == 2 and "--maximize nu: no parameter or disturbance named 'nu'" in done.output, done.output
