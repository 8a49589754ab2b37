"""A model class's time limit, reached in real runs (issue 28, part 4: "Time limits are real").

``certify --model`` gives every class :data:`~lyapcheck.tolerances.MODEL_CLASS_TIME_LIMIT_S`
(``time_limit_s`` of :func:`~lyapcheck.models.surfaces.certify.certify_model`) in two layers:

* the cooperative :class:`~lyapcheck.models.engines.search.Budget`: every solve gets at most the time left
  (Clarabel's own time limit, status ``user_limit``), and the next solve past the limit raises
  :class:`~lyapcheck.models.engines.search.BudgetExhausted`; the class is ``inconclusive`` naming the limit;
* the hard stop of :func:`lyapcheck.models.surfaces.certify._guarded`, a SIGALRM at ``limit * 1.5 + 5`` s
  (:func:`lyapcheck.paper.certification.time_limit`), for work between solves that never consults the
  budget (compiling a program, an exact check, the roa class's simulations).

tests/test_model_classes.py covers a limit already reached before the first solve (0) and one
reached inside roa's iteration of many small solves. These tests take models where the limit
falls inside one long solve (tests/data/time-limit-cubic-6.toml: sos_gas's degree-4 solve, 1.7 s
idle, 3.3 s with the other core busy), inside the roa class's simulation (the hard stop,
tests/data/time-limit-fast-cycle.toml, 48 s of simulation unbounded), and inside the decay-rate
search that follows a proof (tests/data/time-limit-quartic-pairs.toml).

The limit is a safety net (issue 40, item 9): these tests check how it stops a class (Clarabel's
own limit cutting the solve under way, the hard stop's alarm, the reason naming the limit), never
how many seconds a stop took, which a loaded machine can stretch; ``seconds >= limit`` (a class is
not stopped before its limit) is the only figure asserted. How soon after its limit a class stops
is measured in benchmarks/bench_quick_paths.py.
"""

from __future__ import annotations

import json
import signal
import time
from dataclasses import dataclass
from typing import Any

import pytest
from click.testing import CliRunner

from lyapcheck import tolerances
from lyapcheck.models.surfaces.certify import certify_model
from lyapcheck.models.language.modelfile import Model, load_model
from tests.conftest import ROOT

DATA = ROOT / "tests" / "data"
SLOW_SOLVE = DATA / "time-limit-cubic-6.toml"
QUARTIC_PAIRS = DATA / "time-limit-quartic-pairs.toml"
FAST_CYCLE = DATA / "time-limit-fast-cycle.toml"
LIMIT_NAME = "lyapcheck.tolerances.MODEL_CLASS_TIME_LIMIT_S"


def hard_stop(limit: float) -> float:
    """The hard stop of :func:`lyapcheck.models.surfaces.certify._guarded` for a class limit of ``limit``."""
    return limit * 1.5 + 5


@dataclass(frozen=True)
class SlowSolve:
    """The slow model, its programs compiled, and its degree-4 solve measured in full."""

    model: Model
    program: str  # the degree-4 program's key
    solve_s: float  # one whole degree-4 solve, wall time
    iterations: int  # ... and its interior-point iterations

    @property
    def limit(self) -> float:
        """A class limit a third of the way into the degree-4 solve (which starts a few ms into
        sos_gas: linearization, quadratic and sos_gas's degree 2 take milliseconds)."""
        return round(self.solve_s / 3, 2)


@pytest.fixture(scope="module")
def slow_solve() -> SlowSolve:
    """sos_gas on the slow model with the default limit: not_certified after its degree-4 solve.
    This also compiles its programs (cached), so the runs below spend their time solving."""
    model = load_model(SLOW_SOLVE)
    full = certify_model(model, classes=("sos_gas",))
    gas = full.results["sos_gas"]
    assert gas.status == "not_certified", gas.summary
    assert "degree 4: the solver proved the program infeasible" in " ".join(gas.numbers["detail"])
    solves = gas.solver["solves"]
    # degree 2, degree 4; 6 and 8 are above the dense form's size limits, so the clique form is tried
    # there (issue 43): its solves come after the degree-4 one, which is the slow one cut below
    assert len(solves) >= 2 and "V a sum over" in " ".join(gas.numbers["detail"])
    last = solves[1]
    assert last["status"] == "optimal"
    return SlowSolve(model, last["program"], float(last["wall_seconds"]), int(last["iterations"]))


