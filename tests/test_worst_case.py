"""Worst-case disturbance search and the disturbance kinds it adds (bang-bang, square wave,
polynomial feedback, stacked batches).

The search runs once, on the paper's gains with a shortened horizon (30 s, tail 10 s) and a
budget that leaves room for the screening round and the final re-simulation only, so that the
whole module stays fast; the checks are relations (against the constant disturbance from the
same state, against a re-simulation, against the bound), not stored numbers.
"""

from __future__ import annotations

import json
import math
from dataclasses import replace
from fractions import Fraction

import numpy as np
import pytest

from lyapcheck.errors import InvalidParameter
from lyapcheck.paper.params import Problem
from lyapcheck.paper.simulation.disturbances import (
    Adversarial, BangBang, Constant, Feedback, Sinusoid, SquareWave, Stacked, from_description, stack_rows,
)
from lyapcheck.paper.simulation.model import LoopParams
from lyapcheck.paper.simulation.runner import simulate
from lyapcheck.paper.simulation.scenarios import Scenario, paper_problem, preset
from lyapcheck.paper.simulation.worst_case import (
    FAMILIES, WorstCaseResult, search_worst_case, simulate_disturbance, storage_switching,
)
from lyapcheck.tolerances import SIM_REL_TOL

D_STAR = 0.088e-3
DELTA = 0.75e-3
E_PERP = np.array([0.0, 1.0])  # theta_r = 0


@pytest.fixture(scope="module")
def short_scenario() -> Scenario:
    """paper-ilos with a 30 s horizon (the tail still 10 s)."""
    return replace(preset("paper-ilos"), horizon=30.0, tail=10.0)


@pytest.fixture(scope="module")
def result(short_scenario: Scenario) -> WorstCaseResult:
    return search_worst_case(short_scenario, budget_s=1.0, seed=0)


# -- the search ------------------------------------------------------------------------------------
def test_search_is_at_least_the_constant_disturbance_from_the_same_state(
        short_scenario: Scenario, result: WorstCaseResult) -> None:
    """The presets' constant sinking velocity is one of the candidates: the worst case found from
    each initial state is at least what it gives from that state."""
    sinking = Constant(np.array([0.0, -D_STAR]))
    constant = {start: simulate_disturbance(short_scenario, sinking, start=start).measurements.sup_abs_eps_tail_m[0]
                for start in ("preset", "origin")}
    for start, value in constant.items():
        assert result.per_start[start].sup_abs_eps_tail_m >= value * (1 - SIM_REL_TOL)
    assert result.sup_abs_eps_tail_m == max(f.sup_abs_eps_tail_m for f in result.per_start.values())
    # from rest, bang-bang forcing near the loop's resonance beats the constant by far (from the
    # preset's state, 30 s do not suffice for the transient to die out: it dominates there)
    origin = result.per_start["origin"]
    assert origin.disturbance["kind"] != "constant"
    assert origin.sup_abs_eps_tail_m > 2 * constant["origin"]


def test_reported_disturbance_reproduces_its_figure(short_scenario: Scenario, result: WorstCaseResult) -> None:
    """Rebuilt from its JSON description alone and simulated again, the worst disturbance gives the
    reported tail sup (same scenario, same rtol: the integrator's own tolerance)."""
    text = json.dumps(result.to_json())
    doc = json.loads(text)
    again = simulate_disturbance(short_scenario, doc["disturbance"], start=doc["initial_state"])
    assert again.measurements.sup_abs_eps_tail_m[0] == pytest.approx(doc["sup_abs_eps_tail_m"], rel=SIM_REL_TOL)
    assert result.build_disturbance().describe() == from_description(doc["disturbance"]).describe()


