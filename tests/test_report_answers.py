"""The report's head carries the answers of the certificate (issue 40, item 3).

An adaptive cruise control whose unsafe set is reached (its barrier class finds a reproducible
counterexample) must never be shown green: its verdict box is red, each answer is one line under
the verdict, the ``counterexample`` badge is red and explained in the status legend, and the
phase portrait draws the counterexample trajectory (simulated again from its stored start) up to
where it enters the unsafe set. A GES model keeps its green verdict. The PDF carries the same lines.
"""

from __future__ import annotations

import re
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from tests.acc_models import UNSAFE_ACC
from tests.conftest import ROOT
from tests.test_model_reports import Page, figures_of, pdf_text

#: an adaptive cruise control that IS unsafe: from the initial set (a gap of 10 to 12 m, closing at
#: 10 to 12 m/s) the gap falls below 5 m within a second
ACC = UNSAFE_ACC  # (tests/acc_models.py)


@pytest.fixture(scope="module")
def acc(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Any]:
    from lyapcheck.api import certify

    path = tmp_path_factory.mktemp("acc") / "acc.toml"
    path.write_text(ACC, encoding="utf-8")
    doc = certify(model=path, classes="quadratic,barrier").document
    assert doc["verdict"] == "unsafe" and doc["conditions"]["barrier"]["status"] == "counterexample"
    return doc


@pytest.fixture(scope="module")
def acc_context(acc: dict[str, Any]) -> dict[str, Any]:
    from reports.certificate_page import certificate_context

    return certificate_context(acc)


@pytest.fixture(scope="module")
def acc_html(acc_context: dict[str, Any]) -> str:
    from reports.html import render_html

    return render_html("certificate.html.j2", acc_context)


def _verdict(page: Page) -> dict[str, str]:
    (box,) = [a for t, a in page.tags if a.get("id") == "verdict"]
    return box


def _css_rule(html: str, selector: str) -> str:
    """The declarations of the page's CSS rule whose selector list names ``selector``."""
    css = re.sub(r"/\*.*?\*/", "", html.split("</style>")[0], flags=re.S)
    for selectors, body in re.findall(r"([^{}]+)\{([^{}]*)\}", css):
        if selector in [s.strip() for s in selectors.split(",")]:
            return body
    raise AssertionError(f"no CSS rule for {selector}")


# ------------------------------------------------------------------------------------------------
# the tone of a verdict: green only for certified
# ------------------------------------------------------------------------------------------------
@pytest.mark.parametrize("verdict, tone", [("certified", "ok"), ("unsafe", "bad"), ("unstable", "bad"),
                                           ("certified_local", "warn"), ("certified_nominal", "warn"),
                                           ("not_certified", "warn"), ("something new", "warn")])
def test_each_verdict_has_its_tone(verdict: str, tone: str) -> None:
    from lyapcheck.answers import VERDICTS
    from reports.subjects.base import verdict_head

    assert verdict in VERDICTS or verdict == "something new"
    head = verdict_head({"verdict": verdict, "answers": {}})
    assert head["verdict_tone"] == tone and head["verdict_meaning"]


def test_a_negative_answer_is_never_green_whatever_the_stated_verdict() -> None:
    from reports.subjects.base import verdict_head

    answers = {"stability": {"answer": "global", "property": "GES", "by": "quadratic", "text": "GES"},
               "safety": {"answer": "unsafe", "by": "barrier", "text": "UNSAFE: ..."}}
    head = verdict_head({"verdict": "certified", "answers": answers})
    assert head["verdict_tone"] == "bad"
    assert [(a.question, a.answer, a.tone) for a in head["answers"]] == [("stability", "global", "plain"),
                                                                         ("safety", "unsafe", "bad")]
    fine = verdict_head({"verdict": "certified", "answers": {"stability": answers["stability"]}})
    assert fine["verdict_tone"] == "ok" and fine["answers"][0].tone == "ok"


def test_a_switching_disturbance_is_replayed_piece_by_piece() -> None:
    from reports.phase_portrait import _segments

    ref = {"disturbance": {"kind": "bang-bang", "values": [[0.5], [-0.5], [0.5]], "switch_times": [1.0, 2.5]}}
    pieces = _segments(ref, 1, 2.0)
    assert pieces is not None and [(a, b, float(d[0])) for a, b, d in pieces] == [(0.0, 1.0, 0.5), (1.0, 2.0, -0.5)]
    held = _segments({"disturbance": {"kind": "constant", "values": [[0.25]]}}, 1, 3.0)
    assert held is not None and [(a, b, d.tolist()) for a, b, d in held] == [(0.0, 3.0, [0.25])]
    assert _segments({"disturbance": {"kind": "constant", "values": [[0.25, 1.0]]}}, 1, 3.0) is None  # wrong width
    assert _segments({"disturbance": {"kind": "bang-bang", "values": [[1.0]], "switch_times": [1.0]}}, 1, 3.0) is None
    none = _segments({"disturbance": {"kind": "none"}}, 0, 3.0)
    assert none is not None and [(a, b) for a, b, _ in none] == [(0.0, 3.0)]


