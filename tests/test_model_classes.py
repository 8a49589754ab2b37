"""The generic classes of a model file, checked on their conditions, not on stored verdicts.

Every certificate is re-checked here independently of lyapcheck's own exact checks: the model's
equations are read with sympy (the test's own known strings, not a user's), ``V`` is taken from the
certificate in the declared states, and the property it claims is tested exactly at points or
symbolically. Negative and tricky cases (a limit cycle, a second equilibrium, finite escape time,
a GAS field with no polynomial Lyapunov function, an unstable equilibrium) must never get a
global class; a refutation must come with an exact argument.
"""

from __future__ import annotations

import copy
import random
import tomllib
from fractions import Fraction
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import sympy as sp

from lyapcheck.models.surfaces.certificate import build_document, verify_document
from lyapcheck.models.surfaces.certify import certify_model
from lyapcheck.models.language.modelfile import load_model, parse_model
from tests.conftest import ROOT

MODELS = ROOT / "examples" / "models"


def model_text(states: list[str], dynamics: dict[str, str], extra: str = "") -> str:
    lines = ["[model]", f"states = {states!r}".replace("'", '"'), extra, "[dynamics]"]
    lines += [f'{k} = "{v}"' for k, v in dynamics.items()]
    return "\n".join(lines) + "\n"


def run(text: str, **kwargs: Any) -> Any:
    return certify_model(parse_model(text, "<test>"), **kwargs)


def sympy_field(path_or_text: str | Path) -> tuple[list[sp.Symbol], list[sp.Expr], dict[str, Fraction]]:
    """The declared states and right-hand sides (disturbances 0, parameters substituted), by sympy."""
    text = Path(path_or_text).read_text() if isinstance(path_or_text, Path) else path_or_text
    data = tomllib.loads(text)
    states = [sp.Symbol(s) for s in data["model"]["states"]]
    params = {k: sp.Rational(str(v)) for k, v in data.get("parameters", {}).items() if not isinstance(v, str)}
    zero = {sp.Symbol(d): 0 for d in data.get("disturbances", {})}
    rhs = [sp.sympify(data["dynamics"][s.name], locals={k: sp.Symbol(k) for k in params}).subs(params).subs(zero)
           for s in states]
    return states, rhs, params


def v_of(cert: dict[str, Any], states: list[sp.Symbol]) -> sp.Expr:
    """The certificate's V (declared states, shifted equilibrium 0 here) as a sympy expression."""
    total = sp.Integer(0)
    for coef, exps in cert["V"]["terms"]:
        term = sp.Rational(coef)
        for s, e in zip(states, exps):
            term *= s ** e
        total += term
    return total


def random_points(n: int, count: int, radius: Fraction, seed: int) -> list[list[Fraction]]:
    rng = random.Random(seed)
    return [[Fraction(rng.randint(-1000, 1000), 1000) * radius for _ in range(n)] for _ in range(count)]


# -- linearization -------------------------------------------------------------------------------

@pytest.mark.parametrize("dynamics, status", [
    ({"x": "-y", "y": "x - (1 - x**2)*y"}, "certified"),          # reversed Van der Pol: Hurwitz
    ({"x": "y", "y": "-x + (1 - x**2)*y"}, "refuted"),            # Van der Pol: unstable focus
    ({"x": "x", "y": "-y"}, "refuted"),                           # saddle: the Lyapunov equation is singular
    ({"x": "-x**3", "y": "-y"}, "not_certified"),                 # a zero eigenvalue: critical
    ({"x": "y", "y": "-x"}, "not_certified"),                     # a centre: critical
    ({"x": "(-x + y)/(1 + x**2)", "y": "-y"}, "certified"),       # rational
])
def test_linearization_decides_exactly(dynamics: dict[str, str], status: str) -> None:
    text = model_text(["x", "y"], dynamics)
    result = run(text, classes="linearization")
    lin = result.results["linearization"]
    assert lin.status == status
    states, rhs, _ = sympy_field(text)
    J = sp.Matrix([[sp.diff(f, s) for s in states] for f in rhs]).subs({s: 0 for s in states})
    eig = [complex(e) for e in J.eigenvals()]
    if status == "certified":
        assert max(e.real for e in eig) < 0
        if "P" in lin.certificate:  # J^T P + P J = -I with P > 0, recomputed by sympy
            P = sp.Matrix([[sp.Rational(x) for x in row] for row in lin.certificate["P"]])
            assert J.T * P + P * J == -sp.eye(2) and P.is_positive_definite
    elif status == "refuted":
        assert max(e.real for e in eig) > 0
    else:
        assert max(e.real for e in eig) == 0 and lin.numbers["reason"] == "critical"
    doc = build_document(result)
    assert all(ok for _, ok, _ in verify_document(doc))


