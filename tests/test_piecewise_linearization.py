"""``linearization`` at a kink (issue 44, item 3; :mod:`lyapcheck.models.classes.piecewise_linearization`).

What is asserted: the first-order part ``A e + B phi`` derived from the model is the true field's to second
order (checked against the field evaluated in floating point, with ``phi`` the exact ReLU values); the shipped
ReLU pendulum (continuous and its Euler map) is certified LES, its certificate passes ``verify``, and a
forged ``P``, a forged kink or a negative multiplier fail it; the same network with the tanh policy's ``W2``
(its loop is unstable: a start 1e-3 from upright grows) and a saturation's corner with an unstable side are
``not_certified``, never ``refuted``; ``abs`` feedback and both corners of ``sat`` are handled; ``roa`` says why
it has no V.
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
from lyapcheck.models.classes import piecewise_linearization as pw
from lyapcheck.models.classes.recast_classes import base_loop
from lyapcheck.models.language.modelfile import load_any_model
from lyapcheck.models.language.recast import RecastModel

app._register_commands()

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"
RELU = EXAMPLES / "models" / "pendulum-relu-policy.toml"
RELU_MAP = EXAMPLES / "models" / "discrete-pendulum-relu-policy.toml"


def cli(*args: str) -> Any:
    done = CliRunner().invoke(app.cli, list(args))
    assert done.exception is None or isinstance(done.exception, SystemExit), done.output
    assert "Traceback" not in done.output
    return done


def loaded(path: Path) -> RecastModel:
    model = load_any_model(path)
    assert isinstance(model, RecastModel)
    return model


def one_state(tmp_path: Path, rhs: str, name: str = "m.toml") -> RecastModel:
    path = tmp_path / name
    path.write_text(f'[model]\nname = "m"\nstates = ["x"]\n[dynamics]\nx = "{rhs}"\n')
    return loaded(path)


def weights() -> tuple[Any, Any]:
    data = np.load(EXAMPLES / "networks" / "pendulum_relu_policy.npz", allow_pickle=False)
    return data["W1"], data["W2"]


def phi_of(pl: pw.PiecewiseLinear, e: Any) -> Any:
    """The exact piecewise-linear values ``phi(e)`` of the kinks, in order (each uses e and earlier phi)."""
    w = np.concatenate([e, np.zeros(len(pl.kinks))])
    for i, k in enumerate(pl.kinks):
        z = float(np.dot([float(x) for x in k.form], w))
        w[pl.n + i] = abs(z) if k.shape == "abs" else max(0.0, z) if k.shape == "max0" else min(0.0, z)
    return w[pl.n:]


def test_the_first_order_part_is_the_fields_to_second_order() -> None:
    W1, W2 = weights()
    pl = pw.derive(base_loop(loaded(RELU).system))
    assert isinstance(pl, pw.PiecewiseLinear) and len(pl.kinks) == 8 and {k.shape for k in pl.kinks} == {"abs"}
    A = np.array([[float(x) for x in row] for row in pl.A])
    B = np.array([[float(x) for x in row] for row in pl.B])
    rng = np.random.default_rng(3)
    for r in (1e-2, 1e-3):
        for _ in range(20):
            e = rng.normal(size=2)
            e *= r / np.linalg.norm(e)
            u = float((W2 @ np.maximum(W1 @ e, 0.0))[0])
            f = np.array([e[1], np.sin(e[0]) - 0.1 * e[1] + u])
            # sin(theta) - theta = O(r^3); a wrong slope of a ReLU neuron would leave an O(r) error
            assert np.linalg.norm(f - (A @ e + B @ phi_of(pl, e))) <= r ** 2, (r, e)


@pytest.mark.slow  # (roa's ball-arithmetic route tries its fitted V-s first: about 20 s)
def test_the_relu_pendulum_is_certified_and_verify_repeats_it(tmp_path: Path) -> None:
    out = tmp_path / "relu.json"
    done = cli("certify", str(RELU), "--classes", "linearization,roa", "--no-store", "--out", str(out))
    assert done.exit_code == 0, done.output
    conditions = json.loads(out.read_text())["conditions"]
    lin = conditions["linearization"]
    assert lin["status"] == "certified" and lin["property"] == "LES"
    assert lin["certificate"]["kind"] == pw.KIND and lin["summary"] == pw.CERTIFIED_FIELD
    # roa starts from the Jacobian's P and says it has none (the piecewise proof bounds no neighbourhood)
    assert conditions["roa"]["status"] == "not_certified"
    assert "the Jacobian does not exist at the equilibrium" in conditions["roa"]["summary"]
    assert cli("verify", str(out)).exit_code == 0

    def forged(change: Any) -> str:
        doc = json.loads(out.read_text())
        change(doc["conditions"]["linearization"]["certificate"])
        bad = tmp_path / "forged.json"
        bad.write_text(json.dumps(doc))
        again = cli("verify", str(bad))
        assert again.exit_code != 0, again.output
        return str(again.output)

    def shear(cert: dict[str, Any]) -> None:  # a P > 0 that is not the proof's
        cert["P"][0][1] = cert["P"][1][0] = str(-Fraction(cert["P"][0][1]) * 8)

    assert "FAIL linearization" in forged(shear)

    def kink(cert: dict[str, Any]) -> None:
        cert["kinks"][0]["form"][0] = str(Fraction(cert["kinks"][0]["form"][0]) * 2)

    assert "the stated kinks are not the model's" in forged(kink)

    def negative(cert: dict[str, Any]) -> None:
        cert["nu"][0] = "-1"

    assert "negative" in forged(negative)


def test_the_forged_p_fails_the_exact_check_itself() -> None:
    pl = pw.derive(base_loop(loaded(RELU).system))
    assert isinstance(pl, pw.PiecewiseLinear)
    cert, _ = pw.prove(pl, False)
    assert cert is not None
    args = ([Fraction(x) for x in cert["lambda"]], [Fraction(x) for x in cert["nu"]],
            [tuple(p) for p in cert["products"]])
    P = [[Fraction(x) for x in row] for row in cert["P"]]
    assert pw.check(pl, False, P, Fraction(cert["epsilon"]), *args)[0]
    assert not pw.check(pl, False, [[x * 100 if i == j == 0 else x for j, x in enumerate(row)] for i, row in
                                    enumerate(P)], Fraction(cert["epsilon"]), *args)[0]


def test_the_map_variant_is_certified_and_verified(tmp_path: Path) -> None:
    out = tmp_path / "map.json"
    done = cli("certify", str(RELU_MAP), "--classes", "linearization,roa", "--no-store", "--out", str(out))
    assert done.exit_code == 0, done.output
    conditions = json.loads(out.read_text())["conditions"]
    assert conditions["linearization"]["status"] == "certified"
    assert conditions["linearization"]["summary"] == pw.CERTIFIED_MAP
    roa = conditions["roa"]
    assert roa["status"] == "not_applicable" and "abs is not differentiable" in roa["summary"]
    assert cli("verify", str(out)).exit_code == 0
    # the certified map does contract: iterated from small starts, each converges
    W1, W2 = weights()
    for angle in np.linspace(0, 2 * np.pi, 8, endpoint=False):
        x = 1e-3 * np.array([np.cos(angle), np.sin(angle)])
        for _ in range(2000):
            u = float((W2 @ np.maximum(W1 @ x, 0.0))[0])
            x = np.array([x[0] + 0.05 * x[1], x[1] + 0.05 * (np.sin(x[0]) - 0.1 * x[1] + u)])
        assert np.linalg.norm(x) < 1e-6


def test_the_tanh_policys_weights_under_relu_are_not_certified_and_not_refuted(tmp_path: Path) -> None:
    W1, W2 = weights()
    np.savez(tmp_path / "same.npz", W1=W1, b1=np.zeros(8), W2=W2 / 2, b2=np.zeros(1), activation=np.array("relu"))
    text = RELU.read_text().replace("../networks/pendulum_relu_policy.npz", "same.npz")
    (tmp_path / "same.toml").write_text(text)
    result = pw.linearization(base_loop(loaded(tmp_path / "same.toml").system))
    assert result.status == "not_certified", result.summary
    assert "abs is not differentiable" in result.summary and "Nothing is refuted" in result.summary
    # and indeed it is not stable: a start 1e-3 from upright grows (explicit Euler, small step)
    x = 1e-3 * np.array([1.0, 0.0])
    for _ in range(40000):
        u = float((W2 / 2 @ np.maximum(W1 @ x, 0.0))[0])
        x = x + 1e-3 * np.array([x[1], np.sin(x[0]) - 0.1 * x[1] + u])
    assert np.linalg.norm(x) > 1e-2


def test_abs_feedback_is_certified(tmp_path: Path) -> None:
    path = tmp_path / "abs.toml"
    path.write_text('[model]\nname = "m"\nstates = ["x1", "x2"]\n[dynamics]\nx1 = "x2"\n'
                    'x2 = "-x1 - x2 - 0.5*abs(x1)"\n')
    loop = base_loop(loaded(path).system)
    result = pw.linearization(loop)
    assert result.status == "certified" and result.certificate["kind"] == pw.KIND
    pl = pw.derive(loop)
    assert isinstance(pl, pw.PiecewiseLinear)
    assert pl.A == [[0, 1], [-1, -1]] and pl.B == [[0], [Fraction(-1, 2)]]
    assert pl.kinks[0].form == (1, 0, 0)


@pytest.mark.parametrize("rhs, shape, status", [
    ("-x + 0.5*(sat(x + 1, 1) - 1)", "min0", "certified"),      # x' = -x + min(0, x)/2: stable on both sides
    ("-x + 0.5*(sat(x - 1, 1) + 1)", "max0", "certified"),      # x' = -x + max(0, x)/2
    ("-x + 2*(sat(x + 1, 1) - 1)", "min0", "not_certified"),    # x' = x for x < 0: unstable on that side
])
def test_a_saturations_corner(tmp_path: Path, rhs: str, shape: str, status: str) -> None:
    loop = base_loop(one_state(tmp_path, rhs).system)
    pl = pw.derive(loop)
    assert isinstance(pl, pw.PiecewiseLinear) and [k.shape for k in pl.kinks] == [shape]
    result = pw.linearization(loop)
    assert result.status == status, result.summary


def test_without_a_kink_the_route_keeps_the_jacobians_reason(tmp_path: Path) -> None:
    result = pw.linearization(base_loop(one_state(tmp_path, "-sqrt(x**2)").system))
    assert result.status == "not_applicable" and "sqrt is not differentiable" in result.summary


def test_the_kinks_share_the_jacobians_chain_rule(tmp_path: Path) -> None:
    """Away from the kink's coordinate the first-order part is the Jacobian of the loop without the kink:
    one walk (sin through the chain rule, the kink a coordinate of its own)."""
    from lyapcheck.models.classes.recast_classes import first_order, jacobian

    def loop_of(name: str, x2: str) -> Any:
        path = tmp_path / name
        path.write_text(f'[model]\nname = "m"\nstates = ["x1", "x2"]\n[dynamics]\nx1 = "x2"\nx2 = "{x2}"\n')
        return base_loop(loaded(path).system)

    kinked = loop_of("k.toml", "-x1 - x2 - 0.5*abs(sin(x1 - x2)) + 2*sin(x1)")
    smooth = loop_of("s.toml", "-x1 - x2 + 2*sin(x1)")
    pl = pw.derive(kinked)
    assert isinstance(pl, pw.PiecewiseLinear) and pl.A == jacobian(smooth) == [[0, 1], [1, -1]]
    assert pl.B == [[0], [Fraction(-1, 2)]] and pl.kinks[0].form == (1, -1, 0)
    # without the kink asked for, the same walk stops there with the Jacobian's reason
    walked = first_order(kinked)
    assert isinstance(walked, str) and "abs is not differentiable" in walked
    assert walked == jacobian(kinked)


def test_more_kinks_than_the_limit_are_refused_by_their_count(monkeypatch: pytest.MonkeyPatch) -> None:
    """Above PIECEWISE_MAX_KINKS the route says not_certified naming the limit, before the chain rule's walk."""
    from lyapcheck import tolerances

    model = loaded(RELU_MAP)
    monkeypatch.setattr(tolerances, "PIECEWISE_MAX_KINKS", 7)

    def no_walk(loop: Any) -> Any:
        raise AssertionError("derived although refused by the count")

    monkeypatch.setattr(pw, "derive", no_walk)
    result = pw.run_map(model, "kinked")
    assert result is not None and result.status == "not_certified"
    assert "8 kinks at the equilibrium where the limit is 7" in result.summary
    assert "PIECEWISE_MAX_KINKS" in result.summary and not result.certificate
    loop_result = pw.run(base_loop(loaded(RELU).system), "kinked")
    assert loop_result is not None and loop_result.status == "not_certified"


