"""SDSOS and DSOS cones (issue 43, item 2): Gram blocks in the scaled diagonally dominant and the
diagonally dominant cones, built directly and against cvxpy, their exact checks (diagonal dominance and
the H-matrix test, sufficient only, with the semidefinite tests behind them), ``sos_gas`` falling
through to them where the semidefinite forms are too large, and ``verify`` of such a certificate."""

from __future__ import annotations

import json
import sys
from fractions import Fraction
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from lyapcheck.exact import leading_minors_positive
from lyapcheck.sos.definiteness import (BAREISS_MAX, diagonally_dominant, is_positive_definite,
                                        scaled_diagonally_dominant)

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "benchmarks"))

import networks  # noqa: E402  (the benchmark's model generators)


def scaled_field(text: str) -> Any:
    from lyapcheck.models.language.modelfile import parse_model
    from lyapcheck.models.loop.field import apply_scaling, choose_scaling, clear, state_field
    from lyapcheck.models.surfaces.certify import shifted_field

    model = parse_model(text)
    cleared = clear(shifted_field(model), [])
    return state_field(apply_scaling(cleared, choose_scaling(cleared, model.domain)))


POLY2 = '[model]\nstates = ["x", "y"]\n[dynamics]\nx = "-x**3 + y"\ny = "-x - y"\n'


# -- the programs -----------------------------------------------------------------------------------

def test_the_cone_field_leaves_existing_program_keys_alone() -> None:
    """A Gram block in the semidefinite cone prints (and hashes) as before the field existed; the
    other cones are part of the key."""
    from dataclasses import replace

    from lyapcheck.sos.structure import Gram

    g = Gram("V", ((1, 0), (0, 1)), ((0, 1),))
    assert repr(g) == "Gram(name='V', basis=((1, 0), (0, 1)), blocks=((0, 1),), margin=True)"
    assert "cone='sdd'" in repr(replace(g, cone="sdd"))
    field = scaled_field(POLY2)
    from lyapcheck.models.classes import lyapunov
    from lyapcheck.sos.structure import with_cone

    structure = lyapunov.lyapunov_structure(field, 4, lyapunov.symmetry(field))
    assert structure is not None
    keys = {structure.key(), with_cone(structure, "psd").key(), with_cone(structure, "sdd").key(),
            with_cone(structure, "dd").key()}
    assert len(keys) == 3 and with_cone(structure, "psd").key() == structure.key()
    with pytest.raises(ValueError, match="cone must be one of psd, sdd, dd"):
        with_cone(structure, "soc")  # type: ignore[arg-type]


@pytest.mark.parametrize("cone", ["sdd", "dd"])
def test_the_direct_cone_data_and_cvxpy_reach_the_same_optimum(cone: str) -> None:
    """The direct construction of the SDD/DD cones (lyapcheck.sos.direct) against cvxpy's
    (lyapcheck.sos.program.build_cvxpy), on a degree-4 Lyapunov program; the cones' optima are
    below the semidefinite one (inner approximations)."""
    from lyapcheck.models.classes import lyapunov
    from lyapcheck.sos.direct import DirectProgram
    from lyapcheck.sos.program import build_cvxpy
    from lyapcheck.sos.sdp import solve as solve_cvxpy
    from lyapcheck.sos.structure import with_cone

    field = scaled_field('[model]\nstates = ["x1", "x2", "x3"]\n[dynamics]\nx1 = "-x1 + x2"\n'
                         'x2 = "-2*x2 + x3 - x2**3"\nx3 = "-x3 - x1"\n')
    structure = lyapunov.lyapunov_structure(field, 4, lyapunov.symmetry(field))
    assert structure is not None and any(len(idx) >= 3 for g in structure.grams for idx in g.blocks)
    values = lyapunov.lyapunov_values(field, structure, Fraction(0)).floats
    psd = DirectProgram(structure).solve(values)
    cones = with_cone(structure, cone)  # type: ignore[arg-type]
    direct = DirectProgram(cones).solve(values)
    assert direct.report.outcome == "optimal" and direct.values is not None
    problem, params, variables = build_cvxpy(cones)
    for name, value in values.items():
        params[name].value = value
    assert solve_cvxpy(problem).outcome == "optimal"
    assert float(direct.values["t"]) == pytest.approx(float(variables["t"].value), rel=1e-5, abs=1e-7)
    assert psd.values is not None and float(direct.values["t"]) <= float(psd.values["t"]) + 1e-8
    # the solver's Gram blocks lie in the cone: X - t I diagonally dominant (after a scaling, for SDD)
    t = float(direct.values["t"])
    for key, X in direct.values.items():
        if "__b" in key and X.shape[0] >= 2:
            Y = X - t * np.eye(X.shape[0])
            off = np.abs(Y).sum(axis=1) - np.abs(np.diag(Y))
            if cone == "dd":
                assert np.all(np.diag(Y) >= off - 1e-7)
            else:
                assert np.linalg.eigvalsh(Y)[0] >= -1e-7


