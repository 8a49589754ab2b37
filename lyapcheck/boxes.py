"""Certificates for whole boxes of gain space: one proof for every gain set in the box.

Why it is exact. In the scaled coordinates of :mod:`lyapcheck.conditions.ges` the error dynamics
depend on the gains only through three numbers,

    c = a12/(sigma0 |a11|),   a = -a22/|a11|,   b = sigma0 U/(Delta |a11|),

and the generated dynamics (:mod:`symbolic._generated`) make each entry ``a11``, ``a12``,
``a22`` a signed monomial in the positive parameters (``tests/test_boxes.py`` checks this on the
derivation). So ``c``, ``a`` and ``b`` are monomials too, hence monotone in every parameter, and
over a box their ranges are the intervals spanned by their values at the box's corners. The
``ges`` conditions are affine in ``(c, a, b)`` for a fixed certificate (``A(w)`` is affine in
them, ``M(w)`` does not depend on them), and positive definiteness is preserved by convex
combinations, so a certificate checked exactly at the eight corners of the ``(c, a, b)`` box
holds at every gain set of the parameter box. The decay rate in seconds is
``mu |a11| / 2 >= mu min|a11| / 2`` and ``k = sqrt(c2/c1)`` does not depend on the point.

Statuses of a box: ``certified`` (for every point), ``not_certified`` (no common certificate
found), ``refuted`` (a class's own condition is proved impossible at a point of the box: the
paper's eq. ``stabCond`` by the exact ``Gamma_22`` bound, ``sector_ges`` by Shorten-Narendra), and
in :func:`refine` a box that is not certified is split until its relative width is below the
given minimum. The other classes over a box live in their own modules (:data:`BOX_CLASSES`).
No box is ever ``refuted`` for GES itself, and that is a fact of the model, not a gap:
``c = -1`` identically (``tests/test_boxes.py`` checks it on the derivation), so the
linearisation ``[[-1, c], [b, -a]]`` at the origin has ``det = a + b > 0`` at every positive gain
set, and the one exact local obstruction to GES (a non-Hurwitz linearisation) never occurs. A
refutation would need a global argument (trajectories whose decay has no uniform exponential
envelope); none is known for these dynamics.

:func:`cross_check` simulates random points of a certified box against the box's envelope.
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass
from fractions import Fraction
from typing import Any, Mapping, Sequence

from lyapcheck.errors import InvalidParameter
from lyapcheck.params import FIELD_BY_KEY, Problem, validate_field

#: parameters a box may span -> the key of the FIELDS table
BOX_FIELDS: dict[str, str] = {
    "alpha_d": "gains.alpha_d", "sigma0": "gains.sigma0", "k_d": "gains.k_d", "delta_los": "gains.delta_los",
    "los_speed": "gains.los_speed", "e11": "swimmer.e11",
}


@dataclass(frozen=True)
class ParameterBox:
    """Closed intervals ``[lo, hi]`` (SI, exact) of some gain parameters; the others are fixed."""

    bounds: tuple[tuple[str, Fraction, Fraction], ...]

    def to_json(self) -> dict[str, list[str]]:
        return {name: [str(lo), str(hi)] for name, lo, hi in self.bounds}

    @classmethod
    def from_json(cls, data: Mapping[str, Sequence[str]]) -> "ParameterBox":
        return cls(tuple((name, Fraction(lo), Fraction(hi)) for name, (lo, hi) in data.items()))

    def corners(self) -> list[dict[str, Fraction]]:
        return [dict(zip((n for n, _, _ in self.bounds), values))
                for values in itertools.product(*((lo, hi) for _, lo, hi in self.bounds))]

    def split(self) -> tuple["ParameterBox", "ParameterBox"]:
        """Halve the widest interval (relative width, the parameters span decades)."""
        widest = max(range(len(self.bounds)), key=lambda i: self.bounds[i][2] / self.bounds[i][1])
        name, lo, hi = self.bounds[widest]
        mid = (lo + hi) / 2
        left = self.bounds[:widest] + ((name, lo, mid),) + self.bounds[widest + 1:]
        right = self.bounds[:widest] + ((name, mid, hi),) + self.bounds[widest + 1:]
        return ParameterBox(left), ParameterBox(right)

    def relative_width(self) -> float:
        return max(float(hi / lo) - 1 for _, lo, hi in self.bounds)

    def describe(self) -> str:
        return ", ".join(f"{name} in [{float(lo):.6g}, {float(hi):.6g}]" for name, lo, hi in self.bounds)


def parse_box(specs: Sequence[str]) -> ParameterBox:
    """``["alpha_d=540..660", "delta_los=0.5 mm..1 mm"]`` -> :class:`ParameterBox` (one-line errors)."""
    bounds: list[tuple[str, Fraction, Fraction]] = []
    for spec in specs:
        name, sep, interval = spec.partition("=")
        name = name.strip()
        if not sep or ".." not in interval:
            raise InvalidParameter("box", "NAME=LO..HI, e.g. 'alpha_d=540..660'", spec)
        if name not in BOX_FIELDS:
            raise InvalidParameter("box", f"a parameter among {', '.join(BOX_FIELDS)}", name)
        if any(name == b[0] for b in bounds):
            raise InvalidParameter(name, "given once in --box", spec)
        lo_text, _, hi_text = interval.partition("..")
        field = FIELD_BY_KEY[BOX_FIELDS[name]]
        lo, hi = validate_field(field, lo_text.strip()), validate_field(field, hi_text.strip())
        if lo > hi:
            raise InvalidParameter(name, f"an interval with low <= high (box '{spec}')", interval)
        bounds.append((name, lo, hi))
    if not bounds:
        raise InvalidParameter("box", "at least one NAME=LO..HI", "")
    return ParameterBox(tuple(bounds))


def problem_at_point(problem: Problem, point: Mapping[str, Fraction]) -> Problem:
    """``problem`` with the parameters of ``point`` (names of :data:`BOX_FIELDS`) set."""
    from dataclasses import replace

    gains = {k: v for k, v in point.items() if k != "e11"}
    p = problem.with_gains(**gains) if gains else problem
    if "e11" in point:
        p = replace(p, swimmer=replace(p.swimmer, e11=point["e11"]))
    return p


def corner_problems(problem: Problem, box: ParameterBox) -> list[Problem]:
    """The problem at every corner of the box (the other parameters as in ``problem``)."""
    return [problem_at_point(problem, corner) for corner in box.corners()]


def stored_hull(problem: Problem, box: ParameterBox, dynamics: str,
                cert: Mapping[str, Any]) -> tuple[list[Any], Fraction] | str:
    """The ``(c, a, b)`` hull re-derived from the box, or why the certificate's stored copy differs."""
    hull = scaled_hull(problem, box, dynamics)
    if hull is None:
        return "the dynamics at some corner do not have the structure this class needs"
    vertices, ts_min = hull
    stored = {tuple(Fraction(x) for x in v) for v in cert["vertices"]}
    if stored != {(v.c, v.a, v.b) for v in vertices} or Fraction(cert["time_scale_min"]) != ts_min:
        return "the stored (c, a, b) vertices or min |a11| do not match the box"
    return hull


