"""The sentence each decided condition of the paper's loop says, made from its exact data alone.

A certificate's ``summary`` is what a reader believes, so it must never say more than the exact
data beside it, which ``verify`` re-checks. This module is the one place that writes those
sentences (the model files' twin is :mod:`lyapcheck.models.classes.claims`): every class of
:mod:`lyapcheck.paper.conditions` and :mod:`lyapcheck.paper.boxes` sets the summary of a decided
result with :func:`summary` (through :func:`decided` or :func:`decided_box`);
:func:`lyapcheck.paper.certificate.verify_document` and ``verify_box_document`` regenerate it from the
data they have just re-checked and fail where the file's text differs (``limsup |eps| <= 0.001 m``
where 0.03491 m was proved, a refutation turned into a claim, a box summary naming a wider box);
:mod:`reports.certificate_page` prints the regenerated text.

Decided statuses (:data:`DECIDED`) are ``certified``, ``refuted``, ``holds`` and ``fails``; the
paper's classes raise no ``counterexample``, so a condition claiming one has no sentence and fails
``verify``, as does any status a class never decides (a ``refuted`` ``ges``). ``not_certified``,
``inconclusive`` and ``not_applicable`` claim nothing: their text is a reason, left as the class
wrote it.

What each sentence reads: ``cert`` is the condition's certificate, ``ref`` its refutation,
``inputs`` the document's exact SI inputs (``inputs.exact_si``, from which ``verify`` derives the
system), ``box`` the document's box (every box sentence opens with it). A number is printed the
way the class computed it from these, so a fresh certificate's summary is the same text.

=========================  =========  ==========================================================
class                      status     the sentence reads
=========================  =========  ==========================================================
prop41_ges, prop41_iss     certified  nothing (the exact check passed: a fixed sentence)
prop41_ges, prop41_iss     refuted    nothing (the Gamma_22 bound: a fixed sentence)
stabcond2                  holds,     ``lhs_exact`` (``verify`` recomputes it from the inputs)
                           fails
sector_ges                 certified  ``cert.decay_rate``
sector_ges                 refuted    ``ref.A0A1``, ``ref.A0A1inv`` (which has a negative real
                                      eigenvalue, decided here exactly)
switched_ges               certified  ``cert.decay_rate``
switched_ges               refuted    periodic: ``ref.t0``, ``ref.t1``, ``ref.rho``,
                                      ``ref.growth_lower_bound`` and the search's estimates
                                      ``growth_per_period``, ``growth_rate_per_s``; a vertex:
                                      ``ref.rho``, ``ref.vertex``
ultimate_bound             certified  ``cert.eps_bound``, the number of ``cert.stages``
sos_gas                    certified  ``cert.degree``, ``cert.mu_scaled``, ``cert.scaling.time_scale``
ges                        certified  ``cert.c1``, ``cert.c2``, ``cert.mu_scaled``,
                                      ``cert.scaling.time_scale``, ``inputs.sigma0``
saturated_loop             certified  ``cert.strip_half_width_sq_scaled``, ``cert.axis_radius_scaled``,
                                      ``cert.R_lo``/``cert.eps_bound``, ``cert.reach``,
                                      ``real_loop_limsup_eps_m``; ``inputs.delta_los``, ``e11``,
                                      ``omega_so``, ``d_max``
sos_bound                  certified  ``cert.eps_bound``
=========================  =========  ==========================================================

Over a box (``box`` given):

=========================  =========  ==========================================================
prop41_ges, prop41_iss     certified  the number of ``cert.vertices``
prop41_ges, prop41_iss     refuted    ``ref.point`` (a corner of the box)
sector_ges                 certified  ``cert.c1``, ``cert.c2``, ``cert.decay_rate_scaled``,
                                      ``cert.time_scale_min``, ``cert.vertices`` (the polytope)
sector_ges                 refuted    ``ref.point``, ``ref.A0A1``, ``ref.A0A1inv``
ges                        certified  ``cert.c1``, ``cert.c2``, ``cert.mu_scaled`` and
                                      ``cert.time_scale_min`` (one V for the box) or
                                      ``cert.time_scale``, ``cert.degree`` (``form`` parametric)
sos_gas                    certified  ``cert.degree``, ``cert.mu_scaled``, ``cert.time_scale_min``,
                                      the number of ``cert.vertices``
ultimate_bound             certified  ``cert.eps_bound``, the number of ``cert.stages`` and of
                                      the first stage's ``vertices``
saturated_loop             certified  ``cert.reach`` (``Y_q``, ``S_1``, ``gamma``),
                                      ``real_loop_limsup_eps_m``
sos_bound                  certified  ``cert.eps_bound``, the number of ``cert.vertices``
=========================  =========  ==========================================================

The text figures beside some sentences are made here too, and ``verify`` compares them:
``ges.norm`` (:data:`GES_NORM`), ``sos_gas.proves`` (:func:`sos_gas_proves`),
``saturated_loop.not_ges`` (:func:`not_ges`) and ``saturated_loop.reach_condition``
(:func:`reach_condition`).

Every reader raises KeyError, TypeError, ValueError, IndexError or ArithmeticError on data of the
wrong form; ``verify`` reports that as a failed check of the condition, the report as a sentence
it cannot show.
"""

