"""The phase portrait of a 2-state model certificate, and the simulation cross-checks behind it.

What is drawn (declared coordinates, SI): the sets and functions each certified class's report
section contributes (:meth:`reports.sections.base.Section.portrait`), which are today

- every certified set ``{V <= c}`` of ``roa`` and ``candidate``, filled, with ``V`` evaluated
  from the certificate's exact terms (each coefficient converted to the nearest float once, in
  the certificate's scaled coordinates ``x = x_eq + S u``, where the coefficients are of moderate
  size) on a grid, and contoured at ``c`` (contourpy, which matplotlib ships);
- the invariant sets of the safety classes (kind ``"invariant"``: barrier ``{B <= 0}``,
  reach_avoid ``{V <= 0}``), their zero level a solid line and the set lightly hatched;
- the model's ``[sets]`` whenever it has them (whatever classes ran): initial green, unsafe red,
  goal blue, each filled translucent where ``lyapcheck.models.language.sets.margin >= 0`` on a grid;
- the model's ``[domain]`` box, when it has one;
- trajectories with every disturbance 0 from rings of starts around the equilibrium, from
  the boundary of the largest certified set, from just inside each invariant set's boundary and
  from points spread over the initial set, coloured by how they end (converged, escaped,
  neither);
- each ``counterexample`` of a safety class (its ``refutation``: a start in the initial set and a
  disturbance, :mod:`lyapcheck.models.classes.falsify`), simulated again from its stored start with the
  same simulator, drawn wide in dark red from its start (a circle) to where it enters the unsafe
  set (a cross) and named in the legend with the time it enters; a model of other than 2 states,
  which has no portrait, gets its counterexamples against time instead (the unsafe set's margin
  and every state);
- for a model with disturbances and a certified ``sos_bound``, a second panel: each output's
  attracting set ``{V_y <= 1}`` and the band ``|y| <= B`` where the output is a state, with
  trajectories under constant disturbances at their bounds (``d = +b`` and ``d = -b``).

The view is decided beforehand: each set's extent is found along rays from the equilibrium
(bisection on the first crossing of the level, in ``u``), then joined with the domain and the
bounding boxes of the model's ``[sets]`` (found on a grid around the rest).

The simulation is :mod:`lyapcheck.models.engines.trajectories` (the core's cross-checks of certificates
use the same one). The trajectories are also *checked against the certificates* (:class:`CrossCheck`): along
every simulated trajectory that starts in a certified region of attraction ``V`` must not rise
and the start must not escape; a global certificate's ``V`` must not rise (and must decay at
the certified rate) along every trajectory; a storage function must stay below its certified
envelope ``1 + (V(0) - 1) exp(-lam t)``; along every trajectory that starts in an invariant set
``{B <= 0}`` B must stay ``<= 0`` (reach_avoid: until the goal is reached), and no trajectory
from the initial set may enter the unsafe set. A failed check is a soundness alarm on the page.

**A loop with functions** (a :class:`~lyapcheck.models.language.recast.RecastModel`, the pendulum in
(theta, omega)) gets the same portrait in its own states, with the same model's ``[sets]`` and
counterexamples (simulated again on the true loop), and differs in how a set is evaluated and what
is drawn behind it:

- the **true field** (the model's own functions, evaluated by numpy through
  :func:`lyapcheck.models.engines.recast_numeric.field_values`, not the recasting's polynomial field) as
  grey streamlines, in place of simulated trajectories (the ``roa`` class simulated its set on the
  true loop when it was certified, and its figures are on the page);
- each certified set its section names (:meth:`reports.sections.model_file.ModelFileSection.portrait_set`)
  is drawn through its *gauge* (:func:`gauge`), ``<= 1`` exactly on the set: ``V / level`` for a recast
  certificate (V evaluated with every auxiliary at its definition,
  :func:`lyapcheck.models.engines.recast_numeric.v_values`), and for an interval certificate the larger
  of ``V / level`` and the box's own gauge (``max |z_i - centre_i| / half-width_i``), so the drawn set
  is the certificate's ``{x - x_eq in box, V <= level}``; the box is drawn dashed;
- the equilibrium, and where the loop has angles its copies ``2 k pi`` apart that fall in the view.

Its view is the model's ``[domain]`` (else ``+-pi`` in an angle and
:data:`lyapcheck.models.engines.recast_numeric.DEFAULT_HALF_WIDTH` elsewhere, the box the ``roa`` class
compares its sets in) joined with every certificate's box and with each recast set's extent in the
states that are not angles (searched up to :data:`REACH` times that box), the model's sets and the
counterexamples, padded by :data:`RECAST_PAD`. The model text is parsed by the project's parser
only (the caller's :func:`lyapcheck.models.language.modelfile.parse_any_model`); nothing from the
document is evaluated.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from fractions import Fraction
from typing import Any, Final, Sequence

import numpy as np
import numpy.typing as npt

from lyapcheck.models.engines.crosscheck import BISECTIONS, RAY_RADII, check_global, check_region, check_storage, \
    ray_boundary
from lyapcheck.models.language.modelfile import Model
from lyapcheck.models.language.recast import RecastModel
from lyapcheck.models.language.sets import StateSet, margin
from lyapcheck.tolerances import TRAJECTORY_CHECK_REL_TOL
from reports.figures import Figure, WIDTH_IN, resample_closed, to_svg
from lyapcheck.models.engines.trajectories import Trajectory, horizon, jacobian_eigenvalues, simulate
from reports.polynomials import FloatPolynomial
from reports.sections import MODEL_FILE, RECAST_LOOP, section_for
from reports.sections.base import GlobalV, LevelSet
from reports.sections.model_file import ModelFileSection, RecastSet
from reports.views import as_dict, as_fraction, as_number, fmt_float

FloatArray = npt.NDArray[np.float64]

#: rays from the equilibrium along which each set's extent is found (the radii tried, in the
#: scaled coordinates u, and the bisection steps are lyapcheck.models.engines.crosscheck's RAY_RADII and
#: BISECTIONS)
RAYS: Final = 360
#: grid points per axis on which V is evaluated and contoured
GRID: Final = 241
#: padding of a view, as a fraction of its span on each side
PAD: Final = 0.08
#: rings of starts (fractions of the view's half-widths about the equilibrium) and starts per ring
RINGS: Final = (0.3, 0.6, 0.9)
RING_STARTS: Final = 10
#: starts on the boundary of the largest certified region of attraction (just inside it)
BOUNDARY_STARTS: Final = 8
BOUNDARY_INSIDE: Final = 0.999
#: a drawn trajectory ends where it leaves its panel widened by this fraction on every side, and
#: is resampled every DRAW_STEP of the panel (about 0.8 pt of a 6.6-inch figure), with at most
#: PANEL_POINTS points per panel (about 120 kB of SVG before matplotlib's simplification)
DRAW_MARGIN: Final = 0.05
DRAW_STEP: Final = 0.002
PANEL_POINTS: Final = 12_000
#: starts per sign of the constant disturbance in the disturbed panel
DISTURBED_STARTS: Final = 8
#: relative tolerance of the cross-checks (lyapcheck.tolerances.TRAJECTORY_CHECK_REL_TOL: the checks
#: themselves are lyapcheck.models.engines.crosscheck's, shared with the sweeps of model files)
CHECK_TOL: Final = TRAJECTORY_CHECK_REL_TOL
#: the model's [sets] on the portrait: colour and legend words, and the fill's opacity
SET_STYLE: Final = {"initial": ("#1a7f37", "initial set"), "unsafe": ("#cf222e", "unsafe set"),
                    "goal": ("#0969da", "goal set")}
SET_ALPHA: Final = 0.25
#: the grid on which a set of the model is found before the view is known: the other boxes of the
#: view (or 2 scales about the equilibrium), widened this many times about their centre
SET_SEARCH: Final = 3.0
#: an invariant set: its tint, its hatch and the hatch's opacity
INVARIANT_TINT: Final = 0.06
INVARIANT_HATCH: Final = "//"
INVARIANT_HATCH_ALPHA: Final = 0.35
#: starts spread over the initial set (farthest-point picks among the grid's points inside it)
INITIAL_STARTS: Final = 12
#: starts just inside each invariant set's boundary (along the rays from the equilibrium)
INVARIANT_STARTS: Final = 8
#: a class's counterexample (a trajectory from the initial set into the unsafe set, status
#: ``counterexample``): drawn in this red, this wide, simulated again from its stored start for its
#: stored entry time and this share more (so that an entry found a little later is still seen)
COUNTEREXAMPLE_COLOUR: Final = "#a40e26"
COUNTEREXAMPLE_WIDTH: Final = 2.2
COUNTEREXAMPLE_PAST: Final = 0.25
#: a loop with functions' portrait: the points per axis of the grid its field's streamlines are drawn
#: from, matplotlib's streamline density (about 30 x 30 cells carry a line: enough to read the flow,
#: light enough for the page; the field's lines are the figure's largest part), the padding of its
#: view, and a gauge's value outside the grid's finite points (a float the contour code can read)
STREAM_GRID: Final = 61
STREAM_DENSITY: Final = 1.1
RECAST_PAD: Final = 0.06
FAR: Final = 1e6
#: a recast set (no box) is searched up to this many times the model's box about the equilibrium
#: (in the states that are not angles), on a coarse grid of this many points per axis, and the
#: view grown to hold it
REACH: Final = 3.0
REACH_GRID: Final = 121
OUTCOME_STYLE: Final = {"converged": ("#0969da", "converged to the equilibrium"),
                        "escaped": ("#cf222e", "escaped (ran far out of view)"),
                        "other": ("#9a6700", "neither, by the end")}


@dataclass(frozen=True)
class Extent:
    """A set's extent in ``u`` (min, max per axis) and its boundary along the rays (``(RAYS, 2)``)."""

    lo: FloatArray
    hi: FloatArray
    boundary: FloatArray


