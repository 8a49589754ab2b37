"""The certified sets of a certificate document, as regions of the (eps, s) plane (SI).

Each certified ultimate bound says where every trajectory ends; the phase portrait draws those
regions beside the simulated trajectories. Three are read from a certificate document:

``sos_bound``          the sublevel set ``{V <= 1}`` of the polynomial storage function ``V`` of
                       :mod:`lyapcheck.paper.conditions.sos_bound` (``limsup V <= 1`` from every start):
                       a contour of the exact certificate, see :func:`sos_bound_set`;
``ultimate_bound``     the ellipsoid ``x^T P x <= 1`` of its last stage, exact;
``ultimate_bound``     the comparison-lemma box ``|eps| <= E, |s| <= S`` (stage 0), exact.

Every set carries a *gauge*: a function of points that is ``<= 1`` exactly on the set (``V``,
``x^T P x``, ``max(|eps|/E, |s|/S)``), so a trajectory can be tested against the certificate
itself, not against the drawn polygon.

The ``sos_bound`` contour. In the certificate's coordinates ``y = (eps + sigma0 s)/Delta``,
``r = sigma0 s/Delta = beta r~``, ``V`` is a quartic in ``(y, r~)``. The grid is laid out in
``(u, r~)`` with ``u = y - beta r~ = eps/Delta``, where the set is well proportioned and aligned
with the cross-track error, and mapped back linearly: ``eps = Delta u``,
``s = Delta beta r~/sigma0``. Its extent is known before any sampling: the exactly checked output
identity ``V - u^2 + (B - 1) = z^T Q_E z >= 0`` gives ``u^2 <= B`` on ``{V <= 1}``, and for each
``u`` the ``r~`` where ``V = 1`` are the real roots of a quartic (its leading coefficient is the
top-degree part of ``V`` at ``(beta, 1)``, positive because that part is positive definite).
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass
from fractions import Fraction
from typing import Any, Callable, Final

import numpy as np
import numpy.typing as npt

from reports.typeset import parse_fraction, parse_matrix
from reports.views import as_dict

log = logging.getLogger(__name__)

FloatArray = npt.NDArray[np.float64]

#: grid of the sos_bound contour, points per axis: the boundary is drawn to a 400th of the set's
#: width (0.002 mm in eps at the paper's gains), far below what a figure shows
GRID_POINTS: Final = 401
#: the grid reaches this fraction of the set's extent beyond it on every side
GRID_MARGIN: Final = 0.06
#: columns at which the r~-extent of the sos_bound set is found (quartic roots)
EXTENT_COLUMNS: Final = 801


@dataclass(frozen=True)
class CertifiedSet:
    """A region of the (eps, s) plane where every trajectory ends (metres).

    Attributes
    ----------
    name
        The condition class that certifies it.
    kind
        ``"sublevel"``, ``"ellipsoid"`` or ``"box"``.
    label
        Legend text.
    boundary
        Closed polylines, rows ``(eps, s)``.
    eps_bound_m
        The class's certified ``limsup |eps|`` for this set.
    gauge
        ``gauge(points)`` (rows ``(eps, s)``) is ``<= 1`` exactly on the set.
    resolution_eps_m
        How far the drawn boundary may lie from the true one along eps (0 when exact).
    description
        One clause for a caption.
    """

    name: str
    kind: str
    label: str
    boundary: tuple[FloatArray, ...]
    eps_bound_m: float
    gauge: Callable[[FloatArray], FloatArray]
    resolution_eps_m: float
    description: str

    @property
    def key(self) -> str:
        """Unique among a document's sets: ``"sos_bound sublevel"``, ``"ultimate_bound box"``, ..."""
        return f"{self.name} {self.kind}"

    @property
    def short(self) -> str:
        """``"the sos_bound set"``, ``"the ultimate_bound ellipsoid"``, ..."""
        return f"the {self.name} {'set' if self.kind == 'sublevel' else self.kind}"

    @property
    def points(self) -> FloatArray:
        return np.vstack(self.boundary)

    @property
    def max_abs_eps_m(self) -> float:
        """The largest ``|eps|`` of the drawn boundary."""
        return float(np.max(np.abs(self.points[:, 0])))

    @property
    def bbox(self) -> tuple[FloatArray, FloatArray]:
        pts = self.points
        return pts.min(axis=0), pts.max(axis=0)


