"""The classes on loops with functions: what is certified is true, what is false is never certified,
every certificate re-checks exactly, and a changed certificate does not.

Each claim is also checked against the true loop by simulation written here with numpy's own
functions (not lyapcheck's recast code): a certified region's samples converge, modulo 2 pi in an
angle.
"""

from __future__ import annotations

import copy
import json
import subprocess
import sys
from fractions import Fraction
from pathlib import Path

import numpy as np
import pytest

from lyapcheck import api
from lyapcheck.models.classes import lyapunov, lyapunov_relations, recast_classes as rc
from lyapcheck.models.classes import regions
from lyapcheck.models.language.modelfile import parse_any_model
from lyapcheck.models.engines.recast_sos import ConditionCertificate, check_condition, poly_from_json
from lyapcheck.models.engines.search import Budget, Search
from lyapcheck.sos.certificates import GramPoly
from tests.recast_loops import COUPLED, ILOS, LOSSLESS, PENDULUM, SPRING, UNSTABLE, pendulum_field, rk4



def write(tmp_path: Path, name: str, text: str) -> Path:
    path = tmp_path / f"{name}.toml"
    path.write_text(text)
    return path


def v_of(cert: dict, X: np.ndarray) -> np.ndarray:
    """V of a recast certificate at the states X, from its variables, auxiliaries and shift alone
    (each definition here is sin(theta) or cos(theta), evaluated with numpy)."""
    funcs = {"sin(theta)": lambda t: np.sin(t), "cos(theta)": lambda t: np.cos(t)}
    columns = {"theta": X[:, 0], "omega": X[:, 1]}
    for name, definition in cert["auxiliaries"].items():
        columns[name] = funcs[definition](X[:, 0])
    total = np.zeros(len(X))
    for coefficient, exponents in cert["V"]["terms"]:
        term = np.full(len(X), float(Fraction(coefficient)))
        for name, e in zip(cert["variables"], exponents):
            if e:
                term = term * (columns[name] - float(Fraction(cert["shift"].get(name, "0")))) ** e
        total += term
    return total


def test_ilos_course_form_is_globally_asymptotically_stable_exactly(tmp_path: Path) -> None:
    result = api.certify(model=write(tmp_path, "ilos", ILOS))
    gas = result.conditions["sos_gas"]
    assert gas.status == "certified" and gas.property == "GAS"
    cert = gas.certificate
    assert cert["variables"] == ["y", "yi", "r1"]
    assert cert["auxiliaries"] == {"r1": "sqrt(y**2 + y*yi + 1/4*yi**2 + 4)"}
    assert "r1" in cert["recasting"]["roots"]  # sqrt's argument proved >= c^2 > 0: the denominator is positive
    assert api.verify(result).valid
    # a changed coefficient of V, or a relation the text does not give, fails the re-check
    doc = copy.deepcopy(result.document)
    term = doc["conditions"]["sos_gas"]["certificate"]["V"]["terms"][0]
    term[0] = str(Fraction(term[0]) * Fraction(101, 100))
    assert not api.verify(doc).valid
    doc = copy.deepcopy(result.document)
    doc["recast"]["relations"][1]["poly"] = "r1 - 5"
    checks = api.verify(doc)
    assert not checks.valid and any(c.check == "recasting" and not c.ok for c in checks.checks)


def test_pendulum_region_holds_on_the_true_loop_and_global_stability_is_refuted(tmp_path: Path) -> None:
    result = api.certify(model=write(tmp_path, "pendulum", PENDULUM))
    assert result.conditions["linearization"].status == "certified"
    gas = result.conditions["sos_gas"]
    assert gas.status == "refuted" and gas.refutation["point"] == {"theta": "1*pi"}
    roa = result.conditions["roa"]
    # proved by ball arithmetic on the true field: a set in (theta, omega) itself, not modulo 2 pi
    assert roa.status == "certified" and roa.certificate["kind"] == "interval"
    assert "converges to the equilibrium itself" in roa.summary and "modulo" not in roa.summary
    assert api.verify(result).valid
    cert = roa.certificate
    level = float(Fraction(cert["level"]))
    lo = [float(Fraction(cert["box"][s][0])) for s in ("theta", "omega")]
    hi = [float(Fraction(cert["box"][s][1])) for s in ("theta", "omega")]
    rng = np.random.default_rng(3)
    X = np.column_stack([rng.uniform(-np.pi, np.pi, 3000), rng.uniform(-4, 4, 3000)])
    member = (v_of(cert, X) <= level) & np.all((X >= lo) & (X <= hi), axis=1)
    inside = X[member]
    assert len(inside) > 300
    end = rk4(pendulum_field, inside, 40.0)
    assert np.all(np.hypot(end[:, 0], end[:, 1]) < 1e-2)  # to (0, 0), no wrapping
    # the set covers more of the box than the energy level set {1 - cos(theta) + omega^2/2 < 2}
    energy = 1 - np.cos(X[:, 0]) + X[:, 1] ** 2 / 2 < 2
    assert np.mean(member) > np.mean(energy)


