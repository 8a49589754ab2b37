"""``roa`` and ``candidate`` on a polynomial or rational loop (the field multiplied through and scaled), and
the disturbances a stability class's claim covers.

``roa`` (:func:`run_roa`): the linearization's quadratic V and its sublevel sets enlarged by SOS
(:mod:`lyapcheck.models.classes.regions`), the certified set compared with, and cross-checked
against, simulations of the true loop (:class:`FieldSimulation`); on a nominal loop of 1 to 3 states with a
``[domain]``, the ball-arithmetic route's set beside it, the one covering more kept
(:mod:`lyapcheck.models.classes.field_ball_route`). ``candidate`` (:func:`run_candidate`):
the user's V, GAS where its decrease holds everywhere, else its largest certified level. Each is a list
of routes run by the one driver of the region classes (:mod:`lyapcheck.models.classes.region_driver`).
:func:`covering_disturbances`: a stability class tried robustly first (one V for every disturbance
value), then nominally.
"""

from __future__ import annotations

from dataclasses import dataclass
from fractions import Fraction
from typing import TYPE_CHECKING, Any, Callable, Final

from lyapcheck.models.engines.search import Budget, Search
from lyapcheck.models.language.modelfile import Model
from lyapcheck.models.loop.field import ScaledField, StateField, state_field
from lyapcheck.results import ConditionResult, Disturbances
from lyapcheck.sos.polynomials import Ring
from lyapcheck.timing import ClassTimeLimit

if TYPE_CHECKING:  # pragma: no cover
    import numpy as np

    from lyapcheck.models.classes.contexts import Candidate
    from lyapcheck.models.engines.numeric import SetCrossCheck

#: grid of simulated starts per state for the roa share, by number of states (beyond: random starts)
ROA_GRID: Final = {1: 401, 2: 101, 3: 21}
ROA_RANDOM_STARTS: Final = 4000
#: simulated time of the roa cross-check, in units of the loop's typical time
ROA_HORIZON: Final = 60.0


def covering_disturbances(model: Model, robust: StateField | None, nominal: StateField, enters: bool,
                          attempt: Callable[[StateField], ConditionResult]) -> ConditionResult:
    """A stability class on a model, saying which disturbances its claim covers (DESIGN.md,
    "Disturbances in claims"): without disturbances, the plain claim; where no disturbance enters
    the field (``enters`` false: a bound of 0, or one that acts on an output only), the nominal claim,
    which then covers them all; with disturbances that vanish at the equilibrium (``robust``), first
    the robust claim (``V`` common to every disturbance value, so it holds for every disturbance
    signal: ``"all"``), and only if that is not found the nominal one (``"zero"``, saying that the
    robust one was tried); otherwise (a disturbance moves the equilibrium) the nominal one
    (``"zero"``)."""
    if not model.disturbances:
        return attempt(nominal)
    if not enters:
        return covers(attempt(nominal), "all")
    if robust is not None:
        found = attempt(robust)
        if found.status in ("certified", "inconclusive"):
            return covers(found, "all")
        fallback = covers(attempt(nominal), "zero")
        if fallback.status == "certified":
            fallback.numbers["robust_attempt"] = found.summary
        return fallback
    return covers(attempt(nominal), "zero")


def covers(result: ConditionResult, disturbances: "Disturbances | None") -> ConditionResult:
    result.disturbances = disturbances
    return result


def simulated_region(scaled: ScaledField, samples_declared: np.ndarray) -> np.ndarray:
    """Which declared starts converge to the equilibrium (disturbances 0); over a box, at every
    parameter point of :func:`parameter_points` (its centre and corners)."""
    import numpy as np

    from lyapcheck.models.engines.numeric import converges, typical_time

    model = scaled.cleared.shifted.model
    half = _half_widths(model)
    converged = np.ones(len(samples_declared), dtype=bool)
    for params in parameter_points(scaled):
        T = typical_time(model, params)
        converged &= converges(model, samples_declared, t_end=ROA_HORIZON * T, radius=half * 1e-3, escape=half * 1e3,
                               parameters=params).converged
    return converged


def parameter_points(scaled: ScaledField) -> list[dict[str, Fraction]]:
    """The model's parameters, and over a box those at its centre and corners."""
    model = scaled.cleared.shifted.model
    box = scaled.cleared.shifted.box
    if box is None:
        return [dict(model.parameters)]
    centre = {name: box.center(name) for name in box.names}
    return [{**model.parameters, **centre}] + [{**model.parameters, **corner} for corner in box.corners()]


