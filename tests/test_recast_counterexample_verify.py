"""``verify`` re-simulates the counterexample of a loop with functions (issue 41, one pipeline) as it does a
polynomial loop's: on the true loop (each function evaluated by numpy, the disturbances at 0), from its start
alone, stopped at the goal for reach_avoid, and over a box at the point of the box where it was found. It used
to accept one as stated: an edited start, time, point, disturbance or point of the box now fails its row
(exit 1)."""

from __future__ import annotations

import copy
import hashlib
import json
from pathlib import Path
from typing import Any, Callable

import pytest
from click.testing import CliRunner, Result

from lyapcheck import api
from lyapcheck.cli import app
from lyapcheck.models.surfaces.certificate import verify_document
from tests.recast_loops import PENDULUM, SPRING
from tests.test_recast_box_safety import PULSE

app._register_commands()

#: a lightly damped pendulum (b = 0.2) let go near 2.5 rad swings through theta = -0.5 on its way back
SWINGING = PENDULUM.replace("b = 1", "b = 0.2")
PENDULUM_SETS = '[sets]\ninitial = ["(theta - 2.5)**2 + omega**2 <= 0.01"]\nunsafe = ["theta <= -0.5"]\n'
#: the same pendulum pushed by a bounded torque d (the claims are its nominal loop's, d = 0)
PUSHED = SWINGING.replace('b*omega"', 'b*omega + d"') + "[disturbances]\nd = 0.1\n"
#: x'' = -sin x - x - x' from x1 near 2 overshoots through x1 = -0.5 before it settles into the goal
SPRING_SETS = ('[sets]\ninitial = ["(x1 - 2)**2 + x2**2 <= 0.25"]\nunsafe = ["x1 <= -0.5"]\n'
               'goal = ["x1**2 + x2**2 <= 0.1"]\n')

Change = Callable[[dict[str, Any]], None]


def run_cli(*args: str) -> Result:
    return CliRunner().invoke(app.cli, list(args))


def certify(tmp_path: Path, name: str, text: str, cls: str) -> tuple[dict[str, Any], Path]:
    """The document of ``certify FILE --classes cls`` (a counterexample: exit 1) and its path."""
    model, out = tmp_path / f"{name}.toml", tmp_path / f"{name}.json"
    model.write_text(text)
    result = run_cli("certify", str(model), "--classes", cls, "--out", str(out))
    doc = json.loads(out.read_text())
    assert result.exit_code == 1 and doc["conditions"][cls]["status"] == "counterexample", result.output
    assert "true loop" in doc["conditions"][cls]["summary"]
    return doc, out


def verify_forged(tmp_path: Path, doc: dict[str, Any], cls: str, change: Change) -> Result:
    """``verify`` of the document with its counterexample's refutation changed by ``change``."""
    forged = copy.deepcopy(doc)
    change(forged["conditions"][cls]["refutation"])
    path = tmp_path / "forged.json"
    path.write_text(json.dumps(forged))
    return run_cli("verify", str(path))


def rejected(result: Result, cls: str, words: str) -> None:
    """verify exits 1 and its row for ``cls`` names what is wrong (``words``)."""
    assert result.exit_code == 1, result.output
    assert f"{cls}: " in result.output and words in result.output, result.output


@pytest.fixture(scope="module")
def swinging(tmp_path_factory: pytest.TempPathFactory) -> tuple[dict[str, Any], Path]:
    return certify(tmp_path_factory.mktemp("swinging"), "swinging", SWINGING + PENDULUM_SETS, "barrier")


def test_a_barrier_counterexample_is_re_simulated_on_the_true_loop(swinging: tuple[dict[str, Any], Path]) -> None:
    doc, out = swinging
    checked = run_cli("verify", str(out))
    assert checked.exit_code == 0, checked.output
    row = next(why for name, ok, why in verify_document(doc) if name == "barrier")
    assert row.startswith("the counterexample re-simulated from its start and disturbance enters the unsafe set at")


@pytest.mark.parametrize(("change", "words"), [
    # another start of the initial set: its trajectory enters elsewhere and at another time
    (lambda r: r["start"].__setitem__(1, r["start"][1] + 0.02), "not at the stated"),
    (lambda r: r.__setitem__("start", [2.0, 0.0]), "not in the initial set"),
    # an earlier time: by then the trajectory has not entered; a later one: it entered before
    (lambda r: r.__setitem__("time", r["time"] / 2), "does not enter the unsafe set by t ="),
    (lambda r: r.__setitem__("time", r["time"] * 1.5), "not at the stated"),
    (lambda r: r["point"].__setitem__(1, r["point"][1] + 0.1), "not at the stated"),
    # the loop has no disturbance: the simulated one has none
    (lambda r: r.__setitem__("disturbance", {"kind": "constant", "values": [[0.1]], "switch_times": []}),
     "the disturbance's kind must be 'none'"),
    # no box: no point of one
    (lambda r: r.__setitem__("parameters", {"b": "0.2"}), "the document has no box"),
])
def test_an_edited_barrier_counterexample_is_rejected(tmp_path: Path, swinging: tuple[dict[str, Any], Path],
                                                      change: Change, words: str) -> None:
    rejected(verify_forged(tmp_path, swinging[0], "barrier", change), "barrier", words)


