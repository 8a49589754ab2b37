"""``roa`` of a polynomial or rational loop by ball arithmetic where the SOS route does not certify
(issue 41: the SOS route and the ball-arithmetic route are two engines of one class).

The ball route (:mod:`lyapcheck.models.surfaces.ball_roa`) is the recast route's, on the loop read as a loop
with no auxiliaries. Here it is a fallback, where the SOS route does not certify (beside a certified
SOS set, the larger of the two is kept: tests/test_field_ball_route.py). A rational loop whose denominator changes sign away from the equilibrium gets no SOS class
at all (the field cannot be multiplied through); ball arithmetic evaluates the true field and proves
a region. ``verify`` runs the same proof again from the certificate alone, and refuses an edit.
"""

from __future__ import annotations

import copy
import json
from fractions import Fraction
from pathlib import Path
from typing import Any, Callable

import pytest
from click.testing import CliRunner

from lyapcheck import api
from lyapcheck.cli import app
from lyapcheck.models.surfaces import ball_roa
from lyapcheck.models.surfaces.certify import certify_model
from lyapcheck.models.language.modelfile import load_model, parse_model

app._register_commands()  # (the commands are registered lazily, for an instant --help)

MODELS = Path(__file__).resolve().parent.parent / "examples" / "models"

#: x1' = -x1 + x2, x2' = -x1 - x2 + x1^2/(2 - x1): Hurwitz at 0 (J = [[-1, 1], [-1, -1]]), a pole at
#: x1 = 2 and a second equilibrium at (4/3, 4/3), so the region of attraction is bounded on that side.
#: The denominator 2 - x1 changes sign, so no SOS class applies; the true field is smooth on the region.
POLE = """[model]
name = "a rational loop with a pole at x1 = 2"
states = ["x1", "x2"]

[dynamics]
x1 = "-x1 + x2"
x2 = "-x1 - x2 + x1**2/(2 - x1)"

[domain]
x1 = [-1, 1]
x2 = [-1, 1]
"""

Doc = dict[str, Any]


@pytest.fixture(scope="module")
def pole(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Doc, Any]:
    """The rational loop certified from the command line: (certificate file, document, CLI result)."""
    where = tmp_path_factory.mktemp("pole")
    model, out = where / "pole.toml", where / "pole.cert.json"
    model.write_text(POLE)
    done = CliRunner().invoke(app.cli, ["certify", str(model), "--json", "--no-store", "--out", str(out)],
                              catch_exceptions=False)
    return out, json.loads(out.read_text()), done


def test_a_rational_loop_no_sos_class_takes_gets_its_region_by_ball_arithmetic(pole: tuple[Path, Doc, Any]) -> None:
    from lyapcheck.models.classes.claims import interval_sentence as claim_sentence

    path, doc, done = pole
    assert done.exit_code == 0, done.output
    conditions = doc["conditions"]
    for name in ("quadratic", "sos_gas"):  # the SOS route: the denominator x1 - 2 is not of one sign
        assert conditions[name]["status"] == "not_applicable" and "x1 - 2" in conditions[name]["summary"]
    roa = conditions["roa"]
    assert roa["status"] == "certified" and roa["property"] == "ROA" and roa["engine"] == ball_roa.ENGINE
    cert = roa["certificate"]
    assert cert["kind"] == "interval" and cert["whole"] is True and cert["auxiliaries"] == {}
    assert cert["variables"] == ["x1", "x2"] and roa["level"] == float(Fraction(cert["level"]))
    assert roa["summary"] == claim_sentence(cert)  # the recast route's sentence, "V(x)": no function
    assert roa["tried"][0].startswith("sums of squares: the denominator x1 - 2")
    assert roa["degree"] == max(sum(e) for _, e in cert["V"]["terms"])
    assert doc["verdict"] == "certified" and doc["answers"]["stability"]["by"] == "roa"
    # the set excludes the second equilibrium (4/3, 4/3), where V' = 0: V > level there
    V = sum(Fraction(c) * Fraction(4, 3) ** (e[0] + e[1]) for c, e in cert["V"]["terms"])
    assert V > Fraction(cert["level"])
    checked = CliRunner().invoke(app.cli, ["verify", str(path)], catch_exceptions=False)
    assert checked.exit_code == 0, checked.output
    assert "ok   roa:" in checked.output and "by ball arithmetic" in checked.output