def test_pendulum_region_on_the_recasting_relations_is_modulo_2_pi(tmp_path: Path) -> None:
    """The route taken where ball arithmetic does not apply (more than 3 states): V over (sin, cos - 1,
    omega), proved exactly on the recasting's relations, and its claim modulo 2 pi."""
    from lyapcheck.models.classes.recast_regions import comparison_box, run_roa

    model = parse_any_model(PENDULUM, "pendulum.toml")
    loop = rc.base_loop(model.system)
    roa = run_roa(loop, rc.linearization(loop), Budget(60.0, "test"), comparison_box(model, loop), interval=False)
    assert roa.status == "certified" and "modulo 2 pi in theta" in roa.summary
    cert = roa.certificate
    assert cert["kind"] == "recast"
    level = float(Fraction(cert["level"]))
    rng = np.random.default_rng(3)
    X = np.column_stack([rng.uniform(-np.pi, np.pi, 3000), rng.uniform(-4, 4, 3000)])
    inside = X[v_of(cert, X) <= level]
    assert len(inside) > 300
    end = rk4(pendulum_field, inside, 40.0)
    wrapped = np.angle(np.exp(1j * end[:, 0]))
    assert np.all(np.hypot(wrapped, end[:, 1]) < 1e-2)


def test_no_asymptotic_claim_on_a_lossless_or_an_unstable_loop(tmp_path: Path) -> None:
    for name, text in (("lossless", LOSSLESS), ("unstable", UNSTABLE)):
        result = api.certify(model=write(tmp_path, name, text))
        # the lossless loop: nothing proved; the unstable one: its linearization refuted, a negative answer
        assert result.verdict == {"lossless": "not_certified", "unstable": "unstable"}[name], name
        assert all(c.status != "certified" for c in result.conditions.values()), name
    unstable = api.certify(model=write(tmp_path, "unstable", UNSTABLE), classes="linearization")
    assert unstable.conditions["linearization"].status == "refuted"


def test_the_energy_of_a_damped_pendulum_is_not_a_strict_lyapunov_function(tmp_path: Path) -> None:
    result = api.certify(model=write(tmp_path, "pendulum", PENDULUM), classes="candidate",
                         candidate="1 - cos(theta) + omega**2/2")
    cand = result.conditions["candidate"]
    assert cand.status == "not_certified" and "LaSalle" in cand.summary
    assert api.verify(result).valid


def test_dropped_relations_only_weaken() -> None:
    """Without the recasting's inequalities nothing ties sin x1 to x1 near 0 (x1 is no angle here:
    it enters the field itself too): the linearization's V then proves no region (sound: nothing
    false appears), with them it does."""
    model = parse_any_model(SPRING, "spring.toml")
    loop = rc.base_loop(model.system)
    assert not loop.angles
    V0 = rc.quadratic_candidate(loop, rc.jacobian(loop))
    assert V0 is not None
    assert not isinstance(regions.certify_region(loop, V0, Search(loop.ring, Budget(30, "test")), "full"), str)
    weak = rc.Loop(loop.system, [r for r in loop.relations if r.kind == "eq"])
    assert isinstance(regions.certify_region(weak, V0, Search(loop.ring, Budget(30, "test")), "weak"), str)


