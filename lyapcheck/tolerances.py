"""Named numerical tolerances, in one place.

Exact checks use no tolerance at all: they are done in rational arithmetic. The numbers
here only steer the *search* (solver accuracy, line searches) and the comparison of
floating-point simulations; none of them can turn a failed exact check into a pass.
"""

from __future__ import annotations

from typing import Final

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


# -- simulation cross-checks of model certificates (lyapcheck.models.crosscheck) -------------------
#: a simulated trajectory breaks a model certificate's claim (V rises along it, V or |x| leaves its
#: certified envelope) only beyond this relative slack: the trajectories are integrated at rtol 1e-7
#: (lyapcheck.models.trajectories.RTOL) and V is a polynomial of the state, so its float value along
#: a trajectory is good to about its degree times that; 1e-5 leaves a decade over a degree-8 V and
#: stays far below any modelling error a false certificate would show (moved from the report's
#: reports.model_figures.CHECK_TOL, now shared with the sweeps of model files)
TRAJECTORY_CHECK_REL_TOL: Final = 1e-5
