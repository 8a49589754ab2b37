"""The SOS certificate kinds, as exact objects with their exact checks.

Every kind is a polynomial identity whose unknown parts are Gram matrices ``z^T Q z``; the check
verifies the identity exactly (FLINT polynomials over the rationals) and each ``Q`` positive
definite exactly (:mod:`lyapcheck.sos.definiteness`). It reads only the certificate and the field,
never solver state. ``g`` is a polynomial field with ``z' = g / D`` and ``D > 0``; ``sigma``,
``s``, ``tau`` are the certificate's Gram polynomials.

=============  ==================================================  =========================  ================
kind           identity (all Gram matrices positive definite)      where it holds             proves
=============  ==================================================  =========================  ================
Positivity     ``p - c = sigma``, ``c > 0`` (``Q >= 0`` suffices)     everywhere                 ``p >= c > 0``
Lyapunov       ``-grad V . g - mu V D = sigma``, ``mu >= 0``         everywhere                 GAS; ``V' <= -mu V``
LyapunovCl.    the same with ``V``, ``sigma`` sums over cliques     everywhere                 the same
               (:class:`GramSum`, :func:`check_lyapunov_cliques`)
LyapunovVert.  the same at every vertex of a box, ``V`` and the     every ``u`` of the box     the same
               identity's left side multi-affine in ``u``
               (:func:`check_lyapunov_vertices`)
Sublevel       ``-grad V . g - s (c - V) = sigma``                   ``{V <= c}``               ``{V <= c}`` in the ROA
Dissipation    ``-grad V . g - lam (V - 1) D - sum tau_k (b_k^2      every ``|d_k| <= b_k``      ``limsup V <= 1``
               - d_k^2) = sigma``, ``lam > 0``
OutputBound    ``V - y^2 + B - 1 = sigma``                           everywhere                 ``y^2 <= V + B - 1``
Containment    ``c - V - s (r^2 - p) = sigma``                       ``{p <= r^2}``             ``{p <= r^2}`` in ``{V <= c}``
QuadraticBall  ``V = z^T P z``; norm bounds, no Gram remainder         ``{V <= c}``               ``{V <= c}`` in the ROA
Barrier        ``-B - sum s_i p_i = r`` (each initial piece),        initial, unsafe, all z     no trajectory from
               ``B - 1 - sum t_j q_j = r`` (each unsafe piece),                                  initial reaches
               ``-grad B . g + lam B D - sum r_k (1 - u_k^2) = r``                               unsafe
=============  ==================================================  =========================  ================

QuadraticBall (:func:`check_quadratic_ball`) is the one kind without an SOS identity: the
linearization's quadratic ``V`` and a level proved by norm bounds of the field's terms of degree 2
and more, which costs nothing at any number of states (the SOS level step needs a Gram matrix over
every monomial of degree 2 and less: 66 rows in 10 states).

Boxes of parameters. Each identity may carry ``- sum_j r_j (1 - u_j^2)`` with ``r_j`` sums of
squares and ``u_j`` normalized parameters: then it holds for every ``u`` in ``[-1, 1]^p``
(:func:`box_terms`); strictness stays in the states alone (the pure powers carry no ``u``).

Strictness. ``V`` positive definite and radially unbounded needs a pure power of every state in
its basis and no constant (``V >= lambda_min(Q_V) sum_i z_i^(2 k_i)``). ``sigma > 0`` away from 0 (so ``V' < 0`` there) needs a pure
power of every state in its basis (:func:`lyapcheck.sos.bases.has_pure_powers`); the checks
demand both where the conclusion needs them.
"""

from __future__ import annotations

from dataclasses import dataclass
from fractions import Fraction
from typing import Any, Mapping, Sequence

from lyapcheck.sos.bases import has_pure_powers
from lyapcheck.sos.definiteness import is_positive_definite
from lyapcheck.sos.polynomials import Monomial, Poly, Ring, gram_form

ExactMatrix = Sequence[Sequence[Fraction]]


@dataclass(frozen=True)
class GramPoly:
    """``z^T Q z`` over a monomial basis, exactly."""

    basis: tuple[Monomial, ...]
    Q: tuple[tuple[Fraction, ...], ...]

    def poly(self, ring: Ring) -> Poly:
        return gram_form(ring, self.basis, self.Q)

    def positive_definite(self) -> bool:
        return is_positive_definite(self.Q)

    def to_json(self) -> dict[str, Any]:
        return {"basis": [list(m) for m in self.basis], "Q": [[str(x) for x in row] for row in self.Q]}

    @classmethod
    def from_json(cls, data: Mapping[str, Any], nvars: int) -> "GramPoly":
        """A Gram polynomial from its JSON form; ValueError naming the key where an exponent is not a
        non-negative integer (``1.4`` is refused, never truncated) or a size does not fit."""
        if not isinstance(data, Mapping) or not isinstance(data.get("basis"), list) or \
                not isinstance(data.get("Q"), list):
            raise ValueError("a Gram matrix must be a table with lists 'basis' and 'Q'")
        if any(not isinstance(m, list) or len(m) != nvars for m in data["basis"]):
            raise ValueError(f"basis: a basis monomial must have {nvars} exponents")
        basis = tuple(tuple(exponent(e, "basis") for e in m) for m in data["basis"])
        Q = tuple(tuple(Fraction(x) for x in row) for row in data["Q"])
        if len(Q) != len(basis) or any(len(row) != len(basis) for row in Q):
            raise ValueError("a Gram matrix must be square, one row per basis monomial")
        return cls(basis, Q)

    @classmethod
    def of(cls, basis: Sequence[Monomial], Q: ExactMatrix) -> "GramPoly":
        return cls(tuple(tuple(m) for m in basis), tuple(tuple(Fraction(x) for x in row) for row in Q))


