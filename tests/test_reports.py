"""Reports as a reader meets them: HTML parsed, PDF rendered to pixels, a real browser's screenshot.

The certificate report is built once per module from a real certificate (the easy gain set,
where every stability class is certified) and reused by the HTML, PDF and browser tests.
"""

from __future__ import annotations

import copy
import json
import subprocess
from fractions import Fraction
from html.parser import HTMLParser
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from tests.conftest import EASY_GAINS, PAPER_TOML

CHROMIUM = Path("/usr/bin/chromium")


class Page(HTMLParser):
    """Tags, attributes and visible text of a page (stdlib parser: what a browser would see)."""

    def __init__(self, html: str) -> None:
        super().__init__(convert_charrefs=True)
        self.tags: list[tuple[str, dict[str, str]]] = []
        self.text_parts: list[str] = []
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
            self.text_parts.append(data)

    @property
    def text(self) -> str:
        return " ".join(" ".join(self.text_parts).split())

    def find(self, tag: str, cls: str | None = None) -> list[dict[str, str]]:
        return [a for t, a in self.tags if t == tag and (cls is None or cls in a.get("class", "").split())]


def _pdf_pages(pdf: bytes, scale: float = 0.6) -> list[Any]:
    import pypdfium2 as pdfium

    doc = pdfium.PdfDocument(pdf)
    try:
        return [np.asarray(doc[i].render(scale=scale).to_pil().convert("RGB")) for i in range(len(doc))]
    finally:
        doc.close()


def _pdf_text(pdf: bytes) -> list[str]:
    import pypdfium2 as pdfium

    doc = pdfium.PdfDocument(pdf)
    try:
        out = []
        for i in range(len(doc)):
            textpage = doc[i].get_textpage()
            out.append(textpage.get_text_range().replace("\u200b", ""))
            textpage.close()
        return out
    finally:
        doc.close()


def _ink(image: Any) -> float:
    """Fraction of pixels that are not (near) white."""
    return float(np.mean(np.min(image, axis=2) < 235))


def _colour_pixels(image: Any, rgb: tuple[int, int, int], tol: int = 40) -> int:
    return int(np.sum(np.all(np.abs(image.astype(int) - np.array(rgb)) <= tol, axis=2)))


@pytest.fixture(scope="module")
def easy_doc() -> dict[str, Any]:
    from lyapcheck.paper.certificate import build_document
    from lyapcheck.paper.certification import run_conditions, verdict
    from lyapcheck.paper.params import problem_from_sources

    problem = problem_from_sources(PAPER_TOML, EASY_GAINS)
    results = run_conditions(problem, "derived")
    return build_document(problem, "derived", results, verdict(results))


@pytest.fixture(scope="module")
def easy_html(easy_doc: dict[str, Any]) -> str:
    from reports.render import certificate_html

    return certificate_html(easy_doc)


@pytest.fixture(scope="module")
def easy_pdf(easy_html: str) -> bytes:
    from reports.render import html_to_pdf

    return html_to_pdf(easy_html)


def _no_network(page: Page) -> None:
    for tag, attrs in page.tags:
        for name in ("src", "href", "srcset", "data", "action", "poster"):
            value = attrs.get(name, "").strip().lower()
            assert not value.startswith(("http:", "https:", "//", "ftp:", "file:")), (tag, name, value[:80])
        if tag in ("img",):
            assert attrs["src"].startswith("data:image/"), attrs["src"][:40]
    assert not any(t in ("script", "link", "iframe", "object", "embed") for t, _ in page.tags)


# ------------------------------------------------------------------------------------------------
# certificate report
# ------------------------------------------------------------------------------------------------
@pytest.mark.slow
def test_certificate_html_shows_verdicts_matrices_figures_offline(easy_doc: dict[str, Any], easy_html: str) -> None:
    page = Page(easy_html)
    _no_network(page)
    assert "Verdict: certified" in page.text
    badges = {a["class"].split()[1] for a in page.find("span", "badge")}
    assert {"certified", "fails", "holds", "discrepancy"} <= badges
    for name, cond in easy_doc["conditions"].items():
        assert name in page.text and cond["summary"] in page.text
    # every typeset equation carries its Typst source and a plain-text alternative
    maths = page.find("img", "math")
    assert len(maths) > 100  # system matrices, certificates, the claims ledger
    alts = " ".join(a["alt"] for a in maths)
    for entry in easy_doc["conditions"]["prop41_ges"]["certificate"]["P"][0]:
        assert entry in alts  # the exact rational P
    assert "Gamma = -(A^T P + P A)" in page.text
    figures = [a for a in page.find("img") if "math" not in a.get("class", "")]
    assert len(figures) == 4
    assert all(len(a["src"]) > 20_000 for a in figures)
    assert "eq:los3" in page.text and "eq:stabCond2" in page.text
    assert "lyapcheck certify inputs.toml --dynamics derived" in page.text


@pytest.mark.slow
def test_certificate_pdf_pages_figures_and_text(easy_pdf: bytes) -> None:
    pages = _pdf_pages(easy_pdf)
    texts = _pdf_text(easy_pdf)
    assert 10 <= len(pages) <= 60
    assert all(_ink(p) > 0.005 for p in pages)
    joined = "\n".join(texts)
    for needed in ("Verdict:", "prop41_ges", "ultimate_bound", "Claims ledger", "Reproducibility", "eq:los3"):
        assert needed in joined, needed
    sim = next(i for i, t in enumerate(texts) if "Path in the plane" in t)
    # the figures: blue trajectories (matplotlib C0) and the green certified set
    blue = sum(_colour_pixels(p, (31, 119, 180)) for p in pages[sim:sim + 2])
    green = sum(_colour_pixels(p, (44, 160, 44)) for p in pages[sim:sim + 2])
    assert blue > 300 and green > 150, (blue, green)  # a blank or missing figure gives 0
    assert _ink(pages[sim]) > 0.03


def test_html_and_pdf_carry_the_same_content(easy_html: str, easy_pdf: bytes) -> None:
    page = Page(easy_html)
    pdf_text = " ".join(" ".join(_pdf_text(easy_pdf)).split())
    for name in ("prop41_ges", "sector_ges", "ultimate_bound", "Gamma = -(A^T P + P A)"):
        assert name in page.text and name in pdf_text
    labels = [t for t in page.text.split() if t.startswith("eq:")]
    assert labels and all(label in pdf_text for label in labels[:40])


