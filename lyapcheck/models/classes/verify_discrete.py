"""The exact check of each class's certificate on the discrete-time kinds of loop, one callable per class and
kind (the ``verify_map``, ``verify_map_functions`` and ``verify_sampled`` of its entry in
:mod:`lyapcheck.models.classes.registry`).

Each takes the class's name, a decided condition as stored (``c``: ``certified``, ``refuted`` or
``counterexample``) and the check context verify re-derived from the model text
(:class:`~lyapcheck.models.classes.contexts.MapCheck`,
:class:`~lyapcheck.models.classes.contexts.MapFunctionsCheck` or
:class:`~lyapcheck.models.classes.contexts.SampledCheck`), and returns ``(ok, why)``. A status the class
has no check of on that loop (a refuted region, a counterexample) fails in the context's words
(``not_checked``): on these loops only ``linearization`` (by its Jacobian) and a map's ``barrier`` and
``reach_avoid`` (by an unsafe iterate) are ever refuted.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:  # pragma: no cover
    from lyapcheck.models.classes.contexts import MapCheck, MapFunctionsCheck, SampledCheck

#: the statuses a linearization's check re-derives (its certificate or its refutation)
_JACOBIAN_STATUSES = ("certified", "refuted")


def _data(c: dict[str, Any]) -> dict[str, Any]:
    """A linearization's certificate or refutation, by its status."""
    data = c.get("certificate") if c["status"] == "certified" else c.get("refutation")
    return data or {}


# -- a polynomial discrete-time map -------------------------------------------------------------------------

def verify_linearization_map(name: str, c: dict[str, Any], check: "MapCheck") -> tuple[bool, str]:
    """``linearization``: the discrete-time test on the shifted map's Jacobian
    (:func:`lyapcheck.models.classes.discrete_linearization.verify`)."""
    from lyapcheck.models.classes import discrete_linearization

    if c["status"] not in _JACOBIAN_STATUSES:
        return False, check.not_checked(c["status"])
    if check.shifted.box is not None:
        return verify_linearization_map_box(name, c, check)
    return discrete_linearization.verify(check.shifted, c["status"], _data(c))


def verify_linearization_map_box(name: str, c: dict[str, Any], check: "MapCheck") -> tuple[bool, str]:
    """``linearization`` over a box: one Stein certificate for every Jacobian of the box
    (:func:`lyapcheck.models.classes.discrete_lyapunov.verify_linearization_box`)."""
    from lyapcheck.models.classes import discrete_lyapunov

    return discrete_lyapunov.verify_linearization_box(check.shifted, c["status"], _data(c))


def _without_nominal_prefix(c: dict[str, Any]) -> dict[str, Any]:
    """The condition with the ``(d = 0) `` certify puts in front of a map's claim where the model has
    disturbances (every class of a map but ``sos_bound`` is decided with them at 0:
    :func:`lyapcheck.models.classes.claims.covered`) taken off its sentence, for a class's check that compares
    the bare sentence. Only the ``"zero"`` prefix: a claim stated for every disturbance keeps its words, and
    fails that comparison. (The whole sentence, prefix included, is compared by verify's summaries.)"""
    from lyapcheck.models.classes.claims import DISTURBANCE_PREFIX

    prefix = DISTURBANCE_PREFIX["zero"]
    text = c.get("summary")
    if c.get("disturbances") == "zero" and isinstance(text, str) and text.startswith(prefix):
        return {**c, "summary": text[len(prefix):]}
    return c


def verify_lyapunov_map(name: str, c: dict[str, Any], check: "MapCheck") -> tuple[bool, str]:
    """``quadratic``, ``sos_gas``: ``V(F(e)) - V(e) <= -mu V(e) - W(e)`` from the condition's JSON
    (:func:`lyapcheck.models.classes.discrete_lyapunov.verify`, which compares the sentence without the
    ``(d = 0)`` of a map with disturbances)."""
    from lyapcheck.models.classes import discrete_lyapunov

    if c["status"] != "certified":
        return False, check.not_checked(c["status"])
    return discrete_lyapunov.verify(check.shifted, c["status"], _without_nominal_prefix(c))