def exponent(value: Any, key: str, limit: int | None = None) -> int:
    """``value`` as an exponent, index or size read from a certificate: a JSON integer >= 0 (below
    ``limit`` where given); ValueError naming ``key`` otherwise."""
    if isinstance(value, bool) or not isinstance(value, int) or value < 0 or (limit is not None and value >= limit):
        where = f" below {limit}" if limit is not None else ""
        raise ValueError(f"{key}: {value!r} is not a non-negative integer{where}")
    return value


BoxMultipliers = Sequence[tuple[int, GramPoly]]


def box_terms(ring: Ring, multipliers: BoxMultipliers) -> tuple[Poly, str | None]:
    """``sum_j r_j (1 - u_j^2)`` over the multipliers ``(j, r_j)`` of a box (``u_j`` the ring's
    variable ``j``, normalized to ``[-1, 1]``): the S-procedure term that makes an identity hold on
    the box. The second value says why the multipliers are not acceptable (not positive
    semidefinite), or None."""
    from lyapcheck.sos.definiteness import is_positive_semidefinite

    total = ring.zero()
    gens = ring.gens()
    for j, r in multipliers:
        if not 0 <= j < ring.nvars:
            return total, f"a box multiplier names variable {j}, not one of the ring's"
        if not is_positive_semidefinite(r.Q):
            return total, "a box multiplier is not positive semidefinite (exact)"
        total += r.poly(ring) * (ring.constant(1) - gens[j] * gens[j])
    return total, None


def lie_derivative(ring: Ring, V: Poly, g: Sequence[Poly]) -> Poly:
    """``grad V . g`` (the states are the ring's first ``len(g)`` variables)."""
    total = ring.zero()
    for i, gi in enumerate(g):
        total += V.derivative(i) * gi
    return total


def check_positive_definite_v(V: "GramPoly | GramSum", n: int) -> tuple[bool, str]:
    """``V = z^T Q z`` with ``Q > 0``, no constant monomial and a pure power of every state in the
    basis: ``V >= lambda sum_i z_i^(2 k_i)``, so ``V`` is positive definite and radially unbounded
    (``V(0) = 0``, sublevel sets compact)."""
    if not V.basis or not has_pure_powers(V.basis, range(n)):
        return False, "V's basis must hold a pure power of every state (so that V is radially unbounded)"
    if any(sum(m) == 0 for m in V.basis):
        return False, "V's basis may not hold the constant monomial (V(0) must be 0)"
    if not V.positive_definite():
        return False, "Q_V is not positive definite (exact)"
    return True, "Q_V > 0 with a pure power of every state in its basis: V is positive definite, radially unbounded"


def check_lyapunov(ring: Ring, g: Sequence[Poly], D: Poly, V: GramPoly, sigma: GramPoly, mu: Fraction,
                   box: BoxMultipliers = ()) -> tuple[bool, str]:
    """Lyapunov: ``-grad V . g - mu V D - sum_j r_j (1 - u_j^2) = sigma``, ``V``, ``sigma`` as strict
    as GAS needs (``box``: the multipliers of a box of parameters, none for a point)."""
    n = len(g)
    if mu < 0:
        return False, "the decay rate mu must be >= 0"
    ok, why = check_positive_definite_v(V, n)
    if not ok:
        return False, why
    if not has_pure_powers(sigma.basis, range(n)):
        return False, "sigma's basis must hold a pure power of every state (so that V' < 0 away from 0)"
    if not sigma.positive_definite():
        return False, "Q_sigma is not positive definite (exact)"
    v = V.poly(ring)
    boxed, box_why = box_terms(ring, box)
    if box_why is not None:
        return False, box_why
    if -lie_derivative(ring, v, g) - v * D * _q(mu) - boxed != sigma.poly(ring):
        return False, "the identity -grad V . g - mu V D = sigma does not hold exactly"
    return True, "Q_V > 0, Q_sigma > 0 and -grad V . g - mu V D = sigma, exactly" + (" (on the box)" if box else "")


def box_vertices(ring: Ring, n: int) -> list[tuple[int, ...]]:
    """Every vertex of the box ``[-1, 1]^p`` of the ring's variables after the first ``n`` (the
    states), in a fixed order (the last variable's sign changing fastest)."""
    from itertools import product

    return list(product((-1, 1), repeat=ring.nvars - n))


