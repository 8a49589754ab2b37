"""Discrete-time maps (issue 44, item 1): ``[model] time = "discrete"``, where ``[dynamics]`` gives each
state's next value.

What is asserted: the key (a fixed point checked as ``f(x_eq) = x_eq``, ``[units]`` per state, the round
trip through ``from_sympy``); the linearization decided exactly (``rho(A) < 1`` certified, an eigenvalue of
modulus > 1 refuted, the unit circle undecided), against numpy's eigenvalues on random rational matrices;
a map's certificate never verifies against a field and a field's never against a map; and the guard: every
class and every surface on a map is either correct or refused (``not_applicable`` naming discrete-time maps,
or one line, exit 2, naming ``time = "discrete"``), never a continuous-time answer.
"""

from __future__ import annotations

import hashlib
import json
from fractions import Fraction
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from click.testing import CliRunner

from lyapcheck.cli import app
from lyapcheck.errors import LyapcheckError, ModelFileError
from lyapcheck.models.classes import discrete_linearization as dl
from lyapcheck.models.classes.registry import CLASSES, DISCRETE
from lyapcheck.models.language.build import Model as BuiltModel
from lyapcheck.models.language.modelfile import Model, parse_model

app._register_commands()

EXAMPLES = Path(__file__).resolve().parents[1] / "examples" / "models"

#: x+ = a x/2 + y/4, y+ = -x/4 + a y/2 - y^3/8: eigenvalues a/2 +- i/4 (modulus < 1 for |a| < sqrt(3.75))
MAP = """[model]
name = "a contracting rotation"
states = ["x", "y"]
time = "discrete"
[parameters]
a = 1
[dynamics]
x = "a*x/2 + y/4"
y = "-x/4 + a*y/2 - y**3/8"
[domain]
x = [-1, 1]
y = [-1, 1]
[sets]
initial = ["(x - 0.5)**2 + y**2 <= 0.01"]
unsafe = ["x >= 0.9"]
goal = ["x**2 + y**2 <= 0.01"]
"""

#: the same right-hand sides read as a field (an ODE)
FIELD = MAP.replace('time = "discrete"\n', "")


def cli(*args: str) -> Any:
    done = CliRunner().invoke(app.cli, list(args))
    assert done.exception is None or isinstance(done.exception, SystemExit), done.output
    assert "Traceback" not in done.output
    return done


def refused_line(done: Any) -> str:
    """The one line of a refusal (exit 2), naming time = "discrete"."""
    assert done.exit_code == 2, done.output
    [line] = done.stderr.splitlines()
    assert 'time = "discrete"' in line, line
    return line


def write(folder: Path, text: str, name: str = "map.toml") -> Path:
    path = folder / name
    path.write_text(text)
    return path


def F(rows: list[list[Any]]) -> list[list[Fraction]]:
    return [[Fraction(x) for x in row] for row in rows]


# -- the key -----------------------------------------------------------------------------------------
def test_a_map_carries_its_time_and_a_field_is_continuous_by_default() -> None:
    assert parse_model(MAP).time == "discrete" and parse_model(MAP).discrete
    assert parse_model(FIELD).time == "continuous" and not parse_model(FIELD).discrete


def test_the_fixed_point_is_checked_as_f_of_x_eq_equal_to_x_eq() -> None:
    logistic = ('[model]\nname = "l"\nstates = ["x"]\ntime = "discrete"\n[dynamics]\nx = "3.2*x*(1 - x)"\n'
                "[equilibrium]\nx = {}\n")
    assert parse_model(logistic.format("0.6875")).equilibrium == (Fraction(11, 16),)
    assert parse_model(logistic.format("0")).equilibrium == (Fraction(0),)  # f(0) = 0 = x_eq: a fixed point too
    with pytest.raises(ModelFileError, match=r"\[equilibrium\]: is not a fixed point of the map: x\+ = 2/5 there, "
                                             r"not 1/2"):
        parse_model(logistic.format("0.5").replace("3.2", "1.6"))
    # f(x_eq) = 0 is a field's equilibrium, not a map's
    with pytest.raises(ModelFileError, match="not a fixed point"):
        parse_model('[model]\nname = "m"\nstates = ["x"]\ntime = "discrete"\n[dynamics]\nx = "x - 1"\n'
                    "[equilibrium]\nx = 1\n")