def _hostile(doc: dict[str, Any]) -> dict[str, Any]:
    bad = copy.deepcopy(doc)
    script = "<script>alert('x')</script>"
    bad["conditions"][script] = {"status": "certified", "summary": '<img src=x onerror="alert(1)"> & </td>',
                                 "P": [["1", "0"], ["0", "1"]], "note": '#"; #panic("typst") $x$ ] [ \\'}
    bad["inputs"]["given"]["gains.alpha_d"] = '1 </table><a href="https://evil.example">x</a>'
    bad["dynamics"] = '"><b>derived'
    return bad


def test_every_input_string_is_escaped(easy_doc: dict[str, Any]) -> None:
    from reports.render import certificate_html, html_to_pdf

    html = certificate_html(_hostile(easy_doc), ledger=False, simulate=False)
    page = Page(html)
    assert all(t != "script" for t, _ in page.tags)
    assert not any(a.get("src") == "x" or "onerror" in a for _, a in page.tags)
    assert not any(a.get("href", "").startswith("https:") for _, a in page.tags)
    assert "<script>alert('x')</script>" in page.text  # shown as text
    assert '<img src=x onerror="alert(1)"> & </td>' in page.text
    assert "&lt;script&gt;" in html
    pdf_text = " ".join(_pdf_text(html_to_pdf(html)))
    assert "<script>alert('x')</script>" in pdf_text
    assert '#"; #panic("typst") $x$ ] [ \\' in pdf_text  # Typst markup from input stays text


def test_unknown_condition_class_is_shown_generically(easy_doc: dict[str, Any]) -> None:
    from reports.render import certificate_html

    doc = copy.deepcopy(easy_doc)
    doc["conditions"]["future_class"] = {"status": "inconclusive", "summary": "a class from the future",
                                         "weird": {"deep": [[["1/2"]]], "none": None, "flag": True},
                                         "certificate": {"Q": [["2", "1/3"], ["1/3", "5"]]}, 17: [1, "x"]}
    doc["conditions"]["broken_class"] = "not even a table"
    page = Page(certificate_html(doc, ledger=False, simulate=False))
    assert "future_class" in page.text and "a class from the future" in page.text
    assert any('[["2", "1/3"], ["1/3", "5"]]' == a["alt"] for a in page.find("img", "math"))
    assert "broken_class" in page.text and "not even a table" in page.text


def test_certificate_report_picks_the_format_by_extension(easy_doc: dict[str, Any], tmp_path: Path) -> None:
    from lyapcheck.errors import InvalidParameter
    from reports.render import certificate_report

    with pytest.raises(InvalidParameter, match="ending in .html or .pdf"):
        certificate_report(easy_doc, tmp_path / "report.docx")


# ------------------------------------------------------------------------------------------------
# page size: equations on shared sheets, figures simplified
# ------------------------------------------------------------------------------------------------
#: what `lyapcheck certify examples/paper.toml --report paper.html` may weigh (it was 3.8 MB when
#: every equation image carried its own glyph outlines)
PAGE_BUDGET_BYTES = 1_000_000


@pytest.fixture(scope="module")
def paper_results() -> tuple[Any, dict[str, Any]]:
    """The paper's problem and its condition results (derived dynamics), all classes."""
    from lyapcheck.paper.certification import run_conditions
    from lyapcheck.paper.params import problem_from_sources

    problem = problem_from_sources(PAPER_TOML, {})
    return problem, run_conditions(problem, "derived")


@pytest.fixture(scope="module")
def paper_doc(paper_results: tuple[Any, dict[str, Any]]) -> dict[str, Any]:
    """What `lyapcheck certify examples/paper.toml` writes."""
    from lyapcheck.paper.certificate import build_document
    from lyapcheck.paper.certification import verdict

    problem, results = paper_results
    return build_document(problem, "derived", results, verdict(results))


@pytest.fixture(scope="module")
def paper_worst_doc(paper_results: tuple[Any, dict[str, Any]]) -> dict[str, Any]:
    """What `lyapcheck certify examples/paper.toml --worst-case` writes (the real search, smallest budget)."""
    from lyapcheck.api import add_tightness
    from lyapcheck.paper.certificate import build_document
    from lyapcheck.paper.certification import verdict

    problem, results = paper_results
    results = copy.deepcopy(results)
    add_tightness(results, problem, budget_s=1.0)
    return build_document(problem, "derived", results, verdict(results))


@pytest.fixture(scope="module")
def paper_html(paper_doc: dict[str, Any]) -> str:
    from reports.render import certificate_html

    return certificate_html(paper_doc)


def _css(html: str) -> str:
    return html[html.index("<style>"):html.index("</style>")]


def _sheets(html: str) -> dict[str, str]:
    """Sheet class -> the sheet's SVG, read back from the page's stylesheet."""
    import re
    from urllib.parse import unquote

    rule = r'img\.math\.(sheet-\d+) \{ background-image: url\("data:image/svg\+xml,([^"]*)"\); \}'
    rules = re.findall(rule, _css(html))
    return {name: unquote(data) for name, data in rules}


@pytest.mark.slow
def test_paper_certificate_page_is_under_budget_and_self_contained(paper_html: str) -> None:
    import re

    size = len(paper_html.encode("utf-8"))
    assert size < PAGE_BUDGET_BYTES, f"the paper's certificate page is {size} bytes"
    page = Page(paper_html)
    _no_network(page)
    urls = re.findall(r"url\(([^)]{0,40})", _css(paper_html))
    assert urls and all(u.startswith('"data:image/svg+xml,') for u in urls)  # the stylesheet loads nothing either
    maths = page.find("img", "math")
    assert len(maths) > 100
    # every equation is on a sheet, and each keeps what a reader and the PDF need
    assert all("on-sheet" in a["class"] and a["alt"] and a["data-typst"] and a["width"] for a in maths)
    sheets = _sheets(paper_html)
    assert {a["class"].split()[2] for a in maths} == set(sheets)
    # glyph outlines are shared: far fewer definitions than glyphs drawn
    outlines = sum(svg.count("<path id=") for svg in sheets.values())
    glyphs = sum(svg.count("<use ") for svg in sheets.values())
    assert glyphs > 10 * outlines
    assert len([a for a in page.find("img") if "math" not in a.get("class", "")]) == 4  # the figures


