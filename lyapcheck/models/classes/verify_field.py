"""The exact check of each class's certificate on a polynomial or rational loop, one callable per class
(the ``verify_field`` of its entry in :mod:`lyapcheck.models.classes.registry`).

Each takes a decided condition as stored (``c``) and the :class:`~lyapcheck.models.classes.contexts.FieldCheck`
verify re-derived from the model text (and its class's name), and returns ``(ok, why)``; a malformed certificate raises
(``KeyError``, ``ValueError``, ...), which verify reports in one row. A ball-arithmetic region is
checked on the true field instead (:mod:`lyapcheck.models.surfaces.ball_roa`), before the field is
multiplied through.
"""

from __future__ import annotations

from fractions import Fraction
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:  # pragma: no cover
    from lyapcheck.models.classes.contexts import FieldCheck
    from lyapcheck.models.loop.field import ScaledField


def _scaled(check: "FieldCheck") -> "ScaledField":
    """The cleared and scaled field (verify builds it before any class but linearization is checked)."""
    if check.scaled is None:
        raise ValueError("the field was not multiplied through (its denominators' proofs are checked first)")
    return check.scaled


def verify_linearization(name: str, c: dict[str, Any], check: "FieldCheck") -> tuple[bool, str]:
    """``linearization``: the Jacobian's certificate (or refutation), at the model's parameters or for
    every value of its box."""
    from lyapcheck.models.classes import linearization

    data = c.get("certificate") if c["status"] == "certified" else c.get("refutation")
    if check.shifted.box is not None:  # the Jacobian for every value of the box
        return linearization.verify_over_box(check.shifted, c["status"], data or {})
    return linearization.verify(check.shifted, c["status"], data or {})


def _multipliers(data: Any, nvars: int, first: int) -> list[tuple[int, Any]]:
    """A certificate's box multipliers, each on a box parameter (index >= ``first``): a multiplier on
    a state would restrict the states, so any other index makes the certificate malformed."""
    from lyapcheck.models.engines.search import box_multipliers_from_json

    out = box_multipliers_from_json(data or [], nvars)
    if any(not first <= j < nvars for j, _ in out):
        raise ValueError("a box multiplier must act on a box parameter")
    return out


def _gram(data: dict[str, Any], nvars: int) -> Any:
    from lyapcheck.sos.certificates import GramPoly

    return GramPoly.from_json(data, nvars)


def _v_matches(scaled: Any, field: Any, V: Any, stated: dict[str, Any], v0: Fraction = Fraction(0)) -> bool:
    """The stated V (declared states) is the Gram V (scaled states, plus a constant) unscaled, exactly,
    and its exponents are integers (a JSON ``2.0`` equals ``2`` in Python; it is refused here)."""
    from lyapcheck.models.classes.lyapunov import stated_v

    _check_terms(stated)
    return stated_v(scaled, field, V.poly(field.ring) + field.ring.constant(v0)) == stated


def _check_terms(stated: Any) -> None:
    """A stated polynomial's form: ``{"terms": [[coefficient, [exponent, ...]], ...]}`` with
    non-negative integer exponents (ValueError naming the key otherwise)."""
    from lyapcheck.sos.certificates import exponent

    if not isinstance(stated, dict) or not isinstance(stated.get("terms"), list):
        raise ValueError("V must be a table with a list 'terms'")
    for term in stated["terms"]:
        if not isinstance(term, list) or len(term) != 2 or not isinstance(term[1], list):
            raise ValueError(f"V: a term must be [coefficient, [exponents]], got {term!r}")
        for e in term[1]:
            exponent(e, "V.terms")


def _at_most(stated: Any, proved: Fraction) -> bool:
    return stated is None or Fraction(float(stated)) <= proved + abs(proved) / 10**12


def _at_least(stated: Any, proved: Fraction) -> bool:
    return stated is None or Fraction(float(stated)) >= proved - abs(proved) / 10**12


