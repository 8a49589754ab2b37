"""The figures of a discrete-time map's certificate (``[model] time = "discrete"``), and the iterations behind them.

A map ``x+ = f(x)`` has no flow to integrate: where a continuous model's page draws integrated trajectories
(:mod:`reports.phase_portrait`, :mod:`reports.region_slices`), a map's page draws its **iterates**, computed by
the one iterator of ``simulate`` (:func:`lyapcheck.models.surfaces.iterate.iterate`: the polynomial map
evaluated exactly as written, a map with functions through
:class:`~lyapcheck.models.surfaces.iterate.MapIterator`). Three figures:

- **iterates** (two or more states): the iterates of a few starts (two rings around the fixed point, as wide
  as the ``[domain]`` or the certified set) in the plane of the first two states, each iterate a dot and
  consecutive iterates joined by a thin line; with three or more states the starts lie in that plane's slice
  (the other states at the fixed point) and the iterates are drawn projected onto it;
- **the certified region**: each certified set of ``roa`` or ``candidate`` (``{V <= level}``, kinds
  ``discrete_sublevel`` and ``discrete_interval``; the slice through the fixed point for three or more
  states, an interval on the axis for one state) filled, with the iterates of starts just inside its
  boundary (:data:`INSIDE_FRACTION` of the way along rays from the fixed point);
- **the staircase**: every state against the step number, each value held until the next step.

The iterates from inside a certified set are also **checked against the certificate** (evidence, not
proof): a certified ``{V <= level}`` of a map says ``V(f(x)) <= V(x)`` there, so ``V`` must not rise along
them, none may escape, and they should reach the fixed point. A failed check is a soundness alarm on the page.

``V`` is evaluated from the certificate's exact terms (each coefficient the nearest float once): a
``discrete_sublevel`` V is a polynomial in ``e = x - x_eq``, a ``discrete_interval`` V is ``e^T P e``.
Nothing from the document is evaluated as code.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from fractions import Fraction
from typing import TYPE_CHECKING, Any, Callable, Final, Sequence

import numpy as np

from lyapcheck.models.engines.crosscheck import check_region, ray_boundary
from reports.figures import Figure, _new, to_svg
from reports.phase_portrait import CrossCheck
from reports.polynomials import ExactPolynomial

if TYPE_CHECKING:  # pragma: no cover
    from numpy.typing import NDArray

    from lyapcheck.models.language.modelfile import Model
    from lyapcheck.models.language.recast import RecastModel

    FloatArray = NDArray[np.float64]

#: iterations drawn from every start first (a few tens: most certified maps contract within them) ...
STEPS: Final = 40
#: ... then this many times as many while a sequence is undecided, up to MAX_STEPS (a sampled loop's map)
STEPS_GROWTH: Final = 4
MAX_STEPS: Final = 640
#: the most dots drawn along one sequence (past it, every k-th iterate is a dot; the line joins them all)
MAX_DOTS: Final = 60
#: rays along which a certified set's reach in the plane is found (its view)
REACH_DIRECTIONS: Final = 64
#: directions of the starts' rings in the plane, and the rings' radii as fractions of the view's half-width
RING_DIRECTIONS: Final = 8
RING_FRACTIONS: Final = (0.5, 1.0)
#: starts inside a certified set: this fraction of the way to its boundary, along RING_DIRECTIONS rays
INSIDE_FRACTION: Final = 0.95
#: the view around the fixed point: the starts' extent times this
VIEW_PAD: Final = 1.25
#: the grid the certified set is contoured on (per axis)
GRID: Final = 201
#: a state's half-width without a [domain] or a certified set
DEFAULT_HALF_WIDTH: Final = 1.0
#: the staircase's vertical range: at most this many view half-widths from the fixed point
SERIES_CLIP: Final = 3.0
#: the most states drawn in the staircase (one panel each)
MAX_SERIES_STATES: Final = 4
#: the certificate kinds of a map's region of attraction
SET_KINDS: Final = ("discrete_sublevel", "discrete_interval")
#: the classes whose certified set is drawn
SET_CLASSES: Final = ("roa", "candidate")
#: colours of an iterate sequence by how it ended
OUTCOME_COLOURS: Final = {"converged": "#1f6fb4", "escaped": "#c0392b", "other": "#d68910"}


@dataclass(frozen=True)
class MapSet:
    """A certified ``{V <= level}`` of the map: ``V`` of deviations ``e = x - x_eq`` (a batch ``(k, n)``)."""

    cls: str
    kind: str
    V: Callable[["FloatArray"], "FloatArray"]
    level: float


@dataclass
class MapFigures:
    """The map's figures (each None with the reason when not drawn) and the checks of its iterates."""

    iterates: Figure | None = None
    iterates_reason: str = ""
    region: Figure | None = None
    region_reason: str = ""
    series: Figure | None = None
    series_reason: str = ""
    checks: list[CrossCheck] = field(default_factory=list)


