"""Every printed claim is what was proved (issue 28, parts 1 and 2).

Disturbances: a model with ``[disturbances]`` gets, on every condition, the key ``disturbances``:
``"all"`` only where the claim holds for every disturbance signal within its bounds, ``"zero"``
where it was proved with the disturbances held at 0, and the verdict ``certified`` only through a
claim that covers them. ``x' = -x + d x`` diverges for ``d = 2`` (``x(t) = x0 e^t``) and decays for
every ``|d| <= 1/2`` (``V = x^2``, ``V' = 2(d - 1) x^2 <= -x^2``): the first may not be certified
robustly, the second must be.

``verify``: a summary is regenerated from the figures it re-checks, the candidate text must be the
certified V, every exponent and index is a non-negative integer, and a divisor that vanishes at the
equilibrium is refused even where a common factor would cancel it.
"""

from __future__ import annotations

import copy
import json
from pathlib import Path
from typing import Any

import pytest
import sympy as sp
from click.testing import CliRunner

from lyapcheck.cli import app
from lyapcheck.errors import ModelFileError
from lyapcheck.models.surfaces.certificate import build_document, verify_document
from lyapcheck.models.surfaces.certify import certify_model, verdict_of
from lyapcheck.models.language.modelfile import parse_model

app._register_commands()
RUNNER = CliRunner()
STABILITY = ("quadratic", "sos_gas")


def scalar(bound: str, rhs: str = "-x + d*x") -> str:
    return f'[model]\nname = "scalar"\nstates = ["x"]\n[disturbances]\nd = {bound}\n[dynamics]\nx = "{rhs}"\n'


def certify(text: str, **kwargs: Any) -> dict[str, Any]:
    return build_document(certify_model(parse_model(text, "<test>"), **kwargs))


def failed(doc: dict[str, Any]) -> list[str]:
    return [name for name, ok, _ in verify_document(doc) if not ok]


def failures(doc: dict[str, Any]) -> dict[str, str]:
    """Every failed check's messages, joined by check name."""
    out: dict[str, str] = {}
    for name, ok, why in verify_document(doc):
        if not ok:
            out[name] = f"{out[name]}; {why}" if name in out else why
    return out


def test_a_destabilising_disturbance_gets_no_robust_stability_claim() -> None:
    doc = certify(scalar("2"))
    for name, c in doc["conditions"].items():
        assert c["disturbances"] in ("zero", "all"), name
        if c["status"] == "certified" and name != "sos_bound":
            assert c["disturbances"] == "zero", name
            assert c["summary"].startswith("(d = 0) "), c["summary"]
    assert doc["conditions"]["quadratic"]["status"] == "certified"  # the nominal loop x' = -x is GES
    assert doc["conditions"]["sos_bound"]["status"] != "certified"  # x0 e^t has no ultimate bound
    assert doc["verdict"] == "certified_nominal"
    assert failed(doc) == []


def test_disturbances_that_vanish_at_the_equilibrium_are_covered_robustly() -> None:
    doc = certify(scalar("0.5"))
    for name in STABILITY:
        c = doc["conditions"][name]
        assert (c["status"], c["disturbances"]) == ("certified", "all"), (name, c["summary"])
        assert c["summary"].startswith("for every disturbance signal within its bounds: ")
        # V independent of d, and V' < 0 at every d of the box: checked here with sympy at the corners
        x, d = sp.symbols("x d")
        V = sum(sp.Rational(coef) * x ** e[0] for coef, e in c["certificate"]["V"]["terms"])
        for corner in (sp.Rational(-1, 2), sp.Rational(1, 2)):
            assert sp.simplify(sp.diff(V, x) * (-x + corner * x) / V) < 0
    assert doc["conditions"]["linearization"]["disturbances"] == "zero"  # the Jacobian at d = 0
    assert doc["conditions"]["sos_bound"]["disturbances"] == "all"
    assert doc["verdict"] == "certified"
    assert failed(doc) == []


def test_an_additive_disturbance_keeps_stability_claims_nominal_and_bound_covers_it() -> None:
    doc = certify(scalar("0.5", "-x + d"))
    for name in STABILITY:
        assert doc["conditions"][name]["disturbances"] == "zero"
        assert "robust_attempt" not in doc["conditions"][name]  # no robust form can exist: none tried
    assert doc["conditions"]["sos_bound"]["status"] == "certified"
    assert doc["verdict"] == "certified"  # through sos_bound, whose claim covers d
    nominal_only = certify(scalar("0.5", "-x + d"), classes="quadratic,sos_gas")
    assert nominal_only["verdict"] == "certified_nominal"


