"""Simulation scenarios: the paper's Section 5 presets and scenario TOML files.

A scenario TOML is a parameter file (the sections of ``examples/paper.toml``, read by
:func:`lyapcheck.paper.params.problem_from_sources`) plus a ``[simulation]`` table and an optional
``[simulation.disturbance]`` table::

    [simulation]
    controller = "ilos"                  # "ilos" or "los" (conventional LOS, no integral state)
    ods_form = "derived"                 # "derived" or "printed" (eq:ODS2 as printed: diverges)
    initial_position = ["0 mm", "-40 mm"]
    initial_s = "0 m"
    horizon = "100 s"
    tail = "10 s"                        # window [horizon - tail, horizon] of the tail measurements
    band = "0.75 mm"                     # |eps| band of the convergence time (default Delta_LOS)
    d_hat = ["0 mm/s", "0 mm/s"]         # the controller's disturbance estimate (eq:nomCont)
    rtol = 1e-8                          # integrator tolerance, in [2.2e-14, 1e-3] (MIN_RTOL)

    [simulation.disturbance]
    kind = "constant"                    # none | constant | weight | sinusoid | piecewise | adversarial
    velocity = ["0 mm/s", "-0.088 mm/s"] # world frame (x, z), z up

Every value goes through :func:`lyapcheck.paper.params.validate_field` (same units machinery, same
one-line message ``The 'horizon' parameter must be ... Got ... instead.``); a rotation
frequency in Hz becomes an angular velocity in rad/s (factor 2 pi), never 1 Hz = 1 rad/s.
"""

from __future__ import annotations

import math
import sys
from dataclasses import dataclass, field
from fractions import Fraction
from pathlib import Path
from typing import Any, Callable, Final, Mapping, cast

import numpy as np

from lyapcheck.errors import InvalidParameter
from lyapcheck.paper.params import (
    INF, NONNEGATIVE, POSITIVE, FieldSpec, Interval, Problem, build_problem, load_toml,
    problem_from_sources, validate_field,
)
from lyapcheck.paper.simulation.disturbances import (
    ADVERSARIAL_LAYER_FRACTION, Adversarial, Constant, Disturbance, NoDisturbance, PiecewiseConstant,
    Sinusoid, Weight,
)
from lyapcheck.paper.simulation.model import Controller, Form
from lyapcheck.paper.simulation.runner import STEPS_PER_TAIL
from lyapcheck.tolerances import SIM_MAX_STEPS
from lyapcheck.units import Kind

ANY_REAL = Interval(-INF, INF)
#: The smallest integrator tolerance: 100 machine epsilons, scipy's floor for the same reason
#: (solve_ivp raises a smaller rtol to it). Below it the embedded error estimate of a step is
#: rounding noise, and the first-step heuristic divides by a scale that underflows.
MIN_RTOL: Final = 100 * sys.float_info.epsilon
#: the accepted integrator tolerances
RTOL_RANGE: Final = Interval(MIN_RTOL, 1e-3, closed_low=True, closed_high=True)

#: the paper's Section 5 and Table table:micro1 values, with units (same as examples/paper.toml,
#: which a test compares against); strings so that they go through the one validation path
PAPER_VALUES: Final[Mapping[str, object]] = {
    "gains.alpha_d": 600, "gains.sigma0": "0.01", "gains.k_d": "0.15", "gains.delta_los": "0.75 mm",
    "gains.los_speed": "1 m/s",
    "swimmer.e11": "9.3e-5 m", "swimmer.e11_hat": "1 m", "swimmer.n_turns": "3.5",
    "swimmer.pitch_angle": "45 deg", "swimmer.helix_radius": "420 um", "swimmer.weight": "8.7e-5 N",
    "actuation.omega_so": "2.8 Hz", "actuation.omega_0": "1 Hz",
    "path.theta_r": "0 deg", "disturbance.d_max": "0.088 mm/s",
}

