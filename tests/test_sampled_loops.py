"""Sampled-data model files (issue 44, item 2): ``[sampling]`` and ``[controller]``, decided by the
linearization over one period; every other reader refuses the file in one line."""

from __future__ import annotations

import json
from fractions import Fraction
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner
from scipy.linalg import expm

from tests.conftest import ROOT

MODELS = ROOT / "examples" / "models"
STABLE = MODELS / "pendulum-digital-pd.toml"
SLOW = MODELS / "pendulum-digital-pd-slow.toml"

DOUBLE_INTEGRATOR = """
[model]
name = "double integrator, digital PD"
states = ["x", "v"]

[parameters]
kp = 1
kd = 1
T = "100 ms"

[dynamics]
x = "v"
v = "u"

[sampling]
period = "T"

[controller]
u = "-kp*x - kd*v"
"""


def _invoke(*args: str) -> tuple[int, str]:
    from lyapcheck.cli import app

    app._register_commands()
    result = CliRunner().invoke(app.cli, list(args))
    return result.exit_code, result.output


def _critical_period(A: np.ndarray, B: np.ndarray, K: np.ndarray, hi: float) -> float:
    def radius(T: float) -> float:
        n, m = B.shape
        M = np.zeros((n + m, n + m))
        M[:n, :n], M[:n, n:] = A * T, B * T
        E = expm(M)
        return float(max(abs(np.linalg.eigvals(E[:n, :n] + E[:n, n:] @ K))))

    lo = 1e-3
    for _ in range(60):
        mid = (lo + hi) / 2
        lo, hi = (mid, hi) if radius(mid) < 1 else (lo, mid)
    return lo


def test_the_examples_certify_and_refute_as_their_comments_say(tmp_path: Path) -> None:
    out = tmp_path / "stable.json"
    code, text = _invoke("certify", str(STABLE), "--out", str(out))
    assert code == 0, text
    doc = json.loads(out.read_text())
    # (the region of attraction on the true flow, roa, makes the verdict more than local)
    assert doc["verdict"] == "certified"
    assert doc["conditions"]["linearization"]["status"] == "certified"
    assert "period 0.02 s" in doc["conditions"]["linearization"]["summary"]
    assert doc["sampling"]["period"] == "1/50" and doc["sampling"]["controller"] == {"u": "-Kp*theta - Kd*omega"}
    assert {doc["conditions"][c]["status"] for c in ("quadratic", "sos_gas")} == {"not_applicable"}
    assert doc["conditions"]["roa"]["status"] == "certified"
    assert _invoke("verify", str(out))[0] == 0

    out = tmp_path / "slow.json"
    code, text = _invoke("certify", str(SLOW), "--out", str(out))
    assert code == 1, text
    doc = json.loads(out.read_text())
    assert doc["verdict"] == "unstable"
    assert doc["conditions"]["roa"]["status"] == "not_certified"  # (no V decreases near an unstable point)
    assert "modulus > 1" in doc["answers"]["stability"]["text"]
    assert "positive real part" not in doc["answers"]["stability"]["text"]
    assert _invoke("verify", str(out))[0] == 0


def test_a_tampered_document_fails_verify() -> None:
    from lyapcheck.api import certify, verify

    doc = certify(model=STABLE).document
    assert verify(doc).valid
    for change in ("period", "status", "summary", "controller", "verdict"):
        bad = json.loads(json.dumps(doc))
        if change == "period":
            bad["sampling"]["period"] = "1/40"
        elif change == "status":
            bad["conditions"]["linearization"]["status"] = "refuted"
            bad["conditions"]["linearization"]["refutation"] = bad["conditions"]["linearization"].pop("certificate")
        elif change == "summary":
            bad["conditions"]["linearization"]["summary"] += " globally"
        elif change == "controller":
            bad["sampling"]["controller"]["u"] = "-Kp*theta"
        else:  # (the document's verdict is "certified": a region is proved besides the linearization)
            bad["verdict"] = "certified_local"
        assert not verify(bad).valid, change
    # the period in the model text itself, with its hash updated: the stored answer no longer follows
    bad = json.loads(json.dumps(doc))
    import hashlib

    bad["model"]["text"] = bad["model"]["text"].replace('T = "20 ms"', 'T = "500 ms"')
    bad["model"]["sha256"] = hashlib.sha256(bad["model"]["text"].encode()).hexdigest()
    assert not verify(bad).valid


