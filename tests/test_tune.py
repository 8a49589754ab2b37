"""``lyapcheck tune`` (issue 45, item 2): a grid and one refinement over a box of gains, every figure
read from an exact certificate, the winner certified again (verify re-checks its tune table) and a
neighbourhood proved by a box certificate."""

from __future__ import annotations

import json
import math
from fractions import Fraction
from pathlib import Path

import pytest
from click.testing import CliRunner

from lyapcheck.cli import app
from lyapcheck.models.surfaces import tune

ROOT = Path(__file__).resolve().parents[1]
MODELS = ROOT / "examples" / "models"
SCALAR = MODELS / "linear-scalar-disturbed.toml"  # x' = -a x + d, |d| <= 1: worst-case limsup |x| = 1/a exactly
OSCILLATOR = MODELS / "damped-oscillator.toml"  # x'' + c x' + k x = 0
PID = MODELS / "pid-hardening-spring.toml"
app._register_commands()
RUNNER = CliRunner()


def test_the_grid_comes_first_then_one_refinement_around_its_best_point() -> None:
    """A figure peaked at kp = 3, ki = 1, not proved where ki > 1.5 kp: the grid's points in order,
    then half a step either way along each axis around the best, and the best of all wins."""
    seen: list[tuple[Fraction, Fraction]] = []

    def evaluate(values: dict[str, Fraction]) -> tuple[Fraction | None, str, dict]:
        kp, ki = values["kp"], values["ki"]
        seen.append((kp, ki))
        if ki > Fraction(3, 2) * kp:
            return None, "refuted (unstable)", {}
        return 10 - (kp - 3) ** 2 - (ki - 1) ** 2, "certified", {}

    boxes = [("kp", Fraction(1, 2), Fraction(4)), ("ki", Fraction(1, 4), Fraction(2))]
    tried = tune.search(boxes, 3, "max", evaluate)
    grid = [(kp, ki) for kp in (Fraction(1, 2), Fraction(9, 4), Fraction(4)) for ki in (Fraction(1, 4), Fraction(9, 8), Fraction(2))]
    assert seen[:9] == grid and all(p.phase == "grid" for p in tried[:9])
    assert [p.outcome for p in tried[:9]].count("refuted (unstable)") == 2  # kp = 0.5 with ki = 9/8 and 2 (> 0.75)
    best_grid = tune.best_point(tried[:9], "max")
    assert best_grid is not None and best_grid.values == {"kp": Fraction(9, 4), "ki": Fraction(9, 8)}
    refine = tried[9:]
    assert 1 <= len(refine) <= 4 and all(p.phase == "refine" for p in refine)
    for p in refine:  # half a step along one axis from the best grid point
        moved = [k for k in ("kp", "ki") if p.values[k] != best_grid.values[k]]
        assert len(moved) == 1
    winner = tune.best_point(tried, "max")
    assert winner is not None and winner.value is not None
    assert winner.value == max(p.value for p in tried if p.value is not None)
    assert winner.values == {"kp": Fraction(25, 8), "ki": Fraction(9, 8)}  # 2.25 + 1.75 / 2: towards the peak


def test_no_refinement_when_no_grid_point_is_proved() -> None:
    tried = tune.search([("a", Fraction(0), Fraction(1))], 2, "min", lambda v: (None, "not_certified", {}))
    assert len(tried) == 2 and tune.best_point(tried, "min") is None


def test_the_neighbourhood_halves_its_box_until_the_factor_is_proved_and_never_claims_otherwise() -> None:
    boxes = [("k", Fraction(0), Fraction(4))]
    objective = tune.Objective("decay_rate", "decay_rate")
    asked: list[list[str]] = []

    def certify_box(texts: list[str], need: Fraction) -> tuple[Fraction | None, str, dict | None]:
        asked.append(texts)
        lo, hi = (Fraction(x) for x in texts[0].split("=")[1].split(".."))
        got = Fraction(1) - (hi - lo) / 4  # narrower boxes prove more
        return got, "certified", {"box": texts}

    nb = tune.neighbourhood(objective, boxes, {"k": Fraction(2)}, Fraction(1), 2, certify_box, True)
    # threshold 1/2: half a grid step (2) either way is the whole box, width 4, which gives 0; then width 2
    # gives 1/2, which meets it
    assert asked == [["k=0..4"], ["k=1..3"]]
    assert nb["certified"] and nb["box"] == {"k": ["1", "3"]} and Fraction(nb["threshold_exact"]) == Fraction(1, 2)
    never = tune.neighbourhood(objective, boxes, {"k": Fraction(2)}, Fraction(1), 2,
                               lambda texts, need: (None, "not_certified", None), True)
    assert not never["certified"] and [t["box"] for t in never["tries"]] == [["k=0..4"], ["k=1..3"], ["k=1.5..2.5"]]
    assert "no certified neighbourhood" in tune.neighbourhood_sentence(objective, never)
    assert not tune.neighbourhood(objective, boxes, {"k": Fraction(2)}, Fraction(1), 2, certify_box, False)["certified"]


