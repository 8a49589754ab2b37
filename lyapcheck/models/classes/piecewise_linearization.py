"""``linearization`` where a kinked function sits exactly at its kink at the equilibrium (issue 44, item 3):
``abs`` of an argument that is 0 there, ``relu`` (``max(0, z) = (z + |z|)/2``, how a network's ReLU neurons
are recast) of a neuron whose pre-activation is 0 there, ``sat`` at one of its corners. The Jacobian does not
exist (:func:`lyapcheck.models.classes.recast_classes.jacobian` says so); this module proves local exponential
stability from the loop's piecewise-linear first-order part instead, on loops with functions and on
discrete-time maps with functions.

The first-order part. Walk the auxiliaries in order (an argument uses only the states and earlier
auxiliaries). Each variable ``v`` gets a linear form ``L_v`` in ``w = (e, phi)``, ``e`` the deviations of
the states and ``phi`` one coordinate per kink, with ``v - v(eq) = L_v . w(e) + O(|e|^2)`` where
``w(e)`` holds the exact piecewise-linear values below:

- a state: its unit vector; a smooth function of ``u`` (``sin``, ``tanh``, ...) and a kinked one away from
  its kink: its slope at ``u(eq)`` times ``L_u`` (the chain rule: ``jacobian``'s own walk,
  :func:`~lyapcheck.models.classes.recast_classes.first_order`, with the kinks below as coordinates);
- a kink ``a_i = |u_i|`` with ``u_i(eq) = 0``: a new coordinate ``phi_i = |z_i|`` with
  ``z_i = l_i . w``, ``l_i = L_{u_i}`` (it uses only ``e`` and earlier ``phi``). Since ``|.|`` is
  1-Lipschitz, ``|a_i - phi_i| <= |u_i - z_i| = O(|e|^2)`` by induction on ``i``;
- ``sat(u, L)`` at its upper corner ``u(eq) = L``: ``sat(u) - L = min(0, u - L)``, so ``phi_i = min(0, z_i)``;
  at its lower corner ``max(0, z_i)`` (both 1-Lipschitz too).

Then the field (a right-hand side ``N / D`` with ``D(eq) != 0``, ``N(eq) = 0``) is
``f(e) = A e + B phi(e) + O(|e|^2)``, and a map's step ``F(e) = (I + A) e + B phi(e) + O(|e|^2)``.
Every ``phi_i`` is ``O(|e|)``, and the field is locally Lipschitz (abs and sat are), so solutions are unique.

The proof. ``V = e^T P e`` with ``P > 0``. Continuous time:
``V' = 2 e^T P (A e + B phi) + O(|e|^3)``; discrete time:
``V(F(e)) - V(e) = (C w)^T P (C w) - e^T P e + O(|e|^3)`` with ``C = [I + A, B]``. Each is a quadratic form
``Q(w)`` plus ``O(|e|^3)``; if ``Q(w) + eps |e|^2 <= 0`` at every point of the kinks' set

    ``K = {w : phi_i^2 = z_i^2, phi_i >= 0}`` (abs; ``phi_i - z_i >= 0``, ``phi_i + z_i >= 0`` follow),
    ``{phi_i (phi_i - z_i) = 0, phi_i >= 0, phi_i - z_i >= 0}`` (the lower corner, ``max(0, z)``),
    ``{phi_i (phi_i - z_i) = 0, -phi_i >= 0, z_i - phi_i >= 0}`` (the upper corner, ``min(0, z)``),

which holds every ``w(e)``, then ``V`` decreases by at least ``eps |e|^2 / 2`` near the equilibrium: locally
exponentially stable (continuous time: ``V' <= -(eps / 2 lambda_max(P)) V``; discrete time: a contraction
of ``V`` by ``1 - eps / (2 lambda_max(P))`` per step). The inequality on ``K`` is proved by the S-procedure:

    ``M = Q + eps E^T E - sum_i lambda_i (equality_i) + sum_k nu_k g_a g_b  <=  0`` (negative semidefinite),

``g_a, g_b`` two of the nonnegative linear forms above (of one kink, or of any two when there are at most
:data:`~lyapcheck.tolerances.PIECEWISE_PAIR_FORMS` forms), ``nu >= 0``, ``lambda`` free. On ``K`` the
equalities vanish and the products are ``>= 0``, so ``Q + eps |e|^2 <= w^T M w <= 0``. For a fixed eps this is
an LMI in ``(P, lambda, nu)``; Clarabel solves it (its answer is evidence only), ``P``, ``lambda``, ``nu`` are
rounded to short dyadic rationals, and the certificate is the exact check: ``P`` positive definite (exact),
``nu >= 0``, ``-M`` positive semidefinite (exact symmetric elimination).

Nothing is ever refuted here: a pattern of the kinks whose linear loop is unstable may never be realized
near the equilibrium (a cone the trajectories never stay in), and the S-procedure is only sufficient.
Not found is ``not_certified`` with the reason. The search keeps the class's budget
(:class:`~lyapcheck.models.engines.search.Budget`, checked between the solves and the exact steps: ``inconclusive``
once spent), and a loop with more than :data:`~lyapcheck.tolerances.PIECEWISE_MAX_KINKS` kinks is refused by
that count before any LMI is built (``not_certified``, the size limit named). ``verify`` re-derives ``A``, ``B`` and every ``l_i`` from the
model text (:func:`derive`) and re-checks ``M`` exactly (:func:`check`): a forged ``P`` fails.
"""

