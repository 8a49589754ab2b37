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
each certificate kind give the re-derived property and figures (:class:`Stated`; on a loop with functions
:func:`proved_claims`); :func:`check_stated` applies the rule.

The steps of ``verify`` that hold the rest of what a document states to what it proves are here too, each
run by :func:`lyapcheck.models.surfaces.verify.verify_model` on the kinds of loop it applies to: the stated V's
``variables`` and ``V_text`` (:func:`check_stated_v`), the ``disturbances`` keys
(:func:`check_disturbance_keys`), the candidate text (:func:`candidate_of_polynomial`,
:func:`candidate_of_functions`), the summaries (:func:`check_summaries`) and each condition's property and
figures (:func:`check_stated_claims`).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from fractions import Fraction
from typing import TYPE_CHECKING, Any, Final, Mapping

from lyapcheck.models.surfaces.counterexamples import describe_exception as _describe

if TYPE_CHECKING:  # pragma: no cover
    from lyapcheck.models.language.recast import RecastModel

#: verify's (check, ok, message) row
Row = tuple[str, bool, str]

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
    "flow_box_starts_not_converged": "simulated starts in a box proved to flow into the set that did not converge "
                                     "in the first simulation (each then simulated up to its box's stated time)",
    "flow_box_starts_not_in_set_at_their_time": "of those, the starts not in the set at their box's stated time "
                                                "(a soundness alarm)",
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
    "shaping": "the design of a quadratic V shaped for a large region (floating point, a proposal the proof then "
               "decided): its rounds and the sampled shares of the box inside its and the linearization's V at the "
               "levels where sampling first sees V' stop decreasing",
    "other_route": "roa on a polynomial loop: the figures of the other route's set (its level, ball_radius and "
                   "roa_share over the same simulated starts), which the kept set covered no less than "
                   "(lyapcheck.models.classes.field_ball_route)",
    "local_level": "the ball-arithmetic level search's first level (the ellipsoid in the box where the Hessian of V' is "
                   "negative definite); the certified level is at least this",
    # records of the proof's work
    "cells": "cells the ball-arithmetic proof took",
    "cells_spent": "cells the ball-arithmetic level search examined in all (every level it tried)",
    "box_parts": "parts of the box the ball-arithmetic proof split it into",
    "boundary_cells": "cells of the set's boundary the ball-arithmetic proof took",
    "proof_seconds": "wall time of the proof",
    # the boxes proved to flow into a ball-arithmetic set (lyapcheck.models.classes.flow_region): the sentence
    # states their count, volume and longest time from the certificate, which verify re-makes
    "flow_boxes": "boxes of starts proved by validated integration to flow into the set (the certificate's flow)",
    "flow_boxes_volume": "the total volume of those boxes",
    "flow_max_time": "the longest of their times",
    "flow_steps": "integration steps the validated integration took in all (boxes proved or not)",
    "flow_step": "the validated integration's step",
    "flow_boxes_left": "boxes not tried when the validated integration stopped",
    "flow_stopped": "why the validated integration stopped before every box was tried",
    "flow_skipped": "why no box was integrated",
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


# -- the steps of verify that hold what a document states to what it proves --------------------------------
# (:func:`lyapcheck.models.surfaces.verify.verify_model` runs them; each appends a failed row, or a row of its own)

def check_stated_v(model: Any, box: Any, conditions: dict[str, Any], rows: list[Row]) -> None:
    """A certified V's ``variables`` name its exponents (the states, then for ``sos_bound`` the
    disturbances, then a box's parameters) and its ``V_text`` is V written readably, as
    ``certify`` writes them: a V_text edited to show another V fails here (both are optional:
    the exact V is the one checked)."""
    from lyapcheck.models.surfaces.certify import readable_v, stated_polynomials

    for name, c in conditions.items():
        if not isinstance(c, dict) or c.get("status") != "certified" or not isinstance(c.get("certificate"), dict):
            continue
        try:
            for data, variables in stated_polynomials(model, box, name, c["certificate"]):
                if "variables" in data and data["variables"] != variables:
                    rows.append((name, False, f"{name}: 'variables' must be {variables}"))
                elif "V_text" in data and data["V_text"] != readable_v(model, data["V"], variables):
                    rows.append((name, False, f"{name}: V_text is not the certified V written out"))
        except (KeyError, ValueError, TypeError, ArithmeticError) as exc:
            rows.append((name, False, f"{name}: the stated V is malformed: {_describe(exc)}"))


