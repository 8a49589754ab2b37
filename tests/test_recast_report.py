"""The report page of a loop with functions (reports.subjects.model_file, reports.sections.model_file,
reports.phase_portrait): ``certify FILE --report`` and ``report CERT --html/--pdf`` write it, it
shows the model, the recasting, each class's sentence and V_text, and for two states a phase
portrait in the loop's own states whose certified set is the certificate's.

The damped pendulum is certified once for the module, through the command line.
"""

from __future__ import annotations

import base64
import copy
import json
import math
import re
import subprocess
import sys
from fractions import Fraction
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from markupsafe import escape

from lyapcheck import api
from lyapcheck.models.language.modelfile import parse_any_model
from lyapcheck.models.language.recast import RecastModel
from lyapcheck.models.classes.claims import sentence_of
from lyapcheck.models.engines.recast_numeric import v_values
from lyapcheck.models.engines.recast_sos import poly_from_json
from tests.conftest import ROOT
from tests.recast_loops import ILOS

PENDULUM = ROOT / "examples" / "models" / "recast-pendulum.toml"

ONE_STATE = """
[model]
name = "one state with a sine"
states = ["x"]
[dynamics]
x = "-x - sin(x)/2"
"""


def esc(text: str) -> str:
    """Text as the page's templates escape it (markupsafe, as Jinja2's autoescape)."""
    return str(escape(text))


def lyapcheck(*args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, "-m", "lyapcheck", *args], capture_output=True, text=True, cwd=ROOT)


def phase_svg(page: str) -> str:
    """The phase portrait's SVG, out of its data: URI."""
    found = re.search(r'<figure id="fig-phase"><img src="data:image/svg\+xml;base64,([^"]+)"', page)
    assert found, "the page has no phase portrait"
    return base64.b64decode(found.group(1)).decode()


def model_of(doc: dict[str, Any]) -> RecastModel:
    model = parse_any_model(doc["model"]["text"], "cert")
    assert isinstance(model, RecastModel)
    return model


@pytest.fixture(scope="module")
def pendulum(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Any]:
    """``certify recast-pendulum.toml --out --report page.html``: the document and the page."""
    where = tmp_path_factory.mktemp("recast-report")
    cert, page = where / "pendulum.json", where / "pendulum.html"
    run = lyapcheck("certify", str(PENDULUM), "--out", str(cert), "--report", str(page))
    assert run.returncode == 0, run.stderr
    return {"where": where, "cert": cert, "doc": json.loads(cert.read_text()), "html": page.read_text("utf-8")}


@pytest.fixture(scope="module")
def pendulum_context(pendulum: dict[str, Any]) -> dict[str, Any]:
    from reports.certificate_page import certificate_context

    return certificate_context(pendulum["doc"], recheck=False)


def test_certify_report_writes_the_page_with_the_recasting_and_each_claim(pendulum: dict[str, Any]) -> None:
    doc, page = pendulum["doc"], pendulum["html"]
    assert doc["recast"]["auxiliaries"] == {"s1": "sin(theta)", "c1": "cos(theta)"}
    # the model as written, the auxiliaries with their definitions and flows, the relations
    assert "<code>-sin(theta) - b*omega</code>" in page
    for name, definition in doc["recast"]["auxiliaries"].items():
        assert f"<td><code>{name}</code></td><td><code>{definition}</code></td>" in page
    for name, flow in doc["recast"]["flows"].items():
        assert f"<code>{flow}</code>" in page
    for rel in doc["recast"]["relations"]:
        assert esc(rel["why"]) in page
    # each certified claim's sentence, as the certificate supports it, and V written with the functions
    roa = doc["conditions"]["roa"]
    assert roa["status"] == "certified" and roa["certificate"]["kind"] == "interval"
    assert esc(sentence_of(roa["certificate"])) in page
    assert esc(roa["certificate"]["V_text"][:300]) in page
    # every condition's status, and the exact re-check passed (no alarm)
    for name, cond in doc["conditions"].items():
        assert 'href="#class-' in page and f"<code>{name}</code>" in page
        assert f'class="badge {cond["status"]}"' in page
    assert "Re-checked exactly while this report was made: every certified claim re-checks" in page
    assert 'class="alarm"' not in page
    # the portrait: the true field's streamlines and the certified set, as SVG groups
    svg = phase_svg(page)
    assert 'id="true-field"' in svg and 'id="certified-set-roa"' in svg


