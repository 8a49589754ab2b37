"""The answers to the user's questions, read from the conditions of a certificate document.

A model (or the paper's gain set) asks up to four questions; each condition class answers one of
them through the property its ``certified`` proves (:data:`lyapcheck.results.PROPERTY`):

============  ===================================  ===============================================
question      classes (by property)                answers
============  ===================================  ===============================================
stability     GES, GAS (global), ROA (a region),   ``global``, ``region``, ``local``, ``unstable``
              LES (local)                          (the linearization refuted, exactly), ``undecided``
safety        ``safety`` (barrier)                 ``safe``, ``unsafe`` (a reproducible trajectory
                                                   from the initial set into the unsafe set),
                                                   ``undecided``
reach_avoid   ``reach_avoid``                      ``proved``, ``fails`` (a reproducible trajectory
                                                   against it), ``undecided``
bounds        ``ultimate_bound``, ``ISS``          ``bounded``, ``undecided``
============  ===================================  ===============================================

A question is *asked* when one of its classes ran (a status other than ``not_applicable``). A class
``refuted`` inside a positive answer (no global V can exist for a pendulum, whose region is proved)
is part of that answer, not a negative one: only ``unstable``, ``unsafe`` and ``fails`` are negative
(:data:`NEGATIVE`), and only those, or no positive answer at all, make ``certify`` exit 1.

Everything here is a function of the conditions' JSON (their ``status``, ``property``,
``disturbances`` and figures), so ``verify`` recomputes the answers from the conditions it has
re-checked and compares them with the stated ones.
"""

from __future__ import annotations

from fractions import Fraction

from typing import Any, Final, Mapping, Sequence

from lyapcheck.errors import InvalidParameter

#: the questions, in the order the headline states them
QUESTIONS: Final = ("stability", "safety", "reach_avoid", "bounds")
#: which question a property answers
QUESTION_OF: Final[dict[str, str]] = {"GES": "stability", "GAS": "stability", "ROA": "stability", "LES": "stability",
                                      "safety": "safety", "reach_avoid": "reach_avoid",
                                      "ultimate_bound": "bounds", "ISS": "bounds"}
#: stability levels, strongest first: property -> (answer, rank)
STABILITY_RANK: Final[dict[str, tuple[str, int]]] = {"GES": ("global", 4), "GAS": ("global", 3),
                                                     "ROA": ("region", 2), "LES": ("local", 1)}
#: the answers that say no: any of them makes ``certify`` exit 1
NEGATIVE: Final = frozenset({"unstable", "unsafe", "fails"})
#: the answers that say yes
POSITIVE: Final = frozenset({"global", "region", "local", "safe", "proved", "bounded"})
#: the verdicts that are negative answers (beside ``not_certified``): the first negative question's
NEGATIVE_VERDICTS: Final = {"safety": "unsafe", "reach_avoid": "unsafe", "stability": "unstable"}
#: what each property names, for the headline
_PROPERTY_WORDS: Final = {
    "GES": "globally exponentially stable (GES)",
    "GAS": "globally asymptotically stable (GAS)",
    "ROA": "asymptotically stable, with a proved region of attraction (ROA)",
    "LES": "locally stable only (LES)",
}
#: ``--require`` names: the properties a certified condition may prove that meet each
REQUIREMENTS: Final[dict[str, frozenset[str]]] = {
    "GES": frozenset({"GES"}),
    "GAS": frozenset({"GES", "GAS"}),
    "ROA": frozenset({"GES", "GAS", "ROA"}),
    "LES": frozenset({"GES", "LES"}),
    "ISS": frozenset({"ISS"}),
    "ultimate_bound": frozenset({"ultimate_bound", "ISS"}),
    "bounds": frozenset({"ultimate_bound", "ISS"}),
    "safety": frozenset({"safety"}),
    "reach_avoid": frozenset({"reach_avoid"}),
}


def _question(name: str, condition: Mapping[str, Any]) -> str | None:
    prop = condition.get("property")
    if name == "linearization":
        return "stability"
    return QUESTION_OF.get(str(prop)) if prop is not None else None


