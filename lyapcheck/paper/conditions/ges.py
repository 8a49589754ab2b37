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

Search (:func:`search`). The same three inequalities, with ``c1 = 1``, ``c2 = t`` minimised and a
margin in the third, are imposed on ALL of ``[0, 1]`` as sums of squares (:func:`build_program`,
Lukacs' theorem), with coefficients computed exactly from the dynamics. Until issue 24 they were
imposed at 24 grid points of ``w``: the optimal solutions then formed a face, and which point of
it the solver stopped at decided whether the exact check passed between the grid points, so the
decay-rate bisection followed the platform's last bits (a relative perturbation of 1e-13 in the
data made the first rate fail at the paper's gains, and at the centre of sweep-kd-delta dropped the
certified rate from 0.051 to 9e-7 1/s). Every solution of the interval program passes the exact
check with the margin to spare.
"""

from __future__ import annotations

import math
from fractions import Fraction
from functools import lru_cache
from math import comb
from typing import Any, Mapping, Sequence

import numpy as np

from lyapcheck import exact
from lyapcheck.paper import claims
from lyapcheck.paper.claims import envelope
from lyapcheck.paper.conditions.base import System
from lyapcheck.paper.conditions.rate_search import largest_proved_rate
from lyapcheck.paper.conditions.rounding import ceil_to_digits, floor_to_digits
from lyapcheck.results import ConditionResult
from lyapcheck.paper.conditions.sos import ScaledDynamics, scaled_dynamics

#: number of y-weighted terms w^k y l_k^T x (the decay rate it certifies grows with K: 3 gives
#: about 0.06, 4 about 0.9, 6 about 1.9 in scaled time at the paper's gains)
TERMS = 4
#: decay-rate search of mu in scaled time: geometric bisection between these, then a back-off
MU_LOW, MU_HIGH = 1 / 64, 4.0
#: tried when MU_LOW fails: a slow certified decay is still GES (e.g. the printed dynamics,
#: whose scaled time runs 1/e11 times faster)
MU_FLOOR = 1e-7
MU_BISECTION_STEPS = 6
#: the search asks for -(D + mu M) >= MARGIN s t I on all of [0, 1] (M <= t I; s the largest of
#: 1, |a|, |b|, |c|, the scale of D / t): a margin proportional to D, 300 times the rounding of P
#: and l to 8 digits and above the residual of an "inaccurate" solve (with 1e-6, such solves
#: near the largest feasible rate failed the exact check on some platforms; with 1e-4 the
#: margin cost certificates: two points of the snapshot)
MARGIN = 3e-6
#: the certificate's bounds c1 I < M(w) < c2 I: c1 = C1 below the program's M >= I, c2 this share
#: above its optimum t, rounded up to 6 digits (see _bounds)
C1 = Fraction(99, 100)
BOUND_SLACK = 1e-2
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
def polynomial_tables(dyn: ScaledDynamics, terms: int = TERMS) -> tuple[np.ndarray, np.ndarray]:
    """The coefficients of ``M(w)`` and ``D(w)`` as linear maps of the unknowns ``(P, l)``.

    Shape ``(3 + 2 terms, degree + 1, 2, 2)``: entry ``[i, j]`` is the coefficient of ``w^j`` with
    the ``i``-th unknown set to 1 and the others to 0 (both are linear in ``(P, l)``), computed
    exactly by :func:`lyapunov_matrices` and then rounded to doubles: the same numbers on every
    floating-point platform. ``M`` has degree ``terms``, ``D`` degree ``terms + 2``.
    """
    return _tables(dyn.c, dyn.a, dyn.b, terms)


@lru_cache(maxsize=32)
def _tables(c: Fraction, a: Fraction, b: Fraction, terms: int) -> tuple[np.ndarray, np.ndarray]:
    dyn = ScaledDynamics(time_scale=Fraction(1), c=c, a=a, b=b)
    n1 = 3 + 2 * terms
    Ms, Ds = np.zeros((n1, terms + 1, 2, 2)), np.zeros((n1, terms + 3, 2, 2))
    for i in range(n1):
        z = [Fraction(int(i == k)) for k in range(n1)]
        P = ((z[0], z[1]), (z[1], z[2]))
        ells = [z[3 + 2 * k: 5 + 2 * k] for k in range(terms)]
        M, D = lyapunov_matrices(dyn, P, ells)
        for out, poly_matrix in ((Ms, M), (Ds, D)):
            for p in range(2):
                for q in range(2):
                    for j, coefficient in enumerate(poly_matrix[p][q]):
                        out[i, j, p, q] = float(coefficient)
    Ms.flags.writeable = Ds.flags.writeable = False
    return Ms, Ds


def inequalities(terms: int, vertices: int) -> list[tuple[str, int]]:
    """The polynomial matrix inequalities of the search and their degrees in ``w``: ``M - I``,
    ``t I - M`` and, at each vertex, the decay inequality (:func:`build_program`)."""
    return [("lower", terms), ("upper", terms)] + [(f"decay_{v}", terms + 2) for v in range(vertices)]


#: entries (p, q) of a symmetric 2x2 matrix, in the order of the coefficient rows
_ENTRIES = ((0, 0), (0, 1), (1, 1))


def _gram_side(X: Any, Y: Any, half: int) -> Any:
    """The coefficients of ``Z(w)^T X Z(w) + w (1 - w) Z'(w)^T Y Z'(w)``, ``Z = (I, w I, .., w^half I)``,
    ``Z'`` up to ``w^(half - 1)``: row ``3 j + e`` is entry ``_ENTRIES[e]`` of the ``w^j`` coefficient."""
    rows = []
    for j in range(2 * half + 1):
        for p, q in _ENTRIES:
            terms = [X[2 * u + p, 2 * (j - u) + q] for u in range(half + 1) if 0 <= j - u <= half]
            terms += [Y[2 * u + p, 2 * (j - 1 - u) + q] for u in range(half) if 0 <= j - 1 - u <= half - 1]
            terms += [-Y[2 * u + p, 2 * (j - 2 - u) + q] for u in range(half) if 0 <= j - 2 - u <= half - 1]
            rows.append(sum(terms[1:], terms[0]))
    return rows


