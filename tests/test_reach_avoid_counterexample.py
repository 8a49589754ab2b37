"""reach_avoid of a polynomial loop answers "fails" with a counterexample (issue 41, one pipeline): the
trajectories from the initial set are simulated first, each until it reaches the goal
(:func:`lyapcheck.models.classes.falsify.falsify`'s ``stop``); one into the unsafe set before the goal is a
``counterexample`` (exit 1) that verify re-simulates from its start and disturbance, and an entry after the
goal is no soundness alarm beside a certificate."""

from __future__ import annotations

import copy
import json
import math
from pathlib import Path
from typing import Any

import numpy as np
from click.testing import CliRunner, Result

from lyapcheck.cli import app
from lyapcheck.models.classes.falsify import falsify
from lyapcheck.models.language.modelfile import parse_model
from lyapcheck.models.language.sets import margin

app._register_commands()

#: x1' = -x1 + x2, x2' = -x1 - x2 (+ d): x(t) = exp(-t) R(t) x(0), R(t) the clockwise rotation by t
SPIRAL = """[model]
name = "spiral"
states = ["x1", "x2"]
[dynamics]
x1 = "-x1 + x2"
x2 = "-x1 - x2{d}"
[sets]
initial = ["(x1 - 2)**2 + x2**2 <= 0.25"]
unsafe = ["x2 <= -0.5"]
goal = ["x1**2 + x2**2 <= 0.1"]
"""
#: x' = -x from [1.5, 2]: the goal x <= 1 is reached at t = ln(x0), the unsafe [0.4, 0.5] only later, at
#: t >= ln(x0 / 0.5)
AFTER_GOAL = """[model]
name = "after the goal"
states = ["x"]
[dynamics]
x = "-x"
[sets]
initial = ["1.5 <= x <= 2"]
unsafe = ["0.4 <= x <= 0.5"]
goal = ["x <= 1"]
"""


def run_cli(*args: str) -> Result:
    return CliRunner().invoke(app.cli, list(args))


def certify(tmp_path: Path, name: str, text: str) -> tuple[Result, dict[str, Any], Path]:
    model = tmp_path / f"{name}.toml"
    model.write_text(text)
    out = tmp_path / f"{name}.json"
    result = run_cli("certify", str(model), "--classes", "reach_avoid", "--out", str(out), "--no-store")
    return result, json.loads(out.read_text()), out


def verify_forged(tmp_path: Path, doc: dict[str, Any], change: Any) -> Result:
    forged = copy.deepcopy(doc)
    change(forged["conditions"]["reach_avoid"]["refutation"])
    path = tmp_path / "forged.json"
    path.write_text(json.dumps(forged))
    return run_cli("verify", str(path))


def spiral_at(start: np.ndarray, t: float) -> np.ndarray:
    c, s = math.cos(t), math.sin(t)
    return math.exp(-t) * np.array([c * start[0] + s * start[1], -s * start[0] + c * start[1]])


def test_an_unsafe_set_crossed_before_the_goal_is_a_counterexample_verify_re_simulates(tmp_path: Path) -> None:
    result, doc, out = certify(tmp_path, "crossed", SPIRAL.format(d=""))
    assert result.exit_code == 1, result.output
    assert "FAILS" in result.output
    ra = doc["conditions"]["reach_avoid"]
    assert ra["status"] == "counterexample" and ra["property"] == "reach_avoid", ra["summary"]
    assert doc["answers"]["reach_avoid"]["answer"] == "fails" and doc["verdict"] == "unsafe"
    assert "before it reaches the goal" in ra["summary"]
    ref = ra["refutation"]
    start, t = np.array(ref["start"]), ref["time"]
    assert (start[0] - 2) ** 2 + start[1] ** 2 <= 0.25  # a start in the initial set
    # the closed form: at the stated time the trajectory is at the stated point, on the unsafe set's edge,
    # and it is outside the goal all the way there
    assert np.allclose(spiral_at(start, t), ref["point"], atol=1e-6) and ref["point"][1] <= -0.5 + 1e-6
    assert all(np.sum(spiral_at(start, s) ** 2) > 0.1 for s in np.linspace(0, t, 50))
    verified = run_cli("verify", str(out))
    assert verified.exit_code == 0, verified.output
    assert "re-simulated" in verified.output

    # tampered: another start (inside the initial set, whose trajectory enters elsewhere), a start outside it
    moved = verify_forged(tmp_path, doc, lambda r: r["start"].__setitem__(0, r["start"][0] + 0.01))
    assert moved.exit_code == 1 and "not at the stated" in moved.output, moved.output
    away = verify_forged(tmp_path, doc, lambda r: r.__setitem__("start", [2.0, 0.4]))
    assert away.exit_code == 1 and "does not enter the unsafe set before it reaches the goal" in away.output
    outside = verify_forged(tmp_path, doc, lambda r: r.__setitem__("start", [2.0, -0.6]))
    assert outside.exit_code == 1 and "not in the initial set" in outside.output, outside.output


