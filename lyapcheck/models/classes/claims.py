"""The sentence each decided class of a model file prints, made from its checked figures alone.

A certificate's ``summary`` is what a reader believes, so it must never say more than the figures
beside it, which ``verify`` re-checks against the exact certificate. This module is the one place
that writes those sentences: :func:`lyapcheck.models.surfaces.certify.certify_model` sets each ``certified``
or ``refuted`` condition's summary with :func:`summary`, and
:func:`lyapcheck.models.surfaces.certificate.verify_document` regenerates it from the figures it has just
re-checked and fails where the file's text differs (an edited summary, ``limsup |y| <= 0.1`` where
0.52 was proved, is caught there). Reports print the regenerated text.

The disturbances (DESIGN.md, "Disturbances in claims"): a claim proved with every disturbance
held at 0 says ``(d = 0)``; a stability claim proved for every disturbance signal within its bounds
says so. ``not_certified``, ``inconclusive`` and ``not_applicable`` conditions claim nothing; their
text is a reason, not a summary of figures, and is left as the class wrote it.

Every figure is printed with its unit (:func:`with_unit`) and its reference point: times in s and
rates in 1/s (a model file is SI inside, and its time is in seconds with or without ``[units]``); a
bound in its output's unit (``bounds_unit``, with ``[units]``) and on the output's deviation from its
value at the equilibrium (``limsup |h - 30 m| <= 2.9 m``, ``bounds_reference``); a ball's radius in
the states' unit when they share one (``ball_radius_unit``); a level of ``V`` bare (``V`` has no
declared unit). A state's distance is always to the equilibrium: ``|x(t) - x_eq|``.
"""

from __future__ import annotations

from fractions import Fraction
from typing import TYPE_CHECKING, Any, Final, Iterable, Mapping, Sequence

from lyapcheck.exact import read_rational
from lyapcheck.results import ConditionResult

if TYPE_CHECKING:
    from lyapcheck.models.language.parameter_box import ModelBox
    from lyapcheck.results import Disturbances

#: what a ``certified`` sublevel set of each class is called in its sentence
SET_NAMES = {"roa": "region of attraction", "candidate": "the user's V"}
#: the prefix of a claim by the disturbances it covers (a stability class of a disturbed model)
DISTURBANCE_PREFIX = {"zero": "(d = 0) ", "all": "for every disturbance signal within its bounds: "}
#: said of a nominal claim whose robust form was tried and not found
ROBUST_NOT_FOUND = "; with the declared disturbances acting, no certificate of this class was found"
#: what a certified ``barrier`` states (:mod:`lyapcheck.models.classes.barrier`)
BARRIER_SENTENCE = ("safety: no trajectory that starts in the initial set ever enters the unsafe set (B <= 0 on the "
                    "initial set, B >= 1 on the unsafe set, B' <= lambda B everywhere; checked exactly)")
#: the certificate kind of a discrete-time map's barrier (:mod:`lyapcheck.models.classes.discrete_safety`) and
#: what it states: a map has steps, not times, so its sentence says "every iterate"
DISCRETE_BARRIER_KIND = "discrete_barrier"
DISCRETE_BARRIER_SENTENCE = ("safety of the discrete-time map: no iterate of a start in the initial set is ever in the "
                             "unsafe set, at every step (B <= 0 on the initial set, B >= 1 on the unsafe set, "
                             "B(F(x)) <= lambda B(x) for every state with lambda >= 0, so B <= 0 at every iterate; "
                             "checked exactly)")
#: the certificate kind of a discrete-time map's reach_avoid (lyapcheck.models.classes.discrete_safety)
DISCRETE_REACH_KIND = "discrete_reach_avoid"
#: the certificate kind of a discrete-time map's sos_bound (lyapcheck.models.classes.discrete_bounds): its
#: sentence speaks of iterates and steps (a limsup over the steps, not over time)
DISCRETE_BOUND_KIND = "discrete_bound"


def discrete_reach_sentence(steps: int) -> str:
    """The claim of a discrete-time map's ``reach_avoid`` certificate: a bound in steps, not a time."""
    return (f"reach-avoid of the discrete-time map: every start in the initial set has an iterate in the goal within "
            f"{steps} steps, and no iterate before it is in the unsafe set (V <= 0 on the initial set, V >= 1 on the "
            "unsafe set, V(F(x)) <= V(x) - eps for every state outside the goal, V bounded below; checked exactly)")


#: the unit of every time a sentence prints, and of every rate (its inverse): a model file is SI
#: inside and its ``[units]`` accept only ``time = "s"`` (lyapcheck.models.language.dimensions)
TIME_UNIT = "s"
RATE_UNIT = "1/s"
#: the certificate kinds of a loop with functions' safety classes (lyapcheck.models.classes.recast_barrier,
#: reach_avoid; :func:`sentence_of`)
RECAST_BARRIER_KIND = "recast_barrier"
#: the certificate kind of a loop with functions' barrier since barrier has one implementation (issue 41);
#: the older kind is refused by verify (lyapcheck.models.classes.barrier.check)
BARRIER_RELATIONS_KIND = "barrier_relations"
#: the same for reach_avoid (lyapcheck.models.classes.reach_avoid.check_functions refuses the older kind,
#: recast_reach_avoid)
RECAST_REACH_AVOID_KIND = "reach_avoid_relations"
#: how a ball-arithmetic region is proved (its sentence says so: :func:`interval_sentence`)
INTERVAL_METHOD = "ball arithmetic (python-flint arb) on the true field"
#: significant digits of a figure in a sentence (the JSON keeps the full figure)
FIGURE_DIGITS = 4


