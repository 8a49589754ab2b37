"""Certificate documents: write, read, and re-check exactly without a solver.

Schema (version 1)::

    {
      "schema_version": 1,
      "kind": "lyapcheck-certificate",
      "inputs": {"given": {"gains.alpha_d": "600", ...}, "exact_si": {"alpha_d": "600", ...}},
      "dynamics": "derived" | "printed",
      "system": {"A": [[..]], "B": [[..]], "E": [..], "rho_sup": "..", "sigma0": "..", ...},
      "conditions": {"prop41_ges": {"status": .., "certificate": {"P": [[..]]}, ...}, ...},
      "verdict": "certified" | "not_certified",
      "versions": {...}
    }

Rational numbers are strings ``"p/q"``. :func:`verify_document` re-derives the system from the
inputs (through :mod:`symbolic.closed_loop`), compares it with the stored one, and re-runs
every exact check (certificates and refutations); it never imports cvxpy.
"""

from __future__ import annotations

from fractions import Fraction
from pathlib import Path
from typing import Any

from lyapcheck.answers import answers_row, checked_conditions
from lyapcheck.errors import CertificateError, InputFileError
from lyapcheck.fileio import read_json
from lyapcheck.numerics import package_versions  # noqa: F401 (re-exported)

SCHEMA_VERSION = 1
KIND = "lyapcheck-certificate"


def system_to_json(system: Any) -> dict[str, Any]:
    from lyapcheck import exact

    return {
        "A": exact.to_json(system.A), "B": exact.to_json(system.B), "E": [str(x) for x in system.E],
        "rho_sup": str(system.rho_sup), "sigma0": str(system.sigma0), "delta": str(system.delta),
        "speed": str(system.speed), "d_max": str(system.d_max),
    }


def _exact_or_none(value: Fraction | None) -> str | None:
    return None if value is None else str(value)


def document_inputs(problem: Any) -> dict[str, Any]:
    """The inputs as given (text) and exactly in SI; an input not given is null."""
    from lyapcheck.paper.certification import exact_values

    return {"given": dict(problem.given),
            "exact_si": {k: str(v) for k, v in exact_values(problem).items()}
            | {"d_max": _exact_or_none(problem.d_max), "omega_so": _exact_or_none(problem.actuation.omega_so)}}


def build_document(problem: Any, dynamics: str, results: dict[str, Any], verdict: str) -> dict[str, Any]:
    from lyapcheck.answers import answers_of
    from lyapcheck.paper.certification import build_system

    system = build_system(problem, dynamics)
    return {
        "schema_version": SCHEMA_VERSION,
        "kind": KIND,
        "inputs": document_inputs(problem),
        "dynamics": dynamics,
        "system": system_to_json(system),
        "conditions": (conditions := {name: res.to_json() for name, res in results.items()}),
        "answers": answers_of(conditions),
        "verdict": verdict,
        "versions": package_versions(),
    }


def build_box_document(problem: Any, box: Any, dynamics: str, results: dict[str, dict[str, Any]]) -> dict[str, Any]:
    """A certificate for every gain set in ``box`` (:mod:`lyapcheck.paper.boxes`), one entry per class."""
    from lyapcheck.answers import answers_of
    from lyapcheck.paper.boxes.saturated import real_loop_bound
    from lyapcheck.paper.boxes.classes import BOX_STABILITY_CLASSES

    real_loop_bound(results)
    certified = any(r["status"] == "certified" for c, r in results.items() if c in BOX_STABILITY_CLASSES)
    return {
        "schema_version": SCHEMA_VERSION,
        "kind": KIND,
        "inputs": document_inputs(problem),
        "box": box.to_json(),
        "dynamics": dynamics,
        "conditions": results,
        "answers": answers_of(results),
        "verdict": "certified" if certified else "not_certified",
        "versions": package_versions(),
    }


