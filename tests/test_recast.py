"""Soundness of the recasting of non-polynomial loops (lyapcheck.models.language.recast).

Every relation the recasting states must hold at every point with the true function values, every
flow must be the true time derivative of its auxiliary, the recast field must be the true field,
the constants of the angle-addition formula must be exact, sat's relations must determine sat, and
every refused file must be refused in one line naming the file, the key and the call.

The true values come from numpy applied to the text the test wrote (an evaluator independent of
the recasting), or from :func:`lyapcheck.models.engines.recast_numeric.variable_values` (numpy applied to
each auxiliary's argument), as each check needs.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import zlib
from fractions import Fraction
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from lyapcheck.errors import ModelFileError
from lyapcheck.models.language.modelfile import parse_any_model, parse_model
from lyapcheck.models.language.recast import RecastModel, RecastSystem, exact_cos_sin
from lyapcheck.models.engines.recast_numeric import poly_values, variable_values
from lyapcheck.sos.polynomials import Poly, Ring

ROOT = Path(__file__).resolve().parents[1]

# -- helpers -------------------------------------------------------------------------------------------


def model_text(dynamics: dict[str, str], *, equilibrium: dict[str, str] | None = None,
               parameters: dict[str, str] | None = None, extra: str = "") -> str:
    states = ", ".join(f'"{s}"' for s in dynamics)
    text = f"[model]\nstates = [{states}]\n"
    if parameters:
        text += "[parameters]\n" + "".join(f"{k} = {v}\n" for k, v in parameters.items())
    text += extra
    text += "[dynamics]\n" + "".join(f'{k} = "{v}"\n' for k, v in dynamics.items())
    if equilibrium:
        text += "[equilibrium]\n" + "".join(f"{k} = {v}\n" for k, v in equilibrium.items())
    return text


def recast(dynamics: dict[str, str], **kw: Any) -> RecastModel:
    m = parse_any_model(model_text(dynamics, **kw), "test.toml")
    assert isinstance(m, RecastModel)
    return m


#: the language's functions in numpy, written independently of lyapcheck.models.engines.recast_numeric
_TRUE: dict[str, Any] = {"sin": np.sin, "cos": np.cos, "exp": np.exp, "sqrt": np.sqrt, "atan": np.arctan,
                         "tanh": np.tanh, "abs": np.abs, "min": np.minimum, "max": np.maximum,
                         "sat": lambda u, L: np.clip(u, -L, L), "pi": np.pi}


def true_eval(text: str, names: dict[str, np.ndarray]) -> np.ndarray:
    """An expression of this file's own models (or an auxiliary's definition) in numpy. Only texts
    this test wrote, or the recasting's definitions of them, are evaluated, without builtins."""
    try:
        with np.errstate(all="ignore"):
            out = eval(text, {"__builtins__": {}}, {**_TRUE, **names})  # noqa: S307 - the test's own texts
    except (NameError, SyntaxError, TypeError) as exc:
        raise AssertionError(f"{text!r} is not an expression over the states: {exc}") from None
    return np.broadcast_to(np.asarray(out, dtype=np.float64), next(iter(names.values())).shape)


def true_field(m: RecastModel, X: np.ndarray) -> np.ndarray:
    names: dict[str, Any] = {s: X[:, i] for i, s in enumerate(m.states)}
    names.update({k: float(v) for k, v in m.parameters.items()})
    return np.stack([true_eval(m.dynamics_text[s], names) for s in m.states], axis=1)


def term_scale(ring: Ring, p: Poly, cols: dict[str, np.ndarray], rows: int) -> np.ndarray:
    """The sum of the absolute values of ``p``'s terms: the size rounding errors are relative to."""
    out = np.zeros(rows)
    for mono, c in ring.float_terms(p).items():
        term = np.full(rows, abs(c))
        for name, k in zip(ring.names, mono):
            if k:
                term = term * np.abs(cols[name]) ** k
        out += term
    return out


def sample(n: int, rng: np.random.Generator, count: int = 2000, big: float = 50.0,
           center: np.ndarray | None = None) -> np.ndarray:
    """Points around the equilibrium: a quarter within 0.5, half within 4, a quarter within ``big``."""
    q = count // 4
    X = np.concatenate([rng.uniform(-0.5, 0.5, (q, n)), rng.uniform(-4, 4, (count - 2 * q, n)),
                        rng.uniform(-big, big, (q, n))])
    X[:5] = 0.0  # the equilibrium itself (and its neighbourhood above)
    return X + (0 if center is None else center)


def equilibrium_of(m: RecastModel) -> np.ndarray:
    return np.array([float(v) for v in m.equilibrium])


# -- the models: every function, alone and nested ------------------------------------------------------