def test_the_bound_is_minimized_on_the_scalar_loop_and_verify_rechecks_the_tune_table(tmp_path: Path) -> None:
    out = tmp_path / "tuned.json"
    done = RUNNER.invoke(app.cli, ["tune", str(SCALAR), "--box", "a=1..4", "--objective", "bound:y", "--grid", "2",
                                   "--out", str(out), "--json"])
    assert done.exit_code == 0, done.output
    t = json.loads(done.output)["tune"]
    for p in t["tried"]:  # each figure is a certified bound: never below the exact worst case 1/a
        assert Fraction(p["value_exact"]) >= 1 / Fraction(p["point"]["a"])
    assert t["point"] == {"a": "4"} and Fraction(1, 4) <= Fraction(t["value_exact"]) < Fraction(26, 100)
    assert [p["phase"] for p in t["tried"]] == ["grid", "grid", "refine"]  # 2 points, then 2.5 (5.5 is outside)
    nb = t["neighbourhood"]
    assert nb["certified"] and Fraction(nb["box"]["a"][0]) <= 4 <= Fraction(nb["box"]["a"][1])
    assert Fraction(nb["value_exact"]) <= 2 * Fraction(t["value_exact"])
    assert Fraction(nb["value_exact"]) >= 1 / Fraction(nb["box"]["a"][0])  # the box's worst gain
    doc = json.loads(out.read_text())
    assert doc["overrides"] == {"a": "4"} and doc["tune"]["value_exact"] == t["value_exact"]
    checked = RUNNER.invoke(app.cli, ["verify", str(out)])
    assert checked.exit_code == 0 and checked.output.count("ok   tune") == 4, checked.output
    doc["tune"]["value_exact"] = str(Fraction(1, 4) - Fraction(1, 100))  # a better bound than was proved
    out.write_text(json.dumps(doc))
    assert RUNNER.invoke(app.cli, ["verify", str(out)]).exit_code == 1


def _oscillator_rate(k: Fraction, c: Fraction) -> float:
    """The true decay rate of x'' + c x' + k x = 0: minus the largest real part of its roots."""
    disc = float(c * c - 4 * k)
    return float(c) / 2 if disc < 0 else (float(c) - math.sqrt(disc)) / 2


def test_the_decay_rate_is_maximized_on_the_oscillator(tmp_path: Path) -> None:
    out = tmp_path / "tuned.json"
    done = RUNNER.invoke(app.cli, ["tune", str(OSCILLATOR), "--box", "k=0.5..4", "--box", "c=0.5..3",
                                   "--objective", "decay_rate", "--grid", "2", "--out", str(out)])
    assert done.exit_code == 0, done.output
    assert "winner: k = 4, c = 3" in done.output and "certified neighbourhood" in done.output
    t = json.loads(out.read_text())["tune"]
    for p in t["tried"]:  # no certified rate exceeds the true one (the roots' real parts)
        rate = _oscillator_rate(Fraction(p["point"]["k"]), Fraction(p["point"]["c"]))
        assert p["value"] is not None and 0 < p["value"] <= rate
    assert t["value"] == max(p["value"] for p in t["tried"])
    assert RUNNER.invoke(app.cli, ["verify", str(out)]).exit_code == 0


def test_the_local_rate_is_proved_below_the_spectral_abscissa() -> None:
    from lyapcheck.models.classes.linearization import LOCAL_RATE_BITS, hurwitz_determinants, characteristic_polynomial
    from lyapcheck.models.classes.linearization import local_rate

    J = [[Fraction(-1), Fraction(5)], [Fraction(0), Fraction(-3)]]  # eigenvalues -1 and -3: the rate is 1
    rate = local_rate(J)
    assert rate is not None and 1 - Fraction(2, 2 ** LOCAL_RATE_BITS) <= rate < 1
    shifted = [[J[i][j] + (rate if i == j else 0) for j in range(2)] for i in range(2)]
    assert all(h > 0 for h in hurwitz_determinants(characteristic_polynomial(shifted)))
    assert local_rate([[Fraction(1), Fraction(0)], [Fraction(0), Fraction(-1)]]) is None
    assert local_rate([[Fraction(0), Fraction(1)], [Fraction(-1), Fraction(0)]]) is None  # a centre: no rate


