"""The size of a certified region (lyapcheck.models.classes.region_size): exact figures on sets whose
ball and axis reach are known by hand, soundness on a loop with functions, verify's re-derivation
(a forged figure is refused), and the report's slices."""

from __future__ import annotations

import copy
import math
from fractions import Fraction
from pathlib import Path

import numpy as np
import pytest

from lyapcheck.exact import floor_digits, sqrt_lower
from lyapcheck.models.classes.region_size import SIZE_DIGITS, Extra, extras_of, region_size
from lyapcheck.roots import first_positive_root

F = Fraction
EXAMPLES = Path(__file__).resolve().parent.parent / "examples" / "models"

#: a polynomial loop whose roa certifies in about 3 s: x1' = -x1 + x1^3 (region of attraction |x1| < 1)
TWO_STATES = """
[model]
name = "two states, bounded region of attraction"
states = ["x1", "x2"]

[dynamics]
x1 = "-x1 + x1**3"
x2 = "-2*x2"

[domain]
x1 = [-1.5, 1.5]
x2 = [-1.5, 1.5]
"""


def value(V: dict[tuple[int, ...], Fraction], x: tuple[Fraction, ...]) -> Fraction:
    return sum((c * math.prod(xi ** e for xi, e in zip(x, m)) for m, c in V.items()), F(0))


def test_sqrt_lower_and_floor_digits_are_lower_bounds() -> None:
    for q in (F(2), F(1, 3), F(10**12 + 1, 7), F(4)):
        r = sqrt_lower(q)
        assert r * r <= q and float(r) == pytest.approx(math.sqrt(q), rel=1e-25)
        d = floor_digits(r, 6)
        assert d <= r and float(r - d) <= float(r) * 1e-5
    assert sqrt_lower(F(9, 4)) <= F(3, 2)


def test_first_positive_root_brackets_the_first_sign_change() -> None:
    # (t - 1)^2 (t - 3): the double root 1 comes first (no sign change, still the first root)
    lo, hi = first_positive_root([F(-3), F(7), F(-5), F(1)])
    assert 0 < lo <= 1 <= hi and hi - lo <= hi / 2**40
    lo, hi = first_positive_root([F(-2), F(0), F(1)])  # sqrt 2, irrational: a strict bracket
    assert lo ** 2 < 2 < hi ** 2 and hi - lo <= hi / 2**40
    lo, hi = first_positive_root([F(6), F(-5), F(1)])  # 2 before 3
    assert lo <= 2 <= hi < 3
    assert first_positive_root([F(1), F(0), F(1)]) is None  # t^2 + 1: no real root


def test_axis_aligned_ellipse_by_hand() -> None:
    """V = x1^2 + 4 x2^2, level 4: the ball of radius 1 (the short half-axis) and the half-axes 2, 1."""
    V = {(2, 0): F(1), (0, 2): F(4)}
    size = region_size(V, F(4), ["x1", "x2"])
    assert size.ball_mu is not None and 4 <= size.ball_mu <= 4 * (1 + 1e-8)
    assert size.ball_radius is not None and size.ball_radius <= 1 and float(size.ball_radius) == pytest.approx(1, abs=1e-8)
    assert size.ball_radius ** 2 * size.ball_mu <= 4  # in the set: V <= mu r^2 <= level
    a1, a2 = size.axis_extents["x1"], size.axis_extents["x2"]
    assert a1 <= 2 and float(a1) == pytest.approx(2, rel=1e-9)
    assert a2 <= 1 and float(a2) == pytest.approx(1, rel=1e-9)
    assert len(str(a1.numerator)) <= SIZE_DIGITS + 1  # rounded down, written short


def test_rotated_ellipse_by_hand() -> None:
    """V = 2x^2 + 2xy + 2y^2 (eigenvalues 1 and 3), level 3: the ball of radius 1; along x: 2t^2 = 3."""
    V = {(2, 0): F(2), (1, 1): F(2), (0, 2): F(2)}
    size = region_size(V, F(3), ["x", "y"])
    assert float(size.ball_radius) == pytest.approx(1, abs=1e-8) and size.ball_radius <= 1
    for s in ("x", "y"):
        a = size.axis_extents[s]
        assert 2 * a * a <= 3 and float(a) == pytest.approx(math.sqrt(1.5), rel=1e-9)


