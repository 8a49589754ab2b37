"""Sweeps: spec validation, store layout, refinement, soundness flag, fast sector path.

The tests that run real certificates and simulations end to end are in
``tests/test_sweeps_end_to_end.py``; here the unit of work is mostly replaced by a cheap,
deterministic stub so that the storage, resume and refinement logic is tested on its own.
"""

from __future__ import annotations

import re
from fractions import Fraction
from pathlib import Path

import numpy as np
import pytest

from lyapcheck.errors import InputFileError, InvalidParameter
from sweeps import soundness
from sweeps.evaluate import empty_result
from sweeps.refine import coarse_cells, split
from sweeps.run import run_sweep
from sweeps.runners import InlineRunner
from sweeps.schema import CLASSES, SCENARIOS, VARIABLES
from sweeps.spec import cached_spec, load_spec, parse_spec
from sweeps.store import Store, block_regions, chunk_shape, open_results
from sweeps.summary import summarize, violation_count
from tests.conftest import SWEEP_FIXED

ROOT = Path(__file__).resolve().parents[1]
EXAMPLES = [ROOT / "examples" / name for name in
            ("sweep-alpha-sigma.toml", "sweep-kd-delta.toml", "sweep-dmax-alpha.toml")]



def spec_text(axes: str = "", sweep: str = "", simulation: str = "") -> str:
    """A small valid spec, with pieces replaced by the caller."""
    axes = axes or """
[[sweep.axes]]
name = "alpha_d"
start = 300
stop = 1200
num = 5
scale = "log"
[[sweep.axes]]
name = "k_d"
start = 0.05
stop = 2
num = 5
scale = "log"
"""
    return SWEEP_FIXED + "[sweep]\n" + (sweep or "chunk_size = 6\n") + axes + "\n[simulation]\n" + (
        simulation or 'horizon = "20 s"\ntail = "5 s"\n')


def stub_unit(text: str, coords: np.ndarray) -> dict[str, np.ndarray]:
    """A cheap deterministic unit: 'certified' below the line x + y = 1 in normalised coordinates."""
    spec = cached_spec(text)
    lo = np.array([a.values[0] for a in spec.axes])
    hi = np.array([a.values[-1] for a in spec.axes])
    u = (coords - lo) / np.where(hi > lo, hi - lo, 1.0)
    out = empty_result(len(coords))
    inside = u.sum(axis=1) < 1.0
    for cls in spec.classes:
        out[f"status_{cls}"] = np.where(inside, 1, 0).astype(np.int8)
        out[f"margin_{cls}"] = 1.0 - u.sum(axis=1)
    out["eps_bound_m"] = 1.0 + u[:, 0]
    out["sim_eps_sup_m"] = 0.5 + 0.0 * u[:, 0]
    out["ratio_certified_over_simulated"] = out["eps_bound_m"] / out["sim_eps_sup_m"]
    out["done"] = np.ones(len(coords), dtype=bool)
    return out


# -- spec validation ---------------------------------------------------------------------------

@pytest.mark.parametrize("path", EXAMPLES, ids=lambda p: p.name)
def test_shipped_specs_parse(path: Path) -> None:
    spec = load_spec(path)
    assert 1 <= len(spec.axes) <= 3
    assert spec.base.gains.los_speed == 1


def test_axis_values_are_si_and_exact_at_points() -> None:
    spec = parse_spec(spec_text(axes="""
[[sweep.axes]]
name = "delta_los"
values = ["0.5 mm", "750 um", "1 mm"]
""").replace('delta_los = "0.75 mm"', "alpha_d = 600\nk_d = 0.15"))
    assert spec.axes[0].values == (0.0005, 0.00075, 0.001)
    problem = spec.problem_at([0.00075])
    assert problem.gains.delta_los == Fraction(0.00075)  # the stored float, exactly