def test_units_of_a_map_are_the_states_own() -> None:
    head = '[model]\nname = "m"\nstates = ["x"]\ntime = "discrete"\n[parameters]\nk = "{}"\n[dynamics]\nx = "k*x"\n' \
           '[units]\nx = "m"\n'
    assert parse_model(head.format("0.5")).units == {"x": "m"}
    with pytest.raises(ModelFileError, match=r"\[dynamics\] x: .*a map gives the next value"):
        parse_model(head.format("0.5 1/s"))
    assert parse_model(head.format("0.5 1/s").replace('time = "discrete"\n', "")).units == {"x": "m"}


def test_a_map_with_functions_is_read_as_a_map() -> None:
    from lyapcheck.models.language.modelfile import parse_any_model
    from lyapcheck.models.language.recast import RecastModel

    # (taken since issue 44's maps with functions: tests/test_discrete_functions.py)
    model = parse_any_model(MAP.replace('"a*x/2 + y/4"', '"sin(x)/2 + y/4"'))
    assert isinstance(model, RecastModel) and model.time == "discrete" and model.system.flows == {}


def test_from_sympy_keeps_the_time_and_its_text_round_trips() -> None:
    import sympy as sp

    from lyapcheck.models.language.build import from_sympy

    x, y = sp.symbols("x y")
    model = from_sympy([x, y], [x / 2 + y ** 2 / 10, -3 * x / 10 + 3 * y / 5], time="discrete")
    assert isinstance(model, Model) and model.time == "discrete" and parse_model(model.to_toml()).time == "discrete"
    assert from_sympy([x], [-x]).to_toml().count("time") == 0  # a field's text is as before
    with pytest.raises(LyapcheckError, match="time"):
        from_sympy([x], [-x], time="sampled")


def test_a_discrete_time_state_space_closed_with_a_gain_is_a_map() -> None:
    """x+ = (A - B K) x with A = [[1, 0.1], [0, 1]], B = [[0], [0.1]], K = [[2, 3]]: eigenvalues of modulus < 1."""
    control = pytest.importorskip("control")
    from lyapcheck.models.surfaces.certify import certify_model

    system = control.ss([[1, 0.1], [0, 1]], [[0], [0.1]], [[1, 0]], [[0]], dt=0.1)
    model = BuiltModel.from_control(system, [[2, 3]])
    assert isinstance(model, Model) and model.time == "discrete"
    A: list[list[Any]] = [[1, Fraction(1, 10)], [Fraction(-2, 10), Fraction(7, 10)]]
    assert certify_model(model, classes="linearization").results["linearization"].certificate["jacobian"] == \
        [[str(x) for x in row] for row in F(A)]
    assert max(abs(np.linalg.eigvals(np.array(A, dtype=float)))) < 1
    assert certify_model(model, classes="linearization").results["linearization"].status == "certified"
    with pytest.raises(LyapcheckError, match="time"):
        BuiltModel.from_control(system, [[2, 3]], time="continuous")


# -- the linearization, exact -----------------------------------------------------------------------
@pytest.mark.parametrize(("A", "status", "method"), [
    ([[Fraction(1, 2), 0], [Fraction(-3, 10), Fraction(3, 5)]], "certified", "stein_equation"),
    ([[Fraction(1, 2), 1], [0, Fraction(3, 2)]], "refuted", "stein_unbounded"),
    ([[2, 0], [0, Fraction(1, 2)]], "refuted", "cayley_root_isolation"),  # 2 * 1/2 = 1: the Stein equation is singular
    ([[0, -1], [1, 0]], "not_certified", None),  # +-i, on the unit circle
    ([[-1]], "not_certified", None),  # -1: the bilinear transform loses a degree
    ([[-1, 0], [0, 3]], "refuted", "cayley_root_isolation"),  # -1 and 3: 3 is found after -1 is divided out
])
def test_the_spectral_radius_is_decided_exactly(A: list[list[Any]], status: str, method: str | None) -> None:
    r = dl.decide(F(A))
    assert r.status == status, r.summary
    data = r.certificate if status != "refuted" else r.refutation
    assert data.get("method") == method and data["time"] == "discrete"
    if status in ("certified", "refuted"):
        assert dl.verify_matrix(F(A), status, data)[0]
        assert "discrete-time map" in r.summary


