"""The reach_avoid class on loops with functions (lyapcheck.models.classes.reach_avoid, the class's one
implementation for both kinds of loop): the reach-avoid conditions proved on the recasting's relations and
re-checked by verify, a changed certificate refused, one of the older format refused in one line, a
trajectory of the true loop into the unsafe set before the goal as a counterexample, a saturated loop's
reason."""

from __future__ import annotations

import hashlib
import json
from fractions import Fraction
from pathlib import Path
from typing import Any

import numpy as np
from click.testing import CliRunner, Result

from lyapcheck.cli import app
from lyapcheck.models.classes import reach_avoid
from lyapcheck.models.language.modelfile import parse_any_model
from lyapcheck.models.language.recast import RecastModel
from lyapcheck.models.surfaces.certificate import verify_document
from tests.recast_loops import PENDULUM, SPRING, rk4
from tests.test_recast_barrier import _failed, _forged

app._register_commands()

GOAL = '"x1**2 + x2**2 <= 0.1"'
INITIAL = '"(x1 - 2)**2 + x2**2 <= 0.25"'
#: x'' = -sin x - x - x' from x1 near 2 overshoots to x1 = -0.7 or so: it crosses x1 = -0.5, never x1 = -3
FAR = '"x1 <= -3"'
CROSSED = '"x1 <= -0.5"'


def run_cli(*args: str) -> Result:
    return CliRunner().invoke(app.cli, list(args))


def write(tmp_path: Path, name: str, unsafe: str = FAR, goal: str = GOAL) -> Path:
    path = tmp_path / f"{name}.toml"
    path.write_text(SPRING + f"[sets]\ninitial = [{INITIAL}]\nunsafe = [{unsafe}]\ngoal = [{goal}]\n")
    return path


def spring_field(X: np.ndarray) -> np.ndarray:
    return np.stack([X[:, 1], -np.sin(X[:, 0]) - X[:, 0] - X[:, 1]], axis=1)


def test_a_spring_with_a_sine_gets_a_reach_avoid_function_that_verify_re_checks(tmp_path: Path) -> None:
    model = write(tmp_path, "safe")
    out = tmp_path / "safe.json"
    result = run_cli("certify", str(model), "--classes", "reach_avoid", "--out", str(out))
    assert result.exit_code == 0, result.output
    assert "reach-avoid: proved" in result.output, result.output
    doc = json.loads(out.read_text())
    ra = doc["conditions"]["reach_avoid"]
    assert ra["status"] == "certified" and ra["property"] == "reach_avoid", ra["summary"]
    assert doc["answers"]["reach_avoid"]["answer"] == "proved" and doc["verdict"] == "certified"
    cert = ra["certificate"]
    bound = Fraction(cert["C"]) / Fraction(cert["eps_per_s"])
    assert cert["kind"] == reach_avoid.KIND and ra["reach_time_bound_s"] == float(bound)
    assert ra["summary"].startswith("reach-avoid: every trajectory that starts in the initial set reaches the goal")
    assert ra["falsification"]["entry"] is None and ra["closest_approach"] < 0
    assert not _failed(verify_document(doc))
    assert run_cli("verify", str(out)).exit_code == 0

    # the claim on the true loop, by an independent integrator: starts on the initial circle reach the
    # goal within the certified time and never cross x1 = -3 on the way
    angles = np.linspace(0, 2 * np.pi, 16, endpoint=False)
    X = np.stack([2 + 0.5 * np.cos(angles), 0.5 * np.sin(angles)], axis=1)
    reached = np.zeros(len(X), dtype=bool)
    step, t = 0.02, 0.0
    while t < float(bound) and not reached.all():
        X = rk4(spring_field, X, step, step)
        t += step
        assert np.all(X[~reached, 0] > -3)
        reached |= np.sum(X ** 2, axis=1) <= 0.1
    assert reached.all()

    recast = parse_any_model(model.read_text(), str(model), {})
    assert isinstance(recast, RecastModel)
    from lyapcheck.models.classes.recast_classes import v_text
    from lyapcheck.models.engines.recast_sos import poly_from_json, poly_to_json

    ring = recast.system.ring

    def shifted_v(forged: dict[str, Any]) -> None:  # V moved up by 1, its text made consistent
        c = forged["conditions"]["reach_avoid"]["certificate"]
        V = poly_from_json(ring, c["V"], "V") + ring.constant(1)
        c["V"], c["V_text"] = poly_to_json(ring, V), v_text(recast.system, V)

    def shorter_time(forged: dict[str, Any]) -> None:  # C halved: a time bound half as long, stated consistently
        c = forged["conditions"]["reach_avoid"]
        c["certificate"]["C"] = str(Fraction(c["certificate"]["C"]) / 2)
        c["reach_time_bound_s"] = float(bound / 2)
        c["summary"] = c["summary"].replace(c["summary"].split("within ")[1].split(" s")[0],
                                            f"{float(bound / 2):.4g}")

    def faster(forged: dict[str, Any]) -> None:  # eps and C doubled: the same time bound, a faster decrease
        c = forged["conditions"]["reach_avoid"]["certificate"]
        c["eps_per_s"], c["C"] = str(2 * Fraction(c["eps_per_s"])), str(2 * Fraction(c["C"]))

    def smaller_goal(forged: dict[str, Any]) -> None:  # the text's goal changed: the proofs no longer fit it
        text = forged["model"]["text"].replace("x1**2 + x2**2 <= 0.1", "x1**2 + x2**2 <= 0.001")
        forged["model"]["text"], forged["model"]["sha256"] = text, hashlib.sha256(text.encode()).hexdigest()

    def safety(forged: dict[str, Any]) -> None:
        forged["conditions"]["reach_avoid"]["property"] = "safety"

    def invented(forged: dict[str, Any]) -> None:
        forged["conditions"]["reach_avoid"]["lambda_per_s"] = 1.0

    for change, words in ((shifted_v, "V <= 0 on the initial set"), (shorter_time, "V >= delta |z|^2 - C"),
                          (faster, "V' <= -eps where goal inequality 1 fails"),
                          (smaller_goal, "V' <= -eps where goal inequality 1 fails"),
                          (safety, "property"), (invented, "lambda_per_s")):
        failed = _failed(_forged(doc, change))
        assert failed and words in failed[0], (change.__name__, failed)