def verify_region_map(name: str, c: dict[str, Any], check: "MapCheck") -> tuple[bool, str]:
    """``roa``, ``candidate``: ``V(F(e)) <= V(e) - eps m(e)`` on ``{V <= c}`` from the condition's JSON
    (:func:`lyapcheck.models.classes.discrete_regions.verify`)."""
    from lyapcheck.models.classes import discrete_regions

    if c["status"] != "certified":
        return False, check.not_checked(c["status"])
    return discrete_regions.verify(check.shifted, name, c)


def verify_safety_map(name: str, c: dict[str, Any], check: "MapCheck") -> tuple[bool, str]:
    """``barrier``, ``reach_avoid``: the certificate's identities on the map and the sets, or a refutation's
    unsafe iterate, re-derived from the model text (:func:`lyapcheck.models.classes.discrete_safety.verify`)."""
    from lyapcheck.models.classes import discrete_safety, discrete_safety_box

    if c["status"] not in ("certified", "refuted"):
        return False, check.not_checked(c["status"])
    if check.shifted.box is not None:  # over a box (a refutation at its stated value of the box)
        return discrete_safety_box.verify(check.shifted, name, c, check.model)
    return discrete_safety.verify(check.shifted, name, c, check.model)


def verify_bound_map(name: str, c: dict[str, Any], check: "MapCheck") -> tuple[bool, str]:
    """``sos_bound``: each output's step and output identities on the disturbances' box, re-derived from the
    model text (:func:`lyapcheck.models.classes.discrete_bounds.verify`)."""
    from lyapcheck.models.classes import discrete_bounds

    if c["status"] != "certified":
        return False, check.not_checked(c["status"])
    return discrete_bounds.verify(check.shifted, c, check.model)


# -- a discrete-time map with functions ---------------------------------------------------------------------

def verify_linearization_map_functions(name: str, c: dict[str, Any], check: "MapFunctionsCheck"
                                       ) -> tuple[bool, str]:
    """``linearization``: the exact Jacobian again, then the discrete-time test
    (:func:`lyapcheck.models.classes.discrete_functions.verify_linearization`)."""
    from lyapcheck.models.classes import discrete_functions, piecewise_linearization
    from lyapcheck.models.classes.claims import summary

    if c["status"] not in _JACOBIAN_STATUSES:
        return False, check.not_checked(c["status"])
    if check.box is not None:  # one P for every Jacobian of the box, decided again in ball arithmetic
        from lyapcheck.models.classes import discrete_functions_box

        return discrete_functions_box.verify_linearization(check.model, check.box, c["status"], _data(c))
    if piecewise_linearization.is_certificate(_data(c)):  # a kink at the fixed point: the step form's check
        model = check.model
        ok, why = piecewise_linearization.verify(piecewise_linearization.map_loop(model), True, c["status"], _data(c))
        if ok and c.get("summary") != summary(name, c):
            return False, "the printed sentence is not the one the certificate supports"
        return ok, why
    return discrete_functions.verify_linearization(check.model, c["status"], _data(c))


def verify_lyapunov_map_functions(name: str, c: dict[str, Any], check: "MapFunctionsCheck") -> tuple[bool, str]:
    """``quadratic``, ``sos_gas``: the map and its relations re-derived, the identity re-checked exactly
    (:func:`lyapcheck.models.classes.map_relations.verify`)."""
    from lyapcheck.models.classes import map_relations

    if c["status"] != "certified":
        return False, check.not_checked(c["status"])
    return map_relations.verify(check.model, name, _without_nominal_prefix(c), check.box)


def verify_bound_map_functions(name: str, c: dict[str, Any], check: "MapFunctionsCheck") -> tuple[bool, str]:
    """``sos_bound``: the map recast with its disturbances, its relations and each output's two identities
    re-checked exactly (:func:`lyapcheck.models.classes.map_relations_bounds.verify`)."""
    from lyapcheck.models.classes import map_relations_bounds

    if c["status"] != "certified":
        return False, check.not_checked(c["status"])
    return map_relations_bounds.verify(check.model, c, check.box)


def verify_barrier_map_functions(name: str, c: dict[str, Any], check: "MapFunctionsCheck") -> tuple[bool, str]:
    """``barrier``: the map, its relations and the sets re-derived, every identity re-checked exactly; a refuted
    one's iterate re-derived in ball arithmetic through the true functions
    (:func:`lyapcheck.models.classes.map_relations_safety.verify_barrier`)."""
    from lyapcheck.models.classes import map_relations_safety

    if c["status"] not in ("certified", "refuted"):
        return False, check.not_checked(c["status"])
    if c["status"] == "refuted" and check.box is not None:  # at its value of the box
        from lyapcheck.models.classes import map_relations_safety_box

        return map_relations_safety_box.verify_refutation(name, check.model, check.box, c)
    return map_relations_safety.verify_barrier(check.model, _without_nominal_prefix(c), check.box)


