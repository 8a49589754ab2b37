"""Correlative sparsity: Gram bases over cliques of the variables instead of all of them.

A polynomial identity over ``n`` variables whose terms each involve only a few of them (a network:
each state's derivative depends on its neighbours) need not be proved with one Gram matrix over
every monomial of all ``n`` variables: a sum of Gram matrices, each over the monomials of one
*clique* of variables, is also a sum of squares, and its matrices grow with the cliques, not with
``n`` (Waki, Kim, Kojima & Muramatsu, SIAM J. Optim. 2006; Wang, Magron & Lasserre, CS-TSSOS,
2021). Restricting the bases this way is a choice of form: it can only lose certificates, never
admit a false one, so every choice of cliques is sound.

* :func:`neighbourhood_cliques`: the closed neighbourhoods of the variables in the interaction
  graph, the maximal ones kept (a network's subsystem with its neighbours);
* :func:`chordal_cliques`: the maximal cliques of a chordal completion of that graph (networkx's
  MCS-M), the form for which the sparse Positivstellensatz is complete, larger on rings;
* :func:`clique_candidates`: the monomials of a clique between two degrees;
* :func:`reduce_clique_bases`: the Newton polytope reduction per clique (separating hyperplanes in
  the clique's own coordinates, :func:`lyapcheck.sos.bases.inside_half_polytope`), then diagonal
  consistency over all cliques together (a diagonal entry may be cancelled by an off-diagonal
  product of any clique's matrix).
"""

from __future__ import annotations

from typing import Iterable, Sequence

from lyapcheck.sos.bases import inside_half_polytope
from lyapcheck.sos.polynomials import Monomial, monomials

Clique = tuple[int, ...]


def interaction_edges(couplings: Sequence[Iterable[int]]) -> set[tuple[int, int]]:
    """The undirected edges ``{i, j}`` (``i < j``) of ``couplings[i]``: the variables variable ``i``
    is coupled to (for a field, those in ``g_i``)."""
    return {(min(i, j), max(i, j)) for i, js in enumerate(couplings) for j in js if j != i}


def neighbourhood_cliques(n: int, couplings: Sequence[Iterable[int]]) -> list[Clique]:
    """The maximal closed neighbourhoods ``{i} + neighbours(i)`` of the interaction graph, sorted."""
    adjacent: list[set[int]] = [{i} for i in range(n)]
    for i, j in interaction_edges(couplings):
        adjacent[i].add(j)
        adjacent[j].add(i)
    sets = {frozenset(a) for a in adjacent}
    maximal = [s for s in sets if not any(s < t for t in sets)]
    return sorted(tuple(sorted(s)) for s in maximal)


def chordal_cliques(n: int, couplings: Sequence[Iterable[int]]) -> list[Clique]:
    """The maximal cliques of a minimal chordal completion of the interaction graph, sorted."""
    import networkx as nx

    graph = nx.Graph()
    graph.add_nodes_from(range(n))
    graph.add_edges_from(interaction_edges(couplings))
    chordal, _ = nx.complete_to_chordal_graph(graph)
    return sorted(tuple(sorted(c)) for c in nx.chordal_graph_cliques(chordal))


def clique_candidates(clique: Clique, nvars: int, low: int, high: int) -> list[Monomial]:
    """The monomials of ``nvars`` variables supported on ``clique``, of total degree ``low..high``."""
    out = []
    for local in monomials(len(clique), low, high):
        m = [0] * nvars
        for k, e in zip(clique, local):
            m[k] = e
        out.append(tuple(m))
    return out


def _restrict(m: Monomial, clique: Clique) -> Monomial:
    return tuple(m[k] for k in clique)


def reduce_clique_bases(cliques: Sequence[Clique], candidates: Sequence[Sequence[Monomial]],
                        support: Iterable[Monomial]) -> list[list[Monomial]]:
    """Each clique's candidates that may appear in a sum of squares equal to a polynomial with this
    ``support`` (a superset of it is sound: fewer monomials are dropped).

    A candidate ``a`` of clique ``C`` is dropped when a hyperplane in ``C``'s coordinates separates
    ``2a`` from the support's hull (every square of any sum-of-squares decomposition has its
    Newton polytope in half the polynomial's), then when ``a^2`` is not in the support and no
    clique's basis has two different monomials multiplying to it (so every matrix's diagonal
    entry at ``a`` must be 0), repeated until nothing changes."""
    support = set(support)
    kept: list[list[Monomial]] = []
    for clique, cands in zip(cliques, candidates):
        local = {_restrict(m, clique) for m in support}
        inside = inside_half_polytope([_restrict(a, clique) for a in cands], local)
        kept.append([a for a, ok in zip(cands, inside) if ok])
    while True:
        cancellable: set[Monomial] = set()
        for basis in kept:
            for i, b in enumerate(basis):
                for c in basis[i + 1:]:
                    cancellable.add(tuple(x + y for x, y in zip(b, c)))
        reduced = [[a for a in basis if tuple(2 * x for x in a) in support or tuple(2 * x for x in a) in cancellable]
                   for basis in kept]
        if reduced == kept:
            return kept
        kept = reduced