#: (id, dynamics, the model's other tables (parameters, equilibrium), the largest |x| sampled)
CASES: list[tuple[str, dict[str, str], dict[str, Any], float]] = [
    ("sin", {"x1": "-x1 + sin(x2)", "x2": "-x2 - x1**3"}, {}, 50),
    ("cos", {"x1": "-x1 + cos(x2) - 1", "x2": "-x2"}, {}, 50),
    ("sin_cos_same_argument", {"x1": "-x1 + sin(x1 - x2)*cos(x1 - x2)", "x2": "-x2 + cos(x1 - x2) - 1"},
     {}, 50),
    ("sin_pi_over_3", {"x1": "-x1 + sin(x2 + pi/3) - sin(pi/3)", "x2": "-x2"}, {}, 50),
    ("cos_minus_pi_over_4", {"x1": "-x1 + cos(x2 - pi/4) - cos(pi/4)", "x2": "-x2 + sin(x1 + 5*pi/12) - "
                             "sin(5*pi/12)"}, {}, 50),
    ("exp", {"x1": "-x1 + exp(x2) - 1", "x2": "-x2"}, {}, 50),
    ("exp_shifted_equilibrium", {"x1": "-x1 + exp(x2 - 1) - 1", "x2": "1 - x2"}, {"equilibrium": {"x2": "1"}}, 30),
    ("sqrt", {"x1": "-x1 + sqrt(4 + x1**2) - 2", "x2": "-x2"}, {}, 50),
    ("sqrt_two_states", {"x1": "-x1 + x2", "x2": "-x2 - sqrt(x1**2 + x2**2 + 9/4) + 3/2"}, {}, 50),
    ("atan", {"x1": "-x1 + atan(x2)", "x2": "-x2 + atan(x1 - x2)"}, {}, 50),
    ("tanh", {"x1": "-x1 + tanh(x1 + x2)", "x2": "-x2"}, {}, 50),
    ("abs", {"x1": "-x1 + abs(x2)", "x2": "-x2"}, {}, 50),
    ("sat", {"x1": "-x1 + sat(x2, 2)", "x2": "-x2 - sat(x1 + x2, 1/2)"}, {}, 50),
    ("sat_parameter_limit", {"x1": "-x1 + sat(k*x2, L)", "x2": "-x2"}, {"parameters": {"k": "3", "L": "1.5"}}, 50),
    ("min", {"x1": "-x1 + min(x1, x2)", "x2": "-x2"}, {}, 50),
    ("max", {"x1": "-x1", "x2": "-x2 + max(x1, 2*x2)"}, {}, 50),
    ("sat_shifted", {"x1": "-x1 + sat(x2, 1) - 1", "x2": "3 - x2"}, {"equilibrium": {"x2": "3"}}, 50),
    ("nested_sin_exp", {"x1": "-x1 + sin(exp(x2) - 1)", "x2": "-x2"}, {}, 8),
    ("nested_tanh_atan", {"x1": "-x1 + tanh(atan(x2) + x1)", "x2": "-x2"}, {}, 50),
    ("nested_sat_sin", {"x1": "-x1 + sat(sin(x2), 1/2)", "x2": "-x2"}, {}, 50),
    ("nested_sin_sat", {"x1": "-x1 + sin(sat(x2, 1))", "x2": "-x2"}, {}, 50),
    ("nested_abs_of_tanh", {"x1": "-x1 + abs(tanh(x2)) + min(x1, sin(x2))", "x2": "-x2"}, {}, 50),
    ("rational_with_sin", {"x1": "-x1 + x2/(1 + sin(x2)**2)", "x2": "-x2"}, {}, 50),
    ("constant_calls", {"x1": "-x1 + sat(3, 1) + sat(-5/2, 2) + abs(-2) + sqrt(9/4) + exp(0) + atan(0) + tanh(0) "
                        "+ cos(0) + sin(pi/2) + sqrt(8) - 2*sqrt(2) - 11/2 + sin(x2)",
                        "x2": "-x2 + min(x2, x2 + 1) - x2 + max(x1, x1 - 1/2) - x1"}, {}, 50),
]

FUNCTION_OF_CASE = {"sin": "sin", "cos": "cos", "exp": "exp", "sqrt": "sqrt", "atan": "atan", "tanh": "tanh",
                    "abs": "abs", "sat": "sat", "min": "abs", "max": "abs"}


def case_model(case: tuple[str, dict[str, str], dict[str, Any], float]) -> RecastModel:
    return recast(case[1], **case[2])


CASE_IDS = [c[0] for c in CASES]


def test_every_function_is_covered() -> None:
    """The cases make an auxiliary of every function of the language."""
    made = {a.function for case in CASES for a in case_model(case).system.auxiliaries}
    assert made >= {"sin", "cos", "exp", "sqrt", "atan", "tanh", "abs", "sat"}
    for case in CASES:
        s = case_model(case).system
        assert len(set(s.ring.names)) == len(s.ring.names)
        assert s.ring.names[:len(s.states)] == s.states
        for name, function in FUNCTION_OF_CASE.items():
            if case[0] == name:
                assert any(a.function == function for a in s.auxiliaries), case[0]


# -- 1. every relation is true at the true values --------------------------------------------------------


