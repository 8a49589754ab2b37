"""Box certificates (class ges over a box of gains): the covering argument and the exact re-check."""

from __future__ import annotations

import json
import random
from fractions import Fraction
from pathlib import Path

import pytest
import sympy as sp
from click.testing import CliRunner

from lyapcheck import verify
from lyapcheck.paper.boxes.box import ParameterBox, parse_box, sample_points
from lyapcheck.paper.boxes.classes import refine, verify_box
from lyapcheck.paper.boxes.cross_check import cross_check
from lyapcheck.api import certify_box
from lyapcheck.paper.certification import build_system
from lyapcheck.paper.conditions import ges
from lyapcheck.paper.conditions.sos import scaled_dynamics
from lyapcheck.errors import InvalidParameter
from lyapcheck.paper.params import problem_from_sources
from symbolic import _generated
from tests.conftest import PAPER_TOML

#: a box the paper's window certifies (found by refine over alpha_d 60..6000, k_d 0.015..1.5)
CERTIFIED_BOX = ["alpha_d=1545..3030", "k_d=0.7575..1.5"]


@pytest.mark.parametrize("dynamics", ["derived", "printed"])
def test_scaled_coefficients_are_monomials_in_the_parameters(dynamics: str) -> None:
    """The covering argument: c, a, b are signed monomials, hence monotone in every parameter."""
    names = ("alpha_d", "sigma0", "k_d", "delta_los", "los_speed", "e11", "e11_hat")
    symbols = {n: sp.Symbol(n, positive=True) for n in names}
    data = getattr(_generated, dynamics)(**symbols)
    A, B = data["A"], data["B"]
    assert A[1][0] == 0 and B == ((0, 0), (1, 0))
    speed = symbols["los_speed"] if dynamics == "derived" else 1
    ts = -A[0][0]
    c = sp.simplify(A[0][1] / (symbols["sigma0"] * ts))
    a = sp.simplify(-A[1][1] / ts)
    b = sp.simplify(symbols["sigma0"] * speed / (symbols["delta_los"] * ts))
    for expr in (c, a, b, ts):
        coefficient, rest = sp.sympify(expr).as_coeff_Mul()
        powers = rest.as_powers_dict()
        assert coefficient != 0 and all(base in symbols.values() and exponent.is_integer
                                        for base, exponent in powers.items() if base != 1), expr
    # why no GES box is ever 'refuted' (lyapcheck.paper.boxes.quadratic): the linearisation [[-1, c], [b, -a]]
    # at the origin has det = a - b c = a + b > 0 at every positive gain set
    assert c == -1 and sp.simplify(a - b * c).is_positive


@pytest.fixture(scope="module")
def certified() -> tuple:
    result = certify_box(PAPER_TOML, CERTIFIED_BOX)
    return result, problem_from_sources(PAPER_TOML, {})


def test_a_certified_box_rechecks_and_holds_at_interior_points(certified: tuple) -> None:
    result, problem = certified
    assert result.verdict == "certified", result.conditions["ges"].summary
    assert verify(result.to_json()).valid
    cert = result.document["conditions"]["ges"]["certificate"]
    rng = random.Random(3)
    for _ in range(4):  # the certificate at gain sets strictly inside the box, by the point class's check
        alpha = Fraction(1545) + Fraction(rng.randint(1, 999), 1000) * (3030 - 1545)
        kd = Fraction(7575, 10000) + Fraction(rng.randint(1, 999), 1000) * (Fraction(15, 10) - Fraction(7575, 10000))
        dyn = scaled_dynamics(build_system(problem.with_gains(alpha_d=alpha, k_d=kd), "derived"))
        assert dyn is not None
        assert ges.exact_check(dyn, *certificate_at_point(cert, dyn))[0]


