"""``barrier`` and ``reach_avoid`` over a ``--box`` of a loop with functions: one B (one V) for every
parameter value of the box, proved on the loop recast with the box's parameters as bounded constants.

The certified B is simulated on the true loop (numpy's sin and a clip for sat) at both ends of the
box; ``verify`` re-checks the certificates from the document alone and rejects one whose box, B or a
multiplier was changed; a set that names a box parameter is ``not_applicable``; a box at one of whose
corners the true loop enters the unsafe set gets a ``counterexample`` naming that corner.
"""

from __future__ import annotations

import copy
import json
from fractions import Fraction
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from lyapcheck import api
from tests.feature_matrix import BOXES_SPEC, FUNCTIONS
from tests.recast_loops import rk4
from tests.test_model_sweeps import arrays, run

#: two units coupled through a sine and a saturation: the feature matrix's loop with functions
COUPLED = FUNCTIONS
BOX = ["a=0.8..1.2"]

#: a pulse through a sine: from near (0, 2) x1 peaks at about 0.56 a, so the unsafe set x1 >= 1 is
#: reached for a above about 1.7 (simulated here), not at the box's centre 1.5 of [0.5, 2.5]
PULSE = """[model]
name = "a pulse through a sine"
states = ["x1", "x2"]
[parameters]
a = 1
[dynamics]
x1 = "-x1 + a*sin(x2)"
x2 = "-x2"
[domain]
x1 = [-3, 3]
x2 = [-3, 3]
[sets]
initial = ["x1**2 + (x2 - 2)**2 <= 0.01"]
unsafe = ["x1 >= 1"]
goal = ["x1**2 + x2**2 <= 0.25"]
"""


@pytest.fixture(scope="module")
def boxed(tmp_path_factory: pytest.TempPathFactory) -> api.CertifyResult:
    path = tmp_path_factory.mktemp("box-safety") / "coupled.toml"
    path.write_text(COUPLED)
    return api.certify(model=path, box=BOX, classes="barrier,reach_avoid")


def b_of_states(cert: dict[str, Any], X: np.ndarray) -> np.ndarray:
    """B of a certificate whose B uses the states alone (the first variables), at the states X."""
    shift = [float(Fraction(cert["shift"].get(name, "0"))) for name in cert["variables"][:X.shape[1]]]
    total = np.zeros(len(X))
    for coefficient, exponents in cert["B"]["terms"]:
        assert not any(exponents[X.shape[1]:]), "B uses more than the states"
        term = np.full(len(X), float(Fraction(coefficient)))
        for k, e in enumerate(exponents[:X.shape[1]]):
            term = term * (X[:, k] - shift[k]) ** e
        total += term
    return total


def failing(doc: dict[str, Any]) -> dict[str, str]:
    """The rows ``verify`` rejects: check -> message."""
    return {c.check: c.message for c in api.verify(doc).checks if not c.ok}


def test_one_barrier_and_one_reach_avoid_function_serve_every_value_of_the_box(boxed: api.CertifyResult) -> None:
    doc = boxed.document
    assert doc["box"] == {"a": ["4/5", "6/5"]} and doc["overrides"] == {"a": "1"}  # read at the box's centre
    for name in ("barrier", "reach_avoid"):
        c = boxed.conditions[name]
        assert c.status == "certified", c.summary
        assert c.summary.startswith("for every a in [0.8, 1.2]: ")
        assert "a" in c.certificate["variables"]  # the parameter is a coordinate of the identities
    # B uses none of the parameters: along the true loop at both ends of the box it stays <= 0 from
    # the initial set (B <= 0 there), so below 1 (the unsafe set's B >= 1)
    cert = boxed.conditions["barrier"].certificate
    rng = np.random.default_rng(0)
    angle = rng.uniform(0, 2 * np.pi, 100)
    radius = 0.5 * np.sqrt(rng.uniform(0, 1, 100))
    starts = np.column_stack([2 + radius * np.cos(angle), radius * np.sin(angle)])
    for a in (0.8, 1.2):
        def field(x: np.ndarray, a: float = a) -> np.ndarray:
            return np.column_stack([-a * x[:, 0] + np.sin(x[:, 1]) / 2, -x[:, 1] + np.clip(x[:, 0], -1, 1) / 2])

        x = starts.copy()
        for _ in range(400):
            assert b_of_states(cert, x).max() <= 1e-9
            x = rk4(field, x, 0.02)


def test_verify_rechecks_both_box_certificates_from_the_document_and_exits_0(boxed: api.CertifyResult,
                                                                              tmp_path: Path) -> None:
    from tests.test_model_sweeps import cli

    rows = {c.check: c for c in api.verify(boxed.document).checks}
    for name in ("barrier", "reach_avoid"):
        assert rows[name].ok and "for every value of the box" in rows[name].message, rows[name].message
    path = tmp_path / "cert.json"
    path.write_text(json.dumps(boxed.document))
    assert cli("verify", str(path)).exit_code == 0


