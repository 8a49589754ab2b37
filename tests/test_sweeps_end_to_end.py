"""Sweeps with real certificates and simulations: the command line, SIGKILL and resume, Dask,
and the shipped example specs (each in a reduced version: three values per axis over the
same ranges, so that the suite stays within minutes; the full specs are run by hand and in
the benchmark notes)."""

from __future__ import annotations

import json
import os
import re
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner

from sweeps.run import run_sweep
from sweeps.runners import InlineRunner
from sweeps.spec import load_spec, parse_spec
from sweeps.store import Store, open_results
from tests.conftest import SWEEP_FIXED

ROOT = Path(__file__).resolve().parents[1]
EXAMPLES = ("sweep-alpha-sigma.toml", "sweep-kd-delta.toml", "sweep-dmax-alpha.toml")

SMALL = SWEEP_FIXED + """[sweep]
chunk_size = {chunk}
[[sweep.axes]]
name = "alpha_d"
start = 300
stop = 1200
num = {num}
scale = "log"
[[sweep.axes]]
name = "k_d"
start = 0.05
stop = 3
num = {num}
scale = "log"
[simulation]
horizon = "20 s"
tail = "5 s"
"""


def _write(tmp_path: Path, *, num: int, chunk: int) -> Path:
    path = tmp_path / "spec.toml"
    path.write_text(SMALL.format(num=num, chunk=chunk))
    return path


def _sweep_cmd(*args: str) -> list[str]:
    return [sys.executable, "-m", "sweeps", *args]


def _files(root: Path) -> dict[str, bytes]:
    return {str(p.relative_to(root)): p.read_bytes() for p in sorted(root.rglob("*")) if p.is_file()}


@pytest.mark.slow
def test_small_sweep_end_to_end(tmp_path: Path) -> None:
    spec_path = _write(tmp_path, num=3, chunk=5)
    out = tmp_path / "r.zarr"
    proc = subprocess.run(_sweep_cmd(str(spec_path), "--out", str(out), "--workers", "2", "--json",
                                     "--export", str(tmp_path / "r.nc"), "--export", str(tmp_path / "r.csv")),
                          capture_output=True, text=True, timeout=300, cwd=ROOT)
    assert proc.returncode == 0, proc.stderr
    summary = json.loads(proc.stdout)
    assert summary["points"] == summary["computed"] == summary["computed_now"] == 9
    assert summary["soundness_violations"] == []
    ds = open_results(out)
    assert bool(ds["done"].all()) and not bool(ds["soundness_violation"].any())
    sector = set(np.unique(ds["status_sector_ges"].values).tolist())
    assert {1, 2} <= sector  # both certified and refuted points on this grid
    bound, sim = ds["eps_bound_m"].values, ds["sim_eps_sup_m"].values
    assert np.all(np.isfinite(bound)) and np.all(sim <= bound)
    np.testing.assert_allclose(ds["ratio_certified_over_simulated"].values, bound / sim)
    for scenario in ("nominal", "constant", "weight", "adversarial"):
        assert np.all(np.isfinite(ds[f"sim_eps_sup_m_{scenario}"].values)), scenario
    import xarray as xr

    nc = xr.open_dataset(tmp_path / "r.nc")
    np.testing.assert_array_equal(nc["status_sector_ges"].values, ds["status_sector_ges"].values)
    lines = (tmp_path / "r.csv").read_text().splitlines()
    assert lines[0].startswith("alpha_d,k_d,status_prop41_ges") and len(lines) == 10
    # a second run over the finished store computes nothing and reports the same
    again = subprocess.run(_sweep_cmd(str(spec_path), "--out", str(out), "--workers", "1", "--json"),
                           capture_output=True, text=True, timeout=300, cwd=ROOT)
    assert again.returncode == 0 and json.loads(again.stdout)["computed_now"] == 0


