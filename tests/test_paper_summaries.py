"""The paper's certificates: ``verify`` checks every sentence a certificate states (issue 28, part 2).

A decided condition's ``summary`` (``certified``, ``refuted``, ``holds``, ``fails``) is what a reader
believes. :mod:`lyapcheck.paper.claims` makes it from the condition's exact data alone, at creation;
``verify`` regenerates it from the data it has just re-checked and fails where the file's text
differs, and the report prints the regenerated text. Undecided conditions keep their reason,
unchecked. Every exponent, index and count read from a certificate is a JSON integer: a ``2.0``
(equal to ``2`` in Python), a ``2.5`` or a ``true`` fails the check and names the key.
"""

from __future__ import annotations

import copy
import json
from pathlib import Path
from typing import Any

import pytest
from click.testing import CliRunner, Result

from lyapcheck.paper.certificate import build_box_document, build_document, verify_document
from lyapcheck.paper.certification import CONDITION_ORDER, run_conditions, verdict
from lyapcheck.cli import app
from lyapcheck.paper import claims
from lyapcheck.paper.boxes.box import parse_box
from lyapcheck.paper.boxes.classes import BOX_CLASSES
from lyapcheck.paper.params import problem_from_sources
from tests.conftest import EASY_GAINS, PAPER_TOML

app._register_commands()
RUNNER = CliRunner()
BOX = ["alpha_d=588..612", "k_d=0.147..0.153"]


def _certify(tmp: Path, *args: str) -> dict[str, Any]:
    path = tmp / "certificate.json"
    result = RUNNER.invoke(app.cli, ["certify", str(PAPER_TOML), *args, "--out", str(path)])
    assert result.exit_code == 0, result.output
    doc: dict[str, Any] = json.loads(path.read_text())
    return doc


@pytest.fixture(scope="module")
def point(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Any]:
    """``lyapcheck certify examples/paper.toml``: every class at the paper's gains."""
    return _certify(tmp_path_factory.mktemp("point"))


@pytest.fixture(scope="module")
def box(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Any]:
    """``lyapcheck certify examples/paper.toml --box ... --classes all`` (about 10 s)."""
    return _certify(tmp_path_factory.mktemp("box"), "--box", BOX[0], "--box", BOX[1], "--classes", "all")


@pytest.fixture(scope="module")
def others() -> dict[str, dict[str, Any]]:
    """Documents whose classes decide otherwise: the printed dynamics (sector_ges and switched_ges
    certified), the easy gains (prop41_* certified, stabcond2 fails), no d* and no Omega_SO."""
    out = {}
    base = {"gains.alpha_d": "600", "gains.sigma0": "0.01", "gains.k_d": "0.15", "gains.delta_los": "0.75 mm",
            "swimmer.e11": "9.3e-5 m"}
    for label, problem, dynamics in (("printed", problem_from_sources(PAPER_TOML, {}), "printed"),
                                     ("easy", problem_from_sources(PAPER_TOML, EASY_GAINS), "derived"),
                                     ("flags", problem_from_sources(None, base), "derived")):
        results = run_conditions(problem, dynamics, CONDITION_ORDER)
        out[label] = json.loads(json.dumps(build_document(problem, dynamics, results, verdict(results))))
    return out


def verify_file(tmp_path: Path, doc: dict[str, Any]) -> Result:
    path = tmp_path / "edited.json"
    path.write_text(json.dumps(doc))
    return RUNNER.invoke(app.cli, ["verify", str(path)])


def failed_rows(doc: dict[str, Any]) -> dict[str, str]:
    out: dict[str, str] = {}
    for name, ok, message in verify_document(doc):
        if not ok:
            out[name] = f"{out[name]}; {message}" if name in out else message
    return out


def test_untouched_certificates_verify(point: dict[str, Any], box: dict[str, Any],
                                       others: dict[str, dict[str, Any]], tmp_path: Path) -> None:
    for doc in (point, box):
        result = verify_file(tmp_path, doc)
        assert result.exit_code == 0, result.output
    for label, doc in others.items():
        assert not failed_rows(doc), label


def test_a_bound_lowered_in_the_summary_only_fails(point: dict[str, Any], tmp_path: Path) -> None:
    doc = copy.deepcopy(point)
    true = doc["conditions"]["ultimate_bound"]["summary"]
    assert "limsup |eps| <= 0.03491 m" in true
    doc["conditions"]["ultimate_bound"]["summary"] = true.replace("0.03491 m", "0.001 m")
    result = verify_file(tmp_path, doc)
    assert result.exit_code == 1, result.output
    line = next(line for line in result.output.splitlines() if line.startswith("FAIL"))
    assert "ultimate_bound" in line and "summary" in line and repr(true) in line, result.output
    assert "Traceback" not in result.output


