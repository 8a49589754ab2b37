"""Boxes of a model's parameters: one exact certificate for every value, checked on its claims.

Each certified box is cross-checked at random parameter values of the box, independently of the
certificate's own exact check: the claimed property is tested there (a decay, a bound, a set of
starts that converge). Bad boxes are one-line errors; a box widened after the fact fails verify.
"""

from __future__ import annotations

import copy
from fractions import Fraction
from typing import Any

import numpy as np
import pytest

from lyapcheck.errors import ModelFileError
from lyapcheck.models.loop.boxes import parse_model_box
from lyapcheck.models.surfaces.certificate import build_document, verify_document
from lyapcheck.models.surfaces.certify import certify_model
from lyapcheck.models.language.modelfile import load_model, parse_model
from tests.conftest import ROOT

MODELS = ROOT / "examples" / "models"


def model(dynamics: dict[str, str], parameters: dict[str, str], states: tuple[str, ...] = ("x", "y"),
          extra: str = "") -> Any:
    text = "[model]\nstates = [" + ", ".join(f'"{s}"' for s in states) + "]\n[parameters]\n"
    text += "".join(f"{k} = {v}\n" for k, v in parameters.items()) + extra + "[dynamics]\n"
    text += "".join(f'{k} = "{v}"\n' for k, v in dynamics.items())
    return parse_model(text, "<box test>")


@pytest.mark.parametrize("spec, message", [
    (["a=2..1"], "an empty range"),
    (["a=1..1"], "an empty range"),
    (["b=1..2"], "no parameter named 'b'"),
    (["a=1..2", "a=0..3"], "given twice"),
    (["a=1"], "NAME=LO..HI"),
    (["a=one..2"], "numbers or unit strings"),
])
def test_bad_boxes_are_one_line_errors_naming_the_field(spec: list[str], message: str) -> None:
    m = model({"x": "-a*x + y", "y": "-x - y"}, {"a": "1"})
    with pytest.raises((ModelFileError, ValueError), match=message):
        parse_model_box(m, spec)


def test_a_box_where_the_equilibrium_moves_or_the_model_is_undefined_is_refused() -> None:
    moving = model({"x": "-x + a - 1", "y": "-y"}, {"a": "1"})
    with pytest.raises(ModelFileError, match="equilibrium moves"):
        parse_model_box(moving, ["a=0.5..1.5"])
    undefined = model({"x": "-x/(a - 1)", "y": "-y"}, {"a": "2"})
    with pytest.raises(ModelFileError, match="not defined on the whole box"):
        parse_model_box(undefined, ["a=0.5..1.5"])
    parse_model_box(undefined, ["a=1.5..3"])  # the same model is defined on this box


def test_an_output_divided_by_a_box_parameter_is_a_one_line_error() -> None:
    text = '[model]\nname = "o"\nstates = ["x"]\n[parameters]\na = 1\n[outputs]\ny = "x/a"\n[dynamics]\nx = "-a*x"\n'
    with pytest.raises(ModelFileError, match=r"--box a: output y has a denominator depending on a box parameter"):
        parse_model_box(parse_model(text, "<test>"), ["a=1..2"])


def test_the_command_line_says_so_in_one_line(tmp_path: Any) -> None:
    from click.testing import CliRunner

    from lyapcheck.cli import app

    app._register_commands()
    res = CliRunner().invoke(app.cli, ["certify", "--model", str(MODELS / "van-der-pol-reversed.toml"), "--box",
                                       "mu=1.2..0.8"], standalone_mode=False)
    assert res.exit_code == 2
    lines = res.stderr.strip().splitlines()
    assert len(lines) == 1 and "--box mu" in lines[0] and "empty range" in lines[0]