# ------------------------------------------------------------------------------------------------
# the phase portrait: certified sets from the exact certificates, the worst case beside them
# ------------------------------------------------------------------------------------------------
def _polygon_contains(boundary: tuple[Any, ...], points: Any) -> Any:
    from matplotlib.path import Path as MplPath

    inside = np.zeros(len(points), dtype=bool)
    for line in boundary:
        inside ^= MplPath(line).contains_points(points)  # even-odd: a hole would be a second line
    return inside


@pytest.mark.slow
def test_sos_bound_contour_spans_exactly_the_certified_eps_bound(paper_doc: dict[str, Any]) -> None:
    """The drawn {V <= 1}: V = 1 on it, inside the certified strip, touching it at the paper's gains."""
    from reports.certified_sets import certified_sets, sos_bound_set, storage_polynomial

    cset, why = sos_bound_set(paper_doc)
    assert cset is not None, why
    bound = paper_doc["conditions"]["sos_bound"]["eps_bound_m"]
    assert cset.eps_bound_m == bound and 1e-4 < bound < 1e-3  # 0.3326 mm
    h = cset.resolution_eps_m
    assert 0 < h < 1e-2 * bound
    # never beyond the certified bound by more than the grid step, and at these gains the set
    # reaches it (the output certificate is tight here)
    assert cset.max_abs_eps_m <= bound + h
    assert cset.max_abs_eps_m >= bound - h
    # residual: the storage function of the certificate is 1 on the drawn boundary, to the
    # accuracy of linear interpolation on the grid; V itself is the exact Gram form, rounded once
    V = storage_polynomial(paper_doc)
    assert V is not None
    u, r = V.to_scaled(cset.points)
    np.testing.assert_allclose(V.from_scaled(u, r), cset.points, rtol=1e-12, atol=0)
    assert np.max(np.abs(cset.gauge(cset.points) - 1.0)) < 1e-3
    # and above 1 just outside the strip |eps| <= bound, along the set's whole height (the exact
    # output identity V - (eps/Delta)^2 + B - 1 >= 0, evaluated in floats)
    lo, hi = cset.bbox
    s = np.linspace(2 * lo[1], 2 * hi[1], 2001)
    for sign in (-1.0, 1.0):
        outside = np.column_stack([np.full_like(s, sign * bound * (1 + 1e-6)), s])
        assert np.min(cset.gauge(outside)) > 1.0
    # the tightest first; the quadratic box of ultimate_bound (34.9 mm) after it
    sets, notes = certified_sets(paper_doc)
    assert [c.key for c in sets] == ["sos_bound sublevel", "ultimate_bound box"] and not notes


def test_sos_bound_contour_stays_inside_its_bound_where_it_is_not_tight(easy_doc: dict[str, Any]) -> None:
    from reports.certified_sets import certified_sets

    sets, _ = certified_sets(easy_doc)
    assert [c.key for c in sets] == ["ultimate_bound ellipsoid", "sos_bound sublevel", "ultimate_bound box"]
    for c in sets:
        assert c.max_abs_eps_m <= c.eps_bound_m + c.resolution_eps_m + 1e-12 * c.eps_bound_m, c.key
    sos = sets[1]
    assert sos.max_abs_eps_m < 0.8 * sos.eps_bound_m  # strictly inside here: B is not the set's extent
    ellipse = sets[0]  # exact shape: its extent is its bound
    assert ellipse.max_abs_eps_m == pytest.approx(ellipse.eps_bound_m, rel=1e-4)
    assert ellipse.eps_bound_m == pytest.approx(easy_doc["conditions"]["ultimate_bound"]["eps_bound_m"], rel=1e-9)


def test_malformed_sos_bound_certificate_is_not_drawn_and_says_why(easy_doc: dict[str, Any]) -> None:
    from reports.certified_sets import certified_sets

    doc = copy.deepcopy(easy_doc)
    doc["conditions"]["sos_bound"]["certificate"]["Q_V"] = [["1/0", "x"]]
    sets, notes = certified_sets(doc)
    assert "sos_bound sublevel" not in [c.key for c in sets] and len(sets) == 2
    assert len(notes) == 1 and "lacks V" in notes[0]
    # a V whose level set would leave the strip its own output certificate proves: refused
    doc = copy.deepcopy(easy_doc)
    cert = doc["conditions"]["sos_bound"]["certificate"]
    cert["B"] = str(Fraction(cert["B"]) / 16)  # claims a quarter of the set's true eps-extent
    sets, notes = certified_sets(doc)
    assert "sos_bound sublevel" not in [c.key for c in sets] and "reaches beyond" in notes[0]


@pytest.fixture(scope="module")
def paper_worst_run(paper_worst_doc: dict[str, Any]) -> Any:
    from reports.closed_loop import simulate_certificate

    return simulate_certificate(paper_worst_doc)


@pytest.mark.slow
def test_worst_case_is_resimulated_as_stored_and_ends_inside_the_sos_set(paper_worst_doc: dict[str, Any],
                                                                          paper_worst_run: Any) -> None:
    from reports.certified_sets import certified_sets
    from reports.paper_figures import phase_figure

    cond = paper_worst_doc["conditions"]["sos_bound"]
    stored = cond["worst_case_sup_abs_eps_tail_m"]
    worst = paper_worst_run.worst
    assert worst is not None, paper_worst_run.worst_reason
    # the batched re-simulation is the search's own figure (per-trajectory steps), from the start it won at
    assert worst.sup_abs_eps_tail_m == pytest.approx(stored, rel=1e-9)
    assert worst.disturbance == cond["worst_case_disturbance"]
    assert set(worst.per_start) == {"origin", "preset"}
    assert worst.sup_abs_eps_tail_m == max(worst.per_start.values())
    bound = cond["eps_bound_m"]
    assert 0.7 * bound < stored < bound  # about 0.28 mm of 0.3326: the bound is within 20 % of the worst
    # soundness cross-check on the drawn data: the worst tail lies inside the contour, and V <= 1 on it
    sets, _ = certified_sets(paper_worst_doc)
    sos = sets[0]
    tr = worst.trajectory
    tail = np.column_stack([tr.eps, tr.s])[tr.t >= paper_worst_run.horizon_s - paper_worst_run.tail_s]
    assert len(tail) > 100
    assert np.all(_polygon_contains(sos.boundary, tail))
    assert np.max(sos.gauge(tail)) <= 1.0
    fig = phase_figure(paper_worst_run, sets, "", "worst case", "a square wave")
    data = fig.data
    assert data["zoom"] and data["worst_case"]["panel"] == "zoom"
    assert data["worst_case"]["max_gauge_tail"]["sos_bound sublevel"] == pytest.approx(np.max(sos.gauge(tail)))
    assert data["worst_case"]["max_abs_eps_tail_samples_m"] <= worst.sup_abs_eps_tail_m * (1 + 1e-9)
    assert data["sets"]["sos_bound sublevel"]["panels"] == ["transient", "zoom"]
    assert data["omitted"] == ["ultimate_bound box"]  # 70 mm x 6.7 m: named in the caption instead
    assert "Not drawn, far larger than the view: the box" in fig.caption
    assert "as stored in the certificate" in fig.caption and "inside the filled set" in fig.caption
    # the constant-disturbance tails are inside too
    assert data["tails_max_gauge"]["sos_bound sublevel"] <= 1.0