def test_a_refutation_turned_into_a_claim_fails(point: dict[str, Any], tmp_path: Path) -> None:
    doc = copy.deepcopy(point)
    assert doc["conditions"]["prop41_ges"]["status"] == "refuted"
    doc["conditions"]["prop41_ges"]["summary"] = claims.PROP41_HOLDS  # the sentence of a certified one
    result = verify_file(tmp_path, doc)
    assert result.exit_code == 1, result.output
    assert "FAIL prop41_ges" in result.output and "no P satisfies the condition" in result.output


def test_a_box_summary_naming_a_wider_box_fails(box: dict[str, Any], tmp_path: Path) -> None:
    doc = copy.deepcopy(box)
    true = doc["conditions"]["ges"]["summary"]
    assert "alpha_d in [588, 612], k_d in [0.147, 0.153]" in true
    doc["conditions"]["ges"]["summary"] = true.replace("alpha_d in [588, 612]", "alpha_d in [300, 1200]")
    result = verify_file(tmp_path, doc)
    assert result.exit_code == 1, result.output
    assert "FAIL ges" in result.output and "alpha_d in [588, 612]" in result.output
    # a class's own box key must be the document's box too (its sentence names the document's)
    doc = copy.deepcopy(box)
    doc["conditions"]["sos_gas"]["box"] = {"alpha_d": ["300", "1200"], "k_d": ["147/1000", "153/1000"]}
    result = verify_file(tmp_path, doc)
    assert result.exit_code == 1 and "FAIL sos_gas" in result.output, result.output


def _decided(doc: dict[str, Any]) -> list[str]:
    return [name for name, c in doc["conditions"].items() if c["status"] in claims.DECIDED]


def test_every_decided_summary_is_checked(point: dict[str, Any], box: dict[str, Any],
                                          others: dict[str, dict[str, Any]]) -> None:
    """One word more in any decided class's summary (a point's or a box's) fails that class."""
    seen: set[tuple[str, str, bool]] = set()
    for doc in (point, box, *others.values()):
        for name in _decided(doc):
            edited = copy.deepcopy(doc)
            edited["conditions"][name]["summary"] += " and more"
            assert name in failed_rows(edited), name
            seen.add((name, doc["conditions"][name]["status"], "box" in doc))
    assert {(n, s) for n, s, is_box in seen if not is_box} == set(claims.SENTENCES)
    assert {(n, s) for n, s, is_box in seen if is_box} >= {("ges", "certified"), ("sos_gas", "certified"),
                                                            ("sos_bound", "certified"), ("prop41_ges", "refuted"),
                                                            ("sector_ges", "refuted"), ("saturated_loop", "certified"),
                                                            ("ultimate_bound", "certified")}


def test_undecided_conditions_keep_their_reason(others: dict[str, dict[str, Any]]) -> None:
    doc = copy.deepcopy(others["flags"])
    assert doc["conditions"]["ultimate_bound"]["status"] == "not_applicable"
    doc["conditions"]["ultimate_bound"]["summary"] = "any reason at all"
    assert not failed_rows(doc)


def test_the_sentence_tables_cover_every_class() -> None:
    assert {name for name, _ in claims.SENTENCES} == set(CONDITION_ORDER)
    assert {name for name, _ in claims.BOX_SENTENCES} == set(BOX_CLASSES)
    assert claims.summary("ges", {"status": "inconclusive", "summary": "x"}) is None
    for status in ("refuted", "counterexample"):  # ges never decides these: no sentence, a failed check
        with pytest.raises(ValueError, match="never decides"):
            claims.summary("ges", {"status": status})


def test_the_figures_a_sentence_prints_are_checked(point: dict[str, Any], others: dict[str, dict[str, Any]]) -> None:
    """A forger who edits a figure and its sentence together is caught by the figure's check."""
    doc = copy.deepcopy(point)
    switched = doc["conditions"]["switched_ges"]
    switched["growth_per_period"] *= 100  # the search's estimate, held to the exact enclosures
    switched["summary"] = claims.summary("switched_ges", switched, doc["inputs"]["exact_si"])
    assert "growth_per_period" in failed_rows(doc)["switched_ges"]
    doc = copy.deepcopy(point)
    refutation = doc["conditions"]["sector_ges"]["refutation"]
    refutation["statement"] = refutation["statement"].replace("A0 A1 has", "A0 A1 and A0 A1^-1 have")
    assert "sector_ges" in failed_rows(doc)
    doc = copy.deepcopy(others["easy"])
    doc["conditions"]["stabcond2"]["lhs_exact"] = "1/2"
    doc["conditions"]["stabcond2"]["summary"] = claims.summary("stabcond2", doc["conditions"]["stabcond2"])
    assert "stabcond2" in failed_rows(doc)


