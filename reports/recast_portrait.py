"""The phase portrait of a 2-state loop with functions, in its own states (the pendulum in (theta, omega)).

What is drawn:

- the **true field** (the model's own functions, evaluated by numpy through
  :func:`lyapcheck.models.engines.recast_numeric.field_values`, not the recasting's polynomial field) as
  grey streamlines;
- each **certified set** its class's section names (:meth:`reports.sections.recast.RecastSection.portrait_set`),
  filled, with its boundary a solid line. A set is drawn through its *gauge*, ``<= 1`` exactly on
  the set: ``V / level`` for a recast certificate (V evaluated with every auxiliary at its
  definition, :func:`lyapcheck.models.engines.recast_numeric.v_values`), and for an interval certificate
  the larger of ``V / level`` and the box's own gauge (``max |z_i - centre_i| / half-width_i``),
  so the drawn set is the certificate's ``{x - x_eq in box, V <= level}``; the box is drawn dashed;
- the equilibrium, and where the loop has angles its copies ``2 k pi`` apart that fall in the view;
- the model's ``[sets]`` shaded and each ``counterexample`` simulated again on the true loop from its
  stored start, drawn by the polynomial portrait's own functions (:mod:`reports.phase_portrait`).

The view is the model's ``[domain]`` (else ``+-pi`` in an angle and
:data:`lyapcheck.models.engines.recast_numeric.DEFAULT_HALF_WIDTH` elsewhere, the box the ``roa`` class
compares its sets in) joined with every certificate's box and with each recast set's extent in the
states that are not angles (searched up to :data:`REACH` times that box), the model's sets and the
counterexamples, padded. Only the counterexamples are simulated here: the ``roa`` class simulated its
set on the true loop when it was certified, and its figures are on the page. The model text is parsed by the project's parser only (the caller's
:func:`lyapcheck.models.language.modelfile.parse_any_model`); nothing from the document is evaluated.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, Final, Sequence

import numpy as np
import numpy.typing as npt

from lyapcheck.models.language.recast import RecastModel
from reports.figures import Figure, WIDTH_IN, to_svg
from reports.phase_portrait import (SET_SEARCH, Counterexample, counterexample_trajectories, counterexample_words,
                                    draw_counterexamples, draw_model_sets, model_sets_sentence, set_boxes)
from reports.sections import section_for
from reports.sections.recast import RECAST_LOOP, RecastSection, RecastSet
from reports.views import as_dict

FloatArray = npt.NDArray[np.float64]

#: points per axis of the grid each set's gauge is evaluated on
GRID: Final = 241
#: points per axis of the grid the field's streamlines are drawn from
STREAM_GRID: Final = 61
#: matplotlib's streamline density (about 30 x 30 cells carry a line): enough to read the flow,
#: light enough for the page (the field's lines are the figure's largest part)
STREAM_DENSITY: Final = 1.1
#: padding of the view around the boxes it must hold, as a share of their span
PAD: Final = 0.06
#: the gauge's value outside the grid's finite points (a float the contour code can read)
FAR: Final = 1e6
#: a recast set (no box) is searched up to this many times the model's box about the equilibrium
#: (in the states that are not angles), on a coarse grid of this many points per axis, and the
#: view grown to hold it
REACH: Final = 3.0
REACH_GRID: Final = 121


@dataclass
class RecastPortrait:
    """The figure (None with the reason when there is none) and the notes its caption carries."""

    figure: Figure | None
    reason: str = ""
    notes: list[str] = field(default_factory=list)


def certified_sets(doc: dict[str, Any]) -> tuple[list[RecastSet], list[str], list[str]]:
    """The certified sets of the document's classes; the classes with a global claim; notes on the
    sets that cannot be read."""
    sets, global_, notes = [], [], []
    for name, cond in as_dict(doc.get("conditions")).items():
        cond = as_dict(cond)
        if cond.get("status") != "certified":
            continue
        section = section_for(RECAST_LOOP, str(name))
        if not isinstance(section, RecastSection):
            continue
        try:
            found = section.portrait_set(str(name), cond)
        except ValueError as exc:
            notes.append(f"{name}'s set is not drawn: {exc}.")
            continue
        cert = as_dict(cond.get("certificate"))
        if found is not None:
            sets.append(found)
        elif cert.get("kind") == "recast":
            angles = [str(a) for a in cert.get("angles") or []] if isinstance(cert.get("angles"), list) else []
            global_.append(str(name) + (f" (modulo 2π in {', '.join(angles)})" if angles else ""))
    return sets, global_, notes


def base_view(model: RecastModel, angles: set[str]) -> tuple[FloatArray, FloatArray]:
    """The model's [domain], else the box the roa class compares its sets in (absolute states)."""
    from lyapcheck.models.engines.recast_numeric import DEFAULT_HALF_WIDTH

    eq = np.array([float(v) for v in model.equilibrium])
    if model.domain is not None:
        return (np.array([float(model.domain[s][0]) for s in model.states]),
                np.array([float(model.domain[s][1]) for s in model.states]))
    half = np.array([math.pi if s in angles else DEFAULT_HALF_WIDTH for s in model.states])
    return eq - half, eq + half