@pytest.mark.slow
def test_page_shows_certified_against_worst_simulated(paper_worst_doc: dict[str, Any]) -> None:
    from reports.render import certificate_html

    html = certificate_html(paper_worst_doc, ledger=False)
    assert len(html.encode("utf-8")) < PAGE_BUDGET_BYTES
    page = Page(html)
    for name in ("sos_bound", "ultimate_bound"):
        cond = paper_worst_doc["conditions"][name]
        bound, worst, ratio = cond["eps_bound_m"], cond["worst_case_sup_abs_eps_tail_m"], cond["tightness_ratio"]
        assert ratio == pytest.approx(bound / worst)
        row = (f"certified limsup |eps| {bound * 1e3:.4g} mm worst simulated tail sup |eps| (|d| <= d*, full saturated "
               f"loop) {worst * 1e3:.4g} mm")
        assert row in page.text, name
        assert f"tightness ratio = certified / worst simulated {ratio:.4g} (>= 1" in page.text
    assert page.text.count("Certified bound against the worst disturbance found in simulation") == 2
    assert "SOUNDNESS VIOLATION" not in page.text
    caption = page.text[page.text.index("Phase portrait in (eps, s)"):]
    assert "Orange: the worst disturbance found by the certificate's search" in caption
    assert f"tail sup |eps| = {paper_worst_doc['conditions']['sos_bound']['worst_case_sup_abs_eps_tail_m'] * 1e3:.4g} mm" \
        in caption


def test_page_without_worst_case_says_how_to_get_it_and_flags_a_ratio_below_one(easy_doc: dict[str, Any]) -> None:
    from reports.render import certificate_html

    page = Page(certificate_html(easy_doc, ledger=False, simulate=False))
    assert page.text.count("No worst-case search in this certificate") == 2  # ultimate_bound and sos_bound
    bad = copy.deepcopy(easy_doc)
    bound = bad["conditions"]["sos_bound"]["eps_bound_m"]
    bad["conditions"]["sos_bound"].update({"worst_case_sup_abs_eps_tail_m": 2 * bound, "tightness_ratio": 0.5,
                                            "soundness_violation": True,
                                            "worst_case_disturbance": {"kind": "constant", "family": "constant"}})
    page = Page(certificate_html(bad, ledger=False, simulate=False))
    assert "SOUNDNESS VIOLATION" in page.text and "tightness_ratio 0.5 < 1 for sos_bound" in page.text
    assert "0.5: BELOW 1, the simulation exceeds the certified bound" in page.text


@pytest.mark.slow
def test_paper_page_draws_the_sos_set_without_a_worst_case(paper_html: str, paper_doc: dict[str, Any]) -> None:
    caption = Page(paper_html).text
    caption = caption[caption.index("Phase portrait in (eps, s)"):]
    assert "Filled green: the sublevel set V <= 1 of the polynomial storage function of sos_bound" in caption
    bound_mm = paper_doc["conditions"]["sos_bound"]["eps_bound_m"] * 1e3
    assert 0.3 < bound_mm < 0.35 and f"certified limsup |eps| <= {bound_mm:.4g} mm" in caption
    assert "No worst-case trajectory: the certificate carries no worst-case search" in caption


def test_resampled_boundary_and_compact_svg_draw_the_same(tmp_path: Path) -> None:
    import io

    from matplotlib.figure import Figure

    from reports.certified_sets import ellipse_points
    from reports.figures import compact_svg, resample_closed

    # resampling: evenly spaced at the shape's own proportions, on the original curve
    P = np.array([[1 / 0.0003**2, 0.0], [0.0, 1 / 0.2**2]])  # 0.6 mm x 400 mm, like the sos set
    dense = ellipse_points(P, 4001)
    drawn = resample_closed(dense, 240)
    assert len(drawn) == 241 and np.array_equal(drawn[0], drawn[-1])
    assert np.max(np.abs(np.einsum("ni,ij,nj->n", drawn, P, drawn) - 1)) < 1e-3
    steps = np.hypot(*(np.diff(drawn, axis=0) / np.ptp(drawn, axis=0)).T)
    assert steps.max() < 1.01 * steps.min()
    # compaction: fewer bytes, the same pixels (Typst rasterises both)
    fig = Figure(figsize=(4, 3))
    ax = fig.subplots()
    t = np.linspace(0, 100, 2001)
    ax.plot(t, np.sin(t / 7) * np.exp(-t / 50), label="$\\varepsilon$")
    ax.fill(drawn[:, 0] * 1e5, drawn[:, 1] * 100, alpha=0.2)
    ax.legend()
    buf = io.BytesIO()
    fig.savefig(buf, format="svg")
    raw = buf.getvalue()
    small = compact_svg(raw)
    assert len(small) < 0.9 * len(raw) and b"<!--" not in small
    for name, svg in (("raw", raw), ("small", small)):
        (tmp_path / f"{name}.svg").write_bytes(svg)
    pages = _typst_png('#set page(width: 4in, height: 3in, margin: 0pt)\n#image("raw.svg", width: 100%)\n'
                       '#pagebreak()\n#image("small.svg", width: 100%)', tmp_path)
    assert len(pages) == 2
    _assert_same_drawing(1 - pages[0], 1 - pages[1], "compact_svg")


