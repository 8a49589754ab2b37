"""A region of attraction enlarged by boxes proved, by validated integration, to flow into the certified set.

Once ``roa`` has certified a set ``S = {V <= level}`` (within its box) on which ``V`` decreases to the
equilibrium, every start whose trajectory is PROVED to lie in ``S`` at some time converges to the
equilibrium too. This route covers the ``[domain]`` with boxes of starts (:func:`extend`): each box is
carried forward by the validated integrator of :mod:`lyapcheck.models.engines.validated_flow` (the
model's own field, functions included, in ball arithmetic) until the enclosure of all its states lies
in ``S`` (``V``'s upper bound on the enclosure at most ``level``, the enclosure inside the set's box);
a box that does not get there within :data:`~lyapcheck.tolerances.FLOW_HORIZON`, or whose enclosure
cannot be proved, is halved along its widest state, down to a minimum width, within a budget of steps
counted, not timed (:data:`~lyapcheck.tolerances.FLOW_STEP_BUDGET`).

The region then proved is the union of ``S`` and of the boxes: every trajectory starting in it converges
to the equilibrium. It is neither a sublevel set nor invariant (a trajectory from a box may leave the
union before it enters ``S``), and the sentence says so. The certificate is the set's, with ``flow``
added (kind :data:`KIND`): the step, the precision, and each box (rational corners, state deviations)
with the time ``t`` at which it is inside ``S``. ``verify`` integrates every stated box again up to its
time and checks it is inside ``S`` then (:func:`check_flow`): nothing of the stated boxes is trusted.
"""

from __future__ import annotations

from fractions import Fraction
from typing import TYPE_CHECKING, Any, Callable, Final, Sequence

import flint

from lyapcheck.exact import read_rational
from lyapcheck.models.classes.claims import FLOW_KIND, FLOW_METHOD, flow_volume
from lyapcheck.models.engines.interval_field import CompiledPoly, ball
from lyapcheck.models.engines.recast_sos import poly_from_json
from lyapcheck.models.engines.validated_flow import LipschitzLoop, flow_into, jacobian_at, precision
from lyapcheck.results import ConditionResult
from lyapcheck.tolerances import (FLOW_ESTIMATE_MARGIN, FLOW_ESTIMATE_SLACK, FLOW_GROWTH, FLOW_HORIZON,
                                  FLOW_INITIAL_CUTS, FLOW_MAX_PIECES, FLOW_MIN_WIDTH_FRACTION, FLOW_PRECISION_BITS,
                                  FLOW_SIMULATION_STRIDE, FLOW_STEP_BUDGET, FLOW_STEP_SCALE)

if TYPE_CHECKING:
    from lyapcheck.models.classes.recast_classes import Loop
    from lyapcheck.models.engines.search import Budget

#: the ``flow`` part of a certificate
KIND: Final = FLOW_KIND
#: how the boxes are proved, in the certificate and the sentence
METHOD: Final = FLOW_METHOD
#: the states the route takes (the integrator itself takes any number; at 3 states, recast-pendulum-actuator, 12,000
#: steps proved 8 boxes that added nothing to the share, and took its roa from 40 s to 56 s; at 4 to 6 states, the
#: issue-42 robots, no box outside the set proved within 60 s: steps of 1/256 to 1/16,384 from their Jacobians'
#: inf-norms, enclosures past the domain's size long before entry; benchmarks/bench_flow_robots.py and its README)
FLOW_STATES: Final = (2,)


def _target(loop: "Loop", cert: dict[str, Any]) -> Callable[[list[Any]], bool]:
    """Whether an enclosure (balls of the state deviations) lies in the certified set: ``V``'s upper
    bound on it at most ``level`` and, where the set is the part of ``{V <= level}`` in a box, the
    enclosure inside that box."""
    system = loop.system
    ring = loop.ring
    V = CompiledPoly(ring, poly_from_json(ring, cert["V"], "V"))
    level = ball(read_rational(cert["level"]))
    shift = [ball(system.values[name]) if name in system.values else None for name in ring.names]
    field = LipschitzLoop(system)
    corners = cert.get("box") if not cert.get("whole") else None
    lo = hi = None
    if corners is not None:
        lo = [ball(read_rational(corners[s][0])) for s in system.states]
        hi = [ball(read_rational(corners[s][1])) for s in system.states]

    def inside(X: list[Any]) -> bool:
        if lo is not None and hi is not None and not all(x >= a and x <= b for x, a, b in zip(X, lo, hi)):
            return False
        values = [v if s is None else v - s for v, s in zip(field.variables(X), shift)]
        return bool(V(values, flint.arb(0)) <= level)

    return inside


