"""``candidate`` and ``--box`` on a discrete-time map with functions (issue 44, item 1;
:mod:`lyapcheck.models.classes.discrete_functions`, :mod:`lyapcheck.models.classes.discrete_functions_box`).

The map is examples/models/discrete-tanh-gain-map.toml, ``x+ = y``, ``y+ = -x/2 + k tanh(y)``: its Jacobian at the
origin is ``[[0, 1], [-1/2, k]]``, Schur stable exactly when ``|k| < 3/2``.

What is asserted: the user's quadratic V is certified with a level, every sampled start in the set stays in it
and converges when the map is iterated, and ``verify`` re-proves it; a certificate whose P is not the
candidate's (even a P whose level is true) or whose level is raised fails ``verify``; a candidate that is not
a quadratic form is ``not_applicable`` saying so, one whose P is not positive definite ``not_certified``
saying so. Over ``--box k=0.6..0.95`` ``linearization`` and ``roa`` are certified for every k and ``verify``
re-derives them, every sampled k of the box has its iterates stay in the set; a document whose roa level is
raised, or whose box is widened, fails; over ``k=0.5..1.1``, which the centre's P does not cover, the P proved
is another that decreases at every sampled k; a box reaching unstable gains certifies nothing; a box moving the
fixed point exits 2 in one line; the ball-matrix Stein test refuses a box holding an unstable Jacobian.
"""

from __future__ import annotations

import json
import math
from fractions import Fraction
from pathlib import Path
from typing import Any

import flint
import numpy as np
import pytest
from click.testing import CliRunner

from lyapcheck.cli import app
from lyapcheck.models.classes import discrete_functions_box as dbox

app._register_commands()

MAP = Path(__file__).resolve().parents[1] / "examples" / "models" / "discrete-tanh-gain-map.toml"
#: a quadratic V that decreases to first order at k = 0.8 (A^T P A - P has eigenvalues about -1.12 and -0.92)
GOOD = "2*x**2 - 2*x*y + 4*y**2"


def cli(*args: str) -> Any:
    done = CliRunner().invoke(app.cli, list(args))
    assert done.exception is None or isinstance(done.exception, SystemExit), done.output
    assert "Traceback" not in done.output
    return done


def certify(tmp: Path, *args: str, path: Path = MAP) -> tuple[Any, dict[str, Any], Path]:
    out = tmp / "doc.json"
    done = cli("certify", str(path), "--no-store", "--json", "--out", str(out), *args)
    return done, (json.loads(out.read_text()) if out.exists() else {}), out


def step(x: float, y: float, k: float) -> tuple[float, float]:
    return y, -0.5 * x + k * math.tanh(y)


def starts_stay_and_converge(cert: dict[str, Any], ks: list[float], seed: int) -> None:
    """Starts inside and near the boundary of {e^T P e <= level}, iterated at each k: every iterate stays in the
    set and the orbit ends at the fixed point."""
    P = np.array([[float(Fraction(x)) for x in row] for row in cert["P"]])
    level = float(Fraction(cert["level"]))
    L = np.linalg.cholesky(np.linalg.inv(P))
    rng = np.random.default_rng(seed)
    for k in ks:
        for _ in range(60):
            u = rng.normal(size=2)
            e = L @ (u / np.linalg.norm(u)) * math.sqrt(level) * rng.uniform(0.5, 0.999)
            x, y = float(e[0]), float(e[1])
            for _ in range(600):
                x, y = step(x, y, k)
                assert np.array([x, y]) @ P @ np.array([x, y]) <= level * (1 + 1e-9)
            assert abs(x) + abs(y) < 1e-6


# -- candidate ---------------------------------------------------------------------------------------------

@pytest.fixture(scope="module")
def candidate_doc(tmp_path_factory: pytest.TempPathFactory) -> tuple[dict[str, Any], Path]:
    done, doc, out = certify(tmp_path_factory.mktemp("cand"), "--classes", "roa,candidate", "--candidate", GOOD)
    assert done.exit_code == 0, done.output
    return doc, out


