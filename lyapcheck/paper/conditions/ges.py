"""``ges``: global exponential stability from a quadratic form whose matrix depends on the state.

Why a new form. The paper's Proposition 4.1 claims GES. A quadratic Lyapunov function common to
the whole coefficient interval does not exist (``sector_ges`` is refuted), and no Lyapunov
function that only uses ``rho in (0, rho_sup]`` can exist either: the switched system is
unstable (``switched_ges``). A quartic ``V`` (``sos_gas``) proves GAS, but its growth
``|x|^4`` gives no bound linear in ``|x0|``. What is left is a function with *quadratic* growth
that uses how ``rho`` depends on the state.

Coordinates (as in :mod:`lyapcheck.paper.conditions.sos`): ``x = (e, r) = (eps, sigma0 s)/Delta``,
``y = e + r``, scaled time ``tau = |a11| t``, ``w = 1/(1 + y^2)`` in ``(0, 1]``:

    x' = A(w) x,    A(w) = [[-1, c], [b w, -a]].

Certificate. With a symmetric ``P`` and vectors ``l_1..l_K``, with ``1 = (1, 1)``,

    V(x) = x^T P x + sum_k w^k y (l_k^T x) = x^T M(w) x,    M(w) = P + sum_k w^k sym(1 l_k^T).

The terms carry the factor ``y``, so ``d/dt (w^k y) = w^k (1 - 2k(1 - w)) y'`` (because
``y^2 w = 1 - w``) has no cubic part, and

    V' = x^T D(w) x,   D(w) = A^T P + P A + sum_k [w^k (1 - 2k(1 - w)) sym(A^T 1 l_k^T) + w^k sym(1 l_k^T A)],

with ``A = A(w)``: a polynomial in the scalar ``w`` alone. The exact conditions, for every
``w`` in ``[0, 1]``,

    M(w) - c1 I > 0,     c2 I - M(w) > 0,     -(D(w) + mu M(w)) > 0,

are univariate polynomial inequalities (2x2: the (1,1) entry and the determinant), proved
positive on ``[0, 1]`` by Bernstein expansion with subdivision in rational arithmetic. Then
``c1 |x|^2 <= V <= c2 |x|^2`` and ``V' <= -mu V``, hence, in seconds,

    |x(t)| <= sqrt(c2/c1) |x(0)| exp(-mu |a11| t / 2)

for every initial condition: GES, with ``k`` and ``lambda`` reported (also for ``(eps, s)``).
The scope is that of ``sos_gas``: the unsaturated error dynamics without disturbance.
"""

from __future__ import annotations

from fractions import Fraction
from functools import lru_cache
from math import comb
from typing import Any, Sequence

import numpy as np

from lyapcheck import exact
from lyapcheck.paper.conditions.base import System
from lyapcheck.results import ConditionResult
from lyapcheck.paper.conditions.sos import ScaledDynamics, scaled_dynamics

#: number of y-weighted terms w^k y l_k^T x (the decay rate it certifies grows with K: 3 gives
#: about 0.06, 4 about 0.9, 6 about 1.9 in scaled time at the paper's gains)
TERMS = 4
#: points of w in [0, 1] where the search imposes its matrix inequalities (Chebyshev nodes)
GRID_POINTS = 24
#: decay-rate search of mu in scaled time: geometric bisection between these, then a back-off
MU_LOW, MU_HIGH = 1 / 64, 4.0
#: tried when MU_LOW fails: a slow certified decay is still GES (e.g. the printed dynamics,
#: whose scaled time runs 1/e11 times faster)
MU_FLOOR = 1e-7
MU_BISECTION_STEPS = 6
#: the search asks for D + mu M <= -MARGIN I on the grid (M >= I), so that the exact check
#: between grid points and after rounding has room
MARGIN = 1e-3
#: fractions of mu tried in turn when the exact check of the rounded candidate fails at mu itself
BACK_OFF = (1.0, 0.8)
#: Bernstein subdivision depth for the exact positivity proofs on [0, 1]
MAX_SUBDIVISIONS = 14

Poly1 = list[Fraction]  # coefficients in w, lowest degree first


# -- exact univariate polynomial algebra -------------------------------------------------------
def padd(p: Poly1, q: Poly1) -> Poly1:
    n = max(len(p), len(q))
    return [(p[i] if i < len(p) else Fraction(0)) + (q[i] if i < len(q) else Fraction(0)) for i in range(n)]