def verify_box_document(doc: dict[str, Any]) -> list[tuple[str, bool, str]]:
    """Exact re-check of a box certificate: every certified class from the box alone, and every
    refutation at its stated point (which must lie in the box)."""
    from dataclasses import replace

    from lyapcheck.paper.boxes.classes import BOX_CLASSES, BOX_STABILITY_CLASSES, verify_box, verify_box_refutation
    from lyapcheck.paper.boxes.box import ParameterBox
    from lyapcheck.paper.params import Actuation, GainSet, Problem, Swimmer

    try:
        v = {k: Fraction(x) for k, x in doc["inputs"]["exact_si"].items() if x is not None}
        problem = Problem(gains=GainSet(alpha_d=v["alpha_d"], sigma0=v["sigma0"], k_d=v["k_d"],
                                        delta_los=v["delta_los"], los_speed=v["los_speed"]),
                          swimmer=Swimmer(e11=v["e11"], e11_hat=v["e11_hat"]),
                          actuation=Actuation(omega_so=v.get("omega_so")))
        problem = replace(problem, d_max=v.get("d_max"))
        box = ParameterBox.from_json(doc["box"])
        if any(lo <= 0 or lo > hi for _, lo, hi in box.bounds):
            raise ValueError("box bounds must satisfy 0 < lo <= hi")
        conditions = doc["conditions"]
        if not isinstance(conditions, dict) or any(cls not in BOX_CLASSES for cls in conditions):
            raise ValueError(f"conditions must be classes among {', '.join(BOX_CLASSES)}")
        rows: list[tuple[str, bool, str]] = []
        for cls, result in conditions.items():
            if result.get("status") == "certified":
                ok, why = verify_box(problem, box, doc["dynamics"], result, cls)
                rows.append((cls, ok, why if ok else f"{cls}: {why}"))
            elif result.get("status") == "refuted":
                ok, why = verify_box_refutation(problem, box, doc["dynamics"], result, cls)
                rows.append((cls, ok, why if ok else f"{cls}: {why}"))
        for cls, result in conditions.items():  # each result speaks of the document's box, no other
            if isinstance(result, dict) and "box" in result and result["box"] != doc["box"]:
                rows.append((cls, False, f"{cls}: its box {_short(result['box'], 120)} is not the document's "
                                         f"{_short(doc['box'], 120)}"))
        sat = conditions.get("saturated_loop", {})
        if "real_loop_limsup_eps_m" in sat:  # the conjunction of reach and sos_bound, both re-checked above
            bound = conditions.get("sos_bound", {})
            ok = (any(n == "saturated_loop" and good for n, good, _ in rows)
                  and any(n == "sos_bound" and good for n, good, _ in rows)
                  and float(sat["real_loop_limsup_eps_m"]) >= float(Fraction(bound["certificate"]["eps_bound"])) * (1 - 1e-15))
            rows.append(("real_loop_bound", ok, "the real loop's bound is the re-checked sos_bound under re-checked reach"
                         if ok else "real_loop_limsup_eps_m: needs verified saturated_loop reach and a verified sos_bound "
                         "bound no larger than it"))
        _check_summaries(conditions, rows, doc["inputs"]["exact_si"], doc["box"])
        proven = any(conditions.get(c, {}).get("status") == "certified" and any(n == c for n, _, _ in rows)
                     and all(ok for n, ok, _ in rows if n == c) for c in BOX_STABILITY_CLASSES)
        expected = "certified" if proven else "not_certified"
        rows.append(("verdict", doc.get("verdict") == expected,
                     f"verdict '{doc.get('verdict')}' is supported" if doc.get("verdict") == expected
                     else f"verdict: stated '{doc.get('verdict')}' but the re-checked box supports '{expected}'"))
        rows.append(answers_row(doc, checked_conditions(conditions, rows)))
        return rows
    except (KeyError, ValueError, ArithmeticError, TypeError, AttributeError, IndexError) as exc:
        raise CertificateError(f"certificate is malformed: {exc!r}") from None


def read_document(path: str | Path) -> dict[str, Any]:
    """A paper certificate file (:func:`lyapcheck.fileio.read_json`), checked by :func:`check_document`."""
    return check_document(read_json(path), f"'{Path(path)}'")


def check_document(doc: Any, source: str) -> dict[str, Any]:
    """``doc`` if it is a certificate document this version reads (kind and schema), else a one-line error."""
    from lyapcheck.exact import refuse_oversized_numbers

    if not isinstance(doc, dict) or doc.get("kind") != KIND:
        raise InputFileError(f"{source} is not a lyapcheck certificate (missing kind '{KIND}')")
    refuse_oversized_numbers(doc)
    if doc.get("schema_version") != SCHEMA_VERSION:
        raise InputFileError(f"{source} has schema_version {doc.get('schema_version')!r}; "
                             f"this lyapcheck reads {SCHEMA_VERSION}")
    return doc


