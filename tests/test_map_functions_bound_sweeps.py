"""A map with functions' ``sos_bound`` in a point sweep (issue 44): each certified point cross-checked by
iterating its TRUE map (every function by numpy) under disturbance sequences within the bounds (uniform random,
bang-bang at the bounds, each vertex held constant), every output within the certified envelope
``|y_k - y_eq|^2 <= bound^2 + lam^k max(V(e_0) - 1, 0)`` (:meth:`sweeps.crosscheck._MapLoop.check_bound`);
a bound too small or a forged V raises the soundness alarm.

The map is examples/models/discrete-tanh-disturbed-map.toml, ``x+ = y``, ``y+ = -x/2 + k tanh(y) + d``,
``|d| <= 1/10`` (``k = 0.8`` there; a parameter here)."""

from __future__ import annotations

import copy
import json
import math
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from tests.conftest import ROOT
from tests.test_discrete_sweeps import CODES, never_integrate
from tests.test_model_sweeps import arrays, run

EXAMPLE = ROOT / "examples" / "models" / "discrete-tanh-disturbed-map.toml"
TEXT = EXAMPLE.read_text()
#: the example with its tanh gain a parameter k
GAINED = TEXT.replace("[disturbances]", "[parameters]\nk = 0.8\n\n[disturbances]").replace(
    '"-0.5*x + 0.8*tanh(y) + d"', '"-0.5*x + k*tanh(y) + d"')
D_MAX = 0.1


def _true_map(x: float, y: float, d: float, k: float = 0.8) -> tuple[float, float]:
    return y, -0.5 * x + k * math.tanh(y) + d


def _held_limit(k: float) -> float:
    """Where ``d = +1/10`` held drives the map: its fixed point ``x = y = s``, ``s = -s/2 + k tanh(s) + 1/10``
    (the map contracts: iterated to the float fixed point)."""
    x, y = 0.0, 0.0
    for _ in range(2000):
        x, y = _true_map(x, y, D_MAX, k)
    assert abs(x - y) < 1e-12
    return y


@pytest.fixture(scope="module")
def certified() -> tuple[Any, dict[str, Any]]:
    from lyapcheck.api import certify
    from lyapcheck.models.language.modelfile import load_any_model

    doc = dict(certify(model=EXAMPLE, classes="sos_bound").document)
    assert doc["conditions"]["sos_bound"]["status"] == "certified"
    return load_any_model(EXAMPLE), doc


def test_the_disturbed_true_map_is_iterated_with_numpy_s_tanh() -> None:
    """:func:`sweeps.crosscheck.iterate_disturbed` on a map with functions: the closed-form map, step by step."""
    from lyapcheck.models.language.modelfile import load_any_model
    from sweeps.crosscheck import iterate_disturbed

    rng = np.random.default_rng(5)
    starts = rng.uniform(-3, 3, size=(4, 2))
    D = rng.uniform(-D_MAX, D_MAX, size=(30, 4, 1))
    xs = iterate_disturbed(load_any_model(EXAMPLE), starts, D)
    assert xs.shape == (4, 31, 2)
    for r in range(4):
        x, y = starts[r]
        for k in range(30):
            x, y = _true_map(x, y, float(D[k, r, 0]))
            assert xs[r, k + 1] == pytest.approx([x, y], rel=1e-12, abs=1e-12)


