"""One sweep pipeline for every target (issue 29 item 6): the targets' table, classes derived from the
registered ones, one loop."""

from __future__ import annotations

import ast
from pathlib import Path
from types import SimpleNamespace

import numpy as np

from lyapcheck.models.surfaces.certify import MODEL_CLASSES
from sweeps import evaluate, schema, spec, summary, targets
from tests.conftest import ROOT
from tests.test_model_sweeps import LINEAR, POINTS, write
from tests.test_sweeps import spec_text

def test_the_targets_table_lists_the_model_file_and_the_paper() -> None:
    assert [t.name for t in targets.TARGETS] == ["model", "paper"]
    assert targets.target_for_text(POINTS).name == "model"
    assert targets.target_for_text(spec_text()).name == "paper"
    assert targets.target_for_text("not [toml").name == "paper"  # its reader says why


def test_the_one_spec_reader_gives_each_target_its_spec(tmp_path: Path) -> None:
    model = targets.load_any_spec(write(tmp_path / "m", POINTS, LINEAR))
    paper_path = tmp_path / "paper.toml"
    paper_path.write_text(spec_text())
    paper = targets.load_any_spec(paper_path)
    assert isinstance(model, spec.ModelSweepSpec) and targets.target_of(model).name == "model"
    assert isinstance(paper, spec.SweepSpec) and targets.target_of(paper).name == "paper"
    assert targets.target_of(paper).classes("points") == schema.CLASSES


def test_a_model_sweep_runs_the_classes_registered_in_lyapcheck_models() -> None:
    """Every class of MODEL_CLASSES but the user's own candidate, in its order; boxes: those with box
    certificates (not linearization, candidate: point classes)."""
    assert spec.MODEL_POINT_CLASSES == tuple(c for c in MODEL_CLASSES if c != "candidate")
    assert spec.MODEL_BOX_CLASSES == tuple(c for c in MODEL_CLASSES if c != "candidate")
    model = targets.TARGETS[0]
    assert model.classes("points") == spec.MODEL_POINT_CLASSES and model.classes("boxes") == spec.MODEL_BOX_CLASSES


def test_a_new_class_gets_its_store_variables_unit_and_summary_from_the_class_list() -> None:
    """A class registered later (here a made-up 'barrier', with no row in the figures' table) is
    stored, recorded by the unit and summarised without a sweeps module of its own."""
    classes, outputs = ("quadratic", "barrier"), ("y",)
    names = [v.name for v in schema.point_variables(classes, outputs)]
    assert "status_barrier" in names and "quadratic_k" in names
    assert "status_barrier" in [v.name for v in schema.model_box_variables(("p",), classes, outputs)]

    fake = SimpleNamespace(classes=classes, outputs=outputs, discrete=False)
    out = evaluate._model_empty(fake, 1)  # type: ignore[arg-type]
    result = SimpleNamespace(results={
        "quadratic": SimpleNamespace(status="not_certified", numbers={}, disturbances=None),
        "barrier": SimpleNamespace(status="certified", numbers={}, disturbances=None, proves=lambda: "safety"),
    })
    assert evaluate._model_record(fake, result, out, 0) == "certified"  # type: ignore[arg-type]
    assert out["status_barrier"][0] == schema.STATUS_CODES["certified"]
    assert out["note"][0] == "certified by barrier (safety)"

    data = {name: np.asarray(values) for name, values in out.items()}
    data["done"] = np.ones(1, bool)
    found = summary.summarize_model_arrays("model_points", ("p",), {"p": "linear"}, classes, outputs, data,
                                           coords={"p": np.array([1.0])})
    assert found.counts_by_class == {"quadratic": 0, "barrier": 1} and found.share_by_class["barrier"] == 1.0


def test_one_loop_hands_out_every_unit() -> None:
    """Only sweeps.run.pump waits on a runner: no target has a loop of its own."""
    waiting = []
    for path in sorted((ROOT / "sweeps").glob("*.py")):
        if path.name == "runners.py":
            continue
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.Call) and getattr(node.func, "attr", "") == "wait_any":
                waiting.append(path.name)
    assert waiting == ["run.py"]