def _short(value: object, limit: int = 200) -> str:
    """``repr(value)`` cut to ``limit`` characters (an error message is one readable line)."""
    text = repr(value)
    return text if len(text) <= limit else f"{text[:limit]}... ({len(text)} characters)"


def _check_skeleton(doc: dict[str, Any]) -> None:
    """The parts of a certificate every re-check reads, each of the right type and range.

    ``inputs.exact_si`` holds exact rationals as text, each within its field's accepted range
    (:data:`lyapcheck.paper.params.FIELDS`, as ``certify`` validated them); ``conditions`` maps names
    to objects with a text ``status``. Anything else is a :class:`CertificateError` naming the
    field, before an exact check would stumble over it.
    """
    from lyapcheck.errors import InvalidParameter
    from lyapcheck.paper.params import FIELDS
    from lyapcheck.units import Kind, parse_quantity, representable

    def malformed(where: str, expected: str, got: object) -> CertificateError:
        return CertificateError(f"certificate is malformed: '{where}' must be {expected}. Got {_short(got)} instead.")

    inputs = doc.get("inputs")
    exact_si = inputs.get("exact_si") if isinstance(inputs, dict) else None
    if not isinstance(exact_si, dict):
        raise malformed("inputs.exact_si", "an object of exact SI values", exact_si)
    specs = {spec.name: spec for spec in FIELDS}
    for key, value in exact_si.items():
        if value is None and key in ("d_max", "omega_so"):
            continue  # not given: the classes that need it are not_applicable
        if not isinstance(value, str):
            raise malformed(f"inputs.exact_si.{key}", "an exact rational as text ('p/q')", value)
        try:
            number = Fraction(value)
        except (ValueError, ZeroDivisionError):
            raise malformed(f"inputs.exact_si.{key}", "an exact rational as text ('p/q')", value) from None
        if key in specs:
            spec = specs[key]
            try:  # the size of the rational, as for any input (lyapcheck.units)
                parse_quantity(f"inputs.exact_si.{key}", number, Kind.DIMENSIONLESS)
            except InvalidParameter as exc:
                raise CertificateError(f"certificate is malformed: {exc}") from None
            if not (spec.interval.contains(number) and representable(number)):
                raise malformed(f"inputs.exact_si.{key}", f"{spec.interval.accepted()} {spec.kind.si_unit}".rstrip(),
                                value)
    conditions = doc.get("conditions")
    if not isinstance(conditions, dict):
        raise malformed("conditions", "an object of condition results", conditions)
    for name, result in conditions.items():
        if not isinstance(result, dict) or not isinstance(result.get("status"), str):
            raise malformed(f"conditions.{name}", "an object with a text 'status'", result)


def _check_summaries(conditions: dict[str, Any], rows: list[tuple[str, bool, str]], inputs: Any,
                     box: Any = None) -> None:
    """Each decided condition's summary is the sentence its re-checked data give
    (:func:`lyapcheck.paper.claims.summary`, which also wrote it): an edited summary, or data from
    which no sentence can be made, is a failed check of that condition. A condition whose exact
    check has already failed is not judged again on its sentence (one failure names it)."""
    from lyapcheck.paper import claims

    failed = {n for n, ok, _ in rows if not ok}
    for name, c in conditions.items():
        if not isinstance(c, dict) or name in failed:
            continue
        try:
            expected = claims.summary(str(name), c, inputs if isinstance(inputs, dict) else {}, box)
        except claims.MALFORMED as exc:
            reason = f"missing key {exc}" if isinstance(exc, KeyError) else _short(str(exc), 200)[1:-1]
            rows.append((name, False, f"{name}: no summary follows from its data ({reason})"))
            continue
        if expected is not None and c.get("summary") != expected:
            rows.append((name, False, f"{name}: the summary is not what the re-checked data say; they say: "
                                      f"{expected!r}"))


def _at_least(stated: Any, proved: Fraction) -> bool:
    """A bound (``k``, ``eps_bound_m``) stated no smaller than proved (floats round: 1e-12)."""
    return stated is None or Fraction(float(stated)) >= proved - abs(proved) / 10**12


def _at_most(stated: Any, proved: Fraction) -> bool:
    """A rate or margin stated no larger than proved."""
    return stated is None or Fraction(float(stated)) <= proved + abs(proved) / 10**12


