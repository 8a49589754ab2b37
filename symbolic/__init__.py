"""Symbolic derivations of the paper's equations, and the claims ledger.

This package imports none of the toolkit's other packages (see DESIGN.md, layering). It
derives each checkable equation from the model of Section 2 and the guidance law, encodes
the equation as printed, and compares the two (:mod:`symbolic.ledger`). The structured
closed loop consumed by the certificate code lives in :mod:`symbolic.closed_loop`.
"""
