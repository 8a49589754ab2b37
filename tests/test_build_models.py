"""Models built in Python (lyapcheck.models.language.build): sympy expressions and python-control loops, read
as the model file ``to_toml`` returns, exactly."""

from __future__ import annotations

from fractions import Fraction
from pathlib import Path

import numpy as np
import pytest
import sympy as sp

from lyapcheck import Model, certify, close_loop, verify
from lyapcheck.errors import InvalidParameter
from lyapcheck.models.language.modelfile import Model as FileModel
from lyapcheck.models.language.modelfile import load_model, parse_any_model
from lyapcheck.models.language.recast import RecastModel
from tests.conftest import ROOT

EXAMPLES = ROOT / "examples" / "models"
x1, x2, k, c = sp.symbols("x1 x2 k c")


def oscillator() -> FileModel:
    """examples/models/damped-oscillator.toml, written with sympy."""
    model = Model.from_sympy([x1, x2], [x2, -k * x1 - c * x2], parameters={k: 1, c: 1},
                             domain={x1: (-1, 1), x2: (-1, 1)}, name="damped linear oscillator")
    assert isinstance(model, FileModel) and isinstance(model, Model)
    return model


def linear_part(model: FileModel) -> list[list[Fraction]]:
    """The matrix of a linear field with no parameters: f(e_j) is its column j."""
    ring, n = model.ring, model.n
    columns = []
    for j in range(n):
        point = [Fraction(int(i == j)) for i in range(len(ring.names))]
        columns.append([ring.evaluate(f.numerator, point) / ring.evaluate(f.denominator, point)
                        for f in model.dynamics])
    return [[columns[j][i] for j in range(n)] for i in range(n)]


def test_a_polynomial_loop_gets_the_statuses_of_its_file() -> None:
    classes = "linearization,quadratic,sos_gas,roa"
    built = certify(model=oscillator(), classes=classes)
    filed = certify(model=EXAMPLES / "damped-oscillator.toml", classes=classes)
    statuses = {name: (c.status, c.property) for name, c in built.conditions.items()}
    assert statuses == {name: (c.status, c.property) for name, c in filed.conditions.items()}
    assert statuses["quadratic"] == ("certified", "GES") and built.verdict == filed.verdict
    # the certificate carries the built text and its SHA-256, and re-checks
    assert built.to_dict()["model"]["sha256"] == oscillator().sha256
    assert verify(built.to_json()).valid


def test_to_toml_round_trips(tmp_path: Path) -> None:
    model = oscillator()
    path = tmp_path / "oscillator.toml"
    path.write_text(model.to_toml())
    again = load_model(path)
    assert again.dynamics == model.dynamics and again.parameters == model.parameters
    assert again.domain == model.domain and again.sha256 == model.sha256 and again.text == model.text
    filed = load_model(EXAMPLES / "damped-oscillator.toml")
    assert [f.normalized() for f in filed.dynamics] == [f.normalized() for f in model.dynamics]
    assert filed.parameters == model.parameters and filed.domain == model.domain
    read = Model.from_toml(model.to_toml())
    assert isinstance(read, FileModel) and read.dynamics == model.dynamics
    with pytest.raises(TypeError, match="Model.from_sympy"):
        Model()


def test_a_float_is_its_decimal() -> None:
    a = sp.Symbol("a")
    model = Model.from_sympy([x1], [-0.1 * x1 - a * x1 ** 3], parameters={a: 0.3}, equilibrium=[0.0])
    assert isinstance(model, FileModel)
    ring = model.ring
    assert ring.terms(model.dynamics[0].numerator)[(1, 0)] == Fraction(-1, 10)
    assert model.parameters == {"a": Fraction(3, 10)}
    # a sympy Float of another precision is not a double: refused, not rounded
    with pytest.raises(InvalidParameter, match=r"'rhs\[x1\]'.*sympy.Rational"):
        Model.from_sympy([x1], [-sp.Float("0.1", 30) * x1])
    with pytest.raises(InvalidParameter, match=r"'parameters\[a\]'.*terminating decimal"):
        Model.from_sympy([x1], [-a * x1], parameters={a: sp.Rational(1, 3)})