def certificate_at_point(cert: dict, dyn: object) -> tuple:
    """The box certificate at one gain set, as the point class states one: ``(P, l, mu, c1, c2)``
    in that point's own time scale (a common certificate as stored; a parametric one evaluated at
    the point's coordinates ``u``, its rate rescaled from the box's time scale to the point's)."""
    c1, c2 = Fraction(cert["c1"]), Fraction(cert["c2"])
    if cert.get("form") != "parametric":
        P = tuple(tuple(Fraction(v) for v in row) for row in cert["P"])
        return P, [[Fraction(x) for x in ell] for ell in cert["l"]], Fraction(cert["mu_scaled"]), c1, c2
    from lyapcheck.paper.boxes import ges_param

    lo = [Fraction(v) for v in cert["entries"]["lo"]]
    hi = [Fraction(v) for v in cert["entries"]["hi"]]
    ts = dyn.time_scale  # type: ignore[attr-defined]
    entries = (ts, ts * dyn.b, ts * dyn.a)  # type: ignore[attr-defined]
    u = [(entries[i] - lo[i]) / (hi[i] - lo[i]) for i in range(3) if hi[i] != lo[i]]
    mons = ges_param.unknown_monomials(len(u), int(cert["degree"]))
    weights = []
    for alpha in mons:
        weight = Fraction(1)
        for ui, a in zip(u, alpha):
            weight *= ui ** a
        weights.append(weight)
    P = tuple(tuple(sum((w * Fraction(m[r][s]) for w, m in zip(weights, cert["P"])), Fraction(0)) for s in range(2))
              for r in range(2))
    terms = len(cert["l"][0])
    ells = [[sum((w * Fraction(block[k][r]) for w, block in zip(weights, cert["l"])), Fraction(0)) for r in range(2)]
            for k in range(terms)]
    return P, ells, Fraction(cert["mu_scaled"]) * Fraction(cert["time_scale"]) / ts, c1, c2


def test_a_widened_box_fails_its_recheck(certified: tuple) -> None:
    result, _ = certified
    doc = json.loads(json.dumps(result.to_json()))
    doc["box"]["k_d"][0] = "0.015"  # the certificate was not computed for this box
    checked = verify(doc)
    assert not checked.valid and any("do not match the box" in c.message for c in checked.checks if not c.ok)


@pytest.mark.parametrize("spec, field", [
    (["alpha_d=660..540"], "alpha_d"),
    (["omega=1..2"], "box"),
    (["alpha_d=-1..2"], "alpha_d"),
    (["alpha_d=1..2", "alpha_d=3..4"], "alpha_d"),
    (["alpha_d 1..2"], "box"),
    (["delta_los=1..2"], "delta_los"),  # a length needs its unit
])
def test_bad_boxes_name_the_field(spec: list[str], field: str) -> None:
    with pytest.raises(InvalidParameter, match=f"The '{field}' parameter must be"):
        parse_box(spec)


def test_box_units_are_si_inside() -> None:
    box = parse_box(["delta_los=0.5 mm..1 mm", "alpha_d=540..660"])
    assert box.to_json() == {"delta_los": ["1/2000", "1/1000"], "alpha_d": ["540", "660"]}


def test_command_line_box_and_bad_input(tmp_path: Path) -> None:
    from lyapcheck.cli import app

    app._register_commands()
    out = tmp_path / "box.json"
    done = CliRunner().invoke(app.cli, ["certify", str(PAPER_TOML), *sum((["--box", b] for b in CERTIFIED_BOX), []),
                                        "--json", "--out", str(out)])
    assert done.exit_code == 0, done.output
    assert json.loads(out.read_text())["conditions"]["ges"]["status"] == "certified"
    assert CliRunner().invoke(app.cli, ["verify", str(out)]).exit_code == 0
    bad = CliRunner().invoke(app.cli, ["certify", str(PAPER_TOML), "--box", "k_d=2..1"])
    assert bad.exit_code == 2 and bad.stderr.count("\n") == 1 and "'k_d'" in bad.stderr


@pytest.mark.slow
def test_refinement_resolves_a_window_into_certified_and_undecided_boxes() -> None:
    problem = problem_from_sources(PAPER_TOML, {})
    window = parse_box(["alpha_d=800..3200", "k_d=0.4..1.6"])
    leaves = refine(problem, window, min_relative_width=1.0)
    statuses = {leaf.status for leaf in leaves}
    assert "certified" in statuses
    for leaf in leaves:
        if leaf.status == "certified":
            assert verify_box(problem, leaf.box, "derived", leaf.result)[0]
        else:
            assert leaf.box.relative_width() <= 1.0