@dataclass(frozen=True)
class CrossCheck:
    """One simulation cross-check of a certificate: what was checked, whether it held, the figures."""

    what: str
    ok: bool
    detail: str


@dataclass
class PhasePortrait:
    """The figure (or None, with the reason), the cross-checks and notes for the page."""

    figure: Figure | None
    reason: str = ""
    checks: list[CrossCheck] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)


def certificate_scaling(doc: dict[str, Any], model: Model) -> tuple[list[Fraction], Fraction]:
    """The certificate's state scales ``S`` and time scale ``T`` (``t = T tau``), exact; ones when absent."""
    scaling = as_dict(as_dict(doc.get("field")).get("scaling"))
    states = scaling.get("states")
    scales = [as_fraction(s) for s in states] if isinstance(states, list) and len(states) == model.n else []
    time = as_fraction(scaling.get("time"))
    ok = len(scales) == model.n and all(s is not None and s > 0 for s in scales)
    return ([s for s in scales if s is not None] if ok else [Fraction(1)] * model.n,
            time if time is not None and time > 0 else Fraction(1))


def level_sets(doc: dict[str, Any], model: Model) -> tuple[list[LevelSet], list[GlobalV], list[str]]:
    """The certified sets and global Lyapunov functions of a model document; notes for the unreadable."""
    conditions = as_dict(doc.get("conditions"))
    _, time = certificate_scaling(doc, model)
    sets: list[LevelSet] = []
    globals_: list[GlobalV] = []
    notes: list[str] = []
    for name, cond in conditions.items():
        cond = as_dict(cond)
        if cond.get("status") != "certified":
            continue
        try:
            part = section_for(MODEL_FILE, str(name)).portrait(str(name), cond, model.n, time)
        except ValueError as exc:
            notes.append(f"The polynomial of {name} cannot be drawn: {exc}.")
            continue
        sets.extend(part.sets)
        globals_.extend(part.globals)
    return sets, globals_, notes


def set_extent(poly_u: FloatPolynomial, level: float) -> Extent | None:
    """The extent of ``{V <= level}`` along rays from the equilibrium (``u = 0``), or None.

    None when the equilibrium is not in the set or a ray does not leave it within the largest
    radius tried (the set is unbounded, or far larger than anything else drawn).
    """
    theta = np.linspace(0.0, 2 * math.pi, RAYS, endpoint=False)
    directions = np.column_stack([np.cos(theta), np.sin(theta)])
    boundary = ray_boundary(poly_u, level, directions, RAY_RADII, BISECTIONS)
    if boundary is None:
        return None
    return Extent(boundary.min(axis=0), boundary.max(axis=0), boundary)


# -- counterexamples -------------------------------------------------------------------------------
@dataclass(frozen=True)
class Counterexample:
    """A class's counterexample simulated again from its stored start under its stored disturbance
    (:mod:`lyapcheck.models.classes.falsify`'s witness: ``refutation`` of a ``counterexample`` condition).

    ``t``, ``x``: the re-simulated trajectory, up to where it enters the unsafe set (the entry
    found on the dense output, linearly between the last point outside and the first inside)
    or, when it does not enter, to its end; ``entry_time`` is None then.
    """

    name: str
    start: FloatArray
    disturbance: str
    stored_time: float
    t: FloatArray
    x: FloatArray
    entry_time: float | None
    closest_margin: float

    @property
    def label(self) -> str:
        if self.entry_time is not None:
            return f"counterexample ({self.name}): enters the unsafe set at t = {fmt_float(self.entry_time, 4)} s"
        return (f"counterexample ({self.name}), simulated again: does not enter the unsafe set by "
                f"t = {fmt_float(float(self.t[-1]), 4)} s")

    def to_dict(self) -> dict[str, Any]:
        return {"class": self.name, "start": self.start.tolist(), "disturbance": self.disturbance,
                "stored_time_s": self.stored_time, "entered": self.entry_time is not None,
                "entry_time_s": self.entry_time, "entry_point": self.x[-1].tolist() if self.entry_time is not None
                else None, "closest_margin": self.closest_margin}


def _segments(refutation: dict[str, Any], m: int, t_end: float) -> list[tuple[float, float, FloatArray]] | None:
    """The stored disturbance as constant pieces ``(t0, t1, d)`` over ``[0, t_end]`` (``none``,
    ``constant`` or ``bang-bang``: :class:`lyapcheck.models.classes.falsify.Disturbance`); None when it
    cannot be read for ``m`` disturbances."""
    dist = as_dict(refutation.get("disturbance"))
    kind = dist.get("kind")
    if kind == "none" or (kind is None and m == 0):
        return [(0.0, t_end, np.zeros(m))]
    values = dist.get("values")
    if not isinstance(values, list) or not values:
        return None
    try:
        rows = [np.array([float(v) for v in row], dtype=np.float64) for row in values]
    except (TypeError, ValueError):
        return None
    if any(r.shape != (m,) or not np.all(np.isfinite(r)) for r in rows):
        return None
    if kind == "constant":
        return [(0.0, t_end, rows[0])]
    times = dist.get("switch_times") or []
    if kind != "bang-bang" or not isinstance(times, list):
        return None
    edges = [0.0] + [float(t) for t in times if isinstance(t, (int, float)) and 0 < float(t) < t_end] + [t_end]
    if len(edges) - 1 > len(rows) or any(b <= a for a, b in zip(edges, edges[1:])):
        return None
    return [(a, b, rows[j]) for j, (a, b) in enumerate(zip(edges, edges[1:]))]


def counterexample_trajectories(doc: dict[str, Any], model: Model | RecastModel, half: FloatArray
                                ) -> tuple[list[Counterexample], list[str]]:
    """Each ``counterexample`` condition's trajectory, simulated again with the portrait's own
    simulator (:func:`lyapcheck.models.engines.trajectories.simulate`, piece by piece for a switching
    disturbance) from its stored start; notes for those that cannot be read. ``half``: the view's
    half-widths (the escape box and tolerances of the simulation)."""
    from lyapcheck.models.classes.falsify import Disturbance

    out: list[Counterexample] = []
    notes: list[str] = []
    unsafe = model.sets.get("unsafe")
    m = len(model.disturbances)
    for name, cond in as_dict(doc.get("conditions")).items():
        cond = as_dict(cond)
        if cond.get("status") != "counterexample":
            continue
        ref = as_dict(cond.get("refutation"))
        start = ref.get("start")
        stored = as_number(ref.get("time"))
        ok = (ref.get("kind") == "trajectory" and isinstance(start, list) and len(start) == model.n
              and all(as_number(v) is not None and math.isfinite(float(v)) for v in start)
              and stored is not None and math.isfinite(stored) and stored >= 0 and unsafe is not None)
        t_end = (stored or 0.0) * (1 + COUNTEREXAMPLE_PAST)
        pieces = _segments(ref, m, t_end) if ok and t_end > 0 else ([(0.0, 0.0, np.zeros(m))] if ok else None)
        if not ok or pieces is None or unsafe is None or not isinstance(start, list):
            notes.append(f"The counterexample of {name} is not drawn: its stored start, time or disturbance cannot "
                         "be read.")
            continue
        x0 = np.array([float(v) for v in start], dtype=np.float64)
        ts, xs = [np.zeros(1)], [x0[None, :]]
        for a, b, d in pieces:
            if b <= a:
                continue
            (run,) = simulate(model, xs[-1][-1][None, :], t_end=b - a, half_widths=half,
                              disturbances=d[None, :] if m else None)
            ts.append(a + run.t[1:])
            xs.append(run.x[1:])
            if run.outcome == "escaped":
                break
        t, x = np.concatenate(ts), np.vstack(xs)
        finite = np.all(np.isfinite(x), axis=1)
        t, x = t[finite], x[finite]
        values = margin(unsafe, x)
        inside = np.flatnonzero(values >= 0)
        entry: float | None = None
        if inside.size:
            k = int(inside[0])
            if k > 0:  # linearly between the last point outside and the first inside (margin 0)
                s = float(values[k - 1] / (values[k - 1] - values[k]))
                t = np.append(t[:k], t[k - 1] + s * (t[k] - t[k - 1]))
                x = np.vstack([x[:k], x[k - 1] + s * (x[k] - x[k - 1])])
            else:
                t, x = t[:1], x[:1]
            entry = float(t[-1])
        words = Disturbance(str(as_dict(ref.get("disturbance")).get("kind", "none")),
                            tuple(tuple(float(v) for v in p[2]) for p in pieces),
                            tuple(p[0] for p in pieces[1:])).describe(list(model.disturbances))
        out.append(Counterexample(str(name), x0, words, float(stored or 0.0), t, x, entry,
                                  float(np.max(values)) if values.size else -math.inf))
    return out, notes