def step_of(loop: "Loop") -> Fraction | None:
    """The step: the largest power of 2 at most ``FLOW_STEP_SCALE / |Df(x_eq)|_inf`` (None where the
    Jacobian at the equilibrium is not enclosed)."""
    J = jacobian_at(LipschitzLoop(loop.system), [flint.arb(0)] * len(loop.system.states))
    if J is None:
        return None
    norm = max(sum(float(abs(J[i, j]).upper()) for j in range(J.ncols())) for i in range(J.nrows()))
    h = Fraction(1)
    while h * Fraction(norm) > FLOW_STEP_SCALE:
        h /= 2
    return h


def _halves(lo: tuple[Fraction, ...], hi: tuple[Fraction, ...], widths: Sequence[Fraction]
            ) -> list[tuple[tuple[Fraction, ...], tuple[Fraction, ...]]]:
    """The box halved along the state whose width is the largest share of the domain's."""
    k = max(range(len(lo)), key=lambda i: (hi[i] - lo[i]) / widths[i])
    mid = (lo[k] + hi[k]) / 2
    return [(lo, hi[:k] + (mid,) + hi[k + 1:]), (lo[:k] + (mid,) + lo[k + 1:], hi)]


def _max_radius(lo: Sequence[Fraction], hi: Sequence[Fraction]) -> float:
    """An enclosure wider than the domain's largest half-width proves nothing more: the box is given up."""
    return float(max(b - a for a, b in zip(lo, hi)))


