"""Drake's region of attraction of a polynomial (Taylor) model, for ``benchmarks/bench_robot_roa.py``.

Runs in a Python that has ``pydrake`` (``pip install drake``: an optional extra of the benchmarks,
never of the tests), and needs nothing from lyapcheck. It reads one JSON object on stdin:

* ``states``: the state names;
* ``field``: per state, the polynomial right-hand side as ``[[coefficient, [exponents]], ...]``
  (floats; ``bench_robot_roa.py`` writes the cubic Taylor model of the true closed loop);
* ``S``: the matrix of the candidate ``V = z' S z`` (the LQR cost-to-go).

and prints ``{"level": rho, "seconds": t}``: Drake's ``RegionOfAttraction`` (its default SOS
program and solver, floating point) with ``lyapunov_candidate = z' S z`` returns ``V / rho``, whose
1-level set is its estimate; ``rho`` is read back as ``V(z) / (V / rho)(z)`` at a point.
``seconds`` is the call alone (the process's imports excluded).
"""

from __future__ import annotations

import json
import sys
import time

import numpy as np
from pydrake.symbolic import Expression, Variable  # type: ignore[import-not-found]
from pydrake.systems.analysis import RegionOfAttraction, RegionOfAttractionOptions  # type: ignore[import-not-found]
from pydrake.systems.primitives import SymbolicVectorSystem  # type: ignore[import-not-found]


def main() -> None:
    data = json.load(sys.stdin)
    x = [Variable(name) for name in data["states"]]
    field = []
    for terms in data["field"]:
        rhs = Expression(0)
        for coefficient, exponents in terms:
            monomial = Expression(float(coefficient))
            for xi, e in zip(x, exponents):
                monomial = monomial * xi ** int(e)
            rhs = rhs + monomial
        field.append(rhs)
    S = np.array(data["S"], dtype=float)
    V = sum(S[i, j] * x[i] * x[j] for i in range(len(x)) for j in range(len(x)))
    system = SymbolicVectorSystem(state=x, dynamics=field)
    context = system.CreateDefaultContext()
    context.SetContinuousState(np.zeros(len(x)))
    options = RegionOfAttractionOptions()
    options.lyapunov_candidate = V
    options.state_variables = np.array(x, dtype=object)
    start = time.perf_counter()
    scaled = RegionOfAttraction(system, context, options)
    seconds = time.perf_counter() - start
    point = {xi: 0.1 * (k + 1) for k, xi in enumerate(x)}
    level = V.Evaluate(point) / scaled.Evaluate(point)
    print(json.dumps({"level": float(level), "seconds": seconds}))


if __name__ == "__main__":
    main()
