"""Reports of model certificates (``certify --model``): HTML and PDF as a reader meets them.

Three real certificates, each certified once per module: the reversed Van der Pol oscillator
(2 states, a certified region of attraction: phase portrait), the disturbed linear cascade
(2 states, ``sos_bound``: a second panel under constant disturbances) and SOSTOOLS' rational
SOSDEMO2 (3 states: tables only). Synthetic certificates (a true one and a false one, made here
from the shipped model texts) test the figure's geometry against exact answers and the soundness
alarm, in well under a second each.
"""

from __future__ import annotations

import base64
import copy
import json
import os
import re
import subprocess
import sys
from fractions import Fraction
from html.parser import HTMLParser
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from lyapcheck.models.classes.claims import rounded
from tests.conftest import ROOT

MODELS = ROOT / "examples" / "models"


class Page(HTMLParser):
    """Tags, attributes and visible text of a page (the stdlib parser: what a browser sees)."""

    def __init__(self, html: str) -> None:
        super().__init__(convert_charrefs=True)
        self.tags: list[tuple[str, dict[str, str]]] = []
        self.parts: list[str] = []
        self._hidden = 0
        self.feed(html)

    def handle_starttag(self, tag: str, attrs: list[tuple[str, str | None]]) -> None:
        self.tags.append((tag, {k: v or "" for k, v in attrs}))
        if tag in ("style", "script"):
            self._hidden += 1

    def handle_endtag(self, tag: str) -> None:
        if tag in ("style", "script"):
            self._hidden -= 1

    def handle_data(self, data: str) -> None:
        if not self._hidden:
            self.parts.append(data)

    @property
    def text(self) -> str:
        return " ".join(" ".join(self.parts).split())

    def find(self, tag: str, cls: str | None = None) -> list[dict[str, str]]:
        return [a for t, a in self.tags if t == tag and (cls is None or cls in a.get("class", "").split())]


def pdf_text(pdf: bytes) -> str:
    """The text of every page (zero-width break opportunities removed, whitespace collapsed)."""
    import pypdfium2 as pdfium

    doc = pdfium.PdfDocument(pdf)
    try:
        out = []
        for i in range(len(doc)):
            textpage = doc[i].get_textpage()
            out.append(textpage.get_text_range())
            textpage.close()
    finally:
        doc.close()
    return " ".join(" ".join(out).replace("\u200b", "").split())


def pdf_pages(pdf: bytes) -> list[Any]:
    import pypdfium2 as pdfium

    doc = pdfium.PdfDocument(pdf)
    try:
        return [np.asarray(doc[i].render(scale=0.5).to_pil().convert("RGB")) for i in range(len(doc))]
    finally:
        doc.close()


def figures_of(page: Page) -> list[dict[str, str]]:
    """The ``<img>`` of each ``<figure>`` (equations are ``img.math``, figures are not)."""
    return [a for a in page.find("img") if "math" not in a.get("class", "").split()]


def svg_of(img: dict[str, str]) -> bytes:
    prefix = "data:image/svg+xml;base64,"
    assert img["src"].startswith(prefix)
    return base64.b64decode(img["src"][len(prefix):])


def no_network(page: Page) -> None:
    for tag, attrs in page.tags:
        for name in ("src", "href"):
            value = attrs.get(name, "").strip().lower()
            assert not value.startswith(("http:", "https:", "//", "file:")), (tag, value[:60])
    assert not any(t in ("script", "link", "iframe", "object", "embed") for t, _ in page.tags)


def run_cli(*args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, "-m", "lyapcheck", *args], capture_output=True, text=True, cwd=ROOT,
                          env={**os.environ, "COLUMNS": "200"}, timeout=600)


# ------------------------------------------------------------------------------------------------
# certified once per module
# ------------------------------------------------------------------------------------------------
@pytest.fixture(scope="module")
def vdp() -> Any:
    from lyapcheck.api import certify

    result = certify(model=MODELS / "van-der-pol-reversed.toml")
    assert result.conditions["roa"].status == "certified"
    return result


@pytest.fixture(scope="module")
def vdp_context(vdp: Any) -> dict[str, Any]:
    from reports.certificate_page import certificate_context

    return certificate_context(vdp.document)


@pytest.fixture(scope="module")
def vdp_html(vdp_context: dict[str, Any]) -> str:
    from reports.html import render_html

    return render_html("certificate.html.j2", vdp_context)


@pytest.fixture(scope="module")
def l1() -> Any:
    from lyapcheck.api import certify

    result = certify(model=MODELS / "linear-disturbed-l1.toml")
    assert result.conditions["sos_bound"].status == "certified"
    return result