def test_the_bilinear_transform_maps_the_unit_disc_onto_the_left_half_plane() -> None:
    # p(z) = z^2 - 1/4 (roots +-1/2): q(s) = (1 + s)^2 - (1 - s)^2/4 = 3/4 s^2 + 5/2 s + 3/4
    assert dl.cayley([Fraction(-1, 4), Fraction(0), Fraction(1)]) == [Fraction(3, 4), Fraction(5, 2), Fraction(3, 4)]


def test_random_rational_matrices_agree_with_their_eigenvalues() -> None:
    """certified only when every |lambda| < 1, refuted only when some |lambda| > 1 (floating point, away from 1)."""
    rng = np.random.default_rng(44)
    seen = set()
    for _ in range(60):
        n = int(rng.integers(1, 5))
        A = [[Fraction(int(v), 8) for v in row] for row in rng.integers(-8, 9, size=(n, n))]
        r = dl.decide(A)
        radius = float(np.max(np.abs(np.linalg.eigvals(np.array(A, dtype=float)))))
        seen.add(r.status)
        if r.status == "certified":
            assert radius < 1
        elif r.status == "refuted":
            assert radius > 1
        elif abs(radius - 1) > 1e-9:
            assert r.status != "inconclusive", (A, r.summary)
    assert {"certified", "refuted"} <= seen


# -- verify: a map's test never re-checks a field, nor a field's a map ---------------------------------
def _certificate(folder: Path, text: str) -> dict[str, Any]:
    out = folder / "cert.json"
    done = cli("certify", str(write(folder, text)), "--classes", "linearization", "--no-store", "--out", str(out))
    assert done.exit_code == 0, done.output
    return dict(json.loads(out.read_text()))


def _with_text(doc: dict[str, Any], text: str) -> dict[str, Any]:
    doc = json.loads(json.dumps(doc))
    doc["model"]["text"], doc["model"]["sha256"] = text, hashlib.sha256(text.encode()).hexdigest()
    return doc


def test_a_certificate_verifies_against_its_own_kind_of_time_only(tmp_path: Path) -> None:
    from lyapcheck.models.surfaces.certificate import verify_document

    on_map = _certificate(tmp_path, MAP.replace("a = 1", "a = -1"))  # the field at a = -1 is unstable
    assert on_map["conditions"]["linearization"]["certificate"]["time"] == "discrete"
    assert all(ok for _, ok, _ in verify_document(on_map))
    rows = verify_document(_with_text(on_map, FIELD.replace("a = 1", "a = -1")))
    assert any(not ok and "a discrete-time certificate" in why for _, ok, why in rows)
    on_field = _certificate(tmp_path, FIELD.replace("a = 1", "a = -1").replace("- y**3/8", "- y**3/8 - 2*x"))
    rows = verify_document(_with_text(on_field, MAP.replace("a = 1", "a = -1").replace("- y**3/8", "- y**3/8 - 2*x")))
    assert any(not ok and "not a discrete-time one" in why for _, ok, why in rows)


def test_a_certified_class_without_a_discrete_time_check_fails_verify(tmp_path: Path) -> None:
    from lyapcheck.models.surfaces.certificate import verify_document

    doc = _certificate(tmp_path, MAP)
    doc["conditions"]["sos_bound"] = {"status": "certified", "property": "ultimate_bound", "summary": "forged",
                                      "certificate": {"kind": "sos_bound"}}
    rows = verify_document(doc)
    # (sos_bound has a map check since issue 44's bounds: a continuous-time bound certificate is not a map's,
    # lyapcheck.models.classes.discrete_bounds; a class without a map check: tests/test_one_runner.py)
    assert ("sos_bound", False, "sos_bound: not a certificate of a discrete-time map's bound (kind 'sos_bound')") \
        in rows
    # a continuous-time barrier certificate is not a map's (lyapcheck.models.classes.discrete_safety)
    doc = _certificate(tmp_path, MAP)
    doc["conditions"]["barrier"] = {"status": "certified", "property": "safety", "summary": "forged",
                                    "certificate": {"kind": "barrier"}}
    rows = verify_document(doc)
    assert any(name == "barrier" and not ok and "not a barrier certificate of a discrete-time map" in why
               for name, ok, why in rows)
    # a continuous-time region certificate is not a map's (lyapcheck.models.classes.discrete_regions)
    doc = _certificate(tmp_path, MAP)
    doc["conditions"]["roa"] = {"status": "certified", "property": "ROA", "summary": "forged", "level": 1.0,
                                "certificate": {"kind": "sublevel"}}
    rows = verify_document(doc)
    assert any(name == "roa" and not ok and "not a region certificate of a discrete-time map" in why
               for name, ok, why in rows)
    # a continuous-time certificate of a class that has a discrete-time check is not one of its kinds
    doc = _certificate(tmp_path, MAP)
    doc["conditions"]["quadratic"] = {"status": "certified", "property": "GES", "summary": "forged",
                                      "certificate": {"kind": "lyapunov"}}
    rows = verify_document(doc)
    assert any(name == "quadratic" and not ok and "not a certificate of a discrete-time map" in why
               for name, ok, why in rows)


