"""The saturated ILOS/ODS closed loop of the paper, as a batched ODE system.

Plant (eq:eq_dyn): ``p_dot = e11 u + d_mu`` in the plane of the path and gravity, ``p`` in
metres, ``u`` the commanded angular velocity in rad/s (``e11`` in metres per radian).

Controller: the ILOS reference field ``v_d(eps, s)`` and ``s_dot`` (eq:los2, eq:losdynvar,
with the explicit speed ``U`` of :mod:`symbolic.ilos`), turned into a rotation command by the
closed-form ODS law (eq:solFinal) with estimates ``e11_hat`` and ``d_hat``. Every formula is
called from :mod:`symbolic` (``guidance_functions``, ``ods_control``); nothing is re-typed here.
The conventional LOS law of the paper's comparison is the same field with ``sigma0 = 0`` and no
integral state (``s`` frozen at 0).

State per trajectory (columns): ``p_x, p_z, s`` and three running integrals over the tail
window ``[t_tail, horizon]`` used by :mod:`lyapcheck.paper.simulation.metrics`: ``int |eps| dt``,
``int |u| dt`` and ``int z_dot dt``. Integrating them with the state (instead of summing
samples) gives tail means with the integrator's own accuracy; the tail start is a time
breakpoint, so no step straddles it.

``form="printed"`` uses the paper's eq:ODS2 as printed (G_mu with the opposite sign) together
with eq:losdynvar as printed (``U = 1``): the rotation command then points away from the
reference field and the loop diverges, which is what the paper's equations, taken literally,
do.
"""

from __future__ import annotations

from dataclasses import dataclass, fields, replace
from typing import Any, Callable, Final, Literal, Mapping, Sequence

import numpy as np
import numpy.typing as npt

from lyapcheck.paper.simulation.disturbances import Disturbance
from lyapcheck.integrator import Evaluation

FloatArray = npt.NDArray[np.float64]
IntArray = npt.NDArray[np.intp]
Form = Literal["derived", "printed"]
Controller = Literal["ilos", "los"]

#: state columns
PX, PZ, S, Q_EPS, Q_U, Q_Z = range(6)
N_STATE: Final = 6


