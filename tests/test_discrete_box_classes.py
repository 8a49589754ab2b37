"""``certify --box`` on a polynomial discrete-time map, beyond ``quadratic``/``sos_gas``: a box reaching an unstable
gain refutes ``linearization`` at one of its values (its corners and centre decided exactly,
:func:`lyapcheck.models.classes.discrete_linearization.refute_over_box`), and the region classes over a box.

The refutation is re-checked here independently: sympy's eigenvalues of the test's own map strings at the named
value (a modulus > 1), the value a corner of the box; a forged value (moved inside the stable part of the box, or
out of the box) fails ``verify``.
"""

from __future__ import annotations

import json
from fractions import Fraction
from pathlib import Path
from typing import Any

import numpy as np
import sympy as sp
from click.testing import CliRunner

from lyapcheck.cli import app
from tests.conftest import ROOT

app._register_commands()

#: x+ = a x + 0.4 y, y+ = -0.3 x + 0.6 y: Schur stable for a in [0.3, 0.6], unstable at a = 1.6 (eigenvalue 1.46)
LINEAR = {"x": "a*x + 0.4*y", "y": "-0.3*x + 0.6*y"}
GAIN_MAP = ROOT / "examples" / "models" / "discrete-gain-map.toml"


def model_text(dynamics: dict[str, str], a: float = 0.5, extra: str = "") -> str:
    lines = ["[model]", 'name = "a map with a gain a"', f"states = {list(dynamics)!r}".replace("'", '"'),
             'time = "discrete"', "[parameters]", f"a = {a}", "[dynamics]"]
    lines += [f'{k} = "{v}"' for k, v in dynamics.items()]
    return "\n".join(lines) + "\n" + extra


def write(folder: Path, text: str, name: str = "map.toml") -> Path:
    path = folder / name
    path.write_text(text)
    return path


def cli(*args: str) -> Any:
    done = CliRunner().invoke(app.cli, list(args))
    assert done.exception is None or isinstance(done.exception, SystemExit), done.output
    assert "Traceback" not in done.output
    return done


def certify(path: Path, box: str, *extra: str) -> tuple[int, dict[str, Any]]:
    done = cli("certify", str(path), "--box", box, "--no-store", "--json", *extra)
    return done.exit_code, (json.loads(done.stdout) if done.exit_code in (0, 1) else {})


def verify(doc: dict[str, Any], folder: Path, name: str = "c.json") -> Any:
    path = folder / name
    path.write_text(json.dumps(doc))
    return cli("verify", str(path))


def spectral_radius(dynamics: dict[str, str], value: Fraction) -> float:
    symbols = sp.symbols(list(dynamics))
    a = sp.Symbol("a")
    local = {**dict(zip(dynamics, symbols)), "a": a}
    F = [sp.nsimplify(sp.sympify(v, locals=local), rational=True).subs(a, sp.Rational(value))
         for v in dynamics.values()]
    A = sp.Matrix([[sp.diff(f, s).subs({t: 0 for t in symbols}) for s in symbols] for f in F])
    return max(abs(complex(v)) for v in A.eigenvals())


# -- 1. a box reaching an unstable gain: refuted at a value of the box ---------------------------------------

def test_an_unstable_corner_refutes_linearization_for_the_box_and_verifies(tmp_path: Path) -> None:
    code, doc = certify(write(tmp_path, model_text(LINEAR)), "a=0.5..1.6", "--classes", "linearization")
    assert code == 1 and doc["verdict"] == "unstable"
    lin = doc["conditions"]["linearization"]
    assert lin["status"] == "refuted"
    ref = lin["refutation"]
    assert ref["method"] == "box_point" and ref["time"] == "discrete"
    point = Fraction(ref["point"]["a"])
    assert point in (Fraction(1, 2), Fraction(8, 5), Fraction(21, 20))  # a corner or the centre of the box
    assert spectral_radius(LINEAR, point) > 1  # unstable there, by the test's own map
    assert lin["summary"].startswith(f"at a = {float(point):g}, a value of the box, ")
    done = verify(doc, tmp_path)
    assert done.exit_code == 0 and "certificate verified" in done.output, done.output


