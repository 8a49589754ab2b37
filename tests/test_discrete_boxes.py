"""``certify --box`` on a polynomial discrete-time map: ``linearization``, ``quadratic`` and ``sos_gas`` for every
parameter value of the box (:mod:`lyapcheck.models.classes.discrete_lyapunov`), the other classes
``not_applicable``, the fixed point checked not to move (:func:`lyapcheck.models.loop.boxes.check_box`).

Every certificate is re-checked here independently of the module's exact check: sympy rebuilds ``V`` from the
certificate's Gram matrix (a polynomial of the states alone, one for the whole box) and, at parameter values
spread over the box (its ends included), checks the decrease ``V(e) - V(F(e, a)) - mu V(e)`` on the test's own
map strings: a positive definite quadratic form for a linear map (exactly, by sympy), and positive along random
states for a nonlinear one.
"""

from __future__ import annotations

import json
from fractions import Fraction
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import sympy as sp
from click.testing import CliRunner

from lyapcheck.cli import app
from tests.conftest import ROOT

app._register_commands()

#: x+ = a x + 0.4 y, y+ = -0.3 x + 0.6 y: Schur stable for a in [0.3, 0.6] (spectral radius < 0.72), unstable
#: for a = 1.6 (eigenvalues (2.2 +- sqrt(0.52))/2: 1.46 and 0.74)
LINEAR = {"x": "a*x + 0.4*y", "y": "-0.3*x + 0.6*y"}
#: x+ = a x + 0.2 y^2, y+ = 0.5 y: GAS for |a| < 1, with no global quadratic V (V(F) has degree 4)
TRIANGULAR = {"x": "a*x + 0.2*y**2", "y": "0.5*y"}
GAIN_MAP = ROOT / "examples" / "models" / "discrete-gain-map.toml"


def model_text(dynamics: dict[str, str], a: float = 0.5) -> str:
    lines = ["[model]", 'name = "a map with a gain a"', f"states = {list(dynamics)!r}".replace("'", '"'),
             'time = "discrete"', "[parameters]", f"a = {a}", "[dynamics]"]
    lines += [f'{k} = "{v}"' for k, v in dynamics.items()]
    return "\n".join(lines) + "\n"


def write(folder: Path, text: str, name: str = "map.toml") -> Path:
    path = folder / name
    path.write_text(text)
    return path


def cli(*args: str) -> Any:
    done = CliRunner().invoke(app.cli, list(args))
    assert done.exception is None or isinstance(done.exception, SystemExit), done.output
    assert "Traceback" not in done.output
    return done


def certify(path: Path, box: str, *classes: str) -> tuple[int, dict[str, Any]]:
    args = ["certify", str(path), "--box", box, "--no-store", "--json"]
    for c in classes:
        args += ["--classes", c]
    done = cli(*args)
    return done.exit_code, (json.loads(done.stdout) if done.exit_code in (0, 1) else {})


def verify(doc: dict[str, Any], folder: Path, name: str = "c.json") -> Any:
    path = folder / name
    path.write_text(json.dumps(doc))
    return cli("verify", str(path))


def sympy_map(dynamics: dict[str, str]) -> tuple[list[sp.Symbol], sp.Symbol, list[sp.Expr]]:
    symbols = sp.symbols(list(dynamics))
    a = sp.Symbol("a")
    local = {**dict(zip(dynamics, symbols)), "a": a}
    return list(symbols), a, [sp.nsimplify(sp.sympify(v, locals=local), rational=True) for v in dynamics.values()]


def gram_v(symbols: list[sp.Symbol], data: dict[str, Any]) -> sp.Expr:
    """V from the certificate's Gram matrix; its monomials must carry no parameter (one V for the box)."""
    n = len(symbols)
    assert all(not any(m[n:]) for m in data["basis"]), "V must not depend on the box's parameter"
    z = sp.Matrix([sp.Mul(*[s ** e for s, e in zip(symbols, m[:n])]) for m in data["basis"]])
    Q = sp.Matrix([[sp.Rational(x) for x in row] for row in data["Q"]])
    assert Q.is_positive_definite
    return sp.expand((z.T * Q * z)[0, 0])


def box_values(lo: Fraction, hi: Fraction) -> list[sp.Rational]:
    return [sp.Rational(lo + (hi - lo) * k / 6) for k in range(7)]