def draw_counterexamples(ax: Any, shown: Sequence[Counterexample], lo: FloatArray, hi: FloatArray) -> None:
    """Each counterexample: a wide red line from its start (a circle) to where it enters the
    unsafe set (a cross), named in the legend with the time it enters."""
    for ce, line in zip(shown, drawable([ce.x for ce in shown], lo, hi)):
        ax.plot(line[:, 0], line[:, 1], color=COUNTEREXAMPLE_COLOUR, lw=COUNTEREXAMPLE_WIDTH, zorder=6,
                label=_label(ce.label))
        ax.plot([ce.start[0]], [ce.start[1]], "o", ms=6, color=COUNTEREXAMPLE_COLOUR, mec="white", mew=0.8, zorder=7)
        if ce.entry_time is not None:
            ax.plot([ce.x[-1][0]], [ce.x[-1][1]], "X", ms=9, color=COUNTEREXAMPLE_COLOUR, mec="white", mew=0.8,
                    zorder=7)


def counterexample_words(model: Model | RecastModel, shown: Sequence[Counterexample], portrait: bool = True) -> str:
    """The caption's sentences on the counterexamples (``portrait``: drawn in the phase portrait,
    with a circle at the start; else against time)."""
    parts = []
    for ce in shown:
        head = ((("Wide dark red: the" if portrait else "The") + f" counterexample of {ce.name}, simulated again from "
                 f"its stored start {_at(model, ce.start)} with {ce.disturbance}"))
        marks = ["circle: its start"] if portrait else []
        if ce.entry_time is not None:
            marks += [f"cross: where it enters the unsafe set, at t = {fmt_float(ce.entry_time, 4)} s",
                      f"the class found t = {fmt_float(ce.stored_time, 4)} s"]
            parts.append(f"{head} ({'; '.join(marks)}).")
        else:
            parts.append(f"{head}{f' ({marks[0]})' if marks else ''}: simulated again it does not enter the unsafe "
                         f"set by t = {fmt_float(float(ce.t[-1]), 4)} s (largest unsafe margin "
                         f"{ce.closest_margin:.3g}), while the class found an entry at t = "
                         f"{fmt_float(ce.stored_time, 4)} s.")
    return " ".join(parts)


def model_sets_sentence(shown: Sequence[str]) -> str:
    """The caption's sentence on the model's ``[sets]`` drawn (their keys, in :data:`SET_STYLE`'s order)."""
    words = {"initial": "initial (green)", "unsafe": "unsafe (red)", "goal": "goal (blue)"}
    return f"Shaded: the model's [sets] as it states them, {', '.join(words[k] for k in shown)}."


# -- the model's sets ------------------------------------------------------------------------------
def _grid(lo: FloatArray, hi: FloatArray, count: int = GRID) -> tuple[FloatArray, FloatArray, FloatArray]:
    """The axes and the ``(count * count, 2)`` points of a grid over a box."""
    x = np.linspace(lo[0], hi[0], count)
    y = np.linspace(lo[1], hi[1], count)
    X, Y = np.meshgrid(x, y)
    return x, y, np.column_stack([X.ravel(), Y.ravel()])


def set_boxes(model: Model | RecastModel, lo: FloatArray, hi: FloatArray) -> dict[str, tuple[FloatArray, FloatArray] | None]:
    """The bounding box of each of the model's ``[sets]`` within ``lo..hi`` (grid points with
    ``margin >= 0``, widened by a grid step), or None where no grid point is inside."""
    x, y, points = _grid(lo, hi)
    step = np.array([x[1] - x[0], y[1] - y[0]])
    out: dict[str, tuple[FloatArray, FloatArray] | None] = {}
    for key, state_set in model.sets.items():
        inside = points[margin(state_set, points) >= 0]
        out[key] = None if not len(inside) else (np.maximum(inside.min(axis=0) - step, lo),
                                                 np.minimum(inside.max(axis=0) + step, hi))
    return out


def initial_starts(state_set: StateSet, lo: FloatArray, hi: FloatArray, count: int = INITIAL_STARTS) -> FloatArray:
    """Up to ``count`` starts spread over a set: grid points inside it, picked farthest first
    (the first is the grid point deepest inside; the next ones reach its edges)."""
    _, _, points = _grid(lo, hi, 121)
    m = margin(state_set, points)
    inside = points[m >= 0]
    if not len(inside):
        return np.zeros((0, 2))
    span = np.maximum(hi - lo, 1e-300)
    w = (inside - lo) / span
    picked = [int(np.argmax(m[m >= 0]))]
    dist = np.hypot(*(w - w[picked[0]]).T)
    while len(picked) < min(count, len(inside)):
        k = int(np.argmax(dist))
        if dist[k] <= 0:
            break
        picked.append(k)
        dist = np.minimum(dist, np.hypot(*(w - w[k]).T))
    return inside[picked]


def draw_model_sets(ax: Any, model: Model | RecastModel, lo: FloatArray, hi: FloatArray) -> list[str]:
    """Fill each of the model's ``[sets]`` (every piece: ``margin >= 0`` on a grid); the keys drawn."""
    from matplotlib.colors import to_rgba

    x, y, points = _grid(lo, hi)
    drawn = []
    for key in SET_STYLE:
        if key not in model.sets:
            continue
        M = margin(model.sets[key], points).reshape(len(y), len(x))
        if not np.any(M >= 0):
            continue
        colour, words = SET_STYLE[key]
        top = max(float(np.max(M)), 0.0) + 1.0
        ax.contourf(x, y, M, levels=[0.0, top], colors=[to_rgba(colour, SET_ALPHA)], zorder=0.6)
        if np.any(M < 0):
            ax.contour(x, y, M, levels=[0.0], colors=[colour], linewidths=0.9, zorder=0.7)
        pieces = len(model.sets[key])
        ax.fill([], [], facecolor=to_rgba(colour, SET_ALPHA), edgecolor=colour, lw=0.9,
                label=f"{words}{f' ({pieces} pieces)' if pieces > 1 else ''}")
        drawn.append(key)
    return drawn


# -- the figure ------------------------------------------------------------------------------------
@dataclass
class _Drawn:
    """A set with its float polynomial in ``u`` and its extent."""

    spec: LevelSet
    poly_u: FloatPolynomial
    extent: Extent | None


def _view(boxes: Sequence[tuple[FloatArray, FloatArray]], eq: FloatArray) -> tuple[FloatArray, FloatArray]:
    lo = np.minimum(np.min([b[0] for b in boxes], axis=0), eq)
    hi = np.maximum(np.max([b[1] for b in boxes], axis=0), eq)
    span = np.maximum(hi - lo, 1e-300)
    return lo - PAD * span, hi + PAD * span


def _ring(eq: FloatArray, semi: FloatArray, fractions: Sequence[float], count: int) -> FloatArray:
    points = []
    for k, f in enumerate(fractions):
        theta = np.linspace(0.0, 2 * math.pi, count, endpoint=False) + k * math.pi / count
        points.append(eq + f * semi * np.column_stack([np.cos(theta), np.sin(theta)]))
    return np.vstack(points)