@dataclass(frozen=True)
class LoopParams:
    """Per-trajectory parameters of the closed loop, SI, each an array of shape ``(n,)``.

    ``integral`` is 1.0 for ILOS and 0.0 for the conventional LOS law (no ``s`` state,
    ``sigma0`` ignored). Rotation rates are angular velocities in rad/s.
    """

    alpha_d: FloatArray
    sigma0: FloatArray
    k_d: FloatArray
    delta_los: FloatArray
    los_speed: FloatArray
    e11: FloatArray
    e11_hat: FloatArray
    omega_so: FloatArray
    omega_0: FloatArray
    theta_r: FloatArray
    integral: FloatArray
    d_hat: FloatArray  # (n, 2), m/s

    @property
    def size(self) -> int:
        return int(self.alpha_d.shape[0])

    @classmethod
    def build(cls, n: int | None = None, **values: npt.ArrayLike) -> "LoopParams":
        """Broadcast scalars/arrays to a common batch size and check them.

        Raises
        ------
        ValueError
            A missing or unknown name, a shape that does not broadcast, a non-finite value or
            a non-positive value where the paper requires a positive one.
        """
        names = [f.name for f in fields(cls)]
        unknown = set(values) - set(names)
        if unknown:
            raise ValueError(f"The '{sorted(unknown)[0]}' parameter must be one of {', '.join(names)}. Got it instead.")
        missing = [name for name in names if name not in values and name != "d_hat"]
        if missing:
            raise ValueError(f"The '{missing[0]}' parameter must be given. Got nothing instead.")
        arrays = {name: np.asarray(values[name], dtype=np.float64) for name in values}
        arrays.setdefault("d_hat", np.zeros(2))
        sizes = [a.shape[0] for name, a in arrays.items() if (a.ndim == 1 and name != "d_hat") or a.ndim == 2]
        size = n if n is not None else max(sizes, default=1)
        out: dict[str, FloatArray] = {}
        for name, arr in arrays.items():
            shape: tuple[int, ...] = (size, 2) if name == "d_hat" else (size,)
            try:
                out[name] = np.broadcast_to(arr, shape).copy()
            except ValueError:
                raise ValueError(f"The '{name}' parameter must broadcast to shape {shape}. Got shape {arr.shape} instead.") from None
            if not np.all(np.isfinite(out[name])):
                raise ValueError(f"The '{name}' parameter must be finite. Got {values[name]!r} instead.")
        for name in ("alpha_d", "k_d", "delta_los", "los_speed", "e11", "e11_hat", "omega_so", "omega_0"):
            if np.any(out[name] <= 0):
                raise ValueError(f"The '{name}' parameter must be in (0, inf). Got {values[name]!r} instead.")
        if np.any(out["sigma0"] < 0):
            raise ValueError(f"The 'sigma0' parameter must be in [0, inf). Got {values['sigma0']!r} instead.")
        if np.any((out["integral"] != 0) & (out["integral"] != 1)):
            raise ValueError(f"The 'integral' parameter must be 0 or 1. Got {values['integral']!r} instead.")
        return cls(**out)

    @classmethod
    def from_problem(cls, problem: Any, *, controller: Controller = "ilos", n: int = 1,
                     d_hat: npt.ArrayLike = (0.0, 0.0), **overrides: npt.ArrayLike) -> "LoopParams":
        """Parameters of a validated :class:`lyapcheck.paper.params.Problem` (exact SI -> float).

        ``overrides`` replace single fields by arrays, e.g. ``alpha_d=np.linspace(...)``.
        """
        if controller not in ("ilos", "los"):
            raise ValueError(f"The 'controller' parameter must be 'ilos' or 'los'. Got {controller!r} instead.")
        g, sw, act = problem.gains, problem.swimmer, problem.actuation
        values: dict[str, npt.ArrayLike] = {
            "alpha_d": float(g.alpha_d), "sigma0": float(g.sigma0), "k_d": float(g.k_d),
            "delta_los": float(g.delta_los), "los_speed": float(g.los_speed),
            "e11": float(sw.e11), "e11_hat": float(sw.e11_hat),
            "omega_so": float(act.step_out()), "omega_0": float(act.omega_0),
            "theta_r": float(problem.theta_r),
            "integral": 1.0 if controller == "ilos" else 0.0,
            "d_hat": d_hat,
        }
        values.update(overrides)
        return cls.build(n=n if all(np.ndim(v) == 0 or k == "d_hat" for k, v in values.items()) else None, **values)

    def take(self, index: IntArray) -> "LoopParams":
        return LoopParams(**{f.name: getattr(self, f.name)[index] for f in fields(self)})

    @classmethod
    def concat(cls, parts: "Sequence[LoopParams]") -> "LoopParams":
        """Stack batches row-wise (e.g. the three presets into one call)."""
        return cls(**{f.name: np.concatenate([getattr(p, f.name) for p in parts]) for f in fields(cls)})

    def with_(self, **changes: npt.ArrayLike) -> "LoopParams":
        """A copy with some fields replaced (broadcast to the batch)."""
        new = {k: np.broadcast_to(np.asarray(v, dtype=np.float64),
                                  (self.size, 2) if k == "d_hat" else (self.size,)).copy()
               for k, v in changes.items()}
        return replace(self, **new)

    def speed_star(self) -> FloatArray:
        """Steady speed along the path of Corollary corr:invariance, eq:speedSS with the
        estimate: ``(e11/e11_hat) alpha_d Delta`` (``e11 alpha_d Delta`` for ``e11_hat = 1 m``),
        unless ``alpha_d Delta / e11_hat`` exceeds ``Omega_SO`` (then the ODS saturates on the
        path and the speed is ``e11 Omega_SO``)."""
        along = self.alpha_d * self.delta_los / self.e11_hat
        return self.e11 * np.minimum(along, self.omega_so)