def check_disturbance_keys(model: Any, conditions: dict[str, Any], rows: list[Row]) -> None:
    """Every condition of a model with disturbances says which it covers, and only such a model's
    conditions carry the key (DESIGN.md, "Disturbances in claims"). Whether an ``"all"`` claim
    holds is checked with its class (:func:`lyapcheck.models.classes.registry.verify`); a class that proves
    its claim with the disturbances at 0 only (:data:`~lyapcheck.models.classes.registry.ZERO_DISTURBANCE_ONLY`)
    may not claim them all where one enters."""
    from lyapcheck.models.classes.registry import ZERO_DISTURBANCE_ONLY

    for name, c in conditions.items():
        if not isinstance(c, dict):
            continue
        stated = c.get("disturbances")
        if model.disturbances and stated not in ("zero", "all"):
            rows.append((name, False, f"{name}: the model has disturbances, so the key 'disturbances' must be 'zero' "
                                      f"or 'all'; it is {stated!r}"))
        elif not model.disturbances and stated is not None:
            rows.append((name, False, f"{name}: the key 'disturbances' is {stated!r}, but the model has none"))
        elif name in ZERO_DISTURBANCE_ONLY and stated == "all" and c.get("status") == "certified" \
                and _disturbances_enter(model):
            rows.append((name, False, f"{name}: this class proves its claim with the disturbances at 0 only, not "
                                      "'all'"))


def _disturbances_enter(model: Any) -> bool:
    """Whether a disturbance with a bound > 0 occurs in the field (:func:`field.entering`)."""
    from lyapcheck.models.loop.field import entering, shifted_field

    shifted = shifted_field(model)
    return bool(entering(shifted.ring, model.n, (*shifted.numerators, *shifted.denominators),
                         list(model.disturbances.values())))


def candidate_of_polynomial(doc: dict[str, Any], model: Any, rows: list[Row]) -> None:
    """The top-level ``candidate`` text is the user's V: parsed with the model's expression rules,
    it must be the ``V`` of a certified ``candidate`` condition (shifted to the equilibrium)."""
    from lyapcheck.errors import ModelFileError
    from lyapcheck.models.classes.lyapunov import terms_json
    from lyapcheck.models.surfaces.certify import parse_candidate
    from lyapcheck.sos.polynomials import Ring, to_fmpq

    c = doc["conditions"].get("candidate")
    text = doc.get("candidate")
    certified = isinstance(c, dict) and c.get("status") == "certified"
    if text is None and not certified:
        return
    if not isinstance(text, str):
        rows.append(("candidate", False, "candidate: the candidate text must be text"
                     + (", and a certified candidate condition needs it" if certified else "")))
        return
    try:  # a text the report shows must be a candidate of this model, even where nothing certified it
        cand = parse_candidate(model, text)
    except ModelFileError as exc:
        rows.append(("candidate", False, f"candidate: the candidate text does not parse: {exc}"))
        return
    if not isinstance(c, dict) or not certified:
        return
    ring = model.state_ring
    gens = ring.gens()
    images = [g + to_fmpq(e) for g, e in zip(gens[:model.n], model.equilibrium)] + list(gens[model.n:])
    shifted_v = ring.compose(cand.poly, images)
    # (a map's candidate over a box states V in the states and the box's parameters, at exponent 0: one V)
    box_names = tuple(str(k) for k in doc["box"]) if isinstance(doc.get("box"), dict) else ()
    states = Ring(ring.names[:model.n])
    on = Ring(ring.names[:model.n] + box_names)
    v = ring.restrict(shifted_v, states)
    stated = (c.get("certificate") or {}).get("V")
    same = terms_json(states, v) == stated or (bool(box_names) and terms_json(on, on.from_terms(
        {m + (0,) * len(box_names): k for m, k in states.terms(v).items()})) == stated)
    rows.append(("candidate", same, "the candidate text is the certified V" if same else
                 "candidate: the candidate text is not the V of the certified candidate condition"))


#: the figures the exact check of each certificate kind (:mod:`lyapcheck.models.classes.verify_field`) compares
_CHECKED_FIGURES: dict[str, tuple[str, ...]] = {
    "lyapunov": ("decay_rate_V_per_s",), "lyapunov_cliques": ("decay_rate_V_per_s",),
    "lyapunov_vector": ("decay_rate_V_per_s",), "lyapunov_cascade": ("degree",),
    "sublevel": ("level", "ball_radius", "size"),
    "quadratic_ball": ("level", "ball_radius", "size"), "barrier": ("lambda_per_s",), "reach_avoid": ("reach_time_bound_s",),
    "sos_bound": ("bounds", "bounds_reference"), "interval": ("level", "size"),
    "discrete_sublevel": ("level", "size"), "discrete_interval": (),
}
#: what a certificate of each kind proves (a Lyapunov certificate: GAS, or GES where
_KIND_PROPERTY: dict[str, str] = {"lyapunov": "GAS", "lyapunov_cliques": "GAS", "lyapunov_vector": "GAS",
                                  "lyapunov_cascade": "GAS", "sublevel": "ROA",
                                  "quadratic_ball": "ROA", "barrier": "safety", "reach_avoid": "reach_avoid",
                                  "sos_bound": "ultimate_bound", "interval": "ROA", "discrete_sublevel": "ROA",
                                  "discrete_interval": "ROA"}


