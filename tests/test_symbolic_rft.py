"""Tests of symbolic.rft: the RFT derivation of Table table:micro and Proposition prop:mahoney.

The numeric references are independent: the RFT integrals are redone here by adaptive
quadrature (scipy.integrate.quad) of the force on each segment for unit translations and
rotations, with the normal drag written as xi_perp (I - t t^T) rather than the module's
Frenet form.
"""

from __future__ import annotations

import ast
import math
import re
from pathlib import Path
from typing import Callable

import numpy as np
import pytest
import sympy as sp
from scipy.integrate import quad

from symbolic import rft
from symbolic import symbols as S
from symbolic.ledger import LedgerEntry, build_ledger

PAPER = Path("/work/shared/paper/000_d66ce9f99bd12029.tex")

#: every claim's status, pinned: a discrepancy that disappears, or a new one, fails here
EXPECTED_STATUS = {
    "table:micro a_h1": "holds",
    "table:micro a_h2": "holds",
    "table:micro a1": "holds",
    "table:micro a2": "holds",
    "table:micro b11": "holds",
    "table:micro b13": "holds",
    "table:micro b22": "holds",
    "table:micro b33": "holds",
    "table:micro b23": "holds",
    "table:micro with the paper's fractional n_h = 3.5": "discrepancy",
    "eq:simTrans2 D": "holds",
    "eq:simTrans2 E (helix ends at gamma = pi)": "holds",
    "eq:simTrans2 E constant in frame H": "discrepancy",
    "eq:eq_dyn: E k_h = e11 k_h, e11 = -b11/a1 (any spin phase)": "holds",
    "propulsion constant e11": "holds",
    "eq:tmp1 in eq:eq_dyn gives p_dot = v^d": "holds",
    "eq:fddecomp in-plane decomposition of f_d": "holds",
    "eq:tmp3 d_mu = ^W R_H D ^H R_W f_d": "holds",
    "proof: v^d.k_h and v^d.k_h^perp": "holds",
    "proof: d_mu.k_h = |f_d| cos(-Psi + alpha)/a1": "holds",
    "proof: d_mu.k_h^perp = |f_d| cos(pi/2 - Psi + alpha)/a2": "discrepancy",
    "proof: one orientation of the angles for all four projections": "discrepancy",
    "eq:tmp4 from eq:tmp1 and the proof's d_mu.k_h": "discrepancy",
    "eq:tmp5 from eq:tmp1 and the proof's d_mu.k_h^perp": "holds",
    "eq:fdfwdDir solves eq:tmp5": "holds",
    "eq:fdfwdMag restates eq:tmp4": "holds",
    "eq:tmp4 from the model, alpha to f_d": "discrepancy",
    "eq:tmp5 from the model, alpha to f_d": "discrepancy",
    "eq:fdfwdDir tan(Psi) from the model, alpha to f_d": "discrepancy",
    "eq:fdfwdMag |u| from the model, alpha to f_d": "discrepancy",
    "eq:fdfwdDir tan(Psi) from the model, alpha to -f_d": "holds",
    "eq:fdfwdMag |u| from the model, alpha to -f_d": "holds",
}

LABELS = {"table:micro", "eq:simTrans2", "eq:eq_dyn", "eq:e11", "eq:tmp1", "eq:fddecomp", "eq:tmp3",
          "prop:mahoney", "eq:tmp4", "eq:tmp5", "eq:fdfwdDir", "eq:fdfwdMag"}


@pytest.fixture(scope="module")
def ledger() -> dict[str, LedgerEntry]:
    claims = rft.claims()
    return {entry.title: entry for entry in build_ledger(claims)}


# ----------------------------------------------------------------------------------------
# the ledger
# ----------------------------------------------------------------------------------------
def test_every_claim_status_is_pinned(ledger: dict[str, LedgerEntry]) -> None:
    statuses = {title: entry.status for title, entry in ledger.items()}
    assert statuses == EXPECTED_STATUS