def _verify_vertices(c: dict[str, Any], cert: dict[str, Any], scaled: Any, field: Any) -> tuple[bool, str]:
    """A Lyapunov certificate in the vertex form (``form = "vertices"``, the vertex form of
    :mod:`lyapcheck.models.classes.lyapunov`): ``V(z, u)`` exact (``V_scaled``), a Gram matrix of ``V`` and of the remainder at
    each vertex of the box, checked exactly (:func:`~lyapcheck.sos.certificates.check_lyapunov_vertices`)."""
    from lyapcheck.sos.certificates import check_lyapunov_vertices

    if not field.p or field.disturbances:
        return False, "a certificate in the vertex form is for a box of parameters (and no disturbance)"
    if not isinstance(cert.get("gram_V_vertices"), list) or not isinstance(cert.get("gram_sigma_vertices"), list):
        return False, "a certificate in the vertex form has lists 'gram_V_vertices' and 'gram_sigma_vertices'"
    ring, nv = field.ring, field.ring.nvars
    _check_terms(cert["V_scaled"])
    if any(len(m) != nv for _, m in cert["V_scaled"]["terms"]):
        return False, f"V_scaled: a monomial must have {nv} exponents"
    V, differs = _scaled_and_stated(scaled, field, cert, "V", "V_scaled")
    if differs is not None:
        return False, differs
    positive = [_gram(part, nv) for part in cert["gram_V_vertices"]]
    sigmas = [_gram(part, nv) for part in cert["gram_sigma_vertices"]]
    mu = Fraction(cert["mu_scaled"])
    ok, why = check_lyapunov_vertices(ring, field.g, field.D, V, positive, sigmas, mu)
    if not ok:
        return False, why
    if not _at_most(c.get("decay_rate_V_per_s"), mu / scaled.scaling.time):
        return False, "the stated decay rate of V exceeds the certified one"
    if c.get("property") not in ("GAS", None):
        return False, f"a Lyapunov certificate in the vertex form proves GAS, not {c.get('property')}"
    return True, why


def _verify_cliques(c: dict[str, Any], cert: dict[str, Any], scaled: Any, field: Any) -> tuple[bool, str]:
    """A Lyapunov certificate in the clique form (kind ``lyapunov_cliques``, :func:`lyapcheck.models.
    classes.lyapunov.clique_search`): ``V`` and the remainder sums of Gram matrices, checked exactly
    (:func:`~lyapcheck.sos.certificates.check_lyapunov_cliques`)."""
    from lyapcheck.sos.certificates import GramSum, check_lyapunov_cliques

    if field.p:
        return False, "a certificate in the clique form is for a field without box coordinates"
    if not isinstance(cert.get("gram_V"), list) or not isinstance(cert.get("gram_sigma"), list):
        return False, "a certificate in the clique form has lists 'gram_V' and 'gram_sigma'"
    nv = field.ring.nvars
    V = GramSum(tuple(_gram(part, nv) for part in cert["gram_V"]))
    sigma = GramSum(tuple(_gram(part, nv) for part in cert["gram_sigma"]))
    if not _v_matches(scaled, field, V, cert["V"]):
        return False, "the stated V (declared states) is not the certificate's Gram V unscaled"
    mu = Fraction(cert["mu_scaled"])
    ok, why = check_lyapunov_cliques(field.ring, field.g, field.D, V, sigma, mu)
    if not ok:
        return False, why
    if not isinstance(cert.get("cliques"), list) or len(cert["cliques"]) != len(V.parts):
        return False, "'cliques' must name the states of each of V's Gram matrices"
    if not _at_most(c.get("decay_rate_V_per_s"), mu / scaled.scaling.time):
        return False, "the stated decay rate of V exceeds the certified one"
    if c.get("property") not in ("GAS", None):
        return False, f"a Lyapunov certificate in the clique form proves GAS, not {c.get('property')}"
    return True, why


