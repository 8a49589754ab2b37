"""``lyapcheck tune FILE --box P=a..b ... --objective OBJ``: the gains in a box that give the best
certified figure, the winner's certificate, and a proved neighbourhood around it (issue 45, item 2).

Objectives, each a figure read exactly from a certificate that passed its exact check (never a
solver's float):

==============================  ======  =========================================================
objective                       sense   the figure (class)
==============================  ======  =========================================================
``decay_rate``                  max     the GES rate ``r`` of ``|x - x_eq| <= k |x0 - x_eq| e^(-r t)``
                                        (``quadratic``, property GES: ``mu / 2`` of its ``V' <= -mu V``)
``local_decay_rate``            max     a local rate ``r``: every eigenvalue of the Jacobian at the
                                        equilibrium has real part ``< -r`` (``linearization``: ``J + r I``
                                        Hurwitz, exact; :func:`~lyapcheck.models.classes.linearization.local_rate`),
                                        so solutions near the equilibrium decay like ``e^(-r t)``
``roa``                         max     the radius of a ball ``|x - x_eq| <= r`` proved inside the
                                        certified region (``roa``: the larger of its ball certificate's
                                        ``ball_radius`` and ``size.ball_radius``), in the states' units
``bound:OUTPUT``                min     the certified ``limsup |OUTPUT - OUTPUT_eq|`` (``sos_bound``)
``safety:PARAM=LO..HI``         max     the largest ``PARAM`` in ``LO..HI`` at which ``barrier`` certifies
                                        safety (the bisection of :mod:`~lyapcheck.models.surfaces.extremum`
                                        at each gain point): a disturbance bound, a set's size
``safety:min:PARAM=LO..HI``     min     the smallest such value (a wall's distance, a tube's width)
==============================  ======  =========================================================

A safety margin has a direction only the user knows (a larger disturbance bound is harder, a
narrower tube is harder): the plain form is the largest value, ``min:`` the smallest, and the
objective's sense follows it (the largest tolerated disturbance as large as possible; the narrowest
proved tube as narrow as possible).

The search (a bounded amount of work, every point a whole exact certification):

1. a grid of ``N`` points per boxed parameter (``N**k`` points; ``N = 1``: the box's centre), each
   value rounded to a decimal of :data:`~lyapcheck.models.surfaces.extremum.DIGITS` digits, which is
   exactly the value certified;
2. one local refinement around the best grid point: half a grid step either way along each axis
   (at most ``2 k`` points, those inside the box and not tried yet);
3. the winner (the largest or smallest figure; the first in that order on a tie) is certified again
   with its values as ``--set`` overrides: that certificate is the one written, with the figure in it;
4. its neighbourhood: a box around the winner (half a grid step either way, within the search box),
   certified with the objective's class over the box (its box certificate covers every gain in it)
   and accepted when its figure is within :data:`FACTOR` of the winner's (at least half of it for
   a maximized figure, at most twice it for a minimized one; for ``safety``: the box certified safe
   with ``PARAM`` at that value); else the box is halved, :data:`NEIGHBOURHOOD_TRIES` boxes in all.
   Nothing proved: "no certified neighbourhood", with the reason.

Every figure is a lower (maximized) or upper (minimized) bound proved at its own point; the points
between the grid's are not claimed, except inside a certified neighbourhood.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from fractions import Fraction
from typing import Any, Callable, Final, Mapping, Sequence

from lyapcheck.errors import InvalidParameter, ModelFileError
from lyapcheck.models.surfaces.extremum import DIGITS, decimal, parse_range

#: grid points per axis when ``--grid`` is not given
DEFAULT_GRID: Final = 3
#: the most points per axis accepted
MAX_GRID: Final = 9
#: the most grid points in all (``N ** k``): each is a whole certification
MAX_GRID_POINTS: Final = 81
#: the neighbourhood's figure is within this factor of the winner's: at least ``FACTOR x`` the
#: winner's for a maximized figure, at most ``x / FACTOR`` for a minimized one
FACTOR: Final = Fraction(1, 2)
#: boxes tried for the neighbourhood (the first, then each halved)
NEIGHBOURHOOD_TRIES: Final = 3
#: bisection steps of a ``safety:`` margin at each gain point (after the range's two ends)
SAFETY_STEPS: Final = 4
#: the objectives' names and their classes
OBJECTIVE_CLASS: Final = {"decay_rate": "quadratic", "local_decay_rate": "linearization", "roa": "roa",
                           "bound": "sos_bound", "safety": "barrier"}
#: what ``--objective`` accepts (every refusal says it)
ACCEPTED: Final = ("decay_rate, local_decay_rate, roa, bound:OUTPUT (a model with [disturbances]), safety:PARAM=LO..HI or "
                   "safety:min:PARAM=LO..HI (a model with [sets] initial and unsafe)")


@dataclass(frozen=True)
class Objective:
    """A parsed ``--objective``: its kind, its target (an output or a parameter), the sense of the search."""

    text: str
    kind: str  # decay_rate | local_decay_rate | roa | bound | safety
    target: str = ""
    low: Fraction = Fraction(0)
    high: Fraction = Fraction(0)
    sense: str = "max"

    @property
    def cls(self) -> str:
        return OBJECTIVE_CLASS[self.kind]

    def words(self) -> str:
        """What the figure is, in one phrase."""
        if self.kind == "decay_rate":
            return "the GES decay rate r of |x - x_eq| (quadratic), 1/s"
        if self.kind == "local_decay_rate":
            return "a local decay rate r: every eigenvalue of the Jacobian has real part < -r (linearization), 1/s"
        if self.kind == "roa":
            return "the radius of the largest ball around the equilibrium proved inside the certified region (roa)"
        if self.kind == "bound":
            return f"the certified limsup |{self.target} - {self.target}_eq| (sos_bound)"
        word = "largest" if self.sense == "max" else "smallest"
        return f"the {word} {self.target} in {decimal(self.low)}..{decimal(self.high)} at which barrier certifies safety"


def parse_objective(text: str, model: Any) -> Objective:
    """``--objective`` against the model (a :class:`Model` or a loop with functions); a one-line error
    naming ``--objective``, what is accepted and what was given."""
    source = str(getattr(model, "source", "<model>"))

    def refuse(why: str) -> ModelFileError:
        return ModelFileError(source, "--objective", f"must be one of {ACCEPTED}{why}; got {text!r}")

    word, _, rest = str(text).strip().partition(":")
    if word in ("decay_rate", "local_decay_rate", "roa") and not rest:
        return Objective(text, word)
    if word == "bound":
        if not model.disturbances:
            raise refuse(" (bound: needs a model with [disturbances]; this one has none)")
        if rest not in model.outputs:
            raise refuse(f" (bound: names an output among {', '.join(model.outputs)})")
        return Objective(text, "bound", rest, sense="min")
    if word == "safety":
        sets = getattr(model, "sets", {}) or {}
        if not ("initial" in sets and "unsafe" in sets):
            raise refuse(" (safety: needs a model with [sets] initial and unsafe)")
        sense = "max"
        if rest.startswith("min:") or rest.startswith("max:"):
            sense, rest = rest[:3], rest[4:]
        try:
            name, low, high = parse_range(rest, "objective")
        except InvalidParameter:
            raise refuse(" (safety: PARAM=LO..HI with LO < HI, decimal numbers in the file's units)") from None
        if name not in model.parameters and name not in model.disturbances:
            names = ", ".join([*model.parameters, *model.disturbances]) or "none"
            raise refuse(f" (safety: names a parameter or disturbance bound among {names})")
        return Objective(text, "safety", name, low, high, sense)
    raise refuse("")


def check_grid(value: Any) -> int:
    """``--grid N``: an integer in 1..MAX_GRID (one-line error naming ``grid``)."""
    try:
        n = int(value)
        if str(n) != str(value).strip():
            raise ValueError
    except (TypeError, ValueError):
        raise InvalidParameter("grid", f"an integer in 1..{MAX_GRID}", value) from None
    if not 1 <= n <= MAX_GRID:
        raise InvalidParameter("grid", f"an integer in 1..{MAX_GRID}", value)
    return n


def parse_boxes(texts: Sequence[str], model: Any, objective: Objective, settings: Sequence[str],
                grid: int) -> list[tuple[str, Fraction, Fraction]]:
    """The ``--box`` ranges: each ``NAME=LO..HI`` of a parameter of the model, once, not also set by
    ``--set`` nor the ``safety:`` parameter; at most :data:`MAX_GRID_POINTS` grid points in all."""
    source = str(getattr(model, "source", "<model>"))
    if not texts:
        raise InvalidParameter("box", "at least one NAME=LO..HI of a model parameter (the gains to tune)", None)
    boxes: list[tuple[str, Fraction, Fraction]] = []
    given = {str(s).partition("=")[0].strip() for s in settings}
    for text in texts:
        name, low, high = parse_range(text, "box")
        if name not in model.parameters:
            names = ", ".join(model.parameters) or "none"
            raise ModelFileError(source, f"box['{name}']", f"must name a parameter of the model (its [parameters]: "
                                                          f"{names}); got {text!r}")
        if any(name == b[0] for b in boxes):
            raise ModelFileError(source, f"box['{name}']", f"must be given once; got it twice ({text!r})")
        if name in given:
            raise ModelFileError(source, f"box['{name}']", "must not also be given by --set (the search sets it)")
        if objective.kind == "safety" and name == objective.target:
            raise ModelFileError(source, f"box['{name}']", "must not be the safety margin's parameter "
                                                          f"({objective.target}: --objective searches it)")
        boxes.append((name, low, high))
    if grid ** len(boxes) > MAX_GRID_POINTS:
        raise InvalidParameter("grid", f"at most {MAX_GRID_POINTS} grid points in all (N ** boxes: {grid} ** "
                                       f"{len(boxes)} = {grid ** len(boxes)})", grid)
    return boxes


def rounded(x: Fraction) -> Fraction:
    """``x`` as a decimal of :data:`DIGITS` significant digits (the value given to ``--set``, exactly)."""
    return Fraction(f"{float(x):.{DIGITS}g}")


def axis_values(low: Fraction, high: Fraction, n: int) -> list[Fraction]:
    """``n`` evenly spaced values from ``low`` to ``high`` (their midpoint when ``n = 1``)."""
    if n == 1:
        return [rounded((low + high) / 2)]
    return [low if i == 0 else high if i == n - 1 else rounded(low + (high - low) * i / (n - 1)) for i in range(n)]


def step(low: Fraction, high: Fraction, n: int) -> Fraction:
    """The grid's spacing along one axis (half the range for a one-point grid)."""
    return (high - low) / (n - 1) if n > 1 else (high - low) / 2


