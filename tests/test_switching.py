"""``switched_ges``: exact refutation by a growing periodic switching, and its re-check."""

from __future__ import annotations

import copy
import json
import subprocess
import sys
from fractions import Fraction as Q

import mpmath
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from lyapcheck import exact
from lyapcheck.paper.conditions import sector
from lyapcheck.paper.conditions import switching as sw
from lyapcheck.paper.conditions.base import System
from lyapcheck.errors import CertificateError
from tests.conftest import ROOT

#: the exact derived error dynamics at the paper's gains (``build_system(paper, "derived")``)
PAPER_A = exact.matrix([["-279/5000", "-279/500000"], ["0", "-3/20"]])
PAPER_B = exact.matrix([[0, 0], [1, 0]])
PAPER_RHO_SUP = Q(4000, 3)


def make_system(a: exact.Matrix, b: exact.Matrix, rho_sup: Q) -> System:
    return System(dynamics="derived", A=a, B=b, E=(Q(1), Q(0)), rho_sup=rho_sup, sigma0=Q(1, 100),
                  delta=Q(3, 4000), speed=Q(1), d_max=Q(0))


@pytest.fixture(scope="module")
def paper_system() -> System:
    return make_system(PAPER_A, PAPER_B, PAPER_RHO_SUP)


@pytest.fixture(scope="module")
def paper_result(paper_system: System) -> sw.ConditionResult:
    return sw.run(paper_system)


def paper_vertices(system: System) -> list[exact.Matrix]:
    return [system.vertex(system.rho_sup * sw.RHO_LO_FRACTION), system.vertex(system.rho_sup)]


# --- the 2x2 criterion ----------------------------------------------------------------------


@pytest.mark.parametrize(("rows", "expected"), [
    ([[2, 0], [0, "1/10"]], True),               # real, rho = 2
    ([["-3/2", 0], [0, "1/5"]], True),           # real, negative dominant eigenvalue: |T| > 1 + D
    ([["11/10", "-11/10"], ["11/10", "11/10"]], True),  # complex, |D| > 1
    ([["1/2", 100], [0, "1/2"]], False),         # rho = 1/2 despite the large entry
    ([[0, -1], [1, 0]], False),                  # rotation: rho = 1 exactly, not > 1
    ([[1, 0], [0, "-1/2"]], False),              # eigenvalue 1 on the circle
    ([["9/10", "1/10"], ["-1/10", "9/10"]], False),  # complex, |lambda|^2 = 0.82
])
def test_schur_cohn_criterion_on_known_matrices(rows: list[list[object]], expected: bool) -> None:
    m = exact.matrix(rows)  # type: ignore[arg-type]
    assert sw.spectral_radius_exceeds_one_2x2(m) is expected


entry = st.integers(min_value=-36, max_value=36)  # twelfths: rationals in [-3, 3]


@settings(max_examples=120, derandomize=True)
@given(entry, entry, entry, entry)
def test_schur_cohn_criterion_matches_eigenvalues(a: int, b: int, c: int, d: int) -> None:
    m = exact.matrix([[Q(a, 12), Q(b, 12)], [Q(c, 12), Q(d, 12)]])
    radius = float(np.abs(np.linalg.eigvals(np.array(exact.to_float(m)))).max())
    if abs(radius - 1) > 1e-9:
        assert sw.spectral_radius_exceeds_one_2x2(m) == (radius > 1)


def test_interval_criterion_needs_the_whole_box() -> None:
    # |T| > 1 + D holds at T = 2.2 but not at T = 1.4 (D = 1/2): the box does not prove it
    assert not sw.spectral_radius_exceeds_one((Q(14, 10), Q(22, 10)), (Q(1, 2), Q(1, 2)))
    assert not sw.spectral_radius_exceeds_one((Q(-2), Q(2)), (Q(1, 2), Q(1, 2)))
    assert sw.spectral_radius_exceeds_one((Q(16, 10), Q(22, 10)), (Q(1, 2), Q(1, 2)))
    assert sw.spectral_radius_exceeds_one((Q(-22, 10), Q(-16, 10)), (Q(1, 2), Q(1, 2)))