# -- the guard: every class and every surface on a map ------------------------------------------------
def test_every_class_on_a_map_is_its_discrete_time_answer_or_not_applicable(tmp_path: Path) -> None:
    path = write(tmp_path, MAP)
    done = cli("certify", str(path), "--classes", ",".join(c.name for c in CLASSES), "--candidate", "x**2 + y**2",
               "--no-store", "--json", "--out", str(tmp_path / "c.json"))
    assert done.exit_code == 0, done.output
    conditions = json.loads(done.stdout)["conditions"]
    assert list(conditions) == [c.name for c in CLASSES]
    assert DISCRETE == ("linearization", "quadratic", "sos_gas", "roa", "candidate", "sos_bound", "barrier",
                        "reach_avoid")
    assert conditions["linearization"]["status"] == "certified"
    assert conditions["linearization"]["summary"].startswith("every eigenvalue of the map's Jacobian at the fixed "
                                                             "point has modulus < 1")
    for name in ("quadratic", "sos_gas"):  # their discrete-time answers (lyapcheck.models.classes.discrete_lyapunov)
        c = conditions[name]
        assert c["status"] in ("certified", "not_certified")
        assert "discrete-time map" in c["summary"]
        assert c["status"] != "certified" or c["certificate"]["time"] == "discrete"
    for name in ("roa", "candidate"):  # (lyapcheck.models.classes.discrete_regions; roa after GAS: the whole space)
        c = conditions[name]
        assert c["status"] in ("certified", "not_certified", "not_applicable")
        assert c["status"] != "certified" or c["certificate"]["kind"] == "discrete_sublevel"
        assert c["status"] != "not_applicable" or "the region of attraction is the whole state space" in c["summary"]
    # barrier: its discrete-time answer (lyapcheck.models.classes.discrete_safety; the rotation contracts to 0)
    assert conditions["barrier"]["status"] in ("certified", "not_certified")
    assert conditions["barrier"]["status"] != "certified" or \
        conditions["barrier"]["certificate"]["kind"] == "discrete_barrier"
    assert conditions["reach_avoid"]["status"] in ("certified", "not_certified")
    assert conditions["reach_avoid"]["status"] != "certified" or \
        conditions["reach_avoid"]["certificate"]["kind"] == "discrete_reach_avoid"
    # sos_bound: the map has no [disturbances], so the loop's sentence (its bounds: tests/test_discrete_bounds.py)
    assert conditions["sos_bound"]["status"] == "not_applicable"
    assert "the model has no [disturbances]" in conditions["sos_bound"]["summary"]
    for c in CLASSES:
        if c.name not in DISCRETE:
            assert conditions[c.name]["status"] == "not_applicable"
            assert conditions[c.name]["summary"].startswith(f"{c.name} is not yet decided for discrete-time maps")
    assert cli("verify", str(tmp_path / "c.json")).exit_code == 0