def test_a_disturbance_that_does_not_enter_the_field_is_covered_by_the_nominal_claim() -> None:
    doc = certify(scalar("0", "-x + d*x"))
    assert doc["conditions"]["quadratic"]["disturbances"] == "all"
    assert doc["verdict"] == "certified"


def test_the_verdict_rule() -> None:
    assert verdict_of({"a": {"status": "certified", "disturbances": "zero"}}) == "certified_nominal"
    assert verdict_of({"a": {"status": "certified", "disturbances": "zero"},
                       "b": {"status": "certified", "disturbances": "all"}}) == "certified"
    assert verdict_of({"a": {"status": "certified"}}) == "certified"
    assert verdict_of({"a": {"status": "not_certified", "disturbances": "all"}}) == "not_certified"


def test_the_command_line_says_nominal_and_exits_0(tmp_path: Path) -> None:
    path = tmp_path / "m.toml"
    path.write_text(scalar("2"))
    done = RUNNER.invoke(app.cli, ["certify", "--model", str(path)], env={"COLUMNS": "200"})
    assert done.exit_code == 0, done.output
    assert "certified_nominal" in done.output and "(d = 0)" in done.output
    assert "held at 0" in done.output


def test_a_nominal_claim_relabelled_all_fails_verify() -> None:
    doc = certify(scalar("2"), classes="quadratic")
    forged = copy.deepcopy(doc)
    c = forged["conditions"]["quadratic"]
    c["disturbances"] = "all"
    c["summary"] = c["summary"].replace("(d = 0) ", "for every disturbance signal within its bounds: ")
    forged["verdict"] = "certified"
    assert "quadratic" in failed(forged) and "verdict" in failed(forged)
    missing = copy.deepcopy(doc)
    del missing["conditions"]["quadratic"]["disturbances"]
    assert "quadratic" in failed(missing)


@pytest.fixture(scope="module")
def bounded() -> dict[str, Any]:
    return certify(scalar("0.5", "-x + d"))


def test_a_summary_edited_alone_fails_verify(bounded: dict[str, Any]) -> None:
    assert failed(bounded) == []
    forged = copy.deepcopy(bounded)
    c = forged["conditions"]["sos_bound"]
    assert "limsup |x| <= 0.5" in c["summary"]
    c["summary"] = c["summary"].replace("limsup |x| <= 0.5", "limsup |x| <= 0.1")
    # the verdict falls with it (sos_bound was the one claim that covered the disturbance), and the
    # answer to the bounds question
    assert set(failed(forged)) == {"sos_bound", "verdict", "answers"}
    lowered = copy.deepcopy(bounded)  # a figure lowered alone is caught by the exact check
    lowered["conditions"]["sos_bound"]["bounds"]["x"] = 0.1
    assert "sos_bound" in failed(lowered)
    other = copy.deepcopy(bounded)  # and a GES sentence with an edited rate
    q = other["conditions"]["quadratic"]
    q["summary"] = q["summary"].replace("exp(-", "exp(-9")
    # (the stability answer rested on quadratic's GES, so it falls with it)
    assert failed(other) == ["quadratic", "answers"]


@pytest.mark.parametrize("value", [1.4, 2.4, -1, 1.0, "1", True])
def test_a_gram_exponent_that_is_not_a_non_negative_integer_fails_verify(bounded: dict[str, Any],
                                                                         value: object) -> None:
    forged = copy.deepcopy(bounded)
    forged["conditions"]["quadratic"]["certificate"]["gram_V"]["basis"][0][0] = value
    rows = failures(forged)
    assert "quadratic" in rows and "basis" in rows["quadratic"], rows


@pytest.mark.parametrize("value", [2.0, 1.5, -2])
def test_a_stated_v_exponent_that_is_not_an_integer_fails_verify(bounded: dict[str, Any], value: object) -> None:
    forged = copy.deepcopy(bounded)
    forged["conditions"]["quadratic"]["certificate"]["V"]["terms"][0][1][0] = value
    rows = failures(forged)
    assert "quadratic" in rows and "V.terms" in rows["quadratic"], rows


def test_a_box_multiplier_index_out_of_range_fails_verify() -> None:
    doc = certify(scalar("0.5"), classes="quadratic")
    c = doc["conditions"]["quadratic"]["certificate"]
    assert c["box_multipliers"], "the robust certificate carries the multiplier of d's interval"
    for value in (0.5, 7, -1):
        forged = copy.deepcopy(doc)
        forged["conditions"]["quadratic"]["certificate"]["box_multipliers"][0]["variable"] = value
        rows = failures(forged)
        assert "quadratic" in rows and "variable" in rows["quadratic"], rows


