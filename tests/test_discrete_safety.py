"""``barrier`` on polynomial discrete-time maps (issue 44, "digital controllers"):
:mod:`lyapcheck.models.classes.discrete_safety`.

What is asserted: on ``examples/models/discrete-safety-map.toml`` (FOSSIL's DTAhmadi with sets) the class
certifies a ``B`` that ``verify`` re-checks, whose sentence speaks of iterates and steps, and along the map
iterated from starts sampled in the initial set ``B`` stays ``<= 0`` and no iterate is unsafe (floating point,
independent of the class's code); a certificate with ``B``, ``lambda`` or a Gram entry changed fails ``verify``
(exit 1); on ``discrete-unsafe-map.toml`` (one step from the initial set into the unsafe one) the class never
certifies: it is ``refuted`` by a start whose iterate is proved unsafe, which ``verify`` re-derives and which a
changed start or step count does not pass; a map without ``[sets]`` is ``not_applicable`` with the sets'
sentence (and naming the class on the command line is refused in one line, exit 2, as on a field).
``reach_avoid``: a contracting rotation certifies with a steps bound that sampled iterates respect (a
changed bound or eps fails ``verify``); the unsafe map with a goal is refuted by an unsafe iterate before
the goal, and an iterate that is not proved outside the goal does not count; ``stay_in_goal`` is refused.
"""

from __future__ import annotations

import copy
import json
from fractions import Fraction
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from click.testing import CliRunner

from lyapcheck.cli import app
from lyapcheck.models.classes import discrete_safety as ds
from lyapcheck.models.engines.search import Budget
from lyapcheck.models.language.modelfile import load_model, parse_model
from lyapcheck.models.loop.discrete import shifted_map

app._register_commands()

EXAMPLES = Path(__file__).resolve().parents[1] / "examples" / "models"
SAFE = EXAMPLES / "discrete-safety-map.toml"
UNSAFE = EXAMPLES / "discrete-unsafe-map.toml"

NO_SETS = """[model]
name = "a map without sets"
states = ["x", "y"]
time = "discrete"
[dynamics]
x = "0.3*x"
y = "-x + 0.5*y + 7/18*x**2"
"""


def cli(*args: str) -> Any:
    done = CliRunner().invoke(app.cli, list(args))
    assert done.exception is None or isinstance(done.exception, SystemExit), done.output
    assert "Traceback" not in done.output
    return done


def certified(folder: Path, path: Path, name: str) -> tuple[Path, dict[str, Any], int]:
    out = folder / name
    done = cli("certify", str(path), "--classes", "barrier", "--no-store", "--json", "--out", str(out))
    return out, json.loads(out.read_text()), done.exit_code


@pytest.fixture(scope="module")
def safe(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, dict[str, Any], int]:
    return certified(tmp_path_factory.mktemp("safe"), SAFE, "safe.json")


@pytest.fixture(scope="module")
def unsafe(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, dict[str, Any], int]:
    return certified(tmp_path_factory.mktemp("unsafe"), UNSAFE, "unsafe.json")


def _values(terms: dict[str, Any], points: np.ndarray) -> np.ndarray:
    """A stated polynomial (exact terms) at points, in floating point (independent of the class's code)."""
    total = np.zeros(len(points))
    for c, exponents in terms["terms"]:
        total += float(Fraction(c)) * np.prod(points ** np.array(exponents), axis=1)
    return total


def _tampered(folder: Path, doc: dict[str, Any], change: Any, name: str) -> Any:
    bad = copy.deepcopy(doc)
    change(bad["conditions"]["barrier"])
    path = folder / name
    path.write_text(json.dumps(bad))
    return cli("verify", str(path))


def test_the_barrier_certifies_and_verify_rechecks_it(safe: tuple[Path, dict[str, Any], int]) -> None:
    path, doc, code = safe
    assert code == 0
    c = doc["conditions"]["barrier"]
    assert c["status"] == "certified" and c["property"] == "safety"
    assert c["certificate"]["kind"] == "discrete_barrier" and c["certificate"]["time"] == "discrete"
    assert "every iterate" in c["summary"] and "every step" in c["summary"] and "for all t" not in c["summary"]
    assert Fraction(c["certificate"]["lambda"]) >= 0
    done = cli("verify", str(path))
    assert done.exit_code == 0, done.output
    assert "barrier: B <= 0 on the initial set" in done.output