# -- the exact figure of a certificate document --------------------------------------------------------
def figure(objective: Objective, doc: Mapping[str, Any], need: Fraction | None = None) -> tuple[Fraction | None, str]:
    """The objective's figure proved by ``doc`` (a point's or a box's certificate document), exactly,
    from its certificate; ``(None, why)`` when the objective's class did not certify it. ``need``: the
    figure a box must reach (``local_decay_rate`` over a box proves a given rate, not the largest one:
    the figure is then ``need`` when proved)."""
    c = (doc.get("conditions") or {}).get(objective.cls)
    if not isinstance(c, dict):
        return None, f"{objective.cls} not run"
    if c.get("status") != "certified":
        return None, str(c.get("status"))
    cert = c.get("certificate") or {}
    if objective.kind == "decay_rate":
        if c.get("property") != "GES":
            return None, "GAS only (no exponential rate)"
        if cert.get("kind") == "lyapunov":
            from lyapcheck.models.loop.field import Scaling

            return Fraction(cert["mu_scaled"]) / Scaling.from_json(doc["field"]["scaling"]).time / 2, "certified"
        from lyapcheck.models.classes.lyapunov import RELATIONS_KIND, relations_claim

        if cert.get("kind") == RELATIONS_KIND:
            prop, figures = relations_claim(cert)
            if prop == "GES":
                return Fraction(figures["decay_rate_per_s"]), "certified"
        return None, "no GES rate in its certificate"
    if objective.kind == "local_decay_rate":
        # a point's exact Jacobian (a continuous loop's certificate, not a box's polynomial one nor a map's)
        point = cert.get("method") in ("lyapunov_equation", "routh_hurwitz") and cert.get("time") is None
        jacobian = cert.get("jacobian") if point else None
        if not point and isinstance(doc.get("box"), dict) and need is not None and need > 0:
            from lyapcheck.models.classes.linearization import rate_over_box

            # every eigenvalue of J(u) + need I in the left half-plane, for every value of the box
            return (need, "certified") if rate_over_box(cert, list(doc["box"]), need) else \
                (None, f"the rate {float(need):.6g} is not proved for every value of the box")
        if not isinstance(jacobian, list):
            return None, "no Jacobian at a point in its certificate (a box's linearization proves a rate only "\
                         "when one is asked)"
        from lyapcheck.models.classes.linearization import local_rate

        rate = local_rate([[Fraction(x) for x in row] for row in jacobian])
        return (rate, "certified") if rate is not None and rate > 0 else (None, "no positive rate")
    if objective.kind == "roa":
        radii = [Fraction(cert["ball"]["radius"])] if isinstance(cert.get("ball"), dict) else []
        size = cert.get("size")
        if isinstance(size, dict) and size.get("ball_radius") is not None:
            radii.append(Fraction(size["ball_radius"]))
        if not radii:
            return None, "no ball proved inside the region"
        return max(radii), "certified"
    if objective.kind == "bound":
        out = (cert.get("outputs") or {}).get(objective.target)
        if not isinstance(out, dict):
            return None, f"no bound of {objective.target}"
        return Fraction(out["bound"]), "certified"
    # safety: the parameter's value in the document, where barrier certified safety
    value = (doc.get("overrides") or {}).get(objective.target)
    if value is None:
        return None, f"{objective.target} not set"
    return Fraction(str(value)), "certified"