def test_titles_unique_and_labels_are_the_papers() -> None:
    claims = rft.claims()
    titles = [c.title for c in claims]
    assert len(titles) == len(set(titles))
    assert {c.label for c in claims} == LABELS
    if PAPER.exists():
        source_labels = set(re.findall(r"\\label\{([^}]*)\}", PAPER.read_text()))
        assert LABELS <= source_labels


def test_every_entry_has_a_one_sentence_explanation(ledger: dict[str, LedgerEntry]) -> None:
    for entry in ledger.values():
        text = entry.explanation
        assert text and not text.startswith("Neither"), entry
        if entry.status == "discrepancy":
            assert text.count(". ") == 0, text  # one sentence


def test_symbolic_does_not_import_lyapcheck() -> None:
    tree = ast.parse(Path(rft.__file__).read_text())
    modules = {alias.name for node in ast.walk(tree) if isinstance(node, ast.Import) for alias in node.names}
    modules |= {node.module or "" for node in ast.walk(tree) if isinstance(node, ast.ImportFrom)}
    assert not any(name.startswith("lyapcheck") for name in modules)


# ----------------------------------------------------------------------------------------
# the geometry the integrals rest on
# ----------------------------------------------------------------------------------------
C_PHI, S_PHI = sp.Symbol("c_phi", real=True), sp.Symbol("s_phi", real=True)
C_TH, S_TH = sp.Symbol("c_theta", positive=True), sp.Symbol("s_theta", positive=True)


def _vanishes(expr: sp.Expr) -> bool:
    """Exact: is `expr` (rational in cos/sin of phi, theta_h) zero on cos^2 + sin^2 = 1?

    The two circle polynomials have coprime leading terms, so they are a Groebner basis and
    the remainder decides membership.
    """
    expr = sp.sympify(expr).xreplace({sp.cos(S.theta_h): C_TH, sp.sin(S.theta_h): S_TH})
    expr = expr.xreplace({sp.tan(S.theta_h): S_TH / C_TH})
    numerator = sp.numer(sp.together(expr))
    _, remainder = sp.reduced(sp.expand(numerator), [S_PHI**2 + C_PHI**2 - 1, S_TH**2 + C_TH**2 - 1],
                              S_PHI, S_TH, C_PHI, C_TH)
    return bool(sp.expand(remainder) == 0)


def test_helix_frame_is_orthonormal_and_arc_length_is_right() -> None:
    x, th = sp.symbols("x th", real=True)
    to_plain = {C_PHI: sp.cos(x), S_PHI: sp.sin(x), C_TH: sp.cos(th), S_TH: sp.sin(th), rft.phi: x}
    back = {sp.cos(x): C_PHI, sp.sin(x): S_PHI, sp.cos(th): C_TH, sp.sin(th): S_TH}
    r, t, n, b, ds_dphi = rft.helix_curve()
    # differentiate the plain curve (the module differentiates through the placeholders)
    dr = r.xreplace(to_plain).diff(x).xreplace(back)
    assert _vanishes(dr.dot(dr) - ds_dphi**2)
    assert all(_vanishes(e) for e in dr / ds_dphi - t)
    dt = t.xreplace(to_plain).diff(x).xreplace(back)
    assert all(_vanishes(e) for e in dt / S_TH - n)
    frame = sp.Matrix.hstack(t, n, b)
    assert all(_vanishes(e) for e in frame.T * frame - sp.eye(3))   # so I = t t^T + n n^T + b b^T
    assert _vanishes(frame.det() - 1)                                 # right-handed frame
    assert t[0] == C_TH                                               # pitch angle measured from x_H
    # right-handed helix: turning by +phi about x_H advances along +x_H
    assert dr[0] == S.r_h * C_TH / S_TH


