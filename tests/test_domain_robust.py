"""A larger ``[domain]`` never makes ``roa`` fail where a smaller one succeeds (issue 42, item 4).

The upright pendulum with a saturated PD law, ``theta'' = (g/l) sin(theta) - b theta' + sat(-Kp theta -
Kd theta', umax)``: over ``theta in [-2, 2]`` a V fitted over the domain is proved at once; over the
full ``[-pi, pi]`` no polynomial V of the fit's degree decreases at every converging sample of the box
twice the domain's size (the fitting program is infeasible; HiGHS's simplex used to spend a minute on
it before saying "Status 15"), and the route fits V to less of the domain instead
(:data:`lyapcheck.models.classes.recast_interval.DOMAIN_RETRIES`).
"""

from __future__ import annotations

from fractions import Fraction
from pathlib import Path

import numpy as np
import pytest

from lyapcheck import api

PENDULUM = """
[model]
name = "upright pendulum with saturated PD"
states = ["theta", "omega"]

[parameters]
g = 9.81
b = 0.1
Kp = 20
Kd = 5
umax = 12

[dynamics]
theta = "omega"
omega = "g*sin(theta) - b*omega + sat(-Kp*theta - Kd*omega, umax)"

[domain]
theta = [{t0}, {t1}]
omega = [-8, 8]
"""


def _share_of(result: object, theta: float, with_boxes: bool = False) -> float:
    """The share of a 40 x 40 grid of the domain ``theta in +-theta``, ``omega in +-8`` inside the
    certified set (:func:`lyapcheck.models.classes.recast_regions.certified_value`); ``with_boxes``: inside
    the certified region, the set or a box of its certificate's ``flow`` (boxes proved to flow into it)."""
    from lyapcheck.models.classes import recast_classes as rc
    from lyapcheck.models.language.modelfile import parse_any_model
    from lyapcheck.models.language.recast import RecastModel
    from lyapcheck.models.classes.recast_regions import certified_value

    model = parse_any_model(PENDULUM.format(t0=-2, t1=2), "m.toml")
    assert isinstance(model, RecastModel)
    loop = rc.base_loop(model.system)
    roa = result.conditions["roa"]  # type: ignore[attr-defined]
    value, = certified_value(loop, roa)
    axes = [np.linspace(-theta, theta, 40), np.linspace(-8, 8, 40)]
    Z = np.column_stack([g.ravel() for g in np.meshgrid(*axes, indexing="ij")])
    inside = value(Z) <= float(Fraction(roa.certificate["level"]))
    if with_boxes:
        for entry in roa.certificate.get("flow", {}).get("boxes", []):
            lo = np.array([float(Fraction(entry["box"][s][0])) for s in ("theta", "omega")])
            hi = np.array([float(Fraction(entry["box"][s][1])) for s in ("theta", "omega")])
            inside |= np.all((Z >= lo) & (Z <= hi), axis=1)
    return float(np.mean(inside))


@pytest.mark.slow
def test_widening_the_domain_keeps_the_region_and_states_its_share_of_the_domain_given(tmp_path: Path) -> None:
    results = {}
    for name, t in (("narrow", "2"), ("wide", "3.14159")):
        path = tmp_path / f"{name}.toml"
        path.write_text(PENDULUM.format(t0="-" + t, t1=t))
        results[name] = api.certify(model=path, classes="roa")
    narrow, wide = (results[k].conditions["roa"] for k in ("narrow", "wide"))
    assert narrow.status == "certified" and "fitted_domain_share" not in narrow.numbers
    assert wide.status == "certified", wide.summary
    # the wide domain's first fit proved nothing: the set stated was fitted to less, and says so
    assert wide.numbers["tried"][0].startswith("V fitted over the domain: ")
    assert 0 < wide.numbers["fitted_domain_share"] <= 1
    assert api.verify(results["wide"]).valid
    # the coverage stated is of the domain given: every start of the wide domain's grid converges
    # here, so roa_share is the share of that grid in the certified region (the set and the boxes proved
    # to flow into it)
    assert wide.numbers["simulated_roa_share_of_box"] == 1.0
    assert wide.numbers["roa_share"] == pytest.approx(_share_of(results["wide"], 3.14159, True), abs=1e-12)
    assert narrow.numbers["roa_share"] == pytest.approx(_share_of(results["narrow"], 2, True), abs=1e-12)
    # and the wide domain's set is no smaller than the narrow one's, on either domain
    for theta in (2, 3.14159):
        assert _share_of(results["wide"], theta) >= _share_of(results["narrow"], theta)
