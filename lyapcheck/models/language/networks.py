"""``[networks.NAME]``: small feedforward networks read from ``.npz`` or ONNX files, lowered into the
expression language's functions (issue 44, item 3; DESIGN.md, "Networks"; docs/model-files.md,
"Networks").

A network is data, as the model file is: an ``.npz`` file is read with ``allow_pickle=False`` (an
object array is refused, nothing is unpickled), an ONNX file with the ``onnx`` package as a graph of
``Gemm``/``MatMul``/``Add`` and ``Tanh``/``Relu``/``Sigmoid`` nodes whose weights are initializers;
nothing of either file is run.

Orientation: a layer is ``h_k = act_k(W_k h_{k-1} + b_k)`` with ``W_k`` of shape ``(out_k, in_k)``
(PyTorch's ``nn.Linear.weight``) and ``b_k`` of length ``out_k``; ``h_0`` is the inputs in the order
of ``inputs``, the last layer's values the outputs in the order of ``outputs``. In an ``.npz`` file
the arrays are ``W1, b1, W2, b2, ...`` and ``activation`` (a 0-d string array: ``tanh``, ``relu`` or
``sigmoid``) is the activation of every hidden layer, the last layer being linear. An ONNX graph says
each layer's activation itself (it may end in one: a policy bounded by a final ``Tanh``).

Exactness: every weight is the binary floating-point number stored in the file, read exactly as a
rational (``Fraction(float(w))``: ``0.1`` stored as a double is 3602879701896397/36028797018963968,
not 1/10). The network the certificates speak about is therefore exactly the one a float64 forward
pass evaluates, up to that pass's rounding.

Lowering (:func:`lower`): each neuron's pre-activation is an exact affine form of the previous
layer's values, built with the ring's own arithmetic (no text is formatted and read back), and each
activation is handed to the recasting (:class:`lyapcheck.models.language.recast.Recaster`) as the
language's own function: ``tanh(z)``; ``sigmoid(z) = (1 + tanh(z/2))/2`` (an identity); ``relu(z) =
max(0, z)``. The neurons are then auxiliaries with the relations of their functions, and the
network's outputs are names ``[dynamics]`` may use like any expression.
"""

from __future__ import annotations

import hashlib
import zipfile
from dataclasses import dataclass
from fractions import Fraction
from pathlib import Path
from typing import TYPE_CHECKING, Any, Final, Mapping, Sequence

import numpy as np

from lyapcheck.errors import ModelFileError

if TYPE_CHECKING:  # pragma: no cover
    from lyapcheck.models.language.expressions import FunctionCalls, Rational
    from lyapcheck.sos.polynomials import Ring

#: the activations a network may use, and the language's function each one is lowered to
ACTIVATIONS: Final = ("tanh", "relu", "sigmoid")
#: the keys of a ``[networks.NAME]`` table
NETWORK_KEYS: Final = ("file", "inputs", "outputs")
#: the suffixes read, and by what
SUFFIXES: Final = (".npz", ".onnx")
#: the largest network file, in bytes (the weights of a policy of a few hundred neurons)
MAX_NETWORK_BYTES: Final = 4 * 1024 * 1024
#: the most neurons with an activation in all of a model's networks: each one is an auxiliary of the
#: recast loop, and the classes' programs grow with their number
MAX_NEURONS: Final = 64
#: the ONNX operators read (anything else is refused, naming it)
ONNX_OPS: Final = ("Gemm", "MatMul", "Add", "Tanh", "Relu", "Sigmoid")


@dataclass(frozen=True)
class Layer:
    """``act(W h + b)``: ``weights`` rows are the outputs (``(out, in)``), all exact; ``activation`` is one
    of :data:`ACTIVATIONS` or ``"linear"``."""

    weights: tuple[tuple[Fraction, ...], ...]
    bias: tuple[Fraction, ...]
    activation: str

    @property
    def width_in(self) -> int:
        return len(self.weights[0]) if self.weights else 0

    @property
    def width_out(self) -> int:
        return len(self.weights)