def _pid_abscissa(kp: Fraction, ki: Fraction, kd: float = 1.5) -> float:
    import numpy as np

    return float(-max(np.roots([1.0, kd, float(kp), float(ki)]).real))


def test_the_pid_loop_is_tuned_for_its_local_rate_beyond_its_own_gains(tmp_path: Path) -> None:
    """Issue 45's tune target on the PID loop, with the rate the linearization proves (no quadratic V
    exists there, so no GES rate): the winner's proved rate is at least the file's own gains' (kp = 2,
    ki = 1), every rate tried is below the true one, and verify re-checks the tune table."""
    out = tmp_path / "pid.json"
    done = RUNNER.invoke(app.cli, ["tune", str(PID), "--box", "kp=0.5..4", "--box", "ki=0.25..2",
                                   "--objective", "local_decay_rate", "--out", str(out), "--json"])
    assert done.exit_code == 0, done.output
    t = json.loads(done.output)["tune"]
    for p in t["tried"]:
        if p["value_exact"] is not None:
            assert 0 < Fraction(p["value_exact"]) < _pid_abscissa(Fraction(p["point"]["kp"]), Fraction(p["point"]["ki"]))
        else:  # ki > 1.5 kp: unstable, refuted exactly
            assert Fraction(p["point"]["ki"]) > Fraction(3, 2) * Fraction(p["point"]["kp"])
    assert Fraction(t["value_exact"]) > _pid_abscissa(Fraction(2), Fraction(1))  # beyond the file's own gains
    # the neighbourhood: half the winner's rate for every gain of a box around it (J(u) + r I Hurwitz there)
    nb = t["neighbourhood"]
    assert nb["certified"], nb
    need = Fraction(nb["threshold_exact"])
    assert Fraction(t["value_exact"]) / 2 <= need < Fraction(t["value_exact"]) / 2 + Fraction(1, 10**9)
    for kp in nb["box"]["kp"]:
        for ki in nb["box"]["ki"]:  # the box's corners: the true rate there is above the proved one
            assert _pid_abscissa(Fraction(kp), Fraction(ki)) > need
    assert RUNNER.invoke(app.cli, ["verify", str(out)]).exit_code == 0
    doc = json.loads(out.read_text())
    doc["tune"]["value_exact"] = str(Fraction(t["value_exact"]) * 2)
    out.write_text(json.dumps(doc))
    assert RUNNER.invoke(app.cli, ["verify", str(out)]).exit_code == 1


def test_a_rate_over_a_box_is_proved_only_below_the_slowest_eigenvalue() -> None:
    """J(u) = [[-(2 + u)]] on u in [-1, 1]: its eigenvalue -(2 + u) is at most -1, so a rate below 1 is
    proved for every value and 1 (reached at u = -1) or more is not."""
    from lyapcheck.models.classes.linearization import BOX_METHOD, rate_over_box

    data = {"method": BOX_METHOD, "jacobian": [[[["-2", [0]], ["-1", [1]]]]]}
    assert rate_over_box(data, ["k"], Fraction(9, 10))
    assert not rate_over_box(data, ["k"], Fraction(1))
    assert not rate_over_box(data, ["k"], Fraction(11, 10))
    assert not rate_over_box({**data, "method": "routh_hurwitz"}, ["k"], Fraction(1, 2))


def test_the_pid_loop_has_no_ges_rate_so_no_winner() -> None:
    """The hardening spring's -x^3 leaves every quadratic V's derivative with an indefinite quartic
    term: quadratic certifies no point, the table says so and the exit code is 1."""
    done = RUNNER.invoke(app.cli, ["tune", str(PID), "--box", "kp=0.5..4", "--box", "ki=0.25..2",
                                   "--objective", "decay_rate", "--grid", "2", "--json"])
    assert done.exit_code == 1, done.output
    t = json.loads(done.output)["tune"]
    assert t["certified_points"] == 0 and t["point"] is None and len(t["tried"]) == 4
    assert all(p["outcome"] == "not_certified" for p in t["tried"])


