"""What a user calls: certify a model, write and verify its certificate, simulate it.

- :mod:`~lyapcheck.models.surfaces.certify`: ``certify_model``, the one entry for every loop kind (its class
  selection, its sentences and coverage) and the one runner of the classes (each by its entry in
  :mod:`lyapcheck.models.classes.registry`); :mod:`~lyapcheck.models.surfaces.ball_roa`,
  the ball-arithmetic region on a polynomial or rational loop;
- :mod:`~lyapcheck.models.surfaces.certificate`: the one certificate document and ``verify`` entry (it reads
  the model again and makes the rows every document starts with); :mod:`~lyapcheck.models.surfaces.verify`:
  the rest of ``verify``, one flow for every kind of loop (each class's exact check by its registry entry,
  :func:`lyapcheck.models.classes.registry.verify`); :mod:`~lyapcheck.models.surfaces.documents`,
  :mod:`~lyapcheck.models.surfaces.stated`, :mod:`~lyapcheck.models.surfaces.counterexamples`: what both share;
- :mod:`~lyapcheck.models.surfaces.simulate`: ``simulate --model``, one implementation for every loop kind;
  :mod:`~lyapcheck.models.surfaces.iterate`: a discrete-time map iterated instead;
  :mod:`~lyapcheck.models.surfaces.plotting`: the frame every ``--plot`` figure shares.

May import: lyapcheck.models.language, lyapcheck.models.engines, lyapcheck.models.loop,
lyapcheck.models.classes, lyapcheck.sos, lyapcheck.integrator, lyapcheck.answers, lyapcheck.results,
lyapcheck.degrees, lyapcheck.exact, lyapcheck.numerics, lyapcheck.timing, lyapcheck.tolerances,
lyapcheck.units, lyapcheck.errors, lyapcheck.fileio
"""
