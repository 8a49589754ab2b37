"""The certified region of attraction against the simulated one, in 2-D slices: the report's size figure.

For a certified ``roa`` (else ``candidate``) with a set ``{V <= level}``, each panel is a plane
through the equilibrium spanned by two states, the others held at the equilibrium: the phase plane
itself for a loop of 2 states, and for more the pairs (x1, x2), (x3, x4), ... (the last state paired
with the one before it when their count is odd), at most :data:`MAX_SLICES` panels. On each:

- the simulated region of attraction: a grid of starts over the ``[domain]``'s rectangle of the
  pair (without a domain, :data:`REACH` times the set's reach along each axis), each simulated on the true loop (disturbances 0) with the phase portrait's
  simulator (:func:`lyapcheck.models.engines.trajectories.simulate`; :data:`SLICE_STARTS` starts
  shared by the panels, at most :data:`SLICE_GRID` per side) and drawn as a dot where it
  converged; the grid, not the random starts of ``roa_share`` (those lie off the slice in more than
  two states);
- the certified set's slice: V's level curve ``V = level`` (and a ball-arithmetic region's box),
  filled, from the certificate's exact V converted to floats once;
- the size figures (:mod:`lyapcheck.models.classes.region_size`): the largest ball's circle and each
  axis extent's segment, where the certificate states them.

A panel is evidence, not proof: the dots are floating-point simulations; the set, the ball and the
extents are the certificate's.
"""

from __future__ import annotations

from fractions import Fraction
from typing import Any, Final, Sequence

import numpy as np

from reports.figures import Figure
from reports.views import as_dict, as_fraction

#: starts per side of a slice's grid of simulated starts, at most
SLICE_GRID: Final = 24
#: simulated starts of all the panels together (a 6-state loop's 3 panels: 20 x 20 each)
SLICE_STARTS: Final = 1200
#: points per side of the grid V is contoured on
CONTOUR_GRID: Final = 120
#: the most panels drawn (pairs of states)
MAX_SLICES: Final = 3
#: without a [domain]: the window's half-width in a state, in the set's reach along its axis
REACH: Final = 2.5
#: the classes whose set is drawn, in order of preference
SIZED: Final = ("roa", "candidate")


def pairs(n: int) -> list[tuple[int, int]]:
    """The slices of a loop of ``n`` states: (0, 1), (2, 3), ...; an odd last state paired with the one before."""
    if n < 2:
        return []
    out = [(i, i + 1) for i in range(0, n - 1, 2)]
    if n % 2:
        out.append((n - 2, n - 1))
    return out[:MAX_SLICES]


