"""The condition classes of a model file: each one's search, its exact check and its sentence.

- :mod:`~lyapcheck.models.classes.registry`: the one list of classes, what each proves and what a
  sweep stores, each one's entries (:mod:`~lyapcheck.models.classes.runs`: its search on each kind of loop;
  :mod:`~lyapcheck.models.classes.verify_field` and :mod:`~lyapcheck.models.classes.verify_functions`: its
  exact check; :mod:`~lyapcheck.models.classes.runs_discrete` and
  :mod:`~lyapcheck.models.classes.verify_discrete`: the same on maps and sampled-data loops), given one
  :mod:`~lyapcheck.models.classes.contexts` object;
- discrete-time maps: :mod:`~lyapcheck.models.classes.discrete_linearization` (the spectral radius of the
  map's Jacobian, exact);
- polynomial and rational loops: :mod:`~lyapcheck.models.classes.linearization`,
  :mod:`~lyapcheck.models.classes.lyapunov` (quadratic, sos_gas, candidate),
  :mod:`~lyapcheck.models.classes.regions` (roa and candidate's sublevel sets by SOS, on loops with functions
  too), :mod:`~lyapcheck.models.classes.field_regions` (roa and candidate on the cleared field), :mod:`~lyapcheck.models.classes.bounds`
  (sos_bound, on loops with functions too), :mod:`~lyapcheck.models.classes.barrier` (on loops with
  functions too), :mod:`~lyapcheck.models.classes.reach_avoid` (on loops with functions too);
- discrete-time maps ``e+ = F(e)``: :mod:`~lyapcheck.models.classes.discrete_lyapunov` (quadratic and sos_gas);
- loops with functions: :mod:`~lyapcheck.models.classes.recast_classes`,
  :mod:`~lyapcheck.models.classes.piecewise_linearization` (``linearization`` where abs, a ReLU or sat sits at its
  kink at the equilibrium, on maps with functions too),
  :mod:`~lyapcheck.models.classes.recast_regions` (roa and candidate, and the loop a class runs on),
  :mod:`~lyapcheck.models.classes.recast_interval` and :mod:`~lyapcheck.models.classes.fitted_v`
  (the ball-arithmetic region), :mod:`~lyapcheck.models.classes.recast_ball_level` (a quadratic V's
  largest level by ball arithmetic, from its exact local level, at any number of states),
  :mod:`~lyapcheck.models.classes.shaped_quadratic` (a quadratic V shaped for a large region at 4 to 6
  states: a floating-point proposal that route proves),
  :mod:`~lyapcheck.models.classes.flow_region` (that region enlarged by boxes proved, by validated
  integration, to flow into it);
- :mod:`~lyapcheck.models.classes.sampled` (a sampled-data loop's linearization over one period, in ball arithmetic);
- :mod:`~lyapcheck.models.classes.region_driver` (the one driver of ``roa`` and ``candidate`` on continuous
  loops: their routes in order, the result kept, the reasons stated, the kept set simulated once);
- :mod:`~lyapcheck.models.classes.level_search` (the one monotone search of a fixed V's largest proved level);
- :mod:`~lyapcheck.models.classes.region_size` (a certified region's largest ball and reach along each axis, exact);
- :mod:`~lyapcheck.models.classes.falsify` (counterexamples to safety) and
  :mod:`~lyapcheck.models.classes.claims` (the sentence of each decided class, on every loop kind).

May import: lyapcheck.models.language, lyapcheck.models.engines, lyapcheck.models.loop, lyapcheck.sos,
lyapcheck.integrator, lyapcheck.results, lyapcheck.degrees, lyapcheck.exact, lyapcheck.roots, lyapcheck.timing,
lyapcheck.tolerances, lyapcheck.units, lyapcheck.errors
"""