#: 2 device pixels per CSS px (96 ppi is 1): whole-px offsets stay whole, as in a browser
CHECK_PPI = 192


def _typst_png(source: str, root: Path) -> list[Any]:
    import io

    import typst
    from PIL import Image

    (root / "check.typ").write_text(source)
    pages = typst.compile(str(root / "check.typ"), root=str(root), format="png", ppi=CHECK_PPI,
                          ignore_system_fonts=True)
    pages = pages if isinstance(pages, list) else [pages]
    return [np.asarray(Image.open(io.BytesIO(p)).convert("L"), dtype=float) / 255 for p in pages]


def _whole_px_canvas(svg: bytes, width_pt: float, height_pt: float) -> tuple[bytes, float, float]:
    """``svg`` on a canvas widened (top left fixed, drawing untouched) to whole CSS px.

    Typst rasterises an SVG image into a whole-pixel pixmap and resamples it to the image's
    size, so an image of 180.48 px would be drawn slightly blurred and scaled; a sheet (whole px
    by construction) is not. On whole-px canvases both are drawn alike.
    """
    import math
    import re

    width, height = (math.ceil(v / PT_PER_PX) * PT_PER_PX for v in (width_pt, height_pt))
    size = f'viewBox="0 0 {width} {height}" width="{width}pt" height="{height}pt"'.encode()
    return re.sub(rb'viewBox="[^"]*" width="[^"]*" height="[^"]*"', size, svg, count=1), width, height


#: typographic points per CSS px
PT_PER_PX = 0.75


def test_every_equation_cell_draws_the_typst_equation(easy_html: str, tmp_path: Path) -> None:
    """Each <img class="math">, cut from its sheet as the page's CSS says, draws Typst's own SVG.

    Residual check, no browser needed: the cell is read from the img's background-size and
    background-position percentages (CSS: the offset is (box - image) * p) and cut out of the
    sheet as a viewBox window; it and the original SVG are rasterised by the same renderer,
    Typst's, and compared.
    """
    import html as html_lib
    import re

    from reports.typeset import render

    sheets = _sheets(easy_html)
    maths = Page(easy_html).find("img", "math")
    pages = []
    for k, a in enumerate(maths):
        sheet = sheets[a["class"].split()[2]]
        view_w, view_h = (float(v) for v in re.findall(r"viewBox='0 0 ([\d.]+) ([\d.]+)'", sheet)[0])
        w, h = float(a["width"]), float(a["height"])  # the box, CSS px
        size = [float(v) for v in re.findall(r"background-size:([\d.]+)% ([\d.]+)%", a["style"])[0]]
        pos = [float(v) for v in re.findall(r"background-position:([\d.]+)% ([\d.]+)%", a["style"])[0]]
        sheet_w, sheet_h = w * size[0] / 100, h * size[1] / 100
        dx, dy = (w - sheet_w) * pos[0] / 100, (h - sheet_h) * pos[1] / 100
        source = html_lib.unescape(a["data-typst"])
        original = render([source])[source]
        assert original is not None
        svg, page_w, page_h = _whole_px_canvas(original.svg, original.width_pt, original.height_pt)
        (tmp_path / f"eq{k}.svg").write_bytes(svg)
        unit_x, unit_y = view_w / sheet_w, view_h / sheet_h  # sheet units per CSS px
        # to the sheet's own precision, 0.001 pt, as a browser snaps to pixels: Typst copies an
        # image exactly at a whole-pixel offset but resamples (blurs) it at 1e-4 px off
        window = " ".join(f"{v:.3f}" for v in (-dx * unit_x, -dy * unit_y, page_w / PT_PER_PX * unit_x,
                                                page_h / PT_PER_PX * unit_y))
        cell = sheet.replace(f"viewBox='0 0 {view_w:g} {view_h:g}'", f"viewBox='{window}'")
        (tmp_path / f"cell{k}.svg").write_text(cell)
        page = f"#page(width: {page_w}pt, height: {page_h}pt, margin: 0pt)"
        pages.append(f'{page}[#image("eq{k}.svg", width: 100%, height: 100%)]')
        pages.append(f'{page}[#image("cell{k}.svg", width: 100%, height: 100%, fit: "stretch")]')
    images = _typst_png("\n".join(pages), tmp_path)
    assert len(images) == 2 * len(maths) > 30
    for k in range(len(maths)):
        _assert_same_drawing(1 - images[2 * k], 1 - images[2 * k + 1], maths[k]["alt"])


def _assert_same_drawing(want: Any, got: Any, what: str) -> None:
    """Two renderings (ink in [0, 1]) show the same drawing, up to antialiasing.

    Coordinates rounded to 0.001 pt move an edge by 1/1000 of a pixel, yet the renderer's
    quarter-pixel scanlines can turn that into a different row of edge pixels: about 1 % of
    the ink at worst. A shift of half a pixel already costs 30 % or more; a missing glyph, even a
    minus sign, leaves solid pixels with no ink near them in the other image.
    """
    ink = float(np.sum(want))
    assert ink > 5, what  # the original draws something
    assert float(np.sum(np.abs(want - got))) < 0.05 * ink, what
    for a, b in ((want, got), (got, want)):
        near = np.zeros_like(b, dtype=bool)  # some ink within one pixel (3 x 3 neighbourhood)
        padded = np.pad(b > 0.25, 1)
        for dy in range(3):
            for dx in range(3):
                near |= padded[dy:dy + b.shape[0], dx:dx + b.shape[1]]
        assert not np.any((a > 0.5) & ~near), what


def test_equations_typst_writes_otherwise_keep_their_own_svg() -> None:
    from reports.html import MathImages, parse_typst_svg, svg_uri
    from reports.typeset import Typeset, render

    typst_eq = render(["x^2 + 1/2"])["x^2 + 1/2"]
    assert typst_eq is not None and parse_typst_svg(typst_eq.svg) is not None
    foreign = [
        b'<svg xmlns="http://www.w3.org/2000/svg" viewBox="0 0 10 10"><circle r="4"/></svg>',
        b'<svg xmlns="http://www.w3.org/2000/svg" viewBox="0 0 10 10"><path d="M0 0a5 5 0 1 0 1 1"/></svg>',  # an arc
        b'<svg xmlns="http://www.w3.org/2000/svg" viewBox="0 0 10 10"><path d="M0 0h1" onclick="x()"/></svg>',
        b"not xml",
    ]
    for svg in foreign:
        assert parse_typst_svg(svg) is None, svg
    images = MathImages([typst_eq] + [Typeset(svg, 7.5, 7.5) for svg in foreign])
    assert images.sheet_count == 1
    assert "on-sheet" in images.image(typst_eq).cls
    for svg in foreign:
        shown = images.image(Typeset(svg, 7.5, 7.5))
        assert shown.cls == "math" and shown.src == svg_uri(svg) and not shown.style
    # no size in Typst's header: not placed by percentages of an empty box, shown on its own
    sizeless = Typeset(typst_eq.svg, 0.0, 0.0)
    shown = MathImages([sizeless]).image(sizeless)
    assert shown.cls == "math" and shown.src.startswith("data:image/svg+xml,%3Csvg") and "<use" not in shown.src