def at_vertex(ring: Ring, p: Poly, n: int, vertex: Sequence[int]) -> Poly:
    """``p`` with the box variables (after the first ``n``) set to the vertex's signs."""
    return ring.substitute(p, {ring.names[n + j]: Fraction(s) for j, s in enumerate(vertex)})


def multi_affine(ring: Ring, polys: Sequence[Poly], n: int) -> bool:
    """Every polynomial has degree at most 1 in each variable after the first ``n`` (products of
    distinct ones allowed): then, for fixed states, it is the multilinear interpolation of its values
    at the box's vertices, a convex combination of them for every point of the box."""
    return all(all(e <= 1 for e in m[n:]) for p in polys for m in ring.support(p))


def check_lyapunov_vertices(ring: Ring, g: Sequence[Poly], D: Poly, V: Poly, positive: Sequence[GramPoly],
                            sigmas: Sequence[GramPoly], mu: Fraction) -> tuple[bool, str]:
    """Lyapunov over a box by its vertices. The box's variables ``u`` are the ring's variables after
    the states, each in ``[-1, 1]``. ``V(z, u)`` and ``P = -grad_z V . g - mu V D`` are both
    multi-affine in ``u`` (degree at most 1 in each ``u_j``, computed here), and at every vertex
    ``u_k`` of the box ``V(z, u_k) = positive_k`` and ``P(z, u_k) = sigma_k``, each Gram matrix positive
    definite with a pure power of every state in its basis.

    Why it holds on the whole box: a multi-affine function of ``u`` equals the multilinear
    interpolation of its vertex values, ``sum_k lambda_k(u) f(u_k)`` with weights
    ``lambda_k(u) = prod_j (1 + s_kj u_j) / 2 >= 0`` summing to 1. So for every ``u`` of the box
    ``V(., u) = sum_k lambda_k positive_k`` is positive definite and radially unbounded (uniformly in
    ``u``), and ``-V' D = P = sum_k lambda_k sigma_k > 0`` away from ``z = 0``: each parameter value's
    loop is GAS with its own ``V(., u)``, and ``V' <= -mu V``."""
    n = len(g)
    if mu < 0:
        return False, "the decay rate mu must be >= 0"
    P = -lie_derivative(ring, V, g) - V * D * _q(mu)
    if not multi_affine(ring, [V], n):
        return False, "V is not multi-affine in the box's variables, so its vertices do not bound it"
    if not multi_affine(ring, [P], n):
        return False, "-grad V . g - mu V D is not multi-affine in the box's variables, so its vertices do not bound it"
    vertices = box_vertices(ring, n)
    if len(positive) != len(vertices) or len(sigmas) != len(vertices):
        return False, (f"a vertex certificate needs one Gram matrix of V and one of sigma per vertex of the box "
                       f"({len(vertices)}), not {len(positive)} and {len(sigmas)}")
    for vertex, pos, sigma in zip(vertices, positive, sigmas):
        at = f"at the vertex {list(vertex)}"
        if any(any(m[n:]) for m in (*pos.basis, *sigma.basis)):
            return False, f"the Gram matrices {at} may not depend on the box's variables"
        ok, why = check_positive_definite_v(pos, n)
        if not ok:
            return False, f"{why} ({at})"
        if not has_pure_powers(sigma.basis, range(n)):
            return False, f"sigma's basis must hold a pure power of every state ({at})"
        if not sigma.positive_definite():
            return False, f"Q_sigma is not positive definite (exact, {at})"
        if at_vertex(ring, V, n, vertex) != pos.poly(ring):
            return False, f"V is not its Gram form {at}, exactly"
        if at_vertex(ring, P, n, vertex) != sigma.poly(ring):
            return False, f"the identity -grad V . g - mu V D = sigma does not hold exactly {at}"
    return True, (f"V and -grad V . g - mu V D are multi-affine in the box's parameters, and at each of the box's "
                  f"{len(vertices)} vertices Q_V > 0, Q_sigma > 0 and -grad V . g - mu V D = sigma, exactly")


@dataclass(frozen=True)
class GramSum:
    """A sum of Gram polynomials over overlapping bases, one per clique of the variables
    (:mod:`lyapcheck.sos.sparsity`). With every part's ``Q`` positive definite and every monomial
    of the union of the bases in some part, the sum is ``z^T Q z`` over that union with ``Q`` the
    sum of the parts' matrices padded with zeros, which is positive definite too: for ``v != 0``
    some part sees a non-zero ``v_k``, and ``v^T Q v = sum_k v_k^T Q_k v_k > 0``."""

    parts: tuple[GramPoly, ...]

    @property
    def basis(self) -> tuple[Monomial, ...]:
        """The union of the parts' bases, in first-seen order."""
        return tuple(dict.fromkeys(m for part in self.parts for m in part.basis))

    def poly(self, ring: Ring) -> Poly:
        total = ring.zero()
        for part in self.parts:
            total += part.poly(ring)
        return total

    def positive_definite(self) -> bool:
        return bool(self.parts) and all(part.positive_definite() for part in self.parts)