@pytest.fixture(scope="module")
def l1_context(l1: Any) -> dict[str, Any]:
    from reports.certificate_page import certificate_context

    return certificate_context(l1.document)


@pytest.fixture(scope="module")
def rational(tmp_path_factory: pytest.TempPathFactory) -> tuple[dict[str, Any], bytes, str]:
    """SOSDEMO2 through the command line: ``certify --model --out --report F.pdf``, then ``report --html``."""
    where = tmp_path_factory.mktemp("rational")
    cert, pdf, html = where / "cert.json", where / "report.pdf", where / "report.html"
    done = run_cli("certify", "--model", str(MODELS / "sosdemo2-rational.toml"), "--out", str(cert),
                   "--report", str(pdf))
    assert done.returncode == 0, done.stderr
    again = run_cli("report", str(cert), "--html", str(html))
    assert again.returncode == 0, again.stderr
    assert f"wrote {html}" in again.stdout
    return json.loads(cert.read_text()), pdf.read_bytes(), html.read_text(encoding="utf-8")


# ------------------------------------------------------------------------------------------------
# 2 states, a region of attraction: the reversed Van der Pol oscillator
# ------------------------------------------------------------------------------------------------
@pytest.mark.slow
def test_vdp_page_shows_every_class_the_exact_v_and_the_phase_portrait(vdp: Any, vdp_context: dict[str, Any],
                                                                       vdp_html: str) -> None:
    doc = vdp.document
    page = Page(vdp_html)
    no_network(page)
    text = page.text
    assert "Verdict: certified" in text and "reversed Van der Pol oscillator (mu = 1)" in text
    badges = [a["class"].split()[1] for a in page.find("span", "badge")]
    for name, cond in doc["conditions"].items():
        assert f"{name}" in text
        assert cond["status"] in badges
    # the level: its digits in the table of classes, and exactly
    roa = doc["conditions"]["roa"]
    assert f"level c = {rounded(roa['level'], 6, 'down')}" in text
    assert roa["certificate"]["level"] in text
    # V exactly: every term of the certificate's V is in the plain text, coefficient for coefficient
    for coefficient, _ in roa["certificate"]["V"]["terms"]:
        assert coefficient.lstrip("-") in text
    (shown,) = [c for c in vdp_context["conditions"] if c.name == "roa"]
    (v,) = shown.polynomials
    assert v.terms == len(roa["certificate"]["V"]["terms"]) and v.degree == roa["degree"]
    assert any(e["alt"] == v.plain for e in page.find("img", "math"))  # the typeset V, with its exact text
    # the model as stored: source, dynamics as written, parameter, SHA-256, domain
    assert doc["model"]["sha256"] in text and "x1 - mu*(1 - x1**2)*x2" in text and "[-2.5, 2.5]" in text
    assert "LyZNet" in text and "the stored text matches it" in text
    # the exact re-check ran and holds; the simulation cross-check holds
    assert "Re-checked exactly while this report was made: every certified claim re-checks" in text
    assert "THE EXACT RE-CHECK FAILS" not in text and "SOUNDNESS" not in text
    # two figures: the phase portrait, an SVG with the set and the trajectories, then the certified set's
    # size against the simulated region of attraction (reports.region_slices)
    figs = figures_of(page)
    assert len(figs) == 2 and [a.get("id") for t, a in page.tags if t == "figure"] == ["fig-phase", "fig-size"]
    svg = svg_of(figs[0])
    assert svg.startswith(b"<?xml") and svg.count(b"<path") > 40
    assert "Phase portrait of the model in its declared coordinates (x1, x2)" in text
    assert 100_000 < len(vdp_html) < 1_500_000


@pytest.mark.slow
def test_vdp_portrait_draws_the_certified_set_inside_the_true_region(vdp_context: dict[str, Any]) -> None:
    """The drawn set lies inside the limit cycle (x1-crossing 2.0086) and is most of it; every start
    in it converges, V never rises along those trajectories, and starts beyond the cycle escape."""
    portrait = vdp_context["portrait"]
    data = portrait.data
    (roa,) = [s for s in data["sets"] if s["class"] == "roa"]
    lo, hi = roa["extent_declared"]
    assert 1.95 < hi[0] < 2.0086 and -2.0086 < lo[0] < -1.95
    assert data["boundary_starts"] == 8
    assert data["outcomes"]["converged"] >= data["boundary_starts"] and data["outcomes"]["escaped"] > 0
    assert [ok for _, ok in data["checks"]] == [True]
    assert all(c.ok for c in vdp_context["checks"])
    # the view holds the domain box [-2.5, 2.5] x [-3.5, 3.5]
    view_lo, view_hi = data["view"]
    assert view_lo[0] < -2.5 and view_hi[0] > 2.5 and view_lo[1] < -3.5 and view_hi[1] > 3.5