@pytest.mark.parametrize("case", CASES, ids=CASE_IDS)
def test_relations_hold_at_true_values(case: Any) -> None:
    m = case_model(case)
    s = m.system
    rng = np.random.default_rng(zlib.crc32(case[0].encode()))
    X = sample(s.n, rng, big=case[3], center=equilibrium_of(m))
    rows = X.shape[0]
    with np.errstate(all="ignore"):
        cols = variable_values(s, X)
    finite = np.all([np.isfinite(c) for c in cols.values()], axis=0)
    assert finite.mean() > 0.9
    assert s.relations, "a recasting with auxiliaries states relations"
    for r in s.relations:
        with np.errstate(all="ignore"):
            value = poly_values(s.ring, r.poly, cols, rows)
            scale = term_scale(s.ring, r.poly, cols, rows) + 1.0
        ok = finite & np.isfinite(scale)
        assert ok.mean() > 0.9
        value, scale = value[ok], scale[ok]
        if r.kind == "eq":
            worst = np.max(np.abs(value) / scale)
            assert worst <= 1e-9, f"{case[0]}: '{r.why}' ({r.poly} = 0) is off by {worst:.3g} (relative)"
        else:
            assert r.kind == "ge", r.kind
            worst = np.min(value / scale)
            assert worst >= -1e-9, f"{case[0]}: '{r.why}' ({r.poly} >= 0) fails: {worst:.3g} (relative)"


@pytest.mark.parametrize("case", CASES, ids=CASE_IDS)
def test_recast_field_is_the_true_field(case: Any) -> None:
    """The field over the auxiliaries, at the auxiliaries' true values, is the field as written
    (evaluated by numpy from the file's text): the angle-addition constants, min/max and nesting
    are all right."""
    m = case_model(case)
    s = m.system
    rng = np.random.default_rng(1 + zlib.crc32(case[0].encode()))
    X = sample(s.n, rng, big=min(case[3], 20.0), center=equilibrium_of(m))
    rows = X.shape[0]
    with np.errstate(all="ignore"):
        cols = variable_values(s, X)
        truth = true_field(m, X)
    for i, r in enumerate(s.field):
        with np.errstate(all="ignore"):
            num = poly_values(s.ring, r.numerator, cols, rows)
            den = poly_values(s.ring, r.denominator, cols, rows)
            scale = term_scale(s.ring, r.numerator, cols, rows) + np.abs(truth[:, i] * den) + 1.0
        ok = np.isfinite(num) & np.isfinite(den) & np.isfinite(truth[:, i]) & np.isfinite(scale)
        assert ok.mean() > 0.9
        gap = np.abs(num - truth[:, i] * den)[ok] / scale[ok]
        assert gap.max() <= 1e-9, f"{case[0]}: {s.states[i]}' differs from the true field by {gap.max():.3g}"


@pytest.mark.parametrize("case", CASES, ids=CASE_IDS)
def test_definitions_and_equilibrium_values(case: Any) -> None:
    """Each auxiliary's definition (written over the states, as certificates store it) is the
    auxiliary; each value at the equilibrium is the true one, exactly where it is rational."""
    m = case_model(case)
    s = m.system
    rng = np.random.default_rng(2)
    X = sample(s.n, rng, count=400, big=min(case[3], 8.0), center=equilibrium_of(m))
    with np.errstate(all="ignore"):
        cols = variable_values(s, X)
    states = {n: X[:, i] for i, n in enumerate(s.states)}
    for a in s.auxiliaries:
        assert a.name not in s.states
        value = true_eval(a.definition, states)
        ok = np.isfinite(value) & np.isfinite(cols[a.name])
        assert ok.mean() > 0.9
        assert np.allclose(value[ok], cols[a.name][ok], rtol=1e-12, atol=1e-12), (a.name, a.definition)
    at_eq = variable_values(s, equilibrium_of(m)[None, :])
    for a in s.auxiliaries:
        if a.argument is None:
            assert a.name not in s.values and a.name.startswith("rt")
            continue
        assert a.name in s.values and s.values[a.name] == a.value
        assert isinstance(a.value, Fraction)
        assert float(a.value) == pytest.approx(float(at_eq[a.name][0]), abs=1e-15)
    for st, v in zip(s.states, m.equilibrium):
        assert s.values[st] == v


# -- 2. flows --------------------------------------------------------------------------------------------


