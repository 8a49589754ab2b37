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

#: Denominator bound used when rounding a floating-point certificate to rationals.
#: Rounding is followed by an exact check, so this only affects how often the check passes.
RATIONAL_MAX_DENOMINATOR: Final = 10**12

#: A candidate margin is shrunk by this factor before rounding, so that the rounded
#: certificate keeps strict inequalities with room to spare.
MARGIN_BACKOFF: Final = 0.5

#: Relative margins below this are reported as "numerically zero" (status inconclusive at
#: best); the exact check still decides any `certified`.
RELATIVE_MARGIN_FLOOR: Final = 1e-9

#: Second-opinion spot checks of symbolic identities: number of random rational points and
#: the relative threshold used when an expression has transcendental parts (evaluated with
#: 50 significant digits).
SPOT_CHECK_POINTS: Final = 5
SPOT_CHECK_DIGITS: Final = 50
SPOT_CHECK_REL_TOL: Final = 1e-30

#: Simulator accuracy contract (relative to the state scale), tested against solve_ivp.
SIM_REL_TOL: Final = 1e-6