def _half_widths(model: Model) -> np.ndarray:
    import numpy as np

    if model.domain:
        return np.array([max(abs(float(model.domain[s][0] - e)), abs(float(model.domain[s][1] - e)))
                         for s, e in zip(model.states, model.equilibrium)])
    return np.ones(model.n)


def roa_starts(model: Model, seed: int = 0) -> np.ndarray:
    import numpy as np

    from lyapcheck.models.engines.numeric import grid_starts

    assert model.domain is not None
    per_axis = ROA_GRID.get(model.n)
    if per_axis is None:  # beyond ROA_GRID: random starts (two per axis would be the domain's corners alone)
        return grid_starts(model.domain, model.states, ROA_RANDOM_STARTS, ROA_RANDOM_STARTS, seed=seed)
    return grid_starts(model.domain, model.states, per_axis, per_axis ** model.n, seed=seed)


@dataclass
class FieldSimulation:
    """A polynomial loop's simulated region (:class:`~lyapcheck.models.classes.region_driver.SimulatedLoop`):
    the starts simulated (declared states, rows), which converged (:func:`simulated_region`), and a certified
    set's share of them and cross-check (:meth:`simulate`)."""

    scaled: ScaledField
    field: StateField
    starts: np.ndarray
    converged: np.ndarray

    @classmethod
    def of(cls, scaled: ScaledField, field_: StateField, memo: dict[str, Any]) -> "FieldSimulation":
        """The starts of ``memo`` (simulated once, kept there for the next attempt on the same loop: the
        robust and the nominal one simulate it with the disturbances at 0)."""
        import numpy as np

        model = scaled.cleared.shifted.model
        if "starts" not in memo:
            if model.domain:
                starts = roa_starts(model)
            else:
                A = np.array([[float(x) for x in row] for row in scaled.scaling.matrix()])
                eq = np.array([float(v) for v in model.equilibrium])
                rng = np.random.default_rng(0)
                starts = eq + rng.uniform(-4, 4, size=(ROA_RANDOM_STARTS if model.n > 2 else 2500, model.n)) @ A.T
            memo["starts"], memo["converged"] = starts, simulated_region(scaled, starts)
        return cls(scaled, field_, memo["starts"], memo["converged"])

    @property
    def samples(self) -> np.ndarray:
        """The starts in the scaled states (deviations)."""
        return self.scaled.scaling.to_scaled(self.starts - self._equilibrium())

    def _equilibrium(self) -> np.ndarray:
        import numpy as np

        return np.array([float(v) for v in self.scaled.cleared.shifted.model.equilibrium])

    def _set(self, result: ConditionResult) -> tuple[Callable[[np.ndarray], np.ndarray], float, np.ndarray]:
        """The certified set's V (of the scaled states, on rows) and level, from its certificate, and which
        starts lie in it."""
        from lyapcheck.models.classes import regions
        from lyapcheck.sos.certificates import GramPoly

        ring = self.field.ring
        poly = regions.NumericPoly(ring, GramPoly.from_json(result.certificate["gram_V"], ring.nvars).poly(ring))

        def V(Z: np.ndarray) -> np.ndarray:
            return poly(regions.on_states(self.field, Z))

        level = float(Fraction(result.certificate["level_scaled"]))
        return V, level, V(self.samples) <= level

    def share(self, result: ConditionResult) -> float:
        import numpy as np

        _, _, inside = self._set(result)
        return float(np.mean(inside[self.converged])) if self.converged.any() else 0.0

    def simulate(self, result: ConditionResult) -> None:
        """The share of the simulated region the set covers, and every start in it that did not converge
        simulated far longer, V watched (:func:`simulated_region_long`)."""
        import numpy as np

        model = self.scaled.cleared.shifted.model
        V, level, inside = self._set(result)
        converged = self.converged
        numbers = result.numbers
        numbers["simulated_starts"] = int(len(self.starts))
        if model.domain:
            if converged.any():  # (no simulated start converged in the horizon: no share to state, not a share of 0)
                numbers["roa_share"] = float(np.mean(inside[converged]))
            numbers["simulated_roa_share_of_domain"] = float(np.mean(converged))
        suspicious = inside & ~converged
        if suspicious.any():  # a start in a proved set that did not converge: simulate it far longer, V watched
            eq = self._equilibrium()

            def value(X: np.ndarray) -> np.ndarray:
                return V(self.scaled.scaling.to_scaled(np.atleast_2d(X) - eq))

            try:
                again = simulated_region_long(self.scaled, self.starts[suspicious], value, level)
            except ClassTimeLimit:  # the hard stop may end this check, never the proof before it
                numbers["long_simulation"] = "stopped by the class's hard time limit"
            else:
                numbers.update(again.numbers())