def extend(loop: "Loop", result: ConditionResult, budget: "Budget", box: tuple[Any, Any],
           value: Callable[[Any], Any]) -> None:
    """Add to a certified ``roa`` result the boxes of the domain ``box`` (state deviations, floats)
    proved to flow into its set (its certificate's ``flow``, its figures ``flow_*``); nothing where the
    route does not apply (its reason in ``flow_skipped``). ``value``: the set's ``V`` as a float function
    of the states (rows; +inf outside its box), which only guides where the steps are spent. The set's
    own claim is never changed."""
    cert = result.certificate
    n = len(loop.system.states)
    why = None
    if result.status != "certified" or cert.get("kind") != "interval":
        why = "only a ball-arithmetic set (certificate kind 'interval') is enlarged by validated integration"
    elif n not in FLOW_STATES or n != loop.n:
        why = f"validated integration of boxes is taken for {FLOW_STATES} states"
    elif "disturbances" in cert or "parameter_box" in cert:
        why = "validated integration of boxes is taken for the nominal loop only"
    if why is not None:
        result.numbers["flow_skipped"] = why
        return
    h = step_of(loop)
    if h is None:
        result.numbers["flow_skipped"] = "the field's Jacobian at the equilibrium is not enclosed in balls"
        return
    lo0 = tuple(Fraction(float(x)).limit_denominator(1 << 20) for x in box[0])
    hi0 = tuple(Fraction(float(x)).limit_denominator(1 << 20) for x in box[1])
    widths = [b - a for a, b in zip(lo0, hi0)]
    cuts = FLOW_INITIAL_CUTS[n]
    queue: list[tuple[tuple[Fraction, ...], tuple[Fraction, ...]]] = []
    for index in range(cuts ** n):
        digits = [(index // cuts ** i) % cuts for i in range(n)]
        queue.append((tuple(a + w * d / cuts for a, w, d in zip(lo0, widths, digits)),
                      tuple(a + w * (d + 1) / cuts for a, w, d in zip(lo0, widths, digits))))
    target = _target(loop, cert)
    level = float(read_rational(cert["level"]))
    field = LipschitzLoop(loop.system)
    horizon_steps = int(FLOW_HORIZON / h)
    radius = _max_radius(lo0, hi0) / 2
    proved: list[dict[str, Any]] = []
    steps_used = 0
    stopped = ""
    with precision(FLOW_PRECISION_BITS):
        while queue and not stopped:
            # where the box's corners and centre, simulated in floating point, all enter the set: the
            # validated integration is spent on the boxes that can get there, for about as long as they take
            estimates = _entry_steps(loop, value, level, queue, h, horizon_steps, budget)
            halves: list[tuple[tuple[Fraction, ...], tuple[Fraction, ...]]] = []
            # the boxes expected to enter soonest first: the budget proves the most boxes it can
            order = sorted(range(len(queue)), key=lambda i: (estimates[i] is None, estimates[i] or 0, i))
            queue = [queue[i] for i in order]
            estimates = [estimates[i] for i in order]
            for k, ((lo, hi), estimate) in enumerate(zip(queue, estimates)):
                if steps_used >= FLOW_STEP_BUDGET or budget.left() <= 0:
                    # (the class's time limit: the one stop here that depends on the machine)
                    stopped = (f"the step budget ({FLOW_STEP_BUDGET} steps, lyapcheck.tolerances.FLOW_STEP_BUDGET)"
                               if steps_used >= FLOW_STEP_BUDGET else "the class's time limit")
                    halves.extend(queue[k:])
                    break
                outcome = None
                if estimate is not None:
                    limit = min(horizon_steps, FLOW_STEP_BUDGET - steps_used,
                                int(estimate * FLOW_ESTIMATE_MARGIN) + FLOW_ESTIMATE_SLACK)
                    box_radius = float(max(b - a for a, b in zip(lo, hi))) / 2
                    outcome = flow_into(field, lo, hi, h, target, limit, min(radius, FLOW_GROWTH * box_radius),
                                        max_pieces=FLOW_MAX_PIECES)
                    steps_used += outcome.taken
                    if steps_used > FLOW_STEP_BUDGET:  # (its pieces overran the budget: not kept, so that verify's
                        # work, the proved boxes' steps, stays within it)
                        stopped = f"the step budget ({FLOW_STEP_BUDGET} steps, lyapcheck.tolerances.FLOW_STEP_BUDGET)"
                        halves.extend(queue[k:])
                        break
                if outcome is not None and outcome.steps is not None:
                    if outcome.steps > 0:  # (a box inside the set already adds nothing)
                        proved.append({"box": {s: [str(a), str(b)] for s, a, b in zip(loop.system.states, lo, hi)},
                                       "t": str(outcome.steps * h), "pieces": outcome.pieces})
                elif all((b - a) / 2 >= w * FLOW_MIN_WIDTH_FRACTION for a, b, w in zip(lo, hi, widths)):
                    halves.extend(_halves(lo, hi, widths))
            queue = halves
    result.numbers.update({"flow_boxes": len(proved), "flow_steps": steps_used,
                           "flow_step": str(h), "flow_boxes_left": len(queue)})
    if stopped:
        result.numbers["flow_stopped"] = f"stopped by {stopped} with {len(queue)} boxes not tried"
    if not proved:
        return
    volume = sum(flow_volume(p["box"]) for p in proved)
    result.numbers["flow_boxes_volume"] = float(volume)
    result.numbers["flow_max_time"] = float(max(read_rational(p["t"]) for p in proved))
    cert["flow"] = {"kind": KIND, "method": METHOD, "step": str(h), "precision_bits": FLOW_PRECISION_BITS,
                    "boxes": proved}


SIMULATION_STRIDE: Final = FLOW_SIMULATION_STRIDE
#: how many steps of the guide simulation (:func:`_entry_steps`) run between two readings of the class's clock
GUIDE_CLOCK_STEPS: Final = 64


def _entry_steps(loop: "Loop", value: Callable[[Any], Any], level: float,
                 boxes: Sequence[tuple[tuple[Fraction, ...], tuple[Fraction, ...]]], h: Fraction,
                 horizon_steps: int, budget: "Budget") -> list[int | None]:
    """For each box, the validated step by which its corners and centre, simulated on the true loop in
    floating point (RK4), all lie in the set; None where one does not within the horizon (a guide for
    where to spend the step budget, never part of a proof). The simulation ends early, its boxes not yet
    entered None, when the class's time runs out (``budget``): then the caller stops at once, by its own
    test of the same budget."""
    import numpy as np

    from lyapcheck.models.engines.recast_numeric import FloatLoop, rk4_step

    if not boxes:
        return []
    system = loop.system
    n = len(system.states)
    eq = np.array([float(system.values[s]) for s in system.states])
    corners = np.array([[(i >> j) & 1 for j in range(n)] for i in range(1 << n)] + [[0.5] * n])
    points = np.concatenate([np.array([float(a) for a in lo])
                             + corners * np.array([float(b - a) for a, b in zip(lo, hi)])
                             for lo, hi in boxes]) + eq
    f = FloatLoop(system)
    dt = float(h) * SIMULATION_STRIDE
    entered = np.full(len(points), -1)
    X = points.copy()
    with np.errstate(all="ignore"):
        for k in range(0, horizon_steps // SIMULATION_STRIDE + 1):
            newly = (entered < 0) & (value(X) <= level)
            entered[newly] = k * SIMULATION_STRIDE
            if (entered >= 0).all() or (k % GUIDE_CLOCK_STEPS == 0 and budget.left() <= 0):
                break
            X = rk4_step(f, X, dt)
            X[~np.isfinite(X).all(axis=1)] = np.inf
    per_box = entered.reshape(len(boxes), len(corners))
    return [None if (row < 0).any() else int(row.max()) for row in per_box]


def check_flow(loop: "Loop", cert: dict[str, Any]) -> tuple[bool, str]:
    """``verify`` of a certificate's ``flow``: every stated box integrated again with the stated step and
    precision up to its stated time, and its enclosure then inside the certified set (the set's own
    proof is checked apart). Raises ValueError/KeyError/TypeError on a malformed ``flow``."""
    flow = cert["flow"]
    states = list(loop.system.states)
    if flow.get("kind") != KIND or flow.get("method") != METHOD:
        return False, f"flow: kind '{KIND}' proved by {METHOD}"
    if cert.get("kind") != "interval" or "disturbances" in cert or "parameter_box" in cert:
        return False, "flow: boxes enlarge a nominal ball-arithmetic set only"
    h = read_rational(flow["step"])
    bits = flow["precision_bits"]
    if not (h > 0 and h.numerator == 1 and h.denominator & (h.denominator - 1) == 0):
        return False, "flow: the step must be a power of 2"
    if not isinstance(bits, int) or not 53 <= bits <= 1024:
        return False, "flow: precision_bits must be an integer from 53 to 1024"
    boxes = flow["boxes"]
    if not isinstance(boxes, list) or not boxes:
        return False, "flow: boxes must be a non-empty list"
    target = _target(loop, cert)
    field = LipschitzLoop(loop.system)
    longest = Fraction(0)
    work = 0  # (certify proved every box within FLOW_STEP_BUDGET steps in all: a certificate needing more is refused)
    with precision(bits):
        for k, entry in enumerate(boxes):
            corners = entry["box"]
            if list(corners) != states:
                return False, f"flow box {k}: one interval per state, in the states' order"
            lo = [read_rational(corners[s][0]) for s in states]
            hi = [read_rational(corners[s][1]) for s in states]
            t = read_rational(entry["t"])
            steps = t / h
            if any(a >= b for a, b in zip(lo, hi)) or steps.denominator != 1 or not 1 <= steps <= FLOW_HORIZON / h:
                return False, (f"flow box {k}: each interval must have lo < hi, and t a multiple of the step in "
                               f"(0, {FLOW_HORIZON}]")
            pieces = entry["pieces"]
            if not isinstance(pieces, int) or not 1 <= pieces <= FLOW_MAX_PIECES:
                return False, f"flow box {k}: pieces must be an integer from 1 to {FLOW_MAX_PIECES}"
            if work + steps > FLOW_STEP_BUDGET:  # (before integrating: a forged tiny step must not make verify run on)
                return False, (f"flow: the boxes take more than the {FLOW_STEP_BUDGET} steps certify may spend "
                               "(lyapcheck.tolerances.FLOW_STEP_BUDGET)")
            # the same deterministic integration, with the pieces the box was cut into and no other limit
            outcome = flow_into(field, lo, hi, h, target, int(steps), float("inf"), max_pieces=pieces)
            work += outcome.taken
            if outcome.steps != int(steps):
                return False, (f"flow box {k} is not proved inside the set at its time t = {t}: "
                               f"{outcome.why or 'its enclosure is not inside'}")
            if work > FLOW_STEP_BUDGET:
                return False, (f"flow: the boxes take more than the {FLOW_STEP_BUDGET} steps certify may spend "
                               "(lyapcheck.tolerances.FLOW_STEP_BUDGET)")
            longest = max(longest, t)
    return True, (f"each of the {len(boxes)} boxes integrated again enters the set (by t = {float(longest):.4g}), by "
                  f"{METHOD}")


def in_boxes(cert: dict[str, Any], states: Sequence[str], Z: Any) -> Any:
    """Which rows of ``Z`` (state deviations, floats) lie in a box of the certificate's ``flow``
    (a closed box; floats, for the simulated figures only)."""
    import numpy as np

    out = np.zeros(len(Z), dtype=bool)
    for entry in (cert.get("flow") or {}).get("boxes", []):
        lo = np.array([float(read_rational(entry["box"][s][0])) for s in states])
        hi = np.array([float(read_rational(entry["box"][s][1])) for s in states])
        out |= np.all((Z >= lo) & (Z <= hi), axis=1)
    return out


__all__ = ["KIND", "METHOD", "FLOW_STATES", "extend", "check_flow", "in_boxes", "step_of"]