def test_a_spent_budget_stops_the_search_inconclusive() -> None:
    """The class's budget is checked between the solves and the exact steps: spent, the route is inconclusive
    and names the limit (never certified without its exact check)."""
    from lyapcheck.models.engines.search import Budget

    spent = Budget(0.0, "the test's budget")
    result = pw.run_map(loaded(RELU_MAP), "kinked", spent)
    assert result is not None and result.status == "inconclusive", result.summary
    assert "the test's budget" in result.summary and not result.certificate
    fresh = pw.run_map(loaded(RELU_MAP), "kinked", Budget(60.0, "the test's budget"))
    assert fresh is not None and fresh.status == "certified"


def test_the_ysa_policy_as_relu_is_refused_by_its_64_kinks(tmp_path: Path) -> None:
    """The 2 x 32 policy of ysa-pendulum with ReLU activations on the Euler pendulum: 64 kinks, above
    PIECEWISE_MAX_KINKS, refused by the count (no LMI built, no proof claimed)."""
    from lyapcheck import tolerances

    data = np.load(EXAMPLES / "networks" / "ysa_pendulum_tanh.npz", allow_pickle=False)
    arrays = {k: np.array(data[k]) for k in data.files}
    arrays["activation"] = np.array("relu")
    np.savez(tmp_path / "ysa_relu.npz", **arrays)
    text = RELU_MAP.read_text().replace("../networks/pendulum_relu_policy.npz", "ysa_relu.npz")
    (tmp_path / "ysa_relu.toml").write_text(text)
    model = loaded(tmp_path / "ysa_relu.toml")
    assert len(pw.kinks_at_equilibrium(pw.map_loop(model))) == 64 > tolerances.PIECEWISE_MAX_KINKS
    result = pw.run_map(model, "kinked")
    assert result is not None and result.status == "not_certified" and "64 kinks" in result.summary
