"""Validated integration of the true loop: a box of initial states carried forward in ball arithmetic.

Every set this module computes encloses, at its time, the states reached from every start of the
given box by the exact flow of the model's own field (:class:`~lyapcheck.models.engines.interval_field.BallLoop`,
functions included), with outward rounding throughout (python-flint's ``arb``). It is the simplest
scheme found to be sound and usable here, a second-order Taylor / mean-value (Lohner) method:

* the set is kept as ``c + Q r``: ``c`` a point, ``Q`` an exact point matrix (orthonormal up to
  rounding; its inverse is enclosed in balls), ``r`` a box. Keeping the box in the frame of the flow's
  own stretching is what stops the wrapping effect from blowing a rotating set up;
* per step of length ``h``, an a priori enclosure ``B`` of every trajectory over ``[t, t + h]`` (Picard:
  ``X + [0, h] f(B)`` inside ``B``, checked), then the mean-value form
  ``x(h) in phi(c) + J (x0 - c)``, where ``J`` encloses every matrix that maps a difference of two
  starts to the difference at time ``h``. ``J`` comes from the variational equation over ``B``:
  ``J in I + h M + (h^2 / 2) M M P`` with ``M`` the field's Jacobian over ``B`` and ``P`` an a priori
  enclosure of the variational matrix (``I + [0, h] M P`` inside ``P``, checked);
* the centre's image ``phi(c) in c + h f(c) + (h^2 / 2) Df(B_c) f(B_c)`` (Taylor with the remainder on
  the centre's own a priori enclosure ``B_c``).

Where a function has a kink inside a ball (``sat``, ``abs``) its derivative there is enclosed by the
interval between its one-sided slopes (Clarke's generalized derivative): the field is Lipschitz, the
difference of two solutions satisfies ``d' = M(t) d`` with ``M(t)`` inside that enclosure, so the mean-value
form holds. Where a function is not Lipschitz on a ball (``sqrt`` reaching 0, a denominator reaching
0) the step is not taken: the box is not proved.
"""

from __future__ import annotations

from contextlib import contextmanager
from dataclasses import dataclass
from fractions import Fraction
from typing import Any, Callable, Iterator, Sequence

import flint

from lyapcheck.models.engines.interval_field import BallLoop, Jet, apply, ball
from lyapcheck.tolerances import FLOW_APRIORI_FLOOR, FLOW_APRIORI_INFLATION, FLOW_APRIORI_ITERATIONS, FLOW_SPLIT_GROWTH

Ball = Any  # flint.arb
Matrix = Any  # flint.arb_mat

APRIORI_ITERATIONS = FLOW_APRIORI_ITERATIONS
APRIORI_INFLATION = FLOW_APRIORI_INFLATION


@contextmanager
def precision(bits: int) -> Iterator[None]:
    """python-flint's working precision set to ``bits`` for the block (restored after)."""
    old = flint.ctx.prec
    flint.ctx.prec = bits
    try:
        yield
    finally:
        flint.ctx.prec = old


def _clarke(function: str, u: Any, limit: Fraction | None) -> Any:
    """``apply``, with the derivative of a kink crossed by the ball enclosed by its one-sided slopes'
    hull (``sat``: [0, 1], ``abs``: [-1, 1]) instead of dropped: enough for a Lipschitz mean-value form."""
    out = apply(function, u, limit)
    if isinstance(u, Jet) and isinstance(out, Jet) and out.grad is None and u.grad is not None \
            and function in ("sat", "abs"):
        slope = flint.arb(0.5, 0.5) if function == "sat" else flint.arb(0, 1)
        return Jet(out.value, [slope * g for g in u.grad])
    return out


class LipschitzLoop(BallLoop):
    """:class:`BallLoop` whose jets keep a first derivative across ``sat``'s and ``abs``'s kinks (their
    generalized derivative, :func:`_clarke`); values are the same."""

    def variables(self, z: Sequence[Any]) -> list[Any]:
        values: list[Any] = [e + zi for e, zi in zip(self.equilibrium, z)] + list(self.fixed)
        zero = flint.arb(0)
        for function, limit, radicand, argument in self.auxiliaries:
            if argument is None:  # a constant root
                values.append(flint.arb(radicand).sqrt())
                continue
            values.append(_clarke(function, argument(values, zero), limit))
        return values


