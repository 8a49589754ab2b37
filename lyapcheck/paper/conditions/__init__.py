"""Certificate condition classes: each searches numerically, then decides exactly.

Statuses (DESIGN.md): ``certified`` (exact check passed), ``refuted`` (exactly proved that no
certificate of the class exists), ``not_certified`` (none found, nothing proved),
``inconclusive`` (numerical trouble or an exact check that failed), and for ``stabcond2``
``holds`` / ``fails``.
"""