from __future__ import annotations

import decimal
import math
from dataclasses import dataclass
from fractions import Fraction
from typing import TYPE_CHECKING, Any, Callable, Mapping, Sequence

if TYPE_CHECKING:
    from lyapcheck.paper.boxes.box import ParameterBox
    from lyapcheck.results import ConditionResult

#: the statuses that claim something, and so carry a sentence made here
DECIDED = ("certified", "refuted", "holds", "fails", "counterexample")
#: what data of the wrong form raises in a reader (and what callers catch)
MALFORMED = (KeyError, TypeError, ValueError, IndexError, AttributeError, ArithmeticError, RecursionError)


@dataclass(frozen=True)
class Context:
    """What a sentence may read beside its condition: the document's inputs and box."""

    inputs: Mapping[str, Any]
    box: Mapping[str, Sequence[Any]] | None

    def value(self, key: str) -> Fraction:
        """The exact SI input ``key`` (a ``"p/q"`` text or a Fraction)."""
        raw = self.inputs[key]
        if raw is None or isinstance(raw, bool) or not isinstance(raw, (str, int, Fraction)):
            raise TypeError(f"input '{key}' must be an exact rational, got {raw!r}")
        return Fraction(raw)

    def describe(self) -> str:
        """The box as its classes name it (:meth:`ParameterBox.describe`)."""
        from lyapcheck.paper.boxes.box import ParameterBox

        if not isinstance(self.box, Mapping):
            raise TypeError("a box sentence needs the document's box")
        return ParameterBox.from_json(self.box).describe()


Sentence = Callable[[Mapping[str, Any], str, Context], str]


# -- figures as the sentences print them (the classes import these from here) --------------------------

def significant(value: Fraction, digits: int = 6) -> str:
    """``value`` with ``digits`` significant digits (like ``:.6g``), exactly rounded at any magnitude."""
    with decimal.localcontext() as ctx:
        ctx.prec = digits
        ctx.Emax, ctx.Emin = decimal.MAX_EMAX, decimal.MIN_EMIN
        # one correctly rounded division; Decimal exponents do not overflow where floats do
        rounded = (decimal.Decimal(value.numerator) / decimal.Decimal(value.denominator)).normalize()
        return format(rounded, "g")


#: the arguments a switched_ges refutation states (its ``argument`` key)
ARGUMENT_SWITCHING = "periodic_switching_2x2"
ARGUMENT_VERTEX = "vertex_not_hurwitz"


