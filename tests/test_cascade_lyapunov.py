"""The cascade form of ``sos_gas`` (issue 43): one ISS-Lyapunov function per subsystem of a network whose
subsystems form a cascade (:mod:`lyapcheck.models.classes.cascade_lyapunov`): the groups in a topological
order, the exact check on a hand-made certificate and its refusals, a certified chain re-checked by
``verify`` and refused once forged, a strongly connected network left to the other forms, a cascade with an
unstable downstream block not certified, and the cubic-drag platoon, where no certificate of this form
exists (the module's and the benchmark's notes say why)."""

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
def chain(tmp_path_factory: pytest.TempPathFactory) -> dict:
    with pytest.MonkeyPatch.context() as mp:
        return certify(CHAIN.format(damping="1"), tmp_path_factory.mktemp("chain"), mp)


def hand_made() -> tuple[StateField, list[list[int]], list[GramPoly], list[GramPoly], list[GramPoly | None],
                         list[GramPoly]]:
    """``x' = -x``, ``y' = -y + x^2``: ``V_1 = W_1 = x^2`` (``sigma_1 = x^2``), ``V_2 = W_2 = y^2``,
    ``R_2 = x^4`` (``sigma_2 = x^4 - y^2 + 2 y^2 - 2 x^2 y = (x^2 - y)^2``)."""
    ring = Ring(("x", "y"))
    x, y = ring.gens()
    field = StateField(ring, (-x, -y + x**2), ring.constant(1))
    one = ((Fraction(1),),)
    Vs = [GramPoly(((1, 0),), one), GramPoly(((0, 1),), one)]
    Ws = list(Vs)
    Rs: list[GramPoly | None] = [None, GramPoly(((2, 0),), one)]
    square = ((Fraction(1), Fraction(-1)), (Fraction(-1), Fraction(1)))
    sigmas = [GramPoly(((1, 0),), one), GramPoly(((2, 0), (0, 1)), square)]
    return field, [[0], [1]], Vs, Ws, Rs, sigmas


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
    field, groups, Vs, Ws, Rs, sigmas = hand_made()
    ring, g, D = field.ring, field.g, field.D
    ok, why = cascade_lyapunov.check_cascade(ring, g, D, groups, Vs, Ws, Rs, sigmas)
    assert ok, why
    # a V_i's entry changed: the identity fails
    bent = GramPoly(((0, 1),), ((Fraction(11, 10),),))
    ok, why = cascade_lyapunov.check_cascade(ring, g, D, groups, [Vs[0], bent], Ws, Rs, sigmas)
    assert not ok and "dissipation identity of group 2" in why
    # the groups reordered: the first one reads a later one's state
    ok, why = cascade_lyapunov.check_cascade(ring, g, D, groups[::-1], Vs[::-1], Ws[::-1], Rs[::-1], sigmas[::-1])
    assert not ok and "topological" in why
    # an input gain on the first group (it has no earlier group to read)
    ok, why = cascade_lyapunov.check_cascade(ring, g, D, groups, Vs, Ws, [Rs[1], Rs[1]], sigmas)
    assert not ok and "earlier groups only" in why
    # W_2 not positive definite
    zero = GramPoly(((0, 1),), ((Fraction(0),),))
    ok, why = cascade_lyapunov.check_cascade(ring, g, D, groups, Vs, [Ws[0], zero], Rs, sigmas)
    assert not ok and "Q_W2" in why
    # a cycle: x reads y as well; the same certificate is refused whatever the order
    x, y = ring.gens()
    cyclic = (-x + y**2, -y + x**2)
    for order in (1, -1):
        ok, why = cascade_lyapunov.check_cascade(ring, cyclic, D, groups[::order], Vs[::order], Ws[::order],
                                                 Rs[::order], sigmas[::order])
        assert not ok and "topological" in why