def test_the_exact_check_refuses_a_free_multiplier_on_an_inequality() -> None:
    model = parse_any_model(SPRING, "spring.toml")
    loop = rc.base_loop(model.system)
    ring = loop.ring
    k = next(i for i, r in enumerate(loop.relations) if r.kind == "ge")
    g = loop.relations[k].poly
    zero = GramPoly((tuple([0] * ring.nvars),), ((Fraction(0),),))
    # g >= 0 'proved' by a free multiplier 1 on g: the identity holds, the kind is wrong
    cert = ConditionCertificate({k: ring.constant(1)}, {}, zero)
    ok, why = check_condition(ring, g, loop.relations, cert)
    assert not ok and "inequality" in why
    # -g >= 0 is false; no multiplier of the right kind makes the identity hold with these
    cert = ConditionCertificate({}, {k: GramPoly((tuple([0] * ring.nvars),), ((Fraction(1),),))}, zero)
    assert check_condition(ring, g, loop.relations, cert)[0]
    assert not check_condition(ring, -g, loop.relations, cert)[0]


@pytest.mark.parametrize("dynamics, words", [
    ('x1 = "-sqrt(x1)"', ["sqrt(x1)", "non-negative"]),
    ('x1 = "-x1 + foo(x1)"', ["unknown function 'foo'"]),
    ('x1 = "-x1 + sat(x1, 0)"', ["sat", "> 0"]),
])
def test_bad_input_is_one_line_with_exit_2(tmp_path: Path, dynamics: str, words: list[str]) -> None:
    path = write(tmp_path, "bad", f'[model]\nname = "bad"\nstates = ["x1"]\n[dynamics]\n{dynamics}\n')
    run = subprocess.run([sys.executable, "-m", "lyapcheck", "certify", str(path), "--out", str(tmp_path / "c.json")],
                         capture_output=True, text=True)
    assert run.returncode == 2, run.stderr
    line = run.stderr.strip()
    assert "\n" not in line and str(path) in line and all(w in line for w in words), line
    assert not (tmp_path / "c.json").exists()


def test_candidate_with_a_function_of_no_flow_is_refused(tmp_path: Path) -> None:
    path = write(tmp_path, "pendulum", PENDULUM)
    run = subprocess.run([sys.executable, "-m", "lyapcheck", "certify", str(path), "--classes", "candidate",
                          "--candidate", "abs(theta) + omega**2"], capture_output=True, text=True)
    assert run.returncode == 2 and "--candidate" in run.stderr and "\n" not in run.stderr.strip()


def test_certificate_file_round_trip_through_the_command_line(tmp_path: Path) -> None:
    path = write(tmp_path, "ilos", ILOS)
    out = tmp_path / "ilos.json"
    run = subprocess.run([sys.executable, "-m", "lyapcheck", "certify", str(path), "--out", str(out)],
                         capture_output=True, text=True)
    assert run.returncode == 0, run.stderr
    doc = json.loads(out.read_text())
    assert doc["recast"]["auxiliaries"] == {"r1": "sqrt(y**2 + y*yi + 1/4*yi**2 + 4)"}
    V = poly_from_json(parse_any_model(ILOS, "x").system.ring, doc["conditions"]["sos_gas"]["certificate"]["V"], "V")
    assert not V.is_zero()
    check = subprocess.run([sys.executable, "-m", "lyapcheck", "verify", str(out)], capture_output=True, text=True)
    assert check.returncode == 0 and "certificate verified" in check.stdout


def test_report_writes_the_page_of_a_loop_with_functions(tmp_path: Path) -> None:
    path = write(tmp_path, "ilos", ILOS)
    html = tmp_path / "r.html"
    out = tmp_path / "c.json"
    run = subprocess.run([sys.executable, "-m", "lyapcheck", "certify", str(path), "--report", str(html), "--out",
                          str(out)], capture_output=True, text=True)
    assert run.returncode == 0, run.stderr
    assert out.exists() and "The recasting the certificates are proved on" in html.read_text("utf-8")
    again = tmp_path / "again.html"
    run = subprocess.run([sys.executable, "-m", "lyapcheck", "report", str(out), "--html", str(again)],
                         capture_output=True, text=True)
    assert run.returncode == 0, run.stderr
    page = again.read_text("utf-8")
    assert "<code>sqrt(y**2 + y*yi + 1/4*yi**2 + 4)</code>" in page and "every certified claim re-checks" in page


