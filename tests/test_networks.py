"""``[networks.NAME]`` (issue 44, item 3): networks read from ``.npz`` and ONNX files, every refusal in one
line (exit 2), the lowering evaluated as a plain numpy forward pass evaluates the network, and the shipped
example (``examples/models/pendulum-tanh-policy.toml``) certifying as its comment says, its certificate
re-checked by ``verify`` and failing once the network file changes."""

from __future__ import annotations

import json
import shutil
from fractions import Fraction
from pathlib import Path
from typing import Any

import numpy as np
import onnx
import pytest
from click.testing import CliRunner
from onnx import TensorProto, helper, numpy_helper

from lyapcheck.cli import app
from lyapcheck.models.engines.recast_numeric import FloatLoop
from lyapcheck.models.language.modelfile import load_any_model
from lyapcheck.models.language.networks import Network
from lyapcheck.models.language.recast import RecastModel

app._register_commands()

ROOT = Path(__file__).resolve().parents[1]
EXAMPLE = ROOT / "examples" / "models" / "pendulum-tanh-policy.toml"
EXAMPLE_ONNX = ROOT / "examples" / "models" / "pendulum-tanh-policy-onnx.toml"


def model_file(folder: Path, network: str, *, inputs: str = '["x1", "x2"]', outputs: str = '["u"]',
               rhs: str = "-x1 - x2 + u", extra: str = "") -> Path:
    """A two-state loop ``x1' = x2, x2' = rhs`` with one network ``[networks.pi]`` read from ``network``."""
    path = folder / "m.toml"
    path.write_text(f'[model]\nname = "m"\nstates = ["x1", "x2"]\n{extra}\n[networks.pi]\nfile = "{network}"\n'
                    f'inputs = {inputs}\noutputs = {outputs}\n\n[dynamics]\nx1 = "x2"\nx2 = "{rhs}"\n')
    return path


def save_npz(path: Path, layers: list[tuple[Any, Any]], activation: str | None = "tanh", **extra: Any) -> Path:
    arrays: dict[str, Any] = {}
    for k, (W, b) in enumerate(layers, start=1):
        arrays[f"W{k}"], arrays[f"b{k}"] = np.asarray(W), np.asarray(b)
    if activation is not None:
        arrays["activation"] = np.array(activation)
    np.savez(path, **arrays, **extra)
    return path


def network_of(model: Any) -> Network:
    assert isinstance(model, RecastModel) and len(model.networks) == 1
    return model.networks[0]


def random_layers(rng: np.random.Generator, widths: list[int]) -> list[tuple[Any, Any]]:
    return [(rng.normal(size=(o, i)), np.zeros(o)) for i, o in zip(widths, widths[1:])]


# -- reading ---------------------------------------------------------------------------------------

def test_an_npz_network_is_read_exactly_as_its_floats(tmp_path: Path) -> None:
    rng = np.random.default_rng(7)
    layers = random_layers(rng, [2, 3, 1])
    save_npz(tmp_path / "n.npz", layers)
    net = network_of(load_any_model(model_file(tmp_path, "n.npz")))
    assert [layer.activation for layer in net.layers] == ["tanh", "linear"]
    for layer, (W, b) in zip(net.layers, layers):
        assert layer.weights == tuple(tuple(Fraction(float(w)) for w in row) for row in W)  # the binary value
        assert layer.bias == tuple(Fraction(float(v)) for v in b)
    assert net.inputs == ("x1", "x2") and net.outputs == ("u",) and net.neurons == 3


def test_the_shipped_npz_and_onnx_files_give_the_same_loop() -> None:
    npz, onnx_model = load_any_model(EXAMPLE), load_any_model(EXAMPLE_ONNX)
    assert isinstance(npz, RecastModel) and isinstance(onnx_model, RecastModel)
    assert network_of(npz).layers == network_of(onnx_model).layers
    assert npz.system.to_json() == onnx_model.system.to_json()
    assert [a.function for a in npz.system.auxiliaries].count("tanh") == 8