def check_lyapunov_cliques(ring: Ring, g: Sequence[Poly], D: Poly, V: GramSum, sigma: GramSum, mu: Fraction
                           ) -> tuple[bool, str]:
    """Lyapunov with ``V`` and ``sigma`` sums over cliques (:class:`GramSum`):
    ``-grad V . g - mu V D = sigma`` exactly, every part's ``Q`` positive definite, no constant in
    ``V``, and a pure power of every state in the union of ``V``'s bases and in that of ``sigma``'s:
    then ``V >= lambda sum_i z_i^(2 k_i)`` and ``sigma`` likewise, as for one Gram matrix."""
    n = len(g)
    if mu < 0:
        return False, "the decay rate mu must be >= 0"
    ok, why = check_positive_definite_v(V, n)  # (over the union of the bases; every part's Q_V > 0)
    if not ok:
        return False, why
    if not sigma.parts or not has_pure_powers(sigma.basis, range(n)):
        return False, "sigma's bases must hold a pure power of every state (so that V' < 0 away from 0)"
    if not sigma.positive_definite():
        return False, "a clique's Q_sigma is not positive definite (exact)"
    v = V.poly(ring)
    if -lie_derivative(ring, v, g) - v * D * _q(mu) != sigma.poly(ring):
        return False, "the identity -grad V . g - mu V D = sigma does not hold exactly"
    return True, (f"every clique's Q_V > 0 ({len(V.parts)}), Q_sigma > 0 ({len(sigma.parts)}) and "
                  "-grad V . g - mu V D = sigma, exactly")


def check_sublevel(ring: Ring, g: Sequence[Poly], V: GramPoly, level: Fraction, s: GramPoly, sigma: GramPoly,
                   box: BoxMultipliers = ()) -> tuple[bool, str]:
    """Sublevel: ``-grad V . g - s (c - V) = sigma`` with ``s``, ``sigma`` > 0 and ``V`` positive
    definite, radially unbounded: ``V' < 0`` on ``{V <= c}`` minus 0, a compact set."""
    n = len(g)
    if level <= 0:
        return False, "the level c must be > 0"
    ok, why = check_positive_definite_v(V, n)
    if not ok:
        return False, why
    if not has_pure_powers(sigma.basis, range(n)):
        return False, "sigma's basis must hold a pure power of every state (so that V' < 0 away from 0)"
    if any(sum(m) == 0 for m in s.basis):
        return False, "the multiplier s may not have a constant monomial (s(0) must be 0)"
    if not s.positive_definite() or not sigma.positive_definite():
        return False, "Q_s or Q_sigma is not positive definite (exact)"
    v = V.poly(ring)
    boxed, box_why = box_terms(ring, box)
    if box_why is not None:
        return False, box_why
    if -lie_derivative(ring, v, g) - s.poly(ring) * (ring.constant(level) - v) - boxed != sigma.poly(ring):
        return False, "the identity -grad V . g - s (c - V) = sigma does not hold exactly"
    return True, "Q_V, Q_s, Q_sigma > 0 and -grad V . g - s (c - V) = sigma, exactly" + (" (on the box)" if box else "")


def check_positivity(ring: Ring, p: Poly, c: Fraction, sigma: GramPoly, box: BoxMultipliers = ()) -> tuple[bool, str]:
    """Positivity: ``p - c = sigma`` with ``c > 0`` and ``Q_sigma >= 0`` (semidefinite suffices:
    ``sigma >= 0``, so ``p >= c``; a denominator such as ``(x + y)^2 + 1`` has no definite Gram)."""
    from lyapcheck.sos.definiteness import is_positive_semidefinite

    if c <= 0:
        return False, "the constant c must be > 0"
    if not is_positive_semidefinite(sigma.Q):
        return False, "Q_sigma is not positive semidefinite (exact)"
    boxed, box_why = box_terms(ring, box)
    if box_why is not None:
        return False, box_why
    if p - ring.constant(c) - boxed != sigma.poly(ring):
        return False, "the identity p - c = sigma does not hold exactly"
    return True, "p - c = sigma with c > 0 and Q_sigma >= 0, exactly"


def check_dissipation(ring: Ring, g: Sequence[Poly], D: Poly, bounds: Sequence[Fraction], V: GramPoly,
                      lam: Fraction, taus: Sequence[GramPoly], sigma: GramPoly, box: BoxMultipliers = (),
                      v0: Fraction = Fraction(0)) -> tuple[bool, str]:
    """Dissipation, in the ring of (states, disturbances): ``V = z^T Q_V z + v0`` with ``Q_V > 0``
    (``V >= lambda_min |z|^2 + v0``: radially unbounded; ``v0`` any constant), ``lam > 0``, every
    ``tau_k`` and ``sigma`` > 0, and the identity exactly."""
    n = len(g)
    if lam <= 0:
        return False, "the rate lam must be > 0"
    if len(taus) != len(bounds):
        return False, "one multiplier tau per disturbance is needed"
    if not V.basis or not has_pure_powers(V.basis, range(n)) or any(any(m[n:]) for m in V.basis):
        return False, "V's basis must hold a pure power of every state and no disturbance"
    if not V.positive_definite():
        return False, "Q_V is not positive definite (exact)"
    for tau in taus:
        if not tau.positive_definite():
            return False, "a multiplier tau is not positive definite (exact)"
    if not sigma.positive_definite():
        return False, "Q_sigma is not positive definite (exact)"
    v = V.poly(ring) + ring.constant(v0)
    lhs = -lie_derivative(ring, v, g) - (v - ring.constant(1)) * D * _q(lam)
    gens = ring.gens()
    for k, (tau, b) in enumerate(zip(taus, bounds)):
        d = gens[n + k]
        lhs -= tau.poly(ring) * (ring.constant(b * b) - d * d)
    boxed, box_why = box_terms(ring, box)
    if box_why is not None:
        return False, box_why
    if lhs - boxed != sigma.poly(ring):
        return False, "the dissipation identity does not hold exactly"
    return True, "V > 0, tau > 0, sigma > 0 and the dissipation identity holds, exactly"