def envelope(cert: Mapping[str, Any], sigma0: Fraction,
             time_scale: Fraction | None = None) -> tuple[float, float, float]:
    """``(k, rate, k_eps_s)`` of ``|x(t)| <= k |x0| exp(-rate t)`` (``x = (eps, sigma0 s)/Delta``,
    rate in 1/s) and the constant for ``|(eps, s)|``, from a certificate's ``mu_scaled``, ``c1``,
    ``c2`` and its scaling's time scale (or ``time_scale``, before the scaling is stored)."""
    mu, c1, c2 = (Fraction(cert[key]) for key in ("mu_scaled", "c1", "c2"))
    if time_scale is None:
        time_scale = Fraction(cert["scaling"]["time_scale"])
    k = math.sqrt(float(c2 / c1))
    lam = float(mu * time_scale) / 2
    s0 = float(sigma0)
    # x = diag(1, sigma0) (eps, s)/Delta: the constant for |(eps, s)| pays the conditioning of that map
    return k, lam, k * max(1.0, s0) / min(1.0, s0)


#: relative shrink of Omega_SO (given as a float-derived Fraction) to a safe lower bound
OMEGA_ROUNDING = Fraction(1, 10**12)


def figure_text(x: Fraction) -> str:
    """``x`` to 4 significant digits, or what it is beyond the double range."""
    try:
        value: float | None = float(x)
    except OverflowError:  # beyond the double range (extreme corners of a box)
        value = None
    return f"{value:.4g}" if value is not None else ("-" if x < 0 else "") + "beyond 1.8e308"


def summary(name: str, condition: Mapping[str, Any], inputs: Mapping[str, Any] | None = None,
            box: Mapping[str, Sequence[Any]] | None = None) -> str | None:
    """The sentence of a decided condition (its JSON form) of class ``name``, or None for the
    statuses that claim nothing. ``inputs``: the exact SI inputs (``inputs.exact_si`` of a
    document, or Fractions); ``box``: the document's box (``{"alpha_d": ["588", "612"]}``) for a
    box certificate. Raises one of :data:`MALFORMED` where the data do not give a sentence."""
    status = condition.get("status")
    if status not in DECIDED:
        return None
    table = BOX_SENTENCES if box is not None else SENTENCES
    build = table.get((name, status))
    if build is None:
        where = " over a box" if box is not None else ""
        raise ValueError(f"class '{name}' never decides '{status}'{where}: there is no such claim to make")
    return build(condition, name, Context(inputs or {}, box))


def known(name: str, box: bool = False) -> bool:
    """Whether this version writes sentences for class ``name`` (of a box certificate with ``box``)."""
    return any(n == name for n, _ in (BOX_SENTENCES if box else SENTENCES))


def decided(result: "ConditionResult", inputs: Mapping[str, Any] | None = None) -> "ConditionResult":
    """``result`` with its summary set by :func:`summary` (a point class's decided result)."""
    text = summary(result.name, result.to_json(), inputs)
    if text is None:
        raise ValueError(f"{result.name}: '{result.status}' is not a decided status")
    result.summary = text
    return result


def decided_box(name: str, result: dict[str, Any], box: "ParameterBox",
                inputs: Mapping[str, Any] | None = None) -> dict[str, Any]:
    """``result`` (a box class's JSON-ready result) with its ``summary`` set by :func:`summary`."""
    text = summary(name, result, inputs, box.to_json())
    if text is None:
        raise ValueError(f"{name}: '{result.get('status')}' is not a decided status")
    result["summary"] = text
    return result


# -- the pieces that other modules also print ---------------------------------------------------------
#: Proposition 4.1's condition holds at the certificate's P (also the exact check's message)
PROP41_HOLDS = "P > 0 and lambda_min(Gamma) exceeds the right-hand side, exactly"


def lmi_decay(rate: Fraction) -> str:
    """A common quadratic V over the vertices with decay rate ``rate`` (also the exact check's message)."""
    return f"P > 0 and the vertex LMIs hold with decay rate mu = {float(rate):.4g} 1/s, exactly"