@pytest.mark.slow
def test_vdp_pdf_opens_and_carries_the_page(vdp: Any, vdp_html: str) -> None:
    from lyapcheck.tolerances import FIGURE_MODEL_ROA_LEVEL_RTOL
    from reports.render import html_to_pdf

    pdf = html_to_pdf(vdp_html)
    assert pdf.startswith(b"%PDF")
    text = pdf_text(pdf)
    assert "Stability certificate: reversed Van der Pol oscillator (mu = 1)" in text
    # the certified level starts from the solver's answers: its digits follow the platform (0.999656
    # to 1.000008 measured on five x86-64 ones) within the level search's resolution; the page
    # carries this run's level
    roa = vdp.document["conditions"]["roa"]
    assert roa["level"] == pytest.approx(0.999692, rel=FIGURE_MODEL_ROA_LEVEL_RTOL)
    assert f"level c = {rounded(roa['level'], 6, 'down')}" in text and "certified" in text and "not certified" in text
    assert roa["certificate"]["level"] in text or f"{roa['level']:.6g}" in text
    assert "Phase portrait" in text and "Exact re-check" in text
    # the figure is drawn: the filled set's light green is on the page of the portrait
    pages = pdf_pages(pdf)
    greenish = [int(np.sum((p[..., 1].astype(int) - p[..., 0] > 12) & (p[..., 1].astype(int) - p[..., 2] > 6)))
                for p in pages]
    assert max(greenish) > 2000


@pytest.mark.slow
def test_certify_report_path_of_the_api_writes_html_and_pdf(vdp: Any, tmp_path: Path) -> None:
    """What ``lyapcheck certify --model FILE --report F`` calls: api.report on the result."""
    from lyapcheck.api import report

    written = report(vdp, html=tmp_path / "vdp.html", pdf=tmp_path / "vdp.pdf")
    assert [p.name for p in written] == ["vdp.html", "vdp.pdf"]
    assert "Stability certificate: reversed Van der Pol" in Page((tmp_path / "vdp.html").read_text()).text
    assert "Phase portrait" in pdf_text((tmp_path / "vdp.pdf").read_bytes())


# ------------------------------------------------------------------------------------------------
# 2 states with disturbances: sos_bound
# ------------------------------------------------------------------------------------------------
@pytest.mark.slow
def test_sos_bound_page_shows_bounds_storage_functions_and_the_disturbed_panel(l1: Any,
                                                                                l1_context: dict[str, Any]) -> None:
    from reports.html import render_html

    doc = l1.document
    page = Page(render_html("certificate.html.j2", l1_context))
    text = page.text
    bounds = doc["conditions"]["sos_bound"]["bounds"]
    for output, bound in bounds.items():
        assert f"limsup |{output}| <= {rounded(bound, 6, 'up')}" in text
        assert f"storage function for the output {output}, exactly" in text
        for coefficient, _ in doc["conditions"]["sos_bound"]["certificate"]["outputs"][output]["V"]["terms"]:
            assert coefficient.lstrip("-") in text
    assert "ultimate_bound" in text and "|d(t)| ≤ b" in text
    assert len(figures_of(page)) == 1
    data = l1_context["portrait"].data
    assert sorted(s for s, _ in data["disturbed"]["bands"]) == ["x1", "x2"]
    # every disturbed run ends at its equilibrium (+-1/2, +-1/2): the exact worst case, which the
    # certified bounds must not undercut (the exact check guarantees it; the simulation shows it)
    ends = np.abs(np.array(data["disturbed"]["ends"]))
    np.testing.assert_allclose(ends, 0.5, rtol=1e-3)
    assert bounds["y"] >= 0.5 and bounds["w"] >= 0.5
    names = [c.what for c in l1_context["checks"]]
    assert any(n.startswith("sos_bound (y)") for n in names) and any(n.startswith("quadratic") for n in names)
    assert all(c.ok for c in l1_context["checks"])


