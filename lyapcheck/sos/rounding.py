"""From a solver's floating-point point to exact rationals that satisfy the identities exactly.

The solver returns Gram matrices and scalars that satisfy a program's identities
(:mod:`lyapcheck.sos.program`) only within its tolerance. The exact checks need them exactly, so:

1. **Round** every decision deterministically: a matrix's entries to the dyadic grid
   ``2^-ROUND_BITS`` times the power of two above its largest entry, a scalar to
   ``ROUND_BITS`` bits of its own size. The same floats give the same rationals, and floats that
   differ in their last bits almost always do too (a step a thousand million times coarser than
   a double's last bit), which keeps certificates the same across floating-point platforms.
2. **Correct** the non-remainder decisions where an identity has a monomial that its remainder
   Gram cannot represent (no pair of basis monomials multiplies to it): there the identity is a
   linear equation on the other decisions alone, which rounding broke. The least-norm exact
   correction solves those equations (FLINT's rational matrices).
3. **Project** each remainder Gram onto its identity: every monomial's coefficient is a sum of
   Gram entries disjoint from every other monomial's, so the orthogonal projection spreads each
   coefficient's residual equally over its entries (within the Gram's blocks, so a block-diagonal
   matrix stays block diagonal), in exact arithmetic.

Nothing here decides anything: the classes then check positive definiteness and the identities
exactly (:mod:`lyapcheck.sos.definiteness`), and the certificate files are re-checked by
``verify`` from the polynomials alone.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from fractions import Fraction
from typing import Any, Callable, Final, Mapping, Sequence

import numpy as np

from lyapcheck.sos.polynomials import Monomial, Poly, Ring, gram_form
from lyapcheck.sos.program import Coefficients, Gram, Solution, Structure

#: bits kept below the largest entry of a rounded matrix (and of a scalar)
ROUND_BITS: Final = 30

#: the correction's columns (unknowns) between two of the caller's checkpoints: each column's
#: polynomial products take about a millisecond on a large network's program
CHECKPOINT_COLUMNS: Final = 64

ExactMatrix = list[list[Fraction]]


def round_matrix(Q: np.ndarray, bits: int = ROUND_BITS) -> ExactMatrix:
    """Entries on the dyadic grid ``2^(e - bits)`` with ``2^e`` the power of two at or above the
    largest magnitude; symmetric input gives a symmetric result."""
    Q = np.asarray(Q, dtype=np.float64)
    n = Q.shape[0]
    peak = float(np.max(np.abs(Q))) if Q.size else 0.0
    if peak == 0.0 or not math.isfinite(peak):
        return [[Fraction(0)] * n for _ in range(n)]
    e = math.frexp(peak)[1]
    step_exp = e - bits
    scaled = np.rint(np.ldexp(Q, -step_exp))
    unit = Fraction(2) ** step_exp
    out = [[Fraction(int(v)) * unit for v in row] for row in scaled]
    for i in range(n):
        for j in range(i + 1, n):
            if out[i][j] != out[j][i]:
                out[i][j] = out[j][i] = (out[i][j] + out[j][i]) / 2
    return out


def round_scalar(x: float, bits: int = ROUND_BITS) -> Fraction:
    if x == 0.0 or not math.isfinite(x):
        return Fraction(0)
    e = math.frexp(x)[1]
    return Fraction(int(round(math.ldexp(x, bits - e)))) * Fraction(2) ** (e - bits)


@dataclass
class ExactPoint:
    """Exact decisions: full Gram matrices (zero between blocks) and scalars."""

    grams: dict[str, ExactMatrix]
    scalars: dict[str, Fraction]


def coefficient_poly(ring: Ring, coeffs: Coefficients, values: Mapping[str, Sequence[Fraction]]) -> Poly:
    """The polynomial of a :class:`Coefficients` with exact parameter values."""
    vals = coeffs.values if coeffs.param is None else values[coeffs.param]
    return ring.from_terms({m: Fraction(c) for m, c in zip(coeffs.support, vals)})


def decision_poly(ring: Ring, structure: Structure, point: ExactPoint, name: str, derivative: int | None) -> Poly:
    if name in point.grams:
        p = gram_form(ring, structure.gram(name).basis, point.grams[name])
    else:
        p = ring.constant(point.scalars[name])
    return p if derivative is None else p.derivative(derivative)


def identity_value(ring: Ring, structure: Structure, ident: Any, point: ExactPoint,
                   values: Mapping[str, Sequence[Fraction]], *, skip: str | Sequence[str] | None = None) -> Poly:
    """``sum(terms) + constant`` exactly (the terms on decision ``skip``, or on each of them, left out)."""
    skipped = {skip} if isinstance(skip, str) else set(skip or ())
    total = ring.zero()
    for term in ident.terms:
        if term.decision in skipped:
            continue
        total += coefficient_poly(ring, term.coefficients, values) * decision_poly(
            ring, structure, point, term.decision, term.derivative)
    if ident.constant is not None:
        total += coefficient_poly(ring, ident.constant, values)
    return total


def _classes(gram: Gram) -> dict[Monomial, list[tuple[int, int]]]:
    """Monomial -> the Gram entries (within blocks) whose basis product is that monomial."""
    out: dict[Monomial, list[tuple[int, int]]] = {}
    for idx in gram.blocks:
        for i in idx:
            for j in idx:
                m = tuple(a + b for a, b in zip(gram.basis[i], gram.basis[j]))
                out.setdefault(m, []).append((i, j))
    return out


def _remainder_factor(ident: Any) -> Fraction:
    """The literal constant multiplying the remainder (each remainder Gram exactly one term, the same
    constant literal)."""
    factors = set()
    for name in ident.remainders():
        terms = [t for t in ident.terms if t.decision == name]
        if len(terms) != 1 or terms[0].derivative is not None or terms[0].coefficients.param is not None \
                or len(terms[0].coefficients.support) != 1 or any(terms[0].coefficients.support[0]):
            raise ValueError(f"identity {ident.name}: its remainder must appear once, times a constant literal")
        factors.add(terms[0].coefficients.values[0])
    if len(factors) != 1:
        raise ValueError(f"identity {ident.name}: its remainder Grams must share one constant factor")
    return factors.pop()


#: what :func:`exact_point` calls between its steps (a caller's time budget: it may raise to stop
#: the rounding; it decides nothing about the point)
Checkpoint = Callable[[], None]


def _no_checkpoint() -> None:
    return None


def exact_point(ring: Ring, structure: Structure, solution: Solution,
                values: Mapping[str, Sequence[Fraction]], checkpoint: Checkpoint = _no_checkpoint
                ) -> ExactPoint | None:
    """Round, correct and project (see the module docstring); None when no exact point results
    (a residual the remainders cannot absorb and the correction cannot remove). ``checkpoint`` is
    called between the steps (and between the correction's columns): a caller's time limit raises
    there, so that a large program's rounding stops within one step of it."""
    rounded = rounded_point(solution)
    checkpoint()
    return project(ring, structure, rounded, values, checkpoint)


def rounded_point(solution: Solution) -> ExactPoint:
    """Step 1 alone: every decision rounded (a caller may then fix some before :func:`project`)."""
    return ExactPoint(grams={name: round_matrix(Q) for name, Q in solution.grams.items()},
                      scalars={name: round_scalar(x) for name, x in solution.scalars.items() if name != "t"})


def project(ring: Ring, structure: Structure, point: ExactPoint,
            values: Mapping[str, Sequence[Fraction]], checkpoint: Checkpoint = _no_checkpoint
            ) -> ExactPoint | None:
    """Steps 2 and 3 on a rounded point (changed in place and returned), or None; ``checkpoint``
    as :func:`exact_point`'s."""
    for gram in structure.grams:  # zero between blocks, exactly
        allowed = {(i, j) for idx in gram.blocks for i in idx for j in idx}
        Q = point.grams[gram.name]
        for i in range(len(Q)):
            for j in range(len(Q)):
                if (i, j) not in allowed:
                    Q[i][j] = Fraction(0)
    classes = [_identity_classes(structure, ident) for ident in structure.identities]
    checkpoint()
    if not _correct(ring, structure, point, values, classes, checkpoint):
        return None
    for k, ident in enumerate(structure.identities):
        checkpoint()
        factor = _remainder_factor(ident)
        target = identity_value(ring, structure, ident, point, values, skip=ident.remainders())
        # factor * R + target == 0  ->  R = -target / factor (R the sum of the remainder Grams)
        want = ring.terms(target)
        want = {m: -c / factor for m, c in want.items()}
        cls = classes[k]
        if any(m not in cls for m, c in want.items() if c != 0):
            return None
        for m, entries in cls.items():
            residual = want.get(m, Fraction(0)) - sum((point.grams[g][i][j] for g, i, j in entries), Fraction(0))
            if residual:
                # the orthogonal projection: each monomial's entries (over every remainder Gram) are
                # disjoint from every other monomial's, so its residual is spread equally over them
                share = residual / len(entries)
                for g, i, j in entries:
                    point.grams[g][i][j] += share
    return point


def _identity_classes(structure: Structure, ident: Any) -> dict[Monomial, list[tuple[str, int, int]]]:
    """Monomial -> the entries (Gram, row, column) of the identity's remainder Grams that produce it."""
    out: dict[Monomial, list[tuple[str, int, int]]] = {}
    for name in ident.remainders():
        for m, entries in _classes(structure.gram(name)).items():
            out.setdefault(m, []).extend((name, i, j) for i, j in entries)
    return out


def _correct(ring: Ring, structure: Structure, point: ExactPoint, values: Mapping[str, Sequence[Fraction]],
             classes: Sequence[Mapping[Monomial, Any]], checkpoint: Checkpoint = _no_checkpoint) -> bool:
    """Make the identities hold exactly on the monomials their remainders cannot represent, by the
    least-norm change of the other decisions (False if that linear system has no solution).

    On such a monomial ``m`` of identity ``k`` the identity reads ``target_k(x)[m] = 0``, with
    ``target_k`` the identity without its remainder, affine in the other decisions ``x``. So the
    change ``delta`` solves ``A delta = -target(x)`` on those rows, ``A``'s column ``c`` being the
    coefficients the unit of unknown ``c`` contributes.
    """
    import flint

    remainders = {name for ident in structure.identities for name in ident.remainders()}
    rows: list[tuple[int, Monomial]] = []
    rhs: list[Fraction] = []
    for k, ident in enumerate(structure.identities):
        checkpoint()
        target = ring.terms(identity_value(ring, structure, ident, point, values, skip=ident.remainders()))
        for m in sorted(_generic_support(structure, ident) | set(target)):
            if m not in classes[k]:
                rows.append((k, m))
                rhs.append(-target.get(m, Fraction(0)))
    if not any(rhs):
        return True
    # the unknowns: upper-triangle Gram entries within blocks, and scalars, of non-remainder decisions
    columns: list[tuple[str, int, int]] = []
    for g in structure.grams:
        if g.name not in remainders:
            columns += [(g.name, i, j) for idx in g.blocks for a, i in enumerate(idx) for j in idx[a:]]
    columns += [(s.name, -1, -1) for s in structure.scalars if s.name not in remainders]
    row_index = {r: n for n, r in enumerate(rows)}
    entries: dict[tuple[int, int], Fraction] = {}
    for c, (name, i, j) in enumerate(columns):
        if c % CHECKPOINT_COLUMNS == 0:
            checkpoint()
        unit = _unit_point(structure, name, i, j)
        for k, ident in enumerate(structure.identities):
            contribution = ring.zero()
            for term in ident.terms:
                if term.decision == name:
                    contribution += coefficient_poly(ring, term.coefficients, values) * decision_poly(
                        ring, structure, unit, name, term.derivative)
            for m, coef in ring.terms(contribution).items():
                r = row_index.get((k, m))
                if r is not None:
                    entries[(r, c)] = coef
    used = sorted({c for _, c in entries})
    if not used:
        return False
    where = {c: n for n, c in enumerate(used)}
    dense = [[flint.fmpq(0)] * len(used) for _ in rows]
    for (r, c), v in entries.items():
        dense[r][where[c]] = flint.fmpq(v.numerator, v.denominator)
    checkpoint()
    A = flint.fmpq_mat(dense)
    b = flint.fmpq_mat([[flint.fmpq(v.numerator, v.denominator)] for v in rhs])
    independent = _independent_rows(A)
    Ai = flint.fmpq_mat([[A[r, c] for c in range(A.ncols())] for r in independent])
    bi = flint.fmpq_mat([[b[r, 0]] for r in independent])
    try:
        y = (Ai * Ai.transpose()).solve(bi)
    except (ZeroDivisionError, ValueError):
        return False
    delta = Ai.transpose() * y
    if A * delta != b:
        return False  # inconsistent equations: no change of the other decisions makes them hold
    for n, c in enumerate(used):
        name, i, j = columns[c]
        d = delta[n, 0]
        change = Fraction(int(d.p), int(d.q))
        if i < 0:
            point.scalars[name] += change
        else:
            Q = point.grams[name]
            Q[i][j] += change
            if i != j:
                Q[j][i] += change
    return True


def _unit_point(structure: Structure, name: str, i: int, j: int) -> ExactPoint:
    """A point whose only non-zero decision is the unit of one unknown (for the linear map)."""
    if i < 0:
        return ExactPoint(grams={}, scalars={name: Fraction(1)})
    n = len(structure.gram(name).basis)
    Q = [[Fraction(0)] * n for _ in range(n)]
    Q[i][j] = Fraction(1)
    Q[j][i] = Fraction(1)
    return ExactPoint(grams={name: Q}, scalars={})


def _generic_support(structure: Structure, ident: Any) -> set[Monomial]:
    """Every monomial the identity's non-remainder terms can produce, whatever the decisions."""
    out: set[Monomial] = set()
    for term in ident.terms:
        if term.decision in ident.remainders():
            continue
        if any(g.name == term.decision for g in structure.grams):
            g = structure.gram(term.decision)
            monos = {tuple(a + b for a, b in zip(g.basis[i], g.basis[j])) for idx in g.blocks for i in idx for j in idx}
        else:
            monos = {tuple(0 for _ in range(structure.nvars))}
        if term.derivative is not None:
            d = term.derivative
            monos = {m[:d] + (m[d] - 1,) + m[d + 1:] for m in monos if m[d] > 0}
        for a in term.coefficients.support:
            out |= {tuple(x + y for x, y in zip(m, a)) for m in monos}
    if ident.constant is not None:
        out |= set(ident.constant.support)
    return out


def _independent_rows(M: Any) -> list[int]:
    """Indices of a maximal set of linearly independent rows of a FLINT rational matrix (the pivot
    columns of the transpose's reduced row echelon form)."""
    R, rank = M.transpose().rref()
    rows = []
    for r in range(rank):
        rows.append(next(c for c in range(R.ncols()) if R[r, c] != 0))
    return rows