def scaled_hull(problem: Problem, box: ParameterBox, dynamics: str) -> tuple[list[Any], Fraction] | None:
    """Vertices of the ``(c, a, b)`` box over the parameter box, and ``min |a11|`` (exact)."""
    from lyapcheck.certification import build_system
    from lyapcheck.conditions.sos import ScaledDynamics, scaled_dynamics

    points = []
    for p in corner_problems(problem, box):
        dyn = scaled_dynamics(build_system(p, dynamics))
        if dyn is None:
            return None
        points.append(dyn)
    ranges = [(min(getattr(d, k) for d in points), max(getattr(d, k) for d in points)) for k in ("c", "a", "b")]
    vertices = [ScaledDynamics(time_scale=Fraction(1), c=c, a=a, b=b) for c, a, b in itertools.product(*ranges)]
    unique = list({(v.c, v.a, v.b): v for v in vertices}.values())
    return unique, min(d.time_scale for d in points)


#: classes with box certificates, in the order of :data:`lyapcheck.certification.CONDITION_ORDER`:
#: ``prop41_*`` (:mod:`lyapcheck.box_prop41`), ``sector_ges`` and ``ges`` (here), ``ultimate_bound``
#: (:mod:`lyapcheck.box_ultimate`), ``sos_gas`` (:mod:`lyapcheck.box_sos_gas`), ``saturated_loop``
#: (:mod:`lyapcheck.box_saturated`) and ``sos_bound`` (:mod:`lyapcheck.box_bounds`, 5-10 s a box)
BOX_CLASSES: tuple[str, ...] = ("prop41_ges", "prop41_iss", "sector_ges", "ultimate_bound", "sos_gas", "ges",
                                "saturated_loop", "sos_bound")
