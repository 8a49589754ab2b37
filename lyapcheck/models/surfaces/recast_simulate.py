"""``simulate --model`` for a loop with functions: its true loop behind the simulation's field interface.

A loop with functions (sin, sqrt, sat, ...) is simulated by :mod:`lyapcheck.models.surfaces.simulate`, the
same scenarios, starts, tail sups, series, plots and worst-case search as a polynomial loop; this
module gives it what that machinery needs (:func:`prepare_true_loop`):

- the field (:class:`lyapcheck.models.engines.recast_numeric.TrueField`): the model's own, each function evaluated by numpy
  (:class:`lyapcheck.models.engines.recast_numeric.FloatLoop`), never the recast polynomial loop, which only
  holds on its relations' set; under a disturbance, the loop recast with its disturbances as
  variables (:attr:`~lyapcheck.models.language.recast.RecastModel.robust`). Where the recasting could not keep
  a disturbance a variable, the loop is simulated with it held at 0 (scenario ``none`` only) and the
  document says so;
- the bang-bang law's gain ``G_k = dy'/dd_k`` (:class:`TrueOutputGain`): ``dy/dx`` exactly (the
  outputs are polynomials in the states), ``df/dd_k`` by a central difference of the true field;
- the linearisation: the exact Jacobian of the true field at the equilibrium
  (:func:`lyapcheck.models.classes.recast_classes.jacobian`), central differences where it has none (a
  function not differentiable there);
- the angles (:func:`lyapcheck.models.classes.recast_classes.angle_states`): measured modulo 2 pi.

The document is the polynomial loop's, plus ``kind`` ("recast"), ``field`` (what was integrated)
and ``angles_modulo_2pi``.
"""

from __future__ import annotations

import tomllib
from dataclasses import dataclass
from fractions import Fraction
from typing import TYPE_CHECKING, Any, Final, Sequence

import numpy as np

from lyapcheck.models.language.recast import RecastModel, RecastSystem
from lyapcheck.models.engines.recast_numeric import TrueField
from lyapcheck.sos.polynomials import Ring, degree_in

if TYPE_CHECKING:  # pragma: no cover
    from lyapcheck.models.surfaces.simulate import CompiledPolys, FloatArray, Prepared

#: the cross-checks' horizon (sweeps): slowest time constants of the linearisation (60 s without one)
HORIZON_TIME_CONSTANTS: Final = 40.0
#: the cross-checks' horizon without a decaying linearisation, s
FALLBACK_HORIZON_S: Final = 60.0
#: central differences: the step in a disturbance, as a fraction of its bound
GAIN_STEP: Final = 1e-3
#: central differences of the linearisation where the exact Jacobian does not exist: the step, as a
#: fraction of max(1, |x_eq|) (a state) or of the bound (a disturbance)
JACOBIAN_STEP: Final = 1e-6
#: what the document's ``field`` says was integrated
FIELD_TEXT: Final = "the true loop: each function evaluated by numpy, not the recast polynomial loop"


def default_horizon(model: RecastModel) -> float:
    """The horizon of the sweeps' cross-checks (:mod:`sweeps.crosscheck`): 40 slowest time
    constants of the exact linearisation, 60 s without a decaying one. (``simulate`` takes
    :func:`lyapcheck.models.surfaces.simulate.default_horizon`, the same for a polynomial loop.)"""
    from lyapcheck.models.classes.recast_classes import base_loop, jacobian

    J = jacobian(base_loop(model.system))
    if isinstance(J, str):
        return FALLBACK_HORIZON_S
    real = np.linalg.eigvals(np.array([[float(x) for x in row] for row in J])).real
    slowest = np.max(real)
    return float(HORIZON_TIME_CONSTANTS / -slowest) if slowest < 0 else FALLBACK_HORIZON_S


@dataclass(frozen=True)
class TrueOutputGain:
    """``G_k = dy'/dd_k`` at ``d = 0`` on the true loop: ``sum_i dy/dx_i df_i/dd_k``, the first factor
    exact, the second a central difference (the simulation's :class:`~lyapcheck.models.surfaces.simulate.OutputGain`)."""

    field: TrueField
    gradient: "CompiledPolys"
    dependent: tuple[bool, ...]
    bounds: Any

    def depends(self, k: int) -> bool:
        return self.dependent[k]

    def gain(self, k: int, x: FloatArray) -> FloatArray:
        h = GAIN_STEP * float(self.bounds[k])
        step = np.zeros((x.shape[0], len(self.bounds)))
        step[:, k] = h
        slope = (self.field(x, step) - self.field(x, -step)) / (2 * h)
        return np.sum(self.gradient(x) * slope, axis=1)


def _moved_by(system: RecastSystem, disturbance: str) -> list[str]:
    """The disturbance and every auxiliary whose argument depends on it (through earlier ones)."""
    ring = system.ring
    moved = [disturbance]
    for a in system.auxiliaries:
        if a.argument is not None and degree_in(ring, a.argument, moved) > 0:
            moved.append(a.name)
    return moved