@pytest.mark.parametrize("case", CASES, ids=CASE_IDS)
def test_flows_are_true_time_derivatives(case: Any) -> None:
    """Each smooth auxiliary's flow is d/dt a(x(t)) = grad a . f along the true field (central
    differences along f); the non-smooth ones (through abs or sat) have none."""
    m = case_model(case)
    s = m.system
    smooth = {a.name for a in s.auxiliaries if a.smooth}
    assert set(s.flows) == smooth
    for a in s.auxiliaries:
        through_kink = "abs(" in a.definition or "sat(" in a.definition
        assert a.smooth == (not through_kink), (a.name, a.definition, a.smooth)
    if not any(a.argument is not None for a in s.auxiliaries if a.smooth):
        return
    rng = np.random.default_rng(3)
    X = sample(s.n, rng, count=600, big=3.0, center=equilibrium_of(m))
    X = X[5:]  # not the equilibrium itself (where every flow is 0 and says nothing)
    rows = X.shape[0]
    f = true_field(m, X)
    speed = np.maximum(1.0, np.linalg.norm(f, axis=1))[:, None]
    h = 1e-5
    step = h * f / speed
    with np.errstate(all="ignore"):
        cols = variable_values(s, X)
        ahead = variable_values(s, X + step)
        behind = variable_values(s, X - step)
    for name in sorted(smooth):
        r = s.flows[name]
        flow = poly_values(s.ring, r.numerator, cols, rows) / poly_values(s.ring, r.denominator, cols, rows)
        fd = (ahead[name] - behind[name]) / (2 * h) * speed[:, 0]
        ok = np.isfinite(flow) & np.isfinite(fd)
        assert ok.mean() > 0.95
        err = np.abs(flow - fd)[ok] / (1.0 + np.abs(fd[ok]))
        assert err.max() <= 1e-5, f"{case[0]}: the flow of {name} is off by {err.max():.3g}: {r.numerator}"
    for a in s.auxiliaries:
        if a.argument is None:  # rt2, rt3: constants
            assert s.flows[a.name].numerator.is_zero()


def test_flows_cover_nested_smooth_functions() -> None:
    """A function of a smooth function is smooth, with the chain rule through both."""
    s = recast({"x1": "-x1 + sin(exp(x2) - 1)", "x2": "-x2"}).system
    assert {a.function for a in s.auxiliaries if a.smooth} == {"exp", "sin", "cos"}
    assert all(a.smooth for a in s.auxiliaries)


# -- 3. exactness ------------------------------------------------------------------------------------------


def test_exact_cos_sin_of_multiples_of_pi_over_12() -> None:
    import sympy

    roots = {1: 1.0, 2: np.sqrt(2.0), 3: np.sqrt(3.0), 6: np.sqrt(6.0)}
    for k in range(-24, 49):
        c, s = exact_cos_sin(k)
        for value, truth, fn in ((c, np.cos(k * np.pi / 12), sympy.cos), (s, np.sin(k * np.pi / 12), sympy.sin)):
            assert set(value) <= {1, 2, 3, 6}
            assert all(isinstance(x, Fraction) and x != 0 for x in value.values())
            assert abs(sum(float(x) * roots[r] for r, x in value.items()) - truth) <= 1e-12, k
            exact = sum(sympy.Rational(x.numerator, x.denominator) * sympy.sqrt(r) for r, x in value.items())
            gap = sympy.N(exact - fn(k * sympy.pi / 12), 60)
            assert abs(gap) < sympy.Float("1e-50"), (k, exact)


def test_pi_over_3_gives_the_root_of_3_exactly() -> None:
    s = recast({"x1": "-x1 + sin(x1 + pi/3) - sin(pi/3)", "x2": "-x2"}).system
    assert "rt3" in s.ring.names and "rt2" not in s.ring.names
    rt3 = s.ring.gen("rt3")
    assert any(r.kind == "eq" and r.poly == rt3 * rt3 - 3 for r in s.relations)
    assert any(r.kind == "ge" and r.poly == rt3 for r in s.relations)
    assert "rt3" in _used(s.ring, s.field[0].numerator), "sqrt(3)/2 is written with the root rt3"
    rt3_aux = next(a for a in s.auxiliaries if a.name == "rt3")
    assert rt3_aux.argument is None and rt3_aux.value is None and "rt3" not in s.values
    # the field is 0 at the equilibrium exactly: reduced modulo rt3^2 = 3, its value there is the zero polynomial
    for r in s.field:
        at_eq = s.ring.substitute(r.numerator, dict(s.values))
        assert s.reduce(at_eq).is_zero()
    # and sqrt(3) is the only value of rt3 consistent with the relations
    for value, holds in ((3 ** 0.5, True), (-(3 ** 0.5), False), (1.732, False)):
        cols = {n: np.zeros(1) for n in s.ring.names}
        cols["rt3"] = np.array([value])
        ok = all(abs(poly_values(s.ring, r.poly, cols, 1)[0]) < 1e-12 if r.kind == "eq"
                 else poly_values(s.ring, r.poly, cols, 1)[0] >= 0
                 for r in s.relations if set(_used(s.ring, r.poly)) == {"rt3"})
        assert ok == holds


def _used(ring: Ring, p: Poly) -> list[str]:
    return [n for i, n in enumerate(ring.names) if any(m[i] for m in ring.terms(p))]


