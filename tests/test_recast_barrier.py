"""The barrier class on loops with functions (lyapcheck.models.classes.barrier, its one implementation): ``[sets]``
taken, the true loop simulated for a counterexample, a barrier over the recasting's relations proved and
re-checked; a changed multiplier does not verify, and a certificate of the older kind is refused in one line."""

from __future__ import annotations

import copy
import hashlib
import json
from fractions import Fraction
from pathlib import Path
from typing import Any

from click.testing import CliRunner, Result

from lyapcheck.cli import app
from lyapcheck.models.language.modelfile import parse_any_model
from lyapcheck.models.language.recast import RecastModel
from lyapcheck.models.surfaces.certificate import verify_document

app._register_commands()

# an adaptive cruise control: gap h (m), speed v (m/s) behind a leader at vL, acceleration limited
ACC = """[model]
name = "saturated ACC"
states = ["h", "v"]

[parameters]
vL = 20
h0 = 30
kp = 0.5
kd = 1
umax = 3

[dynamics]
h = "vL - v"
v = "{v}"

[equilibrium]
h = 30
v = 20

[sets]
initial = [{initial}]
unsafe = [{unsafe}]
"""
SATURATED = "sat(kp*(h - h0) + kd*(vL - v), umax)"
# 40 m/s behind a 20 m/s leader, 28 to 32 m back: braking at 3 m/s^2 needs 66 m to match speeds
FAST = '"28 <= h", "h <= 32", "38 <= v", "v <= 40"'
NEAR = '"29 <= h", "h <= 31", "19 <= v", "v <= 21"'
TOO_CLOSE = '"h <= 5"'


def run_cli(*args: str) -> Result:
    return CliRunner().invoke(app.cli, list(args))


def write(tmp_path: Path, name: str, v: str = SATURATED, initial: str = FAST, unsafe: str = TOO_CLOSE) -> Path:
    path = tmp_path / f"{name}.toml"
    path.write_text(ACC.format(v=v, initial=initial, unsafe=unsafe))
    return path


def test_an_unsafe_saturated_acc_gets_a_counterexample_on_the_true_loop(tmp_path: Path) -> None:
    model = write(tmp_path, "unsafe")
    out = tmp_path / "unsafe.json"
    result = run_cli("certify", str(model), "--classes", "barrier", "--out", str(out))
    assert result.exit_code == 1, result.output
    doc = json.loads(out.read_text())
    barrier = doc["conditions"]["barrier"]
    assert barrier["status"] == "counterexample" and barrier["property"] == "safety", barrier["summary"]
    assert doc["verdict"] == "unsafe" and doc["answers"]["safety"]["answer"] == "unsafe"
    assert "UNSAFE" in result.output
    h0, v0 = barrier["refutation"]["start"]
    assert 28 <= h0 <= 32 and 38 <= v0 <= 40  # a start in the initial set
    assert barrier["refutation"]["point"][0] <= 5 + 1e-6 and barrier["refutation"]["time"] > 0  # the gap closed
    # the sentence names the true loop's simulation, and verify re-simulates the counterexample on it
    assert "true loop" in barrier["summary"]
    assert all(ok for _, ok, _ in verify_document(doc)), verify_document(doc)


def _forged(doc: dict[str, Any], change: Any) -> list[tuple[str, bool, str]]:
    forged = copy.deepcopy(doc)
    change(forged)
    return verify_document(forged)


def _failed(rows: list[tuple[str, bool, str]]) -> list[str]:
    return [why for _, ok, why in rows if not ok]


