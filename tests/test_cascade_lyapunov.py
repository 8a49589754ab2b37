"""The cascade form of ``sos_gas`` (issue 43): one ISS-Lyapunov function per subsystem of a network whose
subsystems form a cascade (:mod:`lyapcheck.models.classes.cascade_lyapunov`): the groups in a topological
order, the exact check on a hand-made certificate and its refusals, the 3-vehicle platoon and a chain
certified, the platoon's certificate re-checked by ``verify`` and refused once forged, a strongly
connected network left to the other forms, a cascade with an unstable downstream block not certified, and
the platoon's follower, ISS in its slow manifold's coordinates only."""

from __future__ import annotations

import json
import sys
from fractions import Fraction
from pathlib import Path

import pytest

from lyapcheck.models.classes import cascade_lyapunov, lyapunov
from lyapcheck.models.loop.field import StateField
from lyapcheck.sos.certificates import GramPoly
from lyapcheck.sos.polynomials import Ring

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "benchmarks"))

import networks  # noqa: E402  (the benchmark's model generators)

#: the dense programs' size limit of tests/test_vector_lyapunov.py: a 6-state network is beyond the dense and
#: clique forms, a 2-state block's program is not
SMALL_COST_LIMIT = 10**6

#: three damped blocks, each driven by the square of the previous block's position: a cascade whose
#: coupling no linear comparison system of quadratic or quartic V_i bounds (x^2 against V_j)
CHAIN = """# three damped blocks, each driven by the square of the previous one's position
[model]
name = "chain of 3 quadratically driven blocks"
states = ["x1", "y1", "x2", "y2", "x3", "y3"]

[dynamics]
x1 = "y1"
y1 = "-x1 - y1"
x2 = "y2"
y2 = "-x2 - y2 + x1**2"
x3 = "y3"
y3 = "-x3 - {damping}*y3 + x2**2"
"""


def certify(text: str, tmp: Path, monkeypatch: pytest.MonkeyPatch, name: str = "model.toml") -> dict:
    """``sos_gas`` with the dense programs' size limit lowered and the cheaper cones taken away (only the
    forms for networks are left to answer)."""
    from lyapcheck import api
    from lyapcheck.models.engines import store

    monkeypatch.setattr(lyapunov, "BLOCK_COST_LIMIT", SMALL_COST_LIMIT)
    monkeypatch.setattr(lyapunov, "FALLBACK_CONES", ())
    path = tmp / name
    path.write_text(text)
    with store.disabled():
        return api.certify(model=path, classes="sos_gas").document


@pytest.fixture(scope="module")
def platoon(tmp_path_factory: pytest.TempPathFactory) -> dict:
    with pytest.MonkeyPatch.context() as mp:
        return certify(networks.platoon(3), tmp_path_factory.mktemp("platoon"), mp)


@pytest.fixture(scope="module")
def chain(tmp_path_factory: pytest.TempPathFactory) -> dict:
    with pytest.MonkeyPatch.context() as mp:
        return certify(CHAIN.format(damping="1"), tmp_path_factory.mktemp("chain"), mp)


def hand_made() -> tuple[StateField, list[list[int]], list[GramPoly], list, list, list[GramPoly | None],
                         list[GramPoly]]:
    """``x' = -x``, ``y' = -y + x^2``: ``V_1 = W_1 = x^2`` (``sigma_1 = x^2``), ``V_2 = W_2 = y^2``,
    ``R_2 = x^4`` (``sigma_2 = x^4 - y^2 + 2 y^2 - 2 x^2 y = (x^2 - y)^2``)."""
    ring = Ring(("x", "y"))
    x, y = ring.gens()
    field = StateField(ring, (-x, -y + x**2), ring.constant(1))
    one = ((Fraction(1),),)
    Vs = [GramPoly(((1, 0),), one), GramPoly(((0, 1),), one)]
    phis = [[(0, x)], [(1, y)]]
    weights = [[Fraction(1)], [Fraction(1)]]
    Rs: list[GramPoly | None] = [None, GramPoly(((2, 0),), one)]
    square = ((Fraction(1), Fraction(-1)), (Fraction(-1), Fraction(1)))
    sigmas = [GramPoly(((1, 0),), one), GramPoly(((2, 0), (0, 1)), square)]
    return field, [[0], [1]], Vs, phis, weights, Rs, sigmas


def test_the_groups_are_the_strong_components_in_a_topological_order() -> None:
    ring = Ring(("a", "b", "c", "d"))
    a, b, c, d = ring.gens()
    # c, d read nothing else; a, b read d: the order puts {c, d} first
    field = StateField(ring, (-a + b, -b - a + d**2, -c + d, -d - c), ring.constant(1))
    assert cascade_lyapunov.cascade_groups(field) == ([(2, 3), (0, 1)], [[], [3]])
    # one strongly connected network (each reads the other): no cascade
    ring2 = Ring(("p", "q"))
    p, q = ring2.gens()
    assert cascade_lyapunov.cascade_groups(StateField(ring2, (-p + q, -q - p), ring2.constant(1))) is None
    # the ring of oscillators: one component, no cascade
    from lyapcheck.models.classes.vector_lyapunov import strong_components

    names = ("q1", "p1", "q2", "p2", "q3", "p3")
    r = Ring(names)
    q1, p1, q2, p2, q3, p3 = r.gens()
    ring3 = StateField(r, (p1, -q1 - p1 + q2 + q3, p2, -q2 - p2 + q1 + q3, p3, -q3 - p3 + q1 + q2), r.constant(1))
    assert len(strong_components(6, [set() for _ in range(6)])) == 6
    assert cascade_lyapunov.cascade_groups(ring3) is None


