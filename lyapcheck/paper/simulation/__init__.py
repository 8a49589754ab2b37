"""Closed-loop simulation of the saturated ILOS/ODS microswimmer (Section 5 of the paper).

Modules (one concern each; nothing is imported here, so ``lyapcheck --help`` stays light):

* :mod:`~lyapcheck.paper.simulation.model` -- the closed loop (eq:eq_dyn, eq:los2, eq:solFinal) as a
  batched ODE system, and the idealised error dynamics (eq:xCrossdyn);
* :mod:`~lyapcheck.paper.simulation.disturbances` -- constant, weight through D (eq:tmp3), sinusoid,
  random piecewise constant, adversarial for a given V = x^T P x;
* :mod:`~lyapcheck.paper.simulation.metrics` -- quantities accumulated on the fly, recorder for plots;
* :mod:`~lyapcheck.paper.simulation.runner` -- :func:`~lyapcheck.paper.simulation.runner.simulate`, one call
  for a whole batch;
* :mod:`~lyapcheck.paper.simulation.scenarios` -- the Section 5 presets and scenario TOML files;
* :mod:`~lyapcheck.paper.simulation.inference` -- the disturbance inferred from the paper's numbers;
* :mod:`~lyapcheck.paper.simulation.plots` -- the Section 5 figures;
* :mod:`~lyapcheck.paper.simulation.scenario_run` -- run scenarios, the ``simulate`` JSON document.

They integrate with the generic :mod:`lyapcheck.integrator` (batched adaptive Dormand-Prince
5(4)), which every model file's simulation uses too. See ``docs/simulation.md``.
"""
