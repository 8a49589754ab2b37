"""``roa``'s SOS route on a loop with functions (:mod:`lyapcheck.models.classes.regions`, its part on the
recasting's relations): the set it proves verifies, and an edited certificate of it does not.

The class tries ball arithmetic first, and on the shipped loops of 1 to 3 states that route proves a set
before the SOS route is reached; here the ball route is switched off so that the document holds the
SOS route's certificate (the route a loop of more states takes).
"""

from __future__ import annotations

import copy
from fractions import Fraction
from pathlib import Path
from typing import Any, Callable

import pytest

from lyapcheck import api

MODELS = Path(__file__).resolve().parent.parent / "examples" / "models"

Doc = dict[str, Any]


@pytest.fixture(scope="module")
def sos_region() -> Doc:
    """The ILOS course loop's ``roa`` by the SOS route on its recasting's relations (a square root)."""
    from lyapcheck.models.classes import recast_interval

    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(recast_interval, "interval_roa", lambda *args, **kwargs: "ball arithmetic: not tried (test)")
        return api.certify(model=str(MODELS / "recast-ilos-course.toml"), classes="roa").to_json()


def edited(doc: Doc, edit: Callable[[Doc], Any]) -> Doc:
    out = copy.deepcopy(doc)
    edit(out)
    return out


def refusals(doc: Doc) -> list[tuple[str, str]]:
    result = api.verify(doc)
    return [(c.check, c.message) for c in result.checks if not c.ok]


def test_the_sos_route_region_is_certified_with_its_multiplier_and_verifies(sos_region: Doc) -> None:
    roa = sos_region["conditions"]["roa"]
    assert roa["status"] == "certified", roa["summary"]
    cert = roa["certificate"]
    assert "level" in cert and cert["decrease"].get("rho") is not None  # the level step's multiplier
    assert Fraction(cert["level"]) > 0
    assert refusals(sos_region) == []


def test_a_raised_level_of_the_sos_route_region_fails_its_exact_check(sos_region: Doc) -> None:
    """The level raised in the certificate and beside it (so that the stated figure agrees): the
    decrease identity with the stored multipliers no longer holds on the larger set."""
    level = Fraction(sos_region["conditions"]["roa"]["certificate"]["level"]) * 2

    def raise_level(d: Doc) -> None:
        d["conditions"]["roa"]["certificate"]["level"] = str(level)
        d["conditions"]["roa"]["level"] = float(level)

    failed = refusals(edited(sos_region, raise_level))
    assert any(name == "roa" and "decrease" in message for name, message in failed), failed


def test_a_changed_multiplier_of_the_sos_route_region_fails_its_exact_check(sos_region: Doc) -> None:
    """A diagonal entry of the multiplier rho's Gram matrix changed (rho stays SOS): the decrease
    identity no longer holds."""
    def change_rho(d: Doc) -> None:
        Q = d["conditions"]["roa"]["certificate"]["decrease"]["rho"]["Q"]
        Q[0][0] = str(Fraction(Q[0][0]) + Fraction(1, 7))

    failed = refusals(edited(sos_region, change_rho))
    assert any(name == "roa" and "decrease" in message for name, message in failed), failed


def test_a_loop_with_a_constant_root_gets_a_level_of_its_linearization_that_the_exact_check_accepts() -> None:
    """The two-machine power loop's recasting holds the constant root ``rt3`` (``rt3^2 = 3``): the level
    program (the polynomial one with the relations' multipliers) puts it in its bases, so the linearization's
    V gets a level, and its certificate passes the check verify runs, at that level and not at twice it."""
    from lyapcheck.models.classes import recast_classes as rc
    from lyapcheck.models.classes import regions
    from lyapcheck.models.engines.recast_sos import ConditionCertificate, check_condition
    from lyapcheck.models.engines.search import Budget, Search
    from lyapcheck.models.language.modelfile import parse_any_model
    from lyapcheck.models.classes.recast_regions import proved_loop
    from lyapcheck.sos.polynomials import to_fmpq

    path = MODELS / "recast-power-two-machine.toml"
    loop = proved_loop(parse_any_model(path.read_text(), str(path)), 60)  # type: ignore[arg-type]
    assert loop.roots()
    V0 = rc.quadratic_candidate(loop, rc.jacobian(loop))  # type: ignore[arg-type]
    assert V0 is not None
    found = regions.certify_region(loop, V0, Search(loop.ring, Budget(60, "test")), "the linearization")
    assert not isinstance(found, str), found
    ring = loop.ring
    N, _, _ = rc.common_denominator(loop, rc.v_names(loop, V0))
    F = -rc.lie(loop, V0, N) - rc.state_square(loop) * to_fmpq(Fraction(found.certificate["epsilon"]))
    decrease = ConditionCertificate.from_json(ring, found.certificate["decrease"], len(loop.relations))
    assert check_condition(ring, F, loop.relations, decrease, region=V0 - to_fmpq(found.level))[0]
    assert not check_condition(ring, F, loop.relations, decrease, region=V0 - to_fmpq(2 * found.level))[0]
