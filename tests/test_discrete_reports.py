"""The report page of a discrete-time map's certificate (reports.subjects.model_file with reports.map_figures):
``report CERT --html/--pdf`` writes the model page with the map iterated, never integrated.

What is asserted: the page has the iterates, the certified region with the iterates of starts inside it and
the staircase, in a map's words (next value, iterates, steps); the region drawn is the certificate's
(``{V <= level}`` evaluated from the exact terms); the iterates checked against the certificate hold for a
true certificate and raise the soundness alarm for a tampered one; no integrator is called; a map with
functions (``discrete_interval``) and a one-state map get their pages; the PDF carries the same sections.
"""

from __future__ import annotations

import base64
import copy
import json
import re
from fractions import Fraction
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from click.testing import CliRunner

from lyapcheck.cli import app
from tests.conftest import ROOT

EXAMPLES = ROOT / "examples" / "models"
LOCAL = EXAMPLES / "discrete-local-map.toml"
LOGISTIC = EXAMPLES / "discrete-unstable-map.toml"

#: a map with functions whose roa is proved by ball arithmetic (kind discrete_interval) in about a second
WITH_FUNCTIONS = """[model]
name = "a contracting map with a sine"
states = ["x", "y"]
time = "discrete"
[dynamics]
x = "0.5*sin(x) + 0.2*y"
y = "-0.2*x + 0.5*tanh(y)"
[domain]
x = [-2, 2]
y = [-2, 2]
"""


app._register_commands()


def cli(*args: str) -> Any:
    done = CliRunner().invoke(app.cli, list(args))
    assert done.exception is None or isinstance(done.exception, SystemExit), done.output
    return done


def certify(path: Path, out: Path, *classes: str) -> dict[str, Any]:
    extra = ["--classes", ",".join(classes)] if classes else []
    done = cli("certify", str(path), *extra, "--no-store", "--out", str(out))
    assert done.exit_code in (0, 1), done.output
    return dict(json.loads(out.read_text()))


def figure_svg(page: str, ident: str) -> str:
    found = re.search(rf'<figure id="{ident}"><img src="data:image/svg\+xml;base64,([^"]+)"', page)
    assert found, f"the page has no {ident}"
    return base64.b64decode(found.group(1)).decode()


@pytest.fixture(scope="module")
def local(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Any]:
    """discrete-local-map.toml certified (linearization, roa) and its page written by ``report``."""
    where = tmp_path_factory.mktemp("discrete-report")
    doc = certify(LOCAL, where / "local.json", "linearization", "roa")
    assert doc["conditions"]["roa"]["status"] == "certified"
    done = cli("report", str(where / "local.json"), "--html", str(where / "local.html"))
    assert done.exit_code == 0, done.output
    return {"where": where, "doc": doc, "html": (where / "local.html").read_text("utf-8")}


def test_page_iterates_the_map_in_its_own_words(local: dict[str, Any]) -> None:
    page = local["html"]
    for ident in ("fig-iterates", "fig-region", "fig-staircase"):
        assert f'<figure id="{ident}">' in page
    assert 'id="fig-phase"' not in page and 'id="fig-size"' not in page  # no integrated portrait nor slices
    assert "Iterates of the map" in page and "The certified region, iterated" in page
    assert "<th>next value</th>" in page and "<code>x⁺</code>" in page and "time derivative" not in page
    assert "for all t" not in page and "trajectories" not in page
    assert "Iteration against the certificates" in page and "SOUNDNESS" not in page
    iterates = figure_svg(page, "fig-iterates")
    assert len(re.findall(r'<g id="iterates-\d+"', iterates)) == 16  # two rings of 8 starts
    region = figure_svg(page, "fig-region")
    assert 'id="certified-set-roa"' in region and len(re.findall(r'<g id="inside-roa-\d+"', region)) == 8
    staircase = figure_svg(page, "fig-staircase")
    assert len(re.findall(r'<g id="staircase-0-\d+"', staircase)) == 8  # the starts inside the set


def test_region_and_checks_are_the_certificates(local: dict[str, Any]) -> None:
    """The inside starts lie in {V <= level} by the exact V, their iterates decrease V exactly as the map
    says, and the figure's set is the certificate's (its share of the view against the exact V on a grid)."""
    from lyapcheck.models.language.modelfile import parse_model
    from reports.map_figures import INSIDE_FRACTION, map_figures

    doc = local["doc"]
    cert = doc["conditions"]["roa"]["certificate"]
    level = Fraction(cert["level"])
    terms = [(Fraction(c), e) for c, e in cert["V"]["terms"]]

    def V(x: float, y: float) -> Fraction:  # exact, at the float point's exact value
        fx, fy = Fraction(x), Fraction(y)
        return sum((c * fx ** e[0] * fy ** e[1] for c, e in terms), Fraction(0))

    model = parse_model(doc["model"]["text"], "cert")
    drawn = map_figures(doc, model)
    assert drawn.region is not None and drawn.iterates is not None and drawn.series is not None
    [check] = drawn.checks
    assert check.ok and "8 starts" in check.detail and "0 escaped" in check.detail
    [shown] = drawn.region.data["sets"]
    assert shown["class"] == "roa" and shown["level"] == pytest.approx(float(level))
    # the starts inside: INSIDE_FRACTION of the way to the boundary, so V = INSIDE_FRACTION^2 level (V quadratic)
    from lyapcheck.models.surfaces.iterate import iterate
    from reports.map_figures import _directions
    from lyapcheck.models.engines.crosscheck import ray_boundary

    rim = ray_boundary(lambda e: e[:, 0] ** 2 + e[:, 1] ** 2, float(level), _directions(2))
    assert rim is not None
    for x, y in INSIDE_FRACTION * rim:
        assert V(float(x), float(y)) <= level
        path = iterate(model, np.array([[x, y]]), 5)[0]
        values = [V(float(p), float(q)) for p, q in path]
        assert all(b < a for a, b in zip(values, values[1:]))  # the map's own iterates: V strictly decreases