def test_the_candidate_is_certified_with_a_level(candidate_doc: tuple[dict[str, Any], Path]) -> None:
    doc, out = candidate_doc
    c = doc["conditions"]["candidate"]
    assert c["status"] == "certified", c["summary"]
    cert = c["certificate"]
    assert cert["kind"] == "discrete_interval" and cert["V_from"] == "candidate"
    assert [[Fraction(x) for x in row] for row in cert["P"]] == [[2, -1], [-1, 4]]  # the candidate's own P
    assert Fraction(cert["level"]) > 0
    starts_stay_and_converge(cert, [0.8], seed=3)
    done = cli("verify", str(out))
    assert done.exit_code == 0, done.output
    assert "ok   candidate: V(F(e)) < V(e) proved again" in done.output


def _tampered(doc: dict[str, Any], tmp: Path, change: Any) -> Any:
    forged = json.loads(json.dumps(doc))
    change(forged)
    path = tmp / "forged.json"
    path.write_text(json.dumps(forged))
    return cli("verify", str(path))


def test_a_forged_candidate_certificate_fails_verify(candidate_doc: tuple[dict[str, Any], Path],
                                                     tmp_path: Path) -> None:
    doc, _ = candidate_doc
    roa = doc["conditions"]["roa"]["certificate"]

    def other_v(d: dict[str, Any]) -> None:  # the linearization's V and its (true) level, claimed as the user's
        d["conditions"]["candidate"]["certificate"].update(P=roa["P"], level=roa["level"])

    done = _tampered(doc, tmp_path, other_v)
    assert done.exit_code == 1, done.output
    assert "FAIL candidate" in done.output and "the stated P is not the candidate's" in done.output

    def raised(d: dict[str, Any]) -> None:
        cert = d["conditions"]["candidate"]["certificate"]
        cert["level"] = str(Fraction(cert["level"]) * 64)

    done = _tampered(doc, tmp_path, raised)
    assert done.exit_code == 1, done.output
    assert "FAIL candidate" in done.output

    def not_marked(d: dict[str, Any]) -> None:
        del d["conditions"]["candidate"]["certificate"]["V_from"]

    assert _tampered(doc, tmp_path, not_marked).exit_code == 1


@pytest.mark.parametrize(("text", "status", "words"), [
    ("x**4 + y**2", "not_applicable", "not a quadratic form"),
    ("sin(x)**2 + y**2", "not_applicable", "not a quadratic form"),
    ("x**2 - y**2", "not_certified", "not positive definite"),
    ("x**2 + 2*y**2", "not_certified", "was not proved"),  # positive definite, but no decrease to first order
])
def test_a_candidate_it_cannot_take_says_why(tmp_path: Path, text: str, status: str, words: str) -> None:
    done, doc, _ = certify(tmp_path, "--classes", "candidate", "--candidate", text)
    c = doc["conditions"]["candidate"]
    assert c["status"] == status, c["summary"]
    assert words in c["summary"]


# -- over a box -----------------------------------------------------------------------------------------------

@pytest.fixture(scope="module")
def box_doc(tmp_path_factory: pytest.TempPathFactory) -> tuple[dict[str, Any], Path]:
    done, doc, out = certify(tmp_path_factory.mktemp("box"), "--classes", "linearization,roa,quadratic",
                             "--box", "k=0.6..0.95")
    assert done.exit_code == 0, done.output
    return doc, out


