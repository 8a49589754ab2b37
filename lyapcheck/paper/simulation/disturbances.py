"""Disturbance velocities ``d_mu`` (eq:notation) for the batched closed loop.

Every disturbance is a velocity in the world frame ``(x, z)`` of Section 2 (``z`` up, against
gravity), in m/s, one row per trajectory. The closed loop calls :meth:`Disturbance.velocity`
with the time, the state, and the commanded rotation ``u`` (needed by the weight model, whose
velocity depends on the swimmer's axis, H2). Kinds:

=================  =======================================================================
``NoDisturbance``   ``d_mu = 0``
``Constant``        a constant vector per trajectory
``Weight``          the weight ``f = (0, -W)`` mapped through ``D`` with the swimmer's axis
                    along ``u`` (eq:tmp3 under H2), evaluated by :mod:`symbolic.rft`
``Sinusoid``        ``offset + amplitude sin(omega t + phase)``, per component
``PiecewiseConstant``  random values, uniform in the disc ``|d| <= bound``, held for ``hold``
                    seconds each, drawn from ``numpy.random.default_rng(seed)``
``Adversarial``     ``|d| <= bound`` across the path, pushing ``V = x^T P x`` up as hard as
                    the bound allows (``x = (eps, s)``)
``Feedback``        ``|d| <= bound`` across the path, ``bound * sat(sigma(eps, s)/layer)``
                    for a polynomial switching function ``sigma`` (e.g. the gradient of a
                    certified polynomial storage function, or ``eps`` itself)
``BangBang``        ``+-bound`` along a fixed direction, switching sign at given times
``SquareWave``      ``bound * sign(sin(omega t + phase))`` along a fixed direction (a
                    ``BangBang`` with its switching times generated up to a horizon)
``Stacked``         rows of different kinds in one batch (each part evaluates its own rows)
=================  =======================================================================

All of them are :class:`Disturbance` objects that can be sliced (``take``) along with the
batch, and report their time discontinuities (``next_breakpoint``) so that the integrator
lands on them.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, Final

import numpy as np
import numpy.typing as npt

FloatArray = npt.NDArray[np.float64]
IntArray = npt.NDArray[np.intp]

#: default half-width of the adversarial disturbance's boundary layer, as a fraction of the
#: look-ahead distance Delta_LOS (see :class:`Adversarial`)
ADVERSARIAL_LAYER_FRACTION: Final = 1e-3


def _rows(name: str, value: npt.ArrayLike, n: int, width: int | None = None) -> FloatArray:
    """Broadcast a per-trajectory parameter to ``(n,)`` or ``(n, width)``."""
    arr = np.asarray(value, dtype=np.float64)
    shape: tuple[int, ...] = (n,) if width is None else (n, width)
    try:
        out = np.broadcast_to(arr, shape).copy()
    except ValueError:
        raise ValueError(f"The '{name}' parameter must broadcast to shape {shape}. Got shape {arr.shape} instead.") from None
    if not np.all(np.isfinite(out)):
        raise ValueError(f"The '{name}' parameter must be finite. Got {value!r} instead.")
    return out


class Disturbance:
    """Base class: a batch of disturbance velocities (subclasses implement ``velocity``)."""

    #: short name used in reports and JSON
    kind: str = "none"

    @property
    def size(self) -> int | None:
        """Batch size, or ``None`` if the disturbance broadcasts to any batch."""
        return None

    def velocity(self, t: FloatArray, t_segment: FloatArray, eps: FloatArray, s: FloatArray,
                 u: FloatArray) -> FloatArray:
        """``d_mu`` in the world frame, shape ``(n, 2)``, m/s."""
        raise NotImplementedError

    def take(self, index: IntArray) -> "Disturbance":
        return self

    def next_breakpoint(self, t: FloatArray) -> FloatArray:
        return np.full(t.shape, np.inf)

    def bound(self) -> FloatArray | None:
        """An upper bound on ``|d_mu|`` per trajectory when one is known a priori."""
        return None

    #: number of columns :meth:`switching` returns
    n_switches: int = 0

    def switching(self, eps: FloatArray, s: FloatArray) -> FloatArray | None:
        """Functions ``(n, n_switches)`` whose zeros are kinks of ``d_mu`` in the state (or ``None``)."""
        return None

    def describe(self) -> dict[str, Any]:
        """JSON-ready description (SI, units in the key names)."""
        return {"kind": self.kind}


@dataclass(frozen=True)
class NoDisturbance(Disturbance):
    """``d_mu = 0``."""

    kind = "none"

    def velocity(self, t: FloatArray, t_segment: FloatArray, eps: FloatArray, s: FloatArray,
                 u: FloatArray) -> FloatArray:
        return np.zeros((t.shape[0], 2))

    def bound(self) -> FloatArray | None:
        return np.zeros(1)


@dataclass(frozen=True)
class Constant(Disturbance):
    """A constant velocity per trajectory, ``(n, 2)`` or ``(2,)`` (broadcast), m/s."""

    vector: FloatArray
    kind = "constant"
    note: str = ""

    def __post_init__(self) -> None:
        arr = np.asarray(self.vector, dtype=np.float64)
        if arr.shape[-1:] != (2,) or arr.ndim > 2 or not np.all(np.isfinite(arr)):
            raise ValueError(f"The 'vector' parameter must be finite with shape (2,) or (n, 2). Got {self.vector!r} instead.")
        object.__setattr__(self, "vector", arr)

    @property
    def size(self) -> int | None:
        return None if self.vector.ndim == 1 else self.vector.shape[0]

    def velocity(self, t: FloatArray, t_segment: FloatArray, eps: FloatArray, s: FloatArray,
                 u: FloatArray) -> FloatArray:
        return np.broadcast_to(self.vector, (t.shape[0], 2))

    def take(self, index: IntArray) -> "Constant":
        return self if self.vector.ndim == 1 else Constant(self.vector[index], note=self.note)

    def bound(self) -> FloatArray | None:
        return np.atleast_1d(np.hypot(self.vector[..., 0], self.vector[..., 1]))

    def describe(self) -> dict[str, Any]:
        out: dict[str, Any] = {"kind": self.kind, "velocity_m_s": _scalar_or_list(np.atleast_2d(self.vector))}
        if self.note:
            out["note"] = self.note
        return out


@dataclass(frozen=True)
class Weight(Disturbance):
    """The weight mapped through ``D`` with the swimmer's axis along ``u`` (eq:tmp3, H2).

    ``d_mu = (1/a1)(f.k)k + (1/a2)(f.k_perp)k_perp`` with ``f = (0, -weight)`` and
    ``k = u/|u|``; ``a1``, ``a2`` come from :func:`symbolic.rft.rft_constants`. Where
    ``u = 0`` the axis is undefined; the path direction ``e_r`` is used there (a measure-zero
    set the closed loop does not visit: ``u`` has the component ``alpha_d Delta`` along the path
    unless saturated against it).

    Parameters
    ----------
    weight
        ``|d_g|`` in N, per trajectory or scalar.
    a1, a2
        Drag constants of Table table:micro in N s/m, per trajectory or scalar.
    theta_r
        Path angle (rad), for the fallback axis.
    """

    weight: FloatArray
    a1: FloatArray
    a2: FloatArray
    theta_r: FloatArray
    kind = "weight"
    note: str = ""
    details: dict[str, Any] = field(default_factory=dict, compare=False)

    def __post_init__(self) -> None:
        arrays = {name: np.atleast_1d(np.asarray(getattr(self, name), dtype=np.float64))
                  for name in ("weight", "a1", "a2", "theta_r")}
        n = max(a.shape[0] for a in arrays.values())
        for name, arr in arrays.items():
            object.__setattr__(self, name, _rows(name, arr, n))
        if np.any(self.weight < 0) or np.any(self.a1 <= 0) or np.any(self.a2 <= 0):
            raise ValueError("The 'weight', 'a1' and 'a2' parameters must be >= 0, > 0, > 0. Got other values instead.")
        # rft.disturbance_velocity takes scalar a1, a2: one call per distinct pair (usually
        # one), grouped once here rather than at every evaluation
        pairs, inverse = np.unique(np.stack([self.a1, self.a2], axis=1), axis=0, return_inverse=True)
        object.__setattr__(self, "_pairs", (pairs, inverse.reshape(-1)))

    @property
    def size(self) -> int | None:
        return None if self.weight.shape[0] == 1 else self.weight.shape[0]

    def velocity(self, t: FloatArray, t_segment: FloatArray, eps: FloatArray, s: FloatArray,
                 u: FloatArray) -> FloatArray:
        from symbolic.rft import disturbance_velocity

        n = t.shape[0]
        norm = np.hypot(u[:, 0], u[:, 1])
        theta = np.broadcast_to(self.theta_r, (n,))
        fallback = np.stack([np.cos(theta), np.sin(theta)], axis=1)
        safe = np.where(norm > 0, norm, 1.0)
        axis = np.where((norm > 0)[:, None], u / safe[:, None], fallback)
        force = np.zeros((n, 2))
        force[:, 1] = -np.broadcast_to(self.weight, (n,))
        pairs, inverse = self._pairs  # type: ignore[attr-defined]
        if pairs.shape[0] == 1:
            return disturbance_velocity(force, axis, float(pairs[0, 0]), float(pairs[0, 1]))
        out = np.empty((n, 2))
        for g, (p1, p2) in enumerate(pairs):
            rows = inverse == g
            out[rows] = disturbance_velocity(force[rows], axis[rows], float(p1), float(p2))
        return out

    def take(self, index: IntArray) -> "Weight":
        if self.weight.shape[0] == 1:
            return self
        return Weight(self.weight[index], self.a1[index], self.a2[index], self.theta_r[index],
                      note=self.note, details=self.details)

    def bound(self) -> FloatArray | None:
        # |D f| <= |f| max(1/a1, 1/a2)
        return self.weight * np.maximum(1 / self.a1, 1 / self.a2)

    def describe(self) -> dict[str, Any]:
        out: dict[str, Any] = {
            "kind": self.kind,
            "weight_n": _scalar_or_list(self.weight),
            "a1_n_s_per_m": _scalar_or_list(self.a1),
            "a2_n_s_per_m": _scalar_or_list(self.a2),
            "sinking_speed_along_axis_m_s": _scalar_or_list(self.weight / self.a1),
            "sinking_speed_across_axis_m_s": _scalar_or_list(self.weight / self.a2),
        }
        out.update(self.details)
        if self.note:
            out["note"] = self.note
        return out


@dataclass(frozen=True)
class Sinusoid(Disturbance):
    """``offset + amplitude sin(angular_frequency t + phase)``, component-wise, m/s.

    ``angular_frequency`` is in rad/s (a frequency given in Hz is converted by the scenario
    reader with the factor 2 pi, see :mod:`lyapcheck.units`).
    """

    offset: FloatArray
    amplitude: FloatArray
    angular_frequency: FloatArray
    phase: FloatArray
    kind = "sinusoid"

    def __post_init__(self) -> None:
        off = np.atleast_2d(np.asarray(self.offset, dtype=np.float64))
        amp = np.atleast_2d(np.asarray(self.amplitude, dtype=np.float64))
        om = np.atleast_1d(np.asarray(self.angular_frequency, dtype=np.float64))
        ph = np.atleast_1d(np.asarray(self.phase, dtype=np.float64))
        n = max(off.shape[0], amp.shape[0], om.shape[0], ph.shape[0])
        object.__setattr__(self, "offset", _rows("offset", off, n, 2))
        object.__setattr__(self, "amplitude", _rows("amplitude", amp, n, 2))
        object.__setattr__(self, "angular_frequency", _rows("angular_frequency", om, n))
        object.__setattr__(self, "phase", _rows("phase", ph, n))

    @property
    def size(self) -> int | None:
        return None if self.offset.shape[0] == 1 else self.offset.shape[0]

    def velocity(self, t: FloatArray, t_segment: FloatArray, eps: FloatArray, s: FloatArray,
                 u: FloatArray) -> FloatArray:
        wave = np.sin(self.angular_frequency * t + self.phase)
        return self.offset + self.amplitude * wave[:, None]

    def take(self, index: IntArray) -> "Sinusoid":
        if self.offset.shape[0] == 1:
            return self
        return Sinusoid(self.offset[index], self.amplitude[index], self.angular_frequency[index], self.phase[index])

    def bound(self) -> FloatArray | None:
        return np.hypot(np.abs(self.offset[:, 0]) + np.abs(self.amplitude[:, 0]),
                        np.abs(self.offset[:, 1]) + np.abs(self.amplitude[:, 1]))

    def describe(self) -> dict[str, Any]:
        return {
            "kind": self.kind,
            "offset_m_s": _scalar_or_list(self.offset),
            "amplitude_m_s": _scalar_or_list(self.amplitude),
            "angular_frequency_rad_s": _scalar_or_list(self.angular_frequency),
            "frequency_hz": _scalar_or_list(self.angular_frequency / (2 * math.pi)),
            "phase_rad": _scalar_or_list(self.phase),
        }


@dataclass(frozen=True)
class PiecewiseConstant(Disturbance):
    """Random velocities, uniform in the disc of radius ``bound``, each held ``hold`` seconds.

    The table of values is drawn once from ``numpy.random.default_rng(seed)`` (one row per
    trajectory, enough segments for ``horizon``), so a run is reproducible and the integrator
    can land on every switching time ``k * hold``.
    """

    values: FloatArray  # (n, K, 2)
    hold: FloatArray  # (n,)
    bound_m_s: FloatArray  # (n,)
    seed: int = 0
    kind = "piecewise"

    @classmethod
    def draw(cls, *, n: int, bound: npt.ArrayLike, hold: npt.ArrayLike, horizon: float, seed: int) -> "PiecewiseConstant":
        """Draw the value table with ``numpy.random.default_rng(seed)``."""
        bnd = _rows("bound", bound, n)
        hld = _rows("hold", hold, n)
        if np.any(bnd < 0) or np.any(hld <= 0):
            raise ValueError("The 'bound' and 'hold' parameters must be >= 0 and > 0. Got other values instead.")
        segments = int(math.ceil(horizon / float(hld.min()))) + 1
        rng = np.random.default_rng(seed)
        radius = bnd[:, None] * np.sqrt(rng.uniform(0.0, 1.0, size=(n, segments)))
        angle = rng.uniform(0.0, 2 * math.pi, size=(n, segments))
        values = np.stack([radius * np.cos(angle), radius * np.sin(angle)], axis=-1)
        return cls(values=values, hold=hld, bound_m_s=bnd, seed=seed)

    @property
    def size(self) -> int | None:
        return self.values.shape[0]

    def _index(self, t: FloatArray) -> FloatArray:
        """Number of switching times ``k * hold`` (as floats) that are <= t.

        ``floor(t / hold)`` alone is off by one when ``t`` is a rounded multiple of ``hold``
        (e.g. ``3 * 0.7 / 0.7 < 3``), which would make the integrator land on the same
        breakpoint forever; the products ``k * hold`` are the breakpoints, so compare to them.
        """
        k = np.floor(t / self.hold)
        k = np.where((k + 1) * self.hold <= t, k + 1, k)
        return np.where(k * self.hold > t, k - 1, k)

    def _segment(self, t: FloatArray) -> IntArray:
        return np.clip(self._index(t), 0, self.values.shape[1] - 1).astype(np.intp)

    def velocity(self, t: FloatArray, t_segment: FloatArray, eps: FloatArray, s: FloatArray,
                 u: FloatArray) -> FloatArray:
        k = self._segment(t_segment)
        return self.values[np.arange(t.shape[0]), k]

    def take(self, index: IntArray) -> "PiecewiseConstant":
        return PiecewiseConstant(self.values[index], self.hold[index], self.bound_m_s[index], self.seed)

    def next_breakpoint(self, t: FloatArray) -> FloatArray:
        return (self._index(t) + 1.0) * self.hold

    def bound(self) -> FloatArray | None:
        return self.bound_m_s

    def describe(self) -> dict[str, Any]:
        return {"kind": self.kind, "bound_m_s": _scalar_or_list(self.bound_m_s),
                "hold_s": _scalar_or_list(self.hold), "seed": self.seed,
                "distribution": "uniform in the disc |d| <= bound, independent per segment"}


@dataclass(frozen=True)
class Adversarial(Disturbance):
    """Bounded disturbance across the path that pushes ``V = x^T P x`` up (``x = (eps, s)``).

    ``d_mu = bound * sat(sigma / layer) * e_perp`` with the switching function
    ``sigma = (P x)_1 / P_11 = eps + (P_12/P_11) s`` (a length): ``dV/dt`` gains
    ``2 (P x)_1 d_perp`` from the disturbance (eq:Vdot with the derived input ``(d_perp, 0)``),
    which ``d_perp = bound * sign(sigma)`` maximises over ``|d_perp| <= bound``. The sign is
    replaced by a saturation of half-width ``layer`` (metres, a boundary layer as in
    sliding-mode practice) so that the closed loop stays Lipschitz and the integrator does not
    chatter; inside the layer the push on ``V`` is smaller than the worst case by at most
    ``2 bound P_11 layer``. The along-path component is left at zero: it does not enter the
    ``(eps, s)`` dynamics, and the whole bound is spent across the path.
    """

    bound_m_s: FloatArray  # (n,)
    P: FloatArray  # (n, 2, 2)
    layer: FloatArray  # (n,)
    theta_r: FloatArray  # (n,)
    kind = "adversarial"
    n_switches = 2

    def __post_init__(self) -> None:
        P = np.asarray(self.P, dtype=np.float64)
        if P.ndim == 2:
            P = P[None]
        if P.shape[-2:] != (2, 2) or not np.all(np.isfinite(P)):
            raise ValueError(f"The 'P' parameter must be finite with shape (2, 2) or (n, 2, 2). Got shape {P.shape} instead.")
        if not np.allclose(P, np.swapaxes(P, 1, 2), rtol=1e-12, atol=0.0) or np.any(np.linalg.eigvalsh(P)[:, 0] <= 0):
            raise ValueError("The 'P' parameter must be symmetric positive definite. Got another matrix instead.")
        arrays = {
            "bound_m_s": np.atleast_1d(np.asarray(self.bound_m_s, dtype=np.float64)),
            "layer": np.atleast_1d(np.asarray(self.layer, dtype=np.float64)),
            "theta_r": np.atleast_1d(np.asarray(self.theta_r, dtype=np.float64)),
        }
        n = max(P.shape[0], *(a.shape[0] for a in arrays.values()))
        object.__setattr__(self, "P", np.broadcast_to(P, (n, 2, 2)).copy())
        for name, arr in arrays.items():
            object.__setattr__(self, name, _rows(name, arr, n))
        if np.any(self.bound_m_s < 0) or np.any(self.layer <= 0):
            raise ValueError("The 'bound' and 'layer' parameters must be >= 0 and > 0. Got other values instead.")
        # constant per row, evaluated at every stage of every step: computed once (same values)
        object.__setattr__(self, "_slope", self.P[:, 0, 1] / self.P[:, 0, 0])
        object.__setattr__(self, "_across", (-np.sin(self.theta_r), np.cos(self.theta_r)))

    @property
    def size(self) -> int | None:
        return None if self.P.shape[0] == 1 else self.P.shape[0]

    def switching_function(self, eps: FloatArray, s: FloatArray) -> FloatArray:
        """``sigma = (P x)_1 / P_11`` in metres (its sign is that of dV/d eps)."""
        return eps + self._slope * s  # type: ignore[attr-defined,no-any-return]

    def switching(self, eps: FloatArray, s: FloatArray) -> FloatArray | None:
        # the edges of the boundary layer are kinks of the saturation
        sigma = self.switching_function(eps, s)
        out = np.empty((sigma.shape[0], 2))
        out[:, 0] = sigma - self.layer
        out[:, 1] = sigma + self.layer
        return out

    def velocity(self, t: FloatArray, t_segment: FloatArray, eps: FloatArray, s: FloatArray,
                 u: FloatArray) -> FloatArray:
        w = self.bound_m_s * np.clip(self.switching_function(eps, s) / self.layer, -1.0, 1.0)
        across_x, across_z = self._across  # type: ignore[attr-defined]
        out = np.empty((eps.shape[0], 2))
        out[:, 0] = across_x * w
        out[:, 1] = across_z * w
        return out

    def take(self, index: IntArray) -> "Adversarial":
        if self.P.shape[0] == 1:
            return self
        return Adversarial(self.bound_m_s[index], self.P[index], self.layer[index], self.theta_r[index])

    def bound(self) -> FloatArray | None:
        return self.bound_m_s

    def describe(self) -> dict[str, Any]:
        return {"kind": self.kind, "bound_m_s": _scalar_or_list(self.bound_m_s),
                "P": self.P[0].tolist() if self.P.shape[0] == 1 else self.P.tolist(),
                "boundary_layer_m": _scalar_or_list(self.layer),
                "direction": "across the path, sign of dV/d eps"}


def _across(theta_r: FloatArray) -> FloatArray:
    """Unit vectors across the path (e_perp, eq:ehatThetarPerp), one row per angle."""
    return np.stack([-np.sin(theta_r), np.cos(theta_r)], axis=1)


@dataclass(frozen=True)
class Feedback(Disturbance):
    """Bounded state feedback across the path with a polynomial switching function.

    ``d_mu = bound * sat(sigma / layer) * e_perp`` with the switching function

        ``sigma(eps, s) = L * sum_k c_k (eps / L)^(i_k) (s / L)^(j_k)``     (a length),

    ``L`` a length scale per trajectory (``Delta_LOS`` in practice, so the coefficients are
    of order one). Since ``d_mu`` enters ``(eps, s)`` only through ``eps_dot`` (gain 1 in the
    derived dynamics), ``d_perp = bound * sign(dW/d eps)`` maximises ``dW/dt`` over
    ``|d_perp| <= bound`` for any smooth ``W(eps, s)``: give the polynomial ``dW/d eps``
    (scaled) as ``sigma``. ``sigma = eps`` pushes ``eps`` outward (``W = eps^2``); the
    gradient of a certified polynomial storage function pushes that function up.
    :class:`Adversarial` is the special case of a linear ``sigma``. The boundary layer
    (half-width ``layer``, metres) keeps the loop Lipschitz, as there.

    Parameters
    ----------
    bound_m_s
        ``|d|`` outside the layer, m/s.
    coefficients
        ``c_k``, shape ``(K,)`` or ``(n, K)``.
    exponents
        ``(i_k, j_k)``, shape ``(K, 2)``, non-negative integers.
    length_scale, layer, theta_r
        ``L`` (m), the layer half-width (m) and the path angle (rad), per trajectory or scalar.
    """

    bound_m_s: FloatArray
    coefficients: FloatArray
    exponents: IntArray
    length_scale: FloatArray
    layer: FloatArray
    theta_r: FloatArray
    kind = "feedback"
    n_switches = 2
    note: str = ""

    def __post_init__(self) -> None:
        ex = np.asarray(self.exponents)
        if ex.ndim != 2 or ex.shape[1] != 2 or ex.shape[0] == 0 or np.any(ex < 0) or np.any(ex != np.round(ex)):
            raise ValueError(f"The 'exponents' parameter must be non-negative integers of shape (K, 2). Got {self.exponents!r} instead.")
        coef = np.atleast_2d(np.asarray(self.coefficients, dtype=np.float64))
        arrays = {name: np.atleast_1d(np.asarray(getattr(self, name), dtype=np.float64))
                  for name in ("bound_m_s", "length_scale", "layer", "theta_r")}
        n = max(coef.shape[0], *(a.shape[0] for a in arrays.values()))
        object.__setattr__(self, "exponents", ex.astype(np.intp))
        object.__setattr__(self, "coefficients", _rows("coefficients", coef, n, ex.shape[0]))
        for name, arr in arrays.items():
            object.__setattr__(self, name, _rows(name, arr, n))
        if np.any(self.bound_m_s < 0) or np.any(self.layer <= 0) or np.any(self.length_scale <= 0):
            raise ValueError("The 'bound', 'layer' and 'length_scale' parameters must be >= 0, > 0, > 0. "
                             "Got other values instead.")

    @property
    def size(self) -> int | None:
        return None if self.bound_m_s.shape[0] == 1 else self.bound_m_s.shape[0]

    def switching_function(self, eps: FloatArray, s: FloatArray) -> FloatArray:
        """``sigma(eps, s)`` in metres (its sign is the sign of the pushed gradient)."""
        n = eps.shape[0]
        L = np.broadcast_to(self.length_scale, (n,))
        u, v = eps / L, s / L
        ex = self.exponents
        terms = np.broadcast_to(self.coefficients, (n, ex.shape[0])) * u[:, None] ** ex[:, 0] * v[:, None] ** ex[:, 1]
        return L * terms.sum(axis=1)

    def switching(self, eps: FloatArray, s: FloatArray) -> FloatArray | None:
        sigma = self.switching_function(eps, s)
        layer = np.broadcast_to(self.layer, sigma.shape)
        return np.stack([sigma - layer, sigma + layer], axis=1)

    def velocity(self, t: FloatArray, t_segment: FloatArray, eps: FloatArray, s: FloatArray,
                 u: FloatArray) -> FloatArray:
        n = t.shape[0]
        push = np.clip(self.switching_function(eps, s) / np.broadcast_to(self.layer, (n,)), -1.0, 1.0)
        w = np.broadcast_to(self.bound_m_s, (n,)) * push
        return _across(np.broadcast_to(self.theta_r, (n,))) * w[:, None]

    def take(self, index: IntArray) -> "Feedback":
        if self.bound_m_s.shape[0] == 1:
            return self
        return Feedback(self.bound_m_s[index], self.coefficients[index], self.exponents, self.length_scale[index],
                        self.layer[index], self.theta_r[index], note=self.note)

    def bound(self) -> FloatArray | None:
        return self.bound_m_s

    def describe(self) -> dict[str, Any]:
        out: dict[str, Any] = {
            "kind": self.kind, "bound_m_s": _scalar_or_list(self.bound_m_s),
            "switching_function": "L * sum_k c_k (eps/L)^i_k (s/L)^j_k",
            "exponents": self.exponents.tolist(), "coefficients": _scalar_or_list(self.coefficients),
            "length_scale_m": _scalar_or_list(self.length_scale),
            "boundary_layer_m": _scalar_or_list(self.layer), "theta_r_rad": _scalar_or_list(self.theta_r),
            "direction": "across the path, bound * sat(sigma / layer)",
        }
        if self.note:
            out["note"] = self.note
        return out


@dataclass(frozen=True)
class BangBang(Disturbance):
    """``d_mu = bound * sign_k * direction`` on ``[t_k, t_(k+1))``: a fixed direction, the sign
    flipping at each of the given switching times (the form of a bang-bang optimal control).

    Parameters
    ----------
    bound_m_s
        ``|d_mu|``, m/s, per trajectory.
    direction
        Unit vectors in the world frame, ``(2,)`` or ``(n, 2)`` (normalised here).
    switch_times
        Increasing switching times, s, ``(K,)`` or ``(n, K)``; rows with fewer switches are
        padded with ``+inf``. Each switching time is a time breakpoint of the integrator, and
        the sign on a step is the one at its start (``t_segment``), so no step straddles a
        switch.
    initial_sign
        ``+1`` or ``-1``, the sign before the first switch.
    """

    bound_m_s: FloatArray
    direction: FloatArray
    switch_times: FloatArray
    initial_sign: FloatArray
    kind = "bang_bang"
    note: str = ""

    def __post_init__(self) -> None:
        st = np.atleast_2d(np.asarray(self.switch_times, dtype=np.float64))
        dirs = np.atleast_2d(np.asarray(self.direction, dtype=np.float64))
        bnd = np.atleast_1d(np.asarray(self.bound_m_s, dtype=np.float64))
        sgn = np.atleast_1d(np.asarray(self.initial_sign, dtype=np.float64))
        n = max(st.shape[0], dirs.shape[0], bnd.shape[0], sgn.shape[0])
        if st.ndim != 2 or np.any(np.isnan(st)) or np.any(st == -np.inf) or np.any(st <= 0):
            raise ValueError(f"The 'switch_times' parameter must be positive times (padded with inf). Got {self.switch_times!r} instead.")
        try:
            st = np.broadcast_to(st, (n, st.shape[1])).copy()
        except ValueError:
            raise ValueError(f"The 'switch_times' parameter must broadcast to {n} rows. Got shape {st.shape} instead.") from None
        with np.errstate(invalid="ignore"):
            steps = np.diff(st, axis=1)
        if st.shape[1] > 1 and (np.any(steps[np.isfinite(st[:, :-1])] <= 0)
                                or np.any(np.isinf(st[:, :-1]) & np.isfinite(st[:, 1:]))):
            raise ValueError("The 'switch_times' parameter must be strictly increasing in each row. Got another order instead.")
        dirs = _rows("direction", dirs, n, 2)
        norm = np.hypot(dirs[:, 0], dirs[:, 1])
        if np.any(norm == 0):
            raise ValueError(f"The 'direction' parameter must be non-zero vectors. Got {self.direction!r} instead.")
        sgn = _rows("initial_sign", sgn, n)
        if np.any(np.abs(sgn) != 1):
            raise ValueError(f"The 'initial_sign' parameter must be +1 or -1. Got {self.initial_sign!r} instead.")
        bnd = _rows("bound", bnd, n)
        if np.any(bnd < 0):
            raise ValueError(f"The 'bound' parameter must be in [0, inf). Got {self.bound_m_s!r} instead.")
        object.__setattr__(self, "switch_times", st)
        object.__setattr__(self, "direction", dirs / norm[:, None])
        object.__setattr__(self, "initial_sign", sgn)
        object.__setattr__(self, "bound_m_s", bnd)

    @property
    def size(self) -> int | None:
        return None if self.bound_m_s.shape[0] == 1 else self.bound_m_s.shape[0]

    def _rows_of(self, m: int) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
        if self.bound_m_s.shape[0] == m:  # the batch's own rows (the hot path: no broadcasting)
            return self.switch_times, self.direction, self.initial_sign, self.bound_m_s
        st = np.broadcast_to(self.switch_times, (m, self.switch_times.shape[1]))
        return (st, np.broadcast_to(self.direction, (m, 2)), np.broadcast_to(self.initial_sign, (m,)),
                np.broadcast_to(self.bound_m_s, (m,)))

    def sign(self, t: FloatArray) -> FloatArray:
        """The sign in force at ``t`` (switching times count from the instant they occur)."""
        st, _, sgn, _ = self._rows_of(t.shape[0])
        count = np.count_nonzero(st <= t[:, None], axis=1)
        return np.where(count % 2 == 0, sgn, -sgn)

    def velocity(self, t: FloatArray, t_segment: FloatArray, eps: FloatArray, s: FloatArray,
                 u: FloatArray) -> FloatArray:
        _, dirs, _, bnd = self._rows_of(t.shape[0])
        return dirs * (bnd * self.sign(t_segment))[:, None]

    def next_breakpoint(self, t: FloatArray) -> FloatArray:
        st = self._rows_of(t.shape[0])[0]
        return np.where(st > t[:, None], st, np.inf).min(axis=1, initial=np.inf)

    def take(self, index: IntArray) -> "BangBang":
        if self.bound_m_s.shape[0] == 1:
            return self
        return BangBang(self.bound_m_s[index], self.direction[index], self.switch_times[index],
                        self.initial_sign[index], note=self.note)

    def bound(self) -> FloatArray | None:
        return self.bound_m_s

    def describe(self) -> dict[str, Any]:
        times = [[float(x) for x in row if np.isfinite(x)] for row in self.switch_times]
        out: dict[str, Any] = {
            "kind": self.kind, "bound_m_s": _scalar_or_list(self.bound_m_s),
            "direction": _scalar_or_list(self.direction), "initial_sign": _scalar_or_list(self.initial_sign),
            "switch_times_s": times[0] if len(times) == 1 else times,
        }
        if self.note:
            out["note"] = self.note
        return out


@dataclass(frozen=True)
class SquareWave(Disturbance):
    """``d_mu = bound * sign(sin(angular_frequency t + phase)) * direction`` up to ``horizon``.

    A :class:`BangBang` whose switching times ``(k pi - phase) / angular_frequency`` are
    generated once (in ``(0, horizon]``), so that the integrator lands on every switch exactly.
    """

    bound_m_s: FloatArray
    direction: FloatArray
    angular_frequency: FloatArray
    phase: FloatArray
    horizon: float
    kind = "square_wave"

    def __post_init__(self) -> None:
        om = np.atleast_1d(np.asarray(self.angular_frequency, dtype=np.float64))
        ph = np.atleast_1d(np.asarray(self.phase, dtype=np.float64))
        bnd = np.atleast_1d(np.asarray(self.bound_m_s, dtype=np.float64))
        dirs = np.atleast_2d(np.asarray(self.direction, dtype=np.float64))
        n = max(om.shape[0], ph.shape[0], bnd.shape[0], dirs.shape[0])
        om, ph = _rows("angular_frequency", om, n), _rows("phase", ph, n)
        if np.any(om <= 0):
            raise ValueError(f"The 'angular_frequency' parameter must be in (0, inf). Got {self.angular_frequency!r} instead.")
        if not (math.isfinite(self.horizon) and self.horizon > 0):
            raise ValueError(f"The 'horizon' parameter must be a number in (0, inf). Got {self.horizon!r} instead.")
        wrapped = np.mod(ph, 2 * math.pi)
        first = np.floor(wrapped / math.pi) + 1.0  # first k with k pi > phase (mod 2 pi)
        count = int(np.max(np.floor((om * self.horizon + wrapped) / math.pi) - first + 1.0, initial=0.0))
        k = first[:, None] + np.arange(max(count, 0) + 1)[None, :]
        times = (k * math.pi - wrapped[:, None]) / om[:, None]
        times = np.where((times > 0) & (times <= self.horizon), times, np.inf)
        times = np.sort(times, axis=1)
        keep = np.isfinite(times).any(axis=0)
        times = times[:, keep] if keep.any() else np.full((n, 1), np.inf)
        table = BangBang(bnd, dirs, times, np.where(wrapped < math.pi, 1.0, -1.0))
        object.__setattr__(self, "angular_frequency", om)
        object.__setattr__(self, "phase", ph)
        object.__setattr__(self, "bound_m_s", table.bound_m_s)
        object.__setattr__(self, "direction", table.direction)
        object.__setattr__(self, "_table", table)

    @property
    def table(self) -> BangBang:
        """The switching-time table this wave is integrated with."""
        return self._table  # type: ignore[attr-defined,no-any-return]

    @property
    def size(self) -> int | None:
        return None if self.bound_m_s.shape[0] == 1 else self.bound_m_s.shape[0]

    def velocity(self, t: FloatArray, t_segment: FloatArray, eps: FloatArray, s: FloatArray,
                 u: FloatArray) -> FloatArray:
        return self.table.velocity(t, t_segment, eps, s, u)

    def next_breakpoint(self, t: FloatArray) -> FloatArray:
        return self.table.next_breakpoint(t)

    def take(self, index: IntArray) -> "SquareWave":
        if self.bound_m_s.shape[0] == 1:
            return self
        return SquareWave(self.bound_m_s[index], self.direction[index], self.angular_frequency[index],
                          self.phase[index], self.horizon)

    def bound(self) -> FloatArray | None:
        return self.bound_m_s

    def describe(self) -> dict[str, Any]:
        return {
            "kind": self.kind, "bound_m_s": _scalar_or_list(self.bound_m_s),
            "direction": _scalar_or_list(self.direction),
            "angular_frequency_rad_s": _scalar_or_list(self.angular_frequency),
            "frequency_hz": _scalar_or_list(self.angular_frequency / (2 * math.pi)),
            "phase_rad": _scalar_or_list(self.phase), "horizon_s": self.horizon,
            "waveform": "bound * sign(sin(angular_frequency t + phase)) * direction",
        }


@dataclass(frozen=True)
class Stacked(Disturbance):
    """Rows of different disturbance kinds in one batch: row ``i`` is served by ``parts[group[i]]``.

    Each part holds exactly its own rows, in order (or broadcasts, ``size`` ``None``). Build
    with :meth:`concat`. The switching functions of the parts are padded with the constant 1
    (never a kink) to a common width, which :meth:`take` keeps, as the integrator requires.
    """

    parts: tuple[Disturbance, ...]
    group: IntArray
    #: number of switching columns (default: the widest part's); kept by :meth:`take`
    width: int | None = None
    kind = "stacked"

    def __post_init__(self) -> None:
        group = np.asarray(self.group, dtype=np.intp)
        if group.ndim != 1 or np.any(group < 0) or np.any(group >= len(self.parts)):
            raise ValueError(f"The 'group' parameter must index the {len(self.parts)} parts. Got {self.group!r} instead.")
        for g, part in enumerate(self.parts):
            rows = int(np.count_nonzero(group == g))
            if part.size is not None and part.size != rows:
                raise ValueError(f"The 'parts' parameter must have {rows} rows in part {g}. Got {part.size} instead.")
        local = np.zeros(group.shape[0], dtype=np.intp)
        for g in range(len(self.parts)):
            rows = group == g
            local[rows] = np.arange(np.count_nonzero(rows))
        object.__setattr__(self, "group", group)
        object.__setattr__(self, "_local", local)
        # the rows of each part, computed once (velocity is evaluated at every stage)
        object.__setattr__(self, "_parts_rows", [(p, np.flatnonzero(group == g)) for g, p in enumerate(self.parts)])
        widest = max((p.n_switches for p in self.parts), default=0)
        if self.width is not None and self.width < widest:
            raise ValueError(f"The 'width' parameter must be at least {widest}. Got {self.width} instead.")
        object.__setattr__(self, "n_switches", widest if self.width is None else self.width)

    @classmethod
    def concat(cls, parts: "list[tuple[Disturbance, int]]") -> "Stacked":
        """Stack ``(disturbance, rows)`` pairs, in order."""
        group = np.concatenate([np.full(rows, g, dtype=np.intp) for g, (_, rows) in enumerate(parts)])
        return cls(tuple(p for p, _ in parts), group)

    @property
    def size(self) -> int | None:
        return int(self.group.shape[0])

    def row(self, i: int) -> Disturbance:
        """The plain one-row disturbance of row ``i`` (for reports and re-simulation)."""
        part = self.parts[int(self.group[i])]
        return part.take(np.array([self._local[i]], dtype=np.intp))  # type: ignore[attr-defined]

    def _each(self) -> "list[tuple[Disturbance, IntArray]]":
        return self._parts_rows  # type: ignore[attr-defined,no-any-return]

    def _alone(self) -> Disturbance | None:
        """The part that serves every row in order, when there is one (a batch whose other
        parts have finished): the calls go to it directly, without gathering rows."""
        return self.parts[0] if len(self.parts) == 1 else None

    def velocity(self, t: FloatArray, t_segment: FloatArray, eps: FloatArray, s: FloatArray,
                 u: FloatArray) -> FloatArray:
        alone = self._alone()
        if alone is not None:
            return alone.velocity(t, t_segment, eps, s, u)
        out = np.empty((t.shape[0], 2))
        for part, rows in self._each():
            if rows.size:
                out[rows] = part.velocity(t[rows], t_segment[rows], eps[rows], s[rows], u[rows])
        return out

    def next_breakpoint(self, t: FloatArray) -> FloatArray:
        alone = self._alone()
        if alone is not None:
            return alone.next_breakpoint(t)
        out = np.full(t.shape, np.inf)
        for part, rows in self._each():
            if rows.size:
                out[rows] = part.next_breakpoint(t[rows])
        return out

    def switching(self, eps: FloatArray, s: FloatArray) -> FloatArray | None:
        if self.n_switches == 0:
            return None
        alone = self._alone()
        if alone is not None and alone.n_switches == self.n_switches:
            return alone.switching(eps, s)
        out = np.ones((eps.shape[0], self.n_switches))
        for part, rows in self._each():
            if rows.size and part.n_switches:
                sw = part.switching(eps[rows], s[rows])
                if sw is not None:
                    out[rows, :sw.shape[1]] = sw
        return out

    def take(self, index: IntArray) -> "Stacked":
        index = np.asarray(index, dtype=np.intp)
        group = self.group[index]
        local = self._local[index]  # type: ignore[attr-defined]
        parts: list[Disturbance] = []
        new_group = np.empty(index.shape[0], dtype=np.intp)
        for g, part in enumerate(self.parts):
            rows = group == g
            if not rows.any():
                continue
            new_group[rows] = len(parts)
            parts.append(part.take(local[rows]))
        return Stacked(tuple(parts), new_group, width=self.n_switches)

    def bound(self) -> FloatArray | None:
        out = np.empty(self.group.shape[0])
        for part, rows in self._each():
            b = part.bound()
            if b is None:
                return None
            out[rows] = np.broadcast_to(b, (rows.size,))
        return out

    def describe(self) -> dict[str, Any]:
        return {"kind": self.kind, "parts": [p.describe() for p in self.parts],
                "rows_per_part": [int(np.count_nonzero(self.group == g)) for g in range(len(self.parts))]}


def _scalar_or_list(x: FloatArray) -> Any:
    arr = np.asarray(x)
    if arr.ndim >= 1 and arr.shape[0] == 1:
        arr = arr[0]
    if arr.ndim == 0:
        return float(arr)
    flat = arr.reshape(arr.shape[0], -1)
    if np.all(flat == flat[0]):
        return arr[0].tolist() if arr.ndim > 1 else float(arr[0])
    return arr.tolist()


def _merge(rows: "list[Disturbance]") -> Disturbance:
    """One multi-row disturbance from one-row disturbances of the same kind (see :func:`stack_rows`)."""
    first = rows[0]
    if len(rows) == 1 or isinstance(first, NoDisturbance):
        return first if len(rows) == 1 else NoDisturbance()
    if isinstance(first, Constant):
        return Constant(np.array([np.broadcast_to(d.vector, (2,)) for d in rows]), note=first.note)  # type: ignore[attr-defined]
    if isinstance(first, Sinusoid):
        ss: list[Sinusoid] = rows  # type: ignore[assignment]
        return Sinusoid(np.concatenate([d.offset for d in ss]), np.concatenate([d.amplitude for d in ss]),
                        np.concatenate([d.angular_frequency for d in ss]), np.concatenate([d.phase for d in ss]))
    if isinstance(first, SquareWave):
        sq: list[SquareWave] = rows  # type: ignore[assignment]
        return SquareWave(np.concatenate([d.bound_m_s for d in sq]), np.concatenate([d.direction for d in sq]),
                          np.concatenate([d.angular_frequency for d in sq]), np.concatenate([d.phase for d in sq]),
                          first.horizon)
    if isinstance(first, BangBang):
        bb: list[BangBang] = rows  # type: ignore[assignment]
        width = max(d.switch_times.shape[1] for d in bb)
        times = np.full((len(bb), width), np.inf)
        for i, d in enumerate(bb):
            times[i, :d.switch_times.shape[1]] = d.switch_times[0]
        return BangBang(np.concatenate([d.bound_m_s for d in bb]), np.concatenate([d.direction for d in bb]),
                        times, np.concatenate([d.initial_sign for d in bb]), note=first.note)
    if isinstance(first, Feedback):
        fb: list[Feedback] = rows  # type: ignore[assignment]
        return Feedback(np.concatenate([d.bound_m_s for d in fb]), np.concatenate([d.coefficients for d in fb]),
                        first.exponents, np.concatenate([d.length_scale for d in fb]),
                        np.concatenate([d.layer for d in fb]), np.concatenate([d.theta_r for d in fb]), note=first.note)
    raise ValueError(f"The 'rows' parameter must be of one mergeable kind. Got {first.kind!r} instead.")


def _merge_key(d: Disturbance) -> tuple[Any, ...]:
    if isinstance(d, (NoDisturbance, Sinusoid)):
        return (type(d).__name__,)
    if isinstance(d, (Constant, BangBang)):
        return (type(d).__name__, d.note)
    if isinstance(d, SquareWave):
        return (type(d).__name__, d.horizon)
    if isinstance(d, Feedback):
        return (type(d).__name__, d.note, d.exponents.tobytes(), d.exponents.shape)
    return ("unique", id(d))


def stack_rows(rows: "list[Disturbance]") -> Disturbance:
    """One batch from one-row disturbances of any kinds, row ``i`` behaving as ``rows[i]``.

    Rows of the same kind are merged into one multi-row part (one numpy call per kind and
    evaluation, not per row); several kinds make a :class:`Stacked`.
    """
    if not rows:
        raise ValueError("The 'rows' parameter must hold at least one disturbance. Got none instead.")
    for i, d in enumerate(rows):
        if d.size not in (None, 1):
            raise ValueError(f"The 'rows' parameter must hold one-row disturbances. Got {d.size} rows at {i} instead.")
    keys: dict[tuple[Any, ...], int] = {}
    group = np.empty(len(rows), dtype=np.intp)
    members: list[list[Disturbance]] = []
    for i, d in enumerate(rows):
        k = _merge_key(d)
        if k not in keys:
            keys[k] = len(members)
            members.append([])
        group[i] = keys[k]
        members[keys[k]].append(d)
    parts = tuple(_merge(m) for m in members)
    # one kind: the merged part is the batch (a broadcasting part serves any number of rows)
    return parts[0] if len(parts) == 1 else Stacked(parts, group)


def from_description(desc: "dict[str, Any] | Any") -> Disturbance:
    """Rebuild a one-row disturbance from its :meth:`Disturbance.describe` output (kinds ``none``,
    ``constant``, ``sinusoid``, ``square_wave``, ``bang_bang``, ``feedback``).

    Extra keys (``family``, ``note``, derived figures) are ignored.
    """
    kind = desc.get("kind") if hasattr(desc, "get") else None
    f = np.asarray
    try:
        if kind == "none":
            return NoDisturbance()
        if kind == "constant":
            return Constant(f(desc["velocity_m_s"], dtype=np.float64), note=str(desc.get("note", "")))
        if kind == "sinusoid":
            return Sinusoid(f(desc["offset_m_s"]), f(desc["amplitude_m_s"]), f(desc["angular_frequency_rad_s"]),
                            f(desc["phase_rad"]))
        if kind == "square_wave":
            return SquareWave(f(desc["bound_m_s"]), f(desc["direction"]), f(desc["angular_frequency_rad_s"]),
                              f(desc["phase_rad"]), float(desc["horizon_s"]))
        if kind == "bang_bang":
            times = f(desc["switch_times_s"], dtype=np.float64)
            return BangBang(f(desc["bound_m_s"]), f(desc["direction"]), times if times.size else np.array([np.inf]),
                            f(desc["initial_sign"]), note=str(desc.get("note", "")))
        if kind == "feedback":
            return Feedback(f(desc["bound_m_s"]), f(desc["coefficients"]), f(desc["exponents"]),
                            f(desc["length_scale_m"]), f(desc["boundary_layer_m"]), f(desc["theta_r_rad"]),
                            note=str(desc.get("note", "")))
    except KeyError as err:
        raise ValueError(f"The 'description' parameter must have the key {err.args[0]!r} for kind {kind!r}. "
                         "Got a description without it instead.") from None
    raise ValueError("The 'description' parameter must have a 'kind' among none, constant, sinusoid, square_wave, "
                     f"bang_bang, feedback. Got {kind!r} instead.")
