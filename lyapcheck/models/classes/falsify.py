"""Falsification beside a safety certificate: simulate from the initial set, watch the unsafe set.

:func:`falsify` draws starts from a model's initial set, simulates each under every disturbance
scenario (none, or the vertices of the disturbance box held constant and bang-bang switching
among them at random times), and reports how close the trajectories come to the unsafe set: the
largest value, over trajectories and times, of the unsafe set's margin (``>= 0`` inside, so a
negative figure means no trajectory entered). A trajectory that does enter is kept as a
witness: its start, its disturbance and the time it enters. Beside a certificate that proves the
unsafe set unreachable a witness is a soundness violation; without a certificate it is a
counterexample. Simulations are evidence, never proofs, either way.

Sets
----
A set is a tuple of pieces (their union), a piece a tuple of polynomials of
:attr:`~lyapcheck.models.language.modelfile.Model.state_ring`, ``p >= 0`` for every ``p`` meaning inside
(the ``[sets]`` table's form). ``margin_fn(state_set, points)`` gives, per point (rows of
``(k, n)``, the states in declared order), a number ``>= 0`` inside and ``< 0`` outside: the
max over pieces of the min over the piece's polynomials (``lyapcheck.models.language.sets.margin``).

Starts
------
Per piece of the initial set (the samples split evenly between pieces, so a small piece of a
union is not starved):

1. a point inside: candidates (the equilibrium, the origin, seeded Gaussian clouds around both
   at the scales :data:`CLOUD_SCALES`, and uniform points of the ``[domain]`` box when declared);
   from the best few, a seeded evolution strategy then Nelder-Mead raise the margin (clipped to
   the domain box), which also moves the point away from the boundary; a piece with no inside
   point found is refused (``ValueError``);
2. a bounding box grown around it: every face moves out (doubling its distance from the point)
   while seeded points drawn on it are inside the piece, then bisected back to the last distance
   with no inside point on it (:data:`BOX_BISECTIONS`); the box is clipped to the ``[domain]``
   when declared. It is a box found by sampling, so a thin part of a piece beyond it is missed;
3. interior starts by rejection sampling in that box, and a fraction :data:`BOUNDARY_FRACTION`
   of boundary starts: from the inner point towards seeded points of the box outside the piece,
   bisected to the last inside point (the starts with the least margin, where a barrier is
   tightest).

This finds a small ellipse such as ``(x - 1.5)**2 + y**2 <= 0.25`` without any domain (a cloud
at scale 1 or 3 lands in it) and the tiny box ``[0.9, 1.1]^8`` inside ``[-2.2, 2.2]^8`` (no
uniform point of the domain does; the evolution strategy reaches it from the best one).

Disturbances
------------
Without disturbances every start is simulated once with ``d = 0``. With ``m`` disturbances
``|d_k| <= b_k``, every start meets each vertex of the box held constant (all ``2^m`` of them up
to :data:`MAX_VERTICES`, else that many drawn), and :data:`BANG_BANG_PER_START` bang-bang
disturbances: a random vertex on each segment, the switching times a seeded Poisson process
whose mean dwell is drawn log-uniformly between ``horizon / DWELL_MAX_DIVISOR`` and ``horizon /
DWELL_MIN_DIVISOR``; switching times are breakpoints the integrator lands on exactly (like the
square waves of :mod:`lyapcheck.models.surfaces.simulate`). Every one is admissible: ``|d_k| <= b_k`` at
every instant.

Simulation
----------
One batched Dormand-Prince call (:mod:`lyapcheck.integrator`) for every (start,
disturbance) row, steps at most ``horizon /`` :data:`MIN_STEPS`; the unsafe margin is read at
the integrator's points and at :data:`SAMPLE_THETAS` of every step (cubic Hermite), and a first
entry is located by bisection on the step's interpolant. A row farther than
:data:`ESCAPE_FACTOR` box half-widths from the box's centre stops there (it runs away). The
default horizon: :data:`~lyapcheck.models.engines.trajectories.SLOW_TIME_CONSTANTS` of the slowest mode
of an exponentially stable equilibrium, capped at :data:`FAST_TIME_CONSTANTS_CAP` of the
fastest (a stiff loop's explicit steps are bounded by its fastest mode), otherwise
:data:`~lyapcheck.models.engines.trajectories.FAST_TIME_CONSTANTS_CRITICAL` of the fastest (the
horizon rule of :mod:`lyapcheck.models.engines.trajectories`, with a cap ten times as long: a safety
question needs the slow drift too).

Stopping at a goal
------------------
With ``stop`` (a set, reach-avoid's goal), a trajectory is watched only until it reaches that set: the
field is held at 0 inside it (:class:`_Stopped`), so the trajectory stays where it reached the set and
nothing after that counts (an entry into the unsafe set after the goal is no violation of reach-while-avoid).
Before it, the trajectory is the model's exactly. The default horizon is the unstopped field's (a goal
around the equilibrium would make the stopped field's Jacobian there 0). :func:`replay` re-simulates one
witness the same way, from its start and disturbance alone (``verify`` re-checks a counterexample with it).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from typing import Any, Callable, Final, Mapping, Sequence

import numpy as np
import numpy.typing as npt

from lyapcheck.models.language.modelfile import Model
from lyapcheck.models.engines.numeric import FieldEvaluator, ModelSystem
from lyapcheck.models.engines.trajectories import horizon as horizon_of, jacobian_eigenvalues
from lyapcheck.integrator import STATUS_OK, hermite, integrate
from lyapcheck.sos.polynomials import Poly

FloatArray = npt.NDArray[np.float64]
IntArray = npt.NDArray[np.intp]

#: a set: a union of pieces, each the intersection of ``p >= 0`` over its polynomials
StateSet = tuple[tuple[Poly, ...], ...]
#: ``margin_fn(state_set, points)``: ``(k,)`` values, ``>= 0`` inside, for ``(k, n)`` points
MarginFunction = Callable[[StateSet, FloatArray], FloatArray]

#: starts per call by default, and the fraction of them drawn on the boundary of the initial set
SAMPLES: Final = 200
BOUNDARY_FRACTION: Final = 0.25
#: candidates for a point inside a piece: Gaussian clouds of these standard deviations around the
#: equilibrium and the origin (CLOUD_POINTS each), and DOMAIN_POINTS uniform points of the domain
CLOUD_SCALES: Final = tuple(float(s) for s in np.geomspace(1e-3, 1e3, 13))
CLOUD_POINTS: Final = 64
DOMAIN_POINTS: Final = 2048
#: Nelder-Mead polish of the best candidates (this many starts, iterations per state)
POLISH_STARTS: Final = 3
POLISH_ITERATIONS_PER_STATE: Final = 200
#: the evolution strategy before it: first step (fraction of the scale), offspring, rounds at most
EVOLVE_STEP: Final = 0.25
EVOLVE_OFFSPRING: Final = 64
EVOLVE_ROUNDS: Final = 200
#: bounding box: first half-width (fraction of the scale), points drawn per face and state,
#: doubling rounds at most, bisections of each face, the farthest face (scales from the point)
BOX_START: Final = 1e-3
BOX_FACE_POINTS: Final = 24
BOX_ROUNDS: Final = 60
BOX_BISECTIONS: Final = 10
BOX_MAX: Final = 1e4
#: rejection sampling: candidates per batch, and the most drawn per piece
REJECTION_BATCH: Final = 8192
REJECTION_MAX: Final = 2_000_000
#: bisections of a boundary start and of a first entry into the unsafe set
BOUNDARY_BISECTIONS: Final = 40
ENTRY_BISECTIONS: Final = 20
#: disturbances: vertices held constant (all 2**m up to this), bang-bang signals per start, their
#: switches at most, and the range of their mean dwell (horizon / divisor)
MAX_VERTICES: Final = 8
BANG_BANG_PER_START: Final = 2
MAX_SWITCHES: Final = 64
DWELL_MIN_DIVISOR: Final = 4.0
DWELL_MAX_DIVISOR: Final = 64.0
#: default horizon: the exponentially stable case is capped at this many fastest time constants
FAST_TIME_CONSTANTS_CAP: Final = 4000.0
#: integrator: relative tolerance, absolute tolerance per unit of scale, steps per horizon at least
RTOL: Final = 1e-7
ATOL_PER_SCALE: Final = 1e-9
MIN_STEPS: Final = 200
#: points of every accepted step where the unsafe margin is read (fractions of the step)
SAMPLE_THETAS: Final = (0.25, 0.5, 0.75, 1.0)
#: a row farther than this many box half-widths from the box's centre stops (runs away)
ESCAPE_FACTOR: Final = 1e3
#: replay of one witness: simulated this fraction beyond its stated time, and its entry time and point
#: agreeing with the stated ones within this fraction of (1 + the largest magnitude) (the same integrator
#: and tolerances, but one row with its own steps: the two agree to about RTOL, far inside this)
REPLAY_TIME_MARGIN: Final = 0.01
REPLAY_TOLERANCE: Final = 1e-4


# -- the result ---------------------------------------------------------------------------------

@dataclass(frozen=True)
class Disturbance:
    """The disturbance of one row: ``none``, ``constant`` (``values``: one per disturbance) or
    ``bang-bang`` (``values[j]`` held on ``[switch_times[j-1], switch_times[j])``, from t = 0)."""

    kind: str
    values: tuple[tuple[float, ...], ...] = ()
    switch_times: tuple[float, ...] = ()

    def describe(self, names: Sequence[str]) -> str:
        if self.kind == "none":
            return "no disturbance (d = 0)"
        if self.kind == "constant":
            return "constant " + ", ".join(f"{n} = {v:+.6g}" for n, v in zip(names, self.values[0]))
        first = ", ".join(f"{n} = {v:+.6g}" for n, v in zip(names, self.values[0]))
        if not self.switch_times:
            return f"bang-bang, no switch before the end: {first}"
        return (f"bang-bang between the vertices of the disturbance box, {len(self.switch_times)} switches "
                f"(starting with {first}, first switch at t = {self.switch_times[0]:.6g} s)")

    def to_dict(self) -> dict[str, Any]:
        return {"kind": self.kind, "values": [list(v) for v in self.values],
                "switch_times": list(self.switch_times)}


@dataclass(frozen=True)
class Witness:
    """A point of one simulated trajectory: where it started, under which disturbance, and the
    time and state at which the unsafe margin is read (``margin >= 0``: inside the unsafe set)."""

    start: tuple[float, ...]
    disturbance: Disturbance
    time: float
    point: tuple[float, ...]
    margin: float
    #: the trajectory stayed in the [domain] box until ``time`` (None: the model declares none)
    inside_domain: bool | None

    def describe(self, states: Sequence[str], disturbances: Sequence[str], units: Mapping[str, str] | None = None
                 ) -> str:
        """The witness in words; with the model's ``[units]``, each state's value with its unit."""
        from lyapcheck.models.classes.claims import with_unit

        def unit(s: str) -> str | None:
            u = (units or {}).get(s, "").strip()
            return None if u in ("", "1") else u

        start = ", ".join(f"{s} = {with_unit(v, unit(s), 6)}" for s, v in zip(states, self.start))
        point = ", ".join(f"{s} = {with_unit(v, unit(s), 6)}" for s, v in zip(states, self.point))
        return (f"from {start} with {self.disturbance.describe(disturbances)}: at t = {self.time:.6g} s "
                f"at {point} (unsafe margin {self.margin:.6g})")

    def to_dict(self) -> dict[str, Any]:
        return {"start": list(self.start), "disturbance": self.disturbance.to_dict(), "time": self.time,
                "point": list(self.point), "margin": self.margin, "inside_domain": self.inside_domain}


@dataclass(frozen=True)
class Falsification:
    """What the simulations from the initial set found (:func:`falsify`).

    ``closest_approach`` is the largest unsafe margin reached by any trajectory at any time:
    ``< 0`` none entered (how far, in the margin's units, the nearest came), ``>= 0`` one did.
    ``closest`` is where it was reached; ``entry``, when some trajectory entered, is the one that
    entered first (its start, disturbance and time of entry).
    """

    samples: int
    trajectories: int
    horizon: float
    closest_approach: float
    closest: Witness
    entry: Witness | None
    #: trajectories that entered the unsafe set, and of those, the ones inside the domain until then
    entries: int
    entries_in_domain: int
    #: trajectories that ran away (stopped at the escape box) and that the integrator could not finish
    escaped: int
    failed: int
    disturbance_scenarios: int
    seed: int
    elapsed_s: float
    states: tuple[str, ...] = ()
    disturbances: tuple[str, ...] = ()
    #: per piece of the initial set: the box the starts were drawn from (lows, highs)
    boxes: tuple[tuple[tuple[float, ...], tuple[float, ...]], ...] = field(default=())

    @property
    def entered(self) -> bool:
        """Some simulated trajectory from the initial set entered the unsafe set."""
        return self.entry is not None

    def soundness_violation(self, *, within_domain: bool = False) -> bool:
        """True when a trajectory entered (with ``within_domain``: one that stayed inside the
        ``[domain]`` box until it entered, for a claim made over the domain only): beside a
        certificate proving the unsafe set unreachable, that is a soundness violation."""
        return (self.entries_in_domain if within_domain else self.entries) > 0

    def describe(self) -> str:
        head = (f"{self.trajectories} trajectories ({self.samples} starts x {self.disturbance_scenarios} "
                f"disturbances) over {self.horizon:.6g} s")
        if self.entry is not None:
            return (f"{head}: {self.entries} entered the unsafe set; first "
                    f"{self.entry.describe(self.states, self.disturbances)}")
        return (f"{head}: none entered the unsafe set; closest approach (largest unsafe margin) "
                f"{self.closest_approach:.6g}, {self.closest.describe(self.states, self.disturbances)}")

    def to_dict(self) -> dict[str, Any]:
        return {"samples": self.samples, "trajectories": self.trajectories, "horizon": self.horizon,
                "closest_approach": self.closest_approach, "closest": self.closest.to_dict(),
                "entered": self.entered, "entry": None if self.entry is None else self.entry.to_dict(),
                "entries": self.entries, "entries_in_domain": self.entries_in_domain,
                "escaped": self.escaped, "failed": self.failed,
                "disturbance_scenarios": self.disturbance_scenarios, "seed": self.seed,
                "elapsed_s": self.elapsed_s, "states": list(self.states),
                "disturbances": list(self.disturbances),
                "boxes": [[list(lo), list(hi)] for lo, hi in self.boxes]}


# -- sampling the initial set -------------------------------------------------------------------

def _domain_box(model: Model) -> tuple[FloatArray, FloatArray] | None:
    if not model.domain:
        return None
    lo = np.array([float(model.domain[s][0]) if s in model.domain else -np.inf for s in model.states])
    hi = np.array([float(model.domain[s][1]) if s in model.domain else np.inf for s in model.states])
    return lo, hi


class _Piece:
    """One piece's margin, with the domain box (when declared) as extra constraints."""

    def __init__(self, state_set: StateSet, k: int, margin_fn: MarginFunction,
                 domain: tuple[FloatArray, FloatArray] | None) -> None:
        self.single: StateSet = (state_set[k],)
        self.margin_fn = margin_fn
        self.domain = domain

    def __call__(self, x: FloatArray) -> FloatArray:
        return np.asarray(self.margin_fn(self.single, np.atleast_2d(x)), dtype=np.float64)

    def clipped(self, x: FloatArray) -> FloatArray:
        """The margin, min with the distance inside the domain box (the search's objective)."""
        m = self(x)
        if self.domain is not None:
            lo, hi = self.domain
            x = np.atleast_2d(x)
            m = np.minimum(m, np.min(np.minimum(x - lo, hi - x), axis=1))
        return m


def _scale(model: Model, domain: tuple[FloatArray, FloatArray] | None) -> FloatArray:
    n = model.n
    eq = np.array([float(v) for v in model.equilibrium])
    if domain is not None:
        lo, hi = domain
        width = np.where(np.isfinite(hi - lo), (hi - lo) / 2, 0.0)
    else:
        width = np.zeros(n)
    s = np.maximum(width, np.abs(eq))
    return np.where(s > 0, s, 1.0)


def _inner_point(piece: _Piece, model: Model, scale: FloatArray, rng: np.random.Generator) -> FloatArray:
    """A point inside the piece, away from its boundary where the search allows (module doc)."""
    n = model.n
    eq = np.array([float(v) for v in model.equilibrium])
    cands = [eq[None, :], np.zeros((1, n))]
    for centre in (eq, np.zeros(n)):
        for s in CLOUD_SCALES:
            cands.append(centre + s * rng.standard_normal((CLOUD_POINTS, n)))
    if piece.domain is not None:
        lo, hi = piece.domain
        if np.all(np.isfinite(lo)) and np.all(np.isfinite(hi)):
            cands.append(lo + (hi - lo) * rng.random((DOMAIN_POINTS, n)))
            cands.append(((lo + hi) / 2)[None, :])
    pts = np.vstack(cands)
    with np.errstate(all="ignore"):
        values = np.nan_to_num(piece.clipped(pts), nan=-np.inf)
    order = np.argsort(-values, kind="stable")[:POLISH_STARTS]
    best_x, best_v = pts[order[0]], float(values[order[0]])

    def objective(x: FloatArray) -> float:
        with np.errstate(all="ignore"):
            v = float(piece.clipped(x[None, :])[0])
        return -v if math.isfinite(v) else math.inf

    for i in order:
        x0 = _evolve(piece, pts[i], float(values[i]), scale, rng)
        v0 = -objective(x0)
        if v0 >= 0:  # inside already: Nelder-Mead would only move it deeper (seconds in 8 states)
            if v0 > best_v:
                best_x, best_v = x0, v0
            continue
        from scipy.optimize import minimize  # only here: its import is 0.3-0.5 s of a falsification

        step = 0.1 * np.maximum(np.abs(x0), scale * 1e-2)
        simplex = np.vstack([x0] + [x0 + step[k] * np.eye(n)[k] for k in range(n)])
        res = minimize(objective, x0, method="Nelder-Mead",
                       options={"initial_simplex": simplex, "maxiter": POLISH_ITERATIONS_PER_STATE * n,
                                "xatol": 1e-12, "fatol": 1e-14})
        v = -float(res.fun)
        if v > best_v:
            best_x, best_v = np.asarray(res.x, dtype=np.float64), v
    if not best_v >= 0 or not piece(best_x[None, :])[0] >= 0:
        raise ValueError(f"The initial set's piece has no point found inside (the largest margin found is "
                         f"{best_v:.6g}). Got a piece that is empty or too thin to sample instead.")
    return best_x


def _evolve(piece: _Piece, x: FloatArray, value: float, scale: FloatArray,
            rng: np.random.Generator) -> FloatArray:
    """A seeded (1 + lambda) evolution strategy on the clipped margin from ``x``: the best of
    :data:`EVOLVE_OFFSPRING` Gaussian steps replaces ``x`` when it improves, else the step halves
    (the margin of a box or of an intersection is a min of functions, not smooth: Nelder-Mead alone
    stalls on its kinks in 8 states)."""
    sigma = EVOLVE_STEP * scale
    for _ in range(EVOLVE_ROUNDS):
        trial = x + sigma * rng.standard_normal((EVOLVE_OFFSPRING, x.size))
        with np.errstate(all="ignore"):
            v = np.nan_to_num(piece.clipped(trial), nan=-np.inf)
        j = int(np.argmax(v))
        if v[j] > value:
            x, value = trial[j], float(v[j])
            sigma = sigma * 1.5
        else:
            sigma = sigma / 2
        if np.all(sigma < 1e-9 * scale):
            break
    return x


def _face_has_inside(piece: _Piece, lo: FloatArray, hi: FloatArray, k: int, side: int, value: float,
                     rng: np.random.Generator) -> bool:
    n = lo.size
    pts = lo + (hi - lo) * rng.random((BOX_FACE_POINTS * n, n))
    pts[:, k] = value
    with np.errstate(all="ignore"):
        return bool(np.any(piece(pts) >= 0))


def _grow_box(piece: _Piece, c: FloatArray, scale: FloatArray,
              rng: np.random.Generator) -> tuple[FloatArray, FloatArray]:
    """A box around ``c`` with no sampled inside point on its faces (module doc, step 2)."""
    n = c.size
    cap_lo, cap_hi = c - BOX_MAX * scale, c + BOX_MAX * scale
    if piece.domain is not None:
        cap_lo, cap_hi = np.maximum(cap_lo, piece.domain[0]), np.minimum(cap_hi, piece.domain[1])
    dist = np.full((n, 2), 0.0)
    dist[:, 0] = np.minimum(BOX_START * scale, c - cap_lo)
    dist[:, 1] = np.minimum(BOX_START * scale, cap_hi - c)
    limit = np.column_stack([c - cap_lo, cap_hi - c])
    inner = np.zeros((n, 2))

    def box() -> tuple[FloatArray, FloatArray]:
        return c - dist[:, 0], c + dist[:, 1]

    def face(k: int, side: int) -> bool:
        lo, hi = box()
        value = lo[k] if side == 0 else hi[k]
        return _face_has_inside(piece, lo, hi, k, side, value, rng)

    for _ in range(BOX_ROUNDS):
        moved = False
        for k in range(n):
            for side in (0, 1):
                if dist[k, side] < limit[k, side] and face(k, side):
                    inner[k, side] = dist[k, side]
                    dist[k, side] = min(2 * dist[k, side] if dist[k, side] > 0 else BOX_START * scale[k],
                                        limit[k, side])
                    moved = True
        if not moved:
            break
    for k in range(n):
        for side in (0, 1):
            a, b = inner[k, side], dist[k, side]
            if b >= limit[k, side]:
                continue
            for _ in range(BOX_BISECTIONS):
                mid = (a + b) / 2
                dist[k, side] = mid
                if face(k, side):
                    a = mid
                else:
                    b = mid
            dist[k, side] = b
    return box()


def _sample_piece(piece: _Piece, c: FloatArray, lo: FloatArray, hi: FloatArray, count: int,
                  rng: np.random.Generator) -> FloatArray:
    """``count`` starts in the piece: interior by rejection, a fraction on the boundary."""
    n = c.size
    n_boundary = int(round(count * BOUNDARY_FRACTION)) if count > 1 else 0
    n_inside = count - n_boundary
    inside: list[FloatArray] = []
    outside: list[FloatArray] = []
    got, drawn, got_out = 0, 0, 0
    while (got < n_inside or got_out < n_boundary) and drawn < REJECTION_MAX:
        pts = lo + (hi - lo) * rng.random((REJECTION_BATCH, n))
        drawn += REJECTION_BATCH
        with np.errstate(all="ignore"):
            ok = piece(pts) >= 0
        if got < n_inside:
            inside.append(pts[ok][: n_inside - got])
            got += inside[-1].shape[0]
        if got_out < n_boundary:
            outside.append(pts[~ok][: n_boundary - got_out])
            got_out += outside[-1].shape[0]
    starts = np.vstack(inside) if inside else np.zeros((0, n))
    if starts.shape[0] < n_inside:
        # a set thin in its box: fill with copies of the inner point rather than leave starts out
        starts = np.vstack([starts, np.repeat(c[None, :], n_inside - starts.shape[0], axis=0)])
    if n_boundary:
        far = np.vstack(outside) if outside else np.zeros((0, n))
        if far.shape[0] < n_boundary:
            # the piece fills its box (e.g. clipped by the domain): the box's faces are its boundary
            extra = lo + (hi - lo) * rng.random((n_boundary - far.shape[0], n))
            ks = rng.integers(0, n, extra.shape[0])
            sides = rng.integers(0, 2, extra.shape[0])
            extra[np.arange(extra.shape[0]), ks] = np.where(sides == 0, lo[ks], hi[ks])
            far = np.vstack([far, extra])
        a = np.zeros(far.shape[0])
        b = np.ones(far.shape[0])
        with np.errstate(all="ignore"):
            if np.all(piece(far) >= 0):
                a = b.copy()
            for _ in range(BOUNDARY_BISECTIONS):
                mid = (a + b) / 2
                ok = piece(c + mid[:, None] * (far - c)) >= 0
                a = np.where(ok, mid, a)
                b = np.where(ok, b, mid)
        starts = np.vstack([starts, c + a[:, None] * (far - c)])
    return starts


def sample_set(model: Model, state_set: StateSet, margin_fn: MarginFunction, samples: int,
               rng: np.random.Generator) -> tuple[FloatArray, list[tuple[FloatArray, FloatArray]]]:
    """``samples`` starts in ``state_set`` (split evenly between its pieces) and each piece's box."""
    if not state_set:
        raise ValueError("The 'state_set' parameter must have at least one piece. Got an empty set instead.")
    domain = _domain_box(model)
    scale = _scale(model, domain)
    shares = [samples // len(state_set) + (1 if k < samples % len(state_set) else 0) for k in range(len(state_set))]
    out, boxes = [], []
    for k, share in enumerate(shares):
        piece = _Piece(state_set, k, margin_fn, domain)
        c = _inner_point(piece, model, scale, rng)
        lo, hi = _grow_box(piece, c, scale, rng)
        boxes.append((lo, hi))
        if share:
            out.append(_sample_piece(piece, c, lo, hi, share, rng))
    return np.vstack(out), boxes


# -- disturbances -------------------------------------------------------------------------------

def _scenarios(model: Model, horizon: float, starts: int, rng: np.random.Generator,
               disturbed: bool) -> tuple[list[Disturbance], list[Disturbance]]:
    """Per start, the constant scenarios (shared by every start) and the bang-bang ones (drawn per
    start): ``(constant, bang_bang)``; ``bang_bang`` has ``starts * BANG_BANG_PER_START`` entries."""
    m = len(model.disturbances)
    if not m or not disturbed:
        return [Disturbance("none")], []
    bounds = np.array([float(b) for b in model.disturbances.values()])
    if 2 ** m <= MAX_VERTICES:
        signs = np.array(list(np.ndindex(*([2] * m))), dtype=np.float64) * 2 - 1
    else:
        signs = (rng.integers(0, 2, (MAX_VERTICES, m)) * 2.0 - 1).astype(np.float64)
    constant = [Disturbance("constant", (tuple(float(v) for v in s * bounds),)) for s in signs]
    bang = []
    for _ in range(starts * BANG_BANG_PER_START):
        dwell = horizon / math.exp(rng.uniform(math.log(DWELL_MIN_DIVISOR), math.log(DWELL_MAX_DIVISOR)))
        times = np.cumsum(rng.exponential(dwell, MAX_SWITCHES))
        times = times[times < horizon]
        levels = rng.integers(0, 2, (times.size + 1, m)) * 2.0 - 1
        if m == 1:
            # alternate: a switch to the same vertex would be no switch
            levels[:, 0] = levels[0, 0] * (-1.0) ** np.arange(times.size + 1)
        bang.append(Disturbance("bang-bang", tuple(tuple(float(v) for v in row * bounds) for row in levels),
                                tuple(float(t) for t in times)))
    return constant, bang


class _Switched(ModelSystem):
    """The model with a piecewise-constant disturbance per row; its switching times are breakpoints."""

    def __init__(self, field: FieldEvaluator, rows: int, times: FloatArray, levels: FloatArray,
                 index: IntArray | None = None, escape: FloatArray | None = None,
                 center: FloatArray | None = None) -> None:
        super().__init__(field, rows, disturbance=self._value, index=index, escape=escape, center=center)
        self.times = times
        self.levels = levels

    def _value(self, t: FloatArray, y: FloatArray, index: IntArray) -> FloatArray:
        if not self.times.shape[1]:
            return self.levels[index, 0]
        k = np.sum(self.times[index] <= t[:, None], axis=1)
        return self.levels[index, k]

    def take(self, index: IntArray) -> "_Switched":
        return _Switched(self.field, self.rows, self.times, self.levels, self.index[index], self.escape, self.center)

    def next_breakpoint(self, t: FloatArray) -> FloatArray:
        if not self.times.shape[1]:
            return np.full(t.shape, np.inf)
        table = self.times[self.index]
        return np.where(table > t[:, None], table, np.inf).min(axis=1)


def _tables(dists: Sequence[Disturbance], m: int) -> tuple[FloatArray, FloatArray]:
    width = max((len(d.switch_times) for d in dists), default=0)
    times = np.full((len(dists), width), np.inf)
    levels = np.zeros((len(dists), width + 1, m))
    for i, d in enumerate(dists):
        k = len(d.switch_times)
        times[i, :k] = d.switch_times
        vals = np.array(d.values, dtype=np.float64).reshape(-1, m)
        levels[i, : vals.shape[0]] = vals
        levels[i, vals.shape[0]:] = vals[-1]
    return times, levels


# -- watching the unsafe set --------------------------------------------------------------------

class _Watch:
    """The integrator's step observer: per row, the largest unsafe margin and where, the first
    entry (bisected on the step's interpolant) and the first time outside the domain box."""

    def __init__(self, rows: int, n: int, margin: Callable[[FloatArray], FloatArray],
                 domain: tuple[FloatArray, FloatArray] | None) -> None:
        self.margin = margin
        self.domain = domain
        self.best = np.full(rows, -np.inf)
        self.best_t = np.zeros(rows)
        self.best_x = np.full((rows, n), np.nan)
        self.entry_t = np.full(rows, np.nan)
        self.entry_x = np.full((rows, n), np.nan)
        self.entry_m = np.full(rows, np.nan)
        self.left_t = np.full(rows, np.inf)

    def _values(self, x: FloatArray) -> FloatArray:
        with np.errstate(all="ignore"):
            v = np.asarray(self.margin(x), dtype=np.float64)
        return np.where(np.isfinite(v), v, -np.inf)

    def _outside(self, x: FloatArray) -> npt.NDArray[np.bool_]:
        if self.domain is None:
            return np.zeros(x.shape[0], dtype=bool)
        lo, hi = self.domain
        return np.any((x < lo) | (x > hi), axis=1)

    def start(self, index: IntArray, t: FloatArray, y: FloatArray, f: FloatArray) -> None:
        v = self._values(y)
        self.best[index], self.best_t[index], self.best_x[index] = v, t, y
        inside = v >= 0
        self.entry_t[index[inside]] = t[inside]
        self.entry_x[index[inside]] = y[inside]
        self.entry_m[index[inside]] = v[inside]
        out = self._outside(y)
        self.left_t[index[out]] = t[out]

    def step(self, index: IntArray, t0: FloatArray, t1: FloatArray, y0: FloatArray, y1: FloatArray,
             f0: FloatArray, f1: FloatArray) -> None:
        h = t1 - t0
        r, n = y0.shape
        thetas = np.array(SAMPLE_THETAS)
        pts = np.stack([hermite(th, h, y0, y1, f0, f1) for th in SAMPLE_THETAS[:-1]] + [y1])  # (T, r, n)
        flat = pts.reshape(-1, n)
        v = self._values(flat).reshape(len(SAMPLE_THETAS), r)
        j = np.argmax(v, axis=0)
        vj = v[j, np.arange(r)]
        better = vj > self.best[index]
        if better.any():
            rows = np.flatnonzero(better)
            self.best[index[rows]] = vj[rows]
            self.best_t[index[rows]] = t0[rows] + thetas[j[rows]] * h[rows]
            self.best_x[index[rows]] = pts[j[rows], rows]
        out = self._outside(flat).reshape(len(SAMPLE_THETAS), r)
        newly_out = out.any(axis=0) & ~np.isfinite(self.left_t[index])
        if newly_out.any():
            rows = np.flatnonzero(newly_out)
            first = np.argmax(out[:, rows], axis=0)
            self.left_t[index[rows]] = t0[rows] + thetas[first] * h[rows]
        fresh = (v >= 0).any(axis=0) & np.isnan(self.entry_t[index])
        if fresh.any():
            rows = np.flatnonzero(fresh)
            first = np.argmax(v[:, rows] >= 0, axis=0)
            b = thetas[first]
            a = np.where(first > 0, thetas[np.maximum(first - 1, 0)], 0.0)
            args = (h[rows], y0[rows], y1[rows], f0[rows], f1[rows])
            for _ in range(ENTRY_BISECTIONS):
                mid = (a + b) / 2
                ok = self._values(hermite(mid, *args)) >= 0
                a, b = np.where(ok, a, mid), np.where(ok, mid, b)
            x = hermite(b, *args)
            self.entry_t[index[rows]] = t0[rows] + b * h[rows]
            self.entry_x[index[rows]] = x
            self.entry_m[index[rows]] = self._values(x)


# -- the horizon --------------------------------------------------------------------------------

def default_horizon(model: Model, scale: FloatArray | None = None, evaluate: Any = None) -> float:
    """How long :func:`falsify` simulates by default (module doc, Simulation); ``evaluate``: the
    field (default the polynomial model's)."""
    evaluate = FieldEvaluator.of(model) if evaluate is None else evaluate
    eq = np.array([float(v) for v in model.equilibrium])
    scale = np.ones(model.n) if scale is None else scale
    # the phase portraits' rule, with a longer cap (a falsification may take its time)
    return horizon_of(jacobian_eigenvalues(evaluate, eq, scale), fast_cap=FAST_TIME_CONSTANTS_CAP)


# -- the search ---------------------------------------------------------------------------------

class _Stopped:
    """``evaluate`` held at 0 inside ``stop`` (module doc, Stopping at a goal)."""

    def __init__(self, evaluate: Any, stop: StateSet, margin_fn: MarginFunction) -> None:
        self.evaluate = evaluate
        self.stop = stop
        self.margin_fn = margin_fn

    def __call__(self, x: FloatArray, d: FloatArray | None = None) -> FloatArray:
        f = np.asarray(self.evaluate(x, d), dtype=np.float64)
        with np.errstate(all="ignore"):
            reached = np.asarray(self.margin_fn(self.stop, np.atleast_2d(x)), dtype=np.float64) >= 0
        return np.where(reached[:, None], 0.0, f)


def falsify(model: Model, initial: StateSet, unsafe: StateSet, margin_fn: MarginFunction, *,
            samples: int = SAMPLES, horizon: float | None = None, seed: int = 0,
            disturbed: bool = True, evaluate: Any = None, stop: StateSet | None = None) -> Falsification:
    """Simulate from ``samples`` starts in ``initial`` and report the closest approach to ``unsafe``.

    Parameters
    ----------
    model
        The parsed model (its parameters as declared).
    initial, unsafe
        Sets: tuples of pieces (a union), each a tuple of polynomials of ``model.state_ring``,
        ``p >= 0`` inside (the ``[sets]`` table's form).
    margin_fn
        ``margin_fn(state_set, points)``: for ``(k, n)`` points (the states in declared order),
        ``(k,)`` values ``>= 0`` inside the set and ``< 0`` outside (``lyapcheck.models.language.sets.margin``).
    samples
        Starts drawn from the initial set (module doc, Starts); each meets every disturbance
        scenario (module doc, Disturbances).
    horizon
        Simulated time, s (default :func:`default_horizon`).
    seed
        Seed of every random draw (starts, vertices, switching times): the result is a function of
        the arguments.
    disturbed
        With False, the disturbances are held at 0 (for a claim made with ``d = 0`` only).
    evaluate
        The field ``evaluate(x, d)`` (rows), default the polynomial model's
        (:class:`~lyapcheck.models.engines.numeric.FieldEvaluator`); a loop with functions gives its true
        field (:mod:`lyapcheck.models.classes.barrier`), ``model`` then any object with the
        attributes read here (``n``, ``states``, ``equilibrium``, ``domain``, ``disturbances``).
    stop
        A set (reach-avoid's goal): each trajectory is watched only until it reaches it (module doc,
        Stopping at a goal); None (the default) watches the whole horizon.

    Returns
    -------
    Falsification
    """
    t_start = time.perf_counter()
    if samples < 1:
        raise ValueError(f"The 'samples' parameter must be a positive integer. Got {samples!r} instead.")
    if horizon is not None and not (math.isfinite(horizon) and horizon > 0):
        raise ValueError(f"The 'horizon' parameter must be a positive number of seconds. Got {horizon!r} instead.")
    rng = np.random.default_rng(seed)
    n = model.n
    domain = _domain_box(model)
    starts, boxes = sample_set(model, initial, margin_fn, samples, rng)
    eq = np.array([float(v) for v in model.equilibrium])

    # the box of everything: domain (when bounded) or the initial set's boxes and the equilibrium
    if domain is not None and np.all(np.isfinite(domain[0])) and np.all(np.isfinite(domain[1])):
        lo, hi = domain
    else:
        lo = np.minimum(np.min([b[0] for b in boxes], axis=0), eq)
        hi = np.maximum(np.max([b[1] for b in boxes], axis=0), eq)
    half = (hi - lo) / 2
    scale = np.where(half > 0, half, np.maximum(np.abs(eq), 1.0))
    center = (lo + hi) / 2
    if horizon is None:
        horizon = default_horizon(model, scale, evaluate)

    constant, bang = _scenarios(model, horizon, starts.shape[0], rng, disturbed)
    per_start = len(constant) + BANG_BANG_PER_START * (1 if bang else 0)
    row_start = np.repeat(np.arange(starts.shape[0]), per_start)
    dists: list[Disturbance] = []
    for i in range(starts.shape[0]):
        dists.extend(constant)
        dists.extend(bang[i * BANG_BANG_PER_START:(i + 1) * BANG_BANG_PER_START])
    rows = len(dists)
    y0 = starts[row_start]

    evaluate = FieldEvaluator.of(model) if evaluate is None else evaluate
    if stop is not None:  # after the horizon: it is the unstopped field's
        evaluate = _Stopped(evaluate, stop, margin_fn)
    escape = ESCAPE_FACTOR * scale
    system: ModelSystem
    if dists[0].kind == "none":
        system = ModelSystem(evaluate, rows, escape=escape, center=center)
    else:
        times, levels = _tables(dists, len(model.disturbances))
        system = _Switched(evaluate, rows, times, levels, escape=escape, center=center)
    watch = _Watch(rows, n, lambda x: margin_fn(unsafe, x), domain)
    result = integrate(system, 0.0, y0, horizon, rtol=RTOL, atol=ATOL_PER_SCALE * scale,
                       max_step=horizon / MIN_STEPS, observer=watch)

    def witness(i: int, t: float, x: FloatArray, margin: float) -> Witness:
        inside = None if domain is None else bool(watch.left_t[i] > t)
        return Witness(tuple(float(v) for v in y0[i]), dists[i], float(t), tuple(float(v) for v in x),
                       float(margin), inside)

    entered = np.flatnonzero(~np.isnan(watch.entry_t))
    in_domain = entered if domain is None else entered[watch.left_t[entered] > watch.entry_t[entered]]
    entry = None
    if entered.size:
        i = int(entered[np.argmin(watch.entry_t[entered])])
        entry = witness(i, watch.entry_t[i], watch.entry_x[i], watch.entry_m[i])
    k = int(np.argmax(watch.best))
    closest = witness(k, watch.best_t[k], watch.best_x[k], watch.best[k])
    final = result.y
    with np.errstate(all="ignore"):
        escaped = int(np.sum(~np.all(np.abs(final - center) < escape * (1 - 1e-9), axis=1)))
    return Falsification(
        samples=int(starts.shape[0]), trajectories=rows, horizon=float(horizon),
        closest_approach=float(watch.best[k]), closest=closest, entry=entry, entries=int(entered.size),
        entries_in_domain=int(in_domain.size), escaped=escaped, failed=int(np.sum(result.status != STATUS_OK)),
        disturbance_scenarios=per_start, seed=seed, elapsed_s=time.perf_counter() - t_start,
        states=tuple(model.states), disturbances=tuple(model.disturbances),
        boxes=tuple((tuple(float(v) for v in b[0]), tuple(float(v) for v in b[1])) for b in boxes))


# -- replaying one witness ------------------------------------------------------------------------

def disturbance_of(data: Mapping[str, Any], model: Any) -> Disturbance:
    """A witness's disturbance (:meth:`Disturbance.to_dict`) read back, or ValueError when it is not
    one :func:`falsify` could have drawn: ``none``, or ``constant`` / ``bang-bang`` values of one
    entry per disturbance, each ``|d_k| <= b_k``, the switching times finite and increasing."""
    bounds = [float(b) for b in model.disturbances.values()]
    kind = data.get("kind")
    values = tuple(tuple(float(v) for v in row) for row in data.get("values", ()))
    times = tuple(float(t) for t in data.get("switch_times", ()))
    if kind == "none":
        if values or times:
            raise ValueError("a disturbance of kind 'none' has no values and no switching times")
        return Disturbance("none")
    if kind not in ("constant", "bang-bang") or not bounds:
        raise ValueError(f"the disturbance's kind must be 'none'{'' if not bounds else ', constant or bang-bang'}, "
                         f"not {kind!r}")
    rows = 1 if kind == "constant" else len(times) + 1
    if len(values) != rows or (kind == "constant" and times):
        raise ValueError(f"a {kind} disturbance has {rows} row(s) of values, one per segment; it has {len(values)}")
    if any(len(row) != len(bounds) or not all(math.isfinite(v) and abs(v) <= b for v, b in zip(row, bounds))
           for row in values):
        raise ValueError("every disturbance value must be within its declared bound |d_k| <= b_k")
    if not all(math.isfinite(t) and t > 0 for t in times) or any(b <= a for a, b in zip(times, times[1:])):
        raise ValueError("the switching times must be finite, positive and increasing")
    return Disturbance(kind, values, times)


def replay(model: Any, start: Sequence[float], disturbance: Disturbance, until: float, unsafe: StateSet,
           margin_fn: MarginFunction, *, stop: StateSet | None = None, evaluate: Any = None) -> Witness | None:
    """Re-simulate one trajectory as :func:`falsify` does (same integrator and tolerances, ``stop``
    as there) from ``start`` under ``disturbance`` until ``until`` s: its first entry into ``unsafe``
    (start, disturbance, time and point), or None when it does not enter by then."""
    y0 = np.array([[float(v) for v in start]], dtype=np.float64)
    if y0.shape != (1, model.n) or not np.all(np.isfinite(y0)):
        raise ValueError(f"The 'start' parameter must be {model.n} finite numbers. Got {list(start)!r} instead.")
    if not (math.isfinite(until) and until >= 0):
        raise ValueError(f"The 'until' parameter must be a time >= 0 s. Got {until!r} instead.")
    evaluate = FieldEvaluator.of(model) if evaluate is None else evaluate
    if stop is not None:
        evaluate = _Stopped(evaluate, stop, margin_fn)
    domain = _domain_box(model)
    watch = _Watch(1, model.n, lambda x: margin_fn(unsafe, x), domain)
    if until == 0:  # the start itself: no step to take
        watch.start(np.arange(1), np.zeros(1), y0, evaluate(y0))
    else:
        system: ModelSystem
        if disturbance.kind == "none":
            system = ModelSystem(evaluate, 1)
        else:
            times, levels = _tables([disturbance], len(model.disturbances))
            system = _Switched(evaluate, 1, times, levels)
        integrate(system, 0.0, y0, until, rtol=RTOL, atol=ATOL_PER_SCALE * np.maximum(np.abs(y0[0]), 1.0),
                  max_step=until / MIN_STEPS, observer=watch)
    if np.isnan(watch.entry_t[0]):
        return None
    t = float(watch.entry_t[0])
    return Witness(tuple(float(v) for v in y0[0]), disturbance, t, tuple(float(v) for v in watch.entry_x[0]),
                   float(watch.entry_m[0]), None if domain is None else bool(watch.left_t[0] > t))