def test_the_largest_proved_period_is_within_a_percent_of_the_critical_one() -> None:
    from lyapcheck.api import certify_extremum

    A = np.array([[0.0, 1.0], [9.81, -0.1]])
    critical = _critical_period(A, np.array([[0.0], [1.0]]), np.array([[-30.0, -5.0]]), 1.0)
    found = certify_extremum(STABLE, "T=0.01..1", direction="max", steps=12)
    assert found.proved is not None and found.failed is not None
    proved, failed = float(found.proved), float(found.failed.value)
    assert proved <= critical <= failed
    assert proved > 0.99 * critical
    assert found.failed.outcome == "refuted"


def test_a_polynomial_plant_matches_the_floating_point_critical_period(tmp_path: Path) -> None:
    from lyapcheck.api import certify

    path = tmp_path / "di.toml"
    path.write_text(DOUBLE_INTEGRATOR)
    critical = _critical_period(np.array([[0.0, 1.0], [0.0, 0.0]]), np.array([[0.0], [1.0]]),
                                np.array([[-1.0, -1.0]]), 10.0)
    below, above = f"{critical * 0.999:.6f}", f"{critical * 1.001:.6f}"
    assert certify(model=path, settings={"T": below}).document["verdict"] == "certified"  # (linearization and roa)
    assert certify(model=path, settings={"T": above}).document["verdict"] == "unstable"


def test_a_non_zero_equilibrium_uses_the_controls_value_there(tmp_path: Path) -> None:
    from lyapcheck.api import certify
    from lyapcheck.models.classes.sampled import linear_parts
    from lyapcheck.models.language.sampling import load_sampled

    path = tmp_path / "offset.toml"
    path.write_text('[model]\nstates = ["x"]\n[parameters]\nk = 2\n[dynamics]\nx = "-x + u"\n'
                    '[equilibrium]\nx = 1\n[sampling]\nperiod = "0.1 s"\n[controller]\nu = "1 - k*(x - 1)"\n')
    model = load_sampled(path)
    assert model.control_equilibrium == (Fraction(1),)
    assert linear_parts(model) == ([[Fraction(-1)]], [[Fraction(1)]], [[Fraction(-2)]])
    assert certify(model=path).document["verdict"] == "certified"  # (linearization and roa)
    path.write_text(path.read_text().replace('u = "1 - k*(x - 1)"', 'u = "-k*x"'))
    code, text = _invoke("certify", str(path))
    assert code == 2 and "[equilibrium]" in text and "Traceback" not in text


@pytest.mark.parametrize("command", [("simulate", "--worst-case"), ("certify", "--box", "Kp=20..40"),
                                     ("certify", "--candidate", "theta**2 + omega**2")])
def test_other_commands_refuse_a_sampled_file_in_one_line(command: tuple[str, ...]) -> None:
    if command[0] == "simulate":  # simulate takes the file (tests/test_sampled_simulate.py), not --worst-case
        code, text = _invoke("simulate", "--model", str(STABLE), "--worst-case")
    else:
        code, text = _invoke(command[0], str(STABLE), *command[1:])
    assert code == 2, text
    assert "Traceback" not in text and len(text.strip().splitlines()) == 1
    assert "sampled-data" in text


def test_the_continuous_readers_refuse_a_sampled_file() -> None:
    from lyapcheck.errors import ModelFileError
    from lyapcheck.models.language.modelfile import load_any_model, load_model

    for read in (load_model, load_any_model):
        with pytest.raises(ModelFileError, match=r"\[sampling\].*sampled-data loop"):
            read(STABLE)