def test_a_linear_map_is_ges_and_les_for_every_gain_of_the_box_and_verifies(tmp_path: Path) -> None:
    path = write(tmp_path, model_text(LINEAR))
    code, doc = certify(path, "a=0.3..0.6")
    assert code == 0
    c = doc["conditions"]
    assert doc["box"] == {"a": ["3/10", "3/5"]}
    assert c["quadratic"]["status"] == "certified" and c["quadratic"]["property"] == "GES"
    assert c["sos_gas"]["status"] == "certified" and c["linearization"]["status"] == "certified"
    for name in ("quadratic", "sos_gas", "linearization"):
        assert c[name]["summary"].startswith("for every a in [0.3, 0.6]: "), c[name]["summary"]
    # GAS for every value of the box (quadratic) leaves roa nothing to add, over the box as at a point
    assert c["roa"]["status"] == "not_applicable" and "for every value of the box" in c["roa"]["summary"]
    symbols, a, F = sympy_map(LINEAR)
    for name in ("quadratic", "linearization"):
        cert = c[name]["certificate"]
        V = gram_v(symbols, cert["gram_V"])
        mu = sp.Rational(cert["mu"])
        assert 0 <= mu < 1
        P = sp.hessian(V, symbols) / 2
        for value in box_values(Fraction(3, 10), Fraction(3, 5)):
            A = sp.Matrix([[sp.diff(f.subs(a, value), s) for s in symbols] for f in F])
            assert (P - A.T * P * A - mu * P).is_positive_definite, (name, value)
    # the GES figures hold along iterates at both ends of the box
    k, r = float(Fraction(c["quadratic"]["certificate"]["k"])), float(Fraction(c["quadratic"]["certificate"]["r"]))
    rng = np.random.default_rng(3)
    for value in (0.3, 0.6):
        A = np.array([[value, 0.4], [-0.3, 0.6]])
        e0 = rng.normal(size=(20, 2)) * 5
        e = e0
        for step in range(1, 25):
            e = e @ A.T
            assert np.all(np.linalg.norm(e, axis=1) <= k * np.linalg.norm(e0, axis=1) * r ** step * (1 + 1e-12))
    done = verify(doc, tmp_path)
    assert done.exit_code == 0, done.output


def test_a_nonlinear_map_is_gas_by_sos_for_every_gain_of_the_box(tmp_path: Path) -> None:
    path = write(tmp_path, model_text(TRIANGULAR))
    code, doc = certify(path, "a=0.3..0.6", "quadratic")
    assert code == 1 and doc["conditions"]["quadratic"]["status"] == "not_certified"  # V(F) has degree 4
    code, doc = certify(path, "a=0.3..0.6", "sos_gas")
    assert code == 0
    c = doc["conditions"]
    assert c["sos_gas"]["status"] == "certified" and c["sos_gas"]["property"] == "GAS"
    cert = c["sos_gas"]["certificate"]
    assert cert["box_multipliers"], "a V common to the box needs the box's multipliers"
    symbols, a, F = sympy_map(TRIANGULAR)
    V = gram_v(symbols, cert["gram_V"])
    mu = sp.Rational(cert["mu"])
    rng = np.random.default_rng(5)
    points = rng.normal(size=(200, 2)) * 3
    for value in box_values(Fraction(3, 10), Fraction(3, 5)):
        decrease = sp.lambdify(symbols, V - V.subs(dict(zip(symbols, [f.subs(a, value) for f in F])),
                                                   simultaneous=True) - mu * V, "numpy")
        assert np.all(decrease(*points.T) > 0), value
    assert verify(doc, tmp_path).exit_code == 0


def test_a_widened_box_fails_verify(tmp_path: Path) -> None:
    code, doc = certify(write(tmp_path, model_text(LINEAR)), "a=0.3..0.6")
    assert code == 0
    doc["box"] = {"a": ["3/10", "7/10"]}  # the certificate's identities hold for [0.3, 0.6] only
    done = verify(doc, tmp_path, "wide.json")
    assert done.exit_code != 0
    for name in ("quadratic", "sos_gas"):
        assert f"FAIL {name}: {name}: the identity V - V(F) - mu V = W does not hold exactly" in done.output, \
            done.output
    # A(u) re-derived with the wider box's coordinates is not the stored one
    assert "FAIL linearization: linearization: the stored Jacobian differs from the map's over the box" in done.output