def check_output_bound(ring: Ring, V: GramPoly, y: Poly, B: Fraction, sigma: GramPoly, box: BoxMultipliers = (),
                       v0: Fraction = Fraction(0)) -> tuple[bool, str]:
    """OutputBound: ``V - y^2 + B - 1 = sigma`` with ``Q_sigma > 0`` (so ``y^2 <= V + B - 1``;
    ``V = z^T Q_V z + v0`` as in :func:`check_dissipation`)."""
    if not sigma.positive_definite():
        return False, "Q_sigma is not positive definite (exact)"
    boxed, box_why = box_terms(ring, box)
    if box_why is not None:
        return False, box_why
    if V.poly(ring) + ring.constant(v0) - y * y + ring.constant(B - 1) - boxed != sigma.poly(ring):
        return False, "the identity V - y^2 + B - 1 = sigma does not hold exactly"
    return True, "V - y^2 + B - 1 = sigma with Q_sigma > 0, exactly"


def check_containment(ring: Ring, V: GramPoly, level: Fraction, p: Poly, radius_sq: Fraction, s: GramPoly,
                      sigma: GramPoly) -> tuple[bool, str]:
    """Containment: ``c - V - s (r^2 - p) = sigma``, ``s``, ``sigma`` > 0: ``{p <= r^2}`` lies in
    ``{V <= c}``."""
    if radius_sq <= 0:
        return False, "r^2 must be > 0"
    if not s.positive_definite() or not sigma.positive_definite():
        return False, "Q_s or Q_sigma is not positive definite (exact)"
    lhs = ring.constant(level) - V.poly(ring) - s.poly(ring) * (ring.constant(radius_sq) - p)
    if lhs != sigma.poly(ring):
        return False, "the identity c - V - s (r^2 - p) = sigma does not hold exactly"
    return True, "c - V - s (r^2 - p) = sigma with Q_s, Q_sigma > 0, exactly"


SetPiece = Sequence[Poly]
PieceCertificate = tuple[Sequence[GramPoly], GramPoly]


def piece_generators(piece: SetPiece) -> list[Poly]:
    """The products the S-procedure may use on a piece ``{p_1 >= 0, ..., p_m >= 0}``: each ``p_i``,
    then each ``p_i p_j`` (``i < j``, in that order), all ``>= 0`` on the piece. The pairs matter: on
    ``-1/2 <= x <= 1/2`` the product ``(x + 1/2)(1/2 - x)`` bounds a quadratic, which the two
    linear inequalities with constant multipliers cannot."""
    out = list(piece)
    for i in range(len(piece)):
        for j in range(i + 1, len(piece)):
            out.append(piece[i] * piece[j])
    return out


def _on_piece(ring: Ring, lhs: Poly, piece: SetPiece, cert: PieceCertificate, what: str) -> tuple[bool, str]:
    """``lhs - sum_k s_k h_k = r`` over the piece's :func:`piece_generators` ``h_k``, with every ``s_k``
    and ``r`` positive semidefinite (exact): then ``lhs >= 0`` wherever every ``p_i >= 0`` (the
    S-procedure on one piece of a set)."""
    from lyapcheck.sos.definiteness import is_positive_semidefinite

    multipliers, remainder = cert
    generators = piece_generators(piece)
    if len(multipliers) != len(generators):
        return False, f"{what}: one multiplier per inequality of the piece and per pair of them is needed"
    total = lhs
    for s, p in zip(multipliers, generators):
        if not is_positive_semidefinite(s.Q):
            return False, f"{what}: a multiplier is not positive semidefinite (exact)"
        total -= s.poly(ring) * p
    if not is_positive_semidefinite(remainder.Q):
        return False, f"{what}: the remainder is not positive semidefinite (exact)"
    if total != remainder.poly(ring):
        return False, f"{what}: the identity does not hold exactly"
    return True, f"{what}: holds exactly"