def test_a_forged_value_of_the_refutation_fails_verify(tmp_path: Path) -> None:
    code, doc = certify(write(tmp_path, model_text(LINEAR)), "a=0.5..1.6", "--classes", "linearization")
    assert code == 1
    ref = doc["conditions"]["linearization"]["refutation"]
    for forged, why in (("1/2", "at the stated point"), ("17/10", "is not in the box")):
        assert spectral_radius(LINEAR, Fraction(forged)) != spectral_radius(LINEAR, Fraction(ref["point"]["a"]))
        bad = json.loads(json.dumps(doc))
        bad["conditions"]["linearization"]["refutation"]["point"] = {"a": forged}
        done = verify(bad, tmp_path, "forged.json")
        assert done.exit_code != 0 and "FAIL linearization" in done.output and why in done.output, done.output


def test_the_gain_map_example_is_refuted_at_its_unstable_corner(tmp_path: Path) -> None:
    """examples/models/discrete-gain-map.toml with --box a=0.3..1.2, as its comment says: refuted at a = 1.2."""
    assert "--box a=0.3..1.2" in GAIN_MAP.read_text()
    code, doc = certify(GAIN_MAP, "a=0.3..1.2", "--classes", "linearization")
    assert code == 1 and doc["verdict"] == "unstable"
    lin = doc["conditions"]["linearization"]
    assert lin["status"] == "refuted" and lin["refutation"]["point"] == {"a": "6/5"}
    assert spectral_radius({"x": "a*x + 0.1*y**2", "y": "-0.3*x + 0.6*y"}, Fraction(6, 5)) > 1
    assert verify(doc, tmp_path).exit_code == 0


def test_a_stable_box_is_not_refuted(tmp_path: Path) -> None:
    """Every corner and the centre stable: no refutation, the common Stein certificate as before."""
    code, doc = certify(write(tmp_path, model_text(LINEAR)), "a=0.3..0.6", "--classes", "linearization")
    assert code == 0 and doc["conditions"]["linearization"]["status"] == "certified"
    assert doc["conditions"]["linearization"]["certificate"]["method"] == "box_stein"


# -- 2. roa and candidate over a box: one set {V <= c} for every value ----------------------------------------

#: x+ = a x + 0.1 y^2, y+ = -0.3 x + 0.6 y (discrete-gain-map.toml's map): a region of attraction for |a| < 1, no
#: global V (y^2 feeds x)
GAIN = {"x": "a*x + 0.1*y**2", "y": "-0.3*x + 0.6*y"}
DOMAIN = "[domain]\nx = [-1, 1]\ny = [-1, 1]\n"


def gram_poly(symbols: list[sp.Symbol], data: dict[str, Any]) -> sp.Expr:
    """A Gram polynomial of the states alone (its monomials must carry no parameter of the box)."""
    n = len(symbols)
    assert all(not any(m[n:]) for m in data["basis"]), "V must not depend on the box's parameter"
    z = sp.Matrix([sp.Mul(*[s ** e for s, e in zip(symbols, m[:n])]) for m in data["basis"]])
    Q = sp.Matrix([[sp.Rational(x) for x in row] for row in data["Q"]])
    return sp.expand((z.T * Q * z)[0, 0])


def check_region_over_box(dynamics: dict[str, str], cert: dict[str, Any], lo: float, hi: float) -> None:
    """The certified set, re-checked on the test's own map at values spread over the box: V positive definite
    (exact), and from sampled starts in {V <= c} V falls along the map and no iterate leaves the set."""
    symbols = sp.symbols(list(dynamics))
    a = sp.Symbol("a")
    local = {**dict(zip(dynamics, symbols)), "a": a}
    F = [sp.sympify(v, locals=local) for v in dynamics.values()]
    V = gram_poly(symbols, cert["gram_V"])
    assert sp.Matrix([[sp.Rational(x) for x in row] for row in cert["gram_V"]["Q"]]).is_positive_definite
    level = float(Fraction(cert["level"]))
    v = sp.lambdify(symbols, V, "numpy")
    # (a quadratic V here: the set lies in the ball of radius sqrt(level / lambda_min(Q)))
    Q = np.array([[float(Fraction(x)) for x in row] for row in cert["gram_V"]["Q"]])
    reach = float(np.sqrt(level / np.min(np.linalg.eigvalsh(Q))))
    rng = np.random.default_rng(7)
    for value in np.linspace(lo, hi, 5):
        f = sp.lambdify(symbols, [fi.subs(a, value) for fi in F], "numpy")
        e = rng.uniform(-reach, reach, size=(20000, len(symbols)))
        e = e[v(*e.T) <= level][:500]
        assert len(e) > 50
        for _ in range(30):
            nxt = np.array(f(*e.T), dtype=float).T
            assert np.all(v(*nxt.T) <= v(*e.T) * (1 + 1e-9) + 1e-12) and np.all(v(*nxt.T) <= level * (1 + 1e-9))
            e = nxt


