"""A quadratic ``V = z^T P z`` shaped for a large region of attraction on the true loop (issue 42), at 4
to 6 states: a PROPOSAL only, in floating point. The proof is
:func:`~lyapcheck.models.classes.recast_ball_level.ball_level` on the rounded ``P`` (exactly positive
definite, its level proved by ball arithmetic); nothing here is a certificate.

The linearization's ``P`` (``J^T P + P J = -I``) decreases only on a thin ellipsoid of a loop whose
slow and fast modes differ (the cart-pole: a level whose ellipsoid reaches 0.14 in ``x`` of a box of
half-width 2). :func:`shaped_quadratic` looks for a ``P`` whose set ``{z^T P z <= 1}`` covers as much
of its *targets* as it can subject to ``V' < 0`` at sampled points of it on the true field. The targets
are the simulated region of attraction within the ``[domain]`` box: the first SHAPE_TARGET_STARTS of the
box's uniform samples that converge on the true loop (the caller's ``converges``, the same simulation as
the certified set's share, :func:`lyapcheck.models.classes.recast_regions.converging`), or, where fewer
than SHAPE_MIN_TARGETS converge or no simulation is given, all the box's samples:

0. candidate starts (:func:`starts`: the linearization's ``P`` and Lyapunov equations of ``J`` shifted
   towards a margin of decay, with ``Q`` the identity or scaled to the box) are scored as the rounds
   are (step 3), and the best one starts;
1. ``P_k`` is scaled so that its sampled critical level (the smallest ``V`` at which a sample has
   ``V' >= 0``, :func:`critical_level`) is 1; points are drawn in ``E = {z^T P_k z <= rho}`` (``rho``
   the round's trust region, half of them near its boundary);
2. a small SDP (cvxpy, Clarabel) in the whitened coordinates ``z = L y`` of ``P_k`` (``L L^T = P_k^-1``;
   ``P_k`` is then the identity: the solver sees a well-scaled problem) asks, LINEARLY in ``P``,
   ``V'(z) = 2 z^T P f(z) <= mu q(z) (kappa (z^T P z - 1) - margin)`` at every point (``q(z) = z^T P_k z``,
   ``mu`` the linearization's slowest decay rate: a fixed multiplier ``kappa`` relaxes the points
   outside the new ellipsoid, and at its boundary ``V' <= -margin mu q``), ``J^T P + P J <= -margin mu
   P_k`` (the exact local level needs the linearization's decrease) and ``{z^T P z <= 1}`` inside ``E``
   (the points cover it); its objective, the sum over SHAPE_BOX_POINTS targets of how far each lies
   outside the new set (``max(z^T P z - 1, 0)``, convex): a stand-in for the share of the targets it
   covers. The set is not kept inside the box: it may reach past it (the planar quadrotor's best sets do;
   an ellipsoid inside a 6-D box covers at most 8 % of it), the share counting only its part in the box,
   and where the field is defined is the proof's to check;
3. the new ``P`` is kept when the share of the targets inside ``{V <= its critical level}`` is larger;
   otherwise the trust region shrinks.

Aiming at the simulated region rather than the box (issue 42's figure is the certified set's share of
the simulated region): at the sampled critical level (decrease SHAPE_SCORE_RATE), the pendubot's design
covers 26.3 % of its simulated region instead of 22.7 %, the acrobot's 32.5 % instead of 21.0 %; the
simulation costs about 1 s at 4 states.

Every random draw has a fixed seed: the same model gives the same ``P``.
"""

from __future__ import annotations

import time
import warnings
from dataclasses import dataclass, field
from fractions import Fraction
from typing import Any, Callable, Final

import numpy as np

from lyapcheck.models.classes.recast_classes import Loop

