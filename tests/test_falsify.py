"""lyapcheck.models.classes.falsify: simulations from an initial set watching an unsafe set (issue 32).

The example files' ``[sets]`` are read by the model parser (:func:`load_model`, ``model.sets``) and
their margins computed by :func:`lyapcheck.models.language.sets.margin`, as the ``barrier`` class does; the
few sets the tests make up are parsed by the same code (:func:`lyapcheck.models.language.sets.parse_set`).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from lyapcheck.models.classes.falsify import StateSet, falsify, sample_set
from lyapcheck.models.language.modelfile import Model, load_model
from lyapcheck.models.language.sets import evaluate_set, margin, parse_set

MODELS = Path(__file__).resolve().parents[1] / "examples" / "models"


def load_with_sets(path: Path, overrides: dict[str, object] | None = None) -> tuple[Model, StateSet, StateSet]:
    model = load_model(path, overrides)
    return model, model.sets["initial"], model.sets["unsafe"]


def state_set(model: Model, *inequalities: str) -> StateSet:
    """One piece (all of ``inequalities`` hold), read as a ``[sets]`` value of ``model``."""
    _, forms = parse_set(model.source, "initial", list(inequalities), model.ring, model.states,
                         list(model.disturbances))
    return evaluate_set(model.source, "initial", forms, model.ring, model.parameters, model.state_ring)


def test_reachable_example_gives_a_counterexample_with_start_and_time() -> None:
    model, initial, unsafe = load_with_sets(MODELS / "reachable-spiral.toml")
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


def test_safe_example_reports_a_negative_closest_approach() -> None:
    model, initial, unsafe = load_with_sets(MODELS / "fossil-barr3.toml")
    out = falsify(model, initial, unsafe, margin, samples=200)
    assert not out.entered and not out.soundness_violation()
    assert out.entries == 0 and out.closest_approach < 0
    assert out.samples == 200 and out.trajectories == 200
    # every piece of the union was sampled: its box holds the piece
    assert len(out.boxes) == 3  # (its time is benchmarks/bench_quick_paths.py's: no test asserts a wall time)


def test_disturbed_tube_is_safe_and_disturbances_push_a_marginal_case_in() -> None:
    model, initial, unsafe = load_with_sets(MODELS / "disturbed-tube.toml")
    safe = falsify(model, initial, unsafe, margin, samples=40)
    assert not safe.entered and safe.closest_approach < 0
    assert safe.disturbance_scenarios == 4 + 2  # 2**2 vertices + 2 bang-bang per start

    # the wall moved to x >= 0.9 with |d| <= 1: d = 0 stays clear, the constant d = (1, 1) drives
    # the state to its shifted equilibrium (1, 0), through the wall
    model, initial, _ = load_with_sets(MODELS / "disturbed-tube.toml", {"d1": 1, "d2": 1})
    wall = state_set(model, "x >= 0.9")
    start = state_set(model, "x**2 + y**2 <= 0.01")
    nominal = falsify(model, start, wall, margin, samples=40, disturbed=False)
    assert not nominal.entered and nominal.closest_approach < -0.7
    pushed = falsify(model, start, wall, margin, samples=40)
    assert pushed.entered
    assert pushed.entry is not None and pushed.entry.disturbance.kind in ("constant", "bang-bang")
    assert all(abs(v) <= 1 for row in pushed.entry.disturbance.values for v in row)


def test_determinism_by_seed() -> None:
    model, initial, unsafe = load_with_sets(MODELS / "disturbed-tube.toml")
    a = falsify(model, initial, unsafe, margin, samples=20, seed=3)
    b = falsify(model, initial, unsafe, margin, samples=20, seed=3)
    c = falsify(model, initial, unsafe, margin, samples=20, seed=4)
    strip = lambda d: {k: v for k, v in d.items() if k != "elapsed_s"}  # noqa: E731
    assert strip(a.to_dict()) == strip(b.to_dict())
    assert strip(a.to_dict()) != strip(c.to_dict())


def test_small_ellipse_without_domain_is_sampled_inside_and_on_its_boundary() -> None:
    model, _, _ = load_with_sets(MODELS / "reachable-spiral.toml")
    ellipse = state_set(model, "(x - 1.5)**2 + y**2 <= 0.25")
    starts, boxes = sample_set(model, ellipse, margin, 200, np.random.default_rng(0))
    values = margin(ellipse, starts)
    assert starts.shape == (200, 2) and np.all(values >= -1e-12)
    assert np.sum(values < 1e-6) >= 40  # the boundary quarter
    (lo, hi), = boxes
    assert np.allclose(lo, [1.0, -0.5], atol=0.01) and np.allclose(hi, [2.0, 0.5], atol=0.01)


def test_tiny_box_in_a_large_domain_is_found() -> None:
    model, initial, _ = load_with_sets(MODELS / "fossil-highord8.toml")
    starts, _ = sample_set(model, initial, margin, 30, np.random.default_rng(0))
    assert np.all(margin(initial, starts) >= -1e-12)


def test_refuses_an_empty_initial_set() -> None:
    model, _, unsafe = load_with_sets(MODELS / "reachable-spiral.toml")
    empty = state_set(model, "x**2 + y**2 <= -1")
    with pytest.raises(ValueError, match="no point found inside"):
        falsify(model, empty, unsafe, margin, samples=5)
