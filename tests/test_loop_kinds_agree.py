"""The same command answers the same way on a polynomial loop and on a loop with functions (issue 41,
"one pipeline"): where the two kinds of loop disagreed, each now does what docs/model-files.md
describes. Each test runs one command on both kinds (the 2-state spirals of tests/feature_matrix.py)
and compares what the user sees: the exit code, each condition's status and its sentence.
"""

from __future__ import annotations

import json
import re
from pathlib import Path
from typing import Any

import pytest

from tests import feature_matrix as fm
from tests.conftest import ROOT

KINDS = ("polynomial", "functions")


def certify(tmp_path: Path, kind: str, *args: str) -> tuple[int, str, str]:
    """``lyapcheck certify <kind's loop> ARGS`` (through the CLI, in this process)."""
    return fm.cli("certify", str(fm.model_file(tmp_path, kind)), *args)


def conditions(tmp_path: Path, kind: str, *args: str) -> tuple[int, dict[str, dict[str, Any]]]:
    code, out, err = certify(tmp_path, kind, *args, "--json")
    assert code in (0, 1), (kind, code, err)
    return code, json.loads(out)["conditions"]


def test_the_candidate_class_without_candidate_is_not_applicable_naming_the_flag(tmp_path: Path) -> None:
    """It was exit 2 ("The 'candidate' parameter must be a V ... Got 'nothing'") on a loop with functions."""
    found = {kind: conditions(tmp_path, kind, "--classes", "candidate") for kind in KINDS}
    assert found["polynomial"] == found["functions"], found
    code, conds = found["functions"]
    assert code == 1 and list(conds) == ["candidate"]
    assert conds["candidate"]["status"] == "not_applicable" and "--candidate" in conds["candidate"]["summary"]


def test_candidate_with_a_box_is_taken_on_both_kinds_and_a_v_naming_the_box_refused_alike(tmp_path: Path) -> None:
    """docs/model-files.md, "Boxes of parameters": ``--candidate`` with ``--box`` proves the user's V for every
    value of the box on both kinds (it was refused, exit 2, on both), and a V naming a parameter of the box is
    refused in the same one line on both."""
    for kind in KINDS:
        code, conds = conditions(tmp_path, kind, "--classes", "candidate", "--candidate", fm.CANDIDATE,
                                 "--box", fm.BOX)
        cond = conds["candidate"]
        assert code == 0 and cond["status"] == "certified", (kind, cond)
        assert cond["summary"].startswith("for every a in [0.8, 1.2]: "), (kind, cond["summary"])
        assert cond["certificate"]["parameter_box"] == {"a": ["4/5", "6/5"]}, kind
    lines = {}
    for kind in KINDS:
        code, out, err = certify(tmp_path, kind, "--classes", "candidate", "--candidate", "x1**2 + a*x2**2",
                                 "--box", fm.BOX)
        assert code == 2 and not out.strip(), (kind, code, out)
        line = fm._one_line(err, kind)
        assert "--candidate" in line and "parameter a" in line, line
        lines[kind] = line.replace(str(fm.model_file(tmp_path, kind)), "FILE")
    assert lines["polynomial"] == lines["functions"], lines


def test_the_point_classes_over_a_box_say_the_same_sentence(tmp_path: Path) -> None:
    """``candidate``, asked without ``--candidate``, over a box: one sentence on both kinds (they were
    worded twice; over a box too it names the flag, as the class is taken there). ``linearization`` over a box is decided on both kinds by the same test (issue 45: the
    Hurwitz conditions of the Jacobian of every value, on the whole box), with the same sentence."""
    found = {kind: conditions(tmp_path, kind, "--classes", "linearization,candidate", "--box", fm.BOX)
             for kind in KINDS}
    assert found["polynomial"][1]["candidate"] == found["functions"][1]["candidate"], found
    conds = found["functions"][1]
    assert conds["candidate"]["status"] == "not_applicable" and "--candidate" in conds["candidate"]["summary"]
    lin = {kind: found[kind][1]["linearization"] for kind in KINDS}
    assert {c["status"] for c in lin.values()} == {"certified"}, lin
    assert {c["certificate"]["method"] for c in lin.values()} == {"box_hurwitz"}, lin
    assert lin["polynomial"]["summary"] == lin["functions"]["summary"], lin


@pytest.mark.parametrize("box", [False, True])
def test_a_class_not_taken_on_a_loop_with_functions_is_never_listed_as_taken(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch, box: bool) -> None:
    """The generic refusal of ``certify_model`` on a loop with functions (a class whose registry entry has no
    search on it) listed every class, the refused one too ("...: the classes here are linearization, ...,
    barrier")."""
    import dataclasses

    import lyapcheck
    from lyapcheck.models.classes import registry

    # a barrier entry with no search on a loop with functions (the runner then has no answer for it)
    without_barrier = tuple(dataclasses.replace(c, run_functions=None) if c.name == "barrier" else c
                            for c in registry.CLASSES)
    monkeypatch.setattr(registry, "CLASSES", without_barrier)
    result = lyapcheck.certify(model=fm.model_file(tmp_path, "functions"), classes=["barrier"],
                               **({"box": [fm.BOX]} if box else {}))
    cond = result.document["conditions"]["barrier"]
    assert cond["status"] == "not_applicable", cond
    assert "barrier" not in cond["summary"] and "loop with functions" in cond["summary"], cond
    assert ("over a box" in cond["summary"]) is box, cond


def _table_classes(text: str, first_cell: str) -> list[str]:
    """The classes (backquoted names) of the markdown table row whose first cell is ``first_cell``."""
    row = next(line for line in text.splitlines() if line.startswith(f"| {first_cell} |"))
    return re.findall(r"`([a-z_]+)`", row.split("|")[2])


def test_the_class_tables_of_the_docs_list_every_class() -> None:
    """README's class table lists every class; docs/model-sweeps.md's lists those a sweep spec takes."""
    from lyapcheck.models.classes.registry import NAMES
    from sweeps.spec import MODEL_BOX_CLASSES, MODEL_POINT_CLASSES

    readme = (ROOT / "README.md").read_text(encoding="utf-8")
    listed = [name for name in NAMES if re.search(rf"^\| `{name}` \|", readme, flags=re.M)]
    assert listed == list(NAMES)
    sweeps = (ROOT / "docs" / "model-sweeps.md").read_text(encoding="utf-8")
    assert _table_classes(sweeps, "`points`") == list(MODEL_POINT_CLASSES)
    assert _table_classes(sweeps, "`boxes`") == list(MODEL_BOX_CLASSES)