def verify_sos_bound(name: str, c: dict[str, Any], check: "FieldCheck") -> tuple[bool, str]:
    """``sos_bound``: each output's dissipation and output identities, its bound and its figures."""
    from lyapcheck.models.classes.bounds import bound_figures, output_deviation
    from lyapcheck.models.loop.field import StateField
    from lyapcheck.sos.certificates import check_dissipation, check_output_bound

    scaled = _scaled(check)
    cert = c["certificate"]
    ring = scaled.ring
    nv = ring.nvars
    names = list(scaled.outputs)
    for out, data in cert["outputs"].items():
        if out not in scaled.outputs:
            return False, f"no output named {out}"
        y, _ = output_deviation(scaled, out)  # y - y_eq, as the sentence says (lyapcheck.models.classes.bounds)
        s_y = scaled.scaling.outputs[names.index(out)]
        V = _gram(data["gram_V"], nv)
        taus = [_gram(t, nv) for t in data["gram_tau"]]
        lam, B = Fraction(data["lam_scaled"]), Fraction(data["B_scaled"])
        v0 = Fraction(data.get("V_constant", "0"))
        first = scaled.n + scaled.m
        box_d = _multipliers(data.get("box_multipliers_D"), nv, first)
        box_e = _multipliers(data.get("box_multipliers_E"), nv, first)
        if any(any(m[scaled.n:]) for m in V.basis):
            return False, f"output {out}: V may depend on the states only"
        ok, why = check_dissipation(ring, scaled.g, scaled.D, scaled.bounds, V, lam, taus,
                                    _gram(data["gram_sigma_D"], nv), box_d, v0)
        if not ok:
            return False, f"output {out}: {why}"
        ok, why = check_output_bound(ring, V, y, B, _gram(data["gram_sigma_E"], nv), box_e, v0)
        if not ok:
            return False, f"output {out}: {why}"
        bound = Fraction(data["bound"])
        if bound < 0 or bound * bound < B * s_y * s_y:
            return False, f"output {out}: the stated bound {data['bound']} is below s_y sqrt(B)"
        if not _at_least(c.get("bounds", {}).get(out), bound):
            return False, f"output {out}: the stated figure is below the certified bound"
        if not _v_matches(scaled, StateField(ring=ring, g=scaled.g, D=scaled.D), V, data["V"], v0):
            return False, f"output {out}: the stated V is not the certificate's"
    figures = bound_figures(scaled, list(cert["outputs"]))
    if set(c.get("bounds", {})) != set(cert["outputs"]):
        return False, "a bound is stated for an output the certificate does not bound"
    if any(c.get(key) != figures.get(key) for key in ("bounds_reference", "bounds_unit")):
        return False, "the bounds' reference points (bounds_reference) or units (bounds_unit) are not the model's"
    return True, "every output's dissipation and output identities hold exactly"


def verify_barrier(name: str, c: dict[str, Any], check: "FieldCheck") -> tuple[bool, str]:
    """``barrier`` (:func:`_verify_barrier`)."""
    return _verify_barrier(c, c["certificate"], _scaled(check))


def verify_reach_avoid(name: str, c: dict[str, Any], check: "FieldCheck") -> tuple[bool, str]:
    """``reach_avoid`` (:func:`_verify_reach_avoid`)."""
    return _verify_reach_avoid(c, c["certificate"], _scaled(check))


