"""Any polynomial or rational closed loop, or one with functions, from a model file: the generic
condition classes and everything they stand on. Nothing here imports :mod:`lyapcheck.paper`.

Sub-packages, bottom to top (each may import only those below it, as its docstring lists):

1. :mod:`~lyapcheck.models.language`: the model file and its expression language;
2. :mod:`~lyapcheck.models.engines`: SOS programs, ball arithmetic, simulation;
3. :mod:`~lyapcheck.models.loop`: the exact field of the loop, over a box of parameters;
4. :mod:`~lyapcheck.models.classes`: the condition classes;
5. :mod:`~lyapcheck.models.surfaces`: certify, certificates and verify, simulate.
"""
