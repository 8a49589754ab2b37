"""The result of one condition class at one point: the type the paper's classes and the
generic model classes share.

Statuses (DESIGN.md): ``certified`` (an exact check passed), ``refuted`` (exactly proved that no
certificate of the class exists, or, for ``linearization``, that the equilibrium is unstable),
``not_certified`` (none found, nothing proved), ``inconclusive`` (numerical trouble, a time
limit, or an exact check that failed), ``holds`` / ``fails`` (plain arithmetic, ``stabcond2``),
``not_applicable`` (an input the class needs is missing) and ``counterexample`` (a reproducible
trajectory against the property: numerical evidence, not a proof).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Literal

Status = Literal["certified", "refuted", "not_certified", "inconclusive", "holds", "fails", "not_applicable",
                 "counterexample"]

Property = Literal["GES", "GAS", "ISS", "LES", "ROA", "ultimate_bound", "invariant_set", "safety", "reach_avoid"]

#: which disturbances a claim of a model with ``[disturbances]`` covers (DESIGN.md, "Disturbances in
#: claims"): ``"zero"``, proved with every disturbance held at 0 (the nominal loop); ``"all"``, it
#: holds for every disturbance signal within its bounds
Disturbances = Literal["zero", "all"]
#: what a class proves when it is certified, by class name (DESIGN.md: every stability class states
#: it, so that a GAS certificate is never read as GES). A class whose property depends on what its
#: certificate shows (``quadratic``: GES or GAS; ``candidate``: ROA or GAS) sets
#: :attr:`ConditionResult.property` itself. ``stabcond2`` is arithmetic, not a certificate: absent.
PROPERTY: dict[str, Property] = {
    # the paper's classes
    "prop41_ges": "GES", "prop41_iss": "ISS", "sector_ges": "GES", "switched_ges": "GES",
    "ultimate_bound": "ultimate_bound", "sos_gas": "GAS", "ges": "GES", "saturated_loop": "invariant_set",
    "sos_bound": "ultimate_bound",
    # the classes of a model file (lyapcheck.models)
    "linearization": "LES", "quadratic": "GES", "roa": "ROA", "candidate": "ROA", "barrier": "safety",
    "reach_avoid": "reach_avoid",
}


@dataclass
class ConditionResult:
    """Outcome of one condition class at one parameter point.

    ``numbers`` holds the figures behind the status (margins, bounds, rates); ``certificate``
    holds the exact objects (rational matrices and polynomials as strings) that ``verify``
    re-checks; ``solver`` the numerical search's metadata; ``property`` what a ``certified``
    proves, when it is not the class's default (:data:`PROPERTY`); ``disturbances`` which
    disturbances it covers, for a model that declares some (:data:`Disturbances`).
    """

    name: str
    status: Status
    summary: str
    numbers: dict[str, Any] = field(default_factory=dict)
    certificate: dict[str, Any] = field(default_factory=dict)
    refutation: dict[str, Any] = field(default_factory=dict)
    solver: dict[str, Any] = field(default_factory=dict)
    property: Property | None = None
    #: for a model with disturbances: which of them the claim covers (None: the model has none)
    disturbances: Disturbances | None = None

    def proves(self) -> Property | None:
        """The property a ``certified`` of this result proves (None for arithmetic classes)."""
        return self.property if self.property is not None else PROPERTY.get(self.name)

    def to_json(self) -> dict[str, Any]:
        out: dict[str, Any] = {"status": self.status, "summary": self.summary}
        if self.proves() is not None:
            out["property"] = self.proves()
        if self.disturbances is not None:
            out["disturbances"] = self.disturbances
        out.update(self.numbers)
        if self.certificate:
            out["certificate"] = self.certificate
        if self.refutation:
            out["refutation"] = self.refutation
        if self.solver:
            out["solver"] = self.solver
        return out