def onnx_file(path: Path, nodes: list[Any], inits: dict[str, Any], width_in: int = 2, width_out: int = 1) -> Path:
    graph = helper.make_graph(nodes, "g", [helper.make_tensor_value_info("x", TensorProto.FLOAT, [None, width_in])],
                              [helper.make_tensor_value_info("y", TensorProto.FLOAT, [None, width_out])],
                              [numpy_helper.from_array(np.asarray(v, dtype=np.float32), k) for k, v in inits.items()])
    path.write_bytes(helper.make_model(graph, opset_imports=[helper.make_opsetid("", 13)]).SerializeToString())
    return path


def test_an_onnx_graph_of_matmul_add_and_sigmoid_is_the_npz_network(tmp_path: Path) -> None:
    """MatMul multiplies from the right (x W: W is (in, out)); the layers read are (out, in), as in .npz."""
    W1 = np.array([[0.5, -0.25], [0.75, 0.125], [-1.0, 0.5]], dtype=np.float32)  # (out, in)
    W2 = np.array([[1.0, -1.0, 0.5]], dtype=np.float32)
    nodes = [helper.make_node("MatMul", ["x", "M1"], ["z1"]), helper.make_node("Add", ["z1", "c1"], ["a1"]),
             helper.make_node("Sigmoid", ["a1"], ["h1"]), helper.make_node("MatMul", ["h1", "M2"], ["z2"]),
             helper.make_node("Add", ["c2", "z2"], ["y"])]
    path = onnx_file(tmp_path / "n.onnx", nodes, {"M1": W1.T, "c1": np.zeros(3), "M2": W2.T, "c2": [-0.25]})
    save_npz(tmp_path / "n.npz", [(W1, np.zeros(3)), (W2, [-0.25])], "sigmoid")
    from_onnx = network_of(load_any_model(model_file(tmp_path, path.name)))
    from_npz = network_of(load_any_model(model_file(tmp_path, "n.npz")))
    assert from_onnx.layers == from_npz.layers


# -- refusals: exit 2, one line naming [networks.pi], what was expected and what was found ------------

def refusal(path: Path) -> str:
    done = CliRunner().invoke(app.cli, ["certify", str(path), "--classes", "linearization", "--no-store"])
    assert done.exit_code == 2, done.output
    assert "Traceback" not in done.output and done.stdout == ""
    [line] = done.stderr.splitlines()
    assert line.startswith(f"lyapcheck: error: {path}: "), line
    return line


GOOD = [([[1.0, 0.0], [0.0, 1.0]], [0.0, 0.0]), ([[-1.0, -1.0]], [0.0])]