def test_the_cross_check_passes_and_catches_a_bound_too_small_or_a_forged_v(
        certified: tuple[Any, dict[str, Any]], monkeypatch: pytest.MonkeyPatch) -> None:
    """The certified bounds pass (the iterates under the held vertex reach its limit: not vacuous); a bound
    below that limit is contradicted; a V of 0 (its envelope the bound from the first step) is contradicted
    by starts outside the bound; a V naming an auxiliary is not read (the bound alone on the tail)."""
    import lyapcheck.models.engines.trajectories as trajectories
    from sweeps.crosscheck import cross_check_point

    monkeypatch.setattr(trajectories, "simulate", never_integrate)
    model, doc = certified
    bounds = doc["conditions"]["sos_bound"]["bounds"]
    found = cross_check_point(model, doc, {}, starts=8, seed=(0, 0))
    assert not found.violation and found.trajectories == 9 * 4  # 1 + 8 starts, uniform, bang-bang, 2 vertices
    limit = _held_limit(0.8)
    for name in ("x", "y"):
        assert limit * 0.99 <= found.sim_worst[name] <= bounds[name]
    small = copy.deepcopy(doc)
    small["conditions"]["sos_bound"]["bounds"]["y"] = limit / 2
    found = cross_check_point(model, small, {}, starts=8, seed=(0, 0))
    assert len(found.violations) == 1 and found.violations[0].startswith("sos_bound at")
    assert "|y - y_eq| reached" in found.violations[0] and f"above the certified {limit / 2:.6g}" in found.violations[0]
    flat = copy.deepcopy(doc)
    for cert in flat["conditions"]["sos_bound"]["certificate"]["outputs"].values():
        cert["V"] = {"terms": []}
    found = cross_check_point(model, flat, {}, starts=8, seed=(0, 0))
    assert found.violation and all(v.startswith("sos_bound at") for v in found.violations)
    assert any("at step 0 from" in v for v in found.violations)  # (above the bound where it starts)


def test_v_is_read_over_the_states_of_the_certificate_s_variables(certified: tuple[Any, dict[str, Any]]) -> None:
    """The certificate's V (over x, y, d, t1) is read over x, y: the envelope exceeds the bound before the tail
    from a start where V > 1 and falls to it; a V with a term in the auxiliary cannot be read: the bound on the
    tail alone."""
    from sweeps.crosscheck import MAP_BOUND_TAIL_STEPS, _bound_envelope, _over_states

    _, doc = certified
    cert = doc["conditions"]["sos_bound"]["certificate"]
    assert [str(v) for v in cert["variables"]][:2] == ["x", "y"] and len(cert["variables"]) > 2
    y = cert["outputs"]["y"]
    read = _over_states(y, cert["variables"], ("x", "y"))
    assert read is not None and all(len(e) == 2 for _, e in read["V"]["terms"])
    es = np.zeros((1, MAP_BOUND_TAIL_STEPS + 50, 2))
    es[0, 0] = (3.0, -3.0)
    bound = doc["conditions"]["sos_bound"]["bounds"]["y"]
    envelope = _bound_envelope(read, bound, es, ["x", "y"], [])
    assert envelope[0, 0] > 3.0 and envelope[0, -1] == pytest.approx(bound, rel=1e-6)
    aux = copy.deepcopy(y)
    aux["V"]["terms"].append(["1", [0, 0, 0, 2]])  # + t1^2
    assert _over_states(aux, cert["variables"], ("x", "y")) is None
    assert _over_states(y, ["y", "x", "d", "t1"], ("x", "y")) is None
    blind = _bound_envelope(None, bound, es, ["x", "y"], [])
    assert np.all(np.isinf(blind[0, :50])) and np.all(blind[0, 50:] == bound)


def test_a_point_sweep_of_the_tanh_map_certifies_and_cross_checks_its_bounds(tmp_path: Path) -> None:
    """At k = 0.6 and 0.8 each output's bound certifies (disturbances "all") and verifies; iterated on the true
    map under the three policies, no alarm, and the tail sup reaches the held disturbance's limit."""
    import lyapcheck.models.engines.trajectories as trajectories
    from lyapcheck.api import verify

    (tmp_path / "m.toml").write_text(GAINED)
    spec = tmp_path / "bound.toml"
    spec.write_text('[sweep]\nmodel = "m.toml"\nclasses = ["sos_bound"]\nchunk_size = 1\n[[sweep.axes]]\nname = "k"\n'
                    'values = [0.6, 0.8]\n[simulation]\nstarts = 8\n')
    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(trajectories, "simulate", never_integrate)
        run(spec, tmp_path / "bound.zarr")
    data = arrays(tmp_path / "bound.zarr")
    assert list(data["status_sos_bound"]) == [CODES["certified"]] * 2
    for j, k in enumerate(data["k"]):
        doc = json.loads(str(data["certificate"][j]))
        assert verify(doc).valid and doc["conditions"]["sos_bound"]["disturbances"] == "all"
        limit = _held_limit(float(k))
        for name in ("x", "y"):
            assert limit * 0.99 <= data[f"sim_worst_{name}"][j] <= data[f"sos_bound_{name}"][j]
        assert data["cross_check_trajectories"][j] == 9 * 4 and not data["soundness_violation"][j]
