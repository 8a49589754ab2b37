"""Sampled-data loops whose controller is a network (issue 44, item 2 with item 3): ``[networks.NAME]`` beside
``[sampling]``, read by the model files' network reader, lowered with the ``[controller]`` laws (the gain
``K = dk/dx`` the chain rule through the layers), simulated with the true network at each sample, and its
file's SHA-256 in the certificate (``verify`` fails once the file changes)."""

from __future__ import annotations

import hashlib
import json
import shutil
from fractions import Fraction
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from click.testing import CliRunner
from scipy.integrate import solve_ivp
from scipy.linalg import expm

from tests.conftest import ROOT

EXAMPLE = ROOT / "examples" / "models" / "pendulum-digital-tanh-policy.toml"
NETWORK = ROOT / "examples" / "networks" / "pendulum_tanh_policy.npz"

#: a double integrator under a digital network policy; NET is the network file's name
SMALL = ('[model]\nstates = ["x", "v"]\n[parameters]\nT = "100 ms"\n[networks.pi]\nfile = "NET"\n'
         'inputs = ["x", "v"]\noutputs = ["pi_u"]\n[dynamics]\nx = "v"\nv = "u"\n[sampling]\nperiod = "T"\n'
         '[controller]\nu = "LAW"\n')


def _invoke(*args: str) -> tuple[int, str]:
    from lyapcheck.cli import app

    app._register_commands()
    result = CliRunner().invoke(app.cli, list(args))
    return result.exit_code, result.output


def _save(path: Path, layers: list[tuple[Any, Any]], activation: str = "tanh") -> Path:
    arrays: dict[str, Any] = {"activation": np.array(activation)}
    for k, (W, b) in enumerate(layers, start=1):
        arrays[f"W{k}"], arrays[f"b{k}"] = np.asarray(W, dtype=float), np.asarray(b, dtype=float)
    np.savez(path, **arrays)
    return path


def _small(folder: Path, layers: list[tuple[Any, Any]], activation: str = "tanh", law: str = "pi_u") -> Path:
    _save(folder / "net.npz", layers, activation)
    path = folder / "loop.toml"
    path.write_text(SMALL.replace("NET", "net.npz").replace("LAW", law))
    return path


#: a 2-2-1 policy without biases whose slope at 0 is (-1, -2) for tanh, and for relu on the positive side
LAYERS = [([[1.0, 0.0], [0.0, 1.0]], [0.0, 0.0]), ([[-1.0, -2.0]], [0.0])]


def _exact_slope(path: Path) -> list[Fraction]:
    """W2 W1 of a two-layer tanh network, exactly (tanh'(0) = 1), from the file's floats."""
    with np.load(path) as data:
        W1, W2 = data["W1"], data["W2"]
    return [sum((Fraction(float(W2[0, k])) * Fraction(float(W1[k, j])) for k in range(W1.shape[0])), Fraction(0))
            for j in range(W1.shape[1])]


def _critical_period(K: np.ndarray) -> float:
    A, B = np.array([[0.0, 1.0], [1.0, -0.1]]), np.array([[0.0], [1.0]])

    def radius(T: float) -> float:
        M = np.zeros((3, 3))
        M[:2, :2], M[:2, 2:] = A * T, B * T
        E = expm(M)
        return float(max(abs(np.linalg.eigvals(E[:2, :2] + E[:2, 2:] @ K))))

    lo, hi = 0.1, 2.0
    for _ in range(60):
        mid = (lo + hi) / 2
        lo, hi = (mid, hi) if radius(mid) < 1 else (lo, mid)
    return lo


def test_the_example_is_certified_with_the_networks_slope_as_gain(tmp_path: Path) -> None:
    from lyapcheck.models.classes.sampled import linear_parts
    from lyapcheck.models.language.sampling import load_sampled

    model = load_sampled(EXAMPLE)
    assert [n.name for n in model.networks] == ["pi"] and model.control_equilibrium == (Fraction(0),)
    parts = linear_parts(model)
    assert not isinstance(parts, str) and parts[2] == [_exact_slope(NETWORK)]
    out = tmp_path / "cert.json"
    code, text = _invoke("certify", str(EXAMPLE), "--out", str(out))
    assert code == 0, text
    doc = json.loads(out.read_text())
    assert doc["verdict"] == "certified" and doc["conditions"]["linearization"]["status"] == "certified"
    assert doc["conditions"]["roa"]["status"] == "certified"  # (on the true network, by ball arithmetic)
    assert doc["model"]["networks"] == {"pi": {"file": "../networks/pendulum_tanh_policy.npz",
                                               "sha256": hashlib.sha256(NETWORK.read_bytes()).hexdigest()}}
    code, text = _invoke("verify", str(out))
    assert code == 0 and "networks" in text, text


def test_the_largest_period_brackets_the_critical_period() -> None:
    from lyapcheck.api import certify_extremum

    critical = _critical_period(np.array([[float(k) for k in _exact_slope(NETWORK)]]))
    found = certify_extremum(EXAMPLE, "T=0.01..2", direction="max", steps=14)
    assert found.proved is not None and found.failed is not None and found.failed.outcome == "refuted"
    proved, refuted = float(found.proved), float(found.failed.value)
    assert proved <= critical <= refuted and refuted - proved < 1e-3 * critical