#: The disturbance inferred from the paper's reported numbers (docs/simulation.md): a constant
#: sinking velocity. The 1-D least-squares fit of the five reported numbers gives
#: 0.0880 mm/s (:func:`lyapcheck.paper.simulation.inference.fit_paper_disturbance`), rounded to the
#: two digits the paper's numbers carry.
PAPER_DISTURBANCE: Final = ("0 mm/s", "-0.088 mm/s")
PAPER_DISTURBANCE_NOTE: Final = (
    "inferred: constant sinking velocity 0.088 mm/s, the 1-D least-squares fit of the five numbers "
    "reported in Section 5 (docs/simulation.md); the paper does not state its disturbance")

#: numbers reported in Section 5 (SI); the rotation of the conventional law is the alpha_d = 1200 case
PAPER_REPORTED: Final[Mapping[str, Mapping[str, float]]] = {
    "paper-ilos": {"mean_abs_eps_tail_m": 0.09e-3, "steady_rotation_hz": 0.17},
    "paper-los-600": {"mean_abs_eps_tail_m": 1.8e-3},
    "paper-los-1200": {"mean_abs_eps_tail_m": 0.79e-3, "steady_rotation_hz": 0.21},
}

PRESETS: Final = ("paper-ilos", "paper-los-600", "paper-los-1200")
_PRESET_SETUP: Final[Mapping[str, tuple[str, int]]] = {
    "paper-ilos": ("ilos", 600), "paper-los-600": ("los", 600), "paper-los-1200": ("los", 1200),
}

CONTROLLERS: Final = ("ilos", "los")
FORMS: Final = ("derived", "printed")
DISTURBANCE_KINDS: Final = ("none", "constant", "weight", "sinusoid", "piecewise", "adversarial")


@dataclass(frozen=True)
class DisturbanceSpec:
    """A validated disturbance description (SI floats), turned into a batch by :meth:`build`."""

    kind: str
    values: Mapping[str, Any] = field(default_factory=dict)
    note: str = ""

    def build(self, problem: Problem, *, n: int = 1, horizon: float = 100.0) -> Disturbance:
        """The :class:`Disturbance` for ``n`` identical trajectories of ``problem``."""
        v = self.values
        theta_r = float(problem.theta_r)
        if self.kind == "none":
            return NoDisturbance()
        if self.kind == "constant":
            return Constant(np.asarray(v["velocity"], dtype=float), note=self.note)
        if self.kind == "weight":
            return weight_disturbance(problem, xi_par=v.get("xi_par"), xi_perp=v.get("xi_perp"), note=self.note)
        if self.kind == "sinusoid":
            return Sinusoid(np.asarray(v["offset"]), np.asarray(v["amplitude"]), np.asarray(v["angular_frequency"]),
                            np.asarray(v["phase"]))
        if self.kind == "piecewise":
            return PiecewiseConstant.draw(n=n, bound=v["bound"], hold=v["hold"], horizon=horizon, seed=v["seed"])
        if self.kind == "adversarial":
            return Adversarial(np.asarray(v["bound"]), np.asarray(v["P"]), np.asarray(v["layer"]), np.asarray(theta_r))
        raise InvalidParameter("kind", "one of " + ", ".join(repr(k) for k in DISTURBANCE_KINDS), self.kind)


@dataclass(frozen=True)
class Scenario:
    """One closed-loop simulation, validated, SI."""

    name: str
    problem: Problem
    controller: Controller = "ilos"
    form: Form = "derived"
    p0: tuple[float, float] = (0.0, -0.040)
    s0: float = 0.0
    horizon: float = 100.0
    tail: float = 10.0
    band: float | None = None
    d_hat: tuple[float, float] = (0.0, 0.0)
    rtol: float = 1e-8
    disturbance: DisturbanceSpec = field(default_factory=lambda: DisturbanceSpec("none"))
    #: numbers the paper reports for this scenario (presets only)
    reported: Mapping[str, float] = field(default_factory=dict)

    @property
    def alpha_d(self) -> float:
        return float(self.problem.gains.alpha_d)