#: the classes whose certificate proves stability (GES, ISS or GAS): a box's verdict
BOX_STABILITY_CLASSES: tuple[str, ...] = ("prop41_ges", "prop41_iss", "sector_ges", "sos_gas", "ges")
#: run by ``certify --box`` unless ``--classes`` says otherwise (the cheap ones: well under a second)
DEFAULT_BOX_CLASSES: tuple[str, ...] = ("prop41_ges", "prop41_iss", "sector_ges", "ges")


def _class_functions(cls: str) -> tuple[Any, Any]:
    """``(certify(problem, box, dynamics), verify(problem, box, dynamics, result))`` of a box class."""
    from functools import partial

    if cls in ("prop41_ges", "prop41_iss"):
        from lyapcheck.box_prop41 import certify_prop41_box, verify_prop41_box

        iss = cls == "prop41_iss"
        return partial(certify_prop41_box, iss=iss), partial(verify_prop41_box, iss=iss)
    if cls == "ultimate_bound":
        from lyapcheck.box_ultimate import certify_ultimate_box, verify_ultimate_box

        return certify_ultimate_box, verify_ultimate_box
    if cls == "sos_gas":
        from lyapcheck.box_sos_gas import certify_gas_box, verify_gas_box

        return certify_gas_box, verify_gas_box
    if cls == "saturated_loop":
        from lyapcheck.box_saturated import certify_saturated_box, verify_saturated_box

        return certify_saturated_box, verify_saturated_box
    if cls == "sos_bound":
        from lyapcheck.box_bounds import certify_bound_box, verify_bound_box

        return certify_bound_box, verify_bound_box
    return {"sector_ges": (_certify_sector_box, _verify_sector_box),
            "ges": (_certify_ges_box, _verify_ges_box)}[cls]


def certify_box(problem: Problem, box: ParameterBox, dynamics: str = "derived", cls: str = "ges") -> dict[str, Any]:
    """Class ``cls`` (:data:`BOX_CLASSES`) for every gain set in ``box``; a JSON-ready result."""
    if cls not in BOX_CLASSES:
        raise InvalidParameter("classes", "box classes among " + ", ".join(BOX_CLASSES), cls)
    certify, _ = _class_functions(cls)
    try:
        result: dict[str, Any] = certify(problem, box, dynamics)
    except OverflowError:
        # the corners are exact, but the searches work in doubles: a box whose corners combine
        # into figures beyond 1.8e308 gets no search (claiming nothing is always sound)
        from lyapcheck.conditions.base import PROPERTY

        return {"status": "not_certified", "property": PROPERTY[cls], "box": box.to_json(),
                "summary": f"the box's data leave the double range ({box.describe()}): no search was run "
                           "(a narrower box may fit)"}
    return result


def verify_box(problem: Problem, box: ParameterBox, dynamics: str, result: Mapping[str, Any],
               cls: str = "ges") -> tuple[bool, str]:
    """Re-check a box certificate of class ``cls`` exactly (no solver)."""
    if cls not in BOX_CLASSES:
        return False, f"'{cls}' has no box certificates"
    _, verify = _class_functions(cls)
    checked: tuple[bool, str] = verify(problem, box, dynamics, result)
    return checked


def _certify_ges_box(problem: Problem, box: ParameterBox, dynamics: str) -> dict[str, Any]:
    from lyapcheck.conditions import ges

    hull = scaled_hull(problem, box, dynamics)
    if hull is None:
        return {"status": "not_certified", "property": "GES",
                "summary": "the dynamics at some corner do not have the structure this class needs"}
    vertices, ts_min = hull
    log: list[dict[str, Any]] = []
    cert = ges.search(vertices, log)
    if cert is None:
        return {"status": "not_certified", "property": "GES", "box": box.to_json(),
                "summary": f"no state-dependent quadratic V common to the box was found ({box.describe()}); "
                           "this is not a proof that GES fails anywhere in it", "solver": {"solves": log}}
    mu, c1, c2 = (Fraction(cert[k]) for k in ("mu_scaled", "c1", "c2"))
    k = math.sqrt(float(c2 / c1))
    rate = float(mu * ts_min) / 2
    summary = (f"GES for every gain set with {box.describe()}: |x(t)| <= {k:.3g} |x0| exp(-{rate:.3g} t) "
               "(x = (eps, sigma0 s)/Delta), one state-dependent quadratic V checked exactly at the corners")
    return {"status": "certified", "property": "GES", "summary": summary, "box": box.to_json(), "k": k,
            "decay_rate_per_s": rate,
            "certificate": {**cert, "vertices": [[str(v.c), str(v.a), str(v.b)] for v in vertices],
                            "time_scale_min": str(ts_min)},
            "solver": {"solves": log}}