BAD_SPECS = [
    (spec_text().replace('name = "k_d"', 'name = "kd"'), r"'sweep\.axes\[1\]\.name' parameter must be one of"),
    (spec_text().replace("num = 5\nscale = \"log\"\n[[sweep.axes]]", "num = 0\nscale = \"log\"\n[[sweep.axes]]"),
     r"'sweep\.axes\[0\]\.num' parameter must be an integer in \[1,"),
    (spec_text().replace("start = 300", 'start = "300 m"'), r"'alpha_d' parameter must be"),
    (spec_text().replace("start = 0.05", "start = -1"), r"'k_d' parameter must be in \(0, inf\) 1/s"),
    (spec_text().replace('scale = "log"', 'scale = "cubic"', 1), r"'sweep\.axes\[0\]\.scale' parameter must be"),
    (spec_text(sweep='chunk_size = 6\ncolour = "red"\n'), r"'sweep\.colour' parameter must be a known key"),
    (spec_text(sweep='classes = ["sector_ges", "magic"]\n'), r"'sweep\.classes' parameter must be a list"),
    (spec_text(simulation='horizon = "5 s"\ntail = "10 s"\n'), r"'tail' parameter must be at most the horizon"),
    (spec_text(simulation='scenarios = ["storm"]\n'), r"'simulation\.scenarios' parameter must be"),
    (spec_text(simulation='horizon = "1 m"\n'), r"'horizon' parameter must be a duration"),
    (spec_text().replace("sigma0 = 0.01", "sigma0 = 0.01\nalpha_d = 600"), r"either fixed or swept"),
    (spec_text().replace("[swimmer]", "[swimmer]\ncolour = 1"), r"'swimmer\.colour' parameter must be a known key"),
    (spec_text().replace('weight = "8.7e-5 N"', ""), r"'weight' parameter must be given in \[swimmer\] for the"),
    (spec_text(sweep='chunk_size = 6\n[sweep.refine]\nclass = "sector_ges"\nlevels = 3\n'),
     r"'sweep\.axes\[0\]\.num' parameter must be k \* 2\*\*levels \+ 1"),
    (SWEEP_FIXED, r"'sweep' parameter must be a \[sweep\] table"),
]


@pytest.mark.parametrize(("text", "message"), BAD_SPECS)
def test_bad_specs_are_rejected_with_the_one_template(text: str, message: str) -> None:
    with pytest.raises(InvalidParameter, match=message) as info:
        parse_spec(text)
    assert "\n" not in str(info.value)
    assert re.match(r"The '.+' parameter must be .+\. Got .+ instead\.$", str(info.value))


def test_unreadable_and_invalid_toml_are_input_errors(tmp_path: Path) -> None:
    with pytest.raises(InputFileError, match="does not exist"):
        load_spec(tmp_path / "missing.toml")
    bad = tmp_path / "bad.toml"
    bad.write_text("[sweep\n")
    with pytest.raises(InputFileError, match="not valid TOML"):
        load_spec(bad)


# -- store layout ------------------------------------------------------------------------------

@pytest.mark.parametrize(("shape", "size", "expected"), [
    ((20, 20), 200, (10, 20)), ((5, 5), 6, (1, 5)), ((100_000,), 256, (256,)), ((4, 10, 10), 100, (1, 10, 10)),
    ((3, 3), 1, (1, 1)), ((7,), 50, (7,)),
])
def test_chunk_shape(shape: tuple[int, ...], size: int, expected: tuple[int, ...]) -> None:
    assert chunk_shape(shape, size) == expected
    cover = np.zeros(shape, dtype=int)
    for region in block_regions(shape, expected):
        cover[region] += 1
    assert np.all(cover == 1)  # the units tile the grid exactly once


def test_store_schema_and_attributes(tmp_path: Path) -> None:
    spec = parse_spec(spec_text())
    run_sweep(spec, tmp_path / "s.zarr", runner=InlineRunner(), evaluator=stub_unit)
    ds = open_results(tmp_path / "s.zarr")
    assert tuple(ds["done"].dims) == ("alpha_d", "k_d")
    for var in VARIABLES:
        assert ds[var.name].dtype == var.dtype, var.name
    for cls in CLASSES:
        assert f"status_{cls}" in ds and f"margin_{cls}" in ds
    for scenario in SCENARIOS:
        assert f"sim_eps_sup_m_{scenario}" in ds
    assert ds.attrs["spec_toml"] == spec.text
    assert "cvxpy" in ds.attrs["versions"] and '"alpha_d": 600.0' in ds.attrs["paper_point"]
    np.testing.assert_allclose(ds["alpha_d"].values, np.geomspace(300, 1200, 5))
    assert bool(ds["done"].all())
    assert int(ds["status_sos_gas"].min()) == -1  # not asked for: "not computed"