@pytest.mark.parametrize("function", ["sin", "cos"])
def test_every_multiple_of_pi_over_12_is_recast_exactly(function: str) -> None:
    """sin/cos(x2 + k pi/12) - sin/cos(k pi/12), for every k (negative and beyond 2 pi too): the
    recast field is the true one, and the equilibrium is checked exactly over Q(sqrt2, sqrt3)."""
    rng = np.random.default_rng(4)
    X = sample(2, rng, count=200, big=20.0)
    for k in list(range(-13, 26)):
        shift = f"{k}*pi/12"
        m = recast({"x1": f"-x1 + {function}(x2 + {shift}) - {function}({shift})", "x2": "-x2"})
        s = m.system
        assert all(a.argument is None or a.argument == s.ring.gen("x2") for a in s.auxiliaries)
        cols = variable_values(s, X)
        num = poly_values(s.ring, s.field[0].numerator, cols, X.shape[0])
        assert s.field[0].denominator.is_constant()
        num = num / float(s.ring.terms(s.field[0].denominator)[(0,) * s.ring.nvars])
        assert np.allclose(num, true_field(m, X)[:, 0], rtol=1e-12, atol=1e-12), (function, k)


@pytest.mark.parametrize(("rhs", "accepted"), [
    ("-x1 + sin(x2 + pi/4)**2 - 1/2", True),     # (sqrt2/2)^2 = 1/2 exactly
    ("-x1 + sin(x2 + pi/4)**2 - 1/3", False),
    ("-x1 + sin(x2 + pi/12)*cos(x2 + pi/12) - 1/4", True),  # sin(pi/6)/2
    ("-x1 + sin(x2 + pi/12)*cos(x2 + pi/12) - 1/4 + 1e-30", False),
    ("-x1 + sqrt(8) - 2*sqrt(2)", True),
    ("-x1 + sqrt(6) - sqrt(2)*sqrt(3) + sin(x2)", True),
    ("-x1 + sqrt(6) - sqrt(2)*sqrt(3) + 1e-30 + sin(x2)", False),
    ("-x1 + cos(x2)", False),                     # cos(0) = 1: not an equilibrium
])
def test_equilibrium_is_checked_exactly(rhs: str, accepted: bool) -> None:
    text = model_text({"x1": rhs, "x2": "-x2"})
    if accepted:
        m = parse_any_model(text, "eq.toml")
        assert isinstance(m, RecastModel)
        X = np.zeros((1, 2))
        cols = variable_values(m.system, X)
        assert abs(poly_values(m.system.ring, m.system.field[0].numerator, cols, 1)[0]) < 1e-12
    else:
        with pytest.raises(ModelFileError) as info:
            parse_any_model(text, "eq.toml")
        message = str(info.value)
        assert "\n" not in message and message.startswith("eq.toml: [equilibrium]: ")
        assert "x1" in message


# -- 4. sat (and abs) are determined by their relations ---------------------------------------------------


def _sympy_poly(ring: Ring, p: Poly, symbols: dict[str, Any]) -> Any:
    import sympy

    out = sympy.Integer(0)
    for mono, c in ring.terms(p).items():
        term = sympy.Rational(c.numerator, c.denominator)
        for name, k in zip(ring.names, mono):
            if k:
                term = term * symbols[name] ** k
        out += term
    return out


def _exact(ring: Ring, p: Poly, point: dict[str, Fraction]) -> Fraction:
    total = Fraction(0)
    for mono, c in ring.terms(p).items():
        term = c
        for name, k in zip(ring.names, mono):
            if k:
                term *= point[name] ** k
        total += term
    return total


def _sat_system(limit: str, parameters: dict[str, str] | None = None) -> tuple[RecastSystem, str]:
    s = recast({"x1": f"-x1 + sat(x2, {limit})", "x2": "-x2"}, parameters=parameters).system
    (aux,) = [a for a in s.auxiliaries if a.function == "sat"]
    assert aux.argument == s.ring.gen("x2") and aux.limit == 2
    assert len(s.relations) == 3 and not any(a.smooth for a in s.auxiliaries)
    return s, aux.name


@pytest.mark.parametrize(("limit", "parameters"), [("2", None), ("L", {"L": "2"}), ("4/2", None)])
def test_sat_relations_determine_sat(limit: str, parameters: dict[str, str] | None) -> None:
    """For every u of a rational grid, the real q satisfying the equality (solved by sympy) and
    the inequalities is exactly clip(u, -2, 2)."""
    import sympy

    s, q_name = _sat_system(limit, parameters)
    u, q = sympy.symbols("u q", real=True)
    symbols = {n: sympy.Integer(0) for n in s.ring.names} | {"x2": u, q_name: q}
    eqs = [_sympy_poly(s.ring, r.poly, symbols) for r in s.relations if r.kind == "eq"]
    ges = [_sympy_poly(s.ring, r.poly, symbols) for r in s.relations if r.kind == "ge"]
    assert len(eqs) == 1 and len(ges) == 2
    grid = [sympy.Rational(k, 8) for k in range(-48, 49)] + [sympy.Rational(2) + d for d in
                                                           (sympy.Rational(1, 10**9), -sympy.Rational(1, 10**9))]
    grid += [-x for x in grid[-2:]]
    L = sympy.Integer(2)
    for u0 in grid:
        polynomial = sympy.Poly(eqs[0].subs(u, u0), q)
        assert not polynomial.is_zero
        candidates = set(sympy.real_roots(polynomial))
        kept = {c for c in candidates if all(g.subs({u: u0, q: c}) >= 0 for g in ges)}
        assert kept == {sympy.Max(-L, sympy.Min(L, u0))}, (u0, candidates, kept)