def check_stated_claims(model: Any, conditions: dict[str, Any], rows: list[Row]) -> None:
    """Each decided condition's property and figures against what its certificate proves, by the
    rule every loop shares (:func:`lyapcheck.models.surfaces.stated.check_stated`): a figure is one its
    class's exact check compared, one re-derived here (the degree of the stated polynomial), or a
    declared estimate; anything else (a ``k`` beside a region, a decay rate beside the
    linearization) is refused."""
    for name, c in conditions.items():
        if not isinstance(c, dict) or not (c.get("status") == "certified" or
                                           (name == "linearization" and c.get("status") == "refuted")):
            continue
        try:
            if name == "linearization":
                proved = Stated("LES")
            else:
                cert = c["certificate"]
                kind = "sos_bound" if name == "sos_bound" else cert.get("kind")
                if kind not in _KIND_PROPERTY:
                    continue  # an unknown kind already fails its class's check
                prop = "GES" if kind == "lyapunov" and c.get("property") == "GES" else _KIND_PROPERTY[kind]
                checked = _CHECKED_FIGURES[kind] + (("k", "decay_rate_per_s") if prop == "GES" else ())
                stated = cert.get("B" if kind == "barrier" else "V")
                figures = {} if stated is None else {"degree": max(sum(e[:model.n]) for _, e in stated["terms"])}
                if kind == "discrete_interval":  # (a map with functions' region: V = e^T P e, its level, its area)
                    figures = _interval_region_figures(cert)
                proved = Stated(prop, figures, frozenset(checked))
            ok, why = check_stated(c, proved)
        except (KeyError, ValueError, TypeError, ArithmeticError) as exc:
            ok, why = False, f"the stated figures are malformed: {_describe(exc)}"
        if not ok:
            rows.append((name, False, f"{name}: {why}"))


def _interval_region_figures(cert: Mapping[str, Any]) -> dict[str, Any]:
    """The figures a map with functions' ``discrete_interval`` region proves: its level, and with two states the
    area of ``{e^T P e <= level}`` (:func:`lyapcheck.models.classes.discrete_functions.area`, in floating point
    as certify computes it)."""
    from lyapcheck.models.classes.discrete_functions import area

    P = [[Fraction(str(x)) for x in row] for row in cert["P"]]
    level = Fraction(str(cert["level"]))
    figures: dict[str, Any] = {"level": level}
    size = area(P, level)
    if size is not None:
        figures["area"] = size
    return figures


def check_summaries(model: Any, conditions: dict[str, Any], rows: list[Row], box: Any) -> None:
    """Each decided condition's summary is the one its checked figures (and the checked box) give
    (:mod:`lyapcheck.models.classes.claims`), and its figures' units are the model's."""
    from lyapcheck.models.classes.claims import state_unit_figures, summary

    for name, c in conditions.items():
        if not isinstance(c, dict):
            continue
        try:
            expected = summary(name, c, tuple(model.outputs), box)
        except (KeyError, ValueError, TypeError, ArithmeticError) as exc:
            rows.append((name, False, f"{name}: the summary's figures are malformed: {_describe(exc)}"))
            continue
        if expected is not None and c.get("summary") != expected:
            rows.append((name, False, f"{name}: the summary is not what the checked figures say; they say: "
                                      f"{expected!r}"))
        elif expected is not None and ({k: c[k] for k in ("ball_radius_unit",) if k in c}
                                       != state_unit_figures(model.units, model.states, c)):
            rows.append((name, False, f"{name}: ball_radius_unit is not the states' unit"))


