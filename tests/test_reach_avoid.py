"""``reach_avoid`` (issue 32 item 3): the goal reached in a bounded time, the unsafe set avoided,
checked exactly; verify's refusals."""

from __future__ import annotations

import json
from pathlib import Path

from click.testing import CliRunner, Result

from lyapcheck.cli import app

app._register_commands()

SPIRAL = """[model]
name = "reach-avoid"
states = ["x1", "x2"]
[dynamics]
x1 = "-x1 + x2"
x2 = "-x1 - x2"
[sets]
initial = ["(x1 - 2)**2 + x2**2 <= 0.25"]
unsafe = ["(x1 + 1)**2 + (x2 - 2)**2 <= 0.25"]
goal = ["x1**2 + x2**2 <= 0.1"]
"""


def run_cli(*args: str) -> Result:
    return CliRunner().invoke(app.cli, list(args))


def test_reach_avoid_is_certified_with_a_time_bound_and_verify_refuses_a_shorter_one(tmp_path: Path) -> None:
    model = tmp_path / "ra.toml"
    model.write_text(SPIRAL)
    out = tmp_path / "ra.json"
    result = run_cli("certify", str(model), "--classes", "reach_avoid", "--out", str(out))
    assert result.exit_code == 0, result.output
    doc = json.loads(out.read_text())
    ra = doc["conditions"]["reach_avoid"]
    assert ra["status"] == "certified" and ra["property"] == "reach_avoid"
    # the linear spiral contracts |x| like exp(-t): from |x| <= 2.5 into |x|^2 <= 0.1 by t = ln(2.5 / 0.316)
    # = 2.07 s; the certified bound C / eps is larger (conservative) and never smaller
    assert ra["reach_time_bound_s"] >= 2.07 and ra["closest_approach"] < 0
    assert run_cli("verify", str(out)).exit_code == 0
    ra["reach_time_bound_s"] = 1.0
    ra["summary"] = ra["summary"].replace(ra["summary"].split("within ")[1].split(" s")[0], "1")
    forged = tmp_path / "forged.json"
    forged.write_text(json.dumps(doc))
    result = run_cli("verify", str(forged))
    assert result.exit_code == 1 and "time bound" in result.output


def test_a_goal_that_trajectories_leave_is_not_certified(tmp_path: Path) -> None:
    # x' = x: from x in [1, 2] the state grows; the goal near 0 is never reached
    model = tmp_path / "away.toml"
    model.write_text('[model]\nname = "away"\nstates = ["x"]\n[dynamics]\nx = "x"\n'
                     '[sets]\ninitial = ["1 <= x <= 2"]\nunsafe = ["x <= -5"]\ngoal = ["x**2 <= 0.01"]\n')
    out = tmp_path / "away.json"
    run_cli("certify", str(model), "--classes", "reach_avoid", "--out", str(out))
    assert json.loads(out.read_text())["conditions"]["reach_avoid"]["status"] == "not_certified"


def test_reach_avoid_over_a_box_of_parameters(tmp_path: Path) -> None:
    model = tmp_path / "ra.toml"
    model.write_text(SPIRAL.replace('x2 = "-x1 - x2"', 'x2 = "-k*x1 - x2"') + "[parameters]\nk = 1\n")
    out = tmp_path / "box.json"
    result = run_cli("certify", str(model), "--box", "k=0.5..1.5", "--classes", "reach_avoid", "--out", str(out))
    assert result.exit_code == 0, result.output
    ra = json.loads(out.read_text())["conditions"]["reach_avoid"]
    assert ra["status"] == "certified" and ra["summary"].startswith("for every k in [0.5, 1.5]")
    assert run_cli("verify", str(out)).exit_code == 0


def test_stay_in_goal_is_proved_by_an_invariant_set_inside_the_goal(tmp_path: Path) -> None:
    """[sets] stay_in_goal = true: the goal is reached through {W <= 0}, a set inside it around the
    equilibrium that no trajectory leaves; verify checks W, and refuses the certificate without it.
    A goal away from the equilibrium cannot be stayed in (here: not certified, saying why)."""
    model = tmp_path / "stay.toml"
    model.write_text(SPIRAL + "stay_in_goal = true\n")
    out = tmp_path / "stay.json"
    result = run_cli("certify", str(model), "--classes", "reach_avoid", "--out", str(out))
    assert result.exit_code == 0, result.output
    doc = json.loads(out.read_text())
    ra = doc["conditions"]["reach_avoid"]
    assert ra["status"] == "certified" and "stays in the goal afterwards" in ra["summary"]
    assert "W" in ra["certificate"]["stay"]
    assert run_cli("verify", str(out)).exit_code == 0
    del ra["certificate"]["stay"]
    forged = tmp_path / "forged.json"
    forged.write_text(json.dumps(doc))
    assert run_cli("verify", str(forged)).exit_code == 1
    away = tmp_path / "away.toml"
    away.write_text(SPIRAL.replace('goal = ["x1**2 + x2**2 <= 0.1"]', 'goal = ["(x1 - 1)**2 + x2**2 <= 0.1"]')
                    + "stay_in_goal = true\n")
    run_cli("certify", str(away), "--classes", "reach_avoid", "--out", str(out))
    ra = json.loads(out.read_text())["conditions"]["reach_avoid"]
    assert ra["status"] == "not_certified" and "not inside the goal" in ra["summary"]


def test_stay_in_goal_is_a_boolean_and_needs_a_goal(tmp_path: Path) -> None:
    for extra, words in (("stay_in_goal = 1\n", "must be true or false"),):
        model = tmp_path / "bad.toml"
        model.write_text(SPIRAL + extra)
        result = run_cli("certify", str(model), "--classes", "reach_avoid")
        assert result.exit_code == 2 and words in result.output and "Traceback" not in result.output
    model = tmp_path / "nogoal.toml"
    model.write_text(SPIRAL.replace('goal = ["x1**2 + x2**2 <= 0.1"]\n', "stay_in_goal = true\n"))
    result = run_cli("certify", str(model))
    assert result.exit_code == 2 and "has no goal" in result.output
