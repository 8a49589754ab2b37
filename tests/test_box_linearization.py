"""``linearization`` over a box of parameters (issue 45, item 1): the Hurwitz conditions of J(u) proved
positive on the whole box by exact Bernstein coefficients, a refutation at a point of the box, and
``verify`` of both."""

from __future__ import annotations

import json
from fractions import Fraction
from pathlib import Path

import pytest
from click.testing import CliRunner

from lyapcheck.cli import app
from lyapcheck.models.engines.bernstein import bernstein_coefficients, positive_on_box

ROOT = Path(__file__).resolve().parents[1]
PID = ROOT / "examples" / "models" / "pid-hardening-spring.toml"  # Hurwitz exactly when ki < 1.5 kp
app._register_commands()
RUNNER = CliRunner()
F = Fraction
UNIT = ((F(-1), F(1)), (F(-1), F(1)))


def test_bernstein_coefficients_bound_the_polynomial_and_their_corners_are_its_values() -> None:
    q = {(2, 0): F(1), (1, 1): F(-1, 2), (0, 1): F(1, 3), (0, 0): F(1, 5)}  # x^2 - xy/2 + y/3 + 1/5
    box = ((F(-1, 2), F(1)), (F(0), F(2)))
    b = bernstein_coefficients(q, box, [2, 1])

    def value(x: Fraction, y: Fraction) -> Fraction:
        return x * x - x * y / 2 + y / 3 + F(1, 5)

    assert b[(0, 0)] == value(F(-1, 2), F(0)) and b[(2, 1)] == value(F(1), F(2))
    lo, hi = min(b.values()), max(b.values())
    for i in range(11):
        for j in range(11):
            x, y = F(-1, 2) + F(3, 2) * F(i, 10), F(2) * F(j, 10)
            assert lo <= value(x, y) <= hi


def test_positivity_on_a_box_is_proved_refuted_at_a_corner_or_left_open() -> None:
    assert positive_on_box({(2, 0): F(1), (0, 2): F(1), (0, 0): F(1, 1000)}, UNIT).proved
    found = positive_on_box({(1, 1): F(1), (0, 0): F(1, 2)}, UNIT)  # xy + 1/2 is -1/2 at (1, -1)
    assert not found.proved and found.witness is not None
    x, y = found.witness
    assert x * y + F(1, 2) <= 0
    # (x - 1/3)^2 + (y - 1/3)^2: 0 at a point no halving reaches, so neither proved nor a corner found
    q = {(2, 0): F(1), (1, 0): F(-2, 3), (0, 2): F(1), (0, 1): F(-2, 3), (0, 0): F(2, 9)}
    found = positive_on_box(q, UNIT, max_boxes=3)
    assert not found.proved and found.witness is None and found.boxes == 3


def certify(tmp_path: Path, *boxes: str) -> tuple[int, dict, Path]:
    out = tmp_path / "cert.json"
    args = ["certify", str(PID), "--classes", "linearization", "--out", str(out), "--json"]
    for b in boxes:
        args += ["--box", b]
    done = RUNNER.invoke(app.cli, args)
    return done.exit_code, json.loads(done.output), out


def test_a_box_inside_the_stable_gains_is_proved_and_verified(tmp_path: Path) -> None:
    code, doc, out = certify(tmp_path, "kp=1.5..2.5", "ki=0.5..1.5")
    lin = doc["conditions"]["linearization"]
    assert code == 0 and lin["status"] == "certified" and lin["certificate"]["method"] == "box_hurwitz"
    assert lin["certificate"]["conditions"] == ["Delta_1", "Delta_2", "a_3"]
    assert lin["summary"].startswith("for every kp in [1.5, 2.5] and ki in [0.5, 1.5]: ")
    done = RUNNER.invoke(app.cli, ["verify", str(out)])
    assert done.exit_code == 0, done.output
    # the same certificate stated for a box that reaches unstable gains fails: verify proves again
    tampered = json.loads(out.read_text())
    tampered["box"]["ki"] = ["1/2", "4"]
    bad = tmp_path / "bad.json"
    bad.write_text(json.dumps(tampered))
    assert RUNNER.invoke(app.cli, ["verify", str(bad)]).exit_code == 1


def test_a_box_that_holds_an_unstable_gain_is_refuted_there(tmp_path: Path) -> None:
    code, doc, out = certify(tmp_path, "kp=1..2", "ki=1..2")
    lin = doc["conditions"]["linearization"]
    assert code == 1 and lin["status"] == "refuted" and doc["verdict"] == "unstable"
    point = {k: Fraction(v) for k, v in lin["refutation"]["point"].items()}
    assert point["ki"] > Fraction(3, 2) * point["kp"]  # truly unstable there (Routh-Hurwitz)
    assert "a value of the box" in doc["answers"]["stability"]["text"]
    assert RUNNER.invoke(app.cli, ["verify", str(out)]).exit_code == 0
    moved = json.loads(out.read_text())
    moved["conditions"]["linearization"]["refutation"]["point"] = {"kp": "3", "ki": "1"}  # outside the box
    bad = tmp_path / "bad.json"
    bad.write_text(json.dumps(moved))
    done = RUNNER.invoke(app.cli, ["verify", str(bad)])
    assert done.exit_code == 1 and "not in the box" in done.output


@pytest.mark.parametrize("boxes", [("kp=1..2", "ki=0.5..1.5")])
def test_a_box_whose_edge_is_critical_is_not_certified_naming_the_point(tmp_path: Path, boxes: tuple[str, ...]) -> None:
    code, doc, _ = certify(tmp_path, *boxes)
    lin = doc["conditions"]["linearization"]
    assert code == 1 and lin["status"] == "not_certified"
    assert "Delta_2" in lin["summary"] and "kp = 1, ki = 1.5" in lin["summary"]  # 1.5 kp = ki there: critical
