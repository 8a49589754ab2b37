"""``reach_avoid`` on a discrete-time map with functions (issue 44;
:mod:`lyapcheck.models.classes.map_relations_reach`).

The tanh reach map (examples/models/discrete-tanh-reach-map.toml) is certified with a steps bound that the
TRUE map (numpy's tanh, independent of the class's code) obeys from every sampled start of the initial disc:
each reaches the goal within the bound and none is unsafe before; ``V`` obeys its inequalities at sampled
points. ``verify`` (the one flow, the CLI) re-checks it, and a forged steps bound, ``eps`` or ``V`` fails it.
A goal the iterates never reach is ``not_certified`` with a reason (not ``refuted``: staying out of the goal
refutes nothing; tests/test_discrete_safety_box.py has the refutation by an unsafe iterate before the goal),
and a model without the sets is ``not_applicable``.
"""

from __future__ import annotations

import copy
import json
import math
from fractions import Fraction
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from click.testing import CliRunner

from lyapcheck.cli import app
from lyapcheck.models.classes import map_relations_reach as mrr
from lyapcheck.models.classes.claims import summary
from lyapcheck.models.classes.map_relations import on_relations
from lyapcheck.models.engines.recast_sos import poly_from_json
from lyapcheck.models.engines.search import Budget
from lyapcheck.models.language.modelfile import load_any_model, parse_any_model
from lyapcheck.models.language.recast import RecastModel

app._register_commands()

REACH = Path(__file__).resolve().parents[1] / "examples" / "models" / "discrete-tanh-reach-map.toml"


def cli(*args: str) -> Any:
    done = CliRunner().invoke(app.cli, list(args))
    assert done.exception is None or isinstance(done.exception, SystemExit), done.output
    assert "Traceback" not in done.output
    return done


def _map(source: str | Path) -> RecastModel:
    model = load_any_model(source) if isinstance(source, Path) else parse_any_model(source)
    assert isinstance(model, RecastModel)
    return model


def _step(x: float, y: float) -> tuple[float, float]:
    return y, -0.5 * x + 0.8 * math.tanh(y)


@pytest.fixture(scope="module")
def certified(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, dict[str, Any]]:
    out = tmp_path_factory.mktemp("reach") / "reach.json"
    done = cli("certify", str(REACH), "--classes", "reach_avoid", "--no-store", "--out", str(out))
    assert done.exit_code == 0, done.output
    return out, json.loads(out.read_text())


def _condition(doc: dict[str, Any]) -> dict[str, Any]:
    condition = doc["conditions"]["reach_avoid"]
    assert isinstance(condition, dict)
    return condition


def test_certified_bound_holds_on_the_true_map(certified: tuple[Path, dict[str, Any]]) -> None:
    _, doc = certified
    c = _condition(doc)
    assert c["status"] == "certified" and c["certificate"]["kind"] == mrr.KIND
    bound = c["reach_steps_bound"]
    eps, C = Fraction(c["certificate"]["eps"]), Fraction(c["certificate"]["C"])
    assert bound == max(0, math.floor(C / eps)) and bound >= 1
    rng = np.random.default_rng(7)
    radii = np.concatenate([0.1 * np.sqrt(rng.random(2000)), np.full(200, 0.1)])  # the disc and its rim
    for r, t in zip(radii, rng.uniform(0, 2 * math.pi, radii.size)):
        x, y = 0.5 + r * math.cos(t), r * math.sin(t)
        for _ in range(bound + 1):
            if x * x + y * y <= 0.04:
                break
            assert x < 1.5, "an iterate is unsafe before the goal"
            x, y = _step(x, y)
        else:
            pytest.fail(f"a start did not reach the goal within {bound} steps")


def test_v_obeys_its_inequalities_on_the_true_map(certified: tuple[Path, dict[str, Any]]) -> None:
    _, doc = certified
    c = _condition(doc)
    m = on_relations(_map(REACH))
    V = poly_from_json(m.ring, c["certificate"]["V"], "V")
    eps, C = (float(Fraction(c["certificate"][k])) for k in ("eps", "C"))

    def v(x: float, y: float) -> float:
        return float(m.ring.evaluate(V, [Fraction(x), Fraction(y)] + [Fraction(0)] * (m.ring.nvars - 2)))

    rng = np.random.default_rng(8)
    for r, t in zip(0.1 * np.sqrt(rng.random(50)), rng.uniform(0, 2 * math.pi, 50)):
        assert v(0.5 + r * math.cos(t), r * math.sin(t)) <= 1e-9
    for x, y in zip(rng.uniform(1.5, 6, 50), rng.uniform(-6, 6, 50)):
        assert v(x, y) >= 1 - 1e-9
    for x, y in zip(rng.uniform(-4, 4, 200), rng.uniform(-4, 4, 200)):
        assert v(x, y) >= -C - 1e-9
        if x * x + y * y > 0.04:
            assert v(*_step(x, y)) <= v(x, y) - eps + 1e-9 * (1 + abs(v(x, y)))


