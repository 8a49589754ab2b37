"""One runner and one verify dispatch, driven by the class registry (issue 41 item 1): ``certify`` runs each
class by its entry for the kind of loop (lyapcheck.models.classes.registry: ``run_field``,
``run_functions``), and ``verify`` checks each decided condition by its entry (``verify_field``,
``verify_functions``); nothing else names the class."""

from __future__ import annotations

import dataclasses
from pathlib import Path
from typing import Any, cast

import pytest

import lyapcheck
from lyapcheck.models.classes import registry
from lyapcheck.models.classes.contexts import FieldCheck, FieldRun, FunctionsCheck, FunctionsRun
from lyapcheck.results import ConditionResult
from tests import feature_matrix as fm


@pytest.mark.parametrize("kind", ["polynomial", "functions"])
def test_certify_runs_a_class_by_its_registry_entry(tmp_path: Path, monkeypatch: pytest.MonkeyPatch,
                                                    kind: str) -> None:
    """An entry whose search is replaced is the one certify runs, given the loop's context object."""
    given: list[Any] = []

    def stub(ctx: Any, budget: Any) -> ConditionResult:
        given.append(ctx)
        return ConditionResult("quadratic", "inconclusive", "the replaced search ran")

    key = "run_field" if kind == "polynomial" else "run_functions"
    replaced = tuple(dataclasses.replace(c, **{key: stub}) if c.name == "quadratic" else c for c in registry.CLASSES)
    monkeypatch.setattr(registry, "CLASSES", replaced)
    result = lyapcheck.certify(model=fm.model_file(tmp_path, kind), classes=["linearization", "quadratic"])
    conditions = result.document["conditions"]
    assert conditions["quadratic"]["status"] == "inconclusive"
    assert conditions["quadratic"]["summary"] == "the replaced search ran"
    assert conditions["linearization"]["status"] in ("certified", "refuted")  # (its own entry, untouched)
    assert len(given) == 1
    if kind == "polynomial":
        assert isinstance(given[0], FieldRun) and given[0].scaled is not None  # the cleared field
    else:
        assert isinstance(given[0], FunctionsRun) and given[0].box is None and given[0].proved is given[0].loop


@pytest.mark.parametrize("kind", ["polynomial", "functions"])
def test_verify_checks_a_condition_by_its_registry_entry(tmp_path: Path, monkeypatch: pytest.MonkeyPatch,
                                                         kind: str) -> None:
    """A certified linearization verifies; with its entry's check replaced by one that refuses, verify
    reports that refusal on its row (the dispatch reads the entry, not a branch of its own)."""
    document = lyapcheck.certify(model=fm.model_file(tmp_path, kind), classes=["linearization"]).document
    assert document["conditions"]["linearization"]["status"] == "certified"
    assert lyapcheck.verify(document).valid
    seen: list[Any] = []

    def refuse(name: str, c: dict[str, Any], check: Any) -> tuple[bool, str]:
        seen.append(check)
        return False, "the replaced check refused"

    key = "verify_field" if kind == "polynomial" else "verify_functions"
    monkeypatch.setitem(registry.BY_NAME, "linearization",
                        dataclasses.replace(registry.BY_NAME["linearization"], **{key: refuse}))
    checked = lyapcheck.verify(document)
    assert not checked.valid
    assert [c.message for c in checked.checks if c.check == "linearization" and not c.ok] == \
        ["linearization: the replaced check refused"]
    assert len(seen) == 1 and isinstance(seen[0], FieldCheck if kind == "polynomial" else FunctionsCheck)


def test_a_condition_under_a_name_that_is_no_class_fails() -> None:
    ok, why = registry.verify("lyapunov_v2", {"status": "certified"}, FieldCheck(shifted=cast(Any, None)))
    assert not ok and why.startswith("no class named 'lyapunov_v2'")
