"""The compositional form of ``sos_gas`` (issue 43): a vector Lyapunov function with an exactly checked
comparison system (:mod:`lyapcheck.models.classes.vector_lyapunov`): the subsystems, the exact check,
``verify``'s re-check and its refusal of a changed certificate, and a network whose comparison matrix
cannot be Hurwitz left uncertified."""

from __future__ import annotations

import json
import sys
from fractions import Fraction
from pathlib import Path

import pytest

from lyapcheck.models.classes import lyapunov, vector_lyapunov
from lyapcheck.sos.certificates import GramPoly
from lyapcheck.sos.polynomials import Ring

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "benchmarks"))

import networks  # noqa: E402  (the benchmark's model generators)

#: a dense program's size limit low enough that the dense and clique forms of a 6-state network exceed it,
#: and high enough for a 2-state subsystem's quartic V (its program costs about 1e5)
SMALL_COST_LIMIT = 10**6


def certify(path: Path, monkeypatch: pytest.MonkeyPatch) -> dict:
    """``sos_gas`` on ``path`` with the dense programs' size limit at :data:`SMALL_COST_LIMIT` (a network
    beyond the dense and the clique forms, at a size that solves in seconds)."""
    from lyapcheck import api
    from lyapcheck.models.engines import store

    monkeypatch.setattr(lyapunov, "BLOCK_COST_LIMIT", SMALL_COST_LIMIT)
    with store.disabled():
        return api.certify(model=path, classes="sos_gas").document


@pytest.fixture(scope="module")
def swarm6(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, dict]:
    path = tmp_path_factory.mktemp("swarm") / "swarm6.toml"
    path.write_text(networks.swarm(3))
    with pytest.MonkeyPatch.context() as mp:
        return path, certify(path, mp)


def test_the_subsystems_are_the_strong_components_or_the_position_velocity_pairs() -> None:
    from lyapcheck.models.loop.field import StateField

    ring = Ring(("e1", "w1", "e2", "w2", "e3", "w3"))
    e1, w1, e2, w2, e3, w3 = ring.gens()
    # a cascade (the platoon): each vehicle reads the one ahead, not the one behind
    cascade = StateField(ring, (-w1, e1 - w1, w1 - w2, e2 + w1 - w2, w2 - w3, e3 + w2 - w3), ring.constant(1))
    assert vector_lyapunov.subsystem_groups(cascade) == [(0, 1), (2, 3), (4, 5)]
    # one strongly connected network (a ring of oscillators): the pairs q' = p
    coupled = StateField(ring, (w1, -e1 - w1 + e2 + e3, w2, -e2 - w2 + e1 + e3, w3, -e3 - w3 + e1 + e2), ring.constant(1))
    assert vector_lyapunov.subsystem_groups(coupled) == [(0, 1), (2, 3), (4, 5)]
    # no partition into small groups: none
    dense = StateField(Ring(("a", "b")), (Ring(("a", "b")).gens()[1], -Ring(("a", "b")).gens()[0]), Ring(("a", "b")).constant(1))
    assert vector_lyapunov.subsystem_groups(dense) is None


def test_a_network_beyond_the_dense_and_clique_forms_is_certified_by_a_vector_lyapunov_function(
        swarm6: tuple[Path, dict]) -> None:
    _, doc = swarm6
    condition = doc["conditions"]["sos_gas"]
    assert condition["status"] == "certified" and condition["property"] == "GAS", condition["summary"]
    cert = condition["certificate"]
    assert cert["kind"] == vector_lyapunov.KIND
    assert cert["groups"] == [["q1", "p1"], ["q2", "p2"], ["q3", "p3"]]
    assert "a vector Lyapunov function, 3" in condition["summary"] and "Metzler" in condition["summary"]
    assert condition["decay_rate_V_per_s"] > 0
    tried = condition["solver"]
    assert tried  # the dense and clique forms were tried first (and reached the lowered size limit)


def test_the_certificate_passes_its_exact_check_and_its_parts_mean_what_they_say(swarm6: tuple[Path, dict]) -> None:
    _, doc = swarm6
    cert = doc["conditions"]["sos_gas"]["certificate"]
    A = [[Fraction(x) for x in row] for row in cert["A"]]
    d = [Fraction(x) for x in cert["d"]]
    m = len(d)
    assert all(A[i][j] >= 0 for i in range(m) for j in range(m) if i != j)  # Metzler
    assert all(x > 0 for x in d)
    column = [sum(d[i] * A[i][j] for i in range(m)) for j in range(m)]
    assert all(c < 0 for c in column)  # d^T A < 0: W = d^T v decreases
    assert Fraction(cert["mu_scaled"]) == min(-c / dj for c, dj in zip(column, d))
    # each V_i lives on its own group's states
    for k, part in enumerate(cert["gram_V"]):
        used = {i for mono in part["basis"] for i, e in enumerate(mono) if e}
        assert used == {2 * k, 2 * k + 1}