def test_verify_passes_and_the_sentence_is_the_claims(certified: tuple[Path, dict[str, Any]]) -> None:
    path, doc = certified
    c = _condition(doc)
    assert c["summary"] == summary("reach_avoid", c)
    assert str(c["reach_steps_bound"]) in c["summary"]
    done = cli("verify", str(path))
    assert done.exit_code == 0, done.output
    ok, why = mrr.verify(_map(REACH), c)
    assert ok and "on the recasting's relations" in why


def _forged(doc: dict[str, Any], tmp_path: Path, change: Any) -> tuple[int, tuple[bool, str]]:
    forged = copy.deepcopy(doc)
    change(_condition(forged))
    out = tmp_path / "forged.json"
    out.write_text(json.dumps(forged))
    return cli("verify", str(out)).exit_code, mrr.verify(_map(REACH), _condition(forged))


def test_forged_certificates_fail_verify(certified: tuple[Path, dict[str, Any]], tmp_path: Path) -> None:
    _, doc = certified

    def fewer_steps(c: dict[str, Any]) -> None:  # a smaller bound, stated consistently everywhere
        bound = c["reach_steps_bound"] - 1
        c["reach_steps_bound"] = c["certificate"]["reach_steps_bound"] = bound
        c["summary"] = summary("reach_avoid", c)

    code, (ok, why) = _forged(doc, tmp_path, fewer_steps)
    assert code != 0 and not ok and "floor(C / eps)" in why

    def larger_eps(c: dict[str, Any]) -> None:  # eps doubled (and the bound with it): the step identity fails
        cert = c["certificate"]
        cert["eps"] = str(Fraction(cert["eps"]) * 2)
        bound = max(0, math.floor(Fraction(cert["C"]) / Fraction(cert["eps"])))
        c["reach_steps_bound"] = cert["reach_steps_bound"] = bound
        c["summary"] = summary("reach_avoid", c)

    code, (ok, why) = _forged(doc, tmp_path, larger_eps)
    assert code != 0 and not ok and "does not hold" in why

    def shifted_v(c: dict[str, Any]) -> None:  # V's constant moved by 1: V <= 0 on the initial set fails
        constant = next(t for t in c["certificate"]["V"]["terms"] if not any(t[1]))
        constant[0] = str(Fraction(constant[0]) + 1)

    code, (ok, _) = _forged(doc, tmp_path, shifted_v)
    assert code != 0 and not ok


def test_a_goal_never_reached_is_not_certified_with_a_reason() -> None:
    # the iterates tend to the origin: a goal around (3, 0) is never reached (not refuted: no iterate is unsafe)
    text = REACH.read_text().replace('goal = ["x**2 + y**2 <= 0.04"]', 'goal = ["(x - 3)**2 + y**2 <= 0.04"]')
    result = mrr.run(_map(text), Budget(60.0, "test"))
    assert result.status == "not_certified", result.summary
    assert "reach-avoid" in result.summary and any("degree 4" in line for line in result.numbers["tried"])


def test_without_a_goal_or_with_a_goal_of_two_pieces_it_is_not_applicable() -> None:
    no_goal = REACH.read_text().replace('goal = ["x**2 + y**2 <= 0.04"]', "")
    result = mrr.run(_map(no_goal), Budget(60.0, "test"))
    assert result.status == "not_applicable" and "[sets]" in result.summary
    two = REACH.read_text().replace('goal = ["x**2 + y**2 <= 0.04"]',
                                    'goal = [["x**2 + y**2 <= 0.04"], ["(x - 3)**2 + y**2 <= 0.04"]]')
    assert mrr.run(_map(two), Budget(60.0, "test")).status == "not_applicable"


def test_a_point_sweep_cross_checks_the_certified_bound_on_the_true_map(certified: tuple[Path, dict[str, Any]]
                                                                         ) -> None:
    # a map with functions' point sweep takes reach_avoid (sweeps.spec: MAP_FUNCTIONS but sos_bound), and its
    # cross-check iterates the true map against reach_steps_bound: no violation, and a bound of 1 step is caught
    from sweeps.crosscheck import cross_check_point
    from sweeps.spec import map_classes

    assert "reach_avoid" in map_classes(_map(REACH))
    _, doc = certified
    found = cross_check_point(_map(REACH), doc, {}, starts=40, seed=[3])
    assert found.violations == [] and found.trajectories >= 40 and 0 < found.reach_ratio <= 1
    late = copy.deepcopy(doc)
    late["conditions"]["reach_avoid"]["reach_steps_bound"] = 1
    found = cross_check_point(_map(REACH), late, {}, starts=40, seed=[3])
    assert any(v.startswith("reach_avoid") and "not in the goal by the certified 1 steps" in v
               for v in found.violations)
