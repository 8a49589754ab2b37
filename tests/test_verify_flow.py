"""``verify`` of a model certificate is one flow for every kind of loop (issue 41, "one pipeline"):
:func:`lyapcheck.models.surfaces.verify.verify_model` takes the kind of the model read again from the
document's text, and runs the same steps with that kind's part of each; no second driver is left beside it."""

from __future__ import annotations

import copy
from pathlib import Path
from typing import Any

import pytest

import lyapcheck
from lyapcheck.models.language.modelfile import parse_any_model
from lyapcheck.models.surfaces import verify as flow
from tests import feature_matrix as fm

SURFACES = Path(__file__).resolve().parents[1] / "lyapcheck" / "models" / "surfaces"


@pytest.mark.parametrize(("kind", "expected"), [
    ("polynomial", flow.FIELD), ("rational", flow.FIELD), ("disturbances", flow.FIELD), ("discrete", flow.MAP),
    ("functions", flow.FUNCTIONS), ("map_functions", flow.MAP_FUNCTIONS)])
def test_the_kind_of_loop_is_the_model_texts(kind: str, expected: flow.LoopKind) -> None:
    assert flow.loop_kind(parse_any_model(fm.MODELS[kind])) is expected


def test_no_second_driver_is_left_beside_the_flow() -> None:
    """The loop with functions' twin of verify (``recast_certify``) and the map with functions' own driver
    (``map_functions``) are steps of the one flow now."""
    assert not list(SURFACES.glob("recast_*.py")) and not (SURFACES / "map_functions.py").exists()


def linearization_document(tmp_path: Path, kind: str) -> dict[str, Any]:
    document = lyapcheck.certify(model=fm.model_file(tmp_path, kind), classes=["linearization"]).document
    assert document["conditions"]["linearization"]["status"] == "certified"
    assert lyapcheck.verify(document).valid
    return document


def rows_of(document: dict[str, Any]) -> list[tuple[str, bool, str]]:
    return [(c.check, c.ok, c.message) for c in lyapcheck.verify(document).checks]


@pytest.mark.parametrize("kind", ["polynomial", "functions"])
def test_a_box_naming_no_parameter_ends_verify_at_the_box(tmp_path: Path, kind: str) -> None:
    """Step 2 refuses the box and no condition is checked: a polynomial loop's rows end at the box (as they
    always have), a loop with functions' with the verdict the rows before it support."""
    document = copy.deepcopy(linearization_document(tmp_path, kind))
    document["box"] = {"nothing": ["0", "1"]}
    rows = rows_of(document)
    failed = [row for row in rows if not row[1]]
    assert failed[0][0] == "box" and "lo < hi" in failed[0][2]
    assert all(check != "linearization" for check, _, _ in rows)
    assert (rows[-2][0] == "verdict") is (kind == "functions")


def test_a_map_with_functions_box_not_read_at_its_centre_ends_verify_at_the_box(tmp_path: Path) -> None:
    """A map with functions takes a box read at its centre: one added to a point's document, around another
    centre than the model's value, fails its row, and no condition is checked (the verdict row follows)."""
    document = copy.deepcopy(linearization_document(tmp_path, "map_functions"))
    document["box"] = {"a": ["1/5", "3/5"]}  # (the model reads a = 1)
    rows = rows_of(document)
    failed = [row for row in rows if not row[1]]
    assert failed[0][0] == "box" and "centre" in failed[0][2]
    assert all(check != "linearization" for check, _, _ in rows)
    assert rows[-2][0] == "verdict" and not lyapcheck.verify(document).valid