def test_the_exact_check_refuses_a_comparison_matrix_that_is_not_hurwitz_or_not_metzler() -> None:
    from lyapcheck.models.loop.field import StateField

    ring = Ring(("x", "y"))
    x, y = ring.gens()
    field = StateField(ring, (-x + y, -y), ring.constant(1))  # x' = -x + y, y' = -y
    one = ((Fraction(1),),)
    Vs = [GramPoly(((1, 0),), one), GramPoly(((0, 1),), one)]  # V1 = x^2, V2 = y^2
    # V1' = -2x^2 + 2xy <= -x^2 + y^2 = -V1 + V2, V2' = -2 V2: A = [[-1, 1], [0, -2]], d = (1, 1)
    A = [[Fraction(-1), Fraction(1)], [Fraction(0), Fraction(-2)]]
    d = [Fraction(1), Fraction(1)]
    sigma1 = GramPoly(((1, 0), (0, 1)), ((Fraction(1), Fraction(-1)), (Fraction(-1), Fraction(1))))  # (x - y)^2
    sigma2 = GramPoly(((0, 1),), ((Fraction(0),),))
    groups = [(0,), (1,)]
    ok, why = vector_lyapunov.check_vector_lyapunov(ring, field.g, field.D, groups, Vs, A, d, [[sigma1], [sigma2]])
    assert ok, why
    # the same identities with d = (1, 1/4): d^T A = (-1, 1/2), not < 0 (d_2 scales identity 2's remainder)
    quarter = [Fraction(1), Fraction(1, 4)]
    ok, why = vector_lyapunov.check_vector_lyapunov(ring, field.g, field.D, groups, Vs, A, quarter, [[sigma1], [sigma2]])
    assert not ok and "Hurwitz" in why
    # a negative coupling entry: not Metzler
    bad = [[Fraction(-1), Fraction(1)], [Fraction(-1, 10), Fraction(-2)]]
    ok, why = vector_lyapunov.check_vector_lyapunov(ring, field.g, field.D, groups, Vs, bad, d, [[sigma1], [sigma2]])
    assert not ok and "Metzler" in why
    # a V_i that reads another group's state
    crossed = [GramPoly(((1, 0), (0, 1)), ((Fraction(1), Fraction(0)), (Fraction(0), Fraction(1)))), Vs[1]]
    ok, why = vector_lyapunov.check_vector_lyapunov(ring, field.g, field.D, groups, crossed, A, d, [[sigma1], [sigma2]])
    assert not ok and "its group only" in why


def test_verify_rechecks_the_vector_form_and_refuses_a_changed_certificate(swarm6: tuple[Path, dict],
                                                                           tmp_path: Path) -> None:
    from click.testing import CliRunner

    from lyapcheck.cli import app

    app._register_commands()
    _, doc = swarm6
    good = tmp_path / "good.json"
    good.write_text(json.dumps(doc))
    result = CliRunner().invoke(app.cli, ["verify", str(good)])
    assert result.exit_code == 0, result.output
    assert "A Metzler with d^T A < 0" in result.output
    # a coupling entry changed: the comparison identity no longer holds
    changed = json.loads(json.dumps(doc))
    A = changed["conditions"]["sos_gas"]["certificate"]["A"]
    A[0][1] = str(Fraction(A[0][1]) + Fraction(1, 1000))
    bad = tmp_path / "bad.json"
    bad.write_text(json.dumps(changed))
    result = CliRunner().invoke(app.cli, ["verify", str(bad)])
    assert result.exit_code == 1
    assert "comparison identity of group 1 does not hold exactly" in result.output
    # a stated decay rate above the certified one
    faster = json.loads(json.dumps(doc))
    faster["conditions"]["sos_gas"]["decay_rate_V_per_s"] *= 2
    bad.write_text(json.dumps(faster))
    assert CliRunner().invoke(app.cli, ["verify", str(bad)]).exit_code == 1


def test_a_network_whose_comparison_matrix_cannot_be_hurwitz_is_not_certified_by_it(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """The platoon with cubic drag: no polynomial V of a vehicle decays exponentially at large spacing
    errors (the drag's speed ~ e^(1/3) there), so no V_i' <= a_ii V_i with a_ii < 0 and no Hurwitz A; the
    vector form is tried and refuses, and the condition is not certified by it (nothing else fits the
    lowered size limit, the cheaper cones' fallback and the cascade form taken away: at this size SDSOS
    proves it, and the cascade form, tests/test_cascade_lyapunov.py)."""
    from lyapcheck.models.classes import cascade_lyapunov, lyapunov

    monkeypatch.setattr(lyapunov, "FALLBACK_CONES", ())
    monkeypatch.setattr(cascade_lyapunov, "cascade_groups", lambda field: None)
    path = tmp_path / "platoon6.toml"
    path.write_text(networks.platoon(3))
    doc = certify(path, monkeypatch)
    condition = doc["conditions"]["sos_gas"]
    assert condition["status"] == "not_certified"
    lines = [line for line in condition["tried"] if line.startswith(vector_lyapunov.LABEL)]
    assert len(lines) == 1 and not lines[0].endswith(": found"), lines
    assert "V' <= -mu V, mu > 0, which a Hurwitz comparison matrix needs" in lines[0]


def test_the_report_names_one_matrix_per_subsystem(swarm6: tuple[Path, dict]) -> None:
    from reports.sections.model_file import gram_sizes

    _, doc = swarm6
    sizes = gram_sizes(doc["conditions"]["sos_gas"]["certificate"])
    assert any(s.startswith("gram_V: 3 matrices, one per subsystem") for s in sizes), sizes


def test_the_limits_the_page_quotes_are_the_codes() -> None:
    text = (ROOT / "docs" / "model-files.md").read_text()
    assert vector_lyapunov.MAX_GROUP_STATES == 4 and "at most 4 states (`MAX_GROUP_STATES`" in text
    assert vector_lyapunov.VECTOR_DEGREES == (2, 4) and "at degree 2, then 4 (`VECTOR_DEGREES`)" in text
    assert vector_lyapunov.VECTOR_COST_LIMIT == 4 * 10**9 and "`VECTOR_COST_LIMIT` = 4.0e9" in text