@dataclass(frozen=True)
class Network:
    """One ``[networks.NAME]``: where it was read from (``file`` as written, the SHA-256 of its bytes), its
    input and output names and its layers."""

    name: str
    file: str
    sha256: str
    inputs: tuple[str, ...]
    outputs: tuple[str, ...]
    layers: tuple[Layer, ...]

    @property
    def key(self) -> str:
        return f"[networks.{self.name}]"

    @property
    def neurons(self) -> int:
        """The neurons with an activation (each one auxiliary of the recast loop)."""
        return sum(layer.width_out for layer in self.layers if layer.activation != "linear")

    def forward(self, x: Any) -> np.ndarray:
        """The outputs at inputs ``x`` (rows), in float64 as numpy evaluates the file's network."""
        h = np.atleast_2d(np.asarray(x, dtype=np.float64))
        for layer in self.layers:
            W = np.array([[float(w) for w in row] for row in layer.weights])
            z = h @ W.T + np.array([float(b) for b in layer.bias])
            h = (np.tanh(z) if layer.activation == "tanh" else np.maximum(z, 0.0) if layer.activation == "relu"
                 else 1.0 / (1.0 + np.exp(-z)) if layer.activation == "sigmoid" else z)
        return h


# -- reading ---------------------------------------------------------------------------------------

def read_networks(source: str, table: object, states: Sequence[str], taken: Mapping[str, str]) -> tuple[Network, ...]:
    """``[networks]``: each ``[networks.NAME]`` read, checked and returned in the file's order.

    ``taken`` maps every name already declared (states, parameters, disturbances, outputs, the language's
    functions) to what it is, so that an output name is never a second meaning of one. Raises
    :class:`~lyapcheck.errors.ModelFileError` (one line naming ``[networks.NAME]``, what was expected and
    what was found) on anything refused."""
    import keyword

    if not isinstance(table, dict):
        raise ModelFileError(source, "[networks]", f"must be a table of [networks.NAME] tables, got {type(table).__name__}")
    used = dict(taken)
    out = []
    for name, entry in table.items():
        key = f"[networks.{name}]"
        if not isinstance(entry, dict):
            raise ModelFileError(source, key, f"must be a table with {', '.join(NETWORK_KEYS)}, got {entry!r}")
        bad = [k for k in entry if k not in NETWORK_KEYS]
        if bad:
            raise ModelFileError(source, f"{key} {bad[0]}", f"unknown key (keys: {', '.join(NETWORK_KEYS)})")
        for k in NETWORK_KEYS:
            if k not in entry:
                raise ModelFileError(source, key, f"has no '{k}' (keys: {', '.join(NETWORK_KEYS)})")
        file = entry["file"]
        if not isinstance(file, str) or not file:
            raise ModelFileError(source, f"{key} file", f"must be a file name in a string, got {file!r}")
        inputs, outputs = (_names(source, f"{key} {k}", entry[k]) for k in ("inputs", "outputs"))
        for s in inputs:
            if s not in states:
                raise ModelFileError(source, f"{key} inputs", f"'{s}' is not a state; a network's inputs are states "
                                                             f"(states: {', '.join(states)})")
        for o in outputs:
            if not o.isidentifier() or keyword.iskeyword(o) or not o.isascii():
                raise ModelFileError(source, f"{key} outputs", f"'{o}' is not a valid name (letters, digits and _, "
                                                              "not starting with a digit, not a Python keyword)")
            if o in used:
                raise ModelFileError(source, f"{key} outputs", f"the name '{o}' is declared twice (also {used[o]})")
            used[o] = f"an output of {key}"
        path = Path(source).parent / file
        layers, digest = read_layers(source, key, path, file)
        if layers[0].width_in != len(inputs):
            raise ModelFileError(source, f"{key} inputs", f"names {len(inputs)} inputs, but the network's first layer "
                                                         f"takes {layers[0].width_in} (in '{file}')")
        if layers[-1].width_out != len(outputs):
            raise ModelFileError(source, f"{key} outputs", f"names {len(outputs)} outputs, but the network's last "
                                                          f"layer gives {layers[-1].width_out} (in '{file}')")
        out.append(Network(str(name), file, digest, inputs, outputs, layers))
    total = sum(n.neurons for n in out)
    if total > MAX_NEURONS:
        raise ModelFileError(source, "[networks]", f"have {total} neurons with an activation; the limit is "
                                                   f"{MAX_NEURONS} (MAX_NEURONS)")
    return tuple(out)