@pytest.mark.parametrize("cone", ["sdd", "dd"])
def test_a_cone_program_is_solved_and_its_exact_check_passes_by_the_fast_test(cone: str) -> None:
    """``search_degree`` in a cone: a certificate that names it, whose exact check passes, its Gram
    matrices proved positive definite by the O(n^2) tests alone (DD as it is; SDD by a scaling)."""
    from lyapcheck.models.classes import lyapunov
    from lyapcheck.models.engines.search import Budget, Search
    from lyapcheck.sos.certificates import check_lyapunov

    field = scaled_field(POLY2)
    search = Search(field.ring, Budget(60.0, "test"))
    found, why = lyapunov.search_degree(field, 4, search, 0, cone)
    assert found is not None, why
    assert found["cone"] == cone and lyapunov.CONE_WORDS[cone].split(",")[0] in why
    assert check_lyapunov(field.ring, field.g, field.D, found["V"], found["W"], found["mu"])[0]
    for gram in (found["V"], found["W"]):
        fast = diagonally_dominant if cone == "dd" else scaled_diagonally_dominant
        from lyapcheck.exact import diagonal_blocks

        for idx in diagonal_blocks(gram.Q):
            assert fast([[gram.Q[i][j] for j in idx] for i in idx])


# -- the exact tests --------------------------------------------------------------------------------

def test_a_positive_definite_matrix_that_is_not_dominant_is_proved_by_the_fallback() -> None:
    small = [[Fraction(1), Fraction(3)], [Fraction(3), Fraction(10)]]  # det 1: PD, not DD, SDD
    assert not diagonally_dominant(small) and scaled_diagonally_dominant(small) and is_positive_definite(small)
    three = [[Fraction(1) if i == j else Fraction(3, 5) for j in range(3)] for i in range(3)]  # PD, not SDD
    assert not scaled_diagonally_dominant(three) and is_positive_definite(three)
    # above the Bareiss size: the congruence / characteristic polynomial decide after the fast tests
    n = BAREISS_MAX + 6
    big = [[Fraction(1) if i == j else Fraction(1, 2) for j in range(n)] for i in range(n)]  # eigenvalues 1/2, (n+1)/2
    assert not diagonally_dominant(big) and not scaled_diagonally_dominant(big) and is_positive_definite(big)
    singular = [[Fraction(1), Fraction(3)], [Fraction(3), Fraction(9)]]
    assert not scaled_diagonally_dominant(singular) and not is_positive_definite(singular)


def _random_symmetric(rng: np.random.Generator, n: int) -> list[list[Fraction]]:
    """A symmetric rational matrix near the boundary of diagonal dominance: random off-diagonal
    entries, a diagonal about their row sums, and a random symmetric perturbation."""
    off = rng.integers(-9, 10, size=(n, n))
    off = np.triu(off, 1)
    off = off + off.T
    row = np.abs(off).sum(axis=1)
    # a diagonal at the row sum give or take a little (and sometimes far below it)
    diag = row + rng.integers(-1, 4, size=n)
    if rng.random() < 0.3:
        diag[rng.integers(0, n)] -= rng.integers(0, row.max() + 1)
    m = [[Fraction(int(off[i, j])) for j in range(n)] for i in range(n)]
    for i in range(n):
        m[i][i] = Fraction(int(diag[i])) + Fraction(int(rng.integers(-1, 2)), int(rng.integers(2, 7)))
    scale = rng.integers(1, 4, size=n) if rng.random() < 0.5 else np.ones(n, dtype=int)  # D M D: dominance after a scaling
    return [[m[i][j] * int(scale[i]) * int(scale[j]) for j in range(n)] for i in range(n)]


def test_the_fast_tests_never_accept_a_matrix_that_is_not_positive_definite() -> None:
    """Seeded random rational matrices near the boundary (and indefinite ones among them): whenever a
    fast test says yes, the independent exact test (leading minors) agrees; and both answers occur."""
    rng = np.random.default_rng(4301)
    accepted = refused_definite = indefinite = only_scaled = 0
    for _ in range(400):
        n = int(rng.integers(2, 9))
        m = _random_symmetric(rng, n)
        definite = leading_minors_positive(m)
        indefinite += not definite
        for test in (diagonally_dominant, scaled_diagonally_dominant):
            if test(m):
                accepted += 1
                assert definite, m
            elif definite:
                refused_definite += 1
        only_scaled += scaled_diagonally_dominant(m) and not diagonally_dominant(m)
        assert is_positive_definite(m) == definite
    assert accepted > 50 and indefinite > 50 and refused_definite > 10 and only_scaled > 10  # both sides covered