from __future__ import annotations

from dataclasses import dataclass
from fractions import Fraction
from typing import TYPE_CHECKING, Any, Final, Sequence

from lyapcheck import tolerances
from lyapcheck.exact import read_rational
from lyapcheck.models.engines import reasons
from lyapcheck.models.engines.search import Budget, BudgetExhausted
from lyapcheck.results import ConditionResult

if TYPE_CHECKING:  # pragma: no cover
    from lyapcheck.models.classes.recast_classes import Loop
    from lyapcheck.models.language.recast import RecastModel

Matrix = list[list[Fraction]]

#: the certificate kind and its method (a ``linearization`` certificate; :func:`sentence` reads it)
KIND: Final = "piecewise_linear"
#: the shapes of a kink: ``phi = |z|``, ``phi = max(0, z)`` (sat's lower corner), ``phi = min(0, z)`` (upper)
SHAPES: Final = ("abs", "max0", "min0")

CERTIFIED_FIELD: Final = ("locally exponentially stable: near the equilibrium the field is A e + B phi + O(|e|^2), "
                          "phi the kinked functions' piecewise-linear values (abs, ReLU, a saturation's corner at "
                          "the equilibrium), and V = e^T P e has 2 e^T P (A e + B phi) <= -eps |e|^2 on every pattern "
                          "of the kinks (S-procedure; P > 0, the multipliers and the form checked exactly)")
CERTIFIED_MAP: Final = ("the discrete-time map is locally exponentially stable at its fixed point: near it the step is "
                        "(I + A) e + B phi + O(|e|^2), phi the kinked functions' piecewise-linear values (abs, ReLU, a "
                        "saturation's corner at the fixed point), and V = e^T P e decreases by at least eps |e|^2 on "
                        "every pattern of the kinks (S-procedure; P > 0, the multipliers and the form checked exactly)")


@dataclass(frozen=True)
class Kink:
    """One kinked auxiliary at its kink: ``phi = shape(z)``, ``z = form . w`` (``w = (e, phi)``, the
    form's entries on later ``phi`` are 0)."""

    name: str
    written: str
    shape: str
    form: tuple[Fraction, ...]


@dataclass(frozen=True)
class PiecewiseLinear:
    """The loop's first-order part at the equilibrium: ``f(e) = A e + B phi(e) + O(|e|^2)``."""

    n: int
    kinks: tuple[Kink, ...]
    A: Matrix
    B: Matrix

    @property
    def width(self) -> int:
        """The dimension of ``w = (e, phi)``."""
        return self.n + len(self.kinks)