def plane_points(eq: np.ndarray, i: int, j: int, xs: np.ndarray, ys: np.ndarray
                 ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The grid ``xs`` x ``ys`` on the plane of states ``i`` and ``j`` through ``eq`` (every other state at
    its value in ``eq``): the meshes of the two coordinates (``ij`` indexing, ``len(xs) x len(ys)``) and the
    grid's points, one a row of all the states. The one slice through a point that the report's figures
    draw (a continuous loop's panels here, a map's certified region in :mod:`reports.map_figures`)."""
    mx, my = np.meshgrid(xs, ys, indexing="ij")
    points = np.tile(np.asarray(eq, dtype=np.float64), (mx.size, 1))
    points[:, i], points[:, j] = mx.ravel(), my.ravel()
    return mx, my, points


def sized_condition(doc: dict[str, Any]) -> tuple[str, dict[str, Any]] | None:
    """The first certified class of :data:`SIZED` whose certificate has a V and a level."""
    conditions = as_dict(doc.get("conditions"))
    for name in SIZED:
        cond = as_dict(conditions.get(name))
        cert = as_dict(cond.get("certificate"))
        if cond.get("status") == "certified" and "V" in cert and as_fraction(cert.get("level")) is not None:
            return name, cond
    return None


def _evaluator(doc: dict[str, Any], model: Any, cert: dict[str, Any]) -> Any:
    """``Z -> V(Z) / level`` (rows of deviations from the equilibrium), with a ball-arithmetic region's
    box gauge (the set is ``<= 1``)."""
    from lyapcheck.models.language.recast import RecastModel

    level = float(Fraction(cert["level"]))
    n = len(model.states)
    if isinstance(model, RecastModel):
        from lyapcheck.models.engines.recast_numeric import v_values
        from lyapcheck.models.engines.recast_sos import poly_from_json

        V = poly_from_json(model.system.ring, cert["V"], "V")

        def values(Z: np.ndarray) -> np.ndarray:
            return np.asarray(v_values(model.system, V, Z), dtype=np.float64)
    else:
        terms = [(float(Fraction(c)), np.array(e, dtype=np.int64)) for c, e in cert["V"]["terms"]]
        if any(len(e) != n for _, e in terms):
            raise ValueError("V depends on a box's parameters: no slice is drawn")

        def values(Z: np.ndarray) -> np.ndarray:
            out = np.zeros(len(Z))
            for c, e in terms:
                out += c * np.prod(Z ** e, axis=1)
            return out
    box = as_dict(cert.get("box")) if cert.get("kind") == "interval" else {}
    corners = [(float(Fraction(box[s][0])), float(Fraction(box[s][1]))) for s in model.states] if box else None

    def gauge(Z: np.ndarray) -> np.ndarray:
        with np.errstate(all="ignore"):
            g = values(Z) / level
        if corners is not None:
            lo = np.array([c[0] for c in corners])
            hi = np.array([c[1] for c in corners])
            g = np.maximum(g, np.max(np.abs(Z - (lo + hi) / 2) / ((hi - lo) / 2), axis=1))
        return np.where(np.isfinite(g), g, 1e300)

    return gauge


def _window(model: Any, cond: dict[str, Any], eq: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The simulated rectangle per state (declared coordinates): the domain, else around the set's reach."""
    n = len(model.states)
    domain = getattr(model, "domain", None) or {}
    extents = as_dict(as_dict(cond.get("size")).get("axis_extents"))
    lo, hi = np.zeros(n), np.zeros(n)
    for i, s in enumerate(model.states):
        if s in domain:
            a, b = domain[s]
            lo[i], hi[i] = float(a), float(b)
        else:
            reach = float(extents.get(s) or 1.0)
            lo[i], hi[i] = eq[i] - REACH * reach, eq[i] + REACH * reach
    return lo, hi


def size_figure(doc: dict[str, Any], model: Any) -> tuple[Figure | None, str]:
    """The slices figure of a model certificate (module docstring), or None and why not."""
    from lyapcheck.models.engines.trajectories import horizon, jacobian_eigenvalues, simulate
    from lyapcheck.models.engines.numeric import FieldEvaluator
    from lyapcheck.models.engines.recast_numeric import TrueField
    from lyapcheck.models.language.recast import RecastModel
    from reports.figures import _new, to_svg

    found = sized_condition(doc)
    if found is None:
        return None, "no certified region of attraction (roa or candidate) with a level"
    name, cond = found
    cert = as_dict(cond.get("certificate"))
    n = len(model.states)
    slices = pairs(n)
    if not slices:
        return None, "a loop of one state has no plane to draw"
    gauge = _evaluator(doc, model, cert)
    eq = np.array([float(v) for v in model.equilibrium])
    lo, hi = _window(model, cond, eq)
    half = (hi - lo) / 2
    field: Any = TrueField(model) if isinstance(model, RecastModel) else FieldEvaluator.of(model)
    t_end = horizon(jacobian_eigenvalues(field, eq, half))
    size = as_dict(cond.get("size"))
    radius = size.get("ball_radius")
    extents = as_dict(size.get("axis_extents"))
    fig, axes = _new(3.2 * ((len(slices) + 1) // 2), ncols=min(len(slices), 2), nrows=(len(slices) + 1) // 2)
    flat = axes.ravel()
    counts = []
    grid = min(SLICE_GRID, int((SLICE_STARTS / len(slices)) ** 0.5))
    for k, (i, j) in enumerate(slices):
        ax = flat[k]
        X = plane_points(eq, i, j, np.linspace(lo[i], hi[i], grid), np.linspace(lo[j], hi[j], grid))[2]
        runs = simulate(model, X, t_end=t_end, half_widths=half)
        converged = np.array([r.outcome == "converged" for r in runs])
        ux, uy, C = plane_points(eq, i, j, np.linspace(lo[i], hi[i], CONTOUR_GRID),
                                 np.linspace(lo[j], hi[j], CONTOUR_GRID))
        G = gauge(C - eq).reshape(CONTOUR_GRID, CONTOUR_GRID)
        ax.contourf(ux, uy, G, levels=[-1e300, 1.0], colors=["#1a7f37"], alpha=0.25)
        ax.contour(ux, uy, G, levels=[1.0], colors=["#1a7f37"], linewidths=1.2)
        ax.plot(X[converged, i], X[converged, j], ".", ms=2.5, color="#0969da")
        ax.plot(X[~converged, i], X[~converged, j], ".", ms=1.5, color="#cf222e", alpha=0.5)
        if isinstance(radius, (int, float)) and not isinstance(radius, bool):
            t = np.linspace(0, 2 * np.pi, 200)
            ax.plot(eq[i] + radius * np.cos(t), eq[j] + radius * np.sin(t), "--", color="#6e7781", lw=1)
        for axis, other, horizontal in ((i, j, True), (j, i, False)):
            a = extents.get(model.states[axis])
            if isinstance(a, (int, float)) and not isinstance(a, bool):
                seg = np.array([eq[axis] - a, eq[axis] + a])
                fixed = np.array([eq[other], eq[other]])
                ax.plot(*((seg, fixed) if horizontal else (fixed, seg)), "-", color="#8250df", lw=2)
        ax.plot([eq[i]], [eq[j]], "k+", ms=8)
        ax.set_xlim(lo[i], hi[i])
        ax.set_ylim(lo[j], hi[j])
        ax.set_xlabel(model.states[i])
        ax.set_ylabel(model.states[j])
        others = [s for m, s in enumerate(model.states) if m not in (i, j)]
        ax.set_title(f"{model.states[i]}, {model.states[j]}" + (" (others at x_eq)" if others else ""), fontsize=9)
        counts.append(int(converged.sum()))
    for ax in flat[len(slices):]:
        ax.set_visible(False)
    which = ("the phase plane" if n == 2 else
             f"{len(slices)} planes through the equilibrium, two states each, the others at the equilibrium")
    caption = (f"The certified set of {name} (green, V = level: its slice) against the simulated region of attraction "
               f"in {which}: blue dots are grid starts that converged on the true loop (disturbances 0), red ones did "
               "not; dashed, the largest ball proved inside the set (a circle in the states' coordinates, an ellipse where the two axes' scales differ); purple, the set's proved reach along each state's "
               "axis (its reach through the equilibrium, not its projection). The dots are simulations, evidence "
               "not proof; the set, the ball and the segments are the certificate's.")
    alt = f"slices of the certified region of {name} with the simulated region of attraction"
    return Figure(to_svg(fig), caption, alt, {"slices": [(model.states[i], model.states[j]) for i, j in slices],
                                              "converged": counts, "class": name}), ""


__all__ = ["CONTOUR_GRID", "MAX_SLICES", "SLICE_GRID", "SLICE_STARTS", "pairs", "plane_points", "size_figure",
           "sized_condition"]