def test_roa_over_a_box_is_one_region_for_every_gain_and_verifies(tmp_path: Path) -> None:
    path = write(tmp_path, model_text(GAIN, extra=DOMAIN))
    code, doc = certify(path, "a=0.3..0.6", "--classes", "roa")
    assert code == 0
    roa = doc["conditions"]["roa"]
    assert roa["status"] == "certified" and roa["summary"].startswith("for every a in [0.3, 0.6]: ")
    cert = roa["certificate"]
    assert cert["kind"] == "discrete_sublevel" and cert["box_multipliers"]
    check_region_over_box(GAIN, cert, 0.3, 0.6)
    assert verify(doc, tmp_path).exit_code == 0
    wide = json.loads(json.dumps(doc))
    wide["box"] = {"a": ["3/10", "9/10"]}  # the multipliers hold for [0.3, 0.6] only
    done = verify(wide, tmp_path, "wide.json")
    assert done.exit_code != 0 and "FAIL roa" in done.output and "does not hold exactly" in done.output, done.output


def test_candidate_over_a_box_is_the_users_v_for_every_gain_and_verifies(tmp_path: Path) -> None:
    path = write(tmp_path, model_text(GAIN, extra=DOMAIN))
    code, doc = certify(path, "a=0.3..0.6", "--classes", "candidate", "--candidate", "x**2 + 2*y**2")
    assert code == 0
    cand = doc["conditions"]["candidate"]
    assert cand["status"] == "certified" and cand["summary"].startswith("for every a in [0.3, 0.6]: ")
    x, y = sp.symbols("x y")
    assert sp.expand(gram_poly([x, y], cand["certificate"]["gram_V"]) - (x ** 2 + 2 * y ** 2)) == 0
    check_region_over_box(GAIN, cand["certificate"], 0.3, 0.6)
    assert verify(doc, tmp_path).exit_code == 0
    other = json.loads(json.dumps(doc))
    other["candidate"] = "x**2 + 3*y**2"  # the text must be the certified V
    assert verify(other, tmp_path, "other.json").exit_code != 0


def test_candidate_over_a_box_is_refused_where_it_must_be(tmp_path: Path) -> None:
    # a V naming the box's parameter is not one V for the box: one line, exit 2
    path = write(tmp_path, model_text(GAIN))
    done = cli("certify", str(path), "--box", "a=0.3..0.6", "--candidate", "x**2 + a*y**2", "--no-store")
    assert done.exit_code == 2 and len(done.stderr.splitlines()) == 1
    assert "--candidate" in done.stderr and "parameter a" in done.stderr
    # a continuous loop refuses such a V alike (and takes a V of the states over a box: tests/test_candidate_box.py)
    loop = write(tmp_path, '[model]\nname = "a loop"\nstates = ["x"]\n[parameters]\na = 1\n[dynamics]\nx = "-a*x"\n',
                 "loop.toml")
    done = cli("certify", str(loop), "--box", "a=1..2", "--candidate", "a*x**2", "--no-store")
    assert done.exit_code == 2 and "parameter a" in done.stderr


def test_roa_over_a_box_reaching_an_unstable_gain_is_not_certified(tmp_path: Path) -> None:
    path = write(tmp_path, model_text(GAIN, extra=DOMAIN))
    code, doc = certify(path, "a=0.9..1.1", "--classes", "roa")  # a = 1.1: unstable, a = 1: critical
    assert code == 1 and doc["conditions"]["roa"]["status"] == "not_certified"
    assert "common to the box" in doc["conditions"]["roa"]["summary"]