def _stated_figures(conditions: dict[str, Any], system: Any, speed_bound: Fraction | None = None
                    ) -> list[tuple[str, bool, str]]:
    """The figures stated beside each certified class, against what its certificate proves: a
    bound stated lower, or a rate or margin stated higher, is a claim the file does not prove; a
    count is the certificate's, and a text figure (:mod:`lyapcheck.paper.claims`) is the one its
    data give. ``speed_bound``: ``e11 Omega_SO + |E_0| d*`` (m/s), when Omega_SO is given."""
    from lyapcheck.paper import claims
    from lyapcheck.paper.conditions import ges
    from lyapcheck.paper.conditions.sos import scaled_dynamics

    checks: list[tuple[str, str, bool]] = []  # (class, figure, holds)
    # checks added with the summaries (issue 28): a row only where one fails, so that verify's
    # report of a sound certificate reads as before
    quiet: list[tuple[str, str, bool]] = []

    def certified(name: str) -> dict[str, Any] | None:
        c = conditions.get(name)
        return c if isinstance(c, dict) and c.get("status") == "certified" else None

    if (c := certified("ges")) is not None and (dyn := scaled_dynamics(system)) is not None:
        _, _, mu, c1, c2 = ges._from_json(c["certificate"])
        k_sq, rate = c2 / c1, mu * dyn.time_scale / 2
        sigma0 = system.sigma0
        spread = max(Fraction(1), sigma0) / min(Fraction(1), sigma0)
        checks += [("ges", "k", c.get("k") is None or Fraction(float(c["k"])) ** 2 >= k_sq * (1 - Fraction(1, 10**12))),
                   ("ges", "k_eps_s", c.get("k_eps_s") is None
                    or Fraction(float(c["k_eps_s"])) ** 2 >= k_sq * spread**2 * (1 - Fraction(1, 10**12))),
                   ("ges", "decay_rate_per_s", _at_most(c.get("decay_rate_per_s"), rate)),
                   ("ges", "decay_rate_V_per_s", _at_most(c.get("decay_rate_V_per_s"), 2 * rate))]
        quiet.append(("ges", "terms", _count(c.get("terms"), len(c["certificate"]["l"]))))
        quiet.append(("ges", "norm", c.get("norm") in (None, claims.GES_NORM)))
    for name in ("sector_ges", "switched_ges"):
        if (c := certified(name)) is not None:
            quiet.append((name, "decay_rate_per_s",
                           _at_most(c.get("decay_rate_per_s"), Fraction(c["certificate"]["decay_rate"]))))
    c = conditions.get("switched_ges")
    if isinstance(c, dict) and c.get("status") == "refuted" and isinstance(c.get("refutation"), dict) \
            and c["refutation"].get("argument") == "periodic_switching_2x2":
        quiet += _switching_figures(c, system)
    if (c := certified("sos_gas")) is not None:
        cert = c["certificate"]
        rate = Fraction(cert["mu_scaled"]) * Fraction(cert["scaling"]["time_scale"])
        checks.append(("sos_gas", "decay_rate_V_per_s", _at_most(c.get("decay_rate_V_per_s"), rate)))
        quiet.append(("sos_gas", "degree", _count(c.get("degree"), cert.get("degree"))))
        quiet.append(("sos_gas", "proves", c.get("proves") in (None, claims.sos_gas_proves(rate))))
    for name in ("ultimate_bound", "sos_bound"):
        if (c := certified(name)) is not None:
            checks.append((name, "eps_bound_m", _at_least(c.get("eps_bound_m"), Fraction(c["certificate"]["eps_bound"]))))
    if (c := certified("ultimate_bound")) is not None:
        quiet.append(("ultimate_bound", "ellipsoid_stages",
                       _count(c.get("ellipsoid_stages"), len(c["certificate"]["stages"]))))
    if (c := certified("saturated_loop")) is not None:
        cert = c["certificate"]
        reach_proved = isinstance(cert.get("reach"), dict) and Fraction(cert["reach"]["gamma"]) > 0
        quiet.append(("saturated_loop", "global_reach", c.get("global_reach") in
                       (None, "proved" if reach_proved else "not_proved")))
        quiet.append(("saturated_loop", "not_ges", c.get("not_ges") is None
                       or (speed_bound is not None and c["not_ges"] == claims.not_ges(speed_bound))))
        strip_sq = Fraction(cert["strip_half_width_sq_scaled"]) * system.delta**2
        quiet.append(("saturated_loop", "strip_half_width_m", c.get("strip_half_width_m") is None
                       or Fraction(float(c["strip_half_width_m"])) ** 2 >= strip_sq * (1 - Fraction(1, 10**12))))
        checks.append(("saturated_loop", "ultimate_eps_bound_m",
                       _at_least(c.get("ultimate_eps_bound_m"), Fraction(cert["eps_bound"])) if "eps_bound" in cert
                       else c.get("ultimate_eps_bound_m") is None))
        checks.append(("saturated_loop", "invariant_eps_radius_m_at_s0",
                       _at_most(c.get("invariant_eps_radius_m_at_s0"),
                                Fraction(cert["axis_radius_scaled"]) * system.delta)))
        if "reach" in cert:
            reach = cert["reach"]
            quiet.append(("saturated_loop", "reach_condition",
                           c.get("reach_condition") in (None, claims.reach_condition(reach))))
            checks += [("saturated_loop", "windup_bound_s_m", _at_least(c.get("windup_bound_s_m"), Fraction(reach["S_1"]))),
                       ("saturated_loop", "reach_set_y_half_width_m",
                        _at_least(c.get("reach_set_y_half_width_m"), Fraction(reach["Y_q"]))),
                       ("saturated_loop", "reach_margin_m_per_s",
                        _at_most(c.get("reach_margin_m_per_s"), Fraction(reach["gamma"])))]
    return [(name, ok, f"{name}: the stated {figure} follows from the certificate" if ok else
             f"{name}: the stated {figure} is not what the certificate proves (a bound stated too small, a rate "
             "too large, or a count or value that is not the certificate's)")
            for name, figure, ok in checks + [q for q in quiet if not q[2]]]


