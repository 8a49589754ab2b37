"""Result type shared by all condition classes, and the system data they act on."""

from __future__ import annotations

from dataclasses import dataclass, field
from fractions import Fraction
from typing import Any, Literal

from lyapcheck.exact import Matrix

Status = Literal["certified", "refuted", "not_certified", "inconclusive", "holds", "fails", "not_applicable",
                 "counterexample"]
#: classes whose exact pass proves stability of the error dynamics (the verdict "certified")
STABILITY_CLASSES = ("prop41_ges", "prop41_iss", "sector_ges", "switched_ges", "sos_gas", "ges")

Property = Literal["GES", "GAS", "ISS", "ultimate_bound", "invariant_set"]
#: what a class proves when it is certified (DESIGN.md: every stability class states it, so that a
#: GAS certificate is never read as GES). ``stabcond2`` is arithmetic, not a certificate: absent.
PROPERTY: dict[str, Property] = {
    "prop41_ges": "GES", "prop41_iss": "ISS", "sector_ges": "GES", "switched_ges": "GES",
    "ultimate_bound": "ultimate_bound", "sos_gas": "GAS", "ges": "GES", "saturated_loop": "invariant_set",
    "sos_bound": "ultimate_bound",
}


@dataclass(frozen=True)
class System:
    """``x_dot = A x + rho(x) B x + E w``, ``rho in (0, rho_sup]``, ``|w| <= d_max`` (exact)."""

    dynamics: str
    A: Matrix
    B: Matrix
    E: tuple[Fraction, Fraction]
    rho_sup: Fraction
    sigma0: Fraction
    delta: Fraction
    speed: Fraction
    d_max: Fraction

    def vertex(self, rho: Fraction) -> Matrix:
        return tuple(tuple(a + rho * b for a, b in zip(ra, rb)) for ra, rb in zip(self.A, self.B))


@dataclass
class ConditionResult:
    """Outcome of one condition class at one parameter point.

    ``numbers`` holds the figures behind the status (margins, bounds, rates); ``certificate``
    holds the exact objects (rational matrices as strings) that :mod:`lyapcheck.verify`
    re-checks; ``solver`` the numerical search's metadata.
    """

    name: str
    status: Status
    summary: str
    numbers: dict[str, Any] = field(default_factory=dict)
    certificate: dict[str, Any] = field(default_factory=dict)
    refutation: dict[str, Any] = field(default_factory=dict)
    solver: dict[str, Any] = field(default_factory=dict)

    def to_json(self) -> dict[str, Any]:
        out: dict[str, Any] = {"status": self.status, "summary": self.summary}
        if self.name in PROPERTY:
            out["property"] = PROPERTY[self.name]
        out.update(self.numbers)
        if self.certificate:
            out["certificate"] = self.certificate
        if self.refutation:
            out["refutation"] = self.refutation
        if self.solver:
            out["solver"] = self.solver
        return out