def test_the_drawn_set_is_the_certificates_set_in_the_original_states(pendulum: dict[str, Any],
                                                                      pendulum_context: dict[str, Any]) -> None:
    from reports.phase_portrait import gauge
    from reports.sections import RECAST_SECTION

    doc = pendulum["doc"]
    figure = pendulum_context["portrait"]
    assert figure is not None
    drawn = figure.data["sets"]["roa"]
    assert drawn["kind"] == "interval" and drawn["grid_points_inside"] > 1000 and drawn["gauge_at_equilibrium"] == 0
    assert "roa: {V(x) ≤ 0.98} ∩ box" in figure.data["legend"]
    (lo0, lo1), (hi0, hi1) = figure.data["view"]
    assert lo0 < -math.pi and hi0 > math.pi  # the [domain] and the certificate's box are in view
    # the gauge is <= 1 exactly where the certificate's set is: x - x_eq in its box and V <= level,
    # V evaluated from its exact terms (the states only) at random points of the view
    cond = doc["conditions"]["roa"]
    spec = RECAST_SECTION.portrait_set("roa", cond)
    assert spec is not None and spec.box is not None
    model = model_of(doc)
    rng = np.random.default_rng(7)
    X = rng.uniform([lo0, lo1], [hi0, hi1], (4000, 2))
    cert = cond["certificate"]
    V = poly_from_json(model.system.ring, cert["V"], "V")
    in_box = np.all([(X[:, i] >= float(Fraction(cert["box"][s][0]))) & (X[:, i] <= float(Fraction(cert["box"][s][1])))
                     for i, s in enumerate(model.states)], axis=0)
    below = v_values(model.system, V, X) <= float(Fraction(cert["level"]))
    inside = gauge(model, spec, X) <= 1.0
    assert np.array_equal(inside, in_box & below) and inside.sum() > 100


def test_report_writes_html_and_pdf_from_the_certificate_file(pendulum: dict[str, Any]) -> None:
    from tests.test_model_reports import pdf_text

    where = pendulum["where"]
    out_html, out_pdf = where / "again.html", where / "again.pdf"
    run = lyapcheck("report", str(pendulum["cert"]), "--html", str(out_html), "--pdf", str(out_pdf))
    assert run.returncode == 0, run.stderr
    page = out_html.read_text("utf-8")
    assert "The recasting the certificates are proved on" in page and "sin(theta)" in page
    pdf = out_pdf.read_bytes()
    assert pdf.startswith(b"%PDF")
    text = pdf_text(pdf)
    for words in ("The recasting the certificates are proved on", "sin(theta)", "Region of attraction of the true loop",
                  "Phase portrait", "Exact re-check"):
        assert words in text, words


def test_a_recast_set_is_evaluated_with_its_auxiliaries_and_drawn_modulo_2_pi(pendulum: dict[str, Any]) -> None:
    """A recast roa certificate (V over the states and the auxiliaries) whose set is the energy's
    {1 - cos(theta) + omega**2/2 <= 3/2}: written here, not proved, so the page must also raise the
    alarm of the failed exact re-check."""
    from reports.certificate_page import certificate_context
    from reports.html import render_html
    from reports.phase_portrait import gauge
    from reports.sections import RECAST_SECTION

    doc = copy.deepcopy(pendulum["doc"])
    names = doc["recast"]["variables"]
    assert names == ["theta", "omega", "s1", "c1"]
    cert = {"kind": "recast", "variables": names, "auxiliaries": doc["recast"]["auxiliaries"], "angles": ["theta"],
            "shift": {"theta": "0", "omega": "0", "s1": "0", "c1": "1"},
            "V": {"terms": [["1/2", [0, 2, 0, 0]], ["-1", [0, 0, 0, 1]]]},
            "V_text": "1/2*omega**2 - (cos(theta) - 1)", "level": "3/2", "epsilon": "1/100",
            "positivity_epsilon": "1/100"}
    doc["conditions"]["roa"] = {"status": "certified", "property": "ROA", "level": 1.5, "summary": sentence_of(cert),
                                "certificate": cert}
    spec = RECAST_SECTION.portrait_set("roa", doc["conditions"]["roa"])
    assert spec is not None and spec.angles == ("theta",) and spec.box is None
    model = model_of(doc)
    # the auxiliaries at their definitions: V(theta, omega) = 1 - cos(theta) + omega**2/2, a copy every 2 pi
    points = np.array([[0.0, 0.0], [2 * math.pi, 0.0], [math.pi, 0.0], [0.0, 1.5], [1.0, 1.0]])
    expected = (1 - np.cos(points[:, 0]) + points[:, 1] ** 2 / 2) / 1.5
    np.testing.assert_allclose(gauge(model, spec, points), expected, rtol=1e-12, atol=1e-12)
    context = certificate_context(doc)
    figure = context["portrait"]
    assert figure is not None and figure.data["sets"]["roa"]["angles"] == ["theta"]
    # the set {V <= 3/2} crosses omega = 0 only where cos(theta) >= -1/2: |theta| <= 2 pi/3 (+ copies)
    (lo0, _), (hi0, _) = figure.data["view"]
    assert lo0 < -2 * math.pi / 3 and hi0 > 2 * math.pi / 3
    assert "roa: {V(x, a(x)) ≤ 1.5}, modulo 2π in theta" in figure.data["legend"]
    assert "Modulo 2π in theta" in figure.caption
    page = render_html("certificate.html.j2", context)
    assert 'id="certified-set-roa"' in phase_svg(page)
    assert "modulo 2 pi in theta" in page and esc("1/2*omega**2 - (cos(theta) - 1)") in page
    assert "THE EXACT RE-CHECK FAILS" in page and any(name == "roa" and not ok for name, ok, _ in context["recheck"])