def test_the_exact_check_accepts_a_true_cascade_and_refuses_each_broken_part() -> None:
    field, groups, Vs, phis, weights, Rs, sigmas = hand_made()
    ring, g, D = field.ring, field.g, field.D
    check = cascade_lyapunov.check_cascade
    ok, why = check(ring, g, D, groups, Vs, phis, weights, Rs, sigmas)
    assert ok, why
    # a V_i's entry changed: the identity fails
    bent = GramPoly(((0, 1),), ((Fraction(11, 10),),))
    ok, why = check(ring, g, D, groups, [Vs[0], bent], phis, weights, Rs, sigmas)
    assert not ok and "dissipation identity of group 2" in why
    # the groups reordered: the first one reads a later one's state
    ok, why = check(ring, g, D, groups[::-1], Vs[::-1], phis[::-1], weights[::-1], Rs[::-1], sigmas[::-1])
    assert not ok and "topological" in why
    # an input gain on the first group (it has no earlier group to read)
    ok, why = check(ring, g, D, groups, Vs, phis, weights, [Rs[1], Rs[1]], sigmas)
    assert not ok and "earlier groups only" in why
    # W_2's weight not positive
    ok, why = check(ring, g, D, groups, Vs, phis, [weights[0], [Fraction(0)]], Rs, sigmas)
    assert not ok and "W_2's weights" in why
    # W_2's coordinate not an automorphism of y fixing 0 (y^2: not radially unbounded as a square root; y + 1)
    x, y = ring.gens()
    for wrong in (y * y, y + ring.constant(1), y + x):
        ok, why = check(ring, g, D, groups, Vs, [phis[0], [(1, wrong)]], weights, Rs, sigmas)
        assert not ok and "triangular" in why, wrong
    # a cycle: x reads y as well; the same certificate is refused whatever the order
    cyclic = (-x + y**2, -y + x**2)
    for order in (1, -1):
        ok, why = check(ring, cyclic, D, groups[::order], Vs[::order], phis[::order], weights[::order], Rs[::order],
                        sigmas[::order])
        assert not ok and "topological" in why


def test_triangular_coordinates_are_checked_in_their_order() -> None:
    ring = Ring(("e", "w"))
    e, w = ring.gens()
    ok, _ = cascade_lyapunov.check_coordinates(ring, [0, 1], [(0, e - w**3 - 2 * w), (1, w)])
    assert ok
    # the same components in the other order: e's coordinate reads w, which comes before it
    ok, why = cascade_lyapunov.check_coordinates(ring, [0, 1], [(1, w), (0, e - w**3)])
    assert not ok and "triangular" in why
    # two coordinates for one state
    ok, why = cascade_lyapunov.check_coordinates(ring, [0, 1], [(0, e), (0, e)])
    assert not ok and "one component per state" in why


def test_the_platoon_beyond_the_dense_and_clique_forms_is_certified_by_the_cascade_form(platoon: dict) -> None:
    condition = platoon["conditions"]["sos_gas"]
    assert condition["status"] == "certified" and condition["property"] == "GAS", condition["summary"]
    cert = condition["certificate"]
    assert cert["kind"] == cascade_lyapunov.KIND
    assert cert["groups"] == [["e1", "w1"], ["e2", "w2"], ["e3", "w3"]]
    assert cert["gram_R"][0] is None and all(r is not None for r in cert["gram_R"][1:])
    assert "cascade of 3 subsystems" in condition["summary"] and "no decay rate" in condition["summary"]
    assert "decay_rate_V_per_s" not in condition
    # each V_i lives on its group's states, each R_i on the previous vehicle's speed (its only input)
    for k, (V, R) in enumerate(zip(cert["gram_V"], cert["gram_R"])):
        assert {i for mono in V["basis"] for i, e in enumerate(mono) if e} == {2 * k, 2 * k + 1}
        if R is not None:
            assert {i for mono in R["basis"] for i, e in enumerate(mono) if e} == {2 * k - 1}
    # the followers' W in their slow manifold's coordinates: the spacing's reads the speed
    for coords in cert["W_coordinates"][1:]:
        assert [state for state, _ in coords] == [coords[0][0], coords[1][0]] and coords[0][0].startswith("e")
        assert any(exps[2 * int(coords[0][0][1:]) - 1] == 3 for _, exps in coords[0][1]["terms"])


def test_a_chain_of_quadratically_driven_blocks_is_certified_by_the_cascade_form(chain: dict) -> None:
    condition = chain["conditions"]["sos_gas"]
    assert condition["status"] == "certified", condition["summary"]
    assert condition["certificate"]["kind"] == cascade_lyapunov.KIND