def certified_sets(doc: dict[str, Any], n: int) -> list[MapSet]:
    """Every certified set of ``roa`` and ``candidate`` of a map's certificate (module doc)."""
    out = []
    conditions = doc.get("conditions")
    for cls in SET_CLASSES:
        cond = conditions.get(cls) if isinstance(conditions, dict) else None
        if not isinstance(cond, dict) or cond.get("status") != "certified":
            continue
        cert = cond.get("certificate")
        if not isinstance(cert, dict) or cert.get("kind") not in SET_KINDS:
            continue
        level = float(Fraction(str(cert["level"])))
        if cert["kind"] == "discrete_sublevel":
            out.append(MapSet(cls, cert["kind"], ExactPolynomial.from_json(cert["V"], n).evaluator(), level))
            continue
        P = np.array([[float(Fraction(str(v))) for v in row] for row in cert["P"]], dtype=np.float64)
        if P.shape != (n, n):
            raise ValueError(f"the {cls} certificate's P is {P.shape[0]} x {P.shape[1] if P.ndim == 2 else 0}, "
                             f"not {n} x {n}")
        out.append(MapSet(cls, cert["kind"], _quadratic(P), level))
    return out


def _quadratic(P: "FloatArray") -> Callable[["FloatArray"], "FloatArray"]:
    def V(e: "FloatArray") -> "FloatArray":
        return np.asarray(np.einsum("ki,ij,kj->k", e, P, e), dtype=np.float64)
    return V


def _outcome(path: "FloatArray", eq: "FloatArray", scale: "FloatArray") -> str:
    """How an iterate sequence ended: ``escaped`` (left the iterator's escape box: NaN after it),
    ``converged`` (the last iterate within the convergence radius of ``simulate``), else ``other``."""
    from lyapcheck.models.surfaces.simulate import CONVERGENCE_RADIUS

    if not np.all(np.isfinite(path[-1])):
        return "escaped"
    return "converged" if np.all(np.abs(path[-1] - eq) <= CONVERGENCE_RADIUS * scale) else "other"


def _half_widths(model: "Model | RecastModel", eq: "FloatArray", reach: "FloatArray | None") -> "FloatArray":
    """The starts' half-width per state: the ``[domain]``'s, else the certified sets' reach, else a default."""
    if model.domain:
        return np.array([max(abs(float(model.domain[s][0]) - e), abs(float(model.domain[s][1]) - e))
                         for s, e in zip(model.states, eq)])
    if reach is not None:
        return reach
    return np.full(model.n, DEFAULT_HALF_WIDTH)


def _directions(n: int, count: int = RING_DIRECTIONS) -> "FloatArray":
    """``count`` unit directions in the plane of the first two states (the other states 0); one state: +-1."""
    if n == 1:
        return np.array([[1.0], [-1.0]])
    angles = np.linspace(0, 2 * np.pi, count, endpoint=False) + np.pi / count
    out = np.zeros((count, n))
    out[:, 0], out[:, 1] = np.cos(angles), np.sin(angles)
    return out