def shorten_narendra(a0a1: Any, a0a1inv: Any) -> str:
    """Why two Hurwitz 2x2 vertex matrices have no common quadratic V, from ``A0 A1`` and
    ``A0 A1^-1`` (exact matrices or their JSON): the one(s) with a negative real eigenvalue."""
    from lyapcheck import exact

    bad = [label for label, m in (("A0 A1", a0a1), ("A0 A1^-1", a0a1inv))
           if exact.has_negative_real_eigenvalue_2x2(exact.from_json(m))]
    if not bad:
        raise ValueError("neither A0 A1 nor A0 A1^-1 has a negative real eigenvalue: nothing is refuted")
    return (f"{' and '.join(bad)} has a negative real eigenvalue, so the two Hurwitz vertex matrices "
            "have no common quadratic Lyapunov function (Shorten & Narendra 2003)")


def real_loop_clause(limsup_eps_m: Any, *, box: bool = False) -> str:
    """What ``saturated_loop`` adds when global reach and a certified ``sos_bound`` together bound
    the real loop (``real_loop_limsup_eps_m``, metres)."""
    where = " at every gain set of the box," if box else ""
    return (f"; so the real loop's limsup |eps| <= {_float(limsup_eps_m) * 1e3:.4g} mm (sos_bound){where} from every "
            "start")


# -- the text figures beside a sentence (verify compares them with these) ----------------------------
#: ``ges``'s ``norm``: which norm each of its constants bounds
GES_NORM = "|(eps, sigma0 s)|/Delta for k; |(eps, s)| for k_eps_s"


def sos_gas_proves(rate: Fraction) -> str:
    """``sos_gas``'s ``proves``, from the certified decay rate of V (1/s)."""
    return "GAS" + (", V decays like exp(-%.4g t)" % float(rate) if rate > 0 else "")


def not_ges(speed_bound: Fraction) -> str:
    """``saturated_loop``'s ``not_ges``: ``e11 Omega_SO + |E_0| d*`` (m/s) bounds the real loop's speed."""
    return (f"the real loop is not GES: |eps'| <= e11 Omega_SO + d* = {float(speed_bound) * 1e3:.4g} mm/s bounds "
            "its speed")


def reach_condition(reach: Mapping[str, Any]) -> str:
    """``saturated_loop``'s ``reach_condition``, from the reach data ``S_1``, ``pull``, ``push`` (exact)."""
    return (f"with |s| <= {float(_exact(reach, 'S_1')):.4g} m (wind-up, damped near the path) the swimmer pulls y "
            f"toward the strip at >= {float(_exact(reach, 'pull')):.4g} m/s against pushes <= "
            f"{float(_exact(reach, 'push')):.4g} m/s (disturbance and integrator)")


# -- readers ------------------------------------------------------------------------------------------
def _float(value: Any) -> float:
    """A stated figure (a JSON number, not a bool)."""
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise TypeError(f"a figure must be a number, got {value!r}")
    return float(value)


def _number(condition: Mapping[str, Any], key: str) -> float:
    try:
        return _float(condition[key])
    except TypeError:
        raise TypeError(f"figure '{key}' must be a number, got {condition[key]!r}") from None


def _exact(data: Mapping[str, Any], key: str) -> Fraction:
    """An exact rational of a certificate (``"p/q"``)."""
    value = data[key]
    if not isinstance(value, str):
        raise TypeError(f"'{key}' must be an exact rational as text, got {value!r}")
    return Fraction(value)


def _table(condition: Mapping[str, Any], key: str) -> Mapping[str, Any]:
    value = condition[key]
    if not isinstance(value, Mapping):
        raise TypeError(f"'{key}' must be a table, got {value!r}")
    return value


def _list(data: Mapping[str, Any], key: str) -> list[Any]:
    value = data[key]
    if not isinstance(value, list):
        raise TypeError(f"'{key}' must be a list, got {value!r}")
    return value


def _degree(data: Mapping[str, Any]) -> int:
    from lyapcheck.sos.certificates import exponent

    return exponent(data["degree"], "degree")