def _label(text: str) -> str:
    """Text for a matplotlib label: a '$' must not switch on mathtext."""
    return text.replace("$", r"\$")


def _draw_set(ax: Any, drawn: _Drawn, eq: FloatArray, scales: FloatArray, lo: FloatArray, hi: FloatArray,
              label: bool = True) -> int:
    """Fill ``{V <= level}`` within the view; the number of closed boundary lines drawn."""
    import contourpy
    from matplotlib.colors import to_rgba

    x = np.linspace(lo[0], hi[0], GRID)
    y = np.linspace(lo[1], hi[1], GRID)
    X, Y = np.meshgrid(x, y)
    U = np.stack([(X - eq[0]) / scales[0], (Y - eq[1]) / scales[1]], axis=-1)
    Z = drawn.poly_u(U)
    level = float(drawn.spec.level)
    finite = Z[np.isfinite(Z)]
    if not finite.size or not finite.min() < level < finite.max():
        return 0
    lines = contourpy.contour_generator(x, y, np.where(np.isfinite(Z), Z, np.inf)).lines(level)
    count = 0
    colour = drawn.spec.colour
    for line in lines:
        pts = np.asarray(line, dtype=np.float64)
        if len(pts) < 3:
            continue
        closed = bool(np.allclose(pts[0], pts[-1]))
        text = _label(drawn.spec.label) if label and count == 0 else None
        if closed:
            pts = resample_closed(pts)
            ax.fill(pts[:, 0], pts[:, 1], facecolor=to_rgba(colour, 0.16), edgecolor=colour, lw=1.4, label=text,
                    zorder=1)
        else:  # the set reaches past the view: its boundary in view, unfilled
            ax.plot(pts[:, 0], pts[:, 1], color=colour, lw=1.4, label=text, zorder=1)
        count += 1
    return count


def _draw_invariant(ax: Any, drawn: _Drawn, eq: FloatArray, scales: FloatArray, lo: FloatArray,
                    hi: FloatArray) -> bool:
    """An invariant set ``{B <= level}``: lightly hatched, its zero level a solid line (a filled
    contour, so that a set with holes or several parts is drawn as it is); whether it meets the view."""
    from matplotlib import rc_context
    from matplotlib.colors import to_rgba

    x, y, points = _grid(lo, hi)
    Z = drawn.poly_u((points - eq) / scales).reshape(len(y), len(x))
    level = float(drawn.spec.level)
    Z = np.where(np.isfinite(Z), Z, np.inf)
    if not np.any(Z <= level):
        return False
    colour = drawn.spec.colour
    bottom = min(float(np.min(Z)), level) - 1.0
    # the tint and the hatch apart: matplotlib draws a hatch with its face's opacity
    ax.contourf(x, y, Z, levels=[bottom, level], colors=[to_rgba(colour, INVARIANT_TINT)], zorder=0.8)
    with rc_context({"hatch.color": to_rgba(colour, INVARIANT_HATCH_ALPHA), "hatch.linewidth": 0.6}):
        ax.contourf(x, y, Z, levels=[bottom, level], colors="none", hatches=[INVARIANT_HATCH], zorder=0.8)
        ax.fill([], [], facecolor=to_rgba(colour, INVARIANT_TINT), edgecolor=colour, lw=1.6, hatch=INVARIANT_HATCH,
                label=_label(f"{drawn.spec.label}, certified invariant"))
    if np.any(Z > level):
        ax.contour(x, y, Z, levels=[level], colors=[colour], linewidths=1.6, zorder=2.5)
    return True


def drawable(paths: Sequence[FloatArray], lo: FloatArray, hi: FloatArray,
             budget: int = PANEL_POINTS) -> list[FloatArray]:
    """The parts of trajectories a panel shows, as polylines of evenly spaced points.

    Each ends where it first leaves the panel (widened by :data:`DRAW_MARGIN`): an escaping start
    runs to three view widths, which no reader sees but the SVG would carry. The rest is
    resampled by arc length in the panel's own proportions, one point every :data:`DRAW_STEP`,
    with at most ``budget`` points over the panel (shared in proportion to length): a start that
    winds round a limit cycle for many turns costs what the figure shows, not what was stored.
    """
    span = np.maximum(hi - lo, 1e-300)
    cut: list[FloatArray] = []
    arcs: list[FloatArray] = []
    for x in paths:
        w = (np.asarray(x, dtype=np.float64) - lo) / span
        bad = np.any((w < -DRAW_MARGIN) | (w > 1 + DRAW_MARGIN) | ~np.isfinite(w), axis=1)
        if bad.any():
            w = w[: int(np.argmax(bad)) + 1]
            w = w[np.all(np.isfinite(w), axis=1)]
        cut.append(w)
        arcs.append(np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(w, axis=0).T))]) if len(w) else np.zeros(0))
    wanted = [max(2, math.ceil(a[-1] / DRAW_STEP) + 1) if len(a) > 1 else len(a) for a in arcs]
    shrink = min(1.0, budget / max(sum(wanted), 1))
    out = []
    for w, arc, count in zip(cut, arcs, wanted):
        if len(w) < 2:
            out.append(lo + span * w)
            continue
        at = np.linspace(0.0, arc[-1], max(2, int(count * shrink)))
        out.append(lo + span * np.column_stack([np.interp(at, arc, w[:, 0]), np.interp(at, arc, w[:, 1])]))
    return out


def _draw_trajectories(ax: Any, runs: Sequence[Trajectory], starts: FloatArray, lo: FloatArray, hi: FloatArray,
                       by_outcome: bool, colour: str = "#57606a", label: str = "") -> None:
    labelled: set[str] = set()
    lines = drawable([tr.x for tr in runs], lo, hi)
    for tr, x0, line in zip(runs, starts, lines):
        c, text = (OUTCOME_STYLE[tr.outcome] if by_outcome else (colour, label))
        key = tr.outcome if by_outcome else label
        ax.plot(line[:, 0], line[:, 1], color=c, lw=0.8, alpha=0.85, zorder=3,
                label=_label(f"{text} ({sum(r.outcome == tr.outcome for r in runs)})" if by_outcome else text)
                if key not in labelled else None)
        labelled.add(key)
        ax.plot([x0[0]], [x0[1]], "o", ms=2.6, color=c, zorder=4)


def _domain_box(ax: Any, model: Model) -> bool:
    if not model.domain:
        return False
    from matplotlib.patches import Rectangle

    (a0, b0), (a1, b1) = (tuple(float(v) for v in model.domain[s]) for s in model.states)
    ax.add_patch(Rectangle((a0, a1), b0 - a0, b1 - a1, fill=False, ls="--", lw=1.0, color="k", zorder=2,
                           label="[domain] of the model file"))
    return True


def _state_output(model: Model, output: str) -> int | None:
    """The state index an output is (its text is exactly a state's name), else None."""
    text = model.output_text.get(output, "").strip()
    return model.states.index(text) if text in model.states else None


# -- the cross-checks (lyapcheck.models.engines.crosscheck: one home for them) ----------------------------
def _region_check(drawn: _Drawn, runs: Sequence[Trajectory], eq: FloatArray, scales: FloatArray) -> CrossCheck | None:
    level = float(drawn.spec.level)
    inside = [tr for tr in runs if drawn.poly_u((tr.x[:1] - eq) / scales)[0] <= level]
    if not inside:
        return None
    found = check_region([drawn.poly_u((tr.nodes[1] - eq) / scales) for tr in inside], [tr.outcome for tr in inside])
    detail = (f"{found.starts} simulated starts lie in the set; V never rose along them (largest rise "
              f"{found.worst_rise:.2g} of V(0)); {found.converged} reached the equilibrium within the horizon, "
              f"{found.escaped} escaped")
    what = f"{drawn.spec.name}: trajectories from inside {{V ≤ c}} stay in it and do not escape"
    return CrossCheck(what, found.ok, detail)


def _global_check(g: GlobalV, runs: Sequence[Trajectory], t_end: float, eq: FloatArray,
                  scales: FloatArray) -> CrossCheck:
    poly_u = g.poly.scaled([Fraction(s) for s in scales]).evaluator()
    series = [(tr.nodes[0], poly_u((tr.nodes[1] - eq) / scales)) for tr in runs]
    found = check_global(series, [tr.outcome for tr in runs], g.rate)
    rate = (f"; V(t) ≤ V(0) exp(-{fmt_float(g.rate, 4)} t) held (largest excess {found.worst_envelope:.2g} of V(0))"
            if g.rate > 0 else "")
    detail = (f"{len(runs)} trajectories over {fmt_float(t_end, 4)} s: V never rose (largest rise "
              f"{found.worst_rise:.2g} of V(0)){rate}; {found.escaped} escaped")
    return CrossCheck(f"{g.name}: the global Lyapunov function decreases along every simulated trajectory", found.ok,
                      detail)