def derive(loop: "Loop") -> PiecewiseLinear | str:
    """The first-order part (module docstring) of ``loop``'s field, or why there is none here (no kink at
    the equilibrium, a square root at 0, an irrational entry, a box's bounded constants): the Jacobian's
    chain rule (:func:`lyapcheck.models.classes.recast_classes.first_order`) with a coordinate per kink."""
    from lyapcheck.models.classes.recast_classes import _argument_value, first_order

    system = loop.system
    if loop.fixed:
        return "the piecewise-linear route is not built over a box of parameters"
    n = system.n
    at: dict[str, Fraction] = {a.name: _argument_value(system, a) for a in system.auxiliaries if a.argument is not None}
    kinked = kinks_at_equilibrium(loop)
    if not kinked:
        return "no abs, ReLU or saturation sits at its kink at the equilibrium"
    walked = first_order(loop, kinked)
    if isinstance(walked, str):
        return walked
    kinks = tuple(Kink(a.name, a.written_as or a.definition,
                       "abs" if a.function == "abs" else ("min0" if at[a.name] > 0 else "max0"), tuple(du))
                  for a, du in walked.kinks)
    return PiecewiseLinear(n, kinks, [row[:n] for row in walked.rows], [row[n:] for row in walked.rows])


def kinks_at_equilibrium(loop: "Loop") -> list[str]:
    """The auxiliaries (names, in order) at their kink at the equilibrium: ``abs`` of an argument 0 there,
    ``sat`` at a corner. Their count alone, before the chain rule's walk (:func:`derive`)."""
    from lyapcheck.models.classes.recast_classes import _argument_value

    return [a.name for a in loop.system.auxiliaries if a.argument is not None and
            ((a.function == "abs" and _argument_value(loop.system, a) == 0) or
             (a.function == "sat" and abs(_argument_value(loop.system, a)) == a.limit))]


# -- the S-procedure's pieces ------------------------------------------------------------------------

def _unit(width: int, j: int) -> list[Fraction]:
    return [Fraction(int(k == j)) for k in range(width)]


def nonnegative_forms(pl: PiecewiseLinear) -> list[tuple[int, list[Fraction]]]:
    """The linear forms ``>= 0`` on the kinks' set, each with its kink's index."""
    out: list[tuple[int, list[Fraction]]] = []
    for i, k in enumerate(pl.kinks):
        phi = _unit(pl.width, pl.n + i)
        z = list(k.form)
        plus = [p + q for p, q in zip(phi, z)]
        minus = [p - q for p, q in zip(phi, z)]
        if k.shape == "abs":
            out += [(i, phi), (i, minus), (i, plus)]
        elif k.shape == "max0":
            out += [(i, phi), (i, minus)]
        else:
            out += [(i, [-p for p in phi]), (i, [-m for m in minus])]
    return out


#: a quadratic form ``sum c (g . w)(h . w)``, as its terms ``(c, g, h)``
Products = list[tuple[int, list[Fraction], list[Fraction]]]


def equalities(pl: PiecewiseLinear) -> list[Products]:
    """The quadratic forms ``= 0`` on the kinks' set: ``phi^2 - z^2`` for abs, ``phi (phi - z)`` (that is
    ``phi^2 - phi z``) for a saturation's corner."""
    out: list[Products] = []
    for i, k in enumerate(pl.kinks):
        phi = _unit(pl.width, pl.n + i)
        z = list(k.form)
        out.append([(1, phi, phi), (-1, z, z)] if k.shape == "abs" else [(1, phi, phi), (-1, phi, z)])
    return out