def _quadrature_matrices(n: float, theta: float, radius: float, xi_par: float, xi_perp: float,
                         xi_head: float, offset: float, phase: float) -> tuple[np.ndarray, np.ndarray]:
    """A, B by quadrature: columns are minus the force for unit V and unit omega."""
    pitch = radius / math.tan(theta)

    def geometry(p: float) -> tuple[np.ndarray, np.ndarray, float]:
        r = np.array([pitch * (p - math.pi * n), radius * math.cos(p + phase), radius * math.sin(p + phase)])
        dr = np.array([pitch, -radius * math.sin(p + phase), radius * math.cos(p + phase)])
        speed = float(np.linalg.norm(dr))
        return r, dr / speed, speed

    def drag_force(velocity_of: Callable[[np.ndarray], np.ndarray], p: float) -> np.ndarray:
        r, t, speed = geometry(p)
        v = velocity_of(r)
        return (xi_par * t * (t @ v) + xi_perp * (v - t * (t @ v))) * speed

    a_mat, b_mat = np.zeros((3, 3)), np.zeros((3, 3))
    for j in range(3):
        e = np.eye(3)[j]
        for i in range(3):
            a_mat[i, j] = quad(lambda p: drag_force(lambda r: e, p)[i], 0, 2 * math.pi * n, limit=200)[0]
            b_mat[i, j] = quad(lambda p: drag_force(lambda r: np.cross(e, r), p)[i], 0, 2 * math.pi * n,
                               limit=200)[0]
        head = np.array([offset, 0.0, 0.0])
        a_mat[:, j] += xi_head * e
        b_mat[:, j] += xi_head * np.cross(e, head)
    return a_mat, b_mat


PARAMETER_SETS = [
    # n, theta, r_h (m), xi_par, xi_perp (N s/m^2), xi_vm (N s/m), |k_h| (m)
    (3, 0.6, 2.1e-4, 1.3e-3, 2.1e-3, 3.0e-6, 4.0e-4),
    (5, 1.1, 1.0, 1.0, 1.8, 0.7, 2.5),
]


@pytest.mark.parametrize("params", PARAMETER_SETS)
def test_rft_constants_match_quadrature(params: tuple[float, ...]) -> None:
    n, theta, radius, xi_par, xi_perp, xi_head, offset = params
    const = rft.rft_constants(n, theta, radius, xi_par, xi_perp, xi_head, offset)
    a_mat, b_mat = _quadrature_matrices(n, theta, radius, xi_par, xi_perp, xi_head, offset, math.pi)
    a_scale, b_scale = np.abs(a_mat).max(), np.abs(b_mat).max()
    expected_a = np.diag([const["a1"], const["a2"], const["a2"]])
    expected_b = np.array([[const["b11"], 0, const["b13"]],
                           [0, const["b22"], const["b23"]],
                           [0, -const["b23"], const["b33"]]])
    np.testing.assert_allclose(a_mat, expected_a, rtol=1e-9, atol=1e-10 * a_scale)
    np.testing.assert_allclose(b_mat, expected_b, rtol=1e-9, atol=1e-10 * b_scale)
    e_mat = -np.linalg.solve(a_mat, b_mat)
    assert e_mat[0, 0] == pytest.approx(const["e11"], rel=1e-9)


def test_first_column_of_e_is_axial_at_any_spin_phase() -> None:
    n, theta, radius, xi_par, xi_perp, xi_head, offset = PARAMETER_SETS[1]
    const = rft.rft_constants(n, theta, radius, xi_par, xi_perp, xi_head, offset)
    for phase in (0.9, 2.3):
        a_mat, b_mat = _quadrature_matrices(n, theta, radius, xi_par, xi_perp, xi_head, offset, phase)
        e_col = -np.linalg.solve(a_mat, b_mat[:, 0])
        np.testing.assert_allclose(e_col, [const["e11"], 0, 0], atol=1e-10 * abs(const["e11"]))