#: the instability a refuted linearization proves, by its refutation's method, where it is not an
#: eigenvalue of a continuous loop's Jacobian with positive real part
UNSTABLE_BY_METHOD: Final[Mapping[str, str]] = {
    "sampled_routh": "the sampled-data loop's Jacobian over one period has an eigenvalue of modulus > 1 (proved in "
                     "ball arithmetic)",
}


def _is_unstable(name: str, condition: Mapping[str, Any]) -> bool:
    """An exact proof that the equilibrium is unstable: the linearization refuted (an eigenvalue with
    positive real part). A refuted search class (no quadratic V exists) proves nothing of the kind."""
    return name == "linearization" and condition.get("status") == "refuted"


def _nominal(condition: Mapping[str, Any]) -> str:
    return " with every disturbance held at 0" if condition.get("disturbances") == "zero" else ""


def _stability(conditions: Mapping[str, Mapping[str, Any]]) -> dict[str, Any]:
    unstable = [n for n, c in conditions.items() if _is_unstable(n, c)]
    if unstable:
        refutation = conditions[unstable[0]].get("refutation") or {}
        point = refutation.get("point")
        where = (" at " + ", ".join(f"{k} = {float(Fraction(v)):.6g}" for k, v in point.items())
                 + ", a value of the box,") if isinstance(point, dict) and point else ""
        if refutation.get("time") == "discrete":  # a map's (a map with functions' over a box: in ball arithmetic)
            at = refutation.get("at_point")  # (its method: discrete_linearization.BALL_ROUTH_METHOD)
            balls = isinstance(at, dict) and at.get("method") == "ball_cayley_routh"
            how = "in ball arithmetic" if balls else "exactly"
            why = f"the map's Jacobian at the fixed point has an eigenvalue of modulus > 1 (proved {how})"
        else:
            why = UNSTABLE_BY_METHOD.get(str(refutation.get("method")), "the Jacobian at the equilibrium has an "
                                                                         "eigenvalue with positive real part (proved "
                                                                         "exactly)")
        return {"answer": "unstable", "by": unstable[0], "text": f"UNSTABLE:{where} {why}"}
    best: tuple[tuple[int, int], str, Mapping[str, Any]] | None = None
    for name, c in conditions.items():
        prop = str(c.get("property"))
        if c.get("status") != "certified" or prop not in STABILITY_RANK:
            continue
        # among claims of one level, one that covers the disturbances beats a nominal one
        key = (STABILITY_RANK[prop][1], 0 if c.get("disturbances") == "zero" else 1)
        if best is None or key > best[0]:
            best = (key, name, c)
    if best is None:
        return {"answer": "undecided", "by": None,
                "text": "not decided: no class proved or refuted the stability of the equilibrium"}
    _, name, c = best
    prop = str(c["property"])
    out: dict[str, Any] = {"answer": STABILITY_RANK[prop][0], "property": prop, "by": name}
    if c.get("disturbances") is not None:
        out["disturbances"] = c["disturbances"]
    text = f"{_PROPERTY_WORDS[prop]}{_nominal(c)}, proved by {name}"
    if prop == "ROA":
        size = _region_size(c)
        text += f" ({size})" if size else ""
        text += "; no global certificate was found"
    elif prop == "LES":
        text += ": no region of attraction or global certificate was found, so the neighbourhood it holds in is unknown"
    out["text"] = text
    return out


def _region_size(condition: Mapping[str, Any]) -> str:
    """The certified region's size in the figures its class states (share of the simulated region
    of attraction within the domain, largest ball)."""
    parts = []
    share = condition.get("roa_share")
    if isinstance(share, (int, float)) and not isinstance(share, bool):
        parts.append(f"{100 * share:.3g} % of the simulated region of attraction in the domain")
    ball = condition.get("ball_radius")
    if isinstance(ball, (int, float)) and not isinstance(ball, bool):
        from lyapcheck.models.classes.claims import ball_words  # the claim's own words, with the states' unit

        parts.append(ball_words(condition))
    return ", ".join(parts)


