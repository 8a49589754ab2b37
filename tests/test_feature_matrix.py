"""Feature parity, proved by a table (issue 41): every class x loop kind x surface is exercised through the
public command line and API (``tests/feature_matrix.py``) and is either supported or refused for a reason
documented in :data:`tests.feature_matrix.REFUSALS`; a crash fails; the table in docs/model-files.md
("Feature parity") is the generated one.

About 40 ``certify`` runs at a point, 30 over a box, 40 API calls, their ``verify`` and ``report``, eight
sweeps and five simulations: slow. Statuses such as ``not_certified`` are never asserted (they are answers,
and the surface that gave them works); only supported against refused is.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from tests import feature_matrix as fm


@pytest.fixture(scope="module")
def matrix(tmp_path_factory: pytest.TempPathFactory) -> fm.Matrix:
    return fm.build(tmp_path_factory.mktemp("feature-matrix"))


@pytest.mark.slow
def test_every_cell_is_supported_or_refused_for_its_documented_reason(matrix: fm.Matrix) -> None:
    assert len(matrix.cells) == len(fm.KINDS) * len(fm.CLASSES) * len(fm.CLASS_SURFACES)
    assert len(matrix.loop_cells) == len(fm.KINDS) * len(fm.LOOP_SURFACES)
    assert fm.problems(matrix) == []


@pytest.mark.slow
def test_every_documented_refusal_is_met_by_a_refused_cell(matrix: fm.Matrix) -> None:
    refused = [key for key, outcome in matrix.cells.items() if not outcome.supported]
    for entry in fm.REFUSALS:
        assert any(entry.covers(*key) for key in refused), entry.reason


@pytest.mark.slow
def test_the_docs_show_the_generated_table(matrix: fm.Matrix) -> None:
    assert fm.documented() == fm.table(matrix), "run: python -m tests.feature_matrix --write"


@pytest.mark.slow
def test_the_gaps_issue_41_names_are_supported(matrix: fm.Matrix) -> None:
    """[sets] with a barrier, box sweeps, --plot, series and repr on a loop with functions."""
    for surface in fm.CLASS_SURFACES:
        if surface not in ("--box", "sweep points", "sweep boxes"):
            assert matrix.cells["functions", "barrier", surface].supported, surface
    for cls in ("quadratic", "sos_gas", "roa"):
        assert matrix.cells["functions", cls, "sweep boxes"].supported, cls
    for surface in fm.LOOP_SURFACES:
        assert matrix.loop_cells["functions", surface].supported, surface


# -- the classifier itself: each way the table can be wrong is caught -------------------------------------
def _one_cell(kind: str, cls: str, surface: str, outcome: fm.Outcome) -> fm.Matrix:
    return fm.Matrix(cells={(kind, cls, surface): outcome})


def test_a_refusal_without_an_entry_a_stale_entry_and_other_words_are_each_a_problem() -> None:
    unexplained = _one_cell("polynomial", "quadratic", "certify", fm.Outcome(False, "no"))
    assert fm.problems(unexplained) == ["polynomial / quadratic / certify: refused without a documented reason: no"]
    stale = _one_cell("polynomial", "sos_bound", "certify", fm.Outcome(True, "certified"))
    assert "documented as refused, but supported" in fm.problems(stale)[0]
    other = _one_cell("polynomial", "sos_bound", "certify", fm.Outcome(False, "something else"))
    assert "not for the documented reason" in fm.problems(other)[0]
    meant = _one_cell("polynomial", "sos_bound", "certify", fm.Outcome(False, "the model has no [disturbances]"))
    assert fm.problems(meant) == []
    loop = fm.Matrix(loop_cells={("functions", "series"): fm.Outcome(False, "series is None")})
    assert fm.problems(loop) == ["functions / series: refused without a documented reason: series is None"]


def test_the_table_is_written_between_its_markers_only() -> None:
    doc = f"before\n{fm.BEGIN}\nold\n{fm.END}\nafter\n"
    assert fm.replaced(doc, "new\n") == f"before\n{fm.BEGIN}\nnew\n{fm.END}\nafter\n"
    with pytest.raises(ValueError, match="markers"):
        fm.replaced("no markers\n", "new\n")


def test_a_refusal_is_one_line_and_a_crash_is_not_a_refusal() -> None:
    assert fm._one_line("\nlyapcheck: error: x: bad\n", "w") == "lyapcheck: error: x: bad"
    with pytest.raises(fm.Crash, match="one line"):
        fm._one_line("Traceback (most recent call last):\n  File ...\nAssertionError", "w")


@pytest.mark.parametrize("box", [False, True])
def test_the_candidate_class_without_candidate_is_not_applicable_naming_the_flag(tmp_path: Path, box: bool) -> None:
    """It was an internal error (an assertion, exit 3) on a polynomial loop, at a point and over a box."""
    import json

    path = fm.model_file(tmp_path, "polynomial")
    code, out, err = fm.cli("certify", str(path), "--classes", "candidate", "--json",
                            *(["--box", fm.BOX] if box else []))
    cond = json.loads(out)["conditions"]["candidate"]
    assert code == 1 and cond["status"] == "not_applicable"
    assert "needs --candidate" in cond["summary"]  # (over a box too: the class is taken there)