def _stored_quadratic(problem: Problem, box: ParameterBox, dynamics: str,
                      result: Mapping[str, Any]) -> tuple[Mapping[str, Any], list[Any], Fraction, Any] | str:
    """The certificate, its ``(c, a, b)`` vertices re-derived from the box, ``min |a11|`` and ``P``
    (the common start of the ``ges`` and ``sector_ges`` box checks), or why the hull differs."""
    from lyapcheck import exact

    cert = result["certificate"]
    hull = stored_hull(problem, box, dynamics, cert)
    if isinstance(hull, str):
        return hull
    vertices, ts_min = hull
    return cert, vertices, ts_min, exact.from_json(cert["P"])


def _verify_ges_box(problem: Problem, box: ParameterBox, dynamics: str, result: Mapping[str, Any]) -> tuple[bool, str]:
    """Re-derive the ``(c, a, b)`` box from the parameter box and re-check every vertex exactly."""
    from lyapcheck.conditions import ges

    stored = _stored_quadratic(problem, box, dynamics, result)
    if isinstance(stored, str):
        return False, stored
    cert, vertices, ts_min, P = stored
    ells = [[Fraction(x) for x in ell] for ell in cert["l"]]
    mu, c1, c2 = (Fraction(cert[k]) for k in ("mu_scaled", "c1", "c2"))
    for v in vertices:
        ok, why = ges.exact_check(v, P, ells, mu, c1, c2)
        if not ok:
            return False, f"at (c, a, b) = ({float(v.c):.6g}, {float(v.a):.6g}, {float(v.b):.6g}): {why}"
    # the stated envelope is the claim users read: k no smaller, the rate no larger than proved
    if "k" in result and not Fraction(float(result["k"])) ** 2 >= c2 / c1 * (1 - Fraction(1, 10**12)):
        return False, f"the stated k = {result['k']} is below sqrt(c2/c1) = {math.sqrt(float(c2 / c1))}"
    if "decay_rate_per_s" in result and \
            not Fraction(float(result["decay_rate_per_s"])) <= mu * ts_min / 2 * (1 + Fraction(1, 10**12)):
        return False, f"the stated decay rate {result['decay_rate_per_s']} exceeds the certified {float(mu * ts_min) / 2}"
    return True, f"the ges conditions hold exactly at all {len(vertices)} vertices of the (c, a, b) box"


# -- sector_ges over a box: one quadratic V for the whole polytope ------------------------------------
#: vertices of the box's matrix polytope handed to the solver (repeated to this count: the
#: stored program ``sector_8`` has eight vertex parameters)
SECTOR_BOX_VERTICES = 8


def sector_polytope(vertices: Sequence[Any]) -> list[Any]:
    """The matrices ``[[-1, c], [r, -a]]`` at the corners of ``c, a`` ranges and ``r in {0, b_max}``.

    In scaled coordinates the sector system is ``x' = [[-1, c], [r, -a]] x`` with ``0 < r <= b``
    (:mod:`lyapcheck.conditions.sector` in the coordinates of :mod:`lyapcheck.conditions.ges`), and
    over the box ``c``, ``a``, ``b`` range over the intervals spanned by the ``(c, a, b)`` hull. The
    matrix is affine in ``(c, a, r)``, so every matrix of every gain set in the box lies in the
    convex hull of these, and a quadratic form decreasing at them decreases at every one.
    """
    from lyapcheck import exact

    cs = sorted({v.c for v in vertices})
    as_ = sorted({v.a for v in vertices})
    b_max = max(v.b for v in vertices)
    out = []
    for c in (cs[0], cs[-1]):
        for a in (as_[0], as_[-1]):
            for r in (Fraction(0), b_max):
                m = exact.matrix([[-1, c], [r, -a]])
                if m not in out:
                    out.append(m)
    return out


