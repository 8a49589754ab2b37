"""Certificate files of model files: write, and re-check exactly without a solver.

Schema (version 1)::

    {
      "schema_version": 1,
      "kind": "lyapcheck-model-certificate",
      "model": {"name": .., "file": .., "sha256": .., "text": "<the model file, verbatim>",
                "networks": {"pi": {"file": .., "sha256": ..}}},   # only with [networks.NAME]
      "overrides": {"mu": "2"},                      # --set, as given
      "candidate": "x1**2 + x2**2" | null,            # --candidate, as given
      "states": [..], "equilibrium": {"x1": "0", ..}, "parameters": {"mu": "2"},  # exact SI
      "field": {"denominators": [..], "scaling": {..}},
      "conditions": {"linearization": {..}, "roa": {"status": .., "level": .., "disturbances": "all",
                     "certificate": {"V": {"terms": [["3/2", [2, 0]], ..]}, "variables": ["x1", "x2"],
                                     "V_text": "1.5*x1**2 - ...", "level": "p/q", ..}}, ..},
      "verdict": "certified" | "certified_nominal" | "certified_local" | "not_certified" | "unsafe" | "unstable",
      "answers": {"stability": {"answer": .., "by": .., "text": ..}, ..},   # lyapcheck.answers
      "versions": {..}
    }

Polynomials are exact (rationals as ``"p/q"``). ``V`` is in the states as declared, shifted so
that the equilibrium is 0 (the contract); the Gram matrices behind it are in the scaled states of
``field.scaling`` (powers of two), which :func:`verify_document` re-applies to the field it
re-derives from ``model.text``. The check fails when the text does not match its SHA-256, when a
coefficient, level or bound was changed, or when a stated figure claims more than the certificate
proves. It never imports cvxpy or calls a solver: :func:`verify_document` reads the model again and makes
the rows every document starts with, and :func:`lyapcheck.models.surfaces.verify.verify_model` runs the
rest, the same steps for every kind of loop.
"""

from __future__ import annotations

import hashlib
from pathlib import Path
from typing import Any

from lyapcheck.errors import CertificateError, InputFileError
from lyapcheck.exact import refuse_oversized_numbers
from lyapcheck.fileio import read_json as read_json_file
from lyapcheck.models.surfaces.certify import ModelCertification
from lyapcheck.models.surfaces.documents import KIND, SCHEMA_VERSION
from lyapcheck.results import ConditionResult


Row = tuple[str, bool, str]


def build_document(result: ModelCertification) -> dict[str, Any]:
    """The certificate document of either kind of loop: a polynomial or rational loop states its
    cleared ``field`` (denominators' proofs, scaling), a loop with functions its ``recast`` table (the
    recasting's auxiliaries, flows and relations, and its angles); the rest is common."""
    from lyapcheck.answers import answers_of
    from lyapcheck.numerics import package_versions

    model = result.model
    recast: Any = model  # (a loop with functions has its recasting's loop; lyapcheck.models.language.recast
    #                      is not imported for a polynomial one)
    loop = ({"recast": {**recast.system.to_json(), "angles": {a: list(sc) for a, sc in result.loop.angles.items()}}}
            if result.loop is not None else
            {"field": {"denominators": result.denominators,
                       "scaling": result.scaling.to_json() if result.scaling is not None else None}})
    return {
        "schema_version": SCHEMA_VERSION,
        "kind": KIND,
        "model": {"name": model.name, "file": model.source, "sha256": model.sha256, "text": model.text,
                  **_network_files(model)},
        "overrides": dict(model.overrides),
        "candidate": result.candidate.text if result.candidate is not None else None,
        "states": list(model.states),
        "equilibrium": {s: str(v) for s, v in zip(model.states, model.equilibrium)},
        "parameters": {k: str(v) for k, v in model.parameters.items()},
        "disturbances": {k: str(v) for k, v in model.disturbances.items()},
        **loop,
        **({"box": result.box.to_json()} if result.box is not None else {}),
        "conditions": (conditions := {name: r.to_json() for name, r in result.results.items()}),
        "answers": answers_of(conditions),
        "verdict": result.verdict,
        "versions": package_versions(),
    }


def _network_files(model: Any) -> dict[str, Any]:
    """``{"networks": ...}`` for a loop with ``[networks.NAME]`` (their files' SHA-256), else nothing: the
    documents of every other model stay as they were."""
    if not getattr(model, "networks", ()):
        return {}
    from lyapcheck.models.language.networks import stated_files

    return {"networks": stated_files(model.networks)}


def is_model_document(doc: Any) -> bool:
    return isinstance(doc, dict) and doc.get("kind") == KIND