def test_general_matrices_match_quadrature_for_fractional_turns() -> None:
    args = (3.5, 0.8, 0.7, 1.2, 2.0, 0.4, 1.3)
    a_num, b_num = rft.helix_resistance_matrices(*args, end_phase=0.7)
    a_ref, b_ref = _quadrature_matrices(*args, 0.7)
    np.testing.assert_allclose(a_num, a_ref, rtol=1e-9, atol=1e-10 * np.abs(a_ref).max())
    np.testing.assert_allclose(b_num, b_ref, rtol=1e-9, atol=1e-10 * np.abs(b_ref).max())
    assert abs(a_ref[0, 1]) + abs(a_ref[0, 2]) > 1e-3 * a_ref[0, 0]  # the coupling is real


def test_fractional_turn_effect_vanishes_for_whole_turns() -> None:
    whole = rft.fractional_turn_effect(n_turns=3.0)
    assert whole["lateral"] == pytest.approx(0.0, abs=1e-12)
    assert whole["axial"] == pytest.approx(whole["table_e11"], rel=1e-12)
    half = rft.fractional_turn_effect()
    assert half["lateral"] / half["axial"] == pytest.approx(0.209, abs=0.001)


@pytest.mark.parametrize(("n", "radius"), [(1, 1.0), (3, 4.2e-4), (7, 2.0)])
def test_e11_is_a_third_of_the_radius_for_the_textbook_helix(n: int, radius: float) -> None:
    const = rft.rft_constants(n, math.pi / 4, radius, 0.9, 1.8)
    assert const["e11"] == pytest.approx(radius / 3, rel=1e-12)
    exact = rft.derived_table()["e11"].subs({S.theta_h: sp.pi / 4, S.xi_perp: 2 * S.xi_par, S.xi_vm: 0})
    assert sp.simplify(exact - S.r_h / 3) == 0


def test_rft_constants_rejects_bad_input() -> None:
    with pytest.raises(ValueError, match=r"The 'pitch_angle' parameter must be a number in \(0, 1.5708\)\. Got 2"):
        rft.rft_constants(3, 2.0, 1.0, 1.0, 2.0)
    with pytest.raises(ValueError, match="The 'xi_head' parameter must be a number in \\[0, inf\\)"):
        rft.rft_constants(3, 0.5, 1.0, 1.0, 2.0, xi_head=-1.0)


# ----------------------------------------------------------------------------------------
# eq:tmp3 numerically, and the feedforward law by its residual
# ----------------------------------------------------------------------------------------
def _explicit_d_mu(force: np.ndarray, axis: np.ndarray, a1: float, a2: float) -> np.ndarray:
    rot = np.stack([axis, np.stack([-axis[..., 1], axis[..., 0]], axis=-1)], axis=-1)  # columns k, k_perp
    d_mat = np.diag([1 / a1, 1 / a2])
    return np.einsum("...ij,jk,...lk,...l->...i", rot, d_mat, rot, force)


def test_disturbance_velocity_is_the_d_matrix_product() -> None:
    rng = np.random.default_rng(20261121)
    force = rng.normal(size=(4, 3, 2))
    psi = rng.uniform(-math.pi, math.pi, size=(4, 3))
    axis = np.stack([np.cos(psi), np.sin(psi)], axis=-1)
    got = rft.disturbance_velocity(force, axis, 2.5, 0.7)
    assert got.shape == (4, 3, 2)
    np.testing.assert_allclose(got, _explicit_d_mu(force, axis, 2.5, 0.7), rtol=1e-13, atol=1e-15)
    # weight straight down, axis along x: the transverse drag a2 sets the sinking speed
    np.testing.assert_allclose(rft.disturbance_velocity([0.0, -1.0], [1.0, 0.0], 2.0, 4.0), [0.0, -0.25])
    # one force broadcast against many axes
    assert rft.disturbance_velocity([1.0, 0.0], axis[0], 1.0, 2.0).shape == (3, 2)


def test_disturbance_velocity_rejects_bad_input() -> None:
    with pytest.raises(ValueError, match="The 'force_xy' parameter must be an array of shape"):
        rft.disturbance_velocity([1.0, 2.0, 3.0], [1.0, 0.0], 1.0, 1.0)
    with pytest.raises(ValueError, match="The 'axis_xy' parameter must be unit vectors. Got a norm of 2.0"):
        rft.disturbance_velocity([1.0, 0.0], [2.0, 0.0], 1.0, 1.0)
    with pytest.raises(ValueError, match="The 'a2' parameter must be a number in"):
        rft.disturbance_velocity([1.0, 0.0], [1.0, 0.0], 1.0, 0.0)


