"""Named numerical tolerances, in one place.

Exact checks use no tolerance at all: they are done in rational arithmetic. The numbers
here only steer the *search* (solver accuracy, line searches) and the comparison of
floating-point simulations; none of them can turn a failed exact check into a pass.
"""

from __future__ import annotations

from fractions import Fraction
from typing import Any, Final

#: Clarabel's gap / feasibility tolerances for certificate searches (tighter than defaults,
#: because the exact check after rounding needs interior points with some slack).
SOLVER_TOL_GAP_ABS: Final = 1e-10
SOLVER_TOL_GAP_REL: Final = 1e-10
SOLVER_TOL_FEAS: Final = 1e-10
SOLVER_MAX_ITER: Final = 200
#: iteration cap of one ``sos_bound`` solve in its conditioned coordinates: there a solve whose
#: result passes the exact check takes 20-40 iterations (74 at most on 102 points of the shipped
#: sweeps), while one that runs on rarely passes; a failed solve is retried in other coordinates
SOS_BOUND_MAX_ITER: Final = 60
#: an eigenvalue computed in floats below -SCREEN_MARGIN ||m|| shows that the rational matrix m is
#: not positive definite (float error is below 1e-13 ||m|| at the sizes here): a search may then
#: skip the exact check that would fail (lyapcheck.exact.surely_not_positive_definite). Speed only
SCREEN_MARGIN: Final = 1e-9





#: a map's reach_avoid, its steps bound floor(C / eps) tightened after the certificate is found
#: (lyapcheck.models.classes.discrete_safety.tighten_reach): at most this many solves that minimise C
#: with eps fixed, eps multiplied by REACH_TIGHTEN_GROWTH after each one that lowered the bound, and
#: every Gram matrix kept above REACH_TIGHTEN_FLOOR * eps so that the rounded point passes the exact
#: check. Search only: the exact check decides every certificate
REACH_TIGHTEN_SOLVES: Final = 4
REACH_TIGHTEN_GROWTH: Final = Fraction(4)
REACH_TIGHTEN_FLOOR: Final = 1e-4


#: Simulator accuracy contract (relative to the state scale), tested against solve_ivp.
SIM_REL_TOL: Final = 1e-6
#: Step budget of one simulated trajectory (steps tried: accepted, rejected or retried at a
#: kink). Past it the trajectory fails with "step budget exhausted" (``simulate`` exit 1): at
#: extreme but valid scales the loop is stiff and the explicit integrator's step is bounded by
#: stability, so the run would otherwise take hours. Deterministic, unlike a wall-time limit.
#: The shipped scenarios take ~200 steps; the most the shipped sweeps need is ~16,000 (the
#: adversarial disturbance chattering at alpha_d = 2400 over 60 s), hence 3x that. One step of
#: one trajectory costs ~3 ms, so the budget bounds a single simulation to about three minutes.
SIM_MAX_STEPS: Final = 50_000

#: Switching search (``switched_ges``): a periodic switching law counts as a candidate for the
#: exact instability proof when its numerically estimated growth per period exceeds
#: ``1 + SWITCHING_MIN_GROWTH``. Only steers the search; the proof is an exact interval check.
SWITCHING_MIN_GROWTH: Final = 1e-9
#: Relative precision (bits) of the outward-rounded interval enclosures of ``expm(A t)``
#: tried in turn by the exact switching check; more bits only matter when the growth margin
#: ``rho(M) - 1`` is within a few orders of magnitude of ``SWITCHING_MIN_GROWTH``.
SWITCHING_ENCLOSURE_BITS: Final = (96, 192, 384)

#: The paper's ultimate_bound over a box: where every candidate ellipsoid of a stage fails its exact
#: check as solved, each candidate's Q is retried inflated by 1 + d for these d in turn (the exact
#: check decides each). On numpy's SSE loops with OpenBLAS's Nehalem kernel every rounded Q of the
#: +-2 % box fails by about 5e-11 relative; 1e-4 recovers the bound (0.4236 mm, 5 stages). Search only
BOX_STAGE_Q_INFLATIONS: Final = (1e-4, 1e-3, 1e-2, 1e-1)

#: Wall-time limit of one condition class at one point (``certify``): past it the class reports
#: ``inconclusive`` naming this limit. Far above the 1-6 s the slowest class takes at sane gains.
CLASS_TIME_LIMIT_S: Final = 120.0

#: Box cross-check (``lyapcheck.paper.boxes.cross_check.cross_check``): a simulated ``|x(t)|`` counts as leaving a
#: certified GES envelope ``k |x0| exp(-rate t)`` only beyond this relative slack, which absorbs
#: the integrator's error (it runs at ``rtol = 1e-10``), never a modelling slack.
ENVELOPE_REL_TOL: Final = 1e-6

