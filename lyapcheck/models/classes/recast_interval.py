"""``roa`` on a loop with functions by ball arithmetic on the true field: the search, the
certificate and its check (issue 31, item 7).

:mod:`lyapcheck.models.classes.fitted_v` proposes ``(V, level, box)`` from simulations; 
:mod:`lyapcheck.models.engines.interval_region` proves it (boundary, decrease, the equilibrium's
neighbourhood) with python-flint's ``arb`` balls. No relaxation of the functions is involved: the
field proved on is the model's own, so a region can follow the true region of attraction much
more closely than one proved on the recasting's relations. The claim is in the states themselves
(convergence to the equilibrium, not modulo 2 pi).

The certificate (``kind`` "interval") carries ``variables``, ``auxiliaries`` and ``shift`` like
every recast certificate, ``V`` (over the state deviations only), ``V_text``, ``level``, ``box``
(each state's deviation interval) and what the proof took (cells, the local box's half-width).
``verify`` runs the same deterministic proof again from those alone.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from fractions import Fraction
from typing import Any, Final

import flint

from lyapcheck.models.engines.interval_field import BallLoop, Jet, LieDerivative, ball
from lyapcheck.models.engines.interval_region import (ATTEMPT_CELLS_NAME, IntervalClaim, IntervalProof, dyadic_floor,
                                                     low_order_terms, prove_bounded, prove_region)
from lyapcheck.models.language.parameter_box import ModelBox
from lyapcheck.models.language.recast import RecastModel, RecastSystem
from lyapcheck.models.classes.recast_classes import Loop, v_text
from lyapcheck.models.engines.recast_sos import poly_from_json, poly_to_json
from lyapcheck.models.engines.search import Budget
from lyapcheck.results import ConditionResult
from lyapcheck.exact import read_rational
from lyapcheck.models.classes.claims import INTERVAL_METHOD, interval_sentence

#: each retry lowers the proposed level by this factor (the proof failing near the level set's edge)
RETRY_LEVEL_FACTOR: Final = Fraction(9, 10)
#: proposals tried (the first level, then lowered)
INTERVAL_ATTEMPTS: Final = 3
#: the most cells the proof that the whole sublevel set lies in the box may take (a count, not a
#: time, so that the same model gives the same claim on any machine; without it the claim is the set
#: within the box, as proved)
WHOLE_SET_CELL_LIMIT: Final = 20_000
#: over a box of parameters, a proof that fails (not at a proved counterexample) is tried again on the
#: box's halves, down to this depth (at most 2^depth parts): the enclosures of a narrower part are
#: tighter (a parameter enters several entries of V''s Hessian, which the enclosure treats apart)
PARAMETER_SPLITS: Final = 3
#: what the route proves with, in every sentence and certificate
METHOD: Final = INTERVAL_METHOD
#: where the route proves nothing with V fitted over the ``[domain]`` (the fitting program infeasible:
#: no polynomial V of the fit's degree decreases at every converging sample of the box twice the
#: domain's size, as for a pendulum over +-pi; or the proof fails at every level tried), it is tried
#: again with V fitted to less, in this order, until one proves a set: each entry is (the share of
#: the domain, about the equilibrium, whose converging samples V is fitted to; the sampled box's size
#: over that part's, FIT_GROWTH = 2 at first). A count, not a time. A set proved from a part of the
#: domain lies in the region of attraction all the same, and its figures (roa_share) are taken over
#: the whole domain, so a larger domain never loses the set a smaller one gets from these attempts
DOMAIN_RETRIES: Final = ((Fraction(1), 1.5), (Fraction(1), 1.25), (Fraction(3, 4), 1.25), (Fraction(1, 2), 1.25))


@dataclass(frozen=True)
class Robust:
    """A loop's disturbances for a claim that holds for every one of their values: the loop recast
    with them as its last states (:attr:`lyapcheck.models.language.recast.RecastModel.robust`) and their
    bounds ``|d| <= b``."""

    system: RecastSystem
    bounds: dict[str, Fraction]
    #: the box of parameters among the bounds (their values are the box's centres, their bounds its
    #: half-widths), None without one
    box: ModelBox | None = None
    #: a part of the box a proof covers (name -> interval), where it was split (:meth:`halves`)
    part: dict[str, tuple[Fraction, Fraction]] | None = None

    def intervals(self) -> list[tuple[Fraction, Fraction]]:
        """Each constant's interval of values (a disturbance's ``[-b, b]``, a parameter's ``[lo, hi]``,
        or its part's)."""
        part = self.part or {}
        return [part.get(name, (self.system.values[name] - h, self.system.values[name] + h))
                for name, h in self.bounds.items()]

    def halves(self) -> tuple["Robust", "Robust"]:
        """The part of the box split in two at the middle of its widest parameter interval (exact)."""
        assert self.box is not None
        ranges = dict(zip(self.bounds, self.intervals()))
        name = max(self.box.names, key=lambda n: ranges[n][1] - ranges[n][0])
        lo, hi = ranges[name]
        mid = (lo + hi) / 2
        return (replace(self, part={**(self.part or {}), name: (lo, mid)}),
                replace(self, part={**(self.part or {}), name: (mid, hi)}))

    def balls(self) -> list[Any]:
        """Each constant's values as one ball (its interval, exactly enclosed)."""
        return [ball(lo).union(ball(hi)) for lo, hi in self.intervals()]

    def vanishes(self) -> bool:
        """``f(x_eq, d) = 0`` for every ``d`` in the bounds, proved: exactly by substitution
        (:func:`lyapcheck.models.language.recast.stays_put`), else each component's ball is exactly 0."""
        from lyapcheck.models.language.recast import stays_put

        if stays_put(self.system, tuple(self.bounds)):
            return True
        loop = BallLoop(self.system, self.balls())
        return all(not isinstance(v, Jet) and v.is_zero() for v in loop.field([flint.arb(0)] * loop.n))

    def embedded(self, ring: Any, V: Any) -> Any:
        """``V`` (over the nominal ring's states) in the robust ring (states, disturbances, auxiliaries)."""
        n = len(self.system.states) - len(self.bounds)
        size = self.system.ring.nvars
        return self.system.ring.from_terms({tuple(list(m[:n]) + [0] * (size - n)): c for m, c in ring.terms(V).items()})

    def to_json(self) -> dict[str, list[str]]:
        """The disturbances' bounds (a certificate's ``disturbances``; the box is ``parameter_box``)."""
        names = self.box.names if self.box is not None else ()
        return {d: [str(-b), str(b)] for d, b in self.bounds.items() if d not in names}

    def stamp(self, cert: dict[str, Any]) -> None:
        """Put what the claim covers into its certificate: the disturbances' bounds, the parameter box."""
        if self.to_json():
            cert["disturbances"] = self.to_json()
        if self.box is not None:
            cert["parameter_box"] = self.box.to_json()

    def matches(self, cert: dict[str, Any]) -> bool:
        """The certificate states exactly what this covers."""
        return cert.get("disturbances", {}) == self.to_json() and \
            cert.get("parameter_box") == (self.box.to_json() if self.box is not None else None)