def verify_reach_avoid_map_functions(name: str, c: dict[str, Any], check: "MapFunctionsCheck") -> tuple[bool, str]:
    """``reach_avoid``: the map, its relations and the sets re-derived, every identity re-checked exactly, the
    steps bound ``floor(C / eps)``; a refutation's start and its unsafe iterate before the goal re-derived in ball
    arithmetic (:func:`lyapcheck.models.classes.map_relations_reach.verify`)."""
    from lyapcheck.models.classes import map_relations_reach

    if c["status"] not in ("certified", "refuted"):
        return False, check.not_checked(c["status"])
    if c["status"] == "refuted" and check.box is not None:  # at its value of the box
        from lyapcheck.models.classes import map_relations_safety_box

        return map_relations_safety_box.verify_refutation(name, check.model, check.box, c)
    return map_relations_reach.verify(check.model, _without_nominal_prefix(c), check.box)


def verify_roa_map_functions(name: str, c: dict[str, Any], check: "MapFunctionsCheck") -> tuple[bool, str]:
    """``roa``: the ``discrete_interval`` region proved again, cell for cell
    (:func:`lyapcheck.models.classes.discrete_functions.verify_roa`; over a box with its parameters as balls,
    :func:`lyapcheck.models.classes.discrete_functions_box.verify_roa`)."""
    from lyapcheck.models.classes import discrete_functions

    if c["status"] != "certified":
        return False, check.not_checked(c["status"])
    if check.box is not None:
        from lyapcheck.models.classes import discrete_functions_box

        return discrete_functions_box.verify_roa(check.model, check.box, c)
    return discrete_functions.verify_roa(check.model, c)


def verify_candidate_map_functions(name: str, c: dict[str, Any], check: "MapFunctionsCheck") -> tuple[bool, str]:
    """``candidate``: the stated V is the document's candidate, and its level is proved again
    (:func:`lyapcheck.models.classes.discrete_functions.verify_candidate`); over a box, for every value of it
    (:func:`lyapcheck.models.classes.discrete_functions_box.verify_candidate`)."""
    from lyapcheck.models.classes import discrete_functions

    if c["status"] != "certified":
        return False, check.not_checked(c["status"])
    if check.box is not None:
        from lyapcheck.models.classes import discrete_functions_box

        return discrete_functions_box.verify_candidate(check.model, check.box, c)
    return discrete_functions.verify_candidate(check.model, c)


# -- a sampled-data loop ------------------------------------------------------------------------------------

def verify_linearization_sampled(name: str, c: dict[str, Any], check: "SampledCheck") -> tuple[bool, str]:
    """``linearization``: ``A``, ``B``, ``K`` and the period re-derived, the decision checked again in ball
    arithmetic (:func:`lyapcheck.models.classes.sampled.verify_linearization`)."""
    from lyapcheck.models.classes import sampled

    if c["status"] not in _JACOBIAN_STATUSES:
        return False, check.not_checked(c["status"])
    return sampled.verify_linearization(check.model, c["status"], _data(c))


def verify_roa_sampled(name: str, c: dict[str, Any], check: "SampledCheck") -> tuple[bool, str]:
    """``roa``: the region re-derived on the true flow over one period from the model text
    (:func:`lyapcheck.models.classes.sampled_regions.verify`)."""
    from lyapcheck.models.classes import sampled_regions

    if c["status"] != "certified":
        return False, check.not_checked(c["status"])
    return sampled_regions.verify(check.model, c)


__all__ = ["verify_linearization_map", "verify_linearization_map_box", "verify_lyapunov_map", "verify_region_map",
           "verify_safety_map", "verify_bound_map",
           "verify_linearization_map_functions", "verify_lyapunov_map_functions", "verify_bound_map_functions",
           "verify_barrier_map_functions", "verify_reach_avoid_map_functions",
           "verify_roa_map_functions", "verify_linearization_sampled",
           "verify_roa_sampled"]
