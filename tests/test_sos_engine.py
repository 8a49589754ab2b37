"""The SOS engine (lyapcheck/sos): exact definiteness against a second opinion, sound basis
reductions, sign symmetry, exact rounding onto the identities, and the conic data built from a structure."""

from __future__ import annotations

import itertools
import json
import os
import subprocess
import sys
from fractions import Fraction

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

from lyapcheck import exact
from lyapcheck.sos import bases, definiteness
from tests.conftest import ROOT


def _ldl_says_positive_definite(m: list[list[Fraction]]) -> bool:
    """The pure-Python second opinion: exact LDL^T pivots all positive."""
    pivots = exact.ldl_pivots(tuple(tuple(row) for row in m))
    return pivots is not None and all(p > 0 for p in pivots)


symmetric_small = st.integers(min_value=1, max_value=7).flatmap(
    lambda n: st.lists(st.integers(-6, 6), min_size=n * n, max_size=n * n).map(
        lambda xs, n=n: [[Fraction(xs[i * n + j] + xs[j * n + i], 2) + (4 if i == j else 0) for j in range(n)]
                         for i in range(n)]))


@settings(max_examples=300, derandomize=True, deadline=None)
@given(symmetric_small)
def test_positive_definiteness_agrees_with_the_pure_python_ldl(m: list[list[Fraction]]) -> None:
    assert definiteness.is_positive_definite(m) == _ldl_says_positive_definite(m)


@pytest.mark.parametrize("n, shift, seed", [(40, 1e-3, 1), (40, -1e-3, 2), (60, 1e-6, 3)])
def test_large_blocks_take_the_congruence_or_the_characteristic_polynomial(n: int, shift: float, seed: int) -> None:
    rng = np.random.default_rng(seed)
    B = rng.normal(size=(n, n))
    M = B @ B.T / n + shift * np.eye(n) - np.eye(n) * np.linalg.eigvalsh(B @ B.T / n)[0]
    Q = [list(row) for row in exact.symmetrize(exact.rational_matrix(M, 15))]
    assert definiteness.is_positive_definite(Q) == _ldl_says_positive_definite(Q) == (shift > 0)
    assert definiteness._charpoly_positive_definite(Q) == (shift > 0)  # the fallback decides alone too


def _principal_minors_nonnegative(m: list[list[Fraction]]) -> bool:
    n = len(m)
    for k in range(1, n + 1):
        for idx in itertools.combinations(range(n), k):
            if exact.det(tuple(tuple(m[i][j] for j in idx) for i in idx)) < 0:
                return False
    return True


@settings(max_examples=200, derandomize=True, deadline=None)
@given(st.integers(1, 4).flatmap(lambda n: st.lists(st.lists(st.integers(-3, 3), min_size=n, max_size=n),
                                                       min_size=1, max_size=3).map(lambda rows, n=n: (n, rows))))
def test_semidefiniteness_agrees_with_every_principal_minor(data: tuple[int, list[list[int]]]) -> None:
    n, rows = data  # a Gram matrix of rank <= len(rows): semidefinite, singular most of the time
    G = [[Fraction(sum(r[i] * r[j] for r in rows)) for j in range(n)] for i in range(n)]
    assert definiteness.is_positive_semidefinite(G) is True
    shifted = [[G[i][j] - (1 if i == j == 0 else 0) for j in range(n)] for i in range(n)]
    assert definiteness.is_positive_semidefinite(shifted) == _principal_minors_nonnegative(shifted)


def _in_hull(point: tuple[int, ...], support: list[tuple[int, ...]]) -> bool:
    """Exact-enough hull membership by LP (scipy), the reference for the hyperplane reduction."""
    from scipy.optimize import linprog

    pts = np.array(support, dtype=float).T
    A = np.vstack([pts, np.ones(len(support))])
    b = np.array(list(point) + [1.0])
    res = linprog(np.zeros(len(support)), A_eq=A, b_eq=b, bounds=[(0, None)] * len(support), method="highs")
    return bool(res.status == 0)


@settings(max_examples=30, derandomize=True, deadline=None)
@given(st.lists(st.tuples(st.integers(0, 6), st.integers(0, 6)), min_size=2, max_size=8, unique=True))
def test_the_newton_reduction_never_drops_a_monomial_inside_the_half_polytope(support: list[tuple[int, int]]) -> None:
    even = [tuple(2 * x for x in m) for m in support]  # squares: every point is a sum of two candidates
    kept = set(bases.newton_reduce(bases.half_degree_candidates(2, even), even))
    for m in bases.half_degree_candidates(2, even):
        if _in_hull(tuple(2 * x for x in m), even):
            # inside the hull: only the diagonal-consistency rule may drop it, and only if 2m is
            # neither in the support nor a sum of two kept monomials
            twice = tuple(2 * x for x in m)
            sums = {tuple(a + b for a, b in zip(p, q)) for p in kept for q in kept if p != q}
            assert m in kept or (twice not in even and twice not in sums)
        else:
            assert m not in kept