#: the number of states the shaping is tried at (below 4 the fitted-V route of recast_interval runs)
SHAPE_STATES: Final = range(4, 7)
#: rounds of sample-and-solve at most
SHAPE_ROUNDS: Final = 16
#: the points drawn in each round's trust region (half of them in its outer shell)
SHAPE_POINTS: Final = 3000
SHAPE_SHELL: Final = 0.7
#: the trust region: the new ellipsoid at level 1 lies in the last one's at this level; a round that
#: does not improve shrinks it to its square root, down to SHAPE_TRUST_MIN (2.5 rather than 1.5: the
#: sampled share of the box at the critical level 94 -> 97 % on the cart-pole, 12 -> 14 % on the acrobot,
#: 89 -> 97 % on the planar quadrotor, 22 -> 20.5 % on the pendubot; 4 did no better but on the acrobot)
SHAPE_TRUST: Final = 2.5
SHAPE_TRUST_MIN: Final = 1.02
#: the decrease asked at the boundary, in units of the linearization's slowest rate times q, and the
#: fixed multiplier of (V - 1) that relaxes the points outside the new ellipsoid
SHAPE_MARGIN: Final = 0.02
SHAPE_KAPPA: Final = 1.0
#: the linearization's decrease asked of the new P: J^T P + P J <= -SHAPE_LOCAL_RATE mu P (V decays at
#: least at that share of the best rate any quadratic V has near the equilibrium: the exact local level,
#: whose box of a negative definite Hessian of V' grows with that rate, then covers more of the set)
SHAPE_LOCAL_RATE: Final = 0.3
#: the level a P is scored at: the smallest sampled V with V' >= -SHAPE_SCORE_RATE mu V (a decrease
#: with room: the ball arithmetic proves a level with little room only on very many cells)
SHAPE_SCORE_RATE: Final = 0.1
#: the targets (the first of the share's: the converging box samples, or the box's) whose distance outside
#: {z^T P z <= 1} the rounds minimize (the objective: a convex stand-in for the share of the targets covered)
SHAPE_BOX_POINTS: Final = 2000
#: the critical level's sampling: directions (whitened coordinates) and the ratio of successive levels
CRITICAL_DIRECTIONS: Final = 4000
CRITICAL_RATIO: Final = 1.05
CRITICAL_DECADES: Final = 6.0
#: uniform samples of the [domain] box for the share compared
SHARE_SAMPLES: Final = 50_000
#: the first box samples simulated on the true loop: the converging ones are the design's targets (4,000: the
#: pendubot's 3,249 converging targets in 1.2 s), unless fewer than SHAPE_MIN_TARGETS converge (the box's
#: samples are the targets then)
SHAPE_TARGET_STARTS: Final = 4000
SHAPE_MIN_TARGETS: Final = 100
#: significant digits of P's entries once rounded to rationals
SHAPE_DIGITS: Final = 6
#: the starts scored before the rounds: Lyapunov equations (J + a mu/2 I)^T P + P (J + a mu/2 I) = -Q for
#: these shares ``a`` of the slowest rate (a P whose V decays at least at ``a mu`` near the equilibrium: the
#: linearization's P, a = 0, scores nothing at the SHAPE_SCORE_RATE decrease where a fast mode of J
#: meets a small eigenvalue of P), with Q the identity and Q scaled to the box (diag(1/h_i^2))
SHAPE_START_SHIFTS: Final = (0.0, 0.3, 0.6)


#: what the design's targets are (:attr:`Shaped.aimed_at`)
TARGET_SIMULATED: Final = "the simulated region of attraction"
TARGET_BOX: Final = "the box"


@dataclass
class Shaped:
    """The proposal: ``P`` (floats, scaled so that its sampled critical level is 1), the share of the
    targets inside ``{z^T P z <= 1}``, the linearization's share at its own critical level, the rounds run,
    whether a start or a round improved on the linearization's ``P`` (``P`` is that one otherwise), a line
    per start and per round, the start the rounds began from and its share, and what the targets are."""

    P: np.ndarray
    share: float
    linearization_share: float
    rounds: int
    improved: bool
    notes: list[str] = field(default_factory=list)
    #: the start the rounds began from (:func:`starts`) and its sampled share of the targets
    start: str = "the linearization's P"
    start_share: float = 0.0
    #: the targets (module docstring): TARGET_SIMULATED or TARGET_BOX
    aimed_at: str = TARGET_BOX


