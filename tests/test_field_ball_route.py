"""``roa`` on a polynomial loop of 1 to 3 states: the SOS route's set and the ball-arithmetic route's
(:mod:`lyapcheck.models.classes.field_ball_route`), the one covering more of the simulated region of
attraction kept (issue 41), and ``verify`` running the kept ball-arithmetic proof again.

The loop: x' = -2x + xy, y' = -y + xy, stable at 0 with a saddle at (1, 2) whose stable manifold
bounds the region of attraction (a non-convex set). With ``--degree 4`` the SOS route's V is of
degree 4 and the ball route's fitted V (degree 6) covers more; with each class's own ladder the SOS
route's degree-8 V covers more.
"""

from __future__ import annotations

import json
from fractions import Fraction
from pathlib import Path
from typing import Any

import pytest
from click.testing import CliRunner

from lyapcheck.cli import app
from lyapcheck.degrees import degree_ceiling
from lyapcheck.models.classes.field_ball_route import ENGINE, SOS_ROUTE
from lyapcheck.tolerances import BALL_ROUTE_BESIDE_SHARE
from lyapcheck.models.language.modelfile import parse_model
from lyapcheck.models.surfaces.certify import certify_model

app._register_commands()  # (the commands are registered lazily)

SADDLE = """[model]
name = "a polynomial loop whose region of attraction a saddle at (1, 2) bounds"
states = ["x", "y"]

[dynamics]
x = "-2*x + x*y"
y = "-y + x*y"

[domain]
x = [-1, 3]
y = [-1, 3]
"""


def kept_and_other(numbers: dict[str, Any]) -> tuple[float, float, float]:
    """(the kept set's roa_share, the other route's, the SOS route's), checking that both routes'
    figures are stated over the same simulated starts."""
    other = numbers["other_route"]
    assert isinstance(other, dict), other
    assert {numbers["route"], other["route"]} == {SOS_ROUTE, ENGINE}
    kept, rival = numbers["roa_share"], other["roa_share"]
    return kept, rival, kept if numbers["route"] == SOS_ROUTE else rival


@pytest.mark.slow
@pytest.mark.parametrize("degree", [4, None])
def test_a_polynomial_loop_keeps_the_route_covering_more(degree: int | None) -> None:
    """Both routes prove a set; the kept one covers at least as much of the simulated region as the
    other (strictly more where the ball route's is kept), so the SOS route's figure never shrinks;
    the kept ball-arithmetic set is the whole sublevel set, stated with the recast route's sentence."""
    from lyapcheck.models.classes.claims import interval_sentence

    with degree_ceiling(degree):
        roa = certify_model(parse_model(SADDLE, "<saddle>"), classes="roa").results["roa"]
    assert roa.status == "certified"
    share = roa.numbers["roa_share"]
    if roa.numbers["route"] == SOS_ROUTE and share >= BALL_ROUTE_BESIDE_SHARE:  # (the ball route not tried then)
        assert "not tried" in roa.numbers["other_route"] and degree is None
        return
    kept, rival, sos = kept_and_other(roa.numbers)
    assert kept >= rival and kept >= sos
    if roa.numbers["route"] == ENGINE:
        assert kept > rival
        assert roa.numbers["engine"] == ENGINE and roa.certificate["kind"] == "interval"
        assert roa.certificate["whole"] is True and roa.summary == interval_sentence(roa.certificate)
        assert roa.numbers["tried"][0].startswith("sums of squares: region of attraction")
    else:
        assert "engine" not in roa.numbers and roa.certificate["kind"] != "interval"
    if degree == 4:  # (the degree-4 SOS set is the smaller one here: the switch is exercised)
        assert roa.numbers["route"] == ENGINE