def _names(source: str, key: str, value: object) -> tuple[str, ...]:
    if not isinstance(value, list) or not value or not all(isinstance(v, str) for v in value):
        raise ModelFileError(source, key, f"must be a non-empty list of names, got {value!r}")
    if len(set(value)) != len(value):
        twice = next(v for v in value if value.count(v) > 1)
        raise ModelFileError(source, key, f"names '{twice}' twice")
    return tuple(value)


def read_layers(source: str, key: str, path: Path, written: str) -> tuple[tuple[Layer, ...], str]:
    """The layers of the network file at ``path`` (``written`` as the model file gives it) and the
    SHA-256 of its bytes: ``.npz`` (:func:`_npz_layers`) or ``.onnx`` (:func:`_onnx_layers`)."""
    suffix = path.suffix.lower()
    if suffix not in SUFFIXES:
        raise ModelFileError(source, f"{key} file", f"must be a .npz or .onnx file, got '{written}'")
    try:
        size = path.stat().st_size
        if not path.is_file():
            raise ModelFileError(source, f"{key} file", f"'{written}' is not a file")
        if size > MAX_NETWORK_BYTES:
            raise ModelFileError(source, f"{key} file", f"'{written}' is {size} bytes; the limit is {MAX_NETWORK_BYTES} "
                                                        "(MAX_NETWORK_BYTES)")
        data = path.read_bytes()
    except FileNotFoundError:
        raise ModelFileError(source, f"{key} file", f"'{written}' not found (paths are relative to the model file: "
                                                    f"looked for {path})") from None
    except OSError as exc:
        raise ModelFileError(source, f"{key} file", f"'{written}' cannot be read: {exc.strerror or exc}") from None
    digest = hashlib.sha256(data).hexdigest()
    layers = _npz_layers(source, key, path, written) if suffix == ".npz" else _onnx_layers(source, key, data, written)
    return layers, digest


def _exact(source: str, key: str, array: Any, what: str, written: str) -> list[Fraction]:
    """An array's entries as exact rationals (each float's binary value), refusing non-numbers and
    non-finite values."""
    a = np.asarray(array)
    if a.dtype.kind not in "fiu":
        raise ModelFileError(source, key, f"{what} in '{written}' must be an array of numbers, got dtype {a.dtype}")
    if a.dtype.kind == "f" and not np.all(np.isfinite(a)):
        raise ModelFileError(source, key, f"{what} in '{written}' has a value that is not finite "
                                          f"({a.ravel()[~np.isfinite(a.ravel())][0]})")
    return [Fraction(int(v)) if a.dtype.kind in "iu" else Fraction(float(v)) for v in a.ravel()]