# -- validation helpers (one message template: lyapcheck.errors.InvalidParameter) ---------------
def _spec(name: str, kind: Kind, interval: Interval, default: object | None, text: str) -> FieldSpec:
    return FieldSpec("simulation", name, kind, interval, default, text)


SIMULATION_FIELDS: Final[Mapping[str, FieldSpec]] = {
    s.name: s for s in (
        _spec("initial_s", Kind.LENGTH, ANY_REAL, "0 m", "initial integral state s(0)"),
        _spec("horizon", Kind.TIME, POSITIVE, "100 s", "simulated time"),
        _spec("tail", Kind.TIME, POSITIVE, "10 s", "length of the final measurement window"),
        _spec("band", Kind.LENGTH, POSITIVE, None, "band of |eps| for the convergence time"),
        _spec("rtol", Kind.DIMENSIONLESS, RTOL_RANGE, "1e-8", "integrator tolerance"),
    )
}
_VECTOR_FIELDS: Final[Mapping[str, tuple[Kind, object]]] = {
    "initial_position": (Kind.LENGTH, ("0 mm", "-40 mm")),
    "d_hat": (Kind.VELOCITY, ("0 m/s", "0 m/s")),
}
_CHOICE_FIELDS: Final[Mapping[str, tuple[tuple[str, ...], str]]] = {
    "controller": (CONTROLLERS, "ilos"),
    "ods_form": (FORMS, "derived"),
}
_DISTURBANCE_FIELDS: Final[Mapping[str, Mapping[str, tuple[str, Kind, Interval, object | None]]]] = {
    "none": {},
    "constant": {"velocity": ("vector", Kind.VELOCITY, ANY_REAL, None)},
    "weight": {"xi_par": ("scalar", Kind.DRAG_PER_LENGTH, POSITIVE, None),
               "xi_perp": ("scalar", Kind.DRAG_PER_LENGTH, POSITIVE, None)},
    "sinusoid": {"offset": ("vector", Kind.VELOCITY, ANY_REAL, ("0 m/s", "0 m/s")),
                 "amplitude": ("vector", Kind.VELOCITY, ANY_REAL, None),
                 "frequency": ("scalar", Kind.ROTATION, POSITIVE, None),
                 "phase": ("scalar", Kind.ANGLE, ANY_REAL, "0 rad")},
    "piecewise": {"bound": ("scalar", Kind.VELOCITY, NONNEGATIVE, None),
                  "hold": ("scalar", Kind.TIME, POSITIVE, None),
                  "seed": ("integer", Kind.DIMENSIONLESS, NONNEGATIVE, 0)},
    "adversarial": {"bound": ("scalar", Kind.VELOCITY, NONNEGATIVE, None),
                    "P": ("matrix", Kind.DIMENSIONLESS, ANY_REAL, None),
                    "layer": ("scalar", Kind.LENGTH, POSITIVE, None)},
}


def _validate(spec: FieldSpec, raw: object) -> Fraction:
    """:func:`lyapcheck.paper.params.validate_field`, with any stray units-library error mapped to the
    same one-line message (pint raises DimensionalityError for, e.g., "2 rad" as a rotation)."""
    try:
        return validate_field(spec, raw)
    except InvalidParameter:
        raise
    except Exception:
        raise InvalidParameter(spec.name, spec.kind.example, raw) from None


def _scalar(name: str, kind: Kind, interval: Interval, raw: object) -> float:
    return float(_validate(FieldSpec("simulation", name, kind, interval, None, name), raw))


def _vector(name: str, kind: Kind, interval: Interval, raw: object) -> tuple[float, float]:
    if not isinstance(raw, (list, tuple)) or len(raw) != 2:
        raise InvalidParameter(name, f"a list of two values ({kind.example} each)", raw)
    return (_scalar(name, kind, interval, raw[0]), _scalar(name, kind, interval, raw[1]))