@pytest.mark.slow
def test_a_stable_box_is_certified_and_verified(box_doc: tuple[dict[str, Any], Path]) -> None:
    doc, out = box_doc
    assert doc["box"] == {"k": ["3/5", "19/20"]}
    lin, roa = doc["conditions"]["linearization"], doc["conditions"]["roa"]
    assert lin["status"] == "certified", lin["summary"]
    assert lin["summary"].startswith("for every k in [0.6, 0.95]: ")
    assert lin["certificate"]["method"] == dbox.METHOD and lin["certificate"]["box_parts"] >= 1
    assert roa["status"] == "certified", roa["summary"]
    assert roa["certificate"]["parameter_box"] == doc["box"]
    starts_stay_and_converge(roa["certificate"], [0.6, 0.7, 0.8, 0.9, 0.95], seed=5)
    # no quadratic V is common to the gains k tanh(y)/y in [0, 0.95] (the relations' sector): not found, not claimed
    assert doc["conditions"]["quadratic"]["status"] == "not_certified"
    done = cli("verify", str(out))
    assert done.exit_code == 0, done.output
    assert "ok   linearization: A(p)^T P A(p) - P < 0 proved again" in done.output
    assert "ok   roa: V(F(e)) < V(e) proved again" in done.output


@pytest.mark.slow
def test_a_forged_box_document_fails_verify(box_doc: tuple[dict[str, Any], Path], tmp_path: Path) -> None:
    doc, _ = box_doc

    def raised(d: dict[str, Any]) -> None:
        cert = d["conditions"]["roa"]["certificate"]
        cert["level"] = str(Fraction(cert["level"]) * 64)

    done = _tampered(doc, tmp_path, raised)
    assert done.exit_code == 1 and "FAIL roa" in done.output, done.output

    def wider(d: dict[str, Any]) -> None:  # a box widened after the fact, still centred where the model is read
        d["box"] = {"k": ["17/40", "9/8"]}
        d["conditions"]["roa"]["certificate"]["parameter_box"] = d["box"]

    done = _tampered(doc, tmp_path, wider)
    assert done.exit_code == 1, done.output
    assert "FAIL linearization" in done.output


@pytest.fixture(scope="module")
def gas_doc(tmp_path_factory: pytest.TempPathFactory) -> tuple[dict[str, Any], Path]:
    done, doc, out = certify(tmp_path_factory.mktemp("gas"), "--classes", "quadratic,sos_gas,roa",
                             "--box", "k=0.6..0.85")
    assert done.exit_code == 0, done.output
    return doc, out


def test_quadratic_and_sos_gas_over_a_box_hold_for_every_value(gas_doc: tuple[dict[str, Any], Path]) -> None:
    """Over k in [0.6, 0.85] one V of the states decreases for every k (the box's parameter a bounded variable of
    the relations): GES with its figures, sos_gas GAS, roa not run (GAS for every value); iterated at sampled k
    from random starts V(F) <= (1 - mu) V holds, and ``verify`` re-checks both identities."""
    doc, out = gas_doc
    quad, gas = doc["conditions"]["quadratic"], doc["conditions"]["sos_gas"]
    assert quad["status"] == "certified" and quad["property"] == "GES", quad["summary"]
    assert quad["summary"].startswith("for every k in [0.6, 0.85]: GES of the discrete-time map")
    assert gas["status"] == "certified" and gas["property"] == "GAS", gas["summary"]
    assert doc["conditions"]["roa"]["status"] == "not_applicable"
    cert = quad["certificate"]
    assert cert["parameter_box"] == doc["box"] == {"k": ["3/5", "17/20"]} and "k" in cert["variables"]
    Q = cert["gram_V"]["Q"]
    assert [q[2:] for q in cert["gram_V"]["basis"]] == [[0, 0], [0, 0]]  # V of the states alone
    P = np.array([[float(Fraction(x)) for x in row] for row in Q])
    mu = float(Fraction(cert["mu"]))
    rng = np.random.default_rng(3)
    for k in np.linspace(0.6, 0.85, 11):
        for _ in range(50):
            e = rng.normal(size=2) * rng.choice([0.1, 1.0, 30.0])
            x, y = step(float(e[0]), float(e[1]), float(k))
            n = np.array([x, y])
            assert n @ P @ n <= (1 - mu) * (e @ P @ e) * (1 + 1e-9)
    done = cli("verify", str(out))
    assert done.exit_code == 0, done.output
    assert "ok   quadratic: Q_V > 0" in done.output and "ok   sos_gas: Q_V > 0" in done.output


