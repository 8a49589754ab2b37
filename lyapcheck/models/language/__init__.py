"""The model file and its language: what a user writes, parsed and checked, never run.

- :mod:`~lyapcheck.models.language.expressions`: the expression language (a whitelist over ``ast``);
- :mod:`~lyapcheck.models.language.recast`: functions (sin, cos, sqrt, sat, ...) recast into
  auxiliary states with exact polynomial relations;
- :mod:`~lyapcheck.models.language.sets`: ``[sets]`` (initial, unsafe, goal);
- :mod:`~lyapcheck.models.language.dimensions`: ``[units]`` and the dimension check of every expression;
- :mod:`~lyapcheck.models.language.networks`: ``[networks.NAME]``, feedforward networks read from ``.npz``
  or ONNX files and lowered into the language's functions;
- :mod:`~lyapcheck.models.language.parameter_box`: a box of parameters (pure data);
- :mod:`~lyapcheck.models.language.modelfile`: model files, validated (DESIGN.md, "Model files");
- :mod:`~lyapcheck.models.language.build`: the same model built from Python (sympy, python-control).

May import: lyapcheck.errors, lyapcheck.units, lyapcheck.sos.polynomials
"""