def write_case(tmp_path: Path, case: str) -> Path:
    """The model file of one refused case."""
    if case == "suffix":
        (tmp_path / "n.pt").write_bytes(b"x")
        return model_file(tmp_path, "n.pt")
    if case == "missing":
        return model_file(tmp_path, "absent.npz")
    if case == "object array":
        np.savez(tmp_path / "n.npz", W1=np.array([[1.0, 0.0]], dtype=object), b1=np.zeros(1))
        return model_file(tmp_path, "n.npz")
    if case == "not finite":
        save_npz(tmp_path / "n.npz", [([[1.0, np.inf]], [0.0])], None)
        return model_file(tmp_path, "n.npz")
    if case == "chain":
        save_npz(tmp_path / "n.npz", [GOOD[0], ([[-1.0, -1.0, 1.0]], [0.0])])
        return model_file(tmp_path, "n.npz")
    if case == "bias length":
        save_npz(tmp_path / "n.npz", [([[1.0, 0.0], [0.0, 1.0]], [0.0]), GOOD[1]])
        return model_file(tmp_path, "n.npz")
    if case == "inputs":
        save_npz(tmp_path / "n.npz", GOOD)
        return model_file(tmp_path, "n.npz", inputs='["x1"]')
    if case == "outputs":
        save_npz(tmp_path / "n.npz", GOOD)
        return model_file(tmp_path, "n.npz", outputs='["u", "v"]')
    if case == "input not a state":
        save_npz(tmp_path / "n.npz", GOOD)
        return model_file(tmp_path, "n.npz", inputs='["x1", "k"]')
    if case == "output twice":
        save_npz(tmp_path / "n.npz", GOOD)
        return model_file(tmp_path, "n.npz", outputs='["k"]', rhs="-x1 - x2 + k", extra="[parameters]\nk = 1")
    if case == "activation":
        save_npz(tmp_path / "n.npz", GOOD, "softplus")
        return model_file(tmp_path, "n.npz")
    if case == "no activation":
        save_npz(tmp_path / "n.npz", GOOD, None)
        return model_file(tmp_path, "n.npz")
    if case == "gap":
        save_npz(tmp_path / "n.npz", [GOOD[0]], "tanh", W3=np.ones((1, 2)), b3=np.zeros(1))
        return model_file(tmp_path, "n.npz")
    if case == "onnx operator":
        nodes = [helper.make_node("Gemm", ["x", "W", "b"], ["z"], transB=1), helper.make_node("Softplus", ["z"], ["y"])]
        onnx_file(tmp_path / "n.onnx", nodes, {"W": [[1.0, 0.0]], "b": [0.0]})
        return model_file(tmp_path, "n.onnx")
    if case == "onnx not a chain":
        nodes = [helper.make_node("Gemm", ["x", "W", "b"], ["z"], transB=1), helper.make_node("Add", ["z", "z"], ["y"])]
        onnx_file(tmp_path / "n.onnx", nodes, {"W": [[1.0, 0.0]], "b": [0.0]})
        return model_file(tmp_path, "n.onnx")
    if case == "onnx outputs":
        nodes = [helper.make_node("Gemm", ["x", "W", "b"], ["y"], transB=1)]
        onnx_file(tmp_path / "n.onnx", nodes, {"W": [[1.0, 0.0], [0.0, 1.0]], "b": [0.0, 0.0]}, width_out=2)
        return model_file(tmp_path, "n.onnx")
    if case == "onnx garbage":
        (tmp_path / "n.onnx").write_bytes(b"\x00\xffnot a protobuf")
        return model_file(tmp_path, "n.onnx")
    if case == "tanh bias":
        save_npz(tmp_path / "n.npz", [([[1.0, 0.0], [0.0, 1.0]], [0.125, 0.0]), GOOD[1]])
        return model_file(tmp_path, "n.npz")
    if case == "too many neurons":
        save_npz(tmp_path / "n.npz", [(np.ones((65, 2)), np.zeros(65)), (np.ones((1, 65)), np.zeros(1))])
        return model_file(tmp_path, "n.npz")
    raise AssertionError(case)


CASES = {
    "suffix": ("[networks.pi] file:", "must be a .npz or .onnx file, got 'n.pt'"),
    "missing": ("[networks.pi] file:", "'absent.npz' not found"),
    "object array": ("[networks.pi]:", "the array 'W1' in 'n.npz' is a pickled (object) array"),
    "not finite": ("[networks.pi]:", "W1 in 'n.npz' has a value that is not finite (inf)"),
    "chain": ("[networks.pi]:", "W2 in 'n.npz' has shape (1, 3): expected (1, 2), as layer 1 gives 2 values"),
    "bias length": ("[networks.pi]:", "b1 in 'n.npz' has shape (1,): expected (2,)"),
    "inputs": ("[networks.pi] inputs:", "names 1 inputs, but the network's first layer takes 2"),
    "outputs": ("[networks.pi] outputs:", "names 2 outputs, but the network's last layer gives 1"),
    "input not a state": ("[networks.pi] inputs:", "'k' is not a state"),
    "output twice": ("[networks.pi] outputs:", "the name 'k' is declared twice (also a parameter)"),
    "activation": ("[networks.pi]:", "must be one of tanh, relu, sigmoid, got 'softplus'"),
    "no activation": ("[networks.pi]:", "has hidden layers but no 'activation' array"),
    "gap": ("[networks.pi]:", "has an unexpected array 'W3'"),
    "onnx operator": ("[networks.pi]:", "uses the operator 'Softplus'"),
    "onnx not a chain": ("[networks.pi]:", "must add an initializer to the previous output"),
    "onnx outputs": ("[networks.pi] outputs:", "names 1 outputs, but the network's last layer gives 2"),
    "onnx garbage": ("[networks.pi] file:", "'n.onnx' is not a readable ONNX model"),
    "too many neurons": ("[networks]:", "have 65 neurons with an activation; the limit is 64 (MAX_NEURONS)"),
    # a bias moves a tanh neuron's value at the equilibrium to tanh(b), irrational: a clear refusal
    "tanh bias": ("[networks.pi]:", "neuron 1 of layer 1 (tanh) has the argument 0.125 at the equilibrium"),
}