def test_sweeps_reports_and_box_certify_take_a_map(tmp_path: Path) -> None:
    """``certify --box`` takes a map (its classes over a box: tests/test_discrete_boxes.py), a report iterates the
    map (tests/test_discrete_reports.py), a points sweep certifies it point by point and a boxes sweep box by box,
    with the classes --box takes (tests/test_discrete_sweeps.py)."""
    from sweeps.spec import load_model_spec

    path = write(tmp_path, MAP)
    boxed = cli("certify", str(path), "--box", "a=0.8..1.2", "--classes", "linearization", "--no-store", "--json")
    assert boxed.exit_code == 0, boxed.output
    assert json.loads(boxed.stdout)["conditions"]["linearization"]["status"] == "certified"
    cert = tmp_path / "c.json"
    assert cli("certify", str(path), "--classes", "linearization", "--no-store", "--out", str(cert)).exit_code == 0
    assert cli("report", str(cert), "--html", str(tmp_path / "c.html")).exit_code == 0
    assert "the map" in (tmp_path / "c.html").read_text()
    specs = {mode: write(tmp_path, f'[sweep]\nmodel = "map.toml"\nmode = "{mode}"\nclasses = ["linearization"]\n'
                                   '[[sweep.axes]]\nname = "a"\nstart = 0.8\nstop = 1.2\nnum = 2\n', f"{mode}.toml")
             for mode in ("points", "boxes")}
    assert load_model_spec(specs["boxes"]).classes == ("linearization",)
    assert load_model_spec(specs["points"]).classes == ("linearization",)


def test_maximize_on_a_map_brackets_the_true_boundary(tmp_path: Path) -> None:
    """The spectral radius of [[a/2, 1/4], [-1/4, a/2]] is sqrt(a^2/4 + 1/16): 1 at a = sqrt(15)/2 = 1.936; each
    value is certified by the map's own test (read as a field, every a > 0 would be unstable)."""
    from lyapcheck.api import certify_extremum

    found = certify_extremum(write(tmp_path, MAP.replace("- y**3/8", "")), "a=0..4", classes=["linearization"],
                             steps=8)
    boundary = 15 ** 0.5 / 2
    assert found.proved is not None and found.failed is not None
    assert found.proved < boundary < found.failed.value and found.failed.value - found.proved <= Fraction(4, 2 ** 8)
    assert found.failed.outcome == "refuted"


def test_simulate_iterates_the_map(tmp_path: Path) -> None:
    import lyapcheck

    path = write(tmp_path, MAP)
    png = tmp_path / "map.png"
    done = cli("simulate", str(path), "--x0", "x=1,y=0", "--steps", "3", "--json", "--plot", str(png))
    assert done.exit_code == 0, done.output
    doc = json.loads(done.stdout)
    assert doc["mode"] == "iteration" and doc["time"] == "discrete" and doc["steps"] == 3
    assert png.read_bytes().startswith(b"\x89PNG")
    report = lyapcheck.simulate(model=path, x0={"x": 1, "y": 0}, steps=3)
    xs = report.series["x"].values[0]
    # x1 = (1/2, -1/4), x2 = (1/4 - 1/16, -1/8 - 1/8 + 1/512): the map's own iterates, not an ODE's
    assert xs[1].tolist() == [0.5, -0.25]
    assert np.allclose(xs[2], [0.1875, -0.25 + 1 / 512])
    assert "3 steps" in repr(report) or "4 steps" in repr(report)
    for flags in (["--t-end", "3"], ["--worst-case"], ["--scenario", "constant"]):
        refused_line(cli("simulate", str(path), *flags))


# -- the shipped examples -----------------------------------------------------------------------------
@pytest.mark.parametrize(("name", "status", "code", "verdict"), [("discrete-stable-map", "certified", 0, "certified"),
                                                                 ("discrete-unstable-map", "refuted", 1, "unstable")])
def test_the_examples_certify_and_verify(tmp_path: Path, name: str, status: str, code: int, verdict: str) -> None:
    out = tmp_path / f"{name}.json"
    done = cli("certify", str(EXAMPLES / f"{name}.toml"), "--no-store", "--json", "--out", str(out))
    assert done.exit_code == code, done.output
    doc = json.loads(done.stdout)
    assert doc["conditions"]["linearization"]["status"] == status
    assert doc["verdict"] == verdict
    # the stable map is not GAS: its region of attraction is a set of the linearization's V (issue 44, roa on maps)
    assert doc["conditions"]["roa"]["status"] == ("certified" if code == 0 else "not_certified")
    assert cli("verify", str(out)).exit_code == 0
