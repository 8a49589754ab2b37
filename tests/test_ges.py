"""``ges``: GES from a state-dependent quadratic form; the identity behind it and the proof."""

from __future__ import annotations

from fractions import Fraction

import numpy as np
import pytest
import sympy as sp
from scipy.integrate import solve_ivp

from lyapcheck.paper.certification import build_system
from lyapcheck.paper.conditions import ges
from lyapcheck.paper.conditions.sos import scaled_dynamics
from lyapcheck.paper.params import problem_from_sources
from tests.conftest import PAPER_TOML


@pytest.fixture(scope="module")
def paper() -> tuple:
    system = build_system(problem_from_sources(PAPER_TOML, {}), "derived")
    result = ges.run(system)
    return system, result


def test_bernstein_positivity_proofs() -> None:
    F = Fraction
    assert ges.positive_on_unit_interval([F(1, 4) + F(1, 100), F(-1), F(1)])  # (w - 1/2)^2 + 0.01
    assert not ges.positive_on_unit_interval([F(-1, 2), F(1)])  # root at 1/2
    assert not ges.positive_on_unit_interval([F(1, 4), F(-1), F(1)])  # touches 0 at 1/2
    assert ges.positive_on_unit_interval([F(2), F(-3)]) is False  # negative at w = 1
    # positive but with negative Bernstein coefficients before subdivision
    p = [F(1, 4) + F(1, 10**4), F(-1), F(1)]
    assert min(ges.bernstein(p)) < 0 and ges.positive_on_unit_interval(p)


def test_derivative_matrix_is_the_derivative_along_the_nonlinear_field(paper: tuple) -> None:
    """x^T D(w) x equals grad V . f(x) exactly, f the rational error dynamics (not the LDI)."""
    system, result = paper
    dyn = scaled_dynamics(system)
    P = ((Fraction(3), Fraction(1, 2)), (Fraction(1, 2), Fraction(2)))
    ells = [[Fraction(1, 3), Fraction(-2)], [Fraction(5), Fraction(1, 7)], [Fraction(-1), Fraction(2, 9)]]
    e, r = sp.symbols("e r")
    y = e + r
    w = 1 / (1 + y**2)
    R = sp.Rational
    V = sp.Matrix([e, r]).T * sp.Matrix(2, 2, lambda i, j: R(P[i][j])) * sp.Matrix([e, r])
    V = V[0] + sum(w**k * y * (R(ell[0]) * e + R(ell[1]) * r) for k, ell in enumerate(ells, start=1))
    f = (-e + sp.Rational(dyn.c) * r, -sp.Rational(dyn.a) * r + sp.Rational(dyn.b) * w * e)
    Vdot = sp.diff(V, e) * f[0] + sp.diff(V, r) * f[1]
    M, D = ges.lyapunov_matrices(dyn, P, ells)

    def at(poly: list[Fraction], wv: sp.Rational) -> sp.Rational:
        return sum(sp.Rational(c) * wv**i for i, c in enumerate(poly))

    for ev, rv in ((1, 2), (sp.Rational(-3, 7), sp.Rational(5, 2)), (40, -39)):
        ev, rv = sp.Rational(ev), sp.Rational(rv)
        wv = 1 / (1 + (ev + rv) ** 2)
        x = sp.Matrix([ev, rv])
        quad_V = (x.T * sp.Matrix(2, 2, lambda i, j: at(M[i][j], wv)) * x)[0]
        quad_D = (x.T * sp.Matrix(2, 2, lambda i, j: at(D[i][j], wv)) * x)[0]
        assert sp.simplify(V.subs({e: ev, r: rv}) - quad_V) == 0
        assert sp.simplify(Vdot.subs({e: ev, r: rv}) - quad_D) == 0


def test_paper_gains_are_ges_and_the_certificate_rechecks(paper: tuple) -> None:
    system, result = paper
    assert result.status == "certified", result.summary
    assert result.numbers["decay_rate_per_s"] > 0 and result.numbers["k"] >= 1
    ok, why = ges.verify(system, result.certificate)
    assert ok, why


@pytest.mark.parametrize("tamper", ["mu", "c1", "P"])
def test_a_tampered_certificate_fails(paper: tuple, tamper: str) -> None:
    system, result = paper
    cert = {**result.certificate}
    if tamper == "mu":  # a far faster decay than the far field (rate 1 in scaled time) allows
        cert["mu_scaled"] = "3"
    elif tamper == "c1":
        cert["c1"] = str(Fraction(cert["c2"]) * 2 / 3)
    else:
        P = [list(row) for row in cert["P"]]
        P[0][0] = str(-Fraction(P[0][0]))
        cert["P"] = P
    assert not ges.verify(system, cert)[0]


def test_simulated_trajectories_respect_the_certified_envelope(paper: tuple) -> None:
    """|x(tau)| <= k |x0| exp(-mu tau / 2) along the nonlinear flow, from near and far starts."""
    system, result = paper
    dyn = scaled_dynamics(system)
    c, a, b = float(dyn.c), float(dyn.a), float(dyn.b)
    k = result.numbers["k"]
    mu = float(Fraction(result.certificate["mu_scaled"]))

    def field(_t: float, x: np.ndarray) -> list[float]:
        e, r = x
        return [-e + c * r, -a * r + b * e / (1 + (e + r) ** 2)]

    worst = 0.0
    for radius in (1e-2, 1.0, 30.0, 1e3):
        for angle in np.linspace(0, 2 * np.pi, 12, endpoint=False):
            x0 = radius * np.array([np.cos(angle), np.sin(angle)])
            sol = solve_ivp(field, (0, 20), x0, rtol=1e-9, atol=1e-12 * radius, dense_output=True, max_step=0.05)
            norms = np.linalg.norm(sol.y, axis=0)
            envelope = k * radius * np.exp(-mu * sol.t / 2)
            worst = max(worst, float(np.max(norms / envelope)))
    assert worst <= 1.0 + 1e-6