def test_a_changed_box_b_or_multiplier_is_rejected(boxed: api.CertifyResult) -> None:
    # a wider box around the same centre, its claims re-worded to match: the identities no longer hold
    wider = copy.deepcopy(boxed.document)
    wider["box"] = {"a": ["3/5", "7/5"]}
    for name in ("barrier", "reach_avoid"):
        c = wider["conditions"][name]
        c["summary"] = c["summary"].replace("a in [0.8, 1.2]", "a in [0.6, 1.4]")
    rejected = failing(wider)
    assert set(rejected) >= {"barrier", "reach_avoid"}
    assert all("begins" not in rejected[name] for name in ("barrier", "reach_avoid"))  # (not its wording)
    # B changed in one coefficient
    changed = copy.deepcopy(boxed.document)
    terms = changed["conditions"]["barrier"]["certificate"]["B"]["terms"]
    terms[0][0] = str(Fraction(terms[0][0]) * Fraction(101, 100))
    assert "barrier" in failing(changed)
    # one multiplier of the decrease identity changed (a Gram entry)
    changed = copy.deepcopy(boxed.document)
    taus = changed["conditions"]["barrier"]["certificate"]["decrease"]["taus"]
    gram = taus[sorted(taus)[-1]]["Q"]
    gram[0][0] = str(Fraction(gram[0][0]) + 1)
    assert "barrier" in failing(changed)
    proofs = changed["conditions"]["reach_avoid"]["certificate"]["proofs"]
    sigma = proofs["goal0"]["sigma"]["Q"]
    sigma[0][0] = str(Fraction(sigma[0][0]) + 1)
    assert "reach_avoid" in failing(changed)


def test_a_set_naming_a_box_parameter_is_not_applicable(tmp_path: Path) -> None:
    path = tmp_path / "pulse.toml"
    path.write_text(PULSE.replace('unsafe = ["x1 >= 1"]', 'unsafe = ["x1 >= a"]'))
    result = api.certify(model=path, box=["a=0.5..2.5"], classes="barrier,reach_avoid")
    for name in ("barrier", "reach_avoid"):
        c = result.conditions[name]
        assert c.status == "not_applicable"
        assert c.summary == ("over a box the sets may not depend on a parameter of the box (they are read at "
                             "the model's values)")


def test_a_box_whose_corner_reaches_the_unsafe_set_gets_a_counterexample_there(tmp_path: Path) -> None:
    path = tmp_path / "pulse.toml"
    path.write_text(PULSE)
    result = api.certify(model=path, box=["a=0.5..2.5"], classes="barrier,reach_avoid")
    for name in ("barrier", "reach_avoid"):
        c = result.conditions[name]
        assert c.status == "counterexample", c.summary
        assert c.summary.startswith("at a corner of the box (a = 2.5), so not for every value of the box: ")
        assert c.refutation["parameters"] == {"a": "2.5"}
        # the trajectory is the true loop's at a = 2.5: replayed from its start, it enters x1 >= 1
        x = np.array([c.refutation["start"]], dtype=float)
        peak = x[0, 0]
        for _ in range(250):  # 5 s, one RK4 step of 0.02 s at a time
            x = rk4(lambda z: np.column_stack([-z[:, 0] + 2.5 * np.sin(z[:, 1]), -z[:, 1]]), x, 0.02)
            peak = max(peak, x[0, 0])
        assert peak >= 1
    assert result.verdict != "certified"


def test_a_tiny_boxes_sweep_of_a_loop_with_functions_certifies_a_barrier_per_box(tmp_path: Path) -> None:
    from sweeps.schema import BOX_STATUS_CODES, STATUS_CODES
    from sweeps.spec import load_model_spec

    (tmp_path / "m.toml").write_text(COUPLED)
    spec = tmp_path / "spec.toml"
    spec.write_text(BOXES_SPEC.format(model="m.toml", classes='["barrier"]', candidate=""))
    out = tmp_path / "out.zarr"
    run(spec, out)
    data = arrays(out)
    assert list(data["status"]) == [BOX_STATUS_CODES["certified"]], list(data["note"])
    assert list(data["status_barrier"]) == [STATUS_CODES["certified"]]
    document = json.loads(str(data["certificate"][0]))
    assert document["box"] == {"a": [str(Fraction(data["lo_a"][0])), str(Fraction(data["hi_a"][0]))]}
    assert document["conditions"]["barrier"]["summary"].startswith("for every a in ")
    assert api.verify(document).valid
    # reach_avoid is taken by a boxes sweep of a loop with functions too (with the goal in its sets)
    spec.write_text(spec.read_text().replace('["barrier"]', '["reach_avoid", "barrier"]'))
    assert load_model_spec(spec).classes == ("barrier", "reach_avoid")
