"""``sos_bound`` on loops with functions: a global ultimate bound for every disturbance signal, by the
class's one formulation (:mod:`lyapcheck.models.classes.bounds`) with the recasting's relations.

The bounds are checked against what is true of the loop, computed here without lyapcheck: the ILOS
loop under a constant disturbance settles where its integral state is ``d Delta / (kappa
sqrt(U^2 - d^2))``, so no bound below that may be certified, and a bang-bang disturbance simulated
with numpy's own functions never leaves the bounds. Every certificate re-checks exactly and a
changed one does not; one of the relational route's older format is refused in one line.
"""

from __future__ import annotations

import copy
import math
import subprocess
import sys
from fractions import Fraction
from pathlib import Path

import numpy as np
import pytest

from lyapcheck import api
from lyapcheck.models.classes import bounds
from lyapcheck.models.classes.recast_classes import check_denominator_proofs, check_root_proofs
from lyapcheck.models.language.modelfile import load_any_model
from lyapcheck.models.engines.recast_sos import ConditionCertificate
from lyapcheck.sos.certificates import GramPoly
from lyapcheck.sos.polynomials import Ring
from tests.recast_loops import rk4

EXAMPLES = Path(__file__).resolve().parents[1] / "examples" / "models"
ILOS = EXAMPLES / "recast-ilos-course-disturbed.toml"
PENDULUM = EXAMPLES / "recast-pendulum-torque.toml"


@pytest.fixture(scope="module")
def ilos() -> api.ModelCertification:
    return api.certify(model=ILOS, classes="sos_bound", time_limit_s=900)  # (the limit a safety net only)


def test_ilos_under_a_bounded_disturbance_gets_a_bound_on_both_states_that_verifies(ilos) -> None:
    bound = ilos.conditions["sos_bound"]
    assert bound.status == "certified" and bound.disturbances == "all"
    assert ilos.verdict == "certified"  # the claim covers every disturbance signal
    assert bound.summary.startswith("for every disturbance within its bounds and every start: limsup |y| <= ")
    assert set(bound.numbers["bounds"]) == {"y", "yi"}
    assert api.verify(ilos).valid
    # what is true of the loop: a constant d = 0.05 holds yi at d Delta / (kappa sqrt(U^2 - d^2))
    U, Delta, kappa, b = 1.0, 2.0, 0.5, 0.05
    assert bound.numbers["bounds"]["yi"] >= b * Delta / (kappa * math.sqrt(U * U - b * b))
    # and the bound is a bound: a bang-bang d(t) simulated here stays inside it once settled
    def field(x: np.ndarray, d: np.ndarray) -> np.ndarray:
        r = np.sqrt(Delta ** 2 + (x[:, 0] + kappa * x[:, 1]) ** 2)
        return np.column_stack([-U * (x[:, 0] + kappa * x[:, 1]) / r + d, U * x[:, 0] / r])

    rng = np.random.default_rng(3)
    x = rng.uniform(-20, 20, (40, 2))
    late = np.zeros(2)
    for k in range(30000):
        d = b * np.sign(x[:, 0] + 0.5 * x[:, 1] * (k % 2000 < 1000) + 1e-12)
        x = rk4(lambda z: field(z, d), x, 0.02)
        if k * 0.02 > 500:
            late = np.maximum(late, np.abs(x).max(axis=0))
    assert late[0] <= bound.numbers["bounds"]["y"] and late[1] <= bound.numbers["bounds"]["yi"]


def test_the_certificate_says_what_v_and_its_variables_are(ilos) -> None:
    cert = ilos.conditions["sos_bound"].certificate
    assert cert["kind"] == bounds.KIND
    assert cert["variables"] == ["y", "yi", "d", "r1"]  # the states, the disturbance, the auxiliary
    assert cert["auxiliaries"] == {"r1": "sqrt(y**2 + y*yi + 1/4*yi**2 + 4)"}
    assert cert["disturbances"] == {"d": "1/20"}
    for item in cert["outputs"].values():
        assert "d" not in item["v_variables"] and set(item["v_variables"]) <= set(cert["variables"])
        assert Fraction(item["bound"]) ** 2 >= Fraction(item["B"])
        gram = GramPoly.from_json(item["gram_V"], len(cert["variables"]))
        assert gram.positive_definite()  # V = z^T Q z + v0, Q > 0: radially unbounded in the states
        assert all(cert["variables"][i] in item["v_variables"] for m in gram.basis for i, e in enumerate(m) if e)


def test_each_identity_holds_on_the_relations_and_fails_without_the_disturbance_bound(ilos) -> None:
    """The identities themselves, re-checked here; with the relation |d| <= b dropped (a weaker set
    of facts), the dissipation identity no longer holds: the bound uses it, as it must."""
    model = load_any_model(ILOS)
    made = bounds.bound_loop(model)
    assert not isinstance(made, str)
    roots = ilos.conditions["sos_bound"].certificate["recasting"]["roots"]
    loop, why = check_root_proofs(made.loop, roots)
    assert loop is not None, why
    bl = made.with_loop(loop)
    ring = bl.ring
    item = ilos.conditions["sos_bound"].certificate["outputs"]["y"]
    ok, why, N = check_denominator_proofs(loop, item["v_variables"], item["denominators"])
    assert ok, why
    field = bl.field(item["v_variables"], N)
    y = bl.output(model.outputs["y"], Ring(model.states))
    gram = GramPoly.from_json(item["gram_V"], ring.nvars)
    v0, lam, B = (Fraction(item[k]) for k in ("V_constant", "lam", "B"))
    dissipation, output = (ConditionCertificate.from_json(ring, item[k], len(loop.relations))
                           for k in ("dissipation", "output"))
    assert bounds.check_on_relations(field, gram, v0, lam, B, y, dissipation, output)[0]
    index = next(i for i, r in enumerate(loop.relations) if r.why == "|d| <= 1/20")
    assert index in dissipation.taus  # the disturbance's bound is used
    dissipation.taus.pop(index)
    ok, why = bounds.check_on_relations(field, gram, v0, lam, B, y, dissipation, output)
    assert not ok and why.startswith("dissipation: ")