def test_a_given_scaling_decides_exactly() -> None:
    m = [[Fraction(1), Fraction(3)], [Fraction(3), Fraction(10)]]
    assert scaled_diagonally_dominant(m, [31, 10])  # 1*31 > 3*10 and 10*10 > 3*31
    assert not scaled_diagonally_dominant(m, [5, 1])  # 10*1 > 3*5 fails
    assert not scaled_diagonally_dominant(m, [1, 1])  # plain dominance fails


# -- sos_gas through the fallback, and verify --------------------------------------------------------

@pytest.fixture(scope="module")
def fallback_doc(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, dict]:
    """A ring of 4 oscillators (8 states): its dense degree-4 program is beyond BLOCK_COST_LIMIT and,
    with the clique forms taken away (CLIQUE_FORMS empty, as on a network without a sparse
    structure), sos_gas certifies only through the SDSOS fallback."""
    from lyapcheck import api
    from lyapcheck.models.classes import lyapunov
    from lyapcheck.models.engines import store

    path = tmp_path_factory.mktemp("cones") / "ring8.toml"
    path.write_text(networks.ring(4))
    with pytest.MonkeyPatch.context() as mp, store.disabled():
        mp.setattr(lyapunov, "CLIQUE_FORMS", ())
        found = api.certify(model=path, classes="sos_gas")
    return path, found.document


def test_sos_gas_falls_through_to_sdsos_where_the_semidefinite_forms_are_too_large(
        fallback_doc: tuple[Path, dict]) -> None:
    _, doc = fallback_doc
    condition = doc["conditions"]["sos_gas"]
    assert condition["status"] == "certified" and condition["property"] == "GAS", condition["summary"]
    cert = condition["certificate"]
    assert cert["kind"] == "lyapunov" and cert["cone"] == "sdd" and cert["degree"] == 4
    assert condition["cone"] == "sdd"  # the method, beside the figures
    assert "SDSOS, scaled diagonally dominant Gram matrices" in condition["summary"]


def test_a_semidefinite_certificate_names_no_cone(tmp_path: Path) -> None:
    from lyapcheck import api
    from lyapcheck.models.engines import store

    path = tmp_path / "ring4.toml"
    path.write_text(networks.ring(2))
    with store.disabled():
        condition = api.certify(model=path, classes="sos_gas").document["conditions"]["sos_gas"]
    assert condition["status"] == "certified" and "cone" not in condition["certificate"]
    assert "cone" not in condition and "SDSOS" not in condition["summary"]


def test_verify_rechecks_a_cone_certificate_and_refuses_a_tampered_one(fallback_doc: tuple[Path, dict],
                                                                     tmp_path: Path) -> None:
    from click.testing import CliRunner

    from lyapcheck.cli import app

    app._register_commands()
    _, doc = fallback_doc
    good = tmp_path / "good.json"
    good.write_text(json.dumps(doc))
    result = CliRunner().invoke(app.cli, ["verify", str(good)])
    assert result.exit_code == 0, result.output
    changed = json.loads(json.dumps(doc))
    sigma = changed["conditions"]["sos_gas"]["certificate"]["gram_sigma"]
    sigma["Q"][0][0] = str(Fraction(sigma["Q"][0][0]) + Fraction(1, 1000))
    bad = tmp_path / "bad.json"
    bad.write_text(json.dumps(changed))
    result = CliRunner().invoke(app.cli, ["verify", str(bad)])
    assert result.exit_code == 1 and "does not hold exactly" in result.output
    renamed = json.loads(json.dumps(doc))
    renamed["conditions"]["sos_gas"]["certificate"]["cone"] = "dd"  # not the condition's, nor its sentence's
    bad.write_text(json.dumps(renamed))
    result = CliRunner().invoke(app.cli, ["verify", str(bad)])
    assert result.exit_code == 1, result.output
    for where in ("condition", "both"):  # the condition's cone alone, and both with the sentence left as it was
        renamed = json.loads(json.dumps(doc))
        renamed["conditions"]["sos_gas"]["cone"] = "dd"
        if where == "both":
            renamed["conditions"]["sos_gas"]["certificate"]["cone"] = "dd"
        bad.write_text(json.dumps(renamed))
        result = CliRunner().invoke(app.cli, ["verify", str(bad)])
        assert result.exit_code == 1, (where, result.output)
        assert where == "both" or "the condition's cone is not the certificate's" in result.output


