"""The exact check of each class's certificate on a loop with functions, one callable per class (the
``verify_functions`` of its entry in :mod:`lyapcheck.models.classes.registry`).

Each takes a decided condition as stored (``c``) and the
:class:`~lyapcheck.models.classes.contexts.FunctionsCheck` verify re-derived from the model text, and
returns ``(ok, why)`` (each is given its class's name too, which some certificates state); a malformed
certificate raises (``KeyError``, ``ValueError``, ...), which verify reports in one row. Every class but
``linearization`` and ``sos_bound`` is refuted the same way (another equilibrium, proved exactly:
:func:`verify_refutation`).
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any, Callable

if TYPE_CHECKING:  # pragma: no cover
    from lyapcheck.models.classes.contexts import FunctionsCheck
    from lyapcheck.models.classes.recast_classes import Loop
    from lyapcheck.models.language.recast import RecastModel


def verify_linearization(name: str, c: dict[str, Any], check: "FunctionsCheck") -> tuple[bool, str]:
    """``linearization``: the recasting's Jacobian (exact) against the certificate or refutation, and
    its sentence."""
    from lyapcheck.models.classes import piecewise_linearization
    from lyapcheck.models.classes.claims import summary
    from lyapcheck.models.classes.linearization import verify_jacobian
    from lyapcheck.models.classes.recast_classes import jacobian

    if piecewise_linearization.is_certificate(c.get("certificate")):  # a kink at the equilibrium
        ok, why = piecewise_linearization.verify(check.base, False, c["status"], c["certificate"])
        if ok and c.get("summary") != summary(name, c):
            return False, "the printed sentence is not the one the certificate supports"
        return ok, why
    J = jacobian(check.base)
    if isinstance(J, str):
        return False, f"the model's Jacobian is not exact here: {J}"
    data = c.get("certificate") if c["status"] == "certified" else c.get("refutation")
    ok, why = verify_jacobian(J, c["status"], data or {})
    if ok and c.get("summary") != summary(name, c):
        return False, "the printed sentence is not the one the certificate supports"
    return ok, why


def verify_refutation(name: str, c: dict[str, Any], check: "FunctionsCheck") -> tuple[bool, str]:
    """A refuted class: another equilibrium of the recasting, proved exactly, and its sentence."""
    from lyapcheck.models.classes.claims import covered
    from lyapcheck.models.classes.recast_classes import check_refutation, refutation_sentence

    ok, why = check_refutation(check.base, c.get("refutation"))
    if ok and c.get("summary") != covered(c.get("disturbances"), refutation_sentence(c["refutation"]["point"])):
        return False, "the printed sentence is not the one the refutation supports"
    return ok, why


def verify_lyapunov(name: str, c: dict[str, Any], check: "FunctionsCheck") -> tuple[bool, str]:
    """``quadratic`` and ``sos_gas``: the relations' certificate (one implementation for every loop,
    :mod:`lyapcheck.models.classes.lyapunov`) on the proved recasting, and its sentence."""
    from lyapcheck.models.classes.claims import covered
    from lyapcheck.models.classes.lyapunov import OLD_FORMAT, OLD_RELATIONS_KIND, relations_sentence
    from lyapcheck.models.classes.lyapunov_relations import check_relations_certificate

    if c["status"] == "refuted":
        return verify_refutation(name, c, check)
    cert = c["certificate"]
    if cert.get("kind") == OLD_RELATIONS_KIND:
        return False, OLD_FORMAT
    proved, why = _proved_recasting(cert, check.base)
    ok, why = (False, why) if proved is None else check_relations_certificate(name, c, proved)
    if ok and c.get("summary") != covered(c.get("disturbances"), relations_sentence(cert)):
        return False, "the printed sentence is not the one the certificate supports"
    return ok, why


def verify_region(name: str, c: dict[str, Any], check: "FunctionsCheck") -> tuple[bool, str]:
    """``roa`` and ``candidate``: a region proved by ball arithmetic on the true field
    (:func:`lyapcheck.models.classes.recast_interval.check_interval`), or a recast certificate (positivity
    and decrease, everywhere or on ``{V <= level}``, on the recasting's relations), and its sentence."""
    from lyapcheck.exact import read_rational
    from lyapcheck.models.classes.claims import covered, lyapunov_sentence
    from lyapcheck.models.classes.recast_classes import check_denominator_proofs, for_v, lie, state_square, v_names, \
        v_text
    from lyapcheck.models.engines.recast_sos import ConditionCertificate, check_condition, poly_from_json
    from lyapcheck.sos.polynomials import degree_in, to_fmpq

    if c["status"] == "refuted":
        return verify_refutation(name, c, check)
    base, cert = check.base, c["certificate"]
    if cert.get("kind") == "interval":
        from lyapcheck.models.classes.recast_interval import check_interval

        return check_interval(base, c, check.robust)
    if cert.get("kind") != "recast":
        return False, "not a recast certificate"
    system = base.system
    proved, why = _proved_recasting(cert, base)
    if proved is None:
        return False, why
    ring = proved.ring
    V = poly_from_json(ring, cert["V"], "V")
    loop = for_v(proved, V)
    if cert.get("angles") != list(loop.angles):
        return False, "the angles taken modulo 2 pi are not the ones this V allows"
    allowed = {ring.names[i] for i in loop.v_variables()}
    if any(degree_in(ring, V, [n]) > 0 for n in ring.names if n not in allowed):
        return False, "V uses a variable a Lyapunov function may not (an angle, a root, or a non-smooth function)"
    ok, why, N = check_denominator_proofs(loop, v_names(loop, V), cert["recasting"]["denominators"])
    if not ok:
        return False, why
    l2 = state_square(loop)
    eps = read_rational(cert["epsilon"])
    if eps <= 0:
        return False, "epsilon must be > 0"
    region = None
    pos_eps = eps
    if "level" in cert:
        level = read_rational(cert["level"])
        if level <= 0:
            return False, "the level must be > 0"
        if c.get("level") is not None and c.get("level") != float(level):
            return False, "the stated level is not the certificate's"
        region = V - to_fmpq(level)
        pos_eps = read_rational(cert["positivity_epsilon"])
        if pos_eps <= 0:
            return False, "positivity_epsilon must be > 0"
    pos = ConditionCertificate.from_json(ring, cert["positivity"], len(loop.relations))
    ok, why = check_condition(ring, V - l2 * to_fmpq(pos_eps), loop.relations, pos)
    if not ok:
        return False, f"positivity: {why}"
    dec = ConditionCertificate.from_json(ring, cert["decrease"], len(loop.relations))
    if (region is None) != (dec.rho is None):
        return False, "a region's decrease needs its multiplier rho, and only a region's"
    decrease = read_rational(cert.get("decrease_epsilon", eps))
    if decrease < eps:
        return False, "decrease_epsilon must be at least epsilon"
    ok, why = check_condition(ring, -lie(loop, V, N) - l2 * to_fmpq(decrease), loop.relations, dec, region=region)
    if not ok:
        return False, f"decrease: {why}"
    if c.get("summary") != covered(c.get("disturbances"), lyapunov_sentence(cert)):
        return False, "the printed sentence is not the one the certificate supports"
    if cert.get("V_text") != v_text(system, V):
        return False, "V_text is not V written with the functions"
    what = "on {V <= level}" if region is not None else "everywhere"
    modulo = " (modulo 2 pi in the angles)" if loop.angles else ""
    return True, f"positivity and decrease {what}{modulo} on the recasting's relations, exactly"


def verify_sos_bound(name: str, c: dict[str, Any], check: "FunctionsCheck") -> tuple[bool, str]:
    """``sos_bound`` (:func:`lyapcheck.models.classes.bounds.check_functions`, over the document's box if any);
    it refutes nothing."""
    from lyapcheck.models.classes.bounds import check_functions

    if c["status"] != "certified":
        return False, "sos_bound refutes nothing"
    if check.model is None:
        raise ValueError("sos_bound is checked against the model text")
    return check_functions(check.model, c, check.box)


def verify_barrier(name: str, c: dict[str, Any], check: "FunctionsCheck") -> tuple[bool, str]:
    """``barrier`` (:func:`_verify_barrier`), on the model's own parameters or on the loop recast with a
    box's parameters as bounded constants."""
    if c["status"] == "refuted":
        return verify_refutation(name, c, check)
    if check.model is None:
        return False, "a barrier is certified on the model's own parameters, not over a box"
    return _verify_barrier(c, check.base, check.model)


def verify_reach_avoid(name: str, c: dict[str, Any], check: "FunctionsCheck") -> tuple[bool, str]:
    """``reach_avoid`` (:func:`_verify_reach_avoid`), as :func:`verify_barrier`."""
    if c["status"] == "refuted":
        return verify_refutation(name, c, check)
    if check.model is None:
        return False, "a reach-avoid function is certified on the model's own parameters, not over a box"
    return _verify_reach_avoid(c, check.base, check.model)


def _proved_recasting(cert: dict[str, Any], base: Loop) -> tuple[Loop | None, str]:
    """The loop a recast certificate's V (or B) lives on: its variables, auxiliaries and shift must be
    the recasting of the model text, and its square roots' lower bounds are re-proved; or why not."""
    from lyapcheck.models.classes.recast_classes import check_root_proofs

    system = base.system
    if cert.get("variables") != list(system.ring.names) or cert.get("auxiliaries") != system.definitions() or \
            cert.get("shift") != {k: str(v) for k, v in system.values.items()}:
        return None, "variables, auxiliaries or shift differ from the recasting of the model text"
    return check_root_proofs(base, cert["recasting"]["roots"])


def _verify_barrier(c: dict[str, Any], base: Loop, model: RecastModel) -> tuple[bool, str]:
    """A loop with functions' barrier (:func:`lyapcheck.models.classes.barrier.check`), its recasting's square-root
    proofs and its sentence (the polynomial loops' :data:`~lyapcheck.models.classes.claims.BARRIER_SENTENCE`);
    a certificate of the older kind is refused in one line."""
    from lyapcheck.models.classes.barrier import KIND as BARRIER_KIND, OLD_FORMAT, OLD_KIND as RECAST_BARRIER, check
    from lyapcheck.models.classes.claims import BARRIER_SENTENCE

    cert = c["certificate"]
    if cert.get("kind") == RECAST_BARRIER:
        return False, OLD_FORMAT
    if c.get("status") != "certified" or cert.get("kind") != BARRIER_KIND:
        return False, f"a barrier's certificate kind must be {BARRIER_KIND!r}, not {cert.get('kind')!r}"
    return _checked_on_recasting(c, base, lambda proved: check(model, proved, c), BARRIER_SENTENCE)


def _verify_reach_avoid(c: dict[str, Any], base: Loop, model: RecastModel) -> tuple[bool, str]:
    """A reach-avoid certificate of a loop with functions
    (:func:`lyapcheck.models.classes.reach_avoid.check_functions`), its recasting's square-root proofs and its
    sentence (the polynomial loops' reach-avoid one); one of the older kind is refused in one line."""
    from lyapcheck.models.classes.claims import sentence_of
    from lyapcheck.models.classes.reach_avoid import KIND as RECAST_REACH_AVOID, OLD_FORMAT, \
        OLD_KIND as OLD_REACH_AVOID, check_functions as check

    cert = c["certificate"]
    if c.get("status") == "certified" and cert.get("kind") == OLD_REACH_AVOID:
        return False, OLD_FORMAT
    if c.get("status") != "certified" or cert.get("kind") != RECAST_REACH_AVOID:
        return False, f"a reach_avoid certificate's kind must be {RECAST_REACH_AVOID!r}, not {cert.get('kind')!r}"
    return _checked_on_recasting(c, base, lambda proved: check(model, proved, c), sentence_of(cert))


def _checked_on_recasting(c: dict[str, Any], base: Loop, check: Callable[[Loop], tuple[bool, str]],
                          sentence: str) -> tuple[bool, str]:
    """A certificate of a safety class: its recasting's square-root proofs, its class's ``check`` on the
    loop they prove, and its printed sentence."""
    from lyapcheck.models.classes.claims import covered

    proved, why = _proved_recasting(c["certificate"], base)
    if proved is None:
        return False, why
    ok, why = check(proved)
    if ok and c.get("summary") != covered(c.get("disturbances"), sentence):
        return False, "the printed sentence is not the one the certificate supports"
    return ok, why


__all__ = ["verify_linearization", "verify_refutation", "verify_lyapunov", "verify_region", "verify_sos_bound",
           "verify_barrier", "verify_reach_avoid"]