def test_a_tampered_level_raises_the_iteration_alarm(local: dict[str, Any]) -> None:
    """A level 10 times the certified one takes starts beyond the second fixed point (1/2, -1/2): their
    iterates escape, and the page says that an iteration contradicts the certificate."""
    from reports.certificate_page import certificate_context

    doc = copy.deepcopy(local["doc"])
    cert = doc["conditions"]["roa"]["certificate"]
    cert["level"] = str(Fraction(cert["level"]) * 10)
    context = certificate_context(doc, ledger=False, recheck=False)
    assert context["soundness"].startswith("SOUNDNESS: an iteration contradicts a certificate")
    [check] = context["checks"]
    assert not check.ok


def test_the_report_never_integrates_a_map(local: dict[str, Any], monkeypatch: pytest.MonkeyPatch) -> None:
    import lyapcheck.models.engines.trajectories as trajectories
    from reports.certificate_page import certificate_context

    def refuse(*args: Any, **kwargs: Any) -> Any:
        raise AssertionError("a map was integrated as a field")

    monkeypatch.setattr(trajectories, "simulate", refuse)
    context = certificate_context(local["doc"], ledger=False, recheck=False)
    assert context["portrait"] is not None and context["size_figure"] is not None and context["checks"]


@pytest.mark.slow
def test_a_map_with_functions_and_a_one_state_map(tmp_path: Path) -> None:
    path = tmp_path / "sine-map.toml"
    path.write_text(WITH_FUNCTIONS)
    # (its default classes now prove GAS with quadratic, so roa is asked alone: its ball-arithmetic region)
    doc = certify(path, tmp_path / "sine.json", "linearization", "roa")
    assert doc["conditions"]["roa"]["certificate"]["kind"] == "discrete_interval"
    assert cli("report", str(tmp_path / "sine.json"), "--html", str(tmp_path / "sine.html")).exit_code == 0
    page = (tmp_path / "sine.html").read_text("utf-8")
    assert "a loop with functions" in page and "discrete-time map" in page and "The functions of the map" in page
    assert "<th>flow</th>" not in page and "The recasting the certificates are proved on" not in page
    assert all(f'<figure id="{ident}">' in page for ident in ("fig-iterates", "fig-region", "fig-staircase"))
    assert "SOUNDNESS" not in page and "Iteration against the certificates" in page
    logistic = certify(LOGISTIC, tmp_path / "logistic.json")
    assert logistic["verdict"] == "unstable"
    assert cli("report", str(tmp_path / "logistic.json"), "--html", str(tmp_path / "l.html")).exit_code == 0
    page = (tmp_path / "l.html").read_text("utf-8")
    assert '<figure id="fig-staircase">' in page and 'id="fig-iterates"' not in page
    assert "the map has one state" in page and "no roa or candidate set is certified" in page


def test_pdf_carries_the_map_sections(local: dict[str, Any]) -> None:
    import pypdfium2

    pdf = local["where"] / "local.pdf"
    assert cli("report", str(local["where"] / "local.json"), "--pdf", str(pdf)).exit_code == 0
    document = pypdfium2.PdfDocument(str(pdf))
    text = " ".join(document[i].get_textpage().get_text_range() for i in range(len(document)))
    assert "Iterates of the map" in text and "The certified region, iterated" in text


@pytest.mark.slow
def test_three_states_are_drawn_in_the_slice_of_the_first_two(tmp_path: Path) -> None:
    """A 3-state map: starts in the (x, y) slice through the fixed point, the set's slice filled, the
    iterates projected; every state on the staircase."""
    from lyapcheck.models.language.modelfile import parse_model
    from reports.map_figures import map_figures

    path = tmp_path / "map3.toml"
    path.write_text(THREE_STATES)
    doc = certify(path, tmp_path / "map3.json", "linearization", "roa")
    assert doc["conditions"]["roa"]["status"] == "certified"
    drawn = map_figures(doc, parse_model(THREE_STATES, "map3"))
    assert drawn.iterates is not None and drawn.region is not None and drawn.series is not None
    assert "starts in the slice z = z_eq" in drawn.iterates.caption and "(its slice through the fixed point)" in \
        drawn.region.caption
    assert all(check.ok for check in drawn.checks) and drawn.region.data["inside_starts"] == 8
    assert len(re.findall(r'<g id="staircase-\d+-0"', drawn.series.svg.decode())) == 3


THREE_STATES = """[model]
name = "a three-state contracting map"
states = ["x", "y", "z"]
time = "discrete"
[dynamics]
x = "0.5*x + 0.1*y**2"
y = "0.5*y - 0.2*z"
z = "0.3*z + 0.1*x*y"
[domain]
x = [-1, 1]
y = [-1, 1]
z = [-1, 1]
"""