def pairs(pl: PiecewiseLinear) -> list[tuple[int, int]]:
    """The products ``g_a g_b`` (``a < b``, indices into :func:`nonnegative_forms`) the S-procedure uses."""
    forms = nonnegative_forms(pl)
    every = len(forms) <= tolerances.PIECEWISE_PAIR_FORMS
    return [(a, b) for a in range(len(forms)) for b in range(a + 1, len(forms)) if every or forms[a][0] == forms[b][0]]


def _add_outer(M: Matrix, c: Fraction, g: Sequence[Fraction], h: Sequence[Fraction]) -> None:
    """``M += c (g h^T + h g^T) / 2`` (the symmetric matrix of ``c (g . w)(h . w)``), over the forms' nonzero
    entries only (each kink's form is sparse: a network's has the states and one layer's kinks)."""
    half = c / 2
    right = [(j, y) for j, y in enumerate(h) if y]
    for i, x in enumerate(g):
        if x:
            for j, y in right:
                M[i][j] += half * x * y
                M[j][i] += half * x * y


def _stacked(pl: PiecewiseLinear, discrete: bool) -> tuple[Matrix, Matrix]:
    """``E = [I 0]`` and ``C = [A B]`` (a map: ``[I + A, B]``), both ``n x width``."""
    n = pl.n
    E = [_unit(pl.width, i) for i in range(n)]
    C = [[(pl.A[i][j] + (1 if discrete and i == j else 0)) for j in range(n)] + list(pl.B[i]) for i in range(n)]
    return E, C


def form_matrix(pl: PiecewiseLinear, discrete: bool, P: Matrix, eps: Fraction, lam: Sequence[Fraction],
                nu: Sequence[Fraction], products: Sequence[tuple[int, int]], budget: Budget | None = None) -> Matrix:
    """``M`` (module docstring), exactly (``budget`` checked between the kinks' terms: a search's own
    check; verify's has none)."""
    E, C = _stacked(pl, discrete)
    N, n = pl.width, pl.n
    PC = [[sum((P[i][k] * C[k][j] for k in range(n)), Fraction(0)) for j in range(N)] for i in range(n)]
    if discrete:  # C^T P C - E^T P E
        M = [[sum((C[k][i] * PC[k][j] for k in range(n)), Fraction(0)) for j in range(N)] for i in range(N)]
        for i in range(n):
            for j in range(n):
                M[i][j] -= P[i][j]
    else:  # E^T P C + C^T P E
        M = [[Fraction(0)] * N for _ in range(N)]
        for i in range(n):
            for j in range(N):
                M[i][j] += PC[i][j]
                M[j][i] += PC[i][j]
    for i in range(n):
        M[i][i] += eps
    for c, terms in zip(lam, equalities(pl)):
        _tick(budget)
        for sign, g, h in terms if c else ():
            _add_outer(M, -c * sign, g, h)
    forms = nonnegative_forms(pl)
    for c, (a, b) in zip(nu, products):
        _tick(budget)
        if c:
            _add_outer(M, c, forms[a][1], forms[b][1])
    del E
    return M


def check(pl: PiecewiseLinear, discrete: bool, P: Matrix, eps: Fraction, lam: Sequence[Fraction],
          nu: Sequence[Fraction], products: Sequence[tuple[int, int]], budget: Budget | None = None
          ) -> tuple[bool, str]:
    """The exact check of a certificate's numbers against the first-order part ``pl`` (``budget``: the
    search's, checked before each exact step)."""
    from lyapcheck.sos.definiteness import is_positive_definite, is_positive_semidefinite

    n = pl.n
    if len(P) != n or any(len(row) != n for row in P):
        return False, f"P must be {n} x {n}"
    if eps <= 0:
        return False, "epsilon must be > 0"
    if len(lam) != len(pl.kinks):
        return False, f"one lambda per kink ({len(pl.kinks)}) is needed"
    if len(nu) != len(products):
        return False, "one nu per product is needed"
    forms = len(nonnegative_forms(pl))
    if any(not (0 <= a < b < forms) for a, b in products):
        return False, f"a product names no pair of the {forms} nonnegative forms"
    if any(c < 0 for c in nu):
        return False, "a multiplier nu of a product is negative"
    if not is_positive_definite(P):
        return False, "P is not positive definite (exact)"
    M = form_matrix(pl, discrete, P, eps, lam, nu, products, budget)
    _tick(budget)
    if not is_positive_semidefinite([[-x for x in row] for row in M]):
        return False, "the S-procedure's form is not negative semidefinite (exact)"
    return True, "P > 0, nu >= 0 and the S-procedure's form <= 0, exact: locally exponentially stable"