@pytest.mark.parametrize("edit, field", [
    (('period = "T"', 'period = "20 mm"'), "[sampling] period"),
    (('period = "T"', 'period = "0 s"'), "[sampling] period"),
    (('period = "T"', 'period = "T"\nrate = 3'), "[sampling] rate"),
    (('u = "-Kp*theta - Kd*omega"', 'u = "-Kp*tanh(theta + 1)"'), "[controller] u"),  # tanh(1): not exact
    (('u = "-Kp*theta - Kd*omega"', 'u = "-Kp*theta - Kd*w"'), "[controller] u"),
    (('u = "-Kp*theta - Kd*omega"', 'theta = "0"'), "[controller] theta"),
    (("[sampling]", "[sets]\ninitial = [\"theta <= 1\"]\n[sampling]"), "[sets]"),
    (('omega = "g_over_l*sin(theta) - c*omega + u"', 'omega = "g_over_l*sin(theta) - c*omega + u"\nu = "0"'),
     "[dynamics] u"),
])
def test_bad_sampling_input_is_one_line_naming_the_field(tmp_path: Path, edit: tuple[str, str], field: str) -> None:
    path = tmp_path / "bad.toml"
    path.write_text(STABLE.read_text().replace(*edit))
    code, text = _invoke("certify", str(path))
    assert code == 2, text
    assert field in text and "Traceback" not in text and len(text.strip().splitlines()) == 1


def test_the_api_takes_the_classes_and_settings() -> None:
    from lyapcheck.api import certify
    from lyapcheck.errors import InvalidParameter

    result = certify(model=STABLE, classes="linearization", settings={"T": "0.5 s"})
    assert list(result.conditions) == ["linearization"] and result.verdict == "unstable"
    with pytest.raises(InvalidParameter):
        certify(model=STABLE, classes="nonsense")


@pytest.mark.slow
@pytest.mark.parametrize("path, status, verdict_exit", [(STABLE, "certified", 0), (SLOW, "refuted", 1)])
def test_a_sampled_loop_s_report_has_its_sampling_and_its_staircase_simulation(tmp_path: Path, path: Path,
                                                                              status: str, verdict_exit: int) -> None:
    """The page of a stable (20 ms) and of an unstable (0.5 s) period: the linearization's answer in the page's
    words, the period and the controller, the exact re-check, and simulate --plot's staircase figure, whose
    trajectories all converge at the stable period and some diverge at the unstable one; no phase portrait
    and no region."""
    import base64
    import re

    from lyapcheck.models.language.sampling import load_sampled
    from reports.certificate_page import certificate_context, read_certificate

    cert, html = tmp_path / "c.json", tmp_path / "c.html"
    assert _invoke("certify", str(path), "--out", str(cert))[0] == verdict_exit
    code, text = _invoke("report", str(cert), "--html", str(html))
    assert code == 0, text
    page = html.read_text()
    assert 'id="sampling"' in page and "Sampling and controller" in page and "-Kp*theta - Kd*omega" in page
    model = load_sampled(path)
    assert f"{float(model.period):g} s" in page and "zero-order" in page
    found = re.search(r'<figure id="fig-staircase"><img src="data:image/svg\+xml;base64,([^"]+)"', page)
    assert found is not None and base64.b64decode(found.group(1)).lstrip().startswith(b"<?xml")
    assert "fig-phase" not in page and "fig-size" not in page and "Phase portrait" not in page
    assert "the figures of this condition are malformed" not in page
    context = certificate_context(read_certificate(cert))
    linearization = next(c for c in context["conditions"] if c.name == "linearization")
    assert linearization.status == status
    assert ("locally exponentially stable" if status == "certified" else "unstable") in linearization.summary
    assert context["recheck"] and not context["recheck_failed"]
    counts = context["series_figure"].data
    assert counts["trajectories"] == 1 + 2 * model.n  # simulate's default starts: x_eq and +- along each state
    if status == "certified":
        assert counts["converged"] == counts["trajectories"] and counts["diverged"] == 0
    else:
        assert counts["diverged"] > 0
    assert f"{counts['diverged']} diverged" in context["series_figure"].caption


def test_sweeps_refuse_a_sampled_loop_in_one_line(tmp_path: Path) -> None:
    spec = tmp_path / "sweep.toml"
    spec.write_text(f'[sweep]\nmodel = "{STABLE}"\n[[sweep.axes]]\nname = "T"\nstart = 0.1\nstop = 0.5\nnum = 3\n')
    code, text = _invoke("sweep", str(spec), "--out", str(tmp_path / "s.zarr"))
    assert code == 2 and "[sampling]" in text and len(text.strip().splitlines()) == 1
    assert not (tmp_path / "s.zarr").exists()