def test_sat_relations_on_an_exhaustive_grid() -> None:
    """Every (u, q) of a grid of step 1/8 in [-4, 4]^2, exactly: all three relations hold iff q = clip(u)."""
    s, q_name = _sat_system("2")
    others = {n: Fraction(0) for n in s.ring.names}
    grid = [Fraction(k, 8) for k in range(-32, 33)]
    for u0 in grid:
        clip = max(Fraction(-2), min(Fraction(2), u0))
        for q0 in grid:
            point = others | {"x2": u0, q_name: q0}
            holds = all(_exact(s.ring, r.poly, point) == 0 if r.kind == "eq" else _exact(s.ring, r.poly, point) >= 0
                        for r in s.relations)
            assert holds == (q0 == clip), (u0, q0)


def test_abs_relations_determine_abs() -> None:
    s = recast({"x1": "-x1 + abs(x2)", "x2": "-x2"}).system
    (b,) = [a.name for a in s.auxiliaries]
    grid = [Fraction(k, 4) for k in range(-20, 21)]
    for u0 in grid:
        for b0 in grid:
            point = {"x1": Fraction(0), "x2": u0, b: b0}
            holds = all(_exact(s.ring, r.poly, point) == 0 if r.kind == "eq" else _exact(s.ring, r.poly, point) >= 0
                        for r in s.relations)
            assert holds == (b0 == abs(u0)), (u0, b0)


# -- 5. bad input ------------------------------------------------------------------------------------------


@pytest.mark.parametrize(("rhs", "key", "fragments"), [
    ("-x1 + foo(x1)", "[dynamics] x1", ["foo"]),
    ("-x1 + sin(x1, x2)", "[dynamics] x1", ["sin", "2"]),
    ("-x1 + sat(x1)", "[dynamics] x1", ["sat", "1"]),
    ("-x1 + sat(x1, 0)", "[dynamics] x1", ["sat(x1, 0)", "> 0"]),
    ("-x1 + sat(x1, -1)", "[dynamics] x1", ["sat(x1, -1)", "> 0"]),
    ("-x1 + sat(x1, x2)", "[dynamics] x1", ["sat(x1, x2)", "constant"]),
    ("-x1 + sat(x1, pi)", "[dynamics] x1", ["sat(x1, pi)"]),
    ("-x1 + sin(x1 + 1)", "[dynamics]", ["sin(x1 + 1)", "transcendental"]),
    ("-x1 + exp(x1 - 1/2)", "[dynamics]", ["exp(x1 - 1/2)", "transcendental"]),
    ("-x1 + atan(x1 + 2) - atan(2)", "[dynamics] x1", ["atan(2)", "transcendental"]),
    ("-x1 + exp(1)", "[dynamics] x1", ["exp(1)", "transcendental"]),
    ("-x1 + sin(1) * x1", "[dynamics] x1", ["sin", "transcendental"]),
    ("-pi*x1", "[dynamics] x1", ["pi"]),
    ("-x1 + exp(pi*x1) - 1", "[dynamics] x1", ["exp(pi*x1)", "pi"]),
    ("-x1 + sin(pi*x1)", "[dynamics] x1", ["sin(pi*x1)", "pi"]),
    ("-x1/pi", "[dynamics] x1", ["pi"]),
    ("-x1 + sin(x1 + pi/5)", "[dynamics] x1", ["sin(x1 + pi/5)", "pi/12"]),
    ("-x1 + sin(x1/(1 + x2**2))", "[dynamics] x1", ["sin(x1/(1 + x2**2))", "divides"]),
    ("-x1 + sqrt(2 + x1**2) - 1", "[dynamics]", ["sqrt(2 + x1**2)", "irrational"]),
    ("-x1 + sqrt(x1 - 1)", "[dynamics]", ["sqrt(x1 - 1)", "< 0"]),
    ("-x1 + sqrt(-1)", "[dynamics] x1", ["sqrt(-1)", "negative"]),
    ("-x1 + sqrt(5)", "[dynamics] x1", ["sqrt(5)"]),
    ("-x1 + sin(x=x1)", "[dynamics] x1", ["sin(x=x1)", "positional"]),
])
def test_bad_calls_are_refused_in_one_line(rhs: str, key: str, fragments: list[str]) -> None:
    text = model_text({"x1": rhs, "x2": "-x2"})
    with pytest.raises(ModelFileError) as info:
        parse_any_model(text, "bad.toml")
    message = str(info.value)
    assert "\n" not in message
    assert message.startswith(f"bad.toml: {key}: "), message
    for fragment in fragments:
        assert fragment in message, (fragment, message)