def test_cross_check_accepts_the_certified_envelope_and_catches_a_false_one(certified: tuple) -> None:
    """The simulation cross-check is a real check: the box's envelope holds at random interior
    points, and the same envelope with a ten times faster rate is caught as violated."""
    result, problem = certified
    ges_result = result.document["conditions"]["ges"]
    box = parse_box(CERTIFIED_BOX)
    runs, worst = cross_check(problem, box, ges_result, 3, (0, 7))
    assert runs == 3 and 0 < worst <= 1
    assert all(p_in(box, point) for point in sample_points(box, 20, (0, 7)))
    false_claim = {"k": ges_result["k"], "decay_rate_per_s": 10 * ges_result["decay_rate_per_s"]}
    assert cross_check(problem, box, false_claim, 1, (0, 7))[1] > 1


def p_in(box: ParameterBox, point: dict) -> bool:
    return all(lo <= point[name] <= hi for name, lo, hi in box.bounds)


#: a box where one quadratic V serves every gain set (found by trying the window's high-k_d corner)
SECTOR_BOX = ["alpha_d=150..300", "k_d=3..10"]


def test_sector_box_certificate_is_exact_and_covers_interior_points() -> None:
    """sector_ges over a box: the stored P decreases at every vertex of the box's matrix polytope,
    and (the covering argument) at both sector end points of gain sets strictly inside the box."""
    from lyapcheck import exact
    from lyapcheck.paper.conditions import sector

    result = certify_box(PAPER_TOML, SECTOR_BOX, classes="sector_ges")
    assert result.verdict == "certified" and list(result.conditions) == ["sector_ges"]
    assert verify(result.to_json()).valid
    cert = result.document["conditions"]["sector_ges"]["certificate"]
    P = exact.from_json(cert["P"])
    rate = Fraction(cert["decay_rate_scaled"])
    problem = problem_from_sources(PAPER_TOML, {})
    rng = random.Random(5)
    for _ in range(4):
        alpha = Fraction(150) + Fraction(rng.randint(1, 999), 1000) * 150
        kd = Fraction(3) + Fraction(rng.randint(1, 999), 1000) * 7
        dyn = scaled_dynamics(build_system(problem.with_gains(alpha_d=alpha, k_d=kd), "derived"))
        assert dyn is not None
        ends = [exact.matrix([[-1, dyn.c], [0, -dyn.a]]), exact.matrix([[-1, dyn.c], [dyn.b, -dyn.a]])]
        assert sector.exact_check(ends, P, rate)[0]
    doc = result.to_json()
    doc["conditions"]["sector_ges"]["certificate"]["decay_rate_scaled"] = str(rate * 1000)  # an overstated rate
    assert not verify(doc).valid


def test_sector_box_refutation_names_a_point_of_the_box_and_rechecks() -> None:
    """The paper's box: a corner has no common quadratic V for its own sector (Shorten-Narendra),
    so none serves the box; verify re-checks that exactly, and refuses a point outside the box."""
    result = certify_box(PAPER_TOML, ["alpha_d=540..660", "k_d=0.1..0.2"], classes="sector_ges")
    assert result.conditions["sector_ges"].status == "refuted"
    doc = result.to_json()
    assert verify(doc).valid
    doc["conditions"]["sector_ges"]["refutation"]["point"]["alpha_d"] = "700"
    assert not verify(doc).valid


def test_box_classes_are_validated() -> None:
    with pytest.raises(InvalidParameter) as info:
        certify_box(PAPER_TOML, SECTOR_BOX, classes="switched_ges")
    assert info.value.field == "classes"


@pytest.mark.slow
@pytest.mark.parametrize("extreme", [["alpha_d=1e-300..1e300"], ["k_d=1e-300..1e300"], ["sigma0=1e-300..1e300"],
                                     ["delta_los=1e-300 m..1e300 m"], ["los_speed=1e-300 m/s..1e300 m/s"],
                                     ["e11=1e-300 m..1e300 m"]])
def test_every_box_class_answers_on_boxes_spanning_the_double_range(extreme: list[str]) -> None:
    """Corners at both ends of the double range combine into figures no double holds: each class
    answers (here: nothing is proved) instead of overflowing; the document still re-checks."""
    done = certify_box(PAPER_TOML, extreme, classes="all")
    for cls, result in done.conditions.items():
        assert result.status in ("not_certified", "refuted", "certified", "not_applicable"), (cls, result.summary)
    assert verify(done.to_json()).valid
