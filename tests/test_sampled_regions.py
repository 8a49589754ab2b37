"""``roa`` of a sampled-data loop on its true flow over one period (lyapcheck.models.classes.sampled_regions):
the certified set holds its claim on simulations of the true sampled loop, the remainder bound holds on the
numerically integrated flow, and ``verify`` re-derives the certificate (a forged one fails)."""

from __future__ import annotations

import json
import math
from fractions import Fraction
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[1]
PD = ROOT / "examples" / "models" / "pendulum-digital-pd.toml"
SLOW = ROOT / "examples" / "models" / "pendulum-digital-pd-slow.toml"
POLICY = ROOT / "examples" / "models" / "pendulum-digital-tanh-policy.toml"
LINEAR = ('[model]\nstates = ["x", "v"]\n[parameters]\nT = "0.5 s"\n[dynamics]\nx = "v"\nv = "u"\n'
          '[sampling]\nperiod = "T"\n[controller]\nu = "-x - v"\n')


def _certified(path: Path):  # type: ignore[no-untyped-def]
    from lyapcheck.models.classes import sampled_regions
    from lyapcheck.models.language.sampling import load_sampled

    model = load_sampled(path)
    result = sampled_regions.roa(model)
    assert result.status == "certified", result.summary
    return model, result.to_json()


def _matrix(rows: list[list[str]]) -> np.ndarray:
    return np.array([[float(Fraction(x)) for x in row] for row in rows])


def test_the_example_certifies_a_region_whose_figures_are_the_certificates() -> None:
    from lyapcheck.models.classes.claims import summary

    model, c = _certified(PD)
    cert = c["certificate"]
    level, radius = Fraction(cert["level"]), Fraction(cert["radius"])
    assert level == Fraction(cert["lambda_P"]) * radius ** 2  # {V <= c} inside the ball |e| <= r
    P = _matrix(cert["P"])
    assert np.min(np.linalg.eigvalsh(P)) >= float(Fraction(cert["lambda_P"]))
    assert c["level"] == float(level) and c["ball_radius"] == float(radius)
    assert c["intersample_factor"] == float(Fraction(cert["flow"]["Ce"])) >= 1
    assert Fraction(cert["flow"]["rho"]) > Fraction(cert["flow"]["Ce"]) * radius  # the a priori box holds the flow
    assert summary("roa", c) == c["summary"] and "period 0.02 s" in c["summary"]
    assert c["property"] == "ROA"


def test_the_remainder_and_the_excursion_bounds_hold_on_the_integrated_flow() -> None:
    """``|Phi_T(x) - x_eq - A_T e| <= L2 |e|^2`` and ``|x(t) - x_eq| <= Ce |e|`` on starts of the ball,
    the flow integrated by scipy at a tight tolerance (an independent integrator)."""
    from scipy.integrate import solve_ivp
    from scipy.linalg import expm

    model, c = _certified(PD)
    cert = c["certificate"]
    A, B, K = (_matrix(cert[k]) for k in ("A", "B", "K"))
    T = float(model.period)
    E = expm(np.block([[A, B], [np.zeros((1, 2)), np.zeros((1, 1))]]) * T)
    AT = E[:2, :2] + E[:2, 2:] @ K
    r = float(Fraction(cert["radius"]))
    L2, Ce = float(Fraction(cert["flow"]["L2"])), float(Fraction(cert["flow"]["Ce"]))
    rng = np.random.default_rng(7)
    worst_remainder = worst_excursion = 0.0
    for _ in range(40):
        d = rng.normal(size=2)
        e0 = d / np.linalg.norm(d) * r * rng.uniform(0.2, 1.0)
        u = float((K @ e0)[0])  # (the law is linear and the equilibrium 0)
        sol = solve_ivp(lambda t, x: [x[1], 9.81 * math.sin(x[0]) - 0.1 * x[1] + u], (0, T), e0, rtol=1e-12,
                        atol=1e-14, dense_output=True)
        remainder = np.linalg.norm(sol.y[:, -1] - AT @ e0)
        worst_remainder = max(worst_remainder, remainder / (L2 * e0 @ e0))
        path = sol.sol(np.linspace(0, T, 41))
        worst_excursion = max(worst_excursion, np.max(np.linalg.norm(path, axis=0)) / (Ce * np.linalg.norm(e0)))
    assert 0 < worst_remainder <= 1 and 0 < worst_excursion <= 1