@pytest.fixture(scope="module")
def kept_ball(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, dict[str, Any]]:
    """The loop certified from the command line with ``--degree 4`` (the ball route's set kept)."""
    where = tmp_path_factory.mktemp("saddle")
    model, out = where / "saddle.toml", where / "saddle.cert.json"
    model.write_text(SADDLE)
    done = CliRunner().invoke(app.cli, ["certify", str(model), "--classes", "roa", "--degree", "4", "--no-store",
                                        "--out", str(out)], catch_exceptions=False)
    assert done.exit_code == 0, done.output
    return out, json.loads(out.read_text())


@pytest.mark.slow
def test_verify_re_checks_the_kept_ball_region_and_refuses_a_changed_level_or_v(
        kept_ball: tuple[Path, dict[str, Any]], tmp_path: Path) -> None:
    """``verify`` runs the ball-arithmetic proof again on the polynomial model (exit 0); a larger level
    (its figure and sentence made to match) or a changed coefficient of V fails it (exit 1)."""
    from lyapcheck.models.classes.claims import interval_sentence

    path, doc = kept_ball
    roa = doc["conditions"]["roa"]
    assert roa["route"] == ENGINE and roa["certificate"]["kind"] == "interval"
    checked = CliRunner().invoke(app.cli, ["verify", str(path)], catch_exceptions=False)
    assert checked.exit_code == 0, checked.output
    assert "ok   roa:" in checked.output and "by ball arithmetic" in checked.output

    def tampered(edit: Any) -> Any:
        changed = json.loads(path.read_text())
        edit(changed["conditions"]["roa"])
        target = tmp_path / f"{edit.__name__}.cert.json"
        target.write_text(json.dumps(changed))
        return CliRunner().invoke(app.cli, ["verify", str(target)], catch_exceptions=False)

    def level(c: dict[str, Any]) -> None:
        raised = Fraction(c["certificate"]["level"]) * 3
        c["certificate"]["level"], c["level"] = str(raised), float(raised)
        c["summary"] = interval_sentence(c["certificate"])

    def coefficient(c: dict[str, Any]) -> None:
        terms = c["certificate"]["V"]["terms"]
        terms[0][0] = str(Fraction(terms[0][0]) / 4)

    for edit in (level, coefficient):
        failed = tampered(edit)
        assert failed.exit_code == 1, (edit.__name__, failed.output)
        assert "roa" in failed.output and "ball-arithmetic proof does not go through" in failed.output, failed.output


def test_the_ball_route_is_skipped_when_too_little_of_the_class_budget_is_left(monkeypatch: pytest.MonkeyPatch) -> None:
    """With less than BALL_ROUTE_MIN_SECONDS left the SOS set stands, ``tried`` saying why the ball
    route did not run (and it does not)."""
    import numpy as np

    from lyapcheck.models.classes import field_ball_route
    from lyapcheck.models.engines.search import Budget
    from lyapcheck.results import ConditionResult
    from lyapcheck.tolerances import BALL_ROUTE_MIN_SECONDS

    def never(*args: Any, **kwargs: Any) -> Any:
        raise AssertionError("the ball route ran with too little time left")

    monkeypatch.setattr(field_ball_route, "ball_region", never)
    model = parse_model(SADDLE, "<saddle>")
    assert field_ball_route.takes(model, nominal=True) and not field_ball_route.takes(model, nominal=False)
    sos = ConditionResult("roa", "certified", "region of attraction: ...", numbers={"roa_share": 0.5}, property="ROA")
    budget = Budget(BALL_ROUTE_MIN_SECONDS / 2, "lyapcheck.tolerances.MODEL_CLASS_TIME_LIMIT_S")
    kept = field_ball_route.larger_region(model, sos, budget, np.zeros((4, 2)), np.ones(4, dtype=bool))
    assert kept is sos and kept.numbers["route"] == SOS_ROUTE and "other_route" not in kept.numbers
    assert "BALL_ROUTE_MIN_SECONDS" in kept.numbers["tried"][-1] and "not tried" in kept.numbers["tried"][-1]