# (the health check's 'generation is slow' depends on the machine's load, not on the code)
@settings(max_examples=200, derandomize=True, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.lists(st.tuples(st.floats(0.1, 1400.0), st.floats(0.1, 1100.0)), max_size=60))
def test_sheets_hold_every_box_apart_and_in_page_order(boxes: list[tuple[float, float]]) -> None:
    import math

    from reports.html import SHEET_GAP_PX, SHEET_HEIGHT_PX, SHEET_WIDTH_PX, pack

    boxes = [(round(w, 1), round(h, 1)) for w, h in boxes]  # the template's 0.1 px sizes
    sheets = pack(boxes)
    placed = [k for cells, _, _ in sheets for k, _, _ in cells]
    assert placed == list(range(len(boxes)))  # each box once, in page order
    for cells, width, height in sheets:
        assert width == max([SHEET_WIDTH_PX] + [math.ceil(w) for w, _ in boxes])
        assert height <= max([SHEET_HEIGHT_PX] + [math.ceil(boxes[k][1]) for k, _, _ in cells])  # or its tallest box
        rects = [(x, y, x + boxes[k][0], y + boxes[k][1]) for k, x, y in cells]
        assert all(isinstance(v, int) for _, x, y in cells for v in (x, y))  # whole px: no resampling
        assert all(0 <= x0 and 0 <= y0 and x1 <= width and y1 <= height for x0, y0, x1, y1 in rects)
        for i, a in enumerate(rects):  # a neighbour never within the gap, even with a pixel of rounding
            for b in rects[i + 1:]:
                assert a[2] + SHEET_GAP_PX <= b[0] or b[2] + SHEET_GAP_PX <= a[0] \
                    or a[3] + SHEET_GAP_PX <= b[1] or b[3] + SHEET_GAP_PX <= a[1], (a, b)


def test_svg_uris_are_inert_in_attributes_and_css() -> None:
    from reports.html import svg_text_uri

    uri = str(svg_text_uri("<svg a='1' b=\"2\">&amp; \\ # % </style></svg>"))
    assert uri.startswith("data:image/svg+xml,")
    assert not set(uri) & set('"<>&\\#\n')


def _path_points(d: str) -> list[tuple[str, float, float]]:
    """Every point of SVG path data (M m L l H h V v C c Z z), absolute: (command, x, y)."""
    import re

    # the SVG number grammar: "1.5.5" is 1.5 and .5, "2-1" is 2 and -1
    tokens = re.findall(r"[A-Za-z]|[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?", d)
    points: list[tuple[str, float, float]] = []
    x = y = x0 = y0 = 0.0
    i, cmd = 0, ""
    while i < len(tokens):
        if tokens[i].isalpha():
            cmd, i = tokens[i], i + 1
            if cmd in "Zz":
                x, y = x0, y0
                points.append(("z", x, y))
                continue
        rel = cmd.islower()
        if cmd in "Hh":
            x, i = (x if rel else 0.0) + float(tokens[i]), i + 1
            points.append(("l", x, y))
            continue
        if cmd in "Vv":
            y, i = (y if rel else 0.0) + float(tokens[i]), i + 1
            points.append(("l", x, y))
            continue
        pairs = 3 if cmd in "Cc" else 1
        bx, by = (x, y) if rel else (0.0, 0.0)
        for _ in range(pairs):
            px, py, i = bx + float(tokens[i]), by + float(tokens[i + 1]), i + 2
            points.append((cmd.lower(), px, py))
        x, y = px, py
        if cmd in "Mm":
            x0, y0, cmd = x, y, "l" if rel else "L"
    return points


def test_compact_path_data_draws_the_same_path() -> None:
    from reports.html import compact_path_data

    # a superscript glyph as Typst writes it (4 decimals), then absolute and implicit commands
    d = ("M 0 0m 0.9996 3.5616c 0.2688 0 0.4704 0.2016 0.4704 0.4704c 0 0.3024 -0.1596 0.462 -0.4704 0.4704"
         + "l 0.0003 0.0003" * 40 + "Z m 1 1 2 2 h 3 v -1.00049z L 15 0.5 0.25 -0.5 M 1e-3 2.0004")
    short = compact_path_data(d)
    assert len(short) < 0.8 * len(d)
    before, after = _path_points(d), _path_points(short)
    assert [c for c, _, _ in before] == [c for c, _, _ in after]
    # every point within half a unit of the last decimal kept, however long the path
    assert max(max(abs(a[1] - b[1]), abs(a[2] - b[2])) for a, b in zip(before, after)) <= 5e-4 + 1e-12
    assert compact_path_data("M0 0a5 5 0 1 0 1 1") == "M0 0a5 5 0 1 0 1 1"  # arcs: left as they are


@pytest.mark.parametrize("simplify", [True, False])
def test_figures_are_simplified_whatever_the_user_configuration(simplify: bool) -> None:
    import matplotlib
    from matplotlib.figure import Figure

    from reports.figures import to_svg

    t = np.linspace(0.0, 100.0, 2001)  # a simulated trajectory's sampling
    fig = Figure(figsize=(6.6, 3.0))
    fig.subplots().plot(t, np.exp(-t / 30) * np.cos(t / 3))
    with matplotlib.rc_context({"path.simplify": simplify}):
        svg = to_svg(fig).decode()
    line = max(svg.split(' d="')[1:], key=len)
    assert line.count("L") < 500  # drawn smooth with a fraction of the 2001 samples