def _matrix(name: str, raw: object) -> list[list[float]]:
    ok = isinstance(raw, (list, tuple)) and len(raw) == 2 and all(
        isinstance(r, (list, tuple)) and len(r) == 2 for r in raw)
    if not ok:
        raise InvalidParameter(name, "a 2x2 list of numbers [[p11, p12], [p12, p22]]", raw)
    rows: list[Any] = list(raw)  # type: ignore[call-overload]
    P = [[_scalar(name, Kind.DIMENSIONLESS, ANY_REAL, x) for x in row] for row in rows]
    arr = np.asarray(P)
    if arr[0, 1] != arr[1, 0] or arr[0, 0] <= 0 or np.linalg.det(arr) <= 0:
        raise InvalidParameter(name, "a symmetric positive definite 2x2 matrix", raw)
    return P


def _integer(name: str, raw: object) -> int:
    if isinstance(raw, bool) or not isinstance(raw, int) or raw < 0:
        raise InvalidParameter(name, "an integer in [0, inf)", raw)
    return raw


def _choice(name: str, options: tuple[str, ...], raw: object) -> str:
    if raw not in options:
        raise InvalidParameter(name, "one of " + ", ".join(repr(o) for o in options), raw)
    return str(raw)


def parse_disturbance(table: object, problem: Problem) -> DisturbanceSpec:
    """Validate a ``[simulation.disturbance]`` table."""
    if not isinstance(table, Mapping):
        raise InvalidParameter("disturbance", "a table with a 'kind' key", table)
    kind = _choice("kind", DISTURBANCE_KINDS, table.get("kind"))
    known = _DISTURBANCE_FIELDS[kind]
    for key in table:
        if key not in ("kind", "note") and key not in known:
            allowed = ", ".join(["kind", "note", *known])
            raise InvalidParameter(f"disturbance.{key}", f"a known key for kind '{kind}' ({allowed})", key)
    values: dict[str, Any] = {}
    for key, (shape, kind_, interval, default) in known.items():
        raw = table.get(key, default)
        if raw is None:
            if kind == "weight":
                continue  # drag coefficients may come from [swimmer]; checked in weight_disturbance
            if kind == "adversarial" and key == "bound":
                values["bound"] = float(problem.disturbance_bound())
                continue
            if kind == "adversarial" and key == "layer":
                values["layer"] = ADVERSARIAL_LAYER_FRACTION * float(problem.gains.delta_los)
                continue
            raise InvalidParameter(key, f"given for a '{kind}' disturbance ({kind_.example})", None)
        if shape == "scalar":
            values[key] = _scalar(key, kind_, interval, raw)
        elif shape == "vector":
            values[key] = _vector(key, kind_, interval, raw)
        elif shape == "matrix":
            values[key] = _matrix(key, raw)
        else:
            values[key] = _integer(key, raw)
    if kind == "sinusoid":
        values["angular_frequency"] = values.pop("frequency")
    if kind == "weight":
        # fail now, naming the field, rather than at the first evaluation
        weight_disturbance(problem, xi_par=values.get("xi_par"), xi_perp=values.get("xi_perp"))
    return DisturbanceSpec(kind, values, note=str(table.get("note", "")))