# ------------------------------------------------------------------------------------------------
# the unsafe adaptive cruise control
# ------------------------------------------------------------------------------------------------
@pytest.mark.slow
def test_an_unsafe_model_is_red_with_its_answers_under_the_verdict(acc: dict[str, Any], acc_html: str) -> None:
    page = Page(acc_html)
    box = _verdict(page)
    assert box["data-verdict"] == "unsafe" and box["data-tone"] == "bad"
    assert "tone-bad" in box["class"].split() and "tone-ok" not in box["class"]
    # nothing of the head is green: neither the box nor an answer's badge
    assert not [a for t, a in page.tags if "tone-ok" in a.get("class", "").split()]
    assert "var(--bad)" in _css_rule(acc_html, ".verdict.tone-bad")
    # one line per question: question, answer word, the document's sentence
    lines = {a["data-question"]: a["data-answer"] for a in page.find("li", "answer")}
    assert lines == {q: a["answer"] for q, a in acc["answers"].items()}
    assert lines["safety"] == "unsafe" and lines["stability"] == "global"
    text = page.text
    for question, title in (("safety", "Safety"), ("stability", "Stability")):
        assert f"{title}: {acc['answers'][question]['answer']} {acc['answers'][question]['text']}" in text
    head = text[text.index("Verdict:"):text.index("At a glance")]
    assert "UNSAFE" in head and "every claim holds" not in text
    assert "Re-checked exactly while this report was made: every certified claim re-checks" in head


@pytest.mark.slow
def test_the_counterexample_badge_is_red_and_explained(acc_html: str) -> None:
    page = Page(acc_html)
    assert "var(--bad)" in _css_rule(acc_html, ".badge.counterexample")
    assert "var(--bad)" in _css_rule(acc_html, ".condition.counterexample")
    legend = acc_html[acc_html.index('<p class="note">', acc_html.index('id="glance"')):]
    legend = legend[:legend.index("</p>")]
    assert '<span class="badge counterexample">counterexample</span> numerical evidence against the property' in legend
    assert [a for a in page.find("span", "badge") if a["class"] == "badge counterexample"]


@pytest.mark.slow
def test_the_portrait_draws_the_counterexample_into_the_unsafe_set(acc: dict[str, Any], acc_context: dict[str, Any],
                                                                   acc_html: str) -> None:
    from lyapcheck.models.language.modelfile import parse_model
    from lyapcheck.models.language.sets import margin

    page = Page(acc_html)
    (fig,) = [a for t, a in page.tags if t == "figure" and a.get("id") == "fig-phase"]
    assert fig["data-counterexamples"] == "barrier"
    (img,) = figures_of(page)
    assert "counterexample (barrier): enters the unsafe set at t = " in img["alt"]
    data = acc_context["portrait"].data
    assert any(t.startswith("counterexample (barrier): enters the unsafe set at t = ") for t in data["legend"])
    (shown,) = data["counterexamples"]
    stored = acc["conditions"]["barrier"]["refutation"]
    # simulated again from the stored start, it enters where and when the class said it would
    assert shown["start"] == stored["start"] and shown["entered"]
    assert shown["entry_time_s"] == pytest.approx(stored["time"], rel=1e-3)
    assert np.allclose(shown["entry_point"], stored["point"], rtol=1e-3)
    model = parse_model(ACC, "acc.toml")
    assert abs(float(margin(model.sets["unsafe"], np.array([shown["entry_point"]]))[0])) < 1e-6
    assert f"at t = {shown['entry_time_s']:.4g} s" in page.text


@pytest.mark.slow
def test_the_pdf_carries_the_answer_lines(acc: dict[str, Any], acc_html: str, tmp_path: Path) -> None:
    from reports.pdf import html_to_pdf, html_to_typst

    text = pdf_text(html_to_pdf(acc_html))
    assert "Verdict: unsafe" in text
    for question, title in (("safety", "Safety"), ("stability", "Stability")):
        line = f"{title}: {acc['answers'][question]['answer']} {acc['answers'][question]['text']}"
        assert " ".join(line.split()) in text, title
    # the box is drawn red (its tone), the badge of the counterexample too
    source = html_to_typst(acc_html, tmp_path)
    assert 'stroke: 2pt + rgb("#cf222e"), fill: rgb("#ffebe9"))[' in source
    assert '#badge("#cf222e")[#"counterexample";]' in source


# ------------------------------------------------------------------------------------------------
# a GES model stays green
# ------------------------------------------------------------------------------------------------
@pytest.mark.slow
def test_a_globally_stable_model_is_still_green() -> None:
    from lyapcheck.api import certify
    from reports.certificate_page import certificate_context
    from reports.html import render_html

    doc = certify(model=ROOT / "examples" / "models" / "damped-oscillator.toml", classes="quadratic").document
    assert doc["verdict"] == "certified"
    html = render_html("certificate.html.j2", certificate_context(doc, simulate=False))
    page = Page(html)
    box = _verdict(page)
    assert box["data-tone"] == "ok" and "tone-ok" in box["class"].split()
    assert "var(--ok)" in _css_rule(html, ".verdict.tone-ok")
    (line,) = page.find("li", "answer")
    assert (line["data-question"], line["data-answer"]) == ("stability", "global")
    assert [a["class"] for a in page.find("span", "badge") if "tone-" in a["class"]] == ["badge tone-ok"]
    assert "every certified claim re-checks" in page.text