def _storage_check(drawn: _Drawn, runs: Sequence[Trajectory], eq: FloatArray, scales: FloatArray) -> CrossCheck:
    spec = drawn.spec
    worst = check_storage([(tr.nodes[0], drawn.poly_u((tr.nodes[1] - eq) / scales)) for tr in runs], spec.rate)
    ok = worst <= CHECK_TOL
    detail = (f"{len(runs)} trajectories (disturbances 0 and constant at ±their bounds): V(t) ≤ 1 + (V(0) - 1) "
              f"exp(-{fmt_float(spec.rate, 4)} t) held (largest excess {worst:.2g})")
    return CrossCheck(f"sos_bound ({spec.output}): the storage function stays below its certified envelope", ok, detail)


def _until(tr: Trajectory, until: StateSet | None) -> tuple[FloatArray, FloatArray]:
    """The integrator's points of a trajectory up to where it first enters ``until`` (all without one)."""
    t, x = tr.nodes
    if until is None or not len(x):
        return t, x
    hit = np.flatnonzero(margin(until, x) >= 0)
    return (t[:hit[0] + 1], x[:hit[0] + 1]) if hit.size else (t, x)


def _at(model: Model | RecastModel, x: FloatArray) -> str:
    return "(" + ", ".join(f"{s} = {fmt_float(float(v), 4)}" for s, v in zip(model.states, x)) + ")"


def _invariant_check(drawn: _Drawn, runs: Sequence[Trajectory], model: Model, eq: FloatArray,
                     scales: FloatArray) -> CrossCheck | None:
    """Along every trajectory that starts in ``{B <= level}``, B stays ``<= level`` (up to the goal
    when the claim ends there); an excess counts beyond :data:`CHECK_TOL` of the largest ``|B|``
    along the trajectory."""
    spec, level = drawn.spec, float(drawn.spec.level)
    until = model.sets.get(spec.until) if spec.until else None
    b = spec.symbol
    starts, worst, bad = 0, -math.inf, []
    for tr in runs:
        if not drawn.poly_u((tr.x[:1] - eq) / scales)[0] <= level:
            continue
        starts += 1
        t, x = _until(tr, until)
        v = drawn.poly_u((x - eq) / scales)
        excess = float(np.max(v) - level) / max(float(np.max(np.abs(v))), abs(level), 1e-300)
        worst = max(worst, excess)
        if excess > CHECK_TOL:
            k = int(np.argmax(v > level))
            bad.append((x[0], t[k]))
    if not starts:
        return None
    c = fmt_float(level)
    what = (f"{spec.name}: trajectories from inside {{{b} ≤ {c}}} stay in it"
            + (" until they reach the goal" if until is not None else ""))
    above = b if level == 0 else f"{b} - {c}"
    largest = f"largest {above} reached: {worst:.2g} of the largest |{b}| along its trajectory"
    if bad:
        (x0, t0) = bad[0]
        detail = (f"{starts} simulated starts lie in the set; {b} rose above {c} along {len(bad)} of them"
                  + (" before the goal" if until is not None else "")
                  + f" ({largest}), the first from {_at(model, x0)}, leaving at t = {fmt_float(float(t0), 4)} s")
    else:
        detail = (f"{starts} simulated starts lie in the set; {b} stayed ≤ {c} along each"
                  + (" until it reached the goal" if until is not None else "") + f" ({largest})")
    return CrossCheck(what, not bad, detail)


def _avoid_check(spec: LevelSet, runs: Sequence[Trajectory], model: Model) -> CrossCheck | None:
    """No trajectory from the initial set enters the unsafe set (``margin >= 0``; reach_avoid: before the goal)."""
    initial, unsafe = model.sets.get("initial"), model.sets.get("unsafe")
    if initial is None or unsafe is None:
        return None
    until = model.sets.get(spec.until) if spec.until else None
    starts, closest, bad = 0, -math.inf, []
    for tr in runs:
        if not margin(initial, tr.x[:1])[0] >= 0:
            continue
        starts += 1
        t, x = _until(tr, until)
        m = margin(unsafe, x)
        if m.size:
            closest = max(closest, float(np.max(m)))
            if np.max(m) >= 0:
                bad.append((x[0], t[int(np.argmax(m >= 0))]))
    if not starts:
        return None
    before = " before the goal" if until is not None else ""
    what = f"{spec.name}: no trajectory from the initial set enters the unsafe set{before}"
    if bad:
        (x0, t0) = bad[0]
        detail = (f"{starts} simulated starts lie in the initial set; {len(bad)} of them entered the unsafe set"
                  f"{before}, the first from {_at(model, x0)} at t = {fmt_float(float(t0), 4)} s")
    else:
        detail = (f"{starts} simulated starts lie in the initial set; none entered the unsafe set{before} "
                  f"(closest approach: largest unsafe margin {closest:.3g})")
    return CrossCheck(what, not bad, detail)