def read_json(path: str | Path) -> Any:
    """A JSON file, with one-line errors (missing, not JSON, unreadable, a number written with an
    oversized exponent: :func:`lyapcheck.exact.refuse_oversized_numbers`)."""
    doc = read_json_file(path)
    refuse_oversized_numbers(doc)  # (before any reader of the file's numbers: a report, simulate --certificate)
    return doc


def verify_document(doc: dict[str, Any]) -> list[Row]:
    """Re-check every claim of a model certificate exactly; (check, ok, message) rows."""
    refuse_oversized_numbers(doc)
    if doc.get("schema_version") != SCHEMA_VERSION:
        raise InputFileError(f"model certificate has schema_version {doc.get('schema_version')!r}; this lyapcheck "
                             f"reads {SCHEMA_VERSION}")
    try:
        # (a sampled-data loop is read by its own reader, then runs the same steps: its kind, verify.SAMPLED)
        model, rows = _read_model(doc)
        if model is None:
            return rows
        from lyapcheck.models.surfaces.verify import verify_model

        return verify_model(doc, model, rows)  # the same steps for every kind of loop
    except (KeyError, ValueError, ArithmeticError, TypeError, IndexError, AttributeError, RecursionError) as exc:
        text = repr(exc)
        raise CertificateError(f"certificate is malformed: {text[:200]}") from None


def _read_model(doc: dict[str, Any]) -> tuple[Any, list[Row]]:
    """The document's model, read again from its text (with its ``--set`` overrides and, on a loop with
    functions, its candidate recast along; a sampled-data loop's, a ``sampling`` table in its document, by the
    sampled-data reader :func:`lyapcheck.models.language.sampling.parse_sampled`), and the rows every document
    starts with: the text's SHA-256, its parse, its kind (a ``recast`` table exactly when the loop has
    functions), the stated parameters and equilibrium (a sampled-data loop never has disturbances nor a
    candidate), the declared figures and the networks' files; (None, rows) when the rest cannot be checked."""
    from lyapcheck.errors import ModelFileError
    from lyapcheck.models.language.modelfile import parse_any_model
    from lyapcheck.models.language.recast import RecastModel
    from lyapcheck.models.language.sampling import parse_sampled
    from lyapcheck.models.surfaces.stated import check_declared

    part = doc["model"]
    text = part["text"]
    sampled = isinstance(doc.get("sampling"), dict)
    if hashlib.sha256(text.encode()).hexdigest() != part["sha256"]:
        return None, [("model", False, "the model text does not match its SHA-256: the text was changed")]
    file, overrides = part.get("file", "<certificate>"), doc.get("overrides") or {}
    try:
        model = (parse_sampled(text, file, overrides) if sampled else
                 parse_any_model(text, file, overrides, candidate=doc.get("candidate")))
    except ModelFileError as exc:
        kind = " as a sampled-data loop" if sampled else ""
        return None, [("model", False, f"the stored model text no longer parses{kind}: {exc}")]
    recast = isinstance(doc.get("recast"), dict)
    if not sampled and recast != isinstance(model, RecastModel):
        return None, [("model", False, "the stored model has no functions: it is not a recast loop" if recast else
                       "the stored model uses functions: its certificate must state its recasting ('recast')")]
    rows: list[Row] = [("model", True, "the model text matches its SHA-256 and parses as a sampled-data loop"
                        if sampled else "the model text matches its SHA-256, parses and is recast again from it"
                        if recast else "the model text matches its SHA-256 and parses")]
    same = ({k: str(v) for k, v in model.parameters.items()} == doc["parameters"]
            and {s: str(v) for s, v in zip(model.states, model.equilibrium)} == doc["equilibrium"]
            and (not sampled or (doc.get("disturbances") == {} and doc.get("candidate") is None)))
    rows.append(("parameters", same, "parameters and equilibrium as stated" if same else
                 "the stated parameters, equilibrium, disturbances or candidate differ from the model text's"
                 if sampled else "the stated parameters or equilibrium differ from the model text's"))
    rows.append(check_declared(doc, model))
    if getattr(model, "networks", ()) or "networks" in part:  # the files read again now are the ones certified
        from lyapcheck.models.language.networks import check_stated_files

        rows.append(("networks", *check_stated_files(part.get("networks"), getattr(model, "networks", ()))))
    return model, rows


def result_conditions(doc: dict[str, Any]) -> dict[str, ConditionResult]:
    """The document's conditions as results (for the API's typed view)."""
    out = {}
    for name, c in doc["conditions"].items():
        numbers = {k: v for k, v in c.items() if k not in ("status", "summary", "property", "certificate",
                                                           "refutation", "solver")}
        out[name] = ConditionResult(name, c["status"], c["summary"], numbers=numbers,
                                    certificate=c.get("certificate") or {}, refutation=c.get("refutation") or {},
                                    solver=c.get("solver") or {}, property=c.get("property"))
    return out