def test_growth_lower_bound_is_below_the_spectral_radius() -> None:
    for rows in ([[2, 0], [0, "1/10"]], [["-3/2", 1], [0, "1/5"]], [["11/10", "-11/10"], ["11/10", "11/10"]]):
        m = exact.matrix(rows)  # type: ignore[arg-type]
        t, d = m[0][0] + m[1][1], exact.det(m)
        bound = sw.growth_lower_bound((t, t), (d, d))
        radius = float(np.abs(np.linalg.eigvals(np.array(exact.to_float(m)))).max())
        assert float(bound) <= radius < float(bound) + 1e-9  # point intervals: tight


# --- the rigorous exponential -----------------------------------------------------------------


@pytest.mark.parametrize(("rows", "t"), [
    ([["-279/5000", "-279/500000"], ["4000/3", "-3/20"]], Q(21, 10)),  # the paper's rotating vertex
    ([[-1, 10], [0, -2]], Q(7, 3)),                                     # non-normal, real eigenvalues
    ([[-1, 1], [0, -1]], Q(5)),                                         # Jordan block
    ([["1/2", 0], [3, "1/4"]], Q(3)),                                   # unstable
])
def test_expm_enclosure_contains_the_high_precision_exponential(rows: list[list[object]], t: Q) -> None:
    a = exact.matrix(rows)  # type: ignore[arg-type]
    order, squarings = sw.expm_parameters(a, t, 96)
    box = sw.expm_enclosure(a, t, order, squarings, 96)
    with mpmath.workdps(60):
        ref = mpmath.expm(mpmath.matrix([[mpmath.mpf(x.numerator) / x.denominator for x in row] for row in a])
                          * (mpmath.mpf(t.numerator) / t.denominator))
        for i in range(2):
            for j in range(2):
                lo, hi = box[i][j]
                assert mpmath.mpf(lo.numerator) / lo.denominator <= ref[i, j] <= mpmath.mpf(hi.numerator) / hi.denominator
                assert float(hi - lo) < 1e-15 * (1 + abs(float(ref[i, j])))


def test_closed_form_search_exponential_agrees_with_the_enclosure() -> None:
    for rows in ([[-1, 10], [0, -2]], [[-1, 1], [0, -1]], [["-1/20", -1], [1, "-1/10"]], [[-1000, 1], [0, "-1/1000"]]):
        a = exact.matrix(rows)  # type: ignore[arg-type]
        t = Q(3, 2)
        box = sw.expm_enclosure(a, t, *sw.expm_parameters(a, t, 96), 96)
        approx = sw._expm2(np.array(exact.to_float(a)), np.array(float(t)))
        mid = np.array([[float((lo + hi) / 2) for lo, hi in row] for row in box])
        np.testing.assert_allclose(approx, mid, rtol=1e-10, atol=1e-12 * np.abs(mid).max())


# --- the paper's gains ------------------------------------------------------------------------


def test_paper_gains_refuted_exactly(paper_system: System, paper_result: sw.ConditionResult) -> None:
    r = paper_result
    assert r.name == "switched_ges" and r.status == "refuted"
    assert r.numbers["growth_per_period"] > 2 and r.numbers["growth_per_period_lower_bound"] > 2
    assert r.numbers["growth_rate_per_s"] > 0.1
    assert 1 < r.numbers["t1_s"] < 3 and 3 < r.numbers["t0_s"] < 7
    assert "no Lyapunov function of any form" in r.summary
    cert = json.loads(json.dumps(r.refutation))  # JSON round trip: strings and ints only
    assert sw.verify(paper_system, cert)[0]
    assert sw.verify_unstable_switching(paper_vertices(paper_system), cert)[0]