def test_store_refuses_another_spec(tmp_path: Path) -> None:
    run_sweep(parse_spec(spec_text()), tmp_path / "s.zarr", runner=InlineRunner(), evaluator=stub_unit)
    other = parse_spec(spec_text(simulation='horizon = "30 s"\n'))
    with pytest.raises(InputFileError, match="different spec"):
        Store.open_or_create(tmp_path / "s.zarr", other)


def _files(root: Path) -> dict[str, bytes]:
    return {str(p.relative_to(root)): p.read_bytes() for p in sorted(root.rglob("*")) if p.is_file()}


class _Interrupt(Exception):
    pass


@pytest.mark.parametrize("refine", [False, True], ids=["grid", "refined"])
def test_interrupted_run_resumes_to_identical_store(tmp_path: Path, refine: bool) -> None:
    """In-process version of the SIGKILL test (the real one is in test_sweeps_end_to_end)."""
    if refine:
        axes = "".join(f'[[sweep.axes]]\nname = "{n}"\nstart = {a}\nstop = {b}\nnum = 9\n'
                       for n, a, b in (("alpha_d", 300, 1200), ("k_d", 0.05, 2)))
        text = spec_text(axes=axes, sweep='chunk_size = 4\n[sweep.refine]\nclass = "sector_ges"\nlevels = 2\n')
    else:
        text = spec_text()
    spec = parse_spec(text)
    run_sweep(spec, tmp_path / "whole.zarr", runner=InlineRunner(), evaluator=stub_unit)
    calls = {"n": 0}

    def failing(t: str, c: np.ndarray) -> dict[str, np.ndarray]:
        calls["n"] += 1
        if calls["n"] == 3:
            raise _Interrupt()
        return stub_unit(t, c)

    with pytest.raises(_Interrupt):
        run_sweep(spec, tmp_path / "resumed.zarr", runner=InlineRunner(), evaluator=failing)
    partial = Store.open_or_create(tmp_path / "resumed.zarr", spec).done()
    assert 0 < partial.sum() < (spec.n_points if not refine else partial.size)
    seen: list[int] = []

    def counting(t: str, c: np.ndarray) -> dict[str, np.ndarray]:
        seen.append(len(c))
        return stub_unit(t, c)

    run_sweep(spec, tmp_path / "resumed.zarr", runner=InlineRunner(), evaluator=counting)
    assert sum(seen) == int(Store.open_or_create(tmp_path / "whole.zarr", spec).done().sum()) - int(partial.sum())
    assert _files(tmp_path / "whole.zarr") == _files(tmp_path / "resumed.zarr")


# -- refinement --------------------------------------------------------------------------------

def test_refinement_resolves_the_boundary_with_fewer_points(tmp_path: Path) -> None:
    axes = "".join(f'[[sweep.axes]]\nname = "{n}"\nstart = {a}\nstop = {b}\nnum = 33\n'
                   for n, a, b in (("alpha_d", 300, 1200), ("k_d", 0.05, 2)))
    spec = parse_spec(spec_text(axes=axes, sweep='chunk_size = 64\n[sweep.refine]\nclass = "sector_ges"\nlevels = 3\n'))
    report = run_sweep(spec, tmp_path / "r.zarr", runner=InlineRunner(), evaluator=stub_unit)
    assert report.refinement is not None
    assert report.refinement.full_grid_points == 33 * 33
    assert report.refinement.points_computed < 0.5 * 33 * 33
    store = Store.open_or_create(tmp_path / "r.zarr", spec)
    done = store.done()
    status = np.asarray(store.group["status_sector_ges"][...])
    truth = stub_unit(spec.text, np.array([[a, k] for a in spec.axes[0].values for k in spec.axes[1].values]))
    truth_status = truth["status_sector_ges"].reshape(33, 33)
    assert np.array_equal(status[done], truth_status[done])
    # every finest cell that the boundary crosses has all four corners computed
    crossing = truth_status[:-1, :-1] + truth_status[1:, :-1] + truth_status[:-1, 1:] + truth_status[1:, 1:]
    for i, j in np.argwhere((crossing > 0) & (crossing < 4)):
        assert done[i:i + 2, j:j + 2].all(), (i, j)