@pytest.mark.slow
def test_sigkill_then_resume_is_identical_to_an_uninterrupted_run(tmp_path: Path) -> None:
    spec_path = _write(tmp_path, num=4, chunk=2)
    spec = load_spec(spec_path)
    killed = tmp_path / "killed.zarr"
    # its own session: the SIGKILL takes the worker processes down with it, like a killed job
    log = tmp_path / "killed.log"
    with log.open("w") as err:
        proc = subprocess.Popen(_sweep_cmd(str(spec_path), "--out", str(killed), "--workers", "1", "--quiet"),
                                cwd=ROOT, stdout=subprocess.DEVNULL, stderr=err, start_new_session=True)
    deadline = time.monotonic() + 240
    done_before = 0
    try:
        while time.monotonic() < deadline:
            if (killed / "zarr.json").exists():
                done_before = int(Store.open_or_create(killed, spec).done().sum())
                if 2 <= done_before < spec.n_points - 4:
                    break
            if proc.poll() is not None:
                pytest.fail(f"the sweep ended before it could be killed: {log.read_text()}")
            time.sleep(0.1)
    finally:
        os.killpg(proc.pid, signal.SIGKILL)
        proc.wait(timeout=30)
    assert proc.returncode == -signal.SIGKILL
    done_at_kill = int(Store.open_or_create(killed, spec).done().sum())
    assert 0 < done_at_kill < spec.n_points
    resumed = subprocess.run(_sweep_cmd(str(spec_path), "--out", str(killed), "--workers", "1", "--json"),
                             capture_output=True, text=True, timeout=300, cwd=ROOT)
    assert resumed.returncode == 0, resumed.stderr
    assert json.loads(resumed.stdout)["computed_now"] == spec.n_points - done_at_kill  # nothing recomputed
    whole = tmp_path / "whole.zarr"
    full = subprocess.run(_sweep_cmd(str(spec_path), "--out", str(whole), "--workers", "2", "--quiet"),
                          capture_output=True, text=True, timeout=300, cwd=ROOT)
    assert full.returncode == 0, full.stderr
    assert _files(killed) == _files(whole)  # byte for byte


@pytest.mark.slow
def test_dask_local_cluster_gives_the_same_store(tmp_path: Path) -> None:
    distributed = pytest.importorskip("distributed")
    spec = parse_spec(SMALL.format(num=2, chunk=2))
    run_sweep(spec, tmp_path / "inline.zarr", runner=InlineRunner())
    with distributed.LocalCluster(n_workers=1, threads_per_worker=2, processes=False,
                                  dashboard_address=None) as cluster:
        report = run_sweep(spec, tmp_path / "dask.zarr", scheduler=cluster.scheduler_address)
    assert report.computed_now == spec.n_points
    assert _files(tmp_path / "inline.zarr") == _files(tmp_path / "dask.zarr")


def _reduced(path: Path) -> str:
    """The example spec with three values per axis over the same range (and one unit)."""
    text = path.read_text()
    text = re.sub(r"(?m)^num = \d+$", "num = 3", text)
    return re.sub(r"(?m)^chunk_size = \d+$", "chunk_size = 9", text)


@pytest.mark.slow
@pytest.mark.parametrize("name", EXAMPLES)
def test_example_specs_reduced_have_no_soundness_violation(tmp_path: Path, name: str) -> None:
    spec = parse_spec(_reduced(ROOT / "examples" / name))
    run_sweep(spec, tmp_path / "e.zarr", runner=InlineRunner())
    ds = open_results(tmp_path / "e.zarr")
    assert bool(ds["done"].all())
    assert not bool(ds["soundness_violation"].any())
    assert not bool(ds["sim_diverged"].any())
    assert bool((ds["status_ultimate_bound"] == 1).all())
    assert np.all(ds["sim_eps_sup_m"].values <= ds["eps_bound_m"].values)


def _cli() -> object:
    from lyapcheck.cli import app, sweep

    sweep.register(app.cli)
    return app.cli


def test_cli_bad_spec_is_one_line_exit_2(tmp_path: Path) -> None:
    spec_path = tmp_path / "bad.toml"
    spec_path.write_text(SMALL.format(num=3, chunk=5).replace('name = "k_d"', 'name = "kd"'))
    result = CliRunner().invoke(_cli(), ["sweep", str(spec_path), "--out", str(tmp_path / "x.zarr")])  # type: ignore[arg-type]
    assert result.exit_code == 2
    assert result.stderr.strip().count("\n") == 0
    assert "The 'sweep.axes[1].name' parameter must be one of" in result.stderr
    assert not (tmp_path / "x.zarr").exists()