def rounded(value: float | Fraction, digits: int = FIGURE_DIGITS, direction: str = "nearest") -> str:
    """``value`` to ``digits`` significant digits, rounded towards the weaker claim: ``"up"`` for an
    upper bound (a limsup, a GES constant k, a time bound: 2.00015 prints 2.001, never 2),
    ``"down"`` for a lower bound (a decay rate, a level, a ball's radius), ``"nearest"`` for a
    figure that bounds nothing. A printed sentence never claims more than its certificate proves."""
    if direction == "nearest" or value == 0:
        return f"{float(value):.{digits}g}"
    import math
    from decimal import Decimal

    exact = Fraction(value)  # (a float converts exactly)
    exponent = math.floor(math.log10(abs(float(exact)))) - digits + 1
    quantum = Fraction(10) ** exponent
    steps = exact / quantum
    whole = math.ceil(steps) if direction == "up" else math.floor(steps)
    if direction not in ("up", "down"):
        raise ValueError(f"direction must be 'up', 'down' or 'nearest', got {direction!r}")
    text = f"{Decimal(whole).scaleb(exponent):.{digits + 1}g}"  # exact: at most digits + 1 significant digits
    return f"{float(text):.{digits + 1}g}"


def with_unit(value: float | Fraction, unit: str | None, digits: int = FIGURE_DIGITS, direction: str = "nearest"
              ) -> str:
    """A figure as a sentence prints it: ``2.294 m``; bare when it has no unit (``unit`` None or
    ``''``, dimensionless), rounded towards the weaker claim (:func:`rounded`). The one place a
    sentence formats a physical figure."""
    text = rounded(value, digits, direction)
    return f"{text} {unit}" if unit else text


def state_unit_figures(units: Mapping[str, str], states: Sequence[str], condition: Mapping[str, Any]
                       ) -> dict[str, Any]:
    """The unit of a condition's figure in the states (its ``ball_radius``), from the model's
    ``[units]`` as written (``units``; ``{}`` without the table): ``ball_radius_unit`` is the unit
    the states share (``''`` when all are dimensionless), or None when they differ (the radius is
    then a norm of SI values of different units). Nothing without ``[units]`` or a radius."""
    if not units or "ball_radius" not in condition:
        return {}
    found = {"" if units.get(s, "").strip() in ("", "1") else units[s].strip() for s in states}
    return {"ball_radius_unit": found.pop() if len(found) == 1 else None}


def deviation(name: str, reference: float | None, unit: str | None) -> str:
    """``h - 30 m``: a quantity's deviation from its value at the equilibrium, or ``h`` where that
    value is 0 (or not one number: ``reference`` None)."""
    if not reference:
        return name
    sign = "-" if reference > 0 else "+"
    return f"{name} {sign} {with_unit(abs(reference), unit, digits=6)}"


def nominal_coverage(bounds: Iterable[Fraction]) -> "Disturbances | None":
    """What a claim proved with every disturbance held at 0 covers (DESIGN.md, "Disturbances in claims"):
    None for a model without disturbances; ``"all"`` where every bound is 0 (each disturbance is then
    identically 0: the loop at d = 0 is the only one, and its claim holds for every admissible signal);
    ``"zero"`` otherwise."""
    bounds = list(bounds)
    if not bounds:
        return None
    return "all" if all(b == 0 for b in bounds) else "zero"


#: the classes whose certified claim is global asymptotic stability, in the order they run (the last one
#: certified is the one :func:`roa_after_gas` names)
GAS_CLASSES = ("quadratic", "sos_gas")


def roa_after_gas(results: Mapping[str, ConditionResult], covering: "Disturbances | None",
                  nominal: "Disturbances | None" = None, over_box: bool = False) -> ConditionResult | None:
    """``roa`` once GAS is certified, on every kind of loop (one rule): ``not_applicable``, the region of
    attraction being the whole state space, where ``quadratic`` or ``sos_gas`` certified GAS covering
    ``covering`` (DESIGN.md, "Disturbances in claims"); None otherwise (roa runs).

    ``covering``: what roa's own claim would cover, None on a loop without disturbances, ``"all"`` with
    disturbances (a GAS claim for every disturbance leaves roa nothing to add); ``"zero"`` once a region
    for every disturbance was not proved, the GAS claim with the disturbances held at 0 then answering
    roa's question for that loop (the sentence says ``d = 0``). A GAS result that does not state what it
    covers covers ``nominal`` (a loop with functions states its claims' coverage after its classes ran:
    its recasting has every disturbance at 0, :func:`nominal_coverage`). ``over_box``: the claim is for
    every value of a box of parameters, and says so."""
    gas = {(r.disturbances if r.disturbances is not None else nominal): name for name in GAS_CLASSES
           if (r := results.get(name)) is not None and r.status == "certified"}
    if covering not in gas:
        return None
    where = " for every value of the box" if over_box else ""
    why = (f"({gas[covering]}, d = 0){where}: with every disturbance held at 0 the region of attraction is the whole "
           "state space" if covering == "zero" else f"({gas[covering]}){where}: the region of attraction is the whole "
                                                    "state space")
    return ConditionResult("roa", "not_applicable", "global asymptotic stability is certified " + why, property="ROA",
                           disturbances=covering)


