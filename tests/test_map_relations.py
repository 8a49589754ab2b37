"""``quadratic`` and ``sos_gas`` on a discrete-time map with functions
(:mod:`lyapcheck.models.classes.map_relations`): the shipped example certified GES with its figures re-derived
here, verify, forged certificates refused, a map that is not GES left not_certified with its reason, a size
limit refused quickly."""

from __future__ import annotations

import copy
import math
from fractions import Fraction
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from lyapcheck.models.classes import map_relations
from lyapcheck.models.engines.search import Budget
from lyapcheck.models.language.modelfile import load_any_model, parse_any_model
from lyapcheck.models.language.recast import RecastModel
from lyapcheck.sos.certificates import GramPoly

EXAMPLE = Path(__file__).resolve().parent.parent / "examples" / "models" / "discrete-tanh-map.toml"

NOT_GES = """
[model]
name = "a map that is GAS but not GES"
states = ["x", "y"]
time = "discrete"
source = "test"

[dynamics]
x = "x - 0.1*tanh(x)**3"
y = "0.5*y"
"""


def _map(source: str | Path) -> RecastModel:
    """A map with functions from a file or a text."""
    model = load_any_model(source) if isinstance(source, Path) else parse_any_model(source)
    assert isinstance(model, RecastModel)
    return model


def _budget() -> Budget:
    return Budget(60.0, "test")


@pytest.fixture(scope="module")
def certified() -> tuple[RecastModel, dict[str, Any]]:
    model = _map(EXAMPLE)
    result = map_relations.run(model, "quadratic", _budget())
    assert result.status == "certified", result.summary
    return model, result.to_json()


def _true_map(e: np.ndarray) -> np.ndarray:
    x, y = e
    return np.array([x + 0.1 * y, 0.8 * y - 0.1 * x - 0.2 * np.tanh(x + y)])


def test_quadratic_certifies_ges_with_exact_figures(certified: tuple[RecastModel, dict[str, Any]]) -> None:
    model, data = certified
    cert = data["certificate"]
    assert cert["kind"] == map_relations.KIND and data["property"] == "GES"
    V = GramPoly.from_json(cert["gram_V"], 3)
    P = [[V.Q[V.basis.index(tuple(int(k == i) for k in range(3)))][V.basis.index(tuple(int(k == j) for k in range(3)))]
          for j in range(2)] for i in range(2)]
    mu, c1, c2, k, r = (Fraction(cert[key]) for key in ("mu", "c1", "c2", "k", "r"))
    assert 0 < mu < 1
    # c1 I < P < c2 I (2 x 2: trace and determinant), k^2 >= c2 / c1, r^2 >= 1 - mu, exactly
    for c, sign in ((c1, 1), (c2, -1)):
        M = [[sign * (P[i][j] - c * (i == j)) for j in range(2)] for i in range(2)]
        assert M[0][0] > 0 and M[0][0] * M[1][1] - M[0][1] * M[1][0] > 0
    assert k * k >= c2 / c1 and r * r >= 1 - mu
    # the claim on the true map: V(F(e)) <= (1 - mu) V(e) at sampled points, and the GES bound along orbits
    Pf = np.array([[float(p) for p in row] for row in P])
    rng = np.random.default_rng(0)
    for e in rng.uniform(-50, 50, size=(200, 2)):
        assert _true_map(e) @ Pf @ _true_map(e) <= (1 - float(mu)) * (e @ Pf @ e) * (1 + 1e-9)
    e0 = np.array([3.0, -4.0])
    e = e0.copy()
    for step in range(1, 60):
        e = _true_map(e)
        assert np.linalg.norm(e) <= float(k) * np.linalg.norm(e0) * float(r) ** step * (1 + 1e-9)


def test_verify_passes_and_forgeries_fail(certified: tuple[RecastModel, dict[str, Any]]) -> None:
    model, data = certified
    ok, why = map_relations.verify(model, "quadratic", data)
    assert ok, why
    forged_v = copy.deepcopy(data)
    q = forged_v["certificate"]["gram_V"]
    # one entry of V's Gram matrix changed (and the stated polynomial with it would still not match W)
    row = q["Q"][0] if "Q" in q else None
    assert row is not None
    row[0] = str(Fraction(row[0]) * 2)
    assert not map_relations.verify(model, "quadratic", forged_v)[0]
    forged_mu = copy.deepcopy(data)
    forged_mu["certificate"]["mu"] = str(Fraction(data["certificate"]["mu"]) * 2)
    assert not map_relations.verify(model, "quadratic", forged_mu)[0]
    forged_k = copy.deepcopy(data)
    forged_k["certificate"]["k"] = "1"
    assert not map_relations.verify(model, "quadratic", forged_k)[0]


