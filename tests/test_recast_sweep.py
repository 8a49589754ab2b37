"""Sweeps of a loop with functions (``[sweep] model = FILE`` whose ``[dynamics]`` use sin, sqrt, ...),
points mode: each grid point certified as ``certify FILE --set`` certifies it, resume, one-line errors,
workers that get the text only, and the simulation alarm on a false certificate.

The loops are the shipped examples, copied into the test's directory: the damped pendulum
(``recast-pendulum.toml``: LES for every damping b > 0, unstable for b < 0, never GAS because of the
saddle at theta = pi) and the ILOS course loop (``recast-ilos-course.toml``: GAS, sqrt in the field).
Cheap classes only (``linearization``, ``sos_gas``); ``roa`` takes seconds a point.
"""

from __future__ import annotations

import json
from fractions import Fraction
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from lyapcheck.answers import OK_VERDICTS
from tests.conftest import ROOT
from tests.test_model_sweeps import arrays, assert_refused, cli, run  # the model sweeps' own helpers

PENDULUM = (ROOT / "examples" / "models" / "recast-pendulum.toml").read_text()
ILOS = (ROOT / "examples" / "models" / "recast-ilos-course.toml").read_text()
DAMPING = """[sweep]
model = "m.toml"
classes = ["linearization", "sos_gas"]
chunk_size = 1
[[sweep.axes]]
name = "b"
values = [-0.5, 0.5, 1, 2]
"""
KAPPA = """[sweep]
model = "m.toml"
classes = ["sos_gas"]
chunk_size = 2
[[sweep.axes]]
name = "kappa"
start = 0.25
stop = 2
num = 3
scale = "log"
[sweep.set]
U = "2"
[simulation]
starts = 6
"""


def write(directory: Path, spec: str, model: str = PENDULUM) -> Path:
    directory.mkdir(parents=True, exist_ok=True)
    (directory / "m.toml").write_text(model)
    path = directory / "spec.toml"
    path.write_text(spec)
    return path


@pytest.fixture(scope="module")
def damping(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Any]:
    directory = tmp_path_factory.mktemp("damping")
    spec = write(directory, DAMPING)
    return directory / "out.zarr", run(spec, directory / "out.zarr")


# -- each point is what certify says there -------------------------------------------------------------
def test_each_point_of_the_pendulums_damping_is_what_certify_says_there(damping: tuple[Path, Any]) -> None:
    from lyapcheck.api import certify, verify
    from sweeps.spec import exact_decimal

    path, result = damping
    data = arrays(path)
    b = data["b"]
    codes = {"certified": 1, "refuted": 2, "not_certified": 0, "inconclusive": 3, "not_applicable": 4}
    assert result.mode == "model_points" and result.summary.computed == 4
    # damped (b > 0): locally exponentially stable; b < 0: the Jacobian has an unstable eigenvalue, exactly
    assert list(data["status_linearization"]) == [2, 1, 1, 1] and list(data["status"]) == [2, 1, 1, 1]
    assert list(data["status_sos_gas"]) == [2, 2, 2, 2]  # the saddle at theta = pi: never GAS, exactly
    for j, value in enumerate(b):
        direct = certify(model=path.parent / "m.toml", settings=[f"b={exact_decimal(float(value))}"],
                         classes="linearization,sos_gas")
        assert data["status_linearization"][j] == codes[direct.conditions["linearization"].status]
        assert data["status_sos_gas"][j] == codes[direct.conditions["sos_gas"].status]
        cert = str(data["certificate"][j])
        assert (cert != "") == (direct.verdict in OK_VERDICTS)  # (certified_local: the linearization alone)
        if cert:
            doc = json.loads(cert)
            assert Fraction(doc["overrides"]["b"]) == Fraction(float(value))  # the stored float, exactly
            assert doc["model"]["text"] == PENDULUM and verify(doc).valid
            assert data["cross_check_points"][j] == 1 and not data["soundness_violation"][j]
    assert "certified by linearization (LES)" in str(data["note"][1])
    assert result.summary.share_by_class["linearization"] == pytest.approx(result.summary.share["certified"])