def test_a_global_certificate_and_a_one_state_loop(tmp_path: Path) -> None:
    from reports.render import certificate_html

    ilos = tmp_path / "ilos.toml"
    ilos.write_text(ILOS)
    doc = api.certify(model=ilos, classes="sos_gas").document
    assert doc["conditions"]["sos_gas"]["status"] == "certified"
    page = certificate_html(doc)
    assert "<code>sqrt(y**2 + y*yi + 1/4*yi**2 + 4)</code>" in page
    assert esc(doc["conditions"]["sos_gas"]["certificate"]["V_text"]) in page
    assert "Certified globally, so no set to draw: sos_gas." in page
    assert 'id="certified-set-' not in phase_svg(page)
    one = tmp_path / "one.toml"
    one.write_text(ONE_STATE)
    run = lyapcheck("certify", str(one), "--classes", "linearization", "--report", str(tmp_path / "one.html"))
    assert run.returncode == 0, run.stderr
    page = (tmp_path / "one.html").read_text("utf-8")
    assert "No phase portrait: the loop has 1 state: a phase portrait is drawn for 2 states only" in page
    assert "<code>sin(x)</code>" in page


UNSAFE_PENDULUM = """[model]
name = "damped pendulum launched towards an unsafe band"
states = ["theta", "omega"]

[parameters]
b = 0.5

[dynamics]
theta = "omega"
omega = "-sin(theta) - b*omega"

[domain]
theta = [-3, 3]
omega = [-3, 3]

[sets]
initial = ["(theta - 1)**2 + (omega + 2.5)**2 <= 0.04"]
unsafe = ["theta <= -0.6"]
"""


def test_the_portrait_of_a_loop_with_functions_draws_its_sets_and_its_counterexample(tmp_path: Path) -> None:
    """As a polynomial loop's portrait does: the [sets] shaded, and the barrier's counterexample simulated
    again on the true loop (with sin) from its stored start, entering the unsafe set where the class said."""
    from reports.phase_portrait import phase_portrait

    model_file, cert = tmp_path / "unsafe.toml", tmp_path / "unsafe.json"
    model_file.write_text(UNSAFE_PENDULUM)
    run = lyapcheck("certify", str(model_file), "--classes", "barrier", "--out", str(cert))
    assert run.returncode == 1, run.stderr
    doc = json.loads(cert.read_text())
    assert doc["conditions"]["barrier"]["status"] == "counterexample"
    figure = phase_portrait(doc, model_of(doc)).figure
    assert figure is not None
    assert figure.data["model_sets_drawn"] == ["initial", "unsafe"]
    (drawn,) = figure.data["counterexamples"]
    stored = doc["conditions"]["barrier"]["refutation"]
    assert drawn["class"] == "barrier" and drawn["entered"] and drawn["start"] == stored["start"]
    assert drawn["entry_time_s"] == pytest.approx(stored["time"], rel=1e-4)
    assert drawn["entry_point"][0] == pytest.approx(-0.6, abs=1e-6)
    assert "Shaded: the model's [sets]" in figure.caption and "counterexample of barrier" in figure.caption