def test_sos_gas_certifies_gas(certified: tuple[RecastModel, dict[str, Any]]) -> None:
    model, _ = certified
    result = map_relations.run(model, "sos_gas", _budget())
    assert result.status == "certified" and result.property == "GAS"
    assert map_relations.verify(model, "sos_gas", result.to_json())[0]


def test_a_map_that_is_not_ges_is_not_certified() -> None:
    # x+ = x - tanh(x)^3 / 10 converges, but its Jacobian at 0 has the eigenvalue 1: no GES, and V - V(F)
    # grows at most linearly in x for a quadratic V, so no W >= lambda x^2 on the whole line
    model = _map(NOT_GES)
    result = map_relations.run(model, "quadratic", _budget())
    assert result.status == "not_certified"
    assert "no quadratic Lyapunov function" in result.summary and "sos_gas" in result.summary


def test_a_network_map_is_refused_before_its_relations(monkeypatch: pytest.MonkeyPatch) -> None:
    # ysa-pendulum's 68 variables (2 x 32 tanh neurons, sin, cos): refused by a count, before any relation is
    # derived (deriving and shifting its 261 relations took minutes: the count is what keeps it quick)
    def never(*args: Any) -> Any:
        raise AssertionError("the relations were derived")

    monkeypatch.setattr(map_relations, "derived_relations", never)
    model = _map(EXAMPLE.parent / "ysa-pendulum.toml")
    for name in ("quadratic", "sos_gas"):
        result = map_relations.run(model, name, _budget())
        assert result.status == "not_certified"
        assert "too large: 68 variables" in result.summary and "MAP_RELATIONS_VARIABLES" in result.summary


SAT_SIN = """
[model]
name = "a map through saturations and a sine"
states = ["x", "y"]
time = "discrete"
source = "test"

[dynamics]
x = "0.5*x + 0.4*sat(y, 1)"
y = "0.6*y - 0.4*sat(x, 1) + 0.1*sin(x)"
"""


def test_equality_relations_take_free_multipliers() -> None:
    # sat's (u - q)(L^2 - q^2) = 0 and sin^2 + cos^2 = 1 are equalities: their multipliers are free polynomials,
    # and the identity holds on them exactly; the claim is then checked on the true map at sampled points
    model = _map(SAT_SIN)
    result = map_relations.run(model, "quadratic", _budget())
    assert result.status == "certified", result.summary
    data = result.to_json()
    assert map_relations.verify(model, "quadratic", data)[0]
    relations = map_relations.on_relations(model).relations
    lambdas = data["certificate"]["decrease"]["lambdas"]
    assert all(relations[int(i)].kind == "eq" for i in lambdas)
    cert = data["certificate"]
    mu = float(Fraction(cert["mu"]))
    V = GramPoly.from_json(cert["gram_V"], len(cert["variables"]))
    index = [V.basis.index(tuple(int(k == i) for k in range(len(cert["variables"])))) for i in range(2)]
    P = np.array([[float(V.Q[a][b]) for b in index] for a in index])

    def F(e: np.ndarray) -> np.ndarray:
        x, y = e
        return np.array([0.5 * x + 0.4 * np.clip(y, -1, 1), 0.6 * y - 0.4 * np.clip(x, -1, 1) + 0.1 * math.sin(x)])

    for e in np.random.default_rng(1).uniform(-20, 20, size=(300, 2)):
        assert F(e) @ P @ F(e) <= (1 - mu) * (e @ P @ e) * (1 + 1e-9)


def test_a_square_root_of_the_states_is_not_taken() -> None:
    # r^2 = q says nothing where q < 0 (no real r): without a proof that q >= 0 the class claims nothing
    text = SAT_SIN.replace('"0.5*x + 0.4*sat(y, 1)"', '"0.5*x + 0.1*(sqrt(1 + y**2) - 1)"')
    result = map_relations.run(_map(text), "sos_gas", _budget())
    assert result.status == "not_applicable" and "sqrt(1 + y**2)" in result.summary