def test_verify_rechecks_the_cascade_and_refuses_forged_certificates(platoon: dict, tmp_path: Path) -> None:
    from click.testing import CliRunner

    from lyapcheck.cli import app

    app._register_commands()
    good = tmp_path / "good.json"
    good.write_text(json.dumps(platoon))
    result = CliRunner().invoke(app.cli, ["verify", str(good)])
    assert result.exit_code == 0, result.output
    assert "a cascade of ISS subsystems driven by a GAS one, exactly" in result.output

    def forged(change: object) -> str:
        doc = json.loads(json.dumps(platoon))
        change(doc["conditions"]["sos_gas"]["certificate"])  # type: ignore[operator]
        bad = tmp_path / "bad.json"
        bad.write_text(json.dumps(doc))
        out = CliRunner().invoke(app.cli, ["verify", str(bad)])
        assert out.exit_code == 1, out.output
        return out.output

    def bend_v(cert: dict) -> None:
        Q = cert["gram_V"][1]["Q"]
        Q[0][0] = str(Fraction(Q[0][0]) + Fraction(1, 1000))

    assert "dissipation identity of group 2 does not hold exactly" in forged(bend_v)

    def reorder(cert: dict) -> None:
        for key in ("groups", "V_groups", "gram_V", "W_coordinates", "W_weights", "gram_R", "gram_sigma"):
            cert[key][0], cert[key][1] = cert[key][1], cert[key][0]

    assert "topological" in forged(reorder)

    def restate(cert: dict) -> None:
        cert["V_groups"][0] = cert["V_groups"][1]

    assert "V_groups" in forged(restate)

    def untriangular(cert: dict) -> None:
        cert["W_coordinates"][1].reverse()

    assert "triangular" in forged(untriangular)


def test_a_cascade_whose_downstream_block_is_unstable_is_not_certified(tmp_path: Path,
                                                                     monkeypatch: pytest.MonkeyPatch) -> None:
    doc = certify(CHAIN.format(damping="-1"), tmp_path, monkeypatch)  # y3' = -x3 + y3 + x2^2: anti-damped
    condition = doc["conditions"]["sos_gas"]
    assert condition["status"] != "certified"
    lines = [line for line in condition["tried"] if line.startswith(cascade_lyapunov.LABEL)]
    assert len(lines) == 1 and "no ISS-Lyapunov function for the subsystem of x3, y3 with inputs x2" in lines[0]


def test_the_limits_the_page_quotes_are_the_codes() -> None:
    text = (ROOT / "docs" / "model-files.md").read_text()
    assert cascade_lyapunov.CASCADE_DEGREES == (2, 4) and "at degree 2, then 4 (`CASCADE_DEGREES`)" in text
    assert cascade_lyapunov.CASCADE_COST_LIMIT == 2 * 10**9 and "`CASCADE_COST_LIMIT` = 2.0e9" in text


def test_a_strongly_connected_network_does_not_use_the_cascade_form(tmp_path: Path,
                                                                    monkeypatch: pytest.MonkeyPatch) -> None:
    doc = certify(networks.swarm(3), tmp_path, monkeypatch)
    condition = doc["conditions"]["sos_gas"]
    assert condition["certificate"]["kind"] == "lyapunov_vector"
    assert not any(line.startswith(cascade_lyapunov.LABEL) for line in condition.get("tried") or [])


def test_the_platoon_follower_is_iss_in_its_slow_manifold_coordinates_only(monkeypatch: pytest.MonkeyPatch) -> None:
    """A platoon's following vehicle (``e' = u - w``, ``w' = e + 2 (u - w) - w^3``): with ``W >= eps |x|^2``
    (the states themselves) no ``V`` of degree 2 or 4 gives a certificate (the drag's speed at a large
    spacing is ``e^(1/3)``); with ``W = c_1 (e - 2 w - w^3)^2 + c_2 w^2`` a quartic ``V`` does."""
    from lyapcheck.models.engines.search import Budget, Search

    ring = Ring(("e", "w", "u"))
    e, w, u = ring.gens()
    follower = StateField(ring, (u - w, e + 2 * (u - w) - w**3), ring.constant(1))
    choices = cascade_lyapunov.coordinates(follower, 2)
    assert choices == [[(0, e - w**3 - 2 * w), (1, w)], [(0, e), (1, w)]]
    found, why = cascade_lyapunov.search_group(follower, 2, Search(ring, Budget(60.0, "test")))
    assert found is not None and found["phi"] == choices[0] and found["degree"] == 4, why
    assert found["R"] is not None and all(m[:2] == (0, 0) for m in found["R"].basis)
    monkeypatch.setattr(cascade_lyapunov, "coordinates", lambda sub, k: [[(i, sub.ring.gens()[i]) for i in range(k)]])
    found, why = cascade_lyapunov.search_group(follower, 2, Search(ring, Budget(60.0, "test")))
    assert found is None and "degree 2" in why and "degree 4" in why