def test_a_box_reaching_an_unstable_gain_does_not_certify(tmp_path: Path) -> None:
    symbols, a, F = sympy_map(LINEAR)
    A = sp.Matrix([[sp.diff(f.subs(a, sp.Rational(8, 5)), s) for s in symbols] for f in F])
    assert max(abs(complex(v)) for v in A.eigenvals()) > 1  # the box's end is unstable
    code, doc = certify(write(tmp_path, model_text(LINEAR)), "a=0.5..1.6")
    assert code == 1
    assert all(c["status"] != "certified" for c in doc["conditions"].values())
    code, doc = certify(GAIN_MAP, "a=0.3..1.2")
    assert code == 1 and all(c["status"] != "certified" for c in doc["conditions"].values())


def test_the_gain_map_example_is_les_for_every_gain_of_its_box(tmp_path: Path) -> None:
    """examples/models/discrete-gain-map.toml, --box a=0.3..0.9 as its comment says: linearization certified for
    every a (one Stein P), quadratic and sos_gas not (the map is not globally stable: y^2 feeds x), roa one
    region for every a (tests/test_discrete_box_classes.py re-checks such a region)."""
    assert "--box a=0.3..0.9" in GAIN_MAP.read_text()
    code, doc = certify(GAIN_MAP, "a=0.3..0.9")
    assert code == 0 and doc["verdict"] == "certified"
    c = doc["conditions"]
    assert c["linearization"]["status"] == "certified" and c["roa"]["status"] == "certified"
    assert c["quadratic"]["status"] == c["sos_gas"]["status"] == "not_certified"
    cert = c["linearization"]["certificate"]
    P = sp.hessian(gram_v(sp.symbols("x y"), cert["gram_V"]), sp.symbols("x y")) / 2
    for value in box_values(Fraction(3, 10), Fraction(9, 10)):
        A = sp.Matrix([[value, 0], [sp.Rational(-3, 10), sp.Rational(3, 5)]])
        assert (P - A.T * P * A).is_positive_definite, value
    assert verify(doc, tmp_path).exit_code == 0


def test_a_moving_fixed_point_is_refused_in_one_line(tmp_path: Path) -> None:
    path = write(tmp_path, model_text({"x": "0.5*x + a - 0.5"}))  # fixed point 2a - 1: 0 only at a = 0.5
    done = cli("certify", str(path), "--box", "a=0.4..0.6", "--no-store")
    assert done.exit_code == 2
    [line] = done.stderr.splitlines()
    assert "--box a" in line and "fixed point moves" in line and "x+ is not x" in line, line
    # a map whose equilibrium is stated and depends on the parameter (the logistic map's 1 - 1/r)
    done = cli("certify", str(ROOT / "examples" / "models" / "discrete-unstable-map.toml"), "--box", "r=3..3.3",
               "--no-store")
    assert done.exit_code == 2 and "fixed point moves" in done.stderr


@pytest.mark.parametrize("box,code", [("a=0.3..0.6", 0), ("a=0.5..1.6", 1), ("b=0.3..0.6", 2), ("a=0.6..0.3", 2)])
def test_cli_exit_codes(tmp_path: Path, box: str, code: int) -> None:
    done = cli("certify", str(write(tmp_path, model_text(LINEAR))), "--box", box, "--classes", "quadratic",
               "--no-store")
    assert done.exit_code == code, done.output
    if code == 2:
        assert len(done.stderr.splitlines()) == 1 and "--box" in done.stderr


def test_a_point_certificate_does_not_verify_as_a_box_one(tmp_path: Path) -> None:
    """A document that states a box must carry the box's certificate: one of the centre alone fails."""
    path = write(tmp_path, model_text(LINEAR, a=0.45))
    done = cli("certify", str(path), "--classes", "quadratic", "--no-store", "--json")
    assert done.exit_code == 0
    doc = json.loads(done.stdout)
    doc["box"] = {"a": ["3/10", "3/5"]}
    doc["conditions"]["quadratic"]["summary"] = "for every a in [0.3, 0.6]: " + doc["conditions"]["quadratic"]["summary"]
    assert verify(doc, tmp_path).exit_code != 0