def covered(coverage: str | None, text: str) -> str:
    """A claim's sentence with the disturbances it covers in front (``(d = 0) ...``), as for a
    loop with functions, which is certified with its disturbances at 0."""
    return DISTURBANCE_PREFIX.get(coverage, "") + text if coverage is not None else text


def summary(name: str, condition: Mapping[str, Any], outputs: Sequence[str] = (),
            box: Mapping[str, Sequence[Any]] | None = None) -> str | None:
    """The sentence of a ``certified`` or ``refuted`` condition (its JSON form), or None for the
    other statuses and for a ball-arithmetic region (:mod:`lyapcheck.models.surfaces.ball_roa` writes and
    checks its sentence). ``outputs``: the model's output names (``sos_bound`` names those it did not
    bound); ``box``: the document's box of parameters (``{"mu": ["4/5", "6/5"]}``), which a claim
    over it names first. Raises KeyError, TypeError or ValueError on figures of the wrong form
    (verify reports them as a failed check)."""
    status = condition.get("status")
    if status not in ("certified", "refuted"):
        return None
    if name == "linearization":
        text = _linearization(status, condition)
    elif status != "certified":
        return None
    elif (condition.get("certificate") or {}).get("kind") == "interval":
        return None  # a ball-arithmetic region's sentence is the recast route's, re-made by its check (ball_roa)
    elif name == "sos_bound":
        text = _bounds(condition, outputs,
                       discrete=(condition.get("certificate") or {}).get("kind") == DISCRETE_BOUND_KIND)
    elif name == "barrier":
        discrete = (condition.get("certificate") or {}).get("kind") == DISCRETE_BARRIER_KIND
        text = DISCRETE_BARRIER_SENTENCE if discrete else BARRIER_SENTENCE
    elif name == "reach_avoid" and (condition.get("certificate") or {}).get("kind") == DISCRETE_REACH_KIND:
        text = discrete_reach_sentence(int(condition["reach_steps_bound"]))
    elif name == "reach_avoid":
        text = (f"reach-avoid: every trajectory that starts in the initial set reaches the goal within "
                f"{with_unit(_number(condition, 'reach_time_bound_s'), TIME_UNIT, direction='up')} without entering the unsafe set "
                "before (V <= 0 on the initial set, V >= 1 on the unsafe set, V' <= -eps outside the goal, V bounded "
                "below; checked exactly)")
        if "stay" in (condition.get("certificate") or {}):
            text += ("; and it stays in the goal afterwards (it reaches {W <= 0}, a set inside the goal that no "
                     "trajectory leaves: W' <= mu W; checked exactly)")
    else:
        text = _stability(name, condition)
    disturbances = condition.get("disturbances")
    if name != "sos_bound" and disturbances is not None:
        text = DISTURBANCE_PREFIX[disturbances] + text
    if "robust_attempt" in condition:
        text += ROBUST_NOT_FOUND
    if box and not (name == "linearization" and status == "refuted"):  # (a refutation names its point of the box)
        text = f"for every {box_words(box)}: {text}"
    return text


def box_words(box: Mapping[str, Sequence[Any]]) -> str:
    """``mu in [0.8, 1.2] and k in [1, 2]``: a box of parameters (exact bounds as in a certificate's
    ``box``) as a reader reads it (:meth:`~lyapcheck.models.language.parameter_box.ModelBox.describe`)."""
    from lyapcheck.models.language.parameter_box import ModelBox

    return ModelBox.from_json({name: [str(lo), str(hi)] for name, (lo, hi) in box.items()}).describe(" and ")


def _number(condition: Mapping[str, Any], key: str) -> float:
    value = condition[key]
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise TypeError(f"figure '{key}' must be a number, got {value!r}")
    return float(value)


def _linearization(status: str, condition: Mapping[str, Any]) -> str:
    data = condition.get("certificate" if status == "certified" else "refutation") or {}
    method = data.get("method")
    from lyapcheck.models.classes import discrete_linearization, piecewise_linearization

    if status == "certified" and piecewise_linearization.is_certificate(data):  # a kink at the equilibrium
        return piecewise_linearization.sentence(data)

    if method == SAMPLED_METHOD:  # a sampled-data loop's: its period is a figure of the certificate
        return sampled_linearization_sentence(status, read_rational(data["period"], "period"))

    if status == "certified" and method == BOX_BALL_STEIN_METHOD:  # a map with functions' over a box
        return box_ball_stein_sentence(int(data["box_parts"]))
    if discrete_linearization.is_discrete_certificate(data) and method == "box_stein":  # a map's over a box
        return DISCRETE_BOX_STEIN_SENTENCE
    if discrete_linearization.is_discrete_certificate(data):  # a map's: its own methods and words
        return discrete_linearization.sentence(status, data)
    if status == "certified" and method == "lyapunov_equation":
        return ("the Jacobian at the equilibrium is Hurwitz (J^T P + P J = -I with P > 0, exact): locally "
                "exponentially stable")
    if status == "certified" and method == "routh_hurwitz":
        return "the Jacobian is Hurwitz (every Hurwitz determinant > 0, exact): locally exponentially stable"
    if status == "refuted" and method == "lyapunov_inertia":
        return ("the Jacobian has an eigenvalue with positive real part (J^T P + P J = -I with P not positive "
                "definite, exact; inertia theorem): the equilibrium is unstable")
    if status == "certified" and method == "box_hurwitz":
        from lyapcheck.models.classes.linearization import BOX_SENTENCE

        return BOX_SENTENCE
    if status == "refuted" and method == "box_point":
        from lyapcheck.models.classes.linearization import lower_first, point_words

        point = {k: Fraction(v) for k, v in data["point"].items()}
        inner = _linearization("refuted", {"refutation": data["at_point"]})
        return f"at {point_words(point)}, a value of the box, {lower_first(inner)}"
    if status == "refuted" and method == "root_isolation":
        return (f"the Jacobian has an eigenvalue with positive real part (rigorous enclosure {data['root']}): the "
                "equilibrium is unstable")
    raise ValueError(f"unknown linearization method {method!r} for status {status!r}")


