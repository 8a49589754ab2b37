"""``sos_gas`` over a box in the vertex form (issue 45, item 1): ``V`` affine in the box's parameters, its
derivative multi-affine in them, both proved at the box's vertices; the exact check and ``verify``."""

from __future__ import annotations

import copy
import json
from fractions import Fraction
from pathlib import Path
from typing import Any

import pytest
from click.testing import CliRunner

from lyapcheck.api import verify
from lyapcheck.cli import app
from lyapcheck.sos.certificates import GramPoly, box_vertices, check_lyapunov_vertices
from lyapcheck.sos.polynomials import Ring

ROOT = Path(__file__).resolve().parents[1]
PID = ROOT / "examples" / "models" / "pid-hardening-spring.toml"  # GAS exactly when ki < 1.5 kp
app._register_commands()
RUNNER = CliRunner()
F = Fraction


def gram(*diagonal: int) -> GramPoly:
    """``sum_i d_i z_i^2`` over the ring (x, u): the basis is ``x`` alone."""
    return GramPoly.of([(1, 0)], [[F(diagonal[0])]])


def test_the_vertex_check_accepts_a_multi_affine_identity_and_refuses_what_the_vertices_do_not_bound() -> None:
    ring = Ring(("x", "u"))
    x, u = ring.gens()
    g = [-(2 + u) * x]  # x' = -k x with k = 2 + u in [1, 3]
    D = ring.constant(1)
    assert box_vertices(ring, 1) == [(-1,), (1,)]
    # V = x^2: -V' = 2 (2 + u) x^2, 2 x^2 at u = -1 and 6 x^2 at u = 1
    ok, why = check_lyapunov_vertices(ring, g, D, x * x, [gram(1), gram(1)], [gram(2), gram(6)], F(0))
    assert ok, why
    # the rate: V' = -2 k V <= -2 V on the box; mu = 2 leaves 0 x^2 at u = -1 (not positive definite)
    ok, why = check_lyapunov_vertices(ring, g, D, x * x, [gram(1), gram(1)], [gram(1), gram(5)], F(1))
    assert ok, why
    assert not check_lyapunov_vertices(ring, g, D, x * x, [gram(1), gram(1)], [gram(0), gram(4)], F(2))[0]
    # a remainder that is not -V' at its vertex
    ok, why = check_lyapunov_vertices(ring, g, D, x * x, [gram(1), gram(1)], [gram(2), gram(5)], F(0))
    assert not ok and "vertex [1]" in why
    # V = (1 + u/2) x^2 depends on u where g does: -V' = (2 + u)(2 + u) x^2 has a u^2 term, so its vertex
    # values do not bound it (they happen to be positive here, but the check must not rely on that)
    v = (1 + u / 2) * x * x
    ok, why = check_lyapunov_vertices(ring, g, D, v, [GramPoly.of([(1, 0)], [[F(1, 2)]]), GramPoly.of([(1, 0)], [[F(3, 2)]])],
                                      [gram(1), gram(9)], F(0))
    assert not ok and "multi-affine" in why
    # one Gram matrix per vertex, no more, no fewer
    assert not check_lyapunov_vertices(ring, g, D, x * x, [gram(1)], [gram(2)], F(0))[0]


@pytest.fixture(scope="module")
def pid_box(tmp_path_factory: pytest.TempPathFactory) -> tuple[int, dict[str, Any]]:
    out = tmp_path_factory.mktemp("vertices") / "cert.json"
    done = RUNNER.invoke(app.cli, ["certify", str(PID), "--box", "kp=1.5..2.5", "--box", "ki=0.5..1.5",
                                   "--classes", "sos_gas", "--no-store", "--out", str(out), "--json"])
    return done.exit_code, json.loads(out.read_text())


def test_the_pid_loop_is_proved_gas_on_a_box_inside_its_stable_region(pid_box: tuple[int, dict[str, Any]]) -> None:
    code, doc = pid_box
    c = doc["conditions"]["sos_gas"]
    assert code == 0 and c["status"] == "certified" and c["property"] == "GAS", c["summary"]
    cert = c["certificate"]
    assert cert["form"] == "vertices" and len(cert["gram_V_vertices"]) == len(cert["gram_sigma_vertices"]) == 4
    # V depends on the gains, never on v (the state whose right-hand side holds them), and linearly
    names = doc["states"] + list(doc["box"])
    for _, m in cert["V"]["terms"]:
        powers = dict(zip(names, m))
        assert powers["kp"] + powers["ki"] <= 1 and (powers["kp"] + powers["ki"] == 0 or powers["v"] == 0)
    assert any(m[3] + m[4] for _, m in cert["V"]["terms"])
    assert verify(doc).valid


def test_verify_refuses_a_tampered_vertex_certificate(pid_box: tuple[int, dict[str, Any]]) -> None:
    _, doc = pid_box
    bad = copy.deepcopy(doc)
    Q = bad["conditions"]["sos_gas"]["certificate"]["gram_sigma_vertices"][2]["Q"]
    Q[0][0] = str(F(Q[0][0]) + F(1, 10**6))
    assert not verify(bad).valid
    bad = copy.deepcopy(doc)
    bad["conditions"]["sos_gas"]["certificate"]["gram_V_vertices"].pop()
    assert not verify(bad).valid
    bad = copy.deepcopy(doc)  # the box widened into the unstable region: the field at the vertices changes
    bad["box"]["ki"] = ["1/2", "4"]
    assert not verify(bad).valid