# -- the portrait ----------------------------------------------------------------------------------
def phase_portrait(doc: dict[str, Any], model: Model | RecastModel) -> PhasePortrait:
    """The phase portrait of a 2-state model certificate, of a polynomial or rational loop or of a
    loop with functions (see the module docstring)."""
    if isinstance(model, RecastModel):
        return _recast_portrait(doc, model)
    if model.n != 2:
        reason = (f"the model has {model.n} state{'s' if model.n != 1 else ''}: a phase portrait is drawn for 2 "
                  "states only, so this report shows tables")
        return _counterexample_timeline(doc, model, reason)
    sets, globals_, notes = level_sets(doc, model)
    exact_scales, _ = certificate_scaling(doc, model)
    scales = np.array([float(s) for s in exact_scales])
    eq = np.array([float(v) for v in model.equilibrium])
    drawn = [_Drawn(s, s.poly.scaled(exact_scales).evaluator(), None) for s in sets]
    for d in drawn:
        d.extent = set_extent(d.poly_u, float(d.spec.level))
        if d.extent is None and d.spec.kind == "invariant":
            notes.append(f"The set {d.spec.label} reaches past the view (a ray from the equilibrium does not leave it "
                         "within the largest radius tried, or the equilibrium is outside it): it is drawn where it "
                         "meets the view, and no starts are placed on its boundary.")
        elif d.extent is None:
            notes.append(f"The set {d.spec.label} is not drawn whole: it does not contain the equilibrium or reaches "
                         "beyond the largest radius tried.")
    regions = [d for d in drawn if d.spec.kind == "region"]
    storages = [d for d in drawn if d.spec.kind == "attracting"]
    invariants = [d for d in drawn if d.spec.kind == "invariant"]

    boxes = [(eq + scales * d.extent.lo, eq + scales * d.extent.hi) for d in regions + invariants
             if d.extent is not None]
    if model.domain:
        boxes.append((np.array([float(model.domain[s][0]) for s in model.states]),
                      np.array([float(model.domain[s][1]) for s in model.states])))
    found: dict[str, tuple[FloatArray, FloatArray] | None] = {}
    if model.sets:  # the model's sets join the view: found on a grid around the rest (or 2 S about eq)
        around = boxes or [(eq - 2 * scales, eq + 2 * scales)]
        a_lo = np.minimum(np.min([b[0] for b in around], axis=0), eq)
        a_hi = np.maximum(np.max([b[1] for b in around], axis=0), eq)
        centre, half_span = 0.5 * (a_lo + a_hi), 0.5 * SET_SEARCH * (a_hi - a_lo)
        found = set_boxes(model, centre - half_span, centre + half_span)
        boxes += [b for b in found.values() if b is not None]
        for key, box in found.items():
            if box is None:
                notes.append(f"The {key} set is not drawn: no point of the grid searched is in it.")
    if not boxes:  # nothing bounds the view: the storage functions' sets give the scale, else S
        boxes = [(eq + scales * d.extent.lo, eq + scales * d.extent.hi) for d in storages if d.extent is not None]
    if not boxes:
        boxes.append((eq - 2 * scales, eq + 2 * scales))
    # the counterexamples join the view: simulated at the scale of the view without them
    first_lo, first_hi = _view(boxes, eq)
    shown_ce, ce_notes = counterexample_trajectories(doc, model, np.maximum(np.maximum(eq - first_lo, first_hi - eq),
                                                                            1e-300))
    notes += ce_notes
    boxes += [(ce.x.min(axis=0), ce.x.max(axis=0)) for ce in shown_ce]
    base_lo = np.minimum(np.min([b[0] for b in boxes], axis=0), eq)
    base_hi = np.maximum(np.max([b[1] for b in boxes], axis=0), eq)
    lo, hi = _view(boxes, eq)
    half = np.maximum(np.maximum(eq - lo, hi - eq), 1e-300)
    semi = np.minimum(eq - base_lo, base_hi - eq)
    semi = np.where(semi > 0, semi, np.maximum(eq - base_lo, base_hi - eq))
    starts = [_ring(eq, semi, RINGS, RING_STARTS)]
    bounded = [d for d in regions if d.extent is not None]
    largest = max(bounded, key=lambda d: float(np.prod(d.extent.hi - d.extent.lo)) if d.extent else 0.0, default=None)
    if largest is not None and largest.extent is not None:
        pick = np.linspace(0, RAYS, BOUNDARY_STARTS, endpoint=False).astype(int)
        starts.append(eq + scales * BOUNDARY_INSIDE * largest.extent.boundary[pick])
    for d in invariants:
        if d.extent is not None:
            pick = np.linspace(0, RAYS, INVARIANT_STARTS, endpoint=False).astype(int) + RAYS // (2 * INVARIANT_STARTS)
            starts.append(eq + scales * BOUNDARY_INSIDE * d.extent.boundary[pick % RAYS])
    from_initial = initial_starts(model.sets["initial"], lo, hi) if "initial" in model.sets else np.zeros((0, 2))
    starts.append(from_initial)
    x0 = np.vstack(starts)
    disturbed = bool(storages) and len(model.disturbances) > 0
    lower = _disturbed_view(model, storages, eq, scales, half) if disturbed else None
    t_end = horizon(jacobian_eigenvalues(_evaluator(model), eq, half))
    # the escape box (three half-widths) must hold every start of both panels
    reach = half if lower is None else np.maximum(half, np.maximum(np.abs(lower.lo - eq), np.abs(lower.hi - eq)))
    # one batch: the starts with every disturbance 0, then the lower panel's at +b and at -b
    rows = [x0]
    values = [np.zeros((len(x0), len(model.disturbances)))]
    if lower is not None:
        bound = np.array([float(b) for b in model.disturbances.values()])
        rows += [lower.starts, lower.starts]
        values += [np.tile(bound, (len(lower.starts), 1)), np.tile(-bound, (len(lower.starts), 1))]
    every = simulate(model, np.vstack(rows), t_end=t_end, half_widths=reach,
                     disturbances=np.vstack(values) if model.disturbances else None)
    runs, pushed = every[:len(x0)], every[len(x0):]

    fig, axes = _new_figure(2 if lower is not None else 1)
    ax = axes[0]
    shown_sets = draw_model_sets(ax, model, lo, hi)
    shown_invariants = [d for d in invariants if _draw_invariant(ax, d, eq, scales, lo, hi)]
    for d in regions:
        _draw_set(ax, d, eq, scales, lo, hi)
    has_domain = _domain_box(ax, model)
    _draw_trajectories(ax, runs, x0, lo, hi, by_outcome=True)
    draw_counterexamples(ax, shown_ce, lo, hi)
    ax.plot([eq[0]], [eq[1]], "k+", ms=9, mew=1.5, zorder=5, label="equilibrium")
    _axes(ax, model, lo, hi, "disturbances 0" if model.disturbances else "", below=bool(shown_sets or shown_invariants))

    checks = [c for c in (_region_check(d, runs, eq, scales) for d in regions) if c is not None]
    checks += [_global_check(g, runs, t_end, eq, scales) for g in globals_]
    for d in invariants:
        checks += [c for c in (_invariant_check(d, runs, model, eq, scales), _avoid_check(d.spec, runs, model))
                   if c is not None]
    data: dict[str, Any] = {
        "view": (lo.tolist(), hi.tolist()), "t_end_s": t_end, "starts": int(len(x0)),
        "boundary_starts": int(len(x0) - RING_STARTS * len(RINGS) - len(from_initial)),
        "initial_starts": int(len(from_initial)),
        "model_sets": {k: None if b is None else (b[0].tolist(), b[1].tolist()) for k, b in found.items()},
        "model_sets_drawn": shown_sets,
        "invariant_drawn": [d.spec.name for d in shown_invariants],
        "legend": [t.get_text() for t in ax.get_legend().get_texts()] if ax.get_legend() else [],
        "outcomes": {k: sum(tr.outcome == k for tr in runs) for k in OUTCOME_STYLE},
        "counterexamples": [ce.to_dict() for ce in shown_ce],
        "sets": [{"class": d.spec.name, "level": float(d.spec.level), "kind": d.spec.kind,
                  "extent_declared": None if d.extent is None else
                  ((eq + scales * d.extent.lo).tolist(), (eq + scales * d.extent.hi).tolist())} for d in drawn],
    }
    if lower is not None:
        _draw_disturbed(axes[1], model, storages, lower, pushed, eq, scales)
        data["disturbed"] = {"view": (lower.lo.tolist(), lower.hi.tolist()), "starts": len(pushed),
                             "ends": [tr.x[-1].tolist() for tr in pushed],
                             "bands": [(model.states[i], b) for i, b, _, _ in lower.bands]}
    checks += [_storage_check(d, list(runs) + list(pushed), eq, scales) for d in storages]
    data["checks"] = [(c.what, c.ok) for c in checks]
    caption = _caption(model, regions, runs, t_end, has_domain, lower is not None, storages, notes,
                       shown_sets=shown_sets, invariants=invariants, initial_count=len(from_initial),
                       counterexamples=shown_ce)
    alt = (f"phase portrait of {model.states[0]} and {model.states[1]} with {len(regions)} certified region(s) of "
           f"attraction, {len(invariants)} certified invariant set(s)"
           + (f", the model's {', '.join(shown_sets)} set(s)" if shown_sets else "")
           + f" and {len(runs)} simulated trajectories"
           + "".join(f", and the {ce.label}" for ce in shown_ce))
    return PhasePortrait(Figure(to_svg(fig), caption, alt, data), "", checks, notes)


def _counterexample_timeline(doc: dict[str, Any], model: Model, reason: str) -> PhasePortrait:
    """For a model of other than 2 states, which has no phase portrait: its counterexamples
    against time (the unsafe set's margin, which crosses 0 where the trajectory enters, and each
    state), or no figure (``reason``) when it has none."""
    if not any(as_dict(c).get("status") == "counterexample" for c in as_dict(doc.get("conditions")).values()):
        return PhasePortrait(None, reason)
    exact_scales, _ = certificate_scaling(doc, model)
    half = np.array([float(s) for s in exact_scales])
    if model.domain and all(s in model.domain for s in model.states):
        half = np.maximum(np.array([float(model.domain[s][1] - model.domain[s][0]) / 2 for s in model.states]), half)
    shown, notes = counterexample_trajectories(doc, model, half)
    if not shown:
        return PhasePortrait(None, reason, notes=notes)
    from matplotlib.figure import Figure as MplFigure

    fig = MplFigure(figsize=(WIDTH_IN, 5.2), layout="constrained")
    top, bottom = fig.subplots(2, 1, sharex=True)
    unsafe = model.sets["unsafe"]
    for ce in shown:
        top.plot(ce.t, margin(unsafe, ce.x), color=COUNTEREXAMPLE_COLOUR, lw=COUNTEREXAMPLE_WIDTH,
                 label=_label(ce.label))
        if ce.entry_time is not None:
            top.plot([ce.entry_time], [0.0], "X", ms=9, color=COUNTEREXAMPLE_COLOUR, mec="white", mew=0.8, zorder=7)
        for i, state in enumerate(model.states):
            bottom.plot(ce.t, ce.x[:, i], lw=1.2, label=_label(f"{state} ({ce.name})" if len(shown) > 1 else state))
    top.axhline(0.0, color="k", lw=0.8, ls="--")
    top.set_ylabel("unsafe margin (≥ 0: inside)")
    top.grid(alpha=0.3)
    top.legend(loc="lower right", fontsize=7, framealpha=0.85)
    bottom.set_xlabel("t (s)")
    bottom.set_ylabel("state")
    bottom.grid(alpha=0.3)
    bottom.legend(loc="best", fontsize=7, framealpha=0.85, ncol=min(4, model.n * len(shown)))
    caption = (f"The model has {model.n} state{'s' if model.n != 1 else ''}: a phase portrait is drawn for 2 states "
               "only, so the counterexamples are drawn against time: above, the unsafe set's "
               "margin along each (the max over its pieces of the min of their polynomials, ≥ 0 inside the unsafe "
               "set), below, every state. " + counterexample_words(model, shown, portrait=False)
               + (" " + " ".join(notes) if notes else ""))
    alt = ("the counterexample trajectories against time: "
           + "; ".join(ce.label for ce in shown))
    data = {"counterexamples": [ce.to_dict() for ce in shown],
            "legend": [t.get_text() for t in top.get_legend().get_texts()]}
    return PhasePortrait(Figure(to_svg(fig), caption, alt, data), "", [], notes)