def test_paper_gains_from_the_toml_file(paper_problem) -> None:
    from lyapcheck.paper.certification import build_system

    system = build_system(paper_problem, "derived")
    assert (system.A, system.B, system.rho_sup) == (PAPER_A, PAPER_B, PAPER_RHO_SUP)
    # the printed dynamics have a common quadratic Lyapunov function: never refuted
    printed = build_system(paper_problem, "printed")
    result = sw.run(printed)
    assert result.status == "certified"
    assert sw.verify(printed, result.certificate)[0]


def test_search_finds_the_growing_switching(paper_system: System) -> None:
    # (how quickly is benchmarks/bench_quick_paths.py's figure: no test asserts a wall time)
    vertices = paper_vertices(paper_system)
    found = sw.find_unstable_switching(vertices)
    assert found is not None and found["growth_per_period"] > 2
    m = (exact.to_float(vertices[0]), exact.to_float(vertices[1]))
    e0 = sw._expm2(np.array(m[0]), np.array(found["t0"]))
    e1 = sw._expm2(np.array(m[1]), np.array(found["t1"]))
    assert np.abs(np.linalg.eigvals(e0 @ e1)).max() == pytest.approx(found["growth_per_period"], rel=1e-8)


# --- tampering --------------------------------------------------------------------------------


def test_verifier_rejects_tampered_certificates(paper_system: System, paper_result: sw.ConditionResult) -> None:
    vertices = paper_vertices(paper_system)
    good = paper_result.refutation

    shorter = copy.deepcopy(good)
    shorter["t1"] = "1/10"  # stored enclosures no longer contain the recomputed ones
    assert sw.verify_unstable_switching(vertices, shorter) == (
        False, "the stated enclosures of trace and determinant do not contain the recomputed ones")

    # an honest recomputation at a short dwell: the enclosures are right but rho < 1
    honest = copy.deepcopy(shorter)
    t, d = sw._trace_det(vertices, (Q(honest["t0"]), Q(1, 10)), Q(honest["balance"]), honest["taylor_order"],
                         honest["squarings"], honest["precision_bits"])
    honest["trace"], honest["det"] = [str(t[0]), str(t[1])], [str(d[0]), str(d[1])]
    ok, why = sw.verify_unstable_switching(vertices, honest)
    assert not ok and "Schur-Cohn" in why

    moved = copy.deepcopy(good)
    moved["trace"] = [str(Q(x) + Q(1, 10**6)) for x in moved["trace"]]
    assert not sw.verify_unstable_switching(vertices, moved)[0]

    boasting = copy.deepcopy(good)
    boasting["growth_lower_bound"] = "3"
    ok, why = sw.verify_unstable_switching(vertices, boasting)
    assert not ok and "exceeds" in why

    other = copy.deepcopy(good)
    other["rho"] = ["0", other["rho"][1]]  # rho = 0 is outside the sector (0, rho_sup]
    assert not sw.verify(paper_system, other)[0]

    wrong_vertices = [vertices[0], exact.scale(Q(1, 2), vertices[1])]
    assert not sw.verify_unstable_switching(wrong_vertices, good)[0]

    with pytest.raises(CertificateError, match="malformed"):
        sw.verify_unstable_switching(vertices, {k: v for k, v in good.items() if k != "det"})
    hostile = copy.deepcopy(good)
    hostile["squarings"] = [10**9, 3]
    with pytest.raises(CertificateError, match="squarings"):
        sw.verify_unstable_switching(vertices, hostile)


def test_verification_needs_neither_numpy_nor_scipy(paper_result: sw.ConditionResult) -> None:
    code = (
        "import json, sys\n"
        "sys.modules['numpy'] = None; sys.modules['scipy'] = None  # any import of them now fails\n"
        "from fractions import Fraction as Q\n"
        "from lyapcheck import exact\n"
        "from lyapcheck.paper.conditions import switching as sw\n"
        "cert = json.loads(sys.stdin.read())\n"
        "ok, why = sw.verify_unstable_switching([exact.from_json(v) for v in cert['vertices']], cert)\n"
        "assert ok, why\n"
    )
    done = subprocess.run([sys.executable, "-c", code], input=json.dumps(paper_result.refutation),
                          capture_output=True, text=True, cwd=ROOT, timeout=60)
    assert done.returncode == 0, done.stderr[-2000:]