def weight_disturbance(problem: Problem, *, xi_par: float | None = None, xi_perp: float | None = None,
                       note: str = "") -> Weight:
    """The weight mapped through ``D`` (eq:tmp3) for the swimmer of ``problem``.

    ``xi_par`` is required (argument or ``[swimmer] xi_par``). ``xi_perp``, when not given, is
    the value for which the RFT constants reproduce the swimmer's ``e11`` (eq:e11): the helix
    geometry and ``e11`` fix ``xi_perp / xi_par``, so the weight model has one free scale.
    """
    from symbolic.rft import rft_constants

    sw = problem.swimmer
    need = {"n_turns": sw.n_turns, "pitch_angle": sw.pitch_angle, "helix_radius": sw.helix_radius,
            "weight": sw.weight}
    given: dict[str, float] = {}
    for name, value in need.items():
        if value is None:
            raise InvalidParameter(name, "given in [swimmer] for a 'weight' disturbance", None)
        given[name] = float(value)
    par = xi_par if xi_par is not None else (float(sw.xi_par) if sw.xi_par is not None else None)
    if par is None:
        raise InvalidParameter("xi_par", "given ([swimmer] or [simulation.disturbance]) for a 'weight' disturbance", None)
    perp = xi_perp if xi_perp is not None else (float(sw.xi_perp) if sw.xi_perp is not None else None)
    geometry = dict(n_turns=given["n_turns"], pitch_angle=given["pitch_angle"], helix_radius=given["helix_radius"],
                    xi_head=float(sw.xi_head), head_offset=float(sw.head_offset))
    if perp is None:
        perp = par * drag_ratio_for_e11(float(sw.e11), **geometry)
    consts = rft_constants(xi_par=par, xi_perp=perp, **geometry)
    details = {"xi_par_n_s_per_m2": par, "xi_perp_n_s_per_m2": perp, "e11_from_rft_m": consts["e11"]}
    return Weight(np.asarray(given["weight"]), np.asarray(consts["a1"]), np.asarray(consts["a2"]),
                  np.asarray(float(problem.theta_r)), note=note, details=details)


def drag_ratio_for_e11(e11: float, **geometry: float) -> float:
    """``xi_perp / xi_par`` for which the RFT ``e11`` (eq:e11) equals ``e11``.

    Solved with a bracketing root finder on :func:`symbolic.rft.rft_constants` (no re-typed
    formula). ``e11`` depends on the drag coefficients only through their ratio when there is no
    head; with a head the ratio is solved at ``xi_par = 1`` N s/m^2 and is then approximate.
    """
    from scipy.optimize import brentq

    from symbolic.rft import rft_constants

    def gap(ratio: float) -> float:
        return rft_constants(xi_par=1.0, xi_perp=ratio, **geometry)["e11"] - e11

    lo, hi = 1.0 + 1e-12, 2.0
    while gap(hi) < 0:
        hi *= 2
        if hi > 1e6:
            raise InvalidParameter("e11", "reachable by the helix geometry with xi_perp > xi_par", e11)
    return float(brentq(gap, lo, hi, xtol=1e-15, rtol=1e-15))


