"""What a user calls: certify a model, write and verify its certificate, simulate it.

- :mod:`~lyapcheck.models.surfaces.certify` and :mod:`~lyapcheck.models.surfaces.recast_run` /
  :mod:`~lyapcheck.models.surfaces.recast_certify`: run the classes a model asks for;
- :mod:`~lyapcheck.models.surfaces.certificate`, :mod:`~lyapcheck.models.surfaces.documents`,
  :mod:`~lyapcheck.models.surfaces.stated`, :mod:`~lyapcheck.models.surfaces.counterexamples`: certificate
  documents and ``verify``;
- :mod:`~lyapcheck.models.surfaces.simulate`: ``simulate --model``, one implementation for every loop kind.

May import: lyapcheck.models.language, lyapcheck.models.engines, lyapcheck.models.loop,
lyapcheck.models.classes, lyapcheck.sos, lyapcheck.integrator, lyapcheck.answers, lyapcheck.results,
lyapcheck.degrees, lyapcheck.exact, lyapcheck.numerics, lyapcheck.timing, lyapcheck.tolerances,
lyapcheck.units, lyapcheck.errors
"""
