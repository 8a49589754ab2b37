"""Closed-loop simulation of the saturated ILOS/ODS microswimmer (Section 5 of the paper).

Modules (one concern each; nothing is imported here, so ``lyapcheck --help`` stays light):

* :mod:`~lyapcheck.simulation.integrator` -- batched adaptive Dormand-Prince 5(4), a step per
  trajectory, kinks located through switching functions, time breakpoints;
* :mod:`~lyapcheck.simulation.model` -- the closed loop (eq:eq_dyn, eq:los2, eq:solFinal) as a
  batched ODE system, and the idealised error dynamics (eq:xCrossdyn);
* :mod:`~lyapcheck.simulation.disturbances` -- constant, weight through D (eq:tmp3), sinusoid,
  random piecewise constant, adversarial for a given V = x^T P x;
* :mod:`~lyapcheck.simulation.metrics` -- quantities accumulated on the fly, recorder for plots;
* :mod:`~lyapcheck.simulation.runner` -- :func:`~lyapcheck.simulation.runner.simulate`, one call
  for a whole batch;
* :mod:`~lyapcheck.simulation.scenarios` -- the Section 5 presets and scenario TOML files;
* :mod:`~lyapcheck.simulation.inference` -- the disturbance inferred from the paper's numbers;
* :mod:`~lyapcheck.simulation.plots` -- the Section 5 figures;
* :mod:`~lyapcheck.simulation.scenario_run` -- run scenarios, the ``simulate`` JSON document.

See ``docs/simulation.md``.
"""