def test_sign_symmetry_of_an_odd_field_is_the_parity() -> None:
    # g0 = -x + x^3 y^2 (odd), g1 = -y (odd): x -> -x, y -> -y together, and each alone too
    gens = bases.sign_symmetries(2, [([(1, 0), (3, 2)], 0), ([(0, 1)], 1)])
    group = {tuple(sum(c * g[k] for c, g in zip(coeffs, gens)) % 2 for k in range(2))
             for coeffs in itertools.product((0, 1), repeat=len(gens))}
    assert group == {(0, 0), (1, 0), (0, 1), (1, 1)}
    # a term x y in g0 breaks y -> -y alone
    gens = bases.sign_symmetries(2, [([(1, 0), (1, 1)], 0), ([(0, 1)], 1)])
    assert [tuple(g) for g in gens] == [(1, 0)] or all(g[1] == 0 for g in gens)


def test_exact_rounding_makes_the_identity_hold_exactly() -> None:
    """A Lyapunov program for a cubic field: the rounded, corrected and projected point satisfies
    the identity exactly (the classes' exact check says so too)."""
    from lyapcheck.models.classes import lyapunov
    from lyapcheck.models.loop.field import StateField
    from lyapcheck.models.engines.search import Budget, Search
    from lyapcheck.sos.certificates import GramPoly, lie_derivative
    from lyapcheck.sos.polynomials import Ring, gram_form

    ring = Ring(("x", "y"))
    x, y = ring.gens()
    field = StateField(ring, (-x ** 3 + y, -x - y), ring.constant(1))
    structure = lyapunov.lyapunov_structure(field, 4, lyapunov.symmetry(field))
    assert structure is not None
    search = Search(ring, Budget(60, "test"))
    values = lyapunov.lyapunov_values(field, structure, Fraction(0))
    point = search.exact(structure, search.solve(structure, values), values)
    assert point is not None
    V = gram_form(ring, structure.gram("V").basis, point.grams["V"])
    W = gram_form(ring, structure.gram("W").basis, point.grams["W"])
    assert -lie_derivative(ring, V, field.g) == W
    assert GramPoly.of(structure.gram("W").basis, point.grams["W"]).positive_definite()


def test_a_model_is_certified_without_importing_cvxpy() -> None:
    """The generic classes build Clarabel's data from the structure (lyapcheck.sos.direct): no
    cvxpy import (about a second) and no compile step, in the first run as in every other."""
    code = ("import sys, json; from lyapcheck.models.language.modelfile import parse_model; "
            "from lyapcheck.models.surfaces.certify import certify_model; "
            "r = certify_model(parse_model('[model]\\nstates=[\"x\",\"y\"]\\n[dynamics]\\nx=\"-x+y\"\\ny=\"-x-y\"\\n'), "
            "classes='quadratic'); print(json.dumps([r.results['quadratic'].status, 'cvxpy' in sys.modules]))")
    run = subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True, check=True)
    assert json.loads(run.stdout) == ["certified", False]


@pytest.mark.parametrize("system", ["poly2", "linear"])
def test_the_direct_conic_data_and_cvxpy_reach_the_same_optimum(system: str) -> None:
    """The direct construction of a structure's conic data (lyapcheck.sos.direct) against an
    independent one (lyapcheck.sos.program.build_cvxpy, cvxpy's canonicalization, Clarabel both
    times): the same optimum (measured: margins 0.1809 and 0.1111, bounds B 0.2164 and 0.1956, equal
    to 1e-10), on a degree-4 Lyapunov program with sign-symmetry blocks and a trace normalization,
    and on a sos_bound program with scalars, a minimized objective and floors (parameter margins)."""
    import numpy as np

    from lyapcheck.models.classes import bounds, lyapunov
    from lyapcheck.models.surfaces.certify import shifted_field
    from lyapcheck.models.loop.field import apply_scaling, choose_scaling, clear, state_field
    from lyapcheck.models.language.modelfile import parse_model
    from lyapcheck.sos.direct import DirectProgram
    from lyapcheck.sos.program import build_cvxpy
    from lyapcheck.sos.sdp import solve as solve_cvxpy

    text = {"poly2": '[model]\nstates = ["x", "y"]\n[disturbances]\nd = 0.1\n[dynamics]\nx = "-x**3 + y"\n'
                     'y = "-x - y + d"\n',
            "linear": '[model]\nstates = ["x1", "x2", "x3"]\n[disturbances]\nd = 0.5\n[dynamics]\n'
                      'x1 = "-x1 + x2"\nx2 = "-2*x2 + x3"\nx3 = "-x3 - x1 + d"\n'}[system]
    model = parse_model(text)
    shifted = shifted_field(model)
    cleared = clear(shifted, [])
    scaled = apply_scaling(cleared, choose_scaling(cleared, model.domain))
    field = state_field(scaled)
    cases = []
    structure = lyapunov.lyapunov_structure(field, 4, lyapunov.symmetry(field))
    assert structure is not None
    cases.append((structure, lyapunov.lyapunov_values(field, structure, Fraction(0)).floats, "t"))
    y = next(iter(scaled.outputs.values()))
    structure = bounds.bound_structure(scaled, y, 2)
    assert structure is not None
    cases.append((structure, bounds.bound_values(scaled, structure, y, Fraction(1, 2)).floats, "B"))
    for structure, values, figure in cases:
        direct = DirectProgram(structure).solve(values)
        assert direct.report.outcome == "optimal" and direct.values is not None
        problem, params, variables = build_cvxpy(structure)
        for name, value in values.items():
            if name in params:
                params[name].value = value
        assert solve_cvxpy(problem).outcome == "optimal"
        assert float(direct.values[figure]) == pytest.approx(float(variables[figure].value), rel=1e-5, abs=1e-7)