def _count(stated: Any, actual: Any) -> bool:
    """A stated count or degree (``ellipsoid_stages``, ``terms``, ``degree``) is absent or the JSON
    integer ``actual`` (a float ``2.0`` or a bool is not a count, though Python finds them equal)."""
    return stated is None or (isinstance(stated, int) and not isinstance(stated, bool) and stated == actual)


#: a search's estimate of the growth per period, against the exact enclosures (floating point)
ESTIMATE_RTOL = 1e-6


def _switching_figures(c: dict[str, Any], system: Any) -> list[tuple[str, str, bool]]:
    """The figures a periodic-switching refutation states and its sentence prints: the dwell times
    and period are the certificate's, the proved lower bound no higher than proved, the search's
    estimate of the growth between that bound and the enclosures' upper bound (and the growth
    rate its logarithm per period), and the high value of rho is rho_sup."""
    import math

    from lyapcheck.paper.conditions.switching import growth_upper_bound

    ref = c["refutation"]
    t0, t1 = Fraction(ref["t0"]), Fraction(ref["t1"])
    lower = Fraction(ref["growth_lower_bound"])
    trace, det = ((Fraction(ref[k][0]), Fraction(ref[k][1])) for k in ("trace", "det"))
    upper = growth_upper_bound(trace, det)

    def same(key: str, value: Fraction) -> bool:
        return c.get(key) is None or math.isclose(float(c[key]), float(value), rel_tol=1e-12)

    estimate, rate = c.get("growth_per_period"), c.get("growth_rate_per_s")
    estimate_ok = estimate is None or (float(lower) * (1 - ESTIMATE_RTOL) <= float(estimate)
                                       <= upper * (1 + ESTIMATE_RTOL))
    rate_ok = rate is None or estimate is None or (
        float(estimate) > 0 and math.isclose(float(rate), math.log(float(estimate)) / float(t0 + t1),
                                             rel_tol=ESTIMATE_RTOL, abs_tol=1e-300))
    return [("switched_ges", "t0_s", same("t0_s", t0)), ("switched_ges", "t1_s", same("t1_s", t1)),
            ("switched_ges", "period_s", same("period_s", t0 + t1)),
            ("switched_ges", "growth_per_period_lower_bound", _at_most(c.get("growth_per_period_lower_bound"), lower)),
            ("switched_ges", "growth_per_period", estimate_ok), ("switched_ges", "growth_rate_per_s", rate_ok),
            ("switched_ges", "rho", Fraction(ref["rho"][1]) == system.rho_sup)]


