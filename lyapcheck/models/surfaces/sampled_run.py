"""``certify`` of a sampled-data model file (issue 44, item 2), and its document.

A sampled-data loop is decided by its linearization over one sampling period
(:mod:`lyapcheck.models.classes.sampled`) and, on its true flow over one period, by a region of attraction
at the sampling instants with a bound on the excursion between them
(:mod:`lyapcheck.models.classes.sampled_regions`). The other classes state conditions on a continuous
field or a map that this loop does not have in closed form; each is ``not_applicable``, saying so, rather
than answered for the emulated continuous loop, which is another system.

The document has the keys of every model certificate (:func:`lyapcheck.models.surfaces.certificate.build_document`)
with a ``sampling`` table in place of ``field``/``recast``: the period (exact seconds, and as given),
the controller's laws as written and the controls' values at the equilibrium. ``verify`` runs the one flow
of every kind of loop (:data:`lyapcheck.models.surfaces.verify.SAMPLED`): the model text read again, the
``sampling`` table, each decided condition's figures, sentence and proof through its class's entry, then
the verdict and the answers. A controller with ``[networks.NAME]`` has each network file's SHA-256 in
``model.networks`` (as a continuous loop's certificate), and ``verify`` fails when a file now holds another
network.
"""

from __future__ import annotations

import hashlib
from typing import TYPE_CHECKING, Any, Callable, Sequence

from lyapcheck.models.classes.registry import NAMES
from lyapcheck.models.language.sampling import SampledModel
from lyapcheck.results import ConditionResult

if TYPE_CHECKING:  # pragma: no cover
    from lyapcheck.models.classes.registry import ModelClass
    from lyapcheck.models.engines.search import Budget

Row = tuple[str, bool, str]

#: the classes a sampled-data loop gets by default: its linearization, and a line for each Lyapunov
#: class saying why it is not decided (so the user sees what was not asked of the loop)
DEFAULT_CLASSES = ("linearization", "quadratic", "sos_gas", "roa")


def _not_yet(name: str) -> str:
    return (f"{name} is not decided for sampled-data loops yet: the loop's flow over one period has no closed form "
            "to prove it on; its linearization over one period (linearization) and a region of attraction on the "
            "true flow (roa) are decided")


def certify_sampled(model: SampledModel, classes: str | Sequence[str] | None = None) -> dict[str, ConditionResult]:
    """The conditions of a sampled-data loop, by name, in the classes' order: ``classes`` as
    ``certify`` takes them (None or ``"all"``: :data:`DEFAULT_CLASSES`). Each class with a ``run_sampled``
    entry (:data:`lyapcheck.models.classes.registry.SAMPLED`) runs through the one runner
    (:func:`lyapcheck.models.surfaces.certify.certify_model`'s, guarded and timed at
    :data:`~lyapcheck.tolerances.MODEL_CLASS_TIME_LIMIT_S`); every other one is ``not_applicable``, saying
    why."""
    from lyapcheck import tolerances as tol
    from lyapcheck.errors import InvalidParameter
    from lyapcheck.models.classes.contexts import SampledRun
    from lyapcheck.models.surfaces.certify import _discrete_rule, _run_classes

    if classes is None or classes == "all":
        chosen: Sequence[str] = DEFAULT_CLASSES
    else:
        chosen = [c.strip() for c in (classes.split(",") if isinstance(classes, str) else classes) if c and c.strip()]
        unknown = [c for c in chosen if c not in NAMES]
        if not chosen or unknown:
            raise InvalidParameter("classes", "names among " + ", ".join(NAMES), ",".join(unknown) or str(classes))
    results: dict[str, ConditionResult] = {}
    ctx = SampledRun(model=model)

    def decide(entry: ModelClass) -> ConditionResult | None:
        return _discrete_rule(entry, entry.run_sampled, _not_yet(entry.name), results, None, False)

    def compute(entry: ModelClass) -> Callable[[Budget], ConditionResult] | None:
        run_sampled = entry.run_sampled
        return None if run_sampled is None else lambda budget: run_sampled(ctx, budget)

    _run_classes(chosen, results, {}, tol.MODEL_CLASS_TIME_LIMIT_S, decide, compute)
    return results


def build_sampled_document(model: SampledModel, results: dict[str, ConditionResult]) -> dict[str, Any]:
    """The certificate document (module docstring)."""
    from lyapcheck.answers import answers_of, verdict_of
    from lyapcheck.models.surfaces.documents import KIND, SCHEMA_VERSION
    from lyapcheck.numerics import package_versions

    conditions = {name: r.to_json() for name, r in results.items()}
    return {
        "schema_version": SCHEMA_VERSION,
        "kind": KIND,
        "model": {"name": model.name, "file": model.source, "sha256": model.sha256, "text": model.text,
                  **network_files(model)},
        "overrides": dict(model.overrides),
        "candidate": None,
        "states": list(model.states),
        "equilibrium": {s: str(v) for s, v in zip(model.states, model.equilibrium)},
        "parameters": {k: str(v) for k, v in model.parameters.items()},
        "disturbances": {},
        "sampling": model.to_json(),
        "conditions": conditions,
        "answers": answers_of(conditions),
        "verdict": verdict_of(conditions),
        "versions": package_versions(),
    }


def network_files(model: SampledModel) -> dict[str, Any]:
    """``{"networks": ...}`` (each network file's SHA-256, as a continuous loop's certificate states them:
    the model text's SHA-256 does not cover the weights) for a controller with ``[networks.NAME]``, else
    nothing: the other sampled-data documents stay as they were."""
    if not model.networks:
        return {}
    from lyapcheck.models.language.networks import stated_files

    return {"networks": stated_files(model.networks)}


def is_sampled_document(doc: dict[str, Any]) -> bool:
    return isinstance(doc.get("sampling"), dict)


__all__ = ["DEFAULT_CLASSES", "build_sampled_document", "certify_sampled", "is_sampled_document", "network_files"]