def test_inputs_table_stacks_its_cells_under_their_names_on_a_phone(easy_html: str) -> None:
    import re

    section = easy_html[easy_html.index('<section id="inputs">'):]
    table = section[:section.index("</table>")]
    headers = re.findall(r"<th[^>]*>([^<]*)</th>", table[:table.index("</thead>")])
    assert headers == ["parameter", "as given", "SI", "meaning"]
    assert 'class="inputs stack" role="table"' in table
    rows = re.findall(r"<tr role=\"row\">(.*?)</tr>", table[table.index("<tbody"):], re.S)
    assert len(rows) > 10
    for row in rows:  # every value is labelled with its own column's name
        assert re.findall(r'<td role="cell"[^>]* data-label="([^"]*)"', row) == headers
    css = _css(easy_html)
    phone = css[css.index("@media screen and (max-width: 40rem)"):]
    phone = phone[:phone.index("\n}\n")]
    for rule in ("table.stack, table.stack tbody, table.stack tr, table.stack td { display: block;",
                 'table.stack td[data-label]::before { content: attr(data-label) ": ";',
                 "table.stack thead { position: absolute;"):
        assert rule in phone, rule
    assert ".math-wrap { display: block; max-width: 100%; overflow-x: auto;" in css


# ------------------------------------------------------------------------------------------------
# sweep report
# ------------------------------------------------------------------------------------------------
def make_sweep(dims: tuple[str, ...] = ("alpha_d", "sigma0"), *, violations: int = 1) -> Any:
    """A small synthetic sweep store with the issue-5 schema."""
    import xarray as xr

    coords = {"alpha_d": np.geomspace(1.0, 1000.0, 7), "sigma0": np.geomspace(1e-3, 1.0, 5),
              "k_d": np.array([0.05, 0.15, 0.5])}
    c = {d: coords[d] for d in dims}
    shape = tuple(len(v) for v in c.values())
    a = np.meshgrid(*c.values(), indexing="ij")[0]
    status = np.where(a < 30, 1, np.where(a > 300, 2, 0)).astype(np.int8)
    ub = np.where(a < 100, 1, 0).astype(np.int8)
    ub.flat[-1] = -1
    eps = np.where(ub == 1, 1e-4 * (1 + a / 10), np.nan)
    sim = 1e-4 * (1 + a / 20)
    viol = np.zeros(shape, dtype=bool)
    viol.flat[:violations] = True
    data = {"status_prop41_ges": status, "status_ultimate_bound": ub, "status_stabcond2": (a < 10).astype(np.int8),
            "margin_prop41_ges": np.linspace(-1, 1, status.size).reshape(shape),
            "margin_ultimate_bound": np.linspace(0, 1, status.size).reshape(shape),
            "eps_bound_m": eps, "sim_eps_sup_m": sim, "ratio_certified_over_simulated": eps / sim,
            "sim_diverged": a > 500, "soundness_violation": viol, "done": ub >= 0}
    ds = xr.Dataset({k: (dims, v) for k, v in data.items()}, coords=c)
    ds.attrs = {"spec_toml": "[sweep]\nalpha_d = { from = 1, to = 1000, n = 7 }  # <b>not bold</b>\n",
                "versions": json.dumps({"lyapcheck": "0.1.0"}),
                "paper_point": json.dumps({"alpha_d": 600, "sigma0": 0.01, "k_d": 0.15, "delta_los": 0.00075,
                                           "d_max": 8.8e-5})}
    return ds


@pytest.fixture(scope="module")
def sweep_store(tmp_path_factory: pytest.TempPathFactory) -> Path:
    path = tmp_path_factory.mktemp("sweep") / "results.zarr"
    make_sweep().to_zarr(path, mode="w", consolidated=False)
    return path


def test_sweep_report_html_and_pdf(sweep_store: Path, tmp_path: Path) -> None:
    from reports.render import sweep_report

    html_path = sweep_report(sweep_store, tmp_path / "sweep.html")
    pdf_path = sweep_report(sweep_store, tmp_path / "sweep.pdf")
    page = Page(html_path.read_text())
    _no_network(page)
    assert "SOUNDNESS VIOLATIONS: 1 grid point" in page.text
    assert "prop41_ges" in page.text and "ultimate_bound" in page.text
    assert "nearest grid point to the paper's gains" in page.text
    assert "<b>not bold</b>" in page.text and not page.find("b")
    figures = page.find("figure")
    assert len(page.find("img")) == 4 and len(figures) == 4  # one map per class + the ratio map
    pages = _pdf_pages(pdf_path.read_bytes())
    assert 2 <= len(pages) <= 6
    green = sum(_colour_pixels(p, (26, 127, 55), tol=25) for p in pages)
    assert green > 2000  # certified cells drawn
    assert "SOUNDNESS VIOLATIONS" in " ".join(_pdf_text(pdf_path.read_bytes()))


@pytest.mark.parametrize("dims", [("k_d",), ("alpha_d", "sigma0", "k_d")])
def test_sweep_report_one_and_three_parameters(dims: tuple[str, ...]) -> None:
    from reports.render import sweep_html

    page = Page(sweep_html(make_sweep(dims, violations=0)))
    assert "No soundness violation" in page.text
    assert len(page.find("figure")) == 4


def test_sweep_store_without_status_is_refused() -> None:
    from lyapcheck.errors import InputFileError
    from reports.render import sweep_html

    with pytest.raises(InputFileError, match="no 'status_<class>' variable"):
        sweep_html(make_sweep().drop_vars(["status_prop41_ges", "status_ultimate_bound", "status_stabcond2"]))


# ------------------------------------------------------------------------------------------------
# command line
# ------------------------------------------------------------------------------------------------
def _cli() -> Any:
    import click

    from lyapcheck.cli import app, report

    @click.group(cls=app._Group)
    def group() -> None:
        """Test group with only the report command."""

    report.register(group)
    return group


@pytest.mark.parametrize("make, message", [
    (lambda d: d / "absent.json", "does not exist"),
    (lambda d: (d / "bad.json").write_text("{not json") and d / "bad.json", "not valid JSON"),
    (lambda d: (d / "empty.zarr").mkdir() or d / "empty.zarr", "not a readable sweep store"),
])
def test_report_cli_one_line_errors(tmp_path: Path, make: Any, message: str, capsys: pytest.CaptureFixture[str]) -> None:
    source = make(tmp_path)
    with pytest.raises(SystemExit) as exit_info:
        _cli().main(["report", str(source), "--html", str(tmp_path / "out.html")])
    assert exit_info.value.code == 2
    err = capsys.readouterr().err.strip()
    assert message in err and len(err.splitlines()) == 1
    assert not (tmp_path / "out.html").exists()