def test_a_safe_acc_with_a_function_gets_a_barrier_that_verify_re_checks(tmp_path: Path) -> None:
    # the linear ACC with a bounded sine term (a loop with functions, recast exactly): from near the
    # equilibrium the gap never closes to 5 m
    model = write(tmp_path, "safe", v="kp*(h - h0) + kd*(vL - v) + sin(h - h0)/5", initial=NEAR)
    out = tmp_path / "safe.json"
    result = run_cli("certify", str(model), "--classes", "barrier", "--out", str(out))
    assert result.exit_code == 0, result.output
    doc = json.loads(out.read_text())
    barrier = doc["conditions"]["barrier"]
    assert barrier["status"] == "certified" and barrier["property"] == "safety", barrier["summary"]
    assert barrier["summary"].startswith("safety: no trajectory that starts in the initial set")
    assert doc["answers"]["safety"]["answer"] == "safe"
    assert barrier["falsification"]["entry"] is None
    assert not _failed(verify_document(doc))
    assert run_cli("verify", str(out)).exit_code == 0

    cert = barrier["certificate"]
    assert cert["kind"] == "barrier_relations" and barrier["lambda_per_s"] == float(Fraction(cert["lambda_per_s"]))
    recast = parse_any_model(model.read_text(), str(model), {})
    assert isinstance(recast, RecastModel)
    from lyapcheck.models.classes.recast_classes import v_text
    from lyapcheck.models.engines.recast_sos import poly_from_json, poly_to_json

    ring = recast.system.ring

    def shifted_b(forged: dict[str, Any]) -> None:  # B moved up by 1, its text made consistent
        c = forged["conditions"]["barrier"]["certificate"]
        B = poly_from_json(ring, c["B"], "B") + ring.constant(1)
        c["B"], c["B_text"] = poly_to_json(ring, B), v_text(recast.system, B)

    def other_rate(forged: dict[str, Any]) -> None:  # another rate, stated consistently
        c = forged["conditions"]["barrier"]
        c["certificate"]["lambda_per_s"], c["lambda_per_s"] = "-4", -4.0

    def gas(forged: dict[str, Any]) -> None:
        forged["conditions"]["barrier"]["property"] = "GAS"

    def invented(forged: dict[str, Any]) -> None:
        forged["conditions"]["barrier"]["decay_rate_per_s"] = 1.0

    def wider_initial(forged: dict[str, Any]) -> None:  # the text's set changed: the proofs no longer fit it
        text = forged["model"]["text"].replace('"29 <= h"', '"6 <= h"')
        forged["model"]["text"], forged["model"]["sha256"] = text, hashlib.sha256(text.encode()).hexdigest()

    for change, words in ((shifted_b, "B <= 0 on the initial set"), (other_rate, "B' <= lambda B"),
                          (gas, "property"), (invented, "decay_rate_per_s"), (wider_initial, "initial set")):
        failed = _failed(_forged(doc, change))
        assert failed and words in failed[0], (change.__name__, failed)


def test_a_safe_saturated_acc_is_not_certified_with_a_reason(tmp_path: Path) -> None:
    # safe (no simulated trajectory enters), but a barrier must satisfy B' <= lambda B everywhere,
    # and B may not use sat: the answer is "not decided", never a wrong one, and it says why
    model = write(tmp_path, "near", initial=NEAR)
    out = tmp_path / "near.json"
    result = run_cli("certify", str(model), "--classes", "barrier", "--out", str(out))
    barrier = json.loads(out.read_text())["conditions"]["barrier"]
    assert barrier["status"] in ("not_certified", "certified"), barrier
    assert barrier["falsification"]["entry"] is None
    if barrier["status"] == "certified":  # (a search that one day proves it: verify must agree)
        assert result.exit_code == 0 and run_cli("verify", str(out)).exit_code == 0
    else:
        assert result.exit_code == 1 and "barrier was found" in barrier["summary"], barrier["summary"]
        assert any("may not use sat" in line for line in barrier["detail"])


def test_sets_on_a_loop_with_functions_are_read_or_refused_in_one_line(tmp_path: Path) -> None:
    with_function = write(tmp_path, "fun", unsafe='"sin(h) >= 2"')
    result = run_cli("certify", str(with_function), "--classes", "barrier")
    assert result.exit_code == 2 and "[sets] unsafe" in result.output and "sin" in result.output, result.output
    assert len(result.output.strip().splitlines()) == 1
    goal = tmp_path / "goal.toml"
    goal.write_text(write(tmp_path, "base").read_text().replace('unsafe = ["h <= 5"]',
                                                                 'unsafe = ["h <= 5"]\ngoal = ["h >= 29"]'))
    # a goal is read (class reach_avoid: tests/test_recast_reach_avoid.py); staying in it is refused in one line
    assert set(parse_any_model(goal.read_text(), "goal.toml", {}).sets) == {"initial", "unsafe", "goal"}
    stay = tmp_path / "stay.toml"
    stay.write_text(goal.read_text() + "stay_in_goal = true\n")
    result = run_cli("certify", str(stay), "--classes", "barrier")
    assert result.exit_code == 2 and "[sets] stay_in_goal" in result.output, result.output
    assert len(result.output.strip().splitlines()) == 1
    no_sets = tmp_path / "nosets.toml"
    no_sets.write_text(write(tmp_path, "base").read_text().split("[sets]")[0])
    result = run_cli("certify", str(no_sets), "--classes", "barrier")
    assert result.exit_code == 2 and "needs the sets initial and unsafe" in result.output, result.output
    model = parse_any_model(write(tmp_path, "read").read_text(), "read.toml", {})
    assert set(model.sets) == {"initial", "unsafe"} and len(model.sets["initial"][0]) == 4