@pytest.mark.parametrize("case", list(CASES))
def test_each_refusal_is_one_line_naming_the_network(tmp_path: Path, case: str) -> None:
    key, said = CASES[case]
    line = refusal(write_case(tmp_path, case))
    assert f": {key} " in line and said in line, line


def test_a_relu_bias_that_moves_the_equilibrium_is_refused_by_the_exact_equilibrium_check(tmp_path: Path) -> None:
    """relu(1/2) = 1/2 is exact, and the loop's right-hand side at the origin is then -1/2, not 0."""
    save_npz(tmp_path / "n.npz", [([[1.0, 0.0], [0.0, 1.0]], [0.5, 0.0]), GOOD[1]], "relu")
    line = refusal(model_file(tmp_path, "n.npz"))
    assert "[equilibrium]: is not an equilibrium: x2' = -1/2 there" in line, line


def test_nothing_is_unpickled(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """An object array is refused before anything could run: pickle's loader is never called."""
    import pickle

    calls: list[Any] = []
    monkeypatch.setattr(pickle, "load", lambda *a, **k: calls.append(a))
    monkeypatch.setattr(pickle, "loads", lambda *a, **k: calls.append(a))
    refusal(write_case(tmp_path, "object array"))
    assert calls == []


# -- the lowering against a plain numpy forward pass -----------------------------------------------

def forward(layers: list[tuple[Any, Any]], activation: str, X: Any) -> Any:
    h = X
    for k, (W, b) in enumerate(layers):
        h = h @ np.asarray(W).T + np.asarray(b)
        if k < len(layers) - 1:
            h = np.tanh(h) if activation == "tanh" else np.maximum(h, 0) if activation == "relu" else 1 / (1 + np.exp(-h))
    return h


@pytest.mark.parametrize("activation", ["tanh", "relu", "sigmoid"])
def test_the_true_loop_evaluates_the_network_as_numpy_does(tmp_path: Path, activation: str) -> None:
    """Two hidden layers of random weights: the simulated (true) loop's field is the numpy forward pass.
    The last layer's rows come in pairs of opposite sign so that the output is 0 at the origin for every
    activation (sigmoid(0) = 1/2), and the origin stays an exact equilibrium."""
    rng = np.random.default_rng(11)
    layers = random_layers(rng, [2, 4, 3, 1])
    half = rng.normal(size=(1, 3))
    layers[-1] = (np.concatenate([half, -half], axis=1), np.zeros(1))  # pairs of equal neurons, opposite signs
    W2 = np.round(layers[1][0] * 1024) / 1024  # dyadic: the row sums below are exact
    if activation == "sigmoid":  # the first layer gives 1/2 at the origin: rows of sum 0 keep layer 2's argument 0
        W2[:, -1] = -W2[:, :-1].sum(axis=1)
    layers[1] = (np.concatenate([W2, W2], axis=0), np.zeros(6))  # ... made equal: neurons 4-6 repeat 1-3
    save_npz(tmp_path / "n.npz", layers, activation)
    model = load_any_model(model_file(tmp_path, "n.npz"))
    assert isinstance(model, RecastModel)
    X = rng.uniform(-3, 3, size=(200, 2))
    expected = -X[:, 0] - X[:, 1] + forward(layers, activation, X)[:, 0]
    np.testing.assert_allclose(FloatLoop(model.system)(X)[:, 1], expected, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(network_of(model).forward(X)[:, 0], forward(layers, activation, X)[:, 0], rtol=1e-13,
                               atol=1e-13)
    functions = {a.function for a in model.system.auxiliaries}
    assert functions == ({"abs"} if activation == "relu" else {"tanh"})


def test_the_shipped_policy_is_evaluated_as_numpy_evaluates_the_npz_file() -> None:
    model = load_any_model(EXAMPLE)
    assert isinstance(model, RecastModel)
    with np.load(ROOT / "examples" / "networks" / "pendulum_tanh_policy.npz") as f:
        W1, W2 = f["W1"], f["W2"]
    X = np.random.default_rng(3).uniform(-2, 2, size=(100, 2))
    u = np.tanh(X @ W1.T) @ W2.T
    expected = np.sin(X[:, 0]) - 0.1 * X[:, 1] + u[:, 0]
    np.testing.assert_allclose(FloatLoop(model.system)(X)[:, 1], expected, rtol=1e-12, atol=1e-12)


# -- the example, certified and verified -------------------------------------------------------------

@pytest.fixture(scope="module")
def certified_copy(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Path, dict[str, Any]]:
    """The example and its network copied to a fresh folder, certified there (linearization and roa)."""
    folder = tmp_path_factory.mktemp("example")
    (folder / "models").mkdir()
    shutil.copytree(ROOT / "examples" / "networks", folder / "networks")
    model = folder / "models" / EXAMPLE.name
    shutil.copy(EXAMPLE, model)
    cert = folder / "cert.json"
    done = CliRunner().invoke(app.cli, ["certify", str(model), "--classes", "linearization,roa", "--no-store",
                                        "--json", "--out", str(cert)])
    assert done.exit_code == 0, done.output
    return folder, cert, json.loads(done.stdout)


def test_the_example_certifies_as_its_comment_says(certified_copy: tuple[Path, Path, dict[str, Any]]) -> None:
    _, _, doc = certified_copy
    lin, roa = doc["conditions"]["linearization"], doc["conditions"]["roa"]
    assert lin["status"] == "certified" and lin["property"] == "LES"
    assert roa["status"] == "certified" and roa["property"] == "ROA"
    assert roa["certificate"]["kind"] == "interval" and roa["certificate"]["whole"] is True
    assert roa["size"]["ball_radius"] > 1.3  # the comment: the set holds the ball |x| <= 1.40
    assert doc["verdict"] == "certified"
    # the Jacobian is the plant's plus the network's exact slope W2 W1 (tanh'(0) = 1)
    with np.load(ROOT / "examples" / "networks" / "pendulum_tanh_policy.npz") as f:
        slope = [sum((Fraction(float(a)) * Fraction(float(b)) for a, b in zip(f["W2"][0], f["W1"][:, j])), Fraction(0))
                 for j in range(2)]
    J = [[Fraction(v) for v in row] for row in lin["certificate"]["jacobian"]]
    assert J == [[0, 1], [1 + slope[0], Fraction(-1, 10) + slope[1]]]


def test_verify_rechecks_the_certificate_and_fails_once_the_network_changes(
        certified_copy: tuple[Path, Path, dict[str, Any]]) -> None:
    folder, cert, _ = certified_copy
    done = CliRunner().invoke(app.cli, ["verify", str(cert)])
    assert done.exit_code == 0 and "certificate verified" in done.output, done.output
    assert "ok   networks: each network file is the one certified" in done.output
    stated = json.loads(cert.read_text())["model"]["networks"]
    assert stated == {"pi": {"file": "../networks/pendulum_tanh_policy.npz",
                             "sha256": network_of(load_any_model(folder / "models" / EXAMPLE.name)).sha256}}
    npz = folder / "networks" / "pendulum_tanh_policy.npz"
    with np.load(npz) as f:
        arrays = {k: f[k] for k in f.files}
    arrays["W2"] = arrays["W2"] * 0.5  # a weaker policy: the model text is the same, its network is not
    np.savez(npz, **arrays)
    done = CliRunner().invoke(app.cli, ["verify", str(cert)])
    assert done.exit_code == 1, done.output
    assert "FAIL networks: the file '../networks/pendulum_tanh_policy.npz' of [networks.pi] is not the one " \
           "certified: its SHA-256 differs" in done.output, done.output
    assert "FAIL recasting: the stated recasting differs" in done.output, done.output
    assert "FAIL linearization" in done.output and "certificate FAILS" in done.output, done.output


def test_the_onnx_variant_certifies_the_same_linearization() -> None:
    done = CliRunner().invoke(app.cli, ["certify", str(EXAMPLE_ONNX), "--classes", "linearization", "--no-store",
                                        "--json"])
    assert done.exit_code == 0, done.output
    lin = json.loads(done.stdout)["conditions"]["linearization"]
    assert lin["status"] == "certified" and lin["property"] == "LES"



def test_a_relu_network_is_a_loop_with_abs_and_its_linearization_is_piecewise_linear(tmp_path: Path) -> None:
    """relu(z) = max(0, z) = (z + abs(z))/2: not differentiable at the equilibrium, where every bias-free
    ReLU neuron's argument is 0; no Jacobian is guessed: the class proves LES from the piecewise-linear first-order
    part (lyapcheck.models.classes.piecewise_linearization), one kink per neuron, named in its certificate."""
    W1 = np.array([[1.0, 0.5], [-0.5, -1.0]])
    save_npz(tmp_path / "n.npz", [(W1, np.zeros(2)), ([[-1.0, 1.0]], [0.0])], "relu")
    path = model_file(tmp_path, "n.npz")
    model = load_any_model(path)
    assert isinstance(model, RecastModel) and [a.function for a in model.system.auxiliaries] == ["abs", "abs"]
    done = CliRunner().invoke(app.cli, ["certify", str(path), "--classes", "linearization", "--no-store", "--json"])
    lin = json.loads(done.stdout)["conditions"]["linearization"]
    assert lin["status"] == "certified" and lin["property"] == "LES", lin
    assert lin["certificate"]["kind"] == "piecewise_linear"
    assert [k["call"] for k in lin["certificate"]["kinks"]] == [f"neuron {j} of layer 1 of [networks.pi]"
                                                                for j in (1, 2)]


def reference_outputs(path: Path, X: Any) -> Any:
    """The ONNX file evaluated by the onnx package's own reference evaluator (float32)."""
    from onnx.reference import ReferenceEvaluator

    model = onnx.load(str(path))
    [result] = ReferenceEvaluator(model).run(None, {model.graph.input[0].name: np.asarray(X, dtype=np.float32)})
    return np.asarray(result, dtype=np.float64)


def test_the_onnx_files_read_are_the_networks_onnx_itself_evaluates(tmp_path: Path) -> None:
    """The orientation and Gemm's attributes (alpha, beta, transB) as the ONNX operators define them: the
    network read evaluates as onnx's reference evaluator evaluates the file (to float32's precision)."""
    rng = np.random.default_rng(5)
    X = rng.uniform(-2, 2, size=(50, 2))
    shipped = ROOT / "examples" / "networks" / "pendulum_tanh_policy.onnx"
    net = network_of(load_any_model(EXAMPLE_ONNX))
    np.testing.assert_allclose(net.forward(X), reference_outputs(shipped, X), rtol=1e-5, atol=1e-5)
    W = rng.normal(size=(2, 3)).astype(np.float32)  # (in, out): transB = 0
    V = (np.round(rng.normal(size=(1, 3)) * 256) / 256).astype(np.float32)  # (out, in): transB = 1
    c = np.array([0.25, -0.5, 0.125], dtype=np.float32)
    d = -(V @ np.maximum(2.0 * c, 0))  # exact (dyadic): the output is 0 at the origin, an exact equilibrium
    nodes = [helper.make_node("Gemm", ["x", "W", "c"], ["z"], alpha=0.5, beta=2.0),
             helper.make_node("Relu", ["z"], ["h"]),
             helper.make_node("Gemm", ["h", "V", "d"], ["y"], transB=1)]
    path = onnx_file(tmp_path / "n.onnx", nodes, {"W": W, "c": c, "V": V, "d": d})
    net = network_of(load_any_model(model_file(tmp_path, "n.onnx")))
    np.testing.assert_allclose(net.forward(X), reference_outputs(path, X), rtol=1e-5, atol=1e-5)


def _imitates_lqr(W1: np.ndarray, W2: np.ndarray, K: np.ndarray) -> None:
    """What the training script promises of a policy: weights on the 2**-10 grid, a fit of ``-K x`` on the
    box with an rms error under 0.12 (the shipped one: 0.109), a slope at 0 within 15 % of ``-K``, and a
    Hurwitz closed-loop linearization ``[[0, 1], [1 + g1, -0.1 + g2]]``."""
    for W in (W1, W2):
        assert np.array_equal(np.round(W * 2 ** 10) / 2 ** 10, W)
    grid = np.linspace(-1.5, 1.5, 31)
    X = np.array([[a, b] for a in grid for b in grid])
    assert float(np.sqrt(np.mean((np.tanh(X @ W1.T) @ W2.T + X @ K.T) ** 2))) < 0.12
    g = (W2 @ W1).ravel()
    assert np.all(np.abs(g + K.ravel()) <= 0.15 * np.abs(K.ravel())), g
    assert np.all(np.linalg.eigvals(np.array([[0.0, 1.0], [1.0 + g[0], -0.1 + g[1]]])).real < 0)


def test_the_training_script_gives_a_policy_like_the_shipped_one(tmp_path: Path) -> None:
    """examples/networks/train_pendulum_policy.py (fixed seed) writes a network of the shipped kind and
    quality: no biases, 8 tanh neurons, weights on the 2**-10 grid, imitating the LQR law as the shipped one
    does. Its exact weights are not compared: 20 000 gradient steps through numpy's tanh and BLAS land at
    another minimum of the same quality on another numpy (numpy 2.4 moves the slope at 0 from the shipped
    [-2.436, -2.497] to [-2.602, -2.337]); the shipped files are the ones certified."""
    import importlib.util

    spec = importlib.util.spec_from_file_location("train_pendulum_policy",
                                                  ROOT / "examples" / "networks" / "train_pendulum_policy.py")
    assert spec is not None and spec.loader is not None
    script = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(script)
    script.main(tmp_path)
    K = script.lqr_gain()
    with np.load(tmp_path / "pendulum_tanh_policy.npz") as new, \
            np.load(ROOT / "examples" / "networks" / "pendulum_tanh_policy.npz") as shipped:
        assert sorted(new.files) == sorted(shipped.files) == ["W1", "W2", "activation", "b1", "b2"]
        for net in (new, shipped):
            assert net["W1"].shape == (8, 2) and net["W2"].shape == (1, 8) and str(net["activation"]) == "tanh"
            assert not net["b1"].any() and not net["b2"].any()
            _imitates_lqr(net["W1"], net["W2"], K)
    fresh = network_of(load_any_model(model_file(tmp_path, "pendulum_tanh_policy.onnx", inputs='["x1", "x2"]')))
    assert fresh.neurons == 8


def test_the_limits_the_page_quotes_are_the_codes() -> None:
    from lyapcheck.models.language import networks

    text = (ROOT / "docs" / "model-files.md").read_text()
    assert networks.MAX_NEURONS == 64 and "more than 64 neurons with an activation in all (`MAX_NEURONS`)" in text
    assert networks.MAX_NETWORK_BYTES == 4 * 1024 * 1024 and "a file over 4 MiB (`MAX_NETWORK_BYTES`)" in text
    assert networks.ONNX_OPS == ("Gemm", "MatMul", "Add", "Tanh", "Relu", "Sigmoid")