# --- stable pairs, other scales ---------------------------------------------------------------


def test_pair_with_a_common_quadratic_lyapunov_function_is_not_refuted() -> None:
    a0, a1 = exact.matrix([[-1, 0], [0, -1]]), exact.matrix([[-1, 1], [-1, -1]])
    assert sw.find_unstable_switching([a0, a1]) is None
    system = make_system(a0, exact.add(a1, exact.scale(Q(-1), a0)), Q(1))  # vertex(1) = a1
    result = sw.run(system)
    assert result.status == "certified"
    assert sw.verify(system, result.certificate)[0]


def test_unstable_convex_combination_is_found() -> None:
    # both vertices Hurwitz, but (A0 + A1)/2 has eigenvalue 4: fast switching grows
    vertices = [exact.matrix([[-1, 10], [0, -1]]), exact.matrix([[-1, 0], [10, -1]])]
    found = sw.find_unstable_switching(vertices)
    assert found is not None
    cert = sw.certify_unstable_switching(vertices, Q(found["t0_exact"]), Q(found["t1_exact"]))
    assert cert is not None and sw.verify_unstable_switching(vertices, cert)[0]


def test_non_hurwitz_vertex_is_refuted_directly() -> None:
    system = make_system(exact.matrix([[-1, 0], [0, -1]]), exact.matrix([[2, 0], [0, 0]]), Q(1))
    result = sw.run(system)
    assert result.status == "refuted" and result.refutation["argument"] == "vertex_not_hurwitz"
    assert sw.verify(system, result.refutation)[0]


@pytest.mark.parametrize("factor", [Q(1, 10**6), Q(10**6)])
def test_time_scaling_moves_dwell_times_not_growth(paper_system: System, factor: Q) -> None:
    vertices = [exact.scale(factor, v) for v in paper_vertices(paper_system)]
    base = sw.find_unstable_switching(paper_vertices(paper_system))
    found = sw.find_unstable_switching(vertices)
    assert base is not None and found is not None
    assert found["growth_per_period"] == pytest.approx(base["growth_per_period"], rel=1e-6)
    assert found["t0"] * float(factor) == pytest.approx(base["t0"], rel=1e-6)
    cert = sw.certify_unstable_switching(vertices, Q(found["t0_exact"]), Q(found["t1_exact"]))
    assert cert is not None and sw.verify_unstable_switching(vertices, cert)[0]


@pytest.mark.parametrize(("factor", "expected"), [("1e-6", "refuted"), ("1e6", "certified")])
def test_gains_far_from_the_paper(factor: str, expected: str) -> None:
    from lyapcheck.paper.certification import build_system
    from lyapcheck.paper.params import problem_from_sources
    from tests.conftest import PAPER_TOML

    gains = {"gains.alpha_d": str(600 * float(factor)), "gains.k_d": str(0.15 * float(factor))}
    system = build_system(problem_from_sources(PAPER_TOML, gains), "derived")
    result = sw.run(system)
    assert result.status == expected
    assert sw.verify(system, result.refutation or result.certificate)[0]


def test_refuted_and_certified_never_both(paper_system: System) -> None:
    """Two exact arguments that contradict each other would expose a bug in one of them."""
    rng = np.random.default_rng(20240611)
    for _ in range(12):
        vertices = []
        for _ in range(2):
            while True:
                m = exact.rational_matrix(rng.normal(size=(2, 2)), 4)
                if exact.is_hurwitz_2x2(m):
                    break
            vertices.append(m)
        found = sw.find_unstable_switching(vertices)
        refuted = found is not None and sw.certify_unstable_switching(
            vertices, Q(found["t0_exact"]), Q(found["t1_exact"])) is not None
        certified = sw._find_common_quadratic(vertices) is not None
        assert not (refuted and certified)
        if certified:  # Shorten-Narendra: a common quadratic function exists only without the obstruction
            assert sector.refutation(vertices) is None