def interval_roa(loop: Loop, budget: Budget, box: tuple[Any, Any], robust: Robust | None = None,
                 fit_steps: int | None = None) -> ConditionResult | str:
    """The ball-arithmetic region of attraction, or why there is none (one line): V fitted over the
    domain ``box`` first (:func:`_interval_roa_in`, the arguments' meaning there); where that proves
    nothing, V fitted over less of it (each of :data:`DOMAIN_RETRIES`), and of the sets those prove,
    the one covering most of the domain (:func:`domain_share`). The condition's ``tried`` then
    opens with the attempts that proved nothing or less, and ``fitted_domain_share`` says what share
    of the domain V was fitted to."""
    from lyapcheck.models.classes.fitted_v import FIT_GROWTH, fit_excluded
    from lyapcheck.models.engines.interval_region import SAFETY_NET

    found = _interval_roa_in(loop, budget, box, robust, fit_steps, FIT_GROWTH)
    if isinstance(found, ConditionResult) or fit_excluded(loop.system) is not None:
        return found  # (a loop the fit does not take fails the same way on any box)
    others = [f"V fitted over the domain: {found}"]
    best: tuple[float, str, float, ConditionResult] | None = None  # (its share of the domain, ...)
    lo, hi = box
    for share, growth in DOMAIN_RETRIES:
        if budget.left() <= 0:
            others.append(SAFETY_NET)
            break
        where = (f"V fitted over {'the domain' if share == 1 else f'{float(share):g} of the domain'}, sampled "
                 f"{growth:g} times as wide")
        found = _interval_roa_in(loop, budget, (lo * float(share), hi * float(share)), robust, fit_steps, growth)
        if isinstance(found, str):
            others.append(f"{where}: {found}")
            continue
        covers = domain_share(loop, found.certificate, box)
        if best is not None and covers <= best[0]:
            others.append(f"{where}: level {float(found.numbers['level']):.6g} proved, covering "
                          f"{100 * covers:.1f} % of the domain (less)")
            continue
        if best is not None:
            others.append(f"{best[1]}: level {float(best[3].numbers['level']):.6g} proved, covering "
                          f"{100 * best[0]:.1f} % of the domain (less)")
        best = (covers, where, float(share), found)
    if best is None:
        return "; ".join(others)
    covers, where, share_f, result = best
    result.numbers["tried"] = others + [f"{where}: {t}" for t in result.numbers.get("tried", [])] + \
        [f"{where}: covering {100 * covers:.1f} % of the domain (sampled)"]
    result.numbers["fitted_domain_share"] = share_f
    return result