def test_a_certificate_of_the_older_relational_format_is_refused_in_one_line(ilos) -> None:
    doc = copy.deepcopy(ilos.document)
    doc["conditions"]["sos_bound"]["certificate"]["kind"] = "recast_bound"
    report = api.verify(doc)
    assert not report.valid
    refused = [c.message for c in report.checks if not c.ok and c.check == "sos_bound"]
    assert refused == [f"sos_bound: {bounds.OLD_FORMAT}"]  # (and the verdict and exit code follow from it)
    assert "run lyapcheck certify again" in refused[0] and "\n" not in refused[0]


@pytest.mark.parametrize("change", ["B", "bound", "lam", "V", "gram_V", "lambda", "summary", "coverage",
                                    "v_variables"])
def test_a_changed_bound_certificate_does_not_verify(ilos, change: str) -> None:
    doc = copy.deepcopy(ilos.document)
    c = doc["conditions"]["sos_bound"]
    item = c["certificate"]["outputs"]["y"]
    if change == "B":
        item["B"] = str(Fraction(item["B"]) / 2)
    elif change == "bound":
        item["bound"] = str(Fraction(item["bound"]) / 2)
        c["bounds"]["y"] = float(Fraction(item["bound"]))
    elif change == "lam":
        item["lam"] = str(Fraction(item["lam"]) * 2)
    elif change == "V":
        item["V"]["terms"][0][0] = str(Fraction(item["V"]["terms"][0][0]) * 2)
    elif change == "gram_V":  # the Gram matrix and V changed alike: then the identities fail
        item["gram_V"]["Q"][0][0] = str(Fraction(item["gram_V"]["Q"][0][0]) * 2)
    elif change == "lambda":  # a relation's free multiplier in the dissipation identity
        lambdas = item["dissipation"]["lambdas"]
        assert lambdas, "the dissipation identity uses the square root's relation r^2 = q"
        term = next(iter(lambdas.values()))["terms"][0]
        term[0] = str(Fraction(term[0]) + 1)
    elif change == "summary":
        c["summary"] = c["summary"].replace("limsup |y| <= ", "limsup |y| <= 0.0")
    elif change == "coverage":
        c["disturbances"] = "zero"
    else:
        item["v_variables"] = item["v_variables"] + ["d"]
    assert not api.verify(doc).valid


def test_the_pendulum_speed_is_bounded_on_the_cylinder_and_the_angle_is_not_sought(tmp_path: Path) -> None:
    result = api.certify(model=PENDULUM, classes="sos_bound")
    bound = result.conditions["sos_bound"]
    assert bound.status == "certified" and set(bound.numbers["bounds"]) == {"speed"}
    assert api.verify(result).valid
    assert bound.certificate["angles"] == ["theta"]
    limit = bound.numbers["bounds"]["speed"]
    rng = np.random.default_rng(5)
    x = np.column_stack([rng.uniform(-10, 10, 60), rng.uniform(-10, 10, 60)])
    late = 0.0
    for k in range(15000):
        d = 0.2 * np.sign(x[:, 1] + 1e-12)  # pumping energy in
        x = rk4(lambda z: np.column_stack([z[:, 1], -np.sin(z[:, 0]) - z[:, 1] + d]), x, 0.02)
        if k * 0.02 > 200:
            late = max(late, float(np.abs(x[:, 1]).max()))
    assert late <= limit
    # the angle itself as an output: not sought (a start at 2 pi k stays there), said so
    text = PENDULUM.read_text().replace('speed = "omega"', 'speed = "omega"\nangle = "theta"')
    path = tmp_path / "angle.toml"
    path.write_text(text)
    both = api.certify(model=path, classes="sos_bound").conditions["sos_bound"]
    assert set(both.numbers["bounds"]) == {"speed"}
    assert "no bound for angle" in both.summary


def test_without_disturbances_sos_bound_is_not_applicable_and_not_in_the_default(tmp_path: Path) -> None:
    plain = EXAMPLES / "recast-ilos-course.toml"
    result = api.certify(model=plain, classes="sos_bound")
    assert result.conditions["sos_bound"].status == "not_applicable"
    assert "sos_bound" not in api.certify(model=plain, classes="linearization,quadratic").conditions
    default = api.certify(model=ILOS)
    assert "sos_bound" in default.conditions and default.conditions["quadratic"].disturbances == "zero"


@pytest.mark.parametrize(("output", "fragment"), [('"sin(y)"', "[outputs] e"), ('"y/yi"', "[outputs] e")])
def test_an_output_with_a_function_or_a_state_denominator_is_refused_in_one_line(tmp_path: Path, output: str,
                                                                                 fragment: str) -> None:
    path = tmp_path / "bad.toml"
    path.write_text(ILOS.read_text() + f"\n[outputs]\ne = {output}\n")
    run = subprocess.run([sys.executable, "-m", "lyapcheck", "certify", "--model", str(path)], capture_output=True,
                         text=True)
    assert run.returncode == 2 and fragment in run.stderr and "\n" not in run.stderr.strip(), run.stderr