def test_a_disturbed_loops_counterexample_is_its_nominal_loops(tmp_path: Path) -> None:
    """The claims of a loop with functions are made with its disturbances at 0, and its falsification
    simulates that loop: a counterexample under some other admissible disturbance is not what it simulated."""
    doc, out = certify(tmp_path, "pushed", PUSHED + PENDULUM_SETS, "barrier")
    assert doc["conditions"]["barrier"]["refutation"]["disturbance"]["kind"] == "none"
    assert run_cli("verify", str(out)).exit_code == 0
    pushed = verify_forged(tmp_path, doc, "barrier", lambda r: r.__setitem__(
        "disturbance", {"kind": "constant", "values": [[0.1]], "switch_times": []}))
    rejected(pushed, "barrier", "simulated with its disturbances at 0 (d = 0)")


def test_a_reach_avoid_counterexample_is_re_simulated_until_the_goal(tmp_path: Path) -> None:
    doc, out = certify(tmp_path, "spring", SPRING + SPRING_SETS, "reach_avoid")
    checked = run_cli("verify", str(out))
    assert checked.exit_code == 0 and "enters the unsafe set before it reaches the goal" in checked.output, \
        checked.output
    moved = verify_forged(tmp_path, doc, "reach_avoid", lambda r: r["start"].__setitem__(0, r["start"][0] - 0.02))
    rejected(moved, "reach_avoid", "not at the stated")
    early = verify_forged(tmp_path, doc, "reach_avoid", lambda r: r.__setitem__("time", r["time"] / 2))
    rejected(early, "reach_avoid", "does not enter the unsafe set before it reaches the goal")

    # the replay stops at the goal: with a goal the trajectory reaches before the unsafe set (x1 <= 0, the
    # text re-hashed), the same trajectory is no counterexample of reach_avoid, while the barrier's replay
    # (not stopped) still finds it
    text = doc["model"]["text"].replace('goal = ["x1**2 + x2**2 <= 0.1"]', 'goal = ["x1 <= 0"]')
    assert text != doc["model"]["text"]
    regoaled = copy.deepcopy(doc)
    regoaled["model"].update(text=text, sha256=hashlib.sha256(text.encode()).hexdigest())
    rows = {name: (ok, why) for name, ok, why in verify_document(regoaled)}
    assert rows["model"][0]
    ok, why = rows["reach_avoid"]
    assert not ok and "does not enter the unsafe set before it reaches the goal" in why, why
    as_barrier = copy.deepcopy(regoaled)
    as_barrier["conditions"]["barrier"] = {**as_barrier["conditions"].pop("reach_avoid"), "property": "safety"}
    rows = {name: (ok, why) for name, ok, why in verify_document(as_barrier)}
    assert rows["barrier"][0], rows["barrier"]


def test_a_counterexample_over_a_box_is_re_simulated_at_its_point_of_the_box(tmp_path: Path) -> None:
    """PULSE enters x1 >= 1 only for a above about 1.7: its counterexample over [0.5, 2.5] is found at the
    corner a = 2.5, and re-simulated there; at the centre, or outside the box, it is rejected."""
    path = tmp_path / "pulse.toml"
    path.write_text(PULSE)
    result = api.certify(model=path, box=["a=0.5..2.5"], classes="barrier")
    c = result.conditions["barrier"]
    assert c.status == "counterexample" and c.refutation["parameters"] == {"a": "2.5"}, c.summary
    out = tmp_path / "pulse.json"
    out.write_text(json.dumps(result.document))
    checked = run_cli("verify", str(out))
    assert checked.exit_code == 0 and "(the true loop at a = 2.5)" in checked.output, checked.output
    doc = result.document
    centre = verify_forged(tmp_path, doc, "barrier", lambda r: r.__setitem__("parameters", {"a": "1.5"}))
    rejected(centre, "barrier", "does not enter the unsafe set by t =")
    beyond = verify_forged(tmp_path, doc, "barrier", lambda r: r.__setitem__("parameters", {"a": "3"}))
    rejected(beyond, "barrier", "the parameter a = 3 is not a point of the box")
    unnamed = verify_forged(tmp_path, doc, "barrier", lambda r: r.pop("parameters"))
    rejected(unnamed, "barrier", "names the point of the box where it was found")
    # a point whose exact value would take minutes to build is refused before it is read: the whole
    # document, naming the field (lyapcheck.exact.refuse_oversized_numbers)
    huge = verify_forged(tmp_path, doc, "barrier", lambda r: r.__setitem__("parameters", {"a": "1e999999999"}))
    assert huge.exit_code == 1 and "conditions.barrier.refutation.parameters.a writes a number with a decimal " \
        "exponent beyond" in huge.output, huge.output
    # a point written otherwise than as a plain decimal is refused by the counterexample's own check
    odd = verify_forged(tmp_path, doc, "barrier", lambda r: r.__setitem__("parameters", {"a": "25e-1"}))
    rejected(odd, "barrier", "is not a plain decimal number")