def build_program(cp: Any, terms: int, vertices: int) -> tuple[Any, dict[str, Any], dict[str, Any]]:
    """min t s.t. every inequality of :func:`inequalities` holds on all of ``[0, 1]`` (DPP; compiled
    once per size; see :func:`search`).

    A symmetric 2x2 polynomial matrix ``G(w)`` of degree ``<= 2h`` is positive semidefinite on
    ``[0, 1]`` when ``G = Z^T X Z + w (1 - w) Z'^T Y Z'`` with ``X, Y >= 0`` (the matrix form of
    Lukacs' theorem; :func:`_gram_side`): so the search asks for each inequality on the whole
    interval, not at grid points. Its coefficients are affine in the unknowns
    ``z = (P11, P12, P22, l_1, .., l_K, t)``: ``C z + c0``, with ``C`` and ``c0`` the parameters.
    """
    n = 3 + 2 * terms + 1
    z = cp.Variable(n, name="z")
    cons: list[Any] = []
    params: dict[str, Any] = {}
    for name, degree in inequalities(terms, vertices):
        half = (degree + 1) // 2
        C = cp.Parameter((3 * (2 * half + 1), n), name=f"C_{name}")
        c0 = cp.Parameter(3 * (2 * half + 1), name=f"c0_{name}")
        X = cp.Variable((2 * half + 2, 2 * half + 2), symmetric=True, name=f"X_{name}")
        Y = cp.Variable((2 * half, 2 * half), symmetric=True, name=f"Y_{name}")
        gram = _gram_side(X, Y, half)
        cons += [X >> 0, Y >> 0]
        cons += [C[r] @ z + c0[r] == gram[r] for r in range(len(gram))]
        params[f"C_{name}"], params[f"c0_{name}"] = C, c0
    return cp.Problem(cp.Minimize(z[n - 1]), cons), params, {"z": z}