def test_cli_soundness_violation_exits_1_and_says_so(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    from sweeps import evaluate as ev

    def with_violation(spec, coords):  # type: ignore[no-untyped-def]
        out = ev.empty_result(len(coords))
        out["done"][:] = True
        out["eps_bound_m"][:] = 1e-3
        out["sim_eps_sup_m"][:] = 2e-3
        out["soundness_violation"][:] = True
        return out

    monkeypatch.setattr(ev, "evaluate", with_violation)
    spec_path = _write(tmp_path, num=2, chunk=4)
    result = CliRunner().invoke(_cli(), ["sweep", str(spec_path), "--out", str(tmp_path / "v.zarr"),  # type: ignore[arg-type]
                                         "--workers", "0", "--quiet"])
    assert result.exit_code == 1
    assert "SOUNDNESS VIOLATION" in result.stderr and "alpha_d=300" in result.stderr


@pytest.mark.slow
def test_worst_case_scenario_makes_the_sweep_ratio_a_tightness_ratio(tmp_path: Path) -> None:
    """scenarios = [..., "worst_case"]: the worst-case search (on the path, screening round only)
    beats the constant push, stays under the certified bound, and sets the ratio (issue 12)."""
    text = SWEEP_FIXED + """[sweep]
classes = ["sos_bound"]
[[sweep.axes]]
name = "alpha_d"
values = [600]
[[sweep.axes]]
name = "k_d"
values = [0.15]
[simulation]
scenarios = ["constant", "worst_case"]
"""
    spec = parse_spec(text)
    run_sweep(spec, tmp_path / "w.zarr", runner=InlineRunner())
    ds = open_results(tmp_path / "w.zarr")
    bound = float(ds["eps_bound_m"].values.ravel()[0])
    worst = float(ds["sim_eps_sup_m_worst_case"].values.ravel()[0])
    constant = float(ds["sim_eps_sup_m_constant"].values.ravel()[0])
    assert constant < worst <= bound  # the search finds more than a constant push, never more than proved
    ratio = float(ds["ratio_certified_over_simulated"].values.ravel()[0])
    assert ratio == pytest.approx(bound / worst) and 1 <= ratio <= 1.5
    assert not bool(ds["soundness_violation"].any())


def test_the_scenarios_simulated_in_one_batch_give_what_each_gives_alone() -> None:
    """``simulate_points`` runs every simulated scenario in one batch (one loop iteration count
    for all of them); each figure must be the one a batch of that scenario alone gives, bit for
    bit: rows of the integrator are independent, and the stacked disturbance must not change
    what a row sees. A non-identity P (from a certificate) and a missing one are both covered."""
    from sweeps.evaluate import simulate_points

    scenarios = ["nominal", "constant", "weight", "adversarial"]
    text = SMALL.format(num=2, chunk=4).replace(
        'horizon = "20 s"\ntail = "5 s"\n',
        'horizon = "6 s"\ntail = "2 s"\nscenarios = ' + json.dumps(scenarios) + "\n")
    spec = parse_spec(text)
    coords = np.array([[a, k] for a in spec.axes[0].values for k in spec.axes[1].values])
    adversary = [np.array([[2.0, 0.3], [0.3, 1.0]]), None, np.eye(2), np.array([[1.0, -0.5], [-0.5, 4.0]])]
    together = simulate_points(spec, coords, adversary)
    assert sorted(together) == sorted(scenarios)
    for name in scenarios:
        alone_spec = parse_spec(text.replace("scenarios = " + json.dumps(scenarios), "scenarios = " + json.dumps([name])))
        alone = simulate_points(alone_spec, coords, adversary)[name]
        for key in ("sup", "failed", "diverged"):
            np.testing.assert_array_equal(together[name][key], alone[key], err_msg=f"{name} {key}")
    assert np.all(np.isfinite(together["adversarial"]["sup"]))
    # the scenarios differ, so a mix-up of rows between them would show
    assert not np.array_equal(together["constant"]["sup"], together["adversarial"]["sup"])
