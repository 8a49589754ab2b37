"""Certificate classes: verdicts at the paper's gains and elsewhere, all checked exactly."""

from __future__ import annotations

import json
from fractions import Fraction

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from lyapcheck import exact
from lyapcheck.paper.certificate import build_document, verify_document
from lyapcheck.paper.certification import build_system, run_conditions, verdict
from lyapcheck.paper.conditions import prop41, sector
from lyapcheck.paper.params import problem_from_sources
from tests.conftest import PAPER_TOML

PAPER_EXPECTED = {
    "derived": {"prop41_ges": "refuted", "prop41_iss": "refuted", "stabcond2": "holds",
                "sector_ges": "refuted", "switched_ges": "refuted", "ultimate_bound": "certified",
                "sos_gas": "certified", "ges": "certified", "saturated_loop": "certified", "sos_bound": "certified"},
    "printed": {"prop41_ges": "refuted", "prop41_iss": "refuted", "stabcond2": "holds",
                "sector_ges": "certified", "switched_ges": "certified", "ultimate_bound": "certified",
                "sos_gas": "certified", "ges": "certified", "saturated_loop": "not_certified", "sos_bound": "certified"},
}


@pytest.mark.parametrize("dynamics", ["derived", "printed"])
def test_paper_gains_verdicts(paper_problem, dynamics: str) -> None:
    results = run_conditions(paper_problem, dynamics)
    assert {k: v.status for k, v in results.items()} == PAPER_EXPECTED[dynamics]
    assert results["stabcond2"].numbers["implies_stabcond_here"] == "fails"
    doc = build_document(paper_problem, dynamics, results, verdict(results))
    assert all(ok for _, ok, _ in verify_document(doc))


def test_paper_ultimate_bounds(paper_problem) -> None:
    derived = run_conditions(paper_problem, "derived")["ultimate_bound"]
    printed = run_conditions(paper_problem, "printed")["ultimate_bound"]
    # derived: only the comparison box, |eps| <= sigma0 U/(2 k_d) + d*/(e11 alpha_d) (inflated)
    box = 0.01 * 1 / (2 * 0.15) + 88e-6 / (93e-6 * 600)
    assert derived.numbers["eps_bound_m"] == pytest.approx(box, rel=1e-5)
    assert printed.numbers["ellipsoid_stages"] >= 1 and printed.numbers["eps_bound_m"] < 0.01


def test_easy_gains_are_certified_by_every_class(easy_problem) -> None:
    results = run_conditions(easy_problem, "derived")
    statuses = {k: v.status for k, v in results.items()}
    assert {k: statuses[k] for k in ("prop41_ges", "prop41_iss", "stabcond2", "sector_ges", "ultimate_bound")} == {
        "prop41_ges": "certified", "prop41_iss": "certified", "stabcond2": "fails",
        "sector_ges": "certified", "ultimate_bound": "certified"}
    assert verdict(results) == "certified"
    ub = results["ultimate_bound"]
    assert ub.numbers["ellipsoid_stages"] >= 1 and ub.numbers["eps_bound_m"] < ub.numbers["box_eps_bound_m"]
    assert ub.numbers["paper_ball_radius_as_printed"] is not None


def test_prop41_exact_check_rejects_a_perturbed_certificate(easy_problem) -> None:
    system = build_system(easy_problem, "derived")
    P = exact.from_json(run_conditions(easy_problem, "derived")["prop41_ges"].certificate["P"])
    assert prop41.exact_check(system, P, iss=False)[0]
    assert not prop41.exact_check(system, exact.scale(Fraction(-1), P), iss=False)[0]
    skewed = ((P[0][0], P[0][1] + 10 * P[1][1]), (P[0][1] + 10 * P[1][1], P[1][1] * 200))
    assert not prop41.exact_check(system, skewed, iss=False)[0]


def test_shorten_narendra_refutation_agrees_with_the_sdp(paper_problem) -> None:
    system = build_system(paper_problem, "derived")
    verts = [system.vertex(Fraction(0)), system.vertex(system.rho_sup)]
    assert sector.refutation(verts) is not None
    _, _, margin, report = sector.certify_polytope(verts)
    assert report.outcome == "optimal" and margin is not None and margin < 0


def test_programs_are_dpp() -> None:
    from lyapcheck.paper.conditions import compiled

    for key in compiled.PROGRAMS:
        problem, _, _ = compiled.build(key)
        assert problem.is_dpp(), key


def test_tampered_number_fails_verify(easy_problem) -> None:
    results = run_conditions(easy_problem, "derived")
    doc = json.loads(json.dumps(build_document(easy_problem, "derived", results, verdict(results))))
    assert all(ok for _, ok, _ in verify_document(doc))
    P = doc["conditions"]["sector_ges"]["certificate"]["P"]
    P[1][1] = str(-Fraction(P[1][1]))
    rows = {name: (ok, msg) for name, ok, msg in verify_document(doc)}
    assert not rows["sector_ges"][0] and "positive definite" in rows["sector_ges"][1]
    doc2 = json.loads(json.dumps(build_document(easy_problem, "derived", results, verdict(results))))
    doc2["inputs"]["exact_si"]["k_d"] = "1/2"
    rows2 = {name: ok for name, ok, _ in verify_document(doc2)}
    assert not rows2["system"]


