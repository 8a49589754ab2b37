"""``barrier`` (issue 32): the exact conditions themselves, the class end to end, and verify's refusals."""

from __future__ import annotations

import hashlib
import json
from fractions import Fraction
from pathlib import Path

import pytest
from click.testing import CliRunner, Result

from lyapcheck.cli import app
from lyapcheck.sos.certificates import GramPoly, check_barrier
from lyapcheck.sos.polynomials import Ring

app._register_commands()


def run_cli(*args: str) -> Result:
    return CliRunner().invoke(app.cli, list(args))


def _gram(basis: list[tuple[int, ...]], Q: list[list[int]]) -> GramPoly:
    return GramPoly.of(basis, [[Fraction(x) for x in row] for row in Q])


def test_the_barrier_identities_and_signs_by_hand() -> None:
    """x' = -x, initial {1 - x^2 >= 0}, unsafe {x - 2 >= 0}; B = x^2 - 1:
    -B - 1 (1 - x^2) = 0; B - 1 - 2 (x - 2) = (x - 1)^2 + 1; -B' + 0 B = 2 x^2."""
    ring = Ring(("x",))
    (x,) = ring.gens()
    g, D = [-x], ring.constant(1)
    B = x * x - ring.constant(1)
    initial = [[ring.constant(1) - x * x]]
    unsafe = [[x - ring.constant(2)]]
    one = [(0,)]
    lin = [(0,), (1,)]
    initial_certs = [([_gram(one, [[1]])], _gram(one, [[0]]))]
    unsafe_certs = [([_gram(one, [[2]])], _gram(lin, [[2, -1], [-1, 1]]))]
    decrease = _gram([(1,)], [[2]])
    ok, why = check_barrier(ring, g, D, B, Fraction(0), initial, initial_certs, unsafe, unsafe_certs, decrease)
    assert ok, why
    # each condition is checked: an unsafe set that reaches B <= 0 (x >= 1/2), a growing field, a
    # negative multiplier
    half = [[x - ring.constant(Fraction(1, 2))]]
    assert not check_barrier(ring, g, D, B, Fraction(0), initial, initial_certs, half, unsafe_certs, decrease)[0]
    assert not check_barrier(ring, [x], D, B, Fraction(0), initial, initial_certs, unsafe, unsafe_certs, decrease)[0]
    negative = [([_gram(one, [[-1]])], _gram(one, [[0]]))]
    ok, why = check_barrier(ring, g, D, B, Fraction(0), initial, negative, unsafe, unsafe_certs, decrease)
    assert not ok and "multiplier is not positive semidefinite" in why
    # B may not depend on a disturbance coordinate
    ring2 = Ring(("x", "u"))
    x2, u = ring2.gens()
    ok, why = check_barrier(ring2, [-x2], ring2.constant(1), x2 * x2 + u - ring2.constant(1), Fraction(0), [], [],
                            [], [], _gram([(1, 0)], [[2]]))
    assert not ok and "states only" in why


SAFE = """[model]
name = "prajna-barrier"
states = ["x1", "x2"]
[dynamics]
x1 = "x2"
x2 = "-x1 + x1**3/3 - x2"
[sets]
initial = ["(x1 - 1.5)**2 + x2**2 <= 0.25"]
unsafe = ["(x1 + 1)**2 + (x2 + 1)**2 <= 0.16"]
"""


def _forge(doc: dict, old: str, new: str) -> dict:
    text = doc["model"]["text"].replace(old, new)
    assert text != doc["model"]["text"]
    doc["model"]["text"] = text
    doc["model"]["sha256"] = hashlib.sha256(text.encode()).hexdigest()
    return doc


def test_a_barrier_is_certified_and_verify_refuses_a_widened_initial_or_shrunk_unsafe_set(tmp_path: Path) -> None:
    model = tmp_path / "safe.toml"
    model.write_text(SAFE)
    out = tmp_path / "safe.json"
    result = run_cli("certify", str(model), "--classes", "barrier", "--out", str(out))
    assert result.exit_code == 0, result.output
    doc = json.loads(out.read_text())
    barrier = doc["conditions"]["barrier"]
    assert barrier["status"] == "certified" and barrier["property"] == "safety"
    assert barrier["certificate"]["kind"] == "barrier"
    # the simulation beside the proof: no trajectory from the initial set came near the unsafe set
    assert barrier["closest_approach"] < 0 and "soundness_violation" not in barrier
    assert run_cli("verify", str(out)).exit_code == 0
    for old, new in (("<= 0.25", "<= 0.81"), ("<= 0.16", "<= 4")):  # initial 0.5 -> 0.9; unsafe 0.4 -> 2
        forged = tmp_path / "forged.json"
        forged.write_text(json.dumps(_forge(json.loads(out.read_text()), old, new)))
        result = run_cli("verify", str(forged))
        assert result.exit_code == 1 and "FAIL barrier" in result.output, result.output


def test_a_reachable_unsafe_set_gets_no_barrier(tmp_path: Path) -> None:
    # x' = x: every start in [1/2, 1] grows past 2 (at t = ln 4 at the latest)
    model = tmp_path / "reach.toml"
    model.write_text('[model]\nname = "growth"\nstates = ["x"]\n[dynamics]\nx = "x"\n'
                     '[sets]\ninitial = ["0.5 <= x", "x <= 1"]\nunsafe = ["x >= 2"]\n')
    out = tmp_path / "reach.json"
    result = run_cli("certify", str(model), "--classes", "barrier", "--out", str(out))
    barrier = json.loads(out.read_text())["conditions"]["barrier"]
    # no barrier, and the simulation beside the search finds a trajectory that enters: a counterexample
    # with its start (in the initial set) and its time
    assert barrier["status"] == "counterexample", result.output
    assert 0.5 <= barrier["refutation"]["start"][0] <= 1 and 0 < barrier["refutation"]["time"] <= 1.39