#: Wall-time limit of one generic class on a model file (``certify --model``): its search stops
#: there and the class reports ``inconclusive`` naming this limit; the other classes still run.
#: The examples' slowest class (roa on the reversed Van der Pol with mu = 3) takes about 10 s.
MODEL_CLASS_TIME_LIMIT_S: Final = 60.0

# -- sos_gas on networks: the cheaper cones and the order of its forms against its time (issue 43) ---
#
# (the cones' limits moved here from lyapcheck.models.classes.lyapunov, which re-exports them; the
# estimates below only order the forms of a search: every certificate is still decided exactly)

#: the SDSOS/DSOS programs' size limits: a cone program has no dense block to factor, so the
#: semidefinite limits on Gram rows and on the blocks' cost (BLOCK_COST_LIMIT) give way to these,
#: measured on the networks of benchmarks/bench_networks.py (benchmarks/README.md, issue 43)
CONE_CANDIDATE_LIMIT: Final = 1_000
CONE_TARGET_LIMIT: Final = 6_000
CONE_GRAM_ROWS: Final = 500
#: the most decisions of a cone program's blocks (lyapcheck.sos.structure.Structure.cone_size)
CONE_SIZE_LIMIT: Final = 400_000
#: the solves the cones may spend in all (a count, so that a loaded machine does the same work): the
#: 8-state platoon's SDSOS certificate took 2 solves (one facial reduction) and 2 more for its decay rate
CONE_FALLBACK_SOLVES: Final = 40
#: the estimated seconds of one solve and its exact rounding (lyapcheck.models.engines.search.
#: estimated_seconds): a floor for the compile and the solver's start, plus the program's semidefinite
#: work units (Structure.cost) at PSD_WORK_PER_SECOND and its cone decisions (Structure.cone_size) at
#: CONE_DECISIONS_PER_SECOND. Measured on the 8-state platoon and lyznet-10d, one solve and its
#: rounding, on an idle core: 4.4e8 units in 3.5 s, 8.5e8 in 5.7 s, 1.4e8 in 2.1 s (about 1.3e8/s,
#: the rates below are the slower end); 31,452 cone decisions in 17 s, 21,346 in 8 s, 9,921 in 2.8 s
ESTIMATE_SOLVE_FLOOR_S: Final = 0.1
PSD_WORK_PER_SECOND: Final = 1.0e8
CONE_DECISIONS_PER_SECOND: Final = 2_500.0
#: a form (its facial reductions and decay-rate steps) is estimated at this many solves of its first
#: program: later rounds are smaller (measured 1.4 to 4.2 times the first, 7.6 with its decay rate)
FORM_SOLVES_ESTIMATE: Final = 4


# -- figures of the paper's classes across floating-point platforms (issue 24) ------------------
# A status is decided by exact checks and must be the same on every platform. A figure starts from
# a solver's floating-point answer, whose last bits follow numpy's SIMD loops and the OpenBLAS
# kernel, so it may move from one platform to another, by at most what its search resolves:
# the tolerances below, relative (RTOL) and, for figures that sit near 0, absolute (ATOL).
# tests/test_verdicts_unchanged.py compares every figure of its snapshot with them, on this
# machine and on an emulated second platform. :func:`figure_tolerance` maps each figure to one.