def test_the_certified_b_stays_nonpositive_along_the_iterates(safe: tuple[Path, dict[str, Any], int]) -> None:
    c = safe[1]["conditions"]["barrier"]
    rng = np.random.default_rng(7)
    r = 0.5 * np.sqrt(rng.uniform(size=300))
    angle = rng.uniform(0, 2 * np.pi, size=300)
    x = np.stack([r * np.cos(angle), r * np.sin(angle)], axis=1)  # the initial set x^2 + y^2 <= 0.25
    for _ in range(60):
        assert np.all(_values(c["certificate"]["B"], x) <= 1e-9)
        assert np.all(x[:, 1] < 2)  # never in the unsafe set y >= 2
        x = np.stack([0.3 * x[:, 0], -x[:, 0] + 0.5 * x[:, 1] + 7 / 18 * x[:, 0] ** 2], axis=1)


def test_a_tampered_certificate_fails_verify(safe: tuple[Path, dict[str, Any], int], tmp_path: Path) -> None:
    _, doc, _ = safe

    def constant_up(c: dict[str, Any]) -> None:  # B's constant raised: B <= 0 on the initial set is lost
        terms = c["certificate"]["B"]["terms"]
        zero = next(t for t in terms if not any(t[1]))
        zero[0] = str(Fraction(zero[0]) + 100)

    def lam_negative(c: dict[str, Any]) -> None:
        c["certificate"]["lambda"] = "-1"
        c["lambda"] = -1.0

    def gram_entry(c: dict[str, Any]) -> None:
        gram = c["certificate"]["gram_step"]
        key = next(k for k in gram if isinstance(gram[k], list) and gram[k] and isinstance(gram[k][0], list)
                   and all(isinstance(v, str) for v in gram[k][0]))
        gram[key][0][0] = str(Fraction(gram[key][0][0]) + 1)

    for k, change in enumerate((constant_up, lam_negative, gram_entry)):
        done = _tampered(tmp_path, doc, change, f"bad{k}.json")
        assert done.exit_code == 1, (change.__name__, done.output)
        assert "FAIL barrier" in done.output or "barrier:" in done.output


def test_the_unsafe_map_is_refuted_and_verify_rederives_the_iterate(unsafe: tuple[Path, dict[str, Any], int],
                                                                    tmp_path: Path) -> None:
    path, doc, code = unsafe
    assert code == 1
    c = doc["conditions"]["barrier"]
    assert c["status"] == "refuted" and c["status"] != "certified"
    assert c["refutation"]["kind"] == "discrete_iterate" and c["refutation"]["steps"] == c["steps_to_unsafe"]
    # the start, re-read and iterated here in floating point, is in the initial set and its iterate unsafe
    x0 = np.array([float(Fraction(c["refutation"]["start"][s])) for s in ("x", "y")])
    assert (x0[0] - 3) ** 2 + x0[1] ** 2 <= 0.01
    x = x0
    for _ in range(c["refutation"]["steps"]):
        x = np.array([0.3 * x[0], -x[0] + 0.5 * x[1] + 7 / 18 * x[0] ** 2])
    assert (x[0] - 0.9) ** 2 + (x[1] - 0.5) ** 2 <= 0.01
    assert cli("verify", str(path)).exit_code == 0

    def far_start(c: dict[str, Any]) -> None:
        c["refutation"]["start"] = {"x": "0", "y": "0"}

    def more_steps(c: dict[str, Any]) -> None:
        c["refutation"]["steps"] += 1
        c["steps_to_unsafe"] += 1

    for k, change in enumerate((far_start, more_steps)):
        assert _tampered(tmp_path, doc, change, f"bad{k}.json").exit_code == 1, change.__name__


def test_the_exact_iterate_check_refuses_what_is_not_proved() -> None:
    model = load_model(UNSAFE)
    ring, F = ds.map_polynomials(shifted_map(model))
    sets = ds.map_sets(model, ring)
    ok, _ = ds.check_iterate(ring, F, sets["initial"], sets["unsafe"], [Fraction(3), Fraction(0)], 1)
    assert ok  # (3, 0) -> (9/10, 1/2), the centre of the unsafe disc, exactly
    assert not ds.check_iterate(ring, F, sets["initial"], sets["unsafe"], [Fraction(3), Fraction(0)], 2)[0]
    assert not ds.check_iterate(ring, F, sets["initial"], sets["unsafe"], [Fraction(0), Fraction(0)], 1)[0]
    # the safe map: no start of its initial set reaches y >= 2 (the falsification finds none)
    safe_model = load_model(SAFE)
    ring, F = ds.map_polynomials(shifted_map(safe_model))
    sets = ds.map_sets(safe_model, ring)
    assert ds.falsify_map(safe_model, ring, F, sets["initial"], sets["unsafe"]) is None


