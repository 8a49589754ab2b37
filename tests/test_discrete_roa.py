"""``roa`` and ``candidate`` on discrete-time maps (issue 44, item 1): a sublevel set ``{V <= c}`` on which
``V(F(e)) <= V(e) - eps m(e)``, checked exactly (:mod:`lyapcheck.models.classes.discrete_regions`).

What is asserted: on a map that is locally but not globally stable (``examples/models/discrete-local-map.toml``,
a second fixed point at ``(1/2, -1/2)``) ``roa`` certifies a set, below the second fixed point's level of ``V``
and close to it, that ``verify`` re-checks; every start sampled in the certified set converges when the map is
iterated (``simulate``), and the set is forward invariant along the iterates; a certificate with its level
raised, a Gram entry changed or its ``eps`` set to 0 fails ``verify`` (exit 1); the exact check refuses what
the identity does not prove; ``candidate`` takes the user's ``V`` (its level depends on that ``V``) and its
stated text is held to it; ``roa`` is ``not_applicable`` on a map certified GAS.
"""

from __future__ import annotations

import json
from fractions import Fraction
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from click.testing import CliRunner

from lyapcheck.cli import app
from lyapcheck.models.classes import discrete_regions as dr
from lyapcheck.sos.certificates import GramPoly
from lyapcheck.sos.polynomials import Ring, to_fmpq

app._register_commands()

EXAMPLES = Path(__file__).resolve().parents[1] / "examples" / "models"
LOCAL = EXAMPLES / "discrete-local-map.toml"


def cli(*args: str) -> Any:
    done = CliRunner().invoke(app.cli, list(args))
    assert done.exception is None or isinstance(done.exception, SystemExit), done.output
    assert "Traceback" not in done.output
    return done


@pytest.fixture(scope="module")
def local_certificate(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, dict[str, Any]]:
    out = tmp_path_factory.mktemp("roa") / "local.json"
    done = cli("certify", str(LOCAL), "--classes", "linearization,quadratic,roa,candidate", "--candidate",
               "x**2 + 2*y**2", "--no-store", "--json", "--out", str(out))
    assert done.exit_code == 0, done.output
    return out, json.loads(out.read_text())


def _v_values(terms: dict[str, Any], points: np.ndarray) -> np.ndarray:
    """The stated V (exact terms) at points, in floating point (independent of the class's code)."""
    total = np.zeros(len(points))
    for c, exponents in terms["terms"]:
        total += float(Fraction(c)) * np.prod(points ** np.array(exponents), axis=1)
    return total


def test_roa_certifies_a_set_below_the_second_fixed_point_and_verify_rechecks_it(
        local_certificate: tuple[Path, dict[str, Any]]) -> None:
    path, doc = local_certificate
    roa = doc["conditions"]["roa"]
    assert doc["conditions"]["quadratic"]["status"] == "not_certified"
    assert roa["status"] == "certified" and roa["property"] == "ROA"
    cert = roa["certificate"]
    assert cert["kind"] == "discrete_sublevel" and cert["time"] == "discrete"
    assert Fraction(cert["eps"]) > 0
    level = Fraction(cert["level"])
    # (1/2, -1/2) is a fixed point, so no region of attraction of the origin holds it: the level is below its V,
    # and the search comes close to that bound
    v_fixed = _v_values(cert["V"], np.array([[0.5, -0.5]]))[0]
    assert 0.9 * v_fixed < float(level) < v_fixed
    printed = roa["summary"].split("{V <= ", 1)[1].split("}", 1)[0]  # (rounded down: never more than proved)
    assert roa["summary"].startswith(f"{{V <= {printed}}} is a region of attraction of the discrete-time map")
    assert 0.999 * float(level) <= float(printed) <= float(level)
    assert 0 < roa["roa_share"] <= 1 and "starts_left_set" not in roa
    assert roa["size"]["ball_radius"] > 0
    done = cli("verify", str(path))
    assert done.exit_code == 0, done.output
    assert "roa: Q_V > 0" in done.output and "candidate: the candidate text is the certified V" in done.output


def test_every_sampled_start_in_the_certified_set_converges_and_stays_in_it(
        local_certificate: tuple[Path, dict[str, Any]]) -> None:
    import lyapcheck

    _, doc = local_certificate
    cert = doc["conditions"]["roa"]["certificate"]
    level = float(Fraction(cert["level"]))
    rng = np.random.default_rng(3)
    points = rng.uniform(-1, 1, size=(4000, 2))
    inside = points[_v_values(cert["V"], points) <= level][:300]
    assert len(inside) >= 100
    report = lyapcheck.simulate(model=LOCAL, x0=inside, steps=200, series=False)
    assert report.document["n_trajectories"] == len(inside)
    assert report.document["n_converged"] == len(inside) and report.document["n_diverged"] == 0
    x = inside.copy()  # the same map, iterated here: V never rises above the level (forward invariance)
    for _ in range(50):
        x = np.stack([0.5 * x[:, 0] + x[:, 1] ** 2, 0.5 * x[:, 1] - x[:, 0] ** 2], axis=1)
        assert np.all(_v_values(cert["V"], x) <= level * (1 + 1e-12))