def better(a: Fraction, b: Fraction | None, sense: str) -> bool:
    """``a`` strictly better than ``b`` (None: nothing yet)."""
    return b is None or (a > b if sense == "max" else a < b)


# -- the search ---------------------------------------------------------------------------------------
@dataclass
class Point:
    """One gain point tried: its values, the phase (grid or refine), the figure proved (None: the
    outcome says why), and the seconds it took."""

    values: dict[str, Fraction]
    phase: str
    value: Fraction | None
    outcome: str
    seconds: float
    detail: dict[str, Any] = field(default_factory=dict)

    def settings(self) -> list[str]:
        return [f"{k}={decimal(v)}" for k, v in self.values.items()]

    def to_json(self, sense: str) -> dict[str, Any]:
        out: dict[str, Any] = {"point": {k: decimal(v) for k, v in self.values.items()}, "phase": self.phase,
                               "value": None if self.value is None else weaker_float(self.value, sense),
                               "value_exact": None if self.value is None else str(self.value),
                               "outcome": self.outcome, "seconds": round(self.seconds, 2)}
        out.update(self.detail)
        return out


def weaker_float(x: Fraction, sense: str) -> float:
    """``x`` as a float on the side of the weaker claim (not above a maximized figure, not below a
    minimized one), so that a printed or stored float never claims more than the exact value."""
    from lyapcheck.exact import float_above, float_below

    if sense == "max":
        return float_below(x)
    if sense == "min":
        return float_above(x)
    return float(x)