def test_the_benchmark_knob_is_validated(monkeypatch: pytest.MonkeyPatch) -> None:
    from lyapcheck.errors import InvalidParameter
    from lyapcheck.models.classes import lyapunov

    monkeypatch.setenv(lyapunov.FORCE_CONE_ENV, "SDD")
    assert lyapunov.forced_cone() == "sdd"
    monkeypatch.setenv(lyapunov.FORCE_CONE_ENV, "lp")
    with pytest.raises(InvalidParameter, match="LYAPCHECK_FORCE_CONE.*one of psd, sdd, dd.*'lp'"):
        lyapunov.forced_cone()
    monkeypatch.delenv(lyapunov.FORCE_CONE_ENV)
    assert lyapunov.forced_cone() == "psd"


# -- the order of the forms against the time left (issue 43: a limit falls through to the next method) ----

#: the 4-state platoon's identity size limit for these tests: its dense programs of every degree are beyond
#: it, while its clique forms (CLIQUE_TARGET_LIMIT) at degrees 6 and 8 and its dense SDSOS program at
#: degree 4 (CONE_TARGET_LIMIT) are not: a network where a degree already too large leaves the cones
#: pending while later degrees still have semidefinite forms to solve
SMALL_TARGET_LIMIT = 60


def ordered_run(monkeypatch: pytest.MonkeyPatch, budget: Any) -> tuple[Any, list[tuple[str, int, str]]]:
    """``sos_gas`` on the 4-state platoon with :data:`SMALL_TARGET_LIMIT`, and the forms it tried, in
    order: ``(form, degree, cone)``."""
    from lyapcheck.models.classes import lyapunov
    from lyapcheck.models.engines import store
    from lyapcheck.models.engines.search import Search

    monkeypatch.setattr(lyapunov, "TARGET_LIMIT", SMALL_TARGET_LIMIT)
    calls: list[tuple[str, int, str]] = []
    dense, cliques = lyapunov.search_degree, lyapunov.clique_search

    def spy_dense(field: Any, degree: int, search: Any, param_degree: int = 0, cone: str = "psd") -> Any:
        calls.append(("dense", degree, cone))
        return dense(field, degree, search, param_degree, cone)

    def spy_cliques(field: Any, degree: int, search: Any, cone: str = "psd") -> Any:
        calls.append(("cliques", degree, cone))
        return cliques(field, degree, search, cone)

    monkeypatch.setattr(lyapunov, "search_degree", spy_dense)
    monkeypatch.setattr(lyapunov, "clique_search", spy_cliques)
    from lyapcheck.models.language.modelfile import parse_model
    from lyapcheck.models.loop.field import apply_scaling, choose_scaling, clear, state_field
    from lyapcheck.models.surfaces.certify import shifted_field

    model = parse_model(networks.platoon(2))
    cleared = clear(shifted_field(model), [])
    scaled = apply_scaling(cleared, choose_scaling(cleared, model.domain))
    with store.disabled():
        result = lyapunov.run(scaled, "sos_gas", lyapunov.SOS_GAS_DEGREES, Search(state_field(scaled).ring, budget))
    return result, calls


def test_with_time_to_spare_the_cones_come_after_every_semidefinite_form(monkeypatch: pytest.MonkeyPatch) -> None:
    from lyapcheck.models.engines.search import Budget

    result, calls = ordered_run(monkeypatch, Budget(1e6, "test"))
    assert result.status == "certified", result.summary
    assert result.certificate["cone"] == "sdd" and result.certificate["degree"] == 4
    first_cone = next(i for i, c in enumerate(calls) if c[2] != "psd")
    assert ("cliques", 6, "psd") in calls[:first_cone] and ("cliques", 8, "psd") in calls[:first_cone], calls


def test_a_semidefinite_form_that_does_not_fit_the_time_left_goes_after_the_cheaper_cone(
        monkeypatch: pytest.MonkeyPatch) -> None:
    """A budget of 1 s on a clock that stands still (so that it never runs out as a time limit): degree 6's clique form, estimated from its program's size, does not fit beside the cones'
    degree 4, so the cones go first and certify; no semidefinite form of degree 6 or 8 is solved."""
    from lyapcheck.models.engines import search as search_module
    from lyapcheck.models.engines.search import Budget

    monkeypatch.setattr(search_module, "_now", lambda: 0.0)
    result, calls = ordered_run(monkeypatch, Budget(1.0, "test"))
    assert result.status == "certified", result.summary
    assert result.certificate["cone"] == "sdd" and result.certificate["degree"] == 4 and result.numbers["cone"] == "sdd"
    assert calls[-1] == ("dense", 4, "sdd") and not any(c[1] >= 6 for c in calls), calls