def edited(doc: Doc, edit: Callable[[Doc], Any]) -> Doc:
    out = copy.deepcopy(doc)
    edit(out)
    return out


def refused(doc: Doc) -> dict[str, str]:
    """The failed rows of ``verify`` (check -> messages)."""
    result = api.verify(doc)
    failed: dict[str, str] = {}
    for c in result.checks:
        if not c.ok:
            failed[c.check] = failed.get(c.check, "") + c.message
    assert not result.valid and failed
    return failed


def test_a_tampered_ball_region_is_refused(pole: tuple[Path, Doc, Any]) -> None:
    """Each edit is refused by the check that names it; an edit of the claim itself, with its
    sentence made again to match, by the proof run again."""
    from lyapcheck.models.classes.claims import interval_sentence as claim_sentence

    _, doc, _ = pole

    def roa(d: Doc) -> dict[str, Any]:
        return d["conditions"]["roa"]

    def raise_level(d: Doc) -> None:  # a larger set, stated consistently everywhere
        level = Fraction(roa(d)["certificate"]["level"]) * 2
        roa(d)["certificate"]["level"] = str(level)
        roa(d)["level"] = float(level)
        roa(d)["summary"] = claim_sentence(roa(d)["certificate"])

    def narrow(d: Doc) -> None:  # the set said to lie in a smaller box
        box = roa(d)["certificate"]["box"]
        box["x1"][1] = str(Fraction(box["x1"][1]) / 4)
        roa(d)["summary"] = claim_sentence(roa(d)["certificate"])

    def coefficient(d: Doc) -> None:
        terms = roa(d)["certificate"]["V"]["terms"]
        terms[0][0] = str(Fraction(terms[0][0]) / 4)

    def engine(d: Doc) -> None:
        roa(d)["engine"] = "sos"

    def part(d: Doc) -> None:
        roa(d)["certificate"]["whole"] = False

    def stated(d: Doc) -> None:
        roa(d)["level"] = roa(d)["level"] * 1.5

    def invented(d: Doc) -> None:
        roa(d)["k"] = 3

    proof = "the ball-arithmetic proof does not go through"
    for edit, words in ((raise_level, proof), (narrow, proof), (coefficient, proof), (engine, "engine"),
                        (part, "whole sublevel set"), (stated, "stated level"), (invented, "'k'")):
        failed = refused(edited(doc, edit))
        assert words in failed.get("roa", ""), (edit.__name__, failed)


def test_a_loop_sos_certifies_keeps_its_sos_region(monkeypatch: pytest.MonkeyPatch) -> None:
    """Where the SOS route certifies a set holding every converging simulated start (drake-cubic), the
    fallback is not tried and no ball route runs beside it (no set can cover more: tests/test_field_ball_route.py
    has the loops where both run), and the condition is the SOS route's (its certificate kind, no ``engine``)."""
    def never(*args: Any, **kwargs: Any) -> Any:
        raise AssertionError("the ball route was tried after the SOS route certified")

    monkeypatch.setattr(ball_roa, "after_sos", never)
    result = certify_model(load_model(MODELS / "drake-cubic-polynomial.toml"), classes="linearization,roa")
    roa = result.results["roa"]
    assert roa.status == "certified" and roa.certificate["kind"] in ("sublevel", "quadratic_ball")
    assert "engine" not in roa.numbers and "tried" not in roa.numbers
    assert roa.numbers["route"] == "sos" and roa.numbers["roa_share"] == 1.0 and "not tried" in roa.numbers["other_route"]