Evaluate = Callable[[dict[str, Fraction]], tuple[Fraction | None, str, dict[str, Any]]]


def search(boxes: Sequence[tuple[str, Fraction, Fraction]], grid: int, sense: str, evaluate: Evaluate,
           clock: Callable[[], float] | None = None) -> list[Point]:
    """The grid, then one refinement around its best point (module docstring); ``evaluate(values)``
    certifies at one point and returns (the figure or None, the outcome, extra JSON for the record)."""
    import itertools

    tick = clock or time.perf_counter
    tried: list[Point] = []

    def attempt(values: dict[str, Fraction], phase: str) -> None:
        start = tick()
        value, outcome, detail = evaluate(values)
        tried.append(Point(values, phase, value, outcome, tick() - start, detail))

    axes = [axis_values(lo, hi, grid) for _, lo, hi in boxes]
    for combo in itertools.product(*axes):
        attempt({name: v for (name, _, _), v in zip(boxes, combo)}, "grid")
    best = best_point(tried, sense)
    if best is None:
        return tried
    seen = {tuple(p.values.values()) for p in tried}
    for i, (name, lo, hi) in enumerate(boxes):
        half = step(lo, hi, grid) / 2
        for sign in (-1, 1):
            moved = rounded(best.values[name] + sign * half)
            if not lo <= moved <= hi:
                continue
            values = {**best.values, name: moved}
            if tuple(values.values()) in seen:
                continue
            seen.add(tuple(values.values()))
            attempt(values, "refine")
    return tried