def verify_lyapunov(name: str, c: dict[str, Any], check: "FieldCheck") -> tuple[bool, str]:
    """``quadratic``, ``sos_gas``, ``roa`` and ``candidate``: a Lyapunov certificate (GAS, or GES with
    :func:`_verify_ges`; in the clique or the vertex form too) or a sublevel set's (ROA), on the robust
    field where the claim covers every disturbance."""
    from lyapcheck.models.loop.field import state_field
    from lyapcheck.sos.certificates import check_containment, check_lyapunov, check_quadratic_ball, check_sublevel

    scaled = _scaled(check)
    cert = c["certificate"]
    if c.get("cone") != cert.get("cone"):  # the method the condition names (SDSOS, DSOS) is the certificate's
        return False, "the condition's cone is not the certificate's"
    field = state_field(scaled)
    if c.get("disturbances") == "all":
        from lyapcheck.models.loop.field import active_disturbances, robust_field

        if active_disturbances(scaled):
            robust = robust_field(scaled)
            if robust is None:
                return False, ("'disturbances': 'all' is claimed, but a disturbance moves the equilibrium, so no "
                               "stability claim can hold for every disturbance")
            field = robust
    if cert.get("kind") == "lyapunov_cliques":
        return _verify_cliques(c, cert, scaled, field)
    if cert.get("kind") == "lyapunov_vector":
        from lyapcheck.models.classes import vector_lyapunov

        return vector_lyapunov.verify(c, cert, scaled, field)
    if cert.get("kind") == "lyapunov_cascade":
        from lyapcheck.models.classes import cascade_lyapunov

        return cascade_lyapunov.verify(c, cert, scaled, field)
    if cert.get("kind") == "lyapunov" and cert.get("form") == "vertices":
        return _verify_vertices(c, cert, scaled, field)
    box_json = scaled.cleared.shifted.box.to_json() if scaled.cleared.shifted.box is not None else None
    if ("parameter_box" in cert or (name == "candidate" and box_json is not None)) \
            and cert.get("parameter_box") != box_json:
        return False, "a candidate over a box states that box (parameter_box) as the document's, and only then"
    ring, n = field.ring, field.n
    nv = ring.nvars
    V = _gram(cert["gram_V"], nv)
    box = _multipliers(cert.get("box_multipliers"), nv, n)
    if any(any(m[n:n + field.disturbances]) for m in V.basis):
        return False, "V may not depend on a disturbance"
    if not _v_matches(scaled, field, V, cert["V"]):
        return False, "the stated V (declared states) is not the certificate's Gram V unscaled"
    kind = cert.get("kind")
    T = scaled.scaling.time
    if kind == "lyapunov":
        mu = Fraction(cert["mu_scaled"])
        ok, why = check_lyapunov(ring, field.g, field.D, V, _gram(cert["gram_sigma"], nv), mu, box)
        if not ok:
            return False, why
        if not _at_most(c.get("decay_rate_V_per_s"), mu / T):
            return False, "the stated decay rate of V exceeds the certified one"
        if c.get("property") == "GES":
            return _verify_ges(scaled, V, mu, cert, c)
        if c.get("property") not in ("GAS", None):
            return False, f"a Lyapunov certificate proves GAS (or GES), not {c.get('property')}"
        return True, why
    if kind in ("sublevel", "quadratic_ball"):
        level = Fraction(cert["level_scaled"])
        if Fraction(cert["level"]) != level or not _at_most(c.get("level"), level):
            return False, "the stated level is not the certified one"
        if kind == "sublevel":
            ok, why = check_sublevel(ring, field.g, V, level, _gram(cert["gram_s"], nv), _gram(cert["gram_sigma"], nv),
                                     box)
        elif box:
            return False, "a quadratic-ball certificate has no box multipliers"
        else:
            ok, why = check_quadratic_ball(ring, field.g, V, level, Fraction(cert["radius_scaled"]),
                                           Fraction(cert["lambda"]), Fraction(cert["p_bar"]), Fraction(cert["m"]))
        if not ok:
            return False, why
        if "ball" in cert:
            from lyapcheck.models.classes.regions import radius_polynomial, states_only
            from lyapcheck.sos.polynomials import Ring

            sring = Ring(ring.names[:n])
            r = Fraction(cert["ball"]["radius"])
            ok, why2 = check_containment(sring, states_only(V, n), level, radius_polynomial(sring, scaled.scaling), r * r,
                                         _gram(cert["ball"]["gram_s"], n), _gram(cert["ball"]["gram_sigma"], n))
            if not ok or not _at_most(c.get("ball_radius"), r):
                return False, f"the ball: {why2 if not ok else 'the stated radius exceeds the certified one'}"
        elif c.get("ball_radius") is not None:
            return False, "a ball radius is stated without its certificate"
        if c.get("property") != "ROA":
            return False, f"a {kind} certificate proves a region of attraction (ROA)"
        return True, why
    return False, f"unknown certificate kind {kind!r}"