def test_a_saturated_network_law_has_the_same_gain(tmp_path: Path) -> None:
    from lyapcheck.models.classes.sampled import linear_parts
    from lyapcheck.models.language.sampling import load_sampled

    plain, clipped = (load_sampled(_small(tmp_path, LAYERS, law=law)) for law in ("pi_u", "sat(pi_u, 5)"))
    assert linear_parts(plain) == linear_parts(clipped)
    assert linear_parts(plain)[2] == [[Fraction(-1), Fraction(-2)]]  # type: ignore[index]


def test_a_relu_policy_at_0_is_not_applicable_naming_the_neuron(tmp_path: Path) -> None:
    path = _small(tmp_path, LAYERS, activation="relu")
    out = tmp_path / "cert.json"
    code, text = _invoke("certify", str(path), "--out", str(out))
    assert code == 1 and "Traceback" not in text
    doc = json.loads(out.read_text())
    result = doc["conditions"]["linearization"]
    assert result["status"] == "not_applicable" and doc["verdict"] == "not_certified"
    assert "neuron 1 of layer 1 of [networks.pi]" in result["summary"] and "not differentiable" in result["summary"]
    assert _invoke("verify", str(out))[0] == 0


def test_a_changed_network_file_fails_verify(tmp_path: Path) -> None:
    folder = tmp_path / "models"
    folder.mkdir()
    (tmp_path / "networks").mkdir()
    shutil.copy(NETWORK, tmp_path / "networks" / NETWORK.name)
    model = shutil.copy(EXAMPLE, folder / EXAMPLE.name)
    out = tmp_path / "cert.json"
    assert _invoke("certify", str(model), "--out", str(out))[0] == 0
    assert _invoke("verify", str(out))[0] == 0
    with np.load(NETWORK) as data:
        arrays = {k: data[k] for k in data.files}
    arrays["W2"] = arrays["W2"] * 0.5  # the same shapes, another policy
    np.savez(tmp_path / "networks" / NETWORK.name, **arrays)
    code, text = _invoke("verify", str(out))
    assert code == 1
    assert "networks" in text and "SHA-256 differs" in text


@pytest.mark.parametrize("layers, key, says", [
    ([([[1.0, 0.0, 0.0]], [0.0]), ([[1.0]], [0.0])], "[networks.pi] inputs", "first layer takes 3"),
    ([([[1.0, 0.0]], [0.0]), ([[1.0], [2.0]], [0.0, 0.0])], "[networks.pi] outputs", "last layer gives 2"),
    ([([[1.0, 0.0]], [0.25]), ([[1.0]], [0.0])], "[networks.pi]", "neuron 1 of layer 1 (tanh)"),
])
def test_a_network_that_does_not_fit_is_one_line_exit_2(tmp_path: Path, layers: list[tuple[Any, Any]], key: str,
                                                         says: str) -> None:
    code, text = _invoke("certify", str(_small(tmp_path, layers)))
    assert code == 2, text
    assert "Traceback" not in text and len(text.strip().splitlines()) == 1
    assert key in text and says in text


def test_a_network_output_in_the_dynamics_is_refused(tmp_path: Path) -> None:
    path = _small(tmp_path, LAYERS)
    path.write_text(path.read_text().replace('v = "u"', 'v = "u + pi_u"'))
    code, text = _invoke("certify", str(path))
    assert code == 2 and len(text.strip().splitlines()) == 1
    assert "[dynamics] v" in text and "pi_u" in text and "[controller]" in text


def test_simulate_evaluates_the_true_network_at_each_sample(tmp_path: Path) -> None:
    from lyapcheck.models.language.sampling import load_sampled
    from lyapcheck.models.surfaces.sampled_simulate import ControlLaw, run_sampled

    model = load_sampled(EXAMPLE)
    network = model.networks[0]
    points = np.random.default_rng(3).uniform(-2.0, 2.0, size=(50, 2))
    assert ControlLaw(model)(points)[:, 0] == pytest.approx(network.forward(points)[:, 0], rel=1e-13, abs=1e-13)
    # one period from a start: the pendulum's flow under the torque the network gives there, held
    start = np.array([[0.5, -0.3]])
    u = float(network.forward(start)[0, 0])
    doc = run_sampled(model, start, "one start", t_end=0.05).document
    exact = solve_ivp(lambda t, x: [x[1], np.sin(x[0]) - 0.1 * x[1] + u], (0.0, 0.05), start[0], rtol=1e-11,
                      atol=1e-13).y[:, -1]
    final = doc["trajectories"][0]["final_state"]
    assert [final["theta"], final["omega"]] == pytest.approx(exact, abs=1e-7)
    plot = tmp_path / "policy.png"
    code, text = _invoke("simulate", str(EXAMPLE), "--x0", "theta=0.5", "--t-end", "10", "--json", "--plot", str(plot))
    assert code == 0, text
    doc = json.loads(text)
    assert doc["mode"] == "sampled" and doc["n_converged"] == 1 and plot.stat().st_size > 0
