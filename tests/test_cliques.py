"""Correlative sparsity (issue 43): cliques of the states, Gram bases per clique, the rounding of a
remainder that is a sum of Gram matrices, and ``sos_gas`` in the clique form on a network beyond the
dense form's size limit, checked exactly and re-checked by ``verify``."""

from __future__ import annotations

import json
import sys
from types import SimpleNamespace
from fractions import Fraction
from pathlib import Path

import pytest

from lyapcheck.sos import sparsity
from lyapcheck.sos.certificates import GramPoly, GramSum, check_lyapunov_cliques
from lyapcheck.sos.polynomials import Ring

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "benchmarks"))

import networks  # noqa: E402  (the benchmark's model generators)


def ring_couplings(m: int) -> list[set[int]]:
    """The interaction graph of the ring of ``m`` oscillators: states q_k = 2k, p_k = 2k + 1."""
    out: list[set[int]] = []
    for k in range(m):
        out.append({2 * k + 1})  # q_k' = p_k
        out.append({2 * k, 2 * k + 1, 2 * ((k - 1) % m), 2 * ((k + 1) % m)})  # p_k' = f(q_k, p_k, q_k-1, q_k+1)
    return out


def test_neighbourhood_cliques_of_a_ring_are_small_and_cover_every_coupling() -> None:
    m = 6
    couplings = ring_couplings(m)
    cliques = sparsity.neighbourhood_cliques(2 * m, couplings)
    assert max(len(c) for c in cliques) == 4  # a state and its three neighbours, whatever m is
    for i, js in enumerate(couplings):
        for j in js:
            assert any(i in c and j in c for c in cliques), (i, j)
    assert sorted({i for c in cliques for i in c}) == list(range(2 * m))
    # maximal: no clique inside another
    assert not any(set(a) < set(b) for a in cliques for b in cliques)


def test_chordal_cliques_cover_every_coupling_and_are_a_chordal_completion() -> None:
    import networkx as nx

    m = 5
    couplings = ring_couplings(m)
    cliques = sparsity.chordal_cliques(2 * m, couplings)
    for i, js in enumerate(couplings):
        for j in js:
            assert any(i in c and j in c for c in cliques), (i, j)
    graph = nx.Graph()
    graph.add_nodes_from(range(2 * m))
    for c in cliques:
        graph.add_edges_from((a, b) for a in c for b in c if a < b)
    assert nx.is_chordal(graph)


def test_clique_bases_keep_only_what_a_sum_of_squares_can_use() -> None:
    # p = x0^2 + x0^2 x1^2 + x2^4 over cliques {0, 1} and {1, 2}: x1 alone can appear in no square
    # (2 * x1 = x1^2 is outside the Newton polytope of p), x2^2 can (x2^4 is in p)
    support = [(2, 0, 0), (2, 2, 0), (0, 0, 4)]
    cliques = [(0, 1), (1, 2)]
    candidates = [sparsity.clique_candidates(c, 3, 1, 2) for c in cliques]
    kept = sparsity.reduce_clique_bases(cliques, candidates, support)
    assert (0, 1, 0) not in kept[0] and (0, 1, 0) not in kept[1]
    assert (1, 0, 0) in kept[0] and (1, 1, 0) in kept[0]
    assert (0, 0, 2) in kept[1]
    assert all(all(m[0] == 0 for m in basis) for basis in kept[1:])  # each basis stays in its clique


def test_the_exact_check_of_the_clique_form_needs_every_part_positive_definite() -> None:
    ring = Ring(("x", "y"))
    x, y = ring.gens()
    g = (-x, -y)  # x' = -x, y' = -y
    one = ((Fraction(1),),)
    V = GramSum((GramPoly(((1, 0),), one), GramPoly(((0, 1),), one)))  # x^2 + y^2
    sigma = GramSum((GramPoly(((1, 0),), ((Fraction(2),),)), GramPoly(((0, 1),), ((Fraction(2),),))))
    ok, why = check_lyapunov_cliques(ring, g, ring.constant(1), V, sigma, Fraction(0))
    assert ok, why
    # a part that is only semidefinite is refused (the identity then fails too, but definiteness is checked first)
    bad = GramSum((GramPoly(((1, 0),), ((Fraction(2),),)), GramPoly(((0, 1),), ((Fraction(0),),))))
    ok, why = check_lyapunov_cliques(ring, g, ring.constant(1), V, bad, Fraction(0))
    assert not ok and "positive definite" in why
    # an identity that does not hold
    ok, why = check_lyapunov_cliques(ring, g, ring.constant(1), V, sigma, Fraction(1, 2))
    assert not ok and "identity" in why


