"""Reports as a reader meets them: HTML parsed, PDF rendered to pixels, a real browser's screenshot.

The certificate report is built once per module from a real certificate (the easy gain set,
where every stability class is certified) and reused by the HTML, PDF and browser tests.
"""

from __future__ import annotations

import copy
import json
import subprocess
from html.parser import HTMLParser
from pathlib import Path
from typing import Any

import numpy as np
import pytest

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
    from lyapcheck.certificate import build_document
    from lyapcheck.certification import run_conditions, verdict
    from lyapcheck.params import problem_from_sources

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
    blank = "data:image/svg+xml;base64,PHN2ZyB4bWxucz0iaHR0cDovL3d3dy53My5vcmcvMjAwMC9zdmciLz4="
    no_math = re.sub(r'(<img class="math" src=")[^"]+', lambda m: m.group(1) + blank, html)
    shots = []
    for name, text in (("report", html), ("no-math", no_math)):
        (tmp_path / f"{name}.html").write_text(text)
        shots.append(_screenshot(tmp_path / f"{name}.html", tmp_path / f"{name}.png", tmp_path / "profile", 7000))
    full, stripped = shots
    dark = lambda img: int(np.sum(np.max(img, axis=2) < 100))  # noqa: E731 - black glyphs
    assert dark(full) - dark(stripped) > 5000, "the typeset mathematics is not drawn"
    assert _colour_pixels(full, (31, 119, 180)) > 2000, "the trajectory figures are not drawn"
    assert _colour_pixels(full, (26, 127, 55), tol=20) > 500, "the status badges are not drawn"

