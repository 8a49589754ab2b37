"""The Python API: the documented example runs, and the CLI gives the same answers."""

from __future__ import annotations

import json
import os
import re
import subprocess
import sys
from fractions import Fraction
from pathlib import Path

import pytest

from lyapcheck import CertifyResult, certify, verify
from lyapcheck.api import problem_from
from lyapcheck.errors import InvalidParameter
from tests.conftest import PAPER_TOML, ROOT

DOC = ROOT / "docs" / "api.md"


def python_blocks(text: str) -> list[str]:
    return re.findall(r"```python\n(.*?)```", text, flags=re.S)


def test_docs_example_runs(tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]) -> None:
    blocks = python_blocks(DOC.read_text())
    assert len(blocks) >= 2, "docs/api.md lost its runnable example"
    monkeypatch.chdir(tmp_path)
    namespace: dict[str, object] = {}
    for block in blocks:
        exec(compile(block, str(DOC), "exec"), namespace)  # noqa: S102 - the documented example
    out = capsys.readouterr().out
    assert "limsup |eps| <=" in out and "The 'sigma0' parameter must be" in out
    assert (tmp_path / "paper-cert.json").exists()
    assert "lies in the region of attraction" in out and (tmp_path / "cubic.toml").exists()
    # the notebook, box, series and errors sections (docs/api.md runs them all, in order)
    assert "over the box a in [1, 2]" in out and "  candidate      certified       ROA" in out
    assert "series: xarray.Dataset of x, y over 2 trajectories x 501 times" in out
    assert "The 'x0' parameter must be" in out and "cubic.toml: settings['b']: no parameter" in out
    assert "broken.toml: [dynamics] x: unknown name 'z'" in out


def test_every_parameter_form_gives_the_same_problem() -> None:
    nested = {"gains": {"alpha_d": 600, "sigma0": 0.01, "k_d": "0.15 1/s", "delta_los": "0.75 mm"},
              "swimmer": {"e11": "9.3e-5 m"}, "actuation": {"omega_so": "2.8 Hz"}}
    dotted = {"gains.alpha_d": "600", "gains.sigma0": "0.01", "gains.k_d": 0.15, "gains.delta_los": "0.00075 m",
              "swimmer.e11": "9.3e-5 m", "actuation.omega_so": "17.592918860102842 rad/s"}
    short = {"alpha_d": 600, "sigma0": 0.01, "kd": 0.15, "delta_los": "0.75 mm", "e11": "93 um",
             "omega_so": "2.8 Hz"}
    a, b, c = problem_from(nested), problem_from(dotted), problem_from(short)
    assert a.gains == b.gains == c.gains and a.swimmer.e11 == b.swimmer.e11 == c.swimmer.e11
    assert a.gains.delta_los == Fraction(3, 4000)
    # Hz is cycles per second: 2.8 Hz is 2 pi 2.8 rad/s (to the precision of the decimal typed above)
    assert a.actuation.omega_so is not None and b.actuation.omega_so is not None
    assert abs(float(a.actuation.omega_so) - float(b.actuation.omega_so)) < 1e-12
    assert a.d_max is None and a.missing_inputs() == ("disturbance.d_max",)
    assert problem_from(a) is a


def test_bad_parameters_raise_the_one_line_error() -> None:
    with pytest.raises(InvalidParameter, match="The 'alpha_d' parameter must be"):
        problem_from({"alpha_d": "fast", "sigma0": 0.01, "k_d": 0.15, "delta_los": 1, "e11": 1})
    with pytest.raises(InvalidParameter, match="'gains.nope'"):
        problem_from({"gains.nope": 1})
    with pytest.raises(InvalidParameter, match="'classes'"):
        certify(PAPER_TOML, classes=" , ")


def test_the_command_line_prints_the_api_document(tmp_path: Path) -> None:
    api = certify(PAPER_TOML, classes="quick").to_json()
    done = subprocess.run([sys.executable, "-m", "lyapcheck", "certify", str(PAPER_TOML), "--classes", "quick",
                           "--json"], capture_output=True, text=True, cwd=tmp_path, env={**os.environ}, timeout=300)
    cli = json.loads(done.stdout)
    strip = lambda d: {k: v for k, v in d.items() if k != "solver"}  # noqa: E731 - solver timings differ
    assert {k: strip(v) for k, v in cli["conditions"].items()} == {k: strip(v) for k, v in api["conditions"].items()}
    assert cli["verdict"] == api["verdict"] and done.returncode == (0 if api["verdict"] == "certified" else 1)