#: computed from the inputs in exact arithmetic (strip width, wind-up bound, reach margin,
#: comparison box, eq:stabCond2's left-hand side, the gains): the same number, up to the last
#: bit of a float conversion or a correctly rounded square root
FIGURE_EXACT_RTOL: Final = 1e-12
#: a margin: the optimum of a program normalised to scale 1 (trace P = 1, trace Q_V = 1), which
#: Clarabel resolves to its tolerances (1e-10) when it converges, and to ~1e-8 absolute when it
#: stops "inaccurate" at badly scaled gains (measured: 2e-8 at sweep-alpha-sigma@0,11, margin 9e-7)
FIGURE_MARGIN_RTOL: Final = 1e-6
FIGURE_MARGIN_ATOL: Final = 1e-7
#: a figure read off the solver's point at a unique optimum (the paper's ball from the ISS P, the
#: sector decay rate from P rounded to 6 digits): the point moves with the optimum's accuracy,
#: 1e-5 relative at most in the emulations, and the 6-digit roundings add 1e-6
FIGURE_SOLVER_POINT_RTOL: Final = 1e-4
#: lambda_max/lambda_min of a P normalised to trace 1: the solver resolves P's smallest eigenvalue
#: to about this, absolutely, so the ratio to this times the ratio (8.5e7 at the worst shipped
#: case: 1e-2; measured 6e-5 there)
FIGURE_CONDITION_RESOLUTION: Final = 1e-10
#: a decay rate found by geometric bisection whose steps are decided exactly (sos_gas, ges): the
#: steps do not follow the solver's last bits (issue 24), and were a step decided otherwise the
#: rate would move by the last bracket: 4^(1/16) - 1 = 9 % (sos_gas), 256^(1/64) - 1 = 9 % from
#: ges's 1/64 up and 156250^(1/64) - 1 = 21 % on its slow branch below it
FIGURE_BISECTED_RATE_RTOL: Final = 0.21
#: ges's k = sqrt(c2/c1): c2 is the optimum t rounded up to 6 digits with fixed shares of slack,
#: so it moves with t, resolved to ~1e-5 by the "inaccurate" solves of these badly scaled data
#: (measured 9e-6)
FIGURE_GES_K_RTOL: Final = 1e-4
#: ultimate_bound's bound: a golden-section line search whose comparisons treat values within
#: 1e-6 as equal; the bound at the minimum over lambda moves at second order in lambda (measured
#: 2e-5, big_gains)
FIGURE_LINE_SEARCH_RTOL: Final = 1e-4
#: switched_ges's dwell times, rounded to 3 significant digits (the shortest rational that keeps
#: half the growth margin): one unit of the third digit, and the growth at those times with them
FIGURE_DWELL_TIME_RTOL: Final = 1e-2
#: sos_bound's bound (and the real-loop bound that quotes it): the smallest B of a solve stopped
#: at its iteration cap (SOS_BOUND_MAX_ITER), raised by 1e-3 and rounded up to 4 digits; where
#: the solver stops "inaccurate" it is known to ~1 % (measured 0.65 %, slow_k), and a rate whose
#: solutions fail on one platform hands the bound to the next coordinates (1.7 %, measured)
FIGURE_SOS_BOUND_RTOL: Final = 2e-2
#: saturated_loop's figures that follow sos_gas's V (the invariant radius, the bound under d*):
#: the level is on a 4-digit grid (1e-3), and V is the solver's point, whose entries move by about
#: FIGURE_V_RESOLUTION against the margin t of its Gram matrices: rtol = 1e-3 + this / t (2e-3 at
#: t = 1.8e-4; 0.23 at t = 8.6e-7, sweep-alpha-sigma@0,11, where 10 % was measured)
FIGURE_LEVEL_GRID_RTOL: Final = 1e-3
FIGURE_V_RESOLUTION: Final = 2e-7


def figure_tolerance(cls: str, key: str, value: float, case: dict[str, Any]) -> tuple[float, float]:
    """``(rtol, atol)`` of a figure ``key`` of class ``cls`` (a number its ``numbers`` hold), given the
    other classes' results at the same point (``case``: class -> {"status", "numbers"}).

    Raises ``KeyError`` for a figure with no documented tolerance: a new figure must be given one.
    """
    if key in _EXACT_FIGURES.get(cls, ()):
        return FIGURE_EXACT_RTOL, 0.0
    if key == "relative_margin":
        return FIGURE_MARGIN_RTOL, FIGURE_MARGIN_ATOL
    if key == "lambda_max_over_min_P":
        return max(FIGURE_SOLVER_POINT_RTOL, FIGURE_CONDITION_RESOLUTION * abs(value)), 0.0
    if cls in ("sos_gas", "ges") and key in ("decay_rate_V_per_s", "decay_rate_per_s"):
        return FIGURE_BISECTED_RATE_RTOL, 0.0
    if cls == "saturated_loop" and key in ("invariant_eps_radius_m_at_s0", "ultimate_eps_bound_m"):
        margin = case.get("sos_gas", {}).get("numbers", {}).get("relative_margin")
        if not margin:  # pragma: no cover - saturated_loop certifies only with sos_gas's V
            return FIGURE_LEVEL_GRID_RTOL, 0.0
        return FIGURE_LEVEL_GRID_RTOL + FIGURE_V_RESOLUTION / float(margin), 0.0
    return _FIGURE_RTOL[(cls, key)], 0.0


#: the figures computed from the inputs alone (FIGURE_EXACT_RTOL), by class
_EXACT_FIGURES: Final[dict[str, tuple[str, ...]]] = {
    "prop41_ges": ("rhs_gain_g", "iss_gain_e"), "prop41_iss": ("rhs_gain_g", "iss_gain_e"),
    "stabcond2": ("lhs_value",),
    "ultimate_bound": ("box_eps_bound_m", "box_s_bound", "d_max_m_per_s"),
    "saturated_loop": ("strip_half_width_m", "windup_bound_s_m", "reach_set_y_half_width_m", "reach_margin_m_per_s"),
    "sos_bound": ("d_max_m_per_s",),
}
#: every other figure's relative tolerance
_FIGURE_RTOL: Final[dict[tuple[str, str], float]] = {
    ("sector_ges", "decay_rate_per_s"): FIGURE_SOLVER_POINT_RTOL,
    ("ultimate_bound", "paper_ball_radius_as_printed"): FIGURE_SOLVER_POINT_RTOL,
    ("ultimate_bound", "eps_bound_m"): FIGURE_LINE_SEARCH_RTOL,
    ("ges", "k"): FIGURE_GES_K_RTOL, ("ges", "k_eps_s"): FIGURE_GES_K_RTOL,
    ("switched_ges", "t0_s"): FIGURE_DWELL_TIME_RTOL, ("switched_ges", "t1_s"): FIGURE_DWELL_TIME_RTOL,
    ("switched_ges", "period_s"): FIGURE_DWELL_TIME_RTOL,
    ("switched_ges", "growth_per_period"): FIGURE_DWELL_TIME_RTOL,
    ("switched_ges", "growth_per_period_lower_bound"): FIGURE_DWELL_TIME_RTOL,
    ("switched_ges", "growth_rate_per_s"): FIGURE_DWELL_TIME_RTOL,
    ("switched_ges", "decay_rate_per_s"): FIGURE_SOLVER_POINT_RTOL,
    ("sos_bound", "eps_bound_m"): FIGURE_SOS_BOUND_RTOL,
    ("saturated_loop", "real_loop_limsup_eps_m"): FIGURE_SOS_BOUND_RTOL,
}