def best_point(tried: Sequence[Point], sense: str) -> Point | None:
    """The point with the best figure (the first on a tie), or None when none was proved."""
    best: Point | None = None
    for p in tried:
        if p.value is not None and better(p.value, None if best is None else best.value, sense):
            best = p
    return best


# -- the neighbourhood --------------------------------------------------------------------------------
def threshold(value: Fraction, sense: str) -> Fraction:
    """The figure the neighbourhood must prove: ``FACTOR x value`` (max) or ``value / FACTOR`` (min),
    as a decimal of :data:`DIGITS` digits rounded towards the stronger claim (up for max, down for min:
    a safety margin's threshold is given to ``--set``, and proving it keeps the factor true)."""
    from lyapcheck.models.classes.claims import rounded as rounded_text

    exact = value * FACTOR if sense == "max" else value / FACTOR
    return exact if exact == 0 else Fraction(rounded_text(exact, DIGITS, "up" if sense == "max" else "down"))


def neighbourhood_boxes(boxes: Sequence[tuple[str, Fraction, Fraction]], winner: Mapping[str, Fraction], grid: int
                        ) -> list[dict[str, tuple[Fraction, Fraction]]]:
    """The boxes tried around the winner: half a grid step either way (as far as the refinement
    went; within the search box), then halved, :data:`NEIGHBOURHOOD_TRIES` in all (a box that clipping
    makes the same as the one before is tried once); corners are decimals of :data:`DIGITS` digits."""
    out = []
    for t in range(NEIGHBOURHOOD_TRIES):
        box = {}
        for name, lo, hi in boxes:
            half = step(lo, hi, grid) / 2 ** (t + 1)
            w = winner[name]
            box[name] = (max(lo, rounded(w - half)), min(hi, rounded(w + half)))
        if all(a < b for a, b in box.values()) and box not in out:  # (a clipped box may repeat)
            out.append(box)
    return out


def box_text(box: Mapping[str, tuple[Fraction, Fraction]]) -> list[str]:
    return [f"{k}={decimal(a)}..{decimal(b)}" for k, (a, b) in box.items()]


CertifyBox = Callable[[list[str], Fraction], tuple[Fraction | None, str, dict[str, Any] | None]]