@pytest.mark.parametrize(("extra", "section"), [
    ('[sets]\ninitial = ["x1**2 + x2**2 <= 1"]\nunsafe = ["x1 >= 3"]\ngoal = ["x1**2 <= 1"]\nstay_in_goal = true\n',
     "[sets] stay_in_goal"),
])
def test_sections_not_taken_with_functions_are_refused(extra: str, section: str) -> None:
    text = model_text({"x1": "-x1 + sin(x2)", "x2": "-x2"}, extra=extra)
    with pytest.raises(ModelFileError) as info:
        parse_any_model(text, "dist.toml")
    message = str(info.value)
    # the key is what a loop with functions cannot take yet (its initial, unsafe and goal sets it takes:
    # tests/test_recast_barrier.py, tests/test_recast_reach_avoid.py), and the message says so in one line
    assert "\n" not in message and message.startswith(f"dist.toml: {section}: "), message
    assert "not taken yet" in message
    # without stay_in_goal, the goal is taken (class reach_avoid)
    taken = parse_any_model(text.replace("stay_in_goal = true\n", ""), "dist.toml")
    assert isinstance(taken, RecastModel) and set(taken.sets) == {"initial", "unsafe", "goal"}
    # the same sections are still taken by a polynomial loop
    assert not isinstance(parse_any_model(model_text({"x1": "-x1 + x2", "x2": "-x2"}, extra=extra), "p.toml"),
                          RecastModel)


@pytest.mark.parametrize("name", ["sin", "pi", "sat"])
def test_reserved_names_are_refused(name: str) -> None:
    text = model_text({name: f"-{name}", "x2": "-x2 + sin(x2)"})
    with pytest.raises(ModelFileError) as info:
        parse_any_model(text, "reserved.toml")
    message = str(info.value)
    assert "\n" not in message and f"'{name}'" in message


def test_polynomial_entry_refuses_functions_naming_the_commands(tmp_path: Path) -> None:
    text = model_text({"x1": "-x1 + sin(x2)", "x2": "-x2"})
    with pytest.raises(ModelFileError) as info:
        parse_model(text, "poly.toml")
    message = str(info.value)
    assert "\n" not in message and message.startswith("poly.toml: [dynamics] x1: ")  # the equation that uses it
    assert "sin(x2)" in message and "certify --model" in message and "verify" in message
    # a polynomial loop is still read by the polynomial entry
    assert not isinstance(parse_model(model_text({"x1": "-x1 + x2", "x2": "-x2"}), "p.toml"), RecastModel)
    # the command line: simulate integrates the true loop; a flag it cannot take there exits 2 in one line
    path = tmp_path / "sin.toml"
    path.write_text(text)
    done = subprocess.run([sys.executable, "-m", "lyapcheck", "simulate", "--model", str(path), "--json",
                           "--x0", "x1=1,x2=0.5"], capture_output=True, text=True, cwd=ROOT, timeout=120,
                          env={**os.environ, "COLUMNS": "200"})
    assert done.returncode == 0, done.stderr
    doc = json.loads(done.stdout)
    assert doc["kind"] == "recast" and doc["trajectories"][0]["converged"]
    done = subprocess.run([sys.executable, "-m", "lyapcheck", "simulate", "--model", str(path), "--worst-case"],
                          capture_output=True, text=True, cwd=ROOT, timeout=120, env={**os.environ, "COLUMNS": "200"})
    assert done.returncode == 2 and len(done.stderr.strip().splitlines()) == 1 and "Traceback" not in done.stderr


# -- 6. names ----------------------------------------------------------------------------------------------


def check_names_and_truth(m: RecastModel) -> None:
    """The ring's names are distinct, no auxiliary takes a state's name, and the recast loop is the
    true one (field, definitions, relations) at random points."""
    s = m.system
    assert len(set(s.ring.names)) == len(s.ring.names), s.ring.names
    assert not {a.name for a in s.auxiliaries} & set(s.states)
    rng = np.random.default_rng(5)
    X = sample(s.n, rng, count=300, big=5.0)
    rows = X.shape[0]
    cols = variable_values(s, X)
    truth = true_field(m, X)
    for i, r in enumerate(s.field):
        got = poly_values(s.ring, r.numerator, cols, rows) / poly_values(s.ring, r.denominator, cols, rows)
        assert np.allclose(got, truth[:, i], rtol=1e-10, atol=1e-10), (s.states[i], str(r.numerator))
    states = {n: X[:, i] for i, n in enumerate(s.states)}
    for a in s.auxiliaries:
        assert np.allclose(true_eval(a.definition, states), cols[a.name], rtol=1e-12, atol=1e-12), a.definition
    for rel in s.relations:
        value = poly_values(s.ring, rel.poly, cols, rows)
        scale = term_scale(s.ring, rel.poly, cols, rows) + 1
        assert (np.abs(value) <= 1e-9 * scale).all() if rel.kind == "eq" else (value >= -1e-9 * scale).all(), rel.why