# -- simulation cross-checks of model certificates (lyapcheck.models.engines.crosscheck) -------------------
#: a simulated trajectory breaks a model certificate's claim (V rises along it, V or |x| leaves its
#: certified envelope) only beyond this relative slack: the trajectories are integrated at rtol 1e-7
#: (lyapcheck.models.engines.trajectories.RTOL) and V is a polynomial of the state, so its float value along
#: a trajectory is good to about its degree times that; 1e-5 leaves a decade over a degree-8 V and
#: stays far below any modelling error a false certificate would show (moved from the report's
#: phase portrait, reports.phase_portrait.CHECK_TOL, now shared with the sweeps of model files)
TRAJECTORY_CHECK_REL_TOL: Final = 1e-5


# -- figures of model certificates across floating-point platforms (issue 28) ----------------------
#: the level c of a model's certified region of attraction ``{V <= c}`` (``roa``, after its V steps):
#: each V step builds V with the level-1 condition feasible, and the last level step bisects on the
#: solver's feasibility up to a relative width of 1e-3 (lyapcheck.models.classes.regions.LEVEL_REL_TOL), so
#: c is within that width of the largest level the solver finds feasible, 1 or just above; which
#: side of a bisection step a solve falls on follows the platform's last bits, and so does V itself.
#: Measured at the reversed Van der Pol (mu = 1) on five x86-64 platforms (numpy's AVX-512, AVX2 or
#: SSE loops with OpenBLAS's SkylakeX, Haswell or Nehalem kernel): 0.999656 to 1.000008, 3.5e-4
#: apart. Not for a level certified straight from the quadratic start (any level there)
FIGURE_MODEL_ROA_LEVEL_RTOL: Final = 1e-3


# -- the cross-check of a certified region against its own simulation (issue 40) -----------------
#: the small ball of the conclusive cross-check (lyapcheck.models.engines.numeric.check_certified_set): a
#: start of a certified set whose trajectory stays in the set, outside this ball (radius in the
#: certificate's squared distance q, the recast classes' state_square), for longer than the
#: certificate's own decrease V' <= -epsilon q / D allows, contradicts the proof; the same radius
#: as the recast cross-check's convergence (lyapcheck.models.classes.recast_regions.CONVERGED_RADIUS)
CONVERGED_BALL_RADIUS: Final = 2e-2