def _certified_safe_acc(tmp_path: Path) -> tuple[Path, dict[str, Any]]:
    model = write(tmp_path, "safe", v="kp*(h - h0) + kd*(vL - v) + sin(h - h0)/5", initial=NEAR)
    out = tmp_path / "safe.json"
    assert run_cli("certify", str(model), "--classes", "barrier", "--out", str(out)).exit_code == 0
    return out, json.loads(out.read_text())


def test_a_changed_multiplier_of_a_barrier_on_relations_does_not_verify(tmp_path: Path) -> None:
    # the certificate of the one implementation on a loop with functions: each identity's proof by relation
    # index (the recasting's relations, then the piece's generators); any multiplier changed, it fails
    _, doc = _certified_safe_acc(tmp_path)
    cert = doc["conditions"]["barrier"]["certificate"]
    assert not _failed(verify_document(doc))
    recast = parse_any_model(write(tmp_path, "safe", v="kp*(h - h0) + kd*(vL - v) + sin(h - h0)/5",
                                   initial=NEAR).read_text(), "safe.toml", {})
    assert isinstance(recast, RecastModel)
    from lyapcheck.models.classes.recast_classes import base_loop

    relations = len(base_loop(recast.system, cylinder=False).relations)
    # the initial piece's generators follow the recasting's relations: 4 inequalities and their 6 products
    assert {int(k) for k in cert["initial"][0]["taus"]} >= set(range(relations, relations + 10))

    def set_multiplier(forged: dict[str, Any]) -> None:  # an S-procedure multiplier of the initial piece
        taus = forged["conditions"]["barrier"]["certificate"]["initial"][0]["taus"]
        gram = taus[str(relations)]["Q"]
        gram[0][0] = str(Fraction(gram[0][0]) + 1)

    def relation_multiplier(forged: dict[str, Any]) -> None:  # a free multiplier of an equality relation
        decrease = forged["conditions"]["barrier"]["certificate"]["decrease"]
        assert decrease["lambdas"], "the decrease uses the sine's relation s^2 + c^2 = 1"
        term = next(iter(decrease["lambdas"].values()))["terms"][0]
        term[0] = str(Fraction(term[0]) + 1)

    def remainder(forged: dict[str, Any]) -> None:
        sigma = forged["conditions"]["barrier"]["certificate"]["unsafe"][0]["sigma"]["Q"]
        sigma[0][0] = str(Fraction(sigma[0][0]) * 2 + 1)

    for change, words in ((set_multiplier, "B <= 0 on the initial set"), (relation_multiplier, "B' <= lambda B"),
                          (remainder, "B >= 1 on the unsafe set")):
        failed = _failed(_forged(doc, change))
        assert failed and words in failed[0], (change.__name__, failed)


def test_a_barrier_certificate_of_the_older_kind_is_refused_in_one_line(tmp_path: Path) -> None:
    from lyapcheck.models.classes import barrier

    out, doc = _certified_safe_acc(tmp_path)
    doc["conditions"]["barrier"]["certificate"]["kind"] = "recast_barrier"
    failed = [why for check, ok, why in verify_document(doc) if not ok and check == "barrier"]
    assert failed == [f"barrier: {barrier.OLD_FORMAT}"]  # (and the verdict and exit code follow from it)
    assert "run lyapcheck certify again" in failed[0] and "\n" not in failed[0]
    out.write_text(json.dumps(doc))
    result = run_cli("verify", str(out))
    assert result.exit_code == 1, result.output
    assert sum(barrier.OLD_FORMAT in line for line in result.output.splitlines()) == 1, result.output
