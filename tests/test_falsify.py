"""lyapcheck.models.falsify: simulations from an initial set watching an unsafe set (issue 32).

The model files with a ``[sets]`` table live in examples/models/safety/ until the model parser
reads that table; here the table is cut out before :func:`load_model` and its inequalities are
read with the model's own expression parser (a local stand-in for lyapcheck.models.sets).
"""

from __future__ import annotations

import re
import time
import tomllib
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from lyapcheck.models.expressions import parse_expression
from lyapcheck.models.falsify import StateSet, falsify, sample_set
from lyapcheck.models.modelfile import Model, load_model
from lyapcheck.models.numeric import NumericPoly

SAFETY = Path(__file__).resolve().parents[1] / "examples" / "models" / "safety"


def _inequality(text: str, model: Model) -> Any:
    """``a <= b`` or ``a >= b`` as the polynomial that is ``>= 0`` inside."""
    left, op, right = re.split(r"(<=|>=)", text)
    expr = f"({right}) - ({left})" if op == "<=" else f"({left}) - ({right})"
    return parse_expression(expr, model.state_ring).numerator


def parse_set(value: list[Any], model: Model) -> StateSet:
    pieces = value if value and isinstance(value[0], list) else [value]
    return tuple(tuple(_inequality(s, model) for s in piece) for piece in pieces)


def load_with_sets(path: Path, tmp_path: Path, overrides: dict[str, object] | None = None
                   ) -> tuple[Model, StateSet, StateSet]:
    text = path.read_text()
    sets = tomllib.loads(text)["sets"]
    stripped = re.sub(r"^\[sets\].*\Z", "", text, flags=re.S | re.M)
    plain = tmp_path / path.name
    plain.write_text(stripped)
    model = load_model(plain, overrides)
    return model, parse_set(sets["initial"], model), parse_set(sets["unsafe"], model)


def make_margin(model: Model):
    """``margin(state_set, points)``: max over pieces of min over p of p(x), the disturbances at 0."""
    ring = model.state_ring
    cache: dict[int, list[list[NumericPoly]]] = {}
    m = len(model.disturbances)

    def margin(state_set: StateSet, points: np.ndarray) -> np.ndarray:
        compiled = cache.setdefault(id(state_set), [[NumericPoly(ring, p) for p in piece] for piece in state_set])
        x = np.atleast_2d(points)
        xd = np.hstack([x, np.zeros((x.shape[0], m))]) if m else x
        return np.max([np.min([p(xd) for p in piece], axis=0) for piece in compiled], axis=0)

    return margin


def test_reachable_example_gives_a_counterexample_with_start_and_time(tmp_path: Path) -> None:
    model, initial, unsafe = load_with_sets(SAFETY / "reachable-spiral.toml", tmp_path)
    margin = make_margin(model)
    out = falsify(model, initial, unsafe, margin, samples=50)
    assert out.entered and out.soundness_violation()
    assert out.closest_approach >= 0
    entry = out.entry
    assert entry is not None
    # the start is in the initial disk, the entry point on the unsafe disk's boundary
    assert margin(initial, np.array([entry.start]))[0] >= -1e-12
    assert abs(margin(unsafe, np.array([entry.point]))[0]) < 1e-6
    # closed form: from (1, 0) the spiral is inside the unsafe disk at t = pi; the first entry
    # (from the start nearest to it) is a little before
    assert 2.0 < entry.time < np.pi
    assert entry.disturbance.kind == "none"
    assert "entered the unsafe set" in out.describe()
    assert out.to_dict()["entry"]["time"] == entry.time


def test_safe_example_reports_a_negative_closest_approach(tmp_path: Path) -> None:
    model, initial, unsafe = load_with_sets(SAFETY / "fossil-barr3.toml", tmp_path)
    margin = make_margin(model)
    t0 = time.perf_counter()
    out = falsify(model, initial, unsafe, margin, samples=200)
    elapsed = time.perf_counter() - t0
    assert not out.entered and not out.soundness_violation()
    assert out.entries == 0 and out.closest_approach < 0
    assert out.samples == 200 and out.trajectories == 200
    # every piece of the union was sampled: its box holds the piece
    assert len(out.boxes) == 3
    assert elapsed < 2.0


