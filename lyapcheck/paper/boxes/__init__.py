"""The paper's condition classes for every gain set of a box (``certify --box``, box sweeps).

- :mod:`~lyapcheck.paper.boxes.box`: the box, its corners and the ``(c, a, b)`` hull;
- one module per class: :mod:`~lyapcheck.paper.boxes.prop41`, :mod:`~lyapcheck.paper.boxes.quadratic`
  (``sector_ges`` and ``ges``), :mod:`~lyapcheck.paper.boxes.ultimate`,
  :mod:`~lyapcheck.paper.boxes.sos_gas`, :mod:`~lyapcheck.paper.boxes.saturated`,
  :mod:`~lyapcheck.paper.boxes.bounds` (``sos_bound``);
- :mod:`~lyapcheck.paper.boxes.classes`: the dispatch over them, and :func:`refine`;
- :mod:`~lyapcheck.paper.boxes.cross_check`: simulation of a certified box against its envelope.
"""