def gauge(model: RecastModel, spec: RecastSet, X: FloatArray) -> FloatArray:
    """``<= 1`` exactly on the set, at the states ``X`` (rows); :data:`FAR` where V is not finite."""
    from lyapcheck.models.engines.recast_numeric import v_values
    from lyapcheck.models.engines.recast_sos import poly_from_json

    system = model.system
    V = poly_from_json(system.ring, spec.V, "V")
    eq = np.array([float(v) for v in model.equilibrium])
    Z = X - eq
    with np.errstate(all="ignore"):
        g = v_values(system, V, Z) / float(spec.level)
    if spec.box is not None:
        lo = np.array([float(spec.box[s][0]) for s in model.states])
        hi = np.array([float(spec.box[s][1]) for s in model.states])
        centre, half = 0.5 * (lo + hi), 0.5 * (hi - lo)
        g = np.maximum(g, np.max(np.abs(Z - centre) / half, axis=1))
    return np.where(np.isfinite(g), g, FAR)


def reach(model: RecastModel, spec: RecastSet, lo: FloatArray, hi: FloatArray, angles: set[str],
          notes: list[str]) -> tuple[FloatArray, FloatArray]:
    """The view ``(lo, hi)`` grown to hold a recast set (no box of its own) in every state that is
    not an angle (in an angle the set repeats every 2 pi: the view keeps its range). The set is
    searched on a coarse grid up to :data:`REACH` times the view's half-widths about the equilibrium."""
    eq = np.array([float(v) for v in model.equilibrium])
    free = np.array([s not in angles for s in model.states])
    if not free.any():
        return lo, hi
    far_lo = np.where(free, eq - REACH * (eq - lo), lo)
    far_hi = np.where(free, eq + REACH * (hi - eq), hi)
    axes = [np.linspace(far_lo[i], far_hi[i], REACH_GRID) for i in range(2)]
    G0, G1 = np.meshgrid(*axes, indexing="ij")
    points = np.column_stack([G0.ravel(), G1.ravel()])
    inside = points[gauge(model, spec, points) <= 1.0]
    if not len(inside):
        return lo, hi
    step = (far_hi - far_lo) / (REACH_GRID - 1)
    set_lo, set_hi = inside.min(axis=0) - step, inside.max(axis=0) + step
    if np.any(free & ((set_lo <= far_lo) | (set_hi >= far_hi))):
        notes.append(f"{spec.name}'s set reaches past {REACH:g} times the model's box: the view shows its part "
                     "near the equilibrium.")
    return (np.where(free, np.minimum(lo, np.maximum(set_lo, far_lo)), lo),
            np.where(free, np.maximum(hi, np.minimum(set_hi, far_hi)), hi))


def _label(text: str) -> str:
    """Text for a matplotlib label: a '$' must not switch on mathtext."""
    return text.replace("$", r"\$")