def _corner(ref: Mapping[str, Any]) -> str:
    """The refuting point of a box, as its class named it."""
    point = _table(ref, "point")
    return ", ".join(f"{name} = {float(_exact(point, name)):.6g}" for name in point)


# -- the point classes --------------------------------------------------------------------------------
def _prop41_certified(c: Mapping[str, Any], name: str, ctx: Context) -> str:
    return PROP41_HOLDS


def _prop41_refuted(c: Mapping[str, Any], name: str, ctx: Context) -> str:
    _table(c, "refutation")
    return "no P satisfies the condition (exact Gamma_22 bound)" + (
        " - so the ISS condition fails too" if name == "prop41_iss" else "")


def _stabcond2(c: Mapping[str, Any], name: str, ctx: Context) -> str:
    value = _exact(c, "lhs_exact")
    return (f"(sigma0 alpha_d Delta)^2 + 2 alpha_d Delta (1 + k_d/alpha_d) = {significant(value)} "
            + ("<= 1" if value <= 1 else "> 1"))


def _sector_certified(c: Mapping[str, Any], name: str, ctx: Context) -> str:
    return lmi_decay(_exact(_table(c, "certificate"), "decay_rate"))


def _sector_refuted(c: Mapping[str, Any], name: str, ctx: Context) -> str:
    ref = _table(c, "refutation")
    return shorten_narendra(ref["A0A1"], ref["A0A1inv"])


def _switched_certified(c: Mapping[str, Any], name: str, ctx: Context) -> str:
    rate = _exact(_table(c, "certificate"), "decay_rate")
    return ("a common quadratic Lyapunov function for rho in [0, rho_sup] proves GES for every variation of rho in "
            f"the sector: {lmi_decay(rate)}")


def _switched_refuted(c: Mapping[str, Any], name: str, ctx: Context) -> str:
    from lyapcheck import exact

    ref = _table(c, "refutation")
    if ref.get("argument") == ARGUMENT_VERTEX:
        return vertex_not_hurwitz(_exact(ref, "rho"), exact.from_json(ref["vertex"]))
    if ref.get("argument") != ARGUMENT_SWITCHING:
        raise ValueError(f"unknown switched_ges refutation {ref.get('argument')!r}")
    t0, t1, bound = _exact(ref, "t0"), _exact(ref, "t1"), _exact(ref, "growth_lower_bound")
    rhos = _list(ref, "rho")
    if len(rhos) != 2:
        raise ValueError("'rho' must hold two values")
    rho_lo, rho_sup = (Fraction(r) for r in rhos)
    return (f"Switching rho periodically, {float(t1):.4g} s at rho_sup = {float(rho_sup):.4g} then "
            f"{float(t0):.4g} s at rho = {float(rho_lo):.3g}, multiplies the state by "
            f"{_number(c, 'growth_per_period'):.4g} per {float(t0 + t1):.4g} s period (proved exactly: >= "
            f"{float(bound):.4g}; growth rate {_number(c, 'growth_rate_per_s'):.3g} 1/s), so the inclusion "
            "rho in (0, rho_sup] is unstable and no Lyapunov function of any form that uses only "
            "this sector can prove GES. The actual closed loop, where rho depends on the state, "
            "is not shown unstable by this.")


def vertex_not_hurwitz(rho: Fraction, vertex: Any) -> str:
    """``switched_ges`` refuted by holding ``rho`` at a vertex ``A + rho B`` that is not Hurwitz."""
    tr = vertex[0][0] + vertex[1][1]
    dt = vertex[0][0] * vertex[1][1] - vertex[0][1] * vertex[1][0]
    return (f"A + rho B is not Hurwitz at the admissible rho = {float(rho):.6g} (trace {float(tr):.4g}, "
            f"determinant {float(dt):.4g}), so holding rho there gives a trajectory that does not decay: "
            "the inclusion is not GES and no Lyapunov function that uses only the sector can prove GES.")