# -- the search ---------------------------------------------------------------------------------------

def _tick(budget: Budget | None) -> None:
    """The search's budget checked (BudgetExhausted once spent); nothing without one (verify)."""
    if budget is not None:
        budget.check()


def default_budget() -> Budget:
    """A class's own budget, for a caller that passes none (a direct call; the runner passes its class's)."""
    return Budget(tolerances.MODEL_CLASS_TIME_LIMIT_S, "lyapcheck.tolerances.MODEL_CLASS_TIME_LIMIT_S")


def too_large(kinks: int) -> str | None:
    """The size limit's detail line when there are more ``kinks`` than
    :data:`~lyapcheck.tolerances.PIECEWISE_MAX_KINKS` (the route is not tried), else None."""
    if kinks <= tolerances.PIECEWISE_MAX_KINKS:
        return None
    return reasons.size_limit(kinks, "kinks at the equilibrium", tolerances.PIECEWISE_MAX_KINKS,
                              "lyapcheck.tolerances.PIECEWISE_MAX_KINKS")

def _rounded(values: Any, bits: int) -> list[Fraction]:
    """Each value rounded to a dyadic rational with ``bits`` significant bits of the largest one."""
    import math

    flat = [float(v) for v in values]
    top = max((abs(v) for v in flat), default=0.0)
    if top == 0 or not math.isfinite(top):
        return [Fraction(0) for _ in flat]
    step = math.floor(math.log2(top)) - bits
    scale = Fraction(2) ** step
    return [Fraction(round(v / float(scale))) * scale for v in flat]


def _solve(pl: PiecewiseLinear, discrete: bool, eps: Fraction, products: Sequence[tuple[int, int]],
           budget: Budget | None = None) -> tuple[Matrix, list[Fraction], list[Fraction], str] | str:
    """The LMI for one eps (Clarabel): rounded ``P``, ``lambda``, ``nu`` and the solver's status, or why none
    (``budget`` checked before the solve)."""
    import cvxpy as cp
    import numpy as np

    from lyapcheck.sos import sdp

    n, N = pl.n, pl.width
    E, C = (np.array([[float(x) for x in row] for row in m]) for m in _stacked(pl, discrete))

    def sym(g: Any, h: Any) -> Any:
        return (np.outer(g, h) + np.outer(h, g)) / 2

    def vector(g: Sequence[Fraction]) -> Any:
        return np.array([float(x) for x in g])

    eqs = [sum(sign * sym(vector(g), vector(h)) for sign, g, h in terms) for terms in equalities(pl)]
    forms = [vector(g) for _, g in nonnegative_forms(pl)]
    P = cp.Variable((n, n), symmetric=True)
    lam = cp.Variable(len(eqs))
    nu = cp.Variable(len(products), nonneg=True)
    Q = C.T @ P @ C - E.T @ P @ E if discrete else E.T @ P @ C + C.T @ P @ E
    M = Q + float(eps) * (E.T @ E)
    if eqs:
        M = M - cp.reshape(np.column_stack([q.ravel(order="F") for q in eqs]) @ lam, (N, N), order="F")
    if products:
        G = np.column_stack([sym(forms[a], forms[b]).ravel(order="F") for a, b in products])
        M = M + cp.reshape(G @ nu, (N, N), order="F")
    M = (M + M.T) / 2
    _tick(budget)
    problem = cp.Problem(cp.Minimize(cp.trace(P)), [P >> np.eye(n), M << -tolerances.PIECEWISE_ROOM * np.eye(N)])
    report = sdp.solve(problem)
    if report.outcome != "optimal" or P.value is None:
        return f"the LMI's solve ended {report.raw_status} (eps = {eps})"
    bits = tolerances.PIECEWISE_BITS
    p = _rounded(P.value.ravel(), bits)
    P_exact = [[(p[i * n + j] + p[j * n + i]) / 2 for j in range(n)] for i in range(n)]
    lam_exact = _rounded(lam.value if len(eqs) else [], bits)
    nu_exact = [max(Fraction(0), c) for c in _rounded(nu.value if products else [], bits)]
    return P_exact, lam_exact, nu_exact, report.raw_status


