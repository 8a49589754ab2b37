"""SOS programs as data: the frozen declaration of a program's structure.

A program is a list of polynomial identities, each linear in the decision variables:

    sum_t  P_t(z) * L_t(X_t)(z)  +  P_0(z)  =  0          (every coefficient of z)

where ``X_t`` is a Gram polynomial ``z_G^T Q z_G`` (a positive semidefinite ``Q``, block diagonal
by the blocks given) or a scalar, ``L_t`` is the identity or a partial derivative, and ``P_t``,
``P_0`` are polynomials whose coefficients are either literals of the structure or the entries of
a named parameter vector (one entry per monomial of a declared support). Everything numerical that
changes from one solve to the next (the field's coefficients, a decay rate, a level) is a
parameter, so a structure (bases, blocks, supports, identities, objective) is all that
:mod:`lyapcheck.sos.direct` needs to build the solver's data, and its hash names it.
"""

from __future__ import annotations

import hashlib
from dataclasses import dataclass
from fractions import Fraction
from pathlib import Path
from typing import Final, Literal, Mapping, Sequence

from lyapcheck.sos.polynomials import Monomial

#: bump when the meaning of a structure changes (older cached programs are then ignored)
STRUCTURE_VERSION: Final = 1

#: the cones a Gram block may lie in (:attr:`Gram.cone`)
Cone = Literal["psd", "sdd", "dd"]
CONES: Final = ("psd", "sdd", "dd")


# -- the structure ----------------------------------------------------------------------------------

@dataclass(frozen=True)
class Gram:
    """A Gram polynomial ``z^T Q z`` over ``basis``; ``Q`` is block diagonal with ``blocks`` (index
    sets into ``basis``; every index in exactly one block), each block PSD, and ``>= t I`` when
    ``margin`` is True (``t`` the program's margin variable), ``>= phi I`` when it names a scalar
    parameter ``phi``, ``>= 0`` when False."""

    name: str
    basis: tuple[Monomial, ...]
    blocks: tuple[tuple[int, ...], ...]
    margin: bool | str = True
    #: the cone each block (minus its margin) lies in: ``"psd"`` (semidefinite), ``"sdd"`` (scaled
    #: diagonally dominant: a sum of 2x2 PSD matrices, one per pair of rows, second-order cones) or
    #: ``"dd"`` (diagonally dominant, linear): the two inner approximations of Ahmadi & Majumdar
    #: (DSOS/SDSOS), far cheaper to solve; the exact checks are the same for all three
    cone: Cone = "psd"

    def __repr__(self) -> str:
        # the dataclass's own repr, with the cone only where it is not "psd": the structure's hash
        # (:meth:`Structure.key`) of every program that predates the cones is unchanged
        cone = f", cone={self.cone!r}" if self.cone != "psd" else ""
        return (f"Gram(name={self.name!r}, basis={self.basis!r}, blocks={self.blocks!r}, "
                f"margin={self.margin!r}{cone})")


@dataclass(frozen=True)
class Scalar:
    """A scalar decision variable; ``lower``: ``None`` (free), ``"zero"`` (>= 0) or ``"margin"`` (>= t)."""

    name: str
    lower: Literal["zero", "margin"] | None = None


@dataclass(frozen=True)
class Coefficients:
    """The coefficients of a known polynomial: a parameter vector (one entry per monomial of
    ``support``, in that order) when ``param`` is set, else the literal ``values``."""

    support: tuple[Monomial, ...]
    param: str | None = None
    values: tuple[Fraction, ...] = ()

    @classmethod
    def parameter(cls, name: str, support: Sequence[Monomial]) -> "Coefficients":
        return cls(tuple(tuple(m) for m in support), param=name)

    @classmethod
    def literal(cls, terms: Mapping[Monomial, Fraction | int]) -> "Coefficients":
        items = sorted((tuple(m), Fraction(c)) for m, c in terms.items() if c != 0)
        return cls(tuple(m for m, _ in items), values=tuple(c for _, c in items))


@dataclass(frozen=True)
class Term:
    """``coefficients * L(decision)``: ``decision`` names a :class:`Gram` or a :class:`Scalar`;
    ``derivative`` is the variable index of ``L = d/dz_i`` (None: ``L`` is the identity)."""

    coefficients: Coefficients
    decision: str
    derivative: int | None = None