# -- work budgets that decide outcomes (issue 40: the same outcome under load) ----------------------
#: the cells one proof attempt of a ball-arithmetic region may examine (boundary and decrease
#: together, every part of a parameter box together; lyapcheck.models.classes.recast_interval) before it
#: gives up at that level: a count, so that a model gets the same region on any machine and under
#: any load (it replaced a 25 s wall-clock limit per attempt, which a loaded 2-core machine hit on
#: the three-state recast-pendulum-actuator). Calibrated on the shipped examples: the largest proof
#: that passes, recast-pendulum-actuator's at level 0.98, takes 65,193 cells (about 26 s of one
#: core of the 2-core CI machine); the two-state examples take at most a few thousand
INTERVAL_ATTEMPT_CELLS: Final = 100_000
#: the cells one attempt of the ball-arithmetic level search of a quadratic V may examine
#: (lyapcheck.models.classes.recast_ball_level; its faces are proved exactly, so these are the decrease's
#: cells outside the local box; from 4 states the cells of the ellipsoid's own coordinates,
#: lyapcheck.models.engines.ellipsoid_cells): a count, so that the level is the same on any machine. A
#: cell costs about a millisecond of one core at 4 to 6 states (a Hessian enclosure or a Taylor form at
#: its centre), half that at 1 to 3 (issue 42 raised it from 8,000: the 4-state cart-pole's LQR
#: cost-to-go needs about 20,000 to 27,000 cells at the levels 0.02 to 0.3)
BALL_LEVEL_CELLS: Final = 30_000
#: the cells of the whole ball-arithmetic level search of a quadratic V (every attempt together): the
#: largest level proved when they are spent is the answer; the whole search stays within about 40 s of
#: one core, inside MODEL_CLASS_TIME_LIMIT_S (issue 42 raised it from 20,000)
BALL_LEVEL_TOTAL_CELLS: Final = 40_000
#: the same from 4 states (lyapcheck.models.classes.recast_ball_level.ELLIPSOID_JUMP_STATES), in cells of the
#: 4-state cart-pole's cost: the search there tries the sampled level, its double and bisections, and an
#: attempt at a level too large now ends within a few thousand cells (the shell takes its innermost and
#: outermost cells by turns), so the cart-pole's roa proves its third level, 0.0789 (22,948 cells; issue 42,
#: 2026-11-30: 40,000 -> 48,000; its search's 42,855 cells about 35 s of one core, its whole certify run
#: 29 to 46 s on the loaded 2-core machine)
ELLIPSOID_LEVEL_TOTAL_CELLS: Final = 48_000
#: the cells of the first attempt of that search, at the sampled level (in the same cells of the cart-pole's
#: cost): that level only proposes, and where it is too large for the cells (the acrobot's and the pendubot's
#: shaped V, issue 42: their attempts fail by the cells, not by a point where V' >= 0) a failure there cost a
#: whole BALL_LEVEL_CELLS attempt, about 60 % of the search, before the growth from the local level began.
#: The cart-pole's sampled levels take 8,190 cells (its shaped V, 0.344) and 20,484 (its LQR cost-to-go as a
#: candidate, 0.207; 2026-11-30): 10,000 cost the candidate that level (0.414 -> 0.0397), so about 10 % above
#: the larger. It then saves the pendubot a quarter of an attempt, enough for one more level; not the acrobot
ELLIPSOID_JUMP_CELLS: Final = 22_500
#: the most slabs of t in [0, 1] over which the factored cell test of the ellipsoid cells
#: (lyapcheck.models.engines.ellipsoid_cells, V' = z^T (Abar^T P + P Abar) z with Abar(z) = int_0^1 J(t z) dt)
#: encloses the Jacobian: a cell far from the equilibrium takes about its distance over its width, a power
#: of 2 up to this (more slabs: a tighter Abar for a field evaluation more each). Soundness never depends on it
FACTORED_MAX_SLABS: Final = 16
#: the share of the level below which (the cell's upper bound of V) a shell cell whose Taylor form fails tries
#: the factored test: it passes mostly there, where V' ~ |z|^2 is small for a Taylor form (cart-pole, acrobot:
#: about 10 % of the tries pass above 0.9 of the level, where most cells are, so trying there cost a failing
#: level 50 % more time). A choice of work, never of soundness
FACTORED_REACH: Final = 0.5
#: the polynomial model of V' in the ellipsoid's coordinates (lyapcheck.models.engines.polynomial_cells): the
#: total degree kept (the terms above it join its error bound), the Taylor degrees of sin (odd) and of
#: cos - 1 (even) whose remainders join it too, and the most coefficients of its dense tensor, (degree + 1)^n
#: (a cell costs 2n contractions of it: 15^4 = 50,625 at 4 states takes a few milliseconds)
POLY_CELL_DEGREE: Final = 14
POLY_CELL_SIN_DEGREE: Final = 9
POLY_CELL_COS_DEGREE: Final = 10
POLY_CELL_MAX_ENTRIES: Final = 60_000
#: the condition number of V's matrix P from which the ellipsoid cells try the polynomial model first: there
#: ball enclosures over the tilted cells are hundreds of times too wide (the acrobot's shaped P, 48,000; the
#: pendubot's, 8,000), below it the ball tests alone cost less (the cart-pole's shaped P, 584: 16,078 cells
#: in 9.3 s at level 0.6, against 11,926 in 16.2 s with the model first). A choice of work only
POLY_CELL_MIN_CONDITION: Final = 2_000.0
#: significant bits of each entry of V's matrix P on a discrete-time map with functions
#: (lyapcheck.models.classes.discrete_functions: the Stein solution of A^T P A - P = -I rounded to a
#: short dyadic). Short entries keep V's balls exact at a cell's dyadic corners (no widening from V
#: itself), while 30 bits move P by about 2^-30 relative, far inside the margin -I. Soundness never
#: depends on it: whatever P is, V(F(e)) < V(e) is proved cell by cell
P_BITS: Final = 30
#: that class's level search: levels tried upwards from the first proved one, each MAP_LEVEL_GROWTH
#: times the last, at most MAP_LEVEL_GROWTH_STEPS of them (4^16, about 4e9: from the smallest
#: ellipsoid tried to any region a map plausibly has), then MAP_LEVEL_BISECTIONS bisections of the
#: last bracket (the level to a sixteenth of it: a figure, and each bisection is a whole cell proof).
#: Resolution and time only: every level reported is proved, and BALL_LEVEL_TOTAL_CELLS bounds the cells
MAP_LEVEL_GROWTH: Final = Fraction(4)
MAP_LEVEL_GROWTH_STEPS: Final = 16
MAP_LEVEL_BISECTIONS: Final = 4
#: the parts of a box a map with functions' linearization over the box may examine
#: (lyapcheck.models.classes.discrete_functions_box: one P with A(p)^T P A(p) - P < 0 proved in ball arithmetic
#: on each part, a part not proved halved at its widest parameter). A count, so the answer is the same on any
#: machine; a part costs one jet evaluation of the map (milliseconds). Resolution only: every part counted as
#: proved is proved, and a box reaching an unstable value is never proved however many parts it is cut in
MAP_BOX_PIECES: Final = 256
#: values per parameter of the grid whose Jacobians the SDP proposing a P common to a map's box must serve
#: (lyapcheck.models.classes.discrete_functions_box.common_p; ends included): a proposal only, decided over
#: the whole box in ball arithmetic
MAP_BOX_GRID: Final = 5
#: the integrator steps one trajectory of the ball-arithmetic route's fit of V (and of its simulated check) may take when the
#: route runs after the SOS route on a polynomial or rational loop (lyapcheck.models.surfaces.ball_roa):
#: a rational loop's trajectory that runs into a pole crawls towards it step by step (1-state
#: x' = -x + x**2/(3 - x): 14,000 steps, 50 s, for a fit that nothing trusts). The fit only proposes a
#: V, so a row stopped by this budget just does not count as converging; smooth two- and three-state
#: loops need a few hundred steps over the fit's 30 s horizon. Loops with functions keep
#: SIM_MAX_STEPS (their shipped figures were fitted with it)
BALL_FALLBACK_FIT_STEPS: Final = 2_000
#: the seconds of roa's class budget that must be left after the SOS route certified a set on a polynomial
#: or rational loop of 1 to 3 states for the ball-arithmetic route to be tried beside it
#: (lyapcheck.models.classes.field_ball_route.larger_region); with less, the SOS set stands and its
#: ``tried`` says so. The ball route's own work is bounded by counts (INTERVAL_ATTEMPT_CELLS); this only
#: keeps it from starting where the class's time limit (its safety net) would cut it
BALL_ROUTE_MIN_SECONDS: Final = 15.0
#: the ball-arithmetic roa route runs beside a certified SOS set of a polynomial loop only where that set
#: covers less than this share of the simulated region of attraction in the [domain] (measured: on every
#: shipped polynomial example of 1 to 3 states the SOS set covers 0.977 to 1.0 and the ball route, 3 to 17 s
#: more per run, never covered more; on a loop whose SOS set covered 0.64 the ball route's covered 0.985)
BALL_ROUTE_BESIDE_SHARE: Final = 0.95
#: the solves one template of the recast sos_gas / quadratic search (a degree and a set of V
#: variables: its margins eps and its face reductions together; lyapcheck.models.classes.recast_classes)
#: may spend before the next template has its turn. It replaced a 10 s wall-clock limit per
#: template and margin. Calibrated on the shipped examples and tests: a certified template takes at
#: most 3 solves (recast-ilos-course over the box U in [0.5, 2]: two face reductions), most take
#: 1; a template whose points the exact check keeps refusing stops at one margin's face reductions
#: (FACE_ROUNDS + 1 = 4) instead of up to 8
TEMPLATE_SOLVES: Final = 4
#: the most rows of one sum-of-squares matrix of a recast sos_gas template's program (the search
#: skips a larger template as too large; lyapcheck.models.engines.recast_sos.MAX_RECAST_GRAM_ROWS, 60, is
#: every recast program's own limit). A count of the work of one solve (an interior-point
#: iteration costs about the cube of the rows), which replaced the 10 s wall-clock limit per
#: template that cut these solves short. Calibrated on the shipped examples: their templates'
#: programs have at most 27 rows (solved in under a second) or 50-55 rows (10-30 s a solve,
#: none certified: recast-inverted-pendulum-sat, recast-los-heading at degree 4)
TEMPLATE_GRAM_ROWS: Final = 40
#: the most variables (states and auxiliaries) of a discrete-time map with functions whose quadratic and
#: sos_gas derive the recasting's relations (lyapcheck.models.classes.map_relations): a larger map is refused
#: as too large before any relation is derived. A count, measured: ysa-pendulum's 68 variables (2 x 32 tanh
#: neurons, sin, cos) take over a minute to shift their 261 relations to the deviations and then stop at
#: TARGET_LIMIT (1753 monomials in the degree-2 identity); discrete-tanh-map's 3 take under a second
MAP_RELATIONS_VARIABLES: Final = 24
#: the solves one level step of the recast V-s iteration (lyapcheck.models.classes.regions.relations_enlarge: a
#: level's growth and bisection, each level its face reductions) may spend; it replaced a 15 s
#: wall-clock limit. Calibrated on the tests' pendulum (the route without ball arithmetic): its
#: level steps take 12 to 15 solves
VS_LEVEL_SOLVES: Final = 40
#: the solves of the whole V-s iteration (its V steps, one solve each, which replaced an 8 s
#: wall-clock limit per V step, and its level steps); it replaced "stop when less than 35 % of the
#: class's time is left". Calibrated on the same pendulum: 88 solves in all (4-8 s of one core)
VS_SOLVES: Final = 150
#: the solves of the shaped quadratic V's level search on the recasting's relations at 4 to 6 states
#: (lyapcheck.models.classes.recast_regions.shaped_relations: its denominators, positivity, and each level
#: with its face reductions; issue 42). A count, so that a loaded machine gets the same level. The planar
#: quadrotor's search from half the sampled critical level takes about 12 (measured 2026-11-30)
SHAPED_RELATIONS_SOLVES: Final = 30
#: the solves of the enlarging rounds of the polynomial roa class (its V steps and their level-1
#: multipliers; lyapcheck.models.classes.regions.enlarge; the exact check of the best set and its ball
#: come after, not counted); it replaced "stop when less than 35 % of the class's time is left".
#: Calibrated on the shipped examples and tests: van-der-pol-reversed's rounds take 114 solves,
#: van-der-pol-reversed-mu3's 62, the tests' models at most 114 (the ladder's own end, 30 rounds
#: of 2 solves at each of 3 degrees, is 180)
ROA_ENLARGE_SOLVES: Final = 150
#: the largest decimal exponent a number read from a document may carry (lyapcheck.exact.read_rational):
#: "1e999999999" is a short text whose exact value has a billion digits, minutes and gigabytes to
#: build, so a forged certificate could stall verify. A float's exponent is at most 308 and every
#: rational lyapcheck writes is "p" or "p/q" (no exponent); 1000 leaves room for hand-written values
MAX_READ_EXPONENT: Final = 1000
#: relative room of the first guess of ``mu`` above the floating-point largest eigenvalue of a
#: region's quadratic part (lyapcheck.models.classes.region_size: its largest ball), widened a
#: thousandfold per try until ``mu I - P`` is proved positive semidefinite exactly. Speed only: the
#: check is exact, and Gershgorin's bound ends the tries
SIZE_MU_ROOM: Final = 1e-9
#: the margins eps of the piecewise-linear local proof (lyapcheck.models.classes.piecewise_linearization:
#: the form 2 e'P(A e + B phi) + eps |e|^2, or its map's step form, <= 0 on the kinks' set), tried in turn; P
#: is normalized by P >= I, so eps is relative to P's smallest eigenvalue
PIECEWISE_EPSILONS: Final = (Fraction(1, 100), Fraction(1, 10000))
#: the room the solver is asked to leave (the S-procedure matrix <= -PIECEWISE_ROOM I), so that the rounded
#: P, lambda, nu still pass the exact check; speed only: a rounding that fails is refused exactly
PIECEWISE_ROOM: Final = 1e-6
#: the most nonnegative linear forms (three per abs kink, two per saturation corner) whose products of
#: every pair enter the S-procedure; with more, only the products within one kink (the LMI's multipliers
#: grow with the square of the forms: 8 ReLU neurons' 24 forms give 276 products)
PIECEWISE_PAIR_FORMS: Final = 30
#: the most kinks at the equilibrium the piecewise-linear route builds its LMI for: with more it says
#: not_certified, naming this limit, before building anything. A count (its LMI is (n + kinks) square, with
#: three multipliers per kink, and the exact check of its rounded solution grows with the cube of that
#: size), so that a loaded machine refuses the same loops. Calibrated on the ysa pendulum's 2 x 32 network
#: with ReLU activations (benchmarks/bench_piecewise.py --widths 16,12,8 --discrete): all 64 kinks took 28 s
#: (two infeasible solves of about 11 s) before this limit and are refused in 0.5 s with it; cut to 2 x 16
#: (32 kinks) 3.0 s (map 1.7 s), 2 x 12 0.6 s, 2 x 8 0.2 s, each not_certified (those loops are unstable)
PIECEWISE_MAX_KINKS: Final = 32
#: significant bits P, lambda and nu are rounded to before the exact check
PIECEWISE_BITS: Final = 24

