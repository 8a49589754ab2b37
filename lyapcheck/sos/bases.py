"""Monomial bases of Gram matrices: the Newton polytope reduction and sign symmetry.

A polynomial ``p = z^T Q z`` with ``Q`` positive semidefinite can only use monomials ``z_a`` with
``2a`` in the Newton polytope of ``p`` (the convex hull of its exponents); a monomial outside
forces a zero row and column of ``Q``, so a strictly positive definite ``Q`` (which the exact
checks require) is impossible with it in the basis. Two sound reductions, each removing a
monomial only with a proof that it cannot be used:

* **separating hyperplanes** (:func:`newton_reduce`): ``a`` is dropped when an integer direction
  ``w`` has ``2a.w > max_s s.w`` or ``2a.w < min_s s.w`` over the support ``s`` (exact integer
  arithmetic; the directions are the sign vectors of small support, so the test is the exact
  half polytope in low dimension and a superset of it beyond);
* **diagonal consistency** (Lofberg): ``z_a^2`` must appear in ``p`` or be cancelled by an
  off-diagonal product ``z_b z_c`` (``b != c``, both in the basis); otherwise ``Q_aa = 0``, and
  ``a`` goes. Repeated until nothing changes.

**Sign symmetry** (:func:`sign_symmetries`): when ``x -> S x`` (``S`` diagonal, entries +-1) maps
every identity of a program to itself, a feasible certificate's mirror is feasible and their mean
is invariant, so the search may restrict itself to invariant polynomials: Gram matrices block
diagonal by the monomials' characters (:func:`character_blocks`). The group of such ``S`` is the
null space of a linear system over GF(2), found by elimination. This generalizes the paper's
parity reduction (the ILOS field is odd: ``S = -I``).
"""

from __future__ import annotations

import itertools
from typing import TYPE_CHECKING, Iterable, Sequence

from lyapcheck.sos.polynomials import Monomial, monomials

if TYPE_CHECKING:  # pragma: no cover - numpy is imported where a basis is built, not by the exact checks
    import numpy as np

#: sign-vector directions with at most this many non-zero entries are used by the hyperplane test
DIRECTION_SUPPORT = 3
#: the most entries (directions times points, candidates and variables) the hyperplane test builds: in
#: many variables (a loop with a hundred auxiliaries has a million directions of support 3) the
#: support is lowered until they fit. Fewer directions drop fewer monomials: a larger basis, as sound
MAX_DIRECTION_ENTRIES = 10**8


def direction_count(nvars: int, support: int) -> int:
    """How many sign vectors with ``1..support`` non-zero entries, the first of them +1, there are."""
    from math import comb

    return sum(comb(nvars, k) * 2 ** (k - 1) for k in range(1, min(support, nvars) + 1))


def _directions(nvars: int, support: int = DIRECTION_SUPPORT) -> np.ndarray:
    import numpy as np

    out = []
    for k in range(1, min(support, nvars) + 1):
        for idx in itertools.combinations(range(nvars), k):
            for signs in itertools.product((1, -1), repeat=k):
                if signs[0] != 1:
                    continue  # w and -w give the same test (both bounds are checked)
                w = [0] * nvars
                for i, s in zip(idx, signs):
                    w[i] = s
                out.append(w)
    return np.array(out, dtype=np.int64).reshape(-1, nvars)


def inside_half_polytope(candidates: Sequence[Monomial], support: Iterable[Monomial]) -> list[bool]:
    """Whether no tested hyperplane separates ``2a`` from ``support``'s hull, per candidate ``a``."""
    import numpy as np

    pts = np.array(sorted(set(support)), dtype=np.int64)
    if pts.size == 0 or not candidates:
        return [False] * len(candidates)
    nvars = pts.shape[1]
    nonzero = DIRECTION_SUPPORT
    rows = len(pts) + len(candidates) + nvars
    while nonzero > 1 and direction_count(nvars, nonzero) * rows > MAX_DIRECTION_ENTRIES:
        nonzero -= 1
    dirs = _directions(nvars, nonzero)
    proj = pts @ dirs.T  # (points, directions)
    hi, lo = proj.max(axis=0), proj.min(axis=0)
    cand = np.array(candidates, dtype=np.int64).reshape(-1, nvars)
    twice = 2 * cand @ dirs.T
    return [bool(x) for x in np.all((twice <= hi) & (twice >= lo), axis=1)]


def newton_reduce(candidates: Sequence[Monomial], support: Iterable[Monomial]) -> list[Monomial]:
    """The candidates ``a`` whose ``2a`` no tested hyperplane separates from ``support``'s hull,
    then diagonally consistent (see the module docstring). Order is kept."""
    support = list(support)
    kept = [m for m, ok in zip(candidates, inside_half_polytope(candidates, support)) if ok]
    return diagonally_consistent(kept, support)


