"""Every printed figure with its unit and its reference point (issue 40, part 4).

An adaptive cruise control keeps a gap ``h`` to the car ahead; its equilibrium is ``h = 30 m`` at the
leader's speed ``v = 20 m/s``, and an acceleration disturbance ``|a| <= 0.5 m/s^2`` pushes it. What is
true of the loop, computed here without lyapcheck: the constant ``a = 0.5`` holds the gap at ``30 +
a/kp = 32.5 m`` (``v' = kp (h - h0) + ... + a = 0`` with ``v = vL``), so no bound on ``|h - 30 m|``
below 2.5 m may be certified; and a bound on ``|h|`` (at least 30) says nothing of the deviation, so
the sentence must speak of ``|h - 30 m|``, in m. ``verify`` re-derives the sentence, the reference
points and the units from the model and the certificate, and refuses an edited one.
"""

from __future__ import annotations

import copy
import math
import re
from pathlib import Path
from typing import Any

import pytest

from lyapcheck.models.classes.claims import rounded
from lyapcheck import api
from lyapcheck.models.surfaces.certificate import build_document, verify_document
from lyapcheck.models.surfaces.certify import certify_model
from lyapcheck.models.classes.claims import summary
from lyapcheck.models.language.modelfile import parse_model

ACC = """
[model]
name = "adaptive cruise control under an acceleration disturbance"
states = ["h", "v"]

[units]
h = "m"
v = "m/s"

[parameters]
vL = "20 m/s"
kp = "0.2 1/s^2"
kd = "0.5 1/s"
h0 = "30 m"

[disturbances]
a = "0.5 m/s^2"

[dynamics]
h = "vL - v"
v = "kp*(h - h0) + kd*(vL - v) + a"

[equilibrium]
h = "30 m"
v = "20 m/s"
"""
#: the gap the constant disturbance a = 0.5 m/s^2 holds: 30 m + a/kp
HELD_GAP_M = 30 + 0.5 / 0.2

#: a loop with functions whose equilibrium is x = 2: x' = 2 - x - tanh(x - 2)/2 + d, |d| <= 0.1
SHIFTED_TANH = """
[model]
name = "a first-order loop at x = 2"
states = ["x"]

[disturbances]
d = 0.1

[dynamics]
x = "2 - x - 0.5*tanh(x - 2) + d"

[equilibrium]
x = 2
"""


def failures(doc: dict[str, Any]) -> dict[str, str]:
    out: dict[str, str] = {}
    for name, ok, why in verify_document(doc):
        if not ok:
            out[name] = f"{out.get(name, '')}{why}; "
    return out


@pytest.fixture(scope="module")
def acc() -> dict[str, Any]:
    return build_document(certify_model(parse_model(ACC, "acc.toml"), classes="quadratic,sos_bound"))


def test_the_gap_is_bounded_about_its_equilibrium_in_metres(acc: dict[str, Any]) -> None:
    c = acc["conditions"]["sos_bound"]
    assert c["status"] == "certified" and c["disturbances"] == "all"
    assert c["bounds_reference"] == {"h": 30.0, "v": 20.0}
    assert c["bounds_unit"] == {"h": "m", "v": "m/s"}
    found = re.search(r"limsup \|h - 30 m\| <= ([0-9.e+-]+) m\b", c["summary"])
    assert found is not None, c["summary"]
    printed = float(found.group(1))
    assert printed == pytest.approx(c["bounds"]["h"], rel=1e-3)
    # a bound of the deviation: at least what the constant disturbance holds, far below the gap itself
    assert HELD_GAP_M - 30 <= c["bounds"]["h"] < 10
    assert re.search(r"limsup \|v - 20 m/s\| <= [0-9.e+-]+ m/s\b", c["summary"]), c["summary"]
    assert failures(acc) == {}
    # the report's table of key figures says the same
    from reports.sections.model_file import key_figures

    assert f"limsup |h - 30 m| <= {rounded(c['bounds']['h'], 6, 'up')} m" in key_figures(c)


def test_the_bound_does_not_depend_on_where_the_equilibrium_lies(acc: dict[str, Any]) -> None:
    """The same loop about a gap of 3000 m: the same deviation, so the same bound (the output is
    scaled and bounded by its deviation, not by its value)."""
    far = ACC.replace('h0 = "30 m"', 'h0 = "3000 m"').replace('h = "30 m"', 'h = "3000 m"')
    doc = build_document(certify_model(parse_model(far, "far.toml"), classes="sos_bound"))
    c = doc["conditions"]["sos_bound"]
    assert c["bounds_reference"] == {"h": 3000.0, "v": 20.0}
    assert c["bounds"]["h"] == pytest.approx(acc["conditions"]["sos_bound"]["bounds"]["h"], rel=1e-3)
    assert "limsup |h - 3000 m| <= " in c["summary"]


def test_the_stability_sentence_measures_the_distance_to_the_equilibrium(acc: dict[str, Any]) -> None:
    q = acc["conditions"]["quadratic"]
    assert q["status"] == "certified" and q["property"] == "GES"
    # k rounded up, the rate down: the sentence never claims more than the certificate
    assert f"|x(t) - x_eq| <= {rounded(q['k'], 4, 'up')} |x0 - x_eq| exp(-r t) with r = " \
        f"{rounded(q['decay_rate_per_s'], 4, 'down')} 1/s" in q["summary"], q["summary"]
    assert "|x(t)| <=" not in q["summary"]