def _hull(a: Ball, b: Ball) -> Ball:
    return a.union(b)


def _field(loop: BallLoop, X: Sequence[Ball]) -> list[Ball] | None:
    """``f`` over the balls ``X`` (None where it is not finite there)."""
    out = [v.value if isinstance(v, Jet) else v for v in loop.field(list(X))]
    return out if all(v.is_finite() for v in out) else None


def jacobian_at(loop: BallLoop, X: Sequence[Ball]) -> Matrix | None:
    """An enclosure of ``Df`` (generalized at kinks) over the balls ``X``; None where a function is not
    Lipschitz there or a value is not finite."""
    n = loop.n
    f = loop.field([Jet.variable(x, i, n, 1) for i, x in enumerate(X)])
    rows = []
    for fi in f:
        if not isinstance(fi, Jet):  # a constant right-hand side
            rows.append([flint.arb(0)] * n)
            continue
        if fi.grad is None:
            return None
        rows.append(list(fi.grad))
    if not all(v.is_finite() for row in rows for v in row):
        return None
    return flint.arb_mat(rows)


def _inside(inner: Sequence[Ball], outer: Sequence[Ball]) -> bool:
    return all(o.contains(i) for i, o in zip(inner, outer))


def _inflated(X: Sequence[Ball], factor: float) -> list[Ball]:
    return [flint.arb(x.mid(), x.rad() * factor + FLOW_APRIORI_FLOOR * (1 + abs(float(x.mid())))) for x in X]


def apriori(loop: BallLoop, X: Sequence[Ball], h: Ball) -> list[Ball] | None:
    """A box holding every trajectory that starts in ``X`` over ``[0, h]``: ``B`` with ``X + [0, h] f(B)``
    inside ``B`` (so, ``f`` being Lipschitz on ``B``, the solutions stay in ``B``), returned as that
    tighter image; None where the Picard check fails :data:`APRIORI_ITERATIONS` times."""
    span = _hull(flint.arb(0), h)
    f = _field(loop, X)
    if f is None:
        return None
    B = _inflated([x + span * fi for x, fi in zip(X, f)], APRIORI_INFLATION)
    for _ in range(APRIORI_ITERATIONS):
        fB = _field(loop, B)
        if fB is None:
            return None
        image = [x + span * fi for x, fi in zip(X, fB)]
        if _inside(image, B):
            return image
        # the next trial is the image itself, widened (a hull with the last trial would keep every overshoot
        # and let one state's width chase another's)
        B = _inflated(image, APRIORI_INFLATION)
    return None


def _variational(M: Matrix, h: Ball) -> Matrix | None:
    """An enclosure of the variational matrix at ``h`` for every ``M(t)`` in ``M``:
    ``I + h M + (h^2 / 2) M M P`` with ``P`` an a priori enclosure (``I + [0, h] M P`` inside ``P``)."""
    n = M.nrows()
    identity = flint.arb_mat([[1 if i == j else 0 for j in range(n)] for i in range(n)])
    span = _hull(flint.arb(0), h)
    P = identity + M * span
    P = flint.arb_mat([[flint.arb(P[i, j].mid(), P[i, j].rad() * APRIORI_INFLATION + FLOW_APRIORI_FLOOR)
                        for j in range(n)]
                       for i in range(n)])
    for _ in range(APRIORI_ITERATIONS):
        image = identity + (M * P) * span
        if all(P[i, j].contains(image[i, j]) for i in range(n) for j in range(n)):
            return identity + M * h + (M * (M * image)) * (h * h / 2)
        P = flint.arb_mat([[flint.arb(image[i, j].mid(), image[i, j].rad() * APRIORI_INFLATION + FLOW_APRIORI_FLOOR)
                            for j in range(n)] for i in range(n)])
    return None