def test_a_map_s_barrier_over_a_box_is_decided_as_at_a_point(tmp_path: Path) -> None:
    """A polynomial map's barrier is decided over a box too (tests/test_discrete_safety_box.py has the certified
    and refuted boxes): this map's sets get no barrier at its own value, and none over the box either, with the
    same reason, never "not_applicable"."""
    sets = '[sets]\ninitial = ["x**2 + y**2 <= 0.01"]\nunsafe = ["x >= 2"]\n'
    path = write(tmp_path, model_text(GAIN, extra=sets))
    code, doc = certify(path, "a=0.3..0.6", "--classes", "barrier")
    at_point = json.loads(cli("certify", str(path), "--no-store", "--json", "--classes", "barrier").stdout)
    assert code == 1
    assert doc["conditions"]["barrier"]["status"] == at_point["conditions"]["barrier"]["status"] == "not_certified"
    assert "no quadratic or quartic barrier was found" in doc["conditions"]["barrier"]["summary"]


# -- 3. sos_bound over a box: one bound per output for every value and every disturbance sequence ------------

#: x+ = a x + 0.2 y, y+ = 0.6 y + d, |d| <= 1/2: |y| tends to at most 1.25, |x| to at most 0.25 / (1 - a)
DISTURBED = {"x": "a*x + 0.2*y", "y": "0.6*y + d"}
DISTURBANCE = '[disturbances]\nd = 0.5\n[outputs]\nx = "x"\ny = "y"\n'


def test_sos_bound_over_a_box_bounds_every_output_for_every_gain_and_verifies(tmp_path: Path) -> None:
    path = write(tmp_path, model_text(DISTURBED, extra=DISTURBANCE))
    code, doc = certify(path, "a=0.3..0.6", "--classes", "sos_bound")
    assert code == 0
    bound = doc["conditions"]["sos_bound"]
    assert bound["status"] == "certified" and bound["summary"].startswith("for every a in [0.3, 0.6]: ")
    assert set(bound["bounds"]) == {"x", "y"}
    for data in bound["certificate"]["outputs"].values():
        assert all(not any(m[2:]) for _, m in data["V"]["terms"])  # V of the states alone: one V for the box
    # by hand: the worst constant disturbance at the box's top gain reaches |y| = 1.25, |x| = 0.25 / 0.4
    assert bound["bounds"]["y"] >= 1.25 and bound["bounds"]["x"] >= 0.625
    # iterated on the test's own map at gains spread over the box, under random and extreme disturbances
    rng = np.random.default_rng(11)
    for a in np.linspace(0.3, 0.6, 4):
        e = rng.uniform(-5, 5, size=(400, 2))
        for step in range(300):
            d = np.where(rng.random(400) < 0.5, rng.uniform(-0.5, 0.5, 400), np.sign(rng.normal(size=400)) * 0.5)
            e = np.stack([a * e[:, 0] + 0.2 * e[:, 1], 0.6 * e[:, 1] + d], axis=1)
            if step >= 200:
                assert np.all(np.abs(e[:, 0]) <= bound["bounds"]["x"])
                assert np.all(np.abs(e[:, 1]) <= bound["bounds"]["y"])
    assert verify(doc, tmp_path).exit_code == 0
    wide = json.loads(json.dumps(doc))
    wide["box"] = {"a": ["3/10", "9/10"]}  # the multipliers hold for [0.3, 0.6] only
    done = verify(wide, tmp_path, "wide.json")
    assert done.exit_code != 0 and "FAIL sos_bound" in done.output and "does not hold exactly" in done.output, \
        done.output


def test_sos_bound_over_a_box_without_disturbances_is_not_applicable(tmp_path: Path) -> None:
    code, doc = certify(write(tmp_path, model_text(DISTURBED).replace("+ d", "")), "a=0.3..0.6", "--classes",
                        "sos_bound")
    assert doc["conditions"]["sos_bound"]["status"] == "not_applicable"
    assert "no [disturbances]" in doc["conditions"]["sos_bound"]["summary"]
