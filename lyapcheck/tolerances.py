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





#: Simulator accuracy contract (relative to the state scale), tested against solve_ivp.
SIM_REL_TOL: Final = 1e-6