def _simulate(model, starts: np.ndarray, periods: int):  # type: ignore[no-untyped-def]
    """The true sampled loop from ``starts`` by ``simulate``'s engine, its states on a grid of 5 samples per
    period (the sampling instants every 5th)."""
    from lyapcheck.models.surfaces.sampled_simulate import run_sampled

    T = float(model.period)
    run = run_sampled(model, starts, "the certified set", t_end=periods * T, series=True)
    x = run.series["x"].transpose("trajectory", "time", "state").values
    return run.document, x


@pytest.mark.slow
@pytest.mark.parametrize("path", [PD, POLICY])
def test_simulated_starts_in_the_set_never_leave_it_and_converge(path: Path) -> None:
    """Starts on the boundary of the certified set and inside it: at every sampling instant V stays below
    the level (an alarm otherwise: the claim would be false), between samples the excursion bound holds,
    and every start converges."""
    model, c = _certified(path)
    cert = c["certificate"]
    P, level = _matrix(cert["P"]), float(Fraction(cert["level"]))
    Ce = float(Fraction(cert["flow"]["Ce"]))
    x_eq = np.array([float(q) for q in model.equilibrium])
    starts = []
    for k in range(24):
        d = np.array([math.cos(2 * math.pi * k / 24), math.sin(2 * math.pi * k / 24)])
        for share in (0.999, 0.5):
            starts.append(x_eq + d * math.sqrt(share * level / (d @ P @ d)))
    document, x = _simulate(model, np.array(starts), 100)
    assert not document["diverged"]
    e = x - x_eq
    V = np.einsum("rti,ij,rtj->rt", e, P, e)
    at_instants = V[:, ::5]
    assert np.all(at_instants <= level * (1 + 1e-9)), "a simulated start left the certified set"
    assert np.all(np.diff(at_instants, axis=1) <= 1e-12 * level)  # V decreases from instant to instant
    norms = np.linalg.norm(e, axis=2)
    for k in range(0, norms.shape[1] - 1, 5):
        assert np.all(norms[:, k:k + 6] <= Ce * norms[:, k:k + 1] * (1 + 1e-9) + 1e-12)
    assert np.all(V[:, -1] <= 1e-2 * V[:, 0])  # (100 periods: every start well on its way to the equilibrium)


def test_a_linear_loop_has_no_remainder(tmp_path: Path) -> None:
    from lyapcheck.models.classes import sampled_regions
    from lyapcheck.models.language.sampling import load_sampled

    path = tmp_path / "di.toml"
    path.write_text(LINEAR)
    model = load_sampled(path)
    c = sampled_regions.roa(model).to_json()
    assert c["status"] == "certified"
    assert {k: Fraction(c["certificate"]["flow"][k]) for k in ("L2", "W", "LP")} == {"L2": 0, "W": 0, "LP": 0}
    assert sampled_regions.verify(model, c)[0]


def test_an_unstable_period_certifies_nothing_and_a_kink_is_not_applicable(tmp_path: Path) -> None:
    from lyapcheck.models.classes import sampled_regions
    from lyapcheck.models.language.sampling import load_sampled

    slow = sampled_regions.roa(load_sampled(SLOW))
    assert slow.status == "not_certified" and "not Schur" in slow.summary
    path = tmp_path / "abs.toml"
    path.write_text(LINEAR.replace('u = "-x - v"', 'u = "-x - v - abs(x)"'))
    kink = sampled_regions.roa(load_sampled(path))
    assert kink.status == "not_applicable" and "abs" in kink.summary


