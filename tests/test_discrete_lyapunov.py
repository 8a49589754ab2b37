"""``quadratic`` and ``sos_gas`` on a discrete-time map (:mod:`lyapcheck.models.classes.discrete_lyapunov`).

Every certificate is re-checked here independently of the module's own exact check: the map is
read with sympy from the test's own strings, ``V`` and ``W`` are rebuilt from the certificate's
Gram matrices, ``V - V(F) - mu V = W`` is compared symbolically and both Gram matrices are tested
positive definite by sympy; iterating the map from random starts must decrease ``V`` and, for GES,
stay below ``k |e_0| r^k``. Maps that are not globally stable (a critical linearization, an
unstable one, a map that diverges far out) must never be certified, and the same polynomials read
as an ODE must give the continuous answer, not the map's.
"""

from __future__ import annotations

import copy
from fractions import Fraction
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import sympy as sp

from lyapcheck.models.classes import discrete_lyapunov as dl
from lyapcheck.models.language.modelfile import load_model, parse_model
from tests.conftest import ROOT
from lyapcheck.models.loop.field import ShiftedField, shifted_field
from lyapcheck.results import ConditionResult

DATA = Path(__file__).resolve().parent / "data"


def map_of(dynamics: dict[str, str]) -> ShiftedField:
    """The shifted map of a model file whose [dynamics] are read as next values (parsed as a
    continuous model: the polynomials are the same; the equilibrium is 0, a fixed point of both)."""
    states = list(dynamics)
    lines = ["[model]", f"states = {states!r}".replace("'", '"'), "[dynamics]"]
    lines += [f'{k} = "{v}"' for k, v in dynamics.items()]
    return shifted_field(parse_model("\n".join(lines) + "\n", "<test>"))


def sympy_map(dynamics: dict[str, str]) -> tuple[list[sp.Symbol], list[sp.Expr]]:
    symbols = sp.symbols(list(dynamics))
    local = dict(zip(dynamics, symbols))
    return list(symbols), [sp.nsimplify(sp.sympify(v, locals=local), rational=True) for v in dynamics.values()]


def gram(symbols: list[sp.Symbol], data: dict[str, Any]) -> tuple[sp.Expr, sp.Matrix]:
    z = sp.Matrix([sp.Mul(*[s ** e for s, e in zip(symbols, m)]) for m in data["basis"]])
    Q = sp.Matrix([[sp.Rational(x) for x in row] for row in data["Q"]])
    return sp.expand((z.T * Q * z)[0, 0]), Q


def independent_check(dynamics: dict[str, str], result: ConditionResult) -> tuple[sp.Expr, list[sp.Symbol]]:
    """The certificate re-checked with sympy alone; returns ``V`` (declared states) and the states."""
    symbols, F = sympy_map(dynamics)
    cert = result.certificate
    V, Qv = gram(symbols, cert["gram_V"])
    W, Qw = gram(symbols, cert["gram_W"])
    mu = sp.Rational(cert["mu"])
    assert 0 <= mu < 1
    assert Qv.is_positive_definite and Qw.is_positive_definite
    V_next = V.subs(dict(zip(symbols, F)), simultaneous=True)
    assert sp.expand(V - V_next - mu * V - W) == 0
    stated = sum(sp.Rational(c) * sp.Mul(*[s ** e for s, e in zip(symbols, m)]) for c, m in cert["V"]["terms"])
    assert sp.expand(stated - V) == 0
    # a pure power of every state in both bases: V radially unbounded, V(F) < V away from 0
    for data in (cert["gram_V"], cert["gram_W"]):
        for i in range(len(symbols)):
            assert any(m[i] > 0 and sum(m) == m[i] for m in data["basis"])
    return V, symbols


def iterate(dynamics: dict[str, str], starts: np.ndarray, steps: int) -> np.ndarray:
    symbols, F = sympy_map(dynamics)
    step = sp.lambdify(symbols, F, "numpy")
    out = [starts]
    x = starts
    for _ in range(steps):
        x = np.array(step(*x.T), dtype=float).T
        out.append(x)
    return np.array(out)


LINEAR = {"x": "0.5*x + 0.4*y", "y": "-0.3*x + 0.6*y"}
TRIANGULAR = {"x": "0.5*x + 0.2*y**2", "y": "0.5*y"}