def test_a_map_without_sets_is_not_applicable_and_naming_the_class_is_refused(tmp_path: Path) -> None:
    model = parse_model(NO_SETS, "nosets.toml")
    r = ds.run_barrier(model, shifted_map(model), Budget(10.0, "test"))
    assert r.status == "not_applicable"
    assert r.summary == "the model's [sets] needs 'initial' and 'unsafe' (docs/model-files.md, [sets])"
    path = tmp_path / "nosets.toml"
    path.write_text(NO_SETS)
    done = cli("certify", str(path), "--classes", "barrier", "--no-store")
    assert done.exit_code == 2 and "[sets]" in done.output
    done = cli("certify", str(path), "--no-store", "--json")  # barrier is not chosen without sets
    assert done.exit_code == 0 and "barrier" not in json.loads(done.stdout)["conditions"]


ROTATION = """[model]
name = "a contracting rotation"
states = ["x", "y"]
time = "discrete"
[dynamics]
x = "0.6*x - 0.6*y"
y = "0.6*x + 0.6*y"
[sets]
initial = ["(x - 1)**2 + y**2 <= 0.04"]
unsafe = ["(x + 1)**2 + (y - 1)**2 <= 0.04"]
goal = ["x**2 + y**2 <= 0.01"]
"""


def test_reach_avoid_certifies_with_a_steps_bound_that_the_iterates_respect(tmp_path: Path) -> None:
    path = tmp_path / "rotation.toml"
    path.write_text(ROTATION)
    out = tmp_path / "rotation.json"
    done = cli("certify", str(path), "--classes", "reach_avoid", "--no-store", "--json", "--out", str(out))
    assert done.exit_code == 0, done.output
    doc = json.loads(out.read_text())
    c = doc["conditions"]["reach_avoid"]
    assert c["status"] == "certified" and c["certificate"]["kind"] == "discrete_reach_avoid"
    bound = c["reach_steps_bound"]
    assert bound == int(Fraction(c["certificate"]["C"]) / Fraction(c["certificate"]["eps"]))
    assert f"within {bound} steps" in c["summary"] and "for all t" not in c["summary"]
    assert cli("verify", str(out)).exit_code == 0
    # every start sampled in the initial set reaches the goal within the bound, never unsafe before
    rng = np.random.default_rng(3)
    r = 0.2 * np.sqrt(rng.uniform(size=200))
    angle = rng.uniform(0, 2 * np.pi, size=200)
    x = np.stack([1 + r * np.cos(angle), r * np.sin(angle)], axis=1)
    reached = np.zeros(len(x), dtype=bool)
    for _ in range(min(bound, 1000) + 1):
        reached |= x[:, 0] ** 2 + x[:, 1] ** 2 <= 0.01
        assert not np.any(~reached & ((x[:, 0] + 1) ** 2 + (x[:, 1] - 1) ** 2 <= 0.04))
        x = np.stack([0.6 * x[:, 0] - 0.6 * x[:, 1], 0.6 * x[:, 0] + 0.6 * x[:, 1]], axis=1)
    assert reached.all()

    def bound_down(c: dict[str, Any]) -> None:
        c["reach_steps_bound"] -= 1
        c["certificate"]["reach_steps_bound"] -= 1

    def eps_up(c: dict[str, Any]) -> None:
        c["certificate"]["eps"] = str(Fraction(c["certificate"]["eps"]) * 2)

    for k, change in enumerate((bound_down, eps_up)):
        bad = copy.deepcopy(doc)
        change(bad["conditions"]["reach_avoid"])
        (tmp_path / f"bad{k}.json").write_text(json.dumps(bad))
        assert cli("verify", str(tmp_path / f"bad{k}.json")).exit_code == 1, change.__name__