def proved_claims(name: str, c: dict[str, Any], model: "RecastModel") -> Stated:
    """The property and the figures a decided condition of a loop with functions proves, read from its
    certificate (which its class's check then re-checks) and the model: a figure beside the status is
    compared with these, and any other is refused unless it is a declared estimate
    (:func:`lyapcheck.models.surfaces.stated.check_stated`)."""
    from lyapcheck.exact import read_rational
    from lyapcheck.models.classes.barrier import KIND as BARRIER, OLD_KIND as OLD_BARRIER
    from lyapcheck.models.classes.bounds import KIND, OLD_KIND
    from lyapcheck.models.classes.lyapunov import RELATIONS_KIND, relations_claim
    from lyapcheck.models.classes.reach_avoid import KIND as REACH_AVOID, OLD_KIND as OLD_REACH_AVOID

    if name == "linearization":
        return Stated("LES")
    if c["status"] == "refuted":  # another equilibrium, exactly: no global asymptotic stability
        return Stated("GAS")
    cert = c["certificate"]
    if not isinstance(cert, dict):
        raise ValueError("certificate: must be a table")
    kind = cert.get("kind")
    if kind in (KIND, OLD_KIND):  # (an older one is refused by its check, with the advice to certify again)
        from lyapcheck.models.classes.bounds import bound_claim

        claim = bound_claim(model, {out: read_rational(item["bound"]) for out, item in cert["outputs"].items()})
        return Stated("ultimate_bound", {k: v for k, v in claim.items() if k != "status"})
    if kind == RELATIONS_KIND and name in ("quadratic", "sos_gas"):
        return Stated(*relations_claim(cert))
    if kind == "interval":  # (its size: re-derived in a row of its own, check_size_rows)
        return Stated("ROA", {"level": read_rational(cert["level"])}, frozenset({"size"}))
    if kind in (BARRIER, OLD_BARRIER):  # (an older one is refused by its check, with the advice)
        if name != "barrier":
            raise ValueError(f"a barrier certificate under the class {name}")
        return Stated("safety", {"degree": _degree(cert, "B"), "lambda_per_s": read_rational(cert["lambda_per_s"])})
    if kind in (REACH_AVOID, OLD_REACH_AVOID):  # (an older one is refused by its check)
        from lyapcheck.models.classes.claims import recast_reach_time as reach_time

        if name != "reach_avoid":
            raise ValueError(f"a reach-avoid certificate under the class {name}")
        return Stated("reach_avoid", {"degree": _degree(cert, "V"), "reach_time_bound_s": reach_time(cert)})
    degree = _degree(cert, "V", empty=False)
    if "level" in cert:
        return Stated("ROA", {"degree": degree, "level": read_rational(cert["level"])}, frozenset({"size"}))
    return Stated("GAS", {"degree": degree})


def _degree(cert: dict[str, Any], key: str, empty: bool = True) -> int:
    """The degree of the stated polynomial ``cert[key]`` (0 for no term where ``empty``, else it raises)."""
    terms = cert[key]["terms"]
    degree = max((sum(e) for _, e in terms), default=0) if empty else max(sum(e) for _, e in terms)
    if isinstance(degree, bool) or not isinstance(degree, int):
        raise ValueError(f"{key}: exponents must be integers")
    return degree


def candidate_of_functions(doc: dict[str, Any], model: "RecastModel", rows: list[Row]) -> None:
    """The top-level ``candidate`` text is the user's V: recast with the model's functions (the text
    parsed with it, else verify stopped at the model row), it must be the ``V`` of a certified
    ``candidate`` condition, and a certified one needs it."""
    from lyapcheck.models.engines.recast_sos import poly_from_json

    c = doc["conditions"].get("candidate")
    certified = isinstance(c, dict) and c.get("status") == "certified"
    text = doc.get("candidate")
    if not certified:
        if not (text is None or isinstance(text, str)):
            rows.append(("candidate", False, "candidate: the candidate text must be text"))
        return
    assert isinstance(c, dict)
    if not isinstance(text, str) or model.candidate_v is None:
        rows.append(("candidate", False, "candidate: a certified candidate condition needs the candidate text"))
        return
    try:
        cert = c["certificate"]
        if "parameter_box" in cert and cert.get("kind") == "recast":
            # over a box, V on the loop recast with the box's parameters (the ring its certificate names, which
            # its proof's row holds to the recasting of the model text): the text's V moved there by name
            from lyapcheck.models.classes.recast_regions import in_ring
            from lyapcheck.sos.polynomials import Ring

            ring = Ring(tuple(cert["variables"]))
            same = poly_from_json(ring, cert["V"], "V") == in_ring(model.system.ring, ring, model.candidate_v)
        else:
            same = poly_from_json(model.system.ring, cert["V"], "V") == model.candidate_v
    except (KeyError, ValueError, TypeError, ArithmeticError) as exc:
        rows.append(("candidate", False, f"candidate: the certified V is malformed: {str(exc)[:200]}"))
        return
    rows.append(("candidate", same, "the candidate text is the certified V" if same else
                 "candidate: the candidate text is not the V of the certified candidate condition"))


__all__ = ["ESTIMATES", "NOT_FIGURES", "Stated", "check_declared", "check_stated", "is_figure", "check_stated_v",
           "check_disturbance_keys", "candidate_of_polynomial", "candidate_of_functions", "check_stated_claims",
           "check_summaries", "proved_claims"]