def domain_share(loop: Loop, cert: dict[str, Any], box: tuple[Any, Any]) -> float:
    """The share of fixed uniform samples of the domain ``box`` (deviations) in an interval
    certificate's set (``{V <= level}``, within its box unless the whole set is proved to lie in it):
    which of several proved sets to state (each is proved; this only compares them)."""
    import numpy as np

    from lyapcheck.models.engines.recast_numeric import v_values

    claim = claim_of(loop, cert)
    lo, hi = (np.asarray(b, dtype=float) for b in box)
    Z = lo + (hi - lo) * np.random.default_rng(0).random((4000, loop.n))
    inside = v_values(loop.system, claim.V, Z) <= float(claim.level)
    if not cert.get("whole"):
        inside &= np.all((Z >= [float(x) for x in claim.lo]) & (Z <= [float(x) for x in claim.hi]), axis=1)
    return float(np.mean(inside))


def _interval_roa_in(loop: Loop, budget: Budget, box: tuple[Any, Any], robust: Robust | None,
                     fit_steps: int | None, growth: float) -> ConditionResult | str:
    """The ball-arithmetic region of attraction with V fitted over ``box`` (sampled ``growth`` times as
    wide, :func:`~lyapcheck.models.classes.fitted_v.fit_v`), or why there is none (one line). With ``robust``
    disturbances that vanish at the equilibrium, the set is proved for every disturbance value first
    (the claim then covers them: ``"all"``), else with them at 0. With a parameter box in ``robust``,
    only the claim for every value of it is tried (``loop`` is the box's centre). ``fit_steps``: the
    step budget of each trajectory simulated to fit V (:func:`~lyapcheck.models.classes.fitted_v.fit_v`)."""
    from lyapcheck.models.classes.fitted_v import Corners, fit_v

    # over a box of parameters V must serve every value: fitted at the box's corners as well
    corners = Corners.of(robust.system, robust.intervals()) if robust is not None and robust.box is not None else None
    fitted = fit_v(loop.system, loop.ring, box, corners, max_steps=fit_steps, growth=growth)
    if isinstance(fitted, str):
        return fitted
    v_from = "a V fitted to simulations of the true loop (linear program), proved by " + METHOD
    tried = ""
    what = ("value of the box and every disturbance value" if robust is not None and robust.box is not None
            and robust.to_json() else "value of the box" if robust is not None and robust.box is not None
            else "disturbance value")
    if robust is not None and not uses_auxiliaries(loop, fitted.claim.V):
        from lyapcheck.models.classes.fitted_v import propose_robust_level

        proposal = propose_robust_level(loop.system, robust.system, robust.intervals(), fitted.claim.V, box,
                                        growth) if robust.vanishes() else None
        if isinstance(proposal, IntervalClaim):
            found = _prove_lowering(loop, proposal, budget, "roa", v_from, {"sampled_share": fitted.sampled_share},
                                    robust)
            if isinstance(found, ConditionResult):
                if robust.to_json():
                    found.disturbances = "all"
                return found
            tried = f"for every {what}: {found}; "
        elif isinstance(proposal, str):
            tried = f"for every {what}: {proposal}; "
        else:
            tried = (f"the equilibrium is not proved to stay put for every {what} (f(x_eq, .) is not exactly 0 in "
                     "ball arithmetic): with them at 0; ")
    elif robust is not None:
        tried = f"for every {what}: the fitted V uses an auxiliary (a claim for every value takes V in the states); "
    if robust is not None and robust.box is not None:  # a claim at the centre alone says nothing of the box
        return tried.rstrip("; ").removesuffix(": with them at 0")
    found = _prove_lowering(loop, fitted.claim, budget, "roa", v_from, {"sampled_share": fitted.sampled_share})
    if isinstance(found, ConditionResult) and tried:
        found.numbers["robust_attempt"] = tried.rstrip("; ")
    return found if isinstance(found, ConditionResult) else tried + found