class Sampler:
    """The true field in deviations and the fixed samples the rounds share; ``converges`` (deviations, rows ->
    booleans), where given, picks the targets among the box's samples (module docstring)."""

    def __init__(self, loop: Loop, box: tuple[Any, Any],
                 converges: Callable[[np.ndarray], np.ndarray] | None = None) -> None:
        from lyapcheck.models.engines.recast_numeric import FloatLoop

        self.n = loop.n
        self.eq = np.array([float(loop.system.values[s]) for s in loop.system.states])
        self.field = FloatLoop(loop.system)
        lo, hi = (np.asarray(b, dtype=float) for b in box)
        self.lo, self.hi = lo, hi
        self.box_points = lo + (hi - lo) * np.random.default_rng(1).random((SHARE_SAMPLES, self.n))
        self.targets, self.aimed_at = self.box_points, TARGET_BOX
        if converges is not None:
            simulated = self.box_points[:SHAPE_TARGET_STARTS]
            converged = simulated[np.asarray(converges(simulated), dtype=bool)]
            if len(converged) >= SHAPE_MIN_TARGETS:
                self.targets, self.aimed_at = converged, TARGET_SIMULATED
        directions = np.random.default_rng(2).normal(size=(CRITICAL_DIRECTIONS, self.n))
        self.directions = directions / np.linalg.norm(directions, axis=1)[:, None]
        self.rng = np.random.default_rng(0)

    def f(self, Z: np.ndarray) -> np.ndarray:
        with np.errstate(all="ignore"):
            return np.asarray(self.field(Z + self.eq))

    def critical_level(self, P: np.ndarray, rate: float = 0.0) -> float:
        """The smallest sampled ``V = z^T P z`` with ``V' >= -rate V`` (or not finite), along rays of the
        whitened coordinates: levels in ratio 2 from 10^-CRITICAL_DECADES, then in ratio CRITICAL_RATIO
        between the last good one and the first bad; 10^CRITICAL_DECADES when none is bad."""
        L = np.linalg.cholesky(np.linalg.inv(P))
        D = self.directions @ L.T
        DP = D @ P

        def good(level: float) -> bool:
            Z = D * np.sqrt(level)
            with np.errstate(all="ignore"):
                g = 2 * np.sum((DP * np.sqrt(level)) * self.f(Z), axis=1)
            return bool(np.all(g < -rate * level))

        top = 10.0 ** CRITICAL_DECADES
        level = 10.0 ** -CRITICAL_DECADES
        while level < top and good(level):
            level *= 2
        if level >= top:
            return top
        low = level / 2
        while low * CRITICAL_RATIO < level and good(low * CRITICAL_RATIO):
            low *= CRITICAL_RATIO
        return float(min(low * CRITICAL_RATIO, level))

    def share(self, P: np.ndarray, level: float) -> float:
        """The share of the targets inside ``{z^T P z <= level}``."""
        X = self.targets
        return float(np.mean(np.sum((X @ P) * X, axis=1) <= level))

    def points(self, L: np.ndarray, rho: float) -> np.ndarray:
        """SHAPE_POINTS in ``{y^T y <= rho}`` (whitened), half of them in its shell beyond SHAPE_SHELL."""
        U = self.rng.normal(size=(SHAPE_POINTS, self.n))
        U /= np.linalg.norm(U, axis=1)[:, None]
        r = self.rng.random(SHAPE_POINTS) ** (1 / self.n)
        half = SHAPE_POINTS // 2
        r[:half] = SHAPE_SHELL + (1 - SHAPE_SHELL) * self.rng.random(half)
        return (U * (np.sqrt(rho) * r)[:, None]) @ L.T