def parse_simulation(table: object, problem: Problem, name: str) -> Scenario:
    """Validate a ``[simulation]`` table into a :class:`Scenario` (with ``problem``)."""
    if table is None:
        table = {}
    if not isinstance(table, Mapping):
        raise InvalidParameter("simulation", "a table", table)
    known = {*SIMULATION_FIELDS, *_VECTOR_FIELDS, *_CHOICE_FIELDS, "disturbance"}
    for key in table:
        if key not in known:
            raise InvalidParameter(f"simulation.{key}", f"a known key of [simulation] ({', '.join(sorted(known))})", key)
    scal = {k: table.get(k, spec.default) for k, spec in SIMULATION_FIELDS.items()}
    parsed = {k: (None if raw is None else float(_validate(SIMULATION_FIELDS[k], raw))) for k, raw in scal.items()}
    vec = {k: _vector(k, kind, ANY_REAL, table.get(k, default)) for k, (kind, default) in _VECTOR_FIELDS.items()}
    choice = {k: _choice(k, opts, table.get(k, default)) for k, (opts, default) in _CHOICE_FIELDS.items()}
    if parsed["tail"] > parsed["horizon"]:  # type: ignore[operator]
        raise InvalidParameter("tail", f"at most the horizon ({parsed['horizon']:g} s)", table.get("tail"))
    # the largest step is tail / STEPS_PER_TAIL: a tail so short that even the smoothest run needs
    # more steps than the budget could only end in "step budget exhausted"; say so now, for free
    min_tail = parsed["horizon"] * STEPS_PER_TAIL / SIM_MAX_STEPS  # type: ignore[operator]
    if parsed["tail"] < min_tail:  # type: ignore[operator]
        raise InvalidParameter("tail", f"at least horizon * {STEPS_PER_TAIL} / {SIM_MAX_STEPS} = {min_tail:.6g} s (a "
                               f"step is at most tail / {STEPS_PER_TAIL} and a run at most {SIM_MAX_STEPS} steps, "
                               "lyapcheck.tolerances.SIM_MAX_STEPS)", table.get("tail"))
    dist = parse_disturbance(table["disturbance"], problem) if "disturbance" in table else DisturbanceSpec("none")
    return Scenario(
        name=name, problem=problem, controller=cast(Controller, choice["controller"]),
        form=cast(Form, choice["ods_form"]),
        p0=vec["initial_position"], s0=parsed["initial_s"] or 0.0, horizon=parsed["horizon"],  # type: ignore[arg-type]
        tail=parsed["tail"], band=parsed["band"], d_hat=vec["d_hat"], rtol=parsed["rtol"],  # type: ignore[arg-type]
        disturbance=dist,
    )


def load_scenario(path: str | Path) -> Scenario:
    """Read and validate a scenario TOML (parameter sections + ``[simulation]``)."""
    problem = problem_from_sources(path, {})
    data = load_toml(path)
    return parse_simulation(data.get("simulation"), problem, name=str(path))


def paper_problem(**overrides: object) -> Problem:
    """The paper's parameters (:data:`PAPER_VALUES`) through the one validation path."""
    values = dict(PAPER_VALUES)
    values.update(overrides)
    return build_problem(values, source="the paper's Section 5 values")


def paper_disturbance() -> DisturbanceSpec:
    """The presets' default disturbance (see :data:`PAPER_DISTURBANCE`)."""
    vx, vz = (_scalar("velocity", Kind.VELOCITY, ANY_REAL, c) for c in PAPER_DISTURBANCE)
    return DisturbanceSpec("constant", {"velocity": (vx, vz)}, note=PAPER_DISTURBANCE_NOTE)


def preset(name: str) -> Scenario:
    """One of :data:`PRESETS`: the paper's Section 5 simulations with the inferred disturbance."""
    if name not in _PRESET_SETUP:
        raise InvalidParameter("preset", "one of " + ", ".join(repr(p) for p in PRESETS), name)
    controller, alpha = _PRESET_SETUP[name]
    problem = paper_problem(**{"gains.alpha_d": alpha})
    return Scenario(name=name, problem=problem, controller=cast(Controller, controller), form="derived",
                    p0=(0.0, -0.040), horizon=100.0, tail=10.0, disturbance=paper_disturbance(),
                    reported=PAPER_REPORTED[name])


def problem_summary(problem: Problem) -> dict[str, Any]:
    """The parameters of a problem, JSON-ready, SI with units in the key names."""
    g, sw, act = problem.gains, problem.swimmer, problem.actuation
    two_pi = 2 * math.pi
    f: Callable[[Fraction], float] = float
    return {
        "alpha_d_1_s": f(g.alpha_d), "sigma0": f(g.sigma0), "k_d_1_s": f(g.k_d), "delta_los_m": f(g.delta_los),
        "los_speed_m_s": f(g.los_speed), "e11_m": f(sw.e11), "e11_hat_m": f(sw.e11_hat),
        "omega_so_rad_s": f(act.step_out()), "omega_so_hz": f(act.step_out()) / two_pi,
        "omega_0_rad_s": f(act.omega_0), "omega_0_hz": f(act.omega_0) / two_pi,
        "theta_r_rad": f(problem.theta_r),
    }