@pytest.mark.slow
def test_report_command_renders_a_model_certificate_to_html_and_pdf(l1: Any, tmp_path: Path) -> None:
    cert = tmp_path / "l1.json"
    l1.write(cert)
    html, pdf = tmp_path / "l1.html", tmp_path / "l1.pdf"
    done = run_cli("report", str(cert), "--html", str(html), "--pdf", str(pdf))
    assert done.returncode == 0, done.stderr
    page = Page(html.read_text(encoding="utf-8"))
    assert "disturbed linear cascade with exact worst-case bound 1/2" in page.text
    assert len(figures_of(page)) == 1
    text = pdf_text(pdf.read_bytes())
    bound = l1.document["conditions"]["sos_bound"]["bounds"]["y"]
    assert f"limsup |y| <= {rounded(bound, 6, 'up')}" in text and "sos_bound" in text and "Ultimate bound on each output" in text


# ------------------------------------------------------------------------------------------------
# 3 states, rational: tables only
# ------------------------------------------------------------------------------------------------
@pytest.mark.slow
def test_three_state_model_has_tables_and_no_figure(rational: tuple[dict[str, Any], bytes, str]) -> None:
    doc, pdf, html = rational
    page = Page(html)
    no_network(page)
    text = page.text
    assert not figures_of(page) and not page.find("figure")
    assert "the model has 3 states: a phase portrait is drawn for 2 states only, so this report shows tables" in text
    assert doc["conditions"]["sos_gas"]["status"] == "certified" and "not certified" in text
    # the denominator and its positivity certificate, named
    assert "x3**2 + 1" in text and "sum of squares" in text and "c = 1/2" in text
    for coefficient, _ in doc["conditions"]["sos_gas"]["certificate"]["V"]["terms"]:
        assert coefficient in text
    assert "x1 = 0, x2 = 0, x3 = 0" not in text  # the equilibrium is listed per state
    assert "x1 = 0" in text and "-x3 - 3*x3/(x3**2 + 1) + 3*x1**2*x3" in text
    # the PDF written by certify --report
    assert pdf.startswith(b"%PDF")
    ptext = pdf_text(pdf)
    assert "Stability certificate: SOSTOOLS SOSDEMO2 rational system" in ptext
    assert "so this report shows tables" in ptext and "certified" in ptext and "x3**2 + 1" in ptext


# ------------------------------------------------------------------------------------------------
# tampered documents and hostile text
# ------------------------------------------------------------------------------------------------
@pytest.mark.slow
def test_a_changed_level_or_model_text_raises_the_alarm(vdp: Any) -> None:
    from reports.render import certificate_html

    doc = copy.deepcopy(vdp.document)
    level = Fraction(doc["conditions"]["roa"]["certificate"]["level"])
    doc["conditions"]["roa"]["certificate"]["level"] = str(level * 2)
    text = Page(certificate_html(doc, simulate=False)).text
    assert "THE EXACT RE-CHECK FAILS" in text and "Do not trust this certificate" in text
    doc = copy.deepcopy(vdp.document)
    doc["model"]["text"] = doc["model"]["text"].replace("mu = 1\n", "mu = 2\n")
    text = Page(certificate_html(doc, simulate=False)).text
    assert "does not match its SHA-256" in text and "the stored text does NOT match it" in text


def _synthetic(model_file: str, conditions: dict[str, Any], **extra: Any) -> dict[str, Any]:
    """A model document around a shipped model text, with conditions made up by the test."""
    import hashlib

    from lyapcheck.models.surfaces.certificate import KIND, SCHEMA_VERSION
    from lyapcheck.models.language.modelfile import parse_model

    text = (MODELS / model_file).read_text() if not model_file.startswith("[") else model_file
    model = parse_model(text, model_file[:40])
    return {"schema_version": SCHEMA_VERSION, "kind": KIND,
            "model": {"name": model.name, "file": model_file[:40], "sha256": hashlib.sha256(text.encode()).hexdigest(),
                      "text": text},
            "overrides": {}, "candidate": None, "states": list(model.states),
            "equilibrium": {s: str(v) for s, v in zip(model.states, model.equilibrium)},
            "parameters": {k: str(v) for k, v in model.parameters.items()},
            "disturbances": {k: str(v) for k, v in model.disturbances.items()},
            "field": {"denominators": [], "scaling": None}, "conditions": conditions, "verdict": "certified",
            "versions": {"lyapcheck": "test"}, **extra}


def _disc(level: str) -> dict[str, Any]:
    return {"status": "certified", "summary": "made up by the test", "property": "ROA", "level": float(Fraction(level)),
            "certificate": {"kind": "sublevel", "V": {"terms": [["1", [2, 0]], ["1", [0, 2]]]}, "level": level}}