def _on_sets(ring: Ring, F: Poly, name: str, initial: Sequence[SetPiece], initial_certs: Sequence[PieceCertificate],
             unsafe: Sequence[SetPiece], unsafe_certs: Sequence[PieceCertificate]) -> tuple[bool, str]:
    """``F <= 0`` on every initial piece and ``F >= 1`` on every unsafe piece (:func:`_on_piece`): the
    part a barrier ``B`` and a reach-avoid ``V`` share."""
    if len(initial_certs) != len(initial) or len(unsafe_certs) != len(unsafe):
        return False, "one certificate per piece of the initial and the unsafe set is needed"
    for k, (piece, cert) in enumerate(zip(initial, initial_certs)):
        ok, why = _on_piece(ring, -F, piece, cert, f"initial piece {k + 1} ({name} <= 0)")
        if not ok:
            return False, why
    for k, (piece, cert) in enumerate(zip(unsafe, unsafe_certs)):
        ok, why = _on_piece(ring, F - ring.constant(1), piece, cert, f"unsafe piece {k + 1} ({name} >= 1)")
        if not ok:
            return False, why
    return True, f"{name} <= 0 on the initial set and {name} >= 1 on the unsafe set"


def check_on_sets(ring: Ring, F: Poly, name: str, initial: Sequence[SetPiece],
                  initial_certs: Sequence[PieceCertificate], unsafe: Sequence[SetPiece],
                  unsafe_certs: Sequence[PieceCertificate]) -> tuple[bool, str]:
    """``F <= 0`` on every initial piece and ``F >= 1`` on every unsafe piece, each by its S-procedure
    identity with exact positive semidefinite multipliers and remainder: the part of a barrier that does
    not depend on the dynamics (a discrete-time map's barrier,
    :mod:`lyapcheck.models.classes.discrete_safety`, pairs it with its own step condition)."""
    return _on_sets(ring, F, name, initial, initial_certs, unsafe, unsafe_certs)


def _rate_identity(ring: Ring, g: Sequence[Poly], D: Poly, P: Poly, rate: Fraction, remainder: GramPoly,
                   box: BoxMultipliers, what: str, left: str) -> str | None:
    """``-grad P . g + rate P D - sum_k r_k (1 - u_k^2) = sigma`` with ``sigma`` (and the ``r``) positive
    semidefinite, exactly: ``P' <= rate P`` for every ``u`` in the box (a barrier's decrease, a goal's
    invariance). None, or why not (``what``: the remainder's name, ``left``: the identity's left side)."""
    from lyapcheck.sos.definiteness import is_positive_semidefinite

    if not is_positive_semidefinite(remainder.Q):
        return f"the {what} remainder is not positive semidefinite (exact)"
    boxed, box_why = box_terms(ring, box)
    if box_why is not None:
        return box_why
    if -lie_derivative(ring, P, g) + P * D * _q(rate) - boxed != remainder.poly(ring):
        return f"the identity {left} = sigma does not hold exactly"
    return None


def check_barrier(ring: Ring, g: Sequence[Poly], D: Poly, B: Poly, lam: Fraction,
                  initial: Sequence[SetPiece], initial_certs: Sequence[PieceCertificate],
                  unsafe: Sequence[SetPiece], unsafe_certs: Sequence[PieceCertificate],
                  decrease: GramPoly, box: BoxMultipliers = ()) -> tuple[bool, str]:
    """Barrier: no trajectory of ``z' = g / D`` (``D > 0``) that starts in the initial set ever enters
    the unsafe set, on its whole interval of existence, for every ``u`` in the box (the ring's
    variables after the states: disturbances as ``d = b u``, or a box of parameters).

    Each set is a union of pieces, a piece an intersection of ``p >= 0``. The certificate:
    ``B <= 0`` on every initial piece, ``B >= 1`` on every unsafe piece (each by
    :func:`_on_piece`), and ``-grad B . g + lam B D - sum_k r_k (1 - u_k^2) = sigma`` with every
    Gram matrix positive semidefinite, so ``B' = grad B . g / D <= lam B`` everywhere (for every
    ``u`` in the box). Then ``B(t) exp(-lam t)`` never increases, ``B`` stays ``<= 0`` along a
    trajectory that starts with ``B <= 0`` (any real ``lam``), and the unsafe set, where ``B >= 1``,
    is never reached. ``B`` depends on the states only (a disturbance's value may change at any time)."""
    n = len(g)
    if any(any(m[n:]) for m in ring.support(B)):
        return False, "B may depend on the states only"
    ok, why = _on_sets(ring, B, "B", initial, initial_certs, unsafe, unsafe_certs)
    if not ok:
        return False, why
    failed = _rate_identity(ring, g, D, B, lam, decrease, box, "decrease", "-grad B . g + lam B D")
    if failed is not None:
        return False, failed
    return True, ("B <= 0 on the initial set, B >= 1 on the unsafe set and B' <= lam B everywhere"
                  + (" (for every value in the box)" if box else "") + ", exactly")


