"""One runner and one verify dispatch, driven by the class registry (issue 41 item 1): ``certify`` runs each
class by its entry for the kind of loop (lyapcheck.models.classes.registry: ``run_field``,
``run_functions``, and on the discrete-time kinds ``run_map``, ``run_map_functions``, ``run_sampled``), and
``verify`` checks each decided condition by its entry (``verify_field``, ``verify_functions``, ``verify_map``,
``verify_map_functions``, ``verify_sampled``); nothing else names the class."""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path
from typing import Any, cast

import pytest

import lyapcheck
from lyapcheck.models.classes import registry
from lyapcheck.models.classes.contexts import FieldCheck, FieldRun, FunctionsCheck, FunctionsRun, MapCheck, \
    MapFunctionsCheck, MapFunctionsRun, MapRun, SampledCheck, SampledRun
from lyapcheck.results import ConditionResult
from tests import feature_matrix as fm
from tests.conftest import ROOT


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


def _numerical_errors() -> list[BaseException]:
    """One error of each kind of numerical trouble the runner turns into ``inconclusive``."""
    import numpy as np

    from lyapcheck.errors import SolverError

    return [SolverError("the solver reported a numerical error"), np.linalg.LinAlgError("Matrix is singular"),
            ZeroDivisionError("a pivot of 0")]


@pytest.mark.parametrize("error", _numerical_errors(), ids=lambda e: type(e).__name__)
def test_numerical_trouble_in_a_class_is_inconclusive_on_every_kind_of_loop(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch, error: BaseException) -> None:
    """A class whose search raises numerical trouble (SolverError, LinAlgError, an ArithmeticError) is
    ``inconclusive`` naming the error, on a loop with functions as on a polynomial loop (one runner, guarded
    alike): the other classes still decide, and the command line exits as it does for the polynomial loop
    (0 or 1), with no traceback."""

    def trouble(ctx: Any, budget: Any) -> ConditionResult:
        raise error

    replaced = tuple(dataclasses.replace(c, run_field=trouble, run_functions=trouble) if c.name == "quadratic" else c
                     for c in registry.CLASSES)
    monkeypatch.setattr(registry, "CLASSES", replaced)
    codes = {}
    for kind in ("polynomial", "functions"):
        code, stdout, stderr = fm.cli("certify", str(fm.model_file(tmp_path, kind)), "--classes",
                                      "linearization,quadratic", "--json")
        conditions = json.loads(stdout)["conditions"]
        quadratic = conditions["quadratic"]
        assert quadratic["status"] == "inconclusive", (kind, quadratic)
        assert "numerical trouble" in quadratic["summary"], (kind, quadratic["summary"])
        assert quadratic["reason"] == f"{type(error).__name__}: {error}", (kind, quadratic)
        assert conditions["linearization"]["status"] == "certified", kind  # (its own entry, untouched)
        assert "Traceback" not in stderr
        codes[kind] = code
    assert codes["functions"] == codes["polynomial"] and codes["polynomial"] in (0, 1), codes