gain_sets = st.fixed_dictionaries({
    "gains.alpha_d": st.sampled_from(["0.5", "1", "3", "20", "600"]),
    "gains.sigma0": st.sampled_from(["0.01", "0.1", "0.5", "2"]),
    "gains.k_d": st.sampled_from(["0.15", "1", "5", "40"]),
    "gains.delta_los": st.sampled_from(["0.75 mm", "10 mm", "0.5 m", "3 m"]),
    "swimmer.e11": st.sampled_from(["9.3e-5 m", "0.01 m", "1 m"]),
    "disturbance.d_max": st.sampled_from(["0 mm/s", "0.088 mm/s", "5 mm/s"]),
})


@pytest.mark.slow
@settings(max_examples=25, deadline=None, derandomize=True, suppress_health_check=[HealthCheck.too_slow])
@given(gain_sets, st.sampled_from(["derived", "printed"]))
def test_no_certified_or_refuted_verdict_fails_its_exact_recheck(overrides: dict[str, str], dynamics: str) -> None:
    problem = problem_from_sources(PAPER_TOML, overrides)
    results = run_conditions(problem, dynamics)
    doc = json.loads(json.dumps(build_document(problem, dynamics, results, verdict(results))))
    rows = verify_document(doc)
    assert all(ok for _, ok, _ in rows), rows
    for name, res in results.items():
        assert res.status in ("certified", "refuted", "not_certified", "inconclusive", "holds", "fails")
        if res.status == "certified" and name != "ultimate_bound":
            assert res.certificate


def test_linear_views_cross_check(paper_problem, easy_problem) -> None:
    from lyapcheck.paper.linalg_views import linear_views

    paper = linear_views(build_system(paper_problem, "derived"))
    assert paper["A"]["hurwitz_exact"] and paper["linearisation_at_0"]["hurwitz_exact"]
    # linearisation at 0: lightly damped pair, -0.103 +- 0.86i at the paper's gains
    re, im = paper["linearisation_at_0"]["poles"][0]
    assert re == pytest.approx(-(0.0558 + 0.15) / 2, rel=1e-3) and abs(im) == pytest.approx(0.8617, rel=1e-3)
    assert paper["lyap_gamma_identity"]["residual"] < 1e-9
    assert not paper["lyap_gamma_identity"]["satisfies_stabcond_exactly"]  # consistent with the refutation
    easy = linear_views(build_system(easy_problem, "derived"))
    assert easy["lyap_gamma_identity"]["residual"] < 1e-9


def test_verify_rejects_a_sector_certificate_that_does_not_cover_the_sector(easy_problem) -> None:
    results = run_conditions(easy_problem, "derived", ("sector_ges",))
    doc = build_document(easy_problem, "derived", results, verdict(results))
    assert all(ok for _, ok, _ in verify_document(doc))
    doc["conditions"]["sector_ges"]["certificate"]["rho_lo"] = "1/1000"
    rows = verify_document(doc)
    assert any(name == "sector_ges" and not ok and "rho_lo" in message for name, ok, message in rows)


#: the figures stated beside certificates, and the factor that forges each to claim more than is
#: proved: a bound made ten times smaller, a rate or margin ten times larger
FORGED_FIGURES = [("ges", "k", 0.1), ("ges", "k_eps_s", 0.1), ("ges", "decay_rate_per_s", 10),
                  ("ges", "decay_rate_V_per_s", 10), ("sos_gas", "decay_rate_V_per_s", 10),
                  ("ultimate_bound", "eps_bound_m", 0.1), ("sos_bound", "eps_bound_m", 0.1),
                  ("saturated_loop", "ultimate_eps_bound_m", 0.1), ("saturated_loop", "invariant_eps_radius_m_at_s0", 10),
                  ("saturated_loop", "windup_bound_s_m", 0.1), ("saturated_loop", "reach_set_y_half_width_m", 0.1),
                  ("saturated_loop", "reach_margin_m_per_s", 10)]


@pytest.mark.slow
def test_a_figure_stated_beyond_what_its_certificate_proves_fails_verify(easy_problem) -> None:
    """k, rates and bounds are claims too: each must follow from its exact certificate."""
    results = run_conditions(easy_problem, "derived")
    document = build_document(easy_problem, "derived", results, verdict(results))
    assert all(ok for _, ok, _ in verify_document(json.loads(json.dumps(document))))
    for cls, key, factor in FORGED_FIGURES:
        doc = json.loads(json.dumps(document))
        assert doc["conditions"][cls].get(key), (cls, key)  # the figure is stated here, and not 0
        doc["conditions"][cls][key] *= factor
        failed = [name for name, ok, _ in verify_document(doc) if not ok]
        assert cls in failed, (cls, key)
    # the disturbance step of saturated_loop is re-checked too (it used to be taken as stated)
    doc = json.loads(json.dumps(document))
    cert = doc["conditions"]["saturated_loop"]["certificate"]
    cert["R_lo"] = str(Fraction(cert["R_lo"]) / 4)
    assert "saturated_loop" in [name for name, ok, _ in verify_document(doc) if not ok]