@dataclass(frozen=True)
class Identity:
    """``sum(terms) + constant == 0`` as polynomials; ``remainder`` names the Gram that absorbs
    rounding (:mod:`lyapcheck.sos.rounding`), and ``shared`` further Grams that absorb it with it:
    a remainder that is a sum of Gram matrices over overlapping bases (one per clique of the
    variables, correlative sparsity: :mod:`lyapcheck.sos.sparsity`), each in the identity once, with
    the remainder's factor."""

    name: str
    terms: tuple[Term, ...]
    constant: Coefficients | None
    remainder: str
    shared: tuple[str, ...] = ()

    def remainders(self) -> tuple[str, ...]:
        """Every Gram that absorbs the rounding of this identity."""
        return (self.remainder, *self.shared)


@dataclass(frozen=True)
class Structure:
    """A whole program. ``objective``: ``("max_margin",)``, ``("min", scalar)`` or ``("max", scalar)``.
    ``trace_one``: Gram names normalized by ``trace(Q) = 1``. ``inner``: ``(scalar, gram, param)``
    constraints ``scalar == <Q_gram, P>`` with ``P`` a symmetric parameter matrix (an objective
    that weighs a Gram polynomial at sample points)."""

    nvars: int
    grams: tuple[Gram, ...]
    scalars: tuple[Scalar, ...]
    identities: tuple[Identity, ...]
    objective: tuple[str, ...]
    trace_one: tuple[str, ...] = ()
    inner: tuple[tuple[str, str, str], ...] = ()

    def key(self) -> str:
        digest = hashlib.sha256(repr((STRUCTURE_VERSION, _engine_hash(), self)).encode())
        return "sos-" + digest.hexdigest()[:32]

    def gram(self, name: str) -> Gram:
        return next(g for g in self.grams if g.name == name)

    def cost(self) -> int:
        """The sum over the PSD blocks of ``(k (k + 1) / 2)^3`` for a block of ``k`` rows: an
        interior-point iteration factors each block's dense scaling matrix (side ``k (k + 1) / 2``),
        so this is what a solve costs up to a constant (the searches skip a structure above their
        limit). SDD and DD blocks have no dense scaling matrix (3 x 3 and 1 x 1 ones per pair of
        rows): they count in :meth:`cone_size` instead."""
        return sum((len(idx) * (len(idx) + 1) // 2) ** 3 for g in self.grams if g.cone == "psd"
                   for idx in g.blocks)

    def cone_size(self) -> int:
        """The decisions of the SDD and DD blocks: each block's ``k (k + 1) / 2`` entries and the
        auxiliary ones of :mod:`lyapcheck.sos.direct` (two per pair of rows in SDD, one in DD). Their
        cones' scaling matrices are block diagonal with blocks of 3 x 3 at most, so an
        interior-point iteration's work grows with this count and with the identities' rows (the
        sparse factorization of the KKT system), not with a cube of the blocks."""
        return sum(len(idx) * (len(idx) + 1) // 2 + (2 if g.cone == "sdd" else 1) * (len(idx) * (len(idx) - 1) // 2)
                   for g in self.grams if g.cone != "psd" for idx in g.blocks)

    def parameters(self) -> dict[str, tuple[int, ...]]:
        """Every parameter's shape (a vector per :class:`Coefficients`, a matrix per ``inner``)."""
        out: dict[str, tuple[int, ...]] = {}
        for ident in self.identities:
            sources = [t.coefficients for t in ident.terms] + ([ident.constant] if ident.constant else [])
            for c in sources:
                if c.param is not None:
                    shape = (len(c.support),)
                    if out.setdefault(c.param, shape) != shape:
                        raise ValueError(f"parameter {c.param} declared with two supports")
        for _, gram, param in self.inner:
            n = len(self.gram(gram).basis)
            out[param] = (n, n)
        for g in self.grams:
            if isinstance(g.margin, str):
                out[g.margin] = ()
        return out


def _engine_hash() -> str:
    """The structure's meaning is also its construction's: a change to either module renames every key."""
    here = Path(__file__)
    return hashlib.sha256(here.read_bytes() + here.with_name("direct.py").read_bytes()).hexdigest()[:16]


def full_blocks(basis: Sequence[Monomial]) -> tuple[tuple[int, ...], ...]:
    return (tuple(range(len(basis))),) if basis else ()


def with_cone(structure: Structure, cone: Cone) -> Structure:
    """``structure`` with every Gram block in ``cone`` (the SDSOS or DSOS version of a program: the
    same identities, a smaller feasible set, far cheaper solves)."""
    from dataclasses import replace

    if cone not in CONES:
        raise ValueError(f"cone must be one of {', '.join(CONES)}, got {cone!r}")
    return replace(structure, grams=tuple(replace(g, cone=cone) for g in structure.grams))