def _eigen_bounds(P: Any) -> tuple[Fraction, Fraction] | None:
    """Rationals ``c1 <= lambda_min(P)``, ``c2 >= lambda_max(P)``, checked exactly (``c1 > 0``)."""
    import numpy as np

    from lyapcheck import exact

    lam = np.linalg.eigvalsh(np.array(exact.to_float(P)))
    c1 = exact.to_rational(float(lam[0]) * (1 - 1e-6), 8)
    c2 = exact.to_rational(float(lam[1]) * (1 + 1e-6), 8)
    eye = exact.matrix([[1, 0], [0, 1]])
    if c1 <= 0 or not exact.is_positive_definite(exact.add(P, exact.scale(-c1, eye))) \
            or not exact.is_positive_definite(exact.add(exact.scale(c2, eye), exact.scale(Fraction(-1), P))):
        return None
    return c1, c2


def _certify_sector_box(problem: Problem, box: ParameterBox, dynamics: str) -> dict[str, Any]:
    """``sector_ges`` for every gain set in ``box``: a common ``P`` over :func:`sector_polytope`.

    Refuted (exactly) when a corner's own two sector matrices have no common quadratic Lyapunov
    function (Shorten-Narendra): that corner is a gain set of the box, so no ``P`` serves the box.
    """
    from lyapcheck import exact
    from lyapcheck.certification import build_system
    from lyapcheck.conditions import sector
    from lyapcheck.conditions.sos import scaled_dynamics

    hull = scaled_hull(problem, box, dynamics)
    if hull is None:
        return {"status": "not_certified", "property": "GES",
                "summary": "the dynamics at some corner do not have the structure this class needs"}
    vertices, ts_min = hull
    # the corners of the parameter box are gain sets of the box (the (c, a, b) hull's vertices
    # need not be: they combine the ranges independently)
    for corner, p in zip(box.corners(), corner_problems(problem, box)):
        v = scaled_dynamics(build_system(p, dynamics))
        assert v is not None  # scaled_hull succeeded at every corner
        refuted = sector.refutation([exact.matrix([[-1, v.c], [0, -v.a]]), exact.matrix([[-1, v.c], [v.b, -v.a]])])
        if refuted is not None:
            where = ", ".join(f"{name} = {float(value):.6g}" for name, value in corner.items())
            return {"status": "refuted", "property": "GES", "box": box.to_json(),
                    "refutation": {**refuted, "point": {name: str(value) for name, value in corner.items()}},
                    "summary": f"no quadratic V common to the box: at its corner {where}, {refuted['statement']}"}
    polytope = sector_polytope(vertices)
    padded = (polytope * SECTOR_BOX_VERTICES)[:SECTOR_BOX_VERTICES]
    P, rate, margin, report = sector.certify_polytope(padded)
    bounds = None if P is None or not rate else _eigen_bounds(P)
    if P is None or not rate or bounds is None:
        return {"status": "not_certified", "property": "GES", "box": box.to_json(),
                "summary": f"no quadratic V common to the box was found ({box.describe()}, margin "
                           f"{margin if margin is not None else 'n/a'}); this is not a proof that GES fails",
                "solver": {"solves": [report.to_json()]}}
    c1, c2 = bounds
    k = math.sqrt(float(c2 / c1))
    decay = float(rate * ts_min)
    summary = (f"GES for every gain set with {box.describe()}: |x(t)| <= {k:.3g} |x0| exp(-{decay:.3g} t) "
               "(x = (eps, sigma0 s)/Delta), one quadratic V = x^T P x checked exactly at the polytope's "
               f"{len(polytope)} vertices")
    return {"status": "certified", "property": "GES", "summary": summary, "box": box.to_json(), "k": k,
            "decay_rate_per_s": decay,
            "certificate": {"P": exact.to_json(P), "decay_rate_scaled": str(rate), "c1": str(c1), "c2": str(c2),
                            "vertices": [[str(v.c), str(v.a), str(v.b)] for v in vertices],
                            "time_scale_min": str(ts_min)},
            "solver": {"solves": [report.to_json()]}}