def _prove_lowering(loop: Loop, claim: IntervalClaim, budget: Budget, name: str, v_from: str,
                    numbers: dict[str, Any], robust: Robust | None = None) -> ConditionResult | str:
    """Prove the claim; where that fails, lower its level (under a point where ``V' >= 0`` was
    proved, else by RETRY_LEVEL_FACTOR) and try again, INTERVAL_ATTEMPTS times in all. Each attempt
    has a work budget, :data:`~lyapcheck.tolerances.INTERVAL_ATTEMPT_CELLS` cells, so that what is
    proved is the same on any machine and under any load; the class's time limit (``budget``)
    only stops a proof as a safety net, and the reason then says so."""
    import time

    from lyapcheck.models.engines.interval_region import SAFETY_NET
    from lyapcheck.tolerances import INTERVAL_ATTEMPT_CELLS

    reasons: list[str] = []
    for _ in range(INTERVAL_ATTEMPTS):
        if budget.left() <= 0:
            reasons.append(SAFETY_NET)
            break
        proof = prove(loop, claim, deadline=time.perf_counter() + budget.left(), robust=robust,
                      cells=INTERVAL_ATTEMPT_CELLS)
        if proof.ok:
            cert = certificate(loop, claim, proof)
            if robust is not None:
                robust.stamp(cert)
            return ConditionResult(name, "certified", interval_sentence(cert), property="ROA", certificate=cert,
                                   numbers={"level": float(claim.level), "V_from": v_from, "cells": proof.cells,
                                            "boundary_cells": proof.boundary_cells, "proof_seconds": proof.seconds,
                                            **numbers, "tried": reasons + [f"level {float(claim.level):.6g}: proved"]})
        reasons.append(f"level {float(claim.level):.6g}: {proof.why}")
        lower = claim.level * RETRY_LEVEL_FACTOR
        if proof.counterexample_v is not None:  # below the point where V' >= 0
            lower = min(lower, dyadic_floor(Fraction(proof.counterexample_v) * RETRY_LEVEL_FACTOR))
        if lower <= 0:
            break
        claim = IntervalClaim(claim.V, lower, claim.lo, claim.hi)
    return "ball arithmetic: " + "; ".join(reasons)


def uses_auxiliaries(loop: Loop, V: Any) -> bool:
    return any(any(m[loop.n:]) for m in loop.ring.terms(V))


def derivative_of(loop: Loop, V: Any) -> tuple[Any, bool] | str:
    """For a ``V`` that uses auxiliaries: its ball evaluator (``V' = G/D`` from the recasting's
    flows) and whether ``V`` and its gradient in the states vanish at the equilibrium (exact);
    ``(None, True)`` for a ``V`` over the states alone (the prover's own evaluator); or why not."""
    from lyapcheck.models.engines.interval_field import RecastLieDerivative
    from lyapcheck.models.classes.recast_classes import (_at_origin, common_denominator, for_v, gradient_at_equilibrium, lie,
                                                 v_names)

    if not uses_auxiliaries(loop, V):
        return None, True
    loop = for_v(loop, V)
    try:
        N, D, _ = common_denominator(loop, v_names(loop, V))
        G = lie(loop, V, N)
    except ValueError as exc:
        return str(exc)
    gradient = gradient_at_equilibrium(loop, V)
    flat = _at_origin(loop, V) == 0 and not isinstance(gradient, str) and not any(gradient)
    return RecastLieDerivative(BallLoop(loop.system), loop.ring, V, G, D), flat


