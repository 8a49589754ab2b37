"""The engines a class may use on any loop: SOS programs, ball arithmetic, simulation.

- SOS: :mod:`~lyapcheck.models.engines.search` (budgets, solver log, from coefficients to an exact
  point), :mod:`~lyapcheck.models.engines.recast_sos` (multipliers for the relations of a loop with
  functions), :mod:`~lyapcheck.models.engines.store` (what a search found, kept for the next run);
- ball arithmetic: :mod:`~lyapcheck.models.engines.interval_field` (the field over a box),
  :mod:`~lyapcheck.models.engines.interval_region` (V' < 0 proved cell by cell),
  :mod:`~lyapcheck.models.engines.validated_flow` (a box of starts carried along the true flow);
- floating point and simulation: :mod:`~lyapcheck.models.engines.numeric`,
  :mod:`~lyapcheck.models.engines.recast_numeric`, :mod:`~lyapcheck.models.engines.trajectories`,
  :mod:`~lyapcheck.models.engines.iteration` (a discrete-time map's iterates),
  :mod:`~lyapcheck.models.engines.series`, :mod:`~lyapcheck.models.engines.crosscheck`;
- :mod:`~lyapcheck.models.engines.reasons`: what a search tried and what to try next, in one sentence.

May import: lyapcheck.models.language, lyapcheck.sos, lyapcheck.integrator, lyapcheck.degrees,
lyapcheck.exact, lyapcheck.fileio, lyapcheck.tolerances, lyapcheck.errors
"""
