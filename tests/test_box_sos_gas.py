"""sos_gas over a box: one polynomial V proves GAS for every gain set of the box."""

from __future__ import annotations

import copy
from fractions import Fraction
from typing import Any

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from lyapcheck import exact
from lyapcheck.paper import poly
from lyapcheck.paper.boxes.sos_gas import certify_gas_box, verify_gas_box
from lyapcheck.paper.boxes.box import corner_problems, parse_box, scaled_hull
from lyapcheck.paper.certification import build_system
from lyapcheck.paper.conditions import sos
from lyapcheck.paper.conditions.sos import ScaledDynamics, scaled_dynamics
from lyapcheck.paper.params import Problem, problem_from_sources
from tests.conftest import PAPER_TOML

#: the paper's gains +-2 %
NEAR_PAPER = ["alpha_d=588..612", "k_d=0.147..0.153"]
#: alpha_d +-10 %, k_d from 2/3 to 4/3 of the paper's
WIDE = ["alpha_d=540..660", "k_d=0.1..0.2"]
#: sigma0 over a factor 4: b spans a factor 4 and no common V of degree <= 6 is found
NO_COMMON_V = ["sigma0=0.005..0.02"]


@pytest.fixture(scope="module")
def problem() -> Problem:
    return problem_from_sources(PAPER_TOML, {})


@pytest.fixture(scope="module")
def near(problem: Problem) -> dict[str, Any]:
    return certify_gas_box(problem, parse_box(NEAR_PAPER))


@pytest.fixture(scope="module")
def wide(problem: Problem) -> dict[str, Any]:
    return certify_gas_box(problem, parse_box(WIDE))


def test_the_point_class_certifies_the_papers_gain_set(problem: Problem) -> None:
    result = sos.run(build_system(problem, "derived"))
    assert result.status == "certified", result.summary


@pytest.mark.parametrize("spec", [NEAR_PAPER, WIDE])
def test_boxes_around_the_paper_are_certified_and_verify(problem: Problem, near: dict[str, Any],
                                                         wide: dict[str, Any], spec: list[str]) -> None:
    result = near if spec is NEAR_PAPER else wide
    box = parse_box(spec)
    assert result["status"] == "certified", result["summary"]
    assert result["property"] == "GAS" and "GES" not in result["summary"]
    assert result["box"] == box.to_json()
    cert = result["certificate"]
    assert result["degree"] == cert["degree"] in sos.DEGREES
    # c = -1 identically, so the (c, a, b) box has four vertices, one Gram matrix of W each
    assert len(cert["vertices"]) == len(cert["Q_W"]) == 4
    # the stated rate is mu times the smallest |a11| over the box's corners
    ts_min = min(sos.scaled_dynamics(build_system(p, "derived")).time_scale  # type: ignore[union-attr]
                 for p in corner_problems(problem, box))
    assert Fraction(cert["time_scale_min"]) == ts_min
    mu = Fraction(cert["mu_scaled"])
    assert mu > 0 and result["decay_rate_V_per_s"] == float(mu * ts_min)
    ok, why = verify_gas_box(problem, box, "derived", result)
    assert ok, why


def test_the_narrower_box_certifies_the_faster_decay(near: dict[str, Any], wide: dict[str, Any]) -> None:
    assert near["decay_rate_V_per_s"] > wide["decay_rate_V_per_s"] > 0


def _multilinear_weights(vertices: list[tuple[Fraction, ...]], here: tuple[Fraction, ...]) -> dict[tuple, Fraction]:
    """Weights ``w_k >= 0``, ``sum w_k = 1``, with ``sum w_k v_k = here`` (product of 1-D weights)."""
    ranges = [(min(v[i] for v in vertices), max(v[i] for v in vertices)) for i in range(len(here))]
    weights = {}
    for vertex in vertices:
        w = Fraction(1)
        for i, (lo, hi) in enumerate(ranges):
            if hi == lo:
                continue
            t = (here[i] - lo) / (hi - lo)
            assert 0 <= t <= 1
            w *= t if vertex[i] == hi else 1 - t
        weights[vertex] = w
    assert sum(weights.values()) == 1
    assert all(sum(w * v[i] for v, w in weights.items()) == here[i] for i in range(len(here)))
    return weights