def _safety(conditions: Mapping[str, Mapping[str, Any]], question: str) -> dict[str, Any]:
    mine = {n: c for n, c in conditions.items() if _question(n, c) == question}
    bad = [n for n, c in mine.items() if c.get("status") in ("counterexample", "refuted")]
    good = [n for n, c in mine.items() if c.get("status") == "certified"]
    if bad:  # evidence against the property wins over nothing; a certificate and a counterexample cannot both pass
        c = mine[bad[0]]
        word = "UNSAFE" if question == "safety" else "FAILS"
        return {"answer": "unsafe" if question == "safety" else "fails", "by": bad[0],
                "text": f"{word}: {c.get('summary', '')}"}
    if good:
        c = mine[good[0]]
        words = ("safe: no trajectory from the initial set reaches the unsafe set" if question == "safety" else
                 "proved: every trajectory from the initial set reaches the goal and avoids the unsafe set")
        out = {"answer": "safe" if question == "safety" else "proved", "by": good[0],
               "text": f"{words}{_nominal(c)}, proved by {good[0]}"}
        if c.get("disturbances") is not None:
            out["disturbances"] = c["disturbances"]
        return out
    return {"answer": "undecided", "by": None,
            "text": "not decided: neither proved nor contradicted by a simulated trajectory"}


def _bounds(conditions: Mapping[str, Mapping[str, Any]]) -> dict[str, Any]:
    good = [n for n, c in conditions.items() if _question(n, c) == "bounds" and c.get("status") == "certified"]
    if not good:
        return {"answer": "undecided", "by": None, "text": "not decided: no bound under the disturbances was proved"}
    # every certified bound, each with its class: they bound different things or by different means
    text = "; ".join(f"{conditions[n].get('summary', '')} ({n})" for n in good)
    return {"answer": "bounded", "by": good[0], "text": text}


def answers_of(conditions: Mapping[str, Any]) -> dict[str, dict[str, Any]]:
    """One answer per question asked (module docstring), from conditions in their JSON form."""
    ran = {n: c for n, c in conditions.items() if isinstance(c, dict) and c.get("status") != "not_applicable"}
    asked = {q for q in (_question(n, c) for n, c in ran.items()) if q is not None}
    # a question whose every class was not applicable is still named when a class of it was chosen
    # with a reason (roa after GAS is part of stability, which another class answered)
    out: dict[str, dict[str, Any]] = {}
    for q in QUESTIONS:
        if q not in asked:
            continue
        if q == "stability":
            out[q] = _stability(ran)
        elif q == "bounds":
            out[q] = _bounds(ran)
        else:
            out[q] = _safety(ran, q)
    return out


def negative_question(answers: Mapping[str, Mapping[str, Any]]) -> str | None:
    """The first question answered negatively (:data:`NEGATIVE`), in the order of :data:`QUESTIONS`
    with safety first (an unsafe model is named unsafe before anything else), or None."""
    for q in ("safety", "reach_avoid", "stability"):
        if answers.get(q, {}).get("answer") in NEGATIVE:
            return q
    return None


def parse_requirements(text: str | Sequence[str] | None) -> tuple[str, ...]:
    """``--require GAS,safety`` as names of :data:`REQUIREMENTS` (one-line error naming ``require``)."""
    if text is None:
        return ()
    items = text.split(",") if isinstance(text, str) else list(text)
    names = tuple(str(x).strip() for x in items if str(x).strip())
    bad = [n for n in names if n not in REQUIREMENTS]
    if bad or not names:
        raise InvalidParameter("require", "comma-separated names among " + ", ".join(REQUIREMENTS),
                               ",".join(bad) if bad else text)
    return names


def unmet_requirements(conditions: Mapping[str, Any], required: Sequence[str]) -> list[str]:
    """The names of ``required`` that no certified condition meets (:data:`REQUIREMENTS`)."""
    proved = {str(c.get("property")) for c in conditions.values()
              if isinstance(c, dict) and c.get("status") == "certified"}
    return [r for r in required if not (REQUIREMENTS[r] & proved)]