def pmul(p: Poly1, q: Poly1) -> Poly1:
    out = [Fraction(0)] * (len(p) + len(q) - 1)
    for i, a in enumerate(p):
        if a:
            for j, b in enumerate(q):
                out[i + j] += a * b
    return out


def pscale(c: Fraction, p: Poly1) -> Poly1:
    return [c * a for a in p]


def bernstein(p: Poly1) -> list[Fraction]:
    """Bernstein coefficients on [0, 1] of the polynomial ``sum_j p[j] w^j`` (its own degree)."""
    n = len(p) - 1
    return [sum((Fraction(comb(k, j), comb(n, j)) * p[j] for j in range(k + 1)), Fraction(0)) for k in range(n + 1)]


def _halves(b: list[Fraction]) -> tuple[list[Fraction], list[Fraction]]:
    """de Casteljau at 1/2: Bernstein coefficients on the two halves."""
    left, right, work = [b[0]], [b[-1]], list(b)
    while len(work) > 1:
        work = [(u + v) / 2 for u, v in zip(work, work[1:])]
        left.append(work[0])
        right.append(work[-1])
    return left, right[::-1]


def positive_on_unit_interval(p: Poly1, depth: int = MAX_SUBDIVISIONS) -> bool:
    """Exact: ``p(w) > 0`` for every ``w`` in ``[0, 1]`` (Bernstein enclosure with subdivision).

    A ``True`` is a proof (the polynomial is a convex combination of its Bernstein
    coefficients on each piece); ``False`` means not proved within ``depth`` halvings.
    """
    stack = [(bernstein(p), 0)]
    while stack:
        b, level = stack.pop()
        if min(b) > 0:
            continue
        if b[0] <= 0 or b[-1] <= 0 or level >= depth:
            return False
        left, right = _halves(b)
        stack += [(left, level + 1), (right, level + 1)]
    return True


PolyMatrix = list[list[Poly1]]


def matrix_positive_definite_on_unit_interval(m: PolyMatrix) -> bool:
    """Exact: the symmetric 2x2 polynomial matrix ``m(w)`` is positive definite on ``[0, 1]``."""
    det = padd(pmul(m[0][0], m[1][1]), pscale(Fraction(-1), pmul(m[0][1], m[1][0])))
    return positive_on_unit_interval(m[0][0]) and positive_on_unit_interval(det)


# -- the certificate's matrices as polynomials in w --------------------------------------------
def _const(m: exact.Matrix) -> PolyMatrix:
    return [[[Fraction(v)] for v in row] for row in m]


def _madd(a: PolyMatrix, b: PolyMatrix) -> PolyMatrix:
    return [[padd(a[i][j], b[i][j]) for j in range(2)] for i in range(2)]


def _mscale(p: Poly1, a: PolyMatrix) -> PolyMatrix:
    return [[pmul(p, a[i][j]) for j in range(2)] for i in range(2)]


def _mmul(a: PolyMatrix, b: PolyMatrix) -> PolyMatrix:
    return [[padd(pmul(a[i][0], b[0][j]), pmul(a[i][1], b[1][j])) for j in range(2)] for i in range(2)]


def _transpose(a: PolyMatrix) -> PolyMatrix:
    return [[a[j][i] for j in range(2)] for i in range(2)]


def _sym(a: PolyMatrix) -> PolyMatrix:
    return [[pscale(Fraction(1, 2), padd(a[i][j], a[j][i])) for j in range(2)] for i in range(2)]


def _outer(u: Sequence[Poly1], v: Sequence[Poly1]) -> PolyMatrix:
    return [[pmul(u[i], v[j]) for j in range(2)] for i in range(2)]


def lyapunov_matrices(dyn: ScaledDynamics, P: exact.Matrix, ells: Sequence[Sequence[Fraction]]
                      ) -> tuple[PolyMatrix, PolyMatrix]:
    """``M(w)`` and ``D(w)`` of the module docstring, exactly (polynomials in ``w``)."""
    one = [[Fraction(1)], [Fraction(1)]]
    w: Poly1 = [Fraction(0), Fraction(1)]
    A: PolyMatrix = [[[Fraction(-1)], [dyn.c]], [[Fraction(0), dyn.b], [-dyn.a]]]
    At = _transpose(A)
    Pm = _const(P)
    M = Pm
    D = _madd(_mmul(At, Pm), _mmul(Pm, A))
    At_one = [padd(At[i][0], At[i][1]) for i in range(2)]  # A^T 1
    for k, ell in enumerate(ells, start=1):
        wk: Poly1 = [Fraction(0)] * k + [Fraction(1)]
        lcol = [[Fraction(v)] for v in ell]
        M = _madd(M, _mscale(wk, _sym(_outer(one, lcol))))
        factor = pmul(wk, padd([Fraction(1 - 2 * k)], pscale(Fraction(2 * k), w)))  # w^k (1 - 2k(1 - w))
        D = _madd(D, _mscale(factor, _sym(_outer(At_one, lcol))))
        lA = [padd(pmul(lcol[0], A[0][j]), pmul(lcol[1], A[1][j])) for j in range(2)]  # l^T A
        D = _madd(D, _mscale(wk, _sym(_outer(one, lA))))
    return M, D