def assert_cut_in_the_solve(result: dict[str, Any], slow: SlowSolve) -> None:
    """sos_gas (its JSON form): inconclusive, naming the limit, its degree-4 solve cut short."""
    assert result["status"] == "inconclusive", result["summary"]
    detail = " ".join(result["detail"])  # the summary says it in words; the limit's name is in the detail
    assert LIMIT_NAME in detail and f"time limit of {slow.limit:g} s reached" in detail
    assert f"the time limit of {slow.limit:g} s was reached" in result["summary"]
    cut = result["solver"]["solves"][-1]
    assert cut["program"] == slow.program
    # the degree-4 solve was stopped by the budget's time limit (Clarabel's), not run to its end;
    # user_limit, or AlmostSolved (optimal_inaccurate) when the point then met the looser tolerances
    assert cut["iterations"] < slow.iterations, (cut, slow)
    assert cut["status"] in ("user_limit", "optimal_inaccurate"), cut
    # ... and not by the hard stop's alarm: the cooperative budget ended the class
    assert "hard stop" not in detail and "ran past its time limit" not in result["summary"]


def assert_stopped_by_the_budget(seconds: float, slow: SlowSolve) -> None:
    """The class ran up to its limit (never stopped before it) and was stopped by its budget, inside
    the solve under way (:func:`assert_cut_in_the_solve`): it waited neither for the solve's end nor
    for the hard stop. How long after the limit it stopped depends on the machine's load and is
    measured in benchmarks/bench_quick_paths.py, not asserted."""
    assert seconds >= slow.limit, (seconds, slow)


@pytest.mark.slow
def test_a_limit_reached_inside_a_solve_stops_the_class_and_the_others_still_run(slow_solve: SlowSolve) -> None:
    """The class limit falls a third of the way into sos_gas's one slow solve: Clarabel stops there
    (the budget hands it the time left), sos_gas is inconclusive naming the limit, within the limit
    plus one solve; linearization and quadratic before it, and candidate after it, still decide."""
    limit = slow_solve.limit
    found = certify_model(slow_solve.model, classes=("linearization", "quadratic", "sos_gas", "candidate"),
                          candidate="x1**2", time_limit_s=limit)
    results = found.results
    assert_cut_in_the_solve(results["sos_gas"].to_json(), slow_solve)
    assert_stopped_by_the_budget(found.seconds["sos_gas"], slow_solve)
    assert results["linearization"].status == "certified"  # exact, no search
    assert results["quadratic"].status == "not_certified"  # one solve of milliseconds, inside the limit
    # after the stopped class, a fresh budget: the user's V = x1**2 is not positive definite
    assert results["candidate"].status == "not_certified"
    assert "positive definite" in results["candidate"].summary
    # no class needed the hard stop: every one ended on its own or by its budget
    assert not any("hard stop" in " ".join(r.numbers.get("detail", [])) for r in results.values())


@pytest.mark.slow
def test_the_limit_through_the_command_line(slow_solve: SlowSolve, monkeypatch: pytest.MonkeyPatch) -> None:
    """``certify --model`` has no time-limit flag: it runs with MODEL_CLASS_TIME_LIMIT_S, read when
    the command runs (here lowered in this process) and named in the JSON."""
    from lyapcheck.cli import app
    from lyapcheck.sos import sdp

    app._register_commands()
    monkeypatch.setattr(tolerances, "MODEL_CLASS_TIME_LIMIT_S", slow_solve.limit)
    monkeypatch.setattr(sdp, "LEAN_LAPACK_IMPORT", sdp.LEAN_LAPACK_IMPORT)  # the command sets it for its process
    start = time.perf_counter()
    done = CliRunner().invoke(app.cli, ["certify", "--model", str(SLOW_SOLVE), "--classes",
                                        "linearization,quadratic,sos_gas", "--json"], catch_exceptions=False)
    seconds = time.perf_counter() - start
    assert done.exit_code == 0, done.output  # linearization certified: the verdict is certified_local
    doc = json.loads(done.stdout)
    assert doc["verdict"] == "certified_local"
    assert doc["conditions"]["linearization"]["status"] == "certified"
    assert doc["conditions"]["quadratic"]["status"] == "not_certified"
    assert_cut_in_the_solve(doc["conditions"]["sos_gas"], slow_solve)
    # the command's whole run holds sos_gas's, which lasted its limit (the JSON has no per-class
    # seconds); that its solve was cut by the budget, not waited for, assert_cut_in_the_solve showed
    assert seconds >= slow_solve.limit, (seconds, slow_solve)