def test_split_only_disagreeing_cells() -> None:
    certified = np.zeros((5, 5), dtype=bool)
    certified[0, 0] = True
    cells = coarse_cells((5, 5), 2)
    assert cells == [(0, 0, 4)]
    children, points = split(cells, certified)
    assert len(children) == 4
    assert sorted(map(tuple, points)) == [(0, 2), (2, 0), (2, 2), (2, 4), (4, 2)]
    assert split(children[1:], certified)[0] == []


# -- soundness flag ----------------------------------------------------------------------------

def test_soundness_flag_tolerance_and_divergence() -> None:
    bound = np.array([1.0, 1.0, 1.0, np.nan, 2.0])
    sup = np.array([1.0 + 0.5e-6, 1.0 + 2e-6, 0.5, 10.0, 1.0])
    diverged = np.array([False, False, True, False, True])
    statuses = {"sector_ges": np.array([0, 0, 1, 0, 0], dtype=np.int8),
                "prop41_ges": np.array([0, 0, 0, 0, 2], dtype=np.int8)}
    flags = soundness.violations(bound, [sup], diverged, statuses)
    assert flags.tolist() == [False, True, True, False, False]


def test_summary_counts_violations(tmp_path: Path) -> None:
    spec = parse_spec(spec_text())

    def one_bad(t: str, c: np.ndarray) -> dict[str, np.ndarray]:
        out = stub_unit(t, c)
        out["soundness_violation"] = np.isclose(c[:, 0], 300.0) & np.isclose(c[:, 1], 0.05)
        return out

    run_sweep(spec, tmp_path / "v.zarr", runner=InlineRunner(), evaluator=one_bad)
    summary = summarize(Store.open_or_create(tmp_path / "v.zarr", spec))
    assert violation_count(summary) == 1
    assert summary.violations[0]["alpha_d"] == 300.0
    grid = np.array([[a, k] for a in spec.axes[0].values for k in spec.axes[1].values])
    assert summary.certified_fraction["sector_ges"] == np.mean(stub_unit(spec.text, grid)["status_sector_ges"] == 1)


def test_classes_follow_the_certify_module() -> None:
    from lyapcheck.paper.certification import CONDITION_ORDER, QUICK_CLASSES
    from sweeps.schema import DEFAULT_CLASSES

    assert CLASSES == CONDITION_ORDER
    assert DEFAULT_CLASSES == QUICK_CLASSES


# -- fast sector_ges path ----------------------------------------------------------------------

def test_fast_sector_agrees_with_the_condition_module(paper_problem) -> None:  # type: ignore[no-untyped-def]
    from lyapcheck.paper.certification import build_system
    from lyapcheck.paper.conditions import sector
    from sweeps import fast_sector

    statuses = []
    for alpha in (300, 600, 1500):
        for kd in ("0.05", "0.15", "1", "4"):
            system = build_system(paper_problem.with_gains(alpha_d=Fraction(alpha), k_d=Fraction(kd)), "derived")
            fast, slow = fast_sector.certify(system), sector.run(system)
            assert fast.status == slow.status, (alpha, kd, fast.summary, slow.summary)
            if fast.status == "certified":
                vertices = [system.vertex(Fraction(0)), system.vertex(system.rho_sup)]
                P = tuple(tuple(Fraction(x) for x in row) for row in fast.certificate["P"])
                assert sector.exact_check(vertices, P, Fraction(fast.certificate["decay_rate"]))[0]
            statuses.append(fast.status)
    assert {"certified", "refuted"} <= set(statuses)