def test_input_text_reaches_the_page_as_text(tmp_path: Path) -> None:
    from reports.render import certificate_html
    from reports.render import html_to_pdf

    # a certified class's sentence is regenerated from its figures (the file's text is never shown),
    # so the hostile text rides on an undecided class's reason, which is shown as the file has it
    doc = _synthetic("fossil-poly2.toml", {"roa": {**_disc("1"), "summary": "<script>alert(1)</script> & <b>x</b>"},
                                           "quadratic": {"status": "not_certified",
                                                         "summary": "<script>alert(2)</script> & <b>y</b>"}})
    doc["model"]["name"] = "<img src=x onerror=alert(1)> #set page(width: 1pt)"
    html = certificate_html(doc, simulate=False, recheck=False)
    page = Page(html)
    no_network(page)
    assert "<script>alert(2)</script> & <b>y</b>" in page.text
    assert "alert(1)</script>" not in page.text and "every start in {V <= 1}" in page.text
    assert not any(a.get("src") == "x" for a in page.find("img"))
    assert "<img src=x onerror=alert(1)> #set page(width: 1pt)" in pdf_text(html_to_pdf(html))


def test_the_portrait_of_a_true_certificate_matches_the_exact_set() -> None:
    """x**2 + y**2 <= 1 for FOSSIL's Poly2 (V' = -2x^4 - 2y^2): the drawn set is the unit disc and
    every simulated trajectory that starts in it stays there; the domain box [-5, 5]^2 is in view."""
    from lyapcheck.models.language.modelfile import parse_model
    from reports.phase_portrait import phase_portrait

    doc = _synthetic("fossil-poly2.toml", {"roa": _disc("1")})
    portrait = phase_portrait(doc, parse_model(doc["model"]["text"], "poly2"))
    assert portrait.figure is not None and not portrait.reason
    (s,) = portrait.figure.data["sets"]
    lo, hi = s["extent_declared"]
    np.testing.assert_allclose(lo, [-1, -1], atol=1e-9)
    np.testing.assert_allclose(hi, [1, 1], atol=1e-9)
    view_lo, view_hi = portrait.figure.data["view"]
    assert view_lo[0] < -5 < 5 < view_hi[0]
    assert [c.ok for c in portrait.checks] == [True]
    assert portrait.figure.data["outcomes"]["escaped"] == 0


def test_a_false_region_of_attraction_raises_the_soundness_alarm() -> None:
    """The reversed Van der Pol oscillator's true region of attraction crosses the x1-axis at
    2.0086: a made-up "certified" disc of radius 5 contains escaping starts, and the page says so."""
    from reports.certificate_page import certificate_context

    doc = _synthetic("van-der-pol-reversed.toml", {"roa": _disc("25")})
    context = certificate_context(doc, recheck=False)
    (check,) = context["checks"]
    assert not check.ok and "escaped" in check.detail
    assert context["soundness"].startswith("SOUNDNESS: a simulation contradicts a certificate")


def test_a_shifted_equilibrium_is_drawn_where_it_is() -> None:
    """V is stored in x - x_eq: the set {(x1 - 1)^2 + x2^2 <= 1/4} is drawn around (1, 0)."""
    from lyapcheck.models.language.modelfile import parse_model
    from reports.phase_portrait import phase_portrait
    from reports.certificate_page import certificate_context

    text = ('[model]\nname = "shifted"\nstates = ["x1", "x2"]\n[dynamics]\nx1 = "-(x1 - 1)"\nx2 = "-x2"\n'
            "[equilibrium]\nx1 = 1\n")
    doc = _synthetic(text, {"roa": _disc("1/4")})
    portrait = phase_portrait(doc, parse_model(text, "shifted"))
    assert portrait.figure is not None
    lo, hi = portrait.figure.data["sets"][0]["extent_declared"]
    np.testing.assert_allclose(lo, [0.5, -0.5], atol=1e-9)
    np.testing.assert_allclose(hi, [1.5, 0.5], atol=1e-9)
    context = certificate_context(doc, simulate=False, recheck=False)
    (view,) = context["conditions"][0].polynomials
    assert view.plain == "(x1 - 1)**2 + x2**2"


