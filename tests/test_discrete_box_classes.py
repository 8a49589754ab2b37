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
    F = [sp.nsimplify(sp.sympify(v, locals=local), rational=True).subs(a, sp.Rational(value)) for v in dynamics.values()]
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
