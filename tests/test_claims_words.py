"""Say what was proved, in the words a reader needs (issue 29, item 4).

A box certificate says "for every k in [lo, hi]" in its summaries, its report's header and
parameter table, and the report's reproduce command carries the ``--box``; every certified V is
given as ``V_text`` (readable, in the declared states, shifted where the equilibrium is not 0) and
as an exact sympy expression; a not-certified reason says which obstacle stopped it.
"""

from __future__ import annotations

import copy
from typing import Any

import sympy as sp

from lyapcheck.models.surfaces.certificate import build_document, verify_document
from lyapcheck.models.surfaces.certify import certify_model
from lyapcheck.models.classes.claims import box_words, v_expression, v_text
from lyapcheck.models.language.modelfile import load_model, parse_model
from tests.conftest import ROOT

OSCILLATOR = ROOT / "examples" / "models" / "damped-oscillator.toml"


def failed(doc: dict[str, Any]) -> list[str]:
    return [name for name, ok, _ in verify_document(doc) if not ok]


def box_document() -> dict[str, Any]:
    from lyapcheck.models.loop.boxes import parse_model_box

    model = load_model(OSCILLATOR)
    box = parse_model_box(model, ["k=0.5..2"])
    return build_document(certify_model(model, classes="quadratic", box=box))


def test_a_box_certificate_says_its_box_everywhere() -> None:
    from reports.render import certificate_html

    doc = box_document()
    q = doc["conditions"]["quadratic"]
    assert q["status"] == "certified"
    assert q["summary"].startswith("for every k in [0.5, 2]: GES")
    assert failed(doc) == []
    narrowed = copy.deepcopy(doc)  # a summary that claims a wider box than the certificate's
    narrowed["conditions"]["quadratic"]["summary"] = q["summary"].replace("[0.5, 2]", "[0.1, 5]")
    assert set(failed(narrowed)) == {"quadratic", "verdict", "answers"}  # its one class fails, so do the verdict and answers
    html = certificate_html(doc, simulate=False, recheck=False)
    assert "every claim below holds <strong>for every k in [0.5, 2]" in html
    assert "--box k=0.5..2" in html  # the reproduce command
    assert "the box: every value in this range is covered" in html


def test_box_words_are_exact_bounds_read_aloud() -> None:
    assert box_words({"mu": ["4/5", "6/5"], "k": ["1", "2"]}) == "mu in [0.8, 1.2] and k in [1, 2]"


def test_v_text_is_the_certified_v_and_a_forged_one_fails_verify() -> None:
    text = ('[model]\nname = "shifted"\nstates = ["x1", "x2"]\n[equilibrium]\nx1 = 1.5\n[dynamics]\n'
            'x1 = "-(x1 - 1.5) + x2"\nx2 = "-x2"\n')
    doc = build_document(certify_model(parse_model(text, "<test>"), classes="quadratic"))
    cert = doc["conditions"]["quadratic"]["certificate"]
    assert cert["variables"] == ["x1", "x2"]
    assert "(x1 - 1.5)" in cert["V_text"]
    # the readable text and the exact expression are the same V, to the printed digits
    exact = v_expression(cert["V"], cert["variables"], {"x1": "3/2"})
    x1, x2 = sp.symbols("x1 x2")
    readable = sp.sympify(cert["V_text"].replace("(x1 - 1.5)", "(x1 - 3/2)"))  # the test's own string
    for point in ({x1: 2, x2: -1}, {x1: 0, x2: 3}):
        assert abs(float(exact.subs(point)) - float(readable.subs(point))) <= 1e-5 * abs(float(exact.subs(point)))
    assert exact.subs({x1: sp.Rational(3, 2), x2: 0}) == 0  # V vanishes at the equilibrium
    assert failed(doc) == []
    forged = copy.deepcopy(doc)
    forged["conditions"]["quadratic"]["certificate"]["V_text"] = "x1**2 + x2**2"
    assert set(failed(forged)) == {"quadratic", "verdict", "answers"}


def test_v_text_short_form_and_signs() -> None:
    terms = {"terms": [["1", [2, 0]], ["-3/2", [1, 1]], ["1/3", [0, 2]], ["2", [4, 0]]]}
    assert v_text(terms, ["x", "y"]) == "x**2 - 1.5*x*y + 0.333333*y**2 + 2*x**4"
    assert v_text(terms, ["x", "y"], limit=2) == "x**2 - 1.5*x*y + ... (2 more terms)"
    assert v_text({"terms": [["-1", [2]]]}, ["x"]) == "-x**2"


def test_a_not_certified_reason_says_what_stopped_the_search() -> None:
    duffing = '[model]\nname = "d"\nstates = ["x1", "x2"]\n[dynamics]\nx1 = "x2"\nx2 = "-x1 - x2 - x1**3"\n'
    found = certify_model(parse_model(duffing, "<test>"), classes="quadratic").results["quadratic"]
    assert found.status == "not_certified"
    # the summary says what was tried and what to try; the search's own words are its detail (JSON)
    assert found.summary.startswith("no quadratic Lyapunov function was found; try ")
    assert "degree 2: the solver proved the program infeasible (best margin" in " ".join(found.numbers["detail"])
    critical = '[model]\nname = "c"\nstates = ["x1", "x2"]\n[dynamics]\nx1 = "-x1**3 + x2"\nx2 = "-x2"\n'
    found = certify_model(parse_model(critical, "<test>"), classes="quadratic").results["quadratic"]
    # -V' of a quadratic V has x1**4 but no x1**2 term: no strict quadratic certificate can exist. The
    # facial reduction finds that x1's row of V must vanish, and says so (sos_gas finds a quartic V)
    assert found.status == "not_certified"
    assert ("degree 2: no strict certificate of this form exists (V's basis, reduced to the face the solver "
            "found, keeps no pure power of some state)") in " ".join(found.numbers["detail"])


def test_the_table_shows_each_certified_v_and_the_box(tmp_path: Any) -> None:
    from click.testing import CliRunner

    from lyapcheck.cli import app

    app._register_commands()
    done = CliRunner().invoke(app.cli, ["certify", str(OSCILLATOR), "--box", "k=0.5..2", "--classes", "quadratic"],
                              env={"COLUMNS": "120"})
    assert done.exit_code == 0, done.output
    assert "for every k in [0.5, 2]" in done.output.splitlines()[0]
    flat = " ".join(line.strip("│ ") for line in done.output.splitlines())
    assert "V = " in flat and "x1**2" in flat