def test_worst_disturbance_never_exceeds_the_bound(short_scenario: Scenario, result: WorstCaseResult) -> None:
    """|d| <= d* at every recorded instant of the worst trajectory, and a priori for every family's best."""
    res = simulate_disturbance(short_scenario, result.disturbance, start=result.start, record=True)
    assert res.trajectories is not None
    d = res.trajectories[0].d
    assert np.max(np.hypot(d[:, 0], d[:, 1])) <= D_STAR * (1 + 1e-12)
    for finding in result.per_family.values():
        if finding is not None:
            bound = from_description(finding.disturbance).bound()
            assert bound is not None and np.all(bound <= D_STAR * (1 + 1e-12))


def test_result_json_has_the_contract_keys(result: WorstCaseResult) -> None:
    doc = json.loads(json.dumps(result.to_json()))
    assert doc["sup_abs_eps_tail_m"] > 0
    assert doc["disturbance"]["kind"] in ("constant", "sinusoid", "square_wave", "bang_bang", "feedback")
    assert set(doc["per_family"]) == set(FAMILIES)
    assert set(doc["per_start"]) == {"preset", "origin"}
    # every family is either measured or said why not
    assert all((v is None) == (k in doc["skipped"]) for k, v in doc["per_family"].items())
    assert "storage_gradient" in doc["skipped"]  # no certificate was given
    assert doc["candidates_tried"] == sum(r["candidates"] for r in doc["rounds"])
    assert doc["rounds"][-1]["round"] == "final" and doc["rounds"][-1]["rtol"] == doc["rtol"]
    assert doc["per_start"]["origin"]["rtol"] == doc["rtol"]


def test_resonances_are_those_of_the_error_dynamics(result: WorstCaseResult) -> None:
    """Linearised at rest, the ILOS error dynamics have the lightly damped pair ~-0.10 +- 0.86i rad/s."""
    assert result.resonances_rad_s["origin"][0] == pytest.approx(0.861, abs=2e-3)
    assert result.resonances_rad_s["constant_d_max"][0] < result.resonances_rad_s["origin"][0]


def test_bad_inputs_name_the_field(short_scenario: Scenario) -> None:
    with pytest.raises(InvalidParameter, match="'budget_s' parameter"):
        search_worst_case(short_scenario, budget_s=0.0)
    with pytest.raises(InvalidParameter, match="'seed' parameter"):
        search_worst_case(short_scenario, seed=-1)
    no_bound = replace(short_scenario, problem=replace(short_scenario.problem, d_max=None))
    with pytest.raises(InvalidParameter, match="'d_max' parameter"):
        search_worst_case(no_bound)
    with pytest.raises(InvalidParameter, match="'start' parameter"):
        simulate_disturbance(short_scenario, Constant(np.zeros(2)), start="elsewhere")


# -- storage function gradient ------------------------------------------------------------------
def test_storage_switching_is_the_gradient_of_v_along_eps() -> None:
    """The composed polynomial has the sign of dV/d eps (central differences of V itself) for a
    made-up positive definite Gram matrix in the sos_bound basis."""
    from lyapcheck import exact
    from lyapcheck.paper import poly
    from lyapcheck.paper.conditions.sos_bound import Z_V

    rng = np.random.default_rng(3)
    M = rng.normal(size=(len(Z_V), len(Z_V)))
    Q = exact.symmetrize(exact.rational_matrix(M @ M.T + np.eye(len(Z_V))))
    storage = {"Q_V": exact.to_json(Q), "beta": "773/50"}
    sigma0 = Fraction(1, 100)
    exps, coefs = storage_switching(storage, sigma0)
    V = poly.gram_form(Z_V, Q)
    beta = 773 / 50

    def v_of(eps: np.ndarray, s: np.ndarray) -> np.ndarray:
        y, r = (eps + 0.01 * s) / DELTA, 0.01 * s / (DELTA * beta)
        return sum(float(c) * y ** m[0] * r ** m[1] for m, c in V.items())  # type: ignore[return-value]

    eps, s = rng.normal(0, 2e-3, 50), rng.normal(0, 0.2, 50)
    h = 1e-9
    grad = (v_of(eps + h, s) - v_of(eps - h, s)) / (2 * h)
    fb = Feedback(np.asarray(D_STAR), coefs, exps, np.asarray(DELTA), np.asarray(1e-12), np.asarray(0.0))
    sigma = fb.switching_function(eps, s)
    clear = np.abs(grad) > 1e-6 * np.max(np.abs(grad))
    assert np.all(np.sign(sigma[clear]) == np.sign(grad[clear]))
    # proportional, with a positive factor: the ratio is constant
    ratio = sigma[clear] / grad[clear]
    np.testing.assert_allclose(ratio, ratio[0], rtol=1e-5)
    assert ratio[0] > 0


