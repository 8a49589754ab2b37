"""The API in a notebook (issue 29, item 5): short reprs, escaped HTML, attributes that say what
the JSON says, ``simulate(x0=...)`` in Python's own forms, time series, and errors that name the
API's arguments instead of the command line's flags."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from lyapcheck import CertifyResult, SimulationReport, certify, certify_box, simulate, verify
from lyapcheck.errors import InvalidParameter, LyapcheckError, ModelFileError
from lyapcheck.notebook import REPR_LIMIT
from tests.conftest import PAPER_TOML, ROOT

MODELS = ROOT / "examples" / "models"
LINEAR = MODELS / "linear-disturbed-l1.toml"

CUBIC = """
[model]
name = "x' = -a x + x^3"
states = ["x"]
[parameters]
a = 1
[dynamics]
x = "-a*x + x**3"
"""


@pytest.fixture(scope="module")
def cubic(tmp_path_factory: pytest.TempPathFactory) -> Path:
    path = tmp_path_factory.mktemp("models") / "cubic.toml"
    path.write_text(CUBIC)
    return path


@pytest.fixture(scope="module")
def ten_states() -> CertifyResult:
    return certify(model=MODELS / "lyznet-10d.toml")


@pytest.fixture(scope="module")
def paper() -> CertifyResult:
    return certify(PAPER_TOML)


@pytest.fixture(scope="module")
def disturbed() -> CertifyResult:
    return certify(model=LINEAR)


def assert_matches_document(result: CertifyResult) -> None:
    """Every condition's attributes are what the document says under conditions[name]."""
    doc = result.to_dict()
    assert set(result.conditions) == set(doc["conditions"])
    for name, cond in result.conditions.items():
        entry = doc["conditions"][name]
        assert cond.to_json() == entry, name
        assert (cond.status, cond.summary, cond.property, cond.disturbances) == (
            entry["status"], entry["summary"], entry.get("property"), entry.get("disturbances")), name


# -- certify -------------------------------------------------------------------------------------

def test_certify_repr_is_short_and_says_every_class(ten_states: CertifyResult, paper: CertifyResult) -> None:
    for result in (ten_states, paper):
        text = repr(result)
        assert len(text) < REPR_LIMIT and len(text) < len(str(result.document)) / 20
        lines = text.splitlines()
        assert lines[0].startswith(f"CertifyResult: {result.verdict} (")
        assert len(lines) == 1 + len(result.conditions)
        for line, (name, cond) in zip(lines[1:], result.conditions.items()):
            assert line.split()[:2] == [name, cond.status]
    assert "LyZNet 10-state coupled system" in repr(ten_states).splitlines()[0]
    assert "the paper's loop, derived dynamics" in repr(paper).splitlines()[0]


def test_box_results_are_short_and_name_the_box(cubic: Path) -> None:
    boxed = certify(model=cubic, box={"a": (1, 2)}, classes="roa")
    assert "over the box a in [1, 2]" in repr(boxed) and len(repr(boxed)) < REPR_LIMIT
    assert boxed.conditions["roa"].status == "certified" and verify(boxed).valid
    paper_box = certify_box(PAPER_TOML, ["alpha_d=588..612", "k_d=0.147..0.153"])
    assert "over the box alpha_d in [588, 612], k_d in [147/1000, 153/1000]" in repr(paper_box)
    assert len(repr(paper_box)) < REPR_LIMIT
    assert_matches_document(paper_box)


def test_attributes_say_what_the_json_says(ten_states: CertifyResult, paper: CertifyResult,
                                           disturbed: CertifyResult) -> None:
    # the example: the class's default property was None on the attribute, "LES" in the JSON
    assert ten_states.conditions["linearization"].property == "LES"
    assert ten_states.to_dict()["conditions"]["linearization"]["property"] == "LES"
    for result in (ten_states, paper, disturbed):
        assert_matches_document(result)
    # a disturbed model: every claim says which disturbances it covers, on the attribute too
    covers = {name: c.disturbances for name, c in disturbed.conditions.items()}
    assert set(covers.values()) <= {"zero", "all"} and None not in covers.values()
    assert covers["sos_bound"] == "all"


def test_to_dict_is_the_document_as_a_copy(disturbed: CertifyResult) -> None:
    doc = disturbed.to_dict()
    assert doc == disturbed.document == disturbed.to_json()
    doc["verdict"] = "forged"
    assert disturbed.to_dict()["verdict"] != "forged"


def test_html_is_a_small_escaped_table(tmp_path: Path) -> None:
    hostile = tmp_path / "hostile.toml"
    hostile.write_text(CUBIC.replace('name = "x\' = -a x + x^3"', 'name = "<script>alert(1)</script> & co"'))
    result = certify(model=hostile, classes="linearization")
    page = result._repr_html_()
    assert page.startswith("<table>") and page.endswith("</table>")
    assert "<script>" not in page and "&lt;script&gt;alert(1)&lt;/script&gt; &amp; co" in page
    assert "<td style=\"text-align:left\">linearization</td>" in page and "LES" in page


