"""Discrete-time maps with functions (issue 44, item 1): read by the recasting of continuous loops (its
displacement ``F(x) - x``), ``linearization`` by the exact Jacobian through the functions, ``roa`` by ball
arithmetic on the true map (:mod:`lyapcheck.models.classes.discrete_functions`).

What is asserted: a map with ``sin`` and ``tanh`` has its fixed point checked exactly (a point that is not one
is refused in one line, exit 2); its Jacobian is the chain rule's, exactly; ``linearization`` is certified on
a contracting map and refuted on one whose Jacobian has determinant 3/2; ``roa`` is certified within the
search's cell budget, every sampled start in the certified set converges when the map is iterated, ``verify``
re-proves it, and a level raised 64-fold fails ``verify``; ``abs`` at the fixed point makes ``roa``
``not_applicable`` naming it, while ``linearization`` proves LES from the piecewise-linear step form; the other classes are ``not_applicable`` in one line; the Yin-Seiler-Arcak
pendulum (slow) certifies a set larger than any ellipsoid their LMI's constraints allow.
"""

from __future__ import annotations

import json
import math
from fractions import Fraction
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from click.testing import CliRunner

from lyapcheck.cli import app
from lyapcheck.models.classes import discrete_functions as dfn
from lyapcheck.models.language.modelfile import parse_any_model

app._register_commands()

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"

MAP = '''[model]
name = "a small map with sin and tanh"
states = ["x", "y"]
time = "discrete"

[parameters]
a = {a}

[dynamics]
x = "y"
y = "-a*sin(x) + 0.25*tanh(y)"
'''


def cli(*args: str) -> Any:
    done = CliRunner().invoke(app.cli, list(args))
    assert done.exception is None or isinstance(done.exception, SystemExit), done.output
    assert "Traceback" not in done.output
    return done


def write(tmp: Path, name: str, text: str) -> Path:
    path = tmp / name
    path.write_text(text)
    return path


def step(x: float, y: float, a: float) -> tuple[float, float]:
    return y, -a * math.sin(x) + 0.25 * math.tanh(y)


def test_the_jacobian_is_the_chain_rule_exactly() -> None:
    model = parse_any_model(MAP.format(a="0.5"))
    assert model.time == "discrete"
    assert dfn.exact_jacobian(model) == [[0, 1], [Fraction(-1, 2), Fraction(1, 4)]]


@pytest.mark.parametrize(("a", "status"), [("0.5", "certified"), ("1.5", "refuted")])
def test_linearization_is_decided_exactly(a: str, status: str) -> None:
    result = dfn.linearization(parse_any_model(MAP.format(a=a)))
    assert result.status == status, result.summary


def test_a_point_that_is_not_fixed_is_refused_in_one_line(tmp_path: Path) -> None:
    text = MAP.format(a="0.5").replace('"-a*sin(x) + 0.25*tanh(y)"', '"-a*sin(x) + 0.25*tanh(y) + 1"')
    done = cli("certify", str(write(tmp_path, "m.toml", text)), "--no-store")
    assert done.exit_code == 2
    assert "[equilibrium]: is not a fixed point of the map: y+ - y = 1 there" in done.output
    assert len(done.output.strip().splitlines()) == 1


def test_abs_at_the_fixed_point_is_named_and_linearization_is_piecewise_linear(tmp_path: Path) -> None:
    """x+ = |x|/2: no Jacobian at 0; linearization proves LES from the step form (the piecewise-linear route),
    roa names the kink (it starts from a Jacobian)."""
    text = '[model]\nname = "m"\nstates = ["x"]\ntime = "discrete"\n[dynamics]\nx = "0.5*abs(x)"\n'
    out = tmp_path / "abs.json"
    done = cli("certify", str(write(tmp_path, "abs.toml", text)), "--classes", "linearization,roa,sos_bound",
               "--no-store", "--json", "--out", str(out))
    assert done.exit_code == 0, done.output  # (the verdict certified_local)
    conditions = json.loads(out.read_text())["conditions"]
    assert conditions["linearization"]["status"] == "certified"
    assert conditions["linearization"]["certificate"]["kind"] == "piecewise_linear"
    assert conditions["linearization"]["certificate"]["discrete"] is True
    assert conditions["roa"]["status"] == "not_applicable"
    assert "abs is not differentiable" in conditions["roa"]["summary"]
    assert cli("verify", str(out)).exit_code == 0
    # (sos_bound is taken on a map with functions: this one has no [disturbances] to bound)
    from lyapcheck.models.engines.reasons import NO_DISTURBANCES

    assert conditions["sos_bound"]["status"] == "not_applicable"
    assert conditions["sos_bound"]["summary"] == NO_DISTURBANCES
    # quadratic needs no derivative: V = x^2 with V(F) = V/4 on the relations of b = |x| (b^2 = x^2), GES
    done = cli("certify", str(write(tmp_path, "abs.toml", text)), "--classes", "quadratic", "--no-store",
               "--out", str(out))
    assert done.exit_code == 0, done.output
    quadratic = json.loads(out.read_text())["conditions"]["quadratic"]
    assert quadratic["status"] == "certified" and quadratic["property"] == "GES"
    assert Fraction(quadratic["certificate"]["r"]) ** 2 >= Fraction(1, 4)  # no faster than the map's true 1/2