class _Program:
    """The search program of :func:`build_program` for ``terms`` and ``vertices``, compiled once,
    re-solved with the data of :meth:`set_data`."""

    def __init__(self, terms: int, vertices: int = 1) -> None:
        from lyapcheck.paper.conditions import compiled

        self.terms = terms
        self.vertices = vertices
        self.n = 3 + 2 * terms + 1
        self.key = compiled.key_of("ges", terms, vertices)

    def _unpack(self, z: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        P = np.array([[z[0], z[1]], [z[1], z[2]]])
        return P, z[3:3 + 2 * self.terms].reshape(self.terms, 2)

    def set_data(self, dyns: Sequence[ScaledDynamics], mu: float) -> dict[str, np.ndarray]:
        """The coefficients ``C z + c0`` of every inequality at ``mu`` (:func:`build_program`):
        ``M - I``, ``t I - M`` and ``-(D_v + mu M) - margin t I`` at each vertex ``v``, with the
        margin :data:`MARGIN` times the vertex's largest coefficient (``D`` scales with it)."""
        values: dict[str, np.ndarray] = {}
        Ms, _ = polynomial_tables(dyns[0], self.terms)
        diagonal = np.array([1.0, 0.0, 1.0])

        def coefficients(table: np.ndarray, degree: int) -> np.ndarray:
            """``(unknowns, degree + 1, 2, 2)`` -> rows ``3 j + e`` by unknown (zero-padded to the even degree)."""
            half = (degree + 1) // 2
            out = np.zeros((3 * (2 * half + 1), self.n))
            for j in range(table.shape[1]):
                for e, (p, q) in enumerate(_ENTRIES):
                    out[3 * j + e, : self.n - 1] = table[:, j, p, q]
            return out

        def constant(degree: int, diagonal_at_0: float) -> np.ndarray:
            out = np.zeros(3 * ((degree + 1) // 2 * 2 + 1))
            out[:3] = diagonal_at_0 * diagonal
            return out

        values["C_lower"], values["c0_lower"] = coefficients(Ms, self.terms), constant(self.terms, -1.0)
        upper = -coefficients(Ms, self.terms)
        upper[:3, self.n - 1] = diagonal
        values["C_upper"], values["c0_upper"] = upper, constant(self.terms, 0.0)
        for v, dyn in enumerate(dyns):
            _, Ds = polynomial_tables(dyn, self.terms)
            # divided by its scale (the same inequality), so that its Gram matrices are of the order of t
            scale = max(1.0, abs(float(dyn.a)), abs(float(dyn.b)), abs(float(dyn.c)))
            decay = -(coefficients(Ds, self.terms + 2) + mu * coefficients(Ms, self.terms + 2)) / scale
            decay[:3, self.n - 1] = -MARGIN * diagonal
            values[f"C_decay_{v}"], values[f"c0_decay_{v}"] = decay, constant(self.terms + 2, 0.0)
        return values

    def attempt(self, dyns: Sequence[ScaledDynamics], mu: float) -> tuple[Any, Any]:
        """Solve at ``mu``: ``((P, l, t), report)``, or ``(None, report)`` without a point."""
        from lyapcheck.paper.conditions import compiled

        if len(dyns) != self.vertices:
            raise ValueError(f"The 'dyns' parameter must hold {self.vertices} systems. Got {len(dyns)} instead.")
        solved = compiled.load(self.key).solve(self.set_data(dyns, mu))
        if solved.report.outcome not in ("optimal", "inaccurate") or solved.values is None:
            return None, solved.report
        z = solved.values["z"]
        return (*self._unpack(z), float(z[self.n - 1])), solved.report


@lru_cache(maxsize=8)
def program(terms: int = TERMS, vertices: int = 1) -> _Program:
    return _Program(terms, vertices)


def _bounds(t: float) -> tuple[Fraction, Fraction]:
    """Rational ``c1 < 1`` and ``c2 > t`` for a solution with ``I <= M(w) <= t I`` on ``[0, 1]``.

    Fixed shares of the program's own bounds (1 % each side, far above the rounding of ``P`` and
    ``l``), not ``M``'s extreme eigenvalues: where the optimal solutions form a face, those move
    within it from one solve to the next, while ``t``, the optimum, does not."""
    return C1, ceil_to_digits(t * (1 + BOUND_SLACK), 6)


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
    c1, c2 = _bounds(found[2])
    mu_q = floor_to_digits(mu, 4)  # down: the solution holds at mu, so at any smaller rate
    if all(exact_check(dyn, P, ells, mu_q, c1, c2)[0] for dyn in dyns):
        return certificate_json(P, ells, mu_q, c1, c2)
    return None


def search(dyns: Sequence[ScaledDynamics], log: list[dict[str, Any]]) -> dict[str, Any] | None:
    """The exactly checked certificate with the largest decay rate found, common to ``dyns``.

    Bisection on mu (geometric, :data:`MU_BISECTION_STEPS` steps), each step decided by the exact
    check of the rounded solver point, never by the solver's status: the solver often stops at
    "inaccurate" on these badly scaled data, and its point is still a fine candidate. The rate
    checked is ``mu`` rounded down to 4 digits, never a fraction of it: a solve just beyond the
    feasible rates (reported infeasible on one platform, "inaccurate" with a point on another)
    once passed at 0.8 ``mu`` and moved the bisection on that platform only.
    """
    prog = program(vertices=len(dyns))

    def proved(mu: float) -> dict[str, Any] | None:
        candidate, report = prog.attempt(dyns, mu)
        log.append(report.to_json())
        return None if candidate is None else _exact_candidate(dyns, candidate, mu)

    return largest_proved_rate(proved, low=MU_LOW, high=MU_HIGH, floor=MU_FLOOR, steps=MU_BISECTION_STEPS)


def _numbers(system: System, dyn: ScaledDynamics, cert: dict[str, Any]) -> dict[str, Any]:
    k, lam, k_eps_s = envelope(cert, system.sigma0, dyn.time_scale)
    return {"k": k, "decay_rate_per_s": lam, "k_eps_s": k_eps_s, "decay_rate_V_per_s": 2 * lam,
            "norm": claims.GES_NORM, "terms": len(cert["l"])}


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
    scaling = {"time_scale": str(dyn.time_scale), "c": str(dyn.c), "a": str(dyn.a), "b": str(dyn.b)}
    return claims.decided(ConditionResult("ges", "certified", "", numbers=numbers,
                                          certificate={**cert, "scaling": scaling}, solver={"solves": log}),
                          {"sigma0": system.sigma0})


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
