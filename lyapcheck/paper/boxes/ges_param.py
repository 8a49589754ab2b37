"""``ges`` over a box of gains with a certificate whose matrices are polynomials in the gains.

Why. One certificate common to a whole box (:mod:`lyapcheck.paper.boxes.quadratic`) is too rigid:
around the paper's gains it proved +-5 % in ``alpha_d`` and ``k_d`` at less than half the rate of
the point, and nothing at +-10 %. The standard robust construction lets the Lyapunov function
depend on the (constant) parameters: ``V(x; theta)``, one function per gain set, all of them
proved at once by one polynomial identity over the box.

Coordinates. As in :mod:`lyapcheck.paper.conditions.ges`, ``x = (eps, sigma0 s)/Delta``,
``y = x_1 + x_2``, ``w = 1/(1 + y^2)``, but in seconds rather than in each point's own time scale:

    x' = [[-e_1, c e_1], [e_3 w, -e_4]] x,    e_1 = |a11|,  e_3 = |a11| b,  e_4 = |a11| a,

with ``c``, ``a``, ``b`` of :class:`~lyapcheck.paper.conditions.sos.ScaledDynamics`. Each of
``e_1, e_3, e_4`` and ``c`` is a signed monomial in the positive parameters (``tests/test_boxes.py``
checks this on the derivation), hence monotone in each of them: over a box of gains each ``e_i``
ranges over the interval spanned by its values at the box's corners, and ``c`` is constant when
it has the same value at every corner. The box therefore maps into the product ``E`` of those
intervals (onto it for the paper's loop, where ``e_1 = e11 alpha_d``, ``e_4 = k_d`` and
``e_3 = sigma0 U/Delta`` depend on disjoint gains, so nothing is lost). Each ``e_i`` that varies is
written ``lo_i + (hi_i - lo_i) u_i`` with ``u_i`` in ``[0, 1]``, and time is measured in units of
``1/T0`` (``T0`` the middle of ``e_1``'s interval) so that the numbers are those of the point class.

Certificate. ``V = x^T P(u) x + sum_k w^k y l_k(u)^T x = x^T M(w, u) x``, with ``P`` and every
``l_k`` polynomials of degree ``<= d`` in each ``u_i`` (``d = 0``: a common certificate). As in the
point class, ``V' = x^T D(w, u) x`` with ``D`` polynomial in ``(w, u)``, and the conditions are

    M - c1 I > 0,    c2 I - M > 0,    -(D + mu M) > 0    for every w in [0, 1] and u in [0, 1]^q.

Proof of a condition ``G(w, u) > 0``. Expand ``G`` in the tensor Bernstein basis of ``u``:
``G = sum_beta G_beta(w) B_beta(u)`` with ``B_beta >= 0`` and ``sum_beta B_beta = 1`` on the box, so
``G(w, u)`` is a convex combination of the matrices ``G_beta(w)``; if each is positive definite on
``[0, 1]`` (proved exactly as in the point class: the (1,1) entry and the determinant, Bernstein in
``w``), so is ``G``. Where a block is not proved, the ``u`` box is halved along its widest axis
(re-expanded on each half) up to :data:`MAX_PIECES` pieces. Everything is rational arithmetic.
Then for every gain set of the box, in seconds,

    |x(t)| <= sqrt(c2/c1) |x(0)| exp(-mu T0 t / 2).

Search. The same Bernstein blocks, each required positive semidefinite on all of ``[0, 1]`` as a
matrix sum of squares (Lukacs' theorem, as :func:`lyapcheck.paper.conditions.ges.build_program`),
compiled once per shape; the decay rate is bisected, every step decided by the exact check of the
rounded solver point, never by the solver's status.
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass
from fractions import Fraction
from functools import lru_cache
from math import comb
from typing import Any, Mapping, Sequence

import numpy as np

from lyapcheck import exact
from lyapcheck.paper.boxes.box import ParameterBox, corner_problems
from lyapcheck.paper.conditions.rate_search import largest_proved_rate
from lyapcheck.paper.params import Problem
from lyapcheck.sos.polynomials import Poly, Ring
from lyapcheck.paper.system import build_system

#: terms ``w^k y l_k^T x`` of the certificate: 6, not the point class's 4 (with 4, no certificate of
#: this form exists at alpha_d = 750, k_d = 0.1125, a corner of the +-25 % box around the paper's
#: gains; 8 and more leave the solver with an ill-conditioned power basis in w)
TERMS = 6
#: degree of P(u) and l_k(u) in each box coordinate, tried in turn (0: one common certificate)
PARAM_DEGREES = (1,)
#: Bernstein degree in each u of the search's blocks, above the conditions' own degree (a higher
#: degree makes the relaxation tighter at the price of more blocks)
ELEVATION = 0
#: decay-rate search of mu in the normalised time: geometric bisection between these
MU_LOW, MU_HIGH = 1 / 64, 4.0
MU_FLOOR = 1e-5
MU_BISECTION_STEPS = 7
#: the search asks for -(D + mu M)/s >= MARGIN t I (s the largest entry of A over the box): the
#: point class's margin, far above the rounding of the unknowns to :data:`DIGITS` digits
MARGIN = 3e-6
DIGITS = 8
#: the certificate's c1 (the program asks M >= I) and the share of slack above the optimum t for c2
C1 = Fraction(99, 100)
BOUND_SLACK = 1e-2
#: largest number of pieces of the u box in the exact check (halvings of its widest axis)
MAX_PIECES = 64
#: the largest degree in the gains that ``verify`` accepts from a file (the search uses PARAM_DEGREES;
#: a forged degree of 10^9 must be refused before the monomials are listed)
MAX_VERIFIED_DEGREE = 4

Poly1 = list[Fraction]
#: entries (p, q) of a symmetric 2x2 matrix in the order of the program's coefficient rows
_ENTRIES = ((0, 0), (0, 1), (1, 1))


# -- the box in entry coordinates ----------------------------------------------------------------
@dataclass(frozen=True)
class EntryBox:
    """The intervals of ``e_1, e_3, e_4`` over a gain box, the constant ``c`` and ``T0`` (exact)."""

    lo: tuple[Fraction, Fraction, Fraction]
    hi: tuple[Fraction, Fraction, Fraction]
    c: Fraction

    @property
    def axes(self) -> tuple[int, ...]:
        """The entries that vary over the box (each one coordinate ``u``)."""
        return tuple(i for i in range(3) if self.hi[i] != self.lo[i])

    @property
    def t0(self) -> Fraction:
        return (self.lo[0] + self.hi[0]) / 2

    def entry_at(self, i: int, u: Fraction) -> Fraction:
        return self.lo[i] + (self.hi[i] - self.lo[i]) * u

    def to_json(self) -> dict[str, Any]:
        return {"lo": [str(v) for v in self.lo], "hi": [str(v) for v in self.hi], "c": str(self.c)}


def entry_box(problem: Problem, box: ParameterBox, dynamics: str) -> EntryBox | str:
    """The :class:`EntryBox` of ``box`` from its corners, or why the class does not apply."""
    from lyapcheck.paper.conditions.sos import scaled_dynamics

    values = []
    cs = set()
    for p in corner_problems(problem, box):
        dyn = scaled_dynamics(build_system(p, dynamics))
        if dyn is None:
            return "the dynamics at some corner do not have the structure this class needs"
        ts = dyn.time_scale
        values.append((ts, ts * dyn.b, ts * dyn.a))
        cs.add(dyn.c)
    if len(cs) != 1:
        return "the coupling c = a12/(sigma0 |a11|) varies over the box (this class needs it constant)"
    lo = tuple(min(v[i] for v in values) for i in range(3))
    hi = tuple(max(v[i] for v in values) for i in range(3))
    return EntryBox((lo[0], lo[1], lo[2]), (hi[0], hi[1], hi[2]), cs.pop())


# -- exact polynomial matrices in (w, u) ---------------------------------------------------------
PolyMatrix = list[list[Poly]]


@lru_cache(maxsize=8)
def ring(q: int) -> Ring:
    return Ring(("w",) + tuple(f"u{i}" for i in range(q)))


def _dynamics(box: EntryBox, R: Ring) -> PolyMatrix:
    """``A(w, u)`` in the normalised time (module docstring)."""
    w = R.gen("w")
    entries = []
    for i in range(3):
        e = R.constant(box.lo[i])
        if i in box.axes:
            e = e + R.gen(f"u{box.axes.index(i)}") * R.constant(box.hi[i] - box.lo[i])
        entries.append(e * R.constant(1 / box.t0))
    e1, e3, e4 = entries
    return [[-e1, e1 * R.constant(box.c)], [e3 * w, -e4]]


def unknown_monomials(q: int, degree: int) -> list[tuple[int, ...]]:
    """The monomials ``u^alpha`` of ``P(u)`` and ``l_k(u)`` (each exponent ``<= degree``)."""
    return list(itertools.product(range(degree + 1), repeat=q))


def unknowns_per_monomial(terms: int) -> int:
    return 3 + 2 * terms


def certificate_matrices(box: EntryBox, P: Sequence[exact.Matrix], ells: Sequence[Sequence[Sequence[Fraction]]],
                         degree: int) -> tuple[PolyMatrix, PolyMatrix]:
    """``M(w, u)`` and ``D(w, u)`` exactly, for ``P[j]``, ``ells[j][k]`` the coefficients of the
    ``j``-th monomial of :func:`unknown_monomials` (module docstring)."""
    q = len(box.axes)
    R = ring(q)
    A = _dynamics(box, R)
    w = R.gen("w")
    mons = unknown_monomials(q, degree)
    zero = R.zero()

    def u_poly(coefficients: Sequence[Fraction]) -> Poly:
        out = zero
        for alpha, value in zip(mons, coefficients):
            if value:
                out = out + R.monomial((0,) + tuple(alpha), value)
        return out

    Pm = [[u_poly([P[j][r][s] for j in range(len(mons))]) for s in range(2)] for r in range(2)]
    terms = len(ells[0]) if ells else 0
    ls = [[u_poly([ells[j][k][r] for j in range(len(mons))]) for r in range(2)] for k in range(terms)]
    return _assemble(A, Pm, ls, w, R)


def _assemble(A: PolyMatrix, Pm: PolyMatrix, ls: Sequence[Sequence[Poly]], w: Poly, R: Ring
              ) -> tuple[PolyMatrix, PolyMatrix]:
    """``M`` and ``D`` from ``A``, ``P`` and the ``l_k`` (the point class's formulas, in ``(w, u)``)."""
    half = R.constant(Fraction(1, 2))

    def mul(X: PolyMatrix, Y: PolyMatrix) -> PolyMatrix:
        return [[X[i][0] * Y[0][j] + X[i][1] * Y[1][j] for j in range(2)] for i in range(2)]

    def add(X: PolyMatrix, Y: PolyMatrix) -> PolyMatrix:
        return [[X[i][j] + Y[i][j] for j in range(2)] for i in range(2)]

    def sym_outer(a: Sequence[Poly], b: Sequence[Poly]) -> PolyMatrix:
        return [[(a[i] * b[j] + a[j] * b[i]) * half for j in range(2)] for i in range(2)]

    At = [[A[j][i] for j in range(2)] for i in range(2)]
    one = [R.constant(1), R.constant(1)]
    At_one = [At[i][0] + At[i][1] for i in range(2)]  # A^T 1
    M = Pm
    D = add(mul(At, Pm), mul(Pm, A))
    for k, ell in enumerate(ls, start=1):
        wk = w ** k
        factor = wk * (R.constant(1 - 2 * k) + w * R.constant(2 * k))  # w^k (1 - 2k(1 - w))
        lA = [ell[0] * A[0][j] + ell[1] * A[1][j] for j in range(2)]  # l^T A
        M = add(M, [[wk * e for e in row] for row in sym_outer(one, ell)])
        D = add(D, [[factor * e for e in row] for row in sym_outer(At_one, ell)])
        D = add(D, [[wk * e for e in row] for row in sym_outer(one, lA)])
    return M, D


# -- Bernstein blocks ----------------------------------------------------------------------------
def bernstein_blocks(R: Ring, G: PolyMatrix, q: int, n: int) -> dict[tuple[int, ...], list[list[Poly1]]]:
    """``G_beta(w)`` (univariate 2x2 polynomial matrices, lists of coefficients) of the tensor
    Bernstein expansion of degree ``n`` in each ``u_i`` on ``[0, 1]^q``, exactly."""
    out: dict[tuple[int, ...], list[list[Poly1]]] = {}
    betas = list(itertools.product(range(n + 1), repeat=q))
    for beta in betas:
        out[beta] = [[[] for _ in range(2)] for _ in range(2)]
    for r in range(2):
        for s in range(2):
            dense: dict[tuple[int, ...], Fraction] = R.terms(G[r][s])
            wdeg = max((m[0] for m in dense), default=0)
            for beta in betas:
                coefficients = [Fraction(0)] * (wdeg + 1)
                for m, value in dense.items():
                    # power u^alpha -> Bernstein coefficient at beta: prod_i C(beta_i, a_i)/C(n, a_i)
                    weight = Fraction(1)
                    for a_i, b_i in zip(m[1:], beta):
                        if a_i > b_i:
                            weight = Fraction(0)
                            break
                        weight *= Fraction(comb(b_i, a_i), comb(n, a_i))
                    if weight:
                        coefficients[m[0]] += weight * value
                out[beta][r][s] = coefficients
    return out


def _u_degree(R: Ring, G: PolyMatrix) -> int:
    return max((max(m[1:], default=0) for row in G for e in row for m in R.terms(e)), default=0)


def positive_definite_on_box(R: Ring, G: PolyMatrix, q: int, pieces: int = MAX_PIECES) -> bool:
    """Exact: ``G(w, u)`` is positive definite for every ``w`` in ``[0, 1]``, ``u`` in ``[0, 1]^q``
    (Bernstein blocks, the ``u`` box halved along its widest axis where a block is not proved)."""
    from lyapcheck.paper.conditions.ges import matrix_positive_definite_on_unit_interval

    todo: list[tuple[tuple[Fraction, ...], tuple[Fraction, ...]]] = [((Fraction(0),) * q, (Fraction(1),) * q)]
    used = 1
    while todo:
        lo, hi = todo.pop()
        # G on the piece: u_i = lo_i + (hi_i - lo_i) v_i with v in [0, 1]^q
        images = [R.gen("w")] + [R.constant(lo[i]) + R.gen(f"u{i}") * R.constant(hi[i] - lo[i]) for i in range(q)]
        piece = [[R.compose(e, images) for e in row] for row in G]
        n = max(_u_degree(R, piece), 1)
        if all(matrix_positive_definite_on_unit_interval(block)
               for block in bernstein_blocks(R, piece, q, n).values()):
            continue
        if q == 0 or used + 1 > pieces:
            return False
        axis = max(range(q), key=lambda i: hi[i] - lo[i])
        mid = (lo[axis] + hi[axis]) / 2
        todo.append((lo, hi[:axis] + (mid,) + hi[axis + 1:]))
        todo.append((lo[:axis] + (mid,) + lo[axis + 1:], hi))
        used += 1
    return True


def exact_check(box: EntryBox, P: Sequence[exact.Matrix], ells: Sequence[Sequence[Sequence[Fraction]]],
                degree: int, mu: Fraction, c1: Fraction, c2: Fraction) -> tuple[bool, str]:
    """Exact: the three conditions of the module docstring on all of ``[0, 1] x [0, 1]^q``."""
    if not (mu > 0 and 0 < c1 < c2):
        return False, "needs mu > 0 and 0 < c1 < c2"
    q = len(box.axes)
    R = ring(q)
    M, D = certificate_matrices(box, P, ells, degree)
    eye = [[R.constant(1), R.zero()], [R.zero(), R.constant(1)]]

    def combine(a: Fraction, X: PolyMatrix, b: Fraction, Y: PolyMatrix) -> PolyMatrix:
        return [[X[i][j] * R.constant(a) + Y[i][j] * R.constant(b) for j in range(2)] for i in range(2)]

    if not positive_definite_on_box(R, combine(Fraction(1), M, -c1, eye), q):
        return False, "M(w, u) - c1 I > 0 on the box is not proved"
    if not positive_definite_on_box(R, combine(c2, eye, Fraction(-1), M), q):
        return False, "c2 I - M(w, u) > 0 on the box is not proved"
    if not positive_definite_on_box(R, combine(Fraction(-1), D, -mu, M), q):
        return False, "-(D(w, u) + mu M(w, u)) > 0 on the box is not proved"
    return True, ("c1 I < M(w, u) < c2 I and D(w, u) + mu M(w, u) < 0 for every w in [0, 1] and every point of the "
                  "box, exactly (Bernstein in w and in the gains' coordinates)")


# -- numerical search ----------------------------------------------------------------------------
def block_degree(degree: int) -> int:
    """The Bernstein degree in each ``u`` of the search's blocks (``D`` has ``degree + 1``)."""
    return degree + 1 + ELEVATION


def inequalities(terms: int, q: int, n: int) -> list[tuple[str, int]]:
    """The blocks of the search and their degrees in ``w``: ``M - I``, ``t I - M`` and the decay
    inequality, each at every Bernstein index ``beta`` in ``{0..n}^q``."""
    out = []
    for flat, _ in enumerate(itertools.product(range(n + 1), repeat=q)):
        out += [(f"lower_{flat}", terms), (f"upper_{flat}", terms), (f"decay_{flat}", terms + 2)]
    return out


def lukacs_maps(half: int) -> tuple[np.ndarray, np.ndarray]:
    """Constant matrices ``(Gx, Gy)`` with ``Gx vec(X) + Gy vec(Y)`` the coefficient rows of
    ``Z^T X Z + w (1 - w) Z'^T Y Z'`` (row ``3 j + e``: entry ``_ENTRIES[e]`` of the ``w^j``
    coefficient; ``Z = (I, w I, .., w^half I)``, ``Z'`` up to ``w^(half - 1)``; ``vec`` column-major,
    as cvxpy's). One vector constraint per block instead of one per row: cvxpy compiles the
    program in seconds, not minutes."""
    nx, ny = 2 * half + 2, 2 * half
    rows = 3 * (2 * half + 1)
    Gx, Gy = np.zeros((rows, nx * nx)), np.zeros((rows, ny * ny))
    for j in range(2 * half + 1):
        for e, (p, r) in enumerate(_ENTRIES):
            for u in range(half + 1):
                if 0 <= j - u <= half:
                    Gx[3 * j + e, (2 * (j - u) + r) * nx + 2 * u + p] += 1
            for u in range(half):
                if 0 <= j - 1 - u <= half - 1:
                    Gy[3 * j + e, (2 * (j - 1 - u) + r) * ny + 2 * u + p] += 1
                if 0 <= j - 2 - u <= half - 1:
                    Gy[3 * j + e, (2 * (j - 2 - u) + r) * ny + 2 * u + p] -= 1
    return Gx, Gy


def build_program(cp: Any, terms: int, degree: int, q: int) -> tuple[Any, dict[str, Any], dict[str, Any]]:
    """min t s.t. every block of :func:`inequalities` is PSD on all of ``[0, 1]`` (DPP, compiled once
    per shape; the blocks' coefficients ``C z + c0`` are the parameters; Lukacs' theorem in matrix
    form as in :func:`lyapcheck.paper.conditions.ges.build_program`)."""
    n_unknowns = unknowns_per_monomial(terms) * len(unknown_monomials(q, degree)) + 1
    z = cp.Variable(n_unknowns, name="z")
    cons: list[Any] = []
    params: dict[str, Any] = {}
    for name, wdeg in inequalities(terms, q, block_degree(degree)):
        half = (wdeg + 1) // 2
        Gx, Gy = lukacs_maps(half)
        C = cp.Parameter((Gx.shape[0], n_unknowns), name=f"C_{name}")
        c0 = cp.Parameter(Gx.shape[0], name=f"c0_{name}")
        X = cp.Variable((2 * half + 2, 2 * half + 2), symmetric=True, name=f"X_{name}")
        Y = cp.Variable((2 * half, 2 * half), symmetric=True, name=f"Y_{name}")
        cons += [X >> 0, Y >> 0, C @ z + c0 == Gx @ cp.vec(X, order="F") + Gy @ cp.vec(Y, order="F")]
        params[f"C_{name}"], params[f"c0_{name}"] = C, c0
    return cp.Problem(cp.Minimize(z[n_unknowns - 1]), cons), params, {"z": z}


@dataclass
class Tables:
    """The blocks' coefficients as linear maps of the unknowns, for one box (floats of exact values).

    ``M[i][beta]``, ``D[i][beta]``: arrays ``(w degree + 1, 2, 2)`` of the Bernstein block ``beta`` of
    ``M`` and ``D`` with the ``i``-th unknown 1 and the others 0.
    """

    M: np.ndarray  # (unknowns, blocks, terms + 1, 2, 2)
    D: np.ndarray  # (unknowns, blocks, terms + 3, 2, 2)
    scale: float


def tables(box: EntryBox, terms: int, degree: int) -> Tables:
    q = len(box.axes)
    R = ring(q)
    mons = unknown_monomials(q, degree)
    per = unknowns_per_monomial(terms)
    n = block_degree(degree)
    n_blocks = (n + 1) ** q
    count = per * len(mons)
    Ms = np.zeros((count, n_blocks, terms + 1, 2, 2))
    Ds = np.zeros((count, n_blocks, terms + 3, 2, 2))
    for i in range(count):
        j, local = divmod(i, per)
        z = [Fraction(int(local == k)) for k in range(per)]
        P = [((Fraction(0),) * 2,) * 2] * len(mons)
        ells = [[[Fraction(0)] * 2 for _ in range(terms)] for _ in mons]
        P = list(P)
        P[j] = ((z[0], z[1]), (z[1], z[2]))
        for k in range(terms):
            ells[j][k] = z[3 + 2 * k: 5 + 2 * k]
        M, D = certificate_matrices(box, P, ells, degree)
        for out, G in ((Ms, M), (Ds, D)):
            for b, block in enumerate(bernstein_blocks(R, G, q, n).values()):
                for r in range(2):
                    for s in range(2):
                        for d_w, value in enumerate(block[r][s]):
                            out[i, b, d_w, r, s] = float(value)
    t0 = box.t0
    scale = max([1.0] + [float(abs(box.hi[i] / t0)) for i in range(3)] + [float(abs(box.hi[0] * box.c / t0))])
    return Tables(Ms, Ds, scale)


def program_data(tab: Tables, terms: int, mu: float) -> dict[str, np.ndarray]:
    """Parameter values of :func:`build_program` at ``mu``."""
    count = tab.M.shape[0]
    n_unknowns = count + 1
    diagonal = np.array([1.0, 0.0, 1.0])

    def rows(table: np.ndarray, wdeg: int) -> np.ndarray:
        half = (wdeg + 1) // 2
        out = np.zeros((3 * (2 * half + 1), n_unknowns))
        for j in range(table.shape[1]):
            for e, (p, r) in enumerate(_ENTRIES):
                out[3 * j + e, :count] = table[:, j, p, r]
        return out

    def constant(wdeg: int, diagonal_at_0: float) -> np.ndarray:
        out = np.zeros(3 * ((wdeg + 1) // 2 * 2 + 1))
        out[:3] = diagonal_at_0 * diagonal
        return out

    values: dict[str, np.ndarray] = {}
    for b in range(tab.M.shape[1]):
        values[f"C_lower_{b}"], values[f"c0_lower_{b}"] = rows(tab.M[:, b], terms), constant(terms, -1.0)
        upper = -rows(tab.M[:, b], terms)
        upper[:3, n_unknowns - 1] = diagonal
        values[f"C_upper_{b}"], values[f"c0_upper_{b}"] = upper, constant(terms, 0.0)
        decay = -(rows(tab.D[:, b], terms + 2) + mu * rows(tab.M[:, b], terms + 2)) / tab.scale
        decay[:3, n_unknowns - 1] = -MARGIN * diagonal
        values[f"C_decay_{b}"], values[f"c0_decay_{b}"] = decay, constant(terms + 2, 0.0)
    return values


def program_key(terms: int, degree: int, q: int) -> str:
    return f"ges_param_{terms}_{degree}_{q}"


@dataclass
class Found:
    """An exactly checked certificate."""

    P: list[exact.Matrix]
    ells: list[list[list[Fraction]]]
    degree: int
    mu: Fraction
    c1: Fraction
    c2: Fraction


def _round(z: np.ndarray, terms: int, degree: int, q: int) -> tuple[list[exact.Matrix], list[list[list[Fraction]]]]:
    per = unknowns_per_monomial(terms)
    P: list[exact.Matrix] = []
    ells: list[list[list[Fraction]]] = []
    for j in range(len(unknown_monomials(q, degree))):
        block = [exact.to_rational(float(v), DIGITS) for v in z[j * per:(j + 1) * per]]
        P.append(((block[0], block[1]), (block[1], block[2])))
        ells.append([block[3 + 2 * k: 5 + 2 * k] for k in range(terms)])
    return P, ells


def search(box: EntryBox, log: list[dict[str, Any]], *, terms: int = TERMS,
           degrees: Sequence[int] = PARAM_DEGREES) -> Found | None:
    """The exactly checked certificate with the largest decay rate found (module docstring)."""
    from lyapcheck.paper.conditions import compiled
    from lyapcheck.paper.conditions.rounding import ceil_to_digits, floor_to_digits

    q = len(box.axes)
    for degree in degrees:
        tab = tables(box, terms, degree)
        prog = compiled.load(program_key(terms, degree, q))

        def proved(mu: float) -> Found | None:
            solved = prog.solve(program_data(tab, terms, mu))
            log.append(solved.report.to_json())
            if solved.report.outcome not in ("optimal", "inaccurate") or solved.values is None:
                return None
            z = solved.values["z"]
            t = float(z[-1])
            if not (math.isfinite(t) and t > 0):
                return None
            P, ells = _round(z, terms, degree, q)
            c1, c2 = C1, ceil_to_digits(t * (1 + BOUND_SLACK), 6)
            mu_q = floor_to_digits(mu, 4)
            ok, _ = exact_check(box, P, ells, degree, mu_q, c1, c2)
            return Found(P, ells, degree, mu_q, c1, c2) if ok else None

        found = largest_proved_rate(proved, low=MU_LOW, high=MU_HIGH, floor=MU_FLOOR, steps=MU_BISECTION_STEPS)
        if found is not None:
            return found
    return None


# -- the class: certify and verify over a box ----------------------------------------------------
def certificate_json(box: EntryBox, found: Found) -> dict[str, Any]:
    return {"form": "parametric", "entries": box.to_json(), "degree": found.degree,
            "P": [exact.to_json(P) for P in found.P],
            "l": [[[str(v) for v in ell] for ell in block] for block in found.ells],
            "mu_scaled": str(found.mu), "c1": str(found.c1), "c2": str(found.c2), "time_scale": str(box.t0)}


def envelope(box: EntryBox, mu: Fraction, c1: Fraction, c2: Fraction) -> tuple[float, float]:
    """``(k, rate per second)`` of ``|x(t)| <= k |x0| exp(-rate t)``."""
    return math.sqrt(float(c2 / c1)), float(mu * box.t0) / 2


def certify(problem: Problem, box: ParameterBox, dynamics: str) -> dict[str, Any]:
    """``ges`` for every gain set of ``box`` with a certificate polynomial in the gains."""
    eb = entry_box(problem, box, dynamics)
    if isinstance(eb, str):
        return {"status": "not_certified", "property": "GES", "summary": eb}
    log: list[dict[str, Any]] = []
    found = search(eb, log)
    if found is None:
        return {"status": "not_certified", "property": "GES", "box": box.to_json(),
                "summary": f"no certificate polynomial in the gains (degree {', '.join(map(str, PARAM_DEGREES))}, "
                           f"{TERMS} terms) passed the exact check over {box.describe()}; this is not a proof that "
                           "GES fails anywhere in it", "solver": {"solves": log}}
    from lyapcheck.paper import claims

    k, rate = envelope(eb, found.mu, found.c1, found.c2)
    return claims.decided_box("ges", {"status": "certified", "property": "GES", "summary": "", "box": box.to_json(),
                                      "k": k, "decay_rate_per_s": rate, "certificate": certificate_json(eb, found),
                                      "solver": {"solves": log}}, box)


def verify(problem: Problem, box: ParameterBox, dynamics: str, result: Mapping[str, Any]) -> tuple[bool, str]:
    """Re-derive the entry box from the gain box and re-check the certificate exactly (no solver)."""
    from lyapcheck.sos.certificates import exponent

    cert = result.get("certificate")
    if not isinstance(cert, Mapping):
        return False, "the certificate is malformed: not a table"
    eb = entry_box(problem, box, dynamics)
    if isinstance(eb, str):
        return False, eb
    if cert.get("entries") != eb.to_json() or Fraction(cert["time_scale"]) != eb.t0:
        return False, "the stored entry intervals do not match the box (was the box changed?)"
    try:
        degree = exponent(cert["degree"], "degree")
        q = len(eb.axes)
        P = [exact.from_json(m) for m in cert["P"]]
        ells = [[[Fraction(v) for v in ell] for ell in block] for block in cert["l"]]
        mu, c1, c2 = (Fraction(cert[k]) for k in ("mu_scaled", "c1", "c2"))
    except (KeyError, TypeError, ValueError, ZeroDivisionError) as exc:
        return False, f"the certificate is malformed: {exc}"
    if not 0 <= degree <= MAX_VERIFIED_DEGREE:
        return False, f"the degree in the gains must be 0..{MAX_VERIFIED_DEGREE}, got {degree}"
    count = len(unknown_monomials(q, degree))
    if not (len(P) == count and len(ells) == count
            and all(len(m) == 2 and all(len(row) == 2 for row in m) and exact.is_symmetric(m) for m in P)
            and len({len(block) for block in ells}) == 1
            and all(len(ell) == 2 for block in ells for ell in block)):
        return False, "P(u) and l_k(u) must have one symmetric 2x2 matrix and one set of 2-vectors per monomial"
    ok, why = exact_check(eb, P, ells, degree, mu, c1, c2)
    if not ok:
        return False, why
    k, rate = envelope(eb, mu, c1, c2)
    if "k" in result and not float(result["k"]) >= k * (1 - 1e-12):
        return False, f"the stated k = {result['k']} is below sqrt(c2/c1) = {k}"
    if "decay_rate_per_s" in result and not float(result["decay_rate_per_s"]) <= rate * (1 + 1e-12):
        return False, f"the stated decay rate {result['decay_rate_per_s']} exceeds the certified {rate}"
    return True, why
