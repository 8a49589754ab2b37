"""What a certificate document states besides its proofs, held to what is proved (``verify``).

The document names the model's states in order (:func:`check_declared`: against the model text).
Each decided condition carries, besides its exact ``certificate``, a ``property``
(``GES``, ``GAS``, ``ROA``, ...) and figures (``level``, ``k``, ``decay_rate_per_s``, ``bounds``, ...)
that reports, tables and scripts read without opening the certificate. ``verify`` must therefore
hold each of them to the certificate it has just re-checked, with one rule for every class:

* the ``property`` is the one the certificate's kind and content prove for the class (re-derived,
  compared exactly);
* every *figure* (a key whose value is a number, or a table or list holding numbers) is either
  re-derived from the certificate and equal to it (as a document writes it: ``float`` of the exact
  rational), or compared with the certificate by its class's own exact check (on polynomial loops a
  stated rate may be below the certified one: a weaker claim), or one of the declared
  :data:`ESTIMATES` (simulation estimates and records of the search and of the proof's work, which
  claim nothing and are left as stated; ``verify`` names them in its row); any other figure (a decay
  rate where the class proves none, a ``k`` beside a GAS claim) is refused.

Text keys (``V_from``, ``tried``, ``reason``) carry no figure and are not compared. The checkers of
each certificate kind give the re-derived property and figures (:class:`Stated`);
:func:`check_stated` applies the rule.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from fractions import Fraction
from typing import Any, Final, Mapping

#: keys of a condition that are not figures: what it is, its proof, and the solver's record
NOT_FIGURES: Final = frozenset({"status", "summary", "property", "certificate", "refutation", "solver",
                                "disturbances"})

#: figures a condition may carry that claim nothing and are left as stated, with what each is: the
#: simulation estimates (floating point, from sampled or simulated starts; the report and the answers
#: call each "simulated"), and records of the search and of the proof's work (another lyapcheck may
#: prove the same claim with other work, so they are not compared). A new figure a class prints goes
#: either into that class's re-derived figures or here, with what it is.
ESTIMATES: Final[Mapping[str, str]] = {
    # simulation and sampling estimates
    "max_real_part_estimate": "the largest real part of the Jacobian's eigenvalues, in floating point",
    "spectral_radius_estimate": "the largest modulus of a map's Jacobian's eigenvalues, in floating point",
    "roa_share": "the share of the simulated starts that converge which lie in the certified set",
    "simulated_roa_share_of_box": "the share of the simulated starts of the box that converge",
    "simulated_roa_share_of_domain": "the share of the simulated starts of the domain that converge",
    "simulated_starts": "how many starts were simulated",
    "starts_in_set_not_converged": "simulated starts in the set that did not converge in the first simulation",
    "starts_left_set": "simulated starts whose trajectory left the certified set (a soundness alarm)",
    "starts_not_checked_slow_convergence": "simulated starts in the set still converging when the check stopped",
    "starts_past_certified_convergence_time": "simulated starts outside the small ball longer than the certificate's "
                                              "decrease allows (a soundness alarm)",
    "soundness_violation": "the simulation contradicts the certified claim (a soundness alarm)",
    "sampled_share": "the share of sampled points where the fitted V decreases",
    "box_share_estimate": "the share of sampled points of the box in the certified set",
    "level_supremum_estimate": "the largest level where sampling sees V' < 0",
    "level_ratio_to_estimate": "the certified level over level_supremum_estimate",
    "ball_radius_estimate": "a sampled estimate of the largest ball in the set",
    "closest_approach": "the closest a simulated trajectory came to the unsafe set",
    "falsification": "the simulated search for a trajectory into the unsafe set: its starts and closest approach",
    # records of the search
    "relative_margin": "the smallest eigenvalue margin of the solver's Gram matrices, relative (before rounding)",
    "rounds": "the region search's rounds: each level and its share",
    "history": "the region search's rounds: each level and its share",
    "fitted_domain_share": "the share of the domain (about the equilibrium) the proved V was fitted to, where V "
                           "fitted over the whole domain proved nothing (sampled_share is then of that part)",
    "local_level": "the ball-arithmetic level search's first level (the ellipsoid in the box where the Hessian of V' is "
                   "negative definite); the certified level is at least this",
    # records of the proof's work
    "cells": "cells the ball-arithmetic proof took",
    "boundary_cells": "cells of the set's boundary the ball-arithmetic proof took",
    "proof_seconds": "wall time of the proof",
}


@dataclass(frozen=True)
class Stated:
    """What a checked certificate proves, for comparison with what its condition states.

    ``property``: the property it proves for the class; ``figures``: each figure it gives, exactly
    (a rational, an integer, or a table of them by name); ``checked``: the figures its class's own
    exact check holds to the certificate.
    """

    property: str
    figures: Mapping[str, Any] = field(default_factory=dict)
    #: figures the certificate kind's own exact check compares with the certificate (in the direction
    #: that keeps the claim true: a rate at most the certified one), so accepted here
    checked: frozenset[str] = frozenset()


def is_figure(value: Any) -> bool:
    """A number (a flag too), or a table or list holding one at any depth."""
    if isinstance(value, (bool, int, float)):
        return True
    if isinstance(value, Mapping):
        return any(is_figure(v) for v in value.values())
    if isinstance(value, (list, tuple)):
        return any(is_figure(v) for v in value)
    return False


def _same(stated: Any, proved: Any) -> bool:
    """The stated figure is the proved one as a document writes it: an integer as itself, a
    rational as the float nearest to it (``float(Fraction)``, which JSON keeps exactly), a table
    with the same names and each entry the same."""
    if isinstance(proved, Mapping):
        return isinstance(stated, Mapping) and set(stated) == set(proved) and \
            all(_same(stated[k], proved[k]) for k in proved)
    if isinstance(stated, bool) or not isinstance(stated, (int, float)):
        return False
    if isinstance(proved, int):
        return isinstance(stated, int) and stated == proved
    return float(stated) == float(Fraction(proved))


def _shown(proved: Any) -> Any:
    if isinstance(proved, Mapping):
        return {k: _shown(v) for k, v in proved.items()}
    return proved if isinstance(proved, int) else float(Fraction(proved))


def check_stated(condition: Mapping[str, Any], proved: Stated) -> tuple[bool, str]:
    """Hold a condition's ``property`` and figures to what its checked certificate proves (module
    docstring); ``(ok, why)``, where ``why`` names the estimates left as stated when ok."""
    stated = condition.get("property")
    if stated != proved.property:
        return False, f"the stated property {stated!r} is not the one the certificate proves ({proved.property})"
    kept = []
    for key, value in condition.items():
        if key in NOT_FIGURES or not is_figure(value):
            continue
        if key in proved.figures:
            if not _same(value, proved.figures[key]):
                return False, (f"the stated figure '{key}' = {value!r} is not the certificate's "
                               f"({_shown(proved.figures[key])!r})")
        elif key in proved.checked:
            continue
        elif key in ESTIMATES:
            kept.append(key)
        else:
            gives = ", ".join([*proved.figures, *sorted(proved.checked)]) or "none"
            return False, (f"the figure '{key}' is not one this certificate proves (it gives: {gives}) nor a "
                           "declared estimate")
    return True, ("property and figures as proved" +
                  (f"; left as stated, estimates that claim nothing: {', '.join(kept)}" if kept else ""))


def check_declared(doc: Mapping[str, Any], model: Any) -> tuple[str, bool, str]:
    """The ``states`` row: the document's ``states`` are the model text's, in its order (the order
    of every exponent list and of the state vector), and its ``model.name`` is the text's."""
    states, name = doc.get("states"), doc["model"].get("name")
    if states != list(model.states):
        return "states", False, (f"states: the stated order {states!r} is not the model text's "
                                 f"{list(model.states)!r}")
    if name != model.name:
        return "states", False, f"states: the stated model name {name!r} is not the model text's {model.name!r}"
    return "states", True, "the states, in order, and the model's name are the model text's"


__all__ = ["ESTIMATES", "NOT_FIGURES", "Stated", "check_declared", "check_stated", "is_figure"]
