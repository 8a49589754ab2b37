"""Which classes prove their claim with the disturbances at 0 only is declared once, in the class registry
(``ModelClass.zero_disturbance_only``, :data:`lyapcheck.models.classes.registry.ZERO_DISTURBANCE_ONLY`), and
``verify`` reads it on both kinds of loop: such a class's certified claim stating ``"all"`` (every disturbance
signal) fails where a disturbance enters the loop (issue 41)."""

from __future__ import annotations

import copy
from pathlib import Path
from typing import Any

import pytest

import lyapcheck
from lyapcheck.models.classes import registry
from tests import feature_matrix as fm
from tests.test_one_runner import FUNCTIONS_DISTURBED

ZERO_ONLY_ROW = "this class proves its claim with the disturbances at 0 only, not 'all'"
NEITHER_ROW = "a loop with functions is certified with its disturbances at 0"


def failed_rows(document: dict[str, Any], name: str) -> list[str]:
    return [c.message for c in lyapcheck.verify(document).checks if c.check == name and not c.ok]


def test_the_registry_declares_the_classes_proved_with_the_disturbances_at_0() -> None:
    """The linearization is the Jacobian at d = 0, and the candidate's test has no disturbance multipliers:
    the two classes certify with the disturbances at 0 only; every other class may cover them all."""
    assert {c.name for c in registry.CLASSES if c.zero_disturbance_only} == set(registry.ZERO_DISTURBANCE_ONLY)
    assert set(registry.ZERO_DISTURBANCE_ONLY) == {"linearization", "candidate"}


def test_a_polynomial_loops_zero_only_claim_stating_all_fails_by_the_registry(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """A linearization (d = 0) edited to claim every disturbance fails verify naming the class; the row comes
    from the registry's field (without it in the field, that row is not made)."""
    document = lyapcheck.certify(model=fm.model_file(tmp_path, "disturbances"), classes=["linearization"]).document
    assert document["conditions"]["linearization"]["disturbances"] == "zero"
    assert lyapcheck.verify(document).valid
    edited = copy.deepcopy(document)
    edited["conditions"]["linearization"]["disturbances"] = "all"
    assert f"linearization: {ZERO_ONLY_ROW}" in failed_rows(edited, "linearization")
    monkeypatch.setattr(registry, "ZERO_DISTURBANCE_ONLY", ())
    assert all(ZERO_ONLY_ROW not in row for row in failed_rows(edited, "linearization"))


def test_a_loop_with_functions_reads_the_same_field(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """On a loop with functions, a ball-arithmetic region may claim every disturbance value (its robust
    check then decides); a class of the registry's field may not: its ``"all"`` is refused at once."""
    path = tmp_path / "disturbed.toml"
    path.write_text(FUNCTIONS_DISTURBED)
    document = lyapcheck.certify(model=path, classes=["roa"]).document
    roa = document["conditions"]["roa"]
    assert roa["status"] == "certified" and roa["disturbances"] == "zero" and roa["certificate"]["kind"] == "interval"
    edited = copy.deepcopy(document)
    edited["conditions"]["roa"]["disturbances"] = "all"
    rows = failed_rows(edited, "roa")
    assert rows and all(NEITHER_ROW not in row for row in rows)  # (roa's robust check refuses it)
    monkeypatch.setattr(registry, "ZERO_DISTURBANCE_ONLY", ("roa",))
    rows = failed_rows(edited, "roa")
    assert len(rows) == 1 and rows[0].startswith(f"roa: {NEITHER_ROW}") and "'all' is neither" in rows[0]