def test_an_unsafe_set_crossed_before_the_goal_is_a_counterexample_on_the_true_loop(tmp_path: Path) -> None:
    model = write(tmp_path, "crossed", unsafe=CROSSED)
    out = tmp_path / "crossed.json"
    result = run_cli("certify", str(model), "--classes", "reach_avoid", "--out", str(out))
    assert result.exit_code == 1, result.output
    assert "FAILS" in result.output
    doc = json.loads(out.read_text())
    ra = doc["conditions"]["reach_avoid"]
    assert ra["status"] == "counterexample" and ra["property"] == "reach_avoid", ra["summary"]
    assert doc["answers"]["reach_avoid"]["answer"] == "fails" and doc["verdict"] == "unsafe"
    assert "true loop" in ra["summary"] and "before it reaches the goal" in ra["summary"]
    start, entry_time = np.array(ra["refutation"]["start"]), ra["refutation"]["time"]
    assert (start[0] - 2) ** 2 + start[1] ** 2 <= 0.25 + 1e-9  # a start in the initial set
    # reproduced by an independent integrator: the goal is not reached before the unsafe set is
    step = entry_time / 400
    X = start[None, :]
    for _ in range(400):
        X = rk4(spring_field, X, step, step)
        assert np.sum(X ** 2) > 0.1
    assert X[0, 0] <= -0.5 + 1e-3, X
    assert not _failed(verify_document(doc))


def test_a_saturated_loop_says_why_a_reach_avoid_function_is_hard_to_find(tmp_path: Path) -> None:
    # the saturated ACC (tests/test_recast_barrier.py) with a goal around its equilibrium: V may not
    # use sat, yet V' <= -eps must hold outside the goal on the whole state space
    from tests.test_recast_barrier import NEAR, write as write_acc

    model = write_acc(tmp_path, "acc", initial=NEAR)
    model.write_text(model.read_text() + 'goal = ["(h - 30)**2 + (v - 20)**2 <= 0.25"]\n')
    out = tmp_path / "acc.json"
    result = run_cli("certify", str(model), "--classes", "reach_avoid", "--out", str(out))
    doc = json.loads(out.read_text())
    ra = doc["conditions"]["reach_avoid"]
    assert ra["status"] in ("not_certified", "certified"), ra
    assert ra["falsification"]["entry"] is None  # no simulated trajectory defeats it
    if ra["status"] == "certified":  # (a search that one day proves it: verify must agree)
        assert result.exit_code == 0 and run_cli("verify", str(out)).exit_code == 0
    else:
        assert result.exit_code == 1 and "reach-avoid function was found" in ra["summary"], ra["summary"]
        assert any("V may not use sat" in line for line in ra["detail"]), ra["detail"]
        assert doc["answers"]["reach_avoid"]["answer"] == "undecided" and "reach-avoid: undecided" in result.output