def _verify_sector_box(problem: Problem, box: ParameterBox, dynamics: str,
                       result: Mapping[str, Any]) -> tuple[bool, str]:
    from lyapcheck import exact
    from lyapcheck.conditions import sector

    stored = _stored_quadratic(problem, box, dynamics, result)
    if isinstance(stored, str):
        return False, stored
    cert, vertices, ts_min, P = stored
    if len(P) != 2 or not exact.is_symmetric(P):
        return False, "P must be a symmetric 2x2 matrix"
    rate, c1, c2 = (Fraction(cert[k]) for k in ("decay_rate_scaled", "c1", "c2"))
    if rate <= 0 or c1 <= 0:
        return False, "the decay rate and c1 must be positive"
    eye = exact.matrix([[1, 0], [0, 1]])
    if not (exact.is_positive_definite(exact.add(P, exact.scale(-c1, eye)))
            and exact.is_positive_definite(exact.add(exact.scale(c2, eye), exact.scale(Fraction(-1), P)))):
        return False, "c1 I < P < c2 I does not hold"
    polytope = sector_polytope(vertices)
    ok, why = sector.exact_check(polytope, P, rate)
    if not ok:
        return False, why
    k = math.sqrt(float(c2 / c1))
    if "k" in result and not float(result["k"]) >= k * (1 - 1e-12):
        return False, f"the stated k = {result['k']} is below sqrt(c2/c1) = {k}"
    if "decay_rate_per_s" in result and not float(result["decay_rate_per_s"]) <= float(rate * ts_min) * (1 + 1e-12):
        return False, f"the stated decay rate {result['decay_rate_per_s']} exceeds the certified {float(rate * ts_min)}"
    return True, f"one P > 0 decreases at all {len(polytope)} vertices of the box's matrix polytope, exactly"


def verify_box_refutation(problem: Problem, box: ParameterBox, dynamics: str, result: Mapping[str, Any],
                          cls: str) -> tuple[bool, str]:
    """Re-check a box's refutation: its point lies in the box and is refuted there, exactly."""
    from lyapcheck import exact
    from lyapcheck.certification import build_system
    from lyapcheck.conditions import sector
    from lyapcheck.conditions.sos import scaled_dynamics

    if cls not in ("sector_ges", "prop41_ges", "prop41_iss"):
        return False, f"'{cls}' has no box refutations"
    point = {name: Fraction(value) for name, value in result["refutation"]["point"].items()}
    bounds = {name: (lo, hi) for name, lo, hi in box.bounds}
    if set(point) != set(bounds) or any(not bounds[n][0] <= x <= bounds[n][1] for n, x in point.items()):
        return False, "the refuting point is not a point of the box"
    if cls != "sector_ges":
        from lyapcheck.box_prop41 import verify_prop41_refutation

        return verify_prop41_refutation(problem, point, dynamics, result["refutation"])
    v = scaled_dynamics(build_system(problem_at_point(problem, point), dynamics))
    if v is None:
        return False, "the dynamics at the refuting point do not have the structure this class needs"
    refuted = sector.refutation([exact.matrix([[-1, v.c], [0, -v.a]]), exact.matrix([[-1, v.c], [v.b, -v.a]])])
    if refuted is None:
        return False, "the stated point is not refuted (Shorten-Narendra does not apply there)"
    return True, f"refuted at a point of the box: {refuted['statement']}"


@dataclass(frozen=True)
class BoxOutcome:
    box: ParameterBox
    status: str
    result: dict[str, Any]


def refine(problem: Problem, box: ParameterBox, *, min_relative_width: float, dynamics: str = "derived",
           max_boxes: int = 256) -> list[BoxOutcome]:
    """Certify ``box``; split what is not certified until its relative width is below the minimum.

    Returns the leaves: ``certified`` boxes (each with its own exact certificate) and
    ``not_certified`` boxes that reached the minimum width (or the ``max_boxes`` budget).
    """
    if not (min_relative_width > 0):
        raise InvalidParameter("min_relative_width", "a number > 0", min_relative_width)
    todo: list[ParameterBox] = [box]
    leaves: list[BoxOutcome] = []
    while todo:
        current = todo.pop(0)
        result = certify_box(problem, current, dynamics)
        if result["status"] == "certified" or current.relative_width() <= min_relative_width \
                or len(leaves) + len(todo) + 2 > max_boxes:
            leaves.append(BoxOutcome(current, result["status"], result))
        else:
            todo.extend(current.split())
    return leaves


