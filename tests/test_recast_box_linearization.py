"""``linearization`` over a box on a loop with functions (issue 45, item 1): the Jacobian of every value of
the box built exactly on the loop recast with the box's parameters as bounded constants (the chain rule
through sin, sat, ...), decided and re-checked by the polynomial loops' box test (Hurwitz conditions,
exact Bernstein coefficients); ``not_applicable`` where a function's value or slope at the equilibrium is
not polynomial in the parameters over the box; and box sweeps of such a loop that store it.

The saturated pendulum (``examples/models/robot-pendulum-sat-pd.toml``): ``J = [[0, 1], [(m g l - kp) /
(m l^2), -(b + kd) / (m l^2)]]`` with the saturation inactive at the equilibrium, Hurwitz exactly when
``kp > m g l = 4.905`` and ``kd > -b = -0.1``.
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
from tests.conftest import ROOT

PENDULUM = ROOT / "examples" / "models" / "robot-pendulum-sat-pd.toml"
MGL = Fraction(4905, 1000)  # m g l: the gain kp above which the upright pendulum is stable
app._register_commands()
RUNNER = CliRunner()


def certify(model: Path, out: Path, *boxes: str) -> tuple[int, dict[str, Any]]:
    args = ["certify", str(model), "--classes", "linearization", "--no-store", "--json", "--out", str(out)]
    for b in boxes:
        args += ["--box", b]
    done = RUNNER.invoke(app.cli, args)
    assert done.exit_code in (0, 1), done.output
    return done.exit_code, json.loads(done.output)


def verify(doc: dict[str, Any], path: Path) -> Any:
    path.write_text(json.dumps(doc))
    return RUNNER.invoke(app.cli, ["verify", str(path)])


def test_the_saturated_pendulum_is_les_for_every_gain_of_the_box_and_verify_rejects_a_tampered_certificate(
        tmp_path: Path) -> None:
    out = tmp_path / "cert.json"
    code, doc = certify(PENDULUM, out, "kp=15..25", "kd=3..5")
    lin = doc["conditions"]["linearization"]
    assert code == 0 and lin["status"] == "certified", lin
    assert lin["certificate"]["method"] == "box_hurwitz" and lin["certificate"]["conditions"] == ["Delta_1", "a_2"]
    assert lin["summary"].startswith("for every kp in [15, 25] and kd in [3, 5]: the Jacobian")
    assert doc["answers"]["stability"]["answer"] == "local"
    # J(u) is the true Jacobian at every value: kp = 20 + 5 u1, kd = 4 + u2, m l^2 = 1/4
    J = lin["certificate"]["jacobian"]
    omega_row = {tuple(m): Fraction(c) for c, m in J[1][0]}, {tuple(m): Fraction(c) for c, m in J[1][1]}
    assert omega_row == ({(0, 0): (MGL - 20) * 4, (1, 0): Fraction(-20)},
                         {(0, 0): -(Fraction(1, 10) + 4) * 4, (0, 1): Fraction(-4)})
    done = RUNNER.invoke(app.cli, ["verify", str(out)])
    assert done.exit_code == 0, done.output
    # the same certificate stated for a box that reaches unstable gains: verify proves again, and fails
    widened = json.loads(out.read_text())
    widened["box"]["kp"] = ["3", "25"]
    widened["overrides"]["kp"] = widened["parameters"]["kp"] = "14"  # (read at the stated box's centre)
    claim = widened["conditions"]["linearization"]
    claim["summary"] = claim["summary"].replace("kp in [15, 25]", "kp in [3, 25]")
    # the Jacobian of the wider box (kp = 14 + 11 u1), so that the proof itself is run again, and fails
    claim["certificate"]["jacobian"][1][0] = [[str((MGL - 14) * 4), [0, 0]], ["-44", [1, 0]]]
    done = verify(widened, tmp_path / "widened.json")
    assert done.exit_code == 1 and "the Hurwitz conditions are not proved on the box" in done.output, done.output
    # a Jacobian that is not the model's
    tampered = json.loads(out.read_text())
    tampered["conditions"]["linearization"]["certificate"]["jacobian"][1][0][0][0] = "-70"
    done = verify(tampered, tmp_path / "tampered.json")
    assert done.exit_code == 1 and "differs from the model's" in done.output, done.output


def test_a_box_with_an_unstable_corner_is_refuted_at_that_point_and_verified(tmp_path: Path) -> None:
    out = tmp_path / "cert.json"
    code, doc = certify(PENDULUM, out, "kp=3..7", "kd=3..5")
    lin = doc["conditions"]["linearization"]
    assert code == 1 and lin["status"] == "refuted" and doc["verdict"] == "unstable", lin
    point = {k: Fraction(v) for k, v in lin["refutation"]["point"].items()}
    assert point["kp"] < MGL and 3 <= point["kd"] <= 5  # truly unstable there (det J < 0: a saddle)
    assert lin["summary"].startswith(f"at kp = {float(point['kp']):g}, kd = {float(point['kd']):g}, a value of the "
                                     "box, the Jacobian has an eigenvalue with positive real part")
    assert RUNNER.invoke(app.cli, ["verify", str(out)]).exit_code == 0
    moved = json.loads(out.read_text())
    moved["conditions"]["linearization"]["refutation"]["point"] = {"kp": "8", "kd": "4"}  # outside the box
    done = verify(moved, tmp_path / "moved.json")
    assert done.exit_code == 1 and "not in the box" in done.output, done.output


def test_a_box_whose_edge_is_the_stability_boundary_is_not_certified_naming_the_point(tmp_path: Path) -> None:
    code, doc = certify(PENDULUM, tmp_path / "cert.json", "kp=4.905..7", "kd=3..5")
    lin = doc["conditions"]["linearization"]
    assert code == 1 and lin["status"] == "not_certified", lin  # at kp = m g l: an eigenvalue 0, critical
    assert "a_2" in lin["summary"] and "kp = 4.905" in lin["summary"]


def _model(tmp_path: Path, rhs: str, p: str) -> Path:
    path = tmp_path / "m.toml"
    path.write_text(f'[model]\nname = "u"\nstates = ["x"]\n[parameters]\np = {p}\n[dynamics]\nx = "{rhs}"\n')
    return path


@pytest.mark.parametrize(("rhs", "p", "box", "status", "words"), [
    ("-2*x + x*sat(p, 1)", "1", "p=0..0.5", "certified", ""),  # J = p - 2
    ("-2*x + x*sat(p, 1)", "1", "p=1.5..2", "certified", ""),  # saturated: J = -1
    ("-2*x + x*sat(p, 1)", "1", "p=0.5..1.5", "not_applicable", "strictly inside (or strictly beyond) the limits +-1"),
    ("-x*abs(p)", "1", "p=-1..-0.5", "certified", ""),  # J = p
    ("-x*abs(p)", "1", "p=-1..1", "not_applicable", "abs(p): its argument at the equilibrium is not proved of one"),
    ("-2*x + x*cos(p)", "0", "p=-0.5..0.5", "not_applicable", "cos(p): its argument at the equilibrium is not 0"),
])
def test_a_function_whose_value_at_the_equilibrium_is_not_polynomial_over_the_box_is_not_applicable(
        tmp_path: Path, rhs: str, p: str, box: str, status: str, words: str) -> None:
    code, doc = certify(_model(tmp_path, rhs, p), tmp_path / "cert.json", box)
    lin = doc["conditions"]["linearization"]
    assert lin["status"] == status and words in lin["summary"], lin
    assert (code == 0) is (status == "certified")
    if status == "certified":
        assert RUNNER.invoke(app.cli, ["verify", str(tmp_path / "cert.json")]).exit_code == 0


SWEEP = """[sweep]
model = "m.toml"
mode = "boxes"
classes = ["linearization"]
chunk_size = 2
[[sweep.axes]]
name = "kp"
start = 2
stop = 10
num = 3
[sweep.boxes]
max_boxes = 6
min_relative_width = 0.01
cross_check_points = 1
[simulation]
starts = 2
"""


def test_a_box_sweep_of_the_saturated_pendulum_proves_les_on_the_stable_gains_and_splits_a_refuted_box(
        tmp_path: Path) -> None:
    from sweeps.schema import BOX_STATUS_CODES
    from tests.test_model_sweeps import arrays, run
    from tests.test_recast_sweep import write

    out = tmp_path / "out.zarr"
    run(write(tmp_path, SWEEP, PENDULUM.read_text()), out)
    data = arrays(out)
    done = np.asarray(data["done"], bool)
    status, lo, hi = (np.asarray(data[k])[done] for k in ("status", "lo_kp", "hi_kp"))
    corners = np.asarray(data["unstable_corners"])[done]
    certified = status == BOX_STATUS_CODES["certified"]
    assert certified.any() and np.all(lo[certified] >= float(MGL))  # only stable gains, every one of the box
    refuted = status == BOX_STATUS_CODES["refuted"]
    assert np.all(lo[refuted] < float(MGL))
    # [2, 6] holds kp = m g l: refuted, one of its two corners unstable, so it is split (and its stable part proved)
    split = status == BOX_STATUS_CODES["split"]
    assert split.any() and np.all(corners[split] == 1)
    assert np.any(certified & (lo < 6))
    # a stored certificate is verified as certify's own
    j = int(np.flatnonzero(done)[np.flatnonzero(certified)[0]])
    doc = json.loads(str(np.asarray(data["certificate"])[j]))
    assert RUNNER.invoke(app.cli, ["verify", str(_write(tmp_path / "stored.json", doc))]).exit_code == 0


def _write(path: Path, doc: dict[str, Any]) -> Path:
    path.write_text(json.dumps(doc))
    return path
