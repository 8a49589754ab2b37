"""Global reach of the saturated loop (class saturated_loop, step 3): the exact conditions, their
re-check, and the simulator (an independent implementation of the ODS law with step-out
saturation) entering and never leaving the set the proof names."""

from __future__ import annotations

from dataclasses import replace
from fractions import Fraction

import numpy as np
import pytest

from lyapcheck.paper.certification import build_system
from lyapcheck.paper.conditions.saturated import OMEGA_ROUNDING, global_reach, verify_reach
from lyapcheck.paper.simulation.scenarios import paper_problem
from symbolic._generated import unsaturated_strip_sq


def _reach(problem):  # type: ignore[no-untyped-def]
    system = build_system(problem, "derived")
    g, sw = problem.gains, problem.swimmer
    y_sat_sq = unsaturated_strip_sq(g.alpha_d, g.delta_los, sw.e11_hat, problem.actuation.step_out() * (1 - OMEGA_ROUNDING))
    return system, global_reach(system, k_d=g.k_d, y_sat_sq=y_sat_sq, time_scale=-system.A[0][0])


def test_reach_is_proved_at_the_papers_gains_and_rechecks() -> None:
    problem = paper_problem()
    system, reach = _reach(problem)
    assert reach is not None
    S1, Yq, gamma = (Fraction(reach[k]) for k in ("S_1", "Y_q", "gamma"))
    assert gamma > 0  # the swimmer out-pulls disturbance and integrator by 0.73 mm/s
    assert Fraction(reach["S_star_sq"]) < S1 * S1 < Fraction(reach["S_star_sq"]) * Fraction(101, 100)
    assert S1 < system.speed / (2 * problem.gains.k_d) / 9  # ten times below the crude wind-up box 3.33 m
    kwargs = dict(k_d=problem.gains.k_d, alpha_d=problem.gains.alpha_d, e11_hat=problem.swimmer.e11_hat,
                  omega_so=problem.actuation.step_out())
    assert verify_reach(system, reach, **kwargs)[0]
    for key, factor in (("S_1", Fraction(1, 2)), ("Y_q", Fraction(2)), ("gamma", Fraction(2))):
        forged = {**reach, key: str(Fraction(reach[key]) * factor)}
        assert not verify_reach(system, forged, **kwargs)[0], key


def test_the_windup_bound_is_the_maximum_of_forcing_over_damping() -> None:
    """S* = max_y U Delta |y| / (k_d (y^2 + Delta^2) + sigma0 U Delta), on a fine grid."""
    problem = paper_problem()
    g = problem.gains
    U, delta, sigma0, kd = (float(x) for x in (g.los_speed, g.delta_los, g.sigma0, g.k_d))
    y = np.geomspace(1e-6, 10, 200_001)
    ratio = U * delta * y / (kd * (y**2 + delta**2) + sigma0 * U * delta)
    s_star = float(np.sqrt(float(Fraction(_reach(problem)[1]["S_star_sq"]))))
    assert ratio.max() <= s_star * (1 + 1e-12)
    assert ratio.max() >= s_star * (1 - 1e-6)


def test_reach_fails_when_the_disturbance_outswims_the_swimmer() -> None:
    problem = paper_problem()
    strong = replace(problem, d_max=Fraction(2, 1000))  # 2 mm/s > e11 Omega_SO = 1.64 mm/s
    _, reach = _reach(strong)
    assert reach is not None and Fraction(reach["gamma"]) < 0


@pytest.mark.slow
def test_simulated_real_loop_enters_the_reach_set_and_stays() -> None:
    """From far starts with a large wound-up integrator and d = d* across the path, the
    simulator's saturated loop enters {|y| <= Y_q, |s| <= 1.05 S*} and never leaves it."""
    from lyapcheck.paper.simulation.disturbances import Constant
    from lyapcheck.paper.simulation.model import LoopParams
    from lyapcheck.paper.simulation.runner import simulate

    problem = paper_problem()
    _, reach = _reach(problem)
    assert reach is not None
    s_check = 1.05 * float(np.sqrt(float(Fraction(reach["S_star_sq"]))))
    y_q = float(Fraction(reach["Y_q"]))
    starts = [(0.3, 100.0), (-0.3, -100.0), (0.0, 1000.0)]
    result = simulate(LoopParams.from_problem(problem, n=len(starts)), p0=np.array([[0.0, e] for e, _ in starts]),
                      s0=np.array([s for _, s in starts]),
                      disturbance=Constant(np.array([0.0, float(problem.disturbance_bound())])),
                      horizon=800.0, tail=10.0, record=list(range(len(starts))), record_dt=1.0)
    assert result.trajectories is not None
    sigma0 = float(problem.gains.sigma0)
    for trajectory in result.trajectories:
        inside = (np.abs(trajectory.eps + sigma0 * trajectory.s) <= y_q) & (np.abs(trajectory.s) <= s_check)
        assert inside.any(), "never entered"
        assert inside[int(np.argmax(inside)):].all(), "left the set after entering it"


def test_certify_states_the_real_loops_bound_and_verify_rechecks_it(tmp_path) -> None:  # type: ignore[no-untyped-def]
    import json

    from lyapcheck import certify, verify
    from tests.conftest import PAPER_TOML

    result = certify(PAPER_TOML, classes="saturated_loop,sos_bound")
    doc = result.to_json()
    sat, bound = doc["conditions"]["saturated_loop"], doc["conditions"]["sos_bound"]
    assert sat["global_reach"] == "proved" and sat["real_loop_limsup_eps_m"] == bound["eps_bound_m"]
    assert verify(doc).valid
    forged = json.loads(json.dumps(doc))
    forged["conditions"]["saturated_loop"]["certificate"]["reach"]["gamma"] = "1"  # a margin that does not follow
    assert not verify(forged).valid
    smaller = json.loads(json.dumps(doc))
    smaller["conditions"]["saturated_loop"]["real_loop_limsup_eps_m"] = bound["eps_bound_m"] / 2
    assert not verify(smaller).valid
