"""``verify`` of a ``counterexample`` (barrier, reach_avoid): its trajectory re-simulated from the document.

A counterexample is numerical evidence, not a proof: ``verify`` re-simulates its trajectory as certify
simulated it (:func:`lyapcheck.models.classes.falsify.replay`) and checks its start, its disturbance, and
its first entry into the unsafe set (before the goal for reach_avoid) at the stated time and point. The
polynomial loops and the loops with functions (their true loop) share these checks, in one step of
:func:`lyapcheck.models.surfaces.verify.verify_model`; the simulation's side of them is kept here, apart from
that flow.
"""

from __future__ import annotations

from typing import Any, Callable, Final

#: verify's (check, ok, message) row
Row = tuple[str, bool, str]
#: ``check(name, condition, model)``: a counterexample re-simulated, (ok, why)
Check = Callable[[str, dict[str, Any], Any], tuple[bool, str]]


def check_counterexamples(model: Any, conditions: dict[str, Any], rows: list[Row],
                          check: Check | None = None) -> None:
    """A ``counterexample`` of barrier or reach_avoid re-simulated from its start and disturbance alone
    (``check``, by default :func:`verify_counterexample` on the model's polynomial field; a loop with
    functions gives its true loop's: :func:`lyapcheck.models.surfaces.verify._true_loop_replay`); a row per
    counterexample, failed when it does not reproduce."""
    check = verify_counterexample if check is None else check
    for name in ("barrier", "reach_avoid"):
        c = conditions.get(name)
        if not isinstance(c, dict) or c.get("status") != "counterexample":
            continue
        try:
            ok, why = check(name, c, model)
        except (KeyError, ValueError, ArithmeticError, TypeError, IndexError, AttributeError) as exc:
            ok, why = False, f"malformed counterexample: {describe_exception(exc)}"
        rows.append((name, ok, why if ok else f"{name}: {why}"))


#: per class with counterexamples: the property it is evidence against, and whether its trajectories
#: stop at the goal (reach_avoid: an entry after the goal is not one)
COUNTEREXAMPLE_OF: Final = {"barrier": ("safety", False), "reach_avoid": ("reach_avoid", True)}


def verify_counterexample(name: str, c: dict[str, Any], model: Any, evaluate: Any = None) -> tuple[bool, str]:
    """A counterexample's trajectory, re-simulated as certify simulated it
    (:func:`lyapcheck.models.classes.falsify.replay`; for reach_avoid stopped at the goal): its start in
    the initial set, its disturbance admissible, and its first entry into the unsafe set (before the
    goal) at the stated time and point (within :data:`~lyapcheck.models.classes.falsify.REPLAY_TOLERANCE`).
    ``evaluate``: the field simulated (``replay``'s; default the polynomial model's, a loop with functions
    gives its true loop's). Evidence, not a proof: it shows that the stated trajectory is what the model's
    simulation gives."""
    import numpy as np

    from lyapcheck.models.classes.falsify import REPLAY_TIME_MARGIN, REPLAY_TOLERANCE, disturbance_of, replay
    from lyapcheck.models.language.sets import margin

    prop, to_goal = COUNTEREXAMPLE_OF[name]
    if c.get("property") != prop:
        return False, f"a {name} counterexample is evidence against {prop}"
    ref = c.get("refutation") or {}
    if ref.get("kind") != "trajectory":
        return False, "a counterexample's refutation must be a trajectory"
    sets = model.sets
    needed = ("initial", "unsafe", "goal") if to_goal else ("initial", "unsafe")
    if not all(sets.get(key) for key in needed):
        return False, f"the model has no [sets] {', '.join(needed)} for {name}"
    start = [float(v) for v in ref["start"]]
    if len(start) != model.n or not all(np.isfinite(start)):
        return False, f"the start must be {model.n} finite numbers (one per state)"
    if not margin(sets["initial"], np.array([start]))[0] >= 0:
        return False, f"the start {start} is not in the initial set"
    disturbance = disturbance_of(ref["disturbance"], model)
    t = float(ref["time"])
    if not (np.isfinite(t) and t >= 0):
        return False, f"the time of entry must be a number of seconds >= 0, not {ref['time']!r}"
    entry = replay(model, start, disturbance, t * (1 + REPLAY_TIME_MARGIN), sets["unsafe"], margin,
                   stop=sets["goal"] if to_goal else None, evaluate=evaluate)
    before = " before it reaches the goal" if to_goal else ""
    if entry is None:
        return False, (f"re-simulated from its start and disturbance, the trajectory does not enter the unsafe set"
                       f"{before} by t = {t:.6g} s")
    point = [float(v) for v in ref["point"]]
    size = 1 + max(abs(v) for v in (*point, *entry.point))
    if len(point) != model.n or abs(entry.time - t) > REPLAY_TOLERANCE * (1 + t) or \
            max(abs(a - b) for a, b in zip(point, entry.point)) > REPLAY_TOLERANCE * size:
        return False, (f"re-simulated from its start and disturbance, the trajectory enters the unsafe set at "
                       f"t = {entry.time:.6g} s at {list(entry.point)}, not at the stated t = {t:.6g} s at {point}")
    return True, (f"the counterexample re-simulated from its start and disturbance enters the unsafe set{before} "
                  f"at t = {entry.time:.6g} s")


def describe_exception(exc: BaseException) -> str:
    """A malformed document's error in a few words (a missing key named as such)."""
    return f"missing key {exc}" if isinstance(exc, KeyError) else str(exc)[:200]


__all__ = ["COUNTEREXAMPLE_OF", "Check", "check_counterexamples", "verify_counterexample", "describe_exception"]