@pytest.mark.parametrize("edit", ["reference", "reference_and_sentence", "unit_and_sentence", "no_reference"])
def test_an_edited_reference_point_or_unit_fails_verify(acc: dict[str, Any], edit: str) -> None:
    doc = copy.deepcopy(acc)
    c = doc["conditions"]["sos_bound"]
    if edit == "reference":  # the figure alone
        c["bounds_reference"]["h"] = 25.0
    elif edit == "reference_and_sentence":  # the figure and a sentence made from it: the model says 30 m
        c["bounds_reference"]["h"] = 25.0
        c["summary"] = summary("sos_bound", c, ["h", "v"])
        assert "limsup |h - 25 m|" in c["summary"]
    elif edit == "unit_and_sentence":  # the bound claimed in mm: 1000 times smaller
        c["bounds_unit"]["h"] = "mm"
        c["summary"] = summary("sos_bound", c, ["h", "v"])
    else:  # a bound on |h| itself, with the figures of the deviation: the false claim limsup |h| <= 3.6 m
        del c["bounds_reference"]
        c["summary"] = summary("sos_bound", c, ["h", "v"])
        assert "limsup |h| <= " in c["summary"]
    assert "sos_bound" in failures(doc)


def test_a_ball_is_in_the_states_unit_only_where_they_share_one(tmp_path: Path) -> None:
    """A region's ball |x - x_eq| <= r: in m where every state is in m; where they differ (m and
    m/s) the radius is a norm of SI values, and the sentence says so instead of inventing a unit."""
    text = ("[model]\nname = \"cubic\"\nstates = [\"x\", \"y\"]\n[units]\nx = \"m\"\ny = \"{unit}\"\n"
            "[parameters]\nk = \"1 1/s\"\nL = \"1 m\"\n[dynamics]\nx = \"-k*x + k*x**3/L**2\"\ny = \"-k*y\"\n")
    for unit, expected in (("m", "m"), ("m/s", None)):
        model = parse_model(text.replace("{unit}", unit), "cubic.toml")
        doc = build_document(certify_model(model, classes="candidate", candidate="x**2 + y**2"))
        c = doc["conditions"]["candidate"]
        assert c["status"] == "certified" and 0 < c["ball_radius"] <= 1, c["summary"]
        assert c["ball_radius_unit"] == expected
        if expected == "m":
            assert c["summary"].endswith(f"it holds the ball |x - x_eq| <= {rounded(c['ball_radius'], 4, 'down')} m")
        else:
            assert c["summary"].endswith("(the Euclidean norm of the states' SI values: they have different units)")
        assert failures(doc) == {}
        forged = copy.deepcopy(doc)
        forged["conditions"]["candidate"]["ball_radius_unit"] = "km"
        forged["conditions"]["candidate"]["summary"] = summary("candidate", forged["conditions"]["candidate"])
        assert "km" in forged["conditions"]["candidate"]["summary"]
        assert "candidate" in failures(forged)


def test_a_loop_with_functions_bounds_the_deviation_from_its_equilibrium(tmp_path: Path) -> None:
    path = tmp_path / "shifted.toml"
    path.write_text(SHIFTED_TANH)
    result = api.certify(model=path, classes="sos_bound")
    c = result.document["conditions"]["sos_bound"]
    assert c["status"] == "certified" and c["bounds_reference"] == {"x": 2.0} and "bounds_unit" not in c
    found = re.search(r"limsup \|x - 2\| <= ([0-9.e+-]+) \(checked exactly\)", c["summary"])
    assert found is not None, c["summary"]
    # the constant d = 0.1 holds x - 2 at the root e of e + tanh(e)/2 = 0.1 (bisection here): no bound below it
    lo, hi = 0.0, 0.1
    for _ in range(60):
        mid = (lo + hi) / 2
        lo, hi = (mid, hi) if mid + 0.5 * math.tanh(mid) < 0.1 else (lo, mid)
    assert lo <= c["bounds"]["x"] < 1
    assert api.verify(result).valid
    forged = copy.deepcopy(result.document)
    f = forged["conditions"]["sos_bound"]
    f["bounds_reference"]["x"] = 0.0  # the claim limsup |x| <= 0.1: false, x stays near 2
    f["summary"] = summary("sos_bound", f, ["x"])
    assert "limsup |x| <= " in f["summary"]
    assert not api.verify(forged).valid


@pytest.mark.parametrize("value, direction, text", [(2.00015, "up", "2.001"), (2.00015, "down", "2"),
                                                    (0.22929, "down", "0.2292"), (0.22921, "up", "0.2293"),
                                                    (9.99951, "up", "10"), (3.14159e-7, "up", "3.142e-07"),
                                                    (32.29, "up", "32.29"), (123456.7, "down", "1.234e+05")])
def test_a_printed_figure_is_rounded_towards_the_weaker_claim(value: float, direction: str, text: str) -> None:
    assert rounded(value, 4, direction) == text
    printed = float(text)
    assert printed >= value if direction == "up" else printed <= value