def _certified(doc: dict[str, Any], name: str) -> dict[str, Any]:
    cond = as_dict(as_dict(doc.get("conditions")).get(name))
    return cond if cond.get("status") == "certified" else {}


# ----------------------------------------------------------------------------------------------
# sos_bound: the sublevel set {V <= 1}
# ----------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class StoragePolynomial:
    """``V`` of an ``sos_bound`` certificate in ``(u, r~)``, float coefficients ``c[i, j]`` of ``u^i r~^j``."""

    coefficients: FloatArray
    beta: float
    b: float
    delta: float
    sigma0: float

    def __call__(self, u: FloatArray, r: FloatArray) -> FloatArray:
        c = self.coefficients
        out = np.zeros(np.broadcast(u, r).shape)
        for i in range(c.shape[0] - 1, -1, -1):  # Horner in u over polynomials in r
            row = np.zeros_like(out)
            for j in range(c.shape[1] - 1, -1, -1):
                row = row * r + c[i, j]
            out = out * u + row
        return out

    def to_scaled(self, points: FloatArray) -> tuple[FloatArray, FloatArray]:
        """``(u, r~)`` of rows ``(eps, s)`` in metres."""
        return points[:, 0] / self.delta, points[:, 1] * self.sigma0 / (self.delta * self.beta)

    def from_scaled(self, u: FloatArray, r: FloatArray) -> FloatArray:
        return np.column_stack([self.delta * u, self.delta * self.beta * r / self.sigma0])

    def gauge(self, points: FloatArray) -> FloatArray:
        u, r = self.to_scaled(np.atleast_2d(np.asarray(points, dtype=np.float64)))
        return self(u, r)

    def r_extent(self, u: FloatArray) -> tuple[float, float] | None:
        """Smallest and largest ``r~`` with ``V(u, r~) = 1`` over the columns ``u`` (None: no root)."""
        c = self.coefficients
        # coefficient of r~^j at each u: sum_i c[i, j] u^i
        powers = np.vander(u, c.shape[0], increasing=True)
        rows = powers @ c  # (n, degree in r + 1), increasing powers of r~
        rows[:, 0] -= 1.0
        lead = rows[:, -1]
        if not np.all(lead > 0):
            return None
        deg = c.shape[1] - 1
        companion = np.zeros((u.size, deg, deg))
        companion[:, 1:, :-1] = np.eye(deg - 1)
        companion[:, :, -1] = -rows[:, :-1] / lead[:, None]
        roots = np.linalg.eigvals(companion)
        scale = np.maximum(1.0, np.abs(roots))
        real = np.abs(roots.imag) <= 1e-9 * scale
        if not np.any(real):
            return None
        values = roots.real[real]
        return float(values.min()), float(values.max())