#: (document, path to the value, the value, what the failed check must name): each value is one that
#: int() would have turned back into the stored integer
FRACTIONAL = [
    ("point", ("sos_gas", "certificate", "basis_V", 2, 0), 2.0, "basis_V[2][0]"),
    ("point", ("sos_gas", "certificate", "basis_V", 2, 0), 2.4, "basis_V[2][0]"),
    ("point", ("sos_gas", "certificate", "basis_W", 0, 0), True, "basis_W[0][0]"),
    ("point", ("sos_gas", "certificate", "degree"), 4.0, "degree"),
    ("point", ("sos_gas", "certificate", "degree"), 4.5, "degree"),
    ("point", ("sos_gas", "degree"), 4.0, "degree"),
    ("point", ("ultimate_bound", "ellipsoid_stages"), 0.0, "ellipsoid_stages"),
    ("point", ("ges", "terms"), 4.0, "terms"),
    ("box", ("sos_gas", "certificate", "degree"), 4.0, "degree"),
    ("box", ("sos_gas", "certificate", "basis_V", 1, 1), 1.0, "basis_V[1][1]"),
    ("box", ("sos_gas", "degree"), 4.0, "degree"),
    ("box", ("ges", "certificate", "degree"), 1.4, "degree"),
]


@pytest.mark.parametrize(("which", "path", "value", "key"), FRACTIONAL)
def test_exponents_and_counts_must_be_integers(point: dict[str, Any], box: dict[str, Any], tmp_path: Path,
                                               which: str, path: tuple[Any, ...], value: Any, key: str) -> None:
    doc = copy.deepcopy(point if which == "point" else box)
    node = doc["conditions"]
    for step in path[:-1]:
        node = node[step]
    # an integer as certify wrote it, which int() of the forged value would give back (a truncation)
    assert type(node[path[-1]]) is int and node[path[-1]] == int(value), path
    node[path[-1]] = value
    result = verify_file(tmp_path, doc)
    assert result.exit_code == 1, result.output
    fails = [line for line in result.output.splitlines() if line.startswith("FAIL")]
    assert any(line.startswith(f"FAIL {path[0]}") and key in line for line in fails), result.output
    assert "Traceback" not in result.output


def test_the_report_prints_the_regenerated_sentence(point: dict[str, Any], box: dict[str, Any]) -> None:
    from reports.certificate_page import certificate_context
    from reports.render import certificate_html

    doc = copy.deepcopy(point)
    true = doc["conditions"]["ultimate_bound"]["summary"]
    doc["conditions"]["ultimate_bound"]["summary"] = true.replace("0.03491 m", "0.001 m")
    views = {v.name: v for v in certificate_context(doc, ledger=False, simulate=False)["conditions"]}
    assert views["ultimate_bound"].summary == true
    html = certificate_html(doc, ledger=False, simulate=False)
    assert "0.001 m (comparison" not in html and "0.03491 m (comparison" in html
    # a box: the sentence names the document's box, whatever the file says
    doc = copy.deepcopy(box)
    true = doc["conditions"]["ges"]["summary"]
    doc["conditions"]["ges"]["summary"] = true.replace("alpha_d in [588, 612]", "alpha_d in [300, 1200]")
    views = {v.name: v for v in certificate_context(doc, ledger=False, simulate=False)["conditions"]}
    assert views["ges"].summary == true
    # data from which no sentence follows: said so, never a traceback or the file's text
    doc["conditions"]["ges"]["certificate"]["c1"] = "x"
    views = {v.name: v for v in certificate_context(doc, ledger=False, simulate=False)["conditions"]}
    assert "malformed" in views["ges"].summary


def test_the_common_ges_box_form_is_checked_too(box: dict[str, Any]) -> None:
    """``ges`` over a box in its second form (one V for the whole box), which the paper's box does
    not reach (its parametric form certifies first)."""
    from lyapcheck.paper.boxes.quadratic import certify_common_ges_box

    problem = problem_from_sources(PAPER_TOML, {})
    parsed = parse_box(BOX)
    result = certify_common_ges_box(problem, parsed, "derived")
    assert result["status"] == "certified"
    doc = json.loads(json.dumps(build_box_document(problem, parsed, "derived", {"ges": result})))
    assert not failed_rows(doc)
    doc["conditions"]["ges"]["summary"] = doc["conditions"]["ges"]["summary"].replace("exp(-", "exp(-10")
    assert "ges" in failed_rows(doc)


def test_a_vertex_refutation_states_its_own_vertex() -> None:
    from fractions import Fraction

    from lyapcheck.paper.conditions import switching

    vertex = ((Fraction(1), Fraction(2)), (Fraction(-3), Fraction(1, 7)))
    result = switching._vertex_refutation(Fraction(5, 3), vertex, {}).to_json()
    assert result["summary"] == result["refutation"]["statement"] == claims.summary("switched_ges", result)
    assert "trace 1.143, determinant 6.143" in result["summary"]