def test_missing_inputs_make_their_classes_not_applicable_and_verify() -> None:
    result = certify({"alpha_d": 600, "sigma0": 0.01, "k_d": 0.15, "delta_los": "0.75 mm", "e11": "9.3e-5 m"},
                     classes=("sector_ges", "ultimate_bound", "saturated_loop", "sos_bound"))
    assert isinstance(result, CertifyResult)
    statuses = {k: v.status for k, v in result.conditions.items()}
    assert statuses == {"sector_ges": "refuted", "ultimate_bound": "not_applicable",
                        "saturated_loop": "not_applicable", "sos_bound": "not_applicable"}
    assert "--omega-so and --d-max" in result.conditions["saturated_loop"].summary
    doc = result.to_json()
    assert doc["inputs"]["exact_si"]["d_max"] is None and doc["inputs"]["exact_si"]["omega_so"] is None
    assert verify(doc).valid


def test_verify_rejects_a_certified_claim_whose_input_is_missing() -> None:
    doc = certify(PAPER_TOML, classes=("ultimate_bound",)).to_json()
    assert doc["conditions"]["ultimate_bound"]["status"] == "certified" and verify(doc).valid
    doc["inputs"]["exact_si"]["d_max"] = None
    checked = verify(doc)
    assert not checked.valid
    assert any(not c.ok and "is null" in c.message for c in checked.checks)


@pytest.mark.slow
def test_worst_case_search_from_the_command_line_and_tightness_in_certify(tmp_path: Path) -> None:
    done = subprocess.run([sys.executable, "-m", "lyapcheck", "simulate", "--preset", "paper-ilos", "--worst-case",
                           "--budget", "1", "--json"], capture_output=True, text=True, cwd=tmp_path, timeout=600)
    assert done.returncode == 0, done.stderr
    doc = json.loads(done.stdout)
    assert doc["mode"] == "worst_case" and doc["disturbance"]["kind"]
    # the search includes the constant disturbance, so it can only find more
    assert doc["sup_abs_eps_tail_m"] >= doc["constant_sup_abs_eps_tail_m"] > 0
    result = certify(PAPER_TOML, classes=("ultimate_bound",), worst_case=True, worst_case_budget_s=1)
    bound = result.conditions["ultimate_bound"].numbers
    assert bound["tightness_ratio"] == pytest.approx(bound["eps_bound_m"] / bound["worst_case_sup_abs_eps_tail_m"])
    assert bound["tightness_ratio"] >= 1 and "soundness_violation" not in bound


def test_plain_numbers_are_read_in_si_as_the_docs_promise() -> None:
    """``certify({..., "delta_los": 0.00075})`` asked for a unit string before issue 23; the API
    reads a plain number in the field's SI unit (TOML files and flags still want units)."""
    from fractions import Fraction

    from lyapcheck.api import problem_from
    from lyapcheck.errors import InvalidParameter
    from lyapcheck.paper.params import problem_from_sources

    numbers = problem_from({"alpha_d": 600, "sigma0": 0.01, "k_d": 0.15, "delta_los": 0.00075, "e11": 9.3e-5,
                            "omega_so": 17.59})
    units = problem_from({"alpha_d": 600, "sigma0": 0.01, "k_d": "0.15 1/s", "delta_los": "0.75 mm",
                          "e11": "9.3e-5 m", "omega_so": "17.59 rad/s"})
    assert numbers.gains == units.gains and numbers.swimmer.e11 == units.swimmer.e11 == Fraction(93, 10**6)
    assert numbers.actuation.omega_so == units.actuation.omega_so
    with pytest.raises(InvalidParameter, match="delta_los"):
        problem_from_sources(None, {"gains.alpha_d": "600", "gains.sigma0": "0.01", "gains.k_d": "0.15",
                                    "gains.delta_los": "0.00075", "swimmer.e11": "9.3e-5 m"})