def run_roa(scaled: ScaledField, budget: Budget, linearization: ConditionResult | None,
            field_: StateField | None = None, memo: dict[str, Any] | None = None) -> ConditionResult:
    """The ``roa`` class on ``field_`` (default: the nominal :func:`state_field`; the robust one
    proves a set common to every disturbance value), by the routes of
    :func:`~lyapcheck.models.classes.region_driver.drive`. ``memo`` keeps the simulated starts between
    the robust and the nominal attempt (they simulate the same loop, with the disturbances at 0).
    On a nominal loop of 1 to 3 states a certified SOS set is compared with the ball-arithmetic
    route's over the same simulated starts (:func:`~lyapcheck.models.classes.field_ball_route.larger_region`)."""
    from lyapcheck.models.engines import reasons
    from lyapcheck.models.classes import regions
    from lyapcheck.models.classes.region_driver import OutOfTime, Route, drive

    if field_ is None:
        field_ = state_field(scaled)
    on = field_
    search = Search(on.ring, budget)
    if regions.lyapunov_quadratic(on) is None:
        why = reasons.reason("the Jacobian at the equilibrium is not Hurwitz"
                             + (" at the box's centre" if on.p > on.disturbances
                                else " with the disturbances at 0" if on.p else "")
                             + ", so no quadratic Lyapunov function starts the search (see linearization)",
                             ("candidate",))
        return ConditionResult("roa", "not_certified", why.summary, numbers=why.numbers(), property="ROA")
    simulation = FieldSimulation.of(scaled, on, {} if memo is None else memo)
    history: list[dict[str, Any]] = []

    def sos(budget: Budget) -> ConditionResult | str:
        """The linearization's quadratic V, its sublevel sets enlarged by SOS (:func:`regions.enlarge`)."""
        outcome = regions.enlarge(on, search, simulation.samples, simulation.converged)
        history[:] = outcome.history
        if outcome.certificate is None:
            return "no sublevel set passed the exact check"
        cert = outcome.certificate
        found = regions.level_result("roa", scaled, on, cert, search,
                                     {"degree": 2 * max(sum(m) for m in cert.V.basis), "rounds": outcome.history},
                                     "region of attraction")
        from lyapcheck.models.classes import field_ball_route

        model = scaled.cleared.shifted.model
        if not field_ball_route.takes(model, on.p == 0):
            return found
        # the ball route's set where it covers more (issue 41), compared over the same simulated starts: the
        # SOS set is simulated first, and the driver keeps whichever is returned as simulated
        simulation.simulate(found)
        return field_ball_route.larger_region(model, found, budget, simulation.starts, simulation.converged)

    routes = [Route("the linearization's quadratic V enlarged by SOS", sos)]

    def failed(tried: list[str]) -> ConditionResult:
        why = reasons.reason("no region of attraction was proved: no level set of the linearization's quadratic V "
                             "could be proved to shrink", ("domain", "candidate", "time"), tried)
        return ConditionResult("roa", "not_certified", why.summary, property="ROA",
                               solver={"solves": search.log}, numbers=why.numbers({"history": history}))

    return drive("roa", routes, budget, simulation, failed, OutOfTime("a region of attraction", ("time",)))


def simulated_region_long(scaled: ScaledField, starts: np.ndarray, value: Callable[[np.ndarray], np.ndarray],
                          level: float) -> SetCrossCheck:
    """Starts (declared states, rows) in the certified set ``{value <= level}`` that did not converge
    in the first simulation, simulated twenty times longer at every parameter point with V watched
    (:func:`lyapcheck.models.engines.numeric.check_certified_set`): a violation only where one leaves the
    set (the certificate gives no decrease rate to bound the time to converge); the others, still
    converging, are not checked."""
    import numpy as np

    from lyapcheck.models.engines.numeric import FieldEvaluator, ModelSystem, SetCrossCheck, check_certified_set, typical_time
    from lyapcheck.models.engines.trajectories import RTOL

    model = scaled.cleared.shifted.model
    half = _half_widths(model)
    eq = np.array([float(v) for v in model.equilibrium])
    left = np.zeros(len(starts), dtype=bool)
    converged = np.ones(len(starts), dtype=bool)
    for params in parameter_points(scaled):
        system = ModelSystem(FieldEvaluator.of(model, params), len(starts), escape=half * 1e3, center=eq)
        found = check_certified_set(system, starts, 20 * ROA_HORIZON * typical_time(model, params), value=value,
                                    level=level, converged=lambda X: np.all(np.abs(X - eq) <= half * 1e-3, axis=1),
                                    rtol=RTOL, atol=half * 1e-6, max_iterations=200_000)
        left |= found.left
        converged &= found.converged
    return SetCrossCheck(left=left, overdue=np.zeros(len(starts), dtype=bool), converged=converged & ~left)