def _ultimate(c: Mapping[str, Any], name: str, ctx: Context) -> str:
    cert = _table(c, "certificate")
    stages = _list(cert, "stages")
    how = "box + %d ellipsoid stage(s)" % len(stages) if stages else \
        "comparison-lemma box only (no ellipsoid LMI was feasible)"
    return f"limsup |eps| <= {float(_exact(cert, 'eps_bound')):.4g} m ({how})"


def _sos_gas(c: Mapping[str, Any], name: str, ctx: Context) -> str:
    cert = _table(c, "certificate")
    rate = _exact(cert, "mu_scaled") * _exact(_table(cert, "scaling"), "time_scale")
    return (f"polynomial V of degree {_degree(cert)}: global asymptotic stability"
            + (f", V' <= -{float(rate):.3g} V (exponential decay from every start)" if rate > 0 else "")
            + ", exactly checked")


def _ges(c: Mapping[str, Any], name: str, ctx: Context) -> str:
    k, rate, k_eps_s = envelope(_table(c, "certificate"), ctx.value("sigma0"))
    return (f"GES: |x(t)| <= {k:.3g} |x0| exp(-{rate:.3g} t) for every start "
            f"(x = (eps, sigma0 s)/Delta; k = {k_eps_s:.3g} for |(eps, s)|), from a quadratic form "
            "whose matrix depends on (eps + sigma0 s)/Delta, exactly checked")


def _saturated(c: Mapping[str, Any], name: str, ctx: Context) -> str:
    cert = _table(c, "certificate")
    delta = ctx.value("delta_los")
    d_max = ctx.value("d_max") if ctx.inputs.get("d_max") is not None else Fraction(0)
    strip = math.sqrt(float(_exact(cert, "strip_half_width_sq_scaled") * delta**2))
    radius = float(_exact(cert, "axis_radius_scaled") * delta)
    text = (f"{{V <= c}} (contains every start with s = 0, |eps| <= {radius * 1e3:.3g} mm) lies in the unsaturated "
            f"strip |eps + sigma0 s| < {strip * 1e3:.3g} mm: from there the saturated loop never saturates and "
            "converges")
    if d_max > 0:
        if "R_lo" in cert:  # the disturbance step (verify re-checks it where R_lo is stated)
            text += (f"; with |d_perp| <= d* it stays there and ends within |eps| <= "
                     f"{float(_exact(cert, 'eps_bound')) * 1e3:.3g} mm")
        else:
            text += "; under d* this level set is not shown invariant (the reach argument below does not need it)"
    reach = cert.get("reach")
    if reach is not None and _exact(_table(cert, "reach"), "gamma") > 0:
        text += (f"; from ANY start the loop enters {{|eps + sigma0 s| <= {float(_exact(reach, 'Y_q')) * 1e3:.4g} mm, "
                 f"|s| <= {float(_exact(reach, 'S_1')):.3g} m}} in finite time and never leaves it; there it is "
                 "unsaturated, so the sos_gas and sos_bound conclusions hold for the real loop from any start "
                 "(not GES: its speed is bounded)")
    else:
        out_swims = ctx.value("e11") * ctx.value("omega_so") * (1 - OMEGA_ROUNDING) > d_max
        text += "; reaching the strip from anywhere is not proved (" + (
            "the integrator's wind-up pushes y harder than the saturated swimmer pulls)" if out_swims
            else "the swimmer cannot out-swim the disturbance bound)")
    if "real_loop_limsup_eps_m" in c:
        text += real_loop_clause(c["real_loop_limsup_eps_m"])
    return text


def _sos_bound(c: Mapping[str, Any], name: str, ctx: Context) -> str:
    bound = _exact(_table(c, "certificate"), "eps_bound")
    return f"from every initial condition limsup |eps| <= {float(bound) * 1e3:.4g} mm (polynomial V, exactly checked)"