# ------------------------------------------------------------------------------------------------
# the polynomials, exactly
# ------------------------------------------------------------------------------------------------
def test_plain_text_parses_back_to_the_same_polynomial() -> None:
    """The text the page prints is the model-file language: the project's parser reads it back to
    exactly the stored terms (shifted by the equilibrium where it is not 0)."""
    from lyapcheck.models.language.expressions import parse_expression
    from lyapcheck.sos.polynomials import Ring
    from reports.polynomials import ExactPolynomial

    rng = np.random.default_rng(7)
    ring = Ring(("x1", "x2", "x3"))
    for shifts in ([Fraction(0)] * 3, [Fraction(1, 3), Fraction(0), Fraction(-5, 2)]):
        terms = []
        for _ in range(25):
            e = [int(v) for v in rng.integers(0, 4, size=3)]
            c = Fraction(int(rng.integers(-10**9, 10**9)), int(rng.integers(1, 10**9)))
            terms.append([str(c), e])
        poly = ExactPolynomial.from_json({"terms": terms}, 3)
        parsed = parse_expression(poly.plain_text(ring.names, shifts), ring)
        assert parsed.is_polynomial()
        # compare with the stored terms composed with the shift, exactly
        gens = ring.gens()
        expected = ring.constant(0)
        for c, m in poly.terms:
            term = ring.constant(c)
            for g, s, k in zip(gens, shifts, m):
                term = term * (g - ring.constant(s)) ** k
            expected = expected + term
        assert ring.terms(parsed.numerator * (1 / parsed.denominator.leading_coefficient())) == ring.terms(expected)


def test_storage_functions_over_states_and_disturbances_are_read_over_the_states() -> None:
    from reports.polynomials import ExactPolynomial

    poly = ExactPolynomial.from_json({"terms": [["1/2", [2, 0, 0]], ["-3", [1, 1, 0]]]}, 2)
    assert poly.plain_text(["a", "b"], [Fraction(0)] * 2) == "1/2*a**2 - 3*a*b"
    with pytest.raises(ValueError, match="other than the states"):
        ExactPolynomial.from_json({"terms": [["1", [0, 0, 2]]]}, 2)
    with pytest.raises(ValueError, match="not a rational"):
        ExactPolynomial.from_json({"terms": [["__import__('os')", [1, 0]]]}, 2)


def test_a_long_polynomial_is_typeset_truncated_and_compiles() -> None:
    from reports.polynomials import MAX_TYPESET_TERMS, ExactPolynomial
    from reports.typeset import render

    terms = [[f"{k + 1}/{k + 7}", [a, b, c]] for k, (a, b, c) in
             enumerate((a, b, c) for a in range(5) for b in range(5) for c in range(5))]
    poly = ExactPolynomial.from_json({"terms": terms}, 3)
    source, shown = poly.typst(["x1", "x2", "x3"], [Fraction(0)] * 3, "V(x)")
    assert shown == MAX_TYPESET_TERMS < len(poly.terms) == 125
    assert source.rstrip().endswith("dots.c") and source.count("\\\n") >= 3
    (typeset,) = render([source]).values()
    assert typeset is not None and typeset.width_pt < 520


def test_reading_a_certificate_keeps_the_papers_messages(tmp_path: Path) -> None:
    from lyapcheck.errors import InputFileError
    from reports.certificate_page import read_certificate

    other = tmp_path / "other.json"
    other.write_text(json.dumps({"kind": "something else"}))
    with pytest.raises(InputFileError, match=re.escape("is not a lyapcheck certificate (missing kind "
                                                       "'lyapcheck-certificate')")):
        read_certificate(other)
    with pytest.raises(InputFileError, match="does not exist"):
        read_certificate(tmp_path / "absent.json")
    doc = _synthetic("fossil-poly2.toml", {})
    model = tmp_path / "model.json"
    model.write_text(json.dumps({**doc, "schema_version": 99}))
    with pytest.raises(InputFileError, match="schema_version 99"):
        read_certificate(model)
    model.write_text(json.dumps(doc))
    assert read_certificate(model) == doc


# -- the registry of report sections (reports.sections) ----------------------------------------------
def test_every_class_has_one_section_per_model() -> None:
    """Each class of the paper's loop and of model files is shown by the section that names it;
    an unnamed class falls back to its model's generic section, and a model the registry does not
    know is refused."""
    from lyapcheck.paper.certification import CONDITION_ORDER
    from reports.sections import BY_CLASS, FALLBACK, MODEL_FILE, PAPER, SECTIONS, section_for
    from reports.sections.output_bound import OutputBoundSection
    from reports.sections.paper import PaperSection
    from reports.sections.stability import StabilitySection

    for name in ("linearization", "quadratic", "sos_gas", "roa", "candidate"):
        assert isinstance(section_for(MODEL_FILE, name), StabilitySection)
    assert isinstance(section_for(MODEL_FILE, "sos_bound"), OutputBoundSection)
    assert section_for(MODEL_FILE, "no_such_class") is FALLBACK[MODEL_FILE]
    for name in CONDITION_ORDER:  # the paper's sos_bound is the paper's, not the model files'
        assert isinstance(section_for(PAPER, name), PaperSection)
    assert len(BY_CLASS) == sum(len(s.titles) for s in SECTIONS)
    with pytest.raises(ValueError, match="model of a report section"):
        section_for("some-other-model", "roa")