def test_a_forged_quadratic_over_a_box_fails_verify(gas_doc: tuple[dict[str, Any], Path], tmp_path: Path) -> None:
    doc, _ = gas_doc

    def wider(d: dict[str, Any]) -> None:  # the same centre, a box reaching k = 0.975, where no such V exists
        d["box"] = {"k": ["19/40", "39/40"]}
        d["conditions"]["quadratic"]["certificate"]["parameter_box"] = d["box"]

    def changed_p(d: dict[str, Any]) -> None:
        gram = d["conditions"]["quadratic"]["certificate"]["gram_V"]
        gram["Q"][0][0] = str(Fraction(gram["Q"][0][0]) * 2)

    def elsewhere(d: dict[str, Any]) -> None:  # the certificate's box is not the document's
        d["conditions"]["quadratic"]["certificate"]["parameter_box"] = {"k": ["13/20", "4/5"]}

    for forge in (wider, changed_p, elsewhere):
        done = _tampered(doc, tmp_path, forge)
        assert done.exit_code == 1 and "FAIL quadratic" in done.output, (forge.__name__, done.output)


DISTURBED = Path(__file__).resolve().parents[1] / "examples" / "models" / "discrete-tanh-disturbed-map.toml"


@pytest.mark.slow
def test_sos_bound_over_a_box_holds_for_every_value(tmp_path: Path) -> None:
    """The disturbed tanh map with its gain a parameter k over [0.75, 0.85]: one V and one bound per output for
    every k (k a bounded variable of the relations, with the disturbance's); iterated at sampled k under random
    and bang-bang disturbances, the tail stays within the bounds; ``verify`` re-checks the identities, and a
    document whose box is widened or whose B is lowered fails."""
    model = tmp_path / "gain.toml"
    model.write_text(DISTURBED.read_text().replace("0.8*tanh(y) + d", "k*tanh(y) + d").replace(
        "[disturbances]", "[parameters]\nk = 0.8\n\n[disturbances]"))
    done, doc, out = certify(tmp_path, "--classes", "quadratic,sos_bound", "--box", "k=0.75..0.85", path=model)
    assert done.exit_code == 0, done.output
    quad = doc["conditions"]["quadratic"]  # (with d = 0: the box's words, then the disturbances')
    assert quad["status"] == "certified" and quad["summary"].startswith("for every k in [0.75, 0.85]: (d = 0) GES")
    c = doc["conditions"]["sos_bound"]
    assert c["status"] == "certified", c["summary"]
    assert c["summary"].startswith("for every k in [0.75, 0.85]: ") and c["certificate"]["parameter_box"] == doc["box"]
    bounds = {name: float(Fraction(v["bound"])) for name, v in c["certificate"]["outputs"].items()}
    rng = np.random.default_rng(7)
    for k in (0.75, 0.8, 0.85):
        for signal in ("random", "bang"):
            x, y = rng.normal(size=2) * 3
            tail = [0.0, 0.0]
            for i in range(400):
                d = 0.1 * (rng.uniform(-1, 1) if signal == "random" else math.copysign(1, y))
                x, y = y, -0.5 * x + k * math.tanh(y) + d
                if i >= 300:
                    tail = [max(tail[0], abs(x)), max(tail[1], abs(y))]
            assert tail[0] <= bounds["x"] and tail[1] <= bounds["y"], (k, signal, tail, bounds)
    done = cli("verify", str(out))
    assert done.exit_code == 0 and "ok   sos_bound" in done.output and "ok   quadratic" in done.output, done.output

    def wider(d: dict[str, Any]) -> None:  # the same centre
        d["box"] = {"k": ["1/2", "11/10"]}
        d["conditions"]["sos_bound"]["certificate"]["parameter_box"] = d["box"]
        d["conditions"]["quadratic"]["certificate"]["parameter_box"] = d["box"]

    def lower_b(d: dict[str, Any]) -> None:
        for data in d["conditions"]["sos_bound"]["certificate"]["outputs"].values():
            data["B"] = str(Fraction(data["B"]) / 2)

    for forge in (wider, lower_b):
        done = _tampered(doc, tmp_path, forge)
        assert done.exit_code == 1 and "FAIL sos_bound" in done.output, (forge.__name__, done.output)