def _column(v: Sequence[Ball]) -> Matrix:
    return flint.arb_mat([[x] for x in v])


def _entries(m: Matrix) -> list[Ball]:
    return [m[i, 0] for i in range(m.nrows())]


@dataclass
class FlowSet:
    """The set ``c + Q r`` reached at step ``steps`` (``c`` exact points, ``Q`` an exact point matrix,
    ``r`` balls)."""

    c: list[Ball]
    Q: Matrix
    r: list[Ball]
    steps: int = 0

    def enclosure(self) -> list[Ball]:
        """The set's enclosure as one ball per state."""
        return [ci + qi for ci, qi in zip(self.c, _entries(self.Q * _column(self.r)))]


def start(lo: Sequence[Fraction], hi: Sequence[Fraction]) -> FlowSet:
    """The box ``[lo, hi]`` (state deviations) as a set at step 0: ``c`` a dyadic point near its centre,
    ``Q = I``, ``r`` the hull of the box's corners minus ``c`` (the box enclosed outwards)."""
    n = len(lo)
    c = [flint.arb(ball((a + b) / 2).mid()) for a, b in zip(lo, hi)]
    r = [ball(a).union(ball(b)) - ci for a, b, ci in zip(lo, hi, c)]
    Q = flint.arb_mat([[1 if i == j else 0 for j in range(n)] for i in range(n)])
    return FlowSet(c, Q, r)


def _orthonormal_frame(A: Matrix, widths: Sequence[float]) -> Matrix:
    """An exact point matrix close to the orthonormal factor of ``mid(A)`` (columns ordered by their
    reach ``|A e_j| r_j``, longest first: Lohner's pivoting, so the frame follows the set's long axis)."""
    import numpy as np

    n = A.nrows()
    mid = np.array([[float(A[i, j].mid()) for j in range(n)] for i in range(n)])
    order = np.argsort(-np.linalg.norm(mid, axis=0) * np.asarray(widths), kind="stable")
    q, _ = np.linalg.qr(mid[:, order])
    if not np.all(np.isfinite(q)):
        q = np.eye(n)
    return flint.arb_mat([[flint.arb(float(q[i, j])) for j in range(n)] for i in range(n)])


def step(loop: BallLoop, s: FlowSet, h: Ball) -> FlowSet | None:
    """``s`` carried over one step ``h`` (None where an enclosure could not be proved)."""
    X = s.enclosure()
    B = apriori(loop, X, h)
    if B is None:
        return None
    M = jacobian_at(loop, B)
    if M is None:
        return None
    J = _variational(M, h)
    if J is None:
        return None
    Bc = apriori(loop, s.c, h)
    if Bc is None:
        return None
    fc, fBc, MBc = _field(loop, s.c), _field(loop, Bc), jacobian_at(loop, Bc)
    if fc is None or fBc is None or MBc is None:
        return None
    second = _entries(MBc * _column(fBc))
    image_c = [ci + h * fi + (h * h / 2) * si for ci, fi, si in zip(s.c, fc, second)]
    JQ = J * s.Q
    frame = _orthonormal_frame(JQ, [float(ri.rad()) for ri in s.r])
    try:
        inverse = frame.inv()
    except ZeroDivisionError:
        return None
    c_new = [flint.arb(x.mid()) for x in image_c]
    err = [x - m for x, m in zip(image_c, c_new)]
    r_new = _entries((inverse * JQ) * _column(s.r) + inverse * _column(err))
    if not all(x.is_finite() for x in r_new):
        return None
    return FlowSet(c_new, frame, r_new, s.steps + 1)


@dataclass(frozen=True)
class FlowOutcome:
    """Where the integration of a box ended: ``steps``, the step by which every piece of it lay in the
    target (each piece is checked after each of its steps and stops there: the target is an invariant
    set), or None with why not (``blew_up``: an enclosure could not be proved or grew past the limit,
    as opposed to the horizon reached); ``taken``: the steps of all its pieces; ``pieces``: how many."""

    steps: int | None
    why: str
    taken: int
    blew_up: bool = False
    pieces: int = 1