def _round(sampler: Sampler, Pk: np.ndarray, J: np.ndarray, mu: float, rho: float) -> np.ndarray | None:
    """One round's SDP (module docstring, step 2): the new ``P`` (floats), or None when the solver gives
    no point."""
    import cvxpy as cp

    n = sampler.n
    L = np.linalg.cholesky(np.linalg.inv(Pk))  # z = L y: P_k becomes the identity
    Li = np.linalg.inv(L)
    Z = sampler.points(L, rho)
    F = sampler.f(Z)
    keep = np.all(np.isfinite(F), axis=1)
    Y, G = Z[keep] @ Li.T, F[keep] @ Li.T  # the points and the field in whitened coordinates
    q = np.sum(Y * Y, axis=1)
    # V'(z) - mu kappa q (V - 1) = <A_i, W> + mu kappa q, with W = L^T P L and A_i symmetric
    A = np.einsum("ij,ik->ijk", Y, G)
    A = A + A.transpose(0, 2, 1) - mu * SHAPE_KAPPA * q[:, None, None] * np.einsum("ij,ik->ijk", Y, Y)
    W = cp.Variable((n, n), symmetric=True)
    Jy = Li @ J @ L
    cons = [A.reshape(len(Y), -1) @ cp.vec(W, order="C") <= -mu * (SHAPE_KAPPA + SHAPE_MARGIN) * q,
            W >> np.eye(n) / rho,
            Jy.T @ W + W @ Jy << -SHAPE_LOCAL_RATE * mu * W]
    # the objective: the targets outside {y^T W y <= 1}, each by how far (V - 1, convex in W). The
    # ellipsoid is not kept inside the box (it may reach past it: the share counts only its part in the box,
    # and the points above cover all of it); the volume it replaces grew the ellipsoid where the box is not
    B = sampler.targets[:SHAPE_BOX_POINTS] @ Li.T
    objective = cp.sum(cp.pos(cp.sum(cp.multiply(B @ W, B), axis=1) - 1))
    problem = cp.Problem(cp.Minimize(objective), cons)
    try:
        with warnings.catch_warnings():  # "may be inaccurate": the status is read below, the proof decides
            warnings.simplefilter("ignore", UserWarning)
            problem.solve(solver=cp.CLARABEL)
    except cp.error.SolverError:
        return None
    # (a proposal only: an inaccurate point is tried too, the sampled level and then the proof decide)
    if problem.status not in ("optimal", "optimal_inaccurate") or W.value is None:
        return None
    point = (W.value + W.value.T) / 2
    if np.min(np.linalg.eigvalsh(point)) <= 0:
        return None
    return Li.T @ point @ Li


def starts(J: np.ndarray, mu: float, box: tuple[Any, Any]) -> list[tuple[str, np.ndarray]]:
    """The candidate starts of the rounds (floats, positive definite): the solutions of ``(J + s I)^T P + P
    (J + s I) = -Q`` for ``s = a mu / 2``, ``a`` in SHAPE_START_SHIFTS (``J + s I`` stays Hurwitz: ``a <
    1``), ``Q`` the identity and ``diag(1/h_i^2)`` (``h`` the box's half-widths: the states weighed by the
    box's size, not by their units), with a name each; a start whose solution is not positive definite
    (floating point) is left out."""
    from scipy.linalg import solve_continuous_lyapunov

    n = len(J)
    lo, hi = (np.asarray(b, dtype=float) for b in box)
    half = (hi - lo) / 2
    weights = [("Q = I", np.eye(n))]
    if np.all(half > 0) and np.all(np.isfinite(half)):
        weights.append(("Q = diag(1/h^2) of the box", np.diag(1 / half ** 2)))
    out = []
    for a in SHAPE_START_SHIFTS:
        for label, Q in weights:
            try:
                P = solve_continuous_lyapunov((J + a * mu / 2 * np.eye(n)).T, -Q)
            except (np.linalg.LinAlgError, ValueError):
                continue
            P = (P + P.T) / 2
            if np.all(np.isfinite(P)) and np.min(np.linalg.eigvalsh(P)) > 0:
                out.append((f"Lyapunov, {label}, decay {a:g} mu", P))
    return out