def exact_check(dyn: ScaledDynamics, P: exact.Matrix, ells: Sequence[Sequence[Fraction]], mu: Fraction,
                c1: Fraction, c2: Fraction) -> tuple[bool, str]:
    """Exact: ``c1 I < M(w) < c2 I`` and ``D(w) + mu M(w) < 0`` for all ``w`` in ``[0, 1]``."""
    if not (mu > 0 and 0 < c1 < c2):
        return False, "needs mu > 0 and 0 < c1 < c2"
    M, D = lyapunov_matrices(dyn, P, ells)
    eye = _const(exact.identity(2))
    if not matrix_positive_definite_on_unit_interval(_madd(M, _mscale([-c1], eye))):
        return False, "M(w) - c1 I > 0 on [0, 1] is not proved"
    if not matrix_positive_definite_on_unit_interval(_madd(_mscale([c2], eye), _mscale([Fraction(-1)], M))):
        return False, "c2 I - M(w) > 0 on [0, 1] is not proved"
    if not matrix_positive_definite_on_unit_interval(_mscale([Fraction(-1)], _madd(D, _mscale([mu], M)))):
        return False, "-(D(w) + mu M(w)) > 0 on [0, 1] is not proved"
    return True, "c1 I < M(w) < c2 I and D(w) + mu M(w) < 0 on [0, 1], exactly (Bernstein)"


# -- numerical search --------------------------------------------------------------------------
def float_matrices(c: float, a: float, b: float, P: np.ndarray, ells: np.ndarray, w: float
                   ) -> tuple[np.ndarray, np.ndarray]:
    """``M(w)`` and ``D(w)`` in floating point (the search's model of :func:`lyapunov_matrices`), at
    one node: the readable form of the model. The search uses :func:`float_matrices_on_grid`,
    which must equal it bit for bit (``tests/test_ges.py`` holds the two together)."""
    A = np.array([[-1.0, c], [b * w, -a]])
    one = np.ones(2)
    M = P.copy()
    D = A.T @ P + P @ A
    for k, ell in enumerate(ells, start=1):
        R = np.outer(one, ell)
        M = M + w**k * (R + R.T) / 2
        T1 = np.outer(A.T @ one, ell)
        T2 = np.outer(one, ell @ A)
        D = D + w**k * (1 - 2 * k * (1 - w)) * (T1 + T1.T) / 2 + w**k * (T2 + T2.T) / 2
    return M, D


def float_matrices_on_grid(c: float, a: float, b: float, nodes: np.ndarray, terms: int
                           ) -> tuple[np.ndarray, np.ndarray]:
    """:func:`float_matrices` at every node and every unit vector of ``(P, l)``, in one pass.

    Shape ``(nodes, 3 + 2 terms, 2, 2)``. The same floating-point operations, entry by entry, as
    calling :func:`float_matrices` node by node on the unit vectors (the search's model is
    linear in ``(P, l)``): every matrix product here has at most two nonzero terms, whose sum
    does not depend on order, and the scalar factors are formed as there. A test compares the
    two bit for bit.
    """
    n1 = 3 + 2 * terms
    unit = np.eye(n1)
    P = np.empty((n1, 2, 2))
    P[:, 0, 0], P[:, 0, 1], P[:, 1, 0], P[:, 1, 1] = unit[:, 0], unit[:, 1], unit[:, 1], unit[:, 2]
    ells = unit[:, 3:].reshape(n1, terms, 2)
    w = np.asarray(nodes, dtype=np.float64)
    A = np.empty((w.size, 2, 2))
    A[:, 0, 0], A[:, 0, 1], A[:, 1, 0], A[:, 1, 1] = -1.0, c, b * w, -a
    At = A.transpose(0, 2, 1)
    M = np.broadcast_to(P, (w.size, n1, 2, 2)).copy()
    D = At[:, None] @ P[None] + P[None] @ A[:, None]
    one = np.ones(2)
    At_one = At @ one  # (nodes, 2)
    for k in range(1, terms + 1):
        ell = ells[:, k - 1]  # (n1, 2)
        R = np.broadcast_to(ell[:, None, :], (n1, 2, 2))  # outer(one, ell)
        wk = w**k
        M = M + wk[:, None, None, None] * (R + R.transpose(0, 2, 1)) / 2
        T1 = At_one[:, None, :, None] * ell[None, :, None, :]  # outer(A^T 1, ell)
        T2 = np.broadcast_to((ell[None, :, None, :] @ A[:, None])[:, :, 0][:, :, None, :], T1.shape)  # outer(1, ell A)
        f = wk * (1 - 2 * k * (1 - w))
        D = (D + f[:, None, None, None] * (T1 + T1.transpose(0, 1, 3, 2)) / 2
             + wk[:, None, None, None] * (T2 + T2.transpose(0, 1, 3, 2)) / 2)
    return M, D