# -- global classes: certificates checked on their conditions ----------------------------------------

def test_quadratic_ges_on_a_linear_system_holds_symbolically() -> None:
    text = model_text(["x", "y"], {"x": "-3*x + y", "y": "-x - 2*y"})
    result = run(text, classes="quadratic")
    quad = result.results["quadratic"]
    assert quad.status == "certified" and quad.proves() == "GES"
    states, rhs, _ = sympy_field(text)
    V = v_of(quad.certificate, states)
    assert result.scaling is not None
    rate_v = sp.Rational(quad.certificate["mu_scaled"]) / sp.Rational(result.scaling.time)  # 1/s
    assert rate_v > 0 and quad.numbers["decay_rate_V_per_s"] <= float(rate_v) * (1 + 1e-12)
    vdot = sum(sp.diff(V, s) * f for s, f in zip(states, rhs))
    H = sp.hessian(sp.expand(-vdot - rate_v * V), states) / 2  # V' <= -rate V everywhere, exactly
    assert H.is_positive_semidefinite and sp.hessian(V, states).is_positive_definite
    # the claimed envelope |x(t)| <= k |x0| exp(-rate t / 2): k >= sqrt(lambda_max / lambda_min)
    lam = sorted(float(e) for e in (sp.hessian(V, states) / 2).eigenvals(multiple=True))
    assert quad.numbers["k"] >= np.sqrt(lam[1] / lam[0]) * (1 - 1e-12)
    assert quad.numbers["decay_rate_per_s"] <= float(rate_v) / 2 * (1 + 1e-12)


def test_sos_gas_on_the_rational_sosdemo2_field_decreases_everywhere() -> None:
    path = MODELS / "sosdemo2-rational.toml"
    result = certify_model(load_model(path), classes="linearization,sos_gas")
    assert result.results["linearization"].status == "not_certified"  # critical: no local argument
    gas = result.results["sos_gas"]
    assert gas.status == "certified" and gas.proves() == "GAS"
    states, rhs, _ = sympy_field(path)
    V = v_of(gas.certificate, states)
    vdot = sp.together(sum(sp.diff(V, s) * f for s, f in zip(states, rhs)))
    v_fn, vdot_fn = sp.lambdify(states, V, "mpmath"), sp.lambdify(states, vdot, "mpmath")
    for point in random_points(3, 300, Fraction(5), seed=1):
        if any(point):
            x = [sp.Rational(p) for p in point]
            assert V.subs(dict(zip(states, x))) > 0
            assert vdot.subs(dict(zip(states, x))) < 0
    del v_fn, vdot_fn


@pytest.mark.parametrize("dynamics", [{"x": "0*x"}, {"x": "-a*x", "y": "-y"}])
def test_a_state_whose_derivative_is_identically_zero_gets_no_stability_class(dynamics: dict[str, str]) -> None:
    """x' = 0 (every point an equilibrium, no asymptotic stability): the classes run (a polynomial with
    no terms is data of size 0 for the solver) and none certifies; it once stopped with exit 3."""
    result = run(model_text(list(dynamics), dynamics, "[parameters]\na = 0" if "y" in dynamics else ""))
    assert result.results["linearization"].status == "not_certified"
    for name in ("quadratic", "sos_gas", "roa"):
        assert result.results[name].status != "certified"


def test_no_polynomial_lyapunov_function_is_never_certified_globally() -> None:
    """Ahmadi, Krstic and Parrilo's GAS field has no polynomial Lyapunov function at all."""
    result = certify_model(load_model(MODELS / "ahmadi-no-polynomial-lyapunov.toml"))
    assert result.results["quadratic"].status == "not_certified"
    assert result.results["sos_gas"].status == "not_certified"
    assert result.results["linearization"].status == "certified"
    roa = result.results["roa"]
    assert roa.status == "certified" and roa.proves() == "ROA"


