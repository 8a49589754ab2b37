"""Any polynomial or rational closed loop from a model file, with the generic condition classes.

- :mod:`~lyapcheck.models.expressions`: the expression language (a whitelist over ``ast``);
- :mod:`~lyapcheck.models.modelfile`: model files, validated (DESIGN.md, "Model files");
"""