#: starting radii (in x = (eps, sigma0 s)/Delta) and directions of the cross-check trajectories:
#: the claim is global, so from well inside the saturation of the LOS law to far outside it
CROSS_CHECK_RADII: tuple[float, ...] = (0.1, 1.0, 10.0, 100.0)
CROSS_CHECK_ANGLES = 6
#: the simulated time: until the envelope has decayed by exp(-CROSS_CHECK_DECAYS), at most
#: CROSS_CHECK_MAX_TAU time-scaled units
CROSS_CHECK_DECAYS = 4.0
CROSS_CHECK_MAX_TAU = 4000.0


def sample_points(box: ParameterBox, count: int, seed: Sequence[int]) -> list[dict[str, Fraction]]:
    """``count`` points of ``box``, log-uniform in each parameter (the gains span decades),
    from a generator seeded by ``seed`` alone (so a box's points do not depend on run order)."""
    import numpy as np

    rng = np.random.default_rng(list(seed))
    out = []
    for _ in range(count):
        point = {}
        for name, lo, hi in box.bounds:
            u = float(rng.random())
            value = Fraction(math.exp(math.log(lo) + u * (math.log(hi) - math.log(lo)))) if lo > 0 else lo
            point[name] = min(max(value, lo), hi)  # rounding of exp/log must not leave the box
        out.append(point)
    return out


def envelope_ratio(problem: Problem, k: float, rate_per_s: float, dynamics: str = "derived") -> float:
    """Largest ``|x(t)| / (k |x0| exp(-rate t))`` over simulated trajectories of the error dynamics.

    The dynamics are those of the point itself (derived from its own gains, not from the box's
    corners), integrated in time scaled by ``|a11|`` from :data:`CROSS_CHECK_RADII` x
    :data:`CROSS_CHECK_ANGLES` starts at ``rtol = 1e-10``. A value above
    ``1 + ENVELOPE_REL_TOL`` means the box's certificate is wrong at this point.
    """
    import numpy as np
    from scipy.integrate import solve_ivp

    from lyapcheck.certification import build_system
    from lyapcheck.conditions.sos import scaled_dynamics

    dyn = scaled_dynamics(build_system(problem, dynamics))
    if dyn is None:
        return math.nan
    c, a, b, ts = float(dyn.c), float(dyn.a), float(dyn.b), float(dyn.time_scale)
    angles = np.linspace(0, 2 * np.pi, CROSS_CHECK_ANGLES, endpoint=False)
    starts = np.array([[r * np.cos(t), r * np.sin(t)] for r in CROSS_CHECK_RADII for t in angles])
    radius = np.linalg.norm(starts, axis=1)

    def field(_tau: float, z: np.ndarray) -> np.ndarray:
        e, r = z[0::2], z[1::2]
        out = np.empty_like(z)
        out[0::2] = -e + c * r
        out[1::2] = -a * r + b * e / (1.0 + (e + r) ** 2)
        return out

    rate_tau = rate_per_s / ts  # the envelope's rate per unit of scaled time tau = |a11| t
    horizon = min(CROSS_CHECK_DECAYS / rate_tau, CROSS_CHECK_MAX_TAU)
    sol = solve_ivp(field, (0.0, horizon), starts.ravel(), method="LSODA", rtol=1e-10,
                    atol=np.repeat(1e-13 * radius, 2))
    if not sol.success:
        return math.inf
    norms = np.hypot(sol.y[0::2], sol.y[1::2])
    envelope = k * radius[:, None] * np.exp(-rate_tau * sol.t)[None, :]
    return float(np.max(norms / envelope))


def cross_check(problem: Problem, box: ParameterBox, result: Mapping[str, Any], count: int,
                seed: Sequence[int], dynamics: str = "derived") -> tuple[int, float]:
    """Simulate ``count`` random points of a certified ``box`` (:func:`sample_points`) against
    its envelope; returns (points simulated, worst :func:`envelope_ratio`)."""
    worst = -math.inf
    points = sample_points(box, count, seed)
    for point in points:
        p = problem_at_point(problem, point)
        worst = max(worst, envelope_ratio(p, float(result["k"]), float(result["decay_rate_per_s"]), dynamics))
    return len(points), (worst if points else math.nan)