@pytest.mark.parametrize("tamper", ["level", "gram_sigma", "gram_s", "eps"])
def test_a_tampered_certificate_fails_verify(local_certificate: tuple[Path, dict[str, Any]], tmp_path: Path,
                                             tamper: str) -> None:
    _, doc = local_certificate
    doc = json.loads(json.dumps(doc))
    roa = doc["conditions"]["roa"]
    cert = roa["certificate"]
    if tamper == "level":  # the level raised in the certificate and beside the status alike
        raised = Fraction(cert["level"]) * Fraction(11, 10)
        cert["level"], roa["level"] = str(raised), float(raised)
    elif tamper == "eps":
        cert["eps"] = "0"
    else:
        Q = cert[tamper]["Q"]
        Q[0][0] = str(Fraction(Q[0][0]) + Fraction(1, 1000))
    path = tmp_path / "tampered.json"
    path.write_text(json.dumps(doc))
    done = cli("verify", str(path))
    assert done.exit_code == 1, done.output
    assert any(line.startswith("FAIL") and "roa:" in line for line in done.output.splitlines()), done.output


def test_a_stated_level_above_the_certified_one_fails_verify(local_certificate: tuple[Path, dict[str, Any]],
                                                              tmp_path: Path) -> None:
    _, doc = local_certificate
    doc = json.loads(json.dumps(doc))
    doc["conditions"]["roa"]["level"] *= 1.01
    path = tmp_path / "stated.json"
    path.write_text(json.dumps(doc))
    done = cli("verify", str(path))
    assert done.exit_code == 1 and "the stated level exceeds the certified one" in done.output


def test_candidate_takes_the_users_v_and_is_held_to_it(local_certificate: tuple[Path, dict[str, Any]],
                                                        tmp_path: Path) -> None:
    _, doc = local_certificate
    cand = doc["conditions"]["candidate"]
    assert cand["status"] == "certified" and cand["summary"].startswith("the user's V: {V <= ")
    assert cand["certificate"]["V"] == {"terms": [["2", [0, 2]], ["1", [2, 0]]]}
    # V = x^2 + 2 y^2 is 3/4 at the second fixed point: the level is below it
    assert float(Fraction(cand["certificate"]["level"])) < 0.75
    assert Fraction(cand["certificate"]["level"]) != Fraction(doc["conditions"]["roa"]["certificate"]["level"])
    doc = json.loads(json.dumps(doc))
    doc["candidate"] = "x**2 + 3*y**2"
    path = tmp_path / "other.json"
    path.write_text(json.dumps(doc))
    done = cli("verify", str(path))
    assert done.exit_code == 1 and "not the V of the certified candidate" in done.output


def test_roa_is_not_applicable_on_a_map_certified_gas(tmp_path: Path) -> None:
    done = cli("certify", str(EXAMPLES / "fossil-dt-two-room-temp.toml"), "--classes", "quadratic,roa", "--no-store",
               "--json")
    conditions = json.loads(done.stdout)["conditions"]
    assert conditions["quadratic"]["status"] == "certified"
    assert conditions["roa"]["status"] == "not_applicable"
    assert "the region of attraction is the whole state space" in conditions["roa"]["summary"]


def test_the_exact_check_refuses_what_the_identity_does_not_prove() -> None:
    """``e+ = e/2`` in one state: ``V = e^2`` gives ``V - V(F) = 3/4 e^2``; with ``s = 0`` the identity holds
    with ``sigma = (3/4 - eps) e^2`` at any level."""
    ring = Ring(("e",))
    F = (ring.monomial((1,)) * to_fmpq(Fraction(1, 2)),)
    V = GramPoly(((1,),), ((Fraction(1),),))
    zero_s = GramPoly(((1,),), ((Fraction(0),),))

    def cert(level: Fraction, eps: Fraction, sigma: Fraction) -> dr.DiscreteSublevel:
        return dr.DiscreteSublevel(V, level, eps, zero_s, GramPoly(((1,),), ((sigma,),)))

    assert dr.check_discrete_sublevel(ring, F, cert(Fraction(5), Fraction(1, 4), Fraction(1, 2)))[0]
    assert not dr.check_discrete_sublevel(ring, F, cert(Fraction(5), Fraction(0), Fraction(3, 4)))[0]  # eps = 0
    assert not dr.check_discrete_sublevel(ring, F, cert(Fraction(0), Fraction(1, 4), Fraction(1, 2)))[0]  # c = 0
    assert not dr.check_discrete_sublevel(ring, F, cert(Fraction(5), Fraction(1, 4), Fraction(1, 3)))[0]  # identity
    assert not dr.check_discrete_sublevel(ring, F, cert(Fraction(5), Fraction(1), Fraction(-1, 4)))[0]  # sigma < 0
    # an expanding map: V - V(F) = -3 e^2 < 0, so no eps > 0 and sigma >= 0 satisfy the identity with s = 0
    G = (ring.monomial((1,)) * 2,)
    assert not dr.check_discrete_sublevel(ring, G, cert(Fraction(1), Fraction(1, 4), Fraction(-13, 4)))[0]


def test_the_margin_follows_the_lowest_pure_powers_of_v() -> None:
    ring = Ring(("x", "y"))
    quartic = GramPoly(((2, 0), (0, 2), (1, 1)), tuple(tuple(Fraction(int(i == j)) for j in range(3)) for i in range(3)))
    assert dr.margin_polynomial(ring, quartic) == ring.monomial((4, 0)) + ring.monomial((0, 4))
    mixed = GramPoly(((1, 0), (0, 1), (2, 0)), tuple(tuple(Fraction(int(i == j)) for j in range(3)) for i in range(3)))
    assert dr.margin_polynomial(ring, mixed) == ring.monomial((2, 0)) + ring.monomial((0, 2))
    with pytest.raises(ValueError, match="no pure power of y"):
        dr.margin_polynomial(ring, GramPoly(((1, 0),), ((Fraction(1),),)))
