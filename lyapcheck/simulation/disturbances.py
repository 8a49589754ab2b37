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
        a1 = np.broadcast_to(self.a1, (n,))
        a2 = np.broadcast_to(self.a2, (n,))
        # rft.disturbance_velocity takes scalar a1, a2: one call per distinct pair (usually one)
        pairs, inverse = np.unique(np.stack([a1, a2], axis=1), axis=0, return_inverse=True)
        if pairs.shape[0] == 1:
            return disturbance_velocity(force, axis, float(pairs[0, 0]), float(pairs[0, 1]))
        out = np.empty((n, 2))
        inverse = inverse.reshape(-1)
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

    @property
    def size(self) -> int | None:
        return None if self.P.shape[0] == 1 else self.P.shape[0]

    def switching_function(self, eps: FloatArray, s: FloatArray) -> FloatArray:
        """``sigma = (P x)_1 / P_11`` in metres (its sign is that of dV/d eps)."""
        n = eps.shape[0]
        P = np.broadcast_to(self.P, (n, 2, 2))
        return eps + (P[:, 0, 1] / P[:, 0, 0]) * s

    def switching(self, eps: FloatArray, s: FloatArray) -> FloatArray | None:
        # the edges of the boundary layer are kinks of the saturation
        sigma = self.switching_function(eps, s)
        layer = np.broadcast_to(self.layer, sigma.shape)
        return np.stack([sigma - layer, sigma + layer], axis=1)

    def velocity(self, t: FloatArray, t_segment: FloatArray, eps: FloatArray, s: FloatArray,
                 u: FloatArray) -> FloatArray:
        n = t.shape[0]
        push = np.clip(self.switching_function(eps, s) / np.broadcast_to(self.layer, (n,)), -1.0, 1.0)
        w = np.broadcast_to(self.bound_m_s, (n,)) * push
        theta = np.broadcast_to(self.theta_r, (n,))
        return np.stack([-np.sin(theta) * w, np.cos(theta) * w], axis=1)

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