def _on_finite_rows(v_d: FloatArray, fn: Callable[[IntArray | slice], FloatArray], width: int = 2) -> FloatArray:
    """``fn(rows)`` on the rows where the reference ``v_d`` is finite, NaN on the other rows.

    The ODS functions of :mod:`symbolic.ods` reject a non-finite reference (``ValueError``). At
    extreme but valid scales a trial stage of the integrator can overflow the state; NaN in the
    derivative then makes the integrator reject that step (and fail the row as not finite, if
    it persists) instead of aborting the whole batch with an internal error.

    Parameters
    ----------
    v_d
        Reference field, ``(n, 2)``.
    fn
        Evaluates the rows given as an index array (or ``slice(None)`` for all); returns ``(k, width)``.
    width
        Columns of ``fn``'s result.

    Returns
    -------
    numpy.ndarray
        ``(n, width)``.
    """
    finite = np.all(np.isfinite(v_d), axis=1)
    if finite.all():  # the normal case: one call, no copies
        return fn(slice(None))
    out = np.full((v_d.shape[0], width), np.nan)
    rows = np.flatnonzero(finite)
    if rows.size:
        out[rows] = fn(rows)
    return out


@dataclass(frozen=True)
class ClosedLoop:
    """Batched right-hand side of the closed loop (implements the integrator's protocol)."""

    params: LoopParams
    disturbance: Disturbance
    t_tail: FloatArray  # (n,) start of the tail window
    form: Form = "derived"

    def __post_init__(self) -> None:
        if self.form not in ("derived", "printed"):
            raise ValueError(f"The 'form' parameter must be 'derived' or 'printed'. Got {self.form!r} instead.")
        size = self.disturbance.size
        if size is not None and size != self.params.size:
            raise ValueError(f"The 'disturbance' parameter must have {self.params.size} rows. Got {size} instead.")
        object.__setattr__(self, "t_tail", np.broadcast_to(np.asarray(self.t_tail, dtype=np.float64),
                                                           (self.params.size,)).copy())
        # the path frame is constant: compute it once, not at every evaluation
        th = self.params.theta_r
        object.__setattr__(self, "_along", np.stack([np.cos(th), np.sin(th)], axis=1))
        object.__setattr__(self, "_across", np.stack([-np.sin(th), np.cos(th)], axis=1))
        # the ODS law's constant inputs, validated once for the batch (not at every evaluation)
        from symbolic.ods import BatchODS

        pr = self.params
        object.__setattr__(self, "_ods", BatchODS(pr.d_hat, pr.e11_hat, pr.omega_0, pr.omega_so, form=self.form))
        from symbolic.closed_loop import guidance_functions

        object.__setattr__(self, "_guidance", guidance_functions(self.form))

    @property
    def size(self) -> int:
        return self.params.size

    def take(self, index: IntArray) -> "ClosedLoop":
        return ClosedLoop(self.params.take(index), self.disturbance.take(index), self.t_tail[index], self.form)

    def next_breakpoint(self, t: FloatArray) -> FloatArray:
        tail = np.where(t < self.t_tail, self.t_tail, np.inf)
        return np.minimum(tail, self.disturbance.next_breakpoint(t))

    # -- pieces, exposed for tests, metrics and plots ---------------------------------------
    def frame(self) -> tuple[FloatArray, FloatArray]:
        """Unit vectors along (e_r, eq:ehatThetar) and across (e_perp, eq:ehatThetarPerp) the path."""
        return self._along, self._across  # type: ignore[attr-defined]

    def errors(self, y: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray]:
        """``eps`` (eq:output), ``z`` (eq:zeroState) and the effective ``s`` (0 for LOS)."""
        along, across = self.frame()
        eps = across[:, 0] * y[:, PX] + across[:, 1] * y[:, PZ]
        z = along[:, 0] * y[:, PX] + along[:, 1] * y[:, PZ]
        return eps, z, y[:, S] * self.params.integral

    def control(self, y: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray]:
        """Rotation command ``u`` (rad/s, eq:solFinal), reference field ``v_d`` and ``eps``."""
        u, _, v_d, eps = self._control_and_gradient(y)
        return u, v_d, eps

    def _control_and_gradient(self, y: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
        """``u``, ``G_mu`` (eq:ODS2; NaN where ``v_d`` is not finite), ``v_d`` and ``eps``: one ODS
        evaluation serves the command and the saturation's switching function."""
        pr = self.params
        v_d_fn: Callable[..., tuple[FloatArray, FloatArray]] = self._guidance[0]  # type: ignore[attr-defined]
        across = self._across  # type: ignore[attr-defined]
        eps = across[:, 0] * y[:, PX] + across[:, 1] * y[:, PZ]  # as errors() computes it (z is not needed)
        s = y[:, S] * pr.integral
        sigma = pr.sigma0 * pr.integral
        v_d = np.empty((y.shape[0], 2))
        v_d[:, 0], v_d[:, 1] = v_d_fn(eps, s, pr.alpha_d, sigma, pr.delta_los, pr.theta_r)
        ods = self._ods  # type: ignore[attr-defined]
        if np.isfinite(v_d).all():  # the normal case: one call, no copies
            u, G = ods(v_d)
            return u, G, v_d, eps
        both = _on_finite_rows(v_d, lambda r: np.concatenate(ods(v_d[r], r), axis=1), width=4)
        return both[:, :2], both[:, 2:], v_d, eps

    def rhs(self, t: FloatArray, y: FloatArray, t_segment: FloatArray) -> Evaluation:
        pr = self.params
        s_dot_fn: Callable[..., FloatArray] = self._guidance[1]  # type: ignore[attr-defined]
        u, G, v_d, eps = self._control_and_gradient(y)
        along, _ = self.frame()
        s = y[:, S] * pr.integral
        d = self.disturbance.velocity(t, t_segment, eps, s, u)
        p_dot = pr.e11[:, None] * u + d
        sigma = pr.sigma0 * pr.integral
        s_dot = s_dot_fn(eps, s, sigma, pr.k_d, pr.delta_los, pr.los_speed) * pr.integral
        in_tail = (t_segment >= self.t_tail).astype(np.float64)
        u_norm = np.hypot(u[:, 0], u[:, 1])
        dy = np.empty_like(y)
        dy[:, PX:PZ + 1] = p_dot
        dy[:, S] = s_dot
        dy[:, Q_EPS] = in_tail * np.abs(eps)
        dy[:, Q_U] = in_tail * u_norm
        dy[:, Q_Z] = in_tail * (along[:, 0] * p_dot[:, 0] + along[:, 1] * p_dot[:, 1])
        # kinks, for step placement only (the control itself is ods_control's): the ODS
        # saturation boundary |G_mu| = Omega_SO/Omega_0 of eq:solFinal, |eps| = 0 in the tail
        # integral, and the disturbance's own kinks
        extra = self.disturbance.switching(eps, s)
        switches = np.empty((y.shape[0], 2 + (0 if extra is None else extra.shape[1])))
        switches[:, 0] = pr.omega_0 * np.hypot(G[:, 0], G[:, 1]) - pr.omega_so
        switches[:, 1] = eps
        if extra is not None:
            switches[:, 2:] = extra
        return Evaluation(dy, u_norm, switches)

    def disturbance_at(self, t: FloatArray, y: FloatArray) -> FloatArray:
        """``d_mu`` at given states (for plots and checks)."""
        u, _, eps = self.control(y)
        return self.disturbance.velocity(t, t, eps, y[:, S] * self.params.integral, u)

    def initial_state(self, p0: npt.ArrayLike, s0: npt.ArrayLike = 0.0) -> FloatArray:
        """State rows from initial positions ``(n, 2)`` or ``(2,)`` (m) and ``s0`` (m)."""
        y = np.zeros((self.size, N_STATE))
        y[:, PX:PZ + 1] = np.broadcast_to(np.asarray(p0, dtype=np.float64), (self.size, 2))
        y[:, S] = np.broadcast_to(np.asarray(s0, dtype=np.float64), (self.size,)) * self.params.integral
        return y

    def switch_atol(self, rtol: float, length_scale: FloatArray) -> FloatArray:
        """Magnitudes below which the switching functions of :meth:`rhs` are negligible:
        ``rtol * Omega_SO`` for the saturation, ``rtol * L`` for the length-valued ones."""
        L = np.broadcast_to(np.asarray(length_scale, dtype=np.float64), (self.size,))
        cols = [rtol * self.params.omega_so] + [rtol * L] * (1 + self.disturbance.n_switches)
        return np.stack(cols, axis=1)

    def atol(self, rtol: float, length_scale: FloatArray) -> FloatArray:
        """Absolute tolerances per component, from a length scale per trajectory.

        Lengths (p, s, and int |eps| over one second) get ``rtol * L``; the rotation integral
        gets ``rtol * Omega_SO * 1 s`` and the along-path integral ``rtol * e11 Omega_SO * 1 s``,
        i.e. each component is controlled relative to its own natural scale.
        """
        pr = self.params
        L = np.broadcast_to(np.asarray(length_scale, dtype=np.float64), (self.size,))
        out = np.empty((self.size, N_STATE))
        out[:, PX] = out[:, PZ] = out[:, S] = out[:, Q_EPS] = rtol * L
        out[:, Q_U] = rtol * pr.omega_so
        out[:, Q_Z] = rtol * pr.e11 * pr.omega_so
        return out


@dataclass(frozen=True)
class ErrorDynamics:
    """The idealised cross-track error dynamics ``x_dot = A x + rho(x) B x + E w`` (no plant,
    no saturation), batched, from :func:`symbolic.closed_loop.error_dynamics`.

    ``name="printed"`` is eq:xCrossdyn/eq:xCrossdyn2 as printed (rate ``alpha_d`` in eps: a
    stiff system at the paper's gains, used to test the integrator); ``"derived"`` is the
    toolkit's form. ``w`` is a constant ``d_perp`` per trajectory.
    """

    name: Literal["derived", "printed"]
    values: Mapping[str, FloatArray]
    w: FloatArray

    @property
    def size(self) -> int:
        return int(self.w.shape[0])

    def take(self, index: IntArray) -> "ErrorDynamics":
        return ErrorDynamics(self.name, {k: v[index] for k, v in self.values.items()}, self.w[index])

    def next_breakpoint(self, t: FloatArray) -> FloatArray:
        return np.full(t.shape, np.inf)

    def rhs(self, t: FloatArray, y: FloatArray, t_segment: FloatArray) -> Evaluation:
        fn = _error_dynamics_function(self.name)
        v = self.values
        e_dot, s_dot = fn(y[:, 0], y[:, 1], self.w, v["alpha_d"], v["sigma0"], v["k_d"], v["delta_los"],
                          v["los_speed"], v["e11"], v["e11_hat"])
        dy = np.stack(np.broadcast_arrays(e_dot, s_dot), axis=1).astype(np.float64)
        return Evaluation(dy, np.hypot(y[:, 0], y[:, 1]), np.empty((y.shape[0], 0)))

    @classmethod
    def build(cls, name: Literal["derived", "printed"], n: int, w: npt.ArrayLike = 0.0,
              **values: npt.ArrayLike) -> "ErrorDynamics":
        keys = ("alpha_d", "sigma0", "k_d", "delta_los", "los_speed", "e11", "e11_hat")
        missing = [k for k in keys if k not in values]
        if missing:
            raise ValueError(f"The '{missing[0]}' parameter must be given. Got nothing instead.")
        arr = {k: np.broadcast_to(np.asarray(values[k], dtype=np.float64), (n,)).copy() for k in keys}
        return cls(name, arr, np.broadcast_to(np.asarray(w, dtype=np.float64), (n,)).copy())


_ERROR_FN_CACHE: dict[str, Any] = {}


def _error_dynamics_function(name: str) -> Any:
    """Lambdified ``rhs(w)`` of :func:`symbolic.closed_loop.error_dynamics` (cached)."""
    if name not in _ERROR_FN_CACHE:
        import sympy as sp

        from symbolic import symbols as Sy
        from symbolic.closed_loop import error_dynamics

        dyn = error_dynamics(name)  # type: ignore[arg-type]
        w = sp.Symbol("w", real=True)
        rhs = dyn.rhs(w)
        args = (Sy.eps, Sy.s, w, Sy.alpha_d, Sy.sigma0, Sy.k_d, Sy.Delta, Sy.U, Sy.e11, Sy.e11_hat)
        _ERROR_FN_CACHE[name] = sp.lambdify(args, [rhs[0], rhs[1]], modules="numpy")
    return _ERROR_FN_CACHE[name]