def prove(loop: Loop, claim: IntervalClaim, deadline: float | None = None, robust: Robust | None = None,
          cells: int | None = None, cells_name: str = ATTEMPT_CELLS_NAME) -> IntervalProof:
    """:func:`prove_region` with the evaluator ``claim.V`` needs (one path for the search and ``verify``);
    with ``robust``, on the loop with every disturbance value in its bounds (``V`` over the states).
    ``cells``: the work budget of the whole attempt (every part of a box together), ``cells_name`` the
    constant it comes from (named when it is spent); None: each part within INTERVAL_CELL_LIMIT (``verify``)."""
    if robust is not None:
        if uses_auxiliaries(loop, claim.V) or low_order_terms(loop.ring, claim.V, loop.n):
            return IntervalProof(False, "a claim for every disturbance value takes a V over the states alone, "
                                        "without constant or linear terms", 0, 0, None, 0.0)
        if not robust.vanishes():
            return IntervalProof(False, "a disturbance moves the equilibrium", 0, 0, None, 0.0)
        return _prove_parts(loop, claim, deadline, robust, PARAMETER_SPLITS if robust.box is not None else 0,
                            None if cells is None else [cells], cells_name)
    how = derivative_of(loop, claim.V)
    if isinstance(how, str):
        return IntervalProof(False, how, 0, 0, None, 0.0)
    evaluator, flat = how
    return prove_region(loop.system, claim, deadline=deadline, lie=evaluator, flat=flat, cell_budget=cells,
                        budget_name=cells_name)


def _prove_parts(loop: Loop, claim: IntervalClaim, deadline: float | None, robust: Robust, depth: int,
                 cells: list[int] | None = None, cells_name: str = ATTEMPT_CELLS_NAME) -> IntervalProof:
    """The proof for every value of ``robust``'s constants; over a box, where it fails without a
    proved counterexample, on each half of the box (deterministic, so ``verify`` splits the same way).
    ``cells``: the cells left to the whole attempt (one counter shared by every part), or None."""
    lie = LieDerivative(BallLoop(robust.system, robust.balls()), robust.system.ring,
                        robust.embedded(loop.ring, claim.V))
    proof = prove_region(loop.system, claim, deadline=deadline, lie=lie, flat=True,
                         cell_budget=None if cells is None else max(cells[0], 0), budget_name=cells_name)
    if cells is not None:
        cells[0] -= proof.cells + proof.boundary_cells
    if proof.ok or depth == 0 or robust.box is None or proof.counterexample_v is not None:
        return proof
    if cells is not None and cells[0] <= 0:
        return proof  # the attempt's work budget is spent: its reason says so
    parts: list[IntervalProof] = []
    for half in robust.halves():  # in order, stopping at the first failure (the budget is shared)
        parts.append(_prove_parts(loop, claim, deadline, half, depth - 1, cells, cells_name))
        if not parts[-1].ok:
            break
    failed = next((p for p in parts if not p.ok), None)
    if failed is not None:
        return failed
    radii = [p.local_radius for p in parts if p.local_radius is not None]
    return IntervalProof(True, "", sum(p.cells for p in parts), sum(p.boundary_cells for p in parts),
                         min(radii) if radii else None, sum(p.seconds for p in parts))


def interval_candidate(loop: Loop, V: Any, budget: Budget, box: tuple[Any, Any], robust: Robust | None = None
                       ) -> ConditionResult | str:
    """``candidate``'s region by ball arithmetic: the user's ``V`` (it may use the loop's functions),
    its largest level where sampling sees ``V' < 0``, proved on the true field; with ``robust`` holding a
    box of parameters (``loop`` its centre), proved for every value of the box (the parameters as balls,
    the box split as ``roa``'s is; the level proposed at the centre, lowered where the proof fails)."""
    from lyapcheck.models.classes.fitted_v import propose_level

    proposal = propose_level(loop.system, V, box)
    if isinstance(proposal, str):
        return proposal
    return _prove_lowering(loop, proposal, budget, "candidate", "the candidate, proved by " + METHOD, {}, robust)


def certificate(loop: Loop, claim: IntervalClaim, proof: IntervalProof, deadline: float | None = None
                ) -> dict[str, Any]:
    """The certificate of a proved claim; for a ``V`` over the states alone, also the proof that the
    whole sublevel set lies in the box (``whole``), when it goes through (the claim then needs no box)."""
    system = loop.system
    ring = loop.ring
    cert = {"kind": "interval", "method": METHOD, "variables": list(ring.names), "auxiliaries": system.definitions(),
            "angles": [], "shift": {k: str(v) for k, v in system.values.items()},
            "V": poly_to_json(ring, claim.V), "V_text": v_text(system, claim.V), "level": str(claim.level),
            "box": {s: [str(a), str(b)] for s, a, b in zip(system.states, claim.lo, claim.hi)},
            "cells": proof.cells, "boundary_cells": proof.boundary_cells, "local_radius": str(proof.local_radius),
            "whole": False}
    if claim.exact_boundary:  # the faces proved exactly (V a quadratic form); the claim is the set in the box
        cert["boundary"] = "exact"
        return cert
    if not uses_auxiliaries(loop, claim.V):
        whole, _, outer_cells, R = prove_bounded(system, claim, deadline, cell_limit=WHOLE_SET_CELL_LIMIT)
        if whole:
            cert.update({"whole": True, "outer_radius": str(R), "outer_cells": outer_cells})
    return cert