def test_numerical_trouble_in_an_engine_of_a_loop_with_functions_is_inconclusive(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """The relations' Lyapunov search (the engine of ``quadratic`` and ``sos_gas`` on a loop with functions)
    failing with a LinAlgError makes those classes ``inconclusive``, not a traceback."""
    import numpy as np

    from lyapcheck.models.classes import lyapunov_relations

    def singular(*args: Any, **kwargs: Any) -> ConditionResult:
        raise np.linalg.LinAlgError("Singular matrix")

    monkeypatch.setattr(lyapunov_relations, "run_relations", singular)
    result = lyapcheck.certify(model=fm.model_file(tmp_path, "functions"),
                               classes=["linearization", "quadratic", "sos_gas"])
    conditions = result.document["conditions"]
    for name in ("quadratic", "sos_gas"):
        assert conditions[name]["status"] == "inconclusive", conditions[name]
        assert conditions[name]["reason"] == "LinAlgError: Singular matrix"
    assert conditions["linearization"]["status"] == "certified"


#: the feature matrix's loop with functions, pushed by a bounded disturbance that moves its equilibrium
FUNCTIONS_DISTURBED = fm.FUNCTIONS.replace("[dynamics]", "[disturbances]\nd = 0.1\n[dynamics]").replace(
    'x1 = "-a*x1 + sin(x2)/2"', 'x1 = "-a*x1 + sin(x2)/2 + d"')


@pytest.mark.parametrize("kind", ["polynomial", "functions"])
def test_roa_after_gas_is_one_rule_weighing_the_disturbances_on_every_kind_of_loop(tmp_path: Path, kind: str) -> None:
    """``roa`` once GAS is certified (lyapcheck.models.classes.claims.roa_after_gas, one rule): without
    disturbances, the whole state space; with a disturbance that moves the equilibrium, GAS holds with d = 0
    only, and roa says so (``"zero"``, ``d = 0`` in its sentence) on a loop with functions as on a polynomial
    loop; over a box, for every value of it."""
    path = tmp_path / "disturbed.toml"
    assert FUNCTIONS_DISTURBED != fm.FUNCTIONS
    path.write_text(FUNCTIONS_DISTURBED if kind == "functions" else fm.DISTURBANCES)
    plain = lyapcheck.certify(model=fm.model_file(tmp_path, kind), classes=["quadratic", "roa"]).document
    assert plain["conditions"]["quadratic"]["status"] == "certified"
    assert plain["conditions"]["roa"] == {**plain["conditions"]["roa"], "status": "not_applicable",
                                          "summary": "global asymptotic stability is certified (quadratic): the "
                                                     "region of attraction is the whole state space"}
    assert "disturbances" not in plain["conditions"]["roa"]
    disturbed = lyapcheck.certify(model=path, classes=["quadratic", "roa"]).document["conditions"]
    assert disturbed["quadratic"]["status"] == "certified" and disturbed["quadratic"]["disturbances"] == "zero"
    assert disturbed["roa"]["status"] == "not_applicable" and disturbed["roa"]["disturbances"] == "zero"
    assert disturbed["roa"]["summary"] == ("global asymptotic stability is certified (quadratic, d = 0): with every "
                                           "disturbance held at 0 the region of attraction is the whole state space")
    # (the functions loop's quadratic V is not common to its box: the ILOS loop's is, for every kappa)
    boxed = lyapcheck.certify(model=fm.model_file(tmp_path, kind) if kind == "polynomial" else
                              ROOT / "examples" / "models" / "recast-ilos-course.toml", classes=["quadratic", "roa"],
                              box=[fm.BOX if kind == "polynomial" else "kappa=0.4..0.6"]).document["conditions"]
    assert boxed["quadratic"]["status"] == "certified"
    assert boxed["roa"]["summary"] == ("global asymptotic stability is certified (quadratic) for every value of the "
                                       "box: the region of attraction is the whole state space")


def test_roa_after_gas_reads_what_each_gas_claim_covers() -> None:
    """The rule's weighing alone: a GAS claim answers roa only where it covers what roa's claim would; a
    result that states no coverage covers the loop's nominal one; of two GAS claims, the last is named."""
    from lyapcheck.models.classes.claims import roa_after_gas

    def gas(disturbances: Any) -> ConditionResult:
        return ConditionResult("quadratic", "certified", "GAS", disturbances=disturbances)

    assert roa_after_gas({"quadratic": gas("zero")}, "all") is None
    assert roa_after_gas({"quadratic": gas(None)}, "all", nominal="zero") is None
    assert roa_after_gas({"quadratic": gas(None)}, "all", nominal="all") is not None
    answered = roa_after_gas({"quadratic": gas(None)}, "zero", nominal="zero")
    assert answered is not None and answered.disturbances == "zero" and "(quadratic, d = 0)" in answered.summary
    both = roa_after_gas({"quadratic": gas(None), "sos_gas": dataclasses.replace(gas(None), name="sos_gas")}, None)
    assert both is not None and both.status == "not_applicable" and "(sos_gas)" in both.summary
    assert roa_after_gas({"quadratic": dataclasses.replace(gas(None), status="not_certified")}, None) is None


# -- the discrete-time kinds of loop: a map, a map with functions, a sampled-data loop (issue 41) --------------

#: per kind: the model file (the feature matrix's, or a shipped sampled-data loop), a class the kind takes, its
#: entry's search and exact check, and the context types they are given
DISCRETE_KINDS = {
    "discrete": ("quadratic", "run_map", "verify_map", MapRun, MapCheck),
    "map_functions": ("roa", "run_map_functions", "verify_map_functions", MapFunctionsRun, MapFunctionsCheck),
    "sampled": ("linearization", "run_sampled", "verify_sampled", SampledRun, SampledCheck),
}


def _discrete_model(tmp_path: Path, kind: str) -> Path:
    return ROOT / "examples" / "models" / "pendulum-digital-pd.toml" if kind == "sampled" else \
        fm.model_file(tmp_path, kind)


@pytest.mark.parametrize("kind", list(DISCRETE_KINDS))
def test_certify_runs_a_discrete_time_class_by_its_registry_entry(tmp_path: Path, monkeypatch: pytest.MonkeyPatch,
                                                                  kind: str) -> None:
    """On a map, a map with functions and a sampled-data loop, the class's entry for that kind is what certify
    runs (given the kind's context object), guarded and timed by the one runner."""
    name, run_key, _, run_type, _ = DISCRETE_KINDS[kind]
    given: list[Any] = []

    def stub(ctx: Any, budget: Any) -> ConditionResult:
        given.append(ctx)
        return ConditionResult(name, "inconclusive", "the replaced search ran")

    replaced = tuple(dataclasses.replace(c, **{run_key: stub}) if c.name == name else c for c in registry.CLASSES)
    monkeypatch.setattr(registry, "CLASSES", replaced)
    chosen = ["linearization", name] if name != "linearization" else ["linearization", "quadratic"]
    conditions = lyapcheck.certify(model=_discrete_model(tmp_path, kind), classes=chosen).document["conditions"]
    assert conditions[name]["status"] == "inconclusive"
    assert conditions[name]["summary"] == "the replaced search ran"
    assert len(given) == 1 and isinstance(given[0], run_type)
    other = chosen[0] if chosen[1] == name else chosen[1]
    assert conditions[other]["status"] in ("certified", "not_applicable")  # (its own entry, or none)
    if kind == "discrete":
        assert given[0].shifted.numerators and given[0].candidate is None


@pytest.mark.parametrize("kind", ["discrete", "map_functions"])
def test_a_class_without_an_entry_for_a_map_is_not_run_there_and_one_given_an_entry_is(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch, kind: str) -> None:
    """Whether a class runs on a map is its entry alone: ``roa`` without its map entry is ``not_applicable``
    (not searched); ``sos_bound``, which has none, runs once given one."""
    _, run_key, _, _, _ = DISCRETE_KINDS[kind]
    ran: list[str] = []

    def stub(ctx: Any, budget: Any) -> ConditionResult:
        ran.append("sos_bound")
        return ConditionResult("sos_bound", "inconclusive", "the given search ran")

    replaced = tuple(dataclasses.replace(c, **{run_key: None}) if c.name == "roa" else
                     dataclasses.replace(c, **{run_key: stub}) if c.name == "sos_bound" else c
                     for c in registry.CLASSES)
    monkeypatch.setattr(registry, "CLASSES", replaced)
    conditions = lyapcheck.certify(model=fm.model_file(tmp_path, kind),
                                   classes=["roa", "sos_bound"]).document["conditions"]
    assert conditions["roa"]["status"] == "not_applicable"
    assert "discrete-time map" in conditions["roa"]["summary"]
    assert ran == ["sos_bound"] and conditions["sos_bound"]["summary"] == "the given search ran"


@pytest.mark.parametrize("kind", list(DISCRETE_KINDS))
def test_verify_checks_a_discrete_time_condition_by_its_registry_entry(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch, kind: str) -> None:
    """A certified linearization of each discrete-time kind verifies; with its entry's check for that kind
    replaced by one that refuses, verify reports the refusal on its row, given the kind's check context."""
    _, _, verify_key, _, check_type = DISCRETE_KINDS[kind]
    document = lyapcheck.certify(model=_discrete_model(tmp_path, kind), classes=["linearization"]).document
    assert document["conditions"]["linearization"]["status"] == "certified"
    assert lyapcheck.verify(document).valid
    seen: list[Any] = []

    def refuse(name: str, c: dict[str, Any], check: Any) -> tuple[bool, str]:
        seen.append(check)
        return False, "the replaced check refused"

    monkeypatch.setitem(registry.BY_NAME, "linearization",
                        dataclasses.replace(registry.BY_NAME["linearization"], **{verify_key: refuse}))
    checked = lyapcheck.verify(document)
    assert not checked.valid
    assert [c.message for c in checked.checks if c.check == "linearization" and not c.ok] == \
        ["linearization: the replaced check refused"]
    assert len(seen) == 1 and isinstance(seen[0], check_type)


@pytest.mark.parametrize("kind, check, words", [
    ("discrete", MapCheck(shifted=cast(Any, None), model=cast(Any, None)),
     "a certified claim on a discrete-time map that no discrete-time check re-derives"),
    ("map_functions", MapFunctionsCheck(model=cast(Any, None)),
     "a certified claim on a discrete-time map with functions that no check re-derives"),
    ("sampled", SampledCheck(model=cast(Any, None)), "a certified claim on a sampled-data loop that no check re-derives"),
])
def test_a_decided_claim_of_a_class_without_an_entry_for_the_kind_fails_in_its_words(
        kind: str, check: Any, words: str, monkeypatch: pytest.MonkeyPatch) -> None:
    """The dispatch picks the entry by the check context's type; a class without one for that kind fails (never
    reaching another kind's check), in the words of the kind. (``sos_bound`` without its check for the kind: it
    has one on a polynomial map since issue 44's bounds, none on the other kinds.)"""
    field = {"discrete": "verify_map", "map_functions": "verify_map_functions", "sampled": "verify_sampled"}[kind]
    monkeypatch.setitem(registry.BY_NAME, "sos_bound",
                        dataclasses.replace(registry.BY_NAME["sos_bound"], **{field: None}))
    assert getattr(registry.BY_NAME["sos_bound"], field) is None
    assert registry.verify("sos_bound", {"status": "certified"}, check) == (False, words)


def test_the_discrete_time_names_are_derived_from_the_entries() -> None:
    """DISCRETE, MAP_FUNCTIONS and SAMPLED are the classes with each kind's search, and every such class has
    the kind's exact check (no claim certify prints goes unchecked by verify)."""
    from lyapcheck.models.classes.discrete_functions import NOT_YET

    for names, run_key, verify_key in ((registry.DISCRETE, "run_map", "verify_map"),
                                       (registry.MAP_FUNCTIONS, "run_map_functions", "verify_map_functions"),
                                       (registry.SAMPLED, "run_sampled", "verify_sampled")):
        assert names == tuple(c.name for c in registry.CLASSES if getattr(c, run_key) is not None)
        assert all((getattr(c, run_key) is None) == (getattr(c, verify_key) is None) for c in registry.CLASSES)
        assert "linearization" in names
    assert all(name in NOT_YET for name in registry.MAP_FUNCTIONS)  # (its sentence names what a map with
    #                                                                   functions takes)