def _feedforward(forms: dict[str, sp.Expr], v: float, f: float, alpha: float, a1: float, a2: float,
                 e11: float) -> tuple[float, float]:
    """(Psi, |u|) from a tan(Psi) and |u| formula, on the branch with |u| > 0."""
    point = {rft.v_mag: v, rft.f_mag: f, rft.alpha: alpha, rft.a1: a1, rft.a2: a2, S.e11: e11}
    psi = math.atan(float(forms["tan_psi"].subs(point)))
    u = float(forms["u_mag"].subs({**point, rft.Psi: psi}))
    if u < 0:  # arctan only fixes Psi modulo pi
        psi += math.pi
        u = -u
    return psi, u


@pytest.mark.parametrize("alpha", [-1.9, -0.4, 0.3, 2.2])
def test_derived_feedforward_cancels_the_disturbance_and_the_printed_one_does_not(alpha: float) -> None:
    v, f, a1, a2, e11 = 1.0, 0.6, 1.5, 2.0, 0.3
    v_d = np.array([v, 0.0])
    force = f * np.array([math.cos(alpha), math.sin(alpha)])   # alpha measured to f_d

    def residual(psi: float, u: float) -> float:
        axis = np.array([math.cos(psi), math.sin(psi)])
        p_dot = e11 * u * axis + _explicit_d_mu(force, axis, a1, a2)   # eq:eq_dyn
        return float(np.linalg.norm(p_dot - v_d))

    assert residual(*_feedforward(rft.feedforward_forms(False), v, f, alpha, a1, a2, e11)) < 1e-12
    assert residual(*_feedforward(rft.printed_feedforward(), v, f, alpha, a1, a2, e11)) > 1e-3
    # the printed law is right if alpha is taken as the angle of -f_d
    assert residual(*_feedforward(rft.printed_feedforward(), v, f, alpha + math.pi, a1, a2, e11)) < 1e-12


def test_no_angle_convention_satisfies_all_four_projections() -> None:
    table = rft.projection_conventions()
    assert len(table) == 16
    assert max(len(v) for v in table.values()) == 3
    # the module's convention: all but the text's d_mu.k_perp; alpha to -f_d: all but d_mu.k_h
    assert table[(1, 1, 1, 1)] == ["v.k", "v.k_perp", "d.k"]
    assert table[(1, 1, 1, -1)] == ["v.k", "v.k_perp", "d.k_perp"]


def test_spin_phase_dependence_of_b() -> None:
    _, b_gen = rft.rft_matrices(True, None)
    b11 = b_gen[0, 0]
    gamma = rft.gamma
    # B's entries are linear Fourier sums in gamma, so comparing coefficients is exact
    assert _vanishes(b_gen[0, 2] - b11 * sp.cos(gamma) / sp.tan(S.theta_h))
    assert _vanishes(b_gen[0, 1] + b11 * sp.sin(gamma) / sp.tan(S.theta_h))
    assert _vanishes(b_gen[1, 1] + b11 * (2 + sp.cos(2 * gamma)) / 4)
    assert _vanishes(b_gen[2, 2] + b11 * (2 - sp.cos(2 * gamma)) / 4)
    # the spin average (the constant Fourier term) is b13 = 0, b22 = b33 = -b11/2
    average = lambda e: e.xreplace({sp.cos(gamma): 0, sp.sin(gamma): 0,  # noqa: E731
                                    sp.cos(2 * gamma): 0, sp.sin(2 * gamma): 0})
    assert average(b_gen[0, 2]) == 0
    assert _vanishes(average(b_gen[1, 1]) + b11 / 2)
    assert _vanishes(average(b_gen[2, 2]) + b11 / 2)