def neighbourhood(objective: Objective, boxes: Sequence[tuple[str, Fraction, Fraction]],
                  winner: Mapping[str, Fraction], value: Fraction, grid: int, certify_box: CertifyBox,
                  over_box: bool) -> dict[str, Any]:
    """The certified neighbourhood (``certify_box(box_texts, threshold)`` certifies the objective's
    class over a box: its figure, its outcome, its document) or why there is none."""
    need = threshold(value, objective.sense)
    head: dict[str, Any] = {"certified": False, "factor": str(FACTOR), "threshold": weaker_float(need, objective.sense),
                            "threshold_exact": str(need), "tries": []}
    if not over_box:
        return {**head, "reason": f"{objective.cls} has no box certificates"}
    if value <= 0:
        return {**head, "reason": f"the winner's figure {float(value):.6g} is not positive: a factor of it says nothing"}
    for box in neighbourhood_boxes(boxes, winner, grid):
        texts = box_text(box)
        got, outcome, doc = certify_box(texts, need)
        ok = got is not None and (got >= need if objective.sense == "max" else got <= need)
        head["tries"].append({"box": texts, "outcome": outcome,
                              "value": None if got is None else weaker_float(got, objective.sense)})
        if ok and doc is not None:
            return {**head, "certified": True, "box": {k: [decimal(a), decimal(b)] for k, (a, b) in box.items()},
                    "value": weaker_float(got, objective.sense) if got is not None else None,
                    "value_exact": str(got), "certificate": doc}
    last = head["tries"][-1]["outcome"] if head["tries"] else "no box around the winner fits in the search box"
    return {**head, "reason": f"no box around the winner proved it after {len(head['tries'])} tries (last: {last})"}


def neighbourhood_sentence(objective: Objective, nb: Mapping[str, Any]) -> str:
    if not nb.get("certified"):
        return f"no certified neighbourhood: {nb.get('reason')}"
    box = " x ".join(f"{k} in [{a}, {b}]" for k, (a, b) in nb["box"].items())
    if objective.kind == "safety":
        return (f"certified neighbourhood: for every {box}, barrier certifies safety with {objective.target} = "
                f"{nb['threshold']:.6g} ({'half' if objective.sense == 'max' else 'twice'} the winner's)")
    rel, share = (">=", "at least half") if objective.sense == "max" else ("<=", "at most twice")
    return (f"certified neighbourhood: for every {box}, the figure is {rel} {nb['value']:.6g} "
            f"({share} the winner's: {rel} {nb['threshold']:.6g}; one box certificate)")


# -- the result ---------------------------------------------------------------------------------------
@dataclass
class Tuning:
    """What ``tune`` found: the points tried, the winner (None: no point was proved), its re-certified
    result (the API's CertifyResult) and value, and the neighbourhood."""

    objective: Objective
    boxes: list[tuple[str, Fraction, Fraction]]
    grid: int
    tried: list[Point]
    winner: Point | None = None
    value: Fraction | None = None
    result: Any = None
    neighbourhood: dict[str, Any] | None = None
    settings: list[str] = field(default_factory=list)
    why: str = ""

    def to_json(self) -> dict[str, Any]:
        sense = self.objective.sense
        return {"objective": self.objective.text, "figure": self.objective.words(), "sense": sense,
                "class": self.objective.cls,
                "box": {n: [decimal(lo), decimal(hi)] for n, lo, hi in self.boxes}, "grid": self.grid,
                "points": len(self.tried), "certified_points": sum(p.value is not None for p in self.tried),
                "value": None if self.value is None else weaker_float(self.value, sense),
                "value_exact": None if self.value is None else str(self.value),
                "point": None if self.winner is None else {k: decimal(v) for k, v in self.winner.values.items()},
                "settings": list(self.settings),
                "tried": [p.to_json(sense) for p in self.tried],
                "neighbourhood": self.neighbourhood, **({"why": self.why} if self.why else {})}

    def document(self) -> dict[str, Any] | None:
        """The winner's certificate document with the ``tune`` table (None without a winner)."""
        if self.result is None:
            return None
        return {**self.result.to_json(), "tune": self.to_json()}

    def sentence(self) -> str:
        if self.winner is None or self.value is None:
            return f"no winner: {self.why or 'no point was certified'} ({self.objective.words()})"
        return winner_sentence(self.objective, self.winner.values, self.value)

    @classmethod
    def from_json(cls, t: Mapping[str, Any]) -> "Tuning":
        """The search as a ``tune`` table states it (:meth:`to_json`), for a report or a check: the
        points in the order tried, the winner the first point tried at the stated ``point`` (None if
        none is), ``value`` the stated exact figure; ``result`` is None. KeyError, TypeError or
        ValueError on a malformed table."""
        if not isinstance(t, Mapping):
            raise TypeError(f"the table is {type(t).__name__}, not a table")
        objective = _objective_of(t)
        boxes = [(str(n), Fraction(str(lo)), Fraction(str(hi))) for n, (lo, hi) in dict(t["box"]).items()]
        tried = []
        for p in t["tried"]:
            if not isinstance(p, Mapping):
                raise TypeError(f"a point tried is {type(p).__name__}, not a table")
            detail = {k: v for k, v in p.items() if k not in ("point", "phase", "value", "value_exact", "outcome",
                                                               "seconds")}
            exact = p.get("value_exact")
            tried.append(Point({str(k): Fraction(str(v)) for k, v in dict(p["point"]).items()}, str(p["phase"]),
                               None if exact is None else Fraction(str(exact)), str(p.get("outcome", "")),
                               float(p.get("seconds") or 0.0), detail))
        point = t.get("point")
        stated = None if point is None else {str(k): Fraction(str(v)) for k, v in dict(point).items()}
        winner = next((p for p in tried if p.values == stated), None)
        exact = t.get("value_exact")
        return cls(objective, boxes, int(t["grid"]), tried, winner, None if exact is None else Fraction(str(exact)),
                   None, t.get("neighbourhood"), [str(x) for x in t.get("settings") or []], str(t.get("why", "")))