def prove(pl: PiecewiseLinear, discrete: bool, budget: Budget | None = None
          ) -> tuple[dict[str, Any] | None, list[str]]:
    """A checked certificate (JSON) for ``pl``, or None, and what each eps gave (``budget`` checked
    between the solves and the exact steps: BudgetExhausted once spent)."""
    products = pairs(pl)
    tried: list[str] = []
    for eps in tolerances.PIECEWISE_EPSILONS:
        _tick(budget)
        found = _solve(pl, discrete, eps, products, budget)
        if isinstance(found, str):
            tried.append(found)
            continue
        P, lam, nu, _ = found
        _tick(budget)
        ok, why = check(pl, discrete, P, eps, lam, nu, products, budget)
        if ok:
            return certificate(pl, discrete, P, eps, lam, nu, products), tried
        tried.append(f"eps = {eps}: the rounded solution fails the exact check ({why})")
    return None, tried


def certificate(pl: PiecewiseLinear, discrete: bool, P: Matrix, eps: Fraction, lam: Sequence[Fraction],
                nu: Sequence[Fraction], products: Sequence[tuple[int, int]]) -> dict[str, Any]:
    """The certificate's JSON: the first-order part (for the reader; verify re-derives it), ``P``, eps and
    the multipliers (a ``nu`` of 0 and its product left out)."""
    kept = [(c, ab) for c, ab in zip(nu, products) if c]
    return {"kind": KIND, "method": KIND, "discrete": discrete,
            "A": [[str(x) for x in row] for row in pl.A], "B": [[str(x) for x in row] for row in pl.B],
            "kinks": [{"auxiliary": k.name, "call": k.written, "shape": k.shape, "form": [str(x) for x in k.form]}
                      for k in pl.kinks],
            "P": [[str(x) for x in row] for row in P], "epsilon": str(eps), "lambda": [str(x) for x in lam],
            "nu": [str(c) for c, _ in kept], "products": [list(ab) for _, ab in kept]}


def is_certificate(data: Any) -> bool:
    """A piecewise-linear linearization certificate."""
    return isinstance(data, dict) and data.get("kind") == KIND


def sentence(data: Any) -> str:
    """The claim of a certificate (its ``discrete`` flag alone)."""
    return CERTIFIED_MAP if data.get("discrete") is True else CERTIFIED_FIELD


def _result(pl: PiecewiseLinear, discrete: bool, kinked: str, budget: Budget | None) -> ConditionResult:
    import time

    start = time.perf_counter()
    try:
        cert, tried = prove(pl, discrete, budget if budget is not None else default_budget())
    except BudgetExhausted as exc:
        return ConditionResult("linearization", "inconclusive", f"{kinked}; the piecewise-linear route stopped: {exc}",
                               numbers={"detail": [str(exc)]}, property="LES")
    # (the kinks and products are the certificate's; a figure here is one verify knows: the proof's wall time)
    numbers: dict[str, Any] = {"proof_seconds": round(time.perf_counter() - start, 3)}
    if cert is not None:
        return ConditionResult("linearization", "certified", sentence(cert), numbers=numbers, certificate=cert,
                               property="LES")
    why = (f"{kinked}; no V = e^T P e was found that decreases on every pattern of its {len(pl.kinks)} kink(s) "
           f"(S-procedure: {'; '.join(tried)}). Nothing is refuted: a pattern whose linear loop is unstable may never "
           "be followed near the equilibrium")
    return ConditionResult("linearization", "not_certified", why, numbers=numbers, property="LES")