def diagonally_consistent(basis: Sequence[Monomial], support: Iterable[Monomial]) -> list[Monomial]:
    """Drop ``a`` while ``2a`` is neither in ``support`` nor a sum ``b + c`` of two different basis
    monomials (then ``Q_aa`` is forced to 0 and ``a`` cannot be used)."""
    import numpy as np

    kept = list(basis)
    if not kept:
        return kept
    nvars = len(kept[0])
    supp = [tuple(m) for m in support]
    top = 2 * max(max(max(m) for m in kept), max((max(m) for m in supp), default=0)) + 1
    # A monomial's code is its exponents in base ``top`` (a sum of two never carries). With many
    # variables (a loop with 120 auxiliaries) ``top ** nvars`` exceeds int64: the codes are then
    # Python integers (numpy's object arrays), exact at any size.
    dtype: type = np.int64 if top ** nvars <= np.iinfo(np.int64).max else object
    radix: np.ndarray = np.array([top ** k for k in range(nvars)], dtype=dtype)

    def code(ms: Sequence[Monomial]) -> np.ndarray:
        return np.array(ms, dtype=dtype).reshape(-1, nvars) @ radix

    supp_codes = set(code(supp).tolist()) if supp else set()
    while True:
        c = code(kept)
        pair = c[:, None] + c[None, :]
        off = pair[~np.eye(len(kept), dtype=bool)]
        sums = set(off.tolist())  # (np.unique's first call imports numpy.ma: 15-20 ms of a small run)
        twice = (2 * c).tolist()
        keep = [x in supp_codes or x in sums for x in twice]
        if all(keep):
            return kept
        kept = [m for m, k in zip(kept, keep) if k]
        if not kept:
            return kept


def candidate_count(nvars: int, top_degree: int) -> int:
    """How many monomials of degree at most ``top_degree // 2`` there are (a cheap size guard
    before a basis is built)."""
    from math import comb

    return comb(nvars + top_degree // 2, nvars)


def half_degree_candidates(nvars: int, support: Iterable[Monomial]) -> list[Monomial]:
    """Monomials whose total degree lies between half the support's lowest and highest degree."""
    degrees = [sum(m) for m in support]
    if not degrees:
        return []
    lo, hi = (min(degrees) + 1) // 2, max(degrees) // 2
    return monomials(nvars, lo, hi)


def sos_basis(nvars: int, support: Iterable[Monomial]) -> list[Monomial]:
    """A reduced basis for an SOS polynomial of the given (generic) support."""
    supp = list(support)
    return newton_reduce(half_degree_candidates(nvars, supp), supp)


def has_pure_powers(basis: Sequence[Monomial], variables: Sequence[int]) -> bool:
    """Every listed variable has a pure power ``z_i^k`` (``k >= 1``) in the basis: then
    ``z^T Q z >= lambda_min(Q) |z_basis|^2 > 0`` whenever one of those variables is non-zero."""
    for i in variables:
        if not any(m[i] > 0 and sum(m) == m[i] for m in basis):
            return False
    return True


# -- sign symmetry --------------------------------------------------------------------------------

def _gf2_nullspace(rows: Sequence[Sequence[int]], ncols: int) -> list[tuple[int, ...]]:
    """A basis of ``{b in GF(2)^ncols : r . b = 0 (mod 2) for every row r}``."""
    mat = [[x % 2 for x in r] for r in rows]
    pivots: list[int] = []
    r = 0
    for c in range(ncols):
        pivot = next((i for i in range(r, len(mat)) if mat[i][c]), None)
        if pivot is None:
            continue
        mat[r], mat[pivot] = mat[pivot], mat[r]
        for i in range(len(mat)):
            if i != r and mat[i][c]:
                mat[i] = [(a + b) % 2 for a, b in zip(mat[i], mat[r])]
        pivots.append(c)
        r += 1
        if r == len(mat):
            break
    free = [c for c in range(ncols) if c not in pivots]
    basis = []
    for f in free:
        b = [0] * ncols
        b[f] = 1
        for i, c in enumerate(pivots):
            if mat[i][f]:
                b[c] = 1
        basis.append(tuple(b))
    return basis


def sign_symmetries(nvars: int, odd_in: Sequence[tuple[Iterable[Monomial], int | None]],
                    equal_parity: Sequence[Iterable[Monomial]] = ()) -> list[tuple[int, ...]]:
    """Generators (GF(2) vectors ``b``; ``S = diag((-1)^b)``) of the sign changes that respect:

    - each ``(support, i)`` of ``odd_in``: a polynomial with that support changes like ``x_i``
      (``i`` an index), or is invariant (``i`` None): ``b . a + b_i = 0`` for every exponent ``a``;
    - each support of ``equal_parity``: all its terms change alike (the polynomial is invariant or
      changes sign as a whole, as an output whose square is bounded).
    """
    rows: list[list[int]] = []
    for support, i in odd_in:
        for a in support:
            row = list(a)
            if i is not None:
                row[i] += 1
            rows.append(row)
    for support in equal_parity:
        terms = list(support)
        for a in terms[1:]:
            rows.append([x - y for x, y in zip(a, terms[0])])
    return _gf2_nullspace(rows, nvars)


def character(m: Monomial, generators: Sequence[Sequence[int]]) -> tuple[int, ...]:
    """How ``z^m`` changes under each generator: ``(b . m mod 2)`` per generator."""
    return tuple(sum(b_k * e for b_k, e in zip(b, m)) % 2 for b in generators)


def character_blocks(basis: Sequence[Monomial], generators: Sequence[Sequence[int]]) -> list[list[int]]:
    """Index sets of the basis grouped by character: an invariant ``z^T Q z`` has ``Q`` block
    diagonal with these blocks (products of monomials of equal character are invariant)."""
    groups: dict[tuple[int, ...], list[int]] = {}
    for i, m in enumerate(basis):
        groups.setdefault(character(m, generators), []).append(i)
    return [idx for _, idx in sorted(groups.items())]


def invariant_monomials(candidates: Sequence[Monomial], generators: Sequence[Sequence[int]]) -> list[Monomial]:
    """The candidates invariant under every generator (character 0)."""
    return [m for m in candidates if not any(character(m, generators))]