def winner_sentence(objective: Objective, point: Mapping[str, Fraction], value: Fraction) -> str:
    """What ``tune`` says of its winner: the point, the objective's figure there (a float on the weaker
    side), certified again."""
    at = ", ".join(f"{k} = {decimal(v)}" for k, v in point.items())
    extra = f" ({objective.target} = {decimal(value)})" if objective.kind == "safety" else ""
    return (f"winner: {at}: {objective.words()} = {weaker_float(value, objective.sense):.6g}"
            f"{extra}, certified again exactly")


def record_row(found: Tuning) -> tuple[str, bool, str]:
    """Whether a stated search is a record ``tune`` could have made: every point in the box, the grid's
    points before the refinement's, the counts as stated, and the winner a point tried whose recorded
    figure no other point tried beats (the figures themselves were proved when tried, not re-checked)."""
    problems = []
    box = {n: (lo, hi) for n, lo, hi in found.boxes}
    if any(set(p.values) != set(box) or any(not box[k][0] <= v <= box[k][1] for k, v in p.values.items())
           for p in found.tried):
        problems.append("a point tried is not in the box")
    phases = [p.phase for p in found.tried]
    if any(ph not in ("grid", "refine") for ph in phases) or phases != sorted(phases, key=lambda ph: ph != "grid"):
        problems.append("the phases are not the grid's points, then the refinement's")
    winner = found.winner
    if winner is None or winner.value is None:
        problems.append("the winner is not a point tried with a proved figure")
    elif any(p.value is not None and better(p.value, winner.value, found.objective.sense) for p in found.tried):
        problems.append("a point tried has a better recorded figure than the winner's")
    if problems:
        return "tune", False, "the search's record is inconsistent: " + "; ".join(problems)
    return "tune", True, (f"the search's record is consistent: {len(found.tried)} points in the box, the winner the "
                          "best recorded figure")