def run_candidate(scaled: ScaledField, cand: "Candidate | None", budget: Budget) -> ConditionResult:
    """The user's V on the nominal field, by the routes of :func:`~lyapcheck.models.classes.region_driver.drive`:
    GAS where its decrease is proved everywhere, else its largest level proved
    (:func:`lyapcheck.models.classes.regions.largest_level`). Over a box (the field's ring carries the box's
    normalized parameters after the states, :attr:`StateField.p`) V is of the states alone and both proofs hold
    for every value of the box at once: the box's multipliers join the decrease's identity and the level
    program's, and the certificate states the box (``parameter_box``)."""
    import numpy as np

    from lyapcheck.models.engines import reasons
    from lyapcheck.models.classes import regions
    from lyapcheck.models.classes.lyapunov import best_decay_rate, stated_v
    from lyapcheck.models.classes.region_driver import OutOfTime, Route, drive
    from lyapcheck.sos.polynomials import to_fmpq

    assert cand is not None
    model = scaled.cleared.shifted.model
    box = scaled.cleared.shifted.box
    field_ = state_field(scaled)
    ring = field_.ring
    search = Search(ring, budget)
    full = model.state_ring
    # V(x_eq + S z): the candidate in the scaled states
    from lyapcheck.models.loop.field import linear_images

    images = linear_images(full, model.n, scaled.scaling.matrix())
    images = [im + to_fmpq(e) for im, e in zip(images[:model.n], model.equilibrium)] + images[model.n:]
    states = Ring(ring.names[:field_.n])
    v_states = full.restrict(full.compose(cand.poly, images), states)
    # (over a box, in the ring with the box's parameters after the states, at exponent 0: one V for the box)
    v_scaled = ring.from_terms({m + (0,) * field_.p: c for m, c in states.terms(v_states).items()})
    # (over a box: for every value of it, and the box's words where the proof fails)
    every = " for every value of the box" if box is not None else ""
    stamp = {"parameter_box": box.to_json()} if box is not None else {}
    V = regions.gram_of(field_, v_scaled, search)
    if V is None:
        why = reasons.reason("the candidate V could not be proved positive definite and radially unbounded",
                             ("other_candidate",), "no positive definite Gram matrix over its reduced basis with a "
                             "pure power of every state")
        return ConditionResult("candidate", "not_certified", why.summary, numbers=why.numbers(),
                               solver={"solves": search.log}, property="ROA")
    gram = V

    def gas(budget: Budget) -> ConditionResult | str:
        """V' < 0 away from the equilibrium everywhere (for every value of a box), its best decay rate."""
        decrease = regions.global_decrease(field_, gram, Fraction(0), search)
        if decrease is None:
            return f"V' < 0 was not proved everywhere{every}"

        def attempt(mu: Fraction) -> dict[str, Any] | None:
            s = regions.global_decrease(field_, gram, mu, search)
            return None if s is None else {"found": s, "mu": mu}

        best = best_decay_rate(attempt, {"found": decrease, "mu": Fraction(0)})
        found: regions.GlobalDecrease = best["found"]
        rate = float(best["mu"] / scaled.scaling.time)
        tail = f", V' <= -{rate:.4g} V" if best["mu"] > 0 else ""
        certificate: dict[str, Any] = {"kind": "lyapunov", "mu_scaled": str(best["mu"]),
                                       "V": stated_v(scaled, field_, gram.poly(ring)), "gram_V": gram.to_json(),
                                       "gram_sigma": found.sigma.to_json()}
        if found.box:
            certificate["box_multipliers"] = [{"variable": j, "gram": r.to_json()} for j, r in found.box]
        return ConditionResult("candidate", "certified", f"GAS: V' < 0 away from the equilibrium everywhere{tail}"
                                                         f"{every} (checked exactly)",
                               numbers={"decay_rate_V_per_s": rate}, certificate={**certificate, **stamp},
                               solver={"solves": search.log}, property="GAS")

    #: the level route's sentence and figures where it proves none (which search it ran)
    missed: dict[str, Any] = {}

    def level(budget: Budget) -> ConditionResult | str:
        """V's largest level proved: below the sampled points where V' >= 0, or upwards where none was sampled."""
        radius = float(np.max(np.abs(scaled.scaling.to_scaled(np.diag(_half_widths(model)))))) * 4
        top = regions.supremum_estimate(field_, gram, radius)  # (over a box: at its centre and corners)
        if top is None:
            # no sample with V' >= 0 out to 4 half-widths: search the level upwards from V's largest
            # value there, each step an SOS lower bound of min {V : V' >= 0} (no sample needed)
            rng = np.random.default_rng(0)
            ball = rng.normal(size=(200, field_.n))
            ball *= radius / np.linalg.norm(ball, axis=1, keepdims=True)
            guess = float(np.max(regions.NumericPoly(ring, gram.poly(ring))(regions.on_states(field_, ball))))
            cert = regions.largest_level(field_, gram, search, guess, regions.symmetry(field_), grow=True)
            if cert is None:
                missed.update(sentence=f"V' < 0 could not be proved everywhere{every}, nor on any level set "
                                       "{V <= c} (no point with V' >= 0 was sampled)",
                              steps=("other_candidate", "domain", "time"), numbers={})
                return f"no level from {guess:.6g} upwards passed the level program"
            return _stamped(regions.level_result("candidate", scaled, field_, cert, search,
                                                 {"level_search": "upwards, by SOS"}, "the user's V"), stamp)
        cert = regions.largest_level(field_, gram, search, top, regions.symmetry(field_))
        if cert is None:
            where = " (sampled at the box's centre and corners)" if box is not None else ""
            missed.update(sentence=f"V' < 0 could not be proved everywhere{every}, nor on any level set {{V <= c}} "
                                   f"below the sampled points where V' >= 0 (V = {top:.6g}){where}",
                          steps=("other_candidate", "time"), numbers={"level_supremum_estimate": top})
            return f"no level of V passed the exact check (sampled supremum {top:.6g})"
        return _stamped(regions.level_result("candidate", scaled, field_, cert, search,
                                             {"level_supremum_estimate": top,
                                              "level_ratio_to_estimate": float(cert.level) / top}, "the user's V"),
                        stamp)

    routes = [Route("GAS: V decreasing everywhere, by SOS", gas), Route("V's largest level, by SOS", level)]

    def failed(tried: list[str]) -> ConditionResult:
        # (the level route is the last to run: its sentence says what neither proved)
        why = reasons.reason(missed["sentence"], missed["steps"], tried)
        return ConditionResult("candidate", "not_certified", why.summary, numbers=why.numbers(missed["numbers"]),
                               solver={"solves": search.log}, property="ROA")

    # (one route is kept, never compared by its share: the loop is simulated only for a certified level set,
    # whose share of the simulated region of attraction the result then states, as roa's does)
    return drive("candidate", routes, budget, SimulatedWhenCertified(scaled, field_), failed,
                 OutOfTime("a proof with the candidate V", ("time",)))