def test_reach_avoid_is_refuted_by_an_unsafe_iterate_before_the_goal(tmp_path: Path) -> None:
    path = tmp_path / "unsafe-goal.toml"
    path.write_text(UNSAFE.read_text().replace('[sets]\n', '[sets]\ngoal = ["x**2 + y**2 <= 0.01"]\n'))
    out = tmp_path / "u.json"
    done = cli("certify", str(path), "--classes", "reach_avoid", "--no-store", "--json", "--out", str(out))
    assert done.exit_code == 1, done.output
    c = json.loads(out.read_text())["conditions"]["reach_avoid"]
    assert c["status"] == "refuted" and "before any iterate is in the goal" in c["summary"]
    assert cli("verify", str(out)).exit_code == 0
    # a goal that holds the start: the iterate is no longer 'before the goal', the check refuses it
    model = parse_model(path.read_text().replace('goal = ["x**2 + y**2 <= 0.01"]', 'goal = ["(x - 3)**2 + y**2 <= 1"]'),
                        "g.toml")
    ring, F = ds.map_polynomials(shifted_map(model))
    sets = ds.map_sets(model, ring)
    start = [Fraction(3), Fraction(0)]
    assert ds.check_iterate(ring, F, sets["initial"], sets["unsafe"], start, 1)[0]
    assert not ds.check_iterate(ring, F, sets["initial"], sets["unsafe"], start, 1, sets["goal"][0])[0]


def test_reach_avoid_with_stay_in_goal_is_not_taken_on_a_map(tmp_path: Path) -> None:
    path = tmp_path / "stay.toml"
    path.write_text(ROTATION + "stay_in_goal = true\n")
    done = cli("certify", str(path), "--classes", "reach_avoid", "--no-store", "--json")
    c = json.loads(done.stdout)["conditions"]["reach_avoid"]
    assert c["status"] == "not_applicable" and c["summary"] == ds.STAY_NOT_TAKEN


def _rotation_reach() -> tuple[Any, Any, Any, Any, Any]:
    model = parse_model(ROTATION, "rotation.toml")
    ring, F = ds.map_polynomials(shifted_map(model))
    sets = ds.map_sets(model, ring)
    return ring, F, sets["initial"], sets["unsafe"], sets["goal"][0]


def test_the_steps_bound_is_tightened_near_the_best_a_quadratic_v_gives() -> None:
    from lyapcheck.models.engines.search import Search

    ring, F, initial, unsafe, goal = _rotation_reach()
    search = Search(ring, Budget(60.0, "test"))
    structure = ds.reach_structure(ring, F, initial, unsafe, goal, 2)
    assert not isinstance(structure, str)
    loose, _ = ds.attempt_reach(ring, F, structure, 2, initial, unsafe, goal, search)
    assert loose is not None
    tight = ds.tighten_reach(ring, F, structure, 2, initial, unsafe, goal, loose, search)
    assert ds.check_discrete_reach(ring, F, initial, unsafe, goal, tight)[0]
    # For V = a |e|^2 - c (this map's V: rotation-invariant): V <= 0 on the initial disc needs c >= 1.44 a
    # (its farthest point, |e| = 1.2); the step lowers V by a (1 - 2 * 0.36) |e|^2 >= 0.0028 a outside the
    # goal (|e|^2 >= 0.01), so C / eps >= 1.44 / 0.0028 = 514.3 for any quadratic certificate, and no lower.
    assert 514 <= tight.steps_bound() <= 2 * 515 < loose.steps_bound()


def test_a_tighter_certificate_that_fails_the_exact_check_leaves_the_found_one(monkeypatch: pytest.MonkeyPatch) -> None:
    from lyapcheck.models.engines.search import Search

    ring, F, initial, unsafe, goal = _rotation_reach()
    search = Search(ring, Budget(60.0, "test"))
    structure = ds.reach_structure(ring, F, initial, unsafe, goal, 2)
    assert not isinstance(structure, str)
    loose, _ = ds.attempt_reach(ring, F, structure, 2, initial, unsafe, goal, search)
    assert loose is not None
    checked: list[int] = []

    def refuse_the_tighter(*args: Any) -> tuple[bool, str]:
        checked.append(args[-1].steps_bound())
        return False, "refused"

    monkeypatch.setattr(ds, "check_discrete_reach", refuse_the_tighter)
    assert ds.tighten_reach(ring, F, structure, 2, initial, unsafe, goal, loose, search) is loose
    assert checked and checked[0] < loose.steps_bound()  # a tighter one was found, and its check decided