def _forward_van_der_pol_cycle(mu: float = 1.0) -> np.ndarray:
    """Points of the reversed oscillator's unstable limit cycle (the forward one's stable cycle)."""
    from scipy.integrate import solve_ivp

    def forward(_t: float, z: np.ndarray) -> list[float]:
        x1, x2 = z
        return [x2, -x1 + mu * (1 - x1 ** 2) * x2]

    sol = solve_ivp(forward, (0, 60), [0.5, 0.0], rtol=1e-10, atol=1e-12, dense_output=True)
    return sol.sol(np.linspace(40, 60, 2000)).T


def test_a_limit_cycle_gets_a_region_of_attraction_inside_it_and_no_global_class() -> None:
    path = MODELS / "van-der-pol-reversed.toml"
    result = certify_model(load_model(path))
    assert result.results["quadratic"].status == "not_certified"
    assert result.results["sos_gas"].status == "not_certified"
    roa = result.results["roa"]
    assert roa.status == "certified"
    states, _, _ = sympy_field(path)
    V = sp.lambdify(states, v_of(roa.certificate, states), "numpy")
    level = float(Fraction(roa.certificate["level"]))
    cycle = _forward_van_der_pol_cycle()
    assert np.min(V(cycle[:, 0], cycle[:, 1])) > level  # the certified set stays inside the cycle
    assert roa.numbers["roa_share"] >= 0.95  # issue 23's target on the simulated region of attraction
    assert "soundness_violation" not in roa.numbers


def test_a_second_equilibrium_and_finite_escape_bound_the_region() -> None:
    """``x' = -x + x^3``: equilibria at +-1, escape beyond them; the true region is (-1, 1)."""
    result = run(model_text(["x"], {"x": "-x + x**3"}, "[domain]\nx = [-2, 2]"))
    for name in ("quadratic", "sos_gas"):
        assert result.results[name].status == "not_certified"
    roa = result.results["roa"]
    assert roa.status == "certified"
    V = {tuple(e): Fraction(c) for c, e in roa.certificate["V"]["terms"]}
    level = Fraction(roa.certificate["level"])

    def value(x: Fraction) -> Fraction:
        return sum((c * x ** e[0] for e, c in V.items()), Fraction(0))

    assert value(Fraction(1)) > level and value(Fraction(-1)) > level  # the other equilibria are outside


def test_an_unstable_equilibrium_is_refuted_with_an_exact_argument(tmp_path: Path) -> None:
    from click.testing import CliRunner

    from lyapcheck.cli import app

    app._register_commands()
    out = tmp_path / "cert.json"
    res = CliRunner().invoke(app.cli, ["certify", "--model", str(MODELS / "unstable-van-der-pol.toml"), "--json",
                                       "--out", str(out)], standalone_mode=False)
    assert res.exit_code == 1
    import json

    doc = json.loads(out.read_text())
    assert doc["verdict"] == "unstable" and doc["answers"]["stability"]["answer"] == "unstable"
    assert doc["conditions"]["linearization"]["status"] == "refuted"
    assert doc["conditions"]["linearization"]["refutation"]["method"] == "lyapunov_inertia"
    assert all(c["status"] != "certified" for c in doc["conditions"].values())
    assert all(ok for _, ok, _ in verify_document(doc))


def test_sos_bound_is_within_one_and_a_half_of_the_exact_worst_case_and_never_below() -> None:
    """x1' = -x1 + x2, x2' = -2 x2 + d, |d| <= 1: the exact worst cases are limsup |x1| = limsup |x2| = 1/2."""
    result = certify_model(load_model(MODELS / "linear-disturbed-l1.toml"), classes="sos_bound")
    bound = result.results["sos_bound"]
    assert bound.status == "certified"
    for name in ("y", "w"):
        assert 0.5 <= bound.numbers["bounds"][name] <= 0.75
    assert all(ok for _, ok, _ in verify_document(build_document(result)))