def test_a_certified_region_is_simulated_on_the_true_loop(tmp_path: Path) -> None:
    result = api.certify(model=write(tmp_path, "pendulum", PENDULUM), classes="roa")
    roa = result.conditions["roa"]
    assert roa.status == "certified"
    assert roa.numbers["simulated_starts"] == 1600 and 0.5 < roa.numbers["roa_share"] <= 1
    assert not roa.numbers.get("soundness_violation")



def test_quadratic_proves_an_exponential_bound_where_the_field_has_no_denominator(tmp_path: Path) -> None:
    result = api.certify(model=write(tmp_path, "coupled", COUPLED), classes="quadratic")
    q = result.conditions["quadratic"]
    assert q.status == "certified" and q.property == "GES"
    assert q.certificate["kind"] == lyapunov.RELATIONS_KIND
    ges = {k: Fraction(q.certificate[k]) for k in ("c1", "c2", "k")}
    ges["rate"] = Fraction(q.certificate["mu"]) / 2
    assert 0 < ges["c1"] <= ges["c2"] and ges["k"] ** 2 >= ges["c2"] / ges["c1"] and ges["rate"] > 0
    assert q.summary.startswith("GES: |x(t)| <= ")
    assert api.verify(result).valid
    # the bound holds on the true loop, simulated here with numpy's functions
    rng = np.random.default_rng(5)
    X0 = rng.uniform(-5, 5, (200, 2))
    field = lambda X: np.column_stack([-X[:, 0] + np.sin(X[:, 1]) / 2, -X[:, 1] + np.tanh(X[:, 0]) / 2])
    for t in (1.0, 3.0):
        end = rk4(field, X0, t, step=0.01)
        bound = float(ges["k"]) * np.linalg.norm(X0, axis=1) * np.exp(-float(ges["rate"]) * t)
        assert np.all(np.linalg.norm(end, axis=1) <= bound)
    # a smaller k, a larger c1 or a larger rate than proved does not verify
    for key, factor in (("k", Fraction(1, 2)), ("c1", Fraction(3)), ("mu", Fraction(2))):
        doc = copy.deepcopy(result.document)
        stored = doc["conditions"]["quadratic"]["certificate"]
        stored[key] = str(Fraction(stored[key]) * factor)
        assert not api.verify(doc).valid, key


def test_quadratic_with_a_denominator_is_asymptotic_only_and_an_angle_is_not_quadratic(tmp_path: Path) -> None:
    ilos = api.certify(model=write(tmp_path, "ilos", ILOS), classes="quadratic").conditions["quadratic"]
    assert ilos.status == "certified" and ilos.property == "GAS" and "k" not in ilos.certificate
    model = parse_any_model(PENDULUM, "p.toml")
    loop = rc.base_loop(model.system)
    assert lyapunov_relations.run_relations(loop, Budget(10.0, "test"), "quadratic", (2,)).status == "not_applicable"


DISTURBED = """
[model]
name = "pendulum with a torque disturbance"
states = ["theta", "omega"]
[disturbances]
w = 0.2
[dynamics]
theta = "omega"
omega = "-sin(theta) - omega + w*cos(theta)"
[domain]
theta = [-3.14159, 3.14159]
omega = [-4, 4]
"""


def test_a_disturbed_loop_with_functions_is_certified_with_its_disturbances_at_0(tmp_path: Path) -> None:
    result = api.certify(model=write(tmp_path, "disturbed", DISTURBED), classes="linearization,sos_gas,roa")
    assert result.verdict == "certified_nominal"  # no claim covers the disturbance
    assert result.document["disturbances"] == {"w": "1/5"}
    for name, c in result.conditions.items():
        assert c.disturbances == "zero", name
        if c.status in ("certified", "refuted"):
            assert c.summary.startswith("(d = 0) "), name
    assert result.conditions["roa"].status == "certified"
    assert api.verify(result).valid
    # a claim said to cover the disturbance, or a sentence without "(d = 0)", does not verify
    doc = copy.deepcopy(result.document)
    doc["conditions"]["roa"]["disturbances"] = "all"
    assert not api.verify(doc).valid
    doc = copy.deepcopy(result.document)
    doc["conditions"]["roa"]["summary"] = doc["conditions"]["roa"]["summary"].removeprefix("(d = 0) ")
    assert not api.verify(doc).valid
    # the same file without its disturbance: the plain claims, and the same figures
    plain = api.certify(model=write(tmp_path, "plain", DISTURBED.replace("[disturbances]\nw = 0.2\n", "")
                                    .replace(" + w*cos(theta)", "")), classes="roa")
    assert plain.verdict == "certified" and plain.conditions["roa"].disturbances is None
    assert plain.conditions["roa"].certificate["V"] == result.conditions["roa"].certificate["V"]