@pytest.fixture(scope="module")
def certified(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, dict[str, Any]]:
    tmp = tmp_path_factory.mktemp("map")
    out = tmp / "map.json"
    done = cli("certify", str(write(tmp, "map.toml", MAP.format(a="0.5"))), "--classes", "linearization,roa",
               "--no-store", "--json", "--out", str(out))
    assert done.exit_code == 0, done.output
    return out, json.loads(out.read_text())


def test_roa_is_certified_and_its_set_converges(certified: tuple[Path, dict[str, Any]]) -> None:
    _, doc = certified
    roa = doc["conditions"]["roa"]
    assert roa["status"] == "certified", roa["summary"]
    cert = roa["certificate"]
    assert cert["kind"] == dfn.KIND
    assert roa["cells_spent"] <= dfn.tolerances.BALL_LEVEL_TOTAL_CELLS
    P = np.array([[float(Fraction(x)) for x in row] for row in cert["P"]])
    level = float(Fraction(cert["level"]))
    rng = np.random.default_rng(7)
    L = np.linalg.cholesky(np.linalg.inv(P))
    for _ in range(200):  # starts on and inside the boundary of {e^T P e <= level}
        u = rng.normal(size=2)
        e = L @ (u / np.linalg.norm(u)) * math.sqrt(level) * rng.uniform(0.5, 0.999)
        x, y = float(e[0]), float(e[1])
        for _ in range(400):
            x, y = step(x, y, 0.5)
            assert np.array([x, y]) @ P @ np.array([x, y]) <= level * (1 + 1e-9)  # forward invariant
        assert abs(x) + abs(y) < 1e-6


def test_simulate_iterates_the_true_map(tmp_path: Path) -> None:
    """``simulate`` of a map with functions iterates ``F`` itself (sin and tanh by numpy), never integrates its
    displacement as a field: its iterates are the hand-written map's, and a contracting map converges."""
    from lyapcheck.api import simulate

    path = write(tmp_path, "map.toml", MAP.format(a="0.5"))
    report = simulate(model=path, x0={"x": 0.4, "y": -0.3}, steps=30, series=True)
    xs = report.series["x"].values[0]  # (step, state)
    x, y = 0.4, -0.3
    for k in range(1, 31):
        x, y = step(x, y, 0.5)
        assert xs[k] == pytest.approx([x, y], abs=1e-12)
    assert not report.diverged and report.document["n_converged"] == 1
    done = cli("simulate", str(path), "--steps", "20", "--plot", str(tmp_path / "map.png"))
    assert done.exit_code == 0, done.output
    assert (tmp_path / "map.png").stat().st_size > 0


def test_verify_reproves_it_and_a_raised_level_fails(certified: tuple[Path, dict[str, Any]],
                                                     tmp_path: Path) -> None:
    path, doc = certified
    done = cli("verify", str(path))
    assert done.exit_code == 0, done.output
    assert "ok   roa: V(F(e)) < V(e) proved again" in done.output
    cert = doc["conditions"]["roa"]["certificate"]
    tampered = json.loads(json.dumps(doc))
    tampered["conditions"]["roa"]["certificate"]["level"] = str(Fraction(cert["level"]) * 64)
    bad = tmp_path / "tampered.json"
    bad.write_text(json.dumps(tampered))
    done = cli("verify", str(bad))
    assert done.exit_code == 1, done.output
    assert "FAIL roa" in done.output


@pytest.mark.slow
def test_the_yin_seiler_arcak_pendulum(tmp_path: Path) -> None:
    """Their ellipsoid {x^T P x <= 1} satisfies |theta| <= 2.5 and |W1_i x| <= 1/2 for every first-layer
    neuron (their LMI's constraints), so it lies in each parallelogram {|theta| <= 2.5, |W1_i x| <= 1/2},
    whose largest inscribed ellipse has pi/4 of its area 5 / |W1_i2|: ours must be larger than the least."""
    out = tmp_path / "ysa.json"
    done = cli("certify", str(EXAMPLES / "models" / "ysa-pendulum.toml"), "--classes", "linearization,roa",
               "--no-store", "--json", "--out", str(out))
    assert done.exit_code == 0, done.output
    doc = json.loads(out.read_text())
    assert doc["conditions"]["linearization"]["status"] == "certified"
    roa = doc["conditions"]["roa"]
    assert roa["status"] == "certified", roa["summary"]
    W1 = np.load(EXAMPLES / "networks" / "ysa_pendulum_tanh.npz", allow_pickle=False)["W1"]
    theirs = min(math.pi / 4 * 5 / abs(float(w)) for w in W1[:, 1])
    P = [[Fraction(x) for x in row] for row in roa["certificate"]["P"]]
    ours = dfn.area(P, Fraction(roa["certificate"]["level"]))
    assert ours is not None and ours > theirs