@pytest.mark.parametrize("spec, points", [
    (NEAR_PAPER, [(Fraction(600), Fraction(15, 100)), (Fraction(597), Fraction(1503, 10000)),
                  (Fraction(6111, 10), Fraction(1471, 10000))]),
    (WIDE, [(Fraction(541), Fraction(199, 1000)), (Fraction(650), Fraction(12, 100))]),
])
def test_the_convex_combination_of_vertex_grams_certifies_interior_gain_sets(
        problem: Problem, near: dict[str, Any], wide: dict[str, Any], spec: list[str],
        points: list[tuple[Fraction, Fraction]]) -> None:
    """The covering argument on the real derivation: at a gain set inside the box, the
    multilinear combination (in c, a, b) of the vertex Gram matrices of W satisfies the POINT
    certificate's exact check at that gain set's own scaled dynamics, with the box's V and mu."""
    cert = (near if spec is NEAR_PAPER else wide)["certificate"]
    hull = scaled_hull(problem, parse_box(spec), "derived")
    assert hull is not None
    grams = {tuple(Fraction(x) for x in v): exact.from_json(q) for v, q in zip(cert["vertices"], cert["Q_W"])}
    assert set(grams) == {(v.c, v.a, v.b) for v in hull[0]}
    vertices = list(grams)
    n = len(grams[vertices[0]])
    QV, mu, deg = exact.from_json(cert["Q_V"]), Fraction(cert["mu_scaled"]), int(cert["degree"])
    for alpha, kd in points:
        dyn = scaled_dynamics(build_system(problem.with_gains(alpha_d=alpha, k_d=kd), "derived"))
        assert dyn is not None
        weights = _multilinear_weights(vertices, (dyn.c, dyn.a, dyn.b))
        mixed = tuple(tuple(sum((weights[v] * grams[v][i][j] for v in vertices), Fraction(0)) for j in range(n))
                      for i in range(n))
        assert all(mixed != grams[v] for v in vertices)  # a gain set strictly inside, not a vertex
        ok, why = sos.exact_check(dyn, deg, QV, mixed, mu)
        assert ok, why


def test_v_decays_at_the_certified_rate_along_simulated_trajectories(problem: Problem, wide: dict[str, Any]) -> None:
    """Independent of the algebra: the ODE of an interior gain set, integrated in seconds,
    from near and far starts; ``V`` never exceeds ``V(0) exp(-decay_rate_V_per_s t)``."""
    cert = wide["certificate"]
    dyn = scaled_dynamics(build_system(problem.with_gains(alpha_d=Fraction(620), k_d=Fraction(13, 100)), "derived"))
    assert dyn is not None
    z_v, _ = sos.bases(int(cert["degree"]))
    V = {m: float(c) for m, c in poly.gram_form(z_v, exact.from_json(cert["Q_V"])).items()}
    c, a, b, ts = float(dyn.c), float(dyn.a), float(dyn.b), float(dyn.time_scale)

    def field(_t: float, x: np.ndarray) -> np.ndarray:  # (y, r) in seconds: tau = |a11| t
        y, r = x
        e = y - r
        r_dot = -a * r + b * e / (y * y + 1)
        return ts * np.array([-e + c * r + r_dot, r_dot])

    def v_of(x: np.ndarray) -> np.ndarray:
        return sum(coef * x[0] ** i * x[1] ** j for (i, j), coef in V.items())  # type: ignore[no-any-return]

    rate = wide["decay_rate_V_per_s"]
    for start in ((0.01, 0.0), (1.0, -1.0), (30.0, 5.0), (-3.0, 200.0)):
        sol = solve_ivp(field, (0.0, 60.0), start, method="LSODA", rtol=1e-10, atol=1e-12, dense_output=False)
        assert sol.success
        values = v_of(sol.y)
        assert np.all(values <= values[0] * np.exp(-rate * sol.t) * (1 + 1e-6) + 1e-15)
        assert values[-1] < values[0]