def map_figures(doc: dict[str, Any], model: "Model | RecastModel") -> MapFigures:
    """The map's three figures and the checks of the iterates from inside its certified sets (module doc)."""
    from lyapcheck.models.surfaces.iterate import scale_of

    n = model.n
    eq = np.array([float(v) for v in model.equilibrium])
    sets = certified_sets(doc, n)
    dirs = _directions(n)
    inside: list[tuple[MapSet, FloatArray]] = []
    reach = None
    for st in sets:
        # the set's reach in the plane drawn, then the starts' rays spread evenly over its shape (an elongated
        # set would get all its starts near its two ends along evenly spread directions)
        rim = ray_boundary(st.V, st.level, _directions(n, REACH_DIRECTIONS))
        if rim is None:
            continue
        extent = np.max(np.abs(rim), axis=0)
        spread = dirs * np.where(extent > 0, extent, 1.0)
        boundary = ray_boundary(st.V, st.level, spread / np.linalg.norm(spread, axis=1, keepdims=True))
        if boundary is None:
            continue
        inside.append((st, eq + INSIDE_FRACTION * boundary))
        reach = extent if reach is None else np.maximum(reach, extent)
    half = _half_widths(model, eq, reach)
    rings = np.vstack([eq + f * dirs * half for f in RING_FRACTIONS])
    scale = scale_of(model, rings)
    every = np.vstack([rings, *[starts for _, starts in inside]])
    paths, steps = _iterates(model, every, eq, scale, len(rings))
    ring_paths = paths[:len(rings)]
    inside_paths, first = [], len(rings)
    for _, starts in inside:
        inside_paths.append(paths[first:first + len(starts)])
        first += len(starts)
    out = MapFigures()
    for (st, _), mine in zip(inside, inside_paths):
        outcomes = [_outcome(p, eq, scale) for p in mine]
        values = [st.V(p[np.all(np.isfinite(p), axis=1)] - eq) for p in mine]
        found = check_region(values, outcomes)
        out.checks.append(CrossCheck(
            f"{st.cls}: the iterates of starts in {{V <= {st.level:.6g}}} stay in it (V never rises from one step "
            "to the next) and none escapes",
            found.ok, f"{found.starts} starts, {steps} steps each: {found.converged} reached the fixed point, "
                      f"{found.escaped} escaped; largest rise of V {found.worst_rise:.3g} of V(0)"))
    # each figure's view: the rings' (the iterates figure), the certified sets' reach (the region's)
    view = VIEW_PAD * half
    region_view = view if reach is None else VIEW_PAD * reach
    if n >= 2:
        out.iterates = _iterates_figure(model, eq, ring_paths, scale, view, steps)
    else:
        out.iterates_reason = "the map has one state: the staircase below shows its iterates against the step"
    if not sets:
        out.region_reason = "no roa or candidate set is certified"
    elif not inside:
        out.region_reason = "no certified set is bounded around the fixed point in the plane drawn"
    else:
        out.region = _region_figure(model, eq, inside, inside_paths, scale, region_view, steps)
    series_paths = inside_paths[0] if inside_paths else ring_paths
    out.series = _series_figure(model, eq, series_paths, scale, region_view if inside_paths else view, steps,
                                bool(inside_paths))
    return out


def _iterates(model: "Model | RecastModel", starts: "FloatArray", eq: "FloatArray", scale: "FloatArray",
              checked_from: int) -> tuple["FloatArray", int]:
    """The iterates of every start (:func:`lyapcheck.models.surfaces.iterate.iterate`) over :data:`STEPS`,
    and again over :data:`STEPS_GROWTH` times as many while a start from ``checked_from`` on (those inside a
    certified set, whose convergence is checked) has neither reached the fixed point nor escaped (a sampled
    loop's map moves little per step), at most :data:`MAX_STEPS`; and the count."""
    from lyapcheck.models.surfaces.iterate import iterate

    steps = STEPS
    while True:
        paths = iterate(model, starts, steps)
        undecided = any(_outcome(p, eq, scale) == "other" for p in paths[checked_from:])
        if not undecided or steps * STEPS_GROWTH > MAX_STEPS:
            return paths, steps
        steps *= STEPS_GROWTH


def _plane_labels(model: "Model | RecastModel") -> tuple[str, str, str]:
    """The axes' names and, for three or more states, what the plane is."""
    note = "" if model.n == 2 else (f"; starts in the slice {', '.join(f'{s} = {s}_eq' for s in model.states[2:])}, "
                                    f"iterates projected onto ({model.states[0]}, {model.states[1]})")
    return model.states[0], model.states[1], note