#: a sampled-data loop's roa (lyapcheck.models.classes.sampled_regions): the working precision of its ball
#: arithmetic, in bits, and the most a certificate may ask verify to use. Resolution only: every bound is an
#: enclosure at any precision; 128 bits keep the rounding far below the figures' own slack
SAMPLED_REGION_BITS: Final = 128
SAMPLED_REGION_MAX_BITS: Final = 1024
#: the a priori box of the flow over one period: first |e_i| <= START r, then, while the Gronwall excursion
#: Ce r does not fit in it, GROWTH times that excursion, at most TRIES boxes. Time only: a box is accepted
#: only when the excursion proved on it lies strictly inside it
SAMPLED_APRIORI_START: Final = Fraction(3, 2)
SAMPLED_APRIORI_GROWTH: Final = 1.25
SAMPLED_APRIORI_TRIES: Final = 8
#: the shares of a floating-point least eigenvalue tried as its proved lower bound (largest first)
SAMPLED_EIGEN_SHARES: Final = (0.999, 0.99, 0.9, 0.5, 0.1)
#: the radius search: from START (in the states' SI units), doubled at most DOUBLINGS times while it
#: passes (halved as often while it does not), then BISECTIONS bisections; each try is a few jet evaluations
#: over one box (milliseconds). Resolution only: the radius reported is the one proved
SAMPLED_RADIUS_START: Final = Fraction(1, 64)
SAMPLED_RADIUS_DOUBLINGS: Final = 14
SAMPLED_RADIUS_BISECTIONS: Final = 10
#: the significant bits a sampled-data roa's flow figures are rounded up to (upper bounds stay upper bounds)
SAMPLED_FIGURE_BITS: Final = 32
#: passes of a sampled-data roa's excursion bound by the variation of constants after Gronwall's (each one
#: tightens the Hessian's weight and then the bound itself; a pass that does not lower it ends them)
SAMPLED_EXCURSION_PASSES: Final = 3
#: a sampled-data roa's bootstrap box: the excursion factor proved, times this, is the candidate C, and the
#: box's half-width is C r times it again (strictly outside the ball C r). Resolution only: the bootstrap is
#: taken only when the bound it proves is below C
SAMPLED_BOOTSTRAP_SLACK: Final = 1.05