def test_a_box_the_centres_p_misses_takes_a_p_common_to_its_grid(tmp_path: Path) -> None:
    """Over k in [0.5, 1.1] the centre's Stein P stops decreasing near k = 0.95: the P proved is another (the
    grid's SDP proposal), and it does decrease at every sampled k of the box, in floating point too."""
    done, doc, out = certify(tmp_path, "--classes", "linearization", "--box", "k=0.5..1.1")
    assert done.exit_code == 0, done.output
    lin = doc["conditions"]["linearization"]
    assert lin["status"] == "certified", lin["summary"]
    P = np.array([[float(Fraction(x)) for x in row] for row in lin["certificate"]["P"]])
    centre = np.array([[0.0, 1.0], [-0.5, 0.8]])
    assert not np.allclose(P / P[0, 0], np.linalg.solve(np.eye(4) - np.kron(centre.T, centre.T),
                                                        np.eye(2).ravel()).reshape(2, 2) / P[0, 0], rtol=1e-2)
    for k in np.linspace(0.5, 1.1, 61):
        A = np.array([[0.0, 1.0], [-0.5, k]])
        assert np.max(np.linalg.eigvalsh(A.T @ P @ A - P)) < 0
    assert cli("verify", str(out)).exit_code == 0


def test_a_box_reaching_unstable_gains_is_refuted_at_a_corner(tmp_path: Path) -> None:
    """Over k in [1, 1.8] no P is proved; the corner k = 1.8 has the eigenvalue (1.8 + sqrt(1.24))/2 > 1, which
    Routh's column proves in balls: linearization is refuted there (roa stays not_certified), verify re-proves
    it, and a document moving the point to a stable gain, or out of the box, fails."""
    done, doc, out = certify(tmp_path, "--classes", "linearization,roa", "--box", "k=1..1.8")
    assert done.exit_code == 1, done.output
    lin, roa = doc["conditions"]["linearization"], doc["conditions"]["roa"]
    assert lin["status"] == "refuted", lin["summary"]
    data = lin["refutation"]
    assert data["method"] == "box_point" and data["at_point"]["method"] == dbox.BALL_ROUTH_METHOD
    k = float(Fraction(data["point"]["k"]))
    assert 1 <= k <= 1.8 and max(abs(np.linalg.eigvals(np.array([[0.0, 1.0], [-0.5, k]])))) > 1
    assert lin["summary"].startswith("at k = 1.8, a value of the box, ")
    assert roa["status"] == "not_certified" and "MAP_BOX_PIECES" in roa["summary"], roa["summary"]
    assert doc["answers"]["stability"]["answer"] == "unstable"
    done = cli("verify", str(out))
    assert done.exit_code == 0, done.output
    assert "ok   linearization: at a value of the box" in done.output

    def stable_point(d: dict[str, Any]) -> None:  # k = 1 is a value of the box, with spectral radius < 1
        d["conditions"]["linearization"]["refutation"]["point"] = {"k": "1"}

    def outside(d: dict[str, Any]) -> None:
        d["conditions"]["linearization"]["refutation"]["point"] = {"k": "2"}

    for forge, words in ((stable_point, "shows no eigenvalue of modulus > 1"), (outside, "is not in the box")):
        done = _tampered(doc, tmp_path, forge)
        assert done.exit_code == 1 and "FAIL linearization" in done.output and words in done.output, done.output