def test_disturbed_tube_is_safe_and_disturbances_push_a_marginal_case_in(tmp_path: Path) -> None:
    model, initial, unsafe = load_with_sets(SAFETY / "disturbed-tube.toml", tmp_path)
    margin = make_margin(model)
    safe = falsify(model, initial, unsafe, margin, samples=40)
    assert not safe.entered and safe.closest_approach < 0
    assert safe.disturbance_scenarios == 4 + 2  # 2**2 vertices + 2 bang-bang per start

    # the wall moved to x >= 0.9 with |d| <= 1: d = 0 stays clear, the constant d = (1, 1) drives
    # the state to its shifted equilibrium (1, 0), through the wall
    model, initial, _ = load_with_sets(SAFETY / "disturbed-tube.toml", tmp_path, {"d1": 1, "d2": 1})
    margin = make_margin(model)
    wall = ((_inequality("x >= 0.9", model),),)
    start = ((_inequality("x**2 + y**2 <= 0.01", model),),)
    nominal = falsify(model, start, wall, margin, samples=40, disturbed=False)
    assert not nominal.entered and nominal.closest_approach < -0.7
    pushed = falsify(model, start, wall, margin, samples=40)
    assert pushed.entered
    assert pushed.entry is not None and pushed.entry.disturbance.kind in ("constant", "bang-bang")
    assert all(abs(v) <= 1 for row in pushed.entry.disturbance.values for v in row)


def test_determinism_by_seed(tmp_path: Path) -> None:
    model, initial, unsafe = load_with_sets(SAFETY / "disturbed-tube.toml", tmp_path)
    margin = make_margin(model)
    a = falsify(model, initial, unsafe, margin, samples=20, seed=3)
    b = falsify(model, initial, unsafe, margin, samples=20, seed=3)
    c = falsify(model, initial, unsafe, margin, samples=20, seed=4)
    strip = lambda d: {k: v for k, v in d.items() if k != "elapsed_s"}  # noqa: E731
    assert strip(a.to_dict()) == strip(b.to_dict())
    assert strip(a.to_dict()) != strip(c.to_dict())


def test_small_ellipse_without_domain_is_sampled_inside_and_on_its_boundary(tmp_path: Path) -> None:
    model, _, _ = load_with_sets(SAFETY / "reachable-spiral.toml", tmp_path)
    margin = make_margin(model)
    ellipse = ((_inequality("(x - 1.5)**2 + y**2 <= 0.25", model),),)
    starts, boxes = sample_set(model, ellipse, margin, 200, np.random.default_rng(0))
    values = margin(ellipse, starts)
    assert starts.shape == (200, 2) and np.all(values >= -1e-12)
    assert np.sum(values < 1e-6) >= 40  # the boundary quarter
    (lo, hi), = boxes
    assert np.allclose(lo, [1.0, -0.5], atol=0.01) and np.allclose(hi, [2.0, 0.5], atol=0.01)


def test_tiny_box_in_a_large_domain_is_found(tmp_path: Path) -> None:
    model, initial, _ = load_with_sets(SAFETY / "fossil-highord8.toml", tmp_path)
    margin = make_margin(model)
    starts, _ = sample_set(model, initial, margin, 30, np.random.default_rng(0))
    assert np.all(margin(initial, starts) >= -1e-12)


def test_refuses_an_empty_initial_set(tmp_path: Path) -> None:
    model, _, unsafe = load_with_sets(SAFETY / "reachable-spiral.toml", tmp_path)
    empty = ((_inequality("x**2 + y**2 <= -1", model),),)
    with pytest.raises(ValueError, match="no point found inside"):
        falsify(model, empty, unsafe, make_margin(model), samples=5)
