"""A denominator's positivity over a box of parameters (``lyapcheck.models.loop.positivity``).

Found on ``paper-error-dynamics.toml --box k_d=0.1..0.2``: the denominator
``(eps + s/100)^2 + 9/16e6`` does not involve ``k_d``, yet "could not be proved of one sign" over the
box, so every Lyapunov class was ``not_applicable``. A parameter the polynomial does not depend on
gets no box multiplier now.
"""

from __future__ import annotations

from fractions import Fraction

from lyapcheck.models.engines.search import Budget
from lyapcheck.models.loop.positivity import check_certificate, prove_positive
from lyapcheck.sos.polynomials import Ring


def _budget() -> Budget:
    return Budget(60.0, "lyapcheck.tolerances.MODEL_CLASS_TIME_LIMIT_S")


def test_positive_without_the_box_parameter() -> None:
    ring = Ring(("eps", "s", "d", "u"))
    eps, s = ring.gen("eps"), ring.gen("s")
    p = eps**2 + eps * s / 50 + s**2 / 10000 + ring.constant(Fraction(9, 16000000))
    cert = prove_positive(ring, p, _budget(), free=3)
    assert cert is not None and cert["kind"] == "sos"
    assert "box_multipliers" not in cert
    assert check_certificate(ring, p, cert, free=3)[0]
    # the same certificate does not prove a polynomial that is negative somewhere
    assert not check_certificate(ring, p - ring.constant(Fraction(1, 1000)), cert, free=3)[0]


def test_box_parameter_that_occurs_keeps_its_multiplier() -> None:
    ring = Ring(("x", "u"))
    x, u = ring.gens()
    positive = x**2 + u + ring.constant(2)  # >= 1 for u in [-1, 1]
    cert = prove_positive(ring, positive, _budget(), free=1)
    assert cert is not None and check_certificate(ring, positive, cert, free=1)[0]
    assert [m["variable"] for m in cert.get("box_multipliers", [])] == [1]
    # negative at u = -1: no certificate
    assert prove_positive(ring, x**2 + u + ring.constant(Fraction(1, 2)), _budget(), free=1) is None