def test_a_new_family_of_classes_is_one_section(monkeypatch: pytest.MonkeyPatch) -> None:
    """What a later family (a made-up class here; barrier and reach_avoid are real ones) needs from the
    reports: a Section subclass in one module and its entry in the registry. Its view reaches the
    table and its own section, its set the phase portrait; nothing else of the page changes."""
    from fractions import Fraction

    from reports.certificate_page import certificate_context
    from reports.html import render_html
    from reports.phase_portrait import level_sets
    from reports.polynomials import ExactPolynomial
    from reports.sections import BY_CLASS, MODEL_FILE
    from reports.sections.base import LevelSet, PortraitPart
    from reports.sections.model_file import ModelFileSection
    from lyapcheck.models.language.modelfile import parse_model

    class TubeSection(ModelFileSection):
        titles = {"made_up_tube": "Tube certificate: the unsafe set is never reached"}

        def portrait(self, name: str, cond: dict[str, Any], n: int, time_scale: Fraction) -> PortraitPart:
            b = ExactPolynomial.from_json(cond["certificate"]["B"], n)
            return PortraitPart(sets=(LevelSet(name, "{B <= 0}", b, Fraction(0), "region", "#cf222e"),))

    made_up = {"status": "certified", "summary": "made up by the test", "property": "invariant_set",
               "certificate": {"B": {"terms": [["1", [2, 0]], ["1", [0, 2]], ["-1", [0, 0]]]}}}
    doc = _synthetic("fossil-poly2.toml", {"made_up_tube": made_up})
    before = certificate_context(doc, simulate=False, recheck=False)
    assert before["conditions"][0].title == "made_up_tube"  # the fallback: shown generically, under its key
    monkeypatch.setitem(BY_CLASS, (MODEL_FILE, "made_up_tube"), TubeSection())
    context = certificate_context(doc, simulate=False, recheck=False)
    (view,) = context["conditions"]
    assert view.title == "Tube certificate: the unsafe set is never reached"
    assert view.property == "invariant_set" and view.anchor == "class-1"
    page = Page(render_html("certificate.html.j2", context))
    assert "Tube certificate: the unsafe set is never reached" in page.text
    sets, globals_, notes = level_sets(doc, parse_model(doc["model"]["text"], "m.toml"))
    assert [(s.name, s.level, s.kind) for s in sets] == [("made_up_tube", 0, "region")] and not globals_ and not notes


# -- the safety classes: the model's [sets] and the invariant set {B <= 0} ------------------------------
PRAJNA = ('[model]\nname = "prajna"\nstates = ["x1", "x2"]\n[dynamics]\nx1 = "x2"\nx2 = "-x1 + x1**3/3 - x2"\n'
          '[sets]\ninitial = ["(x1 - 1.5)**2 + x2**2 <= 0.25"]\n'
          'unsafe = [["(x1 + 1)**2 + (x2 + 1)**2 <= 0.16"], ["0.4 <= x1", "x1 <= 0.6", "0.1 <= x2", "x2 <= 0.5"]]\n')


@pytest.fixture(scope="module")
def prajna(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Any]:
    """Prajna's barrier example (FOSSIL's Barr3 with one initial piece), certified by the command line."""
    where = tmp_path_factory.mktemp("prajna")
    (where / "prajna.toml").write_text(PRAJNA)
    done = run_cli("certify", str(where / "prajna.toml"), "--classes", "barrier", "--out", str(where / "b.json"))
    assert done.returncode == 0, done.stderr
    doc: dict[str, Any] = json.loads((where / "b.json").read_text())
    assert doc["conditions"]["barrier"]["status"] == "certified"
    return doc