def test_the_order_rule_falls_back_to_the_semidefinite_forms_when_the_cones_find_nothing(
        monkeypatch: pytest.MonkeyPatch) -> None:
    """With the cones first and finding nothing (their budget of solves taken away), the semidefinite
    forms of the later degrees still run, and the detail says the cones went first and why."""
    from lyapcheck.models.classes import lyapunov
    from lyapcheck.models.engines import search as search_module
    from lyapcheck.models.engines.search import Budget

    monkeypatch.setattr(search_module, "_now", lambda: 0.0)
    monkeypatch.setattr(lyapunov, "CONE_FALLBACK_SOLVES", 0)
    result, calls = ordered_run(monkeypatch, Budget(1.0, "test"))
    assert result.status == "not_certified", result.summary
    assert ("dense", 4, "sdd") in calls and ("cliques", 6, "psd") in calls
    assert calls.index(("dense", 4, "sdd")) < calls.index(("cliques", 6, "psd")), calls
    detail = " ".join(result.numbers["detail"])
    assert "the cheaper cones of degree 4 were tried before the semidefinite forms of degree 6" in detail
    assert "CONE_FALLBACK_SOLVES" in detail


def test_a_class_out_of_time_stops_with_the_budgets_words(monkeypatch: pytest.MonkeyPatch) -> None:
    """A clock that advances one second per reading and a budget of 12 s: the search stops part-way
    (in a solve's preparation, a rounding or the cones) and says so in the time limit's words, never
    certified on a search cut short."""
    from lyapcheck.models.engines import search as search_module
    from lyapcheck.models.engines.search import Budget

    ticks = iter(range(10**6))
    monkeypatch.setattr(search_module, "_now", lambda: float(next(ticks)))
    result, calls = ordered_run(monkeypatch, Budget(12.0, "lyapcheck.tolerances.MODEL_CLASS_TIME_LIMIT_S"))
    assert result.status in ("inconclusive", "not_certified"), result.summary
    assert calls  # it stopped part-way, not before its first form
    words = " ".join([result.summary, *result.numbers.get("detail", [])])
    assert "time limit of 12 s reached (a safety net: lyapcheck.tolerances.MODEL_CLASS_TIME_LIMIT_S)" in words


def test_the_exact_rounding_checks_the_budget_between_its_steps() -> None:
    """A solve's rounding run on a budget already spent raises the budget's words instead of finishing;
    with time left the same rounding gives the exact point the check then judges."""
    from lyapcheck.models.classes import lyapunov
    from lyapcheck.models.engines.search import Budget, BudgetExhausted, Search

    field = scaled_field(networks.platoon(2))
    structure = lyapunov.lyapunov_structure(field, 4, lyapunov.symmetry(field))
    assert structure is not None
    values = lyapunov.lyapunov_values(field, structure, Fraction(0))
    search = Search(field.ring, Budget(60.0, "test"))
    solution = search.solve(structure, values)
    assert search.exact(structure, solution, values) is not None
    spent = Search(field.ring, Budget(0.0, "SOME_LIMIT"))
    with pytest.raises(BudgetExhausted, match=r"time limit of 0 s reached \(a safety net: SOME_LIMIT\)"):
        spent.exact(structure, solution, values)


def test_the_order_reads_the_estimates_of_the_work_done_never_the_clock(monkeypatch: pytest.MonkeyPatch) -> None:
    """``fits`` compares estimates with the budget less the estimates recorded so far; a clock that makes
    the machine look thousands of times slower changes nothing (issue 40: work decides, the clock guards)."""
    from lyapcheck.models.engines import search as search_module
    from lyapcheck.models.engines.search import Budget

    budget = Budget(60.0, "test")
    assert budget.fits(30.0, 30.0) and not budget.fits(30.0, 30.5)
    budget.record(20.0)
    assert budget.fits(20.0, 20.0) and not budget.fits(20.0, 20.5)
    ticks = iter(range(0, 10**9, 1000))
    monkeypatch.setattr(search_module, "_now", lambda: float(next(ticks)))
    slow = Budget(60.0, "test")
    slow.record(20.0)
    assert slow.fits(20.0, 20.0) and not slow.fits(20.0, 20.5)