def discrete_lyapunov_sentence(kind: str, degree: int, mu: Fraction, figures: Mapping[str, Fraction] | None) -> str:
    """The claim of a discrete-time map's ``quadratic`` or ``sos_gas`` certificate
    (:mod:`lyapcheck.models.classes.discrete_lyapunov`), from its figures alone: ``k`` and ``r`` rounded
    up, the contraction ``1 - mu`` of V rounded up (a weaker claim, never a stronger one)."""
    if figures is not None:
        return (f"GES of the discrete-time map: |e_k| <= {rounded(figures['k'], 4, 'up')} |e_0| "
                f"{rounded(figures['r'], 4, 'up')}^k from every start (a quadratic V with V(F(e)) <= (1 - mu) V(e), "
                "checked exactly)")
    what = "a quadratic V" if degree == 2 else f"a polynomial V of degree {degree}"
    tail = f", and V(F(e)) <= {rounded(1 - mu, 4, 'up')} V(e) (V decays geometrically)" if mu > 0 else ""
    return (f"GAS of the discrete-time map: {what} with V(F(e)) < V(e) away from the equilibrium{tail} "
            "(checked exactly)")


#: the method of a sampled-data loop's linearization (lyapcheck.models.classes.sampled)
SAMPLED_METHOD = "sampled_routh"


def seconds_text(period: Fraction) -> str:
    """``period`` as an exact decimal where it has one (``1/50`` is ``0.02``), else ``p/q``."""
    from lyapcheck.exact import exact_decimal

    try:
        return exact_decimal(period)
    except ValueError:
        return str(period)


def sampled_linearization_sentence(status: str, period: Fraction) -> str:
    """The claim of a sampled-data loop's decided linearization (:mod:`lyapcheck.models.classes.sampled`,
    ``certified`` or ``refuted``) at ``period`` seconds, written exactly (an exact decimal where it has one,
    else ``p/q``): the claim holds at that period, and a rounded one near the critical period would name
    another loop."""
    loop = f"the sampled-data loop (zero-order hold, period {seconds_text(period)} s)"
    if status == "certified":
        return (f"{loop} is locally exponentially stable: every eigenvalue of its Jacobian over one period has "
                "modulus < 1 (checked in ball arithmetic)")
    if status == "refuted":
        return (f"{loop} is unstable: its Jacobian over one period has an eigenvalue of modulus > 1 (checked in ball "
                "arithmetic)")
    raise ValueError(f"a sampled-data linearization states nothing when {status!r}")


#: the certificate kind of a sampled-data loop's roa (lyapcheck.models.classes.sampled_regions)
SAMPLED_REGION_KIND = "sampled_region"


def sampled_region_sentence(period: Fraction, cert: Mapping[str, Any]) -> str:
    """The claim of a sampled-data loop's ``roa`` certificate (:mod:`lyapcheck.models.classes.sampled_regions`):
    the set at the sampling instants, the ball it lies in and the inter-sample excursion, each figure rounded
    the safe way (the level and the radius down, the excursion factor up)."""
    level = read_rational(cert["level"], "level")
    radius = read_rational(cert["radius"], "radius")
    factor = read_rational(cert["flow"]["Ce"], "Ce")
    return (f"region of attraction of the sampled-data loop (zero-order hold, period {seconds_text(period)} s): every "
            f"start x(t_k) in {{V <= {rounded(level, 6, 'down')}}} (V = e^T P e, inside |x - x_eq| <= "
            f"{rounded(radius, 6, 'down')}) stays in it at every sampling instant and converges to the equilibrium, "
            f"and between samples |x(t) - x_eq| <= {rounded(factor, 6, 'up')} |x(t_k) - x_eq| (V(Phi_T(x)) < V(x) "
            "proved by ball arithmetic on the true flow over one period: its remainder bounded by Gronwall and the "
            "field's Hessian)")


#: the claim of a map's linearization over a box (lyapcheck.models.classes.discrete_lyapunov.run_linearization_box;
#: the summary puts "for every <box>: " in front)
DISCRETE_BOX_STEIN_SENTENCE = ("every eigenvalue of the map's Jacobian at the fixed point has modulus < 1 (one P > 0 "
                               "with A^T P A - P < 0 for every Jacobian A of the box, by S-procedure multipliers, "
                               "exact): the discrete-time map is locally exponentially stable there")
#: the certificate kinds of a discrete-time map's quadratic and sos_gas (lyapcheck.models.classes.discrete_lyapunov)
DISCRETE_LYAPUNOV_KINDS = ("discrete_quadratic", "discrete_sos")
#: the certificate kind of a discrete-time map with functions' quadratic and sos_gas
#: (lyapcheck.models.classes.map_relations): the same sentences, GES where it states k and r
DISCRETE_RELATIONS_KIND = "discrete_relations"
#: the certificate kind of a discrete-time map's roa and candidate (lyapcheck.models.classes.discrete_regions)
DISCRETE_REGION_KIND = "discrete_sublevel"