@pytest.mark.slow
def test_the_hard_stop_ends_the_roa_simulation() -> None:
    """roa simulates its starts before its search, without consulting its budget: on this model the
    simulation alone takes tens of seconds, and it is the hard stop (limit * 1.5 + 5 s) that ends
    the class, inconclusive naming the limit; the alarm is cleared and the handler restored after."""
    model = load_model(FAST_CYCLE)
    limit = 0.1
    before = signal.getsignal(signal.SIGALRM)
    cpu = time.process_time()
    found = certify_model(model, classes=("linearization", "roa"), time_limit_s=limit)
    cpu = time.process_time() - cpu
    assert found.results["linearization"].status == "certified"
    roa = found.results["roa"]
    assert roa.status == "inconclusive", roa.summary
    detail = " ".join(roa.numbers["detail"])
    assert LIMIT_NAME in detail and "hard stop" in detail
    assert f"time limit of {hard_stop(limit):g} s reached" in detail
    assert f"stopped at {hard_stop(limit):g} s" in roa.summary and "--time-limit" in roa.summary
    # not before the hard stop; and the alarm interrupted the simulation: this process's own CPU
    # time (which a busy machine does not stretch: it counts only the work done) stayed far below
    # the simulation's tens of seconds. How soon after the alarm the class ended is a wall time,
    # measured in benchmarks/bench_quick_paths.py
    assert found.seconds["roa"] >= hard_stop(limit), found.seconds
    assert cpu < 3 * hard_stop(limit), cpu
    assert signal.getitimer(signal.ITIMER_REAL) == (0.0, 0.0)
    assert signal.getsignal(signal.SIGALRM) is before


def test_a_proof_found_before_the_limit_is_kept(monkeypatch: pytest.MonkeyPatch) -> None:
    """sos_gas proves GAS at degree 4 (mu = 0), then searches the best decay rate with more solves;
    a limit reached in that search must keep the proof (certified, with the best rate proved so
    far), not report the class inconclusive. The limit is made to fall there deterministically: the
    budget is exhausted at the first solve after the degree-4 proof (a wall-time limit would depend
    on this machine's speed)."""
    from lyapcheck.models.engines import search as search_module

    model = load_model(QUARTIC_PAIRS)
    full = certify_model(model, classes=("sos_gas",))
    gas = full.results["sos_gas"]
    assert gas.status == "certified" and gas.numbers["degree"] == 4, gas.summary
    solves = gas.solver["solves"]
    proof = next(k for k, entry in enumerate(solves) if entry.get("margin", -1) > 0 and k > 0)
    assert len(solves) > proof + 1, "the rate search must follow the proof"
    calls = {"n": 0}
    original = search_module.Search.solve

    def limited(self: Any, structure: Any, values: Any) -> Any:
        calls["n"] += 1
        if calls["n"] > proof + 1:
            raise search_module.BudgetExhausted("time limit of 1 s reached (test)")
        return original(self, structure, values)

    monkeypatch.setattr(search_module.Search, "solve", limited)
    cut = certify_model(model, classes=("sos_gas",)).results["sos_gas"]
    assert cut.status == "certified", cut.summary
    assert cut.numbers["degree"] == 4
    assert cut.numbers["decay_rate_V_per_s"] <= gas.numbers["decay_rate_V_per_s"]


def test_a_region_search_cut_by_the_time_limit_is_inconclusive(monkeypatch: pytest.MonkeyPatch, tmp_path: Any) -> None:
    """A loop with functions whose candidate is positive but not strictly decreasing goes on to a level
    search; when the class's time runs out inside it (here: the level search spends the budget), the
    answer is ``inconclusive`` naming the limit, not ``not_certified`` (a planar quadrotor's candidate
    came out ``not_certified`` with the reason "time limit of 60 s reached")."""
    from lyapcheck import api
    from lyapcheck.models.classes import regions
    from lyapcheck.models.engines.search import BudgetExhausted, Search
    from tests.recast_loops import PENDULUM

    def out_of_time(loop: Any, V: Any, search: Search, label: str, start: Any = None, plan: Any = None) -> Any:
        search.budget.start -= search.budget.seconds + 1.0  # the whole limit spent inside this search
        raise BudgetExhausted(search.budget.reached())

    monkeypatch.setattr(regions, "certify_region", out_of_time)
    path = tmp_path / "pendulum.toml"
    path.write_text(PENDULUM)
    found = api.certify(model=path, classes="candidate", candidate="1 - cos(theta) + omega**2/2")
    cand = found.conditions["candidate"]
    assert cand.status == "inconclusive", cand.summary
    assert "time limit" in cand.summary and "--time-limit" in cand.summary