def _draw_paths(ax: Any, paths: "FloatArray", eq: "FloatArray", scale: "FloatArray", gid: str) -> dict[str, int]:
    """Each start's iterates as dots joined per step, coloured by how they ended; the counts per outcome."""
    counts = {"converged": 0, "escaped": 0, "other": 0}
    for i, path in enumerate(paths):
        outcome = _outcome(path, eq, scale)
        counts[outcome] += 1
        finite = path[np.all(np.isfinite(path), axis=1)]
        line, = ax.plot(finite[:, 0], finite[:, 1], "-", color=OUTCOME_COLOURS[outcome], lw=0.5, alpha=0.7,
                        marker=".", ms=3.5, markevery=max(1, -(-len(finite) // MAX_DOTS)))
        line.set_gid(f"{gid}-{i}")
        ax.plot(finite[:1, 0], finite[:1, 1], "o", color=OUTCOME_COLOURS[outcome], ms=4, mfc="white")
    return counts


def _limits(ax: Any, eq: "FloatArray", view: "FloatArray") -> None:
    ax.set_xlim(eq[0] - view[0], eq[0] + view[0])
    ax.set_ylim(eq[1] - view[1], eq[1] + view[1])


def _iterates_figure(model: "Model | RecastModel", eq: "FloatArray", paths: "FloatArray", scale: "FloatArray",
                     view: "FloatArray", steps: int) -> Figure:
    x, y, note = _plane_labels(model)
    fig, axes = _new(4.6)
    ax = axes[0, 0]
    if model.domain:
        lo = [float(model.domain[s][0]) for s in model.states[:2]]
        hi = [float(model.domain[s][1]) for s in model.states[:2]]
        ax.add_patch(_rectangle(lo, hi))
    counts = _draw_paths(ax, paths, eq, scale, "iterates")
    ax.plot(eq[0], eq[1], "k+", ms=11, mew=1.6, label="fixed point")
    _limits(ax, eq, view)
    ax.set_xlabel(x)
    ax.set_ylabel(y)
    ax.grid(alpha=0.3)
    ax.set_title(f"iterates of the map from {len(paths)} starts, {steps} steps each", fontsize=9)
    caption = (f"The map's iterates x[k+1] = f(x[k]) from {len(paths)} starts on two rings around the fixed point "
               f"({steps} steps each; each iterate a dot, consecutive iterates joined by a line, the start a circle; "
               f"blue: reached the fixed point, red: escaped, amber: neither by step {steps}){note}. "
               f"{counts['converged']} reached the fixed point, {counts['escaped']} escaped.")
    return Figure(to_svg(fig), caption, f"iterates of {model.name} in the ({x}, {y}) plane",
                  data={"starts": len(paths), "steps": steps, **counts})


def _rectangle(lo: Sequence[float], hi: Sequence[float]) -> Any:
    from matplotlib.patches import Rectangle

    box = Rectangle((lo[0], lo[1]), hi[0] - lo[0], hi[1] - lo[1], fill=False, ls="--", lw=0.8, ec="0.45",
                    label="[domain]")
    box.set_gid("domain")
    return box


def _region_figure(model: "Model | RecastModel", eq: "FloatArray", inside: Sequence[tuple[MapSet, "FloatArray"]],
                   paths: Sequence["FloatArray"], scale: "FloatArray", view: "FloatArray", steps: int) -> Figure:
    fig, axes = _new(4.6)
    ax = axes[0, 0]
    colours = ("#2e86c1", "#8e44ad")
    data: dict[str, Any] = {"sets": [], "inside_starts": 0}
    if model.n == 1:
        for k, ((st, _), p) in enumerate(zip(inside, paths)):
            boundary = ray_boundary(st.V, st.level, np.array([[1.0], [-1.0]]))
            assert boundary is not None  # inside holds only the bounded sets
            lo, hi = eq[0] + float(boundary[1, 0]), eq[0] + float(boundary[0, 0])
            band = ax.axhspan(lo, hi, color=colours[k % 2], alpha=0.18, lw=0, label=f"{st.cls}: {{V <= {st.level:.4g}}}")
            band.set_gid(f"certified-set-{st.cls}")
            for i, path in enumerate(p):
                line, = ax.step(np.arange(path.shape[0]), path[:, 0], where="post", color=colours[k % 2], lw=0.9)
                line.set_gid(f"inside-{st.cls}-{i}")
            data["sets"].append({"class": st.cls, "interval": [lo, hi]})
            data["inside_starts"] += len(p)
        ax.set_xlabel("step k")
        ax.set_ylabel(model.states[0])
        what = "the certified interval on the state's axis, and the iterates of starts at its ends against the step"
    else:
        from reports.region_slices import plane_points

        U, W, points = plane_points(eq, 0, 1, np.linspace(eq[0] - view[0], eq[0] + view[0], GRID),
                                    np.linspace(eq[1] - view[1], eq[1] + view[1], GRID))
        for k, ((st, _), p) in enumerate(zip(inside, paths)):
            gauge = (st.V(points - eq) / st.level).reshape(U.shape)  # (V of the deviations from the fixed point)
            filled = ax.contourf(U, W, gauge, levels=[-np.inf, 1.0], colors=[colours[k % 2]], alpha=0.2)
            filled.set_gid(f"certified-set-{st.cls}")
            ax.contour(U, W, gauge, levels=[1.0], colors=[colours[k % 2]], linewidths=1.2)
            _draw_paths(ax, p, eq, scale, f"inside-{st.cls}")
            data["sets"].append({"class": st.cls, "level": st.level, "inside_share_of_view": float(np.mean(gauge <= 1))})
            data["inside_starts"] += len(p)
        ax.plot(eq[0], eq[1], "k+", ms=11, mew=1.6)
        _limits(ax, eq, view)
        ax.set_xlabel(model.states[0])
        ax.set_ylabel(model.states[1])
        x, y, note = _plane_labels(model)
        what = (f"each certified set {{V <= level}} filled in the ({x}, {y}) plane"
                + (" (its slice through the fixed point)" if model.n > 2 else "")
                + f", and the iterates of starts {INSIDE_FRACTION:g} of the way to its boundary" + note)
    ax.grid(alpha=0.3)
    ax.set_title("the certified region of attraction and iterates from inside it", fontsize=9)
    names = ", ".join(f"{st.cls} ({st.kind}, level {st.level:.6g})" for st, _ in inside)
    caption = (f"The certified region of the map: {what}; {steps} steps each. Every start in such a set stays in "
               f"it and its iterates converge to the fixed point (proved); the drawn iterates are checked against "
               f"that below. Sets: {names}.")
    return Figure(to_svg(fig), caption, f"certified region of {model.name} with iterates", data=data)


def _series_figure(model: "Model | RecastModel", eq: "FloatArray", paths: "FloatArray", scale: "FloatArray",
                   view: "FloatArray", steps: int, from_set: bool) -> Figure:
    shown = min(model.n, MAX_SERIES_STATES)
    fig, axes = _new(1.7 * shown + 0.6, nrows=shown, sharex=True)
    k = np.arange(paths.shape[1])
    for s in range(shown):
        ax = axes[s, 0]
        for i, path in enumerate(paths):
            colour = OUTCOME_COLOURS[_outcome(path, eq, scale)]
            line, = ax.step(k, path[:, s], where="post", color=colour, lw=0.9, alpha=0.8)
            line.set_gid(f"staircase-{s}-{i}")
        ax.axhline(eq[s], color="k", lw=0.6, ls=":")
        # an escaping sequence grows geometrically before it stops: the axis keeps to the starts' scale
        values = paths[:, :, s][np.isfinite(paths[:, :, s])]
        lo = max(float(values.min()), eq[s] - SERIES_CLIP * view[s])
        hi = min(float(values.max()), eq[s] + SERIES_CLIP * view[s])
        pad = 0.05 * max(hi - lo, 1e-12)
        ax.set_ylim(lo - pad, hi + pad)
        ax.set_ylabel(model.states[s])
        ax.grid(alpha=0.3)
    axes[-1, 0].set_xlabel("step k")
    more = "" if model.n <= MAX_SERIES_STATES else f" (the first {MAX_SERIES_STATES} of {model.n} states)"
    where = ("starts just inside the certified set" if from_set else "the starts of the iterates figure")
    caption = (f"Every state{more} against the step k from {len(paths)} {where}, {steps} steps: a map's state "
               f"holds its value from one step to the next (a staircase); the dotted line is the fixed point.")
    return Figure(to_svg(fig), caption, f"states of {model.name} against the step", data={"starts": len(paths),
                                                                                          "steps": steps})


__all__ = ["STEPS", "MAX_STEPS", "MapSet", "MapFigures", "certified_sets", "map_figures"]