def shaped_quadratic(loop: Loop, J: list[list[Fraction]], box: tuple[Any, Any], deadline: float,
                     converges: Callable[[np.ndarray], np.ndarray] | None = None) -> Shaped | None:
    """The rounds of the module docstring from the best of the starts until SHAPE_ROUNDS, a trust
    region below SHAPE_TRUST_MIN or ``deadline`` (``time.perf_counter()``), aimed at the simulated region of
    attraction where ``converges`` (which starts, deviations in rows, converge on the true loop) gives one;
    None where the linearization gives no positive definite ``P`` or the loop is not of SHAPE_STATES."""
    from lyapcheck.models.classes.linearization import lyapunov_solution

    if loop.n not in SHAPE_STATES:
        return None
    exact = lyapunov_solution(J)
    if exact is None:
        return None
    P0 = np.array([[float(x) for x in row] for row in exact])
    Jf = np.array([[float(x) for x in row] for row in J])
    if np.min(np.linalg.eigvalsh(P0)) <= 0:
        return None
    mu = 2 * float(np.min(-np.linalg.eigvals(Jf).real))
    if mu <= 0:
        return None
    sampler = Sampler(loop, box, converges)
    rate = SHAPE_SCORE_RATE * mu
    c0 = sampler.critical_level(P0, rate)
    best = P0 / c0
    first = best_share = sampler.share(best, 1.0)
    best_volume = -np.linalg.slogdet(best)[1]
    rho, rounds, improved, notes = SHAPE_TRUST, 0, False, []
    start = "the linearization's P"
    for name, S in starts(Jf, mu, box):  # (scored as the rounds are: the best one starts)
        c = sampler.critical_level(S, rate)
        share, volume = sampler.share(S / c, 1.0), -np.linalg.slogdet(S / c)[1]
        notes.append(f"start {name}: share {share:.4g}")
        if share > best_share or (share == best_share and volume > best_volume):
            best, best_share, best_volume, improved, start = S / c, share, volume, True, name
    start_share = best_share
    Pk = best
    while rounds < SHAPE_ROUNDS and rho >= SHAPE_TRUST_MIN and time.perf_counter() < deadline:
        rounds += 1
        P = _round(sampler, Pk, Jf, mu, rho)
        if P is None:
            notes.append(f"round {rounds}: no point from the solver")
            rho = float(np.sqrt(rho))
            continue
        P = (P + P.T) / 2
        try:
            c = sampler.critical_level(P, rate)
        except np.linalg.LinAlgError:  # (a P too ill-conditioned to whiten: the round is not kept)
            notes.append(f"round {rounds}: the solver's P could not be whitened")
            rho = float(np.sqrt(rho))
            continue
        share, volume = sampler.share(P / c, 1.0), -np.linalg.slogdet(P / c)[1]
        notes.append(f"round {rounds}: share {share:.4g} at level {c:.4g} (trust {rho:.3g})")
        if share > best_share or (share == best_share and volume > best_volume):
            best, best_share, best_volume, improved = P / c, share, volume, True
            Pk, rho = best, SHAPE_TRUST
        else:
            rho = float(np.sqrt(rho))
            Pk = best
    return Shaped(P=best, share=best_share, linearization_share=first, rounds=rounds, improved=improved, notes=notes,
                  start=start, start_share=start_share, aimed_at=sampler.aimed_at)


def rational_form(P: np.ndarray) -> list[list[Fraction]] | None:
    """``P`` rounded to SHAPE_DIGITS significant digits, symmetric, as exact rationals; None unless it is
    positive definite exactly (:func:`lyapcheck.sos.definiteness.is_positive_definite`)."""
    from lyapcheck.sos.definiteness import is_positive_definite

    n = len(P)
    R = [[Fraction(0)] * n for _ in range(n)]
    for i in range(n):
        for j in range(i, n):
            R[i][j] = R[j][i] = Fraction(format(float(P[i][j]), f".{SHAPE_DIGITS}g"))
    return R if is_positive_definite(R) else None


__all__ = ["Shaped", "rational_form", "shaped_quadratic"]