@pytest.mark.parametrize(("rhs", "named"), [
    (-x1 ** sp.Rational(1, 3), r"x1\*\*\(1/3\)"),
    (-x1 + sp.Symbol("z"), r"the symbol 'z' is not declared"),
    (-sp.cot(x1), r"the function 'cot'"),
    (-sp.Function("f")(x1), r"the function 'f'"),
    (-x1 + sp.I, r"'I'"),
])
def test_outside_the_language_is_refused_naming_it(rhs: sp.Expr, named: str) -> None:
    with pytest.raises(InvalidParameter, match=r"^The 'rhs\[x1\]' parameter must be an expression of the model "
                                               r"language.*" + named) as caught:
        Model.from_sympy([x1], [rhs])
    assert "\n" not in str(caught.value)


def test_a_string_never_reaches_sympify(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.chdir(tmp_path)
    attack = "__import__('pathlib').Path('ran').touch() or x1"
    with pytest.raises(InvalidParameter, match=r"'rhs\[x1\]'.*not a string"):
        Model.from_sympy([x1], [attack])
    with pytest.raises(InvalidParameter, match=r"'outputs\[y\]'.*not a string"):
        Model.from_sympy([x1], [-x1], outputs={"y": attack})
    with pytest.raises(InvalidParameter, match=r"'sets\[unsafe\]\[0\]'.*a string is never parsed"):
        Model.from_sympy([x1], [-x1], sets={"unsafe": [attack]})
    u = sp.Symbol("u")
    with pytest.raises(InvalidParameter, match=r"'law\[u\]'.*not a string"):
        close_loop([x1], [u], [u], law=[attack])
    with pytest.raises(InvalidParameter, match=r"'states\[0\]'.*Symbol"):
        Model.from_sympy(["x1"], [-x1])
    assert not (tmp_path / "ran").exists()


def test_a_loop_with_sin_certifies() -> None:
    # x'' = -x - sin(x) - x': the energy x**2/2 + 1 - cos(x) is radially unbounded, 0 the only equilibrium
    theta, omega = sp.symbols("theta omega")
    model = Model.from_sympy([theta, omega], [omega, -theta - sp.sin(theta) - omega])
    assert isinstance(model, RecastModel) and isinstance(model, Model)
    assert 'omega = "-omega - theta - sin(theta)"' in model.to_toml()
    again = parse_any_model(model.to_toml())
    assert isinstance(again, RecastModel) and again.sha256 == model.sha256
    found = certify(model=model, classes="linearization,sos_gas")  # type: ignore[arg-type]  # certify takes both kinds
    assert found.conditions["linearization"].status == "certified"
    assert found.conditions["sos_gas"].status == "certified" and verify(found.to_json()).valid


def test_a_state_space_closed_with_a_gain_is_a_minus_b_k_exactly() -> None:
    control = pytest.importorskip("control")
    A = np.array([[0.0, 1.0, 0.0], [0.0, 0.0, 1.0], [-0.3, 0.1, -1.7]])
    B = np.array([[0.0, 1.0], [0.0, 0.2], [1.0, 0.0]])
    K, _, _ = control.lqr(A, B, np.eye(3), np.eye(2))
    model = Model.from_control(control.ss(A, B, np.eye(3), np.zeros((3, 2))), K)
    assert isinstance(model, FileModel) and model.states == ("x1", "x2", "x3")
    exact = lambda v: Fraction(repr(float(v)))  # noqa: E731 - the decimal a float is read as
    expected = [[exact(A[i, j]) - sum(exact(B[i, m]) * exact(K[m, j]) for m in range(2)) for j in range(3)]
                for i in range(3)]
    assert linear_part(model) == expected
    assert np.allclose(np.array(expected, dtype=float), A - B @ K, rtol=1e-12, atol=1e-12)
    # with an equilibrium, u = -K (x - x_eq): the loop is (A - B K)(x - x_eq) + A x_eq, declared with
    # x_eq (which the parser checks is one); here A = 0, so every x_eq is
    shifted = Model.from_control(control.ss(np.zeros((3, 3)), B, np.eye(3), np.zeros((3, 2))), K,
                                 equilibrium=[0.5, 0, 0])
    assert isinstance(shifted, FileModel) and shifted.equilibrium == (Fraction(1, 2), Fraction(0), Fraction(0))
    point = [Fraction(3, 2), Fraction(0), Fraction(0)]  # x - x_eq = e_1: f is column 1 of -B K
    assert [shifted.ring.evaluate(f.numerator, point) for f in shifted.dynamics] == \
        [-sum(exact(B[i, m]) * exact(K[m, 0]) for m in range(2)) for i in range(3)]


def test_a_nonlinear_io_system_is_refused_in_one_line() -> None:
    control = pytest.importorskip("control")
    plant = control.nlsys(lambda t, x, u, params: -x + u, None, states=1, inputs=1, outputs=1)
    with pytest.raises(InvalidParameter, match=r"NonlinearIOSystem.*close_loop") as caught:
        Model.from_control(plant, [[1.0]])
    assert "\n" not in str(caught.value)
    with pytest.raises(InvalidParameter, match=r"'gain'.*1 x 2"):
        Model.from_control(control.ss([[0, 1], [0, 0]], [[0], [1]], np.eye(2), np.zeros((2, 1))), [[1.0]])


def test_a_sympy_plant_closed_with_a_law_is_the_substituted_loop() -> None:
    u, b = sp.symbols("u b")
    plant = [x2, -sp.sin(x1) - b * x2 + u]
    by_law = close_loop([x1, x2], [u], plant, law={u: -x1 - 2 * x2}, parameters={b: 0.5})
    by_gain = close_loop([x1, x2], [u], plant, gain=[[1, 2]], parameters={b: 0.5})
    by_hand = Model.from_sympy([x1, x2], [x2, -sp.sin(x1) - b * x2 - x1 - 2 * x2], parameters={b: 0.5})
    assert by_law.to_toml() == by_gain.to_toml() == by_hand.to_toml()
    with pytest.raises(InvalidParameter, match=r"'law\[u\]'.*not in the inputs"):
        close_loop([x1, x2], [u], plant, law=[-x1 + u])
    with pytest.raises(InvalidParameter, match=r"'law'.*one of law and gain"):
        close_loop([x1, x2], [u], plant)


@pytest.mark.parametrize("expr", [
    -x1 + sp.Rational(1, 3) - x2 / 7, 3 * x1 ** 2 * x2 / (4 * (x1 - 2) ** 2 * (x2 + 3)), -(x1 + 1) ** 3 / 5,
    x1 / (x2 ** 2 + 1) - 1 / (x1 - 2), sp.Rational(-7, 20) * x1 * x2 - sp.Rational(3, 40) + x2 ** 12,
    (x1 - x2) * (x1 + 2 * x2 - sp.Rational(1, 2)) ** 2 - 2, 1 / (2 * x1 - 5),
])
def test_the_printed_text_is_the_expression(expr: sp.Expr) -> None:
    # the printer's text, read by the model language, is the sympy expression exactly (at points
    # where it is defined): parentheses, signs, coefficients and denominators are kept
    from lyapcheck.models.language.build import expression_text
    from lyapcheck.models.language.expressions import parse_expression
    from lyapcheck.sos.polynomials import Ring

    ring = Ring(("x1", "x2"))
    read = parse_expression(expression_text("rhs", expr, ["x1", "x2"]), ring)
    for point in [(Fraction(1, 3), Fraction(-2, 7)), (Fraction(-5, 2), Fraction(3)), (Fraction(7), Fraction(1, 9))]:
        value = expr.subs({x1: sp.Rational(point[0].numerator, point[0].denominator),
                           x2: sp.Rational(point[1].numerator, point[1].denominator)})
        got = ring.evaluate(read.numerator, list(point)) / ring.evaluate(read.denominator, list(point))
        assert Fraction(int(value.p), int(value.q)) == got


def test_sets_and_outputs_are_written_as_inequalities() -> None:
    model = Model.from_sympy([x1, x2], [x2, -x1 - x2], outputs={"speed": x2},
                             sets={"initial": [x1 ** 2 + x2 ** 2 <= sp.Rational(1, 4)],
                                   "unsafe": [[x1 >= 2], [x1 <= -2, x2 > 1]]})
    text = model.to_toml()
    assert 'initial = ["x1**2 + x2**2 <= 1/4"]' in text and 'unsafe = [["x1 >= 2"], ["x1 <= -2", "x2 > 1"]]' in text
    assert isinstance(model, FileModel) and set(model.sets) == {"initial", "unsafe"}
    assert list(model.outputs) == ["speed"]