@pytest.mark.slow
def test_the_papers_loop_as_a_model_file_gets_gas_and_an_ultimate_bound() -> None:
    path = MODELS / "paper-error-dynamics.toml"
    result = certify_model(load_model(path), classes="sos_gas,sos_bound")
    assert result.results["sos_gas"].status == "certified"
    bound = result.results["sos_bound"]
    assert bound.status == "certified"
    eps_bound = bound.numbers["bounds"]["eps"]
    # under the constant disturbance d = d*, the steady state solves the field = 0 exactly
    states, _, _ = sympy_field(path)
    eps, s = states
    a, sigma0, k, delta, U, d = (sp.Rational(600 * 93, 10**6), sp.Rational(1, 100), sp.Rational(15, 100),
                                 sp.Rational(3, 4000), 1, sp.Rational(88, 10**6))
    steady = sp.nsolve([-a * (eps + sigma0 * s) + d, -k * s + U * delta * eps / ((eps + sigma0 * s) ** 2 + delta ** 2)],
                       [eps, s], [1e-4, 0.0])
    assert abs(float(steady[0])) < eps_bound < 2e-3
    assert all(ok for _, ok, _ in verify_document(build_document(result)))


# -- candidate: the user's V ---------------------------------------------------------------------

def test_candidate_level_never_exceeds_the_true_supremum_and_reaches_it_within_one_percent() -> None:
    """``x' = -x + x y^2, y' = -y`` with ``V = x^2 + y^2``: ``V' = -2x^2 - 2y^2 + 2x^2y^2``, first
    zero on a level set at ``x^2 = y^2 = 2``, so the supremum of the certifiable level is 4."""
    result = run(model_text(["x", "y"], {"x": "-x + x*y**2", "y": "-y"}), classes="candidate",
                 candidate="x**2 + y**2")
    cand = result.results["candidate"]
    assert cand.status == "certified" and cand.proves() == "ROA"
    level = Fraction(cand.certificate["level"])
    assert Fraction(396, 100) <= level < 4
    assert all(ok for _, ok, _ in verify_document(build_document(result)))


def test_candidate_in_one_dimension_reaches_the_supremum() -> None:
    result = run(model_text(["x"], {"x": "-x + x**3"}), classes="candidate", candidate="x**2")
    level = Fraction(result.results["candidate"].certificate["level"])
    assert Fraction(99, 100) <= level < 1  # V' = -2x^2 (1 - x^2) < 0 exactly on 0 < x^2 < 1


def test_candidate_level_set_states_its_share_of_the_simulated_region() -> None:
    """``x' = -x + x^3`` converges exactly from ``|x| < 1``; ``V = x^2``'s certified set ``{x^2 <= c}``,
    ``c`` just below 1, holds nearly all the converging starts of the domain ``[-2, 2]`` (issue 42, item 5:
    the polynomial ``candidate`` states its size as ``roa`` does), and none of them fails to converge."""
    text = model_text(["x"], {"x": "-x + x**3"}) + "[domain]\nx = [-2, 2]\n"
    cand = run(text, classes="candidate", candidate="x**2").results["candidate"]
    assert cand.status == "certified" and cand.proves() == "ROA"
    level = float(Fraction(cand.certificate["level"]))
    assert cand.numbers["simulated_starts"] > 0
    assert 0.25 < cand.numbers["simulated_roa_share_of_domain"] < 0.75  # about half of [-2, 2] converges
    # the starts in (-sqrt(c), sqrt(c)) over those in (-1, 1): about sqrt(c), up to the grid's spacing
    assert abs(cand.numbers["roa_share"] - level ** 0.5) < 0.05
    assert "starts_in_set_not_converged" not in cand.numbers  # every start of the set converged at once


def test_candidate_that_decreases_everywhere_is_gas() -> None:
    result = certify_model(load_model(MODELS / "fossil-poly2.toml"), classes="candidate", candidate="x**2 + y**2")
    cand = result.results["candidate"]
    assert cand.status == "certified" and cand.proves() == "GAS"
    assert "simulated_starts" not in cand.numbers  # (GAS: no set to simulate, no time spent on one)


def test_candidate_that_is_not_positive_definite_is_not_certified() -> None:
    result = run(model_text(["x", "y"], {"x": "-x", "y": "-y"}), classes="candidate", candidate="x**2 - y**2")
    assert result.results["candidate"].status == "not_certified"