def _layer(source: str, key: str, W: Any, b: Any, activation: str, k: int, written: str, width_in: int | None
           ) -> Layer:
    """Layer ``k`` (from 1) from its arrays, shapes checked: ``W`` is ``(out, in)`` with ``in`` the previous
    layer's ``out``, ``b`` of length ``out``."""
    W, b = np.asarray(W), np.asarray(b)
    if W.ndim != 2 or 0 in W.shape:
        raise ModelFileError(source, key, f"W{k} in '{written}' must be a matrix (out, in), got shape {W.shape}")
    out, inp = W.shape
    if width_in is not None and inp != width_in:
        raise ModelFileError(source, key, f"W{k} in '{written}' has shape {W.shape}: expected ({out}, {width_in}), as "
                                          f"layer {k - 1} gives {width_in} values (W is (out, in))")
    if b.shape != (out,):
        raise ModelFileError(source, key, f"b{k} in '{written}' has shape {b.shape}: expected ({out},), the rows of "
                                          f"W{k}")
    w = _exact(source, key, W, f"W{k}", written)
    return Layer(tuple(tuple(w[i * inp:(i + 1) * inp]) for i in range(out)),
                 tuple(_exact(source, key, b, f"b{k}", written)), activation)


def _npz_layers(source: str, key: str, path: Path, written: str) -> tuple[Layer, ...]:
    """``W1, b1, W2, b2, ...`` and ``activation`` from an ``.npz`` file, read with ``allow_pickle=False``."""
    try:
        archive = np.load(path, allow_pickle=False)
    except (ValueError, OSError, zipfile.BadZipFile, EOFError) as exc:
        raise ModelFileError(source, f"{key} file", f"'{written}' is not a readable .npz archive ({_short(exc)})") \
            from None
    if not isinstance(archive, np.lib.npyio.NpzFile):  # a bare .npy saved under the suffix .npz
        raise ModelFileError(source, f"{key} file", f"'{written}' is a single array, not an .npz archive of W1, b1, ...")
    with archive:
        arrays: dict[str, Any] = {}
        for name in archive.files:
            try:
                arrays[name] = archive[name]
            except ValueError:  # an object array: reading it would unpickle
                raise ModelFileError(source, key, f"the array '{name}' in '{written}' is a pickled (object) array; "
                                                  "only numeric arrays and the activation string are read, nothing is "
                                                  "unpickled") from None
            except (OSError, zipfile.BadZipFile, EOFError) as exc:
                raise ModelFileError(source, key, f"the array '{name}' in '{written}' cannot be read "
                                                  f"({_short(exc)})") from None
    depth = 0
    while f"W{depth + 1}" in arrays or f"b{depth + 1}" in arrays:
        depth += 1
        for part in ("W", "b"):
            if f"{part}{depth}" not in arrays:
                raise ModelFileError(source, key, f"'{written}' has {'b' if part == 'W' else 'W'}{depth} but no "
                                                  f"{part}{depth} (arrays W1, b1, W2, b2, ... and activation)")
    if depth == 0:
        raise ModelFileError(source, key, f"'{written}' has no W1 and b1 (arrays W1, b1, W2, b2, ... and activation); "
                                          f"found {', '.join(sorted(arrays)) or 'no array'}")
    expected = {f"{p}{k}" for k in range(1, depth + 1) for p in "Wb"} | {"activation"}
    stray = sorted(set(arrays) - expected)
    if stray:
        raise ModelFileError(source, key, f"'{written}' has an unexpected array '{stray[0]}' (expected W1, b1, ..., "
                                          f"W{depth}, b{depth} consecutive, and activation)")
    activation = "linear"
    if depth > 1 or "activation" in arrays:
        if "activation" not in arrays:
            raise ModelFileError(source, key, f"'{written}' has hidden layers but no 'activation' array (one of "
                                              f"{', '.join(ACTIVATIONS)})")
        act = arrays["activation"]
        if act.shape != () or act.dtype.kind not in "US":
            raise ModelFileError(source, key, f"'activation' in '{written}' must be a 0-d string array (one of "
                                              f"{', '.join(ACTIVATIONS)}), got dtype {act.dtype} shape {act.shape}")
        activation = act.item().decode() if act.dtype.kind == "S" else str(act.item())
        if activation not in ACTIVATIONS:
            raise ModelFileError(source, key, f"'activation' in '{written}' must be one of {', '.join(ACTIVATIONS)}, "
                                              f"got {activation!r}")
    layers: list[Layer] = []
    for k in range(1, depth + 1):
        layers.append(_layer(source, key, arrays[f"W{k}"], arrays[f"b{k}"], activation if k < depth else "linear", k,
                             written, layers[-1].width_out if layers else None))
    return tuple(layers)


