"""roa's quadratic ball (issue 30): a level of the linearization's V proved by norm bounds, so that
every locally exponentially stable equilibrium gets a certified set, at any number of states."""

from __future__ import annotations

import json
from fractions import Fraction
from pathlib import Path

import pytest
from click.testing import CliRunner, Result

from lyapcheck.cli import app
from lyapcheck.sos.certificates import GramPoly, check_quadratic_ball, sphere_bound
from lyapcheck.sos.polynomials import Ring

app._register_commands()


def run_cli(*args: str) -> Result:
    return CliRunner().invoke(app.cli, list(args))


def test_sphere_bound_is_the_maximum_of_the_monomial_on_the_sphere() -> None:
    # x^2 y on x^2 + y^2 = 1: the maximum 2 / (3 sqrt 3) = 0.3849 at x^2 = 2/3
    k = sphere_bound((2, 1))
    assert Fraction(3849, 10000) < k < Fraction(3850, 10000)
    assert sphere_bound((3, 0)) == 1
    assert sphere_bound((1, 1)) >= Fraction(1, 2) and sphere_bound((1, 1)) - Fraction(1, 2) < Fraction(1, 10**5)


def test_cubic_scalar_ball_reaches_the_true_region_of_attraction() -> None:
    # x' = -x + x^3: V = x^2, L = -1, M = 2, h = x^3; the bound 4 r^2 > 4 r^6 holds for r < 1,
    # and the true region of attraction is (-1, 1)
    ring = Ring(("x",))
    (x,) = ring.gens()
    g = [-x + x * x * x]
    V = GramPoly.of([(1,)], [[Fraction(1)]])
    one = Fraction(1)
    assert check_quadratic_ball(ring, g, V, Fraction(99, 100) ** 2, Fraction(99, 100), one, one, Fraction(2))[0]
    ok, why = check_quadratic_ball(ring, g, V, one, one, one, one, Fraction(2))
    assert not ok and "radius is too large" in why
    # every stated bound is checked: P <= p_bar I with p_bar below P, a level beyond lam r^2
    assert not check_quadratic_ball(ring, g, V, Fraction(1, 4), Fraction(1, 2), one, Fraction(1, 2), Fraction(2))[0]
    assert not check_quadratic_ball(ring, g, V, Fraction(1, 2), Fraction(1, 2), one, one, Fraction(2))[0]
    assert not check_quadratic_ball(ring, g, V, Fraction(1, 4), Fraction(1, 2), one, one, Fraction(3))[0]


def _chain(n: int, path: Path) -> Path:
    """n / 2 reversed Van der Pol oscillators in a ring, each pushed by the next: LES, not GAS."""
    states = [f"x{i}" for i in range(1, n + 1)]
    lines = ["[model]", f'name = "vdp-chain-{n}"', "states = [" + ", ".join(f'"{s}"' for s in states) + "]",
             "[dynamics]"]
    for j in range(n // 2):
        a, b, c = states[2 * j], states[2 * j + 1], states[(2 * j + 2) % n]
        lines += [f'{a} = "-{b}"', f'{b} = "{a} - (1 - {a}**2)*{b} + 0.1*{c}"']
    path.write_text("\n".join(lines) + "\n")
    return path


@pytest.mark.slow
def test_ten_state_les_system_gets_a_certified_set_that_verify_rechecks(tmp_path: Path) -> None:
    model = _chain(10, tmp_path / "chain.toml")
    out = tmp_path / "chain.json"
    result = run_cli("certify", str(model), "--classes", "roa", "--out", str(out))
    assert result.exit_code == 0, result.output
    doc = json.loads(out.read_text())
    roa = doc["conditions"]["roa"]
    assert roa["status"] == "certified" and roa["certificate"]["kind"] == "quadratic_ball"
    assert roa["ball_radius"] > 0.1  # measured 0.160
    assert run_cli("verify", str(out)).exit_code == 0
    # a level beyond the proved one (radius and level tripled) fails the re-check
    cert = roa["certificate"]
    cert["radius_scaled"] = str(Fraction(cert["radius_scaled"]) * 3)
    cert["level_scaled"] = cert["level"] = str(Fraction(cert["level_scaled"]) * 9)
    roa["level"] = float(Fraction(cert["level"]))
    forged = tmp_path / "forged.json"
    forged.write_text(json.dumps(doc))
    result = run_cli("verify", str(forged))
    assert result.exit_code == 1 and "radius is too large" in result.output


def test_candidate_level_without_a_sampled_boundary_is_found_upwards_by_sos(tmp_path: Path) -> None:
    # x' = -x + x^3/1000, V = x^2: V' >= 0 only where x^2 >= 1000, far beyond the sampled region
    # (4 scales); the exact largest level is 1000, which the SOS lower bounds approach from below
    model = tmp_path / "far.toml"
    model.write_text('[model]\nname = "far"\nstates = ["x"]\n[dynamics]\nx = "-x + x**3/1000"\n')
    out = tmp_path / "far.json"
    result = run_cli("certify", str(model), "--classes", "candidate", "--candidate", "x**2", "--out", str(out))
    assert result.exit_code == 0, result.output
    cand = json.loads(out.read_text())["conditions"]["candidate"]
    assert cand["status"] == "certified"
    assert 990 <= Fraction(cand["certificate"]["level"]) <= 1000
    assert run_cli("verify", str(out)).exit_code == 0