# -- the disturbance kinds ------------------------------------------------------------------------
def test_square_wave_is_the_sign_of_the_sine() -> None:
    om, ph = np.array([0.4, 1.3]), np.array([0.0, 4.0])
    wave = SquareWave(np.asarray(D_STAR), E_PERP, om, ph, 100.0)
    t = np.linspace(0.05, 99.95, 4001)
    for row in range(2):
        w = wave.take(np.full(t.size, row, dtype=np.intp))
        d = w.velocity(t, t, np.zeros(t.size), np.zeros(t.size), np.zeros((t.size, 2)))
        expected = D_STAR * np.sign(np.sin(om[row] * t + ph[row]))
        near_switch = np.abs(np.sin(om[row] * t + ph[row])) < 1e-9
        np.testing.assert_array_equal(d[~near_switch, 1], expected[~near_switch])
        assert np.all(d[:, 0] == 0)


def test_bang_bang_breakpoints_are_its_switching_times() -> None:
    bb = BangBang(np.asarray(D_STAR), E_PERP, np.array([[1.0, 2.5, np.inf], [0.5, 0.7, 3.0]]), np.array([1.0, -1.0]))
    t = np.array([0.0, 0.0])
    np.testing.assert_array_equal(bb.next_breakpoint(t), [1.0, 0.5])
    np.testing.assert_array_equal(bb.next_breakpoint(np.array([1.0, 0.7])), [2.5, 3.0])
    np.testing.assert_array_equal(bb.next_breakpoint(np.array([2.5, 3.0])), [np.inf, np.inf])
    # a switch counts from the instant it occurs (the segment time that lands on it)
    np.testing.assert_array_equal(bb.sign(np.array([0.999, 0.5])), [1.0, 1.0])
    np.testing.assert_array_equal(bb.sign(np.array([1.0, 0.7])), [-1.0, -1.0])
    with pytest.raises(ValueError, match="'switch_times' parameter"):
        BangBang(np.asarray(D_STAR), E_PERP, np.array([2.0, 1.0]), np.asarray(1.0))
    with pytest.raises(ValueError, match="'initial_sign' parameter"):
        BangBang(np.asarray(D_STAR), E_PERP, np.array([1.0]), np.asarray(0.5))


def test_feedback_with_a_linear_switching_function_is_the_adversarial_kind() -> None:
    """Adversarial (quadratic V) is the linear case of Feedback: same velocity at every state."""
    P = np.array([[1.0, 0.02], [0.02, 0.01]])
    layer = 1e-7
    rng = np.random.default_rng(2)
    eps, s = rng.normal(0, 1e-3, 100), rng.normal(0, 0.1, 100)
    adv = Adversarial(np.asarray(D_STAR), P, np.asarray(layer), np.asarray(0.3))
    fb = Feedback(np.asarray(D_STAR), np.array([1.0, P[0, 1] / P[0, 0]]), np.array([[1, 0], [0, 1]]),
                  np.asarray(DELTA), np.asarray(layer), np.asarray(0.3))
    args = (np.zeros(100), np.zeros(100), eps, s, np.zeros((100, 2)))
    np.testing.assert_allclose(fb.velocity(*args), adv.velocity(*args), rtol=1e-12, atol=1e-20)