def test_a_chain_beyond_the_dense_and_clique_forms_is_certified_by_the_cascade_form(chain: dict) -> None:
    condition = chain["conditions"]["sos_gas"]
    assert condition["status"] == "certified" and condition["property"] == "GAS", condition["summary"]
    cert = condition["certificate"]
    assert cert["kind"] == cascade_lyapunov.KIND
    assert cert["groups"] == [["x1", "y1"], ["x2", "y2"], ["x3", "y3"]]
    assert cert["gram_R"][0] is None and all(r is not None for r in cert["gram_R"][1:])
    assert "cascade of 3 subsystems" in condition["summary"] and "no decay rate" in condition["summary"]
    assert "decay_rate_V_per_s" not in condition
    # each V_i lives on its group's states, each R_i on the previous group's
    for k, (V, R) in enumerate(zip(cert["gram_V"], cert["gram_R"])):
        assert {i for mono in V["basis"] for i, e in enumerate(mono) if e} == {2 * k, 2 * k + 1}
        if R is not None:
            assert {i for mono in R["basis"] for i, e in enumerate(mono) if e} <= {2 * k - 2, 2 * k - 1}


def test_verify_rechecks_the_cascade_and_refuses_forged_certificates(chain: dict, tmp_path: Path) -> None:
    from click.testing import CliRunner

    from lyapcheck.cli import app

    app._register_commands()
    good = tmp_path / "good.json"
    good.write_text(json.dumps(chain))
    result = CliRunner().invoke(app.cli, ["verify", str(good)])
    assert result.exit_code == 0, result.output
    assert "a cascade of ISS subsystems driven by a GAS one, exactly" in result.output

    def forged(change: object) -> str:
        doc = json.loads(json.dumps(chain))
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
        for key in ("groups", "V_groups", "gram_V", "gram_W", "gram_R", "gram_sigma"):
            cert[key][0], cert[key][1] = cert[key][1], cert[key][0]

    assert "topological" in forged(reorder)

    def restate(cert: dict) -> None:
        cert["V_groups"][0] = cert["V_groups"][1]

    assert "V_groups" in forged(restate)


def test_a_cascade_whose_downstream_block_is_unstable_is_not_certified(tmp_path: Path,
                                                                     monkeypatch: pytest.MonkeyPatch) -> None:
    doc = certify(CHAIN.format(damping="-1"), tmp_path, monkeypatch)  # y3' = -x3 + y3 + x2^2: anti-damped
    condition = doc["conditions"]["sos_gas"]
    assert condition["status"] != "certified"
    lines = [line for line in condition["tried"] if line.startswith(cascade_lyapunov.LABEL)]
    assert len(lines) == 1 and "no ISS-Lyapunov function for the subsystem of x3, y3 with inputs x2" in lines[0]


def test_a_strongly_connected_network_does_not_use_the_cascade_form(tmp_path: Path,
                                                                    monkeypatch: pytest.MonkeyPatch) -> None:
    doc = certify(networks.swarm(3), tmp_path, monkeypatch)
    condition = doc["conditions"]["sos_gas"]
    assert condition["certificate"]["kind"] == "lyapunov_vector"
    assert not any(line.startswith(cascade_lyapunov.LABEL) for line in condition.get("tried") or [])


def test_the_cubic_drag_platoon_vehicle_has_no_iss_certificate_of_this_form() -> None:
    """A platoon's following vehicle (``e' = u - w``, ``w' = e + 2 (u - w) - w^3``): ``W >= eps |x|^2`` meets
    the slow manifold ``e = w^3`` where the drag's speed is only ``e^(1/3)``, and no ``V`` of degree 2 to 6
    gives a strictly feasible program (benchmarks/README.md, issue 43); its leader (``u = 0``) is proved."""
    from lyapcheck.models.engines.search import Budget, Search

    ring = Ring(("e", "w", "u"))
    e, w, u = ring.gens()
    follower = StateField(ring, (u - w, e + 2 * (u - w) - w**3), ring.constant(1))
    found, why = cascade_lyapunov.search_group(follower, 2, Search(ring, Budget(60.0, "test")))
    assert found is None and "degree 4" in why and "degree 6" in why
    alone = Ring(("e", "w"))
    e, w = alone.gens()
    leader = StateField(alone, (-w, e - 2 * w - w**3), alone.constant(1))
    found, why = cascade_lyapunov.search_group(leader, 2, Search(alone, Budget(60.0, "test")))
    assert found is not None and found["R"] is None, why