def _onnx_layers(source: str, key: str, data: bytes, written: str) -> tuple[Layer, ...]:
    """An ONNX graph read as a chain of layers: from its one input, ``MatMul``/``Gemm``/``Add`` with
    initializer weights accumulate one affine map (composed exactly), and ``Tanh``/``Relu``/``Sigmoid``
    closes a layer; the chain must end at the graph's one output."""
    import onnx
    from onnx import numpy_helper

    try:
        model = onnx.load_model_from_string(data)
    except Exception as exc:  # the protobuf decoder's own errors (DecodeError and others): not an ONNX file
        raise ModelFileError(source, f"{key} file", f"'{written}' is not a readable ONNX model ({_short(exc)})") \
            from None
    graph = model.graph
    weights: dict[str, Any] = {}
    for init in graph.initializer:
        if init.data_location == onnx.TensorProto.EXTERNAL:
            raise ModelFileError(source, key, f"the initializer '{init.name}' in '{written}' is stored in an external "
                                              "file; only weights inside the ONNX file are read")
        weights[init.name] = numpy_helper.to_array(init)
    inputs = [i for i in graph.input if i.name not in weights]
    if len(inputs) != 1 or len(graph.output) != 1:
        raise ModelFileError(source, key, f"'{written}' must have one input and one output, got {len(inputs)} "
                                          f"input(s) and {len(graph.output)} output(s)")
    current = inputs[0].name
    layers: list[Layer] = []
    W: list[list[Fraction]] | None = None  # the affine map since the last activation (None: the identity)
    b: list[Fraction] = []
    width: int | None = _static_width(inputs[0])

    def operand(node: Any, name: str, what: str) -> Any:
        if name not in weights:
            raise ModelFileError(source, key, f"node '{node.name or node.op_type}' ({node.op_type}) in '{written}': "
                                              f"its {what} '{name}' is not an initializer (a network is a chain of "
                                              "layers whose weights are initializers)")
        return weights[name]

    def identity(n: int) -> list[list[Fraction]]:
        return [[Fraction(int(i == j)) for j in range(n)] for i in range(n)]

    for node in graph.node:
        op = node.op_type
        if op not in ONNX_OPS or node.domain not in ("", "ai.onnx"):
            raise ModelFileError(source, key, f"'{written}' uses the operator {op!r} (node '{node.name}'); read are "
                                              f"{', '.join(ONNX_OPS)}")
        if current not in node.input:
            raise ModelFileError(source, key, f"node '{node.name or op}' ({op}) in '{written}' does not take the "
                                              f"previous node's output '{current}': the graph is not a chain of layers")
        others = [name for name in node.input if name != current and name]
        if op in ("Tanh", "Relu", "Sigmoid"):
            if W is None:  # an activation right after another one, or on the input
                if width is None:
                    raise ModelFileError(source, key, f"'{written}': the width before {op} is not known")
                W, b = identity(width), [Fraction(0)] * width
            layers.append(Layer(tuple(tuple(r) for r in W), tuple(b), op.lower()))
            width, W, b = len(W), None, []
        elif op in ("MatMul", "Gemm"):
            attrs = {a.name: onnx.helper.get_attribute_value(a) for a in node.attribute}
            if node.input[0] != current or attrs.get("transA", 0):
                raise ModelFileError(source, key, f"node '{node.name or op}' ({op}) in '{written}' must multiply the "
                                                  "previous output from the left, untransposed (x W or Gemm with "
                                                  "transA = 0)")
            matrix = np.asarray(operand(node, node.input[1], "weight"))
            if matrix.ndim != 2:
                raise ModelFileError(source, key, f"the weight '{node.input[1]}' in '{written}' must be a matrix, got "
                                                  f"shape {matrix.shape}")
            if op == "Gemm" and attrs.get("transB", 0):
                matrix = matrix.T
            # x (1, in) times matrix (in, out): in the (out, in) orientation the layer's W is matrix^T
            inp, out = matrix.shape
            if width is not None and inp != width:
                raise ModelFileError(source, key, f"node '{node.name or op}' ({op}) in '{written}' takes {inp} values, "
                                                  f"but {width} come in (weight '{node.input[1]}' of shape "
                                                  f"{matrix.shape})")
            values = _exact(source, key, matrix, f"the weight '{node.input[1]}'", written)
            M = [[values[i * out + j] for i in range(inp)] for j in range(out)]  # (out, in)
            alpha = Fraction(float(attrs.get("alpha", 1.0))) if op == "Gemm" else Fraction(1)
            M = [[alpha * m for m in row] for row in M]
            prev, prev_b = (identity(inp), [Fraction(0)] * inp) if W is None else (W, b)
            W = [[sum((M[j][i] * prev[i][c] for i in range(inp)), Fraction(0)) for c in range(len(prev[0]))]
                 for j in range(out)]
            b = [sum((M[j][i] * prev_b[i] for i in range(inp)), Fraction(0)) for j in range(out)]
            width = out
            if op == "Gemm" and len(node.input) > 2 and node.input[2]:
                beta = Fraction(float(attrs.get("beta", 1.0)))
                c = _bias(source, key, operand(node, node.input[2], "bias"), out, node.input[2], written)
                b = [bj + beta * cj for bj, cj in zip(b, c)]
        else:  # Add: a bias
            if len(others) != 1:
                raise ModelFileError(source, key, f"node '{node.name or op}' (Add) in '{written}' must add an "
                                                  "initializer to the previous output")
            if W is None:
                if width is None:
                    raise ModelFileError(source, key, f"'{written}': the width before Add is not known")
                W, b = identity(width), [Fraction(0)] * width
            c = _bias(source, key, operand(node, others[0], "bias"), len(W), others[0], written)
            b = [bj + cj for bj, cj in zip(b, c)]
        if len(node.output) != 1:
            raise ModelFileError(source, key, f"node '{node.name or op}' ({op}) in '{written}' must have one output")
        current = node.output[0]
    if W is not None:
        layers.append(Layer(tuple(tuple(r) for r in W), tuple(b), "linear"))
    if current != graph.output[0].name or not layers:
        raise ModelFileError(source, key, f"'{written}': the chain of nodes does not end at the graph's output "
                                          f"'{graph.output[0].name}'")
    return tuple(layers)