#: the certificate kind of a discrete-time map with functions' roa and candidate, proved by ball arithmetic
#: (lyapcheck.models.classes.discrete_functions; over a box, discrete_functions_box)
DISCRETE_INTERVAL_KIND = "discrete_interval"
#: the method of a map with functions' linearization over a box (lyapcheck.models.classes.discrete_functions_box)
BOX_BALL_STEIN_METHOD = "box_ball_stein"


def discrete_interval_sentence(name: str, level: Fraction, over_box: bool) -> str:
    """The claim of a ``discrete_interval`` certificate (a map with functions' ``roa`` or ``candidate``, proved by
    ball arithmetic on the true map; ``over_box``: with the box's parameters as balls, the box's words put first
    by :func:`summary`), its level as the certificate states it (6 significant digits)."""
    if name == "candidate":
        V = "V the candidate"
    elif over_box:
        V = "V = e^T P e (P the linearization's over the box)"
    else:
        V = "V = e^T P e (P from the discrete Lyapunov equation of the exact Jacobian)"
    tail = (" with the box's parameters as balls" if over_box else
            " (every start in it stays in it and converges to the fixed point)")
    return (f"region of attraction of the map: {{V <= {float(level):.6g}}} with {V}, V(F(e)) < V(e) proved on it by "
            f"ball arithmetic on the true map{tail}")


def box_ball_stein_sentence(parts: int) -> str:
    """The claim of a map with functions' linearization over a box (one ``P`` for every Jacobian of the box,
    proved in ball arithmetic on ``parts`` parts of it); the box's words are put first by :func:`summary`."""
    return ("the map's fixed point is locally exponentially stable: one P > 0 with A(p)^T P A(p) - P < 0 for every "
            f"Jacobian A(p) of the box, proved in ball arithmetic on {parts} part(s) of the box")


def discrete_region_sentence(name: str, level: float) -> str:
    """The claim of a discrete-time map's ``roa`` or ``candidate`` certificate
    (:mod:`lyapcheck.models.classes.discrete_regions`): the set, its level rounded down, and that it is a
    region of attraction of the map."""
    prefix = "the user's V: " if name == "candidate" else ""
    return (f"{prefix}{{V <= {rounded(level, 6, 'down')}}} is a region of attraction of the discrete-time map: every "
            "start in it stays in it and its iterates converge to the fixed point (V(F(e)) <= V(e) - eps m(e) on the "
            "set, checked exactly)")


def _stability(name: str, condition: Mapping[str, Any]) -> str:
    cert = condition.get("certificate") or {}
    kind = cert.get("kind")
    if kind in DISCRETE_LYAPUNOV_KINDS or kind == DISCRETE_RELATIONS_KIND:
        ges = kind == "discrete_quadratic" or (kind == DISCRETE_RELATIONS_KIND and "k" in cert)
        figures = {key: read_rational(cert[key]) for key in ("k", "r")} if ges else None
        return discrete_lyapunov_sentence("discrete_quadratic" if ges else "discrete_sos", int(cert["degree"]),
                                          read_rational(cert["mu"]), figures)
    if kind == DISCRETE_REGION_KIND:
        return discrete_region_sentence(name, _number(condition, "level"))
    if kind == SAMPLED_REGION_KIND:
        return sampled_region_sentence(read_rational(cert["period"], "period"), cert)
    if kind == DISCRETE_INTERVAL_KIND:
        return discrete_interval_sentence(name, read_rational(cert["level"]), "parameter_box" in cert)
    if kind in ("sublevel", "quadratic_ball"):
        what = SET_NAMES.get(name, name)
        level = _number(condition, "level")
        ball = f"; {ball_words(condition)}" if "ball_radius" in condition else ""
        return (f"{what}: every start in {{V <= {rounded(level, 6, 'down')}}} converges to the equilibrium (checked "
                f"exactly){ball}")
    if kind == "lyapunov_vector":  # a vector Lyapunov function (lyapcheck.models.classes.vector_lyapunov)
        from lyapcheck.models.classes.vector_lyapunov import sentence

        return sentence(len(cert["groups"]), int(cert["degree"]),
                        with_unit(_number(condition, "decay_rate_V_per_s"), RATE_UNIT, direction="down"))
    if kind == "lyapunov_cascade":  # ISS-Lyapunov functions of a cascade (lyapcheck.models.classes.cascade_lyapunov)
        from lyapcheck.models.classes.cascade_lyapunov import sentence as cascade_sentence

        return cascade_sentence(len(cert["groups"]), int(cert["degree"]))
    if kind not in ("lyapunov", "lyapunov_cliques"):
        raise ValueError(f"unknown certificate kind {kind!r}")
    if condition.get("property") == "GES":
        return (f"GES: |x(t) - x_eq| <= {rounded(_number(condition, 'k'), FIGURE_DIGITS, 'up')} |x0 - x_eq| exp(-r t) "
                f"with r = {with_unit(_number(condition, 'decay_rate_per_s'), RATE_UNIT, direction='down')}, from every start (a quadratic V "
                "with V' <= -mu V, checked exactly)")
    rate = _number(condition, "decay_rate_V_per_s")
    if name == "candidate":
        tail = f", V' <= -r V with r = {with_unit(rate, RATE_UNIT, direction='down')}" if rate > 0 else ""
        return f"GAS: V' < 0 away from the equilibrium everywhere{tail} (checked exactly)"
    degree = condition["degree"]
    if isinstance(degree, bool) or not isinstance(degree, int):
        raise TypeError(f"figure 'degree' must be an integer, got {degree!r}")
    tail = (f", and V' <= -r V with r = {with_unit(rate, RATE_UNIT, direction='down')} (V decays exponentially from every start)"
            if rate > 0 else "")
    what = "a quadratic V" if degree == 2 else f"a polynomial V of degree {degree}"
    if kind == "lyapunov_cliques":
        what += f", a sum over {len(cert['cliques'])} cliques of the states,"
    from lyapcheck.models.classes.lyapunov import CONE_WORDS, cone_words

    cone = cert.get("cone")
    if cone is not None and cone not in CONE_WORDS:
        raise ValueError(f"unknown cone {cone!r} (one of {', '.join(CONE_WORDS)})")
    return f"GAS: {what} with V' < 0 away from the equilibrium{tail} (checked exactly{cone_words(cone)})"