def test_a_barrier_page_draws_the_sets_and_its_invariant_set(prajna: dict[str, Any]) -> None:
    """The portrait fills the initial and the unsafe set (both pieces) and hatches {B <= 0}, with a
    legend entry each; B stays <= 0 along every start inside it and no start in the initial set
    enters the unsafe set; the class shows the sets and the falsification as tables."""
    from reports.certificate_page import certificate_context
    from reports.html import render_html
    from reports.phase_portrait import level_sets
    from lyapcheck.models.language.modelfile import parse_model

    sets, globals_, notes = level_sets(prajna, parse_model(PRAJNA, "prajna.toml"))
    assert [(s.name, s.kind, s.level, s.symbol) for s in sets] == [("barrier", "invariant", 0, "B")]
    assert not globals_ and not notes
    context = certificate_context(prajna, recheck=False)
    data = context["portrait"].data
    assert data["model_sets_drawn"] == ["initial", "unsafe"] and data["invariant_drawn"] == ["barrier"]
    assert {"initial set", "unsafe set (2 pieces)", "barrier: {B ≤ 0}, certified invariant"} <= set(data["legend"])
    lo, hi = (np.array(v) for v in data["view"])  # both sets in view: the disc about (-1, -1) and the box
    assert np.all(lo < [-1.4, -1.4]) and np.all(hi > [2.0, 0.5])
    assert data["initial_starts"] == 12
    checks = {c.what: c for c in context["checks"]}
    assert set(checks) == {"barrier: trajectories from inside {B ≤ 0} stay in it",
                           "barrier: no trajectory from the initial set enters the unsafe set"}
    assert all(c.ok for c in checks.values()) and not context["soundness"]
    found = re.search(r"(\d+) simulated starts lie in the initial set; none entered", " ".join(
        c.detail for c in checks.values()))
    assert found is not None and int(found.group(1)) >= 12  # the spread starts, and any ring start in it
    text = Page(render_html("certificate.html.j2", context)).text
    assert "The sets, as the model states them set piece inequalities (all hold) initial 1 of 1 (x1 - 1.5)**2" in text
    assert "2 of 2 0.4 <= x1 and x1 <= 0.6 and 0.1 <= x2 and x2 <= 0.5" in text
    assert "Falsification beside the search" in text and "starts sampled in the initial set 100" in text
    assert "Shaded: the model's [sets] as it states them, initial (green), unsafe (red)." in text


def test_a_made_up_barrier_whose_zero_level_a_trajectory_leaves_raises_the_alarm() -> None:
    """{B <= 0} a disc of radius sqrt(0.3) about the initial set's centre holds the initial set, but
    every trajectory from it leaves for the equilibrium at 0: the invariance check fails (the
    unsafe set is still never entered, as the true system is safe) and the page raises the alarm."""
    from reports.certificate_page import certificate_context

    made_up = {"status": "certified", "summary": "made up by the test", "property": "safety", "degree": 2,
               "certificate": {"kind": "barrier", "B": {"terms": [["1", [2, 0]], ["1", [0, 2]], ["-3", [1, 0]],
                                                                  ["39/20", [0, 0]]]}}}
    context = certificate_context(_synthetic(PRAJNA, {"barrier": made_up}), recheck=False)
    checks = {c.what: c for c in context["checks"]}
    stay = checks["barrier: trajectories from inside {B ≤ 0} stay in it"]
    assert not stay.ok and re.search(r"B rose above 0 along \d+ of them", stay.detail) and "leaving at t = " in stay.detail
    assert checks["barrier: no trajectory from the initial set enters the unsafe set"].ok
    assert context["soundness"].startswith("SOUNDNESS: a simulation contradicts a certificate")
    assert context["portrait"].data["invariant_drawn"] == ["barrier"]


def test_the_safety_tables_read_the_sets_as_written_and_the_falsification() -> None:
    """For any number of states: one row per piece of each set the class is about, and the
    falsification's figures (a reach_avoid also lists its goal)."""
    from reports.sections.safety import falsification_table, sets_table

    text = {"initial": (("x <= 0", "y >= 1"),), "unsafe": (("x >= 2",), ("z**2 >= 9",)), "goal": (("x**2 <= 1",),)}
    table = sets_table("reach_avoid", text)
    assert table is not None and table.rows == [("initial", "1 of 1", "x <= 0  and  y >= 1"),
                                                ("unsafe", "1 of 2", "x >= 2"), ("", "2 of 2", "z**2 >= 9"),
                                                ("goal", "1 of 1", "x**2 <= 1")]
    barrier = sets_table("barrier", text)
    assert barrier is not None and [r[0] for r in barrier.rows] == ["initial", "unsafe", ""]
    assert sets_table("barrier", {}) is None
    trial = falsification_table({"closest_approach": -0.25, "falsification": {
        "samples": 100, "trajectories": 400, "horizon": 24.0, "disturbance_scenarios": 4, "entered": False}})
    assert trial is not None
    rows = dict(trial.rows)
    assert rows["trajectories simulated"] == "400 (100 starts x 4 disturbance scenarios)"
    assert rows["horizon"] == "24 s" and rows["a trajectory entered the unsafe set"] == "no"
    assert rows["closest approach (largest unsafe margin reached)"].startswith("-0.25: no trajectory entered")
    assert falsification_table({}) is None