def test_the_search_tables_are_the_exact_polynomials_rounded_once() -> None:
    """The search's data are the exact coefficients of M(w) and D(w) rounded to doubles: the same
    on every platform (issue 24: the grid's array power differed in the last bit under numpy's
    AVX-512 loops), and linear in (P, l) as the program assumes."""
    rng = np.random.default_rng(3)
    for _ in range(4):
        c, a, b = (Fraction(int(v), 97) for v in rng.integers(-500, 500, 3))
        dyn = scaled_dynamics_of(c, a, b)
        Ms, Ds = ges.polynomial_tables(dyn)
        z = [Fraction(int(v), 7) for v in rng.integers(-50, 50, 3 + 2 * ges.TERMS)]
        M, D = ges.lyapunov_matrices(dyn, ((z[0], z[1]), (z[1], z[2])), [z[3 + 2 * k: 5 + 2 * k] for k in range(ges.TERMS)])
        zf = np.array([float(v) for v in z])
        for table, exact_poly in ((Ms, M), (Ds, D)):
            combined = np.tensordot(zf, table, axes=1)  # (degree + 1, 2, 2)
            for p in range(2):
                for q in range(2):
                    coefficients = [float(x) for x in exact_poly[p][q]]
                    coefficients += [0.0] * (combined.shape[0] - len(coefficients))
                    np.testing.assert_allclose(combined[:, p, q], coefficients, rtol=1e-12, atol=1e-12 * np.abs(combined).max())


def scaled_dynamics_of(c: Fraction, a: Fraction, b: Fraction) -> "ges.ScaledDynamics":
    return ges.ScaledDynamics(time_scale=Fraction(1), c=c, a=a, b=b)


def _lukacs_polynomial(X: np.ndarray, Y: np.ndarray, half: int, w: float) -> np.ndarray:
    """The 2x2 matrix polynomial whose coefficients _gram_side gives, evaluated at ``w``."""
    rows = ges._gram_side(X, Y, half)
    g = np.zeros((2, 2))
    for j in range(2 * half + 1):
        for e, (p, q) in enumerate(ges._ENTRIES):
            g[p, q] += rows[3 * j + e] * w**j
    g[1, 0] = g[0, 1]
    return g


def test_the_program_imposes_each_inequality_on_the_whole_interval() -> None:
    """_gram_side is Z^T X Z + w (1 - w) Z'^T Y Z' coefficient by coefficient (Lukacs' form): with
    X, Y >= 0 the matrix polynomial is positive semidefinite at every w in [0, 1], not only at
    grid points (the search before issue 24 imposed it at 24 points only)."""
    rng = np.random.default_rng(5)
    for half in (2, 3):
        B, C = rng.normal(size=(2 * half + 2, 2 * half + 2)), rng.normal(size=(2 * half, 2 * half))
        X, Y = B @ B.T, C @ C.T
        for w in np.linspace(0, 1, 9):
            Z = np.kron(np.array([w**u for u in range(half + 1)])[:, None], np.eye(2))
            Zp = np.kron(np.array([w**u for u in range(half)])[:, None], np.eye(2))
            G = _lukacs_polynomial(X, Y, half, w)
            np.testing.assert_allclose(G, Z.T @ X @ Z + w * (1 - w) * Zp.T @ Y @ Zp, rtol=1e-10, atol=1e-10)
            assert np.linalg.eigvalsh(G).min() >= -1e-9
    # the w (1 - w) factor is what confines it to [0, 1]: X = 0, Y = I gives w (1 - w) I, negative at w = 2
    assert np.linalg.eigvalsh(_lukacs_polynomial(np.zeros((4, 4)), np.eye(2), 1, 2.0)).max() < 0


def test_the_decay_rate_search_lands_on_the_same_rate_when_the_data_move_in_the_last_bits(paper: tuple) -> None:
    """Issue 24: the rate and k may not follow the last bits of the data. Relative perturbations of
    1e-13 (far above what another platform's rounding does to the data) give the same rate and
    the same k within lyapcheck.tolerances.FIGURE_GES_K_RTOL."""
    from lyapcheck import tolerances

    system, result = paper
    dyn = scaled_dynamics(system)
    rng = np.random.default_rng(11)
    prog = ges.program()
    real = prog.set_data
    for _ in range(3):
        def noisy(dyns: object, mu: float) -> dict[str, np.ndarray]:
            return {k: v * (1 + 1e-13 * rng.standard_normal(v.shape)) for k, v in real(dyns, mu).items()}

        prog.set_data = noisy  # type: ignore[method-assign]
        try:
            cert = ges.search([dyn], [])
        finally:
            del prog.set_data
        assert cert is not None
        assert cert["mu_scaled"] == result.certificate["mu_scaled"]
        k = float(np.sqrt(float(Fraction(cert["c2"]) / Fraction(cert["c1"]))))
        assert k == pytest.approx(result.numbers["k"], rel=tolerances.FIGURE_GES_K_RTOL)