def test_a_box_moving_the_fixed_point_exits_2(tmp_path: Path) -> None:
    moved = tmp_path / "moved.toml"
    moved.write_text(MAP.read_text().replace('"-0.5*x + k*tanh(y)"', '"-0.5*x + k*tanh(y) + k - 0.8"'))
    done = cli("certify", str(moved), "--no-store", "--box", "k=0.7..0.9")
    assert done.exit_code == 2, done.output
    assert "the map's fixed point moves with the box's parameters" in done.output
    assert len(done.output.strip().splitlines()) == 1
    done = cli("certify", str(moved), "--no-store", "--classes", "linearization")  # k = 0.8: a fixed point
    assert done.exit_code == 0, done.output


def test_a_candidate_over_a_box_holds_for_every_value(tmp_path: Path) -> None:
    """The user's V over k in [0.6, 0.95]: its largest level proved with k a ball on each part of the box, every
    sampled start iterated at sampled k stays in the set and converges, ``verify`` re-proves it; a document
    whose P is not the candidate's, whose level is raised or whose box is widened fails."""
    done, doc, out = certify(tmp_path, "--classes", "candidate", "--box", "k=0.6..0.95", "--candidate", GOOD)
    assert done.exit_code == 0, done.output
    c = doc["conditions"]["candidate"]
    assert c["status"] == "certified", c["summary"]
    assert c["summary"].startswith("for every k in [0.6, 0.95]: region of attraction of the map")
    cert = c["certificate"]
    assert cert["V_from"] == "candidate" and cert["parameter_box"] == doc["box"] and cert["box_parts"] >= 1
    assert [[Fraction(x) for x in row] for row in cert["P"]] == [[2, -1], [-1, 4]]
    starts_stay_and_converge(cert, [0.6, 0.75, 0.95], seed=11)
    done = cli("verify", str(out))
    assert done.exit_code == 0 and "ok   candidate: V(F(e)) < V(e) proved again" in done.output, done.output

    def other_p(d: dict[str, Any]) -> None:
        d["conditions"]["candidate"]["certificate"]["P"] = [["2", "-1"], ["-1", "5"]]

    def raised(d: dict[str, Any]) -> None:
        d["conditions"]["candidate"]["certificate"]["level"] = str(Fraction(cert["level"]) * 64)

    def wider(d: dict[str, Any]) -> None:  # the same centre, k up to 1.6 (unstable there)
        d["box"] = {"k": ["-1/20", "8/5"]}
        d["conditions"]["candidate"]["certificate"]["parameter_box"] = d["box"]

    for forge in (other_p, raised, wider):
        done = _tampered(doc, tmp_path, forge)
        assert done.exit_code == 1 and "FAIL candidate" in done.output, (forge.__name__, done.output)


def test_a_candidate_naming_a_box_parameter_exits_2() -> None:
    done = cli("certify", str(MAP), "--no-store", "--box", "k=0.6..0.95", "--candidate", "k*x**2 + y**2")
    assert done.exit_code == 2, done.output
    assert "--candidate" in done.output and "names the box's parameter k" in done.output
    assert len(done.output.strip().splitlines()) == 1


def test_the_ball_stein_test_refuses_an_unstable_jacobian() -> None:
    """``P - A^T P A > 0`` over a ball matrix: proved for a ball of stable Jacobians around k = 0.8, refused for
    one reaching k = 1.6 (spectral radius > 1 there: no P can pass)."""
    P = [[Fraction(2), Fraction(-1)], [Fraction(-1), Fraction(4)]]

    def A(lo: float, hi: float) -> list[list[Any]]:
        k = flint.arb(lo).union(flint.arb(hi))
        return [[flint.arb(0), flint.arb(1)], [flint.arb(-0.5), k]]

    assert dbox.stein_margin_proved(P, A(0.79, 0.81))
    assert not dbox.stein_margin_proved(P, A(0.79, 1.6))
    assert not dbox.stein_margin_proved(P, A(1.6, 1.6))