def test_quartic_by_hand_and_box_cap() -> None:
    """V = x^2 + x^4 + y^2, level 2: along x t^2 + t^4 = 2 at t = 1; the ball: r^2 + r^4 = 2 too."""
    V = {(2, 0): F(1), (4, 0): F(1), (0, 2): F(1)}
    size = region_size(V, F(2), ["x", "y"])
    assert float(size.axis_extents["x"]) == pytest.approx(1, rel=1e-9) and size.axis_extents["x"] < 1
    assert float(size.axis_extents["y"]) == pytest.approx(math.sqrt(2), rel=1e-9)
    assert float(size.ball_radius) == pytest.approx(1, rel=1e-8)
    boxed = region_size(V, F(2), ["x", "y"], box={"x": (F(-1, 2), F(3, 4)), "y": (F(-2), F(2))})
    assert boxed.axis_extents["x"] == F(1, 2) and boxed.ball_radius == F(1, 2)


def test_ball_of_a_mixed_quartic_is_tight() -> None:
    """V = x^2 + y^2 + x^2 y^2, level 2: on the circle of radius r, V peaks at x = y with r^2 + r^4 / 4,
    so the largest ball has r^2 = 2 sqrt(3) - 2 (the monomial's peak 1/4 on the unit sphere, not 1)."""
    V = {(2, 0): F(1), (0, 2): F(1), (2, 2): F(1)}
    size = region_size(V, F(2), ["x", "y"])
    r = size.ball_radius
    assert float(r) == pytest.approx(math.sqrt(2 * math.sqrt(3) - 2), rel=1e-8)
    assert value(V, (r / 2 ** 0.5, r / 2 ** 0.5)) <= 2 + 1e-12


def test_axis_reach_is_not_the_projection() -> None:
    """V = (y - x^2)^2 + x^2 (level 1): along x the set reaches 1 exactly, though it spans more of x elsewhere."""
    V = {(0, 2): F(1), (2, 1): F(-2), (4, 0): F(1), (2, 0): F(1)}
    size = region_size(V, F(1), ["x", "y"])
    a = size.axis_extents["x"]
    assert value(V, (a, F(0))) <= 1 and float(a) == pytest.approx(((5 ** 0.5 - 1) / 2) ** 0.5, rel=1e-9)
    assert value(V, (F(19, 20), F(19, 20) ** 2)) <= 1  # the set spans farther in x off the axis


def test_unbounded_axis_and_unknown_auxiliary() -> None:
    V = {(2, 0): F(1)}  # the whole x2 axis lies in {x1^2 <= 1}
    size = region_size(V, F(1), ["x1", "x2"])
    assert size.unbounded_axes == ["x2"] and "x2" not in size.axis_extents
    blind = region_size({(2, 0, 0): F(1), (0, 0, 2): F(1)}, F(1), ["x1", "x2"], [Extra("e1", "exp(x1)")])
    assert blind.ball_radius is None and not blind.axis_extents and "exp(x1)" in blind.omitted


def test_pendulum_with_cosine_is_sound() -> None:
    """V = 1 - cos(theta) + omega^2 / 2 on the recast pendulum: the figures hold at the true functions."""
    from lyapcheck.models.language.modelfile import parse_any_model

    path = EXAMPLES / "recast-pendulum.toml"
    model = parse_any_model(path.read_text(), str(path), {})
    names = list(model.system.ring.names)
    extras = extras_of(names, model.states, model.system)
    c1 = names.index("c1")
    V = {tuple(int(j == c1) for j in range(len(names))): F(-1),
         tuple(2 * int(j == 1) for j in range(len(names))): F(1, 2)}
    level = F(3, 2)
    size = region_size(V, level, model.states, extras)
    a = float(size.axis_extents["theta"])
    # the second-order bound |cos t - 1| <= t^2 / 2 wins here: t^2 / 2 = 3/2
    assert a == pytest.approx(math.sqrt(3), rel=1e-9) and 1 - math.cos(a) <= 1.5
    assert float(size.axis_extents["omega"]) == pytest.approx(math.sqrt(3), rel=1e-9)
    r = float(size.ball_radius)
    angles = np.random.default_rng(3).uniform(0, 2 * np.pi, 5000)
    th, om = r * np.cos(angles), r * np.sin(angles)
    assert np.all(1 - np.cos(th) + om ** 2 / 2 <= 1.5)