@dataclass
class SimulatedWhenCertified:
    """A :class:`~lyapcheck.models.classes.region_driver.SimulatedLoop` that simulates the loop only when a
    set is certified (``candidate``: the user's V is proved, not compared with other sets, so a run that
    proves nothing, or proves GAS, spends no time simulating); then as :class:`FieldSimulation`."""

    scaled: ScaledField
    field: StateField

    def simulate(self, result: ConditionResult) -> None:
        try:
            FieldSimulation.of(self.scaled, self.field, {}).simulate(result)
        except ClassTimeLimit:  # (the hard stop may end the simulation, never the proof before it)
            result.numbers["simulation"] = "stopped by the class's hard time limit"

    def share(self, result: ConditionResult) -> float:
        return FieldSimulation.of(self.scaled, self.field, {}).share(result)


def _stamped(result: ConditionResult, stamp: dict[str, Any]) -> ConditionResult:
    """A certified result's certificate with the box it holds over (``parameter_box``; none at a point)."""
    result.certificate.update(stamp)
    return result


__all__ = ["ROA_GRID", "ROA_RANDOM_STARTS", "ROA_HORIZON", "covering_disturbances", "covers", "simulated_region",
           "parameter_points", "roa_starts", "FieldSimulation", "SimulatedWhenCertified", "run_roa",
           "simulated_region_long", "run_candidate"]