def test_stable_linear_map_is_ges_with_a_rate_above_its_spectral_radius() -> None:
    result = dl.run(map_of(LINEAR), "quadratic")
    assert result.status == "certified" and result.proves() == "GES"
    assert result.certificate["kind"] == dl.QUADRATIC_KIND and result.certificate["time"] == "discrete"
    assert "discrete-time map" in result.summary
    V, symbols = independent_check(LINEAR, result)
    k, r = Fraction(result.certificate["k"]), Fraction(result.certificate["r"])
    A = np.array([[0.5, 0.4], [-0.3, 0.6]])
    rho = max(abs(np.linalg.eigvals(A)))
    assert rho <= float(r) < 1  # a rate can never beat the spectral radius
    # the Stein inequality: P - A'PA > 0 for V = e'Pe, exactly
    P = sp.hessian(V, symbols) / 2
    Aq = sp.Matrix([[sp.Rational(1, 2), sp.Rational(2, 5)], [sp.Rational(-3, 10), sp.Rational(3, 5)]])
    assert (P - Aq.T * P * Aq).is_positive_definite
    # the claim on trajectories: |e_k| <= k |e_0| r^k
    rng = np.random.default_rng(7)
    path = iterate(LINEAR, rng.normal(size=(50, 2)) * 10, 30)
    norms = np.linalg.norm(path, axis=2)
    bound = float(k) * norms[0] * float(r) ** np.arange(31)[:, None]
    assert np.all(norms <= bound * (1 + 1e-12))


def test_stable_nonlinear_map_is_gas_by_sos_and_not_by_a_quadratic() -> None:
    shifted = map_of(TRIANGULAR)
    assert dl.run(shifted, "quadratic").status == "not_certified"  # V(F) has degree 4 > 2: no global quadratic
    result = dl.run(shifted, "sos_gas")
    assert result.status == "certified" and result.proves() == "GAS"
    assert result.certificate["kind"] == dl.SOS_KIND and result.numbers["degree"] == 4
    V, symbols = independent_check(TRIANGULAR, result)
    values = sp.lambdify(symbols, V, "numpy")
    rng = np.random.default_rng(11)
    path = iterate(TRIANGULAR, rng.normal(size=(40, 2)) * 5, 8)
    v = np.array([values(*p.T) for p in path])
    assert np.all(v[1:] < v[:-1])


@pytest.mark.parametrize("dynamics,why", [
    ({"x": "x - x**3", "y": "0.5*y"}, "a critical linearization (eigenvalue 1), and x = 2 escapes"),
    ({"x": "1.1*x + y**2", "y": "0.5*y"}, "unstable: eigenvalue 1.1"),
    ({"x": "-x + 0.1*y", "y": "0.2*y"}, "eigenvalue -1: not asymptotically stable"),
])
def test_maps_that_are_not_gas_are_never_certified(dynamics: dict[str, str], why: str) -> None:
    shifted = map_of(dynamics)
    for name in ("quadratic", "sos_gas"):
        assert dl.run(shifted, name).status == "not_certified", why


def test_tampered_certificates_fail_verify() -> None:
    shifted = map_of(LINEAR)
    data = dl.run(shifted, "quadratic").to_json()
    assert dl.verify(shifted, "certified", data)[0]
    tampered = []
    worse = copy.deepcopy(data)  # a faster rate than proved
    worse["certificate"]["r"] = str(Fraction(data["certificate"]["r"]) / 2)
    tampered.append(worse)
    entry = copy.deepcopy(data)  # one Gram entry changed: the identity breaks
    entry["certificate"]["gram_V"]["Q"][0][0] = str(Fraction(entry["certificate"]["gram_V"]["Q"][0][0]) * 2)
    tampered.append(entry)
    words = copy.deepcopy(data)  # the sentence of another claim
    words["summary"] = words["summary"].replace("|e_0|", "|e_0|^2")
    tampered.append(words)
    prop = copy.deepcopy(data)
    prop["property"] = "ISS"
    tampered.append(prop)
    figure = copy.deepcopy(data)  # a stated figure better than the certificate's
    figure["contraction_per_step"] = data["contraction_per_step"] / 2
    tampered.append(figure)
    kind = copy.deepcopy(data)  # a continuous-time kind is not a map's certificate
    kind["certificate"]["kind"] = "lyapunov"
    tampered.append(kind)
    for bad in tampered:
        assert not dl.verify(shifted, "certified", bad)[0]
    # the certificate of one map is not one of another
    assert not dl.verify(map_of({"x": "0.5*x + 0.5*y", "y": "-0.3*x + 0.6*y"}), "certified", data)[0]


def test_the_continuous_reading_of_the_same_polynomials_answers_differently() -> None:
    from lyapcheck.models.surfaces.certify import certify_model

    def continuous(dynamics: dict[str, str]) -> dict[str, str]:
        lines = ["[model]", f"states = {list(dynamics)!r}".replace("'", '"'), "[dynamics]"]
        lines += [f'{k} = "{v}"' for k, v in dynamics.items()]
        out = certify_model(parse_model("\n".join(lines) + "\n", "<test>"), classes="linearization,quadratic")
        return {name: r.status for name, r in out.results.items()}

    # a contraction as a map (|eigenvalues| 1/2), unstable as an ODE (eigenvalues +1/2)
    halving = {"x": "0.5*x", "y": "0.5*y"}
    assert dl.run(map_of(halving), "quadratic").status == "certified"
    assert continuous(halving) == {"linearization": "refuted", "quadratic": "not_certified"}
    # stable as an ODE (eigenvalues -2, -3), unstable as a map (|eigenvalues| > 1)
    fast = {"x": "-2*x", "y": "-3*y + x"}
    assert continuous(fast)["quadratic"] == "certified"
    for name in ("quadratic", "sos_gas"):
        assert dl.run(map_of(fast), name).status == "not_certified"