def ball_words(condition: Mapping[str, Any]) -> str:
    """``it holds the ball |x - x_eq| <= 0.5 m``: a certified set's largest ball, with the states'
    unit where they share one (``ball_radius_unit``); where they do not (``null``), the radius is a
    Euclidean norm of the states' SI values, and the sentence says so."""
    radius = _number(condition, "ball_radius")
    unit = condition.get("ball_radius_unit")
    if unit is not None and not isinstance(unit, str):
        raise TypeError(f"figure 'ball_radius_unit' must be a unit or null, got {unit!r}")
    mixed = "ball_radius_unit" in condition and unit is None
    return (f"it holds the ball |x - x_eq| <= {with_unit(radius, unit, direction='down')}"
            + (" (the Euclidean norm of the states' SI values: they have different units)" if mixed else ""))


def size_words(condition: Mapping[str, Any]) -> str:
    """``size: the ball |x - x_eq| <= 1.13 m lies in the set; its reach along each state's axis from
    x_eq: x1 +-2.002 m, x2 +-2.167 m/s``: a certified region's size figures
    (:mod:`lyapcheck.models.classes.region_size`), each rounded down, in the states' units where
    ``[units]`` gives them; the ball is the larger of the size's and the SOS containment's
    (``ball_radius``), both proved. ``''`` when the condition states no size (the certificate's
    ``size.omitted`` then says why, and is printed instead)."""
    size = condition.get("size")
    found = condition.get("certificate")
    cert: Mapping[str, Any] = found if isinstance(found, Mapping) else {}
    table: Mapping[str, Any] = cert["size"] if isinstance(cert.get("size"), Mapping) else {}
    if not isinstance(size, Mapping) or not size:
        omitted = table.get("omitted")
        return f"size: not stated ({omitted})" if isinstance(omitted, str) and omitted else ""
    units: Mapping[str, Any] = table["units"] if isinstance(table.get("units"), Mapping) else {}
    parts = []
    radii = [r for r in (size.get("ball_radius"), condition.get("ball_radius"))
             if isinstance(r, (int, float)) and not isinstance(r, bool)]
    if radii:
        shared = set(units.values())
        unit = shared.pop() if len(shared) == 1 else None
        mixed = len(shared) > 1
        parts.append(f"the ball |x - x_eq| <= {with_unit(max(radii), unit, direction='down')} lies in the set"
                     + (" (a norm of SI values of different units)" if mixed else ""))
    extents = size.get("axis_extents")
    if isinstance(extents, Mapping) and extents:
        reach = ", ".join(f"{s} +-{with_unit(_number(extents, s), units.get(s) or None, direction='down')}"
                          for s in extents)
        parts.append(f"its reach along each state's axis from x_eq: {reach}")
    unbounded = table.get("unbounded_axes")
    if isinstance(unbounded, list) and unbounded:
        parts.append(f"it holds the whole axis of {', '.join(map(str, unbounded))}")
    return "size: " + "; ".join(parts) if parts else ""


def _bounds(condition: Mapping[str, Any], outputs: Sequence[str], discrete: bool = False) -> str:
    bounds = condition["bounds"]
    if not isinstance(bounds, dict):
        raise TypeError("figure 'bounds' must be a table of outputs")
    references = _table(condition, "bounds_reference", bounds)
    units = _table(condition, "bounds_unit", bounds)
    parts = []
    for k in bounds:
        # absent: a document without reference points (the output's value at the equilibrium is 0);
        # None: that value depends on a box's parameters, and the proof bounds the output itself
        reference = 0.0 if k not in references else None if references[k] is None else _number(references, k)
        unit = units.get(k)
        if unit is not None and not isinstance(unit, str):
            raise TypeError(f"figure 'bounds_unit' of {k} must be a unit, got {unit!r}")
        text = f"limsup |{deviation(k, reference, unit)}| <= {with_unit(_number(bounds, k), unit, direction='up')}"
        if reference is None:
            text += f" (of {k} itself: its value at the equilibrium depends on the box's parameters)"
        parts.append(text)
    if discrete:
        # a limsup over the steps: from any start each output comes, and stays, within any margin above its
        # bound (within the bound itself from a start in {V <= 1}, which no iterate leaves)
        out = (f"for every disturbance sequence within its bounds and every start, limsup over the steps: "
               f"{', '.join(parts)} (every iterate eventually stays within any margin above each bound; "
               "checked exactly)")
    else:
        out = f"for every disturbance within its bounds and every start: {', '.join(parts)} (checked exactly)"
    missing = [k for k in outputs if k not in bounds]
    if missing:
        out += f"; no bound for {', '.join(missing)}"
    return out