def recast_portrait(doc: dict[str, Any], model: RecastModel) -> RecastPortrait:
    """The phase portrait of a 2-state loop with functions (see the module docstring)."""
    from matplotlib.colors import to_rgba
    from matplotlib.figure import Figure as MplFigure
    from matplotlib.patches import Rectangle

    from lyapcheck.models.engines.recast_numeric import field_values

    n = len(model.states)
    if n != 2:
        return RecastPortrait(None, f"the loop has {n} state{'s' if n != 1 else ''}: a phase portrait is drawn for 2 "
                                    "states only, so this report shows tables")
    sets, global_, notes = certified_sets(doc)
    angles = {str(a) for a in as_dict(as_dict(doc.get("recast")).get("angles"))}
    eq = np.array([float(v) for v in model.equilibrium])
    lo, hi = base_view(model, angles)
    for spec in sets:
        if spec.box is not None:
            lo = np.minimum(lo, eq + np.array([float(spec.box[s][0]) for s in model.states]))
            hi = np.maximum(hi, eq + np.array([float(spec.box[s][1]) for s in model.states]))
    for spec in sets:
        if spec.box is None:
            lo, hi = reach(model, spec, lo, hi, angles, notes)
    # the model's [sets] and the counterexamples join the view, as in a polynomial loop's portrait
    centre, half_span = 0.5 * (lo + hi), 0.5 * SET_SEARCH * (hi - lo)
    for key, found in set_boxes(model, centre - half_span, centre + half_span).items():
        if found is None:
            notes.append(f"The {key} set is not drawn: no point of the grid searched is in it.")
        else:
            lo, hi = np.minimum(lo, found[0]), np.maximum(hi, found[1])
    counterexamples, ce_notes = counterexample_trajectories(doc, model, np.maximum((hi - lo) / 2, 1e-300))
    notes += ce_notes
    for ce in counterexamples:
        lo, hi = np.minimum(lo, ce.x.min(axis=0)), np.maximum(hi, ce.x.max(axis=0))
    span = hi - lo
    lo, hi = lo - PAD * span, hi + PAD * span

    fig = MplFigure(figsize=(WIDTH_IN, 4.6), layout="constrained")
    ax = fig.subplots()
    sx, sy = np.linspace(lo[0], hi[0], STREAM_GRID), np.linspace(lo[1], hi[1], STREAM_GRID)
    SX, SY = np.meshgrid(sx, sy)
    with np.errstate(all="ignore"):
        F = field_values(model.system, np.column_stack([SX.ravel(), SY.ravel()]))
    U = np.ma.masked_invalid(F[:, 0].reshape(SX.shape))
    W = np.ma.masked_invalid(F[:, 1].reshape(SX.shape))
    stream = ax.streamplot(sx, sy, U, W, density=STREAM_DENSITY, color="#8c959f", linewidth=0.6, arrowsize=0.7,
                           zorder=1)
    stream.lines.set_gid("true-field")
    ax.plot([], [], color="#8c959f", lw=0.8, label="the true field (streamlines)")

    x, y = np.linspace(lo[0], hi[0], GRID), np.linspace(lo[1], hi[1], GRID)
    X, Y = np.meshgrid(x, y)
    points = np.column_stack([X.ravel(), Y.ravel()])
    data: dict[str, Any] = {"view": (lo.tolist(), hi.tolist()), "sets": {}, "global": list(global_)}
    cell = float((x[1] - x[0]) * (y[1] - y[0]))
    for spec in sets:
        try:
            G = gauge(model, spec, points).reshape(X.shape)
        except (ValueError, ArithmeticError) as exc:
            notes.append(f"{spec.name}'s set is not drawn: its V cannot be read ({exc}).")
            continue
        inside = int(np.count_nonzero(G <= 1.0))
        at_eq = float(gauge(model, spec, eq[None, :])[0])
        data["sets"][spec.name] = {"kind": spec.kind, "level": float(spec.level), "grid_points_inside": inside,
                                   "area": inside * cell, "gauge_at_equilibrium": at_eq, "angles": list(spec.angles)}
        if not inside:
            notes.append(f"{spec.name}'s set meets no point of the grid (it is smaller than a grid cell).")
            continue
        bottom = min(float(G.min()), 0.0) - 1.0
        filled = ax.contourf(x, y, G, levels=[bottom, 1.0], colors=[to_rgba(spec.colour, 0.22)], zorder=2)
        filled.set_gid(f"certified-set-{spec.name}")
        if np.any(G > 1.0):
            ax.contour(x, y, G, levels=[1.0], colors=[spec.colour], linewidths=1.5, zorder=3)
        ax.fill([], [], facecolor=to_rgba(spec.colour, 0.22), edgecolor=spec.colour, lw=1.5, label=_label(spec.label))
        if spec.box is not None:
            blo = eq + np.array([float(spec.box[s][0]) for s in model.states])
            bhi = eq + np.array([float(spec.box[s][1]) for s in model.states])
            ax.add_patch(Rectangle((blo[0], blo[1]), bhi[0] - blo[0], bhi[1] - blo[1], fill=False, ls="--", lw=1.0,
                                   edgecolor=spec.colour, zorder=3, label=_label(f"{spec.name}'s box")))

    shown_sets = draw_model_sets(ax, model, lo, hi)
    draw_counterexamples(ax, counterexamples, lo, hi)
    data["model_sets_drawn"] = shown_sets
    data["counterexamples"] = [ce.to_dict() for ce in counterexamples]
    ax.plot([eq[0]], [eq[1]], "ko", ms=5, zorder=5, label="the equilibrium")
    copies = []
    for i, s in enumerate(model.states):
        if s not in angles:
            continue
        k_lo, k_hi = math.ceil((lo[i] - eq[i]) / (2 * math.pi)), math.floor((hi[i] - eq[i]) / (2 * math.pi))
        for k in range(k_lo, k_hi + 1):
            if k:
                point = eq.copy()
                point[i] += 2 * math.pi * k
                copies.append(point)
    if copies:
        pts = np.array(copies)
        ax.plot(pts[:, 0], pts[:, 1], "o", mfc="white", mec="k", ms=5, zorder=5,
                label=_label(f"the equilibrium shifted by 2π in {', '.join(sorted(angles))}"))
    data["equilibrium_copies"] = [p.tolist() for p in copies]
    ax.set_xlim(lo[0], hi[0])
    ax.set_ylim(lo[1], hi[1])
    ax.set_xlabel(_label(model.states[0]))
    ax.set_ylabel(_label(model.states[1]))
    ax.grid(alpha=0.3)
    ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.14), ncol=2, fontsize=7, framealpha=0.85)
    legend = ax.get_legend()
    data["legend"] = [t.get_text() for t in legend.get_texts()] if legend is not None else []
    drawn = [s for s in sets if s.name in data["sets"] and data["sets"][s.name]["grid_points_inside"]]
    caption = _caption(model, drawn, global_, notes, shown_sets, counterexamples)
    alt = (f"phase portrait of the loop with functions in {model.states[0]} and {model.states[1]}: the true field's "
           f"streamlines, {len(drawn)} certified set(s) and the equilibrium")
    return RecastPortrait(Figure(to_svg(fig), caption, alt, data), "", notes)