def _verify_barrier(c: dict[str, Any], cert: dict[str, Any], scaled: Any) -> tuple[bool, str]:
    """A barrier certificate on the robust field (every disturbance that enters a box coordinate),
    with the sets re-read from the model (a widened initial set or a shrunk unsafe set in the
    model's text makes an identity fail), B stated in the declared states as its scaled form."""
    from lyapcheck.sos.certificates import check_barrier

    if cert.get("kind") != "barrier":
        return False, f"a barrier's certificate kind must be 'barrier', not {cert.get('kind')!r}"
    if c.get("property") != "safety":
        return False, "a barrier certificate proves safety"
    _, sets = _model_sets(scaled)
    if not sets.get("initial") or not sets.get("unsafe"):
        return False, "the model has no [sets] initial and unsafe for a barrier"
    field, initial, unsafe = _robust_pieces(scaled, sets)
    ring, n = field.ring, field.n
    nv = ring.nvars
    B, differs = _scaled_and_stated(scaled, field, cert, "B")
    if differs is not None:
        return False, differs

    lam = Fraction(cert["lambda_scaled"])
    box = _multipliers(cert.get("box_multipliers"), nv, n)
    ok, why = check_barrier(ring, field.g, field.D, B, lam, initial, _set_pieces(cert, "initial", len(initial), nv),
                            unsafe, _set_pieces(cert, "unsafe", len(unsafe), nv), _gram(cert["gram_decrease"], nv), box)
    if not ok:
        return False, why
    stated = c.get("lambda_per_s")
    if stated is not None and abs(float(stated) - float(lam / scaled.scaling.time)) > 1e-9 * (1 + abs(float(stated))):
        return False, "the stated rate lambda_per_s is not the certificate's"
    return True, why


def _model_sets(scaled: Any) -> tuple[Any, dict[str, Any]]:
    """The model and its ``[sets]`` (empty without), read again from the model's text."""
    model = scaled.cleared.shifted.model
    return model, getattr(model, "sets", None) or {}


def _robust_pieces(scaled: Any, sets: dict[str, Any]) -> tuple[Any, Any, Any]:
    """The robust field (every disturbance that enters a box coordinate) and the initial and unsafe sets'
    pieces in its scaled coordinates."""
    from lyapcheck.models.classes.barrier import scaled_pieces
    from lyapcheck.models.loop.field import state_field

    field = state_field(scaled, robust=True)
    return field, scaled_pieces(scaled, field, sets["initial"]), scaled_pieces(scaled, field, sets["unsafe"])


def _scaled_and_stated(scaled: Any, field: Any, cert: dict[str, Any], name: str, scaled_name: str | None = None
                       ) -> tuple[Any, str | None]:
    """A certificate's polynomial ``cert[name + "_scaled"]`` (scaled coordinates, exactly) and None, or why
    its stated form ``cert[name]`` (declared states) is not it unscaled (``scaled_name``: what the reason
    calls the scaled one, ``name`` by default)."""
    from lyapcheck.models.classes.lyapunov import stated_v
    from lyapcheck.sos.certificates import exponent

    key = f"{name}_scaled"
    P = field.ring.from_terms({tuple(exponent(e, key) for e in m): Fraction(v) for v, m in cert[key]["terms"]})
    _check_terms(cert[name])
    if stated_v(scaled, field, P) != cert[name]:
        return P, f"the stated {name} (declared states) is not the certificate's {scaled_name or name} unscaled"
    return P, None


def _set_pieces(cert: dict[str, Any], key: str, count: int, nv: int) -> list[tuple[list[Any], Any]]:
    """A barrier's or reach-avoid's multipliers and remainder for each piece of one set (``key``: "initial",
    "unsafe", ...), one entry per piece."""
    data = cert[key]
    if not isinstance(data, list) or len(data) != count:
        raise ValueError(f"{key}: one entry per piece of the set is needed")
    return [([_gram(g, nv) for g in item["multipliers"]], _gram(item["remainder"], nv)) for item in data]