def _dependence(model: RecastModel, output_gradient: Sequence[Any]) -> tuple[bool, ...]:
    """Per disturbance, whether ``y'`` may depend on it: a state whose rate ``y`` feels (its
    ``dy/dx_i`` is not identically 0) has a field that uses the disturbance or a function of it.
    (Structural: a term that cancels still counts, and its gain is then 0.)"""
    robust = model.robust
    if robust is None:
        return tuple(False for _ in model.disturbances)
    ring = robust.ring
    out = []
    for d in model.disturbances:
        moved = _moved_by(robust, d)
        out.append(any(not dy.is_zero() and (degree_in(ring, r.numerator, moved) > 0
                                             or degree_in(ring, r.denominator, moved) > 0)
                       for dy, r in zip(output_gradient, robust.field[:model.n])))
    return tuple(out)


def _jacobian(model: RecastModel, field: TrueField, equilibrium: FloatArray, bounds: FloatArray
              ) -> tuple[list[list[Any]], list[list[Any]]]:
    """``A = df/dx``, ``B = df/dd`` at the equilibrium (``d = 0``): exact (the chain rule through the
    auxiliaries, :func:`lyapcheck.models.classes.recast_classes.jacobian`), else central differences."""
    from lyapcheck.models.classes.recast_classes import base_loop, jacobian

    n, m = model.n, len(model.disturbances)
    system = model.robust if m and model.robust is not None else model.system
    exact = jacobian(base_loop(system))
    if not isinstance(exact, str):
        A = [row[:n] for row in exact[:n]]
        B = [row[n:n + m] if system is model.robust else [Fraction(0)] * m for row in exact[:n]]
        return A, B
    x0, d0 = equilibrium[None, :], np.zeros((1, m))
    A_num = np.zeros((n, n))
    for j in range(n):
        h = JACOBIAN_STEP * max(1.0, abs(float(equilibrium[j])))
        e = np.zeros((1, n))
        e[0, j] = h
        with np.errstate(all="ignore"):
            A_num[:, j] = (field(x0 + e, d0 if m else None) - field(x0 - e, d0 if m else None))[0] / (2 * h)
    B_num = np.zeros((n, m))
    if field.disturbed is not None:
        for k in range(m):
            h = JACOBIAN_STEP * float(bounds[k])
            e = np.zeros((1, m))
            e[0, k] = h
            with np.errstate(all="ignore"):
                B_num[:, k] = (field(x0, e) - field(x0, -e))[0] / (2 * h)
    A_num[~np.isfinite(A_num)] = 0.0
    B_num[~np.isfinite(B_num)] = 0.0
    return A_num.tolist(), B_num.tolist()


def output_text(model: RecastModel) -> dict[str, str]:
    """Each output's text as the file writes it (default: each state, named by itself)."""
    table = tomllib.loads(model.text).get("outputs")
    written = table if isinstance(table, dict) else {}
    return {name: str(written.get(name, name)) for name in model.outputs}


def prepare_true_loop(model: RecastModel) -> "Prepared":
    """A loop with functions ready for :mod:`lyapcheck.models.surfaces.simulate`: its true field, outputs,
    bang-bang gains, linearisation and angles (the module docstring)."""
    from lyapcheck.models.classes.recast_classes import angle_states
    from lyapcheck.models.surfaces.simulate import CompiledPolys, Prepared, linearization

    states = Ring(model.states)
    eq = np.array([float(v) for v in model.equilibrium])
    bounds = np.array([float(b) for b in model.disturbances.values()])
    field = TrueField(model)
    names = tuple(model.outputs)
    feedback: dict[str, TrueOutputGain] = {}
    C: dict[str, list[Fraction]] = {}
    for name in names:
        y = model.outputs[name]
        grad = [y.derivative(s) for s in model.states]
        C[name] = [states.evaluate(g, list(model.equilibrium)) for g in grad]
        feedback[name] = TrueOutputGain(field, CompiledPolys(states, grad), _dependence(model, grad), bounds)
    A, B = _jacobian(model, field, eq, bounds)
    angles = tuple(angle_states(model.system))
    held = None
    text = FIELD_TEXT
    if model.disturbances and model.robust is None:
        held = ("its disturbances cannot be kept as variables of the recast loop: it is simulated with "
                f"{', '.join(model.disturbances)} held at 0")
        text += f"; the disturbances {', '.join(model.disturbances)} held at 0 (scenario none only)"
    return Prepared(model=model, field=field, output_polys=CompiledPolys(states, [model.outputs[y] for y in names]),
                    output_names=names, feedback=feedback, linearization=linearization(A, B, C), equilibrium=eq,
                    bounds=bounds, output_text=output_text(model),
                    angles=tuple(model.states.index(a) for a in angles), undisturbed_only=held,
                    document_keys={"kind": "recast", "field": text, "angles_modulo_2pi": list(angles)})


__all__ = ["TrueOutputGain", "prepare_true_loop", "output_text", "default_horizon"]