@pytest.mark.parametrize(("model", "args", "named"), [
    (OSCILLATOR, ["--box", "k=1..2", "--objective", "bound:x1"], "--objective"),  # no disturbances
    (SCALAR, ["--box", "a=1..2", "--objective", "bound:z"], "--objective"),  # no such output
    (OSCILLATOR, ["--box", "k=1..2", "--objective", "safety:c=0..1"], "--objective"),  # no [sets]
    (OSCILLATOR, ["--box", "k=1..2", "--objective", "speed"], "--objective"),
    (OSCILLATOR, ["--box", "nu=1..2", "--objective", "decay_rate"], "--box nu"),
    (OSCILLATOR, ["--box", "x1=1..2", "--objective", "decay_rate"], "--box x1"),  # a state, not a parameter
    (OSCILLATOR, ["--box", "k=2..2", "--objective", "decay_rate"], "box"),  # an empty range
    (OSCILLATOR, ["--box", "k=1..2", "--box", "k=2..3", "--objective", "decay_rate"], "--box k"),
    (OSCILLATOR, ["--box", "k=1..2", "--set", "k=3", "--objective", "decay_rate"], "--box k"),
    (OSCILLATOR, ["--box", "k=1..2", "--objective", "decay_rate", "--grid", "0"], "grid"),
    (OSCILLATOR, ["--box", "k=1..2", "--box", "c=1..2", "--objective", "decay_rate", "--grid", "10"], "grid"),
    (OSCILLATOR, ["--objective", "decay_rate"], "box"),
    (OSCILLATOR, ["--box", "k=1..2", "--objective", "decay_rate", "--classes", "bogus"], "classes"),
    (OSCILLATOR, ["--box", "k=1..2", "--objective", "decay_rate", "--set", "nu=1"], "--set nu"),
    (ROOT / "examples" / "paper.toml", ["--box", "alpha_d=500..600", "--objective", "decay_rate"], "FILE"),
])
def test_bad_input_is_one_line_naming_the_flag(model: Path, args: list[str], named: str) -> None:
    done = RUNNER.invoke(app.cli, ["tune", str(model), *args])
    assert done.exit_code == 2, done.output
    assert len(done.output.strip().splitlines()) == 1 and named in done.output, done.output


def test_an_objective_refusal_says_what_is_accepted_and_what_was_given() -> None:
    done = RUNNER.invoke(app.cli, ["tune", str(OSCILLATOR), "--box", "k=1..2", "--objective", "bound:x1"])
    assert "--objective: must be one of decay_rate, local_decay_rate, roa, bound:OUTPUT" in done.output
    assert "needs a model with [disturbances]" in done.output
    assert "got 'bound:x1'" in done.output


TUBE = """
[model]
name = "disturbed spiral with a damping gain"
states = ["x", "y"]

[parameters]
a = 1

[disturbances]
d1 = 0.1
d2 = 0.1

[dynamics]
x = "-a*x + y + d1"
y = "-x - a*y + d2"

[sets]
initial = ["(x - 1)**2 + y**2 <= 0.01"]
unsafe = ["1.25 <= x"]
"""


@pytest.mark.slow
def test_the_safety_margin_is_the_largest_disturbance_proved_at_each_gain(tmp_path: Path,
                                                                          monkeypatch: pytest.MonkeyPatch) -> None:
    """At each damping gain a, the largest bound of d1 at which barrier proves the wall is never reached
    (a bisection over d1); the winner's certificate holds that bound as an override."""
    monkeypatch.setattr(tune, "SAFETY_STEPS", 1)  # the two ends and one midpoint at each gain
    model = tmp_path / "tube.toml"
    model.write_text(TUBE)
    out = tmp_path / "tuned.json"
    done = RUNNER.invoke(app.cli, ["tune", str(model), "--box", "a=0.5..2", "--objective", "safety:d1=0.05..3",
                                   "--grid", "2", "--out", str(out), "--json"])
    assert done.exit_code == 0, done.output
    t = json.loads(done.output)["tune"]
    assert all(p["margin_tried"] <= 3 for p in t["tried"])
    margin = {p["point"]["a"]: Fraction(p["value_exact"]) for p in t["tried"] if p["value_exact"] is not None}
    # more damping tolerates a larger disturbance (measured with 4 halvings: 0.7875 at a = 0.5, 2.816 at a = 2,
    # where d1 = 0.97 and 3 are refuted by simulated trajectories that reach the wall)
    assert margin["0.5"] < margin["2"] and t["point"] == {"a": "2"}
    doc = json.loads(out.read_text())
    assert doc["overrides"]["a"] == t["point"]["a"] and Fraction(doc["overrides"]["d1"]) == Fraction(t["value_exact"])
    assert Fraction(t["value_exact"]) == max(Fraction(p["value_exact"]) for p in t["tried"] if p["value_exact"])
    assert doc["conditions"]["barrier"]["status"] == "certified"
    assert RUNNER.invoke(app.cli, ["verify", str(out)]).exit_code == 0