def check_reach_avoid(ring: Ring, g: Sequence[Poly], D: Poly, V: Poly, eps: Fraction, C: Fraction, delta: Fraction,
                      initial: Sequence[SetPiece], initial_certs: Sequence[PieceCertificate],
                      unsafe: Sequence[SetPiece], unsafe_certs: Sequence[PieceCertificate],
                      goal: SetPiece, goal_certs: Sequence[tuple[GramPoly, GramPoly]], bounded: GramPoly,
                      box_per_goal: Sequence[BoxMultipliers] = ()) -> tuple[bool, str]:
    """ReachAvoid: every trajectory of ``z' = g / D`` (``D > 0``) from the initial set reaches the goal
    ``{q_1 >= 0, ..., q_m >= 0}`` (one piece) within time ``C / eps`` and does not enter the unsafe
    set before, for every ``u`` in the box.

    * ``V <= 0`` on every initial piece and ``V >= 1`` on every unsafe piece (:func:`_on_piece`);
    * for each ``i``: ``-grad V . g - eps D + s_i q_i - sum_k r_ik (1 - u_k^2) = sigma_i`` with ``s_i``,
      ``sigma_i`` (and the ``r``) positive semidefinite: where ``q_i <= 0`` (outside the goal some
      ``q_i < 0``), ``V' = grad V . g / D <= -eps``;
    * ``V + C - delta |z|^2 = sigma_B``, ``delta > 0``: ``V >= delta |z|^2 - C``.

    So from a start with ``V <= 0``, while outside the goal ``V`` falls at least at rate ``eps``,
    stays ``<= 0`` (the unsafe set, where ``V >= 1``, is not reached) and within the compact
    ``{V <= 0}`` (no escape); it cannot fall below ``-C``, so the goal is reached by ``C / eps``."""
    from lyapcheck.sos.definiteness import is_positive_semidefinite

    n = len(g)
    if any(any(m[n:]) for m in ring.support(V)):
        return False, "V may depend on the states only"
    if not (eps > 0 and delta > 0 and C >= 0):
        return False, "eps and delta must be > 0 and C >= 0"
    if len(goal_certs) != len(goal):
        return False, "one certificate per inequality of the goal is needed"
    ok, why = _on_sets(ring, V, "V", initial, initial_certs, unsafe, unsafe_certs)
    if not ok:
        return False, why
    boxes = list(box_per_goal) or [()] * len(goal)
    if len(boxes) != len(goal):
        return False, "one set of box multipliers per inequality of the goal"
    decrease = -lie_derivative(ring, V, g) - D * _q(eps)
    for i, (q, (s, sigma), box) in enumerate(zip(goal, goal_certs, boxes)):
        if not is_positive_semidefinite(s.Q) or not is_positive_semidefinite(sigma.Q):
            return False, f"goal inequality {i + 1}: a Gram matrix is not positive semidefinite (exact)"
        boxed, box_why = box_terms(ring, box)
        if box_why is not None:
            return False, box_why
        if decrease + s.poly(ring) * q - boxed != sigma.poly(ring):
            return False, (f"goal inequality {i + 1}: the identity -grad V . g - eps D + s q = sigma does not hold "
                           "exactly")
    if not is_positive_semidefinite(bounded.Q):
        return False, "the bound V >= delta |z|^2 - C: its Gram matrix is not positive semidefinite (exact)"
    radius = ring.zero()
    for z in ring.gens()[:n]:
        radius += z * z
    if V + ring.constant(C) - radius * _q(delta) != bounded.poly(ring):
        return False, "the identity V + C - delta |z|^2 = sigma does not hold exactly"
    return True, ("V <= 0 on the initial set, V >= 1 on the unsafe set, V' <= -eps outside the goal and "
                  "V >= delta |z|^2 - C, exactly")


def check_goal_invariant(ring: Ring, g: Sequence[Poly], D: Poly, W: Poly, mu: Fraction, goal: SetPiece,
                         inside: Sequence[GramPoly], decrease: GramPoly, box: BoxMultipliers = ()) -> tuple[bool, str]:
    """GoalInvariant: ``{W <= 0}`` lies in the goal ``{q_1 >= 0, ..., q_m >= 0}`` and no trajectory
    leaves it, for every ``u`` in the box: ``W + q_i = sigma_i`` (so ``q_i >= -W >= 0`` where
    ``W <= 0``) and ``-grad W . g + mu W D - sum_k r_k (1 - u_k^2) = sigma`` (``W' <= mu W``, so
    ``W(t) exp(-mu t)`` never increases and ``W`` stays ``<= 0``), every Gram matrix positive
    semidefinite, and ``W(0) < 0`` (the equilibrium inside)."""
    from lyapcheck.sos.definiteness import is_positive_semidefinite

    n = len(g)
    if any(any(m[n:]) for m in ring.support(W)):
        return False, "W may depend on the states only"
    if not ring.evaluate(W, [Fraction(0)] * ring.nvars) < 0:
        return False, "W(0) must be < 0 (the equilibrium inside {W <= 0})"
    if len(inside) != len(goal):
        return False, "one Gram matrix per inequality of the goal is needed"
    for i, (q, sigma) in enumerate(zip(goal, inside)):
        if not is_positive_semidefinite(sigma.Q) or W + q != sigma.poly(ring):
            return False, f"goal inequality {i + 1}: W + q = sigma does not hold with sigma >= 0 (exact)"
    failed = _rate_identity(ring, g, D, W, mu, decrease, box, "invariance", "-grad W . g + mu W D")
    if failed is not None:
        return False, failed
    return True, "{W <= 0} lies in the goal and W' <= mu W, exactly: no trajectory leaves it"