def test_verify_result_repr_lists_what_fails(cubic: Path) -> None:
    found = certify(model=cubic, candidate="x**2", classes="candidate")
    assert repr(verify(found)).startswith("VerifyResult: valid (all ")
    forged = found.to_dict()
    forged["conditions"]["candidate"]["certificate"]["V"] = {"terms": [["abc", [2]]]}
    checked = verify(forged)
    text = repr(checked)
    assert text.startswith("VerifyResult: NOT valid (") and "FAIL candidate" in text and len(text) < REPR_LIMIT
    assert "<table>" in checked._repr_html_() and checked.to_dict() == checked.to_json()


# -- simulate ------------------------------------------------------------------------------------

def test_simulation_repr_is_short_for_ten_states() -> None:
    run = simulate(model=MODELS / "lyznet-10d.toml")
    text = repr(run)
    assert len(text) < REPR_LIMIT and len(text.splitlines()) <= 4
    assert "82 trajectories (82 converged, 0 diverged)" in text and "x10 " in text
    assert "series: xarray.Dataset of x, y over 82 trajectories x 501 times" in text
    assert dict(run.series.sizes) == {"trajectory": 82, "time": 501, "state": 10, "output": 10}
    assert "<table>" in run._repr_html_() and run.to_dict() is run.document


def test_series_follows_the_closed_form() -> None:
    """x1' = -x1 + x2, x2' = -2 x2 with d = 0: x2 = b e^{-2t}, x1 = (a + b) e^{-t} - b e^{-2t}."""
    run = simulate(model=LINEAR, x0={"x1": 1, "x2": 1}, scenarios=["none"])
    ds = run.series
    assert isinstance(run, SimulationReport) and ds.time.attrs["units"] == "s"
    t = ds.time.values
    x = ds.x.sel(trajectory=0)
    np.testing.assert_allclose(x.sel(state="x2"), np.exp(-2 * t), atol=1e-6)
    np.testing.assert_allclose(x.sel(state="x1"), 2 * np.exp(-t) - np.exp(-2 * t), atol=1e-6)
    # the outputs are the model's [outputs] (y = x1, w = x2), the last sample the document's final state
    np.testing.assert_array_equal(ds.y.sel(trajectory=0, output="y"), x.sel(state="x1"))
    final = run["trajectories"][0]["final_state"]
    assert [float(v) for v in x.isel(time=-1)] == [final["x1"], final["x2"]]
    assert list(ds.scenario.values) == ["none"] and bool(ds.converged[0])


def test_series_of_every_scenario_and_a_diverging_start(tmp_path: Path) -> None:
    run = simulate(model=LINEAR, x0=[0, 0])
    ds = run.series
    assert ds.sizes["trajectory"] == len(run["trajectories"]) == 1 + 2 + 4 + 8
    assert list(ds.scenario.values) == [t["scenario"] for t in run["trajectories"]]
    # the reversed Van der Pol oscillator from outside its limit cycle escapes: NaN after its last step
    vdp = simulate(model=MODELS / "van-der-pol-reversed.toml", x0=[[0.5, 0], [2.5, 0]], t_end=20)
    x = vdp.series.x
    assert vdp.diverged and bool(vdp.series.diverged[1]) and not bool(vdp.series.diverged[0])
    assert not np.isnan(x.isel(trajectory=0)).any() and np.isnan(x.isel(trajectory=1, time=-1)).all()


def test_paper_simulation_has_its_series() -> None:
    run = simulate(preset="paper-ilos")
    ds = run.series
    assert set(ds.data_vars) == {"p_x", "p_z", "s", "eps", "u_x", "u_z", "v_x", "v_z", "d_x", "d_z"}
    assert ds.eps.attrs["units"] == "m" and float(ds.time[-1]) == run["horizon_s"]
    assert float(ds.eps.isel(time=-1)) == pytest.approx(run["final_eps_m"], rel=1e-6)
    assert len(repr(run)) < REPR_LIMIT and simulate(preset="paper-ilos", series=False).series is None


def test_worst_case_repr_and_no_series() -> None:
    run = simulate(model=LINEAR, worst_case=True, budget_s=1)
    assert run.series is None and "worst case of model" in repr(run) and len(repr(run)) < REPR_LIMIT
    assert "worst tail sup" in run._repr_html_()


@pytest.mark.parametrize("x0", [
    {"x1": 1, "x2": 0.5}, {"x1": "1 m", "x2": 0.5}, [1, 0.5], (1.0, 0.5), np.array([1.0, 0.5]), "x1=1 x2=0.5",
    "x1=1,x2=0.5", [{"x1": 1, "x2": 0.5}], [[1, 0.5]], np.array([[1.0, 0.5]]), ["x1=1 x2=0.5"]])