#: the verdicts (one word beside the answers):
#: ``unsafe`` / ``unstable`` when a question is answered negatively (exit 1); else ``certified`` when a
#: certified claim beyond the linearization covers the declared disturbances (``"all"``, or the model
#: has none), ``certified_nominal`` when every such claim holds with the disturbances held at 0 only,
#: ``certified_local`` when the linearization (LES) is all that is proved (exit 0: positive, but in an
#: unknown neighbourhood), else ``not_certified`` (exit 1)
VERDICTS: Final = ("certified", "certified_nominal", "certified_local", "not_certified", "unsafe", "unstable")
#: the verdicts that exit 0
OK_VERDICTS: Final = ("certified", "certified_nominal", "certified_local")
#: what each verdict means, printed beside it
VERDICT_MEANING: Final = {
    "certified": "every asked question answered without a negative, and a certified claim passed its exact check",
    "certified_nominal": "exact checks passed only with every disturbance held at 0; no certified claim covers the "
                         "declared disturbances",
    "certified_local": "only the linearization is proved: the equilibrium is locally stable, in a neighbourhood of "
                       "unknown size",
    "not_certified": "no claim passed an exact check",
    "unsafe": "a trajectory from the initial set reaches the unsafe set (or misses the goal): see the counterexample",
    "unstable": "the equilibrium is proved unstable",
}


def verdict_of(conditions: Mapping[str, Any]) -> str:
    """The verdict of conditions in their JSON form (one rule for ``certify`` and ``verify``; see
    :data:`VERDICTS`)."""
    negative = negative_question(answers_of(conditions))
    if negative is not None:
        return NEGATIVE_VERDICTS[negative]
    certified = [c for c in conditions.values() if isinstance(c, dict) and c.get("status") == "certified"]
    beyond_local = [c for c in certified if c.get("property") != "LES"]
    if not certified:
        return "not_certified"
    if not beyond_local:
        return "certified_local"
    if any(c.get("disturbances") in (None, "all") for c in beyond_local):
        return "certified"
    return "certified_nominal"


Row = tuple[str, bool, str]


def checked_conditions(conditions: Mapping[str, Any], rows: Sequence[Row], prerequisites: bool = True
                       ) -> dict[str, Any]:
    """Conditions as a re-check supports them (``rows``: ``verify``'s (check, ok, message)): a
    ``certified`` or ``refuted`` whose rows did not all pass, or whose ``prerequisites`` (the model,
    its parameters, ...) failed, counts as ``not_certified``; the other statuses stand as stated
    (``counterexample`` is numerical evidence, not a proof, and its trajectory is reproducible)."""
    out: dict[str, Any] = {}
    for name, c in conditions.items():
        if isinstance(c, dict) and c.get("status") in ("certified", "refuted"):
            proved = prerequisites and any(n == name for n, _, _ in rows) and all(ok for n, ok, _ in rows if n == name)
            if not proved:
                c = {**c, "status": "not_certified"}
        out[name] = c
    return out


def answers_row(doc: Mapping[str, Any], checked: Mapping[str, Any]) -> Row:
    """``verify``'s row for the stated ``answers`` against those of the re-checked conditions
    (:func:`checked_conditions`). A document written before answers existed states none."""
    if "answers" not in doc:
        return ("answers", True, "no answers stated (a document from before answers were written)")
    expected = answers_of(checked)
    stated = doc["answers"] if isinstance(doc["answers"], dict) else {}
    if stated == expected and isinstance(doc["answers"], dict):
        return ("answers", True, "the answer to each question follows from the re-checked conditions")
    differ = sorted(q for q in set(expected) | set(stated) if stated.get(q) != expected.get(q)) or ["the document"]
    return ("answers", False, f"answers: the stated answers ({', '.join(differ)}) are not the ones the re-checked "
                              "conditions give")


__all__ = ["VERDICTS", "OK_VERDICTS", "VERDICT_MEANING", "verdict_of", "QUESTIONS", "NEGATIVE", "POSITIVE", "REQUIREMENTS", "answers_of", "negative_question",
           "parse_requirements", "unmet_requirements",
           "checked_conditions", "answers_row"]