def _table(condition: Mapping[str, Any], key: str, bounds: Mapping[str, Any]) -> Mapping[str, Any]:
    """A per-output figure table (``bounds_reference``, ``bounds_unit``): absent, or a table over
    the bounded outputs exactly."""
    table = condition.get(key, {})
    if not isinstance(table, dict) or (key in condition and set(table) != set(bounds)):
        raise TypeError(f"figure '{key}' must be a table over the bounded outputs")
    return table


# -- V as a reader sees it ------------------------------------------------------------------------

#: significant digits of a coefficient in ``V_text`` and in the table's short form of V
V_DIGITS = 6
#: the table's short form of V shows this many terms, then how many more there are
V_SHORT_TERMS = 6


def v_text(terms: Mapping[str, Any], variables: Sequence[str], shifts: Mapping[str, Any] | None = None,
           limit: int | None = None) -> str:
    """``V`` (the contract's exact ``{"terms": [[coefficient, [exponents]], ...]}``, in ``z = x -
    x_eq``) as a readable polynomial in the declared names: coefficients to :data:`V_DIGITS`
    significant digits, each state with a non-zero equilibrium value written ``(x1 - 1.5)``; with
    ``limit``, only the first terms (by degree) and how many more. The exact V is ``terms``."""

    shifts = shifts or {}
    rows = []
    for coefficient, exponents in terms["terms"]:
        if len(exponents) != len(variables):
            raise ValueError(f"V: a term has {len(exponents)} exponents for {len(variables)} variables")
        rows.append((Fraction(coefficient), exponents))
    parts = []
    for k, (c, exponents) in enumerate(rows):
        if limit is not None and k == limit and len(rows) > limit + 1:  # one term more is shown, not counted
            parts.append(f"+ ... ({len(rows) - limit} more terms)")
            break
        factors = []
        for name, e in zip(variables, exponents):
            if e == 0:
                continue
            shift = read_rational(shifts.get(name, 0))
            base = name if shift == 0 else f"({name} {'-' if shift > 0 else '+'} {float(abs(shift)):.{V_DIGITS}g})"
            factors.append(base if e == 1 else f"{base}**{e}")
        magnitude = f"{float(abs(c)):.{V_DIGITS}g}"
        body = "*".join(factors) if magnitude == "1" and factors else "*".join([magnitude] + factors)
        sign = "-" if c < 0 else "+"
        parts.append(body if not parts and sign == "+" else f"{sign} {body}" if parts else f"-{body}")
    return " ".join(parts) if parts else "0"


def v_expression(terms: Mapping[str, Any], variables: Sequence[str], shifts: Mapping[str, Any] | None = None) -> Any:
    """``V`` exactly, as a sympy expression in the declared names (``x - x_eq`` where the
    equilibrium is not 0); the numbers are the certificate's rationals."""
    import sympy as sp

    shifts = shifts or {}
    def rational(value: Any) -> Any:  # through Fraction's own reader: no text reaches sympy's parser
        exact = read_rational(value)
        return sp.Rational(exact.numerator, exact.denominator)

    symbols = [sp.Symbol(name) - rational(shifts.get(name, 0)) for name in variables]
    total = sp.Integer(0)
    for coefficient, exponents in terms["terms"]:
        term = rational(coefficient)
        for base, e in zip(symbols, exponents):
            term *= base ** int(e)
        total += term
    return total


def box_prefix(box: ModelBox, status: str) -> str:
    """What a claim over a box says first: ``for every b in [0.5, 2]: `` (certified), or where in the
    box a refutation holds (its centre, one point of the box: the claim for every value is false)."""
    from lyapcheck.exact import exact_decimal

    if status == "certified":
        return f"for every {box_words({n: (lo, hi) for n, lo, hi in box.bounds})}: "
    centre = ", ".join(f"{n} = {exact_decimal(box.center(n))}" for n in box.names)
    return f"at the box's centre ({centre}), so not for every value of the box: "


# -- loops with functions: a certificate's own sentence --------------------------------------------------

def recast_reach_time(cert: dict[str, Any]) -> Fraction:
    """The certified time bound ``C / eps`` (s) of a reach-avoid certificate of a loop with functions
    (its time is in seconds: the loop is not scaled)."""
    return read_rational(cert["C"]) / read_rational(cert["eps_per_s"])


def sentence_of(cert: dict[str, Any]) -> str:
    """The claim sentence of a certificate of a loop with functions, of any kind (a barrier's is the
    polynomial loops' one): certify writes it, ``verify`` and the report re-make it from the certificate."""
    if cert.get("kind") in (RECAST_BARRIER_KIND, BARRIER_RELATIONS_KIND):
        return BARRIER_SENTENCE
    if cert.get("kind") == RECAST_REACH_AVOID_KIND:
        text = summary("reach_avoid", {"status": "certified", "reach_time_bound_s": float(recast_reach_time(cert))})
        assert text is not None  # (a certified reach_avoid always has its sentence)
        return text
    if cert.get("kind") == "interval":
        return interval_sentence(cert)
    if cert.get("kind") == "lyapunov_relations":  # quadratic, sos_gas: the polynomial loops' implementation
        from lyapcheck.models.classes.lyapunov import relations_sentence

        return relations_sentence(cert)
    return lyapunov_sentence(cert)