def storage_polynomial(doc: dict[str, Any]) -> StoragePolynomial | None:
    """``V`` of the document's certified ``sos_bound`` (exact composition, then floats)."""
    from lyapcheck import exact
    from lyapcheck.paper import poly
    from lyapcheck.paper.conditions.sos_bound import Z_V

    cert = as_dict(_certified(doc, "sos_bound").get("certificate"))
    system = as_dict(doc.get("system"))
    beta, b = parse_fraction(cert.get("beta")), parse_fraction(cert.get("B"))
    delta, sigma0 = parse_fraction(system.get("delta")), parse_fraction(system.get("sigma0"))
    try:  # not parse_matrix: exact entries of any length
        q_v = exact.from_json(cert["Q_V"])
    except (KeyError, TypeError, ValueError, ZeroDivisionError):
        return None
    if beta is None or b is None or delta is None or sigma0 is None or len(q_v) != len(Z_V) \
            or any(len(row) != len(Z_V) for row in q_v):
        return None
    if not (beta > 0 and b > 0 and delta > 0 and sigma0 > 0):
        return None
    V = poly.gram_form(Z_V, q_v)
    # y = u + beta r~: compose exactly, then round once
    y: poly.Poly = {(1, 0): Fraction(1), (0, 1): beta}
    composed: poly.Poly = {}
    for (i, j), coefficient in V.items():
        term: poly.Poly = {(0, j): Fraction(coefficient)}
        for _ in range(i):
            term = poly.mul(term, y)
        composed = poly.add(composed, term)
    degree = max((sum(m) for m in composed), default=0)
    c = np.zeros((degree + 1, degree + 1))
    for (i, j), coefficient in composed.items():
        c[i, j] = float(coefficient)
    return StoragePolynomial(c, float(beta), float(b), float(delta), float(sigma0))


def level_set_boundary(x: FloatArray, y: FloatArray, z: FloatArray, level: float = 1.0) -> list[FloatArray]:
    """The polylines where ``z`` (shape ``(len(x), len(y))``) crosses ``level`` (linear interpolation)."""
    import contourpy

    gen = contourpy.contour_generator(x, y, z.T, line_type=contourpy.LineType.Separate)
    return [np.asarray(line, dtype=np.float64) for line in gen.lines(level) if len(line) > 2]


def sos_bound_set(doc: dict[str, Any], n: int = GRID_POINTS) -> tuple[CertifiedSet | None, str]:
    """The set ``{V <= 1}`` of the document's ``sos_bound`` certificate; (set, reason if none)."""
    cond = _certified(doc, "sos_bound")
    if not cond:
        return None, "sos_bound is not certified"
    V = storage_polynomial(doc)
    bound = cond.get("eps_bound_m")
    if V is None or not isinstance(bound, (int, float)):
        return None, "the sos_bound certificate lacks V (Q_V, beta, B) or the system's Delta and sigma0"
    u_max = math.sqrt(V.b)  # |u| <= sqrt(B) on the set (module docstring)
    extent = V.r_extent(np.linspace(-u_max, u_max, EXTENT_COLUMNS))
    if extent is None:
        return None, "the sos_bound storage function has no point with V <= 1 on the grid"
    r_lo, r_hi = extent
    pad_u, pad_r = GRID_MARGIN * 2 * u_max, GRID_MARGIN * max(r_hi - r_lo, 1e-12)
    u = np.linspace(-u_max - pad_u, u_max + pad_u, n)
    r = np.linspace(r_lo - pad_r, r_hi + pad_r, n)
    z = V(u[:, None], r[None, :])
    border = np.concatenate([z[0], z[-1], z[:, 0], z[:, -1]])
    if np.any(border <= 1.0):
        return None, "the sos_bound sublevel set reaches beyond what its output certificate allows (|eps| <= Delta sqrt(B))"
    lines = level_set_boundary(u, r, z)
    if not lines:
        return None, "the sos_bound sublevel set is empty on the grid"
    boundary = tuple(V.from_scaled(line[:, 0], line[:, 1]) for line in lines)
    step = float(u[1] - u[0]) * V.delta
    eps_extent = max(float(np.max(np.abs(line[:, 0]))) for line in boundary)
    return CertifiedSet(
        name="sos_bound", kind="sublevel", label="certified: every trajectory ends inside (sos_bound)", boundary=boundary,
        eps_bound_m=float(bound), gauge=V.gauge, resolution_eps_m=step,
        description=(f"the sublevel set V <= 1 of the polynomial storage function of sos_bound (contour of the exact "
                     f"certificate on a {n} x {n} grid), where every trajectory ends; its eps-extent is "
                     f"{eps_extent * 1e3:.4g} mm as drawn, within the certified limsup |eps| <= "
                     f"{float(bound) * 1e3:.4g} mm"),
    ), ""


