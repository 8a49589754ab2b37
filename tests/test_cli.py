"""The command line as a user meets it: exit codes, one-line errors, files."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

from tests.conftest import EASY_GAINS, PAPER_TOML, ROOT


def run(*args: str, cwd: Path = ROOT) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, "-m", "lyapcheck", *args], capture_output=True, text=True, cwd=cwd,
                          env={**os.environ, "COLUMNS": "200"}, timeout=300)


def test_help_does_not_import_heavy_libraries() -> None:
    code = ("import sys; from lyapcheck.cli import main; sys.argv=['lyapcheck','--help']\n"
            "try:\n main()\nexcept SystemExit: pass\n"
            "bad=[m for m in ('sympy','cvxpy','numpy','pint','scipy') if m in sys.modules]\n"
            "assert not bad, bad")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert done.returncode == 0, done.stderr


def test_derive_json_lists_labels_with_statuses() -> None:
    done = run("derive", "--json")
    assert done.returncode == 0, done.stderr
    entries = json.loads(done.stdout)["ledger"]
    labels = {e["label"] for e in entries}
    for needed in ("eq:los3", "eq:xCrossdyn2", "eq:stabCond2", "eq:zdyn", "eq:speedSS"):
        assert needed in labels
    assert all(set(e) >= {"label", "status", "printed", "derived", "explanation"} for e in entries)
    assert {e["status"] for e in entries} <= {"holds", "discrepancy", "unverifiable"}


def test_certify_paper_and_verify(tmp_path: Path) -> None:
    cert = tmp_path / "paper.json"
    done = run("certify", str(PAPER_TOML), "--json", "--out", str(cert))
    assert done.returncode == 0, done.stderr  # certified by the polynomial class (sos_gas) only
    doc = json.loads(done.stdout)
    assert doc["verdict"] == "certified"
    assert doc["conditions"]["sector_ges"]["status"] == "refuted" and doc["conditions"]["sos_gas"]["status"] == "certified"
    assert set(doc["conditions"]) >= {"prop41_ges", "prop41_iss", "stabcond2", "sector_ges", "ultimate_bound"}
    assert json.loads(cert.read_text()) == doc
    assert run("verify", str(cert)).returncode == 0


def test_certify_easy_gains_by_flags_exits_0() -> None:
    flags = ["--alpha-d", EASY_GAINS["gains.alpha_d"], "--sigma0", EASY_GAINS["gains.sigma0"],
             "--kd", EASY_GAINS["gains.k_d"], "--delta-los", EASY_GAINS["gains.delta_los"],
             "--e11", EASY_GAINS["swimmer.e11"], "--omega-so", "2.8 Hz", "--d-max", "0.088 mm/s"]
    done = run("certify", *flags, "--json")
    assert done.returncode == 0, done.stderr
    assert json.loads(done.stdout)["verdict"] == "certified"


@pytest.mark.parametrize(
    ("args", "fragment"),
    [
        (["certify", str(PAPER_TOML), "--alpha-d", "-3"], "'alpha_d'"),
        (["certify", str(PAPER_TOML), "--delta-los", "0.75 Hz"], "'delta_los'"),
        (["certify", str(PAPER_TOML), "--omega-so", "nan Hz"], "'omega_so'"),
        (["certify", "missing.toml"], "does not exist"),
        (["certify", str(PAPER_TOML), "--dynamics", "guessed"], "guessed"),
        (["verify", "missing.json"], "does not exist"),
        (["frobnicate"], "frobnicate"),
    ],
)
def test_bad_input_is_one_line_exit_2(args: list[str], fragment: str, tmp_path: Path) -> None:
    out = tmp_path / "never.json"
    done = run(*args, "--out", str(out)) if args[0] == "certify" else run(*args)
    assert done.returncode == 2
    lines = done.stderr.strip().splitlines()
    assert len(lines) == 1 and fragment in lines[0] and "Traceback" not in done.stderr
    assert not out.exists()


def test_corrupt_certificate_is_one_line_exit_2(tmp_path: Path) -> None:
    bad = tmp_path / "bad.json"
    bad.write_text("{not json")
    done = run("verify", str(bad))
    assert done.returncode == 2 and len(done.stderr.strip().splitlines()) == 1


def test_quick_classes_and_unknown_class() -> None:
    done = run("certify", str(PAPER_TOML), "--classes", "quick", "--json")
    assert done.returncode == 1  # no quadratic certificate exists at the paper's gains
    assert list(json.loads(done.stdout)["conditions"]) == [
        "prop41_ges", "prop41_iss", "stabcond2", "sector_ges", "switched_ges", "ultimate_bound"]
    bad = run("certify", str(PAPER_TOML), "--classes", "prop41_ges,magic")
    assert bad.returncode == 2 and "'classes'" in bad.stderr and "Traceback" not in bad.stderr


def test_unwritable_output_is_one_line_exit_2() -> None:
    done = run("certify", str(PAPER_TOML), "--classes", "quick", "--out", "/proc/no-such-dir/c.json")
    assert done.returncode == 2 and len(done.stderr.strip().splitlines()) == 1
    assert "cannot access" in done.stderr and "Traceback" not in done.stderr
