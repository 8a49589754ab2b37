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


def test_a_map_with_functions_region_is_held_to_its_figures_and_sentence(tmp_path: Path) -> None:
    """A map with functions' roa (ball arithmetic): its stated level, area and sentence are re-derived from the
    certificate, so a document whose proof is intact but whose printed level or sentence is edited fails."""
    document = lyapcheck.certify(model=fm.model_file(tmp_path, "map_functions"), classes=["roa"]).document
    roa = document["conditions"]["roa"]
    assert roa["status"] == "certified" and lyapcheck.verify(document).valid
    for key, value in (("level", roa["level"] * 4), ("area", roa["area"] * 4),
                       ("summary", "GES of the discrete-time map from every start"), ("cells_spent", 1)):
        forged = copy.deepcopy(document)
        forged["conditions"]["roa"][key] = value
        failed = [row for row in rows_of(forged) if not row[1]]
        if key == "cells_spent":  # a record of the search's work, left as stated and named as such
            assert not failed
        else:
            assert failed and failed[0][0] == "roa", key


def test_a_refuted_claim_nothing_re_derives_fails(tmp_path: Path) -> None:
    """On a polynomial loop only the linearization is ever refuted: a certified quadratic edited to
    'refuted' has no check behind it, and verify fails it instead of counting it silently as not certified."""
    document = lyapcheck.certify(model=fm.model_file(tmp_path, "polynomial"), classes=["quadratic"]).document
    assert document["conditions"]["quadratic"]["status"] == "certified"
    forged = copy.deepcopy(document)
    forged["conditions"]["quadratic"]["status"] = "refuted"
    assert ("quadratic", False, "quadratic: a refuted claim that no check of this kind of loop re-derives") \
        in rows_of(forged)
    assert not lyapcheck.verify(forged).valid