def sphere_bound(a: Monomial) -> Fraction:
    """A rational ``k >= max |z^a|`` over the unit sphere ``|z| = 1``: the maximum is
    ``sqrt(prod_j a_j^a_j / |a|^|a|)`` (at ``z_j^2 = a_j / |a|``, by the weighted AM-GM inequality),
    rounded up exactly; 1 for a pure power."""
    from lyapcheck.exact import sqrt_upper

    total = sum(a)
    if max(a) == total:
        return Fraction(1)
    square = Fraction(1)
    for e in a:
        if e:
            square *= Fraction(e, total) ** e
    return min(Fraction(1), sqrt_upper(square, 6))


def check_quadratic_ball(ring: Ring, g: Sequence[Poly], V: GramPoly, level: Fraction, radius: Fraction,
                         lam: Fraction, p_bar: Fraction, m: Fraction) -> tuple[bool, str]:
    """QuadraticBall: ``{V <= c}`` minus the equilibrium has ``grad V . g > 0`` nowhere.

    With ``V = z^T P z`` (``P`` over the states' degree-1 monomials), ``g = L z + h(z)`` (``h``: the
    terms of degree 2 and more; ``g(0) = 0``) and ``M = -(P L + L^T P)``, the certificate states
    rationals with ``P >= lam I``, ``P <= p_bar I``, ``M >= m I`` (``lam, m > 0``), and ``r``. Then

        -grad V . g = z^T M z - 2 (P z) . h(z) >= |z| (m |z| - 2 p_bar |h(z)|),

    and ``|h_i(z)| <= b_i(|z|) = sum_a |h_ia| k_a |z|^|a|`` (:func:`sphere_bound`: ``|z^a| <= k_a
    |z|^|a|``); as every ``b_i(rho) /
    rho`` grows with ``rho``, ``m^2 r^2 > 4 p_bar^2 sum_i b_i(r)^2`` gives ``-grad V . g > 0`` for
    ``0 < |z| <= r``. With ``c <= lam r^2`` the compact set ``{V <= c}`` lies in ``{|z| <= r}``, so
    ``V' < 0`` on it away from 0 (``D > 0``): every start in it converges to the equilibrium."""
    from lyapcheck.sos.definiteness import is_positive_semidefinite

    n = len(g)
    if ring.nvars != n:
        return False, "a quadratic-ball certificate is for a point of parameters with no disturbance ring"
    if not (level > 0 and radius > 0 and lam > 0 and m > 0 and p_bar > 0):
        return False, "the level, the radius and the bounds lam, p_bar, m must be > 0"
    order = [tuple(int(k == i) for k in range(n)) for i in range(n)]
    if sorted(V.basis) != sorted(order) or len(V.basis) != n:
        return False, "V must be quadratic: its basis is the states, once each"
    idx = [V.basis.index(e) for e in order]
    P = [[V.Q[idx[i]][idx[j]] for j in range(n)] for i in range(n)]
    L = [[Fraction(0)] * n for _ in range(n)]
    b_sq = Fraction(0)
    for i, gi in enumerate(g):
        bound = Fraction(0)
        for mono, c in ring.terms(gi).items():
            degree = sum(mono)
            if degree == 0:
                return False, "the field does not vanish at the equilibrium"
            if degree == 1:
                L[i][mono.index(1)] = Fraction(c)
            else:
                bound += abs(Fraction(c)) * sphere_bound(mono) * radius ** degree
        b_sq += bound * bound
    M = [[-sum(P[i][k] * L[k][j] + L[k][i] * P[k][j] for k in range(n)) for j in range(n)] for i in range(n)]
    eye = [[Fraction(int(i == j)) for j in range(n)] for i in range(n)]
    if not is_positive_semidefinite([[P[i][j] - lam * eye[i][j] for j in range(n)] for i in range(n)]):
        return False, "P >= lam I does not hold (exact)"
    if not is_positive_semidefinite([[p_bar * eye[i][j] - P[i][j] for j in range(n)] for i in range(n)]):
        return False, "P <= p_bar I does not hold (exact)"
    if not is_positive_semidefinite([[M[i][j] - m * eye[i][j] for j in range(n)] for i in range(n)]):
        return False, "-(P L + L^T P) >= m I does not hold (exact)"
    if not m * m * radius * radius > 4 * p_bar * p_bar * b_sq:
        return False, "m^2 r^2 > 4 p_bar^2 sum_i b_i(r)^2 does not hold: the radius is too large"
    if level > lam * radius * radius:
        return False, "the level exceeds lam r^2: the set is not inside the ball |z| <= r"
    return True, ("P >= lam I, P <= p_bar I, -(P L + L^T P) >= m I and m^2 r^2 > 4 p_bar^2 sum b_i(r)^2, "
                  "exactly: V' < 0 on {V <= c} minus the equilibrium")


def _q(x: Fraction) -> Any:
    import flint

    return flint.fmpq(x.numerator, x.denominator)