def test_rounding_spreads_a_residual_over_every_remainder_gram() -> None:
    """A remainder that is a sum of two Gram matrices over overlapping bases: the exact point
    satisfies the identity exactly, with no entry moved outside the Grams' blocks."""
    from lyapcheck.models.engines.search import one
    from lyapcheck.sos.program import Solution
    from lyapcheck.sos.rounding import exact_point, identity_value
    from lyapcheck.sos.structure import Coefficients, Gram, Identity, Structure, Term

    ring = Ring(("x", "y", "z"))
    # target: x^2 + 2 y^2 + z^2 + x y + y z == W0(x, y) + W1(y, z)
    target = {(2, 0, 0): 1, (0, 2, 0): 2, (0, 0, 2): 1, (1, 1, 0): 1, (0, 1, 1): 1}
    w0 = Gram("W0", ((1, 0, 0), (0, 1, 0)), ((0, 1),))
    w1 = Gram("W1", ((0, 1, 0), (0, 0, 1)), ((0, 1),))
    structure = Structure(nvars=3, grams=(w0, w1), scalars=(),
                          identities=(Identity("split", (Term(one(ring, -1), "W0"), Term(one(ring, -1), "W1")),
                                               Coefficients.literal(target), "W0", shared=("W1",)),),
                          objective=("max_margin",))
    import numpy as np

    noisy = Solution(grams={"W0": np.array([[1.0 + 3e-12, 0.5], [0.5, 1.0]]),
                            "W1": np.array([[1.0, 0.5 - 1e-12], [0.5 - 1e-12, 1.0]])},
                     scalars={"t": 0.5}, report=SimpleNamespace(outcome="optimal"))  # type: ignore[arg-type]
    point = exact_point(ring, structure, noisy, {})
    assert point is not None
    assert identity_value(ring, structure, structure.identities[0], point, {}) == ring.zero()
    assert point.grams["W0"][0][1] == point.grams["W0"][1][0]


@pytest.fixture(scope="module")
def ring8(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, dict]:
    """A ring of 4 oscillators (8 states), whose dense degree-4 program is beyond BLOCK_COST_LIMIT."""
    from lyapcheck.models.engines import store

    path = tmp_path_factory.mktemp("ring") / "ring8.toml"
    path.write_text(networks.ring(4))
    from lyapcheck import api

    with store.disabled():
        found = api.certify(model=path, classes="sos_gas")
    return path, found.document


def test_sos_gas_on_a_network_beyond_the_dense_limit_uses_cliques(ring8: tuple[Path, dict]) -> None:
    _, doc = ring8
    condition = doc["conditions"]["sos_gas"]
    assert condition["status"] == "certified" and condition["property"] == "GAS"
    cert = condition["certificate"]
    assert cert["kind"] == "lyapunov_cliques" and cert["degree"] == 4
    assert len(cert["gram_V"]) == len(cert["cliques"]) >= 2
    assert all(len(c) < 8 for c in cert["cliques"])  # each clique smaller than the whole
    assert "a sum over" in condition["summary"] and "cliques of the states" in condition["summary"]


def test_the_dense_form_stays_where_it_fits(tmp_path: Path) -> None:
    """Three oscillators (6 states): the one-Gram-matrix form fits the size limits and is used, as before."""
    from lyapcheck import api
    from lyapcheck.models.engines import store

    path = tmp_path / "ring6.toml"
    path.write_text(networks.ring(3))
    with store.disabled():
        found = api.certify(model=path, classes="sos_gas")
    condition = found.document["conditions"]["sos_gas"]
    assert condition["status"] == "certified" and condition["certificate"]["kind"] == "lyapunov"


def test_verify_rechecks_the_clique_form_and_refuses_a_changed_matrix(ring8: tuple[Path, dict],
                                                                       tmp_path: Path) -> None:
    from click.testing import CliRunner

    from lyapcheck.cli import app

    app._register_commands()
    _, doc = ring8
    good = tmp_path / "good.json"
    good.write_text(json.dumps(doc))
    result = CliRunner().invoke(app.cli, ["verify", str(good)])
    assert result.exit_code == 0, result.output
    assert "every clique's Q_V > 0" in result.output
    bad_doc = json.loads(json.dumps(doc))
    sigma = bad_doc["conditions"]["sos_gas"]["certificate"]["gram_sigma"][1]
    sigma["Q"][0][0] = str(Fraction(sigma["Q"][0][0]) + Fraction(1, 1000))
    bad = tmp_path / "bad.json"
    bad.write_text(json.dumps(bad_doc))
    result = CliRunner().invoke(app.cli, ["verify", str(bad)])
    assert result.exit_code == 1
    assert "does not hold exactly" in result.output


def test_a_thirty_state_model_is_read() -> None:
    from lyapcheck.models.language.modelfile import MAX_STATES, parse_any_model

    assert MAX_STATES == 30
    model = parse_any_model(networks.ring(15), "ring30.toml")
    assert len(model.states) == 30


def test_the_report_names_the_clique_matrices(ring8: tuple[Path, dict]) -> None:
    from reports.sections.model_file import gram_sizes

    _, doc = ring8
    cert = doc["conditions"]["sos_gas"]["certificate"]
    sizes = gram_sizes(cert)
    assert any(s.startswith(f"gram_V: {len(cert['gram_V'])} matrices, one per clique") for s in sizes), sizes
    assert any(s.startswith("gram_sigma: ") for s in sizes), sizes