def lyapunov_sentence(cert: dict[str, Any]) -> str:
    """What a certified recast condition proves, in one sentence made from its certificate alone
    (``verify`` re-makes it and compares: a printed sentence never claims more than the proof). A
    distance is to the equilibrium, a rate in 1/s (:func:`lyapcheck.models.classes.claims.with_unit`)."""
    angles = list(cert["angles"])
    modulo = (f" modulo 2 pi in {', '.join(angles)} (the loop is periodic in {'it' if len(angles) == 1 else 'them'})"
              if angles else "")
    eps = cert["epsilon"]
    if "level" in cert:
        level = read_rational(cert["level"])
        return (f"region of attraction: every trajectory of the true loop starting where V(x, a(x)) <= "
                f"{rounded(level, 6, 'down')} (exactly {level}) converges to the equilibrium{modulo} (V positive definite "
                f"and V' <= -{eps} |dx|^2 / D there, D > 0, proved exactly on the recasting's relations; V_text in "
                "the certificate)")
    return (f"globally asymptotically stable{modulo}: V(x, a(x)) >= {cert.get('positivity_epsilon', eps)} |dx|^2 and "
            f"V' <= -{eps} |dx|^2 / D everywhere, D > 0 (proved exactly on the recasting's relations; V_text in the "
            "certificate)")


#: a ball-arithmetic set's boxes proved to flow into it (lyapcheck.models.classes.flow_region): the kind of the
#: certificate's ``flow`` and how the boxes are proved
FLOW_KIND: Final = "validated_flow"
FLOW_METHOD: Final = ("validated integration of the true loop in ball arithmetic (python-flint arb, outward rounding; "
                      "second-order Taylor steps with a Picard a priori enclosure and a mean-value (Lohner) form)")


def flow_volume(corners: Mapping[str, Sequence[str]]) -> Fraction:
    """The volume of a box given by each state's ``[lo, hi]`` (rational texts)."""
    v = Fraction(1)
    for a, b in corners.values():
        v *= read_rational(b) - read_rational(a)
    return v


def flow_sentence(cert: dict[str, Any]) -> str:
    """The words a certificate's ``flow`` adds to its set's sentence (from the certificate alone)."""
    boxes = cert["flow"]["boxes"]
    volume = sum((flow_volume(p["box"]) for p in boxes), Fraction(0))
    longest = max(read_rational(p["t"]) for p in boxes)
    return (f"; and every trajectory starting in any of the {len(boxes)} boxes of the certificate's flow (state "
            f"deviations, rational corners, total volume {float(volume):.6g}) converges to the equilibrium itself "
            f"too: each box is proved, by {FLOW_METHOD}, to lie inside that set by its stated time (at most "
            f"{float(longest):.6g}). The region of attraction proved is the union of the set and the boxes; that "
            "union is not a sublevel set and is not proved invariant")


def interval_sentence(cert: dict[str, Any]) -> str:
    """What a ball-arithmetic region (certificate kind ``interval``) proves, from the certificate alone
    (``verify`` re-makes and compares)."""
    level = read_rational(cert["level"])
    n = len(cert["box"])
    written = "V(x, a(x))" if any(any(e[n:]) for _, e in cert["V"]["terms"]) else "V(x)"
    # the box rounded towards the weaker claim: outwards where the set is said to lie in it, inwards
    # where the proved set is the part of {V <= level} in it
    out, inward = ("down", "up") if cert.get("whole") else ("up", "down")
    units = cert.get("units") or {}
    box = ", ".join(f"{s} - eq in [{rounded(Fraction(a), 6, out)}, {rounded(Fraction(b), 6, inward)}]"
                    + (f" {units[s]}" if units.get(s) else "") for s, (a, b) in cert["box"].items())
    level_text = rounded(level, 6, "down")
    if "flow" in cert:  # boxes proved to flow into the set (lyapcheck.models.classes.flow_region)
        return interval_sentence({k: v for k, v in cert.items() if k != "flow"}) + flow_sentence(cert)
    if cert.get("whole"):
        return (f"region of attraction: every trajectory of the true loop starting where {written} <= "
                f"{level_text} (exactly {level}) converges to the equilibrium itself (the whole set lies in "
                f"{box}: V > level outside it, and V' < 0 on the set except at the equilibrium; proved by {INTERVAL_METHOD}, "
                "with an exact Hessian argument at the equilibrium and an exact growth bound of V far out; V_text "
                "in the certificate)")
    return (f"region of attraction: every trajectory of the true loop starting where {written} <= {level_text} "
            f"(exactly {level}) with {box} converges to the equilibrium itself (V > level on that box's boundary, "
            f"V' < 0 on the set except at the equilibrium; proved by {INTERVAL_METHOD}, with an exact Hessian argument at the "
            "equilibrium; V_text in the certificate)")


__all__ = ["summary", "roa_after_gas", "GAS_CLASSES", "box_words", "box_prefix", "ball_words", "size_words", "with_unit", "deviation", "state_unit_figures", "v_text",
           "v_expression", "sentence_of", "recast_reach_time", "lyapunov_sentence", "interval_sentence", "SET_NAMES", "DISTURBANCE_PREFIX", "TIME_UNIT",
           "RATE_UNIT", "DISCRETE_BARRIER_KIND", "DISCRETE_BARRIER_SENTENCE",
           "DISCRETE_REACH_KIND", "DISCRETE_BOUND_KIND", "discrete_reach_sentence", "SAMPLED_METHOD",
           "sampled_linearization_sentence", "seconds_text",
           "SAMPLED_REGION_KIND", "sampled_region_sentence"]
