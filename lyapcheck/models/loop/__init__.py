"""The closed loop as the classes see it: its exact field, scaled over a box of parameters, with
every denominator proved positive.

- :mod:`~lyapcheck.models.loop.field`: the field of a polynomial or rational model, shifted to its
  equilibrium and scaled;
- :mod:`~lyapcheck.models.loop.boxes`: ``--box``: one field for every parameter value in a box;
- :mod:`~lyapcheck.models.loop.positivity`: denominators proved positive, exactly;
- :mod:`~lyapcheck.models.loop.discrete`: a discrete-time map (``[model] time = "discrete"``): the shifted
  map and the one guard that keeps a map from every class and surface that reads it as a field.

May import: lyapcheck.models.language, lyapcheck.models.engines, lyapcheck.sos, lyapcheck.exact,
lyapcheck.units, lyapcheck.errors
"""