def test_stacked_rows_behave_as_the_plain_kinds(paper_problem: Problem) -> None:
    """One batch of mixed kinds gives, row by row, what each kind gives alone."""
    rows = [
        Constant(np.array([0.0, -D_STAR])),
        SquareWave(np.asarray(D_STAR), E_PERP, np.asarray(0.9), np.asarray(0.3), 20.0),
        Sinusoid(np.zeros(2), D_STAR * E_PERP, np.asarray(0.7), np.asarray(0.0)),
        Feedback(np.asarray(D_STAR), np.array([1.0, 1e-3]), np.array([[1, 0], [0, 0]]), np.asarray(DELTA),
                 np.asarray(DELTA * 1e-3), np.asarray(0.0)),
        SquareWave(np.asarray(D_STAR), E_PERP, np.asarray(0.4), np.asarray(1.0), 20.0),
    ]
    batch = stack_rows(rows)
    assert isinstance(batch, Stacked) and batch.size == len(rows) and batch.n_switches == 2
    params = LoopParams.from_problem(paper_problem, n=len(rows))
    together = simulate(params, p0=(0.0, -0.002), disturbance=batch, horizon=20.0, tail=5.0)
    for i, d in enumerate(rows):
        assert batch.row(i).describe() == d.describe()
        alone = simulate(LoopParams.from_problem(paper_problem), p0=(0.0, -0.002), disturbance=d,
                         horizon=20.0, tail=5.0)
        assert alone.measurements.sup_abs_eps_tail_m[0] == pytest.approx(
            together.measurements.sup_abs_eps_tail_m[i], rel=SIM_REL_TOL)


@pytest.mark.parametrize("dist", [
    Constant(np.array([1e-5, -D_STAR])),
    Sinusoid(np.array([0.0, 1e-6]), D_STAR * E_PERP, np.asarray(0.7), np.asarray(0.2)),
    SquareWave(np.asarray(D_STAR), np.array([0.6, 0.8]), np.asarray(0.4), np.asarray(2.0), 50.0),
    BangBang(np.asarray(D_STAR), E_PERP, np.array([3.0, 7.5, 9.0]), np.asarray(-1.0), note="n"),
    Feedback(np.asarray(D_STAR), np.array([1.0, 0.5, 0.25]), np.array([[1, 0], [0, 1], [3, 0]]),
             np.asarray(DELTA), np.asarray(1e-7), np.asarray(0.1)),
])
def test_descriptions_rebuild_the_same_disturbance(dist: object) -> None:
    desc = json.loads(json.dumps(dist.describe()))  # type: ignore[attr-defined]
    again = from_description(desc)
    assert again.describe() == dist.describe()  # type: ignore[attr-defined]
    t = np.linspace(0.0, 20.0, 41)
    eps, s = np.full(41, 2e-4), np.full(41, 0.01)
    u = np.zeros((41, 2))
    np.testing.assert_array_equal(again.velocity(t, t, eps, s, u), dist.velocity(t, t, eps, s, u))  # type: ignore[attr-defined]


def test_unknown_description_names_the_kind() -> None:
    with pytest.raises(ValueError, match="'description' parameter must have a 'kind'"):
        from_description({"kind": "weight"})
    with pytest.raises(ValueError, match="'angular_frequency_rad_s'"):
        from_description({"kind": "square_wave", "bound_m_s": 1.0, "direction": [0, 1]})


def test_zero_bound_searches_nothing_but_zero() -> None:
    problem = paper_problem(**{"disturbance.d_max": "0 mm/s"})
    scenario = Scenario(name="rest", problem=problem, horizon=10.0, tail=5.0, p0=(0.0, 0.0))
    res = search_worst_case(scenario, budget_s=1.0)
    assert res.sup_abs_eps_tail_m == 0.0
    assert res.disturbance["kind"] == "constant" and res.per_family["square_wave"] is None
    assert math.isfinite(res.wall_time_s)