# -- denominators -------------------------------------------------------------------------------

def test_a_denominator_of_changing_sign_makes_the_field_classes_not_applicable() -> None:
    result = run(model_text(["x"], {"x": "-x/(x**2 - 4)"}))
    assert result.results["linearization"].status == "refuted"  # J = 1/4 > 0, exactly
    for name in ("quadratic", "sos_gas", "roa"):
        r = result.results[name]
        assert r.status == "not_applicable" and "x**2 - 4" in r.summary


def test_a_negative_denominator_moves_its_sign_into_the_numerator() -> None:
    """``x/(-1 - x^2)`` is read as ``-x/(1 + x^2)`` (denominators are kept with a positive leading
    coefficient), whose denominator is then proved positive: the field is GAS."""
    result = run(model_text(["x"], {"x": "x/(-1 - x**2)"}), classes="quadratic")
    assert result.results["quadratic"].status == "certified"
    assert [(d["denominator"], d["sign"]) for d in result.denominators] == [("x**2 + 1", 1)]


# -- verify and limits ---------------------------------------------------------------------------

@pytest.fixture(scope="module")
def vdp_document() -> dict[str, Any]:
    return build_document(certify_model(load_model(MODELS / "drake-cubic-polynomial.toml")))


def test_verify_fails_when_the_text_a_coefficient_or_the_level_changes(vdp_document: dict[str, Any]) -> None:
    assert all(ok for _, ok, _ in verify_document(vdp_document))
    roa = vdp_document["conditions"]["roa"]
    assert roa["status"] == "certified"

    text = copy.deepcopy(vdp_document)
    text["model"]["text"] = text["model"]["text"].replace("x**3", "x**3 + 0")
    assert not all(ok for _, ok, _ in verify_document(text))

    level = copy.deepcopy(vdp_document)
    lv = Fraction(level["conditions"]["roa"]["certificate"]["level"]) * Fraction(1001, 1000)
    level["conditions"]["roa"]["certificate"]["level"] = level["conditions"]["roa"]["certificate"]["level_scaled"] = str(lv)
    assert not all(ok for _, ok, _ in verify_document(level))

    coefficient = copy.deepcopy(vdp_document)
    terms = coefficient["conditions"]["roa"]["certificate"]["V"]["terms"]
    terms[0][0] = str(Fraction(terms[0][0]) * 2)
    assert not all(ok for _, ok, _ in verify_document(coefficient))

    gram = copy.deepcopy(vdp_document)
    Q = gram["conditions"]["roa"]["certificate"]["gram_sigma"]["Q"]
    Q[0][0] = str(Fraction(Q[0][0]) + 1)
    assert not all(ok for _, ok, _ in verify_document(gram))

    claim = copy.deepcopy(vdp_document)
    claim["conditions"]["roa"]["level"] = float(Fraction(roa["certificate"]["level"])) * 1.01
    assert not all(ok for _, ok, _ in verify_document(claim))


def test_every_class_is_bounded_in_time_and_the_others_still_run() -> None:
    """A limit already reached stops every search class at its first check (a limit of 1 ms did not
    on a fast machine with warm caches: quadratic's one solve began inside it and ended
    not_certified, which is its honest answer); a limit reached mid-search stops roa's iteration
    (about 3 s here) soon after it, and the classes after it still run."""
    vdp = load_model(MODELS / "van-der-pol-reversed.toml")
    result = certify_model(vdp, time_limit_s=0)
    assert result.results["linearization"].status == "certified"  # exact, no search
    for name in ("quadratic", "sos_gas", "roa"):
        r = result.results[name]
        assert r.status == "inconclusive" and "MODEL_CLASS_TIME_LIMIT_S" in " ".join(r.numbers["detail"])
        assert "time limit" in r.summary and "--time-limit" in r.summary
    result = certify_model(vdp, classes=("roa", "linearization"), time_limit_s=0.2)
    roa = result.results["roa"]
    assert roa.status == "inconclusive" and "MODEL_CLASS_TIME_LIMIT_S" in " ".join(roa.numbers["detail"])
    assert "--time-limit" in roa.summary
    # (how soon after the limit a class stops is tests/test_time_limits.py's, in CPU time: no wall time here)
    assert result.results["linearization"].status == "certified"