# -- verify's check of a ``tune`` table ---------------------------------------------------------------
def check_tune(doc: Mapping[str, Any]) -> list[tuple[str, bool, str]]:
    """The rows ``verify`` adds for a document with a ``tune`` table: the stated value is the figure
    the document's certificate proves (exactly), the point is the document's overrides, and a
    certified neighbourhood's box certificate passes its own exact check with a figure within the
    stated factor. (The other points tried are a record of the search, not re-checked: only that the
    record is consistent, :func:`record_row`.)"""
    from lyapcheck.models.surfaces.certificate import verify_document

    rows: list[tuple[str, bool, str]] = []
    try:
        t = doc["tune"]
        objective = _objective_of(t)
        value, why = figure(objective, doc)
        stated = Fraction(t["value_exact"])
        ok = value is not None and value == stated and _weaker(t.get("value"), stated, objective.sense)
        rows.append(("tune", ok, f"the value {t.get('value')} is the figure the certificate proves" if ok else
                     f"the stated value is not the certificate's figure ({why})"))
        overrides = doc.get("overrides") or {}
        same = all(Fraction(str(overrides.get(k))) == Fraction(v) for k, v in (t.get("point") or {}).items()
                   if overrides.get(k) is not None) and all(k in overrides for k in (t.get("point") or {}))
        rows.append(("tune", same, "the point is the certificate's overrides" if same else
                     "the stated point is not the certificate's overrides"))
        nb = t.get("neighbourhood") or {}
        if nb.get("certified"):
            rows.extend(_check_neighbourhood(objective, nb, stated, verify_document))
        found = Tuning.from_json(t)
        counted = t.get("points") == len(found.tried) and \
            t.get("certified_points") == sum(p.value is not None for p in found.tried)
        rows.append(record_row(found) if counted else ("tune", False, "the search's record is inconsistent: the "
                                                                      "counts of points are not the table's"))
    except (KeyError, TypeError, ValueError, ZeroDivisionError, AttributeError) as exc:  # (a table where a mapping was)
        rows.append(("tune", False, f"the table is malformed ({type(exc).__name__}: {exc})"))
    return rows


def _weaker(stated: Any, exact: Fraction, sense: str) -> bool:
    return stated is not None and (Fraction(float(stated)) <= exact if sense == "max" else
                                   Fraction(float(stated)) >= exact)


def _objective_of(t: Mapping[str, Any]) -> Objective:
    """The objective a ``tune`` table states (its text parsed without a model: the model's checks
    were made when it was written; the figure is what is re-checked here)."""
    text = str(t["objective"])
    word, _, rest = text.partition(":")
    if word in ("decay_rate", "local_decay_rate", "roa"):
        return Objective(text, word)
    if word == "bound":
        return Objective(text, "bound", rest, sense="min")
    if word == "safety":
        sense = "max"
        if rest.startswith("min:") or rest.startswith("max:"):
            sense, rest = rest[:3], rest[4:]
        name, low, high = parse_range(rest, "objective")
        return Objective(text, "safety", name, low, high, sense)
    raise ValueError(f"unknown objective {text!r}")


def _check_neighbourhood(objective: Objective, nb: Mapping[str, Any], value: Fraction,
                         verify_document: Callable[[dict[str, Any]], list[tuple[str, bool, str]]]
                         ) -> list[tuple[str, bool, str]]:
    sub = dict(nb["certificate"])
    sub_rows = verify_document(sub)
    bad = [m for _, ok, m in sub_rows if not ok]
    if bad:
        return [("tune", False, f"the neighbourhood's certificate fails: {bad[0]}")]
    need = threshold(value, objective.sense)
    if Fraction(nb["threshold_exact"]) != need:
        return [("tune", False, "the neighbourhood's threshold is not the stated factor of the value")]
    box = {k: [Fraction(str(a)), Fraction(str(b))] for k, (a, b) in (sub.get("box") or {}).items()}
    stated = {k: [Fraction(a), Fraction(b)] for k, (a, b) in nb["box"].items()}
    if box != stated:
        return [("tune", False, "the neighbourhood's box is not its certificate's")]
    got, why = figure(objective, sub, need)
    ok = got is not None and (got >= need if objective.sense == "max" else got <= need)
    return [("tune", ok, "the neighbourhood's box certificate checks and proves the stated factor" if ok else
             f"the neighbourhood's certificate does not prove the stated factor ({why})")]


__all__ = ["DEFAULT_GRID", "MAX_GRID", "MAX_GRID_POINTS", "FACTOR", "NEIGHBOURHOOD_TRIES", "SAFETY_STEPS",
           "OBJECTIVE_CLASS", "Objective", "parse_objective", "check_grid", "parse_boxes", "axis_values", "figure",
           "Point", "search", "best_point", "threshold", "neighbourhood", "neighbourhood_sentence", "Tuning",
           "check_tune", "weaker_float", "winner_sentence", "record_row"]