def split(s: FlowSet) -> tuple[FlowSet, FlowSet]:
    """``s`` cut in two along its widest coordinate of ``r``: each half re-centred (its reference point
    moved to its middle, exactly a point, the rounding of the move put into its ``r``), their union
    holding ``s``."""
    n = len(s.r)
    k = max(range(n), key=lambda i: float(s.r[i].rad()))
    lo, hi = s.r[k].lower(), s.r[k].upper()
    mid = flint.arb(s.r[k].mid())
    inverse = s.Q.inv()
    halves = []
    for a, b in ((flint.arb(lo), mid), (mid, flint.arb(hi))):
        piece = a.union(b)
        centre = flint.arb(piece.mid())
        moved = [ci + s.Q[i, k] * centre for i, ci in enumerate(s.c)]
        c_new = [flint.arb(x.mid()) for x in moved]
        rounding = _entries(inverse * _column([x - m for x, m in zip(moved, c_new)]))
        r = list(s.r)
        r[k] = piece - centre
        halves.append(FlowSet(c_new, s.Q, [ri + e for ri, e in zip(r, rounding)], s.steps))
    return halves[0], halves[1]


def _size(s: FlowSet) -> float:
    return max(float(x.rad()) for x in s.r)


def flow_into(loop: BallLoop, lo: Sequence[Fraction], hi: Sequence[Fraction], h: Fraction,
              target: Callable[[list[Ball]], bool], max_steps: int, max_radius: float,
              max_pieces: int = 1, split_growth: float = FLOW_SPLIT_GROWTH) -> FlowOutcome:
    """Integrate the box ``[lo, hi]`` (state deviations) with step ``h`` until every piece of it lies in
    ``target`` (an invariant set: a piece is checked after each step and stops once inside), each piece
    for at most ``max_steps`` steps; a piece whose ``r`` has grown ``split_growth`` times since it was
    made (or ``split_growth^3`` times the whole box's) is cut in two (:func:`split`), up to ``max_pieces``
    pieces; the box is given up where an enclosure's radius exceeds ``max_radius``. Deterministic: the
    same arguments give the same outcome (``verify`` runs it again)."""
    hb = ball(h)
    first = start(lo, hi)
    # a piece is cut where its box of coordinates has grown split_growth times since it was made, or past
    # split_growth^3 times the whole box's at the start (without that cap a piece stretched along one coordinate
    # would keep its other coordinate's width as its own and grow without end)
    cap = split_growth ** 3 * _size(first)
    stack = [(first, _size(first))]
    made = 1
    taken = 0
    latest = 0
    while stack:
        s, made_at = stack.pop()
        while not target(s.enclosure()):
            # a split comes before the step limit: halves may be inside where the whole is not
            if _size(s) > min(split_growth * made_at, cap) and made < max_pieces:
                s, other = split(s)
                made += 1
                stack.append((other, _size(other)))
                made_at = _size(s)
                continue
            if s.steps >= max_steps:
                return FlowOutcome(None, f"a piece is not inside the target after {max_steps} steps", taken,
                                   pieces=made)
            nxt = step(loop, s, hb)
            taken += 1
            if nxt is None:
                return FlowOutcome(None, f"no enclosure could be proved at step {s.steps + 1}", taken, blew_up=True,
                                   pieces=made)
            s = nxt
            if max(float(x.rad()) for x in s.enclosure()) > max_radius:
                return FlowOutcome(None, f"the enclosure grew past radius {max_radius:g} at step {s.steps}", taken,
                                   blew_up=True, pieces=made)
        latest = max(latest, s.steps)
    return FlowOutcome(latest, "", taken, pieces=made)


__all__ = ["APRIORI_ITERATIONS", "APRIORI_INFLATION", "FlowOutcome", "FlowSet", "split", "LipschitzLoop", "apriori",
           "flow_into", "jacobian_at",
           "precision", "start", "step"]