SENTENCES: dict[tuple[str, str], Sentence] = {
    ("prop41_ges", "certified"): _prop41_certified, ("prop41_iss", "certified"): _prop41_certified,
    ("prop41_ges", "refuted"): _prop41_refuted, ("prop41_iss", "refuted"): _prop41_refuted,
    ("stabcond2", "holds"): _stabcond2, ("stabcond2", "fails"): _stabcond2,
    ("sector_ges", "certified"): _sector_certified, ("sector_ges", "refuted"): _sector_refuted,
    ("switched_ges", "certified"): _switched_certified, ("switched_ges", "refuted"): _switched_refuted,
    ("ultimate_bound", "certified"): _ultimate,
    ("sos_gas", "certified"): _sos_gas,
    ("ges", "certified"): _ges,
    ("saturated_loop", "certified"): _saturated,
    ("sos_bound", "certified"): _sos_bound,
}


# -- the box classes ----------------------------------------------------------------------------------
def _box_prop41_certified(c: Mapping[str, Any], name: str, ctx: Context) -> str:
    iss = name == "prop41_iss"
    which = "its ISS variant" if iss else "eq. stabCond"
    vertices = _list(_table(c, "certificate"), "vertices")
    return (f"{which} holds for every gain set with {ctx.describe()}: one P, checked exactly at the "
            f"{len(vertices)} vertices of the (a11, a12, a22, g{', e' if iss else ''}) box")


def _box_prop41_refuted(c: Mapping[str, Any], name: str, ctx: Context) -> str:
    ctx.describe()  # a box sentence needs the box, though this one names a corner
    return (f"no P satisfies eq. stabCond at the box's corner {_corner(_table(c, 'refutation'))} (exact Gamma_22 "
            "bound), so none serves the box" + (": the ISS condition fails too" if name == "prop41_iss" else ""))


def _box_sector_certified(c: Mapping[str, Any], name: str, ctx: Context) -> str:
    from lyapcheck.paper.conditions.base import ScaledDynamics, sector_polytope

    cert = _table(c, "certificate")
    k = math.sqrt(float(_exact(cert, "c2") / _exact(cert, "c1")))
    decay = float(_exact(cert, "decay_rate_scaled") * _exact(cert, "time_scale_min"))
    vertices = [ScaledDynamics(time_scale=Fraction(1), c=Fraction(v[0]), a=Fraction(v[1]), b=Fraction(v[2]))
                for v in _list(cert, "vertices")]
    return (f"GES for every gain set with {ctx.describe()}: |x(t)| <= {k:.3g} |x0| exp(-{decay:.3g} t) "
            "(x = (eps, sigma0 s)/Delta), one quadratic V = x^T P x checked exactly at the polytope's "
            f"{len(sector_polytope(vertices))} vertices")


def _box_sector_refuted(c: Mapping[str, Any], name: str, ctx: Context) -> str:
    ctx.describe()
    ref = _table(c, "refutation")
    why = shorten_narendra(ref["A0A1"], ref["A0A1inv"])
    return f"no quadratic V common to the box: at its corner {_corner(ref)}, {why}"


def _box_ges(c: Mapping[str, Any], name: str, ctx: Context) -> str:
    cert = _table(c, "certificate")
    mu, c1, c2 = (_exact(cert, key) for key in ("mu_scaled", "c1", "c2"))
    k = math.sqrt(float(c2 / c1))
    if cert.get("form") == "parametric":
        rate = float(mu * _exact(cert, "time_scale")) / 2
        return (f"GES for every gain set with {ctx.describe()}: |x(t)| <= {k:.3g} |x0| exp(-{rate:.3g} t) "
                "(x = (eps, sigma0 s)/Delta), from V(x; gains) whose matrices are polynomials of degree "
                f"{_degree(cert)} in the coefficients of the dynamics (e11 alpha_d, k_d, sigma0 U/Delta), checked "
                "exactly over the whole box")
    rate = float(mu * _exact(cert, "time_scale_min")) / 2
    return (f"GES for every gain set with {ctx.describe()}: |x(t)| <= {k:.3g} |x0| exp(-{rate:.3g} t) "
            "(x = (eps, sigma0 s)/Delta), one state-dependent quadratic V checked exactly at the corners")