def verify_document(doc: dict[str, Any]) -> list[tuple[str, bool, str]]:
    """Exact re-check of every claim in the document; returns (condition, ok, message) rows."""
    from lyapcheck.exact import refuse_oversized_numbers

    refuse_oversized_numbers(doc)
    if isinstance(doc, dict) and "box" in doc:
        return verify_box_document(doc)
    from lyapcheck import exact
    from lyapcheck.paper.conditions import prop41, sector, ultimate
    from lyapcheck.paper.certification import system_from_values
    from lyapcheck.paper.conditions.stabcond2 import run as stabcond2_run

    _check_skeleton(doc)
    try:
        stored = dict(doc["inputs"]["exact_si"])
        # an input not given is null; the classes that need it must then be not_applicable
        given_d_max = None if stored.get("d_max") is None else Fraction(stored["d_max"])
        omega_so = None if stored.get("omega_so") is None else Fraction(stored["omega_so"])
        values = {k: Fraction(v) for k, v in stored.items() if k not in ("d_max", "omega_so")}
        d_max = given_d_max if given_d_max is not None else Fraction(0)
        system = system_from_values(doc["dynamics"], values, d_max)
        conditions = doc["conditions"]
    except (KeyError, ValueError, ArithmeticError, TypeError, AttributeError) as exc:
        raise CertificateError(f"certificate is malformed: {exc!r}") from None

    rows: list[tuple[str, bool, str]] = []
    rows.append(("system", system_to_json(system) == doc.get("system"),
                 "stored system matrices match the derivation at the stored inputs"
                 if system_to_json(system) == doc.get("system") else "stored system matrices differ from the derivation"))

    def ok_row(name: str, ok: bool, good: str, bad: str) -> None:
        rows.append((name, ok, good if ok else bad))

    from lyapcheck.paper.certification import NEEDS

    absent = {"disturbance.d_max": given_d_max is None, "actuation.omega_so": omega_so is None}
    for name, needs in NEEDS.items():
        status = conditions.get(name, {}).get("status") if isinstance(conditions.get(name), dict) else None
        lacking = [key for key, _ in needs if absent[key]]
        if lacking and status not in (None, "not_applicable"):
            ok_row(name, False, "", f"{name}: stated '{status}' but its input {', '.join(lacking)} is null")

    try:
        for name in ("prop41_ges", "prop41_iss"):
            if name not in conditions:
                continue
            c = conditions[name]
            iss = name == "prop41_iss"
            if c["status"] == "certified":
                ok, why = prop41.exact_check(system, exact.from_json(c["certificate"]["P"]), iss)
                ok_row(name, ok, why, f"{name}: {why}")
            elif c["status"] == "refuted":
                ok = prop41.check_refutation(system, c["refutation"])
                ok_row(name, ok, "refutation re-derived exactly", f"{name}: the Gamma_22 refutation does not hold")
        c = conditions.get("sector_ges", {"status": "absent"})
        if c["status"] == "certified":
            cert = c["certificate"]
            rho_lo = Fraction(cert["rho_lo"])
            verts = [system.vertex(rho_lo), system.vertex(system.rho_sup)]
            ok, why = sector.exact_check(verts, exact.from_json(cert["P"]), Fraction(cert["decay_rate"]))
            if rho_lo > 0:  # the vertices must span the whole sector (0, rho_sup]
                ok, why = False, f"rho_lo = {rho_lo} > 0: the vertices do not cover rho in (0, rho_sup]"
            ok_row("sector_ges", ok, why, f"sector_ges: {why}")
        elif c["status"] == "refuted":
            fresh = sector.refutation([system.vertex(Fraction(0)), system.vertex(system.rho_sup)])
            ok_row("sector_ges", fresh is not None and all(c["refutation"].get(k) == v for k, v in fresh.items()),
                   "Shorten-Narendra refutation re-derived exactly",
                   "sector_ges: the refutation (A0A1, A0A1inv and its statement) is not the one re-derived")
        c = conditions.get("switched_ges", {"status": "absent"})
        if c["status"] in ("certified", "refuted"):
            from lyapcheck.paper.conditions import switching

            ok, why = switching.verify(system, c["certificate"] if c["status"] == "certified" else c["refutation"])
            ok_row("switched_ges", ok, why, f"switched_ges: {why}")
        c = conditions.get("ges", {"status": "absent"})
        if c["status"] == "certified":
            from lyapcheck.paper.conditions import ges

            ok, why = ges.verify(system, c["certificate"])
            ok_row("ges", ok, why, f"ges: {why}")
        c = conditions.get("ultimate_bound", {"status": "absent"})
        if c["status"] == "certified":
            ok, why = ultimate.verify(system, c["certificate"])
            ok_row("ultimate_bound", ok, why, f"ultimate_bound: {why}")
        c = conditions.get("sos_gas", {"status": "absent"})
        if c["status"] == "certified":
            from lyapcheck.paper.conditions import sos

            ok, why = sos.verify(system, c["certificate"])
            ok_row("sos_gas", ok, why, f"sos_gas: {why}")
            sat = conditions.get("saturated_loop", {"status": "absent"})
            if sat["status"] == "certified" and omega_so is not None:
                from lyapcheck.paper.conditions import saturated

                ok, why = saturated.verify(system, c["certificate"], sat["certificate"], alpha_d=values["alpha_d"],
                                           e11_hat=values["e11_hat"], omega_so=omega_so, k_d=values["k_d"])
                ok_row("saturated_loop", ok, why, f"saturated_loop: {why}")
        c = conditions.get("sos_bound", {"status": "absent"})
        if c["status"] == "certified":
            from lyapcheck.paper.conditions import sos_bound

            ok, why = sos_bound.verify(system, c["certificate"])
            ok_row("sos_bound", ok, "limsup |eps| bound follows exactly from the polynomial certificate", f"sos_bound: {why}")
        sat = conditions.get("saturated_loop", {"status": "absent"})
        if sat.get("real_loop_limsup_eps_m") is not None:
            # the conjunction of two re-checked results: reach proved, and sos_bound's number
            from lyapcheck.paper.conditions.saturated import verify_reach

            reach = sat.get("certificate", {}).get("reach") or {}
            bound = conditions.get("sos_bound", {})
            ok = (bound.get("status") == "certified" and omega_so is not None and "gamma" in reach
                  and Fraction(reach["gamma"]) > 0
                  and verify_reach(system, reach, k_d=values["k_d"], alpha_d=values["alpha_d"],
                                   e11_hat=values["e11_hat"], omega_so=omega_so)[0]
                  and float(sat["real_loop_limsup_eps_m"]) >= float(Fraction(bound["certificate"]["eps_bound"])))
            ok_row("saturated_loop", ok, "the real loop's limsup |eps| is sos_bound's, by the proved global reach",
                   "saturated_loop: real_loop_limsup_eps_m needs a proved reach and a certified sos_bound at least as large")
        speed_bound = None if omega_so is None else values["e11"] * omega_so + abs(system.E[0]) * system.d_max
        rows += _stated_figures(conditions, system, speed_bound)
        if "stabcond2" in conditions:
            c = conditions["stabcond2"]
            s2 = stabcond2_run(values["alpha_d"], values["sigma0"], values["k_d"], values["delta_los"], "undecided")
            ok_row("stabcond2", s2.status == c["status"] and s2.numbers["lhs_exact"] == c.get("lhs_exact"),
                   f"eq:stabCond2 {s2.status}, as stated",
                   f"stabcond2: stated '{c['status']}' with left-hand side {_short(c.get('lhs_exact'), 80)}, but the "
                   f"arithmetic gives '{s2.status}' with {s2.numbers['lhs_exact']}")
    except (KeyError, ValueError, ArithmeticError, TypeError, IndexError, AttributeError, RecursionError) as exc:
        # what a field of the wrong type or scale does to an exact check that reads it (a float
        # view of '1e400', a string where a matrix belongs): the file is malformed, in one line
        raise CertificateError(f"certificate is malformed: {_short(exc)}") from None

    _check_summaries(conditions, rows, stored)

    from lyapcheck.paper.conditions.base import STABILITY_CLASSES

    stated = doc.get("verdict")
    proven = any(conditions.get(c, {}).get("status") == "certified" and any(n == c for n, _, _ in rows)
                 and all(ok for n, ok, _ in rows if n == c) for c in STABILITY_CLASSES)
    expected = "certified" if proven else "not_certified"
    ok_row("verdict", stated == expected, f"verdict '{stated}' is supported",
           f"verdict: stated '{stated}' but the re-checked conditions support '{expected}'")
    rows.append(answers_row(doc, checked_conditions(conditions, rows)))
    return rows
