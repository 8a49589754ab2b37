"""The simulation cross-check of a certified region cries "soundness violation" only when it is
conclusive (issue 40, item 7): a start of the set whose trajectory leaves the set (the set is
invariant under its certificate), or one that stays outside a small ball longer than the
certificate's own decrease allows. A trajectory still converging slowly is counted as not checked.

A correct region of a slowly damped pendulum is certified without an alarm; wrong certificates fed
to the same cross-checks (a set that is not invariant, a decrease rate the loop does not have, a
level tripled beyond the region of attraction) still raise one.
"""

from __future__ import annotations

import dataclasses
import json
from fractions import Fraction
from pathlib import Path
from typing import Any

import pytest
from click.testing import CliRunner

from lyapcheck.cli import app
from lyapcheck.models.classes import recast_classes as rc
from lyapcheck.models.language.modelfile import parse_any_model
from lyapcheck.models.classes.recast_regions import comparison_box, simulated_check
from lyapcheck.models.engines.recast_sos import poly_to_json
from lyapcheck.results import ConditionResult
from tests.recast_loops import LOSSLESS as LOSSLESS_LOOP

app._register_commands()

EXAMPLES = Path(__file__).resolve().parents[1] / "examples" / "models"

#: the lossless pendulum (tests/recast_loops.py) over a domain
LOSSLESS = LOSSLESS_LOOP + """[domain]
theta = [-3, 3]
omega = [-3, 3]
"""


def certify_json(*args: str) -> tuple[int, dict[str, Any], str]:
    result = CliRunner().invoke(app.cli, ["certify", *args, "--json"])
    return result.exit_code, json.loads(result.stdout), result.stderr


def forged(loop: Any, V: Any, level: str, **extra: str) -> ConditionResult:
    """A region result whose certificate was never proved (for the cross-check alone)."""
    certificate = {"kind": "recast", "V": poly_to_json(loop.ring, V), "level": level, **extra}
    return ConditionResult("roa", "certified", "forged for the test", certificate=certificate, property="ROA")


def test_slowly_damped_pendulum_region_is_certified_without_an_alarm() -> None:
    # b = 0.02: trajectories of the certified set take about 800 s to converge, longer than the
    # cross-check simulates; none leaves the set, so none is a violation
    code, doc, stderr = certify_json(str(EXAMPLES / "recast-pendulum.toml"), "--set", "b=0.02", "--classes", "roa")
    roa = doc["conditions"]["roa"]
    assert roa["status"] == "certified"
    assert "soundness_violation" not in roa and "SOUNDNESS VIOLATION" not in stderr
    assert code == 0
    assert roa["starts_left_set"] == 0
    assert roa["starts_not_checked_slow_convergence"] > 0
    assert roa["starts_not_checked_slow_convergence"] <= roa["starts_in_set_not_converged"]


def test_a_set_that_is_not_invariant_raises_the_alarm() -> None:
    # {omega^2 <= 1/4} is no region of attraction: from (theta, omega) = (2, 0) gravity speeds the
    # pendulum past |omega| = 1/2, so its trajectory leaves the set
    model = parse_any_model((EXAMPLES / "recast-pendulum.toml").read_text(), "pendulum.toml", {"b": "0.02"})
    loop = rc.base_loop(model.system)
    omega = loop.ring.gen("omega")
    wrong = forged(loop, omega * omega, "1/4")
    simulated_check(loop, wrong, comparison_box(model, loop))
    assert wrong.numbers.get("soundness_violation") is True
    assert wrong.numbers["starts_left_set"] > 0


def test_a_decrease_the_loop_does_not_have_raises_the_alarm() -> None:
    # the energy's sublevel set IS invariant for the lossless pendulum (no start leaves it), but
    # nothing converges; a certificate claiming V' <= -10 |z|^2 forces every start into the small
    # ball within V(0) / (10 r^2) <= 12.5 time units, far below the cross-check's horizon (a small
    # level: a few starts)
    model = parse_any_model(LOSSLESS, "lossless.toml")
    loop = rc.base_loop(model.system)
    ring = loop.ring
    omega, c = ring.gen("omega"), ring.gen("c1")
    energy = omega * omega * ring.constant(Fraction(1, 2)) - c  # 1 - cos(theta) + omega^2 / 2, in deviations
    wrong = forged(loop, energy, "1/20", epsilon="10", denominator=poly_to_json(ring, ring.constant(1)))
    simulated_check(loop, wrong, comparison_box(model, loop))
    assert wrong.numbers["starts_left_set"] == 0
    assert wrong.numbers.get("starts_past_certified_convergence_time", 0) > 0
    assert wrong.numbers.get("soundness_violation") is True
    # the same set without a decrease rate: nothing conclusive, so no alarm
    honest = forged(loop, energy, "1/20")
    simulated_check(loop, honest, comparison_box(model, loop))
    assert "soundness_violation" not in honest.numbers
    assert honest.numbers["starts_not_checked_slow_convergence"] > 0


def test_a_tripled_level_raises_the_alarm_on_a_polynomial_loop(monkeypatch: pytest.MonkeyPatch) -> None:
    # the reversed Van der Pol's region is bounded by an unstable limit cycle: the certified level
    # tripled takes in starts beyond it, whose trajectories leave the set
    from lyapcheck.models.classes import regions

    enlarge = regions.enlarge

    def tripled(*args: Any, **kwargs: Any) -> Any:
        outcome = enlarge(*args, **kwargs)
        assert outcome.certificate is not None
        return dataclasses.replace(outcome, certificate=dataclasses.replace(outcome.certificate,
                                                                            level=3 * outcome.certificate.level))

    monkeypatch.setattr(regions, "enlarge", tripled)
    code, doc, stderr = certify_json(str(EXAMPLES / "van-der-pol-reversed.toml"), "--classes", "roa")
    roa = doc["conditions"]["roa"]
    assert roa.get("soundness_violation") is True and roa["starts_left_set"] > 0
    assert code == 1 and "SOUNDNESS VIOLATION" in stderr