def linearization(loop: "Loop", budget: Budget | None = None) -> ConditionResult:
    """``linearization`` of a loop with functions: its Jacobian's decision
    (:func:`lyapcheck.models.classes.recast_classes.linearization`), or where a kink leaves it without one,
    this route's (the Jacobian's reason kept when this route does not apply either)."""
    from lyapcheck.models.classes.recast_classes import linearization as by_jacobian

    result = by_jacobian(loop)
    if result.status != "not_applicable":
        return result
    return run(loop, result.summary, budget) or result


def run(loop: "Loop", kinked: str, budget: Budget | None = None) -> ConditionResult | None:
    """``linearization`` of a loop with functions whose Jacobian does not exist (``kinked``, why not), or None
    when this route does not apply either (:func:`derive`'s reason: the caller keeps its own)."""
    return _route(loop, False, kinked, budget)


def _route(loop: "Loop", discrete: bool, kinked: str, budget: Budget | None) -> ConditionResult | None:
    """:func:`run` and :func:`run_map`: the kinks counted first (too many: ``not_certified`` naming the limit,
    before the chain rule's walk and any LMI: a count, the same on any machine), then derived and proved."""
    large = None if loop.fixed else too_large(len(kinks_at_equilibrium(loop)))
    if large is not None:
        return ConditionResult("linearization", "not_certified",
                               f"{kinked}; the piecewise-linear route was not tried: {large}. Nothing is refuted",
                               numbers={"detail": [large]}, property="LES")
    pl = derive(loop)
    return None if isinstance(pl, str) else _result(pl, discrete, kinked, budget)


def map_loop(model: "RecastModel") -> "Loop":
    """The recast displacement of a map, in deviations (as :mod:`~lyapcheck.models.classes.discrete_functions`
    reads it)."""
    from lyapcheck.models.classes.recast_classes import base_loop

    return base_loop(model.system, cylinder=False)


def run_map(model: "RecastModel", kinked: str, budget: Budget | None = None) -> ConditionResult | None:
    """The same for a discrete-time map with functions (the step form)."""
    return _route(map_loop(model), True, kinked, budget)


def verify(loop: "Loop", discrete: bool, status: str, data: Any) -> tuple[bool, str]:
    """Re-derive the first-order part from the model and re-check the certificate exactly."""
    if status != "certified":
        return False, f"a piecewise-linear linearization is never {status}"
    if not is_certificate(data) or data.get("discrete") is not discrete:
        return False, "not a piecewise-linear certificate of this kind of loop"
    pl = derive(loop)
    if isinstance(pl, str):
        return False, f"the model's first-order part is not exact here: {pl}"
    stated = [(k.get("auxiliary"), k.get("shape"), [read_rational(x) for x in k.get("form", [])])
              for k in data.get("kinks", [])]
    if stated != [(k.name, k.shape, list(k.form)) for k in pl.kinks]:
        return False, "the stated kinks are not the model's"
    P = [[read_rational(x) for x in row] for row in data["P"]]
    products = [(int(a), int(b)) for a, b in data["products"]]
    return check(pl, discrete, P, read_rational(data["epsilon"]), [read_rational(x) for x in data["lambda"]],
                 [read_rational(x) for x in data["nu"]], products)


__all__ = ["KIND", "SHAPES", "Kink", "PiecewiseLinear", "derive", "kinks_at_equilibrium", "nonnegative_forms",
           "equalities", "pairs", "too_large", "default_budget", "form_matrix", "check", "prove", "certificate",
           "is_certificate", "sentence", "linearization", "run", "run_map", "map_loop", "verify"]