def test_a_disturbed_counterexample_is_re_simulated_with_its_disturbance(tmp_path: Path) -> None:
    result, doc, out = certify(tmp_path, "disturbed", SPIRAL.format(d=" + d") + "[disturbances]\nd = 0.1\n")
    assert result.exit_code == 1, result.output
    ref = doc["conditions"]["reach_avoid"]["refutation"]
    assert ref["disturbance"]["kind"] in ("constant", "bang-bang")
    verified = run_cli("verify", str(out))
    assert verified.exit_code == 0, verified.output
    # a disturbance beyond its bound is not one the claim covers
    beyond = verify_forged(tmp_path, doc, lambda r: r["disturbance"]["values"][0].__setitem__(0, 0.5))
    assert beyond.exit_code == 1 and "within its declared bound" in beyond.output, beyond.output


def test_entering_the_unsafe_set_after_the_goal_raises_no_alarm(tmp_path: Path) -> None:
    model = parse_model(AFTER_GOAL, "after", {})
    sets = model.sets
    # every simulated trajectory does enter the unsafe set, after the goal: watched to the end, it counts
    whole = falsify(model, sets["initial"], sets["unsafe"], margin, samples=20)
    assert whole.entries == whole.trajectories
    stopped = falsify(model, sets["initial"], sets["unsafe"], margin, samples=20, stop=sets["goal"])
    assert stopped.entry is None and stopped.closest_approach < 0
    assert abs(stopped.closest.point[0] - 1) < 1e-3  # where the trajectories stop: the goal's edge x = 1

    result, doc, out = certify(tmp_path, "after", AFTER_GOAL)
    ra = doc["conditions"]["reach_avoid"]
    assert ra["status"] in ("certified", "not_certified"), ra["summary"]
    assert "soundness_violation" not in ra and ra["falsification"]["entry"] is None
    if ra["status"] == "certified":
        assert result.exit_code == 0, result.output
        assert "SOUNDNESS" not in result.output
        assert run_cli("verify", str(out)).exit_code == 0


def test_a_barrier_counterexample_is_re_simulated_by_verify_too(tmp_path: Path) -> None:
    """The barrier's counterexample has the same form and the same check: verify re-simulates it (it used
    to accept one as stated), and a moved start is rejected."""
    text = SPIRAL.format(d="").replace('goal = ["x1**2 + x2**2 <= 0.1"]\n', "")
    model, out = tmp_path / "spiral-barrier.toml", tmp_path / "spiral-barrier.json"
    model.write_text(text)
    result = run_cli("certify", str(model), "--classes", "barrier", "--out", str(out))
    doc = json.loads(out.read_text())
    assert result.exit_code == 1 and doc["conditions"]["barrier"]["status"] == "counterexample", result.output
    checked = run_cli("verify", str(out))
    assert checked.exit_code == 0 and "the counterexample re-simulated" in checked.output, checked.output
    forged = copy.deepcopy(doc)
    forged["conditions"]["barrier"]["refutation"]["start"][0] += 0.01
    out.write_text(json.dumps(forged))
    moved = run_cli("verify", str(out))
    assert moved.exit_code == 1 and "barrier: re-simulated from its start" in moved.output, moved.output