#: validated integration of boxes into a certified region of attraction (lyapcheck.models.classes.flow_region):
#: the step is the largest power of 2 at most FLOW_STEP_SCALE / |Df(x_eq)|_inf (a dyadic step keeps every
#: time exact); each box is integrated for at most FLOW_HORIZON time units; the domain is first cut into
#: FLOW_INITIAL_CUTS parts per state (by the number of states), a box that does not enter the set is halved
#: along its widest state down to FLOW_MIN_WIDTH_FRACTION of the domain's width; all boxes together take at
#: most FLOW_STEP_BUDGET steps (a count, not a time, so the same model gives the same boxes on any machine;
#: 0.3 to 0.7 ms a step for 2 states on one core: 12,000 steps take 4 to 9 s, which a roa that took 8 s before
#: adds, within MODEL_CLASS_TIME_LIMIT_S with the set's own proof)
FLOW_STEP_SCALE: Final = Fraction(1, 4)
FLOW_HORIZON: Final = Fraction(12)
FLOW_INITIAL_CUTS: Final = {2: 16, 3: 6, 4: 4}  # (by the number of states)
FLOW_MIN_WIDTH_FRACTION: Final = Fraction(1, 64)
FLOW_STEP_BUDGET: Final = 12_000
#: the working precision (bits) of the validated integration
FLOW_PRECISION_BITS: Final = 53
#: a box whose floating-point corners enter the set by step k is integrated for at most
#: FLOW_ESTIMATE_MARGIN * k + FLOW_ESTIMATE_SLACK validated steps; one whose enclosure grows past FLOW_GROWTH times its
#: own half-width is given up (halved) at once
FLOW_ESTIMATE_MARGIN: Final = Fraction(3, 2)
FLOW_ESTIMATE_SLACK: Final = 64
FLOW_GROWTH: Final = 16.0
#: a box's set is cut in two in flight where its box of coordinates has doubled since it was made (the wrapping of a
#: set crossing a kink of sat or abs grows with its width), into at most FLOW_MAX_PIECES pieces; the certificate states
#: each box's count, which verify uses
FLOW_MAX_PIECES: Final = 16
#: the validated integrator's a priori enclosures (lyapcheck.models.engines.validated_flow): Picard checks tried before
#: a step is given up, the widening of each trial about its centre, and an absolute floor of that widening
#: (relative to the value's size: a trial of radius 0 can never hold its own image)
FLOW_APRIORI_ITERATIONS: Final = 6
FLOW_APRIORI_INFLATION: Final = 1.5
FLOW_APRIORI_FLOOR: Final = 1e-12
#: a piece of a box's set is cut in two once its coordinates' box has grown this many times since it was made
FLOW_SPLIT_GROWTH: Final = 2.0
#: the floating-point simulation that picks the boxes worth integrating takes this many validated steps at once
FLOW_SIMULATION_STRIDE: Final = 4
#: a simulated start of a flow box that did not converge is simulated up to its box's stated time and must then
#: have V <= level (1 + this): the float simulation's error is far below it, a forged or false time far above
FLOW_CHECK_MARGIN: Final = 1e-6