CANDIDATE_MODEL = '[model]\nname = "c"\nstates = ["x1", "x2"]\n[dynamics]\nx1 = "-x1 + x2"\nx2 = "-x2"\n'


def test_the_candidate_text_must_be_the_certified_v() -> None:
    doc = build_document(certify_model(parse_model(CANDIDATE_MODEL, "<test>"), classes="candidate",
                                       candidate="x1**2 + 2*x2**2"))
    assert doc["conditions"]["candidate"]["status"] == "certified"
    assert failed(doc) == []
    for text in ("x1**2 + 3*x2**2", "x1**2 + 2*x2**2 + x1*x2", "import os", None):
        forged = copy.deepcopy(doc)
        forged["candidate"] = text
        assert "candidate" in failed(forged), text


def test_a_document_round_trips_through_the_cli(tmp_path: Path) -> None:
    path = tmp_path / "m.toml"
    path.write_text(scalar("0.5", "-x + d"))
    out = tmp_path / "c.json"
    done = RUNNER.invoke(app.cli, ["certify", "--model", str(path), "--classes", "sos_bound", "--out", str(out)])
    assert done.exit_code == 0, done.output
    doc = json.loads(out.read_text())
    doc["conditions"]["sos_bound"]["summary"] = "for every start: limsup |x| <= 0.1"
    out.write_text(json.dumps(doc))
    done = RUNNER.invoke(app.cli, ["verify", str(out)])
    assert done.exit_code == 1 and "FAIL sos_bound" in done.output, done.output


@pytest.mark.parametrize("rhs, equilibrium", [("-x**2/x", "0"), ("-(x - 1)*x/(x - 1)", "1"),
                                              ("-x + x**3/(x*(1 + x**2))", "0")])
def test_a_divisor_that_vanishes_at_the_equilibrium_is_refused_even_when_it_cancels(rhs: str,
                                                                                      equilibrium: str) -> None:
    text = f'[model]\nname = "s"\nstates = ["x"]\n[equilibrium]\nx = {equilibrium}\n[dynamics]\nx = "{rhs}"\n'
    with pytest.raises(ModelFileError) as raised:
        parse_model(text, "<test>")
    message = str(raised.value)
    assert "[dynamics] x" in message and "is 0 at the equilibrium" in message and "\n" not in message


def test_a_divisor_that_cancels_away_from_the_equilibrium_is_accepted() -> None:
    text = '[model]\nname = "s"\nstates = ["x"]\n[equilibrium]\nx = 1\n[dynamics]\nx = "-(x - 1)*x/x"\n'
    model = parse_model(text, "<test>")
    assert model.dynamics[0].is_polynomial()


def test_every_condition_of_a_disturbed_model_says_which_disturbances_even_when_not_applicable() -> None:
    # a denominator that cannot be proved of one sign makes the cleared classes not_applicable
    text = scalar("0.5", "-x/(x - 1) + d*x")
    doc = certify(text.replace('[dynamics]', '[equilibrium]\nx = 0\n[dynamics]'), classes="quadratic,candidate")
    assert all(c["disturbances"] in ("zero", "all") for c in doc["conditions"].values()), doc["conditions"]
    assert "candidate" in doc["conditions"] and doc["conditions"]["candidate"]["status"] == "not_applicable"
    assert failed(doc) == []


def test_a_candidate_text_that_is_no_candidate_fails_even_where_nothing_certified_it() -> None:
    doc = certify(scalar("0.5"), classes="quadratic")
    given = copy.deepcopy(doc)
    given["candidate"] = "x**2"  # given with --candidate while only other classes ran: shown, must parse
    assert failed(given) == []
    for text in ("y**2", "import os", 3):
        forged = copy.deepcopy(doc)
        forged["candidate"] = text
        assert "candidate" in failed(forged), text


def test_a_report_of_a_figure_beyond_doubles_is_written_not_an_internal_error(tmp_path: Path) -> None:
    from reports.render import certificate_html

    doc = certify(scalar("0.5"), classes="quadratic")
    doc["conditions"]["quadratic"]["k"] = 10**400
    assert "quadratic" in failed(doc)
    assert "Stability certificate" in certificate_html(doc, simulate=False, recheck=False)