def test_verify_rederives_the_region_and_a_forged_one_fails() -> None:
    from lyapcheck.api import certify, verify
    from lyapcheck.models.classes.claims import summary

    doc = certify(model=PD).document
    assert doc["conditions"]["roa"]["status"] == "certified"
    result = verify(doc)
    assert result.valid
    assert any(row.check == "roa" and row.ok for row in result.checks)
    forgeries = {
        "level raised": lambda c: c["certificate"].update(level=str(Fraction(c["certificate"]["level"]) * 101 / 100)),
        "P changed": lambda c: c["certificate"].update(P=[[x if i == j else str(-Fraction(x)) for j, x in enumerate(row)]
                                                          for i, row in enumerate(c["certificate"]["P"])]),
        "P scaled": lambda c: c["certificate"].update(P=[[str(Fraction(x) * 2) if i == j else x
                                                          for j, x in enumerate(row)]
                                                         for i, row in enumerate(c["certificate"]["P"])]),
        "radius raised": lambda c: c["certificate"].update(radius=str(Fraction(c["certificate"]["radius"]) * 2)),
        "remainder lowered": lambda c: c["certificate"]["flow"].update(L2=str(Fraction(c["certificate"]["flow"]["L2"]) / 2)),
        "excursion lowered": lambda c: c["certificate"]["flow"].update(Ce="1"),
        "figure": lambda c: c.update(ball_radius=c["ball_radius"] * 2),
        "summary": lambda c: c.update(summary=c["summary"].replace("converges", "converges globally")),
    }
    for what, forge in forgeries.items():
        bad = json.loads(json.dumps(doc))
        c = bad["conditions"]["roa"]
        forge(c)
        if what not in ("figure", "summary"):  # the figures and the sentence made to agree: the proof must fail
            cert = c["certificate"]
            c.update(level=float(Fraction(cert["level"])), ball_radius=float(Fraction(cert["radius"])),
                     intersample_factor=float(Fraction(cert["flow"]["Ce"])),
                     remainder_L2=float(Fraction(cert["flow"]["L2"])))
            c["summary"] = summary("roa", c)
        again = verify(bad)
        assert not again.valid, what
        assert any(row.check == "roa" and not row.ok for row in again.checks), what


def test_verify_runs_the_one_flow_for_a_sampled_loop() -> None:
    """The sampled-data loop's rows come from the steps every kind runs (verify.SAMPLED): a box in its
    document fails, as does a certified claim of a class with no sampled-data check."""
    from lyapcheck.api import certify, verify
    from lyapcheck.models.language.sampling import load_sampled
    from lyapcheck.models.surfaces.verify import SAMPLED, loop_kind

    assert loop_kind(load_sampled(PD)) is SAMPLED
    doc = certify(model=PD, classes="linearization,quadratic").document
    names = [row.check for row in verify(doc).checks]
    assert names[:5] == ["model", "parameters", "states", "sampling", "linearization"]
    bad = json.loads(json.dumps(doc))
    bad["box"] = {"T": ["1/100", "1/50"]}
    assert not verify(bad).valid
    bad = json.loads(json.dumps(doc))
    bad["conditions"]["quadratic"]["status"] = "certified"
    assert any(row.check == "quadratic" and not row.ok for row in verify(bad).checks)


@pytest.mark.slow
def test_every_field_of_the_region_given_a_wrong_value_fails_in_its_row() -> None:
    """Each leaf of the roa condition replaced by a value of another form: verify answers (no exception
    escapes) and the document is not valid."""
    from lyapcheck.api import certify, verify

    doc = certify(model=PD, classes="roa").document

    def leaves(node: object, path: tuple[object, ...] = ()):  # type: ignore[no-untyped-def]
        if isinstance(node, dict):
            for k, v in node.items():
                yield from leaves(v, (*path, k))
        elif isinstance(node, list):
            for i, v in enumerate(node):
                yield from leaves(v, (*path, i))
        else:
            yield path

    paths = list(leaves(doc["conditions"]["roa"]))
    assert len(paths) > 20
    for path in paths:
        for wrong in ("x", -1, None, [], "-1/3"):
            bad = json.loads(json.dumps(doc))
            node = bad["conditions"]["roa"]
            for key in path[:-1]:
                node = node[key]
            if node[path[-1]] == wrong:
                continue
            node[path[-1]] = wrong
            assert not verify(bad).valid, (path, wrong)