# names that once collided with the recaster's own (fixed: its markers are '#k#' and '#pi#', no
# identifier; a constant root renamed 'rt3_' keeps its radicand): each must give the true loop
@pytest.mark.parametrize("dynamics", [
    pytest.param({"s1": "-s1 + sin(x2)", "x2": "-x2"}, id="state_s1"),
    pytest.param({"c1": "-c1 + sin(x2)", "x2": "-x2 + cos(c1) - 1"}, id="state_c1"),
    pytest.param({"s1": "-s1 + sin(x2)", "s1_": "-s1_ + sin(s1)", "x2": "-x2"}, id="states_s1_and_s1_"),
    pytest.param({"q1": "-q1 + sat(x2, 1)", "b1": "-b1 + min(q1, x2)", "x2": "-x2"}, id="states_q1_b1"),
    pytest.param({"e1": "-e1 + exp(x2) - 1", "r1": "-r1 + sqrt(1 + x2**2) - 1", "x2": "-x2"}, id="states_e1_r1"),
    pytest.param({"rt3": "-rt3 + sin(x2 + pi/3) - sin(pi/3)", "x2": "-x2"}, id="state_rt3"),
    pytest.param({"rt2": "-rt2 + cos(x2 + pi/4) - cos(pi/4)", "x2": "-x2"}, id="state_rt2"),
    pytest.param({"_slot0": "-_slot0", "x2": "-x2 + 2*sin(x2)"}, id="state__slot0"),
    pytest.param({"_pi": "-x2", "x2": "-x2 + sin(x2 + 12*_pi)"}, id="state__pi"),
    pytest.param({"x_slot1": "-x_slot1 + sin(x2) + sin(x_slot1)", "x2": "-x2"}, id="state_x_slot1"),
])
def test_state_names_never_collide_with_auxiliaries(dynamics: dict[str, str]) -> None:
    """Whatever the states are called, the recast loop is the true one, or the file is refused in
    one line (a refusal is sound; a loop with a state mistaken for an auxiliary is not)."""
    try:
        m = recast(dynamics)
    except ModelFileError as exc:
        assert "\n" not in str(exc)
        return
    check_names_and_truth(m)


def test_state_s1_keeps_its_name_and_the_sine_gets_another() -> None:
    m = recast({"s1": "-s1 + sin(x2)", "x2": "-x2"})
    s = m.system
    sine = next(a for a in s.auxiliaries if a.function == "sin")
    cosine = next(a for a in s.auxiliaries if a.function == "cos")
    assert s.states == ("s1", "x2") and sine.name != "s1" and cosine.name != "s1" and sine.name != cosine.name
    assert sine.definition == "sin(x2)" and cosine.definition == "cos(x2)"
    # the field of s1 uses the state s1 and the sine, as two different variables
    used = _used(s.ring, s.field[0].numerator)
    assert set(used) == {"s1", sine.name}
    check_names_and_truth(m)


@pytest.mark.parametrize(("rhs", "name"), [
    ("-x1 + c1", "c1"),
    ("-x1 + s1", "s1"),
    ("-x1 + _slot0", "_slot0"),
    ("-x1 + _slot1*x1", "_slot1"),
    ("-x1 + _pi", "_pi"),
    ("-x1 + rt2*x1", "rt2"),
])
def test_user_text_cannot_name_an_auxiliary(rhs: str, name: str) -> None:
    text = model_text({"x1": rhs, "x2": "-x2 + sin(x2 + pi/4) - sin(pi/4)"})
    with pytest.raises(ModelFileError) as info:
        parse_any_model(text, "names.toml")
    message = str(info.value)
    assert "\n" not in message and message.startswith("names.toml: [dynamics] x1: ")
    assert f"unknown name '{name}'" in message


# -- the recasting is deterministic and shares one auxiliary per argument ---------------------------------


def test_one_auxiliary_per_distinct_argument() -> None:
    """sin and cos of one argument share a pair; the same call twice is one auxiliary; a
    different argument is another."""
    s = recast({"x1": "-x1 + sin(x2)*cos(x2) + sin(x2)", "x2": "-x2 + sin(2*x2) + exp(x2) - exp(x2)"}).system
    by_function: dict[str, list[str]] = {}
    for a in s.auxiliaries:
        by_function.setdefault(a.function, []).append(a.definition)
    assert sorted(by_function["sin"]) == ["sin(2*x2)", "sin(x2)"]
    assert sorted(by_function["cos"]) == ["cos(2*x2)", "cos(x2)"]
    assert by_function["exp"] == ["exp(x2)"]
    again = recast({"x1": "-x1 + sin(x2)*cos(x2) + sin(x2)", "x2": "-x2 + sin(2*x2) + exp(x2) - exp(x2)"}).system
    assert again.ring.names == s.ring.names and again.to_json() == s.to_json()