def _evaluator(model: Model) -> Any:
    from lyapcheck.models.engines.numeric import FieldEvaluator

    return FieldEvaluator.of(model)


def _new_figure(panels: int, height: float | None = None) -> tuple[Any, list[Any]]:
    from matplotlib.figure import Figure as MplFigure

    # one panel 4.4 in tall, two of 3.7 in: a figure and its caption fit an A4 page of the PDF
    height = height if height is not None else 4.4 if panels == 1 else 3.7 * panels
    fig = MplFigure(figsize=(WIDTH_IN, height), layout="constrained")
    axes = fig.subplots(panels, 1, squeeze=False)
    return fig, [a for a in axes[:, 0]]


def _axes(ax: Any, model: Model | RecastModel, lo: FloatArray, hi: FloatArray, title: str, below: bool = False,
          columns: int = 3, drop: float = 0.13) -> None:
    """Limits, labels, grid, title and legend (``below``: under the panel in ``columns`` columns,
    ``drop`` of the panel's height below it, for a legend of the model's sets, which would
    otherwise cover them)."""
    ax.set_xlim(lo[0], hi[0])
    ax.set_ylim(lo[1], hi[1])
    ax.set_xlabel(_label(model.states[0]))
    ax.set_ylabel(_label(model.states[1]))
    ax.grid(alpha=0.3)
    if title:
        ax.set_title(_label(title), fontsize=9)
    if below:
        ax.legend(loc="upper center", bbox_to_anchor=(0.5, -drop), ncol=columns, fontsize=7, framealpha=0.85)
    else:
        ax.legend(loc="upper right", fontsize=7, framealpha=0.85)


@dataclass(frozen=True)
class _Lower:
    """The lower panel's view, its starts and the bands ``|y| <= B`` of outputs that are states."""

    lo: FloatArray
    hi: FloatArray
    starts: FloatArray
    bands: list[tuple[int, float, str, str]]


def _disturbed_view(model: Model, storages: Sequence[_Drawn], eq: FloatArray, scales: FloatArray,
                    half: FloatArray) -> _Lower:
    """Around sos_bound's attracting sets and bands, with a ring of starts inside the view's edge."""
    boxes = [(eq + scales * d.extent.lo, eq + scales * d.extent.hi) for d in storages if d.extent is not None]
    bands = []
    for d in storages:
        i = _state_output(model, d.spec.output)
        if i is not None and d.spec.bound is not None:
            bands.append((i, d.spec.bound, d.spec.colour, d.spec.output))
            box_lo, box_hi = eq.copy(), eq.copy()
            box_lo[i], box_hi[i] = eq[i] - d.spec.bound, eq[i] + d.spec.bound  # the bound is on |y - y_eq|
            boxes.append((box_lo, box_hi))
    if not boxes:
        boxes.append((eq - half, eq + half))
    lo, hi = _view(boxes, eq)
    lo, hi = lo - 0.15 * (hi - lo), hi + 0.15 * (hi - lo)
    centre, semi = 0.5 * (lo + hi), 0.45 * (hi - lo)
    return _Lower(lo, hi, _ring(centre, semi, (1.0,), DISTURBED_STARTS), bands)


def _draw_disturbed(ax: Any, model: Model, storages: Sequence[_Drawn], lower: _Lower, pushed: Sequence[Trajectory],
                    eq: FloatArray, scales: FloatArray) -> None:
    """The lower panel: sos_bound's attracting sets and bands, trajectories under constant +b and -b."""
    for d in storages:
        _draw_set(ax, d, eq, scales, lower.lo, lower.hi)
    for i, b, colour, output in lower.bands:
        line = ax.axvline if i == 0 else ax.axhline
        shown = f"{output} - {fmt_float(eq[i], 6)}" if eq[i] else output
        line(eq[i] + b, color=colour, ls="--", lw=1.1,
             label=_label(f"|{shown}| = {fmt_float(b, 4)} (certified limsup)"))
        line(eq[i] - b, color=colour, ls="--", lw=1.1)
    k = len(lower.starts)
    _draw_trajectories(ax, pushed[:k], lower.starts, lower.lo, lower.hi, by_outcome=False, colour="#0969da",
                       label="constant d = +b")
    _draw_trajectories(ax, pushed[k:], lower.starts, lower.lo, lower.hi, by_outcome=False, colour="#cf222e",
                       label="constant d = -b")
    _axes(ax, model, lower.lo, lower.hi, "disturbances constant at their bounds")


def _caption(model: Model, regions: Sequence[_Drawn], runs: Sequence[Trajectory], t_end: float,
             has_domain: bool, disturbed: bool, storages: Sequence[_Drawn], notes: Sequence[str], *,
             shown_sets: Sequence[str] = (), invariants: Sequence[_Drawn] = (), initial_count: int = 0,
             counterexamples: Sequence[Counterexample] = ()) -> str:
    counts = {k: sum(tr.outcome == k for tr in runs) for k in OUTCOME_STYLE}
    parts = [f"Phase portrait of the model in its declared coordinates ({model.states[0]}, {model.states[1]})."]
    if shown_sets:
        parts.append(model_sets_sentence(shown_sets))
    if invariants:
        shown = "; ".join(f"{d.spec.name}: {{{d.spec.symbol} ≤ {fmt_float(float(d.spec.level))}}}" for d in invariants)
        until = any(d.spec.until for d in invariants)
        parts.append(f"Hatched, bounded by a solid line (its zero level): the certified invariant sets ({shown}), "
                     "which contain the initial set, exclude the unsafe set and which no trajectory leaves"
                     + (" (reach_avoid: before it reaches the goal)" if until else "")
                     + " (checked exactly), evaluated from the certificate's exact polynomial.")
    if regions:
        shown = "; ".join(f"{d.spec.name}: {{V ≤ {fmt_float(float(d.spec.level))}}}" for d in regions)
        parts.append(f"Filled: the certified regions of attraction ({shown}); every start in them converges to the "
                     "equilibrium (checked exactly), V evaluated from the certificate's exact polynomial.")
    elif not invariants:
        parts.append("No region of attraction is certified, so no certified set is filled.")
    boundary = len(runs) - RING_STARTS * len(RINGS) - initial_count
    sources = ["rings of starts around the equilibrium"]
    if boundary > 0:
        sources.append(f"{boundary} starts just inside the boundaries of the certified sets")
    if initial_count:
        sources.append(f"{initial_count} starts spread over the initial set")
    joined = sources[0] if len(sources) == 1 else ", ".join(sources[:-1]) + " and " + sources[-1]
    parts.append(f"Lines: {len(runs)} trajectories with every disturbance 0, over {fmt_float(t_end, 4)} s, from "
                 f"{joined}: {counts['converged']} converged (blue), {counts['escaped']} escaped (red), "
                 f"{counts['other']} neither by the end (amber).")
    if counterexamples:
        parts.append(counterexample_words(model, counterexamples))
    if has_domain:
        parts.append("Dashed box: the model's [domain].")
    if disturbed:
        parts.append("Lower panel: the same loop with every disturbance held at +b (blue) or -b (red), and for each "
                     "output the attracting set {V ≤ 1} of sos_bound's storage function, which every trajectory "
                     "enters for every disturbance within its bounds; dashed lines: the certified bound on an output "
                     "that is a state.")
    elif storages:
        parts.append("sos_bound's sets are not drawn: the model has no disturbance to simulate them with.")
    return " ".join(parts + list(notes))


