"""A box of parameters on a loop with functions needs the equilibrium to stay put for every value of it
(``f(x_eq, p) = 0``). Ball arithmetic alone cannot see that ``sin(x + p) - sin(p)`` is 0 at ``x = 0`` for every
``p`` (``sin`` of an interval minus ``sin`` of the same interval is an interval around 0), so such a box was
refused (exit 2); the recasting proves it exactly by substitution
(:func:`lyapcheck.models.language.recast.stays_put`), and a box whose equilibrium does move is still refused."""

from __future__ import annotations

import json
from fractions import Fraction
from pathlib import Path

import pytest

from lyapcheck.models.language.modelfile import parse_any_model
from lyapcheck.models.language.recast import recast_with_constants, stays_put
from tests import feature_matrix as fm

SHIFTED_SINE = """[model]
name = "a stable loop through a shifted sine"
states = ["x"]
[parameters]
p = 0
[dynamics]
x = "{rhs}"
[equilibrium]
x = {eq}
[domain]
x = [-2, 2]
"""


def model_text(rhs: str, eq: int = 0) -> str:
    return SHIFTED_SINE.format(rhs=rhs, eq=eq)


@pytest.mark.parametrize("rhs, eq, put", [
    ("-2*x + sin(x + p) - sin(p)", 0, True),
    ("-2*(x - 1) + sin(x - 1 + p) - sin(p)", 1, True),  # (the equilibrium's value is substituted, not 0)
    ("-2*x + p*sin(x) + sat(x + p, 1) - sat(p, 1)", 0, True),
    ("-2*x + sin(x + p)", 0, False),  # f(0, p) = sin(p): the equilibrium moves with p
    ("-2*x + sin(x + p) - sin(2*p)", 0, False),
])
def test_the_equilibrium_is_proved_to_stay_put_exactly_where_it_does(rhs: str, eq: int, put: bool) -> None:
    model = parse_any_model(model_text(rhs, eq))
    assert stays_put(recast_with_constants(model, {"p": Fraction(0)}), ("p",)) is put


def test_a_box_whose_equilibrium_provably_stays_put_is_certified_and_verifies(tmp_path: Path) -> None:
    """The box is taken (it was exit 2): roa holds for every p of it, and verify re-checks the claim."""
    path = tmp_path / "m.toml"
    path.write_text(model_text("-2*x + sin(x + p) - sin(p)"))
    out = tmp_path / "cert.json"
    code, stdout, stderr = fm.cli("certify", str(path), "--box", "p=-0.5..0.5", "--classes", "roa", "--json",
                                  "--out", str(out))
    assert code == 0, stderr
    roa = json.loads(stdout)["conditions"]["roa"]
    assert roa["status"] == "certified" and roa["summary"].startswith("for every p in [-0.5, 0.5]: "), roa["summary"]
    code, stdout, stderr = fm.cli("verify", str(out))
    assert code == 0, stdout + stderr


def test_a_box_whose_equilibrium_moves_is_still_refused_in_one_line(tmp_path: Path) -> None:
    path = tmp_path / "m.toml"
    path.write_text(model_text("-2*x + sin(x + p)"))
    code, stdout, stderr = fm.cli("certify", str(path), "--box", "p=-0.5..0.5", "--classes", "roa")
    assert code == 2
    assert "--box p: the equilibrium is not proved to stay put over the box" in stderr and len(stderr.splitlines()) == 1