# ----------------------------------------------------------------------------------------------
# ultimate_bound: the ellipsoid of its last stage and the box of stage 0
# ----------------------------------------------------------------------------------------------
def ellipse_points(P: FloatArray, n: int = 361) -> FloatArray:
    """Boundary of ``{x : x^T P x <= 1}`` for a 2x2 positive definite ``P`` (rows of points)."""
    w, v = np.linalg.eigh(P)
    t = np.linspace(0.0, 2 * math.pi, n)
    return (v @ (np.vstack([np.cos(t), np.sin(t)]) / np.sqrt(w)[:, None])).T


def ellipsoid_set(doc: dict[str, Any]) -> CertifiedSet | None:
    cond = _certified(doc, "ultimate_bound")
    stages = as_dict(cond.get("certificate")).get("stages")
    found: list[tuple[float, FloatArray, int]] = []
    for k, stage in enumerate(stages if isinstance(stages, list) else []):
        rows = parse_matrix(as_dict(stage).get("P"))
        if rows is None or len(rows) != 2 or len(rows[0]) != 2:
            continue
        P = np.array([[float(x) for x in r] for r in rows])
        if np.all(np.linalg.eigvalsh(P) > 0):
            found.append((math.sqrt(float(np.linalg.inv(P)[0, 0])), P, k + 1))
    if not found:
        return None
    # every stage's ellipsoid is certified; the one with the smallest eps-extent is the class's bound
    bound, P, stage_no = min(found, key=lambda f: f[0])

    def gauge(points: FloatArray) -> FloatArray:
        x = np.atleast_2d(np.asarray(points, dtype=np.float64))
        return np.einsum("ni,ij,nj->n", x, P, x)

    return CertifiedSet("ultimate_bound", "ellipsoid", "certified ellipsoid $x^T P x \\leq 1$ (ultimate_bound)",
                        (ellipse_points(P),), bound, gauge, 0.0,
                        f"the ellipsoid x^T P x <= 1 of ultimate_bound's stage {stage_no} (|eps| <= {bound * 1e3:.4g} mm)")


def box_set(doc: dict[str, Any]) -> CertifiedSet | None:
    cond = _certified(doc, "ultimate_bound")
    box = as_dict(as_dict(cond.get("certificate")).get("box"))
    e, s = parse_fraction(box.get("eps_bound")), parse_fraction(box.get("s_bound"))
    if e is None or s is None or e <= 0 or s <= 0:
        return None
    E, S = float(e), float(s)

    def gauge(points: FloatArray) -> FloatArray:
        x = np.atleast_2d(np.asarray(points, dtype=np.float64))
        return np.maximum(np.abs(x[:, 0]) / E, np.abs(x[:, 1]) / S)

    shape = np.array([[-E, -S], [E, -S], [E, S], [-E, S], [-E, -S]])
    return CertifiedSet("ultimate_bound", "box", "certified box (ultimate_bound, stage 0)", (shape,), E, gauge, 0.0,
                        f"the box |eps| <= {E * 1e3:.4g} mm, |s| <= {S * 1e3:.4g} mm of ultimate_bound (stage 0)")


def certified_sets(doc: dict[str, Any]) -> tuple[list[CertifiedSet], list[str]]:
    """Every certified set of the document, tightest (smallest eps bound) first; (sets, notes)."""
    notes: list[str] = []
    sos, why = sos_bound_set(doc)
    if sos is None and _certified(doc, "sos_bound"):
        notes.append(f"The sos_bound set is not drawn: {why}.")
        log.warning("sos_bound set not drawn: %s", why)
    sets = [s for s in (sos, ellipsoid_set(doc), box_set(doc)) if s is not None]
    sets.sort(key=lambda s: s.eps_bound_m)
    return sets, notes