def test_x0_in_every_form_gives_the_same_start(x0: Any) -> None:
    run = simulate(model=LINEAR, x0=x0, scenarios=["none"], t_end=1, series=False)
    assert run["starts"] == [{"x1": 1.0, "x2": 0.5}]


def test_x0_several_starts_and_the_equilibrium_for_missing_states() -> None:
    run = simulate(model=LINEAR, x0=[{"x2": 2}, [1, 0.5], "x1=3"], scenarios=["none"], t_end=1, series=False)
    assert run["starts"] == [{"x1": 0.0, "x2": 2.0}, {"x1": 1.0, "x2": 0.5}, {"x1": 3.0, "x2": 0.0}]


@pytest.mark.parametrize("x0", [{"x9": 1}, [1, 2, 3], [1, math.nan], {"x1": "fast"}, {"x1": math.inf}, 5,
                                [[1], [1, 2]], {"x1": True}, [True, False], "x9=1", [object()]])
def test_bad_x0_is_one_line_naming_x0(x0: Any) -> None:
    with pytest.raises(InvalidParameter) as info:
        simulate(model=LINEAR, x0=x0, scenarios=["none"], series=False)
    message = str(info.value)
    assert info.value.field == "x0" and "\n" not in message and "--" not in message


# -- errors name the API's arguments -------------------------------------------------------------

API_ERRORS: list[tuple[dict[str, Any], str]] = [
    ({"t_end": -1}, "t_end"),
    ({"t_end": "5 m"}, "t_end"),
    ({"scenarios": ["storm"]}, "scenarios"),
    ({"worst_case": True, "budget_s": 0}, "budget_s"),
    ({"worst_case": True, "scenarios": ["none"]}, "scenarios"),
    ({"certificate": "cert.json"}, "certificate"),
    ({"grid": 3}, "grid"),
    ({"frequencies": "10..1"}, "frequencies"),
    ({"plot": "out.pdf"}, "plot"),
]


@pytest.mark.parametrize("kwargs,field", API_ERRORS, ids=[f for _, f in API_ERRORS])
def test_simulate_errors_name_the_api_argument(kwargs: dict[str, Any], field: str) -> None:
    with pytest.raises(InvalidParameter) as info:
        simulate(model=LINEAR, series=False, **kwargs)
    assert info.value.field == field and "--" not in str(info.value), str(info.value)


def test_worst_case_without_disturbances_names_worst_case() -> None:
    with pytest.raises(InvalidParameter) as info:
        simulate(model=MODELS / "van-der-pol-reversed.toml", worst_case=True)
    assert info.value.field == "worst_case" and "--" not in str(info.value)


@pytest.mark.parametrize("settings,key", [({"q": 1}, "settings['q']"), (["q"], "settings"),
                                           (["d=-1"], "settings['d']")])
def test_settings_errors_name_settings(settings: Any, key: str) -> None:
    with pytest.raises(ModelFileError) as info:
        simulate(model=LINEAR, settings=settings, series=False)
    assert info.value.key == key and "--set" not in str(info.value)


def test_the_paper_loop_refuses_a_models_arguments_by_name() -> None:
    with pytest.raises(InvalidParameter, match="'budget_s'"):
        simulate(preset="paper-ilos", worst_case=True, budget_s=0)
    for name, value in (("x0", {"x": 1}), ("t_end", 10), ("scenarios", ["none"]), ("settings", {"mu": 1})):
        with pytest.raises(InvalidParameter) as info:
            simulate(preset="paper-ilos", **{name: value})
        assert info.value.field == name and "model=" in str(info.value)


def test_the_command_line_still_names_its_flags(tmp_path: Path) -> None:
    from click.testing import CliRunner

    from lyapcheck.cli import app  # type: ignore[attr-defined]

    app._register_commands()
    for args, flag in ((["--t-end", "-1"], "'t-end'"), (["--set", "q=1"], "--set q"),
                       (["--worst-case", "--scenario", "none"], "--worst-case"), (["--grid", "3"], "--x0")):
        done = CliRunner().invoke(app.cli, ["simulate", str(LINEAR), *args], catch_exceptions=False)
        assert done.exit_code == 2 and flag in done.stderr, (args, done.stderr)
    done = CliRunner().invoke(app.cli, ["simulate", "--preset", "paper-ilos", "--worst-case", "--budget", "0"],
                              catch_exceptions=False)
    assert done.exit_code == 2 and "'budget'" in done.stderr, done.stderr


def test_every_api_error_is_a_lyapcheck_error() -> None:
    with pytest.raises(LyapcheckError):
        simulate(model=LINEAR, x0="nonsense")