def test_reach_avoid_needs_its_goal_on_a_loop_with_functions(tmp_path: Path) -> None:
    model = tmp_path / "nogoal.toml"
    model.write_text(SPRING + f"[sets]\ninitial = [{INITIAL}]\nunsafe = [{FAR}]\n")
    result = run_cli("certify", str(model), "--classes", "reach_avoid")
    assert result.exit_code == 2 and "[sets]" in result.output and "goal" in result.output, result.output
    assert len(result.output.strip().splitlines()) == 1
    # by default (no --classes) a loop without a goal is not asked the question
    out = tmp_path / "nogoal.json"
    run_cli("certify", str(model), "--classes", "barrier", "--out", str(out))
    assert "reach_avoid" not in json.loads(out.read_text())["conditions"]


def test_a_pendulum_whose_angle_makes_another_equilibrium_outside_the_goal_says_none_can_exist(tmp_path: Path) -> None:
    # theta enters through sin only: (2 pi, 0) is an equilibrium too, outside the goal, where V' = 0, so
    # no V with V' <= -eps outside the goal exists (the reach-avoid property itself may hold: undecided)
    model = tmp_path / "pendulum.toml"
    model.write_text(PENDULUM + '[sets]\ninitial = ["(theta - 1)**2 + omega**2 <= 0.04"]\nunsafe = ["theta <= -3"]\n'
                                'goal = ["theta**2 + omega**2 <= 0.1"]\n')
    out = tmp_path / "pendulum.json"
    result = run_cli("certify", str(model), "--classes", "reach_avoid", "--out", str(out))
    assert result.exit_code == 1, result.output
    doc = json.loads(out.read_text())
    ra = doc["conditions"]["reach_avoid"]
    assert ra["status"] == "not_certified" and "can exist" in ra["summary"] and "theta_eq + 2 pi" in ra["summary"]
    assert ra["falsification"]["entry"] is None and doc["answers"]["reach_avoid"]["answer"] == "undecided"
    # a wider goal that holds theta_eq + 2 pi and - 2 pi still misses theta_eq + 4 pi
    wide = tmp_path / "wide.toml"
    wide.write_text(model.read_text().replace("theta**2 + omega**2 <= 0.1", "theta**2 + omega**2 <= 50"))
    run_cli("certify", str(wide), "--classes", "reach_avoid", "--out", str(out))
    assert "theta_eq + 4 pi" in json.loads(out.read_text())["conditions"]["reach_avoid"]["summary"]
    # a goal that holds every such equilibrium (every theta) is searched, and the note is not given
    wide.write_text(model.read_text().replace("theta**2 + omega**2 <= 0.1", "omega**2 <= 0.1"))
    run_cli("certify", str(wide), "--classes", "reach_avoid", "--out", str(out))
    assert "can exist" not in json.loads(out.read_text())["conditions"]["reach_avoid"]["summary"]


def test_a_changed_proof_and_a_certificate_of_the_older_kind_are_refused(tmp_path: Path) -> None:
    """The certificate of the class's one implementation (kind reach_avoid.KIND) is checked proof by proof:
    a multiplier of one condition changed fails verify, naming the condition; one of the kind the loops
    with functions' own module wrote before (recast_reach_avoid) is refused in one line, asking to certify
    again, and the CLI exits 1."""
    model = write(tmp_path, "safe")
    out = tmp_path / "safe.json"
    assert run_cli("certify", str(model), "--classes", "reach_avoid", "--out", str(out)).exit_code == 0
    doc = json.loads(out.read_text())
    assert doc["conditions"]["reach_avoid"]["certificate"]["kind"] == reach_avoid.KIND
    assert not _failed(verify_document(doc))

    def changed_remainder(forged: dict[str, Any]) -> None:  # the lower bound's remainder (sigma) changed
        proof = forged["conditions"]["reach_avoid"]["certificate"]["proofs"]["bounded"]
        Q = proof["sigma"]["Q"]
        Q[0][0] = str(2 * Fraction(Q[0][0]) + 1)

    failed = _failed(_forged(doc, changed_remainder))
    assert failed and failed[0].startswith("reach_avoid: V >= delta |z|^2 - C: "), failed

    def older(forged: dict[str, Any]) -> None:
        forged["conditions"]["reach_avoid"]["certificate"]["kind"] = reach_avoid.OLD_KIND

    refused = [why for name, ok, why in _forged(doc, older) if not ok and name == "reach_avoid"]
    assert refused == [f"reach_avoid: {reach_avoid.OLD_FORMAT}"] and "\n" not in refused[0]
    assert "run lyapcheck certify again" in refused[0]
    old = tmp_path / "old.json"
    forged = json.loads(json.dumps(doc))
    older(forged)
    old.write_text(json.dumps(forged))
    result = run_cli("verify", str(old))
    assert result.exit_code == 1 and reach_avoid.OLD_FORMAT in result.output, result.output