def build_program(cp: Any, terms: int, points: int, vertices: int) -> tuple[Any, dict[str, Any], dict[str, Any]]:
    """The grid LMIs of :class:`_Program` as 2x2 second-order cones (DPP; compiled once per size)."""
    n = 3 + 2 * terms + 1
    rows = (2 + vertices) * points  # cones
    F = cp.Parameter((3 * rows, n), name="F")
    f0 = cp.Parameter(3 * rows, name="f0")
    z = cp.Variable(n, name="z")
    g = cp.reshape(F @ z + f0, (3, rows), order="F")  # rows of (g11, g12, g22)
    cone = cp.SOC(g[0] + g[2], cp.vstack([g[0] - g[2], 2 * g[1]]), axis=0)
    return cp.Problem(cp.Minimize(z[n - 1]), [cone]), {"F": F, "f0": f0}, {"z": z}


class _Program:
    """Grid LMIs at a given mu as 2x2 second-order cones, compiled once, re-solved.

    Unknowns ``z = (P11, P12, P22, l_1, .., l_K, t)``. At each grid point ``w`` three 2x2
    inequalities ``M >= I``, ``t I - M >= 0``, ``-(D + mu M) - MARGIN I >= 0``, each affine in
    ``z``: ``G = G0 + sum_i z_i G_i``, ``G >= 0`` iff ``g11 + g22 >= ||(g11 - g22, 2 g12)||``.
    The matrices ``G_i`` depend on the system and on mu; they are the numeric parameters of
    :func:`build_program`, compiled once (:mod:`lyapcheck.paper.conditions.compiled`). ``M`` and ``D``
    at the grid do not depend on mu: they are computed once per system and kept.
    """

    def __init__(self, terms: int, points: int, vertices: int = 1) -> None:
        from lyapcheck.paper.conditions import compiled

        self.terms = terms
        self.vertices = vertices
        self.nodes = 0.5 - 0.5 * np.cos(np.pi * np.arange(points) / (points - 1))  # Chebyshev, ends included
        self.n = 3 + 2 * terms + 1
        self.per_node = 2 + vertices  # M - I, t I - M, and one decay cone per vertex
        self.key = compiled.key_of("ges", terms, points, vertices)
        self._tables: dict[tuple[tuple[float, float, float], ...], tuple[np.ndarray, np.ndarray]] = {}

    def _unpack(self, z: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        P = np.array([[z[0], z[1]], [z[1], z[2]]])
        return P, z[3:3 + 2 * self.terms].reshape(self.terms, 2)

    def _grid(self, coefficients: tuple[tuple[float, float, float], ...]) -> tuple[np.ndarray, np.ndarray]:
        """``M`` and ``D`` at every node, vertex and unit vector: shape (nodes, vertices, n - 1, 2, 2)."""
        cached = self._tables.get(coefficients)
        if cached is None:
            shape = (len(self.nodes), len(coefficients), self.n - 1, 2, 2)
            Ms, Ds = np.zeros(shape), np.zeros(shape)
            for v, (c, a, b) in enumerate(coefficients):  # M, D are linear in (P, l): on the unit vectors
                Ms[:, v], Ds[:, v] = float_matrices_on_grid(c, a, b, self.nodes, self.terms)
            cached = self._tables.setdefault(coefficients, (Ms, Ds))
            if len(self._tables) > 8:  # a few systems at a time (a box's vertices, a point)
                self._tables.pop(next(iter(self._tables)))
        return cached

    def set_data(self, dyns: Sequence[ScaledDynamics], mu: float) -> dict[str, np.ndarray]:
        F = np.zeros((3, self.per_node * len(self.nodes), self.n))
        f0 = np.zeros((3, self.per_node * len(self.nodes)))
        coefficients = tuple((float(d.c), float(d.a), float(d.b)) for d in dyns)
        Ms, Ds = self._grid(coefficients)
        G = -(Ds + mu * Ms)  # elementwise, as -(D + mu * M) on each 2x2
        rows = self.per_node * np.arange(len(self.nodes))
        M0 = Ms[:, 0]  # (nodes, n - 1, 2, 2)
        for r, (p, q) in enumerate(((0, 0), (0, 1), (1, 1))):
            F[r, rows, : self.n - 1] = M0[:, :, p, q]
            F[r, rows + 1, : self.n - 1] = -M0[:, :, p, q]
            for v in range(len(coefficients)):
                F[r, rows + 2 + v, : self.n - 1] = G[:, v, :, p, q]
        F[:, rows + 1, self.n - 1] = np.array([1.0, 0.0, 1.0])[:, None]  # + t I
        f0[:, rows] = np.array([-1.0, 0.0, -1.0])[:, None]  # M - I
        for v in range(len(coefficients)):
            f0[:, rows + 2 + v] = np.array([-MARGIN, 0.0, -MARGIN])[:, None]
        return {"F": F.transpose(1, 0, 2).reshape(-1, self.n), "f0": f0.T.reshape(-1)}

    def attempt(self, dyns: Sequence[ScaledDynamics], mu: float) -> tuple[Any, Any]:
        from lyapcheck.paper.conditions import compiled

        if len(dyns) != self.vertices:
            raise ValueError(f"The 'dyns' parameter must hold {self.vertices} systems. Got {len(dyns)} instead.")
        solved = compiled.load(self.key).solve(self.set_data(dyns, mu))
        if solved.report.outcome not in ("optimal", "inaccurate") or solved.values is None:
            return None, solved.report
        return self._unpack(solved.values["z"]), solved.report


@lru_cache(maxsize=8)
def program(terms: int = TERMS, points: int = GRID_POINTS, vertices: int = 1) -> _Program:
    return _Program(terms, points, vertices)


def _bounds(dyn: ScaledDynamics, P: exact.Matrix, ells: Sequence[Sequence[Fraction]]) -> tuple[Fraction, Fraction]:
    """Rational c1 < min and c2 > max of the eigenvalues of M(w) over a fine grid of [0, 1]."""
    Pf = np.array(exact.to_float(P))
    grid = np.linspace(0, 1, 401)
    M = np.broadcast_to(Pf, (grid.size, 2, 2)).copy()
    for k, ell in enumerate(ells, start=1):
        l = np.array([float(v) for v in ell])
        S = np.outer(np.ones(2), l) + np.outer(l, np.ones(2))
        wk = np.array([wv**k for wv in grid])  # the scalar powers, as one node at a time computed them
        M += wk[:, None, None] * S / 2
    eig = np.linalg.eigvalsh(M)
    lo, hi = float(eig[:, 0].min()), float(eig[:, -1].max())
    return exact.to_rational(lo * 0.99, 6), exact.to_rational(hi * 1.01, 6)


def certificate_json(P: exact.Matrix, ells: Sequence[Sequence[Fraction]], mu: Fraction, c1: Fraction,
                     c2: Fraction) -> dict[str, Any]:
    return {"P": exact.to_json(P), "l": [[str(v) for v in ell] for ell in ells], "mu_scaled": str(mu),
            "c1": str(c1), "c2": str(c2)}


def _from_json(cert: dict[str, Any]) -> tuple[exact.Matrix, list[list[Fraction]], Fraction, Fraction, Fraction]:
    return (exact.from_json(cert["P"]), [[Fraction(v) for v in ell] for ell in cert["l"]],
            Fraction(cert["mu_scaled"]), Fraction(cert["c1"]), Fraction(cert["c2"]))


def _exact_candidate(dyns: Sequence[ScaledDynamics], found: Any, mu: float) -> dict[str, Any] | None:
    P = exact.symmetrize(exact.rational_matrix(found[0], 8))
    ells = [[exact.to_rational(float(v), 8) for v in ell] for ell in found[1]]
    c1, c2 = _bounds(dyns[0], P, ells)
    for share in BACK_OFF:
        mu_q = exact.to_rational(mu * share, 4)
        if all(exact_check(dyn, P, ells, mu_q, c1, c2)[0] for dyn in dyns):
            return certificate_json(P, ells, mu_q, c1, c2)
    return None


def search(dyns: Sequence[ScaledDynamics], log: list[dict[str, Any]]) -> dict[str, Any] | None:
    """The exactly checked certificate with the largest decay rate found, common to ``dyns``.

    Bisection on mu (geometric), each step decided by the exact check of the rounded solver
    point, never by the solver's status: the solver often stops at "inaccurate" on these badly
    scaled data, and its point is still a fine candidate.
    """
    prog = program(vertices=len(dyns))

    def proved(mu: float) -> dict[str, Any] | None:
        candidate, report = prog.attempt(dyns, mu)
        log.append(report.to_json())
        return None if candidate is None else _exact_candidate(dyns, candidate, mu)

    cert = proved(MU_LOW)
    lo, hi = MU_LOW, MU_HIGH
    if cert is None:
        cert = proved(MU_FLOOR)
        lo, hi = MU_FLOOR, MU_LOW
    if cert is None:
        return None
    for _ in range(MU_BISECTION_STEPS):
        mid = float(np.sqrt(lo * hi))
        better = proved(mid)
        if better is not None:
            lo, cert = mid, better
        else:
            hi = mid
    return cert


def _numbers(system: System, dyn: ScaledDynamics, cert: dict[str, Any]) -> dict[str, Any]:
    _, _, mu, c1, c2 = _from_json(cert)
    k = float(np.sqrt(float(c2 / c1)))
    lam = float(mu * dyn.time_scale) / 2
    sigma0 = float(system.sigma0)
    # x = diag(1, sigma0) (eps, s)/Delta: the constant for |(eps, s)| pays the conditioning of that map
    k_eps_s = k * max(1.0, sigma0) / min(1.0, sigma0)
    return {"k": k, "decay_rate_per_s": lam, "k_eps_s": k_eps_s, "decay_rate_V_per_s": 2 * lam,
            "norm": "|(eps, sigma0 s)|/Delta for k; |(eps, s)| for k_eps_s", "terms": len(cert["l"])}


def run(system: System) -> ConditionResult:
    """Search ``V = x^T M(w) x`` (module docstring) and prove GES exactly, with k and lambda."""
    dyn = scaled_dynamics(system)
    if dyn is None:
        return ConditionResult("ges", "not_certified", "the dynamics do not have the structure this class needs")
    log: list[dict[str, Any]] = []
    cert = search([dyn], log)
    if cert is None:
        return ConditionResult("ges", "not_certified",
                               f"no state-dependent quadratic V with {TERMS} terms passed the exact check (decay "
                               f"rate >= {MU_FLOOR:g} in scaled time); this is not a proof that GES fails",
                               solver={"solves": log})
    numbers = _numbers(system, dyn, cert)
    summary = (f"GES: |x(t)| <= {numbers['k']:.3g} |x0| exp(-{numbers['decay_rate_per_s']:.3g} t) for every start "
               f"(x = (eps, sigma0 s)/Delta; k = {numbers['k_eps_s']:.3g} for |(eps, s)|), from a quadratic form "
               "whose matrix depends on (eps + sigma0 s)/Delta, exactly checked")
    scaling = {"time_scale": str(dyn.time_scale), "c": str(dyn.c), "a": str(dyn.a), "b": str(dyn.b)}
    return ConditionResult("ges", "certified", summary, numbers=numbers,
                           certificate={**cert, "scaling": scaling}, solver={"solves": log})


def verify(system: System, cert: dict[str, Any]) -> tuple[bool, str]:
    """Re-check a ``ges`` certificate exactly against ``system`` (no solver)."""
    from lyapcheck.paper.conditions.sos import stored_scaling_mismatch

    dyn, mismatch = stored_scaling_mismatch(system, cert)
    if dyn is None or mismatch is not None:
        return False, mismatch or ""
    P, ells, mu, c1, c2 = _from_json(cert)
    if not exact.is_symmetric(P) or any(len(ell) != 2 for ell in ells) or len(P) != 2:
        return False, "P must be a symmetric 2x2 matrix and each l a 2-vector"
    return exact_check(dyn, P, ells, mu, c1, c2)
