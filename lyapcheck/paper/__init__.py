"""The paper's closed loop (ILOS guidance with the ODS controller, ``../shared/paper``).

- :mod:`lyapcheck.paper.conditions`: its condition classes at one gain set (``prop41_*``,
  ``stabcond2``, ``sector_ges``, ``switched_ges``, ``ultimate_bound``, ``sos_gas``, ``ges``,
  ``saturated_loop``, ``sos_bound``), each built for the structure of its error dynamics;
- :mod:`lyapcheck.paper.boxes`: the same classes over a box of gains;
- :mod:`lyapcheck.paper.claims`: the sentence (``summary``) of every decided result of both, made
  from its exact data alone; ``verify`` regenerates it and the report prints it;
- :mod:`lyapcheck.paper.simulation`: the closed loop of Section 5 simulated (scenarios, figures).

Any other closed loop comes from a model file and is handled by :mod:`lyapcheck.models`; the SOS
engine both use lives in :mod:`lyapcheck.sos`.
"""