def _static_width(value_info: Any) -> int | None:
    """The last dimension of a graph input, when the file states it."""
    dims = value_info.type.tensor_type.shape.dim
    return int(dims[-1].dim_value) if dims and dims[-1].HasField("dim_value") else None


def _bias(source: str, key: str, array: Any, width: int, name: str, written: str) -> list[Fraction]:
    a = np.asarray(array)
    if a.size != width or (a.ndim > 1 and a.shape[-1] != width):
        raise ModelFileError(source, key, f"the bias '{name}' in '{written}' has shape {a.shape}: expected ({width},)")
    return _exact(source, key, a, f"the bias '{name}'", written)


def _short(exc: BaseException) -> str:
    text = " ".join(str(exc).split()) or type(exc).__name__
    return text if len(text) <= 120 else text[:120] + "..."


def outputs_at(source: str, network: Network, point: Mapping[str, Fraction]) -> tuple[Fraction, ...]:
    """The network's outputs at the states ``point`` (the equilibrium), exactly; a ``tanh`` or ``sigmoid``
    neuron whose argument is not 0 there has a transcendental value, and the loop's equilibrium could
    not be checked exactly: refused in one line naming the neuron (a network without biases, or whose
    biases cancel there, keeps the equilibrium exact)."""
    h = [point[s] for s in network.inputs]
    for k, layer in enumerate(network.layers, start=1):
        z = [sum((w * v for w, v in zip(row, h)), bias) for row, bias in zip(layer.weights, layer.bias)]
        if layer.activation in ("tanh", "sigmoid"):
            for j, zj in enumerate(z, start=1):
                if zj != 0:
                    raise ModelFileError(source, network.key, f"neuron {j} of layer {k} ({layer.activation}) has the "
                                                              f"argument {float(zj):.6g} at the equilibrium, where "
                                                              f"{layer.activation} is transcendental: the equilibrium "
                                                              "cannot be checked exactly (expected 0 there: no biases, "
                                                              "or biases that cancel at the equilibrium)")
            h = [Fraction(0) if layer.activation == "tanh" else Fraction(1, 2) for _ in z]
        elif layer.activation == "relu":
            h = [max(Fraction(0), zj) for zj in z]
        else:
            h = z
    return tuple(h)