def claim_of(loop: Loop, cert: dict[str, Any]) -> IntervalClaim:
    """The claim a certificate states (ValueError/KeyError when malformed)."""
    system = loop.system
    V = poly_from_json(loop.ring, cert["V"], "V")
    box = cert["box"]
    if list(box) != list(system.states):
        raise ValueError("box: one interval per state, in the states' order")
    lo = tuple(read_rational(box[s][0]) for s in system.states)
    hi = tuple(read_rational(box[s][1]) for s in system.states)
    if cert.get("boundary", "cells") not in ("cells", "exact"):
        raise ValueError("boundary: 'exact' or absent")
    return IntervalClaim(V, read_rational(cert["level"]), lo, hi, exact_boundary=cert.get("boundary") == "exact")


def box_units(model: RecastModel) -> dict[str, str] | None:
    """Each state's unit as ``[units]`` declares it (``''`` dimensionless), which a certificate's box
    is printed in (its ``units``); None without ``[units]``. ``verify`` re-makes it from the model."""
    from lyapcheck.models.language.dimensions import read_units

    if not model.units:
        return None
    table = read_units(model.units, model.states)
    return {s: "" if table.states[s][0].strip() in ("", "1") else table.states[s][0].strip() for s in model.states}


def check_interval(loop: Loop, c: dict[str, Any], robust: Robust | None = None) -> tuple[bool, str]:
    """``verify`` of an "interval" certificate: the same proof, run again from the certificate
    (``robust``: the model's disturbances, re-derived from its text, for a claim covering them)."""
    cert = c["certificate"]
    system = loop.system
    if cert.get("variables") != list(loop.ring.names) or cert.get("auxiliaries") != system.definitions() or \
            cert.get("shift") != {k: str(v) for k, v in system.values.items()}:
        return False, "variables, auxiliaries or shift differ from the recasting of the model text"
    if cert.get("angles") != [] or cert.get("method") != METHOD:
        return False, "an interval certificate is in the states themselves, proved by " + METHOD
    claim = claim_of(loop, cert)
    if c.get("level") is not None and c.get("level") != float(claim.level):
        return False, "the stated level is not the certificate's"
    boxed = robust is not None and robust.box is not None
    if c.get("disturbances") == "all" or boxed:
        if robust is None or not robust.matches(cert) or (c.get("disturbances") == "all") != bool(robust.to_json()):
            return False, ("a claim for every disturbance value or every value of a box needs the model's disturbances "
                           "and the box, with their bounds, in the certificate, and only those")
    elif "disturbances" in cert or "parameter_box" in cert:
        return False, "the certificate proves for every disturbance or parameter value but the claim does not say so"
    proof = prove(loop, claim, robust=robust if c.get("disturbances") == "all" or boxed else None)
    if not proof.ok:
        return False, f"the ball-arithmetic proof does not go through: {proof.why}"
    if cert.get("whole") not in (True, False):
        return False, "whole must be true or false"
    if cert["whole"]:
        whole, why, _, _ = prove_bounded(system, claim)
        if not whole:
            return False, f"the whole sublevel set is not proved to lie in the box: {why}"
    from lyapcheck.models.classes.claims import covered

    if c.get("summary") != covered(c.get("disturbances"), interval_sentence(cert)):
        return False, "the printed sentence is not the one the certificate supports"
    if cert.get("V_text") != v_text(system, claim.V):
        return False, "V_text is not V written with the functions"
    outside = "V > level everywhere outside the box, " if cert["whole"] else "V > level on the box's boundary, "
    flowed = ""
    if "flow" in cert:  # boxes proved to flow into the set: every one integrated again
        from lyapcheck.models.classes.flow_region import check_flow

        ok, why = check_flow(loop, cert)
        if not ok:
            return False, why
        flowed = f"; {why}"
    return True, (f"{outside}V' < 0 on the set ({proof.cells} cells, the equilibrium's box of half-width "
                  f"{proof.local_radius} by the Hessian), by {METHOD}{flowed}")


__all__ = ["interval_roa", "domain_share", "interval_candidate", "check_interval", "box_units", "METHOD"]