@pytest.mark.parametrize(("extra", "fragment"), [("w = -0.2", "must be >= 0"), ("sin = 0.2", "'sin'")])
def test_bad_disturbances_of_a_loop_with_functions_are_refused_in_one_line(tmp_path: Path, extra: str,
                                                                          fragment: str) -> None:
    text = DISTURBED.replace("w = 0.2", extra)
    path = write(tmp_path, "bad", text)
    run = subprocess.run([sys.executable, "-m", "lyapcheck", "certify", str(path)], capture_output=True, text=True)
    assert run.returncode == 2 and fragment in run.stderr and "\n" not in run.stderr.strip()


VANISHING = """
[model]
name = "pendulum whose damping is disturbed"
states = ["theta", "omega"]
[disturbances]
w = 0.3
[dynamics]
theta = "omega"
omega = "-sin(theta) - omega + w*omega*cos(theta)"
[domain]
theta = [-3.14159, 3.14159]
omega = [-4, 4]
"""


def test_a_region_is_proved_for_every_disturbance_value_where_they_vanish_at_the_equilibrium(tmp_path: Path) -> None:
    result = api.certify(model=write(tmp_path, "vanishing", VANISHING), classes="linearization,roa")
    roa = result.conditions["roa"]
    assert roa.status == "certified" and roa.disturbances == "all"
    assert roa.summary.startswith("for every disturbance signal within its bounds: region of attraction")
    assert roa.certificate["disturbances"] == {"w": ["-3/10", "3/10"]}
    assert result.verdict == "certified"  # a claim covers the disturbance
    assert api.verify(result).valid
    # outside lyapcheck: starts in the set converge under a constant and a time-varying w within 0.3
    cert = roa.certificate
    rng = np.random.default_rng(4)
    X = np.column_stack([rng.uniform(-np.pi, np.pi, 3000), rng.uniform(-4, 4, 3000)])
    V = np.zeros(len(X))
    for coefficient, (e1, e2, *_) in cert["V"]["terms"]:
        V += float(Fraction(coefficient)) * X[:, 0] ** e1 * X[:, 1] ** e2
    lo = [float(Fraction(cert["box"][s][0])) for s in ("theta", "omega")]
    hi = [float(Fraction(cert["box"][s][1])) for s in ("theta", "omega")]
    inside = X[(V <= float(Fraction(cert["level"]))) & np.all((X >= lo) & (X <= hi), axis=1)]
    assert len(inside) > 100
    for w in (lambda t: 0.3, lambda t: -0.3, lambda t: 0.3 * np.sin(3 * t)):
        Y, t, h = inside.copy(), 0.0, 0.01
        f = lambda Y, t: np.column_stack([Y[:, 1], -np.sin(Y[:, 0]) - Y[:, 1] + w(t) * Y[:, 1] * np.cos(Y[:, 0])])
        for _ in range(6000):
            k1 = f(Y, t)
            k2 = f(Y + h / 2 * k1, t + h / 2)
            k3 = f(Y + h / 2 * k2, t + h / 2)
            k4 = f(Y + h * k3, t + h)
            Y, t = Y + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4), t + h
        assert np.all(np.hypot(Y[:, 0], Y[:, 1]) < 1e-2)
    # the claim narrowed to d = 0 while the certificate proves more, or wider bounds, do not verify
    doc = copy.deepcopy(result.document)
    doc["conditions"]["roa"]["disturbances"] = "zero"
    assert not api.verify(doc).valid
    doc = copy.deepcopy(result.document)
    doc["conditions"]["roa"]["certificate"]["disturbances"]["w"] = ["-1/2", "1/2"]
    assert not api.verify(doc).valid