# -- in certificates -------------------------------------------------------------------------------

def stated_files(networks: Sequence[Network]) -> dict[str, dict[str, str]]:
    """``model.networks`` of a certificate: each network's file as the model file writes it and the
    SHA-256 of its bytes (the model text's own SHA-256 does not cover them)."""
    return {n.name: {"file": n.file, "sha256": n.sha256} for n in networks}


def check_stated_files(stated: object, networks: Sequence[Network]) -> tuple[bool, str]:
    """Whether a certificate's ``model.networks`` are the files the model reads now (``verify``'s row)."""
    if stated == stated_files(networks):
        return True, "each network file is the one certified (its SHA-256)"
    if not isinstance(stated, dict):
        return False, "the certificate does not state its network files' SHA-256"
    for n in networks:
        entry = stated.get(n.name)
        if not isinstance(entry, dict) or entry.get("sha256") != n.sha256:
            return False, f"the file '{n.file}' of {n.key} is not the one certified: its SHA-256 differs"
    return False, "the stated networks are not the model text's"


# -- lowering --------------------------------------------------------------------------------------

def lower(network: Network, ring: "Ring", calls: "FunctionCalls") -> dict[str, "Rational"]:
    """Each output of ``network`` as an exact expression of the ring's states (``calls``, the recasting,
    makes each neuron's activation an auxiliary): layer by layer, ``z = W h + b`` on the exact
    rationals, then ``tanh(z)``, ``(1 + tanh(z/2))/2`` or ``max(0, z)``."""
    from lyapcheck.models.language.expressions import Rational
    from lyapcheck.sos.polynomials import to_fmpq

    def constant(c: Fraction) -> Rational:
        return Rational.polynomial(ring, ring.constant(c))

    h = [Rational.polynomial(ring, ring.gen(s)) for s in network.inputs]
    for k, layer in enumerate(network.layers, start=1):
        z = []
        for row, bias in zip(layer.weights, layer.bias):
            num = ring.constant(bias)
            for w, value in zip(row, h):
                if w:
                    num = num + value.numerator * to_fmpq(w)  # every h is a polynomial (denominator 1)
            z.append(Rational.polynomial(ring, num))
        if layer.activation == "linear":
            h = z
            continue
        h = []
        for j, zj in enumerate(z, start=1):
            text = f"neuron {j} of layer {k} of {network.key}"
            if layer.activation == "tanh":
                h.append(calls.apply("tanh", [zj], text))
            elif layer.activation == "sigmoid":
                half = constant(Fraction(1, 2))
                h.append(half + half * calls.apply("tanh", [half * zj], text))
            else:
                h.append(calls.apply("max", [constant(Fraction(0)), zj], text))
        h = [Rational.polynomial(ring, v.normalized().numerator) for v in h]
    return dict(zip(network.outputs, h))


__all__ = ["ACTIVATIONS", "Layer", "Network", "read_networks", "read_layers", "outputs_at", "lower", "stated_files",
           "check_stated_files", "MAX_NEURONS"]
