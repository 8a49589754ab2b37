"""Train the small tanh policy of ``examples/models/pendulum-tanh-policy.toml`` and write it as
``pendulum_tanh_policy.npz`` and ``pendulum_tanh_policy.onnx`` beside this script.

The plant is the normalized inverted pendulum ``theta'' = sin(theta) - 0.1*theta' + u`` (Astrom &
Murray, Feedback Systems, Example 2.10). Its linearization at the upright equilibrium,
``A = [[0, 1], [1, -0.1]]``, ``B = [[0], [1]]``, gives the LQR gain ``K`` (python-control's ``lqr``,
``Q = I``, ``R = 1``); the network ``u = W2 tanh(W1 [theta, omega])`` (2 inputs, 8 tanh neurons, 1
output) is fitted to ``u = -K x`` on a grid of the box ``[-1.5, 1.5]^2`` by plain full-batch gradient
descent from a fixed seed, then every weight is rounded to a multiple of ``2**-QUANTUM_BITS``.

Why no biases: with a bias ``b``, a neuron's value at the upright state is ``tanh(b)``, irrational for
every rational ``b != 0``, and the network's output there is not 0: the equilibrium moves off the
origin to a point nobody can write exactly. Without biases ``u(0) = 0`` exactly and the origin stays
an exact equilibrium, which lyapcheck checks in rational arithmetic.

Why rounded weights: lyapcheck reads each weight as the exact rational value of its binary float;
rounding to multiples of 2**-10 makes those rationals short (and the same in float32, the ONNX
file's type, and float64, the .npz file's), so the exact checks stay cheap. The rounded network is
the one shipped and certified.

Run: ``python examples/networks/train_pendulum_policy.py`` (deterministic on one machine and numpy: the
same files each time). Another numpy may land at another minimum of the same quality (its ``tanh`` and
BLAS round the 20 000 gradient steps differently: numpy 2.4 gives the slope [-2.602, -2.337] at 0
where the shipped network has [-2.436, -2.497]); the shipped files are the ones certified.
"""

from __future__ import annotations

from pathlib import Path

import control
import numpy as np
import onnx
from onnx import TensorProto, helper, numpy_helper

HERE = Path(__file__).resolve().parent
NAME = "pendulum_tanh_policy"
SEED = 0
HIDDEN = 8
STEPS = 20000
LEARNING_RATE = 0.05
QUANTUM_BITS = 10
HALF_WIDTH = 1.5


def lqr_gain() -> np.ndarray:
    A = np.array([[0.0, 1.0], [1.0, -0.1]])
    B = np.array([[0.0], [1.0]])
    K, _, _ = control.lqr(A, B, np.eye(2), np.eye(1))
    return np.asarray(K)


def train(K: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``W1`` (8, 2) and ``W2`` (1, 8) minimizing the mean squared error to ``-K x`` on the grid."""
    rng = np.random.default_rng(SEED)
    grid = np.linspace(-HALF_WIDTH, HALF_WIDTH, 31)
    X = np.array([[a, b] for a in grid for b in grid])
    target = -X @ K.T
    W1 = rng.normal(scale=0.5, size=(HIDDEN, 2))
    W2 = rng.normal(scale=0.5, size=(1, HIDDEN))
    for _ in range(STEPS):
        H = np.tanh(X @ W1.T)
        error = H @ W2.T - target
        grad_W2 = 2 * error.T @ H / len(X)
        grad_H = 2 * error @ W2 / len(X)
        grad_W1 = ((1 - H ** 2) * grad_H).T @ X
        W1 -= LEARNING_RATE * grad_W1
        W2 -= LEARNING_RATE * grad_W2
    return W1, W2


def quantized(W: np.ndarray) -> np.ndarray:
    return np.asarray(np.round(W * 2 ** QUANTUM_BITS) / 2 ** QUANTUM_BITS)


def write_onnx(W1: np.ndarray, W2: np.ndarray, path: Path) -> None:
    """The same network as an ONNX graph: Gemm (transB: W is (out, in)), Tanh, Gemm; zero biases."""
    inits = [numpy_helper.from_array(W1.astype(np.float32), "W1"), numpy_helper.from_array(np.zeros(HIDDEN, np.float32), "b1"),
             numpy_helper.from_array(W2.astype(np.float32), "W2"), numpy_helper.from_array(np.zeros(1, np.float32), "b2")]
    nodes = [helper.make_node("Gemm", ["x", "W1", "b1"], ["z1"], name="layer1", transB=1),
             helper.make_node("Tanh", ["z1"], ["h1"], name="tanh1"),
             helper.make_node("Gemm", ["h1", "W2", "b2"], ["u"], name="layer2", transB=1)]
    graph = helper.make_graph(nodes, NAME, [helper.make_tensor_value_info("x", TensorProto.FLOAT, [None, 2])],
                              [helper.make_tensor_value_info("u", TensorProto.FLOAT, [None, 1])], inits)
    model = helper.make_model(graph, producer_name="lyapcheck examples", opset_imports=[helper.make_opsetid("", 13)])
    model.ir_version = 8
    onnx.checker.check_model(model)
    path.write_bytes(model.SerializeToString())


def main(folder: Path = HERE) -> None:
    """Train and write both files into ``folder`` (by default beside this script)."""
    K = lqr_gain()
    W1, W2 = (quantized(W) for W in train(K))
    assert np.array_equal(W1.astype(np.float32).astype(np.float64), W1)  # exact in float32 too
    grid = np.linspace(-HALF_WIDTH, HALF_WIDTH, 31)
    X = np.array([[a, b] for a in grid for b in grid])
    rms = float(np.sqrt(np.mean((np.tanh(X @ W1.T) @ W2.T + X @ K.T) ** 2)))
    gain = W2 @ W1  # the network's slope at 0 (tanh'(0) = 1): u ~ gain x near the origin
    print(f"LQR K = {K.ravel()}, network slope at 0 = {gain.ravel()}, rms error on the box = {rms:.4f}")
    np.savez(folder / f"{NAME}.npz", W1=W1, b1=np.zeros(HIDDEN), W2=W2, b2=np.zeros(1), activation=np.array("tanh"))
    write_onnx(W1, W2, folder / f"{NAME}.onnx")


if __name__ == "__main__":
    main()