def test_report_cli_writes_both_formats(sweep_store: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    _cli().main(["report", str(sweep_store), "--html", str(tmp_path / "r.html"), "--pdf", str(tmp_path / "r.pdf")])
    assert (tmp_path / "r.html").read_text().startswith("<!DOCTYPE html>")
    assert (tmp_path / "r.pdf").read_bytes().startswith(b"%PDF")
    assert "wrote" in capsys.readouterr().out


# ------------------------------------------------------------------------------------------------
# a real browser
# ------------------------------------------------------------------------------------------------
def _screenshot(html_file: Path, png: Path, profile: Path, height: int) -> Any:
    from PIL import Image

    subprocess.run([str(CHROMIUM), "--headless", "--no-sandbox", "--disable-gpu", "--disable-background-networking",
                    "--disable-component-update", "--no-first-run", "--disable-sync", f"--user-data-dir={profile}",
                    "--hide-scrollbars", f"--window-size=900,{height}", f"--screenshot={png}", html_file.as_uri()],
                   check=True, capture_output=True, timeout=120)
    return np.asarray(Image.open(png).convert("RGB"))


@pytest.mark.slow
@pytest.mark.skipif(not CHROMIUM.exists(), reason="headless Chromium not installed (Debian package 'chromium')")
def test_chromium_draws_mathematics_and_figures(easy_doc: dict[str, Any], tmp_path: Path) -> None:
    import re

    from reports.render import certificate_html

    # the conditions (equations) and the figures, without the long ledger, fit one tall screenshot
    html = certificate_html(easy_doc, ledger=False)
    # without the sheets (the equations' backgrounds) and any equation's own image
    blank = "data:image/svg+xml;base64,PHN2ZyB4bWxucz0iaHR0cDovL3d3dy53My5vcmcvMjAwMC9zdmciLz4="
    no_math = re.sub(r'background-image: url\("[^"]+"\)', "background-image: none", html)
    no_math = re.sub(r'(<img class="math[^"]*" src=")[^"]+', lambda m: m.group(1) + blank, no_math)
    assert no_math.count("background-image: none") >= 1
    shots = []
    for name, text in (("report", html), ("no-math", no_math)):
        (tmp_path / f"{name}.html").write_text(text)
        shots.append(_screenshot(tmp_path / f"{name}.html", tmp_path / f"{name}.png", tmp_path / "profile", 7000))
    full, stripped = shots
    dark = lambda img: int(np.sum(np.max(img, axis=2) < 100))  # noqa: E731 - black glyphs
    assert dark(full) - dark(stripped) > 5000, "the typeset mathematics is not drawn"
    assert _colour_pixels(full, (31, 119, 180)) > 2000, "the trajectory figures are not drawn"
    assert _colour_pixels(full, (26, 127, 55), tol=20) > 500, "the status badges are not drawn"



#: what a report reader's phone shows: a CSS px width
PHONE_WIDTH_PX = 375
_LAYOUT_PROBE = """<script>
window.addEventListener("load", () => {
  const root = document.documentElement, table = document.querySelector("#inputs table");
  const cells = [...table.querySelectorAll("td")].filter(c => c.offsetParent !== null && c.textContent.trim());
  parent.document.getElementById("probe").textContent = JSON.stringify({
    viewport: root.clientWidth, page: root.scrollWidth,
    wrap: [table.parentElement.clientWidth, table.parentElement.scrollWidth],
    clipped: cells.filter(c => c.scrollWidth > c.clientWidth + 1).length,
    labels: cells.map(c => getComputedStyle(c, "::before").content),
    header_shown: table.querySelector("thead").getBoundingClientRect().height > 1,
  });
});
</script>"""


def _layout(html: str, width: int, tmp_path: Path) -> dict[str, Any]:
    """Layout facts of a page at ``width`` CSS px, measured by Chromium (a probe script added to a copy).

    The page sits in an iframe of that width: headless Chromium's window cannot be that narrow.
    """
    import html as html_lib
    import re

    inner = html.replace("</body>", _LAYOUT_PROBE + "</body>")
    outer = (f'<!DOCTYPE html><html><body style="margin:0"><pre id="probe"></pre><iframe style="width:{width}px;'
             f'height:1500px;border:0" srcdoc="{html_lib.escape(inner, quote=True)}"></iframe></body></html>')
    (tmp_path / "outer.html").write_text(outer)
    command = [str(CHROMIUM), "--headless", "--no-sandbox", "--disable-gpu", "--disable-background-networking",
               "--disable-component-update", "--no-first-run", "--disable-sync",
               f"--user-data-dir={tmp_path / 'profile'}", "--virtual-time-budget=10000", "--dump-dom",
               (tmp_path / "outer.html").as_uri()]
    dom = subprocess.run(command, check=True, capture_output=True, text=True, timeout=120).stdout
    found = re.search(r'<pre id="probe">(.+?)</pre>', dom, re.S)
    assert found, dom[-500:]
    return dict(json.loads(html_lib.unescape(found.group(1))))


@pytest.mark.slow
@pytest.mark.skipif(not CHROMIUM.exists(), reason="headless Chromium not installed (Debian package 'chromium')")
def test_chromium_phone_width_inputs_readable_page_not_wider(easy_html: str, tmp_path: Path) -> None:
    phone = _layout(easy_html, PHONE_WIDTH_PX, tmp_path)
    assert phone["viewport"] <= PHONE_WIDTH_PX
    assert phone["page"] <= phone["viewport"], phone  # nothing makes the whole page scroll sideways
    assert phone["wrap"][1] <= phone["wrap"][0], phone  # the inputs need no sideways scroll either
    assert phone["clipped"] == 0 and not phone["header_shown"]
    # each value shows its column's name ("as given: 600"); the parameter's name heads its block
    assert {'"as given: "', '"SI: "', '"meaning: "'} <= set(phone["labels"]) and "none" in phone["labels"]
    desk = _layout(easy_html, 900, tmp_path)
    assert desk["header_shown"] and set(desk["labels"]) == {"none"}  # a plain table where it fits