# -- a loop with functions -------------------------------------------------------------------------
def recast_sets(doc: dict[str, Any]) -> tuple[list[RecastSet], list[str], list[str]]:
    """The certified sets of a loop with functions' classes; the classes with a global claim; notes
    on the sets that cannot be read."""
    sets, global_, notes = [], [], []
    for name, cond in as_dict(doc.get("conditions")).items():
        cond = as_dict(cond)
        if cond.get("status") != "certified":
            continue
        section = section_for(RECAST_LOOP, str(name))
        if not isinstance(section, ModelFileSection):
            continue
        try:
            found = section.portrait_set(str(name), cond)
        except ValueError as exc:
            notes.append(f"{name}'s set is not drawn: {exc}.")
            continue
        cert = as_dict(cond.get("certificate"))
        if found is not None:
            sets.append(found)
        elif cert.get("kind") in ("recast", "lyapunov_relations"):  # (quadratic, sos_gas: lyapunov_relations)
            angles = [str(a) for a in cert.get("angles") or []] if isinstance(cert.get("angles"), list) else []
            global_.append(str(name) + (f" (modulo 2π in {', '.join(angles)})" if angles else ""))
    return sets, global_, notes


def recast_base_view(model: RecastModel, angles: set[str]) -> tuple[FloatArray, FloatArray]:
    """The model's [domain], else the box the roa class compares its sets in (absolute states)."""
    from lyapcheck.models.engines.recast_numeric import DEFAULT_HALF_WIDTH

    eq = np.array([float(v) for v in model.equilibrium])
    if model.domain is not None:
        return (np.array([float(model.domain[s][0]) for s in model.states]),
                np.array([float(model.domain[s][1]) for s in model.states]))
    half = np.array([math.pi if s in angles else DEFAULT_HALF_WIDTH for s in model.states])
    return eq - half, eq + half


def gauge(model: RecastModel, spec: RecastSet, X: FloatArray) -> FloatArray:
    """``<= 1`` exactly on a loop with functions' certified set, at the states ``X`` (rows);
    :data:`FAR` where V is not finite. Where a polynomial loop's set is evaluated from its
    certificate's V in scaled coordinates, this is the one place a recast set is evaluated."""
    from lyapcheck.models.engines.recast_numeric import v_values
    from lyapcheck.models.engines.recast_sos import poly_from_json

    system = model.system
    V = poly_from_json(system.ring, spec.V, "V")
    eq = np.array([float(v) for v in model.equilibrium])
    Z = X - eq
    with np.errstate(all="ignore"):
        g = v_values(system, V, Z) / float(spec.level)
    if spec.box is not None:
        lo, hi = _box_corners(model, spec.box, np.zeros_like(eq))
        centre, half = 0.5 * (lo + hi), 0.5 * (hi - lo)
        g = np.maximum(g, np.max(np.abs(Z - centre) / half, axis=1))
    return np.where(np.isfinite(g), g, FAR)


def _box_corners(model: RecastModel, box: dict[str, tuple[Fraction, Fraction]],
                 eq: FloatArray) -> tuple[FloatArray, FloatArray]:
    """A certificate's box of deviations, about ``eq``, as its two corners."""
    return (eq + np.array([float(box[s][0]) for s in model.states]),
            eq + np.array([float(box[s][1]) for s in model.states]))


def recast_reach(model: RecastModel, spec: RecastSet, lo: FloatArray, hi: FloatArray, angles: set[str],
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
    _, _, points = _grid(far_lo, far_hi, REACH_GRID)
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


def _recast_portrait(doc: dict[str, Any], model: RecastModel) -> PhasePortrait:
    """The phase portrait of a 2-state loop with functions (see the module docstring)."""
    from matplotlib.colors import to_rgba
    from matplotlib.patches import Rectangle

    from lyapcheck.models.engines.recast_numeric import field_values

    n = len(model.states)
    if n != 2:
        return PhasePortrait(None, f"the loop has {n} state{'s' if n != 1 else ''}: a phase portrait is drawn for 2 "
                                   "states only, so this report shows tables")
    sets, global_, notes = recast_sets(doc)
    angles = {str(a) for a in as_dict(as_dict(doc.get("recast")).get("angles"))}
    eq = np.array([float(v) for v in model.equilibrium])
    lo, hi = recast_base_view(model, angles)
    for spec in sets:
        if spec.box is not None:
            box_lo, box_hi = _box_corners(model, spec.box, eq)
            lo, hi = np.minimum(lo, box_lo), np.maximum(hi, box_hi)
    for spec in sets:
        if spec.box is None:
            lo, hi = recast_reach(model, spec, lo, hi, angles, notes)
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
    lo, hi = lo - RECAST_PAD * span, hi + RECAST_PAD * span

    fig, (ax,) = _new_figure(1, height=4.6)
    sx, sy, stream_points = _grid(lo, hi, STREAM_GRID)
    with np.errstate(all="ignore"):
        F = field_values(model.system, stream_points)
    U = np.ma.masked_invalid(F[:, 0].reshape(len(sy), len(sx)))
    W = np.ma.masked_invalid(F[:, 1].reshape(len(sy), len(sx)))
    stream = ax.streamplot(sx, sy, U, W, density=STREAM_DENSITY, color="#8c959f", linewidth=0.6, arrowsize=0.7,
                           zorder=1)
    stream.lines.set_gid("true-field")
    ax.plot([], [], color="#8c959f", lw=0.8, label="the true field (streamlines)")

    x, y, points = _grid(lo, hi)
    data: dict[str, Any] = {"view": (lo.tolist(), hi.tolist()), "sets": {}, "global": list(global_)}
    cell = float((x[1] - x[0]) * (y[1] - y[0]))
    for spec in sets:
        try:
            G = gauge(model, spec, points).reshape(len(y), len(x))
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
            blo, bhi = _box_corners(model, spec.box, eq)
            ax.add_patch(Rectangle((blo[0], blo[1]), bhi[0] - blo[0], bhi[1] - blo[1], fill=False, ls="--", lw=1.0,
                                   edgecolor=spec.colour, zorder=3, label=_label(f"{spec.name}'s box")))

    shown_sets = draw_model_sets(ax, model, lo, hi)
    draw_counterexamples(ax, counterexamples, lo, hi)
    data["model_sets_drawn"] = shown_sets
    data["counterexamples"] = [ce.to_dict() for ce in counterexamples]
    ax.plot([eq[0]], [eq[1]], "ko", ms=5, zorder=5, label="the equilibrium")
    copies = _copies(model, eq, angles, lo, hi)
    if copies:
        pts = np.array(copies)
        ax.plot(pts[:, 0], pts[:, 1], "o", mfc="white", mec="k", ms=5, zorder=5,
                label=_label(f"the equilibrium shifted by 2π in {', '.join(sorted(angles))}"))
    data["equilibrium_copies"] = [p.tolist() for p in copies]
    _axes(ax, model, lo, hi, "", below=True, columns=2, drop=0.14)
    legend = ax.get_legend()
    data["legend"] = [t.get_text() for t in legend.get_texts()] if legend is not None else []
    drawn = [s for s in sets if s.name in data["sets"] and data["sets"][s.name]["grid_points_inside"]]
    caption = _recast_caption(model, drawn, global_, notes, shown_sets, counterexamples)
    alt = (f"phase portrait of the loop with functions in {model.states[0]} and {model.states[1]}: the true field's "
           f"streamlines, {len(drawn)} certified set(s) and the equilibrium")
    return PhasePortrait(Figure(to_svg(fig), caption, alt, data), "", [], notes)


def _copies(model: RecastModel, eq: FloatArray, angles: set[str], lo: FloatArray, hi: FloatArray) -> list[FloatArray]:
    """The equilibrium shifted by ``2 k pi`` (k != 0) in each angle, where it falls in the view."""
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
    return copies


def _recast_caption(model: RecastModel, drawn: list[RecastSet], global_: list[str], notes: list[str],
                    shown_sets: Sequence[str] = (), counterexamples: Sequence[Counterexample] = ()) -> str:
    s0, s1 = model.states
    parts = [f"Phase portrait of the true loop in its own states ({s0}, {s1}). Grey: streamlines of the field as the "
             "model writes it, with its functions (not the recasting's polynomial field). Black dot: the equilibrium."]
    if any(s.box is not None for s in drawn):
        parts.append("An interval certificate's set is {x : x - x_eq in its box, V(x) ≤ level}: filled where both "
                     "hold, its box dashed; every start in it converges to the equilibrium itself (proved by ball "
                     "arithmetic on the true field).")
    recast = [s for s in drawn if s.box is None]
    if recast:
        parts.append("A recast certificate's set is {x : V(x, a(x)) ≤ level}, V evaluated with each auxiliary at its "
                     "definition; every start in it converges to the equilibrium (proved exactly on the recasting's "
                     "relations).")
        modulo = sorted({a for s in recast for a in s.angles})
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