def _verify_reach_avoid(c: dict[str, Any], cert: dict[str, Any], scaled: Any) -> tuple[bool, str]:
    """A reach-avoid certificate on the robust field, the sets re-read from the model's text, V
    stated in the declared states as its scaled form, and the stated time bound the certified one."""
    from lyapcheck.models.classes.barrier import scaled_pieces
    from lyapcheck.sos.certificates import check_reach_avoid

    if cert.get("kind") != "reach_avoid":
        return False, f"a reach_avoid certificate's kind must be 'reach_avoid', not {cert.get('kind')!r}"
    if c.get("property") != "reach_avoid":
        return False, "a reach_avoid certificate proves reach_avoid"
    model, sets = _model_sets(scaled)
    if not sets.get("initial") or not sets.get("unsafe") or len(sets.get("goal") or ()) != 1:
        return False, "the model has no [sets] initial, unsafe and a one-piece goal for reach_avoid"
    field, initial, unsafe = _robust_pieces(scaled, sets)
    ring, n = field.ring, field.n
    nv = ring.nvars
    (goal,) = scaled_pieces(scaled, field, sets["goal"])
    V, differs = _scaled_and_stated(scaled, field, cert, "V")
    if differs is not None:
        return False, differs

    if "stay" in cert:  # reach {W <= 0}, inside the goal and never left, instead of the goal itself
        from lyapcheck.sos.certificates import check_goal_invariant

        stay = cert["stay"]
        W, differs = _scaled_and_stated(scaled, field, stay, "W")
        if differs is not None:
            return False, differs
        ok, why = check_goal_invariant(ring, field.g, field.D, W, Fraction(stay["mu_scaled"]), goal,
                                       [_gram(g, nv) for g in stay["inside"]], _gram(stay["gram_invariant"], nv),
                                       _multipliers(stay.get("box_multipliers"), nv, n))
        if not ok:
            return False, f"stay_in_goal: {why}"
        goal = [-W]
    elif getattr(model, "stay_in_goal", False):
        return False, "the model asks to stay in the goal, and the certificate does not prove it"
    goal_certs = [(_gram(item["multiplier"], nv), _gram(item["remainder"], nv)) for item in cert["goal"]]
    boxes = [_multipliers(box, nv, n) for box in cert.get("box_multipliers") or [[] for _ in goal]]
    eps, delta, C = Fraction(cert["eps_scaled"]), Fraction(cert["delta_scaled"]), Fraction(cert["C_scaled"])
    ok, why = check_reach_avoid(ring, field.g, field.D, V, eps, C, delta, initial,
                                _set_pieces(cert, "initial", len(initial), nv), unsafe, _set_pieces(cert, "unsafe", len(unsafe), nv), goal, goal_certs,
                                _gram(cert["gram_bounded"], nv), boxes)
    if not ok:
        return False, why
    if not _at_least(c.get("reach_time_bound_s"), C / eps * scaled.scaling.time):
        return False, "the stated time bound is below the certified one"
    return True, why


def _verify_ges(scaled: Any, V: Any, mu: Fraction, cert: dict[str, Any], c: dict[str, Any]) -> tuple[bool, str]:
    from lyapcheck.sos.definiteness import is_positive_definite

    n = scaled.n
    if mu <= 0 or any(sum(m) != 1 or any(m[n:]) for m in V.basis) or len(V.basis) != n:
        return False, "GES needs a quadratic V (every state, degree 1, common to a box) and mu > 0"
    from lyapcheck.models.loop.field import declared_quadratic

    nv = len(V.basis[0])
    order = [V.basis.index(tuple(int(k == i) for k in range(nv))) for i in range(n)]
    P = declared_quadratic(scaled.scaling, [[V.Q[order[i]][order[j]] for j in range(n)] for i in range(n)])
    c1, c2, k = Fraction(cert["c1"]), Fraction(cert["c2"]), Fraction(cert["k"])
    eye = [[Fraction(int(i == j)) for j in range(n)] for i in range(n)]
    if not (c1 > 0 and is_positive_definite([[P[i][j] - c1 * eye[i][j] for j in range(n)] for i in range(n)])
            and is_positive_definite([[c2 * eye[i][j] - P[i][j] for j in range(n)] for i in range(n)])):
        return False, "c1 I < P < c2 I does not hold"
    if k * k < c2 / c1 or not _at_least(c.get("k"), k):
        return False, "k is below sqrt(c2/c1)"
    if not _at_most(c.get("decay_rate_per_s"), mu / scaled.scaling.time / 2):
        return False, "the stated decay rate of |x| exceeds mu / 2"
    return True, "a quadratic V with V' <= -mu V and c1 I < P < c2 I: GES, exactly"


__all__ = ["verify_linearization", "verify_sos_bound", "verify_barrier", "verify_reach_avoid", "verify_lyapunov"]