def _caption(model: RecastModel, drawn: list[RecastSet], global_: list[str], notes: list[str],
             shown_sets: Sequence[str] = (), counterexamples: Sequence[Counterexample] = ()) -> str:
    s0, s1 = model.states
    parts = [f"Phase portrait of the true loop in its own states ({s0}, {s1}). Grey: streamlines of the field as the "
             "model writes it, with its functions (not the recasting's polynomial field). Black dot: the equilibrium."]
    if any(s.box is not None for s in drawn):
        parts.append("An interval certificate's set is {x : x - x_eq in its box, V(x) ≤ level}: filled where both "
                     "hold, its box dashed; every start in it converges to the equilibrium itself (proved by ball "
                     "arithmetic on the true field).")
    recast_sets = [s for s in drawn if s.box is None]
    if recast_sets:
        parts.append("A recast certificate's set is {x : V(x, a(x)) ≤ level}, V evaluated with each auxiliary at its "
                     "definition; every start in it converges to the equilibrium (proved exactly on the recasting's "
                     "relations).")
        modulo = sorted({a for s in recast_sets for a in s.angles})
        if modulo:
            parts.append(f"Modulo 2π in {', '.join(modulo)}: V sees {', '.join(modulo)} only through sine and cosine, "
                         "so the set repeats every 2π and a start in a copy converges to the equilibrium shifted by "
                         "the same multiple of 2π.")
    if drawn:
        parts.append("Sets: " + "; ".join(f"{s.label}" for s in drawn) + ".")
    else:
        parts.append("No certified set to fill: no class certified a region.")
    if global_:
        parts.append(f"Certified globally, so no set to draw: {'; '.join(global_)}.")
    if shown_sets:
        parts.append(model_sets_sentence(shown_sets))
    if counterexamples:
        parts.append(counterexample_words(model, counterexamples))
    parts.append("The view holds the model's [domain] (without one: ±π in an angle, ±4 elsewhere about the "
                 "equilibrium), every certificate's box, the recast sets' extent, the model's [sets] and the "
                 "counterexamples.")
    return " ".join(parts + notes)


__all__ = ["RecastPortrait", "recast_portrait", "certified_sets", "gauge", "base_view"]