def test_a_gas_loop_is_cross_checked_by_simulating_its_true_field(tmp_path: Path) -> None:
    from lyapcheck.api import verify

    result = run(write(tmp_path, KAPPA, ILOS), tmp_path / "out.zarr")
    data = arrays(tmp_path / "out.zarr")
    assert list(data["status_sos_gas"]) == [1, 1, 1]
    assert list(data["cross_check_trajectories"]) == [6, 6, 6] and not data["soundness_violation"].any()
    assert np.all(data["cross_check_worst_rise"] <= 1e-5)
    for cert, kappa in zip(data["certificate"], data["kappa"]):
        doc = json.loads(str(cert))
        assert doc["overrides"] == {"U": "2", "kappa": str(doc["overrides"]["kappa"])}
        assert Fraction(doc["parameters"]["kappa"]) == Fraction(float(kappa)) and verify(doc).valid
    assert result.summary.to_json()["cross_check"]["trajectories"] == 18



def test_a_disturbed_loop_with_functions_sweeps_its_bound_with_the_disturbance_from_the_spec(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """sos_bound per point, the disturbance's bound set by [sweep.set]: a smaller bound proves a smaller limsup."""
    from lyapcheck import tolerances
    from lyapcheck.api import verify

    # the class's time limit as a safety net only (d = 0.02 needs a quartic V, about 30 s idle): the outcome is
    # the search's fixed list of solves, which a loaded machine must not cut short
    monkeypatch.setattr(tolerances, "MODEL_CLASS_TIME_LIMIT_S", 900.0)

    model = (ROOT / "examples" / "models" / "recast-ilos-course-disturbed.toml").read_text()
    spec = ('[sweep]\nmodel = "m.toml"\nclasses = ["sos_bound"]\n[sweep.set]\nd = {d}\n'
            '[[sweep.axes]]\nname = "kappa"\nvalues = [0.5]\n')
    bounds = {}
    for d in ("0.02", "0.05"):
        run(write(tmp_path / d, spec.format(d=d), model), tmp_path / d / "out.zarr")
        data = arrays(tmp_path / d / "out.zarr")
        assert list(data["status_sos_bound"]) == [1]
        doc = json.loads(str(data["certificate"][0]))
        assert doc["disturbances"] == {"d": str(Fraction(d))} and verify(doc).valid
        bounds[d] = float(data["sos_bound_y"][0])
        # simulated under disturbances at their bound: inside the certified bound, and the constant
        # d holds yi at d Delta / (kappa sqrt(U^2 - d^2)), which the bang-bang search reaches
        assert 0 < data["sim_worst_y"][0] <= data["sos_bound_y"][0] and not data["soundness_violation"][0]
        assert data["sim_worst_yi"][0] >= 0.99 * float(d) * 2 / (0.5 * (1 - float(d) ** 2) ** 0.5)
    assert bounds["0.02"] < bounds["0.05"]


def test_a_bound_below_what_the_loop_reaches_raises_the_alarm() -> None:
    """A certified sos_bound halved: the disturbed ILOS reaches more than it under a disturbance at its
    bound (yi settles at d Delta / (kappa sqrt(U^2 - d^2)) for a constant d), and the sweep says so."""
    from lyapcheck.models.language.modelfile import parse_any_model
    from sweeps.crosscheck import cross_check_point

    text = (ROOT / "examples" / "models" / "recast-ilos-course-disturbed.toml").read_text()
    model = parse_any_model(text, "m.toml", {"kappa": "0.5"})
    claim = {"conditions": {"sos_bound": {"status": "certified", "bounds": {"yi": 0.1}}}}
    found = cross_check_point(model, claim, {"kappa": Fraction(1, 2)}, starts=4, seed=(0, 2))
    assert found.violation and found.violations[0].startswith("sos_bound at kappa = 0.5: ")
    assert found.sim_worst["yi"] > 0.2


# -- resume ----------------------------------------------------------------------------------------------
class Interrupt(Exception):
    """Raised from the progress callback: the sweep stops between units, as after a kill."""


def test_an_interrupted_sweep_resumes_with_the_missing_points_only(tmp_path: Path, damping: tuple[Path, Any]) -> None:
    whole, _ = damping
    spec = write(tmp_path, DAMPING)
    out = tmp_path / "out.zarr"
    seen = [0]

    def progress(done: int, total: int) -> None:
        seen[0] += done
        if seen[0] >= 2:
            raise Interrupt()

    with pytest.raises(Interrupt):
        run(spec, out, progress=progress)
    finished = int(arrays(out)["done"].sum())
    assert 0 < finished < 4
    resumed = run(spec, out)
    assert resumed.run.computed_now == 4 - finished
    files_a = {p.relative_to(whole): p.read_bytes() for p in whole.rglob("*") if p.is_file()}
    files_b = {p.relative_to(out): p.read_bytes() for p in out.rglob("*") if p.is_file()}
    assert files_a.keys() == files_b.keys() and all(files_a[k] == files_b[k] for k in files_a)
    assert run(spec, out).run.computed_now == 0


# -- bad input: one line, exit 2, nothing written --------------------------------------------------------------
AXIS = '[[sweep.axes]]\nname = "b"\nvalues = [0.5, 1]\n'


@pytest.mark.parametrize("spec, model, needle", [
    ('[sweep]\nmodel = "m.toml"\n[[sweep.axes]]\nname = "g"\nvalues = [1, 2]\n', PENDULUM,
     "'sweep.axes[0].name' parameter must be a parameter declared in the model (b). Got 'g' instead."),
    ('[sweep]\nmodel = "m.toml"\nmode = "boxes"\nclasses = ["barrier"]\n[[sweep.axes]]\nname = "b"\n'
     'start = 0.5\nstop = 2\nnum = 3\n', PENDULUM,
     "'sweep.classes' parameter must be in a boxes sweep of a loop with functions, a list of distinct names from "
     "'linearization', 'quadratic', 'sos_gas', 'roa', 'sos_bound'. Got ['barrier'] instead."),
    ('[sweep]\nmodel = "m.toml"\nmode = "boxes"\nclasses = ["sos_gas"]\n[[sweep.axes]]\nname = "Delta"\n'
     'values = [-1, 0, 1]\n', ILOS, "sweep.axes, the box Delta in [-1, 0]: the loop cannot be recast over all of it"),
    ('[sweep]\nmodel = "m.toml"\nclasses = ["sos_bound"]\n' + AXIS, PENDULUM,
     "'sweep.classes' parameter must be classes that apply to the model: sos_bound needs [disturbances]"),
    ('[sweep]\nmodel = "m.toml"\nclasses = ["barrier"]\n' + AXIS, PENDULUM,
     "'sweep.classes' parameter must be in a points sweep of a loop with functions, a list of distinct names from "
     "'linearization', 'quadratic', 'sos_gas', 'roa', 'sos_bound'"),
    ('[sweep]\nmodel = "m.toml"\nclasses = ["candidate"]\n' + AXIS, PENDULUM, "'sweep.classes' parameter must be"),
    ('[sweep]\nmodel = "m.toml"\n[sweep.set]\nq = 1\n' + AXIS, PENDULUM,
     "'sweep.set.q' parameter must be a parameter or disturbance declared in the model (b)"),
    ('[sweep]\nmodel = "m.toml"\n[sweep.set]\nb = 1\n' + AXIS, PENDULUM, "'sweep.set.b' parameter must be absent"),
    ('[sweep]\nmodel = "m.toml"\n[[sweep.axes]]\nname = "Delta"\nvalues = [0, 1]\n', ILOS,
     "sweep.axes at the grid point Delta = 0: the model is not defined there"),
])
def test_a_bad_spec_is_one_line_exit_2_and_writes_nothing(tmp_path: Path, spec: str, model: str, needle: str) -> None:
    assert_refused(write(tmp_path, spec, model), needle)


def test_a_loop_with_functions_is_swept_over_the_classes_of_a_polynomial_loop() -> None:
    from lyapcheck.models.language.modelfile import parse_any_model
    from lyapcheck.models.language.recast import RecastModel
    from sweeps.spec import MODEL_BOX_CLASSES, MODEL_POINT_CLASSES, _model_classes

    pendulum = parse_any_model(PENDULUM)
    assert isinstance(pendulum, RecastModel) and not pendulum.sets and not pendulum.disturbances
    without_sets = ("sos_bound", "barrier", "reach_avoid")  # (no disturbances, no [sets])
    assert "candidate" not in MODEL_POINT_CLASSES  # (the user's V: a sweep cannot run it)
    assert _model_classes(None, "points", pendulum) == tuple(c for c in MODEL_POINT_CLASSES if c not in without_sets)
    # and over boxes too, the linearization included (its Jacobian over a box, by the chain rule)
    assert "linearization" in MODEL_BOX_CLASSES
    assert _model_classes(None, "boxes", pendulum) == tuple(c for c in MODEL_BOX_CLASSES if c not in without_sets)


# -- workers, a point the recasting cannot take, the alarm -----------------------------------------------------
def test_workers_need_the_spec_text_only(tmp_path: Path) -> None:
    from sweeps.evaluate import evaluate_model_points
    from sweeps.spec import load_model_spec

    spec = load_model_spec(write(tmp_path, DAMPING))
    (tmp_path / "m.toml").unlink()  # a worker on another machine has no model file
    out = evaluate_model_points(spec.worker_text, np.array([[0.5], [-0.5]]))
    assert list(out["status"]) == [1, 2] and json.loads(str(out["certificate"][0]))["model"]["text"] == PENDULUM


def test_a_point_whose_recasting_fails_is_stored_not_certified_with_the_reason(tmp_path: Path) -> None:
    """``sqrt(4 + x)`` can be negative: the recasting's proof of its argument fails at every point."""
    model = '[model]\nstates = ["x"]\n[parameters]\nc = 1\n[dynamics]\nx = "-c*x + sqrt(4 + x) - 2"\n'
    spec = '[sweep]\nmodel = "m.toml"\nclasses = ["linearization"]\n[[sweep.axes]]\nname = "c"\nvalues = [1, 2]\n'
    run(write(tmp_path, spec, model), tmp_path / "out.zarr")
    data = arrays(tmp_path / "out.zarr")
    assert list(data["status"]) == [0, 0] and list(data["status_linearization"]) == [0, 0]
    assert all("could not be recast at this point" in str(n) and "could not be proved non-negative" in str(n)
               for n in data["note"])


def test_a_false_certificate_of_the_pendulum_raises_the_alarm() -> None:
    """``V = theta**2 + omega**2`` claimed GAS: starts at high speed turn over the saddle and V rises.
    The energy ``1 - cos(theta) + omega**2/2`` (``V' = -b omega**2 <= 0``) never rises: no alarm."""
    from lyapcheck.models.language.modelfile import parse_any_model
    from sweeps.crosscheck import cross_check_point

    model = parse_any_model(PENDULUM, "m.toml", {"b": "0.5"})
    names = list(model.system.ring.names)  # theta, omega, then sin(theta) and cos(theta)
    cosine = next(a.name for a in model.system.auxiliaries if a.function == "cos")

    def power(name: str, k: int) -> list[int]:
        return [k if n == name else 0 for n in names]

    def claim(terms: list[list[Any]]) -> dict[str, Any]:
        return {"conditions": {"sos_gas": {"status": "certified", "property": "GAS", "certificate": {
            "variables": names, "shift": {k: str(v) for k, v in model.system.values.items()}, "angles": ["theta"],
            "V": {"terms": terms}}}}}

    false = claim([["1", power("theta", 2)], ["1", power("omega", 2)]])
    found = cross_check_point(model, false, {"b": Fraction(1, 2)}, starts=8, seed=(0, 1))
    assert found.violation and found.worst_rise > 1e-5 and found.violations[0].startswith("sos_gas at b = 0.5")
    energy = claim([["-1", power(cosine, 1)], ["1/2", power("omega", 2)]])  # cos shifted: c - 1
    found = cross_check_point(model, energy, {"b": Fraction(1, 2)}, starts=8, seed=(0, 1))
    assert not found.violation and found.trajectories == 8 and found.worst_rise <= 1e-5


def test_a_sweep_shouts_a_violation_its_certifier_reported(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """A certificate whose own simulation when certified found a start that did not converge (here
    put there by a wrapper) is a soundness violation of the sweep: exit 1, shouted."""
    import lyapcheck.models.surfaces.certify as certify

    honest = certify.certify_model

    def flagged(*args: Any, **kwargs: Any) -> Any:
        found = honest(*args, **kwargs)
        found.results["sos_gas"].numbers.update({"soundness_violation": True, "starts_in_set_not_converged": 1})
        return found

    monkeypatch.setattr(certify, "certify_model", flagged)
    spec = write(tmp_path, KAPPA.replace("num = 3", "num = 2"), ILOS)
    result = cli("sweep", str(spec), "--out", str(tmp_path / "out.zarr"), "--workers", "0", "--quiet")
    assert result.exit_code == 1, result.output
    assert "SOUNDNESS VIOLATION" in result.stderr and "did not converge" in result.stderr
