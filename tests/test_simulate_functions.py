"""``simulate`` of a loop with functions (sin, sqrt, sat, ...): its true loop through the same pipeline
as a polynomial loop (:mod:`lyapcheck.models.surfaces.simulate`, its constructor
:func:`~lyapcheck.models.surfaces.simulate.prepare_true_loop`).

Figures are checked against closed forms and against a polynomial twin: the linear cascade of
``examples/models/linear-disturbed-l1.toml`` written with ``sat(., 100)`` around terms that never
reach 100 is the same loop, so both routes must give the same document and the same figures; the
disturbed ILOS loop's integral state rejects a constant disturbance exactly (``y -> 0``,
``kappa yi -> d Delta / sqrt(U^2 - d^2)``); the damped pendulum's starts end in the wells
``(2 k pi, 0)``, which are its equilibrium modulo 2 pi.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest
import xarray as xr
from click.testing import CliRunner, Result

from lyapcheck.api import SimulationReport, simulate
from lyapcheck.cli import app  # type: ignore[attr-defined]  # the module, as tests/test_model_simulate.py uses it
from lyapcheck.errors import InvalidParameter
from lyapcheck.notebook import REPR_LIMIT
from tests.conftest import ROOT

app._register_commands()
RUNNER = CliRunner()
MODELS = ROOT / "examples" / "models"
PENDULUM = MODELS / "recast-pendulum.toml"
ILOS = MODELS / "recast-ilos-course-disturbed.toml"
LINEAR = MODELS / "linear-disturbed-l1.toml"
#: the keys a loop with functions adds to a polynomial loop's document
RECAST_KEYS = {"kind", "field", "angles_modulo_2pi"}
#: the disturbed ILOS loop's parameters (the file's) and its certified bounds (the file's comment)
U, DELTA, KAPPA, D_BOUND = 1.0, 2.0, 0.5, 0.05
CERTIFIED = {"y": 0.1602, "yi": 0.2606}


def invoke(*args: str) -> Result:
    return RUNNER.invoke(app.cli, list(args), catch_exceptions=False)


@pytest.fixture(scope="module")
def pendulum() -> SimulationReport:
    return simulate(model=PENDULUM)


def test_the_pendulum_has_a_series_and_a_repr(pendulum: SimulationReport) -> None:
    ds = pendulum.series
    assert isinstance(ds, xr.Dataset) and ds.x.dims == ("trajectory", "time", "state")
    assert ds.sizes["trajectory"] == len(pendulum["trajectories"]) == len(pendulum["starts"]) > 1
    assert ds.sizes["time"] > 100 and float(ds.time[-1]) == pendulum["t_end_s"]
    # each series ends at the document's final state, and starts at its start
    for i, t in enumerate(pendulum["trajectories"]):
        assert [float(v) for v in ds.x.sel(trajectory=i).isel(time=-1)] == list(t["final_state"].values())
        assert [float(v) for v in ds.x.sel(trajectory=i).isel(time=0)] == list(pendulum["starts"][t["start"]].values())
    text = repr(pendulum)
    assert text.startswith("SimulationReport: model 'damped pendulum (b = 1)': ") and len(text) < REPR_LIMIT
    assert "modulo 2 pi in theta" in text and "series: xarray.Dataset of x, y" in text
    assert "<table>" in pendulum._repr_html_()


def test_the_pendulum_converges_modulo_2pi(pendulum: SimulationReport) -> None:
    doc = pendulum.document
    assert doc["kind"] == "recast" and doc["angles_modulo_2pi"] == ["theta"] and "true loop" in doc["field"]
    finals = np.array([[t["final_state"]["theta"], t["final_state"]["omega"]] for t in doc["trajectories"]])
    wells = np.round(finals[:, 0] / (2 * math.pi))
    # every start of the box ends in a well (2 k pi, 0), some of them in a neighbouring one (k != 0) ...
    assert np.all(np.abs(finals[:, 0] - 2 * math.pi * wells) < 1e-6) and np.all(np.abs(finals[:, 1]) < 1e-6)
    assert np.any(wells != 0)
    # ... which is the equilibrium on the cylinder: every trajectory converged, none diverged
    assert all(t["converged"] and not t["diverged"] for t in doc["trajectories"])
    assert doc["n_converged"] == doc["n_trajectories"] and not pendulum.diverged


def test_the_same_document_and_figures_as_the_polynomial_twin(tmp_path: Path) -> None:
    text = LINEAR.read_text()
    twin_text = text.replace('x1 = "-x1 + x2"', 'x1 = "-x1 + sat(x2, 100)"').replace(
        'x2 = "-2*x2 + d"', 'x2 = "-2*x2 + sat(d, 100)"')
    assert twin_text.count("sat(") == 2
    twin = tmp_path / "twin.toml"
    twin.write_text(twin_text)
    starts = [[0, 0], [1, -1]]
    poly = simulate(model=LINEAR, x0=starts, series=False).document
    true = simulate(model=twin, x0=starts, series=False).document
    assert true["kind"] == "recast" and "kind" not in poly
    assert set(true) - set(poly) == RECAST_KEYS and set(poly) <= set(true)
    assert [set(t) for t in true["trajectories"]] == [set(t) for t in poly["trajectories"]]
    for key in ("states", "equilibrium", "disturbance_bounds", "outputs", "starts", "t_end_s", "tail_window_s",
                "frequencies_rad_s", "state_scale", "n_trajectories", "n_converged", "n_diverged"):
        assert true[key] == poly[key], key
    assert list(true["scenarios"]) == list(poly["scenarios"]) == ["none", "constant", "bang-bang", "square"]
    for name, scenario in poly["scenarios"].items():
        assert true["scenarios"][name]["disturbances"] == scenario["disturbances"], name
        for y, value in scenario["sup_abs_output_tail"].items():
            assert true["scenarios"][name]["sup_abs_output_tail"][y] == pytest.approx(value, rel=1e-6, abs=1e-12)
    # the closed form: d = 1 constant drives x1 to 1/2, the worst case of the cascade
    assert true["scenarios"]["constant"]["sup_abs_output_tail"]["y"] == pytest.approx(0.5, rel=1e-6)


def test_a_disturbed_loop_with_functions_runs_its_disturbance_scenarios() -> None:
    run = simulate(model=ILOS, x0={"y": 0, "yi": 0}, series=False)
    doc = run.document
    assert list(doc["scenarios"]) == ["none", "constant", "bang-bang", "square"]
    assert doc["disturbance_bounds"] == {"d": D_BOUND} and not run.diverged
    # 1 + 2 sign patterns + 2 outputs x 2 directions + 8 square waves (one sign pattern), from one start
    assert doc["n_trajectories"] == 1 + 2 + 4 + 8
    for t in doc["trajectories"]:
        d = t["disturbance"]
        assert all(abs(v) <= D_BOUND for v in {**d.get("d", {}), **d.get("amplitude", {})}.values())
    # a constant d is rejected by the integral state: y -> 0 and kappa yi -> d Delta / sqrt(U^2 - d^2)
    constant = doc["scenarios"]["constant"]["sup_abs_output_tail"]
    assert constant["y"] < 1e-6
    assert constant["yi"] == pytest.approx(D_BOUND * DELTA / math.sqrt(U ** 2 - D_BOUND ** 2) / KAPPA, rel=1e-6)
    # a bang-bang d(t) keeps y moving, within the certified bounds (sos_bound of the file)
    bang = doc["scenarios"]["bang-bang"]["sup_abs_output_tail"]
    assert 100 * constant["y"] < bang["y"] <= CERTIFIED["y"] and bang["yi"] <= CERTIFIED["yi"]
    # the worst-case search takes the loop too, and finds at least what the scenarios found
    worst = simulate(model=ILOS, worst_case=True, budget_s=1)
    assert worst["kind"] == "recast" and not worst.diverged
    assert bang["y"] * (1 - 1e-6) <= worst["sup_abs_output_tail"]["y"] <= CERTIFIED["y"]
    assert "worst case of model 'ILOS" in repr(worst)


def test_plot_writes_a_png(tmp_path: Path) -> None:
    out = tmp_path / "pendulum.png"
    result = invoke("simulate", "--model", str(PENDULUM), "--plot", str(out), "--json", "--x0", "theta=1,omega=0",
                    "--x0", "theta=3,omega=2")
    assert result.exit_code == 0, result.output
    doc = json.loads(result.output)
    assert doc["plot"] == str(out) and doc["kind"] == "recast" and len(doc["trajectories"]) == 2
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and out.stat().st_size > 10_000
    # the table names what was integrated and how convergence is measured
    table = invoke("simulate", "--model", str(PENDULUM), "--x0", "theta=1,omega=0")
    assert table.exit_code == 0 and "modulo 2 pi in theta" in " ".join(table.output.split())


def test_a_disturbance_scenario_without_disturbances_is_refused() -> None:
    with pytest.raises(InvalidParameter) as info:
        simulate(model=PENDULUM, scenarios=["constant"], series=False)
    assert info.value.field == "scenarios" and "\n" not in str(info.value)


#: documents of other shapes: the former recast document (``model`` a bare name), empty or partial ones
ODD_DOCUMENTS = [
    {"model": "damped pendulum", "kind": "recast", "trajectories": [{"converged": True}], "n_converged": 1},
    {},
    {"model": {"name": "m"}},
    {"model": None, "scenarios": {"none": None}, "sup_abs_output_tail": {"y": None}, "tail_window_s": [1]},
    {"model": {"name": "m"}, "mode": "worst_case", "worst": {"y": {}}, "tightness": {"y": None}},
    {"mode": "worst_case"},
]


@pytest.mark.parametrize("doc", ODD_DOCUMENTS)
def test_any_document_shape_has_a_repr(doc: dict) -> None:
    report = SimulationReport(diverged=False, document=doc)
    text = repr(report)
    assert text.startswith("SimulationReport: ") and len(text) < REPR_LIMIT
    assert "<table>" in report._repr_html_()
    if isinstance(doc.get("model"), str):
        assert text.startswith("SimulationReport: model 'damped pendulum': 1 trajectories (1 converged)")