def test_barrier_without_sets_is_bad_input_and_not_run_by_default(tmp_path: Path) -> None:
    model = tmp_path / "plain.toml"
    model.write_text('[model]\nname = "p"\nstates = ["x"]\n[dynamics]\nx = "-x"\n')
    result = run_cli("certify", str(model), "--classes", "barrier")
    assert result.exit_code == 2 and "[sets]: the class barrier needs the sets initial and unsafe" in result.output
    assert len(result.output.strip().splitlines()) == 1
    out = tmp_path / "plain.json"
    assert run_cli("certify", str(model), "--out", str(out)).exit_code == 0
    assert "barrier" not in json.loads(out.read_text())["conditions"]


@pytest.mark.parametrize("bound", ["0.2"])
def test_a_disturbed_barrier_holds_for_every_disturbance(tmp_path: Path, bound: str) -> None:
    # x' = -x + d, |d| <= 0.2: from |x| <= 0.5 the state stays within max(0.5, 0.2); unsafe x >= 1
    model = tmp_path / "tube.toml"
    model.write_text(f'[model]\nname = "tube"\nstates = ["x"]\n[disturbances]\nd = {bound}\n[dynamics]\nx = "-x + d"\n'
                     '[sets]\ninitial = ["-0.5 <= x <= 0.5"]\nunsafe = [["x >= 1"], ["x <= -1"]]\n')
    out = tmp_path / "tube.json"
    result = run_cli("certify", str(model), "--classes", "barrier", "--out", str(out))
    assert result.exit_code == 0, result.output
    barrier = json.loads(out.read_text())["conditions"]["barrier"]
    assert barrier["status"] == "certified" and barrier["disturbances"] == "all"
    assert "box_multipliers" in barrier["certificate"]
    assert run_cli("verify", str(out)).exit_code == 0


def test_a_trajectory_into_a_proved_unreachable_set_is_a_soundness_violation(tmp_path: Path,
                                                                            monkeypatch: pytest.MonkeyPatch) -> None:
    """Were the simulation beside a certified barrier to enter the unsafe set, the run says so and
    exits 1 (the proof or the simulation is wrong): stood in here by a made-up falsification."""
    from lyapcheck.models.classes import barrier

    class Entered:
        entered, closest_approach, entry = True, 0.01, None

        def to_dict(self) -> dict:
            return {"closest_approach": 0.01}

    monkeypatch.setattr(barrier, "_falsification", lambda model: Entered())
    model = tmp_path / "safe.toml"
    model.write_text(SAFE)
    result = CliRunner().invoke(app.cli, ["certify", str(model), "--classes", "barrier", "--json"])
    assert result.exit_code == 1
    assert '"soundness_violation": true' in result.output and "SOUNDNESS VIOLATION" in result.output


def test_a_barrier_over_a_box_of_parameters(tmp_path: Path) -> None:
    """One B for every a in the box: x' = -a x + d, |d| <= 0.5, from |x| <= 0.5 never |x| >= 1 when
    a >= 0.8 (the state stays below max(0.5, 0.5 / a) <= 0.625); not at a = 0.1 (0.5 / a = 5). A set
    that names a parameter of the box is not_applicable (sets are read at the model's values)."""
    text = ('[model]\nname = "tube"\nstates = ["x"]\n[parameters]\na = 1\nw = 1\n[disturbances]\nd = 0.5\n'
            '[dynamics]\nx = "-a*x + d"\n[sets]\ninitial = ["-0.5 <= x <= 0.5"]\nunsafe = [["x >= w"], ["x <= -1"]]\n')
    model = tmp_path / "tube.toml"
    model.write_text(text)
    out = tmp_path / "box.json"
    result = run_cli("certify", str(model), "--box", "a=0.8..2", "--classes", "barrier", "--out", str(out))
    assert result.exit_code == 0, result.output
    barrier = json.loads(out.read_text())["conditions"]["barrier"]
    assert barrier["status"] == "certified" and barrier["summary"].startswith("for every a in [0.8, 2]")
    assert run_cli("verify", str(out)).exit_code == 0
    run_cli("certify", str(model), "--box", "a=0.1..2", "--classes", "barrier", "--out", str(out))
    assert json.loads(out.read_text())["conditions"]["barrier"]["status"] != "certified"
    run_cli("certify", str(model), "--box", "w=0.9..1.1", "--classes", "barrier", "--out", str(out))
    barrier = json.loads(out.read_text())["conditions"]["barrier"]
    assert barrier["status"] == "not_applicable" and "parameter of the box" in barrier["summary"]


def test_the_degree_figure_is_the_stated_barriers_and_fossil_barr1_verifies(tmp_path: Path) -> None:
    """FOSSIL's barr1 is found at degree 4 with B's quartic terms rounded to 0: the ``degree`` figure is B's
    own degree (the one verify re-derives from the stated B), not the search's bound, and its certificate
    passes verify (it failed with "the stated figure 'degree' = 4 is not the certificate's (3)")."""
    out = tmp_path / "barr1.json"
    models = Path(__file__).resolve().parents[1] / "examples" / "models"
    r = run_cli("certify", str(models / "fossil-barr1.toml"), "--classes", "barrier", "--out", str(out))
    assert r.exit_code == 0, r.output
    c = json.loads(out.read_text())["conditions"]["barrier"]
    assert c["status"] == "certified"
    assert c["degree"] == max(sum(e) for _, e in c["certificate"]["B"]["terms"])
    v = run_cli("verify", str(out))
    assert v.exit_code == 0, v.output