def test_the_ball_route_is_not_tried_once_the_sos_route_spent_the_time_limit(monkeypatch: pytest.MonkeyPatch) -> None:
    """A limit already reached leaves roa inconclusive, naming it, as before: the class's time is spent."""
    def never(*args: Any, **kwargs: Any) -> Any:
        raise AssertionError("the ball route was tried after the time limit")

    monkeypatch.setattr(ball_roa, "after_sos", never)
    roa = certify_model(load_model(MODELS / "van-der-pol-reversed.toml"), classes="roa", time_limit_s=0).results["roa"]
    assert roa.status == "inconclusive" and "MODEL_CLASS_TIME_LIMIT_S" in " ".join(roa.numbers["detail"])


def test_where_neither_engine_proves_a_region_the_reason_names_both(monkeypatch: pytest.MonkeyPatch) -> None:
    """The ball route's engine finding nothing (its reason stands in for it here): ``not_certified``,
    the sentence saying that neither sums of squares nor ball arithmetic proved one, the ball
    route's reason in the detail."""
    from lyapcheck.models.classes import recast_interval

    monkeypatch.setattr(recast_interval, "interval_roa", lambda *args, **kwargs: "ball arithmetic: no V fitted")
    roa = certify_model(parse_model(POLE, "<pole>"), classes="roa").results["roa"]
    assert roa.status == "not_certified" and "engine" not in roa.numbers
    assert roa.summary.startswith("no region of attraction was proved: the SOS route does not apply (the "
                                  "denominator x1 - 2"), roa.summary
    assert "nor was one proved by ball arithmetic (python-flint arb) on the true field" in roa.summary
    assert roa.numbers["detail"][-1] == "ball arithmetic: no V fitted"


@pytest.mark.slow
def test_a_region_for_every_disturbance_value_is_proved_and_re_checked_with_the_disturbances() -> None:
    """The same loop with ``d*x1`` added, ``|d| <= 1/100`` (0 at the equilibrium): the set is proved for
    every value of ``d`` at once (``disturbances`` "all", its bounds in the certificate), and verify
    re-runs that proof on the loop with ``d`` as a ball; a certificate claiming wider bounds is refused."""
    text = POLE.replace('x1**2/(2 - x1)"', 'x1**2/(2 - x1) + d*x1"\n\n[disturbances]\nd = 0.01')
    doc = api.certify(model=parse_model(text, "<pole, disturbed>"), classes="roa").to_json()
    roa = doc["conditions"]["roa"]
    assert roa["status"] == "certified" and roa["engine"] == ball_roa.ENGINE and roa["disturbances"] == "all"
    assert roa["certificate"]["disturbances"] == {"d": ["-1/100", "1/100"]}
    assert api.verify(doc).valid
    wider = edited(doc, lambda d: d["conditions"]["roa"]["certificate"].update(disturbances={"d": ["-1/10", "1/10"]}))
    assert "disturbances" in refused(wider).get("roa", "")


INTO_THE_POLE = """[model]
name = "one state whose trajectories beyond 1.5 run into a pole at x = 3"
states = ["x"]

[dynamics]
x = "-x + x**2/(3 - x)"
"""


@pytest.mark.slow
def test_trajectories_that_run_into_a_pole_do_not_eat_the_class(tmp_path: Path) -> None:
    """x' = -x + x**2/(3 - x): equilibria 0 and 1.5, and from (1.5, 3) a finite escape into the pole,
    which the integrator approaches step by step. The fallback's simulations stop each trajectory at
    BALL_FALLBACK_FIT_STEPS (a count), so the class proves its region instead of reaching the time
    limit (before: inconclusive after 95 s); the region stays left of the second equilibrium 1.5."""
    model, out = tmp_path / "pole1.toml", tmp_path / "pole1.cert.json"
    model.write_text(INTO_THE_POLE)
    done = CliRunner().invoke(app.cli, ["certify", str(model), "--classes", "roa", "--no-store", "--out", str(out)],
                              catch_exceptions=False)
    assert done.exit_code == 0, done.output
    roa = json.loads(out.read_text())["conditions"]["roa"]
    assert roa["status"] == "certified" and roa["engine"] == ball_roa.ENGINE
    lo, hi = (Fraction(b) for b in roa["certificate"]["box"]["x"])
    assert lo < 0 < hi < Fraction(3, 2)
    assert CliRunner().invoke(app.cli, ["verify", str(out)]).exit_code == 0