def test_tampered_box_certificates_fail_verify(problem: Problem, near: dict[str, Any], wide: dict[str, Any]) -> None:
    box = parse_box(NEAR_PAPER)
    assert verify_gas_box(problem, box, "derived", near)[0]

    doc = copy.deepcopy(near)  # one entry of one vertex's Gram matrix of W
    q = doc["certificate"]["Q_W"][2]
    q[0][0] = str(Fraction(q[0][0]) + Fraction(1, 10**9))
    ok, why = verify_gas_box(problem, box, "derived", doc)
    assert not ok and "identity" in why

    doc = copy.deepcopy(near)  # two vertices' Gram matrices swapped: each must hold at its own vertex
    q = doc["certificate"]["Q_W"]
    q[0], q[1] = q[1], q[0]
    assert not verify_gas_box(problem, box, "derived", doc)[0]

    doc = copy.deepcopy(near)  # one entry of V
    q = doc["certificate"]["Q_V"]
    q[1][1] = str(Fraction(q[1][1]) * 2)
    assert not verify_gas_box(problem, box, "derived", doc)[0]

    doc = copy.deepcopy(near)  # a faster decay than certified
    doc["decay_rate_V_per_s"] = near["decay_rate_V_per_s"] * 1.01
    ok, why = verify_gas_box(problem, box, "derived", doc)
    assert not ok and "exceeds" in why

    doc = copy.deepcopy(near)  # a larger mu than the Gram matrices were projected for
    doc["certificate"]["mu_scaled"] = str(Fraction(doc["certificate"]["mu_scaled"]) * 2)
    assert not verify_gas_box(problem, box, "derived", doc)[0]

    doc = copy.deepcopy(near)  # a negative mu would not make V decrease, whatever the identity says
    doc["certificate"]["mu_scaled"] = "-5"
    ok, why = verify_gas_box(problem, box, "derived", doc)
    assert not ok and "mu" in why

    doc = copy.deepcopy(near)  # a Gram matrix of the wrong size: invalid, not an exception
    doc["certificate"]["Q_W"][0] = [row[:-1] for row in doc["certificate"]["Q_W"][0][:-1]]
    ok, why = verify_gas_box(problem, box, "derived", doc)
    assert not ok and "must be" in why

    doc = copy.deepcopy(near)  # a vertex left out
    for key in ("vertices", "Q_W"):
        doc["certificate"][key] = doc["certificate"][key][:-1]
    assert not verify_gas_box(problem, box, "derived", doc)[0]

    # a wider box than the one certified, and the near-paper certificate offered for the wide box
    assert not verify_gas_box(problem, parse_box(["alpha_d=500..612", "k_d=0.147..0.153"]), "derived", near)[0]
    assert not verify_gas_box(problem, parse_box(WIDE), "derived", near)[0]
    # the wide box's certificate is not one for the near-paper box either: its vertices differ
    # (it would be true there, but the stored vertices must be the box's own)
    assert not verify_gas_box(problem, box, "derived", wide)[0]


def test_a_box_without_a_common_v_is_not_certified_and_never_refuted(problem: Problem) -> None:
    box = parse_box(NO_COMMON_V)
    # every corner is certified on its own: the box fails for want of one V common to all of it
    assert all(sos.run(build_system(p, "derived")).status == "certified" for p in corner_problems(problem, box))
    result = certify_gas_box(problem, box)
    assert result["status"] == "not_certified"
    assert "certificate" not in result and "not a proof" in result["summary"]
    assert [s["degree"] for s in result["solver"]["solves"]] == list(sos.DEGREES)


def test_vertices_are_those_of_the_scaled_hull(problem: Problem, near: dict[str, Any]) -> None:
    hull = scaled_hull(problem, parse_box(NEAR_PAPER), "derived")
    assert hull is not None
    vertices, ts_min = hull
    assert near["certificate"]["vertices"] == [[str(v.c), str(v.a), str(v.b)] for v in vertices]
    assert all(isinstance(v, ScaledDynamics) and v.c == -1 for v in vertices)