def _box_sos_gas(c: Mapping[str, Any], name: str, ctx: Context) -> str:
    cert = _table(c, "certificate")
    mu = _exact(cert, "mu_scaled")
    rate = float(mu * _exact(cert, "time_scale_min"))
    return (f"GAS for every gain set with {ctx.describe()}: one polynomial V of degree {_degree(cert)}"
            + (f", V' <= -{rate:.3g} V (1/s, V decays exponentially from every start)" if mu > 0 else "")
            + f", checked exactly at the {len(_list(cert, 'vertices'))} vertices of the (c, a, b) box")


def _box_ultimate(c: Mapping[str, Any], name: str, ctx: Context) -> str:
    cert = _table(c, "certificate")
    stages = _list(cert, "stages")
    how = (f"box + {len(stages)} ellipsoid stage(s), one P per stage checked exactly at the "
           f"{len(_list(stages[0], 'vertices'))} vertices of the box's (A_r, e d*) polytope" if stages
           else "comparison-lemma box only (no ellipsoid common to the box was feasible)")
    bound = float(_exact(cert, "eps_bound"))
    return (f"for every gain set with {ctx.describe()}: limsup |eps| <= {bound * 1e3:.4g} mm "
            f"for every |d_perp| <= d* ({how})")


def _box_saturated(c: Mapping[str, Any], name: str, ctx: Context) -> str:
    reach = _table(_table(c, "certificate"), "reach")
    text = (f"for every gain set with {ctx.describe()}, from ANY start and every |d_perp| <= d*, the real "
            f"(saturated) loop enters {{|eps + sigma0 s| <= {figure_text(_exact(reach, 'Y_q'))} m, "
            f"|s| <= {figure_text(_exact(reach, 'S_1'))} m}} in finite time and never leaves it; there it is "
            "unsaturated, so the box's sos_gas and sos_bound conclusions hold for the real loop (reach margin >= "
            f"{figure_text(_exact(reach, 'gamma'))} m/s)")
    if "real_loop_limsup_eps_m" in c:
        text += real_loop_clause(c["real_loop_limsup_eps_m"], box=True)
    return text


def _box_sos_bound(c: Mapping[str, Any], name: str, ctx: Context) -> str:
    cert = _table(c, "certificate")
    bound = float(_exact(cert, "eps_bound"))
    return (f"for every gain set with {ctx.describe()}: limsup |eps| <= {bound * 1e3:.4g} mm "
            "from every initial condition and every |d_perp| <= d* (one polynomial V, checked exactly at the "
            f"{len(_list(cert, 'vertices'))} vertices of the (c, a, b, k) box)")


BOX_SENTENCES: dict[tuple[str, str], Sentence] = {
    ("prop41_ges", "certified"): _box_prop41_certified, ("prop41_iss", "certified"): _box_prop41_certified,
    ("prop41_ges", "refuted"): _box_prop41_refuted, ("prop41_iss", "refuted"): _box_prop41_refuted,
    ("sector_ges", "certified"): _box_sector_certified, ("sector_ges", "refuted"): _box_sector_refuted,
    ("ges", "certified"): _box_ges,
    ("sos_gas", "certified"): _box_sos_gas,
    ("ultimate_bound", "certified"): _box_ultimate,
    ("saturated_loop", "certified"): _box_saturated,
    ("sos_bound", "certified"): _box_sos_bound,
}


__all__ = ["summary", "known", "decided", "decided_box", "DECIDED", "MALFORMED", "PROP41_HOLDS", "lmi_decay",
           "shorten_narendra", "real_loop_clause", "vertex_not_hurwitz", "GES_NORM", "sos_gas_proves", "not_ges",
           "reach_condition", "SENTENCES", "BOX_SENTENCES"]