@pytest.fixture(scope="module")
def certified(tmp_path_factory: pytest.TempPathFactory) -> dict:
    from lyapcheck.api import certify_model_file

    path = tmp_path_factory.mktemp("size") / "two.toml"
    path.write_text(TWO_STATES)
    doc = certify_model_file(str(path), classes="roa").document
    assert doc["conditions"]["roa"]["status"] == "certified"
    return doc


def _failed(doc: dict) -> list[str]:
    from lyapcheck.models.surfaces.certificate import verify_document

    return [why for _, ok, why in verify_document(doc) if not ok]


def test_certified_region_states_its_size_and_verify_rederives_it(certified: dict) -> None:
    c = certified["conditions"]["roa"]
    size, table = c["size"], c["certificate"]["size"]
    assert set(size["axis_extents"]) == {"x1", "x2"}
    # the true region of attraction in x1 is |x1| < 1: the proved reach stays inside it
    assert 0.9 < size["axis_extents"]["x1"] < 1
    assert size["ball_radius"] == float(F(table["ball_radius"]))
    assert _failed(certified) == []


@pytest.mark.parametrize("forge", ["extent_figure", "extent_exact", "radius_figure", "radius_exact", "mu"])
def test_verify_refuses_a_forged_size(certified: dict, forge: str) -> None:
    doc = copy.deepcopy(certified)
    c = doc["conditions"]["roa"]
    table = c["certificate"]["size"]
    if forge == "extent_figure":
        c["size"]["axis_extents"]["x1"] = 1.5
    elif forge == "extent_exact":
        table["axis_extents"]["x1"] = "3/2"
        c["size"]["axis_extents"]["x1"] = 1.5
    elif forge == "radius_figure":
        c["size"]["ball_radius"] *= 1.01
    elif forge == "radius_exact":
        table["ball_radius"] = str(F(table["ball_radius"]) * 2)
    else:
        table["ball_mu"] = str(F(table["ball_mu"]) / 2)
    failed = _failed(doc)
    assert any(why.startswith("roa:") and "size" in why for why in failed), failed


def test_report_slices_of_a_three_state_region() -> None:
    """More than 2 states: planes (x1, x2) and (x2, x3) through the equilibrium; the page carries them."""
    from lyapcheck.models.language.modelfile import parse_any_model
    from reports.region_slices import pairs, size_figure
    from reports.render import certificate_html

    text = TWO_STATES.replace('states = ["x1", "x2"]', 'states = ["x1", "x2", "x3"]').replace(
        'x2 = "-2*x2"', 'x2 = "-2*x2"\nx3 = "-x3"').replace("x2 = [-1.5, 1.5]", "x2 = [-1.5, 1.5]\nx3 = [-1.5, 1.5]")
    model = parse_any_model(text, "three.toml", {})
    assert pairs(3) == [(0, 1), (1, 2)] and pairs(6) == [(0, 1), (2, 3), (4, 5)]
    # a set drawn from its certificate's keys alone (the figure checks nothing: verify does)
    V = {"terms": [["1", [2, 0, 0]], ["1", [0, 2, 0]], ["1", [0, 0, 2]]]}
    size = region_size({(2, 0, 0): F(1), (0, 2, 0): F(1), (0, 0, 2): F(1)}, F(1, 2), model.states)
    cond = {"status": "certified", "property": "ROA", "summary": "", "size": size.figures(),
            "certificate": {"kind": "sublevel", "V": V, "level": "1/2", "size": size.to_json()}}
    doc = {"schema_version": 1, "kind": "lyapcheck-model-certificate", "conditions": {"roa": cond},
           "model": {"name": model.name, "file": "three.toml", "sha256": "", "text": text},
           "states": list(model.states), "equilibrium": {s: "0" for s in model.states}, "parameters": {}}
    fig, why = size_figure(doc, model)
    assert fig is not None, why
    assert fig.data["slices"] == [("x1", "x2"), ("x2", "x3")]
    assert all(k > 0 for k in fig.data["converged"])  # the loop is globally stable in x2, x3 near 0
    page = certificate_html(doc, recheck=False)
    assert 'id="fig-size"' in page and "Size of the certified region" in page