def test_fossil_discrete_time_benchmarks() -> None:
    """FOSSIL 2.0's discrete-time rows (tests/data/fossil-dt-*.toml): TwoRoomTemp is GES (quadratic),
    DTAhmadi GAS (a quartic V; no quadratic one exists), DTAhmadi2 is not globally stable."""
    room = shifted_field(load_model(DATA / "fossil-dt-two-room-temp.toml"))
    result = dl.run(room, "quadratic")
    assert result.status == "certified" and result.proves() == "GES"
    independent_check({"e1": "0.725*e1 + 0.25*e2", "e2": "0.25*e1 + 0.71*e2"}, result)
    ahmadi = shifted_field(load_model(DATA / "fossil-dt-ahmadi.toml"))
    assert dl.run(ahmadi, "quadratic").status == "not_certified"
    result = dl.run(ahmadi, "sos_gas")
    assert result.status == "certified" and result.numbers["degree"] == 4
    independent_check({"x": "0.3*x", "y": "-x + 0.5*y + 7/18*x**2"}, result)
    far = iterate({"x": "0.687*x + 0.558*y - 0.0001*x*y", "y": "-0.292*x + 0.773*y"}, np.array([[1e5, 1e5]]), 6)
    norms = np.linalg.norm(far[:, 0], axis=1)
    assert np.all(np.diff(norms) > 0) and norms[-1] > 1e13 * norms[0]  # diverges: no global certificate exists
    ahmadi2 = shifted_field(load_model(DATA / "fossil-dt-ahmadi2.toml"))
    for name in ("quadratic", "sos_gas"):
        assert dl.run(ahmadi2, name).status == "not_certified"


def test_programs_are_dpp_and_one_structure_serves_every_decay_rate() -> None:
    from lyapcheck.sos.program import build_cvxpy

    ring, F = dl.map_polynomials(map_of(TRIANGULAR))
    built = dl.discrete_program(ring, F, 4, dl.symmetry(ring, F))
    assert not isinstance(built, str)
    structure, alphas = built
    problem, params, _ = build_cvxpy(structure)
    assert problem.is_dpp()
    # the decay rate enters only the parameters: their values at two rates differ, the structure not
    a, b = dl.decrease_values(ring, F, alphas, Fraction(0)), dl.decrease_values(ring, F, alphas, Fraction(1, 2))
    assert set(a.exact) == set(b.exact) == set(params) and a.exact != b.exact


def test_a_map_with_a_state_dependent_denominator_is_not_applicable() -> None:
    result = dl.run(map_of({"x": "0.5*x/(1 + y**2)", "y": "0.5*y"}), "sos_gas")
    assert result.status == "not_applicable" and "denominator" in result.summary


@pytest.mark.parametrize("example, certified", [("fossil-dt-two-room-temp", ("linearization", "quadratic", "sos_gas")),
                                                ("fossil-dt-ahmadi", ("linearization", "sos_gas"))])
def test_the_fossil_examples_certify_as_their_comments_say_and_verify(example: str, certified: tuple[str, ...]) -> None:
    """FOSSIL 2.0's discrete-time rows as shipped examples ([model] time = "discrete"): TwoRoomTemp in
    temperatures with its fixed point at 15 degrees (GES), DTAhmadi GAS with a quartic V and no quadratic one."""
    from lyapcheck.api import certify, verify

    result = certify(model=ROOT / "examples" / "models" / f"{example}.toml")
    statuses = {name: c["status"] for name, c in result.document["conditions"].items()}
    assert {name for name, status in statuses.items() if status == "certified"} == set(certified)
    assert result.document["verdict"] == "certified"
    if "quadratic" in certified:
        assert result.document["conditions"]["quadratic"]["property"] == "GES"
        assert result.document["conditions"]["quadratic"]["certificate"]["kind"] == "discrete_quadratic"
    else:
        assert statuses["quadratic"] == "not_certified"
        assert result.document["conditions"]["sos_gas"]["certificate"]["degree"] == 4
    assert verify(result.document).valid


def test_sos_gas_on_a_map_takes_certify_s_degree() -> None:
    """``--degree`` caps a map's sos_gas ladder as every other sos_gas search (its not_certified sentence
    suggests it): DTAhmadi, proved with a quartic V, is not proved at degree 2 alone, and only degree 2 was
    tried; with the default ladder it is certified."""
    from lyapcheck.degrees import degree_ceiling
    from lyapcheck.models.loop.discrete import shifted_map

    shifted = shifted_map(load_model(ROOT / "examples" / "models" / "fossil-dt-ahmadi.toml"))
    with degree_ceiling(2):
        capped = dl.run(shifted, "sos_gas")
    assert capped.status == "not_certified"
    assert [line.split(":")[0] for line in capped.numbers["tried"]] == ["degree 2"]
    assert dl.run(shifted, "sos_gas").status == "certified"