def test_quadratic_over_a_box_is_ges_at_every_parameter_value() -> None:
    """``x' = -a x + y, y' = -x - y`` for ``a in [0.5, 2]``: one quadratic V for all of it."""
    m = model({"x": "-a*x + y", "y": "-x - y"}, {"a": "1"})
    box = parse_model_box(m, ["a=0.5..2"])
    result = certify_model(m, classes="quadratic", box=box)
    quad = result.results["quadratic"]
    assert quad.status == "certified" and quad.proves() == "GES"
    doc = build_document(result)
    assert doc["box"] == {"a": ["1/2", "2"]} and all(ok for _, ok, _ in verify_document(doc))
    # the claim at random values of the box: |x(t)| <= k |x0| exp(-rate t) for the exact matrix flow
    from scipy.linalg import expm

    k, rate = quad.numbers["k"], quad.numbers["decay_rate_per_s"]
    for a in np.random.default_rng(3).uniform(0.5, 2.0, size=20):
        A = np.array([[-a, 1.0], [-1.0, -1.0]])
        for t in np.linspace(0.0, 10.0, 41):
            assert np.linalg.norm(expm(A * t), 2) <= k * np.exp(-rate * t) * (1 + 1e-9)


def test_a_widened_box_fails_verify() -> None:
    m = model({"x": "-a*x + y", "y": "-x - y"}, {"a": "1"})
    doc = build_document(certify_model(m, classes="quadratic", box=parse_model_box(m, ["a=0.5..2"])))
    wide = copy.deepcopy(doc)
    wide["box"]["a"] = ["1/2", "3"]
    assert not all(ok for _, ok, _ in verify_document(wide))
    narrow = copy.deepcopy(doc)
    narrow["box"]["a"] = ["1", "2"]  # a narrower box changes the normalization too: the file's claim is its box
    assert not all(ok for _, ok, _ in verify_document(narrow))


def test_a_parameter_in_a_denominator_is_proved_positive_on_the_box() -> None:
    m = model({"x": "-x/(k + y**2)", "y": "-y"}, {"k": "1"})
    result = certify_model(m, classes="sos_gas", box=parse_model_box(m, ["k=1..3"]))
    assert result.results["sos_gas"].status == "certified"
    assert result.denominators and result.denominators[0]["kind"] == "sos"
    assert all(ok for _, ok, _ in verify_document(build_document(result)))


def test_sos_bound_over_a_box_never_falls_below_a_worst_case_in_it() -> None:
    """``x' = -a x + d``, ``|d| <= 1``, ``a in [1, 2]``: the worst case at ``a`` is ``1/a``, at most 1."""
    m = model({"x": "-a*x + d"}, {"a": "1"}, states=("x",), extra="[disturbances]\nd = 1\n")
    result = certify_model(m, classes="sos_bound", box=parse_model_box(m, ["a=1..2"]))
    bound = result.results["sos_bound"]
    assert bound.status == "certified"
    assert 1.0 <= bound.numbers["bounds"]["x"] <= 1.5
    assert all(ok for _, ok, _ in verify_document(build_document(result)))


@pytest.mark.slow
def test_a_region_of_attraction_over_a_box_holds_at_random_parameter_values() -> None:
    m = load_model(MODELS / "van-der-pol-reversed.toml")
    box = parse_model_box(m, ["mu=0.9..1.1"])
    result = certify_model(m, classes="roa", box=box)
    roa = result.results["roa"]
    assert roa.status == "certified" and roa.proves() == "ROA"
    doc = build_document(result)
    assert all(ok for _, ok, _ in verify_document(doc))
    # starts inside the certified set converge at random values of mu in the box
    from lyapcheck.models.engines.numeric import converges

    level = float(Fraction(roa.certificate["level"]))
    terms = [(float(Fraction(c)), e) for c, e in roa.certificate["V"]["terms"]]
    rng = np.random.default_rng(11)
    pts = rng.uniform([-2.5, -3.5], [2.5, 3.5], size=(4000, 2))
    V = sum(c * pts[:, 0] ** e[0] * pts[:, 1] ** e[1] for c, e in terms)
    inside = pts[V <= level][:300]
    assert len(inside) > 50
    for mu in box.points(3, seed=5):
        conv = converges(m, inside, t_end=60.0, radius=np.array([1e-3, 1e-3]), escape=np.array([1e3, 1e3]),
                         parameters={**m.parameters, **mu})
        assert conv.converged.all()
